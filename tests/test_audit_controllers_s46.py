"""Session-46 audit of the path-tracking controllers and the rate-limited steering actuator.

Independent checks: the plant here is written from SPEC section 1 (rear-axle bicycle,
``yaw' = v tan(delta) / L``, the front-wheel angle slewing toward the command at no more
than ``max_steer_rate``, linearly within the step), integrated with small Euler
sub-steps, not with ``rrtdrive.vehicle.bicycle_step``; the LQR gain is recomputed with
python-control and with the closed-form Riccati solution of the double integrator; the
steering laws are recomputed from the docstrings' formulas; the highway-env checks
recompute the actuator's rate, limits and gear changes from the logs / trajectory CSV.
"""

from __future__ import annotations

import csv
import json
import math
import subprocess
import sys

import control
import numpy as np
import pytest

from rrtdrive.controllers import (
    CONTROLLERS,
    LQR,
    Controller,
    PurePursuit,
    SpeedConfig,
    Stanley,
    VehicleState,
    make_controller,
)
from rrtdrive.controllers.lqr import design_gain, lateral_error_model
from rrtdrive.types import InputError, Path, Pose, VehicleParams

NAMES = sorted(CONTROLLERS)
CAR = VehicleParams()
L = CAR.wheelbase
RATE = 0.4
DT = 0.05
STEER_LIMIT = math.atan(L / CAR.min_turning_radius)
NO_WP = np.zeros((0, 2))


# --------------------------------------------------------------------------- helpers
def _path(rows) -> Path:
    return Path(np.asarray(rows, dtype=float), NO_WP)


def line_path(length: float = 40.0, gear: int = 1, ds: float = 0.25) -> Path:
    """Straight along the x axis, nose at yaw 0; reverse travels from x=length to 0."""
    xs = np.arange(0.0, length + 1e-9, ds)
    if gear < 0:
        xs = xs[::-1]
    return _path(np.column_stack([xs, 0 * xs, 0 * xs, 0 * xs, gear + 0 * xs]))


def circle_path(radius: float, arc: float, gear: int, ds: float = 0.25) -> Path:
    """A left arc of the circle centred at (0, radius), starting at the origin, nose yaw 0.

    Forward it runs counter-clockwise; in reverse the car backs along the same circle
    (travel toward -x), nose yaw ``-s / R``; in both gears kappa = tan(delta) / L = +1/R.
    """
    s = np.linspace(0.0, arc, int(round(arc / ds)) + 1)
    th = s / radius
    sign = 1.0 if gear > 0 else -1.0
    x = sign * radius * np.sin(th)
    y = radius - radius * np.cos(th)
    yaw = sign * th
    return _path(np.column_stack([x, y, yaw, 0 * s + 1.0 / radius, gear + 0 * s]))


def pieces(spec, x=0.0, y=0.0, yaw=0.0, ds=0.2) -> Path:
    """Rows of exact arcs ``(gear, kappa, length)``; each cusp row repeated with the new gear."""
    rows = []
    for gear, k, length in spec:
        n = int(math.ceil(length / ds))
        h = length / n
        for i in range(n + 1):
            rows.append([x, y, yaw, k, gear])
            if i == n:
                break
            step = h * gear
            if abs(k) < 1e-12:
                x, y = x + step * math.cos(yaw), y + step * math.sin(yaw)
            else:
                ny = yaw + k * step
                x += (math.sin(ny) - math.sin(yaw)) / k
                y -= (math.cos(ny) - math.cos(yaw)) / k
                yaw = ny
    return _path(rows)


#: Columns of :func:`simulate`'s log.
T, X, Y, YAW, V, DELTA, CMD, ACC, GEAR, WANT = range(10)


def simulate(name, path, start, rate=RATE, v0=0.0, t_max=60.0, dt=DT, sub=10, **opts):
    """Drive ``path`` with controller ``name`` on this file's own plant; returns (ctrl, log).

    log rows: t, x, y, yaw, v, delta (actual wheels at t), command, accel, gear,
    steer_wanted. The last row is the final state (command columns NaN).
    """
    veh = VehicleParams(max_steer_rate=rate)
    c = make_controller(name, vehicle=veh, **opts)
    c.reset(path, v0)
    x, y, yaw = start
    v, delta, t = v0, 0.0, 0.0
    log = []
    while t < t_max:
        a, cmd = c.control(VehicleState(x, y, yaw, v, delta, t))
        log.append((t, x, y, yaw, v, delta, cmd, a, c.gear, c.steer_wanted))
        new = min(max(cmd, -veh.max_steer), veh.max_steer)
        if rate is not None:
            new = min(max(new, delta - rate * dt), delta + rate * dt)
        v1 = v + a * dt
        h = dt / sub
        for i in range(sub):
            d = delta + (new - delta) * (i + 0.5) / sub
            vi = v + a * (i + 0.5) * h
            if v != 0.0 and vi * v < 0.0:
                vi = 0.0  # stops at zero within the step, as the ego does
            x += vi * math.cos(yaw) * h
            y += vi * math.sin(yaw) * h
            yaw += vi * math.tan(d) / L * h
        if v * v1 < 0.0 or abs(v1) < 1e-9:
            v1 = 0.0  # (the ego's own rule: a speed under 1e-9 m/s is a stop)
        v, delta, t = v1, new, t + dt
        if c.arrived and abs(v) < 1e-3:
            break
    nan = float("nan")
    log.append((t, x, y, yaw, v, delta, nan, nan, c.gear, nan))
    return c, np.asarray(log, dtype=float)


def check_actuator(log, rate=RATE, limit=STEER_LIMIT):
    """Commands within the curvature limit; the wheels never faster than the rate."""
    cmd = log[:-1, CMD]
    assert np.abs(cmd).max() <= limit + 1e-12
    assert np.abs(log[:, DELTA]).max() <= limit + 1e-12
    if rate is not None:
        steer_rate = np.abs(np.diff(np.r_[0.0, log[:, DELTA]])) / DT
        assert steer_rate.max() <= rate + 1e-9
    kappa_exec = np.abs(np.tan(log[:, DELTA])) / L
    assert kappa_exec.max() <= CAR.kappa_max + 1e-9


# --------------------------------------------------------------------------- LQR gain
@pytest.mark.parametrize("weights", [(1.0, 1.0, 4.0), (1.0, 1.0, 16.0), (2.0, 0.0, 1.0),
                                     (3.5, 0.2, 0.7), (0.01, 5.0, 100.0)])
def test_lqr_gain_is_python_controls_on_the_documented_model(weights):
    q_e, q_psi, r = weights
    A, B = lateral_error_model()
    # The docstring's model: de/ds = e_psi, de_psi/ds = u.
    assert np.array_equal(A, [[0.0, 1.0], [0.0, 0.0]]) and np.array_equal(B, [[0.0], [1.0]])
    K, _, _ = control.lqr(A, B, np.diag([q_e, q_psi]), np.array([[r]]))
    got = design_gain(q_e, q_psi, r)
    assert np.allclose(got, np.asarray(K).ravel(), rtol=1e-10, atol=1e-12)
    # Closed form for the double integrator:
    # k_e = sqrt(q_e / r), k_psi = sqrt((q_psi + 2 sqrt(q_e r)) / r).
    closed = [math.sqrt(q_e / r), math.sqrt((q_psi + 2.0 * math.sqrt(q_e * r)) / r)]
    assert np.allclose(got, closed, rtol=1e-9)
    # Stable closed loop in arc length.
    assert np.all(np.linalg.eigvals(A - B @ got.reshape(1, 2)).real < 0.0)
    c = LQR(q_e=q_e, q_psi=q_psi, r=r)
    assert np.allclose(c.gain, closed, rtol=1e-9)


def test_lqr_default_reach_and_bandwidth_figures_in_the_docstring():
    k_e, k_psi = LQR().gain
    # "approach_angle k_psi / k_e (0.45 m with the default weights)"
    assert round(0.2 * k_psi / k_e, 2) == 0.45
    # natural frequency (q_e / r)^(1/4) per metre equals sqrt(k_e) of s^2 + k_psi s + k_e
    assert math.isclose(math.sqrt(k_e), (1.0 / 4.0) ** 0.25)


@pytest.mark.parametrize("speed", [0.3, 2.0, 3.2, 6.0, 9.7])
def test_lqr_scheduled_gain_is_the_documented_rule(speed):
    """Rate-limited car: r grows to q_e (v / bandwidth)^4, designed per 0.5 m/s (rounded up)."""
    e, epsi = 0.05, 0.02  # inside the approach clip
    c = LQR()
    c.reset(line_path(60.0), speed)
    _, steer = c.control(VehicleState(5.0, e, epsi, speed, 0.0, 0.0))  # first call: no reach clip
    v_design = 0.5 * math.ceil(speed / 0.5)
    r_eff = max(4.0, 1.0 * (v_design / 2.0) ** 4)
    A, B = lateral_error_model()
    K, _, _ = control.lqr(A, B, np.diag([1.0, 1.0]), np.array([[r_eff]]))
    k_e, k_psi = np.asarray(K).ravel()
    assert steer == pytest.approx(math.atan(L * -(k_e * e + k_psi * epsi)), abs=1e-9)


# ------------------------------------------------------------------ laws vs docstrings
def _first_command(name, path, state, **opts):
    c = make_controller(name, vehicle=VehicleParams(max_steer_rate=None), **opts)
    c.reset(path, state.speed)
    return c, c.control(state)[1]


def test_forward_laws_match_docstrings():
    p = line_path(30.0, 1)
    x0, y0, yaw0, v = 3.0, 0.05, 0.02, 2.0
    s = VehicleState(x0, y0, yaw0, v, 0.0, 0.0)
    # Stanley: psi + atan2(-k e, k_soft + v), e of the front axle, positive left.
    c, steer = _first_command("stanley", p, s)
    e_front = y0 + L * math.sin(yaw0)
    assert steer == pytest.approx(-yaw0 + math.atan2(-1.5 * e_front, 0.5 + v), abs=1e-12)
    assert c.cte == pytest.approx(y0) and c.heading_error == pytest.approx(yaw0)
    # LQR: tan(delta) = L (kappa - K [e, e_psi]).
    _, steer = _first_command("lqr", p, s)
    assert steer == pytest.approx(math.atan(L * -(0.5 * y0 + math.sqrt(1.25) * yaw0)), abs=1e-12)
    # Pure pursuit: ld = max(clip(0.6 |v|, 2, 10), |cte| / tan(0.2)); atan(2 L sin(alpha) / l).
    _, steer = _first_command("pure-pursuit", p, s)
    ld = max(min(max(0.6 * v, 2.0), 10.0), y0 / math.tan(0.2))
    alpha = math.atan2(-y0, ld) - yaw0
    expect = math.atan(2 * L * math.sin(alpha) / math.hypot(ld, y0))
    assert steer == pytest.approx(expect, abs=1e-12)


def test_reverse_laws_are_the_mirrored_cars():
    """Reverse: yaw + pi, speed and steering negated, errors in the direction of travel."""
    p = line_path(30.0, -1)  # nose at yaw 0, travelling toward -x
    x0, y0, yaw0, v = 20.0, 0.05, 0.02, -2.0
    s = VehicleState(x0, y0, yaw0, v, 0.0, 0.0)
    # The car is right of its direction of travel: cte < 0; heading error is nose - nose.
    c, steer = _first_command("lqr", p, s)
    assert c.gear == -1
    assert c.cte == pytest.approx(-y0) and c.heading_error == pytest.approx(yaw0)
    u = -(0.5 * (-y0) + math.sqrt(1.25) * yaw0)
    assert steer == pytest.approx(-math.atan(L * u), abs=1e-12)
    # Stanley's steered point lies L behind the real car (ahead in the travel direction).
    _, steer = _first_command("stanley", p, s)
    e = -(y0 - L * math.sin(yaw0))  # left of travel (-x) is -y
    assert steer == pytest.approx(-(-yaw0 + math.atan2(-1.5 * e, 0.5 + abs(v))), abs=1e-12)
    _, steer = _first_command("pure-pursuit", p, s)
    ld = max(min(max(0.6 * abs(v), 2.0), 10.0), y0 / math.tan(0.2))
    alpha = math.atan2(-y0, -ld) - (math.pi + yaw0)
    expect = -math.atan(2 * L * math.sin(alpha) / math.hypot(ld, y0))
    assert steer == pytest.approx(expect, abs=1e-12)


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize("gear", [1, -1])
def test_kappa_is_tan_delta_over_L_in_both_gears(name, gear):
    """On a left arc (kappa = +1/R) the wheels settle at +atan(L / R) forward and in reverse."""
    radius = 8.0
    c, log = simulate(name, circle_path(radius, math.pi * radius, gear), (0.0, 0.0, 0.0))
    assert c.arrived
    mid = log[len(log) // 3 : 2 * len(log) // 3]
    assert np.sign(mid[:, V]).tolist() == [gear] * len(mid)
    assert mid[:, DELTA].mean() == pytest.approx(math.atan(L / radius), abs=2e-3)


# ---------------------------------------------------------------- convergence (plant)
@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize("gear", [1, -1])
@pytest.mark.parametrize("rate", [RATE, None])
def test_straight_line_converges(name, gear, rate):
    start = (0.0, 0.6, 0.1) if gear > 0 else (40.0, 0.6, 0.1)
    c, log = simulate(name, line_path(40.0, gear), start, rate=rate)
    assert c.arrived
    y = np.abs(log[:, Y])
    assert np.all(np.sign(log[:-1, V][log[:-1, V] != 0]) == gear)
    assert y[len(y) // 2 :].max() < 0.01  # settled by half way
    assert y[-1] < 0.005
    assert abs(log[-1, X] - (40.0 if gear > 0 else 0.0)) < 0.05
    check_actuator(log, rate=rate)


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize("gear", [1, -1])
@pytest.mark.parametrize("offset", [0.5, -0.5])
def test_circle_converges(name, gear, offset):
    """Constant curvature 1/8 with the car 0.5 m outside / inside: the radial error shrinks."""
    radius = 8.0
    p = circle_path(radius, 1.5 * math.pi * radius, gear)
    c, log = simulate(name, p, (0.0, -offset, 0.0), t_max=90.0)
    assert c.arrived
    err = np.abs(np.hypot(log[:, X], log[:, Y] - radius) - radius)
    n = len(err)
    assert err[0] == pytest.approx(0.5)
    # (pure pursuit drifts up to 2.7 cm inward over the last metres of a forward-only
    # path: its look-ahead runs onto the straight extension past the end)
    assert err[3 * n // 4 :].max() < 0.03
    end = p.samples[-1]
    assert math.hypot(log[-1, X] - end[0], log[-1, Y] - end[1]) < 0.05
    check_actuator(log)


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize(("v0", "offset", "yaw0"), [(8.0, 1.0, 0.0), (5.0, 2.0, -0.2)])
def test_moving_start_far_off_at_speed_settles(name, v0, offset, yaw0):
    c, log = simulate(
        name, line_path(300.0, 1), (0.0, offset, yaw0), v0=v0, t_max=80.0,
        speed=SpeedConfig(v_max=8.0),
    )  # fmt: skip
    x, y = log[:, X], np.abs(log[:, Y])
    assert y[x > 60.0].max() < 0.01
    check_actuator(log)
    if name != "stanley":
        # approach_angle (0.2 rad) bounds the heading while heading back (1 step of slack)
        assert np.abs(log[:, YAW]).max() < max(abs(yaw0), 0.2) + 0.03


# ------------------------------------------------------------------------------ cusps
THREE_POINT = [(1, 1.0 / 6.0, 8.0), (-1, -1.0 / 6.0, 6.0), (1, 1.0 / 6.0, 8.0)]


@pytest.mark.parametrize("name", NAMES)
def test_cusps_stop_then_turn_wheels_at_rest_then_reverse(name):
    p = pieces(THREE_POINT)
    c, log = simulate(name, p, (0.0, 0.0, 0.0), t_max=120.0)
    assert c.arrived
    gear, v = log[:, GEAR], log[:, V]
    changes = np.nonzero(np.diff(gear))[0] + 1
    assert gear[changes].tolist() == [-1, 1]
    g = p.samples[:, 4]
    cusps = [p.samples[i, :2] for i in range(1, len(g)) if g[i] != g[i - 1]]
    for i, cusp in zip(changes, cusps, strict=True):
        assert abs(v[i]) <= 1e-3  # the gear changes at standstill
        assert math.hypot(log[i, X] - cusp[0], log[i, Y] - cusp[1]) < 0.05
        # At rest until the wheels are within start_steer_tol of the wish, then moving
        # in the new gear.
        j = i
        while abs(log[j, DELTA] - log[j, WANT]) > 0.005:
            assert abs(log[j, V]) < 1e-9 and log[j, ACC] == 0.0
            j += 1
        assert j > i  # the wheels had to turn from lock to lock
        k = j + int(2.0 / DT)
        assert np.sign(v[k]) == gear[i]
    # The speed never has the sign opposite to the gear being driven.
    moving = v[:-1] != 0.0
    assert np.all(np.sign(v[:-1][moving]) == gear[:-1][moving])
    end = p.samples[-1]
    assert math.hypot(log[-1, X] - end[0], log[-1, Y] - end[1]) < 0.05
    check_actuator(log)


@pytest.mark.parametrize("name", NAMES)
def test_command_after_a_cusp_is_within_the_actuators_reach(name):
    # Was a bug: each gear segment forgot the time of the last call, so the first command
    # after a cusp jumped lock to lock (0.79 rad in a 0.02 rad step).
    c, log = simulate(name, pieces([(1, 1 / 6, 6.0), (-1, -1 / 6, 6.0)]), (0.0, 0.0, 0.0))
    assert c.arrived
    # Every call but the episode's first one has a known dt: the documented clip applies.
    jump = np.abs(log[1:-1, CMD] - log[1:-1, DELTA])
    assert jump.max() <= RATE * DT + 1e-12


@pytest.mark.parametrize("name", NAMES)
def test_command_never_exceeds_steer_limit_even_from_wheels_at_full_lock(name):
    # Was a bug: the reach clip came after the limit's, so wheels at 30 deg lock got 0.50.
    c = make_controller(name, steer_limit=0.3)
    c.reset(line_path(30.0), 2.0)
    lock = CAR.max_steer
    c.control(VehicleState(0.0, 0.0, 0.0, 2.0, lock, 0.0))
    _, steer = c.control(VehicleState(0.1, 0.0, 0.0, 2.0, lock, DT))
    assert abs(steer) <= c.steer_limit


# ------------------------------------------------------------------ degenerate inputs
@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize("gear", [1, -1])
def test_two_row_path_is_driven_to_its_end(name, gear):
    rows = [[0, 0, 0, 0, gear], [3, 0, 0, 0, gear]]
    if gear < 0:
        rows = rows[::-1]
    c, log = simulate(name, _path(rows), tuple(rows[0][:3]), t_max=30.0)
    assert c.arrived
    assert math.hypot(log[-1, X] - rows[-1][0], log[-1, Y]) < 0.02


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize(
    "rows",
    [
        [[0, 0, 0, 0, 1], [0, 0, 0, 0, 1]],
        [[1, 2, 0.3, 0, 1]] * 5,
        [[1, 2, 0.3, 0, 1], [1, 2, 0.3, 0, -1], [1, 2, 0.3, 0, 1]],
    ],
    ids=["zero-length", "identical", "identical-gears"],
)
def test_paths_without_length_are_refused_clearly(name, rows):
    c = make_controller(name)
    with pytest.raises(InputError, match="path: all samples coincide"):
        c.reset(_path(rows))
    with pytest.raises(RuntimeError, match="before reset"):
        c.control(VehicleState(0.0, 0.0, 0.0))


@pytest.mark.parametrize(("col", "field"), [(0, "column 0"), (3, "column 3"), (2, "column 2")])
def test_path_with_nan_names_row_and_column(col, field):
    rows = np.array([[0, 0, 0, 0, 1], [1, 0, 0, 0, 1], [2, 0, 0, 0, 1]], dtype=float)
    rows[1, col] = np.nan
    msg = f"path.samples: must be finite, got nan in row 1, {field}"
    with pytest.raises(InputError, match=msg):
        _path(rows)


def test_vehicle_state_with_nan_names_the_field():
    for field in ("x", "y", "yaw", "speed", "steer", "t"):
        kw = {"x": 0.0, "y": 0.0, "yaw": 0.0, field: float("nan")}
        with pytest.raises(InputError, match=rf"state\.{field}"):
            VehicleState(**kw)


BAD_OPTIONS = [
    (LQR, {"q_e": -1.0}, "lqr.q_e"), (LQR, {"q_e": float("nan")}, "lqr.q_e"),
    (LQR, {"r": 0.0}, "lqr.r"), (LQR, {"r": float("inf")}, "lqr.r"),
    (LQR, {"q_psi": -1.0}, "lqr.q_psi"), (LQR, {"q_psi": float("nan")}, "lqr.q_psi"),
    (LQR, {"bandwidth": 0.0}, "lqr.bandwidth"), (LQR, {"bandwidth": float("nan")}, "lqr.bandwidth"),
    (LQR, {"approach_angle": 0.0}, "lqr.approach_angle"),
    (LQR, {"approach_angle": math.pi / 2}, "lqr.approach_angle"),
    (Stanley, {"k": -1.5}, "stanley.k"), (Stanley, {"k": 0.0}, "stanley.k"),
    (Stanley, {"k": float("nan")}, "stanley.k"), (Stanley, {"k_soft": 0.0}, "stanley.k_soft"),
    (Stanley, {"k": "1"}, "stanley.k"), (Stanley, {"k": True}, "stanley.k"),
    (PurePursuit, {"ld_min": 0.0}, "pure_pursuit.ld_min"),
    (PurePursuit, {"ld_min": -1.0}, "pure_pursuit.ld_min"),
    (PurePursuit, {"ld_min": float("nan")}, "pure_pursuit.ld_min"),
    (PurePursuit, {"ld_gain": float("nan")}, "pure_pursuit.ld_gain"),
    (PurePursuit, {"ld_gain": -0.1}, "ld_gain"),
    (PurePursuit, {"ld_max": float("inf")}, "pure_pursuit.ld_max"),
    (PurePursuit, {"ld_min": 3.0, "ld_max": 2.0}, "ld_max"),
    (PurePursuit, {"compensate": 1}, "pure_pursuit.compensate"),
    (PurePursuit, {"approach_angle": float("nan")}, "pure_pursuit.approach_angle"),
    (PurePursuit, {"steer_limit": 0.0}, "controller.steer_limit"),
    (Stanley, {"steer_limit": float("nan")}, "controller.steer_limit"),
    (LQR, {"steer_limit": -0.1}, "controller.steer_limit"),
    (LQR, {"vehicle": "car"}, "controller.vehicle"),
    (Stanley, {"speed": {"v_max": 3}}, "controller.speed"),
]  # fmt: skip


@pytest.mark.parametrize(("cls", "options", "field"), BAD_OPTIONS)
def test_bad_parameters_raise_value_error_naming_them(cls, options, field):
    with pytest.raises(ValueError, match=field.replace(".", r"\.")):
        cls(**options)
    with pytest.raises(InputError, match=field.replace(".", r"\.")):
        make_controller(cls.name, **options)


def test_unknown_controller_and_option_are_named():
    with pytest.raises(InputError, match="unknown controller 'LQR'"):
        make_controller("LQR")
    with pytest.raises(InputError, match=r"controller\.k: unknown option of LQR"):
        make_controller("lqr", k=1.0)
    for name in NAMES:
        c = make_controller(name)
        assert isinstance(c, Controller) and c.name == name


# ------------------------------------------------------------- determinism, symmetry
def _mirror_rows(rows):
    r = np.array(rows, dtype=float)
    r[:, 1] *= -1
    r[:, 2] *= -1
    r[:, 3] *= -1
    return r


def _moved_rows(rows, th, dx, dy):
    r = np.array(rows, dtype=float)
    c, s = math.cos(th), math.sin(th)
    x, y = r[:, 0].copy(), r[:, 1].copy()
    r[:, 0], r[:, 1] = c * x - s * y + dx, s * x + c * y + dy
    r[:, 2] += th
    return r


@pytest.mark.parametrize("name", NAMES)
def test_deterministic_reusable_and_symmetric(name):
    rows = pieces([(1, 0.0, 2.0), (1, 1 / 8, 5.0), (-1, -1 / 10, 5.0), (1, 1 / 7, 4.0)]).samples
    start = (0.0, 0.3, 0.05)
    _, a = simulate(name, _path(rows), start)
    _, b = simulate(name, _path(rows), start)
    assert np.array_equal(a, b, equal_nan=True)
    # Mirror image: y, yaw, kappa and steering negated.
    _, m = simulate(name, _path(_mirror_rows(rows)), (0.0, -0.3, -0.05))
    assert len(m) == len(a)
    assert np.allclose(m[:, Y], -a[:, Y], atol=1e-9)
    assert np.allclose(m[:, DELTA], -a[:, DELTA], atol=1e-9)
    # Rigid motion of the whole problem: the same steering.
    th = 2.0
    moved_start = (30 - math.sin(th) * 0.3, -12 + math.cos(th) * 0.3, 0.05 + th)
    _, r = simulate(name, _path(_moved_rows(rows, th, 30.0, -12.0)), moved_start)
    assert len(r) == len(a)
    assert np.allclose(r[:, DELTA], a[:, DELTA], atol=1e-9)
    # A controller reset after driving is a fresh one.
    used = make_controller(name)
    used.reset(_path(rows))
    used.cap_accel(-1.0)
    used.hold_at(3.0)
    for i in range(30):
        used.control(VehicleState(0.1 * i, 0.3, 0.05, 0.5, 0.01, DT * i))
    used.reset(_path(rows))
    fresh = make_controller(name)
    fresh.reset(_path(rows))
    seq = [VehicleState(0.2 * i, 0.3, 0.02, 1.0, 0.01 * i, DT * i) for i in range(60)]
    assert [used.control(s) for s in seq] == [fresh.control(s) for s in seq]


# --------------------------------------------------------------- highway-env, end to end
EMPTY_MAP = {"name": "empty", "bounds": [0, 0, 60, 30], "obstacles": [],
             "start": [10, 15, 0.0], "goal": [50, 15, 0.0]}  # fmt: skip


def _applied_rate(steer: np.ndarray, dt: float) -> np.ndarray:
    return np.abs(np.diff(np.r_[0.0, steer])) / dt


def test_highway_env_far_off_start_converges_and_respects_the_actuator(tmp_path):
    from rrtdrive.evaluation import evaluate
    from rrtdrive.maps import load_map
    from rrtdrive.sim.runner import run_episode
    from rrtdrive.sim.tasks import CustomTask

    f = tmp_path / "empty.json"
    f.write_text(json.dumps(EMPTY_MAP))
    xs = np.arange(10.0, 50.0001, 0.25)
    path = _path(np.column_stack([xs, 15 + 0 * xs, 0 * xs, 0 * xs, 1 + 0 * xs]))
    logs = {}
    for name in NAMES:
        task = CustomTask.from_map(load_map(str(f)), start=Pose(10.0, 15.8, 0.05))
        ep = run_episode(task, planner=path, controller=name, seed=0)
        report = evaluate(ep)
        assert report.success and not report.collision
        states, steer = ep.log.states, ep.log.controls[:, 1]
        y = np.abs(states[:, 1] - 15.0)
        assert y[0] == pytest.approx(0.8)
        assert y[states[:, 0] > 30.0].max() < 0.005
        rate = _applied_rate(steer, ep.log.dt)
        assert rate.max() <= RATE + 1e-9
        assert report.max_steering_rate == pytest.approx(rate.max(), abs=1e-9)
        assert np.abs(steer).max() <= STEER_LIMIT + 1e-12
        logs[name] = ep.log
    # Deterministic: the same episode again, bit for bit.
    task = CustomTask.from_map(load_map(str(f)), start=Pose(10.0, 15.8, 0.05))
    again = run_episode(task, planner=path, controller="lqr", seed=0).log
    assert np.array_equal(again.states, logs["lqr"].states)
    assert np.array_equal(again.controls, logs["lqr"].controls)


@pytest.mark.parametrize("name", ["stanley", "lqr"])
def test_cli_three_point_turn_trajectory_respects_gears_and_actuator(tmp_path, name):
    m = dict(EMPTY_MAP, start=[20, 10, 0.0], goal=[40, 10, 0.0])
    (tmp_path / "map.json").write_text(json.dumps(m))
    path = pieces([(1, 0.0, 3.0), (1, 1 / 6, 8.0), (-1, -1 / 6, 6.0), (1, 1 / 6, 6.0)], 20.0, 10.0)
    (tmp_path / "p.json").write_text(json.dumps({"path": path.samples.tolist()}))
    out = subprocess.run(
        [sys.executable, "-m", "rrtdrive", "simulate", str(tmp_path / "map.json"),
         "--path", str(tmp_path / "p.json"), "--controller", name,
         "--trajectory", str(tmp_path / "t.csv"), "--json", str(tmp_path / "r.json")],
        capture_output=True, text=True, timeout=240,
    )  # fmt: skip
    assert out.returncode == 0, out.stderr
    report = json.loads((tmp_path / "r.json").read_text())
    with open(tmp_path / "t.csv") as fh:
        rows = list(csv.DictReader(fh))
    t = np.array([float(r["t"]) for r in rows])
    steer = np.array([float(r["steer"]) for r in rows])
    speed = np.array([float(r["speed"]) for r in rows])
    gear = np.array([int(float(r["gear"])) for r in rows])
    assert report["success"] and not report["collision"]
    assert np.allclose(np.diff(t), 1.0 / report["simulation_frequency"])
    rate = _applied_rate(steer, 1.0 / report["simulation_frequency"])
    assert rate.max() <= RATE + 1e-9
    assert report["max_steering_rate"] == pytest.approx(rate.max(), abs=1e-6)
    assert report["steering_rate_over_limit_share"] == 0.0
    assert np.abs(steer).max() <= STEER_LIMIT + 1e-9
    changes = np.nonzero(np.diff(gear))[0]
    assert len(changes) == report["gear_changes"] == report["path_cusps"] == 2
    for i in changes:
        assert abs(speed[i]) <= 1e-3  # stopped before the gear changed
    moving = speed != 0.0
    assert np.all(np.sign(speed[moving]) == gear[moving])
    assert report["goal_position_err_m"] < 0.2
