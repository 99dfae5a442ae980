"""Default planner speed, old code against new, on the same queries, with the answers compared.

Usage::

    # Interleaved benchmark: this tree against the code of commit REF (old), query by query
    python experiments/bench_default.py --ref 6b0d9b8 --out results --gears rev --repeat 3
    # Equivalence only: record this tree's answers, later check a changed tree against them
    python experiments/bench_default.py --record /tmp/default_base.pkl
    python experiments/bench_default.py --check /tmp/default_base.pkl

The queries are those of ``experiments/coverage.py``: ``parking_lot`` with the
``--count`` random goal poses and random start poses of
:func:`random_goals.draw_goals` (seed 1), each planned by the default planner
``improved-rrt-connect`` (planner seed 0, ``Budget(max_time_s=10)``) forward-only
(``fwd``) and with reverse (``rev``): 400 plans by default.

Two answers are *the same* when the status, the message with its quoted times
masked (``1.23 s`` -> ``T s``), the iterations, the stage and the path rows (to
1e-9) agree. The benchmark runs the old code (a ``git archive`` of ``REF``'s
``src/``, imported in a worker process) and this tree in another worker,
alternating query by query (the worker machinery of ``bench_hybrid.py``), and
writes ``OUT/bench_default.{json,md}``: per query both CPU times (the least of
``--repeat`` runs) and whether the answers agree; the median per-query ratio new / old.
"""

from __future__ import annotations

import argparse
import os
import pickle
import re
import sys
import time
from pathlib import Path as FsPath

HERE = FsPath(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(HERE))
import bench_hybrid as bh  # noqa: E402  (the sibling benchmark's worker machinery)

positive_int = bh.positive_int
_TIME = re.compile(r"\d+\.\d+ s")


def query_ids(count: int = 100, gears: tuple[str, ...] = ("fwd", "rev")) -> list[str]:
    """Every query's id: ``goal:rev:3``, ``start:fwd:12``."""
    return [
        f"{vary}:{gear}:{i}" for vary in ("goal", "start") for gear in gears for i in range(count)
    ]


class _Runner(bh._Runner):
    """Plans queries by id with the default planner of the ``rrtdrive`` this process imports."""

    PLANNER = "improved-rrt-connect"
    MAX_TIME_S = 10.0

    def compared(self, res) -> dict:  # noqa: ANN001 - a PlanResult of either tree
        """The message with the times it quotes masked, and the stage in place of nodes."""
        from rrtdrive.planning.hybrid.escalation import stage_of

        return {"message": _TIME.sub("T s", res.message), "nodes": stage_of(res)}


def _markdown(meta: dict, summary: dict, rows: list[dict]) -> str:
    lines = [
        "# Default planner (improved-rrt-connect): old code against new, same answers",
        "",
        f"Command: `{meta['command']}`  ",
        f"Old: `src/` of {meta['ref']} ({meta['ref_sha'][:10]}); new: {meta['new']}. "
        f"{meta['machine']}, load {meta['load']}; wall time {meta['wall_s'] / 60:.1f} min. "
        f"CPU times: the worker's process time of the `solve` call, the least of "
        f"{meta['repeat']} runs; old and new alternate query by query.",
        "",
        "| queries | n | same answer | solved | CPU total old / new [s] "
        "| CPU median old / new [ms] | CPU median ratio new/old | wall median ratio |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for name, s in summary.items():
        group = [r for r in rows if name == "all" or bh._group(r["id"]) == name]
        old_ms = 1e3 * bh._median([r["old_cpu_s"] for r in group])
        new_ms = 1e3 * bh._median([r["new_cpu_s"] for r in group])
        lines.append(
            f"| {name} | {s['queries']} | {s['same']} | {s['solved']} "
            f"| {s['old_cpu_total_s']:.2f} / {s['new_cpu_total_s']:.2f} "
            f"| {old_ms:.1f} / {new_ms:.1f} "
            f"| {s['cpu_median_ratio']:.3f} | {s['median_ratio']:.3f} |"
        )
    diff = [r for r in rows if not r["same"]]
    lines += ["", f"Queries whose answers differ: {len(diff)}."]
    lines += [f"- `{r['id']}`: {r['why']}" for r in diff]
    lines += [
        "",
        "The CPU median ratio is the median of the per-query ratios; the medians "
        "old / new are of the per-query CPU times.",
        "",
        "| query | status | stage | old CPU [ms] | new CPU [ms] | ratio |",
        "|---|---|---|---|---|---|",
    ]
    for r in rows:
        ratio = r["new_cpu_s"] / r["old_cpu_s"] if r["old_cpu_s"] > 0 else float("nan")
        lines.append(
            f"| {r['id']} | {r['status']} | {r['stage']} | {1e3 * r['old_cpu_s']:.1f} "
            f"| {1e3 * r['new_cpu_s']:.1f} | {ratio:.3f} |"
        )
    return "\n".join(lines) + "\n"


def _bench(args: argparse.Namespace, ids: list[str]) -> int:
    t0 = time.perf_counter()
    meta = bh.provenance(args.ref)
    rows = []
    for qid, a, b, same, why in bh.interleaved(
        meta["ref_sha"], ids, args.count, args.repeat, args.warm or bh.warm_query(args.count),
        FsPath(__file__),
    ):
        rows.append({
            "id": qid, "status": b["status"], "stage": b["nodes"],
            "iterations": b["iterations"], "old_s": a["time_s"], "new_s": b["time_s"],
            "old_cpu_s": a["cpu_s"], "new_cpu_s": b["cpu_s"], "same": same, "why": why,
        })  # fmt: skip
        print(f"{qid:16s} {b['status']:18s} old {1e3 * a['cpu_s']:8.1f} ms  new "
              f"{1e3 * b['cpu_s']:8.1f} ms  {'same' if same else 'DIFFERENT ' + why}",
              flush=True)  # fmt: skip
    summary = bh._summary(rows)
    meta = {
        "command": "python experiments/bench_default.py " + " ".join(sys.argv[1:]),
        **meta,
        "repeat": args.repeat,
        "machine": bh.machine(),
        "load": " ".join(f"{v:.1f}" for v in os.getloadavg()),
        "wall_s": time.perf_counter() - t0,
    }
    payload = {"meta": meta, "summary": summary, "queries": rows}
    bh.write_results(args.out, "bench_default", payload, _markdown(meta, summary, rows))
    for name, s in summary.items():
        print(f"{name}: same {s['same']}/{s['queries']}, CPU {s['old_cpu_total_s']:.2f} -> "
              f"{s['new_cpu_total_s']:.2f} s, CPU median ratio {s['cpu_median_ratio']:.3f}")
    return 0 if all(r["same"] for r in rows) else 1


def main(argv: list[str] | None = None) -> int:
    from results_io import out_folder  # the sibling module (run as a script)

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--ref", default="6b0d9b8", help="the old code's commit (default: %(default)s)")
    ap.add_argument("--out", type=out_folder, default="results",
                    help="directory for bench_default.json and .md (default: %(default)s)")
    ap.add_argument("--count", type=positive_int, default=100,
                    help="random goals and starts each (default: %(default)s)")
    ap.add_argument("--gears", default="fwd,rev", help="fwd, rev or fwd,rev (default: %(default)s)")
    ap.add_argument("--repeat", type=positive_int, default=1,
                    help="runs per query; times: the least")
    ap.add_argument("--warm", default=None, help=argparse.SUPPRESS)
    ap.add_argument("--only", default="", help="comma-separated query ids (default: all)")
    ap.add_argument("--record", default="",
                    help="record this tree's answers to a file (default: %(default)s)")
    ap.add_argument("--check", default="",
                    help="compare this tree's answers to a record (default: %(default)s)")
    ap.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.worker:
        return bh._worker(args.count, args.repeat, args.warm or bh.warm_query(args.count), _Runner)
    gears = tuple(args.gears.split(","))
    if not gears or any(g not in ("fwd", "rev") for g in gears):
        ap.error(f"--gears: expected fwd, rev or fwd,rev, got {args.gears!r}")
    ids = args.only.split(",") if args.only else query_ids(args.count, gears)
    known = set(query_ids(args.count))
    unknown = [q for q in ids if q not in known]
    if unknown:
        ap.error(f"--only: unknown query id(s) {unknown}; ids are VARY:GEAR:I, e.g. goal:rev:7 "
                 f"(VARY goal or start, GEAR fwd or rev, I below --count {args.count})")
    if not (args.record or args.check):
        return _bench(args, ids)
    runner = _Runner(args.count)
    runner.run(args.warm or bh.warm_query(args.count))
    base = pickle.loads(FsPath(args.check).read_bytes()) if args.check else {}
    got, bad, total = {}, 0, 0.0
    for qid in ids:
        r = runner.run(qid, args.repeat)
        got[qid] = r
        total += r["cpu_s"]
        note = ""
        if args.check:
            same, why = bh.same_answer(base[qid], r)
            bad += not same
            note = f"old {1e3 * base[qid]['cpu_s']:8.1f} ms  " + ("same" if same else "DIFF " + why)
        print(f"{qid:16s} {r['status']:18s} {r['nodes']:22s} {1e3 * r['cpu_s']:8.1f} ms  {note}",
              flush=True)  # fmt: skip
    if args.record:
        from rrtdrive.atomic import atomic_target  # this tree's, in the main process

        with atomic_target(args.record) as tmp:  # whole or not at all (Ctrl-C)
            tmp.write_bytes(pickle.dumps(got))
    print(f"total CPU {total:.2f} s" + (f"; {bad} answers differ" if args.check else ""))
    return 1 if bad else 0


if __name__ == "__main__":
    from results_io import run_main

    raise SystemExit(run_main(main))
