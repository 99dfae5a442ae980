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


@settings(max_examples=20, deadline=None)
@given(st.sampled_from([15.0, 25.0, 30.0]), st.floats(1.0, 4.0))
def test_any_log_rate_is_judged_on_nuplans_0_1_s_grid(freq, top):
    # The same smooth speed change logged at 20 Hz and at another rate: the same
    # figures (every round(0.1 / dt)-th sample stepped 0.133 s at 15 Hz, 0.08 s at 25 Hz).
    def speed(t):
        return top / 2 * (1 - np.cos(np.pi * np.clip(t / 4.0, 0.0, 1.0)))

    ref = nuplan_comfort(T, 0.05 * T, speed(T), 1.255)
    t = np.arange(0.0, 12.0, 1.0 / freq)
    c = nuplan_comfort(t, 0.05 * t, speed(t), 1.255)
    assert np.isclose(c.lon_jerk_abs_max, ref.lon_jerk_abs_max, rtol=0.03)
    assert np.isclose(c.jerk_abs_max, ref.jerk_abs_max, rtol=0.03)
    assert np.isclose(c.lon_accel_max, ref.lon_accel_max, rtol=0.02)


def test_too_short_a_drive_has_no_figures():
    # Under 0.3 s there are fewer than four samples at 0.1 s: null, not zeros.
    for n in (1, 2, 6):
        t = np.arange(n) * 0.05
        assert nuplan_comfort(t, 0.01 * t, np.full(n, 1.0), 1.255) is None
    assert nuplan_comfort(np.arange(7) * 0.05, np.zeros(7), np.ones(7), 1.255) is not None


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
