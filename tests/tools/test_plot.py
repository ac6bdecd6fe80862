"""tools/screwfem_plot.py: joint axes in the units joints.json gives, separate axes for runs
whose scales differ by more than 10x, and the connected parts the snapshots are framed on.

    /usr/bin/python3 -m unittest -v test_plot      (from tests/tools; SCREWFEM_SOURCE_DIR)
"""

import os
import sys
import unittest

import numpy as np

sys.path.insert(0, os.path.join(os.environ.get("SCREWFEM_SOURCE_DIR", "../.."), "tools"))
import screwfem_plot  # noqa: E402


class Figures(unittest.TestCase):
    def setUp(self):
        # Keep the figure instead of writing it.
        self.figures = []
        self._save = screwfem_plot.save_figure
        screwfem_plot.save_figure = lambda fig, figdir, name: self.figures.append(fig) or name

    def tearDown(self):
        screwfem_plot.save_figure = self._save

    @staticmethod
    def joint_run(scale):
        t = np.linspace(0.0, 1.0, 11)
        q = scale * np.sin(t)
        return ["t", "J.q", "J.qd", "J.qdd", "J.effort"], np.column_stack([t, q, q, q, q])

    def test_scale_groups_split_beyond_ten_times(self):
        self.assertEqual(screwfem_plot.scale_groups([1.0, 2.0, 30.0]), [[0, 1], [2]])
        self.assertEqual(screwfem_plot.scale_groups([5.0, 0.6, 1.0]), [[1, 2, 0]])
        self.assertEqual(screwfem_plot.scale_groups([0.0, 3.0, 400.0]), [[0, 1], [2]])
        self.assertEqual(screwfem_plot.scale_groups([0.0, 0.0]), [[0, 1]])

    def test_joint_axes_carry_the_units_of_joints_json(self):
        units = {"unit": "rad", "rate_unit": "rad/s", "acceleration_unit": "rad/s²",
                 "effort_unit": "N m", "type": "revolute", "quantity": "angle"}
        screwfem_plot.plot_joint("J", [("a", self.joint_run(1.0))], "unused", units)
        labels = [ax.get_ylabel() for ax in self.figures[-1].axes]
        self.assertEqual(labels, ["rad", "rad/s", "rad/s²", "N m"])
        slide = dict(units, unit="m", rate_unit="m/s", acceleration_unit="m/s²", effort_unit="N")
        screwfem_plot.plot_joint("J", [("a", self.joint_run(1.0))], "unused", slide)
        self.assertEqual([ax.get_ylabel() for ax in self.figures[-1].axes], ["m", "m/s", "m/s²", "N"])

    def test_runs_of_different_scales_get_their_own_axes(self):
        runs = [("small", self.joint_run(1.0)), ("close", self.joint_run(3.0)),
                ("large", self.joint_run(50.0))]
        screwfem_plot.plot_joint("J", runs, "unused")
        axes = self.figures[-1].axes
        self.assertEqual(len(axes), 8)  # 4 quantities x 2 scale groups
        legends = [[t.get_text() for t in ax.get_legend().get_texts()] for ax in axes]
        self.assertEqual(legends[0], ["small", "close"])
        self.assertEqual(legends[1], ["large"])
        # Within 10x: one axis per quantity, runs overlaid.
        screwfem_plot.plot_joint("J", runs[:2], "unused")
        self.assertEqual(len(self.figures[-1].axes), 4)


class Parts(unittest.TestCase):
    def test_a_far_slide_splits_the_mechanism_in_two_parts(self):
        points = np.array([[0, 0, 0], [1, 0, 0], [1, 0, 0], [20, 0, 0], [21, 0, 0]], dtype=float)
        cells = [([0, 1], "body"), ([2], "joint"), ([3, 4], "rod")]
        self.assertEqual(screwfem_plot.parts(points, cells, 0.2), [[0, 1], [2]])
        self.assertEqual(screwfem_plot.parts(points, cells, 50.0), [[0, 1, 2]])


if __name__ == "__main__":
    unittest.main()
