"""Coverage benchmark: which random queries each planner solves, side by side in one run.

Usage (the OMPL rows need ``pip install "ompl>=2.0.1"`` in the same environment)::

    python experiments/coverage.py --map parking_lot \
        --count 100 --jobs 2 --out results --doc docs/coverage.md

The random goal poses and the random start poses of ``experiments/random_goals.py``
(``--count`` of each, seed ``--seed``: uniform position and heading where the body
is free; the other end is the map's own) are planned by every planner of
``--planners`` (comma-separated):

- a registered rrtdrive planner by name (``improved-rrt-connect``, ``hybrid-a-star``
  ...), planner seed 0, budget ``--max-time``; ``NAME+reverse`` plans the same with
  reversing allowed (``PlanningProblem(..., reverse=True)``); a tail
  ``@field=value:...`` passes planner options, e.g.
  ``improved-rrt-connect+reverse@rrt_share=1:escalation_fallback_joints=64`` (the
  RRT-Connect stages on their full budgets, as before the counted share);
- ``ompl-dubins-rrt`` (``DubinsStateSpace(r_min)`` + RRT, forward only) and
  ``ompl-rs-rrtconnect`` (``ReedsSheppStateSpace(r_min)`` + RRTConnect, reversing),
  range 5 m, ``--ompl-time`` seconds, our *exact* body test
  (:meth:`~rrtdrive.collision.CollisionChecker.pose_free`) as the validity checker,
  motions checked every 0.25 m, the solution simplified (``simplifySolution``).

A name that is not available today (a planner not registered, ``+reverse`` before
``PlanningProblem`` has its ``reverse`` field, OMPL not installed) is skipped with a
note in the output. Every solved path is checked by :func:`rrtdrive.verify.verify_path`
per gear segment, with the sharpness bound of 0.2 rad/m (``verified``) and without
it (``verified_any_sharpness``); OMPL's paths are its own curves sampled 0.1 m
apart, with gears and cusps read off the motion. Per planner and set: solved,
verified, median planning time and length of the solved, median time of the
failures; per pair (ours, OMPL): the share of OMPL's solved that ours solves and,
on the queries both solve, the median per-query time and length ratios and the
ratios of the medians. OMPL's times include its simplification. OMPL seeds its RNG
once per worker process, so OMPL rows are not reproducible query by query; ours are.

Writes ``OUT/coverage_MAP.json`` (every row, the resolved settings) and ``.md``.
"""

from __future__ import annotations

import argparse
import dataclasses
import importlib.util
import json
import math
import os
import platform
import statistics
import sys
import time
from pathlib import Path as FsPath
from typing import Any

import numpy as np

sys.path.insert(0, str(FsPath(__file__).resolve().parent))
from coverage_report import SHARPNESS_BOUND, report, tight_report  # noqa: E402
from random_goals import draw_goals  # noqa: E402  (the sibling script's pose sets)
from results_io import check_doc, json_text, out_folder, write_doc  # noqa: E402

from rrtdrive.atomic import write_text_atomic  # noqa: E402
from rrtdrive.bench.backends import parallel_map  # noqa: E402
from rrtdrive.cli_args import flags_for, int_at_least, positive_float, positive_int  # noqa: E402
from rrtdrive.maps import builtin_map  # noqa: E402
from rrtdrive.planning import PLANNERS, PlanningProblem, make_planner  # noqa: E402
from rrtdrive.planning.hybrid.escalation import stage_of  # noqa: E402
from rrtdrive.planning.smoothing import max_sharpness  # noqa: E402
from rrtdrive.types import Budget, InputError, Path, Pose  # noqa: E402
from rrtdrive.verify import verify_path  # noqa: E402

DEFAULT_PLANNERS = (
    "improved-rrt-connect,improved-rrt-connect+reverse,hybrid-a-star,hybrid-a-star+reverse,"
    "ompl-dubins-rrt,ompl-rs-rrtconnect"
)
#: Stage counters of the improved planner copied into a row when present.
STAGE_STATS = (
    "postprocess_attempts", "rrt_iterations", "rrt_stages_time_s", "escalation_time_s",
    "dubins_time_s", "hybrid_expansions",
)
#: OMPL comparators: name -> (state space, geometric planner class).
OMPL = {"ompl-dubins-rrt": ("dubins", "RRT"), "ompl-rs-rrtconnect": ("rs", "RRTConnect")}


def ompl_spec(name: str) -> tuple[str, float] | None:
    """``(OMPL planner, body clearance)`` of an OMPL row's name, ``None`` for ours.

    ``ompl-dubins-rrt`` lets states touch obstacles (0 m); ``ompl-dubins-rrt@0.15m`` keeps
    0.15 m, as ours do (a ValueError for a clearance that is not a number of metres).

    Examples
    --------
    >>> ompl_spec("ompl-dubins-rrt@0.15m"), ompl_spec("ompl-rs-rrtconnect"), ompl_spec("rrt")
    (('ompl-dubins-rrt', 0.15), ('ompl-rs-rrtconnect', 0.0), None)
    """
    base, at, tail = name.partition("@")
    if base not in OMPL:
        return None
    if not at:
        return base, 0.0
    try:
        clearance = float(tail.removesuffix("m"))
    except ValueError:
        clearance = math.nan
    if not tail.endswith("m") or not 0.0 <= clearance <= 1.0:
        raise ValueError(f"{name}: expected {base}@<clearance in metres, 0-1>m, e.g. @0.15m")
    return base, clearance


def availability(name: str) -> str | None:
    """Why planner spec ``name`` cannot run today, or ``None`` when it can."""
    try:
        ompl = ompl_spec(name)
    except ValueError as exc:
        return str(exc)
    if ompl is not None:
        if importlib.util.find_spec("ompl") is None:
            return "OMPL is not installed here (pip install '.[ompl]')"
        return None
    spec, _, opts = name.partition("@")
    try:
        _options(opts)
    except ValueError as exc:
        return str(exc)
    base, _, flag = spec.partition("+")
    if flag and flag != "reverse":
        return f"unknown suffix +{flag}"
    if base not in PLANNERS:
        return f"planner {base!r} is not registered (yet)"
    if flag and "reverse" not in {f.name for f in dataclasses.fields(PlanningProblem)}:
        return "PlanningProblem has no reverse field yet"
    return None


def _problem(item: dict[str, Any]) -> tuple[Any, PlanningProblem]:
    base = builtin_map(item["map"])
    m = dataclasses.replace(base, **{item["vary"]: Pose(*item["pose"])})
    return m, PlanningProblem.from_map(m)


#: The check fields of a row without a path.
_UNCHECKED = {"verified": False, "verified_any_sharpness": False, "collision_free": False}


def _check(m: Any, path: Path) -> dict[str, Any]:
    """The independent check, with the sharpness bound and without it."""
    check = verify_path(m, path, max_sharpness=SHARPNESS_BOUND)
    return {
        "verified": bool(check.ok),
        "verified_any_sharpness": check.failed in ((), ("sharpness_ok",)),
        "collision_free": bool(check.collision_free),
        "discrete_sharpness": check.max_discrete_sharpness,
    }


def _options(text: str) -> dict[str, Any]:
    """Planner options of a spec's ``@field=value:...`` tail (values as JSON numbers or words).

    Examples
    --------
    >>> _options("rrt_share=1:escalation_fallback_joints=64"), _options("")
    ({'rrt_share': 1, 'escalation_fallback_joints': 64}, {})
    """
    out: dict[str, Any] = {}
    for part in filter(None, text.split(":")):
        key, eq, value = part.partition("=")
        if not eq or not key:
            raise ValueError(f"bad planner option {part!r}: expected field=value")
        try:
            out[key] = json.loads(value)
        except json.JSONDecodeError:
            out[key] = value
    return out


def run_ours(item: dict[str, Any]) -> dict[str, Any]:
    """One query with an rrtdrive planner."""
    m, problem = _problem(item)
    spec, _, opts = item["planner"].partition("@")
    base, _, flag = spec.partition("+")
    if flag == "reverse":
        problem = dataclasses.replace(problem, reverse=True)
    res = make_planner(base, **_options(opts)).solve(
        problem, np.random.default_rng(item.get("seed", 0)), Budget(max_time_s=item["max_time"])
    )
    row: dict[str, Any] = {
        "status": res.status.value,
        "solved": res.success,
        "time_s": res.planning_time_s,
        "length_m": res.path.length if res.success else None,
        "cusps": len(res.path.cusps) if res.success else None,
        "message": res.message[:300],
        "iterations": res.iterations,
    }
    # Which stage answered and what the stages before it cost (the default planner's
    # counted shares, ImprovedConfig.rrt_share): the stages' own counters.
    if base == "improved-rrt-connect":
        row["stage"] = stage_of(res) if res.success else None
    for key in STAGE_STATS:
        if key in res.stats:
            row[key] = res.stats[key]
    if res.success:
        # Per gear segment (a cusp is a stop); JSON has no inf: a jump is the string "inf".
        sharp = max_sharpness(res.path.samples, problem.vehicle.wheelbase)
        row["max_sharpness"] = sharp if math.isfinite(sharp) else "inf"
    diagnosis = getattr(res, "diagnosis", None)
    if diagnosis is not None:
        row["diagnosis"] = diagnosis.kind.value
    if "diagnosis_time_s" in res.stats:  # after the stopwatch, before the answer
        row["diagnosis_time_s"] = res.stats["diagnosis_time_s"]
    row.update(_check(m, res.path) if res.success else _UNCHECKED)
    return row


def solve_ompl(
    problem: PlanningProblem, index: int, planner: str, seconds: float, clearance: float = 0.0,
    cap_at_ends: bool = False,
) -> tuple[float, float, float | None, Path | None]:
    """OMPL's ``planner`` on query ``index``, with our exact body test as validity checker.

    Returns the solve time, the time with its simplification, the simplified path's
    length and the path itself: rows at most 0.1 m apart along OMPL's own curves,
    with the gears of its motion and each cusp repeated
    (:func:`rrtdrive.bench.ompl_planners.reeds_shepp_path`; all forward for Dubins);
    ``clearance``: the distance every state's body must keep (0: touching is valid; our
    planners keep 0.15 m, so a comparison at their clearance sets it to that);
    ``cap_at_ends``: capped, as ours are, at the start's and goal's own body clearance
    (else a start 0.1 m from a car is no valid state and OMPL answers nothing at once).

    ``None``, ``None`` without an exact solution.
    """
    from ompl import base as ob
    from ompl import geometric as og
    from ompl import util as ou

    from rrtdrive.bench.ompl_planners import reeds_shepp_path, simple_setup

    ou.setLogLevel(ou.LogLevel.LOG_NONE)
    space, algorithm = OMPL[planner]
    ss, si = simple_setup(problem, space)
    free = problem.checker.pose_free
    if cap_at_ends and clearance > 0.0:
        # A micron under the ends' own: the exact test wants more than the clearance, so a
        # start kept exactly at its own would be no valid state (7 of 400 random starts).
        ends = (problem.start.as_tuple(), problem.goal.as_tuple())
        own = min(problem.checker.body_clearance(e) for e in ends)
        clearance = max(0.0, min(clearance, own - 1e-6))
    ss.setStateValidityChecker(lambda s: free((s.getX(), s.getY(), s.getYaw()), clearance))
    ou.RNG.setSeed(1 + index)  # takes effect only before a process's first draw
    search = getattr(og, algorithm)(si)
    search.setRange(5.0)
    ss.setPlanner(search)
    objective = ob.PathLengthOptimizationObjective(si)
    objective.setCostThreshold(ob.Cost(float("inf")))
    ss.setOptimizationObjective(objective)
    t0 = time.perf_counter()
    status = ss.solve(float(seconds))
    solve_s = time.perf_counter() - t0
    if status.asString() != "Exact solution":
        return solve_s, solve_s, None, None
    ss.simplifySolution()
    total_s = time.perf_counter() - t0
    sol = ss.getSolutionPath()
    corners = np.array([(sol.getState(i).getX(), sol.getState(i).getY())
                        for i in range(sol.getStateCount())])  # fmt: skip
    return solve_s, total_s, float(sol.length()), reeds_shepp_path(si.getStateSpace(), sol, corners)


def run_ompl(item: dict[str, Any]) -> dict[str, Any]:
    """One query with OMPL on our exact body test."""
    m, problem = _problem(item)
    spec = ompl_spec(item["planner"])
    assert spec is not None
    base, clearance = spec
    solve_s, total_s, length, path = solve_ompl(
        problem, item["index"], base, item["ompl_time"], clearance, cap_at_ends=True
    )
    exact = path is not None
    row: dict[str, Any] = {"status": "solved" if exact else "no_path_in_budget", "solved": exact}
    if path is None:
        row.update(time_s=solve_s, solve_s=solve_s, length_m=None, **_UNCHECKED)
        return row
    row.update(time_s=total_s, solve_s=solve_s, length_m=length, cusps=len(path.cusps),
               **_check(m, path))
    return row


def run_one(item: dict[str, Any]) -> dict[str, Any]:
    """A worker's job: one (query, planner) pair; the row carries its item's keys."""
    row = run_ompl(item) if ompl_spec(item["planner"]) else run_ours(item)
    keys = ("map", "vary", "index", "planner", "query", "seed")
    return {**{k: item[k] for k in keys if k in item}, **row}


def _median(values: list[float]) -> float | None:
    return statistics.median(values) if values else None


def _ratio(a: float | None, b: float | None) -> float | None:
    return None if a is None or not b else a / b




def _sharpness(ok: list[dict[str, Any]]) -> dict[str, Any]:
    """The largest sharpness of the solved paths and how many keep the bound."""
    vals = [math.inf if r["max_sharpness"] == "inf" else r["max_sharpness"]
            for r in ok if "max_sharpness" in r]  # fmt: skip
    if not vals:
        return {"max_sharpness": None, "within_bound": None}
    top = max(vals)
    return {
        "max_sharpness": top if math.isfinite(top) else "inf",
        "within_bound": sum(v <= SHARPNESS_BOUND + 1e-9 for v in vals),
    }


def _stages(vals: list[dict[str, Any]]) -> dict[str, Any]:
    """The default planner's stages: which solved, and the time of the stages before it."""
    if not any("rrt_iterations" in r for r in vals):
        return {}
    by: dict[str, int] = {}
    for r in vals:
        if r["solved"] and r.get("stage"):
            by[r["stage"]] = by.get(r["stage"], 0) + 1
    escalated = [r for r in vals if "rrt_stages_time_s" in r]
    return {
        "solved_by_stage": by,
        "escalated": len(escalated),
        "median_rrt_stages_time_escalated_s": _median(
            [r["rrt_stages_time_s"] for r in escalated]
        ),
        "median_escalation_time_s": _median(
            [r["escalation_time_s"] for r in escalated if "escalation_time_s" in r]
        ),
    }


def _cusp_pair(ours: list[dict[str, Any]], ref: list[dict[str, Any]]) -> dict[str, Any]:
    """Gear changes (each a stop) on the queries both solve: means and per-query order.

    Empty when a row has no count (a results file from before the count was kept).
    """
    if not ours or any(r.get("cusps") is None for r in (*ours, *ref)):
        return {}
    diff = [a["cusps"] - b["cusps"] for a, b in zip(ours, ref, strict=True)]
    return {
        "mean_cusps_ours": statistics.fmean(r["cusps"] for r in ours),
        "mean_cusps_ompl": statistics.fmean(r["cusps"] for r in ref),
        "median_cusps_ours": _median([r["cusps"] for r in ours]),
        "median_cusps_ompl": _median([r["cusps"] for r in ref]),
        "cusps_fewer_equal_more": [sum(d < 0 for d in diff), sum(d == 0 for d in diff),
                                   sum(d > 0 for d in diff)],
    }


def summarise(rows: list[dict[str, Any]], planners: list[str], sets: list[str]) -> dict:
    """Per planner x set figures and the (ours, OMPL) pair figures."""
    cell: dict[tuple[str, str], dict[int, dict]] = {
        (p, s): {} for p in planners for s in sets
    }
    for r in rows:
        cell[(r["planner"], r["vary"])][r["index"]] = r
    per: dict[str, dict[str, Any]] = {}
    for (p, s), runs in cell.items():
        vals = list(runs.values())
        ok = [r for r in vals if r["solved"]]
        bad = [r for r in vals if not r["solved"]]
        statuses: dict[str, int] = {}
        for r in vals:
            statuses[r["status"]] = statuses.get(r["status"], 0) + 1
        per.setdefault(p, {})[s] = {
            "queries": len(vals),
            "solved": len(ok),
            "verified": sum(r["verified"] for r in vals),
            "verified_any_sharpness": sum(r.get("verified_any_sharpness", False) for r in vals),
            "collision_free": sum(r["collision_free"] for r in vals),
            "median_time_solved_s": _median([r["time_s"] for r in ok]),
            "median_length_m": _median([r["length_m"] for r in ok]),
            "median_time_failed_s": _median([r["time_s"] for r in bad]),
            # What a user waits for a failure: the search and then its diagnosis.
            "median_answer_time_failed_s": _median(
                [r["time_s"] + r.get("diagnosis_time_s", 0.0) for r in bad]
            ),
            "statuses": statuses,
            **_sharpness(ok),
            **_stages(vals),
        }
    pairs: dict[str, dict[str, Any]] = {}
    ompl = [p for p in planners if ompl_spec(p)]
    for ours in (p for p in planners if not ompl_spec(p)):
        for ref in ompl:
            for s in sets:
                a, b = cell[(ours, s)], cell[(ref, s)]
                ref_ok = [i for i, r in b.items() if r["solved"]]
                both = [i for i in ref_ok if a.get(i, {}).get("solved")]
                pairs[f"{ours} vs {ref} / {s}"] = {
                    "ompl_solved": len(ref_ok),
                    "both_solved": len(both),
                    "ours_only": sum(
                        1 for i, r in a.items() if r["solved"] and not b.get(i, {}).get("solved")
                    ),
                    "share_of_ompl_solved": len(both) / len(ref_ok) if ref_ok else None,
                    "median_time_ratio": _median(
                        [a[i]["time_s"] / b[i]["time_s"] for i in both if b[i]["time_s"] > 0]
                    ),
                    "median_length_ratio": _median(
                        [a[i]["length_m"] / b[i]["length_m"] for i in both if b[i]["length_m"]]
                    ),
                    # The wording: our median over OMPL's median, same queries.
                    "time_ratio_of_medians": _ratio(
                        _median([a[i]["time_s"] for i in both]),
                        _median([b[i]["time_s"] for i in both]),
                    ),
                    "length_ratio_of_medians": _ratio(
                        _median([a[i]["length_m"] for i in both]),
                        _median([b[i]["length_m"] for i in both]),
                    ),
                    **_cusp_pair([a[i] for i in both], [b[i] for i in both]),
                }
    return {"per_planner": per, "pairs": pairs}


def _load() -> str:
    """The load averages, as ``uptime`` prints them (``-`` where the OS has none)."""
    try:
        return ", ".join(f"{v:.2f}" for v in os.getloadavg())
    except OSError:
        return "-"


def tight_queries() -> list[tuple[str, str, Pose]]:
    """``(map, label, goal)`` of the tight maps: each map's own query, every free garage bay."""
    from rrtdrive.maps import TIGHT_MAP_NAMES
    from rrtdrive.tight_maps import GARAGE_EMPTY_BAYS, garage_goal

    out = []
    for name in TIGHT_MAP_NAMES:
        if name == "garage":
            out += [(name, f"garage bay {b}", garage_goal(*b)) for b in GARAGE_EMPTY_BAYS]
        else:
            out.append((name, name, builtin_map(name).goal))
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--map", default="parking_lot",
                    help="built-in map name (default: %(default)s)")
    ap.add_argument("--count", type=positive_int, default=100, help="poses per set (default 100)")
    ap.add_argument("--sets", default="goal,start", help="goal, start or both (default)")
    ap.add_argument("--seed", type=int_at_least(0), default=1, help="seed of the pose sets")
    ap.add_argument("--planners", default=DEFAULT_PLANNERS,
                    help="comma-separated: NAME[+reverse][@field=value:...] of a registered "
                    "planner, ompl-dubins-rrt, ompl-rs-rrtconnect (default: %(default)s)")
    ap.add_argument("--max-time", type=positive_float, default=5.0,
                    help="our planners' budget [s] (default: %(default)s)")
    ap.add_argument("--ompl-time", type=positive_float, default=10.0,
                    help="OMPL's time cap [s] (default: %(default)s)")
    ap.add_argument("--jobs", type=positive_int, default=2,
                    help="worker processes (default: %(default)s)")
    ap.add_argument("--out", default="results", type=out_folder,
                    help="directory for coverage_MAP.json and .md, or coverage_tight.* "
                    "(default: %(default)s)")
    ap.add_argument("--doc", default=None, help="also write this markdown page")
    ap.add_argument(
        "--tight", action="store_true",
        help="plan the tight maps' queries instead (garage bays, turning bulb, kerbside, "
        "reverse bay); writes OUT/coverage_tight.*",
    )
    ap.add_argument("--seeds", type=positive_int, default=3,
                    help="with --tight: planner seeds per query (default: %(default)s)")
    args = ap.parse_args(argv)
    check_doc(args.doc, "coverage.py")
    if not args.tight:
        with flags_for({"map": "--map"}):  # before any work, named by its flag
            builtin_map(args.map)
    sets = [s for s in args.sets.split(",") if s]
    if args.count < 1 or not set(sets) <= {"goal", "start"} or not sets:
        ap.error("--count must be >= 1 and --sets a list of goal, start")
    wanted = [p for p in args.planners.split(",") if p]
    skipped = {p: why for p in wanted if (why := availability(p)) is not None}
    # Only an optional comparator that is not installed is skipped; a misspelt name or
    # option is the command's mistake (it was listed as skipped, and the run exited 0).
    wrong = {p: why for p, why in skipped.items() if not why.startswith("OMPL is not installed")}
    if wrong:
        raise InputError("--planners: " + "; ".join(f"{p}: {w}" for p, w in wrong.items()))
    planners = [p for p in wanted if p not in skipped]
    for p, why in skipped.items():
        print(f"skipping {p}: {why}", file=sys.stderr)
    if not planners:  # a typo skipped alone would give empty tables and exit 0
        why = "; ".join(f"{p}: {w}" for p, w in skipped.items())
        raise InputError(f"--planners: none of them can run here ({why})")
    items = []
    if args.tight:
        for index, (name, label, goal) in enumerate(tight_queries()):
            for seed in range(args.seeds):
                for p in planners:
                    items.append({
                        "map": name, "vary": "goal", "index": index, "pose": goal.as_tuple(),
                        "planner": p, "max_time": args.max_time, "ompl_time": args.ompl_time,
                        "query": label, "seed": seed,
                    })  # fmt: skip
        sets = []
    for vary in sets:
        for index, pose in enumerate(draw_goals(args.map, args.count, args.seed, vary)):
            for p in planners:
                items.append({
                    "map": args.map, "vary": vary, "index": index, "pose": pose.as_tuple(),
                    "planner": p, "max_time": args.max_time, "ompl_time": args.ompl_time,
                })  # fmt: skip
    t0 = time.perf_counter()
    load_start = _load()

    def progress(done: int, total: int) -> None:
        print(f"\r{done}/{total} runs, {time.perf_counter() - t0:.0f} s", end="",
              file=sys.stderr, flush=True)

    rows = parallel_map(run_one, items, args.jobs, progress, run_timeout_s=600.0)
    print(file=sys.stderr)
    wall = time.perf_counter() - t0
    command = "python experiments/coverage.py " + " ".join(
        sys.argv[1:] if argv is None else argv
    )
    machine = f"{platform.machine()} {os.cpu_count()} CPUs, Python {platform.python_version()}"
    out = FsPath(args.out)
    out.mkdir(parents=True, exist_ok=True)
    if args.tight:
        cells: dict[tuple[str, str], list[dict[str, Any]]] = {}
        for r in rows:
            cells.setdefault((r["query"], r["planner"]), []).append(r)
        summary = [
            {
                "query": q, "planner": p, "runs": len(rs),
                "solved": sum(r["solved"] for r in rs),
                "verified": sum(r["verified"] for r in rs),
                "verified_any_sharpness": sum(r["verified_any_sharpness"] for r in rs),
                "collision_free": sum(r["collision_free"] for r in rs),
                "statuses": {st: sum(r["status"] == st for r in rs)
                             for st in sorted({r["status"] for r in rs})},
                "diagnoses": sorted({r["diagnosis"] for r in rs if r.get("diagnosis")}),
                **_sharpness([r for r in rs if r["solved"]]),
                "median_time_solved_s": _median([r["time_s"] for r in rs if r["solved"]]),
                "median_length_m": _median([r["length_m"] for r in rs if r["solved"]]),
                "median_cusps": _median(
                    [r["cusps"] for r in rs if r["solved"] and r.get("cusps") is not None]
                ),
            }
            for (q, p), rs in cells.items()
        ]  # fmt: skip
        payload = {
            "command": command.strip(), "seeds": args.seeds, "planners": planners,
            "skipped": skipped, "max_time_s": args.max_time, "ompl_time_s": args.ompl_time,
            "jobs": args.jobs, "machine": machine, "wall_time_s": wall, "summary": summary,
            "rows": rows,
        }  # fmt: skip
        write_text_atomic(out / "coverage_tight.json", json_text(payload))
        text = tight_report(payload)
        write_text_atomic(out / "coverage_tight.md", text)
        if args.doc:
            write_doc(args.doc, text, "coverage.py")
        print(text)
        return 0
    payload = {
        "command": command.strip(),
        "map": args.map,
        "count": args.count,
        "sets": sets,
        "seed": args.seed,
        "planners": planners,
        "skipped": skipped,
        "max_time_s": args.max_time,
        "ompl_time_s": args.ompl_time,
        "jobs": args.jobs,
        "machine": machine,
        "wall_time_s": wall,
        "load": {"start": load_start, "end": _load()},
        "summary": summarise(rows, planners, sets),
        "rows": rows,
    }
    stem = f"coverage_{args.map}"
    write_text_atomic(out / f"{stem}.json", json_text(payload))
    text = report(payload)
    write_text_atomic(out / f"{stem}.md", text)
    if args.doc:
        write_doc(args.doc, text, "coverage.py")
    print(text)
    return 0


if __name__ == "__main__":
    from results_io import run_main

    code = run_main(main)
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)  # no interpreter teardown: nanobind's leak warnings (FACTS.md)
