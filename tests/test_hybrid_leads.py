"""Straight lead-ins into boxed-in poses (``planning/hybrid/leads.py``) and the garage moves.

The geometry is judged by shapely (the car's rectangle against the obstacles' and
the map's edges), not by the body test that :func:`lead_ins` itself uses.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely
from shapely.geometry import Polygon

from rrtdrive.collision import CollisionChecker
from rrtdrive.maps import Map, builtin_map
from rrtdrive.planning import PlanningProblem, make_planner
from rrtdrive.planning.hybrid.body import BodyTest
from rrtdrive.planning.hybrid.config import HybridConfig
from rrtdrive.planning.hybrid.leads import ARC_PROBE, lead_ins
from rrtdrive.planning.hybrid.primitives import arc_poses
from rrtdrive.planning.hybrid.shots import analytic_shots
from rrtdrive.tight_maps import garage_goal, garage_map
from rrtdrive.types import Budget, InputError, Pose, VehicleParams
from rrtdrive.verify import verify_path

CAR = VehicleParams()
KAPPA = CAR.kappa_max
CLEARANCE = 0.15


def _walls(m: Map) -> shapely.Geometry:
    x0, y0, x1, y1 = m.bounds
    outside = shapely.box(x0 - 5, y0 - 5, x1 + 5, y1 + 5).difference(shapely.box(x0, y0, x1, y1))
    return shapely.union_all([outside, *(o.polygon() for o in m.obstacles)])


def _body(x: float, y: float, yaw: float) -> Polygon:
    c, s = math.cos(yaw), math.sin(yaw)
    back, front, half = CAR.rear_overhang, CAR.front_extent, CAR.width / 2
    return Polygon(
        [(x + c * u - s * v, y + s * u + c * v) for u, v in
         ((-back, -half), (front, -half), (front, half), (-back, half))]
    )  # fmt: skip


def _clear(walls: shapely.Geometry, poses: np.ndarray, clearance: float) -> bool:
    return all(_body(*p[:3]).distance(walls) >= clearance - 1e-6 for p in poses)


def _arc_hits(walls, pose: Pose, turn: float, gear: int) -> bool:
    s = np.arange(1, round(ARC_PROBE / 0.05) + 1) * 0.05
    return not _clear(walls, arc_poses(pose.x, pose.y, pose.yaw, turn * KAPPA, gear, s), CLEARANCE)


@pytest.mark.parametrize("aisle", [6.0, 9.0])
@pytest.mark.parametrize("tail_in", [False, True])
def test_a_bay_gets_straight_lead_ins_out_to_where_the_car_can_turn(aisle, tail_in):
    m = garage_map(aisle)
    goal = garage_goal(1, 11, aisle, tail_in=tail_in)
    walls = _walls(m)
    body = BodyTest(CollisionChecker.for_map(m), CLEARANCE)
    leads = lead_ins(goal, body, KAPPA, (1, -1), 0.1, 2 * CAR.length)
    assert leads
    # Nose-in the car comes in forward, tail-in in reverse; the other way is the wall.
    assert {lead.gear for lead in leads} == {-1 if tail_in else 1}
    gear = leads[0].gear
    # Boxed in: both full-lock arcs out of the bay hit within the probe (shapely).
    assert _arc_hits(walls, goal, 1.0, -gear) and _arc_hits(walls, goal, -1.0, -gear)
    for lead in leads:
        rows = lead.rows
        assert np.allclose(rows[0, :3], lead.via.as_tuple())
        assert np.allclose(rows[-1, :3], goal.as_tuple())
        assert np.all(rows[:, 3] == 0.0)
        assert np.allclose(rows[:, 2], goal.yaw)  # straight along the bay
        travel = np.diff(rows[:, :2], axis=0) @ [math.cos(goal.yaw), math.sin(goal.yaw)]
        assert np.all(np.sign(travel) == gear)  # driven in the lead's gear
        assert np.max(np.hypot(*np.diff(rows[:, :2], axis=0).T)) <= 0.1 + 1e-9
        assert _clear(walls, rows, CLEARANCE)
    # The first lead-in starts where a full-lock arc no longer hits.
    first = leads[0].via
    assert not (_arc_hits(walls, first, 1.0, -gear) and _arc_hits(walls, first, -1.0, -gear))


def test_an_open_pose_gets_no_lead_in():
    m = builtin_map("parking_lot")
    body = BodyTest(CollisionChecker.for_map(m), CLEARANCE)
    assert lead_ins(m.start, body, KAPPA, (1, -1), 0.1, 2 * CAR.length) == ()


@pytest.mark.parametrize("reverse", [False, True])
def test_a_shot_with_a_lead_in_ends_straight_on_the_goal(reverse):
    m = garage_map()
    goal = m.goal
    body = BodyTest(CollisionChecker.for_map(m), CLEARANCE)
    leads = lead_ins(goal, body, KAPPA, (1, -1) if reverse else (1,), 0.1, 2 * CAR.length)
    # Aim from the aisle's far side: the words to the goal itself all fail here.
    pose = Pose(goal.x - 12.0, 5.5 + 6.5, 0.0)
    plain = list(analytic_shots(goal, 1 / KAPPA, reverse, 0.1, body)(pose))
    shots = list(analytic_shots(goal, 1 / KAPPA, reverse, 0.1, body, leads=leads)(pose))
    assert len(shots) > len(plain)  # the lead-ins' words come after the goal's own
    last = shots[-1][-1]
    assert last.gear == 1
    assert np.allclose(last.rows[-1, :2], [goal.x, goal.y])
    assert math.isclose(math.cos(last.rows[-1, 2] - goal.yaw), 1.0)
    tail = last.rows[-round(2.0 / 0.1):]
    assert np.all(tail[:, 3] == 0.0)
    assert np.allclose(np.cos(tail[:, 2]), math.cos(goal.yaw), atol=1e-9)


@pytest.mark.parametrize("aisle", [6.0, 9.0])
def test_bay_to_bay_across_a_narrow_aisle_connects_in_a_few_expansions(aisle):
    # Before the lead-ins: 8 426 (6 m) and 5 267 (9 m) expansions, 28.2 / 34.8 m, 5 / 3 cusps.
    base = garage_map(aisle)
    m = Map("b2b", base.bounds, base.obstacles, garage_goal(0, 9, aisle),
            garage_goal(1, 11, aisle))  # fmt: skip
    problem = PlanningProblem.from_map(m, reverse=True)
    res = make_planner("hybrid-a-star").solve(
        problem, np.random.default_rng(0), Budget(max_iterations=20_000, max_time_s=60.0)
    )
    assert res.success, res.message
    assert res.iterations <= 100
    assert len(res.path.cusps) <= 3
    assert res.path.length < 26.0
    check = verify_path(m, res.path, max_sharpness=0.2)
    assert check.ok, check.failed
    assert _clear(_walls(m), res.path.samples[::3], 0.1)


def test_the_count_of_lead_ins_is_the_configs():
    m = garage_map()
    body = BodyTest(CollisionChecker.for_map(m), CLEARANCE)
    counts = [len(lead_ins(m.goal, body, KAPPA, (1, -1), 0.1, 2 * CAR.length, n)) for n in range(4)]
    assert counts == [0, 1, 2, 3]
    with pytest.raises(InputError, match="hybrid.lead_ins"):
        HybridConfig(lead_ins=-1)


def test_leaving_a_bay_searches_from_the_goal_sooner():
    # The start is boxed in its bay: the search from the goal, whose shots aim at the
    # start's lead-ins, starts after 100 expansions instead of 400 (before: 425).
    base = garage_map(7.0)
    m = Map("leave", base.bounds, base.obstacles, garage_goal(0, 9, 7.0),
            Pose(base.bounds[2] - 4.0, 5.5 + 7.0 / 4, 0.0))  # fmt: skip
    res = make_planner("hybrid-a-star").solve(
        PlanningProblem.from_map(m, reverse=True), np.random.default_rng(0),
        Budget(max_iterations=20_000, max_time_s=60.0),
    )  # fmt: skip
    assert res.success, res.message
    assert 100 < res.iterations <= 150
    check = verify_path(m, res.path, max_sharpness=0.2)
    assert check.ok, check.failed
