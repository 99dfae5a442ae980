"""Session 51 audit: rrtdrive under concurrency, as a user running several things at once.

Threads planning on one shared map (README's "Threads may plan on one map") and on a
checker each, ``cached_checker`` asked from many threads, the library's other users of
the shared checker (``random_free_poses``, the footprint judge ``map_collision``), atomic
outputs written from threads, several CLI processes writing one file, ``bench
--jobs 2`` against ``--jobs 1``, two benches in one folder, and SIGTERM / Ctrl-C of a
bench with worker processes. A crash of the interpreter (GEOS is not thread-safe) is
observed in a child process; every wait is bounded. The four bugs it found (two
SIGSEGVs, the umask read, a bench's plots after its lock) were fixed in session 51.
"""

from __future__ import annotations

import csv
import dataclasses
import json
import os
import re
import signal
import subprocess
import sys
import textwrap
import threading
import time
from pathlib import Path

import pytest

from rrtdrive import builtin_map
from rrtdrive.collision import CheckerConfig, CollisionChecker
from rrtdrive.planning import checker_cache
from rrtdrive.planning.base import cached_checker

PY = sys.executable


def _python(
    code: str, timeout: float = 90.0, cwd: Path | None = None
) -> subprocess.CompletedProcess:
    """Run ``code`` in a fresh interpreter (a segfault is its exit status, not ours)."""
    return subprocess.run([PY, "-c", textwrap.dedent(code)], capture_output=True, text=True,
                          timeout=timeout, cwd=cwd)  # fmt: skip


def _cli(*args: str) -> list[str]:
    return [PY, "-m", "rrtdrive", *args]


def _untimed(doc: dict) -> dict:
    """A result without its wall-clock measurements."""
    return {k: v for k, v in doc.items() if not k.endswith("_time_s") and k != "wall_time_s"}


def _hidden_leftovers(folder: Path) -> list[str]:
    """Hidden files other than a bench's lock: an atomic write's temporary left behind."""
    return sorted(p.name for p in folder.iterdir() if p.name.startswith(".") and p.name != ".lock")


# ------------------------------------------------------------------ Python API, threads

_JOBS = """
import json, sys, threading, time
import numpy as np
from rrtdrive import Budget, builtin_map
from rrtdrive.collision import CollisionChecker
from rrtdrive.planning import PlanningProblem, make_planner
# (map, planner, seed, reverse): Hybrid A* (its Dubins tables and ramp caches are
# per process), the improved planner with reverse, a tree baseline.
JOBS = [("reverse_bay", "hybrid-a-star", 0, True), ("kerbside", "hybrid-a-star", 1, True),
        ("garage", "improved-rrt-connect", 2, True), ("turning_bulb", "hybrid-a-star", 3, True),
        ("narrow_gap", "rrt-star", 4, False), ("dead_end", "improved-rrt-connect", 5, True),
        ("parking_lot", "improved-rrt-connect", 6, False)]
def run(job, problem):
    name, planner, seed, rev = job
    r = make_planner(planner).solve(problem, np.random.default_rng(seed),
                                    Budget(max_iterations=3000))
    rows = r.path.samples.tobytes() if r.path is not None else b""
    return r.status.value, rows, r.iterations
def fresh(job):  # a checker of its own: the query as it runs alone
    m = builtin_map(job[0])
    return PlanningProblem(m, CollisionChecker.for_map(m), m.start, m.goal, reverse=job[3])
def shared(job):  # README's recipe: the process's checker of the map
    return PlanningProblem.from_map(builtin_map(job[0]), reverse=job[3])
serial = [run(j, fresh(j)) for j in JOBS]
def threaded(make, threads=3, rounds=2):
    out, errors = {}, []
    def work(k):
        try:
            for r in range(rounds):
                for i in range(len(JOBS)):
                    j = (i + k + r) % len(JOBS)  # each thread in another order
                    out[k, r, j] = run(JOBS[j], make(JOBS[j]))
        except BaseException as exc:
            errors.append(repr(exc))
    ts = [threading.Thread(target=work, args=(k,), daemon=True) for k in range(threads)]
    [t.start() for t in ts]
    deadline = time.monotonic() + 60
    for t in ts:
        t.join(max(0.0, deadline - time.monotonic()))
    hung = sum(t.is_alive() for t in ts)
    same = all(out.get((k, r, j)) == serial[j]
               for k in range(threads) for r in range(rounds) for j in range(len(JOBS)))
    return {"hung": hung, "errors": errors, "same": same, "runs": len(out)}
"""


@pytest.fixture(scope="module")
def thread_plans() -> dict:
    """Three threads × all jobs × two rounds: one shared checker per map, a checker each."""
    done = _python(_JOBS + textwrap.dedent("""
        print(json.dumps({"shared": threaded(shared), "own": threaded(fresh),
                          "statuses": [s[0] for s in serial]}))
    """))
    assert done.returncode == 0, f"exit {done.returncode}: {done.stderr[-1500:]}"
    return json.loads(done.stdout.strip().splitlines()[-1])


def test_the_thread_jobs_are_real_plans(thread_plans):
    # Every job plans a path (else equality below would compare failures only).
    assert thread_plans["statuses"] == ["solved"] * 7


@pytest.mark.parametrize("how", ["shared", "own"])
def test_threads_plan_bit_for_bit_as_each_query_alone(thread_plans, how):
    report = thread_plans[how]
    assert report["hung"] == 0 and report["errors"] == []
    assert report["runs"] == 3 * 2 * 7
    assert report["same"], f"{how}: a threaded plan differs from the same query run alone"


def test_cached_checker_from_many_threads_builds_once(monkeypatch):
    """Eight threads asking at once for a map nobody asked for yet: one build, one object."""
    builds: list[int] = []
    real = CollisionChecker.for_map.__func__

    def slow_for_map(cls, m, *args, **kwargs):
        builds.append(threading.get_ident())
        time.sleep(0.2)  # widen the window in which the others ask
        return real(cls, m, *args, **kwargs)

    monkeypatch.setattr(CollisionChecker, "for_map", classmethod(slow_for_map))
    m = builtin_map("narrow_gap")
    config = CheckerConfig(margin=0.0123)  # a key no other test has cached
    gate = threading.Barrier(8)
    got: list[object] = []

    def ask():
        gate.wait(timeout=10)
        got.append(cached_checker(m, config))

    threads = [threading.Thread(target=ask, daemon=True) for _ in range(8)]
    [t.start() for t in threads]
    [t.join(timeout=30) for t in threads]
    assert not any(t.is_alive() for t in threads), "cached_checker deadlocked"
    assert len(got) == 8 and all(c is got[0] for c in got)
    assert len(builds) == 1
    assert checker_cache._BUILDING == {}  # no per-key lock left behind


def test_cached_checker_hands_each_thread_its_own_maps_checker_while_the_cache_clears():
    """Twenty maps from ten threads (the cache keeps 17 and clears on the 18th)."""
    base = builtin_map("reverse_bay")
    maps = [dataclasses.replace(base, bounds=(0.0, 0.0, 30.0 + 0.01 * k, 22.0))
            for k in range(20)]  # fmt: skip
    wrong: list[int] = []
    errors: list[str] = []

    def work(k):
        try:
            for r in range(3):
                m = maps[(k + 7 * r) % 20]
                c = cached_checker(m)
                if tuple(c.bounds) != tuple(m.bounds) or c.obstacles != m.obstacles:
                    wrong.append(k)
        except Exception as exc:  # noqa: BLE001 - reported below
            errors.append(repr(exc))

    threads = [threading.Thread(target=work, args=(k,), daemon=True) for k in range(10)]
    [t.start() for t in threads]
    [t.join(timeout=60) for t in threads]
    assert not any(t.is_alive() for t in threads)
    assert errors == [] and wrong == []
    assert len(checker_cache._CHECKERS) <= 17
    assert checker_cache._BUILDING == {}


def test_episodes_driven_and_judged_in_threads_are_those_driven_alone():
    """run_episode + evaluate from three threads (each job in another order) vs serially."""
    done = _python("""
        import json, threading
        from rrtdrive.evaluation import evaluate
        from rrtdrive.sim.runner import run_episode
        JOBS = [("parking", "pure-pursuit", 0), ("overtake", "stanley", 2),
                ("u-turn", "lqr", 3)]
        def go(job):
            ep = run_episode(job[0], controller=job[1], seed=job[2])
            rep = {k: v for k, v in evaluate(ep).to_json().items() if "time" not in k}
            return ep.log.states.tobytes(), json.dumps(rep, sort_keys=True, default=str)
        serial = [go(j) for j in JOBS]
        out, errors = {}, []
        def work(k):
            try:
                for i in range(len(JOBS)):
                    j = (i + k) % len(JOBS)
                    out[k, j] = go(JOBS[j])
            except Exception as exc:
                errors.append(repr(exc))
        ts = [threading.Thread(target=work, args=(k,), daemon=True) for k in range(3)]
        [t.start() for t in ts]
        [t.join(60) for t in ts]
        print(json.dumps({"hung": sum(t.is_alive() for t in ts), "errors": errors,
                          "same": all(out.get((k, j)) == serial[j]
                                      for k in range(3) for j in range(len(JOBS)))}))
    """, timeout=120)
    assert done.returncode == 0, f"exit {done.returncode}: {done.stderr[-1500:]}"
    report = json.loads(done.stdout.strip().splitlines()[-1])
    assert report == {"hung": 0, "errors": [], "same": True}


def test_random_free_poses_from_threads_does_not_crash():
    done = _python("""
        import threading, time
        from rrtdrive import builtin_map
        from rrtdrive.pose_sets import random_free_poses
        m = builtin_map("parking_lot")
        ref = [random_free_poses(m, 100, seed=s) for s in range(4)]
        deadline = time.monotonic() + 3.0  # the crash came within 1-4 s, 8 runs of 8
        same = []
        def work(k):
            while time.monotonic() < deadline:
                same.append(random_free_poses(m, 100, seed=k) == ref[k])
        ts = [threading.Thread(target=work, args=(k,)) for k in range(4)]
        [t.start() for t in ts]
        [t.join(30) for t in ts]
        print(len(same) > 4 and all(same))
    """, timeout=60)
    assert done.returncode == 0, f"exit {done.returncode} (-11: SIGSEGV)"
    assert done.stdout.strip() == "True"


def test_footprint_judge_from_threads_does_not_crash():
    done = _python("""
        import dataclasses, threading, time
        import numpy as np
        from rrtdrive import builtin_map
        from rrtdrive.evaluation.collisions import map_collision
        from rrtdrive.sim.runner import run_episode
        ep = run_episode("parking", controller="pure-pursuit", seed=0)
        # The same log driven straight across the lot's parked cars: poses the disc
        # screens cannot clear, so the exact (shapely) test runs.
        st = ep.log.states.copy()
        t = np.linspace(0.0, 1.0, len(st))
        st[:, 0], st[:, 1], st[:, 2] = 5 + 90 * t, 6 + 80 * t, 0.3 * np.sin(40 * t)
        ep = dataclasses.replace(ep, log=dataclasses.replace(ep.log, states=st))
        ref = map_collision(ep, 0.1)
        deadline = time.monotonic() + 3.0  # the crash came within 1-4 s, 8 runs of 8
        same = []
        def work():
            while time.monotonic() < deadline:
                same.append(map_collision(ep, 0.1) == ref)
        ts = [threading.Thread(target=work) for _ in range(4)]
        [t.start() for t in ts]
        [t.join(30) for t in ts]
        print(ref is True and len(same) > 4 and all(same))
    """, timeout=60)
    assert done.returncode == 0, f"exit {done.returncode} (-11: SIGSEGV, -6: abort)"
    assert done.stdout.strip() == "True"


def test_atomic_writes_leave_other_threads_files_with_the_umasks_mode(tmp_path, monkeypatch):
    """A thread switch inside the atomic write (the GIL may switch between any two calls).

    The switch is made to happen where it can: ``os.umask`` is wrapped so that, once the
    process umask has been set to 0, another thread creates its file before it goes on.
    """
    real_umask = os.umask
    zero_set, created = threading.Event(), threading.Event()

    def umask(mask: int) -> int:
        old = real_umask(mask)
        if mask == 0 and not zero_set.is_set():
            zero_set.set()
            created.wait(5)  # the other thread's turn
        return old

    modes: list[int] = []

    def other_thread() -> None:
        zero_set.wait(2)  # whenever the writer leaves the umask at 0, or not at all
        path = tmp_path / "theirs.txt"
        with open(path, "w"):
            pass
        modes.append(path.stat().st_mode & 0o777)
        created.set()

    old = real_umask(0o022)
    try:
        monkeypatch.setattr(os, "umask", umask)
        thread = threading.Thread(target=other_thread, daemon=True)
        thread.start()
        from rrtdrive.atomic import write_text_atomic

        write_text_atomic(tmp_path / "ours.txt", "x")
        thread.join(10)
    finally:
        monkeypatch.undo()
        real_umask(old)
    assert (tmp_path / "ours.txt").stat().st_mode & 0o777 == 0o644
    assert modes == [0o644], f"another thread's new file got mode {oct(modes[0])}"


# ------------------------------------------------------------------ CLI processes at once


def test_two_plans_writing_one_json_leave_one_whole_plan(tmp_path):
    """Seeds 1 and 2 into one file, beside each into a file of its own (all at once)."""
    args = ("plan", "parking_lot", "--max-iterations", "3000")
    outs = [(1, "ref1.json"), (2, "ref2.json"), (1, "same.json"), (2, "same.json")]
    procs = [subprocess.Popen(_cli(*args, "--seed", str(s), "--json", name), cwd=tmp_path,
                              stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
             for s, name in outs]  # fmt: skip
    for p in procs:
        assert p.wait(timeout=60) == 0
    refs = {s: _untimed(json.loads((tmp_path / f"ref{s}.json").read_text())) for s in (1, 2)}
    assert refs[1] != refs[2]
    doc = json.loads((tmp_path / "same.json").read_text())  # whole, never interleaved
    assert _untimed(doc) == refs[doc["seed"]]
    assert _hidden_leftovers(tmp_path) == []


def test_two_simulations_writing_one_json_and_one_trajectory(tmp_path):
    procs = [subprocess.Popen(
        _cli("simulate", "parking", "--seed", str(s), "--json", "same.json",
             "--trajectory", "same.csv"),
        cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        for s in (0, 1)]  # fmt: skip
    steps = {}
    for s, p in zip((0, 1), procs, strict=True):
        out, err = p.communicate(timeout=90)
        assert p.returncode == 0, err[-1000:]
        steps[s] = int(re.search(r"(\d+) steps", out).group(1))
    doc = json.loads((tmp_path / "same.json").read_text())
    assert doc["seed"] in steps and doc["steps"] == steps[doc["seed"]]
    with open(tmp_path / "same.csv", newline="") as fh:
        rows = list(csv.reader(fh))
    assert rows[0] == ["t", "x", "y", "yaw", "speed", "steer", "accel", "gear"]
    assert all(len(r) == 8 for r in rows[1:])
    assert len(rows) - 2 in steps.values()  # header + steps + 1 rows of one run
    assert _hidden_leftovers(tmp_path) == []


_GRID = ("--maps", "parking_lot,narrow_gap", "--planners", "improved-rrt-connect,rrt-connect",
         "--seeds", "3", "--max-iterations", "2000", "--deterministic", "--no-plots", "--quiet")


def _rows(folder: Path) -> dict:
    lines = (folder / "runs.jsonl").read_text().splitlines()
    rows = [json.loads(line) for line in lines]  # every line whole
    drop = {"planning_time_s", "setup_time_s", "diagnosis_time_s", "wall_time_s", "worker",
            "finished_at"}  # fmt: skip
    return {(r["config_hash"], r["seed"]): {k: v for k, v in r.items() if k not in drop}
            for r in rows}  # fmt: skip


def _untimed_summary(folder: Path) -> list[dict]:
    with open(folder / "summary.csv", newline="") as fh:
        rows = [r for r in csv.DictReader(fh) if not r["metric"].endswith("_time_s")]
    assert {r["metric"] for r in rows} >= {"success", "length_m", "iterations"}
    return rows


def test_bench_with_two_jobs_gives_the_rows_of_one_job_and_a_second_bench_is_locked_out(tmp_path):
    one = subprocess.Popen(_cli("bench", *_GRID, "--jobs", "1", "--out", "b1"), cwd=tmp_path,
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    two = subprocess.Popen(_cli("bench", *_GRID, "--jobs", "2", "--out", "b2"), cwd=tmp_path,
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    # A second bench into b1 while the first writes there: refused, nothing written.
    deadline = time.monotonic() + 30
    while not (tmp_path / "b1" / ".lock").exists() and time.monotonic() < deadline:
        time.sleep(0.02)
    rival = subprocess.run(_cli("bench", *_GRID, "--jobs", "1", "--out", "b1"), cwd=tmp_path,
                           capture_output=True, text=True, timeout=60)
    for p in (one, two):
        _, err = p.communicate(timeout=90)
        assert p.returncode == 0, err[-1000:]
    assert rival.returncode == 2 and "another bench is writing into" in rival.stderr
    a, b = _rows(tmp_path / "b1"), _rows(tmp_path / "b2")
    assert len(a) == 12 and a == b
    # The summaries agree too (the bootstrap's fixed seed, rows taken in seed order).
    assert _untimed_summary(tmp_path / "b1") == _untimed_summary(tmp_path / "b2")
    for folder in ("b1", "b2"):
        assert _hidden_leftovers(tmp_path / folder) == []


def test_a_bench_taking_over_the_folder_is_not_overwritten_by_the_one_before(tmp_path):
    done = _python(f"""
        import fcntl, os, subprocess, sys, time, pathlib
        from rrtdrive.bench.core import BenchConfig, run_bench
        out = pathlib.Path({str(tmp_path / "race")!r})
        a = subprocess.Popen([sys.executable, "-m", "rrtdrive", "bench", "--maps",
                              "parking_lot,narrow_gap", "--planners",
                              "improved-rrt-connect,rrt-connect", "--seeds", "3",
                              "--max-iterations", "2000", "--deterministic", "--jobs", "1",
                              "--out", str(out), "--quiet"],
                             stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        runs, got = out / "runs.jsonl", False
        deadline = time.monotonic() + 60
        while not got and time.monotonic() < deadline:
            if runs.exists() and runs.read_text().count("\\n") >= 12:
                fd = os.open(out / ".lock", os.O_RDWR)
                try:
                    fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
                    got = True
                except OSError:
                    pass
                os.close(fd)
            time.sleep(0.002)
        # The first bench let go of the folder (its runs are stored): this one takes it,
        # a grid already run.
        run_bench(BenchConfig(maps=("parking_lot",), planners=("rrt-connect",), seeds=3,
                              workers=1, out=str(out), max_iterations=2000,
                              deterministic=True, plots=False))
        a.wait(timeout=60)
        print(got, sorted(p.name for p in out.iterdir() if p.suffix == ".png"))
    """, timeout=90, cwd=tmp_path)
    assert done.returncode == 0, done.stderr[-1500:]
    got, _, pngs = done.stdout.strip().partition(" ")
    assert got == "True", "the first bench never let go of OUT/.lock"
    # The folder is the last bench's: no figures (it said --no-plots), its summary.
    assert pngs == "[]"


# ------------------------------------------------------------------ interrupting a bench

_SLOW_GRID = ("--maps", "parking_lot,narrow_gap", "--planners", "improved-rrt-connect,rrt-star",
              "--seeds", "40", "--max-iterations", "20000", "--deterministic", "--no-plots",
              "--quiet")


def _sigint_deliverable() -> None:
    # As a terminal's process: a test run started in the background by a shell (CI) hands
    # SIGINT down ignored, or blocked from a worker's mask; the bench then ran on.
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})


def _session_processes(sid: int) -> list[str]:
    """Live (not zombie) processes of session ``sid``."""
    ps = subprocess.run(["ps", "-o", "pid=,stat=,args=", "-s", str(sid)], capture_output=True,
                        text=True, timeout=10).stdout  # fmt: skip
    return [line for line in ps.splitlines() if line.split()[1][:1] != "Z"]


@pytest.mark.parametrize(("sig", "to_group", "code"), [
    (signal.SIGTERM, False, 143),  # `kill PID`, systemd, timeout(1)
    (signal.SIGINT, True, 130),    # Ctrl-C: the terminal signals the whole process group
])  # fmt: skip
def test_stopping_a_bench_with_two_workers_leaves_no_process_and_whole_rows(tmp_path, sig,
                                                                          to_group, code):
    out = tmp_path / "bench"
    p = subprocess.Popen(_cli("bench", *_SLOW_GRID, "--jobs", "2", "--out", str(out)),
                         start_new_session=True, stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True,
                         preexec_fn=_sigint_deliverable)  # fmt: skip
    try:
        runs = out / "runs.jsonl"
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline and p.poll() is None:
            if runs.exists() and runs.read_text().count("\n") >= 1:
                break
            time.sleep(0.05)
        assert p.poll() is None, "the bench ended before it could be stopped"
        workers = _session_processes(p.pid)
        assert len(workers) >= 3  # the bench and its two workers
        if to_group:
            os.killpg(p.pid, sig)
        else:
            p.send_signal(sig)
        _, err = p.communicate(timeout=30)
    finally:
        if p.poll() is None:  # pragma: no cover - only when the bench hangs
            os.killpg(p.pid, signal.SIGKILL)
            p.wait(timeout=10)
    assert p.returncode == code, err[-1000:]
    deadline = time.monotonic() + 10
    while _session_processes(p.pid) and time.monotonic() < deadline:
        time.sleep(0.1)
    assert _session_processes(p.pid) == [], "worker processes outlived the bench"
    text = runs.read_text()
    assert text.endswith("\n")
    rows = [json.loads(line) for line in text.splitlines()]
    assert 1 <= len(rows) < 160  # a grid far longer than the wait (CI once finished 16)
    assert _hidden_leftovers(out) == []
    assert not (out / "summary.md").exists()  # the grid never finished: no summary of it

