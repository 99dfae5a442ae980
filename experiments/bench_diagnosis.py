"""The failure diagnosis on big maps: the pass search, old against new, side by side.

Usage::

    python experiments/bench_diagnosis.py --out results/bench_diagnosis_s38

A failed plan is diagnosed after the planning stopwatch (``diagnosis_time_s`` in the
plan JSON). On a map whose start and goal are joined only through a narrow gap the
diagnosis finds the gap's narrowest place (:func:`rrtdrive.planning.diagnosis.checks.
pass_cell`): until session 38 with two distance transforms of the whole grid, since
then with KD-trees of the two sides' edge cells. This script builds the maps
(``--sizes``: a square map of that side with one wall across it, ``--gap`` metres open
in its middle; a 500 m map with 5 000 boxes and a 1 km map with 50 000, whose goal they
wall off, seeded), diagnoses each query with the old pass search and walled-off check
(kept here as the reference) and the new ones, alternating,
``--repeats`` times in one process, and checks that both give the same diagnosis.
Writes ``OUT/bench_diagnosis.{json,md}``: per map the grid, the least time of each and
the ratio new / old.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path as FsPath
from typing import Any

import numpy as np
from results_io import (
    cell,
    command,
    machine,
    numbers_above,
    out_folder,
    run_main,
    write_results,
)
from scipy import ndimage

sys.path.insert(0, str(FsPath(__file__).resolve().parents[1] / "src"))

from box_maps import box_map  # noqa: E402  (after src/ joins the path, as rrtdrive)

from rrtdrive.cli_args import int_at_least, positive_float, positive_int  # noqa: E402
from rrtdrive.collision import CollisionChecker  # noqa: E402
from rrtdrive.maps import Map, Obstacle  # noqa: E402
from rrtdrive.planning import PlanningProblem  # noqa: E402
from rrtdrive.planning.diagnosis import checks, diagnose  # noqa: E402
from rrtdrive.types import Pose  # noqa: E402


def old_pass_cell(
    grid: np.ndarray, lo: float, hi: float, a: tuple[int, int], b: tuple[int, int]
) -> tuple[int, int]:
    """The pass search before session 38: two whole-grid distance transforms."""
    structure = np.ones((3, 3), dtype=bool)
    low, _ = ndimage.label(grid >= lo, structure=structure)
    high, _ = ndimage.label(grid >= hi, structure=structure)
    band = (low == low[a]) & (high == 0)
    if high[a] == 0 or high[b] == 0 or high[a] == high[b]:
        best = np.unravel_index(int(np.argmax(np.where(band, grid, -np.inf))), grid.shape)
        return int(best[0]), int(best[1])
    to_a = ndimage.distance_transform_edt(high != high[a])
    to_b = ndimage.distance_transform_edt(high != high[b])
    best = np.unravel_index(int(np.argmin(np.where(band, to_a + to_b, np.inf))), grid.shape)
    return int(best[0]), int(best[1])


def old_joined_in_free_space(checker: Any, p: Pose, q: Pose) -> bool:
    """The walled-off check before session 38: free space cut from a union with the edge."""
    import shapely

    polys = [o.polygon() for o in checker.obstacles]
    edge = shapely.box(*checker.bounds).exterior
    shapely.union_all([edge, *[poly.exterior for poly in polys]])  # built with it, unused
    free = shapely.box(*checker.bounds).difference(shapely.union_all([edge, *polys]))
    here, there = shapely.Point(p.x, p.y), shapely.Point(q.x, q.y)
    return any(
        piece.intersects(here) and piece.intersects(there) for piece in shapely.get_parts(free)
    )


def wall_gap_map(side: float, gap: float) -> Map:
    """A ``side`` m square, a 1 m wall across x = side / 2 open ``gap`` m in the middle."""
    half, low = side / 2.0, side / 2.0 - gap / 2.0
    wall = (
        Obstacle((half, low / 2.0), (1.0, low)),
        Obstacle((half, side - low / 2.0), (1.0, low)),
    )
    return Map(f"wall_gap_{side:g}_{gap:g}", (0.0, 0.0, side, side), wall,
               Pose(5.0, 5.0, 0.0), Pose(side - 5.0, side - 5.0, 0.0))  # fmt: skip


def _diagnosis(problem: PlanningProblem) -> tuple[float, Any]:
    t0 = time.perf_counter()
    found = diagnose(problem)
    took = time.perf_counter() - t0
    return took, None if found is None else (found.kind.value, found.message, found.numbers)


def run(m: Map, repeats: int) -> dict[str, Any]:
    """Both pass searches on one map, alternating; the least time of each."""
    new_pass, new_joined = checks.pass_cell, checks.joined_in_free_space
    sides = {"old": (old_pass_cell, old_joined_in_free_space), "new": (new_pass, new_joined)}
    times: dict[str, list[float]] = {"old": [], "new": []}
    answers: dict[str, Any] = {}
    try:
        for _ in range(repeats):
            for name, (pass_fn, joined_fn) in sides.items():
                # A fresh checker each time: the new check shares the map's obstacle union
                # with the exact body test, which a plan would have built already or not.
                problem = PlanningProblem.from_map(m, checker=CollisionChecker.for_map(m))
                checks.pass_cell, checks.joined_in_free_space = pass_fn, joined_fn
                took, answers[name] = _diagnosis(problem)
                times[name].append(took)
    finally:
        checks.pass_cell, checks.joined_in_free_space = new_pass, new_joined
    old, new = min(times["old"]), min(times["new"])
    return {
        "map": m.name,
        "grid": list(problem.checker.clearance_grid.shape),
        "obstacles": len(m.obstacles),
        "old_s": old,
        "new_s": new,
        "ratio": new / old,
        "same": answers["old"] == answers["new"],
        "diagnosis": None if answers["new"] is None else answers["new"][1],
    }


def report(payload: dict[str, Any]) -> str:
    """The results page."""
    lines = [
        "# The failure diagnosis on big maps: pass search, old against new",
        "",
        f"Command: `{payload['command']}`  ",
        f"{payload['machine']}; {payload['repeats']} alternating rounds per map in one "
        "process; each time the least of its rounds (the whole `diagnose` call).",
        "",
        "| map | obstacles | grid cells | old [s] | new [s] | new / old | same diagnosis "
        "| diagnosis |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for r in payload["rows"]:
        n, m = r["grid"]
        lines.append(
            f"| {r['map']} | {r['obstacles']} | {n} x {m} ({n * m / 1e6:.1f} M) | "
            f"{cell(r['old_s'], 1, 2)} | "
            f"{cell(r['new_s'], 1, 2)} | {cell(r['ratio'], 1, 3)} | "
            f"{'yes' if r['same'] else '**no**'} | {r['diagnosis'] or '-'} |"
        )
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--sizes", default="500,2000",
                   help="sides of the wall-gap maps, metres, comma-separated (default 500,2000)")
    p.add_argument("--gap", type=positive_float, default=1.5,
                   help="the wall's opening, metres (default 1.5: narrower than the car)")
    p.add_argument("--boxes", type=int_at_least(0), default=5000,
                   help="boxes on the 500 m box map, 0 for none (default 5000)")
    p.add_argument("--walled-boxes", type=int_at_least(0), default=50000,
                   help="boxes on a 1 km map whose goal they wall off, 0 for none "
                   "(default 50000)")
    p.add_argument("--repeats", type=positive_int, default=2, help="rounds per map (default 2)")
    p.add_argument("--out", type=out_folder, default="results/bench_diagnosis",
                   help="folder for bench_diagnosis.{json,md} (default results/bench_diagnosis)")
    args = p.parse_args(argv)
    if args.gap >= 100.0:
        p.error("--gap: expected less than 100 m (the smallest map's wall)")
    try:
        sizes = numbers_above(args.sizes, "--sizes")
    except ValueError as exc:
        p.error(str(exc))
    maps = [wall_gap_map(s, args.gap) for s in sizes]
    maps += [box_map(500.0, args.boxes)] if args.boxes else []
    maps += [box_map(1000.0, args.walled_boxes)] if args.walled_boxes else []
    rows = []
    for m in maps:
        print(f"{m.name} ...", file=sys.stderr, flush=True)
        rows.append(run(m, args.repeats))
    payload = {
        "command": command("bench_diagnosis.py", argv),
        "machine": machine(),
        "repeats": args.repeats,
        "rows": rows,
    }
    print(write_results(args.out, "bench_diagnosis", payload, report))
    return 0 if all(r["same"] for r in rows) else 1


if __name__ == "__main__":
    sys.exit(run_main(main))
