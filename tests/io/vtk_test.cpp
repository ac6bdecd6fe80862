// ParaView frames (io/vtk.h): a frame read back holds the model's state bit for bit, in the
// binary encoding (a parser of the raw AppendedData block below) and in the ascii one; the
// scene key outputs.vtk_format selects the encoding, binary by default.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <map>
#include <string>
#include <vector>

#include "io/run_test_util.h"
#include "screwfem/assemble/outputs.h"
#include "screwfem/elements/contact.h"
#include "screwfem/elements/joint.h"
#include "screwfem/elements/tendon.h"
#include "screwfem/io/run.h"
#include "screwfem/io/scene.h"
#include "screwfem/io/vtk.h"
#include "screwfem/model/errors.h"
#include "screwfem/solve/dynamics.h"

namespace screwfem::vtk_test {
namespace {

using test::ReadFile;
using test::ScopedDir;

// One <DataArray> of a frame, its values decoded: doubles for Float64, integers otherwise.
struct Array {
  std::string type, format;
  int components = 1;
  std::vector<double> doubles;
  std::vector<long long> integers;
};

std::string Attribute(const std::string& tag, const std::string& name) {
  const std::size_t at = tag.find(" " + name + "=\"");
  if (at == std::string::npos) return {};
  const std::size_t start = at + name.size() + 3;
  return tag.substr(start, tag.find('"', start) - start);
}

// The arrays of a .vtp file by "Section/Name" (FieldData/TimeValue, PointData/velocity,
// CellData/joint_id, Points/position, Lines/offsets, ...), decoded from raw appended data
// (UInt64 headers, the file's byte order being the machine's) or from ascii text.
std::map<std::string, Array> ReadArrays(const std::string& file) {
  std::map<std::string, Array> arrays;
  const std::size_t appended = file.find("<AppendedData encoding=\"raw\">");
  const std::size_t xml_end = appended == std::string::npos ? file.size() : appended;
  const std::size_t base = appended == std::string::npos ? 0 : file.find('_', appended) + 1;
  const char* sections[] = {"FieldData", "PointData", "CellData", "Points", "Verts", "Lines"};
  std::size_t at = 0;
  while ((at = file.find("<DataArray", at)) < xml_end) {
    std::string section = "?";
    std::size_t nearest = 0;
    for (const char* s : sections) {
      const std::size_t open = file.rfind(std::string("<") + s, at);
      if (open != std::string::npos && open >= nearest) {
        nearest = open;
        section = s;
      }
    }
    const std::size_t tag_end = file.find('>', at);
    const std::string tag = file.substr(at, tag_end + 1 - at);
    Array a;
    a.type = Attribute(tag, "type");
    a.format = Attribute(tag, "format");
    const std::string components = Attribute(tag, "NumberOfComponents");
    a.components = components.empty() ? 1 : std::stoi(components);
    if (a.format == "appended") {
      const std::size_t offset = base + std::stoull(Attribute(tag, "offset"));
      std::uint64_t bytes = 0;
      std::memcpy(&bytes, file.data() + offset, sizeof bytes);
      const char* data = file.data() + offset + sizeof bytes;
      if (a.type == "Float64") {
        a.doubles.resize(bytes / 8);
        std::memcpy(a.doubles.data(), data, bytes);
      } else if (a.type == "Int64") {
        a.integers.resize(bytes / 8);
        std::memcpy(a.integers.data(), data, bytes);
      } else {
        std::vector<std::int32_t> v(bytes / 4);
        std::memcpy(v.data(), data, bytes);
        a.integers.assign(v.begin(), v.end());
      }
    } else {
      const std::string text =
          file.substr(tag_end + 1, file.find("</DataArray>", tag_end) - tag_end - 1);
      const char* p = text.c_str();
      for (char* end = nullptr;; p = end) {
        const double v = std::strtod(p, &end);
        if (end == p) break;
        if (a.type == "Float64")
          a.doubles.push_back(v);
        else
          a.integers.push_back(static_cast<long long>(v));
      }
    }
    arrays[section + "/" + Attribute(tag, "Name")] = a;
    at = tag_end;
  }
  return arrays;
}

// Bit-for-bit equality of the three doubles at point i of a 3-component array with x.
void ExpectSameBits(const Array& a, long long i, const Vec3& x, const std::string& what) {
  ASSERT_LE(3 * (i + 1), static_cast<long long>(a.doubles.size())) << what;
  for (int k = 0; k < 3; ++k) {
    const double v = a.doubles[static_cast<std::size_t>(3 * i + k)];
    EXPECT_EQ(std::memcmp(&v, &x(k), sizeof v), 0)
        << what << " component " << k << ": " << v << " vs " << x(k);
  }
}

// The rigid GRM with 2 elements per soft body, moved 20 steps from rest (every node, joint
// and body away from its reference frame, velocities nonzero).
struct MovedGrm {
  Scene scene;
  Data data;
};
MovedGrm MoveGrm() {
  MovedGrm m{LoadScene(std::string(SCREWFEM_SOURCE_DIR) + "/examples/grm/grm_rigid.yaml",
                       {"defaults.elements=2"}),
             {}};
  m.data = MakeData(m.scene.model);
  Integrator integ;
  std::string why;
  EXPECT_TRUE(InitializeDynamics(m.scene.model, m.data, integ, m.scene.analysis.dynamic, &why))
      << why;
  for (int i = 0; i < 20; ++i) {
    EXPECT_TRUE(Step(m.scene.model, m.data, integ, 1e-3).ok);
    m.data.time += 1e-3;
  }
  return m;
}

// Checks the frame file against the state: time, every rod node's and rigid body's position,
// frame axes and velocity, every joint vertex; cells and ids.
void ExpectFrameHoldsTheState(const std::string& file, const Model& model, const Data& data,
                              const std::string& format) {
  std::map<std::string, Array> a = ReadArrays(file);
  for (const char* name : {"FieldData/TimeValue",     "Points/position",    "PointData/frame_x",
                           "PointData/frame_y",       "PointData/frame_z",  "PointData/velocity",
                           "PointData/joint_id",      "CellData/rod_id",    "CellData/body_id",
                           "CellData/joint_id",       "PointData/radius",   "PointData/half_size",
                           "PointData/contact_force", "CellData/kind",      "CellData/item_id",
                           "CellData/tension",        "Verts/connectivity", "Verts/offsets",
                           "Lines/connectivity",      "Lines/offsets"}) {
    ASSERT_TRUE(a.count(name)) << name;
    EXPECT_EQ(a[name].format, format) << name;
  }
  ASSERT_EQ(a["FieldData/TimeValue"].doubles.size(), 1u);
  EXPECT_EQ(std::memcmp(&a["FieldData/TimeValue"].doubles[0], &data.time, sizeof(double)), 0);

  // Cells: vertices (the joints, in order, then the bodies' inertia boxes), then lines (rods,
  // then body segments).
  const std::vector<long long>& verts = a["Verts/connectivity"].integers;
  const std::vector<long long>& lines = a["Lines/connectivity"].integers;
  const std::vector<long long>& line_ends = a["Lines/offsets"].integers;
  const std::vector<long long>& rod_id = a["CellData/rod_id"].integers;
  const std::vector<long long>& body_id = a["CellData/body_id"].integers;
  const std::vector<long long>& kind = a["CellData/kind"].integers;
  ASSERT_EQ(verts.size(), model.joints.size() + model.bodies.size());  // joints, inertia boxes
  ASSERT_EQ(rod_id.size(), verts.size() + line_ends.size());
  ASSERT_EQ(kind.size(), rod_id.size());
  for (std::size_t c = 0; c < verts.size(); ++c)
    EXPECT_EQ(kind[c], static_cast<int>(c < model.joints.size() ? VtkCellKind::kJoint
                                                                : VtkCellKind::kInertiaBox));

  for (std::size_t j = 0; j < model.joints.size(); ++j) {
    const Joint& joint = model.joints[j];
    const SE3 H = NodeFrame(data, joint.node_a) * joint.offset_a *
                  JointRelativeFrame(model, data, static_cast<int>(j));
    ExpectSameBits(a["Points/position"], verts[j], H.x, "joint " + joint.name);
    EXPECT_EQ(a["PointData/joint_id"].integers[static_cast<std::size_t>(verts[j])],
              static_cast<long long>(j));
  }
  long long start = 0;
  int rods_seen = 0, bodies_seen = 0;
  for (std::size_t c = 0; c < line_ends.size(); ++c) {
    const std::size_t cell = verts.size() + c;
    const long long end = line_ends[c];
    if (rod_id[cell] >= 0) {
      EXPECT_EQ(kind[cell], static_cast<int>(VtkCellKind::kRod));
      const Rod& rod = model.rods[static_cast<std::size_t>(rod_id[cell])];
      ASSERT_EQ(end - start, static_cast<long long>(rod.nodes.size()));
      for (std::size_t k = 0; k < rod.nodes.size(); ++k) {
        const int node = rod.nodes[k];
        const SE3& H = data.H[static_cast<std::size_t>(node)];
        const long long p = lines[static_cast<std::size_t>(start) + k];
        const std::string what = rod.name + " node " + std::to_string(k);
        ExpectSameBits(a["Points/position"], p, H.x, what + " position");
        ExpectSameBits(a["PointData/frame_x"], p, H.R.col(0), what + " frame_x");
        ExpectSameBits(a["PointData/frame_y"], p, H.R.col(1), what + " frame_y");
        ExpectSameBits(a["PointData/frame_z"], p, H.R.col(2), what + " frame_z");
        ExpectSameBits(a["PointData/velocity"], p,
                       CalcNodePointMotion(model, data, node, Vec3::Zero()).velocity,
                       what + " velocity");
      }
      ++rods_seen;
    } else {
      ASSERT_GE(body_id[cell], 0);
      EXPECT_EQ(kind[cell], static_cast<int>(VtkCellKind::kBodySegment));
      ASSERT_EQ(end - start, 2);
      const RigidBody& body = model.bodies[static_cast<std::size_t>(body_id[cell])];
      const SE3& H = data.H[static_cast<std::size_t>(body.node)];
      ExpectSameBits(a["Points/position"], lines[static_cast<std::size_t>(start)], H.x,
                     body.name + " origin");
      ExpectSameBits(a["PointData/frame_z"], lines[static_cast<std::size_t>(start) + 1], H.R.col(2),
                     body.name + " segment end frame_z");
      ++bodies_seen;
    }
    start = end;
  }
  EXPECT_EQ(rods_seen, static_cast<int>(model.rods.size()));
  EXPECT_GE(bodies_seen, static_cast<int>(model.bodies.size()));
}

TEST(VtkWriter, BinaryFrameHoldsTheModelStateBitForBit) {
  MovedGrm m = MoveGrm();
  const ScopedDir dir("vtk_binary");
  VtkWriter w;
  w.Open(dir.path(), m.scene.model, VtkFormat::kBinary, 2);
  ASSERT_TRUE(w.WriteFrame(m.scene.model, m.data, m.data.time));
  const std::string file = ReadFile(dir.path() + "/frame_00000.vtp");
  EXPECT_NE(file.find("<AppendedData encoding=\"raw\">"), std::string::npos);
  EXPECT_NE(file.find("header_type=\"UInt64\""), std::string::npos);
  EXPECT_EQ(file.substr(file.size() - 11), "</VTKFile>\n");
  ExpectFrameHoldsTheState(file, m.scene.model, m.data, "appended");
}

TEST(VtkWriter, AsciiFrameHoldsTheModelStateBitForBit) {
  MovedGrm m = MoveGrm();
  const ScopedDir dir("vtk_ascii");
  VtkWriter w;
  w.Open(dir.path(), m.scene.model, VtkFormat::kAscii, 2);
  ASSERT_TRUE(w.WriteFrame(m.scene.model, m.data, m.data.time));
  const std::string file = ReadFile(dir.path() + "/frame_00000.vtp");
  EXPECT_EQ(file.find("AppendedData"), std::string::npos);
  ExpectFrameHoldsTheState(file, m.scene.model, m.data, "ascii");
}

// Later frames of the binary writer change only the values: same size, same XML, and the
// collection lists every frame with its time.
TEST(VtkWriter, BinaryFramesOfOneModelDifferOnlyInTheirValues) {
  MovedGrm m = MoveGrm();
  const ScopedDir dir("vtk_frames");
  VtkWriter w;
  w.Open(dir.path(), m.scene.model, VtkFormat::kBinary, 1);
  const Data at_rest = MakeData(m.scene.model);
  ASSERT_TRUE(w.WriteFrame(m.scene.model, at_rest, 0.0));
  ASSERT_TRUE(w.WriteFrame(m.scene.model, m.data, m.data.time));  // beyond the reservation
  const std::string first = ReadFile(dir.path() + "/frame_00000.vtp");
  const std::string second = ReadFile(dir.path() + "/frame_00001.vtp");
  ASSERT_EQ(first.size(), second.size());
  const std::size_t xml = first.find("<AppendedData");
  EXPECT_EQ(first.substr(0, xml), second.substr(0, xml));
  EXPECT_NE(first, second);
  ExpectFrameHoldsTheState(second, m.scene.model, m.data, "appended");
  ASSERT_TRUE(w.WriteCollection());
  const std::string pvd = ReadFile(dir.path() + "/motion.pvd");
  EXPECT_NE(pvd.find("timestep=\"0\" group=\"\" part=\"0\" file=\"frame_00000.vtp\""),
            std::string::npos)
      << pvd;
  EXPECT_NE(pvd.find("file=\"frame_00001.vtp\""), std::string::npos) << pvd;
}

// The drawn sizes and the items beyond the mechanism's skeleton, on the viewer's true-size
// scene (tests/view/true_size.yaml) moved 10 steps: rods carry their section's radius and half
// sizes (circle, rectangle), the box, sphere and capsule shapes and the obstacles theirs, the
// box body its inertia box; the tendon passes through its eyelets with its tension, and the
// contact vertices carry CalcContactState's force (the box's bottom corners its weight).
TEST(VtkWriter, FrameCarriesSizesShapesObstaclesTendonsAndContactForces) {
  const Scene scene = LoadScene(std::string(SCREWFEM_SOURCE_DIR) + "/tests/view/true_size.yaml");
  const Model& model = scene.model;
  Data data = MakeData(model);
  Integrator integ;
  std::string why;
  ASSERT_TRUE(InitializeDynamics(model, data, integ, scene.analysis.dynamic, &why)) << why;
  for (int i = 0; i < 10; ++i) {
    ASSERT_TRUE(Step(model, data, integ, 2e-3).ok);
    data.time += 2e-3;
  }
  for (const VtkFormat format : {VtkFormat::kBinary, VtkFormat::kAscii}) {
    SCOPED_TRACE(NameOf(format));
    const ScopedDir dir("vtk_sizes");
    VtkWriter w;
    w.Open(dir.path(), model, format, 1);
    ASSERT_TRUE(w.WriteFrame(model, data, data.time));
    std::map<std::string, Array> a = ReadArrays(ReadFile(dir.path() + "/frame_00000.vtp"));
    const std::vector<long long>& verts = a["Verts/connectivity"].integers;
    const std::vector<long long>& lines = a["Lines/connectivity"].integers;
    const std::vector<long long>& line_ends = a["Lines/offsets"].integers;
    const std::vector<long long>& kind = a["CellData/kind"].integers;
    const std::vector<long long>& item = a["CellData/item_id"].integers;
    const std::vector<double>& radius = a["PointData/radius"].doubles;
    const std::vector<double>& half = a["PointData/half_size"].doubles;
    ASSERT_EQ(kind.size(), verts.size() + line_ends.size());
    ASSERT_EQ(item.size(), kind.size());
    ASSERT_EQ(a["CellData/tension"].doubles.size(), kind.size());
    const auto half_size = [&](long long p) {
      return Vec3(half[static_cast<std::size_t>(3 * p)], half[static_cast<std::size_t>(3 * p + 1)],
                  half[static_cast<std::size_t>(3 * p + 2)]);
    };
    const auto position = [&](long long p) {
      const std::vector<double>& x = a["Points/position"].doubles;
      return Vec3(x[static_cast<std::size_t>(3 * p)], x[static_cast<std::size_t>(3 * p + 1)],
                  x[static_cast<std::size_t>(3 * p + 2)]);
    };
    std::map<int, int> counts;
    for (std::size_t c = 0; c < kind.size(); ++c) {
      const VtkCellKind k = static_cast<VtkCellKind>(kind[c]);
      const std::size_t i = static_cast<std::size_t>(item[c]);
      ++counts[static_cast<int>(k)];
      // The cell's points: a vertex, or the line's span of the connectivity.
      std::vector<long long> points;
      if (c < verts.size()) {
        points = {verts[c]};
      } else {
        const std::size_t l = c - verts.size();
        const long long begin = l == 0 ? 0 : line_ends[l - 1];
        points.assign(lines.begin() + begin, lines.begin() + line_ends[l]);
      }
      const long long p = points[0];
      const double r = radius[static_cast<std::size_t>(p)];
      switch (k) {
        case VtkCellKind::kRod:
          for (long long q : points) {
            if (model.rods[i].name == "beam") {
              EXPECT_EQ(radius[static_cast<std::size_t>(q)], 0.008);
              EXPECT_EQ(half_size(q), Vec3(0.0, 0.008, 0.008));
            } else {
              EXPECT_DOUBLE_EQ(radius[static_cast<std::size_t>(q)], 0.5 * std::hypot(0.01, 0.004));
              EXPECT_EQ(half_size(q), Vec3(0.0, 0.005, 0.002));
            }
          }
          break;
        case VtkCellKind::kBox: {
          const ContactShape& s = model.contact_shapes[i];
          const SE3& H =
              data.H[static_cast<std::size_t>(model.bodies[static_cast<std::size_t>(s.body)].node)];
          ExpectSameBits(a["Points/position"], p, H.Act(s.from), "box centre");
          ExpectSameBits(a["PointData/frame_z"], p, H.R.col(2), "box axis z");
          EXPECT_EQ(half_size(p), Vec3(0.02, 0.02, 0.02));
          break;
        }
        case VtkCellKind::kSphere:
          EXPECT_EQ(r, 0.01);
          break;
        case VtkCellKind::kCapsule:
          ASSERT_EQ(points.size(), 2u);
          EXPECT_EQ(r, 0.004);
          EXPECT_NEAR((position(points[1]) - position(points[0])).norm(), 0.04, 1e-12);
          break;
        case VtkCellKind::kInertiaBox:
          if (model.bodies[i].name == "block") {
            EXPECT_NEAR(half_size(p).minCoeff(), 0.02, 1e-6);
            EXPECT_NEAR(half_size(p).maxCoeff(), 0.02, 1e-6);
          }
          break;
        case VtkCellKind::kPlane:
          ExpectSameBits(a["PointData/frame_z"], p, Vec3::UnitZ(), "plane normal");
          break;
        case VtkCellKind::kObstacleSphere:
          EXPECT_EQ(r, 0.02);
          ExpectSameBits(a["Points/position"], p, model.obstacles[i].point, "obstacle centre");
          break;
        case VtkCellKind::kObstacleCapsule:
          EXPECT_EQ(r, 0.01);
          break;
        case VtkCellKind::kTendon: {
          const Tendon& t = model.tendons[i];
          ASSERT_EQ(points.size(), t.eyelets.size());
          for (std::size_t e = 0; e < points.size(); ++e)
            ExpectSameBits(a["Points/position"], points[e],
                           BodyPointPosition(model, data, t.eyelets[e]), "eyelet");
          EXPECT_EQ(a["CellData/tension"].doubles[c], CalcTendonState(model, data, item[c]).force);
          EXPECT_EQ(a["CellData/tension"].doubles[c], 1.0);
          break;
        }
        case VtkCellKind::kContact: {
          const ContactState s = CalcContactState(model, data, item[c]);
          const Vec3 F =
              s.active ? Vec3(s.normal_force * s.normal + s.friction_force) : Vec3::Zero();
          ExpectSameBits(a["PointData/contact_force"], p, F, "contact force");
          break;
        }
        default:
          break;
      }
    }
    EXPECT_EQ(counts[static_cast<int>(VtkCellKind::kJoint)], 3);
    EXPECT_EQ(counts[static_cast<int>(VtkCellKind::kRod)], 2);
    EXPECT_EQ(counts[static_cast<int>(VtkCellKind::kBox)], 1);
    EXPECT_EQ(counts[static_cast<int>(VtkCellKind::kSphere)], 1);
    EXPECT_EQ(counts[static_cast<int>(VtkCellKind::kCapsule)], 1);
    EXPECT_EQ(counts[static_cast<int>(VtkCellKind::kInertiaBox)], 2);
    EXPECT_EQ(counts[static_cast<int>(VtkCellKind::kPlane)], 1);
    EXPECT_EQ(counts[static_cast<int>(VtkCellKind::kObstacleSphere)], 1);
    EXPECT_EQ(counts[static_cast<int>(VtkCellKind::kObstacleCapsule)], 1);
    EXPECT_EQ(counts[static_cast<int>(VtkCellKind::kTendon)], 1);
    EXPECT_EQ(counts[static_cast<int>(VtkCellKind::kContact)],
              static_cast<int>(model.contact_pairs.size()));
    // The box rests on its four bottom corners: their upward forces carry its weight.
    double lift = 0.0;
    for (std::size_t c = 0; c < verts.size(); ++c)
      if (kind[c] == static_cast<int>(VtkCellKind::kContact))
        lift += a["PointData/contact_force"].doubles[static_cast<std::size_t>(3 * verts[c] + 2)];
    EXPECT_NEAR(lift, 0.064 * 9.81, 0.01 * 0.064 * 9.81);
  }
}

// The scene key: binary by default, ascii on request, in the summary; a bad value names the
// file, line and the choices.
TEST(VtkWriter, SceneKeySelectsTheEncoding) {
  const std::string scene_path = std::string(SCREWFEM_TEST_DATA_DIR) + "/pendulum.yaml";
  EXPECT_EQ(LoadScene(scene_path).outputs.vtk_format, VtkFormat::kBinary);
  const Scene ascii = LoadScene(scene_path, {"outputs.vtk_format=ascii"});
  EXPECT_EQ(ascii.outputs.vtk_format, VtkFormat::kAscii);
  const ScopedDir dir("vtk_scene_key");
  ASSERT_TRUE(RunScene(ascii, dir.path()).ok);
  EXPECT_NE(ReadFile(dir.path() + "/vtk/frame_00000.vtp").find("format=\"ascii\""),
            std::string::npos);
  EXPECT_NE(ReadFile(dir.path() + "/summary.json").find("\"vtk_format\": \"ascii\""),
            std::string::npos);

  std::string text = ReadFile(scene_path);
  text.replace(text.find("  vtk: true\n"), 12, "  vtk: true\n  vtk_format: binry\n");
  try {
    ParseScene(text, "pendulum.yaml");
    FAIL() << "no error for vtk_format: binry";
  } catch (const InputError& e) {
    const std::string message = e.what();
    EXPECT_EQ(message.rfind("pendulum.yaml:25:15: outputs.vtk_format: ", 0), 0u) << message;
    EXPECT_NE(message.find("binary"), std::string::npos) << message;
    EXPECT_NE(message.find("ascii"), std::string::npos) << message;
  }
}

}  // namespace
}  // namespace screwfem::vtk_test
