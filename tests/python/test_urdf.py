"""URDF robots from Python (SceneSpec.add_urdf; docs/urdf.md).

The example arm added in code with its drives runs exactly as the same arm under a scene
file's ``robots:`` (the files of the two runs are equal byte for byte); a soft finger attaches
to a link by its name; bad URDF files and options raise InputError naming the element and the
field, and leave the spec unchanged.

    cd tests/python && PYTHONPATH=<build>/python /usr/bin/python3 -m unittest -v test_urdf
"""

import pathlib
import tempfile
import unittest

import screwfem as sf
from test_recording import read_files  # a run folder's files

ROOT = pathlib.Path(__file__).resolve().parents[2]
ARM = ROOT / "examples" / "urdf" / "arm.urdf"

SCENE = f"""
name: urdf arm
gravity: [0, 0, -9.81]
inputs: {{u: 0.1}}
robots:
  arm:
    urdf: {ARM}
    base: {{at: [0.5, 0, 0], orientation: {{axis: [0, 0, 1], angle: pi/2}}}}
    joints:
      waist: {{drive: {{type: prescribed, profile: {{type: ramp, t1: 0.05, value: 0.4}}}}}}
      elbow: {{stiffness: 40, drive: {{type: series_elastic, profile: {{type: input, name: u}}}}}}
sections:
  finger: {{stiffness: [1000, 300, 300, 1.5e-3, 2e-3, 2e-3], inertia: [0.22, 0.22, 0.22, 7e-6, 3.5e-6, 3.5e-6]}}
bodies:
  finger: {{type: soft, from: [0.5, 0.90625, 0.1875], to: [0.5, 0.90625, 0.1075], section: finger,
           elements: 4, up: [1, 0, 0]}}
joints:
  mount: {{type: fixed, at: [0.5, 0.90625, 0.1875], between: [arm/flange, finger]}}
analysis: {{type: dynamic, end_time: 0.08, step: 2e-3}}
outputs:
  interval: 0.01
  vtk: false
  points:
    tip: {{body: finger, at: [0.5, 0.90625, 0.1075]}}
    flange: {{body: arm/flange, at: [0.5, 0.9375, 0.25]}}
"""


def build_in_code():
    spec = sf.SceneSpec(name="urdf arm", gravity=(0, 0, -9.81))
    spec.add_input("u", 0.1)
    added = spec.add_urdf(
        "arm", ARM, at=(0.5, 0, 0), orientation={"axis": [0, 0, 1], "angle": 3.141592653589793 / 2},
        joints={"waist": {"drive": {"type": "prescribed", "profile": sf.Profile.ramp(0, 0.05, 0.4)}},
                "elbow": {"stiffness": 40,
                          "drive": {"type": "series_elastic", "profile": spec.input("u")}}})
    assert [j.joint.name for j in added] == ["arm/waist", "arm/shoulder", "arm/elbow", "arm/wrist"]
    section = sf.Section([1000, 300, 300, 1.5e-3, 2e-3, 2e-3],
                         [0.22, 0.22, 0.22, 7e-6, 3.5e-6, 3.5e-6])
    spec.add_soft_body("finger", from_=(0.5, 0.90625, 0.1875), to=(0.5, 0.90625, 0.1075),
                       section=section, elements=4, up=(1, 0, 0))
    spec.add_joint("mount", "fixed", at=(0.5, 0.90625, 0.1875), between=("arm/flange", "finger"))
    spec.set_analysis(type="dynamic", end_time=0.08, step=2e-3)
    spec.add_output_point("tip", body="finger", at=(0.5, 0.90625, 0.1075))
    spec.add_output_point("flange", body="arm/flange", at=(0.5, 0.9375, 0.25))
    spec.set_outputs(interval=0.01, vtk=False)
    return spec


class UrdfTest(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.dir = pathlib.Path(self.tmp.name)

    def tearDown(self):
        self.tmp.cleanup()

    def test_the_arm_in_code_runs_as_the_scene_file(self):
        from_file = sf.read_scene_spec(SCENE, source_name="arm.yaml")
        in_code = build_in_code()
        self.assertEqual([b.name for b in in_code.bodies], [b.name for b in from_file.bodies])
        self.assertEqual(in_code.bodies[2].name, "arm/upper_arm")
        # The base turned by 90 degrees about z: the upper arm points along world y.
        self.assertAlmostEqual(in_code.bodies[2].com[1], 0.25, places=15)
        sf.run_scene(from_file.compile("arm.yaml"), str(self.dir / "file"))
        sf.run_scene(in_code.compile(), str(self.dir / "code"))
        a = read_files(self.dir / "file", without_source=True)
        b = read_files(self.dir / "code", without_source=True)
        for name in ("points.csv", "joints.csv", "reactions.csv", "energy.csv"):
            self.assertEqual(a[name], b[name], name)
        # The waist turned by its ramp's 0.4 rad (joints.csv: arm/waist.q at the end).
        header, last = a["joints.csv"].decode().splitlines()[0], a["joints.csv"].decode().splitlines()[-1]
        column = header.split(",").index("arm/waist.q")
        self.assertAlmostEqual(float(last.split(",")[column]), 0.4, places=9)

    def test_errors_name_the_element_and_leave_the_spec_unchanged(self):
        bad = self.dir / "bad.urdf"
        bad.write_text('<robot name="r">\n  <link name="a"/>\n</robot>\n')
        spec = sf.SceneSpec()
        with self.assertRaises(sf.InputError) as e:
            spec.add_urdf("r", bad)
        self.assertEqual(str(e.exception),
                         f"<python spec>: robots.r.urdf: {bad}:2:3: link 'a': no <inertial> "
                         "(every link is a rigid body and needs its mass and inertia)")
        self.assertEqual(len(spec.bodies), 0)
        with self.assertRaises(sf.InputError) as e:
            spec.add_urdf("arm", ARM, joints={"elbo": {"damping": 1}})
        self.assertIn("robots.arm.joints.elbo: the URDF has no joint 'elbo'", str(e.exception))
        with self.assertRaises(sf.InputError) as e:
            spec.add_urdf("arm", ARM, orientation={"quaternion": [1, 0, 0, 1]})
        self.assertIn("robots.arm.base.orientation.quaternion: expected a unit quaternion",
                      str(e.exception))
        self.assertEqual((len(spec.bodies), len(spec.joints)), (0, 0))
        spec.add_urdf("arm", ARM)
        with self.assertRaises(sf.InputError) as e:
            spec.add_urdf("arm", ARM)
        self.assertIn("the spec already has a body 'arm/base'", str(e.exception))
        self.assertEqual((len(spec.bodies), len(spec.joints)), (5, 4))


if __name__ == "__main__":
    unittest.main()
