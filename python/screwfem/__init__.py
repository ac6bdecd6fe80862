"""screwfem: geometrically exact screw-based finite elements for articulated soft robots.

A thin package over the compiled module ``screwfem._screwfem`` (pybind11 bindings of the C++
library, include/screwfem). Names follow the C++ API in snake_case: ``load_scene``
(LoadScene), ``run_scene`` (RunScene), ``Simulation`` (Model + Data + Integrator, with
``initialize`` = InitializeDynamics, ``step`` = Step, ``solve_static`` = SolveStatic,
``calc_energy`` = CalcEnergy, ``calc_node_point_motion`` = CalcNodePointMotion, ...).

Units are SI (m, kg, s, N, rad). Point positions, velocities and accelerations are in the
world frame; node velocities in ``Simulation.v`` are body velocities [v; w] in the node frame.
Invalid input raises ``InputError`` (a ValueError), numerical failure ``SolverError`` (a
RuntimeError).

``SceneSpec`` is the scene as data (python/screwfem/_spec.py): built in code with its adders
(``add_soft_body``, ``add_joint``, ...) or read from a file with ``read_scene_spec``, then
``compile()``d into a Scene; docs/python.md, "Building a scene in code".

``sweep`` runs many variants of a scene (a grid, a list or random samples of overrides) as Dask
tasks and returns a pandas DataFrame (screwfem/_sweep.py); ``python3 -m screwfem sweep`` is its
command line.

``Env`` and ``VectorEnv`` are Gymnasium-style reinforcement-learning environments over a scene
(actions into its run-time inputs, ``reset``/``step``, ``Box`` spaces); VectorEnv steps its
copies on C++ threads (screwfem/_env.py, docs/python.md).

``Simulation.view()`` shows a simulation stepped from Python in the browser viewer as it steps
(a ``LiveView``: a local server and a WebSocket; screwfem/_live.py, docs/python.md "Live view").
"""

from . import _screwfem
from ._screwfem import *  # noqa: F401,F403  (the package re-exports the module)
from ._screwfem import __version__
from ._spec import (  # noqa: F401  (the scene spec: python/screwfem/_spec.py)
    ActuatorSpec, BodyPointSpec, BodySpec, ContactSpec, ForceSpec, JointEntrySpec, LoadSpec,
    OutputPointSpec, OutputsSpec, SceneSpec, TendonSpec, read_scene_spec, route_helical,
    route_offset)
from ._env import Box, Env, VectorEnv  # noqa: F401  (environments: python/screwfem/_env.py)
from ._live import LiveView  # noqa: F401  (Simulation.view: python/screwfem/_live.py)
from ._sweep import (  # noqa: F401  (sweeps: python/screwfem/_sweep.py)
    DEFAULT_METRICS, ColumnMetric, Counters, MaxConstraintResidual, PeakJointEffort,
    PointPosition, Run, WallTime, format_overrides, format_summary, notable_variants,
    run_variant, short_names, summary_table, sweep, variant_id, variants, write_figures)

__all__ = [name for name in dir(_screwfem) if not name.startswith("_")] + [
    "sweep", "variants", "format_overrides", "variant_id", "run_variant", "Run", "PointPosition",
    "MaxConstraintResidual", "WallTime", "Counters", "PeakJointEffort", "DEFAULT_METRICS",
    "ColumnMetric", "short_names", "summary_table", "format_summary", "notable_variants",
    "write_figures"] + [
    "SceneSpec", "BodySpec", "JointEntrySpec", "LoadSpec", "BodyPointSpec", "TendonSpec",
    "ForceSpec", "ActuatorSpec", "OutputPointSpec", "ContactSpec", "OutputsSpec",
    "read_scene_spec", "route_offset", "route_helical", "Box", "Env", "VectorEnv", "LiveView"]
