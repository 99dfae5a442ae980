"""Hybrid A* on the random goal (or start) poses of ``random_goals.py``, forward or reversing.

Usage::

    python experiments/random_goals_hybrid.py --vary goal --out results
    python experiments/random_goals_hybrid.py --vary start --reverse --out results

The same seeded poses as ``experiments/random_goals.py`` (``draw_goals``), planned
with ``hybrid-a-star`` (``--reverse``: ``PlanningProblem(..., reverse=True)``).
Budget: ``--max-expansions`` expansions, ``--max-time`` seconds as a safety cap.
Every solved path is checked per gear segment by the independent
:func:`rrtdrive.verify.verify_path` (a reverse segment as the forward drive of
the same geometry, rows reversed), with the exact start, goal and cusp poses.
Writes ``OUT/hybrid_random_{goals,starts}_MAP[_reverse].json`` and ``.md``.
"""

from __future__ import annotations

import argparse
import collections
import dataclasses
import statistics
import sys
from pathlib import Path as FsPath

import numpy as np
from random_goals import add_pose_set_options, draw_goals

from rrtdrive.cli_args import flags_for, positive_float, positive_int
from rrtdrive.maps import Map, builtin_map, write_text_atomic
from rrtdrive.planning.base import PlanningProblem
from rrtdrive.planning.hybrid import HybridAStar
from rrtdrive.types import Budget, Path, Pose
from rrtdrive.verify import verify_path


def verify_gears(m: Map, path: Path) -> bool:
    """Each gear segment passes :func:`verify_path` between its own end poses."""
    s = path.samples
    if len(s) < 2 or not (
        np.allclose(s[0, :3], m.start.as_tuple()) and np.allclose(s[-1, :3], m.goal.as_tuple())
    ):
        return False
    for a, b in path.segments():
        seg = s[a:b] if s[a, 4] > 0 else s[a:b][::-1]
        sub = dataclasses.replace(m, start=Pose(*seg[0, :3]), goal=Pose(*seg[-1, :3]))
        if not verify_path(sub, Path(seg[:, :4], np.zeros((0, 2)))).ok:
            return False
    return True


def main(argv: list[str] | None = None) -> int:
    from results_io import json_text, out_folder  # the sibling module (run as a script)

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    add_pose_set_options(ap)
    ap.add_argument("--reverse", action="store_true",
                    help="plan with gear changes allowed (default: forward only)")
    ap.add_argument("--max-expansions", type=positive_int, default=20_000,
                    help="expansion budget per plan (default: %(default)s)")
    ap.add_argument("--max-time", type=positive_float, default=10.0,
                    help="wall-clock safety cap per plan [s] (default: %(default)s)")
    ap.add_argument("--out", type=out_folder, default="results",
                    help="directory for hybrid_random_{goals,starts}_MAP[_reverse].json and "
                    ".md (default: %(default)s)")
    args = ap.parse_args(argv)
    with flags_for({"map": "--map"}):
        base = builtin_map(args.map)
    budget = Budget(max_iterations=args.max_expansions, max_time_s=args.max_time)
    planner = HybridAStar()
    rows = []
    for k, pose in enumerate(draw_goals(args.map, args.goals, args.seed, args.vary)):
        m = dataclasses.replace(base, **{args.vary: pose})
        res = planner.solve(
            PlanningProblem.from_map(m, reverse=args.reverse), np.random.default_rng(0), budget
        )
        rows.append({
            args.vary: pose.as_tuple(),
            "status": res.status.value,
            "verified": bool(res.success and verify_gears(m, res.path)),
            "time_s": res.planning_time_s,
            "setup_s": res.setup_time_s,
            "expansions": res.iterations,
            "length_m": res.path.length if res.success else None,
            "cusps": len(res.path.cusps) if res.success else None,
        })  # fmt: skip
        print(f"{args.vary} {k + 1}/{args.goals}", file=sys.stderr, end="\r")
    print(file=sys.stderr)
    solved = [r for r in rows if r["status"] == "solved"]
    summary = {
        "queries": len(rows),
        "solved": len(solved),
        "verified": sum(r["verified"] for r in rows),
        "statuses": dict(collections.Counter(r["status"] for r in rows)),
        "median_time_solved_s": statistics.median(r["time_s"] for r in solved) if solved else None,
        "median_length_solved_m": (
            statistics.median(r["length_m"] for r in solved) if solved else None
        ),
        "median_expansions_solved": (
            statistics.median(r["expansions"] for r in solved) if solved else None
        ),
        "median_time_failed_s": (
            statistics.median(r["time_s"] for r in rows if r["status"] != "solved")
            if len(solved) < len(rows)
            else None
        ),
        "with_cusps": sum(1 for r in solved if r["cusps"]),
    }
    command = "python experiments/random_goals_hybrid.py " + " ".join(
        sys.argv[1:] if argv is None else argv
    )
    out = FsPath(args.out)
    out.mkdir(parents=True, exist_ok=True)
    stem = f"hybrid_random_{args.vary}s_{args.map}" + ("_reverse" if args.reverse else "")
    record = {
        "command": command, "map": args.map, "seed": args.seed, "vary": args.vary,
        "reverse": args.reverse, "budget": dataclasses.asdict(budget),
        "config": repr(planner.config), "summary": summary, "rows": rows,
    }  # fmt: skip
    write_text_atomic(out / f"{stem}.json", json_text(record))
    s = summary
    fmt = lambda v, f: "-" if v is None else format(v, f)  # noqa: E731
    lines = [
        f"# Hybrid A* on random {args.vary} poses of `{args.map}` "
        f"({'with reverse' if args.reverse else 'forward only'})",
        "",
        f"Command: `{command}`  ",
        f"{s['queries']} poses of `random_goals.py` (seed {args.seed}); budget "
        f"{args.max_expansions} expansions, {args.max_time:g} s cap; every solved path checked "
        "per gear segment by `verify_path`.",
        "",
        "| solved | verified | with cusps | median time solved [ms] | median length [m] "
        "| median expansions | median time failed [s] | statuses |",
        "|---|---|---|---|---|---|---|---|",
        f"| {s['solved']}/{s['queries']} | {s['verified']} | {s['with_cusps']} "
        f"| {fmt(s['median_time_solved_s'] and 1e3 * s['median_time_solved_s'], '.1f')} "
        f"| {fmt(s['median_length_solved_m'], '.1f')} | {fmt(s['median_expansions_solved'], 'g')} "
        f"| {fmt(s['median_time_failed_s'], '.2f')} | "
        + ", ".join(f"{k} {v}" for k, v in sorted(s["statuses"].items()))
        + " |",
    ]
    write_text_atomic(out / f"{stem}.md", "\n".join(lines) + "\n")
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    from results_io import run_main

    raise SystemExit(run_main(main))
