"""The ``rrtdrive simulate`` subcommand: one closed-loop episode, metrics as JSON, optional MP4.

``SCENARIO`` is a built-in scenario (parking, overtake, overtake-traffic,
parallel-parking, u-turn), a stock highway-env env (parking-v0,
parking-parked-v0: driven through its own ``env.step``, JSON adds
``highway_env_success``), or a map (a ``.json`` file or a built-in map name that is
not a scenario name: its rectangles become highway-env obstacles).

Wiring in ``rrtdrive.cli``::

    from rrtdrive.sim import cli_simulate
    cli_simulate.add_parser(subparsers)   # sets func=cli_simulate.run

Exit codes: 0 when the episode succeeds, 1 when it fails (planning failure,
collision, goal missed, time out), 2 on bad input (one line on stderr).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import sys
import time
from typing import Any

from rrtdrive.cli_args import (
    PLOT_SUFFIXES,
    cell_size,
    distinct_outputs,
    flags_for,
    int_at_least,
    nonneg_int,
    parse_planner_options,
    planner_option_flags,
    positive_float,
    positive_int,
    raise_unwritten,
    register_ompl_if_named,
    validate_output,
    write_each,
    writing,
)
from rrtdrive.json_safe import options_json
from rrtdrive.sim.cli_media import write_media
from rrtdrive.sim.cli_targets import given_path, make_task, target_kind, with_simulate_hint
from rrtdrive.sim.limits import MAX_SIM_FREQUENCY, MAX_VIDEO_FPS, MIN_SIM_FREQUENCY
from rrtdrive.types import Budget, InputError
from rrtdrive.values import did_you_mean
from rrtdrive.vehicle_json import vehicle_to_json

__all__ = ["add_parser", "run", "episode_json", "metrics_block", "HELP", "NO_WALL_LIMIT_S"]

EXIT_OK, EXIT_FAILED, EXIT_BAD_INPUT = 0, 1, 2
CONTROLLER_NAMES = ("pure-pursuit", "stanley", "lqr")
HELP = "plan and drive one closed-loop episode in highway-env"
#: ``--deterministic``'s planning time budget: never reached, the iteration budget binds.
NO_WALL_LIMIT_S = 1e6
#: The plan's wall-clock safety cap, ``rrtdrive plan``'s: 5 s cut off plans the iterations
#: would finish (the forward-only proof for a random lot start takes 1.5 s on one machine,
#: so about 5 s on a 3-4x slower one), and the episode then hung on the machine's speed.
DEFAULT_PLAN_TIME_S = Budget().max_time_s


def add_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Add ``simulate`` to an argparse subparsers object and return its parser.

    Imports nothing of the simulator: ``rrtdrive simulate --help`` stays fast.
    """
    p = subparsers.add_parser(
        "simulate",
        help=HELP,
        description="Plan a path for SCENARIO, track it in highway-env with a controller at "
        "the simulation frequency, and report the evaluators' metrics. Exit 0 when the "
        "episode succeeds, 1 when it fails, 2 on bad input; 130 on Ctrl-C, 143 on SIGTERM.",
    )
    p.add_argument(
        "scenario", metavar="SCENARIO",
        help="parking, overtake, overtake-traffic, parallel-parking or u-turn (and "
        "parking-reverse-in: parking --reverse-in); a stock "
        "highway-env env (parking-v0, parking-parked-v0); or a map: a .json file or a "
        "built-in map name (garage, kerbside, ...)",
    )
    p.add_argument(
        "--reverse", action="store_true",
        help="plan with gear changes (as 'rrtdrive plan --reverse'); parallel-parking, "
        "u-turn and parking --reverse-in always do",
    )
    p.add_argument(
        "--reverse-in", action="store_true",
        help="parking: the goal faces out of the spot, which is entered backwards",
    )
    p.add_argument("--start", metavar="X,Y,YAW", help="a map: rear-axle start (yaw in radians)")
    p.add_argument("--goal", metavar="X,Y,YAW", help="a map: rear-axle goal (yaw in radians)")
    p.add_argument(
        "--planner", default=None, metavar="NAME",
        help="registered planner (default: the runner's DEFAULT_PLANNER, "
        "improved-rrt-connect)",
    )
    p.add_argument(
        "--planner-option", action="append", dest="planner_options", metavar="FIELD=VALUE",
        help="set a field of the planner's config (repeatable), as 'rrtdrive plan "
        "--planner-option'; not for overtake-traffic, which re-plans with its own",
    )
    p.add_argument(
        "--path", default=None, metavar="PLAN.json",
        help="a map: drive this plan's path as it is instead of planning one (the JSON of "
        "'rrtdrive plan --json', or any {\"path\": ROWS} with ROWS [[x, y, yaw, kappa(, "
        "gear)], ...] or [[x, y, yaw], ...], whose gears and kappa are then read off the "
        "motion); the drive starts at its first row and ends at its last",
    )
    p.add_argument(
        "--controller", default="pure-pursuit", metavar="NAME",
        help=f"one of {', '.join(CONTROLLER_NAMES)} (default: pure-pursuit)",
    )
    p.add_argument("--seed", type=nonneg_int, default=0, metavar="N",
                   help="episode seed (default 0)")
    p.add_argument(
        "--frequency", type=int_at_least(MIN_SIM_FREQUENCY, "Hz", MAX_SIM_FREQUENCY),
        default=20, metavar="HZ",
        help=f"simulation and control frequency in Hz, {MIN_SIM_FREQUENCY} to "
        f"{MAX_SIM_FREQUENCY} (default 20)",
    )
    p.add_argument(
        "--max-time", type=positive_float, default=None, metavar="S",
        help="time limit of the drive in seconds, up to 1e6 (default: the scenario's)",
    )
    p.add_argument(
        "--resolution", type=cell_size, default=None, metavar="M",
        help="a map: the planner's collision grid cell size in metres, up to 100 (default "
        "0.1, coarser up to 0.5 m on a big map; a bigger one needs it given)",
    )
    p.add_argument(
        "--plan-time", type=positive_float, default=None, metavar="S",
        help=f"planning wall-clock safety cap in seconds (default {DEFAULT_PLAN_TIME_S:g}); "
        "a plan that reaches it fails as 'timeout' (the iterations decide otherwise)",
    )
    p.add_argument(
        "--max-iterations", type=positive_int, default=None, metavar="N",
        help="planning iteration budget, as 'rrtdrive plan --max-iterations': with the seed "
        "it decides the plan (default 20000)",
    )
    p.add_argument(
        "--deterministic", action="store_true",
        help="wall-clock limits off: planning stops on its iteration budget only and "
        "overtake-traffic's re-planning cycles are not cut at their time budget, so an "
        "episode depends on its seed alone, not on the machine's speed",
    )
    p.add_argument(
        "--oncoming", type=nonneg_int, default=0, metavar="N",
        help="overtake: number of oncoming cars, 0-10 (default 0: only the stopped car)",
    )
    traffic = p.add_argument_group(
        "overtake-traffic",
        "a slow moving lead car and a stream of oncoming cars; the ego re-plans in the loop",
    )
    traffic.add_argument(
        "--density", default=None, metavar="D",
        help="oncoming cars per km, up to 30, or low / default / high (5, 10, 20; "
        "default: default)",
    )
    traffic.add_argument(
        "--lead-speed", type=positive_float, default=None, metavar="V",
        help="lead car speed in m/s, below 9 (the ego's cap is 11; default 4); the lead "
        "reaches the end of the 1.5 km road sooner the faster it is, which caps --max-time",
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
        "--plot", metavar="FILE.png",
        help="draw the map, the planned path, the driven trajectory and the other cars, "
        "with the speed, steering angle and rate against the car's limits and the "
        "cross-track error over time, to a figure (.png, .pdf or .svg)",
    )
    p.add_argument(
        "--trajectory", metavar="FILE.csv",
        help="write the executed trajectory, one row per logged state (the start and each "
        "simulation step): "
        "t,x,y,yaw,speed,steer,accel,gear (rear axle, applied steering and acceleration)",
    )
    p.add_argument(
        "--video-fps", type=positive_float, default=None, metavar="FPS",
        help="the video's frame rate, with --video (default: real time, the simulation's "
        "frequency over the stride; less plays slower)",
    )
    p.add_argument(
        "--video-stride", type=positive_int, default=None, metavar="N",
        help="simulation steps per video frame, with --video (default: every step up to "
        f"{MAX_VIDEO_FPS} Hz, above it the fewest that keep the video within {MAX_VIDEO_FPS} "
        "fps)",
    )
    p.set_defaults(func=run)
    return p


def _drive_stock(args: argparse.Namespace, config: Any, stride: int) -> tuple[Any, int]:
    """Drive a stock env; at ``--video-stride 1`` its frames stream into the video.

    Every state is then a frame, so the real-time fps is the simulation frequency,
    known before the drive; at another stride it depends on where the drive ends,
    and the frames are kept (1/stride of them) to be written afterwards. Returns the
    drive and the frames written into the video (0: none, or kept in the drive's
    ``frames``).
    """
    from rrtdrive.sim.stock import drive_stock_env

    def drive(render_stride: int, on_frame: Any = None) -> Any:
        with flags_for({"max_time_s": "--max-time"}):
            return drive_stock_env(
                args.scenario, args.seed, args.planner, args.controller, config,
                reverse=args.reverse, render_stride=render_stride, on_frame=on_frame,
            )

    if not args.video or stride != 1:
        return drive(stride if args.video else 0), 0
    from rrtdrive.sim.video import even_frame, open_frames_video

    with writing("--video", args.video):
        fps = getattr(args, "video_fps", None) or float(config.sim.simulation_frequency)
        writer = open_frames_video(args.video, fps)

    def put(frame: Any) -> None:
        with writing("--video", args.video):  # ffmpeg's failure surfaces here
            writer.append(even_frame(frame))

    try:
        stock = drive(1, put)
    except BaseException:
        writer.abort()
        raise
    if writer.frames == 0:  # nothing was driven: no file
        writer.abort()
        return stock, 0
    t0 = time.perf_counter()
    with writing("--video", args.video):
        writer.close()
    # Encoding the last frames is not the episode's time.
    close_s = time.perf_counter() - t0
    return dataclasses.replace(stock, render_time_s=stock.render_time_s + close_s), writer.frames


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


def _fmt(value: Any, spec: str, unit: str = "") -> str:
    return "n/a" if value is None else f"{value:{spec}}{unit}"


def _deg(value: Any) -> str:

    return "n/a" if value is None else f"{math.degrees(value):.2f}°"


def metrics_block(data: dict[str, Any]) -> list[str]:
    """The few metrics a person reads first, as indented lines (from ``episode_json``).

    Every metric is in ``--json``; docs/metrics.md defines them.
    """
    lines = [
        f"  {data.get('message', '')}",
        f"  tracking   cte rms {_fmt(data.get('cte_rms_m'), '.3f', ' m')}, "
        f"max {_fmt(data.get('cte_max_m'), '.3f', ' m')}; heading error rms "
        f"{_deg(data.get('heading_err_rms_rad'))}, max {_deg(data.get('heading_err_max_rad'))}",
        f"  path       {_fmt(data.get('path_length_m'), '.2f', ' m')}, max curvature "
        f"{_fmt(data.get('path_max_curvature'), '.4f')} (bound "
        f"{_fmt(data.get('kappa_max'), '.4f')}), executed "
        f"{_fmt(data.get('executed_max_curvature'), '.4f')} 1/m",
        f"  comfort    max lateral accel {_fmt(data.get('max_lateral_accel'), '.2f', ' m/s²')}, "
        f"max jerk {_fmt(data.get('max_jerk'), '.2f', ' m/s³')}",
    ]
    if data.get("goal_position_err_m") is not None:
        lines.append(
            f"  goal       position error {_fmt(data.get('goal_position_err_m'), '.3f', ' m')}, "
            f"heading error {_deg(data.get('goal_heading_err_rad'))}"
        )
    if data.get("replans") is not None:
        lines.append(
            f"  traffic    min distance {_fmt(data.get('min_distance_m'), '.2f', ' m')}, "
            f"min ttc {_fmt(data.get('ttc_min_s'), '.2f', ' s')}, "
            f"{data.get('replans')} re-plans (median "
            f"{_fmt(data.get('replan_time_median_s'), '.3f', ' s')}), "
            f"{data.get('collisions_vehicles', 0)} collisions with cars"
        )
    planning = data.get("planning_time_s")
    lines.append(
        f"  time       {_fmt(data.get('duration_s'), '.2f', ' s')} simulated in "
        f"{data.get('steps')} steps; "
        + ("" if planning is None else f"planning {planning:.3f} s, ")
        + f"total {_fmt(data.get('total_time_s'), '.2f', ' s')}"
    )
    return lines


def _run(args: argparse.Namespace) -> int:
    from rrtdrive.evaluation import evaluate, failure_reason
    from rrtdrive.planning import PLANNERS, forward_only_note, make_planner, reverses
    from rrtdrive.sim.runner import EpisodeConfig, run_episode
    from rrtdrive.sim.scenes import SimConfig
    from rrtdrive.sim.stock import STOCK_ENVS
    from rrtdrive.sim.tasks import (
        DEFAULT_PLANNER,
        REPLANNING_SCENARIOS,
        SCENARIO_VARIANTS,
        SCENARIOS,
        TASKS,
        make_scenario,
    )

    for name, default in (("reverse", False), ("reverse_in", False), ("start", None),
                          ("goal", None), ("resolution", None)):
        if not hasattr(args, name):  # a Namespace built by a caller without these flags
            setattr(args, name, default)
    if args.scenario in SCENARIO_VARIANTS:  # parking-reverse-in: parking --reverse-in
        args.scenario, options = SCENARIO_VARIANTS[args.scenario]
        for key, value in options.items():
            setattr(args, key, value)
    target = target_kind(args.scenario, SCENARIOS, STOCK_ENVS)
    if target != "map":
        for flag, value in (("--start", args.start), ("--goal", args.goal)):
            if value is not None:
                raise InputError(
                    f"{flag}: only a map takes a start and goal; {args.scenario} draws its own"
                )
        if args.resolution is not None:
            raise InputError(
                f"--resolution: only a map takes a grid size; {args.scenario} sets its own"
            )
    if args.reverse_in and args.scenario != "parking":
        raise InputError("--reverse-in: only the parking scenario has reverse-in bays")
    path, made_on, car = (
        given_path(args, target) if getattr(args, "path", None) is not None
        else (None, None, None)
    )

    if args.controller not in CONTROLLER_NAMES:
        raise InputError(
            f"--controller: unknown controller {args.controller!r}"
            f"{did_you_mean(args.controller, CONTROLLER_NAMES)}; "
            f"choose from {', '.join(CONTROLLER_NAMES)}"
        )
    if args.planner is None:
        args.planner = DEFAULT_PLANNER
    register_ompl_if_named(args.planner, getattr(args, "reverse", False))
    if args.planner not in PLANNERS:
        from rrtdrive.planning import unknown_planner

        raise unknown_planner("--planner", args.planner)
    options = parse_planner_options(getattr(args, "planner_options", None), "--planner-option")
    if options:  # checked once here, named by the flag (an episode plans later)
        if args.scenario in REPLANNING_SCENARIOS:
            raise InputError(f"--planner-option: {args.scenario} re-plans with its own planner")
        with flags_for(planner_option_flags(options, "--planner-option")):
            make_planner(args.planner, **options)
    # Printed once the drive has run, so bad input stays one line (a note, then an error,
    # was two: the checks go on into the task and the drive).
    notes = []
    if getattr(args, "reverse", False) and not reverses(args.planner):
        notes.append(forward_only_note(args.planner))
    if args.max_time is not None and args.max_time < 1.0 / args.frequency:
        # The loop runs whole steps: a shorter limit would still drive one.
        raise InputError(
            f"--max-time: {args.max_time:g} s is shorter than one simulation step "
            f"({1.0 / args.frequency:g} s at {args.frequency} Hz)"
        )
    if args.max_time is not None:
        from rrtdrive.sim.loop import require_episode_time

        require_episode_time("--max-time", args.max_time)  # the episodes' own limit
    if args.video is not None and args.video == "-":
        raise InputError("--video: needs a file name ending in .mp4")
    # Before the episode runs: a bad target should not cost a whole episode.
    validate_output(args.video, "--video", (".mp4",), allow_stdout=False)
    validate_output(args.json, "--json")
    validate_output(args.trajectory, "--trajectory", (".csv",), allow_stdout=False)
    plot = getattr(args, "plot", None)  # a Namespace built by a caller may lack it
    validate_output(plot, "--plot", PLOT_SUFFIXES, allow_stdout=False)
    distinct_outputs(
        {"SCENARIO": args.scenario, "--path": getattr(args, "path", None)},
        video=args.video, json=args.json, trajectory=args.trajectory, plot=plot,
    )
    deterministic = bool(getattr(args, "deterministic", False))
    plan_time = getattr(args, "plan_time", None)
    if deterministic and plan_time is not None:
        raise InputError("--plan-time: --deterministic turns the planning time limit off")
    stride = getattr(args, "video_stride", None)
    if stride is not None and args.video is None:
        raise InputError("--video-stride: only with --video (it sets the video's frames)")
    if getattr(args, "video_fps", None) is not None and args.video is None:
        raise InputError("--video-fps: only with --video (it sets the video's frame rate)")
    if stride is None:
        # Every step up to MAX_VIDEO_FPS Hz; above it every n-th, so the video stays real
        # time at a rate players take (--frequency 1000 made a 1000 fps MP4 that imageio
        # read as 0 fps; an audit).
        stride = max(1, math.ceil(args.frequency / MAX_VIDEO_FPS))
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
    # None: the task plans once (every map and stock env too).
    replan_config = TASKS[args.scenario].REPLAN_CONFIG if target == "scenario" else None
    if replan_config is not None and args.reverse:
        raise InputError(f"--reverse: {args.scenario} re-plans while driving, forward only")
    max_iterations = getattr(args, "max_iterations", None)
    for flag, value in (("--plan-time", plan_time), ("--max-iterations", max_iterations)):
        if replan_config is not None and value is not None:
            raise InputError(
                f"{flag}: {args.scenario} plans nothing ahead; it re-plans while driving, "
                "each cycle within its deadline (set by --replan-rate)"
            )
    if target != "scenario":
        given = [k for k, v in traffic_opts.items() if v is not None]
        if given or getattr(args, "oncoming", None):
            flag = "--" + (given[0] if given else "oncoming").replace("_", "-")
            # As the scenarios word it ("only a built-in scenario" sent a user to parking).
            owner = "overtake-traffic scenario has it"
            if not given:
                owner = "overtake scenario has a count of oncoming cars"
            raise InputError(f"{flag}: only the {owner}, not {args.scenario}")
    if replan_config is not None:
        if deterministic:
            replan_opts["wall_limit"] = False
        # The config names its fields (replan.rate_hz); on the command line, flags.
        with flags_for({"replan.rate_hz": "--replan-rate", "replan.predictor": "--predictor"}):
            replan = replan_config(**replan_opts)
    elif replan_opts:
        flag = "--replan-rate" if "rate_hz" in replan_opts else "--predictor"
        raise InputError(
            f"{flag}: only the {' or '.join(REPLANNING_SCENARIOS)} scenario re-plans"
        )
    config = EpisodeConfig(
        sim=SimConfig(simulation_frequency=args.frequency),
        budget=Budget(
            max_iterations=max_iterations or Budget().max_iterations,
            max_time_s=NO_WALL_LIMIT_S if deterministic else plan_time or DEFAULT_PLAN_TIME_S,
        ),
        max_time_s=args.max_time,
        replan=replan,
        planner_options=options,
    )
    t0 = time.perf_counter()
    oncoming = getattr(args, "oncoming", 0) or 0
    stock, streamed = None, 0
    if target == "stock":
        stock, streamed = _drive_stock(args, config, stride)
        episode = stock.episode
    else:
        scenario = make_task(args, target, oncoming, traffic_opts, make_scenario, path, made_on,
                             car)
        if path is None:
            from rrtdrive.collision import CheckerConfig
            from rrtdrive.collision.grid import setup_notice

            grid = scenario.checker_config or CheckerConfig()
            if (notice := setup_notice(scenario.map.bounds, grid)) is not None:
                # As plan says it: seconds of silence else (a 20 km map at 2.83 m: 13-20 s).
                print(f"rrtdrive simulate: {notice}", file=sys.stderr, flush=True)
        if path is None and scenario.reverse and not args.reverse and not reverses(args.planner):
            # u-turn, parallel-parking, parking --reverse-in plan with gear changes unasked.
            asked = f"the {args.scenario} scenario's gear changes take"
            notes.append(forward_only_note(args.planner, asked=asked))
        with flags_for({"episode.max_time_s": "--max-time", "planner": "--planner"}):
            episode = run_episode(
                scenario, args.planner if path is None else path, args.controller, args.seed,
                config,
            )
    for note in notes:
        print(f"rrtdrive simulate: {note}", file=sys.stderr)
    episode = with_simulate_hint(episode)
    report = evaluate(episode)
    # Drawing a stock env's frames happens during its drive; like writing the video, it
    # is not the episode's time.
    total = time.perf_counter() - t0 - (stock.render_time_s if stock is not None else 0.0)
    diagnosis = None if episode.plan is None else episode.plan.diagnosis
    plans_nothing = path is not None or replan_config is not None
    extra: dict[str, Any] = {
        "total_time_s": round(total, 6),
        "oncoming": oncoming,
        "deterministic": deterministic,
        "target": target,
        "reverse": bool(episode.scenario.reverse),
        "planner_options": options_json(options),  # what the plan was made with ({}: defaults)
        # Per-map set-up (distance field, grids), never planning time (null: no plan ahead).
        "setup_time_s": None if episode.plan is None else round(episode.plan.setup_time_s, 6),
        # The plan's budget, so a failed plan names what cut it short (null: no plan ahead).
        "max_iterations": None if plans_nothing else config.budget.max_iterations,
        "plan_max_time_s": None if plans_nothing or deterministic else config.budget.max_time_s,
        # A failed plan's constraint in the user's terms, as `plan --json` gives it.
        "diagnosis": None if diagnosis is None else diagnosis.to_json(),
        # The plan's own status (a capped plan's `timeout` read only in the message; an
        # audit), as bench's episode rows give it.
        "plan_status": None if episode.plan is None else episode.plan.status.value,
        # The episode's time limit and the plan's grid as used (--max-time, --resolution:
        # two runs differing in either wrote the same settings; an audit).
        "max_time_s": config.max_time_s or episode.scenario.max_time_s,
        "resolution_m": (
            None if episode.plan is None else episode.plan.stats.get("grid_resolution_m")
        ),
        "vehicle": vehicle_to_json(episode.scenario.vehicle),  # the ego's car (session 50)
    }
    extra.update(episode.scenario.describe())
    if replan is not None:  # the re-planning settings asked for, as the traffic's above
        extra["replan_rate_hz"], extra["predictor"] = replan.rate_hz, replan.predictor
    if target != "scenario":
        extra["scenario"] = args.scenario  # the name asked for, not the task kind "custom"
    if path is not None:
        extra["path_file"] = args.path  # the driven path's plan file (planner "given")
    if stock is not None:
        extra.update(stock.to_json())
    # An output that cannot be written fails the run (exit 1) after the others and the
    # summary are out, each failure named: the drive's metrics are not lost with it (a
    # --trajectory failure lost the JSON and the summary; an audit).
    unwritten = write_media(args, episode, stock, streamed, stride, plot, extra)
    data = episode_json(report, extra)
    text = json.dumps(data, indent=2) + "\n"
    from rrtdrive.maps import write_text_atomic
    from rrtdrive.sim.episode import trajectory_csv

    files = write_each([
        ("--trajectory", args.trajectory,
         lambda: write_text_atomic(args.trajectory, trajectory_csv(episode))),
        ("--json", args.json, lambda: write_text_atomic(args.json, text)),
    ])  # fmt: skip
    unwritten += files
    written = args.trajectory not in (None, "", "-") and "--trajectory" not in {
        exc.flag for exc in files
    }
    if written and not report.steps:  # a header-only file (an audit)
        print("rrtdrive simulate: --trajectory: nothing was driven (the plan failed); "
              "the file has its header only", file=sys.stderr)
    if args.json == "-":
        sys.stdout.write(text)
        sys.stdout.flush()
    # With the JSON on stdout, the summary goes to stderr (as `plan` does; README).
    out = sys.stderr if args.json == "-" else sys.stdout
    verdict = "success" if report.success else f"{report.outcome} ({failure_reason(report)})"
    cte = "n/a" if report.cte_rms_m is None else f"{report.cte_rms_m:.3f} m"
    print(
        f"{args.scenario} seed {args.seed} {episode.planner}/{args.controller}: {verdict}; "
        f"cte rms {cte}; {report.steps} steps, {report.duration_s:.2f} s simulated",
        file=out,
    )
    if diagnosis is not None:  # the planner failed: the constraint, as `plan` prints it
        print(f"  why: {diagnosis.message}", file=out)
    if report.success and stock is not None and not stock.highway_env_success:
        # Exit 1 under a "success" line said nothing of why (an audit).
        print(
            "  but highway-env's own is_success is false at the end (its goal test): exit 1",
            file=out,
        )
    print("\n".join(metrics_block(data)), file=out)
    raise_unwritten("simulate", unwritten)
    ok = report.success and (stock is None or stock.highway_env_success)
    return EXIT_OK if ok else EXIT_FAILED
