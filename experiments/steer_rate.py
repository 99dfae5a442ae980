"""Closed loop with a rate-limited steering actuator: the drivability targets of issue 12.

Usage::

    python experiments/steer_rate.py --steer-rate 0.4 --seeds 50 --jobs 2 --out results
    python experiments/steer_rate.py --steer-rate 0.4 --scenarios overtake-traffic --seeds 50
    python experiments/steer_rate.py --planner rrt-connect --steer-rate none --seeds 10

With ``--planner`` (default: the default planner), for every scenario (``parking``,
``overtake``, ``overtake-traffic`` at ``--density``),
controller and seed 0..seeds-1: plan, drive in highway-env with the ego's steering
limited to ``--steer-rate`` rad/s (``VehicleParams.max_steer_rate``; ``none`` for
instant steering), evaluate. Reports per scenario x controller: success, collisions
by both judges (highway-env's ``crashed`` / the exact footprint check), CTE RMS and
max, the executed steering rate (max, and the largest share of steps over the
evaluators' 0.4 rad/s), the share of episodes nuPlan finds comfortable (and the
worst of each of its six figures), and the planned path's largest sharpness
``|d delta/ds|``. Writes ``OUT/steer_rate[_TAG].{json,md}`` with the command.
"""

from __future__ import annotations

import argparse
import json
import math
import platform
import sys
import time
from collections import Counter
from pathlib import Path as FsPath

from results_io import out_folder  # the sibling module

from rrtdrive.atomic import write_text_atomic
from rrtdrive.bench.backends import episode_progress, parallel_map
from rrtdrive.cli_args import flags_for, int_at_least, positive_float, positive_int
from rrtdrive.controllers import make_controller
from rrtdrive.evaluation import evaluate
from rrtdrive.evaluation.nuplan_comfort import COMFORT_BOUNDS
from rrtdrive.planning import make_planner
from rrtdrive.sim.limits import MAX_SIM_FREQUENCY, MIN_SIM_FREQUENCY
from rrtdrive.sim.replanning import ReplanConfig
from rrtdrive.sim.runner import EpisodeConfig, run_episode
from rrtdrive.sim.scenes import SimConfig
from rrtdrive.sim.tasks import DEFAULT_PLANNER, make_scenario
from rrtdrive.types import Budget, VehicleParams

SCENARIOS = ("parking", "overtake", "overtake-traffic")
CONTROLLERS = ("pure-pursuit", "stanley", "lqr")
#: The issue's targets (issue 12).
TARGETS = {"success": 0.99, "cte_rms_m": 0.10, "cte_max_m": 0.30}


#: A planning time cap no query reaches (``--no-wall-limit``): iteration budgets decide.
NO_WALL_LIMIT_S = 1e6


def episode_config(hz: int, no_wall: bool) -> EpisodeConfig:
    """The episode settings: with ``no_wall`` no wall-clock cap can decide an outcome.

    Planning (the reference plan and every re-planning cycle) is then bounded by its
    iteration budgets alone: the planning budget's safety cap is
    :data:`NO_WALL_LIMIT_S` and the re-planner runs without its cycle deadline
    (``ReplanConfig(wall_limit=False)``). Otherwise the defaults: a 30 s planning cap
    and the re-planner's wall-time cycle budget.
    """
    sim = SimConfig(simulation_frequency=hz)
    if no_wall:
        return EpisodeConfig(
            sim=sim, budget=Budget(max_time_s=NO_WALL_LIMIT_S),
            replan=ReplanConfig(wall_limit=False),
        )
    return EpisodeConfig(sim=sim)


def wall_capped(message: str) -> bool:
    """A planner message saying the wall clock (a safety cap or a deadline) stopped it."""
    return "safety cap" in message or "deadline passed" in message


def run_one(job: tuple[str, str, int, float | None, str, int, bool, str]) -> dict:
    scenario, controller, seed, rate, density, hz, no_wall, planner = job
    options = {"density": density} if scenario == "overtake-traffic" else {}
    task = make_scenario(scenario, seed, vehicle=VehicleParams(max_steer_rate=rate), **options)
    ep = run_episode(task, planner, controller=controller, seed=seed,
                     config=episode_config(hz, no_wall))
    out = evaluate(ep).to_json()
    out["scenario"] = scenario
    plan = ep.plan
    out["plan_wall_capped"] = bool(plan is not None and wall_capped(plan.message))
    if ep.traffic is not None:
        records = ep.traffic.records
        out["cycle_outcomes"] = dict(Counter(r.outcome for r in records))
        out["planner_runs"] = sum(r.planning_time_s > 0 for r in records)
        out["wall_capped_cycles"] = sum(wall_capped(r.message) for r in records)
        out["horizon_rejections"] = sum("horizon" in r.message for r in records)
    return out


def _max(rows: list[dict], key: str) -> float | None:
    vals = [r[key] for r in rows if r.get(key) is not None]
    return max(vals) if vals else None


def _min(rows: list[dict], key: str) -> float | None:
    vals = [r[key] for r in rows if r.get(key) is not None]
    return min(vals) if vals else None


def summarise(rows: list[dict]) -> dict:
    """The figures of one scenario x controller group."""
    n = len(rows)
    drove = [r for r in rows if r.get("steps", 1) > 0]
    rms = [r["cte_rms_m"] for r in rows if r.get("cte_rms_m") is not None]
    return {
        "episodes": n,
        "success": sum(bool(r["success"]) for r in rows),
        "collisions_highway_env": sum(bool(r["collision_highway_env"]) for r in rows),
        "collisions_footprint": sum(bool(r["collision_footprint"]) for r in rows),
        "cte_rms_m_mean": sum(rms) / len(rms) if rms else None,
        "cte_rms_m_max": max(rms) if rms else None,
        "cte_max_m_max": _max(rows, "cte_max_m"),
        "steering_rate_max": _max(rows, "max_steering_rate"),
        "steering_rate_over_limit_share_max": _max(rows, "steering_rate_over_limit_share"),
        "nuplan_comfortable": sum(bool(r.get("nuplan_comfortable")) for r in rows),
        "nuplan_lon_accel_min": _min(rows, "nuplan_lon_accel_min"),
        "nuplan_lon_accel_max": _max(rows, "nuplan_lon_accel_max"),
        "nuplan_lat_accel_abs_max": _max(rows, "nuplan_lat_accel_abs_max"),
        "nuplan_lon_jerk_abs_max": _max(rows, "nuplan_lon_jerk_abs_max"),
        "nuplan_jerk_abs_max": _max(rows, "nuplan_jerk_abs_max"),
        "nuplan_yaw_rate_abs_max": _max(rows, "nuplan_yaw_rate_abs_max"),
        "nuplan_yaw_accel_abs_max": _max(rows, "nuplan_yaw_accel_abs_max"),
        "path_max_sharpness_max": _max(rows, "path_max_sharpness"),
        # Over the episodes that drove (a failed plan's 0 s is no drive).
        "duration_s_mean": (
            sum(r["duration_s"] for r in drove) / len(drove) if drove else None
        ),
        "plans_wall_capped": sum(bool(r.get("plan_wall_capped")) for r in rows),
        "planner_runs": sum(r.get("planner_runs", 0) for r in rows),
        "wall_capped_cycles": sum(r.get("wall_capped_cycles", 0) for r in rows),
        "horizon_rejections": sum(r.get("horizon_rejections", 0) for r in rows),
    }


def _f(v: float | None, digits: int = 3) -> str:
    return "n/a" if v is None else f"{v:.{digits}f}"


def table(summaries: dict[str, dict]) -> str:
    """The markdown table of :func:`summarise` per ``scenario/controller``."""
    head = (
        "| scenario | controller | success | collisions (highway-env / footprint) | "
        "CTE RMS mean / max [m] | CTE max [m] | steering rate max [rad/s] | "
        "share of steps over 0.4 rad/s (max) | nuPlan comfortable | "
        "nuPlan lon accel min / max, lat, lon jerk, jerk, yaw rate, yaw accel (worst) | "
        "path sharpness max [rad/m] | time mean [s] |\n"
        "|---|---|---|---|---|---|---|---|---|---|---|---|\n"
    )
    rows = []
    for key, s in summaries.items():
        scen, ctrl = key.split("/")
        n = s["episodes"]
        nup = (
            f"{_f(s['nuplan_lon_accel_min'], 2)} / {_f(s['nuplan_lon_accel_max'], 2)}, "
            f"{_f(s['nuplan_lat_accel_abs_max'], 2)}, {_f(s['nuplan_lon_jerk_abs_max'], 2)}, "
            f"{_f(s['nuplan_jerk_abs_max'], 2)}, {_f(s['nuplan_yaw_rate_abs_max'], 2)}, "
            f"{_f(s['nuplan_yaw_accel_abs_max'], 2)}"
        )
        rows.append(
            f"| {scen} | {ctrl} | {s['success']}/{n} | "
            f"{s['collisions_highway_env']} / {s['collisions_footprint']} | "
            f"{_f(s['cte_rms_m_mean'])} / {_f(s['cte_rms_m_max'])} | {_f(s['cte_max_m_max'])} | "
            f"{_f(s['steering_rate_max'])} | {_f(s['steering_rate_over_limit_share_max'])} | "
            f"{s['nuplan_comfortable']}/{n} | {nup} | {_f(s['path_max_sharpness_max'])} | "
            f"{_f(s['duration_s_mean'], 1)} |"
        )
    b = COMFORT_BOUNDS
    foot = (
        f"\nnuPlan bounds: lon accel [{b['min_lon_accel']}, {b['max_lon_accel']}] m/s², "
        f"|lat accel| <= {b['max_abs_lat_accel']}, |lon jerk| <= {b['max_abs_lon_jerk']}, "
        f"|jerk| <= {b['max_abs_jerk']} m/s³, |yaw rate| <= {b['max_abs_yaw_rate']} rad/s, "
        f"|yaw accel| <= {b['max_abs_yaw_accel']} rad/s².\n"
    )
    return head + "\n".join(rows) + "\n" + foot


def misses(summaries: dict[str, dict], rate: float | None) -> list[str]:
    """The issue's targets each group misses, in words."""
    out = []
    for key, s in summaries.items():
        n = s["episodes"]
        why = []
        if s["success"] < math.ceil(TARGETS["success"] * n):
            why.append(f"success {s['success']}/{n}")
        if s["collisions_highway_env"] or s["collisions_footprint"]:
            why.append(
                f"collisions {s['collisions_highway_env']} / {s['collisions_footprint']}"
            )
        if not key.startswith("overtake-traffic"):
            if (s["cte_rms_m_max"] or 0.0) > TARGETS["cte_rms_m"]:
                why.append(f"CTE RMS max {s['cte_rms_m_max']:.3f} m")
            if (s["cte_max_m_max"] or 0.0) > TARGETS["cte_max_m"]:
                why.append(f"CTE max {s['cte_max_m_max']:.3f} m")
        if rate is not None and (s["steering_rate_max"] or 0.0) > rate + 1e-9:
            why.append(f"steering rate {s['steering_rate_max']:.3f} rad/s")
        if s["nuplan_comfortable"] < n:
            why.append(f"nuPlan comfortable {s['nuplan_comfortable']}/{n}")
        if why:
            out.append(f"- {key}: " + ", ".join(why))
    return out


def rate_or_none(text: str) -> float | None:
    """An argparse type for ``--steer-rate``: rad/s > 0, or ``none`` (instant steering)."""
    if text.lower() == "none":
        return None
    try:
        return positive_float(text)
    except argparse.ArgumentTypeError as exc:
        raise argparse.ArgumentTypeError(f"{exc} (or 'none' for instant steering)") from None


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--steer-rate", type=rate_or_none, default="0.4",
                    help="the ego's steering rate limit in rad/s, or 'none' (instant)"
                         " (default: %(default)s)")
    ap.add_argument("--seeds", type=positive_int, default=50,
                    help="seeds 0..N-1 per scenario and controller (default: %(default)s)")
    ap.add_argument("--scenarios", default="parking,overtake",
                    help="comma-separated: parking, overtake, overtake-traffic\n"
                    "(default: %(default)s)")
    ap.add_argument("--controllers", default=",".join(CONTROLLERS),
                    help="comma-separated controllers (default: %(default)s)")
    ap.add_argument("--density", default=None,
                    help="overtake-traffic's traffic density (default: default), only with "
                    "overtake-traffic among --scenarios")
    ap.add_argument("--planner", default=DEFAULT_PLANNER,
                    help="the reference path's planner (default: %(default)s; rrt-connect: the\n"
                    "baseline's raw paths, which jump in curvature)")
    ap.add_argument("--frequency", default=20,
                    type=int_at_least(MIN_SIM_FREQUENCY, "Hz", MAX_SIM_FREQUENCY),
                    help="control and simulation frequency [Hz] (default: %(default)s)")
    ap.add_argument("--jobs", type=positive_int, default=2,
                    help="worker processes (default: %(default)s)")
    ap.add_argument("--out", default="results", type=out_folder,
                    help="directory for steer_rate[_TAG].json and .md (default: %(default)s)")
    ap.add_argument("--tag", default="",
                    help="output name suffix: steer_rate_TAG.json and .md (default: none)")
    ap.add_argument(
        "--no-wall-limit", action="store_true",
        help="no wall-clock cap on planning and re-planning (iteration budgets decide: "
        "outcomes do not depend on the machine's load)",
    )
    args = ap.parse_args(argv)
    rate = args.steer_rate
    scenarios = args.scenarios.split(",")
    controllers = args.controllers.split(",")
    if args.density is not None and "overtake-traffic" not in scenarios:
        # It was ignored without a word (an audit).
        ap.error("--density: only overtake-traffic takes it; --scenarios has none")
    if args.density is None:
        args.density = "default"
    # Every name before any episode, each error naming its flag (not "scenario:").
    with flags_for({"scenario": "--scenarios", "controller": "--controllers",
                    "planner": "--planner", "density": "--density"}):  # fmt: skip
        for s in scenarios:
            options = {"density": args.density} if s == "overtake-traffic" else {}
            make_scenario(s, 0, **options)
        for c in controllers:
            make_controller(c)
        make_planner(args.planner)
    jobs = [
        (s, c, seed, rate, args.density, args.frequency, args.no_wall_limit, args.planner)
        for s in scenarios for c in controllers for seed in range(args.seeds)
    ]
    t0 = time.perf_counter()
    progress = episode_progress()
    reports = parallel_map(run_one, jobs, args.jobs, progress)
    print(file=sys.stderr)
    summaries = {
        f"{s}/{c}": summarise([r for r in reports if r["scenario"] == s and r["controller"] == c])
        for s in scenarios for c in controllers
    }
    failures = [
        {k: r[k] for k in ("scenario", "controller", "seed", "status", "message")}
        for r in reports if not r["success"]
    ]
    command = " ".join(["python", *sys.argv])
    settings = {
        "command": command, "steer_rate": rate, "seeds": args.seeds, "scenarios": scenarios,
        "controllers": controllers, "planner": args.planner, "density": args.density,
        "frequency": args.frequency,
        "no_wall_limit": args.no_wall_limit,
        "python": platform.python_version(), "wall_time_s": round(time.perf_counter() - t0, 1),
    }
    missed = misses(summaries, rate)
    md = (
        "## Closed loop with a rate-limited steering actuator\n\n"
        f"Command: `{command}`; ego steering "
        + ("instant" if rate is None else f"limited to {rate} rad/s")
        + f", planner {args.planner}, {args.seeds} seeds, control and simulation at "
        f"{args.frequency} Hz"
        + (", no wall-clock planning limits" if args.no_wall_limit else "")
        + ".\n\n"
        + table(summaries)
        + "\nPlanning stopped by the wall clock (a safety cap or the re-planner's cycle "
        "deadline), per group: "
        + "; ".join(
            f"{k}: reference plans {s['plans_wall_capped']}/{s['episodes']}"
            + (
                f", re-planning cycles {s['wall_capped_cycles']} of {s['planner_runs']} "
                f"planner runs (plans rejected as ending beyond the prediction horizon: "
                f"{s['horizon_rejections']})"
                if k.startswith("overtake-traffic") else ""
            )
            for k, s in summaries.items()
        )
        + ".\n"
        + "\nTargets missed (issue 12):\n\n"
        + ("\n".join(missed) if missed else "- none")
        + "\n"
    )
    if failures:
        md += "\nFailed episodes:\n\n" + "".join(
            f"- {f['scenario']} / {f['controller']} / seed {f['seed']}: {f['status']}: "
            f"{f['message']}\n" for f in failures
        )
    out = FsPath(args.out)
    out.mkdir(parents=True, exist_ok=True)
    tag = f"_{args.tag}" if args.tag else ""
    write_text_atomic(out / f"steer_rate{tag}.md", md)
    write_text_atomic(
        out / f"steer_rate{tag}.json",
        json.dumps({"settings": settings, "summaries": summaries, "failures": failures,
                    "reports": reports}, indent=1, allow_nan=False) + "\n",
    )
    print(md)
    return 0


if __name__ == "__main__":
    from results_io import run_main

    raise SystemExit(run_main(main))
