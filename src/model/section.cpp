#include "screwfem/model/section.h"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include "screwfem/model/errors.h"

namespace screwfem {

namespace {

struct Resolved {
  double E, G, nu, rho;
};

Resolved Resolve(const Material& m) {
  if (!(m.youngs_modulus > 0.0) || !std::isfinite(m.youngs_modulus))
    throw InputError("material: youngs_modulus must be a positive number");
  if (!(m.density >= 0.0) || !std::isfinite(m.density))
    throw InputError("material: density must be a non-negative number");
  double G = m.shear_modulus, nu = m.poisson_ratio;
  if (G > 0.0) {
    nu = m.youngs_modulus / (2.0 * G) - 1.0;
  } else {
    if (!(nu > -1.0 && nu <= 0.5))
      throw InputError("material: give shear_modulus > 0 or poisson_ratio in (-1, 0.5]");
    G = m.youngs_modulus / (2.0 * (1.0 + nu));
  }
  return {m.youngs_modulus, G, nu, m.density};
}

Section Build(const Resolved& r, double kappa, double A, double I2, double I3, double J) {
  Section s;
  s.stiffness << r.E * A, kappa * r.G * A, kappa * r.G * A, r.G * J, r.E * I2, r.E * I3;
  s.inertia << r.rho * A, r.rho * A, r.rho * A, r.rho * (I2 + I3), r.rho * I2, r.rho * I3;
  return s;
}

}  // namespace

Section Section::FromDiagonals(const Vec6& stiffness, const Vec6& inertia) {
  for (int i = 0; i < 6; ++i) {
    if (!(stiffness(i) > 0.0) || !std::isfinite(stiffness(i)))
      throw InputError("section: stiffness entry " + std::to_string(i) +
                       " must be a positive number");
    if (!(inertia(i) >= 0.0) || !std::isfinite(inertia(i)))
      throw InputError("section: inertia entry " + std::to_string(i) +
                       " must be a non-negative number");
  }
  Section s;
  s.stiffness = stiffness;
  s.inertia = inertia;
  return s;
}

Section Section::Circle(double radius, const Material& material) {
  if (!(radius > 0.0)) throw InputError("section: circle radius must be positive");
  const Resolved r = Resolve(material);
  const double A = std::numbers::pi * radius * radius;
  const double I = 0.25 * std::numbers::pi * std::pow(radius, 4);
  // Cowper (1966) for a solid circle.
  const double kappa = material.shear_coefficient > 0.0 ? material.shear_coefficient
                                                        : 6.0 * (1.0 + r.nu) / (7.0 + 6.0 * r.nu);
  Section s = Build(r, kappa, A, I, I, 2.0 * I);
  s.width = s.height = 2.0 * radius;
  s.round = true;
  return s;
}

Section Section::Rectangle(double width, double height, const Material& material) {
  if (!(width > 0.0) || !(height > 0.0))
    throw InputError("section: rectangle width and height must be positive");
  const Resolved r = Resolve(material);
  const double A = width * height;
  const double I2 = width * std::pow(height, 3) / 12.0;  // bending about axis 2 (height along 3)
  const double I3 = height * std::pow(width, 3) / 12.0;
  // Saint-Venant torsion constant of a rectangle (Roark's approximation, error < 0.5 %).
  const double a = std::max(width, height) / 2.0, b = std::min(width, height) / 2.0;
  const double J =
      a * std::pow(b, 3) * (16.0 / 3.0 - 3.36 * (b / a) * (1.0 - std::pow(b / a, 4) / 12.0));
  const double kappa = material.shear_coefficient > 0.0
                           ? material.shear_coefficient
                           : 10.0 * (1.0 + r.nu) / (12.0 + 11.0 * r.nu);
  Section s = Build(r, kappa, A, I2, I3, J);
  s.width = width;
  s.height = height;
  return s;
}

Section Section::Tube(double outer_radius, double inner_radius, const Material& material) {
  if (!(outer_radius > 0.0) || !(inner_radius >= 0.0) || !(inner_radius < outer_radius))
    throw InputError("section: tube needs 0 <= inner_radius < outer_radius");
  const Resolved r = Resolve(material);
  const double ro2 = outer_radius * outer_radius, ri2 = inner_radius * inner_radius;
  const double A = std::numbers::pi * (ro2 - ri2);
  const double I = 0.25 * std::numbers::pi * (ro2 * ro2 - ri2 * ri2);
  // Cowper (1966) for a hollow circle, m = ri/ro.
  const double m2 = ri2 / ro2;
  const double kappa =
      material.shear_coefficient > 0.0
          ? material.shear_coefficient
          : 6.0 * (1.0 + r.nu) * (1.0 + m2) * (1.0 + m2) /
                ((7.0 + 6.0 * r.nu) * (1.0 + m2) * (1.0 + m2) + (20.0 + 12.0 * r.nu) * m2);
  Section s = Build(r, kappa, A, I, I, 2.0 * I);
  s.width = s.height = 2.0 * outer_radius;
  s.round = true;
  return s;
}

}  // namespace screwfem
