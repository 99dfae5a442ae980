"""Dubins optimality without OMPL: analytic lengths, mirror symmetry, an independent bound.

Mutation audit, session 35: with the RLR word's ``/ 8.0`` changed to ``/ 8.8`` in
``dubins._normalised`` the word was never found and 7% of random goals got a longer
"shortest" path, yet every test passed (the only optimality test needs OMPL). These
tests need no OMPL: the turn-around's closed-form length, the left/right mirror
symmetry of the shortest length, and an upper bound from an independent construction
of the six words by circle geometry (tangent lines, a third tangent circle), each of
its candidates integrated here and kept only when it really ends at the goal.
"""

from __future__ import annotations

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rrtdrive.planning.dubins import dubins_paths, shortest_dubins
from rrtdrive.types import Pose

_TWO_PI = 2.0 * math.pi

Vec = tuple[float, float]
# One segment: +1 left arc, -1 right arc, 0 straight; and its length in metres.
Segment = tuple[int, float]


def _mod2pi(a: float) -> float:
    return a % _TWO_PI


def _centre(p: Pose, turn: int, r: float) -> Vec:
    """Centre of the turning circle on side ``turn`` (+1 left, -1 right) of pose ``p``."""
    return (p.x - turn * r * math.sin(p.yaw), p.y + turn * r * math.cos(p.yaw))


def _drive(p: Pose, segments: list[Segment], r: float) -> Pose:
    """End pose of ``segments`` from ``p``, integrated in closed form (arcs and lines)."""
    x, y, yaw = p.x, p.y, p.yaw
    for turn, length in segments:
        if turn == 0:
            x, y = x + length * math.cos(yaw), y + length * math.sin(yaw)
        else:
            k = turn / r
            yaw1 = yaw + length * k
            x += (math.sin(yaw1) - math.sin(yaw)) / k
            y -= (math.cos(yaw1) - math.cos(yaw)) / k
            yaw = yaw1
    return Pose(x, y, yaw)


def _csc(p: Pose, q: Pose, t1: int, t2: int, r: float) -> list[Segment] | None:
    """Arc, tangent line, arc: the common tangent of the two circles, or None."""
    c1, c2 = _centre(p, t1, r), _centre(q, t2, r)
    dx, dy = c2[0] - c1[0], c2[1] - c1[1]
    dist = math.hypot(dx, dy)
    phi = math.atan2(dy, dx)
    if t1 == t2:  # outer tangent: parallel to the line of centres
        line, h = dist, phi
    else:  # inner tangent: the centres differ by (line, -2 r t1) in the line's frame
        if dist < 2.0 * r:
            return None
        line = math.sqrt(dist * dist - 4.0 * r * r)
        h = phi + math.atan2(2.0 * r * t1, line)
    a1 = _mod2pi(t1 * (h - p.yaw))
    a2 = _mod2pi(t2 * (q.yaw - h))
    return [(t1, a1 * r), (0, line), (t2, a2 * r)]


def _ccc(p: Pose, q: Pose, t: int, side: int, r: float) -> list[Segment] | None:
    """Arc, opposite arc, arc: a third circle tangent to both end circles, or None."""
    c1, c2 = _centre(p, t, r), _centre(q, t, r)
    dx, dy = c2[0] - c1[0], c2[1] - c1[1]
    dist = math.hypot(dx, dy)
    if dist > 4.0 * r or dist == 0.0:
        return None
    h = math.sqrt(4.0 * r * r - 0.25 * dist * dist)
    c3 = (
        0.5 * (c1[0] + c2[0]) - side * h * dy / dist,
        0.5 * (c1[1] + c2[1]) + side * h * dx / dist,
    )

    def angle(frm: Vec, to: Vec) -> float:
        return math.atan2(to[1] - frm[1], to[0] - frm[0])

    # Angular travel around each centre, counter-clockwise for a left arc.
    a1 = _mod2pi(t * (angle(c1, c3) - angle(c1, (p.x, p.y))))
    a2 = _mod2pi(-t * (angle(c3, c2) - angle(c3, c1)))
    a3 = _mod2pi(t * (angle(c2, (q.x, q.y)) - angle(c2, c3)))
    return [(t, a1 * r), (-t, a2 * r), (t, a3 * r)]


def _independent_lengths(p: Pose, q: Pose, r: float) -> dict[str, float]:
    """Length of each word built here that verifiably joins ``p`` to ``q`` (radius ``r``)."""
    candidates: dict[str, list[list[Segment] | None]] = {
        "LSL": [_csc(p, q, 1, 1, r)],
        "RSR": [_csc(p, q, -1, -1, r)],
        "LSR": [_csc(p, q, 1, -1, r)],
        "RSL": [_csc(p, q, -1, 1, r)],
        "LRL": [_ccc(p, q, 1, s, r) for s in (1, -1)],
        "RLR": [_ccc(p, q, -1, s, r) for s in (1, -1)],
    }
    out: dict[str, float] = {}
    for word, options in candidates.items():
        for segs in options:
            if segs is None:
                continue
            end = _drive(p, segs, r)
            dyaw = math.remainder(end.yaw - q.yaw, _TWO_PI)
            if math.hypot(end.x - q.x, end.y - q.y) <= 1e-7 * max(1.0, r) and abs(dyaw) <= 1e-7:
                length = sum(s for _, s in segs)
                out[word] = min(out.get(word, math.inf), length)
    return out


def _shortest(p: Pose, q: Pose, r: float) -> float:
    best = shortest_dubins(p, q, r)
    assert best is not None
    return best.length


@pytest.mark.parametrize("r", [1.0, 2.5, 6.0])
def test_turning_round_on_the_spot_is_7_pi_r_over_3(r: float) -> None:
    # Facing back on the same spot: the end circles' centres are 2 r apart, so the middle
    # circle makes an equilateral triangle with them: arcs of pi/3, 5 pi/3 and pi/3
    # (7 pi r / 3), shorter than any CSC word (LSL and RSR need 3 pi r + 2 r; the inner
    # tangents do not exist). By symmetry both LRL and RLR achieve it: the audit's
    # mutation lost RLR.
    start, goal = Pose(0.0, 0.0, 0.0), Pose(0.0, 0.0, math.pi)
    want = 7.0 * math.pi * r / 3.0
    assert _shortest(start, goal, r) == pytest.approx(want, rel=1e-9)
    found = {p.word: p.length for p in dubins_paths(start, goal, r)}
    assert found.get("LRL") == pytest.approx(want, rel=1e-9), found
    assert found.get("RLR") == pytest.approx(want, rel=1e-9), found
    # The independent construction agrees (it checks its own geometry).
    mine = _independent_lengths(start, goal, r)
    assert mine["LRL"] == pytest.approx(want, rel=1e-9)
    assert mine["RLR"] == pytest.approx(want, rel=1e-9)


near = st.floats(-10.0, 10.0, allow_nan=False)  # within 4 r: the CCC words exist
heading = st.floats(-math.pi, math.pi, allow_nan=False)
radii = st.floats(1.0, 4.0, allow_nan=False)


@settings(max_examples=300, deadline=None)
@given(near, near, heading, radii)
def test_shortest_length_is_mirror_symmetric(x: float, y: float, phi: float, r: float) -> None:
    # Reflecting the goal in the start's axis swaps left and right (LSL <-> RSR,
    # LRL <-> RLR), so the shortest length is unchanged. A lost or wrong word of one
    # hand (the audit's RLR) breaks it for the goals that word serves.
    start = Pose(0.0, 0.0, 0.0)
    a = _shortest(start, Pose(x, y, phi), r)
    b = _shortest(start, Pose(x, -y, -phi), r)
    assert a == pytest.approx(b, rel=1e-9, abs=1e-6 * r)


@settings(max_examples=300, deadline=None)
@given(near, near, heading, radii)
def test_shortest_is_no_longer_than_any_independently_built_word(
    x: float, y: float, phi: float, r: float
) -> None:
    # Every word built here is integrated and kept only if it ends at the goal, so each is
    # a real path of curvature 1/r: the shortest Dubins path cannot be longer than any.
    start, goal = Pose(0.0, 0.0, 0.0), Pose(x, y, phi)
    mine = _independent_lengths(start, goal, r)
    # LSL and RSR (outer tangents) exist for any two poses: the bound is never empty.
    assert {"LSL", "RSR"} <= set(mine)
    assert _shortest(start, goal, r) <= min(mine.values()) + 1e-6 * r
