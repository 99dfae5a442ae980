"""Turning round in a street closed at both ends: ours with reverse against OMPL's RS RRTConnect.

Usage (OMPL lives in the lead's venv only; without it its rows are skipped)::

    python experiments/street_turns.py --out results/street_turns

A user's three-point turn: a street ``--length`` metres long and ``W`` metres wide
(each of ``--widths``), walled at both ends, the car at (8, W/2) facing along it and the
goal the same position facing back (yaw pi); with ``--lanes BACK``, from lane to lane:
the start in the right-hand lane (y = W/4) at x = 16, the goal in the other lane
(y = 3W/4) facing back, BACK metres behind it. For each width and seed
(``--seeds``), in one run: the default planner and ``hybrid-a-star``, both with
``reverse``, on the counted 20 000-iteration budget (``--max-time`` is the cap), and
OMPL's Reeds-Shepp RRTConnect with our exact body test as validity checker
(``--ompl-time``, simplified), as ``experiments/coverage.py`` plans it, once for each
body clearance its states must keep (``--ompl-clearances``, default 0 m: touching allowed,
and our planners' 0.15 m; a row ``ompl-rs-rrtconnect@0.15m``). Every path is
judged by ``verify_path`` with the 0.2 rad/m sharpness bound (``verified``) and without
it (``any sharpness``). Ours are deterministic for a seed; OMPL's generator is seeded
once per process.

Writes ``OUT/street_turns.{json,md}``.
"""

from __future__ import annotations

import argparse
import math
import os
import statistics
import sys
import time
from typing import Any

import numpy as np
import shapely

sys.path.insert(0, os.path.dirname(__file__))
import coverage as cov  # noqa: E402  (the sibling script)
from results_io import command, machine, numbers_above, out_folder, write_results  # noqa: E402

from rrtdrive.cli_args import positive_float, positive_int  # noqa: E402
from rrtdrive.maps import Map  # noqa: E402
from rrtdrive.planning import PlanningProblem, make_planner  # noqa: E402
from rrtdrive.planning.hybrid import HybridConfig  # noqa: E402
from rrtdrive.types import Budget, Path, Pose  # noqa: E402

#: Our planners, each with reverse.
OURS = ("improved-rrt-connect", "hybrid-a-star")
OMPL_NAME = "ompl-rs-rrtconnect"
#: The body clearance our planners keep (both defaults), for OMPL's row at the same.
OUR_CLEARANCE = HybridConfig().body_clearance


def street(width: float, length: float, back: float | None = None) -> Map:
    """The closed street of ``width`` x ``length`` m, start and goal facing opposite ways.

    ``back`` (lanes): the start in the right-hand lane at x = 16, the goal in the
    other lane ``back`` metres behind it, as a three-point turn from lane to lane.
    """
    if back is None:
        y = width / 2.0
        return Map(f"street_{width:g}m", (0.0, 0.0, length, width), (), Pose(8.0, y, 0.0),
                   Pose(8.0, y, math.pi))  # fmt: skip
    x = 16.0
    return Map(f"lanes_{width:g}m", (0.0, 0.0, length, width), (), Pose(x, width / 4, 0.0),
               Pose(x - back, 3 * width / 4, math.pi))  # fmt: skip


def least_clearance(m: Map, path: Path) -> float:
    """The least distance from the car's body at any path row to an obstacle or the map's
    edge, by shapely (independent of the planner's checker), metres."""
    car = m.vehicle
    rows = path.samples
    c, s = np.cos(rows[:, 2]), np.sin(rows[:, 2])
    back, front, half = car.rear_overhang, car.length - car.rear_overhang, car.width / 2
    local = np.array([(-back, -half), (front, -half), (front, half), (-back, half)])
    xs = rows[:, 0, None] + c[:, None] * local[:, 0] - s[:, None] * local[:, 1]
    ys = rows[:, 1, None] + s[:, None] * local[:, 0] + c[:, None] * local[:, 1]
    bodies = shapely.polygons(np.stack([xs, ys], axis=-1))
    x0, y0, x1, y1 = m.bounds
    frame = shapely.box(x0 - 50, y0 - 50, x1 + 50, y1 + 50)
    outside = frame.difference(shapely.box(x0, y0, x1, y1))
    walls = shapely.union_all([outside, *(o.polygon() for o in m.obstacles)])
    return float(np.min(shapely.distance(bodies, walls)))


def ours_row(m: Map, planner: str, seed: int, max_time: float) -> dict[str, Any]:
    """One plan of ours with reverse, judged."""
    problem = PlanningProblem.from_map(m, reverse=True)
    res = make_planner(planner).solve(
        problem, np.random.default_rng(seed), Budget(max_iterations=20_000, max_time_s=max_time)
    )
    row = {"status": res.status.value, "solved": res.success, "time_s": res.planning_time_s,
           "iterations": res.iterations}  # fmt: skip
    if res.success:
        stats = res.stats
        row |= {
            # The body clearance the path's search kept (the default's escalation prefixes it).
            "clearance_m": stats.get("body_clearance_m", stats.get("hybrid_body_clearance_m")),
            "length_m": res.path.length,
            "cusps": len(res.path.cusps),
            "least_clearance_m": least_clearance(m, res.path),
            **cov._check(m, res.path),
        }
    else:
        row["message"] = res.message[:300]
    return row


def ompl_row(m: Map, seed: int, seconds: float, clearance: float = 0.0) -> dict[str, Any]:
    """OMPL's RS RRTConnect on the same map and checker (its body ``clearance`` clear), judged."""
    problem = PlanningProblem.from_map(m, reverse=True)
    _, total_s, length, path = cov.solve_ompl(problem, seed, OMPL_NAME, seconds, clearance)
    row: dict[str, Any] = {"solved": path is not None, "time_s": total_s}
    if path is not None:
        row["clearance_m"] = clearance  # the clearance its states had to keep
        row |= {
            "length_m": length,
            "cusps": len(path.cusps),
            "least_clearance_m": least_clearance(m, path),
            **cov._check(m, path),
        }
    return row


def add_run_options(ap: argparse.ArgumentParser, unit: str, out: str) -> None:
    """The options every side-by-side script shares: seeds, our cap, OMPL's time and
    clearances (``--ompl-clearances``: one OMPL row each), out."""
    ap.add_argument("--seeds", type=positive_int, default=3, help=f"seeds per {unit} (default 3)")
    ap.add_argument("--max-time", type=positive_float, default=10.0,
                    help="our wall-clock cap, s (default: %(default)s)")
    ap.add_argument("--ompl-time", type=positive_float, default=10.0,
                    help="OMPL's time, s (default: %(default)s)")
    ap.add_argument(
        "--ompl-clearances", default=f"0,{OUR_CLEARANCE:g}",
        help="body clearances OMPL's states must keep, m, one OMPL row each (default "
        f"0,{OUR_CLEARANCE:g}: touching allowed, and the {OUR_CLEARANCE:g} m our planners keep)",
    )  # fmt: skip
    ap.add_argument("--out", type=out_folder, default=out,
                    help=f"directory for {os.path.basename(out)}.json "
                    "and .md (default: %(default)s)")


def ompl_clearances(ap: argparse.ArgumentParser, text: str) -> tuple[float, ...]:
    """The parsed ``--ompl-clearances`` (exit 2 naming it when a value is bad)."""
    try:
        values = tuple(numbers_above(text, "--ompl-clearances", floor=-math.inf))
    except ValueError as err:
        ap.error(str(err))
    if any(not 0.0 <= v <= 1.0 for v in values):
        ap.error(f"--ompl-clearances: each value must lie within [0, 1] m, got {text!r}")
    return values


def ompl_label(clearance: float) -> str:
    """The row name of OMPL at ``clearance``: the bare name when touching is allowed."""
    return OMPL_NAME if clearance <= 0.0 else f"{OMPL_NAME}@{clearance:g}m"


def check_run_options(ap: argparse.ArgumentParser, args: argparse.Namespace) -> None:
    """Exit 2 naming the option when a shared one is out of range."""
    if args.seeds < 1 or args.max_time <= 0 or args.ompl_time <= 0:
        ap.error("--seeds must be >= 1, --max-time and --ompl-time > 0")
    args.ompl_clearances = ompl_clearances(ap, args.ompl_clearances)


def run_payload(
    script: str, argv: list[str] | None, args: argparse.Namespace, load: str, t0: float,
    rows: dict[str, Any],
) -> dict[str, Any]:
    """The results payload of a side-by-side script: its command, settings, machine, rows."""
    return {
        "command": command(script, argv),
        "seeds": args.seeds, "max_time": args.max_time, "ompl_time": args.ompl_time,
        "ompl_clearances": list(args.ompl_clearances), "load": load, "machine": machine(),
        "wall_time_s": time.perf_counter() - t0, "rows": rows,
    }  # fmt: skip


def planner_rows(
    m: Map, label: str, seeds: int, max_time: float, ompl_time: float, have_ompl: bool,
    ours: tuple[str, ...] = OURS,
    clearances: tuple[float, ...] = (0.0,),
) -> dict[str, list[dict[str, Any]]]:
    """Every planner's rows on one map: ours with reverse, then OMPL's when it is installed.

    ``label`` names the query in the progress lines on stderr; OMPL gets one row per
    body clearance of ``clearances`` (:func:`ompl_label`).
    """
    by_planner: dict[str, list[dict[str, Any]]] = {}
    for planner in ours:
        print(f"{label}: {planner} ...", file=sys.stderr, flush=True)
        by_planner[f"{planner}+reverse"] = [ours_row(m, planner, s, max_time) for s in range(seeds)]
    for clearance in clearances if have_ompl else ():
        name = ompl_label(clearance)
        print(f"{label}: {name} ...", file=sys.stderr, flush=True)
        by_planner[name] = [ompl_row(m, s, ompl_time, clearance) for s in range(seeds)]
    return by_planner


def median_cell(
    rows: list[dict[str, Any]], key: str, scale: float = 1.0, fmt: str = "{:.1f}"
) -> str:
    """The median of ``key`` times ``scale`` over the solved rows that have it (``-``: none)."""
    values = [r[key] * scale for r in rows if r["solved"] and r.get(key) is not None]
    return fmt.format(statistics.median(values)) if values else "-"


def page_header(payload: dict[str, Any], title: str, setting: str) -> list[str]:
    """The first lines of a side-by-side page: title, command, machine, ``setting``, budgets."""
    return [
        f"# {title}",
        "",
        f"Command: `{payload['command']}`  ",
        f"{payload['machine']}; wall time {payload['wall_time_s']:.0f} s; load at the start "
        f"{payload['load']}. {setting}; {payload['seeds']} seeds; ours 20 000 iterations "
        f"(cap {payload['max_time']:g} s), OMPL {payload['ompl_time']:g} s"
        f"{_ompl_clearances_note(payload)}.",
        "",
    ]


def _ompl_clearances_note(payload: dict[str, Any]) -> str:
    """The header's words on OMPL's clearances (runs before they were recorded: none)."""
    kept = [c for c in payload.get("ompl_clearances", []) if c > 0.0]
    if not kept:
        return ""
    rows = ", ".join(f"`{ompl_label(c)}`" for c in kept)
    return f"; OMPL's states may touch obstacles in its plain row, keep the clearance in {rows}"


def report(payload: dict[str, Any]) -> str:
    """The markdown page of a payload."""
    ends = (
        "the goal is the start turned round"
        if payload.get("lanes") is None
        else f"start in the right-hand lane at x = 16, goal in the other lane "
        f"{payload['lanes']:g} m behind it"
    )
    lines = [
        *page_header(
            payload,
            "Turning round in a closed street: ours with reverse and OMPL's RS RRTConnect",
            f"Street {payload['length']:g} m long; {ends}",
        ),
        "| width [m] | planner | solved | verified | any sharpness | median time [ms] | "
        "median length [m] | median cusps |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for width, by_planner in payload["rows"].items():
        for planner, rows in by_planner.items():
            lines.append(f"| {width} | {planner} | " + " | ".join(row_cells(rows)) + " |")
    return "\n".join(lines) + "\n"


def least_clearance_cell(rows: list[dict[str, Any]]) -> str:
    """The least body clearance over a planner's solved paths (``-`` where none has it)."""
    values = [r["least_clearance_m"] for r in rows if r["solved"] and "least_clearance_m" in r]
    return f"{min(values):.3f}" if values else "-"


def clearance_table_rows(payload: dict[str, Any]) -> list[str]:
    """A page's table rows: the case's key parts (``a|b|...``), the planner, its cells and
    the least clearance (the pages of ``angled_bays.py`` and ``garage_moves.py``)."""
    lines = []
    for key, by_planner in payload["rows"].items():
        case = " | ".join(key.split("|"))
        for planner, rows in by_planner.items():
            cells = " | ".join([*row_cells(rows), least_clearance_cell(rows)])
            lines.append(f"| {case} | {planner} | {cells} |")
    return lines


def row_cells(rows: list[dict[str, Any]]) -> list[str]:
    """A planner's cells for one query: solved, verified, any sharpness, median time,
    length and cusps (the columns ``kerb_gaps.py`` shares)."""
    solved = [r for r in rows if r["solved"]]
    cusps = statistics.median(r["cusps"] for r in solved) if solved else "-"
    return [
        f"{len(solved)}/{len(rows)}",
        f"{sum(r.get('verified', False) for r in rows)}",
        f"{sum(r.get('verified_any_sharpness', False) for r in rows)}",
        median_cell(rows, "time_s", 1000.0), median_cell(rows, "length_m"), f"{cusps}",
    ]  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--widths", default="6.5,7,7.5,8,9,10,12",
                    help="street widths, m (default: %(default)s)")
    ap.add_argument("--length", type=float, default=30.0, help="street length, m (default 30)")
    add_run_options(ap, "width", "results/street_turns")
    ap.add_argument(
        "--lanes", type=float, default=None, metavar="BACK",
        help="from lane to lane: the start in the right-hand lane at x = 16, the goal in "
        "the other lane BACK metres behind it (default: the goal is the start turned round)",
    )  # fmt: skip
    args = ap.parse_args(argv)
    try:
        widths = numbers_above(args.widths, "--widths", floor=2.0)
    except ValueError as err:
        ap.error(str(err))
    if args.lanes is not None and not 0.0 <= args.lanes <= 12.0:
        ap.error(f"--lanes must lie within [0, 12] m, got {args.lanes:g}")
    if args.length < 16.0:
        ap.error(f"--length must be >= 16, got {args.length:g}")
    check_run_options(ap, args)
    clearances = args.ompl_clearances
    have_ompl = cov.availability(OMPL_NAME) is None
    t0 = time.perf_counter()
    load = f"{os.getloadavg()[0]:.1f}"
    rows: dict[str, dict[str, list[dict[str, Any]]]] = {}
    for w in widths:
        m = street(w, args.length, args.lanes)
        rows[f"{w:g}"] = planner_rows(
            m, f"width {w:g} m", args.seeds, args.max_time, args.ompl_time, have_ompl,
            clearances=clearances,
        )
    payload = {
        "command": command("street_turns.py", argv),
        "length": args.length, "lanes": args.lanes, "seeds": args.seeds, "max_time": args.max_time,
        "ompl_time": args.ompl_time, "ompl_clearances": list(clearances), "load": load,
        "machine": machine(),
        "wall_time_s": time.perf_counter() - t0, "rows": rows,
    }  # fmt: skip
    print(write_results(args.out, "street_turns", payload, report))
    return 0


if __name__ == "__main__":
    from results_io import run_main

    raise SystemExit(run_main(main))
