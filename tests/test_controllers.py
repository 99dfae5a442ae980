"""Controllers on the kinematic bicycle: sign conventions, steady state, convergence, speed."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from speed_runs import point_mass_run

from rrtdrive.controllers import (
    LQR,
    Controller,
    PathProjector,
    PurePursuit,
    SpeedConfig,
    SpeedController,
    SpeedProfile,
    Stanley,
    VehicleState,
    make_controller,
)
from rrtdrive.controllers.lqr import design_gain, lateral_error_model
from rrtdrive.controllers.speed import PAST_END_M
from rrtdrive.controllers.stanley import front_axle_path
from rrtdrive.speed_profile import actuator_profile
from rrtdrive.types import InputError, Path, VehicleParams
from rrtdrive.vehicle import bicycle_step

NAMES = ["pure-pursuit", "stanley", "lqr"]
#: Instant steering: ``simulate`` applies each command at once (the actuator is tested
#: in test_drivable.py).
V = VehicleParams(max_steer_rate=None)


def straight_path(length: float = 60.0, step: float = 0.1) -> Path:
    xs = np.arange(0.0, length + 1e-9, step)
    return Path(np.column_stack([xs, 0 * xs, 0 * xs, 0 * xs]), np.zeros((0, 2)))


def circle_path(radius: float, angle: float = 2 * math.pi, step: float = 0.1) -> Path:
    """Counter-clockwise circle from (0, 0) heading +x, centre (0, radius)."""
    th = np.linspace(0.0, angle, int(angle * radius / step) + 1)
    x, y = radius * np.sin(th), radius * (1 - np.cos(th))
    return Path(np.column_stack([x, y, th, np.full_like(th, 1 / radius)]), np.zeros((0, 2)))


def simulate(ctrl, path: Path, x0, speed: float = 2.0, dt: float = 0.05, steps: int = 600):
    """Track with the exact bicycle at constant speed (no highway-env here)."""
    ctrl.reset(path, v_start=speed)
    x, y, yaw = x0
    out = []
    for k in range(steps):
        _, steer = ctrl.control(VehicleState(x, y, yaw, speed, 0.0, k * dt))
        out.append((x, y, yaw, steer))
        x, y, yaw = bicycle_step((x, y, yaw), speed, steer, dt, V.wheelbase)
    return np.array(out)


@pytest.mark.parametrize("name", NAMES)
def test_protocol_and_factory(name):
    c = make_controller(name)
    assert isinstance(c, Controller)
    assert c.name == name


def test_factory_rejects_bad_input():
    with pytest.raises(InputError, match="controller"):
        make_controller("mpc")
    with pytest.raises(InputError, match="controller"):
        make_controller("lqr", gain=3)
    with pytest.raises(InputError, match="pure_pursuit"):
        PurePursuit(ld_min=-1.0)


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize(
    ("y", "yaw", "expect"),
    [
        (0.5, 0.0, -1),  # left of the path: steer right
        (-0.5, 0.0, +1),  # right of the path: steer left
        (0.0, 0.2, -1),  # pointing left of the path: steer right
        (0.0, -0.2, +1),  # pointing right: steer left
    ],
)
def test_sign_conventions(name, y, yaw, expect):
    c = make_controller(name)
    c.reset(straight_path())
    _, steer = c.control(VehicleState(5.0, y, yaw, 2.0))
    assert math.copysign(1.0, steer) == expect
    assert steer != 0.0


def test_stanley_uses_the_front_axle():
    c = Stanley()
    c.reset(straight_path())
    # Rear axle 0.3 m right of the path, heading 0.2 rad left: the front axle is
    # 0.3 - L sin(0.2) ~ 0.2 m *left* of the path, so Stanley's cross-track term
    # alone pushes right; heading term pushes right too.
    c.control(VehicleState(5.0, -0.3, 0.2, 2.0))
    assert c.front_cte == pytest.approx(-0.3 + V.wheelbase * math.sin(0.2), abs=1e-6)
    assert c.cte == pytest.approx(-0.3, abs=1e-9)


def test_front_axle_path_is_the_front_wheel_trace():
    p = circle_path(8.0, math.pi / 2)
    f = front_axle_path(p, V.wheelbase)
    # Front axle radius about the circle's centre: sqrt(R^2 + L^2).
    r = np.hypot(f.samples[:, 0], f.samples[:, 1] - 8.0)
    assert np.allclose(r, math.hypot(8.0, V.wheelbase))
    assert np.allclose(f.samples[:, 2] - p.samples[:, 2], math.atan(V.wheelbase / 8.0))


@pytest.mark.parametrize("name", NAMES)
def test_steady_state_on_a_circle_is_the_curvature_angle(name):
    radius = 8.0
    c = make_controller(name)
    c.reset(circle_path(radius))
    th = 1.0
    state = VehicleState(radius * math.sin(th), radius * (1 - math.cos(th)), th, 2.0)
    _, steer = c.control(state)
    assert steer == pytest.approx(math.atan(V.wheelbase / radius), abs=0.01)


@pytest.mark.parametrize("name", NAMES)
def test_converges_from_an_offset(name):
    ctrl = make_controller(name, vehicle=V)
    traj = simulate(ctrl, straight_path(80.0), (0.0, 1.0, 0.0), steps=500)
    # After 30 m the rear axle is on the path and aligned.
    late = traj[traj[:, 0] > 30.0]
    assert np.max(np.abs(late[:, 1])) < 0.05
    assert np.max(np.abs(late[:, 2])) < 0.02


@pytest.mark.parametrize("name", NAMES)
def test_tracks_a_circle_at_the_curvature_limit(name):
    radius = 1.0 / V.kappa_max
    # Stay short of the path's end (past it the path runs straight on).
    path = circle_path(radius, 1.9 * math.pi)
    steps = int(1.75 * math.pi * radius / (2.0 * 0.05))
    traj = simulate(make_controller(name, vehicle=V), path, (0.0, 0.0, 0.0), steps=steps)
    r = np.hypot(traj[:, 0], traj[:, 1] - radius)
    assert np.max(np.abs(r - radius)) < 0.15


@pytest.mark.parametrize("name", NAMES)
def test_steering_never_exceeds_the_curvature_limit(name):
    # 0.3 m off, heading 1 rad away: full lock (from 3 m off pure pursuit now looks
    # far enough ahead to turn back at 0.13 1/m, below the limit).
    traj = simulate(make_controller(name, vehicle=V), straight_path(), (0.0, 0.3, 1.0), steps=300)
    kappa = np.tan(np.abs(traj[:, 3])) / V.wheelbase
    assert np.all(kappa <= V.kappa_max + 1e-12)
    assert np.max(kappa) == pytest.approx(V.kappa_max)  # it did saturate


def test_lqr_gain_comes_from_control_lqr():
    import control

    A, B = lateral_error_model()
    K = design_gain(1.0, 1.0, 4.0)
    K_ref, _, _ = control.lqr(A, B, np.diag([1.0, 1.0]), np.array([[4.0]]))
    assert np.allclose(K, np.asarray(K_ref).ravel())
    # Double integrator: K = [sqrt(q_e/r), sqrt(q_psi/r + 2 sqrt(q_e/r))].
    assert K == pytest.approx([0.5, math.sqrt(0.25 + 1.0)])
    closed = A - B @ K.reshape(1, 2)
    assert np.all(np.linalg.eigvals(closed).real < 0)
    assert LQR(q_e=2.0, r=8.0).gain == pytest.approx(design_gain(2.0, 1.0, 8.0))


def test_projector_on_an_arc():
    p = PathProjector(circle_path(10.0, math.pi))
    pr = p.project(0.0, -0.4)  # below the start: cte negative (right of the path)
    assert pr.cte == pytest.approx(-0.4, abs=1e-6)
    x, y, yaw, kappa = p.point_at(10.0 * math.pi / 2)
    assert (x, y) == pytest.approx((10.0, 10.0), abs=1e-3)
    assert yaw == pytest.approx(math.pi / 2, abs=1e-3) and kappa == pytest.approx(0.1)
    # Past the end: straight extension.
    x, y, yaw, kappa = p.point_at(p.length + 2.0)
    assert (x, y) == pytest.approx((-2.0, 20.0), abs=1e-3) and kappa == 0.0
    with pytest.raises(InputError, match="path"):
        PathProjector(Path(np.zeros((1, 4)), np.zeros((0, 2))))


def test_speed_profile_limits():
    cfg = SpeedConfig(v_max=5.0, a_lat_max=1.5, accel=1.0, decel=0.8)
    path = circle_path(6.0, math.pi)
    s = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(path.xy, axis=0).T))])
    kappa = np.where((s > 5.0) & (s < 12.0), 1 / 6.0, 0.0)
    prof = SpeedProfile(s, kappa, cfg, v_start=0.0)
    v = prof.v
    assert v[-1] == 0.0 and np.all(v <= cfg.v_max + 1e-12)
    assert np.all(v[kappa > 0] <= math.sqrt(1.5 * 6.0) + 1e-9)
    dv2 = np.diff(v**2) / (2 * np.diff(s))
    assert np.all(dv2 <= cfg.accel + 1e-9) and np.all(dv2 >= -cfg.decel - 1e-9)
    with pytest.raises(InputError, match="speed.v_max"):
        SpeedConfig(v_max=0.0)


def test_speed_loop_stops_at_the_end():
    cfg = SpeedConfig(v_max=3.0)
    s = np.linspace(0.0, 30.0, 301)
    ctrl = SpeedController(cfg)
    ctrl.reset(SpeedProfile(s, np.zeros_like(s), cfg))
    pos, v, _ = point_mass_run(ctrl, 0.0, 0.0)
    assert ctrl.arrived
    assert abs(pos - 30.0) < 0.05
    assert v == 0.0


def _stop_from(length: float, stop_at: float | None, speed: float, comfort: bool) -> float:
    """Point-mass run of the speed loop from where it must stop, at ``speed``: how far it ran.

    On a straight ``length`` m profile, from its end (``stop_at`` None) or from a stop
    line at ``stop_at``; asserts that the car stops within a second.
    """
    cfg = SpeedConfig()
    s = np.linspace(0.0, length, int(round(length * 10)) + 1)
    ctrl = SpeedController(cfg, comfort=comfort)
    ctrl.reset(SpeedProfile(s, np.zeros_like(s), cfg))
    ctrl.stop_at = stop_at
    start = length if stop_at is None else stop_at
    pos, v, t = point_mass_run(ctrl, start, speed, steps=400, until_arrived=False)
    assert v == 0.0 and t < 1.0
    return pos - start


def _stop_window(speed: float, dt: float = 0.05) -> float:
    # The window, or the brake's own limit where that is longer, and one step's run (the
    # command acts a step after the sample).
    return max(PAST_END_M, speed**2 / (2 * -SpeedConfig().a_min)) + speed * dt


@pytest.mark.parametrize("speed", [0.1, 0.4, 1.0])
@pytest.mark.parametrize("comfort", [False, True])
def test_a_car_past_the_end_stops_within_the_window(speed: float, comfort: bool):
    # A 0.7 m gear segment of a multi-point turn: the jerk-limited loop reached its end
    # at 0.4 m/s and, braking with v^2 / 0.1 asked anew each step, crawled 0.19 m on.
    assert _stop_from(0.7, None, speed, comfort) <= _stop_window(speed)


@pytest.mark.parametrize("speed", [0.1, 0.4, 1.0])
@pytest.mark.parametrize("comfort", [False, True])
def test_a_car_past_a_stop_line_stops_within_the_window(speed: float, comfort: bool):
    # The stop line of a traffic gate, 10 m along a 30 m path: the car is at the line.
    assert _stop_from(30.0, 10.0, speed, comfort) <= _stop_window(speed)


@pytest.mark.parametrize("short", [0.1, 0.2, 0.5])
@pytest.mark.parametrize("comfort", [False, True])
def test_a_car_at_rest_short_of_the_end_drives_on_to_it(short: float, comfort: bool):
    # A car stopped short of a cusp: the profile's braking fed forward whole (v_ref dv/ds,
    # as if the car ran at the profile's speed) held it to 1 cm/s: 5.6-6.5 s to creep on.
    cfg = SpeedConfig()
    s = np.linspace(0.0, 30.0, 301)
    ctrl = SpeedController(cfg, comfort=comfort)
    ctrl.reset(SpeedProfile(s, np.zeros_like(s), cfg))
    pos, v, t = point_mass_run(ctrl, 30.0 - short, 0.0)
    assert ctrl.arrived and v == 0.0
    assert t <= 2.5
    assert abs(pos - 30.0) <= cfg.stop_distance


def _drive_straight(cfg: SpeedConfig, length: float = 30.0, dt: float = 0.05):
    """Point-mass run of the speed loop on a straight profile: positions, commands."""
    s = np.linspace(0.0, length, int(length * 10) + 1)
    ctrl = SpeedController(cfg)
    ctrl.reset(SpeedProfile(s, np.zeros_like(s), cfg))
    pos, v, cmds = 0.0, 0.0, []
    for k in range(4000):
        a = ctrl.control(pos, v, k * dt)
        cmds.append(a)
        v1 = max(0.0, v + a * dt)
        pos += 0.5 * (v + v1) * dt
        v = v1
        if ctrl.arrived and v == 0.0 and a == 0.0:
            break
    return ctrl, pos, np.array(cmds)


def test_default_braking_is_jerk_limited_and_the_stop_tapers():
    dt = 0.05
    ctrl, pos, cmds = _drive_straight(SpeedConfig(v_max=3.0), dt=dt)
    assert ctrl.arrived and abs(pos - 30.0) < 0.05
    jerk = np.abs(np.diff(cmds)) / dt
    assert jerk.max() <= 5.0 + 1e-6  # rises (jerk_max) and falls (jerk_brake_max) alike
    assert cmds.min() < -0.9  # it did brake
    # The old stop: constant deceleration to standstill, then the hold's jump.
    old = SpeedConfig(v_max=3.0, jerk_brake_max=None, stop_taper=False)
    ctrl, pos, cmds = _drive_straight(old, dt=dt)
    assert ctrl.arrived and abs(pos - 30.0) < 0.05
    assert (np.abs(np.diff(cmds)) / dt).max() > 15.0
    with pytest.raises(InputError, match="speed.jerk_brake_max"):
        SpeedConfig(jerk_brake_max=0.0)
    with pytest.raises(InputError, match="speed.taper_start"):
        SpeedConfig(taper_start=0.0)


@pytest.mark.parametrize(
    "field, value",
    [("kp", 30.0), ("ki", 1e300), ("stop_distance", 10.0), ("stop_speed", 2.0),
     ("taper_stop_speed", 0.6)],
)  # fmt: skip
def test_speed_config_refuses_gains_and_stop_windows_past_their_bounds(field, value):
    with pytest.raises(InputError, match=f"^speed.{field}: must be <= "):
        SpeedConfig(**{field: value})
    SpeedConfig(**{field: 0.5 if "stop" in field else 15.0})  # the bound itself is taken


def test_a_following_cap_brakes_at_once():
    # A car-following law (accel_cap) must not wait for the comfort jerk limit.
    cfg = SpeedConfig(v_max=5.0)
    s = np.linspace(0.0, 100.0, 1001)
    ctrl = SpeedController(cfg)
    ctrl.reset(SpeedProfile(s, np.zeros_like(s), cfg, v_start=5.0))
    ctrl.control(10.0, 5.0, 0.0)
    ctrl.accel_cap = -3.5
    assert ctrl.control(10.25, 5.0, 0.05) == pytest.approx(-3.5)
    ctrl.accel_cap = None
    a = ctrl.control(10.5, 4.8, 0.10)  # released: rises at most jerk_max * dt
    assert a <= -3.5 + cfg.jerk_max * 0.05 + 1e-9


@pytest.mark.parametrize("name", NAMES)
def test_retarget_steers_along_the_new_path(name):
    # Re-planning switches paths while driving: every controller must steer along the
    # new one (Stanley used to keep its front-axle trace of the first path).
    xs = np.linspace(0.0, 40.0, 161)
    first = Path(np.column_stack([xs, 0 * xs, 0 * xs, 0 * xs]), np.zeros((0, 2)))
    second = Path(np.column_stack([xs, 0 * xs + 3.0, 0 * xs, 0 * xs]), np.zeros((0, 2)))
    fresh = make_controller(name)
    fresh.reset(second, v_start=2.0)
    switched = make_controller(name)
    switched.reset(first, v_start=2.0)
    switched.retarget(second, 2.0)
    state = VehicleState(5.0, 3.0, 0.0, 2.0)
    assert switched.control(state)[1] == pytest.approx(fresh.control(state)[1], abs=1e-12)


@settings(max_examples=60, deadline=None)
@given(
    slow_end=st.floats(0.0, 30.0),
    rest=st.floats(3.0, 30.0),
    slow_speed=st.floats(0.3, 2.5),
)
def test_the_comfort_loop_does_not_overshoot_the_top_of_a_rise(
    slow_end: float, rest: float, slow_speed: float
):
    # A slow stretch (a bend whose lateral-acceleration cap is slow_speed), then a rise
    # and the stop at the end, as the controllers' profile (actuator_profile) has it; the
    # actuator is fast enough not to cap it. Lagging on the rise, the jerk-limited loop's
    # PI asked for more than the profile's acceleration and could not ramp it down in
    # time: up to 0.34 m/s over the peak and 0.58 m past the end, braking at -4 m/s^2
    # (stock parking-v0 seed 32: 0.26 m/s over, -3.5 m/s^2 before the goal).
    cfg = SpeedConfig()
    length = slow_end + rest
    s = np.linspace(0.0, length, int(length / 0.25) + 2)
    kappa = np.where(s < slow_end, cfg.a_lat_max / slow_speed**2, 0.0)
    profile = actuator_profile(s, kappa, cfg, 0.0, 2.51, 1e3)
    ctrl = SpeedController(cfg, comfort=True)
    ctrl.reset(profile)
    trace: list[tuple[float, float, float, float]] = []
    pos, v, _ = point_mass_run(ctrl, 0.0, 0.0, steps=4000, trace=trace)
    assert max(step[2] for step in trace) <= float(profile.v.max()) + 0.05
    assert min(step[3] for step in trace) >= -1.5 * cfg.decel
    assert ctrl.arrived and v == 0.0 and abs(pos - length) <= cfg.stop_distance
