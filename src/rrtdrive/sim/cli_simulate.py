"""The ``rrtdrive simulate`` subcommand: one closed-loop episode, metrics as JSON, optional MP4.

Wiring in ``rrtdrive.cli``::

    from rrtdrive.sim import cli_simulate
    cli_simulate.add_parser(subparsers)   # sets func=cli_simulate.run

Exit codes: 0 when the episode succeeds, 1 when it fails (planning failure,
collision, goal missed, time out), 2 on bad input (one line on stderr).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from typing import Any

from rrtdrive.cli_args import int_at_least, nonneg_int, positive_float
from rrtdrive.types import InputError

__all__ = ["add_parser", "run", "episode_json"]

EXIT_OK, EXIT_FAILED, EXIT_BAD_INPUT = 0, 1, 2
CONTROLLER_NAMES = ("pure-pursuit", "stanley", "lqr")


def add_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Add ``simulate`` to an argparse subparsers object and return its parser."""
    from rrtdrive.sim.tasks import DEFAULT_PLANNER

    p = subparsers.add_parser(
        "simulate",
        help="plan and drive one closed-loop episode in highway-env",
        description="Plan a path for SCENARIO, track it in highway-env with a controller at "
        "the simulation frequency, and report the evaluators' metrics. Exit 0 when the "
        "episode succeeds, 1 when it fails, 2 on bad input.",
    )
    p.add_argument(
        "scenario", metavar="SCENARIO", help="parking, overtake or overtake-traffic"
    )
    p.add_argument(
        "--planner", default=DEFAULT_PLANNER, metavar="NAME",
        help=f"registered planner (default: {DEFAULT_PLANNER})",
    )
    p.add_argument(
        "--controller", default="pure-pursuit", metavar="NAME",
        help=f"one of {', '.join(CONTROLLER_NAMES)} (default: pure-pursuit)",
    )
    p.add_argument("--seed", type=nonneg_int, default=0, help="episode seed (default 0)")
    p.add_argument(
        "--frequency", type=int_at_least(15, 'Hz'), default=20,
        help="simulation and control frequency in Hz, >= 15 (default 20)",
    )
    p.add_argument(
        "--max-time", type=positive_float, default=None,
        help="time limit of the drive in seconds (default: the scenario's)",
    )
    p.add_argument(
        "--plan-time", type=positive_float, default=5.0,
        help="planning time budget in seconds (default 5)",
    )
    p.add_argument(
        "--oncoming", type=nonneg_int, default=0,
        help="overtake: number of oncoming cars, 0-10 (default 0: only the stopped car)",
    )
    traffic = p.add_argument_group(
        "overtake-traffic",
        "a slow moving lead car and a stream of oncoming cars; the ego re-plans in the loop",
    )
    traffic.add_argument(
        "--density", default=None, metavar="D",
        help="oncoming cars per km, or low / default / high (default: default, 10 per km)",
    )
    traffic.add_argument(
        "--lead-speed", type=positive_float, default=None, metavar="V",
        help="lead car speed in m/s (default 4)",
    )
    traffic.add_argument(
        "--lead-model", default=None, metavar="NAME",
        help="lead car driver: idm (default) or constant",
    )
    traffic.add_argument(
        "--replan-rate", type=positive_float, default=None, metavar="HZ",
        help="re-planning rate, 2-5 Hz (default 4); the cycle budget is one period",
    )
    traffic.add_argument(
        "--predictor", default=None, metavar="NAME",
        help="constant-velocity (default) or lane-following (highway-env's)",
    )
    p.add_argument("--json", metavar="FILE|-", help="write the metrics as JSON ('-' for stdout)")
    p.add_argument("--video", metavar="FILE.mp4", help="write a headless MP4 of the episode")
    p.add_argument(
        "--video-stride", type=nonneg_int, default=1,
        help="simulation steps per video frame (default 1: every step)",
    )
    p.set_defaults(func=run)
    return p


def episode_json(report: Any, extra: dict[str, Any] | None = None) -> dict[str, Any]:
    """The JSON contract of ``rrtdrive simulate``: every metric of the report plus ``extra``."""
    out = report.to_json()
    if extra:
        out.update(extra)
    return out


def run(args: argparse.Namespace) -> int:
    """Run the ``simulate`` subcommand; return the exit code.

    Bad input is reported as one line on stderr with exit code 2.
    """
    try:
        return _run(args)
    except InputError as exc:
        print(f"rrtdrive simulate: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT


def failure_reason(report: Any, config: Any = None) -> str:
    """Why an episode that was not a success failed: its status and each unmet condition.

    Parameters
    ----------
    report : EpisodeReport
        From :func:`rrtdrive.evaluation.evaluate`.
    config : EvalConfig, optional
        The thresholds the report was evaluated with (default the defaults).

    Examples
    --------
    >>> from types import SimpleNamespace as R
    >>> failure_reason(R(status="arrived", collision=False, goal_position_err_m=0.1,
    ...                  goal_heading_err_rad=0.21, stopped=True, passed_lead=None,
    ...                  back_in_lane=None, reached_goal=False))
    'arrived but heading error 12.0 deg > 10 deg'
    """
    from rrtdrive.evaluation import EvalConfig

    cfg = config or EvalConfig()
    why = []
    if report.collision:
        why.append("a collision")
    pos, head = report.goal_position_err_m, report.goal_heading_err_rad
    if pos is not None and pos > cfg.goal_tol_m:
        why.append(f"position error {pos:.2f} m > {cfg.goal_tol_m:g} m")
    if head is not None and head > cfg.goal_tol_rad:
        why.append(
            f"heading error {math.degrees(head):.1f} deg > {math.degrees(cfg.goal_tol_rad):g} deg"
        )
    if pos is None and not report.reached_goal and report.status == "completed":
        why.append("the overtake is not complete")
    if not report.stopped:
        why.append(f"not stopped (above {cfg.stop_speed:g} m/s)")
    if report.passed_lead is False:
        why.append("the lead car not passed")
    if report.back_in_lane is False:
        why.append("not back in the lane")
    status = str(report.status)
    if not why:
        return status
    # "arrived but ...": the drive ended as it should, a success condition did not hold.
    joiner = " but " if status in ("arrived", "completed") else ": "
    return status + joiner + ", ".join(why)


def _validate_output(target: str | None, suffix: str, flag: str) -> None:
    from pathlib import Path

    if target is None or target == "-":
        return
    out = Path(target)
    if suffix and out.suffix.lower() != suffix:
        raise InputError(f"{flag}: the file must end in {suffix}, got {target!r}")
    parent = out.parent if str(out.parent) else Path(".")
    if not parent.is_dir():
        raise InputError(f"{flag}: folder {str(parent)!r} does not exist")
    if out.is_dir():
        raise InputError(f"{flag}: {target!r} is a folder")


def _run(args: argparse.Namespace) -> int:
    from rrtdrive.evaluation import evaluate
    from rrtdrive.planning import PLANNERS
    from rrtdrive.sim.runner import EpisodeConfig, run_episode
    from rrtdrive.sim.scenes import SimConfig
    from rrtdrive.sim.tasks import SCENARIOS, make_scenario
    from rrtdrive.types import Budget

    if args.scenario not in SCENARIOS:
        raise InputError(
            f"scenario: unknown scenario {args.scenario!r}; choose from {', '.join(SCENARIOS)}"
        )
    if args.controller not in CONTROLLER_NAMES:
        raise InputError(
            f"--controller: unknown controller {args.controller!r}; "
            f"choose from {', '.join(CONTROLLER_NAMES)}"
        )
    if args.planner not in PLANNERS:
        raise InputError(
            f"--planner: unknown planner {args.planner!r}; "
            f"choose from {', '.join(sorted(PLANNERS))}"
        )
    if args.video is not None and args.video == "-":
        raise InputError("--video: needs a file name ending in .mp4")
    _validate_output(args.video, ".mp4", "--video")
    _validate_output(args.json, "", "--json")
    stride = getattr(args, "video_stride", 1) or 1
    traffic_opts = {
        "density": getattr(args, "density", None),
        "lead_speed": getattr(args, "lead_speed", None),
        "lead_model": getattr(args, "lead_model", None),
    }
    replan_opts = {
        k: v
        for k, v in (
            ("rate_hz", getattr(args, "replan_rate", None)),
            ("predictor", getattr(args, "predictor", None)),
        )
        if v is not None
    }
    replan = None
    if args.scenario == "overtake-traffic":
        from rrtdrive.sim.replanning import ReplanConfig

        replan = ReplanConfig(**replan_opts)
    elif replan_opts:
        flag = "--replan-rate" if "rate_hz" in replan_opts else "--predictor"
        raise InputError(f"{flag}: only the overtake-traffic scenario re-plans")
    config = EpisodeConfig(
        sim=SimConfig(simulation_frequency=args.frequency),
        budget=Budget(max_time_s=args.plan_time),
        max_time_s=args.max_time,
        replan=replan,
    )
    t0 = time.perf_counter()
    oncoming = getattr(args, "oncoming", 0) or 0
    scenario = make_scenario(args.scenario, args.seed, oncoming=oncoming, **traffic_opts)
    episode = run_episode(scenario, args.planner, args.controller, args.seed, config)
    report = evaluate(episode)
    total = time.perf_counter() - t0
    extra: dict[str, Any] = {"total_time_s": round(total, 6), "oncoming": oncoming}
    extra.update(scenario.describe())
    if args.video:
        if episode.log.steps == 0:
            extra["video"] = None
            print(
                f"rrtdrive simulate: no video: {episode.message}", file=sys.stderr
            )
        else:
            from rrtdrive.sim.video import write_video

            frames = write_video(episode, args.video, stride=stride)
            extra["video"] = args.video
            extra["video_frames"] = frames
    data = episode_json(report, extra)
    text = json.dumps(data, indent=2) + "\n"
    if args.json == "-":
        sys.stdout.write(text)
        sys.stdout.flush()
    elif args.json:
        from rrtdrive.maps import write_text_atomic

        try:
            write_text_atomic(args.json, text)
        except OSError as exc:
            raise InputError(f"--json: cannot write {args.json}: {exc.strerror}") from None
    if args.json != "-":
        verdict = "success" if report.success else f"{report.outcome} ({failure_reason(report)})"
        cte = "n/a" if report.cte_rms_m is None else f"{report.cte_rms_m:.3f} m"
        print(
            f"{args.scenario} seed {args.seed} {episode.planner}/{args.controller}: {verdict}; "
            f"cte rms {cte}; {report.steps} steps, {report.duration_s:.2f} s simulated",
            file=sys.stdout,
        )
    return EXIT_OK if report.success else EXIT_FAILED
