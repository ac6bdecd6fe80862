"""Stepping a scene from Python: the rigid pendulum of tests/data/pendulum.yaml.

Shows load_scene, Simulation (initialize, step, joint and point outputs, energies) and the
NumPy views of the state. The link (0.2 kg, centre of mass 0.2 m from a revolute joint about
the world y axis) is released from the horizontal; with rho_inf = 1 (no numerical damping)
the example steps one period, prints the tip's world position and the energy every 0.1 s,
and compares the period with the closed form T = 4 K(1/2) / w0 (an elliptic integral). It
exits non-zero if the period or the energy is off by more than the integrator's O(h^2).

Run from the repository root with the bindings on the path:
    PYTHONPATH=build/release/python /usr/bin/python3 examples/python/pendulum.py [scene.yaml]
"""

import math
import pathlib
import sys

import numpy as np

import screwfem as sf

root = pathlib.Path(__file__).resolve().parents[2]
scene = sf.load_scene(sys.argv[1] if len(sys.argv) > 1 else str(root / "tests/data/pendulum.yaml"))
scene.analysis.rho_inf = 1.0
sim = sf.Simulation(scene)
sim.initialize()

# Closed-form period from the model's mass properties: w0 = sqrt(m g d / I_O).
body = scene.model.bodies[0]
d = float(np.linalg.norm(body.com))
pivot_inertia = body.inertia[1, 1] + body.mass * d * d
mgd = body.mass * -scene.model.gravity[2] * d
a, b = 1.0, math.sqrt(0.5)
for _ in range(40):
    a, b = 0.5 * (a + b), math.sqrt(a * b)
period = 4.0 * (math.pi / (2.0 * a)) / math.sqrt(mgd / pivot_inertia)

h = 5e-4
q = sim.q_joint  # a view: it follows the state as the simulation steps
e0 = sim.calc_energy().total()
print(f"{'t [s]':>7} {'angle [rad]':>12} {'tip x [m]':>10} {'tip z [m]':>10} {'energy [J]':>12}")
next_print, crossings, energy_error = 0.0, [], 0.0
while len(crossings) < 2:
    if sim.time >= next_print - 1e-9:
        tip = sim.point_motion("tip").position
        print(f"{sim.time:7.3f} {q[0]:12.6f} {tip[0]:10.6f} {tip[2]:10.6f} "
              f"{sim.calc_energy().total():12.3e}")
        next_print += 0.1
    t0, v0 = sim.time, sim.joint_velocity("hinge")
    sim.step(h)
    v1 = sim.joint_velocity("hinge")
    energy_error = max(energy_error, abs(sim.calc_energy().total() - e0) / mgd)
    if t0 > 0.25 * period and (v0 > 0.0) != (v1 > 0.0):  # turning points at T/2 and T
        crossings.append(t0 + h * v0 / (v0 - v1))

error = (crossings[1] - period) / period
print(f"period: {crossings[1]:.9f} s, closed form {period:.9f} s, relative error {error:.2e}")
print(f"largest energy error over the period: {energy_error:.2e} m g d "
      f"({sim.steps} steps, {sim.iterations} Newton iterations)")
bound = 0.15 * (math.sqrt(mgd / pivot_inertia) * h) ** 2
sys.exit(0 if abs(error) < bound and energy_error < bound else 1)
