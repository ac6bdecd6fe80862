"""PEP 517 build backend of the screwfem Python package (pyproject.toml), standard library only.

pip runs it from the source tree (backend-path), offline: nothing is downloaded. build_wheel

  1. chooses a CMake build tree:
       * an existing one, when told so by the config setting ``build-dir`` (pip:
         ``--config-settings build-dir=DIR``) or the environment variable SCREWFEM_BUILD_DIR;
         it is built, not reconfigured (so the test suite's tree is reused as it is);
       * otherwise ``build/wheel`` in the source tree, configured here in Release without the
         tests, benchmarks and examples (reconfigured, not rebuilt, on the next install);
  2. builds only the target ``_screwfem`` (the extension and the libraries it links), with
     ``jobs`` (config setting) or SCREWFEM_BUILD_JOBS parallel jobs, default: the CPU count;
  3. packs the wheel with zipfile: the package's Python files from python/screwfem, the
     extension from the build tree, and the .dist-info (METADATA from pyproject.toml's
     [project] table, the version from CMakeLists.txt's project(... VERSION ...)).

The extension is compiled for the interpreter that runs pip (the build tree's must match it:
its file name carries the interpreter's ABI) and, with SCREWFEM_NATIVE=ON (the default), for
the build machine's instruction set: the wheel is for this machine, not for distribution.
No sdist and no editable installs.
"""

import base64
import hashlib
import importlib.machinery
import os
import pathlib
import re
import shutil
import subprocess
import sys
import sysconfig
import tomllib
import zipfile

_SOURCE = pathlib.Path(__file__).resolve().parents[2]
_TARGET = "_screwfem"


class BuildError(RuntimeError):
    """A build step that failed (the message says which and how to fix it)."""


def _log(message):
    print(f"screwfem_wheel: {message}", file=sys.stderr, flush=True)


def _setting(config_settings, key, env):
    value = (config_settings or {}).get(key)
    if isinstance(value, list):  # pip passes a repeated setting as a list
        value = value[-1]
    return value or os.environ.get(env) or None


def _project():
    """(name, version, [project] table)."""
    with open(_SOURCE / "pyproject.toml", "rb") as f:
        project = tomllib.load(f)["project"]
    text = (_SOURCE / "CMakeLists.txt").read_text()
    m = re.search(r"project\(\s*screwfem\s+VERSION\s+([0-9][0-9.]*)", text)
    if not m:
        raise BuildError(f"{_SOURCE / 'CMakeLists.txt'}: no project(screwfem VERSION ...) line")
    return project["name"], m.group(1), project


def _run(cmd):
    _log(" ".join(str(c) for c in cmd))
    try:
        subprocess.run([str(c) for c in cmd], check=True, stdout=sys.stderr)
    except FileNotFoundError as e:
        raise BuildError(f"cannot run {cmd[0]}: {e} (install cmake: scripts/setup-deps.sh)") from e
    except subprocess.CalledProcessError as e:
        raise BuildError(f"{' '.join(str(c) for c in cmd)} failed with status {e.returncode}") from e


def _build_extension(config_settings):
    """Builds _screwfem and returns the directory holding it (BUILD/python/screwfem)."""
    jobs = _setting(config_settings, "jobs", "SCREWFEM_BUILD_JOBS") or str(os.cpu_count() or 1)
    given = _setting(config_settings, "build-dir", "SCREWFEM_BUILD_DIR")
    if given:
        build = pathlib.Path(given).resolve()
        if not (build / "CMakeCache.txt").is_file():
            raise BuildError(f"{build}: not a configured CMake build tree (no CMakeCache.txt); "
                             "configure it first, or leave build-dir and SCREWFEM_BUILD_DIR "
                             "unset to let the backend configure build/wheel")
        _log(f"reusing the build tree {build}")
    else:
        build = _SOURCE / "build" / "wheel"
        _run(["cmake", "-S", _SOURCE, "-B", build, "-DCMAKE_BUILD_TYPE=Release",
              "-DSCREWFEM_BUILD_TESTS=OFF", "-DSCREWFEM_BUILD_BENCH=OFF",
              "-DSCREWFEM_BUILD_EXAMPLES=OFF", "-DSCREWFEM_BUILD_PYTHON=ON",
              "-DSCREWFEM_SANITIZE=OFF", f"-DPython3_EXECUTABLE={sys.executable}"])
    _run(["cmake", "--build", build, "--target", _TARGET, "--parallel", jobs])
    return build / "python" / "screwfem"


def _extension(package_dir):
    """The built extension's path; it must load into this interpreter."""
    suffixes = importlib.machinery.EXTENSION_SUFFIXES
    found = sorted(package_dir.glob(_TARGET + ".*"))
    for path in found:
        if any(path.name == _TARGET + s for s in suffixes):
            return path
    names = ", ".join(p.name for p in found) or "none"
    raise BuildError(f"{package_dir}: no {_TARGET} extension for this interpreter "
                     f"({sys.executable}, suffixes {', '.join(suffixes)}; found: {names}); the "
                     "build tree was configured for another Python or without the bindings "
                     "(SCREWFEM_BUILD_PYTHON=OFF, SCREWFEM_SANITIZE=ON)")


def _tag():
    """py-abi-platform of a wheel holding an extension for this interpreter."""
    impl = sys.implementation.name
    short = {"cpython": "cp"}.get(impl, impl)
    version = f"{sys.version_info.major}{sys.version_info.minor}"
    abi = f"{short}{version}{sys.abiflags}"
    platform = re.sub(r"[-.]", "_", sysconfig.get_platform())
    return f"{short}{version}-{abi}-{platform}"


def _metadata(name, version, project):
    lines = ["Metadata-Version: 2.1", f"Name: {name}", f"Version: {version}",
             f"Summary: {project.get('description', '')}", "License: Apache-2.0"]
    if "requires-python" in project:
        lines.append(f"Requires-Python: {project['requires-python']}")
    for dep in project.get("dependencies", []):
        lines.append(f"Requires-Dist: {dep}")
    for extra, deps in project.get("optional-dependencies", {}).items():
        lines.append(f"Provides-Extra: {extra}")
        for dep in deps:
            lines.append(f'Requires-Dist: {dep}; extra == "{extra}"')
    return "\n".join(lines) + "\n"


def _dist_info(name, version):
    return f"{name}-{version}.dist-info"


def _write_metadata_dir(directory):
    name, version, project = _project()
    info = pathlib.Path(directory) / _dist_info(name, version)
    info.mkdir(parents=True, exist_ok=True)
    (info / "METADATA").write_text(_metadata(name, version, project))
    return info.name


# --- PEP 517 hooks ------------------------------------------------------------------------------

def get_requires_for_build_wheel(config_settings=None):
    return []


def prepare_metadata_for_build_wheel(metadata_directory, config_settings=None):
    return _write_metadata_dir(metadata_directory)


def build_wheel(wheel_directory, config_settings=None, metadata_directory=None):
    name, version, project = _project()
    package_dir = _build_extension(config_settings)
    extension = _extension(package_dir)
    tag = _tag()
    files = [(f"screwfem/{p.name}", p.read_bytes())
             for p in sorted((_SOURCE / "python" / "screwfem").glob("*.py"))]
    files.append((f"screwfem/{extension.name}", extension.read_bytes()))
    info = _dist_info(name, version)
    files += [
        (f"{info}/METADATA", _metadata(name, version, project).encode()),
        (f"{info}/WHEEL", (f"Wheel-Version: 1.0\nGenerator: screwfem_wheel {version}\n"
                           f"Root-Is-Purelib: false\nTag: {tag}\n").encode()),
        (f"{info}/top_level.txt", b"screwfem\n"),
        (f"{info}/LICENSE", (_SOURCE / "LICENSE").read_bytes()),
    ]
    record = []
    for arcname, data in files:
        digest = base64.urlsafe_b64encode(hashlib.sha256(data).digest()).rstrip(b"=").decode()
        record.append(f"{arcname},sha256={digest},{len(data)}")
    record.append(f"{info}/RECORD,,")
    files.append((f"{info}/RECORD", ("\n".join(record) + "\n").encode()))

    wheel_name = f"{name}-{version}-{tag}.whl"
    os.makedirs(wheel_directory, exist_ok=True)
    path = pathlib.Path(wheel_directory) / wheel_name
    tmp = path.with_suffix(".tmp")
    with zipfile.ZipFile(tmp, "w", compression=zipfile.ZIP_DEFLATED) as z:
        for arcname, data in files:
            entry = zipfile.ZipInfo(arcname, date_time=(1980, 1, 1, 0, 0, 0))
            entry.external_attr = 0o644 << 16
            entry.compress_type = zipfile.ZIP_DEFLATED
            z.writestr(entry, data)
    shutil.move(tmp, path)
    _log(f"wrote {path}")
    return wheel_name
