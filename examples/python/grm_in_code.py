"""The generic robotic mechanism (GRM) of the method paper, built in code with screwfem.SceneSpec.

examples/grm/grm_soft_k.yaml (case 2, soft joints) and grm_rigid.yaml (case 1, rigid joints)
written with the Python spec API instead of YAML: six rigid and five soft bodies, revolute,
prismatic and fixed joints, series-elastic (or prescribed) drives with bang-bang profiles, a
closed loop (base - crank - coupler - rocker) and welded soft arms under world-frame loads.
The spec compiles through the same compiler as the file; the example runs both for a short
time and checks that every output file is the same, byte for byte (exit status 1 if not).

    PYTHONPATH=build/release/python python3 examples/python/grm_in_code.py [--case soft_k|rigid]
        [--end-time 0.2] [--out DIR]
"""

import argparse
import math
import pathlib
import sys
import tempfile

import screwfem as sf

ROOT = pathlib.Path(__file__).resolve().parents[2]
TABLES = ("points.csv", "joints.csv", "reactions.csv", "energy.csv", "joints.json")

# Table I of the paper (initial configuration) [m]; P2p and P3p are its 2' and 3'.
POINTS = {
    "P0": (0, 0, 0), "P1": (0.2, 0.6, 0), "P2p": (1, 1, 0), "P3p": (1.2, 0, 0),
    "P2": (0, 1, 0), "P3": (0.2, 1.5, 0), "P4": (0.5, 1.3, 0.2), "P5": (0.8, 1.6, 0.2),
    "P6": (1, 1.8, 0.3), "P7": (1.2, 2, 0.4), "P8": (1.4, 2.2, 0.5),
}


def build_grm(case="soft_k"):
    """The GRM as a SceneSpec: case 'soft_k' (K = 10 on every joint, series-elastic drives)
    or 'rigid' (ideal joints, prescribed drives)."""
    soft = case == "soft_k"
    spec = sf.SceneSpec(name="GRM, case 2: soft joints, K = 10" if soft else
                        "GRM, case 1: rigid joints", gravity=(0, 0, -9.81))
    for name, p in POINTS.items():
        spec.add_point(name, p)

    # Rigid bodies: m = 0.15 kg, J = 1e-4 I kg m^2 about the midpoint; the frame at the first
    # point, world-aligned.
    for name, a, b in (("base", "P0", "P3p"), ("crank", "P0", "P1"), ("link12", "P1", "P2"),
                       ("guide", "P2", "P3"), ("link34", "P3", "P4"), ("link45", "P4", "P5")):
        spec.add_rigid_body(name, between=(a, b), mass=0.15, inertia=(1e-4, 1e-4, 1e-4),
                            fixed=name == "base")
    # Soft bodies, per unit length: EA = GA = 1e6 N, GJ = EI = 1 N m^2; rho A = 0.1 kg/m,
    # rotational inertia 0.5 kg m. The arms are welded to each other at 6 and 7.
    arm = sf.Section(stiffness=[1e6, 1e6, 1e6, 1, 1, 1], inertia=[0.1, 0.1, 0.1, 0.5, 0.5, 0.5])
    for name, a, b, weld in (("coupler", "P1", "P2p", None), ("rocker", "P2p", "P3p", None),
                             ("arm56", "P5", "P6", None), ("arm67", "P6", "P7", "arm56"),
                             ("arm78", "P7", "P8", "arm67")):
        spec.add_soft_body(name, path=[a, b], section=arm, elements=8, weld_start=weld)

    # Table II. Actuated joints follow a bang-bang profile from 0 to q_f over 1 s (Table III):
    # exactly (rigid) or through their spring (series elastic, soft).
    spring = {"stiffness": 10} if soft else {}

    def drive(q_final):
        return {"type": "series_elastic" if soft else "prescribed",
                "profile": sf.Profile.bang_bang(0, 1, q_final)}

    z = (0, 0, 1)
    spec.add_joint("J0", "revolute", at="P0", between=("ground", "crank"), axis=z, **spring,
                   drive=drive(math.pi / 6))
    spec.add_joint("J1", "revolute", at="P1", between=("crank", "coupler"), axis=z, **spring)
    spec.add_joint("W1", "fixed", at="P1", between=("crank", "link12"))
    spec.add_joint("J2p", "revolute", at="P2p", between=("coupler", "rocker"), axis=z, **spring)
    spec.add_joint("J3p", "revolute", at="P3p", between=("rocker", "base"), axis=z, **spring)
    spec.add_joint("J2", "revolute", at="P2", between=("link12", "guide"), axis=z, **spring,
                   drive=drive(math.pi / 6))
    spec.add_joint("J3", "prismatic", at="P3", between=("guide", "link34"),
                   axis={"from": "P2", "to": "P3"}, **spring, drive=drive(0.75))
    spec.add_joint("J4", "revolute", at="P4", between=("link34", "link45"), axis=z, **spring)
    spec.add_joint("J5", "revolute", at="P5", between=("link45", "arm56"), axis=(1, 0, 0),
                   **spring, drive=drive(math.pi / 3))

    # Table IV: world-frame forces, the same S-shaped law from 0 to their values over 1 s.
    for name, body, at, force in (("f1", "arm67", "P6", (100, -100, 0)),
                                  ("f2", "arm78", "P7", (-100, 100, 0)),
                                  ("f3", "arm78", "P8", (100, -100, 0))):
        spec.add_load(name, body=body, at=at, force=force, frame="world",
                      profile=sf.Profile.bang_bang(0, 1))

    spec.set_analysis(type="dynamic", start_time=0, end_time=2, step=1e-3, rho_inf=0.8,
                      align_steps=True, rod_inertia="exact")
    spec.add_output_point("P8", body="arm78", at="P8")
    spec.add_output_point("P4", body="link34", at="P4")
    spec.set_outputs(joints="all", interval=0.001, vtk=True, vtk_interval=0.02)
    return spec


def differing_files(a, b):
    """The files of two run folders that differ (summary.json aside, which names the source
    and the clock)."""
    def files(folder):
        return {str(p.relative_to(folder)): p.read_bytes()
                for p in sorted(pathlib.Path(folder).rglob("*"))
                if p.is_file() and p.name not in ("summary.json", ".screwfem.lock")}
    fa, fb = files(a), files(b)
    return sorted(name for name in fa.keys() | fb.keys() if fa.get(name) != fb.get(name))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--case", choices=("soft_k", "rigid"), default="soft_k")
    parser.add_argument("--end-time", type=float, default=0.2, help="[s] (the file's: 2)")
    parser.add_argument("--out", help="folder for the two runs (default: a temporary one)")
    args = parser.parse_args()

    spec = build_grm(args.case)
    spec.analysis.end_time = args.end_time
    code_scene = spec.compile()
    file_scene = sf.load_scene(str(ROOT / "examples" / "grm" / f"grm_{args.case}.yaml"),
                               [f"analysis.end_time={args.end_time!r}"])

    with tempfile.TemporaryDirectory() as tmp:
        out = pathlib.Path(args.out or tmp)
        runs = {}
        for label, scene in (("code", code_scene), ("file", file_scene)):
            result = sf.run_scene(scene, str(out / label), force=True)
            if not result.ok:
                print(f"{label}: the run failed: {result.message}", file=sys.stderr)
                return 1
            runs[label] = out / label
        differing = differing_files(runs["code"], runs["file"])
        count = sum(1 for p in runs["code"].rglob("*") if p.is_file())
        tip = (out / "code" / "points.csv").read_text().splitlines()[-1].split(",")[1:4]
    print(f"GRM {args.case}, {len(spec.bodies)} bodies and {len(spec.joints)} joints built in "
          f"code, {result.steps} steps to t = {result.end_time:g} s; tip P8 at "
          f"({', '.join(tip)}) m")
    if differing:
        print(f"differs from the scene file's run: {', '.join(differing)}", file=sys.stderr)
        return 1
    print(f"the same as the scene file's run, byte for byte: {', '.join(TABLES)} and the "
          f"ParaView files ({count - 1} files; summary.json names the source)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
