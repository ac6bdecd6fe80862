"""The ParaView frames `screwfem run` writes, read back: the binary (default) and the ascii
encoding of one run hold the same values bit for bit as tools/screwfem_vtk.py reads them (also
the kinds, sizes, tensions and contact forces of tests/view/true_size.yaml), and,
when VTK's own Python module is installed (Debian's python3-vtk9, not a dependency of the
project), VTK's vtkXMLPolyDataReader — the reader ParaView uses — reads both to the same points.

    /usr/bin/python3 -m unittest -v test_vtk_frames
        (from tests/tools; SCREWFEM_SOURCE_DIR, SCREWFEM_CLI = the screwfem program)
"""

import math
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

SOURCE = os.environ.get("SCREWFEM_SOURCE_DIR", "../..")
sys.path.insert(0, os.path.join(SOURCE, "tools"))
import screwfem_vtk  # noqa: E402

try:
    from vtkmodules.vtkIOXML import vtkXMLPolyDataReader
    from vtkmodules.util.numpy_support import vtk_to_numpy
except ImportError:
    vtkXMLPolyDataReader = None


class Frames(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cli = os.environ.get("SCREWFEM_CLI")
        if not cli:
            raise unittest.SkipTest("SCREWFEM_CLI (the screwfem program) is not set")
        cls.tmp = tempfile.mkdtemp(prefix="screwfem_vtk_frames_")
        cls.runs = {}
        scene = os.path.join(SOURCE, "examples", "grm", "grm_rigid.yaml")
        for fmt in ("binary", "ascii"):
            out = os.path.join(cls.tmp, fmt)
            subprocess.run([cli, "run", scene, "-o", out, "-q", "--set", "defaults.elements=2",
                            "--set", "analysis.end_time=0.1", "--set", f"outputs.vtk_format={fmt}"],
                           check=True)
            cls.runs[fmt] = screwfem_vtk.read_collection(out)

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.tmp, ignore_errors=True)

    def test_binary_and_ascii_frames_hold_the_same_values(self):
        binary, ascii_ = self.runs["binary"], self.runs["ascii"]
        self.assertEqual(len(binary), 6)  # t = 0, 0.02, ..., 0.1
        self.assertEqual([t for t, _ in binary], [t for t, _ in ascii_])
        for (_, b), (_, a) in zip(binary, ascii_):
            fb, fa = screwfem_vtk.read_frame(b), screwfem_vtk.read_frame(a)
            with open(b, "rb") as f:
                self.assertIn(b'<AppendedData encoding="raw">', f.read())
            self.assertEqual(fb["time"], fa["time"])
            self.assertEqual(fb["points"], fa["points"])  # float == float: bit for bit
            self.assertEqual(fb["point_data"], fa["point_data"])
            self.assertEqual(fb["cell_data"], fa["cell_data"])
            self.assertEqual(fb["cells"], fa["cells"])

    def test_sizes_shapes_tendons_and_forces_read_back_in_both_encodings(self):
        # The viewer's true-size scene: every kind of cell, with the sizes and the per-frame
        # tension and contact forces, the same in both encodings.
        scene = os.path.join(SOURCE, "tests", "view", "true_size.yaml")
        frames = {}
        for fmt in ("binary", "ascii"):
            out = os.path.join(self.tmp, "sizes_" + fmt)
            subprocess.run([os.environ["SCREWFEM_CLI"], "run", scene, "-o", out, "-q",
                            "--set", "analysis.end_time=0.02", "--set", f"outputs.vtk_format={fmt}"],
                           check=True)
            frames[fmt] = screwfem_vtk.read_frame(screwfem_vtk.read_collection(out)[-1][1])
        binary, ascii_ = frames["binary"], frames["ascii"]
        self.assertEqual(binary["point_data"], ascii_["point_data"])
        self.assertEqual(binary["cell_data"], ascii_["cell_data"])
        kinds = binary["kinds"]
        for kind in ("joint", "rod", "body_point", "tendon", "contact", "pair_contact", "sphere",
                     "capsule", "box", "inertia_box", "plane", "obstacle_sphere", "obstacle_capsule"):
            self.assertIn(kind, kinds)
        radius = binary["point_data"]["radius"][1]
        rod = binary["cells"][kinds.index("rod")]
        self.assertEqual([radius[i] for i in rod], [0.008] * len(rod))
        tension = binary["cell_data"]["tension"][1]
        self.assertEqual(tension[kinds.index("tendon")], 1.0)
        force = binary["point_data"]["contact_force"][1]
        lift = sum(force[3 * c[0] + 2] for c, k in zip(binary["cells"], kinds) if k == "contact")
        self.assertAlmostEqual(lift, 0.064 * 9.81, delta=0.05 * 0.064 * 9.81)

    def test_contact_states_stick_and_slip_reach_the_viewer(self):
        # examples/contact/slide.yaml: the box launched at 2 m/s slides (mu 0.3) until 0.68 s,
        # then sticks. Its four bottom corners' contact_state: slipping with the whole friction
        # (share mu_k / mu_s = 1) at 0.3 s, sticking at 0.8 s inside the cone (share and
        # deflection below half their limits); the viewer's page data carries them per contact.
        import screwfem_view
        scene = os.path.join(SOURCE, "examples", "contact", "slide.yaml")
        out = os.path.join(self.tmp, "slide")
        subprocess.run([os.environ["SCREWFEM_CLI"], "run", scene, "-o", out, "-q",
                        "--set", "analysis.end_time=0.8", "--set", "outputs.interval=0.1"],
                       check=True)
        frames = [(t, screwfem_vtk.read_frame(f)) for t, f in screwfem_vtk.read_collection(out)]
        by_time = {round(t, 6): f for t, f in frames}

        def corners(f):
            force = f["point_data"]["contact_force"][1]
            state = f["point_data"]["contact_state"][1]
            cells = [c[0] for c, k in zip(f["cells"], f["kinds"]) if k == "contact"]
            return [state[3 * i:3 * i + 3] for i in cells if abs(force[3 * i + 2]) > 1e-6 and
                    f["points"][i][1] < 0.5]  # the box (y = 0), not the rod (y = 1)

        sliding, stuck = corners(by_time[0.3]), corners(by_time[0.8])
        self.assertEqual(len(sliding), 4)
        self.assertEqual(len(stuck), 4)
        for slip, deflection, share in sliding:
            self.assertEqual(slip, 1.0)
            self.assertAlmostEqual(share, 1.0, places=9)
        for slip, deflection, share in stuck:
            self.assertEqual(slip, 0.0)
            self.assertLess(share, 0.5)
            self.assertLess(deflection, 0.5 * 0.3 * 9.81 / 4 / 1e5)  # below mu f_n / k_t
        summary = screwfem_view.read_json(os.path.join(out, "summary.json"), True)
        data = screwfem_view.page_data(frames, len(frames), summary, None, {}, "slide", None, [])
        self.assertIsNotNone(data["contact_states"])
        self.assertEqual(len(data["contacts"]) * 3 * len(frames),
                         len(__import__("base64").b64decode(data["contact_states"]["data"])) // 2)
    def test_cylinders_turned_boxes_and_box_obstacles_at_their_size_and_pose(self):
        # examples/contact/shapes.yaml: the crate's box turned by 0.3 rad about z, the wall box
        # by 0.2 rad, the can and the post cylinders of radius 0.04 and 0.05.
        scene = os.path.join(SOURCE, "examples", "contact", "shapes.yaml")
        out = os.path.join(self.tmp, "shapes")
        subprocess.run([os.environ["SCREWFEM_CLI"], "run", scene, "-o", out, "-q",
                        "--set", "analysis.end_time=0.01"], check=True)
        f = screwfem_vtk.read_frame(screwfem_vtk.read_collection(out)[0][1])
        kinds, pd, cells = f["kinds"], f["point_data"], f["cells"]
        radius, half = pd["radius"][1], pd["half_size"][1]
        fx = pd["frame_x"][1]

        def one(kind):
            self.assertEqual(kinds.count(kind), 1, kind)
            return cells[kinds.index(kind)]
        for kind, r, turn, halves in (("box", None, 0.3, [0.05, 0.05, 0.05]),
                                      ("obstacle_box", None, 0.2, [0.05, 0.3, 0.1])):
            p = one(kind)[0]
            self.assertEqual(half[3 * p:3 * p + 3], halves)
            for k, value in enumerate((math.cos(turn), math.sin(turn), 0.0)):
                self.assertAlmostEqual(fx[3 * p + k], value, delta=1e-12)
        for kind, r, length in (("cylinder", 0.04, 0.12), ("obstacle_cylinder", 0.05, 0.4)):
            a, b = one(kind)
            self.assertEqual((radius[a], radius[b]), (r, r))
            d = [f["points"][b][k] - f["points"][a][k] for k in range(3)]
            self.assertAlmostEqual(math.sqrt(sum(x * x for x in d)), length, delta=1e-9)

    def test_chambers_and_visual_radius(self):
        # tests/view/chamber.yaml: a static run of 4 load steps (a frame each, the load factor
        # as its time) of a rod drawn by visual_radius 10 mm with a pressure chamber of 50 mm^2
        # at r = (0, -5 mm, 0) along its whole length.
        scene = os.path.join(SOURCE, "tests", "view", "chamber.yaml")
        for fmt in ("binary", "ascii"):
            out = os.path.join(self.tmp, "chamber_" + fmt)
            subprocess.run([os.environ["SCREWFEM_CLI"], "run", scene, "-o", out, "-q",
                            "--set", f"outputs.vtk_format={fmt}"], check=True)
            collection = screwfem_vtk.read_collection(out)
            self.assertEqual([t for t, _ in collection], [0.25, 0.5, 0.75, 1.0])
            for lam, path in (collection[0], collection[-1]):
                f = screwfem_vtk.read_frame(path)
                kinds, pd = f["kinds"], f["point_data"]
                self.assertEqual(kinds.count("chamber"), 1)
                rod = f["cells"][kinds.index("rod")]
                chamber = f["cells"][kinds.index("chamber")]
                self.assertEqual(len(rod), 9)
                self.assertEqual(len(chamber), 9)  # every node: the chamber covers the rod
                self.assertEqual(f["cell_data"]["item_id"][1][kinds.index("chamber")], 0)
                radius, half = pd["radius"][1], pd["half_size"][1]
                r = (5e-5 / math.pi) ** 0.5
                for i in rod:
                    self.assertEqual((radius[i], half[3 * i:3 * i + 3]), (0.01, [0.0, 0.01, 0.01]))
                for i in chamber:
                    self.assertAlmostEqual(radius[i], r, delta=1e-15)
                    self.assertEqual(half[3 * i + 1:3 * i + 3], [radius[i], radius[i]])
                # The chamber's points: the rod nodes' points offset by -5 mm along their
                # section y axis, with the rods' axes.
                fy = pd["frame_y"][1]
                for a, b in zip(rod, chamber):
                    for k in range(3):
                        self.assertAlmostEqual(f["points"][b][k],
                                               f["points"][a][k] - 0.005 * fy[3 * a + k],
                                               delta=1e-15)
                        self.assertEqual(fy[3 * b + k], fy[3 * a + k])
                # Curled towards +y: the arc of curvature lambda p A |r2| / EI = lambda 12.5
                # 1/m (per reference length 0.1 m) stretched by lambda p A / EA
                # (examples/pneumatic/finger.yaml), to 1e-9 m.
                tip = f["points"][rod[-1]]
                kappa, stretch = lam * 12.5, 1 + lam * 5.0 / 225
                self.assertAlmostEqual(tip[0], stretch * math.sin(kappa * 0.1) / kappa, delta=1e-9)
                self.assertAlmostEqual(tip[1], stretch * (1 - math.cos(kappa * 0.1)) / kappa,
                                       delta=1e-9)
                self.assertAlmostEqual(tip[2], 0.0, delta=1e-12)

    @unittest.skipIf(vtkXMLPolyDataReader is None, "VTK's Python module (python3-vtk9) not installed")
    def test_vtk_reads_both_encodings_to_the_same_points(self):
        for fmt in ("binary", "ascii"):
            for _, path in self.runs[fmt]:
                ours = screwfem_vtk.read_frame(path)
                reader = vtkXMLPolyDataReader()
                reader.SetFileName(path)
                reader.Update()
                poly = reader.GetOutput()
                self.assertEqual(poly.GetNumberOfPoints(), len(ours["points"]), path)
                points = vtk_to_numpy(poly.GetPoints().GetData())
                self.assertEqual([tuple(p) for p in points.tolist()], ours["points"], path)
                velocity = vtk_to_numpy(poly.GetPointData().GetArray("velocity")).ravel().tolist()
                self.assertEqual(velocity, ours["point_data"]["velocity"][1], path)
                self.assertEqual(poly.GetNumberOfCells(), len(ours["cells"]), path)
                time = poly.GetFieldData().GetArray("TimeValue").GetValue(0)
                self.assertEqual(time, ours["time"], path)


if __name__ == "__main__":
    unittest.main()
