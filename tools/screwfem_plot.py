"""Plots the results of screwfem runs (run with Debian's /usr/bin/python3; `screwfem plot` does).

    screwfem_plot.py OUTDIR [OUTDIR ...] -o FIGDIR [--points P8,P4] [--times 0,0.5,1,1.5,2]
                     [--animate [--fps 25] [--speed 1]]

Every figure's abscissa is the time t [s], or the load factor for a static path (summary.json
settings.analysis "static", or a load_factor column): one row per converged load step.
Columns are selected by name, so tables with more columns than these are read alike.

Runs overlaid, their directory names as labels:
  point_P.png     per recorded point P (points.csv): displacement x - x(start), velocity and
                  acceleration (rows; a static path: the position only) of the x, y and z
                  components (columns) -- the layout of Fig. 4 of the GRM paper.
  joint_J.png     per recorded joint J (joints.csv): q, dq/dt, d2q/dt2 and effort (a static
                  path: q and effort), in the units joints.json gives (rad or m).
  When the runs' scales in one panel differ by more than 10x, each scale group gets its own row
  of panels (the group's runs are in its legend).
Per run RUN (when the run wrote the table):
  tendons_RUN.png      tendons.csv: length, rate and tension, one curve per tendon;
  forces_RUN.png       forces.csv: length, rate and force (> 0 tension) per force element;
  actuators_RUN.png    actuators.csv: each actuator's value (pressure [Pa], activation [-] or
                       the factor of its vector; a static path: times the load factor, the
                       applied value), actuators of scales 10x apart in panels of their own;
  contacts_RUN.png     contacts.csv (one row per active pair): per shape and obstacle (rod or
                       body index, obstacle index) the summed normal force, the magnitude of
                       the summed friction force, the number of active pairs and the smallest
                       gap;
  pair_contacts_RUN.png  pair_contacts.csv: the same per pair of moving shapes;
  reactions_RUN.png    reactions.csv: per joint (rows) the force and the moment (columns) it
                       transmits to its side B, x, y, z;
  energy_RUN.png       energy.csv: kinetic, strain, spring, gravity and total energy; the
                       total's drift from its start; linear and angular momentum (a static
                       path: the energies only);
  rod_fields_RUN.png   rod_fields.csv: strains, curvatures, section forces and moments along s
                       (rows gamma, kappa, n, m; columns the components 1, 2, 3) at the --times
                       (default: 5 times evenly spaced over the run, or 5 load steps along a
                       static path), one colour per time and one line style per rod;
  snapshots_RUN.png    the ParaView frames (vtk/, read by screwfem_vtk.py): the mechanism at the
                       chosen times (the frames nearest to them) in one 3D view -- Fig. 3 style;
                       a mechanism that travels far also gets one view per time, framed on it.
With --animate, FIGDIR/animation_RUN.gif (and .mp4 when ffmpeg is installed) per run: the
mechanism in 3D. It plays in real time (--speed X: X simulated seconds per second of the
animation) at --fps frames per second: frame k shows the recorded frame nearest to
t0 + k X / fps, so duration x fps / X + 1 frames (a static path: one frame per recorded frame).
The view is fixed on the whole motion while that stays within 3 times the mechanism's initial
size; otherwise it follows the largest connected part (a cube of constant size). The scene is
drawn once and its lines updated per frame.

Needs numpy and matplotlib (Debian: python3-numpy, python3-matplotlib; python3-pil for the
GIF); uses the Agg backend.
Exit status: 0 on success, 2 when an input is missing or malformed.
"""

import argparse
import csv
import json
import math
import os
import shutil
import subprocess
import sys

import matplotlib

matplotlib.use("Agg")
# Titles, labels and legends carry run folder, point and joint names as given: no mathtext (a
# run folder named 'run$\\frac{$' was a parse error and a traceback).
matplotlib.rcParams["text.parse_math"] = False
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.ticker import MaxNLocator  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import screwfem_vtk  # noqa: E402  (the ParaView frames, whatever their encoding)

AXES = ("x", "y", "z")
T_LABEL = "t [s]"
LOAD_LABEL = "load factor"
# GIF frame delays are whole hundredths of a second, and viewers play delays below 0.02 s
# slower (as 0.1 s): at most 50 frames per second.
MAX_FPS = 50.0


class InputProblem(Exception):
    """A missing or malformed input file: reported as 'error: ...' with exit status 2."""


def run_label(outdir):
    return os.path.basename(os.path.normpath(outdir))


def read_table(path):
    """Returns (columns, data) of a screwfem CSV table; data has one row per line."""
    if not os.path.isfile(path):
        raise InputProblem(f"{path} not found (is {os.path.dirname(path) or '.'} a screwfem "
                           f"output directory? `screwfem run SCENE -o OUTDIR` writes it)")
    with open(path, newline="") as f:
        header = next(csv.reader(f), None)
    if not header or header[0] != "t":
        raise InputProblem(f"{path}: the first line must be a header starting with 't'")
    try:
        data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    except ValueError as e:
        raise InputProblem(f"{path}: cannot read the numbers: {e}") from e
    if data.size == 0:
        data = np.zeros((0, len(header)))
    if data.shape[1] != len(header):
        raise InputProblem(f"{path}: {data.shape[1]} values per row but {len(header)} columns")
    return header, data


def column(columns, data, name):
    """The values of the column called `name`."""
    return data[:, columns.index(name)]


def abscissa(columns, data):
    """(values, axis label) a table is drawn against: its load_factor column on a static path,
    else t."""
    if "load_factor" in columns:
        return column(columns, data, "load_factor"), LOAD_LABEL
    return data[:, 0], T_LABEL


def row_keys(columns, data):
    """The output step of every row, as tuples: (t,), or (t, load factor) on a static path (where
    t stays at the end time). Equal keys: rows written at the same output step (long tables)."""
    cols = [0] + ([columns.index("load_factor")] if "load_factor" in columns else [])
    return [tuple(r) for r in data[:, cols].tolist()]


def point_names(columns):
    return [c[:-2] for c in columns if c.endswith(".x") and c[:-2] + ".az" in columns]


def joint_names(columns):
    """Joint prefixes in column order: 'J0' for one coordinate, 'J7.0', 'J7.1' for several."""
    return [c[:-2] for c in columns if c.endswith(".q")]


def prefixes(columns, suffixes):
    """The names N, in column order, for which every column N + suffix exists."""
    first = suffixes[0]
    return [c[:-len(first)] for c in columns
            if c.endswith(first) and all(c[:-len(first)] + s in columns for s in suffixes)]


def save_figure(fig, figdir, filename):
    """Lays out, writes figdir/filename (PNG, 120 dpi) and closes fig; returns the path."""
    fig.tight_layout()
    path = os.path.join(figdir, filename)
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


class Run:
    """One run's output directory: its tables (read once, on demand) and summary.json."""

    def __init__(self, outdir):
        self.outdir = outdir
        self.label = run_label(outdir)
        self.summary = {}
        path = os.path.join(outdir, "summary.json")
        if os.path.isfile(path):
            try:
                with open(path) as f:
                    self.summary = json.load(f)
            except (OSError, ValueError) as e:
                raise InputProblem(f"{path}: cannot read: {e}") from e
        self._tables = {}

    def has(self, name):
        return os.path.isfile(os.path.join(self.outdir, name))

    def table(self, name):
        if name not in self._tables:
            self._tables[name] = read_table(os.path.join(self.outdir, name))
        return self._tables[name]

    @property
    def static(self):
        """A static path: summary.json says so, or points.csv has a load_factor column."""
        settings = self.summary.get("settings") if isinstance(self.summary, dict) else None
        if isinstance(settings, dict) and settings.get("analysis") == "static":
            return True
        return self.has("points.csv") and "load_factor" in self.table("points.csv")[0]

    def title(self, what):
        """'RUN: what' with the scene's name, and the run's status when it did not complete."""
        scene = self.summary.get("scene", {}) if isinstance(self.summary, dict) else {}
        name = scene.get("name") if isinstance(scene, dict) else None
        status = self.summary.get("status") if isinstance(self.summary, dict) else None
        text = f"{self.label}: {what}" + (f" ({name})" if name else "")
        if status and status != "completed":
            text += f" [{status} at {LOAD_LABEL if self.static else 't ='} " \
                    f"{self._last_abscissa():.4g}]"
        return text

    def _last_abscissa(self):
        columns, data = self.table("points.csv")
        x, _ = abscissa(columns, data)
        return float(x[-1]) if len(x) else float("nan")

    def output_steps(self):
        """(keys, x, x label) of the run's output steps: the rows of points.csv (every table
        without a long format has the same rows)."""
        columns, data = self.table("points.csv")
        x, label = abscissa(columns, data)
        return row_keys(columns, data), x, label


def scale_groups(scales, ratio=10.0):
    """Groups of run indices whose scales lie within `ratio` of each other (smallest first).

    Runs whose scales differ by more than `ratio` get axes of their own, so that a small
    motion is not flattened by a large one; runs at round-off (scale 0) join the first group."""
    order = sorted(range(len(scales)), key=lambda i: scales[i])
    groups = []
    for i in order:
        if groups and (scales[i] <= ratio * max(scales[groups[-1][0]], 1e-300) or scales[groups[-1][0]] == 0.0
                       and scales[i] == 0.0):
            groups[-1].append(i)
        else:
            groups.append([i])
    zero = [i for g in groups for i in g if scales[i] == 0.0]
    groups = [[i for i in g if scales[i] > 0.0] for g in groups]
    groups = [g for g in groups if g]
    if not groups:
        return [zero]
    groups[0] = zero + groups[0]
    return groups


def largest(values):
    """max |v| over the finite values (0 without any)."""
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    return float(np.max(np.abs(v))) if v.size else 0.0


def x_label(labels):
    """The abscissa label of axes whose curves are drawn against `labels` (t, load factor)."""
    labels = sorted(set(labels), key=[T_LABEL, LOAD_LABEL].index)
    return " or ".join(labels) if labels else T_LABEL


def all_static(runs):
    return bool(runs) and all("load_factor" in cols for _, (cols, _) in runs)


def plot_grouped(name, runs, rows, columns, figdir, filename, width):
    """One figure with a row of panels (one per column spec) for every quantity, overlaid runs,
    each against its abscissa (t, or the load factor of a static path); a quantity whose runs'
    scales differ by more than 10x gets one row per scale group.

    rows: [(title, unit, get(columns, data, column_spec) -> values)]; columns: [(spec, label)]."""
    colors = {label: f"C{k}" for k, (label, _) in enumerate(runs)}
    layout = []  # (row spec, group of run indices)
    for row in rows:
        scales = []
        for _, (cols, data) in runs:
            m = 0.0
            for spec, _ in columns:
                m = max(m, largest(row[2](cols, data, spec)))
            scales.append(m)
        for group in scale_groups(scales):
            layout.append((row, group, max(scales[i] for i in group)))
    fig, axes = plt.subplots(len(layout), len(columns), figsize=(width, 2.9 * len(layout) + 0.4),
                             sharex=True, squeeze=False)
    labels = set()
    for r, ((title, unit, get), group, scale) in enumerate(layout):
        for c, (spec, label) in enumerate(columns):
            ax = axes[r][c]
            for i in group:
                run_label, (cols, data) = runs[i]
                v = get(cols, data, spec)
                x, xlabel = abscissa(cols, data)
                labels.add(xlabel)
                ax.plot(x, v, label=run_label, color=colors[run_label],
                        marker="o" if len(data) == 1 else None)
            ax.set_title(f"{name} {title}{' ' + label if label else ''}", fontsize=9)
            ax.set_ylabel(unit)
            ax.grid(True, alpha=0.3)
            # A component at round-off level (e.g. the z motion of a planar chain) is shown on
            # the scale of the other components, not magnified into noise.
            low, high = ax.get_ylim()
            if scale > 0.0 and high - low < 1e-9 * scale:
                ax.set_ylim(-0.05 * scale, 0.05 * scale)
        axes[r][0].legend(fontsize=7)
    for ax in axes[-1]:
        ax.set_xlabel(x_label(labels))
    return save_figure(fig, figdir, filename)


def plot_point(name, runs, figdir):
    """Displacement, velocity and acceleration of point `name`; a static path: the position only
    (its first row is the first load step, not the unloaded state, and its velocity and
    acceleration are zero)."""
    def getter(prefix, relative):
        def get(cols, data, axis):
            v = column(cols, data, f"{name}.{prefix}{axis}")
            return v - v[0] if relative and len(v) else v
        return get

    rows = [("displacement", "m", getter("", True)), ("velocity", "m/s", getter("v", False)),
            ("acceleration", "m/s²", getter("a", False))]
    if all_static(runs):
        rows = [("position", "m", getter("", False))]
    return plot_grouped(name, runs, rows, [(a, a) for a in AXES], figdir, f"point_{name}.png", 13)


def read_joint_units(outdir):
    """{column prefix: coordinate entry of joints.json} of a run, {} without joints.json."""
    path = os.path.join(outdir, "joints.json")
    if not os.path.isfile(path):
        return {}
    try:
        with open(path) as f:
            described = json.load(f)
    except (OSError, ValueError) as e:
        raise InputProblem(f"{path}: cannot read: {e}") from e
    units = {}
    for joint in described.get("joints", []):
        for coordinate in joint.get("coordinates", []):
            if coordinate.get("column"):
                units[coordinate["column"]] = dict(coordinate, type=joint.get("type", ""))
    return units


def plot_joint(name, runs, figdir, units=None):
    """q, dq/dt, d2q/dt2 and effort of joint coordinate `name` (a static path: q and effort),
    with the units that joints.json gives ("rad" or "m"); without it, "m or rad"."""
    u = units or {}
    rows = [("coordinate", u.get("unit", "m or rad"), "q"),
            ("rate", u.get("rate_unit", "m/s or rad/s"), "qd"),
            ("acceleration", u.get("acceleration_unit", "m/s² or rad/s²"), "qdd"),
            ("effort", u.get("effort_unit", "N or N m"), "effort")]
    if all_static(runs):
        rows = [rows[0], rows[3]]
    rows = [(title, unit, (lambda suffix: lambda cols, data, _: column(cols, data, f"{name}.{suffix}"))(s))
            for title, unit, s in rows]
    title = name + (f" ({u['type']} {u['quantity']})" if "type" in u and "quantity" in u else "")
    return plot_grouped(title, runs, rows, [(None, "")], figdir, f"joint_{name}.png", 8)


# ---- per-run tables ----------------------------------------------------------------------------

def panel_figure(run, what, panels, xlabel, figdir, filename, ncols=1, width=8.0, height=2.6):
    """One figure of panels laid out in rows of `ncols`, titled with the run: panels are
    (title, y label, curves), curves (label or None, x, y, plot keywords)."""
    nrows = max(1, -(-len(panels) // ncols))
    fig, axes = plt.subplots(nrows, ncols, figsize=(width, height * nrows + 0.7), sharex=True,
                             squeeze=False)
    flat = list(axes.flat)
    # Per unit, the largest value of its panels: a panel at round-off level against it (a moment
    # of 1e-14 N m beside 0.1 N m) is shown on that scale, not magnified into noise.
    scales = {}
    for _, unit, curves in panels:
        scales[unit] = max([scales.get(unit, 0.0)] + [largest(c[2]) for c in curves])
    for ax, (title, ylabel, curves) in zip(flat, panels):
        for label, x, y, style in curves:
            style = dict(style)
            if len(x) == 1:
                style.setdefault("marker", "o")
            ax.plot(x, y, label=label, **style)
        if not curves:
            ax.text(0.5, 0.5, "nothing recorded", ha="center", va="center", transform=ax.transAxes,
                    color="0.5")
        ax.set_title(title, fontsize=9)
        ax.set_ylabel(ylabel)
        ax.grid(True, alpha=0.3)
        if ylabel == "count":
            ax.yaxis.set_major_locator(MaxNLocator(integer=True))
        scale = scales[ylabel]
        if scale > 0.0 and max([largest(c[2]) for c in curves] + [0.0]) < 1e-9 * scale:
            ax.set_ylim(-0.05 * scale, 0.05 * scale)
        labelled = [c for c in curves if c[0] is not None]
        if labelled:
            ax.legend(fontsize=7, ncol=1 + (len(labelled) - 1) // 8)
    for ax in flat[len(panels):]:
        ax.set_visible(False)
    # The x label under the lowest panel of every column.
    for c in range(ncols):
        used = [r for r in range(nrows) if r * ncols + c < len(panels)]
        if used:
            axes[used[-1]][c].set_xlabel(xlabel)
            axes[used[-1]][c].xaxis.set_tick_params(labelbottom=True)
    fig.suptitle(run.title(what), fontsize=10)
    return save_figure(fig, figdir, filename)


def plot_lines(run, table, figdir, force, force_title, force_unit="N"):
    """tendons.csv or forces.csv: length, rate and the force per tendon or force element (a
    static path: length and force). None when the table names none."""
    columns, data = run.table(table)
    names = prefixes(columns, [".length", ".rate", force])
    if not names:
        return None
    x, xlabel = abscissa(columns, data)
    rows = [("length", "m", ".length"), ("rate of the length", "m/s", ".rate"),
            (force_title, force_unit, force)]
    if "load_factor" in columns:
        rows = [rows[0], rows[2]]
    panels = [(title, unit, [(n, x, column(columns, data, n + suffix), {}) for n in names])
              for title, unit, suffix in rows]
    stem = table[:-4]
    return panel_figure(run, stem, panels, xlabel, figdir, f"{stem}_{run.label}.png")


def plot_actuators(run, figdir):
    """actuators.csv: every actuator's value, in panels of scales within 10x of each other."""
    columns, data = run.table("actuators.csv")
    names = [c for c in columns[1:] if c != "load_factor"]
    if not names:
        return None
    x, xlabel = abscissa(columns, data)
    static = "load_factor" in columns
    values = {n: column(columns, data, n) * (x if static else 1.0) for n in names}
    what = "applied value (profile value x load factor)" if static else "value"
    unit = "Pa, - or factor"
    panels = []
    for group in scale_groups([largest(values[n]) for n in names]):
        panels.append((f"actuator {what}: pressure [Pa], activation [-] or factor of its vector",
                       unit, [(names[i], x, values[names[i]], {}) for i in group]))
    return panel_figure(run, "actuators", panels, xlabel, figdir, f"actuators_{run.label}.png")


def shape_name(rod, owner):
    return f"{'rod' if rod else 'body'} {int(owner)}"


def contact_groups(table, columns, data):
    """(label, sign) per row of contacts.csv or pair_contacts.csv: the shape and obstacle, or the
    two shapes of a pair in a fixed order (sign -1: the row's sides are swapped, its friction
    force on side A is the opposite on the first shape of the label)."""
    out = []
    if table == "contacts.csv":
        rod, owner, obstacle = (column(columns, data, c) for c in ("rod", "owner", "obstacle"))
        for r, o, b in zip(rod, owner, obstacle):
            out.append((f"{shape_name(r, o)} - obstacle {int(b)}", 1.0))
        return out
    a = zip(column(columns, data, "rod_a"), column(columns, data, "owner_a"))
    b = zip(column(columns, data, "rod_b"), column(columns, data, "owner_b"))
    for sa, sb in zip(a, b):
        first, second = sorted([sa, sb], key=lambda s: (-s[0], s[1]))
        out.append((f"{shape_name(*first)} - {shape_name(*second)}", 1.0 if first == sa else -1.0))
    return out


def contact_sums(run, table):
    """Per group of contacts.csv or pair_contacts.csv, over the run's output steps: summed normal
    force, summed friction force (n x 3), number of active pairs and smallest gap (NaN without a
    pair). Returns (x, x label, {label: (fn, ft, count, gap)})."""
    columns, data = run.table(table)
    keys, x, xlabel = run.output_steps()
    index = {k: i for i, k in enumerate(keys)}
    step = np.array([index.get(k, -1) for k in row_keys(columns, data)], dtype=int)
    # Rows of a step that points.csv does not hold (a run still writing) are left out.
    known = step >= 0
    groups = contact_groups(table, columns, data)
    fn = column(columns, data, "fn")
    ft = np.column_stack([column(columns, data, c) for c in ("ftx", "fty", "ftz")])
    gap = column(columns, data, "gap")
    labels = {g: k for k, g in enumerate(dict.fromkeys(g for g, _ in groups))}
    which = np.array([labels[g] for g, _ in groups], dtype=int)
    sign = np.array([s for _, s in groups], dtype=float)
    n = len(keys)
    sums = {}
    for label, k in labels.items():
        rows = (which == k) & known
        total_fn, total_ft = np.zeros(n), np.zeros((n, 3))
        count, smallest = np.zeros(n), np.full(n, np.nan)
        np.add.at(total_fn, step[rows], fn[rows])
        np.add.at(total_ft, step[rows], sign[rows, None] * ft[rows])
        np.add.at(count, step[rows], 1.0)
        np.fmin.at(smallest, step[rows], gap[rows])
        sums[label] = (total_fn, total_ft, count, smallest)
    return x, xlabel, sums


def plot_contacts(run, table, figdir):
    """contacts.csv or pair_contacts.csv (long format): per shape and obstacle (or pair of
    shapes) the summed normal force, |summed friction force|, active pairs and smallest gap."""
    x, xlabel, sums = contact_sums(run, table)
    curves = {k: [] for k in ("fn", "ft", "count", "gap")}
    for label, (fn, ft, count, gap) in sums.items():
        curves["fn"].append((label, x, fn, {}))
        curves["ft"].append((label, x, np.linalg.norm(ft, axis=1), {}))
        curves["count"].append((label, x, count, {"drawstyle": "steps-post"}))
        curves["gap"].append((label, x, gap, {"marker": "." if len(x) < 200 else None}))
    panels = [("normal force, summed over the active pairs", "N", curves["fn"]),
              ("friction force: |sum over the active pairs|", "N", curves["ft"]),
              ("active pairs", "count", curves["count"]),
              ("smallest gap (< 0: penetration)", "m", curves["gap"])]
    stem = table[:-4]
    what = "contacts with obstacles" if table == "contacts.csv" else "contacts between moving shapes"
    return panel_figure(run, what, panels, xlabel, figdir, f"{stem}_{run.label}.png")


def plot_reactions(run, figdir):
    """reactions.csv: per joint the force [N] and moment [N m] on its side B (world, about the
    joint point)."""
    columns, data = run.table("reactions.csv")
    joints = prefixes(columns, [".Fx", ".Fy", ".Fz", ".Mx", ".My", ".Mz"])
    if not joints:
        return None
    x, xlabel = abscissa(columns, data)
    panels = []
    for j in joints:
        for kind, unit, what in (("F", "N", "force"), ("M", "N m", "moment about the joint point")):
            panels.append((f"{j}: {what} on side B", unit,
                           [(a, x, column(columns, data, f"{j}.{kind}{a}"), {}) for a in AXES]))
    return panel_figure(run, "joint reactions", panels, xlabel, figdir, f"reactions_{run.label}.png",
                        ncols=2, width=11.0, height=2.4)


MOMENTUM = {"px", "py", "pz", "Lx", "Ly", "Lz"}


def plot_energy(run, figdir):
    """energy.csv: the energies; the total's drift from its start; linear and angular momentum
    (a static path: the energies)."""
    columns, data = run.table("energy.csv")
    x, xlabel = abscissa(columns, data)
    energies = [c for c in columns[1:] if c != "load_factor" and c not in MOMENTUM]
    panels = [("energy", "J", [(c, x, column(columns, data, c), {"lw": 2.2 if c == "total" else 1.3})
                               for c in energies])]
    if "load_factor" not in columns:
        if "total" in columns and len(data):
            total = column(columns, data, "total")
            drift = total - total[0]
            title = "total energy - its value at the start"
            if total[0] != 0.0:
                title += (f": largest |drift| {largest(drift) / abs(total[0]):.3g} of the start's "
                          f"|total| ({abs(total[0]):.4g} J)")
            panels.append((title, "J", [(None, x, drift, {"color": "C4"})]))
        for names, what, unit in ((("px", "py", "pz"), "linear momentum", "kg m/s"),
                                  (("Lx", "Ly", "Lz"), "angular momentum about the world origin",
                                   "kg m²/s")):
            if all(n in columns for n in names):
                panels.append((what, unit, [(n, x, column(columns, data, n), {}) for n in names]))
    return panel_figure(run, "energy and momentum", panels, xlabel, figdir, f"energy_{run.label}.png")


ROD_FIELDS = (("gamma", "γ", "-", ("extension", "shear 2", "shear 3")),
              ("kappa", "κ", "1/m", ("twist", "bending curvature 2", "bending curvature 3")),
              ("n", "n", "N", ("axial force (> 0 tension)", "shear force 2", "shear force 3")),
              ("m", "m", "N m", ("torque", "bending moment 2", "bending moment 3")))


def output_blocks(columns, data):
    """(start, stop) of the blocks of consecutive rows written at one output step."""
    keys = row_keys(columns, data)
    starts = [i for i in range(len(keys)) if i == 0 or keys[i] != keys[i - 1]]
    return list(zip(starts, starts[1:] + [len(keys)]))


def chosen_blocks(x, times, static, count=5):
    """Indices of the blocks to draw: those nearest to `times` (dynamic runs), else `count`
    evenly spaced ones."""
    if not len(x):
        return []
    if times is None or static:
        return sorted({int(round(v)) for v in np.linspace(0, len(x) - 1, min(count, len(x)))})
    return sorted({int(np.argmin(np.abs(x - t))) for t in times})


def plot_rod_fields(run, figdir, times=None):
    """rod_fields.csv (long format: one row per station at each output step): strain, curvature,
    section force and moment along s at a few times (or load steps)."""
    columns, data = run.table("rod_fields.csv")
    if "s" not in columns or "rod" not in columns:
        raise InputProblem(f"{os.path.join(run.outdir, 'rod_fields.csv')}: no 's' or 'rod' column")
    x, _ = abscissa(columns, data)
    static = "load_factor" in columns
    blocks = output_blocks(columns, data)
    chosen = chosen_blocks(np.array([x[b] for b, _ in blocks]), times, static)
    s, rod = column(columns, data, "s"), column(columns, data, "rod")
    rods = sorted(set(rod.tolist()))
    colors = plt.cm.viridis(np.linspace(0.0, 0.9, max(len(chosen), 1)))
    styles = ["-", "--", ":", "-."]
    panels = []
    for name, symbol, unit, titles in ROD_FIELDS:
        for k, title in enumerate(titles, start=1):
            if f"{name}{k}" not in columns:
                continue
            values = column(columns, data, f"{name}{k}")
            curves = []
            for color, b in zip(colors, chosen):
                start, stop = blocks[b]
                when = f"{LOAD_LABEL} {x[start]:.4g}" if static else f"t = {x[start]:.4g} s"
                for r_index, r in enumerate(rods):
                    rows = np.arange(start, stop)[rod[start:stop] == r]
                    rows = rows[np.argsort(s[rows], kind="stable")]
                    label = when + (f", rod {int(r)}" if len(rods) > 1 else "")
                    curves.append((label if not panels else None, s[rows], values[rows],
                                   {"color": color, "ls": styles[r_index % len(styles)],
                                    "marker": "."}))
            panels.append((f"{symbol}{k}: {title}", unit, curves))
    if not panels:
        return None
    return panel_figure(run, "rod fields along s", panels, "s [m]", figdir,
                        f"rod_fields_{run.label}.png", ncols=3, width=13.0, height=2.5)


def plot_tables(run, figdir, times=None):
    """The figures of every table the run wrote besides points.csv and joints.csv."""
    plots = [("tendons.csv", lambda: plot_lines(run, "tendons.csv", figdir, ".tension", "tension")),
             ("forces.csv", lambda: plot_lines(run, "forces.csv", figdir, ".force",
                                               "force (> 0 tension)")),
             ("actuators.csv", lambda: plot_actuators(run, figdir)),
             ("contacts.csv", lambda: plot_contacts(run, "contacts.csv", figdir)),
             ("pair_contacts.csv", lambda: plot_contacts(run, "pair_contacts.csv", figdir)),
             ("reactions.csv", lambda: plot_reactions(run, figdir)),
             ("energy.csv", lambda: plot_energy(run, figdir)),
             ("rod_fields.csv", lambda: plot_rod_fields(run, figdir, times))]
    written = []
    for table, plot in plots:
        if run.has(table):
            path = plot()
            if path:
                written.append(path)
    return written


# ---- ParaView frames: snapshots ---------------------------------------------------------------

def read_collection(outdir):
    """[(time, path)] of the ParaView frames of a run, or None without them."""
    try:
        return screwfem_vtk.read_collection(outdir)
    except screwfem_vtk.VtkError as e:
        raise InputProblem(str(e)) from e


# Box edges as one path through the 8 corners (index bits: x, y, z), every edge at least once.
BOX_PATH = (0, 1, 3, 2, 0, 4, 5, 7, 6, 4, 6, 2, 3, 7, 5, 1)


def read_frame(path):
    """Points (n x 3) and cells of one .vtp frame: a list of (point indices, kind) with kind
    'joint' (a dot), 'rod', 'body' (a rigid body's link), 'tendon', 'force_element' or 'shape'
    (lines). A rigid body's contact shapes become lines of the points added for them (box
    edges, a sphere's three great circles, a capsule's axis and end circles); inertia boxes,
    contact points and obstacles are left out, and so are the points no drawn cell uses."""
    try:
        frame = screwfem_vtk.read_frame(path)
    except screwfem_vtk.VtkError as e:
        raise InputProblem(str(e)) from e
    xyz = np.array(frame["points"], dtype=float).reshape(-1, 3)
    pd = frame["point_data"]
    has_axes = all(a in pd for a in ("frame_x", "frame_y", "frame_z"))
    half = np.array(pd["half_size"][1], dtype=float).reshape(-1, 3) if "half_size" in pd else None
    radius = np.array(pd["radius"][1], dtype=float) if "radius" in pd else None

    def axes(i):
        if not has_axes:
            return np.eye(3)
        return np.column_stack([pd[a][1][3 * i:3 * i + 3] for a in ("frame_x", "frame_y", "frame_z")])

    def circle(center, u, v, r):
        angles = np.linspace(0.0, 2.0 * np.pi, 25)
        return [center + r * (np.cos(a) * u + np.sin(a) * v) for a in angles]

    out_points, cells, index = [], [], {}

    def keep(i):
        if i not in index:
            index[i] = len(out_points)
            out_points.append(xyz[i])
        return index[i]

    def added(path_points, kind="shape"):
        first = len(out_points)
        out_points.extend(path_points)
        cells.append((list(range(first, len(out_points))), kind))

    for ids, kind in zip(frame["cells"], frame["kinds"]):
        if kind in ("joint", "rod", "body", "tendon", "force_element"):
            cells.append(([keep(p) for p in ids], kind))
        elif half is not None and kind == "box":
            c, R, h = xyz[ids[0]], axes(ids[0]), half[ids[0]]
            corners = [c + R @ (h * [1 if b & 1 else -1, 1 if b & 2 else -1, 1 if b & 4 else -1])
                       for b in range(8)]
            added([corners[b] for b in BOX_PATH])
        elif radius is not None and kind == "sphere":
            c, r, e = xyz[ids[0]], radius[ids[0]], np.eye(3)
            for a in range(3):
                added(circle(c, e[a], e[(a + 1) % 3], r))
        elif radius is not None and kind == "capsule":
            a, b, r = xyz[ids[0]], xyz[ids[1]], radius[ids[0]]
            d = b - a
            d = d / (np.linalg.norm(d) or 1.0)
            u = np.cross(d, [1.0, 0.0, 0.0] if abs(d[0]) < 0.9 else [0.0, 1.0, 0.0])
            u /= np.linalg.norm(u)
            v = np.cross(d, u)
            added([a, b])
            for end in (a, b):
                added(circle(end, u, v, r))
    points = np.array(out_points, dtype=float).reshape(-1, 3)
    return points, cells


def draw_frame(ax, points, cells, color, label=None):
    """Draws one frame's geometry (rods thin, rigid bodies' links thick, shapes, tendons and
    force elements thin, joints as dots) on a 3D axis."""
    first = True
    widths = {"body": 2.5, "rod": 1.5}
    for ids, kind in cells:
        p = points[ids]
        if kind == "joint":
            ax.scatter(p[:, 0], p[:, 1], p[:, 2], color=color, s=12)
            continue
        ax.plot(p[:, 0], p[:, 1], p[:, 2], color=color, linewidth=widths.get(kind, 0.8),
                linestyle="--" if kind == "force_element" else "-",
                label=label if first else None)
        first = False


def set_cube(ax, lo, hi, margin=0.05):
    """Equal-aspect limits: the cube around the box [lo, hi] (and labelled axes)."""
    center, half = 0.5 * (lo + hi), (0.5 + margin) * max(float(np.max(hi - lo)), 1e-9)
    ax.set_xlim(center[0] - half, center[0] + half)
    ax.set_ylim(center[1] - half, center[1] + half)
    ax.set_zlim(center[2] - half, center[2] + half)
    ax.set_box_aspect((1, 1, 1))
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_zlabel("z [m]")


def parts(points, cells, gap):
    """The connected parts of a frame: lists of cell indices whose cells lie within `gap` of
    each other (a prismatic joint that slides far splits the mechanism into two parts)."""
    parent = list(range(len(cells)))

    def root(i):
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    pts = [points[ids] for ids, _ in cells]
    for i in range(len(cells)):
        for j in range(i + 1, len(cells)):
            if root(i) == root(j) or not len(pts[i]) or not len(pts[j]):
                continue
            d = np.min(np.linalg.norm(pts[i][:, None, :] - pts[j][None, :, :], axis=2))
            if d <= gap:
                parent[root(i)] = root(j)
    groups = {}
    for i in range(len(cells)):
        groups.setdefault(root(i), []).append(i)
    return sorted(groups.values(), key=lambda g: -sum(len(cells[i][0]) for i in g))


def extent(points):
    return float(np.max(points.max(axis=0) - points.min(axis=0))) if len(points) else 0.0


def plot_snapshots(outdir, times, figdir):
    """The mechanism at the chosen times. Overlaid in one view while the motion stays within
    3 times the mechanism's initial size; otherwise (a mechanism that travels or stretches
    far) one view of the whole motion and then one view per time and connected part, each
    framed on that part."""
    frames = read_collection(outdir)
    label = run_label(outdir)
    if not frames:
        print(f"warning: {outdir} has no ParaView frames (vtk/): no snapshots "
              f"(set outputs.vtk: true)", file=sys.stderr)
        return None
    frame_times = np.array([t for t, _ in frames])
    if times is None:
        times = np.linspace(frame_times[0], frame_times[-1], min(5, len(frames)))
    chosen = sorted({int(np.argmin(np.abs(frame_times - t))) for t in times})
    colors = plt.cm.viridis(np.linspace(0.0, 0.9, len(chosen)))
    shots = []
    for color, index in zip(colors, chosen):
        t, path = frames[index]
        points, cells = read_frame(path)
        if len(points):
            shots.append((t, points, cells, color))
    if not shots:
        return None
    every = np.vstack([p for _, p, _, _ in shots])
    lo, hi = every.min(axis=0), every.max(axis=0)
    size0 = max(extent(read_frame(frames[0][1])[0]), 1e-12)
    if float(np.max(hi - lo)) <= 3.0 * size0:
        fig = plt.figure(figsize=(9, 8))
        ax = fig.add_subplot(projection="3d")
        for t, points, cells, color in shots:
            draw_frame(ax, points, cells, color, f"t = {t:.3g} s")
        set_cube(ax, lo, hi)
        ax.set_title(f"{label}: snapshots")
        ax.legend(fontsize=8, loc="upper left")
        return save_figure(fig, figdir, f"snapshots_{label}.png")
    panels = []
    for t, points, cells, color in shots:
        groups = parts(points, cells, 0.2 * size0)
        for k, group in enumerate(groups[:3]):
            sub = [cells[i] for i in group]
            title = f"t = {t:.3g} s" + (f", part {k + 1} of {len(groups)}" if len(groups) > 1 else "")
            panels.append((title, points, sub, color))
    ncols = 3
    nrows = (len(panels) + 1 + ncols - 1) // ncols
    fig = plt.figure(figsize=(5.0 * ncols, 4.6 * nrows))
    ax = fig.add_subplot(nrows, ncols, 1, projection="3d")
    for t, points, cells, color in shots:
        draw_frame(ax, points, cells, color, f"t = {t:.3g} s")
    set_cube(ax, lo, hi)
    ax.set_title(f"{label}: the whole motion\n(the next views: one part at one time)", fontsize=10)
    ax.legend(fontsize=7, loc="upper left")
    for k, (title, points, cells, color) in enumerate(panels):
        ax = fig.add_subplot(nrows, ncols, k + 2, projection="3d")
        draw_frame(ax, points, cells, color)
        used = np.vstack([points[ids] for ids, _ in cells])
        set_cube(ax, used.min(axis=0), used.max(axis=0))
        ax.set_title(title, fontsize=10)
    return save_figure(fig, figdir, f"snapshots_{label}.png")


# ---- animation ---------------------------------------------------------------------------------

def frame_plan(times, fps, speed):
    """How an animation shows frames recorded at `times`, playing `speed` simulated seconds per
    second at `fps` frames per second. Output frame k shows the recorded frame nearest to
    t0 + k speed / fps, k = 0 ... floor(duration fps / speed), and lasts until output frame k + 1
    starts at (k + 1) / fps, rounded to a hundredth of a second (a GIF's delays are whole
    hundredths, so the total stays exact). Frames recorded at one time (a static path) are shown
    one per output frame. Consecutive output frames that show the same recorded frame are one
    longer frame: returns ([(recorded frame index, duration [ms], output frames)], output frames).
    """
    times = np.asarray(times, dtype=float)
    if len(times) and times[-1] > times[0]:
        count = int(math.floor((times[-1] - times[0]) * fps / speed + 1e-6)) + 1
        wanted = times[0] + np.arange(count) * (speed / fps)
        right = np.searchsorted(times, wanted).clip(1, max(len(times) - 1, 1))
        left = right - 1
        index = np.where(wanted - times[left] <= times[right] - wanted, left, right)
    else:
        count = len(times)
        index = np.arange(count)
    ends = np.round(100.0 * np.arange(1, count + 1) / fps).astype(int)
    durations = 10 * np.diff(np.concatenate([[0], ends]))
    plan = []
    for i, d in zip(index.tolist(), durations.tolist()):
        if plan and plan[-1][0] == i:
            plan[-1][1] += d
            plan[-1][2] += 1
        else:
            plan.append([i, d, 1])
    return [tuple(p) for p in plan], count


def frame_lines(points, cells):
    """{kind: (n, 3) points}: the cells of each kind ('rod', 'body', 'joint') one after the other,
    each followed by a row of NaN (a break in the drawn line)."""
    pieces = {}
    for ids, kind in cells:
        if len(ids):
            pieces.setdefault(kind, []).extend([points[ids], np.full((1, 3), np.nan)])
    return {kind: np.vstack(p) for kind, p in pieces.items()}


# How each kind of cell is drawn in the animation (the snapshots' draw_frame, as lines).
ANIMATION_STYLE = {"rod": dict(color="C0", lw=1.5),
                   "body": dict(color="C0", lw=2.5),
                   "joint": dict(color="C0", ls="none", marker="o", ms=3.5)}


class MotionMovie:
    """The 3D view of an animation, drawn once: per frame only the lines' data (set_data_3d) and
    the title change. With a fixed view the axes (panes, grid, ticks) are kept as a background
    picture and only the lines and the title are drawn on it (blitting); a view that follows the
    mechanism redraws the axes for its new limits."""

    def __init__(self, label, fixed_box, dpi=90):
        self.label = label
        self.fig = plt.figure(figsize=(6.4, 6.0), dpi=dpi)
        self.ax = self.fig.add_subplot(projection="3d")
        self.lines = {kind: self.ax.plot([], [], [], **style)[0]
                      for kind, style in ANIMATION_STYLE.items()}
        self.title = self.ax.set_title(" ", fontsize=10)
        self.fixed = fixed_box is not None
        if self.fixed:
            set_cube(self.ax, *fixed_box)
            for artist in [*self.lines.values(), self.title]:
                artist.set_animated(True)
            self.fig.canvas.draw()
            self.background = self.fig.canvas.copy_from_bbox(self.fig.bbox)
        else:
            set_cube(self.ax, np.zeros(3), np.ones(3), margin=0.0)  # labels; limits per frame

    def render(self, points, cells, title, box=None):
        """Draws one frame; returns its pixels (height x width x 3, uint8, a copy)."""
        lines = frame_lines(points, cells)
        for kind, artist in self.lines.items():
            p = lines.get(kind, np.zeros((0, 3)))
            artist.set_data_3d(p[:, 0], p[:, 1], p[:, 2])
        self.title.set_text(title)
        canvas = self.fig.canvas
        if self.fixed:
            canvas.restore_region(self.background)
            for artist in [*self.lines.values(), self.title]:
                self.ax.draw_artist(artist)
        else:
            lo, hi = box
            self.ax.set_xlim(lo[0], hi[0])
            self.ax.set_ylim(lo[1], hi[1])
            self.ax.set_zlim(lo[2], hi[2])
            canvas.draw()
        return np.asarray(canvas.buffer_rgba())[:, :, :3].copy()

    def close(self):
        plt.close(self.fig)


def start_ffmpeg(path, width, height, fps):
    """An ffmpeg process that encodes raw RGB frames from its stdin into an H.264 MP4, or None
    when ffmpeg is not installed."""
    if not shutil.which("ffmpeg"):
        return None
    command = ["ffmpeg", "-y", "-loglevel", "error", "-f", "rawvideo", "-pix_fmt", "rgb24",
               "-s", f"{width}x{height}", "-r", f"{fps:g}", "-i", "-", "-an", "-c:v", "libx264",
               "-pix_fmt", "yuv420p", "-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2", path]
    return subprocess.Popen(command, stdin=subprocess.PIPE)


def animate(outdir, figdir, fps=25.0, speed=1.0):
    """FIGDIR/animation_RUN.gif (Pillow) and .mp4 (when ffmpeg is on PATH): the mechanism in 3D,
    in real time at `fps` frames per second (`speed` simulated seconds per second; frame_plan).
    Framed on the whole motion while its extent stays within 3 times the mechanism's initial
    size; otherwise framed as it moves: a cube of constant size (the largest its biggest
    connected part needs at any shown time) whose centre follows that part's centre.
    Returns the written paths."""
    from PIL import Image

    frames = read_collection(outdir)
    label = run_label(outdir)
    if not frames:
        print(f"warning: {outdir} has no ParaView frames (vtk/): no animation", file=sys.stderr)
        return []
    times = [t for t, _ in frames]
    plan, count = frame_plan(times, fps, speed)
    geometry = {i: read_frame(frames[i][1]) for i, _, _ in plan}
    shown = [geometry[i] for i, _, _ in plan if len(geometry[i][0])]
    if not shown:
        return []
    size0 = max(extent(shown[0][0]), 1e-12)
    every = np.vstack([points for points, _ in shown])
    lo, hi = every.min(axis=0), every.max(axis=0)
    boxes = {}
    if float(np.max(hi - lo)) <= 3.0 * size0:
        movie = MotionMovie(label, (lo, hi))
    else:
        movie = MotionMovie(label, None)
        followed = {}
        for i, (points, cells) in geometry.items():
            if len(points):
                main = parts(points, cells, 0.2 * size0)[0]
                followed[i] = np.vstack([points[cells[c][0]] for c in main])
        half = max(0.55 * max(extent(u) for u in followed.values()), 1e-9)
        for i, used in followed.items():
            c = 0.5 * (used.min(axis=0) + used.max(axis=0))
            boxes[i] = (c - half, c + half)
    one_time = not times[-1] > times[0]
    gif_path = os.path.join(figdir, f"animation_{label}.gif")
    mp4_path = os.path.join(figdir, f"animation_{label}.mp4")
    ffmpeg = None
    images, durations = [], []
    palette = None
    try:
        for k, (i, duration, repeats) in enumerate(plan):
            points, cells = geometry[i]
            t = frames[i][0]
            title = f"{label}   " + (f"frame {i + 1} of {len(frames)}" if one_time
                                     else f"t = {t:.3f} s")
            pixels = movie.render(points, cells, title, boxes.get(i, (lo, hi)))
            if k == 0:
                ffmpeg = start_ffmpeg(mp4_path, pixels.shape[1], pixels.shape[0], fps)
                if ffmpeg is None:
                    print("note: ffmpeg not found: no MP4 (the GIF is written)", file=sys.stderr)
            if ffmpeg is not None:
                ffmpeg.stdin.write(pixels.tobytes() * repeats)
            image = Image.fromarray(pixels, "RGB")
            # One palette for all frames, from the first (the colours do not change): quantizing
            # to a fixed palette is ten times faster than an adaptive palette per frame.
            if palette is None:
                palette = image.quantize(colors=255, method=Image.Quantize.MEDIANCUT)
            images.append(image.quantize(palette=palette, dither=Image.Dither.NONE))
            durations.append(duration)
    finally:
        movie.close()
        if ffmpeg is not None:
            ffmpeg.stdin.close()
            ffmpeg.wait()
    images[0].save(gif_path, save_all=True, append_images=images[1:], duration=durations, loop=0)
    written = [gif_path]
    if ffmpeg is not None:
        if ffmpeg.returncode == 0:
            written.append(mp4_path)
        else:
            print(f"warning: ffmpeg failed (exit status {ffmpeg.returncode}): no MP4",
                  file=sys.stderr)
    return written


def parse_list(text, kind, what):
    if text is None:
        return None
    try:
        return [kind(v.strip()) for v in text.split(",") if v.strip()]
    except ValueError as e:
        raise InputProblem(f"--{what}: expected a comma-separated list: {e}") from e


def main(argv):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("outdirs", nargs="+", help="run output directories (screwfem run -o)")
    parser.add_argument("-o", "--output", required=True, help="figure directory")
    parser.add_argument("--points", help="comma-separated point names (default: all)")
    parser.add_argument("--times", help="comma-separated snapshot (and rod field) times [s] "
                                        "(default: 5 evenly spaced)")
    parser.add_argument("--animate", action="store_true",
                        help="also write animation_RUN.gif (and .mp4 with ffmpeg) per run")
    parser.add_argument("--fps", type=float, default=25.0,
                        help=f"frames per second of the animation (default 25, at most {MAX_FPS:g})")
    parser.add_argument("--speed", type=float, default=1.0,
                        help="simulated seconds per second of the animation (default 1: real "
                             "time; 0.5: slow motion)")
    args = parser.parse_args(argv)
    try:
        if not (0.0 < args.fps <= MAX_FPS):
            raise InputProblem(f"--fps {args.fps:g}: expected more than 0 and at most {MAX_FPS:g} "
                               f"(a GIF's frame delays are whole hundredths of a second, and viewers "
                               f"slow down delays below 0.02 s)")
        if not (0.0 < args.speed < math.inf):
            raise InputProblem(f"--speed {args.speed:g}: expected a positive number")
        for outdir in args.outdirs:
            if not os.path.isdir(outdir):
                raise InputProblem(f"{outdir} is not a directory")
        runs = [Run(d) for d in args.outdirs]
        point_runs = [(run.label, run.table("points.csv")) for run in runs]
        joint_runs = [(run.label, run.table("joints.csv")) for run in runs if run.has("joints.csv")]
        wanted = parse_list(args.points, str, "points")
        times = parse_list(args.times, float, "times")

        names = []
        for _, (columns, _) in point_runs:
            names += [n for n in point_names(columns) if n not in names]
        if wanted is not None:
            for name in wanted:
                missing = [label for label, (columns, _) in point_runs if name not in point_names(columns)]
                if missing:
                    raise InputProblem(f"point '{name}' is not recorded in {', '.join(missing)} "
                                       f"(recorded: {', '.join(names) or 'none'})")
            names = wanted
        os.makedirs(args.output, exist_ok=True)
        written = []
        for name in names:
            selected = [(label, table) for label, table in point_runs if name in point_names(table[0])]
            written.append(plot_point(name, selected, args.output))
        joints = []
        for _, (columns, _) in joint_runs:
            joints += [n for n in joint_names(columns) if n not in joints]
        units = {}
        for outdir in args.outdirs:
            for column_name, entry in read_joint_units(outdir).items():
                units.setdefault(column_name, entry)
        for name in joints:
            selected = [(label, table) for label, table in joint_runs if f"{name}.q" in table[0]]
            written.append(plot_joint(name, selected, args.output, units.get(name)))
        for run in runs:
            written += plot_tables(run, args.output, times)
            path = plot_snapshots(run.outdir, times, args.output)
            if path:
                written.append(path)
            if args.animate:
                written += animate(run.outdir, args.output, args.fps, args.speed)
    except InputProblem as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    for path in written:
        print(path)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
