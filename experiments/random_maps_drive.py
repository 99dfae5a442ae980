"""Random user-like maps driven closed loop: plan with reverse, track in highway-env, judge.

Usage::

    python experiments/random_maps_drive.py --maps 200 --jobs 2 --out results/random_maps_drive
    python experiments/random_maps_drive.py --seeds 36,112 --out results/random_maps_drive_two

The maps of ``experiments/random_maps.py`` (seeds ``0 .. --maps - 1``), each driven
from its start to its goal as ``rrtdrive simulate MAP --reverse`` drives it (episode
seed 0, the default planner unless ``--planner``), by each controller of
``--controllers``, through :func:`rrtdrive.sim.runner.run_episode` and judged by
:func:`rrtdrive.evaluation.evaluate` (highway-env's collisions and the exact footprint
judge). Writes ``OUT/random_maps_drive.{json,md}``: per controller the episodes that
arrived, planning failures, collisions by either judge, the largest cross-track and
goal errors and gear changes driven, then every episode that did not arrive.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import sys
import time
from typing import Any

sys.path.insert(0, os.path.dirname(__file__))
from random_maps import random_map  # noqa: E402
from results_io import cell, command, machine, out_folder, write_results  # noqa: E402

from rrtdrive.bench.backends import episode_progress, parallel_map  # noqa: E402
from rrtdrive.cli_args import positive_int  # noqa: E402
from rrtdrive.types import VehicleParams  # noqa: E402

CONTROLLERS = ("pure-pursuit", "stanley", "lqr")


def driving_task(seed: int, vehicle: VehicleParams | None = None) -> Any:
    """Random map ``seed`` driven start to goal with reverse, episode seed 0 (on ``vehicle``).

    The task of this script's episodes, and of ``commonroad_judge.py --random-maps``.
    """
    from rrtdrive.sim.tasks import CustomTask

    m = random_map(seed)
    if vehicle is not None:
        m = dataclasses.replace(m, vehicle=vehicle)
    return CustomTask.from_map(m, 0, reverse=True)


def drive(item: tuple[int, str, str]) -> dict[str, Any]:
    """One map, one controller: the episode's judged outcome."""
    from rrtdrive.evaluation import evaluate
    from rrtdrive.sim.runner import run_episode

    seed, controller, planner = item
    ep = run_episode(driving_task(seed), planner=planner, controller=controller, seed=0)
    ev = evaluate(ep).to_json()
    return {
        "map": seed, "controller": controller, "status": ep.status.value,
        "success": bool(ev["success"]), "plan_status": ep.plan.status.value if ep.plan else None,
        "collision_highway_env": bool(ev["collision_highway_env"]),
        "collision_footprint": bool(ev["collision_footprint"]),
        "cte_max_m": ev["cte_max_m"], "goal_position_err_m": ev["goal_position_err_m"],
        "cusps": len(ep.path.cusps), "gear_changes": ev["gear_changes"],
        "duration_s": ev["duration_s"], "nuplan_comfortable": ev.get("nuplan_comfortable"),
        "message": ep.message[:200],
    }  # fmt: skip


def summarise(rows: list[dict[str, Any]]) -> dict[str, dict[str, Any]]:
    """Per controller: counts and the worst errors over the episodes that drove."""
    out: dict[str, dict[str, Any]] = {}
    for c in dict.fromkeys(r["controller"] for r in rows):
        mine = [r for r in rows if r["controller"] == c]
        drove = [r for r in mine if r["plan_status"] == "solved"]
        out[c] = {
            "episodes": len(mine),
            "success": sum(r["success"] for r in mine),
            "plan_failed": len(mine) - len(drove),
            "collision_highway_env": sum(r["collision_highway_env"] for r in mine),
            "collision_footprint": sum(r["collision_footprint"] for r in mine),
            "cte_max_m": max((r["cte_max_m"] for r in drove), default=None),
            "goal_error_max_m": max((r["goal_position_err_m"] for r in drove), default=None),
            "with_cusps": sum(r["cusps"] > 0 for r in drove),
            "gear_changes_equal_cusps": sum(r["gear_changes"] == r["cusps"] for r in drove),
        }
    return out


def _seeds(payload: dict[str, Any]) -> str:
    """The map seeds of a payload: a range, or the list given with ``--seeds``."""
    seeds = sorted({r["map"] for r in payload["rows"]})
    if seeds == list(range(len(seeds))):
        return f"0-{len(seeds) - 1}"
    return ", ".join(map(str, seeds))


def report(payload: dict[str, Any]) -> str:
    """The markdown page of a payload."""
    lines = [
        "# Random maps driven closed loop, with reverse",
        "",
        f"Command: `{payload['command']}`  ",
        f"{payload['machine']}; wall time {payload['wall_time_s'] / 60:.1f} min. "
        f"{payload['maps']} maps of `experiments/random_maps.py` (seeds {_seeds(payload)}), "
        f"each driven from its start to its goal (`{payload['planner']}`, reverse allowed, "
        "episode seed 0).",
        "",
        "| controller | arrived | plan failed | collisions (highway-env / footprint) | "
        "CTE max [m] | goal error max [m] | plans with cusps | gear changes driven = cusps |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for c, s in payload["summary"].items():
        cte, goal = cell(s["cte_max_m"], 1, 3), cell(s["goal_error_max_m"], 1, 3)
        lines.append(
            f"| {c} | {s['success']}/{s['episodes']} | {s['plan_failed']} | "
            f"{s['collision_highway_env']} / {s['collision_footprint']} | {cte} | {goal} | "
            f"{s['with_cusps']} | {s['gear_changes_equal_cusps']} |"
        )
    misses = [r for r in payload["rows"] if not r["success"]]
    lines += ["", "Episodes that did not arrive (map: controller, status, message):", ""]
    lines += [f"- map {r['map']}: {r['controller']}, {r['status']}: {r['message']}" for r in misses]
    if not misses:
        lines.append("- none")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--maps", type=positive_int, default=200,
                    help="maps: seeds 0..N-1 (default 200)")
    ap.add_argument("--seeds", default=None, metavar="S,S,...",
                    help="these map seeds instead of 0..--maps - 1")  # fmt: skip
    ap.add_argument("--controllers", default=",".join(CONTROLLERS),
                    help="comma-separated (default: %(default)s)")
    ap.add_argument("--planner", default="improved-rrt-connect", help="planner (the default's)")
    ap.add_argument("--jobs", type=positive_int, default=1, help="worker processes (default 1)")
    ap.add_argument("--out", type=out_folder, default="results/random_maps_drive",
                    help="directory for random_maps_drive.json and .md (default: %(default)s)")
    args = ap.parse_args(argv)
    controllers = [c.strip() for c in args.controllers.split(",") if c.strip()]
    unknown = sorted(set(controllers) - set(CONTROLLERS))
    if unknown or not controllers:
        ap.error(f"--controllers: choose from {', '.join(CONTROLLERS)}, got {args.controllers!r}")
    if args.maps < 1 or args.jobs < 1:
        ap.error("--maps and --jobs must be >= 1")
    from rrtdrive.planning import PLANNERS

    if args.planner not in PLANNERS:
        ap.error(f"--planner: unknown planner {args.planner!r}; choose from {sorted(PLANNERS)}")
    t0 = time.perf_counter()
    try:
        seeds = (
            [int(x) for x in args.seeds.split(",") if x.strip()]
            if args.seeds is not None else list(range(args.maps))
        )  # fmt: skip
    except ValueError:
        ap.error(f"--seeds: expected comma-separated integers, got {args.seeds!r}")
    if not seeds or min(seeds) < 0:
        ap.error(f"--seeds: expected non-negative map seeds, got {args.seeds!r}")
    items = [(seed, c, args.planner) for seed in seeds for c in controllers]
    rows = parallel_map(drive, items, args.jobs, episode_progress())
    payload = {
        "command": command("random_maps_drive.py", argv), "maps": len(seeds),
        "planner": args.planner, "machine": machine(),
        "wall_time_s": time.perf_counter() - t0,
        "summary": summarise(rows), "rows": rows,
    }  # fmt: skip
    print(write_results(args.out, "random_maps_drive", payload, report))
    return 0


if __name__ == "__main__":
    from results_io import run_main

    raise SystemExit(run_main(main))
