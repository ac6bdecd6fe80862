"""The scene spec from Python (screwfem.SceneSpec, python/screwfem/_spec.py).

A scene built in code and the same scene read from its file are the same kind of object and go
through the same compiler (CompileScene): their runs write the same files, byte for byte. The
GRM of the method paper (examples/grm) is written here with the spec API only; a read spec
edited in Python equals the file with the equivalent override; tendon routes; bad values raise
InputError naming the entity and the field.

    cd tests/python && PYTHONPATH=<build>/python /usr/bin/python3 -m unittest -v test_spec
"""

import math
import pathlib
import sys
import tempfile
import unittest

import screwfem as sf
from screwfem import _screwfem

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[2] / "examples" / "python"))
import grm_in_code  # noqa: E402  (the GRM built in code)
from test_recording import read_files  # noqa: E402  (a run folder's files)

ROOT = pathlib.Path(__file__).resolve().parents[2]
GRM = ROOT / "examples" / "grm"
ARM = ROOT / "examples" / "python" / "soft_arm_control.yaml"
TABLES = ("points.csv", "joints.csv", "reactions.csv", "energy.csv", "joints.json")


def grm_spec(case):
    """examples/grm/grm_{case}.yaml with the spec API, as examples/python/grm_in_code.py
    builds it ('soft_k' or 'rigid'): the test checks the example's construction."""
    return grm_in_code.build_grm(case)


def run_files(scene, folder):
    """Runs a scene into `folder`; returns its files (summary.json without the source and the
    clock), and the result."""
    result = sf.run_scene(scene, str(folder))
    return read_files(folder, without_source=True), result


class SpecTestCase(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.dir = pathlib.Path(self.tmp.name)

    def tearDown(self):
        self.tmp.cleanup()

    def assertSameRuns(self, code_scene, file_scene, steps):
        code, rc = run_files(code_scene, self.dir / "code")
        file, rf = run_files(file_scene, self.dir / "file")
        self.assertTrue(rc.ok, rc.message)
        self.assertTrue(rf.ok, rf.message)
        if steps is not None:
            self.assertEqual(rc.steps, steps)
        self.assertEqual(rc.steps, rf.steps)
        self.assertEqual(sorted(code), sorted(file))
        for name in code:
            self.assertEqual(code[name], file[name], f"{name} differs")
        return code


class GrmBuiltInCode(SpecTestCase):
    """The GRM written with the spec API writes the tables of its scene file, bit for bit."""

    def check_case(self, case):
        spec = grm_spec(case)
        spec.analysis.end_time = 0.2
        code_scene = spec.compile()
        self.assertEqual(code_scene.source, "<python spec>")
        file_scene = sf.load_scene(str(GRM / f"grm_{case}.yaml"), ["analysis.end_time=0.2"])
        files = self.assertSameRuns(code_scene, file_scene, steps=200)
        for table in TABLES:
            self.assertIn(table, files)
        self.assertEqual(len(files["points.csv"].splitlines()), 202)  # header, t = 0 ... 0.2
        self.assertTrue(any(name.startswith("vtk/") for name in files))
        # Not the model at rest: the drives have moved the tip.
        last = files["points.csv"].splitlines()[-1].split(b",")
        self.assertGreater(abs(float(last[1]) - 1.4), 1e-3)

    def test_soft_joints_k10(self):
        self.check_case("soft_k")

    def test_rigid_joints(self):
        self.check_case("rigid")

    def test_the_spec_reads_as_the_file_does(self):
        code, file = grm_spec("soft_k"), sf.read_scene_spec(GRM / "grm_soft_k.yaml")
        self.assertEqual([b.name for b in code.bodies], [b.name for b in file.bodies])
        self.assertEqual([b.rigid for b in code.bodies], [b.rigid for b in file.bodies])
        for a, b in zip(code.bodies, file.bodies):
            self.assertEqual(a.origin, b.origin)
            self.assertEqual(a.com, b.com)
            self.assertEqual(a.path, b.path)
            self.assertEqual(a.weld_start, b.weld_start)
        for a, b in zip(code.joints, file.joints):
            self.assertEqual((a.name, a.body_a, a.body_b), (b.name, b.body_a, b.body_b))
            self.assertEqual(list(a.joint.axis), list(b.joint.axis))
            self.assertEqual(list(a.joint.stiffness), list(b.joint.stiffness))
        self.assertEqual(code.points, file.points)
        self.assertEqual([(l.name, l.body, l.where, l.at, l.force) for l in code.loads],
                         [(l.name, l.body, l.where, l.at, l.force) for l in file.loads])
        self.assertEqual(code.outputs.points, file.outputs.points)


class ReadEditCompile(SpecTestCase):
    """read_scene_spec, an edit in Python, compile: the run of load_scene with the override."""

    def test_edits_equal_overrides(self):
        spec = sf.read_scene_spec(str(GRM / "grm_soft_k.yaml"))
        spec.analysis.end_time = 0.15
        spec.bodies[spec.body_index("arm56")].elements = 4
        # Eigen members of the C++ objects are assigned whole (their arrays are read-only).
        spec.joints[spec.joint_index("J1")].joint.stiffness = [20, 0, 0, 0, 0, 0]
        spec.loads[0].force = (50, -100, 0)
        spec.outputs.vtk = False
        file_scene = sf.load_scene(str(GRM / "grm_soft_k.yaml"), [
            "analysis.end_time=0.15", "bodies.arm56.elements=4", "joints.J1.stiffness=20",
            "loads.f1.force=[50, -100, 0]", "outputs.vtk=false"])
        self.assertSameRuns(spec.compile(), file_scene, steps=150)

    def test_defaults_follow_the_edits(self):
        # The defaults a file leaves out (about 1000 rows, every joint with coordinates, the
        # time of statics) follow the edits as they follow overrides: the compiler resolves
        # them.
        text = (ROOT / "tests" / "data" / "slider_crank.yaml").read_text()
        spec = sf.read_scene_spec(text, source_name="slider_crank.yaml")
        self.assertLess(spec.outputs.interval, 0)  # the default, not yet a number
        self.assertTrue(spec.outputs.all_joints)
        spec.set_analysis(type="dynamic", end_time=4)
        spec.add_rigid_body("bob", at="C", mass=0.1, inertia=[1e-4] * 3)
        spec.add_joint("tip", "revolute", at="C", between=("slider", "bob"), axis=[0, 0, 1])
        scene = spec.compile()
        file_scene = sf.parse_scene(text, "slider_crank.yaml", [
            "analysis.type=dynamic", "analysis.end_time=4",
            "bodies.bob={type: rigid, at: C, mass: 0.1, inertia: [1e-4, 1e-4, 1e-4]}",
            "joints.tip={type: revolute, at: C, between: [slider, bob], axis: [0, 0, 1]}"])
        self.assertEqual(scene.outputs.interval, 4e-3)
        self.assertEqual(scene.outputs.interval, file_scene.outputs.interval)
        self.assertEqual(scene.outputs.vtk_interval, file_scene.outputs.vtk_interval)
        self.assertEqual([j.name for j in scene.outputs.joints],
                         ["pivot", "elbow", "wrist", "guide", "tip"])
        self.assertEqual([j.name for j in scene.outputs.joints],
                         [j.name for j in file_scene.outputs.joints])
        spec.set_analysis(type="static", end_time=0.5)
        self.assertEqual(spec.compile().analysis.statics.time, 0.5)
        self.assertEqual(scene.analysis.statics.time, 0.0)

    def test_copy_is_deep(self):
        spec = sf.read_scene_spec(GRM / "grm_rigid.yaml", ["analysis.end_time=0.1"])
        copy = spec.copy()
        copy.bodies[1].mass = 0.3
        copy.joints[0].joint.drive_profile = sf.Profile.constant(0.0)
        self.assertEqual(spec.bodies[1].mass, 0.15)
        self.assertEqual(spec.joints[0].joint.drive_profile(2.0), math.pi / 6)
        self.assertEqual(len(copy.compile().model.joints), 9)

    def test_errors_of_the_file_name_the_line(self):
        with self.assertRaisesRegex(ValueError, r"^arm\.yaml:\d+:\d+: bodies\.arm\.section: "
                                    "undefined section 'nope'"):
            sf.read_scene_spec(ARM.read_text().replace("section: arm}", "section: nope}"),
                               source_name="arm.yaml")
        with self.assertRaisesRegex(ValueError, "cannot open the scene file"):
            sf.read_scene_spec(str(self.dir / "missing.yaml"))


class EveryScene(SpecTestCase):
    """Every scene file of the repository, read into a SceneSpec, converted to Python objects
    and back (copy) and compiled, runs as load_scene runs it: the conversions keep every field
    the scenes use (contact, shapes, actuation, force elements, inputs, step: auto, ...)."""

    def test_round_trip_through_python(self):
        paths = sorted(ROOT.glob("examples/*/*.yaml")) + sorted(ROOT.glob("tests/data/*.yaml"))
        self.assertGreater(len(paths), 10)
        for i, path in enumerate(paths):
            with self.subTest(scene=str(path.relative_to(ROOT))):
                a = sf.read_scene_spec(path).analysis
                # A few steps (static analyses: as they are).
                overrides = [] if a.kind == sf.AnalysisKind.STATIC else [
                    f"analysis.end_time={a.start_time + 5 * a.step!r}"]
                spec = sf.read_scene_spec(path, overrides).copy()
                code, rc = run_files(spec.compile(), self.dir / f"{i}_code")
                file, rf = run_files(sf.load_scene(str(path), overrides), self.dir / f"{i}_file")
                self.assertEqual((rc.ok, rc.steps), (rf.ok, rf.steps))
                self.assertEqual(sorted(code), sorted(file))
                for name in code:
                    self.assertEqual(code[name], file[name], f"{name} differs")


class Tendons(SpecTestCase):
    S = [0.0, 0.0375, 0.075, 0.1125, 0.15, 0.1875, 0.225, 0.2625, 0.3]

    def arm_spec(self):
        """examples/python/soft_arm_control.yaml in code."""
        spec = sf.SceneSpec(name="soft arm tip-height control", gravity=(0, 0, -9.81))
        spec.add_input("u", 0.0)
        spec.add_point("BASE", [0, 0, 0])
        spec.add_point("TIP", [0.3, 0, 0])
        silicone = sf.Material(E=1e7, nu=0.45, density=1100)
        section = sf.Section.circle(0.01, silicone, rayleigh_stiffness=2e-3)
        arm = spec.add_soft_body("arm", from_="BASE", to="TIP", section=section, elements=8)
        self.assertEqual(arm.contact_radius, 0.01)
        spec.add_joint("clamp", "fixed", at="BASE", between=("ground", "arm"))
        spec.add_tendon("lifter", eyelets=sf.route_offset(arm, self.S, (0, 0, 0.009)),
                        tension=spec.input("u"))
        spec.set_analysis(type="dynamic", end_time=2, step=2e-3, rho_inf=0.6)
        spec.add_output_point("tip", body="arm", at="TIP")
        spec.set_outputs(interval=0.01, vtk=True, vtk_interval=0.02)
        return spec

    def test_offset_route_equals_the_file(self):
        spec = self.arm_spec()
        spec.analysis.end_time = 0.2
        spec.inputs["u"] = 1.5  # pulling: the arm curls up
        file_scene = sf.load_scene(str(ARM), ["analysis.end_time=0.2", "inputs.u=1.5"])
        files = self.assertSameRuns(spec.compile(), file_scene, steps=100)
        self.assertIn("tendons.csv", files)

    def test_helical_route(self):
        spec = self.arm_spec()
        arm = spec.bodies[0]
        s = [0.3 * i / 16 for i in range(17)]
        route = sf.route_helical(arm, s, radius=0.008, turns=1.5, phase=0.25)
        self.assertEqual(len(route), 17)
        for eyelet, si in zip(route, s):
            t = 0.25 + 2 * math.pi * 1.5 * si / 0.3
            self.assertEqual(eyelet["s"], si)
            self.assertEqual(eyelet["offset"], (0.0, 0.008 * math.cos(t), 0.008 * math.sin(t)))
        self.assertAlmostEqual(math.hypot(*route[5]["offset"]), 0.008, places=15)
        # Between nodes too (16 eyelets on 8 elements): the tendon compiles and runs.
        tendon = spec.add_tendon("spiral", eyelets=route, tension=sf.Profile.ramp(0, 0.05, 0.5))
        self.assertEqual([p.offset for p in tendon.eyelets], [e["offset"] for e in route])
        self.assertTrue(all(p.along_rod for p in tendon.eyelets))
        spec.analysis.end_time = 0.05
        self.assertEqual(spec.compile().model.num_tendons, 2)
        self.assertTrue(sf.run_scene(spec.compile(), str(self.dir / "spiral")).ok)
        # A length instead of the BodySpec's path.
        self.assertEqual(sf.route_helical("arm", s, 0.008, 1.5, 0.25, length=0.3), route)

    def test_conform_mesh(self):
        """SceneSpec.conform_mesh (defaults.conform_mesh): an eyelet between nodes becomes a node
        unless it is off (docs/numerics.md, 'Conforming rod meshes')."""
        spec = self.arm_spec()
        spec.add_tendon("short", eyelets=[{"body": "arm", "s": 0.0, "offset": (0, 0.009, 0)},
                                          {"body": "arm", "s": 0.1, "offset": (0, 0.009, 0)}],
                        tension=1.0)
        self.assertTrue(spec.conform_mesh)
        model = spec.compile().model
        self.assertEqual(model.conformed_nodes, 1)  # s = 0.1 lies inside element 2 (0.075, 0.1125)
        self.assertEqual(model.rods[0].num_elements, 9)
        spec.conform_mesh = False
        model = spec.compile().model
        self.assertEqual(model.conformed_nodes, 0)
        self.assertEqual(model.rods[0].num_elements, 8)
        self.assertGreaterEqual(model.tendons[1].eyelets[1].element, 0)
        self.assertFalse(sf.read_scene_spec(str(ARM), ["defaults.conform_mesh=false"]).conform_mesh)

    def test_route_rule_equals_the_long_form_file_and_builder(self):
        """The scene's route item ({'route': {...}}, docs/scene-format.md 'Routing helpers')
        from Python gives the eyelets of the long form, of the same route in a YAML file and of
        route_along_rod on a ModelBuilder, bit for bit."""
        def eyelets(scene):
            model = scene.model
            return [(p.node, tuple(p.offset)) for p in model.tendons[0].eyelets]

        long_form = self.arm_spec()
        rule = self.arm_spec()
        rule.tendons.clear()
        t = rule.add_tendon("lifter", eyelets=[{"route": {"body": "arm", "offset": (0, 0, 0.009)}}],
                            tension=rule.input("u"))
        self.assertTrue(t.eyelets[0].routed)
        self.assertEqual(t.eyelets[0].route.every, 1)
        self.assertEqual(eyelets(rule.compile()), eyelets(long_form.compile()))
        self.assertEqual(len(eyelets(rule.compile())), 9)
        # The same route in the file.
        file_scene = sf.load_scene(str(ARM), [
            "tendons.lifter.eyelets=[{route: {body: arm, offset: [0, 0, 0.009]}}]"])
        self.assertEqual(eyelets(file_scene), eyelets(long_form.compile()))
        # A helical rule, every 2nd node from 0.075 m: the builder function on the same rod.
        helix = {"route": {"body": "arm", "every": 2, "from": 0.075,
                           "helix": {"radius": 0.008, "pitch": 0.2, "phase": 0.25}}}
        rule.tendons.clear()
        rule.add_tendon("lifter", eyelets=[helix], tension=1.0)
        b = sf.ModelBuilder()
        rod = b.add_straight_rod("arm", (0, 0, 0), (0.3, 0, 0), 8,
                                 sf.Section.circle(0.01, sf.Material(E=1e7, nu=0.45,
                                                                     density=1100)))
        route = sf.RodRoute(rod=rod, every=2, from_=0.075, helix_radius=0.008, helix_pitch=0.2,
                            helix_phase=0.25)
        points = sf.route_along_rod(b, route)
        arcs = sf.rod_node_arc_lengths(b, rod)
        self.assertEqual([round(a, 12) for a in arcs], [round(0.0375 * i, 12) for i in range(9)])
        compiled = eyelets(rule.compile())
        self.assertEqual([o for _, o in compiled], [tuple(p.offset) for p in points])
        self.assertEqual(len(points), 4)  # nodes 2, 4, 6, 8
        for (_, offset), i in zip(compiled, (2, 4, 6, 8)):
            a = 0.25 + 2 * math.pi * (arcs[i] - 0.075) / 0.2
            self.assertAlmostEqual(offset[1], 0.008 * math.cos(a), places=15)
            self.assertAlmostEqual(offset[2], 0.008 * math.sin(a), places=15)
        # Bad rules name the field.
        with self.assertRaisesRegex(sf.InputError, r"tendons.t.eyelets\[0\].route.every"):
            rule.add_tendon("t", eyelets=[{"route": {"body": "arm", "every": 0}}], tension=1)
        with self.assertRaisesRegex(sf.InputError, "route along 'arm': no node lies from 0.1 m to 0.11 m"):
            rule.tendons.clear()
            rule.add_tendon("t", eyelets=[{"route": {"body": "arm", "from": 0.1, "to": 0.11}}],
                            tension=1)
            rule.compile()


# A scene using the adders the GRM does not: sections by shape, contact (shapes, an obstacle,
# exclusions), force elements, actuation, inputs, step: auto, rod output points, listed joints.
MIXED = """
name: mixed
gravity: [0, 0, -9.81]
inputs: {p: 2e4}
materials:
  rubber: {E: 2e6, nu: 0.45, density: 1100}
sections:
  band: {shape: rectangle, width: 0.02, height: 0.01, material: rubber, rayleigh_mass: 0.5}
  hose: {shape: tube, outer_radius: 0.01, inner_radius: 0.006, material: rubber,
         damping: [0, 0, 0, 1e-4, 1e-4, 1e-4]}
bodies:
  base: {type: rigid, at: [0, 0, 0.3], mass: 0.5, inertia: [1e-3, 1e-3, 1e-3],
         shapes: [{type: sphere, center: [0, 0, 0.3], radius: 0.02}]}
  finger: {type: soft, path: [[0, 0, 0.3], [0.1, 0, 0.3], [0.15, 0, 0.25]], section: hose,
           elements: 4}
  strap: {type: soft, from: [0.0, 0.1, 0.3], to: [0.1, 0.1, 0.3], section: band, elements: 2,
          up: [0, 1, 0]}
  ball: {type: rigid, at: [0.3, 0, 0.1], mass: 0.05, inertia: [2e-6, 2e-6, 2e-6], free: true,
         initial_velocity: {linear: [0, 0, -0.5]},
         shapes: [{type: capsule, from: [0.29, 0, 0.1], to: [0.31, 0, 0.1], radius: 0.01}]}
joints:
  lift: {type: prismatic, at: [0, 0, 0.3], between: [ground, base], axis: [0, 0, 1],
         stiffness: 100, damping: 1, initial_velocity: 0.1}
  root: {type: fixed, at: [0, 0, 0.3], between: [base, finger]}
  clamp: {type: fixed, at: [0.0, 0.1, 0.3], between: [ground, strap]}
forces:
  brace: {a: {body: finger, s: 0.025, offset: [0, 0.005, 0]}, b: {body: strap, at: [0.1, 0.1, 0.3]},
          stiffness: 50, damping: 0.1, force: {type: ramp, t1: 0.01, value: 0.2}}
  tether: {a: {at: [0.3, 0, 0.3]}, b: {body: ball, at: [0.3, 0, 0.1]}, stiffness: 20}
actuation:
  chamber: {type: pressure, rod: finger, area: 3e-5, offset: [0, -0.004],
            pressure: {type: input, name: p, value: 1.5}}
  curl: {type: rest_strain, rod: strap, from: 0.05, vector: [0, 0, 0, 0, 0, 2],
         profile: {sum: [{type: ramp, t1: 0.02, value: 0.5}, 0.1]}}
contact:
  friction: 0.2
  obstacles:
    floor: {type: plane, point: [0, 0, 0], normal: [0, 0, 1]}
  exclude: [[base, floor], [finger, strap]]
analysis: {type: dynamic, end_time: 0.02, step: auto, tolerance: 1e-5, max_step: 5e-3}
outputs:
  points:
    tip: {rod: finger, s: 0.15}
    ball: {body: ball, at: [0.3, 0, 0.1]}
  joints: [lift]
  interval: 0.002
  vtk: false
"""


class EveryAdder(SpecTestCase):
    def test_mixed_scene_equals_its_text(self):
        spec = sf.SceneSpec(name="mixed", gravity=(0, 0, -9.81))
        spec.add_input("p", 2e4)
        rubber = sf.Material(E=2e6, nu=0.45, density=1100)
        band = sf.Section.rectangle(0.02, 0.01, rubber, rayleigh_mass=0.5)
        hose = sf.Section.tube(0.01, 0.006, rubber, damping=[0, 0, 0, 1e-4, 1e-4, 1e-4])
        spec.add_rigid_body("base", at=[0, 0, 0.3], mass=0.5, inertia=[1e-3] * 3,
                            shapes=[{"type": "sphere", "center": [0, 0, 0.3], "radius": 0.02}])
        finger = spec.add_soft_body("finger", path=[[0, 0, 0.3], [0.1, 0, 0.3], [0.15, 0, 0.25]],
                                    section=hose, elements=4)
        self.assertEqual(finger.contact_radius, 0.01)
        strap = spec.add_soft_body("strap", from_=[0.0, 0.1, 0.3], to=[0.1, 0.1, 0.3],
                                   section=band, elements=2, up=[0, 1, 0])
        self.assertEqual(strap.contact_radius, 0.005)
        spec.add_rigid_body("ball", at=[0.3, 0, 0.1], mass=0.05, inertia=[2e-6] * 3, free=True,
                            initial_velocity={"linear": [0, 0, -0.5]},
                            shapes=[{"type": "capsule", "from": [0.29, 0, 0.1],
                                     "to": [0.31, 0, 0.1], "radius": 0.01}])
        spec.add_joint("lift", "prismatic", at=[0, 0, 0.3], between=("ground", "base"),
                       axis=[0, 0, 1], stiffness=100, damping=1, initial_velocity=0.1)
        spec.add_joint("root", "fixed", at=[0, 0, 0.3], between=("base", "finger"))
        spec.add_joint("clamp", "fixed", at=[0.0, 0.1, 0.3], between=("ground", "strap"))
        spec.add_force("brace", a={"body": "finger", "s": 0.025, "offset": [0, 0.005, 0]},
                       b={"body": "strap", "at": [0.1, 0.1, 0.3]}, stiffness=50, damping=0.1,
                       force=sf.Profile.ramp(0, 0.01, 0.2))
        spec.add_force("tether", a={"at": [0.3, 0, 0.3]}, b={"body": "ball", "at": [0.3, 0, 0.1]},
                       stiffness=20)
        spec.add_actuator("chamber", type="pressure", rod="finger", area=3e-5,
                          offset=[0, -0.004], pressure=spec.input("p", 1.5))
        spec.add_actuator("curl", type="rest_strain", rod="strap", from_=0.05,
                          vector=[0, 0, 0, 0, 0, 2], profile=sf.Profile.ramp(0, 0.02, 0.5) + 0.1)
        spec.set_contact(friction=0.2)
        spec.add_obstacle("floor", "plane", point=[0, 0, 0], normal=[0, 0, 1])
        spec.exclude_contact("base", "floor")
        spec.exclude_contact("finger", "strap")
        spec.set_analysis(type="dynamic", end_time=0.02, step="auto", tolerance=1e-5,
                          max_step=5e-3)
        spec.add_output_point("tip", body="finger", s=0.15)
        spec.add_output_point("ball", body="ball", at=[0.3, 0, 0.1])
        spec.set_outputs(joints=["lift"], interval=0.002, vtk=False)
        file_scene = sf.parse_scene(MIXED, "mixed.yaml")
        files = self.assertSameRuns(spec.compile(), file_scene, steps=None)
        for table in ("forces.csv", "actuators.csv", "contacts.csv", "pair_contacts.csv"):
            self.assertIn(table, files)


class BadInput(unittest.TestCase):
    """Bad values raise InputError (a ValueError) naming the entity and the field; the spec is
    left as it was."""

    def setUp(self):
        self.spec = sf.SceneSpec()
        self.spec.add_rigid_body("crank", at=[0, 0, 0], mass=1, inertia=[1, 1, 1])
        self.spec.add_soft_body("arm", path=[[0, 0, 0], [1, 0, 0]],
                                section=sf.Section([1] * 6, [1] * 6), elements=2)

    def assertError(self, pattern, call, *args, **kwargs):
        n = {k: len(getattr(self.spec, k)) for k in ("bodies", "joints", "loads", "tendons")}
        with self.assertRaisesRegex(ValueError, pattern) as e:
            call(*args, **kwargs)
        self.assertIsInstance(e.exception, sf.InputError)
        self.assertEqual(n, {k: len(getattr(self.spec, k)) for k in n})
        return str(e.exception)

    def test_unknown_body(self):
        self.assertError(r"^<python spec>: joints\.J1\.between\[1\]: undefined body 'arn' "
                         r"\(known: crank, arm\)", self.spec.add_joint, "J1", "revolute",
                         between=("crank", "arn"), at=[0, 0, 0], axis=[0, 0, 1])
        self.assertError(r"loads\.push\.body: undefined body 'nope'", self.spec.add_load,
                         "push", body="nope", at=[0, 0, 0], force=[1, 0, 0])
        self.assertError(r"undefined point 'P9'", self.spec.add_output_point, "tip",
                         body="arm", at="P9")

    def test_wrong_length_vector(self):
        self.assertError(r"loads\.push\.force: expected \[x, y, z\] \(3 numbers\), got 2",
                         self.spec.add_load, "push", body="arm", at=[1, 0, 0], force=[1, 2])
        self.assertError(r"bodies\.rod\.path\[1\]: expected \[x, y, z\] \(3 numbers\), got 4",
                         self.spec.add_soft_body, "rod", path=[[0, 0, 0], [1, 0, 0, 0]],
                         section=sf.Section([1] * 6))
        self.assertError(r"joints\.J1\.stiffness: expected one value per coordinate \(1 "
                         r"numbers\), got 2", self.spec.add_joint, "J1", "revolute",
                         between=("ground", "crank"), at=[0, 0, 0], axis=[0, 0, 1],
                         stiffness=[1, 2])

    def test_negative_mass_and_nan(self):
        self.assertError(r"^<python spec>: bodies\.link\.mass: expected a positive number, "
                         "got -1", self.spec.add_rigid_body, "link", at=[1, 0, 0], mass=-1,
                         inertia=[1, 1, 1])
        self.assertError(r"bodies\.link\.at\[0\]: expected a finite number, got nan",
                         self.spec.add_rigid_body, "link", at=[math.nan, 0, 0], mass=1,
                         inertia=[1, 1, 1])
        self.assertError(r"bodies\.link\.inertia: the inertia matrix must be positive definite",
                         self.spec.add_rigid_body, "link", at=[1, 0, 0], mass=1,
                         inertia=[[1, 0, 0], [0, 1, 0], [0, 0, -1]])
        self.assertError(r"bodies\.crank: duplicate body name 'crank'", self.spec.add_rigid_body,
                         "crank", at=[1, 0, 0], mass=1, inertia=[1, 1, 1])

    def test_values_of_the_joint_vocabulary(self):
        self.assertError(r"joints\.J1\.axis: expected a unit vector, got length 2",
                         self.spec.add_joint, "J1", "revolute", between=("ground", "crank"),
                         at=[0, 0, 0], axis=[0, 0, 2])
        self.assertError(r"joints\.W\.axis: 'axis' is not used by fixed joints",
                         self.spec.add_joint, "W", "fixed", between=("ground", "crank"),
                         at=[0, 0, 0], axis=[0, 0, 1])
        self.assertError(r"joints\.J1\.type: expected one of revolute, ", self.spec.add_joint,
                         "J1", "hinge", between=("ground", "crank"), at=[0, 0, 0])
        self.assertError(r"joints\.J1\.drive: a series_elastic drive needs a positive "
                         "stiffness", self.spec.add_joint, "J1", "revolute",
                         between=("ground", "crank"), at=[0, 0, 0], axis=[0, 0, 1],
                         drive={"type": "series_elastic", "profile": 1.0})

    def test_edits_are_checked_by_compile(self):
        self.spec.add_joint("clamp", "fixed", at=[0, 0, 0], between=("ground", "arm"))
        self.spec.add_joint("pin", "revolute", at=[1, 0, 0], between=("arm", "crank"),
                            axis=[0, 0, 1])
        self.spec.compile()
        self.spec.bodies[0].mass = -2.0
        with self.assertRaisesRegex(ValueError, r"bodies\.crank\.mass: expected a positive "
                                    "number, got -2"):
            self.spec.compile()
        self.spec.bodies[0].mass = 1.0
        self.spec.bodies[1].up = (0, 1)
        with self.assertRaisesRegex(ValueError, r"bodies\.arm\.up: expected \[x, y, z\]"):
            self.spec.compile()
        self.spec.bodies[1].up = (0, 0, 1)
        # The compiler's own errors name the entity's field as a scene file would.
        self.spec.joints[1].joint.point = (0.7, 0, 0)
        with self.assertRaisesRegex(ValueError, r"^<python spec>: joints\.pin\.between\[0\]: "
                                    "joint point: soft body 'arm' has no node at"):
            self.spec.compile()


class Defaults(unittest.TestCase):
    """The Python classes default to the C++ structs' defaults."""

    @staticmethod
    def plain(v):
        if isinstance(v, sf.Profile):
            return ("profile", v(0.0), v(0.5), v(2.0))
        if isinstance(v, sf.Section):
            return ("section", tuple(v.stiffness), tuple(v.inertia), tuple(v.damping))
        if isinstance(v, sf.JointSpec):
            return ("joint", v.name, v.type, tuple(v.axis), tuple(v.stiffness), v.drive)
        if isinstance(v, sf.ContactSettings):
            return ("contact", v.stiffness, v.onset, v.friction, v.self)
        if isinstance(v, sf.AnalysisSettings):
            return ("analysis", v.kind, v.end_time, v.step, v.dynamic.rho_inf)
        if isinstance(v, sf.BodyPointSpec):
            return v
        if isinstance(v, (list, tuple)):
            return [Defaults.plain(x) for x in v]
        return v

    def test_python_defaults_are_the_cpp_defaults(self):
        cpp = _screwfem._default_spec()
        python = {"bodies": sf.BodySpec(), "joints": sf.JointEntrySpec(),
                  "loads": sf.LoadSpec(), "tendons": sf.TendonSpec(), "forces": sf.ForceSpec(),
                  "actuators": sf.ActuatorSpec()}
        for key, default in python.items():
            entity = getattr(cpp, key)[0]
            for f in default.__dataclass_fields__:
                self.assertEqual(self.plain(getattr(entity, f)), self.plain(getattr(default, f)),
                                 f"{key}: {f}")
        self.assertEqual(cpp.outputs.points[0], sf.OutputPointSpec())
        empty = sf.SceneSpec()
        for f in ("name", "gravity", "rod_inertia", "conform_mesh", "points", "inputs"):
            self.assertEqual(getattr(cpp, f), getattr(empty, f), f)
        for f in ("all_joints", "joints", "interval", "vtk", "vtk_format", "vtk_interval"):
            self.assertEqual(getattr(cpp.outputs, f), getattr(empty.outputs, f), f)
        self.assertEqual(self.plain(cpp.analysis), self.plain(empty.analysis))
        self.assertEqual(self.plain(cpp.contact.settings), self.plain(empty.contact.settings))


class Settling(unittest.TestCase):
    """analysis.stop_at_rest from the spec (set_analysis) and Simulation.calc_settling: a box
    thrown across a plane slides v0^2 / (2 mu g) and the run ends at rest, settling.csv holding
    what calc_settling gives."""

    def spec(self, **analysis):
        spec = sf.SceneSpec()
        spec.gravity = [0, 0, -9.81]
        spec.add_rigid_body("box", at=[0, 0, 0.10002996], mass=1, inertia=[0.00667] * 3,
                            free=True, initial_velocity={"linear": [2, 0, 0]},
                            shapes=[{"type": "box", "center": [0, 0, 0.10002996],
                                     "half_sizes": [0.1] * 3}])
        spec.set_contact(stiffness=1e5, onset=1e-4, friction=0.3)
        spec.add_obstacle("ground", "plane", point=[0, 0, 0], normal=[0, 0, 1])
        spec.set_analysis(type="dynamic", end_time=5, step=1e-3, **analysis)
        return spec

    def test_stop_at_rest_ends_the_run_at_rest(self):
        spec = self.spec(stop_at_rest={"speed": 1e-3, "hold": 0.1})
        self.assertTrue(spec.analysis.stop_at_rest.enabled)
        self.assertEqual(spec.analysis.stop_at_rest.angular_speed, 1e-2)
        with tempfile.TemporaryDirectory() as d:
            result = sf.run_scene(spec.compile(), d)
            self.assertTrue(result.ok, result.message)
            t_stop = 2 / (0.3 * 9.81)
            self.assertGreater(result.end_time, t_stop + 0.1)
            self.assertLess(result.end_time, t_stop + 0.12)
            self.assertIn("at rest at t = ", result.message)
            rows = pathlib.Path(d, "settling.csv").read_text().splitlines()
            self.assertEqual(rows[0], "t,kinetic,speed,angular_speed,contacts,slipping,"
                                      "overlap,overlap_ratio")
            last = [float(x) for x in rows[-1].split(",")]
            self.assertEqual(last[0], result.end_time)
            self.assertLess(last[2], 1e-3)
            self.assertEqual(last[4:6], [4.0, 0.0])

    def test_calc_settling_while_sliding(self):
        sim = sf.Simulation(self.spec().compile())
        sim.initialize()
        sim.advance_to(0.3)
        s = sim.calc_settling()
        # Sliding at v0 - mu g t on its four bottom corners, every one slipping.
        self.assertAlmostEqual(s.speed, 2 - 0.3 * 9.81 * 0.3, delta=0.02)
        self.assertEqual((s.contacts, s.slipping), (4, 4))
        self.assertAlmostEqual(s.kinetic, sim.calc_energy().kinetic, places=12)

    def test_bad_values(self):
        with self.assertRaisesRegex(ValueError, r"analysis\.stop_at_rest\.hold: expected a "
                                    r"value >= 0"):
            self.spec(stop_at_rest={"hold": -1})
        with self.assertRaisesRegex(ValueError, r"analysis\.stop_at_rest\.sped: unknown key"):
            self.spec(stop_at_rest={"sped": 1})
        spec = sf.SceneSpec()
        with self.assertRaisesRegex(ValueError, r"analysis\.stop_at_rest: applies to dynamic "
                                    r"analyses only"):
            spec.set_analysis(type="static", stop_at_rest=True)


class ContactMaterials(unittest.TestCase):
    """Materials per pair of contact groups (the scene's contact.groups and contact.pairs) from
    the spec and from ModelBuilder, read back from Model.contact_laws with their defaults, and
    the spec's round trip of a file that has them."""

    def spec(self):
        spec = sf.SceneSpec()
        for name, y in (("grip", 0.0), ("slick", 0.5)):
            spec.add_rigid_body(name, at=[0, y, 0.05], mass=1, inertia=[0.00167] * 3, free=True,
                                shapes=[{"type": "box", "center": [0, y, 0.05],
                                         "half_sizes": [0.05] * 3}])
        spec.set_contact(stiffness=1e5, friction=0.3)
        spec.add_obstacle("ground", "plane", point=[0, 0, 0], normal=[0, 0, 1])
        return spec

    def test_spec_pairs_resolve_with_the_scenes_defaults(self):
        spec = self.spec()
        self.assertEqual(spec.add_contact_group("gripping", ["grip"]), 0)
        spec.add_contact_pair("gripping", "ground", friction=0.5, static_friction=0.6)
        spec.add_contact_pair("slick", "ground", friction=0.1, stiffness=2e5, damping_ratio=0.5)
        model = spec.compile().model
        self.assertEqual(model.contact_group_names, ["gripping", "ground", "slick"])
        laws = [(m.groups, m.friction, m.static_friction, m.stiffness, m.damping_ratio,
                 m.tangential_stiffness) for m in model.contact_laws]
        self.assertEqual(laws, [((-1, -1), 0.3, 0.3, 1e5, 1.0, 1e5),
                                ((0, 1), 0.5, 0.6, 1e5, 1.0, 1e5),
                                ((2, 1), 0.1, 0.1, 2e5, 0.5, 2e5)])

    def test_pair_onset(self):
        """A pair's own onset (contact.pairs[].onset) from the spec and from a file: resolved
        per law, the others the scene's (the force starting there: contact_materials_test.cpp),
        and the spec's error for a zero onset."""
        spec = self.spec()
        spec.set_contact(stiffness=1e5, friction=0.3, onset=1e-4)
        spec.add_contact_pair("grip", "ground", onset=1e-3)
        spec.add_contact_pair("slick", "ground", friction=0.1)
        model = spec.compile().model
        self.assertEqual([m.onset for m in model.contact_laws], [1e-4, 1e-3, 1e-4])
        with self.assertRaisesRegex(ValueError, r"contact\.pairs\[2\]\.onset: expected a "
                                    r"positive number, got 0"):
            spec.add_contact_pair("grip", "slick", onset=0)
        text = """
bodies:
  a: {type: rigid, at: [0, 0, 0.05], mass: 1, inertia: [1, 1, 1], free: true,
      shapes: [{type: sphere, center: [0, 0, 0.05], radius: 0.05}]}
contact:
  onset: 2e-4
  obstacles: {ground: {type: plane, point: [0, 0, 0], normal: [0, 0, 1]}}
  pairs: [{groups: [a, ground], onset: 5e-4}]
"""
        spec = sf.read_scene_spec(text)
        self.assertEqual(spec.contact.pairs[0].onset, 5e-4)
        self.assertEqual([m.onset for m in spec.compile().model.contact_laws], [2e-4, 5e-4])

    def test_file_and_spec_agree(self):
        text = """
bodies:
  a: {type: rigid, at: [0, 0, 0.05], mass: 1, inertia: [1, 1, 1], free: true,
      shapes: [{type: sphere, center: [0, 0, 0.05], radius: 0.05}]}
contact:
  friction: 0.2
  obstacles: {ground: {type: plane, point: [0, 0, 0], normal: [0, 0, 1]}}
  pairs: [{groups: [a, ground], friction: 0.7}]
"""
        spec = sf.read_scene_spec(text)
        self.assertEqual([g[0] for g in spec.contact.groups], ["a", "ground"])
        self.assertEqual(spec.contact.pairs[0].groups, (0, 1))
        self.assertEqual(spec.contact.pairs[0].friction, 0.7)
        self.assertEqual(spec.compile().model.contact_laws[1].friction, 0.7)

    def test_bad_pairs(self):
        spec = self.spec()
        spec.add_contact_pair("grip", "ground", friction=0.4)
        with self.assertRaisesRegex(ValueError, r"contact\.pairs\[1\]\.groups: the pair "
                                    r"\[ground, grip\] is given twice"):
            spec.add_contact_pair("ground", "grip")
        with self.assertRaisesRegex(ValueError, r"contact\.pairs\[1\]\.static_friction: "
                                    r"expected a value >= the pair's friction 0\.3"):
            spec.add_contact_pair("slick", "ground", static_friction=0.2)
        with self.assertRaisesRegex(ValueError, r"undefined body 'slik'"):
            spec.add_contact_pair("slik", "ground")
        with self.assertRaisesRegex(ValueError, r"contact\.groups\.both\[1\]: 'grip' is in "
                                    r"contact group 'grip' already"):
            spec.add_contact_group("both", ["slick", "grip"])

    def test_model_builder(self):
        b = sf.ModelBuilder()
        frame = [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0.1], [0, 0, 0, 1]]
        body = b.add_rigid_body("ball", b.add_node(frame), 1.0, [0, 0, 0],
                                [[1, 0, 0], [0, 1, 0], [0, 0, 1]])
        b.add_contact_shape(sf.ContactShape(body, sf.ContactShapeType.SPHERE, [0, 0, 0],
                                            radius=0.1))
        plane = sf.ContactObstacle()
        plane.name = "ground"
        ground = b.add_obstacle(plane)
        m = sf.ContactMaterial()
        m.groups = (b.add_contact_material_group("ball", [(False, body)]),
                    b.add_contact_material_group("floor", [], [ground]))
        m.friction = 0.8
        b.add_contact_material(m)
        model = b.build()
        self.assertEqual(model.contact_laws[1].friction, 0.8)
        self.assertEqual(model.contact_laws[1].static_friction, 0.8)
        b.add_contact_material(m)
        with self.assertRaisesRegex(ValueError, "contact pair 1: the groups 'ball' and 'floor' "
                                    "have a material already"):
            b.build()


if __name__ == "__main__":
    unittest.main()
