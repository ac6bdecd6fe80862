// Typed ids at the builder's API (model/ids.h, build/model_builder.h): the compile-time checks
// are static_asserts (a call that passes a node where a body is expected is not invocable), the
// run-time ones the ids the builder hands out.
#include <gtest/gtest.h>

#include <string>
#include <type_traits>
#include <unordered_set>
#include <utility>

#include "screwfem/build/model_builder.h"

namespace screwfem {
namespace {

// Zero cost: one int, copied as one.
static_assert(sizeof(NodeId) == sizeof(int) && std::is_trivially_copyable_v<NodeId>);
// Explicit from int, never implicit; no id from an id of another kind, explicitly either.
static_assert(std::is_constructible_v<NodeId, int> && !std::is_convertible_v<int, NodeId>);
static_assert(!std::is_convertible_v<NodeId, BodyId> && !std::is_constructible_v<BodyId, NodeId>);
static_assert(!std::is_convertible_v<RodId, NodeId> && !std::is_constructible_v<NodeId, RodId>);
static_assert(!std::is_constructible_v<JointId, TendonId>);
// An id reads as its int (Model arrays and item fields stay int).
static_assert(std::is_convertible_v<NodeId, int>);
// kGround is a node, and no other kind of id.
static_assert(std::is_convertible_v<GroundNode, NodeId> &&
              !std::is_convertible_v<GroundNode, BodyId>);
static_assert(NodeId(kGround).value() == -1 && !NodeId().valid() && NodeId(0).valid());

// Ids of two kinds are not compared.
template <class A, class B, class = void>
struct Comparable : std::false_type {};
template <class A, class B>
struct Comparable<A, B, std::void_t<decltype(std::declval<A>() == std::declval<B>())>>
    : std::true_type {};
static_assert(Comparable<NodeId, NodeId>::value && !Comparable<NodeId, BodyId>::value &&
              !Comparable<RodId, BodyId>::value);

// Passing a node where a body or rod is expected does not compile (and vice versa).
template <class... Args>
constexpr bool kCanAddRigidBody =
    std::is_invocable_v<decltype(&ModelBuilder::AddRigidBody), ModelBuilder&, std::string, Args...>;
static_assert(kCanAddRigidBody<NodeId, double, Vec3, Mat3>);
static_assert(!kCanAddRigidBody<BodyId, double, Vec3, Mat3>);
static_assert(!kCanAddRigidBody<RodId, double, Vec3, Mat3>);
static_assert(!kCanAddRigidBody<int, double, Vec3, Mat3>);
static_assert(std::is_invocable_v<decltype(&ModelBuilder::FixNode), ModelBuilder&, NodeId>);
static_assert(!std::is_invocable_v<decltype(&ModelBuilder::FixNode), ModelBuilder&, BodyId>);
static_assert(!std::is_invocable_v<decltype(&ModelBuilder::FixNode), ModelBuilder&, int>);
static_assert(std::is_invocable_v<decltype(&ModelBuilder::RodLength), ModelBuilder&, RodId>);
static_assert(!std::is_invocable_v<decltype(&ModelBuilder::RodLength), ModelBuilder&, NodeId>);
static_assert(
    !std::is_invocable_v<decltype(&ModelBuilder::AddContactRod), ModelBuilder&, BodyId, double>);
static_assert(!std::is_assignable_v<NodeId&, BodyId> && !std::is_assignable_v<NodeId&, int>);
static_assert(std::is_assignable_v<NodeId&, GroundNode>);

TEST(TypedIds, BuilderHandsOutIdsInOrder) {
  ModelBuilder b;
  const NodeId n0 = b.AddNode(SE3::Identity(), "a");
  const NodeId n1 = b.AddNode(SE3::Translation(Vec3(1, 0, 0)), "b");
  EXPECT_EQ(n0.value(), 0);
  EXPECT_EQ(n1.index(), 1u);
  const BodyId body = b.AddRigidBody("body", n1, 1.0, Vec3::Zero(), Mat3::Identity());
  EXPECT_EQ(body.value(), 0);
  const RodId rod = b.AddStraightRod("rod", Vec3(0, 0, 0), Vec3(1, 0, 0), 2,
                                     Section::FromDiagonals(Vec6::Ones()), Vec3::UnitZ(), n0, n1);
  EXPECT_EQ(rod.value(), 0);
  const std::vector<NodeId> nodes = b.RodNodes(rod);
  ASSERT_EQ(nodes.size(), 3u);
  EXPECT_EQ(nodes.front(), n0);
  EXPECT_EQ(nodes.back(), n1);
  EXPECT_EQ(nodes[1].value(), 2);  // the rod's new middle node
  const JointId j = b.AddJointAt("pin", JointType::kRevolute, kGround, n0, Vec3::Zero());
  EXPECT_EQ(j.value(), 0);
  EXPECT_EQ(b.model().joints[j].node_a, kGround);
  EXPECT_EQ(b.model().joints[j].node_b, 0);
  EXPECT_EQ(b.FindNodeAt(Vec3(0.5, 0, 0), rod).node, nodes[1]);
  EXPECT_FALSE(b.FindNodeAt(Vec3(0.4, 0, 0), rod).node.valid());
}

TEST(TypedIds, HashAndOrder) {
  std::unordered_set<NodeId> set{NodeId(3), NodeId(1), NodeId(3)};
  EXPECT_EQ(set.size(), 2u);
  EXPECT_TRUE(set.count(NodeId(1)));
  EXPECT_LT(NodeId(1), NodeId(3));
  EXPECT_NE(NodeId(1), NodeId(3));
  EXPECT_EQ(NodeId(kGround), NodeId(-1));
}

TEST(TypedIds, RodNodesNamesAMissingRod) {
  ModelBuilder b;
  try {
    b.RodNodes(RodId(2));
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "RodNodes: no rod 2");
  }
}

}  // namespace
}  // namespace screwfem
