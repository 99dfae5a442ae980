"""Guards found by mutation testing of the checker's grid, field, exact test and map input.

Each test fails under a real-looking bug that the rest of the suite let through. The
references are built here: shapely cell boxes, distances, intersections and buffers, and
grid cell counts worked out by hand.
"""

from __future__ import annotations

import dataclasses
import functools
import math

import numpy as np
import pytest
import shapely
from test_mutation_guards_collision import _body

from rrtdrive.collision import CheckerConfig, CollisionChecker
from rrtdrive.collision.exact import RectangleTest
from rrtdrive.collision.grid import (
    grid_origin,
    grid_resolution,
    grid_shape,
    rasterise,
    setup_notice,
)
from rrtdrive.geometry import densify
from rrtdrive.json_input import parse_json
from rrtdrive.maps import Obstacle, map_from_json
from rrtdrive.types import InputError, InputWarning, VehicleParams

V = VehicleParams()

#: Bounds with xmin != ymin, taller than wide, their far walls off the 0.1 m cell grid.
TALL = (-3.0, 2.0, 17.03, 42.07)
#: Obstacles of every kind the grid must mark: turned, overlapping, across a wall, high up
#: (row indices past the column count), and a post thinner than a cell.
TALL_OBSTACLES = (
    Obstacle((8.0, 38.0), (3.0, 2.0), 0.4),
    Obstacle((5.0, 20.0), (3.0, 1.0), 0.7),
    Obstacle((6.2, 20.5), (2.0, 1.5), -0.3),
    Obstacle((17.0, 30.0), (1.0, 4.0), 0.0),
    Obstacle((2.0, 2.3), (4.0, 1.0), 1.2),
    Obstacle((-1.0, 12.0), (0.03, 0.04), 0.9),
    Obstacle((12.0, 41.5), (1.5, 0.6), 2.0),
)


@functools.cache
def _tall_checker() -> CollisionChecker:
    return CollisionChecker(TALL, TALL_OBSTACLES, V)


def _true_clearance(bounds: tuple[float, ...], obstacles, points: np.ndarray) -> np.ndarray:
    """Shapely's distance from each point (inside the bounds) to the walls and the obstacles.

    0 inside an obstacle.
    """
    geoms = shapely.points(points)
    walls = shapely.distance(shapely.box(*bounds).exterior, geoms)
    if not obstacles:
        return walls
    union = shapely.union_all([shapely.Polygon(o.corners()) for o in obstacles])
    inside = shapely.contains_xy(union, points[:, 0], points[:, 1])
    return np.minimum(walls, np.where(inside, 0.0, shapely.distance(union, geoms)))


def _points_in(bounds: tuple[float, ...], obstacles, seed: int, n: int = 20_000) -> np.ndarray:
    """Uniform points in the bounds, plus points scattered about every obstacle corner."""
    rng = np.random.default_rng(seed)
    xmin, ymin, xmax, ymax = bounds
    uniform = np.column_stack([rng.uniform(xmin, xmax, n), rng.uniform(ymin, ymax, n)])
    corners = [o.corners() for o in obstacles]
    near = [c + rng.normal(0.0, 0.2, (300, 2)) for c in np.concatenate(corners)] if corners else []
    pts = np.concatenate([uniform, *near])
    keep = (pts[:, 0] > xmin) & (pts[:, 0] < xmax) & (pts[:, 1] > ymin) & (pts[:, 1] < ymax)
    return pts[keep]


# ---------------------------------------------------------------------------- the field


def test_clearance_is_a_lower_bound_and_tight_in_tall_offset_bounds():
    # The field's promise (a lower bound of the distance to walls and obstacles) and its
    # documented error: a point is at most h/sqrt2 from its cell centre, an occupied centre
    # at most h from the obstacle (the rectangle grown by h/sqrt2 a side), and h sqrt2 is
    # subtracted; so the field is never more than h (1/sqrt2 + 1 + sqrt2) below the truth.
    # Bounds with xmin != ymin and rows past the column count: a grid origin or a cell
    # window that mixed x and y would leave the top of the map blocked (or obstacles out).
    checker = _tall_checker()
    h = checker.resolution
    points = _points_in(TALL, TALL_OBSTACLES, 1)
    true = _true_clearance(TALL, TALL_OBSTACLES, points)
    got = checker.clearances(points)
    assert np.all(got <= true + 1e-9), float(np.max(got - true))
    worst = h * (1.0 / math.sqrt(2.0) + 1.0 + math.sqrt(2.0)) + 1e-9
    assert np.all(true - got <= worst), float(np.max(true - got))


@pytest.mark.parametrize(("pad", "cell"), [(0.05, 0.1), (0.04, 0.15), (0.1, 0.3)])
def test_clearance_is_a_lower_bound_with_a_border_thinner_than_a_cell(pad, cell):
    # CheckerConfig.pad under one cell still leaves a whole cell of occupied border on
    # every side (the border is a whole number of cells, rounded up): rounded down, the
    # grid ended inside the far walls and the field read 19 m where the wall was 0.
    bounds = (-3.1, 2.2, 27.0, 17.03)
    checker = CollisionChecker(bounds, (), V, CheckerConfig(resolution=cell, pad=pad))
    points = _points_in(bounds, (), 2)
    true = _true_clearance(bounds, (), points)
    assert np.all(checker.clearances(points) <= true + 1e-9)


@pytest.mark.parametrize("axis", [0, 1])
def test_clearance_is_a_lower_bound_at_either_far_wall_off_the_cell_grid(axis):
    # A far wall 300.5 cells out, on x or on y: the cell straddling it (centre inside)
    # touches the outside and counts as occupied. Points swept densely up to that wall.
    far = 30.05
    bounds = (0.0, 0.0, far, 20.0) if axis == 0 else (0.0, 0.0, 20.0, far)
    checker = CollisionChecker(bounds, (), V)
    along = np.linspace(far - 3.0, far, 30001)
    points = np.column_stack([along, np.full_like(along, 10.0)])
    if axis == 1:
        points = points[:, ::-1].copy()
    true = _true_clearance(bounds, (), points)
    assert np.all(checker.clearances(points) <= true + 1e-9)


# ---------------------------------------------------------------------------- rasterise


@pytest.mark.parametrize(
    ("bounds", "cell"), [(TALL, 0.1), (TALL, 0.25), ((0.0, 0.0, 30.0, 20.0), 0.1)]
)
def test_rasterise_marks_exactly_the_cells_its_docstring_promises(bounds, cell):
    # Every cell that touches an obstacle or reaches past the bounds is occupied (shapely
    # on the cell's box): the superset the field's lower bound rests on. And no more than
    # promised: an occupied cell either reaches past the bounds or has its centre within
    # h of an obstacle (the rectangle grown by h/sqrt2 a side), so the field stays tight.
    origin = grid_origin(bounds, cell, 1.0)
    nx, ny = grid_shape(bounds, cell, 1.0)
    occupied = rasterise(bounds, TALL_OBSTACLES, origin, cell, nx, ny)
    i, j = np.meshgrid(np.arange(nx), np.arange(ny), indexing="ij")
    x0, y0 = origin[0] + i.ravel() * cell, origin[1] + j.ravel() * cell
    boxes = shapely.box(x0, y0, x0 + cell, y0 + cell)
    union = shapely.union_all([shapely.Polygon(o.corners()) for o in TALL_OBSTACLES])
    xmin, ymin, xmax, ymax = bounds
    tol = 1e-6 * cell
    past = ((x0 < xmin - tol) | (y0 < ymin - tol)
            | (x0 + cell > xmax + tol) | (y0 + cell > ymax + tol))
    touches = shapely.intersects(union, boxes)
    flat = occupied.ravel()
    assert np.all(flat[touches | past])
    centres = shapely.points(x0 + 0.5 * cell, y0 + 0.5 * cell)
    near = shapely.distance(union, centres) <= cell * (1.0 + 1e-9)
    # Cells wholly inside the bounds with no obstacle within h are free (not only those
    # off the edge: a cell flush with a wall touches no outside).
    assert not np.any(flat & ~near & ~past)


# ---------------------------------------------------------------------------- grid size

#: 100 x 100 m at 0.25 m cells (exact in binary) with a 1 m border: 400 + 2 * 4 = 408
#: cells a side, counted by hand.
CELLS_AT_QUARTER = 408 * 408


def test_a_grid_of_exactly_the_cell_limit_is_kept():
    # "At most max_grid_cells": a grid of exactly that many cells keeps its resolution;
    # one cell fewer allowed and it must coarsen (to the next centimetre, 0.26 m).
    bounds = (0.0, 0.0, 100.0, 100.0)
    exact = CheckerConfig(resolution=0.25, max_grid_cells=CELLS_AT_QUARTER)
    assert grid_resolution(bounds, exact) == 0.25
    one_fewer = dataclasses.replace(exact, max_grid_cells=CELLS_AT_QUARTER - 1)
    assert grid_resolution(bounds, one_fewer) == 0.26


def test_coarsening_stops_at_the_first_cell_whose_grid_fits_exactly():
    # From 0.1 m the search reaches 0.25 m, whose grid is exactly the limit: it fits, so
    # it is the answer (0.24 m gives 417 + 2 * 5 = 427 cells a side, too many).
    bounds = (0.0, 0.0, 100.0, 100.0)
    assert grid_resolution(bounds, CheckerConfig(max_grid_cells=CELLS_AT_QUARTER)) == 0.25


def test_a_coarsening_to_exactly_the_coarsest_allowed_is_taken():
    # max_auto_resolution is the coarsest the checker takes by itself: reaching it exactly
    # is allowed, not refused.
    bounds = (0.0, 0.0, 100.0, 100.0)
    config = CheckerConfig(max_grid_cells=CELLS_AT_QUARTER, max_auto_resolution=0.25)
    assert grid_resolution(bounds, config) == 0.25
    with pytest.raises(InputError, match="^bounds: "):
        grid_resolution(bounds, CheckerConfig(max_grid_cells=CELLS_AT_QUARTER - 1,
                                              max_auto_resolution=0.25))


def test_the_refusal_names_the_coarsest_cell_the_checker_would_have_taken():
    # A resolution set coarser than max_auto_resolution is the coarsest taken; the refusal
    # of a map needing more says so (not the smaller max_auto_resolution).
    config = CheckerConfig(resolution=0.2, max_grid_cells=300 * 300, max_auto_resolution=0.1)
    with pytest.raises(InputError) as err:
        grid_resolution((0.0, 0.0, 100.0, 100.0), config)
    assert "coarser than the 0.2 m the checker chooses by itself" in str(err.value)


def test_the_long_set_up_notice_is_for_more_than_four_million_cells():
    # 248 m at 0.125 m with a 1 m border: 1984 + 16 = 2000 cells a side, exactly 4 M: no
    # notice. One more row (248.125 m) is more than 4 M: the notice.
    config = CheckerConfig(resolution=0.125)
    assert setup_notice((0.0, 0.0, 248.0, 248.0), config) is None
    assert setup_notice((0.0, 0.0, 248.0, 248.125), config) is not None


# ---------------------------------------------------------------------------- connectivity


def _swept_box_is_free(bounds, obstacles, x0: float, x1: float, y0: float, y1: float) -> bool:
    """Shapely: the axis-aligned box a straight drive sweeps lies inside and clear of all."""
    box = shapely.box(x0, y0, x1, y1)
    union = shapely.union_all([shapely.Polygon(o.corners()) for o in obstacles])
    return shapely.box(*bounds).contains(box) and not union.intersects(box)


def test_a_wide_car_backed_up_to_a_wall_is_not_proved_stuck():
    # A car 2.5 m wide (half-width 1.25 m, rear overhang 0.895 m) with its rear bumper
    # 5.5 cm from the west wall drives 10 m east (shapely: the swept box is clear). The
    # rear axle is only 0.95 m from the wall: the proof may assume the smaller of the two
    # radii, never the larger, or it calls a drivable pair disconnected.
    car = VehicleParams(width=2.5)
    bounds = (0.0, 0.0, 30.0, 10.0)
    wall = (Obstacle((20.0, 9.0), (2.0, 2.0)),)  # not in the way
    start, goal = (0.95, 5.0), (10.95, 5.0)
    assert _swept_box_is_free(bounds, wall, start[0] - car.rear_overhang,
                              goal[0] + car.front_extent, 5.0 - 1.25, 5.0 + 1.25)
    checker = CollisionChecker(bounds, wall, car)
    assert checker.pose_free((*start, 0.0)) and checker.pose_free((*goal, 0.0))
    assert not checker.provably_disconnected(start, goal)


def test_points_high_in_a_tall_map_are_not_proved_apart():
    # Rows past the column count: a straight drive north at x = 2 from y = 26 to y = 33
    # (shapely: clear) is no proof of disconnection, whichever way it is asked.
    a, b = (2.0, 26.0), (2.0, 33.0)
    assert _swept_box_is_free(TALL, TALL_OBSTACLES, 2.0 - V.width / 2, 2.0 + V.width / 2,
                              a[1] - V.rear_overhang, b[1] + V.front_extent)
    checker = _tall_checker()
    assert not checker.provably_disconnected(a, b)
    assert not checker.provably_disconnected(b, a)


def test_sampler_cells_lie_in_the_starts_room_of_bounds_off_the_origin():
    # Two rooms, one above the other, split by a wall at y = 35 across the whole map;
    # the bounds start at y = 20, not at 0. The cells a sampler draws from for a start in
    # the lower room (free_cells, passage_cells) all lie in the lower room, and many do.
    bounds = (0.0, 20.0, 30.0, 50.0)
    wall = (Obstacle((15.0, 35.0), (32.0, 1.0)),)
    checker = CollisionChecker(bounds, wall, V)
    start = (15.0, 25.0)
    cells = checker.free_cells(start)
    ny = checker.clearance_grid.shape[1]
    centres = checker.grid_origin + (np.column_stack([cells // ny, cells % ny]) + 0.5) * 0.1
    assert len(centres) > 1000
    assert np.all(centres[:, 1] < 35.0)
    passages = checker.passage_cells(start, 1.5)
    assert np.all(passages[:, 1] < 35.0)


# ---------------------------------------------------------------------------- exact test


@pytest.mark.parametrize("n", [1, 63, 64, 65, 66, 130])
def test_exact_test_answers_batches_of_any_size(n):
    # RectangleTest keeps empty hole lists for 64 polygons and grows them on demand: a
    # batch of 65 (one past the store) must be answered, and as shapely answers it.
    bounds = (0.0, 0.0, 30.0, 20.0)
    post = shapely.box(14.0, 9.0, 16.0, 11.0)
    test = RectangleTest(bounds, post, V)
    rng = np.random.default_rng(n)
    poses = np.column_stack([rng.uniform(10.0, 20.0, n), rng.uniform(6.0, 14.0, n),
                             rng.uniform(-math.pi, math.pi, n)])
    bodies = np.array([_body(*p) for p in poses], dtype=object)
    want = shapely.contains(shapely.box(*bounds), bodies) & ~shapely.intersects(post, bodies)
    assert np.array_equal(test.free(poses), want)


# ---------------------------------------------------------------------------- map input


@pytest.mark.parametrize(
    "size", [(2.0, 0.0), (2.0, -1.0), (0.0, 2.0), (-1.0, 2.0), (2.0, math.nan)]
)
def test_an_obstacle_of_no_width_or_no_length_is_refused_naming_its_size(size):
    # Both sides must be > 0 (the width as much as the length), as SPEC's obstacles are.
    with pytest.raises(InputError, match=r"^obstacle\.size: "):
        Obstacle((5.0, 5.0), size)


@pytest.mark.parametrize("yaw", [2e6, -2e6])
def test_an_obstacle_turned_past_the_yaw_limit_either_way_is_refused(yaw):
    # Beyond MAX_YAW (1e6 rad) an angle keeps too little precision: refused whatever
    # its sign, naming obstacle.yaw.
    with pytest.raises(InputError, match=r"^obstacle\.yaw: "):
        Obstacle((5.0, 5.0), (2.0, 1.0), yaw)


def _lot(**changes) -> dict:
    """A 40 x 20 m map file (wider than tall), an obstacle in its middle."""
    data = {"bounds": [0, 0, 40, 20], "obstacles": [{"center": [20, 10], "size": [6, 4]}],
            "start": [5, 5, 0], "goal": [30, 15, 0]}
    data.update(changes)
    return data


@pytest.mark.parametrize("start", [[5, 25, 0], [5, -3, 0], [45, 5, 0], [-1, 5, 0]])
def test_a_start_off_the_map_on_any_side_is_named_outside_the_bounds(start):
    # Above, below, right or left of the bounds: "lies outside the bounds", the message
    # for a rear axle off the map (not the body test's "leaves or touches").
    with pytest.raises(InputError, match=r"^start: \(.*\) lies outside the bounds"):
        map_from_json(_lot(start=start))


@pytest.mark.parametrize(("label", "pose"), [("start", [5, 19.5, 0]), ("goal", [30, 19.2, 3.0]),
                                             ("start", [5, 0.5, 0]), ("goal", [39.0, 5, 0])])
def test_a_body_sticking_out_of_any_wall_is_refused(label, pose):
    # Rear axle inside, body through the wall (shapely: the body leaves the bounds box).
    assert not shapely.box(0, 0, 40, 20).contains(_body(*pose))
    with pytest.raises(InputError, match=rf"^{label}: the car's body at .* leaves or touches"):
        map_from_json(_lot(**{label: pose}))


@pytest.mark.parametrize("pose", [[18.0, 10.0, 0.0], [23.895, 10.0, 0.0]])
def test_a_start_inside_an_obstacle_or_touching_it_is_refused(pose):
    # A body wholly inside the 6 x 4 m obstacle, or with its rear bumper on the obstacle's
    # east face (x = 23; shapely: within, and touches): both are on the obstacle.
    obstacle = shapely.box(17.0, 8.0, 23.0, 12.0)
    x, y, _ = pose
    body = shapely.box(x - V.rear_overhang, y - V.width / 2, x + V.front_extent, y + V.width / 2)
    assert obstacle.contains(body) or obstacle.touches(body)
    # Inside: "overlaps ... by"; on the face: "touches" (no shift of 0 m named).
    with pytest.raises(InputError, match=r"^start: the car's body at .* (overlaps|touches) ob"):
        map_from_json(_lot(start=pose))


@pytest.mark.parametrize(
    "obstacle",
    [{"center": [-2, 10], "size": [4, 2]},  # its east face on the west wall (x = 0)
     {"center": [42, 10], "size": [4, 2]},  # west face on the east wall
     {"center": [20, -1], "size": [4, 2]},  # top on the south wall
     {"center": [20, 21], "size": [4, 2]},  # bottom on the north wall (y = 20 < xmax)
     {"center": [20, 30], "size": [4, 2]}],  # wholly above the map, below x = 40
)
def test_an_obstacle_wholly_outside_any_wall_warns(obstacle):
    # Outside the bounds (at most touching them from outside) an obstacle changes nothing:
    # a warning names it, whichever side it lies on.

    rect = shapely.box(obstacle["center"][0] - 2, obstacle["center"][1] - 1,
                       obstacle["center"][0] + 2, obstacle["center"][1] + 1)
    assert not rect.overlaps(shapely.box(0, 0, 40, 20))
    data = _lot(obstacles=[{"center": [20, 10], "size": [6, 4]}, obstacle])
    with pytest.warns(InputWarning, match=r"^obstacles\[1\]: .* wholly outside the bounds"):
        map_from_json(data)


def test_a_byte_order_mark_in_text_input_is_skipped():
    # parse_json takes text too (a plan piped through a text stream without a buffer): a
    # byte-order mark at its start is skipped as it is in bytes, not a syntax error.
    assert parse_json("\ufeff{\"a\": [1, 2]}", "plan", "stdin") == {"a": [1, 2]}
    assert parse_json("\ufeff{\"a\": [1, 2]}".encode(), "plan", "stdin") == {"a": [1, 2]}


@pytest.mark.parametrize("text", [b"", b"  \n\t ", b"\n\n"])
def test_an_empty_file_is_malformed_json_with_no_empty_excerpt(text):
    # Nothing before the error to show: the message ends at the position, without
    # ", near ''".
    with pytest.raises(InputError) as err:
        parse_json(text, "map", "m.json")
    message = str(err.value)
    assert message.startswith("map: malformed JSON in m.json: Expecting value (line ")
    assert "near" not in message and message.endswith(")")


@pytest.mark.parametrize(
    ("field", "value"),
    [("center", (1.0, 2.0, 3.0)), ("size", (1.0, 2.0, 3.0)), ("center", (1.0,)), ("size", ())],
)
def test_an_obstacle_pair_of_other_than_two_numbers_is_refused(field, value):
    # A centre or size of three numbers (a pose pasted in?) is not silently cut to two.
    args = {"center": (5.0, 5.0), "size": (2.0, 1.0), field: value}
    with pytest.raises(InputError, match=rf"^obstacle\.{field}: expected two numbers"):
        Obstacle(args["center"], args["size"])


def test_a_file_that_is_not_utf8_names_the_offset_of_its_first_bad_byte():
    # A name written in Latin-1: its e-acute (0xE9) is the first byte UTF-8 refuses, byte 13
    # counted from 0 (b'{"name": "caf' before it), not the one after it.
    raw = b'{"name": "' + "caf\u00e9".encode("latin-1") + b'"}'
    bad = raw.index(b"\xe9")
    with pytest.raises(InputError, match=rf"^map: m\.json is not a UTF-8 text file \(byte {bad}: "):
        parse_json(raw, "map", "m.json")


@pytest.mark.parametrize("yaw", [0.0, 0.4, -1.2, 2.9])
@pytest.mark.parametrize("amount", [0.2, 1.0])
def test_a_grown_obstacle_is_the_rectangle_buffered_by_half_the_amount(yaw, amount):
    # grown(a) (the improved planner's expanded obstacles) adds a to the length and to the
    # width: the rectangle buffered by a/2 with mitred corners, turned as the original.
    o = Obstacle((7.0, -3.0), (4.0, 1.5), yaw)
    want = shapely.Polygon(o.corners()).buffer(amount / 2.0, join_style="mitre")
    got = shapely.Polygon(o.grown(amount).corners())
    assert got.symmetric_difference(want).area < 1e-9
    assert o.grown(amount).yaw == o.yaw


# ---------------------------------------------------------------------------- densify


@pytest.mark.parametrize("rel_slack", [1e-7, 1e-6, 1e-3])
def test_densify_with_a_relative_slack_keeps_every_gap_that_much_under_the_spacing(rel_slack):
    # The slack is there so that rows re-read (rounded a hair over, through JSON) still
    # keep the spacing: each gap is at most spacing / (1 + rel_slack). Segments of whole
    # multiples of the spacing, each a hair over, are where it decides the piece count.
    spacing = 0.1
    lengths = np.arange(1, 41) * spacing * (1.0 + rel_slack / 10.0)
    x = np.concatenate([[0.0], np.cumsum(lengths)])
    points = np.column_stack([x, np.zeros_like(x)])
    d = densify(points, spacing, rel_slack=rel_slack)
    gaps = np.diff(d.points[:, 0])
    assert np.all(gaps <= spacing / (1.0 + rel_slack) * (1.0 + 1e-12))


def test_densify_names_the_input_segment_of_every_row():
    # Densified.segment: each output row lies on the segment it names, the last row (the
    # last vertex) on the last segment: never an index past it.
    p = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 0.35], [3.0, 0.35]])
    d = densify(p, 0.25)
    seg = d.segment
    assert len(seg) == len(d.points) and seg.max() == len(p) - 2 and seg[-1] == len(p) - 2
    for row, k in zip(d.points, seg, strict=True):
        assert shapely.LineString(p[k : k + 2]).distance(shapely.Point(row)) < 1e-12


def test_densify_of_one_row_names_a_segment_for_it():
    # A path of one pose (a start that is the goal) densifies to that row, and
    # Densified.segment still has an entry per row, as callers index it by row.
    p = np.array([[1.0, 2.0, 0.5]])
    d = densify(p, 0.1)
    assert np.array_equal(d.points, p) and len(d.pieces) == 0
    assert d.segment.tolist() == [0]


# ---------------------------------------------------------------------------- tight maps


@pytest.mark.parametrize("aisle", [6.0, 12.0])
def test_a_garage_of_another_aisle_width_has_that_aisle(aisle):
    # garage_map(aisle): two rows of 5.5 m bays either side of an aisle ``aisle`` wide,
    # each parked nose 0.5 m from its wall (shapely), and the start in the aisle.
    from rrtdrive.tight_maps import garage_map

    m = garage_map(aisle)
    top = 2 * 5.5 + aisle
    assert m.bounds[3] == pytest.approx(top)
    north = [o for o in m.obstacles if o.center[1] > top / 2]
    south = [o for o in m.obstacles if o.center[1] < top / 2]
    assert north and south
    top_wall = shapely.LineString([(m.bounds[0], top), (m.bounds[2], top)])
    for o in north:
        assert top_wall.distance(shapely.Polygon(o.corners())) == pytest.approx(0.5)
    assert 5.5 < m.start.y < 5.5 + aisle


@pytest.mark.parametrize("offset", [0.1, 0.6])
def test_kerbside_cars_and_goal_keep_the_kerb_offset_asked_for(offset):
    # kerbside_map(kerb_offset=d): every parked car and the parked goal body are d from
    # the kerb (y = 0), by shapely.
    from rrtdrive.tight_maps import kerbside_map

    m = kerbside_map(kerb_offset=offset)
    kerb = shapely.LineString([(0.0, 0.0), (60.0, 0.0)])
    for o in m.obstacles:
        assert kerb.distance(shapely.Polygon(o.corners())) == pytest.approx(offset)
    assert kerb.distance(_body(*m.goal.as_tuple())) == pytest.approx(offset)


@pytest.mark.parametrize("tail_in", [False, True])
@pytest.mark.parametrize(("side", "index"), [(0, 5), (1, 11)])
def test_a_garage_goal_parks_nose_or_tail_to_the_wall_half_a_metre_off(side, index, tail_in):
    # garage_goal: the body 0.5 m from its bay's wall (shapely), with the nose nearer the
    # wall parked nose-in and the tail nearer it parked tail-in (facing the aisle).
    from rrtdrive.tight_maps import garage_goal, garage_map

    m = garage_map()
    goal = garage_goal(side, index, tail_in=tail_in)
    wall_y = 0.0 if side == 0 else m.bounds[3]
    wall = shapely.LineString([(m.bounds[0], wall_y), (m.bounds[2], wall_y)])
    assert wall.distance(_body(*goal.as_tuple())) == pytest.approx(0.5)
    c, s = math.cos(goal.yaw), math.sin(goal.yaw)
    nose = shapely.Point(goal.x + c * V.front_extent, goal.y + s * V.front_extent)
    tail = shapely.Point(goal.x - c * V.rear_overhang, goal.y - s * V.rear_overhang)
    assert (wall.distance(tail) < wall.distance(nose)) == tail_in
