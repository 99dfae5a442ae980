"""Why a forward-only random query that OMPL's Dubins RRT solves is not solved by ours.

Usage (OMPL lives in the lead's venv only; without it the OMPL rows are skipped)::

    python experiments/forward_misses.py --query start:81 --out results/forward_misses
    python experiments/forward_misses.py --seed 2 --count 400 --variants default \\
        --query goal:21,start:75 --out results/forward_misses_seed2

For random queries of ``experiments/coverage.py`` (``parking_lot``; the set of
``--seed``, default 1, with ``--count`` poses, default 100) it measures, in one run:

- OMPL's Dubins RRT path (as ``coverage.py`` plans it: our exact body test as validity
  checker, 10 s, simplified, interpolated every 0.1 m; ``--ompl-clearance`` the body
  clearance its states keep, ``--ompl-tries`` the seeds tried): its length, its least body
  clearance (``CollisionChecker.body_clearance``) and where, and the largest
  curvature jump between its arcs (it has no steering-rate bound);
- ``hybrid-a-star`` forward only under settings that drop our guarantees one by one:
  the default; keeping no clearance (``body_clearance=0, min_clearance=0``) with 11
  steering curvatures and 200 goal connections; the same with exact arcs
  (``curve=arcs``: curvature jumps where arcs meet, no sharpness bound); exact arcs
  keeping 0.05 m. Each with a counted budget of ``--expansions``.

Writes ``OUT/forward_misses.{json,md}``.
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time
from pathlib import Path as FsPath
from typing import Any

import numpy as np

sys.path.insert(0, str(FsPath(__file__).resolve().parent))
import coverage as cov  # noqa: E402  (the sibling script)

from rrtdrive.atomic import write_text_atomic  # noqa: E402
from rrtdrive.cli_args import positive_float, positive_int  # noqa: E402
from rrtdrive.planning import make_planner  # noqa: E402
from rrtdrive.planning.smoothing import max_sharpness  # noqa: E402
from rrtdrive.types import Budget  # noqa: E402
from rrtdrive.verify import verify_path  # noqa: E402

#: Short names of :data:`VARIANTS` for ``--variants``.
SHORT = {
    "default": "default",
    "no-clearance": "no clearance, 11 curvatures, 200 connections",
    "no-clearance-arcs": "no clearance, exact arcs (no sharpness bound)",
    "arcs-0.05": "0.05 m clearance, exact arcs (no sharpness bound)",
    "full-lock-0.05": "0.05 m clearance, full lock (radius 1.0 / kappa_max)",
    "arcs-full-lock-0.05": "0.05 m clearance, full lock, exact arcs",
    "fine-full-lock-0.05": "0.05 m clearance, full lock, 0.2 m / 1.5 deg grid, 0.5 m steps",
    "fine-arcs-full-lock-0.05": "0.05 m clearance, full lock, exact arcs, 0.2 m / 1.5 deg grid",
    "fine-full-lock-0": "no clearance, full lock, 0.2 m / 1.5 deg grid, 0.5 m steps",
}
#: Our planner's settings, from the default to none of the guarantees but the body's.
VARIANTS = {
    "default": "",
    "no clearance, 11 curvatures, 200 connections": (
        "body_clearance=0:min_clearance=0:curvatures=11:max_solutions=200:coarse_after=0"
    ),
    "no clearance, exact arcs (no sharpness bound)": (
        "body_clearance=0:min_clearance=0:curvatures=11:curve=arcs:coarse_after=0"
    ),
    "0.05 m clearance, exact arcs (no sharpness bound)": (
        "body_clearance=0.05:min_clearance=0.05:curvatures=11:curve=arcs:coarse_after=0"
    ),
    # Session 22: every search turning as tight as OMPL's Dubins curves (the default's
    # last resorts do since), with the ramps; then without them.
    "0.05 m clearance, full lock (radius 1.0 / kappa_max)": (
        "body_clearance=0.05:min_clearance=0.05:coarse_after=0:radius_factor=1.0"
    ),
    "0.05 m clearance, full lock, exact arcs": (
        "body_clearance=0.05:min_clearance=0.05:curvatures=11:curve=arcs:coarse_after=0:"
        "radius_factor=1.0"
    ),
    # Session 37: the same with ramps on a finer grid (refined once: 0.1 m / 0.75 deg).
    "0.05 m clearance, full lock, 0.2 m / 1.5 deg grid, 0.5 m steps": (
        "body_clearance=0.05:min_clearance=0.05:coarse_after=0:radius_factor=1.0:"
        "xy_resolution=0.2:yaw_resolution=0.026179938779914945:step=0.5:curvatures=9"
    ),
    # Session 38: the fine grid without the ramps (is the sharpness bound what stops
    # it?), and with the ramps but no clearance (is the 0.05 m?).
    "0.05 m clearance, full lock, exact arcs, 0.2 m / 1.5 deg grid": (
        "body_clearance=0.05:min_clearance=0.05:coarse_after=0:radius_factor=1.0:curve=arcs:"
        "xy_resolution=0.2:yaw_resolution=0.026179938779914945:step=0.5:curvatures=11"
    ),
    "no clearance, full lock, 0.2 m / 1.5 deg grid, 0.5 m steps": (
        "body_clearance=0:min_clearance=0:coarse_after=0:radius_factor=1.0:"
        "xy_resolution=0.2:yaw_resolution=0.026179938779914945:step=0.5:curvatures=9"
    ),
}


def _item(query: str, seed: int = 1, count: int = 100) -> dict[str, Any]:
    """The coverage item of ``goal:N`` / ``start:N`` (a ValueError naming --query else).

    ``seed`` and ``count``: the random set's, as ``coverage.py --seed --count`` draws it.
    """
    vary, _, index = query.partition(":")
    if vary not in ("goal", "start") or not index.isdigit() or not 0 <= int(index) < count:
        raise ValueError(
            f"--query: expected goal:N or start:N with N in 0..{count - 1}, got {query!r}"
        )
    i = int(index)
    pose = cov.draw_goals("parking_lot", count, seed, vary)[i]
    return {"map": "parking_lot", "vary": vary, "index": i, "pose": pose.as_tuple()}


def ompl_row(
    item: dict[str, Any], seconds: float, clearance: float = 0.0, tries: int = 1
) -> dict[str, Any] | None:
    """OMPL's Dubins RRT on the query, as coverage.py runs it, with its path's figures.

    ``clearance``: what OMPL's states must keep (coverage.py's ``ompl-dubins-rrt@0.05m``);
    ``tries``: OMPL seeds tried (coverage.py's, then + 1000, + 2000, ...) until one
    solves; the row says how many were tried and which solved.
    """
    if cov.availability("ompl-dubins-rrt") is not None:
        return None
    m, problem = cov._problem(item)
    spent = 0.0
    for k in range(tries):
        index = item["index"] + 1000 * k
        solve_s, _, length, path = cov.solve_ompl(
            problem, index, "ompl-dubins-rrt", seconds, clearance, cap_at_ends=clearance > 0
        )
        spent += solve_s
        if path is not None:
            break
    if path is None:
        return {"solved": False, "time_s": spent, "tries": tries, "clearance_m": clearance}
    states = path.samples[:, :3]  # forward only: Dubins curves have no cusps
    clear = np.array([problem.checker.body_clearance(p) for p in states])
    ds = np.hypot(*np.diff(states[:, :2], axis=0).T)
    kappa = np.diff(np.unwrap(states[:, 2])) / np.where(ds > 0, ds, np.inf)
    worst = int(np.argmin(clear))
    return {
        "solved": True, "time_s": spent, "length_m": length, "ompl_seed_index": index,
        "min_clearance_m": float(clear[worst]),
        "min_clearance_at": [round(float(v), 3) for v in states[worst]],
        "max_curvature_jump": float(np.max(np.abs(np.diff(kappa)))),
        "clearance_m": clearance, "tries": k + 1,
        # The independent check at the clearance OMPL kept, sharpness aside (it has none).
        "verified_but_sharpness": verify_path(m, path, clearance=clearance).ok,
    }  # fmt: skip


def ours_row(item: dict[str, Any], options: str, expansions: int) -> dict[str, Any]:
    """``hybrid-a-star`` forward only with ``options`` (coverage.py's ``field=value:...``)."""
    m, problem = cov._problem(item)
    t0 = time.perf_counter()
    res = make_planner("hybrid-a-star", **cov._options(options)).solve(
        problem, np.random.default_rng(0), Budget(max_iterations=expansions, max_time_s=600.0)
    )
    row: dict[str, Any] = {
        "options": options, "status": res.status.value, "solved": res.success,
        "time_s": time.perf_counter() - t0, "expansions": res.iterations,
        "message": res.message,
    }  # fmt: skip
    if res.success:
        clear = np.array([problem.checker.body_clearance(p) for p in res.path.samples[:, :3]])
        row.update(
            length_m=res.path.length, min_clearance_m=float(clear.min()),
            max_sharpness=float(max_sharpness(res.path.samples, problem.vehicle.wheelbase)),
            verified=bool(verify_path(m, res.path).ok),
        )  # fmt: skip
    return row


def report(payload: dict[str, Any]) -> str:
    """The results page: a summary row per query, then each query's section."""
    queries = payload.get("queries") or [payload]  # pages before --query took a list
    names = ", ".join(q["query"] for q in queries)
    lines = [
        f"# Forward-only {'query' if len(queries) == 1 else 'queries'} {names}: what it takes",
        "", f"Command: `{payload['command']}`  ",
        f"{payload['machine']}; wall time {payload['wall_time_s']:.0f} s; random set seed "
        f"{payload.get('seed', 1)}, {payload.get('count', 100)} poses.", "",
    ]  # fmt: skip
    if len(queries) > 1:
        names = list(queries[0]["ours"])
        lines += [
            "| query | OMPL Dubins RRT [m] | its least body clearance [m] | "
            + " | ".join(f"ours: {n}" for n in names) + " |",
            "|---|---|---|" + "---|" * len(names),
        ]
        for q in queries:
            o = q["ompl"]
            length = f"{o['length_m']:.1f}" if o and o["solved"] else "-"
            clear = f"{o['min_clearance_m']:.4f}" if o and o["solved"] else "-"
            ours = " | ".join(q["ours"][n]["status"] for n in names)
            lines.append(f"| {q['query']} | {length} | {clear} | {ours} |")
        lines.append("")
    for k, q in enumerate(queries):
        if len(queries) > 1:
            lines += ([""] if k else []) + [f"## {q['query']}", ""]
        lines += _query_lines(q, payload["expansions"])
    return "\n".join(lines) + "\n"


def _kept(ompl: dict[str, Any]) -> str:
    """What OMPL's states kept, for its line (nothing said for 0 m, the default)."""
    kept = ompl.get("clearance_m", 0.0)
    return f" keeping {kept:g} m" if kept else ""


def _query_lines(payload: dict[str, Any], expansions: int) -> list[str]:
    """One query's OMPL line, our settings' table and messages."""
    lines: list[str] = []
    o = payload["ompl"]
    if o is None:
        lines.append("OMPL: not installed, skipped.")
    elif not o["solved"]:
        lines.append(
            f"OMPL Dubins RRT{_kept(o)}: no path in {o['time_s']:.1f} s"
            f" ({o.get('tries', 1)} seed(s))."
        )
    else:
        lines.append(
            f"OMPL Dubins RRT{_kept(o)}: {o['length_m']:.1f} m in {o['time_s']:.2f} s "
            f"(try {o.get('tries', 1)}, seed index {o.get('ompl_seed_index', '-')}, the time "
            "of every try); least body "
            f"clearance **{o['min_clearance_m']:.4f} m** at pose {o['min_clearance_at']}; "
            f"largest curvature jump between its arcs {o['max_curvature_jump']:.3f} 1/m "
            "(no steering-rate bound); `rrtdrive.verify` at that clearance, sharpness aside: "
            + ("passes." if o.get("verified_but_sharpness") else "fails.")
        )
    lines += [
        "", f"`hybrid-a-star` forward only, {expansions} expansions:", "",
        "| settings | status | expansions | length [m] | least clearance [m] | max sharpness "
        "[rad/m] | verified |",
        "|---|---|---|---|---|---|---|",
    ]  # fmt: skip
    for name, r in payload["ours"].items():
        if r["solved"]:
            cells = (f"{r['length_m']:.1f}", f"{r['min_clearance_m']:.3f}",
                     f"{r['max_sharpness']:.3g}", "yes" if r["verified"] else "no")
        else:
            cells = ("-", "-", "-", "-")
        lines.append(f"| {name} | {r['status']} | {r['expansions']} | " + " | ".join(cells) + " |")
    lines += ["", "Messages:", ""]
    lines += [f"- {name}: {r['message']}" for name, r in payload["ours"].items()]
    return lines


def main(argv: list[str] | None = None) -> int:
    from results_io import json_text, out_folder  # the sibling module (run as a script)

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--query", default="start:81",
                    help="goal:N or start:N, comma-separated (default start:81)")
    ap.add_argument("--seed", type=int, default=1, help="the random set's seed (default 1)")
    ap.add_argument("--count", type=positive_int, default=100, help="poses per set (default 100)")
    ap.add_argument("--variants", default=",".join(SHORT),
                    help="our settings to run, comma-separated (default: all of "
                    f"{', '.join(SHORT)})")
    ap.add_argument("--expansions", type=positive_int, default=20000,
                    help="our counted budget (default: %(default)s)")
    ap.add_argument("--ompl-time", type=positive_float, default=10.0,
                    help="OMPL's time cap [s] (default: %(default)s)")
    ap.add_argument("--ompl-clearance", type=float, default=0.0,
                    help="body clearance OMPL's states keep, metres, 0-1 (default: 0)")
    ap.add_argument("--ompl-tries", type=positive_int, default=1,
                    help="OMPL seeds tried until one solves (default: %(default)s)")
    ap.add_argument("--out", type=out_folder, default="results/forward_misses",
                    help="directory for forward_misses.json and .md (default: %(default)s)")
    args = ap.parse_args(argv)  # fmt: skip
    if args.expansions < 1 or args.ompl_time <= 0 or args.count < 1:
        ap.error("--expansions and --count must be >= 1 and --ompl-time > 0")
    if not 0.0 <= args.ompl_clearance <= 1.0:
        ap.error(f"--ompl-clearance: expected metres in 0-1, got {args.ompl_clearance}")
    variants = [v for v in args.variants.split(",") if v]
    unknown = [v for v in variants if v not in SHORT]
    if unknown or not variants:
        ap.error(f"--variants: unknown {unknown}; choose from {list(SHORT)}")
    variants = [SHORT[v] for v in variants]
    try:
        items = [(q, _item(q, args.seed, args.count)) for q in args.query.split(",") if q]
    except ValueError as err:
        ap.error(str(err))
    t0 = time.perf_counter()
    queries = []
    for query, item in items:
        print(f"{query}: OMPL ...", file=sys.stderr, flush=True)
        ompl = ompl_row(item, args.ompl_time, args.ompl_clearance, args.ompl_tries)
        ours = {}
        for name in variants:
            print(f"{query}: {name} ...", file=sys.stderr, flush=True)
            ours[name] = ours_row(item, VARIANTS[name], args.expansions)
        queries.append({"query": query, "ompl": ompl, "ours": ours})
    payload = {
        "command": "python experiments/forward_misses.py "
        + " ".join(sys.argv[1:] if argv is None else argv),
        "seed": args.seed, "count": args.count, "expansions": args.expansions,
        "machine": f"{platform.machine()} {os.cpu_count()} CPUs, "
        f"Python {platform.python_version()}",
        "wall_time_s": time.perf_counter() - t0, "queries": queries,
    }  # fmt: skip
    out = FsPath(args.out)
    out.mkdir(parents=True, exist_ok=True)
    write_text_atomic(out / "forward_misses.json", json_text(payload))
    text = report(payload)
    write_text_atomic(out / "forward_misses.md", text)
    print(text)
    return 0


if __name__ == "__main__":
    from results_io import run_main

    raise SystemExit(run_main(main))
