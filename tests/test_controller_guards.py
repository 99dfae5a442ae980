"""Controller behaviours a mutation audit found unguarded (session 38).

Each test computes what the documented law gives independently and fails on the
mutant named in its comment: the steering-rate clip, the manoeuvre braking limit,
LQR's bandwidth schedule and curvature preview, the plain pure-pursuit law on
forward-only paths, Stanley's preview, the projector's arc end and yaw unwrapping.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from rrtdrive.controllers import (
    LQR,
    PathProjector,
    PurePursuit,
    SpeedConfig,
    Stanley,
    VehicleState,
)
from rrtdrive.geometry import wrap_angle
from rrtdrive.types import Path, VehicleParams

#: Clothoid sharpness of the preview paths, 1/m^2.
C = 0.02


# The command of a rate-limited controller stays within rate * dt of the current angle.

RATE = 0.4


def _straight(gear):
    xs = np.linspace(0.0, 30.0, 121)
    if gear < 0:
        xs = xs[::-1]
    return Path(np.column_stack([xs, 0 * xs, 0 * xs, 0 * xs, gear + 0 * xs]), np.zeros((0, 2)))


@pytest.mark.parametrize("cls", [PurePursuit, Stanley, LQR])
@pytest.mark.parametrize("gear, speed", [(1, 3.0), (-1, -1.0)])
@pytest.mark.parametrize("dt", [0.05, 0.1])
def test_command_moves_at_most_rate_dt_from_the_current_angle(cls, gear, speed, dt):
    vehicle = VehicleParams(max_steer_rate=RATE)
    c = cls(vehicle=vehicle)
    c.reset(_straight(gear))
    # 1 m left of the path: every law wants a large steering angle.
    c.control(VehicleState(15.0, 1.0, 0.0, speed, 0.0, 0.0))
    current = 0.1 if gear > 0 else -0.1  # wheels turned the wrong way
    _, steer = c.control(VehicleState(15.0 + speed * dt, 1.0, 0.0, speed, current, dt))
    reach = RATE * dt
    assert abs(c.steer_wanted - current) > reach  # the clip binds
    assert abs(steer - current) <= reach + 1e-12
    # It moves as far as it can towards what it wants.
    expected = current + math.copysign(reach, c.steer_wanted - current)
    assert steer == pytest.approx(expected, abs=1e-12)
    lo, hi = c.steer_window
    assert (lo, hi) == pytest.approx((current - reach, current + reach), abs=1e-12)


# Every gear segment of a path with gears brakes at most accel_manoeuvre.

def _there_and_back(length=12.0):
    xs = np.linspace(0.0, length, int(length / 0.25) + 1)
    fwd = np.column_stack([xs, 0 * xs, 0 * xs, 0 * xs, 1 + 0 * xs])
    back = np.column_stack([xs[::-1], 0 * xs, 0 * xs, 0 * xs, -1 + 0 * xs])
    return Path(np.vstack([fwd, back]), np.zeros((0, 2)))


def _max_decel(profile, length):
    s = np.linspace(0.0, length, 4001)
    v = np.array([profile.at(x)[0] for x in s])
    # v dv/ds = d(v^2)/ds / 2, the deceleration along the profile.
    a = np.diff(v**2) / (2.0 * np.diff(s))
    return float(-a.min())


@pytest.mark.parametrize("cls", [PurePursuit, Stanley, LQR])
@pytest.mark.parametrize("rate", [None, 0.4])
def test_manoeuvre_segments_brake_at_most_accel_manoeuvre(cls, rate):
    cfg = SpeedConfig(accel=1.0, decel=1.0, accel_manoeuvre=0.5, v_max=3.0)
    c = cls(vehicle=VehicleParams(max_steer_rate=rate), speed=cfg)
    c.reset(_there_and_back())
    for k, seg in enumerate(c.segments):
        c.start_segment(k)
        assert _max_decel(c.profile, seg.length) <= cfg.accel_manoeuvre * 1.02
        # ... and it does brake (the check is not vacuous).
        assert _max_decel(c.profile, seg.length) > 0.3 * cfg.accel_manoeuvre


# The rate-limited LQR's closed-loop bandwidth in time never exceeds ``bandwidth``.
#
# Arc-length design: natural frequency (k_e)^(1/2) per metre (k_e = sqrt(q_e / r_eff)),
# so v * sqrt(k_e) per second; the docs promise the schedule keeps that <= bandwidth.

@pytest.mark.parametrize("bandwidth", [1.0, 2.0])
def test_time_bandwidth_bounded_at_every_speed(bandwidth):
    c = LQR(vehicle=VehicleParams(max_steer_rate=0.4), bandwidth=bandwidth)
    for v in np.arange(0.05, 12.0, 0.13):
        k_e, _ = c._gains(float(v))
        omega_t = v * math.sqrt(k_e)
        assert omega_t <= bandwidth * (1 + 1e-9), (v, omega_t)


# With a rate-limited actuator LQR reads the feed-forward curvature ff_preview ahead.


def _clothoid(length, n):
    """A clothoid from the origin, curvature C * s, as a path; and its arc lengths."""
    s = np.linspace(0.0, length, n)
    yaw = 0.5 * C * s**2
    ds = np.diff(s)
    mid = 0.5 * (yaw[1:] + yaw[:-1])
    x = np.concatenate([[0.0], np.cumsum(np.cos(mid) * ds)])
    y = np.concatenate([[0.0], np.cumsum(np.sin(mid) * ds)])
    return Path(np.column_stack([x, y, yaw, C * s]), np.zeros((0, 2))), s


def test_feed_forward_reads_the_curvature_one_step_ahead():
    path, s = _clothoid(20.0, 2001)
    L = VehicleParams().wheelbase
    c = LQR(vehicle=VehicleParams(max_steer_rate=0.4))
    c.reset(path)
    i0, i1 = 500, 520  # 5.0 m and 5.2 m along
    v, dt = 2.0, 0.1
    row = path.samples
    c.control(VehicleState(row[i0, 0], row[i0, 1], row[i0, 2], v, 0.0, 0.0))
    c.control(VehicleState(row[i1, 0], row[i1, 1], row[i1, 2], v, math.atan(L * C * s[i1]), dt))
    assert c.ff_preview == pytest.approx(v * dt)
    # On the path (no error): the command is the curvature v * dt ahead of the car.
    assert abs(c.cte) < 1e-6 and abs(c.heading_error) < 1e-6
    assert c.steer_wanted == pytest.approx(math.atan(L * C * (s[i1] + v * dt)), abs=1e-6)


# On a forward-only path pure pursuit is the plain law, whatever ``compensate`` says.


@pytest.mark.parametrize("offset", [0.0, 0.3, -0.3])
def test_forward_only_path_uses_the_plain_chord_law(offset):
    path, _ = _clothoid(30.0, 301)
    vehicle = VehicleParams(max_steer_rate=None)
    row = path.samples[50]  # 5 m along, kappa 0.1 (under the steering limit)
    nx, ny = -math.sin(row[2]), math.cos(row[2])
    state = VehicleState(row[0] + offset * nx, row[1] + offset * ny, row[2], 2.0)
    c = PurePursuit(vehicle=vehicle, compensate=True)
    c.reset(path)
    _, steer = c.control(state)
    # Plain pure pursuit, computed independently: the look-ahead point ld of arc length
    # past the projection, the arc through it: kappa = 2 sin(alpha) / l.
    ld = c.lookahead
    proj = c.projector.project(state.x, state.y)
    tx, ty = c.projector.point_at(proj.s + ld)[:2]
    alpha = math.atan2(ty - state.y, tx - state.x) - state.yaw
    chord = math.hypot(tx - state.x, ty - state.y)
    plain = math.atan(vehicle.wheelbase * 2.0 * math.sin(alpha) / chord)
    plain = min(max(plain, -c.steer_limit), c.steer_limit)
    assert steer == pytest.approx(plain, abs=1e-9)
    c2 = PurePursuit(vehicle=vehicle, compensate=False)
    c2.reset(path)
    assert c2.control(state)[1] == pytest.approx(steer, abs=1e-12)


# Rate-limited Stanley on a circle, car on it: steers the circle's angle atan(L k).

@pytest.mark.parametrize("k", [0.1, -0.15])
def test_on_a_circle_with_preview_steers_the_circles_angle(k):
    vehicle = VehicleParams(max_steer_rate=0.4)
    L = vehicle.wheelbase
    s = np.linspace(0.0, 1.5 * math.pi / abs(k), 2001)
    yaw = k * s
    path = Path(np.column_stack([np.sin(yaw) / k, (1 - np.cos(yaw)) / k, yaw, k + 0 * s]),
                np.zeros((0, 2)))
    c = Stanley(vehicle=vehicle)
    c.reset(path)
    v, dt = 2.0, 0.1
    want = math.atan(L * k)
    for i, t in ((400, 0.0), (420, dt)):
        row = path.samples[i]
        c.control(VehicleState(row[0], row[1], row[2], v, want, t))
    assert c.ff_preview == pytest.approx(v * dt)  # the preview is active
    assert c.steer_wanted == pytest.approx(want, abs=2e-3)


# PathProjector past the end on the end's circle; yaw interpolated across +-pi.

def _arc(k, yaw0, length, n=201):
    s = np.linspace(0.0, length, n)
    yaw = yaw0 + k * s
    x = (np.sin(yaw) - math.sin(yaw0)) / k
    y = -(np.cos(yaw) - math.cos(yaw0)) / k
    return Path(np.column_stack([x, y, wrap_angle(yaw), k + 0 * s]), np.zeros((0, 2))), s


@pytest.mark.parametrize("k", [0.2, -0.25])
@pytest.mark.parametrize("yaw0", [0.0, 1.0, 2.5])
def test_arc_end_continues_on_the_circle(k, yaw0):
    path, s = _arc(k, yaw0, 5.0)
    p = PathProjector(path, arc_end=True)
    for d in (0.5, 2.0, 4.0):
        x, y, yaw, kappa = p.point_at(p.length + d)
        # The analytic circle point (the same circle the path lies on).
        y1 = yaw0 + k * (s[-1] + d)
        ex = (math.sin(y1) - math.sin(yaw0)) / k
        ey = -(math.cos(y1) - math.cos(yaw0)) / k
        assert (x, y) == pytest.approx((ex, ey), abs=1e-3)
        assert wrap_angle(yaw - y1) == pytest.approx(0.0, abs=1e-6)
        assert kappa == k


def test_heading_is_continuous_across_plus_minus_pi():
    # A left turn through heading pi (westwards at the top of the circle), yaw wrapped.
    k = 0.2
    path, s = _arc(k, 2.8, 3.0, n=13)
    assert np.any(np.diff(path.samples[:, 2]) < -math.pi)  # the stored yaw jumps
    p = PathProjector(path)
    for q in np.linspace(0.1, 2.9, 15):
        yaw_true = 2.8 + k * q
        x, y, yaw, _ = p.point_at(q)
        assert wrap_angle(yaw - yaw_true) == pytest.approx(0.0, abs=1e-2)
        pr = p.project(x, y)
        assert wrap_angle(pr.yaw - yaw_true) == pytest.approx(0.0, abs=1e-2)
