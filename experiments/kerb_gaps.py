"""Parallel parking into kerbside gaps of several lengths: ours with reverse against OMPL's.

Usage (OMPL lives in the lead's venv only; without it its rows are skipped)::

    python experiments/kerb_gaps.py --out results/kerb_gaps

The built-in ``kerbside`` map (:func:`rrtdrive.tight_maps.kerbside_map`) with its gap
``F`` car lengths long, for each ``F`` of ``--factors``: cars parked along the kerb, the
goal parallel-parked in the gap 0.3 m from its rear car and ``--kerb-offset`` (0.3 m)
from the kerb; with ``--positions``, moved along the gap (0 is 0.3 m from its rear car,
1 is 0.3 m from its front car). For each factor, position and seed (``--seeds``), in one
run: the default planner and ``hybrid-a-star``, both with ``reverse``, on the counted 20
000-iteration budget (``--max-time`` is the cap), and OMPL's Reeds-Shepp RRTConnect with
our exact body test as validity checker (``--ompl-time``; once per clearance of
``--ompl-clearances``, default 0 and 0.15 m), as ``experiments/street_turns.py`` plans
them; every path judged by ``verify_path`` with the 0.2 rad/m sharpness bound
(``verified``) and without it (``any sharpness``). Our rows also give the body clearance
the returned path's search kept (``stats["body_clearance_m"]``: 0.15 usually, less after
the snug or tight search).

Writes ``OUT/kerb_gaps.{json,md}``.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import sys
import time
from typing import Any

sys.path.insert(0, os.path.dirname(__file__))
import coverage as cov  # noqa: E402  (the sibling scripts)
import street_turns as st  # noqa: E402
from results_io import numbers_above, write_results  # noqa: E402

from rrtdrive.tight_maps import KERB_OFFSET, KERB_REAR_ROOM, kerbside_map  # noqa: E402
from rrtdrive.types import VehicleParams  # noqa: E402

KERB_CAR = VehicleParams()

GEARED = ("improved-rrt-connect", "hybrid-a-star")


def report(payload: dict[str, Any]) -> str:
    """The markdown page of a payload."""
    lines = [
        *st.page_header(
            payload,
            "Parallel parking into kerbside gaps: ours with reverse and OMPL's RS RRTConnect",
            "The `kerbside` map with its gap F car lengths (4.3 m) long",
        ),
        "| gap [car lengths] (@ goal position) | planner | solved | verified | any sharpness "
        "| median time [ms] | median length [m] | median cusps | clearance kept [m] | outcomes |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for factor, by_planner in payload["rows"].items():
        for planner, rows in by_planner.items():
            outcomes: dict[str, int] = {}
            for r in rows:
                key = r.get("status", "solved" if r["solved"] else "no_path_in_budget")
                outcomes[key] = outcomes.get(key, 0) + 1
            cells = [
                *st.row_cells(rows),
                st.median_cell(rows, "clearance_m", fmt="{:.2f}"),
                ", ".join(f"{k} {v}" for k, v in sorted(outcomes.items())),
            ]
            lines.append(f"| {factor} | {planner} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--factors", default="1.3,1.4,1.5,1.6,1.8,2.0,2.5",
                    help="gap lengths in car lengths (default 1.3,...,2.5)")  # fmt: skip
    ap.add_argument("--kerb-offset", type=float, default=KERB_OFFSET,
                    help=f"the parked cars' and the goal's distance from the kerb, m "
                         f"(default {KERB_OFFSET:g})")  # fmt: skip
    ap.add_argument("--positions", default="0",
                    help="where in the gap the goal sits, 0 (0.3 m from the rear car) to 1 "
                         "(0.3 m from the front car); comma-separated (default 0)")  # fmt: skip
    st.add_run_options(ap, "gap", "results/kerb_gaps")
    args = ap.parse_args(argv)
    try:
        factors = numbers_above(args.factors, "--factors", floor=1.0)
        positions = numbers_above(args.positions, "--positions", floor=-1e-12)
    except ValueError as err:
        ap.error(str(err))
    if not 0.0 <= args.kerb_offset <= 1.0:
        ap.error(f"--kerb-offset: must lie in [0, 1] m, got {args.kerb_offset:g}")
    if any(p > 1.0 for p in positions):
        ap.error(f"--positions: each must lie in [0, 1], got {args.positions!r}")
    st.check_run_options(ap, args)
    have_ompl = cov.availability(st.OMPL_NAME) is None
    t0 = time.perf_counter()
    load = f"{os.getloadavg()[0]:.1f}"
    rows: dict[str, dict[str, list[dict[str, Any]]]] = {}
    for f in factors:
        for p in positions:
            m = kerbside_map(f, args.kerb_offset)
            # The goal's free travel along the gap: 0.3 m from either car.
            travel = f * KERB_CAR.length - KERB_CAR.length - 2 * KERB_REAR_ROOM
            m = dataclasses.replace(m, goal=dataclasses.replace(m.goal, x=m.goal.x + p * travel))
            key = f"{f:g}" if positions == [0.0] else f"{f:g} @ {p:g}"
            rows[key] = st.planner_rows(
                m, f"gap {key}", args.seeds, args.max_time, args.ompl_time,
                have_ompl, GEARED, args.ompl_clearances,
            )  # fmt: skip
    payload = st.run_payload("kerb_gaps.py", argv, args, load, t0, rows)
    print(write_results(args.out, "kerb_gaps", payload, report))
    return 0


if __name__ == "__main__":
    from results_io import run_main

    raise SystemExit(run_main(main))
