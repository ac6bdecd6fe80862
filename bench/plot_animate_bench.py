#!/usr/bin/python3
"""Benchmark of `screwfem plot --animate` on the gripper: the animation code before issue 33
(tools/screwfem_plot.py at OLD_REVISION, read with `git show`) against the current one. Adds its
results to bench/RESULTS.md (section "Animation of `screwfem plot`", which bench/make_results.py
keeps when it rewrites the file).

    /usr/bin/python3 bench/plot_animate_bench.py [--cli build/release/app/screwfem] [--rounds 3]
        [--no-write]

Runs examples/gripper/gripper.yaml with the screwfem program into a temporary directory (its
ParaView frames: one every 10 ms, 301 over the 3 s), then times `animate(RUN, FIGDIR)` of each
version with its defaults, as `screwfem plot RUN -o FIGDIR --animate` calls it, each in a fresh
/usr/bin/python3 process (the module imported before the clock starts). The two versions run
alternately, the order flipped every round (A B, B A, ...): the speed of the shared machine
drifts by up to 25 % over minutes, so only ratios within a round are compared. Both read the
frames with the current tools/screwfem_vtk.py, so that only the plotting differs. Reported: wall
and CPU time of the call per version and round, the ratios old / new and their medians, and what
each GIF holds (frames, playing time against the 3 s simulated).
"""

import argparse
import datetime
import json
import os
import pathlib
import shutil
import statistics
import subprocess
import sys
import tempfile

from bench_common import revision

ROOT = pathlib.Path(__file__).resolve().parents[1]
RESULTS = ROOT / "bench" / "RESULTS.md"
SECTION = "## Animation of `screwfem plot`"
# The section the Dask benchmark appends its runs to (bench/sweep_bench.py): ours goes before it.
BEFORE = "## Parameter sweeps on Dask"
SCENE = ROOT / "examples" / "gripper" / "gripper.yaml"
# The last revision of tools/screwfem_plot.py before issue 33 (item 4) rewrote the animation.
OLD_REVISION = "6bab20bfb80e765d98a8defd17c60db2890e6262"
PYTHON = "/usr/bin/python3"

CHILD = r"""
import json, sys, time
sys.path.insert(0, sys.argv[1])
import screwfem_plot
t0, c0 = time.perf_counter(), time.process_time()
paths = screwfem_plot.animate(sys.argv[2], sys.argv[3])
print(json.dumps({"wall": time.perf_counter() - t0, "cpu": time.process_time() - c0,
                  "paths": paths}))
"""


def gif_timing(path):
    """(frames, playing time [s]) of a GIF."""
    from PIL import Image

    with Image.open(path) as im:
        total = 0
        for k in range(im.n_frames):
            im.seek(k)
            total += im.info.get("duration", 0)
        return im.n_frames, total / 1000.0


def time_animate(tools, run, figdir):
    """{wall, cpu, paths} of animate(run, figdir) with the screwfem_plot.py in `tools`."""
    shutil.rmtree(figdir, ignore_errors=True)
    os.makedirs(figdir)
    out = subprocess.run([PYTHON, "-c", CHILD, str(tools), str(run), str(figdir)],
                         check=True, capture_output=True, text=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--cli", default=str(ROOT / "build" / "release" / "app" / "screwfem"),
                        help="the screwfem program (default: build/release/app/screwfem)")
    parser.add_argument("--rounds", type=int, default=3, help="rounds of one run each (default 3)")
    parser.add_argument("--no-write", action="store_true", help="print only")
    args = parser.parse_args()

    tmp = pathlib.Path(tempfile.mkdtemp(prefix="screwfem_plot_bench_"))
    try:
        run = tmp / "gripper"
        subprocess.run([args.cli, "run", str(SCENE), "-o", str(run), "-q"], check=True)
        frames = len(list((run / "vtk").glob("frame_*.vtp")))
        versions = {"old": tmp / "old", "new": tmp / "new"}
        for d in versions.values():
            d.mkdir()
            shutil.copy(ROOT / "tools" / "screwfem_vtk.py", d)
        (versions["old"] / "screwfem_plot.py").write_text(subprocess.run(
            ["git", "show", f"{OLD_REVISION}:tools/screwfem_plot.py"], cwd=ROOT, check=True,
            capture_output=True, text=True).stdout)
        shutil.copy(ROOT / "tools" / "screwfem_plot.py", versions["new"])

        load_before = os.getloadavg()
        samples = {"old": [], "new": []}
        gifs = {}
        for r in range(args.rounds):
            order = ["old", "new"] if r % 2 == 0 else ["new", "old"]
            for name in order:
                result = time_animate(versions[name], run, tmp / f"fig_{name}")
                samples[name].append(result)
                gifs[name] = gif_timing(result["paths"][0])
                print(f"round {r + 1} {name}: {result['wall']:.2f} s wall, {result['cpu']:.2f} s CPU",
                      file=sys.stderr)
        load_after = os.getloadavg()
    finally:
        shutil.rmtree(tmp, ignore_errors=True)

    wall = [o["wall"] / n["wall"] for o, n in zip(samples["old"], samples["new"])]
    cpu = [o["cpu"] / n["cpu"] for o, n in zip(samples["old"], samples["new"])]
    stamp = datetime.datetime.now(datetime.timezone.utc).replace(microsecond=0).isoformat()
    lines = [
        f"### {stamp}, revision {revision()}",
        "",
        f"Load average before: {', '.join(f'{x:.2f}' for x in load_before)}; after: "
        f"{', '.join(f'{x:.2f}' for x in load_after)} ({os.cpu_count()} cores). The gripper run: "
        f"{frames} ParaView frames over 3 s.",
        "",
        "| Round | Old wall | New wall | Ratio old / new | Old CPU | New CPU | CPU ratio |",
        "|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for k, (o, n) in enumerate(zip(samples["old"], samples["new"])):
        lines.append(f"| {k + 1} | {o['wall']:.2f} s | {n['wall']:.2f} s | {wall[k]:.1f} | "
                     f"{o['cpu']:.2f} s | {n['cpu']:.2f} s | {cpu[k]:.1f} |")
    (old_frames, old_play), (new_frames, new_play) = gifs["old"], gifs["new"]
    median = statistics.median(wall)
    lines += [
        "",
        f"`animate` is **{median:.0f}x** faster than before in wall time (median of the rounds; "
        f"range {min(wall):.0f} to {max(wall):.0f}), {statistics.median(cpu):.0f}x in CPU time "
        f"(target at least 10x: {'met' if median >= 10.0 else 'NOT met'}). The old GIF: "
        f"{old_frames} frames playing {old_play:.2f} s ({3.0 / old_play:.2f}x real time); the new "
        f"one: {new_frames} frames playing {new_play:.2f} s ({3.0 / new_play:.2f}x real time).",
        "",
    ]
    text = "\n".join(lines)
    print(text)
    if not args.no_write:
        RESULTS.write_text(add_subsection(RESULTS.read_text() if RESULTS.exists() else
                                          "# Benchmark results\n", text))
    return 0 if median >= 10.0 else 1


def add_subsection(body, text):
    """body with `text` at the end of SECTION, which is added (with EXPLANATION) before the Dask
    section, or at the end, when the body does not have it."""
    if SECTION not in body:
        block = SECTION + "\n\n" + EXPLANATION + "\n"
        if BEFORE in body:
            at = body.index(BEFORE)
            body = body[:at] + block + "\n" + body[at:]
        else:
            body = body.rstrip("\n") + "\n\n" + block
    start = body.index(SECTION) + len(SECTION)
    end = body.find("\n## ", start)
    end = len(body) if end < 0 else end + 1
    return body[:end].rstrip("\n") + "\n\n" + text.rstrip("\n") + "\n" + \
        ("\n" + body[end:] if end < len(body) else "")


EXPLANATION = """\
Written by `bench/plot_animate_bench.py` (one subsection per run, added at the end of this
section; `bench/make_results.py` keeps it when it rewrites the file). `screwfem plot --animate`
on `examples/gripper/gripper.yaml` (3 s, a ParaView frame every 10 ms): the animation before
issue 33 (`tools/screwfem_plot.py` at 6bab20b: one GIF frame per ParaView frame at 25 frames
per second, i.e. 0.25x real time; every frame cleared and drawn anew, its 39 joint dots as one
3D scatter each; the figure drawn twice per frame, by the animation and by the writer; a
palette computed per frame) against the current one (real time at 25 frames per second: the
frames nearest to every 40 ms; the scene drawn once and its lines updated per frame, the axes
kept as a background picture; one palette for all frames). Each version's `animate()` call
runs in a fresh `/usr/bin/python3` process, wall and CPU time of the call; the versions
alternate, the order flipped every round, and the ratio is taken per round.

Reproduce with `/usr/bin/python3 bench/plot_animate_bench.py` (build the screwfem program
first; about 2 minutes per round on an idle machine, nearly all of it the old version)."""


if __name__ == "__main__":
    sys.exit(main())
