"""The ``rrtdrive`` command line: ``plan``, ``maps``, ``verify``, ``simulate`` and ``bench``.

Exit codes: 0 success, 1 planning or episode failure (or an output file that could
not be written once the checks passed: a full disk), 2 bad input (one line on stderr,
no traceback).

Start-up is kept short: only the chosen subcommand's parser is built, so
``rrtdrive --help``, ``--version`` and ``maps`` import no planner, simulator,
controller or plotting code, and ``plan`` imports plotting only for ``--plot``.
"""

from __future__ import annotations

import argparse
import importlib
import json
import math
import os
import sys
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, NoReturn

import numpy as np

from rrtdrive.atomic import write_text_atomic
from rrtdrive.cli_args import (
    PLOT_SUFFIXES,
    OutputError,
    cell_size,
    distinct_outputs,
    flags_for,
    join_negative_values,
    map_with_poses,
    names_stdout,
    nonneg_int,
    parse_planner_options,
    parse_pose,
    planner_option_flags,
    positive_float,
    positive_int,
    raise_unwritten,
    register_ompl_if_named,
    validate_output,
    write_each,
    write_output,
)
from rrtdrive.cli_signals import (
    EXIT_TERMINATED,
    interrupt_behind,
    loading_done,
    sigterm_raises,
    sigterm_received,
)
from rrtdrive.cli_stdout import run_writing_stdout
from rrtdrive.cli_warnings import warnings_as_lines
from rrtdrive.json_safe import options_json
from rrtdrive.types import Budget, InputError, PlanResult, Pose, VehicleParams
from rrtdrive.values import did_you_mean

if TYPE_CHECKING:
    pass

__all__ = ["COMMANDS", "build_parser", "main", "plan_to_json", "parse_pose"]

EXIT_OK, EXIT_FAILED, EXIT_BAD_INPUT = 0, 1, 2

#: The planner's fields as ``plan``'s flags, for its messages (``planner.step: ...``).
PLANNER_FLAGS = {
    "planner": "--planner", "planner.step": "--step", "hybrid.step": "--step",
    "planner.disable": "--disable",
}


class _Parser(argparse.ArgumentParser):
    """An argparse parser whose errors are one line on stderr, exit code 2."""

    def error(self, message: str) -> NoReturn:
        if self.prog.endswith(" bench") and message.startswith("unrecognized arguments"):
            # `--scenarios a.json b.json`: bench's lists are one comma-separated value
            # (or the flag repeated); b.json read as a stray argument (an audit).
            message += "; bench's lists are comma-separated (--scenarios a.json,b.json)"
        if message.startswith("unrecognized arguments: --"):
            # `--max-iteratons 5`: the option meant, as for a misspelt name.
            # Compared without the dashes (--out is not close to --plot).
            wrong = message.split()[2].split("=", 1)[0].lstrip("-")
            names = [o[2:] for o in self._option_string_actions if o.startswith("--")]
            if close := did_you_mean(wrong, names):
                message += close.replace("'", "'--", 1)
        self.exit(EXIT_BAD_INPUT, f"{self.prog}: error: {message} (see --help)\n")


def plan_to_json(
    result: PlanResult,
    seed: int,
    map_name: str,
    vehicle: VehicleParams | None = None,
    reverse: bool = False,
    start: Pose | None = None,
    goal: Pose | None = None,
    map_file: str | None = None,
    planner_options: Mapping[str, object] | None = None,
    budget: Budget | None = None,
    resolution: float | None = None,
) -> dict[str, object]:
    """The JSON contract of ``rrtdrive plan`` (SPEC §5, docs/planning.md).

    ``planner_options``: the planner's keyword arguments the plan was made with
    (``--step``, ``--disable``, ``--paper-smoothing``, ``--planner-option``; ``{}``:
    its defaults), so a plan can be made again from its JSON, with the ``budget``
    (``max_iterations``, ``max_time_s``) and the collision grid's cell size
    ``resolution`` (``resolution_m``: the one used, coarser than ``--resolution`` on a
    map too big for it) it was made with; each ``null`` when not given.

    ``start`` and ``goal`` are the query's poses ``[x, y, yaw]`` (``null`` when not
    given), so ``rrtdrive verify`` can check the path against them; ``map_file`` the
    absolute path of the map file the plan was made on (``null`` for a built-in map),
    which ``rrtdrive verify`` reads when it is given no map.
    ``vehicle`` is the car it was planned for (:func:`~rrtdrive.vehicle_json.vehicle_to_json`).
    ``reverse`` is whether gear changes were allowed (``--reverse``); ``path`` rows
    are ``[x, y, yaw, kappa, gear]`` and ``cusps`` counts the gear changes (0 for a
    forward-only path, also when a planner that cannot reverse was allowed to).
    ``max_sharpness`` is the path's largest steering rate per metre ``|d delta/ds|``
    (rad/m, from its rows and the ``vehicle``'s wheelbase, see
    :func:`~rrtdrive.planning.smoothing.max_sharpness`); ``steer_rate_speed_limit``
    the speed (m/s) at which that needs exactly ``vehicle.max_steer_rate`` (null for
    instant steering or a failed plan). ``stage`` names the stage of the planner that
    solved it (``null`` on failure). ``body_clearance_m``: the body clearance the
    path's final check kept at poses <= 0.1 m apart (``null`` on failure and for the
    baselines, which keep none), the default of ``rrtdrive verify --clearance``.
    """
    from rrtdrive.planning.hybrid.escalation import stage_of
    from rrtdrive.planning.smoothing import max_sharpness, steer_rate_speed_limit
    from rrtdrive.vehicle_json import vehicle_to_json

    car = vehicle if vehicle is not None else VehicleParams()
    sharp = max_sharpness(result.path.samples, car.wheelbase) if result.success else None
    limit = steer_rate_speed_limit(sharp, car.max_steer_rate) if sharp is not None else None
    return {
        "success": result.success,
        "status": result.status.value,
        "planner": result.planner,
        # Which stage of the planner solved it (e.g. the default's Hybrid A* escalation).
        "stage": stage_of(result) if result.success else None,
        "map": map_name,
        "map_file": None if map_file is None else os.path.abspath(map_file),
        "seed": int(seed),  # np.int64 from a seed sweep: json cannot write it
        "reverse": bool(reverse),
        # The car it was planned for: verify judges by it (a custom car's path failed
        # the paper car's curvature; an audit).
        "vehicle": vehicle_to_json(car),
        "planner_options": options_json(dict(planner_options or {})),
        # What decided the outcome besides the seed and options: a plan cut short by
        # --max-iterations must not read like the default's.
        "max_iterations": None if budget is None else int(budget.max_iterations),
        # As given, unrounded: the plan is made again from its JSON (a 1e-9 s cap read 0.0,
        # which --max-time refuses; an audit).
        "max_time_s": (
            None if budget is None or not math.isfinite(budget.max_time_s)
            else float(budget.max_time_s)
        ),
        "resolution_m": None if resolution is None else float(resolution),
        "start": None if start is None else [float(v) for v in start.as_tuple()],
        "goal": None if goal is None else [float(v) for v in goal.as_tuple()],
        "path": np.round(result.path.samples, 6).tolist(),
        "cusps": len(result.path.cusps) if result.success else None,
        "waypoints": np.round(result.path.waypoints, 6).tolist(),
        # A failed plan has no path to measure: null, as in bench rows, not 0.0.
        "length_m": round(result.path.length, 6) if result.success else None,
        "max_curvature": round(result.path.max_curvature, 6) if result.success else None,
        "max_sharpness": _json_number(sharp),
        "steer_rate_speed_limit": _json_number(limit),
        # The body clearance the path's final check kept (null: a planner that keeps none).
        "body_clearance_m": _json_number(result.stats.get("body_clearance_m"))
        if result.success else None,
        "nodes": result.nodes,
        "iterations": result.iterations,
        "planning_time_s": result.planning_time_s,
        "setup_time_s": result.setup_time_s,
        # A failure's diagnosis runs after the planning stopwatch (null on success).
        "diagnosis_time_s": result.stats.get("diagnosis_time_s"),
        "message": result.message,
        "diagnosis": None if result.diagnosis is None else result.diagnosis.to_json(),
    }


def _json_number(value: float | None) -> float | None:
    """Rounded for the JSON; None (null) for None and for inf (a path that never steers)."""
    return None if value is None or not math.isfinite(value) else round(value, 6)


def _takes_option(factory: Callable[..., object], name: str) -> bool:
    import inspect

    try:
        return name in inspect.signature(factory).parameters
    except (TypeError, ValueError):  # no signature to read: let the factory decide
        return True


def _cmd_plan(args: argparse.Namespace) -> int:
    from rrtdrive.maps import BUILTIN_MAPS
    from rrtdrive.planning import (
        PLANNERS,
        forward_only_note,
        make_planner,
        reverses,
        solve_on_map,
    )

    validate_output(args.json, "--json")
    validate_output(args.plot, "--plot", PLOT_SUFFIXES, allow_stdout=False)
    distinct_outputs({"MAP": args.map}, json=args.json, plot=args.plot)
    register_ompl_if_named(args.planner, args.reverse)
    if args.disable and args.planner in PLANNERS:
        takes = sorted(n for n in PLANNERS if _takes_option(PLANNERS[n], "disable"))
        if args.planner not in takes:
            raise InputError(
                f"--disable: applies to the improved planner only ({', '.join(takes)}), "
                f"not {args.planner!r}"
            )
    start = parse_pose(args.start, "--start") if args.start is not None else None
    goal = parse_pose(args.goal, "--goal") if args.goal is not None else None
    # The poses given replace the map's before it is checked (a file's own bad start
    # does not stop a good --start).
    m = map_with_poses(args.map, start, goal)
    options: dict[str, object] = {}
    if args.step is not None:
        options["step"] = args.step
    if args.disable:
        options["disable"] = tuple(dict.fromkeys(args.disable))  # each named once
    if args.paper_smoothing:
        if args.planner in PLANNERS and not _takes_option(PLANNERS[args.planner], "disable"):
            raise InputError(
                f"--paper-smoothing: applies to the improved planner only, not {args.planner!r}"
            )
        from rrtdrive.planning.smoothing import CurveKind

        options["smoothing"] = {"curve": CurveKind.BSPLINE}
    extra = parse_planner_options(args.planner_options, "--planner-option")
    flags = {**PLANNER_FLAGS, **planner_option_flags(extra, "--planner-option")}
    for key in extra.keys() & {*options, *(args.disable or ())}:
        flag = {"smoothing": "--paper-smoothing", "step": "--step"}.get(key, "--disable")
        raise InputError(f"--planner-option {key}: also given by {flag}; give it once")
    with flags_for(flags):
        planner = make_planner(args.planner, **options, **extra)
    reversing = args.reverse and bool(getattr(planner, "reverses", False))
    if args.reverse and not reversing:
        # The default reverses only in its escalation: --disable escalation ends that.
        off = (
            "--disable escalation" if "escalation" in (args.disable or ())
            else "--planner-option escalation=false"
        )  # fmt: skip
        why = f" with {off} (it reverses in that stage)"
        why = why if reverses(args.planner) else ""
        print(f"rrtdrive plan: {forward_only_note(args.planner, why=why)}", file=sys.stderr)
    budget = Budget(max_iterations=args.max_iterations, max_time_s=args.max_time)
    from rrtdrive.collision import CheckerConfig
    from rrtdrive.collision.grid import setup_notice

    config = (
        CheckerConfig() if args.resolution is None else CheckerConfig(resolution=args.resolution)
    )
    if (notice := setup_notice(m.bounds, config)) is not None:  # seconds of silence else
        print(f"rrtdrive plan: {notice}", file=sys.stderr, flush=True)
    # The map's distance field: per-map set-up too (a map too big for any grid: exit 2).
    problem, result = solve_on_map(
        lambda: planner, m, np.random.default_rng(args.seed), budget, config=config,
        reverse=args.reverse,
    )  # fmt: skip
    text = ""
    if args.json:
        doc = plan_to_json(
            result, args.seed, m.name, m.vehicle, reverse=args.reverse, start=m.start,
            goal=m.goal, map_file=None if args.map in BUILTIN_MAPS else args.map,
            planner_options={**options, **extra}, budget=budget,
            resolution=problem.checker.resolution,
        )  # fmt: skip
        text = json.dumps(doc) + "\n"
    if args.json == "-":
        write_output(args.json, text)

    def plot() -> None:
        from rrtdrive.plotting import plot_plan, save_figure

        save_figure(plot_plan(m, result, seed=args.seed, reverse=reversing), args.plot)

    # Each file whatever became of the other; a failure is reported after the summary.
    unwritten = write_each([
        ("--json", args.json, lambda: write_text_atomic(args.json, text)),
        ("--plot", args.plot, plot),
    ])  # fmt: skip
    cusps = len(result.path.cusps)
    gears = f"{cusps} gear change{'s' if cusps != 1 else ''}, " if cusps else ""
    setup = f"set-up {result.setup_time_s:.1f} s" if notice is not None else ""
    diagnosis_s = result.stats.get("diagnosis_time_s")
    if setup and not result.success and diagnosis_s is not None:  # a big map's whole grid
        setup += f", diagnosis {diagnosis_s:.1f} s"
    from rrtdrive.planning.hybrid.escalation import stage_of

    stage = stage_of(result) if result.success else result.planner
    # The stage that solved it when not the planner's first (the JSON's "stage").
    by = f", by its {stage} stage" if stage != result.planner else ""
    summary = f"{m.name}: {result.planner} seed {args.seed}: " + (
        f"solved, length {result.path.length:.2f} m, {gears}max curvature "
        f"{result.path.max_curvature:.4f} 1/m, {result.nodes} nodes, "
        f"{1e3 * result.planning_time_s:.1f} ms{by}" + (f" ({setup})" if setup else "")
        if result.success
        else f"FAILED ({result.status.value}{', ' + setup if setup else ''}): {result.message}"
        + ("" if result.diagnosis is None else f"\n  why: {result.diagnosis.message}")
    )
    # With the JSON on stdout, the human summary goes to stderr to keep stdout parseable.
    print(summary, file=sys.stderr if args.json == "-" else sys.stdout)
    raise_unwritten("plan", unwritten)
    return EXIT_OK if result.success else EXIT_FAILED


@dataclass(frozen=True)
class Command:
    """A subcommand: its one-line help and where its full parser is built.

    ``module:function`` is imported only when the subcommand is run (or its own
    ``--help`` is asked for); the function receives the subparsers object.
    """

    name: str
    help: str
    builder: str


#: Every subcommand, in ``rrtdrive --help`` order.
COMMANDS: tuple[Command, ...] = (
    Command("plan", "plan a path on a map", "rrtdrive.cli:add_plan_parser"),
    Command(
        "maps",
        "list or export the built-in maps, import an occupancy image",
        "rrtdrive.cli_maps:add_parser",
    ),
    Command(
        "verify",
        "check a plan's path against its map with the independent verifier",
        "rrtdrive.verify_cli:add_parser",
    ),
    Command(
        "simulate",
        "plan and drive one closed-loop episode in highway-env",
        "rrtdrive.sim.cli_simulate:add_parser",
    ),
    Command(
        "bench",
        "run a grid of maps/scenarios x planners x controllers x seeds in parallel",
        "rrtdrive.bench.cli_bench:add_parser",
    ),
)


def add_plan_parser(sub: Any) -> argparse.ArgumentParser:
    """Add ``plan`` to an argparse subparsers object and return its parser."""
    from rrtdrive.planning import PLANNERS

    default_planner = (
        "improved-rrt-connect" if "improved-rrt-connect" in PLANNERS else "rrt-connect"
    )
    plan = sub.add_parser(
        "plan",
        help=_command("plan").help,
        description="Plan a path from the map's start to its goal (or --start/--goal). "
        "Exit 0 when solved, 1 when no path was found (or an output could not be "
        "written), 2 on bad input; 130 on Ctrl-C, 143 on SIGTERM.",
    )
    plan.add_argument("map", help="a built-in map name (see `rrtdrive maps`) or a map .json file")
    plan.add_argument(
        "--start", metavar="X,Y,YAW",
        help="override the start pose (yaw in rad); negative values work: --start -5,6,0",
    )
    plan.add_argument("--goal", metavar="X,Y,YAW", help="override the goal pose (yaw in rad)")
    plan.add_argument(
        "--planner",
        default=default_planner,
        metavar="NAME",
        help=f"one of {', '.join(sorted(PLANNERS))} (default: {default_planner})",
    )
    plan.add_argument(
        "--seed", type=nonneg_int, default=0, metavar="N", help="random seed (default 0)"
    )
    plan.add_argument(
        "--step", type=positive_float, default=None, metavar="M",
        help="step in metres: the tree's, or hybrid-a-star's expansion step (planner default)",
    )
    plan.add_argument(
        "--disable",
        action="append",
        metavar="COMPONENT",
        help="switch off a component of the improved planner (repeatable), for ablation; "
        "improved-rrt-connect only: direct_connect, obtuse_parent, adaptive_step, "
        "obstacle_expansion, prune, sharp_repair, supplement, passage_sampling, "
        "dubins_fallback, escalation (supplement acts on the B-spline of "
        "--paper-smoothing only)",
    )
    plan.add_argument(
        "--planner-option",
        action="append",
        dest="planner_options",
        metavar="FIELD=VALUE",
        help="set a field of the planner's config (repeatable), e.g. reverse_detour_tree=false "
        "(the improved planner: ImprovedConfig; hybrid-a-star: HybridConfig); a nested "
        "config's field is dotted (smoothing.max_rounds=8); values are read as JSON (4, 0.5, "
        "true, Infinity), else as text",
    )
    plan.add_argument(
        "--paper-smoothing",
        action="store_true",
        help="the paper's degree-2 B-spline post-processing (curvature jumps where a leg "
        "meets a fillet) instead of the default clothoid turns (continuous curvature, "
        "steering rate per metre <= max_steer_rate / 2 m/s, 0.2 rad/m by default); "
        "improved-rrt-connect only",
    )
    plan.add_argument(
        "--max-iterations",
        type=positive_int,
        default=20_000,
        metavar="N",
        help="iteration budget: with the seed it decides the outcome (default 20000)",
    )
    plan.add_argument(
        "--max-time", type=positive_float, default=Budget().max_time_s, metavar="S",
        help="wall-clock safety cap in seconds, set-up excluded (default "
        f"{Budget().max_time_s:g}); reaching it fails with status 'timeout', since the "
        "result would depend on the machine's speed; a forward failure's diagnosis may "
        "then run its counted reverse probe (4000 expansions) for up to 30 s more",
    )
    plan.add_argument(
        "--resolution", type=cell_size, default=None, metavar="M",
        help="collision grid cell size in metres, up to 100 (default 0.1; a map too big for "
        "that gets a coarser grid up to 0.5 m automatically, with a warning)",
    )
    plan.add_argument(
        "--reverse", action="store_true",
        help="allow gear changes (driving in reverse); a planner that cannot reverse "
        "returns a forward-only path (JSON: \"reverse\": true, \"cusps\": 0)",
    )
    plan.add_argument("--json", metavar="FILE|-", help="write the result as JSON ('-' for stdout)")
    plan.add_argument(
        "--plot", metavar="FILE.png",
        help="draw map, trees and path to a figure (.png, .pdf or .svg)",
    )
    plan.set_defaults(func=_cmd_plan)
    return plan


def _command(name: str) -> Command:
    return next(c for c in COMMANDS if c.name == name)


def _add_full_parser(sub: Any, command: Command) -> argparse.ArgumentParser:
    module_name, function = command.builder.split(":")
    try:
        module = importlib.import_module(module_name)
    except ImportError as exc:  # e.g. highway-env missing from a partial install
        raise InputError(f"{command.name}: not available ({exc})") from None
    return getattr(module, function)(sub)


def _build(
    command: str | None, all_in_full: bool = False
) -> tuple[argparse.ArgumentParser, argparse.ArgumentParser | None]:
    parser = _Parser(
        prog="rrtdrive",
        description="Plan curvature-bounded car paths with an improved RRT-Connect and drive "
        "them closed-loop in highway-env.",
    )
    from rrtdrive import __version__

    parser.add_argument("--version", action="version", version=f"rrtdrive {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    sub.required = True
    chosen = None
    for c in COMMANDS:
        if all_in_full or c.name == command:
            full = _add_full_parser(sub, c)
            if c.name == command:
                chosen = full
        else:
            # Listed in --help, never parsed: main builds the chosen command in full.
            sub.add_parser(c.name, help=c.help, add_help=False)
    return parser, chosen


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The argument parser: every subcommand in full, or only ``command`` in full.

    Parameters
    ----------
    command : str, optional
        Build only this subcommand's arguments (the others are listed in ``--help``
        but have none); ``None`` builds all of them, which imports every subsystem.
    """
    return _build(command, all_in_full=command is None)[0]


def _command_in(argv: Sequence[str]) -> str | None:
    # The top-level parser has only flags without values, so the first word is the command.
    names = {c.name for c in COMMANDS}
    for token in argv:
        if not token.startswith("-"):
            return token if token in names else None
    return None


def _value_options(parser: argparse.ArgumentParser) -> set[str]:
    return {
        opt
        for action in parser._actions  # argparse offers no public list of its options
        if action.nargs is None and action.option_strings
        for opt in action.option_strings
        if opt.startswith("--")
    }


def main(argv: Sequence[str] | None = None) -> int:
    """Run the CLI; return the exit code.

    Parameters
    ----------
    argv : sequence of str, optional
        The arguments (default: ``sys.argv[1:]``).

    Returns
    -------
    int
        0 success, 1 failure (also when stdout or an output file cannot be written),
        2 bad input,
        141 when the reader of stdout went away, 130 on Ctrl-C, 143 on SIGTERM.
    """
    return run_writing_stdout(lambda: _interruptible(argv))


def _interruptible(argv: Sequence[str] | None) -> int:
    # Ctrl-C also while the subcommand's modules load (bench: up to 3 s), not just as it runs.
    loading_done()  # the package's own imports had their handler (cli_signals)
    try:
        return _main(argv)
    except KeyboardInterrupt:
        print("rrtdrive: interrupted", file=sys.stderr)
        return 130
    except ImportError as exc:  # Ctrl-C while a C extension initialised (building parsers)
        if interrupt_behind(exc) is None:
            raise
        print("rrtdrive: interrupted", file=sys.stderr)
        return 130


def _main(argv: Sequence[str] | None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    command = _command_in(argv)
    try:
        parser, chosen = _build(command)
    except InputError as exc:
        print(f"rrtdrive {command}: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    if chosen is not None:
        argv = join_negative_values(argv, _value_options(chosen))
    args, extra = parser.parse_known_args(argv)
    if extra:  # named by the subcommand, whose --help lists what it takes
        (chosen or parser).error(f"unrecognized arguments: {' '.join(extra)}")
    if getattr(args, "json", None) not in (None, "-") and names_stdout(args.json):
        args.json = "-"  # --json /dev/stdout: keep the human lines off stdout as for '-'
    args.argv = argv  # what was run, for the records (main(argv) is not sys.argv)
    try:
        with sigterm_raises(), warnings_as_lines(f"rrtdrive {args.command}"):
            try:
                return int(args.func(args))
            except ImportError as exc:  # a signal while a C extension initialised
                if (interrupt := interrupt_behind(exc)) is None:
                    raise
                raise interrupt from None
    except InputError as exc:
        print(f"rrtdrive {args.command}: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except OutputError as exc:
        print(f"rrtdrive {args.command}: error: {exc}", file=sys.stderr)
        return EXIT_FAILED
    except KeyboardInterrupt:
        if not sigterm_received():  # Ctrl-C: _interruptible says so
            raise
        print("rrtdrive: terminated", file=sys.stderr)
        return EXIT_TERMINATED


if __name__ == "__main__":
    sys.exit(main())
