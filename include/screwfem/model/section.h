// Cross-section properties of a Cosserat rod (elements/rod.h).
//
// 6-vectors are translation first: stiffness = (EA, GA2, GA3, GJ, EI2, EI3) in
// (N, N, N, N m^2, N m^2, N m^2); inertia per unit length = (rhoA, rhoA, rhoA, rhoJ1, rhoI2,
// rhoI3) in (kg/m x3, kg m x3). Section axis 1 is the rod axis; axes 2 and 3 span the section.
#pragma once

#include "screwfem/lie/se3.h"

namespace screwfem {

struct Material {
  double youngs_modulus = 0.0;     // E [Pa], > 0
  double shear_modulus = 0.0;      // G [Pa]; if 0, computed from poisson_ratio
  double poisson_ratio = -1.0;     // nu; used when shear_modulus is 0 (must be in (-1, 0.5])
  double density = 0.0;            // rho [kg/m^3], >= 0
  double shear_coefficient = 0.0;  // kappa; 0 selects Cowper's value for the shape
};

struct Section {
  Vec6 stiffness = Vec6::Zero();  // diagonal of the sectional stiffness matrix K
  Vec6 inertia = Vec6::Zero();    // diagonal of the sectional mass matrix M (per length)
  Vec6 damping = Vec6::Zero();    // viscous damping on strain rates (per mode), K-units times s
  // Rayleigh damping of the rod, C = a_M M_e + a_K K (elements/rod.h, AddRodDamping), in
  // addition to `damping`. A mode of angular frequency w gets the damping ratio
  // a_M / (2 w) + a_K w / 2. a_M also damps rigid-body motion; a_K acts on strain rates.
  double rayleigh_mass = 0.0;       // a_M [1/s], >= 0
  double rayleigh_stiffness = 0.0;  // a_K [s], >= 0
  // The outline, for drawing only (the mechanics reads the diagonals above; the ParaView
  // frames draw rods with it, io/vtk.h): the extent along section axes 2 and 3 [m] (a circle's
  // or a tube's outer diameter twice, a rectangle's width and height) and whether it is round.
  // Set by Circle, Rectangle and Tube; zero for FromDiagonals (a caller may set them).
  double width = 0.0, height = 0.0;
  bool round = false;

  static Section FromDiagonals(const Vec6& stiffness, const Vec6& inertia = Vec6::Zero());
  // Solid circle of radius r.
  static Section Circle(double radius, const Material& material);
  // Solid rectangle, width b along section axis 2, height h along section axis 3.
  static Section Rectangle(double width, double height, const Material& material);
  // Circular tube with outer and inner radius.
  static Section Tube(double outer_radius, double inner_radius, const Material& material);
};

}  // namespace screwfem
