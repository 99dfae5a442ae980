"""Hybrid A* with and without the stretch-at-a-time ramp fit, side by side.

Usage::

    python experiments/bench_ramp_chunks.py --out results/bench_ramp_chunks_s39

When a gear segment's whole ramp fit fails, Hybrid A* fits it again a stretch at a time
(``HybridConfig.ramp_chunks``, session 39; docs/planning.md, "A long segment a stretch
at a time"). This script plans random box maps (``--sides``, metres; boxes at the
density of 200 per 200 x 200 m; ``--seeds`` maps each; the start and goal in opposite
corners) forward and with reverse, with ``ramp_chunks`` on and off alternately in one
process (CPU time of each query; the first query of a map pays its set-up, so each
map's queries run after one untimed warm-up query), checks every path with
``rrtdrive.verify.verify_path`` (sharpness bound 0.2 rad/m + 0.005, the plan's body
clearance less 2 mm) and counts solved queries, expansions and lengths. Writes
``OUT/bench_ramp_chunks.{json,md}``.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path as FsPath
from typing import Any

import numpy as np
from results_io import cell, command, machine, numbers_above, out_folder, run_main, write_results

sys.path.insert(0, str(FsPath(__file__).resolve().parents[1] / "src"))

from box_maps import box_map  # noqa: E402  (after src/ joins the path, as rrtdrive)

from rrtdrive.cli_args import positive_int  # noqa: E402
from rrtdrive.planning import PlanningProblem, make_planner  # noqa: E402
from rrtdrive.types import Budget  # noqa: E402
from rrtdrive.verify import verify_path  # noqa: E402

#: Boxes per square metre (200 on a 200 m square).
DENSITY = 200 / 200.0**2


def _solve(problem: PlanningProblem, chunks: bool, iterations: int) -> dict[str, Any]:
    planner = make_planner("hybrid-a-star", ramp_chunks=chunks)
    t0 = time.process_time()
    res = planner.solve(problem, np.random.default_rng(0), Budget(max_iterations=iterations))
    took = time.process_time() - t0
    verified = None
    if res.success:
        keep = res.stats.get("body_clearance_m")
        check = verify_path(
            problem.map, res.path, max_sharpness=0.205,
            clearance=0.0 if keep is None else max(0.0, keep - 0.002),
        )  # fmt: skip
        verified = bool(check.ok)
    return {
        "status": res.status.value,
        "solved": res.success,
        "expansions": res.iterations,
        "length_m": res.path.length if res.success else None,
        "cpu_s": took,
        "verified": verified,
    }


def run(side: float, seed: int, reverse: bool, iterations: int) -> dict[str, Any]:
    """One query with the stretch fit on and off (off first, then on)."""
    m = box_map(side, round(DENSITY * side * side), seed, name=f"boxes_{side:g}_s{seed}")
    problem = PlanningProblem.from_map(m, reverse=reverse)
    _solve(problem, True, 200)  # the map's set-up, untimed
    off, on = _solve(problem, False, iterations), _solve(problem, True, iterations)
    return {"map": m.name, "side": side, "seed": seed, "reverse": reverse, "off": off, "on": on}


def _answer(x: dict[str, Any]) -> tuple[Any, ...]:
    """What a query answered: status, expansions, length."""
    return x["status"], x["expansions"], x["length_m"]


def _median(values: list[float]) -> float | None:
    return statistics.median(values) if values else None


def report(payload: dict[str, Any]) -> str:
    """The results page: per side and gear, then the queries whose answer changed."""
    lines = [
        "# Hybrid A*: ramps fitted a stretch at a time (on) against the whole fit alone (off)",
        "",
        f"Command: `{payload['command']}`  ",
        f"{payload['machine']}; {payload['iterations']} expansions per query; CPU time per "
        "query in one process (off, then on); `verified`: `verify_path` with the sharpness "
        "bound and the plan's clearance.",
        "",
        "| side [m] | gear | queries | solved off / on | verified off / on | lost | "
        "expansions off / on (sum) | median CPU ratio on / off | changed answers | "
        "shorter / longer |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    groups: dict[tuple[float, bool], list[dict[str, Any]]] = {}
    for r in payload["rows"]:
        groups.setdefault((r["side"], r["reverse"]), []).append(r)
    for (side, reverse), rows in sorted(groups.items()):
        off = [r["off"] for r in rows]
        on = [r["on"] for r in rows]
        changed = [r for r in rows if _answer(r["off"]) != _answer(r["on"])]
        both = [r for r in changed if r["off"]["solved"] and r["on"]["solved"]]
        shorter = sum(r["on"]["length_m"] < r["off"]["length_m"] for r in both)
        longer = sum(r["on"]["length_m"] > r["off"]["length_m"] for r in both)
        lost = sum(r["off"]["solved"] and not r["on"]["solved"] for r in rows)
        ratio = _median([b["cpu_s"] / a["cpu_s"] for a, b in zip(off, on, strict=True)])
        lines.append(
            f"| {side:g} | {'reverse' if reverse else 'forward'} | {len(rows)} | "
            f"{sum(x['solved'] for x in off)} / {sum(x['solved'] for x in on)} | "
            f"{sum(bool(x['verified']) for x in off)} / {sum(bool(x['verified']) for x in on)} | "
            f"{lost} | {sum(x['expansions'] for x in off)} / {sum(x['expansions'] for x in on)} | "
            f"{cell(ratio, 1, 2)} | {len(changed)} | {shorter} / {longer} |"
        )
    lines += ["", "Changed answers:", "", "| map | gear | off | on |", "|---|---|---|---|"]
    for r in payload["rows"]:
        a, b = r["off"], r["on"]
        if _answer(a) == _answer(b):
            continue

        def said(x: dict[str, Any]) -> str:
            length = "" if x["length_m"] is None else f", {x['length_m']:.1f} m"
            return f"{x['status']}, {x['expansions']} exp{length}, {x['cpu_s']:.2f} s"

        gear = "reverse" if r["reverse"] else "forward"
        lines.append(f"| {r['map']} | {gear} | {said(a)} | {said(b)} |")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument(
        "--sides",
        default="100,200,300",
        help="map sides, metres, comma-separated (default 100,200,300)",
    )
    p.add_argument("--seeds", type=positive_int, default=6, help="maps per side (default 6)")
    p.add_argument(
        "--iterations",
        type=positive_int,
        default=20_000,
        help="Hybrid A* expansions per query (default 20000, the default budget)",
    )
    p.add_argument(
        "--out",
        type=out_folder,
        default="results/bench_ramp_chunks",
        help="folder for bench_ramp_chunks.{json,md} (default results/bench_ramp_chunks)",
    )
    args = p.parse_args(argv)
    try:
        sides = numbers_above(args.sides, "--sides", floor=40.0)
    except ValueError as exc:
        p.error(str(exc))
    rows = []
    for side in sides:
        for seed in range(args.seeds):
            for reverse in (False, True):
                print(f"{side:g} m seed {seed} reverse {reverse} ...", file=sys.stderr, flush=True)
                rows.append(run(side, seed, reverse, args.iterations))
    payload = {
        "command": command("bench_ramp_chunks.py", argv),
        "machine": machine(),
        "iterations": args.iterations,
        "rows": rows,
    }
    print(write_results(args.out, "bench_ramp_chunks", payload, report))
    broken = [r for r in rows for k in ("off", "on") if r[k]["solved"] and not r[k]["verified"]]
    return 1 if broken else 0


if __name__ == "__main__":
    sys.exit(run_main(main))
