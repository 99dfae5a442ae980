"""Hybrid A* settings side by side: each query planned by every variant in turn.

Usage::

    python experiments/hybrid_variants.py --out results/hybrid_variants
    python experiments/hybrid_variants.py --variants "session7=heuristic_weight=1.5,\
retry_weight=1.5,long_steps=(),shot_cell=0;default=" --sets rev --repeat 3 --out DIR

The queries are those of ``experiments/coverage.py`` (``parking_lot``, the
``--count`` random goal poses and random start poses of
:func:`random_goals.draw_goals`, seed ``--seed``), forward only (``fwd``) and with
reverse (``rev``), and the gear scenarios ``parking-reverse-in``,
``parallel-parking`` and ``u-turn`` (seeds ``0 .. --scenario-seeds - 1``; ``gear``);
``turns`` (not by default): the angled bays entered against the row of
``experiments/angled_bays.py`` (45 and 60 deg, aisles 4, 5, 6 m) and the lane-to-lane
turns of ``experiments/street_turns.py --lanes 0`` at 7 and 7.5 m.
Every query is planned by each variant of ``hybrid-a-star`` one after the other
(interleaved, so load changes hit all alike), ``--repeat`` times each, and the
least process (CPU) time is kept (the first plan of a query computes what the
others reuse, the goal's distance field: the variants take turns going first);
the budget is counted (20 000 expansions; the wall-clock cap 1e6 s), so the
answers do not depend on the machine.

A variant is ``name=field=value,field=value`` of :class:`HybridConfig` fields
(values read as Python literals); an empty field list is the default config.
Per variant and set: solved, median CPU time, median expansions, median length,
and against the first variant on the queries both solve: the median per-query
time and length ratios and the queries one solves and the other does not.

Writes ``OUT/hybrid_variants.json`` (every row and the resolved settings) and
``OUT/hybrid_variants.md``.
"""

from __future__ import annotations

import argparse
import ast
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
from random_goals import draw_goals  # noqa: E402

from rrtdrive.atomic import write_text_atomic  # noqa: E402
from rrtdrive.cli_args import int_at_least, positive_int  # noqa: E402
from rrtdrive.maps import builtin_map  # noqa: E402
from rrtdrive.planning import PlanningProblem, make_planner  # noqa: E402
from rrtdrive.planning.hybrid import HybridConfig  # noqa: E402
from rrtdrive.types import Budget  # noqa: E402

#: Session 7's search (before this session's long steps, weights and shot memo).
DEFAULT_VARIANTS = (
    "session7=heuristic_weight=1.5,retry_weight=1.5,long_steps=(),shot_cell=0;"
    "long_steps=heuristic_weight=1.5,retry_weight=1.5,shot_cell=0;"
    "weights=shot_cell=0;"
    "default="
)
SCENARIOS = ("parking-reverse-in", "parallel-parking", "u-turn")


def parse_variants(text: str) -> dict[str, dict[str, Any]]:
    """``name=field=value,...;name=...`` as ``{name: {field: value}}``, fields checked.

    Examples
    --------
    >>> parse_variants("a=heuristic_weight=2.0,long_steps=(2.0, 4.0);b=")
    {'a': {'heuristic_weight': 2.0, 'long_steps': (2.0, 4.0)}, 'b': {}}
    """
    fields = {f.name for f in dataclasses.fields(HybridConfig)}
    out: dict[str, dict[str, Any]] = {}
    for part in filter(None, (p.strip() for p in text.split(";"))):
        name, _, rest = part.partition("=")
        opts: dict[str, Any] = {}
        # Split on commas outside brackets (tuples hold commas).
        depth, item, items = 0, "", []
        for ch in rest:
            depth += ch in "([" and 1 or 0
            depth -= ch in ")]" and 1 or 0
            if ch == "," and depth == 0:
                items.append(item)
                item = ""
            else:
                item += ch
        items.append(item)
        for it in filter(None, (i.strip() for i in items)):
            key, eq, value = it.partition("=")
            if not eq or key not in fields:
                raise ValueError(f"--variants: {it!r} is not field=value of HybridConfig")
            opts[key] = ast.literal_eval(value)
        HybridConfig(**opts)  # validate now, not in the middle of the run
        out[name] = opts
    if not out:
        raise ValueError("--variants: no variant given")
    return out


def queries(sets: list[str], count: int, seed: int, scenario_seeds: int) -> list[tuple[str, Any]]:
    """``(id, PlanningProblem)`` of every query of ``sets``."""
    from rrtdrive.sim.tasks import make_scenario

    base = builtin_map("parking_lot")
    out = []
    for gear in (s for s in sets if s in ("fwd", "rev")):
        for vary in ("goal", "start"):
            for i, pose in enumerate(draw_goals("parking_lot", count, seed, vary)):
                m = dataclasses.replace(base, **{vary: pose})
                out.append((f"{vary}:{gear}:{i}",
                            PlanningProblem.from_map(m, reverse=gear == "rev")))  # fmt: skip
    if "turns" in sets:
        # Turning round in a narrow aisle or street (session 14): angled bays entered
        # against the row, and lane-to-lane turns in closed streets.
        from angled_bays import angled_map
        from street_turns import street

        for angle in (45.0, 60.0):
            for aisle in (4.0, 5.0, 6.0):
                m = angled_map(angle, aisle, "against")
                out.append((f"turns:{m.name}", PlanningProblem.from_map(m, reverse=True)))
        for width in (7.0, 7.5):
            m = street(width, 30.0, 0.0)
            out.append((f"turns:{m.name}", PlanningProblem.from_map(m, reverse=True)))
    if "gear" in sets:
        for name in SCENARIOS:
            for s in range(scenario_seeds):
                task = (make_scenario("parking", s, reverse_in=True)
                        if name == "parking-reverse-in" else make_scenario(name, s))  # fmt: skip
                problem = PlanningProblem.from_map(task.map, reverse=task.reverse)
                out.append((f"{name}:{s}", problem))
    return out


def group_of(qid: str) -> str:
    """``goal:rev:3`` -> ``goals rev``; ``u-turn:4`` -> ``u-turn``."""
    parts = qid.split(":")
    return f"{parts[0]}s {parts[1]}" if len(parts) == 3 else parts[0]


def summarise(rows: dict[str, dict[str, dict]], names: list[str]) -> list[dict[str, Any]]:
    """Per group and variant: counts, medians, and ratios against the first variant."""
    groups = sorted({group_of(q) for q in rows[names[0]]}, key=list(
        dict.fromkeys(group_of(q) for q in rows[names[0]])).index)
    out = []
    for g in groups:
        for name in names:
            vals = {q: r for q, r in rows[name].items() if group_of(q) == g}
            ok = [r for r in vals.values() if r["solved"]]
            ref = {q: r for q, r in rows[names[0]].items() if group_of(q) == g}
            both = [q for q in vals if vals[q]["solved"] and ref[q]["solved"]]
            out.append({
                "group": g, "variant": name, "queries": len(vals), "solved": len(ok),
                "median_cpu_ms": 1e3 * statistics.median(r["cpu_s"] for r in vals.values()),
                "median_expansions": statistics.median(r["expansions"] for r in vals.values()),
                "median_length_m": statistics.median(r["length_m"] for r in ok) if ok else None,
                "time_ratio": statistics.median(
                    vals[q]["cpu_s"] / ref[q]["cpu_s"] for q in both) if both else None,
                "length_ratio": statistics.median(
                    vals[q]["length_m"] / ref[q]["length_m"] for q in both) if both else None,
                "lost": sorted(q for q in vals if ref[q]["solved"] and not vals[q]["solved"]),
                "won": sorted(q for q in vals if vals[q]["solved"] and not ref[q]["solved"]),
            })  # fmt: skip
    return out


def render(summary: list[dict[str, Any]], names: list[str], meta: dict[str, Any]) -> str:
    """The markdown page."""
    lines = [
        "# Hybrid A* settings side by side",
        "",
        f"Command: `{meta['command']}`  ",
        f"{meta['machine']}; load {meta['load_start']} at the start, {meta['load_end']} at "
        f"the end; wall time {meta['wall_min']:.1f} min. CPU time of each plan, the least of "
        f"{meta['repeat']} (interleaved per query); budget 20 000 expansions (counted).",
        "",
        "Variants: " + "; ".join(f"`{n}`: {meta['variants'][n] or 'the default'}" for n in names),
        "",
        f"| set | variant | solved | median CPU [ms] | median expansions | median length [m] "
        f"| time ratio vs `{names[0]}` | length ratio | lost | won |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in summary:
        def f(v: Any, d: int = 3) -> str:
            return "-" if v is None else f"{v:.{d}f}"

        lines.append(
            f"| {r['group']} | {r['variant']} | {r['solved']}/{r['queries']} | "
            f"{f(r['median_cpu_ms'], 1)} | {r['median_expansions']:.0f} | "
            f"{f(r['median_length_m'], 2)} | {f(r['time_ratio'])} | {f(r['length_ratio'])} | "
            f"{', '.join(r['lost']) or '-'} | {', '.join(r['won']) or '-'} |"
        )
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    """Run the variants and write the results."""
    from results_io import json_text, out_folder  # the sibling module (run as a script)

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--variants", default=DEFAULT_VARIANTS,
                    help="name=field=value,...;name=... (default: session 7 and the steps since)")
    ap.add_argument(
        "--sets", default="rev,fwd,gear", help="of rev, fwd, gear, turns (default rev,fwd,gear)"
    )
    ap.add_argument("--count", type=positive_int, default=30,
                    help="random poses per set (default 30)")
    ap.add_argument("--seed", type=int_at_least(0), default=1,
                    help="seed of the pose sets (default 1)")
    ap.add_argument("--scenario-seeds", type=positive_int, default=10,
                    help="seeds per gear scenario (default: %(default)s)")
    ap.add_argument("--repeat", type=positive_int, default=2,
                    help="plans per query and variant, the least CPU time kept (default 2)")
    ap.add_argument("--out", type=out_folder, default="results/hybrid_variants",
                    help="directory for hybrid_variants.json and .md (default: %(default)s)")
    args = ap.parse_args(argv)
    try:
        variants = parse_variants(args.variants)
    except (ValueError, SyntaxError) as exc:
        ap.error(str(exc))
    sets = [s.strip() for s in args.sets.split(",") if s.strip()]
    if not sets or set(sets) - {"rev", "fwd", "gear", "turns"}:
        ap.error("--sets: a comma-separated list of rev, fwd, gear, turns")
    for name in ("count", "scenario_seeds", "repeat"):
        if getattr(args, name) < 1:
            ap.error(f"--{name.replace('_', '-')}: must be >= 1")
    names = list(variants)
    items = queries(sets, args.count, args.seed, args.scenario_seeds)
    planners = {n: make_planner("hybrid-a-star", **o) for n, o in variants.items()}
    budget = Budget(max_time_s=1e6)
    load_start = ", ".join(f"{v:.2f}" for v in os.getloadavg())
    t_start = time.perf_counter()
    for p in planners.values():  # imports, per-process tables, the map's set-up
        p.solve(items[0][1], np.random.default_rng(0), budget)
    rows: dict[str, dict[str, dict]] = {n: {} for n in names}
    for k, (qid, problem) in enumerate(items):
        # The first plan of a query pays what the others then share (the goal's distance
        # field): the variants take turns going first, and the least of --repeat counts.
        for n in names[k % len(names) :] + names[: k % len(names)]:
            best = float("inf")
            for _ in range(args.repeat):
                t0 = time.process_time()
                res = planners[n].solve(problem, np.random.default_rng(0), budget)
                best = min(best, time.process_time() - t0)
            rows[n][qid] = {
                "solved": res.success, "status": res.status.value, "cpu_s": best,
                "expansions": res.iterations,
                "length_m": res.path.length if res.success else None,
            }  # fmt: skip
        print(f"\r{k + 1}/{len(items)} queries", end="", file=sys.stderr, flush=True)
    print(file=sys.stderr)
    meta = {
        "command": "python experiments/hybrid_variants.py " + " ".join(
            sys.argv[1:] if argv is None else argv),
        "machine": f"{platform.machine()} {os.cpu_count()} CPUs, "
        f"Python {platform.python_version()}",
        "load_start": load_start,
        "load_end": ", ".join(f"{v:.2f}" for v in os.getloadavg()),
        "wall_min": (time.perf_counter() - t_start) / 60.0,
        "repeat": args.repeat, "sets": sets, "count": args.count, "seed": args.seed,
        "scenario_seeds": args.scenario_seeds,
        "variants": {n: {k: repr(v) for k, v in o.items()} for n, o in variants.items()},
        "resolved": {
            n: repr(dataclasses.replace(HybridConfig(), **o)) for n, o in variants.items()
        },
    }  # fmt: skip
    summary = summarise(rows, names)
    out = FsPath(args.out)
    out.mkdir(parents=True, exist_ok=True)
    payload = {"meta": meta, "summary": summary, "rows": rows}
    write_text_atomic(out / "hybrid_variants.json", json_text(payload))
    text = render(summary, names, meta)
    write_text_atomic(out / "hybrid_variants.md", text)
    print(text)
    return 0


if __name__ == "__main__":
    from results_io import run_main

    raise SystemExit(run_main(main))
