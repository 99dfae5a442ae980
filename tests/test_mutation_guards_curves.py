"""Guards found by mutation testing of the curve modules (Reeds-Shepp, Dubins, clothoids, B-spline).

Each test pins one behaviour that a small change of the code left untested; the
reference is independent of the code under test (closed-form geometry, numerical
integration of the curvature, shapely bodies, or the Reeds-Shepp theory).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st
from test_clothoid import integrate_turn
from test_improved import densify
from test_smoothing import menger

from rrtdrive.collision import CollisionChecker
from rrtdrive.maps import Map, Obstacle, builtin_map
from rrtdrive.planning import dubins
from rrtdrive.planning import reeds_shepp as rs
from rrtdrive.planning.base import cached_checker
from rrtdrive.planning.dubins import dubins_paths
from rrtdrive.planning.edges import exact_edge_free
from rrtdrive.planning.reeds_shepp import reeds_shepp_paths
from rrtdrive.planning.reeds_shepp_table import ReedsSheppTable
from rrtdrive.planning.smoothing import CurveKind, SmoothingConfig, curvature, make_drivable
from rrtdrive.planning.smoothing.checks import CheckerView
from rrtdrive.planning.smoothing.clothoid import (
    clothoid_turn,
    sample_turn,
    sharpness_levels,
    turn_circle,
)
from rrtdrive.planning.smoothing.clothoid_curve import (
    ClothoidFitter,
    polygon_curve,
    polygon_turns,
    sample_pieces,
)
from rrtdrive.planning.smoothing.corners import Corner, CornerKind, Ends, turn_reach
from rrtdrive.types import InputError, Pose
from rrtdrive.vehicle import footprint_corners

KAPPA = 1.0 / 6.0
SIGMA = 0.2 / 2.51

coord = st.floats(-40.0, 40.0, allow_nan=False)
near = st.floats(-4.0, 4.0, allow_nan=False)
angle = st.floats(-math.pi, math.pi, allow_nan=False)
radius = st.floats(0.5, 12.0, allow_nan=False)


@st.composite
def near_pairs(draw: st.DrawFn) -> tuple[Pose, Pose]:
    """A start anywhere and a goal within a few metres (where the cusp words live)."""
    start = Pose(draw(coord), draw(coord), draw(angle))
    return start, Pose(start.x + draw(near), start.y + draw(near), draw(angle))


# ----------------------------------------------------------------------------- Reeds-Shepp


@settings(max_examples=60, deadline=None)
@given(near_pairs(), radius)
def test_rs_last_sample_is_the_goal_exactly(poses: tuple[Pose, Pose], r: float) -> None:
    """The documented contract: the last row is ``goal``, bit for bit, not the integrated end."""
    start, goal = poses
    for path in reeds_shepp_paths(start, goal, r, limit=3):
        if not path.word:  # a goal within 1e-10 r: the one row is the start
            continue
        last = path.sample(0.5)[-1]
        assert last[0] == goal.x and last[1] == goal.y
        assert last[2] == pytest.approx(math.remainder(goal.yaw, 2 * math.pi), abs=1e-15)


def _rs_with(monkeypatch: pytest.MonkeyPatch, word: str, lengths: tuple[float, ...]) -> None:
    """Make the formulas return one (possibly wrong) candidate, to test the end check."""
    monkeypatch.setattr(rs, "candidates", lambda x, y, phi: [(word, lengths)])


def test_rs_keeps_a_candidate_within_tol_times_radius_and_drops_one_beyond(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A candidate is kept when it ends within ``tol * max(1, radius)`` metres of the goal."""
    r, tol = 5.0, 1e-6  # position tolerance tol * max(1, r) = 5e-6 m
    start, goal = Pose(0.0, 0.0, 0.0), Pose(10.0, 0.0, 0.0)
    _rs_with(monkeypatch, "S", ((10.0 + 2.5e-6) / r,))  # a straight 2.5e-6 m too long
    assert [p.word for p in reeds_shepp_paths(start, goal, r, tol=tol)] == ["S"]
    _rs_with(monkeypatch, "S", ((10.0 + 1e-5) / r,))  # 1e-5 m too long
    assert reeds_shepp_paths(start, goal, r, tol=tol) == []


def test_rs_drops_a_candidate_that_ends_at_the_goal_position_with_another_heading(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A wrong formula cannot return a path that ends at the goal's place facing elsewhere."""
    _rs_with(monkeypatch, "S", (2.0,))  # reaches (10, 0) at radius 5, heading 0
    assert reeds_shepp_paths(Pose(0.0, 0.0, 0.0), Pose(10.0, 0.0, 0.3), 5.0) == []


@pytest.mark.parametrize("r", [1.0, 2.0, 5.0])
def test_rs_half_turn_then_back_on_one_circle_stays_two_segments(r: float) -> None:
    """A cusp between two arcs of one circle is two segments, never merged into one.

    The goal is a quarter turn right (centre (0, -r)): driving R forward by pi r (a
    half turn) and then R in reverse by pi r / 2 reaches it (a quarter turn back on
    the same circle), the R|R word (pi r, -pi r / 2) with one cusp.
    """
    goal = Pose(r, -r, -math.pi / 2)
    paths = reeds_shepp_paths(Pose(0.0, 0.0, 0.0), goal, r)
    rr = [p for p in paths if p.word == "RR"]
    assert rr, [p.word for p in paths]
    assert rr[0].lengths == pytest.approx((math.pi * r, -0.5 * math.pi * r), abs=1e-9)
    assert rr[0].gear_changes == 1
    # and no returned word has two neighbours of one kind in one gear (they are one segment)
    for p in paths:
        for a, b in zip(p.segments, p.segments[1:], strict=False):
            assert not (a.kind == b.kind and a.gear == b.gear)


@settings(max_examples=80, deadline=None)
@given(near_pairs(), radius)
def test_rs_no_straight_touches_a_cusp(poses: tuple[Pose, Pose], r: float) -> None:
    """Reeds & Shepp's families: a straight's neighbours share its gear, at most two cusps.

    In every family (CSC, C|C|C, CC|CC, C|C(pi/2) S C, C|C(pi/2) S C(pi/2)|C) the cusps
    lie between arcs; a cusp beside a straight could be shortened. A formula whose sign
    condition is dropped admits e.g. L+ R- S- L+ (a cusp after the straight).
    """
    for p in reeds_shepp_paths(*poses, r):
        assert p.gear_changes <= 2
        segs = p.segments
        for i, seg in enumerate(segs):
            if seg.kind == "S":
                for j in (i - 1, i + 1):
                    if 0 <= j < len(segs):
                        assert segs[j].gear == seg.gear, (p.word, p.lengths)


@settings(max_examples=60, deadline=None)
@given(near_pairs(), radius, st.floats(0.05, 2.0))
def test_rs_rows_within_a_gear_are_distinct(poses: tuple[Pose, Pose], r: float, ds: float) -> None:
    """Only a cusp repeats a position: a junction in one gear is one row.

    A repeated row would be a zero-length step with a curvature jump (an infinite
    steering rate for anything that differentiates the samples).
    """
    for path in reeds_shepp_paths(*poses, r, limit=3):
        rows = path.sample(ds)
        gap = np.hypot(*np.diff(rows[:, :2], axis=0).T)
        same_gear = rows[1:, 4] == rows[:-1, 4]
        assert np.all(gap[same_gear] > 0.0), (path.word, path.lengths)


def test_rs_table_grid_covers_the_requested_extent() -> None:
    """0.3 / 0.1 is 2.9999999999999996 in floats: the grid still reaches 0.3 m (4 nodes)."""
    table = ReedsSheppTable.build(1.0, extent=0.3, resolution=0.1, yaw_bins=4)
    assert table.values.shape[:2] == (4, 4)
    assert table.extent == pytest.approx(0.3)


# ----------------------------------------------------------------------------- Dubins


@settings(max_examples=60, deadline=None)
@given(near_pairs(), radius)
def test_dubins_last_sample_and_polygon_end_are_the_goal_exactly(
    poses: tuple[Pose, Pose], r: float
) -> None:
    """``goal`` is set by :func:`dubins_paths`: the last sample and polygon vertex are it."""
    start, goal = poses
    for path in dubins_paths(start, goal, r):
        last = path.sample(0.5)[-1]
        assert last[0] == goal.x and last[1] == goal.y
        assert last[2] == pytest.approx(math.remainder(goal.yaw, 2 * math.pi), abs=1e-15)
        end = path.polygon()[-1]
        assert end[0] == goal.x and end[1] == goal.y


@pytest.mark.parametrize("d", [0.5, 7.0, 30.0])
def test_dubins_straight_ahead_along_x_samples_one_straight(d: float) -> None:
    """A goal straight ahead along +x: the arcs are exactly 0, every row has kappa 0.

    Rows are distinct and at most 0.4 m apart: ``ceil(d / 0.4) + 1`` of them.
    """
    path = dubins_paths(Pose(0.0, 0.0, 0.0), Pose(d, 0.0, 0.0), 5.0)[0]
    assert path.lengths[0] == path.lengths[2] == 0.0
    rows = path.sample(0.4)
    assert np.all(rows[:, 3] == 0.0)
    assert len(rows) == math.ceil(d / 0.4 - 1e-9) + 1
    assert np.hypot(*np.diff(rows[:, :2], axis=0).T).min() > 0.0


def test_dubins_straight_ahead_at_an_angle_samples_one_straight() -> None:
    """Straight ahead at heading 0.7, LSL's last arc is 5.6e-16 m of float noise.

    ``sample`` gave it a row of its own: the end position twice, with kappa 1/r and
    then 0, so the samples' steering rate (``max_sharpness``) was 5.7e14 rad/m.
    """
    start = Pose(1.0, 2.0, 0.7)
    goal = Pose(1.0 + 7.0 * math.cos(0.7), 2.0 + 7.0 * math.sin(0.7), 0.7)
    rows = dubins_paths(start, goal, 5.0)[0].sample(0.4)
    assert np.all(rows[:, 3] == 0.0)
    assert np.hypot(*np.diff(rows[:, :2], axis=0).T).min() > 1e-9


@pytest.mark.parametrize("max_arc", [math.pi, 0.0])
def test_dubins_polygon_refuses_a_half_turn_sub_arc(max_arc: float) -> None:
    """A sub-arc of pi has its tangents' meeting point at infinity: ``max_arc`` < pi."""
    path = dubins_paths(Pose(0.0, 0.0, 0.0), Pose(0.0, 4.0, math.pi), 2.0)[0]
    with pytest.raises(InputError, match="max_arc"):
        path.polygon(max_arc)


def _dubins_with(monkeypatch: pytest.MonkeyPatch, seg: tuple[float, float, float]) -> None:
    """Make every word's formula return ``seg`` (radius 1), to test the end check."""
    monkeypatch.setattr(dubins, "_normalised", lambda word, a, b, d: seg)


def test_dubins_keeps_a_word_within_tol_times_radius_and_drops_one_beyond(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """As documented by Reeds-Shepp and the tests of both: ``tol * max(1, radius)`` metres."""
    r = 5.0  # 5e-6 m of slack for tol = 1e-6
    start, goal = Pose(0.0, 0.0, 0.0), Pose(10.0, 0.0, 0.0)
    _dubins_with(monkeypatch, (0.0, (10.0 + 2.5e-6) / r, 0.0))
    # (0, p, 0) is a straight for the four CSC words (for RLR and LRL an arc of p)
    assert sorted(p.word for p in dubins_paths(start, goal, r)) == ["LSL", "LSR", "RSL", "RSR"]
    _dubins_with(monkeypatch, (0.0, (10.0 + 1e-5) / r, 0.0))
    assert dubins_paths(start, goal, r) == []


def test_dubins_drops_a_word_that_ends_at_the_goal_position_with_another_heading(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A wrong formula cannot return a word that ends at the goal's place facing elsewhere."""
    _dubins_with(monkeypatch, (0.0, 2.0, 0.0))  # reaches (10, 0) at radius 5, heading 0
    assert dubins_paths(Pose(0.0, 0.0, 0.0), Pose(10.0, 0.0, 0.3), 5.0) == []


# ----------------------------------------------------------------------------- clothoids


@pytest.mark.parametrize("theta", [5e-4, -2e-5, math.pi - 5e-4])
def test_clothoid_turn_of_a_tiny_or_near_reversal_deflection_turns_by_it(theta: float) -> None:
    """The turn deflects by ``theta`` and ends on the outgoing leg (closed-form corner).

    Its end, integrated numerically, lies at ``T (1 + cos theta, sin theta)`` (the
    corner at ``(T, 0)`` plus ``T`` along the outgoing leg) facing ``theta``.
    """
    turn = clothoid_turn(theta, KAPPA, SIGMA)
    assert 0.0 < turn.length and math.isfinite(turn.tangent)
    end = integrate_turn(turn, turn.length)
    t = turn.tangent
    out = np.array([t * (1.0 + math.cos(theta)), t * math.sin(theta)])
    assert end[2] == pytest.approx(theta, abs=1e-7)
    assert np.hypot(*(end[:2] - out)) <= 1e-6 * max(1.0, t)
    assert sample_turn(turn, np.array([turn.length]))[0, 2] == pytest.approx(theta, abs=1e-12)


def test_polygon_curve_rounds_a_tiny_corner_without_a_kink() -> None:
    """A 5e-4 rad corner is still turned: the heading is continuous and ends on the last leg."""
    theta = 5e-4
    pts = np.array(
        [[0.0, 0.0], [30.0, 0.0], [30.0 + 30.0 * math.cos(theta), 30.0 * math.sin(theta)]]
    )
    pieces = polygon_curve(pts, KAPPA, SIGMA)
    assert pieces is not None
    rows, _ = sample_pieces(pieces, 0.01)  # the turn is 0.16 m long
    assert rows[-1, 2] == pytest.approx(theta, abs=1e-12)
    gaps = np.hypot(*np.diff(rows[:, :2], axis=0).T)
    # |d yaw| <= kappa ds between rows (the peak curvature is sqrt(theta sigma) here)
    assert np.all(np.abs(np.diff(rows[:, 2])) <= math.sqrt(theta * SIGMA) * gaps + 1e-12)
    # and the heading is turned by curvature: the integral of kappa ds is theta
    # (trapezoids over a piecewise-linear kappa; the peak may fall between rows)
    turned = float(np.sum(0.5 * (rows[1:, 3] + rows[:-1, 3]) * gaps))
    assert turned == pytest.approx(theta, rel=0.05)


def test_polygon_curve_of_a_repeated_corner_is_none() -> None:
    """A repeated point has no direction to turn from: no curve (rather than a kink)."""
    pts = np.array([[0.0, 0.0], [20.0, 0.0], [20.0, 0.0], [20.0, 20.0]])
    assert polygon_curve(pts, KAPPA, SIGMA) is None


def test_polygon_curve_keeps_the_end_gap_on_the_first_and_last_leg_only_beside_a_turn() -> None:
    """``end_gap`` is added to a first or last leg whose inner end has a turn, nowhere else."""
    tangent = clothoid_turn(math.pi / 2, KAPPA, SIGMA).tangent
    gap = 0.5

    def l_shape(first: float, last: float) -> np.ndarray:
        return np.array([[-first, 0.0], [0.0, 0.0], [0.0, last]])

    roomy = tangent + 1.1 * gap  # each end leg: the turn's tangent plus the gap
    tight = tangent + 0.9 * gap
    assert polygon_curve(l_shape(roomy, roomy), KAPPA, SIGMA, end_gap=gap) is not None
    assert polygon_curve(l_shape(tight, roomy), KAPPA, SIGMA, end_gap=gap) is None
    assert polygon_curve(l_shape(roomy, tight), KAPPA, SIGMA, end_gap=gap) is None
    # A straight first corner has no turn: the 0.1 m first leg needs no gap.
    pts = np.array([[-0.1, 0.0], [0.0, 0.0], [30.0, 0.0], [30.0, 30.0]])
    assert polygon_curve(pts, KAPPA, SIGMA, end_gap=gap) is not None


# ----------------------------------------------------------------------------- make_drivable


def test_curvature_where_the_speed_vanishes_is_infinite() -> None:
    """A zero first derivative is a cusp: ``inf`` (not drivable), never NaN.

    The curvature checks compare ``|kappa| > kappa_max``, which NaN would pass.
    """
    k = curvature(np.array([[0.0, 0.0], [2.0, 0.0]]), np.array([[0.0, 0.0], [0.0, 4.0]]))
    assert k[0] == math.inf
    assert k[1] == pytest.approx(1.0)  # x' y'' / |r'|^3 = 2 * 4 / 2^3


def _steer_rate(samples: np.ndarray, wheelbase: float) -> float:
    """Largest ``|d delta / ds|`` between rows, ``delta = atan(L kappa)``, by finite differences."""
    delta = np.arctan(wheelbase * samples[:, 3])
    ds = np.hypot(*np.diff(samples[:, :2], axis=0).T)
    return float(np.max(np.abs(np.diff(delta)) / ds))


def test_make_drivable_reports_the_sharpness_its_samples_show() -> None:
    """``max_sharpness`` is ``|d delta / ds|`` in rad/m (wheelbase times sigma), not sigma."""
    m = builtin_map("parking_lot")
    g = m.goal
    raw = np.array([[5.0, 6.0], [11.5, 6.0], [11.5, 81.0], [60.0, 81.0], [g.x, 81.0], [g.x, g.y]])
    res = make_drivable(raw, m.start, g, cached_checker(m))
    assert res.ok
    measured = _steer_rate(res.samples, m.vehicle.wheelbase)
    # Finite differences of a clothoid's delta are at most its peak rate, and close to it.
    assert 0.9 * res.max_sharpness <= measured <= res.max_sharpness + 1e-9


@pytest.mark.parametrize("degree", [2, 3])
def test_the_bspline_pipeline_keeps_its_guarantees(degree: int) -> None:
    """``curve=BSPLINE`` (the paper's pipeline): ends, curvature bound and a free body.

    ``SmoothingConfig(degree=3)`` alone keeps the default clothoid curve; the B-spline
    pipeline is only run with ``curve=CurveKind.BSPLINE``. References: Menger
    curvature of the samples, shapely bodies at poses at most 0.1 m apart.
    """
    m = builtin_map("parking_lot")
    g = m.goal
    checker = cached_checker(m)
    raw = np.array([[5.0, 6.0], [11.5, 6.0], [11.5, 81.0], [60.0, 81.0], [g.x, 81.0], [g.x, g.y]])
    cfg = SmoothingConfig(curve=CurveKind.BSPLINE, degree=degree)
    res = make_drivable(raw, m.start, g, checker, cfg)
    assert res.ok
    s = res.samples
    assert np.array_equal(s[0, :2], [m.start.x, m.start.y])
    assert np.array_equal(s[-1, :2], [g.x, g.y])
    assert res.max_curvature <= cfg.kappa_max
    assert np.abs(menger(s[:, :2])).max() <= cfg.kappa_max * 1.01
    assert np.abs(s[:, 3]).max() <= cfg.kappa_max + 1e-9
    bodies = shapely.polygons(footprint_corners(densify(s), checker.vehicle))
    union = shapely.union_all([o.polygon() for o in checker.obstacles])
    assert not shapely.intersects(union, bodies).any()


@pytest.mark.parametrize("radius", [0.0, 12.0])
def test_clothoid_turn_reach_uses_the_corners_radius(radius: float) -> None:
    """A corner's reach is the tangent of the turn of its radius (0: the design radius).

    For a deflection ``theta >= kappa^2 / sigma`` the tangent is Fraichard & Scheuer's
    ``r_in tan(theta / 2) + d`` (inner circle ``(r_in, d)`` of ``turn_circle``).
    """
    cfg = SmoothingConfig()
    r = radius if radius > 0.0 else cfg.design_radius
    r_in, d = turn_circle(1.0 / r, cfg.tightest_sigma)
    want = r_in * math.tan(math.pi / 4) + d
    corner, u_in, u_out = np.array([3.0, 4.0]), (1.0, 0.0), (0.0, 1.0)
    assert turn_reach(cfg, corner, u_in, u_out, radius) == pytest.approx(want, rel=1e-9)
    memo: dict[tuple[float, float], float] = {}
    for _ in range(2):  # computed, then remembered
        assert turn_reach(cfg, corner, u_in, u_out, radius, memo) == pytest.approx(want, rel=1e-9)


def test_two_gentle_corners_on_one_leg_share_it_fairly() -> None:
    """Each of two flexible corners on a shared leg gets at least half of it.

    The options are brute-forced independently: the tightest turn and every
    sharpness level at the corner's radius; a corner may take any that fits half
    the shared leg, so neither ends with less than the gentlest of those.
    """
    levels = sharpness_levels(0.2, 0.02, 2.51, 0.97)
    leg = 20.0
    pts = [[0.0, -40.0], [0.0, 0.0], [leg, 0.0], [leg, -40.0]]
    turns, conflicts = polygon_turns(pts, [KAPPA] * 4, levels, [False] * 4, 0.05)
    assert conflicts == []
    first, second = turns[1], turns[2]
    assert first is not None and second is not None
    assert first.tangent + second.tangent <= leg + 1e-9
    options = [clothoid_turn(-math.pi / 2, KAPPA, float(s)).tangent for s in levels]
    half = max(t for t in options if t <= 0.5 * leg)
    assert min(first.tangent, second.tangent) >= half - 1e-9


def test_clothoid_collision_check_tests_the_goal_pose() -> None:
    """A body that touches an obstacle only at the goal pose is found (and its corner named).

    The obstacle overlaps the car's front by 3 cm at the goal and is 7 cm clear of
    it 0.1 m earlier along the last straight leg.
    """
    start, goal = Pose(10.0, 10.0, 0.0), Pose(50.0, 50.0, math.pi / 2)
    probe = Map("probe", (0.0, 0.0, 100.0, 100.0), (), start, goal)
    front = float(footprint_corners(np.array(goal.as_tuple()), probe.vehicle)[..., 1].max())
    block = Obstacle((50.0, front - 0.03 + 0.5), (2.0, 1.0))
    # (the map's own goal is elsewhere: a map checks that its goal is free)
    m = Map("probe", (0.0, 0.0, 100.0, 100.0), (block,), start, Pose(50.0, 40.0, math.pi / 2))
    checker = CollisionChecker.for_map(m)
    assert not checker.pose_free(goal.as_tuple())
    assert checker.pose_free((50.0, 49.9, math.pi / 2))
    corners = [
        Corner.at(np.array(p), kind, i)
        for i, (p, kind) in enumerate(
            [((10.0, 10.0), CornerKind.START), ((50.0, 10.0), CornerKind.NODE),
             ((50.0, 50.0), CornerKind.GOAL)]
        )
    ]  # fmt: skip
    fitter = ClothoidFitter(SmoothingConfig(), CheckerView(checker), Ends.of(start, goal))
    curve, conflicts = fitter.build(corners)
    assert curve is not None and conflicts == []
    bad, dense = fitter.check_collision(curve, len(corners))
    assert bad == [1]
    assert np.array_equal(dense[-1, :2], [50.0, 50.0])


# ----------------------------------------------------------------------------- edges


class _Recorder:
    """A checker whose exact batch test records the poses and finds them all free."""

    def __init__(self) -> None:
        self.poses: list[np.ndarray] = []

    def poses_free(self, poses: np.ndarray, clearance: float = 0.0) -> np.ndarray:
        self.poses.append(np.array(poses))
        return np.ones(len(poses), dtype=bool)


@pytest.mark.parametrize("length", [1.05, 0.35, 2.0])
def test_exact_edge_test_covers_the_edge_at_the_spacing(length: float) -> None:
    """Poses tested (both passes together) run from ``a`` to ``b`` at most 0.1 m apart.

    Every pose faces along the edge; a 1.05 m edge needs ``ceil(10.5) + 1 = 12`` poses.
    """
    yaw = 0.4
    a = np.array([2.0, -1.0])
    b = a + length * np.array([math.cos(yaw), math.sin(yaw)])
    rec = _Recorder()
    assert exact_edge_free(rec, a, b)  # type: ignore[arg-type]
    poses = np.vstack(rec.poses)
    assert len(poses) == math.ceil(length / 0.1 - 1e-9) + 1
    along = np.sort((poses[:, :2] - a) @ np.array([math.cos(yaw), math.sin(yaw)]))
    assert along[0] == pytest.approx(0.0, abs=1e-12)
    assert along[-1] == pytest.approx(length, abs=1e-12)
    assert np.diff(along).max() <= 0.1 + 1e-12
    assert np.allclose(poses[:, 2], yaw, atol=1e-12)


def test_exact_edge_test_of_a_half_millimetre_edge_in_the_open() -> None:
    """A 0.5 mm edge whose body is free at both ends is free (only a point has no heading)."""
    rec = _Recorder()
    a = np.array([2.0, -1.0])
    assert exact_edge_free(rec, a, a + np.array([5e-4, 0.0]))  # type: ignore[arg-type]
    assert not exact_edge_free(rec, a, a.copy())  # type: ignore[arg-type]
