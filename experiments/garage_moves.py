"""Everyday garage moves at several aisle widths: ours with reverse against OMPL's RS RRTConnect.

Usage (OMPL lives in the lead's venv only; without it its rows are skipped)::

    python experiments/garage_moves.py --out results/garage_moves

The built-in ``garage`` (:func:`rrtdrive.tight_maps.garage_map`: two rows of 2.6 m bays,
5.5 m deep, parked cars 0.4 m from each neighbour) with its aisle ``A`` metres wide, for
each ``A`` of ``--aisles``, and four moves a driver makes there:

- ``leave east``: from nose-in in bay (0, 9), out into the aisle's right-hand lane facing east;
- ``leave west``: the same, into the other lane facing west;
- ``bay to bay``: from nose-in in bay (0, 9) to nose-in in bay (1, 11) across the aisle;
- ``tail in``: from the aisle's west end into bay (0, 5), reversing in.

For each move and seed (``--seeds``), in one run: the default planner and
``hybrid-a-star``, both with ``reverse``, on the counted 20 000-iteration budget
(``--max-time`` is the cap), and OMPL's Reeds-Shepp RRTConnect with our exact body test
as validity checker (``--ompl-time``; once per body clearance of ``--ompl-clearances``,
default 0 and 0.15 m), as ``experiments/street_turns.py`` plans them;
every path judged by ``verify_path`` with the 0.2 rad/m sharpness bound (``verified``)
and without it (``any sharpness``).

Writes ``OUT/garage_moves.{json,md}``.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from typing import Any

sys.path.insert(0, os.path.dirname(__file__))
import coverage as cov  # noqa: E402  (the sibling scripts)
import street_turns as st  # noqa: E402
from results_io import numbers_above, write_results  # noqa: E402

from rrtdrive.maps import Map  # noqa: E402
from rrtdrive.tight_maps import GARAGE_BAY_DEPTH, garage_goal, garage_map  # noqa: E402
from rrtdrive.types import Pose  # noqa: E402

MOVES = ("leave east", "leave west", "bay to bay", "tail in")


def move_map(aisle: float, move: str) -> Map:
    """The garage with an ``aisle`` m aisle and the start and goal of ``move``."""
    base = garage_map(aisle)
    parked = garage_goal(0, 9, aisle)
    if move == "leave east":
        start, goal = parked, Pose(base.bounds[2] - 4.0, GARAGE_BAY_DEPTH + aisle / 4, 0.0)
    elif move == "leave west":
        start, goal = parked, Pose(4.0, GARAGE_BAY_DEPTH + 3 * aisle / 4, math.pi)
    elif move == "bay to bay":
        start, goal = parked, garage_goal(1, 11, aisle)
    elif move == "tail in":
        start, goal = base.start, garage_goal(0, 5, aisle, tail_in=True)
    else:
        raise ValueError(f"unknown move {move!r}; moves are {MOVES}")
    name = f"{base.name}_{move.replace(' ', '_')}"
    return Map(name, base.bounds, base.obstacles, start, goal)


def report(payload: dict[str, Any]) -> str:
    """The markdown page of a payload."""
    lines = [
        *st.page_header(
            payload,
            "Everyday garage moves: ours with reverse and OMPL's RS RRTConnect",
            "The `garage` map (2.6 m bays, 5.5 m deep) with its aisle A m wide",
        ),
        "| aisle [m] | move | planner | solved | verified | any sharpness | median time [ms] | "
        "median length [m] | median cusps | least clearance [m] |",
        "|---|---|---|---|---|---|---|---|---|---|",
        *st.clearance_table_rows(payload),
    ]
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--aisles", default="9,7,6", help="aisle widths, m (default 9,7,6)")
    ap.add_argument("--moves", default=",".join(MOVES), help=f"moves (default all: {MOVES})")
    st.add_run_options(ap, "move", "results/garage_moves")
    args = ap.parse_args(argv)
    try:
        aisles = numbers_above(args.aisles, "--aisles", floor=4.0)
    except ValueError as err:
        ap.error(str(err))
    moves = [m.strip() for m in args.moves.split(",") if m.strip()]
    unknown = [m for m in moves if m not in MOVES]
    if unknown or not moves:
        ap.error(f"--moves: unknown {unknown}; choose from {', '.join(MOVES)}")
    st.check_run_options(ap, args)
    have_ompl = cov.availability(st.OMPL_NAME) is None
    t0 = time.perf_counter()
    load = f"{os.getloadavg()[0]:.1f}"
    rows: dict[str, dict[str, list[dict[str, Any]]]] = {}
    for aisle in aisles:
        for move in moves:
            rows[f"{aisle:g}|{move}"] = st.planner_rows(
                move_map(aisle, move), f"aisle {aisle:g} m, {move}", args.seeds,
                args.max_time, args.ompl_time, have_ompl, clearances=args.ompl_clearances,
            )  # fmt: skip
    payload = st.run_payload("garage_moves.py", argv, args, load, t0, rows)
    print(write_results(args.out, "garage_moves", payload, report))
    return 0


if __name__ == "__main__":
    from results_io import run_main

    raise SystemExit(run_main(main))
