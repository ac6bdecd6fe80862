// The contact build step (build/build_steps.h): validates contact rods, shapes, obstacles and
// the law, lists the (moving shape, obstacle) pairs and the segments of the moving shapes with
// the entity pairs that may touch, and resolves the law's defaults.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>
#include <string>
#include <vector>

#include "build_steps.h"
#include "screwfem/build/model_builder.h"
#include "screwfem/elements/shape_pair.h"
#include "screwfem/model/errors.h"
#include "screwfem/model/memory.h"

namespace screwfem::build_steps {

namespace {

bool IsPositiveSize(double x) { return std::isfinite(x) && x > 0.0; }

// A rotation matrix to round-off: orthonormal, determinant +1.
bool IsRotation(const Mat3& R) {
  return R.allFinite() && (R.transpose() * R - Mat3::Identity()).norm() < 1e-9 &&
         R.determinant() > 0.0;
}

// The weight per unit mass for the law's defaults: |g|, or standard gravity without gravity.
double ContactGravity(const Model& m) { return m.gravity.norm() > 0.0 ? m.gravity.norm() : 9.81; }

// The group bitmasks of a rod or body (model.h, ContactGroup): the first set, else 1 and 1.
ContactGroup ContactGroupOf(const Model& m, bool rod, int index) {
  for (const ContactGroup& g : m.contact_groups)
    if (g.rod == rod && g.index == index) return g;
  return ContactGroup{rod, index, 1u, 1u};
}

// ---- Contact materials (model.h, ContactMaterial) ------------------------------------------

// The material group of a rod or body, or -1 (CheckMaterialGroups: at most one).
int MaterialGroupOf(const Model& m, bool rod, int index) {
  for (std::size_t g = 0; g < m.contact_material_groups.size(); ++g) {
    const std::vector<int>& members =
        rod ? m.contact_material_groups[g].rods : m.contact_material_groups[g].bodies;
    if (std::find(members.begin(), members.end(), index) != members.end())
      return static_cast<int>(g);
  }
  return -1;
}

int ObstacleMaterialGroup(const Model& m, int obstacle) {
  for (std::size_t g = 0; g < m.contact_material_groups.size(); ++g) {
    const std::vector<int>& members = m.contact_material_groups[g].obstacles;
    if (std::find(members.begin(), members.end(), obstacle) != members.end())
      return static_cast<int>(g);
  }
  return -1;
}

// Groups: unique non-empty names, members that exist, each in at most one group.
void CheckMaterialGroups(const Model& m) {
  std::set<std::string> names;
  std::set<std::pair<int, int>> seen;  // (kind, index): 0 rod, 1 body, 2 obstacle
  const char* kinds[3] = {"rod", "body", "obstacle"};
  for (const ContactMaterialGroup& g : m.contact_material_groups) {
    if (g.name.empty()) throw InputError("contact group: the name must not be empty");
    if (!names.insert(g.name).second)
      throw InputError("contact group '" + g.name + "' is defined twice");
    const std::vector<int>* lists[3] = {&g.rods, &g.bodies, &g.obstacles};
    const std::size_t sizes[3] = {m.rods.size(), m.bodies.size(), m.obstacles.size()};
    for (int k = 0; k < 3; ++k)
      for (int i : *lists[k]) {
        if (i < 0 || i >= static_cast<int>(sizes[k]))
          throw InputError("contact group '" + g.name + "': no " + kinds[k] + " " +
                           std::to_string(i));
        if (!seen.insert({k, i}).second)
          throw InputError("contact group '" + g.name + "': " + kinds[k] + " " + std::to_string(i) +
                           " is in another group already");
      }
  }
}

// The materials: existing groups, each pair of groups once, values finite and in range.
void CheckMaterials(const Model& m) {
  const int groups = static_cast<int>(m.contact_material_groups.size());
  std::set<std::pair<int, int>> pairs;
  for (std::size_t i = 0; i < m.contact_materials.size(); ++i) {
    const ContactMaterial& c = m.contact_materials[i];
    const std::string label = "contact pair " + std::to_string(i);
    for (int g : c.group)
      if (g < 0 || g >= groups) throw InputError(label + ": no contact group " + std::to_string(g));
    const auto name = [&](int g) {
      return "'" + m.contact_material_groups[static_cast<std::size_t>(g)].name + "'";
    };
    if (!pairs.insert({std::min(c.group[0], c.group[1]), std::max(c.group[0], c.group[1])}).second)
      throw InputError(label + ": the groups " + name(c.group[0]) + " and " + name(c.group[1]) +
                       " have a material already");
    for (double v : {c.friction, c.static_friction, c.stiffness, c.damping_ratio,
                     c.tangential_stiffness, c.onset})
      if (!std::isfinite(v)) throw InputError(label + ": the parameters must be finite");
    if (c.stiffness == 0.0 || c.tangential_stiffness == 0.0 || c.onset == 0.0)
      throw InputError(label +
                       ": stiffness, tangential stiffness and onset must be positive (or left "
                       "to the scene's)");
  }
}

// Model::contact_laws and contact_law_table from the resolved settings (ResolveContactLaw).
void ResolveMaterials(Model& m) {
  const ContactSettings& c = m.contact;
  m.contact_laws.clear();
  m.contact_laws.emplace_back();
  ContactMaterial& base = m.contact_laws[0];
  base.friction = c.friction;
  base.static_friction = std::max(c.static_friction, c.friction);
  base.stiffness = c.stiffness;
  base.damping_ratio = c.damping_ratio;
  base.tangential_stiffness = c.tangential_stiffness > 0.0 ? c.tangential_stiffness : c.stiffness;
  base.onset = c.onset;
  const std::size_t n = m.contact_material_groups.size() + 1;
  m.contact_law_table.assign(n * n, 0);
  for (std::size_t i = 0; i < m.contact_materials.size(); ++i) {
    const ContactMaterial& given = m.contact_materials[i];
    ContactMaterial law = given;
    const ContactMaterial& d = m.contact_laws[0];
    const bool own_friction = given.friction >= 0.0;
    if (!own_friction) law.friction = d.friction;
    if (given.static_friction < 0.0)
      law.static_friction = own_friction ? law.friction : std::max(d.static_friction, law.friction);
    if (given.stiffness < 0.0) law.stiffness = d.stiffness;
    if (given.damping_ratio < 0.0) law.damping_ratio = d.damping_ratio;
    if (given.onset < 0.0) law.onset = d.onset;
    if (given.tangential_stiffness < 0.0)
      law.tangential_stiffness =
          c.tangential_stiffness > 0.0 ? c.tangential_stiffness : law.stiffness;
    if (law.static_friction < law.friction) {
      char buf[256];
      std::snprintf(buf, sizeof buf,
                    "contact pair %zu: the static friction coefficient must be >= the friction "
                    "(mu_s >= mu_k), got %g < %g",
                    i, law.static_friction, law.friction);
      throw InputError(buf);
    }
    m.contact_laws.push_back(law);
    const int index = static_cast<int>(m.contact_laws.size()) - 1;
    const std::size_t a = static_cast<std::size_t>(given.group[0] + 1);
    const std::size_t b = static_cast<std::size_t>(given.group[1] + 1);
    m.contact_law_table[a * n + b] = index;
    m.contact_law_table[b * n + a] = index;
  }
}

// ---- Moving shapes: entities, their segments and the entity pairs that may touch ----------

// Entities: rods (contact_rods) and bodies with shapes (spheres, capsules, boxes).
struct ContactEntity {
  bool rod;
  int index;    // rod or body index
  int contact;  // contact_rods index (rods)
  std::vector<int> nodes;
};

// The segments of an entity: sides with their masses.
struct EntitySegment {
  ShapePairSide side;
  double mass;      // INFINITY when every node of the side is fixed
  int first, last;  // rod: the element's position along the rod and its arc-length span
  double s0, s1;
};

// Per entity: the largest finite segment mass (-1: none), whether a segment is fixed, the
// smallest size (radius, or a box's smallest half size).
struct EntitySizes {
  std::vector<double> heaviest, smallest;
  std::vector<char> has_fixed;
};

std::vector<ContactEntity> ListContactEntities(const Model& m) {
  std::vector<ContactEntity> entities;
  for (std::size_t i = 0; i < m.contact_rods.size(); ++i) {
    const ContactRod& c = m.contact_rods[i];
    entities.push_back(
        {true, c.rod, static_cast<int>(i), m.rods[static_cast<std::size_t>(c.rod)].nodes});
  }
  for (const ContactShape& c : m.contact_shapes) {
    bool seen = false;
    for (const ContactEntity& e : entities) seen = seen || (!e.rod && e.index == c.body);
    if (!seen)
      entities.push_back({false, c.body, -1, {m.bodies[static_cast<std::size_t>(c.body)].node}});
  }
  return entities;
}

// The pair exclusions name existing rods and bodies.
void CheckPairExclusions(const Model& m) {
  for (const ContactPairExclusion& x : m.contact_pair_exclusions)
    for (int k = 0; k < 2; ++k) {
      const std::size_t size = x.rod[k] ? m.rods.size() : m.bodies.size();
      if (x.index[k] < 0 || x.index[k] >= static_cast<int>(size))
        throw InputError(std::string("contact exclusion: no ") + (x.rod[k] ? "rod " : "body ") +
                         std::to_string(x.index[k]));
    }
}

// The entity pairs (i < k) that never touch: excluded (contact: exclude) or joined (a shared
// node or a joint between their nodes). Built in time linear in the nodes, joints and
// exclusions (the pairwise tests took time quadratic in the entities times their nodes).
std::set<std::pair<int, int>> SeparatedEntityPairs(const Model& m,
                                                   const std::vector<ContactEntity>& entities) {
  std::set<std::pair<int, int>> out;
  const auto add = [&](int a, int b) {
    if (a >= 0 && b >= 0 && a != b) out.insert({std::min(a, b), std::max(a, b)});
  };
  // Entity of each rod and body.
  std::vector<int> of_rod(m.rods.size(), -1), of_body(m.bodies.size(), -1);
  for (std::size_t e = 0; e < entities.size(); ++e)
    (entities[e].rod ? of_rod : of_body)[static_cast<std::size_t>(entities[e].index)] =
        static_cast<int>(e);
  for (const ContactPairExclusion& x : m.contact_pair_exclusions)
    add((x.rod[0] ? of_rod : of_body)[static_cast<std::size_t>(x.index[0])],
        (x.rod[1] ? of_rod : of_body)[static_cast<std::size_t>(x.index[1])]);
  // The entities holding each node (a node shared by two entities joins them).
  std::vector<std::vector<int>> of_node(m.nodes.size());
  for (std::size_t e = 0; e < entities.size(); ++e)
    for (int n : entities[e].nodes)
      if (n >= 0) of_node[static_cast<std::size_t>(n)].push_back(static_cast<int>(e));
  for (const std::vector<int>& list : of_node)
    for (std::size_t i = 0; i < list.size(); ++i)
      for (std::size_t k = i + 1; k < list.size(); ++k) add(list[i], list[k]);
  for (const Joint& j : m.joints) {
    if (j.node_a < 0 || j.node_b < 0) continue;
    for (int a : of_node[static_cast<std::size_t>(j.node_a)])
      for (int b : of_node[static_cast<std::size_t>(j.node_b)]) add(a, b);
  }
  return out;
}

bool FixedOrGround(const Model& m, int node) {
  return node == kGround || m.nodes[static_cast<std::size_t>(node)].fixed;
}

// A rod's segments: its element capsules, with their arc-length spans.
std::vector<EntitySegment> RodSegments(const Model& m, const ContactEntity& e) {
  std::vector<EntitySegment> out;
  const Rod& rod = m.rods[static_cast<std::size_t>(e.index)];
  const double radius = m.contact_rods[static_cast<std::size_t>(e.contact)].radius;
  double arc = 0.0;
  for (int k = 0; k < rod.num_elements; ++k) {
    const RodElement& el = m.elements[static_cast<std::size_t>(rod.first_element + k)];
    EntitySegment g;
    g.side.node[0] = el.node_a;
    g.side.node[1] = el.node_b;
    g.side.end_node[1] = 1;
    g.side.radius = radius;
    g.side.rod = true;
    g.side.owner = e.index;
    g.side.element = rod.first_element + k;
    g.mass = FixedOrGround(m, el.node_a) && FixedOrGround(m, el.node_b)
                 ? INFINITY
                 : rod.section.inertia(0) * el.length;
    g.first = g.last = k;
    g.s0 = arc;
    arc += el.length;
    g.s1 = arc;
    out.push_back(g);
  }
  return out;
}

// A body's segments: its spheres, capsules and boxes (a box: half sizes, radius 0).
std::vector<EntitySegment> BodySegments(const Model& m, const ContactEntity& e) {
  std::vector<EntitySegment> out;
  const RigidBody& body = m.bodies[static_cast<std::size_t>(e.index)];
  for (const ContactShape& c : m.contact_shapes) {
    if (c.body != e.index) continue;
    EntitySegment g;
    g.side.node[0] = body.node;
    g.side.offset[0] = c.from;
    g.side.offset[1] = c.type == ContactShapeType::kCapsule ? c.to : c.from;
    g.side.radius = c.radius;
    if (c.type == ContactShapeType::kBox) {
      g.side.half = c.to;
      g.side.rotation = c.rotation;
      g.side.radius = 0.0;
    } else if (c.type == ContactShapeType::kCylinder) {
      g.side.offset[1] = c.to;
      g.side.cylinder = c.radius;
      g.side.radius = 0.0;
    }
    g.side.owner = e.index;
    g.mass = FixedOrGround(m, body.node) ? INFINITY : body.mass;
    g.first = g.last = 0;
    g.s0 = g.s1 = 0.0;
    out.push_back(g);
  }
  return out;
}

// Every entity's segments into Model::contact_segments, in entity order; the entities' sizes.
EntitySizes AddContactSegments(Model& m, const std::vector<ContactEntity>& entities) {
  const int ne = static_cast<int>(entities.size());
  EntitySizes sizes;
  sizes.heaviest.assign(static_cast<std::size_t>(ne), -1.0);
  sizes.smallest.assign(static_cast<std::size_t>(ne), INFINITY);
  sizes.has_fixed.assign(static_cast<std::size_t>(ne), 0);
  for (int e = 0; e < ne; ++e) {
    const ContactEntity& entity = entities[static_cast<std::size_t>(e)];
    for (const EntitySegment& g : entity.rod ? RodSegments(m, entity) : BodySegments(m, entity)) {
      ContactSegment cs;
      cs.side = g.side;
      cs.mass = g.mass;
      cs.entity = e;
      cs.s0 = g.s0;
      cs.s1 = g.s1;
      cs.material_group = MaterialGroupOf(m, entity.rod, entity.index);
      m.contact_segments.push_back(cs);
      const std::size_t k = static_cast<std::size_t>(e);
      if (std::isinf(g.mass))
        sizes.has_fixed[k] = 1;
      else
        sizes.heaviest[k] = std::max(sizes.heaviest[k], g.mass);
      sizes.smallest[k] = std::min(sizes.smallest[k], g.side.half.x() > 0.0 ? g.side.half.minCoeff()
                                                      : g.side.cylinder > 0.0 ? g.side.cylinder
                                                                              : g.side.radius);
    }
  }
  return sizes;
}

// The law's defaults over the pairs that can occur: max over pairs of min(m_x, m_y) is the
// lighter entity's heaviest segment (or the heaviest of one side against a fixed segment).
void WeighEntityPair(const EntitySizes& sizes, int a, int b, double gravity, double* r_min,
                     double* w_max) {
  const std::size_t ka = static_cast<std::size_t>(a), kb = static_cast<std::size_t>(b);
  double w = std::min(sizes.heaviest[ka], sizes.heaviest[kb]);
  if (sizes.has_fixed[ka]) w = std::max(w, sizes.heaviest[kb]);
  if (sizes.has_fixed[kb]) w = std::max(w, sizes.heaviest[ka]);
  if (w > 0.0) *w_max = std::max(*w_max, w * gravity);
  *r_min = std::min(*r_min, std::min(sizes.smallest[ka], sizes.smallest[kb]));
}

// Model::contact_entity_pairs (the entities' group bits, the pairs set apart), and the self skip
// of each rod in self-contact; weighs every pair that can occur.
void PairContactEntities(Model& m, const std::vector<ContactEntity>& entities,
                         const EntitySizes& sizes, double* r_min, double* w_max) {
  const ContactSettings& law = m.contact;
  const double gravity = ContactGravity(m);
  const int ne = static_cast<int>(entities.size());
  const std::size_t une = static_cast<std::size_t>(ne);
  // Group bitmasks per entity (the first ContactGroup of each, ContactGroupOf), in one pass.
  std::vector<ContactGroup> groups(une);
  {
    std::vector<int> of_rod(m.rods.size(), -1), of_body(m.bodies.size(), -1);
    for (std::size_t e = 0; e < une; ++e) {
      (entities[e].rod ? of_rod : of_body)[static_cast<std::size_t>(entities[e].index)] =
          static_cast<int>(e);
      groups[e] = ContactGroup{entities[e].rod, entities[e].index, 1u, 1u};
    }
    std::vector<char> set(une, 0);
    for (const ContactGroup& g : m.contact_groups) {
      const std::vector<int>& of = g.rod ? of_rod : of_body;
      if (g.index < 0 || g.index >= static_cast<int>(of.size())) continue;
      const int e = of[static_cast<std::size_t>(g.index)];
      if (e < 0 || set[static_cast<std::size_t>(e)]) continue;
      set[static_cast<std::size_t>(e)] = 1;
      groups[static_cast<std::size_t>(e)] = g;
    }
  }
  ContactEntityPairs& table = m.contact_entity_pairs;
  for (int i = 0; i < ne; ++i) {
    const ContactGroup& g = groups[static_cast<std::size_t>(i)];
    table.SetGroups(i, g.contype, g.conaffinity);
  }
  for (const auto& [i, k] : SeparatedEntityPairs(m, entities)) table.SetApart(i, k);
  table.Finish();
  for (int i = 0; i < ne; ++i) {
    const ContactEntity& a = entities[static_cast<std::size_t>(i)];
    for (int k = i + 1; k < ne; ++k)
      if (table.MayTouch(i, k)) WeighEntityPair(sizes, i, k, gravity, r_min, w_max);
    if (a.rod && law.self) {
      const double skip = law.self_skip > 0.0
                              ? law.self_skip
                              : 4.0 * m.contact_rods[static_cast<std::size_t>(a.contact)].radius;
      m.contact_entity_self_skip[static_cast<std::size_t>(i)] = skip;
      const Rod& rod = m.rods[static_cast<std::size_t>(a.index)];
      double length = 0.0;
      for (int e = 0; e < rod.num_elements; ++e)
        length += m.elements[static_cast<std::size_t>(rod.first_element + e)].length;
      // Two of its elements can be skip apart.
      if (length > skip) WeighEntityPair(sizes, i, i, gravity, r_min, w_max);
    }
  }
}

// A cylinder touches spheres, capsules and rods (and obstacles), not a box or a cylinder of
// another body: two entities that may touch with such shapes are an error naming them.
void CheckCylinderPairs(const Model& m, const std::vector<ContactEntity>& entities) {
  const std::size_t ne = entities.size();
  std::vector<char> cylinder(ne, 0), box(ne, 0);
  for (const ContactSegment& g : m.contact_segments) {
    const std::size_t e = static_cast<std::size_t>(g.entity);
    if (g.side.cylinder > 0.0) cylinder[e] = 1;
    if (g.side.half.x() > 0.0) box[e] = 1;
  }
  for (std::size_t i = 0; i < ne; ++i) {
    if (!cylinder[i]) continue;
    for (std::size_t k = 0; k < ne; ++k) {
      if (k == i || !(cylinder[k] || box[k]) ||
          !m.contact_entity_pairs.MayTouch(static_cast<int>(i), static_cast<int>(k)))
        continue;
      const std::string a = m.bodies[static_cast<std::size_t>(entities[i].index)].name;
      const std::string b = m.bodies[static_cast<std::size_t>(entities[k].index)].name;
      throw InputError("contact between the cylinder of body '" + a + "' and the " +
                       (cylinder[k] ? "cylinder" : "box") + " of body '" + b +
                       "' is not supported (a cylinder touches spheres, capsules, soft bodies "
                       "and obstacles); exclude the pair (contact: exclude: [[" +
                       a + ", " + b + "]]) or give one of them spheres or capsules");
    }
  }
}

// The moving shapes (elements/shape_pair.h) as segments for the broad phase, and which two
// contact entities (a rod: its element capsules; a body: its spheres, capsules and boxes) may
// touch: their group bitmasks match, they are not excluded and not joined (a shared node or a
// joint between their nodes); a rod with itself when ContactSettings::self, skipping elements
// whose nearest ends are closer along the rod than self_skip. No pair of segments is listed
// here: the broad phase finds them per assembly (UpdateShapePairs), in time linear in the
// segments. r_min gets the smallest size and w_max the largest weight a pair can carry (the
// lighter side of the heaviest pair) for the law's defaults.
void BuildContactSegments(Model& m, double* r_min, double* w_max) {
  m.contact_segments.clear();
  m.contact_entity_pairs.Reset(0);
  m.contact_entity_self_skip.clear();
  m.num_contact_entities = 0;
  const ContactSettings& law = m.contact;
  if (!std::isfinite(law.self_skip) || law.self_skip == 0.0)
    throw InputError("contact: self_skip must be positive (or left to its default)");
  const std::vector<ContactEntity> entities = ListContactEntities(m);
  CheckPairExclusions(m);
  const int ne = static_cast<int>(entities.size());
  m.num_contact_entities = ne;
  m.contact_entity_pairs.Reset(ne);
  m.contact_entity_self_skip.assign(static_cast<std::size_t>(ne), -1.0);
  const EntitySizes sizes = AddContactSegments(m, entities);
  PairContactEntities(m, entities, sizes, r_min, w_max);
  CheckCylinderPairs(m, entities);
}

// ---- Validation -----------------------------------------------------------------------------

void ValidateContactRods(const Model& m) {
  for (std::size_t i = 0; i < m.contact_rods.size(); ++i) {
    const ContactRod& c = m.contact_rods[i];
    const EntityRef entity{EntityKind::kContactRod, static_cast<int>(i), {}};
    if (c.rod < 0 || c.rod >= static_cast<int>(m.rods.size()))
      throw InputError("contact rod " + std::to_string(i) + ": no rod " + std::to_string(c.rod),
                       entity);
    if (!IsPositiveSize(c.radius))
      throw InputError("contact of rod '" + m.rods[static_cast<std::size_t>(c.rod)].name +
                           "': the contact radius must be positive, got " +
                           std::to_string(c.radius),
                       entity);
  }
}

void ValidateContactShapes(const Model& m) {
  for (std::size_t i = 0; i < m.contact_shapes.size(); ++i) {
    const ContactShape& c = m.contact_shapes[i];
    const EntityRef entity{EntityKind::kContactShape, static_cast<int>(i), {}};
    if (c.body < 0 || c.body >= static_cast<int>(m.bodies.size()))
      throw InputError("contact shape " + std::to_string(i) + ": no body " + std::to_string(c.body),
                       entity);
    const std::string label =
        "contact shape of body '" + m.bodies[static_cast<std::size_t>(c.body)].name + "'";
    if (!c.from.allFinite() || !c.to.allFinite())
      throw InputError(label + ": points and sizes must be finite", entity);
    if (c.type == ContactShapeType::kBox ? !(c.to.minCoeff() > 0.0) : !IsPositiveSize(c.radius))
      throw InputError(
          label + (c.type == ContactShapeType::kBox ? ": the half sizes must be positive"
                                                    : ": the radius must be positive"),
          entity);
    if (c.type == ContactShapeType::kCylinder && !((c.to - c.from).norm() > 0.0))
      throw InputError(label + ": the cylinder's axis ends must differ", entity);
    if (!IsRotation(c.rotation))
      throw InputError(label + ": the orientation must be a rotation", entity);
  }
}

// Obstacles: finite, a non-zero plane normal (normalised here) or a positive radius, unique
// names.
void ValidateObstacles(Model& m) {
  std::set<std::string> names;
  for (std::size_t i = 0; i < m.obstacles.size(); ++i) {
    ContactObstacle& o = m.obstacles[i];
    const EntityRef entity{EntityKind::kObstacle, static_cast<int>(i), {}};
    const std::string label = "obstacle '" + o.name + "'";
    if (!o.point.allFinite() || !o.normal.allFinite() || !o.to.allFinite())
      throw InputError(label + ": points and normal must be finite", entity);
    if (o.type == ObstacleType::kPlane) {
      if (!(o.normal.norm() > 0.0))
        throw InputError(label + ": the plane normal must not be zero", entity);
      o.normal.normalize();
    } else if (o.type == ObstacleType::kBox) {
      if (!(o.to.minCoeff() > 0.0))
        throw InputError(label + ": the half sizes must be positive", entity);
      if (!IsRotation(o.rotation))
        throw InputError(label + ": the orientation must be a rotation", entity);
    } else if (o.type == ObstacleType::kMesh || o.type == ObstacleType::kHeightfield) {
      // docs/numerics.md, "Triangle meshes": the world triangles and their tree, built once.
      if (!o.mesh) throw InputError(label + ": the mesh has no triangles", entity);
      const std::string why = CheckTriangleMesh(*o.mesh, label);
      if (!why.empty()) throw InputError(why, entity);
      if (!IsPositiveSize(o.scale))
        throw InputError(label + ": the scale must be positive and finite", entity);
      if (!IsRotation(o.rotation))
        throw InputError(label + ": the orientation must be a rotation", entity);
      auto tree = std::make_shared<MeshTree>();
      tree->Build(*o.mesh, o.rotation, o.point, o.scale);
      o.tree = std::move(tree);
    } else if (!IsPositiveSize(o.radius)) {
      throw InputError(label + ": the radius must be positive, got " + std::to_string(o.radius),
                       entity);
    } else if (o.type == ObstacleType::kCylinder && !((o.to - o.point).norm() > 0.0)) {
      throw InputError(label + ": the cylinder's axis ends must differ", entity);
    }
    if (o.moving() && o.type != ObstacleType::kPlane)
      throw InputError(label + ": only a plane has a moving surface (velocity, spin)", entity);
    if (!o.velocity.allFinite() || !std::isfinite(o.spin))
      throw InputError(label + ": the surface velocity and spin must be finite", entity);
    if (o.type == ObstacleType::kPlane) o.velocity -= o.normal * o.normal.dot(o.velocity);
    if (!o.name.empty() && !names.insert(o.name).second)
      throw InputError("duplicate obstacle name '" + o.name + "'", entity);
  }
}

// The law: friction and damping ratio finite and >= 0; stiffness, onset and slip velocity
// positive or negative (left to their defaults).
void ValidateContactLaw(const Model& m) {
  const ContactSettings& law = m.contact;
  if (!(law.friction >= 0.0) || !std::isfinite(law.friction))
    throw InputError("contact: the friction coefficient must be finite and >= 0, got " +
                     std::to_string(law.friction));
  if (!(law.damping_ratio >= 0.0) || !std::isfinite(law.damping_ratio))
    throw InputError("contact: the damping ratio must be finite and >= 0");
  for (double v : {law.stiffness, law.onset, law.slip_velocity, law.tangential_stiffness})
    if (!std::isfinite(v) || v == 0.0)
      throw InputError(
          "contact: stiffness, onset, slip velocity and tangential stiffness must be positive "
          "(or left to their defaults)");
  if (!IsEnumValue(law.friction_law))
    throw InputError("contact: the friction law must be 'stick' or 'smooth'");
  if (!std::isfinite(law.static_friction) ||
      (law.static_friction >= 0.0 && law.static_friction < law.friction))
    throw InputError(
        "contact: the static friction coefficient must be >= the friction (mu_s >= "
        "mu_k), got " +
        std::to_string(law.static_friction) + " < " + std::to_string(law.friction));
}

// ---- Pairs of a moving shape and an obstacle ------------------------------------------------

bool ObstacleExcluded(const Model& m, bool rod, int index, int obstacle) {
  for (const ContactExclusion& e : m.contact_exclusions)
    if (e.rod == rod && e.index == index && e.obstacle == obstacle) return true;
  return false;
}

// Whether a rod or body may touch obstacle oi: the group bitmasks match and it is not excluded.
bool MayTouchObstacle(const Model& m, int oi, bool rod, int index) {
  const ContactObstacle& o = m.obstacles[static_cast<std::size_t>(oi)];
  const ContactGroup g = ContactGroupOf(m, rod, index);
  return ((g.contype & o.conaffinity) | (o.contype & g.conaffinity)) != 0u &&
         !ObstacleExcluded(m, rod, index, oi);
}

// A contact rod against obstacle oi: its node spheres against a plane, its element capsules
// against curved obstacles; each pair's mass (for the damping) into `masses`.
void AddRodObstaclePairs(Model& m, const ContactRod& c, int oi, double* r_min,
                         std::vector<double>* masses) {
  const bool plane = m.obstacles[static_cast<std::size_t>(oi)].type == ObstacleType::kPlane;
  const Rod& rod = m.rods[static_cast<std::size_t>(c.rod)];
  const double rho_a = rod.section.inertia(0);
  *r_min = std::min(*r_min, c.radius);
  if (plane) {
    // Node spheres (a chord's closest point to a plane is an end).
    for (std::size_t k = 0; k < rod.nodes.size(); ++k) {
      const int node = rod.nodes[k];
      if (m.nodes[static_cast<std::size_t>(node)].fixed) continue;
      double length = 0.0;
      if (k > 0)
        length +=
            0.5 * m.elements[static_cast<std::size_t>(rod.first_element + static_cast<int>(k) - 1)]
                      .length;
      if (k + 1 < rod.nodes.size())
        length +=
            0.5 *
            m.elements[static_cast<std::size_t>(rod.first_element + static_cast<int>(k))].length;
      ContactPair p;
      p.node[0] = node;
      p.radius = c.radius;
      p.obstacle = oi;
      p.rod = true;
      p.owner = c.rod;
      m.contact_pairs.push_back(p);
      masses->push_back(rho_a * length);
    }
  } else {
    for (int e = rod.first_element; e < rod.first_element + rod.num_elements; ++e) {
      const RodElement& el = m.elements[static_cast<std::size_t>(e)];
      ContactPair p;
      p.node[0] = el.node_a;
      p.node[1] = el.node_b;
      p.end_node[1] = 1;
      p.radius = c.radius;
      p.obstacle = oi;
      p.rod = true;
      p.owner = c.rod;
      m.contact_pairs.push_back(p);
      masses->push_back(rho_a * el.length);
    }
  }
}

// A body's contact shape against obstacle oi (none when the body's node is fixed); each pair's
// mass, the body's, into `masses`.
void AddShapeObstaclePairs(Model& m, const ContactShape& c, int oi, double* r_min,
                           std::vector<double>* masses) {
  const bool plane = m.obstacles[static_cast<std::size_t>(oi)].type == ObstacleType::kPlane;
  const RigidBody& body = m.bodies[static_cast<std::size_t>(c.body)];
  if (m.nodes[static_cast<std::size_t>(body.node)].fixed) return;
  auto add = [&](const Vec3& a, const Vec3& b, double radius) {
    ContactPair p;
    p.node[0] = body.node;
    p.offset[0] = a;
    p.offset[1] = b;
    p.radius = radius;
    p.obstacle = oi;
    p.owner = c.body;
    m.contact_pairs.push_back(p);
    masses->push_back(body.mass);
  };
  switch (c.type) {
    case ContactShapeType::kSphere:
      *r_min = std::min(*r_min, c.radius);
      add(c.from, c.from, c.radius);
      break;
    case ContactShapeType::kCapsule:
      *r_min = std::min(*r_min, c.radius);
      if (plane) {
        add(c.from, c.from, c.radius);
        add(c.to, c.to, c.radius);
      } else {
        add(c.from, c.to, c.radius);
      }
      break;
    case ContactShapeType::kCylinder: {
      // docs/numerics.md, "Cylinders": against a plane, three rim points of each flat end;
      // against a sphere or capsule, the cylinder's point nearest to it.
      *r_min = std::min(*r_min, c.radius);
      const ObstacleType type = m.obstacles[static_cast<std::size_t>(oi)].type;
      if (type == ObstacleType::kCylinder || type == ObstacleType::kBox ||
          type == ObstacleType::kMesh || type == ObstacleType::kHeightfield)
        throw InputError("contact between the cylinder of body '" + body.name + "' and the " +
                         NameOf(type) + " obstacle '" +
                         m.obstacles[static_cast<std::size_t>(oi)].name +
                         "' is not supported (a cylinder touches planes, spheres and capsules); "
                         "exclude the pair (contact: exclude: [[" +
                         body.name + ", " + m.obstacles[static_cast<std::size_t>(oi)].name + "]])");
      for (int part = 0; part < (plane ? 6 : 1); ++part) {
        add(c.from, c.to, 0.0);
        m.contact_pairs.back().cylinder = c.radius;
        m.contact_pairs.back().part = plane ? part : -1;
      }
      break;
    }
    case ContactShapeType::kBox: {
      // docs/numerics.md, "Contact": 8 vertex spheres and (against curved obstacles) 12 edge
      // capsules, of radius 0, at the box's orientation.
      *r_min = std::min(*r_min, c.to.minCoeff());
      const ObstacleType type = m.obstacles[static_cast<std::size_t>(oi)].type;
      if (type == ObstacleType::kMesh || type == ObstacleType::kHeightfield)
        throw InputError("contact between the box of body '" + body.name + "' and the " +
                         NameOf(type) + " obstacle '" +
                         m.obstacles[static_cast<std::size_t>(oi)].name +
                         "' is not supported (a mesh touches rods, spheres and capsules); "
                         "exclude the pair (contact: exclude: [[" +
                         body.name + ", " + m.obstacles[static_cast<std::size_t>(oi)].name + "]])");
      Vec3 v[8];
      for (int k = 0; k < 8; ++k) v[k] = c.from + c.rotation * BoxCorner(Vec3::Zero(), c.to, k);
      for (int k = 0; k < 8; ++k) add(v[k], v[k], 0.0);
      if (!plane)
        for (int k = 0; k < 8; ++k)
          for (int bit : {1, 2, 4})
            if (!(k & bit)) add(v[k], v[k | bit], 0.0);
      break;
    }
  }
}

// The number of pairs AddRodObstaclePairs and AddShapeObstaclePairs make for obstacle oi.
double CountObstaclePairs(const Model& m, int oi) {
  const bool plane = m.obstacles[static_cast<std::size_t>(oi)].type == ObstacleType::kPlane;
  double count = 0.0;
  for (const ContactRod& c : m.contact_rods) {
    if (!MayTouchObstacle(m, oi, true, c.rod)) continue;
    const Rod& rod = m.rods[static_cast<std::size_t>(c.rod)];
    if (!plane) {
      count += rod.num_elements;
      continue;
    }
    for (int node : rod.nodes) count += m.nodes[static_cast<std::size_t>(node)].fixed ? 0.0 : 1.0;
  }
  for (const ContactShape& c : m.contact_shapes) {
    if (!MayTouchObstacle(m, oi, false, c.body)) continue;
    if (m.nodes[static_cast<std::size_t>(m.bodies[static_cast<std::size_t>(c.body)].node)].fixed)
      continue;
    switch (c.type) {
      case ContactShapeType::kSphere:
        count += 1;
        break;
      case ContactShapeType::kCapsule:
        count += plane ? 2 : 1;
        break;
      case ContactShapeType::kBox:
        count += plane ? 8 : 20;
        break;
      case ContactShapeType::kCylinder:
        count += plane ? 6 : 1;
        break;
    }
  }
  return count;
}

// The pairs of moving shapes and obstacles, before they are made: at most kMaxObstaclePairs
// (every pair is tested at every assembly), within the memory limit.
void CheckObstaclePairs(const Model& m) {
  if (m.obstacles.empty()) return;
  double count = 0.0;
  for (int oi = 0; oi < static_cast<int>(m.obstacles.size()); ++oi)
    count += CountObstaclePairs(m, oi);
  const std::string hint =
      "Exclude the shapes that cannot reach an obstacle (contact: exclude: [[body, obstacle]], "
      "or the contype and conaffinity bitmasks), or use fewer obstacles or rod elements";
  char why[256];
  std::snprintf(why, sizeof why,
                "%.0f pairs: every contact shape (a rod element or node, a body's shape) "
                "against each of the %zu obstacles",
                count, m.obstacles.size());
  if (count > kMaxObstaclePairs) {
    char head[256];
    std::snprintf(head, sizeof head,
                  "contact: the moving shapes and obstacles make %.0f pairs, more than %.0f "
                  "(the limit: every pair is tested at every assembly)",
                  count, kMaxObstaclePairs);
    throw InputError(std::string(head) + ". " + hint);
  }
  CheckMemory({{"pairs of moving shapes and obstacles",
                count * static_cast<double>(sizeof(ContactPair) + sizeof(double)), why}},
              m.memory_limit, "contact with obstacles", hint);
}

// Defaults (docs/numerics.md, "Contact") and the damping of each pair.
void ResolveContactLaw(Model& m, const std::vector<double>& masses, double r_min, double w_max) {
  ContactSettings& law = m.contact;
  const double gravity = ContactGravity(m);
  for (double mass : masses) w_max = std::max(w_max, mass * gravity);
  if (law.onset < 0.0) law.onset = std::isfinite(r_min) ? 0.01 * r_min : 1e-4;
  if (law.stiffness < 0.0) law.stiffness = w_max > 0.0 ? 100.0 * w_max / law.onset : 1e6;
  if (law.slip_velocity < 0.0) law.slip_velocity = 1e-3;
  ResolveMaterials(m);
  for (std::size_t i = 0; i < m.contact_pairs.size(); ++i) {
    ContactPair& p = m.contact_pairs[i];
    p.material = ContactLawIndex(m, MaterialGroupOf(m, p.rod, p.owner),
                                 ObstacleMaterialGroup(m, p.obstacle));
    const ContactMaterial& pl = m.contact_laws[static_cast<std::size_t>(p.material)];
    p.damping = 2.0 * pl.damping_ratio * std::sqrt(pl.stiffness * std::max(masses[i], 0.0));
  }
}

}  // namespace

// Contact (docs/numerics.md, "Contact"): validates shapes, obstacles and the law, enumerates the
// (moving shape, obstacle) pairs and resolves the defaults (model.h, ContactSettings).
void BuildContacts(Model& m) {
  m.contact_pairs.clear();
  ValidateContactRods(m);
  ValidateContactShapes(m);
  ValidateObstacles(m);
  ValidateContactLaw(m);
  CheckMaterialGroups(m);
  CheckMaterials(m);
  // Pairs: each moving shape against each obstacle it may touch; counted before they are made.
  CheckObstaclePairs(m);
  double r_min = INFINITY, w_max = 0.0;
  std::vector<double> masses;  // per pair, for the damping
  for (int oi = 0; oi < static_cast<int>(m.obstacles.size()); ++oi) {
    for (const ContactRod& c : m.contact_rods)
      if (MayTouchObstacle(m, oi, true, c.rod)) AddRodObstaclePairs(m, c, oi, &r_min, &masses);
    for (const ContactShape& c : m.contact_shapes)
      if (MayTouchObstacle(m, oi, false, c.body)) AddShapeObstaclePairs(m, c, oi, &r_min, &masses);
  }
  BuildContactSegments(m, &r_min, &w_max);
  ResolveContactLaw(m, masses, r_min, w_max);
}

}  // namespace screwfem::build_steps
