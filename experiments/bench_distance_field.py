"""The checker's distance field: scipy's transform against ours, side by side.

Usage::

    python experiments/bench_distance_field.py --out results/bench_distance_field_s38

Every collision checker's set-up computes the Euclidean distance field of its occupancy
grid (two checkers per map for the default planner: the map's and the one with the
paper's expanded obstacles). :func:`rrtdrive.collision.distance.distance_field` gives
``scipy.ndimage.distance_transform_edt``'s values bit for bit from scipy's feature
transform, computing the distances a block of rows at a time. This script rasterises
maps as a checker does (``--sizes``: square maps of that side, metres, with ``--boxes``
random boxes, seeded; at the checker's default cell size, coarser where the grid bound
asks), times both ``--repeats`` times, alternating, in one process, measures each one's
peak of traced memory (numpy reports its arrays to ``tracemalloc``) and checks the two
fields are equal. Writes ``OUT/bench_distance_field.{json,md}``.
"""

from __future__ import annotations

import argparse
import sys
import time
import tracemalloc
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

from rrtdrive.cli_args import int_at_least, positive_int  # noqa: E402
from rrtdrive.collision import CheckerConfig  # noqa: E402
from rrtdrive.collision.distance import distance_field  # noqa: E402
from rrtdrive.collision.grid import (  # noqa: E402
    grid_origin,
    grid_resolution,
    grid_shape,
    rasterise,
)


def occupancy(side: float, boxes: int) -> np.ndarray:
    """The free cells of a box map's grid, as a checker with the default config builds it."""
    m = box_map(side, boxes)
    config = CheckerConfig()
    h = grid_resolution(m.bounds, config)
    nx, ny = grid_shape(m.bounds, h, config.pad)
    origin = grid_origin(m.bounds, h, config.pad)
    return ~rasterise(m.bounds, m.obstacles, origin, h, nx, ny)


def _timed(fn: Any, free: np.ndarray) -> tuple[float, float, np.ndarray]:
    tracemalloc.start()
    t0 = time.perf_counter()
    field = fn(free)
    took = time.perf_counter() - t0
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return took, peak, field


def run(side: float, boxes: int, repeats: int) -> dict[str, Any]:
    """Both transforms on one grid, alternating; the least time and peak of each."""
    free = occupancy(side, boxes)
    times: dict[str, list[float]] = {"scipy": [], "ours": []}
    peaks: dict[str, list[float]] = {"scipy": [], "ours": []}
    fields = {}
    for _ in range(repeats):
        for name, fn in (("scipy", ndimage.distance_transform_edt), ("ours", distance_field)):
            took, peak, fields[name] = _timed(fn, free)
            times[name].append(took)
            peaks[name].append(peak)
    return {
        "map": f"{side:g} m, {boxes} boxes",
        "grid": list(free.shape),
        "scipy_s": min(times["scipy"]),
        "ours_s": min(times["ours"]),
        "ratio": min(times["ours"]) / min(times["scipy"]),
        "scipy_peak_mb": min(peaks["scipy"]) / 1e6,
        "ours_peak_mb": min(peaks["ours"]) / 1e6,
        "equal": bool(np.array_equal(fields["scipy"], fields["ours"])),
    }


def report(payload: dict[str, Any]) -> str:
    """The results page."""
    lines = [
        "# The checker's distance field: scipy's transform against ours",
        "",
        f"Command: `{payload['command']}`  ",
        f"{payload['machine']}; {payload['repeats']} alternating rounds per grid in one "
        "process; each figure the least of its rounds; peak: traced memory during the call.",
        "",
        "| map | grid cells | scipy [s] | ours [s] | ours / scipy | scipy peak [MB] "
        "| ours peak [MB] | equal |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for r in payload["rows"]:
        n, m = r["grid"]
        lines.append(
            f"| {r['map']} | {n} x {m} ({n * m / 1e6:.1f} M) | {cell(r['scipy_s'], 1, 2)} | "
            f"{cell(r['ours_s'], 1, 2)} | {cell(r['ratio'], 1, 3)} | "
            f"{cell(r['scipy_peak_mb'], 1, 0)} | {cell(r['ours_peak_mb'], 1, 0)} | "
            f"{'yes' if r['equal'] else '**no**'} |"
        )
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--sizes", default="100,500,1000",
                   help="map sides, metres, comma-separated (default 100,500,1000)")
    p.add_argument("--boxes", type=int_at_least(0), default=5000,
                   help="random boxes on each map (default 5000)")
    p.add_argument("--repeats", type=positive_int, default=2, help="rounds per grid (default 2)")
    p.add_argument("--out", type=out_folder, default="results/bench_distance_field",
                   help="folder for bench_distance_field.{json,md} "
                   "(default results/bench_distance_field)")
    args = p.parse_args(argv)
    try:
        sizes = numbers_above(args.sizes, "--sizes")
    except ValueError as exc:
        p.error(str(exc))
    rows = []
    for side in sizes:
        print(f"{side:g} m ...", file=sys.stderr, flush=True)
        rows.append(run(side, args.boxes, args.repeats))
    payload = {
        "command": command("bench_distance_field.py", argv),
        "machine": machine(),
        "repeats": args.repeats,
        "rows": rows,
    }
    print(write_results(args.out, "bench_distance_field", payload, report))
    return 0 if all(r["equal"] for r in rows) else 1


if __name__ == "__main__":
    sys.exit(run_main(main))
