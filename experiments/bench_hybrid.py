"""Hybrid A* speed, old code against new, on the same queries, with the answers compared.

Usage::

    # Interleaved benchmark: this tree against the code of commit REF (old), query by query
    python experiments/bench_hybrid.py --ref 2bf6e48 --out results
    # Equivalence only: record this tree's answers, later check a changed tree against them
    python experiments/bench_hybrid.py --record /tmp/hybrid_base.pkl
    python experiments/bench_hybrid.py --check /tmp/hybrid_base.pkl
    # Map files of your own (paths from the repository's root), with or without reverse
    python experiments/bench_hybrid.py --ref d623b82 --out results/hybrid_tail_s24 \
        --only file:rev:results/hybrid_tail_s24/maps/fz865.json,file:fwd:results/...

The queries: ``parking_lot`` with the 30 random goal poses and the 30 random start
poses of :func:`random_goals.draw_goals` (seed 1), each planned by ``hybrid-a-star``
forward-only and with reverse (120 plans), and the gear scenarios
``parking-reverse-in``, ``parallel-parking`` and ``u-turn`` (seeds 0..9, reverse as
the task says: 30 plans). Every plan has a counted budget (20 000 expansions; the
wall-clock cap is 1e6 s), so its answer does not depend on the machine's load.

Two answers are *the same* when the status, the message, the expansions, the nodes
and the path rows (to 1e-9) agree. The benchmark runs the old code (a ``git
archive`` of ``REF``'s ``src/``, imported in a worker process) and this tree in
another worker, alternating query by query, and writes
``OUT/bench_hybrid.{json,md}``: per query both planning times and whether the
answers agree; total and median times and the median per-query ratio new / old.

Exit status: 0 when every answer agrees, 1 when any differs (the old and the new code
plan differently: expected when ``REF`` predates a change of answers, as the default
``--ref`` does today), 2 for bad input.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import os
import pickle
import statistics
import subprocess
import sys
import tarfile
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path as FsPath

HERE = FsPath(__file__).resolve().parent
ROOT = HERE.parent

#: The gear scenarios and their seeds.
SCENARIOS = ("parking-reverse-in", "parallel-parking", "u-turn")
SEEDS = range(10)
#: The query each worker runs first, untimed (imports, caches, the map's set-up).
WARM = "goal:rev:7"


def positive_int(text: str) -> int:
    """An argparse type: an integer >= 1 (not rrtdrive's: a worker imports an old tree)."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer >= 1, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected an integer >= 1, got {value}")
    return value


def warm_query(count: int) -> str:
    """The warm-up query (:data:`WARM`), or the last goal of a smaller ``--count``."""
    return f"goal:rev:{min(7, count - 1)}"
#: Path rows agree to this (metres / radians / 1/m).
ROW_TOL = 1e-9


def query_ids(count: int = 30, seeds: int = len(SEEDS)) -> list[str]:
    """Every query's id: ``goal:rev:3``, ``start:fwd:12``, ``u-turn:4``."""
    out = [
        f"{vary}:{gear}:{i}"
        for vary in ("goal", "start")
        for gear in ("fwd", "rev")
        for i in range(count)
    ]
    out += [f"{name}:{seed}" for name in SCENARIOS for seed in range(seeds)]
    return out


class _Runner:
    """Plans queries by id with the ``rrtdrive`` this process imports."""

    def __init__(self, count: int) -> None:
        sys.path.insert(0, str(HERE))
        from random_goals import draw_goals

        self.draws = {v: draw_goals("parking_lot", count, 1, v) for v in ("goal", "start")}

    def problem(self, qid: str):  # noqa: ANN201 - a PlanningProblem of either tree
        from rrtdrive.maps import builtin_map
        from rrtdrive.planning import PlanningProblem
        from rrtdrive.sim.tasks import make_scenario

        if qid.startswith("file:"):  # file:rev:MAP.json, a map file's own start and goal
            from rrtdrive.maps import load_map

            _, gear, name = qid.split(":", 2)
            return PlanningProblem.from_map(load_map(ROOT / name), reverse=gear == "rev")
        parts = qid.split(":")
        if len(parts) == 3:
            vary, gear, i = parts
            m = dataclasses.replace(builtin_map("parking_lot"), **{vary: self.draws[vary][int(i)]})
            return PlanningProblem.from_map(m, reverse=gear == "rev")
        name, seed = parts
        if name == "parking-reverse-in":
            task = make_scenario("parking", int(seed), reverse_in=True)
        else:
            task = make_scenario(name, int(seed))
        return PlanningProblem.from_map(task.map, reverse=task.reverse)

    def run(self, qid: str, repeat: int = 1) -> dict:
        """The answer to ``qid``; its times the least of ``repeat`` runs (answers checked equal)."""
        out = self.run_once(qid)
        for _ in range(repeat - 1):
            again = self.run_once(qid)
            same, why = same_answer(out, again)
            if not same:
                raise RuntimeError(f"{qid}: a repeated run answered differently ({why})")
            out["time_s"] = min(out["time_s"], again["time_s"])
            out["cpu_s"] = min(out["cpu_s"], again["cpu_s"])
        return out

    #: The planner run, and its wall-clock cap (a safety cap: the budgets are counted).
    PLANNER = "hybrid-a-star"
    MAX_TIME_S = 1e6

    def compared(self, res) -> dict:  # noqa: ANN001 - a PlanResult of either tree
        """The answer's ``message`` and ``nodes``, as compared between old and new code."""
        return {"message": res.message, "nodes": int(res.nodes)}

    def run_once(self, qid: str) -> dict:
        import numpy as np

        from rrtdrive.planning import make_planner
        from rrtdrive.types import Budget

        problem = self.problem(qid)
        problem.checker.component_labels  # noqa: B018 - per-map set-up, outside the timing
        planner = make_planner(self.PLANNER)
        cpu = time.process_time()
        res = planner.solve(problem, np.random.default_rng(0), Budget(max_time_s=self.MAX_TIME_S))
        cpu = time.process_time() - cpu
        rows = None if res.path is None else np.asarray(res.path.samples, dtype=float).tolist()
        return {
            "id": qid,
            "status": res.status.value,
            "iterations": int(res.iterations),
            **self.compared(res),
            "time_s": float(res.planning_time_s),
            "cpu_s": cpu,
            "rows": rows,
        }


def same_answer(a: dict, b: dict) -> tuple[bool, str]:
    """Whether two answers agree (status, message, counts, rows to :data:`ROW_TOL`)."""
    for key in ("status", "message", "iterations", "nodes"):
        if a[key] != b[key]:
            return False, f"{key}: {a[key]!r} != {b[key]!r}"
    ra, rb = a["rows"], b["rows"]
    if (ra is None) != (rb is None):
        return False, "one has a path"
    if ra is None:
        return True, ""
    if len(ra) != len(rb):
        return False, f"rows: {len(ra)} != {len(rb)}"
    worst = max(
        (abs(x - y) for r, s in zip(ra, rb, strict=True) for x, y in zip(r, s, strict=True)),
        default=0.0,
    )
    if not worst <= ROW_TOL:
        return False, f"rows differ by {worst:.3g}"
    return True, ""


def _worker(count: int, repeat: int, warm: str, runner_cls: type[_Runner] = _Runner) -> int:
    """Answer query ids read from stdin, one JSON line each, on stdout."""
    import rrtdrive

    runner = runner_cls(count)
    runner.run(warm)  # imports, caches and the map's set-up: not in the first query's time
    print(json.dumps({"ready": str(FsPath(rrtdrive.__file__).resolve())}), flush=True)
    for line in sys.stdin:
        qid = line.strip()
        if not qid:
            continue
        print(json.dumps(runner.run(qid, repeat)), flush=True)
    return 0


class _Worker:
    """A worker process importing ``rrtdrive`` from ``src``."""

    def __init__(
        self, src: FsPath, count: int, repeat: int, warm: str, script: FsPath = FsPath(__file__)
    ) -> None:
        env = dict(os.environ, PYTHONPATH=str(src))
        # ``script`` (this one or a sibling built on it) answers in its --worker mode.
        cmd = [sys.executable, str(script.resolve()), "--worker", "--count", str(count)]
        cmd += ["--repeat", str(repeat), "--warm", warm]
        self.proc = subprocess.Popen(
            cmd,
            stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True, env=env, cwd=str(ROOT),
        )  # fmt: skip
        ready = json.loads(self.ask_line())
        self.module = ready["ready"]
        if not self.module.startswith(str(src.resolve())):
            raise RuntimeError(f"worker imported {self.module}, not from {src}")

    def ask_line(self) -> str:
        assert self.proc.stdout is not None
        line = self.proc.stdout.readline()
        if not line:
            raise RuntimeError("worker died")
        return line

    def run(self, qid: str) -> dict:
        assert self.proc.stdin is not None
        self.proc.stdin.write(qid + "\n")
        self.proc.stdin.flush()
        return json.loads(self.ask_line())

    def close(self) -> None:
        assert self.proc.stdin is not None
        self.proc.stdin.close()
        self.proc.wait()


#: Packages that live beside ``src/`` and are installed as ``rrtdrive.<name>``.
_TOP_LEVEL = ("controllers", "envs")


def _export(ref: str | None, into: FsPath) -> FsPath:
    """The package of commit ``ref`` (``None``: this working tree) laid out as installed.

    ``src/`` and the top-level ``controllers/`` and ``envs/`` (installed as
    ``rrtdrive.controllers`` and ``rrtdrive.envs``) go into ``into/src/rrtdrive``, so a
    worker importing from ``into/src`` reads every module from ``ref``: with ``src/``
    alone, an installed package supplied today's ``controllers/`` to old code (an
    ImportError) and a non-editable install lacked them for ``src/`` altogether.
    """
    import shutil

    if ref is None:
        skip = shutil.ignore_patterns("__pycache__", "*.pyc")
        shutil.copytree(ROOT / "src", into / "src", ignore=skip)
        for name in _TOP_LEVEL:
            target = into / "src" / "rrtdrive" / name
            if (ROOT / name).is_dir() and not target.exists():
                shutil.copytree(ROOT / name, target, ignore=skip)
        return into / "src"
    present = [
        name for name in ("src", *_TOP_LEVEL)
        if subprocess.run(["git", "cat-file", "-e", f"{ref}:{name}"], cwd=ROOT,
                          capture_output=True).returncode == 0
    ]  # fmt: skip
    data = subprocess.run(
        ["git", "archive", ref, *present], cwd=ROOT, check=True, capture_output=True
    ).stdout
    tar = into / "src.tar"
    tar.write_bytes(data)
    with tarfile.open(tar) as t:
        t.extractall(into, filter="data")
    for name in present[1:]:
        target = into / "src" / "rrtdrive" / name
        if not target.exists():  # older commits kept them inside src/rrtdrive already
            (into / name).rename(target)
    return into / "src"


def _median(v: list[float]) -> float:
    return statistics.median(v) if v else math.nan


def _group(qid: str) -> str:
    parts = qid.split(":")
    return f"{parts[0]}s {parts[1]}" if len(parts) == 3 else "gear scenarios"


def _summary(rows: list[dict]) -> dict:
    groups: dict[str, list[dict]] = {}
    for r in rows:
        groups.setdefault(_group(r["id"]), []).append(r)
    groups["all"] = rows
    out = {}
    for name, g in groups.items():
        old = [r["old_s"] for r in g]
        new = [r["new_s"] for r in g]
        old_cpu = [r["old_cpu_s"] for r in g]
        new_cpu = [r["new_cpu_s"] for r in g]
        out[name] = {
            "queries": len(g),
            "same": sum(r["same"] for r in g),
            "solved": sum(r["status"] == "solved" for r in g),
            "old_total_s": sum(old),
            "new_total_s": sum(new),
            "old_median_ms": 1e3 * _median(old),
            "new_median_ms": 1e3 * _median(new),
            "median_ratio": _median([n / o for n, o in zip(new, old, strict=True) if o > 0]),
            "old_cpu_total_s": sum(old_cpu),
            "new_cpu_total_s": sum(new_cpu),
            "cpu_median_ratio": _median(
                [n / o for n, o in zip(new_cpu, old_cpu, strict=True) if o > 0]
            ),
        }
    return out


def _markdown(meta: dict, summary: dict, rows: list[dict]) -> str:
    lines = [
        "# Hybrid A*: old code against new, same queries, same answers",
        "",
        f"Command: `{meta['command']}`  ",
        f"Old: `src/` of {meta['ref']} ({meta['ref_sha'][:10]}); new: {meta['new']}. "
        f"{meta['machine']}, load {meta['load']}; wall time {meta['wall_s'] / 60:.1f} min. "
        "Planning time excludes the per-map set-up; the budget is counted (20 000 "
        "expansions), so the answers do not depend on load.",
        "",
        "Times are the planner's `planning_time_s` (wall clock); the CPU columns are the "
        "worker's process time of the whole `solve` call (less sensitive to load).",
        "",
        "| queries | n | same answer | solved | old total [s] | new total [s] "
        "| old median [ms] | new median [ms] | median ratio new/old "
        "| CPU total old / new [s] | CPU median ratio |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for name, s in summary.items():
        lines.append(
            f"| {name} | {s['queries']} | {s['same']} | {s['solved']} | {s['old_total_s']:.2f} "
            f"| {s['new_total_s']:.2f} | {s['old_median_ms']:.1f} | {s['new_median_ms']:.1f} "
            f"| {s['median_ratio']:.3f} | {s['old_cpu_total_s']:.2f} / "
            f"{s['new_cpu_total_s']:.2f} | {s['cpu_median_ratio']:.3f} |"
        )
    diff = [r for r in rows if not r["same"]]
    lines += ["", f"Queries whose answers differ: {len(diff)}."]
    for r in diff:
        lines.append(f"- `{r['id']}`: {r['why']}")
    lines += [
        "",
        "| query | status | expansions | old [ms] | new [ms] | ratio |",
        "|---|---|---|---|---|---|",
    ]
    for r in rows:
        ratio = r["new_s"] / r["old_s"] if r["old_s"] > 0 else math.nan
        lines.append(
            f"| {r['id']} | {r['status']} | {r['iterations']} | {1e3 * r['old_s']:.1f} "
            f"| {1e3 * r['new_s']:.1f} | {ratio:.3f} |"
        )
    return "\n".join(lines) + "\n"


def provenance(ref: str) -> dict:
    """The old code's commit (``ref``, ``ref_sha``) and what "new" is (this tree)."""

    def git(*cmd: str) -> str:
        return subprocess.run(
            ["git", *cmd], cwd=ROOT, check=True, capture_output=True, text=True
        ).stdout.strip()

    head, dirty = git("rev-parse", "--short", "HEAD"), git("status", "--porcelain", "src")
    new = f"this tree at {head}" + (" with uncommitted changes in src/" if dirty else "")
    return {"ref": ref, "ref_sha": git("rev-parse", ref), "new": new}


def provenance_line(meta: dict) -> str:
    """``New: ...; old: `src/` of REF (sha). MACHINE, load before / after A / B``."""
    old = (
        f"; old: `src/` of {meta['ref']} ({meta['ref_sha'][:10]})" if meta["ref"] is not None
        else ""
    )  # fmt: skip
    return (
        f"New: {meta['new']}{old}. {meta['machine']}, load before / after "
        f"{meta['load_before']} / {meta['load_after']}"
    )


def interleaved(
    sha: str, ids: list[str], count: int, repeat: int, warm: str, script: FsPath
) -> Iterator[tuple[str, dict, dict, bool, str]]:
    """``(qid, old answer, new answer, same, why)`` per query: commit ``sha``'s ``src/``
    against this tree's, each in a worker running ``script``, taking turns going first."""
    with tempfile.TemporaryDirectory(prefix=f"{script.stem}_") as tmp:
        (FsPath(tmp) / "old").mkdir()
        (FsPath(tmp) / "new").mkdir()
        old = _Worker(_export(sha, FsPath(tmp) / "old"), count, repeat, warm, script)
        new = _Worker(_export(None, FsPath(tmp) / "new"), count, repeat, warm, script)
        try:
            for n, qid in enumerate(ids):
                # Alternate which runs first, so neither always meets a warm cache.
                pair = (old, new) if n % 2 == 0 else (new, old)
                got = {id(w): w.run(qid) for w in pair}
                a, b = got[id(old)], got[id(new)]
                yield (qid, a, b, *same_answer(a, b))
        finally:
            old.close()
            new.close()


def write_results(out: str, name: str, payload: dict, text: str) -> None:
    """``OUT/NAME.json`` and ``OUT/NAME.md``, each written whole (temp file, then rename)."""
    # The sibling module imports this tree's rrtdrive: in the main process only.
    import results_io

    results_io.write_results(out, name, payload, lambda _: text)


def machine() -> str:
    """This machine, for a results page (the sibling module's line)."""
    import results_io  # imports this tree's rrtdrive: in the main process only

    return results_io.machine()


def _bench(args: argparse.Namespace, ids: list[str]) -> int:
    t0 = time.perf_counter()
    meta = provenance(args.ref)
    rows = []
    for qid, a, b, same, why in interleaved(
        meta["ref_sha"], ids, args.count, args.repeat, warm_query(args.count),
        FsPath(__file__),
    ):
        rows.append({
            "id": qid, "status": b["status"], "iterations": b["iterations"],
            "old_s": a["time_s"], "new_s": b["time_s"], "old_cpu_s": a["cpu_s"],
            "new_cpu_s": b["cpu_s"], "same": same, "why": why,
        })  # fmt: skip
        print(f"{qid:24s} {b['status']:20s} old {1e3 * a['time_s']:8.1f} ms  new "
              f"{1e3 * b['time_s']:8.1f} ms  {'same' if same else 'DIFFERENT ' + why}",
              flush=True)  # fmt: skip
    summary = _summary(rows)
    meta = {
        "command": "python experiments/bench_hybrid.py " + " ".join(sys.argv[1:]),
        **meta,
        "machine": machine(),
        "load": " ".join(f"{v:.1f}" for v in os.getloadavg()),
        "wall_s": time.perf_counter() - t0,
    }
    payload = {"meta": meta, "summary": summary, "queries": rows}
    write_results(args.out, "bench_hybrid", payload, _markdown(meta, summary, rows))
    for name, s in summary.items():
        print(f"{name}: same {s['same']}/{s['queries']}, total {s['old_total_s']:.2f} -> "
              f"{s['new_total_s']:.2f} s, median {s['old_median_ms']:.1f} -> "
              f"{s['new_median_ms']:.1f} ms, median ratio {s['median_ratio']:.3f} "
              f"(CPU {s['cpu_median_ratio']:.3f})")  # fmt: skip
    return 0 if all(r["same"] for r in rows) else 1


def main(argv: list[str] | None = None) -> int:
    from results_io import out_folder  # the sibling module (run as a script)

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--ref", default="2bf6e48", help="the old code's commit (default: %(default)s)")
    ap.add_argument("--out", type=out_folder, default="results",
                    help="directory for bench_hybrid.json and .md (default: %(default)s)")
    ap.add_argument("--count", type=positive_int, default=30,
                    help="random goals and starts each (default: %(default)s)")
    ap.add_argument("--seeds", type=positive_int, default=len(SEEDS),
                    help="seeds per gear scenario (default: %(default)s)")
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
        return _worker(args.count, args.repeat, args.warm or warm_query(args.count))
    ids = args.only.split(",") if args.only else query_ids(args.count, args.seeds)
    if not (args.record or args.check):
        return _bench(args, ids)
    runner = _Runner(args.count)
    runner.run(warm_query(args.count))
    base = pickle.loads(FsPath(args.check).read_bytes()) if args.check else {}
    got, bad, total = {}, 0, 0.0
    for qid in ids:
        r = runner.run(qid, args.repeat)
        got[qid] = r
        total += r["time_s"]
        note = ""
        if args.check:
            same, why = same_answer(base[qid], r)
            bad += not same
            note = f"old {1e3 * base[qid]['time_s']:8.1f} ms  "
            note += "same" if same else "DIFF " + why
        print(f"{qid:24s} {r['status']:20s} {r['iterations']:6d} {1e3 * r['time_s']:8.1f} ms  "
              f"{note}", flush=True)  # fmt: skip
    if args.record:
        from rrtdrive.atomic import atomic_target  # this tree's, in the main process

        with atomic_target(args.record) as tmp:  # whole or not at all (Ctrl-C)
            tmp.write_bytes(pickle.dumps(got))
    print(f"total planning {total:.2f} s" + (f"; {bad} answers differ" if args.check else ""))
    return 1 if bad else 0


if __name__ == "__main__":
    from results_io import run_main

    raise SystemExit(run_main(main))
