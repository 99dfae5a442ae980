"""``steer_rate.py --no-wall-limit``: no wall clock decides an outcome, however slow the machine."""

from __future__ import annotations

import importlib.util
import sys
import time
from pathlib import Path

import pytest

from rrtdrive.controllers import make_controller
from rrtdrive.sim.drivelog import DriveRecorder
from rrtdrive.sim.replanning import ReplanConfig
from rrtdrive.sim.scenes import build_env, scenario_rngs
from rrtdrive.sim.tasks import make_scenario, traffic_speed_config
from rrtdrive.sim.traffic_driver import TrafficDriver

ROOT = Path(__file__).resolve().parents[1]


def _steer_rate():
    path = ROOT / "experiments" / "steer_rate.py"
    spec = importlib.util.spec_from_file_location("steer_rate", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules["steer_rate"] = module
    spec.loader.exec_module(module)
    return module


@pytest.fixture
def slow_clock(monkeypatch: pytest.MonkeyPatch) -> None:
    """The wall clock of a machine 1000 times slower: every wall cap fires at once."""
    real = time.perf_counter
    t0 = real()
    monkeypatch.setattr(time, "perf_counter", lambda: t0 + 1000.0 * (real() - t0))


def _replan_cycles(wall_limit: bool, steps: int = 6) -> list:
    scen = make_scenario("overtake-traffic", 8)
    env = build_env(scen)
    try:
        speed = traffic_speed_config(scen)
        ctrl = make_controller("pure-pursuit", vehicle=scen.vehicle, speed=speed)
        driver = TrafficDriver(env, scen, ctrl, speed, ReplanConfig(wall_limit=wall_limit),
                               scenario_rngs(8)[1])
        driver.start()
        dt = 1.0 / env.unwrapped.config["simulation_frequency"]
        recorder = DriveRecorder(env, dt)
        for k in range(steps):
            recorder.step(*driver.control(k * dt))
        return [r for r in driver.records if r.planning_time_s > 0]
    finally:
        env.close()


def test_no_wall_limit_settings_have_no_wall_cap() -> None:
    sr = _steer_rate()
    cfg = sr.episode_config(20, True)
    assert cfg.replan.wall_limit is False
    assert cfg.budget.max_time_s >= sr.NO_WALL_LIMIT_S
    on = sr.episode_config(20, False).replan
    assert on is None or on.wall_limit  # the default: the re-planner's wall budget


def test_no_wall_limit_planning_ignores_a_slow_clock(slow_clock: None) -> None:
    sr = _steer_rate()
    out = sr.run_one(("overtake", "lqr", 0, 0.4, "default", 20, True))
    assert out["success"] and not out["plan_wall_capped"]
    runs = _replan_cycles(wall_limit=False)
    assert runs, "the planner never ran: the test does not reach a plan"
    assert not any(sr.wall_capped(r.message) or r.deadline_hit for r in runs)
    # The same cycles with the re-planner's wall budget on: the slow clock stops them.
    capped = _replan_cycles(wall_limit=True)
    assert capped and all(r.deadline_hit or sr.wall_capped(r.message) for r in capped)
