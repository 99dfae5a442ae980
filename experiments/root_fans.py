"""How open each root's fan is, against when (and whether) the root grew (``narrow_fan``).

Usage::

    python experiments/root_fans.py results/root_growth_s18/root_growth.json \\
        --out results/root_fans_s19

Reads a run of ``experiments/root_growth.py`` (every pair of trees of the default
planner over its queries, with ``root_patience=0``: when each root first grew, if ever)
and gives each start and goal root its open share
(:func:`rrtdrive.planning.improved.boxed.open_share`: the share of the directions within
90 degrees of its heading with room for a growth edge there). Writes
``OUT/root_fans.{json,md}``: per band of open share, the roots that grew and the latest
iteration of their pair at which one did, and the roots of failed pairs that never grew
(per map), which is what ``ImprovedConfig.narrow_fan`` and ``narrow_patience`` rest on.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections import Counter
from pathlib import Path as FsPath
from typing import Any

HERE = FsPath(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from results_io import command, machine, out_folder, write_results  # noqa: E402

from rrtdrive.planning.improved.boxed import open_share  # noqa: E402

#: Bands of open share, [lo, hi).
BANDS = ((0.0, 0.05), (0.05, 0.1), (0.1, 0.15), (0.15, 0.2), (0.2, 0.3), (0.3, 0.5), (0.5, 1.01))


def shares(query_ids: list[str], count: int, seeds: int) -> dict[str, tuple[float, float]]:
    """Each query's ``(start share, goal share)``, its problem as ``root_growth.py`` made it."""
    from root_growth import queries

    problems = {qid: problem for qid, problem, _seed in queries(count, seeds)}
    out: dict[str, tuple[float, float]] = {}
    for qid in query_ids:
        problem = problems[qid]
        out[qid] = (
            open_share(problem.checker, problem.start), open_share(problem.checker, problem.goal)
        )
    return out


def summarise(pairs: list[dict[str, Any]], by_query: dict[str, tuple[float, float]]) -> dict:
    """Per band: roots that grew (and the latest iteration), roots that never grew."""
    grew: list[tuple[float, int]] = []
    never: list[tuple[float, str]] = []
    for p in pairs:
        for k, end in enumerate(("start", "goal")):
            share, when = by_query[p["query"]][k], p[f"{end}_grew"]
            if when is not None:
                grew.append((share, when))
            elif not p["met"]:
                never.append((share, p["query"]))
    bands = []
    for lo, hi in BANDS:
        g = [when for s, when in grew if lo <= s < hi]
        n = [q for s, q in never if lo <= s < hi]
        bands.append({
            "band": [lo, min(hi, 1.0)], "grew": len(g), "latest_growth": max(g, default=None),
            "never_grew": len(n), "never_grew_by_map": dict(Counter(q.split(":")[0] for q in n)),
        })  # fmt: skip
    return {"roots_grew": len(grew), "roots_never_grew": len(never), "bands": bands}


def report(payload: dict[str, Any]) -> str:
    """The markdown page of a payload."""
    s = payload["summary"]
    lines = [
        "# Root fans: open share against root growth",
        "",
        f"Command: `{payload['command']}`  ",
        f"{payload['machine']}. The pairs of `{payload['source']}`: {s['roots_grew']} roots "
        f"grew, {s['roots_never_grew']} roots of failed pairs never did.",
        "",
        "| open share | roots that grew | latest iteration a root grew | roots that never grew "
        "(failed pairs) | by map |",
        "|---|---|---|---|---|",
    ]
    for b in s["bands"]:
        lo, hi = b["band"]
        latest = "-" if b["latest_growth"] is None else str(b["latest_growth"])
        maps = ", ".join(f"{k} {v}" for k, v in sorted(b["never_grew_by_map"].items())) or "-"
        lines.append(
            f"| [{lo:g}, {hi:g}) | {b['grew']} | {latest} | {b['never_grew']} | {maps} |"
        )
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("run", help="a root_growth.json of experiments/root_growth.py")
    ap.add_argument("--out", type=out_folder, default="results/root_fans",
                    help="directory for root_fans.json and .md (default: %(default)s)")
    args = ap.parse_args(argv)
    try:
        data = json.loads(FsPath(args.run).read_text())
        pairs, count = data["pairs"], int(data["meta"]["count"])
        seeds = int(data["meta"]["seeds"])
    except (OSError, ValueError, KeyError) as exc:
        ap.error(f"run: not a root_growth.json ({exc})")
    by_query = shares(sorted({p["query"] for p in pairs}), count, seeds)
    payload = {
        "command": command("root_fans.py", argv), "source": args.run, "machine": machine(),
        "summary": summarise(pairs, by_query),
        "shares": {q: list(v) for q, v in by_query.items()},
    }  # fmt: skip
    print(write_results(args.out, "root_fans", payload, report))
    return 0


if __name__ == "__main__":
    from results_io import run_main

    raise SystemExit(run_main(main))
