"""Parking in angled bays, with the row's direction and against it: ours with reverse and OMPL's.

Usage (OMPL lives in the lead's venv only; without it its rows are skipped)::

    python experiments/angled_bays.py --out results/angled_bays

A row of :data:`BAYS` bays, 2.6 m wide (across the bay) and 5.5 m deep, at ``A`` degrees
to an aisle ``W`` metres wide above them (each ``A`` of ``--angles``, each ``W`` of
``--aisles``); parked cars (the paper's 4.30 m x 1.80 m) centred in every bay but one.
The car starts at the aisle's west end facing east. ``with``: the goal is nose-in in the
free bay as a driver coming along the aisle turns into it (heading ``-A``); ``against``:
the bay is angled the other way (heading ``A - 180``), so the car must turn round first
(a driver who came the wrong way along a one-way row). For each case and seed
(``--seeds``), in one run: the default planner and ``hybrid-a-star``, both with
``reverse``, and OMPL's Reeds-Shepp RRTConnect with our exact body test (once per body
clearance of ``--ompl-clearances``, default 0 and 0.15 m), as
``experiments/street_turns.py`` plans them; every path judged by ``verify_path`` with
the 0.2 rad/m sharpness bound (``verified``) and without it (``any sharpness``).

Writes ``OUT/angled_bays.{json,md}``.
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

from rrtdrive.maps import Map, Obstacle  # noqa: E402
from rrtdrive.types import Pose, VehicleParams  # noqa: E402

BAYS = 12
FREE_BAY = 6
BAY_WIDTH = 2.6
BAY_DEPTH = 5.5
DIRECTIONS = ("with", "against")
_CAR = VehicleParams()


def angled_map(angle_deg: float, aisle: float, direction: str) -> Map:
    """The row of bays at ``angle_deg`` under an ``aisle`` m aisle; goal in the free bay."""
    if direction not in DIRECTIONS:
        raise ValueError(f"direction: {direction!r}, choose from {DIRECTIONS}")
    a = math.radians(angle_deg)
    yaw = -a if direction == "with" else -(math.pi - a)
    pitch = BAY_WIDTH / math.sin(a)  # bay to bay along the aisle
    back = _CAR.length / 2 - _CAR.rear_overhang  # rear axle behind the car's centre
    obstacles, goal = [], None
    for i in range(BAYS):
        cx, cy = 6.0 + i * pitch, BAY_DEPTH / 2
        if i == FREE_BAY:
            goal = Pose(cx - back * math.cos(yaw), cy - back * math.sin(yaw), yaw)
        else:
            obstacles.append(Obstacle((cx, cy), (_CAR.length, _CAR.width), yaw))
    assert goal is not None
    return Map(
        f"angled_{angle_deg:g}_{direction}_{aisle:g}m",
        (0.0, -1.0, 12.0 + BAYS * pitch, BAY_DEPTH + aisle),
        tuple(obstacles),
        Pose(2.0, BAY_DEPTH + aisle / 2, 0.0),
        goal,
    )


def report(payload: dict[str, Any]) -> str:
    """The markdown page of a payload."""
    lines = [
        *st.page_header(
            payload,
            "Angled bays, with the row's direction and against it: ours with reverse and OMPL's",
            "Bays 2.6 m wide, 5.5 m deep, at the angle to the aisle",
        ),
        "| angle [deg] | direction | aisle [m] | planner | solved | verified | any sharpness "
        "| median time [ms] | median length [m] | median cusps | least clearance [m] |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
        *st.clearance_table_rows(payload),
    ]
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--angles", default="45,60", help="bay angles, deg (default 45,60)")
    ap.add_argument("--aisles", default="4,5,6", help="aisle widths, m (default 4,5,6)")
    st.add_run_options(ap, "case", "results/angled_bays")
    args = ap.parse_args(argv)
    try:
        angles = numbers_above(args.angles, "--angles", floor=20.0)
        aisles = numbers_above(args.aisles, "--aisles", floor=3.0)
    except ValueError as err:
        ap.error(str(err))
    if any(a > 90.0 for a in angles):
        ap.error("--angles must lie within [20, 90] degrees")
    st.check_run_options(ap, args)
    have_ompl = cov.availability(st.OMPL_NAME) is None
    t0 = time.perf_counter()
    load = f"{os.getloadavg()[0]:.1f}"
    rows: dict[str, dict[str, list[dict[str, Any]]]] = {}
    for angle in angles:
        for direction in DIRECTIONS:
            for aisle in aisles:
                rows[f"{angle:g}|{direction}|{aisle:g}"] = st.planner_rows(
                    angled_map(angle, aisle, direction), f"{angle:g} deg {direction}, {aisle:g} m",
                    args.seeds, args.max_time, args.ompl_time, have_ompl,
                    clearances=args.ompl_clearances,
                )  # fmt: skip
    payload = st.run_payload("angled_bays.py", argv, args, load, t0, rows)
    print(write_results(args.out, "angled_bays", payload, report))
    return 0


if __name__ == "__main__":
    from results_io import run_main

    raise SystemExit(run_main(main))
