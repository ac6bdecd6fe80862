"""Tests of screwfem.Env and screwfem.VectorEnv (python/screwfem/_env.py) and of the threaded
stepping behind them (_step_many, python/bind_env.cpp).

Run by ctest (python/CMakeLists.txt, test python_env) as
    /usr/bin/python3 -m unittest -v test_env
from tests/python with PYTHONPATH=<build>/python. SCREWFEM_TEST_DATA_DIR names tests/data.

Scenes: examples/python/soft_arm_control.yaml, a silicone arm clamped at its base that sags
under gravity, with a tendon along its top whose tension is the run-time input u [N] (one
action component; one output point, the tip: observations of 6 values); and
tests/data/pendulum.yaml, a rigid pendulum on a revolute joint released from the horizontal
(no inputs: an empty action), end_time 0.5 s.
"""

import multiprocessing
import os
import pathlib
import threading
import unittest

import numpy as np

import screwfem as sf
from screwfem import _screwfem

ROOT = pathlib.Path(__file__).resolve().parents[2]
DATA_DIR = pathlib.Path(os.environ.get("SCREWFEM_TEST_DATA_DIR", ROOT / "tests" / "data"))
ARM = str(ROOT / "examples" / "python" / "soft_arm_control.yaml")
PENDULUM = str(DATA_DIR / "pendulum.yaml")
Z_TARGET = 0.02  # a tip height the tendon can lift the arm to [m]


def tip_reward(sim, obs, action):
    """Minus the tip's distance from the target height (obs[2] is the tip's z)."""
    return -abs(obs[2] - Z_TARGET)


def same_bits(a, b):
    a, b = np.asarray(a, np.float64), np.asarray(b, np.float64)
    return a.shape == b.shape and np.array_equal(a.view(np.uint64), b.view(np.uint64))


def fragile_arm():
    """The soft arm with Newton capped at 3 iterations and no halving: a step at rest with u = 0
    converges, one with u = 1 N does not (SolverError from Simulation.step)."""
    scene = sf.load_scene(ARM)
    scene.analysis.dynamic.max_iterations = 3
    scene.analysis.dynamic.max_halvings = 0
    return scene


class EnvApiTest(unittest.TestCase):
    def test_reset_and_step_return_gymnasium_types_and_shapes(self):
        env = sf.Env(ARM, reward=tip_reward)
        self.assertEqual(env.action_names, ("u",))
        self.assertEqual(env.action_space.shape, (1,))
        self.assertEqual(env.observation_space.shape, (6,))
        self.assertEqual(env.action_space.dtype, np.float64)
        self.assertTrue(np.all(np.isneginf(env.action_space.low)))  # inputs declare no range
        self.assertTrue(np.all(np.isposinf(env.action_space.high)))
        self.assertEqual(env.control_period, env.scene.analysis.step)
        with self.assertRaisesRegex(RuntimeError, "reset"):
            env.step([0.0])

        obs, info = env.reset(seed=0)
        self.assertIsInstance(obs, np.ndarray)
        self.assertEqual(obs.dtype, np.float64)
        self.assertEqual(obs.shape, (6,))
        self.assertTrue(env.observation_space.contains(obs))
        np.testing.assert_array_equal(obs, [0.3, 0, 0, 0, 0, 0])  # the tip, at rest
        self.assertEqual(info, {"time": 0.0, "steps": 0})

        result = env.step(env.action_space.sample())
        self.assertEqual(len(result), 5)
        obs, reward, terminated, truncated, info = result
        self.assertEqual(obs.shape, (6,))
        self.assertIs(type(reward), float)
        self.assertIs(type(terminated), bool)
        self.assertIs(type(truncated), bool)
        self.assertFalse(terminated or truncated)
        self.assertEqual(reward, -abs(obs[2] - Z_TARGET))
        self.assertEqual(info["steps"], 1)
        self.assertAlmostEqual(info["time"], env.h)
        self.assertNotIn("error", info)
        # A new array every step: a kept observation does not change.
        kept = obs.copy()
        obs2 = env.step([0.5])[0]
        self.assertIsNot(obs2, obs)
        np.testing.assert_array_equal(obs, kept)
        # The action went into the simulation's input.
        self.assertEqual(env.sim.inputs["u"], 0.5)

    def test_observation_kinds(self):
        # "state": 3 positions per node, then Simulation.v.
        env = sf.Env(ARM, observe="state")
        obs, _ = env.reset()
        sim = env.sim
        n_nodes = sim.model.num_nodes
        self.assertEqual(obs.shape, (3 * n_nodes + sim.model.nv,))
        np.testing.assert_array_equal(obs[:3 * n_nodes], sim.node_frames()[:, :3, 3].ravel())
        obs = env.step([0.2])[0]
        np.testing.assert_array_equal(obs[3 * n_nodes:], env.sim.v)

        # "joints" on the pendulum: its hinge angle and rate; gravity swings it down (positive
        # angle, the link rotating about +y from the horizontal towards -z).
        env = sf.Env(PENDULUM, observe="joints")
        self.assertEqual(env.action_space.shape, (0,))
        obs, _ = env.reset()
        np.testing.assert_array_equal(obs, [0.0, 0.0])
        for _ in range(20):
            obs = env.step([])[0]
        self.assertEqual(obs[0], env.sim.joint_coordinate("hinge"))
        self.assertEqual(obs[1], env.sim.joint_velocity("hinge"))
        self.assertGreater(obs[0], 0.0)
        self.assertGreater(obs[1], 0.0)
        with self.assertRaisesRegex(ValueError, "joint coordinates"):
            sf.Env(ARM, observe="joints")  # a clamped arm: a fixed joint only

        # A callable.
        env = sf.Env(ARM, observe=lambda sim: [sim.time, sim.inputs["u"]])
        self.assertEqual(env.observation_space.shape, (2,))
        env.reset()
        np.testing.assert_array_equal(env.step([0.25])[0], [env.h, 0.25])
        with self.assertRaisesRegex(ValueError, "observe must be"):
            sf.Env(ARM, observe="nodes")

    def test_termination_and_truncation(self):
        # The pendulum's end_time is 0.5 s: with a control period of 0.1 s the fifth step
        # truncates, and stepping on raises until reset.
        env = sf.Env(PENDULUM, control_period=0.1, substeps=100)
        self.assertAlmostEqual(env.h, 1e-3)
        env.reset()
        flags = [env.step([])[3] for _ in range(5)]
        self.assertEqual(flags, [False] * 4 + [True])
        self.assertAlmostEqual(env.sim.time, 0.5, delta=1e-12)
        with self.assertRaisesRegex(RuntimeError, "episode has ended"):
            env.step([])
        # max_steps; reset starts over.
        env = sf.Env(PENDULUM, max_steps=3)
        for _ in range(2):
            env.reset()
            self.assertEqual([env.step([])[3] for _ in range(3)], [False, False, True])
            self.assertEqual(env.sim.steps, 3)
        # The terminated callable, with the step's simulation, observation and action.
        seen = []

        def past(sim, obs, action):
            seen.append((sim.time, obs.copy(), action.copy()))
            return sim.time > 0.005

        env = sf.Env(ARM, terminated=past)
        env.reset()
        done = [env.step([0.1])[2] for _ in range(2)]
        obs, _, terminated, truncated, _ = env.step([0.1])
        self.assertEqual(done + [terminated, truncated], [False, False, True, False])
        self.assertEqual(len(seen), 3)
        np.testing.assert_array_equal(seen[-1][1], obs)
        np.testing.assert_array_equal(seen[-1][2], [0.1])

    def test_action_bounds_clip_and_sample_within(self):
        env = sf.Env(ARM, action_bounds=(0.0, 0.5))
        np.testing.assert_array_equal(env.action_space.low, [0.0])
        np.testing.assert_array_equal(env.action_space.high, [0.5])
        env.reset(seed=1)
        for _ in range(20):
            a = env.action_space.sample()
            self.assertTrue(env.action_space.contains(a))
        env.step([2.0])
        self.assertEqual(env.sim.inputs["u"], 0.5)  # clipped to the bound
        env.step([-1.0])
        self.assertEqual(env.sim.inputs["u"], 0.0)
        self.assertFalse(env.action_space.contains([0.7]))
        self.assertFalse(env.action_space.contains([np.nan]))
        self.assertFalse(env.action_space.contains([0.1, 0.2]))

    def test_box(self):
        box = sf.Box([0.0, -np.inf, -np.inf, 1.0], [1.0, np.inf, 2.0, np.inf], seed=5)
        self.assertEqual(box.shape, (4,))
        x = np.array([box.sample() for _ in range(200)])
        self.assertTrue(all(box.contains(r) for r in x))
        self.assertTrue(((x[:, 0] >= 0) & (x[:, 0] <= 1)).all())
        self.assertTrue((x[:, 2] <= 2).all() and (x[:, 3] >= 1).all())
        self.assertLess(x[:, 1].min(), 0.0)  # unbounded: normal, both signs
        self.assertGreater(x[:, 1].max(), 0.0)
        box.seed(5)
        first = box.sample()
        box.seed(5)
        self.assertTrue(same_bits(box.sample(), first))
        with self.assertRaisesRegex(ValueError, "low must be <= high"):
            sf.Box(1.0, 0.0, shape=(2,))

    def test_scene_argument_and_settings(self):
        scene = sf.load_scene(ARM)
        env = sf.Env(scene, substeps=3)
        scene.analysis.step = 1e-2  # the Env has its own copy
        self.assertEqual(env.h, 2e-3)
        self.assertEqual(env.control_period, 3 * 2e-3)
        env.reset()
        env.step([0.0])
        self.assertEqual(env.sim.steps, 3)
        with self.assertRaisesRegex(TypeError, "Scene or a path"):
            sf.Env(42)
        with self.assertRaisesRegex(ValueError, "substeps must be an integer >= 1"):
            sf.Env(ARM, substeps=0)
        with self.assertRaisesRegex(ValueError, "control_period must be a time > 0"):
            sf.Env(ARM, control_period=float("nan"))
        scene.analysis.kind = sf.AnalysisKind.STATIC
        with self.assertRaisesRegex(ValueError, "static"):
            sf.Env(scene)
        with self.assertRaisesRegex(ValueError, "n must be an integer >= 1"):
            sf.VectorEnv(0, ARM)

    def test_action_inputs_names(self):
        with self.assertRaisesRegex(KeyError, "no input named 'v'.*'u'"):
            sf.Env(ARM, action_inputs=["v"])
        with self.assertRaisesRegex(ValueError, "twice"):
            sf.Env(ARM, action_inputs=["u", "u"])
        env = sf.Env(ARM, action_inputs=[])  # no action: u keeps its default
        env.reset()
        env.step(np.empty(0))
        self.assertEqual(env.sim.inputs["u"], 0.0)


class EnvDeterminismTest(unittest.TestCase):
    @staticmethod
    def rollout(env, seed, steps=40):
        """Observations and rewards of `steps` sampled actions after reset(seed)."""
        obs, _ = env.reset(seed=seed)
        trajectory, rewards = [obs], []
        for _ in range(steps):
            obs, reward, terminated, truncated, _ = env.step(env.action_space.sample())
            assert not (terminated or truncated)
            trajectory.append(obs)
            rewards.append(reward)
        return np.array(trajectory), np.array(rewards)

    def test_same_seed_same_trajectory_other_seed_differs(self):
        a = sf.Env(ARM, reward=tip_reward)
        b = sf.Env(ARM, reward=tip_reward)
        obs_a, rew_a = self.rollout(a, 7)
        obs_b, rew_b = self.rollout(b, 7)
        self.assertTrue(same_bits(obs_a, obs_b))
        self.assertTrue(same_bits(rew_a, rew_b))
        # The same Env reset with the same seed repeats its episode too.
        obs_again, rew_again = self.rollout(a, 7)
        self.assertTrue(same_bits(obs_a, obs_again) and same_bits(rew_a, rew_again))
        # Another seed samples other tensions (a tendon pulls for u > 0): other motions.
        obs_c, rew_c = self.rollout(b, 8)
        self.assertFalse(np.array_equal(obs_a, obs_c))
        self.assertFalse(np.array_equal(rew_a, rew_c))

    def test_reset_noise_gets_the_seeded_generator(self):
        def noise(sim, rng):
            sim.v[:] = 1e-3 * rng.standard_normal(sim.v.shape)  # before initialize()

        env = sf.Env(ARM, observe="state", reset_noise=noise)
        first, _ = env.reset(seed=3)
        again, _ = env.reset(seed=3)
        other, _ = env.reset(seed=4)
        self.assertTrue(same_bits(first, again))
        self.assertFalse(np.array_equal(first, other))
        self.assertNotEqual(np.abs(first[-env.sim.model.nv:]).max(), 0.0)


class EnvPhysicsTest(unittest.TestCase):
    def test_constant_tension_matches_a_simulation_bit_for_bit(self):
        # u = 2 N held for 0.5 s: the Env (C++ stepping through _step_many, 5 steps per
        # control period) and a Simulation stepped by Python with sim.step(h) reach the same
        # state, bit for bit.
        u, substeps, periods = 2.0, 5, 50
        env = sf.Env(ARM, substeps=substeps)
        env.reset()
        z_pulled = np.array([env.step([u])[0][2] for _ in range(periods)])
        obs = env.step([u])[0]

        sim = sf.Simulation(sf.load_scene(ARM))
        sim.initialize()
        sim.inputs["u"] = u
        h = env.h
        for _ in range((periods + 1) * substeps):
            sim.step(h)
        tip = sim.point_motion("tip")
        self.assertEqual(sim.time, env.sim.time)
        self.assertTrue(same_bits(obs[:3], tip.position))
        self.assertTrue(same_bits(obs[3:], tip.velocity))
        self.assertTrue(same_bits(sim.v, env.sim.v))
        self.assertEqual(sim.iterations, env.sim.iterations)

        # Physics: released from rest, the arm swings about its sagging equilibrium (lightly
        # damped). The tendon's constant pull is a step load: the difference between the
        # pulled and the slack arm's tip heights is the step response of the (nearly linear)
        # arm, which rises from 0 and stays between 0 and twice its static value dz_static
        # (the static solutions under u and 0; about 1 cm for 2 N). Measured: 0.09 to 1.76
        # dz_static.
        slack = sf.Env(ARM, substeps=substeps)
        slack.reset()
        z_slack = np.array([slack.step([0.0])[0][2] for _ in range(periods)])
        statics = []
        for tension in (0.0, u):
            s = sf.Simulation(sf.load_scene(ARM))
            s.inputs["u"] = tension
            s.solve_static()
            statics.append(s.point_motion("tip").position[2])
        dz_static = statics[1] - statics[0]
        self.assertGreater(dz_static, 0.005)
        dz = z_pulled - z_slack
        self.assertGreater(dz.min(), 0.0)
        self.assertLess(dz.max(), 2.0 * dz_static)
        self.assertGreater(dz.max(), 1.2 * dz_static)  # it overshoots: dynamics, not statics

    def test_static_preload_starts_at_equilibrium(self):
        # analysis.static_preload: reset() solves the sagging equilibrium before initialize(),
        # as run_scene does; the unactuated arm then stays there.
        scene = sf.load_scene(ARM, ["analysis.static_preload=true"])
        env = sf.Env(scene)
        obs, _ = env.reset()
        static = sf.Simulation(scene)
        static.solve_static()
        np.testing.assert_array_equal(obs[:3], static.point_motion("tip").position)
        self.assertLess(obs[2], -0.04)  # sagged about 4.3 cm
        for _ in range(10):
            obs = env.step([0.0])[0]
        np.testing.assert_allclose(obs[:3], static.point_motion("tip").position, atol=1e-9)
        np.testing.assert_allclose(obs[3:], 0.0, atol=1e-9)

    def test_vector_env_copies_equal_single_envs(self):
        # Three copies with different tensions, on 1 and on 3 threads, against three Envs.
        tensions = np.array([[0.0], [0.3], [0.6]])
        singles = [sf.Env(ARM, substeps=4) for _ in tensions]
        for e in singles:
            e.reset()
        for threads in (1, 3, None):
            venv = sf.VectorEnv(3, ARM, threads=threads, substeps=4)
            obs, info = venv.reset(seed=0)
            self.assertEqual(obs.shape, (3, 6))
            np.testing.assert_array_equal(info["steps"], [0, 0, 0])
            trajectory = [venv.step(tensions)[0] for _ in range(30)]
            if threads == 1:
                expected = [np.array([e.step(t)[0] for e, t in zip(singles, tensions)])
                            for _ in range(30)]
            for got, want in zip(trajectory, expected):
                self.assertTrue(same_bits(got, want), f"threads={threads}")
            for i in range(3):
                self.assertTrue(same_bits(venv.envs[i].sim.v, singles[i].sim.v))
        # Different tensions, different tips: the copies are independent.
        self.assertLess(trajectory[-1][0, 2], trajectory[-1][1, 2])
        self.assertLess(trajectory[-1][1, 2], trajectory[-1][2, 2])


def vector_rollout(tensions, steps=20):
    """Observations of a VectorEnv of len(tensions) copies of the arm, each holding its
    tension, on as many threads as the machine has (module level: a forked child runs it)."""
    venv = sf.VectorEnv(len(tensions), ARM, substeps=2)
    venv.reset(seed=0)
    actions = np.array(tensions, dtype=float).reshape(-1, 1)
    return np.array([venv.step(actions)[0] for _ in range(steps)])


class ThreadPoolTest(unittest.TestCase):
    """_step_many keeps its worker threads between calls: they must serve calls from several
    Python threads and from a forked child, which has none of its parent's threads."""

    def test_calls_from_two_python_threads(self):
        expected = vector_rollout([0.5, 1.0, 1.5])
        results = [None, None]

        def run(k):
            results[k] = vector_rollout([0.5, 1.0, 1.5])

        threads = [threading.Thread(target=run, args=(k,)) for k in range(2)]
        for t in threads:
            t.start()
        for t in threads:
            t.join(timeout=120)
        for r in results:
            self.assertTrue(same_bits(r, expected))

    def test_forked_child_steps_on_its_own_pool(self):
        expected = vector_rollout([0.5, 1.0])  # the parent's pool is running now
        context = multiprocessing.get_context("fork")
        with context.Pool(1) as pool:
            got = pool.apply_async(vector_rollout, ([0.5, 1.0],)).get(timeout=120)
        self.assertTrue(same_bits(got, expected))


class EnvErrorTest(unittest.TestCase):
    def test_bad_actions_raise_value_error(self):
        env = sf.Env(ARM)
        env.reset()
        for bad, pattern in (([0.1, 0.2], r"shape \(2,\), expected \(1,\).*\['u'\]"),
                             ([[0.1]], r"shape \(1, 1\), expected \(1,\)"),
                             ([np.nan], r"action\[0\] \(input 'u'\) is nan.*finite"),
                             ([np.inf], r"input 'u'.*finite"),
                             (["high"], "not an array of numbers")):
            with self.assertRaisesRegex(ValueError, pattern):
                env.step(bad)
        self.assertEqual(env.sim.steps, 0)  # nothing stepped
        env.step(0.1)  # one input: a scalar is accepted
        self.assertEqual(env.sim.inputs["u"], 0.1)

        venv = sf.VectorEnv(2, ARM)
        venv.reset()
        with self.assertRaisesRegex(ValueError, r"shape \(2,\), expected \(2, 1\)"):
            venv.step([0.1, 0.2])
        with self.assertRaisesRegex(ValueError, r"copy 1: action\[0\] \(input 'u'\) is nan"):
            venv.step([[0.4], [np.nan]])
        # The good row was not written either: nothing changed.
        self.assertEqual([e.sim.inputs["u"] for e in venv.envs], [0.0, 0.0])
        self.assertEqual([e.sim.steps for e in venv.envs], [0, 0])

    def test_failed_step_terminates_with_the_message(self):
        scene = fragile_arm()
        env = sf.Env(scene)
        env.reset()
        obs, reward, terminated, truncated, info = env.step([1.0])
        self.assertTrue(terminated)
        self.assertFalse(truncated)
        # The message Simulation.step raises for the same step.
        sim = sf.Simulation(scene)
        sim.initialize()
        sim.inputs["u"] = 1.0
        with self.assertRaises(sf.SolverError) as caught:
            sim.step(env.h)
        self.assertEqual(info["error"], str(caught.exception))
        self.assertIn("Newton did not converge", info["error"])
        # The state is the one at the failed step's start: the tip at rest.
        np.testing.assert_array_equal(obs, [0.3, 0, 0, 0, 0, 0])
        self.assertEqual(env.sim.time, 0.0)
        with self.assertRaisesRegex(RuntimeError, "episode has ended"):
            env.step([0.0])
        env.reset()
        self.assertFalse(env.step([0.0])[2])  # u = 0 converges in 3 iterations

    def test_vector_env_failed_copy_autoresets(self):
        venv = sf.VectorEnv(2, fragile_arm())
        venv.reset(seed=1)
        obs, reward, terminated, truncated, info = venv.step([[0.0], [1.0]])
        np.testing.assert_array_equal(terminated, [False, True])
        np.testing.assert_array_equal(truncated, [False, False])
        np.testing.assert_array_equal(info["_final_obs"], [False, True])
        np.testing.assert_array_equal(info["_final_info"], [False, True])
        self.assertIsNone(info["final_obs"][0])
        self.assertIn("Newton did not converge", info["final_info"][1]["error"])
        np.testing.assert_array_equal(info["final_obs"][1], [0.3, 0, 0, 0, 0, 0])
        # Copy 1 starts over; copy 0 went on.
        np.testing.assert_array_equal(info["steps"], [1, 0])
        self.assertEqual(info["time"][1], 0.0)
        self.assertEqual(venv.envs[1].sim.inputs["u"], 0.0)  # a fresh simulation
        self.assertEqual(venv.envs[0].sim.steps, 1)
        obs, _, terminated, _, info = venv.step([[0.0], [0.0]])
        np.testing.assert_array_equal(terminated, [False, False])
        self.assertNotIn("final_obs", info)

    def test_vector_env_truncation_autoresets_same_step(self):
        venv = sf.VectorEnv(2, ARM, max_steps=3)
        first, _ = venv.reset(seed=0)
        for k in range(3):
            obs, _, terminated, truncated, info = venv.step(np.full((2, 1), 0.2))
        np.testing.assert_array_equal(truncated, [True, True])
        np.testing.assert_array_equal(terminated, [False, False])
        np.testing.assert_array_equal(obs, first)  # the new episodes' first observations
        self.assertEqual(info["final_info"][0]["steps"], 3)
        self.assertFalse(np.array_equal(info["final_obs"][0], first[0]))
        np.testing.assert_array_equal(info["steps"], [0, 0])
        venv.step(np.full((2, 1), 0.2))  # the copies go on without reset()

    def test_step_many_checks(self):
        sim = sf.Simulation(sf.load_scene(ARM))
        with self.assertRaisesRegex(RuntimeError, r"sims\[0\] is not initialized"):
            _screwfem._step_many([sim], 1e-3)
        sim.initialize()
        with self.assertRaisesRegex(ValueError, "twice"):
            _screwfem._step_many([sim, sim], 1e-3)
        with self.assertRaisesRegex(ValueError, "h must be"):
            _screwfem._step_many([sim], 0.0)
        with self.assertRaisesRegex(ValueError, "substeps"):
            _screwfem._step_many([sim], 1e-3, 0)
        self.assertEqual(_screwfem._step_many([], 1e-3), [])
        self.assertEqual(_screwfem._step_many([sim], 1e-3, 3), [""])
        self.assertEqual(sim.steps, 3)


if __name__ == "__main__":
    unittest.main()
