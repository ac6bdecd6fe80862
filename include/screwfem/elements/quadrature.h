// Gauss-Legendre rules on [0, 1] (the one definition of each): points xi_i and weights w_i,
// int_0^1 f dxi ~ sum_i w_i f(xi_i).
#pragma once

namespace screwfem {

// 3 points, exact for polynomials of degree 5: rod inertia (option A), distributed loads,
// gravity potential (docs/numerics.md, "Rod inertia").
inline constexpr int kGauss3Points = 3;
inline constexpr double kGauss3Xi[kGauss3Points] = {0.5 - 0.3872983346207417, 0.5,
                                                    0.5 + 0.3872983346207417};
inline constexpr double kGauss3W[kGauss3Points] = {5.0 / 18.0, 8.0 / 18.0, 5.0 / 18.0};

// 2 points, exact for cubics (equal weights 1/2): rod inertia, option B.
inline constexpr int kGauss2Points = 2;
inline constexpr double kGauss2Xi[kGauss2Points] = {0.5 - 0.28867513459481287,
                                                    0.5 + 0.28867513459481287};

}  // namespace screwfem
