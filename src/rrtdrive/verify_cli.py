"""The ``rrtdrive verify`` subcommand: check a plan's path with :func:`rrtdrive.verify.verify_path`.

It reads the JSON of ``rrtdrive plan --json`` (or any ``{"path": [[x, y, yaw,
kappa(, gear)], ...]}`` or ``{"path": [[x, y, yaw], ...]}``, so paths from other planners
can be judged too: poses alone get their gears and kappa from the motion), takes the
map from the command line, else the plan's map file (``map_file``), else the
built-in map the plan names, the start and goal from ``--start`` /
``--goal``, else the plan's, else the map's own, and prints each check with its
measured value and bound.

Exit codes: 0 when every check passes, 1 when one fails (or the plan has no path),
2 on bad input (one line on stderr, naming the field).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import sys
import warnings
from collections.abc import Mapping
from typing import Any

import numpy as np

from rrtdrive.atomic import write_text_atomic
from rrtdrive.cli_args import (
    PLOT_SUFFIXES,
    distinct_outputs,
    flags_for_warnings,
    nonneg_float,
    parse_pose,
    positive_float,
    raise_unwritten,
    validate_output,
    write_each,
    write_output,
)
from rrtdrive.json_safe import json_safe
from rrtdrive.plan_file import plan_car, read_plan_json, with_plan_car
from rrtdrive.types import (
    InputError,
    InputWarning,
    Pose,
    VehicleParams,
    brief_repr,
    is_finite_number,
)

__all__ = ["add_parser", "run", "HELP"]

EXIT_OK, EXIT_FAILED = 0, 1
#: What ``--clearance`` allows under a plan's ``body_clearance_m``: the improved planner
#: checks its curve, which the 0.25 m rows (interpolated here) follow within 1.3 mm
#: (``kappa_max s^2 / 8``); Hybrid A* checks the rows themselves (to the JSON's 6 decimals).
CLEARANCE_SLACK_M = 0.002
HELP = "check a plan's path against its map with the independent verifier"


def add_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Add ``verify`` to an argparse subparsers object and return its parser."""
    p = subparsers.add_parser(
        "verify",
        help=HELP,
        description="Check a path against a map with code that shares nothing with the "
        "planners: the car's body (shapely) at poses <= 0.1 m apart clear of every "
        "obstacle and inside the bounds, with the least clearance it keeps, curvature "
        "(from the positions and the yaw's turn) and sharpness measured, not read from "
        "kappa (whose column must agree with the yaw's turn, by the gear), headings at "
        "both ends, exact start and goal poses, sample spacing, and per "
        "gear segment the direction of travel and the cusps. Exit 0 when every check "
        "passes, 1 when one fails, 2 on bad input; 130 on Ctrl-C, 143 on SIGTERM.",
    )
    p.add_argument("plan", metavar="PLAN", help="the plan JSON ('-' for stdin), e.g. from "
                   "`rrtdrive plan MAP --json plan.json`, or another planner's {\"path\": "
                   "rows}: [x, y, yaw, kappa(, gear)], or [x, y, yaw] whose gears and kappa "
                   "are read off the motion")
    p.add_argument(
        "map", nargs="?", default=None, metavar="MAP",
        help="a built-in map name or a map .json file (default: the plan's map file, else "
        "the built-in map it names)",
    )
    p.add_argument("--start", metavar="X,Y,YAW",
                   help="the start pose (default: the plan's, else the map's)")
    p.add_argument("--goal", metavar="X,Y,YAW",
                   help="the goal pose (default: the plan's, else the map's)")
    sharp = p.add_mutually_exclusive_group()
    sharp.add_argument(
        "--max-sharpness", type=positive_float, default=None, metavar="RAD_PER_M",
        help="bound on the steering angle's change per metre (default: the default "
        "planners' guarantee, 0.2 rad/m, or the car's max_steer_rate / 2 m/s when smaller)",
    )
    sharp.add_argument(
        "--no-sharpness", action="store_true",
        help="do not check sharpness (paths of --paper-smoothing or of planners without "
        "steering-rate limits jump in curvature by design)",
    )
    p.add_argument(
        "--clearance", type=nonneg_float, default=None, metavar="M",
        help="least distance in metres the body must keep from every obstacle and the edge "
        "of the bounds at the tested poses (default: the plan's body_clearance_m less "
        f"{CLEARANCE_SLACK_M * 1000:g} mm, else 0: no contact); the least clearance is "
        "measured and printed either way",
    )
    p.add_argument("--json", metavar="FILE|-", help="also write the checks as JSON ('-': stdout)")
    p.add_argument(
        "--plot", metavar="FILE.png",
        help="draw the map, the path (reverse dashed, cusps marked) and the body at the "
        "first pose that collides to a figure (.png, .pdf or .svg)",
    )
    p.set_defaults(func=run)
    return p


def _plan_pose(data: dict[str, Any], field: str) -> Pose | None:
    value = data.get(field)
    if value is None:
        return None
    # The plan's own field name in errors ("plan.start"), never Pose's generic "pose".
    return Pose.from_seq(value, f"plan.{field}")


def _map_of(
    args: argparse.Namespace, data: dict[str, Any], start: Pose | None, goal: Pose | None
) -> Any:
    """The map to check against: ``MAP``, else the plan's map file, else its built-in map.

    ``start`` and ``goal`` replace the map's poses, unchecked: a path from or to a pose
    in collision fails its body check there, it is not bad input.
    """
    import os

    from rrtdrive.maps import BUILTIN_MAPS, resolve_map

    # A yaw that looks like degrees is named by where it came from.
    sources = {
        field: f"--{field}" if getattr(args, field) is not None else f"plan.{field}"
        for field, pose in (("start", start), ("goal", goal)) if pose is not None
    }

    def load(spec: str) -> Any:
        try:
            with flags_for_warnings(sources):
                return resolve_map(spec, start=start, goal=goal, check_query=False)
        except InputError as exc:
            # "goal: must be finite" alone read as the plan's goal (named plan.goal:).
            if str(exc).startswith("map"):
                raise
            raise InputError(f"map {spec}: {exc}") from None

    spec = data.get("map")
    map_file = data.get("map_file")
    if map_file is not None and not isinstance(map_file, str):
        raise InputError(
            f"plan.map_file: expected the map file's path or null, got {brief_repr(map_file)}"
        )
    if args.map is not None:
        m = load(args.map)
        if isinstance(spec, str) and spec and m.name != spec:
            warnings.warn(
                f"MAP: the plan was made on map {spec!r}; it is checked against {m.name!r} "
                "as asked", InputWarning, stacklevel=2,
            )
        return m
    if map_file:
        if os.path.isdir(map_file):
            raise InputError(
                f"map: the plan was made on the map file {map_file}, which is now a folder; "
                "give the map: rrtdrive verify PLAN MAP.json"
            )
        if not os.path.isfile(map_file):
            raise InputError(
                f"map: the plan was made on the map file {map_file}, which is not there any "
                "more; give the map: rrtdrive verify PLAN MAP.json"
            )
        return load(map_file)
    if not isinstance(spec, str) or not spec:
        raise InputError("map: the plan names no map; give one: rrtdrive verify PLAN MAP")
    if spec not in BUILTIN_MAPS:
        raise InputError(
            f"map: the plan names map {spec!r}, which is not built in, and no map file; "
            "give its file: rrtdrive verify PLAN MAP.json"
        )
    return load(spec)


def _metres(value: float, spec: str = ".3f") -> str:
    """``value`` in metres; a path row at 1e308 m shows as 1e+308 m, not 309 digits."""
    return f"{value:{spec}} m" if abs(value) < 1e9 else f"{value:.3g} m"


def _where(check: Any) -> str:
    """Where the body check first fails: the pose and what the body overlaps there."""
    if check.first_collision is None:
        return ""
    x, y, yaw = check.first_collision
    return (f"first at ({_metres(x, '.2f')[:-2]}, {_metres(y, '.2f')[:-2]}), "
            f"yaw {math.degrees(yaw):.1f} deg: {check.collides_with}")


def _lines(
    check: Any, bounds: dict[str, float | None], why: str = "", kappa_given: bool = True
) -> list[str]:
    """One line per check: its name, pass or FAIL, and the measured value against its bound.

    ``kappa_given`` false: the rows were poses alone, their ``kappa`` read off the yaw's
    turn, so its line says so instead of judging it.
    """
    from rrtdrive.verify import (
        CURVATURE_TOL,
        HEADING_TOL_DEG,
        KAPPA_TOL,
        SHARPNESS_TOL,
        TRAVEL_TOL_DEG,
    )

    mark = {True: "ok  ", False: "FAIL"}
    sharp = bounds["sharpness_bound"]
    rows = [
        (check.collision_free, "body clear of obstacles and inside the bounds",
         _where(check)),
        (check.curvature_ok, "curvature",
         f"{check.max_discrete_curvature:.4f} 1/m "
         f"(max {bounds['kappa_max']:.4f} + {CURVATURE_TOL:g})"),
        (check.sharpness_ok, "sharpness",
         f"{check.max_discrete_sharpness:.4f} rad/m "
         + ("(not checked)" if sharp is None else f"(max {sharp:g} + {SHARPNESS_TOL:g})")),
        (check.headings_ok, "headings at start / goal",
         f"{check.start_heading_err_deg:.2f} / {check.goal_heading_err_deg:.2f} deg "
         f"(max {HEADING_TOL_DEG:g})"),
        (check.endpoints_ok, "ends exactly at start and goal",
         f"{_metres(check.endpoint_err_m, '.6f')} / {check.endpoint_yaw_err_deg:.4f} deg "
         "(max 1e-06 m / 0.0001 deg)"),
        (check.spacing_ok, "sample spacing", f"{_metres(check.max_spacing_m)} (max 0.25)"),
        (check.travel_ok, "direction of travel along the yaw",
         f"{check.travel_heading_err_deg:.2f} deg (max {TRAVEL_TOL_DEG:g})"),
        (check.cusps_ok, "cusps repeat their pose", _cusp_detail(check)),
        (check.clearance_ok, "clearance to obstacles and bounds",
         f"{_metres(check.min_clearance_m, '.4f')} (min {bounds['clearance']:g}{why})"),
        (check.kappa_ok, "kappa column agrees with the yaw's turn",
         f"{check.kappa_column_err:.4f} 1/m off (max {KAPPA_TOL:g})"
         + ("" if check.worst_kappa_row is None else f"; worst at row {check.worst_kappa_row}")
         if kappa_given else "not given: rows [x, y, yaw], gears and kappa read off the motion"),
    ]
    return [f"  {mark[bool(ok)]} {name:48s} {detail}".rstrip() for ok, name, detail in rows]


def _cusp_detail(check: Any) -> str:
    detail = f"{check.cusps} gear change(s)"
    if check.cusps:
        detail += (f", largest jump {_metres(check.cusp_gap_m, '.6f')} / "
                   f"{check.cusp_yaw_err_deg:.4f} deg (max 1e-06 m / 0.001 deg)")  # fmt: skip
    if check.first_bad_cusp_row is not None:
        detail += f"; first at row {check.first_bad_cusp_row}"
    return detail


def run(args: argparse.Namespace) -> int:
    """Run ``rrtdrive verify``; return the exit code."""
    from rrtdrive.verify import path_from_json, verify_path

    plot = getattr(args, "plot", None)  # a Namespace built by a caller may lack it
    validate_output(args.json, "--json")
    validate_output(plot, "--plot", PLOT_SUFFIXES, allow_stdout=False)
    data = read_plan_json(args.plan, "plan")
    map_file = data.get("map_file") if args.map is None else args.map
    distinct_outputs(
        {"PLAN": args.plan, "MAP": map_file if isinstance(map_file, str) else None},
        json=args.json, plot=plot,
    )
    path = path_from_json(data)
    rows_given = data["path"]
    kappa_given = not (isinstance(rows_given, list) and rows_given and len(rows_given[0]) == 3)
    start = parse_pose(args.start, "--start") if args.start is not None else _plan_pose(
        data, "start"
    )
    goal = parse_pose(args.goal, "--goal") if args.goal is not None else _plan_pose(data, "goal")
    m = with_plan_car(_map_of(args, data, start, goal), plan_car(data, "plan.vehicle"), "MAP")
    bound = args.max_sharpness
    if bound is None and not args.no_sharpness:
        from rrtdrive.planning.smoothing.config import SmoothingConfig, sharpness_bound

        # The bound the default planners keep for this car.
        bound = sharpness_bound(SmoothingConfig().max_sharpness, m.vehicle.max_steer_rate)
    clearance, why = args.clearance, ""
    kept = data.get("body_clearance_m")
    if kept is not None and not (is_finite_number(kept) and kept >= 0):
        # A claim that cannot be read is bad input, not a claim of none.
        raise InputError(
            f"plan.body_clearance_m: expected a number >= 0 (metres) or null, got "
            f"{brief_repr(kept)}"
        )
    if clearance is None and kept is not None and kept >= CLEARANCE_SLACK_M:
        clearance = float(kept) - CLEARANCE_SLACK_M
        why = f": the plan's {kept:g} less {CLEARANCE_SLACK_M * 1000:g} mm"
    clearance = clearance or 0.0
    # The sharpness bound is not named max_sharpness: plan --json uses that for the
    # path's measured value (here max_discrete_sharpness).
    bounds = {"kappa_max": m.vehicle.kappa_max, "sharpness_bound": bound, "clearance": clearance}
    # With the JSON on stdout, the human lines go to stderr to keep stdout parseable.
    out = sys.stderr if args.json == "-" else sys.stdout
    label = "stdin" if args.plan == "-" else args.plan
    rows = len(path.samples)
    check = verify_path(m, path, max_sharpness=bound, clearance=clearance)
    with np.errstate(all="ignore"):  # a row at 1e308 m: the length is inf, quietly
        length = path.length if rows else 0.0
    claims = _claims(data, check.cusps)
    failed = [*check.failed, *(["claims_ok"] if claims else [])]
    text = ""
    if args.json:
        from rrtdrive.vehicle_json import vehicle_to_json

        doc = {"map": m.name, "rows": rows, "kappa_given": kappa_given,
               "length_m": round(length, 6), "vehicle": vehicle_to_json(m.vehicle),
               **bounds, **dataclasses.asdict(check), "claims_ok": not claims,
               "ok": not failed, "failed": failed}
        # Strict JSON: a non-finite number (a row far off the map) is null, not Infinity.
        text = json.dumps(json_safe(doc), allow_nan=False) + "\n"
    def draw() -> None:
        from rrtdrive.plotting import plot_check, save_figure

        save_figure(plot_check(m, path, check, label), plot)

    # The files first: a reader of stdout that goes away (| head) ends the printing,
    # and the files asked for were then never written. Each is written whatever became
    # of the other; a failure is reported after the verdict.
    unwritten = write_each([
        ("--plot", plot, draw),
        ("--json", args.json, lambda: write_text_atomic(args.json, text)),
    ])  # fmt: skip
    if rows < 2:
        status = data.get("status", "unknown")
        what = "no path" if rows == 0 else "a path of one row (a path needs two)"
        print(f"{m.name}: {label}: FAILED: the plan has {what} (status {status})", file=out)
    else:
        verdict = "OK, every check passed" if not failed else "FAILED"
        print(f"{m.name}: {label}: {verdict} ({rows} rows, {_metres(length, '.2f')})", file=out)
        car = m.vehicle
        if car != VehicleParams():  # which car was judged: only the bounds showed it
            print(f"  for a car of {car.length:g} x {car.width:g} m, wheelbase "
                  f"{car.wheelbase:g} m, min turning radius {car.min_turning_radius:g} m "
                  f"({'the plan' if data.get('vehicle') is not None else 'the map'}'s)",
                  file=out)  # fmt: skip
        print("\n".join(_lines(check, bounds, why, kappa_given)), file=out)
        if "reverse" in data or "cusps" in data:
            mark = "FAIL" if claims else "ok  "
            detail = "; ".join(claims) or "reverse and cusps as its path"
            print(f"  {mark} {'the plan says what its path does':48s} {detail}", file=out)
    if check.failed == ("sharpness_ok",):
        print("  (only the sharpness fails: paths of --paper-smoothing and of planners "
              "without a steering-rate limit, such as OMPL's, jump in curvature by design; "
              "--no-sharpness checks the rest)", file=out)
    if args.json == "-":
        write_output(args.json, text)
    raise_unwritten("verify", unwritten)
    return EXIT_OK if not failed else EXIT_FAILED


def _claims(data: Mapping[str, Any], cusps: int) -> list[str]:
    """Where a plan file's own ``reverse`` and ``cusps`` disagree with its path's gears.

    A plan that says it is forward only and changes gear passed every check (an audit):
    a user who planned without ``--reverse`` relies on that claim.
    """
    out = []
    if data.get("reverse") is False and cusps:
        out.append(f"it says reverse: false, but its path changes gear {cusps} time(s)")
    said = data.get("cusps")
    if isinstance(said, int) and not isinstance(said, bool) and said != cusps:
        out.append(f"it says cusps: {said}, but its path changes gear {cusps} time(s)")
    return out
