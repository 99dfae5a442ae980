"""The checker against shapely, the independent reference."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely
from hypothesis import given
from hypothesis import strategies as st

from rrtdrive.collision import CheckerConfig, CollisionChecker
from rrtdrive.maps import Map, Obstacle, builtin_map
from rrtdrive.planning.base import cached_checker
from rrtdrive.types import Pose, VehicleParams

V = VehicleParams()


def reference_body(x: float, y: float, yaw: float) -> shapely.Polygon:
    """The body rectangle built from first principles (not with rrtdrive.vehicle)."""
    c, s = math.cos(yaw), math.sin(yaw)
    pts = []
    for lx, ly in ((-0.895, -0.9), (3.405, -0.9), (3.405, 0.9), (-0.895, 0.9)):
        pts.append((x + c * lx - s * ly, y + s * lx + c * ly))
    return shapely.Polygon(pts)


_UNIONS: dict[Map, shapely.Geometry] = {}


def reference_free(m: Map, x: float, y: float, yaw: float) -> bool:
    body = reference_body(x, y, yaw)
    if not shapely.box(*m.bounds).contains(body):
        return False
    if m not in _UNIONS:
        _UNIONS[m] = shapely.union_all([shapely.Polygon(o.corners()) for o in m.obstacles])
        shapely.prepare(_UNIONS[m])
    return not _UNIONS[m].intersects(body)


poses = st.tuples(st.floats(0.0, 100.0), st.floats(0.0, 100.0), st.floats(-math.pi, math.pi))


@given(pose=poses)
def test_exact_pose_test_agrees_with_shapely(parking_lot, parking_checker, pose):
    assert parking_checker.pose_free(pose) == reference_free(parking_lot, *pose)


def test_exact_agrees_on_many_poses_near_obstacles(parking_lot, parking_checker):
    rng = np.random.default_rng(1)
    # Poses concentrated around obstacle corners, where the fast screen is inconclusive.
    corners = np.concatenate([o.corners() for o in parking_lot.obstacles])
    pick = corners[rng.integers(0, len(corners), 3000)]
    poses = np.column_stack(
        [pick + rng.normal(0, 2.0, pick.shape), rng.uniform(-math.pi, math.pi, len(pick))]
    )
    got = parking_checker.poses_free(poses)
    want = np.array([reference_free(parking_lot, *p) for p in poses])
    assert (got == want).all()
    # Both outcomes occur, so the comparison means something.
    assert 0.1 < want.mean() < 0.9


@given(pose=poses)
def test_fast_pose_screen_is_conservative(parking_lot, parking_checker, pose):
    if parking_checker.poses_free_fast(np.array([pose]))[0]:
        assert reference_free(parking_lot, *pose)


@given(
    a=st.tuples(st.floats(0.0, 100.0), st.floats(0.0, 100.0)),
    angle=st.floats(-math.pi, math.pi),
    length=st.floats(0.0, 12.0),
)
def test_fast_edge_test_never_calls_a_colliding_edge_free(
    parking_lot, parking_checker, a, angle, length
):
    b = (a[0] + length * math.cos(angle), a[1] + length * math.sin(angle))
    if not parking_checker.edge_free(a, b):
        return
    # Swept body: rectangles at dense poses along the edge, heading along the edge.
    n = max(2, int(length / 0.05) + 1)
    for t in np.linspace(0.0, 1.0, n):
        x, y = a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])
        assert reference_free(parking_lot, x, y, angle)


def test_edge_test_is_not_uselessly_strict(parking_checker):
    # Plenty of room in the bottom aisle: a 20 m edge there is free.
    assert parking_checker.edge_free((5.0, 6.0), (25.0, 6.0))
    # Straight through a parked row is not.
    assert not parking_checker.edge_free((50.0, 6.0), (50.0, 30.0))


def test_edge_test_random_rate_matches_shapely_rate(parking_lot, parking_checker):
    # Conservative but not useless: it frees most edges that the swept shapely body frees.
    rng = np.random.default_rng(3)
    free_fast = free_ref = 0
    for _ in range(300):
        a = rng.uniform(0, 100, 2)
        ang = rng.uniform(-math.pi, math.pi)
        b = a + 5.0 * np.array([math.cos(ang), math.sin(ang)])
        fast = parking_checker.edge_free(a, b)
        ref = all(
            reference_free(parking_lot, *(a + t * (b - a)), ang) for t in np.linspace(0, 1, 51)
        )
        assert not fast or ref
        free_fast += fast
        free_ref += ref
    assert free_fast >= 0.7 * free_ref


@given(p=st.tuples(st.floats(-5.0, 105.0), st.floats(-5.0, 105.0)))
def test_clearance_is_a_lower_bound(parking_lot, parking_checker, p):
    point = shapely.Point(p)
    outside = shapely.box(*parking_lot.bounds).exterior
    if not shapely.box(*parking_lot.bounds).contains(point):
        assert parking_checker.clearance(*p) <= 0.0
        return
    true = min(parking_lot.obstacle_union().distance(point), outside.distance(point))
    if parking_lot.obstacle_union().contains(point):
        true = 0.0
    assert parking_checker.clearance(*p) <= true + 1e-9
    assert parking_checker.clearance(*p) >= true - 0.3  # and tight to within the grid error


@given(
    p=st.tuples(
        st.floats(allow_nan=True, allow_infinity=True),
        st.one_of(st.floats(-5.0, 105.0), st.floats(allow_nan=True, allow_infinity=True)),
    )
)
def test_clearance_of_any_float_point_is_a_number_and_matches_the_batch(parking_checker, p):
    # Far outside (beyond 2**63 cells the cast to int wraps round), infinite or NaN:
    # not clear (-inf off the grid), from the scalar and the batch alike; no exception.
    one = parking_checker.clearance(*p)
    batch = parking_checker.clearances(np.array([p, p[::-1]]))
    assert batch[0] == one and batch[1] == parking_checker.clearance(*p[::-1])
    inside = all(math.isfinite(v) and 0.0 <= v <= 100.0 for v in p)
    assert inside or one <= 0.0
    if not all(math.isfinite(v) and abs(v) < 1e6 for v in p):
        assert one == -math.inf


rect = st.builds(
    lambda cx, cy, lx, ly, yaw: Obstacle((cx, cy), (lx, ly), yaw),
    st.floats(2.0, 28.0),
    st.floats(2.0, 28.0),
    st.floats(0.2, 8.0),
    st.floats(0.2, 8.0),
    st.floats(-math.pi, math.pi),
)


@given(
    obstacles=st.lists(rect, min_size=1, max_size=5),
    pose=st.tuples(st.floats(0.0, 30.0), st.floats(0.0, 30.0), st.floats(-math.pi, math.pi)),
)
def test_random_maps_exact_and_fast_agree_with_shapely(obstacles, pose):
    checker = CollisionChecker((0.0, 0.0, 30.0, 30.0), obstacles, V, CheckerConfig(resolution=0.1))
    ref_map_free = shapely.box(0, 0, 30, 30).contains(reference_body(*pose)) and not any(
        o.polygon().intersects(reference_body(*pose)) for o in obstacles
    )
    assert checker.pose_free(pose) == ref_map_free
    if checker.poses_free_fast(np.array([pose]))[0]:
        assert ref_map_free


def test_path_free_finds_the_colliding_segment(parking_checker):
    samples = np.array([[5.0, 6.0, 0.0], [30.0, 6.0, 0.0], [30.0, 30.0, math.pi / 2]])
    ok, bad = parking_checker.path_free(samples, spacing=0.1)
    assert not ok
    assert list(bad) == [1]
    ok, bad = parking_checker.path_free(samples[:2], spacing=0.1)
    assert ok and len(bad) == 0


@pytest.mark.parametrize(
    "name, disconnected",
    [
        ("no_path", True),
        ("parking_lot", False),
        ("overtake", False),
        ("narrow_gap", False),
    ],
)
def test_connectivity_proof(name, disconnected):
    m = builtin_map(name)
    checker = cached_checker(m)
    assert checker.provably_disconnected(m.start.xy, m.goal.xy) == disconnected


def test_connectivity_proof_is_sound_for_a_gap_the_car_just_fits():
    # A 1.9 m gap: the car (1.8 m) fits, so the grid must not call it closed.
    walls = (Obstacle((15.0, 7.05), (1.0, 14.1)), Obstacle((15.0, 23.95), (1.0, 14.1)))
    m = Map("gap", (0.0, 0.0, 30.0, 31.0), walls, Pose(3.0, 15.5, 0.0), Pose(25.0, 15.5, 0.0))
    assert not CollisionChecker.for_map(m).provably_disconnected(m.start.xy, m.goal.xy)
    # The car driving straight through the gap is free by the exact reference.
    assert all(reference_free(m, x, 15.5, 0.0) for x in np.linspace(3.0, 25.0, 221))


@given(pose=poses, clearance=st.sampled_from([0.0, 0.15, 0.5]))
def test_scalar_fast_pose_test_equals_vectorised(parking_checker, pose, clearance):
    assert parking_checker.pose_free_fast(*pose) == bool(
        parking_checker.poses_free_fast(np.array([pose]))[0]
    )
    assert parking_checker.pose_free_fast(*pose, clearance) == bool(
        parking_checker.poses_free_fast(np.array([pose]), clearance)[0]
    )


@given(pose=poses, clearance=st.sampled_from([0.05, 0.2, 0.5]))
def test_exact_test_with_clearance_agrees_with_shapely_distance(
    parking_lot, parking_checker, pose, clearance
):
    body = reference_body(*pose)
    xmin, ymin, xmax, ymax = parking_lot.bounds
    inner = shapely.box(xmin + clearance, ymin + clearance, xmax - clearance, ymax - clearance)
    union = shapely.union_all([shapely.Polygon(o.corners()) for o in parking_lot.obstacles])
    want = inner.contains(body) and union.distance(body) > clearance
    got = bool(parking_checker.poses_free(np.array([pose]), clearance)[0])
    assert got == want
    # The scalar test (an outside planner's validity checker) gives the same answer.
    assert parking_checker.pose_free(pose, clearance) == want


@given(pose=poses)
def test_body_clearance_matches_shapely(parking_lot, parking_checker, pose):
    body = reference_body(*pose)
    box = shapely.box(*parking_lot.bounds)
    union = shapely.union_all([shapely.Polygon(o.corners()) for o in parking_lot.obstacles])
    if not box.contains(body) or union.intersects(body):
        want = 0.0
    else:
        want = min(box.exterior.distance(body), union.distance(body))
    assert parking_checker.body_clearance(pose) == pytest.approx(want, abs=1e-9)


@given(pose=poses, clearance=st.sampled_from([0.0, 0.15, 0.5]))
def test_exact_tests_disc_screens_are_conservative(parking_lot, parking_checker, pose, clearance):
    # Each screen of poses_free (three, then six discs, no margin) only ever clears
    # poses whose body keeps the clearance by shapely's distance.
    body = reference_body(*pose)
    xmin, ymin, xmax, ymax = parking_lot.bounds
    inner = shapely.box(xmin + clearance, ymin + clearance, xmax - clearance, ymax - clearance)
    union = shapely.union_all([shapely.Polygon(o.corners()) for o in parking_lot.obstacles])
    p = np.array([pose])
    for offsets, radius in parking_checker._screens:
        if parking_checker._discs_clear(p, offsets, radius + clearance)[0]:
            assert inner.contains(body) and union.distance(body) > clearance


def test_far_end_first_edge_test_gives_the_walks_answers(parking_checker):
    # The sphere tracing looks at the far end first; the answers are those of a
    # plain walk from the near end.
    def walk(a, b, radius):
        ax, ay = a
        dx, dy = b[0] - ax, b[1] - ay
        length = math.hypot(dx, dy)
        ux, uy = dx / length, dy / length
        t = 0.0
        while True:
            room = parking_checker.clearance(ax + ux * t, ay + uy * t) - radius
            if room < parking_checker.config.min_trace_step:
                return False
            if t >= length:
                return True
            t = min(t + room, length)

    rng = np.random.default_rng(11)
    seen = set()
    for _ in range(2000):
        a = rng.uniform(-2, 102, 2)
        b = a + rng.normal(0, 6, 2)
        got = parking_checker.segment_clear(a, b, 1.0)
        assert got == walk(tuple(a), tuple(b), 1.0)
        seen.add(got)
    assert seen == {True, False}
