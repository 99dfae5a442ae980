"""Guards found by mutation testing of the collision checker (each fails under a real-looking bug).

References are shapely geometry built here and first principles (the union of a body
turned about its rear axle is the disc of its farthest corner), not the checker's code.
"""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest
import shapely

from rrtdrive.collision import CollisionChecker
from rrtdrive.maps import Obstacle
from rrtdrive.types import VehicleParams

V = VehicleParams()
BOUNDS = (0.0, 0.0, 30.0, 30.0)
#: The near face of the box (x = FACE): just off a cell boundary of the 0.1 m grid, where
#: the field is at its tightest (an occupied cell centre 2 cm inside the box).
FACE = 19.93
#: A box and a turned box: faces along the grid and across it.
OBSTACLES = (Obstacle((FACE + 1.0, 15.0), (2.0, 10.0)), Obstacle((8.0, 8.0), (3.0, 2.0), 0.6))


@functools.cache
def _checker() -> CollisionChecker:
    return CollisionChecker(BOUNDS, OBSTACLES, V)


@functools.cache
def _union() -> shapely.Geometry:
    union = shapely.union_all([shapely.Polygon(o.corners()) for o in OBSTACLES])
    shapely.prepare(union)
    return union


def _body(x: float, y: float, yaw: float) -> shapely.Polygon:
    """The body rectangle from first principles (rear axle at x, y; nose along yaw)."""
    c, s = math.cos(yaw), math.sin(yaw)
    local = ((-V.rear_overhang, -V.width / 2), (V.front_extent, -V.width / 2),
             (V.front_extent, V.width / 2), (-V.rear_overhang, V.width / 2))
    return shapely.Polygon([(x + c * u - s * v, y + s * u + c * v) for u, v in local])


def _keeps(pose, clearance: float) -> bool:
    """Shapely's answer: inside the bounds shrunk by ``clearance``, farther than it from all."""
    xmin, ymin, xmax, ymax = BOUNDS
    inner = shapely.box(xmin + clearance, ymin + clearance, xmax - clearance, ymax - clearance)
    body = _body(*pose)
    if not inner.contains(body):
        return False
    return _union().distance(body) > clearance if clearance > 0 else not _union().intersects(body)


def _poses_near_obstacles(n: int, seed: int) -> np.ndarray:
    """Poses scattered about the obstacles' corners, where the screens cannot decide alone."""
    rng = np.random.default_rng(seed)
    corners = np.concatenate([o.corners() for o in OBSTACLES])
    pick = corners[rng.integers(0, len(corners), n)]
    return np.column_stack([pick + rng.normal(0.0, 2.5, pick.shape),
                            rng.uniform(-math.pi, math.pi, n)])  # fmt: skip


def test_clearances_xy_beyond_the_grids_upper_edges_is_minus_inf():
    # Points half a cell past the last column (or row) of the grid, beside points inside:
    # not in the grid, so -inf, as clearances() says (not an index past the field).
    checker = _checker()
    ox, oy = checker.grid_origin
    nx, ny = checker.clearance_grid.shape
    h = checker.resolution
    beyond_x, beyond_y = ox + (nx + 0.5) * h, oy + (ny + 0.5) * h
    for x, y in (([5.0, beyond_x], [5.0, 5.0]), ([5.0, 5.0], [5.0, beyond_y])):
        x, y = np.array(x), np.array(y)
        got = checker.clearances_xy(x, y)
        want = checker.clearances(np.column_stack([x, y]))
        assert got[1] == -math.inf and np.array_equal(got, want)


def test_a_degenerate_edge_is_free_only_when_every_heading_is_with_the_margin():
    # edge_free(a, a) is the body at a with any heading: the union of those bodies is the
    # disc of the farthest corner (the rectangle holds the rear axle and is convex). As
    # every fast test, True must leave checker.margin beyond it (CheckerConfig.margin):
    # shapely's distance from a to the obstacles is at least reach + margin. Rear axles
    # swept towards the box's face, across many positions within a cell.
    checker = _checker()
    reach = math.hypot(V.front_extent, V.width / 2)
    need = reach + checker.config.margin
    union = _union()
    frees = 0
    for d in np.arange(reach - 0.05, reach + 0.5, 0.0005):
        a = (FACE - d, 15.0)
        if checker.edge_free(a, a):
            frees += 1
            assert union.distance(shapely.Point(a)) >= need, d
    assert frees > 0  # the sweep reaches far enough to be called free


@pytest.mark.parametrize("clearance", [0.0, 0.2, 0.5])
def test_unscreened_test_agrees_with_shapely_at_a_clearance(clearance):
    # poses_free_unscreened (the six-disc screen, then shapely) is poses_free's answer
    # for poses the three-disc screen does not clear: shapely's answer with the clearance.
    checker = _checker()
    poses = _poses_near_obstacles(1500, 5)
    three = checker._screens[0]
    unsure = poses[~checker._discs_clear(poses, three[0], three[1] + clearance)]
    got = checker.poses_free_unscreened(unsure, clearance)
    want = np.array([_keeps(p, clearance) for p in unsure])
    assert np.array_equal(got, want)
    assert np.array_equal(got, checker.poses_free(unsure, clearance))
    assert 0.05 < want.mean() < 0.95  # both answers occur


@pytest.mark.parametrize("clearance", [0.2, 0.5])
def test_scalar_pose_test_keeps_the_clearance_near_obstacles(clearance):
    # pose_free(pose, clearance) is shapely's answer where it matters: close to obstacles,
    # where a screen that forgot the clearance would clear bodies within it.
    checker = _checker()
    poses = _poses_near_obstacles(1500, 9)
    got = np.array([checker.pose_free(p, clearance) for p in poses])
    want = np.array([_keeps(p, clearance) for p in poses])
    assert np.array_equal(got, want)
    assert 0.05 < want.mean() < 0.95


def test_path_free_names_segments_of_an_already_dense_path():
    # Rows 0.05 m apart (no densifying needed) driving into the box's face: the bad
    # indices are segments i -> i + 1, each colliding row naming the segment it starts
    # (the last row, which starts none, the last segment): never past len - 2.
    x = np.arange(10.0, 17.0 + 1e-9, 0.05)
    rows = np.column_stack([x, np.full_like(x, 15.0), np.zeros_like(x)])
    ok, bad = _checker().path_free(rows, spacing=0.1)
    hit = [i for i, p in enumerate(rows) if not _keeps(p, 0.0)]
    assert not ok and hit and hit[-1] == len(rows) - 1
    assert bad.tolist() == sorted({min(i, len(rows) - 2) for i in hit})


def test_path_free_tests_the_poses_between_rows_half_a_spacing_apart():
    # Two rows 0.15 m apart turning 0.4 rad: at spacing 0.1 the pose halfway between them
    # is tested too. A 2 cm post where only that pose's body reaches (its front corner
    # sweeps outside both rows' bodies) makes the path collide.
    a, b = (10.0, 15.0, 0.0), (10.15, 15.0, 0.4)
    mid = tuple(0.5 * (p + q) for p, q in zip(a, b, strict=True))
    only_mid = _body(*mid).difference(shapely.union_all([_body(*a), _body(*b)]))
    centre = shapely.get_coordinates(only_mid.buffer(-0.015).representative_point())[0]
    post = Obstacle(tuple(centre), (0.02, 0.02))
    checker = CollisionChecker(BOUNDS, (post,), V)
    assert checker.poses_free(np.array([a, b])).all()
    assert not checker.poses_free(np.array([mid]))[0]
    ok, bad = checker.path_free(np.array([a, b]), spacing=0.1)
    assert not ok and bad.tolist() == [0]


def test_path_free_of_no_rows_is_not_free():
    ok, bad = _checker().path_free(np.zeros((0, 3)))
    assert not ok and len(bad) == 0


@pytest.mark.parametrize("step", [0.05, 0.3])
def test_path_free_keeps_the_clearance_for_one_row_dense_and_sparse_rows(step):
    # A drive along x under the box (its lower side y = 10), the body's top 0.3 m below
    # it by shapely once they overlap in x: free at a clearance of 0.2, not at 0.4, whether
    # the rows need densifying (0.3 m apart) or not (0.05 m), and so is its last row alone.
    x = np.arange(FACE - 6.0, FACE + 1.0 + 1e-9, step)
    rows = np.column_stack([x, np.full_like(x, 10.0 - 0.3 - V.width / 2), np.zeros_like(x)])
    assert _union().distance(_body(*rows[-1])) == pytest.approx(0.3)
    checker = _checker()
    for clearance, want in ((0.2, True), (0.4, False)):
        assert [_keeps(p, clearance) for p in rows[[0, -1]]] == [True, want]
        ok, bad = checker.path_free(rows, spacing=0.1, clearance=clearance)
        assert ok == want and (want or len(bad) > 0)
        assert checker.path_free(rows[-1:], clearance=clearance)[0] == want


def test_clearance_is_a_lower_bound_around_turned_obstacles():
    # The field's promise where it is tightest: right around obstacles turned off the grid,
    # most of all beside their extreme corners (the ends of each obstacle's cell window).
    turned = (Obstacle((8.0, 20.0), (3.0, 1.5), 0.3), Obstacle((16.0, 9.0), (2.0, 4.0), -0.7),
              Obstacle((22.0, 22.0), (5.0, 0.6), 1.1), Obstacle((8.0, 8.0), (1.0, 1.0), 2.5),
              Obstacle((19.65, 17.59), (0.83, 1.54), 1.58))
    checker = CollisionChecker(BOUNDS, turned, V)
    union = shapely.union_all([shapely.Polygon(o.corners()) for o in turned])
    rng = np.random.default_rng(17)
    extremes = np.concatenate([o.corners()[np.argsort(-o.corners(), axis=0)[0]] for o in turned])
    points = np.concatenate([c + rng.normal(0.0, 0.15, (3000, 2)) for c in extremes])
    inside = shapely.contains_xy(union, points[:, 0], points[:, 1])
    true = np.where(inside, 0.0, shapely.distance(union, shapely.points(points)))
    got = checker.clearances(points)
    assert np.all(got <= true + 1e-9), float(np.max(got - true))
    assert np.mean(true - got < 0.3) > 0.9  # and tight (not trivially low)


@pytest.mark.parametrize("offset", [0.0, 0.033, 0.071])
def test_connectivity_proof_never_closes_a_gap_the_car_drives_through(offset):
    # Gaps from 1.81 to 1.99 m (the car is 1.8 m wide) at three offsets against the grid:
    # the car drives straight through each (shapely), so none may be proved closed.
    for gap in np.arange(1.81, 2.0, 0.02):
        y0 = 15.5 + offset
        walls = (Obstacle((15.0, (y0 - gap / 2) / 2), (1.0, y0 - gap / 2)),
                 Obstacle((15.0, (y0 + gap / 2 + 31.0) / 2), (1.0, 31.0 - y0 - gap / 2)))
        walls_union = shapely.union_all([w.polygon() for w in walls])
        assert not any(walls_union.intersects(_body(x, y0, 0.0)) for x in (14.0, 15.0, 16.0))
        checker = CollisionChecker((0.0, 0.0, 30.0, 31.0), walls, V)
        assert not checker.provably_disconnected((3.0, y0), (25.0, y0)), gap


@pytest.mark.parametrize("width", [1.8, 1.85])
def test_free_cells_are_the_point_free_cells_of_the_start_component(width):
    # GridCache.free_cells: a cell qualifies when point_free holds at it and it lies in
    # the start's component; checked cell by cell at the centres. A car 1.85 m wide has
    # half a width over its rear overhang (0.925 > 0.895): the smaller one counts.
    checker = CollisionChecker(BOUNDS, OBSTACLES, VehicleParams(width=width))
    start = (3.0, 25.0)
    labels = checker.component_labels
    ij = np.argwhere(labels == labels.ravel()[checker.free_cells(start)[0]])
    centres = checker.grid_origin + (ij + 0.5) * checker.resolution
    want = {int(i * labels.shape[1] + j) for (i, j), (x, y) in zip(ij, centres, strict=True)
            if checker.point_free(x, y)}
    assert set(checker.free_cells(start).tolist()) == want
