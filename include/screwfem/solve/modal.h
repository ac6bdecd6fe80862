// Linearisation of the constrained equations of motion about an equilibrium, natural
// frequencies and mode shapes (docs/validation.md, D1).
//
// The matrices come from the same assembly as the Newton solvers (assemble/assemble.h), read
// back from the banded matrix through model.permutation:
//   M = dr/d(vdot)             (Assemble with c_mass = 1, the others 0, at rest),
//   K = dr/d(dh)               (the static tangent: elements, loads, joint springs),
//   C = dr/dv at rest           (strain-rate and Rayleigh damping, joint dampers),
//   B = dphi/d(dh)             (constraint rows, including prescribed drives, which the
//                               linearisation holds at their value at `time`).
// Small motions dx = Z y stay in the null space of B (Z orthonormal); the undamped modes solve
// Z^T K Z y = omega^2 Z^T M Z y. Admissible directions without mass (e.g. massless joint
// coordinates, rods without rotary inertia) are condensed out statically (exact for them).
//
// Limits. Everything is dense: O(nv^2) memory and O(nv^3) time, fine up to a few thousand
// unknowns (nv = 3000: ~0.1 GB, tens of seconds). The assembled tangent omits
// d(B^T lambda)/dq, the geometric stiffness of constraint reactions. On the admissible space
// this term vanishes for joints to the ground, for welds (fixed joints) and whenever the
// reactions vanish (e.g. no gravity or loads); for joints between two moving bodies that
// transmit a moment normal to their free axes under preload the frequencies are approximate.
// Follower loads (and right-trivialised coordinates away from equilibrium) make K
// non-symmetric; the symmetric part is used and the asymmetry is reported.
#pragma once

#include <string>
#include <vector>

#include "screwfem/model/data.h"

namespace screwfem {

struct ModalOptions {
  double time = 0.0;              // loads and drives are evaluated at this time (load factor 1)
  int num_modes = 0;              // lowest modes to return; 0 = all
  double rank_tolerance = 1e-10;  // relative threshold for the rank of B
};

// The linearised system in the velocity layout (size nv; node blocks are right-trivialised
// 6-vectors [translation; rotation] in node-frame components, then joint coordinates).
struct LinearizedSystem {
  Eigen::MatrixXd mass;         // M, nv x nv
  Eigen::MatrixXd stiffness;    // K, nv x nv
  Eigen::MatrixXd damping;      // C, nv x nv
  Eigen::MatrixXd constraints;  // B, nc x nv (rows of redundant constraints are zero)
  Eigen::MatrixXd null_space;   // Z, nv x (nv - rank B), orthonormal columns, B Z = 0
  // |r + B^T lambda|_inf relative to the largest force term, at the state and data.lambda:
  // zero at an equilibrium (e.g. after SolveStatic).
  double relative_residual = 0.0;
};

// Evaluates M, K, C, B and Z at data's configuration (velocities are taken as zero; data.v and
// data.vdot are restored on return, the assembly workspaces are overwritten). Returns false if
// an element's rotation is outside its admissible range.
bool CalcLinearizedSystem(const Model& model, Data& data, const ModalOptions& options,
                          LinearizedSystem* out);

struct ModalResult {
  bool ok = false;
  std::string message;          // why it failed
  Eigen::VectorXd eigenvalues;  // omega^2 [rad^2/s^2], ascending; < 0: unstable equilibrium
  Eigen::VectorXd omega;        // natural angular frequencies sqrt(max(omega^2, 0)) [rad/s]
  Eigen::VectorXd frequency;    // omega / (2 pi) [Hz]
  // Modal damping ratio phi^T C phi / (2 omega) (exact for proportional damping, e.g.
  // Rayleigh); 0 where omega^2 <= 0, meaningless for rigid-body modes (omega ~ round-off).
  Eigen::VectorXd damping_ratio;
  // Mode shapes, one per column, in the velocity layout (nv rows), mass-normalised
  // (phi^T M phi = 1) and admissible (B phi = 0). A small motion is dx = a phi (retraction).
  Eigen::MatrixXd modes;
  int num_dofs = 0;                   // dimension of the admissible space (nv - rank B)
  int num_massless = 0;               // admissible directions without mass, condensed out
  double stiffness_asymmetry = 0.0;   // |Z^T (K - K^T) Z| / |Z^T K Z| (Frobenius)
  double relative_residual = 0.0;     // as in LinearizedSystem
  std::vector<std::string> warnings;  // not at equilibrium, unstable, non-symmetric K
};

// Natural frequencies and mode shapes of the constrained system linearised about data's
// configuration, which should be an equilibrium (a reference state without loads, or the
// result of SolveStatic with data.lambda). See the header comment for the limits.
ModalResult CalcModes(const Model& model, Data& data, const ModalOptions& options = {});

}  // namespace screwfem
