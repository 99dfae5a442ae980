"""``ramped_segment`` old against new, call by call, on the segments real plans ramp.

Usage::

    # Record every ramped_segment call of bench_hybrid.py's 150 plans, then time the
    # ramps.py of commit REF (old) against this tree's (new), interleaved per segment
    python experiments/bench_ramps.py --ref d4ad454 --out results
    # Keep the recorded segments for later runs (or read them back)
    python experiments/bench_ramps.py --ref d4ad454 --segments /tmp/segments.pkl --out results

The segments: the arguments of every :func:`~rrtdrive.planning.hybrid.ramps.ramped_segment`
call the Hybrid A* makes on the queries of ``bench_hybrid.py`` (``--only`` picks some),
planned with this tree. Each segment is ramped by the old and the new module in turn
(the order alternating), ``--repeat`` times each; a call's time is the least of its
runs. The answers must be the same arrays, bit for bit (or both ``None``). Writes
``OUT/bench_ramps.{json,md}``: per-call times (median, mean, total), the median
per-call ratio new / old, and the segments whose answers differ.
"""

from __future__ import annotations

import argparse
import importlib.util
import os
import pickle
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path as FsPath
from types import ModuleType

HERE = FsPath(__file__).resolve().parent
ROOT = HERE.parent
RAMPS = "src/rrtdrive/planning/hybrid/ramps.py"


def record(ids: list[str]) -> list[dict]:
    """The arguments and answer of every ``ramped_segment`` call the plans ``ids`` make."""
    import numpy as np

    import rrtdrive.planning.hybrid.path as hybrid_path

    sys.path.insert(0, str(HERE))
    import bench_hybrid

    calls: list[dict] = []
    current = {"id": ""}
    original = hybrid_path.ramped_segment

    def recording(rows, gear, rate, wheelbase, delta_max, spacing=0.2, angle_weight=0.1):  # noqa: ANN001, ANN202
        args = {
            "rows": np.array(rows, dtype=float), "gear": int(gear), "rate": float(rate),
            "wheelbase": float(wheelbase), "delta_max": float(delta_max),
            "spacing": float(spacing), "angle_weight": float(angle_weight),
        }  # fmt: skip
        out = original(rows, gear, rate, wheelbase, delta_max, spacing, angle_weight)
        calls.append({"query": current["id"], "args": args})
        return out

    hybrid_path.ramped_segment = recording
    try:
        runner = bench_hybrid._Runner(30)
        for qid in ids:
            current["id"] = qid
            runner.run_once(qid)
    finally:
        hybrid_path.ramped_segment = original
    return calls


def _module(path: FsPath, name: str) -> ModuleType:
    spec = importlib.util.spec_from_file_location(name, path)
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _same(a, b) -> bool:  # noqa: ANN001 - arrays or None
    import numpy as np

    if a is None or b is None:
        return a is None and b is None
    return a.shape == b.shape and bool(np.array_equal(a, b))


def bench(calls: list[dict], old: ModuleType, new: ModuleType, repeat: int) -> list[dict]:
    """Per segment: the least time of ``repeat`` runs of each module, interleaved."""
    rows = []
    for k, call in enumerate(calls):
        a = call["args"]
        args = (a["rows"], a["gear"], a["rate"], a["wheelbase"], a["delta_max"], a["spacing"],
                a["angle_weight"])  # fmt: skip
        best = {"old": float("inf"), "new": float("inf")}
        out = {}
        for r in range(repeat):
            order = ("old", "new") if (k + r) % 2 == 0 else ("new", "old")
            for name in order:
                mod = old if name == "old" else new
                t0 = time.perf_counter()
                out[name] = mod.ramped_segment(*args)
                best[name] = min(best[name], time.perf_counter() - t0)
        rows.append({
            "query": call["query"], "pieces_rows": len(a["rows"]), "old_s": best["old"],
            "new_s": best["new"], "same": _same(out["old"], out["new"]),
            "closed": out["new"] is not None,
        })  # fmt: skip
    return rows


def _summary(rows: list[dict]) -> dict:
    old = [r["old_s"] for r in rows]
    new = [r["new_s"] for r in rows]
    return {
        "segments": len(rows),
        "same": sum(r["same"] for r in rows),
        "closed": sum(r["closed"] for r in rows),
        "old_median_ms": 1e3 * statistics.median(old),
        "new_median_ms": 1e3 * statistics.median(new),
        "old_mean_ms": 1e3 * statistics.fmean(old),
        "new_mean_ms": 1e3 * statistics.fmean(new),
        "old_total_s": sum(old),
        "new_total_s": sum(new),
        "median_ratio": statistics.median(n / o for n, o in zip(new, old, strict=True)),
    }


def main(argv: list[str] | None = None) -> int:
    from results_io import json_text, out_folder  # the sibling module (run as a script)

    sys.path.insert(0, str(HERE))
    from bench_hybrid import positive_int  # the sibling script's (no rrtdrive import here)

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--ref", default="d4ad454", help="the old code's commit (default: %(default)s)")
    ap.add_argument("--out", type=out_folder, default="results",
                    help="directory for bench_ramps.json and .md (default: %(default)s)")
    ap.add_argument("--segments", default="",
                    help="pickle of recorded segments (read or write) (default: %(default)s)")
    ap.add_argument("--only", default="",
                    help="comma-separated bench_hybrid query ids (default: %(default)s)")
    ap.add_argument("--repeat", type=positive_int, default=3,
                    help="runs per segment and module (default: %(default)s)")
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    seg_file = FsPath(args.segments) if args.segments else None
    if seg_file is not None and seg_file.is_file():
        calls = pickle.loads(seg_file.read_bytes())
    else:
        sys.path.insert(0, str(HERE))
        import bench_hybrid

        ids = args.only.split(",") if args.only else bench_hybrid.query_ids()
        calls = record(ids)
        if seg_file is not None:
            from rrtdrive.atomic import atomic_target  # this tree's, in the main process

            with atomic_target(seg_file) as tmp:  # whole or not at all (Ctrl-C)
                tmp.write_bytes(pickle.dumps(calls))
    sha = subprocess.run(
        ["git", "rev-parse", args.ref], cwd=ROOT, check=True, capture_output=True, text=True
    ).stdout.strip()
    text = subprocess.run(
        ["git", "show", f"{sha}:{RAMPS}"], cwd=ROOT, check=True, capture_output=True, text=True
    ).stdout
    with tempfile.TemporaryDirectory(prefix="bench_ramps_") as tmp:
        old_file = FsPath(tmp) / "ramps_old.py"
        old_file.write_text(text)
        old = _module(old_file, "ramps_old")
        new = _module(ROOT / RAMPS, "ramps_new")
        rows = bench(calls, old, new, args.repeat)
    summary = _summary(rows)
    head = subprocess.run(
        ["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, check=True, capture_output=True,
        text=True,
    ).stdout.strip()  # fmt: skip
    dirty = subprocess.run(
        ["git", "status", "--porcelain", RAMPS], cwd=ROOT, capture_output=True, text=True
    ).stdout.strip()
    meta = {
        "command": "python experiments/bench_ramps.py " + " ".join(sys.argv[1:]),
        "ref": args.ref, "ref_sha": sha, "repeat": args.repeat,
        "new": f"this tree at {head}" + (" with uncommitted changes in ramps.py" if dirty else ""),
        "machine": f"{platform.machine()} {os.cpu_count()} CPUs, "
        f"Python {platform.python_version()}",
        "load": " ".join(f"{v:.1f}" for v in os.getloadavg()),
        "wall_s": time.perf_counter() - t0,
    }  # fmt: skip
    out = FsPath(args.out)
    out.mkdir(parents=True, exist_ok=True)
    from rrtdrive.atomic import write_text_atomic

    write_text_atomic(
        out / "bench_ramps.json",
        json_text({"meta": meta, "summary": summary, "segments": rows}),
    )
    s = summary
    lines = [
        "# ramped_segment: old code against new, same segments, same answers",
        "",
        f"Command: `{meta['command']}`  ",
        f"Old: ramps.py of {args.ref} ({sha[:10]}); new: {meta['new']}. {meta['machine']}, "
        f"load {meta['load']}. A call's time is the least of {args.repeat} runs, old and new "
        "interleaved segment by segment.",
        "",
        "| segments | same answer (bit for bit) | closed | old median [ms] | new median [ms] "
        "| median ratio new/old | old mean [ms] | new mean [ms] | old total [s] | new total [s] |",
        "|---|---|---|---|---|---|---|---|---|---|",
        f"| {s['segments']} | {s['same']} | {s['closed']} | {s['old_median_ms']:.3f} "
        f"| {s['new_median_ms']:.3f} | {s['median_ratio']:.3f} | {s['old_mean_ms']:.3f} "
        f"| {s['new_mean_ms']:.3f} | {s['old_total_s']:.2f} | {s['new_total_s']:.2f} |",
        "",
        f"Segments whose answers differ: {s['segments'] - s['same']}.",
    ]
    lines += [f"- segment {k} of `{r['query']}`" for k, r in enumerate(rows) if not r["same"]]
    write_text_atomic(out / "bench_ramps.md", "\n".join(lines) + "\n")
    print(f"{s['segments']} segments, {s['same']} same; median {s['old_median_ms']:.3f} -> "
          f"{s['new_median_ms']:.3f} ms, mean {s['old_mean_ms']:.3f} -> {s['new_mean_ms']:.3f} ms, "
          f"median ratio {s['median_ratio']:.3f}")  # fmt: skip
    return 0 if s["same"] == s["segments"] else 1


if __name__ == "__main__":
    from results_io import run_main

    raise SystemExit(run_main(main))
