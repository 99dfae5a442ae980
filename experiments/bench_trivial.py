"""Hybrid A* with reverse on trivial queries: the fixed per-query cost, old code against new.

Usage::

    # This tree alone: per query the least CPU time of --repeat runs
    python experiments/bench_trivial.py --out results
    # This tree against the code of commit REF, interleaved query by query
    python experiments/bench_trivial.py --ref fe62cbf --out results

The queries: ``parking_lot`` with the random start poses of
:func:`random_goals.draw_goals` (``draw_goals("parking_lot", 100, 1, "start")``,
the coverage benchmark's start set) at ``--indices``, planned by ``hybrid-a-star``
with reverse. The default indices are the queries near the median of
``coverage.py``'s per-query time ratio against OMPL on random starts: all solved by
the first Reeds-Shepp shot from the start, so their time is the query's fixed cost
(set-up of the searches, the shot, the ramped path and its re-check).

Each query runs in a worker process importing ``rrtdrive`` from this tree (and,
with ``--ref``, in another one importing a ``git archive`` of ``REF``'s ``src/``,
:mod:`bench_hybrid`'s workers), ``--repeat`` rounds; in each round every query
runs once in each worker, the order alternating. A query's time is the least CPU
time (``time.process_time``) of its ``solve`` calls over the rounds; the planner's
own ``planning_time_s`` (wall clock, set-up excluded) is given beside it. The
answers of both trees are compared (status, message, expansions, nodes, path rows
to 1e-9). Writes ``OUT/bench_trivial.{json,md}``: per query both times and the
ratio new / old, and the median ratio.
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path as FsPath

HERE = FsPath(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(HERE))
import bench_hybrid  # noqa: E402  (the sibling script's workers and answer comparison)

#: The random start queries near the median of the coverage benchmark's time ratio.
INDICES = (87, 79, 33, 66, 24, 80, 95, 18, 88, 89, 42, 76, 84, 52)
#: Random poses drawn (the coverage benchmark's ``--count``); the indices pick from them.
COUNT = 100


def _git(*args: str) -> str:
    return subprocess.run(
        ["git", *args], cwd=ROOT, check=True, capture_output=True, text=True
    ).stdout.strip()


def _rounds(workers: dict[str, bench_hybrid._Worker], ids: list[str], repeat: int) -> dict:
    """``{name: {qid: answer}}``, each answer's times the least over ``repeat`` rounds."""
    best: dict[str, dict[str, dict]] = {name: {} for name in workers}
    names = list(workers)
    for r in range(repeat):
        for n, qid in enumerate(ids):
            # Alternate which tree runs first, so neither always meets a warm cache.
            order = names if (n + r) % 2 == 0 else names[::-1]
            for name in order:
                got = workers[name].run(qid)
                old = best[name].get(qid)
                if old is not None:
                    same, why = bench_hybrid.same_answer(old, got)
                    if not same:
                        raise RuntimeError(f"{name} {qid}: a repeated run differs ({why})")
                    got["time_s"] = min(got["time_s"], old["time_s"])
                    got["cpu_s"] = min(got["cpu_s"], old["cpu_s"])
                best[name][qid] = got
        print(f"round {r + 1}/{repeat} done", flush=True)
    return best


def _markdown(meta: dict, rows: list[dict], summary: dict) -> str:
    has_old = meta["ref"] is not None
    lines = [
        "# Hybrid A* with reverse on trivial queries: per-query CPU time",
        "",
        f"Command: `{meta['command']}`  ",
        bench_hybrid.provenance_line(meta) + f"; wall time {meta['wall_s']:.0f} s.",
        "",
        f"`parking_lot`, random start poses (draw_goals(..., {COUNT}, 1, 'start')) at the given "
        f"indices, `hybrid-a-star` with reverse; per query the least CPU time of the `solve` "
        f"call over {meta['repeat']} interleaved rounds, and the least `planning_time_s`.",
        "",
    ]
    if has_old:
        lines += [
            "| query | status | old CPU [ms] | new CPU [ms] | ratio new/old "
            "| old planning [ms] | new planning [ms] | ratio | same answer |",
            "|---|---|---|---|---|---|---|---|---|",
        ]
        for r in rows:
            lines.append(
                f"| {r['id']} | {r['status']} | {1e3 * r['old_cpu_s']:.3f} "
                f"| {1e3 * r['new_cpu_s']:.3f} | {r['cpu_ratio']:.3f} "
                f"| {1e3 * r['old_s']:.3f} | {1e3 * r['new_s']:.3f} | {r['time_ratio']:.3f} "
                f"| {'yes' if r['same'] else 'NO: ' + r['why']} |"
            )
        lines += [
            "",
            f"Median ratio new/old: CPU **{summary['cpu_median_ratio']:.3f}**, planning time "
            f"{summary['time_median_ratio']:.3f}; median CPU old / new "
            f"{summary['old_cpu_median_ms']:.3f} / {summary['new_cpu_median_ms']:.3f} ms; "
            f"answers the same: {summary['same']}/{len(rows)}.",
        ]
    else:
        lines += [
            "| query | status | CPU [ms] | planning [ms] |",
            "|---|---|---|---|",
        ]
        for r in rows:
            lines.append(
                f"| {r['id']} | {r['status']} | {1e3 * r['new_cpu_s']:.3f} "
                f"| {1e3 * r['new_s']:.3f} |"
            )
        lines += ["", f"Median CPU {summary['new_cpu_median_ms']:.3f} ms."]
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    from results_io import json_text, out_folder  # the sibling module (run as a script)

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--ref", default=None, help="the old code's commit (default: no comparison)")
    ap.add_argument("--out", type=out_folder, default="results",
                    help="directory of bench_trivial.{json,md} (default: %(default)s)")
    ap.add_argument("--repeat", type=bench_hybrid.positive_int, default=7,
                    help="interleaved rounds; times: the least (default: %(default)s)")
    ap.add_argument(
        "--indices", default=",".join(map(str, INDICES)),
        help="comma-separated indices into the 100 random start poses (default: %(default)s)",
    )  # fmt: skip
    args = ap.parse_args(argv)
    if args.repeat < 1:
        ap.error("--repeat: must be >= 1")
    ids = [f"start:rev:{int(i)}" for i in args.indices.split(",")]
    if any(not 0 <= int(q.rsplit(":", 1)[1]) < COUNT for q in ids):
        ap.error(f"--indices: each must be in [0, {COUNT})")
    t0 = time.perf_counter()
    load_before = " ".join(f"{v:.2f}" for v in os.getloadavg())
    head = _git("rev-parse", "--short", "HEAD")
    dirty = _git("status", "--porcelain", "src")
    given = sys.argv[1:] if argv is None else argv
    meta = {
        "command": "python experiments/bench_trivial.py " + " ".join(given),
        "ref": args.ref,
        "ref_sha": _git("rev-parse", args.ref) if args.ref else None,
        "new": f"this tree at {head}" + (" with uncommitted changes in src/" if dirty else ""),
        "machine": (
            f"{platform.machine()} {os.cpu_count()} CPUs, Python {platform.python_version()}"
        ),
        "repeat": args.repeat,
        "load_before": load_before,
    }
    warm = ids[0]  # imports, caches and the map's set-up before the first timed query
    with tempfile.TemporaryDirectory(prefix="bench_trivial_") as tmp:
        workers = {}
        for side in ("old", "new"):
            (FsPath(tmp) / side).mkdir()
        if args.ref:
            src = bench_hybrid._export(meta["ref_sha"], FsPath(tmp) / "old")
            workers["old"] = bench_hybrid._Worker(src, COUNT, 1, warm)
        new_src = bench_hybrid._export(None, FsPath(tmp) / "new")
        workers["new"] = bench_hybrid._Worker(new_src, COUNT, 1, warm)
        try:
            best = _rounds(workers, ids, args.repeat)
        finally:
            for w in workers.values():
                w.close()
    rows = []
    for qid in ids:
        b = best["new"][qid]
        row = {"id": qid, "status": b["status"], "iterations": b["iterations"],
               "new_s": b["time_s"], "new_cpu_s": b["cpu_s"]}  # fmt: skip
        if args.ref:
            a = best["old"][qid]
            same, why = bench_hybrid.same_answer(a, b)
            row.update(
                old_s=a["time_s"], old_cpu_s=a["cpu_s"], cpu_ratio=b["cpu_s"] / a["cpu_s"],
                time_ratio=b["time_s"] / a["time_s"], same=same, why=why,
            )  # fmt: skip
        rows.append(row)
    summary = {
        "new_cpu_median_ms": 1e3 * statistics.median(r["new_cpu_s"] for r in rows),
        "new_time_median_ms": 1e3 * statistics.median(r["new_s"] for r in rows),
    }
    if args.ref:
        summary.update(
            old_cpu_median_ms=1e3 * statistics.median(r["old_cpu_s"] for r in rows),
            old_time_median_ms=1e3 * statistics.median(r["old_s"] for r in rows),
            cpu_median_ratio=statistics.median(r["cpu_ratio"] for r in rows),
            time_median_ratio=statistics.median(r["time_ratio"] for r in rows),
            same=sum(r["same"] for r in rows),
        )
    meta["load_after"] = " ".join(f"{v:.2f}" for v in os.getloadavg())
    meta["wall_s"] = time.perf_counter() - t0
    out = FsPath(args.out)
    out.mkdir(parents=True, exist_ok=True)
    from rrtdrive.atomic import write_text_atomic  # here: a worker imports an old tree

    write_text_atomic(
        out / "bench_trivial.json",
        json_text({"meta": meta, "summary": summary, "queries": rows}),
    )
    write_text_atomic(out / "bench_trivial.md", _markdown(meta, rows, summary))
    for r in rows:
        line = f"{r['id']:16s} {r['status']:8s} new {1e3 * r['new_cpu_s']:7.3f} ms"
        if args.ref:
            line += f"  old {1e3 * r['old_cpu_s']:7.3f} ms  ratio {r['cpu_ratio']:.3f}"
            line += "" if r["same"] else f"  DIFFERENT {r['why']}"
        print(line)
    if args.ref:
        print(
            f"median CPU ratio new/old {summary['cpu_median_ratio']:.3f} (planning time "
            f"{summary['time_median_ratio']:.3f}); same answers {summary['same']}/{len(rows)}"
        )
        return 0 if summary["same"] == len(rows) else 1
    print(f"median CPU {summary['new_cpu_median_ms']:.3f} ms")
    return 0


if __name__ == "__main__":
    from results_io import run_main

    raise SystemExit(run_main(main))
