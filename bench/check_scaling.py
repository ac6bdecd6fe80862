"""How `screwfem check` scales with the size of a scene (docs/limits.md): scenes whose checks
were quadratic or allocated without bound, each at two sizes ten times apart. Appends its
results to bench/RESULTS.md (section "Checks at size", which bench/make_results.py keeps when
it rewrites the file).

    /usr/bin/python3 bench/check_scaling.py --screwfem build/release/app/screwfem [--no-write]

Cases (CPU seconds of the child, user + system, best of --repeat runs; peak resident memory):
  inputs      a pendulum with N run-time inputs (`inputs: {u0: 0, ...}`): 1e5 took 12.6 s
              (a pairwise duplicate-name search)
  eyelets     a tendon of N eyelets at arc lengths `s` along a 10,000-element rod: 1e4 took
              19.6 s (a walk along the rod, with a logarithm per node, per eyelet)
  obstacles   N sphere obstacles beside a 100,000-element rod: 1000 ran 66 s up to 3.4 GB and
              out of memory; now refused from the count of pairs (exit 2)
  spheres     N free spheres on a plane, every two of which may touch: 10,000 had a band of
              59,999 (86 GB of LU factors for a run); now a band of 5 (exit 0)
A linear check takes about ten times longer at the larger size (plus a constant). Obstacles
at N = 100 make 10,000,000 pairs, the most a model may have (kMaxObstaclePairs): accepted.
"""

import argparse
import datetime
import os
import pathlib
import subprocess
import sys
import tempfile

ROOT = pathlib.Path(__file__).resolve().parents[1]
RESULTS = ROOT / "bench" / "RESULTS.md"
SECTION = "## Checks at size"

ROD = """points: {{O: [0, 0, 0], E: [{length}, 0, 0]}}
materials: {{m: {{E: 1e6, nu: 0.45, density: 1000}}}}
sections: {{s: {{shape: circle, radius: 0.01, material: m}}}}
bodies:
  arm: {{type: soft, from: O, to: E, section: s, elements: {elements}}}
joints:
  clamp: {{type: fixed, at: O, between: [ground, arm]}}
"""


def inputs_scene(n):
    text = (ROOT / "tests" / "data" / "pendulum.yaml").read_text()
    inputs = "inputs: {" + ", ".join(f"u{i}: 0.0" for i in range(n)) + "}\n"
    return text.replace("analysis:", inputs + "analysis:", 1)


def eyelets_scene(n):
    eyelets = ", ".join(f"{{body: arm, s: {0.9 * (i + 1) / n:.9f}, offset: [0, 0.005, 0]}}"
                        for i in range(n))
    return (ROD.format(length=1, elements=10000)
            + f"tendons:\n  t: {{eyelets: [{eyelets}], tension: 1}}\n"
            + "analysis: {type: static}\n")


def obstacles_scene(n):
    lines = [f"    o{i}: {{type: sphere, center: [{0.1 * i:.3f}, 1, 0], radius: 0.05}}"
             for i in range(n)]
    return (ROD.format(length=100, elements=100000) + "contact:\n  obstacles:\n"
            + "\n".join(lines) + "\nanalysis: {type: static}\n")


def spheres_scene(n):
    lines = []
    for i in range(n):
        x, y = 0.2 * (i % 100), 0.2 * (i // 100)
        lines.append(f"  b{i}: {{type: rigid, at: [{x:.1f}, {y:.1f}, 0.1], mass: 0.1, "
                     f"inertia: [1e-4, 1e-4, 1e-4], free: true, shapes: [{{type: sphere, "
                     f"center: [{x:.1f}, {y:.1f}, 0.1], radius: 0.05}}]}}")
    return ("bodies:\n" + "\n".join(lines) + "\ncontact:\n  obstacles:\n    ground: {type: plane, "
            "point: [0, 0, 0], normal: [0, 0, 1]}\nanalysis: {type: dynamic, end_time: 0.01, "
            "step: 1e-3}\n")


CASES = [("inputs", inputs_scene, (10000, 100000)),
         ("eyelets", eyelets_scene, (1000, 10000)),
         ("obstacles", obstacles_scene, (10, 100, 1000)),
         ("spheres", spheres_scene, (1000, 10000))]


def run_check(screwfem, path):
    """(exit code, CPU seconds, peak RSS in MiB, stderr lines) of `screwfem check path`, from
    the child's own resource usage (wait4)."""
    with tempfile.TemporaryFile() as err:
        proc = subprocess.Popen([screwfem, "check", path], stdout=subprocess.DEVNULL, stderr=err)
        _, status, usage = os.wait4(proc.pid, 0)
        proc.returncode = os.waitstatus_to_exitcode(status)
        err.seek(0)
        lines = err.read().decode(errors="replace").strip().splitlines()
    return proc.returncode, usage.ru_utime + usage.ru_stime, usage.ru_maxrss / 1024.0, lines


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--screwfem", default=str(ROOT / "build" / "release" / "app" / "screwfem"))
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--no-write", action="store_true")
    args = parser.parse_args()
    rows = []
    with tempfile.TemporaryDirectory(prefix="screwfem-check-scaling-") as tmp:
        for name, make, sizes in CASES:
            times = []
            for n in sizes:
                path = os.path.join(tmp, f"{name}_{n}.yaml")
                with open(path, "w") as f:
                    f.write(make(n))
                size = os.path.getsize(path)
                best, code, rss, err = None, None, 0.0, []
                for _ in range(args.repeat):
                    code, cpu, rss, err = run_check(args.screwfem, path)
                    best = cpu if best is None else min(best, cpu)
                times.append(best)
                ratio = f"{best / times[0]:.1f}" if len(times) > 1 and times[0] > 0 else ""
                rows.append(f"| {name} | {n} | {size / 1024:.0f} KiB | {code} | {best:.2f} s | "
                            f"{ratio} | {rss:.0f} MiB |")
                print(rows[-1], (err[-1][:100] if err and code else ""), flush=True)
    load = os.getloadavg()[0]
    revision = subprocess.run(["git", "-C", str(ROOT), "describe", "--always", "--dirty"],
                              capture_output=True, text=True).stdout.strip()
    stamp = datetime.datetime.now(datetime.timezone.utc).replace(microsecond=0).isoformat()
    text = "\n".join([
        f"### {stamp}, revision {revision}, load average {load:.1f}",
        "",
        "| Case | N | Scene | Exit | CPU (best) | Ratio to N/10 | Peak RSS |",
        "|---|---:|---:|---:|---:|---:|---:|",
        *rows,
        "",
    ])
    print(text)
    if args.no_write:
        return 0
    body = RESULTS.read_text() if RESULTS.exists() else "# Benchmark results\n"
    if SECTION not in body:
        body = body.rstrip("\n") + "\n\n" + SECTION + "\n\n" + __doc__.split("\n\n", 2)[2].strip() + "\n"
    RESULTS.write_text(body.rstrip("\n") + "\n\n" + text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
