"""Mutation guards for the closed-loop controllers (``rrtdrive.controllers``).

Each test states a law of a controller against an independent reference: the
pure-pursuit arc through the look-ahead point in the car's own frame, Stanley's law
from the front axle's offset worked out by hand, the LQR gain from the Riccati
equation (scipy) and its closed form, the projection from shapely, the speed loop
on a point mass. Found by mutation testing of ``controllers/`` (each test names the
slips it catches in its docstring).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.linalg
from gear_paths import integrate_pieces
from hypothesis import given, settings
from hypothesis import strategies as st
from shapely.geometry import LineString, Point

from rrtdrive.controllers import (
    LQR,
    PathProjector,
    PurePursuit,
    SpeedConfig,
    SpeedController,
    SpeedProfile,
    Stanley,
    VehicleState,
    gear_segments,
    make_controller,
)
from rrtdrive.controllers.lqr import design_gain
from rrtdrive.types import InputError, InputWarning, Path, VehicleParams

#: Instant steering: the law's output is the command (no rate window).
INSTANT = VehicleParams(max_steer_rate=None)
NO_WAYPOINTS = np.zeros((0, 2))


def line_path(length: float = 40.0, step: float = 0.1, gear: int = 1) -> Path:
    """A straight path along +x from the origin (``gear`` -1: driven backwards along -x).

    In reverse the car's nose points +x while it travels toward -x: the rows run from
    ``x = 0`` down to ``x = -length``.
    """
    xs = np.arange(0.0, length + 1e-9, step)
    if gear < 0:
        xs = -xs
    z = np.zeros_like(xs)
    return Path(np.column_stack([xs, z, z, z, np.full_like(xs, gear)]), NO_WAYPOINTS)


def arc_steer(wheelbase: float, px: float, py: float) -> float:
    """Steering angle of the circle tangent to the car's heading through car-frame ``(px, py)``.

    The circle through the rear axle, tangent to its heading, through the point has
    curvature ``2 py / (px^2 + py^2)`` whichever way the car drives along it.
    """
    return math.atan(wheelbase * 2.0 * py / (px * px + py * py))


def car_frame(x: float, y: float, yaw: float, tx: float, ty: float) -> tuple[float, float]:
    """``(tx, ty)`` in the frame of a car at ``(x, y)`` with nose heading ``yaw``."""
    dx, dy = tx - x, ty - y
    c, s = math.cos(yaw), math.sin(yaw)
    return dx * c + dy * s, -dx * s + dy * c


# --- gear segments -------------------------------------------------------------------


def test_a_repeated_cusp_row_is_no_gear_segment() -> None:
    """A zero-length reverse 'segment' (one repeated row) is dropped, not driven.

    Guards gears.py's length filter: a segment of one row would be handed to a
    projector that needs two distinct samples (the controller would refuse the path).
    """
    xs = np.linspace(0.0, 5.0, 11)
    z = np.zeros_like(xs)
    fwd = np.column_stack([xs, z, z, z, np.ones_like(xs)])
    cusp = np.array([[5.0, 0.0, 0.0, 0.0, -1.0]])
    again = np.column_stack([xs + 5.0, z, z, z, np.ones_like(xs)])
    path = Path(np.vstack([fwd, cusp, again]), NO_WAYPOINTS)
    segs = gear_segments(path)
    assert [s.gear for s in segs] == [1, 1]
    assert [s.s0 for s in segs] == pytest.approx([0.0, 5.0])
    assert [s.length for s in segs] == pytest.approx([5.0, 5.0])
    c = PurePursuit(vehicle=INSTANT)
    c.reset(path)  # drivable: every segment has two distinct samples
    assert len(c.segments) == 2


# --- pure pursuit --------------------------------------------------------------------


@pytest.mark.parametrize("wheelbase", [2.51, 2.0])
@pytest.mark.parametrize(
    ("speed", "y", "yaw"),
    [
        (1.0, 0.1, 0.0),  # slow: ld_min
        (10.0, -0.2, 0.05),  # ld_gain * v
        (25.0, 0.3, -0.02),  # capped at ld_max
        (-10.0, 0.2, 0.0),  # rolling back in forward gear: |v| schedules the look-ahead
        (1.0, 1.5, 0.0),  # far off: the approach angle lengthens the look-ahead
    ],
)
def test_pure_pursuit_steers_the_arc_through_the_lookahead_point(
    wheelbase: float, speed: float, y: float, yaw: float
) -> None:
    """Forward: the arc through the point ``clip(0.6 |v|, 2, 10)`` m (at least
    ``|cte| / tan(0.2)``) ahead of the projection, curvature ``2 py / l^2`` in the car frame.

    Guards the look-ahead schedule's clamps, the approach angle, the chord law's
    factor 2 and sign, and the wheelbase in the steering angle.
    """
    v = VehicleParams(wheelbase=wheelbase, max_steer_rate=None)
    c = PurePursuit(vehicle=v, steer_limit=v.max_steer)
    c.reset(line_path())
    x = 5.0
    _, steer = c.control(VehicleState(x, y, yaw, speed))
    ld = min(max(0.6 * abs(speed), 2.0), 10.0)
    ld = max(ld, abs(y) / math.tan(0.2))
    assert c.lookahead == pytest.approx(ld)
    px, py = car_frame(x, y, yaw, x + ld, 0.0)
    assert steer == pytest.approx(arc_steer(wheelbase, px, py), abs=1e-9)


@pytest.mark.parametrize(("speed", "y", "yaw"), [(-1.0, 0.2, 0.0), (-4.0, -0.3, 0.1)])
def test_pure_pursuit_reversing_aims_at_a_point_behind_the_car(
    speed: float, y: float, yaw: float
) -> None:
    """Reverse: the look-ahead point lies ``ld`` metres *behind* the car along the path.

    Guards the look-ahead's direction and the mirrored steering sign in reverse.
    """
    c = PurePursuit(vehicle=INSTANT, steer_limit=INSTANT.max_steer)
    c.reset(line_path(gear=-1))
    x = -5.0
    _, steer = c.control(VehicleState(x, y, yaw, speed))
    assert c.gear == -1
    ld = min(max(0.6 * abs(speed), 2.0), 10.0)
    px, py = car_frame(x, y, yaw, x - ld, 0.0)
    assert px < 0.0  # behind the car
    assert steer == pytest.approx(arc_steer(INSTANT.wheelbase, px, py), abs=1e-9)


# --- Stanley -------------------------------------------------------------------------


@pytest.mark.parametrize(("k", "k_soft"), [(1.5, 0.5), (2.0, 1.3)])
@pytest.mark.parametrize(
    ("speed", "y", "yaw"), [(0.0, 0.1, 0.0), (2.0, -0.2, 0.05), (6.0, 0.3, -0.1)]
)
def test_stanley_law_on_a_straight_from_the_front_axle(
    k: float, k_soft: float, speed: float, y: float, yaw: float
) -> None:
    """``delta = -yaw + atan2(-k e, k_soft + |v|)``, ``e = y + L sin(yaw)`` the front axle's offset.

    Guards the front-axle point, the heading term's sign, the cross-track sign and
    the softening speed (which keeps the gain finite at rest).
    """
    c = Stanley(vehicle=INSTANT, k=k, k_soft=k_soft, steer_limit=INSTANT.max_steer)
    if (k, k_soft) == (1.5, 0.5):  # the defaults (docs/closed_loop.md: k = 1.5, k_soft = 0.5 m/s)
        c = Stanley(vehicle=INSTANT, steer_limit=INSTANT.max_steer)
    c.reset(line_path())
    _, steer = c.control(VehicleState(5.0, y, yaw, speed))
    e = y + INSTANT.wheelbase * math.sin(yaw)
    want = -yaw + math.atan2(-k * e, k_soft + abs(speed))
    assert abs(want) < INSTANT.max_steer  # the cases stay inside the limit
    assert steer == pytest.approx(want, abs=1e-9)


@pytest.mark.parametrize(("speed", "y", "yaw"), [(-1.0, 0.2, 0.0), (-3.0, -0.1, 0.08)])
def test_stanley_in_reverse_steers_its_point_behind_the_car(
    speed: float, y: float, yaw: float
) -> None:
    """Reverse: the steered point lies ``L`` behind the rear axle; the law is mirrored.

    The mirrored car (heading ``yaw + pi``) travels along -x; its offset ``e`` is left of
    that direction (``-y`` of the point ``L`` behind), and the real steering is the
    mirrored law negated. Guards Stanley's reverse handling.
    """
    k, k_soft = 1.5, 0.5
    c = Stanley(vehicle=INSTANT, k=k, k_soft=k_soft, steer_limit=INSTANT.max_steer)
    c.reset(line_path(gear=-1))
    _, steer = c.control(VehicleState(-5.0, y, yaw, speed))
    L = INSTANT.wheelbase
    point_y = y - L * math.sin(yaw)
    e = -point_y
    psi = -yaw  # path direction pi minus mirrored heading yaw + pi
    want = -(psi + math.atan2(-k * e, k_soft + abs(speed)))
    assert steer == pytest.approx(want, abs=1e-9)


# --- LQR -----------------------------------------------------------------------------


@pytest.mark.parametrize(("q_e", "q_psi", "r"), [(1.0, 1.0, 4.0), (4.0, 0.5, 2.0), (0.3, 2.0, 9.0)])
def test_lqr_gain_is_the_riccati_solution(q_e: float, q_psi: float, r: float) -> None:
    """The gain solves the Riccati equation of the double integrator ``e'' = u`` (scipy).

    Closed form ``K = [sqrt(q_e / r), sqrt(q_psi / r + 2 sqrt(q_e / r))]``. Guards the
    error model, the order of the state weights and the input weight.
    """
    A = np.array([[0.0, 1.0], [0.0, 0.0]])
    B = np.array([[0.0], [1.0]])
    P = scipy.linalg.solve_continuous_are(A, B, np.diag([q_e, q_psi]), np.array([[r]]))
    K_ref = (B.T @ P / r).ravel()
    assert design_gain(q_e, q_psi, r) == pytest.approx(K_ref, rel=1e-9)
    closed = [math.sqrt(q_e / r), math.sqrt(q_psi / r + 2.0 * math.sqrt(q_e / r))]
    assert LQR(q_e=q_e, q_psi=q_psi, r=r).gain == pytest.approx(closed, rel=1e-9)


def _lqr_steer(k_e: float, k_psi: float, e: float, e_psi: float, kappa: float, wheelbase: float,
               approach: float = 0.2) -> float:
    reach = approach * k_psi / k_e
    u = -(k_e * min(max(e, -reach), reach) + k_psi * e_psi)
    return math.atan(wheelbase * (kappa + u))


@pytest.mark.parametrize(
    ("y", "yaw"), [(0.1, 0.0), (-0.3, 0.05), (0.0, -0.1), (2.0, 0.0), (-1.0, 0.1)]
)
def test_lqr_law_on_a_straight(y: float, yaw: float) -> None:
    """``tan(delta) = L (kappa - k_e clip(e) - k_psi e_psi)``, ``e`` clipped at
    ``0.2 k_psi / k_e`` far off (the approach angle).

    Guards the gains' roles, the heading term's sign and the approach clip.
    """
    q_e, q_psi, r = 0.5, 2.0, 6.0
    k_e = math.sqrt(q_e / r)
    k_psi = math.sqrt(q_psi / r + 2.0 * k_e)
    c = LQR(vehicle=INSTANT, q_e=q_e, q_psi=q_psi, r=r, steer_limit=INSTANT.max_steer)
    c.reset(line_path())
    _, steer = c.control(VehicleState(5.0, y, yaw, 2.0))
    want = _lqr_steer(k_e, k_psi, y, yaw, 0.0, INSTANT.wheelbase)
    assert abs(want) < INSTANT.max_steer
    assert steer == pytest.approx(want, abs=1e-9)


@pytest.mark.parametrize("speed", [0.3, 2.2, 4.9, 5.2, 7.7])
def test_lqr_gain_schedule_with_a_slow_actuator(speed: float) -> None:
    """Rate-limited car: ``r`` grows to ``q_e (v / bandwidth)^4``, ``v`` rounded *up* to 0.5 m/s.

    The law's angle (:attr:`steer_wanted`, before the actuator's reach) uses the gain
    of that weight. Guards the schedule's rounding, its exponent and that the
    scheduled gain is used.
    """
    car = VehicleParams(max_steer_rate=0.4)
    q_e, q_psi, r, bandwidth = 1.0, 1.0, 4.0, 2.0
    c = LQR(vehicle=car, q_e=q_e, q_psi=q_psi, r=r, bandwidth=bandwidth,
            steer_limit=car.max_steer)
    c.reset(line_path(), v_start=speed)
    y, yaw = 0.05, 0.02
    c.control(VehicleState(5.0, y, yaw, speed, 0.0, 0.0))
    v_design = 0.5 * math.ceil(speed / 0.5)
    r_eff = max(r, q_e * (v_design / bandwidth) ** 4)
    k_e = math.sqrt(q_e / r_eff)
    k_psi = math.sqrt(q_psi / r_eff + 2.0 * k_e)
    want = _lqr_steer(k_e, k_psi, y, yaw, 0.0, car.wheelbase)
    assert c.steer_wanted == pytest.approx(want, abs=1e-9)


# --- the shared tracking machinery ---------------------------------------------------


@pytest.mark.parametrize("cls", [PurePursuit, Stanley, LQR])
def test_a_steer_limit_past_full_lock_is_cut_to_full_lock(cls: type) -> None:
    """``steer_limit`` wider than the car's ``max_steer`` commands at most full lock.

    Guards the cap of the limit by the actuator's own angle.
    """
    # ... and says so (since session 46: a tuned limit that never acts was silent).
    with pytest.warns(InputWarning, match="beyond the car's"):
        c = cls(vehicle=INSTANT, steer_limit=1.2)
    assert c.steer_limit == pytest.approx(INSTANT.max_steer)
    c.reset(line_path())
    for yaw in (1.2, -1.2):  # heading far off the path: every law asks for more than lock
        _, steer = c.control(VehicleState(5.0, 0.0, yaw, 0.5))
        assert steer == pytest.approx(-math.copysign(INSTANT.max_steer, yaw))
    # A slow actuator: the law's angle (before the actuator's reach) is cut the same way.
    with pytest.warns(InputWarning, match="beyond the car's"):
        slow = cls(vehicle=VehicleParams(max_steer_rate=0.4), steer_limit=1.2)
    slow.reset(line_path())
    for yaw in (1.2, -1.2):
        slow.control(VehicleState(5.0, 0.0, yaw, 0.5))
        assert slow.steer_wanted == pytest.approx(-math.copysign(INSTANT.max_steer, yaw))


def three_point_turn() -> Path:
    """Forward left 8 m, reverse right 6 m, forward left 8 m, on the exact bicycle."""
    k = 1.0 / VehicleParams().min_turning_radius
    return integrate_pieces([(1, k, 8.0), (-1, -k, 6.0), (1, k, 8.0)])


def test_remaining_is_the_distance_to_the_next_stop_on_every_segment() -> None:
    """:attr:`remaining` on the second gear segment is measured from that segment's start.

    Reference: shapely's projection of the car on the segment's own polyline. Guards
    the offset of the segment's start in the travelled length.
    """
    path = three_point_turn()
    c = PurePursuit(vehicle=INSTANT)
    c.reset(path)
    seg = c.segments[1]
    assert seg.s0 == pytest.approx(8.0, abs=1e-3)
    c.start_segment(1)
    line = LineString(seg.path.samples[:, :2])
    for frac in (0.2, 0.5, 0.8):
        x, y = line.interpolate(frac, normalized=True).coords[0]
        yaw = float(np.interp(frac * line.length, c.projector.s, c.projector.yaw)) - math.pi
        c.control(VehicleState(x, y, yaw, -0.5, 0.0, 0.0))
        assert c.s == pytest.approx(seg.s0 + frac * line.length, abs=1e-6)
        assert c.remaining == pytest.approx((1.0 - frac) * line.length, abs=1e-6)


def test_next_cusp_is_where_the_segment_being_driven_ends() -> None:
    """:attr:`next_cusp_s`: the travelled length of the next cusp ahead (8 m, 14 m), then None.

    Reference: the pieces' lengths the turn was integrated from. Guards the cusp's
    position (the end of the segment, not its start).
    """
    c = PurePursuit(vehicle=INSTANT)
    c.reset(three_point_turn())
    assert c.next_cusp_s == pytest.approx(8.0, abs=1e-3)
    c.start_segment(1)
    assert c.next_cusp_s == pytest.approx(14.0, abs=1e-3)
    c.start_segment(2)
    assert c.next_cusp_s is None


# --- projection ----------------------------------------------------------------------


def clothoid_path(k0: float, k1: float, length: float = 12.0, step: float = 0.1) -> Path:
    """Rows of the curve ``kappa(s) = k0 + k1 s`` from the origin (midpoint-rule positions)."""
    n = int(round(length / step))
    s = np.linspace(0.0, length, n + 1)
    yaw = k0 * s + 0.5 * k1 * s * s
    mid = k0 * (s[:-1] + 0.5 * step) + 0.5 * k1 * (s[:-1] + 0.5 * step) ** 2
    x = np.concatenate([[0.0], np.cumsum(step * np.cos(mid))])
    y = np.concatenate([[0.0], np.cumsum(step * np.sin(mid))])
    return Path(np.column_stack([x, y, yaw, k0 + k1 * s]), NO_WAYPOINTS)


@settings(max_examples=60, deadline=None)
@given(
    k0=st.floats(-0.08, 0.08),
    k1=st.floats(-0.006, 0.006),
    frac=st.floats(0.05, 0.95),
    offset=st.floats(-1.0, 1.0).filter(lambda d: abs(d) > 1e-3),
)
def test_projection_is_shapelys_nearest_point(
    k0: float, k1: float, frac: float, offset: float
) -> None:
    """A point beside a curved path projects on its nearest point (shapely), left positive.

    The foot, its arc length, the offset's size and side, and the heading and
    curvature interpolated at the foot along the rows. Guards the segment search,
    the foot's clamp into its segment, the offset's sign and the interpolations.
    """
    path = clothoid_path(k0, k1)
    rows = path.samples
    line = LineString(rows[:, :2])
    s_rows = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(rows[:, :2], axis=0).T))])
    base = frac * line.length
    bx, by = line.interpolate(base).coords[0]
    yaw0 = float(np.interp(base, s_rows, rows[:, 2]))
    px, py = bx - offset * math.sin(yaw0), by + offset * math.cos(yaw0)
    pr = PathProjector(path).project(px, py)
    # The foot is a nearest point (two tie where the point lies on a row's bisector)...
    dist = line.distance(Point(px, py))
    assert math.hypot(pr.x - px, pr.y - py) == pytest.approx(dist, abs=1e-9)
    # ... on the polyline, at its own arc length.
    assert line.distance(Point(pr.x, pr.y)) < 1e-9
    s_ref = line.project(Point(pr.x, pr.y))
    assert pr.s == pytest.approx(s_ref, abs=1e-6)
    assert abs(pr.cte) == pytest.approx(dist, abs=1e-3)
    assert math.copysign(1.0, pr.cte) == math.copysign(1.0, offset)
    assert pr.yaw == pytest.approx(float(np.interp(s_ref, s_rows, rows[:, 2])), abs=1e-9)
    assert pr.kappa == pytest.approx(float(np.interp(s_ref, s_rows, rows[:, 3])), abs=1e-9)
    # point_at walks the same polyline by arc length.
    x, y, yaw, kappa = PathProjector(path).point_at(base)
    assert (x, y) == pytest.approx((bx, by), abs=1e-9)
    assert yaw == pytest.approx(yaw0, abs=1e-9)
    assert kappa == pytest.approx(float(np.interp(base, s_rows, rows[:, 3])), abs=1e-9)


@pytest.mark.parametrize("end", ["start", "end"])
@pytest.mark.parametrize(("along", "offset"), [(0.7, 0.4), (3.0, -0.9)])
def test_projection_runs_straight_on_past_either_end(end: str, along: float, offset: float) -> None:
    """Beyond either end the path runs straight on along the end row's heading.

    Reference: shapely on the polyline with 100 m straight extensions along the end
    headings. Guards the extension's choice, its arc length, its offset's sign and its
    zero curvature.
    """
    path = clothoid_path(0.06, 0.004)
    rows = path.samples
    first, last = rows[0], rows[-1]
    ext = np.vstack([
        first[:2] - 100.0 * np.array([math.cos(first[2]), math.sin(first[2])]),
        rows[:, :2],
        last[:2] + 100.0 * np.array([math.cos(last[2]), math.sin(last[2])]),
    ])
    line = LineString(ext)
    row = first if end == "start" else last
    sign = -1.0 if end == "start" else 1.0
    c, s_ = math.cos(row[2]), math.sin(row[2])
    px = row[0] + sign * along * c - offset * s_
    py = row[1] + sign * along * s_ + offset * c
    p = PathProjector(path)
    if end == "end":
        p.reset_hint(len(rows))  # the search starts where a car would be, near the end
    pr = p.project(px, py)
    assert pr.s == pytest.approx(line.project(Point(px, py)) - 100.0, abs=1e-6)
    assert pr.cte == pytest.approx(offset, abs=1e-6)
    assert pr.yaw == pytest.approx(row[2]) and pr.kappa == 0.0
    x, y, yaw, kappa = p.point_at(pr.s)
    assert (x, y) == pytest.approx(line.interpolate(pr.s + 100.0).coords[0], abs=1e-6)
    assert yaw == pytest.approx(row[2]) and kappa == 0.0


def test_the_segment_search_moves_on_over_a_tie() -> None:
    """A point as near to the next segment as to this one is taken on the next one.

    "Walks forward while the next segment is at least as near": a car exactly abreast a
    row (both segments' nearest point) counts on the segment ahead, so the search
    never stalls. Guards the tie rule of the forward walk.
    """
    p = PathProjector(line_path(length=10.0, step=0.5))
    assert p.nearest_segment(2.0, 0.3) == 4  # abreast row 4: segments 3 and 4 tie
    p.reset_hint(7)
    assert p.nearest_segment(2.0, 0.3) == 4 or p.nearest_segment(2.0, 0.3) == 3


@pytest.mark.parametrize("cls", [PurePursuit, Stanley, LQR])
def test_retarget_keeps_the_acceleration_command_continuous(cls: type) -> None:
    """A path stitched on at the car keeps the speed loop's state: the command does not jump.

    Point mass on a straight, accelerating from rest; after :meth:`retarget` onto the
    rest of the line the next command moves at most ``jerk_max dt`` from the last one
    (a fresh loop would start from 0 with no step to rise in). Guards retarget's
    carrying over of the loop's state.
    """
    c = cls(vehicle=INSTANT)
    c.reset(line_path(60.0))
    dt, x, v, a = 0.05, 0.0, 0.0, 0.0
    for k in range(30):
        a, _ = c.control(VehicleState(x, 0.0, 0.0, v, 0.0, k * dt))
        x, v = x + v * dt + 0.5 * a * dt * dt, v + a * dt
    assert a > 0.3  # still speeding up
    xs = np.arange(x, 60.0, 0.1)
    z = np.zeros_like(xs)
    c.retarget(Path(np.column_stack([xs, z, z, z]), NO_WAYPOINTS), v_start=v)
    a_next, _ = c.control(VehicleState(x, 0.0, 0.0, v, 0.0, 30 * dt))
    assert abs(a_next - a) <= c.speed_config.jerk_max * dt + 1e-9


@pytest.mark.parametrize("cls", [PurePursuit, Stanley, LQR])
def test_a_car_already_reversing_is_tracked_from_its_own_speed(cls: type) -> None:
    """``reset(reverse path, v_start=-1.2)``: the reference starts at the car's -1.2 m/s.

    ``v_start`` is signed (positive forward); on a reverse segment the profile of the
    mirrored car starts from ``+1.2``, so the signed reference is ``-1.2``, not the
    launch speed. Guards the mirroring of the start speed.
    """
    c = cls(vehicle=INSTANT)
    c.reset(line_path(20.0, gear=-1), v_start=-1.2)
    accel, _ = c.control(VehicleState(0.0, 0.0, 0.0, -1.2))
    assert c.gear == -1
    assert c.v_ref == pytest.approx(-1.2, abs=1e-6)
    assert abs(accel) < 0.2  # on its reference: no launch nor brake


@pytest.mark.parametrize("gear", [1, -1])
def test_braking_at_rest_never_pushes_the_car_against_its_gear(gear: int) -> None:
    """A car at rest under a braking cap (car-following) gets no acceleration command.

    A negative command at rest would roll the car backwards in forward gear (forwards in
    reverse). Guards the hold at rest in both gears.
    """
    c = LQR(vehicle=INSTANT)
    c.reset(line_path(20.0, gear=gear))
    c.cap_accel(-1.5)
    accel, _ = c.control(VehicleState(0.0, 0.0, 0.0, 0.0))
    assert accel == 0.0
    c.cap_accel(None)  # uncapped, it drives off in its gear within a second
    cmds = [c.control(VehicleState(0.0, 0.0, 0.0, 0.0, 0.0, 0.05 * k))[0] for k in range(1, 21)]
    assert max(gear * a for a in cmds) > 0.0


def test_a_stop_line_on_a_later_segment_is_measured_along_the_whole_path() -> None:
    """``hold_at(s)`` takes ``s`` along the whole path, also on the second gear segment.

    On the turn's reverse segment (8 m to 14 m) a line at 9 m stops a car reversing at
    0.3 m/s 1 m into the segment: reference 0, braking (a positive command in
    reverse). Guards the segment offset of the stop line.
    """
    c = PurePursuit(vehicle=INSTANT)
    c.reset(three_point_turn())
    seg = c.segments[1]
    c.start_segment(1)
    line = LineString(seg.path.samples[:, :2])
    x, y = line.interpolate(1.0).coords[0]
    yaw = float(np.interp(1.0, c.projector.s, c.projector.yaw)) - math.pi
    c.hold_at(seg.s0 + 1.0)
    accel, _ = c.control(VehicleState(x, y, yaw, -0.3, 0.0, 0.0))
    assert c.v_ref == 0.0
    assert accel > 0.5  # braking the reversing car hard
    c.hold_at(seg.s0 + 5.0)  # 4 m on: it drives on
    c.control(VehicleState(x, y, yaw, -0.3, 0.0, 0.05))
    assert c.v_ref < -0.3


def test_near_a_cusp_pure_pursuit_aims_along_the_circle_past_it() -> None:
    """On a path with gear changes the look-ahead point past a segment's end lies on the
    circle of its last curvature, not on a straight.

    The turn's first segment is the left circle of radius 6 about (0, 6) for 8 m; a car
    at 7 m, 0.1 m inside, aims 2 m on: at 9 m of that circle. Plain chord law (no
    compensation), so the point alone sets the angle. Guards the arc extension of the
    gear segments' projection.
    """
    R = VehicleParams().min_turning_radius
    c = PurePursuit(vehicle=INSTANT, compensate=False, steer_limit=INSTANT.max_steer)
    c.reset(three_point_turn())
    th = 7.0 / R
    x, y, yaw = (R - 0.1) * math.sin(th), R - (R - 0.1) * math.cos(th), th
    _, steer = c.control(VehicleState(x, y, yaw, 1.0))
    assert c.lookahead == pytest.approx(2.0)
    t9 = 9.0 / R
    px, py = car_frame(x, y, yaw, R * math.sin(t9), R * (1.0 - math.cos(t9)))
    assert steer == pytest.approx(arc_steer(INSTANT.wheelbase, px, py), abs=2e-3)


@pytest.mark.parametrize("length", [1.5, 3.0, 6.0])
def test_a_manoeuvre_segment_peaks_low_enough_to_hold_a_plateau(length: float) -> None:
    """Rate-limited car, a straight gear segment from rest: the profile's peak ``v`` leaves a
    plateau of ``swing / J`` seconds, ``v^2 / a + v swing / J <= length``.

    ``a = accel_manoeuvre`` (0.5), ``swing`` the command's range ``2 a``, ``J`` the comfort
    jerk (2): the comfort loop has time to turn speeding up into braking before the
    cusp. Solved as a quadratic here. Guards that a manoeuvre's segment profile
    rises to such a peak.
    """
    cfg = LQR().speed_config
    a, J = cfg.accel_manoeuvre, cfg.comfort_jerk
    lag = 2.0 * a / J
    v_star = (-lag + math.sqrt(lag * lag + 4.0 * length / a)) / (2.0 / a)
    path = integrate_pieces([(1, 0.0, length), (-1, 0.0, length)])
    c = LQR(vehicle=VehicleParams(max_steer_rate=0.4))
    c.reset(path)
    peak = float(np.max(c.profile.v))
    assert peak <= v_star + 1e-6
    assert peak >= 0.9 * v_star  # and it does speed up to about that


def test_stanley_on_the_return_leg_of_a_u_turn_steers_along_it() -> None:
    """A car driving exactly along a U-turn steers ``atan(L kappa)`` all the way round.

    Back on the return leg its front axle is nearer to the outgoing leg's start than
    the trace's start is to itself: the front axle's search must start at the rear
    axle's segment, not at the path's start. Guards Stanley's search hint.
    """
    R = VehicleParams().min_turning_radius
    path = integrate_pieces([(1, 0.0, 10.0), (1, 1.0 / R, math.pi * R), (1, 0.0, 10.0)])
    c = Stanley(vehicle=INSTANT, steer_limit=INSTANT.max_steer)
    c.reset(path)
    rows = path.samples
    for i in range(0, len(rows) - 25, 5):
        x, y, yaw, kappa, _ = rows[i]
        _, steer = c.control(VehicleState(x, y, yaw, 1.0, 0.0, 0.01 * i))
        if np.ptp(rows[max(i - 30, 0) : i + 30, 3]) == 0.0:  # away from the curvature steps
            assert steer == pytest.approx(math.atan(INSTANT.wheelbase * kappa), abs=2e-2)


def test_the_gear_changes_only_once_the_car_stands_still_at_the_cusp() -> None:
    """At the cusp a car still creeping (5 mm/s) is held in its gear; standing, it changes gear.

    Guards the standstill test of the gear change (``|v| <= CUSP_SPEED``, 1 mm/s).
    """
    c = LQR(vehicle=INSTANT)
    path = line_path(5.0)
    back = line_path(5.0, gear=-1).samples + np.array([5.0, 0.0, 0.0, 0.0, 0.0])
    c.reset(Path(np.vstack([path.samples, back]), NO_WAYPOINTS))
    assert [s.gear for s in c.segments] == [1, -1]
    for k in range(3):
        accel, _ = c.control(VehicleState(5.0, 0.0, 0.0, 0.005, 0.0, 0.05 * k))
        assert c.segment == 0 and c.at_stop
        assert accel < 0.0  # held: the creep is braked away
    c.control(VehicleState(5.0, 0.0, 0.0, 0.0, 0.0, 0.2))
    assert c.segment == 1 and c.gear == -1


def test_in_reverse_the_wanted_angle_and_the_window_are_the_real_cars() -> None:
    """Reversing with a slow actuator: :attr:`steer_wanted` is the law's angle and
    :attr:`steer_window` the reachable ``(low, high)``, both in the real car's terms.

    The law's angle is the arc through the point 2 m behind the car (as with an instant
    actuator); the window is ``steer +- rate dt`` and holds the command. Guards the
    mirroring back of the diagnostics a residual policy adds to.
    """
    rate, dt = 0.4, 0.05
    c = PurePursuit(vehicle=VehicleParams(max_steer_rate=rate), steer_limit=INSTANT.max_steer)
    c.reset(line_path(gear=-1), v_start=-1.0)
    x, y, steer0 = -5.0, 0.3, 0.1
    c.control(VehicleState(x, y, 0.0, -1.0, steer0, 0.0))
    _, steer = c.control(VehicleState(x, y, 0.0, -1.0, steer0, dt))
    px, py = car_frame(x, y, 0.0, x - 2.0, 0.0)
    want = arc_steer(INSTANT.wheelbase, px, py)
    assert abs(want - steer0) > rate * dt  # the actuator cannot reach it in a step
    assert c.steer_wanted == pytest.approx(want, abs=1e-9)
    assert c.steer_window == pytest.approx((steer0 - rate * dt, steer0 + rate * dt))
    assert steer == pytest.approx(steer0 + math.copysign(rate * dt, want - steer0))


def test_a_repeated_row_changes_no_projection() -> None:
    """A path with a row given twice projects as the same path with it once.

    Guards the dropping of repeated samples (a zero-length segment has no direction).
    """
    rows = clothoid_path(0.05, 0.0, length=6.0).samples
    twice = Path(np.vstack([rows[:20], rows[19:]]), NO_WAYPOINTS)
    once, again = PathProjector(Path(rows, NO_WAYPOINTS)), PathProjector(twice)
    assert again.length == pytest.approx(once.length)
    for px, py in [(1.9, 0.3), (2.0, -0.2), (4.5, 0.9)]:
        a, b = once.project(px, py), again.project(px, py)
        assert np.isfinite([b.s, b.x, b.y, b.yaw, b.cte]).all()
        assert (b.s, b.x, b.y, b.yaw, b.kappa, b.cte) == pytest.approx(
            (a.s, a.x, a.y, a.yaw, a.kappa, a.cte), abs=1e-12
        )


def test_headings_across_plus_minus_pi_interpolate_through_pi() -> None:
    """A path heading west with its yaw column wrapped (+3.13, -3.13) projects with heading ~pi.

    Reference: the circle's own tangent at the foot. Guards the unwrapping of the
    path's headings before they are interpolated.
    """
    R = 6.0
    th = np.linspace(math.pi - 0.3, math.pi + 0.3, 61)  # heading through pi, turning left
    x, y = R * np.sin(th), -R * np.cos(th)
    yaw = (th + math.pi) % (2 * math.pi) - math.pi  # wrapped: jumps from +pi to -pi
    p = PathProjector(Path(np.column_stack([x, y, yaw, np.full_like(th, 1 / R)]), NO_WAYPOINTS))
    for t in (math.pi - 0.105, math.pi - 0.005, math.pi + 0.2):  # the middle one: on the jump
        pr = p.project(0.9 * R * math.sin(t), -0.9 * R * math.cos(t))
        assert math.cos(pr.yaw - t) == pytest.approx(1.0, abs=1e-4)
        assert pr.cte == pytest.approx(0.1 * R, abs=1e-3)  # inside the left turn


# --- the speed loop ------------------------------------------------------------------


def straight_profile(cfg: SpeedConfig, length: float = 30.0, v_start: float = 0.0) -> SpeedProfile:
    """The speed profile of a straight ``length`` m path (0.1 m rows) from ``v_start``."""
    s = np.linspace(0.0, length, int(round(length * 10)) + 1)
    return SpeedProfile(s, np.zeros_like(s), cfg, v_start=v_start)


@pytest.mark.parametrize(("d0", "v0"), [(1.0, 1.2), (1.8, 1.5)])
def test_the_stop_at_the_end_is_the_constant_jerk_stop(d0: float, v0: float) -> None:
    """From ``d0`` metres before the end at ``v0`` the loop brakes ``a = a0 (1 - t / T)``:
    ``a0 = -2 v0^2 / (3 d0)``, ``T = 3 d0 / v0``, and stops at the end (``v = v0 (1 - t/T)^2``).

    The closed form of the stop whose jerk is constant and whose deceleration fades to 0
    at standstill; point mass, falls of the command unlimited so the stop starts at
    once. Guards the taper law, where it starts, that it latches, and its reference.
    """
    cfg = SpeedConfig(jerk_brake_max=None)
    ctrl = SpeedController(cfg)
    length = 30.0
    ctrl.reset(straight_profile(cfg, length))
    a0, T = -2.0 * v0 * v0 / (3.0 * d0), 3.0 * d0 / v0
    assert a0 <= -cfg.taper_start * cfg.decel  # the taper starts here
    dt, pos, v, t = 0.01, length - d0, v0, 0.0
    while v > 0.0 and t < 2.0 * T:
        a = ctrl.control(pos, v, t)
        if t < 0.8 * T:
            assert a == pytest.approx(a0 * (1.0 - t / T), abs=0.03)
            assert ctrl.v_ref == 0.0
        v1 = max(0.0, v + a * dt)
        pos, v, t = pos + 0.5 * (v + v1) * dt, v1, t + dt
    # v(t) = v0 (1 - t / T)^2: held at once below taper_stop_speed, then at rest.
    assert t == pytest.approx(T * (1.0 - math.sqrt(cfg.taper_stop_speed / v0)), abs=0.05)
    assert pos == pytest.approx(length, abs=0.02)


def test_a_following_cap_above_the_command_changes_nothing() -> None:
    """A car-following cap above what the loop commands leaves the command alone.

    A car cruising on its reference with a cap of 1.5 m/s^2 keeps commanding about 0,
    and is slowed at once by a cap of -1. Guards the direction of the cap's test.
    """
    cfg = SpeedConfig()
    ctrl = SpeedController(cfg)
    ctrl.reset(straight_profile(cfg, 60.0, v_start=3.0))
    ctrl.accel_cap = 1.5
    for k in range(10):
        a = ctrl.control(10.0 + 0.15 * k, 3.0, 0.05 * k)
        assert abs(a) < 0.05
    ctrl.accel_cap = -1.0
    assert ctrl.control(11.5, 3.0, 0.5) == pytest.approx(-1.0)


def test_comfort_mode_speeds_up_at_most_comfort_a_max() -> None:
    """Comfort mode (slow actuator): a car far below its reference ramps up to
    ``comfort_a_max`` (1.5 m/s^2), not ``a_max`` (2), rising at most ``comfort_jerk``.

    Guards the comfort mode's acceleration and jerk bounds.
    """
    cfg = SpeedConfig(v_max=10.0)
    ctrl = SpeedController(cfg, comfort=True)
    ctrl.reset(straight_profile(cfg, 200.0, v_start=10.0))
    dt, last, cmds = 0.05, 0.0, []
    for k in range(60):
        a = ctrl.control(5.0, 1.0, k * dt)
        assert a - last <= cfg.comfort_jerk * dt + 1e-9
        last = a
        cmds.append(a)
    assert max(cmds) == pytest.approx(cfg.comfort_a_max)


@pytest.mark.parametrize("comfort", [False, True])
def test_the_stop_at_the_end_starts_within_the_jerk_bound(comfort: bool) -> None:
    """From cruising into the taper the braking sets in at most ``jerk_brake_max`` m/s^3
    (``comfort_jerk`` in comfort mode), then the car stops at the end.

    Guards the jerk limit on the taper's onset.
    """
    cfg = SpeedConfig()
    fall = cfg.comfort_jerk if comfort else cfg.jerk_brake_max
    ctrl = SpeedController(cfg, comfort=comfort)
    length = 30.0
    ctrl.reset(straight_profile(cfg, length))
    dt, pos, v, t, last = 0.05, length - 1.0, 1.2, 0.0, 0.0
    while v > 0.0 and t < 10.0:
        a = ctrl.control(pos, v, t)
        assert a - last >= -fall * dt - 1e-9
        last = a
        v1 = max(0.0, v + a * dt)
        pos, v, t = pos + 0.5 * (v + v1) * dt, v1, t + dt
    assert ctrl.arrived and pos == pytest.approx(length, abs=0.1)


def test_once_arrived_the_car_is_held_even_when_pushed() -> None:
    """After the stop at the end the car stays arrived and held: a push is braked away.

    "From then on it is held at rest": a car nudged to 0.3 m/s at the goal gets the
    hold (``-v / dt``, within ``a_min``), not a new approach. Guards the arrival latch.
    """
    cfg = SpeedConfig()
    ctrl = SpeedController(cfg)
    ctrl.reset(straight_profile(cfg, 10.0))
    ctrl.control(9.99, 0.0, 0.0)
    assert ctrl.arrived
    a = ctrl.control(9.99, 0.3, 0.05)
    assert ctrl.arrived and ctrl.v_ref == 0.0
    assert a == pytest.approx(max(-0.3 / 0.05, cfg.a_min))


@pytest.mark.parametrize("cls", [PurePursuit, Stanley, LQR])
def test_a_moving_car_does_not_wait_for_its_wheels(cls: type) -> None:
    """Slow actuator: only a car *at rest* waits for its wheels to turn first.

    A car taken over at 2 m/s with its wheels 0.2 rad off the law's angle keeps its
    reference speed (a moving car cannot stand still to turn them). Guards the
    at-rest test of the wheels-first start.
    """
    c = cls(vehicle=VehicleParams(max_steer_rate=0.4))
    c.reset(line_path(), v_start=2.0)
    c.control(VehicleState(5.0, 0.4, 0.0, 2.0, 0.2, 0.0))
    assert abs(c.steer_wanted - 0.2) > c.speed_config.start_steer_tol
    assert c.v_ref >= 1.8  # its profile from its own speed, not the wait's 0


# --- feed-forward with a slow actuator -----------------------------------------------


@pytest.mark.parametrize("cls", [LQR, Stanley])
def test_a_car_on_a_clothoid_steers_the_curvature_one_step_ahead(cls: type) -> None:
    """Slow actuator, car exactly on a clothoid (``kappa = 0.02 + 0.01 s``) at 5 m/s, 0.1 s
    steps: the law's angle is ``atan(L kappa)`` read ``v dt`` = 0.5 m of driving ahead.

    For Stanley the front axle runs ``sqrt(1 + (L kappa)^2)`` times as far as the rear
    axle, so its 0.5 m are ``0.5 / sqrt(1 + (L kappa)^2)`` m of the rear axle's path.
    Guards the feed-forward's preview in LQR and Stanley.
    """
    k0, k1, v, dt = 0.02, 0.01, 5.0, 0.1
    path = clothoid_path(k0, k1)
    car = VehicleParams(max_steer_rate=0.4)
    L = car.wheelbase
    c = cls(vehicle=car, steer_limit=car.max_steer)
    c.reset(path, v_start=v)
    rows = path.samples
    i = 60  # s = 6 m
    x, y, yaw, kappa, _ = rows[i]
    s = float(np.sum(np.hypot(*np.diff(rows[: i + 1, :2], axis=0).T)))
    c.control(VehicleState(x, y, yaw, v, 0.0, 0.0))
    c.control(VehicleState(x, y, yaw, v, 0.0, dt))
    ahead = v * dt if cls is LQR else v * dt / math.sqrt(1.0 + (L * kappa) ** 2)
    want = math.atan(L * (k0 + k1 * (s + ahead)))
    assert abs(want - math.atan(L * kappa)) > 0.01  # the preview matters here
    assert c.steer_wanted == pytest.approx(want, abs=3e-3)


def clothoid_manoeuvre() -> Path:
    """A forward clothoid (``kappa = 0.02 + 0.01 s``, 12 m), then 5 m straight back."""
    fwd = clothoid_path(0.02, 0.01).samples
    end = fwd[-1]
    back = np.arange(0.0, 5.0 + 1e-9, 0.1)
    c, s_ = math.cos(end[2]), math.sin(end[2])
    rev = np.column_stack([
        end[0] - back * c, end[1] - back * s_, np.full_like(back, end[2]),
        np.zeros_like(back), -np.ones_like(back),
    ])
    return Path(np.vstack([fwd, rev]), NO_WAYPOINTS)


@pytest.mark.parametrize("compensate", [True, False])
def test_pure_pursuit_compensates_corner_cutting_on_manoeuvres_only_when_asked(
    compensate: bool,
) -> None:
    """On a path with gear changes: ``kappa = 2 py / l^2 + kappa_path(s) - (the same chord law
    from the foot's pose)``; with ``compensate=False``, the chord law alone.

    Reference: the foot and the look-ahead point from shapely, the curvature and heading
    interpolated along the rows. Guards the compensation's terms and its switch.
    """
    path = clothoid_manoeuvre()
    c = PurePursuit(vehicle=INSTANT, compensate=compensate, steer_limit=INSTANT.max_steer)
    c.reset(path)
    rows = c.segments[0].path.samples
    line = LineString(rows[:, :2])
    s_rows = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(rows[:, :2], axis=0).T))])
    bx, by = line.interpolate(5.0).coords[0]
    yaw0 = float(np.interp(5.0, s_rows, rows[:, 2]))
    x, y, yaw = bx - 0.2 * math.sin(yaw0), by + 0.2 * math.cos(yaw0), yaw0 + 0.05
    _, steer = c.control(VehicleState(x, y, yaw, 1.0))
    s_foot = line.project(Point(x, y))
    fx, fy = line.interpolate(s_foot).coords[0]
    tx, ty = line.interpolate(s_foot + 2.0).coords[0]
    kappa = 2.0 * car_frame(x, y, yaw, tx, ty)[1] / math.dist((x, y), (tx, ty)) ** 2
    if compensate:
        fyaw = float(np.interp(s_foot, s_rows, rows[:, 2]))
        chord0 = 2.0 * car_frame(fx, fy, fyaw, tx, ty)[1] / math.dist((fx, fy), (tx, ty)) ** 2
        kappa += float(np.interp(s_foot, s_rows, rows[:, 3])) - chord0
    assert steer == pytest.approx(math.atan(INSTANT.wheelbase * kappa), abs=1e-6)


def test_pure_pursuit_on_a_forward_only_clothoid_is_the_plain_chord_law() -> None:
    """A forward-only path is tracked by the plain chord law, whatever ``compensate`` says.

    Guards that the compensation is for paths with gear changes only.
    """
    path = clothoid_path(0.02, 0.01)
    rows = path.samples
    line = LineString(rows[:, :2])
    c = PurePursuit(vehicle=INSTANT, compensate=True, steer_limit=INSTANT.max_steer)
    c.reset(path)
    bx, by = line.interpolate(5.0).coords[0]
    x, y, yaw = bx, by + 0.2, 0.2
    _, steer = c.control(VehicleState(x, y, yaw, 1.0))
    tx, ty = line.interpolate(line.project(Point(x, y)) + 2.0).coords[0]
    px, py = car_frame(x, y, yaw, tx, ty)
    assert steer == pytest.approx(arc_steer(INSTANT.wheelbase, px, py), abs=1e-6)


def test_lqr_takes_a_zero_heading_weight() -> None:
    """``q_psi = 0`` is allowed (">= 0"): ``K = [sqrt(q_e / r), sqrt(2 sqrt(q_e / r))]``.

    Guards the bound of the heading weight's check.
    """
    assert design_gain(1.0, 0.0, 4.0) == pytest.approx([0.5, 1.0], rel=1e-9)


def test_an_unknown_controller_option_is_named() -> None:
    """``make_controller('lqr', gain=3)`` names the option and the options there are.

    Guards the factory's own check of option names.
    """
    named = r"controller\.gain: unknown option of LQR; choose from approach_angle, bandwidth, "
    with pytest.raises(InputError, match=named):
        make_controller("lqr", gain=3)


def _loop(comfort: bool = False, **cfg_options: object) -> tuple[SpeedConfig, SpeedController]:
    """A speed loop on a 30 m straight profile from 3 m/s (``v = min(3, sqrt(2 (30 - s)))``)."""
    cfg = SpeedConfig(**cfg_options)  # type: ignore[arg-type]
    ctrl = SpeedController(cfg, comfort=comfort)
    ctrl.reset(straight_profile(cfg, 30.0, v_start=3.0))
    return cfg, ctrl


@pytest.mark.parametrize("past", [0.02, 0.045, 0.3])
@pytest.mark.parametrize("speed", [0.3, -0.3])
def test_past_the_end_the_car_brakes_to_stop_within_what_is_left_of_the_window(
    past: float, speed: float
) -> None:
    """``past`` metres beyond the end the brake is ``-v |v| / (2 max(0.05 - past, 0.01))``.

    The constant deceleration that stops within what is left of the 5 cm window (at
    least 1 cm), against the motion in either direction. Guards the window, its
    shrinking, its floor and the brake's sign for a car rolling back.
    """
    cfg, ctrl = _loop()
    a = ctrl.control(30.0 + past, speed, 0.0)
    window = max(0.05 - past, 0.01)
    want = min(max(-speed * abs(speed) / (2.0 * window), cfg.a_min), cfg.a_max)
    assert a == pytest.approx(want)
    assert ctrl.v_ref == 0.0


@pytest.mark.parametrize("comfort", [False, True])
def test_a_stop_line_caps_the_reference_by_the_braking_curve(comfort: bool) -> None:
    """A stop line ``d`` ahead caps the reference at ``sqrt(2 decel d)``; comfort mode reads
    it ``|v| tau`` ahead (``tau = 0.5 max(accel, decel) / comfort_jerk``, 0.25 s).

    Guards the stop line's cap and its preview in comfort mode.
    """
    cfg, ctrl = _loop(comfort=comfort)
    s, v, d = 5.0, 1.0, 3.0
    ctrl.stop_at = s + d
    ctrl.control(s, v, 0.0)
    tau = 0.5 * max(cfg.accel, cfg.decel) / cfg.comfort_jerk if comfort else 0.0
    assert ctrl.v_ref == pytest.approx(math.sqrt(2.0 * cfg.decel * (d - v * tau)))


def test_on_the_braking_curve_of_a_stop_line_the_loop_brakes_v2_over_2d() -> None:
    """A car on the braking curve of a stop line ``d`` ahead is commanded ``-v^2 / (2 d)``.

    Falls of the command unlimited, first call (no integral): the command is the
    feed-forward alone. Guards the stop line's feed-forward.
    """
    cfg, ctrl = _loop(jerk_brake_max=None)
    d = 3.0
    v = math.sqrt(2.0 * cfg.decel * d)
    ctrl.stop_at = 5.0 + d
    a = ctrl.control(5.0, v, 0.0)
    assert ctrl.v_ref == pytest.approx(v)
    assert a == pytest.approx(-v * v / (2.0 * d))


@pytest.mark.parametrize(("s", "v"), [(28.0, 1.5), (29.0, 1.2), (29.0, 1.8), (26.0, 3.2)])
def test_the_feed_forward_is_the_profiles_braking_at_the_cars_speed(s: float, v: float) -> None:
    """First command: ``a_ref + kp (v_ref - v)``, with the profile's ``a_ref = -decel`` on its
    braking ramp taken at the car's speed (``a_ref v / v_ref``) when the car is slower, and
    ``v_ref = min(3, sqrt(2 decel (30 - s)))``.

    ``stop_taper=False``: within the last 2 m ``a_ref`` is at most the
    ``-v^2 / (2 remaining)`` that stops exactly at the end. (Cases that brake: a first
    command cannot rise, ``jerk_max`` from 0 in no time.) Guards the feed-forward's terms.
    """
    cfg, ctrl = _loop(stop_taper=False, jerk_brake_max=None, kp=0.5, ki=0.0)
    a = ctrl.control(s, v, 0.0)
    v_ref = min(3.0, math.sqrt(2.0 * cfg.decel * (30.0 - s)))
    assert ctrl.v_ref == pytest.approx(v_ref, abs=1e-9)
    a_ref = -cfg.decel if 30.0 - s < 4.5 else 0.0
    if v < v_ref:
        a_ref *= v / v_ref
    if 30.0 - s < 2.0:
        a_ref = min(a_ref, -v * v / (2.0 * (30.0 - s)))
    want = a_ref + cfg.kp * (v_ref - v)
    assert want < 0.0
    assert a == pytest.approx(max(want, cfg.a_min))


def test_the_integral_grows_by_the_error_times_the_step_and_not_while_limited() -> None:
    """The PI integral adds ``err dt`` per step, and nothing while the command is limited.

    A car held at 0 m/s under a 3 m/s reference saturates the command for 2 s; the car then
    on its reference gets ``ki * integral`` = 0 (no wind-up). Then at 0.2 m/s below it the
    command rises by ``ki err dt`` a step. Guards the integration and the anti-windup.
    """
    cfg, ctrl = _loop(jerk_brake_max=None)
    dt = 0.05
    for k in range(40):
        assert ctrl.control(5.0, 0.0, k * dt) <= cfg.a_max
    a = ctrl.control(5.0, 3.0, 40 * dt)
    assert a == pytest.approx(0.0, abs=1e-9)
    cmds = [ctrl.control(5.0, 2.8, (41 + k) * dt) for k in range(10)]
    steps = np.diff(cmds[-5:])
    assert steps == pytest.approx(np.full(4, cfg.ki * 0.2 * dt), abs=1e-9)


def test_the_comfort_stop_at_a_line_fades_to_standstill_before_it() -> None:
    """Comfort mode: a car cruising at 2 m/s toward a stop line stops just short of it, its
    deceleration fading to (nearly) 0 at standstill, with no step of the command over
    ``comfort_jerk dt``.

    The constant-jerk stop ``a = -2 v^2 / (3 d)`` (a constant-deceleration stop would end at
    full braking). Guards the line stop's law.
    """
    cfg, ctrl = _loop(comfort=True)
    ctrl.reset(straight_profile(cfg, 60.0, v_start=2.0))
    line = 20.0
    ctrl.stop_at = line
    dt, pos, v, last, t = 0.05, 2.0, 2.0, 0.0, 0.0
    moving = []
    for k in range(400):
        a = ctrl.control(pos, v, k * dt)
        if k > 0:
            assert abs(a - last) <= cfg.comfort_jerk * dt + 1e-9 or v <= cfg.taper_stop_speed
        last = a
        if v > 0.0:
            moving.append((v, a))
        v1 = max(0.0, v + a * dt)
        pos, v, t = pos + 0.5 * (v + v1) * dt, v1, t + dt
        if v == 0.0 and k > 10:
            break
    assert v == 0.0 and line - 0.1 < pos <= line
    slowest = [a for (speed, a) in moving if speed < 0.1]
    assert slowest and max(abs(a) for a in slowest) < 0.35


def test_comfort_mode_leaves_room_to_ramp_down_before_the_top_speed() -> None:
    """Comfort mode, speeding up from 1 m/s to a 3 m/s plateau: every command ``a`` can ramp
    down to 0 at ``comfort_jerk`` before the car passes 3 m/s (``a^2 / 2J <= 3 - v``), and
    the car does not overshoot.

    Guards the comfort loop's cap at the top of a rise.
    """
    cfg, ctrl = _loop(comfort=True)
    ctrl.reset(straight_profile(cfg, 200.0, v_start=3.0))
    dt, pos, v = 0.05, 5.0, 1.0
    top = 0.0
    for k in range(200):
        a = ctrl.control(pos, v, k * dt)
        if a > 0.0:
            assert a * a / (2.0 * cfg.comfort_jerk) <= 3.0 - v + 1e-9
        v1 = v + a * dt
        pos, v = pos + 0.5 * (v + v1) * dt, v1
        top = max(top, v)
    assert top <= 3.0 + 0.01


def test_a_segment_index_past_the_last_is_refused() -> None:
    """``start_segment(len(segments))`` is an :class:`InputError`, not an IndexError.

    Guards the bound of the segment index check.
    """
    c = PurePursuit(vehicle=INSTANT)
    c.reset(three_point_turn())
    with pytest.raises(InputError, match="segment"):
        c.start_segment(len(c.segments))
    c.start_segment(len(c.segments) - 1)
    assert c.gear == 1 and c.next_cusp_s is None


@pytest.mark.parametrize("cls", [PurePursuit, LQR])
def test_an_approach_angle_of_a_right_angle_is_refused(cls: type) -> None:
    """``approach_angle`` lies in the open ``(0, pi/2)``: a right angle never heads back.

    Guards the open upper bound of the approach angle.
    """
    with pytest.raises(InputError, match="approach_angle"):
        cls(approach_angle=0.5 * math.pi)
