// Build steps that place items on the rods and nodes (build/build_steps.h): loads, tendons
// and their segments, force elements, actuators and the per-element actuator lists.
#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "build_steps.h"
#include "screwfem/model/enum_names.h"
#include "screwfem/model/errors.h"

namespace screwfem::build_steps {

// Loads: finite values and valid profiles; a concentrated rod load finds its element and xi.
void PlaceLoads(Model& m) {
  const int num_nodes = static_cast<int>(m.nodes.size());
  auto valid_node = [&](int n) { return n >= 0 && n < num_nodes; };
  for (std::size_t i = 0; i < m.point_loads.size(); ++i) {
    const PointLoad& l = m.point_loads[i];
    const EntityRef entity{EntityKind::kPointLoad, static_cast<int>(i), {}};
    if (!valid_node(l.node))
      throw InputError("point load: invalid node " + std::to_string(l.node), entity);
    const std::string label = "point load on " + NodeLabel(m, l.node);
    if (!l.force.allFinite() || !l.moment.allFinite() || !l.point.allFinite())
      throw InputError(label + ": values must be finite", entity);
    ValidateProfile(m, l.profile, label, entity);
  }
  for (std::size_t i = 0; i < m.rod_loads.size(); ++i) {
    RodLoad& l = m.rod_loads[i];
    const EntityRef entity{EntityKind::kRodLoad, static_cast<int>(i), {}};
    if (l.rod < 0 || l.rod >= static_cast<int>(m.rods.size()))
      throw InputError("rod load: invalid rod " + std::to_string(l.rod), entity);
    const Rod& rod = m.rods[static_cast<std::size_t>(l.rod)];
    const std::string label = "load on rod '" + rod.name + "'";
    if (!l.force.allFinite() || !l.moment.allFinite())
      throw InputError(label + ": values must be finite", entity);
    ValidateProfile(m, l.profile, label, entity);
    if (l.distributed) continue;
    if (!(l.arc_length >= 0.0 && l.arc_length <= rod.length * (1.0 + 1e-12)))
      throw InputError(
          label + ": arc length must be within [0, " + std::to_string(rod.length) + "]", entity);
    double s0 = 0.0;
    l.element = rod.first_element + rod.num_elements - 1;
    for (int k = 0; k < rod.num_elements; ++k) {
      const double L = m.elements[static_cast<std::size_t>(rod.first_element + k)].length;
      if (l.arc_length <= s0 + L || k == rod.num_elements - 1) {
        l.element = rod.first_element + k;
        l.xi = std::clamp((l.arc_length - s0) / L, 0.0, 1.0);
        break;
      }
      s0 += L;
    }
  }
}

namespace {

// A lower bound of a profile over all times: the sum of each term's lower bound (a ramp or
// step lies between 0 and its scale, a sine between -|scale| and |scale|, a table between its
// extreme values times the scale).
double ProfileLowerBound(const Profile& profile) {
  double bound = 0.0;
  for (const ProfileTerm& t : profile.terms()) {
    switch (t.kind) {
      case ProfileTerm::Kind::kConstant:
        bound += t.scale;
        break;
      case ProfileTerm::Kind::kRamp:
      case ProfileTerm::Kind::kBangBang:
      case ProfileTerm::Kind::kSmoothStep:
        bound += std::min(0.0, t.scale);
        break;
      case ProfileTerm::Kind::kSine:
        bound -= std::abs(t.scale);
        break;
      case ProfileTerm::Kind::kTable: {
        double lo = 0.0;
        for (std::size_t i = 0; i < t.values.size(); ++i) {
          const double v = t.scale * t.values[i];
          lo = i == 0 ? v : std::min(lo, v);
        }
        bound += lo;
        break;
      }
      // A run-time input can take any value; the tension is clamped at 0 when it arrives
      // (TendonTension), so it adds nothing to the bound checked here.
      case ProfileTerm::Kind::kInput:
        break;
    }
  }
  return bound;
}

// A body point: a valid node (or the ground) and a finite offset; "" when it is, else why not.
std::string BodyPointProblem(const Model& m, const BodyPoint& p) {
  if (p.node != kGround && (p.node < 0 || p.node >= static_cast<int>(m.nodes.size())))
    return "invalid node " + std::to_string(p.node);
  if (!p.offset.allFinite()) return "the offset must be finite";
  return {};
}

Vec3 ReferencePosition(const Model& m, const BodyPoint& p) {
  SE3 H = NodeReferenceFrame(m, p.node);
  if (p.element >= 0)  // the section H_A0 exp(xi d0) of the element
    H = H * ExpSE3(p.xi * m.elements[static_cast<std::size_t>(p.element)].d0);
  return H.x + H.R * p.offset;
}

// An eyelet at an arc length of a rod (BodyPoint::rod >= 0): on the node there (within 1e-8
// of the element length) or between the nodes of the element holding it (element, xi, node A).
// "" when placed, else why not.
// Per rod, the arc length at each node (prefix[k]: the sum of the first k element lengths,
// added in order), made on first use: a point is placed by a binary search, so that a tendon
// of n eyelets on a rod of N elements is placed in n log N (a walk along the rod per eyelet
// took 19.6 s for 1e4 eyelets).
using ArcPrefixes = std::vector<std::vector<double>>;

std::string PlaceOnRod(const Model& m, BodyPoint& p, ArcPrefixes& prefixes) {
  if (p.rod < 0) return {};
  if (p.rod >= static_cast<int>(m.rods.size())) return "invalid rod " + std::to_string(p.rod);
  const Rod& rod = m.rods[static_cast<std::size_t>(p.rod)];
  if (!(p.arc_length >= 0.0 && p.arc_length <= rod.length * (1.0 + 1e-12)))
    return "arc length " + std::to_string(p.arc_length) + " m is off the rod (length " +
           std::to_string(rod.length) + " m)";
  if (rod.num_elements <= 0) return "rod '" + rod.name + "' has no elements";
  if (prefixes.size() != m.rods.size()) prefixes.assign(m.rods.size(), {});
  std::vector<double>& prefix = prefixes[static_cast<std::size_t>(p.rod)];
  if (prefix.empty()) {
    prefix.push_back(0.0);
    for (int k = 0; k < rod.num_elements; ++k)
      prefix.push_back(prefix.back() +
                       m.elements[static_cast<std::size_t>(rod.first_element + k)].length);
  }
  // The first element whose end is at or beyond the point (the last one otherwise).
  const auto end = std::lower_bound(prefix.begin() + 1, prefix.end() - 1, p.arc_length);
  const int k = static_cast<int>(end - prefix.begin()) - 1;
  const int e = rod.first_element + k;
  const RodElement& el = m.elements[static_cast<std::size_t>(e)];
  const double xi =
      std::clamp((p.arc_length - prefix[static_cast<std::size_t>(k)]) / el.length, 0.0, 1.0);
  p.element = -1;
  p.xi = 0.0;
  if (xi <= 1e-8) {
    p.node = el.node_a;
  } else if (xi >= 1.0 - 1e-8) {
    p.node = el.node_b;
  } else {
    p.node = el.node_a;
    p.element = e;
    p.xi = xi;
  }
  return {};
}

}  // namespace

namespace {

// Places the eyelets of tendon `index` (PlaceOnRod) and checks them: valid body points, and
// consecutive eyelets apart in the reference configuration.
void PlaceTendonEyelets(const Model& m, Tendon& t, int index, const std::string& label,
                        ArcPrefixes& prefixes) {
  for (std::size_t k = 0; k < t.eyelets.size(); ++k) {
    std::string problem = PlaceOnRod(m, t.eyelets[k], prefixes);
    if (problem.empty()) problem = BodyPointProblem(m, t.eyelets[k]);
    if (!problem.empty())
      throw InputError(label + ": eyelet " + std::to_string(k) + ": " + problem,
                       {EntityKind::kTendon, index, "eyelets[" + std::to_string(k) + "]"}, problem);
    if (k == 0) continue;
    const double l =
        (ReferencePosition(m, t.eyelets[k]) - ReferencePosition(m, t.eyelets[k - 1])).norm();
    if (!(l > 1e-9 * std::max(1.0, m.length_scale))) {
      const std::string what = "coincides with eyelet " + std::to_string(k - 1) +
                               " in the reference configuration (no direction between them)";
      throw InputError(label + ": eyelet " + std::to_string(k) + " " + what,
                       {EntityKind::kTendon, index, "eyelets[" + std::to_string(k) + "]"}, what);
    }
  }
}

// The profiles of a tendon: valid inputs; a length (drawn by length) that stays positive and a
// tension that cannot become negative, by their terms' lower bounds (ProfileLowerBound).
void CheckTendonProfiles(const Model& m, const Tendon& t, const std::string& label,
                         const EntityRef& entity) {
  if (t.drive == TendonDrive::kLength) {
    ValidateProfile(m, t.length, label + " length", entity);
    const double lower = ProfileLowerBound(t.length);
    if (!(lower > 0.0))
      throw InputError(label +
                           ": the length profile can become zero or negative (its terms' "
                           "lower bound is " +
                           std::to_string(lower) + " m)",
                       entity);
  }
  ValidateProfile(m, t.tension, label + " tension", entity);
  const double lower = ProfileLowerBound(t.tension);
  if (lower < 0.0)
    throw InputError(label +
                         ": the tension profile can become negative (its terms' lower "
                         "bound is " +
                         std::to_string(lower) + " N); a tendon can only pull",
                     entity);
}

// The segments on nodes, grouped by node pair in the order of their first segments.
void GroupTendonSegments(Model& m) {
  m.tendon_segment_groups.clear();
  m.tendon_group_segments.clear();
  std::map<std::pair<int, int>, std::vector<int>> by_pair;
  std::vector<std::pair<int, int>> order;
  for (std::size_t i = 0; i < m.tendon_segments.size(); ++i) {
    const TendonSegment& s = m.tendon_segments[i];
    if (s.a.element >= 0 || s.b.element >= 0) continue;  // TendonSpanSegmentKind's
    std::vector<int>& list = by_pair[{s.a.node, s.b.node}];
    if (list.empty()) order.emplace_back(s.a.node, s.b.node);
    list.push_back(static_cast<int>(i));
  }
  for (const auto& key : order) {
    const std::vector<int>& list = by_pair[key];
    m.tendon_segment_groups.push_back({key.first, key.second,
                                       static_cast<int>(m.tendon_group_segments.size()),
                                       static_cast<int>(list.size())});
    m.tendon_group_segments.insert(m.tendon_group_segments.end(), list.begin(), list.end());
  }
}

}  // namespace

// Tendons (docs/numerics.md, "Tendons and force elements"): eyelets, tension profile, unique names; their segments.
void BuildTendons(Model& m) {
  m.tendon_segments.clear();
  ArcPrefixes prefixes;
  std::set<std::string> names;
  for (std::size_t i = 0; i < m.tendons.size(); ++i) {
    Tendon& t = m.tendons[i];
    const std::string label = "tendon '" + t.name + "'";
    const int index = static_cast<int>(i);
    const EntityRef entity{EntityKind::kTendon, index, {}};
    if (t.eyelets.size() < 2)
      throw InputError(label + ": needs at least two eyelets (it runs between them), got " +
                           std::to_string(t.eyelets.size()),
                       entity);
    PlaceTendonEyelets(m, t, index, label, prefixes);
    t.reference_length = 0.0;
    for (std::size_t k = 0; k + 1 < t.eyelets.size(); ++k)
      t.reference_length +=
          (ReferencePosition(m, t.eyelets[k + 1]) - ReferencePosition(m, t.eyelets[k])).norm();
    CheckTendonProfiles(m, t, label, entity);
    if (!t.name.empty() && !names.insert(t.name).second)
      throw InputError("duplicate tendon name '" + t.name + "'", entity);
    t.first_segment = static_cast<int>(m.tendon_segments.size());
    for (std::size_t k = 0; k + 1 < t.eyelets.size(); ++k)
      m.tendon_segments.push_back({index, t.eyelets[k], t.eyelets[k + 1]});
  }
  GroupTendonSegments(m);
}

namespace {

// Throws the InputError of an actuator for one of its parts.
struct ActuatorError {
  const std::string& label;
  int index;
  [[noreturn]] void operator()(const std::string& part, const std::string& what) const {
    throw InputError(label + ": " + what, {EntityKind::kActuator, index, part}, what);
  }
};

// The range [from, to] of an actuator on its rod (a negative `to`: the rod's end) must start
// and end at nodes: sets first_element and num_elements; an error names the nearest node's arc
// length.
void PlaceActuatorRange(const Model& m, Actuator& a, const ActuatorError& fail) {
  const Rod& rod = m.rods[static_cast<std::size_t>(a.rod)];
  const double to = a.to < 0.0 ? rod.length : a.to;
  const double tol = 1e-8 * std::max(1.0, rod.length);
  if (!(a.from >= 0.0) || !std::isfinite(a.from))
    fail("from", "must be a finite arc length >= 0, got " + std::to_string(a.from));
  if (!(to <= rod.length + tol) || !std::isfinite(to))
    fail("to", "must not exceed the rod's length " + std::to_string(rod.length) + " m, got " +
                   std::to_string(to));
  if (!(to > a.from + tol))
    fail("to",
         "must be greater than from (" + std::to_string(a.from) + " m), got " + std::to_string(to));
  // The range's ends at nodes: the first element starting at `from`, the last ending at `to`.
  int first = -1, last = -1;
  double s = 0.0, near_from = INFINITY, near_to = INFINITY;
  for (int k = 0; k < rod.num_elements; ++k) {
    const double L = m.elements[static_cast<std::size_t>(rod.first_element + k)].length;
    if (std::abs(s - a.from) <= tol) first = k;
    if (std::abs(s - a.from) < std::abs(near_from - a.from)) near_from = s;
    s += L;
    if (std::abs(s - to) <= tol) last = k;
    if (std::abs(s - to) < std::abs(near_to - to)) near_to = s;
  }
  // Only without a conforming mesh (Model::conform_mesh puts nodes at both ends).
  const std::string hint = "; a conforming mesh (defaults.conform_mesh: true) puts one there";
  if (first < 0)
    fail("from", "arc length " + std::to_string(a.from) + " m is not at a node of rod '" +
                     rod.name + "' (the nearest node is at " + std::to_string(near_from) + " m)" +
                     hint);
  if (last < 0)
    fail("to", "arc length " + std::to_string(to) + " m is not at a node of rod '" + rod.name +
                   "' (the nearest node is at " + std::to_string(near_to) + " m)" + hint);
  a.first_element = rod.first_element + first;
  a.num_elements = last - first + 1;
}

// eps0 and sigma_a per unit profile value: a pressure or muscle chamber's stress from its area
// and offset, else the actuator's vector.
void SetActuatorUnits(Actuator& a, const ActuatorError& fail) {
  a.rest_strain_unit.setZero();
  a.active_stress_unit.setZero();
  const bool chamber = a.type == ActuatorType::kPressure || a.type == ActuatorType::kMuscle;
  if (chamber) {
    if (!(a.area > 0.0) || !std::isfinite(a.area))
      fail("area", "must be a positive area [m^2], got " + std::to_string(a.area));
    if (!a.offset.allFinite()) fail("offset", "must be finite");
    // A chamber or muscle runs along the rod: its offset lies in the section plane, and a
    // first (axial) component would be ignored.
    if (a.offset(0) != 0.0)
      fail("offset",
           "the first (axial) component must be 0: a chamber or muscle runs along the "
           "rod, its offset lies in the section plane (got " +
               std::to_string(a.offset(0)) + " m)");
    // sigma_a per unit pressure: A [e1; r x e1] (docs/numerics.md, "Active stress and rest strain").
    Vec6 unit;
    unit << 1.0, 0.0, 0.0, 0.0, a.offset(2), -a.offset(1);
    unit *= a.area;
    if (a.type == ActuatorType::kMuscle) {
      if (!(a.max_stress >= 0.0) || !std::isfinite(a.max_stress))
        fail("max_stress",
             "must be finite and non-negative [Pa], got " + std::to_string(a.max_stress));
      unit *= -a.max_stress;
    }
    a.active_stress_unit = unit;
    if (!a.vector.isZero()) fail("vector", "is not used by a chamber or muscle (it must be 0)");
    if (a.type == ActuatorType::kPressure && a.max_stress != 0.0)
      fail("max_stress", "is not used by a pressure chamber (it must be 0)");
  } else {
    if (a.area != 0.0 || !a.offset.isZero() || a.max_stress != 0.0)
      fail(a.area != 0.0        ? "area"
           : !a.offset.isZero() ? "offset"
                                : "max_stress",
           std::string("is not used by type '") + NameOf(a.type) + "' (it must be 0)");
    if (!a.vector.allFinite()) fail("vector", "must be finite");
    (a.type == ActuatorType::kRestStrain ? a.rest_strain_unit : a.active_stress_unit) = a.vector;
  }
}

// Per element, its actuators in order (several on one element add).
void ListElementActuators(Model& m) {
  m.element_actuators.clear();
  for (std::size_t e = 0; e < m.elements.size(); ++e) {
    RodElement& el = m.elements[e];
    el.first_actuator = static_cast<int>(m.element_actuators.size());
    for (std::size_t i = 0; i < m.actuators.size(); ++i) {
      const Actuator& a = m.actuators[i];
      const int k = static_cast<int>(e) - a.first_element;
      if (k >= 0 && k < a.num_elements) m.element_actuators.push_back(static_cast<int>(i));
    }
    el.num_actuators = static_cast<int>(m.element_actuators.size()) - el.first_actuator;
  }
}

}  // namespace

// Actuators (docs/numerics.md, "Active stress and rest strain"): rod, range at nodes, values; eps0 and sigma_a per unit
// profile value; the per-element lists of Model::element_actuators.
void BuildActuators(Model& m) {
  std::set<std::string> names;
  for (std::size_t i = 0; i < m.actuators.size(); ++i) {
    Actuator& a = m.actuators[i];
    const std::string label = "actuator '" + a.name + "'";
    const int index = static_cast<int>(i);
    const EntityRef entity{EntityKind::kActuator, index, {}};
    const ActuatorError fail{label, index};
    if (a.rod < 0 || a.rod >= static_cast<int>(m.rods.size()))
      fail("rod", "invalid rod " + std::to_string(a.rod));
    if (!IsEnumValue(a.type)) fail("type", "invalid actuator type");
    PlaceActuatorRange(m, a, fail);
    SetActuatorUnits(a, fail);
    ValidateProfile(m, a.profile, label + " profile", entity);
    if (!a.name.empty() && !names.insert(a.name).second)
      throw InputError("duplicate actuator name '" + a.name + "'", entity);
  }
  ListElementActuators(m);
}

// Force elements: ends (at an arc length: PlaceOnRod, as eyelets), values, rest length (the
// reference distance when negative), names.
void BuildForceElements(Model& m) {
  std::set<std::string> names;
  ArcPrefixes prefixes;
  for (std::size_t i = 0; i < m.force_elements.size(); ++i) {
    ForceElement& f = m.force_elements[i];
    const std::string label = "force element '" + f.name + "'";
    const int index = static_cast<int>(i);
    const EntityRef entity{EntityKind::kForceElement, index, {}};
    for (const auto& [p, part] : {std::pair<BodyPoint*, const char*>{&f.a, "a"}, {&f.b, "b"}}) {
      std::string problem = PlaceOnRod(m, *p, prefixes);  // at an arc length, as an eyelet
      if (problem.empty()) problem = BodyPointProblem(m, *p);
      if (!problem.empty())
        throw InputError(label + ": end " + part + ": " + problem,
                         {EntityKind::kForceElement, index, part}, problem);
    }
    if (f.a.node == f.b.node && f.a.element < 0 && f.b.element < 0)
      throw InputError(label + ": both ends are on " + NodeLabel(m, f.a.node), entity);
    if (!(f.stiffness >= 0.0) || !std::isfinite(f.stiffness) || !(f.damping >= 0.0) ||
        !std::isfinite(f.damping))
      throw InputError(label + ": stiffness and damping must be finite and non-negative", entity);
    if (!std::isfinite(f.rest_length))
      throw InputError(label + ": the rest length must be finite", entity);
    const double l = (ReferencePosition(m, f.b) - ReferencePosition(m, f.a)).norm();
    if (!(l > 1e-9 * std::max(1.0, m.length_scale)))
      throw InputError(label +
                           ": its ends coincide in the reference configuration (no direction "
                           "between them)",
                       {EntityKind::kForceElement, index, "b"},
                       "coincides with end a in the reference configuration");
    if (f.rest_length < 0.0) f.rest_length = l;
    ValidateProfile(m, f.actuator, label + " actuator", entity);
    if (!f.name.empty() && !names.insert(f.name).second)
      throw InputError("duplicate force element name '" + f.name + "'", entity);
  }
}

}  // namespace screwfem::build_steps
