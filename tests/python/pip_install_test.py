#!/usr/bin/python3
"""The Python package installs with Debian's pip from the source tree and works from anywhere.

    /usr/bin/python3 tests/python/pip_install_test.py --source SRC --build BUILD

(ctest `python_pip_install`). In BUILD/pip-install-test: creates a virtual environment with
the system site packages (Debian's numpy), runs
``pip install --no-build-isolation --no-index --config-settings build-dir=BUILD SRC``, which
builds the wheel with the in-tree backend (python/packaging/screwfem_wheel.py) reusing the
build tree BUILD (its _screwfem target is up to date, so nothing is compiled again), then from
a fresh directory outside both trees imports screwfem with the environment's interpreter,
runs tests/data/pendulum.yaml for 1.3 s and checks the physics in the written tables:

  * the package and its extension come from the environment's site-packages, not from the
    source or build tree's python/ directories;
  * the compound pendulum released from the horizontal conserves its energy to 2e-5 of
    m g d (generalized-alpha with rho_inf = 0.9 damps only unresolved high frequencies);
  * it first passes the vertical at a quarter of the period of the large-amplitude
    pendulum, T/4 = K(sin 45 deg) sqrt(I_O / (m g d)), to 1e-5 relative (O(h^2) error).

Exit status 0 on success, 1 on a failed check or step (the output says which).
"""

import argparse
import os
import pathlib
import shutil
import subprocess
import sys
import tempfile
import venv

CHECK = r'''
import csv, math, os, pathlib, sys, sysconfig
import screwfem

where = pathlib.Path(screwfem.__file__).resolve()
ext = pathlib.Path(screwfem._screwfem.__file__).resolve()
site = pathlib.Path(sysconfig.get_paths()["platlib"]).resolve()
for p in (where, ext):
    assert site in p.parents, f"{p} is not in the environment's site-packages {site}"
    for tree in (pathlib.Path(SOURCE) / "python", pathlib.Path(BUILD) / "python"):
        assert tree.resolve() not in p.parents, f"{p} comes from {tree}"
print("imported", where, "version", screwfem.__version__)

scene = screwfem.load_scene(SCENE, ["analysis.end_time=1.3", "outputs.interval=0",
                                    "outputs.vtk_interval=0.1"])
r = screwfem.run_scene(scene, "run")
assert r.ok, r.message
body = scene.model.bodies[0]
m, com = body.mass, list(body.com)
g = 9.81
d = math.hypot(com[0], com[2])          # pivot to centre of mass [m]
I_O = body.inertia[1][1] + m * d * d    # about the hinge axis y [kg m^2]

with open("run/points.csv") as f:
    rows = [{k: float(v) for k, v in row.items()} for row in csv.DictReader(f)]
L = math.hypot(rows[0]["tip.x"], rows[0]["tip.z"])
def energy(row):
    speed2 = row["tip.vx"] ** 2 + row["tip.vy"] ** 2 + row["tip.vz"] ** 2
    return 0.5 * I_O * speed2 / (L * L) + m * g * row["tip.z"] * d / L
e0, scale = energy(rows[0]), m * g * d
drift = max(abs(energy(row) - e0) for row in rows) / scale
print(f"energy drift {drift:.2e} m g d over {rows[-1]['t']:.2f} s ({len(rows)} rows)")
assert drift < 2e-5, drift

# First passage through the vertical: tip.x changes sign (linear interpolation).
for a, b in zip(rows, rows[1:]):
    if a["tip.x"] > 0.0 >= b["tip.x"]:
        quarter = a["t"] + (b["t"] - a["t"]) * a["tip.x"] / (a["tip.x"] - b["tip.x"])
        break
else:
    raise AssertionError("the pendulum never reached the vertical")
# K(k) by the arithmetic-geometric mean: K = pi / (2 agm(1, sqrt(1 - k^2))), k = sin(45 deg).
x, y = 1.0, math.sqrt(0.5)
for _ in range(8):  # quadratic convergence: full precision after 5
    x, y = 0.5 * (x + y), math.sqrt(x * y)
exact = math.pi / (2.0 * x) * math.sqrt(I_O / (m * g * d))
print(f"quarter period {quarter:.8f} s, exact {exact:.8f} s")
assert abs(quarter - exact) < 1e-5 * exact, (quarter, exact)
print("pip install check: ok")
'''


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--source", required=True, help="the source tree (holds pyproject.toml)")
    parser.add_argument("--build", required=True, help="a configured build tree to reuse")
    args = parser.parse_args()
    source = pathlib.Path(args.source).resolve()
    build = pathlib.Path(args.build).resolve()
    work = build / "pip-install-test"
    shutil.rmtree(work, ignore_errors=True)
    env_dir = work / "venv"
    print(f"creating {env_dir}", flush=True)
    venv.EnvBuilder(system_site_packages=True, with_pip=False, symlinks=True).create(env_dir)
    python = env_dir / "bin" / "python"
    # Debian's pip (python3-pip) runs inside the environment as a module of the system site
    # packages: no ensurepip wheel and no download.
    # No pip configuration of the machine or the user (index URLs, find-links): --no-index
    # and the source tree only.
    env = {k: v for k, v in os.environ.items()
           if not k.startswith("PIP_") and k not in ("PYTHONPATH", "SCREWFEM_BUILD_DIR")}
    env.update(PIP_CONFIG_FILE=os.devnull, PIP_DISABLE_PIP_VERSION_CHECK="1",
               PYTHONDONTWRITEBYTECODE="1")
    cmd = [str(python), "-m", "pip", "install", "--no-build-isolation", "--no-index",
           "--config-settings", f"build-dir={build}", str(source)]
    print(" ".join(cmd), flush=True)
    if subprocess.run(cmd, env=env).returncode != 0:
        print("pip install failed", file=sys.stderr)
        return 1
    outside = pathlib.Path(tempfile.mkdtemp(prefix="screwfem_pip_"))
    try:
        for tree in (source, build):
            if tree == outside or tree in outside.parents:
                print(f"{outside} is inside {tree}", file=sys.stderr)
                return 1
        scene = source / "tests" / "data" / "pendulum.yaml"
        code = (f"SOURCE, BUILD, SCENE = {str(source)!r}, {str(build)!r}, {str(scene)!r}\n"
                + CHECK)
        status = subprocess.run([str(python), "-c", code], cwd=outside, env=env).returncode
    finally:
        shutil.rmtree(outside, ignore_errors=True)
    return 0 if status == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
