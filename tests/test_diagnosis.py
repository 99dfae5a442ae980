"""Failure diagnosis: each finding on a small map built here, its numbers against shapely."""

from __future__ import annotations

import dataclasses
import json
import math
from dataclasses import dataclass

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

from rrtdrive.cli import main, plan_to_json
from rrtdrive.maps import Map, Obstacle, builtin_map, save_map
from rrtdrive.planning import make_planner
from rrtdrive.planning.base import PlanningProblem
from rrtdrive.planning.diagnosis import (
    Diagnosis,
    DiagnosisKind,
    diagnose,
    edge_keep,
    end_keep,
    free_run,
    street_width,
    u_turn_width,
)
from rrtdrive.types import Budget, Pose, VehicleParams
from rrtdrive.vehicle import footprint_polygon

CAR = VehicleParams()
F, B = CAR.front_extent, CAR.rear_overhang


@dataclass(frozen=True, eq=False)
class ReverseProblem(PlanningProblem):
    """A problem that allows reversing (until PlanningProblem has the field itself)."""

    reverse: bool = True


def problem(m: Map) -> PlanningProblem:
    return PlanningProblem.from_map(m)


def wall_map(gap_ahead: float | None = None, gap_behind: float | None = None) -> Map:
    """A 60 x 20 m room; the start at (20, 10) heading +x, walls across at the given gaps."""
    obstacles = []
    if gap_ahead is not None:
        obstacles.append(Obstacle((20.0 + F + gap_ahead + 0.5, 10.0), (1.0, 20.0)))
    if gap_behind is not None:
        obstacles.append(Obstacle((20.0 - B - gap_behind - 0.5, 10.0), (1.0, 20.0)))
    obstacles.append(Obstacle((55.0, 2.0), (2.0, 2.0)))  # a far-away block
    return Map("walls", (0.0, 0.0, 60.0, 20.0), tuple(obstacles), Pose(20.0, 10.0, 0.0),
               Pose(10.0, 10.0, math.pi) if gap_ahead else Pose(35.0, 10.0, 0.0))


def test_start_facing_a_wall_needs_reverse_with_the_gap_shapely_measures():
    m = wall_map(gap_ahead=0.4)
    found = diagnose(problem(m))
    assert found.kind is DiagnosisKind.NEEDS_REVERSE
    body = footprint_polygon(m.start.as_tuple(), CAR)
    gap = body.distance(m.obstacles[0].polygon())
    assert gap == pytest.approx(0.4, abs=1e-9)
    assert found.numbers["straight_gap_m"] == pytest.approx(gap, abs=2e-3)
    assert found.numbers["straight_gap_m"] <= gap  # a lower bound
    assert found.numbers["obstacle"] == 0
    cx, cy = m.obstacles[0].center  # named with its centre, as the map file gives it
    assert f"obstacle 0 at ({cx:.1f}, {cy:.1f}) 0.40 m ahead of its nose" in found.message
    assert "can only be left in reverse (try --reverse)" in found.message


def test_goal_backing_onto_a_wall_can_only_be_reached_in_reverse():
    wall = Obstacle((30.0 - B - 0.3 - 0.5, 10.0), (1.0, 20.0))
    m = Map("bay", (0.0, 0.0, 60.0, 20.0), (wall,), Pose(45.0, 10.0, math.pi),
            Pose(30.0, 10.0, 0.0))
    found = diagnose(problem(m))
    assert found.kind is DiagnosisKind.NEEDS_REVERSE
    gap = footprint_polygon(m.goal.as_tuple(), CAR).distance(wall.polygon())
    assert found.numbers["straight_gap_m"] == pytest.approx(gap, abs=2e-3)
    assert "0.30 m behind its rear" in found.message
    assert "it can only be reached in reverse" in found.message
    # With reversing allowed the wall is no constraint any more.
    rev = ReverseProblem(m, problem(m).checker, m.start, m.goal, m.vehicle)
    again = diagnose(rev)
    assert again is None or again.kind is not DiagnosisKind.NEEDS_REVERSE


def test_boxed_in_between_two_walls():
    walls = wall_map(gap_ahead=0.5, gap_behind=0.6)
    # Walls 16 m long in the 20 m room: 2 m ways round both ends join start and goal.
    short = tuple(Obstacle(o.center, (1.0, 16.0)) for o in walls.obstacles[:2])
    m = dataclasses.replace(walls, obstacles=short + walls.obstacles[2:])
    found = diagnose(problem(m))
    assert found.kind is DiagnosisKind.BOXED_IN
    assert found.numbers["room_ahead_m"] == pytest.approx(0.5, abs=2e-3)
    assert found.numbers["room_behind_m"] == pytest.approx(0.6, abs=2e-3)
    assert "boxed in" in found.message and "at least one gear change" in found.message
    assert found.message.endswith("(try --reverse)")
    # With reverse allowed the search had gear changes: saying it needs one told nothing.
    rev = diagnose(PlanningProblem.from_map(m, reverse=True), tree_edges=False)
    assert rev.kind is DiagnosisKind.BOXED_IN and rev.numbers == found.numbers
    assert rev.message.endswith("short moves with gear changes in that room, and the search "
                                "found none that fits")


def test_walled_off_comes_before_the_room_at_the_ends():
    # The walls span the room: the goal lies beyond one. "Boxed in ... (try --reverse)"
    # was true of the start but no gear change reaches that goal.
    m = wall_map(gap_ahead=0.5, gap_behind=0.6)
    for p in (problem(m), ReverseProblem(m, problem(m).checker, m.start, m.goal, m.vehicle)):
        found = diagnose(p)
        assert found.kind is DiagnosisKind.WALLED_OFF
        assert found.message == "the goal is walled off from the start: no gap connects them"


def test_tight_clearance_only_for_planners_of_tree_edges_alone():
    # A block 0.08 m beside the goal's body stops every tree edge, not Hybrid A*: not
    # its diagnosis.
    side = Obstacle((30.0 + 1.255, 10.0 + 0.9 + 0.08 + 0.5), (6.0, 1.0))
    m = Map("side", (0.0, 0.0, 60.0, 20.0), (side,), Pose(5.0, 10.0, 0.0), Pose(30.0, 10.0, 0.0))
    assert diagnose(problem(m)).kind is DiagnosisKind.TIGHT_CLEARANCE
    assert diagnose(problem(m), tree_edges=False) is None


def test_free_run_matches_the_shapely_gap_on_straights():
    m = wall_map(gap_ahead=1.234)
    checker = problem(m).checker
    run = free_run(checker, m.start, 1, 0.0, 5.0)
    assert run == pytest.approx(1.234, abs=1.5e-3) and run <= 1.234
    assert free_run(checker, m.start, -1, 0.0, 5.0) == 5.0  # nothing behind within 5 m


@settings(max_examples=15, deadline=None)
@given(gap=st.floats(0.05, 3.0), yaw=st.floats(-0.3, 0.3))
def test_free_run_is_a_tight_lower_bound_of_the_shapely_run(gap, yaw):
    # A wall square to the x axis, ``gap`` ahead of the body of a car turned by ``yaw``
    # (of its foremost corner: placed by the unturned nose, a turned car's corner overlapped
    # the wall for a small gap; the stress profile found gap 0.0625, yaw 0.25): the straight
    # run until the body touches is the shapely distance along the heading.
    body = footprint_polygon((20.0, 10.0, yaw), CAR)
    wall = Obstacle((body.bounds[2] + gap + 0.5, 10.0), (1.0, 20.0))
    m = Map("w", (0.0, 0.0, 60.0, 20.0), (wall,), Pose(20.0, 10.0, yaw), Pose(10.0, 10.0, 0.0))
    checker = problem(m).checker
    run = free_run(checker, m.start, 1, 0.0, 5.0)
    # Moving along the heading, the body's leading corner closes the x gap at cos(yaw).
    truth = min(body.distance(wall.polygon()) / math.cos(yaw), 5.0)
    assert truth - 2e-3 <= run <= truth + 1e-9


def test_tight_clearance_names_the_obstacle_and_the_edge_tests_keep():
    # A block 0.08 m beside the goal's body, parallel to it.
    goal = Pose(30.0, 10.0, 0.0)
    side = Obstacle((30.0 + 1.255, 10.0 + 0.9 + 0.08 + 0.5), (6.0, 1.0))
    m = Map("side", (0.0, 0.0, 60.0, 20.0), (Obstacle((55.0, 2.0), (2.0, 2.0)), side),
            Pose(5.0, 10.0, 0.0), goal)
    found = diagnose(problem(m))
    assert found.kind is DiagnosisKind.TIGHT_CLEARANCE
    gap = footprint_polygon(goal.as_tuple(), CAR).distance(side.polygon())
    assert found.numbers["gap_m"] == pytest.approx(gap, abs=1e-9)
    assert found.numbers["obstacle"] == 1
    assert found.numbers["keep_m"] == pytest.approx(edge_keep(problem(m).checker))
    assert found.message.startswith(
        f"the goal's body is 0.08 m from obstacle 1 at ({side.center[0]:.1f}, "
        f"{side.center[1]:.1f}); this planner's straight tree edges keep"
    )


def test_goal_nose_near_a_wall_defeats_one_edge_test_not_every_edge():
    # The garage case: the nose 0.5 m from the wall, less than the edge test's end keep,
    # so the edge along the heading into the goal fails; but edges from behind at 45 deg
    # pass, and so do edges driven out of the goal (rrt-connect's goal tree reaches the
    # start): "so none reaches it" would be false, and no such finding is made (session
    # 40; it was, from the one edge along the heading).
    checker = problem(wall_map(gap_ahead=0.5)).checker
    assert 0.5 < end_keep(checker) < 1.0
    wall = Obstacle((30.0 + F + 0.5 + 0.5, 10.0), (1.0, 20.0))
    m = Map("nose", (0.0, 0.0, 60.0, 20.0), (wall,), Pose(5.0, 10.0, 0.0), Pose(30.0, 10.0, 0.0))
    edges = problem(m).checker
    goal = m.goal.xy
    assert not edges.edge_free(goal - (0.5, 0.0), goal)  # along the heading: fails
    behind_45 = goal - 0.5 * np.array([math.cos(math.pi / 4), math.sin(math.pi / 4)])
    assert edges.edge_free(behind_45, goal) and edges.edge_free(goal, goal - (0.5, 0.0))
    assert diagnose(problem(m)) is None
    solved = make_planner("rrt-connect").solve(problem(m), np.random.default_rng(0), Budget())
    assert solved.success
    # The swept capsule's round end pokes r - sqrt(r^2 - (W/2)^2) past the bumper (shapely).
    r = checker.edge_radius
    capsule = shapely.LineString([(0.0, 0.0), (10.0, 0.0)]).buffer(r)
    beyond = capsule.bounds[2] - 10.0 - math.sqrt(r * r - 0.81)
    assert end_keep(checker) - checker.grid_error - checker.config.min_trace_step == (
        pytest.approx(beyond, abs=1e-3)
    )
    # A wall beyond the keep is no finding of this kind.
    far = Obstacle((30.0 + F + end_keep(checker) + 0.1 + 0.5, 10.0), (1.0, 20.0))
    m2 = Map("far", m.bounds, (far,), m.start, m.goal)
    assert diagnose(problem(m2)) is None


def gap_wall_map(gap: float) -> Map:
    """A wall across x = 30 with one opening ``gap`` wide centred on y = 10."""
    low = 10.0 - gap / 2
    high = 10.0 + gap / 2
    wall = (
        Obstacle((30.0, low / 2), (1.0, low)),
        Obstacle((30.0, (high + 20.0) / 2), (1.0, 20.0 - high)),
    )
    return Map("gap", (0.0, 0.0, 60.0, 20.0), wall, Pose(10.0, 10.0, 0.0), Pose(50.0, 10.0, 0.0))


def test_narrow_passage_located_and_measured():
    m = gap_wall_map(2.1)
    found = diagnose(problem(m))
    assert found.kind is DiagnosisKind.NARROW_PASSAGE
    x, y = found.numbers["x"], found.numbers["y"]
    assert abs(x - 30.0) < 1.0 and abs(y - 10.0) < 0.5
    walls = shapely.union_all([o.polygon() for o in m.obstacles])
    # The gap's own width (the two walls' distance), not twice the distance from the
    # grid cell's centre, which lies up to half a cell off the centre line (2.00 here).
    assert found.numbers["width_m"] == pytest.approx(2.1)
    assert found.numbers["width_m"] >= 2 * shapely.Point(x, y).distance(walls)
    assert found.numbers["width_m"] <= 2.1 + 1e-9 and found.numbers["width_m"] > 1.8
    assert found.numbers["needed_m"] == pytest.approx(1.8 + 2 * edge_keep(problem(m).checker))
    assert "tree edges need at least" in found.message
    # For Hybrid A* (or the default, which escalates to it) the gap must leave the body its
    # least clearance, 0.05 m, each side: 2.1 m is no finding; 1.85 m is, with that need
    # (it said "tree edges need at least 2.32 m", a planner without tree edges; an audit).
    assert diagnose(problem(m), tree_edges=False) is None
    hybrid = diagnose(problem(gap_wall_map(1.85)), tree_edges=False)
    assert hybrid.kind is DiagnosisKind.NARROW_PASSAGE
    assert hybrid.numbers["needed_m"] == pytest.approx(1.9) and "tree edge" not in hybrid.message
    # A gap narrower than the car, and none at all.
    assert "narrower than the car" in diagnose(problem(gap_wall_map(1.5))).message
    no_path = diagnose(problem(builtin_map("no_path")))
    assert no_path.kind is DiagnosisKind.WALLED_OFF and no_path.numbers["width_m"] == 0.0
    # A gap the edge test passes is no finding.
    assert diagnose(problem(gap_wall_map(3.0))) is None


def staggered_gap_map(gap: float) -> Map:
    """A wall from below and one from above, overlapping nowhere: ``gap`` apart sideways.

    A third wall beside the upper one leaves a 0.3 m slit (a decoy). From an audit's map:
    its 1.85 m gap was reported as "the passage near (0.9, 0.9) is 1.70 m wide; narrower
    than the car" (the map's corner, where the grid's clearance equals the gap's).
    """
    walls = (
        Obstacle((19.5, 4.5), (1.0, 9.0)),
        Obstacle((20.0 + gap + 0.7, 14.5), (1.4, 11.0)),
        Obstacle((20.0 + gap + 2.2, 15.0), (1.0, 10.0)),
    )
    ends = Pose(5.0, 10.0, 0.0), Pose(35.0, 10.0, 0.0)
    return Map("stagger", (0.0, 0.0, 40.0, 20.0), walls, *ends)


@pytest.mark.parametrize("gap", [0.6, 1.0, 1.85])
def test_a_staggered_gap_is_found_where_it_is(gap: float) -> None:
    m = staggered_gap_map(gap)
    found = diagnose(problem(m), tree_edges=False)
    assert found.kind is DiagnosisKind.NARROW_PASSAGE, found.message
    lower, upper = (m.obstacles[0].polygon(), m.obstacles[1].polygon())
    assert found.numbers["width_m"] == pytest.approx(lower.distance(upper))
    # Between the lower wall's top right corner and the upper wall's bottom left one.
    pass_centre = shapely.Point(20.0 + gap / 2, 9.0)
    assert shapely.Point(found.numbers["x"], found.numbers["y"]).distance(pass_centre) < 0.5
    assert ("narrower than the car" in found.message) is (gap < 1.8)


def test_a_gap_too_narrow_for_the_grid_is_not_called_no_gap() -> None:
    m = staggered_gap_map(0.3)
    found = diagnose(problem(m), tree_edges=False)
    assert found.kind is DiagnosisKind.WALLED_OFF
    free = shapely.box(*m.bounds).difference(shapely.union_all([o.polygon() for o in m.obstacles]))
    assert isinstance(free, shapely.Polygon)  # one piece: a 0.3 m gap joins start and goal
    assert found.message.startswith("the goal is cut off from the start: the only gaps")
    assert "no gap connects them" not in found.message


def test_u_turn_width_is_the_swept_strip_of_a_tightest_half_circle():
    r = CAR.min_turning_radius
    yaws = np.linspace(0.0, math.pi, 721)
    # Left turn about (0, r) from the origin heading +x.
    poses = np.column_stack([r * np.sin(yaws), r - r * np.cos(yaws), yaws])
    swept = shapely.union_all([footprint_polygon(tuple(p), CAR) for p in poses])
    _, ymin, _, ymax = swept.bounds
    assert u_turn_width(CAR) == pytest.approx(ymax - ymin, abs=2e-3)


def street_map(width: float = 10.0) -> Map:
    """A dead-end street along x, ``width`` wide, closed at both ends by the bounds."""
    walls = (
        Obstacle((40.0, 5.0 - 0.5), (80.0, 1.0)),
        Obstacle((40.0, 5.0 + width + 0.5), (80.0, 1.0)),
    )
    mid = 5.0 + width / 2
    return Map("street", (0.0, 0.0, 80.0, width + 10.0), walls, Pose(10.0, mid - 2.5, 0.0),
               Pose(30.0, mid + 2.5, math.pi))


@pytest.mark.parametrize("width", [14.6, 14.9])
def test_u_turn_in_a_street_a_last_resort_turn_may_fit_says_so(width: float) -> None:
    # Keeping 0.15 m each side a forward U-turn needs 14.95 m; keeping the last resort's
    # 0.05 m, 14.75 m: in a 14.9 m street an audit's forward path keeping 0.105 m passed
    # verify, and the line implied there was none.
    found = diagnose(problem(street_map(width)))
    assert found.kind is DiagnosisKind.U_TURN
    least = u_turn_width(CAR) + 2 * 0.05
    may_fit = "one may fit that the search missed" in found.message
    assert may_fit is (width >= least)
    assert ("needed_least_m" in found.numbers) is may_fit
    if may_fit:
        assert found.numbers["needed_least_m"] == pytest.approx(least)
        assert f"a U-turn needs {least:.2f} m" in found.message


def test_a_proof_from_the_goal_is_named_only_for_a_pocket_behind_it() -> None:
    # A 15.2 m street: the goal across it, facing back, has 30 m and more behind it. The
    # search's exhaustion from the goal was reported as "it can only be reached in
    # reverse"; an audit's forward path keeping 0.25 m passed verify. A goal in a pocket
    # (less than 20 m behind on every steady steering) keeps its line (goal 75 above, and
    # the corridor below).
    m = Map("wide street", (0.0, 0.0, 80.0, 15.2), (), Pose(10.0, 1.2, 0.0),
            Pose(10.0, 14.0, math.pi))
    found = diagnose(problem(m), no_approach=True)
    assert found is None or found.kind is not DiagnosisKind.NEEDS_REVERSE, found.message
    # A dead-end corridor 3 m wide, the goal facing out 10.1 m from its closed end: its
    # line was lost when the pocket ended at 10 m (a regression audit).
    walls = (Obstacle((32.5, 12.0), (15.0, 1.0)), Obstacle((32.5, 8.0), (15.0, 1.0)))
    corridor = Map("corridor", (0.0, 0.0, 40.0, 20.0), walls, Pose(5.0, 10.0, 0.0),
                   Pose(29.0, 10.0, math.pi))
    found = diagnose(problem(corridor), no_approach=True)
    assert found.kind is DiagnosisKind.NEEDS_REVERSE, found
    assert found.numbers["room_behind_m"] == pytest.approx(10.1, abs=0.02)


def test_u_turn_in_a_narrow_street():
    m = street_map(10.0)
    found = diagnose(problem(m))
    assert found.kind is DiagnosisKind.U_TURN
    assert found.numbers["street_width_m"] == pytest.approx(10.0, abs=1e-9)
    # The swept strip plus the planners' 0.15 m each side (a 14.8 m street got no word).
    assert found.numbers["needed_m"] == pytest.approx(u_turn_width(CAR) + 0.30)
    assert found.numbers["widest_m"] < u_turn_width(CAR)
    # The widest place is the street's own width (a disc across it), measured exactly:
    # the distance field's value read dead_end's 7.5 m street as 7.4 m.
    assert found.numbers["widest_m"] == pytest.approx(10.0, abs=0.02)
    assert found.message.startswith("the street at (11.3, 7.5) is 10.0 m wide; a forward U-turn "
                                    "keeping 0.15 m each side needs 15.0 m; no place reachable "
                                    "from the start is wider")
    centre = shapely.Point(found.numbers["x"], found.numbers["y"])
    across = sum(centre.distance(o.polygon()) for o in m.obstacles)
    assert found.numbers["street_width_m"] == pytest.approx(across, abs=1e-9)
    assert street_width(m, (centre.x, centre.y), 0.0) == found.numbers["street_width_m"]
    # A street wide enough for the turn is no finding.
    assert diagnose(problem(street_map(16.0))) is None


def test_the_street_width_is_across_the_street_not_the_car(tmp_path):
    # A car at 0.5 rad to a 10 m street read "11.4 m wide" (10 / cos 0.5) beside "no place
    # wider than 10.0 m" (a helper's audit, session 34). Shapely's reference: the two walls'
    # distance.
    m = street_map(10.0)
    tilted = dataclasses.replace(m, start=Pose(m.start.x, m.start.y, 0.5))
    found = diagnose(problem(tilted))
    assert found.kind is DiagnosisKind.U_TURN
    walls = [o.polygon() for o in m.obstacles]
    assert found.numbers["street_width_m"] == pytest.approx(walls[0].distance(walls[1]), abs=0.01)


@pytest.mark.parametrize("width", [14.8, 14.9])
def test_a_street_wider_than_the_bare_u_turn_but_not_with_clearance_is_named(width):
    found = diagnose(problem(street_map(width)))
    assert found is not None and found.kind is DiagnosisKind.U_TURN, found
    assert found.numbers["street_width_m"] < found.numbers["needed_m"]


def test_a_place_too_small_to_turn_round_in_is_not_offered():
    # An 8 m street opening into a 15 m square: wider than the street's U-turn strip, but
    # a round place has no street to swing the rear into; the front corner's circle,
    # 2 hypot(R + W/2, front) + 2 x 0.15 = 15.69 m, does not fit ("drive to a wider
    # place" sent the car where Hybrid A* finds no turn either; a helper's audit).
    walls = (Obstacle((15.0, 1.75), (30.0, 3.5)), Obstacle((15.0, 13.25), (30.0, 3.5)))
    m = Map("plaza", (0.0, 0.0, 45.0, 15.0), walls, Pose(5.0, 5.5, 0.0), Pose(10.0, 9.5, math.pi))
    found = diagnose(problem(m))
    assert found.kind is DiagnosisKind.U_TURN
    assert found.numbers["widest_m"] == pytest.approx(15.0, abs=0.02)
    v = m.vehicle
    circle = 2 * math.hypot(v.min_turning_radius + v.width / 2, v.front_extent) + 0.30
    assert found.numbers["turning_circle_m"] == pytest.approx(circle)
    assert "wider place" not in found.message and found.message.endswith("(try --reverse)")


def test_a_wide_place_behind_the_car_is_not_where_it_can_drive_forward():
    # Facing into an 8 m dead end with a plaza behind it: "first drive to a wider place"
    # sent the car to the plaza it can only reach by the turn it cannot make.
    walls = (Obstacle((42.5, 5.5), (35.0, 11.0)), Obstacle((42.5, 24.5), (35.0, 11.0)))
    m = Map("plaza_behind", (0.0, 0.0, 60.0, 30.0), walls, Pose(40.0, 13.0, 0.0),
            Pose(35.0, 17.0, math.pi))  # fmt: skip
    found = diagnose(problem(m))
    assert found.kind is DiagnosisKind.U_TURN
    assert found.numbers["widest_x"] < 40.0  # the plaza, behind the start
    assert "lies behind the car (try --reverse)" in found.message
    assert "first drive to a wider place" not in found.message


def test_the_widest_place_is_measured_not_bounded():
    # A 14.9 m box: the widest place was "about 15.0 m across" (the distance field plus its
    # grid error, an upper bound), which also took the wrong branch of the message.
    m = Map("box", (0.0, 0.0, 40.0, 14.9), (), Pose(22.0, 7.45, 0.0), Pose(14.0, 7.45, math.pi))
    found = diagnose(problem(m))
    assert found.kind is DiagnosisKind.U_TURN
    assert found.numbers["widest_m"] == pytest.approx(14.9, abs=2e-3)
    assert "no place reachable from the start is wider than 14.9 m" in found.message


def test_the_clearance_the_diagnosis_assumes_is_the_planners():
    from rrtdrive.planning.diagnosis.checks import BODY_CLEARANCE, MIN_CLEARANCE
    from rrtdrive.planning.hybrid import HybridConfig
    from rrtdrive.planning.improved import ImprovedConfig

    assert BODY_CLEARANCE == ImprovedConfig().body_clearance == HybridConfig().body_clearance
    assert MIN_CLEARANCE == HybridConfig().min_clearance


def test_with_reverse_a_narrow_gap_is_named_before_a_boxed_start():
    # A start parked between two cars (boxed in) behind a 1.85 m gap: with --reverse the
    # car backs out of the box, and the gap stops it; it was told "boxed in" again.
    obstacles = (
        Obstacle((25.0, 0.4), (50.0, 0.8)), Obstacle((17.055, 2.0), (4.3, 1.8)),
        Obstacle((5.455, 2.0), (4.3, 1.8)), Obstacle((30.0, 7.4375), (10.0, 13.275)),
        Obstacle((30.0, 22.9625), (10.0, 14.075)),
    )  # fmt: skip
    m = Map("boxed_gap", (0.0, 0.0, 50.0, 30.0), obstacles, Pose(10.0, 2.0, 0.0),
            Pose(45.0, 15.0, 0.0))  # fmt: skip
    assert diagnose(problem(m)).kind is DiagnosisKind.BOXED_IN  # forward: the box first
    reversing = PlanningProblem.from_map(m, reverse=True)
    found = diagnose(reversing, tree_edges=False)
    assert found.kind is DiagnosisKind.NARROW_PASSAGE, found
    assert found.numbers["width_m"] == pytest.approx(1.85, abs=1e-6)


def test_steady_steering_is_tried_between_the_five_arcs():
    # Two posts behind the goal block the straight, half and full lock arcs back from it,
    # not a quarter lock: the goal is reachable forward, so no "only in reverse" (the old
    # five arcs said "at most 4.22 m on any steady steering").
    posts = (Obstacle((19.9, 14.0), (0.3, 0.3)), Obstacle((20.1, 16.8), (0.3, 0.3)))
    m = Map("posts", (0.0, 0.0, 40.0, 30.0), posts, Pose(5.0, 15.0, 0.0), Pose(25.0, 15.0, 0.0))
    found = diagnose(problem(m))
    assert found is None or found.kind is not DiagnosisKind.NEEDS_REVERSE, found


def corridor(width: float = 4.0, goal_x: float = 8.0, goal_yaw: float = 0.0) -> Map:
    """A straight corridor 30 m long, the start in its middle heading +x, the goal behind."""
    return Map("corridor", (0.0, 0.0, 30.0, width), (), Pose(15.0, width / 2, 0.0),
               Pose(goal_x, width / 2, goal_yaw))  # fmt: skip


def test_a_goal_behind_in_a_corridor_too_narrow_to_turn_round(tmp_path, capsys):
    m = corridor()
    found = diagnose(problem(m))
    assert found.kind is DiagnosisKind.U_TURN
    behind = shapely.Point(m.start.x, m.start.y).distance(shapely.Point(m.goal.x, m.goal.y))
    assert found.numbers["behind_m"] == pytest.approx(behind)
    assert found.numbers["street_width_m"] == pytest.approx(4.0, abs=1e-9)
    assert found.message.startswith(
        "the goal is 7.0 m behind the start, facing the same way: driving forward the car "
        "must turn round to reach it (and back); the street at"
    )
    assert found.message.endswith("(try --reverse)")
    # Reversing allowed: not the constraint (and the default drives the 7 m back).
    rev = PlanningProblem.from_map(m, reverse=True)
    assert diagnose(rev) is None
    # The planner's failure carries it to the CLI's why line.
    f = tmp_path / "corridor.json"
    save_map(m, f)
    assert main(["plan", str(f)]) == 1
    out = capsys.readouterr().out
    assert "\n  why: the goal is 7.0 m behind the start" in out


@pytest.mark.parametrize(
    ("width", "goal_x", "goal_yaw"),
    [(16.0, 8.0, 0.0),  # wide enough to turn round
     (4.0, 14.5, 0.0),  # 0.5 m back: not behind
     (4.0, 25.0, 0.0)],  # ahead
)
def test_a_goal_not_behind_or_a_street_wide_enough_is_no_u_turn(width, goal_x, goal_yaw):
    found = diagnose(problem(corridor(width, goal_x, goal_yaw)))
    assert found is None or found.kind is not DiagnosisKind.U_TURN


def test_body_collision_names_the_obstacle():
    m = wall_map(gap_ahead=2.0)
    inside = Pose(20.0 + F + 2.0 + 0.5, 10.0, 0.0)  # rear axle in the wall
    p = problem(m)
    bad = PlanningProblem(m, p.checker, m.start, inside, m.vehicle)
    found = diagnose(bad)
    assert found.kind is DiagnosisKind.BODY_COLLIDES
    assert footprint_polygon(inside.as_tuple(), CAR).intersects(m.obstacles[0].polygon())
    assert found.numbers["obstacle"] == 0 and "goal's body" in found.message


def test_open_query_has_no_finding_and_json_rounds():
    assert diagnose(problem(builtin_map("overtake"))) is None
    d = Diagnosis(DiagnosisKind.U_TURN, "m", {"a": 1.234567})
    assert d.to_json() == {"kind": "u_turn", "message": "m", "numbers": {"a": 1.2346}}


def test_failed_plan_carries_the_diagnosis_into_result_and_json(tmp_path, capsys):
    m = street_map(10.0)
    res = make_planner("improved-rrt-connect").solve(
        problem(m), np.random.default_rng(0), Budget(max_iterations=300, max_time_s=1e6)
    )
    assert not res.success
    assert res.diagnosis is not None and res.diagnosis.kind is DiagnosisKind.U_TURN
    payload = plan_to_json(res, 0, m.name)
    assert payload["diagnosis"]["kind"] == "u_turn"
    assert payload["diagnosis"]["message"] == res.diagnosis.message
    solved = make_planner("improved-rrt-connect").solve(
        problem(builtin_map("overtake")), np.random.default_rng(0), Budget(max_time_s=1e6)
    )
    assert solved.success and solved.diagnosis is None
    assert plan_to_json(solved, 0, "overtake")["diagnosis"] is None
    # The CLI prints it and writes it.
    path = tmp_path / "street.json"
    save_map(m, path)
    code = main(["plan", str(path), "--max-iterations", "300", "--max-time", "1000",
                 "--json", str(tmp_path / "out.json")])
    assert code == 1
    out = capsys.readouterr().out
    assert "why: the street at" in out
    assert json.loads((tmp_path / "out.json").read_text())["diagnosis"]["kind"] == "u_turn"
    # simulate's JSON carries the plan's diagnosis too (it printed the why line only).
    code = main(["simulate", str(path), "--plan-time", "1000", "--json", str(tmp_path / "s.json")])
    assert code == 1 and "why: the street at" in capsys.readouterr().out
    simulated = json.loads((tmp_path / "s.json").read_text())
    assert simulated["diagnosis"]["kind"] == "u_turn"
    assert simulated["diagnosis"]["message"].startswith("the street at")


def test_a_walled_off_goal_beside_a_wall_is_walled_off_not_needs_reverse():
    # The goal 0.10 m from a side wall inside a closed box: the finding was "it can only
    # be reached in reverse (try --reverse)", which no gear change mends.
    box = [Obstacle((30.0, 7.0), (8.0, 0.2)), Obstacle((30.0, 13.0), (8.0, 0.2)),
           Obstacle((26.0, 10.0), (0.2, 6.2)), Obstacle((34.0, 10.0), (0.2, 6.2))]
    inside = Pose(28.0, 7.1 + 0.1 + 0.9, 0.0)  # body 0.10 m from the box's lower wall
    m = Map("box", (0.0, 0.0, 60.0, 20.0), tuple(box), Pose(5.0, 10.0, 0.0), inside)
    found = diagnose(problem(m))
    assert found.kind is DiagnosisKind.WALLED_OFF


def test_a_gap_narrower_than_the_car_comes_before_the_advice_to_reverse():
    # Only a 1.60 m gap leads to a goal whose tail is 0.50 m from the map's edge: it was
    # "it can only be reached in reverse (try --reverse)", which cannot help.
    walls = (Obstacle((20.0, 7.1), (1.0, 14.2)), Obstacle((20.0, 22.9), (1.0, 14.2)))
    m = Map("gap", (0.0, 0.0, 40.0, 30.0), walls, Pose(5.0, 15.0, 0.0),
            Pose(38.605, 15.0, math.pi))
    found = diagnose(problem(m))
    assert found.kind is DiagnosisKind.NARROW_PASSAGE
    assert found.numbers["width_m"] == pytest.approx(1.6)
    assert "narrower than the car" in found.message


def _body_along(pose: Pose, distance: float, vehicle: VehicleParams) -> shapely.Polygon:
    """The body moved ``distance`` metres along ``pose``'s heading (negative: back)."""
    moved = (pose.x + distance * math.cos(pose.yaw), pose.y + distance * math.sin(pose.yaw),
             pose.yaw)  # fmt: skip
    return shapely.Polygon(footprint_polygon(moved, vehicle))


#: The forward failures Hybrid A* proves from one end, with more than a car length of room
#: there (so room_at_ends says nothing): (end, pose, direction of the run measured, its
#: cap, the room's number, the obstacle that stops the straight run, the message's end).
PROVEN_ENDS = [
    # Random goal 75 of coverage.py --count 100 --seed 1 (rounded): facing a bay's back
    # wall with 4.74 m behind it; the search from the goal proves no forward way in.
    ("goal", Pose(9.17, 21.0, 3.0894), -1, 30.0, "room_behind_m", 136, "try --reverse"),
    # Random start 3 (rounded): nose 2 m from a car, 5.33 m ahead on the best steady
    # steering; the search from the start runs out of states.
    ("start", Pose(32.97, 78.84, -1.2366), 1, 10.0, "room_ahead_m", 120,
     "left in reverse (try --reverse)"),
]  # fmt: skip


@pytest.mark.parametrize("planner", ["hybrid-a-star", "improved-rrt-connect"])
@pytest.mark.parametrize(("end", "pose", "direction", "cap", "key", "obstacle", "phrase"),
                         PROVEN_ENDS)  # fmt: skip
def test_a_forward_failure_proven_at_one_end_says_why(
    planner, end, pose, direction, cap, key, obstacle, phrase
):
    # These failures had no why line (sessions 34-35). The room at that end is measured
    # and the proof named; the straight run ends at the obstacle it names (shapely).
    from rrtdrive.planning.diagnosis.measures import best_run

    m = dataclasses.replace(builtin_map("parking_lot"), **{end: pose})
    problem = PlanningProblem.from_map(m)
    result = make_planner(planner).solve(problem, np.random.default_rng(0), Budget())
    assert not result.success and result.diagnosis is not None, result.message
    d = result.diagnosis
    assert d.kind is DiagnosisKind.NEEDS_REVERSE and phrase in d.message
    room = d.numbers[key]
    assert m.vehicle.length < room == pytest.approx(best_run(problem.checker, pose, direction,
                                                             m.vehicle, cap))
    gap, wall = d.numbers["straight_gap_m"], shapely.Polygon(m.obstacles[obstacle].corners())
    assert d.numbers["obstacle"] == obstacle and gap < room
    before = _body_along(pose, direction * (gap - 0.05), m.vehicle)
    after = _body_along(pose, direction * (gap + 0.05), m.vehicle)
    assert not before.intersects(wall) and after.intersects(wall)
    reverse = dataclasses.replace(problem, reverse=True)
    assert make_planner(planner).solve(reverse, np.random.default_rng(0), Budget()).success



def _reference_pass_cell(grid, lo, hi, a, b):
    """pass_cell as it was, with two whole-grid distance transforms (the reference)."""
    from scipy import ndimage

    structure = np.ones((3, 3), dtype=bool)
    low, _ = ndimage.label(grid >= lo, structure=structure)
    high, _ = ndimage.label(grid >= hi, structure=structure)
    band = (low == low[a]) & (high == 0)
    to_a = ndimage.distance_transform_edt(high != high[a])
    to_b = ndimage.distance_transform_edt(high != high[b])
    total = np.where(band, to_a + to_b, np.inf)
    return total, np.unravel_index(int(np.argmin(total)), grid.shape)


def test_pass_cell_equals_the_whole_grid_distance_transforms():
    # Since session 38 pass_cell measures the two distances from KD-trees of the sides'
    # edge cells (10.6 s and 2 GB of transforms on a 2 km map before): the same cell, on
    # 300 random grids, of which the ends of at least 30 lie in two sides of a pass.
    from scipy import ndimage

    from rrtdrive.planning.diagnosis.checks import connected, pass_cell

    compared = 0
    for seed in range(300):
        rng = np.random.default_rng(seed)
        free = np.ones((rng.integers(20, 90), rng.integers(20, 90)), dtype=bool)
        for _ in range(rng.integers(1, 12)):
            i, j = rng.integers(0, free.shape[0]), rng.integers(0, free.shape[1])
            free[i:i + rng.integers(1, 15), j:j + rng.integers(1, 15)] = False
        grid = ndimage.distance_transform_edt(free) * 0.1
        cells = np.argwhere(free)
        a, b = (tuple(int(v) for v in cells[rng.integers(len(cells))]) for _ in range(2))
        lo, hi = 1e-9, float(min(grid[a], grid[b]))
        if not connected(grid, lo, a, b) or connected(grid, hi, a, b):
            continue  # joined at the ends' clearance, or never: no pass between them
        for _ in range(10):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if connected(grid, mid, a, b) else (lo, mid)
        high, _ = ndimage.label(grid >= hi, structure=np.ones((3, 3), dtype=bool))
        compared += bool(high[a] and high[b] and high[a] != high[b])
        total, expected = _reference_pass_cell(grid, lo, hi, a, b)
        got = pass_cell(grid, lo, hi, a, b)
        assert total[got] == pytest.approx(total[expected], abs=1e-9), seed
        assert got == tuple(int(v) for v in expected), seed
    assert compared >= 30


@settings(max_examples=80, deadline=None)
@given(st.integers(0, 2**31 - 1))
def test_distance_to_a_side_equals_the_distance_transform(seed):
    # pass_cell's distances, from a KD-tree of the side's edge cells, against scipy's
    # whole-grid transform at every cell outside the side (sides touching the border too).
    from scipy import ndimage

    from rrtdrive.planning.diagnosis.checks import _distance_to

    rng = np.random.default_rng(seed)
    side = np.zeros((rng.integers(5, 60), rng.integers(5, 60)), dtype=bool)
    for _ in range(rng.integers(1, 6)):
        i, j = rng.integers(0, side.shape[0]), rng.integers(0, side.shape[1])
        side[i:i + rng.integers(1, 20), j:j + rng.integers(1, 20)] = True
    side[rng.random(side.shape) < rng.uniform(0, 0.05)] = True  # specks
    if side.all():
        return
    outside = np.nonzero(~side)
    expected = ndimage.distance_transform_edt(~side)[outside]
    np.testing.assert_allclose(_distance_to(side, outside), expected, rtol=0, atol=1e-12)
