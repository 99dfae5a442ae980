"""Re-run the queries of one planner that a coverage run did not solve, with another cap.

Usage::

    python experiments/coverage_rerun.py results/coverage_all_cap40/coverage_parking_lot.json \
        --planner improved-rrt-connect+reverse --max-time 300 \
        --out results/coverage_all_cap40/default_reverse_rerun300s.json

A query stopped by the wall-clock safety cap (``timeout``) on a loaded machine says
nothing about the planner's budget; re-run with a larger cap, the outcome is the one
the iteration budget decides. Rows as :func:`coverage.run_one` writes them.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import coverage as cov  # noqa: E402  (the sibling script)
from results_io import json_text  # noqa: E402  (the sibling module)

from rrtdrive.atomic import write_text_atomic  # noqa: E402
from rrtdrive.cli_args import positive_float  # noqa: E402
from rrtdrive.types import InputError  # noqa: E402


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("run", help="a coverage_MAP.json of experiments/coverage.py")
    ap.add_argument("--planner", required=True,
                    help="planner name as in the run's rows; its unsolved queries are re-run")
    ap.add_argument("--max-time", type=positive_float, default=300.0,
                    help="wall-clock cap per query [s]; OMPL keeps the run's cap "
                    "(default: %(default)s)")
    ap.add_argument("--out", required=True,
                    help="JSON file to write (its folder is created)")
    args = ap.parse_args(argv)
    d = json.loads(Path(args.run).read_text())
    ran = sorted({r["planner"] for r in d["rows"]})
    if args.planner not in ran:  # else: an empty re-run, exit 0
        raise InputError(f"--planner: {args.planner!r} has no rows in {args.run}; it has {ran}")
    todo = [r for r in d["rows"] if r["planner"] == args.planner and not r["solved"]]
    poses = {v: cov.draw_goals(d["map"], d["count"], d["seed"], v) for v in d["sets"]}
    rows = []
    for r in todo:
        item = {
            "map": d["map"], "vary": r["vary"], "index": r["index"],
            "pose": poses[r["vary"]][r["index"]].as_tuple(), "planner": args.planner,
            "max_time": args.max_time, "ompl_time": d["ompl_time_s"],
        }  # fmt: skip
        row = cov.run_one(item)
        rows.append(row)
        print(f"{row['vary']} {row['index']} {row['status']} {row['time_s']:.1f} s",
              file=sys.stderr, flush=True)  # fmt: skip
    command = "python experiments/coverage_rerun.py " + " ".join(
        sys.argv[1:] if argv is None else argv
    )
    payload = {"command": command, "rows": rows}
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    write_text_atomic(Path(args.out), json_text(payload))
    solved = sum(r["solved"] for r in rows)
    print(f"{solved}/{len(rows)} solved with a {args.max_time:g} s cap")
    return 0


if __name__ == "__main__":
    from results_io import run_main

    raise SystemExit(run_main(main))
