"""Which plans of the gear scenarios and stock parking-v0 a change of the default's stages alters.

Usage::

    python experiments/stage_order.py --seeds 100 --out results/stage_order \
        --old escalation_first=never:reverse_postprocess_attempts=6

Plans every query twice with ``improved-rrt-connect``, once with the planner options
of ``--old`` (``field=value:...``, as ``experiments/coverage.py``'s ``@`` tail) and
once with ``--new`` (default: none, the current defaults), as the closed loop plans
it: the planner stream of the episode seed (``scenario_rngs``), a counted budget
(20 000 iterations; wall-clock cap 1e6 s, as ``simulate --deterministic``). The
queries: ``parking-reverse-in``, ``parallel-parking`` and ``u-turn`` (reverse, as
their tasks say) and highway-env's own ``parking-v0`` with ``--reverse``
(``map_from_env`` after ``env.reset(seed)``), seeds ``0..--seeds-1`` each.

Writes ``OUT/stage_order.{json,md}``: per query both plans' status, solving stage,
iterations, length, cusps and whether the rows are equal (to 1e-9); per set how many
plans are equal, the stages, and the median planning time of each (wall clock:
compare the two columns of one run only). A seed whose plan changed can be driven
with ``rrtdrive simulate parking-v0 --reverse --seed N --deterministic``.
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import sys
import time
from collections import Counter
from pathlib import Path as FsPath
from typing import Any

import numpy as np

sys.path.insert(0, str(FsPath(__file__).resolve().parent))
from coverage import _options  # noqa: E402  (the "field=value:..." parser)

from rrtdrive.atomic import write_text_atomic  # noqa: E402
from rrtdrive.cli_args import positive_int  # noqa: E402
from rrtdrive.planning import PlanningProblem, make_planner  # noqa: E402
from rrtdrive.planning.hybrid.escalation import stage_of  # noqa: E402
from rrtdrive.sim.scenes import scenario_rngs  # noqa: E402
from rrtdrive.types import Budget, PlanResult  # noqa: E402

SETS = ("parking-reverse-in", "parallel-parking", "u-turn", "parking-v0")


def problem_of(kind: str, seed: int) -> PlanningProblem:
    """The planning problem of one seed of a set, as the closed loop builds it."""
    if kind == "parking-v0":
        from rrtdrive.sim.extract import attach_ego, map_from_env
        from rrtdrive.sim.stock import make_stock_env
        from rrtdrive.types import VehicleParams

        car = VehicleParams()
        env = make_stock_env("parking-v0", 20, vehicle=car)
        try:
            env.reset(seed=seed)
            attach_ego(env, car)
            m = map_from_env(env, vehicle=car, name="parking-v0")
        finally:
            env.close()
        return PlanningProblem.from_map(m, reverse=True)
    from rrtdrive.sim.tasks import make_scenario

    if kind == "parking-reverse-in":
        task = make_scenario("parking", seed, reverse_in=True)
    else:
        task = make_scenario(kind, seed)
    return PlanningProblem.from_map(task.map, reverse=task.reverse)


def plan(problem: PlanningProblem, seed: int, options: dict[str, Any]) -> tuple[PlanResult, float]:
    """The default planner's plan with ``options``, and its wall time."""
    _, rng, _ = scenario_rngs(seed)
    t0 = time.perf_counter()
    res = make_planner("improved-rrt-connect", **options).solve(
        problem, rng, Budget(max_time_s=1e6)
    )
    return res, time.perf_counter() - t0


def _row(res: PlanResult, wall: float) -> dict[str, Any]:
    return {
        "status": res.status.value,
        "stage": stage_of(res) if res.success else None,
        "iterations": int(res.iterations),
        "length_m": float(res.path.length) if res.success else None,
        "cusps": len(res.path.cusps) if res.success else None,
        "time_s": wall,
    }


def _same(a: PlanResult, b: PlanResult) -> bool:
    if a.success != b.success:
        return False
    sa, sb = np.asarray(a.path.samples), np.asarray(b.path.samples)
    return sa.shape == sb.shape and bool(np.all(np.abs(sa - sb) <= 1e-9))


def report(payload: dict[str, Any]) -> str:
    """The markdown page of a run."""
    lines = [
        "# The default planner's plans under two stage settings",
        "",
        f"Command: `{payload['command']}`  ",
        f"old: `{payload['old'] or '(defaults)'}`; new: `{payload['new'] or '(defaults)'}`; "
        f"{payload['machine']}, load {payload['load']}; wall time {payload['wall_s'] / 60:.1f} "
        "min. Times are wall clock: compare the two columns of one row only.",
        "",
        "| set | plans | equal | stages old | stages new | median time old / new [ms] |",
        "|---|---|---|---|---|---|",
    ]
    for kind, s in payload["summary"].items():
        lines.append(
            f"| {kind} | {s['plans']} | {s['equal']} | {s['stages_old']} | {s['stages_new']} "
            f"| {s['median_old_ms']:.1f} / {s['median_new_ms']:.1f} |"
        )
    changed = [r for r in payload["rows"] if not r["equal"]]
    lines += ["", f"Plans that changed: {len(changed)}.", ""]
    if changed:
        lines += [
            "| query | old: stage, length [m], cusps | new: stage, length [m], cusps |",
            "|---|---|---|",
        ]
        for r in changed:
            o, n = r["old"], r["new"]
            lines.append(
                f"| {r['id']} | {o['stage']}, {o['length_m'] or 0:.2f}, {o['cusps']} "
                f"| {n['stage']}, {n['length_m'] or 0:.2f}, {n['cusps']} |"
            )
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    from results_io import json_text, out_folder  # the sibling module (run as a script)

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seeds", type=positive_int, default=100,
                    help="seeds per set (default: %(default)s)")
    ap.add_argument("--sets", default=",".join(SETS),
                    help=f"comma-separated of {SETS} (default: %(default)s)")
    ap.add_argument("--old", default="escalation_first=never:reverse_postprocess_attempts=6",
                    help="planner options of the old plans (field=value:...)"
                         " (default: %(default)s)")  # fmt: skip
    ap.add_argument("--new", default="",
                    help="planner options of the new plans (default: %(default)s)")
    ap.add_argument("--out", type=out_folder, default="results",
                    help="directory for stage_order.json and .md (default: %(default)s)")
    args = ap.parse_args(argv)
    sets = [s for s in args.sets.split(",") if s]
    unknown = sorted(set(sets) - set(SETS))
    if unknown:
        ap.error(f"--sets: unknown {unknown}; choose from {list(SETS)}")
    old, new = _options(args.old), _options(args.new)
    t0 = time.perf_counter()
    rows = []
    for kind in sets:
        for seed in range(args.seeds):
            problem = problem_of(kind, seed)
            a, ta = plan(problem, seed, old)
            b, tb = plan(problem, seed, new)
            row = {"id": f"{kind}:{seed}", "set": kind, "equal": _same(a, b),
                   "old": _row(a, ta), "new": _row(b, tb)}  # fmt: skip
            rows.append(row)
            print(f"{row['id']:24s} {'equal' if row['equal'] else 'CHANGED':8s} "
                  f"{row['old']['stage']} -> {row['new']['stage']}", flush=True)  # fmt: skip
    summary = {}
    for kind in sets:
        g = [r for r in rows if r["set"] == kind]
        summary[kind] = {
            "plans": len(g),
            "equal": sum(r["equal"] for r in g),
            "stages_old": dict(Counter(str(r["old"]["stage"] or r["old"]["status"]) for r in g)),
            "stages_new": dict(Counter(str(r["new"]["stage"] or r["new"]["status"]) for r in g)),
            "median_old_ms": 1e3 * statistics.median(r["old"]["time_s"] for r in g),
            "median_new_ms": 1e3 * statistics.median(r["new"]["time_s"] for r in g),
        }
    payload = {
        "command": "python experiments/stage_order.py " + " ".join(sys.argv[1:] if argv is None
                                                                  else argv),
        "old": args.old, "new": args.new, "seeds": args.seeds, "sets": sets,
        "machine": f"{platform.machine()} {os.cpu_count()} CPUs, Python "
                   f"{platform.python_version()}",
        "load": " ".join(f"{v:.1f}" for v in os.getloadavg()),
        "wall_s": time.perf_counter() - t0, "summary": summary, "rows": rows,
    }  # fmt: skip
    out = FsPath(args.out)
    out.mkdir(parents=True, exist_ok=True)
    write_text_atomic(out / "stage_order.json", json_text(payload))
    write_text_atomic(out / "stage_order.md", report(payload))
    for kind, s in summary.items():
        print(f"{kind}: {s['equal']}/{s['plans']} plans equal; stages old {s['stages_old']}, "
              f"new {s['stages_new']}")  # fmt: skip
    return 0


if __name__ == "__main__":
    from results_io import run_main

    raise SystemExit(run_main(main))
