"""Mesh and height-field obstacles from Python (docs/numerics.md, "Triangle meshes"): a ball
resting on a mesh box presses with its weight, a height field takes numpy heights, and the mass
properties of a closed mesh are the closed form of a box."""
import math
import unittest

import numpy as np

import screwfem as sf


def box_mesh(h):
    v = np.array([[(h[0] if k & 1 else -h[0]), (h[1] if k & 2 else -h[1]),
                   (h[2] if k & 4 else -h[2])] for k in range(8)])
    quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]]
    f = [[q[0], q[1], q[2]] for q in quads] + [[q[0], q[2], q[3]] for q in quads]
    return v, np.array(f, dtype=np.int32)


class MeshObstacleTest(unittest.TestCase):
    def test_mesh_mass_properties_of_a_box(self):
        v, f = box_mesh([0.3, 0.2, 0.1])
        mass, com, inertia = sf.mesh_mass_properties(v + [1.0, 2.0, 3.0], f, 1000.0)
        assert abs(mass - 1000.0 * 0.6 * 0.4 * 0.2) < 1e-10
        assert np.allclose(com, [1.0, 2.0, 3.0], atol=1e-14)
        assert abs(inertia[2, 2] - mass * (0.6**2 + 0.4**2) / 12) < 1e-12


    def test_ball_on_a_mesh_box_rests_at_the_planes_equilibrium_gap(self):
        # docs/numerics.md T6.1: gap g* = delta - sqrt(2 delta m g / k), as on a plane.
        b = sf.ModelBuilder()
        gap = 1e-4 - math.sqrt(2 * 1e-4 * 9.81 / 1e6)
        frame = np.eye(4)
        frame[2, 3] = 0.1 + gap
        node = b.add_node(frame, "ball")
        b.add_rigid_body("ball", node, 1.0, [0, 0, 0], 0.004 * np.eye(3))
        b.add_contact_shape(sf.ContactShape(0, sf.ContactShapeType.SPHERE, [0, 0, 0], radius=0.1))
        block = sf.ContactObstacle()
        block.name = "block"
        block.type = sf.ObstacleType.MESH
        block.point = [0.0, 0.0, -0.1]
        v, f = box_mesh([0.5, 0.5, 0.1])
        block.set_mesh(v, f)
        assert block.mesh_faces().shape == (12, 3)
        b.add_obstacle(block)
        hill = sf.ContactObstacle()
        hill.name = "hill"
        hill.type = sf.ObstacleType.HEIGHTFIELD
        hill.point = [5.0, 0.0, 0.0]
        hill.set_heights(np.zeros((3, 4)), 0.5, 0.5)
        assert hill.mesh_faces().shape == (12, 3)
        b.add_obstacle(hill)
        law = sf.ContactSettings()
        law.stiffness = 1e6
        law.onset = 1e-4
        law.friction = 0.3
        b.set_contact_settings(law)
        b.set_gravity([0, 0, -9.81])
        sim = sf.Simulation(sf.Scene(b.build(), "mesh"))
        sim.initialize()
        for _ in range(50):
            sim.step(1e-3)
        contacts = [c for c in sim.contact_states() if c["normal_force"] > 0]
        assert len(contacts) == 1
        assert abs(contacts[0]["normal_force"] - 9.81) < 1e-6
        assert abs(contacts[0]["gap"] - gap) < 1e-10
        bad = sf.ContactObstacle()
        bad.name = "bad"
        try:
            bad.set_mesh(v, np.array([[0, 1, 99]], dtype=np.int32))
        except sf.InputError as e:
            assert "face 0 refers to vertex 99" in str(e)
        else:
            raise AssertionError("no error")


if __name__ == "__main__":
    unittest.main()
