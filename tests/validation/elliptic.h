// Complete elliptic integral K(m) and Jacobi elliptic functions sn, cn, dn for the closed-form
// references of the validation tests (parameter m = k^2, 0 <= m < 1). Arithmetic-geometric
// mean and the descending Landen transformation (Abramowitz & Stegun 17.6, 16.4); accurate to
// a few ulps, independent of any screwfem code.
#pragma once

#include <array>
#include <cmath>
#include <numbers>

namespace screwfem::test {

// K(m) = pi / (2 AGM(1, sqrt(1 - m))).
inline double EllipticK(double m) {
  double a = 1.0, b = std::sqrt(1.0 - m);
  for (int i = 0; i < 64 && std::abs(a - b) > 1e-16 * a; ++i) {
    const double an = 0.5 * (a + b);
    b = std::sqrt(a * b);
    a = an;
  }
  return 0.5 * std::numbers::pi / a;
}

struct Jacobi {
  double sn, cn, dn, am;
};

// sn(u|m), cn(u|m), dn(u|m) and the amplitude am(u|m) (continuous in u).
inline Jacobi JacobiElliptic(double u, double m) {
  if (m == 0.0) return {std::sin(u), std::cos(u), 1.0, u};
  constexpr int kMax = 32;
  std::array<double, kMax + 1> a{}, c{};
  a[0] = 1.0;
  double b = std::sqrt(1.0 - m);
  c[0] = std::sqrt(m);
  int n = 0;
  while (n < kMax && std::abs(c[n]) > 1e-17 * a[n]) {
    a[n + 1] = 0.5 * (a[n] + b);
    c[n + 1] = 0.5 * (a[n] - b);
    b = std::sqrt(a[n] * b);
    ++n;
  }
  // phi_N = 2^N a_N u; phi_{n-1} = (phi_n + asin(c_n / a_n sin phi_n)) / 2.
  double phi = std::ldexp(1.0, n) * a[n] * u;
  for (int i = n; i >= 1; --i) {
    phi = 0.5 * (phi + std::asin(c[i] / a[i] * std::sin(phi)));
  }
  const double sn = std::sin(phi), cn = std::cos(phi);
  // dn^2 = 1 - m sn^2 = (1 - m) + m cn^2, written without cancellation for m near 1.
  const double dn = std::sqrt((1.0 - m) + m * cn * cn);
  return {sn, cn, dn, phi};
}

}  // namespace screwfem::test
