"""Random user-like maps: ours against OMPL (Reeds-Shepp RRTConnect, or Dubins RRT forward).

Usage (OMPL lives in the lead's venv only; without it its rows are skipped)::

    python experiments/random_maps.py --maps 200 --jobs 2 --out results/random_maps
    python experiments/random_maps.py --maps 200 --jobs 2 --forward --out results/random_maps_fwd
    python experiments/random_maps.py --maps 50 --out /tmp/rm \\
        --planners hybrid-a-star,hybrid-a-star@persist=false

Each map (seeds ``0 .. --maps - 1``, one generator per seed): bounds 20-60 m by
15-40 m, 0-9 rectangles 0.5-8 m a side at any angle, start and goal anywhere 3 m or
more inside the bounds at any heading; a map whose start or goal body overlaps an
obstacle is drawn again from the same generator. Each of ``--planners`` plans it with
reverse (``--forward``: forward only; planner seed 0, 20 000 iterations, ``--max-time``
cap); a planner spec may carry options, ``NAME@field=value:...``. OMPL's RS RRTConnect
(``--forward``: its Dubins RRT; ``--ompl-time``, our exact body test as validity
checker, as ``experiments/coverage.py`` plans it) is the outside judge. Every path is
checked by ``verify_path`` with the 0.2 rad/m sharpness bound (``verified``) and
without it (``any sharpness``).

Writes ``OUT/random_maps.{json,md}``: per planner solved, verified, the share of OMPL's
solved maps it solves, median times and the maps OMPL solves and it does not (with the
least distance of OMPL's path to an obstacle or edge, by shapely).
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from typing import Any

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
import coverage as cov  # noqa: E402  (the sibling scripts)
from results_io import cell, command, machine, out_folder, write_results  # noqa: E402
from street_turns import least_clearance  # noqa: E402

from rrtdrive.bench.backends import episode_progress, parallel_map  # noqa: E402
from rrtdrive.cli_args import positive_float, positive_int  # noqa: E402
from rrtdrive.maps import Map, Obstacle  # noqa: E402
from rrtdrive.planning import PlanningProblem, make_planner  # noqa: E402
from rrtdrive.types import Budget, InputError, Pose  # noqa: E402

OMPL_NAMES = ("ompl-rs-rrtconnect", "ompl-dubins-rrt")
DEFAULT_PLANNERS = "improved-rrt-connect,hybrid-a-star"


def random_map(seed: int) -> Map:
    """The map of ``seed``: drawn until its start and goal bodies are free."""
    rng = np.random.default_rng(seed)
    while True:
        w, h = rng.uniform(20, 60), rng.uniform(15, 40)
        obstacles = tuple(
            Obstacle((rng.uniform(0, w), rng.uniform(0, h)),
                     (rng.uniform(0.5, 8), rng.uniform(0.5, 8)), rng.uniform(-math.pi, math.pi))
            for _ in range(rng.integers(0, 10))
        )  # fmt: skip
        ends = [
            Pose(rng.uniform(3, w - 3), rng.uniform(3, h - 3), rng.uniform(-math.pi, math.pi))
            for _ in range(2)
        ]
        try:
            return Map(f"random_{seed}", (0.0, 0.0, w, h), obstacles, *ends)
        except InputError:
            continue  # an end's body overlaps an obstacle: draw again


def run_one(item: dict[str, Any]) -> dict[str, Any]:
    """One map with one planner, with reverse unless ``item["forward"]``."""
    m = random_map(item["seed"])
    problem = PlanningProblem.from_map(m, reverse=not item["forward"])
    if item["planner"] in OMPL_NAMES:
        # Timed as experiments/coverage.py does: a solved query's time includes OMPL's
        # simplification (its length is the simplified path's).
        solve_s, total_s, length, path = cov.solve_ompl(problem, item["seed"], item["planner"],
                                                        item["ompl_time"])  # fmt: skip
        row = {"solved": path is not None, "time_s": total_s, "length_m": length}
        if path is None:
            return row | dict(cov._UNCHECKED)
        # How close OMPL's path passes (shapely): where ours misses, whether it kept
        # the clearance ours keep (0.15 m; 0.05 m in the last resort).
        return row | cov._check(m, path) | {"least_clearance_m": least_clearance(m, path)}
    spec, _, opts = item["planner"].partition("@")
    res = make_planner(spec, **cov._options(opts)).solve(
        problem, np.random.default_rng(0),
        Budget(max_iterations=20_000, max_time_s=item["max_time"]),
    )  # fmt: skip
    row = {
        "solved": res.success, "status": res.status.value, "time_s": res.planning_time_s,
        "iterations": res.iterations, "length_m": res.path.length if res.success else None,
        "message": res.message[:400],
    }  # fmt: skip
    return row | (cov._check(m, res.path) if res.success else dict(cov._UNCHECKED))


def summarise(rows: list[dict[str, Any]], planners: list[str], maps: int) -> dict[str, Any]:
    """Per planner: solved, verified, against OMPL, times."""
    by = {p: [r for r in rows if r["planner"] == p] for p in planners}
    ompl = {r["seed"]: r for name in OMPL_NAMES for r in by.get(name, [])}
    out: dict[str, Any] = {}
    for p, rs in by.items():
        solved = [r for r in rs if r["solved"]]
        s: dict[str, Any] = {
            "maps": maps, "solved": len(solved), "verified": sum(r["verified"] for r in rs),
            "any_sharpness": sum(r["verified_any_sharpness"] for r in rs),
            "median_time_solved_s": cov._median([r["time_s"] for r in solved]),
            "median_time_failed_s": cov._median([r["time_s"] for r in rs if not r["solved"]]),
            "max_time_s": max((r["time_s"] for r in rs), default=None),
        }  # fmt: skip
        if ompl and p not in OMPL_NAMES:
            theirs = [seed for seed, r in ompl.items() if r["solved"]]
            mine = {r["seed"] for r in solved}
            both = [seed for seed in theirs if seed in mine]
            s |= {
                "ompl_solved": len(theirs),
                "share_of_ompl": len(both) / len(theirs) if theirs else None,
                "missed": sorted(set(theirs) - mine),
                "ours_only": sorted(mine - set(theirs)),
                "time_ratio_of_medians": cov._ratio(
                    cov._median([r["time_s"] for r in solved if r["seed"] in both]),
                    cov._median([ompl[seed]["time_s"] for seed in both]),
                ),
            }  # fmt: skip
        out[p] = s
    return out


def _missed(seeds: list[int], rows: list[dict[str, Any]]) -> str:
    """The maps OMPL solves and a planner does not, each with OMPL's least clearance."""
    near = {r["seed"]: r.get("least_clearance_m") for r in rows if r["planner"] in OMPL_NAMES}
    return ", ".join(
        f"{seed} ({cell(near.get(seed), 1, 3)} m)" for seed in seeds
    ) or "-"


def report(payload: dict[str, Any]) -> str:
    """The page."""
    lines = [
        "# Random maps: ours "
        + ("forward only and OMPL's Dubins RRT" if payload["forward"]
           else "with reverse and OMPL's RS RRTConnect"),
        "",
        f"Command: `{payload['command']}`  ",
        f"{payload['machine']}; wall time {payload['wall_time_s'] / 60:.1f} min; load at the "
        f"start {payload['load']}. {payload['maps']} random maps (seeds 0-"
        f"{payload['maps'] - 1}; `random_map` in the script), each planned "
        f"{'forward only' if payload['forward'] else 'with reverse'}; ours "
        f"20 000 iterations (cap {payload['max_time']:g} s), OMPL {payload['ompl_time']:g} s.",
        "",
        "| planner | solved | verified | any sharpness | OMPL solved | share of OMPL's "
        "| maps OMPL solves, not this (its path's least clearance) | median time solved [ms] "
        "| time ratio of medians vs OMPL | median time failed [ms] | longest [s] |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for p, s in payload["summary"].items():
        share = s.get("share_of_ompl")
        lines.append(
            f"| {p} | {s['solved']}/{s['maps']} | {s['verified']} | {s['any_sharpness']} "
            f"| {s.get('ompl_solved', '-')} | {cell(share, 100, 1, ' %')} "
            f"| {_missed(s.get('missed', []), payload['rows'])} "
            f"| {cell(s['median_time_solved_s'], 1000)} "
            f"| {cell(s.get('time_ratio_of_medians'), 1, 3)} "
            f"| {cell(s['median_time_failed_s'], 1000)} | {cell(s['max_time_s'], 1, 2)} |"
        )
    lines += ["", "Failures of ours (map seed: status, message):", ""]
    for r in payload["rows"]:
        if r["planner"] not in OMPL_NAMES and not r["solved"]:
            lines.append(f"- `{r['planner']}` map {r['seed']}: {r['status']}: {r['message']}")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--maps", type=positive_int, default=100, help="random maps (default 100)")
    ap.add_argument("--planners", default=DEFAULT_PLANNERS,
                    help=f"our planner specs, comma-separated (default {DEFAULT_PLANNERS})")
    ap.add_argument("--max-time", type=positive_float, default=10.0,
                    help="our safety cap, s (default: %(default)s)")
    ap.add_argument("--ompl-time", type=positive_float, default=10.0,
                    help="OMPL's time, s (default: %(default)s)")
    ap.add_argument("--forward", action="store_true",
                    help="plan forward only (OMPL: Dubins RRT) instead of with reverse")
    ap.add_argument("--jobs", type=positive_int, default=1, help="worker processes")
    ap.add_argument("--out", type=out_folder, required=True,
                    help="directory for random_maps.{json,md}")
    args = ap.parse_args(argv)
    if args.maps < 1 or args.jobs < 1 or args.max_time <= 0 or args.ompl_time <= 0:
        ap.error("--maps and --jobs must be >= 1, --max-time and --ompl-time > 0")
    planners = [p for p in args.planners.split(",") if p]
    for p in planners:
        why = cov.availability(p)
        if why is not None:
            ap.error(f"--planners: {p}: {why}")
    ompl = OMPL_NAMES[1] if args.forward else OMPL_NAMES[0]
    if cov.availability(ompl) is None:
        planners.append(ompl)
    items = [
        {"seed": seed, "planner": p, "max_time": args.max_time, "ompl_time": args.ompl_time,
         "forward": args.forward}
        for seed in range(args.maps) for p in planners
    ]  # fmt: skip
    t0, load = time.perf_counter(), f"{os.getloadavg()[0]:.1f}"
    rows = parallel_map(run_one, items, args.jobs, progress=episode_progress(every=20))
    print(file=sys.stderr)
    rows = [item | row for item, row in zip(items, rows, strict=True)]
    payload = {
        "command": command("random_maps.py", argv), "machine": machine(), "load": load,
        "maps": args.maps, "max_time": args.max_time, "ompl_time": args.ompl_time,
        "forward": args.forward,
        "wall_time_s": time.perf_counter() - t0,
        "summary": summarise(rows, planners, args.maps), "rows": rows,
    }  # fmt: skip
    print(write_results(args.out, "random_maps", payload, report))
    return 0


if __name__ == "__main__":
    from results_io import run_main

    raise SystemExit(run_main(main))
