"""The CommonRoad judge (optional extra): skipped without commonroad-drivability-checker."""

import numpy as np
import pytest

pytest.importorskip("commonroad_dc.feasibility.feasibility_checker")

from rrtdrive.commonroad_judge import judge_trajectory  # noqa: E402
from rrtdrive.types import VehicleParams  # noqa: E402
from rrtdrive.vehicle import bicycle_step  # noqa: E402

DT = 0.05


def _drive(steer, accel):
    veh = VehicleParams()
    s = [(0.0, 0.0, 0.0, 0.0)]
    for d, a in zip(steer, accel, strict=True):
        x, y, yaw, v = s[-1]
        v1 = v + a * DT
        x, y, yaw = bicycle_step((x, y, yaw), 0.5 * (v + v1), d, DT, veh.wheelbase)
        s.append((x, y, yaw, v1))
    return np.arange(len(s)) * DT, np.array(s)


def test_slow_steering_ramp_is_feasible_and_models_agree():
    n = 200
    steer = np.clip(np.arange(n) * DT * 0.3, 0.0, 0.3)  # 0.3 rad/s < 0.4
    accel = np.r_[np.full(40, 1.0), np.zeros(n - 40)]
    verdict = judge_trajectory(*_drive(steer, accel), steer, accel)
    assert verdict.feasible and verdict.first_infeasible_step is None
    assert verdict.max_steer_rate == pytest.approx(0.3)
    # CommonRoad integrates the steering inside a step, we hold it: a few cm over 60 m.
    assert verdict.max_position_drift_m < 0.05


def test_steering_jump_is_rejected_at_its_step():
    n = 120
    steer = np.r_[np.zeros(50), np.full(n - 50, 0.3)]
    accel = np.r_[np.full(40, 1.0), np.zeros(n - 40)]
    verdict = judge_trajectory(*_drive(steer, accel), steer, accel)
    assert not verdict.feasible
    assert verdict.first_infeasible_step == 50
    assert verdict.max_steer_rate == pytest.approx(0.3 / DT)


def test_the_limit_is_a_parameter():
    n = 120
    steer = np.clip(np.arange(n) * DT * 0.3, 0.0, 0.3)
    accel = np.r_[np.full(40, 1.0), np.zeros(n - 40)]
    t, states = _drive(steer, accel)
    assert not judge_trajectory(t, states, steer, accel, steer_rate_limit=0.2).feasible


def test_a_rate_limited_episode_is_feasible_and_both_models_agree():
    from rrtdrive.sim.runner import run_episode
    from rrtdrive.sim.tasks import make_scenario

    task = make_scenario("parking", 1, vehicle=VehicleParams(max_steer_rate=0.4))
    ep = run_episode(task, controller="pure-pursuit", seed=1)
    log = ep.log
    verdict = judge_trajectory(log.t, log.states, log.controls[:, 1], log.controls[:, 0])
    assert verdict.feasible
    # The ego turns its wheels within a step as the KS model does: the two agree closely.
    assert verdict.max_position_drift_m < 0.02


def test_logged_states_the_inputs_cannot_produce_are_infeasible():
    # CommonRoad's input check never looks at the states after the first: a log whose
    # positions jump 5 m sideways, with inputs that drive straight, was called feasible.
    n = 200
    t = np.arange(n + 1) * DT
    straight = np.column_stack((2 * t, 0 * t, 0 * t, np.full(n + 1, 2.0)))
    assert judge_trajectory(t, straight, np.zeros(n), np.zeros(n)).feasible
    jumped = straight.copy()
    jumped[100:, 1] += 5.0
    verdict = judge_trajectory(t, jumped, np.zeros(n), np.zeros(n))
    assert verdict.inputs_feasible and not verdict.feasible
    assert "drifts 5 m" in verdict.why
    turned = straight.copy()
    turned[100:, 2] += 0.2  # heading alone off
    assert "heading drifts" in judge_trajectory(t, turned, np.zeros(n), np.zeros(n)).why


def test_an_angle_or_speed_past_the_limits_is_infeasible():
    # CommonRoad caps both silently (a 0.9 rad angle, -30 m/s in reverse passed).
    veh = VehicleParams()
    n = 200
    steer = np.minimum(0.3 * DT * np.arange(1, n + 1), 0.9)
    t, states = _drive(np.minimum(steer, veh.max_steer), np.r_[np.full(40, 1.0), np.zeros(n - 40)])
    verdict = judge_trajectory(t, states, steer, np.r_[np.full(40, 1.0), np.zeros(n - 40)])
    assert "steering angle over" in verdict.why
    t = np.arange(n + 1) * DT
    fast = np.column_stack((-30 * t, 0 * t, 0 * t, np.full(n + 1, -30.0)))
    verdict = judge_trajectory(t, fast, np.zeros(n), np.zeros(n))
    assert not verdict.feasible and "a speed outside" in verdict.why
