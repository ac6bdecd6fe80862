"""Parameter sweeps: many variants of one scene, run as Dask tasks (screwfem.sweep).

A variant is a list of override strings ('key.path=value', docs/scene-format.md, "Overrides");
running it is parse_scene(text, path, overrides) + run_scene into a directory -- exactly what
`screwfem run SCENE --set ...` does -- followed by the metrics, functions of the run (class
Run). Each variant is one task: on a Dask cluster (a LocalCluster over this machine's cores
unless a client or scheduler address is given) or, with scheduler="serial", in this process.
Nothing here computes physics: metrics read what run_scene wrote (points.csv and joints.csv are
written with 17 significant digits, so the values read back are the simulated doubles).

Variants are identified by a stable hash of their override strings (variant_id), so a sweep
written to `outdir` can be resumed: rows are appended to OUTDIR/rows.jsonl as they complete,
one whole line each, flushed; a resumed sweep runs only the variants without a row.

Dask and pandas are imported when a sweep starts, so `import screwfem` stays light.
"""

import hashlib
import itertools
import json
import math
import numbers
import os
import pathlib
import shutil
import sys
import tempfile
import time

from ._screwfem import InputError, parse_memory_size, parse_scene, run_scene

__all__ = [
    "sweep", "variants", "format_overrides", "variant_id", "run_variant", "Run",
    "PointPosition", "MaxConstraintResidual", "WallTime", "Counters", "PeakJointEffort",
    "ColumnMetric", "DEFAULT_METRICS", "ROWS_FILE", "TABLE_FILE", "SUMMARY_FILE", "short_names",
    "summary_table", "format_summary", "notable_variants", "write_figures",
]

ROWS_FILE = "rows.jsonl"      # the journal: one JSON row per finished variant
TABLE_FILE = "results.csv"    # the table, rewritten from the journal at the end of a sweep
SUMMARY_FILE = "summary.csv"  # the tidy table: short parameter names, status and metrics
FIGURES_DIR = "figures"       # a figure of each metric against the parameters
MANIFEST_FILE = "sweep.json"  # scene file, its hash and the variant list of the sweep


# ---------------------------------------------------------------------------------------------
# Variants

def _format_value(value):
    """A parameter value as YAML text for an override: floats by repr (round-trips exactly)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, numbers.Integral):
        return str(int(value))
    if isinstance(value, numbers.Real):
        return repr(float(value))
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_format_value(v) for v in value) + "]"
    return str(value)


def _key_paths(key):
    """Override paths of a parameter key: 'a.b', a tuple of paths, or 'a.b+c.d' (one value set at
    every path)."""
    if isinstance(key, tuple):
        return list(key)
    return [p for p in str(key).split("+") if p]


def _key_name(key):
    return "+".join(_key_paths(key))


def short_names(keys):
    """{key name: short name} for the parameter keys of a sweep: the last component of each
    override path ('parameters.length' -> 'length', 'joints.J0.damping' -> 'damping'), with
    more components from the end where two keys would share a name ('J0.damping',
    'J1.damping'); a key of several paths joins the distinct ones with '+'."""
    paths = {_key_name(k): [p.split(".") for p in _key_paths(k)] for k in keys}
    depth = {name: 1 for name in paths}

    def short(name):
        parts = []
        for p in paths[name]:
            text = ".".join(p[-depth[name]:])
            if text not in parts:
                parts.append(text)
        return "+".join(parts)

    for _ in range(64):
        names = {n: short(n) for n in paths}
        clash = {n for n in paths if list(names.values()).count(names[n]) > 1}
        grow = {n for n in clash if any(depth[n] < len(p) for p in paths[n])}
        if not grow:
            return names
        for n in grow:
            depth[n] += 1
    return {n: n for n in paths}


def format_overrides(assignment):
    """Override strings of one variant: {key: value} -> ['path=value', ...] in key order."""
    out = []
    for key, value in assignment.items():
        text = _format_value(value)
        out.extend(f"{path}={text}" for path in _key_paths(key))
    return out


def variant_id(overrides):
    """Stable identity of a variant: the first 16 hex digits of SHA-256 of its override
    strings, one per line (order matters: overrides apply in order)."""
    return hashlib.sha256("\n".join(overrides).encode()).hexdigest()[:16]


def variants(parameters, samples=None, seed=0):
    """The variants of a sweep, as a list of {parameter name: value} dicts (in run order).

    `parameters` is one of
      - a grid: {key: [v1, v2, ...]} -> every combination (itertools.product, the last key
        varying fastest);
      - a list of {key: value} dicts -> those variants, in order;
      - with `samples=N`: {key: spec} -> N random variants from numpy.random.default_rng(seed),
        drawn sample by sample in key order, where spec is (low, high) (uniform on
        [low, high)), a list (one element, uniformly), or a callable f(rng) -> value.
    A key is an override path ('joints.J0.damping'), or several paths that take the same value:
    a tuple of paths or one string joined with '+'. Values become YAML text: bools
    true/false, integers as they are, other numbers by repr(float) (exact), lists as [a, b].
    """
    if samples is not None:
        import numpy as np

        if not isinstance(parameters, dict):
            raise TypeError("sweep: random samples need a dict "
                            "{key: (low, high) | list | callable}")
        rng = np.random.default_rng(seed)
        out = []
        for _ in range(int(samples)):
            row = {}
            for key, spec in parameters.items():
                if callable(spec):
                    row[key] = spec(rng)
                elif isinstance(spec, tuple) and len(spec) == 2:
                    row[key] = float(rng.uniform(spec[0], spec[1]))
                elif isinstance(spec, list) and spec:
                    row[key] = spec[int(rng.integers(len(spec)))]
                else:
                    raise TypeError(f"sweep: sample spec of '{_key_name(key)}' must be "
                                    "(low, high), a non-empty list or a callable")
            out.append(row)
        return out
    if isinstance(parameters, dict):
        keys = list(parameters)
        for key in keys:
            if not isinstance(parameters[key], (list, tuple)) or len(parameters[key]) == 0:
                raise TypeError(f"sweep: grid values of '{_key_name(key)}' must be a "
                                "non-empty list")
        combos = itertools.product(*(parameters[k] for k in keys))
        return [dict(zip(keys, combo)) for combo in combos]
    parameters = list(parameters)
    if not all(isinstance(v, dict) for v in parameters):
        raise TypeError("sweep: parameters must be a grid dict or a list of override dicts")
    return [dict(v) for v in parameters]


# ---------------------------------------------------------------------------------------------
# What a metric sees, and the built-in metrics

class Run:
    """One variant's run, as metrics see it (on the worker that ran it).

    Attributes: `overrides` (list of str), `variant_id`, `result` (RunResult: ok, steps,
    newton_iterations, halvings, max_constraint_residual, max_element_rotation, message, ...),
    `outdir` (pathlib.Path holding points.csv, joints.csv and summary.json while the metrics
    run), `wall_seconds` and `cpu_seconds` (load, compile and run, measured here: wall time,
    and CPU time of the thread that ran them).
    """

    def __init__(self, overrides, vid, result, outdir, wall_seconds, cpu_seconds):
        self.overrides = overrides
        self.variant_id = vid
        self.result = result
        self.outdir = pathlib.Path(outdir)
        self.wall_seconds = wall_seconds
        self.cpu_seconds = cpu_seconds
        self._tables = {}

    def table(self, name):
        """(columns, rows) of one of the run's tables, by file stem ('points', 'joints',
        'tendons', 'energy', ...): a list of column names and a 2-D NumPy array (one row per
        recorded time; the values as simulated)."""
        if name not in self._tables:
            import numpy as np

            path = self.outdir / f"{name}.csv"
            with open(path) as f:
                header = f.readline().strip().split(",")
                body = f.read()
            data = np.empty((0, len(header)))
            if body.strip():  # no rows when the first step failed
                data = np.loadtxt(body.splitlines(), delimiter=",", ndmin=2)
            self._tables[name] = (header, data.reshape(-1, len(header)))
        return self._tables[name]

    def tables(self):
        """The stems of the run's tables (points and joints first, then the others by name)."""
        found = sorted(p.stem for p in self.outdir.glob("*.csv"))
        return [t for t in ("points", "joints") if t in found] + \
            [t for t in found if t not in ("points", "joints")]

    def column(self, name):
        """One recorded column by name ('t', 'P8.x', 'J0.effort', 'flexor.tension', ...) as a
        1-D array, from the first table (points, joints, then the others) that has it."""
        for table in self.tables():
            header, data = self.table(table)
            if name in header:
                return data[:, header.index(name)]
        raise KeyError(f"no recorded column '{name}' in " +
                       ", ".join(f"{t}.csv" for t in self.tables()))

    def point_position(self, point, t):
        """World position [m] of a recorded point at the recorded time nearest to t [s].
        Raises ValueError when t is outside the recorded times (e.g. after a failed step)."""
        import numpy as np

        times = self.column("t")
        tol = 1e-9 * max(1.0, abs(t))
        if len(times) == 0 or t < times[0] - tol or t > times[-1] + tol:
            raise ValueError(f"t = {t:g} s is outside the recorded times")
        i = int(np.argmin(np.abs(times - t)))
        return np.array([self.column(f"{point}.{a}")[i] for a in "xyz"])


class PointPosition:
    """Columns '<point>.<x|y|z>@<t>': world position [m] of a recorded point at the recorded
    times nearest to `times` [s]."""

    def __init__(self, point, times):
        self.point, self.times = point, list(times)

    def __call__(self, run):
        out = {}
        for t in self.times:
            p = run.point_position(self.point, t)
            out.update({f"{self.point}.{a}@{t:g}": float(p[i]) for i, a in enumerate("xyz")})
        return out


class MaxConstraintResidual:
    """Column 'max_constraint_residual': largest |phi| over the run [m or rad]."""

    def __call__(self, run):
        return {"max_constraint_residual": run.result.max_constraint_residual}


class WallTime:
    """Columns 'wall_seconds' and 'cpu_seconds': wall and CPU time of the load, compile and run
    of the variant on its worker [s] (not reproducible: leave them out of comparisons). CPU
    time well below the wall time means the task waited for a processor."""

    def __call__(self, run):
        return {"wall_seconds": run.wall_seconds, "cpu_seconds": run.cpu_seconds}


class Counters:
    """Columns 'end_time' [s], 'steps', 'newton_iterations', 'halvings'."""

    def __call__(self, run):
        r = run.result
        return {"end_time": r.end_time, "steps": r.steps, "newton_iterations": r.newton_iterations,
                "halvings": r.halvings}


class PeakJointEffort:
    """Column 'peak_effort' (or `name`): largest |effort| over the run [N or N m] of the given
    recorded joints (all recorded joints when None)."""

    def __init__(self, joints=None, name="peak_effort"):
        self.joints, self.name = joints, name

    def __call__(self, run):
        header, data = run.table("joints")
        cols = [i for i, c in enumerate(header) if c.endswith(".effort")
                and (self.joints is None or c.split(".")[0] in self.joints)]
        if not cols:
            raise KeyError("no recorded joint effort among " + str(self.joints))
        return {self.name: float(abs(data[:, cols]).max()) if len(data) else math.nan}


class ColumnMetric:
    """A metric written as a small expression over one recorded column of any of the run's
    tables (Run.column): max(C), min(C), absmax(C), initial(C), final(C), mean(C) (over the
    recorded rows), rms(C) (root mean square over the rows) or at(C, T) (the row nearest to
    time T [s]). Column 'name' or the expression without spaces, e.g. 'max(tip.z)',
    'final(flexor.tension)', 'at(P8.x,0.5)', 'rms(J1.q)'. NaN when the run recorded no row
    (or, for at, when T is outside the recorded times)."""

    FUNCTIONS = ("max", "min", "absmax", "initial", "final", "mean", "rms", "at")

    def __init__(self, expression, name=None):
        import re

        m = re.fullmatch(r"\s*([a-z]+)\s*\(\s*([^,()\s]+)\s*(?:,\s*([^,()\s]+)\s*)?\)\s*",
                         expression)
        if not m or m.group(1) not in self.FUNCTIONS:
            raise ValueError(f"metric '{expression}': expected FUNCTION(COLUMN) or at(COLUMN, T) "
                             f"with FUNCTION one of {', '.join(self.FUNCTIONS)}")
        self.function, self.column, t = m.group(1), m.group(2), m.group(3)
        if (self.function == "at") != (t is not None):
            raise ValueError(f"metric '{expression}': " +
                             ("at(COLUMN, T) needs a time" if t is None else
                              f"{self.function}(COLUMN) takes no time"))
        self.time = float(t) if t is not None else None
        self.name = name or "".join(expression.split())

    def __call__(self, run):
        import numpy as np

        values = run.column(self.column)
        if len(values) == 0:
            return {self.name: math.nan}
        f = self.function
        if f == "at":
            times = run.column("t")
            tol = 1e-9 * max(1.0, abs(self.time))
            if self.time < times[0] - tol or self.time > times[-1] + tol:
                return {self.name: math.nan}
            value = values[int(np.argmin(np.abs(times - self.time)))]
        elif f == "rms":
            value = math.sqrt(float(np.mean(values * values)))
        else:
            value = {"max": np.max, "min": np.min, "absmax": lambda v: np.max(np.abs(v)),
                     "initial": lambda v: v[0], "final": lambda v: v[-1],
                     "mean": np.mean}[f](values)
        return {self.name: float(value)}


DEFAULT_METRICS = (MaxConstraintResidual(), Counters(), WallTime())


def _metric_name(metric):
    return getattr(metric, "__name__", type(metric).__name__)


def _call_metric(metric, run):
    value = metric(run)
    if isinstance(value, dict):
        return value
    return {_metric_name(metric): value}


def _plain(value):
    """A metric value as a JSON-able Python value (NumPy scalars become float / int)."""
    if isinstance(value, (bool, str)) or value is None:
        return value
    if isinstance(value, numbers.Integral):
        return int(value)
    if isinstance(value, numbers.Real):
        return float(value)
    return value


# ---------------------------------------------------------------------------------------------
# One variant (the task)

def run_variant(scene_text, scene_source, overrides, metrics=DEFAULT_METRICS, keep_dir=None,
                vtk=False, max_memory=None):
    """Runs one variant and returns its row (a dict): variant_id, overrides ('; '-joined),
    status, message and the metrics' columns.

    status: 'completed'; 'failed' (a step or static solution failed even after halving:
    message is the solver's, with the time); 'invalid' (InputError: message is
    'FILE:LINE:COLUMN: FIELD: ...' or 'FILE: override ...'); 'error' (any other exception,
    e.g. a metric that raised on a completed run). Metrics are evaluated for failed runs too
    (on the rows recorded before the failure); one that raises there gives NaN.
    `keep_dir` keeps the run's files there (vtk/ only when `vtk`); otherwise they go to a
    temporary directory removed afterwards. `max_memory` bounds the memory of the variant's
    model and solver (parse_scene; a larger variant is 'invalid').
    """
    overrides = list(overrides)
    vid = variant_id(overrides)
    row = {"variant_id": vid, "overrides": "; ".join(overrides), "status": "", "message": ""}
    t0, c0 = time.perf_counter(), time.thread_time()
    try:
        scene = parse_scene(scene_text, scene_source, overrides, max_memory=max_memory)
    except InputError as e:
        row.update(status="invalid", message=str(e))
        return row
    scene.outputs.vtk = bool(vtk and keep_dir)
    tmp = None
    try:
        if keep_dir:
            outdir = pathlib.Path(keep_dir)
            shutil.rmtree(outdir, ignore_errors=True)  # a re-run (resume, lost worker) starts clean
        else:
            tmp = tempfile.mkdtemp(prefix="screwfem-variant-")
            outdir = pathlib.Path(tmp)
        result = run_scene(scene, str(outdir))
        wall, cpu = time.perf_counter() - t0, time.thread_time() - c0
        row["status"] = "completed" if result.ok else "failed"
        row["message"] = result.message
        run = Run(overrides, vid, result, outdir, wall, cpu)
        for metric in metrics:
            try:
                values = _call_metric(metric, run)
            except Exception as e:  # a metric's own error
                if row["status"] == "completed":
                    row.update(status="error", message=f"metric {_metric_name(metric)}: "
                               f"{type(e).__name__}: {e}")
                continue
            row.update({k: _plain(v) for k, v in values.items()})
    except InputError as e:  # settings checked by run_scene, or an unwritable directory
        row.update(status="invalid", message=str(e))
    except Exception as e:
        row.update(status="error", message=f"{type(e).__name__}: {e}")
    finally:
        if tmp:
            shutil.rmtree(tmp, ignore_errors=True)
    return row


# ---------------------------------------------------------------------------------------------
# Files read from disk, with their size limits (docs/limits.md): the scene file as the C++
# reader's (kMaxSceneBytes), the manifest, and each journal row.
MAX_SCENE_BYTES = 16 << 20
MAX_MANIFEST_BYTES = 256 << 20
MAX_JOURNAL_LINE = 1 << 20


def _read_limited(path, limit, what):
    """The bytes of a regular file of at most `limit` bytes (ValueError otherwise: a device such
    as /dev/zero, a directory, a larger file), read in pieces (Ctrl-C interrupts it)."""
    path = pathlib.Path(path)
    if not path.is_file():
        raise ValueError(f"sweep: {path}: the {what} is not a regular file")
    chunks, size = [], 0
    with open(path, "rb") as f:
        while True:
            chunk = f.read(1 << 16)
            if not chunk:
                break
            size += len(chunk)
            if size > limit:
                raise ValueError(f"sweep: {path}: the {what} is larger than {limit >> 20} MiB "
                                 "(the limit)")
            chunks.append(chunk)
    return b"".join(chunks)


# The journal (OUTDIR/rows.jsonl)

def _read_journal(path):
    """Rows of a journal keyed by variant_id; a last line cut short by a kill is ignored. A row
    with status 'error' (which a resumed sweep runs again) gives way to a later row."""
    rows = {}
    if not path.exists():
        return rows
    if not path.is_file():
        raise ValueError(f"sweep: {path}: not a regular file")
    with open(path) as f:
        while True:
            line = f.readline(MAX_JOURNAL_LINE)
            if not line.endswith("\n"):
                if len(line) >= MAX_JOURNAL_LINE:
                    raise ValueError(f"sweep: {path}: a line longer than {MAX_JOURNAL_LINE} "
                                     "characters (not a journal of screwfem sweep)")
                break
            try:
                row = json.loads(line)
            except ValueError:
                continue
            old = rows.get(row["variant_id"])
            if old is None or old.get("status") == "error":
                rows[row["variant_id"]] = row
    return rows


class _Journal:
    def __init__(self, path):
        self.path = path
        if path.exists():  # drop a partial last line left by a kill
            data = path.read_bytes()
            if data and not data.endswith(b"\n"):
                path.write_bytes(data[:data.rfind(b"\n") + 1])
        self.file = open(path, "a")

    def append(self, row):
        self.file.write(json.dumps(row, allow_nan=True) + "\n")
        self.file.flush()
        os.fsync(self.file.fileno())

    def close(self):
        self.file.close()


# ---------------------------------------------------------------------------------------------
# Progress (stderr, on a terminal)

class _Progress:
    def __init__(self, total, done_before, enabled):
        self.total, self.enabled = total, enabled
        self.done_before = done_before
        self.done = self.failed = 0
        self.t0 = time.monotonic()

    def update(self, row):
        """Counts a finished row ('failed' counts every status but 'completed') and redraws."""
        self.done += 1
        if row["status"] != "completed":
            self.failed += 1
        if not self.enabled:
            return
        finished = self.done_before + self.done
        remaining = self.total - finished
        elapsed = time.monotonic() - self.t0
        eta = elapsed / self.done * remaining
        sys.stderr.write(f"\rsweep: {finished}/{self.total} done, {self.failed} failed, "
                         f"{remaining} remaining, about {eta:.0f} s left   ")
        if remaining == 0:
            sys.stderr.write("\n")
        sys.stderr.flush()


# ---------------------------------------------------------------------------------------------
# The sweep

def _local_cluster(workers):
    """A LocalCluster of `workers` single-threaded worker processes, every socket on the
    loopback interface (scheduler, workers, nannies and their HTTP servers)."""
    import logging
    import signal
    import threading

    from distributed import LocalCluster

    # Ctrl-C is the client's to handle (it stops the sweep, keeps the rows and closes the
    # cluster): the worker processes started now ignore SIGINT, a disposition inherited
    # through exec, instead of each printing a KeyboardInterrupt traceback.
    previous = None
    if threading.current_thread() is threading.main_thread():
        previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        return LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                            host="127.0.0.1", dashboard_address="127.0.0.1:0",
                            worker_dashboard_address="127.0.0.1:0", silence_logs=logging.ERROR)
    finally:
        if previous is not None:
            signal.signal(signal.SIGINT, previous)


def _table(rows, names, order):
    """The DataFrame of a sweep: one row per finished variant, in variant order."""
    import pandas as pd

    records = []
    for i, vid in enumerate(order):
        if vid in rows:
            records.append({"variant": i, **rows[vid]})
    df = pd.DataFrame.from_records(records)
    if df.empty:
        df = pd.DataFrame(columns=["variant", "variant_id", "overrides", "status", "message"])
    front = ["variant", "variant_id", *names, "overrides", "status", "message"]
    front = [c for c in front if c in df.columns]
    return df[front + [c for c in df.columns if c not in front]]


def _write_table(df, outdir):
    df.to_csv(outdir / TABLE_FILE, index=False)  # shortest repr: reads back to the same doubles
    try:
        import pyarrow  # noqa: F401
    except ImportError:
        return
    df.to_parquet(outdir / "results.parquet", index=False)


# ---------------------------------------------------------------------------------------------
# Summaries: the tidy table, its text and figures, the notable variants

NOT_METRICS = ("variant", "variant_id", "overrides", "status", "message")
UNREPRODUCIBLE = ("wall_seconds", "cpu_seconds")


def summary_table(df, names):
    """The tidy table of a sweep's DataFrame: variant, one column per parameter (short names,
    short_names), status, then one column per metric. `names`: the parameter key names (the
    columns of df that hold parameters)."""
    params = [n for n in names if n in df.columns]
    metrics = [c for c in df.columns if c not in NOT_METRICS and c not in params]
    short = short_names(params)
    taken = set(metrics) | {"variant", "status"}
    short = {n: (n if short[n] in taken else short[n]) for n in params}  # a metric's name: long
    return df[["variant", *params, "status", *metrics]].rename(columns=short)


def format_summary(table, max_rows=20):
    """The tidy table as aligned text: numbers with 6 significant digits, at most `max_rows`
    rows (the first and last halves, '...' between)."""
    def cell(v):
        if isinstance(v, float):
            return "nan" if math.isnan(v) else f"{v:.6g}"
        return str(v)

    cols = list(table.columns)
    rows = [[cell(v) for v in r] for r in table.itertuples(index=False)]
    if len(rows) > max_rows:
        half = max_rows // 2
        rows = rows[:half] + [["..."] * len(cols)] + rows[-half:]
    widths = [max([len(c)] + [len(r[i]) for r in rows]) for i, c in enumerate(cols)]
    lines = ["  ".join(c.rjust(w) for c, w in zip(cols, widths))]
    lines += ["  ".join(v.rjust(w) for v, w in zip(r, widths)) for r in rows]
    return "\n".join(lines)


def notable_variants(df, names):
    """{variant_id: why} of the variants worth keeping: every one that did not complete, and
    among the completed ones those with the smallest and largest value of each reproducible
    metric (not wall or CPU time)."""
    import pandas as pd

    out = {}
    for _, row in df[df["status"] != "completed"].iterrows():
        out[row["variant_id"]] = row["status"]
    done = df[df["status"] == "completed"]
    for c in df.columns:
        if c in NOT_METRICS or c in names or c in UNREPRODUCIBLE:
            continue
        values = pd.to_numeric(done[c], errors="coerce")
        if values.notna().sum() < 2 or values.min() == values.max():
            continue
        for what, i in (("min", values.idxmin()), ("max", values.idxmax())):
            vid = done.loc[i, "variant_id"]
            out[vid] = (out[vid] + ", " if vid in out else "") + f"{what} {c}"
    return out


def write_figures(table, params, outdir):
    """One PNG per metric of the tidy table in OUTDIR/figures/ (metrics that vary): the metric
    against the first parameter that takes several numeric values, a line per combination of
    the others (at most 12; points otherwise), failed variants left out. Returns the files written (none without
    matplotlib or a numeric parameter)."""
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return []
    import pandas as pd

    done = table[table["status"] == "completed"]
    numeric = [p for p in params
               if pd.to_numeric(done[p], errors="coerce").notna().all() and done[p].nunique() > 1]
    if not numeric:
        return []
    x = numeric[0]
    others = [p for p in params if p != x and table[p].nunique() > 1]
    metrics = [c for c in table.columns if c not in ("variant", "status", *params)]
    folder = pathlib.Path(outdir) / FIGURES_DIR
    folder.mkdir(parents=True, exist_ok=True)
    written = []
    groups = [((), done)]
    if len(others) == 1:
        groups = [((k,), g) for k, g in done.groupby(others[0])]
    elif others:
        groups = list(done.groupby(others))
    for m in metrics:
        y = pd.to_numeric(done[m], errors="coerce")
        if y.isna().all() or y.nunique() < 2:
            continue  # nothing to see: no number, or the same for every variant
        fig, ax = plt.subplots(figsize=(6, 4))
        for key, g in groups[:12]:
            key = key if isinstance(key, tuple) else (key,)
            label = ", ".join(f"{o} = {v}" for o, v in zip(others, key)) or None
            g = g.sort_values(x)
            ax.plot(pd.to_numeric(g[x]), pd.to_numeric(g[m], errors="coerce"),
                    "o-" if len(groups) <= 12 else "o", label=label)
        ax.set_xlabel(x)
        ax.set_ylabel(m)
        ax.grid(True, alpha=0.3)
        if others and len(groups) <= 12:
            ax.legend(fontsize=8)
        fig.tight_layout()
        name = "".join(ch if ch.isalnum() or ch in "._-" else "_" for ch in m).strip("_")
        path = folder / f"{name}.png"
        fig.savefig(path, dpi=100)
        plt.close(fig)
        written.append(path)
    return written


def sweep(scene, parameters, metrics=DEFAULT_METRICS, client=None, scheduler=None, workers=None,
          outdir=None, samples=None, seed=0, resume=False, keep_outputs=False, vtk=False,
          progress=None, timeout=None, max_memory=None, summary=False):
    """Runs every variant of `scene` and returns a pandas DataFrame, one row per variant.

    scene       scene file (YAML); workers receive its text, so they need no shared files.
    parameters  a grid {key: [values]}, a list of {key: value} dicts, or with `samples` a
                random-sampling spec (see `variants`). Keys are override paths.
    metrics     functions f(run: Run) -> number or {column: number}; default: max constraint
                residual, counters, wall time. Built-ins: PointPosition, MaxConstraintResidual,
                WallTime, Counters, PeakJointEffort. They run on the workers (picklable by
                cloudpickle: closures and lambdas are fine).
    client      a distributed.Client to run on; or `scheduler`: 'tcp://host:8786' (connect to
                it), or 'serial' (no Dask: one variant after another in this process). Default:
                a LocalCluster of `workers` processes (default: os.cpu_count()) on 127.0.0.1,
                closed at the end (in a script, call sweep under `if __name__ ==
                "__main__":`: the workers are spawned processes, which import the main
                module). Workers of a remote cluster need screwfem importable.
    outdir      writes OUTDIR/rows.jsonl (a row per variant as it completes), results.csv
                (shortest round-trip decimals: pandas.read_csv(..., float_precision=
                "round_trip") reads the exact doubles; also results.parquet when pyarrow is
                present) and sweep.json. `resume=True`
                keeps the rows already in OUTDIR/rows.jsonl and runs only the missing
                variants and those whose row has status 'error' (e.g. a task lost with too
                many workers); the scene file must be unchanged. `keep_outputs` keeps each
                variant's files in OUTDIR/runs/<variant_id>/ on the worker's file system
                (ParaView files only with `vtk`); keep_outputs='notable' keeps only those of
                the variants that did not complete and of the smallest and largest value of
                each metric (notable_variants; the others are removed at the end; on a
                remote cluster only those the workers wrote on this file system).
    summary     with `outdir`: also writes OUTDIR/summary.csv (summary_table: short parameter
                names, status, metrics) and OUTDIR/figures/METRIC.png (write_figures).
    timeout     seconds to wait for the whole sweep (None: no limit); raises TimeoutError.
    max_memory  bytes, or a size such as '8G': variants whose model and solver would need more
                are 'invalid' (parse_scene's max_memory; default: half the physical memory of
                the worker; docs/limits.md). The CLI's --max-memory.

    Columns: variant (index in the variant list), variant_id, one per parameter, overrides,
    status ('completed', 'failed', 'invalid', 'error'; see run_variant), message, then the
    metrics. A failed or invalid variant is a row, not an exception. Metrics are identical,
    bit for bit, to the same variants run serially (wall time aside).
    Ctrl-C (KeyboardInterrupt) stops the sweep with the finished rows kept in OUTDIR and
    re-raises.
    """
    if isinstance(max_memory, str):
        max_memory = parse_memory_size(max_memory)  # InputError (a ValueError) before any run
    scene_path = pathlib.Path(scene)
    scene_text = _read_limited(scene_path, MAX_SCENE_BYTES, "scene file").decode()
    assignments = variants(parameters, samples=samples, seed=seed)
    overrides = [format_overrides(a) for a in assignments]
    ids = [variant_id(o) for o in overrides]
    if len(set(ids)) != len(ids):
        raise ValueError("sweep: the parameters give the same variant more than once")
    names = []
    for a in assignments:
        names.extend(_key_name(k) for k in a if _key_name(k) not in names)
    params_of = {vid: {_key_name(k): _plain(v) if not isinstance(v, (list, tuple)) else
                       _format_value(v) for k, v in a.items()} for vid, a in zip(ids, assignments)}
    metrics = list(metrics)

    rows, journal = {}, None
    if outdir is not None:
        outdir = pathlib.Path(outdir)
        outdir.mkdir(parents=True, exist_ok=True)
        manifest = {"scene": str(scene_path), "scene_sha256":
                    hashlib.sha256(scene_text.encode()).hexdigest(),
                    "variants": [{"variant_id": v, "overrides": o} for v, o in zip(ids, overrides)]}
        journal_path = outdir / ROWS_FILE
        if resume:
            old = outdir / MANIFEST_FILE
            if old.exists():
                previous = json.loads(_read_limited(old, MAX_MANIFEST_BYTES, "manifest"))
                if previous.get("scene_sha256") != manifest["scene_sha256"]:
                    raise ValueError(f"sweep: cannot resume in {outdir}: the scene file changed "
                                     "since the rows there were computed")
            rows = {v: r for v, r in _read_journal(journal_path).items()
                    if v in params_of and r.get("status") != "error"}
        elif journal_path.exists() and journal_path.stat().st_size > 0:
            raise FileExistsError(f"sweep: {journal_path} exists (resume=True continues it; or "
                                  "choose another outdir)")
        (outdir / MANIFEST_FILE).write_text(json.dumps(manifest, indent=1) + "\n")
        journal = _Journal(journal_path)

    todo = [i for i, vid in enumerate(ids) if vid not in rows]
    show = sys.stderr.isatty() if progress is None else progress
    bar = _Progress(len(ids), len(ids) - len(todo), show)
    deadline = None if timeout is None else time.monotonic() + timeout

    def keep_dir(i):
        return str(outdir / "runs" / ids[i]) if (keep_outputs and outdir is not None) else None

    if keep_outputs not in (False, True, None, "notable"):
        raise ValueError(f"sweep: keep_outputs must be True, False or 'notable', got "
                         f"{keep_outputs!r}")

    def finish(i, row):
        row = {**params_of[ids[i]], **row}
        rows[ids[i]] = row
        if journal:
            journal.append(row)
        bar.update(row)

    try:
        if scheduler == "serial":
            for i in todo:
                if deadline is not None and time.monotonic() > deadline:
                    raise TimeoutError("sweep: timed out")
                finish(i, run_variant(scene_text, str(scene_path), overrides[i], metrics,
                                      keep_dir(i), vtk, max_memory))
        else:
            _run_on_dask(todo, lambda i: (scene_text, str(scene_path), overrides[i], metrics,
                                          keep_dir(i), vtk, max_memory),
                         ids, finish, client, scheduler, workers, deadline)
    finally:
        if journal:
            journal.close()
        df = _table(rows, names, ids)
        if outdir is not None:
            _write_table(df, outdir)
    if outdir is not None and summary:  # a whole sweep (not interrupted)
        table = summary_table(df, names)
        table.to_csv(outdir / SUMMARY_FILE, index=False)
        write_figures(table, list(table.columns[1:1 + len([n for n in names if n in df.columns])]),
                      outdir)
    if outdir is not None and keep_outputs == "notable" and (outdir / "runs").is_dir():
        keep = notable_variants(df, names)
        for d in (outdir / "runs").iterdir():
            if d.is_dir() and d.name not in keep:
                shutil.rmtree(d, ignore_errors=True)
        df.attrs["notable"] = keep
    return df


def _run_on_dask(todo, args_of, ids, finish, client, scheduler, workers, deadline):
    """Submits one task per variant and records each row as its task completes."""
    from distributed import Client, as_completed

    cluster = None
    own_client = client is None
    try:
        if own_client:
            if scheduler:
                client = Client(scheduler, timeout=_remaining(deadline, 60))
            else:
                cluster = _local_cluster(workers or os.cpu_count() or 1)
                client = Client(cluster, timeout=_remaining(deadline, 60))
        if not todo:
            return
        # pure=False with an explicit key: a re-submission is a new task; the key names the
        # variant (dashboard, logs).
        futures = {client.submit(run_variant, *args_of(i), pure=False,
                                 key=f"screwfem-variant-{ids[i]}-{os.urandom(4).hex()}"): i
                   for i in todo}
        # Results are gathered in the background as tasks finish (with_results).
        pending = as_completed(futures, with_results=True, raise_errors=False)
        try:
            while True:
                batch = _next_batch(pending, deadline)
                if batch is None:
                    break
                for future, result in batch:
                    i = futures[future]
                    if future.status == "finished":
                        row = result
                    else:  # lost too many workers, or could not run at all
                        exc = result[1] if isinstance(result, tuple) else result  # (type, exc, tb)
                        row = {"variant_id": ids[i], "overrides": "; ".join(args_of(i)[2]),
                               "status": "error", "message": f"{type(exc).__name__}: {exc}"}
                    finish(i, row)
        finally:
            client.cancel(list(futures))
    finally:
        if own_client and client is not None:
            client.close(timeout=10)
        if cluster is not None:
            cluster.close(timeout=20)


def _remaining(deadline, default):
    if deadline is None:
        return default
    return max(1.0, min(default, deadline - time.monotonic()))


def _next_batch(pending, deadline):
    """The next completed futures (a list), None when all are done; polls so that a deadline
    and Ctrl-C are noticed within a fraction of a second."""
    while True:
        if pending.is_empty():
            return None
        batch = pending.next_batch(block=False)
        if batch:
            return batch
        if deadline is not None and time.monotonic() > deadline:
            raise TimeoutError("sweep: timed out")
        time.sleep(0.02)
