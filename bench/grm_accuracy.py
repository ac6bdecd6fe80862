#!/usr/bin/python3
"""Time-discretisation error of the rigid GRM: fixed steps against error-controlled steps.

Runs examples/grm/grm_rigid.yaml (4 elements per soft body, 0 to 2 s, rows every 1 ms; rows of
`step: auto` runs interpolated by the dense output) with the screwfem command-line program and
compares every row with a reference run at a small fixed step:

  error of a run = max over the rows of |P8 - P8_ref|   (and of |q - q_ref| of the passive
                   joints J1, J2p, J3p, J4)

The reference's own error is estimated against a run at half its step. Then the fixed step
h = 1e-3 s and `step: auto` at each tolerance (absolute = relative) are measured, and the
loosest tolerance whose P8 error is at most the fixed step's is named.

    /usr/bin/python3 bench/grm_accuracy.py build/dev/app/screwfem_cli \\
        [--reference 1.25e-4] [--tolerances 1e-5,3e-6,1e-6,3e-7,1e-7]

Prints a table (tolerance, steps, rejected, Newton iterations, P8 error, joint error).
"""
import argparse
import csv
import json
import os
import subprocess
import sys
import tempfile

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
SCENE = os.path.join(HERE, "..", "examples", "grm", "grm_rigid.yaml")
PASSIVE = ["J1", "J2p", "J3p", "J4"]


def read_csv(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    header = rows[0]
    data = np.array([[float(x) for x in r] for r in rows[1:]])
    return {name: data[:, i] for i, name in enumerate(header)}


def run(cli, workdir, label, overrides):
    out = os.path.join(workdir, label)
    cmd = [cli, "run", SCENE, "-o", out, "--set", "defaults.elements=4", "--set", "outputs.vtk=false"]
    for o in overrides:
        cmd += ["--set", o]
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
    points = read_csv(os.path.join(out, "points.csv"))
    joints = read_csv(os.path.join(out, "joints.csv"))
    with open(os.path.join(out, "summary.json")) as f:
        summary = json.load(f)
    return {"t": points["t"],
            "p8": np.stack([points["P8." + c] for c in "xyz"], axis=1),
            "q": np.stack([joints[j + ".q"] for j in PASSIVE], axis=1),
            "summary": summary}


def errors(r, ref):
    if len(r["t"]) != len(ref["t"]) or np.max(np.abs(r["t"] - ref["t"])) > 1e-9:
        raise RuntimeError("the runs' rows are at different times")
    p8 = np.linalg.norm(r["p8"] - ref["p8"], axis=1)
    dq = np.abs(r["q"] - ref["q"])
    return p8.max(), r["t"][p8.argmax()], dq.max(), PASSIVE[int(np.unravel_index(dq.argmax(), dq.shape)[1])]


def find(summary, key):
    """The value of `key` anywhere in the summary (first match, depth first)."""
    if isinstance(summary, dict):
        if key in summary:
            return summary[key]
        for v in summary.values():
            found = find(v, key)
            if found is not None:
                return found
    return None


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("cli", help="the screwfem command-line program")
    parser.add_argument("--reference", type=float, default=1.25e-4, help="reference step [s]")
    parser.add_argument("--tolerances", default="1e-5,3e-6,1e-6,3e-7,1e-7")
    parser.add_argument("--fixed", default="1e-3", help="fixed steps to measure, comma-separated")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="grm_accuracy_") as work:
        ref = run(args.cli, work, "ref", [f"analysis.step={args.reference}"])
        half = run(args.cli, work, "half", [f"analysis.step={args.reference / 2}"])
        e_ref, t_ref, q_ref, _ = errors(ref, half)
        print(f"reference h = {args.reference:g}: P8 error vs h/2 {e_ref * 1e3:.4f} mm "
              f"(t = {t_ref:.3f} s), passive joints {q_ref:.3g}")
        print(f"{'run':>16s} {'steps':>6s} {'rejected':>8s} {'newton':>7s} {'P8 error [mm]':>14s} "
              f"{'at t [s]':>8s} {'joint error':>12s}")
        results = []
        for h in args.fixed.split(","):
            results.append((f"fixed h = {h}", run(args.cli, work, "fixed" + h, [f"analysis.step={h}"])))
        for tol in args.tolerances.split(","):
            results.append((f"auto tol {tol}", run(args.cli, work, "auto" + tol,
                                                   ["analysis.step=auto", f"analysis.tolerance={tol}"])))
        e_fixed = None
        loosest = None
        for label, r in results:
            e, t, q, j = errors(r, ref)
            s = r["summary"]
            steps = find(s, "accepted")
            rejected = find(s, "rejected") or 0
            newton = find(s, "newton_iterations")
            print(f"{label:>16s} {steps:6d} {rejected:8d} {newton:7d} {e * 1e3:14.4f} {t:8.3f} "
                  f"{q:10.3g} ({j})")
            if label.startswith("fixed") and e_fixed is None:
                e_fixed = e
            elif label.startswith("auto") and e_fixed is not None and e <= e_fixed and loosest is None:
                loosest = label
        print(f"loosest tolerance at the accuracy of the first fixed step: {loosest}")
        if e_ref > 0.05 * e_fixed:
            print(f"WARNING: the reference's own error is {e_ref / e_fixed:.1%} of the fixed step's")
    return 0


if __name__ == "__main__":
    sys.exit(main())
