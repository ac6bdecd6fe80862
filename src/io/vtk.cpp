#include "screwfem/io/vtk.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <numbers>
#include <tuple>
#include <utility>

#include "screwfem/assemble/outputs.h"
#include "screwfem/elements/contact.h"
#include "screwfem/elements/shape_pair.h"
#include "screwfem/elements/joint.h"
#include "screwfem/elements/rod.h"
#include "screwfem/elements/tendon.h"
#include "screwfem/io/writers.h"
#include "screwfem/model/errors.h"

namespace screwfem {

namespace {

void AppendInt(std::string* text, long long value) {
  char buf[24];
  text->append(buf, std::to_chars(buf, buf + sizeof buf, value).ptr);
}

// frame_NNNNN.vtp: the frame index with at least five digits.
void AppendFrameName(std::string* text, int index) {
  char digits[16];
  char* end = std::to_chars(digits, digits + sizeof digits, index).ptr;
  *text += "frame_";
  for (std::ptrdiff_t n = end - digits; n < 5; ++n) *text += '0';
  text->append(digits, end);
  *text += ".vtp";
}

const char* kVtkTypeName[] = {"Float64", "Int32", "Int64"};
enum VtkType { kFloat64, kInt32, kInt64 };

// The opening of a <DataArray> up to its format attribute.
void AppendArrayTag(std::string* f, const char* indent, VtkType type, const char* name,
                    int components, long tuples_for_field = -1) {
  *f += indent;
  *f += "<DataArray type=\"";
  *f += kVtkTypeName[type];
  *f += "\" Name=\"";
  *f += name;
  *f += '"';
  if (components > 1) {
    *f += " NumberOfComponents=\"";
    AppendInt(f, components);
    *f += '"';
  }
  if (tuples_for_field >= 0) {
    *f += " NumberOfTuples=\"";
    AppendInt(f, tuples_for_field);
    *f += '"';
  }
}

// Writes `size` bytes to a new file `name` of `folder` (open/write/close: no stdio buffer to
// allocate; OutputFolder::Create: never through a link). On failure removes the file and
// returns false with errno kept.
bool WriteWholeFile(const OutputFolder& folder, const char* name, const char* data,
                    std::size_t size) {
  const int fd = folder.Create(name);
  if (fd < 0) return false;
  bool ok = true;
  while (ok && size > 0) {
    const ssize_t n = ::write(fd, data, size);
    if (n < 0 && errno == EINTR) continue;
    ok = n > 0;
    if (ok) {
      data += n;
      size -= static_cast<std::size_t>(n);
    }
  }
  int saved = errno;
  if (::close(fd) != 0 && ok) {
    ok = false;
    saved = errno;
  }
  if (!ok) {
    folder.Remove(name);
    errno = saved;
  }
  return ok;
}

}  // namespace

void VtkWriter::Open(const std::string& dir, const Model& model, VtkFormat format,
                     int expected_frames, bool rod_fields) {
  if (!IsEnumValue(format)) throw InputError("VtkWriter::Open: unknown VtkFormat value");
  // An empty dir composes frames in memory only (ComposeFrame, the live view).
  if (!dir.empty()) folder_.Open(dir, true);
  Prepare(model, format, expected_frames, rod_fields);
}

void VtkWriter::Open(const OutputFolder& parent, const Model& model, VtkFormat format,
                     int expected_frames, bool rod_fields) {
  if (!IsEnumValue(format)) throw InputError("VtkWriter::Open: unknown VtkFormat value");
  folder_.OpenSubfolder(parent, kVtkFolder, true);
  Prepare(model, format, expected_frames, rod_fields);
}

void VtkWriter::Prepare(const Model& model, VtkFormat format, int expected_frames,
                        bool rod_fields) {
  format_ = format;
  times_.clear();
  times_.reserve(static_cast<std::size_t>(std::max(expected_frames, 1)));
  name_.reserve(32);
  LayOut(model);
  rod_fields_ = rod_fields;
  LayOutRodFields(model);
  if (format_ == VtkFormat::kBinary) {
    ComposeBinaryImage();
  } else {
    // Room for a frame of shortest doubles (at most 24 characters each) and the cells.
    image_.clear();
    image_.reserve(4096 + (rod_fields_ ? 900 : 600) * sources_.size() +
                   24 * (vert_connectivity_.size() + line_connectivity_.size()) +
                   120 * cell_rod_.size());
  }
}

long long VtkWriter::AddPoint(const PointSource& source, double radius, const Vec3& half_size,
                              int joint) {
  sources_.push_back(source);
  point_joint_.push_back(joint);
  radius_.push_back(radius);
  for (int k = 0; k < 3; ++k) half_size_.push_back(half_size(k));
  return static_cast<long long>(sources_.size()) - 1;
}

void VtkWriter::AddVertex(long long point, const CellInfo& cell) {
  vert_connectivity_.push_back(point);
  vert_offsets_.push_back(static_cast<long long>(vert_connectivity_.size()));
  vert_cells_.push_back(cell);
}

void VtkWriter::EndLine(const CellInfo& cell) {
  line_offsets_.push_back(static_cast<long long>(line_connectivity_.size()));
  line_cells_.push_back(cell);
}

void VtkWriter::AddLine(std::initializer_list<long long> points, const CellInfo& cell) {
  line_connectivity_.insert(line_connectivity_.end(), points.begin(), points.end());
  EndLine(cell);
}

namespace {

// The drawn size of a rod's section: (radius, half sizes along the section frame's x, y, z).
std::pair<double, Vec3> RodSectionSize(const Model& model, int rod) {
  const Section& s = model.rods[static_cast<std::size_t>(rod)].section;
  if (s.width > 0.0 && s.height > 0.0) {
    const double radius = s.round ? 0.5 * s.width : 0.5 * std::hypot(s.width, s.height);
    return {radius, Vec3(0.0, 0.5 * s.width, 0.5 * s.height)};
  }
  for (const ContactRod& c : model.contact_rods)
    if (c.rod == rod) return {c.radius, Vec3(0.0, c.radius, c.radius)};
  return {0.0, Vec3::Zero()};
}

// The solid box of a rigid body's mass and inertia: its principal axes (columns, a rotation)
// and half sizes, a_i^2 = 3 (I_j + I_k - I_i) / (2 m) (a negative value, from inertia no box
// has, clamped to 0). False for a body without mass or inertia.
bool InertiaBox(const RigidBody& body, Mat3* axes, Vec3* half) {
  if (!(body.mass > 0.0) || !(body.inertia.trace() > 0.0)) return false;
  const Eigen::SelfAdjointEigenSolver<Mat3> eigen(0.5 * (body.inertia + body.inertia.transpose()));
  *axes = eigen.eigenvectors();
  if (axes->determinant() < 0.0) axes->col(2) *= -1.0;
  const Vec3 I = eigen.eigenvalues();
  for (int i = 0; i < 3; ++i) {
    const double a2 = 1.5 * (I((i + 1) % 3) + I((i + 2) % 3) - I(i)) / body.mass;
    (*half)(i) = std::sqrt(std::max(a2, 0.0));
  }
  return true;
}

}  // namespace

// The drawn points and cells; constant for a model.
void VtkWriter::LayOut(const Model& model) {
  sources_.clear();
  vert_connectivity_.clear();
  vert_offsets_.clear();
  line_connectivity_.clear();
  line_offsets_.clear();
  vert_cells_.clear();
  line_cells_.clear();
  point_joint_.clear();
  radius_.clear();
  half_size_.clear();

  // Joints: a vertex at the joint frame H_A C_A H_J, moving with side B when it is a node.
  std::vector<std::vector<Vec3>> attachments(model.nodes.size());
  for (std::size_t jj = 0; jj < model.joints.size(); ++jj) {
    const Joint& j = model.joints[jj];
    const int joint = static_cast<int>(jj);
    PointSource s;
    s.kind = PointSource::Kind::kJoint;
    s.index = joint;
    AddVertex(AddPoint(s, 0.0, Vec3::Zero(), joint), {VtkCellKind::kJoint, joint, -1, -1, joint});
    if (j.node_a != kGround)
      attachments[static_cast<std::size_t>(j.node_a)].push_back(j.offset_a.x);
    if (j.node_b != kGround)
      attachments[static_cast<std::size_t>(j.node_b)].push_back(j.offset_b.x);
  }

  // Rods: polylines through their nodes, with the section's size.
  for (std::size_t r = 0; r < model.rods.size(); ++r) {
    const int rod = static_cast<int>(r);
    const auto [radius, half] = RodSectionSize(model, rod);
    for (int node : model.rods[r].nodes) {
      PointSource s;
      s.index = node;
      line_connectivity_.push_back(AddPoint(s, radius, half));
    }
    EndLine({VtkCellKind::kRod, rod, rod, -1, -1});
  }

  LayOutBodies(model, attachments);
  LayOutLines(model);
  LayOutContact(model);
  LayOutChambers(model);

  // Cell data in the order VTK stores the cells: vertices, then lines.
  cell_kind_.clear();
  cell_item_.clear();
  cell_rod_.clear();
  cell_body_.clear();
  cell_joint_.clear();
  for (const std::vector<CellInfo>* cells : {&vert_cells_, &line_cells_})
    for (const CellInfo& c : *cells) {
      cell_kind_.push_back(static_cast<int>(c.kind));
      cell_item_.push_back(c.item);
      cell_rod_.push_back(c.rod);
      cell_body_.push_back(c.body);
      cell_joint_.push_back(c.joint);
    }
  tension_.assign(cell_kind_.size(), 0.0);

  const std::size_t n = 3 * sources_.size();
  for (std::vector<double>& axis : frame_axes_) axis.assign(n, 0.0);
  velocity_.assign(n, 0.0);
  position_.assign(n, 0.0);
  contact_force_.assign(n, 0.0);
  contact_state_.assign(model.contact_pairs.empty() && model.contact_segments.empty() ? 0 : n, 0.0);
}

// Rigid bodies: segments from the node origin to the centre of mass and the attachments (a
// vertex at the node for a body without any), the box of the inertia, the contact shapes.
void VtkWriter::LayOutBodies(const Model& model,
                             const std::vector<std::vector<Vec3>>& attachments) {
  for (std::size_t b = 0; b < model.bodies.size(); ++b) {
    const RigidBody& body = model.bodies[b];
    const int id = static_cast<int>(b);
    const CellInfo segment{VtkCellKind::kBodySegment, id, -1, id, -1};
    std::vector<Vec3> ends = attachments[static_cast<std::size_t>(body.node)];
    ends.push_back(body.com);
    PointSource s;
    s.index = body.node;
    const long long origin = AddPoint(s);
    bool drawn = false;
    for (std::size_t e = 0; e < ends.size(); ++e) {
      const Vec3& p = ends[e];
      bool repeated = p.norm() <= 1e-12 * model.length_scale;
      for (std::size_t f = 0; f < e && !repeated; ++f)
        repeated = (ends[f] - p).norm() <= 1e-12 * model.length_scale;
      if (repeated) continue;
      PointSource end = s;
      end.offset = p;
      end.origin = false;
      AddLine({origin, AddPoint(end)}, segment);
      drawn = true;
    }
    if (!drawn) AddVertex(origin, {VtkCellKind::kBodyPoint, id, -1, id, -1});

    Mat3 axes;
    Vec3 half;
    if (InertiaBox(body, &axes, &half)) {
      PointSource c = s;
      c.offset = body.com;
      c.origin = false;
      c.rotated = true;
      c.axes = axes;
      AddVertex(AddPoint(c, half.norm(), half), {VtkCellKind::kInertiaBox, id, -1, id, -1});
    }
  }

  for (std::size_t i = 0; i < model.contact_shapes.size(); ++i) {
    const ContactShape& shape = model.contact_shapes[i];
    const int id = static_cast<int>(i);
    PointSource s;
    s.index = model.bodies[static_cast<std::size_t>(shape.body)].node;
    s.offset = shape.from;
    s.origin = false;
    const double r = shape.radius;
    switch (shape.type) {
      case ContactShapeType::kSphere:
        AddVertex(AddPoint(s, r, Vec3::Constant(r)), {VtkCellKind::kSphere, id, -1, shape.body});
        break;
      case ContactShapeType::kBox:
        // Its frame axes along its edges (half_size along them).
        s.rotated = true;
        s.axes = shape.rotation;
        AddVertex(AddPoint(s, shape.to.norm(), shape.to), {VtkCellKind::kBox, id, -1, shape.body});
        break;
      case ContactShapeType::kCylinder: {
        PointSource to = s;
        to.offset = shape.to;
        AddLine({AddPoint(s, r, Vec3::Constant(r)), AddPoint(to, r, Vec3::Constant(r))},
                {VtkCellKind::kCylinder, id, -1, shape.body});
        break;
      }
      case ContactShapeType::kCapsule: {
        PointSource to = s;
        to.offset = shape.to;
        AddLine({AddPoint(s, r, Vec3::Constant(r)), AddPoint(to, r, Vec3::Constant(r))},
                {VtkCellKind::kCapsule, id, -1, shape.body});
        break;
      }
    }
  }
}

// Tendons: polylines through their eyelets; force elements: a line between their ends.
void VtkWriter::LayOutLines(const Model& model) {
  const auto body_point = [&](const BodyPoint& p) {
    PointSource s;
    s.kind = p.node == kGround ? PointSource::Kind::kWorld : PointSource::Kind::kNode;
    s.index = p.node;
    if (p.element >= 0) {  // an eyelet between nodes: on its element's section
      s.kind = PointSource::Kind::kSection;
      s.index = p.element;
      s.xi = p.xi;
    }
    s.offset = p.offset;
    s.origin = false;
    return AddPoint(s);
  };
  for (std::size_t t = 0; t < model.tendons.size(); ++t) {
    for (const BodyPoint& e : model.tendons[t].eyelets) line_connectivity_.push_back(body_point(e));
    EndLine({VtkCellKind::kTendon, static_cast<int>(t)});
  }
  for (std::size_t f = 0; f < model.force_elements.size(); ++f) {
    const ForceElement& fe = model.force_elements[f];
    AddLine({body_point(fe.a), body_point(fe.b)},
            {VtkCellKind::kForceElement, static_cast<int>(f)});
  }
}

// Contact: the points that carry the contact forces, and the obstacles.
void VtkWriter::LayOutContact(const Model& model) {
  // Contact pairs: a vertex at each pair's surface point, carrying the contact force.
  for (std::size_t i = 0; i < model.contact_pairs.size(); ++i) {
    PointSource s;
    s.kind = PointSource::Kind::kContact;
    s.index = static_cast<int>(i);
    AddVertex(AddPoint(s), {VtkCellKind::kContact, s.index});
  }
  // Moving shapes: a vertex per contact segment (the pairs change from step to step), at the
  // force-weighted mean of its contact points, carrying the sum of its contact forces.
  if (MayHaveShapePairs(model))
    for (std::size_t i = 0; i < model.contact_segments.size(); ++i) {
      PointSource s;
      s.kind = PointSource::Kind::kPairContact;
      s.index = static_cast<int>(i);
      AddVertex(AddPoint(s), {VtkCellKind::kPairContact, s.index});
    }
  segment_force_.assign(model.contact_segments.size(), Vec3::Zero());
  segment_point_.assign(model.contact_segments.size(), Vec3::Zero());
  segment_weight_.assign(model.contact_segments.size(), 0.0);
  segment_state_.assign(model.contact_segments.size(), Vec3::Zero());

  // Obstacles, fixed in the world: a plane's point with z along its normal, a sphere's
  // centre, a capsule's axis.
  for (std::size_t i = 0; i < model.obstacles.size(); ++i) {
    const ContactObstacle& o = model.obstacles[i];
    const int id = static_cast<int>(i);
    PointSource s;
    s.kind = PointSource::Kind::kWorld;
    s.offset = o.point;
    s.origin = false;
    const Vec3 r3 = Vec3::Constant(o.radius);
    switch (o.type) {
      case ObstacleType::kPlane: {
        const Mat3 along = FrameAlong(o.normal, Vec3::UnitZ());  // x along the normal
        s.rotated = true;
        s.axes << along.col(1), along.col(2), along.col(0);
        AddVertex(AddPoint(s), {VtkCellKind::kPlane, id});
        break;
      }
      case ObstacleType::kSphere:
        AddVertex(AddPoint(s, o.radius, r3), {VtkCellKind::kObstacleSphere, id});
        break;
      case ObstacleType::kCapsule:
      case ObstacleType::kCylinder: {
        PointSource to = s;
        to.offset = o.to;
        AddLine({AddPoint(s, o.radius, r3), AddPoint(to, o.radius, r3)},
                {o.type == ObstacleType::kCapsule ? VtkCellKind::kObstacleCapsule
                                                  : VtkCellKind::kObstacleCylinder,
                 id});
        break;
      }
      case ObstacleType::kBox:
        s.rotated = true;
        s.axes = o.rotation;
        AddVertex(AddPoint(s, o.to.norm(), o.to), {VtkCellKind::kObstacleBox, id});
        break;
      case ObstacleType::kMesh:
      case ObstacleType::kHeightfield:
        LayOutMesh(o, id);
        break;
    }
  }
}

// A mesh or height-field obstacle: its world vertices, each triangle a closed polyline
// a-b-c-a (a wireframe; kind kObstacleMesh, item the obstacle).
void VtkWriter::LayOutMesh(const ContactObstacle& o, int id) {
  if (!o.tree) return;
  const std::vector<Vec3>& v = o.tree->vertices();
  const long long first = static_cast<long long>(sources_.size());
  for (const Vec3& p : v) {
    PointSource s;
    s.kind = PointSource::Kind::kWorld;
    s.offset = p;
    s.origin = false;
    AddPoint(s);
  }
  for (const std::array<int, 3>& t : o.tree->faces())
    AddLine({first + t[0], first + t[1], first + t[2], first + t[0]},
            {VtkCellKind::kObstacleMesh, id});
}

// The rods' polylines are the first lines (LayOut): point k of rod r is its node k, between
// its elements k - 1 and k.
// Pressure chambers: a polyline per actuator of type pressure through its centroid at the rod
// nodes it covers, of the radius of a circle of its area.
void VtkWriter::LayOutChambers(const Model& model) {
  for (std::size_t a = 0; a < model.actuators.size(); ++a) {
    const Actuator& act = model.actuators[a];
    if (act.type != ActuatorType::kPressure || act.rod < 0 || act.num_elements <= 0) continue;
    const Rod& rod = model.rods[static_cast<std::size_t>(act.rod)];
    const int first = act.first_element - rod.first_element;
    if (first < 0 || first + act.num_elements >= static_cast<int>(rod.nodes.size())) continue;
    const double radius = std::sqrt(std::max(act.area, 0.0) / std::numbers::pi);
    for (int k = first; k <= first + act.num_elements; ++k) {
      PointSource s;
      s.index = rod.nodes[static_cast<std::size_t>(k)];
      s.origin = false;
      s.offset = Vec3(0.0, act.offset(1), act.offset(2));
      s.rotated = true;
      line_connectivity_.push_back(AddPoint(s, radius, Vec3(0.0, radius, radius)));
    }
    EndLine({VtkCellKind::kChamber, static_cast<int>(a), act.rod, -1, -1});
  }
}

void VtkWriter::LayOutRodFields(const Model& model) {
  rod_points_.clear();
  const std::size_t n = rod_fields_ ? 6 * sources_.size() : 0;
  strain_.assign(n, 0.0);
  stress_.assign(n, 0.0);
  if (!rod_fields_) return;
  long long first_station = 0;
  for (std::size_t r = 0; r < model.rods.size(); ++r) {
    const long long elements = model.rods[r].num_elements;
    const std::size_t begin = r == 0 ? 0 : static_cast<std::size_t>(line_offsets_[r - 1]);
    for (long long k = 0; k <= elements; ++k)
      rod_points_.push_back({line_connectivity_[begin + static_cast<std::size_t>(k)],
                             first_station + std::max(k - 1, 0LL),
                             first_station + std::min(k, elements - 1)});
    first_station += elements;
  }
  field_rows_.assign(static_cast<std::size_t>(kRodFieldValues * first_station), 0.0);
}

void VtkWriter::CalcRodFields(const Model& model, const Data& data, double load_factor) {
  CalcRodFieldRows(model, data, -1, load_factor, &field_rows_);
  const auto row = [&](long long station) {
    return &field_rows_[static_cast<std::size_t>(station * kRodFieldValues)];
  };
  for (const auto& [point, a, b] : rod_points_) {
    const double *ra = row(a), *rb = row(b);  // rod, s, then the strain and the stress
    double* strain = &strain_[static_cast<std::size_t>(6 * point)];
    double* stress = &stress_[static_cast<std::size_t>(6 * point)];
    for (int c = 0; c < 6; ++c) {
      strain[c] = 0.5 * (ra[2 + c] + rb[2 + c]);
      stress[c] = 0.5 * (ra[8 + c] + rb[8 + c]);
    }
  }
}

// Positions, frame axes and velocities of the points at data's state (assemble/outputs.h).
void VtkWriter::CalcPoints(const Model& model, const Data& data, double load_factor) {
  // The contact forces on each contact segment, and their points weighted by |F|.
  std::fill(segment_force_.begin(), segment_force_.end(), Vec3::Zero());
  std::fill(segment_point_.begin(), segment_point_.end(), Vec3::Zero());
  std::fill(segment_weight_.begin(), segment_weight_.end(), 0.0);
  std::fill(segment_state_.begin(), segment_state_.end(), Vec3::Zero());
  for (int p = 0; p < data.num_shape_pairs && !segment_force_.empty(); ++p) {
    const ShapePairState c = CalcShapePairState(model, data, p);
    if (!c.active) continue;
    const ShapePair& pair = data.shape_pairs[static_cast<std::size_t>(p)];
    const Vec3 F = c.normal_force * c.normal + c.friction_force;
    for (int side = 0; side < 2; ++side) {
      const std::size_t g = static_cast<std::size_t>(pair.segment[side]);
      segment_force_[g] += side == 0 ? F : Vec3(-F);
      segment_point_[g] += F.norm() * c.point[side];
      segment_weight_[g] += F.norm();
      Vec3& st = segment_state_[g];
      st = Vec3(std::max(st(0), c.slipping ? 1.0 : 0.0), std::max(st(1), c.deflection),
                std::max(st(2), c.friction_share));
    }
  }
  const auto node_point = [&](int node, const Vec3& p) {
    return node == kGround ? PointMotion{p, Vec3::Zero(), Vec3::Zero()}
                           : CalcNodePointMotion(model, data, node, p);
  };
  for (std::size_t i = 0; i < sources_.size(); ++i) {
    const PointSource& s = sources_[i];
    Vec3 x, v;
    Mat3 R;
    if (s.kind == PointSource::Kind::kWorld) {
      x = s.offset;
      R = s.axes;
      v = Vec3::Zero();
    } else if (s.kind == PointSource::Kind::kContact) {
      const ContactState c = CalcContactState(model, data, s.index);
      x = c.point;
      R = Mat3::Identity();
      v = Vec3::Zero();
      const Vec3 F = c.active ? Vec3(c.normal_force * c.normal + c.friction_force) : Vec3::Zero();
      for (int k = 0; k < 3; ++k) contact_force_[3 * i + k] = F(k);
      if (!contact_state_.empty()) {
        contact_state_[3 * i] = c.active && c.slipping ? 1.0 : 0.0;
        contact_state_[3 * i + 1] = c.active ? c.deflection : 0.0;
        contact_state_[3 * i + 2] = c.active ? c.friction_share : 0.0;
      }
    } else if (s.kind == PointSource::Kind::kSection) {
      // H_A exp(xi d) and the interpolated body velocity N(xi, d) [eta_A; eta_B] (docs/numerics.md, "Rod inertia").
      const RodElement& e = model.elements[static_cast<std::size_t>(s.index)];
      const SE3& HA = NodeFrame(data, e.node_a);
      const Vec6 d = CalcRodRelativeMotion(HA, NodeFrame(data, e.node_b),
                                           data.w_ref[static_cast<std::size_t>(s.index)]);
      const SE3 H = HA * ExpSE3(s.xi * d);
      const int nodes[2] = {e.node_a, e.node_b};
      Vec12 eta;
      GatherNodeMotion<2>(model, data, nodes, &eta, nullptr);
      const Vec6 eta_s = CalcRodN(s.xi, d) * eta;
      x = H.Act(s.offset);
      R = H.R;
      v = CalcPointMotion(H, eta_s, Vec6::Zero(), s.offset).velocity;
    } else if (s.kind == PointSource::Kind::kPairContact) {
      const std::size_t g = static_cast<std::size_t>(s.index);
      const double w = segment_weight_[g];
      if (w > 0.0) {
        x = segment_point_[g] / w;
      } else {  // no contact: the middle of the segment (or the box's centre)
        const ShapePairSide& sd = model.contact_segments[g].side;
        const SE3& Ha = NodeFrame(data, sd.node[sd.end_node[0]]);
        const SE3& Hb = NodeFrame(data, sd.node[sd.end_node[1]]);
        x = 0.5 * (Ha.Act(sd.offset[0]) + Hb.Act(sd.half.x() > 0.0 ? sd.offset[0] : sd.offset[1]));
      }
      R = Mat3::Identity();
      v = Vec3::Zero();
      for (int k = 0; k < 3; ++k) contact_force_[3 * i + k] = segment_force_[g](k);
      for (int k = 0; k < 3 && !contact_state_.empty(); ++k)
        contact_state_[3 * i + static_cast<std::size_t>(k)] = segment_state_[g](k);
    } else if (s.kind == PointSource::Kind::kJoint) {
      const Joint& j = model.joints[static_cast<std::size_t>(s.index)];
      const SE3 H =
          NodeFrame(data, j.node_a) * j.offset_a * JointRelativeFrame(model, data, s.index);
      x = H.x;
      R = H.R;
      v = j.node_b != kGround ? node_point(j.node_b, j.offset_b.x).velocity
                              : node_point(j.node_a, j.offset_a.x).velocity;
    } else {
      const SE3& H = data.H[static_cast<std::size_t>(s.index)];
      x = s.origin ? H.x : H.Act(s.offset);
      R = s.rotated ? Mat3(H.R * s.axes) : H.R;
      v = node_point(s.index, s.offset).velocity;
    }
    for (int k = 0; k < 3; ++k) {
      position_[3 * i + k] = x(k);
      velocity_[3 * i + k] = v(k);
      for (int axis = 0; axis < 3; ++axis) frame_axes_[axis][3 * i + k] = R(k, axis);
    }
  }
  // Tendon tensions and force element forces at the load factor, as tendons.csv and forces.csv
  // give them.
  for (std::size_t c = 0; c < cell_kind_.size(); ++c) {
    const VtkCellKind kind = static_cast<VtkCellKind>(cell_kind_[c]);
    if (kind == VtkCellKind::kTendon)
      tension_[c] = CalcTendonState(model, data, cell_item_[c], load_factor).force;
    else if (kind == VtkCellKind::kForceElement)
      tension_[c] = CalcForceElementState(model, data, cell_item_[c], load_factor).force;
  }
}

// The binary file: the XML with offsets into the appended block, then the block, every array
// as UInt64 byte count + values. All sizes are fixed by the model, so only the doubles change
// from frame to frame (time_at_, frame_axes_at_, velocity_at_, position_at_).
void VtkWriter::ComposeBinaryImage() {
  struct Block {
    const void* data;
    std::size_t bytes;
    std::size_t* at;  // where the values land in image_ (nullptr: constant)
  };
  std::vector<Block> blocks;
  std::string& f = image_;
  f.clear();
  std::uint64_t offset = 0;
  const double zero_time = 0.0;
  const auto array = [&](const char* indent, VtkType type, const char* name, int components,
                         const void* data, std::size_t count, std::size_t* at,
                         long field_tuples = -1) {
    AppendArrayTag(&f, indent, type, name, components, field_tuples);
    f += " format=\"appended\" offset=\"";
    AppendInt(&f, static_cast<long long>(offset));
    f += "\"/>\n";
    const std::size_t bytes = count * (type == kInt32 ? 4 : 8);
    blocks.push_back({data, bytes, at});
    offset += sizeof(std::uint64_t) + bytes;
  };
  const std::size_t n = sources_.size();

  f += "<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"";
  f += std::endian::native == std::endian::little ? "LittleEndian" : "BigEndian";
  f += "\" header_type=\"UInt64\">\n  <PolyData>\n    <FieldData>\n";
  array("      ", kFloat64, "TimeValue", 1, &zero_time, 1, &time_at_, 1);
  f += "    </FieldData>\n    <Piece NumberOfPoints=\"";
  AppendInt(&f, static_cast<long long>(n));
  f += "\" NumberOfVerts=\"";
  AppendInt(&f, static_cast<long long>(vert_offsets_.size()));
  f += "\" NumberOfLines=\"";
  AppendInt(&f, static_cast<long long>(line_offsets_.size()));
  f += "\" NumberOfStrips=\"0\" NumberOfPolys=\"0\">\n      <PointData Vectors=\"velocity\">\n";
  const char* axis_names[] = {"frame_x", "frame_y", "frame_z"};
  for (int axis = 0; axis < 3; ++axis)
    array("        ", kFloat64, axis_names[axis], 3, frame_axes_[axis].data(), 3 * n,
          &frame_axes_at_[axis]);
  array("        ", kFloat64, "velocity", 3, velocity_.data(), 3 * n, &velocity_at_);
  array("        ", kFloat64, "contact_force", 3, contact_force_.data(), 3 * n, &contact_force_at_);
  if (!contact_state_.empty())
    array("        ", kFloat64, "contact_state", 3, contact_state_.data(), 3 * n,
          &contact_state_at_);
  array("        ", kInt32, "joint_id", 1, point_joint_.data(), n, nullptr);
  array("        ", kFloat64, "radius", 1, radius_.data(), n, nullptr);
  array("        ", kFloat64, "half_size", 3, half_size_.data(), 3 * n, nullptr);
  if (rod_fields_) {
    array("        ", kFloat64, "strain", 6, strain_.data(), 6 * n, &strain_at_);
    array("        ", kFloat64, "stress", 6, stress_.data(), 6 * n, &stress_at_);
  }
  f += "      </PointData>\n      <CellData Scalars=\"rod_id\">\n";
  const std::size_t cells = cell_kind_.size();
  array("        ", kInt32, "rod_id", 1, cell_rod_.data(), cells, nullptr);
  array("        ", kInt32, "body_id", 1, cell_body_.data(), cells, nullptr);
  array("        ", kInt32, "joint_id", 1, cell_joint_.data(), cells, nullptr);
  array("        ", kInt32, "kind", 1, cell_kind_.data(), cells, nullptr);
  array("        ", kInt32, "item_id", 1, cell_item_.data(), cells, nullptr);
  array("        ", kFloat64, "tension", 1, tension_.data(), cells, &tension_at_);
  f += "      </CellData>\n      <Points>\n";
  array("        ", kFloat64, "position", 3, position_.data(), 3 * n, &position_at_);
  f += "      </Points>\n";
  for (const auto& [tag, connectivity, offsets] :
       {std::tuple{"Verts", &vert_connectivity_, &vert_offsets_},
        std::tuple{"Lines", &line_connectivity_, &line_offsets_}}) {
    if (offsets->empty()) continue;
    f += "      <";
    f += tag;
    f += ">\n";
    array("        ", kInt64, "connectivity", 1, connectivity->data(), connectivity->size(),
          nullptr);
    array("        ", kInt64, "offsets", 1, offsets->data(), offsets->size(), nullptr);
    f += "      </";
    f += tag;
    f += ">\n";
  }
  f += "    </Piece>\n  </PolyData>\n  <AppendedData encoding=\"raw\">\n   _";
  f.reserve(f.size() + offset + 64);
  for (const Block& b : blocks) {
    const std::uint64_t bytes = b.bytes;
    f.append(reinterpret_cast<const char*>(&bytes), sizeof bytes);
    if (b.at != nullptr) *b.at = f.size();
    f.append(static_cast<const char*>(b.data), b.bytes);
  }
  f += "\n  </AppendedData>\n</VTKFile>\n";
}

// The ascii file of the current values.
void VtkWriter::ComposeAsciiImage(double time) {
  std::string& f = image_;
  f.clear();
  const auto doubles = [&](const char* name, const std::vector<double>& values,
                           std::size_t components = 3) {
    AppendArrayTag(&f, "        ", kFloat64, name, static_cast<int>(components));
    f += " format=\"ascii\">\n";
    for (std::size_t i = 0; i < values.size(); i += components) {
      f += "         ";
      for (std::size_t k = i; k < i + components; ++k) {
        f += ' ';
        AppendShortest(&f, values[k]);
      }
      f += '\n';
    }
    f += "        </DataArray>\n";
  };
  const auto integers = [&](VtkType type, const char* name, const auto& values) {
    AppendArrayTag(&f, "        ", type, name, 1);
    f += " format=\"ascii\">\n         ";
    for (const auto v : values) {
      f += ' ';
      AppendInt(&f, v);
    }
    f += "\n        </DataArray>\n";
  };

  f += "<?xml version=\"1.0\"?>\n"
       "<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\" "
       "header_type=\"UInt64\">\n"
       "  <PolyData>\n    <FieldData>\n";
  AppendArrayTag(&f, "      ", kFloat64, "TimeValue", 1, 1);
  f += " format=\"ascii\">\n        ";
  AppendShortest(&f, time);
  f += "\n      </DataArray>\n    </FieldData>\n    <Piece NumberOfPoints=\"";
  AppendInt(&f, static_cast<long long>(sources_.size()));
  f += "\" NumberOfVerts=\"";
  AppendInt(&f, static_cast<long long>(vert_offsets_.size()));
  f += "\" NumberOfLines=\"";
  AppendInt(&f, static_cast<long long>(line_offsets_.size()));
  f += "\" NumberOfStrips=\"0\" NumberOfPolys=\"0\">\n      <PointData Vectors=\"velocity\">\n";
  doubles("frame_x", frame_axes_[0]);
  doubles("frame_y", frame_axes_[1]);
  doubles("frame_z", frame_axes_[2]);
  doubles("velocity", velocity_);
  doubles("contact_force", contact_force_);
  if (!contact_state_.empty()) doubles("contact_state", contact_state_);
  integers(kInt32, "joint_id", point_joint_);
  doubles("radius", radius_, 1);
  doubles("half_size", half_size_);
  if (rod_fields_) {
    doubles("strain", strain_, 6);
    doubles("stress", stress_, 6);
  }
  f += "      </PointData>\n      <CellData Scalars=\"rod_id\">\n";
  integers(kInt32, "rod_id", cell_rod_);
  integers(kInt32, "body_id", cell_body_);
  integers(kInt32, "joint_id", cell_joint_);
  integers(kInt32, "kind", cell_kind_);
  integers(kInt32, "item_id", cell_item_);
  doubles("tension", tension_, 1);
  f += "      </CellData>\n      <Points>\n";
  doubles("position", position_);
  f += "      </Points>\n";
  if (!vert_offsets_.empty()) {
    f += "      <Verts>\n";
    integers(kInt64, "connectivity", vert_connectivity_);
    integers(kInt64, "offsets", vert_offsets_);
    f += "      </Verts>\n";
  }
  if (!line_offsets_.empty()) {
    f += "      <Lines>\n";
    integers(kInt64, "connectivity", line_connectivity_);
    integers(kInt64, "offsets", line_offsets_);
    f += "      </Lines>\n";
  }
  f += "    </Piece>\n  </PolyData>\n</VTKFile>\n";
}

bool VtkWriter::WriteFrame(const Model& model, const Data& data, double time, double load_factor) {
  ComposeFrame(model, data, time, load_factor);
  name_.clear();
  AppendFrameName(&name_, frames());
  if (!WriteWholeFile(folder_, name_.c_str(), image_.data(), image_.size())) return false;
  times_.push_back(time);
  return true;
}

const std::string& VtkWriter::ComposeFrame(const Model& model, const Data& data, double time,
                                           double load_factor) {
  CalcPoints(model, data, load_factor);
  if (rod_fields_) CalcRodFields(model, data, load_factor);
  if (format_ == VtkFormat::kBinary) {
    std::memcpy(&image_[time_at_], &time, sizeof time);
    const std::size_t bytes = position_.size() * sizeof(double);
    for (int axis = 0; axis < 3; ++axis)
      std::memcpy(&image_[frame_axes_at_[axis]], frame_axes_[axis].data(), bytes);
    std::memcpy(&image_[velocity_at_], velocity_.data(), bytes);
    std::memcpy(&image_[contact_force_at_], contact_force_.data(), bytes);
    if (!contact_state_.empty())
      std::memcpy(&image_[contact_state_at_], contact_state_.data(), bytes);
    std::memcpy(&image_[tension_at_], tension_.data(), tension_.size() * sizeof(double));
    std::memcpy(&image_[position_at_], position_.data(), bytes);
    if (rod_fields_) {
      std::memcpy(&image_[strain_at_], strain_.data(), 2 * bytes);
      std::memcpy(&image_[stress_at_], stress_.data(), 2 * bytes);
    }
  } else {
    ComposeAsciiImage(time);
  }
  return image_;
}

bool VtkWriter::WriteCollection() const {
  std::string text =
      "<?xml version=\"1.0\"?>\n"
      "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
      "  <Collection>\n";
  char line[128];
  for (std::size_t i = 0; i < times_.size(); ++i) {
    std::string name;
    AppendFrameName(&name, static_cast<int>(i));
    std::snprintf(line, sizeof line,
                  "    <DataSet timestep=\"%.17g\" group=\"\" part=\"0\" file=\"%s\"/>\n",
                  times_[i], name.c_str());
    text += line;
  }
  text += "  </Collection>\n</VTKFile>\n";
  return WriteFileAtomically(folder_, kCollectionFile, text);
}

}  // namespace screwfem
