"""The controllers and speed loop with a rate-limited steering actuator (issue 12)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rrtdrive.controllers import (
    SpeedConfig,
    SpeedController,
    SpeedProfile,
    VehicleState,
    make_controller,
)
from rrtdrive.evaluation import evaluate
from rrtdrive.sim.runner import run_episode
from rrtdrive.sim.tasks import make_scenario
from rrtdrive.speed_profile import steering_rate_speed_cap, steering_sharpness
from rrtdrive.types import InputError, Path, VehicleParams
from rrtdrive.vehicle import bicycle_step

NAMES = ["pure-pursuit", "stanley", "lqr"]
RATE = 0.4
DT = 0.05
L = VehicleParams().wheelbase


def clothoid_path(sharp_kappa: float = 0.08, step: float = 0.1) -> Path:
    """Straight 10 m, curvature ramp 0 -> 0.12 1/m at ``sharp_kappa`` 1/m^2, arc, straight."""
    ds = step
    ramp = 0.12 / sharp_kappa
    s = np.arange(0.0, 10.0 + ramp + 8.0, ds)
    kappa = np.clip((s - 10.0) * sharp_kappa, 0.0, 0.12)
    yaw = np.concatenate([[0.0], np.cumsum(0.5 * (kappa[1:] + kappa[:-1]) * ds)])
    x = np.concatenate([[0.0], np.cumsum(np.cos(0.5 * (yaw[1:] + yaw[:-1])) * ds)])
    y = np.concatenate([[0.0], np.cumsum(np.sin(0.5 * (yaw[1:] + yaw[:-1])) * ds)])
    return Path(np.column_stack([x, y, yaw, kappa]), np.zeros((0, 2)))


def test_sharpness_of_a_curvature_ramp_is_the_derivative_of_the_steering_angle():
    p = clothoid_path(0.08).samples
    s = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(p[:, :2], axis=0).T))])
    sh = steering_sharpness(s, p[:, 3], L)
    # d/ds atan(L kappa) = L kappa' / (1 + (L kappa)^2): largest at kappa = 0.
    assert sh.max() == pytest.approx(L * 0.08, rel=0.02)
    assert sh[s < 9.0].max() == 0.0 and sh[s > 12.0].max() == 0.0


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 10_000), st.floats(0.02, 0.2))
def test_sharpness_does_not_blow_up_on_repeated_or_close_samples(seed, jitter):
    p = clothoid_path(0.05).samples
    rng = np.random.default_rng(seed)
    s = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(p[:, :2], axis=0).T))])
    # Insert repeated rows and rows a micrometre apart.
    idx = np.sort(rng.choice(len(s) - 1, 20, replace=False))
    s2 = np.insert(s, idx + 1, s[idx] + rng.choice([0.0, 1e-6], 20))
    k2 = np.insert(p[:, 3], idx + 1, p[idx, 3] + rng.normal(0.0, jitter * 1e-3, 20))
    assert steering_sharpness(s2, k2, L).max() <= steering_sharpness(s, p[:, 3], L).max() + 0.02


def test_speed_cap_keeps_the_paths_steering_rate_within_the_share():
    p = clothoid_path(0.08)
    s = p.arc_length()
    cap = steering_rate_speed_cap(s, p.samples[:, 3], L, RATE, share=0.7)
    sharp = steering_sharpness(s, p.samples[:, 3], L)
    finite = np.isfinite(cap)
    assert np.all(cap[finite] * sharp[finite] <= 0.7 * RATE + 1e-12)
    assert np.all(np.isinf(cap[sharp == 0.0]))
    prof = SpeedProfile(s, p.samples[:, 3], SpeedConfig(), v_start=0.0, v_cap=cap)
    assert np.all(prof.v <= cap + 1e-12)


def test_steer_rate_share_is_validated():
    with pytest.raises(InputError, match="speed.steer_rate_share"):
        SpeedConfig(steer_rate_share=1.5)
    with pytest.raises(InputError, match="speed.comfort_jerk"):
        SpeedConfig(comfort_jerk=0.0)


def drive(ctrl, path: Path, steps: int, x0=(0.0, 0.3, 0.05)):
    """A rate-limited kinematic car (the ego's slew, without highway-env) under ``ctrl``."""
    ctrl.reset(path)
    x, y, yaw = x0
    v = steer = 0.0
    out = []
    for k in range(steps):
        a, cmd = ctrl.control(VehicleState(x, y, yaw, v, steer, k * DT))
        applied = min(max(cmd, steer - RATE * DT), steer + RATE * DT)
        out.append((a, cmd, applied, steer, v))
        v1 = max(0.0, v + a * DT)
        x, y, yaw = bicycle_step((x, y, yaw), 0.5 * (v + v1), 0.5 * (steer + applied), DT, L)
        v, steer = v1, applied
    return np.array(out)


@pytest.mark.parametrize("name", NAMES)
def test_commands_stay_within_the_actuators_reach_and_the_car_waits_for_its_wheels(name):
    car = VehicleParams(max_steer_rate=RATE)
    ctrl = make_controller(name, vehicle=car, speed=SpeedConfig(v_max=3.0))
    assert ctrl.steer_rate == RATE
    log = drive(ctrl, clothoid_path(0.08), 500)
    a, cmd, applied, steer_before, v = log.T
    # From the second call on the command is one the actuator reaches in a step.
    assert np.all(np.abs(cmd[1:] - steer_before[1:]) <= RATE * DT + 1e-12)
    # At rest until the wheels reached the start command, with no acceleration.
    moving = np.flatnonzero(v > 0.0)
    assert len(moving) and moving[0] > 1
    first = int(np.flatnonzero(a != 0.0)[0])
    assert np.all(a[:first] == 0.0)
    assert abs(cmd[first] - steer_before[first]) <= SpeedConfig().start_steer_tol + 1e-12


@pytest.mark.parametrize("name", NAMES)
def test_an_instant_actuator_starts_at_once(name):
    instant = VehicleParams(max_steer_rate=None)
    ctrl = make_controller(name, vehicle=instant, speed=SpeedConfig(v_max=3.0))
    assert ctrl.steer_rate is None
    ctrl.reset(clothoid_path())
    a, _ = ctrl.control(VehicleState(0.0, 0.3, 0.05, 0.0, 0.0, 0.0))
    a, _ = ctrl.control(VehicleState(0.0, 0.3, 0.05, 0.0, 0.0, DT))
    assert a > 0.0


def test_comfort_mode_bounds_the_jerk_also_under_a_following_cap():
    cfg = SpeedConfig(v_max=10.0)
    s = np.linspace(0.0, 200.0, 2001)
    for comfort in (False, True):
        loop = SpeedController(cfg, comfort=comfort)
        loop.reset(SpeedProfile(s, np.zeros_like(s), cfg, v_start=5.0))
        a = [loop.control(10.0 + 0.25 * k, 5.0, k * DT) for k in range(40)]
        loop.accel_cap = -2.0
        a += [loop.control(20.0 + 0.25 * k, 5.0, (40 + k) * DT) for k in range(40)]
        jerk = np.abs(np.diff(a)) / DT
        if comfort:
            assert jerk.max() <= cfg.comfort_jerk + 1e-9
            assert a[-1] == pytest.approx(-2.0)
        else:
            assert jerk.max() > 10.0  # today's loop brakes at once under the cap


def test_a_rate_limited_lqr_parking_episode_meets_the_targets():
    task = make_scenario("parking", 0, vehicle=VehicleParams(max_steer_rate=RATE))
    ep = run_episode(task, controller="lqr", seed=0)
    r = evaluate(ep)
    assert r.success and not r.collision
    assert r.max_steering_rate <= RATE + 1e-9
    assert r.cte_max_m <= 0.30 and r.cte_rms_m <= 0.10
    assert r.nuplan_comfortable
    assert math.isfinite(r.path_max_sharpness)
