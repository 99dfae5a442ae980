"""Record or compare a behaviour snapshot: plan JSON and episode metrics, timings dropped.

Used to show that a change of structure does not change behaviour: record before
the change, compare after it.

    python experiments/behaviour_snapshot.py --record results/behaviour_before.json
    python experiments/behaviour_snapshot.py --compare results/behaviour_before.json

What it records (wall-clock limits off, so the outcome is decided by iteration
budgets alone):

- ``rrtdrive plan`` JSON of every built-in map x planner (rrt, rrt-connect, rrt-star,
  improved-rrt-connect) for seeds 0-4;
- the episode metrics JSON of parking, overtake and overtake-traffic for seeds 0-4 x
  pure-pursuit, stanley, lqr, plus a SHA-256 of each episode's logged states and
  commands.

Timing fields (``planning_time_s``, ``wall_time_s``, re-plan cycle times) are dropped,
and wall times quoted in messages are masked.
Exit code 0 when ``--compare`` finds every entry equal, 1 otherwise (each difference
is printed).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import re
import sys
from pathlib import Path

import numpy as np

from rrtdrive import Budget, builtin_map
from rrtdrive.atomic import write_text_atomic
from rrtdrive.cli import plan_to_json
from rrtdrive.planning import PlanningProblem, make_planner
from rrtdrive.planning.smoothing import CurveKind

MAPS = ("overtake", "parking_lot", "narrow_gap", "no_path")
PLANNERS = ("rrt", "rrt-connect", "rrt-star", "improved-rrt-connect")
SCENARIOS = ("parking", "overtake", "overtake-traffic")
CONTROLLERS = ("pure-pursuit", "stanley", "lqr")
SEEDS = range(5)
#: Fields that measure wall time: they differ from run to run.
TIMING_KEYS = {
    "planning_time_s",
    "setup_time_s",
    "diagnosis_time_s",
    "wall_time_s",
    "replan_time_median_s",
    "replan_time_max_s",
    "replans_over_budget",
}
#: A time cap no query reaches, so iteration budgets alone decide.
NO_WALL_LIMIT_S = 1e6


#: Wall times quoted inside messages, e.g. "(20000 iterations, 6.664 s, 8268 nodes)".
_SECONDS = re.compile(r"\b\d+\.\d+ s\b")


def _drop_timing(d: dict) -> dict:
    out = {k: v for k, v in d.items() if k not in TIMING_KEYS}
    if isinstance(out.get("message"), str):
        out["message"] = _SECONDS.sub("<t> s", out["message"])
    return out


def plan_entries(paper: bool = False) -> dict[str, dict]:
    """Plan JSON (timings dropped) of every built-in map x planner x seed.

    ``paper``: the improved planner with the paper's B-spline post-processing
    (``rrtdrive plan --paper-smoothing``) instead of the default clothoid turns.
    """
    out: dict[str, dict] = {}
    budget = Budget(max_time_s=NO_WALL_LIMIT_S)
    for name in MAPS:
        problem = PlanningProblem.from_map(builtin_map(name))
        for planner in PLANNERS:
            options: dict[str, object] = {}
            if paper and planner == "improved-rrt-connect":
                options["smoothing"] = {"curve": CurveKind.BSPLINE}
            for seed in SEEDS:
                result = make_planner(planner, **options).solve(
                    problem, np.random.default_rng(seed), budget
                )
                out[f"plan/{name}/{planner}/{seed}"] = _drop_timing(
                    plan_to_json(
                        result, seed, name, budget=budget,
                        resolution=problem.checker.resolution,
                    )
                )
    return out


def _log_digest(episode: object) -> str:
    log = episode.log  # type: ignore[attr-defined]
    h = hashlib.sha256()
    for name in ("t", "states", "controls", "crashed", "others"):
        value = getattr(log, name, None)
        if value is not None:
            h.update(np.ascontiguousarray(np.asarray(value, dtype=float)).tobytes())
    return h.hexdigest()


def episode_entries() -> dict[str, dict]:
    """Episode metrics (timings dropped) and log digests, wall-clock limits off."""
    from rrtdrive.evaluation import evaluate
    from rrtdrive.sim.replanning import ReplanConfig
    from rrtdrive.sim.runner import EpisodeConfig, run_episode

    out: dict[str, dict] = {}
    for scenario in SCENARIOS:
        for controller in CONTROLLERS:
            for seed in SEEDS:
                config = EpisodeConfig(
                    budget=Budget(max_time_s=NO_WALL_LIMIT_S),
                    replan=ReplanConfig(wall_limit=False),
                )
                ep = run_episode(scenario, controller=controller, seed=seed, config=config)
                entry = _drop_timing(evaluate(ep).to_json())
                entry["log_sha256"] = _log_digest(ep)
                out[f"episode/{scenario}/{controller}/{seed}"] = entry
                print(f"{scenario} {controller} {seed}: {entry['status']}", file=sys.stderr)
    return out


def snapshot(episodes: bool = True, paper: bool = False) -> dict[str, dict]:
    """The whole snapshot (``paper``: plans with the paper's smoothing, see plan_entries)."""
    data = plan_entries(paper)
    if episodes:
        data.update(episode_entries())
    return data


#: Plan JSON keys added with gears (issue #13), and their value for a forward-only plan.
GEAR_DEFAULTS = {"reverse": False, "cusps": 0}


def with_gears(entry: dict) -> dict:
    """A plan entry recorded before gears in today's form: 4-number rows get gear +1."""
    if "path" not in entry:
        return entry
    out = {**GEAR_DEFAULTS, **entry}
    out["path"] = [list(row) + [1.0] if len(row) == 4 else row for row in entry["path"]]
    return out


#: Plan JSON keys added since session 44 (the budget and grid a plan was made with): a
#: record older than them is compared on the rest.
ADDED_FIELDS = frozenset({"max_iterations", "max_time_s", "resolution_m"})


def compare(before: dict[str, dict], after: dict[str, dict]) -> list[str]:
    """Human-readable differences between two snapshots (older plan entries read with gears)."""
    diffs = []
    before = {k: with_gears(v) if k.startswith("plan/") else v for k, v in before.items()}
    for key in sorted(set(before) | set(after)):
        a, b = before.get(key), after.get(key)
        if a is None or b is None:
            diffs.append(f"{key}: only in {'after' if a is None else 'before'}")
            continue
        for field in sorted(set(a) | set(b)):
            if field in ADDED_FIELDS and field not in a:
                continue
            if a.get(field) != b.get(field):
                va, vb = repr(a.get(field))[:80], repr(b.get(field))[:80]
                diffs.append(f"{key}.{field}: {va} -> {vb}")
    return diffs


def main() -> int:
    from results_io import json_text  # the sibling module (run as a script)

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    group = ap.add_mutually_exclusive_group(required=True)
    group.add_argument("--record", metavar="FILE", help="write a snapshot to FILE")
    group.add_argument("--compare", metavar="FILE", help="compare against a recorded FILE")
    ap.add_argument("--plans-only", action="store_true", help="skip the episodes")
    ap.add_argument(
        "--paper", action="store_true",
        help="plan with the paper's B-spline smoothing (rrtdrive plan --paper-smoothing); "
        "episodes keep the default planner",
    )
    args = ap.parse_args()
    data = snapshot(episodes=not args.plans_only, paper=args.paper)
    if args.record:
        write_text_atomic(args.record, json_text(data, sort_keys=True))
        print(f"recorded {len(data)} entries in {args.record}")
        return 0
    before = json.loads(Path(args.compare).read_text())
    if args.plans_only:
        before = {k: v for k, v in before.items() if k.startswith("plan/")}
    diffs = compare(before, data)
    for line in diffs:
        print(line)
    print(f"{len(data)} entries compared, {len(diffs)} differences")
    return 1 if diffs else 0


if __name__ == "__main__":
    from results_io import run_main

    raise SystemExit(run_main(main))
