"""The independent check's cost (``verify_path``) on planned paths, old code against new.

Usage::

    # This tree alone
    python experiments/bench_verify.py --out results
    # This tree against the code of commit REF, in turns
    python experiments/bench_verify.py --ref f7b2980 --out results

The paths: ``rrtdrive plan MAP --seed S`` (this tree, the default planner; with
``--reverse`` for the maps of ``--reverse-maps``) for every map and seed, planned once
and saved as plan JSON. Each tree then checks the same paths in a fresh worker
process that imports its own ``rrtdrive`` (``src/`` of ``REF`` exported as
:mod:`bench_hybrid` does), ``--repeat`` rounds, the trees taking turns going first.
A path's time is the least CPU time (``time.process_time``) of its ``verify_path``
calls; the verdicts of both trees are compared field by field. Writes
``OUT/bench_verify.{json,md}``.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path as FsPath

HERE = FsPath(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import bench_hybrid  # noqa: E402  (the export of an old tree, provenance, results)
from results_io import out_folder, run_main  # noqa: E402


def _worker(plans_file: str, repeat: int) -> int:
    """Check every plan of ``plans_file`` ``repeat`` times; print one JSON answer."""
    import dataclasses

    from rrtdrive.maps import builtin_map
    from rrtdrive.verify import path_from_json, verify_path

    plans = json.loads(FsPath(plans_file).read_text())
    answers = []
    for item in plans:
        m, path = builtin_map(item["map"]), path_from_json(item["plan"])
        best = float("inf")
        for _ in range(repeat):
            t0 = time.process_time()
            check = verify_path(m, path)
            best = min(best, time.process_time() - t0)
        verdict = json.loads(json.dumps(dataclasses.asdict(check), default=str))
        answers.append({"id": item["id"], "cpu_s": best, "verdict": verdict})
    print(json.dumps(answers))
    return 0


def _plans(maps: list[str], seeds: int, reverse_maps: set[str], into: FsPath) -> list[dict]:
    from rrtdrive.cli import main as cli_main

    plans = []
    for name in maps:
        for seed in range(seeds):
            out = into / f"{name}_{seed}.json"
            argv = ["plan", name, "--seed", str(seed), "--json", str(out)]
            if name in reverse_maps:
                argv.append("--reverse")
            with contextlib.redirect_stdout(io.StringIO()):  # its one-line summaries
                code = cli_main(argv)
            if code == 0:
                plan = json.loads(out.read_text())
                plans.append({"id": f"{name}:{seed}", "map": name, "plan": plan,
                              "rows": len(plan["path"])})  # fmt: skip
    return plans


def _run(src: FsPath, plans_file: FsPath, repeat: int) -> dict[str, dict]:
    env = {**os.environ, "PYTHONPATH": str(src), "OMP_NUM_THREADS": "1"}
    argv = [sys.executable, __file__, "--worker", str(plans_file), "--repeat", str(repeat)]
    done = subprocess.run(argv, env=env, capture_output=True, text=True, check=True)
    return {a["id"]: a for a in json.loads(done.stdout.strip().splitlines()[-1])}


def _markdown(meta: dict, rows: list[dict], summary: dict) -> str:
    old = meta["ref"] is not None
    lines = [
        "# The independent check's cost: `verify_path` per planned path",
        "",
        f"Command: `{meta['command']}`  ",
        bench_hybrid.provenance_line(meta) + ".",
        "",
        f"Per path the least CPU time of its check over {meta['repeat']} calls in each of "
        f"{meta['rounds']} rounds (fresh worker processes, the trees taking turns).",
        "",
    ]
    if old:
        lines += ["| map | paths | rows (median) | old [ms] | new [ms] | ratio new/old "
                  "| same verdicts |", "|---|---|---|---|---|---|---|"]  # fmt: skip
    else:
        lines += ["| map | paths | rows (median) | CPU [ms] |", "|---|---|---|---|"]
    for name, g in summary["maps"].items():
        cells = [name, str(g["paths"]), f"{g['rows_median']:.0f}"]
        if old:
            cells += [f"{g['old_ms']:.2f}", f"{g['new_ms']:.2f}", f"{g['ratio']:.3f}",
                      f"{g['same']}/{g['paths']}"]  # fmt: skip
        else:
            cells.append(f"{g['new_ms']:.2f}")
        lines.append("| " + " | ".join(cells) + " |")
    if old:
        lines += ["", f"Median ratio new/old over all {len(rows)} paths: "
                      f"**{summary['ratio']:.3f}**; verdicts the same: "
                      f"{summary['same']}/{len(rows)}."]  # fmt: skip
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--ref", default=None, help="the old code's commit (default: no comparison)")
    ap.add_argument("--out", default="results", type=out_folder,
                    help="directory of bench_verify.{json,md} (default: %(default)s)")
    ap.add_argument("--maps", default="parking_lot,overtake,narrow_gap,garage,kerbside,reverse_bay",
                    help="comma-separated built-in maps (default: %(default)s)")  # fmt: skip
    ap.add_argument("--reverse-maps", default="garage,kerbside,reverse_bay",
                    help="maps planned with --reverse (default: %(default)s)")  # fmt: skip
    ap.add_argument("--seeds", type=bench_hybrid.positive_int, default=5,
                    help="seeds per map (default: %(default)s)")
    ap.add_argument("--rounds", type=bench_hybrid.positive_int, default=3,
                    help="worker processes per tree, taking turns"
                         " (default: %(default)s)")  # fmt: skip
    ap.add_argument("--repeat", type=bench_hybrid.positive_int, default=3,
                    help="checks per path in a worker; its time: the least"
                         " (default: %(default)s)")  # fmt: skip
    ap.add_argument("--worker", default=None, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.worker:
        return _worker(args.worker, args.repeat)
    from rrtdrive.maps import BUILTIN_MAPS

    for option, names in (("--maps", args.maps), ("--reverse-maps", args.reverse_maps)):
        unknown = [n for n in names.split(",") if n not in BUILTIN_MAPS]
        if unknown:
            ap.error(f"{option}: unknown map(s) {unknown}; built-ins are {sorted(BUILTIN_MAPS)}")
    load_before = round(os.getloadavg()[0], 2)
    with tempfile.TemporaryDirectory(prefix="bench_verify_") as tmp:
        root = FsPath(tmp)
        (root / "plans").mkdir()
        plans = _plans(args.maps.split(","), args.seeds, set(args.reverse_maps.split(",")),
                       root / "plans")  # fmt: skip
        plans_file = root / "plans.json"
        plans_file.write_text(json.dumps(plans))
        trees = {}
        for name, ref in (("new", None), ("old", args.ref)):
            if name == "new" or ref:
                (root / name).mkdir()
                trees[name] = bench_hybrid._export(ref, root / name)
        best: dict[str, dict[str, dict]] = {name: {} for name in trees}
        for r in range(args.rounds):
            order = list(trees) if r % 2 == 0 else list(trees)[::-1]
            for name in order:
                for qid, a in _run(trees[name], plans_file, args.repeat).items():
                    prev = best[name].get(qid)
                    if prev is None or a["cpu_s"] < prev["cpu_s"]:
                        best[name][qid] = a
            print(f"round {r + 1}/{args.rounds} done", flush=True)
    rows = []
    for p in plans:
        row = {"id": p["id"], "map": p["map"], "rows": p["rows"],
               "new_cpu_s": best["new"][p["id"]]["cpu_s"],
               "ok": best["new"][p["id"]]["verdict"]["ok"]}  # fmt: skip
        if args.ref:
            row["old_cpu_s"] = best["old"][p["id"]]["cpu_s"]
            row["ratio"] = row["new_cpu_s"] / row["old_cpu_s"]
            row["same"] = best["old"][p["id"]]["verdict"] == best["new"][p["id"]]["verdict"]
        rows.append(row)
    summary: dict = {"maps": {}}
    for name in dict.fromkeys(r["map"] for r in rows):
        g = [r for r in rows if r["map"] == name]
        s = {"paths": len(g), "rows_median": statistics.median(r["rows"] for r in g),
             "new_ms": 1e3 * statistics.median(r["new_cpu_s"] for r in g)}  # fmt: skip
        if args.ref:
            s["old_ms"] = 1e3 * statistics.median(r["old_cpu_s"] for r in g)
            s["ratio"] = statistics.median(r["ratio"] for r in g)
            s["same"] = sum(r["same"] for r in g)
        summary["maps"][name] = s
    if args.ref:
        summary["ratio"] = statistics.median(r["ratio"] for r in rows)
        summary["same"] = sum(r["same"] for r in rows)
    meta = {
        "command": "python experiments/bench_verify.py "
        + " ".join(sys.argv[1:] if argv is None else argv),
        "machine": bench_hybrid.machine(), "repeat": args.repeat, "rounds": args.rounds,
        "load_before": load_before, "load_after": round(os.getloadavg()[0], 2),
        **(bench_hybrid.provenance(args.ref) if args.ref else
           {"ref": None, "ref_sha": None, "new": "this tree"}),
    }  # fmt: skip
    text = _markdown(meta, rows, summary)
    bench_hybrid.write_results(args.out, "bench_verify",
                               {"meta": meta, "summary": summary, "rows": rows}, text)  # fmt: skip
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(run_main(main))  # Ctrl-C: one line and exit 130, no traceback
