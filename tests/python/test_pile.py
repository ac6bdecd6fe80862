"""The pile generator (examples/contact/pile.py; docs/numerics.md, "Impacts and the contact line
search"): its scenes are valid, the committed 20-rod example is its output, and a pile of rigid
capsules (without a halving) and one of rods and boxes settle with the default contact settings
from Python, the energy never above its start."""

import csv
import json
import pathlib
import sys
import tempfile
import unittest

import screwfem as sf

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "examples" / "contact"))
import pile  # noqa: E402


def body(text):
    return [line for line in text.splitlines() if line and not line.startswith("#")]


class PileGenerator(unittest.TestCase):
    def test_committed_example_is_the_generator_output(self):
        text = pile.scene(layers=2, rods=10, friction=1.0, end_time=1.5)
        committed = (ROOT / "examples" / "contact" / "pile20.yaml").read_text()
        self.assertEqual(body(text), body(committed))

    def test_scenes_have_the_layers_rods_and_shapes_asked(self):
        with tempfile.TemporaryDirectory() as d:
            rods = pile.load(pathlib.Path(d) / "r.yaml", layers=3, rods=4)
            self.assertEqual(rods.model.num_rods, 12)
            caps = pile.load(pathlib.Path(d) / "c.yaml", layers=2, rods=3, kind="capsules")
            self.assertEqual(caps.model.num_rods, 0)
            self.assertEqual(len(caps.model.bodies), 6)
            mixed = pile.load(pathlib.Path(d) / "m.yaml", layers=2, rods=4, kind="mixed")
            self.assertEqual(mixed.model.num_rods, 6)  # layer 1: two of its four are boxes
        with self.assertRaises(ValueError):
            pile.scene(kind="spheres")

    def settle(self, kind, friction):
        """Runs a small pile of `kind` for 1 s; returns the summary and energy rows."""
        with tempfile.TemporaryDirectory() as d:
            scene = pile.load(pathlib.Path(d) / "p.yaml", layers=2, rods=3, kind=kind,
                              friction=friction, end_time=1.0)
            scene.outputs.vtk = False
            result = sf.run_scene(scene, str(pathlib.Path(d) / "out"))
            self.assertTrue(result.ok, result.message)
            summary = json.loads((pathlib.Path(d) / "out" / "summary.json").read_text())
            with open(pathlib.Path(d) / "out" / "energy.csv") as f:
                rows = list(csv.DictReader(f))
        return summary, [float(r["total"]) for r in rows], float(rows[-1]["kinetic"])

    def test_piles_of_capsules_and_of_rods_and_boxes_settle(self):
        for kind in ("capsules", "mixed"):
            summary, energy, kinetic = self.settle(kind, 0.5)
            with self.subTest(kind=kind):
                self.assertEqual(summary["settings"]["rho_inf"], 0.0)  # auto, with contact
                # Rigid capsules need no halving; rods falling onto box edges still take some
                # (22 in this run: a box edge across a rod is a sharp contact).
                if kind == "capsules":
                    self.assertEqual(summary["step_halvings"], 0)
                # No external work: the total energy (gravity included) never exceeds its start.
                self.assertLessEqual(max(energy), energy[0] * (1 + 1e-9))
                self.assertLess(kinetic, 1e-3 * (energy[0] - min(energy)))


if __name__ == "__main__":
    unittest.main()
