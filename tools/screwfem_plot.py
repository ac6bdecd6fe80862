"""Plots the results of screwfem runs (run with Debian's /usr/bin/python3; `screwfem plot` does).

    screwfem_plot.py OUTDIR [OUTDIR ...] -o FIGDIR [--points P8,P4] [--times 0,0.5,1,1.5,2]
                     [--animate]

For every recorded point P (points.csv), FIGDIR/point_P.png: displacement x(t) - x(t0),
velocity and acceleration (rows) of the x, y and z components (columns), the runs overlaid
with their directory names as labels -- the layout of Fig. 4 of the GRM paper.
For every recorded joint J (joints.csv), FIGDIR/joint_J.png: q, dq/dt, d2q/dt2 and effort,
in the units joints.json gives (rad or m). When the runs' scales in one panel differ by more
than 10x, each scale group gets its own row of panels (the group's runs are in its legend).
For every run with ParaView frames (vtk/, read by screwfem_vtk.py), FIGDIR/snapshots_RUN.png:
the mechanism at the chosen times (the frames nearest to them) in one 3D view -- Fig. 3 style;
a mechanism that travels far also gets one view per time, framed on it.
With --animate, FIGDIR/animation_RUN.gif (and .mp4 when ffmpeg is installed) per run: the
mechanism in 3D, framed on it as it moves.

Needs numpy and matplotlib (Debian: python3-numpy, python3-matplotlib; python3-pil for the
GIF); uses the Agg backend.
Exit status: 0 on success, 2 when an input is missing or malformed.
"""

import argparse
import csv
import json
import os
import shutil
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


def plot_grouped(name, runs, rows, columns, figdir, filename, width):
    """One figure with a row of panels (one per column spec) for every quantity, overlaid runs;
    a quantity whose runs' scales differ by more than 10x gets one row per scale group.

    rows: [(title, unit, get(columns, data, column_spec) -> values)]; columns: [(spec, label)]."""
    colors = {label: f"C{k}" for k, (label, _) in enumerate(runs)}
    layout = []  # (row spec, group of run indices)
    for row in rows:
        scales = []
        for _, (cols, data) in runs:
            m = 0.0
            for spec, _ in columns:
                v = row[2](cols, data, spec)
                if len(v):
                    m = max(m, float(np.max(np.abs(v))))
            scales.append(m)
        for group in scale_groups(scales):
            layout.append((row, group, max(scales[i] for i in group)))
    fig, axes = plt.subplots(len(layout), len(columns), figsize=(width, 2.9 * len(layout) + 0.4),
                             sharex=True, squeeze=False)
    for r, ((title, unit, get), group, scale) in enumerate(layout):
        for c, (spec, label) in enumerate(columns):
            ax = axes[r][c]
            for i in group:
                run_label, (cols, data) = runs[i]
                v = get(cols, data, spec)
                ax.plot(data[:, 0], v, label=run_label, color=colors[run_label],
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
        ax.set_xlabel("t [s]")
    return save_figure(fig, figdir, filename)


def plot_point(name, runs, figdir):
    def getter(prefix, relative):
        def get(cols, data, axis):
            v = data[:, cols.index(f"{name}.{prefix}{axis}")]
            return v - v[0] if relative and len(v) else v
        return get

    rows = [("displacement", "m", getter("", True)), ("velocity", "m/s", getter("v", False)),
            ("acceleration", "m/s²", getter("a", False))]
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
    """q, dq/dt, d2q/dt2 and effort of joint coordinate `name`, with the units that joints.json
    gives ("rad" or "m"); without it, "m or rad"."""
    u = units or {}
    rows = [("coordinate", u.get("unit", "m or rad"), "q"),
            ("rate", u.get("rate_unit", "m/s or rad/s"), "qd"),
            ("acceleration", u.get("acceleration_unit", "m/s² or rad/s²"), "qdd"),
            ("effort", u.get("effort_unit", "N or N m"), "effort")]
    rows = [(title, unit, (lambda suffix: lambda cols, data, _: data[:, cols.index(f"{name}.{suffix}")])(s))
            for title, unit, s in rows]
    title = name + (f" ({u['type']} {u['quantity']})" if "type" in u and "quantity" in u else "")
    return plot_grouped(title, runs, rows, [(None, "")], figdir, f"joint_{name}.png", 8)


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


def animate(outdir, figdir, fps=25):
    """FIGDIR/animation_RUN.gif (Pillow) and .mp4 (when ffmpeg is on PATH): the mechanism in 3D,
    one picture per ParaView frame, framed as it moves: a cube of constant size (the largest
    its biggest connected part needs at any time) whose centre follows that part's centre.
    Returns the written paths."""
    from matplotlib import animation

    frames = read_collection(outdir)
    label = run_label(outdir)
    if not frames:
        print(f"warning: {outdir} has no ParaView frames (vtk/): no animation", file=sys.stderr)
        return []
    geometry = [(t, *read_frame(path)) for t, path in frames]
    geometry = [g for g in geometry if len(g[1])]
    if not geometry:
        return []
    size0 = max(extent(geometry[0][1]), 1e-12)
    followed = []
    for _, points, cells in geometry:
        main = parts(points, cells, 0.2 * size0)[0]
        used = np.vstack([points[cells[i][0]] for i in main])
        followed.append(used)
    half = max(0.55 * max(extent(u) for u in followed), 1e-9)
    centers = np.array([0.5 * (u.min(axis=0) + u.max(axis=0)) for u in followed])
    fig = plt.figure(figsize=(6.4, 6.0))
    ax = fig.add_subplot(projection="3d")

    def draw(k):
        ax.cla()
        t, points, cells = geometry[k]
        draw_frame(ax, points, cells, "C0")
        c = centers[k]
        set_cube(ax, c - half, c + half, margin=0.0)
        ax.set_title(f"{label}   t = {t:.3f} s", fontsize=10)
        return []

    written = []
    writers = [("gif", animation.PillowWriter(fps=fps))]
    if shutil.which("ffmpeg") and animation.FFMpegWriter.isAvailable():
        writers.append(("mp4", animation.FFMpegWriter(fps=fps, bitrate=1800)))
    else:
        print("note: ffmpeg not found: no MP4 (the GIF is written)", file=sys.stderr)
    movie = animation.FuncAnimation(fig, draw, frames=len(geometry), blit=False)
    for ext, writer in writers:
        path = os.path.join(figdir, f"animation_{label}.{ext}")
        movie.save(path, writer=writer, dpi=90)
        written.append(path)
    plt.close(fig)
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
    parser.add_argument("--times", help="comma-separated snapshot times [s] (default: 5 evenly spaced)")
    parser.add_argument("--animate", action="store_true",
                        help="also write animation_RUN.gif (and .mp4 with ffmpeg) per run")
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
        units = {}
        for outdir in args.outdirs:
            for column, entry in read_joint_units(outdir).items():
                units.setdefault(column, entry)
        for name in joints:
            runs = [(label, table) for label, table in joint_runs if f"{name}.q" in table[0]]
            written.append(plot_joint(name, runs, args.output, units.get(name)))
        for outdir in args.outdirs:
            path = plot_snapshots(outdir, times, args.output)
            if path:
                written.append(path)
            if args.animate:
                written += animate(outdir, args.output)
    except InputProblem as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    for path in written:
        print(path)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
