"""Reeds-Shepp paths: end poses, sampling, gears, lengths against Dubins and OMPL."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import example, given, settings
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
from rrtdrive.planning.reeds_shepp_table import (
    ReedsSheppTable,
    reeds_shepp_table,
    shortest_lengths,
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
    # Forward-only paths are a subset: never longer than the shortest Dubins path (to
    # the Dubins module's accuracy: its cancellation near d = 0 leaves ~1e-8 m).
    assert best.length <= shortest_dubins(start, goal, r).length + 1e-6 * max(1.0, r)


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
    # reeds_shepp_paths keeps one copy of each of them (overlapping families): every
    # candidate is one of the paths, every path a candidate, no two paths the same.
    paths = reeds_shepp_paths(start, goal, r)

    def same(word, lengths, p):
        scaled = [s / r for s in p.lengths]
        return p.word == word and np.allclose(lengths, scaled, rtol=0.0, atol=1e-9)

    assert all(any(same(w, ls, p) for p in paths) for w, ls in raw)
    assert all(any(same(w, ls, p) for w, ls in raw) for p in paths)
    for i, p in enumerate(paths):
        assert not any(same(p.word, [s / r for s in p.lengths], q) for q in paths[i + 1 :])


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


# --- many poses at once, and the lookup table (planning/reeds_shepp_table.py) ---------


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 2**32 - 1), st.floats(0.1, 8.0))
def test_vectorised_lengths_equal_the_scalar_ones(seed, spread):
    rng = np.random.default_rng(seed)
    x, y = rng.uniform(-spread, spread, (2, 200))
    phi = rng.uniform(-4.0, 4.0, 200)
    # Exact headings and axes too, where the formulas' sign tests sit on their edges.
    phi[:40] = rng.choice([0.0, math.pi / 2, -math.pi / 2, math.pi, -math.pi], 40)
    y[40:60] = 0.0
    got = shortest_lengths(x, y, phi)
    want = [words.shortest_length(a, b, c) for a, b, c in zip(x, y, phi, strict=True)]
    assert np.allclose(got, want, rtol=0.0, atol=1e-9)


@pytest.fixture(scope="module")
def small_table() -> ReedsSheppTable:
    return ReedsSheppTable.build(2.0, extent=6.0, resolution=0.25, yaw_bins=48)


def test_table_is_exact_on_its_nodes_in_all_four_quadrants(small_table):
    t = small_table
    rng = np.random.default_rng(1)
    n = t.values.shape[0]
    for _ in range(200):
        i, j, k = rng.integers(0, n), rng.integers(0, n), rng.integers(0, t.yaw_bins)
        x, y, yaw = i * t.resolution, j * t.resolution, k * 2 * math.pi / t.yaw_bins
        sx, sy = rng.choice([-1.0, 1.0], 2)
        # Mirroring a quadrant negates the heading once per axis flipped.
        goal_yaw = yaw * (sx * sy)
        start = Pose(3.0, -1.0, 0.0)
        goal = Pose(3.0 + sx * x, -1.0 + sy * y, goal_yaw)
        exact = reeds_shepp_distance(start, goal, t.radius)
        assert t.distance(start, goal) == pytest.approx(exact, abs=1e-9)
        assert t.lookup(sx * x, sy * y, goal_yaw) == pytest.approx(exact, abs=1e-9)


def test_table_lookup_between_nodes_and_outside(small_table):
    t = small_table
    rng = np.random.default_rng(2)
    starts = [Pose(*rng.uniform(-5, 5, 2), rng.uniform(-math.pi, math.pi)) for _ in range(300)]
    err = []
    for k, s in enumerate(starts):
        reach = 5.5 if k % 3 else 12.0  # a third of the goals may fall outside the grid
        g = Pose(
            s.x + rng.uniform(-reach, reach),
            s.y + rng.uniform(-reach, reach),
            rng.uniform(-math.pi, math.pi),
        )
        exact = reeds_shepp_distance(s, g, t.radius)
        got = t.distance(s, g)
        # The scalar and the array lookups are one interpolation.
        c, sn = math.cos(s.yaw), math.sin(s.yaw)
        dx, dy = g.x - s.x, g.y - s.y
        assert t.lookup(c * dx + sn * dy, c * dy - sn * dx, g.yaw - s.yaw) == pytest.approx(got)
        local = (abs(c * dx + sn * dy), abs(c * dy - sn * dx))
        if max(local) > t.extent:
            assert got == exact  # outside: the exact length
        else:
            err.append(abs(got - exact))
    assert len(err) > 100
    # Interpolation error: at most what build() measured on its own random poses, plus
    # slack for poses it did not draw; small on average.
    assert max(err) <= 2 * t.max_error + 1e-9
    assert float(np.mean(err)) < 0.1 * t.resolution


def test_table_cache_and_errors():
    assert reeds_shepp_table(1.5, 3.0, 0.5, 8) is reeds_shepp_table(1.5, 3.0, 0.5, 8)
    with pytest.raises(InputError, match="radius"):
        ReedsSheppTable.build(0.0)
    with pytest.raises(InputError, match="resolution"):
        ReedsSheppTable.build(1.0, resolution=-1.0)
    with pytest.raises(InputError, match="yaw_bins"):
        ReedsSheppTable.build(1.0, yaw_bins=2)


def _pose_at(path: ReedsSheppPath, s: float) -> tuple[float, float, float]:
    """The pose ``s`` metres (driven, either gear) along ``path``, integrated by hand."""
    x, y, yaw = path.start.x, path.start.y, path.start.yaw
    for seg in path.segments:
        step = max(-s, seg.length) if seg.gear < 0 else min(s, seg.length)
        s -= abs(step)
        if seg.kind == "S":
            x, y = x + step * math.cos(yaw), y + step * math.sin(yaw)
        else:
            k = (1.0 if seg.kind == "L" else -1.0) / path.radius
            yaw1 = yaw + step * k
            x += (math.sin(yaw1) - math.sin(yaw)) / k
            y -= (math.cos(yaw1) - math.cos(yaw)) / k
            yaw = yaw1
        if s <= 0:
            break
    return x, y, yaw


def test_geometry_matches_ompl_interpolation():
    # Not only the length: the shortest word itself, pose by pose along it, where it is
    # unique (ties between words of equal length may be broken either way).
    ob = pytest.importorskip("ompl.base")
    rng = np.random.default_rng(4)
    compared = 0
    for _ in range(300):
        r = float(rng.uniform(1.0, 8.0))
        space = ob.ReedsSheppStateSpace(r)
        a, b, c = space.allocState(), space.allocState(), space.allocState()
        s = Pose(*rng.uniform(-10, 10, 2), rng.uniform(-math.pi, math.pi))
        g = Pose(*(s.xy + rng.uniform(-3 * r, 3 * r, 2)), rng.uniform(-math.pi, math.pi))
        a.setX(s.x), a.setY(s.y), a.setYaw(s.yaw)
        b.setX(g.x), b.setY(g.y), b.setYaw(g.yaw)
        paths = reeds_shepp_paths(s, g, r)
        if len(paths) > 1 and paths[1].length - paths[0].length < 1e-9:
            continue
        compared += 1
        for t in np.linspace(0.05, 0.95, 7):
            space.interpolate(a, b, float(t), c)
            x, y, yaw = _pose_at(paths[0], t * paths[0].length)
            assert math.hypot(c.getX() - x, c.getY() - y) < 1e-9
            assert abs(wrap_angle(c.getYaw() - yaw)) < 1e-9
    assert compared > 200


@settings(max_examples=80, deadline=None)
@given(pose_pairs(), radius, st.floats(0.01, 5.0), st.integers(1, 6))
def test_a_cusp_cost_orders_the_same_paths_by_length_plus_cost(poses, r, cost, limit):
    start, goal = poses
    plain = reeds_shepp_paths(start, goal, r)
    costed = reeds_shepp_paths(start, goal, r, cusp_cost=cost)
    key = [p.length + cost * p.gear_changes for p in costed]
    assert key == sorted(key)
    # The same paths, to 1e-9 m: of two near-equal copies of a word found by different
    # symmetries, the order may keep either (1e-15 m apart).
    a = sorted((p.word, p.lengths) for p in plain)
    b = sorted((p.word, p.lengths) for p in costed)
    assert [w for w, _ in a] == [w for w, _ in b]
    for (_, la), (_, lb) in zip(a, b, strict=True):
        assert la == pytest.approx(lb, abs=1e-9)
    # ``limit`` keeps the first of that order.
    first = reeds_shepp_paths(start, goal, r, limit=limit, cusp_cost=cost)[:limit]
    assert [p.length + cost * p.gear_changes for p in first] == pytest.approx(key[:limit])


def test_a_cusp_cost_drops_a_last_move_of_two_centimetres():
    # Into a parking-reverse-in bay (seed 0): the shortest word ends in a 1.5 cm forward
    # move after the reverse into the bay, 0.05 mm shorter than the word without it.
    start, goal, r = Pose(29.347, 28.266, 0.284), Pose(66.5, 21.995, math.pi / 2), 1 / 0.163
    words_by_length = [p.word for p in reeds_shepp_paths(start, goal, r)]
    assert words_by_length.index("LRSLR") < words_by_length.index("LRSL")
    costed = reeds_shepp_paths(start, goal, r, cusp_cost=0.5)
    assert [p.word for p in costed].index("LRSL") < [p.word for p in costed].index("LRSLR")
    lrsl = next(p for p in costed if p.word == "LRSL")
    assert lrsl.gear_changes == 1 and min(abs(s) for s in lrsl.lengths) > 1.0


@settings(max_examples=200, deadline=None)
@given(
    x=st.floats(-200.0, 200.0), y=st.floats(-200.0, 200.0), yaw=st.floats(-math.pi, math.pi),
    d=st.floats(1e-4, 2.0), behind=st.booleans(),
)
def test_a_goal_just_ahead_or_behind_is_one_straight(
    x: float, y: float, yaw: float, d: float, behind: bool
) -> None:
    """The float noise of cos/sin in the goal does not turn a straight into a shuffle.

    A goal 1 cm behind at 0.3 rad gave LRLR of 2.4 cm with two cusps (no CSC word
    passed the sign tests), and Hybrid A* drove 4 m with a cusp to get there.
    """
    s = -d if behind else d
    start = Pose(x, y, yaw)
    goal = Pose(x + s * math.cos(yaw), y + s * math.sin(yaw), yaw)
    best = reeds_shepp_paths(start, goal, 6.0)[0]
    # The floats of the goal put it up to ~1e-12 m off the exact distance.
    assert best.length == pytest.approx(math.hypot(goal.x - x, goal.y - y), abs=1e-9)
    assert all(v <= 0.0 if behind else v >= 0.0 for v in best.lengths), best


_SEGMENT = st.tuples(st.sampled_from((-1.0, 0.0, 1.0)), st.floats(1e-3, 3.0), st.booleans())


@settings(max_examples=300, deadline=None)
@given(
    x=st.floats(-2000.0, 2000.0), y=st.floats(-2000.0, 2000.0),
    yaw=st.floats(-math.pi, math.pi), segments=st.lists(_SEGMENT, min_size=1, max_size=3),
)
# Three that the 10 eps slack lost (LRLR 1.115, RLRL 1.017, LRLR 1.707 times the drive).
@example(x=-55.669, y=82.444, yaw=2.5044, segments=[(1.0, 0.0147, False), (0.0, 0.0013, False)])
@example(x=-51.712, y=-24.46, yaw=-1.8095, segments=[(-1.0, 0.5445, False), (0.0, 0.0067, False)])
@example(x=106.806, y=-71.594, yaw=0.0452, segments=[(0.0, 0.0019, False), (-1.0, 0.0019, False)])
def test_no_word_is_longer_than_a_drive_that_reaches_the_goal(
    x: float, y: float, yaw: float, segments: list[tuple[float, float, bool]]
) -> None:
    """Drive up to three arcs or lines in either gear; the shortest word is no longer.

    With OMPL's 10 eps slack on the formulas' sign tests, a zero-length arc came out
    -1e-13 (float noise over a short neighbour) and its word was lost: a line then an
    arc gave LRLR up to 50 % longer (21 of 6 000 random drives).
    """
    radius = 6.0
    pose, total = (x, y, yaw), 0.0
    for turn, length, back in segments:
        s = -length if back else length
        px, py, pyaw = pose
        if turn == 0.0:
            pose = (px + s * math.cos(pyaw), py + s * math.sin(pyaw), pyaw)
        else:
            k = turn / radius
            pose = (px + (math.sin(pyaw + k * s) - math.sin(pyaw)) / k,
                    py - (math.cos(pyaw + k * s) - math.cos(pyaw)) / k, pyaw + k * s)  # fmt: skip
        total += length
    best = reeds_shepp_paths(Pose(x, y, yaw), Pose(*pose), radius)[0]
    assert best.length <= total + 1e-6
    if not any(back for _, _, back in segments):  # forward only: Dubins too
        assert shortest_dubins(Pose(x, y, yaw), Pose(*pose), radius).length <= total + 1e-6
