"""PEP 517 build backend of the screwfem Python package (pyproject.toml), standard library only.

pip runs it from the source tree (backend-path), offline: nothing is downloaded. build_wheel

  1. chooses a CMake build tree:
       * the one named by the config setting ``build-dir`` (pip: ``--config-settings
         build-dir=DIR``) or the environment variable SCREWFEM_BUILD_DIR;
       * otherwise an existing tree of the source tree that can build the extension: build/main
         (the main job's, scripts/run-main.sh) or build/release (the test job's), when its
         CMakeCache.txt names this source tree, has SCREWFEM_BUILD_PYTHON on, no sanitizers and
         this interpreter's extension suffix; of two, the one whose extension was built last;
       * otherwise ``build/wheel`` in the source tree, configured here in Release without the
         tests, benchmarks and examples (reconfigured, not rebuilt, on the next install).
     An existing tree is built, never reconfigured with other options: its cache is its
     owner's (the test job's next configure keeps its test suite);
  2. builds only the target ``_screwfem`` (the extension and the libraries it links), with
     ``jobs`` (config setting) or SCREWFEM_BUILD_JOBS parallel jobs, default: the CPU count;
  3. packs the wheel with zipfile: the package's Python files from python/screwfem, the
     extension from the build tree, and the .dist-info (METADATA from pyproject.toml's
     [project] table, the version from CMakeLists.txt's project(... VERSION ...)).

The extension is compiled for the interpreter that runs pip (the build tree's must match it:
its file name carries the interpreter's ABI) and, with SCREWFEM_NATIVE=ON (the default), for
the build machine's instruction set: the wheel is for this machine, not for distribution.
No sdist and no editable installs.

pip 23 shows a backend's output (stdout and stderr, one pipe) only with ``pip install -v`` or
when the build fails; without -v it shows a spinner. So the one line that says where the
extension is built, how many files are to be compiled and about how long that takes goes to
the terminal (/dev/tty) when there is one, else to stderr; the build's progress lines (make's
``[ 45%] Building CXX object ...``, ninja's ``[12/17] ...``) go to stderr, which
``pip install -v`` shows as they come.
"""

import base64
import hashlib
import importlib.machinery
import json
import os
import pathlib
import re
import shutil
import subprocess
import sys
import sysconfig
import time
import tomllib
import zipfile

_SOURCE = pathlib.Path(__file__).resolve().parents[2]
_TARGET = "_screwfem"
# Existing build trees of the source tree that an install reuses, in order of preference when
# none holds a built extension: the main job's and the test job's (docs/getting-started.md).
_REUSABLE = ("build/main", "build/release")
# CPU seconds of one translation unit of the _screwfem target and the libraries it links, for
# the announcement's estimate: a clean build/wheel compiles 17 (12 of the libraries, 5 of the
# module) in 360 CPU-s (GCC 12).
_SECONDS_PER_UNIT = 21.0


class BuildError(RuntimeError):
    """A build step that failed (the message says which and how to fix it)."""


def _log(message):
    print(f"screwfem_wheel: {message}", file=sys.stderr, flush=True)


def _announce(message):
    """Writes `message` where the user sees it: the terminal when there is one (pip shows the
    backend's stderr only with -v), else stderr."""
    line = f"screwfem: {message}\n"
    try:
        with open("/dev/tty", "w") as tty:
            # A line of its own: pip's spinner line ("Building wheel ... ") has no newline yet.
            tty.write("\n" + line)
            return
    except OSError:  # no controlling terminal (CI, ctest, cron)
        pass
    sys.stderr.write(line)
    sys.stderr.flush()


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


def _cache(build):
    """The entries of BUILD/CMakeCache.txt as {name: value}; {} when there is none."""
    entries = {}
    try:
        text = (pathlib.Path(build) / "CMakeCache.txt").read_text(errors="replace")
    except OSError:
        return entries
    for line in text.splitlines():
        m = re.match(r"([^#/\s][^:=]*)(?::[A-Z]+)?=(.*)$", line)
        if m:
            entries[m.group(1)] = m.group(2)
    return entries


def _cmake_true(value):
    """CMake's if(<constant>) of a cache value: ON, YES, TRUE, Y or a non-zero number."""
    value = (value or "").strip().upper()
    if value in ("ON", "YES", "TRUE", "Y"):
        return True
    try:
        return float(value) != 0.0
    except ValueError:
        return False


def unusable_reason(build, source=None):
    """Why the CMake build tree BUILD cannot build the extension of SOURCE (default: this
    source tree) for this interpreter, or None when it can. Only its cache is read."""
    build = pathlib.Path(build)
    source = pathlib.Path(source or _SOURCE).resolve()
    cache = _cache(build)
    if not cache:
        return "not a configured CMake build tree (no CMakeCache.txt)"
    home = cache.get("CMAKE_HOME_DIRECTORY", "")
    if not home or pathlib.Path(home).resolve() != source:
        return f"configured from another source tree ({home or 'unknown'})"
    if not _cmake_true(cache.get("SCREWFEM_BUILD_PYTHON", "ON")):
        return "configured without the Python module (SCREWFEM_BUILD_PYTHON=OFF)"
    if _cmake_true(cache.get("SCREWFEM_SANITIZE")):
        return "a sanitizer build (SCREWFEM_SANITIZE=ON), which has no Python module"
    suffix = cache.get("PYTHON_MODULE_EXTENSION")
    if suffix and suffix != sysconfig.get_config_var("EXT_SUFFIX"):
        return (f"configured for another Python (extension suffix {suffix}, this interpreter's "
                f"{sysconfig.get_config_var('EXT_SUFFIX')})")
    if not (build / "python" / "CMakeFiles" / f"{_TARGET}.dir").is_dir():
        return f"has no {_TARGET} target (configure it again with cmake)"
    return None


def _built_extension_mtime(build):
    times = [p.stat().st_mtime for p in (build / "python" / "screwfem").glob(_TARGET + ".*")]
    return max(times, default=None)


def find_build_tree(source=None, candidates=_REUSABLE):
    """The existing build tree an install reuses: of the trees `candidates` (relative to
    SOURCE) that can build the extension (unusable_reason), the one whose extension was built
    last, else the first. Returns (tree or None, [(tree, reason it was passed over)])."""
    source = pathlib.Path(source or _SOURCE).resolve()
    usable, skipped = [], []
    for name in candidates:
        build = source / name
        if not build.exists():
            continue
        reason = unusable_reason(build, source)
        if reason:
            skipped.append((build, reason))
        else:
            usable.append(build)
    if not usable:
        return None, skipped
    built = [b for b in usable if _built_extension_mtime(b) is not None]
    if built:
        return max(built, key=_built_extension_mtime), skipped
    return usable[0], skipped


def _run(cmd):
    _log(" ".join(str(c) for c in cmd))
    try:
        subprocess.run([str(c) for c in cmd], check=True, stdout=sys.stderr)
    except FileNotFoundError as e:
        raise BuildError(f"cannot run {cmd[0]}: {e} (install cmake: scripts/setup-deps.sh)") from e
    except subprocess.CalledProcessError as e:
        raise BuildError(f"{' '.join(str(c) for c in cmd)} failed with status "
                         f"{e.returncode}") from e


def _depfile_paths(text):
    """The prerequisites of a compiler's depfile (make syntax: 'obj: a b \\' lines)."""
    text = text.replace("\\\n", " ")
    paths = []
    for line in text.splitlines():
        _, sep, deps = line.partition(": ")
        if sep:
            paths += deps.split()
    return paths


def _ninja_deps(build):
    """{object: [prerequisites]} from ninja's deps log (ninja reads and deletes the compiler's
    depfiles), paths absolute; {} without ninja."""
    ninja = _cache(build).get("CMAKE_MAKE_PROGRAM") or "ninja"
    try:
        out = subprocess.run([ninja, "-C", str(build), "-t", "deps"], capture_output=True,
                             text=True, check=True).stdout
    except (OSError, subprocess.CalledProcessError):
        return {}
    deps, current = {}, None
    for line in out.splitlines():
        if line.startswith("    ") and current is not None:
            current.append(build / line.strip())
        elif ": #deps" in line:
            current = deps.setdefault(build / line.split(": #deps")[0], [])
        else:
            current = None
    return deps


def _units_to_compile(build):
    """How many translation units building _screwfem compiles in BUILD: those of the module
    and of the libraries (src/) in compile_commands.json whose object is missing or older than
    a file it was compiled from (the compiler's depfile, or ninja's deps log): the generator's
    own test, less changes of flags. None when BUILD has no compile_commands.json."""
    try:
        entries = json.loads((build / "compile_commands.json").read_text())
    except (OSError, ValueError):
        return None
    ninja_deps = _ninja_deps(build) if (build / "build.ninja").is_file() else None
    mtimes = {}

    def mtime(path):
        if path not in mtimes:
            try:
                mtimes[path] = os.stat(path).st_mtime_ns
            except OSError:
                mtimes[path] = None
        return mtimes[path]

    closure = (build / "src" / "CMakeFiles", build / "python" / "CMakeFiles" / f"{_TARGET}.dir")
    units = 0
    for entry in entries:
        directory = pathlib.Path(entry.get("directory", build))
        m = re.search(r"\s-o\s+(\S+)", entry.get("command", ""))
        output = directory / m.group(1) if m else None
        if not output or not any(d in output.parents for d in closure):
            continue
        if ninja_deps is not None:
            deps = ninja_deps.get(output)
        else:
            try:
                text = pathlib.Path(f"{output}.d").read_text(errors="replace")
                deps = [directory / d for d in _depfile_paths(text)]
            except OSError:
                deps = None
        obj = mtime(output)
        if obj is None or not deps or any((t := mtime(d)) is None or t > obj for d in deps):
            units += 1
    return units


def _minutes(seconds):
    return f"{seconds / 60:.0f} min" if seconds >= 90 else f"{seconds:.0f} s"


def _build_extension(config_settings):
    """Builds _screwfem and returns the directory holding it (BUILD/python/screwfem)."""
    jobs = _setting(config_settings, "jobs", "SCREWFEM_BUILD_JOBS") or str(os.cpu_count() or 1)
    given = _setting(config_settings, "build-dir", "SCREWFEM_BUILD_DIR")
    if given:
        build = pathlib.Path(given).resolve()
        reason = unusable_reason(build)
        if reason:
            raise BuildError(f"{build}: {reason}; name another tree, or leave build-dir and "
                             "SCREWFEM_BUILD_DIR unset to let the backend choose one")
        _log(f"reusing the build tree {build} (named by build-dir or SCREWFEM_BUILD_DIR)")
    else:
        build, skipped = find_build_tree()
        for tree, reason in skipped:
            _log(f"not reusing {tree}: {reason}")
        if build:
            _log(f"reusing the build tree {build}")
        else:
            build = _SOURCE / "build" / "wheel"
            _log(f"building in {build}")
            _run(["cmake", "-S", _SOURCE, "-B", build, "-DCMAKE_BUILD_TYPE=Release",
                  "-DSCREWFEM_BUILD_TESTS=OFF", "-DSCREWFEM_BUILD_BENCH=OFF",
                  "-DSCREWFEM_BUILD_EXAMPLES=OFF", "-DSCREWFEM_BUILD_PYTHON=ON",
                  "-DSCREWFEM_SANITIZE=OFF", f"-DPython3_EXECUTABLE={sys.executable}"])
    units = _units_to_compile(build)
    cores = max(1, min(int(jobs), os.cpu_count() or 1))
    if units == 0:
        _announce(f"the extension in {build} is up to date")
    elif units:
        estimate = _minutes(units * _SECONDS_PER_UNIT / min(cores, units))
        files = "1 file" if units == 1 else f"{units} files"
        _announce(f"building the extension in {build}: {files} to compile, about {estimate} "
                  f"on {cores} cores (pip install -v shows the progress)")
    else:
        _announce(f"building the extension in {build} (pip install -v shows the progress)")
    start = time.monotonic()
    _run(["cmake", "--build", build, "--target", _TARGET, "--parallel", jobs])
    if units != 0:
        _announce(f"built the extension in {_minutes(time.monotonic() - start)}")
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
    # The viewer's files, for Simulation.view (screwfem/_live.py looks in screwfem/_viewer).
    for rel in ("screwfem_view.py", "screwfem_vtk.py", "viewer/viewer.html", "viewer/viewer.js"):
        files.append((f"screwfem/_viewer/{rel}", (_SOURCE / "tools" / rel).read_bytes()))
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
