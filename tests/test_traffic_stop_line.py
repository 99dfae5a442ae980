"""The comfort-mode stop at a stop line (the oncoming gate's): jerk-limited, still at the line."""

from __future__ import annotations

import numpy as np
import pytest

from rrtdrive.controllers import SpeedConfig
from rrtdrive.controllers.speed import SpeedController
from rrtdrive.speed_profile import SpeedProfile

DT = 0.05


def _approach(v0: float, line: float, comfort: bool, line_from: float = 0.0) -> tuple:
    """A point mass on a long straight profile; the stop line appears at ``line_from`` m."""
    cfg = SpeedConfig(v_max=4.0)
    s_grid = np.linspace(0.0, 200.0, 801)
    ctrl = SpeedController(cfg, comfort=comfort)
    ctrl.reset(SpeedProfile(s_grid, np.zeros_like(s_grid), cfg, v_start=v0))
    ctrl.last_a = 0.0
    s, v, t = 0.0, v0, 0.0
    accels, positions = [], []
    for _ in range(int(40.0 / DT)):
        if s >= line_from:
            ctrl.stop_at = line
        a = ctrl.control(s, v, t)
        accels.append(a)
        v_new = max(v + a * DT, 0.0)
        s += 0.5 * (v + v_new) * DT
        v = v_new
        t += DT
        positions.append(s)
    return np.asarray(accels), np.asarray(positions), v


@pytest.mark.parametrize("v0", [1.0, 3.0])
def test_comfort_stop_line_is_jerk_limited_and_stops_before_the_line(v0: float) -> None:
    line = 25.0
    accels, pos, v_end = _approach(v0, line, comfort=True)
    jerk = np.abs(np.diff(accels)) / DT
    assert v_end == 0.0
    assert pos.max() <= line + 1e-9, "passed the stop line"
    assert line - pos[-1] < 0.1, f"stopped {line - pos[-1]:.3f} m short of the line"
    # The comfort jerk (2 m/s^3) while braking, the hold at the end (< 0.2 m/s^2 in a step).
    assert jerk.max() <= 4.5, f"raw jerk {jerk.max():.1f} m/s^3"
    # The plain loop (not comfort) ends its approach with the hard brake at the line.
    plain, _, _ = _approach(v0, line, comfort=False)
    assert (np.abs(np.diff(plain)) / DT).max() > jerk.max()


def test_comfort_stop_line_set_late_still_stops_at_the_line() -> None:
    # The line appears 3 m ahead of a car at 3 m/s (v^2 / 2 decel = 4.5 m: no
    # comfortable stop); safety first: the car stops, passing the line by no more
    # than the plain loop does.
    line = 23.0
    _, pos, v_end = _approach(3.0, line, comfort=True, line_from=20.0)
    _, pos_plain, _ = _approach(3.0, line, comfort=False, line_from=20.0)
    assert v_end == 0.0
    assert pos.max() <= max(pos_plain.max(), line) + 0.05


def test_oncoming_gate_stop_in_highway_env(monkeypatch: pytest.MonkeyPatch) -> None:
    """Overtake with oncoming cars (seed 13 waited at the line with an 83 m/s^3 step)."""
    from rrtdrive.evaluation import evaluate
    from rrtdrive.sim.runner import run_episode
    from rrtdrive.sim.tasks import make_scenario
    from rrtdrive.sim.traffic import OncomingGate

    seen: list[tuple[float, float, float | None]] = []
    original = OncomingGate.stop_line

    def recording(self: OncomingGate, s: float, speed: float, cars: object) -> float | None:
        line = original(self, s, speed, cars)
        seen.append((s, speed, line))
        return line

    monkeypatch.setattr(OncomingGate, "stop_line", recording)
    ep = run_episode(make_scenario("overtake", 13, oncoming=2), controller="pure-pursuit", seed=13)
    report = evaluate(ep)
    held = [(s, v, line) for s, v, line in seen if line is not None]
    assert report.success and not report.collision_footprint
    assert held, "the gate never held the car: the test does not reach the stop line"
    assert max(s - line for s, _, line in held) <= 0.0, "passed the stop line while held"
    assert any(v == 0.0 and line - s < 0.2 for s, v, line in held), "never waited at the line"
    assert report.max_jerk <= 5.0, f"raw jerk {report.max_jerk:.1f} m/s^3"
