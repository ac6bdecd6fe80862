"""Contact between moving bodies from Python (elements/shape_pair.h): a sphere resting on a
fixed sphere carries its weight along the normal at the penalty law's gap; an excluded pair
never touches.

Run by ctest (python/CMakeLists.txt, test python_shape_pairs) as
    /usr/bin/python3 -m unittest -v test_shape_pairs
from tests/python with PYTHONPATH=<build>/python.
"""

import math
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


class SolidShapesTest(unittest.TestCase):
    """Cylinders, turned boxes and moving surfaces (docs/numerics.md, "Cylinders", "Moving
    surfaces") from Python: a box turned about z rides a conveyor belt at its speed, and a
    cylinder lying on a plane rests on its two deepest rim points."""

    def test_turned_box_rides_the_belt_and_a_cylinder_lies_on_two_rim_points(self):
        gap = 1e-4 - math.sqrt(2 * 1e-4 * 9.81 / 4 / 1e6)
        b = sf.ModelBuilder()
        frame = np.eye(4)
        frame[2, 3] = 0.05 + gap
        node = b.add_node(frame, "crate")
        b.add_rigid_body("crate", node, 1.0, [0, 0, 0], 0.002 * np.eye(3))
        c, s = math.cos(0.4), math.sin(0.4)
        turn = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
        box = sf.ContactShape(0, sf.ContactShapeType.BOX, [0, 0, 0], [0.05, 0.04, 0.05],
                              rotation=turn)
        self.assertTrue(np.allclose(box.rotation, turn, atol=1e-15))
        b.add_contact_shape(box)
        belt = sf.ContactObstacle()
        belt.name = "belt"
        belt.type = sf.ObstacleType.PLANE
        belt.velocity = [0.5, 0, 0]
        belt.motion = sf.Profile.ramp(0.0, 0.1)
        b.add_obstacle(belt)
        law = sf.ContactSettings()
        law.stiffness = 1e6
        law.onset = 1e-4
        law.friction = 0.3
        law.static_friction = 0.4
        b.set_contact_settings(law)
        b.set_gravity([0, 0, -9.81])
        sim = sf.Simulation(sf.Scene(b.build(), "belt"))
        sim.initialize()
        for _ in range(500):
            sim.step(1e-3)
        # Its speed is the belt's (body-frame components: it may turn a little about z).
        self.assertAlmostEqual(math.hypot(sim.v[0], sim.v[1]), 0.5, delta=1e-9)
        self.assertAlmostEqual(sim.v[2], 0.0, delta=1e-9)
        # A cylinder (radius 0.05) lying along y: its two deepest rim points carry it.
        b = sf.ModelBuilder()
        frame = np.eye(4)
        frame[2, 3] = 0.05 + 1e-4 - math.sqrt(2 * 1e-4 * 9.81 / 2 / 1e6)
        node = b.add_node(frame, "can")
        b.add_rigid_body("can", node, 1.0, [0, 0, 0], 0.002 * np.eye(3))
        b.add_contact_shape(sf.ContactShape(0, sf.ContactShapeType.CYLINDER, [0, -0.1, 0],
                                            [0, 0.1, 0], radius=0.05))
        ground = sf.ContactObstacle()
        ground.name = "ground"
        b.add_obstacle(ground)
        b.set_contact_settings(law)
        b.set_gravity([0, 0, -9.81])
        sim = sf.Simulation(sf.Scene(b.build(), "can"))
        sim.initialize()
        for _ in range(100):
            sim.step(1e-3)
        contacts = sim.contact_states()
        self.assertEqual(len(contacts), 2)
        for contact in contacts:
            self.assertAlmostEqual(contact["normal_force"], 9.81 / 2, places=6)


if __name__ == "__main__":
    unittest.main()
