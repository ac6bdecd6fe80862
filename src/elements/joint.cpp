#include "screwfem/elements/joint.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "screwfem/elements/rod.h"
#include "screwfem/model/errors.h"

namespace screwfem {

namespace {

Vec6 Rotation(const Vec3& a) {
  Vec6 c;
  c << Vec3::Zero(), a;
  return c;
}
Vec6 Translation(const Vec3& a) {
  Vec6 c;
  c << a, Vec3::Zero();
  return c;
}

// ---- per-type functions of the table (docs/architecture.md) ------------------------------

Mat6X RevoluteBasis(const Vec3& e, const Vec3&, double) {
  Mat6X A(6, 1);
  A.col(0) = Rotation(e);
  return A;
}
Mat6X PrismaticBasis(const Vec3& e, const Vec3&, double) {
  Mat6X A(6, 1);
  A.col(0) = Translation(e);
  return A;
}
Mat6X HelicalBasis(const Vec3& e, const Vec3&, double pitch) {
  Mat6X A(6, 1);
  Vec6 c;
  c << pitch * e, e;
  A.col(0) = c;
  return A;
}
Mat6X CylindricalBasis(const Vec3& e, const Vec3&, double) {
  Mat6X A(6, 2);
  A.col(0) = Translation(e);
  A.col(1) = Rotation(e);
  return A;
}
Mat6X SphericalBasis(const Vec3&, const Vec3&, double) {
  Mat6X A(6, 3);
  A.col(0) = Rotation(Vec3::UnitX());
  A.col(1) = Rotation(Vec3::UnitY());
  A.col(2) = Rotation(Vec3::UnitZ());
  return A;
}
// Normal e: the in-plane axes are the y and z axes of the frame whose x axis is e.
Mat6X PlanarBasis(const Vec3& e, const Vec3&, double) {
  const Mat3 R =
      FrameAlong(e, Vec3::UnitZ().cross(e).norm() > 1e-6 ? Vec3::UnitZ() : Vec3::UnitX());
  Mat6X A(6, 3);
  A.col(0) = Translation(R.col(1));
  A.col(1) = Translation(R.col(2));
  A.col(2) = Rotation(e);
  return A;
}
Mat6X UniversalBasis(const Vec3& e, const Vec3& e2, double) {
  Mat6X A(6, 2);
  A.col(0) = Rotation(e);
  A.col(1) = Rotation(e2);
  return A;
}
Mat6X FixedBasis(const Vec3&, const Vec3&, double) { return Mat6X(6, 0); }

// H_J = exp(A_J alpha) for abelian subgroups.
SE3 SubgroupFrame(const Mat6X& A, const double* alpha) {
  return ExpSE3(A * Eigen::Map<const Eigen::VectorXd>(alpha, A.cols()));
}
void ConstantBasis(const Mat6X& A, const double*, Mat6X* out) { *out = A; }
// Universal joint: H_J = exp(a1 A_1) exp(a2 A_2); d H_J = H_J wedge(Ad(exp(-a2 A_2)) A_1 da1 +
// A_2 da2).
SE3 UniversalFrame(const Mat6X& A, const double* alpha) {
  return ExpSE3(A.col(0) * alpha[0]) * ExpSE3(A.col(1) * alpha[1]);
}
void UniversalCurrentBasis(const Mat6X& A, const double* alpha, Mat6X* out) {
  *out = A;
  out->col(0) = Ad(ExpSE3(-alpha[1] * A.col(1))) * A.col(0);
}

// The joint-type table: one row per JointType, in the enum's order.
constexpr bool kYes = true, kNo = false;
const std::array<JointTypeInfo, 9> kJointTypes = {{
    // type                   name           k  global constr. axis axis2 pitch  spring law
    {JointType::kRevolute, "revolute", 1, kYes, kYes, kYes, kNo, kNo, JointSpringLaw::kCoordinates,
     RevoluteBasis, SubgroupFrame, ConstantBasis},
    {JointType::kPrismatic, "prismatic", 1, kYes, kYes, kYes, kNo, kNo,
     JointSpringLaw::kCoordinates, PrismaticBasis, SubgroupFrame, ConstantBasis},
    {JointType::kHelical, "helical", 1, kYes, kYes, kYes, kNo, kYes, JointSpringLaw::kCoordinates,
     HelicalBasis, SubgroupFrame, ConstantBasis},
    {JointType::kCylindrical, "cylindrical", 2, kYes, kYes, kYes, kNo, kNo,
     JointSpringLaw::kCoordinates, CylindricalBasis, SubgroupFrame, ConstantBasis},
    {JointType::kSpherical, "spherical", 3, kNo, kYes, kNo, kNo, kNo, JointSpringLaw::kLogarithm,
     SphericalBasis, nullptr, nullptr},
    {JointType::kPlanar, "planar", 3, kNo, kYes, kYes, kNo, kNo, JointSpringLaw::kLogarithm,
     PlanarBasis, nullptr, nullptr},
    {JointType::kUniversal, "universal", 2, kYes, kYes, kYes, kYes, kNo,
     JointSpringLaw::kCoordinates, UniversalBasis, UniversalFrame, UniversalCurrentBasis},
    {JointType::kFixed, "fixed", 0, kYes, kYes, kNo, kNo, kNo, JointSpringLaw::kCoordinates,
     FixedBasis, SubgroupFrame, ConstantBasis},
    {JointType::kFree, "free", 0, kNo, kNo, kNo, kNo, kNo, JointSpringLaw::kRelativeMotion,
     FixedBasis, nullptr, nullptr},
}};

}  // namespace

// ---- the table ---------------------------------------------------------------------------------

const JointTypeInfo& GetJointTypeInfo(JointType type) {
  const auto i = static_cast<std::size_t>(type);
  SCREWFEM_CHECK(i < kJointTypes.size() && kJointTypes[i].type == type);
  return kJointTypes[i];
}

const JointTypeInfo* FindJointType(std::string_view name) {
  for (const JointTypeInfo& t : kJointTypes)
    if (name == t.name) return &t;
  return nullptr;
}

std::vector<std::string> JointTypeNameList() {
  std::vector<std::string> names;
  for (const JointTypeInfo& t : kJointTypes) names.emplace_back(t.name);
  return names;
}

const char* JointTypeName(JointType type) { return GetJointTypeInfo(type).name; }

Mat6X JointBasis(JointType type, const Vec3& e, const Vec3& e2, double pitch) {
  return GetJointTypeInfo(type).basis(e, e2, pitch);
}

bool JointHasGlobalCoordinates(JointType type) { return GetJointTypeInfo(type).global_coordinates; }

int JointSpringCount(const Joint& joint) {
  return GetJointTypeInfo(joint.type).spring_law == JointSpringLaw::kRelativeMotion ? 6 : joint.k();
}

// ---- the kernel --------------------------------------------------------------------------------

SE3 JointRelativeFrame(const Model& model, const Data& data, int joint) {
  const Joint& j = model.joints[static_cast<std::size_t>(joint)];
  const JointTypeInfo& t = GetJointTypeInfo(j.type);
  if (!t.global_coordinates) return data.HJ[static_cast<std::size_t>(joint)];
  return t.relative_frame(j.basis, data.q_joint.data() + (j.coord - model.nv_nodes));
}

Mat6X JointCurrentBasis(const Model& model, const Data& data, int joint) {
  const Joint& j = model.joints[static_cast<std::size_t>(joint)];
  const JointTypeInfo& t = GetJointTypeInfo(j.type);
  if (!t.global_coordinates) return j.basis;
  Mat6X A;
  t.current_basis(j.basis, data.q_joint.data() + (j.coord - model.nv_nodes), &A);
  return A;
}

Vec6 JointConstraint(const Model& model, const Data& data, int joint) {
  const Joint& j = model.joints[static_cast<std::size_t>(joint)];
  const SE3 G = j.offset_a.Inverse() * NodeFrame(data, j.node_a).Inverse() *
                NodeFrame(data, j.node_b) * j.offset_b;
  return LogSE3(JointRelativeFrame(model, data, joint).Inverse() * G);
}

void CalcJointGradient(const Joint& joint, const SE3& H_A, const SE3& H_B, const SE3& H_J,
                       JointGradient* out) {
  const SE3 G = joint.offset_a.Inverse() * H_A.Inverse() * H_B * joint.offset_b;
  out->phi = LogSE3(H_J.Inverse() * G);
  out->Tinv = TSE3Inv(out->phi);
  out->Cb_inv = joint.offset_b.Inverse();
  out->G_A = out->Cb_inv * H_B.Inverse() * H_A;
}

void CalcJointReferenceGradient(const Model& model, const Joint& joint, JointGradient* out) {
  out->phi.setZero();
  out->Tinv.setIdentity();
  out->Cb_inv = joint.offset_b.Inverse();
  out->G_A = out->Cb_inv * NodeReferenceFrame(model, joint.node_b).Inverse() *
             NodeReferenceFrame(model, joint.node_a);
}

Mat6 JointGradientA(const JointGradient& g) { return Mat6(-g.Tinv * Ad(g.G_A)); }
Mat6 JointGradientB(const JointGradient& g) { return Mat6(g.Tinv * Ad(g.Cb_inv)); }
Mat6X JointGradientCoordinates(const JointGradient& g, const Mat6X& basis, const JointMatrix& T_J) {
  return -(g.Tinv - ad(g.phi)) * basis * T_J;  // T^-1(-phi) = T^-1(phi) - ad(phi)
}

void JointGradientTransposeTimes(const JointGradient& g, const Vec6& lambda, Vec6* bt_a,
                                 Vec6* bt_b) {
  const Vec6 tl = g.Tinv.transpose() * lambda;
  *bt_a = -AdTransposeTimes(g.G_A, tl);
  *bt_b = AdTransposeTimes(g.Cb_inv, tl);
}

Vec6 JointGradientTimes(const JointGradient& g, const Vec6* x_a, const Vec6* x_b) {
  Vec6 rel = Vec6::Zero();
  if (x_b != nullptr) rel += Ad(g.Cb_inv) * *x_b;
  if (x_a != nullptr) rel -= Ad(g.G_A) * *x_a;
  return g.Tinv * rel;
}

void CalcJointConstraintForceTangent(const Joint& joint, const JointGradient& g, const Vec6& lambda,
                                     const Mat6X& basis, JointForceTangent* out) {
  const int k = static_cast<int>(basis.cols());
  const int n = 12 + k;
  // dphi / d[x_A, x_B, x_J].
  Eigen::Matrix<double, 6, Eigen::Dynamic, 0, 6, 18> dphi(6, n);
  dphi.leftCols<6>() = JointGradientA(g);
  dphi.middleCols<6>(6) = JointGradientB(g);
  if (k > 0)
    dphi.rightCols(k) = JointGradientCoordinates(g, basis, Mat6::Identity().topLeftCorner(k, k));
  const Mat6 D = DTSE3InvT(g.phi, lambda);
  const Mat6 ad_ga_t = Ad(g.G_A).transpose();
  out->resize(n, n);
  out->topRows<6>().noalias() = -ad_ga_t * D * dphi;
  out->middleRows<6>(6).noalias() = Ad(g.Cb_inv).transpose() * D * dphi;
  if (k > 0) out->bottomRows(k).noalias() = basis.transpose() * DTSE3InvT(-g.phi, lambda) * dphi;
  // The variation of Ad(G_A) in B_A^T lambda: G_A <- G_A exp(x_A - Ad(G_A^-1 C_B^-1) x_B).
  const Mat6 S = Star(AdTransposeTimes(g.G_A, g.Tinv.transpose() * lambda));
  out->block<6, 6>(0, 0) -= S;
  out->block<6, 6>(0, 6) += S * Ad(g.G_A.Inverse() * g.Cb_inv);
  // The universal joint's moving first axis A_1(alpha_2) = Ad(exp(-alpha_2 A_2)) A_1:
  // dA_1/dalpha_2 = -ad(A_2) A_1, so d(-A_1^T T^-T(-phi) lambda)/dalpha_2 = [A_2, A_1] . nu.
  if (joint.type == JointType::kUniversal) {
    const Vec6 nu = (g.Tinv - ad(g.phi)).transpose() * lambda;
    (*out)(12, 13) += Bracket(basis.col(1), basis.col(0)).dot(nu);
  }
}

void CalcJointVelocityConstraintTangent(const Joint& joint, const JointGradient& g, const Vec6* v_a,
                                        const Vec6* v_b,
                                        const Eigen::Ref<const Eigen::VectorXd>& v_j,
                                        const Mat6X& basis, JointVelocityTangent* out) {
  const int k = static_cast<int>(basis.cols());
  const int n = 12 + k;
  Eigen::Matrix<double, 6, Eigen::Dynamic, 0, 6, 18> dphi(6, n);
  dphi.leftCols<6>() = JointGradientA(g);
  dphi.middleCols<6>(6) = JointGradientB(g);
  if (k > 0)
    dphi.rightCols(k) = JointGradientCoordinates(g, basis, Mat6::Identity().topLeftCorner(k, k));
  // u = Ad(C_B^-1) v_B - Ad(G_A) v_A - A_J v_J.
  const Vec6 av_j = k > 0 ? Vec6(basis * v_j.head(k)) : Vec6::Zero();
  Vec6 u = -av_j;
  if (v_b != nullptr) u += Ad(g.Cb_inv) * *v_b;
  if (v_a != nullptr) u -= Ad(g.G_A) * *v_a;
  // [dT^-1(phi)/dphi . e_i] u for the six directions e_i, then through dphi.
  Mat6 dtinv_u;
  for (int i = 0; i < 6; ++i) dtinv_u.col(i) = TSE3InvDirectionalTimes(g.phi, Vec6::Unit(i), u);
  out->resize(6, n);
  out->noalias() = (dtinv_u - ad(av_j)) * dphi;
  // The variation of Ad(G_A) v_A: G_A <- G_A exp(x_A - Ad(G_A^-1 C_B^-1) x_B).
  if (v_a != nullptr) {
    const Mat6 W = g.Tinv * Ad(g.G_A) * ad(*v_a);
    out->leftCols<6>() += W;
    out->middleCols<6>(6) -= W * Ad(g.G_A.Inverse() * g.Cb_inv);
  }
  // The universal joint's moving first axis: dA_1/dalpha_2 = -ad(A_2) A_1, which enters
  // B_J v_J = -(T^-1(phi) - ad(phi)) A_J v_J.
  if (joint.type == JointType::kUniversal)
    out->col(13) += v_j(0) * (g.Tinv - ad(g.phi)) * ad(Vec6(basis.col(1))) * basis.col(0);
}

JointCoordinateSpring JointCoordinateSpringLaw(const Joint& j, int c, double alpha,
                                               double alpha_dot, const ProfileValue& drive,
                                               double load_factor, bool dynamics) {
  JointCoordinateSpring out;
  out.rest = j.rest(c);
  // A series-elastic drive moves the rest of its coordinate to q(t).
  if (j.drive == DriveKind::kSeriesElastic && c == j.drive_coord) {
    out.rest += load_factor * drive.value;
    out.rest_rate = load_factor * drive.rate;
  }
  out.force = j.stiffness(c) * (alpha - out.rest);
  if (dynamics) out.force += j.damping(c) * (alpha_dot - out.rest_rate);
  return out;
}

void CalcJointCoordinateTerms(const Model& model, const Data& data, int joint, double time,
                              double load_factor, bool dynamics, bool tangent,
                              JointCoordinateTerms* out) {
  const Joint& j = model.joints[static_cast<std::size_t>(joint)];
  const int k = j.k();
  out->force.setZero();
  out->stiffness.setZero();
  out->damping.setZero();
  out->drive_constraint = 0.0;
  out->term_scale = 0.0;
  if (k == 0) return;
  const auto alpha = data.q_joint.segment(j.coord - model.nv_nodes, k);
  const auto alpha_dot = data.v.segment(j.coord, k);
  ProfileValue drive{};
  if (j.drive != DriveKind::kNone) drive = EvalProfile(j.drive_profile, time, data);
  Vec6& f = out->force;
  if (GetJointTypeInfo(j.type).spring_law == JointSpringLaw::kCoordinates) {
    for (int c = 0; c < k; ++c) {
      const JointCoordinateSpring spring =
          JointCoordinateSpringLaw(j, c, alpha(c), alpha_dot(c), drive, load_factor, dynamics);
      out->term_scale =
          std::max(out->term_scale, j.stiffness(c) * (std::abs(alpha(c)) + std::abs(spring.rest)));
      f(c) = spring.force;
      out->stiffness(c, c) = j.stiffness(c);
      if (dynamics) out->damping(c, c) = j.damping(c);
    }
  } else if (j.stiffness.head(k).squaredNorm() > 0.0 || j.damping.head(k).squaredNorm() > 0.0) {
    // Energy 1/2 delta^T K delta, delta = A^T log(H_J) (spring law kLogarithm): f = A^T T^-T(xi) A K
    // delta, and its derivative along the retraction H_J exp(A dx).
    const Mat6X& A = j.basis;
    const Vec6 xi = LogSE3(data.HJ[static_cast<std::size_t>(joint)]);
    const Mat6 Ti = TSE3Inv(xi);
    const Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 6, 1> delta = A.transpose() * xi;
    const Vec6 Kd_alg = A * j.stiffness.head(k).cwiseProduct(delta);
    f.head(k) = A.transpose() * Ti.transpose() * Kd_alg;
    if (tangent)
      out->stiffness.topLeftCorner(k, k) =
          A.transpose() *
          (Ti.transpose() * A * j.stiffness.head(k).asDiagonal() * A.transpose() * Ti +
           DTSE3InvT(xi, Kd_alg) * Ti) *
          A;
    if (dynamics) {
      for (int c = 0; c < k; ++c) {
        f(c) += j.damping(c) * alpha_dot(c);
        out->damping(c, c) = j.damping(c);
      }
    }
  }
  if (j.drive == DriveKind::kForce) f(j.drive_coord) -= load_factor * drive.value;
  if (j.drive == DriveKind::kPrescribed) {
    f(j.drive_coord) += data.lambda(j.drive_row);  // B_act^T lambda_act
    out->drive_constraint = alpha(j.drive_coord) - load_factor * drive.value;
  }
}

void CalcJointCoordinateTangent(const Joint& joint, const Eigen::Ref<const Eigen::VectorXd>& x,
                                Mat6* out) {
  const int k = joint.k();
  out->setIdentity();
  const Vec6 xi = joint.basis * x.head(k);
  out->topLeftCorner(k, k) = joint.basis.transpose() * TSE3(xi) * joint.basis;
}

void RetractJoint(const Model& model, Data& data, int joint,
                  const Eigen::Ref<const Eigen::VectorXd>& dx) {
  const Joint& j = model.joints[static_cast<std::size_t>(joint)];
  const int k = j.k();
  if (k == 0) return;
  if (!GetJointTypeInfo(j.type).global_coordinates) {
    SE3& HJ = data.HJ[static_cast<std::size_t>(joint)];
    HJ = HJ * ExpSE3(j.basis * dx.head(k));
  }
  data.q_joint.segment(j.coord - model.nv_nodes, k) += dx.head(k);
}

double CalcMaxJointConstraint(const Model& model, const Data& data, double time) {
  double r = 0.0;
  for (std::size_t jj = 0; jj < model.joints.size(); ++jj) {
    const Joint& j = model.joints[jj];
    if (j.row >= 0)
      r = std::max(r, JointConstraint(model, data, static_cast<int>(jj)).cwiseAbs().maxCoeff());
    if (j.drive == DriveKind::kPrescribed)
      r = std::max(r, std::abs(data.q_joint(j.coord + j.drive_coord - model.nv_nodes) -
                               EvalProfile(j.drive_profile, time, data).value));
  }
  return r;
}

Vec6 CalcFreeJointDeflection(const Model& model, const Data& data, int joint) {
  const Joint& j = model.joints[static_cast<std::size_t>(joint)];
  return LogSE3(j.offset_a.Inverse() * NodeFrame(data, j.node_a).Inverse() *
                NodeFrame(data, j.node_b) * j.offset_b);
}

bool JointSpringKind::Calc(const Model& m, const Data& d, const Item& joint, const NodeMotion<2>& x,
                           const KernelOptions& o, ElementTerms<2>* t) {
  const Joint& j = m.joints[static_cast<std::size_t>(joint)];
  const bool has_damping = o.dynamics && j.damping.squaredNorm() > 0.0;
  if (j.stiffness.squaredNorm() == 0.0 && !has_damping) {
    t->active = false;
    return true;
  }
  const Vec6 delta = CalcFreeJointDeflection(m, d, joint);
  const Mat6x12 P = CalcRodP(delta);
  const Mat6 EA = Ad(j.offset_a.Inverse()), EB = Ad(j.offset_b.Inverse());
  Mat6x12 G;
  G.leftCols<6>().noalias() = P.leftCols<6>() * EA;
  G.rightCols<6>().noalias() = P.rightCols<6>() * EB;
  const Vec6 sigma = j.stiffness.cwiseProduct(delta);
  Vec6 f = sigma;
  if (has_damping) f += j.damping.cwiseProduct(G * x.eta);
  t->residual = G.transpose() * f;
  if (!o.tangent) return true;
  Mat12& K = t->stiffness;
  K = G.transpose() * j.stiffness.asDiagonal() * G;
  Mat6x12 geo_top = DTSE3InvT(-delta, sigma) * P, geo_bottom = DTSE3InvT(delta, sigma) * P;
  for (Mat6x12* rows : {&geo_top, &geo_bottom}) {
    rows->leftCols<6>() = rows->leftCols<6>() * EA;
    rows->rightCols<6>() = rows->rightCols<6>() * EB;
  }
  K.topRows<6>() += EA.transpose() * geo_top;
  K.bottomRows<6>() += EB.transpose() * geo_bottom;
  t->has_stiffness = true;
  if (has_damping) {
    t->damping = G.transpose() * j.damping.asDiagonal() * G;
    t->has_damping = true;
  }
  return true;
}

void JointSpringKind::AddEnergy(const Model& m, const Data& d, const Item& joint, Energy* E) {
  const Joint& j = m.joints[static_cast<std::size_t>(joint)];
  const Vec6 delta = CalcFreeJointDeflection(m, d, joint);
  E->spring += 0.5 * delta.dot(j.stiffness.cwiseProduct(delta));
}

double JointDriveEffort(const Model& model, const Data& data, int joint) {
  const Joint& j = model.joints[static_cast<std::size_t>(joint)];
  switch (j.drive) {
    case DriveKind::kNone:
      return 0.0;
    case DriveKind::kPrescribed:
      return -data.lambda(j.drive_row);
    case DriveKind::kForce:
      return EvalProfile(j.drive_profile, data.time, data).value;
    case DriveKind::kSeriesElastic: {
      // Minus the kernel's spring-damper force (0.0 - f: a spring at rest reports +0, not -0).
      const int c = j.coord + j.drive_coord;
      const JointCoordinateSpring spring =
          JointCoordinateSpringLaw(j, j.drive_coord, data.q_joint(c - model.nv_nodes), data.v(c),
                                   EvalProfile(j.drive_profile, data.time, data), 1.0, true);
      return 0.0 - spring.force;
    }
  }
  return 0.0;
}

double JointCoordinateEffort(const Model& model, const Data& data, int joint, int c) {
  const Joint& j = model.joints[static_cast<std::size_t>(joint)];
  if (j.drive != DriveKind::kNone && c == j.drive_coord)
    return JointDriveEffort(model, data, joint);
  if (j.stiffness(c) == 0.0 && j.damping(c) == 0.0 &&
      GetJointTypeInfo(j.type).spring_law == JointSpringLaw::kCoordinates)
    return 0.0;
  // The force the assembly puts on the coordinate's residual row, with its sign turned.
  JointCoordinateTerms terms;
  CalcJointCoordinateTerms(model, data, joint, data.time, 1.0, true, false, &terms);
  return -terms.force(c);
}

double JointSpringEnergy(const Model& model, const Data& data, int joint) {
  const Joint& j = model.joints[static_cast<std::size_t>(joint)];
  const int k = j.k();
  double energy = 0.0;
  if (k == 0) return energy;
  if (GetJointTypeInfo(j.type).spring_law == JointSpringLaw::kLogarithm) {
    const Vec6 xi = LogSE3(data.HJ[static_cast<std::size_t>(joint)]);
    for (int c = 0; c < k; ++c) {
      const double delta = j.basis.col(c).dot(xi);
      energy += 0.5 * j.stiffness(c) * delta * delta;
    }
    return energy;
  }
  const auto alpha = data.q_joint.segment(j.coord - model.nv_nodes, k);
  for (int c = 0; c < k; ++c) {
    double rest = j.rest(c);
    if (j.drive == DriveKind::kSeriesElastic && c == j.drive_coord)
      rest += EvalProfile(j.drive_profile, data.time, data).value;
    const double delta = alpha(c) - rest;
    energy += 0.5 * j.stiffness(c) * delta * delta;
  }
  return energy;
}

}  // namespace screwfem
