"""The ``rrtdrive`` command line: ``plan``, ``maps`` and (when available) ``simulate``.

Exit codes: 0 success, 1 planning or episode failure, 2 bad input (one line on
stderr, no traceback).
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence
from typing import NoReturn

import numpy as np

from rrtdrive.cli_args import nonneg_int, positive_float, positive_int
from rrtdrive.types import Budget, InputError, PlanResult, Pose

__all__ = ["main", "plan_to_json", "parse_pose"]

EXIT_OK, EXIT_FAILED, EXIT_BAD_INPUT = 0, 1, 2


class _Parser(argparse.ArgumentParser):
    """An argparse parser whose errors are one line on stderr, exit code 2."""

    def error(self, message: str) -> NoReturn:
        self.exit(EXIT_BAD_INPUT, f"{self.prog}: error: {message} (see --help)\n")


def parse_pose(text: str, name: str) -> Pose:
    """Parse ``"x,y,yaw"`` (yaw in radians) into a :class:`Pose`, naming ``name`` in errors."""
    parts = text.split(",")
    if len(parts) != 3:
        raise InputError(f"{name}: expected x,y,yaw, got {text!r}")
    try:
        values = [float(p) for p in parts]
    except ValueError:
        raise InputError(f"{name}: expected three numbers x,y,yaw, got {text!r}") from None
    return Pose.from_seq(values, name)


def plan_to_json(result: PlanResult, seed: int, map_name: str) -> dict[str, object]:
    """The JSON contract of ``rrtdrive plan`` (SPEC §5)."""
    return {
        "success": result.success,
        "status": result.status.value,
        "planner": result.planner,
        "map": map_name,
        "seed": seed,
        "path": np.round(result.path.samples, 6).tolist(),
        "waypoints": np.round(result.path.waypoints, 6).tolist(),
        "length_m": round(result.path.length, 6),
        "max_curvature": round(result.path.max_curvature, 6),
        "nodes": result.nodes,
        "iterations": result.iterations,
        "planning_time_s": result.planning_time_s,
        "message": result.message,
    }


def _write_output(target: str, text: str) -> None:
    if target == "-":
        sys.stdout.write(text)
        sys.stdout.flush()
    else:
        from rrtdrive.maps import write_text_atomic

        try:
            write_text_atomic(target, text)
        except OSError as exc:
            raise InputError(f"--json: cannot write {target}: {exc.strerror}") from None


def _cmd_plan(args: argparse.Namespace) -> int:
    from rrtdrive.maps import resolve_map
    from rrtdrive.planning import PlanningProblem, make_planner

    m = resolve_map(args.map)
    start = parse_pose(args.start, "--start") if args.start else None
    goal = parse_pose(args.goal, "--goal") if args.goal else None
    if start or goal:
        m = m.with_query(start, goal)
    options: dict[str, object] = {}
    if args.step is not None:
        options["step"] = args.step
    if args.disable:
        options["disable"] = tuple(args.disable)
    planner = make_planner(args.planner, **options)
    budget = Budget(max_iterations=args.max_iterations, max_time_s=args.max_time)
    problem = PlanningProblem.from_map(m)
    result = planner.solve(problem, np.random.default_rng(args.seed), budget)
    if args.json:
        _write_output(args.json, json.dumps(plan_to_json(result, args.seed, m.name)) + "\n")
    if args.plot:
        from rrtdrive.plotting import plot_plan, save_figure

        try:
            save_figure(plot_plan(m, result), args.plot)
        except OSError as exc:
            raise InputError(f"--plot: cannot write {args.plot}: {exc.strerror}") from None
    summary = f"{m.name}: {result.planner} seed {args.seed}: " + (
        f"solved, length {result.path.length:.2f} m, max curvature "
        f"{result.path.max_curvature:.4f} 1/m, {result.nodes} nodes, "
        f"{1e3 * result.planning_time_s:.1f} ms"
        if result.success
        else f"FAILED ({result.status.value}): {result.message}"
    )
    # With the JSON on stdout, the human summary goes to stderr to keep stdout parseable.
    print(summary, file=sys.stderr if args.json == "-" else sys.stdout)
    return EXIT_OK if result.success else EXIT_FAILED


def _cmd_maps(args: argparse.Namespace) -> int:
    from pathlib import Path

    from rrtdrive.maps import BUILTIN_MAPS, builtin_map, save_map

    for name in BUILTIN_MAPS:
        m = builtin_map(name)
        line = (
            f"{name:12s} {len(m.obstacles):4d} obstacles  start {m.start.as_tuple()}  goal "
            + str(tuple(round(v, 3) for v in m.goal.as_tuple()))
        )
        if args.export:
            out = Path(args.export)
            if not out.is_dir():
                raise InputError(f"--export: {out} is not a folder")
            save_map(m, out / f"{name}.json")
            line += f"  -> {out / (name + '.json')}"
        print(line)
    return EXIT_OK


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with every subcommand."""
    from rrtdrive.planning import PLANNERS

    parser = _Parser(
        prog="rrtdrive",
        description="Plan curvature-bounded car paths with an improved RRT-Connect and drive "
        "them closed-loop in highway-env.",
    )
    from rrtdrive import __version__

    parser.add_argument("--version", action="version", version=f"rrtdrive {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    sub.required = True

    default_planner = (
        "improved-rrt-connect" if "improved-rrt-connect" in PLANNERS else "rrt-connect"
    )
    plan = sub.add_parser(
        "plan",
        help="plan a path on a map",
        description="Plan a path from the map's start to its goal (or --start/--goal). "
        "Exit 0 when solved, 1 when no path was found, 2 on bad input.",
    )
    plan.add_argument("map", help="a built-in map name (see `rrtdrive maps`) or a map .json file")
    plan.add_argument("--start", metavar="X,Y,YAW", help="override the start pose (yaw in rad)")
    plan.add_argument("--goal", metavar="X,Y,YAW", help="override the goal pose (yaw in rad)")
    plan.add_argument(
        "--planner",
        default=default_planner,
        metavar="NAME",
        help=f"one of {', '.join(sorted(PLANNERS))} (default: {default_planner})",
    )
    plan.add_argument("--seed", type=nonneg_int, default=0, help="random seed (default 0)")
    plan.add_argument(
        "--step", type=float, default=None, help="tree step in metres (planner default)"
    )
    plan.add_argument(
        "--disable",
        action="append",
        metavar="COMPONENT",
        help="switch off a component of the improved planner (repeatable), for ablation",
    )
    plan.add_argument(
        "--max-iterations",
        type=positive_int,
        default=20_000,
        help="iteration budget (default 20000)",
    )
    plan.add_argument(
        "--max-time", type=positive_float, default=5.0, help="time budget in seconds (default 5)"
    )
    plan.add_argument("--json", metavar="FILE|-", help="write the result as JSON ('-' for stdout)")
    plan.add_argument("--plot", metavar="FILE.png", help="draw map, trees and path to a PNG")
    plan.set_defaults(func=_cmd_plan)

    maps = sub.add_parser(
        "maps",
        help="list the built-in maps",
        description="List the built-in maps; --export writes them as JSON files.",
    )
    maps.add_argument("--export", metavar="DIR", help="write each built-in map to DIR/NAME.json")
    maps.set_defaults(func=_cmd_maps)

    try:
        from rrtdrive.sim import cli_simulate
    except ImportError:
        cli_simulate = None
    if cli_simulate is not None:
        cli_simulate.add_parser(sub)
    try:
        from rrtdrive.bench import cli_bench
    except ImportError:
        cli_bench = None
    if cli_bench is not None:
        cli_bench.add_parser(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the CLI; return the exit code."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args))
    except InputError as exc:
        print(f"rrtdrive {args.command}: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        print("rrtdrive: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
