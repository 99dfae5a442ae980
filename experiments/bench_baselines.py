"""Timing of the three baselines (RRT, RRT-Connect, RRT*) and of the collision checker.

Usage::

    python experiments/bench_baselines.py --map parking_lot --seeds 20 --out results/

Builds the map's problem once (the checker's construction and its lazy set-up
are timed apart from planning), runs every baseline with the paper's settings
(Sec. 4.1) for seeds ``0 .. N-1``, and measures the checker's cost per fast edge
test (random 5 m edges over the map) and per exact pose test. Writes
``OUT/baselines_<map>.json`` (command, seeds, settings, summaries, every run)
and ``OUT/baselines_<map>.md``, each through a temporary file and a rename.
Times are wall-clock on this machine, single-threaded.
"""

from __future__ import annotations

import argparse
import json
import math
import platform
import shlex
import statistics
import sys
import time
from pathlib import Path

import numpy as np

from rrtdrive.cli_args import positive_float, positive_int
from rrtdrive.collision import CollisionChecker
from rrtdrive.maps import resolve_map, write_text_atomic
from rrtdrive.planning import PlanningProblem, make_planner
from rrtdrive.stats import describe as stat_describe
from rrtdrive.types import Budget

BASELINES = ("rrt", "rrt-connect", "rrt-star")


def time_checker(problem: PlanningProblem, n_edges: int, n_poses: int, seed: int) -> dict:
    """Microseconds per fast edge test and per exact pose test on random queries."""
    checker = problem.checker
    rng = np.random.default_rng(seed)
    xmin, ymin, xmax, ymax = problem.bounds
    lo, span = np.array([xmin, ymin]), np.array([xmax - xmin, ymax - ymin])
    a = lo + rng.random((n_edges, 2)) * span
    ang = rng.uniform(-math.pi, math.pi, n_edges)
    b = a + 5.0 * np.column_stack([np.cos(ang), np.sin(ang)])
    a_list, b_list = a.tolist(), b.tolist()
    t0 = time.perf_counter()
    free_edges = sum(checker.edge_free(p, q) for p, q in zip(a_list, b_list, strict=True))
    edge_us = (time.perf_counter() - t0) / n_edges * 1e6

    poses = np.column_stack(
        [lo + rng.random((n_poses, 2)) * span, rng.uniform(-math.pi, math.pi, n_poses)]
    )
    pose_list = poses.tolist()
    checker.poses_free(poses[:50])  # warm-up: first calls into shapely pay set-up costs
    t0 = time.perf_counter()
    free_scalar = sum(checker.pose_free(p) for p in pose_list)
    pose_us = (time.perf_counter() - t0) / n_poses * 1e6
    t0 = time.perf_counter()
    free_batch = checker.poses_free(poses)
    batch_us = (time.perf_counter() - t0) / n_poses * 1e6
    unsure = ~checker.poses_free_fast(poses)
    t0 = time.perf_counter()
    checker.poses_free(poses[unsure])
    unsure_us = (time.perf_counter() - t0) / max(1, int(unsure.sum())) * 1e6
    assert free_scalar == int(free_batch.sum())
    return {
        "edges": n_edges,
        "edge_length_m": 5.0,
        "edge_us": edge_us,
        "edge_free_share": free_edges / n_edges,
        "poses": n_poses,
        "pose_exact_scalar_us": pose_us,
        "pose_exact_batch_us": batch_us,
        "pose_unsure_share": float(unsure.mean()),
        "pose_exact_unsure_batch_us": unsure_us,
        "pose_free_share": free_scalar / n_poses,
    }


def finite(obj: object) -> object:
    """A copy with NaN and infinities replaced by None (strict JSON)."""
    if isinstance(obj, dict):
        return {k: finite(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [finite(v) for v in obj]
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    return obj


def describe(values: list[float]) -> dict[str, float]:
    """Median, mean, min and max (NaN when empty)."""
    if not values:
        return {"median": math.nan, "mean": math.nan, "min": math.nan, "max": math.nan}
    s = stat_describe(values)
    return {"median": s.median, "mean": s.mean, "min": s.min, "max": s.max}


def run_planner(name: str, problem: PlanningProblem, seeds: list[int], budget: Budget) -> list:
    """One row per seed."""
    planner = make_planner(name)
    rows = []
    for seed in seeds:
        r = planner.solve(problem, np.random.default_rng(seed), budget)
        rows.append(
            {
                "seed": seed,
                "status": r.status.value,
                "success": r.success,
                "planning_time_s": r.planning_time_s,
                "nodes": r.nodes,
                "iterations": r.iterations,
                "raw_length_m": r.stats.get("raw_length_m", math.nan),
                "waypoints": len(r.raw_path),
                "edge_checks": r.stats.get("edge_checks", 0),
                "exact_edge_checks": r.stats.get("exact_edge_checks", 0),
            }
        )
    return rows


def summarise(rows: list[dict]) -> dict:
    """Success rate; time and nodes over all runs; length over the solved runs."""
    ok = [r for r in rows if r["success"]]
    return {
        "runs": len(rows),
        "solved": len(ok),
        "success_rate": len(ok) / len(rows) if rows else math.nan,
        "planning_time_s": describe([r["planning_time_s"] for r in rows]),
        "planning_time_solved_s": describe([r["planning_time_s"] for r in ok]),
        "nodes": describe([float(r["nodes"]) for r in rows]),
        "raw_length_m": describe([r["raw_length_m"] for r in ok]),
        "edge_checks": describe([float(r["edge_checks"]) for r in rows]),
    }


def markdown(report: dict) -> str:
    """The report as a Markdown page."""
    c = report["checker"]
    lines = [
        f"# Baselines on `{report['map']}`",
        "",
        f"Command: `{report['command']}`  ",
        f"Seeds: {report['seeds'][0]}..{report['seeds'][-1]} ({len(report['seeds'])} runs "
        f"per planner); budget {report['budget']['max_iterations']} iterations, "
        f"{report['budget']['max_time_s']} s.  ",
        f"Machine: {report['environment']['platform']}, Python "
        f"{report['environment']['python']}, numpy {report['environment']['numpy']}.",
        "",
        "Time and nodes over all runs; length over solved runs (the raw tree path, "
        "no post-processing).",
        "",
        "| planner | settings | success | time median (ms) | time mean (ms) | nodes median "
        "| nodes mean | length median (m) | length mean (m) |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for name, s in report["summary"].items():
        settings = ", ".join(f"{k}={v}" for k, v in report["settings"][name].items())
        t = s["planning_time_s"]
        lines.append(
            f"| {name} | {settings} | {s['solved']}/{s['runs']} "
            f"| {t['median'] * 1e3:.1f} | {t['mean'] * 1e3:.1f} "
            f"| {s['nodes']['median']:.0f} | {s['nodes']['mean']:.1f} "
            f"| {s['raw_length_m']['median']:.1f} | {s['raw_length_m']['mean']:.1f} |"
        )
    prep = report["setup"]
    lines += [
        "",
        "## Checker",
        "",
        f"- construction: {prep['checker_build_s'] * 1e3:.1f} ms; lazy set-up (free-space "
        f"components, sampling cells): {prep['lazy_setup_s'] * 1e3:.1f} ms",
        f"- fast edge test (`edge_free`, {c['edges']} random {c['edge_length_m']:g} m edges, "
        f"{c['edge_free_share']:.0%} free): **{c['edge_us']:.2f} µs per edge**",
        f"- exact pose test (`pose_free`, {c['poses']} random poses, {c['pose_free_share']:.0%} "
        f"free): {c['pose_exact_scalar_us']:.2f} µs per pose scalar, "
        f"{c['pose_exact_batch_us']:.2f} µs per pose in one `poses_free` batch; "
        f"{c['pose_unsure_share']:.0%} of poses need shapely after the disc screen, "
        f"{c['pose_exact_unsure_batch_us']:.1f} µs each in a batch",
        "",
    ]
    rs = report["runs"].get("rrt-star")
    if rs:
        cap = report["settings"]["rrt-star"]["max_nodes"]
        exact = [r["planning_time_s"] for r in rs if r["success"] and r["nodes"] == cap]
        line = f"RRT*: {len(exact)}/{len(rs)} runs stopped at exactly {cap} nodes"
        if len(exact) < len(rs):
            line += " (the others grew on until the goal was connected, or failed)"
        if exact:
            line += f"; their median time {statistics.median(exact) * 1e3:.1f} ms"
        lines.append(line + ".")
        lines.append("")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    from results_io import out_folder  # the sibling module (run as a script)

    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument(
        "--seeds", type=positive_int, default=20, help="runs per planner (seeds 0..N-1)"
                                                       " (default: %(default)s)"
    )
    parser.add_argument("--map", default="parking_lot",
                        help="built-in map name or map file (default: %(default)s)")
    parser.add_argument("--out", type=out_folder, default="results/",
                        help="output folder (default: %(default)s)")
    parser.add_argument("--planners", nargs="+", default=list(BASELINES), choices=BASELINES,
                        help="baselines to time, space-separated (default: all)")
    parser.add_argument("--max-iterations", type=positive_int, default=20_000,
                        help="iteration budget per query (default: %(default)s)")
    parser.add_argument("--max-time", type=positive_float, default=10.0,
                        help="seconds per query (default: %(default)s)")
    parser.add_argument("--edges", type=positive_int, default=20_000,
                        help="random edges to time (default: %(default)s)")
    parser.add_argument("--poses", type=positive_int, default=5_000,
                        help="random poses to time (default: %(default)s)")
    args = parser.parse_args(argv)
    if args.seeds <= 0:
        parser.error("--seeds: must be > 0")

    m = resolve_map(args.map)
    t0 = time.perf_counter()
    checker = CollisionChecker.for_map(m)
    build_s = time.perf_counter() - t0
    problem = PlanningProblem.from_map(m, checker=checker)
    t0 = time.perf_counter()
    checker.provably_disconnected(problem.start.xy, problem.goal.xy)
    checker.free_cells(problem.start.as_tuple()[:2])
    lazy_s = time.perf_counter() - t0

    budget = Budget(max_iterations=args.max_iterations, max_time_s=args.max_time)
    seeds = list(range(args.seeds))
    runs, summary, settings = {}, {}, {}
    for name in args.planners:
        planner = make_planner(name)
        settings[name] = {
            k: v
            for k, v in vars(planner).items()
            if k in ("step", "goal_bias", "rewire_radius", "max_nodes")
        }
        runs[name] = run_planner(name, problem, seeds, budget)
        summary[name] = summarise(runs[name])
        s = summary[name]
        print(
            f"{name:12s} solved {s['solved']}/{s['runs']}  time median "
            f"{s['planning_time_s']['median'] * 1e3:7.1f} ms mean "
            f"{s['planning_time_s']['mean'] * 1e3:7.1f} ms  nodes median "
            f"{s['nodes']['median']:6.0f}  length median {s['raw_length_m']['median']:6.1f} m",
            flush=True,
        )

    checker_stats = time_checker(problem, args.edges, args.poses, seed=0)
    report = {
        "map": m.name,
        "command": shlex.join(
            ["python", "experiments/bench_baselines.py", *(sys.argv[1:] if argv is None else argv)]
        ),
        "argv": vars(args),
        "seeds": seeds,
        "budget": {"max_iterations": budget.max_iterations, "max_time_s": budget.max_time_s},
        "settings": settings,
        "environment": {
            "python": platform.python_version(),
            "numpy": np.__version__,
            "platform": platform.platform(),
            "processor": platform.machine(),
        },
        "setup": {"checker_build_s": build_s, "lazy_setup_s": lazy_s},
        "checker": checker_stats,
        "summary": summary,
        "runs": runs,
    }
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    stem = f"baselines_{m.name}"
    text = json.dumps(finite(report), indent=1, allow_nan=False)
    write_text_atomic(out / f"{stem}.json", text + "\n")
    md = markdown(report)
    write_text_atomic(out / f"{stem}.md", md)
    print()
    print(md)
    print(f"wrote {out / (stem + '.json')} and {out / (stem + '.md')}")
    return 0


if __name__ == "__main__":
    from results_io import run_main

    raise SystemExit(run_main(main))
