// Mesh and height-field obstacles from scene files (docs/scene-format.md, "contact"): inline
// meshes and grids compile to the triangles they list, placed at their pose and scale; STL
// (ASCII and binary) and OBJ files read to the same triangles; bad input is reported at
// file:line:col, and bad files by file and line.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

#include <unistd.h>

#include "screwfem/io/mesh_file.h"
#include "screwfem/io/scene.h"
#include "screwfem/model/errors.h"

namespace screwfem::mesh_scene_test {
namespace {

const std::string kHead = R"(gravity: [0, 0, -9.81]
bodies:
  ball: {type: rigid, at: [0, 0, 1], mass: 1, inertia: [1, 1, 1], free: true,
         shapes: [{type: sphere, center: [0, 0, 1], radius: 0.1}]}
contact:
  obstacles:
)";

std::string Error(const std::string& text) {
  try {
    ParseScene(text, "bad.yaml");
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

void ExpectError(const std::string& text, const std::string& location, const std::string& what) {
  const std::string message = Error(text);
  EXPECT_EQ(message.rfind(location + ": ", 0), 0u) << "message: " << message;
  EXPECT_NE(message.find(what), std::string::npos) << "message: " << message;
}

TEST(MeshScene, InlineMeshAndHeightFieldCompileAtTheirPose) {
  const Scene s = ParseScene(kHead + R"(    tent: {type: mesh, center: [1, 2, 0], scale: 2,
           orientation: {axis: [0, 0, 1], angle: 1.5707963267948966},
           vertices: [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], faces: [[0, 1, 2, 3]]}
    hill: {type: heightfield, spacing: [0.5, 0.25], center: [0, 0, -1],
           heights: [[0, 0.1, 0.2], [0.3, 0.4, 0.5]]}
)",
                             "mesh.yaml");
  ASSERT_EQ(s.model.obstacles.size(), 2u);
  const ContactObstacle& tent = s.model.obstacles[0];
  EXPECT_EQ(tent.type, ObstacleType::kMesh);
  ASSERT_TRUE(tent.tree);
  ASSERT_EQ(tent.tree->faces().size(), 2u);  // the quad, fan-triangulated
  // Vertex (1, 0, 0) turned a quarter about z, doubled, at (1, 2, 0): (1, 4, 0).
  EXPECT_LT((tent.tree->vertices()[1] - Vec3(1, 4, 0)).norm(), 1e-15);
  const ContactObstacle& hill = s.model.obstacles[1];
  EXPECT_EQ(hill.type, ObstacleType::kHeightfield);
  ASSERT_EQ(hill.tree->faces().size(), 4u);
  EXPECT_LT((hill.tree->vertices()[5] - Vec3(0.5, 0.125, -0.5)).norm(), 1e-15);
  // The ball's sphere against both: one pair each.
  EXPECT_EQ(s.model.contact_pairs.size(), 2u);
}

TEST(MeshScene, StlAndObjFilesReadToTheSameTriangles) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("screwfem_mesh_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  {
    std::ofstream(dir / "t.obj") << "# a tetrahedron\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n"
                                    "f 1 3 2\nf 1 2 4\nf 1/1 4/1 3/1\nf -3 -2 -1\n";
    std::ofstream(dir / "t.stl") << "solid t\n facet normal 0 0 -1\n  outer loop\n"
                                    "   vertex 0 0 0\n   vertex 0 1 0\n   vertex 1 0 0\n"
                                    "  endloop\n endfacet\nendsolid t\n";
    std::string bin(84 + 50, '\0');
    const std::uint32_t one = 1;
    std::memcpy(&bin[80], &one, 4);
    const float v[9] = {0, 0, 0, 0, 1, 0, 1, 0, 0};
    std::memcpy(&bin[84 + 12], v, sizeof v);
    std::ofstream(dir / "b.stl", std::ios::binary) << bin;
    std::ofstream(dir / "short.stl", std::ios::binary) << bin.substr(0, 100);
    std::ofstream(dir / "bad.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n";
    std::ofstream(dir / "h.csv") << "# heights\n0, 0.1\n0.2, 0.3\n";
  }
  const TriangleMesh obj = ReadMeshFile((dir / "t.obj").string());
  ASSERT_EQ(obj.faces.size(), 4u);
  EXPECT_EQ(obj.faces[3], (std::array<int, 3>{1, 2, 3}));
  EXPECT_NEAR(CalcMeshMassProperties(obj).volume, 1.0 / 6.0, 1e-16);
  for (const char* name : {"t.stl", "b.stl"}) {
    const TriangleMesh stl = ReadMeshFile((dir / name).string());
    ASSERT_EQ(stl.faces.size(), 1u) << name;
    EXPECT_EQ(stl.vertices[1], Vec3(0, 1, 0)) << name;
  }
  auto error = [&](const char* name) {
    try {
      ReadMeshFile((dir / name).string());
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("(no error)");
  };
  EXPECT_EQ(error("short.stl"), (dir / "short.stl").string() +
                                    ": truncated binary STL: its header gives 1 triangles, 134 "
                                    "bytes, the file has 100");
  EXPECT_EQ(error("bad.obj"),
            (dir / "bad.obj").string() + ":4: vertex index 9 out of range (3 vertices so far)");
  // A scene names the file relative to its folder.
  const std::string scene = (dir / "scene.yaml").string();
  std::ofstream(scene) << kHead << "    tet: {type: mesh, file: t.obj}\n"
                       << "    grid: {type: heightfield, file: h.csv, spacing: 0.1}\n"
                       << "    wrong: {type: mesh, file: bad.obj}\n";
  const std::string message = [&] {
    try {
      LoadScene(scene);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("(no error)");
  }();
  EXPECT_EQ(message.rfind(scene + ":9:31: contact.obstacles.wrong.file: ", 0), 0u) << message;
  EXPECT_NE(message.find("bad.obj:4: vertex index 9 out of range"), std::string::npos) << message;
  std::filesystem::remove_all(dir);
}

// The example reads its OBJ relative to itself: 32 side quads and two 32-gons, 124 triangles,
// the prism's volume.
TEST(MeshScene, ExampleReadsItsObjNextToIt) {
  const Scene s = LoadScene(std::string(SCREWFEM_SOURCE_DIR) + "/examples/contact/mesh_wrap.yaml");
  ASSERT_EQ(s.model.obstacles.size(), 1u);
  const ContactObstacle& post = s.model.obstacles[0];
  ASSERT_TRUE(post.mesh);
  EXPECT_EQ(post.mesh->faces.size(), 124u);
  const double volume = 0.5 * 32 * 0.05 * 0.05 * std::sin(2.0 * M_PI / 32) * 0.4;
  EXPECT_NEAR(CalcMeshMassProperties(*post.mesh).volume, volume, 1e-15);
  EXPECT_EQ(s.model.contact_pairs.size(), 24u);  // one per rod element
}

TEST(MeshScene, BadInputIsReportedAtFileLineColumnNamingTheField) {
  ExpectError(kHead +
                  "    m: {type: mesh, vertices: [[0, 0, 0], [1, 0, 0], [0, 1, 0]], "
                  "faces: [[0, 1, 3]]}\n",
              "bad.yaml:7:81: contact.obstacles.m.faces[0][2]", "expected an integer from 0 to 2");
  ExpectError(kHead +
                  "    m: {type: mesh, vertices: [[0, 0, 0], [1, 0, 0], [2, 0, 0]], "
                  "faces: [[0, 1, 2]]}\n",
              "bad.yaml:7:31: contact.obstacles.m", "face 0 (vertices 0, 1, 2) is degenerate");
  ExpectError(kHead + "    m: {type: mesh, faces: [[0, 1, 2]]}\n",
              "bad.yaml:7:8: contact.obstacles.m", "give either 'file' or 'vertices'");
  ExpectError(kHead + "    h: {type: heightfield, spacing: 0.1, heights: [[0, 1], [2]]}\n",
              "bad.yaml:7:60: contact.obstacles.h.heights[1]", "as many in every row");
  ExpectError(kHead + "    h: {type: heightfield, heights: [[0, 1], [2, 3]], spacing: [1, -1]}\n",
              "bad.yaml:7:64: contact.obstacles.h.spacing", "expected positive spacings");
  ExpectError(kHead +
                  "    h: {type: heightfield, spacing: 1, heights: [[0, 1], [2, 3]], "
                  "scale: 2}\n",
              "bad.yaml:7:67: contact.obstacles.h.scale", "'scale' is not used by");
}

}  // namespace
}  // namespace screwfem::mesh_scene_test
