"""Tests of parameter sweeps (python/screwfem/_sweep.py, python/screwfem/__main__.py, the
`screwfem sweep` command): results, robustness and resumption, on a Dask LocalCluster of two
single-threaded worker processes bound to 127.0.0.1.

Run by ctest (python/CMakeLists.txt, test python_sweep) as
    /usr/bin/python3 -m unittest -v test_sweep
from tests/python with PYTHONPATH=<build>/python, SCREWFEM_TEST_DATA_DIR=tests/data and
SCREWFEM_CLI=<the built screwfem program> (the command-line test is skipped without it).

The scene is the rigid pendulum of tests/data/pendulum.yaml (see test_bindings.py), shortened
by overrides. Every wait is bounded: sweeps get a timeout, subprocesses too.
"""

import csv
import hashlib
import json
import os
import pathlib
import signal
import subprocess
import tempfile
import threading
import time
import unittest

import numpy as np

import screwfem as sf
from screwfem import _sweep

DATA_DIR = pathlib.Path(
    os.environ.get("SCREWFEM_TEST_DATA_DIR", pathlib.Path(__file__).resolve().parents[1] / "data"))
PENDULUM = str(DATA_DIR / "pendulum.yaml")
TIMEOUT = 120.0  # seconds, for any one sweep or subprocess

# 12 variants: 3 masses x 4 numerical dampings, 0.1 s of swing.
GRID12 = {"analysis.end_time": [0.1], "bodies.link.mass": [0.1, 0.2, 0.3],
          "analysis.rho_inf": [0.6, 0.8, 0.9, 1.0]}
METRICS = [sf.PointPosition("tip", [0.05, 0.1]), sf.MaxConstraintResidual(), sf.Counters()]
REPRODUCIBLE = ["tip.x@0.05", "tip.y@0.05", "tip.z@0.05", "tip.x@0.1", "tip.y@0.1", "tip.z@0.1",
                "max_constraint_residual", "end_time", "steps", "newton_iterations", "halvings"]


def assert_same_bits(test, a, b, columns):
    """Columns of two sweep tables hold the same doubles, bit for bit, variant by variant."""
    a = a.set_index("variant_id").sort_index()
    b = b.set_index("variant_id").sort_index()
    test.assertEqual(list(a.index), list(b.index))
    for c in columns:
        x = np.asarray(a[c], dtype=np.float64)
        y = np.asarray(b[c], dtype=np.float64)
        test.assertTrue(np.array_equal(x.view(np.uint64), y.view(np.uint64)), c)


def journal_lines(outdir):
    path = pathlib.Path(outdir) / _sweep.ROWS_FILE
    return path.read_text().splitlines() if path.exists() else []


class VariantsTest(unittest.TestCase):
    """The variant list and identities (no cluster)."""

    def test_grid_is_the_product_with_the_last_key_fastest(self):
        v = sf.variants({"a": [1, 2], "b+c": [0.5, 1e-5]})
        self.assertEqual(v, [{"a": 1, "b+c": 0.5}, {"a": 1, "b+c": 1e-5},
                             {"a": 2, "b+c": 0.5}, {"a": 2, "b+c": 1e-5}])
        self.assertEqual(sf.format_overrides(v[1]), ["a=1", "b=1e-05", "c=1e-05"])
        self.assertEqual(sf.format_overrides({("x", "y"): [1.5, True]}),
                         ["x=[1.5, true]", "y=[1.5, true]"])

    def test_random_samples_are_reproducible_from_the_seed(self):
        spec = {"k": (1.0, 2.0), "n": [4, 8], "f": lambda rng: int(rng.integers(10))}
        a = sf.variants(spec, samples=5, seed=3)
        self.assertEqual(a, sf.variants(spec, samples=5, seed=3))
        self.assertNotEqual(a, sf.variants(spec, samples=5, seed=4))
        self.assertTrue(all(1.0 <= v["k"] < 2.0 and v["n"] in (4, 8) for v in a))

    def test_variant_id_depends_on_the_overrides_only(self):
        self.assertEqual(sf.variant_id(["a=1", "b=2"]), sf.variant_id(["a=1", "b=2"]))
        self.assertNotEqual(sf.variant_id(["a=1", "b=2"]), sf.variant_id(["b=2", "a=1"]))
        self.assertEqual(sf.variant_id(["a=1", "b=2"]),
                         hashlib.sha256(b"a=1\nb=2").hexdigest()[:16])
        self.assertEqual(len(sf.variant_id([])), 16)


class JournalTest(unittest.TestCase):
    """OUTDIR/rows.jsonl across an interruption (serial sweeps: no cluster)."""

    def test_resume_drops_a_cut_line_and_reruns_error_rows_only(self):
        grid = {"analysis.end_time": [0.05], "bodies.link.mass": [0.1, 0.2, 0.3]}
        with tempfile.TemporaryDirectory() as tmp:
            first = sf.sweep(PENDULUM, grid, metrics=METRICS[1:], scheduler="serial", outdir=tmp)
            lines = journal_lines(tmp)
            row = json.loads(lines[1])
            row["status"] = "error"  # as if its task had been lost
            lines[1] = json.dumps(row)
            # ... and a kill cut the journal in the middle of a fourth line.
            (pathlib.Path(tmp) / _sweep.ROWS_FILE).write_text("\n".join(lines) + '\n{"varia')
            with self.assertRaises(FileExistsError):  # without resume: refuses to overwrite
                sf.sweep(PENDULUM, grid, scheduler="serial", outdir=tmp)
            again = sf.sweep(PENDULUM, grid, metrics=METRICS[1:], scheduler="serial",
                             outdir=tmp, resume=True)
            after = journal_lines(tmp)
            self.assertEqual(after[:3], lines)  # kept; the cut line is gone
            self.assertEqual(len(after), 4)     # only the error row ran again
            self.assertEqual(json.loads(after[3])["variant_id"], row["variant_id"])
            self.assertEqual(list(again["status"]), ["completed"] * 3)
            assert_same_bits(self, first, again, REPRODUCIBLE[6:])


class BoundedInputsTest(unittest.TestCase):
    """The files a sweep reads are bounded regular files; max_memory reaches the variants
    (docs/limits.md)."""

    def test_a_device_or_a_huge_scene_is_refused_before_any_run(self):
        with self.assertRaisesRegex(ValueError, r"^sweep: /dev/zero: the scene file is not a "
                                                r"regular file$"):
            sf.sweep("/dev/zero", {"analysis.end_time": [0.05]}, scheduler="serial")
        with tempfile.TemporaryDirectory() as tmp:
            big = pathlib.Path(tmp) / "big.yaml"
            with open(big, "wb") as f:
                f.truncate((16 << 20) + 1)
            with self.assertRaisesRegex(ValueError, "big.yaml: the scene file is larger than "
                                                    r"16 MiB \(the limit\)$"):
                sf.sweep(str(big), {"analysis.end_time": [0.05]}, scheduler="serial")

    def test_a_journal_line_beyond_a_megabyte_is_an_error(self):
        grid = {"analysis.end_time": [0.05]}
        with tempfile.TemporaryDirectory() as tmp:
            sf.sweep(PENDULUM, grid, metrics=METRICS[1:], scheduler="serial", outdir=tmp)
            with open(pathlib.Path(tmp) / _sweep.ROWS_FILE, "a") as f:
                f.write("x" * (1 << 20) + "\n")
            with self.assertRaisesRegex(ValueError, "a line longer than 1048576 characters"):
                sf.sweep(PENDULUM, grid, scheduler="serial", outdir=tmp, resume=True)

    def test_max_memory_makes_larger_variants_invalid(self):
        with self.assertRaisesRegex(ValueError, "memory size: expected a size such as 8G"):
            sf.sweep(PENDULUM, {"analysis.end_time": [0.05]}, scheduler="serial",
                     max_memory="lots")
        df = sf.sweep(PENDULUM, {"analysis.end_time": [0.05]}, scheduler="serial",
                      max_memory=1000)
        self.assertEqual(list(df["status"]), ["invalid"])
        self.assertRegex(df["message"][0], r"more than the memory limit of 1000 B \(set by "
                                           r"--max-memory or max_memory;")
        df = sf.sweep(PENDULUM, {"analysis.end_time": [0.05]}, scheduler="serial",
                      max_memory="1G")
        self.assertEqual(list(df["status"]), ["completed"])


FINGER = str(pathlib.Path(__file__).resolve().parents[2] / "examples" / "tendon" / "finger.yaml")


class SummaryTest(unittest.TestCase):
    """The sweep summary: short parameter names, column metrics, the tidy table, its text and
    figures, and the variants kept (serial: no cluster)."""

    def test_short_names_are_the_last_components_that_tell_keys_apart(self):
        self.assertEqual(
            sf.short_names(["parameters.length", "joints.J0.damping", "joints.J1.damping",
                            "bodies.a.elements+bodies.b.elements", "gravity"]),
            {"parameters.length": "length", "joints.J0.damping": "J0.damping",
             "joints.J1.damping": "J1.damping", "bodies.a.elements+bodies.b.elements": "elements",
             "gravity": "gravity"})

    def test_column_metric_expressions_and_their_errors(self):
        m = sf.ColumnMetric("at( tip.y , 0.1 )")
        self.assertEqual((m.function, m.column, m.time, m.name), ("at", "tip.y", 0.1,
                                                                  "at(tip.y,0.1)"))
        for bad in ("median(tip.y)", "at(tip.y)", "max(tip.y, 1)", "max tip.y"):
            with self.assertRaises(ValueError):
                sf.ColumnMetric(bad)

    def test_a_two_by_three_grid_gives_its_table_figures_and_notable_runs(self):
        grid = {"parameters.tension": [20, 50], "parameters.offset": [0.01, 0.02, 0.03],
                "analysis.end_time": [0.2]}
        metrics = [sf.ColumnMetric("max(tip.y)"), sf.ColumnMetric("at(tip.y, 0.1)"),
                   sf.ColumnMetric("final(flexor.tension)"), sf.ColumnMetric("rms(tip.x)")]
        with tempfile.TemporaryDirectory() as tmp:
            out = pathlib.Path(tmp)
            df = sf.sweep(FINGER, grid, metrics=metrics, scheduler="serial", outdir=out,
                          keep_outputs="notable", summary=True, timeout=TIMEOUT)
            table = __import__("pandas").read_csv(out / _sweep.SUMMARY_FILE,
                                                  float_precision="round_trip")
            # One column per parameter with its short name (a constant one too), one per metric.
            self.assertEqual(list(table.columns),
                             ["variant", "tension", "offset", "end_time", "status", "max(tip.y)",
                              "at(tip.y,0.1)", "final(flexor.tension)", "rms(tip.x)"])
            self.assertEqual(list(table["tension"]), [20, 20, 20, 50, 50, 50])
            self.assertEqual(list(table["offset"]), [0.01, 0.02, 0.03] * 2)
            # Physics: while the curl is small the tip moves with the moment tension x offset
            # (the finger's bending is linear there): 5x from (20 N, 1 cm) to (50 N, 2 cm).
            y = table["at(tip.y,0.1)"]
            self.assertAlmostEqual(y[4] / y[0], 5.0, delta=5e-3)
            self.assertAlmostEqual(y[2] / y[0], 3.0, delta=3e-3)
            # The tension is the profile's, whatever the offset: smooth step to 50 N over 1 s.
            self.assertEqual(table["final(flexor.tension)"][0], table["final(flexor.tension)"][2])
            # Kept: the smallest and largest of each metric, with their files; the metric equals
            # the column of the kept points.csv, bit for bit.
            kept = {d.name for d in (out / "runs").iterdir()}
            self.assertEqual(kept, set(df.attrs["notable"]))
            self.assertIn(df["variant_id"][0], kept)  # min max(tip.y): 20 N, 1 cm
            self.assertIn(df["variant_id"][5], kept)  # max max(tip.y): 50 N, 3 cm
            self.assertLess(len(kept), 6)
            for i in (0, 5):
                with open(out / "runs" / df["variant_id"][i] / "points.csv") as f:
                    rows = list(csv.DictReader(f))
                self.assertEqual(max(float(r["tip.y"]) for r in rows), table["max(tip.y)"][i])
            # A figure of each metric that varies, against the tension, a line per offset.
            figures = sorted(p.name for p in (out / "figures").iterdir())
            self.assertEqual(figures, ["at_tip.y_0.1.png", "final_flexor.tension.png",
                                       "max_tip.y.png", "rms_tip.x.png"])
            for name in figures:
                self.assertEqual((out / "figures" / name).read_bytes()[:8], b"\x89PNG\r\n\x1a\n")
            # The printed table.
            text = sf.format_summary(sf.summary_table(df, list(grid)))
            self.assertRegex(text.splitlines()[0], r"^variant +tension +offset +end_time +status "
                             r"+max\(tip\.y\)")
            self.assertEqual(len(text.splitlines()), 7)

    def test_a_failed_variant_keeps_its_files(self):
        parameters = [{"analysis.end_time": 0.05},
                      {"analysis.end_time": 0.05, "analysis.max_iterations": 1,
                       "analysis.max_halvings": 0}]
        with tempfile.TemporaryDirectory() as tmp:
            out = pathlib.Path(tmp)
            df = sf.sweep(PENDULUM, parameters, metrics=[sf.ColumnMetric("final(tip.z)")],
                          scheduler="serial", outdir=out, keep_outputs="notable", summary=True,
                          timeout=TIMEOUT)
            self.assertEqual(list(df["status"]), ["completed", "failed"])
            self.assertEqual(df.attrs["notable"], {df["variant_id"][1]: "failed"})
            self.assertEqual([d.name for d in (out / "runs").iterdir()], [df["variant_id"][1]])
            self.assertTrue((out / "runs" / df["variant_id"][1] / "summary.json").exists())


class ClusterSweepTest(unittest.TestCase):
    """Sweeps on one LocalCluster of 2 worker processes, shared by the tests of this class."""

    @classmethod
    def setUpClass(cls):
        from distributed import Client

        cls.cluster = _sweep._local_cluster(2)
        cls.client = Client(cls.cluster, timeout=60)

    @classmethod
    def tearDownClass(cls):
        cls.client.close(timeout=10)
        cls.cluster.close(timeout=30)

    def setUp(self):
        self.client.wait_for_workers(2, timeout=60)  # a worker killed by a test is replaced
        self.tmp = tempfile.TemporaryDirectory()

    def tearDown(self):
        self.tmp.cleanup()

    def test_every_socket_is_on_the_loopback_interface(self):
        info = self.client.scheduler_info()
        addresses = [info["address"]] + list(info["workers"])
        addresses += [w["nanny"] for w in info["workers"].values()]
        self.assertEqual(len(addresses), 5)
        for a in addresses:
            self.assertTrue(a.startswith("tcp://127.0.0.1:"), a)

    def test_cluster_metrics_equal_serial_runs_bitwise(self):
        parallel = sf.sweep(PENDULUM, GRID12, metrics=METRICS, client=self.client, timeout=TIMEOUT)
        serial = sf.sweep(PENDULUM, GRID12, metrics=METRICS, scheduler="serial")
        self.assertEqual(len(parallel), 12)
        self.assertEqual(list(parallel["status"]), ["completed"] * 12)
        self.assertEqual(list(parallel["variant"]), list(range(12)))
        assert_same_bits(self, parallel, serial, REPRODUCIBLE)
        # The variants really differ, and a row is what `load_scene` + `run_scene` give.
        self.assertEqual(len(set(parallel["tip.z@0.1"])), 12)
        row = parallel.iloc[7]
        scene = sf.load_scene(PENDULUM, row["overrides"].split("; "))
        result = sf.run_scene(scene, self.tmp.name)
        with open(pathlib.Path(self.tmp.name) / "points.csv", newline="") as f:
            table = {float(r[0]): r for r in list(csv.reader(f))[1:]}
        self.assertEqual(float(table[0.1][3]), row["tip.z@0.1"])
        self.assertEqual(result.newton_iterations, row["newton_iterations"])
        self.assertEqual(row["bodies.link.mass"], 0.2)
        self.assertEqual(row["analysis.rho_inf"], 1.0)

    def test_a_killed_worker_loses_no_row_and_duplicates_none(self):
        def slow_metric(run):  # 0.3 s per task: a kill lands mid-task
            time.sleep(0.3)
            return {"worker_pid": os.getpid()}

        grid = {"analysis.end_time": [0.1], "bodies.link.mass": [0.1, 0.15, 0.2, 0.25],
                "analysis.rho_inf": [0.5, 0.6, 0.7, 0.8, 0.9, 1.0]}
        pids = sorted(self.client.run(os.getpid).values())
        self.assertEqual(len(pids), 2)
        outdir = pathlib.Path(self.tmp.name) / "sweep"
        killed = []

        def killer():  # kill the first worker once 4 rows are in
            deadline = time.monotonic() + TIMEOUT
            while len(journal_lines(outdir)) < 4 and time.monotonic() < deadline:
                time.sleep(0.05)
            os.kill(pids[0], signal.SIGKILL)
            killed.append(len(journal_lines(outdir)))

        thread = threading.Thread(target=killer, daemon=True)
        thread.start()
        df = sf.sweep(PENDULUM, grid, metrics=[*METRICS, slow_metric], client=self.client,
                      outdir=outdir, timeout=TIMEOUT)
        thread.join(timeout=10)
        self.assertEqual(len(killed), 1)
        self.assertLess(killed[0], 24)  # the kill landed during the sweep
        expected = [sf.variant_id(sf.format_overrides(v)) for v in sf.variants(grid)]
        self.assertEqual(sorted(df["variant_id"]), sorted(expected))
        self.assertEqual(list(df["status"]), ["completed"] * 24, df["message"].iloc[0])
        lines = [json.loads(line) for line in journal_lines(outdir)]
        self.assertEqual(sorted(r["variant_id"] for r in lines), sorted(expected))
        # Rows came from the killed worker before the kill and from others after it.
        workers = set(df["worker_pid"])
        self.assertIn(pids[0], workers)
        self.assertGreaterEqual(len(workers), 2)
        # The scheduler sent the variants the dead worker held back to be run again.
        def lost_tasks(dask_scheduler):
            return sorted({t.key for t in dask_scheduler.transition_log
                           if t.key.startswith("screwfem-variant-") and t.start == "processing"
                           and t.finish == "released"})

        lost = self.client.run_on_scheduler(lost_tasks)
        self.assertGreaterEqual(len(lost), 1)
        for key in lost:  # screwfem-variant-<variant_id>-<nonce>: one row each
            self.assertEqual(list(df["variant_id"]).count(key.split("-")[2]), 1)
        serial = sf.sweep(PENDULUM, grid, metrics=METRICS, scheduler="serial")
        assert_same_bits(self, df, serial, REPRODUCIBLE)
        table = __import__("pandas").read_csv(outdir / _sweep.TABLE_FILE)
        self.assertEqual(len(table), 24)

    def test_failing_and_invalid_variants_are_rows(self):
        parameters = [
            {"analysis.end_time": 0.1},
            # One Newton iteration and no halving: the first step that needs two fails.
            {"analysis.end_time": 0.1, "analysis.max_iterations": 1, "analysis.max_halvings": 0},
            {"bodies.link.mas": 0.3},      # unknown key: located by the override
            {"points.E": [0.0, 0.0, 0.0]},  # zero-length link: located at its line in the file
        ]
        df = sf.sweep(PENDULUM, parameters, metrics=METRICS, client=self.client, timeout=TIMEOUT)
        self.assertEqual(list(df["status"]), ["completed", "failed", "invalid", "invalid"])
        failed = df.iloc[1]
        self.assertRegex(failed["message"],
                         r"^step failed at t = [0-9.e-]+ s .*Newton did not converge in 1 iter")
        self.assertLess(failed["end_time"], 0.1)
        self.assertTrue(np.isnan(failed["tip.z@0.1"]))  # not recorded before the failure
        self.assertEqual(df.iloc[2]["message"], PENDULUM + ": override 'bodies.link.mas=0.3': "
                         "bodies.link.mas: unknown key 'mas' (did you mean 'mass'?)")
        self.assertRegex(df.iloc[3]["message"], "^" + PENDULUM.replace(".", r"\.") +
                         r":10:[0-9]+: bodies\.link\.between: the two points coincide")

    def test_interrupted_cli_sweep_keeps_rows_and_resume_runs_only_the_missing(self):
        cli = os.environ.get("SCREWFEM_CLI")
        if not cli:
            self.skipTest("SCREWFEM_CLI (the screwfem program) not set")
        outdir = pathlib.Path(self.tmp.name) / "cli"
        # 10 variants of about 0.2 s each (a 1e-5 s step).
        args = [cli, "sweep", PENDULUM, "--grid", "analysis.step=1e-5", "--grid",
                "analysis.end_time=0.2", "--grid", "outputs.interval=0.01", "--grid",
                "bodies.link.mass=0.10,0.11,0.12,0.13,0.14,0.15,0.16,0.17,0.18,0.19",
                "--metric", "point:tip@0.1,0.2", "--metric", "counters",
                "--scheduler", self.client.scheduler.address, "-o", str(outdir)]
        proc = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                start_new_session=True)  # its own process group, as on a terminal
        try:
            deadline = time.monotonic() + TIMEOUT
            while len(journal_lines(outdir)) < 2 and time.monotonic() < deadline:
                time.sleep(0.02)
            os.killpg(proc.pid, signal.SIGINT)  # Ctrl-C
            _, err = proc.communicate(timeout=TIMEOUT)
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait(timeout=10)
        self.assertEqual(proc.returncode, 130, err.decode())
        first = journal_lines(outdir)
        self.assertGreaterEqual(len(first), 2)
        self.assertLess(len(first), 10)
        kept = __import__("pandas").read_csv(outdir / _sweep.TABLE_FILE)
        self.assertEqual(len(kept), len(first))  # the table holds the finished rows

        done = subprocess.run(args + ["--resume", "--quiet"], capture_output=True,
                              timeout=TIMEOUT, text=True)
        self.assertEqual(done.returncode, 0, done.stderr)
        self.assertIn("10 variants (10 completed)", done.stdout)
        lines = journal_lines(outdir)
        self.assertEqual(lines[:len(first)], first)  # the finished rows are not run again
        ids = [json.loads(line)["variant_id"] for line in lines]
        self.assertEqual(len(ids), 10)
        self.assertEqual(len(set(ids)), 10)
        table = __import__("pandas").read_csv(outdir / _sweep.TABLE_FILE)
        self.assertEqual(list(table["variant"]), list(range(10)))
        # Resuming a complete sweep runs nothing.
        again = subprocess.run(args + ["--resume", "--quiet"], capture_output=True,
                               timeout=TIMEOUT, text=True)
        self.assertEqual(again.returncode, 0, again.stderr)
        self.assertEqual(journal_lines(outdir), lines)


if __name__ == "__main__":
    unittest.main()
