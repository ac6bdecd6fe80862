"""Convergence study of the GRM (rigid case) in space and time; prints a Markdown table.

    /usr/bin/python3 tools/grm_convergence.py SCREWFEM_PROGRAM OUTDIR [--scene SCENE]

Runs SCENE (default examples/grm/grm_rigid.yaml) with 2, 4, 8 and 16 elements per soft body
and steps h = 1e-3 and 5e-4, and with 4 elements at h = 2e-3 and 2.5e-4, over its whole time span, through `screwfem run --set ...`, into
OUTDIR/e<elements>_h<step>/, and prints the position of P8 at t = 0.5, 1, 1.5 and 2 s for
every run, then the differences between successive refinements at t = 0.5 s and their
ratios (about 4 for a second-order method, about 2 for a first-order one).
scripts/run-convergence.sh runs it; docs/getting-started.md ("Convergence") shows its output.
Standard library only (Debian's /usr/bin/python3).
"""

import argparse
import csv
import math
import os
import subprocess
import sys
import time

ELEMENTS = (2, 4, 8, 16)
STEPS = (1e-3, 5e-4)
TIME_ORDER_ELEMENTS = 4
TIME_ORDER_STEPS = (2e-3, 1e-3, 5e-4, 2.5e-4)
TIMES = (0.5, 1.0, 1.5, 2.0)
POINT = "P8"


def run(program, scene, outdir, elements, step):
    """Runs one case and returns ({t: (x, y, z)} at TIMES, wall seconds)."""
    os.makedirs(outdir, exist_ok=True)
    args = [program, "run", scene, "-o", outdir, "--quiet", "--force",
            "--set", f"defaults.elements={elements}", "--set", f"analysis.step={step:g}",
            "--set", "outputs.vtk=false", "--set", "outputs.interval=0"]
    start = time.monotonic()
    done = subprocess.run(args, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    wall = time.monotonic() - start
    if done.returncode != 0:
        sys.exit(f"grm_convergence: {' '.join(args)} failed ({done.returncode}):\n{done.stdout}")
    with open(os.path.join(outdir, "points.csv"), newline="") as f:
        rows = list(csv.reader(f))
    header = rows[0]
    cols = [header.index(f"{POINT}.{a}") for a in "xyz"]
    values = {}
    for t in TIMES:
        # The row whose time is nearest to t (every step is recorded; steps land on 0.5 s
        # multiples because the profiles' breakpoints are aligned with step ends).
        row = min(rows[1:], key=lambda r: abs(float(r[0]) - t))
        if abs(float(row[0]) - t) > 1e-9:
            sys.exit(f"grm_convergence: no row at t = {t} in {outdir}/points.csv")
        values[t] = tuple(float(row[c]) for c in cols)
    return values, wall


def distance(a, b):
    return math.sqrt(sum((x - y) ** 2 for x, y in zip(a, b)))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("program", help="the screwfem program")
    parser.add_argument("outdir", help="directory for the runs")
    parser.add_argument("--scene", default="examples/grm/grm_rigid.yaml")
    args = parser.parse_args()

    results = {}
    cases = [(e, h) for h in STEPS for e in ELEMENTS]
    cases += [(TIME_ORDER_ELEMENTS, h) for h in TIME_ORDER_STEPS if h not in STEPS]
    for e, h in cases:
        outdir = os.path.join(args.outdir, f"e{e}_h{h:g}")
        results[(e, h)], wall = run(args.program, args.scene, outdir, e, h)
        print(f"ran {e:2d} elements per soft body, h = {h:g} s: {wall:.1f} s wall",
              file=sys.stderr)

    print(f"Position of {POINT} [m] in `{args.scene}`:\n")
    print("| elements | h [s] | " + " | ".join(f"t = {t:g} s" for t in TIMES) + " |")
    print("|---|---|" + "---|" * len(TIMES))
    for h in STEPS:
        for e in ELEMENTS:
            cells = ["(" + ", ".join(f"{c:.6f}" for c in results[(e, h)][t]) + ")" for t in TIMES]
            print(f"| {e} | {h:g} | " + " | ".join(cells) + " |")

    t = TIMES[0]
    print(f"\nDifferences of {POINT} at t = {t:g} s between successive refinements [m]:\n")
    print("| refinement | difference | ratio to the previous |")
    print("|---|---|---|")
    for h in STEPS:
        print_differences([(f"elements {a} -> {b} (h = {h:g} s)", results[(a, h)][t], results[(b, h)][t])
                           for a, b in zip(ELEMENTS, ELEMENTS[1:])])
    e = TIME_ORDER_ELEMENTS
    print_differences([(f"h {a:g} -> {b:g} s ({e} elements)", results[(e, a)][t], results[(e, b)][t])
                       for a, b in zip(TIME_ORDER_STEPS, TIME_ORDER_STEPS[1:])])


def print_differences(refinements):
    """Table rows of successive refinements (label, coarse, fine) with the ratio of each
    difference to the previous one."""
    previous = None
    for label, coarse, fine in refinements:
        d = distance(coarse, fine)
        ratio = f"{previous / d:.2f}" if previous else ""
        print(f"| {label} | {d:.3e} | {ratio} |")
        previous = d

if __name__ == "__main__":
    main()
