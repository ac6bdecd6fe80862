"""tools/screwfem_plot.py: joint axes in the units joints.json gives, separate axes for runs
whose scales differ by more than 10x, the connected parts the snapshots are framed on; static
paths drawn against the load factor; a figure for every table a run writes, its curves equal to
the table's columns; the animation's frame count and timing for --fps and --speed.

    /usr/bin/python3 -m unittest -v test_plot
        (from tests/tools; SCREWFEM_SOURCE_DIR; SCREWFEM_CLI = the screwfem program, for the
        tests that run it)

The tables are synthesized (physics-free: every value written as the shortest text that reads
back as the same double, so the figures' data must equal them exactly); the tests named *_cli
run small scenes with the screwfem program and plot them with `screwfem plot`.
"""

import contextlib
import io
import json
import os
import shutil
import stat
import subprocess
import sys
import tempfile
import unittest

import numpy as np

SOURCE = os.environ.get("SCREWFEM_SOURCE_DIR", "../..")
sys.path.insert(0, os.path.join(SOURCE, "tools"))
import screwfem_plot  # noqa: E402  (selects matplotlib's Agg backend)
import matplotlib.pyplot as plt  # noqa: E402
from PIL import Image  # noqa: E402


def write_csv(path, columns, rows):
    with open(path, "w") as f:
        f.write(",".join(columns) + "\n")
        for row in rows:
            f.write(",".join(repr(float(v)) for v in row) + "\n")


def read_csv(path):
    return screwfem_plot.read_table(path)


def lines_of(ax):
    """(label, x, y) of every line drawn on an axis."""
    return [(line.get_label(), np.asarray(line.get_xdata(), float), np.asarray(line.get_ydata(), float))
            for line in ax.get_lines()]


def gif_timing(path):
    """(frames, total duration [ms], per-frame durations) of a GIF."""
    with Image.open(path) as im:
        durations = []
        for k in range(im.n_frames):
            im.seek(k)
            durations.append(im.info["duration"])
        return im.n_frames, sum(durations), durations


class CapturedFigures(unittest.TestCase):
    """Keeps the figures instead of writing them (self.figures: {file name: figure})."""

    def setUp(self):
        self.figures = {}
        self._save = screwfem_plot.save_figure

        def keep(fig, figdir, name):
            self.figures[name] = fig
            return os.path.join(figdir, name)

        screwfem_plot.save_figure = keep
        self.tmp = tempfile.mkdtemp(prefix="screwfem_plot_test_")

    def tearDown(self):
        screwfem_plot.save_figure = self._save
        plt.close("all")
        shutil.rmtree(self.tmp, ignore_errors=True)


class Figures(CapturedFigures):
    @staticmethod
    def joint_run(scale):
        t = np.linspace(0.0, 1.0, 11)
        q = scale * np.sin(t)
        return ["t", "J.q", "J.qd", "J.qdd", "J.effort"], np.column_stack([t, q, q, q, q])

    def last(self):
        return list(self.figures.values())[-1]

    def test_scale_groups_split_beyond_ten_times(self):
        self.assertEqual(screwfem_plot.scale_groups([1.0, 2.0, 30.0]), [[0, 1], [2]])
        self.assertEqual(screwfem_plot.scale_groups([5.0, 0.6, 1.0]), [[1, 2, 0]])
        self.assertEqual(screwfem_plot.scale_groups([0.0, 3.0, 400.0]), [[0, 1], [2]])
        self.assertEqual(screwfem_plot.scale_groups([0.0, 0.0]), [[0, 1]])

    def test_joint_axes_carry_the_units_of_joints_json(self):
        units = {"unit": "rad", "rate_unit": "rad/s", "acceleration_unit": "rad/s²",
                 "effort_unit": "N m", "type": "revolute", "quantity": "angle"}
        screwfem_plot.plot_joint("J", [("a", self.joint_run(1.0))], "unused", units)
        labels = [ax.get_ylabel() for ax in self.last().axes]
        self.assertEqual(labels, ["rad", "rad/s", "rad/s²", "N m"])
        slide = dict(units, unit="m", rate_unit="m/s", acceleration_unit="m/s²", effort_unit="N")
        screwfem_plot.plot_joint("J", [("a", self.joint_run(1.0))], "unused", slide)
        self.assertEqual([ax.get_ylabel() for ax in self.last().axes], ["m", "m/s", "m/s²", "N"])

    def test_runs_of_different_scales_get_their_own_axes(self):
        runs = [("small", self.joint_run(1.0)), ("close", self.joint_run(3.0)),
                ("large", self.joint_run(50.0))]
        screwfem_plot.plot_joint("J", runs, "unused")
        axes = self.last().axes
        self.assertEqual(len(axes), 8)  # 4 quantities x 2 scale groups
        legends = [[t.get_text() for t in ax.get_legend().get_texts()] for ax in axes]
        self.assertEqual(legends[0], ["small", "close"])
        self.assertEqual(legends[1], ["large"])
        # Within 10x: one axis per quantity, runs overlaid.
        screwfem_plot.plot_joint("J", runs[:2], "unused")
        self.assertEqual(len(self.last().axes), 4)


class Parts(unittest.TestCase):
    def test_a_far_slide_splits_the_mechanism_in_two_parts(self):
        points = np.array([[0, 0, 0], [1, 0, 0], [1, 0, 0], [20, 0, 0], [21, 0, 0]], dtype=float)
        cells = [([0, 1], "body"), ([2], "joint"), ([3, 4], "rod")]
        self.assertEqual(screwfem_plot.parts(points, cells, 0.2), [[0, 1], [2]])
        self.assertEqual(screwfem_plot.parts(points, cells, 50.0), [[0, 1, 2]])


# ---- a synthesized run with every table ----------------------------------------------------------

POINT_COLUMNS = ["x", "y", "z", "vx", "vy", "vz", "ax", "ay", "az", "qw", "qx", "qy", "qz"]
T = [0.0, 0.1, 0.2, 0.3]  # output times of the dynamic run
LOAD = [0.1, 0.25, 0.2, 0.4, 0.7]  # load factors of the static path (arc length: not monotone)


def write_run(outdir, static=False):
    """A run directory with every table screwfem writes (points.csv with the orientation columns
    and one more column it does not know), the values arbitrary but distinct."""
    os.makedirs(outdir)
    rng = np.random.default_rng(7)
    steps = [(1.0, lf) for lf in LOAD] if static else [(t,) for t in T]
    lead = ["t", "load_factor"] if static else ["t"]

    def table(name, columns, width=None):
        rows = [list(s) + list(rng.normal(size=len(columns))) for s in steps]
        write_csv(os.path.join(outdir, name), lead + columns, rows)

    table("points.csv", [f"tip.{c}" for c in POINT_COLUMNS] + ["tip.extra"])
    table("joints.csv", ["hinge.q", "hinge.qd", "hinge.qdd", "hinge.effort"])
    table("tendons.csv", [f"{n}.{q}" for n in ("flexor", "extensor") for q in ("length", "rate", "tension")])
    table("forces.csv", ["spring.length", "spring.rate", "spring.force"])
    table("actuators.csv", ["chamber", "muscle"])
    table("reactions.csv", [f"{j}.{q}" for j in ("hinge", "clamp")
                            for q in ("Fx", "Fy", "Fz", "Mx", "My", "Mz")])
    table("energy.csv", ["kinetic", "strain", "spring", "gravity", "total",
                         "px", "py", "pz", "Lx", "Ly", "Lz"])
    # Long tables: contacts at the second and fourth step only (none at the others).
    contact_columns = ["pair", "rod", "owner", "obstacle", "px", "py", "pz", "nx", "ny", "nz",
                       "fn", "ftx", "fty", "ftz", "gap"]
    rows = []
    for k, gap in ((1, -1e-4), (3, -3e-4)):
        # rod 0 on obstacle 0 (two pairs), body 1 on obstacle 0 (one pair)
        rows.append(list(steps[k]) + [0, 1, 0, 0, 0, 0, 0, 0, 0, 1, 1.5 * k, 0.1, 0.2, 0.0, gap])
        rows.append(list(steps[k]) + [1, 1, 0, 0, 0, 0, 0, 0, 0, 1, 2.0, 0.3, -0.1, 0.0, 2e-4])
        rows.append(list(steps[k]) + [5, 0, 1, 0, 0, 0, 0, 0, 0, 1, 4.0, 0.0, 0.0, 0.5, 3e-4])
    write_csv(os.path.join(outdir, "contacts.csv"), lead + contact_columns, rows)
    pair_columns = ["pair", "rod_a", "owner_a", "element_a", "rod_b", "owner_b", "element_b",
                    "pax", "pay", "paz", "pbx", "pby", "pbz", "nx", "ny", "nz", "fn", "ftx", "fty",
                    "ftz", "gap", "part"]
    rows = []
    for k in (0, 2):
        # rod 0 against body 1, once with the sides as (rod, body) and once as (body, rod)
        rows.append(list(steps[k]) + [7, 1, 0, 3, 0, 1, -1] + [0] * 9 + [1.0, 0.5, 0.0, 0.0, 1e-5, -1])
        rows.append(list(steps[k]) + [9, 0, 1, -1, 1, 0, 4] + [0] * 9 + [2.0, 0.25, 0.0, 0.0, 2e-5, -1])
    write_csv(os.path.join(outdir, "pair_contacts.csv"), lead + pair_columns, rows)
    fields = ["gamma1", "gamma2", "gamma3", "kappa1", "kappa2", "kappa3", "n1", "n2", "n3",
              "m1", "m2", "m3"]
    rows = []
    for s in steps:
        for rod in (0, 1):
            for e in (2, 0, 1):  # stations not in order of s
                rows.append(list(s) + [rod, 0.1 * e + 0.05] + list(rng.normal(size=12)))
    write_csv(os.path.join(outdir, "rod_fields.csv"), lead + ["rod", "s"] + fields, rows)
    with open(os.path.join(outdir, "summary.json"), "w") as f:
        json.dump({"scene": {"name": "synthetic"}, "status": "completed",
                   "settings": {"analysis": "static" if static else "dynamic"}}, f)


TABLE_FIGURES = ["tendons", "forces", "actuators", "contacts", "pair_contacts", "reactions",
                 "energy", "rod_fields"]


class Tables(unittest.TestCase):
    """The synthesized runs, dynamic and static, plotted once by main(): the files written and
    the figures kept (self.figures[run][file name])."""

    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.mkdtemp(prefix="screwfem_plot_tables_")
        cls.figures, cls.status = {}, {}
        save = screwfem_plot.save_figure

        def save_and_keep(fig, figdir, name):
            label = os.path.basename(figdir)[len("fig_"):]
            cls.figures[label][name] = fig
            if label == "static":  # kept only: writing is tested on the other run
                plt.close(fig)
                return os.path.join(figdir, name)
            return save(fig, figdir, name)  # closes the figure; its lines stay readable

        screwfem_plot.save_figure = save_and_keep
        try:
            for label in ("run", "static"):
                cls.figures[label] = {}
                write_run(os.path.join(cls.tmp, label), static=label == "static")
                extra = ["--times", "0.12,0.3"] if label == "run" else []
                cls.status[label] = cls.main([os.path.join(cls.tmp, label), "-o",
                                              os.path.join(cls.tmp, "fig_" + label), *extra])
        finally:
            screwfem_plot.save_figure = save

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.tmp, ignore_errors=True)

    @staticmethod
    def main(argv):
        """main(argv) with its output (the written paths, warnings) kept from the test's."""
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
            return screwfem_plot.main(argv)

    def run_dir(self, name):
        return os.path.join(self.tmp, name)

    def panels(self, name, run="run"):
        """{title: axis} of a kept figure's visible panels."""
        return {ax.get_title(): ax for ax in self.figures[run][name].axes if ax.get_visible()}

    def test_every_table_gives_its_figure_file(self):
        for label in ("run", "static"):
            self.assertEqual(self.status[label], 0)
            expected = {"point_tip.png", "joint_hinge.png"} | {f"{t}_{label}.png" for t in TABLE_FIGURES}
            self.assertEqual(set(self.figures[label]), expected)
        figdir = os.path.join(self.tmp, "fig_run")
        self.assertEqual(set(os.listdir(figdir)), set(self.figures["run"]))
        for name in os.listdir(figdir):
            self.assertGreater(os.path.getsize(os.path.join(figdir, name)), 1000)
        # Without a table, no figure of it.
        outdir = os.path.join(self.tmp, "few")
        os.makedirs(outdir)
        for name in ("points.csv", "forces.csv"):
            shutil.copy(os.path.join(self.tmp, "run", name), outdir)
        figdir = os.path.join(self.tmp, "fig_few")
        self.assertEqual(self.main([outdir, "-o", figdir]), 0)
        self.assertEqual(sorted(os.listdir(figdir)), ["forces_few.png", "point_tip.png"])

    def test_static_path_is_drawn_against_the_load_factor(self):
        outdir = self.run_dir("static")
        figures = self.figures["static"]
        columns, points = read_csv(os.path.join(outdir, "points.csv"))
        load = screwfem_plot.column(columns, points, "load_factor")
        self.assertEqual(load.tolist(), LOAD)
        # points: the position only, against the load factor (t is 1 on every row).
        axes = [ax for ax in figures["point_tip.png"].axes]
        self.assertEqual(len(axes), 3)
        for ax, a in zip(axes, "xyz"):
            ((_, x, y),) = lines_of(ax)
            np.testing.assert_array_equal(x, load)
            np.testing.assert_array_equal(y, screwfem_plot.column(columns, points, f"tip.{a}"))
            self.assertEqual(ax.get_xlabel(), "load factor")
            self.assertTrue(ax.get_title().endswith(f"position {a}"))
        # joints: q and effort.
        jc, joints = read_csv(os.path.join(outdir, "joints.csv"))
        axes = figures["joint_hinge.png"].axes
        self.assertEqual(len(axes), 2)
        for ax, q in zip(axes, ("q", "effort")):
            ((_, x, y),) = lines_of(ax)
            np.testing.assert_array_equal(x, load)
            np.testing.assert_array_equal(y, screwfem_plot.column(jc, joints, f"hinge.{q}"))
        # every table's figure: the x data of every curve is the load factor column
        for stem in TABLE_FIGURES[:-1]:
            for ax in figures[f"{stem}_static.png"].axes:
                for label, x, _ in lines_of(ax):
                    np.testing.assert_array_equal(x, load, err_msg=f"{stem}: {label}")
        # actuators on a static path: the applied value, the profile's value x the load factor
        ac, act = read_csv(os.path.join(outdir, "actuators.csv"))
        curves = [c for ax in figures["actuators_static.png"].axes for c in lines_of(ax)]
        self.assertEqual(sorted(c[0] for c in curves), ["chamber", "muscle"])
        for label, _, y in curves:
            np.testing.assert_array_equal(y, screwfem_plot.column(ac, act, label) * load)
        # and no rate, drift or momentum panel (zero on a static path)
        self.assertEqual(list(self.panels("tendons_static.png", "static")), ["length", "tension"])
        self.assertEqual(list(self.panels("energy_static.png", "static")), ["energy"])

    def test_static_is_read_from_the_summary_or_the_columns(self):
        self.assertTrue(screwfem_plot.Run(self.run_dir("static")).static)
        self.assertFalse(screwfem_plot.Run(self.run_dir("run")).static)
        outdir = os.path.join(self.tmp, "no_summary")
        os.makedirs(outdir)
        shutil.copy(os.path.join(self.tmp, "static", "points.csv"), outdir)
        self.assertTrue(screwfem_plot.Run(outdir).static)  # the load_factor column

    def test_curves_equal_the_table_columns(self):
        outdir = self.run_dir("run")
        figures = self.figures["run"]

        def table(name):
            return read_csv(os.path.join(outdir, name))

        # points.csv with orientation and unknown columns: selected by name
        pc, points = table("points.csv")
        t = points[:, 0]
        for ax in figures["point_tip.png"].axes:
            ((_, x, y),) = lines_of(ax)
            np.testing.assert_array_equal(x, t)
        ax = figures["point_tip.png"].axes[1]  # displacement y
        y = points[:, pc.index("tip.y")]
        np.testing.assert_array_equal(lines_of(ax)[0][2], y - y[0])
        ax = figures["point_tip.png"].axes[5]  # velocity z
        np.testing.assert_array_equal(lines_of(ax)[0][2], points[:, pc.index("tip.vz")])
        # tendons and forces: one curve per tendon in each panel
        for name, force in (("tendons", "tension"), ("forces", "force")):
            columns, data = table(f"{name}.csv")
            panels = self.panels(f"{name}_run.png")
            self.assertEqual(len(panels), 3)
            for (title, ax), quantity in zip(panels.items(), ("length", "rate", force)):
                for label, x, y in lines_of(ax):
                    np.testing.assert_array_equal(x, t)
                    np.testing.assert_array_equal(
                        y, screwfem_plot.column(columns, data, f"{label}.{quantity}"))
                expected = ["flexor", "extensor"] if name == "tendons" else ["spring"]
                self.assertEqual([c[0] for c in lines_of(ax)], expected)
        # reactions: force and moment components per joint
        columns, data = table("reactions.csv")
        panels = self.panels("reactions_run.png")
        self.assertEqual(len(panels), 4)
        for title, ax in panels.items():
            joint = title.split(":")[0]
            kind = "F" if "force" in title else "M"
            self.assertEqual([c[0] for c in lines_of(ax)], ["x", "y", "z"])
            for label, x, y in lines_of(ax):
                np.testing.assert_array_equal(
                    y, screwfem_plot.column(columns, data, f"{joint}.{kind}{label}"))
        # energy: the energies, the total's drift, the momenta
        columns, data = table("energy.csv")
        axes = [ax for ax in figures["energy_run.png"].axes if ax.get_visible()]
        self.assertEqual(len(axes), 4)
        energies = lines_of(axes[0])
        self.assertEqual([c[0] for c in energies], ["kinetic", "strain", "spring", "gravity", "total"])
        for label, _, y in energies:
            np.testing.assert_array_equal(y, screwfem_plot.column(columns, data, label))
        total = screwfem_plot.column(columns, data, "total")
        np.testing.assert_array_equal(lines_of(axes[1])[0][2], total - total[0])
        for ax, names in ((axes[2], ["px", "py", "pz"]), (axes[3], ["Lx", "Ly", "Lz"])):
            self.assertEqual([c[0] for c in lines_of(ax)], names)
            for label, _, y in lines_of(ax):
                np.testing.assert_array_equal(y, screwfem_plot.column(columns, data, label))

    def test_contacts_are_summed_per_shape_and_obstacle(self):
        panels = self.panels("contacts_run.png")
        fn, ft, count, gap = (dict((c[0], c[2]) for c in lines_of(ax)) for ax in panels.values())
        self.assertEqual(sorted(fn), ["body 1 - obstacle 0", "rod 0 - obstacle 0"])
        # steps 1 and 3 hold pairs; 0 and 2 none
        np.testing.assert_array_equal(fn["rod 0 - obstacle 0"], [0.0, 1.5 + 2.0, 0.0, 4.5 + 2.0])
        np.testing.assert_array_equal(fn["body 1 - obstacle 0"], [0.0, 4.0, 0.0, 4.0])
        np.testing.assert_array_equal(count["rod 0 - obstacle 0"], [0, 2, 0, 2])
        np.testing.assert_array_equal(count["body 1 - obstacle 0"], [0, 1, 0, 1])
        friction = np.hypot(0.1 + 0.3, 0.2 - 0.1)
        np.testing.assert_allclose(ft["rod 0 - obstacle 0"], [0.0, friction, 0.0, friction], rtol=1e-15)
        np.testing.assert_array_equal(ft["body 1 - obstacle 0"], [0.0, 0.5, 0.0, 0.5])
        np.testing.assert_array_equal(gap["rod 0 - obstacle 0"], [np.nan, -1e-4, np.nan, -3e-4])
        for ax in panels.values():
            for _, x, _ in lines_of(ax):
                np.testing.assert_array_equal(x, T)
        # pairs of moving shapes: one group whatever the order of the sides; the friction on
        # the first shape of the label (a rod before a body)
        panels = self.panels("pair_contacts_run.png")
        fn, ft, count, gap = (dict((c[0], c[2]) for c in lines_of(ax)) for ax in panels.values())
        self.assertEqual(list(fn), ["rod 0 - body 1"])
        np.testing.assert_array_equal(fn["rod 0 - body 1"], [3.0, 0.0, 3.0, 0.0])
        np.testing.assert_array_equal(ft["rod 0 - body 1"], [0.25, 0.0, 0.25, 0.0])  # 0.5 - 0.25
        np.testing.assert_array_equal(count["rod 0 - body 1"], [2, 0, 2, 0])
        np.testing.assert_array_equal(gap["rod 0 - body 1"], [1e-5, np.nan, 1e-5, np.nan])

    def test_rod_fields_along_s_at_the_chosen_times(self):
        outdir = self.run_dir("run")  # plotted with --times 0.12,0.3
        columns, data = read_csv(os.path.join(outdir, "rod_fields.csv"))
        panels = self.panels("rod_fields_run.png")
        self.assertEqual(len(panels), 12)
        ax = panels["κ2: bending curvature 2"]
        curves = lines_of(ax)
        self.assertEqual(len(curves), 4)  # 2 times x 2 rods
        for (_, s, y), (t, rod) in zip(curves, [(0.1, 0), (0.1, 1), (0.3, 0), (0.3, 1)]):
            rows = data[(data[:, 0] == t) & (data[:, columns.index("rod")] == rod)]
            rows = rows[np.argsort(rows[:, columns.index("s")])]
            np.testing.assert_array_equal(s, rows[:, columns.index("s")])
            np.testing.assert_array_equal(y, rows[:, columns.index("kappa2")])
        legend = [t.get_text() for t in panels["γ1: extension"].get_legend().get_texts()]
        self.assertEqual(legend, ["t = 0.1 s, rod 0", "t = 0.1 s, rod 1", "t = 0.3 s, rod 0",
                                  "t = 0.3 s, rod 1"])


# ---- animation -----------------------------------------------------------------------------------

class MathTextInNames(unittest.TestCase):
    def test_run_folder_with_dollar_signs_is_plotted_by_name(self):
        tmp = tempfile.mkdtemp(prefix="screwfem_plot_names_")
        self.addCleanup(shutil.rmtree, tmp, True)
        name = "run$\\frac{$"
        write_run(os.path.join(tmp, name))
        for table in os.listdir(os.path.join(tmp, name)):  # two tables suffice (and are quick)
            if table not in ("points.csv", "energy.csv", "summary.json"):
                os.remove(os.path.join(tmp, name, table))
        figures = {}
        save = screwfem_plot.save_figure

        def keep(fig, figdir, file_name):
            figures[file_name] = fig
            return save(fig, figdir, file_name)

        screwfem_plot.save_figure = keep
        try:
            with contextlib.redirect_stdout(io.StringIO()), \
                    contextlib.redirect_stderr(io.StringIO()) as err:
                status = screwfem_plot.main([os.path.join(tmp, name), "-o",
                                             os.path.join(tmp, "fig")])
        finally:
            screwfem_plot.save_figure = save
        self.assertEqual(status, 0, err.getvalue())
        self.assertNotIn("Traceback", err.getvalue())
        self.assertIn(f"energy_{name}.png", os.listdir(os.path.join(tmp, "fig")))
        titles = [t.get_text() for fig in figures.values() for t in
                  [fig._suptitle] + [ax.title for ax in fig.axes] if t is not None]
        self.assertTrue(any(name in t for t in titles), titles)


class FramePlan(unittest.TestCase):
    def test_frames_and_durations_follow_fps_and_speed(self):
        times = np.arange(0, 201) * 0.01  # 2 s recorded at 100 frames per second
        for fps, speed, count in ((25, 1, 51), (25, 2, 26), (10, 0.5, 41), (30, 1, 61), (50, 4, 26)):
            plan, n = screwfem_plot.frame_plan(times, fps, speed)
            self.assertEqual(n, count)
            self.assertEqual(n, round(2.0 * fps / speed) + 1)
            self.assertEqual(sum(p[2] for p in plan), n)
            self.assertEqual(sum(p[1] for p in plan), 10 * round(100 * n / fps))
            self.assertTrue(all(p[1] % 10 == 0 and p[1] >= 20 for p in plan))
            # frame k shows the recorded frame nearest to t = k speed / fps
            k = np.cumsum([0] + [p[2] for p in plan[:-1]])
            np.testing.assert_allclose(times[[p[0] for p in plan]], k * speed / fps, atol=0.005 + 1e-12)
        # Recorded more sparsely than shown: a frame lasts until the next recorded one.
        plan, n = screwfem_plot.frame_plan([0.0, 0.5, 1.0], 10, 1)
        self.assertEqual(n, 11)
        self.assertEqual(plan, [(0, 300, 3), (1, 500, 5), (2, 300, 3)])
        # All at one time (a static path): one output frame per recorded frame.
        plan, n = screwfem_plot.frame_plan([1.0, 1.0, 1.0], 25, 1)
        self.assertEqual((plan, n), ([(0, 40, 1), (1, 40, 1), (2, 40, 1)], 3))


class Animation(unittest.TestCase):
    """animate() on synthesized frames: a link that turns (or travels far) at every frame."""

    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="screwfem_plot_anim_")
        self._read = screwfem_plot.read_collection, screwfem_plot.read_frame

    def tearDown(self):
        screwfem_plot.read_collection, screwfem_plot.read_frame = self._read
        shutil.rmtree(self.tmp, ignore_errors=True)

    def frames(self, duration, rate, travel=0.0):
        times = np.arange(round(duration * rate) + 1) / rate
        frames = {}
        for k, t in enumerate(times):
            a = 2.0 * t
            p = np.array([[0, 0, 0], [np.cos(a), 0, np.sin(a)], [np.cos(a), 0.2, np.sin(a)]])
            frames[f"f{k}"] = (p + [travel * t, 0, 0], [([0], "joint"), ([0, 1], "body"), ([1, 2], "rod")])
        screwfem_plot.read_collection = lambda outdir: [(t, f"f{k}") for k, t in enumerate(times)]
        screwfem_plot.read_frame = lambda path: frames[path]

    def animate(self, fps, speed, name="run"):
        with contextlib.redirect_stderr(io.StringIO()):  # "note: ffmpeg not found"
            paths = screwfem_plot.animate(os.path.join(self.tmp, name), self.tmp, fps, speed)
        self.assertEqual(paths[0], os.path.join(self.tmp, f"animation_{name}.gif"))
        return gif_timing(paths[0])

    def test_frames_written_equal_duration_times_fps_over_speed(self):
        self.frames(2.0, 100)
        for fps, speed in ((25, 1), (20, 2), (10, 0.5)):
            frames, total, durations = self.animate(fps, speed)
            self.assertEqual(frames, 2.0 * fps / speed + 1)
            self.assertEqual(total, round(1000 * frames / fps))  # real time x 1 / speed
            self.assertEqual(set(durations), {round(1000 / fps)})

    def test_a_mechanism_that_travels_far_is_followed(self):
        self.frames(1.0, 50, travel=20.0)
        frames, total, _ = self.animate(10, 1)
        self.assertEqual((frames, total), (11, 1100))

    def test_mp4_gets_every_frame_when_ffmpeg_is_installed(self):
        # A stand-in for ffmpeg that writes the number of bytes it was sent.
        bindir = os.path.join(self.tmp, "bin")
        os.makedirs(bindir)
        fake = os.path.join(bindir, "ffmpeg")
        with open(fake, "w") as f:
            f.write(f"#!{sys.executable}\nimport sys\n"
                    "n = len(sys.stdin.buffer.read())\n"
                    "open(sys.argv[-1], 'w').write(str(n) + ' ' + ' '.join(sys.argv[1:]))\n")
        os.chmod(fake, os.stat(fake).st_mode | stat.S_IEXEC)
        path = os.environ["PATH"]
        os.environ["PATH"] = bindir + os.pathsep + path
        try:
            self.frames(1.0, 4)  # recorded at 4 per second, shown at 10: frames repeat
            paths = screwfem_plot.animate(os.path.join(self.tmp, "run"), self.tmp, 10, 1)
        finally:
            os.environ["PATH"] = path
        self.assertEqual(paths[1], os.path.join(self.tmp, "animation_run.mp4"))
        with open(paths[1]) as f:
            sent, *args = f.read().split()
        width, height = map(int, args[args.index("-s") + 1].split("x"))
        self.assertEqual(args[args.index("-r") + 1], "10")
        self.assertEqual(int(sent), 11 * width * height * 3)  # 11 frames of RGB
        frames, total, _ = gif_timing(paths[0])
        self.assertEqual((frames, total), (5, 1100))  # in the GIF, repeats are longer frames


# ---- the screwfem program ------------------------------------------------------------------------

class Cli(unittest.TestCase):
    """Small scenes run by the screwfem program and plotted by `screwfem plot` (this script)."""

    @classmethod
    def setUpClass(cls):
        cls.cli = os.environ.get("SCREWFEM_CLI")
        if not cls.cli:
            raise unittest.SkipTest("SCREWFEM_CLI (the screwfem program) is not set")
        cls.tmp = tempfile.mkdtemp(prefix="screwfem_plot_cli_")
        cls.env = dict(os.environ, SCREWFEM_PLOT_SCRIPT=os.path.join(SOURCE, "tools", "screwfem_plot.py"))

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.tmp, ignore_errors=True)

    def run_scene(self, scene, name, *settings, status=0):
        out = os.path.join(self.tmp, name)
        args = [self.cli, "run", os.path.join(SOURCE, scene), "-o", out, "-q", "--force"]
        for s in settings:
            args += ["--set", s]
        result = subprocess.run(args, capture_output=True, text=True)
        self.assertEqual(result.returncode, status, result.stderr)
        return out

    def plot(self, *args, status=0):
        result = subprocess.run([self.cli, "plot", *args], capture_output=True, text=True, env=self.env)
        self.assertEqual(result.returncode, status, result.stderr)
        return result

    def test_static_path_cli(self):
        # The slider crank past its dead centre by arc length: the load factor turns back.
        out = self.run_scene("tests/data/slider_crank.yaml", "static", "analysis.statics.method=arclength",
                             "analysis.statics.max_steps=40", status=1)
        figdir = os.path.join(self.tmp, "fig_static")
        printed = self.plot(out, "-o", figdir).stdout.split()
        names = sorted(os.path.basename(p) for p in printed)
        self.assertEqual(names, ["energy_static.png", "joint_elbow.png", "joint_guide.png", "joint_pivot.png",
                                 "joint_wrist.png", "point_slider.png", "reactions_static.png"])
        columns, data = read_csv(os.path.join(out, "points.csv"))
        load = screwfem_plot.column(columns, data, "load_factor")
        self.assertEqual(len(set(data[:, 0])), 1)  # t is the end time on every row
        self.assertLess(np.min(np.diff(load)), 0.0)  # the path turns back
        figures = {}
        save = screwfem_plot.save_figure
        screwfem_plot.save_figure = lambda fig, figdir, name: figures.setdefault(name, fig)
        try:
            screwfem_plot.plot_point("slider", [("static", (columns, data))], figdir)
        finally:
            screwfem_plot.save_figure = save
        ((_, x, y),) = lines_of(figures["point_slider.png"].axes[0])
        np.testing.assert_array_equal(x, load)
        np.testing.assert_array_equal(y, screwfem_plot.column(columns, data, "slider.x"))

    def test_animation_fps_and_speed_cli(self):
        out = self.run_scene("tests/data/pendulum.yaml", "pendulum", "outputs.vtk_interval=0.01")
        figdir = os.path.join(self.tmp, "fig_pendulum")
        self.plot(out, "-o", figdir, "--animate", "--fps", "10", "--speed", "0.5")
        frames, total, durations = gif_timing(os.path.join(figdir, "animation_pendulum.gif"))
        self.assertEqual(frames, 0.5 * 10 / 0.5 + 1)  # 0.5 s at 10 frames per second, half speed
        self.assertEqual(durations, [100] * frames)
        for name in ("point_tip.png", "joint_hinge.png", "reactions_pendulum.png", "energy_pendulum.png",
                     "snapshots_pendulum.png"):
            self.assertTrue(os.path.isfile(os.path.join(figdir, name)), name)
        # Out of range: an input error (exit status 2) naming the option.
        self.assertIn("--fps", self.plot(out, "-o", figdir, "--animate", "--fps", "60", status=2).stderr)
        self.assertIn("--speed", self.plot(out, "-o", figdir, "--speed", "0", status=2).stderr)


if __name__ == "__main__":
    unittest.main()
