"""A tendon's routing offset and a length-driven tendon: sensitivities with multipliers, and
calibration of the offset.

1. Dynamics with a multiplier: a 1 m finger (EI = 1 N m^2) drawn by a length-driven tendon 2 cm
   off its axis (the tendon's tension is the constraint's multiplier); the prescribed length
   shortens piecewise-linearly with knots every 10 ms, so the run restarts at each knot (with the
   tendon's inelastic catch). screwfem.dynamic_sensitivity differentiates the tip's trajectory
   with respect to a knot of the length profile (TENDON_LENGTH with a hat shape) and to the
   tendon's offset (TENDON_OFFSET, component y); the derivatives are checked against central
   differences of whole runs of models built with the perturbed values (1e-6 of the largest),
   and the adjoint gradient of an objective over the run against the forward one (1e-10).
2. Calibration: the same finger pulled by a tension-driven tendon, measured at three tensions
   with the tendon actually 2.5 mm farther from the axis than the model says, plus 20 um of
   noise; screwfem.calibrate recovers the offset error within its reported interval.

Exits non-zero when a check fails. Run from the repository root with the bindings on the path:
    PYTHONPATH=build/release/python /usr/bin/python3 examples/inverse/finger_offset.py
"""

import sys

import numpy as np

import screwfem as sf

H, STEPS = 2e-3, 20                         # 40 ms, through the knots at 10, 20 and 30 ms
KNOTS = [0.0, 0.01, 0.02, 0.03, 0.04]
LENGTHS = [1.0, 0.998, 0.995, 0.994, 0.994]  # [m]
OFFSET = 0.02                               # [m]
TIP = 4


def finger(offset=OFFSET, lengths=LENGTHS, tension=None):
    """The finger (4 elements, clamped at x = 0, under a weak gravity along -z) with a length-driven tendon (or a
    tension-driven one pulling with `tension`) through eyelets `offset` off its axis."""
    b = sf.ModelBuilder()
    section = sf.Section([1e3, 1e3, 1e3, 1.0, 1.0, 1.0], [1e-2, 1e-2, 1e-2, 1e-6, 1e-6, 2e-6])
    b.add_straight_rod("finger", [0, 0, 0], [1, 0, 0], 4, section)
    b.fix_node(0)
    eyelets = [sf.BodyPoint(n, [0.0, offset, 0.0]) for n in range(5)]
    if tension is None:
        b.add_length_driven_tendon("pull", eyelets, sf.Profile.table(KNOTS, list(lengths)))
    else:
        b.add_tendon("pull", eyelets, sf.Profile.constant(tension))
    b.set_gravity([0.0, 0.0, -2.0])
    return sf.Simulation(sf.Scene(b.build(), "finger"))


def tight():
    """Newton converged to round-off (differences of whole runs divide by 1e-6)."""
    o = sf.DynamicOptions()
    o.increment_tolerance = 1e-14
    o.residual_tolerance = 1e-13
    return o


def tip_outputs():
    return [sf.SensitivityOutput(sf.OutputKind.POINT_POSITION, TIP, c) for c in range(3)]


def dynamics_check():
    sim = finger()
    knot = sf.Parameter(sf.ParameterKind.TENDON_LENGTH, 0, -1,
                        sf.Profile.table([0.0, 0.01, 0.02, 0.03], [0.0, 0.0, 1.0, 0.0]))
    offset = sf.Parameter(sf.ParameterKind.TENDON_OFFSET, 0, 1)
    params = [knot, offset]
    fwd = sf.dynamic_sensitivity(sim, params, tip_outputs(), H, STEPS, dynamics=tight())
    ok = fwd.restarts == 4
    d = 1e-6
    variants = [
        lambda s: finger(lengths=[v + (s * d if i == 2 else 0.0) for i, v in enumerate(LENGTHS)]),
        lambda s: finger(offset=OFFSET + s * d),
    ]
    for j, make in enumerate(variants):
        runs = [np.asarray(sf.dynamic_sensitivity(make(s), [], tip_outputs(), H, STEPS,
                                                   dynamics=tight()).values)
                for s in (1.0, -1.0)]
        fd = ((runs[0] - runs[1]) / (2 * d)).reshape(-1)
        exact = np.asarray(fwd.outputs)[:, j]
        error = np.abs(exact - fd).max() / np.abs(fd).max()
        print(f"{params[j]}: largest derivative {np.abs(fd).max():.3e}, error {error:.1e}")
        ok &= error < 1e-6
    rng = np.random.default_rng(1)
    weights = rng.uniform(-1, 1, (STEPS + 1, 3))
    f = sf.dynamic_sensitivity(sim, params, tip_outputs(), H, STEPS, weights)
    a = sf.dynamic_sensitivity(sim, params, tip_outputs(), H, STEPS, weights,
                               sf.SensitivityMode.ADJOINT)
    gap = np.abs(np.asarray(a.gradient) - f.gradient).max() / np.abs(f.gradient).max()
    print(f"adjoint gradient {np.asarray(a.gradient)}, forward {np.asarray(f.gradient)}: "
          f"relative gap {gap:.1e}")
    return ok and gap < 1e-10


def calibration_check():
    tensions = [5.0, 10.0, 15.0]
    truth, sigma = 0.0025, 2e-5
    rng = np.random.default_rng(7)
    cases = []
    for t in tensions:
        measured = finger(offset=OFFSET + truth, tension=t)
        measured.solve_static()
        tip = np.asarray(measured.node_frame(TIP))[:3, 3] + rng.normal(0.0, sigma, 3)
        cases.append(sf.CalibrationCase([sf.Parameter(sf.ParameterKind.TENDON_TENSION, 0)], [t],
                                        [sf.InverseTarget(TIP, [0, 0, 0], tip)]))
    model = finger(tension=0.0)
    r = sf.calibrate(model, [sf.Parameter(sf.ParameterKind.TENDON_OFFSET, 0, 1)], [0.0], cases)
    print(f"offset error {r.values[0] * 1e3:.4f} mm (true {truth * 1e3:.4f} mm), interval "
          f"[{r.lower[0] * 1e3:.4f}, {r.upper[0] * 1e3:.4f}] mm, {r.iterations} iterations")
    return r.converged and r.lower[0] <= truth <= r.upper[0] and r.standard_error[0] < 1e-4


def main():
    ok = dynamics_check()
    ok &= calibration_check()
    if not ok:
        print("FAILED", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
