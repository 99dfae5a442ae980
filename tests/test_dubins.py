"""Dubins paths: endpoints, curvature, lengths, against OMPL when it is installed."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rrtdrive.geometry import wrap_angle
from rrtdrive.planning.dubins import dubins_paths, shortest_dubins
from rrtdrive.planning.hybrid.heuristic import dubins_lengths
from rrtdrive.types import InputError, Pose

coord = st.floats(-40.0, 40.0, allow_nan=False)
angle = st.floats(-math.pi, math.pi, allow_nan=False)
radius = st.floats(1.0, 12.0, allow_nan=False)


_wrap = wrap_angle


@settings(max_examples=200, deadline=None)
@given(coord, coord, angle, coord, coord, angle, radius)
def test_shortest_path_joins_the_poses_with_bounded_curvature(x0, y0, a0, x1, y1, a1, r):
    start, goal = Pose(x0, y0, a0), Pose(x1, y1, a1)
    paths = dubins_paths(start, goal, r)
    assert paths, "a Dubins path exists between any two poses"
    best = paths[0]
    assert [p.length for p in paths] == sorted(p.length for p in paths)
    # Within the ends' tolerance (1e-6 m) a goal 0.12 um behind is the start: 0 m, not a
    # loop (the stress profile found it once full turns of float noise became 0).
    assert best.length >= math.hypot(x1 - x0, y1 - y0) - 1e-6 * max(1.0, r)
    s = best.sample(0.2)
    # Both ends, headings included; samples at most 0.2 m apart.
    assert np.allclose(s[0, :3], [x0, y0, _wrap(a0)], atol=1e-9)
    assert math.hypot(s[-1, 0] - x1, s[-1, 1] - y1) < 1e-6 * max(1.0, r)
    assert abs(_wrap(s[-1, 2] - a1)) < 1e-6
    gaps = np.hypot(*np.diff(s[:, :2], axis=0).T)
    assert gaps.max() <= 0.2 + 1e-9
    # Curvature is 0 or +-1/r, and the polyline's length is the path's (chords of arcs).
    assert np.all(np.isclose(np.abs(s[:, 3]), 1.0 / r) | (s[:, 3] == 0.0))
    # A chord of an arc step of at most 0.2 m is shorter by at most (0.2 / r)^2 / 24.
    assert best.length * (1 - (0.2 / r) ** 2 / 24) - 1e-6 <= gaps.sum() <= best.length + 1e-6
    # The heading of each sample points along the motion to the next one.
    mid = (s[1:, :2] - s[:-1, :2])
    moving = np.hypot(*mid.T) > 1e-6
    chord = np.arctan2(mid[:, 1], mid[:, 0])
    # On an arc the chord turns by half the step's angle, asin(chord * kappa / 2).
    k = s[:-1, 3]
    yaw_mid = s[:-1, 2] + np.sign(k) * np.arcsin(np.clip(gaps * np.abs(k) / 2, 0.0, 1.0))
    assert np.all(np.abs(_wrap(chord - yaw_mid))[moving] < 1e-6)


def test_known_lengths():
    # Straight ahead: the line itself.
    p = shortest_dubins(Pose(0, 0, 0), Pose(10, 0, 0), 2.0)
    assert p.length == pytest.approx(10.0) and p.lengths[0] == pytest.approx(0.0)
    # A half circle to the left: pi r.
    p = shortest_dubins(Pose(0, 0, 0), Pose(0, 4, math.pi), 2.0)
    assert p.length == pytest.approx(2 * math.pi) and p.word in ("LSL", "LRL")
    # Turning round in place needs more than a half circle's width: longer than pi r.
    p = shortest_dubins(Pose(0, 0, 0), Pose(0, 0, math.pi), 2.0)
    assert p.length > 2 * math.pi
    with pytest.raises(InputError, match="radius"):
        dubins_paths(Pose(0, 0, 0), Pose(1, 0, 0), 0.0)
    with pytest.raises(InputError, match="spacing"):
        p.sample(0.0)


def test_lengths_match_ompl():
    ob = pytest.importorskip("ompl.base")
    rng = np.random.default_rng(7)
    r = 6.0
    space = ob.DubinsStateSpace(r)
    a, b = space.allocState(), space.allocState()
    for _ in range(500):
        s = Pose(*rng.uniform(-30, 30, 2), rng.uniform(-math.pi, math.pi))
        g = Pose(*rng.uniform(-30, 30, 2), rng.uniform(-math.pi, math.pi))
        a.setX(s.x), a.setY(s.y), a.setYaw(s.yaw)
        b.setX(g.x), b.setY(g.y), b.setYaw(g.yaw)
        assert shortest_dubins(s, g, r).length == pytest.approx(space.distance(a, b), abs=1e-6)


@settings(max_examples=300, deadline=None)
@given(
    x=st.floats(-2000.0, 2000.0), y=st.floats(-2000.0, 2000.0),
    yaw=st.floats(-math.pi, math.pi), d=st.floats(1e-4, 2.0),
)
def test_a_goal_just_ahead_is_one_straight(x: float, y: float, yaw: float, d: float) -> None:
    """The float noise of cos/sin in the goal does not add a full loop.

    A goal 1.2 cm straight ahead at -2.86 rad put atan2 1e-13 under a full turn, and
    the shortest word was a 37.7 m loop (12 of 2 000 random short goals).
    """
    start = Pose(x, y, yaw)
    goal = Pose(x + d * math.cos(yaw), y + d * math.sin(yaw), yaw)
    best = dubins_paths(start, goal, 6.0)[0]
    # The floats of the goal put it up to ~1e-12 m off the exact distance.
    exact = math.hypot(goal.x - x, goal.y - y)
    assert best.length == pytest.approx(exact, abs=1e-9)
    # Hybrid A*'s forward heuristic, element-wise, agrees.
    got = dubins_lengths(np.array([[x, y, yaw]]), goal, 6.0)[0]
    assert got == pytest.approx(exact, abs=1e-9)


@settings(max_examples=300, deadline=None)
@given(
    x=st.floats(-200.0, 200.0), y=st.floats(-200.0, 200.0), yaw=st.floats(-math.pi, math.pi),
    s=st.floats(1e-4, 3.0), left=st.booleans(),
)
def test_a_goal_on_one_arc_is_that_arc(x: float, y: float, yaw: float, s: float, left: bool):
    """A goal one full-lock arc ahead: the words find it, not a 38 m loop.

    The straight of LSL (or the turn of LSR) has squared length 0 there, and float
    noise put it at -1e-16: no such word, and in 2 237 of 2 500 random arcs the
    shortest word left was a loop.
    """
    k = (1.0 if left else -1.0) / 6.0
    start = Pose(x, y, yaw)
    goal = Pose(x + (math.sin(yaw + k * s) - math.sin(yaw)) / k,
                y - (math.cos(yaw + k * s) - math.cos(yaw)) / k, yaw + k * s)  # fmt: skip
    assert dubins_paths(start, goal, 6.0)[0].length == pytest.approx(s, abs=1e-6)
    got = dubins_lengths(np.array([[x, y, yaw]]), goal, 6.0)[0]
    assert got == pytest.approx(s, abs=1e-6)


@pytest.mark.parametrize("aside", [1e-5, -1e-5, 2e-7, 1e-9])
def test_a_heading_a_hair_off_the_line_is_a_real_angle(aside: float) -> None:
    """Only a word's arcs lose a hair under a full turn, never the headings themselves.

    Snapping the headings too, a goal 1e-5 m aside over 20 m (5e-7 rad off the line)
    had no Dubins word at all (the stress profile found it).
    """
    start, goal = Pose(0.0, aside, 0.0), Pose(20.0, 0.0, 0.0)
    best = shortest_dubins(start, goal, 1.0)
    assert best is not None and best.length == pytest.approx(20.0, abs=1e-4)
    got = dubins_lengths(np.array([[0.0, aside, 0.0]]), goal, 1.0)[0]
    assert got == pytest.approx(best.length, abs=1e-6)
