"""Audit (session 47): nothing hangs, explodes in memory or writes half a file on extreme inputs.

SPEC §3/§6 ("nothing hangs: every search has an iteration and a time budget"; per-map set-up
outside the budget; the wall-clock cap a separate ``timeout`` status; outputs whole or not at
all), README's plan and maps sections, docs/planning.md "Budgets and determinism" and
"Bounded grid memory". Every map is a JSON file (SPEC §2) written to ``tmp_path``; every
registered planner is asked through the Python API and ``rrtdrive plan`` runs in a
subprocess with a hard timeout, its peak memory read from ``wait4``'s rusage.

Times are measured, not asserted tightly: a call with a cap of C seconds must return within
``SLACK_S`` + its reported set-up and diagnosis seconds (SPEC: set-up is outside the budget).
"""

from __future__ import annotations

import json
import math
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from rrtdrive.collision import CheckerConfig
from rrtdrive.maps import load_map
from rrtdrive.planning import PLANNERS, PlanningProblem, make_planner
from rrtdrive.types import Budget, InputError, PlanStatus

PLANNER_NAMES = sorted(n for n in PLANNERS if not n.startswith("ompl-"))  # as collected alone
STATUSES = {s.value for s in PlanStatus}
#: Generous: "cap 2 s must return within 30 s" on a loaded shared 2-core machine.
SLACK_S = 30.0
#: Hard kill for a subprocess that hangs.
HARD_TIMEOUT_S = 120.0
GIB = 1024**3
TIME_FIELDS = ("planning_time_s", "setup_time_s", "diagnosis_time_s")
#: Children of pytest-xdist may inherit SIGINT ignored; Python then never raises
#: KeyboardInterrupt. Restore the default so Ctrl-C reaches the CLI as it would from a shell.
def RESTORE_SIGINT() -> None:  # noqa: N802 - the name the tests below use
    # A mask survives exec too: a worker that ran a bench may hand SIGINT down blocked.
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})


# --- maps (SPEC §2 JSON) ------------------------------------------------------------------


def write_map(folder: Path, doc: dict) -> Path:
    path = folder / f"{doc['name']}.json"
    path.write_text(json.dumps(doc), encoding="utf-8")
    return path


def tiny_obstacles_map(n: int = 3000, side: float = 200.0, seed: int = 1, name: str = "tiny"):
    """``n`` 0.2 x 0.1 m obstacles at random odd angles, clear of the start and goal."""
    rng = np.random.default_rng(seed)
    obs = []
    start, goal = (8.0, 10.0), (side - 15.0, side - 15.0)
    while len(obs) < n:
        x, y = rng.uniform(1.0, side - 1.0, 2)
        if math.dist((x, y), start) < 8.0 or math.dist((x, y), goal) < 8.0:
            continue
        obs.append({"center": [float(x), float(y)], "size": [0.2, 0.1],
                    "yaw": float(rng.uniform(-3.0, 3.0))})  # fmt: skip
    return {"name": name, "bounds": [0, 0, side, side], "obstacles": obs,
            "start": [*start, 0.0], "goal": [*goal, 0.7]}  # fmt: skip


def overlap_map():
    """Rotated bars overlapping one another, and boxes at odd angles across every bound."""
    obs = [{"center": [50 + 0.6 * k, 50 + 0.5 * k], "size": [20, 3], "yaw": 0.123 * k + 0.017}
           for k in range(12)]  # fmt: skip
    obs += [{"center": [0, 50], "size": [4, 20], "yaw": 0.0},
            {"center": [100, 30], "size": [6, 6], "yaw": 0.785398},
            {"center": [30, 100], "size": [10, 2], "yaw": 1.234},
            {"center": [80, 0], "size": [3, 3], "yaw": 2.9}]  # fmt: skip
    return {"name": "overlap", "bounds": [0, 0, 100, 100], "obstacles": obs,
            "start": [10.0, 10.0, 0.3], "goal": [90.0, 85.0, 2.0]}  # fmt: skip


def bounds_corridor_map():
    """The map is one 500 m x 2.5 m corridor: its bounds are its walls."""
    return {"name": "corridor", "bounds": [0, 0, 500, 2.5], "obstacles": [],
            "start": [2.0, 1.25, 0.0], "goal": [495.0, 1.25, 0.0]}  # fmt: skip


def walls_corridor_map():
    """A 500 m long, 2.5 m wide corridor between two wall rectangles, open space either end."""
    y0, gap, w = 10.0, 2.5, 5.0
    return {"name": "walls", "bounds": [0, 0, 540, 20 + gap],
            "obstacles": [{"center": [270, y0 - w / 2], "size": [500, w], "yaw": 0.0},
                          {"center": [270, y0 + gap + w / 2], "size": [500, w], "yaw": 0.0}],
            "start": [5.0, y0 + gap / 2, 0.0], "goal": [530.0, y0 + gap / 2, 0.0]}  # fmt: skip


def close_map(dyaw: float = 0.0):
    """Start and goal 1e-7 m apart (the same heading, or turned by ``dyaw``)."""
    return {"name": f"close{dyaw:g}", "bounds": [0, 0, 60, 60], "obstacles": [],
            "start": [30.0, 30.0, 0.0], "goal": [30.0 + 1e-7, 30.0, dyaw]}  # fmt: skip


def behind_map():
    """The goal exactly 0.5 m behind the start, facing the same way."""
    return {"name": "behind", "bounds": [0, 0, 50, 50], "obstacles": [],
            "start": [20.0, 25.0, 0.0], "goal": [19.5, 25.0, 0.0]}  # fmt: skip


def huge_map(side: float):
    return {"name": f"huge{int(side)}", "bounds": [0, 0, side, side],
            "obstacles": [{"center": [side / 2, side / 2], "size": [10, 10], "yaw": 0.3}],
            "start": [5.0, 5.0, 0.0], "goal": [side - 10.0, side - 10.0, 0.0]}  # fmt: skip


MAPS = {
    "overlap": (overlap_map, False),
    "tiny2000": (lambda: tiny_obstacles_map(2000, 100.0), False),
    "corridor_bounds": (bounds_corridor_map, False),
    "corridor_walls": (walls_corridor_map, False),
    "close_1e-7": (close_map, False),
    "close_1e-7_turned": (lambda: close_map(math.pi / 2), False),
    "behind_0.5": (behind_map, False),
    "behind_0.5_reverse": (behind_map, True),
}


@pytest.fixture(scope="module")
def map_files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("extreme_maps")
    return {key: write_map(folder, make()) for key, (make, _) in MAPS.items()}


# --- helpers ------------------------------------------------------------------------------


def timed_solve(name: str, problem: PlanningProblem, budget: Budget, seed: int = 0):
    t0 = time.perf_counter()
    result = make_planner(name).solve(problem, np.random.default_rng(seed), budget)
    return result, time.perf_counter() - t0


def check_answer(result, wall: float, budget: Budget, problem: PlanningProblem) -> None:
    """The contract every answer keeps, whatever the input."""
    assert result.status.value in STATUSES
    assert result.success == (result.status is PlanStatus.SOLVED)
    diagnosis_s = result.stats.get("diagnosis_time_s") or 0.0
    assert wall <= SLACK_S + result.setup_time_s + diagnosis_s, (wall, result.message)
    if result.status is PlanStatus.TIMEOUT:
        # Only the cap makes a timeout, and a timeout never carries a path.
        assert result.planning_time_s >= budget.max_time_s * 0.999, result
        assert len(result.path) == 0
    if result.success:
        rows = result.path.samples
        assert len(rows) >= 2 and np.isfinite(rows).all()
        np.testing.assert_allclose(rows[0, :2], problem.start.xy, atol=1e-6)
        np.testing.assert_allclose(rows[-1, :2], problem.goal.xy, atol=1e-6)
        if not problem.reverse:
            assert result.path.is_forward_only


def same_answer(a, b) -> None:
    assert (a.status, a.iterations, a.nodes, a.message) == (b.status, b.iterations, b.nodes,
                                                           b.message)  # fmt: skip
    np.testing.assert_array_equal(a.path.samples, b.path.samples)


#: Runs a command and writes its own peak RSS (``wait4``) to a file. A child forked from
#: the pytest worker would report the worker's RSS (Linux keeps the parent's high-water
#: mark across fork and exec); forked from this small launcher it reports its own.
LAUNCHER = """
import os, signal, subprocess, sys
signal.signal(signal.SIGINT, signal.SIG_DFL)
proc = subprocess.Popen(sys.argv[2:])
_, status, usage = os.wait4(proc.pid, 0)
with open(sys.argv[1], "w") as f:
    f.write(str(usage.ru_maxrss * 1024))
code = os.waitstatus_to_exitcode(status)
sys.exit(code if code >= 0 else 128 - code)
"""


def run_cli(args: list[str], cwd: Path, timeout: float = HARD_TIMEOUT_S):
    """``rrtdrive ARGS`` in a subprocess: (exit code, stdout, stderr, seconds, peak RSS bytes)."""
    out, err, rss = cwd / "cli.stdout", cwd / "cli.stderr", cwd / "cli.rss"
    command = [sys.executable, "-c", LAUNCHER, str(rss), sys.executable, "-m", "rrtdrive", *args]
    t0 = time.perf_counter()
    with open(out, "wb") as fo, open(err, "wb") as fe:
        proc = subprocess.Popen(command, cwd=cwd, stdout=fo, stderr=fe,
                                stdin=subprocess.DEVNULL, start_new_session=True)  # fmt: skip
        try:
            code = proc.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)  # the launcher's own group: it and rrtdrive
            proc.wait()
            pytest.fail(f"rrtdrive {args} hung: killed after {timeout} s")
    seconds = time.perf_counter() - t0
    return code, out.read_text(), err.read_text(), seconds, int(rss.read_text())


def leftovers(folder: Path) -> list[str]:
    """Hidden temporary files the atomic writer would leave behind."""
    return sorted(p.name for p in folder.iterdir() if p.name.startswith("."))


# --- the Python API -----------------------------------------------------------------------


@pytest.mark.parametrize("name", PLANNER_NAMES)
@pytest.mark.parametrize("key", list(MAPS))
def test_every_planner_answers_extreme_maps_in_time_and_by_count(map_files, key, name):
    problem = PlanningProblem.from_map(load_map(map_files[key]), reverse=MAPS[key][1])
    tiny = Budget(max_iterations=1, max_time_s=2.0)
    capped = Budget(max_iterations=200, max_time_s=0.05)
    counted = Budget(max_iterations=200, max_time_s=2.0)
    answers = {}
    for label, budget in (("tiny", tiny), ("capped", capped), ("counted", counted),
                          ("again", counted)):  # fmt: skip
        result, wall = timed_solve(name, problem, budget)
        check_answer(result, wall, budget, problem)
        answers[label] = result
    assert answers["tiny"].iterations <= 1
    # Counts decide: with no cap met, the same seed and budget give the same plan again,
    # and a tighter cap that was not met changes nothing.
    if PlanStatus.TIMEOUT not in (answers["counted"].status, answers["again"].status):
        same_answer(answers["counted"], answers["again"])
        if answers["capped"].status is not PlanStatus.TIMEOUT:
            same_answer(answers["capped"], answers["counted"])


@pytest.mark.parametrize("name", PLANNER_NAMES)
def test_a_huge_budget_ends_at_the_cap_without_growing_memory(tmp_path, name):
    # 1e12 iterations: nothing may be sized by the iteration budget; the 1 s cap ends it.
    m = load_map(write_map(tmp_path, tiny_obstacles_map(800, 120.0, seed=5, name="hugebudget")))
    problem = PlanningProblem.from_map(m)
    budget = Budget(max_iterations=10**12, max_time_s=1.0)
    result, wall = timed_solve(name, problem, budget)
    check_answer(result, wall, budget, problem)
    assert result.iterations < 10**9


@pytest.mark.parametrize("side", [10_000.0, 100_000.0])
def test_api_refuses_a_map_too_big_for_the_grid_naming_bounds(tmp_path, side):
    m = load_map(write_map(tmp_path, huge_map(side)))
    t0 = time.perf_counter()
    with pytest.raises(InputError, match=r"^bounds: "):
        PlanningProblem.from_map(m)
    assert time.perf_counter() - t0 < 10.0  # refused before any grid is allocated


@pytest.mark.parametrize("name", PLANNER_NAMES)
def test_a_100_km_map_at_a_coarse_explicit_grid_answers_in_time(tmp_path, name):
    m = load_map(write_map(tmp_path, huge_map(100_000.0)))
    problem = PlanningProblem.from_map(m, config=CheckerConfig(resolution=50.0))
    budget = Budget(max_iterations=100, max_time_s=0.5)
    result, wall = timed_solve(name, problem, budget)
    check_answer(result, wall, budget, problem)
    assert result.stats["grid_resolution_m"] == 50.0


def test_a_maps_first_query_is_not_charged_the_maps_setup(tmp_path):
    # A fresh map (its own obstacles: no checker cache shared with other tests).
    doc = tiny_obstacles_map(3000, 200.0, seed=4747, name="fresh")
    m = load_map(write_map(tmp_path, doc))
    budget = Budget(max_iterations=50, max_time_s=0.05)
    first, _ = timed_solve("rrt", PlanningProblem.from_map(m), budget)
    second, _ = timed_solve("rrt", PlanningProblem.from_map(m), budget)
    if second.status is PlanStatus.TIMEOUT:
        pytest.skip("this machine cannot run 50 RRT iterations in 50 ms")
    assert (first.status, first.iterations) == (second.status, second.iterations), (
        first.message, first.planning_time_s, first.setup_time_s)  # fmt: skip


# --- the command line ---------------------------------------------------------------------


@pytest.mark.parametrize("side", [10_000, 100_000])
def test_cli_refuses_a_map_too_big_with_one_line_naming_bounds(tmp_path, side):
    path = write_map(tmp_path, huge_map(float(side)))
    code, out, err, seconds, rss = run_cli(["plan", path.name, "--json", "plan.json"], tmp_path)
    assert code == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("rrtdrive plan: error: bounds: "), err
    assert "Traceback" not in err and out == ""
    assert not (tmp_path / "plan.json").exists() and leftovers(tmp_path) == []
    assert rss < 1 * GIB and seconds < SLACK_S


def test_cli_coarsens_a_1_km_map_and_stays_within_a_few_gib(tmp_path):
    # 1000 x 1000 m at 0.1 m would be 100 M cells: README promises a coarser grid with a
    # warning (docs: 0.15 m, about 1.5 GB), never a MemoryError.
    path = write_map(tmp_path, huge_map(1000.0))
    args = ["plan", path.name, "--planner", "rrt", "--max-iterations", "50",
            "--max-time", "2", "--json", "plan.json"]  # fmt: skip
    code, _, err, seconds, rss = run_cli(args, tmp_path)
    assert code in (0, 1), err
    assert "warning: bounds:" in err and "Traceback" not in err
    doc = json.loads((tmp_path / "plan.json").read_text())
    assert 0.1 < doc["resolution_m"] <= 0.5
    assert rss < 4 * GIB, rss / GIB
    assert seconds <= SLACK_S + doc["setup_time_s"] + (doc["diagnosis_time_s"] or 0.0)


def test_cli_max_time_does_not_count_the_maps_setup(tmp_path):
    doc = tiny_obstacles_map(3000, 200.0, seed=4848, name="fresh_cli")
    path = write_map(tmp_path, doc)
    # The same query on a warm map, in this process: its counts decide well inside the cap.
    problem = PlanningProblem.from_map(load_map(path))
    timed_solve("rrt", problem, Budget(max_iterations=1, max_time_s=60.0))  # warm the map
    warm, _ = timed_solve("rrt", problem, Budget(max_iterations=50, max_time_s=0.1))
    if warm.status is PlanStatus.TIMEOUT:
        pytest.skip("this machine cannot run 50 RRT iterations in 0.1 s")
    args = ["plan", path.name, "--planner", "rrt", "--max-iterations", "50", "--max-time", "0.1",
            "--json", "plan.json"]  # fmt: skip
    code, _, err, seconds, rss = run_cli(args, tmp_path)
    got = check_cli_plan(code, err, seconds, rss, tmp_path / "plan.json")
    assert (got["status"], got["iterations"]) == (warm.status.value, warm.iterations), (
        got["message"], got["planning_time_s"], got["setup_time_s"])  # fmt: skip


CLI_CASES = {
    "tiny2000_default": ("tiny2000", ["--max-iterations", "300", "--max-time", "2"]),
    "corridor_rrt_star_capped": ("corridor_bounds", ["--planner", "rrt-star", "--max-iterations",
                                                     "100000000", "--max-time", "0.05"]),
    "close_default_one_iteration": ("close_1e-7_turned", ["--max-iterations", "1"]),
    "behind_reverse": ("behind_0.5", ["--reverse", "--max-iterations", "300", "--max-time", "2"]),
}  # fmt: skip


def check_cli_plan(code: int, err: str, seconds: float, rss: int, target: Path) -> dict:
    assert code in (0, 1), err
    assert "Traceback" not in err
    doc = json.loads(target.read_text())  # whole: parses
    assert doc["status"] in STATUSES and doc["success"] == (code == 0)
    assert doc["success"] == (doc["status"] == "solved")
    if doc["status"] == "timeout":
        assert doc["planning_time_s"] >= doc["max_time_s"] * 0.999
    assert seconds <= SLACK_S + doc["setup_time_s"] + (doc["diagnosis_time_s"] or 0.0)
    assert rss < 3 * GIB
    return doc


@pytest.mark.parametrize("case", list(CLI_CASES))
def test_cli_extreme_plans_exit_in_time_with_whole_json(map_files, tmp_path, case):
    key, extra = CLI_CASES[case]
    args = ["plan", str(map_files[key]), *extra, "--json", "plan.json"]
    code, _, err, seconds, rss = run_cli(args, tmp_path)
    doc = check_cli_plan(code, err, seconds, rss, tmp_path / "plan.json")
    assert leftovers(tmp_path) == []
    if doc["success"]:  # from exactly the start to exactly the goal (6 decimals)
        assert math.dist(doc["path"][0][:2], doc["start"][:2]) < 1e-6
        assert math.dist(doc["path"][-1][:2], doc["goal"][:2]) < 1e-6
    if case == "corridor_rrt_star_capped":
        assert doc["status"] == "timeout" and code == 1  # 1e8 iterations cannot fit in 50 ms


def test_cli_seeded_iteration_budget_gives_the_same_json_twice(map_files, tmp_path):
    args = ["plan", str(map_files["overlap"]), "--planner", "hybrid-a-star", "--seed", "3",
            "--max-iterations", "300", "--max-time", "60"]  # fmt: skip
    docs = []
    for k in range(2):
        code, _, err, seconds, rss = run_cli([*args, "--json", f"p{k}.json"], tmp_path)
        doc = check_cli_plan(code, err, seconds, rss, tmp_path / f"p{k}.json")
        assert doc["status"] != "timeout"
        docs.append({f: v for f, v in doc.items() if f not in TIME_FIELDS})
    assert docs[0] == docs[1]


# --- signals: whole files or nothing -------------------------------------------------------

#: Runs the CLI with ``Path.write_text`` slowed down half way through, so that a signal
#: lands while the JSON is half written (the temporary file beside the target).
SLOW_WRITER = """
import pathlib, sys, time
def slow(self, data, encoding=None, errors=None, newline=None):
    with open(self, "w", encoding=encoding or "utf-8") as f:
        f.write(data[: len(data) // 2]); f.flush()
        sys.stderr.write("HALF-WRITTEN\\n"); sys.stderr.flush()
        time.sleep(60)
        f.write(data[len(data) // 2 :])
    return len(data)
pathlib.Path.write_text = slow
from rrtdrive.cli import main
sys.exit(main(sys.argv[1:]))
"""


def start_slow_writer(map_path: Path, target: Path) -> subprocess.Popen:
    args = ["plan", str(map_path), "--max-iterations", "300", "--json", str(target)]
    return subprocess.Popen([sys.executable, "-c", SLOW_WRITER, *args], cwd=target.parent,
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                            stdin=subprocess.DEVNULL, preexec_fn=RESTORE_SIGINT)  # fmt: skip


def wait_for_line(proc: subprocess.Popen, needle: bytes, timeout: float) -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        line = proc.stderr.readline()
        if needle in line:
            return
        if not line and proc.poll() is not None:
            pytest.fail(f"exited {proc.returncode} before {needle!r}")
    proc.kill()
    proc.wait()
    pytest.fail(f"no {needle!r} within {timeout} s")


@pytest.mark.parametrize(
    ("sig", "code"), [(signal.SIGTERM, 143), (signal.SIGINT, 130), (signal.SIGKILL, -9)]
)
def test_a_signal_mid_write_leaves_the_old_file_whole(map_files, tmp_path, sig, code):
    target = tmp_path / "plan.json"
    old = '{"written": "before"}'
    target.write_text(old, encoding="utf-8")
    proc = start_slow_writer(map_files["close_1e-7"], target)
    try:
        wait_for_line(proc, b"HALF-WRITTEN", HARD_TIMEOUT_S)
        assert leftovers(tmp_path), "the half-written temporary file is beside the target"
        proc.send_signal(sig)
        proc.communicate(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == code
    assert target.read_text(encoding="utf-8") == old  # never half-written, nothing lost
    if sig is not signal.SIGKILL:  # a clean-up can run: the temporary file is gone too
        assert leftovers(tmp_path) == []


@pytest.mark.parametrize(("sig", "code"), [(signal.SIGTERM, 143), (signal.SIGINT, 130)])
def test_a_signal_mid_search_writes_nothing(tmp_path, sig, code):
    # A 210 m map (over 4 M cells: the CLI says it is setting up, so its handlers are in
    # place); RRT* refining toward 200 000 nodes runs to its 60 s cap: stop it on the way.
    path = write_map(tmp_path, huge_map(210.0))
    args = ["plan", path.name, "--planner", "rrt-star", "--planner-option", "max_nodes=200000",
            "--max-iterations", "100000000", "--max-time", "60", "--json", "plan.json"]  # fmt: skip
    proc = subprocess.Popen([sys.executable, "-m", "rrtdrive", *args], cwd=tmp_path,
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                            stdin=subprocess.DEVNULL, preexec_fn=RESTORE_SIGINT)  # fmt: skip
    try:
        wait_for_line(proc, b"setting up", HARD_TIMEOUT_S)
        time.sleep(1.5)  # set-up (about 0.5 s here), then the search
        assert proc.poll() is None
        proc.send_signal(sig)
        _, err = proc.communicate(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == code, err
    assert not (tmp_path / "plan.json").exists() and leftovers(tmp_path) == []
