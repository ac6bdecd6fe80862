"""What every benchmark script states about the run: the revision measured and the CPU.

Imported by the scripts of bench/ (run as `/usr/bin/python3 bench/NAME.py`, so this folder is
on the module path)."""
import pathlib
import subprocess

ROOT = pathlib.Path(__file__).resolve().parents[1]


def revision():
    """`git describe --always --dirty` of the repository, or 'unknown'."""
    try:
        return subprocess.run(["git", "describe", "--always", "--dirty"], cwd=ROOT, text=True,
                              capture_output=True, timeout=10).stdout.strip() or "unknown"
    except (OSError, subprocess.SubprocessError):
        return "unknown"


def cpu_model(unknown="unknown"):
    """The 'model name' of /proc/cpuinfo, or `unknown`."""
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return unknown


def append_run(results, section, explanation, text):
    """Appends one run's `text` to the section `section` of bench/RESULTS.md (`results`, a
    pathlib.Path), creating the section with its `explanation` when it is missing
    (bench/make_results.py keeps such sections when it rewrites the file)."""
    body = results.read_text() if results.exists() else "# Benchmark results\n"
    if section not in body:
        body = body.rstrip("\n") + "\n\n" + section + "\n\n" + explanation + "\n"
    results.write_text(body.rstrip("\n") + "\n\n" + text)
