#include "screwfem/io/vtk.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <cerrno>
#include <charconv>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <tuple>

#include "screwfem/assemble/outputs.h"
#include "screwfem/elements/contact.h"
#include "screwfem/elements/shape_pair.h"
#include "screwfem/elements/joint.h"
#include "screwfem/elements/rod.h"
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

// Writes `size` bytes to a new file at path (open/write/close: no stdio buffer to allocate).
// On failure removes the file and returns false with errno kept.
bool WriteWholeFile(const std::string& path, const char* data, std::size_t size) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
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
    std::remove(path.c_str());
    errno = saved;
  }
  return ok;
}

}  // namespace

void VtkWriter::Open(const std::string& dir, const Model& model, VtkFormat format,
                     int expected_frames, bool rod_fields) {
  if (!IsEnumValue(format)) throw InputError("VtkWriter::Open: unknown VtkFormat value");
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw InputError("cannot create directory " + dir + ": " + ec.message());
  dir_ = dir;
  format_ = format;
  times_.clear();
  times_.reserve(static_cast<std::size_t>(std::max(expected_frames, 1)));
  path_.reserve(dir_.size() + 32);
  LayOut(model);
  rod_fields_ = rod_fields;
  LayOutRodFields(model);
  if (format_ == VtkFormat::kBinary) {
    ComposeBinaryImage();
  } else {
    // Room for a frame of shortest doubles (at most 24 characters each) and the cells.
    image_.clear();
    image_.reserve(4096 + (rod_fields_ ? 780 : 480) * sources_.size() +
                   24 * (vert_connectivity_.size() + line_connectivity_.size()) +
                   64 * cell_rod_.size());
  }
}

// The drawn points and cells; constant for a model.
void VtkWriter::LayOut(const Model& model) {
  sources_.clear();
  vert_connectivity_.clear();
  vert_offsets_.clear();
  line_connectivity_.clear();
  line_offsets_.clear();
  point_joint_.clear();
  cell_rod_.clear();
  cell_body_.clear();
  cell_joint_.clear();
  std::vector<int> vert_rod, vert_body, vert_joint;  // vertices' cell data, put first below
  const auto add_point = [&](const PointSource& s, int joint = -1) {
    sources_.push_back(s);
    point_joint_.push_back(joint);
    return static_cast<long long>(sources_.size()) - 1;
  };
  const auto add_vert = [&](long long point, int rod, int body, int joint) {
    vert_connectivity_.push_back(point);
    vert_offsets_.push_back(static_cast<long long>(vert_connectivity_.size()));
    vert_rod.push_back(rod);
    vert_body.push_back(body);
    vert_joint.push_back(joint);
  };
  const auto end_line = [&](int rod, int body) {
    line_offsets_.push_back(static_cast<long long>(line_connectivity_.size()));
    cell_rod_.push_back(rod);
    cell_body_.push_back(body);
    cell_joint_.push_back(-1);
  };

  // Joints: a vertex at the joint frame H_A C_A H_J, moving with side B when it is a node.
  std::vector<std::vector<Vec3>> attachments(model.nodes.size());
  for (std::size_t jj = 0; jj < model.joints.size(); ++jj) {
    const Joint& j = model.joints[jj];
    const int joint = static_cast<int>(jj);
    PointSource s;
    s.kind = PointSource::Kind::kJoint;
    s.index = joint;
    add_vert(add_point(s, joint), -1, -1, joint);
    if (j.node_a != kGround)
      attachments[static_cast<std::size_t>(j.node_a)].push_back(j.offset_a.x);
    if (j.node_b != kGround)
      attachments[static_cast<std::size_t>(j.node_b)].push_back(j.offset_b.x);
  }

  // Rods: polylines through their nodes.
  for (std::size_t r = 0; r < model.rods.size(); ++r) {
    for (int node : model.rods[r].nodes) {
      PointSource s;
      s.index = node;
      line_connectivity_.push_back(add_point(s));
    }
    end_line(static_cast<int>(r), -1);
  }

  // Rigid bodies: segments from the node origin to the centre of mass and the attachments.
  for (std::size_t b = 0; b < model.bodies.size(); ++b) {
    const RigidBody& body = model.bodies[b];
    const int id = static_cast<int>(b);
    std::vector<Vec3> ends = attachments[static_cast<std::size_t>(body.node)];
    ends.push_back(body.com);
    PointSource s;
    s.index = body.node;
    const long long origin = add_point(s);
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
      line_connectivity_.push_back(origin);
      line_connectivity_.push_back(add_point(end));
      end_line(-1, id);
      drawn = true;
    }
    if (!drawn) add_vert(origin, -1, id, -1);  // a point mass: a vertex at its node
  }

  // Tendons: polylines through their eyelets; force elements: a line between their ends.
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
    return add_point(s);
  };
  for (const Tendon& t : model.tendons) {
    for (const BodyPoint& e : t.eyelets) line_connectivity_.push_back(body_point(e));
    end_line(-1, -1);
  }
  for (const ForceElement& fe : model.force_elements) {
    line_connectivity_.push_back(body_point(fe.a));
    line_connectivity_.push_back(body_point(fe.b));
    end_line(-1, -1);
  }

  // Contact pairs: a vertex at each pair's surface point, carrying the contact force.
  for (std::size_t i = 0; i < model.contact_pairs.size(); ++i) {
    PointSource s;
    s.kind = PointSource::Kind::kContact;
    s.index = static_cast<int>(i);
    add_vert(add_point(s), -1, -1, -1);
  }
  // Moving shapes: a vertex per contact segment (the pairs change from step to step), at the
  // force-weighted mean of its contact points, carrying the sum of its contact forces.
  if (MayHaveShapePairs(model))
    for (std::size_t i = 0; i < model.contact_segments.size(); ++i) {
      PointSource s;
      s.kind = PointSource::Kind::kPairContact;
      s.index = static_cast<int>(i);
      add_vert(add_point(s), -1, -1, -1);
    }
  segment_force_.assign(model.contact_segments.size(), Vec3::Zero());
  segment_point_.assign(model.contact_segments.size(), Vec3::Zero());
  segment_weight_.assign(model.contact_segments.size(), 0.0);

  // Cell data in the order VTK stores the cells: vertices, then lines.
  cell_rod_.insert(cell_rod_.begin(), vert_rod.begin(), vert_rod.end());
  cell_body_.insert(cell_body_.begin(), vert_body.begin(), vert_body.end());
  cell_joint_.insert(cell_joint_.begin(), vert_joint.begin(), vert_joint.end());

  const std::size_t n = 3 * sources_.size();
  for (std::vector<double>& axis : frame_axes_) axis.assign(n, 0.0);
  velocity_.assign(n, 0.0);
  position_.assign(n, 0.0);
  contact_force_.assign(n, 0.0);
}

// The rods' polylines are the first lines (LayOut): point k of rod r is its node k, between
// its elements k - 1 and k.
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

// Positions, frame axes and velocities of the points at data's state (method.md §6).
void VtkWriter::CalcPoints(const Model& model, const Data& data) {
  // The contact forces on each contact segment, and their points weighted by |F|.
  std::fill(segment_force_.begin(), segment_force_.end(), Vec3::Zero());
  std::fill(segment_point_.begin(), segment_point_.end(), Vec3::Zero());
  std::fill(segment_weight_.begin(), segment_weight_.end(), 0.0);
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
      R = Mat3::Identity();
      v = Vec3::Zero();
    } else if (s.kind == PointSource::Kind::kContact) {
      const ContactState c = CalcContactState(model, data, s.index);
      x = c.point;
      R = Mat3::Identity();
      v = Vec3::Zero();
      const Vec3 F = c.active ? Vec3(c.normal_force * c.normal + c.friction_force) : Vec3::Zero();
      for (int k = 0; k < 3; ++k) contact_force_[3 * i + k] = F(k);
    } else if (s.kind == PointSource::Kind::kSection) {
      // H_A exp(xi d) and the interpolated body velocity N(xi, d) [eta_A; eta_B] (method.md §2.5).
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
      R = H.R;
      v = node_point(s.index, s.offset).velocity;
    }
    for (int k = 0; k < 3; ++k) {
      position_[3 * i + k] = x(k);
      velocity_[3 * i + k] = v(k);
      for (int axis = 0; axis < 3; ++axis) frame_axes_[axis][3 * i + k] = R(k, axis);
    }
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
  array("        ", kInt32, "joint_id", 1, point_joint_.data(), n, nullptr);
  if (rod_fields_) {
    array("        ", kFloat64, "strain", 6, strain_.data(), 6 * n, &strain_at_);
    array("        ", kFloat64, "stress", 6, stress_.data(), 6 * n, &stress_at_);
  }
  f += "      </PointData>\n      <CellData Scalars=\"rod_id\">\n";
  array("        ", kInt32, "rod_id", 1, cell_rod_.data(), cell_rod_.size(), nullptr);
  array("        ", kInt32, "body_id", 1, cell_body_.data(), cell_body_.size(), nullptr);
  array("        ", kInt32, "joint_id", 1, cell_joint_.data(), cell_joint_.size(), nullptr);
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
  integers(kInt32, "joint_id", point_joint_);
  if (rod_fields_) {
    doubles("strain", strain_, 6);
    doubles("stress", stress_, 6);
  }
  f += "      </PointData>\n      <CellData Scalars=\"rod_id\">\n";
  integers(kInt32, "rod_id", cell_rod_);
  integers(kInt32, "body_id", cell_body_);
  integers(kInt32, "joint_id", cell_joint_);
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
  CalcPoints(model, data);
  if (rod_fields_) CalcRodFields(model, data, load_factor);
  if (format_ == VtkFormat::kBinary) {
    std::memcpy(&image_[time_at_], &time, sizeof time);
    const std::size_t bytes = position_.size() * sizeof(double);
    for (int axis = 0; axis < 3; ++axis)
      std::memcpy(&image_[frame_axes_at_[axis]], frame_axes_[axis].data(), bytes);
    std::memcpy(&image_[velocity_at_], velocity_.data(), bytes);
    std::memcpy(&image_[contact_force_at_], contact_force_.data(), bytes);
    std::memcpy(&image_[position_at_], position_.data(), bytes);
    if (rod_fields_) {
      std::memcpy(&image_[strain_at_], strain_.data(), 2 * bytes);
      std::memcpy(&image_[stress_at_], stress_.data(), 2 * bytes);
    }
  } else {
    ComposeAsciiImage(time);
  }
  path_.assign(dir_);
  path_ += '/';
  AppendFrameName(&path_, frames());
  if (!WriteWholeFile(path_, image_.data(), image_.size())) return false;
  times_.push_back(time);
  return true;
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
  return WriteFileAtomically(dir_ + "/motion.pvd", text);
}

}  // namespace screwfem
