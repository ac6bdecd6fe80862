"""Closed-loop control from Python: PID control of a soft arm's tip height.

The scene (soft_arm_control.yaml, next to this file) is a silicone rod clamped at its base that
sags under gravity, with a tendon along its top through an eyelet at every node. The tendon's
tension takes its value from the run-time input `u` ({type: input, name: u}, in newtons); a
tendon only pulls, so a negative u leaves it slack. Between steps the controller reads the tip
(Simulation.point_motion) and writes the input (sim.inputs["u"] = ...), as one writes MuJoCo's
data.ctrl; the engine holds the value over the next step.

The controller is a sampled PID on the tip height z with target Z_TARGET: u = Kp e + Ki int(e)
- Kd z_dot, e = Z_TARGET - z (the integral term cancels the arm's elastic and gravity forces
at the target). The example exits non-zero unless the tip settles at the target to within
0.5 mm and stays there over the last 0.5 s, and the settled input balances the arm: the
static solution under the settled tension puts the tip at the target too.

With --out DIR the controlled run is recorded (Simulation.record) into DIR: the files
`screwfem run` writes for the scene (points.csv, tendons.csv, summary.json, ParaView frames ...),
which `screwfem plot DIR` and `screwfem view DIR` read. The main job (scripts/run-main.sh) runs
it so into out/soft_arm_control/.

Run from the repository root with the bindings on the path (after the main job):
    PYTHONPATH=build/main/python /usr/bin/python3 examples/python/soft_arm_control.py \
        [--out out/soft_arm_control] [--force]
"""

import argparse
import contextlib
import pathlib
import sys

import screwfem as sf

HERE = pathlib.Path(__file__).resolve().parent
Z_TARGET = 0.02            # tip height to reach [m] (the tip sags to about -0.04 m unactuated)
KP, KI, KD = 800.0, 4000.0, 20.0  # [N/m], [N/(m s)], [N s/m]: tension per tip error
T_END = 2.0                # [s]


def actuate(sim, u):
    """The actuator: the tendon's tension (a joint torque or a load would take the same input)."""
    sim.inputs["u"] = u


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", help="record the controlled run into this folder")
    parser.add_argument("--force", action="store_true",
                        help="replace the results of an earlier run in --out")
    args = parser.parse_args(argv)

    scene = sf.load_scene(str(HERE / "soft_arm_control.yaml"))
    h = scene.analysis.step  # the scene's time step, the controller's sampling period [s]
    sim = sf.Simulation(scene)
    sim.initialize()
    integral, u, worst_late = 0.0, 0.0, 0.0
    print(f"{'t [s]':>6} {'tip z [m]':>10} {'u [N]':>8}")
    steps = int(round(T_END / h))
    recording = sim.record(args.out, force=args.force) if args.out else contextlib.nullcontext()
    with recording:
        for n in range(steps):
            tip = sim.point_motion("tip")
            z, z_dot = tip.position[2], tip.velocity[2]
            e = Z_TARGET - z
            integral += e * h
            u = KP * e + KI * integral - KD * z_dot
            actuate(sim, u)
            sim.step()  # the scene's next step, as `screwfem run` takes it
            if n % 100 == 0:
                print(f"{sim.time:6.2f} {z:10.5f} {u:8.4f}")
            if sim.time > T_END - 0.5:
                worst_late = max(worst_late,
                                 abs(sim.point_motion("tip").position[2] - Z_TARGET))
    if args.out:
        print(f"recorded into {args.out}: screwfem plot {args.out}; screwfem view {args.out}")
    z_end = sim.point_motion("tip").position[2]
    print(f"final tip height {z_end:.6f} m (target {Z_TARGET} m), input {u:.5f} N; "
          f"largest error over the last 0.5 s {worst_late:.2e} m")

    # The settled input, held constant in a static solution, holds the tip at the
    # target: the controller found the tension that balances the arm there.
    check = sf.Simulation(scene)
    check.inputs["u"] = u
    check.solve_static()
    z_static = check.point_motion("tip").position[2]
    print(f"static tip height under u = {u:.5f} N: {z_static:.6f} m")

    ok = worst_late < 5e-4 and abs(z_static - Z_TARGET) < 5e-4
    print("controller reached its target" if ok else "FAILED: the controller missed its target")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
