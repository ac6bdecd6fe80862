"""Reinforcement-learning environments over a scene: ``Env`` and ``VectorEnv``.

The API is Gymnasium's (``reset(seed) -> (obs, info)``, ``step(action) -> (obs, reward,
terminated, truncated, info)``, ``action_space`` and ``observation_space`` boxes) without
depending on gymnasium, which Debian does not package: ``Box`` is a small stand-in for
``gymnasium.spaces.Box``. A wrapper that subclasses ``gymnasium.Env`` needs only to forward
these calls.

The physics runs in C++: ``Env.step`` writes the action into the scene's run-time inputs
(``inputs:``, docs/scene-format.md) and advances the simulation by one control period in equal
fixed steps; ``VectorEnv`` steps its copies on C++ threads with the GIL released
(``screwfem._screwfem._step_many``, python/bind_env.cpp). docs/python.md, "Environments",
describes both with measured throughput.
"""

import math
import numbers
import os

import numpy as np

from ._screwfem import AnalysisKind, Scene, Simulation, _step_many, load_scene

__all__ = ["Box", "Env", "VectorEnv"]


class Box:
    """A box in R^shape, [low, high] per component (gymnasium.spaces.Box's interface).

    ``low`` and ``high`` are scalars or arrays broadcast to ``shape``; -inf and inf leave a side
    unbounded. ``sample()`` draws as gymnasium does: uniform on a bounded component, low +
    Exponential(1) or high - Exponential(1) on a half-bounded one, Normal(0, 1) on an unbounded
    one, from the box's own numpy Generator (``seed(s)``; Env.reset(seed) seeds its action
    space). ``contains(x)`` tests shape, dtype castability and bounds.
    """

    def __init__(self, low, high, shape=None, dtype=np.float64, seed=None):
        """Box(low, high, shape=None, dtype=numpy.float64, seed=None); shape defaults to the
        broadcast shape of low and high."""
        self.dtype = np.dtype(dtype)
        low = np.asarray(low, dtype=self.dtype)
        high = np.asarray(high, dtype=self.dtype)
        if shape is None:
            shape = np.broadcast_shapes(low.shape, high.shape)
        self.shape = tuple(int(s) for s in shape)
        self.low = np.array(np.broadcast_to(low, self.shape), dtype=self.dtype)
        self.high = np.array(np.broadcast_to(high, self.shape), dtype=self.dtype)
        if np.isnan(self.low).any() or np.isnan(self.high).any():
            raise ValueError("Box: low and high must not be NaN")
        if (self.low > self.high).any():
            raise ValueError("Box: low must be <= high in every component")
        self._rng = np.random.default_rng(seed)

    def seed(self, seed=None):
        """Reseeds the Generator of sample() (None: fresh entropy from the OS)."""
        self._rng = np.random.default_rng(seed)

    @property
    def np_random(self):
        """The numpy Generator sample() draws from."""
        return self._rng

    def sample(self):
        """A random point of the box (a new array of shape `shape`, dtype `dtype`)."""
        rng = self._rng
        bounded_low = np.isfinite(self.low)
        bounded_high = np.isfinite(self.high)
        out = rng.normal(size=self.shape)
        lower = bounded_low & ~bounded_high
        upper = ~bounded_low & bounded_high
        both = bounded_low & bounded_high
        if lower.any():
            out[lower] = self.low[lower] + rng.exponential(size=int(lower.sum()))
        if upper.any():
            out[upper] = self.high[upper] - rng.exponential(size=int(upper.sum()))
        if both.any():
            out[both] = rng.uniform(self.low[both], self.high[both])
        return out.astype(self.dtype, copy=False)

    def contains(self, x):
        """True if x has the box's shape, a dtype that casts safely to its dtype, and every
        component within [low, high] (NaN is outside)."""
        x = np.asarray(x)
        if x.shape != self.shape or not np.can_cast(x.dtype, self.dtype):
            return False
        with np.errstate(invalid="ignore"):
            return bool(np.all((x >= self.low) & (x <= self.high)))

    def __contains__(self, x):
        return self.contains(x)

    def __eq__(self, other):
        return (isinstance(other, Box) and self.shape == other.shape
                and self.dtype == other.dtype and np.array_equal(self.low, other.low)
                and np.array_equal(self.high, other.high))

    def __repr__(self):
        lo = np.unique(self.low)
        hi = np.unique(self.high)
        low = lo[0] if lo.size == 1 else "array"
        high = hi[0] if hi.size == 1 else "array"
        return f"Box({low}, {high}, {self.shape}, {self.dtype})"


def _as_scene(scene):
    """A Scene from a Scene or a path to a scene file."""
    if isinstance(scene, Scene):
        return scene
    if isinstance(scene, (str, os.PathLike)):
        return load_scene(os.fspath(scene))
    raise TypeError(f"Env: scene must be a screwfem.Scene or a path, got {type(scene).__name__}")


def _observer(observe, sim):
    """f(sim) -> a new float64 array, for the `observe` argument of Env."""
    if callable(observe):
        def user(s):
            return np.array(observe(s), dtype=np.float64)
        return user
    if observe == "points":
        names = [p.name for p in sim.scene.outputs.points]
        if not names:
            raise ValueError("Env: observe='points' needs output points (the scene's "
                             "outputs.points is empty)")
        size = 6 * len(names)

        def points(s):
            out = np.empty(size)
            for i, name in enumerate(names):
                m = s.point_motion(name)
                out[6 * i:6 * i + 3] = m.position
                out[6 * i + 3:6 * i + 6] = m.velocity
            return out
        return points
    if observe == "joints":
        nv_nodes = sim.model.nv_nodes
        if sim.model.nv == nv_nodes:
            raise ValueError("Env: observe='joints' needs joint coordinates (the scene's joints "
                             "have none: only fixed joints or none at all)")

        def joints(s):
            return np.concatenate((s.q_joint, s.v[nv_nodes:]))
        return joints
    if observe == "state":
        def state(s):
            return np.concatenate((s.node_frames()[:, :3, 3].ravel(), s.v))
        return state
    raise ValueError(f"Env: observe must be 'points', 'joints', 'state' or a callable "
                     f"f(sim) -> array, got {observe!r}")


def _positive_int(value, what):
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or value < 1:
        raise ValueError(f"Env: {what} must be an integer >= 1, got {value!r}")
    return int(value)


class Env:
    """Env(scene, *, observe="points", reward=None, terminated=None, control_period=None,
    substeps=1, max_steps=None, action_inputs=None, action_bounds=None, reset_noise=None)

    A Gymnasium-style environment over a scene (a screwfem.Scene or a path to a scene file;
    the Env keeps its own copy). The action is one value per run-time input of the scene
    (``inputs:``), in the order of `action_inputs` (default: all inputs, in Model.input_names
    order). step(action) writes it into the simulation's inputs (as ``sim.inputs[name] =
    value``; a zero-order hold over the control period) and advances `control_period` seconds
    in `substeps` fixed steps of h = control_period / substeps (Simulation.step(h), generalized
    alpha with the scene's analysis.dynamic options). control_period defaults to substeps x
    the scene's analysis.step (with ``step: auto``: its first step).

    observe: what an observation is, a new float64 array each step:
      "points"  per output point of the scene (outputs.points, in order) its world position
                and velocity, 6 values [m, m/s] (Simulation.point_motion);
      "joints"  the joint coordinates then their rates (Simulation.q_joint, then v after
                Model.nv_nodes) [m or rad, m/s or rad/s];
      "state"   every node's world position (3 per node, Simulation.node_frames) then the
                velocity vector Simulation.v (body velocities of the free nodes, then the joint
                rates);
      f(sim)    a callable returning an array (copied).
    reward(sim, obs, action) -> float (default 0.0) and terminated(sim, obs, action) -> bool
    (default False) are called after every step with the validated action (a float64 array).

    Episodes are truncated after `max_steps` steps (None: no limit) or once the simulated time
    reaches the scene's analysis.end_time (to within half a control period). A step whose
    time integration fails (SolverError: Newton did not converge after every halving) ends the
    episode with terminated=True and info["error"] = the solver's message; the state is then
    the one at the start of the failed time step, and obs and reward are computed from it.
    After the end of an episode, step() raises RuntimeError until reset().

    Action bounds: scene inputs declare a default value and no range, so action_space is
    unbounded (-inf..inf) unless `action_bounds` = (low, high) is given (scalars or one value
    per action component); actions outside given bounds are clipped to them (MuJoCo's ctrlrange
    convention). Actions must be finite and of shape action_space.shape (a scalar is accepted
    when there is one input): otherwise step raises ValueError.

    Seeding: reset(seed) seeds action_space.sample() and the Generator `np_random` handed to
    `reset_noise`, nothing else: the physics is deterministic, so the same seed with the same
    policy repeats an episode bit for bit. reset_noise(sim, rng), if given, is called on each
    fresh Simulation before its static preload and initialize(), to randomise its initial
    state or parameters (e.g. sim.v[...] = rng.normal(...), sim.set_joint_stiffness).

    Stepping runs in C++ with the GIL released (screwfem._screwfem._step_many), so Envs in
    different Python threads step in parallel; VectorEnv does this on its own threads.
    Ctrl-C is handled between steps, not inside one.
    """

    metadata = {"render_modes": []}

    def __init__(self, scene, *, observe="points", reward=None, terminated=None,
                 control_period=None, substeps=1, max_steps=None, action_inputs=None,
                 action_bounds=None, reset_noise=None):
        scene = _as_scene(scene)
        if scene.analysis.kind != AnalysisKind.DYNAMIC:
            raise ValueError("Env: the scene's analysis is static; an Env steps a dynamic "
                             "analysis (analysis: {type: dynamic})")
        # The template: a private copy of the scene (Simulation copies it), initialised once to
        # check the observation, and the scene every reset() copies again.
        self._template = Simulation(scene)
        self.scene = self._template.scene
        """The Env's copy of the scene (changes affect the following resets)."""
        self._substeps = _positive_int(substeps, "substeps")
        if control_period is None:
            h = self.scene.analysis.step  # the scene's step exactly, not (substeps h) / substeps
            control_period = self._substeps * h
        else:
            control_period = float(control_period)
            if not (math.isfinite(control_period) and control_period > 0.0):
                raise ValueError(f"Env: control_period must be a time > 0 s, got "
                                 f"{control_period!r}")
            h = control_period / self._substeps
        self.control_period = control_period
        """Simulated seconds per step() [s]."""
        self.h = h
        """Time step of the integrator [s]: control_period / substeps."""
        self.max_steps = None if max_steps is None else _positive_int(max_steps, "max_steps")
        """Steps after which an episode is truncated (None: only the scene's end_time)."""

        model_inputs = list(self.scene.model.input_names)
        if action_inputs is None:
            action_inputs = model_inputs
        elif isinstance(action_inputs, str):
            action_inputs = [action_inputs]
        action_inputs = list(action_inputs)
        for name in action_inputs:
            if name not in model_inputs:
                known = ", ".join(f"'{n}'" for n in model_inputs) or "none"
                raise KeyError(f"Env: action_inputs: no input named '{name}' (the scene's "
                               f"inputs: {known})")
        if len(set(action_inputs)) != len(action_inputs):
            raise ValueError(f"Env: action_inputs names an input twice: {action_inputs}")
        self.action_names = tuple(action_inputs)
        """The inputs the action components set, in order."""
        self._input_index = np.array([model_inputs.index(n) for n in action_inputs], dtype=np.intp)

        dim = len(action_inputs)
        low, high = (-np.inf, np.inf) if action_bounds is None else action_bounds
        self.action_space = Box(low, high, shape=(dim,))
        """Box of shape (len(action_names),): unbounded unless action_bounds was given."""
        self._clip = bool(np.isfinite(self.action_space.low).any()
                          or np.isfinite(self.action_space.high).any())

        if reward is not None and not callable(reward):
            raise TypeError("Env: reward must be a callable f(sim, obs, action) -> float")
        if terminated is not None and not callable(terminated):
            raise TypeError("Env: terminated must be a callable f(sim, obs, action) -> bool")
        if reset_noise is not None and not callable(reset_noise):
            raise TypeError("Env: reset_noise must be a callable f(sim, rng)")
        self._reward = reward
        self._terminated = terminated
        self._reset_noise = reset_noise
        self._observe = _observer(observe, self._template)
        self._template.initialize()
        probe = self._observe(self._template)
        if probe.ndim == 0:
            raise ValueError("Env: the observation must be an array, got a scalar")
        self.observation_space = Box(-np.inf, np.inf, shape=probe.shape)
        """Box of the observation's shape, unbounded."""

        self.np_random = None
        """The numpy Generator handed to reset_noise (seeded by reset(seed))."""
        self.sim = None
        """The current episode's Simulation (None before the first reset)."""
        self._sims = []
        self._inputs = None
        self._end_time = math.inf
        self._steps = 0
        self._done = False

    # -- Gymnasium API -------------------------------------------------------------------------

    def reset(self, seed=None, options=None):
        """reset(seed=None, options=None) -> (obs, info)

        Starts an episode on a fresh Simulation of the scene: the initial state of the scene
        (reference configuration, initial_position / initial_velocity, the inputs' default
        values), reset_noise(sim, np_random) if given, the static preload if the scene asks for
        one (analysis.static_preload), then initialize(). `seed` (an int) reseeds
        action_space.sample() and np_random; None continues their streams (the first reset
        without a seed seeds them from the OS). `options` is accepted for Gymnasium's
        signature and ignored. A SolverError of the initial state propagates (a scene that
        cannot start is not an episode). info: {"time": start time [s], "steps": 0}.
        """
        if seed is not None or self.np_random is None:
            noise_seed, action_seed = np.random.SeedSequence(seed).spawn(2)
            self.np_random = np.random.default_rng(noise_seed)
            self.action_space.seed(action_seed)
        sim = Simulation(self.scene)
        if self._reset_noise is not None:
            self._reset_noise(sim, self.np_random)
        if self.scene.analysis.static_preload:
            sim.solve_static()
        sim.initialize()
        self.sim = sim
        self._sims = [sim]
        self._end_time = self.scene.analysis.end_time
        self._inputs = sim.input_values  # a writable view of the simulation's inputs
        self._steps = 0
        self._done = False
        obs = self._observation()
        return obs, {"time": sim.time, "steps": 0}

    def step(self, action):
        """step(action) -> (obs, reward, terminated, truncated, info)

        Writes `action` into the inputs named by action_names, advances control_period
        seconds in `substeps` steps, and returns the observation, reward(sim, obs, action),
        terminated (the terminated callable, or a failed time step), truncated (max_steps or
        the scene's end_time reached) and info {"time": t [s], "steps": steps in this episode,
        "error": the solver's message, only after a failed step}. Raises ValueError for an
        action of the wrong shape or not finite, RuntimeError before reset() or after the
        episode ended.
        """
        self._ready("Env.step")
        a = self._check_action(action)
        self._write_action(a)
        error = _step_many(self._sims, self.h, self._substeps)[0]
        return self._end_step(a, error)

    def close(self):
        """Releases the simulation (Gymnasium's close; the Env can be reset again)."""
        self.sim = None
        self._sims = []
        self._inputs = None

    @property
    def unwrapped(self):
        """This Env (Gymnasium's unwrapped)."""
        return self

    @property
    def substeps(self):
        """Integrator steps per step()."""
        return self._substeps

    @property
    def episode_steps(self):
        """step() calls since the last reset."""
        return self._steps

    def __repr__(self):
        return (f"<screwfem.Env '{self.scene.name}' actions={list(self.action_names)} "
                f"obs={self.observation_space.shape} control_period={self.control_period}>")

    # -- shared with VectorEnv -----------------------------------------------------------------

    def _check_action(self, action, where="Env.step"):
        """The action as a float64 array of action_space's shape, clipped to the bounds;
        ValueError if it has another shape or a value that is not finite."""
        try:
            a = np.asarray(action, dtype=np.float64)
        except (TypeError, ValueError) as e:
            raise ValueError(f"{where}: the action is not an array of numbers ({e})") from None
        shape = self.action_space.shape
        if a.shape != shape:
            if a.ndim == 0 and shape == (1,):
                a = a.reshape(1)
            else:
                raise ValueError(f"{where}: action of shape {a.shape}, expected {shape} (one "
                                 f"value per input: {list(self.action_names)})")
        finite = np.isfinite(a)
        if not finite.all():
            i = int(np.argmin(finite))
            raise ValueError(f"{where}: action[{i}] (input '{self.action_names[i]}') is "
                             f"{a[i]}; actions must be finite")
        if self._clip:
            a = np.clip(a, self.action_space.low, self.action_space.high)
        return a

    def _ready(self, where):
        if self.sim is None:
            raise RuntimeError(f"{where}: call reset() first")
        if self._done:
            raise RuntimeError(f"{where}: the episode has ended (terminated or truncated); "
                               "call reset()")

    def _write_action(self, a):
        """Writes a checked action into the simulation's inputs (Data::inputs)."""
        self._inputs[self._input_index] = a

    def _end_step(self, a, error):
        """The step's (obs, reward, terminated, truncated, info) after _step_many returned
        `error` ("" on success) for this Env's simulation."""
        sim = self.sim
        self._steps += 1
        obs = self._observation()
        reward = 0.0 if self._reward is None else float(self._reward(sim, obs, a))
        terminated = bool(error) or (
            self._terminated is not None and bool(self._terminated(sim, obs, a)))
        truncated = ((self.max_steps is not None and self._steps >= self.max_steps)
                     or sim.time > self._end_time - 0.5 * self.control_period)
        info = {"time": sim.time, "steps": self._steps}
        if error:
            info["error"] = error
        self._done = terminated or truncated
        return obs, reward, terminated, truncated, info

    def _observation(self):
        obs = self._observe(self.sim)
        if obs.shape != self.observation_space.shape:
            raise ValueError(f"Env: the observation has shape {obs.shape}, expected "
                             f"{self.observation_space.shape} (the first one's)")
        return obs


class VectorEnv:
    """VectorEnv(n, scene, *, threads=None, **env_kwargs)

    n independent copies of Env(scene, **env_kwargs), stepped together: step(actions) writes
    each copy's action, advances all copies on C++ threads with the GIL released (up to
    `threads` threads, default one per hardware thread, never more than n; each thread steps a
    contiguous share of the copies), then computes observations, rewards and terminations in
    Python. Results are stacked: obs (n, *obs_shape), reward (n,) float64, terminated and
    truncated (n,) bool. The copies' trajectories are bit for bit those of n single Envs
    given the same actions.

    Autoreset, same step (Gymnasium's AutoresetMode.SAME_STEP): a copy whose episode ends in a
    step is reset within that step. Its row of obs is then the first observation of the new
    episode; reward, terminated and truncated are those of the step that ended the old one,
    whose observation and info are in info["final_obs"][i] and info["final_info"][i] (object
    arrays, None for the other copies; boolean masks info["_final_obs"] and
    info["_final_info"]). A failed time step's message is thus info["final_info"][i]["error"].
    info also holds "time" and "steps" (arrays over the copies: time [s] and steps of the
    current episode, after any reset).

    Seeding: reset(seed) resets copy i with seed + i (None: each continues its stream);
    autoresets continue the copy's stream. `single_action_space` and
    `single_observation_space` are the copies' boxes; `action_space` and `observation_space`
    the batched ones, with n as the first dimension.
    """

    metadata = {"render_modes": [], "autoreset_mode": "SameStep"}

    def __init__(self, n, scene, *, threads=None, **env_kwargs):
        if isinstance(n, bool) or not isinstance(n, numbers.Integral) or n < 1:
            raise ValueError(f"VectorEnv: n must be an integer >= 1, got {n!r}")
        if threads is not None and (isinstance(threads, bool)
                                    or not isinstance(threads, numbers.Integral) or threads < 1):
            raise ValueError(f"VectorEnv: threads must be an integer >= 1 or None, got {threads!r}")
        scene = _as_scene(scene)  # loaded once for all copies
        self.num_envs = int(n)
        """Number of copies."""
        self.envs = [Env(scene, **env_kwargs) for _ in range(self.num_envs)]
        """The copies (Env objects; step them only through this VectorEnv)."""
        self.threads = 0 if threads is None else int(threads)
        """Most threads a step uses (0: one per hardware thread)."""
        first = self.envs[0]
        self.single_action_space = first.action_space
        """The action space of one copy."""
        self.single_observation_space = first.observation_space
        """The observation space of one copy."""
        self.action_space = Box(first.action_space.low, first.action_space.high,
                                shape=(self.num_envs,) + first.action_space.shape)
        """Box of shape (n, action_dim): the stacked actions step() takes."""
        self.observation_space = Box(-np.inf, np.inf,
                                     shape=(self.num_envs,) + first.observation_space.shape)
        """Box of shape (n, *obs_shape): the stacked observations."""
        self._sims = [None] * self.num_envs
        self._h = first.h
        self._substeps = first.substeps

    def reset(self, seed=None, options=None):
        """reset(seed=None, options=None) -> (obs, info)

        Resets every copy (copy i with seed + i if seed is given); obs is (n, *obs_shape),
        info {"time": (n,), "steps": (n,)}. The batched action_space is seeded with `seed`.
        """
        obs = np.empty(self.observation_space.shape)
        for i, env in enumerate(self.envs):
            obs[i], _ = env.reset(seed=None if seed is None else seed + i, options=options)
            self._sims[i] = env.sim
        if seed is not None:
            self.action_space.seed(seed)
        return obs, self._info()

    def step(self, actions):
        """step(actions) -> (obs, reward, terminated, truncated, info)

        actions: (n, action_dim), row i for copy i (ValueError for another shape or a value
        that is not finite, naming the copy). Returns stacked arrays; finished copies are reset
        in the same step (see the class docstring for info["final_obs"] and
        info["final_info"]).
        """
        try:
            a = np.asarray(actions, dtype=np.float64)
        except (TypeError, ValueError) as e:
            raise ValueError(f"VectorEnv.step: the actions are not an array of numbers ({e})") \
                from None
        want = self.action_space.shape
        if a.shape != want:
            raise ValueError(f"VectorEnv.step: actions of shape {a.shape}, expected {want} (one "
                             f"row per copy, one column per input: "
                             f"{list(self.envs[0].action_names)})")
        # Every copy's action is checked before any is written: a bad row changes nothing.
        rows = []
        for i, env in enumerate(self.envs):
            where = f"VectorEnv.step: copy {i}"
            env._ready(where)
            rows.append(env._check_action(a[i], where))
        for env, row in zip(self.envs, rows):
            env._write_action(row)
        errors = _step_many(self._sims, self._h, self._substeps, self.threads)

        n = self.num_envs
        obs = np.empty(self.observation_space.shape)
        reward = np.empty(n)
        terminated = np.zeros(n, dtype=bool)
        truncated = np.zeros(n, dtype=bool)
        final_obs = final_info = None
        for i, env in enumerate(self.envs):
            o, reward[i], terminated[i], truncated[i], info = env._end_step(rows[i], errors[i])
            if terminated[i] or truncated[i]:
                if final_obs is None:
                    final_obs = np.full(n, None, dtype=object)
                    final_info = np.full(n, None, dtype=object)
                final_obs[i], final_info[i] = o, info
                o, _ = env.reset()
                self._sims[i] = env.sim
            obs[i] = o
        info = self._info()
        if final_obs is not None:
            done = terminated | truncated
            info.update(final_obs=final_obs, _final_obs=done, final_info=final_info,
                        _final_info=done.copy())
        return obs, reward, terminated, truncated, info

    def close(self):
        """Releases the copies' simulations."""
        for env in self.envs:
            env.close()
        self._sims = [None] * self.num_envs

    def __len__(self):
        return self.num_envs

    def __repr__(self):
        return f"<screwfem.VectorEnv n={self.num_envs} of {self.envs[0]!r}>"

    def _info(self):
        return {"time": np.array([e.sim.time for e in self.envs]),
                "steps": np.array([e.episode_steps for e in self.envs])}
