// Triangle meshes for contact (docs/numerics.md, "Triangle meshes"): the triangles of a mesh or
// height-field obstacle, their static bounding-volume tree (an AABB tree built once at set-up)
// and the closest-point query of a segment against them, and the mass properties of a closed
// mesh (Mirtich 1996).
#pragma once

#include <array>
#include <string>
#include <vector>

#include "screwfem/lie/se3.h"

namespace screwfem {

// A triangle soup with shared vertices: faces index `vertices` (0-based), counter-clockwise
// seen from outside (the face normal (b - a) x (c - a) points out of the solid).
struct TriangleMesh {
  std::vector<Vec3> vertices;
  std::vector<std::array<int, 3>> faces;
};

// Why a mesh is unusable, or empty when it is fine: no faces, a non-finite vertex, a face index
// out of range, or a degenerate face (zero area). `what` names the mesh in the message.
std::string CheckTriangleMesh(const TriangleMesh& mesh, const std::string& what);

// A height field as triangles: heights h[i * cols + j] at x = (j - (cols - 1) / 2) dx,
// y = (i - (rows - 1) / 2) dy (the grid centred on the origin), z = h; each cell split along
// its diagonal from (i, j) to (i + 1, j + 1), faces pointing up (+z). rows, cols >= 2.
TriangleMesh HeightFieldMesh(const std::vector<double>& heights, int rows, int cols, double dx,
                             double dy);

// Volume, centre of mass and inertia about the centre of mass (per unit density: multiply by
// the density) of the solid a closed, outward-oriented mesh bounds: the divergence theorem over
// its faces (Mirtich, Fast and accurate computation of polyhedral mass properties, 1996; in
// the form of Eberly's PolyhedralMassProperties). Exact to round-off for any closed polyhedron.
struct MeshMassProperties {
  double volume = 0.0;           // [m^3] (negative: the faces point inwards)
  Vec3 centroid = Vec3::Zero();  // [m]
  Mat3 inertia = Mat3::Zero();   // about the centroid, per unit density [m^5]
};
MeshMassProperties CalcMeshMassProperties(const TriangleMesh& mesh);

// The closest feature of a mesh to a segment (MeshTree::ClosestToSegment).
struct MeshHit {
  bool found = false;
  double distance = 0.0;  // signed: < 0 when the point is behind the face it is under
  double s = 0.0;         // parameter of the segment's point p(s) = A + s (B - A)
  // A segment parallel to the faces under it: the part of it over them, s its middle (else
  // s_lo = s_hi = s).
  double s_lo = 0.0, s_hi = 0.0;
  Vec3 point = Vec3::Zero();    // the mesh's point nearest to p(s)
  Vec3 normal = Vec3::UnitZ();  // unit, from the mesh to the segment
  int face = -1;
  // Where on the face: 0 inside it (normal = the face normal), 1 on an edge, 2 at a vertex
  // (normal along p(s) - point).
  int feature = 0;
};

// A static AABB tree over the triangles of a mesh placed in the world (x + R scale v for each
// vertex v), built once (Build) and queried without allocation: median splits along the longest
// axis of the centroids' box, at most kLeafSize triangles a leaf, depth at most kMaxDepth.
class MeshTree {
 public:
  static constexpr int kLeafSize = 4;
  static constexpr int kMaxDepth = 64;

  void Build(const TriangleMesh& mesh, const Mat3& R, const Vec3& x, double scale);

  // The mesh's closest feature to the segment A-B (A == B: a point), among those nearer than
  // `reach` (unsigned), or, for the points of the segment behind a face and in the prism over
  // it, no deeper than `depth` (the solid behind each face is taken `depth` thick):
  // - per triangle, the segment clipped to the prism over the face gives its lowest point (the
  //   middle of the clipped part when parallel to the face), with the signed height above the
  //   face; the segment's closest points to the three edges give unsigned distances;
  // - a point behind a face (negative) wins over one in front; among points in front the
  //   nearest wins, among points behind the shallowest (the face through which it leaves);
  // - ties of equal distance under parallel faces merge: s is the middle of their union (a
  //   segment lying across several coplanar triangles is carried at the middle of its part
  //   over them, not at one triangle's).
  MeshHit ClosestToSegment(const Vec3& A, const Vec3& B, double reach, double depth) const;

  const std::vector<Vec3>& vertices() const { return vertices_; }  // world
  const std::vector<std::array<int, 3>>& faces() const { return faces_; }
  const std::vector<Vec3>& normals() const { return normals_; }  // unit face normals, world
  Vec3 lower() const { return nodes_.empty() ? Vec3::Zero() : nodes_[0].lo; }
  Vec3 upper() const { return nodes_.empty() ? Vec3::Zero() : nodes_[0].hi; }
  std::size_t bytes() const;

 private:
  struct TreeNode {
    Vec3 lo = Vec3::Zero(), hi = Vec3::Zero();
    int first = 0;  // leaf: first index into order_; inner: the left child (right: left + 1)
    int count = 0;  // leaf: triangles (> 0); inner: 0
  };
  void BuildNode(int node, int first, int count, int depth, std::vector<Vec3>& centroids);
  // The best candidates in front of and behind the faces (ClosestToSegment).
  void Search(const Vec3& A, const Vec3& B, double reach, double depth, MeshHit* front,
              MeshHit* behind) const;
  std::vector<Vec3> vertices_;
  std::vector<std::array<int, 3>> faces_;
  std::vector<Vec3> normals_;
  std::vector<int> order_;
  std::vector<TreeNode> nodes_;
  double extent_ = 0.0;  // the diagonal of the root box [m]
};

}  // namespace screwfem
