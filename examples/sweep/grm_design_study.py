"""A design study of the GRM on a Dask cluster: arm bending stiffness x soft-joint damping.

Shows screwfem.sweep with a grid of overrides (one parameter setting several scene keys), a
user metric (a closure over a reference trajectory, run on the workers) beside built-in ones,
and a heat map of the results. The base scene is examples/grm/grm_soft_kd.yaml (soft joints
with K = 10 and D = 5); each variant sets
  - the bending stiffness EI of the arms' section (sections.soft_arm.stiffness.4 and .5, the
    two bending entries of (EA, GA2, GA3, GJ, EI2, EI3); the paper's value is 1 N m^2);
  - the damping D of all eight soft joints (joints.J*.damping; the paper's value is 5, in
    N m s/rad or N s/m);
and measures
  - tip deviation: the largest distance over the run between the tip P8 and the tip of the
    rigid-joint case (examples/grm/grm_rigid.yaml, same mesh and end time, run once here) [m];
  - peak actuator effort: the largest |effort| of the revolute actuators J0, J2, J5 [N m];
  - the largest constraint residual, steps and Newton iterations.
Figure OUTDIR/design_study.png: one heat map per metric over the grid. Table OUTDIR/results.csv.

The default study (3 x 3 variants, 4 elements per soft body, 1 s of the 2 s motion) runs in
well under a minute on 2 cores, most of it the start of the local cluster; --full runs 6 x 6
variants at 8 elements over the full 2 s. Run from the repository root:
    PYTHONPATH=build/release/python /usr/bin/python3 examples/sweep/grm_design_study.py \\
        [-o out/design_study] [--full] [--resume] [--workers N | --scheduler tcp://HOST:8786]
It exits non-zero unless every variant completes, more joint damping lowers the tip deviation
and raises the effort at every stiffness, and the paper's design point (EI = 1, D = 5)
reproduces the single run of its scene bit for bit.
"""

import argparse
import pathlib
import sys
import tempfile

import numpy as np

import screwfem as sf

ROOT = pathlib.Path(__file__).resolve().parents[2]
SOFT = ROOT / "examples/grm/grm_soft_kd.yaml"
RIGID = ROOT / "examples/grm/grm_rigid.yaml"
SOFT_JOINTS = ["J0", "J1", "J2p", "J3p", "J2", "J3", "J4", "J5"]  # all but the weld W1
EI_KEY = "sections.soft_arm.stiffness.4+sections.soft_arm.stiffness.5"
DAMPING_KEY = "+".join(f"joints.{j}.damping" for j in SOFT_JOINTS)


def rigid_tip(common):
    """Times [s] and positions [m] of P8 in the rigid-joint case (one run, here)."""
    with tempfile.TemporaryDirectory() as tmp:
        result = sf.run_scene(sf.load_scene(str(RIGID), common + ["outputs.vtk=false"]), tmp)
        if not result.ok:
            sys.exit(f"rigid reference run failed: {result.message}")
        data = np.loadtxt(pathlib.Path(tmp) / "points.csv", delimiter=",", skiprows=1)
        with open(pathlib.Path(tmp) / "points.csv") as f:
            header = f.readline().strip().split(",")
    return data[:, 0], data[:, [header.index(f"P8.{a}") for a in "xyz"]]


def tip_deviation(times, positions):
    """A metric: max_t |P8(t) - P8_rigid(t)| [m] over the recorded times of both runs."""

    def metric(run):
        t = run.column("t")
        n = min(len(t), len(times))
        if not np.array_equal(t[:n], times[:n]):
            raise ValueError("recorded times differ from the rigid reference")
        p = np.column_stack([run.column(f"P8.{a}") for a in "xyz"])[:n]
        return {"tip_deviation": float(np.max(np.linalg.norm(p - positions[:n], axis=1)))}

    return metric


def heat_maps(df, ei_values, damping_values, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    shown = [("tip_deviation", "tip deviation from the rigid case [m]"),
             ("peak_effort", "peak actuator effort J0, J2, J5 [N m]")]
    fig, axes = plt.subplots(1, len(shown), figsize=(5.2 * len(shown), 4.2), squeeze=False)
    for ax, (column, title) in zip(axes[0], shown):
        grid = np.full((len(ei_values), len(damping_values)), np.nan)
        for _, row in df.iterrows():
            i = ei_values.index(row[EI_KEY])
            j = damping_values.index(row[DAMPING_KEY])
            grid[i, j] = row[column] if row["status"] == "completed" else np.nan
        image = ax.imshow(grid, origin="lower", aspect="auto", cmap="viridis")
        ax.set_xticks(range(len(damping_values)), [f"{d:g}" for d in damping_values])
        ax.set_yticks(range(len(ei_values)), [f"{e:g}" for e in ei_values])
        ax.set_xlabel("soft-joint damping D [N m s/rad, N s/m]")
        ax.set_ylabel("arm bending stiffness EI [N m$^2$]")
        ax.set_title(title, fontsize=10)
        for i in range(grid.shape[0]):
            for j in range(grid.shape[1]):
                ax.text(j, i, "failed" if np.isnan(grid[i, j]) else f"{grid[i, j]:.3g}",
                        ha="center", va="center", color="w", fontsize=8)
        fig.colorbar(image, ax=ax)
    fig.suptitle("GRM design study (soft joints, K = 10): variants of grm_soft_kd.yaml")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("-o", "--output", default="out/design_study", help="output directory")
    parser.add_argument("--full", action="store_true", help="6 x 6 variants, 8 elements, 2 s")
    parser.add_argument("--workers", type=int, help="local worker processes (default: all cores)")
    parser.add_argument("--scheduler", help="a Dask scheduler address, or 'serial'")
    parser.add_argument("--resume", action="store_true",
                        help="keep the rows already in OUTDIR and run only the missing variants")
    args = parser.parse_args()

    if args.full:
        ei_values = [0.25, 0.5, 1.0, 2.0, 4.0, 8.0]
        damping_values = [0.5, 1.0, 2.5, 5.0, 10.0, 20.0]
        common = ["defaults.elements=8", "outputs.interval=0.005"]
    else:
        ei_values = [0.5, 1.0, 4.0]
        damping_values = [1.0, 5.0, 20.0]
        common = ["defaults.elements=4", "analysis.end_time=1", "outputs.interval=0.01"]

    times, positions = rigid_tip(common)
    # The settings shared by every variant are one-value grid axes (they name the variant too).
    parameters = {c.split("=")[0]: [float(c.split("=")[1])] for c in common}
    parameters[EI_KEY] = ei_values
    parameters[DAMPING_KEY] = damping_values
    metrics = [tip_deviation(times, positions), sf.PeakJointEffort(["J0", "J2", "J5"]),
               sf.MaxConstraintResidual(), sf.Counters(), sf.WallTime()]
    outdir = pathlib.Path(args.output)
    if not args.resume:
        (outdir / "rows.jsonl").unlink(missing_ok=True)  # this example's own earlier rows
    df = sf.sweep(str(SOFT), parameters, metrics=metrics, workers=args.workers,
                  scheduler=args.scheduler, outdir=outdir, resume=args.resume)
    heat_maps(df, ei_values, damping_values, outdir / "design_study.png")

    table = df.assign(EI=df[EI_KEY], D=df[DAMPING_KEY])
    print(table[["EI", "D", "status", "tip_deviation", "peak_effort", "newton_iterations"]]
          .to_string(index=False))
    print(f"-> {outdir / 'results.csv'}, {outdir / 'design_study.png'}")

    # Checks: all completed; at every arm stiffness, more joint damping keeps the tip closer to
    # the rigid case and costs more actuator effort; the design point (EI = 1, D = 5: the
    # scene as written) equals one run of the scene, bit for bit.
    ok = bool((df["status"] == "completed").all())
    for ei in ei_values:
        by_damping = df[df[EI_KEY] == ei].sort_values(DAMPING_KEY)
        ok &= bool(np.all(np.diff(by_damping["tip_deviation"].to_numpy()) < 0))
        ok &= bool(np.all(np.diff(by_damping["peak_effort"].to_numpy()) > 0))
    point = df[(df[EI_KEY] == 1.0) & (df[DAMPING_KEY] == 5.0)]
    if len(point) == 1:
        with tempfile.TemporaryDirectory() as tmp:
            sf.run_scene(sf.load_scene(str(SOFT), common + ["outputs.vtk=false"]), tmp)
            data = np.loadtxt(pathlib.Path(tmp) / "joints.csv", delimiter=",", skiprows=1)
            with open(pathlib.Path(tmp) / "joints.csv") as f:
                header = f.readline().strip().split(",")
        peak = max(np.max(np.abs(data[:, header.index(f"{j}.effort")])) for j in ("J0", "J2", "J5"))
        ok &= bool(peak == point["peak_effort"].iloc[0])
    print("checks:", "passed" if ok else "FAILED")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
