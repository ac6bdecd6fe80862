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
