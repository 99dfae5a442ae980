"""Reeds-Shepp paths: end poses, sampling, gears, lengths against Dubins and OMPL."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rrtdrive.geometry import wrap_angle
from rrtdrive.planning import reeds_shepp as rs
from rrtdrive.planning import reeds_shepp_words as words
from rrtdrive.planning.dubins import shortest_dubins
from rrtdrive.planning.reeds_shepp import (
    ReedsSheppPath,
    ReedsSheppSegment,
    reeds_shepp_distance,
    reeds_shepp_paths,
    shortest_reeds_shepp,
)
from rrtdrive.types import InputError, Pose

coord = st.floats(-40.0, 40.0, allow_nan=False)
near = st.floats(-4.0, 4.0, allow_nan=False)  # goals within a few radii: the cusp words
angle = st.floats(-math.pi, math.pi, allow_nan=False)
radius = st.floats(0.5, 12.0, allow_nan=False)
spacing = st.floats(0.05, 2.0, allow_nan=False)


@st.composite
def pose_pairs(draw: st.DrawFn, near_only: bool = False) -> tuple[Pose, Pose]:
    """A start anywhere and a goal anywhere or (half the time) within a few metres."""
    start = Pose(draw(coord), draw(coord), draw(angle))
    if near_only or draw(st.booleans()):
        return start, Pose(start.x + draw(near), start.y + draw(near), draw(angle))
    return start, Pose(draw(coord), draw(coord), draw(angle))


def check_samples(path: ReedsSheppPath, goal: Pose, ds: float) -> np.ndarray:
    """Assert the sampled geometry of ``path``; return the samples."""
    s = path.sample(ds)
    r = path.radius
    assert s.shape[1] == 5
    start = path.start
    assert np.allclose(s[0, :3], [start.x, start.y, wrap_angle(start.yaw)], atol=1e-12)
    # The last row is the goal, and so is the closed-form end of the segments.
    assert math.hypot(s[-1, 0] - goal.x, s[-1, 1] - goal.y) < 1e-6 * max(1.0, r)
    assert abs(wrap_angle(s[-1, 2] - goal.yaw)) < 1e-6
    ex, ey, eyaw = path.end()
    assert math.hypot(ex - goal.x, ey - goal.y) < 1e-6 * max(1.0, r)
    assert abs(wrap_angle(eyaw - goal.yaw)) < 1e-6
    # Gears are +-1, curvatures 0 or +-1/r, in both gears.
    assert set(np.unique(s[:, 4])) <= {-1.0, 1.0}
    assert np.all((s[:, 3] == 0.0) | np.isclose(np.abs(s[:, 3]), 1.0 / r, rtol=1e-12))
    # A cusp repeats the position row exactly, with the new gear; one per gear change.
    change = np.flatnonzero(np.diff(s[:, 4]) != 0)
    assert len(change) == path.gear_changes
    assert np.array_equal(s[change, :3], s[change + 1, :3])
    step = np.diff(s[:, :2], axis=0)
    gap = np.hypot(*step.T)
    assert gap.max(initial=0.0) <= ds + 1e-9
    # Along a segment: yaw change = kappa * signed ds, and the chord points along the
    # direction of travel (nose for gear +1, tail for -1) turned by half the step.
    moving = np.ones(len(gap), dtype=bool)
    moving[change] = False
    k, gear = s[:-1, 3], s[:-1, 4]
    arc = np.where(k == 0.0, gap, 2.0 * np.arcsin(np.clip(gap * np.abs(k) / 2, 0.0, 1.0)) * r)
    dyaw = wrap_angle(np.diff(s[:, 2]))
    assert np.allclose(dyaw[moving], (k * gear * arc)[moving], atol=1e-8)
    travel = s[:-1, 2] + np.where(gear < 0, math.pi, 0.0) + dyaw / 2
    chord = np.arctan2(step[:, 1], step[:, 0])
    real = moving & (gap > 1e-6)
    assert np.all(np.abs(wrap_angle(chord - travel))[real] < 1e-6)
    # Arc length of the samples is the path's length (chords of arcs are not shorter by much).
    assert arc[moving].sum() == pytest.approx(path.length, abs=1e-6)
    return s


@settings(max_examples=150, deadline=None)
@given(pose_pairs(), radius, spacing)
def test_shortest_path_reaches_the_goal_with_exact_samples(poses, r, ds):
    start, goal = poses
    paths = reeds_shepp_paths(start, goal, r)
    assert paths, "a Reeds-Shepp path exists between any two poses"
    assert [p.length for p in paths] == sorted(p.length for p in paths)
    best = paths[0]
    assert best.length >= math.hypot(goal.x - start.x, goal.y - start.y) - 1e-9
    check_samples(best, goal, ds)
    # The fast distance is the same minimum.
    assert reeds_shepp_distance(start, goal, r) == pytest.approx(best.length, abs=1e-9)
    # Forward-only paths are a subset: never longer than the shortest Dubins path.
    assert best.length <= shortest_dubins(start, goal, r).length + 1e-9


@settings(max_examples=60, deadline=None)
@given(pose_pairs(near_only=True), radius)
def test_every_candidate_of_the_formulas_reaches_the_goal(poses, r):
    # The end-pose filter in reeds_shepp_paths is a safety net: no formula relies on it.
    start, goal = poses
    x, y, phi = rs._normalised_goal(start, goal, r)
    raw = [rs._tidy(w, ls) for w, ls in words.candidates(x, y, phi)]
    assert raw
    for word, lengths in raw:
        p = ReedsSheppPath(start, word, tuple(s * r for s in lengths), r)
        check_samples(p, goal, 0.5)
    # reeds_shepp_paths keeps one copy of each of them (overlapping families).
    paths = reeds_shepp_paths(start, goal, r)
    distinct = {(w, tuple(round(s, 6) for s in ls)) for w, ls in raw}
    assert len(paths) == len(distinct)
    assert {(p.word, tuple(round(s / r, 6) for s in p.lengths)) for p in paths} == distinct


@settings(max_examples=100, deadline=None)
@given(pose_pairs(), radius)
def test_symmetries_of_the_length(poses, r):
    a, b = poses
    d = reeds_shepp_distance(a, b, r)
    # Driving the path backwards in time joins b to a.
    assert reeds_shepp_distance(b, a, r) == pytest.approx(d, abs=1e-9)
    # The mirror image about the start's axis (left <-> right).
    x, y, phi = rs._normalised_goal(a, b, r)
    mirror = Pose(x * r, -y * r, -phi)
    assert reeds_shepp_distance(Pose(0.0, 0.0, 0.0), mirror, r) == pytest.approx(d, abs=1e-9)
    # Timeflip: the goal behind, every gear swapped.
    flip = Pose(-x * r, y * r, -phi)
    assert reeds_shepp_distance(Pose(0.0, 0.0, 0.0), flip, r) == pytest.approx(d, abs=1e-9)


def test_pure_straight_forward_and_reverse():
    ahead = Pose(1.0 + 8 * math.cos(0.5), 2.0 + 8 * math.sin(0.5), 0.5)
    p = shortest_reeds_shepp(Pose(1.0, 2.0, 0.5), ahead, 3.0)
    assert p.word == "S" and p.lengths == pytest.approx((8.0,)) and p.gear_changes == 0
    assert p.segments == (ReedsSheppSegment("S", p.lengths[0]),) and p.segments[0].gear == 1
    s = p.sample(1.0)
    assert len(s) == 9 and np.all(s[:, 4] == 1.0) and np.all(s[:, 3] == 0.0)
    # Straight back: nose still along +x, gear -1 throughout.
    p = shortest_reeds_shepp(Pose(0.0, 0.0, 0.0), Pose(-3.0, 0.0, 0.0), 5.0)
    assert p.word == "S" and p.lengths == pytest.approx((-3.0,)) and p.gears == (-1,)
    s = check_samples(p, Pose(-3.0, 0.0, 0.0), 0.25)
    assert np.all(s[:, 4] == -1.0) and np.allclose(s[:, 2], 0.0) and len(s) == 13
    # Start = goal: one row, no segment.
    p = shortest_reeds_shepp(Pose(1.0, 1.0, 1.0), Pose(1.0, 1.0, 1.0), 2.0)
    assert p.word == "" and p.length == 0.0
    assert p.sample(0.5).tolist() == [[1.0, 1.0, 1.0, 0.0, 1.0]]


@pytest.mark.parametrize("t", [0.05, 0.2, 0.42, 0.5])
def test_parallel_shift_with_two_cusps(t):
    # R+t L-u R-u L+t: by hand, with radius 1 the end is (4 sin t - 2 sin(t+u),
    # 4 cos t - 2 - 2 cos(t+u), 0); sin(t+u) = 2 sin t makes it a pure sideways shift.
    r = 4.0
    tu = math.asin(2 * math.sin(t))
    h = r * (4 * math.cos(t) - 2 - 2 * math.cos(tu))
    goal = Pose(0.0, h, 0.0)
    p = shortest_reeds_shepp(Pose(0.0, 0.0, 0.0), goal, r)
    assert p.word == "RLRL" and p.gears == (1, -1, -1, 1) and p.gear_changes == 2
    assert p.lengths == pytest.approx((r * t, -r * (tu - t), -r * (tu - t), r * t), abs=1e-9)
    assert p.length == pytest.approx(2 * r * tu, abs=1e-9)
    s = check_samples(p, goal, 0.1)
    assert len(np.flatnonzero(np.diff(s[:, 4]))) == 2
    # The mirror shift to the right is the mirrored word.
    q = shortest_reeds_shepp(Pose(0.0, 0.0, 0.0), Pose(0.0, -h, 0.0), r)
    assert q.word == "LRLR" and q.length == pytest.approx(p.length, abs=1e-9)


def test_errors_name_the_field():
    with pytest.raises(InputError, match="radius"):
        reeds_shepp_paths(Pose(0, 0, 0), Pose(1, 0, 0), 0.0)
    with pytest.raises(InputError, match="radius"):
        reeds_shepp_distance(Pose(0, 0, 0), Pose(1, 0, 0), math.nan)
    p = shortest_reeds_shepp(Pose(0, 0, 0), Pose(1, 1, 1), 1.0)
    with pytest.raises(InputError, match="spacing"):
        p.sample(0.0)
    with pytest.raises(InputError, match="lengths"):
        ReedsSheppPath(Pose(0, 0, 0), "LS", (1.0,), 1.0)
    with pytest.raises(InputError, match="kind"):
        ReedsSheppSegment("X", 1.0)
    with pytest.raises(InputError, match="length"):
        ReedsSheppSegment("L", 0.0)


def test_lengths_match_ompl():
    ob = pytest.importorskip("ompl.base")
    rng = np.random.default_rng(7)
    for r in (1.0, 6.0):
        space = ob.ReedsSheppStateSpace(r)
        a, b = space.allocState(), space.allocState()
        for i in range(1000):
            s = Pose(*rng.uniform(-30, 30, 2), rng.uniform(-math.pi, math.pi))
            spread = 3.0 * r if i % 2 else 30.0  # half the goals within a few radii
            g = Pose(*(s.xy + rng.uniform(-spread, spread, 2)), rng.uniform(-math.pi, math.pi))
            a.setX(s.x), a.setY(s.y), a.setYaw(s.yaw)
            b.setX(g.x), b.setY(g.y), b.setYaw(g.yaw)
            ref = space.distance(a, b)
            assert shortest_reeds_shepp(s, g, r).length == pytest.approx(ref, abs=1e-6)
            assert reeds_shepp_distance(s, g, r) == pytest.approx(ref, abs=1e-6)
