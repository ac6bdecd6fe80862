"""Plots the results of screwfem runs (run with Debian's /usr/bin/python3; `screwfem plot` does).

    screwfem_plot.py OUTDIR [OUTDIR ...] -o FIGDIR [--points P8,P4] [--times 0,0.5,1,1.5,2]

For every recorded point P (points.csv), FIGDIR/point_P.png: displacement x(t) - x(t0),
velocity and acceleration (rows) of the x, y and z components (columns), the runs overlaid
with their directory names as labels -- the layout of Fig. 4 of the GRM paper.
For every recorded joint J (joints.csv), FIGDIR/joint_J.png: q, dq/dt, d2q/dt2 and effort.
For every run with ParaView frames (vtk/, read by screwfem_vtk.py), FIGDIR/snapshots_RUN.png: the mechanism
at the chosen times (the frames nearest to them) in one 3D view -- Fig. 3 style.

Needs numpy and matplotlib (Debian: python3-numpy, python3-matplotlib); uses the Agg backend.
Exit status: 0 on success, 2 when an input is missing or malformed.
"""

import argparse
import csv
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import screwfem_vtk  # noqa: E402  (the ParaView frames, whatever their encoding)

AXES = ("x", "y", "z")


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


def point_names(columns):
    return [c[:-2] for c in columns if c.endswith(".x") and c[:-2] + ".az" in columns]


def joint_names(columns):
    """Joint prefixes in column order: 'J0' for one coordinate, 'J7.0', 'J7.1' for several."""
    return [c[:-2] for c in columns if c.endswith(".q")]


def save_figure(fig, figdir, filename):
    """Lays out, writes figdir/filename (PNG, 120 dpi) and closes fig; returns the path."""
    fig.tight_layout()
    path = os.path.join(figdir, filename)
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def plot_point(name, runs, figdir):
    fig, axes = plt.subplots(3, 3, figsize=(13, 9), sharex=True, squeeze=False)
    quantities = (("displacement", "", "m"), ("velocity", "v", "m/s"), ("acceleration", "a", "m/s²"))
    row_scale = [0.0, 0.0, 0.0]  # largest magnitude of each quantity over components and runs
    for label, (columns, data) in runs:
        t = data[:, 0]
        for row, (title, prefix, unit) in enumerate(quantities):
            for col, axis in enumerate(AXES):
                values = data[:, columns.index(f"{name}.{prefix}{axis}")]
                if row == 0 and len(values):
                    values = values - values[0]
                if len(values):
                    row_scale[row] = max(row_scale[row], float(np.max(np.abs(values))))
                ax = axes[row][col]
                ax.plot(t, values, label=label, marker="o" if len(t) == 1 else None)
                ax.set_title(f"{name} {title} {axis}", fontsize=10)
                ax.set_ylabel(unit)
                ax.grid(True, alpha=0.3)
    # A component that stays at round-off level (e.g. the z motion of a planar chain) is shown
    # on the scale of the other components, not magnified into noise.
    for row, scale in enumerate(row_scale):
        for ax in axes[row]:
            low, high = ax.get_ylim()
            if scale > 0.0 and high - low < 1e-9 * scale:
                ax.set_ylim(-0.05 * scale, 0.05 * scale)
    for ax in axes[-1]:
        ax.set_xlabel("t [s]")
    axes[0][0].legend(fontsize=8)
    return save_figure(fig, figdir, f"point_{name}.png")


def plot_joint(name, runs, figdir):
    quantities = (("q", "coordinate", "m or rad"), ("qd", "rate", "m/s or rad/s"),
                  ("qdd", "acceleration", "m/s² or rad/s²"), ("effort", "effort", "N or N m"))
    fig, axes = plt.subplots(4, 1, figsize=(8, 10), sharex=True)
    for label, (columns, data) in runs:
        for ax, (suffix, title, unit) in zip(axes, quantities):
            ax.plot(data[:, 0], data[:, columns.index(f"{name}.{suffix}")], label=label,
                    marker="o" if len(data) == 1 else None)
            ax.set_title(f"{name} {title}", fontsize=10)
            ax.set_ylabel(unit)
            ax.grid(True, alpha=0.3)
    axes[-1].set_xlabel("t [s]")
    axes[0].legend(fontsize=8)
    return save_figure(fig, figdir, f"joint_{name}.png")


def read_collection(outdir):
    """[(time, path)] of the ParaView frames of a run, or None without them."""
    try:
        return screwfem_vtk.read_collection(outdir)
    except screwfem_vtk.VtkError as e:
        raise InputProblem(str(e)) from e


def read_frame(path):
    """Points (n x 3) and cells of one .vtp frame: a list of (point indices, kind) with kind
    'joint', 'rod' or 'body'."""
    try:
        frame = screwfem_vtk.read_frame(path)
    except screwfem_vtk.VtkError as e:
        raise InputProblem(str(e)) from e
    points = np.array(frame["points"], dtype=float).reshape(-1, 3)
    return points, list(zip(frame["cells"], frame["kinds"]))


def plot_snapshots(outdir, times, figdir):
    frames = read_collection(outdir)
    label = run_label(outdir)
    if not frames:
        print(f"warning: {outdir} has no ParaView frames (vtk/motion.pvd): no snapshots "
              f"(set outputs.vtk: true)", file=sys.stderr)
        return None
    frame_times = np.array([t for t, _ in frames])
    if times is None:
        times = np.linspace(frame_times[0], frame_times[-1], min(5, len(frames)))
    chosen = sorted({int(np.argmin(np.abs(frame_times - t))) for t in times})
    fig = plt.figure(figsize=(9, 8))
    ax = fig.add_subplot(projection="3d")
    colors = plt.cm.viridis(np.linspace(0.0, 0.9, len(chosen)))
    lo, hi = np.full(3, np.inf), np.full(3, -np.inf)
    for color, index in zip(colors, chosen):
        t, path = frames[index]
        points, cells = read_frame(path)
        if len(points):
            lo, hi = np.minimum(lo, points.min(axis=0)), np.maximum(hi, points.max(axis=0))
        first = True
        for ids, kind in cells:
            p = points[ids]
            if kind == "joint":
                ax.scatter(p[:, 0], p[:, 1], p[:, 2], color=color, s=12)
                continue
            ax.plot(p[:, 0], p[:, 1], p[:, 2], color=color, linewidth=2.5 if kind == "body" else 1.5,
                    label=f"t = {t:.3g} s" if first else None)
            first = False
    if np.all(np.isfinite(lo)):
        center, half = 0.5 * (lo + hi), 0.5 * max(float(np.max(hi - lo)), 1e-9)
        ax.set_xlim(center[0] - half, center[0] + half)
        ax.set_ylim(center[1] - half, center[1] + half)
        ax.set_zlim(center[2] - half, center[2] + half)
        ax.set_box_aspect((1, 1, 1))
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_zlabel("z [m]")
    ax.set_title(f"{label}: snapshots")
    ax.legend(fontsize=8, loc="upper left")
    return save_figure(fig, figdir, f"snapshots_{label}.png")


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
    parser.add_argument("--times", help="comma-separated snapshot times [s] (default: 5 evenly spaced)")
    args = parser.parse_args(argv)
    try:
        for outdir in args.outdirs:
            if not os.path.isdir(outdir):
                raise InputProblem(f"{outdir} is not a directory")
        labels = [run_label(d) for d in args.outdirs]
        point_runs = [(label, read_table(os.path.join(d, "points.csv")))
                      for label, d in zip(labels, args.outdirs)]
        joint_path = [os.path.join(d, "joints.csv") for d in args.outdirs]
        joint_runs = [(label, read_table(p)) for label, p in zip(labels, joint_path) if os.path.isfile(p)]
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
            runs = [(label, table) for label, table in point_runs if name in point_names(table[0])]
            written.append(plot_point(name, runs, args.output))
        joints = []
        for _, (columns, _) in joint_runs:
            joints += [n for n in joint_names(columns) if n not in joints]
        for name in joints:
            runs = [(label, table) for label, table in joint_runs if f"{name}.q" in table[0]]
            written.append(plot_joint(name, runs, args.output))
        for outdir in args.outdirs:
            path = plot_snapshots(outdir, times, args.output)
            if path:
                written.append(path)
    except InputProblem as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    for path in written:
        print(path)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
