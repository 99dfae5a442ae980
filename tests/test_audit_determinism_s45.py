"""Audit (session 45) of the determinism promise: counts decide, the wall clock is a cap.

For a seed, ``rrtdrive plan --json``, ``rrtdrive simulate --json`` (and its trajectory),
the gymnasium env (``reset(seed)`` + fixed actions) and ``rrtdrive bench`` rows must be
the same on a fast and on a slow machine, timing fields aside (docs/planning.md "The plan
JSON", docs/metrics.md, docs/bench.md "Rows"). The slow machine is made three ways, each
in its own interpreter: another ``PYTHONHASHSEED`` and the commands in reverse order; a
collision checker that sleeps in every test; and a wall clock that runs K times too fast
(which the stopwatch takes for a K times slower machine). Only a query whose safety cap
was met may differ, and then it is ``timeout`` (exit 1) with a message naming the cap.
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import textwrap
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

from rrtdrive.cli import main

#: Timing fields, as the docs name them: plan JSON (docs/planning.md), simulate JSON
#: (docs/metrics.md: total_time_s, the wall-clock fields, setup_time_s) and bench rows
#: (docs/bench.md: wall_time_s, worker, finished_at).
TIMING = frozenset({
    "planning_time_s", "setup_time_s", "diagnosis_time_s", "total_time_s", "wall_time_s",
    "replan_time_median_s", "replan_time_max_s", "replans_over_budget", "worker",
    "finished_at",
})
#: Seconds quoted in a message ("stopped by the 120 s safety cap" is kept: it is the cap).
_SECONDS = re.compile(r"\b\d+\.\d+ s\b")

PLANS = {
    "overtake": ["plan", "overtake", "--seed", "0", "--max-iterations", "1500"],
    "lot-rev": ["plan", "parking_lot", "--seed", "2", "--reverse", "--max-iterations", "1500"],
    "no-path": ["plan", "no_path", "--seed", "0", "--max-iterations", "1500"],
    "bulb": ["plan", "turning_bulb", "--seed", "0", "--max-iterations", "1500"],
    "kerb-fwd": ["plan", "kerbside", "--seed", "0", "--max-iterations", "1500"],
    "kerb-rev": ["plan", "kerbside", "--seed", "2", "--reverse", "--max-iterations", "1500"],
    "bay-hybrid-rev": ["plan", "reverse_bay", "--planner", "hybrid-a-star", "--reverse",
                       "--max-iterations", "1500"],
    "dead-end-fwd": ["plan", "dead_end", "--seed", "0", "--max-iterations", "1500"],
    "dead-end-hybrid-rev": ["plan", "dead_end", "--planner", "hybrid-a-star", "--seed", "1",
                            "--reverse", "--max-iterations", "1500"],
    "lot-rrt-star": ["plan", "parking_lot", "--planner", "rrt-star", "--seed", "3",
                     "--max-iterations", "800"],
    "gap-rrt-connect": ["plan", "narrow_gap", "--planner", "rrt-connect", "--seed", "3",
                        "--max-iterations", "800"],
    "wall-goal": ["plan", "overtake", "--goal", "30,44,3.14159", "--seed", "0",
                  "--max-iterations", "600"],
}
SIMS = {
    "sim-kerb-lqr": ["simulate", "kerbside", "--reverse", "--controller", "lqr",
                     "--max-iterations", "3000", "--trajectory", "{traj}"],
    "sim-traffic": ["simulate", "overtake-traffic", "--seed", "1", "--deterministic",
                    "--trajectory", "{traj}"],
    "sim-dead-end": ["simulate", "dead_end", "--seed", "0", "--max-iterations", "1500",
                     "--trajectory", "{traj}"],
}
GYMS = {
    "gym-parking": ["rrtdrive/Parking-v0", {}, 3],
    "gym-kerb": ["rrtdrive/Map-v0", {"scenario": "kerbside",
                                     "scenario_options": {"reverse": True}}, 0],
    "gym-traffic": ["rrtdrive/OvertakeTraffic-v0",
                    {"residual": True, "replan_options": {"wall_limit": False}}, 2],
}
#: Clock speed-ups (a machine that many times slower, as the stopwatch sees it).
CLOCKS = (1000.0, 5000.0, 50000.0)
SIM_CLOCK = 5000.0

DRIVER = textwrap.dedent('''
    import contextlib, io, json, math, os, sys, time
    mode = json.loads(sys.argv[1])
    jobs = json.load(open(sys.argv[2]))
    work = sys.argv[3]
    calls = [0]
    if mode.get("delay"):
        from rrtdrive.collision.checker import CollisionChecker
        def slow(f):
            def g(self, *a, **k):
                calls[0] += 1
                time.sleep(mode["delay"])
                return f(self, *a, **k)
            return g
        for n in ("edge_free", "pose_free", "pose_free_fast", "poses_free", "poses_free_fast",
                  "poses_free_unscreened", "rectangles_free", "path_free", "body_clearance"):
            setattr(CollisionChecker, n, slow(getattr(CollisionChecker, n)))
    scale = [1.0]
    real = time.perf_counter
    origin = real()
    time.perf_counter = lambda: origin + (real() - origin) * scale[0]
    from rrtdrive.cli import main

    def clean(x):
        if isinstance(x, dict):
            return {str(k): clean(v) for k, v in x.items()}
        if hasattr(x, "tolist"):
            x = x.tolist()
        if isinstance(x, (list, tuple)):
            return [clean(v) for v in x]
        if isinstance(x, float):
            return None if math.isnan(x) else x
        return x if isinstance(x, (int, str, bool, type(None))) else repr(x)

    def cli(name, argv):
        out, traj = os.path.join(work, name + ".json"), os.path.join(work, name + ".csv")
        argv = [traj if a == "{traj}" else a for a in argv] + ["--json", out]
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
            try:
                rc = main(argv)
            except SystemExit as e:
                rc = e.code
        data = json.load(open(out))
        csv = open(traj).read() if os.path.exists(traj) else None
        for p in (out, traj):
            if os.path.exists(p):
                os.remove(p)
        return {"rc": rc, "json": data, "traj": csv}

    def gym_run(env_id, kwargs, seed):
        import numpy as np
        import gymnasium as gym
        import rrtdrive.envs  # noqa: F401
        env = gym.make(env_id, **kwargs)
        obs, info = env.reset(seed=seed)
        rec = [clean(obs), clean(info)]
        rng = np.random.default_rng(123)
        for _ in range(60):
            a = rng.uniform(-0.3, 0.3, env.action_space.shape).astype(env.action_space.dtype)
            obs, r, term, trunc, info = env.step(a)
            rec.append([clean(obs), float(r), bool(term), bool(trunc), clean(info)])
            if term or trunc:
                break
        env.close()
        return rec

    items = list(jobs.items())
    if mode.get("reverse"):
        items.reverse()
    res = {}
    for clock in mode.get("clocks", [1.0]):
        scale[0] = clock
        for name, job in items:
            key = name if clock == 1.0 else f"{name}@{clock:g}"
            if name.startswith("sim-") and clock not in (1.0, mode.get("sim_clock")):
                continue
            res[key] = gym_run(*job) if name.startswith("gym-") else cli(name, job)
    res["__calls__"] = calls[0]
    json.dump(res, open(os.path.join(work, "result.json"), "w"))
''')


def _run_driver(tmp: Path, mode: dict, jobs: dict, hashseed: str) -> dict:
    tmp.mkdir(parents=True, exist_ok=True)
    (tmp / "driver.py").write_text(DRIVER)
    (tmp / "jobs.json").write_text(json.dumps(jobs))
    env = {**os.environ, "PYTHONHASHSEED": hashseed}
    done = subprocess.run(
        [sys.executable, str(tmp / "driver.py"), json.dumps(mode), str(tmp / "jobs.json"),
         str(tmp)], env=env, capture_output=True, text=True, timeout=240,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr[-2000:]
    return json.loads((tmp / "result.json").read_text())


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """The same jobs in three interpreters: reference, slowed checker, fast clock."""
    base = tmp_path_factory.mktemp("determinism")
    everything = {**PLANS, **SIMS, **GYMS}
    specs = {
        "ref": ({}, everything, "0"),
        "slow": ({"delay": 1e-4, "reverse": True}, everything, "12345"),
        "clock": ({"clocks": list(CLOCKS), "sim_clock": SIM_CLOCK}, {**PLANS, **SIMS}, "7"),
    }
    with ThreadPoolExecutor(3) as pool:
        futures = {k: pool.submit(_run_driver, base / k, *spec) for k, spec in specs.items()}
        return {k: f.result() for k, f in futures.items()}


def _plain(data: dict) -> dict:
    """A JSON object without its timing fields, seconds in its message masked."""
    out = {k: v for k, v in data.items() if k not in TIMING}
    if isinstance(out.get("message"), str):
        out["message"] = _SECONDS.sub("<t> s", out["message"])
    return out


def _differences(a: dict, b: dict) -> dict:
    x, y = _plain(a), _plain(b)
    return {k: (x.get(k), y.get(k)) for k in sorted(set(x) | set(y)) if x.get(k) != y.get(k)}


def test_the_slow_run_was_really_slowed(runs):
    """The slowed checker slept in thousands of collision tests (else the audit proves nothing)."""
    assert runs["slow"]["__calls__"] > 1000
    assert runs["ref"]["__calls__"] == 0


@pytest.mark.parametrize("name", list(PLANS))
def test_plan_json_is_the_same_on_a_slow_machine(runs, name):
    """Another hash seed, the reverse order and a slow checker: the same plan JSON and exit."""
    ref, slow = runs["ref"][name], runs["slow"][name]
    assert ref["json"]["status"] != "timeout"
    assert (slow["rc"], _differences(ref["json"], slow["json"])) == (ref["rc"], {})


def test_the_plans_cover_solved_and_counted_failures(runs):
    statuses = {runs["ref"][n]["json"]["status"] for n in PLANS}
    assert {"solved", "proven_unreachable", "no_path_in_budget", "postprocess_failed"} <= statuses


def _is_timeout(run: dict, cap_flag: str) -> bool:
    data = run["json"]
    return (
        run["rc"] == 1 and data["status"] == "timeout" and data["success"] is False
        and data["path"] == [] and data["length_m"] is None and data["stage"] is None
        and "stopped by the 120 s safety cap" in data["message"] and cap_flag in data["message"]
    )  # fmt: skip


@pytest.mark.parametrize("clock", CLOCKS)
def test_a_plan_that_meets_the_cap_says_timeout_else_it_is_the_same(runs, clock):
    """A K times slower machine: every plan is the counted one or a `timeout` naming the cap."""
    capped = 0
    for name in PLANS:
        ref, run = runs["ref"][name], runs["clock"][f"{name}@{clock:g}"]
        if _differences(ref["json"], run["json"]) or run["rc"] != ref["rc"]:
            assert _is_timeout(run, "raise --max-time"), (name, run["rc"], run["json"]["status"],
                                                          run["json"]["message"][:200])
            capped += 1
    if clock == CLOCKS[-1]:  # a cap of 2.4 ms of real time: most queries meet it
        assert capped >= len(PLANS) // 2


@pytest.mark.parametrize("name", list(SIMS))
def test_simulate_json_and_trajectory_are_the_same_on_a_slow_machine(runs, name):
    ref, slow = runs["ref"][name], runs["slow"][name]
    assert ref["json"]["status"] != "timeout"
    assert (slow["rc"], _differences(ref["json"], slow["json"])) == (ref["rc"], {})
    assert slow["traj"] == ref["traj"]
    driven = ref["json"]["status"] != "plan_failed"
    assert ref["traj"].count("\n") > 100 if driven else ref["traj"].count("\n") == 1


@pytest.mark.parametrize("name", list(SIMS))
def test_simulate_on_a_slower_machine_is_the_same_or_a_planning_timeout(runs, name):
    ref, run = runs["ref"][name], runs["clock"][f"{name}@{SIM_CLOCK:g}"]
    if not _differences(ref["json"], run["json"]) and run["traj"] == ref["traj"]:
        return
    data = run["json"]
    assert run["rc"] == 1 and data["status"] == "plan_failed" and data["steps"] == 0
    assert data["message"].startswith("planning failed (timeout): stopped by the 120 s safety cap")
    assert "raise --plan-time" in data["message"]


@pytest.mark.parametrize("name", list(GYMS))
def test_gym_reset_seed_and_fixed_actions_are_the_same_on_a_slow_machine(runs, name):
    ref, slow = runs["ref"][name], runs["slow"][name]
    assert len(ref) > 10
    assert slow == ref


def _bench(out: Path, workers: int) -> dict:
    argv = ["bench", "--maps", "overtake,kerbside", "--scenarios", "parallel-parking",
            "--planners", "improved-rrt-connect,hybrid-a-star", "--seeds", "1",
            "--max-iterations", "1500", "--reverse", "--deterministic", "--no-plots",
            "--quiet", "--workers", str(workers), "--out", str(out)]
    done = subprocess.run([sys.executable, "-m", "rrtdrive", *argv], capture_output=True,
                          text=True, timeout=240)
    assert done.returncode == 0, done.stderr[-2000:]
    rows = [json.loads(line) for line in (out / "runs.jsonl").read_text().splitlines()]
    return {(r["config_hash"], r["seed"]): r for r in rows}


def test_bench_rows_are_the_same_with_one_and_two_workers(tmp_path):
    with ThreadPoolExecutor(2) as pool:
        one, two = pool.map(lambda w: _bench(tmp_path / f"w{w}", w), (1, 2))
    assert len(one) == 6 and one.keys() == two.keys()
    assert {r["kind"] for r in one.values()} == {"plan", "episode"}
    assert len({r["worker"] for r in one.values()}) == 1
    diffs = {k: _differences(one[k], two[k]) for k in one}
    assert {k: d for k, d in diffs.items() if d} == {}


@pytest.mark.parametrize("planner", ["improved-rrt-connect", "hybrid-a-star", "rrt-star"])
def test_a_tiny_max_time_is_timeout_with_exit_1(tmp_path, capsys, planner):
    out = tmp_path / "p.json"
    rc = main(["plan", "dead_end", "--reverse", "--planner", planner, "--max-time", "0.0005",
               "--json", str(out)])
    data = json.loads(out.read_text())
    assert rc == 1
    assert data["status"] == "timeout" and data["path"] == [] and data["max_time_s"] == 0.0005
    assert data["message"].startswith("stopped by the 0.0005 s safety cap after ")
    assert "FAILED (timeout): stopped by the 0.0005 s safety cap" in capsys.readouterr().out


def test_gym_reset_does_not_swap_a_capped_episode_for_another(monkeypatch):
    import gymnasium as gym

    import rrtdrive.envs  # noqa: F401
    from rrtdrive.planning import base

    env = gym.make("rrtdrive/Parking-v0")
    _, info = env.reset(seed=3)
    counted = info["episode_seed"]
    env.close()

    made = []
    init = base.Stopwatch.__init__

    def first_watch_capped(self, *args, **kwargs):  # the first query's cap is already past
        init(self, *args, **kwargs)
        if not made:
            self._deadline = self.t0 - 1.0
        made.append(self)

    monkeypatch.setattr(base.Stopwatch, "__init__", first_watch_capped)
    env = gym.make("rrtdrive/Parking-v0")
    try:
        _, info = env.reset(seed=3)
    except RuntimeError as err:  # what a user can act on: the cap, named
        assert "safety cap" in str(err)
        return
    finally:
        env.close()
    assert made and made[0].capped  # the cap was met by the first draw's plan
    assert info["episode_seed"] == counted, (
        f"reset(seed=3) gave episode {info['episode_seed']} instead of {counted}")

