"""How far every forward drive from a pose gets when the steering rate is bounded.

Usage::

    python experiments/forward_reach.py --query start:81 --out results/forward_reach

A sweep of the forward drives from one pose of ``experiments/coverage.py``'s random
sets (``parking_lot``, seed 1, 100 poses per set), for each steering-rate bound of
``--sharpness`` (rad of steering angle per metre), from the wheels straight or (with
``--turned-wheels``) from any steering angle: every ``--step`` metres each drive
turns its steering angle by ``-s step``, ``0`` or ``+s step`` (clipped at the car's
``delta_max``), the poses in between (every ``step / 4``) are tested with the
planner's exact body test keeping ``--clearance``, and the drives that collide are
dropped. Drives that end in the same ``--cell`` metres square, ``--bin`` degrees
heading bin and steering bin (``delta_max / 20``) are merged. The sweep stops when no
drive is left ("dies after X m": within the sweep's resolution, no forward drive at
that bound gets further) or one has driven ``--distance`` metres ("drove D m": such a
drive exists; it is returned and checked by :func:`rrtdrive.verify.verify_path`'s
sharpness estimate). A layer with more than ``--max-states`` drives keeps an even
subset of them ("capped"): a capped sweep that dies proves less than one that is not.

Merging and the three steering moves make it a sweep at a resolution, not a proof;
``--cell`` shows how much the answer depends on it.

Writes ``OUT/forward_reach.{json,md}``.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from dataclasses import asdict
from typing import Any

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
import coverage as cov  # noqa: E402  (the sibling script)
from forward_misses import _item  # noqa: E402  (the query parser of the sibling script)
from reach_sweep import Reach, sweep  # noqa: E402
from results_io import command, machine, numbers_above, out_folder, write_results  # noqa: E402

from rrtdrive.cli_args import nonneg_float, positive_float, positive_int  # noqa: E402
from rrtdrive.types import Path, Pose  # noqa: E402
from rrtdrive.verify import verify_path  # noqa: E402


def _row(reach: Reach, m: Any) -> dict[str, Any]:
    """A sweep's JSON row; a surviving drive is judged by the independent check."""
    row = {k: v for k, v in asdict(reach).items() if k != "poses"}
    if reach.survived:
        end = Pose(*reach.poses[-1, :3])
        check = verify_path(m.with_query(goal=end), Path(reach.poses, np.zeros((0, 2))))
        row |= {
            "drive_max_sharpness": check.max_discrete_sharpness,
            "drive_collision_free": check.collision_free,
            "drive_curvature_ok": check.curvature_ok,
        }
    return row


def report(payload: dict[str, Any]) -> str:
    """The markdown page of a payload."""
    lines = [
        f"# Forward drives from {payload['query']} at a steering-rate bound",
        "",
        f"Command: `{payload['command']}`  ",
        f"{payload['machine']}; wall time {payload['wall_time_s']:.0f} s. Pose "
        f"{payload['pose']}; body clearance kept {payload['clearance']} m; a step of "
        f"{payload['step']} m; "
        + (
            "starting at any steering angle (turned at rest)."
            if payload.get("turned_wheels")
            else "starting with the wheels straight."
        ),
        "",
        "| steering rate [rad/m] | merge cell [m] | outcome | drives at the peak | capped |",
        "|---|---|---|---|---|",
    ]
    for r in payload["rows"]:
        outcome = (
            f"drove {r['driven_m']:.1f} m: measured rate {r['drive_max_sharpness']:.3f}, "
            f"body clear (shapely) {'yes' if r['drive_collision_free'] else '**no**'}"
            if r["survived"]
            else f"**dies** after {r['driven_m']:.1f} m"
        )
        lines.append(
            f"| {r['sharpness']:g} | {r['cell']:g} | {outcome} | "
            f"{r['peak_states']} | {'yes' if r['capped'] else 'no'} |"
        )
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--query", default="start:81", help="goal:N or start:N (default start:81)")
    ap.add_argument(
        "--sharpness",
        default="0.2,0.4,1,2,5",
        help="steering-rate bounds to sweep, rad/m (default 0.2,0.4,1,2,5)",
    )
    ap.add_argument("--cell", default="0.05",
                    help="merge cells, m, comma-separated (default: %(default)s)")
    ap.add_argument("--clearance", type=nonneg_float, default=0.0, help="body clearance kept, m")
    ap.add_argument("--step", type=positive_float, default=0.2,
                    help="metres between steering moves (default: %(default)s)")
    ap.add_argument("--distance", type=positive_float, default=30.0,
                    help="metres a drive must reach (default: %(default)s)")
    ap.add_argument("--max-states", type=positive_int, default=300_000,
                    help="drives kept per step (default: %(default)s)")
    ap.add_argument(
        "--turned-wheels", action="store_true",
        help="start at any steering angle, lock to lock (the car turns its wheels at rest "
        "before it sets off, as the controllers do); default: wheels straight",
    )  # fmt: skip
    ap.add_argument("--out", type=out_folder, default="results/forward_reach",
                    help="directory for forward_reach.json and .md (default: %(default)s)")
    args = ap.parse_args(argv)
    try:
        sharpness = numbers_above(args.sharpness, "--sharpness")
        cells = numbers_above(args.cell, "--cell")
        item = _item(args.query)
    except ValueError as err:
        ap.error(str(err))
    if args.clearance < 0 or args.step <= 0 or args.distance <= 0 or args.max_states < 1:
        ap.error("--clearance must be >= 0, --step and --distance > 0, --max-states >= 1")
    m, problem = cov._problem(item)
    car = problem.vehicle
    t0 = time.perf_counter()
    rows = []
    for s in sharpness:
        for c in cells:
            print(f"sharpness {s:g} rad/m, cell {c:g} m ...", file=sys.stderr, flush=True)
            reach = sweep(
                problem.checker,
                item["pose"],
                wheelbase=car.wheelbase,
                kappa_max=car.kappa_max,
                sharpness=s,
                clearance=args.clearance,
                step=args.step,
                cell=c,
                distance=args.distance,
                max_states=args.max_states,
                turned_wheels=args.turned_wheels,
            )
            rows.append(_row(reach, m))
    payload = {
        "command": command("forward_reach.py", argv),
        "query": args.query, "pose": [round(v, 4) for v in item["pose"]],
        "clearance": args.clearance, "step": args.step, "turned_wheels": args.turned_wheels,
        "machine": machine(),
        "wall_time_s": time.perf_counter() - t0, "rows": rows,
    }  # fmt: skip
    print(write_results(args.out, "forward_reach", payload, report))
    return 0


if __name__ == "__main__":
    from results_io import run_main

    raise SystemExit(run_main(main))
