"""Recording a run driven from Python (Simulation.record) and run_scene's callback.

The files a Python loop records are those `screwfem run` writes, bit for bit: both go through
the same Recording (include/screwfem/io/recording.h), and Simulation.step() without a step size
and Simulation.simulate() take the steps the CLI takes. Inputs set from a callback equal the
same values read from an input table. An exception inside a `record` block leaves complete files
and a summary saying how the run ended.

    cd tests/python && PYTHONPATH=<build>/python /usr/bin/python3 -m unittest -v test_recording
"""

import contextlib
import csv
import json
import math
import os
import pathlib
import resource
import tempfile
import unittest

import screwfem as sf

ROOT = pathlib.Path(__file__).resolve().parents[2]
ARM = str(ROOT / "examples" / "python" / "soft_arm_control.yaml")
PENDULUM = str(ROOT / "tests" / "data" / "pendulum.yaml")
FINGER = str(ROOT / "examples" / "tendon" / "finger.yaml")


@contextlib.contextmanager
def file_size_limit(nbytes):
    """RLIMIT_FSIZE for this process (Python ignores SIGXFSZ: writes past it fail with EFBIG,
    as on a full disk)."""
    old = resource.getrlimit(resource.RLIMIT_FSIZE)
    resource.setrlimit(resource.RLIMIT_FSIZE, (nbytes, old[1]))
    try:
        yield
    finally:
        resource.setrlimit(resource.RLIMIT_FSIZE, old)

# The summary fields that depend on the clock (or on how the run was started), not on the run.
CLOCK_FIELDS = {"wall_seconds", "real_time_factor"}


def read_files(folder, without_source=False):
    """Every file of a run folder, the summary without its clock fields (and, with
    `without_source`, without the scene's source: runs of one scene given two ways)."""
    out = {}
    for path in sorted(pathlib.Path(folder).rglob("*")):
        if path.is_dir() or path.name == ".screwfem.lock":
            continue
        rel = str(path.relative_to(folder))
        if rel == "summary.json":
            summary = json.loads(path.read_text())
            for key in CLOCK_FIELDS:
                summary.pop(key, None)
            if without_source:
                summary.pop("source", None)
                summary.get("scene", {}).pop("source", None)
            out[rel] = summary
        else:
            out[rel] = path.read_bytes()
    return out


def rows(path):
    with open(path, newline="") as f:
        return list(csv.reader(f))


class RecordEqualsRun(unittest.TestCase):
    """sim.record + the CLI's steps leave the files of run_scene (= `screwfem run`)."""

    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.dir = pathlib.Path(self.tmp.name)

    def tearDown(self):
        self.tmp.cleanup()

    def assertSameFiles(self, a, b):
        fa, fb = read_files(a), read_files(b)
        self.assertEqual(sorted(fa), sorted(fb))
        for name in fa:
            self.assertEqual(fa[name], fb[name], f"{name} differs")

    def compare(self, overrides, drive):
        scene = sf.load_scene(ARM, overrides)
        cli = self.dir / "cli"
        result = sf.run_scene(scene, str(cli))
        self.assertTrue(result.ok, result.message)
        sim = sf.Simulation(sf.load_scene(ARM, overrides))
        sim.initialize()
        with sim.record(str(self.dir / "py")) as rec:
            drive(sim)
        self.assertTrue(rec.result.ok)
        self.assertSameFiles(cli, self.dir / "py")
        return cli

    def test_fixed_steps_one_by_one(self):
        # u = 0.3 N from a profile of the scene, ParaView frames every 0.02 s, rows every 0.01 s.
        over = ["analysis.end_time=0.2", "outputs.vtk=true", "outputs.vtk_interval=0.02",
                "tendons.lifter.tension=0.3"]

        def drive(sim):
            while sim.time < 0.2 - 1e-12:
                sim.step()
        cli = self.compare(over, drive)
        table = rows(cli / "points.csv")
        self.assertEqual(len(table), 1 + 21)  # header, t = 0, 0.01, ..., 0.2
        self.assertTrue((cli / "vtk" / "motion.pvd").exists())
        self.assertTrue((cli / "tendons.csv").exists())

    def test_simulate_with_error_controlled_steps(self):
        # step: auto interpolates the rows due inside a step: simulate() records them alike.
        over = ["analysis.end_time=0.2", "analysis.step=auto", "analysis.tolerance=1e-6",
                "tendons.lifter.tension=0.3"]
        cli = self.compare(over, lambda sim: sim.simulate())
        summary = json.loads((cli / "summary.json").read_text())
        self.assertTrue(summary["settings"]["adaptive_steps"])
        self.assertGreater(summary["step_history"]["accepted"], 3)

    def test_static_path(self):
        # A static analysis records solve_static's path, a row per load step.
        over = ["analysis.type=static", "analysis.load_steps=4", "tendons.lifter.tension=0.5"]
        scene = sf.load_scene(ARM, over)
        result = sf.run_scene(scene, str(self.dir / "cli"))
        self.assertTrue(result.ok, result.message)
        sim = sf.Simulation(sf.load_scene(ARM, over))
        with sim.record(str(self.dir / "py")):
            sim.solve_static()
        self.assertSameFiles(self.dir / "cli", self.dir / "py")
        table = rows(self.dir / "py" / "points.csv")
        self.assertEqual(table[0][:2], ["t", "load_factor"])
        self.assertEqual(float(table[-1][1]), 1.0)


class RecordingEnds(unittest.TestCase):
    """What a recording leaves when its block ends early, and its arguments."""

    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.dir = pathlib.Path(self.tmp.name)
        self.sim = sf.Simulation(sf.load_scene(ARM, ["outputs.vtk=true"]))
        self.sim.initialize()

    def tearDown(self):
        self.tmp.cleanup()

    def test_an_exception_leaves_valid_files_and_says_failed(self):
        out = self.dir / "run"
        with self.assertRaises(ZeroDivisionError):
            with self.sim.record(str(out), interval=0.0):
                for _ in range(5):
                    self.sim.step(1e-3)
                1 / 0
        summary = json.loads((out / "summary.json").read_text())
        self.assertEqual(summary["status"], "failed")
        self.assertIn("ZeroDivisionError", summary["message"])
        table = rows(out / "points.csv")
        self.assertEqual(len(table), 1 + 6)  # t = 0 and every step (interval 0)
        self.assertAlmostEqual(float(table[-1][0]), 5e-3, delta=1e-15)
        self.assertEqual(summary["outputs"]["rows"], 6)
        # Frames every 0.02 s (the scene's vtk_interval): the one at t = 0, in the collection.
        pvd = (out / "vtk" / "motion.pvd").read_text()
        self.assertEqual(pvd.count("<DataSet"), 1)
        self.assertEqual(len(list((out / "vtk").glob("frame_*.vtp"))), 1)

    def test_keyboard_interrupt_says_interrupted(self):
        out = self.dir / "run"
        with self.assertRaises(KeyboardInterrupt):
            with self.sim.record(str(out)):
                self.sim.step(1e-3)
                raise KeyboardInterrupt
        summary = json.loads((out / "summary.json").read_text())
        self.assertEqual(summary["status"], "interrupted")
        self.assertEqual(summary["signal"], "SIGINT")

    def test_the_last_state_is_recorded(self):
        out = self.dir / "run"
        with self.sim.record(str(out)):  # rows every 0.01 s
            for _ in range(7):
                self.sim.step(2e-3)
        table = rows(out / "points.csv")
        times = [float(r[0]) for r in table[1:]]
        self.assertEqual(times[0], 0.0)
        self.assertAlmostEqual(times[-1], 0.014, delta=1e-12)  # the end, though not due
        self.assertEqual(len(times), 3)  # 0, 0.01 (first step end at or after it), 0.014

    def test_refuses_an_earlier_run_unless_force(self):
        out = str(self.dir / "run")
        with self.sim.record(out):
            self.sim.step(1e-3)
        with self.assertRaisesRegex(ValueError, "earlier run"):
            with self.sim.record(out):
                pass
        with self.sim.record(out, force=True):
            self.sim.step(1e-3)
        self.assertEqual(len(rows(pathlib.Path(out) / "points.csv")), 1 + 2)

    def test_bad_arguments(self):
        with self.assertRaisesRegex(ValueError, "interval"):
            self.sim.record(str(self.dir / "x"), interval=-1.0)
        with self.sim.record(str(self.dir / "a")):
            with self.assertRaisesRegex(RuntimeError, "recorded already"):
                with self.sim.record(str(self.dir / "b")):
                    pass

    def test_step_without_h_follows_the_schedule(self):
        # The scene's step, 2e-3 s, with the time set to each step end: t = n h exactly as in
        # the CLI's StepSchedule, where repeated t + h would accumulate round-off.
        schedule, t = sf.StepSchedule(0.0, 2.0, 2e-3), 0.0
        for _ in range(10):
            self.sim.step()
            t = schedule.next(t)
            self.assertEqual(self.sim.time, t)
        self.assertEqual(self.sim.time, 0.02)
        self.sim.time = 2.0
        with self.assertRaisesRegex(ValueError, "pass a step h"):
            self.sim.step()


class OutputFolder(unittest.TestCase):
    """Simulation.record has the CLI's protections: the same C++ Recording."""

    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.dir = pathlib.Path(self.tmp.name)

    def tearDown(self):
        self.tmp.cleanup()

    def test_a_write_error_stops_a_static_path_at_once(self):
        # 2000 load steps; the first 64 KiB of rows do not fit under the 30000-byte limit: the
        # solve stops at its next Newton iteration and raises, the summary says why.
        sim = sf.Simulation(sf.load_scene(FINGER, ["analysis.type=static",
                                                   "analysis.load_steps=2000",
                                                   "outputs.vtk=false"]))
        out = self.dir / "static"
        with file_size_limit(30000):
            with self.assertRaisesRegex(RuntimeError, "writing the files failed: cannot write "
                                        "at load factor λ = .*: File too large; the tables "
                                        "hold the [0-9]+ rows up to load factor λ = "):
                with sim.record(str(out)):
                    sim.solve_static()
        summary = json.loads((out / "summary.json").read_text())
        self.assertEqual(summary["status"], "failed")
        self.assertIn("File too large", summary["message"])
        steps = summary["static_solution"]["load_steps"]
        table = rows(out / "points.csv")
        self.assertGreater(steps, len(table) - 1)
        self.assertLess(steps, 1000)  # of 2000
        for name in ("joints.csv", "tendons.csv", "forces.csv"):
            self.assertEqual(len(rows(out / name)), len(table), name)

    def test_static_tendon_tension_is_scaled_by_the_load_factor(self):
        # tendons.csv holds the applied tension, load_factor x 50 N, as tendon_state gives it.
        sim = sf.Simulation(sf.load_scene(FINGER, ["analysis.type=static",
                                                   "analysis.load_steps=4"]))
        out = self.dir / "scaled"
        with sim.record(str(out)):
            sim.solve_static()
        table = rows(out / "tendons.csv")
        self.assertEqual(table[0], ["t", "load_factor", "flexor.length", "flexor.rate",
                                    "flexor.tension"])
        # (4 load steps, some of them halved: the rows are the converged load factors.)
        self.assertGreaterEqual(len(table) - 1, 4)
        for r in table[1:]:
            self.assertEqual(float(r[4]), 50.0 * float(r[1]))
        self.assertEqual(float(table[-1][4]), 50.0)
        self.assertEqual(sim.tendon_state("flexor", load_factor=0.5)[2], 25.0)
        self.assertEqual(sim.tendon_state("flexor")[2], 50.0)

    def test_a_write_error_stops_a_dynamic_run(self):
        sim = sf.Simulation(sf.load_scene(FINGER, ["analysis.end_time=100",
                                                   "outputs.interval=0", "outputs.vtk=false"]))
        sim.initialize()
        out = self.dir / "dynamic"
        with file_size_limit(30000):
            with self.assertRaisesRegex(RuntimeError, "cannot write at t = .*File too large"):
                with sim.record(str(out)):
                    sim.simulate()
        self.assertLess(sim.time, 5.0)
        summary = json.loads((out / "summary.json").read_text())
        self.assertEqual(summary["status"], "failed")

    def test_links_are_refused(self):
        victim = self.dir / "victim.txt"
        victim.write_text("precious\n")
        out = self.dir / "out"
        out.mkdir()
        os.symlink(victim, out / "tendons.csv")
        sim = sf.Simulation(sf.load_scene(PENDULUM))
        sim.initialize()
        for force in (False, True):
            with self.assertRaisesRegex(ValueError, "tendons.csv is a symbolic link; screwfem "
                                        "writes its files into the output directory itself"):
                with sim.record(str(out), force=force):
                    pass
        self.assertEqual(victim.read_text(), "precious\n")

    def test_max_rows_estimate_and_refusal(self):
        scene = sf.load_scene(PENDULUM)
        e = sf.estimate_outputs(scene)
        self.assertEqual((e.rows, e.field_times, e.frames), (51.0, 0.0, 6.0))
        self.assertEqual(scene.outputs.max_rows, 1000000)
        sim = sf.Simulation(scene)
        sim.initialize()
        outputs = scene.outputs
        outputs.max_rows = 100
        self.assertEqual(sf.estimate_outputs(scene, outputs).rows, 51.0)
        # record's interval 1e-3 s: a row every step, 501 rows.
        scene2 = sf.load_scene(PENDULUM, ["outputs.max_rows=100"])
        sim2 = sf.Simulation(scene2)
        sim2.initialize()
        with self.assertRaisesRegex(ValueError, "about 501 rows in each table, above the limit "
                                    "of 100 .* record less often .outputs.interval."):
            with sim2.record(str(self.dir / "x"), interval=1e-3):
                pass
        self.assertFalse((self.dir / "x").exists())
        every_step = sf.load_scene(PENDULUM, ["outputs.interval=0", "outputs.max_rows=500"])
        with self.assertRaisesRegex(ValueError, "about 501 rows in each table, above the limit "
                                    "of 500"):
            sf.estimate_outputs(every_step, check=True)
        spec = sf.read_scene_spec(PENDULUM)
        spec.set_outputs(max_rows=5e5)
        self.assertEqual(spec.outputs.max_rows, 500000)
        self.assertEqual(spec.compile().outputs.max_rows, 500000)
        with self.assertRaisesRegex(ValueError, "outputs.max_rows"):
            spec.set_outputs(max_rows=0)


class Callbacks(unittest.TestCase):
    """run_scene(callback=...): closed loop from Python inside the CLI's run loop."""

    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.dir = pathlib.Path(self.tmp.name)
        self.over = ["analysis.end_time=0.3", "outputs.interval=0"]

    def tearDown(self):
        self.tmp.cleanup()

    def test_callback_inputs_equal_an_input_table(self):
        # A proportional controller on the tip height sets u before every step; its values,
        # logged at the end of the step they are held over, replayed as --inputs give the same
        # tables bit for bit.
        log = []

        def control(sim):
            z = sim.point_motion("tip").position[2]
            u = max(0.0, 40.0 * (0.0 - z))
            sim.inputs["u"] = u
            log.append((sim.time, u))

        scene = sf.load_scene(ARM, self.over)
        result = sf.run_scene(scene, str(self.dir / "loop"), callback=control)
        self.assertTrue(result.ok, result.message)
        self.assertEqual(len(log), 1 + result.steps)  # the start and every step
        self.assertGreater(max(u for _, u in log), 0.1)  # the controller acted
        # The value set at t_k is held over the step (t_k, t_k+1]: the table's row at t_k+1
        # (and at the start, the first value).
        table = self.dir / "u.csv"
        with open(table, "w") as f:
            f.write("t,u\n")
            f.write(f"{log[0][0]!r},{log[0][1]!r}\n")
            for (_, u), (t_next, _) in zip(log[:-1], log[1:]):
                f.write(f"{t_next!r},{u!r}\n")
        replay = sf.run_scene(sf.load_scene(ARM, self.over), str(self.dir / "table"),
                              inputs=str(table))
        self.assertTrue(replay.ok, replay.message)
        for name in ("points.csv", "joints.csv", "tendons.csv", "energy.csv"):
            self.assertEqual((self.dir / "loop" / name).read_bytes(),
                             (self.dir / "table" / name).read_bytes(), name)

    def test_every_and_reading_the_state(self):
        seen = []
        sf.run_scene(sf.load_scene(ARM, self.over), str(self.dir / "r"),
                     callback=lambda sim: seen.append(sim.time), every=10)
        # The start, then every 10th of the 150 steps of 2 ms.
        self.assertEqual(len(seen), 1 + 15)
        self.assertEqual(seen[0], 0.0)
        self.assertTrue(all(math.isclose(t, 0.02 * i) for i, t in enumerate(seen)))

    def test_an_exception_in_the_callback_ends_the_run_and_is_raised(self):
        def boom(sim):
            if sim.time > 0.05:
                raise ValueError("controller failed")

        with self.assertRaisesRegex(ValueError, "controller failed"):
            sf.run_scene(sf.load_scene(ARM, self.over), str(self.dir / "r"), callback=boom)
        summary = json.loads((self.dir / "r" / "summary.json").read_text())
        self.assertEqual(summary["status"], "interrupted")
        self.assertGreater(summary["outputs"]["rows"], 20)

    def test_the_callback_cannot_step(self):
        with self.assertRaisesRegex(RuntimeError, "run_scene callback"):
            sf.run_scene(sf.load_scene(ARM, self.over), str(self.dir / "r"),
                         callback=lambda sim: sim.step(1e-3))
        with self.assertRaisesRegex(ValueError, "every"):
            sf.run_scene(sf.load_scene(ARM, self.over), str(self.dir / "s"),
                         callback=lambda sim: None, every=0)


if __name__ == "__main__":
    unittest.main()
