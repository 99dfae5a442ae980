"""Nudged ends (hybrid/nudge.py): the gentle arc out of a start or goal turned off its slot."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rrtdrive.maps import Map, Obstacle
from rrtdrive.planning import PlanningProblem
from rrtdrive.planning.hybrid.nudge import NUDGES_DEG, nudge
from rrtdrive.planning.hybrid.primitives import arc_poses
from rrtdrive.planning.hybrid.resolution import body_test
from rrtdrive.types import Pose

STEP, SPACING, KEEP = 0.5, 0.1, 0.05


def _slot(goal_yaw_off: float) -> Map:
    """A slot 2.15 m wide open to the north; the goal nose-in, 0.11 m left of its axis."""
    walls = (
        Obstacle((13.625, 8.0), (0.6, 7.5)),
        Obstacle((16.375, 8.0), (0.6, 7.5)),
        Obstacle((15.0, 3.95), (3.35, 0.6)),
    )
    return Map("slot", (0.0, 0.0, 30.0, 20.0), walls, Pose(15.0, 17.0, -math.pi / 2),
               Pose(14.89, 9.2, -math.pi / 2 + goal_yaw_off))  # fmt: skip


def _nudge_of(m: Map, end: Pose, at_goal: bool, gears=(1,)):
    problem = PlanningProblem.from_map(m)
    body = body_test(problem.checker, KEEP)
    return nudge(end, at_goal, gears, body, problem.vehicle.kappa_max, STEP, SPACING), body


def _free_run(body, pose: Pose, way: int) -> float:
    s = np.arange(1, 61) * 0.1
    free = body.free(arc_poses(pose.x, pose.y, pose.yaw, 0.0, way, s))
    return 6.0 if free.all() else float(s[np.argmin(free)])


@pytest.mark.parametrize("off", [0.008, -0.006])
def test_a_turned_goal_gets_an_arrival_arc_that_ends_exactly_on_it(off):
    m = _slot(off)
    if off < 0:  # turned the other way: the goal sits right of the axis then
        m = Map(m.name, m.bounds, m.obstacles, m.start, Pose(15.11, 9.2, -math.pi / 2 + off))
    found, body = _nudge_of(m, m.goal, at_goal=True)
    assert found is not None
    rows, goal = found.piece.rows, m.goal
    assert found.piece.gear == 1
    assert np.allclose(rows[-1, :3], goal.as_tuple())
    assert np.allclose(rows[0, :3], found.pose.as_tuple())
    kappa = rows[0, 3]
    assert np.all(rows[:, 3] == kappa)
    assert 0 < abs(kappa) * STEP <= math.radians(max(NUDGES_DEG)) + 1e-12
    # Driven forward from the nudged pose with that steering, the arc reaches the goal.
    end = arc_poses(found.pose.x, found.pose.y, found.pose.yaw, kappa, 1, np.array([STEP]))[0]
    assert np.allclose(end, goal.as_tuple(), atol=1e-9)
    # The way the car came in is now straight for longer, and the arc itself is free.
    assert body.free(rows[:, :3]).all()
    assert _free_run(body, found.pose, -1) >= _free_run(body, goal, -1) + 1.0
    # The nudge turns the heading towards the slot's axis.
    assert abs(found.pose.yaw + math.pi / 2) < abs(goal.yaw + math.pi / 2)


def test_a_start_gets_a_departure_arc_from_it():
    m = _slot(0.008)
    leaving = Pose(m.goal.x, m.goal.y, m.goal.yaw + math.pi)  # nose out, same body
    found, _ = _nudge_of(m, leaving, at_goal=False)
    assert found is not None
    assert np.allclose(found.piece.rows[0, :3], leaving.as_tuple())
    assert np.allclose(found.piece.rows[-1, :3], found.pose.as_tuple())


def test_no_nudge_where_the_way_out_is_open_or_the_pose_is_on_the_axis():
    open_map = Map("open", (0.0, 0.0, 40.0, 20.0), (), Pose(5.0, 10.0, 0.0), Pose(20.0, 10.0, 0.01))
    assert _nudge_of(open_map, open_map.goal, at_goal=True)[0] is None
    straight = _slot(0.0)
    assert _nudge_of(straight, straight.goal, at_goal=True)[0] is None
