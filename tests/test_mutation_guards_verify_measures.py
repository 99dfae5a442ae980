"""Guards found by mutation testing of the verifier's discrete measures (rrtdrive.verify_measures).

Rows are built in closed form or by fine integration of a curvature profile, as in
test_verify_turns; each test fails under a real-looking bug the other tests let through.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from rrtdrive.maps import Map
from rrtdrive.types import Path, Pose
from rrtdrive.verify import verify_path

KAPPA_MAX = 1 / 6


def _verify(rows: np.ndarray, **kwargs):
    m = Map("open", (0.0, 0.0, 60.0, 60.0), (), Pose(*rows[0, :3]), Pose(*rows[-1, :3]))
    return verify_path(m, Path(rows, np.zeros((0, 2))), **kwargs)


def _integrate(s: np.ndarray, phi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Positions from (20, 20) along headings ``phi`` at arc lengths ``s`` (midpoint rule)."""
    mid = 0.5 * (phi[1:] + phi[:-1])
    ds = np.diff(s)
    x = 20.0 + np.concatenate([[0.0], np.cumsum(np.cos(mid) * ds)])
    y = 20.0 + np.concatenate([[0.0], np.cumsum(np.sin(mid) * ds)])
    return x, y


def _straight(n: int = 41, step: float = 0.25) -> np.ndarray:
    x = 10.0 + step * np.arange(n)
    return np.column_stack([x, np.full_like(x, 20.0), 0 * x, 0 * x, 1 + 0 * x])


def test_positions_turning_tighter_than_the_yaw_fail_the_curvature():
    # Positions: 3 m straight, 0.8 m of arc at kappa 0.25 (over kappa_max), 3 m straight.
    # The yaw turns the same 0.2 rad at kappa_max over 1.2 m centred on the arc: within
    # 1.8 deg of the travel, and a yaw turn the car can make; only the positions' own
    # curvature (points 0.5 m apart) shows the arc.
    radius, arc, lead, step = 4.0, 0.8, 3.0, 0.05
    turn = arc / radius
    s = np.arange(0.0, 2 * lead + arc + 1e-9, step)
    x, y = _integrate(s, np.clip((s - lead) / radius, 0.0, turn))
    window = turn / KAPPA_MAX
    begin = lead + arc / 2 - window / 2
    yaw = np.clip((s - begin) * KAPPA_MAX, 0.0, turn)
    kappa = np.where((s > begin) & (s < begin + window), KAPPA_MAX, 0.0)
    # At the 3 deg travel tolerance of before session 46 (1 deg now fails travel_ok too):
    # the positions' curvature alone must catch it.
    check = _verify(np.column_stack([x, y, yaw, kappa, np.ones_like(s)]), travel_tol_deg=3.0)
    assert check.failed == ("curvature_ok",), check.failed
    assert check.max_discrete_curvature > 0.2


def test_a_short_gear_segment_on_a_tight_arc_fails_the_curvature():
    # The whole path: 0.5 m on an arc of radius 3 (kappa 1/3), the yaw turning at kappa_max
    # (its mean 2.4 deg from the travel at worst). Under a metre: measured over points a
    # quarter of its length apart, not read as 0.
    s = np.arange(0.0, 0.5 + 1e-9, 0.05)
    x, y = _integrate(s, s / 3.0)
    yaw = 0.25 * KAPPA_MAX + KAPPA_MAX * s
    check = _verify(np.column_stack([x, y, yaw, np.full_like(s, KAPPA_MAX), np.ones_like(s)]),
                    travel_tol_deg=3.0)  # as above
    assert check.failed == ("curvature_ok",), check.failed
    assert check.max_discrete_curvature == pytest.approx(1 / 3, rel=0.02)


def test_a_small_turn_on_the_spot_inside_a_gear_segment_fails():
    # The car stops halfway, turns 3 deg standing (a row that repeats the position), and
    # drives on along the new yaw: a turn with no chord is infinite curvature.
    a = _straight(21)
    b = _straight(21)
    turn = math.radians(3.0)
    b[:, 0] -= b[0, 0]
    b[:, :2] = a[-1, :2] + np.column_stack([b[:, 0] * math.cos(turn), b[:, 0] * math.sin(turn)])
    b[:, 2] = turn
    check = _verify(np.vstack([a, b]))
    assert check.cusps == 0 and not check.curvature_ok
    assert check.max_discrete_curvature == math.inf


def test_a_millimetre_hop_sideways_fails_the_travel():
    # One extra row 1 mm to the left of a row (the yaw along x): the car moved sideways.
    rows = _straight()
    hop = rows[20].copy()
    hop[1] += 1e-3
    rows = np.vstack([rows[:21], hop, rows[21:]])
    rows[22:, 1] += 1e-3
    check = _verify(rows)
    assert not check.travel_ok and check.travel_heading_err_deg == pytest.approx(90.0)


def test_a_wrong_kappa_in_the_second_row_of_a_segment_is_caught():
    # A straight drive: the column must be 0 on every row but the first and last (stops).
    rows = _straight()
    rows[1, 3] = 0.1
    check = _verify(rows)
    assert check.failed == ("kappa_ok",) and check.worst_kappa_row == 1
    assert check.kappa_column_err == pytest.approx(0.1, abs=1e-4)  # less the rounding slack


@pytest.mark.parametrize("gear", [1, -1])
def test_the_peak_of_a_steering_ramp_passes_the_kappa_column(gear):
    # kappa rises at 0.15 /m^2 from 0 to 0.15 and falls back (a triangle, its peak on a
    # row): the peak row's kappa lies 0.015 (over curvature_tol) above both its steps'
    # means; the lines through the steps beyond, extended to the row, bracket it. Rows
    # 0.2 m apart, by fine integration.
    n, fine = 11, 200
    s = np.linspace(0.0, 2.0, (n - 1) * fine + 1)
    k = 0.15 - 0.15 * np.abs(s - 1.0)
    ds = s[1] - s[0]
    yaw = 0.2 + gear * np.concatenate([[0.0], np.cumsum(0.5 * (k[1:] + k[:-1]) * ds)])
    x, y = _integrate(gear * s, yaw)
    rows = np.column_stack([x, y, yaw, k, np.full_like(s, float(gear))])[::fine]
    check = _verify(rows)
    assert check.kappa_ok, (check.kappa_column_err, check.worst_kappa_row)
    assert check.ok, check.failed


@pytest.mark.parametrize("gear", [1.0, -1.0])
def test_an_end_row_steering_beyond_the_car_fails_kappa_ok(gear):
    # A gear segment's end rows are stops whose kappa is a convention (0, or the next
    # piece's), but the controller turns the wheels to it before moving: 5 1/m on a
    # straight path passed every check (an audit).
    s = np.arange(0.0, 10.0 + 1e-9, 0.25)
    x = 20.0 + gear * s
    rows = np.column_stack([x, np.full_like(s, 20.0), np.zeros_like(s), np.zeros_like(s),
                            np.full_like(s, gear)])  # fmt: skip
    assert _verify(rows).ok
    for end in (0, -1):
        bad = rows.copy()
        bad[end, 3] = 5.0
        check = _verify(bad)
        assert check.failed == ("kappa_ok",), check.failed
        assert check.kappa_column_err == pytest.approx(5.0 - KAPPA_MAX)
        assert check.worst_kappa_row == (len(rows) - 1 if end else 0)
    within = rows.copy()
    within[[0, -1], 3] = (KAPPA_MAX, -KAPPA_MAX)  # the lock either way: a convention kept
    assert _verify(within).ok
