"""Hybrid A* with continuous curvature (``curve="clothoid"``, the default) against exact arcs.

Usage::

    python experiments/hybrid_curve.py --count 30 --reverse --out results/hybrid_curve

The random goal and start poses of ``experiments/random_goals.py`` on ``parking_lot``
(``--count`` of each, seed 1) are planned by ``hybrid-a-star`` with both settings of
``HybridConfig.curve`` under the same expansion budget (``--expansions``) and a
generous wall-clock cap (``--cap``, only a safety cap), so the outcome is decided by
the budget and compares across machines: solved, expansions, goal connections tried
(a connection whose ramped segments collide or cannot be closed is rejected and the
search goes on), length and the largest sharpness per gear segment. Writes
``OUT/hybrid_curve.json`` and ``.md``.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import statistics
import sys
from pathlib import Path as FsPath
from typing import Any

import numpy as np

sys.path.insert(0, str(FsPath(__file__).resolve().parent))
from random_goals import draw_goals  # noqa: E402
from results_io import command, json_text, out_folder  # noqa: E402

from rrtdrive.atomic import write_text_atomic  # noqa: E402
from rrtdrive.cli_args import positive_float, positive_int
from rrtdrive.maps import builtin_map  # noqa: E402
from rrtdrive.planning import PlanningProblem, make_planner  # noqa: E402
from rrtdrive.planning.smoothing import max_sharpness  # noqa: E402
from rrtdrive.types import Budget  # noqa: E402
from rrtdrive.verify import verify_path  # noqa: E402

CURVES = ("clothoid", "arcs")


def run(vary: str, pose: tuple[float, float, float], curve: str, args: argparse.Namespace) -> dict:
    """One query with one curve setting."""
    from rrtdrive.types import Pose

    m = dataclasses.replace(builtin_map("parking_lot"), **{vary: Pose(*pose)})
    problem = dataclasses.replace(PlanningProblem.from_map(m), reverse=args.reverse)
    budget = Budget(max_iterations=args.expansions, max_time_s=args.cap)
    res = make_planner("hybrid-a-star", curve=curve).solve(
        problem, np.random.default_rng(0), budget
    )
    row: dict[str, Any] = {
        "status": res.status.value,
        "solved": res.success,
        "expansions": res.stats.get("expansions"),
        "connections": res.stats.get("connections"),
        "time_s": res.planning_time_s,
    }
    if res.success:
        sharp = max_sharpness(res.path.samples, problem.vehicle.wheelbase)
        row.update(
            length_m=res.path.length,
            max_sharpness=sharp if math.isfinite(sharp) else "inf",
            cusps=len(res.path.cusps),
            collision_free=bool(verify_path(m, res.path).collision_free),
        )
    return row


def _median(vals: list[float]) -> float | None:
    return statistics.median(vals) if vals else None


def _num(v: float | None, digits: int) -> str:
    if v is None:
        return "-"
    return "inf" if v == math.inf else f"{v:.{digits}f}"


def main(argv: list[str] | None = None) -> int:

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--count", type=positive_int, default=30,
                    help="random goal poses and start poses each (default: %(default)s)")
    ap.add_argument("--reverse", action="store_true",
                    help="plan with gear changes allowed (default: forward only)")
    ap.add_argument("--expansions", type=positive_int, default=20000,
                    help="expansion budget per plan (default: %(default)s)")
    ap.add_argument("--cap", type=positive_float, default=120.0,
                    help="wall-clock safety cap [s] (default: %(default)s)")
    ap.add_argument("--out", type=out_folder, default="results/hybrid_curve",
                    help="directory for hybrid_curve.json and .md (default: %(default)s)")
    args = ap.parse_args(argv)
    rows = []
    for vary in ("goal", "start"):
        for index, pose in enumerate(draw_goals("parking_lot", args.count, 1, vary)):
            for curve in CURVES:
                r = run(vary, pose.as_tuple(), curve, args)
                rows.append({"vary": vary, "index": index, "curve": curve, **r})
                print(f"{vary} {index} {curve}: {r['status']} {r['expansions']}", file=sys.stderr)
    lines = [
        "# Hybrid A*: continuous curvature (clothoid) against exact arcs",
        "",
        f"Command: `{command('hybrid_curve.py', argv)}`  ",
        f"parking_lot, {args.count} random goals and starts (seed 1), "
        f"{'with' if args.reverse else 'without'} reverse, {args.expansions} expansions, "
        f"{args.cap:g} s safety cap.",
        "",
        "| set | curve | solved | collision-free | timeouts | median expansions (solved) "
        "| median connections | median length [m] | max sharpness [rad/m] |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    summary = {}
    for vary in ("goal", "start"):
        for curve in CURVES:
            rs = [r for r in rows if r["vary"] == vary and r["curve"] == curve]
            ok = [r for r in rs if r["solved"]]
            sharp = [math.inf if r["max_sharpness"] == "inf" else r["max_sharpness"] for r in ok]
            c = {
                "queries": len(rs),
                "solved": len(ok),
                "collision_free": sum(r["collision_free"] for r in ok),
                "timeouts": sum(r["status"] == "timeout" for r in rs),
                "median_expansions": _median([r["expansions"] for r in ok]),
                "median_connections": _median([r["connections"] for r in ok]),
                "median_length_m": _median([r["length_m"] for r in ok]),
                "max_sharpness": (max(sharp) if sharp else None),
            }
            summary[f"{vary}/{curve}"] = c
            top = c["max_sharpness"]
            lines.append(
                f"| {vary}s | {curve} | {c['solved']}/{c['queries']} | {c['collision_free']} | "
                f"{c['timeouts']} | {c['median_expansions']} | {c['median_connections']} | "
                f"{_num(c['median_length_m'], 2)} | {_num(top, 3)} |"
            )
    both = {}
    for vary in ("goal", "start"):
        pairs = {}
        for r in rows:
            if r["vary"] == vary:
                pairs.setdefault(r["index"], {})[r["curve"]] = r
        common = [p for p in pairs.values() if p["clothoid"]["solved"] and p["arcs"]["solved"]]
        ratio = _median([p["clothoid"]["length_m"] / p["arcs"]["length_m"] for p in common])
        both[vary] = {"both_solved": len(common), "median_length_ratio": ratio}
        lines.append("")
        lines.append(
            f"{vary}s solved by both: {len(common)}; median length ratio clothoid / arcs "
            f"{_num(ratio, 4)}."
        )
    out = FsPath(args.out)
    out.mkdir(parents=True, exist_ok=True)
    payload = {
        "command": command("hybrid_curve.py", argv), "args": vars(args),
        "summary": summary, "both": both, "rows": rows,
    }
    for s in summary.values():
        if s["max_sharpness"] == math.inf:
            s["max_sharpness"] = "inf"
    write_text_atomic(out / "hybrid_curve.json", json_text(payload))
    text = "\n".join(lines) + "\n"
    write_text_atomic(out / "hybrid_curve.md", text)
    print(text)
    return 0


if __name__ == "__main__":
    from results_io import run_main

    raise SystemExit(run_main(main))
