// screwfem statics example: two classic large-deformation problems of a Cosserat rod, solved
// with the helical (SE(3)) element and the static Newton solver with load stepping.
//
// 1. Roll-up (docs/validation.md, S1): a cantilever (L = 10, EI = 100) under an end moment
//    M = lambda 2 pi EI / L curls into a circular arc, and for lambda = 1 into a full circle
//    with the tip back at the root. The arc has constant strain, which the helical element
//    represents exactly, so 10 elements reproduce the closed form to round-off:
//    tip = L (sin phi, 1 - cos phi) / phi, tip rotation phi = 2 pi lambda.
// 2. Elastica (docs/validation.md, S3): the same kind of cantilever (L = 1, EI = 1) under a dead
//    transverse tip force P, compared with Mattiasson's table for P L^2 / EI = 1, 2, 5, 10.
//    The moment now varies along the rod, so the element is not exact: it converges at O(h^2),
//    and 32 elements give about three significant digits (the test suite uses 128 for four).
//
// For each case the program prints the computed and the reference value, the relative error,
// and the Newton iterations and load steps the solver needed. It exits with status 1 if any
// error exceeds its tolerance, so CI can run it as a test.
#include <cmath>
#include <cstdio>
#include <numbers>
#include <vector>

#include "screwfem/model/model.h"
#include "screwfem/solve/statics.h"
#include "screwfem/build/model_builder.h"

namespace {

using screwfem::Data;
using screwfem::LoadFrame;
using screwfem::Model;
using screwfem::ModelBuilder;
using screwfem::NodeId;
using screwfem::PointLoad;
using screwfem::RodId;
using screwfem::Section;
using screwfem::StaticResult;
using screwfem::Vec3;
using screwfem::Vec6;

constexpr double kPi = std::numbers::pi;

// A cantilever along x from the origin, clamped at the root, with one load at the tip.
struct Cantilever {
  Model model;
  int tip = -1;
};

Cantilever MakeCantilever(double length, const Vec6& stiffness, int num_elements,
                          const PointLoad& tip_load) {
  ModelBuilder b;
  const RodId rod = b.AddStraightRod("cantilever", Vec3::Zero(), Vec3(length, 0.0, 0.0),
                                     num_elements, Section::FromDiagonals(stiffness));
  const std::vector<NodeId> nodes = b.RodNodes(rod);
  b.FixNode(nodes.front());
  PointLoad load = tip_load;
  load.node = nodes.back();
  b.AddPointLoad(load);
  return {b.Build(), nodes.back()};
}

// One line of the table; counts the checks whose error exceeds the tolerance.
void Row(const char* label, double computed, double reference, double error, double tolerance,
         int* failures) {
  const bool ok = error <= tolerance;
  if (!ok) ++*failures;
  std::printf("  %-22s %14.9f %14.9f %10.2e%s\n", label, computed, reference, error,
              ok ? "" : "  <-- exceeds tolerance");
}

void Solver(const StaticResult& r, int* failures) {
  std::printf("  Newton iterations %d, load steps %d (halvings %d)%s\n\n", r.total_iterations,
              r.load_steps, r.halvings, r.converged ? "" : "  <-- did not converge");
  if (!r.converged) {
    std::printf("  %s\n\n", r.message.c_str());
    ++*failures;
  }
}

void RollUp(int* failures) {
  constexpr double L = 10.0, EI = 100.0, kTolerance = 1e-8;
  constexpr int kElements = 10;
  Vec6 stiffness;
  stiffness << 1e4, 1e4, 1e4, 100.0, EI, EI;  // EA, GA2, GA3, GJ, EI2, EI3
  std::printf("1. Roll-up of a cantilever by an end moment (L = %g, EI = %g, %d elements)\n", L, EI,
              kElements);
  std::printf("  %-22s %14s %14s %10s\n", "quantity", "computed", "exact", "rel. error");
  for (const double lambda : {0.25, 0.5, 0.75, 1.0}) {
    PointLoad load;
    load.frame = LoadFrame::kWorld;
    load.moment = Vec3(0.0, 0.0, lambda * 2.0 * kPi * EI / L);
    const Cantilever c = MakeCantilever(L, stiffness, kElements, load);
    Data d = MakeData(c.model);
    const StaticResult r = SolveStatic(c.model, d);
    const double phi = 2.0 * kPi * lambda;
    const Vec3 tip = d.H[static_cast<std::size_t>(c.tip)].x;
    // The tip rotation including whole turns: the sum of the element rotations, each on its
    // continuous branch (elements/rod.h).
    double rotation = 0.0;
    for (const Vec3& w : d.w_ref) rotation += w.z();
    const double x = L * std::sin(phi) / phi, y = L * (1.0 - std::cos(phi)) / phi;
    std::printf(" lambda = %.2f\n", lambda);
    Row("tip x / L", tip.x() / L, x / L, std::abs(tip.x() - x) / L, kTolerance, failures);
    Row("tip y / L", tip.y() / L, y / L, std::abs(tip.y() - y) / L, kTolerance, failures);
    Row("tip rotation [rad]", rotation, phi, std::abs(rotation - phi) / phi, kTolerance, failures);
    Solver(r, failures);
  }
}

void Elastica(int* failures) {
  constexpr int kElements = 32;
  constexpr double kTolerance = 1e-3;
  struct Reference {
    double alpha, w, u, theta;  // P L^2 / EI, w / L, u / L, tip rotation (Mattiasson 1981)
  };
  constexpr Reference kTable[] = {{1.0, 0.301721, 0.0564332, 0.461352},
                                  {2.0, 0.493458, 0.160642, 0.781750},
                                  {5.0, 0.713792, 0.387628, 1.215368},
                                  {10.0, 0.810609, 0.554996, 1.430286}};
  Vec6 stiffness;
  stiffness << 1e7, 1e7, 1e7, 1.0, 1.0, 1.0;  // nearly inextensible and unshearable
  std::printf("2. Cantilever elastica under a dead tip force (L = 1, EI = 1, %d elements)\n",
              kElements);
  std::printf("  %-22s %14s %14s %10s\n", "quantity", "computed", "Mattiasson", "rel. error");
  for (const Reference& ref : kTable) {
    PointLoad load;
    load.frame = LoadFrame::kWorld;
    load.force = Vec3(0.0, ref.alpha, 0.0);
    const Cantilever c = MakeCantilever(1.0, stiffness, kElements, load);
    Data d = MakeData(c.model);
    const StaticResult r = SolveStatic(c.model, d);
    const screwfem::SE3& H = d.H[static_cast<std::size_t>(c.tip)];
    const double w = H.x.y(), u = 1.0 - H.x.x(), theta = std::atan2(H.R(1, 0), H.R(0, 0));
    std::printf(" P L^2 / EI = %g\n", ref.alpha);
    Row("w / L", w, ref.w, std::abs(w - ref.w) / ref.w, kTolerance, failures);
    Row("u / L", u, ref.u, std::abs(u - ref.u) / ref.u, kTolerance, failures);
    Row("tip rotation [rad]", theta, ref.theta, std::abs(theta - ref.theta) / ref.theta, kTolerance,
        failures);
    Solver(r, failures);
  }
}

}  // namespace

int main() {
  int failures = 0;
  RollUp(&failures);
  Elastica(&failures);
  if (failures > 0) {
    std::printf("%d check(s) failed\n", failures);
    return 1;
  }
  std::printf("all checks passed\n");
  return 0;
}
