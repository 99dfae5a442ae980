"""Evaluators on hand-made episodes with known answers."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rrtdrive.evaluation import (
    EvalConfig,
    densify_poses,
    evaluate,
    summarise,
    tracking_errors,
)
from rrtdrive.sim.episode import DriveLog, Episode
from rrtdrive.sim.runner import EpisodeConfig
from rrtdrive.sim.tasks import make_scenario
from rrtdrive.types import InputError, Path, VehicleParams

V = VehicleParams()
DT = 0.05


def _episode(scen, path, states, controls, crashed=None, status="arrived", others=None, sizes=None):
    states = np.asarray(states, float)
    n = len(states)
    log = DriveLog(
        dt=DT,
        t=np.arange(n) * DT,
        states=states,
        controls=np.asarray(controls, float).reshape(-1, 2),
        crashed=np.zeros(n, bool) if crashed is None else np.asarray(crashed, bool),
        others=np.zeros((n, 0, 4)) if others is None else np.asarray(others, float),
        other_sizes=np.zeros((0, 2)) if sizes is None else np.asarray(sizes, float),
        arrived=status == "arrived",
        wall_time_s=0.01,
    )
    return Episode(
        scen, "given", "pure-pursuit", scen.seed, None, path, log, status, "", EpisodeConfig()
    )


def _lane_path(scen, x_end=92.0):
    x = np.arange(scen.start.x, x_end + 1e-9, 0.1)
    y = np.full_like(x, scen.lane_y)
    return Path(np.column_stack([x, y, 0 * x, 0 * x]), np.zeros((0, 2)))


@pytest.fixture(scope="module")
def overtake():
    return make_scenario("overtake", 0, jitter=(0.0, 0.0, 0.0))


def test_tracking_errors_signed_and_heading():
    xs = np.linspace(0.0, 10.0, 101)
    p = Path(np.column_stack([xs, 0 * xs, 0 * xs, 0 * xs]), np.zeros((0, 2)))
    cte, he = tracking_errors(p, np.array([[1.0, 0.2, 0.0], [5.0, -0.3, 0.1], [12.0, 0.0, 0.0]]))
    assert cte == pytest.approx([0.2, -0.3, 2.0])  # past the end: distance to the end point
    assert he == pytest.approx([0.0, 0.1, 0.0])
    th = np.linspace(0, math.pi, 400)
    arc = Path(np.column_stack([10 * np.sin(th), 10 * (1 - np.cos(th)), th, np.full_like(th, 0.1)]),
               np.zeros((0, 2)))
    cte, _ = tracking_errors(arc, np.array([[10.5, 10.0, math.pi / 2]]))  # outside: right
    assert cte[0] == pytest.approx(-0.5, abs=1e-3)


def test_densify():
    d = densify_poses(np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.2]]), 0.1)
    assert len(d) == 11 and np.max(np.diff(d[:, 0])) <= 0.1 + 1e-12
    assert d[5, 2] == pytest.approx(0.1)


def test_metrics_of_a_known_trajectory(overtake):
    path = _lane_path(overtake, 30.0)
    n = 101
    x = np.linspace(overtake.start.x, 30.0, n)
    offset = 0.1 * np.sin(np.linspace(0, math.pi, n))  # left of the path, 0.1 m at most
    v = np.linspace(2.0, 0.0, n)
    states = np.column_stack([x, overtake.lane_y + offset, np.zeros(n), v])
    steer = np.full(n - 1, math.atan(V.wheelbase * 0.1))
    steer[10] = math.atan(V.wheelbase * 0.2)  # one step over kappa_max
    controls = np.column_stack([np.full(n - 1, -0.4), steer])
    scen = overtake.__class__(**{**overtake.__dict__, "map": overtake.map.with_query(
        goal=overtake.map.goal.__class__(30.0, overtake.lane_y, 0.0))})
    ep = _episode(scen, path, states, controls)
    r = evaluate(ep)
    assert r.cte_max_m == pytest.approx(0.1, abs=1e-4)
    assert r.cte_rms_m == pytest.approx(np.sqrt(np.mean(offset**2)), rel=1e-6)
    assert r.heading_err_max_rad == pytest.approx(0.0)
    assert r.executed_max_curvature == pytest.approx(0.2)
    assert r.executed_curvature_violation_share == pytest.approx(1 / (n - 1))
    assert r.max_lateral_accel == pytest.approx(max(v[:-1] ** 2 * np.tan(steer) / V.wheelbase))
    # Steering rate: the jump to 0.2 and back, over one step.
    jump = (math.atan(V.wheelbase * 0.2) - math.atan(V.wheelbase * 0.1)) / DT
    assert r.max_steering_rate == pytest.approx(max(jump, math.atan(V.wheelbase * 0.1) / DT))
    assert r.goal_position_err_m == pytest.approx(0.0, abs=1e-9)
    assert r.stopped and r.reached_goal and not r.collision
    assert r.passed_lead is False  # it stopped before the lead car at x = 50
    assert not r.success
    assert r.duration_s == pytest.approx((n - 1) * DT) and r.steps == n - 1
    js = r.to_json()
    assert js["seed"] == 0 and isinstance(js["cte_max_m"], float)


def test_both_collision_judges_are_reported_separately(overtake):
    path = _lane_path(overtake)
    # Straight through the stopped car at x = 50.
    x = np.arange(overtake.start.x, 60.0, 0.2)
    states = np.column_stack([x, np.full_like(x, overtake.lane_y), 0 * x, np.full_like(x, 4.0)])
    controls = np.zeros((len(x) - 1, 2))
    r = evaluate(_episode(overtake, path, states, controls, status="timeout"))
    assert r.collision_footprint and not r.collision_highway_env and r.collision
    crashed = np.zeros(len(x), bool)
    crashed[-1] = True
    short = states[:20]
    r2 = evaluate(_episode(overtake, path, short, controls[:19], crashed=crashed[-20:],
                           status="crashed"))
    assert r2.collision_highway_env and not r2.collision_footprint and not r2.success


def test_footprint_judge_sees_moving_vehicles(overtake):
    path = _lane_path(overtake, 40.0)
    x = np.linspace(overtake.start.x, 20.0, 50)
    states = np.column_stack([x, np.full_like(x, overtake.lane_y), 0 * x, np.full_like(x, 3.0)])
    controls = np.zeros((49, 2))
    # An oncoming car driving straight through the ego's lane position at step 30.
    cx = states[:, 0] + 1.255
    others = np.zeros((50, 1, 4))
    others[:, 0, 0] = cx[30]
    others[:, 0, 1] = overtake.lane_y + 4.0
    others[30, 0, 1] = overtake.lane_y
    r = evaluate(_episode(overtake, path, states, controls, status="timeout", others=others,
                          sizes=[[4.3, 1.8]]))
    assert r.collision_footprint


def test_success_of_a_clean_overtake(overtake):
    path = _lane_path(overtake)
    # A fake but clean trajectory: along the oncoming lane past the car, back, stop at the goal.
    x = np.arange(overtake.start.x, 92.0 + 1e-9, 0.2)
    y = np.where((x > 30) & (x < 70), overtake.lane_y + 4.0, overtake.lane_y)
    states = np.column_stack([x, y, 0 * x, np.append(np.full(len(x) - 1, 3.0), 0.0)])
    r = evaluate(_episode(overtake, path, states, np.zeros((len(x) - 1, 2))))
    assert r.passed_lead and r.back_in_lane and r.success
    assert r.time_to_goal_s == pytest.approx(r.duration_s)
    s = summarise([r, r])
    assert s["success_rate"] == 1.0 and s["collisions_footprint"] == 0
    assert s["cte_max_m_max"] == pytest.approx(4.0)


def test_plan_failure_report(overtake):
    log = DriveLog.empty(DT)
    ep = Episode(overtake, "rrt", "lqr", 0, None, Path.empty(), log, "plan_failed", "x",
                 EpisodeConfig())
    r = evaluate(ep)
    assert not r.success and r.cte_rms_m is None and r.steps == 0
    assert r.to_json()["cte_rms_m"] is None


def test_config_validation():
    with pytest.raises(InputError, match="goal_tol_m"):
        EvalConfig(goal_tol_m=0.0)
    with pytest.raises(InputError, match="reports"):
        summarise([])
