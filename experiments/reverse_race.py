"""What the default planner's ``--reverse`` answers would measure if Hybrid A* raced its stages.

Usage::

    python experiments/reverse_race.py RUN.json [RUN.json ...] [--out DIR]

Each RUN is what ``experiments/coverage.py`` writes with the planners
``improved-rrt-connect+reverse``, ``hybrid-a-star+reverse`` and ``ompl-rs-rrtconnect``.
Nothing is planned again: on the queries all three solve, per query set, the ratios
of medians against OMPL's Reeds-Shepp RRTConnect (issue 13's length and time targets)
of

- ``default``: the default planner with reverse as it is (its RRT-Connect stage and
  the direct Dubins path go first and are kept when they succeed, item 3 of the issue);
- ``hybrid-a-star``: the reversing search alone;
- ``race``: the default's stages, then, when one of them solved the query, the
  reversing search too, keeping the shorter path (the default's own escalation is
  that search, query by query, so an escalated answer stands); its time is the
  default's plus, where a stage before the escalation solved the query, the search's.

The race is a thought experiment on measured rows, not a planner: it shows what the
two targets would cost each other.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
from collections.abc import Sequence
from typing import Any

sys.path.insert(0, os.path.dirname(__file__))
from results_io import command, out_folder, write_results  # noqa: E402  (the sibling script)

DEFAULT, HYBRID = "improved-rrt-connect+reverse", "hybrid-a-star+reverse"
OMPL = "ompl-rs-rrtconnect"
#: The default planner's stage that is its escalation (the others go before it).
ESCALATION = "hybrid-a-star"


def measure(run: dict[str, Any]) -> list[dict[str, Any]]:
    """One row per query set of ``run``: the three variants' ratios of medians to OMPL's."""
    rows = {(r["planner"], r["vary"], r["index"]): r for r in run["rows"]}
    out = []
    for vary in run["sets"]:
        both = sorted(
            i for (p, v, i), r in rows.items()
            if p == OMPL and v == vary and r["solved"]
            and rows.get((DEFAULT, v, i), {}).get("solved")
            and rows.get((HYBRID, v, i), {}).get("solved")
        )  # fmt: skip
        if not both:
            continue

        def med(values: Sequence[float]) -> float:
            return float(statistics.median(values))

        ompl_len = med([rows[(OMPL, vary, i)]["length_m"] for i in both])
        ompl_time = med([rows[(OMPL, vary, i)]["time_s"] for i in both])
        default = [rows[(DEFAULT, vary, i)] for i in both]
        hybrid = [rows[(HYBRID, vary, i)] for i in both]
        early = [d["stage"] != ESCALATION for d in default]
        race_len = [
            min(d["length_m"], h["length_m"]) if e else d["length_m"]
            for d, h, e in zip(default, hybrid, early, strict=True)
        ]
        race_time = [
            d["time_s"] + (h["time_s"] if e else 0.0)
            for d, h, e in zip(default, hybrid, early, strict=True)
        ]
        out.append({
            "seed": run["seed"], "count": run["count"], "set": vary, "both": len(both),
            "solved_before_escalation": sum(early),
            "length_ratio": {
                "default": med([d["length_m"] for d in default]) / ompl_len,
                "hybrid-a-star": med([h["length_m"] for h in hybrid]) / ompl_len,
                "race": med(race_len) / ompl_len,
            },
            "time_ratio": {
                "default": med([d["time_s"] for d in default]) / ompl_time,
                "hybrid-a-star": med([h["time_s"] for h in hybrid]) / ompl_time,
                "race": med(race_time) / ompl_time,
            },
        })  # fmt: skip
    return out


def report(payload: dict[str, Any]) -> str:
    """The markdown page of :func:`measure`'s rows."""
    lines = [
        "# The default planner with reverse, and a race against Hybrid A*",
        "",
        f"Command: `{payload['command']}`  ",
        "Ratios of medians against OMPL Reeds-Shepp RRTConnect on the queries all three "
        "solve (issue 13: length <= 1, time <= 0.5); `race` is the default's stages, then "
        "the reversing search where they solved the query, keeping the shorter path "
        "(docstring of `experiments/reverse_race.py`).",
        "",
        "| run | set | queries | solved before the escalation | length: default / "
        "hybrid-a-star / race | time: default / hybrid-a-star / race |",
        "|---|---|---|---|---|---|",
    ]
    for r in payload["rows"]:
        length, time = r["length_ratio"], r["time_ratio"]
        lines.append(
            f"| seed {r['seed']}, {r['count']} | {r['set']}s | {r['both']} | "
            f"{r['solved_before_escalation']} | "
            + " / ".join(f"{length[k]:.3f}" for k in ("default", "hybrid-a-star", "race"))
            + " | "
            + " / ".join(f"{time[k]:.3f}" for k in ("default", "hybrid-a-star", "race"))
            + " |"
        )
    return "\n".join(lines) + "\n"


def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("runs", nargs="+", metavar="RUN.json",
                    help="coverage.py results with the three planners")  # fmt: skip
    ap.add_argument("--out", type=out_folder, default=None,
                    help="write reverse_race.json and .md here")
    args = ap.parse_args(argv)
    rows = []
    for path in args.runs:
        with open(path, encoding="utf-8") as f:
            run = json.load(f)
        missing = {DEFAULT, HYBRID, OMPL} - set(run["planners"])
        if missing:
            ap.error(f"{path}: the run has no rows of {', '.join(sorted(missing))}")
        rows += measure(run)
    payload = {"command": command("reverse_race.py", argv), "rows": rows}
    page = (
        write_results(args.out, "reverse_race", payload, report) if args.out else report(payload)
    )
    print(page, end="")
    return 0


if __name__ == "__main__":
    from results_io import run_main

    raise SystemExit(run_main(main))
