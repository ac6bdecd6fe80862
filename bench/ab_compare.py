#!/usr/bin/python3
"""Interleaved A/B comparison of two builds of one Google Benchmark program.

The machine's speed drifts by tens of percent over minutes, so two revisions are compared by
running their benchmark programs alternately (A, B, A, B, ...) in one session and reporting,
per benchmark, the median time of each and the median of the per-round ratios B/A.

    /usr/bin/python3 bench/ab_compare.py A/bench/screwfem_bench_dynamics \\
        B/bench/screwfem_bench_dynamics --filter 'BM_GrmSolver/grm_rigid' --rounds 8

With --scene, A and B are two builds' screwfem CLI programs instead: each round runs
`PROGRAM run SCENE -o TMP --force --quiet` (plus every --set) with both, and the table has the
wall-clock and the CPU time (user + system of the child) of each, per scene:

    /usr/bin/python3 bench/ab_compare.py A/app/screwfem B/app/screwfem --rounds 8 \\
        --scene examples/grm/grm_rigid.yaml --set defaults.elements=4 \\
        --set outputs.interval=1 --set outputs.vtk_interval=1

Prints a table; exits 1 if a program fails.
"""
import argparse
import json
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time


def run(program, bench_filter, repetitions):
    cmd = [program, "--benchmark_format=json", f"--benchmark_filter={bench_filter}"]
    if repetitions > 1:
        cmd += [f"--benchmark_repetitions={repetitions}", "--benchmark_report_aggregates_only=true"]
    out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    # Per benchmark: the median aggregate when the run has repetitions (its own or ours), the
    # single measurement otherwise.
    times, medians = {}, {}
    for b in json.loads(out)["benchmarks"]:
        name = b.get("run_name", b["name"])
        t = b["real_time"] * {"ns": 1e-9, "us": 1e-6, "ms": 1e-3, "s": 1.0}[b["time_unit"]]
        if b.get("run_type") == "aggregate":
            if b.get("aggregate_name") == "median":
                medians[name] = t
        else:
            times[name] = t
    times.update(medians)
    return times


def run_scene(program, scene, sets, out):
    """Wall and CPU seconds of one CLI run of `scene` (outputs into `out`)."""
    cmd = [program, "run", scene, "-o", out, "--force", "--quiet"]
    for s in sets:
        cmd += ["--set", s]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    subprocess.run(cmd, check=True, capture_output=True)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return {"wall": wall, "cpu": cpu}


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("a", help="benchmark program of revision A (the reference)")
    parser.add_argument("b", help="benchmark program of revision B")
    parser.add_argument("--filter", default=".", help="--benchmark_filter regex")
    parser.add_argument("--rounds", type=int, default=6, help="A/B pairs (default 6)")
    parser.add_argument("--repetitions", type=int, default=1,
                        help="repetitions per run, their median taken (default 1)")
    parser.add_argument("--scene", action="append", default=[],
                        help="compare CLI runs of this scene (repeatable)")
    parser.add_argument("--set", action="append", default=[], dest="sets",
                        help="a --set override for every CLI run (repeatable)")
    args = parser.parse_args()
    tmp = tempfile.mkdtemp(prefix="ab_compare_")

    def measure(program, label):
        if not args.scene:
            return run(program, args.filter, args.repetitions)
        times = {}
        for scene in args.scene:
            name = os.path.splitext(os.path.basename(scene))[0]
            t = run_scene(program, scene, args.sets, os.path.join(tmp, label + "_" + name))
            times[name + " wall"] = t["wall"]
            times[name + " cpu"] = t["cpu"]
        return times

    samples = {}
    for r in range(args.rounds):
        order = [("A", args.a), ("B", args.b)] if r % 2 == 0 else [("B", args.b), ("A", args.a)]
        for label, program in order:
            try:
                times = measure(program, label)
            except subprocess.CalledProcessError as e:
                print(f"ab_compare: {program} failed ({e.returncode})", file=sys.stderr)
                return 1
            for name, t in times.items():
                samples.setdefault(name, {"A": [], "B": []})[label].append(t)
    print(f"{'benchmark':44s} {'A median':>12s} {'B median':>12s} {'B/A (median of rounds)':>24s}")
    for name, s in samples.items():
        n = min(len(s["A"]), len(s["B"]))
        ratios = [s["B"][i] / s["A"][i] for i in range(n)]
        print(f"{name:44s} {statistics.median(s['A']) * 1e3:10.2f}ms "
              f"{statistics.median(s['B']) * 1e3:10.2f}ms {statistics.median(ratios):12.3f} "
              f"[{min(ratios):.3f}, {max(ratios):.3f}]")
    shutil.rmtree(tmp, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
