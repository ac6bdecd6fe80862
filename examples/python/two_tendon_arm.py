"""A tendon-driven continuum arm with two tendons, steered to sideways targets from Python.

The scene (two_tendon_arm.yaml, next to this file) is a silicone rod clamped at its base with a
tendon along each side (+y and -y, 9 mm from the axis) through an eyelet at every node; their
tensions are the run-time inputs `left` and `right` [N]. The controller is a sampled PID on the
tip's sideways position y that drives the pair antagonistically: a command c > 0 pulls the left
tendon, c < 0 the right one, each on top of a small pretension that keeps both taut,

    left = P + max(0, c),   right = P + max(0, -c),   c = Kp e + Ki int(e) - Kd y_dot,

with e = y_target - y. The target is Y_TARGETS[0] for the first half of the run and
Y_TARGETS[1] (the other side) for the second. The example exits non-zero unless the tip settles
within 1 mm of each target over the last 0.3 s of its phase, no tendon tension is ever negative,
and the settled tensions held constant in a static solution put the tip on the last target.

With --figure PATH (and Debian's python3-matplotlib) it draws the tip's path against the targets,
the two tensions over time, and the arm's centreline at the end of each phase (seen from above).

Run from the repository root with the bindings on the path:
    PYTHONPATH=build/release/python /usr/bin/python3 examples/python/two_tendon_arm.py \\
        --figure two_tendon_arm.png
"""

import argparse
import pathlib
import sys

import screwfem as sf

HERE = pathlib.Path(__file__).resolve().parent
Y_TARGETS = (0.05, -0.04)          # sideways tip targets [m], one per half of the run
PRETENSION = 0.5                   # [N] on both tendons
KP, KI, KD = 800.0, 4000.0, 20.0   # [N/m], [N/(m s)], [N s/m]
H = 2e-3                           # time step [s] (the controller's sampling period)
T_END = 2.0                        # [s]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--figure", help="write the figure (PNG) to this path")
    args = parser.parse_args()

    scene = sf.load_scene(str(HERE / "two_tendon_arm.yaml"))
    sim = sf.Simulation(scene)
    sim.initialize()
    steps = int(round(T_END / H))
    half = steps // 2
    integral = 0.0
    history = []          # (t, y, target, left, right)
    shapes = []           # the arm's centreline at the end of each phase
    worst = [0.0, 0.0]    # largest |e| over the last 0.3 s of each phase
    min_tension = 0.0
    left = right = PRETENSION
    for n in range(steps):
        phase = 0 if n < half else 1
        target = Y_TARGETS[phase]
        tip = sim.point_motion("tip")
        y, y_dot = tip.position[1], tip.velocity[1]
        e = target - y
        integral += e * H
        c = KP * e + KI * integral - KD * y_dot
        left, right = PRETENSION + max(0.0, c), PRETENSION + max(0.0, -c)
        sim.inputs["left"] = left
        sim.inputs["right"] = right
        sim.step(H)
        tip = sim.point_motion("tip")
        tensions = (sim.tendon_state("left")[2], sim.tendon_state("right")[2])
        min_tension = min(min_tension, *tensions)
        history.append((sim.time, tip.position[1], target, *tensions))
        phase_end = (phase + 1) * half * H
        if sim.time > phase_end - 0.3:
            worst[phase] = max(worst[phase], abs(tip.position[1] - target))
        if n + 1 in (half, steps):
            shapes.append(sim.rod_centerline("arm").copy())
        if n % 100 == 0:
            print(f"t {sim.time:5.2f} s  tip y {tip.position[1]:+.5f} m  "
                  f"left {tensions[0]:7.3f} N  right {tensions[1]:7.3f} N")

    # The settled tensions, held constant in a static solution, hold the tip on the last target.
    check = sf.Simulation(scene)
    check.inputs["left"] = left
    check.inputs["right"] = right
    check.solve_static()
    y_static = check.point_motion("tip").position[1]
    print(f"largest error over the last 0.3 s of each phase: {worst[0]:.2e} m, {worst[1]:.2e} m; "
          f"static tip y under the settled tensions {y_static:+.5f} m")

    if args.figure:
        write_figure(args.figure, history, shapes)

    ok = (max(worst) < 1e-3 and min_tension >= 0.0 and abs(y_static - Y_TARGETS[1]) < 1e-3)
    print("the arm reached both targets" if ok else "FAILED: the arm missed a target")
    return 0 if ok else 1


def write_figure(path, history, shapes):
    try:
        import matplotlib
    except ImportError:
        print("no figure: matplotlib is not installed (Debian: python3-matplotlib)")
        return
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = [row[0] for row in history]
    fig, (ax_y, ax_t, ax_shape) = plt.subplots(1, 3, figsize=(14, 4.2))
    ax_y.plot(t, [row[1] * 1e3 for row in history], label="tip y")
    ax_y.plot(t, [row[2] * 1e3 for row in history], "--", label="target")
    ax_y.set(xlabel="t [s]", ylabel="tip y [mm]", title="tip towards the targets")
    ax_y.legend()
    ax_t.plot(t, [row[3] for row in history], label="left tendon (+y)")
    ax_t.plot(t, [row[4] for row in history], label="right tendon (-y)")
    ax_t.set(xlabel="t [s]", ylabel="tension [N]", title="tendon tensions")
    ax_t.legend()
    for shape, target, label in zip(shapes, Y_TARGETS, ("end of phase 1", "end of phase 2")):
        line, = ax_shape.plot(shape[:, 0] * 1e3, shape[:, 1] * 1e3, "o-", label=label)
        ax_shape.axhline(target * 1e3, color=line.get_color(), linestyle=":")
    ax_shape.set(xlabel="x [mm]", ylabel="y [mm]", title="arm seen from above (targets dotted)")
    ax_shape.set_aspect("equal", adjustable="datalim")
    ax_shape.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    print(f"wrote {path}")


if __name__ == "__main__":
    sys.exit(main())
