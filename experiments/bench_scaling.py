"""Throughput of ``rrtdrive bench`` on 1 vs 2 local workers, on 200-run grids.

Usage::

    python experiments/bench_scaling.py --out results            # both grids, 2 repeats
    python experiments/bench_scaling.py --grids closed-loop --repeats 3

Grids (200 runs each):

- ``closed-loop``: scenarios parking, overtake × planner rrt-connect × controllers
  pure-pursuit, lqr × 50 seeds (plan, drive in highway-env, evaluate: about 0.3–0.6 s
  a run);
- ``planning``: maps parking_lot, overtake × planners rrt-star, improved-rrt-connect
  × 50 seeds (planning and the independent verifier: tens of ms a run).

Each trial runs the whole bench through :func:`rrtdrive.bench.run_bench` (the code
behind ``rrtdrive bench``) into a fresh folder, so nothing is resumed. Throughput =
runs / wall time of the execution phase, which includes starting the worker
processes and each worker building its checkers; the summary and plots after it
are timed apart. Trials alternate 1, 2, 1, 2 … workers so that slow drifts of the
machine hit both alike; the ratio is of the medians.

The machine is shared, so every trial also records the CPU time that *other*
processes used during it (``/proc/stat`` busy time minus this process and its
workers): a trial with much foreign CPU ran on fewer than its cores. With
``--quiet-load L`` the script waits (up to ``--quiet-wait`` s) for the 1-minute load
average to fall below L before each trial, and with ``--max-foreign F`` a trial in
which other processes took more than the share F of the machine's CPU is
discarded (kept in the JSON, marked) and repeated, up to ``--attempts`` times.

``--probe`` first measures the machine's own ceiling without any bench code: a
fixed Python/numpy loop in one process alone, then in two processes at once (on a
VM, two vCPUs need not give twice the work). Each trial also records the time to
its first row (worker start-up and first checker) and the sum of the runs' own
wall times (equal for 1 and 2 workers when the cores do not slow each other).

Writes ``OUT/bench_scaling.json`` (every trial, the command, the machine) and
``OUT/bench_scaling.md``.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import statistics
import sys
import tempfile
import time
from pathlib import Path

from rrtdrive.bench import BenchConfig, run_bench
from rrtdrive.cli_args import positive_int
from rrtdrive.maps import write_text_atomic

GRIDS = {
    "closed-loop": dict(
        scenarios=("parking", "overtake"), planners=("rrt-connect",),
        controllers=("pure-pursuit", "lqr"), seeds=50,
    ),
    "planning": dict(
        maps=("parking_lot", "overtake"), planners=("rrt-star", "improved-rrt-connect"),
        seeds=50,
    ),
}


def busy_seconds() -> float:
    """Busy CPU seconds of the whole machine since boot (/proc/stat)."""
    with open("/proc/stat") as fh:
        fields = [int(v) for v in fh.readline().split()[1:]]
    idle = fields[3] + (fields[4] if len(fields) > 4 else 0)
    return (sum(fields[:8]) - idle) / os.sysconf("SC_CLK_TCK")


def own_cpu_seconds() -> float:
    me = resource.getrusage(resource.RUSAGE_SELF)
    kids = resource.getrusage(resource.RUSAGE_CHILDREN)
    return me.ru_utime + me.ru_stime + kids.ru_utime + kids.ru_stime


def busy_share(window_s: float = 2.0) -> float:
    """Share of the machine's CPU that was busy over the next ``window_s`` seconds."""
    b0, t0 = busy_seconds(), time.perf_counter()
    time.sleep(window_s)
    return (busy_seconds() - b0) / ((time.perf_counter() - t0) * (os.cpu_count() or 1))


def wait_quiet(limit: float | None, max_wait: float, idle_limit: float = 0.05) -> float:
    """Wait (up to ``max_wait`` s) for load average < ``limit`` and a nearly idle CPU."""
    load = os.getloadavg()[0]
    if limit is None:
        return load
    t0 = time.monotonic()
    while time.monotonic() - t0 < max_wait:
        load = os.getloadavg()[0]
        if load <= limit and busy_share() <= idle_limit:
            break
        time.sleep(3.0)
    return load


def _burn(seconds: float) -> float:
    """A fixed mixed Python/numpy workload; returns its wall time."""
    import numpy as np

    rng = np.random.default_rng(0)
    t0 = time.perf_counter()
    acc = 0.0
    for _ in range(int(seconds * 95_000)):  # about 10 us an iteration
        a = rng.random((64, 2))
        acc += float(np.hypot(*a.T).sum())
        for i in range(300):
            acc += i * 1e-9
    return time.perf_counter() - t0


def cpu_probe(seconds: float = 3.0) -> dict:
    """The VM's own ceiling: one busy process alone vs two at once (no bench code)."""
    import multiprocessing as mp

    ctx = mp.get_context("spawn")
    with ctx.Pool(2) as pool:
        pool.map(_burn, [0.2, 0.2])  # warm both processes
        alone = pool.apply(_burn, (seconds,))
        t0 = time.perf_counter()
        both = pool.map(_burn, [seconds, seconds])
        wall = time.perf_counter() - t0
    return {
        "one_process_s": alone,
        "two_processes_each_s": both,
        "two_processes_wall_s": wall,
        "parallel_speedup": 2 * alone / wall,
    }


def trial(grid: str, workers: int, quiet: float | None, quiet_wait: float) -> dict:
    load = wait_quiet(quiet, quiet_wait)
    with tempfile.TemporaryDirectory(prefix=f"bench_scaling_{grid}_{workers}w_") as tmp:
        cfg = BenchConfig(**GRIDS[grid], workers=workers, out=tmp, plots=True)
        busy0, own0, t0 = busy_seconds(), own_cpu_seconds(), time.perf_counter()
        first: list[float] = []

        def on_row(_row: dict) -> None:
            if not first:
                first.append(time.perf_counter() - t0)

        report = run_bench(cfg, on_row=on_row)
        total = time.perf_counter() - t0
        busy1, own1 = busy_seconds(), own_cpu_seconds()
        rows = [json.loads(x) for x in (Path(tmp) / "runs.jsonl").read_text().splitlines()]
    assert report.executed == len(rows) == cfg.runs == 200, (report, len(rows))
    foreign = max(0.0, (busy1 - busy0) - (own1 - own0))
    return {
        "grid": grid,
        "workers": workers,
        "runs": report.executed,
        "errors": report.errors,
        "run_wall_s": report.run_wall_s,
        "throughput_runs_per_s": report.throughput,
        "total_wall_s": total,
        "summary_and_plots_s": total - report.run_wall_s,
        "success_rate": sum(bool(r.get("success")) for r in rows) / len(rows),
        "sum_of_run_wall_s": sum(r.get("wall_time_s") or 0.0 for r in rows),
        "first_row_s": first[0] if first else None,
        "own_cpu_s": own1 - own0,
        "foreign_cpu_s": foreign,
        "foreign_cpu_share": foreign / (total * (os.cpu_count() or 1)),
        "load_before": load,
    }


def main(argv: list[str] | None = None) -> int:
    from results_io import json_text, out_folder  # the sibling module (run as a script)

    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--grids", default="closed-loop,planning",
                        help="comma-separated grids: closed-loop, planning (default: both)")
    parser.add_argument("--repeats", type=positive_int, default=2,
                        help="1- and 2-worker trial pairs per grid (default: %(default)s)")
    parser.add_argument("--out", type=out_folder, default="results",
                        help="directory for bench_scaling.json and .md (default: %(default)s)")
    parser.add_argument("--quiet-load", type=float, default=None,
                        help="wait for the 1-min load average to drop below this")
    parser.add_argument("--quiet-wait", type=float, default=300.0,
                        help="longest wait for --quiet-load per trial [s] (default: %(default)s)")
    parser.add_argument("--max-foreign", type=float, default=None,
                        help="repeat a trial in which other processes took more than this "
                        "share of the CPU")
    parser.add_argument("--attempts", type=positive_int, default=3,
                        help="tries per trial under --max-foreign; the last one is kept "
                        "(default: %(default)s)")
    parser.add_argument("--probe", action="store_true",
                        help="first measure the machine's own 1 vs 2 process speed-up")
    args = parser.parse_args(argv)
    grids = [g.strip() for g in args.grids.split(",") if g.strip()]
    for g in grids:
        if g not in GRIDS:
            parser.error(f"--grids: unknown grid {g!r}; choose from {sorted(GRIDS)}")
    trials: list[dict] = []
    discarded: list[dict] = []
    probes: list[dict] = []
    if args.probe:
        wait_quiet(args.quiet_load, args.quiet_wait)
        probes.append(cpu_probe())
        print(f"cpu probe: two processes at once run {probes[-1]['parallel_speedup']:.2f}x "
              "one alone", file=sys.stderr)
    for g in grids:
        for rep in range(args.repeats):
            for workers in (1, 2):
                for attempt in range(args.attempts):
                    t = trial(g, workers, args.quiet_load, args.quiet_wait)
                    t["repeat"] = rep
                    ok = args.max_foreign is None or t["foreign_cpu_share"] <= args.max_foreign
                    print(
                        f"{g:12s} rep {rep} {workers} worker(s): {t['runs']} runs in "
                        f"{t['run_wall_s']:.1f} s = {t['throughput_runs_per_s']:.2f} runs/s "
                        f"(foreign CPU {t['foreign_cpu_s']:.1f} s = "
                        f"{100 * t['foreign_cpu_share']:.0f} %, load {t['load_before']:.2f})"
                        + ("" if ok else " -> discarded, machine busy"),
                        file=sys.stderr,
                    )
                    if ok or attempt == args.attempts - 1:
                        t["accepted_with_foreign_load"] = not ok
                        trials.append(t)
                        break
                    discarded.append(t)
    summary = {}
    for g in grids:
        tp = {
            w: [t["throughput_runs_per_s"] for t in trials if t["grid"] == g and t["workers"] == w]
            for w in (1, 2)
        }
        med = {w: statistics.median(v) for w, v in tp.items()}
        pairs = [b / a for a, b in zip(tp[1], tp[2], strict=True)]
        summary[g] = {
            "throughput_1_worker": med[1],
            "throughput_2_workers": med[2],
            "ratio_of_medians": med[2] / med[1],
            "ratio_per_repeat": pairs,
            "meets_1_8": med[2] / med[1] >= 1.8,
        }
    command = "python experiments/bench_scaling.py " + " ".join(argv or sys.argv[1:])
    payload = {
        "command": command.strip(),
        "machine": f"{platform.machine()} {platform.python_version()}, "
        f"{os.cpu_count()} logical CPUs",
        "grids": {g: {k: list(v) if isinstance(v, tuple) else v for k, v in GRIDS[g].items()}
                  for g in grids},
        "summary": summary,
        "cpu_probe": probes,
        "trials": trials,
        "discarded_trials": discarded,
    }
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    write_text_atomic(out / "bench_scaling.json", json_text(payload))
    lines = [
        "# `rrtdrive bench` throughput: 1 vs 2 local workers (200 runs per bench)",
        "",
        f"Command: `{payload['command']}`  ",
        f"Machine: {payload['machine']}",
        "",
        "| grid | runs/s, 1 worker | runs/s, 2 workers | ratio (medians) | per repeat |",
        "|---|---|---|---|---|",
    ]
    for g, s in summary.items():
        lines.append(
            f"| {g} | {s['throughput_1_worker']:.2f} | {s['throughput_2_workers']:.2f} | "
            f"**{s['ratio_of_medians']:.2f}** | "
            + ", ".join(f"{r:.2f}" for r in s["ratio_per_repeat"]) + " |"
        )
    for p in probes:
        lines += [
            "",
            f"Machine ceiling (no bench code): a mixed Python/numpy loop takes "
            f"{p['one_process_s']:.2f} s alone; two copies at once take "
            f"{p['two_processes_wall_s']:.2f} s: **{p['parallel_speedup']:.2f}x** throughput.",
        ]
    lines += [
        "",
        "Every trial (execution phase = worker start to last row; foreign CPU = CPU time "
        "of other processes on the machine during the trial):",
        "",
        "| grid | rep | workers | run wall [s] | runs/s | first row [s] | sum of run times [s] "
        "| summary+plots [s] | success | own CPU [s] | foreign CPU [s] | load before |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for t in trials:
        lines.append(
            f"| {t['grid']} | {t['repeat']} | {t['workers']} | {t['run_wall_s']:.1f} | "
            f"{t['throughput_runs_per_s']:.2f} | {t['first_row_s']:.1f} | "
            f"{t['sum_of_run_wall_s']:.1f} | {t['summary_and_plots_s']:.1f} | "
            f"{100 * t['success_rate']:.0f} % | {t['own_cpu_s']:.1f} | "
            f"{t['foreign_cpu_s']:.1f} | {t['load_before']:.2f} |"
        )
    if discarded:
        lines += [
            "",
            f"{len(discarded)} trial(s) discarded because other processes took more than "
            f"{100 * args.max_foreign:.0f} % of the CPU (in the JSON).",
        ]
    text = "\n".join(lines) + "\n"
    write_text_atomic(out / "bench_scaling.md", text)
    print(text)
    return 0


if __name__ == "__main__":
    from results_io import run_main

    raise SystemExit(run_main(main))
