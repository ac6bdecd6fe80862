// Conforming rod meshes (ModelBuilder::SetConformMesh, Model::conform_mesh; docs/numerics.md,
// "Conforming rod meshes"): Build puts a node wherever a tendon eyelet, a force element's end,
// a concentrated rod load or an actuator's end falls inside an element. Checks:
//  * the nodes: appended after the given ones (NodeIds and RodNodes stay valid), on the
//    element's helix at the feature's arc length, the features then on nodes; off: as given;
//  * closed forms that a conforming mesh reproduces exactly: a concentrated moment between
//    nodes (an arc up to it, straight beyond; without, the strain of the element holding it
//    never converges) and a rest curvature over an arc-length range whose ends are between
//    nodes (previously an error);
//  * the tendon case of issue 40 (a cantilever, 5 eyelets at an offset, the last 4 between the
//    original nodes of every mesh, the tendon ending at the last): the tip and the strains at
//    the element stations converge at second order with the mesh conforming; without, the tip
//    converges with a larger error and the strain of the elements holding eyelets not at all.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "screwfem/build/model_builder.h"
#include "screwfem/elements/tendon.h"
#include "screwfem/model/data.h"
#include "screwfem/solve/statics.h"

namespace screwfem::conform_mesh_test {
namespace {

constexpr double kEA = 1e5, kEI = 1.0;

Section RodSection() {
  return Section::FromDiagonals((Vec6() << kEA, kEA, kEA, kEI, kEI, kEI).finished());
}

TEST(ConformMesh, FeaturesBetweenNodesBecomeNodesOnTheElementsHelix) {
  Model original;  // conform_mesh off
  for (bool conform : {false, true}) {
    SCOPED_TRACE(conform);
    ModelBuilder b;
    b.SetConformMesh(conform);
    // A bent rod: two segments of 2 elements each (length 1 per segment), curved at the bend.
    const RodId rod =
        b.AddRodAlongPath("arm", {Vec3::Zero(), Vec3(1, 0, 0), Vec3(1.8, 0.6, 0)}, 2, RodSection());
    const std::vector<NodeId> given = b.RodNodes(rod);
    const std::vector<double> arcs = b.RodArcLengths(rod);
    const double length = arcs.back();
    b.FixNode(given.front());
    auto at = [&](double s, Vec3 offset = Vec3::Zero()) {
      BodyPoint p{kGround, offset};
      p.rod = rod;
      p.arc_length = s;
      return p;
    };
    // Features: eyelets at 0.3 and 0.7 L (0.3 twice, in two tendons), the tip; a force element
    // end at 0.55 L; a concentrated load at 0.1 L; an actuator over [0.2 L, 0.9 L]; and an
    // eyelet on a node (arcs[1]).
    b.AddTendon("t1",
                {{kGround, Vec3(0, 0.1, 0)},
                 at(0.3 * length, Vec3(0, 0.01, 0)),
                 at(0.7 * length),
                 at(length)},
                Profile::Constant(1.0));
    b.AddTendon("t2", {{kGround, Vec3(0, -0.1, 0)}, at(0.3 * length), at(arcs[1])},
                Profile::Constant(1.0));
    ForceElement f;
    f.a = {kGround, Vec3(0.5, -0.5, 0)};
    f.b = at(0.55 * length);
    f.stiffness = 1.0;
    b.AddForceElement(f);
    RodLoad load;
    load.rod = rod;
    load.distributed = false;
    load.arc_length = 0.1 * length;
    load.force = Vec3(0, 0, 1);
    b.AddRodLoad(load);
    Actuator a;
    a.type = ActuatorType::kRestStrain;
    a.rod = rod;
    a.from = 0.2 * length;
    a.to = 0.9 * length;
    a.vector << 0, 0, 0, 0, 0, 1;
    b.AddActuator(a);
    if (!conform) {  // an actuator's ends must then be at nodes
      EXPECT_THROW(b.Build(), InputError);
      b.model().actuators.clear();
      original = b.Build();
      EXPECT_EQ(original.conformed_nodes, 0);
      EXPECT_EQ(original.rods[0].num_elements, 4);
      EXPECT_GE(original.tendons[0].eyelets[1].element, 0);  // between nodes: on a section
      EXPECT_GE(original.rod_loads[0].xi, 0.3);
      continue;
    }
    const Model m = b.Build();
    const Rod& r = m.rods[0];
    // 0.1, 0.2, 0.3, 0.55, 0.7, 0.9 of the length: six new nodes, after the given five.
    EXPECT_EQ(m.conformed_nodes, 6);
    ASSERT_EQ(r.num_elements, 10);
    ASSERT_EQ(m.nodes.size(), given.size() + 6);
    std::vector<int> kept;
    for (int n : r.nodes)
      if (n < static_cast<int>(given.size())) kept.push_back(n);
    ASSERT_EQ(kept.size(), given.size());
    for (std::size_t i = 0; i < given.size(); ++i) EXPECT_EQ(kept[i], given[i].value());
    EXPECT_NEAR(r.length, length, 1e-12 * length);
    // The new nodes lie on the original elements' helices: every piece has the strain d0 / L
    // of the original element it is part of.
    const std::vector<double> original_arcs = [&] {
      std::vector<double> s{0.0};
      for (const RodElement& e : original.elements) s.push_back(s.back() + e.length);
      return s;
    }();
    double s_piece = 0.0;
    for (int e = 0; e < r.num_elements; ++e) {
      const RodElement& el = m.elements[static_cast<std::size_t>(r.first_element + e)];
      const double mid = s_piece + 0.5 * el.length;
      s_piece += el.length;
      int k = 0;
      while (k < 3 && original_arcs[static_cast<std::size_t>(k) + 1] < mid) ++k;
      const RodElement& whole = original.elements[static_cast<std::size_t>(k)];
      EXPECT_LT((el.d0 / el.length - whole.d0 / whole.length).norm(), 1e-12) << e;
    }
    for (const Tendon& t : m.tendons)
      for (const BodyPoint& p : t.eyelets) EXPECT_EQ(p.element, -1);
    EXPECT_EQ(m.force_elements[0].b.element, -1);
    const RodLoad& l = m.rod_loads[0];
    EXPECT_TRUE(l.xi == 0.0 || l.xi == 1.0) << l.xi;
    // Nodes at 0.2, 0.25, 0.3, 0.5, 0.55, 0.7, 0.75 and 0.9 L (0.25 and 0.75: given).
    EXPECT_EQ(m.actuators[0].num_elements, 7);
    // The eyelets are where the non-conforming model puts them (on the element's section).
    const Data d = MakeData(m), d_original = MakeData(original);
    for (std::size_t k = 1; k < 4; ++k)
      EXPECT_LT((BodyPointPosition(m, d, m.tendons[0].eyelets[k]) -
                 BodyPointPosition(original, d_original, original.tendons[0].eyelets[k]))
                    .norm(),
                1e-14)
          << k;
    const BodyPoint& e1 = m.tendons[0].eyelets[1];
    EXPECT_GE(e1.node, static_cast<int>(given.size()));
    EXPECT_EQ(m.nodes[static_cast<std::size_t>(e1.node)].name.rfind("arm.s0.6", 0), 0u)
        << m.nodes[static_cast<std::size_t>(e1.node)].name;
  }
}

// A cantilever along x (length 1, clamped at s = 0) with n elements, solved in statics.
struct Cantilever {
  Model model;
  Data data;
  StaticResult result;
  Vec3 Tip() const { return data.H[static_cast<std::size_t>(model.rods[0].nodes.back())].x; }
};

template <typename AddFeatures>
Cantilever SolveCantilever(int n, bool conform, AddFeatures add, int load_steps = 4) {
  ModelBuilder b;
  b.SetConformMesh(conform);
  const RodId rod = b.AddStraightRod("rod", Vec3::Zero(), Vec3::UnitX(), n, RodSection());
  b.FixNode(b.RodNodes(rod).front());
  add(b, rod);
  Cantilever c{b.Build(), {}, {}};
  c.data = MakeData(c.model);
  StaticOptions o;
  o.load_steps = load_steps;
  c.result = SolveStatic(c.model, c.data, o);
  return c;
}

// The bending curvature kappa3 of each element (its constant strain, (log(H_A^-1 H_B))_6 / L0
// on the straight reference) at its station, the element's midpoint (as rod_fields.csv
// reports it).
struct Station {
  double s, kappa;
};
std::vector<Station> Stations(const Cantilever& c) {
  std::vector<Station> out;
  double s = 0.0;
  const Rod& rod = c.model.rods[0];
  for (int e = 0; e < rod.num_elements; ++e) {
    const RodElement& el = c.model.elements[static_cast<std::size_t>(rod.first_element + e)];
    const SE3 rel = c.data.H[static_cast<std::size_t>(el.node_a)].Inverse() *
                    c.data.H[static_cast<std::size_t>(el.node_b)];
    out.push_back({s + 0.5 * el.length, LogSE3(rel)(5) / el.length});
    s += el.length;
  }
  return out;
}

// A concentrated moment M about z at s = a: the section moment is M on [0, a] (no force), so
// the rod bends into an arc of curvature k = M / EI up to a and is straight beyond. A helical
// element holds a constant curvature exactly, so the conforming mesh is exact, tip and
// strains. Without, the element holding the moment cannot bend only part of itself: its
// curvature is the average, k xi (k / 3 off at its station), at every mesh (a = 7/30 lies at xi = 1/3 of an element on
// 10, 40 and 160 elements): the strain there never converges, while the tip (a nodal value)
// converges at second order.
TEST(ConformMesh, ConcentratedMomentBetweenNodesIsExactOnAConformingMesh) {
  const double a = 7.0 / 30.0, M = 1.3, k = M / kEI;
  const Vec3 exact(std::sin(k * a) / k + (1 - a) * std::cos(k * a),
                   (1 - std::cos(k * a)) / k + (1 - a) * std::sin(k * a), 0.0);
  auto moment = [&](ModelBuilder& b, RodId rod) {
    RodLoad l;
    l.rod = rod;
    l.distributed = false;
    l.arc_length = a;
    l.moment = Vec3(0, 0, M);
    b.AddRodLoad(l);
  };
  auto strain_error = [&](const Cantilever& c) {
    double worst = 0.0;
    for (const Station& st : Stations(c))
      worst = std::max(worst, std::abs(st.kappa - (st.s < a ? k : 0.0)));
    return worst;
  };
  std::vector<double> off;
  for (int n : {10, 40, 160}) {
    SCOPED_TRACE(n);
    const Cantilever on = SolveCantilever(n, true, moment);
    ASSERT_TRUE(on.result.converged) << on.result.message;
    EXPECT_EQ(on.model.conformed_nodes, 1);
    EXPECT_LT((on.Tip() - exact).norm(), 1e-10);
    EXPECT_LT(strain_error(on), 1e-9);
    const Cantilever o = SolveCantilever(n, false, moment);
    ASSERT_TRUE(o.result.converged) << o.result.message;
    off.push_back((o.Tip() - exact).norm());
    // The element's curvature is the average k xi, its station (at xi = 1/2) beyond a: k / 3.
    EXPECT_NEAR(strain_error(o), k / 3.0, 1e-6 * k);
  }
  std::printf("moment at a = %.4f: non-conforming tip errors %.3g %.3g %.3g m (orders %.2f %.2f)\n",
              a, off[0], off[1], off[2], std::log(off[0] / off[1]) / std::log(4.0),
              std::log(off[1] / off[2]) / std::log(4.0));
}

// A rest curvature kappa over [s0, s1] (an actuator whose ends fall between the nodes; without
// a conforming mesh an error): an arc over the range, straight elsewhere, exactly.
TEST(ConformMesh, RestCurvatureOverARangeBetweenNodesIsExact) {
  const double s0 = 0.237, s1 = 0.681, kappa = 2.0;
  const double t = kappa * (s1 - s0);  // the turn over the range
  const Vec3 arc_end(s0 + std::sin(t) / kappa, (1 - std::cos(t)) / kappa, 0.0);
  const Vec3 exact = arc_end + (1 - s1) * Vec3(std::cos(t), std::sin(t), 0.0);
  const Cantilever c = SolveCantilever(6, true, [&](ModelBuilder& b, RodId rod) {
    Actuator a;
    a.type = ActuatorType::kRestStrain;
    a.rod = rod;
    a.from = s0;
    a.to = s1;
    a.vector << 0, 0, 0, 0, 0, kappa;
    b.AddActuator(a);
  });
  ASSERT_TRUE(c.result.converged) << c.result.message;
  EXPECT_EQ(c.model.conformed_nodes, 2);
  EXPECT_LT((c.Tip() - exact).norm(), 1e-10);
}

// The tendon case of issue 40: tension 50 N at offset 0.02 m (section y) through 5 eyelets, at
// the clamp, at 7/30, 13/30 and 19/30 and ending at 22/30 of the length: the section moment
// jumps by tau d there (the rod beyond is straight), and the kinks of the tendon at the other
// eyelets put small jumps in the section force. The four eyelets off the clamp lie at xi = 1/3
// of an element on 10, 40, 160 and 640 elements (the error's constant stays the same).
constexpr double kTension = 50.0, kOffset = 0.02;

Cantilever SolveTendon(int n, bool conform) {
  return SolveCantilever(
      n, conform,
      [](ModelBuilder& b, RodId rod) {
        std::vector<BodyPoint> eyelets;
        for (double s : {0.0, 7.0 / 30.0, 13.0 / 30.0, 19.0 / 30.0, 22.0 / 30.0}) {
          BodyPoint p{kGround, Vec3(0.0, kOffset, 0.0)};
          p.rod = rod;
          p.arc_length = s;
          eyelets.push_back(p);
        }
        b.AddTendon("tendon", eyelets, Profile::Constant(kTension));
      },
      10);
}

// The reference curvature at s: linear between the stations of the fine conforming mesh on the
// same side of every feature (the curvature jumps at the eyelets).
double ReferenceKappa(const std::vector<Station>& fine, double s) {
  const double features[] = {7.0 / 30.0, 13.0 / 30.0, 19.0 / 30.0, 22.0 / 30.0};
  auto side = [&](double x) {
    int n = 0;
    for (double f : features) n += x > f;
    return n;
  };
  auto hi = std::lower_bound(fine.begin(), fine.end(), s,
                             [](const Station& st, double x) { return st.s < x; });
  if (hi == fine.begin()) return hi->kappa;
  if (hi == fine.end()) return fine.back().kappa;
  const Station& l = *(hi - 1);
  const Station& h = *hi;
  if (side(l.s) != side(s)) return h.kappa;
  if (side(h.s) != side(s)) return l.kappa;
  return l.kappa + (h.kappa - l.kappa) * (s - l.s) / (h.s - l.s);
}

TEST(ConformMesh, TendonEyeletsBetweenNodesConvergeAtSecondOrder) {
  // The reference: Richardson's extrapolation of the conforming tips on 2560 and 5120
  // elements (second order: x + (x - x_coarse) / 3); the curvature of the one on 5120.
  const Cantilever fine = SolveTendon(5120, true), coarse = SolveTendon(2560, true);
  ASSERT_TRUE(fine.result.converged && coarse.result.converged);
  EXPECT_EQ(fine.model.conformed_nodes, 4);
  const Vec3 tip = fine.Tip() + (fine.Tip() - coarse.Tip()) / 3.0;
  const std::vector<Station> reference = Stations(fine);
  auto strain_error = [&](const Cantilever& c) {
    double worst = 0.0;
    for (const Station& st : Stations(c))
      worst = std::max(worst, std::abs(st.kappa - ReferenceKappa(reference, st.s)));
    return worst;
  };
  const int meshes[] = {10, 40, 160, 640};
  double on[4], off[4], on_strain[4], off_strain[4];
  for (int i = 0; i < 4; ++i) {
    SCOPED_TRACE(meshes[i]);
    const Cantilever c = SolveTendon(meshes[i], true), o = SolveTendon(meshes[i], false);
    ASSERT_TRUE(c.result.converged && o.result.converged);
    EXPECT_EQ(c.model.conformed_nodes, 4);
    EXPECT_EQ(c.model.rods[0].num_elements, meshes[i] + 4);
    EXPECT_EQ(o.model.rods[0].num_elements, meshes[i]);
    on[i] = (c.Tip() - tip).norm();
    off[i] = (o.Tip() - tip).norm();
    on_strain[i] = strain_error(c);
    off_strain[i] = strain_error(o);
  }
  auto order = [](const double* e, int i) { return std::log(e[i - 1] / e[i]) / std::log(4.0); };
  std::printf(
      "tendon, 5 eyelets: elements | tip error: conforming order, non-conforming order | "
      "station curvature error: conforming order, non-conforming\n");
  for (int i = 0; i < 4; ++i)
    std::printf("  %4d | %9.3g %5.2f  %9.3g %5.2f | %9.3g %5.2f  %9.3g\n", meshes[i], on[i],
                i ? order(on, i) : 0.0, off[i], i ? order(off, i) : 0.0, on_strain[i],
                i ? order(on_strain, i) : 0.0, off_strain[i]);
  for (int i = 2; i < 4; ++i) {
    SCOPED_TRACE(meshes[i]);
    EXPECT_GT(order(on, i), 1.8);
    EXPECT_LT(order(on, i), 2.2);
    EXPECT_GT(order(on_strain, i), 1.8);
    EXPECT_LT(order(on_strain, i), 2.2);
    // Without: the tip (a nodal value) converges too, with a larger error; the strain of the
    // element holding the tendon's end stays the average across the jump (about tau d / EI / 3).
    EXPECT_GT(off[i], 1.3 * on[i]);
    EXPECT_GT(off_strain[i], 0.3);
  }
  // The case: 1.5e-5 L off at 1296 elements with eyelets between nodes.
  EXPECT_LT(on[3], 1.5e-6);
}

}  // namespace
}  // namespace screwfem::conform_mesh_test
