// Issue 16's tipping case, shared by tests/elements/shape_pair_face_test.cpp and
// tests/alloc/no_alloc_test.cpp: a 1 kg box of half sizes (0.05, 0.04, 0.03) m, tilted by
// `theta` about x with its lowest edge `drop` above a fixed table box (top face at z = 0),
// under gravity; contact law k = 1e5, onset 1e-4 m, mu = 0.3.
#pragma once

#include <cmath>

#include "screwfem/build/model_builder.h"

namespace screwfem::tilted_box_drop {

inline constexpr double kMass = 1.0;
inline const Vec3 kHalf(0.05, 0.04, 0.03);

// `inertia`: the box's principal moments about its centre [kg m^2].
inline Model MakeTiltedBoxDrop(double theta, double drop, const Vec3& inertia) {
  ModelBuilder b;
  const NodeId base = b.AddNode(SE3{Mat3::Identity(), Vec3::Zero()});
  b.FixNode(base);
  b.AddRigidBody("table", base, 1.0, Vec3::Zero(), Mat3::Identity());
  b.AddContactShape({0, ContactShapeType::kBox, Vec3(0.0, 0.0, -0.05), Vec3(0.3, 0.3, 0.05), 0.0});
  const double lowest = kHalf.y() * std::sin(theta) + kHalf.z() * std::cos(theta);
  const NodeId node =
      b.AddNode(SE3{ExpSO3(Vec3(theta, 0.0, 0.0)), Vec3(0.02, -0.01, lowest + drop)});
  b.AddRigidBody("block", node, kMass, Vec3::Zero(), inertia.asDiagonal());
  b.AddContactShape({1, ContactShapeType::kBox, Vec3::Zero(), kHalf, 0.0});
  ContactSettings law;
  law.stiffness = 1e5;
  law.onset = 1e-4;
  law.friction = 0.3;
  law.friction_law = FrictionLaw::kSmooth;  // the smooth law's step halvings are measured
  b.SetContactSettings(law);
  b.SetGravity(Vec3(0.0, 0.0, -9.81));
  return b.Build();
}

}  // namespace screwfem::tilted_box_drop
