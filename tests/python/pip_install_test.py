#!/usr/bin/python3
"""The Python package installs with Debian's pip from the source tree and works from anywhere.

    /usr/bin/python3 tests/python/pip_install_test.py --source SRC --build BUILD

(ctest `python_pip_install`). First checks the backend's choice of a build tree
(python/packaging/screwfem_wheel.py, find_build_tree) on fake build trees: a tree is reused
only when its cache names this source tree, has the Python module and this interpreter's
extension suffix; of two, the one whose extension was built last. Then, in
BUILD/pip-install-test, creates a virtual environment with the system site packages (Debian's
numpy) and runs ``pip install -v --no-build-isolation --no-index SRC``, which builds the wheel
with the in-tree backend reusing the build tree BUILD: found by the backend itself when BUILD is
the tree it would choose (SRC/build/main or SRC/build/release), else named with
``--config-settings build-dir=BUILD``. The backend's log must name BUILD, and BUILD's extension
must not have been rebuilt (its modification time is unchanged: BUILD was built before).
Then, from a fresh directory outside both trees, imports screwfem with the environment's
interpreter, runs tests/data/pendulum.yaml for 1.3 s and checks the physics in the written
tables:

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
import sysconfig
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


def fake_tree(source, name, python="ON", home=None, suffix=None, built=None):
    """A build tree SOURCE/NAME with just what the backend reads: the cache, the target's
    directory and, when `built` is a time, the extension with that modification time."""
    tree = source / name
    (tree / "python" / "CMakeFiles" / "_screwfem.dir").mkdir(parents=True)
    suffix = suffix or sysconfig.get_config_var("EXT_SUFFIX")
    (tree / "CMakeCache.txt").write_text(
        f"CMAKE_HOME_DIRECTORY:INTERNAL={home or source}\n"
        f"SCREWFEM_BUILD_PYTHON:BOOL={python}\nSCREWFEM_SANITIZE:BOOL=OFF\n"
        f"PYTHON_MODULE_EXTENSION:INTERNAL={suffix}\n")
    if built is not None:
        ext = tree / "python" / "screwfem" / f"_screwfem{suffix}"
        ext.parent.mkdir(parents=True)
        ext.write_bytes(b"")
        os.utime(ext, (built, built))
    return tree


def check_tree_choice(backend):
    """find_build_tree on fake trees: which one is reused, and why the others are not."""
    ok = True

    def expect(what, got, want):
        nonlocal ok
        print(f"tree choice, {what}: {got}", flush=True)
        if got != want:
            print(f"  expected {want}", file=sys.stderr)
            ok = False

    with tempfile.TemporaryDirectory(prefix="screwfem_trees_") as tmp:
        tmp = pathlib.Path(tmp).resolve()
        cases = {
            "main without the module, release usable": (
                [("build/main", dict(python="OFF", built=2.0)), ("build/release", {})],
                "build/release"),
            "both usable, release built last": (
                [("build/main", dict(built=1.0)), ("build/release", dict(built=2.0))],
                "build/release"),
            "both usable, main built last": (
                [("build/main", dict(built=2.0)), ("build/release", dict(built=1.0))],
                "build/main"),
            "both usable, neither built": (
                [("build/main", {}), ("build/release", {})], "build/main"),
            "another source tree, another Python": (
                [("build/main", dict(home=tmp)), ("build/release", dict(suffix=".cpython-39.so"))],
                None),
        }
        for i, (what, (trees, want)) in enumerate(cases.items()):
            source = tmp / str(i)
            for name, options in trees:
                fake_tree(source, name, **options)
            chosen, skipped = backend.find_build_tree(source)
            got = str(chosen.relative_to(source)) if chosen else None
            expect(what, got, want)
            for tree, reason in skipped:
                print(f"  not reusing {tree.relative_to(source)}: {reason}")
    return ok


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--source", required=True, help="the source tree (holds pyproject.toml)")
    parser.add_argument("--build", required=True, help="a configured build tree to reuse")
    args = parser.parse_args()
    source = pathlib.Path(args.source).resolve()
    build = pathlib.Path(args.build).resolve()
    sys.path.insert(0, str(source / "python" / "packaging"))
    import screwfem_wheel as backend  # the in-tree build backend

    if not check_tree_choice(backend):
        print("the backend chose the wrong build tree", file=sys.stderr)
        return 1
    reason = backend.unusable_reason(build, source)
    if reason:
        print(f"{build}: {reason}", file=sys.stderr)
        return 1
    built = sorted((build / "python" / "screwfem").glob("_screwfem.*"))
    if not built:
        print(f"{build}: no extension built (build the tree before the test)", file=sys.stderr)
        return 1
    mtimes = {p: p.stat().st_mtime_ns for p in built}

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
    cmd = [str(python), "-m", "pip", "install", "-v", "--no-build-isolation", "--no-index"]
    chosen, _ = backend.find_build_tree(source)
    if chosen == build:
        print(f"the backend finds {build} itself", flush=True)
    else:
        print(f"the backend would choose {chosen or 'build/wheel'}: naming {build}", flush=True)
        cmd += ["--config-settings", f"build-dir={build}"]
    cmd.append(str(source))
    print(" ".join(cmd), flush=True)
    # -v: pip shows the backend's output (else only on failure); kept to check its log. A
    # session of its own, without a controlling terminal: the backend's line for the user
    # goes to its stderr, into this log, not to the terminal ctest runs in.
    pip = subprocess.run(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                         text=True, start_new_session=True)
    print(pip.stdout, flush=True)
    if pip.returncode != 0:
        print("pip install failed", file=sys.stderr)
        return 1
    if f"screwfem_wheel: reusing the build tree {build}" not in pip.stdout:
        print(f"the backend's log does not say that it reused {build}", file=sys.stderr)
        return 1
    rebuilt = [p.name for p, t in mtimes.items() if not p.exists() or p.stat().st_mtime_ns != t]
    if rebuilt:
        print(f"pip install rebuilt {', '.join(rebuilt)} in {build}: the tree was not up to "
              "date, or the install did not reuse it as it was", file=sys.stderr)
        return 1
    print(f"reused {build}: nothing rebuilt", flush=True)

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
