"""Tests of the Python bindings (python/): physics through the bindings, not just calls.

Run by ctest (python/CMakeLists.txt, test python_bindings) as
    /usr/bin/python3 -m unittest -v test_bindings
from tests/python with PYTHONPATH=<build>/python. SCREWFEM_TEST_DATA_DIR names tests/data (the
default is the directory next to this one).

The pendulum (tests/data/pendulum.yaml) is a rigid link of mass m = 0.2 kg with its centre of
mass at d = 0.2 m from a revolute joint about the world y axis, released at rest from the
horizontal under g = 9.81 m/s^2 along -z. Its pivot inertia is I_O = J_yy + m d^2 and
w0 = sqrt(m g d / I_O). The joint angle alpha rotates the link about +y, so the tip E = (0.4,
0, 0) moves to (0.4 cos alpha, 0, -0.4 sin alpha) and the link hangs down at alpha = pi/2.
Exact period for the amplitude pi/2: T = 4 K(k^2) / w0 with k = sin(pi/4), K the complete
elliptic integral of the first kind (by the arithmetic-geometric mean).
"""

import contextlib
import csv
import json
import math
import os
import pathlib
import re
import signal
import tempfile
import unittest

import numpy as np

import screwfem as sf

DATA_DIR = pathlib.Path(
    os.environ.get("SCREWFEM_TEST_DATA_DIR", pathlib.Path(__file__).resolve().parents[1] / "data"))
PENDULUM = str(DATA_DIR / "pendulum.yaml")
TIP = np.array([0.4, 0.0, 0.0])  # point E in the link's frame [m]


def elliptic_k(m):
    """Complete elliptic integral of the first kind K(m), m = k^2 < 1 (AGM, converged)."""
    a, b = 1.0, math.sqrt(1.0 - m)
    for _ in range(40):  # quadratic convergence: exact to round-off long before 40 rounds
        a, b = 0.5 * (a + b), math.sqrt(a * b)
    return math.pi / (2.0 * a)


def pendulum_constants(model):
    """(m, d, I_O, g, w0) of the pendulum, read from the compiled model."""
    body = model.bodies[0]
    m = body.mass
    d = float(np.linalg.norm(body.com))
    inertia_pivot = body.inertia[1, 1] + m * d * d
    g = -model.gravity[2]
    return m, d, inertia_pivot, g, math.sqrt(m * g * d / inertia_pivot)


def rotation_y(angle):
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def undamped(sim):
    """Initializes with rho_inf = 1 (no numerical damping)."""
    options = sf.DynamicOptions()
    options.rho_inf = 1.0
    sim.initialize(options)


_SWINGS = {}


def swing(h):
    """One period of the undamped pendulum with step h: the times of the zero crossings of
    the joint rate at T/2 and T (linear interpolation over the bracketing step; its error is
    O(h^3) because d^2(alpha_dot)/dt^2 vanishes at a turning point) and the largest energy
    error |E(t) - E(0)| [J]. Cached: the period and energy tests share the runs."""
    if h not in _SWINGS:
        sim = sf.Simulation(sf.load_scene(PENDULUM))
        undamped(sim)
        _, _, _, _, w0 = pendulum_constants(sim.model)
        period = 4.0 * elliptic_k(0.5) / w0
        e0 = sim.calc_energy().total()
        crossings, energy_error = [], 0.0
        while len(crossings) < 2 and sim.time < 1.2 * period:
            t0, v0 = sim.time, sim.joint_velocity("hinge")
            sim.step(h)
            v1 = sim.joint_velocity("hinge")
            energy_error = max(energy_error, abs(sim.calc_energy().total() - e0))
            if t0 > 0.25 * period and (v0 > 0.0) != (v1 > 0.0):
                crossings.append(t0 + h * v0 / (v0 - v1))
        _SWINGS[h] = (crossings, energy_error)
    return _SWINGS[h]


def read_csv(path):
    """{t: row values} of a points.csv / joints.csv (shortest round-trip text: exact doubles)."""
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    return rows[0], {float(r[0]): np.array([float(x) for x in r[1:]]) for r in rows[1:]}


class SceneAndModelTest(unittest.TestCase):
    def test_load_scene_compiles_the_pendulum(self):
        scene = sf.load_scene(PENDULUM)
        self.assertEqual(scene.name, "pendulum")
        self.assertEqual(scene.source, PENDULUM)
        model = scene.model
        # One free node (6 body-velocity components) and one revolute coordinate; the joint
        # adds its 6 relative-frame constraint rows.
        self.assertEqual((model.nv, model.nv_nodes, model.nc), (7, 6, 6))
        self.assertEqual(model.num_unknowns(), 13)
        self.assertEqual((model.num_nodes, model.num_elements, model.num_rods), (1, 0, 0))
        self.assertEqual((model.num_bodies, model.num_joints), (1, 1))
        np.testing.assert_array_equal(model.gravity, [0.0, 0.0, -9.81])
        body = model.bodies[0]
        self.assertEqual(body.name, "link")
        self.assertEqual(body.mass, 0.2)
        np.testing.assert_array_equal(body.com, [0.2, 0.0, 0.0])  # midpoint of O, E
        np.testing.assert_array_equal(body.inertia, np.diag([1e-4, 2.7e-3, 2.7e-3]))

    def test_entities_and_lookups_by_name(self):
        model = sf.load_scene(PENDULUM).model
        self.assertEqual(model.find_joint("hinge"), 0)
        self.assertEqual(model.find_joint("hinj"), -1)
        self.assertEqual(model.find_body("link"), 0)
        node = model.nodes[model.bodies[0].node]
        self.assertEqual(model.find_node(node.name), model.bodies[0].node)
        self.assertFalse(node.fixed)
        np.testing.assert_array_equal(node.reference, np.eye(4))  # at O, world-aligned
        joint = model.joints[0]
        self.assertEqual(joint.name, "hinge")
        self.assertEqual(joint.type, sf.JointType.REVOLUTE)
        self.assertEqual(sf.joint_type_name(joint.type), "revolute")
        self.assertEqual((joint.node_a, joint.node_b), (sf.kGround, 0))
        self.assertEqual((joint.k(), joint.coord, joint.row), (1, 6, 0))
        self.assertEqual(joint.drive, sf.DriveKind.NONE)
        np.testing.assert_array_equal(joint.basis[:, 0], [0, 0, 0, 0, 1, 0])  # rotation about y

    def test_analysis_settings_are_readable_and_writable(self):
        scene = sf.load_scene(PENDULUM)
        a = scene.analysis
        self.assertEqual(a.kind, sf.AnalysisKind.DYNAMIC)
        self.assertEqual((a.start_time, a.end_time, a.step, a.rho_inf), (0.0, 0.5, 1e-3, 0.9))
        a.end_time, a.step, a.rho_inf = 0.25, 5e-4, 1.0
        self.assertEqual((scene.analysis.end_time, scene.analysis.step), (0.25, 5e-4))
        self.assertEqual(scene.analysis.dynamic.rho_inf, 1.0)  # rho_inf is dynamic.rho_inf
        scene.analysis.dynamic.max_iterations = 7
        self.assertEqual(scene.analysis.dynamic.max_iterations, 7)

    def test_overrides_are_applied_before_compilation(self):
        scene = sf.load_scene(PENDULUM, ["analysis.step=5e-4", "bodies.link.mass=0.3"])
        self.assertEqual(scene.analysis.step, 5e-4)
        self.assertEqual(scene.model.bodies[0].mass, 0.3)
        self.assertEqual([p.name for p in scene.outputs.points], ["tip"])
        self.assertEqual([j.name for j in scene.outputs.joints], ["hinge"])


class InputErrorTest(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.TemporaryDirectory()
        with open(PENDULUM) as f:
            self.text = f.read()

    def tearDown(self):
        self.dir.cleanup()

    def write(self, text):
        path = os.path.join(self.dir.name, "bad.yaml")
        with open(path, "w") as f:
            f.write(text)
        return path

    def location(self, text, needle):
        """1-based (line, column) of the first occurrence of needle."""
        for number, line in enumerate(text.splitlines(), start=1):
            if needle in line:
                return number, line.index(needle) + 1
        raise AssertionError(needle)

    def test_unknown_key_raises_input_error_with_file_line_and_column(self):
        text = self.text.replace("mass: 0.2", "mas: 0.2")
        path = self.write(text)
        line, column = self.location(text, "mas: 0.2")
        with self.assertRaises(sf.InputError) as caught:
            sf.load_scene(path)
        self.assertIsInstance(caught.exception, ValueError)
        self.assertEqual(
            str(caught.exception),
            f"{path}:{line}:{column}: bodies.link.mas: unknown key 'mas' (did you mean 'mass'?)")

    def test_invalid_value_names_the_field_at_its_line(self):
        text = self.text.replace("mass: 0.2", "mass: -0.2")
        path = self.write(text)
        line, _ = self.location(text, "mass: -0.2")
        with self.assertRaisesRegex(sf.InputError,
                                    "^" + re.escape(f"{path}:{line}:") + r"\d+: bodies\.link\.mass: "):
            sf.load_scene(path)

    def test_parse_scene_and_overrides_report_their_source(self):
        with self.assertRaisesRegex(sf.InputError, r"^inline\.yaml:\d+:\d+: "):
            sf.parse_scene(self.text.replace("axis: [0, 1, 0]", "axis: [0, 2, 0]"), "inline.yaml")
        with self.assertRaisesRegex(
                sf.InputError, re.escape(f"{PENDULUM}: override 'analysis.stepp=1e-3': analysis.stepp")):
            sf.load_scene(PENDULUM, ["analysis.stepp=1e-3"])

    def test_linear_solver_choice_and_counters(self):
        # The scene key and its counters (docs/numerics.md, "Sparse direct solve"): the
        # pendulum stays banded under auto; sparse gives the same motion, one symbolic
        # analysis and a factorisation per simplified-Newton step.
        runs = {}
        for solver in ("auto", "banded", "sparse"):
            scene = sf.load_scene(PENDULUM, [f"analysis.linear_solver={solver}"])
            self.assertEqual(scene.model.linear_solver, getattr(sf.LinearSolver, solver.upper()))
            self.assertEqual(scene.model.sparse_solver, solver == "sparse")
            self.assertGreater(scene.model.banded_flops, 0.0)
            # The costs auto compares: no contact coupling; the sparse one infinite unless
            # the pattern was analysed.
            self.assertEqual(scene.model.coupled_nodes, 0)
            self.assertEqual(scene.model.coupling_flops, 0.0)
            self.assertEqual(scene.model.banded_cost, scene.model.banded_flops)
            if solver == "sparse":
                self.assertAlmostEqual(
                    scene.model.sparse_cost,
                    4.0 * scene.model.sparse_flops + 200.0 * (scene.model.nv + scene.model.nc))
            else:
                self.assertEqual(scene.model.sparse_cost, float("inf"))
            sim = sf.Simulation(scene)
            sim.initialize(sf.DynamicOptions())
            for _ in range(20):
                sim.step(1e-3)
            runs[solver] = (sim.joint_coordinate("hinge"), sim.symbolic_analyses,
                            sim.sparse_factorizations, sim.factorizations, sim.sparse_fallbacks)
            # No contact pairs: the pattern never changes (docs/numerics.md, "Pairs and the
            # sparse pattern").
            self.assertEqual((sim.sparse_pattern_changes, sim.sparse_pattern_hits), (0, 0))
        self.assertEqual(runs["auto"][1:3], (0, 0))
        self.assertAlmostEqual(runs["sparse"][0], runs["banded"][0], delta=1e-12)
        self.assertEqual(runs["sparse"][1], 1)
        self.assertGreaterEqual(runs["sparse"][2], runs["sparse"][3])
        self.assertGreater(runs["sparse"][3], 0)
        self.assertEqual(runs["sparse"][4], 0)
        spec = sf.SceneSpec()
        spec.set_analysis(linear_solver="sparse")
        self.assertEqual(spec.linear_solver, sf.LinearSolver.SPARSE)
        with self.assertRaisesRegex(sf.InputError, "analysis.linear_solver"):
            spec.set_analysis(linear_solver="dense")
        builder = sf.ModelBuilder()
        builder.set_linear_solver(sf.LinearSolver.BANDED)

    def test_newton_variants_reach_the_same_state(self):
        # Full Newton from vdot = 0 against the defaults (simplified Newton, adaptive start):
        # the same solution, with fewer factorisations than iterations for the defaults.
        runs = []
        for newton, predictor in ((sf.NewtonMatrix.FULL, sf.Predictor.ZERO),
                                  (sf.NewtonMatrix.SIMPLIFIED, sf.Predictor.ADAPTIVE)):
            sim = sf.Simulation(sf.load_scene(PENDULUM))
            options = sf.DynamicOptions()
            options.newton_matrix = newton
            options.predictor = predictor
            sim.initialize(options)
            for _ in range(100):
                sim.step(1e-3)
            runs.append((sim.joint_coordinate("hinge"), sim.factorizations, sim.iterations))
        # Measured convergence tests (a residual at every accepted iterate): the same state,
        # and no step accepted by estimate.
        sim = sf.Simulation(sf.load_scene(PENDULUM))
        options = sf.DynamicOptions()
        self.assertEqual(options.convergence, sf.ConvergenceTest.ESTIMATED)
        options.convergence = sf.ConvergenceTest.MEASURED
        sim.initialize(options)
        for _ in range(100):
            sim.step(1e-3)
        self.assertAlmostEqual(sim.joint_coordinate("hinge"), runs[1][0], delta=1e-9)
        self.assertEqual(sim.estimated_convergences, 0)
        self.assertAlmostEqual(runs[0][0], runs[1][0], delta=1e-9)
        self.assertEqual(runs[0][1], runs[0][2])
        self.assertLess(runs[1][1], runs[1][2])
        options = sf.DynamicOptions()
        options.refresh_ratio = 1.0
        with self.assertRaisesRegex(sf.InputError, "refresh_ratio"):
            sf.Simulation(sf.load_scene(PENDULUM)).initialize(options)

    def test_misuse_of_a_simulation_raises(self):
        sim = sf.Simulation(sf.load_scene(PENDULUM))
        with self.assertRaisesRegex(RuntimeError, "initialize"):
            sim.step(1e-3)
        options = sf.DynamicOptions()
        options.rho_inf = 1.5
        with self.assertRaisesRegex(sf.InputError, "rho_inf"):
            sim.initialize(options)
        sim.initialize()
        for h in (0.0, -1e-3, math.nan, math.inf):
            with self.assertRaises(sf.InputError):
                sim.step(h)
        with self.assertRaises(IndexError):
            sim.node_frame(1)
        with self.assertRaises(IndexError):
            sim.joint_coordinate("hinge", 1)
        with self.assertRaises(KeyError):
            sim.joint_coordinate("hinj")
        with self.assertRaises(KeyError):
            sim.point_motion("top")
        with self.assertRaises(sf.InputError):
            sim.v = np.zeros(3)


class NumpyArraysTest(unittest.TestCase):
    def test_state_arrays_have_the_model_sizes(self):
        sim = sf.Simulation(sf.load_scene(PENDULUM))
        model = sim.model
        for name, size in (("v", model.nv), ("vdot", model.nv), ("lambda_", model.nc),
                           ("q_joint", model.nv - model.nv_nodes)):
            array = getattr(sim, name)
            self.assertEqual(array.shape, (size,), name)
            self.assertEqual(array.dtype, np.float64, name)
        self.assertEqual(sim.node_frame(0).shape, (4, 4))
        self.assertEqual(sim.joint_relative_frame("hinge").shape, (4, 4))
        self.assertEqual(sim.calc_point_row().shape, (13,))  # x, v, a, orientation quaternion
        self.assertEqual(len(sim.point_columns()), 13)
        self.assertEqual(sim.calc_joint_row().shape, (4,))
        self.assertEqual(sim.joint_columns(), ["hinge.q", "hinge.qd", "hinge.qdd", "hinge.effort"])
        motion = sim.point_motion("tip")
        for v in (motion.position, motion.velocity, motion.acceleration):
            self.assertEqual(v.shape, (3,))

    def test_arrays_are_views_of_the_simulation_state(self):
        sim = sf.Simulation(sf.load_scene(PENDULUM))
        sim.initialize()
        v, vdot, lam, q = sim.v, sim.vdot, sim.lambda_, sim.q_joint
        for array in (v, vdot, lam):  # writable: the state is set from Python
            self.assertTrue(array.flags.writeable)
        self.assertFalse(q.flags.writeable)
        for _ in range(20):
            sim.step(1e-3)
        # The arrays taken before stepping show the state after it, without a copy.
        for name, array in (("v", v), ("vdot", vdot), ("lambda_", lam), ("q_joint", q)):
            self.assertTrue(np.shares_memory(array, getattr(sim, name)), name)
            np.testing.assert_array_equal(array, getattr(sim, name))
        self.assertNotEqual(q[0], 0.0)
        self.assertEqual(q[0], sim.joint_coordinate("hinge"))
        # A view keeps its simulation alive.
        del sim
        self.assertEqual(q.shape, (1,))
        self.assertTrue(np.isfinite(v).all())

    def test_writing_v_sets_the_initial_velocities(self):
        sim = sf.Simulation(sf.load_scene(PENDULUM))
        rate = 2.0  # [rad/s] about the hinge: node body rotation rate w_y and the joint rate
        sim.v = np.array([0, 0, 0, 0, rate, 0, rate])
        sim.initialize()
        m, d, inertia_pivot, g, _ = pendulum_constants(sim.model)
        energy = sim.calc_energy()
        self.assertAlmostEqual(energy.kinetic, 0.5 * inertia_pivot * rate ** 2, delta=1e-15)
        # The tip moves with w x r = (0, rate, 0) x (0.4, 0, 0) = (0, 0, -0.4 rate).
        np.testing.assert_allclose(sim.point_motion("tip").velocity, [0, 0, -0.4 * rate],
                                   rtol=0, atol=1e-15)


class PendulumDynamicsTest(unittest.TestCase):
    def test_initial_acceleration_is_the_gravity_torque_over_the_pivot_inertia(self):
        sim = sf.Simulation(sf.load_scene(PENDULUM))
        sim.initialize()
        m, d, inertia_pivot, g, _ = pendulum_constants(sim.model)
        alpha_ddot = m * g * d / inertia_pivot
        self.assertAlmostEqual(sim.joint_acceleration("hinge") / alpha_ddot, 1.0, delta=1e-12)
        # Tip acceleration w' x r = (0, alpha_ddot, 0) x (0.4, 0, 0) in the world frame.
        np.testing.assert_allclose(sim.point_motion("tip").acceleration,
                                   [0.0, 0.0, -0.4 * alpha_ddot], rtol=0, atol=1e-11)

    def test_period_matches_the_closed_form_at_second_order(self):
        # Generalized-alpha with rho_inf = 1 has a phase error O((w0 h)^2); its measured
        # coefficient here is 0.057 (h = 1e-3: relative period error 2.1e-6).
        _, _, _, _, w0 = pendulum_constants(sf.load_scene(PENDULUM).model)
        period = 4.0 * elliptic_k(0.5) / w0
        errors = []
        for h in (1e-3, 5e-4):
            (half, full), _ = swing(h)
            error = (full - period) / period
            self.assertLess(abs(error), 0.1 * (w0 * h) ** 2, f"h = {h}: period error {error}")
            self.assertLess(abs((2.0 * half - period) / period), 0.1 * (w0 * h) ** 2)
            errors.append(error)
        self.assertGreater(errors[0] / errors[1], 3.8)
        self.assertLess(errors[0] / errors[1], 4.2)
        # Richardson extrapolation removes the h^2 term.
        richardson = (4.0 * errors[1] - errors[0]) / 3.0
        self.assertLess(abs(richardson), 1e-8)

    def test_energy_is_conserved_to_second_order_without_numerical_damping(self):
        # The largest energy error over a period is O((w0 h)^2) (coefficient measured 0.083 of
        # m g d) and it does not drift: halving h divides it by 4.
        m, d, _, g, w0 = pendulum_constants(sf.load_scene(PENDULUM).model)
        errors = [swing(h)[1] / (m * g * d) for h in (1e-3, 5e-4)]
        for h, error in zip((1e-3, 5e-4), errors):
            self.assertLess(error, 0.15 * (w0 * h) ** 2, f"h = {h}")
        self.assertGreater(errors[0] / errors[1], 3.8)
        self.assertLess(errors[0] / errors[1], 4.2)

    def test_perturbed_start_is_applied_on_a_smooth_pendulum(self):
        # DynamicOptions.perturbed_start perturbs the start where the step resolves the change
        # of the acceleration (docs/numerics.md, "When the perturbed start is left out"): on the
        # pendulum swinging through the horizontal it is applied, so the skip counter stays 0
        # and the motion differs from the plain start's at rho_inf = 0.8 (by the start's
        # (alpha_m - alpha_f) h times the acceleration's rate, which is not zero here).
        angles = []
        for perturbed in (False, True):
            sim = sf.Simulation(sf.load_scene(PENDULUM, ["joints.hinge.initial_velocity=2"]))
            options = sf.DynamicOptions()
            options.rho_inf = 0.8
            options.perturbed_start = perturbed
            sim.initialize(options)
            for _ in range(50):
                sim.step(1e-3)
            self.assertEqual(sim.perturbed_start_skips, 0)
            angles.append(sim.joint_coordinate("hinge"))
        # 2.3e-11 rad after 50 steps; a skipped perturbation repeats the plain run bit for bit.
        self.assertGreater(abs(angles[1] - angles[0]), 1e-13)
        self.assertLess(abs(angles[1] - angles[0]), 1e-4 * abs(angles[0]))

    def test_numerical_damping_dissipates_energy_when_rho_inf_is_below_one(self):
        sim = sf.Simulation(sf.load_scene(PENDULUM, ["analysis.rho_inf=0"]))
        sim.initialize()
        m, d, _, g, _ = pendulum_constants(sim.model)
        for _ in range(1000):
            sim.step(1e-3)
        self.assertLess(sim.calc_energy().total(), -1e-6 * m * g * d)

    def test_advance_to_lands_on_the_quarter_period_with_error_controlled_steps(self):
        sim = sf.Simulation(sf.load_scene(PENDULUM))
        options = sf.DynamicOptions()
        options.rho_inf = 1.0
        options.absolute_tolerance = options.relative_tolerance = 1e-8
        options.initial_step = 1e-4
        sim.initialize(options)
        m, d, inertia_pivot, g, w0 = pendulum_constants(sim.model)
        quarter = elliptic_k(0.5) / w0
        # Two output times: the controller keeps its step between the calls.
        sim.advance_to(0.5 * quarter)
        self.assertEqual(sim.time, 0.5 * quarter)
        result = sim.advance_to(quarter)
        self.assertTrue(result.ok)
        self.assertEqual(sim.time, quarter)
        # At the bottom alpha = pi/2 and I_O alpha_dot^2 / 2 = m g d.
        self.assertAlmostEqual(sim.joint_coordinate("hinge"), math.pi / 2, delta=1e-5)
        rate = math.sqrt(2.0 * m * g * d / inertia_pivot)
        self.assertAlmostEqual(abs(sim.joint_velocity("hinge")), rate, delta=1e-5 * rate)
        history = sim.step_history
        self.assertEqual(history["accepted"], sim.steps)
        self.assertAlmostEqual(history["mean_step"] * history["accepted"], quarter, delta=1e-12)
        self.assertLessEqual(history["min_step"], history["mean_step"])
        self.assertGreater(history["max_step"], history["mean_step"])
        self.assertLessEqual(sim.error_norm, 1.0)
        self.assertGreaterEqual(sim.rejected_steps, 0)
        # Fewer steps than the fixed step of the same accuracy (5e-4, the test below).
        self.assertLess(sim.steps, quarter / 5e-4)
        options.min_step = 0.0
        with self.assertRaises(sf.InputError):
            sim.initialize(options)

    def test_tip_is_at_the_bottom_with_the_energy_speed_after_a_quarter_period(self):
        sim = sf.Simulation(sf.load_scene(PENDULUM))
        undamped(sim)
        m, d, inertia_pivot, g, w0 = pendulum_constants(sim.model)
        quarter = elliptic_k(0.5) / w0
        h = 5e-4
        while sim.time < quarter - h:
            sim.step(h)
        sim.step(quarter - sim.time)
        self.assertAlmostEqual(sim.time, quarter, delta=1e-15)
        motion = sim.point_motion("tip")
        # At the bottom alpha = pi/2 and I_O alpha_dot^2 / 2 = m g d.
        rate = math.sqrt(2.0 * m * g * d / inertia_pivot)
        speed = 0.4 * rate
        # The relative phase error of the period test, 0.1 (w0 h)^2, turns into an angle error
        # of rate * quarter * phase at the bottom; the tip moves by 0.4 m times it and its
        # velocity turns by it (the speed is stationary there; its O(h^2) energy error is
        # smaller).
        angle_tolerance = rate * quarter * 0.1 * (w0 * h) ** 2
        self.assertAlmostEqual(sim.joint_coordinate("hinge"), math.pi / 2, delta=angle_tolerance)
        np.testing.assert_allclose(motion.position, [0.0, 0.0, -0.4], rtol=0,
                                   atol=0.4 * angle_tolerance)
        np.testing.assert_allclose(motion.velocity, [-speed, 0.0, 0.0], rtol=0,
                                   atol=speed * angle_tolerance)

    def test_frames_points_and_joint_coordinates_agree(self):
        sim = sf.Simulation(sf.load_scene(PENDULUM))
        sim.initialize()
        for _ in range(150):
            sim.step(1e-3)
        alpha = sim.joint_coordinate("hinge")
        rate = sim.joint_velocity("hinge")
        accel = sim.joint_acceleration("hinge")
        frame = sim.node_frame("link")
        np.testing.assert_allclose(frame[:3, :3], rotation_y(alpha), rtol=0, atol=1e-12)
        np.testing.assert_allclose(frame[:3, 3], 0.0, rtol=0, atol=1e-12)  # the pivot stays
        np.testing.assert_allclose(sim.joint_relative_frame("hinge")[:3, :3], rotation_y(alpha),
                                   rtol=0, atol=1e-12)
        r = rotation_y(alpha) @ TIP  # world vector from the pivot to the tip
        w, w_dot = np.array([0.0, rate, 0.0]), np.array([0.0, accel, 0.0])
        motion = sim.calc_node_point_motion("link", TIP)
        np.testing.assert_allclose(motion.position, r, rtol=0, atol=1e-12)
        np.testing.assert_allclose(motion.velocity, np.cross(w, r), rtol=0, atol=1e-11)
        # The joint's and the node's accelerations are separate unknowns of the Newton solve,
        # consistent to its stopping test (amplified by 1/(beta h^2) in vdot), not to round-off.
        np.testing.assert_allclose(motion.acceleration,
                                   np.cross(w_dot, r) + np.cross(w, np.cross(w, r)),
                                   rtol=1e-8, atol=0)
        np.testing.assert_array_equal(sim.point_motion("tip").position, motion.position)
        self.assertLess(sim.max_constraint_violation(), 1e-12)

    def test_stepping_from_python_reproduces_run_scene_outputs(self):
        scene = sf.load_scene(PENDULUM)
        scene.outputs.vtk = False
        with tempfile.TemporaryDirectory() as outdir:
            result = sf.run_scene(scene, outdir)
            point_header, points = read_csv(os.path.join(outdir, "points.csv"))
            joint_header, joints = read_csv(os.path.join(outdir, "joints.csv"))
        self.assertTrue(result.ok, result.message)
        self.assertEqual(result.message, "")
        self.assertEqual(result.steps, 500)
        self.assertAlmostEqual(result.end_time, 0.5, delta=1e-12)
        self.assertEqual(len(points), 51)  # t = 0, 0.01, ..., 0.5
        # The same loop as run_scene: the scene's settings and its step schedule.
        sim = sf.Simulation(scene)
        sim.initialize()
        self.assertEqual(point_header[1:], sim.point_columns())
        self.assertEqual(joint_header[1:], sim.joint_columns())
        a = scene.analysis
        schedule = sf.StepSchedule(a.start_time, a.end_time, a.step,
                                   sf.profile_breakpoints(scene.model))
        compared = 0
        largest = 0.0

        def compare():
            nonlocal compared, largest
            if sim.time in points:
                largest = max(largest, np.abs(sim.calc_point_row() - points[sim.time]).max(),
                              np.abs(sim.calc_joint_row() - joints[sim.time]).max())
                compared += 1

        compare()
        while not schedule.done(sim.time):
            t_next = schedule.next(sim.time)
            sim.step(t_next - sim.time)
            sim.time = t_next
            compare()
        self.assertEqual(compared, len(points))
        self.assertLessEqual(largest, 1e-12)
        self.assertEqual((sim.steps, sim.iterations, sim.halvings),
                         (result.steps, result.newton_iterations, result.halvings))
        self.assertLess(result.max_constraint_residual, 1e-10)

    def test_failed_step_raises_solver_error_and_keeps_the_state(self):
        sim = sf.Simulation(sf.load_scene(PENDULUM))
        options = sf.DynamicOptions()
        options.max_iterations, options.max_halvings = 1, 0
        sim.initialize(options)
        v = sim.v.copy()
        with self.assertRaises(sf.SolverError) as caught:
            sim.step(1e-2)
        self.assertIsInstance(caught.exception, RuntimeError)
        self.assertFalse(caught.exception.result.ok)
        self.assertIn("step failed at t = 0 s", str(caught.exception))
        self.assertEqual(caught.exception.result.message, str(caught.exception))
        self.assertEqual(sim.time, 0.0)
        np.testing.assert_array_equal(sim.v, v)
        np.testing.assert_array_equal(sim.node_frame(0), np.eye(4))


class ModelBuilderTest(unittest.TestCase):
    """ModelBuilder from Python: rods along a polyline, the node at a point, joints in one call."""

    def test_rod_along_a_bent_path_has_bisector_frames_at_the_corner(self):
        b = sf.ModelBuilder()
        section = sf.Section(np.ones(6), np.ones(6))
        rod = b.add_rod_along_path("L", [[0, 0, 0], [2, 0, 0], [2, 1, 0]], 2, section)
        model = b.build()
        frames = [model.nodes[n].reference for n in model.rods[rod].nodes]
        positions = [[0, 0, 0], [1, 0, 0], [2, 0, 0], [2, 0.5, 0], [2, 1, 0]]
        c = math.sqrt(0.5)
        tangents = [[1, 0, 0], [1, 0, 0], [c, c, 0], [0, 1, 0], [0, 1, 0]]
        for H, x, t in zip(frames, positions, tangents):
            np.testing.assert_allclose(H[:3, 3], x, rtol=0, atol=1e-15)
            np.testing.assert_allclose(H[:3, 0], t, rtol=0, atol=1e-15)  # section axis
            np.testing.assert_allclose(H[:3, 2], [0, 0, 1], rtol=0, atol=1e-15)  # up
        # The two elements at the corner are arcs, longer than their chords.
        self.assertGreater(model.rods[rod].length, 3.0)

    def test_find_node_at_finds_the_node_two_welded_rods_share(self):
        b = sf.ModelBuilder()
        section = sf.Section(np.ones(6), np.ones(6))
        b.add_rod_along_path("a", [[0, 0, 0], [1, 0, 0]], 4, section)
        shared = b.find_node_at([1, 0, 0], rod=0).node
        self.assertGreaterEqual(shared, 0)
        b.add_rod_along_path("c", [[1, 0, 0], [2, 0, 0], [2, 1, 0]], 3, section,
                             start_node=shared)
        self.assertEqual(b.find_node_at([1, 0, 0]).node, shared)
        self.assertEqual(b.find_node_at([1, 0, 0], rod=1).node, shared)
        miss = b.find_node_at([0.1, 0, 0], rod=0)
        self.assertEqual(miss.node, -1)
        self.assertAlmostEqual(miss.distance, 0.1, delta=1e-15)
        with self.assertRaisesRegex(sf.InputError, "rod 'bad': start_node: the section frames"):
            b.add_rod_along_path("bad", [[1, 0, 0], [1, 1, 0]], 2, section, start_node=shared)

    def test_pendulum_built_with_a_joint_spec_has_the_small_angle_period(self):
        g, length, theta0 = 9.81, 0.5, 0.02
        b = sf.ModelBuilder()
        pivot = b.add_node(np.eye(4), "pivot")
        b.add_rigid_body("bob", pivot, 2.0, [length * math.sin(theta0), -length * math.cos(theta0), 0],
                         1e-10 * np.eye(3))
        pin = sf.JointSpec()
        pin.name = "pin"
        pin.type = sf.JointType.REVOLUTE
        pin.node_a = sf.GROUND
        pin.node_b = pivot
        pin.axis = [0, 0, 1]
        b.add_joint(pin)
        b.set_gravity([0, -g, 0])
        sim = sf.Simulation(sf.Scene(b.build(), "pendulum"))
        undamped(sim)
        period = 2 * math.pi * math.sqrt(length / g) * (1 + theta0 ** 2 / 16)
        h, crossings = 1e-3, []
        while len(crossings) < 2 and sim.time < 2 * period:
            t0, v0 = sim.time, sim.joint_velocity("pin")
            sim.step(h)
            v1 = sim.joint_velocity("pin")
            if t0 > 0 and (v0 > 0) != (v1 > 0):
                crossings.append(t0 + h * v0 / (v0 - v1))
        self.assertEqual(len(crossings), 2)
        self.assertAlmostEqual(crossings[1] / period, 1.0, delta=1e-4)

    def test_joint_spec_drive_prescribes_the_coordinate(self):
        b = sf.ModelBuilder()
        node = b.add_node(np.eye(4), "slider")
        b.add_rigid_body("block", node, 1.0, [0, 0, 0], np.eye(3))
        slide = sf.JointSpec()
        slide.name = "slide"
        slide.type = sf.JointType.PRISMATIC
        slide.node_b = node
        slide.axis = [1, 0, 0]
        slide.drive = sf.DriveKind.PRESCRIBED
        slide.drive_profile = sf.Profile.ramp(0.0, 0.1, 0.05)
        b.add_joint(slide)
        sim = sf.Simulation(sf.Scene(b.build()))
        sim.initialize()
        while sim.time < 0.2 - 1e-12:
            sim.step(1e-2)
        self.assertAlmostEqual(sim.joint_coordinate("slide"), 0.05, delta=1e-12)

    def test_force_element_from_python_is_the_spring_mass_oscillator(self):
        # 2 kg hanging from the ground point (0, 0, 1) by a 50 N/m spring of rest length 1.1 m:
        # period 2 pi sqrt(m / k); the state reports length, rate and force.
        b = sf.ModelBuilder()
        n = b.add_node(np.eye(4), "mass")
        b.add_rigid_body("mass", n, 2.0, [0, 0, 0], np.eye(3))
        spring = sf.ForceElement()
        spring.name = "spring"
        spring.a = sf.BodyPoint(sf.GROUND, [0, 0, 1])
        spring.b = sf.BodyPoint(n)
        spring.stiffness = 50.0
        spring.rest_length = 1.1
        b.add_force_element(spring)
        model = b.build()
        self.assertEqual(model.num_force_elements, 1)
        sim = sf.Simulation(sf.Scene(model, "oscillator"))
        undamped(sim)
        length, rate, force = sim.force_element_state("spring")
        self.assertAlmostEqual(length, 1.0, delta=1e-15)
        self.assertAlmostEqual(force, -5.0, delta=1e-12)  # compressed: pushes
        period = 2 * math.pi * math.sqrt(2.0 / 50.0)
        h = period / 400
        for _ in range(400):
            sim.step(h)
        self.assertAlmostEqual(sim.force_element_state("spring")[0], 1.0, delta=1e-4)

    def test_tendon_from_python_pulls_with_its_tension(self):
        b = sf.ModelBuilder()
        section = sf.Section(np.array([1e5, 1e5, 1e5, 1.0, 1.0, 1.0]), np.ones(6))
        rod = b.add_rod_along_path("rod", [[0, 0, 0], [1, 0, 0]], 4, section)
        b.fix_node(b.find_node_at([0, 0, 0]).node)
        eyelets = [sf.BodyPoint(b.find_rod_node_at_arc_length(rod, 0.25 * i).node, [0, 0.02, 0])
                   for i in range(5)]
        b.add_tendon("flexor", eyelets, sf.Profile.constant(50.0))
        with self.assertRaisesRegex(sf.InputError, "tendon 'one': needs at least two eyelets"):
            bad = sf.ModelBuilder()
            bad.add_rod_along_path("rod", [[0, 0, 0], [1, 0, 0]], 1, section)
            bad.add_tendon("one", [sf.BodyPoint(0)], sf.Profile.constant(1.0))
            bad.build()
        sim = sf.Simulation(sf.Scene(b.build(), "tendon"))
        options = sf.StaticOptions()
        options.load_steps = 40
        sim.solve_static(options)
        length, rate, tension = sim.tendon_state("flexor")
        self.assertEqual(tension, 50.0)
        # The discrete model's curvature with four elements (tests/validation/tendon_test.cpp).
        tip = sim.node_frame(sim.model.rods[0].nodes[-1])[:3, 3]
        np.testing.assert_allclose(tip[:2], [0.729126, 0.572854], atol=2e-6)
        self.assertLess(length, 1.0)

    def test_tendon_eyelets_between_nodes_from_python(self):
        # Eyelets at the midpoints of 8 elements (BodyPoint.on_rod): the rod curls towards the
        # arc of curvature tau d / EI = 1 1/m (tip error 0.0295 m with 8 elements, second order,
        # tests/elements/tendon_eyelet_test.cpp), with the mesh as given (set_conform_mesh(False));
        # conforming (the default), the 8 eyelets become nodes.
        b = sf.ModelBuilder()
        b.set_conform_mesh(False)
        section = sf.Section(np.array([1e5, 1e5, 1e5, 1.0, 1.0, 1.0]), np.ones(6))
        rod = b.add_rod_along_path("rod", [[0, 0, 0], [1, 0, 0]], 8, section)
        b.fix_node(b.find_node_at([0, 0, 0]).node)
        arcs = [0.0] + [(i + 0.5) / 8 for i in range(8)] + [1.0]
        eyelets = [sf.BodyPoint.on_rod(rod, s, [0, 0.02, 0]) for s in arcs]
        self.assertEqual(eyelets[1].rod, rod)
        self.assertEqual(eyelets[1].element, -1)  # placed by build
        b.add_tendon("flexor", eyelets, sf.Profile.constant(50.0))
        sim = sf.Simulation(sf.Scene(b.build(), "eyelets"))
        options = sf.StaticOptions()
        options.load_steps = 20
        sim.solve_static(options)
        self.assertEqual(sim.tendon_state("flexor")[2], 50.0)
        tip = sim.node_frame(sim.model.rods[0].nodes[-1])[:3, 3]
        arc = (1 - 5e-4) * np.array([math.sin(1.0), 1 - math.cos(1.0)])
        self.assertLess(np.linalg.norm(tip[:2] - arc), 0.032)
        self.assertGreater(np.linalg.norm(tip[:2] - arc), 0.027)
        self.assertEqual(sim.model.conformed_nodes, 0)
        b.set_conform_mesh(True)
        model = b.build()
        self.assertTrue(model.conform_mesh)
        self.assertEqual(model.conformed_nodes, 8)
        self.assertEqual(model.rods[0].num_elements, 16)
        self.assertEqual([p.element for p in model.tendons[0].eyelets], [-1] * 10)
        with self.assertRaisesRegex(sf.InputError, "off the rod"):
            bad = sf.ModelBuilder()
            r = bad.add_rod_along_path("rod", [[0, 0, 0], [1, 0, 0]], 2, section)
            bad.add_tendon("t", [sf.BodyPoint(sf.GROUND, [0, 1, 0]),
                                 sf.BodyPoint.on_rod(r, 1.5)], sf.Profile.constant(1.0))
            bad.build()

    def test_force_element_between_rod_points_from_python(self):
        # A spring between two points of a cantilever between nodes (BodyPoint.on_rod, as the
        # eyelets): build places both ends on element sections (ForceElementSpanKind) and the
        # actuator's 5 N curls the rod towards its ends' side against the spring
        # (tests/io/force_span_scene_test.cpp: tip y 0.0809 m, length 0.6930 m).
        b = sf.ModelBuilder()
        b.set_conform_mesh(False)  # the span kind (conforming, the ends would be nodes)
        section = sf.Section(np.array([1e5, 1e5, 1e5, 1.0, 1.0, 1.0]), np.ones(6))
        rod = b.add_rod_along_path("rod", [[0, 0, 0], [1, 0, 0]], 4, section)
        b.fix_node(b.find_node_at([0, 0, 0]).node)
        spring = sf.ForceElement()
        spring.name = "brace"
        spring.a = sf.BodyPoint.on_rod(rod, 0.1, [0, 0.05, 0])
        spring.b = sf.BodyPoint.on_rod(rod, 0.8, [0, 0.05, 0])
        spring.stiffness = 200.0
        spring.actuator = sf.Profile.constant(5.0)
        b.add_force_element(spring)
        sim = sf.Simulation(sf.Scene(b.build(), "brace"))
        options = sf.StaticOptions()
        options.load_steps = 10
        sim.solve_static(options)
        length, rate, force = sim.force_element_state("brace")
        self.assertLess(length, 0.7)
        self.assertAlmostEqual(force, 5.0 + 200.0 * (length - 0.7), delta=1e-12)
        tip = sim.node_frame(sim.model.rods[0].nodes[-1])[:3, 3]
        self.assertAlmostEqual(tip[1], 0.0809311, delta=1e-6)

    def test_actuators_from_python_curl_the_rod_and_take_inputs(self):
        # A cantilever (EA = 1e5 N, EI = 1 N m^2) with a pressure chamber driven by the input
        # "p": one element bends by kappa3 = -p A r2 / EI exactly (docs/numerics.md T5.2).
        b = sf.ModelBuilder()
        section = sf.Section(np.array([1e5, 1e5, 1e5, 1.0, 1.0, 1.0]), np.ones(6))
        rod = b.add_rod_along_path("rod", [[0, 0, 0], [1, 0, 0]], 1, section)
        b.fix_node(0)
        chamber = sf.Actuator()
        chamber.name = "chamber"
        chamber.type = sf.ActuatorType.PRESSURE
        chamber.rod = rod
        chamber.area = 1e-4
        chamber.offset = [0.0, 0.01, 0.0]
        chamber.profile = sf.Profile.input(b.add_input("p", 0.0))
        b.add_actuator(chamber)
        bad = sf.Actuator()
        bad.name = "bad"
        bad.type = sf.ActuatorType.PRESSURE
        bad.rod = rod
        bad.offset = [0.0, 0.01, 0.0]
        with self.assertRaisesRegex(sf.InputError, "actuator 'bad': must be a positive area"):
            other = sf.ModelBuilder()
            other.add_rod_along_path("rod", [[0, 0, 0], [1, 0, 0]], 1, section)
            other.fix_node(0)
            other.add_actuator(bad)
            other.build()
        sim = sf.Simulation(sf.Scene(b.build(), "chamber"))
        self.assertEqual(sim.model.num_actuators, 1)
        sim.inputs["p"] = 2e5  # p A = 20 N
        self.assertEqual(sim.actuator_value("chamber"), 2e5)
        options = sf.StaticOptions()
        options.load_steps = 2
        sim.solve_static(options)
        kappa = -20.0 * 0.01 / 1.0
        tip = sim.node_frame(1)[:3, 3]
        np.testing.assert_allclose(tip[:2], (1 + 2e-4) * np.array(
            [math.sin(kappa) / kappa, (1 - math.cos(kappa)) / kappa]), atol=1e-9)
        total, elastic = sim.rod_stresses("rod")
        self.assertEqual(total.shape, (1, 6))
        self.assertLess(np.abs(total).max(), 1e-8)  # the section transmits nothing
        np.testing.assert_allclose(elastic[0], [20, 0, 0, 0, 0, -0.2], atol=1e-8)

    def test_length_driven_tendon_from_python_reports_its_tension(self):
        # The tendon test's cantilever drawn by length to the length that 50 N gives: the multiplier,
        # reported as the tension, is 50 N (tests/solve/tendon_length_test.cpp).
        section = sf.Section(np.array([1e5, 1e5, 1e5, 1.0, 1.0, 1.0]), np.ones(6))
        lengths = {}
        for by_length in (False, True):
            b = sf.ModelBuilder()
            rod = b.add_rod_along_path("rod", [[0, 0, 0], [1, 0, 0]], 4, section)
            b.fix_node(b.find_node_at([0, 0, 0]).node)
            eyelets = [sf.BodyPoint(b.find_rod_node_at_arc_length(rod, 0.25 * i).node,
                                    [0, 0.02, 0]) for i in range(5)]
            if by_length:
                b.add_length_driven_tendon("flexor", eyelets,
                                           sf.Profile.constant(lengths[False]))
            else:
                b.add_tendon("flexor", eyelets, sf.Profile.constant(50.0))
            sim = sf.Simulation(sf.Scene(b.build(), "tendon"))
            options = sf.StaticOptions()
            options.load_steps = 40
            sim.solve_static(options)
            lengths[by_length], _, tension = sim.tendon_state("flexor")
        self.assertAlmostEqual(lengths[True], lengths[False], delta=1e-9)
        self.assertAlmostEqual(tension, 50.0, delta=1e-6)

    def test_contact_from_python_holds_a_sphere_on_a_plane_at_the_equilibrium_gap(self):
        # docs/numerics.md T6.1: gap g* = delta - sqrt(2 delta m g / k) on the onset branch.
        b = sf.ModelBuilder()
        gap = 1e-4 - math.sqrt(2 * 1e-4 * 9.81 / 1e6)
        frame = np.eye(4)
        frame[2, 3] = 0.1 + gap
        node = b.add_node(frame, "ball")
        b.add_rigid_body("ball", node, 1.0, [0, 0, 0], 0.004 * np.eye(3))
        b.add_contact_shape(sf.ContactShape(0, sf.ContactShapeType.SPHERE, [0, 0, 0], radius=0.1))
        ground = sf.ContactObstacle()
        ground.name = "ground"
        ground.type = sf.ObstacleType.PLANE
        b.add_obstacle(ground)
        law = sf.ContactSettings()
        law.stiffness = 1e6
        law.onset = 1e-4
        law.friction = 0.3
        b.set_contact_settings(law)
        b.set_gravity([0, 0, -9.81])
        sim = sf.Simulation(sf.Scene(b.build(), "contact"))
        sim.initialize()
        for _ in range(50):
            sim.step(1e-3)
        contacts = sim.contact_states()
        self.assertEqual(len(contacts), 1)
        self.assertAlmostEqual(contacts[0]["normal_force"], 9.81, places=6)
        self.assertAlmostEqual(contacts[0]["gap"], gap, places=10)
        bad = sf.ModelBuilder()
        bad.add_rigid_body("b", bad.add_node(np.eye(4)), 1.0, [0, 0, 0], np.eye(3))
        bad.add_contact_shape(sf.ContactShape(0, sf.ContactShapeType.SPHERE, [0, 0, 0], radius=-1))
        bad.add_obstacle(ground)
        with self.assertRaisesRegex(sf.InputError, "the radius must be positive"):
            bad.build()

    def test_invalid_joint_side_raises_input_error(self):
        b = sf.ModelBuilder()
        spec = sf.JointSpec()
        spec.name = "j"
        spec.node_b = 3
        with self.assertRaisesRegex(sf.InputError, "joint 'j': invalid node 3"):
            b.add_joint(spec)


class StaticsTest(unittest.TestCase):
    def test_pendulum_with_a_hinge_spring_balances_gravity(self):
        # Equilibrium k alpha = m g d cos(alpha) (a scalar Newton solve for the reference).
        k = 1.0  # [N m/rad]
        sim = sf.Simulation(sf.load_scene(PENDULUM, [f"joints.hinge.stiffness={k}"]))
        m, d, _, g, _ = pendulum_constants(sim.model)
        alpha = 0.0
        for _ in range(50):
            alpha -= (k * alpha - m * g * d * math.cos(alpha)) / (k + m * g * d * math.sin(alpha))
        result = sim.solve_static()
        self.assertTrue(result.converged)
        self.assertEqual(result.load_factor, 1.0)
        self.assertAlmostEqual(sim.joint_coordinate("hinge"), alpha, delta=1e-10)
        self.assertAlmostEqual(sim.joint_effort("hinge"), -k * alpha, delta=1e-9)
        energy = sim.calc_energy()
        self.assertAlmostEqual(energy.spring, 0.5 * k * alpha ** 2, delta=1e-10)
        self.assertAlmostEqual(energy.gravity, -m * g * d * math.sin(alpha), delta=1e-10)
        self.assertEqual(energy.kinetic, 0.0)
        self.assertFalse(sim.initialized)

    def test_rod_rolls_up_into_a_circular_arc_under_a_tip_moment(self):
        # A clamped rod of length L under a tip moment M about y bends into an arc of
        # curvature M / EI: the point at arc length s is at (sin(ks)/k, 0, -(1 - cos(ks))/k)
        # with k = M / EI, exact for helical elements (constant strain) at any mesh.
        length, ei = 0.5, 2.0
        moment = 0.5 * math.pi * ei / length  # a quarter circle
        text = f"""
name: quarter roll-up
points: {{O: [0, 0, 0], TIP: [{length}, 0, 0]}}
sections:
  s: {{stiffness: [1e4, 1e4, 1e4, 3, {ei}, {ei}]}}
bodies:
  arm: {{type: soft, from: O, to: TIP, section: s, elements: 4}}
joints:
  clamp: {{type: fixed, at: O, between: [ground, arm]}}
loads:
  tip: {{body: arm, at: TIP, moment: [0, {moment}, 0]}}
analysis: {{type: static, load_steps: 4}}
outputs:
  points:
    tip: {{body: arm, at: TIP}}
    third: {{rod: arm, s: {length / 3}}}
  vtk: false
  rod_fields: true
"""
        scene = sf.parse_scene(text, "rollup.yaml")
        self.assertTrue(scene.outputs.rod_fields)
        self.assertEqual((scene.model.num_rods, scene.model.num_elements, scene.model.num_nodes),
                         (1, 4, 5))
        self.assertEqual(scene.model.rods[0].nodes, [0, 1, 2, 3, 4])
        sim = sf.Simulation(scene)
        result = sim.solve_static()
        self.assertTrue(result.converged)
        self.assertEqual(result.load_steps, 4)
        curvature = moment / ei

        def arc(s):
            return [math.sin(curvature * s) / curvature, 0.0,
                    -(1.0 - math.cos(curvature * s)) / curvature]

        np.testing.assert_allclose(sim.point_motion("tip").position, arc(length), rtol=0, atol=1e-12)
        rod_point = sim.calc_rod_point_motion("arm", length / 3)
        np.testing.assert_allclose(rod_point.motion.position, arc(length / 3), rtol=0, atol=1e-12)
        np.testing.assert_allclose(rod_point.frame[:3, :3], rotation_y(curvature * length / 3),
                                   rtol=0, atol=1e-12)
        self.assertEqual(rod_point.element, 1)
        self.assertAlmostEqual(rod_point.xi, 1.0 / 3.0, delta=1e-12)
        np.testing.assert_allclose(sim.node_frame("arm.4")[:3, :3], rotation_y(math.pi / 2),
                                   rtol=0, atol=1e-12)
        self.assertAlmostEqual(sim.calc_energy().strain / (0.5 * moment ** 2 * length / ei), 1.0,
                               delta=1e-12)
        # Section fields: t, rod, s, gamma1..3, kappa1..3, n1..3, m1..3 per element; the
        # moment about y bends about section axis 2: kappa2 = M / EI, m2 = M, nothing else.
        fields = sim.rod_fields("arm")
        self.assertEqual(fields.shape, (4, 15))
        np.testing.assert_allclose(fields[:, 2], [0.0625, 0.1875, 0.3125, 0.4375], atol=1e-15)
        np.testing.assert_allclose(fields[:, 7], curvature, rtol=1e-12)
        np.testing.assert_allclose(fields[:, 13], moment, rtol=1e-12)
        others = np.delete(fields[:, 3:], [4, 10], axis=1)
        self.assertLess(np.abs(others).max(), 1e-9)
        # run_scene solves the same problem and records the same row.
        with tempfile.TemporaryDirectory() as outdir:
            run = sf.run_scene(scene, outdir)
            header, rows = read_csv(os.path.join(outdir, "points.csv"))
            with open(os.path.join(outdir, "rod_fields.csv"), newline="") as f:
                field_rows = list(csv.reader(f))
        # rod_fields.csv: t, load_factor, then the values; the last load step's 4 rows are the
        # equilibrium sim.rod_fields saw.
        self.assertEqual(field_rows[0][:4], ["t", "load_factor", "rod", "s"])
        self.assertEqual(len(field_rows), 1 + 4 * 4)
        last = np.array([[float(x) for x in r] for r in field_rows[-4:]])
        np.testing.assert_array_equal(last[:, 1], 1.0)
        np.testing.assert_allclose(last[:, 2:], fields[:, 1:], rtol=0, atol=1e-14)
        self.assertTrue(run.ok, run.message)
        # Static analyses: every load step's row at the same t, the load factor after t (the
        # dict keeps the last row, the equilibrium at load factor 1).
        self.assertEqual(list(rows), [scene.analysis.statics.time])
        self.assertEqual(header[1], "load_factor")
        self.assertEqual(rows[scene.analysis.statics.time][0], 1.0)
        np.testing.assert_allclose(rows[scene.analysis.statics.time][1:], sim.calc_point_row(),
                                   rtol=0, atol=1e-14)

    def test_static_solve_continues_from_the_current_state_and_follows_the_arc_length(self):
        # The roll-up of the test above (tip on a circle of curvature s M / EI at load factor
        # s): half the moment, then from there the rest (continuation); arc length from rest.
        length, ei = 0.5, 2.0
        moment = 0.5 * math.pi * ei / length
        text = f"""
points: {{O: [0, 0, 0], TIP: [{length}, 0, 0]}}
sections:
  s: {{stiffness: [1e4, 1e4, 1e4, 3, {ei}, {ei}]}}
bodies:
  arm: {{type: soft, from: O, to: TIP, section: s, elements: 4}}
joints:
  clamp: {{type: fixed, at: O, between: [ground, arm]}}
loads:
  tip: {{body: arm, at: TIP, moment: [0, {moment}, 0]}}
analysis: {{type: static, statics: {{method: arclength}}}}
outputs: {{vtk: false}}
"""
        scene = sf.parse_scene(text, "rollup.yaml")
        self.assertEqual(scene.analysis.statics.method, sf.StaticMethod.ARCLENGTH)

        def tip(load_factor):
            k = load_factor * moment / ei
            return [math.sin(k * length) / k, 0.0, -(1.0 - math.cos(k * length)) / k]

        sim = sf.Simulation(scene)
        first = sf.StaticOptions()
        first.end_load_factor = 0.5
        result = sim.solve_static(first)
        self.assertEqual(result.load_factor, 0.5)
        np.testing.assert_allclose(sim.node_frame("arm.4")[:3, 3], tip(0.5), rtol=0, atol=1e-12)
        rest = sf.StaticOptions()
        rest.start_load_factor = result.load_factor
        rest.load_steps = 2
        result = sim.solve_static(rest)
        self.assertEqual((result.load_factor, result.load_steps), (1.0, 2))
        self.assertAlmostEqual(result.steps[0].load_factor, 0.75, delta=1e-15)
        np.testing.assert_allclose(sim.node_frame("arm.4")[:3, 3], tip(1.0), rtol=0, atol=1e-12)
        # The scene's settings: arc length from rest, no limit point on this path.
        arc = sf.Simulation(scene).solve_static()
        self.assertTrue(arc.converged)
        self.assertEqual(arc.limit_points, [])
        self.assertEqual(arc.load_factor, 1.0)
        # A step cap too small for the path: SolverError with the message and the result.
        capped = sf.StaticOptions()
        capped.max_steps = 2
        with self.assertRaisesRegex(sf.SolverError, "max_steps") as caught:
            sf.Simulation(scene).solve_static(capped)
        self.assertEqual(caught.exception.result.load_steps, 2)


@contextlib.contextmanager
def keyboard_interrupt_after(seconds):
    """SIGALRM after `seconds`, handled like Ctrl-C (KeyboardInterrupt)."""
    previous = signal.signal(signal.SIGALRM, signal.default_int_handler)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0.0)
        signal.signal(signal.SIGALRM, previous)


class InterruptTest(unittest.TestCase):
    """A signal (Ctrl-C) during a long C++ call ends it, instead of waiting for it to finish."""

    def test_keyboard_interrupt_ends_run_scene_with_an_interrupted_summary(self):
        # 2e6 steps: about 10 s when nothing polls the signal.
        scene = sf.load_scene(PENDULUM, ["analysis.end_time=20", "analysis.step=1e-5",
                                         "outputs.vtk=false"])
        with tempfile.TemporaryDirectory() as outdir:
            with self.assertRaises(KeyboardInterrupt):
                with keyboard_interrupt_after(0.3):
                    sf.run_scene(scene, outdir)
            with open(os.path.join(outdir, "summary.json")) as f:
                summary = json.load(f)
            header, rows = read_csv(os.path.join(outdir, "points.csv"))
        self.assertEqual(summary["status"], "interrupted")
        self.assertLess(summary["time"], 20.0)
        self.assertEqual(len(rows), summary["outputs"]["rows"])

    def test_keyboard_interrupt_ends_solve_static_at_a_converged_load_step(self):
        overrides = ["joints.hinge.stiffness=1", "analysis.type=static"]
        reference = sf.Simulation(sf.load_scene(PENDULUM, overrides))
        reference.solve_static()
        equilibrium = reference.joint_coordinate("hinge")
        self.assertGreater(abs(equilibrium), 0.1)
        # A million load steps: several seconds when nothing polls the signal.
        sim = sf.Simulation(sf.load_scene(PENDULUM, overrides + ["analysis.load_steps=1000000"]))
        with self.assertRaises(KeyboardInterrupt):
            with keyboard_interrupt_after(0.2):
                sim.solve_static()
        self.assertLess(abs(sim.joint_coordinate("hinge")), 0.5 * abs(equilibrium))


class ValidationTest(unittest.TestCase):
    """Python reaches the C++ validation of every setting (ValueError), never a hang."""

    def test_halvings_iterations_and_tolerances_are_range_checked(self):
        sim = sf.Simulation(sf.load_scene(PENDULUM))
        for field, value in (("max_halvings", 31), ("max_halvings", 10 ** 6), ("max_halvings", -1),
                             ("max_iterations", 0), ("max_iterations", 1001),
                             ("increment_tolerance", math.nan), ("constraint_tolerance", math.inf),
                             ("residual_tolerance", 0.0), ("rho_inf", math.nan)):
            options = sf.DynamicOptions()
            setattr(options, field, value)
            with self.assertRaisesRegex(ValueError, "DynamicOptions." + field, msg=field):
                sim.initialize(options)
        for field, value in (("max_halvings", 31), ("load_steps", 0), ("time", math.inf),
                             ("residual_tolerance", math.nan), ("increment_tolerance", -1.0)):
            options = sf.StaticOptions()
            setattr(options, field, value)
            with self.assertRaisesRegex(ValueError, "StaticOptions." + field, msg=field):
                sim.solve_static(options)
        # run_scene checks the scene's settings with the same function.
        scene = sf.load_scene(PENDULUM)
        scene.analysis.dynamic.max_halvings = 10 ** 6
        with tempfile.TemporaryDirectory() as outdir:
            with self.assertRaisesRegex(ValueError, "max_halvings"):
                sf.run_scene(scene, outdir)

    def test_enum_values_out_of_range_are_rejected(self):
        sim = sf.Simulation(sf.load_scene(PENDULUM))
        for field, enum in (("predictor", sf.Predictor), ("newton_matrix", sf.NewtonMatrix),
                            ("convergence", sf.ConvergenceTest)):
            options = sf.DynamicOptions()
            try:
                setattr(options, field, enum(7))
            except (ValueError, TypeError):
                continue  # refused already
            with self.assertRaisesRegex(ValueError, "DynamicOptions." + field):
                sim.initialize(options)
        scene = sf.load_scene(PENDULUM)
        try:
            scene.analysis.kind = sf.AnalysisKind(5)
        except (ValueError, TypeError):
            return
        with tempfile.TemporaryDirectory() as outdir:
            with self.assertRaisesRegex(ValueError, "analysis.kind"):
                sf.run_scene(scene, outdir)

    def test_step_schedule_rejects_times_it_cannot_step_through(self):
        schedule = sf.StepSchedule(0.0, 1.0, 1e-3)
        self.assertAlmostEqual(schedule.next(0.0), 1e-3, delta=1e-15)
        for t in (-1e308, -1.0, math.nan, math.inf, 1.0, 2.0):
            with self.assertRaises(ValueError, msg=str(t)):
                schedule.next(t)
        with self.assertRaisesRegex(ValueError, "relative accuracy"):
            sf.StepSchedule(1e15, 1e15 + 1.0, 1e-3)
        with self.assertRaisesRegex(ValueError, "1e9"):
            sf.StepSchedule(0.0, 1e9, 1e-3)

    def test_paths_with_an_embedded_nul_are_rejected(self):
        with self.assertRaisesRegex(ValueError, "NUL"):
            sf.load_scene(PENDULUM + "\0.backup")
        scene = sf.load_scene(PENDULUM, ["analysis.end_time=0.01"])
        with tempfile.TemporaryDirectory() as parent:
            with self.assertRaisesRegex(ValueError, "NUL"):
                sf.run_scene(scene, os.path.join(parent, "out\0x"))
            self.assertEqual(os.listdir(parent), [])

    def test_a_folder_with_results_is_replaced_only_with_force(self):
        scene = sf.load_scene(PENDULUM, ["analysis.end_time=0.01"])
        with tempfile.TemporaryDirectory() as outdir:
            self.assertTrue(sf.run_scene(scene, outdir).ok)
            with self.assertRaisesRegex(ValueError, "results of an earlier run"):
                sf.run_scene(scene, outdir)
            self.assertTrue(sf.run_scene(scene, outdir, force=True).ok)



CANTILEVER = """
inputs: {u: 0.0}
points: {A: [0, 0, 0], B: [0.3, 0, 0]}
materials: {m: {E: 1e7, nu: 0.45, density: 1100}}
sections: {s: {shape: circle, radius: 0.01, material: m}}
bodies:
  arm: {type: soft, from: A, to: B, section: s, elements: 6}
joints:
  clamp: {type: fixed, at: A, between: [ground, arm]}
loads:
  tip: {body: arm, at: B, force: [0, 0, 1], profile: {type: input, name: u}}
analysis: {type: dynamic, end_time: 0.1, step: 2e-3}
outputs: {points: {tip: {body: arm, at: B}}}
"""


class MemoryLimitTest(unittest.TestCase):
    """The memory limit from Python (docs/limits.md): max_memory of load_scene and parse_scene,
    set_memory_limit, ModelBuilder.set_memory_limit and estimate_memory."""

    def test_max_memory_refuses_a_scene_beyond_it_and_is_restored(self):
        before = sf.memory_limit()
        with self.assertRaisesRegex(
                sf.InputError, r"pendulum.yaml: the model's solver workspace needs about .*, "
                r"more than the memory limit of 1000 B \(set by --max-memory or max_memory; "
                r"--max-memory SIZE or max_memory= change it\): the largest part is the "):
            sf.load_scene(PENDULUM, max_memory=1000)
        self.assertEqual(sf.memory_limit(), before)
        scene = sf.load_scene(PENDULUM, max_memory="1G")
        with open(PENDULUM) as f:
            text = f.read()
        with self.assertRaisesRegex(sf.InputError, "more than the memory limit of 1000 B"):
            sf.parse_scene(text, "p.yaml", max_memory=1000)
        parts = sf.estimate_memory(scene.model)
        self.assertEqual(parts[0][0], "banded LU factors of the iteration matrix")
        n = scene.model.nv + scene.model.nc
        b = scene.model.bandwidth
        self.assertEqual(parts[0][1], n * (3 * b + 1) * 8 + 52 * n)
        for bad in ("lots", "0", -5, 0, 1.5, True):
            with self.assertRaises(ValueError):
                sf.load_scene(PENDULUM, max_memory=bad)

    def test_reactions_and_energy_tables_can_be_turned_off(self):
        scene = sf.load_scene(PENDULUM, ["analysis.end_time=0.01", "outputs.vtk=false"])
        self.assertTrue(scene.outputs.reactions)
        self.assertTrue(scene.outputs.energy)
        scene.outputs.reactions = False
        with tempfile.TemporaryDirectory() as outdir:
            self.assertTrue(sf.run_scene(scene, outdir).ok)
            self.assertFalse(os.path.exists(os.path.join(outdir, "reactions.csv")))
            self.assertTrue(os.path.exists(os.path.join(outdir, "energy.csv")))
        scene = sf.load_scene(PENDULUM, ["analysis.end_time=0.01", "outputs.vtk=false",
                                         "outputs.energy=false"])
        self.assertFalse(scene.outputs.energy)
        with tempfile.TemporaryDirectory() as outdir:
            self.assertTrue(sf.run_scene(scene, outdir).ok)
            self.assertTrue(os.path.exists(os.path.join(outdir, "reactions.csv")))
            self.assertFalse(os.path.exists(os.path.join(outdir, "energy.csv")))

    def test_run_memory_lists_the_model_and_the_integrator(self):
        scene = sf.load_scene(PENDULUM)
        m = scene.model
        fixed = sf.estimate_run_memory(m)
        self.assertEqual([p[0] for p in fixed],
                         ["model (nodes, elements, joints, ordering)"] +
                         [p[0] for p in sf.estimate_memory(m)] + ["time integrator's workspace"])
        auto = sf.estimate_run_memory(m, adaptive=True)
        self.assertEqual(auto[-1][0], "time integrator's workspace (error-controlled steps)")
        # 9 vectors of nv, 2 of nc and a configuration (node and joint frames of 96 bytes, the
        # joint coordinates) more.
        state = (len(m.nodes) + len(m.joints)) * 96 + (m.nv - m.nv_nodes) * 8
        self.assertEqual(auto[-1][1] - fixed[-1][1], (9 * m.nv + 2 * m.nc) * 8 + state)
        self.assertEqual(sf.estimate_run_memory(m, statics=True)[-1][1],
                         (4 * (m.nv + m.nc) + m.nv) * 8)

    def test_process_and_builder_limits(self):
        before = sf.memory_limit()
        sf.set_memory_limit("2G")
        try:
            self.assertEqual(sf.memory_limit(), 2 << 30)
            with self.assertRaisesRegex(sf.InputError, r"memory limit of 1000 B \(set by "):
                sf.load_scene(PENDULUM, max_memory=1000)
            self.assertEqual(sf.memory_limit(), 2 << 30)
        finally:
            sf.set_memory_limit(None)
        self.assertEqual(sf.memory_limit(), before)
        self.assertEqual(sf.parse_memory_size("512M"), 512 << 20)
        b = sf.ModelBuilder()
        node = b.add_node(np.eye(4), "n")
        b.add_rigid_body("body", node, 1.0, [0, 0, 0], np.eye(3))
        b.set_memory_limit(100)
        with self.assertRaisesRegex(sf.InputError, r"memory limit of 100 B \(set by "
                                                   r"ModelBuilder.set_memory_limit;"):
            b.build()
        b.set_memory_limit(None)
        b.build()


class EnumValidationTest(unittest.TestCase):
    """Enum values from Python: an integer outside an enum is a ValueError, never a value that
    reaches C++ (JointType(99) aborted the interpreter in joint_type_name and add_joint)."""

    ENUMS = ["JointType", "DriveKind", "RodInertia", "LinearSolver", "LoadFrame", "ActuatorType",
             "ContactShapeType", "ObstacleType", "NewtonMatrix", "Predictor", "ConvergenceTest",
             "ConstraintFormulation", "StaticMethod", "AnalysisKind", "VtkFormat"]

    def test_every_enum_refuses_integers_outside_it(self):
        for name in self.ENUMS:
            cls = getattr(sf, name)
            members = list(cls.__members__.values())
            for m in members:
                self.assertEqual(cls(int(m)), m)
            for bad in (len(members) + 7, -1, 99):
                if bad in [int(m) for m in members]:
                    continue
                with self.assertRaisesRegex(ValueError, f"^{name}: {bad} is not a member \\("):
                    cls(bad)

    def test_an_unpickled_out_of_range_joint_type_is_refused_where_it_enters(self):
        bad = sf.JointType.__new__(sf.JointType)
        bad.__setstate__(99)
        with self.assertRaisesRegex(ValueError, r"^JointType: 99 is not a member \(REVOLUTE, "):
            sf.joint_type_name(bad)
        spec = sf.JointSpec()
        with self.assertRaisesRegex(ValueError, "JointType: 99 is not a member"):
            spec.type = bad
        self.assertEqual(spec.type, sf.JointType.REVOLUTE)
        options = sf.DynamicOptions()
        newton = sf.NewtonMatrix.__new__(sf.NewtonMatrix)
        newton.__setstate__(5)
        with self.assertRaisesRegex(ValueError, r"NewtonMatrix: 5 is not a member \(SIMPLIFIED, FULL\)"):
            options.newton_matrix = newton

    def test_joint_type_names_of_valid_members(self):
        self.assertEqual(sf.joint_type_name(sf.JointType.REVOLUTE), "revolute")
        self.assertEqual(sf.joint_type_name(sf.JointType(int(sf.JointType.FREE))), "free")


class InputsAndStateTest(unittest.TestCase):
    """Run-time inputs (sim.inputs), state save/restore, rod arrays, body outputs."""

    def test_inputs_by_name_move_the_arm_and_unknown_names_raise(self):
        sim = sf.Simulation(sf.parse_scene(CANTILEVER, "arm.yaml"))
        self.assertEqual(list(sim.inputs.keys()), ["u"])
        self.assertEqual(len(sim.inputs), 1)
        self.assertIn("u", sim.inputs)
        self.assertEqual(sim.model.input_names, ["u"])
        with self.assertRaisesRegex(KeyError, "no input named 'v'"):
            sim.inputs["v"] = 1.0
        with self.assertRaises(ValueError):
            sim.inputs["u"] = math.nan
        sim.initialize()
        sim.inputs["u"] = 0.5
        self.assertEqual(sim.input_values[0], 0.5)
        for _ in range(20):
            sim.step(2e-3)
        self.assertGreater(sim.point_motion("tip").position[2], 1e-4)  # pushed up

    def test_non_finite_values_written_through_the_input_view_are_refused(self):
        sim = sf.Simulation(sf.parse_scene(CANTILEVER, "arm.yaml"))
        sim.input_values[0] = math.nan  # an element write: no setter sees it
        message = (r"input_values\[0\] \(input 'u'\) is nan; run-time inputs must be finite")
        with self.assertRaisesRegex(ValueError, "Simulation.initialize: " + message):
            sim.initialize()
        sim.input_values[0] = 0.0
        sim.initialize()
        sim.input_values[0] = math.inf
        t = sim.time
        for call in (lambda: sim.step(2e-3), lambda: sim.advance_to(t + 1e-3),
                     lambda: sim.simulate(t + 1e-3)):
            with self.assertRaisesRegex(ValueError, r"input_values\[0\] \(input 'u'\) is inf"):
                call()
        self.assertEqual(sim.time, t)
        with self.assertRaisesRegex(ValueError, "Simulation.solve_static: "):
            sim.solve_static()
        with self.assertRaisesRegex(ValueError, r"_step_many: sims\[0\]: input_values\[0\]"):
            sf._screwfem._step_many([sim], 1e-3)
        with self.assertRaisesRegex(ValueError, "must be finite"):
            sim.input_values = [math.nan]

    def test_restored_state_repeats_the_rollout_bit_for_bit(self):
        sim = sf.Simulation(sf.parse_scene(CANTILEVER, "arm.yaml"))
        sim.initialize()
        sim.inputs["u"] = 0.2
        for _ in range(5):
            sim.step(2e-3)
        saved = sim.get_state()
        self.assertAlmostEqual(saved.time, 0.01, delta=1e-15)

        def rollout():
            for n in range(10):
                sim.inputs["u"] = -0.1 * n
                sim.step(2e-3)
            return sim.rod_centerline("arm").copy(), sim.time

        first, t1 = rollout()
        sim.set_state(saved)
        self.assertEqual(sim.inputs["u"], 0.2)
        again, t2 = rollout()
        self.assertEqual(t1, t2)
        np.testing.assert_array_equal(first, again)

    def test_rod_centerline_and_rotations(self):
        sim = sf.Simulation(sf.parse_scene(CANTILEVER, "arm.yaml"))
        x = sim.rod_centerline("arm")
        self.assertEqual(x.shape, (7, 3))
        np.testing.assert_allclose(x[:, 0], np.linspace(0.0, 0.3, 7), atol=1e-15)
        r = sim.rod_rotations(0)
        self.assertEqual(r.shape, (7, 3, 3))
        for q in r:
            np.testing.assert_allclose(q @ q.T, np.eye(3), atol=1e-14)
        frames = sim.node_frames()
        self.assertEqual(frames.shape, (7, 4, 4))
        frames[:, 2, 3] += 0.01  # lift every node by 1 cm
        sim.set_node_frames(frames)
        np.testing.assert_allclose(sim.rod_centerline("arm")[:, 2], 0.01, atol=1e-15)
        with self.assertRaises(ValueError):
            sim.set_node_frames(np.zeros((7, 4, 4)))

    def test_pendulum_started_by_scene_initial_state_and_body_outputs(self):
        scene = sf.load_scene(PENDULUM, [
            "joints.hinge.initial_position=pi/2", "joints.hinge.initial_velocity=0.5"])
        sim = sf.Simulation(scene)
        self.assertAlmostEqual(sim.joint_coordinate("hinge"), math.pi / 2, delta=1e-15)
        np.testing.assert_allclose(sim.body_angular_velocity("link"), [0, 0.5, 0], atol=1e-14)
        q = sim.body_orientation("link")  # rotation by pi/2 about y
        np.testing.assert_allclose(q, [math.cos(math.pi / 4), 0, math.sin(math.pi / 4), 0],
                                   atol=1e-14)
        # Hanging at rest position with a rate: the hinge carries m g plus the centripetal
        # force m d w^2, upwards, and no moment about its axis.
        sim.initialize()
        m, d, _, g, _ = pendulum_constants(sim.model)
        r = sim.joint_reaction("hinge")
        self.assertAlmostEqual(r[2], m * g + m * d * 0.25, delta=1e-9)
        self.assertAlmostEqual(r[4], 0.0, delta=1e-12)
        # A soft-joint stiffness set between steps acts at once: the hinge's effort is then the
        # spring's -k (q - rest), rest 0, no damper.
        with self.assertRaisesRegex(ValueError, "finite and >= 0"):
            sim.set_joint_stiffness("hinge", [-1.0])
        sim.set_joint_stiffness("hinge", [2.0])
        self.assertAlmostEqual(sim.joint_effort("hinge"), -2.0 * sim.joint_coordinate("hinge"),
                               delta=1e-12)
        p = sim.calc_momentum()  # v_com = w x r_com = (0, 0.5, 0) x (0, 0, -d): along -x
        self.assertAlmostEqual(p[0], -m * d * 0.5, delta=1e-14)


class ThreadsTest(unittest.TestCase):
    """The parallel assembly from Python (docs/architecture.md, "Parallel assembly")."""

    SCENE = """
points: {A: [0, 0, 0], B: [1, 0, 0]}
sections: {s: {stiffness: [1e6, 1e6, 1e6, 1, 1, 1], inertia: [0.1, 0.1, 0.1, 0.5, 0.5, 0.5]}}
gravity: [0, 0, -9.81]
bodies: {rod: {type: soft, from: A, to: B, section: s, elements: 300}}
joints: {clamp: {type: fixed, at: A, between: [ground, rod]}}
analysis: {end_time: 0.01, step: 1e-3}
"""

    def test_two_threads_reach_the_serial_state_bit_for_bit(self):
        scene = sf.parse_scene(self.SCENE, "rod.yaml")
        self.assertEqual(scene.analysis.threads, "auto")
        states = []
        for threads in (1, 2):
            sim = sf.Simulation(scene)
            self.assertEqual(sim.threads, 1)  # auto: 300 elements stay on one thread
            sim.threads = threads
            self.assertEqual(sim.threads, threads)
            sim.initialize()
            for _ in range(10):
                sim.step(1e-3)
            states.append((sim.v.copy(), sim.vdot.copy()))
        self.assertTrue(np.array_equal(states[0][0], states[1][0]))
        self.assertTrue(np.array_equal(states[0][1], states[1][1]))
        self.assertGreater(np.abs(states[0][0]).max(), 0.0)  # it moved

    def test_scene_setting_reaches_the_simulation(self):
        scene = sf.parse_scene(self.SCENE, "rod.yaml", ["analysis.threads=2"])
        self.assertEqual(scene.analysis.threads, 2)
        self.assertEqual(sf.Simulation(scene).threads, 2)
        with self.assertRaisesRegex(sf.InputError, "expected an integer from 1 to 256"):
            sf.Simulation(scene).threads = 0
        with self.assertRaisesRegex(sf.InputError, "expected 'auto' or an integer"):
            scene.analysis.threads = "many"


if __name__ == "__main__":
    unittest.main()
