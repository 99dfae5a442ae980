"""Post-processing steps against independent references (paper Sec. 3.2, SPEC §3 items 5-9)."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely
from hypothesis import example, given
from hypothesis import strategies as st
from test_improved import densify

from rrtdrive.collision import CollisionChecker
from rrtdrive.maps import Map, Obstacle, builtin_map
from rrtdrive.planning.base import cached_checker
from rrtdrive.planning.smoothing import (
    CurveKind,
    SmoothingConfig,
    clamped_uniform_knots,
    curvature,
    fillet_points,
    fit_bspline,
    is_sharp,
    make_drivable,
    parameter_grid,
    prune,
    quadratic_span_max_curvature,
    repair_sharp_angles,
    sample_spline,
    sharp_flags,
    spline_curvature,
    supplement,
)
from rrtdrive.types import InputError, Pose
from rrtdrive.vehicle import footprint_corners

KAPPA = 1.0 / 6.0


class Open:
    """Every edge is free."""

    def __init__(self) -> None:
        self.calls: list[tuple[tuple[float, ...], tuple[float, ...]]] = []

    def edge_free(self, a, b) -> bool:
        self.calls.append((tuple(a), tuple(b)))
        return True


class Blocked:
    """Edges listed as (a, b) point pairs are blocked; the rest are free."""

    def __init__(self, blocked: list[tuple[tuple[float, float], tuple[float, float]]]) -> None:
        self.blocked = {(tuple(map(float, a)), tuple(map(float, b))) for a, b in blocked}

    def edge_free(self, a, b) -> bool:
        return (tuple(map(float, a)), tuple(map(float, b))) not in self.blocked


class NoScreen:
    """A real checker's edge test without the obstacle screen (hides ``obstacles``)."""

    def __init__(self, checker: CollisionChecker) -> None:
        self.edge_free = checker.edge_free


def polyline_length(p: np.ndarray) -> float:
    return float(np.hypot(*np.diff(p, axis=0).T).sum())


def menger(points: np.ndarray) -> np.ndarray:
    """Curvature of the circle through each three consecutive points (independent reference)."""
    a, b, c = points[:-2], points[1:-1], points[2:]
    ab, bc, ca = b - a, c - b, a - c
    cross = ab[:, 0] * bc[:, 1] - ab[:, 1] * bc[:, 0]
    den = np.hypot(*ab.T) * np.hypot(*bc.T) * np.hypot(*ca.T)
    return 2.0 * cross / den


def random_free_walk(checker: CollisionChecker, rng: np.random.Generator, n: int) -> np.ndarray:
    """A polyline of ``n`` nodes whose every edge is free, wandering through the map."""
    while True:
        start = rng.uniform(5, 95, 2)
        if checker.point_free(*start) and checker.clearance(*start) > 3.0:
            break
    pts = [start]
    while len(pts) < n:
        step = rng.uniform(2.0, 6.0)
        ang = rng.uniform(-math.pi, math.pi)
        q = pts[-1] + step * np.array([math.cos(ang), math.sin(ang)])
        if checker.edge_free(pts[-1], q):
            pts.append(q)
    return np.array(pts)


# ----------------------------------------------------------------------------- prune


@pytest.mark.parametrize("seed", range(8))
def test_prune_keeps_ends_frees_every_edge_shortens_and_is_farthest(parking_checker, seed):
    rng = np.random.default_rng(seed)
    raw = random_free_walk(parking_checker, rng, 25)
    idx = prune(raw, parking_checker)
    assert idx is not None
    assert idx[0] == 0 and idx[-1] == len(raw) - 1
    assert np.all(np.diff(idx) > 0)
    for i, j in zip(idx[:-1], idx[1:], strict=True):
        assert parking_checker.edge_free(raw[i], raw[j])
        # Farthest: no later node is reachable from i by a free edge.
        assert not any(parking_checker.edge_free(raw[i], raw[k]) for k in range(j + 1, len(raw)))
    assert polyline_length(raw[idx]) <= polyline_length(raw) + 1e-9
    # The centre-line screen changes nothing.
    assert np.array_equal(prune(raw, NoScreen(parking_checker)), idx)


def test_prune_keeps_required_points_and_reports_a_dead_end():
    pts = np.array([[0.0, 0.0], [1.0, 1.0], [2.0, 0.0], [3.0, 1.0], [4.0, 0.0]])
    assert prune(pts, Open()).tolist() == [0, 4]
    assert prune(pts, Open(), keep=(2,)).tolist() == [0, 2, 4]
    blocked = Blocked([(pts[1], pts[k]) for k in range(2, 5)])
    assert prune(pts, blocked, keep=(1,)) is None


def test_prune_tries_the_farthest_node_first():
    pts = np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [3.0, 0.0]])
    blocked = Blocked([(pts[0], pts[3])])
    assert prune(pts, blocked).tolist() == [0, 2, 3]


# ----------------------------------------------------------------------------- sharp angles

finite = st.floats(-50.0, 50.0, allow_nan=False)
points = st.tuples(finite, finite)


@given(p=points, q=points, r=points)
def test_is_sharp_means_an_angle_of_at_most_90_degrees(p, q, r):
    u = np.subtract(p, q)
    v = np.subtract(r, q)
    nu, nv = np.linalg.norm(u), np.linalg.norm(v)
    if nu < 1e-3 or nv < 1e-3:
        return
    angle = math.degrees(math.acos(np.clip(u @ v / (nu * nv), -1.0, 1.0)))
    if abs(angle - 90.0) < 1e-3:
        return
    assert is_sharp(p, q, r) == (angle < 90.0)


def test_sharp_flags_agree_with_is_sharp():
    rng = np.random.default_rng(3)
    pts = rng.uniform(0, 20, (40, 2))
    flags = sharp_flags(pts)
    assert not flags[0] and not flags[-1]
    assert flags[1:-1].tolist() == [is_sharp(pts[i - 1], pts[i], pts[i + 1]) for i in range(1, 39)]


def angle_deg(a, b, c) -> float:
    u, v = np.subtract(a, b), np.subtract(c, b)
    return math.degrees(math.acos(np.clip(u @ v / (np.linalg.norm(u) * np.linalg.norm(v)), -1, 1)))


def seg_dist(p, a, b) -> float:
    shp = shapely.LineString([a, b])
    return shp.distance(shapely.Point(p))


def reference_sharp_repair(raw, key, free):
    """SPEC item 6 written out with angles and shapely distances."""
    idx = list(key)
    i = 1
    while i < len(idx) - 1:
        a, b, c = raw[idx[i - 1]], raw[idx[i]], raw[idx[i + 1]]
        if angle_deg(a, b, c) > 90.0:
            i += 1
            continue
        done = False
        first = sorted(range(idx[i - 1] + 1, idx[i]), key=lambda t: -seg_dist(raw[t], a, b))
        for t in first:
            q = raw[t]
            if angle_deg(a, q, b) > 90 and angle_deg(q, b, c) > 90 and free(a, q) and free(q, b):
                idx.insert(i, t)
                i += 1
                done = True
                break
        if not done:
            second = sorted(range(idx[i] + 1, idx[i + 1]), key=lambda t: -seg_dist(raw[t], b, c))
            for t in second:
                q = raw[t]
                if (
                    angle_deg(a, b, q) > 90
                    and angle_deg(b, q, c) > 90
                    and free(b, q)
                    and free(q, c)
                ):
                    idx.insert(i + 1, t)
                    i += 1
                    break
        i += 1
    return idx


@pytest.mark.parametrize("seed", range(40))
def test_sharp_repair_matches_a_reference_implementation(seed):
    rng = np.random.default_rng(seed)
    raw = np.cumsum(rng.uniform(-5, 5, (14, 2)), axis=0)
    key = np.sort(rng.choice(np.arange(1, 13), size=4, replace=False))
    key = np.concatenate([[0], key, [13]])
    # Block a random third of all edges.
    blocked = {(i, j) for i in range(14) for j in range(14) if rng.random() < 0.33}
    table = {(tuple(raw[i]), tuple(raw[j])) for i, j in blocked}

    class Some:
        def edge_free(self, a, b):
            return (tuple(map(float, a)), tuple(map(float, b))) not in table

    free = Some().edge_free
    got = repair_sharp_angles(raw, key, Some()).tolist()
    assert got == reference_sharp_repair(raw, key.tolist(), free)


def test_sharp_repair_order_first_side_farthest_then_next_then_other_side():
    raw = np.array([[0, 0], [2, 0], [4, 0.5], [5, 2], [4.5, 4.5], [0, 4]], dtype=float)
    key = np.array([0, 3, 5])
    # raw 1 and raw 2 (first side) both leave the angle at q1 acute; raw 4 fits.
    assert repair_sharp_angles(raw, key, Open()).tolist() == [0, 3, 4, 5]
    # Give the first side a fitting node: raw 2 moved so that both angles are obtuse.
    raw2 = raw.copy()
    raw2[2] = [4.0, -1.2]
    q0, q1, q2 = raw2[0], raw2[3], raw2[5]
    assert not is_sharp(q0, raw2[2], q1) and not is_sharp(raw2[2], q1, q2)
    assert repair_sharp_angles(raw2, key, Open()).tolist() == [0, 2, 3, 5]
    # Block its edge: the next farthest of the first side (raw 1) does not fit, so the
    # other side's raw 4 is taken.
    blocked = Blocked([(q0, raw2[2])])
    assert repair_sharp_angles(raw2, key, blocked).tolist() == [0, 3, 4, 5]


def test_sharp_repair_keeps_the_point_when_nothing_fits():
    raw = np.array([[0, 0], [5, 0], [0, 3]], dtype=float)
    assert repair_sharp_angles(raw, np.array([0, 1, 2]), Open()).tolist() == [0, 1, 2]


@pytest.mark.parametrize("seed", range(5))
def test_sharp_repair_only_inserts_raw_nodes_with_free_edges(parking_checker, seed):
    rng = np.random.default_rng(seed)
    raw = random_free_walk(parking_checker, rng, 30)
    key = prune(raw, parking_checker)
    out = repair_sharp_angles(raw, key, parking_checker)
    assert set(key.tolist()) <= set(out.tolist())
    assert np.all(np.diff(out) > 0)
    for i, j in zip(out[:-1], out[1:], strict=True):
        assert parking_checker.edge_free(raw[i], raw[j])


# ----------------------------------------------------------------------------- supplement


def test_supplement_inserts_midpoints_exactly_on_long_legs():
    pts = np.array([[0.0, 0.0], [5.0, 0.0], [5.0, 5.66], [5.0, 20.0]])
    out = supplement(pts, delta=5.66, n=0.5)
    # 5 m < delta: untouched; 5.66 m = delta: one midpoint (>=); 14.34 m: one midpoint.
    want = [[0, 0], [5, 0], [5, 2.83], [5, 5.66], [5, 12.83], [5, 20]]
    np.testing.assert_allclose(out, want, atol=1e-12)


def test_supplement_with_smaller_multiple_inserts_several_points():
    out = supplement(np.array([[0.0, 0.0], [8.0, 0.0]]), delta=5.66, n=0.25)
    np.testing.assert_allclose(out[:, 0], [0, 2, 4, 6, 8])
    assert len(supplement(np.array([[0.0, 0.0], [3.0, 4.0]]))) == 2


# ----------------------------------------------------------------------------- B-spline


def test_knot_vector_follows_eq_15():
    n_ctrl, k = 7, 2  # n = 6
    t = clamped_uniform_knots(n_ctrl, k)
    n = n_ctrl - 1
    assert len(t) == n + k + 2
    assert np.all(t[: k + 1] == 0) and np.all(t[-(k + 1) :] == 1)
    np.testing.assert_allclose(np.diff(t[k : n + 2]), 1.0 / (n - k + 1))
    with pytest.raises(ValueError):
        clamped_uniform_knots(3, 3)


polygons = st.integers(4, 12).flatmap(
    lambda m: st.lists(st.tuples(finite, finite), min_size=m, max_size=m)
)


@given(ctrl=polygons, degree=st.sampled_from([2, 3]))
def test_bspline_is_clamped_with_end_tangents_along_the_end_legs(ctrl, degree):
    c = np.array(ctrl)
    legs = np.hypot(*np.diff(c, axis=0).T)
    if legs[0] < 1e-3 or legs[-1] < 1e-3:
        return
    spl = fit_bspline(c, degree)
    np.testing.assert_allclose(spl(0.0), c[0], atol=1e-9)
    np.testing.assert_allclose(spl(1.0), c[-1], atol=1e-9)
    d0, d1 = spl(0.0, nu=1), spl(1.0, nu=1)
    first, last = c[1] - c[0], c[-1] - c[-2]
    assert abs(d0[0] * first[1] - d0[1] * first[0]) <= 1e-9 * np.linalg.norm(d0) * legs[0] + 1e-12
    assert d0 @ first > 0 and d1 @ last > 0
    assert abs(d1[0] * last[1] - d1[1] * last[0]) <= 1e-9 * np.linalg.norm(d1) * legs[-1] + 1e-12


def test_curvature_of_a_circle():
    for radius in (0.5, 6.0, 40.0):
        t = np.linspace(0, 2 * np.pi, 17)
        d1 = radius * np.column_stack([-np.sin(t), np.cos(t)])
        d2 = radius * np.column_stack([-np.cos(t), -np.sin(t)])
        np.testing.assert_allclose(curvature(d1, d2), 1.0 / radius)
        # Clockwise: negative.
        np.testing.assert_allclose(curvature(d1 * [1, -1], d2 * [1, -1]), -1.0 / radius)


def test_spline_curvature_of_a_circle_like_spline():
    # A degree-3 spline through a fine regular polygon circumscribing a circle of radius 10.
    ang = np.linspace(0, 2 * np.pi, 200)
    ctrl = 10.0 * np.column_stack([np.cos(ang), np.sin(ang)])
    spl = fit_bspline(ctrl, 3)
    k = spline_curvature(spl, np.linspace(0.2, 0.8, 50))
    np.testing.assert_allclose(k, 0.1, rtol=2e-3)


@pytest.mark.parametrize("degree", [2, 3])
def test_spline_curvature_matches_finite_differences(degree):
    rng = np.random.default_rng(degree)
    ctrl = np.cumsum(rng.uniform(2.0, 6.0, (9, 2)) * [1, 1] * rng.choice([-1, 1], (9, 2)), axis=0)
    spl = fit_bspline(ctrl, degree)
    u = np.linspace(0.05, 0.95, 400)
    h = 1e-5
    for ui in u[::20]:
        p = spl(np.array([ui - h, ui, ui + h]))
        ref = menger(p)[0]
        if abs(ref) < 1e3:
            assert spline_curvature(spl, np.array([ui]))[0] == pytest.approx(
                ref, rel=1e-3, abs=1e-6
            )


@given(ctrl=polygons)
@example(ctrl=[(0.0, 0.0), (0.0, 0.5), (0.25, 34.0), (0.0, 1.0)])  # found by CI, a near-cusp
@example(ctrl=[(0.0, 0.0), (1.8857981996553033e-11, 7.48046875), (0.0, 2.0), (0.0, 0.0)])
@example(ctrl=[(0.0, 0.0), (0.0, 1.0), (3.0, 0.5), (1e-09, 1.0)])
def test_quadratic_span_maximum_matches_dense_sampling(ctrl):
    c = np.array(ctrl)
    if np.hypot(*np.diff(c, axis=0).T).min() < 0.5:
        return
    spl = fit_bspline(c, 2)
    exact = quadratic_span_max_curvature(c)
    n_span = len(c) - 2
    for j in range(n_span):
        # Strictly inside the span: the curvature of a degree-2 spline jumps at knots.
        u = np.linspace(j / n_span + 1e-12, (j + 1) / n_span - 1e-12, 2001)
        if exact[j] == np.inf:
            # A cusp: the speed vanishes inside the span.
            speed = np.hypot(*spl(u, nu=1).T)
            assert speed.min() <= 1e-2 * speed.max()
            continue
        k = np.abs(spline_curvature(spl, u))
        dense, i = float(k.max()), int(k.argmax())
        # Zoom in on the sampled peak (sharp peaks fall between samples): a near-cusp's
        # peak of 1.6e7 1/m is 1.2e-4 short after one round, 4 rounds find it.
        lo, hi = u[max(i - 1, 0)], u[min(i + 1, len(u) - 1)]
        for _ in range(4):
            fine = np.linspace(lo, hi, 2001)
            kf = np.abs(spline_curvature(spl, fine))
            dense, m = max(dense, float(kf.max())), int(kf.argmax())
            lo, hi = fine[max(m - 1, 0)], fine[min(m + 1, len(fine) - 1)]
        # Beyond 1e6 1/m (a micron's radius: a cusp in all but name) the curvature's own
        # floats are ill-conditioned: 1.5e-7 apart at a peak of 1.5e24, 1.2e-6 at 7.6e20
        # (the stress profile).
        above, below = (1e-9, 1e-4) if exact[j] < 1e6 else (1e-3, 1e-3)
        assert dense <= exact[j] * (1 + above) + 1e-12
        assert dense >= exact[j] * (1 - below)


@given(ctrl=polygons, degree=st.sampled_from([2, 3]), spacing=st.sampled_from([0.1, 0.25, 1.0]))
def test_parameter_grid_bounds_the_arc_length_between_samples(ctrl, degree, spacing):
    c = np.array(ctrl)
    if np.hypot(*np.diff(c, axis=0).T).min() < 1e-3:
        return
    spl = fit_bspline(c, degree)
    u = parameter_grid(spl, spacing)
    assert u[0] == 0.0 and u[-1] == 1.0 and np.all(np.diff(u) >= 0)
    for i in range(0, len(u) - 1, max(1, len(u) // 40)):
        fine = spl(np.linspace(u[i], u[i + 1], 64))
        assert polyline_length(fine) <= spacing * (1 + 1e-6)


def test_sample_spline_rows_are_position_heading_curvature():
    spl = fit_bspline(np.array([[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [20.0, 10.0]]), 2)
    rows, u = sample_spline(spl, 0.25)
    np.testing.assert_allclose(rows[:, :2], spl(u))
    d = spl(u, nu=1)
    np.testing.assert_allclose(rows[:, 2], np.arctan2(d[:, 1], d[:, 0]))
    np.testing.assert_allclose(rows[:, 3], spline_curvature(spl, u))


# ----------------------------------------------------------------------------- fillets


@given(
    turn=st.floats(0.05, 2.8),
    left=st.booleans(),
    radius=st.floats(3.0, 20.0),
    heading=st.floats(-math.pi, math.pi),
    max_deg=st.sampled_from([10.0, 15.0, 30.0]),
)
def test_fillet_bounds_the_quadratic_spline_curvature(turn, left, radius, heading, max_deg):
    u_in = np.array([math.cos(heading), math.sin(heading)])
    out_heading = heading + (turn if left else -turn)
    u_out = np.array([math.cos(out_heading), math.sin(out_heading)])
    corner = np.array([3.0, -2.0])
    f = fillet_points(corner, u_in, u_out, radius, math.radians(max_deg))
    m = len(f.vertices)
    phi = turn / m
    assert phi <= math.radians(max_deg) + 1e-9
    assert f.tangent == pytest.approx(radius * math.tan(turn / 2))
    far = f.reach + 10.0
    ctrl = np.vstack(
        [corner - far * u_in, corner - f.reach * u_in, f.vertices, corner + f.reach * u_out,
         corner + far * u_out]
    )  # fmt: skip
    k = quadratic_span_max_curvature(ctrl)
    bound = 1.0 / (radius * math.cos(phi / 2))
    assert k.max() <= bound * (1 + 1e-9)
    assert k.max() >= bound * (1 - 1e-9)
    # The curve follows the legs up to the tangent points: straight spans before and after.
    assert k[0] == pytest.approx(0.0, abs=1e-9) and k[-1] == pytest.approx(0.0, abs=1e-9)
    spl = fit_bspline(ctrl, 2)
    rows, _ = sample_spline(spl, 0.05)
    xy = rows[:, :2] - corner
    # It leaves the incoming line only at the tangent point, and joins the outgoing
    # line at the other tangent point.
    off_in = np.abs(xy @ np.array([-u_in[1], u_in[0]])) > 1e-7
    first_off = int(np.argmax(off_in))
    assert xy[first_off] @ u_in >= -f.tangent - 0.05
    off_out = np.abs(xy @ np.array([-u_out[1], u_out[0]])) > 1e-7
    last_off = len(xy) - 1 - int(np.argmax(off_out[::-1]))
    assert xy[last_off] @ u_out <= f.tangent + 0.05


def test_fillet_of_a_straight_corner_and_a_reversal():
    f = fillet_points((1.0, 1.0), (1.0, 0.0), (1.0, 0.0), 6.0)
    assert len(f.vertices) == 1 and f.reach == 0.0
    assert fillet_points((1.0, 1.0), (1.0, 0.0), (-1.0, 0.0), 6.0).tangent == math.inf


# ----------------------------------------------------------------------------- make_drivable


def check_guarantees(res, start: Pose, goal: Pose, checker: CollisionChecker) -> None:
    s = res.samples
    assert res.ok and len(s) >= 2
    assert np.array_equal(s[0, :2], [start.x, start.y])
    assert np.array_equal(s[-1, :2], [goal.x, goal.y])
    assert np.hypot(*np.diff(s[:, :2], axis=0).T).max() <= 0.25 + 1e-9
    chord0 = math.atan2(*(s[1, 1::-1] - s[0, 1::-1]))
    chord1 = math.atan2(*(s[-1, 1::-1] - s[-2, 1::-1]))
    assert abs((chord0 - start.yaw + math.pi) % (2 * math.pi) - math.pi) < math.radians(3)
    assert abs((chord1 - goal.yaw + math.pi) % (2 * math.pi) - math.pi) < math.radians(3)
    assert np.abs(menger(s[:, :2])).max() <= KAPPA * 1.01
    assert res.max_curvature <= KAPPA
    # The exact body at poses <= 0.1 m apart, with shapely.
    poses = densify(s)
    bodies = shapely.polygons(footprint_corners(poses, checker.vehicle))
    union = shapely.union_all([o.polygon() for o in checker.obstacles])
    assert not shapely.intersects(union, bodies).any()
    assert shapely.contains(shapely.box(*checker.bounds), bodies).all()


def test_make_drivable_on_an_overtake_path():
    m = builtin_map("overtake")
    checker = cached_checker(m)
    raw = np.array([[5.0, 44.0], [30.0, 44.0], [42.0, 48.0], [60.0, 48.0], [92.0, 44.0]])
    res = make_drivable(raw, m.start, m.goal, checker)
    check_guarantees(res, m.start, m.goal, checker)
    # The first and last control legs lie on the headings.
    c = res.control_points
    assert abs(c[1, 1] - c[0, 1]) < 1e-9 and c[1, 0] > c[0, 0]
    assert abs(c[-1, 1] - c[-2, 1]) < 1e-9 and c[-1, 0] > c[-2, 0]


def test_make_drivable_degree_3():
    m = builtin_map("overtake")
    checker = cached_checker(m)
    raw = np.array([[5.0, 44.0], [30.0, 44.0], [42.0, 48.0], [60.0, 48.0], [92.0, 44.0]])
    # The degree is the B-spline's: the default curve (clothoid) has none.
    res = make_drivable(
        raw, m.start, m.goal, checker, SmoothingConfig(degree=3, curve=CurveKind.BSPLINE)
    )
    assert res.ok and np.isnan(res.max_sharpness), res.message  # nan: a B-spline ran
    check_guarantees(res, m.start, m.goal, checker)


def test_make_drivable_turns_into_a_parking_spot(parking_lot, parking_checker):
    # A hand-made path up the left side, along the top aisle and down into the spot.
    g = parking_lot.goal
    raw = np.array([[5.0, 6.0], [11.5, 6.0], [11.5, 81.0], [60.0, 81.0], [g.x, 81.0], [g.x, g.y]])
    assert all(parking_checker.edge_free(a, b) for a, b in zip(raw[:-1], raw[1:], strict=True))
    res = make_drivable(raw, parking_lot.start, g, parking_checker)
    check_guarantees(res, parking_lot.start, g, parking_checker)


def wall_map(start: Pose, goal: Pose) -> Map:
    return Map(
        "wall", (0.0, 0.0, 100.0, 100.0), (Obstacle((48.0, 50.0), (1.0, 20.0)),), start, goal
    )


def test_make_drivable_fails_honestly_when_the_goal_cannot_be_entered_forwards():
    # A wall 0.6 m behind the goal's rear bumper: no forward approach along its heading.
    m = wall_map(Pose(10.0, 10.0, 0.0), Pose(50.0, 50.0, 0.0))
    checker = CollisionChecker.for_map(m)
    raw = np.array([[10.0, 10.0], [50.0, 30.0], [50.0, 50.0]])
    res = make_drivable(raw, m.start, m.goal, checker)
    assert not res.ok and len(res.samples) == 0
    assert "goal heading leg" in res.message


def test_make_drivable_fails_honestly_when_the_start_faces_a_wall():
    m = wall_map(Pose(43.5, 50.0, 0.0), Pose(20.0, 80.0, 0.0))
    checker = CollisionChecker.for_map(m)
    res = make_drivable(np.array([[43.5, 50.0], [20.0, 80.0]]), m.start, m.goal, checker)
    assert not res.ok and "start heading leg" in res.message


def test_smoothing_config_validation_names_the_field():
    with pytest.raises(InputError, match="smoothing.degree"):
        SmoothingConfig(degree=4)
    with pytest.raises(InputError, match="smoothing.supplement_n"):
        SmoothingConfig(supplement_n=1.0)
    with pytest.raises(InputError, match="smoothing.kappa_max"):
        SmoothingConfig(kappa_max=0.0)


def test_repair_constants_are_validated_config_fields_with_the_old_values():
    cfg = SmoothingConfig()
    assert cfg.radius_steps == (1.0, 1.6) and len(cfg.corner_moves) == 18
    assert cfg.corner_moves[0] == ("back", 1.5) and cfg.corner_moves[-1] == ("ahead", 12.0)
    assert cfg.unprune_turn == math.radians(100.0) and cfg.hairpin_turn == math.radians(135.0)
    assert cfg.unprune_hairpin_turn == math.radians(120.0)
    assert cfg.drop_hairpin_turn == math.radians(150.0) and cfg.end_gap == 0.05
    assert SmoothingConfig(curve=CurveKind.BSPLINE).design_radius == pytest.approx(
        1.0 / (KAPPA * 0.97 * math.cos(math.radians(5.0)))
    )
    assert cfg.design_radius == pytest.approx(1.0 / (KAPPA * 0.97))
    for kwargs, name in (
        ({"radius_steps": ()}, "radius_steps"),
        ({"radius_steps": (1.0, -1.0)}, "radius_steps"),
        ({"corner_moves": (("sideways", 1.0),)}, "corner_moves"),
        ({"corner_moves": (("back", 0.0),)}, "corner_moves"),
        ({"hairpin_turn": 4.0}, "hairpin_turn"),
        ({"unprune_turn": 0.0}, "unprune_turn"),
        ({"end_gap": -0.1}, "end_gap"),
    ):
        with pytest.raises(InputError, match=f"smoothing.{name}"):
            SmoothingConfig(**kwargs)


def test_without_corner_moves_a_colliding_corner_fails_honestly_or_is_dropped():
    # No moves: treatments are the fillet radii, then un-pruning or dropping.
    m = builtin_map("overtake")
    checker = cached_checker(m)
    raw = np.array([[5.0, 44.0], [30.0, 44.0], [42.0, 48.0], [60.0, 48.0], [92.0, 44.0]])
    res = make_drivable(raw, m.start, m.goal, checker, SmoothingConfig(corner_moves=()))
    if res.ok:
        check_guarantees(res, m.start, m.goal, checker)
        assert res.stats["moves"] == 0
    else:
        assert res.message.startswith("post-processing failed")


# ----------------------------------------------------------------------------- seams


def test_checker_view_caches_the_obstacle_union_per_checker(parking_lot):
    from rrtdrive.planning.smoothing.checks import CheckerView, EdgeCache, edge_screen

    checker = CollisionChecker.for_map(parking_lot)
    union = CheckerView(checker).obstacle_union()
    assert union is CheckerView(checker).obstacle_union()
    assert union.equals(shapely.union_all([o.polygon() for o in checker.obstacles]))
    edges = EdgeCache(CheckerView(checker))
    assert edge_screen(edges) is not None
    # Without obstacles there is no screen, and prune still works on the edge test alone.
    bare = EdgeCache(CheckerView(NoScreen(checker)))
    assert CheckerView(NoScreen(checker)).obstacle_union() is None
    assert edge_screen(bare) is None and CheckerView(NoScreen(checker)).poses_free() is None
    a, b = [5.0, 6.0], [11.5, 6.0]
    assert bare.edge_free(a, b) == checker.edge_free(a, b)
    assert bare.edge_free(a, b) and bare.checks == 1  # memoised


def test_repairs_report_whether_they_changed_the_polygon():
    from rrtdrive.planning.smoothing.checks import CheckerView, EdgeCache
    from rrtdrive.planning.smoothing.corners import CornerKind, Ends, build_key_polygon
    from rrtdrive.planning.smoothing.repair import Repairer

    ends = Ends.of(Pose(0.0, 0.0, 0.0), Pose(40.0, 20.0, 0.0))
    raw = np.array([[0.0, 0.0], [20.0, 0.0], [20.0, 20.0], [40.0, 20.0]])
    edges = EdgeCache(CheckerView(Open()))
    cfg = SmoothingConfig(prune=False, sharp_repair=False)  # every tree node stays a corner
    poly = build_key_polygon(raw, ends, 5.0, 5.0, edges, cfg, None)
    assert not isinstance(poly, str)
    assert [c.kind for c in poly.corners] == [
        CornerKind.START, CornerKind.START_LEG, CornerKind.NODE, CornerKind.NODE,
        CornerKind.GOAL_LEG, CornerKind.GOAL,
    ]  # fmt: skip
    assert [c.raw_index for c in poly.corners] == list(range(6))
    rep = Repairer(poly, ends, edges, cfg)
    n = len(poly)
    assert not rep.drop(1)  # a heading-leg point is never dropped
    assert rep.advance(2) and poly.corners[2].radius == pytest.approx(cfg.design_radius)
    assert rep.advance(2) and poly.corners[2].radius == pytest.approx(1.6 * cfg.design_radius)
    assert rep.shrink_wide_fillets(1) and poly.corners[2].radius == cfg.design_radius
    assert not rep.shrink_wide_fillets(1)
    assert rep.drop(2) and len(poly) == n - 1 and rep.drops == 1
