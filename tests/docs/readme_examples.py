"""Runs the examples of README.md and checks their physics (ctest readme_scene, readme_python).

    /usr/bin/python3 tests/docs/readme_examples.py scene --source REPO --screwfem CLI --work DIR
    PYTHONPATH=build/release/python /usr/bin/python3 tests/docs/readme_examples.py python \
        --source REPO --work DIR

scene: the first ```yaml block of README.md, written to DIR/finger.yaml, is run with
`screwfem run` as it stands and with one element per rod (`--set`). A pressure chamber of area
A at offset r in the section of a clamped rod is the active stress pA [1, 0, 0, 0, r3, -r2]:
constant strain gamma1 = pA/EA and kappa3 = -pA r2/EI3 (docs/scene-format.md, "actuation"),
which a helical element represents exactly, so the tip in points.csv must lie at
((1 + gamma1) sin(kappa3 L) / kappa3, (1 + gamma1) (1 - cos(kappa3 L)) / kappa3, 0) to 1e-7 m
whatever the mesh; summary.json must say the static solution completed.

python: the first ```python block runs in this process. Its PI controller must have settled the
tip on the target height (within 0.1 mm, at rest within 1 mm/s), and the pressure it settled at
must be the pressure that holds the tip at that height in statics by the closed form above
(solved for p by bisection), within 0.5 % (measured: 9 um and 0.05 %), and the line it prints
must be the one the README quotes (to 1e-5 m and 0.1 %): a controller that ended anywhere else, or a pressure
chamber that bent the rod by another law, fails.
"""

import argparse
import contextlib
import csv
import io
import json
import math
import pathlib
import re
import subprocess
import sys


def block(readme, language):
    m = re.search(r"^```%s\n(.*?)^```" % language, readme, re.S | re.M)
    if not m:
        sys.exit("readme_examples: README.md has no ```%s block" % language)
    return m.group(1)


def finger_tip(p, area, r2, E, radius, length):
    """Tip of a clamped circular rod along x curled by a chamber at (r2, 0): exact."""
    EA = E * math.pi * radius ** 2
    EI = E * math.pi * radius ** 4 / 4
    gamma1 = p * area / EA
    kappa3 = -p * area * r2 / EI
    if kappa3 == 0:
        return (1 + gamma1) * length, 0.0
    return ((1 + gamma1) * math.sin(kappa3 * length) / kappa3,
            (1 + gamma1) * (1 - math.cos(kappa3 * length)) / kappa3)


def check_scene(args, readme):
    text = block(readme, "yaml")
    work = args.work / "scene"
    work.mkdir(parents=True, exist_ok=True)
    scene = work / "finger.yaml"
    scene.write_text(text)
    # The scene's numbers, read from the text so that the check follows an edit of the README.
    def number(key):
        m = re.search(r"\b%s:\s*([-0-9.e]+)" % key, text)
        if not m:
            sys.exit("readme_examples: no '%s' in the README's scene" % key)
        return float(m.group(1))
    offset = re.search(r"offset:\s*\[([^\]]*)\]", text).group(1).split(",")
    r2 = float(offset[0])
    E, radius, area, p = number("E"), number("radius"), number("area"), number("pressure")
    tip_point = re.search(r"TIP:\s*\[([^\]]*)\]", text).group(1).split(",")
    length = float(tip_point[0])
    expected = finger_tip(p, area, r2, E, radius, length)
    worst = 0.0
    for elements in (None, 1):
        out = work / ("out" if elements is None else "out_1")
        cmd = [args.screwfem, "run", str(scene), "-o", str(out), "--force", "--quiet"]
        if elements is not None:
            cmd += ["--set", "bodies.finger.elements=%d" % elements]
        run = subprocess.run(cmd, capture_output=True, text=True)
        if run.returncode != 0:
            sys.exit("readme_examples: %s failed (%d):\n%s%s" % (" ".join(cmd), run.returncode,
                                                                 run.stdout, run.stderr))
        summary = json.loads((out / "summary.json").read_text())
        if summary.get("status") != "completed":
            sys.exit("readme_examples: status %r, expected 'completed'" % summary.get("status"))
        with open(out / "points.csv") as f:
            rows = list(csv.DictReader(f))
        last = rows[-1]
        tip = (float(last["tip.x"]), float(last["tip.y"]), float(last["tip.z"]))
        error = math.dist(tip, (expected[0], expected[1], 0.0))
        print("elements %s: tip (%.9f, %.9f, %.1e) m, closed form (%.9f, %.9f, 0), error %.2e m"
              % (elements or "as written", *tip, *expected, error))
        worst = max(worst, error)
    # The README's typo: the first ' section: ' misspelt, the message it quotes, exactly.
    quoted = re.search(r"`(error: finger\.yaml:[^`]*)`", readme, re.S)
    if not quoted:
        sys.exit("readme_examples: README.md quotes no 'error: finger.yaml:...' message")
    typo_dir = work / "typo"
    typo_dir.mkdir(exist_ok=True)
    (typo_dir / "finger.yaml").write_text(text.replace(" section: ", " sectoin: ", 1))
    run = subprocess.run([args.screwfem, "run", "finger.yaml", "-o", "out"], cwd=typo_dir,
                         capture_output=True, text=True)
    message = " ".join(quoted.group(1).split())
    if run.returncode != 2 or run.stderr.strip() != message:
        sys.exit("readme_examples: FAILED: the misspelt scene gave exit status %d and\n  %s\n"
                 "the README says exit status 2 and\n  %s" % (run.returncode, run.stderr.strip(),
                                                              message))
    if (typo_dir / "out").exists():
        sys.exit("readme_examples: FAILED: the misspelt scene wrote its output folder")
    print("typo: %s" % message)
    if worst > 1e-7:
        sys.exit("readme_examples: FAILED: the tip is %.2e m off the closed form (limit 1e-7 m)"
                 % worst)
    print("readme_scene: passed")


def check_python(args, readme):
    code = block(readme, "python")
    work = args.work / "python"
    work.mkdir(parents=True, exist_ok=True)
    namespace = {"__name__": "__readme__"}
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        exec(compile(code, "README.md (python block)", "exec"), namespace)
    print(printed.getvalue(), end="")
    # The line the README says it prints, to its digits (the controller's end state).
    line = r"tip height ([0-9.]+) m at p = ([0-9]+) Pa"
    quoted, got = re.search("`" + line + "`", readme), re.search(line, printed.getvalue())
    if not quoted or not got:
        sys.exit("readme_examples: FAILED: no 'tip height ... m at p = ... Pa' line in %s"
                 % ("the README" if not quoted else "the program's output"))
    if abs(float(quoted[1]) - float(got[1])) > 1e-5 or \
            abs(float(quoted[2]) - float(got[2])) > 1e-3 * float(quoted[2]):
        sys.exit("readme_examples: FAILED: the program printed '%s', the README says '%s'"
                 % (got[0], quoted[0][1:-1]))
    sim, target = namespace["sim"], namespace["target"]
    tip = sim.point_motion("tip")
    height, speed = tip.position[1], math.hypot(*tip.velocity)
    pressure = sim.inputs["p"]
    # The static pressure for that tip height, by bisection on the closed form (the README's
    # rod: E 1e6 Pa, radius 0.01 m, length 0.1 m, chamber 5e-5 m^2 at r2 = -0.005 m).
    # The height rises monotonically with p until the finger has curled through pi.
    lo, hi = 0.0, math.pi * (1e6 * math.pi * 0.01 ** 4 / 4) / (5e-5 * 0.005 * 0.1)
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if finger_tip(mid, 5e-5, -0.005, 1e6, 0.01, 0.1)[1] < target:
            lo = mid
        else:
            hi = mid
    static = 0.5 * (lo + hi)
    print("tip height %.6f m (target %.3f), speed %.2e m/s; pressure %.1f Pa, statics %.1f Pa "
          "(%.3f %%)" % (height, target, speed, pressure, static,
                         100 * (pressure - static) / static))
    if abs(height - target) > 1e-4 or speed > 1e-3:
        sys.exit("readme_examples: FAILED: the tip did not settle on its target")
    if abs(pressure - static) > 0.005 * static:
        sys.exit("readme_examples: FAILED: the settled pressure is not the static one")
    print("readme_python: passed")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("part", choices=["scene", "python"])
    parser.add_argument("--source", type=pathlib.Path, required=True)
    parser.add_argument("--screwfem")
    parser.add_argument("--work", type=pathlib.Path, required=True)
    args = parser.parse_args()
    if args.screwfem:
        args.screwfem = str(pathlib.Path(args.screwfem).resolve())
    readme = (args.source / "README.md").read_text(encoding="utf-8")
    if args.part == "scene":
        check_scene(args, readme)
    else:
        check_python(args, readme)


if __name__ == "__main__":
    main()
