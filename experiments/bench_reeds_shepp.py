"""Time per call of the Reeds-Shepp functions over random pose pairs.

Usage::

    python experiments/bench_reeds_shepp.py --pairs 1000 --repeats 5 --radius 6 --seed 0

A planner that reverses calls these thousands of times per query (heuristic and
analytic expansion), so their cost per call matters. For ``--pairs`` seeded random
start/goal pairs (starts uniform in a 60 m square, goals either anywhere in it or
within 3 turning radii of the start, half each; headings uniform) the script times

* ``reeds_shepp_paths`` (all candidates, sorted, checked, as path objects);
* ``shortest_reeds_shepp``;
* ``reeds_shepp_distance`` (the length only);
* ``ReedsSheppPath.sample(0.1)`` of the shortest path;
* ``ReedsSheppTable.distance`` (trilinear lookup in the table of
  ``planning/reeds_shepp_table.py``, exact outside it; built before timing, its build
  time and its error against the exact length over the pairs reported);
* OMPL's ``ReedsSheppStateSpace.distance`` when ``ompl`` imports (a reference).

Each function runs over all pairs ``--repeats`` times; the mean per call is reported
for every repeat, with their minimum (the least disturbed by other processes on a
shared machine), in wall-clock and CPU time. The lengths are also checked against
OMPL's (largest difference reported). Writes ``OUT/reeds_shepp.json``.
"""

from __future__ import annotations

import argparse
import json
import math
import platform
import sys
import time
from collections.abc import Callable
from pathlib import Path as FsPath

import numpy as np

from rrtdrive.atomic import write_text_atomic
from rrtdrive.cli_args import int_at_least, positive_int
from rrtdrive.planning.reeds_shepp import (
    reeds_shepp_distance,
    reeds_shepp_paths,
    shortest_reeds_shepp,
)
from rrtdrive.planning.reeds_shepp_table import ReedsSheppTable
from rrtdrive.types import Pose


def random_pairs(n: int, radius: float, seed: int) -> list[tuple[Pose, Pose]]:
    """``n`` start/goal pairs: half with the goal anywhere, half within 3 radii."""
    rng = np.random.default_rng(seed)
    pairs = []
    for i in range(n):
        start = Pose(*rng.uniform(0.0, 60.0, 2), rng.uniform(-math.pi, math.pi))
        if i % 2:
            gx, gy = start.x + rng.uniform(-3, 3) * radius, start.y + rng.uniform(-3, 3) * radius
        else:
            gx, gy = rng.uniform(0.0, 60.0, 2)
        pairs.append((start, Pose(gx, gy, rng.uniform(-math.pi, math.pi))))
    return pairs


def time_calls(fn: Callable[..., object], calls: list[tuple], repeats: int) -> dict[str, object]:
    """Mean time of ``fn(*args)`` per call for each repeat (wall clock, CPU) and the minima."""
    wall, cpu = [], []
    for _ in range(repeats):
        w0, c0 = time.perf_counter(), time.process_time()
        for args in calls:
            fn(*args)
        wall.append((time.perf_counter() - w0) / len(calls))
        cpu.append((time.process_time() - c0) / len(calls))
    return {
        "wall_mean_us_per_repeat": [round(t * 1e6, 2) for t in wall],
        "cpu_mean_us_per_repeat": [round(t * 1e6, 2) for t in cpu],
        "wall_mean_us_best": round(min(wall) * 1e6, 2),
        "cpu_mean_us_best": round(min(cpu) * 1e6, 2),
    }


def _ompl_distance(radius: float) -> Callable[[Pose, Pose], float] | None:
    try:
        from ompl import base as ob
    except ImportError:
        return None
    space = ob.ReedsSheppStateSpace(radius)
    sa, sb = space.allocState(), space.allocState()

    def distance(a: Pose, b: Pose) -> float:
        sa.setX(a.x), sa.setY(a.y), sa.setYaw(a.yaw)
        sb.setX(b.x), sb.setY(b.y), sb.setYaw(b.yaw)
        return space.distance(sa, sb)

    return distance


def main(argv: list[str] | None = None) -> int:
    """Run the benchmark; return 0, or 1 when a length differs from OMPL's by > 1e-6."""
    from results_io import json_text, out_folder  # the sibling module (run as a script)

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--pairs", type=positive_int, default=1000,
                    help="random start/goal pose pairs, >= 1 (default: %(default)s)")
    ap.add_argument("--repeats", type=positive_int, default=5,
                    help="timed passes over all pairs per function, >= 1 (default: %(default)s)")
    ap.add_argument("--radius", type=float, default=6.0,
                    help="minimum turning radius [m], > 0 (default: %(default)s)")
    ap.add_argument("--seed", type=int_at_least(0), default=0,
                    help="seed of the random pairs and the table check (default: %(default)s)")
    ap.add_argument("--table-extent", type=float, default=24.0,
                    help="table covers |dx|, |dy| up to this [m] (default: %(default)s)")
    ap.add_argument("--table-resolution", type=float, default=0.5,
                    help="table grid spacing in x and y [m] (default: %(default)s)")
    ap.add_argument("--table-yaw-bins", type=int_at_least(4), default=72,
                    help="table heading bins over 360 degrees, >= 4 (default: %(default)s)")
    ap.add_argument("--out", type=out_folder, default="results",
                    help="directory for reeds_shepp.json (default: %(default)s)")
    args = ap.parse_args(argv)
    if args.pairs < 1 or args.repeats < 1 or not args.radius > 0:
        ap.error("--pairs and --repeats must be >= 1, --radius > 0")
    r = args.radius
    pairs = random_pairs(args.pairs, r, args.seed)
    shortest = [shortest_reeds_shepp(a, b, r) for a, b in pairs]
    funcs: dict[str, Callable[[Pose, Pose], object]] = {
        "reeds_shepp_paths": lambda a, b: reeds_shepp_paths(a, b, r),
        "shortest_reeds_shepp": lambda a, b: shortest_reeds_shepp(a, b, r),
        "reeds_shepp_distance": lambda a, b: reeds_shepp_distance(a, b, r),
    }
    c0 = time.process_time()
    table = ReedsSheppTable.build(
        r, args.table_extent, args.table_resolution, args.table_yaw_bins, seed=args.seed
    )
    table_build_cpu_s = time.process_time() - c0
    funcs["table_distance"] = table.distance
    ompl = _ompl_distance(r)
    if ompl is not None:
        funcs["ompl_distance"] = ompl
    timings = {name: time_calls(fn, pairs, args.repeats) for name, fn in funcs.items()}
    timings["sample_0.1m"] = time_calls(
        lambda p: p.sample(0.1), [(p,) for p in shortest], args.repeats
    )
    candidates = [len(reeds_shepp_paths(a, b, r)) for a, b in pairs]
    checks: dict[str, object] = {
        "candidates_per_pair_mean": round(float(np.mean(candidates)), 3),
        "shortest_with_cusps": sum(p.gear_changes > 0 for p in shortest),
        "ompl": ompl is not None,
    }
    exact = np.array([p.length for p in shortest])
    looked = np.array([table.distance(a, b) for a, b in pairs])
    inside = looked != exact
    err = np.abs(looked - exact)
    checks["table"] = {
        "shape": list(table.values.shape),
        "build_cpu_s": round(table_build_cpu_s, 3),
        "max_error_at_build_m": round(table.max_error, 4),
        "pairs_inside_grid": int(np.sum(inside)),
        "error_inside_mean_m": round(float(err[inside].mean()), 5) if inside.any() else None,
        "error_inside_p99_m": round(float(np.quantile(err[inside], 0.99)), 4)
        if inside.any()
        else None,
        "error_inside_max_m": round(float(err[inside].max()), 4) if inside.any() else None,
    }
    if ompl is not None:
        diff = max(abs(p.length - ompl(a, b)) for p, (a, b) in zip(shortest, pairs, strict=True))
        checks["max_abs_length_diff_vs_ompl_m"] = diff
    given = sys.argv[1:] if argv is None else argv
    report = {
        "meta": {
            "command": "python experiments/bench_reeds_shepp.py " + " ".join(given),
            "config": vars(args),
            "python": platform.python_version(),
            "machine": platform.machine(),
        },
        "timings": timings,
        "checks": checks,
    }
    out = FsPath(args.out)
    out.mkdir(parents=True, exist_ok=True)
    write_text_atomic(out / "reeds_shepp.json", json_text(report))
    for name, t in timings.items():
        print(
            f"{name:22s} mean per call: best {t['wall_mean_us_best']:8.1f} us wall, "
            f"{t['cpu_mean_us_best']:8.1f} us CPU (of {args.repeats} repeats)"
        )
    print(json.dumps(checks))
    return 0 if checks.get("max_abs_length_diff_vs_ompl_m", 0.0) <= 1e-6 else 1


if __name__ == "__main__":
    from results_io import run_main

    raise SystemExit(run_main(main))
