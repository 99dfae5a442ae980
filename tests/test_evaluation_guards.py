"""Evaluator behaviours a mutation audit found unguarded (session 38).

On hand-made episodes (``episode_logs``), each metric against its definition
computed here: curvature violations both ways, path sharpness in steering angle,
braking in the largest longitudinal acceleration, the over-limit steering-rate
share, a car still reversing at the goal not stopped, the goal heading wrapped.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from episode_logs import DT, drive_to, episode, overtake

from rrtdrive.evaluation import EvalConfig, evaluate
from rrtdrive.evaluation.comfort import curvature_violation_share, path_sharpness
from rrtdrive.evaluation.success import success_terms
from rrtdrive.types import Path, VehicleParams

# Curvature violations count right turns; path sharpness is in steering angle.

V = VehicleParams()


def test_violation_share_counts_both_turn_directions():
    kappa = np.array([-0.3, 0.1, 0.25, -0.1, -0.21, 0.0, 0.0, 0.0])
    kmax = 0.2
    expected = sum(1 for k in kappa if abs(k) > kmax) / len(kappa)  # 3 of 8
    assert curvature_violation_share(kappa, kmax, 0.0) == pytest.approx(expected)
    assert curvature_violation_share(-kappa, kmax, 0.0) == pytest.approx(expected)


def test_evaluate_counts_a_right_turn_over_the_limit():
    scen = overtake(goal=(30.0, overtake().lane_y, 0.0))
    states = drive_to(scen, 30.0)
    n = len(states)
    kmax = V.kappa_max
    steer = np.zeros(n - 1)
    steer[5:10] = -math.atan(V.wheelbase * kmax * 1.5)  # five steps turning right too hard
    r = evaluate(episode(scen, states, np.column_stack([np.zeros(n - 1), steer])))
    assert r.executed_curvature_violation_share == pytest.approx(5 / (n - 1))


def test_path_sharpness_is_the_steering_angle_per_metre():
    L = V.wheelbase
    # Curvature steps from 0 to 0.2 over 1 m, then stays.
    xs = np.array([0.0, 1.0, 2.0, 3.0])
    kappa = np.array([0.0, 0.2, 0.2, 0.2])
    path = Path(np.column_stack([xs, 0 * xs, 0 * xs, kappa]), np.zeros((0, 2)))
    assert path_sharpness(path, L) == pytest.approx(math.atan(L * 0.2) / 1.0)
# Max_long_accel is the largest magnitude, braking included.

def test_braking_counts_in_max_long_accel():
    scen = overtake(goal=(30.0, overtake().lane_y, 0.0))
    states = drive_to(scen, 30.0)
    n = len(states)
    accel = np.full(n - 1, 0.5)
    accel[-20:] = -2.5  # hard braking at the end
    r = evaluate(episode(scen, states, np.column_stack([accel, np.zeros(n - 1)])))
    assert r.max_long_accel == pytest.approx(float(np.max(np.abs(accel))))
    assert r.max_long_accel == pytest.approx(2.5)
# Steering_rate_over_limit_share is the share of steps faster than the limit.

def test_steps_between_the_limit_and_twice_it_count():
    scen = overtake(goal=(30.0, overtake().lane_y, 0.0))
    cfg = EvalConfig()
    states = drive_to(scen, 30.0)
    n = len(states)
    rate = np.zeros(n - 1)
    rate[10:20] = 1.5 * cfg.steer_rate_limit    # over the limit, under twice it
    rate[20:30] = -1.5 * cfg.steer_rate_limit   # and back
    rate[40:45] = 0.5 * cfg.steer_rate_limit    # within it
    steer = np.cumsum(rate * DT)
    r = evaluate(episode(scen, states, np.column_stack([np.zeros(n - 1), steer])), cfg)
    prev = np.concatenate([[0.0], steer[:-1]])
    expected = np.mean(np.abs(steer - prev) / DT > cfg.steer_rate_limit)
    assert expected == pytest.approx(20 / (n - 1))
    assert r.steering_rate_over_limit_share == pytest.approx(expected)
# A car still reversing has not stopped; the goal heading error is wrapped.

def test_a_car_reversing_through_the_goal_has_not_stopped():
    scen = overtake(goal=(30.0, overtake().lane_y, 0.0))
    cfg = EvalConfig()
    states = drive_to(scen, 30.0, v_end=-1.0)  # ends at the goal, backing at 1 m/s
    n = len(states)
    ep = episode(scen, states, np.zeros((n - 1, 2)))
    t = success_terms(ep, cfg)
    assert t.stopped == (abs(states[-1, 3]) <= cfg.stop_speed) and not t.stopped
    r = evaluate(ep, cfg)
    assert not r.stopped and not r.success


@pytest.mark.parametrize("goal_yaw, final_yaw", [
    (math.pi - 0.02, -math.pi + 0.02),   # facing west, either side of the wrap
    (0.05, 2 * math.pi),                 # an unwrapped logged yaw
])
def test_goal_heading_error_is_the_wrapped_angle(goal_yaw, final_yaw):
    lane_y = overtake().lane_y
    scen = overtake(goal=(30.0, lane_y, goal_yaw))
    states = drive_to(scen, 30.0, yaw_end=final_yaw)
    ep = episode(scen, states, np.zeros((len(states) - 1, 2)))
    t = success_terms(ep, EvalConfig())
    d = (final_yaw - goal_yaw) % (2 * math.pi)
    expected = min(d, 2 * math.pi - d)
    assert t.goal_heading_err_rad == pytest.approx(expected, abs=1e-9)
    assert t.reached_goal
