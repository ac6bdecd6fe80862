// The memory estimate and its limit (model/memory.h, docs/limits.md): sizes parsed and
// printed, the bytes of the banded LU estimated as Resize allocates them, Build refusing a
// model beyond the limit before allocating it (naming the part, its bytes and why), the cap on
// the pairs of moving shapes and obstacles, and the broad phase's pool stopping at its limit
// with a message.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "screwfem/assemble/assemble.h"
#include "screwfem/build/model_builder.h"
#include "screwfem/model/data.h"
#include "screwfem/model/errors.h"
#include "screwfem/model/memory.h"

namespace screwfem::memory_test {
namespace {

template <class F>
std::string ErrorOf(F f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

Section RodSection() {
  Section s;
  s.stiffness = Vec6::Constant(1e3);
  s.inertia = Vec6::Constant(1e-3);
  return s;
}

// A rod of n elements along x, clamped at its start.
ModelBuilder ClampedRod(int n, double length = 1.0) {
  ModelBuilder b;
  const RodId rod = b.AddStraightRod("arm", Vec3::Zero(), Vec3(length, 0, 0), n, RodSection());
  b.FixNode(b.RodNodes(rod).front());
  return b;
}

TEST(MemorySize, UnitsArePowersOf1024) {
  EXPECT_EQ(ParseMemorySize("8G", "x"), std::size_t{8} << 30);
  EXPECT_EQ(ParseMemorySize("512MiB", "x"), std::size_t{512} << 20);
  EXPECT_EQ(ParseMemorySize("1.5g", "x"), std::size_t{3} << 29);
  EXPECT_EQ(ParseMemorySize("12kb", "x"), std::size_t{12} << 10);
  EXPECT_EQ(ParseMemorySize("2T", "x"), std::size_t{2} << 40);
  EXPECT_EQ(ParseMemorySize("1000000", "x"), std::size_t{1000000});
  EXPECT_EQ(ParseMemorySize("100B", "x"), std::size_t{100});
  for (const char* bad : {"", "0", "-1", "8X", "G", "8 G", " 8G", "nan", "inf", "1e30T", "8GG"})
    EXPECT_EQ(ErrorOf([&] { ParseMemorySize(bad, "--max-memory"); }),
              std::string("--max-memory: expected a size such as 8G or 512M (K, M, G, T: powers "
                          "of 1024), got '") +
                  bad + "'")
        << bad;
}

TEST(MemorySize, BytesArePrintedInBinaryUnits) {
  EXPECT_EQ(FormatBytes(100), "100 B");
  EXPECT_EQ(FormatBytes(1536), "1.5 KiB");
  EXPECT_EQ(FormatBytes(60000.0 * 179998.0 * 8.0), "80.5 GiB");
  EXPECT_EQ(FormatBytes(std::ldexp(1.0, 40)), "1 TiB");
}

TEST(MemoryLimit, DefaultIsHalfThePhysicalMemoryUnlessSet) {
  const std::size_t physical = PhysicalMemoryBytes();
  ASSERT_GT(physical, 0u);
  EXPECT_EQ(ResolveMemoryLimit(0), static_cast<std::size_t>(0.5 * static_cast<double>(physical)));
  SetDefaultMemoryLimit(std::size_t{3} << 30);
  EXPECT_EQ(ResolveMemoryLimit(0), std::size_t{3} << 30);
  EXPECT_EQ(ResolveMemoryLimit(12345), 12345u);  // a model's own limit comes first
  SetDefaultMemoryLimit(0);
  EXPECT_EQ(ResolveMemoryLimit(0), static_cast<std::size_t>(0.5 * static_cast<double>(physical)));
}

TEST(MemoryEstimate, BandedFactorsAreWhatResizeAllocates) {
  const Model m = ClampedRod(200).Build();
  const std::vector<MemoryPart> parts = EstimateDataMemory(m);
  ASSERT_EQ(parts.size(), 2u);  // no contact: the LU and the state
  const double n = m.num_unknowns();
  // BandedLU::Resize: ldab = 2 kl + ku + 1 doubles per column (kl = ku = the bandwidth), and 52
  // bytes of pivots, inverse pivots and extents per column.
  EXPECT_EQ(parts[0].part, "banded LU factors of the iteration matrix");
  EXPECT_EQ(parts[0].bytes, n * (3.0 * m.bandwidth + 1.0) * 8.0 + 52.0 * n);
  EXPECT_EQ(parts[0].why,
            std::to_string(m.num_unknowns()) + " unknowns (nv = " + std::to_string(m.nv) +
                ", nc = " + std::to_string(m.nc) + ") x " + std::to_string(3 * m.bandwidth + 1) +
                " band entries (bandwidth " + std::to_string(m.bandwidth) + ": 3 x " +
                std::to_string(m.bandwidth) + " + 1) x 8 bytes");
  EXPECT_EQ(m.nv, 1200);
  EXPECT_EQ(m.bandwidth, 11);
}

TEST(MemoryEstimate, BuildRefusesAModelBeyondItsLimitNamingTheLargestPart) {
  ModelBuilder b = ClampedRod(200);
  const Model ok = b.Build();
  const std::vector<MemoryPart> parts = EstimateDataMemory(ok);
  b.SetMemoryLimit(static_cast<std::size_t>(TotalBytes(parts)));  // exactly enough
  EXPECT_NO_THROW(b.Build());
  b.SetMemoryLimit(static_cast<std::size_t>(TotalBytes(parts)) - 1);
  EXPECT_EQ(ErrorOf([&] { b.Build(); }),
            "the model's solver workspace needs about " + FormatBytes(TotalBytes(parts)) +
                ", more than the memory limit of " + FormatBytes(TotalBytes(parts) - 1) +
                " (set by ModelBuilder.set_memory_limit; --max-memory SIZE or max_memory= change "
                "it): the largest part is the banded LU factors of the iteration matrix, " +
                FormatBytes(parts[0].bytes) + " (" + parts[0].why +
                "). The band is the widest span of coupled unknowns in the solver's ordering "
                "(closed loops, tendons, force elements and contact between distant bodies "
                "widen it); fewer elements make fewer unknowns");
}

// A rod of `elements` against `obstacles` sphere obstacles beside it.
ModelBuilder RodAndSphereObstacles(int elements, int obstacles) {
  ModelBuilder b = ClampedRod(elements, 100.0);
  b.AddContactRod(RodId(0), 0.01);
  for (int i = 0; i < obstacles; ++i) {
    ContactObstacle o;
    o.type = ObstacleType::kSphere;
    o.name = "o" + std::to_string(i);
    o.point = Vec3(0.1 * i, 1.0, 0.0);
    o.radius = 0.05;
    b.AddObstacle(o);
  }
  return b;
}

TEST(MemoryEstimate, ObstaclePairsAreCountedBeforeTheyAreMade) {
  // 100,000 elements against 101 curved obstacles: 10,100,000 pairs, over kMaxObstaclePairs
  // (1000 obstacles: 1e8 pairs, 11 GB, took `check` 66 s before running out of memory).
  EXPECT_EQ(ErrorOf([] { RodAndSphereObstacles(100000, 101).Build(); }),
            "contact: the moving shapes and obstacles make 10100000 pairs, more than 10000000 "
            "(the limit: every pair is tested at every assembly). Exclude the shapes that cannot "
            "reach an obstacle (contact: exclude: [[body, obstacle]], or the contype and "
            "conaffinity bitmasks), or use fewer obstacles or rod elements");
  // Below the cap, the memory limit: 1000 elements x 10 obstacles.
  ModelBuilder b = RodAndSphereObstacles(1000, 10);
  EXPECT_EQ(b.Build().contact_pairs.size(), 10000u);
  b.SetMemoryLimit(100000);
  const double bytes = 10000.0 * (sizeof(ContactPair) + sizeof(double));
  EXPECT_EQ(ErrorOf([&] { b.Build(); }),
            "contact with obstacles needs about " + FormatBytes(bytes) +
                ", more than the memory limit of 97.7 KiB (set by "
                "ModelBuilder.set_memory_limit; --max-memory SIZE or max_memory= change it): the "
                "largest part is the pairs of moving shapes and obstacles, " +
                FormatBytes(bytes) +
                " (10000 pairs: every contact shape (a rod element or node, a body's shape) "
                "against each of the 10 obstacles). Exclude the shapes that cannot reach an "
                "obstacle (contact: exclude: [[body, obstacle]], or the contype and conaffinity "
                "bitmasks), or use fewer obstacles or rod elements");
}

// `count` free spheres of radius 0.05 whose centres are within 1 mm of the origin: every two
// overlap.
ModelBuilder OverlappingSpheres(int count) {
  ModelBuilder b;
  for (int i = 0; i < count; ++i) {
    const Vec3 c(1e-3 * std::cos(i), 1e-3 * std::sin(i), 0.0);
    const NodeId node = b.AddNode(SE3::Translation(c), "s" + std::to_string(i));
    b.AddRigidBody("s" + std::to_string(i), node, 0.1, Vec3::Zero(), 1e-4 * Mat3::Identity());
    ContactShape shape;
    shape.body = i;
    shape.type = ContactShapeType::kSphere;
    shape.radius = 0.05;
    b.AddContactShape(shape);
  }
  return b;
}

TEST(ShapePairPool, StopsAtItsLimitAndTheAssemblySaysWhy) {
  const Model free_model = OverlappingSpheres(20).Build();
  Data data = MakeData(free_model);
  ASSERT_TRUE(Assemble(free_model, data, {}));
  EXPECT_EQ(data.num_shape_pairs, 190);  // 20 x 19 / 2
  EXPECT_FALSE(data.shape_pair_limit_reached);
  // A limit that leaves the pool no room beyond the one MakeData allocates (4 x 20 + 64).
  ModelBuilder b = OverlappingSpheres(20);
  b.SetMemoryLimit(static_cast<std::size_t>(TotalBytes(EstimateDataMemory(free_model))) + 1000);
  const Model tight = b.Build();
  EXPECT_EQ(ShapePairPoolLimit(tight), 144u);
  Data d = MakeData(tight);
  EXPECT_FALSE(Assemble(tight, d, {}));
  EXPECT_TRUE(d.shape_pair_limit_reached);
  EXPECT_EQ(d.shape_pairs.size(), 144u);
  EXPECT_EQ(ShapePairLimitMessage(tight),
            "the broad phase found more than 144 pairs of moving shapes near each other (the "
            "limit: at most 2000000, and " +
                FormatBytes(144.0 * sizeof(ShapePair)) +
                " within the memory limit); a smaller contact onset, a larger self_skip or "
                "fewer, longer elements make fewer pairs");
}

TEST(BandContactLinks, ManyEntitiesThatMayTouchStayOffTheBand) {
  // 1000 spheres: 499,500 node pairs linked in the band (below kMaxBandContactLinks): a band
  // over all of them.
  const Model linked = OverlappingSpheres(1000).Build();
  EXPECT_EQ(linked.bandwidth, 5999);
  EXPECT_TRUE(linked.warnings.empty());
  // 1500 spheres: 1,124,250, more than 1e6: none is, the band is a body's own. The banded LU
  // warns; auto takes the sparse LU (1500 nodes may be coupled off the band, more than the
  // Woodbury coupling's 128), whose pattern takes the pairs that touch, without a warning.
  ModelBuilder banded = OverlappingSpheres(1500);
  banded.SetLinearSolver(LinearSolver::kBanded);
  const Model apart = banded.Build();
  EXPECT_FALSE(apart.sparse_solver);
  EXPECT_EQ(apart.bandwidth, 5);
  ASSERT_EQ(apart.warnings.size(), 1u);
  EXPECT_EQ(apart.warnings[0],
            "the 1124250 pairs of contact entities that may touch would couple 1124250 node "
            "pairs in the solver's band (more than 1000000): they are left off the band, and "
            "those that touch enter the solve as the off-band coupling (at most 128 nodes at a "
            "time)");
  const Model sparse = OverlappingSpheres(1500).Build();
  EXPECT_TRUE(sparse.sparse_solver);
  EXPECT_TRUE(sparse.warnings.empty());
  // Its base pattern is the bodies' own blocks (the contact pairs enter at run time).
  EXPECT_EQ(sparse.sparse_pattern.size(), 1500u);
}

// Which two contact entities may touch (Model::contact_entity_pairs): the group bits and the
// pairs set apart (excluded, joined), against the rule applied pair by pair; memory linear in
// the entities (a byte per ordered pair made 100 MB for 10,000 spheres).
TEST(ContactEntityPairs, GroupBitsAndPairsSetApartInMemoryLinearInTheEntities) {
  const int n = 12;
  ModelBuilder b = OverlappingSpheres(n);
  const unsigned type[n] = {1, 1, 2, 2, 4, 1, 3, 0, 1, 2, 1, 1};
  const unsigned affinity[n] = {1, 2, 1, 4, 2, 0, 1, 3, 1, 1, 1, 1};
  for (int i = 0; i < n; ++i) b.SetContactGroup(BodyId(i), type[i], affinity[i]);
  b.ExcludeContactPair(BodyId(0), BodyId(1));
  b.ExcludeContactPair(BodyId(8), BodyId(3));
  b.ExcludeContactPair(BodyId(4), BodyId(7));  // bits that do not match anyway
  // Joined: a joint between the nodes of 10 and 11.
  b.AddJointAt("j", JointType::kSpherical, NodeId(10), NodeId(11), Vec3::Zero());
  const Model m = b.Build();
  const ContactEntityPairs& t = m.contact_entity_pairs;
  ASSERT_EQ(t.size(), n);
  double pairs = 0.0;
  for (int i = 0; i < n; ++i)
    for (int k = 0; k < n; ++k) {
      if (i == k) continue;
      const int lo = std::min(i, k), hi = std::max(i, k);
      const bool apart = (lo == 0 && hi == 1) || (lo == 3 && hi == 8) || (lo == 10 && hi == 11);
      const bool bits = ((type[i] & affinity[k]) | (type[k] & affinity[i])) != 0u;
      EXPECT_EQ(t.MayTouch(i, k), bits && !apart) << i << " " << k;
      if (i < k && bits && !apart) pairs += 1.0;
    }
  EXPECT_EQ(t.pairs(), pairs);
  EXPECT_TRUE(MayHaveShapePairs(m));
  // 3000 spheres that may all touch: the model holds a few bytes per sphere for it, not
  // 3000 (a byte per ordered pair), and the model's estimate is linear in them.
  const Model many = OverlappingSpheres(3000).Build();
  EXPECT_EQ(many.contact_entity_pairs.pairs(), 3000.0 * 2999.0 / 2.0);
  EXPECT_LE(many.contact_entity_pairs.bytes(), 3000u * 2u * sizeof(unsigned) + 64u);
  const double per_sphere = EstimateModelMemory(many).bytes / 3000.0;
  const double per_sphere_small =
      EstimateModelMemory(OverlappingSpheres(300).Build()).bytes / 300.0;
  EXPECT_LT(per_sphere, 1.2 * per_sphere_small) << per_sphere << " " << per_sphere_small;
  // None may touch: no pairs, and the broad phase has nothing to find.
  ModelBuilder none = OverlappingSpheres(3);
  for (int i = 0; i < 3; ++i) none.SetContactGroup(BodyId(i), 1u, 2u);
  const Model apart = none.Build();
  EXPECT_FALSE(apart.contact_entity_pairs.any());
  EXPECT_FALSE(MayHaveShapePairs(apart));
}

}  // namespace
}  // namespace screwfem::memory_test
