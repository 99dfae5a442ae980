"""When does each root of the default planner's tree pairs first grow? (``root_patience``)

Usage::

    python experiments/root_growth.py --out results/root_growth_s18
    python experiments/root_growth.py --count 10 --seeds 2 --out /tmp/rg   # a quick look

Each query is planned by ``improved-rrt-connect`` with ``root_patience=0`` (every pair
of trees grows for the stages' whole share, as before session 17) and a counted budget
(20 000 iterations, a 1e6 s wall-clock cap). Every call of the growth
(:func:`rrtdrive.planning.improved.growth.grow_until_meet`, one per pair of trees) is
watched through its ``expired`` callback, which the growth calls once per iteration:
the iteration of the pair at which its start tree, and its goal tree, first held more
than its root. The queries: ``parking_lot`` with the ``--count`` random goal and start
poses of :func:`random_goals.draw_goals` (seed 1), and every built-in map with planner
seeds ``0 .. --seeds - 1``; each forward-only and with reverse.

Writes ``OUT/root_growth.{json,md}``: per pair whether it met, each root's first growth
and the pair's iterations; the pairs that failed with a root that never grew (per
map); for the pairs that met, the latest iteration at which their last root grew, which
is what a ``root_patience`` must exceed to change no pair that meets.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import sys
from collections.abc import Sequence
from pathlib import Path as FsPath

import numpy as np

HERE = FsPath(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from results_io import command, machine, out_folder, write_results  # noqa: E402

from rrtdrive.bench.backends import episode_progress  # noqa: E402
from rrtdrive.cli_args import positive_int  # noqa: E402
from rrtdrive.maps import BUILTIN_MAPS, builtin_map  # noqa: E402
from rrtdrive.planning import PlanningProblem  # noqa: E402
from rrtdrive.planning.improved import ImprovedConfig, ImprovedRRTConnect  # noqa: E402
from rrtdrive.planning.improved import planner as improved_planner  # noqa: E402
from rrtdrive.types import Budget  # noqa: E402

BUDGET = Budget(max_iterations=20_000, max_time_s=1e6)


def queries(
    count: int, seeds: int, maps: Sequence[str] | None = None
) -> list[tuple[str, PlanningProblem, int]]:
    """``(id, problem, planner seed)`` of every query, both gears (``maps``: default all)."""
    from random_goals import draw_goals

    out = []
    for gear in ("fwd", "rev"):
        rev = gear == "rev"
        for vary in ("goal", "start"):
            for i, pose in enumerate(draw_goals("parking_lot", count, 1, vary)):
                m = dataclasses.replace(builtin_map("parking_lot"), **{vary: pose})
                out.append((f"{vary}:{gear}:{i}", PlanningProblem.from_map(m, reverse=rev), 0))
        for name in BUILTIN_MAPS if maps is None else maps:
            problem = PlanningProblem.from_map(builtin_map(name), reverse=rev)
            out.extend((f"{name}:{gear}:{s}", problem, s) for s in range(seeds))
    return out


def watch_pairs(qid: str, pairs: list[dict], grow):  # noqa: ANN001, ANN201 - the growth
    """``grow`` (``grow_until_meet``) recording, per call, when each root first grew."""

    def watched(ts, tg, *args, iterations: int, expired, **kw):  # noqa: ANN001, ANN202
        first = iterations
        seen = {"start": None, "goal": None}
        count = [iterations]

        def probe() -> bool:
            # Called before each iteration: the trees as the previous iterations left them.
            for end, tree in (("start", ts), ("goal", tg)):
                if seen[end] is None and tree.size > 1:
                    seen[end] = count[0] - first
            count[0] += 1
            return expired()

        found, used = grow(ts, tg, *args, iterations=iterations, expired=probe, **kw)
        for end, tree in (("start", ts), ("goal", tg)):
            if seen[end] is None and tree.size > 1:
                seen[end] = used - first
        pairs.append({
            "query": qid, "met": found is not None, "iterations": used - first,
            "start_grew": seen["start"], "goal_grew": seen["goal"],
        })  # fmt: skip
        return found, used

    return watched


def run(count: int, seeds: int, maps: Sequence[str] | None = None) -> list[dict]:
    """Every pair of every query (``maps``: the built-in maps planned, default all)."""
    pairs: list[dict] = []
    planner = ImprovedRRTConnect(ImprovedConfig(root_patience=0))
    original = improved_planner.grow_until_meet
    try:
        todo = queries(count, seeds, maps)
        progress = episode_progress(every=20)
        for i, (qid, problem, seed) in enumerate(todo, 1):
            improved_planner.grow_until_meet = watch_pairs(qid, pairs, original)
            planner.solve(problem, np.random.default_rng(seed), BUDGET)
            progress(i, len(todo))
        print(file=sys.stderr)
    finally:
        improved_planner.grow_until_meet = original
    return pairs


def summarise(pairs: list[dict]) -> dict:
    """Failed pairs with a root that never grew; the latest last-root growth of a pair that met."""
    failed = [p for p in pairs if not p["met"]]
    stuck = [p for p in failed if p["start_grew"] is None or p["goal_grew"] is None]
    per_map: dict[str, int] = {}
    for p in stuck:
        where = p["query"].split(":")[0]
        key = where if where in BUILTIN_MAPS else f"parking_lot random {where}"
        per_map[key] = per_map.get(key, 0) + 1
    met = [p for p in pairs if p["met"]]
    last = [max(p["start_grew"], p["goal_grew"]) for p in met]
    latest = max(met, key=lambda p: max(p["start_grew"], p["goal_grew"]), default=None)
    return {
        "pairs": len(pairs),
        "failed": len(failed),
        "failed_root_never_grew": len(stuck),
        "failed_root_never_grew_by_map": dict(sorted(per_map.items())),
        "failed_iterations_median": float(np.median([p["iterations"] for p in failed]))
        if failed else math.nan,
        "met": len(met),
        "met_last_root_grew_max": max(last, default=None),
        "met_last_root_grew_max_query": latest["query"] if latest else None,
        "met_last_root_grew_p99": float(np.percentile(last, 99)) if last else math.nan,
        "met_last_root_grew_over": {
            str(k): sum(v > k for v in last) for k in (1000, 2000, 3000, 4000)
        },
    }  # fmt: skip


def markdown(payload: dict) -> str:
    """The page: the counts of :func:`summarise`."""
    meta, s = payload["meta"], payload["summary"]
    lines = [
        "# When the default planner's tree roots first grow",
        "",
        f"Command: `{meta['command']}`  ",
        f"{meta['machine']}.  ",
        f"{meta['queries']} queries (`parking_lot` random goals and starts, {meta['count']} "
        f"each; every built-in map x planner seeds 0..{meta['seeds'] - 1}; forward and "
        "reverse), `improved-rrt-connect` with `root_patience=0`, 20 000 iterations.",
        "",
        "| pairs of trees | met | failed | failed with a root that never grew "
        "| median iterations of a failed pair |",
        "|---|---|---|---|---|",
        f"| {s['pairs']} | {s['met']} | {s['failed']} | {s['failed_root_never_grew']} "
        f"| {s['failed_iterations_median']:.0f} |",
        "",
        "Failed pairs whose root never grew, by map: "
        + ", ".join(f"{k} {v}" for k, v in s["failed_root_never_grew_by_map"].items())
        + ".",
        "",
        f"Pairs that met: their last root first grew at iteration {s['met_last_root_grew_max']} "
        f"of the pair at the latest ({s['met_last_root_grew_max_query']}); 99th percentile "
        f"{s['met_last_root_grew_p99']:.0f}; pairs later than 1000 / 2000 / 3000 / 4000: "
        + " / ".join(str(v) for v in s["met_last_root_grew_over"].values())
        + ".",
        "",
    ]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--count", type=positive_int, default=100,
                    help="random goals and starts each (default: %(default)s)")
    ap.add_argument("--seeds", type=positive_int, default=20,
                    help="planner seeds per built-in map (default: %(default)s)")
    ap.add_argument("--maps", default=None,
                    help="comma-separated built-in maps planned (default: all of them)")
    ap.add_argument("--out", type=out_folder, required=True,
                    help="directory for root_growth.{json,md}")
    args = ap.parse_args(argv)
    maps = None if args.maps is None else [m.strip() for m in args.maps.split(",") if m.strip()]
    unknown = sorted(set(maps or ()) - set(BUILTIN_MAPS))
    if unknown:
        ap.error(f"--maps: unknown map(s) {', '.join(unknown)}; choose from {sorted(BUILTIN_MAPS)}")
    if args.count < 0 or args.seeds < 0:
        ap.error("--count and --seeds must be >= 0")
    pairs = run(args.count, args.seeds, maps)
    s = summarise(pairs)
    meta = {
        "command": command("root_growth.py", argv),
        "machine": machine(),
        "count": args.count,
        "seeds": args.seeds,
        "maps": maps,
        "queries": len(queries(args.count, args.seeds, maps)),
    }
    payload = {"meta": meta, "summary": s, "pairs": pairs}
    print(write_results(args.out, "root_growth", payload, markdown))
    return 0


if __name__ == "__main__":
    from results_io import run_main

    raise SystemExit(run_main(main))
