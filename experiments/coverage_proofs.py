"""Forward Hybrid A*'s ``proven_unreachable`` queries of a coverage run, re-planned finer.

Usage::

    python experiments/coverage_proofs.py results/coverage_all/coverage_parking_lot.json \
        --out results/coverage_all/forward_proofs.json

Each query that ``hybrid-a-star`` (forward only) reported as ``proven_unreachable`` in
the run is planned again by ``hybrid-a-star`` at its own settings (0.5 m / 5 deg,
0.15 m body clearance), on a finer grid (0.25 m), with finer headings (2.5 deg) and
with no body clearance: a proof that holds on the finer grids is not an artefact of
the resolution; one that fails with no clearance is about the clearance. Expansion
budget 20 000, a 40 s cap (``--max-time``). Rows: the query, the variant, the status,
expansions, time, and whether OMPL's Dubins RRT solved it in the run.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import coverage as cov  # noqa: E402  (the sibling script)
from results_io import json_text  # noqa: E402  (the sibling module)

from rrtdrive.atomic import write_text_atomic  # noqa: E402
from rrtdrive.cli_args import positive_float  # noqa: E402
from rrtdrive.planning import make_planner  # noqa: E402
from rrtdrive.types import Budget  # noqa: E402

#: The re-planned variants: name -> HybridConfig options.
VARIANTS: dict[str, dict[str, float]] = {
    "0.5 m / 5 deg": {},
    "0.25 m / 5 deg": {"xy_resolution": 0.25},
    "0.5 m / 2.5 deg": {"yaw_resolution": math.radians(2.5)},
    "body clearance 0": {"body_clearance": 0.0},
}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("run", help="a coverage_MAP.json of experiments/coverage.py")
    ap.add_argument("--max-time", type=positive_float, default=40.0,
                    help="wall-clock cap per re-planned query [s] (default: %(default)s)")
    ap.add_argument("--out", required=True,
                    help="JSON file to write (its folder is created)")
    args = ap.parse_args(argv)
    d = json.loads(Path(args.run).read_text())
    by = {(r["planner"], r["vary"], r["index"]): r for r in d["rows"]}
    todo = sorted(
        (r["vary"], r["index"]) for r in d["rows"]
        if r["planner"] == "hybrid-a-star" and r["status"] == "proven_unreachable"
    )  # fmt: skip
    poses = {v: cov.draw_goals(d["map"], d["count"], d["seed"], v) for v in d["sets"]}
    rows = []
    for vary, index in todo:
        _, problem = cov._problem(
            {"map": d["map"], "vary": vary, "pose": poses[vary][index].as_tuple()}
        )
        ompl = by.get(("ompl-dubins-rrt", vary, index), {}).get("solved")
        for name, options in VARIANTS.items():
            res = make_planner("hybrid-a-star", **options).solve(
                problem, np.random.default_rng(0), Budget(max_time_s=args.max_time)
            )
            row = {
                "vary": vary, "index": index, "variant": name, "status": res.status.value,
                "expansions": res.iterations, "time_s": res.planning_time_s,
                "ompl_dubins_solved": ompl, "message": res.message[:200],
            }  # fmt: skip
            rows.append(row)
            print(f"{vary} {index} {name}: {row['status']} ({row['expansions']} expansions)",
                  file=sys.stderr, flush=True)  # fmt: skip
    command = "python experiments/coverage_proofs.py " + " ".join(
        sys.argv[1:] if argv is None else argv
    )
    payload = {"command": command, "rows": rows}
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    write_text_atomic(Path(args.out), json_text(payload))
    for name in VARIANTS:
        held = sum(r["status"] == "proven_unreachable" for r in rows if r["variant"] == name)
        print(f"{name}: {held}/{len(todo)} still proven unreachable")
    return 0


if __name__ == "__main__":
    from results_io import run_main

    raise SystemExit(run_main(main))
