"""Guards against mutants of the failure diagnosis that survived the suite.

Each test checks a claim the diagnosis makes to the user (a distance, the obstacle named,
the words for an end) against an independent reference: shapely geometry, the car's
footprint, a brute-force sweep of the checker's own edge test, or hand-worked numbers.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

from rrtdrive.maps import Map, Obstacle
from rrtdrive.planning.base import PlanningProblem
from rrtdrive.planning.diagnosis import DiagnosisKind, diagnose, free_run
from rrtdrive.planning.diagnosis.measures import (
    body_centre,
    cell_centres,
    grid_cell,
    ray_runs,
)
from rrtdrive.types import Pose, VehicleParams
from rrtdrive.vehicle import footprint_polygon

CAR = VehicleParams()
F, B = CAR.front_extent, CAR.rear_overhang


def _problem(m: Map, *, reverse: bool = False) -> PlanningProblem:
    return PlanningProblem.from_map(m, reverse=reverse)


# ---------------------------------------------------------------------- free runs


def test_a_wall_within_the_last_step_of_the_limit_stops_the_run() -> None:
    """A wall within the last step before the run's limit still ends the run.

    A wall 0.27 m ahead of the nose, runs looked at up to 0.3 m: the run is the gap
    (shapely), not the limit. 0.3 / 0.05 is 5.999... in floating point: the last pose,
    0.30 m on, must still be tested.
    """
    start = Pose(20.0, 10.0, 0.0)
    wall = Obstacle((20.0 + F + 0.27 + 0.5, 10.0), (1.0, 20.0))
    m = Map("w", (0.0, 0.0, 60.0, 20.0), (wall,), start, Pose(5.0, 10.0, 0.0))
    gap = footprint_polygon(start.as_tuple(), CAR).distance(wall.polygon())
    assert gap == pytest.approx(0.27)
    run = free_run(_problem(m).checker, start, 1, 0.0, 0.3)
    assert gap - 2e-3 <= run <= gap + 1e-9


# ---------------------------------------------------------------------- body collides


def test_a_body_overlapping_two_obstacles_names_the_first_of_them() -> None:
    """A body overlapping two obstacles is said to overlap the first of them.

    The goal's nose pokes into obstacles 1 and 2 (its rear axle in neither): the
    finding names obstacle 1, the lowest index shapely finds overlapping the body.
    """
    goal = Pose(30.0, 10.0, 0.0)
    obstacles = (
        Obstacle((5.0, 18.0), (1.0, 1.0)),  # far away
        Obstacle((30.0 + F - 0.3 + 0.5, 9.0), (1.0, 1.0)),  # nose, right corner
        Obstacle((30.0 + F - 0.3 + 0.5, 11.0), (1.0, 1.0)),  # nose, left corner
    )
    m = Map("nose", (0.0, 0.0, 60.0, 20.0), obstacles, Pose(10.0, 10.0, 0.0),
            Pose(50.0, 10.0, 0.0))  # fmt: skip
    body = footprint_polygon(goal.as_tuple(), CAR)
    hits = [i for i, o in enumerate(obstacles) if body.intersects(o.polygon())]
    assert hits == [1, 2]
    assert not any(o.polygon().contains(shapely.Point(goal.x, goal.y)) for o in obstacles)
    p = _problem(m)
    found = diagnose(PlanningProblem(m, p.checker, m.start, goal, m.vehicle))
    assert found.kind is DiagnosisKind.BODY_COLLIDES
    assert found.numbers["obstacle"] == hits[0]
    cx, cy = obstacles[1].center
    assert found.message == (
        f"the goal's body at (30.0, 10.0) overlaps obstacle 1 at ({cx:.1f}, {cy:.1f})"
    )


def test_a_body_overlapping_obstacle_0_names_it_not_the_bounds() -> None:
    """A body overlapping obstacle 0 names it, not the bounds.

    Obstacle 0 is an obstacle like any other: the message names it (index 0 is not the
    map's edge, -1 is).
    """
    start = Pose(20.0, 10.0, 0.0)
    wall = Obstacle((20.0 + F - 0.2 + 0.5, 10.0), (1.0, 4.0))  # the nose 0.2 m into it
    m = Map("w", (0.0, 0.0, 60.0, 20.0), (wall,), Pose(10.0, 10.0, 0.0), Pose(5.0, 10.0, 0.0))
    assert footprint_polygon(start.as_tuple(), CAR).intersects(wall.polygon())
    assert not wall.polygon().contains(shapely.Point(start.x, start.y))
    p = _problem(m)
    found = diagnose(PlanningProblem(m, p.checker, start, m.goal, m.vehicle))
    assert found.kind is DiagnosisKind.BODY_COLLIDES
    assert found.numbers["obstacle"] == 0
    cx, cy = wall.center
    assert found.message == (
        f"the start's body at (20.0, 10.0) overlaps obstacle 0 at ({cx:.1f}, {cy:.1f})"
    )


# ---------------------------------------------------------------------- room at the ends


def _boxed_start() -> tuple[Map, float, float]:
    """A start 0.5 m from a wall ahead and 0.9 m from one behind, 2 m ways round both."""
    ahead = Obstacle((20.0 + F + 0.5 + 0.5, 10.0), (1.0, 16.0))
    behind = Obstacle((20.0 - B - 0.9 - 0.5, 10.0), (1.0, 16.0))
    m = Map("box", (0.0, 0.0, 60.0, 20.0), (ahead, behind), Pose(20.0, 10.0, 0.0),
            Pose(40.0, 10.0, 0.0))  # fmt: skip
    body = footprint_polygon(m.start.as_tuple(), CAR)
    return m, body.distance(ahead.polygon()), body.distance(behind.polygon())


def test_a_boxed_start_says_how_much_room_is_behind_and_ahead() -> None:
    """A boxed-in start says its room behind and ahead the right way round.

    Room behind (0.9 m) and ahead (0.5 m, shapely) in the sentence's own order, and
    leaving (not reaching) the start takes a gear change.
    """
    m, ahead, behind = _boxed_start()
    assert (round(ahead, 2), round(behind, 2)) == (0.5, 0.9)
    found = diagnose(_problem(m))
    assert found.kind is DiagnosisKind.BOXED_IN
    assert found.numbers["room_ahead_m"] == pytest.approx(ahead, abs=2e-3)
    assert found.numbers["room_behind_m"] == pytest.approx(behind, abs=2e-3)
    assert "at most 0.90 m behind it and 0.50 m ahead of it" in found.message
    assert "; leaving it takes at least one gear change (try --reverse)" in found.message


# ---------------------------------------------------------------------- tight clearance


def test_tight_clearance_beside_the_maps_edge_names_the_edge() -> None:
    """A goal squeezed against the map's edge names the edge, not obstacle 0.

    An empty map, the goal's body 0.08 m from its lower edge: no tree edge reaches it,
    and what it is close to is the map's edge (shapely: 0.08 m), not an obstacle 0.
    """
    goal = Pose(30.0, 0.9 + 0.08, 0.0)
    m = Map("edge", (0.0, 0.0, 60.0, 20.0), (), Pose(5.0, 10.0, 0.0), goal)
    gap = footprint_polygon(goal.as_tuple(), CAR).distance(shapely.box(*m.bounds).exterior)
    found = diagnose(_problem(m))
    assert found is not None and found.kind is DiagnosisKind.TIGHT_CLEARANCE, found
    assert found.numbers["obstacle"] == -1
    assert found.numbers["gap_m"] == pytest.approx(gap, abs=1e-9)
    assert found.message.startswith("the goal's body is 0.08 m from the map's edge;")
    # Into a goal, an edge's round end reaches past the car's nose (it drove there).
    assert " m beyond its nose, so none reaches it" in found.message


# ---------------------------------------------------------------------- measures


@settings(max_examples=40, deadline=None)
@given(
    seed=st.integers(0, 2**31 - 1),
    n=st.integers(1, 6),
)
def test_ray_runs_are_shapelys_first_hits(seed: int, n: int) -> None:
    """Each ray's run is the distance to its first wall, as shapely finds it.

    Each ray's run is the distance to its first crossing with the walls (shapely's
    intersection of the ray with them), or ``reach`` where it meets none.
    """
    rng = np.random.default_rng(seed)
    walls = shapely.MultiLineString(
        [rng.uniform(-10.0, 10.0, size=(2, 2)).tolist() for _ in range(n)]
    )
    origin = rng.uniform(-3.0, 3.0, size=2)
    angles = rng.uniform(-math.pi, math.pi, size=24)
    reach = 30.0
    got = ray_runs(origin, angles, walls, reach)
    here = shapely.Point(origin)
    for angle, run in zip(angles, got, strict=True):
        tip = origin + reach * np.array([math.cos(angle), math.sin(angle)])
        hit = shapely.LineString([origin, tip]).intersection(walls)
        expected = reach if hit.is_empty else here.distance(hit)
        assert run == pytest.approx(expected, abs=1e-6)


@settings(max_examples=60, deadline=None)
@given(
    x=st.floats(-50.0, 50.0),
    y=st.floats(-50.0, 50.0),
    yaw=st.floats(-math.pi, math.pi),
)
def test_the_body_centre_is_the_footprints_centroid(x: float, y: float, yaw: float) -> None:
    """The street is measured across the body's centre: the footprint's centroid."""
    c = footprint_polygon((x, y, yaw), CAR).centroid
    bx, by = body_centre(Pose(x, y, yaw), CAR)
    assert (bx, by) == (pytest.approx(c.x, abs=1e-9), pytest.approx(c.y, abs=1e-9))


def test_grid_cells_hold_their_points_and_none_lies_past_the_grid() -> None:
    """A point's grid cell holds it; past the grid's last cell there is none.

    A point's cell centre is within half a cell of it on each axis, and a point past
    the grid's last cell (origin + shape x resolution) has no cell.
    """
    m = Map("open", (0.0, 0.0, 30.0, 20.0), (), Pose(5.0, 10.0, 0.0), Pose(25.0, 10.0, 0.0))
    checker = _problem(m).checker
    h = checker.resolution
    rng = np.random.default_rng(0)
    for p in rng.uniform((0.0, 0.0), (30.0, 20.0), size=(200, 2)):
        cell = grid_cell(checker, (float(p[0]), float(p[1])))
        assert cell is not None
        cx, cy = cell_centres(checker, *cell)
        assert abs(cx - p[0]) <= h / 2 + 1e-9 and abs(cy - p[1]) <= h / 2 + 1e-9
    nx, ny = checker.clearance_grid.shape
    far = checker.grid_origin + h * np.array([nx, ny]) + h / 2
    assert grid_cell(checker, (float(far[0]), 10.0)) is None
    assert grid_cell(checker, (10.0, float(far[1]))) is None


# ---------------------------------------------------------------------- tight clearance, edges


def _ring_round(pose: Pose, inner: float, right_from: float | None = None) -> tuple[Obstacle, ...]:
    """Square posts (0.3 m) ringing ``pose`` ``inner``..``inner + 0.6`` m out.

    With ``right_from``, the right half (x above ``pose.x + 0.3``) is filled from that
    radius out as well, clear of a body heading up (+y) from ``pose``.
    """
    posts = []
    step = 0.3
    reach = inner + 0.6
    k = int(math.ceil(reach / step))
    for x in (step * i for i in range(-k, k + 1)):
        for y in (step * j for j in range(-k, k + 1)):
            d = math.hypot(x, y)
            in_ring = inner <= d <= reach
            beside = x > 0.3 and not (x < 1.3 and -1.3 < y < 3.9)  # clear of the body
            in_right = right_from is not None and right_from <= d <= reach and beside
            if in_ring or in_right:
                posts.append(Obstacle((pose.x + x, pose.y + y), (step, step)))
    return tuple(posts)


@pytest.mark.parametrize("right_half", [False, True])
def test_tight_clearance_is_not_claimed_where_an_edge_into_the_goal_passes(
    right_half: bool,
) -> None:
    """No ``tight_clearance`` where an edge into the goal passes the edge test.

    Posts ring the goal (heading +y) 4.4 m out: every 0.5 m edge driven out of it reaches
    them with its nose, but edges driven into it (the car coming from 0.5 m away) stop
    short, so "none reaches it" is false. With the right half filled from 2.6 m too, only
    edges whose nose points left (coming from the right) pass: every direction round the
    goal must be tried, not the first half turn from its heading. The reference is the
    checker's own edge test, searched by brute force.
    """
    from rrtdrive.planning.diagnosis.checks import tight_clearance

    goal = Pose(30.0, 15.0, math.pi / 2)
    posts = _ring_round(goal, 4.4, 2.6 if right_half else None)
    m = Map("ring", (0.0, 0.0, 60.0, 30.0), posts, Pose(5.0, 15.0, 0.0), goal)
    checker = _problem(m).checker
    here = np.array(goal.xy)
    units = [np.array([math.cos(a), math.sin(a)]) for a in np.radians(np.arange(0.0, 360.0, 5.0))]
    leaving = [u for u in units if checker.edge_free(here, here + 0.5 * u)]
    arriving = [u for u in units if checker.edge_free(here + 0.5 * u, here)]
    assert not leaving and arriving  # the reference: only edges into the goal pass
    if right_half:  # they come from the right: more than half a turn from the heading
        assert all(u[0] > 0.0 for u in arriving)
    assert tight_clearance(m, checker, m.start, goal) is None


def test_tight_clearance_needs_the_body_free_along_its_heading() -> None:
    """No ``tight_clearance`` where the exact body cannot drive the first edge either.

    A start 0.2 m from a wall ahead with a block 0.08 m beside it: no edge leaves, but
    the body itself cannot drive the first 0.5 m (shapely), so the swept test's keep is not
    what stops it (room at the ends speaks) and no ``tight_clearance`` is claimed.
    """
    from rrtdrive.planning.diagnosis.checks import tight_clearance

    start = Pose(20.0, 10.0, 0.0)
    wall = Obstacle((20.0 + F + 0.2 + 0.5, 10.0), (1.0, 20.0))
    side = Obstacle((20.0 + 1.255, 10.0 + 0.9 + 0.08 + 0.5), (6.0, 1.0))
    m = Map("nook", (0.0, 0.0, 60.0, 20.0), (wall, side), start, Pose(5.0, 5.0, 0.0))
    checker = _problem(m).checker
    moved = footprint_polygon((start.x + 0.5, start.y, start.yaw), CAR)
    assert moved.intersects(wall.polygon())
    here = np.array(start.xy)
    assert not any(
        checker.edge_free(here, here + 0.5 * np.array([math.cos(a), math.sin(a)]))
        or checker.edge_free(here + 0.5 * np.array([math.cos(a), math.sin(a)]), here)
        for a in np.radians(np.arange(0.0, 360.0, 5.0))
    )
    assert tight_clearance(m, checker, start, m.goal) is None


# ---------------------------------------------------------------------- narrow passages


def _gap_wall(gap: float) -> Map:
    """A wall across x = 30 of a 60 x 20 m room with one opening ``gap`` wide at y = 10."""
    low, high = 10.0 - gap / 2, 10.0 + gap / 2
    wall = (
        Obstacle((30.0, low / 2), (1.0, low)),
        Obstacle((30.0, (high + 20.0) / 2), (1.0, 20.0 - high)),
    )
    return Map("gap", (0.0, 0.0, 60.0, 20.0), wall, Pose(10.0, 10.0, 0.0), Pose(50.0, 10.0, 0.0))


def _an_edge_crosses(m: Map) -> bool:
    """Whether some 0.5 m tree edge through the wall's opening passes the edge test.

    Whether some 0.5 m tree edge with its middle in the wall's opening passes the
    checker's swept edge test (brute force over places and headings).
    """
    checker = _problem(m).checker
    for y0 in np.arange(9.7, 10.301, 0.01):
        for deg in np.arange(-10.0, 10.01, 1.0):
            u = np.array([math.cos(math.radians(deg)), math.sin(math.radians(deg))])
            a = np.array([30.0, y0]) - 0.25 * u
            if checker.edge_free(a, a + 0.5 * u):
                return True
    return False


@pytest.mark.parametrize("gap", [2.2, 2.3])
def test_a_gap_no_tree_edge_crosses_is_named_for_tree_planners(gap: float) -> None:
    """A gap that no tree edge crosses is named for the tree planners.

    No swept tree edge crosses a 2.2 or 2.3 m opening (brute force of the edge test):
    that gap is what stops rrt and rrt-connect, and the diagnosis names it, with the room
    the edge test needs beside the body (margin, grid error, trace step) each side.
    """
    m = _gap_wall(gap)
    assert not _an_edge_crosses(m)
    found = diagnose(_problem(m))
    assert found is not None and found.kind is DiagnosisKind.NARROW_PASSAGE, found
    assert found.numbers["width_m"] == pytest.approx(gap)
    assert found.numbers["needed_m"] > gap


def test_the_gap_between_a_block_and_the_maps_edge_is_their_distance() -> None:
    """The gap between a lone block and the map's edge is their own distance.

    ``gap_width`` at a cell of a 2.05 m opening between a lone block and the map's
    lower edge: the two walls' own distance (shapely), not twice the cell centre's
    distance to the nearer one.
    """
    from rrtdrive.planning.diagnosis.measures import gap_width

    block = Obstacle((30.0, 2.05 + 2.0), (1.0, 4.0))  # 2.05 m above the lower edge
    m = Map("lone", (0.0, 0.0, 60.0, 30.0), (block,), Pose(10.0, 15.0, 0.0),
            Pose(50.0, 15.0, 0.0))  # fmt: skip
    checker = _problem(m).checker
    cell = grid_cell(checker, (30.0, 1.0))
    x, y = (float(v) for v in cell_centres(checker, *cell))
    exact = block.polygon().distance(shapely.box(*m.bounds).exterior)
    assert exact == pytest.approx(2.05)
    assert 2.0 * min(y, block.polygon().distance(shapely.Point(x, y))) < exact - 0.02
    assert gap_width(checker, x, y) == pytest.approx(exact)


# ------------------------------------------------- the audit's two bugs, fixed


def test_a_24_m_gap_no_tree_edge_crosses_is_named() -> None:
    """A 2.4 m gap that no tree edge crosses is named.

    No swept tree edge crosses a 2.4 m opening (brute force of the edge test), so
    rrt / rrt-connect cannot pass it; ``diagnose`` said nothing (the audit's find): it
    took the gap as wide enough because it is wider than 1.8 + 2 x 0.26 = 2.32 m,
    while the grid may read it up to two grid errors narrower.
    """
    m = _gap_wall(2.4)
    assert not _an_edge_crosses(m)
    assert _an_edge_crosses(_gap_wall(2.5))  # a control: 10 cm more and edges cross
    found = diagnose(_problem(m))
    assert found is not None and found.kind is DiagnosisKind.NARROW_PASSAGE


def test_a_183_m_gap_beside_the_maps_edge_is_not_narrower_than_the_car() -> None:
    """A 1.83 m gap beside the map's edge is not called narrower than the car.

    A block from the top edge down leaves a 1.83 m opening above the lower edge
    (shapely). Hybrid A*'s need is 1.90 m, so it is a narrow passage; the diagnosis
    read 1.76 m and said "narrower than the car (1.80 m)", which the car is not (the
    audit's find: the bounds' outline was one wall, 0 m from the block at the top).
    """
    gap = 1.83
    block = Obstacle((30.0, (gap + 30.0) / 2), (1.0, 30.0 - gap))
    m = Map("g", (0.0, 0.0, 60.0, 30.0), (block,), Pose(10.0, 15.0, 0.0), Pose(50.0, 15.0, 0.0))
    exact = block.polygon().distance(shapely.LineString([(0.0, 0.0), (60.0, 0.0)]))
    assert exact == pytest.approx(gap)
    found = diagnose(_problem(m), tree_edges=False)
    assert found is not None and found.kind is DiagnosisKind.NARROW_PASSAGE
    assert found.numbers["width_m"] == pytest.approx(exact, abs=1e-6)
    assert "narrower than the car" not in found.message


# ---------------------------------------------------------------------- u-turn


def test_headings_either_side_of_pi_are_no_u_turn() -> None:
    """Headings either side of pi, 0.1 rad apart, need no U-turn.

    Start heading pi - 0.05 rad, goal 7 m ahead of it heading -pi + 0.05: both face
    -x, 0.1 rad apart (by hand), so a 4 m street needs no U-turn for it, however the two
    yaws are written.
    """
    from rrtdrive.planning.diagnosis.checks import goal_behind, u_turn

    start, goal = Pose(15.0, 2.0, math.pi - 0.05), Pose(8.0, 2.0, -math.pi + 0.05)
    m = Map("corridor", (0.0, 0.0, 30.0, 4.0), (), start, goal)
    heading = np.array([math.cos(start.yaw), math.sin(start.yaw)])
    assert float(np.dot(np.subtract(goal.xy, start.xy), heading)) > 6.9  # ahead
    assert goal_behind(start, goal) is None
    assert u_turn(m, _problem(m).checker, start, goal) is None
    # A control: the same street with the goal turned round is one.
    turned = Pose(8.0, 2.0, 0.0)
    found = u_turn(m, _problem(m).checker, start, turned)
    assert found is not None and found.kind is DiagnosisKind.U_TURN


def test_a_goal_behind_facing_back_is_not_said_to_face_the_same_way() -> None:
    """A goal 7 m behind the start and turned round (pi apart, by hand).

    It is a U-turn in a 4 m corridor; the sentence for a goal behind facing the same way
    would be false, and the finding opens with the street.
    """
    start, goal = Pose(15.0, 2.0, 0.0), Pose(8.0, 2.0, math.pi)
    m = Map("corridor", (0.0, 0.0, 30.0, 4.0), (), start, goal)
    found = diagnose(_problem(m))
    assert found is not None and found.kind is DiagnosisKind.U_TURN, found
    assert "facing the same way" not in found.message
    assert found.message.startswith("the street at (")
    assert "behind_m" not in found.numbers


def test_needs_reverse_names_the_wall_that_stops_the_start() -> None:
    """The wall 0.4 m ahead of the start is obstacle 1 (a block far away is obstacle 0).

    The number and the sentence name the one the body meets when driven 0.05 m past the
    reported gap (shapely), not obstacle 0.
    """
    start = Pose(20.0, 10.0, 0.0)
    far = Obstacle((55.0, 2.0), (2.0, 2.0))
    wall = Obstacle((20.0 + F + 0.4 + 0.5, 10.0), (1.0, 20.0))
    m = Map("wall", (0.0, 0.0, 60.0, 20.0), (far, wall), start, Pose(10.0, 10.0, math.pi))
    found = diagnose(_problem(m))
    assert found is not None and found.kind is DiagnosisKind.NEEDS_REVERSE, found
    gap = found.numbers["straight_gap_m"]
    past = footprint_polygon((start.x + gap + 0.05, start.y, 0.0), CAR)
    hit = [i for i, o in enumerate(m.obstacles) if past.intersects(o.polygon())]
    assert hit == [1]
    assert found.numbers["obstacle"] == 1
    cx, cy = wall.center
    assert f"the start has obstacle 1 at ({cx:.1f}, {cy:.1f}) 0.40 m ahead of its nose" in (
        found.message
    )


def _pocket_ahead() -> Map:
    """A start facing into a 3 m dead-end corridor, its nose 7.6 m from the closed end."""
    walls = (Obstacle((32.5, 12.0), (15.0, 1.0)), Obstacle((32.5, 8.0), (15.0, 1.0)))
    return Map("pocket", (0.0, 0.0, 40.0, 20.0), walls, Pose(29.0, 10.0, 0.0),
               Pose(5.0, 10.0, math.pi))  # fmt: skip


def test_with_reverse_no_exhausted_forward_search_says_try_reverse() -> None:
    """``start_exhausted`` is a forward-only proof: with reverse allowed it is no finding.

    Forward only, the pocket ahead (7.6 m by hand, under 10 m) is named with the advice to
    reverse (a control); with reversing allowed that advice is no answer.
    """
    m = _pocket_ahead()
    forward = diagnose(_problem(m), start_exhausted=True)
    assert forward is not None and forward.kind is DiagnosisKind.NEEDS_REVERSE, forward
    assert forward.numbers["room_ahead_m"] < 10.0
    found = diagnose(_problem(m, reverse=True), start_exhausted=True)
    assert found is None or "try --reverse" not in found.message, found.message


# ---------------------------------------------------------------------- which finding first


def _side_block(pose: Pose, gap: float) -> Obstacle:
    """A 6 m block ``gap`` beside the left of the body of a car at ``pose`` heading +x."""
    return Obstacle((pose.x + 1.255, pose.y + 0.9 + gap + 0.5), (6.0, 1.0))


def test_no_room_ahead_is_named_before_a_tight_clearance_at_the_start() -> None:
    """A start 2 m from a wall ahead and 0.08 m from a block beside it.

    Both hold (the tight clearance is checked alone as a control), but the room at the
    ends comes first: under a car length ahead on every steady steering, which no planner
    option mends, while --reverse does.
    """
    from rrtdrive.planning.diagnosis.checks import tight_clearance

    start = Pose(20.0, 10.0, 0.0)
    wall = Obstacle((20.0 + F + 2.0 + 0.5, 10.0), (1.0, 20.0))
    m = Map("nook", (0.0, 0.0, 60.0, 20.0), (wall, _side_block(start, 0.08)), start,
            Pose(5.0, 5.0, math.pi))  # fmt: skip
    checker = _problem(m).checker
    # The reference for the control: the body drives 0.5 m (shapely), yet no 0.5 m edge
    # leaves or reaches the start in any direction (the checker's own edge test).
    moved = footprint_polygon((start.x + 0.5, start.y, 0.0), CAR)
    assert not moved.intersects(shapely.union_all([o.polygon() for o in m.obstacles]))
    here = np.array(start.xy)
    assert not any(
        checker.edge_free(here, here + 0.5 * np.array([math.cos(a), math.sin(a)]))
        or checker.edge_free(here + 0.5 * np.array([math.cos(a), math.sin(a)]), here)
        for a in np.radians(np.arange(0.0, 360.0, 5.0))
    )
    assert tight_clearance(m, checker, start, m.goal) is not None
    found = diagnose(_problem(m))
    assert found is not None and found.kind is DiagnosisKind.NEEDS_REVERSE, found
    gap = footprint_polygon(start.as_tuple(), CAR).distance(wall.polygon())
    assert found.numbers["straight_gap_m"] == pytest.approx(gap, abs=2e-3)


def test_a_proven_pocket_behind_the_goal_is_named_before_the_u_turn() -> None:
    """A 4 m street 60 m long: the goal, turned round, has 5 m behind its rear (by hand).

    Forward, the car can neither turn round here (a U-turn finding) nor come into the
    goal from behind; with the search's proof (``no_approach``) the pocket is named first.
    """
    from rrtdrive.planning.diagnosis.checks import u_turn

    goal = Pose(60.0 - B - 5.0, 2.0, math.pi)
    m = Map("street", (0.0, 0.0, 60.0, 4.0), (), Pose(10.0, 2.0, 0.0), goal)
    assert u_turn(m, _problem(m).checker, m.start, goal) is not None
    found = diagnose(_problem(m), no_approach=True)
    assert found is not None and found.kind is DiagnosisKind.NEEDS_REVERSE, found
    assert found.numbers["room_behind_m"] == pytest.approx(5.0, abs=2e-3)
    assert found.numbers["obstacle"] == -1  # the map's edge
    assert "(the map's edge 5.00 m behind its rear)" in found.message


def test_both_ends_at_fault_the_start_is_named_first() -> None:
    """Both bodies overlap a wall, or both sit 0.08 m from a block: the start is named."""
    start, goal = Pose(20.0, 10.0, 0.0), Pose(40.0, 10.0, 0.0)
    into = tuple(Obstacle((p.x + F - 0.2 + 0.5, 10.0), (1.0, 4.0)) for p in (start, goal))
    m = Map("walls", (0.0, 0.0, 60.0, 20.0), into, Pose(10.0, 10.0, 0.0), Pose(50.0, 3.0, 0.0))
    p = _problem(m)
    found = diagnose(PlanningProblem(m, p.checker, start, goal, m.vehicle))
    assert found is not None and found.kind is DiagnosisKind.BODY_COLLIDES, found
    assert found.message.startswith("the start's body")
    beside = tuple(_side_block(q, 0.08) for q in (start, goal))
    m = Map("blocks", (0.0, 0.0, 60.0, 20.0), beside, start, goal)
    found = diagnose(_problem(m))
    assert found is not None and found.kind is DiagnosisKind.TIGHT_CLEARANCE, found
    cx, cy = beside[0].center
    assert found.message.startswith(f"the start's body is 0.08 m from obstacle 0 at ({cx:.1f}, ")
