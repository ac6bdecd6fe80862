// Build step that conforms the rod meshes to the features placed on them (build/build_steps.h;
// docs/numerics.md, "Conforming rod meshes"): a node wherever a tendon eyelet, a force
// element's end, a concentrated rod load or an actuator's end falls inside an element.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "build_steps.h"

namespace screwfem::build_steps {

namespace {

// The arc lengths of the features on each rod (any order, duplicates allowed). Values the
// later steps reject (an invalid rod, an arc length off the rod, not finite) are left out:
// those steps report them.
std::vector<std::vector<double>> FeatureArcLengths(const Model& m) {
  std::vector<std::vector<double>> at(m.rods.size());
  auto add = [&](int rod, double s) {
    if (rod >= 0 && rod < static_cast<int>(m.rods.size()) && std::isfinite(s) && s > 0.0)
      at[static_cast<std::size_t>(rod)].push_back(s);
  };
  auto add_point = [&](const BodyPoint& p) {
    if (p.rod >= 0) add(p.rod, p.arc_length);
  };
  for (const Tendon& t : m.tendons)
    for (const BodyPoint& p : t.eyelets) add_point(p);
  for (const ForceElement& f : m.force_elements) {
    add_point(f.a);
    add_point(f.b);
  }
  for (const RodLoad& l : m.rod_loads)
    if (!l.distributed) add(l.rod, l.arc_length);
  for (const Actuator& a : m.actuators) {
    add(a.rod, a.from);
    if (a.to >= 0.0) add(a.rod, a.to);
  }
  return at;
}

// A node name not taken yet: the rod's name and the arc length ("arm.s0.125"); "" for a rod
// without a name.
std::string NewNodeName(const std::string& rod, double s, std::set<std::string>& names) {
  if (rod.empty()) return {};
  char buffer[48];
  std::snprintf(buffer, sizeof buffer, ".s%.9g", s);
  std::string name = rod + buffer;
  for (int k = 2; !names.insert(name).second; ++k) name = rod + buffer + "." + std::to_string(k);
  return name;
}

}  // namespace

// Per rod, the features strictly inside an element (xi in (1e-8, 1 - 1e-8), PlaceOnRod's test
// of a point on a node) become nodes: the element is split there, its pieces on the element's
// own helix (the new node's reference frame is the section H_A0 exp(xi d0)), so the reference
// geometry, the rod's length and every other element stay as they were. Several features in
// one element split it into several pieces; features within 1e-8 of the element's length of
// each other give one node. The new nodes are appended to Model::nodes (NodeIds stay valid);
// a node given an initial velocity passes it on as the rigid motion of its frame, the two
// ends' weighted by 1 - xi and xi. Rods whose node lists or elements are invalid are left to
// BuildRodElements to report.
void ConformRodMeshes(Model& m) {
  m.conformed_nodes = 0;
  if (!m.conform_mesh) return;
  const std::vector<std::vector<double>> features = FeatureArcLengths(m);
  std::set<std::string> names;
  bool have_names = false;
  const int num_nodes = static_cast<int>(m.nodes.size());
  for (std::size_t r = 0; r < m.rods.size(); ++r) {
    std::vector<double> at = features[r];
    if (at.empty()) continue;
    Rod& rod = m.rods[r];
    if (rod.num_elements < 1 || rod.nodes.size() != static_cast<std::size_t>(rod.num_elements) + 1)
      continue;
    // The elements as BuildRodElements makes them, and the arc length at each node as
    // PlaceOnRod sums it.
    std::vector<Vec6> d0(static_cast<std::size_t>(rod.num_elements));
    std::vector<double> prefix{0.0};
    bool valid = true;
    for (int e = 0; e < rod.num_elements && valid; ++e) {
      const int a = rod.nodes[static_cast<std::size_t>(e)],
                b = rod.nodes[static_cast<std::size_t>(e) + 1];
      if (a < 0 || a >= num_nodes || b < 0 || b >= num_nodes || a == b) {
        valid = false;
        break;
      }
      const SE3 rel = m.nodes[static_cast<std::size_t>(a)].reference.Inverse() *
                      m.nodes[static_cast<std::size_t>(b)].reference;
      d0[static_cast<std::size_t>(e)] = LogSE3(rel);
      const double length = d0[static_cast<std::size_t>(e)].head<3>().norm();
      if (!(length > 1e-12 * std::max(1.0, rel.x.norm())) ||
          d0[static_cast<std::size_t>(e)].tail<3>().norm() > 3.14159265358979323846 - 1e-3)
        valid = false;
      prefix.push_back(prefix.back() + length);
    }
    if (!valid) continue;
    // Per element, the xi of the features inside it.
    std::vector<std::vector<double>> inside(static_cast<std::size_t>(rod.num_elements));
    bool any = false;
    for (double s : at) {
      if (s > prefix.back() * (1.0 + 1e-12)) continue;  // off the rod: reported later
      const auto end = std::lower_bound(prefix.begin() + 1, prefix.end() - 1, s);
      const std::size_t k = static_cast<std::size_t>(end - prefix.begin()) - 1;
      const double xi = (s - prefix[k]) / (prefix[k + 1] - prefix[k]);
      if (xi > 1e-8 && xi < 1.0 - 1e-8) {
        inside[k].push_back(xi);
        any = true;
      }
    }
    if (!any) continue;
    if (!have_names) {
      for (const Node& n : m.nodes)
        if (!n.name.empty()) names.insert(n.name);
      have_names = true;
    }
    std::vector<int> nodes;
    nodes.reserve(rod.nodes.size() + at.size());
    for (int e = 0; e < rod.num_elements; ++e) {
      const std::size_t k = static_cast<std::size_t>(e);
      nodes.push_back(rod.nodes[k]);
      std::vector<double>& xis = inside[k];
      std::sort(xis.begin(), xis.end());
      double last = -1.0;
      for (double xi : xis) {
        if (xi - last <= 1e-8) continue;
        last = xi;
        const Node& a = m.nodes[static_cast<std::size_t>(rod.nodes[k])];
        const Node& b = m.nodes[static_cast<std::size_t>(rod.nodes[k + 1])];
        Node n;
        const SE3 to_new = ExpSE3(xi * d0[k]);  // H_A0^-1 H_E0
        n.reference = a.reference * to_new;
        n.name = NewNodeName(rod.name, prefix[k] + xi * (prefix[k + 1] - prefix[k]), names);
        if (a.has_initial_velocity || b.has_initial_velocity) {
          // A rigid motion of A's (B's) frame seen in the new frame: Ad(H_E^-1 H_A) v_A.
          const SE3 from_b = to_new.Inverse() * a.reference.Inverse() * b.reference;
          n.has_initial_velocity = true;
          n.initial_velocity = (1.0 - xi) * (Ad(to_new.Inverse()) * a.initial_velocity) +
                               xi * (Ad(from_b) * b.initial_velocity);
        }
        nodes.push_back(static_cast<int>(m.nodes.size()));
        m.nodes.push_back(std::move(n));
        ++m.conformed_nodes;
      }
    }
    nodes.push_back(rod.nodes.back());
    rod.nodes = std::move(nodes);
    rod.num_elements = static_cast<int>(rod.nodes.size()) - 1;
  }
}

}  // namespace screwfem::build_steps
