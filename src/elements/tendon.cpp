#include "screwfem/elements/tendon.h"

#include <algorithm>
#include <cmath>

#include "screwfem/elements/rod.h"

namespace screwfem {

namespace {

// S(r)^T M for a 3 x 3 block M: the rows [M; Skew(r) M] (S(r)^T y = [y; r x y]).
Eigen::Matrix<double, 6, 3> STimes(const Vec3& r, const Mat3& M) {
  Eigen::Matrix<double, 6, 3> out;
  out.topRows<3>() = M;
  out.bottomRows<3>().noalias() = Skew(r) * M;
  return out;
}

// The section frame of an eyelet between two nodes, from its element's node frames H_A, H_B:
// H_E = H_A exp(xi d) with d = log(H_A^-1 H_B) on the element's branch, and (N != nullptr)
// the interpolation N(xi, d) with dh_E = N [dh_A; dh_B].
struct SpanEnd {
  SE3 H;
  Vec6 d;
};
void CalcSpanEnd(const Data& data, const BodyPoint& p, const SE3& H_A, const SE3& H_B,
                 SpanEnd* out) {
  out->d = CalcRodRelativeMotion(H_A, H_B, data.w_ref[static_cast<std::size_t>(p.element)]);
  out->H = H_A * ExpSE3(p.xi * out->d);
}

int NodeB(const Model& model, const BodyPoint& p) {
  return model.elements[static_cast<std::size_t>(p.element)].node_b;
}

}  // namespace

Vec3 BodyPointPosition(const Data& data, const BodyPoint& point) {
  const SE3& H = NodeFrame(data, point.node);
  return H.x + H.R * point.offset;
}

SE3 BodyPointFrame(const Model& model, const Data& data, const BodyPoint& point) {
  if (point.element < 0) return NodeFrame(data, point.node);
  SpanEnd e;
  CalcSpanEnd(data, point, NodeFrame(data, point.node), NodeFrame(data, NodeB(model, point)), &e);
  return e.H;
}

Vec3 BodyPointPosition(const Model& model, const Data& data, const BodyPoint& point) {
  const SE3 H = BodyPointFrame(model, data, point);
  return H.x + H.R * point.offset;
}

bool CalcSegmentGradient(const Model& model, const Data& data, const TendonSegment& segment,
                         SegmentGradient* out) {
  const BodyPoint* ends[2] = {&segment.a, &segment.b};
  SpanEnd span[2];
  SE3 H[2];
  for (int k = 0; k < 2; ++k) {
    const BodyPoint& p = *ends[k];
    if (p.element < 0) {
      H[k] = NodeFrame(data, p.node);
    } else {
      CalcSpanEnd(data, p, NodeFrame(data, p.node), NodeFrame(data, NodeB(model, p)), &span[k]);
      H[k] = span[k].H;
    }
  }
  PointDistance g;
  if (!CalcPointDistance(H[0], segment.a.offset, H[1], segment.b.offset, false, &g)) return false;
  out->length = g.length;
  out->count = 0;
  auto add = [&](int node, const Vec6& part) {
    if (node == kGround) return;
    out->nodes[out->count] = node;
    out->parts[out->count] = part;
    ++out->count;
  };
  for (int k = 0; k < 2; ++k) {
    const BodyPoint& p = *ends[k];
    const Vec6 g_E = g.gradient.segment<6>(6 * k);
    if (p.element < 0) {
      add(p.node, g_E);
    } else {
      const Mat6x12 N = CalcRodN(p.xi, span[k].d);
      add(p.node, N.leftCols<6>().transpose() * g_E);
      add(NodeB(model, p), N.rightCols<6>().transpose() * g_E);
    }
  }
  return true;
}

bool CalcPointDistance(const SE3& H_A, const Vec3& r_A, const SE3& H_B, const Vec3& r_B,
                       bool hessian, PointDistance* out) {
  const Vec3 delta = (H_B.x + H_B.R * r_B) - (H_A.x + H_A.R * r_A);
  const double l = delta.norm();
  if (!(l > 0.0) || !std::isfinite(l)) return false;
  const Vec3 e = delta / l;
  out->length = l;
  out->direction = e;
  // docs/numerics.md, "Tendons and force elements": gradient J^T e with J = [-R_A S(r_A)  R_B S(r_B)].
  const Vec3 e_A = H_A.R.transpose() * e, e_B = H_B.R.transpose() * e;
  out->gradient.segment<3>(0) = -e_A;
  out->gradient.segment<3>(3) = -r_A.cross(e_A);
  out->gradient.segment<3>(6) = e_B;
  out->gradient.segment<3>(9) = r_B.cross(e_B);
  if (!hessian) return true;
  // J^T (I - e e^T) J / l in node-frame 3 x 3 blocks: with P_XY = R_X^T (I - e e^T) R_Y / l,
  // block (X, Y) = s_X s_Y S(r_X)^T P_XY S(r_Y), s_A = -1, s_B = +1.
  const Mat3 P = (Mat3::Identity() - e * e.transpose()) / l;
  const Mat3 P_AA = H_A.R.transpose() * P * H_A.R;
  const Mat3 P_BB = H_B.R.transpose() * P * H_B.R;
  const Mat3 P_AB = H_A.R.transpose() * P * H_B.R;
  const Mat3 SA = Skew(r_A), SB = Skew(r_B);
  Mat12& H = out->hessian;
  auto fill = [&](int row, int col, const Vec3& r_row, const Mat3& M, const Mat3& S_col,
                  double sign) {
    // S(r_row)^T M S(r_col) = [M, -M S_col; Skew(r_row) M, -Skew(r_row) M S_col].
    const Eigen::Matrix<double, 6, 3> left = STimes(r_row, M);
    H.block<6, 3>(row, col) = sign * left;
    H.block<6, 3>(row, col + 3).noalias() = -sign * left * S_col;
  };
  fill(0, 0, r_A, P_AA, SA, 1.0);
  fill(6, 6, r_B, P_BB, SB, 1.0);
  fill(0, 6, r_A, P_AB, SB, -1.0);
  fill(6, 0, r_B, P_AB.transpose(), SA, -1.0);
  // The rotation of e into each node frame: -S(r_A)^T Skew(e_A) on dtheta_A, S(r_B)^T Skew(e_B)
  // on dtheta_B.
  H.block<6, 3>(0, 3) -= STimes(r_A, Skew(e_A));
  H.block<6, 3>(6, 9) += STimes(r_B, Skew(e_B));
  return true;
}

double TendonTension(const Tendon& tendon, const Data& data, double time, double load_factor) {
  // Drawn by length: the multiplier (held at zero by its row while slack, assemble.cpp).
  if (tendon.drive == TendonDrive::kLength)
    return tendon.row >= 0 && tendon.row < data.lambda.size() ? data.lambda(tendon.row) : 0.0;
  return std::max(0.0, load_factor * EvalProfile(tendon.tension, time, data).value);
}

namespace {

// out = C T for a node tangent operator T = [A B; 0 A] (3 x 3 blocks: the SE(3) tangent of
// lie/se3.h, or the identity), C with 6 columns: [C_1 A, C_1 B + C_2 A], three products of
// 3 x 3 blocks instead of one 6 x 6.
void TimesNodeTangent(const Eigen::Matrix<double, 12, 6>& C, const Mat6& T,
                      Eigen::Ref<Eigen::Matrix<double, 12, 6>> out) {
  const Mat3 A = T.topLeftCorner<3, 3>();
  const Mat3 B = T.topRightCorner<3, 3>();
  out.leftCols<3>().noalias() = C.leftCols<3>() * A;
  out.rightCols<3>().noalias() = C.leftCols<3>() * B;
  out.rightCols<3>().noalias() += C.rightCols<3>() * A;
}

// rows [M; Skew(r) M] of S(r)^T M for a 3 x 6 block M (Skew(r) M column by column as r x m).
void AddSTimes(const Vec3& r, const Eigen::Matrix<double, 3, 6>& M, Mat6* out) {
  out->topRows<3>() += M;
  for (int j = 0; j < 6; ++j) out->block<3, 1>(3, j) += r.cross(M.col(j));
}

// M Skew(r) for a 3 x 3 block M: its row i is m_i x r (m_i the row i of M).
Mat3 TimesSkew(const Mat3& M, const Vec3& r) {
  Mat3 out;
  for (int i = 0; i < 3; ++i) out.row(i) = Vec3(M.row(i).transpose().cross(r)).transpose();
  return out;
}

}  // namespace

bool TendonSegmentKind::Calc(const Model& model, const Data& data, const Item& group,
                             const NodeMotion<2>& x, const KernelOptions& o, ElementTerms<2>* t) {
  const TendonSegmentGroup& grp = model.tendon_segment_groups[static_cast<std::size_t>(group)];
  const SE3& H_A = *x.H[0];
  const SE3& H_B = *x.H[1];
  // The stiffness blocks c_K tau d2l before the node tangents, summed over the group's segments
  // (docs/numerics.md, "Tendons and force elements", the factors of CalcPointDistance's hessian; a tendon has no mass or
  // damping). With R^T R = I, e_X = R_X^T e, s_A = -1, s_B = +1, P_X = (I - e_X e_X^T) / l and
  // P_AB = (R_A^T R_B - e_A e_B^T) / l:
  //   K_XX = S(r_X)^T [P_X   s_X Skew(e_X) - P_X Skew(r_X)]   (the string, and the rotation of e
  //                                                            into the node frame on dtheta_X),
  //   K_AB = S(r_A)^T [-P_AB   P_AB Skew(r_B)],   K_BA = K_AB^T,
  // all times c_K tau; S(r)^T M = [M; Skew(r) M].
  Mat6 K_AA, K_BB, K_AB;
  bool any = false;
  double scale = 0.0;
  for (int i = 0; i < grp.count; ++i) {
    const TendonSegment& s = model.tendon_segments[static_cast<std::size_t>(
        model.tendon_group_segments[static_cast<std::size_t>(grp.first + i)])];
    const double tau = TendonTension(model.tendons[static_cast<std::size_t>(s.tendon)], data,
                                     o.time, o.load_factor);
    if (tau == 0.0) continue;
    PointDistance g;
    if (!CalcPointDistance(H_A, s.a.offset, H_B, s.b.offset, false, &g))
      continue;  // coinciding eyelets: no direction, no force
    if (!any) {
      any = true;
      t->residual.setZero();
      if (o.tangent) {
        K_AA.setZero();
        K_BB.setZero();
        K_AB.setZero();
      }
    }
    // docs/numerics.md, "Tendons and force elements", prescribed tension: residual +tau dl/dq, tangent tau d2l.
    t->residual.noalias() += tau * g.gradient;
    const double arm = std::max({1.0, s.a.offset.norm(), s.b.offset.norm()});
    scale = std::max(scale, tau * arm);  // the pulls of two segments at an eyelet cancel
    if (!o.tangent) continue;
    const Vec3& r_A = s.a.offset;
    const Vec3& r_B = s.b.offset;
    const Vec3 e_A = -g.gradient.segment<3>(0);  // R_A^T e
    const Vec3 e_B = g.gradient.segment<3>(6);   // R_B^T e
    const double k = o.c_stiffness * tau;
    const double c = k / g.length;
    Eigen::Matrix<double, 3, 6> top;
    Mat3 P = c * (Mat3::Identity() - e_A * e_A.transpose());
    top.leftCols<3>() = P;
    top.rightCols<3>() = -k * Skew(e_A) - TimesSkew(P, r_A);
    AddSTimes(r_A, top, &K_AA);
    P = c * (Mat3::Identity() - e_B * e_B.transpose());
    top.leftCols<3>() = P;
    top.rightCols<3>() = k * Skew(e_B) - TimesSkew(P, r_B);
    AddSTimes(r_B, top, &K_BB);
    P.noalias() = H_A.R.transpose() * H_B.R;
    P.noalias() -= e_A * e_B.transpose();
    P *= c;
    top.leftCols<3>() = -P;
    top.rightCols<3>() = TimesSkew(P, r_B);
    AddSTimes(r_A, top, &K_AB);
  }
  if (!any) {
    t->active = false;
    return true;
  }
  t->force_scale = scale;
  t->term_scale = scale;
  if (!o.tangent) return true;
  // S = K blockdiag(T_A, T_B), column block by column block.
  Mat12& S = t->matrix;
  if (o.node_tangent) {
    Eigen::Matrix<double, 12, 6> C;
    C.topRows<6>() = K_AA;
    C.bottomRows<6>() = K_AB.transpose();
    TimesNodeTangent(C, *x.T[0], S.leftCols<6>());
    C.topRows<6>() = K_AB;
    C.bottomRows<6>() = K_BB;
    TimesNodeTangent(C, *x.T[1], S.rightCols<6>());
  } else {
    S.topLeftCorner<6, 6>() = K_AA;
    S.topRightCorner<6, 6>() = K_AB;
    S.bottomLeftCorner<6, 6>() = K_AB.transpose();
    S.bottomRightCorner<6, 6>() = K_BB;
  }
  t->combined = true;
  return true;
}

bool CalcSpanDistance(const Data& data, const BodyPoint& a, const BodyPoint& b,
                      const SE3* const (&H_nodes)[4], double scale, double* length,
                      Eigen::Matrix<double, 24, 1>* gradient,
                      Eigen::Matrix<double, 24, 24>* hessian) {
  const BodyPoint* ends[2] = {&a, &b};
  SpanEnd span[2];
  SE3 H[2];
  for (int k = 0; k < 2; ++k) {
    if (ends[k]->element < 0) {
      H[k] = *H_nodes[2 * k];
    } else {
      CalcSpanEnd(data, *ends[k], *H_nodes[2 * k], *H_nodes[2 * k + 1], &span[k]);
      H[k] = span[k].H;
    }
  }
  PointDistance g;
  if (!CalcPointDistance(H[0], a.offset, H[1], b.offset, hessian != nullptr, &g)) return false;
  *length = g.length;
  // dh_E = N_k [dh of the end's two nodes]; an end on a node: [I 0].
  Eigen::Matrix<double, 12, 24> N = Eigen::Matrix<double, 12, 24>::Zero();
  for (int k = 0; k < 2; ++k) {
    if (ends[k]->element < 0)
      N.block<6, 6>(6 * k, 12 * k).setIdentity();
    else
      N.block<6, 12>(6 * k, 12 * k) = CalcRodN(ends[k]->xi, span[k].d);
  }
  gradient->noalias() = scale * (N.transpose() * g.gradient);
  if (hessian == nullptr) return true;
  // scale (N^T H_l N + blockdiag(G_E P(d))): the eyelet frames' hessian carried to the nodes and
  // the variation of the interpolation at fixed g_E.
  const Eigen::Matrix<double, 12, 24> HN = g.hessian * N;
  hessian->noalias() = scale * (N.transpose() * HN);
  for (int k = 0; k < 2; ++k) {
    if (ends[k]->element < 0) continue;
    const Vec6 g_E = g.gradient.segment<6>(6 * k);
    hessian->block<12, 12>(12 * k, 12 * k).noalias() +=
        scale * (CalcRodNTransposeDerivative(ends[k]->xi, span[k].d, g_E) * CalcRodP(span[k].d));
  }
  return true;
}

bool TendonSpanSegmentKind::Calc(const Model& model, const Data& data, const Item& segment,
                                 const NodeMotion<4>& x, const KernelOptions& o,
                                 ElementTerms<4>* t) {
  const TendonSegment& s = model.tendon_segments[static_cast<std::size_t>(segment)];
  const double tau =
      TendonTension(model.tendons[static_cast<std::size_t>(s.tendon)], data, o.time, o.load_factor);
  if (tau == 0.0) {
    t->active = false;
    return true;
  }
  double length;
  if (!CalcSpanDistance(data, s.a, s.b, x.H, tau, &length, &t->residual,
                        o.tangent ? &t->stiffness : nullptr)) {
    t->active = false;  // coinciding eyelets: no direction, no force
    return true;
  }
  const double arm = std::max({1.0, s.a.offset.norm(), s.b.offset.norm()});
  t->force_scale = tau * arm;
  t->term_scale = tau * arm;
  t->has_stiffness = o.tangent;
  return true;
}

ForceElementForce ForceElementLaw(const ForceElement& fe, const Data& data, double length,
                                  double rate, double time, double load_factor) {
  ForceElementForce out;
  out.actuator = load_factor * EvalProfile(fe.actuator, time, data).value;
  out.force = fe.stiffness * (length - fe.rest_length) + fe.damping * rate + out.actuator;
  return out;
}

bool ForceElementKind::Calc(const Model& model, const Data& data, const Item& element,
                            const NodeMotion<2>& x, const KernelOptions& o, ElementTerms<2>* t) {
  const ForceElement& fe = model.force_elements[static_cast<std::size_t>(element)];
  PointDistance g;
  if (!CalcPointDistance(*x.H[0], fe.a.offset, *x.H[1], fe.b.offset, o.tangent, &g)) {
    t->active = false;  // coinciding ends: no direction, no force
    return true;
  }
  const bool damped = o.dynamics && fe.damping != 0.0;
  const double rate = damped ? g.gradient.dot(x.eta) : 0.0;
  const ForceElementForce law = ForceElementLaw(fe, data, g.length, rate, o.time, o.load_factor);
  const double f = law.force, actuator = law.actuator;
  t->residual = f * g.gradient;
  const double arm = std::max({1.0, fe.a.offset.norm(), fe.b.offset.norm()});
  t->force_scale = std::abs(f) * arm;
  t->term_scale = (fe.stiffness * std::max(g.length, fe.rest_length) + std::abs(actuator)) * arm;
  if (!o.tangent) return true;
  Mat12& K = t->stiffness;
  K.noalias() = fe.stiffness * g.gradient * g.gradient.transpose();
  K += f * g.hessian;
  t->has_stiffness = true;
  if (damped) {
    // d(dl/dt)/dq at fixed eta = (d2l^T eta)^T.
    K.noalias() += fe.damping * g.gradient * (g.hessian.transpose() * x.eta).transpose();
    t->damping.noalias() = fe.damping * g.gradient * g.gradient.transpose();
    t->has_damping = true;
  }
  return true;
}

void ForceElementKind::AddEnergy(const Model& model, const Data& data, const Item& element,
                                 Energy* E) {
  const ForceElement& fe = model.force_elements[static_cast<std::size_t>(element)];
  const double l = (BodyPointPosition(data, fe.b) - BodyPointPosition(data, fe.a)).norm();
  E->spring += 0.5 * fe.stiffness * (l - fe.rest_length) * (l - fe.rest_length);
}

namespace {

// Length and rate of the segment between two body points in the current state.
void AddSegmentState(const Model& model, const Data& data, const BodyPoint& a, const BodyPoint& b,
                     LineForceState* s) {
  SegmentGradient g;
  if (!CalcSegmentGradient(model, data, {-1, a, b}, &g))
    return;  // coinciding points: zero length, no rate
  s->length += g.length;
  for (int i = 0; i < g.count; ++i) {
    const int node[1] = {g.nodes[i]};
    Vec6 eta;
    GatherNodeMotion<1>(model, data, node, &eta, nullptr);
    s->rate += g.parts[i].dot(eta);
  }
}

}  // namespace

LineForceState CalcTendonState(const Model& model, const Data& data, int tendon,
                               double load_factor) {
  const Tendon& td = model.tendons[static_cast<std::size_t>(tendon)];
  LineForceState s;
  for (std::size_t k = 0; k + 1 < td.eyelets.size(); ++k)
    AddSegmentState(model, data, td.eyelets[k], td.eyelets[k + 1], &s);
  s.force = TendonTension(td, data, data.time, load_factor);
  return s;
}

LineForceState CalcForceElementState(const Model& model, const Data& data, int element,
                                     double load_factor) {
  const ForceElement& fe = model.force_elements[static_cast<std::size_t>(element)];
  LineForceState s;
  AddSegmentState(model, data, fe.a, fe.b, &s);
  s.force = ForceElementLaw(fe, data, s.length, s.rate, data.time, load_factor).force;
  return s;
}

ProfileValue TendonTargetLength(const Tendon& tendon, const Data& data, double time,
                                double load_factor) {
  ProfileValue p = EvalProfile(tendon.length, time, data);
  p.value = tendon.reference_length + load_factor * (p.value - tendon.reference_length);
  p.rate *= load_factor;
  p.accel *= load_factor;
  return p;
}

double CalcTendonLength(const Model& model, const Data& data, int tendon) {
  const Tendon& td = model.tendons[static_cast<std::size_t>(tendon)];
  double L = 0.0;
  for (std::size_t k = 0; k + 1 < td.eyelets.size(); ++k) {
    const BodyPoint& a = td.eyelets[k];
    const BodyPoint& b = td.eyelets[k + 1];
    L += (BodyPointPosition(model, data, b) - BodyPointPosition(model, data, a)).norm();
  }
  return L;
}

int UpdateTendonSlack(const Model& model, Data& data, double time, double load_factor) {
  int changed = 0;
  for (std::size_t i = 0; i < model.tendons.size(); ++i) {
    const Tendon& t = model.tendons[i];
    if (t.drive != TendonDrive::kLength || t.row < 0) continue;
    char& slack = data.tendon_slack[i];
    if (!slack && data.lambda(t.row) < 0.0) {
      slack = 1;
      data.lambda(t.row) = 0.0;
      ++changed;
    } else if (slack) {
      const double L = CalcTendonLength(model, data, static_cast<int>(i));
      const double target = TendonTargetLength(t, data, time, load_factor).value;
      if (L >= target - 1e-12 * std::max(1.0, target)) {
        slack = 0;
        ++changed;
      }
    }
  }
  return changed;
}

}  // namespace screwfem
