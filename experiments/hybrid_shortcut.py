"""Hybrid A* with and without shortcuts (``HybridConfig.shortcut_tries``), query by query.

Usage::

    python experiments/hybrid_shortcut.py --tries 40 --out results/hybrid_shortcut

On the 100 random goal poses and the 100 random start poses of
``experiments/coverage.py`` (``parking_lot``, seed 1), each planned by
``hybrid-a-star`` with reverse, once with ``shortcut_tries=0`` (the default) and once
with ``--tries``, alternating, twice each in this process: per query the path
lengths, the least CPU time of each setting's ``solve`` calls, whether the independent check passes
and the sharpness of the shortened path. Writes ``OUT/hybrid_shortcut.{json,md}``:
the median and mean length ratio (with / without) and the median CPU ratio per set.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import platform
import statistics
import sys
import time
from pathlib import Path as FsPath
from typing import Any

import numpy as np

sys.path.insert(0, str(FsPath(__file__).resolve().parent))
import coverage as cov  # noqa: E402  (the sibling script)

from rrtdrive.atomic import write_text_atomic  # noqa: E402
from rrtdrive.cli_args import positive_int  # noqa: E402
from rrtdrive.planning import make_planner  # noqa: E402
from rrtdrive.planning.smoothing import max_sharpness  # noqa: E402
from rrtdrive.types import Budget  # noqa: E402
from rrtdrive.verify import verify_path  # noqa: E402


def run_query(vary: str, index: int, pose: tuple, tries: int) -> dict[str, Any]:
    """One query without and with shortcuts: lengths, CPU times, checks."""
    m, problem = cov._problem({"map": "parking_lot", "vary": vary, "index": index, "pose": pose})
    problem = dataclasses.replace(problem, reverse=True)
    out: dict[str, Any] = {"vary": vary, "index": index}
    # Twice each, alternating, the least CPU time kept: the first solve of a query
    # also fills the per-process caches (the goal's field) that later ones reuse.
    cpus: dict[str, float] = {}
    for key, n in (("without", 0), ("with", tries)) * 2:
        planner = make_planner("hybrid-a-star", shortcut_tries=n)
        cpu = time.process_time()
        res = planner.solve(problem, np.random.default_rng(0), Budget(max_time_s=60.0))
        cpus[key] = min(cpus.get(key, float("inf")), time.process_time() - cpu)
        out[key] = {
            "status": res.status.value, "cpu_s": cpus[key],
            "length_m": res.path.length if res.success else None,
            "verified": bool(res.success and verify_path(m, res.path).ok),
            "max_sharpness": (float(max_sharpness(res.path.samples, problem.vehicle.wheelbase))
                              if res.success else None),
        }  # fmt: skip
    return out


def summarise(rows: list[dict[str, Any]]) -> dict[str, Any]:
    """Per set: both solved, median / mean length ratio, median CPU ratio, shortened count."""
    out: dict[str, Any] = {}
    for vary in ("goal", "start"):
        both = [r for r in rows if r["vary"] == vary
                and r["without"]["length_m"] and r["with"]["length_m"]]  # fmt: skip
        ratio = [r["with"]["length_m"] / r["without"]["length_m"] for r in both]
        cpu = [r["with"]["cpu_s"] / r["without"]["cpu_s"] for r in both]
        out[vary] = {
            "queries": sum(r["vary"] == vary for r in rows), "both_solved": len(both),
            "verified_with": sum(r["with"]["verified"] for r in both),
            "shortened": sum(x < 1.0 - 1e-9 for x in ratio),
            "longer": sum(x > 1.0 + 1e-9 for x in ratio),
            "median_length_ratio": statistics.median(ratio) if ratio else None,
            "mean_length_ratio": float(np.mean(ratio)) if ratio else None,
            "min_length_ratio": min(ratio) if ratio else None,
            "median_cpu_ratio": statistics.median(cpu) if cpu else None,
            "max_sharpness_with": max((r["with"]["max_sharpness"] for r in both), default=None),
        }  # fmt: skip
    return out


def report(payload: dict[str, Any]) -> str:
    """The results page."""
    lines = [
        "# Hybrid A* shortcuts: with and without, per query", "",
        f"Command: `{payload['command']}`  ",
        f"{payload['machine']}; wall time {payload['wall_time_s'] / 60:.1f} min; "
        f"`hybrid-a-star` with reverse, `shortcut_tries` 0 against {payload['tries']}, "
        "the least CPU time of two `solve` calls each, alternating.", "",
        "| set | both solved | verified (with) | shortened | longer | median length ratio "
        "| mean | least | median CPU ratio | max sharpness (with) [rad/m] |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]  # fmt: skip
    for vary, s in payload["summary"].items():
        lines.append(
            f"| {vary}s | {s['both_solved']}/{s['queries']} | {s['verified_with']} | "
            f"{s['shortened']} | {s['longer']} | {s['median_length_ratio']:.4f} | "
            f"{s['mean_length_ratio']:.4f} | {s['min_length_ratio']:.3f} | "
            f"{s['median_cpu_ratio']:.3f} | {s['max_sharpness_with']:.3f} |"
        )
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    from results_io import json_text, out_folder  # the sibling module (run as a script)

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--tries", type=positive_int, default=40,
                    help="shortcut_tries of the 'with' runs (default: %(default)s)")
    ap.add_argument("--count", type=positive_int, default=100, help="poses per set (default 100)")
    ap.add_argument("--out", type=out_folder, default="results/hybrid_shortcut",
                    help="directory for hybrid_shortcut.json and .md (default: %(default)s)")
    args = ap.parse_args(argv)
    if args.tries < 1 or not 1 <= args.count <= 100:
        ap.error("--tries must be >= 1 and --count within 1..100")
    t0 = time.perf_counter()
    rows = []
    for vary in ("goal", "start"):
        for index, pose in enumerate(cov.draw_goals("parking_lot", 100, 1, vary)[: args.count]):
            rows.append(run_query(vary, index, pose.as_tuple(), args.tries))
            print(f"\r{vary} {index + 1}/{args.count}", end="", file=sys.stderr, flush=True)
    print(file=sys.stderr)
    payload = {
        "command": "python experiments/hybrid_shortcut.py "
        + " ".join(sys.argv[1:] if argv is None else argv),
        "tries": args.tries,
        "machine": f"{platform.machine()} {os.cpu_count()} CPUs, "
        f"Python {platform.python_version()}",
        "wall_time_s": time.perf_counter() - t0, "summary": summarise(rows), "rows": rows,
    }  # fmt: skip
    out = FsPath(args.out)
    out.mkdir(parents=True, exist_ok=True)
    write_text_atomic(out / "hybrid_shortcut.json", json_text(payload))
    text = report(payload)
    write_text_atomic(out / "hybrid_shortcut.md", text)
    print(text)
    return 0


if __name__ == "__main__":
    from results_io import run_main

    raise SystemExit(run_main(main))
