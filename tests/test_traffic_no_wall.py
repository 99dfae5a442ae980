"""``steer_rate.py --no-wall-limit``: no wall clock decides an outcome, however slow the machine."""

from __future__ import annotations

import importlib.util
import sys
import time
from pathlib import Path

import pytest
from traffic_drive import traffic_driver

from rrtdrive.sim.replanning import ReplanConfig

ROOT = Path(__file__).resolve().parents[1]


def _steer_rate():
    # Its sibling modules (results_io) import from the experiments folder: alone (or on
    # an xdist worker that ran no other experiments test first) that is not on the path.
    if str(ROOT / "experiments") not in sys.path:
        sys.path.insert(0, str(ROOT / "experiments"))
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
    _, _, driver = traffic_driver(8, ReplanConfig(wall_limit=wall_limit), steps)
    return [r for r in driver.records if r.planning_time_s > 0]


def test_no_wall_limit_settings_have_no_wall_cap() -> None:
    sr = _steer_rate()
    cfg = sr.episode_config(20, True)
    assert cfg.replan.wall_limit is False
    assert cfg.budget.max_time_s >= sr.NO_WALL_LIMIT_S
    on = sr.episode_config(20, False).replan
    assert on is None or on.wall_limit  # the default: the re-planner's wall budget


def test_no_wall_limit_planning_ignores_a_slow_clock(slow_clock: None) -> None:
    sr = _steer_rate()
    out = sr.run_one(("overtake", "lqr", 0, 0.4, "default", 20, True, "improved-rrt-connect"))
    assert out["success"] and not out["plan_wall_capped"]
    runs = _replan_cycles(wall_limit=False)
    assert runs, "the planner never ran: the test does not reach a plan"
    assert not any(sr.wall_capped(r.message) or r.deadline_hit for r in runs)
    # The same cycles with the re-planner's wall budget on: the slow clock stops them.
    capped = _replan_cycles(wall_limit=True)
    assert capped and all(r.deadline_hit or sr.wall_capped(r.message) for r in capped)
