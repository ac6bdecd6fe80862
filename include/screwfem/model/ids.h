// Typed ids: what ModelBuilder hands out and takes (build/model_builder.h). An Id<Tag> is an
// int index into one of the Model's arrays that knows which array: a NodeId where a BodyId is
// expected does not compile, nor does an int where any id is expected; an id reads as its int
// (implicitly, as Drake's TypeSafeIndex does, so model.nodes[node] and the int fields of the
// Model's items take it), and value() and index() say so explicitly. Zero cost: one int.
// Inside the Model the arrays and item fields stay int (docs/architecture.md, "Typed ids").
#pragma once

#include <cstddef>
#include <functional>
#include <type_traits>

namespace screwfem {

// The world frame where a node is expected: converts to the node index -1 (the Model's items
// and kernels compare their int node fields with it) and to a NodeId (ModelBuilder's joint
// sides and contact pairs), but to no other id.
struct GroundNode {
  constexpr operator int() const { return -1; }  // NOLINT(google-explicit-constructor)
};
inline constexpr GroundNode kGround{};

template <typename Tag>
class Id {
 public:
  // An invalid id (-1): FindNodeAt's node when none is within the tolerance.
  constexpr Id() = default;
  constexpr explicit Id(int value) : value_(value) {}
  // Only a NodeId is constructed from kGround.
  template <typename T = Tag, std::enable_if_t<T::kTakesGround, int> = 0>
  constexpr Id(GroundNode) : value_(-1) {}  // NOLINT(google-explicit-constructor)
  // No id from another kind of id (explicitly either).
  template <typename Other, std::enable_if_t<!std::is_same_v<Other, Tag>, int> = 0>
  Id(Id<Other>) = delete;

  constexpr int value() const { return value_; }
  constexpr std::size_t index() const { return static_cast<std::size_t>(value_); }
  constexpr bool valid() const { return value_ >= 0; }
  constexpr operator int() const { return value_; }  // NOLINT(google-explicit-constructor)

  friend constexpr bool operator==(Id a, Id b) { return a.value_ == b.value_; }
  friend constexpr bool operator!=(Id a, Id b) { return a.value_ != b.value_; }
  friend constexpr bool operator<(Id a, Id b) { return a.value_ < b.value_; }
  friend constexpr bool operator<=(Id a, Id b) { return a.value_ <= b.value_; }
  friend constexpr bool operator>(Id a, Id b) { return a.value_ > b.value_; }
  friend constexpr bool operator>=(Id a, Id b) { return a.value_ >= b.value_; }
  // Ids of two kinds are not compared (both would otherwise read as ints).
  template <typename Other, std::enable_if_t<!std::is_same_v<Other, Tag>, int> = 0>
  bool operator==(Id<Other>) const = delete;
  template <typename Other, std::enable_if_t<!std::is_same_v<Other, Tag>, int> = 0>
  bool operator!=(Id<Other>) const = delete;

 private:
  int value_ = -1;
};

struct NodeTag {
  static constexpr bool kTakesGround = true;
};
#define SCREWFEM_ID_TAG(Name)                   \
  struct Name##Tag {                            \
    static constexpr bool kTakesGround = false; \
  }
SCREWFEM_ID_TAG(Rod);
SCREWFEM_ID_TAG(Body);
SCREWFEM_ID_TAG(Joint);
SCREWFEM_ID_TAG(Tendon);
SCREWFEM_ID_TAG(ForceElement);
SCREWFEM_ID_TAG(Actuator);
SCREWFEM_ID_TAG(PointLoad);
SCREWFEM_ID_TAG(RodLoad);
SCREWFEM_ID_TAG(Input);
SCREWFEM_ID_TAG(ContactRod);
SCREWFEM_ID_TAG(ContactShape);
SCREWFEM_ID_TAG(Obstacle);
#undef SCREWFEM_ID_TAG

using NodeId = Id<NodeTag>;                  // Model::nodes (or kGround where allowed)
using RodId = Id<RodTag>;                    // Model::rods
using BodyId = Id<BodyTag>;                  // Model::bodies (rigid bodies)
using JointId = Id<JointTag>;                // Model::joints
using TendonId = Id<TendonTag>;              // Model::tendons
using ForceElementId = Id<ForceElementTag>;  // Model::force_elements
using ActuatorId = Id<ActuatorTag>;          // Model::actuators
using PointLoadId = Id<PointLoadTag>;        // Model::point_loads
using RodLoadId = Id<RodLoadTag>;            // Model::rod_loads
using InputId = Id<InputTag>;                // Model::inputs (Profile::Input takes it)
using ContactRodId = Id<ContactRodTag>;      // Model::contact_rods
using ContactShapeId = Id<ContactShapeTag>;  // Model::contact_shapes
using ObstacleId = Id<ObstacleTag>;          // Model::obstacles

}  // namespace screwfem

template <typename Tag>
struct std::hash<screwfem::Id<Tag>> {
  std::size_t operator()(screwfem::Id<Tag> id) const noexcept {
    return std::hash<int>()(id.value());
  }
};
