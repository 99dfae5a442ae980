"""The improved planner on random goal (or start) poses, as shipped and as the paper's pipeline.

Usage::

    python experiments/random_goals.py --map parking_lot --goals 100 --out results
    python experiments/random_goals.py --map parking_lot --goals 100 --vary start --out results

Draws ``--goals`` poses uniformly over the map (position and heading, seeded by
``--seed``), keeps those where the car's body is free, and plans from the map's
start to each (``--vary start``: from each to the map's goal) with
``improved-rrt-connect`` twice: as shipped (with the Dubins fallback and the Hybrid
A* escalation) and with ``dubins_fallback`` and ``escalation`` off (the paper's
pipeline alone, with the default clothoid post-processing). Every solved path is checked
by the independent :func:`rrtdrive.verify.verify_path`. A forward-only car cannot
reach every free pose (a car nose-first against a wall can only have reversed
there), so the share solved is a lower bound of what is reachable, not a rate
against a known answer. Writes ``OUT/random_goals_MAP.json`` and ``.md``
(``random_starts_MAP`` with ``--vary start``).
"""

from __future__ import annotations

import argparse
import collections
import dataclasses
import statistics
import sys
from pathlib import Path as FsPath

import numpy as np
from results_io import json_text, machine, out_folder  # the sibling module

from rrtdrive.cli_args import int_at_least, positive_float, positive_int
from rrtdrive.maps import BUILTIN_MAPS, builtin_map, write_text_atomic
from rrtdrive.planning.base import PlanningProblem
from rrtdrive.planning.hybrid.escalation import stage_of
from rrtdrive.planning.improved import ImprovedRRTConnect
from rrtdrive.pose_sets import random_free_poses
from rrtdrive.types import Budget, InputError, Pose
from rrtdrive.verify import verify_path


def draw_goals(map_name: str, count: int, seed: int, field: str = "goal") -> list[Pose]:
    """``count`` seeded poses where the body is free and the map accepts them as ``field``.

    The package's :func:`rrtdrive.pose_sets.random_free_poses`, under the name the
    benchmark scripts and their records use.
    """
    return random_free_poses(map_name, count, seed, field)


def add_pose_set_options(ap: argparse.ArgumentParser) -> None:
    """The options that pick the random pose set (:func:`draw_goals`): --map, --goals,
    --seed, --vary; shared with random_goals_hybrid.py, whose sets must be the same."""
    ap.add_argument("--map", default="parking_lot",
                    help="built-in map name (default: %(default)s)")
    ap.add_argument("--goals", type=positive_int, default=100,
                    help="random free poses to plan to (or from) (default: %(default)s)")
    ap.add_argument("--seed", type=int_at_least(0), default=1,
                    help="seed of the random poses (default: %(default)s)")
    ap.add_argument("--vary", choices=("goal", "start"), default="goal",
                    help="map pose the random poses replace (default: %(default)s)")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    add_pose_set_options(ap)
    ap.add_argument("--max-time", type=positive_float, default=5.0,
                    help="wall-clock safety cap per plan [s] (default: %(default)s)")
    ap.add_argument("--out", default="results", type=out_folder,
                    help="directory for random_{goals,starts}_MAP.json and .md "
                    "(default: %(default)s)")
    args = ap.parse_args(argv)
    if args.map not in BUILTIN_MAPS:
        raise InputError(f"--map: {args.map!r} is not a built-in map; this script plans on "
                         f"one of {sorted(BUILTIN_MAPS)}")
    base = builtin_map(args.map)
    budget = Budget(max_time_s=args.max_time)
    # The paper's pipeline alone: neither the Dubins fallback nor the Hybrid A* escalation
    # (ImprovedConfig: without("dubins_fallback", "escalation")).
    arms = {
        "with fallback": (),
        "paper pipeline (fallback and escalation off)": ("dubins_fallback", "escalation"),
    }
    rows = []
    for k, pose in enumerate(draw_goals(args.map, args.goals, args.seed, args.vary)):
        m = dataclasses.replace(base, **{args.vary: pose})
        problem = PlanningProblem.from_map(m)
        row = {args.vary: pose.as_tuple()}
        for arm, disable in arms.items():
            res = ImprovedRRTConnect(disable=disable).solve(
                problem, np.random.default_rng(0), budget
            )
            row[arm] = {
                "status": res.status.value,
                "verified": bool(res.success and verify_path(m, res.path).ok),
                "fallback": bool(res.stats.get("dubins_fallback", 0.0)),
                "stage": stage_of(res) if res.success else None,
                "time_s": res.planning_time_s,
                "length_m": res.path.length if res.success else None,
            }
        rows.append(row)
        print(f"{args.vary} {k + 1}/{args.goals}", file=sys.stderr, end="\r")
    print(file=sys.stderr)
    summary = {}
    for arm in arms:
        runs = [r[arm] for r in rows]
        solved = [x for x in runs if x["status"] == "solved"]
        summary[arm] = {
            "goals": len(runs),
            "solved": len(solved),
            "verified": sum(x["verified"] for x in runs),
            "by_fallback": sum(x["fallback"] for x in runs),
            "by_escalation": sum(x["stage"] == "hybrid-a-star" for x in runs),
            "statuses": dict(collections.Counter(x["status"] for x in runs)),
            "median_time_solved_s": (
                statistics.median(x["time_s"] for x in solved) if solved else None
            ),
        }
    command = "python experiments/random_goals.py " + " ".join(
        sys.argv[1:] if argv is None else argv
    )
    out = FsPath(args.out)
    out.mkdir(parents=True, exist_ok=True)
    stem = f"random_{args.vary}s_{args.map}"
    write_text_atomic(out / f"{stem}.json", json_text(
        {"command": command, "map": args.map, "seed": args.seed, "vary": args.vary,
         # The wall-clock cap can decide a query on a slow machine: both are recorded.
         "max_time_s": args.max_time, "machine": machine(),
         "summary": summary,
         "rows": rows}))
    lines = [
        f"# Random {args.vary} poses on `{args.map}`: improved RRT-Connect as shipped and as "
        "the paper's pipeline", "",
        f"Command: `{command}`  ",
        f"{args.goals} {args.vary} poses drawn uniformly (position and heading, seed "
        f"{args.seed}) where the body is free; "
        f"{'start' if args.vary == 'goal' else 'goal'} = the map's; planner seed 0; every "
        "solved path checked by `verify_path`.", "",
        "| planner | solved | verified | solved by the fallback | solved by the escalation "
        "| other outcomes | median time of the solved [ms] |",
        "|---|---|---|---|---|---|---|",
    ]
    for arm, s in summary.items():
        other = ", ".join(f"{k} {v}" for k, v in sorted(s["statuses"].items()) if k != "solved")
        t = s["median_time_solved_s"]
        lines.append(
            f"| {arm} | {s['solved']}/{s['goals']} | {s['verified']} | {s['by_fallback']} | "
            f"{s['by_escalation']} | {other or '-'} | {'-' if t is None else f'{t * 1e3:.1f}'} |"
        )
    write_text_atomic(out / f"{stem}.md", "\n".join(lines) + "\n")
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    from results_io import run_main

    raise SystemExit(run_main(main))
