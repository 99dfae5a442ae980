"""Sharpness of the improved planner's paths: default clothoid turns vs the paper's B-spline.

Usage::

    python experiments/bench_sharpness.py --seeds 10 --goals 100 --out results

Part 1, the built-in maps x seeds, both settings in the same run (interleaved per
seed, so machine load hits both alike): success, the largest steering rate per
metre ``max |d delta / ds|`` (rad/m, :func:`rrtdrive.planning.smoothing.max_sharpness`,
exact on the clothoid rows), the largest ``|kappa|``, the length, the median
planning time, the independent :func:`rrtdrive.verify.verify_path`, and the ratio
of the median planning times default / paper (the setting that plans first
alternates per seed: a map's first query warms caches).

Part 2, the random-goal experiment (:mod:`random_goals`: ``--goals`` seeded free
poses on ``parking_lot`` as goals, then as starts): every solved default path is
checked for the bound, and both settings' success is counted.

Writes ``OUT/sharpness.json`` and ``OUT/sharpness.md`` (command and settings included).
"""

from __future__ import annotations

import argparse
import dataclasses
import statistics
import sys
import time
from pathlib import Path as FsPath

import numpy as np

from rrtdrive.cli_args import int_at_least, positive_float, positive_int
from rrtdrive.maps import BUILTIN_MAPS, TIGHT_MAP_NAMES, builtin_map, write_text_atomic
from rrtdrive.planning import PlanningProblem
from rrtdrive.planning.improved import ImprovedRRTConnect
from rrtdrive.planning.smoothing import CurveKind, SmoothingConfig, max_sharpness
from rrtdrive.types import Budget, PlanStatus
from rrtdrive.verify import verify_path

sys.path.insert(0, str(FsPath(__file__).resolve().parent))
from random_goals import draw_goals  # noqa: E402
from results_io import json_text  # noqa: E402

SETTINGS = {
    "default (clothoid)": {},
    "paper (B-spline)": {"smoothing": {"curve": CurveKind.BSPLINE}},
}
BOUND = SmoothingConfig().max_sharpness


def plan_row(m, problem, options, seed, budget) -> dict:
    """One plan: status, time and, when solved, its exact figures."""
    t0 = time.perf_counter()
    res = ImprovedRRTConnect(**options).solve(problem, np.random.default_rng(seed), budget)
    wall = time.perf_counter() - t0
    row = {"seed": seed, "status": res.status.value, "time_s": res.planning_time_s,
           "wall_s": wall}  # fmt: skip
    if res.success:
        s = res.path.samples
        row.update(
            max_sharpness=max_sharpness(s, m.vehicle.wheelbase),
            max_curvature=res.path.max_curvature,
            length_m=res.path.length,
            end_curvature=max(abs(float(s[0, 3])), abs(float(s[-1, 3]))),
            verified=bool(verify_path(m, res.path).ok),
            fallback=bool(res.stats.get("dubins_fallback", 0.0)),
        )
    return row


def summarise(rows: list[dict]) -> dict:
    solved = [r for r in rows if r["status"] == PlanStatus.SOLVED.value]
    out = {
        "runs": len(rows),
        "solved": len(solved),
        "verified": sum(r["verified"] for r in solved),
        "median_time_s": statistics.median(r["time_s"] for r in rows) if rows else None,
        "by_fallback": sum(r["fallback"] for r in solved),
        "statuses": {s: sum(r["status"] == s for r in rows) for s in {r["status"] for r in rows}},
    }
    if solved:
        out.update(
            max_sharpness=max(r["max_sharpness"] for r in solved),
            median_sharpness=statistics.median(r["max_sharpness"] for r in solved),
            max_curvature=max(r["max_curvature"] for r in solved),
            max_end_curvature=max(r["end_curvature"] for r in solved),
            mean_length_m=statistics.fmean(r["length_m"] for r in solved),
            over_bound=sum(r["max_sharpness"] > BOUND + 1e-9 for r in solved),
        )
    return out


def main(argv: list[str] | None = None) -> int:
    from results_io import out_folder  # the sibling module (run as a script)

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", type=positive_int, default=10,
                    help="planner seeds 0..N-1 per map (default: %(default)s)")
    ap.add_argument("--goals", type=int_at_least(0), default=100,
                    help="random poses (0: skip part 2) (default: %(default)s)")
    ap.add_argument("--goal-seed", type=int_at_least(0), default=1, help="seed of the random poses")
    ap.add_argument("--max-time", type=positive_float, default=5.0,
                    help="safety cap per plan [s] (default: %(default)s)")
    ap.add_argument("--out", type=out_folder, default="results",
                    help="directory for sharpness.json and .md (default: %(default)s)")
    args = ap.parse_args(argv)
    command = "python experiments/bench_sharpness.py " + " ".join(
        sys.argv[1:] if argv is None else argv
    )
    budget = Budget(max_time_s=args.max_time)
    maps: dict[str, dict] = {}
    # The tight maps (issue 13) are the coverage benchmark's: experiments/coverage.py.
    for name in [n for n in BUILTIN_MAPS if n not in TIGHT_MAP_NAMES]:
        m = builtin_map(name)
        problem = PlanningProblem.from_map(m)
        rows: dict[str, list[dict]] = {arm: [] for arm in SETTINGS}
        for seed in range(args.seeds):
            # Alternate which setting goes first: a map's first query warms caches.
            order = list(SETTINGS.items())[:: 1 if seed % 2 == 0 else -1]
            for arm, options in order:
                rows[arm].append(plan_row(m, problem, options, seed, budget))
        maps[name] = {arm: {"summary": summarise(rs), "rows": rs} for arm, rs in rows.items()}
        print(f"{name} done", file=sys.stderr)
    random: dict[str, dict] = {}
    for vary in ("goal", "start") if args.goals > 0 else ():
        base = builtin_map("parking_lot")
        rows = {arm: [] for arm in SETTINGS}
        for k, pose in enumerate(draw_goals("parking_lot", args.goals, args.goal_seed, vary)):
            m = dataclasses.replace(base, **{vary: pose})
            problem = PlanningProblem.from_map(m)
            for arm, options in SETTINGS.items():
                row = plan_row(m, problem, options, 0, budget)
                row[vary] = pose.as_tuple()
                rows[arm].append(row)
            print(f"random {vary} {k + 1}/{args.goals}", file=sys.stderr, end="\r")
        print(file=sys.stderr)
        random[vary] = {arm: {"summary": summarise(rs), "rows": rs} for arm, rs in rows.items()}
    out = FsPath(args.out)
    out.mkdir(parents=True, exist_ok=True)
    report = {"command": command, "bound_rad_per_m": BOUND, "seeds": args.seeds,
              "goals": args.goals, "goal_seed": args.goal_seed,
              "budget": {"max_time_s": args.max_time, "max_iterations": budget.max_iterations},
              "maps": maps, "random": random}  # fmt: skip
    write_text_atomic(out / "sharpness.json", json_text(report))
    md = [
        "# Sharpness of the improved planner's paths: clothoid turns (default) vs the paper's "
        "B-spline", "",
        f"Command: `{command}`  ",
        f"Bound of the default: `max |dδ/ds|` ≤ {BOUND} rad/m (0.4 rad/s at 2 m/s). Seeds "
        f"0–{args.seeds - 1} per map; both settings alternate per seed in one run. "
        "Sharpness from the path rows (exact for the clothoid rows; for the degree-2 "
        "B-spline the curvature jump over a sample gap, its true value being unbounded). "
        "Times are planning times (setup excluded); `verified`: "
        "`rrtdrive.verify.verify_path`.", "",
        "| map | setting | solved | verified | max sharpness [rad/m] | median sharpness "
        "| max κ [1/m] | max end κ | mean length [m] | median time [ms] |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]  # fmt: skip
    for name, arms in maps.items():
        for arm, data in arms.items():
            md.append(_line(name, arm, data["summary"]))
    ratios = {}
    for name, arms in maps.items():
        a, b = (arms[arm]["summary"]["median_time_s"] for arm in SETTINGS)
        ratios[name] = a / b if b else float("nan")
    md += ["", "Median planning time default / paper: " + ", ".join(
        f"`{n}` {r:.2f}" for n, r in ratios.items()) + " (target on `parking_lot`: ≤ 1.5).", ""]
    report["time_ratios"] = ratios
    for vary, arms in random.items():
        md += [
            f"## Random {vary} poses on `parking_lot` ({args.goals}, seed {args.goal_seed}; "
            "planner seed 0)", "",
            "| setting | solved | verified | by the fallback | over the bound | max sharpness "
            "| max end κ | other outcomes | median time [ms] |",
            "|---|---|---|---|---|---|---|---|---|",
        ]  # fmt: skip
        for arm, data in arms.items():
            s = data["summary"]
            other = ", ".join(f"{k} {v}" for k, v in sorted(s["statuses"].items())
                              if k != "solved")  # fmt: skip
            md.append(
                f"| {arm} | {s['solved']}/{s['runs']} | {s['verified']} | {s['by_fallback']} | "
                f"{s.get('over_bound', '–')} | {_num(s.get('max_sharpness'))} | "
                f"{_num(s.get('max_end_curvature'), 4)} | {other or '-'} | "
                f"{1e3 * s['median_time_s']:.1f} |"
            )
        md.append("")
    write_text_atomic(out / "sharpness.json", json_text(report))
    write_text_atomic(out / "sharpness.md", "\n".join(md) + "\n")
    print("\n".join(md))
    return 0


def _num(v: float | None, digits: int = 3) -> str:
    return "–" if v is None else f"{v:.{digits}f}"


def _line(name: str, arm: str, s: dict) -> str:
    return (
        f"| `{name}` | {arm} | {s['solved']}/{s['runs']} | {s['verified']} | "
        f"{_num(s.get('max_sharpness'))} | {_num(s.get('median_sharpness'))} | "
        f"{_num(s.get('max_curvature'), 4)} | {_num(s.get('max_end_curvature'), 4)} | "
        f"{_num(s.get('mean_length_m'), 2)} | {1e3 * s['median_time_s']:.1f} |"
    )


if __name__ == "__main__":
    from results_io import run_main

    raise SystemExit(run_main(main))
