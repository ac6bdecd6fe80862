"""Actuator efforts of the rigid GRM across the drive switch at 0.5 s; one figure per joint.

    /usr/bin/python3 tools/grm_switch_efforts.py SCREWFEM_PROGRAM OUTDIR [--scene SCENE]

Runs SCENE (default examples/grm/grm_rigid.yaml) from 0 to 0.6 s with a row every step in three
variants, through `screwfem run --set ...`, into OUTDIR/<variant>/:

  no_restart   rho_inf = 0.8 (the scene's), no restart at the switches: the integrator carries
               its auxiliary acceleration across the jump and the efforts ring (issue 14);
  restart      rho_inf = 0.8 with the restart at the switches (the default);
  restart_rho0 rho_inf = 0 with the restart: the soft bodies' stiff modes, which the jump of the
               prescribed acceleration excites, are damped within about ten steps.

and writes OUTDIR/effort_switch_<joint>.png for J0, J2, J3 and J5 (effort over 0.48 to 0.56 s,
and its second difference e[n+1] - 2 e[n] + e[n-1] over the series' range on a log scale), and
prints the largest second difference from the 2nd to the 10th step after the switch and from
the 10th step to 0.56 s. docs/numerics.md ("Efforts across drive switches") explains the curves.
scripts/run-main.sh runs it. Needs numpy and matplotlib (Debian: python3-numpy,
python3-matplotlib).
"""

import argparse
import csv
import os
import subprocess
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

JOINTS = ("J0", "J2", "J3", "J5")
SWITCH = 0.5
END = 0.6
STEP = 1e-3
VARIANTS = (("no_restart", 0.8, False, "rho_inf 0.8, no restart"),
            ("restart", 0.8, True, "rho_inf 0.8, restart"),
            ("restart_rho0", 0.0, True, "rho_inf 0, restart"))


def run(program, scene, outdir, rho_inf, restart):
    """Runs one variant; returns (t, {joint: effort}) as numpy arrays."""
    os.makedirs(outdir, exist_ok=True)
    args = [program, "run", scene, "-o", outdir, "--quiet", "--force",
            "--set", f"analysis.end_time={END:g}", "--set", f"analysis.step={STEP:g}",
            "--set", f"analysis.rho_inf={rho_inf:g}",
            "--set", f"analysis.restart_at_breakpoints={'true' if restart else 'false'}",
            "--set", "outputs.vtk=false", "--set", "outputs.interval=0"]
    done = subprocess.run(args, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    if done.returncode != 0:
        sys.exit(f"grm_switch_efforts: {' '.join(args)} failed ({done.returncode}):\n"
                 f"{done.stdout}")
    with open(os.path.join(outdir, "joints.csv"), newline="") as f:
        rows = list(csv.reader(f))
    header = rows[0]
    data = np.array([[float(x) for x in r] for r in rows[1:]])
    t = data[:, header.index("t")]
    return t, {j: data[:, header.index(f"{j}.effort")] for j in JOINTS}


def second_difference(e):
    """|e[n+1] - 2 e[n] + e[n-1]| / range(e), for n = 1 .. len - 2."""
    return np.abs(e[2:] - 2.0 * e[1:-1] + e[:-2]) / (e.max() - e.min())


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("program")
    parser.add_argument("outdir")
    parser.add_argument("--scene", default="examples/grm/grm_rigid.yaml")
    args = parser.parse_args()

    results = {}
    for name, rho_inf, restart, _ in VARIANTS:
        results[name] = run(args.program, args.scene, os.path.join(args.outdir, name),
                            rho_inf, restart)

    print("| joint | variant | max d2/range, steps 2-10 after 0.5 s | steps 10 to 0.56 s |")
    print("|---|---|---|---|")
    for j in JOINTS:
        fig, (ax_e, ax_d) = plt.subplots(2, 1, figsize=(8, 6.5), sharex=True)
        for name, _, _, label in VARIANTS:
            t, efforts = results[name]
            e = efforts[j]
            window = (t >= 0.48) & (t <= 0.56)
            ax_e.plot(t[window], e[window], marker=".", markersize=3, linewidth=0.8,
                      label=label)
            d2 = second_difference(e)
            tm = t[1:-1]
            w2 = (tm >= 0.48) & (tm <= 0.56)
            ax_d.semilogy(tm[w2], np.maximum(d2[w2], 1e-12), marker=".", markersize=3,
                          linewidth=0.8, label=label)
            early = (tm > SWITCH + 1.5 * STEP) & (tm < SWITCH + 10 * STEP)
            late = (tm > SWITCH + 10 * STEP) & (tm < 0.56)
            print(f"| {j} | {label} | {d2[early].max():.2e} | {d2[late].max():.2e} |")
        ax_e.set_ylabel(f"{j} effort [N m or N]")
        ax_e.set_title(f"GRM rigid: {j} effort across the drive switch at 0.5 s (h = 1 ms)")
        ax_e.legend(fontsize=8)
        ax_d.set_ylabel("|second difference| / range")
        ax_d.set_xlabel("t [s]")
        for ax in (ax_e, ax_d):
            ax.axvline(SWITCH, color="0.6", linewidth=0.6)
            ax.grid(True, linewidth=0.3)
        fig.tight_layout()
        fig.savefig(os.path.join(args.outdir, f"effort_switch_{j}.png"), dpi=120)
        plt.close(fig)


if __name__ == "__main__":
    main()
