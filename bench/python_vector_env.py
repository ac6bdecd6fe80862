"""Benchmark of screwfem.VectorEnv: environment steps per second with n = 1, 2, 4 copies, the
copies' physics on C++ threads with the GIL released (_step_many, python/bind_env.cpp).
Writes its latest run into the section "Vector environments (Python)" of bench/RESULTS.md,
before "Parameter sweeps on Dask" (bench/make_results.py keeps both when it rewrites the
file).

    PYTHONPATH=build/release/python /usr/bin/python3 bench/python_vector_env.py \\
        [--rounds 9] [--steps 200] [--substeps 10] [--no-write]

The scene is examples/python/soft_arm_control.yaml (a silicone arm of 8 elements with a
tendon along its top whose tension is the input u; the scene's step h = 2 ms): each env step
holds u = 1 N over a control period of `substeps` steps (20 ms by default) and observes the
tip's position and velocity. An episode is the scene's 2 s (100 env steps by default), then
the copy is reset within the step (autoreset), so resets are part of the throughput.

Throughput = copies x env steps / wall seconds. The n = 1, 2, 4 measurements alternate
within each round (n = 1, 2, 4, 1, 2, 4, ...) because the machine's speed drifts by up to
25 % over minutes; each round gives ratios to its own n = 1 measurement, and the medians of
the ratios over the rounds are reported. *Physics only*: _step_many on n initialised
Simulations with the same steps, without the Python side of an env step (actions,
observations, rewards, info, autoreset); the difference is the Python share that runs
serially under the GIL. *CPU*: the process's CPU time (all threads) over the wall time.
Target: at n = 2 on 2 cores at least 1.7x the steps per second of n = 1.
"""

import argparse
import datetime
import os
import pathlib
import statistics
import sys
import time

import numpy as np

import screwfem as sf
from screwfem import _screwfem
from bench_common import cpu_model, revision

ROOT = pathlib.Path(__file__).resolve().parents[1]
RESULTS = ROOT / "bench" / "RESULTS.md"
SECTION = "## Vector environments (Python)"
SWEEP_SECTION = "## Parameter sweeps on Dask"
SCENE = ROOT / "examples" / "python" / "soft_arm_control.yaml"
COPIES = (1, 2, 4)
TARGET = 1.7  # n = 2 against n = 1


def time_env(venv, steps):
    """(wall s, CPU s of the process, CPU s of this thread) of `steps` VectorEnv steps holding
    u = 1 N on every copy."""
    actions = np.ones(venv.action_space.shape)
    m0, c0, t0 = time.thread_time(), time.process_time(), time.perf_counter()
    for _ in range(steps):
        venv.step(actions)
    return time.perf_counter() - t0, time.process_time() - c0, time.thread_time() - m0


class Physics:
    """n Simulations stepped by _step_many as a VectorEnv's copies are, episode after episode
    (fresh Simulations at each end, outside the timing), without the Python side."""

    def __init__(self, scene, n, substeps, episode_steps):
        self.scene, self.n, self.substeps = scene, n, substeps
        self.episode_steps = episode_steps
        self.sims, self.done = self.fresh(), 0

    def fresh(self):
        sims = [sf.Simulation(self.scene) for _ in range(self.n)]
        for s in sims:
            s.initialize()
            s.inputs["u"] = 1.0
        return sims

    def time(self, steps):
        """(wall s, CPU s of the process, CPU s of this thread) of `steps` _step_many calls of
        `substeps` steps each."""
        wall = cpu = main = 0.0
        h = self.scene.analysis.step
        while steps > 0:
            if self.done == self.episode_steps:
                self.sims, self.done = self.fresh(), 0
            chunk = min(steps, self.episode_steps - self.done)
            m0, c0, t0 = time.thread_time(), time.process_time(), time.perf_counter()
            for _ in range(chunk):
                errors = _screwfem._step_many(self.sims, h, self.substeps)
                assert not any(errors), errors
            wall += time.perf_counter() - t0
            cpu += time.process_time() - c0
            main += time.thread_time() - m0
            steps -= chunk
            self.done += chunk
        return wall, cpu, main


def scheduling():
    """This process's nice value and, with autogroup scheduling, its group's nice: the share
    of the processors it competes for against other sessions."""
    text = f"nice {os.nice(0)}"
    try:
        with open("/proc/sys/kernel/sched_autogroup_enabled", encoding="utf-8") as f:
            enabled = f.read().strip() == "1"
        with open("/proc/self/autogroup", encoding="utf-8") as f:
            group = f.read().split()
        if enabled:
            text += f", autogroup nice {group[-1]}"
    except (OSError, IndexError):
        pass
    return text


def replace_section(body, text):
    """`body` with the section SECTION replaced by `text`. A new section goes before "Parameter
    sweeps on Dask", the history bench/sweep_bench.py appends to at the end of the file."""
    start = body.find(SECTION)
    if start >= 0:
        end = body.find("\n## ", start + len(SECTION))
        rest = "" if end < 0 else body[end:]
        return body[:start] + text.rstrip("\n") + "\n" + rest
    before = body.find(SWEEP_SECTION)
    if before < 0:
        return body.rstrip("\n") + "\n\n" + text
    return body[:before] + text.rstrip("\n") + "\n\n" + body[before:]


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=9, help="rounds of n = 1, 2, 4")
    parser.add_argument("--steps", type=int, default=200, help="env steps per measurement")
    parser.add_argument("--substeps", type=int, default=10, help="time steps per env step")
    parser.add_argument("--no-write", action="store_true", help="print only")
    args = parser.parse_args()

    scene = sf.load_scene(str(SCENE))
    h = scene.analysis.step
    venvs = {n: sf.VectorEnv(n, scene, substeps=args.substeps) for n in COPIES}
    for venv in venvs.values():
        venv.reset(seed=0)
    episode = venvs[1].envs[0]
    episode_steps = round((scene.analysis.end_time - scene.analysis.start_time)
                          / episode.control_period)
    physics = {n: Physics(scene, n, args.substeps, episode_steps) for n in COPIES}
    for n in COPIES:  # warm-up
        time_env(venvs[n], 5)
        physics[n].time(5)
    load_before = os.getloadavg()
    env_runs = {n: [] for n in COPIES}
    phys_runs = {n: [] for n in COPIES}
    for _ in range(args.rounds):
        for n in COPIES:
            env_runs[n].append(time_env(venvs[n], args.steps))
        for n in COPIES:
            phys_runs[n].append(physics[n].time(args.steps))
    load_after = os.getloadavg()

    def rate(n, run):
        return n * args.steps / run[0]

    def summary(runs):
        rows = {}
        for n in COPIES:
            rates = [rate(n, r) for r in runs[n]]
            ratios = [rate(n, r) / rate(1, r1) for r, r1 in zip(runs[n], runs[1])]
            cpu = [r[1] / r[0] for r in runs[n]]
            # The calling thread steps its share of the copies and does all the Python work;
            # the other threads step equal shares at the same time. On idle cores its CPU time
            # is the critical path, whatever other load the machine had during the run.
            projected = [(n / r[2]) / (1 / r1[2]) for r, r1 in zip(runs[n], runs[1])]
            rows[n] = (statistics.median(rates), max(rates), statistics.median(ratios),
                       min(ratios), max(ratios), statistics.median(cpu),
                       statistics.median(projected))
        return rows

    env_rows, phys_rows = summary(env_runs), summary(phys_runs)
    ratio2 = env_rows[2][2]
    met = ratio2 >= TARGET
    stamp = datetime.datetime.now(datetime.timezone.utc).replace(microsecond=0).isoformat()
    period_ms = 1e3 * args.substeps * h
    lines = [
        SECTION,
        "",
        "Written by `bench/python_vector_env.py` (the latest run replaces this section;",
        "`bench/make_results.py` keeps it). `screwfem.VectorEnv` with n copies of",
        "`examples/python/soft_arm_control.yaml` (a silicone arm of 8 elements, a tendon",
        f"along its top pulled with u = 1 N), {args.substeps} steps of h = {1e3 * h:g} ms per "
        f"env step (control period {period_ms:g} ms),",
        "observations the tip's position and velocity, same-step autoreset after the scene's",
        "2 s. *Steps/s* = copies x env steps / wall s, median (and best) of the rounds;",
        f"{args.rounds} rounds of {args.steps} env steps per n, the n = 1, 2, 4 measurements",
        "interleaved within each round (the machine's speed drifts by up to 25 % over",
        "minutes); *ratio to n = 1*: per round, then the median and range over the rounds.",
        "*Physics only*: `_step_many` on n initialised Simulations, the same steps without",
        "the Python side of an env step. *CPU / wall*: the process's CPU time over its wall",
        "time (2 = both cores busy; less: the run did not get two cores, other load took",
        "them). *Idle projection*: the ratio to n = 1 from the calling thread's CPU time",
        "(`time.thread_time`): that thread steps its share of the copies and does all the",
        "Python work while the other threads step theirs, so its CPU time is the wall time",
        "on idle cores, whatever other load the machine had (optimistic by a thread's start",
        "latency and any imbalance between the shares). The run line names the process's",
        "nice value and its autogroup's: when other sessions keep the cores busy, a run at",
        "raised priority (as root: `setsid bash -c 'echo -10 > /proc/self/autogroup; exec",
        "nice -n -10 ...'`) competes for more of them.",
        "",
        f"Run {stamp}, revision {revision()}, {cpu_model('unknown CPU')}, {os.cpu_count()} cores, "
        f"{scheduling()}; load average before {', '.join(f'{x:.2f}' for x in load_before)}, "
        f"after {', '.join(f'{x:.2f}' for x in load_after)}.",
        "",
        "| Copies n | Env steps/s | Best | Ratio to n = 1 | Range | CPU / wall "
        "| Idle projection | Physics only, steps/s | Physics ratio | Physics CPU / wall "
        "| Physics idle projection |",
        "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for n in COPIES:
        e, p = env_rows[n], phys_rows[n]
        lines.append(f"| {n} | {e[0]:.0f} | {e[1]:.0f} | {e[2]:.2f} | {e[3]:.2f} to {e[4]:.2f} "
                     f"| {e[5]:.2f} | {e[6]:.2f} | {p[0]:.0f} | {p[2]:.2f} | {p[5]:.2f} "
                     f"| {p[6]:.2f} |")
    # Costs per env step of one copy at n = 1 from CPU times (independent of the load).
    env_us = 1e6 * statistics.median(r[2] for r in env_runs[1]) / args.steps
    phys_us = 1e6 * statistics.median(r[2] for r in phys_runs[1]) / args.steps
    projected2 = env_rows[2][6]
    lines += [
        "",
        f"n = 2 against n = 1: **{ratio2:.2f}x** measured (median over the rounds; target at "
        f"least {TARGET}x on 2 cores: {'met' if met else 'NOT met'}), "
        f"{projected2:.2f}x projected for idle cores "
        f"({'met' if projected2 >= TARGET else 'NOT met'}); n = 4: {env_rows[4][2]:.2f}x "
        f"measured, {env_rows[4][6]:.2f}x projected. CPU time of one env step of one copy at "
        f"n = 1: {env_us:.0f} µs, of which the physics {phys_us:.0f} µs and the Python side "
        f"{env_us - phys_us:.0f} µs."
        + ("" if env_rows[2][5] >= 1.6 else
           f" The run did not get two cores (CPU / wall {env_rows[2][5]:.2f} at n = 2): the "
           "measured ratios show the machine's load, the idle projection the threading."),
        "",
        "Reproduce with `PYTHONPATH=build/release/python /usr/bin/python3 "
        "bench/python_vector_env.py` (about 20 s on 2 cores).",
        "",
    ]
    text = "\n".join(lines)
    print(text)
    if not args.no_write:
        body = RESULTS.read_text() if RESULTS.exists() else "# Benchmark results\n"
        RESULTS.write_text(replace_section(body, text))
    return 0 if met else 1


if __name__ == "__main__":
    sys.exit(main())
