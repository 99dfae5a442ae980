import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from rrtdrive.evaluation.nuplan_comfort import COMFORT_BOUNDS, nuplan_comfort

T = np.arange(0.0, 12.0, 0.05)


def test_straight_constant_speed_is_comfortable_and_zero():
    c = nuplan_comfort(T, np.zeros_like(T), np.full_like(T, 5.0), 1.255)
    assert c.comfortable
    assert abs(c.lon_accel_max) < 1e-9 and abs(c.yaw_rate_abs_max) < 1e-9
    assert c.violations() == []


@settings(max_examples=30, deadline=None)
@given(st.floats(0.5, 8.0), st.floats(4.0, 40.0), st.floats(-np.pi, np.pi))
def test_circle_matches_kinematics(v, radius, yaw0):
    # A circle at constant speed: yaw rate v/R, lateral acceleration v^2/R, no jerk.
    yaw = yaw0 + v / radius * T
    c = nuplan_comfort(T, yaw, np.full_like(T, v), 1.255)
    assert np.isclose(c.yaw_rate_abs_max, v / radius, rtol=1e-6)
    assert np.isclose(c.lat_accel_abs_max, v * v / radius, rtol=1e-6)
    assert c.lon_jerk_abs_max < 1e-6
    assert c.yaw_accel_abs_max < 1e-6


def test_hard_brake_violates_longitudinal_bounds():
    # 10 m/s, then braking at 6 m/s^2 to a stop.
    v = np.where(T < 4.0, 10.0, np.maximum(10.0 - 6.0 * (T - 4.0), 0.0))
    c = nuplan_comfort(T, np.zeros_like(T), v, 1.255)
    assert not c.comfortable
    assert c.lon_accel_min < COMFORT_BOUNDS["min_lon_accel"]
    assert any("longitudinal acceleration" in s for s in c.violations())


def test_gentle_speed_change_within_bounds():
    # A smooth (cosine) change from 0 to 4 m/s over 8 s: accel <= 0.8, jerk <= 0.32.
    v = 2.0 - 2.0 * np.cos(np.pi * np.clip(T / 8.0, 0.0, 1.0))
    c = nuplan_comfort(T, np.zeros_like(T), v, 1.255)
    assert c.comfortable
    assert 0.7 < c.lon_accel_max < 0.85


def test_heading_wrap_does_not_spike_yaw_rate():
    yaw = np.angle(np.exp(1j * (0.3 * T + 3.0)))  # wraps through +-pi
    c = nuplan_comfort(T, yaw, np.full_like(T, 2.0), 1.255)
    assert np.isclose(c.yaw_rate_abs_max, 0.3, rtol=1e-6)


def test_episode_report_carries_the_drivability_figures():
    from rrtdrive.evaluation import EvalConfig, evaluate
    from rrtdrive.sim.runner import run_episode

    ep = run_episode("overtake", controller="stanley", seed=1)
    report = evaluate(ep)
    v = ep.scenario.vehicle
    direct = nuplan_comfort(
        ep.log.t, ep.log.states[:, 2], ep.log.states[:, 3], v.length / 2 - v.rear_overhang
    )
    assert report.nuplan_comfortable == direct.comfortable
    assert report.nuplan_yaw_rate_abs_max == direct.yaw_rate_abs_max
    # Sharpness from the path samples, computed independently.
    s = ep.path.samples
    d = np.arctan(v.wheelbase * s[:, 3])
    ds = np.hypot(np.diff(s[:, 0]), np.diff(s[:, 1]))
    keep = ds > 1e-9
    assert np.isclose(report.path_max_sharpness, np.max(np.abs(np.diff(d))[keep] / ds[keep]))
    # The share of steps over the steering-rate limit falls as the limit rises.
    loose = evaluate(ep, EvalConfig(steer_rate_limit=100.0))
    assert loose.steering_rate_over_limit_share == 0.0
    assert 0.0 <= report.steering_rate_over_limit_share <= 1.0
