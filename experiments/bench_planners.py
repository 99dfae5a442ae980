"""Speed benchmark: the improved RRT-Connect against OMPL, side by side, same map, same checker.

Usage::

    pip install ".[ompl]"
    python experiments/bench_planners.py --map parking_lot --seeds 20 --out results \
        --doc docs/bench_planners.md

Rows:

- ``improved-rrt-connect``: our planner, planning time including post-processing.
- ``ompl-r2-rrtconnect+simplify``: OMPL RRTConnect (range 5 m) in R² plus
  ``simplifySolution`` — the same geometric problem without the curvature bound.
  A state is valid when the checker's clearance at the point is at least the
  swept-capsule radius of our edge test (W/2 + margin).
- ``ompl-dubins-*``: OMPL's forward-only curvature-bounded planners in
  ``DubinsStateSpace(6.0)``: RRT, BIT* stopped at the first solution, RRTConnect
  (known to fail in that asymmetric space, ompl#1356). A state is valid when the
  body's three covering discs are clear (the checker's fast pose test).

Every OMPL planner gets the same wall-time cap; a run that returns no exact
solution in time counts as a failure. Writes ``OUT/bench_planners_<map>.json``
and ``.md`` with the command, the seeds and every per-run row.
"""

from __future__ import annotations

import argparse
import math
import os
import statistics
import sys
import time
from pathlib import Path

import numpy as np

from rrtdrive.cli_args import positive_float, positive_int
from rrtdrive.maps import builtin_map, write_text_atomic
from rrtdrive.planning import PlanningProblem, make_planner
from rrtdrive.types import Budget


def ompl_run(kind: str, planner_name: str, problem: PlanningProblem, seed: int, cap: float) -> dict:
    from ompl import base as ob
    from ompl import geometric as og
    from ompl import util as ou

    from rrtdrive.bench.ompl_planners import simple_setup

    ss, si = simple_setup(problem, kind)
    # OMPL takes a seed only before its first random number in a process, so OMPL
    # rows are not reproducible seed by seed here; ours are.
    ou.RNG.setSeed(seed + 1)
    if planner_name == "RRTConnect":
        planner = og.RRTConnect(si)
        planner.setRange(5.0)
    elif planner_name == "RRT":
        planner = og.RRT(si)
        planner.setRange(5.0)
    elif planner_name == "BITstar":
        planner = og.BITstar(si)
    else:
        raise ValueError(planner_name)
    ss.setPlanner(planner)
    objective = ob.PathLengthOptimizationObjective(si)
    objective.setCostThreshold(ob.Cost(float("inf")))
    ss.setOptimizationObjective(objective)
    t0 = time.perf_counter()
    status = ss.solve(cap)
    exact = status.asString() == "Exact solution"
    if exact and kind == "r2":
        ss.simplifySolution()
    elapsed = time.perf_counter() - t0
    length = ss.getSolutionPath().length() if exact else float("nan")
    return {"success": exact, "time_s": elapsed, "length_m": length}


def ours_run(problem: PlanningProblem, seed: int, budget: Budget) -> dict:
    planner = make_planner("improved-rrt-connect")
    result = planner.solve(problem, np.random.default_rng(seed), budget)
    return {
        "success": result.success,
        "time_s": result.planning_time_s,
        "length_m": result.path.length if result.success else float("nan"),
    }


ROWS = (
    ("improved-rrt-connect", None, None),
    ("ompl-r2-rrtconnect+simplify", "r2", "RRTConnect"),
    ("ompl-dubins-rrt", "dubins", "RRT"),
    ("ompl-dubins-bitstar-first", "dubins", "BITstar"),
    ("ompl-dubins-rrtconnect", "dubins", "RRTConnect"),
)


def summarise(runs: list[dict]) -> dict:
    ok = [r for r in runs if r["success"]]
    times = [r["time_s"] for r in runs]
    return {
        "runs": len(runs),
        "success_rate": len(ok) / len(runs),
        "median_time_s": statistics.median(times),
        "mean_time_s": statistics.fmean(times),
        "mean_length_m": statistics.fmean(r["length_m"] for r in ok) if ok else float("nan"),
    }


def finite(value: float, digits: int) -> str:
    """A table cell: ``value`` to ``digits`` decimals, "–" for a planner that never solved."""
    return f"{value:.{digits}f}" if math.isfinite(value) else "–"


def main(argv: list[str] | None = None) -> int:
    from results_io import json_text, machine, out_folder  # the sibling module (run as a script)

    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--map", default="parking_lot",
                        help="built-in map name (default: %(default)s)")
    parser.add_argument("--seeds", type=positive_int, default=20,
                        help="runs per planner, seeds 0..N-1 (default: %(default)s)")
    parser.add_argument("--cap", type=positive_float, default=5.0,
                        help="OMPL time cap per run [s] (default: %(default)s)")
    parser.add_argument("--out", type=out_folder, default="results",
                        help="directory for bench_planners_MAP.json and .md (default: %(default)s)")
    parser.add_argument(
        "--doc", default=None,
        help="also write this markdown page (docs/bench_planners.md for the docs)",
    )
    args = parser.parse_args(argv)
    try:
        from ompl import util as ou
    except ImportError:
        print("OMPL is not installed: pip install '.[ompl]'", file=sys.stderr)
        return 2
    ou.setLogLevel(ou.LogLevel.LOG_NONE)
    m = builtin_map(args.map)
    t0 = time.perf_counter()
    problem = PlanningProblem.from_map(m)
    checker_build_s = time.perf_counter() - t0
    budget = Budget(max_iterations=20_000, max_time_s=args.cap)
    per_run: dict[str, list[dict]] = {name: [] for name, _, _ in ROWS}
    # Interleave planners seed by seed so that machine noise hits every row alike.
    for seed in range(args.seeds):
        for name, kind, ompl_name in ROWS:
            if kind is None:
                row = ours_run(problem, seed, budget)
            else:
                row = ompl_run(kind, ompl_name, problem, seed, args.cap)
            per_run[name].append({"seed": seed, **row})
        print(f"seed {seed + 1}/{args.seeds} done", file=sys.stderr)
    summary = {name: summarise(runs) for name, runs in per_run.items()}
    ours = summary["improved-rrt-connect"]
    for s in summary.values():
        s["time_ratio_ours_over_this"] = ours["median_time_s"] / s["median_time_s"]
        s["length_ratio_ours_over_this"] = ours["mean_length_m"] / s["mean_length_m"]
    command = "python experiments/bench_planners.py " + " ".join(argv or sys.argv[1:])
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    payload = {
        "command": command.strip(),
        "map": args.map,
        "seeds": list(range(args.seeds)),
        "ompl_time_cap_s": args.cap,
        "checker_build_s": checker_build_s,
        "machine": machine(),
        "date": time.strftime("%Y-%m-%d"),
        # The times are this machine's under this load; the ratios are side by side.
        "load_average": [round(v, 2) for v in os.getloadavg()],
        "summary": summary,
        "runs": per_run,
    }
    write_text_atomic(out / f"bench_planners_{args.map}.json", json_text(payload))
    lines = [
        f"# Planner speed on `{args.map}` ({args.seeds} seeds, same checker)",
        "",
        f"Command: `{payload['command']}`  ",
        f"Checker construction (once per map, not in any row): {checker_build_s * 1e3:.0f} ms.  ",
        f"Times measured on {payload['machine']}, {payload['date']} (load average "
        f"{' '.join(f'{v:.2f}' for v in payload['load_average'])} at the end), planners "
        "interleaved seed by seed; the ratios compare them in this one run.",
        "",
        "| planner | success | median time [ms] | mean length [m] | ours / this time "
        "| ours / this length |",
        "|---|---|---|---|---|---|",
    ]
    for name, s in summary.items():
        lines.append(
            f"| {name} | {100 * s['success_rate']:.0f} % | {1e3 * s['median_time_s']:.2f} | "
            f"{finite(s['mean_length_m'], 2)} | {s['time_ratio_ours_over_this']:.3f} | "
            f"{finite(s['length_ratio_ours_over_this'], 3)} |"
        )
    text = "\n".join(lines) + "\n"
    write_text_atomic(out / f"bench_planners_{args.map}.md", text)
    if args.doc:  # docs/ changes only when asked
        write_text_atomic(Path(args.doc), text)
    print(text)
    return 0


if __name__ == "__main__":
    from results_io import run_main

    code = run_main(main)
    sys.stdout.flush()
    sys.stderr.flush()
    # Skip interpreter teardown, as the bench workers do: OMPL objects (BITstar's) still
    # alive then make nanobind print ~20 lines of leak warnings, and nanobind offers no
    # Python switch to silence them.
    os._exit(code)
