"""Controllers across cusps on the bicycle model: reverse straight, reverse arc, three-point turn.

The plant here is the ego's own longitudinal rule (the speed changes linearly and
stops at zero within a step rather than reversing) with the exact rear-axle arcs,
and with the actuator either instant or slewing at 0.4 rad/s (turning linearly
within the step, as the ego integrates it). The highway-env runs are in
``test_reverse_highway.py``.
"""

from __future__ import annotations

import numpy as np
import pytest
from gear_paths import integrate_pieces, track_on_bicycle

from rrtdrive.controllers import (
    CONTROLLERS,
    SpeedConfig,
    VehicleState,
    gear_segments,
    make_controller,
    mirror_path,
)
from rrtdrive.types import InputError, Path, VehicleParams

NAMES = sorted(CONTROLLERS)
RATES = [None, 0.4]
L = VehicleParams().wheelbase
DT = 0.05  # the closed loop's 20 Hz


def drive(name: str, path: Path, rate: float | None, x0=None, max_time: float = 120.0):
    """Track ``path`` from rest; rows ``t, x, y, yaw, v, steer, segment, cte, heading_err``."""
    c = make_controller(name, vehicle=VehicleParams(max_steer_rate=rate))
    return c, track_on_bicycle(c, path, rate, x0, max_time)


R = VehicleParams().min_turning_radius
PATHS = {
    "reverse-straight": integrate_pieces([(-1, 0.0, 15.0)]),
    "reverse-arc": integrate_pieces([(-1, 1.0 / R, 9.0)]),
    # Forward left, reverse right, forward left: at the curvature limit throughout.
    "three-point-turn": integrate_pieces(
        [(1, 1.0 / R, 8.0), (-1, -1.0 / R, 6.0), (1, 1.0 / R, 8.0)]
    ),
}
#: Bounds measured with this file's plant (``drive``) and stated in docs/closed_loop.md:
#: largest |CTE| (m, against the segment driven), final position error (m).
BOUNDS = {
    (None, "reverse-straight"): (0.01, 0.05),
    (None, "reverse-arc"): (0.01, 0.05),
    (None, "three-point-turn"): (0.05, 0.05),
    (0.4, "reverse-straight"): (0.01, 0.06),
    (0.4, "reverse-arc"): (0.01, 0.06),
    (0.4, "three-point-turn"): (0.20, 0.20),
}


def test_mirror_is_the_forward_problem():
    back = PATHS["reverse-arc"]
    m = mirror_path(back)
    assert m.is_forward_only
    assert np.allclose(m.samples[:, :2], back.samples[:, :2])
    # The mirrored yaw is the direction of travel; the mirrored curvature its turning.
    d = np.diff(m.samples[:, :2], axis=0)
    travel = np.arctan2(d[:, 1], d[:, 0])
    assert np.allclose(np.cos(travel - m.samples[:-1, 2]), 1.0, atol=1e-3)
    dyaw = np.diff(np.unwrap(m.samples[:, 2]))
    assert np.allclose(dyaw / np.hypot(*d.T), m.samples[:-1, 3], atol=1e-6)
    segs = gear_segments(PATHS["three-point-turn"])
    assert [s.gear for s in segs] == [1, -1, 1]
    assert np.allclose([s.s0 for s in segs], [0.0, 8.0, 14.0], atol=1e-3)  # chords of arcs


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize(
    ("y", "yaw", "expect"),
    [
        (0.5, 0.0, -1),  # left of the nose line: steer right, as forward
        (-0.5, 0.0, +1),
        (0.0, 0.2, +1),  # nose left of the path: steer left (reversing turns it back)
        (0.0, -0.2, -1),
    ],
)
def test_sign_conventions_in_reverse(name, y, yaw, expect):
    c = make_controller(name, vehicle=VehicleParams(max_steer_rate=None))
    c.reset(Path(PATHS["reverse-straight"].samples, np.zeros((0, 2))))
    _, steer = c.control(VehicleState(-3.0, y, yaw, -1.0))
    assert np.sign(steer) == expect
    assert c.gear == -1


@pytest.mark.parametrize("rate", RATES)
@pytest.mark.parametrize("name", NAMES)
def test_converges_in_reverse_from_an_offset(name, rate):
    c, rows = drive(name, PATHS["reverse-straight"], rate, x0=(0.0, 0.4, 0.05))
    assert c.arrived
    assert abs(rows[-1, 7]) < 0.05 and abs(rows[-1, 8]) < 0.03
    assert np.all(rows[:, 4] <= 0.0)  # never forward on a reverse-only path


@pytest.mark.parametrize("rate", RATES)
@pytest.mark.parametrize("path_name", list(PATHS))
@pytest.mark.parametrize("name", NAMES)
def test_tracks_stops_at_every_cusp_and_arrives(name, path_name, rate):
    path = PATHS[path_name]
    c, rows = drive(name, path, rate)
    assert c.arrived
    cte_bound, end_bound = BOUNDS[(rate, path_name)]
    assert np.max(np.abs(rows[:, 7])) <= cte_bound
    assert np.hypot(*(rows[-1, 1:3] - path.samples[-1, :2])) <= end_bound
    # Each segment is driven in its own gear; the gear changes only at rest.
    seg = rows[:, 6].astype(int)
    gears = np.array([s.gear for s in c.segments])
    moving = rows[:, 4] != 0.0
    assert np.all(np.sign(rows[moving, 4]) == gears[seg[moving]])
    for i in np.flatnonzero(np.diff(seg)):
        assert abs(rows[i + 1, 4]) < 0.05  # |v| at the cusp
        cusp = path.samples[path.cusps[seg[i]], :2]
        assert np.hypot(*(rows[i + 1, 1:3] - cusp)) < max(end_bound, 0.06)
    # The reverse speed cap (the PI loop overshoots the profile by a few percent).
    cap = SpeedConfig().v_max_reverse
    assert np.min(rows[:, 4]) >= -1.1 * cap


@pytest.mark.parametrize("name", NAMES)
def test_wheels_turn_at_rest_at_a_cusp_with_a_slow_actuator(name):
    c, rows = drive(name, PATHS["three-point-turn"], 0.4)
    seg = rows[:, 6].astype(int)
    first = np.flatnonzero(seg == 1)[0]
    start = np.flatnonzero((seg == 1) & (rows[:, 4] != 0.0))[0]
    # From nearly full left to nearly full right at rest before reversing.
    assert rows[first, 5] > 0.3 and rows[start, 5] < -0.3
    assert start - first >= int(0.6 / 0.4 / DT)


def test_speed_config_validates_the_reverse_fields():
    with pytest.raises(InputError, match="speed.v_max_reverse"):
        SpeedConfig(v_max_reverse=0.0)
    with pytest.raises(InputError, match="speed.accel_manoeuvre"):
        SpeedConfig(accel_manoeuvre=-1.0)


@pytest.mark.parametrize("name", NAMES)
def test_a_reverse_stub_of_two_rows_is_driven(name):
    """A 0.12 m first segment given by its two end rows alone is driven, not waited at.

    Hybrid A*'s Reeds-Shepp words can start so (stock parking-v0 --reverse seeds 77 and
    91): a profile on the two rows stops at both and is zero throughout, and the car
    stood still until the episode's time ran out.
    """
    stub = np.array([[0.0, 0.0, 0.0, 0.0, -1.0], [-0.12, 0.0, 0.0, 0.0, -1.0]])
    ahead = np.array([[-0.12 + 0.1 * k, 0.0, 0.0, 0.0, 1.0] for k in range(101)])
    path = Path(np.vstack([stub, ahead]), np.zeros((0, 2)))
    c, rows = drive(name, path, 0.4, max_time=60.0)
    assert c.arrived and rows[-1, 6] == 1  # both segments driven
    assert np.hypot(*(rows[-1, 1:3] - path.samples[-1, :2])) < 0.1
    assert rows[-1, 0] < 30.0


@pytest.mark.parametrize("name", NAMES)
def test_wheels_turn_first_when_the_speed_reads_a_float32_zero(name):
    """At rest is |v| <= CUSP_SPEED: a stock env's standing car reads -2.4e-8 m/s.

    Before, only 0.0 counted as rest, so at a cusp in parking-v0 the wheels did not
    turn first (seeds 23, 38, 61, 66 of parking-v0 --reverse set off with the wrong
    lock and left the path).
    """
    path = integrate_pieces([(1, -1.0 / R, 6.0)])  # full right lock from the start
    c = make_controller(name, vehicle=VehicleParams(max_steer_rate=0.4))
    c.reset(path)
    x, y, yaw = path.samples[0, :3]
    accel, steer = c.control(VehicleState(x, y, yaw, -2.4e-8, 0.3, 0.0))
    accel2, steer2 = c.control(VehicleState(x, y, yaw, -2.4e-8, steer, DT))
    assert accel == 0.0 and accel2 == 0.0  # waits while the wheels turn
    assert steer < 0.0 and steer2 <= steer  # towards the right lock
