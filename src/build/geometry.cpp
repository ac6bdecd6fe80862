// ModelBuilder's geometry (docs/architecture.md, "ModelBuilder's geometry"): straight rods,
// rods through nodes and along polylines, the node at a world point or at an arc length, and
// a rod's reference length.
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "build_steps.h"
#include "screwfem/build/model_builder.h"
#include "screwfem/model/errors.h"

namespace screwfem {

namespace {

// The rod that a node belongs to ("'name'"), or the node's label when no rod has it.
std::string OwnerLabel(const Model& m, int node) {
  for (const Rod& r : m.rods)
    if (std::find(r.nodes.begin(), r.nodes.end(), node) != r.nodes.end()) return "'" + r.name + "'";
  return build_steps::NodeLabel(m, node);
}

// Frames of the nodes of a rod along a polyline with n elements per segment (AddRodAlongPath).
// Throws InputError for `rod` with the part "path[i]" of the offending point.
std::vector<SE3> PathNodeFrames(const std::string& name, const EntityRef& rod,
                                const std::vector<Vec3>& pts, int n, const Vec3& up) {
  auto fail = [&](std::size_t i, const std::string& detail) {
    const std::string part = "path[" + std::to_string(i) + "]";
    throw InputError("rod '" + name + "': " + part + ": " + detail, {rod.kind, rod.index, part},
                     detail);
  };
  for (std::size_t i = 0; i < pts.size(); ++i)
    if (!pts[i].allFinite()) fail(i, "the point is not finite");
  for (std::size_t i = 1; i < pts.size(); ++i)
    if (!((pts[i] - pts[i - 1]).norm() > 1e-12 * std::max(1.0, pts[i].norm())))
      fail(i, "zero-length segment (its end points coincide)");
  const std::size_t segs = pts.size() - 1;
  std::vector<Vec3> dir(segs);
  for (std::size_t i = 0; i < segs; ++i) dir[i] = (pts[i + 1] - pts[i]).normalized();
  // At path point i: along the segment at the ends, along the bisector inside.
  auto vertex_frame = [&](std::size_t i) {
    const Vec3 t = i == 0 ? dir[0] : i == segs ? dir[segs - 1] : Vec3(dir[i - 1] + dir[i]);
    if (!(t.norm() > 1e-6)) fail(i, "the path turns back on itself here");
    return FrameAlong(t, up);
  };
  std::vector<SE3> frames;
  frames.reserve(segs * static_cast<std::size_t>(n) + 1);
  SE3 H;
  H.R = vertex_frame(0);
  H.x = pts[0];
  frames.push_back(H);
  for (std::size_t s = 0; s < segs; ++s) {
    for (int e = 1; e <= n; ++e) {
      const bool vertex = e == n;
      H.R = vertex ? vertex_frame(s + 1) : FrameAlong(dir[s], up);
      H.x =
          vertex ? pts[s + 1] : Vec3(pts[s] + (pts[s + 1] - pts[s]) * (static_cast<double>(e) / n));
      frames.push_back(H);
    }
  }
  return frames;
}

}  // namespace

RodId ModelBuilder::AddStraightRod(std::string name, const Vec3& p0, const Vec3& p1,
                                   int num_elements, const Section& section, const Vec3& up,
                                   NodeId start_node, NodeId end_node) {
  const double length = (p1 - p0).norm();
  if (!(length > 0.0) || !std::isfinite(length))
    throw InputError("rod '" + name + "': zero length (its end points coincide)", NextRod());
  SE3 root;
  root.R = FrameAlong(p1 - p0, up);
  root.x = p0;
  return AddStraightRodFromFrame(std::move(name), root, length, num_elements, section, start_node,
                                 end_node);
}

RodId ModelBuilder::AddStraightRodFromFrame(std::string name, const SE3& root, double length,
                                            int num_elements, const Section& section,
                                            NodeId start_node, NodeId end_node) {
  if (num_elements < 1)
    throw InputError(
        "rod '" + name + "': needs at least one element, got " + std::to_string(num_elements),
        NextRod());
  if (!(length > 0.0) || !std::isfinite(length))
    throw InputError("rod '" + name + "': length must be positive", NextRod());
  std::vector<NodeId> nodes;
  for (int i = 0; i <= num_elements; ++i) {
    SE3 H = root;
    H.x = root.x + root.R.col(0) * (length * i / num_elements);
    if (i == 0 && start_node.valid()) {
      nodes.push_back(start_node);
    } else if (i == num_elements && end_node.valid()) {
      nodes.push_back(end_node);
    } else {
      nodes.push_back(AddNode(H, name.empty() ? std::string{} : name + "." + std::to_string(i)));
    }
  }
  return AddRodThroughNodes(std::move(name), nodes, section);
}

RodId ModelBuilder::AddRodThroughNodes(std::string name, const std::vector<NodeId>& nodes,
                                       const Section& section) {
  Rod rod;
  rod.name = std::move(name);
  rod.section = section;
  rod.nodes.assign(nodes.begin(), nodes.end());
  rod.num_elements = static_cast<int>(nodes.size()) - 1;
  model_.rods.push_back(rod);
  return RodId(static_cast<int>(model_.rods.size()) - 1);
}

RodId ModelBuilder::AddRodAlongPath(std::string name, const std::vector<Vec3>& path,
                                    int elements_per_segment, const Section& section,
                                    const Vec3& up, NodeId start_node, NodeId end_node) {
  const EntityRef rod = NextRod();
  const std::string label = "rod '" + name + "'";
  if (path.size() < 2) throw InputError(label + ": a path needs at least two points", rod);
  if (elements_per_segment < 1)
    throw InputError(label + ": needs at least one element per segment, got " +
                         std::to_string(elements_per_segment),
                     rod);
  if (!up.allFinite() || !(up.norm() > 0.0))
    throw InputError(label + ": the up vector must be finite and non-zero", rod);
  const std::vector<SE3> frames = PathNodeFrames(name, rod, path, elements_per_segment, up);
  // A shared end node must sit at the path's end with the same section frame (else the rod
  // would start with a kink that no element carries).
  auto check_shared = [&](NodeId node, const SE3& H, const char* part) {
    if (!node.valid()) return;
    std::string detail;
    if (node.index() >= model_.nodes.size()) {
      detail = "no node " + std::to_string(node);
    } else {
      const SE3& Ho = model_.nodes[node.index()].reference;
      const double tol = 1e-8 * std::max({1.0, H.x.norm(), (path.back() - path.front()).norm()});
      if ((Ho.x - H.x).norm() > tol)
        detail = build_steps::NodeLabel(model_, node) + " is not at the path's end";
      else if ((Ho.R - H.R).norm() > 1e-9)
        detail = "the section frames of '" + name + "' and " + OwnerLabel(model_, node) +
                 " differ at the shared node (a kink or a different up vector); join them by a "
                 "fixed joint instead";
    }
    if (!detail.empty())
      throw InputError(label + ": " + part + ": " + detail, {rod.kind, rod.index, part}, detail);
  };
  check_shared(start_node, frames.front(), "start_node");
  check_shared(end_node, frames.back(), "end_node");
  // Two points: the straight rod (its node positions are computed along the frame's x axis).
  if (path.size() == 2)
    return AddStraightRod(std::move(name), path[0], path[1], elements_per_segment, section, up,
                          start_node, end_node);
  std::vector<NodeId> nodes;
  nodes.reserve(frames.size());
  for (std::size_t i = 0; i < frames.size(); ++i) {
    if (i == 0 && start_node.valid()) {
      nodes.push_back(start_node);
    } else if (i + 1 == frames.size() && end_node.valid()) {
      nodes.push_back(end_node);
    } else {
      nodes.push_back(
          AddNode(frames[i], name.empty() ? std::string{} : name + "." + std::to_string(i)));
    }
  }
  return AddRodThroughNodes(std::move(name), nodes, section);
}

NodeMatch ModelBuilder::FindNodeAt(const Vec3& p, RodId rod, double tolerance) const {
  const Model& m = model_;
  if (rod.valid() && rod.index() >= m.rods.size())
    throw InputError("FindNodeAt: no rod " + std::to_string(rod));
  NodeMatch match;
  match.distance = std::numeric_limits<double>::infinity();
  auto valid = [&](int n) { return n >= 0 && n < static_cast<int>(m.nodes.size()); };
  auto consider = [&](int n) {
    if (!valid(n)) return;
    const double d = (m.nodes[static_cast<std::size_t>(n)].reference.x - p).norm();
    if (d < match.distance) {
      match.distance = d;
      match.nearest = NodeId(n);
    }
  };
  double extent = 0.0;
  if (rod.valid()) {
    const Rod& r = m.rods[rod.index()];
    for (int n : r.nodes) consider(n);
    if (!r.nodes.empty() && valid(r.nodes.front()) && valid(r.nodes.back()))
      extent = (m.nodes[static_cast<std::size_t>(r.nodes.front())].reference.x -
                m.nodes[static_cast<std::size_t>(r.nodes.back())].reference.x)
                   .norm();
  } else {
    for (int n = 0; n < static_cast<int>(m.nodes.size()); ++n) consider(n);
  }
  if (tolerance < 0.0) tolerance = 1e-8 * std::max({1.0, p.norm(), extent});
  if (match.distance <= tolerance) match.node = match.nearest;
  return match;
}

std::vector<double> ModelBuilder::RodArcLengths(RodId rod) const {
  const Model& m = model_;
  if (!rod.valid() || rod.index() >= m.rods.size())
    throw InputError("RodLength: no rod " + std::to_string(rod));
  const Rod& r = m.rods[rod.index()];
  const int num_nodes = static_cast<int>(m.nodes.size());
  for (int n : r.nodes)
    if (n < 0 || n >= num_nodes)
      throw InputError("RodLength: rod " + std::to_string(rod) + " has an invalid node");
  std::vector<double> arcs(std::max<std::size_t>(r.nodes.size(), 1), 0.0);
  for (std::size_t i = 1; i < r.nodes.size(); ++i)
    arcs[i] =
        arcs[i - 1] + LogSE3(m.nodes[static_cast<std::size_t>(r.nodes[i - 1])].reference.Inverse() *
                             m.nodes[static_cast<std::size_t>(r.nodes[i])].reference)
                          .head<3>()
                          .norm();
  return arcs;
}

double ModelBuilder::RodLength(RodId rod) const { return RodArcLengths(rod).back(); }

std::vector<NodeId> ModelBuilder::RodNodes(RodId rod) const {
  if (!rod.valid() || rod.index() >= model_.rods.size())
    throw InputError("RodNodes: no rod " + std::to_string(rod));
  const std::vector<int>& nodes = model_.rods[rod.index()].nodes;
  std::vector<NodeId> out;
  out.reserve(nodes.size());
  for (int n : nodes) out.push_back(NodeId(n));
  return out;
}

NodeMatch ModelBuilder::FindRodNodeAtArcLength(RodId rod, double s, double tolerance) const {
  const std::vector<double> arcs = RodArcLengths(rod);  // validates the rod and its nodes
  const Rod& r = model_.rods[rod.index()];
  if (tolerance < 0.0) tolerance = 1e-8 * std::max(1.0, arcs.back());
  NodeMatch match;
  match.distance = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < r.nodes.size(); ++i) {
    const double distance = std::abs(arcs[i] - s);
    if (distance < match.distance) {
      match.distance = distance;
      match.nearest = NodeId(r.nodes[i]);
    }
  }
  if (match.distance <= tolerance) match.node = match.nearest;
  return match;
}

}  // namespace screwfem
