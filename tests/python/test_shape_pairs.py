"""Contact between moving bodies from Python (elements/shape_pair.h): a sphere resting on a
fixed sphere carries its weight along the normal at the penalty law's gap; an excluded pair
never touches.

Run by ctest (python/CMakeLists.txt, test python_shape_pairs) as
    /usr/bin/python3 -m unittest -v test_shape_pairs
from tests/python with PYTHONPATH=<build>/python.
"""

import unittest

import numpy as np

import screwfem as sf


def resting_spheres(exclude):
    # k = 1e5 N/m, onset 1e-4 m, 1 kg: the penetration branch, gap onset/2 - m g / k.
    gap = 0.5e-4 - 9.81 / 1e5
    b = sf.ModelBuilder()
    low = np.eye(4)
    low[2, 3] = 1.0
    top = np.eye(4)
    top[2, 3] = 1.2 + gap
    n0 = b.add_node(low, "low")
    b.fix_node(n0)
    b.add_rigid_body("low", n0, 1.0, [0, 0, 0], np.eye(3))
    n1 = b.add_node(top, "top")
    b.add_rigid_body("top", n1, 1.0, [0, 0, 0], 0.004 * np.eye(3))
    for body in (0, 1):
        b.add_contact_shape(sf.ContactShape(body, sf.ContactShapeType.SPHERE, [0, 0, 0],
                                            radius=0.1))
    law = sf.ContactSettings()
    law.stiffness = 1e5
    law.onset = 1e-4
    b.set_contact_settings(law)
    if exclude:
        b.exclude_contact_pair(False, 0, False, 1)
    b.set_gravity([0, 0, -9.81])
    sim = sf.Simulation(sf.Scene(b.build(), "pairs"))
    sim.initialize()
    for _ in range(30):
        sim.step(1e-3)
    return sim, gap


class ShapePairTest(unittest.TestCase):
    def test_resting_sphere_carries_its_weight(self):
        sim, gap = resting_spheres(False)
        states = sim.pair_contact_states()
        self.assertEqual(len(states), 1)
        c = states[0]
        self.assertAlmostEqual(c["normal_force"], 9.81, places=6)
        self.assertAlmostEqual(c["gap"], gap, places=10)
        self.assertAlmostEqual(c["normal"][2], -1.0, places=12)  # from top (B) to low (A)
        self.assertEqual((c["owner_a"], c["owner_b"]), (0, 1))
        self.assertEqual(c["part"], -1)  # two spheres: one point

    def test_excluded_pair_never_touches(self):
        sim, _ = resting_spheres(True)
        self.assertEqual(sim.pair_contact_states(), [])


if __name__ == "__main__":
    unittest.main()
