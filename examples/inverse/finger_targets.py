"""Inverse statics of a three-tendon finger: the tensions that put its tip on moving targets.

The scene (examples/tendon/finger3.yaml) is a 1 m rod clamped at its base with three tendons
120 degrees apart around it; their tensions are the run-time inputs t1, t2, t3 [N]. For each
target on a circle (a moving target, as a controller would ask for one per control step),
screwfem.inverse_statics finds the tensions in [0, 40] N whose equilibrium puts the tip there:
bounded least squares (Ceres) with the exact Jacobian of the equilibrium
(screwfem.static_sensitivity; docs/inverse.md), each target warm-started from the last
solution. A last target out of reach is reported with the nearest equilibrium within the bounds.

The example exits non-zero unless every reachable target is met to 1e-8 m within the bounds,
the Jacobian agrees with central differences of re-solved equilibria to 1e-6, and the
unreachable target is reported as such.

Run from the repository root with the bindings on the path:
    PYTHONPATH=build/release/python /usr/bin/python3 examples/inverse/finger_targets.py
"""

import math
import pathlib
import sys

import numpy as np

import screwfem as sf

ROOT = pathlib.Path(__file__).resolve().parents[2]
SCENE = ROOT / "examples" / "tendon" / "finger3.yaml"
T_MAX = 40.0  # [N]
TARGETS = 20


def check_jacobian(sim, params):
    """The exact Jacobian of the tip against central differences of re-solved equilibria."""
    tip = sf.inverse_target(sim, "tip", [0, 0, 0])
    outputs = [sf.SensitivityOutput(sf.OutputKind.POINT_POSITION, tip.node, c, tip.offset)
               for c in range(3)]
    exact = sf.static_sensitivity(sim, params, outputs).outputs
    adjoint = sf.static_sensitivity(sim, params, outputs, sf.SensitivityMode.ADJOINT).outputs
    base = np.array(sim.input_values)
    fd = np.zeros_like(exact)
    h = 1e-3
    for j in range(len(params)):
        tips = []
        for sign in (1, -1):
            sim.input_values[:] = base
            sim.input_values[j] += sign * h
            sim.solve_static()
            tips.append(sim.point_motion("tip").position)
        fd[:, j] = (np.asarray(tips[0]) - np.asarray(tips[1])) / (2 * h)
    sim.input_values[:] = base
    sim.solve_static()
    error = np.abs(exact - fd).max() / np.abs(fd).max()
    adjoint_error = np.abs(exact - adjoint).max() / np.abs(exact).max()
    print(f"Jacobian against central differences: {error:.2e} relative; adjoint: "
          f"{adjoint_error:.2e}")
    return error < 1e-6 and adjoint_error < 1e-10


def main():
    sim = sf.Simulation(sf.load_scene(str(SCENE)))
    model = sim.model
    params = [sf.Parameter(sf.ParameterKind.INPUT, model.find_input(name))
              for name in ("t1", "t2", "t3")]
    lower, upper = np.zeros(3), np.full(3, T_MAX)
    ok = True

    sim.input_values[:] = [10.0, 25.0, 5.0]
    sim.solve_static()
    ok &= check_jacobian(sim, params)

    # A moving target that circles the finger's axis: the tips of equilibria (of another
    # Simulation) at tensions that go round a circle in tension space, so every target is
    # reachable; the tensions found need not be those.
    values = np.array(sim.input_values)
    worst, solves = 0.0, 0
    for k in range(TARGETS):
        angle = 2 * math.pi * k / TARGETS
        probe = sf.Simulation(sf.load_scene(str(SCENE)))
        tensions = np.maximum(0.0, 20.0 + 18.0 * np.array(
            [math.sin(angle), math.sin(angle - 2 * math.pi / 3), math.sin(angle + 2 * math.pi / 3)]))
        probe.input_values[:] = tensions
        probe.solve_static()
        target = np.asarray(probe.point_motion("tip").position)
        r = sf.inverse_statics(sim, params, lower, upper,
                               [sf.inverse_target(sim, "tip", target)], start=values)
        values = np.asarray(r.values)
        reached = np.linalg.norm(np.asarray(sim.point_motion("tip").position) - target)
        worst = max(worst, r.distance)
        solves += r.equilibrium_solves
        inside = bool(np.all(values >= 0.0) and np.all(values <= T_MAX))
        print(f"target {k:2d} at ({target[0]:.4f}, {target[1]:+.4f}, {target[2]:+.4f}) m: "
              f"tensions {values[0]:6.3f} {values[1]:6.3f} {values[2]:6.3f} N, distance "
              f"{r.distance:.1e} m, {r.iterations} iterations, {r.equilibrium_solves} solves")
        ok &= r.converged and r.distance < 1e-8 and reached < 1e-8 and inside
    print(f"{TARGETS} targets: largest distance {worst:.1e} m, {solves} equilibrium solves")

    # Out of reach: behind the clamp.
    far = np.array([-0.5, 0.0, 0.0])
    r = sf.inverse_statics(sim, params, lower, upper, [sf.inverse_target(sim, "tip", far)],
                           start=values)
    print(f"unreachable target {far}: converged {r.converged}, nearest tip "
          f"{np.round(sim.point_motion('tip').position, 4)} at {r.distance:.4f} m, tensions "
          f"{np.round(r.values, 3)} N\n  {r.message}")
    ok &= (not r.converged) and r.distance > 0.1 and "not reached" in r.message
    ok &= bool(np.all(np.asarray(r.values) >= 0.0) and np.all(np.asarray(r.values) <= T_MAX))
    if not ok:
        print("FAILED", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
