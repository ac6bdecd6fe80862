"""Executes one tutorial notebook (docs/tutorials/*.ipynb) as the ctest tests tutorial_* do.

    /usr/bin/python3 tests/tutorials/run_notebook.py NOTEBOOK --output-dir DIR

runs Debian's `jupyter-nbconvert --to notebook --execute` on NOTEBOOK and writes the executed
copy, with its outputs and figures, to DIR/<name>/<name>.ipynb. A cell that raises (the last
cell of every tutorial asserts a physical result) makes nbconvert, and so this script, exit
non-zero; the failing cell's traceback is printed.

The kernel is Debian's interpreter, whatever `python3` comes first on PATH or in another
Jupyter data directory: the script writes a `python3` kernelspec whose argv starts with
/usr/bin/python3 into DIR/<name>/jupyter/kernels and puts that directory first on
JUPYTER_PATH, then checks that jupyter_client resolves `python3` to it. The user's Jupyter,
IPython and matplotlib configuration is kept out (JUPYTER_CONFIG_DIR, IPYTHONDIR, MPLCONFIGDIR
in DIR/<name>), so a startup script in ~/.ipython cannot change a result.

The notebook finds the repository from SCREWFEM_SOURCE_DIR and the `screwfem` package from
PYTHONPATH (both set by the test, tests/tutorials/CMakeLists.txt) and writes its run outputs to
SCREWFEM_TUTORIAL_OUTDIR, which this script sets to DIR/<name>/run (emptied first): nothing is
written into the source tree.
"""

import argparse
import json
import os
import pathlib
import shutil
import subprocess
import sys
import time

PYTHON = "/usr/bin/python3"
NBCONVERT = "/usr/bin/jupyter-nbconvert"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("notebook", type=pathlib.Path)
    parser.add_argument("--output-dir", type=pathlib.Path, required=True)
    parser.add_argument("--timeout", type=int, default=600, help="seconds per cell")
    args = parser.parse_args()

    if not os.access(NBCONVERT, os.X_OK):
        print(f"run_notebook: {NBCONVERT} not found: install Debian's jupyter-nbconvert and "
              "python3-ipykernel (scripts/setup-deps.sh rest)", file=sys.stderr)
        return 1
    notebook = args.notebook.resolve()
    name = notebook.stem
    work = args.output_dir.resolve() / name
    shutil.rmtree(work, ignore_errors=True)
    jupyter = work / "jupyter"
    kernel_dir = jupyter / "kernels" / "python3"
    kernel_dir.mkdir(parents=True)
    (kernel_dir / "kernel.json").write_text(json.dumps({
        "argv": [PYTHON, "-m", "ipykernel_launcher", "-f", "{connection_file}",
                 "--InteractiveShell.colors=NoColor"],  # plain tracebacks in the log
        "display_name": "Python 3 (Debian)",
        "language": "python",
    }, indent=1) + "\n")
    run_dir = work / "run"
    run_dir.mkdir()

    env = dict(os.environ)
    env["JUPYTER_PATH"] = str(jupyter)  # searched first: this kernelspec wins
    env["JUPYTER_CONFIG_DIR"] = str(jupyter / "config")
    env["JUPYTER_RUNTIME_DIR"] = str(jupyter / "runtime")
    env["IPYTHONDIR"] = str(jupyter / "ipython")
    env["MPLCONFIGDIR"] = str(jupyter / "matplotlib")
    env["SCREWFEM_TUTORIAL_OUTDIR"] = str(run_dir)
    env.setdefault("PYTHONDONTWRITEBYTECODE", "1")
    env["PYDEVD_DISABLE_FILE_VALIDATION"] = "1"  # the kernel's debugger: no frozen-module notice

    resolve = subprocess.run(
        [PYTHON, "-c", "from jupyter_client.kernelspec import KernelSpecManager as M; "
         "print(M().get_kernel_spec('python3').argv[0])"],
        env=env, capture_output=True, text=True)
    if resolve.returncode != 0 or resolve.stdout.strip() != PYTHON:
        print(f"run_notebook: kernelspec 'python3' resolves to {resolve.stdout.strip()!r}, not "
              f"{PYTHON}\n{resolve.stderr}", file=sys.stderr)
        return 1

    command = [NBCONVERT, "--to", "notebook", "--execute",
               "--ExecutePreprocessor.kernel_name=python3",
               f"--ExecutePreprocessor.timeout={args.timeout}",
               "--output-dir", str(work), str(notebook)]
    print(" ".join(command), flush=True)
    start = time.monotonic()
    status = subprocess.run(command, env=env).returncode
    seconds = time.monotonic() - start
    if status == 0:
        print(f"{name}: executed in {seconds:.1f} s; executed copy {work / (name + '.ipynb')}, "
              f"run outputs in {run_dir}", flush=True)
    else:
        print(f"{name}: FAILED after {seconds:.1f} s (exit status {status}; the failing cell's "
              f"traceback is above); run outputs in {run_dir}", flush=True)
    return status


if __name__ == "__main__":
    sys.exit(main())
