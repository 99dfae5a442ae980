"""Turning round further along (:func:`rrtdrive.planning.hybrid.turn.abreast`).

A row of 45-degree bays entered against the row: the multi-point turn from the
start is stuck against the map's west wall; driven on to abreast of the free bay, it
turns there. Geometry is judged by shapely and :func:`rrtdrive.verify.verify_path`.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely

from rrtdrive.collision import CollisionChecker
from rrtdrive.maps import Map, Obstacle
from rrtdrive.planning import PlanningProblem, make_planner
from rrtdrive.planning.hybrid.body import BodyTest
from rrtdrive.planning.hybrid.config import HybridConfig
from rrtdrive.planning.hybrid.turn import abreast
from rrtdrive.types import Budget, InputError, Pose, VehicleParams
from rrtdrive.verify import verify_path

CAR = VehicleParams()


def _against_row(aisle: float = 5.0, angle_deg: float = 45.0) -> Map:
    """Bays 2.6 m wide at ``angle_deg`` under the aisle, angled against a car driving east."""
    a = math.radians(angle_deg)
    yaw = -(math.pi - a)
    pitch, back = 2.6 / math.sin(a), CAR.length / 2 - CAR.rear_overhang
    obstacles, goal = [], None
    for i in range(12):
        cx, cy = 6.0 + i * pitch, 2.75
        if i == 6:
            goal = Pose(cx - back * math.cos(yaw), cy - back * math.sin(yaw), yaw)
        else:
            obstacles.append(Obstacle((cx, cy), (CAR.length, CAR.width), yaw))
    return Map("against", (0.0, -1.0, 12.0 + 12 * pitch, 5.5 + aisle), tuple(obstacles),
               Pose(2.0, 5.5 + aisle / 2, 0.0), goal)  # fmt: skip


def _plan(m: Map, **options: object):
    return make_planner("hybrid-a-star", **options).solve(
        PlanningProblem.from_map(m, reverse=True), np.random.default_rng(0),
        Budget(max_iterations=20_000, max_time_s=120.0),
    )  # fmt: skip


def test_the_drives_run_straight_to_abreast_of_the_goal_nearest_first():
    m = Map("street", (0.0, 0.0, 40.0, 8.0), (Obstacle((35.0, 4.0), (2.0, 8.0)),),
            Pose(3.0, 2.0, 0.0), Pose(21.0, 6.0, math.pi))  # fmt: skip
    body = BodyTest(CollisionChecker.for_map(m), 0.15)
    drives = list(abreast(m.start, m.goal, body, 0.1, tries=6))
    ends = [round(pose.x, 9) for _, pose in drives]
    assert ends == [21.0, 19.0, 23.0, 17.0, 25.0, 15.0]
    walls = shapely.union_all([o.polygon() for o in m.obstacles])
    for piece, pose in drives:
        rows = piece.rows
        assert piece.gear == 1 and np.all(rows[:, 3] == 0.0)
        assert np.allclose(rows[0, :3], m.start.as_tuple())
        assert np.allclose(rows[-1, :3], pose.as_tuple())
        assert np.allclose(rows[:, 1:3], [2.0, 0.0])  # along the start's heading
        assert np.max(np.diff(rows[:, 0])) <= 0.1 + 1e-9
        for x, y, yaw, _ in rows[::5]:
            c, s = math.cos(yaw), math.sin(yaw)
            corners = [(x + c * u - s * v, y + s * u + c * v) for u, v in (
                (-CAR.rear_overhang, -0.9), (CAR.length - CAR.rear_overhang, -0.9),
                (CAR.length - CAR.rear_overhang, 0.9), (-CAR.rear_overhang, 0.9))]  # fmt: skip
            assert shapely.Polygon(corners).distance(walls) >= 0.15
    # Drives whose nose (3.4 m ahead of the rear axle, and 0.15 m more) would reach the
    # wall at x = 34 are not given: of 31, 29, 33 and 27, only 29 and 27.
    far = list(abreast(m.start, Pose(31.0, 6.0, math.pi), body, 0.1, tries=4))
    assert CAR.length - CAR.rear_overhang + 0.15 > 34.0 - 31.0
    assert [round(p.x, 9) for _, p in far] == [29.0, 27.0]


def test_a_goal_behind_is_driven_to_in_reverse():
    m = Map("street", (0.0, 0.0, 40.0, 8.0), (), Pose(30.0, 2.0, 0.0), Pose(14.0, 6.0, 0.0))
    body = BodyTest(CollisionChecker.for_map(m), 0.15)
    piece, pose = next(abreast(m.start, m.goal, body, 0.1))
    assert piece.gear == -1 and math.isclose(pose.x, 14.0) and math.isclose(pose.yaw, 0.0)


def test_angled_bay_against_the_row_turns_abreast_of_it():
    # Before (abreast_turns=0): 5 260 expansions, 91.5 m, the 2 m / 20 deg search's path.
    m = _against_row()
    res = _plan(m)
    assert res.success, res.message
    assert res.iterations <= 600
    assert res.path.length < 50.0
    assert "multi-point turn" in res.message
    check = verify_path(m, res.path, max_sharpness=0.2)
    assert check.ok, check.failed
    without = _plan(m, abreast_turns=0, lattice_after=0)
    assert without.iterations > 5 * res.iterations
    # The heading lattice's guidance (after 800 expansions) finds a way too, later.
    guided = _plan(m, abreast_turns=0)
    assert guided.success and guided.iterations > res.iterations


def test_abreast_turns_are_validated():
    with pytest.raises(InputError, match="hybrid.abreast_turns"):
        HybridConfig(abreast_turns=-1)


def test_no_turn_further_along_when_the_car_only_turns_off():
    # Leaving a garage bay into the aisle turns the car by 90 degrees: the search's own
    # path stands (with a 90-degree threshold the turn further along connected first,
    # 8.2 m longer, at the 6 m aisle).
    from rrtdrive.tight_maps import GARAGE_BAY_DEPTH, garage_goal, garage_map

    base = garage_map(6.0)
    m = Map("leave", base.bounds, base.obstacles, garage_goal(0, 9, 6.0),
            Pose(base.bounds[2] - 4.0, GARAGE_BAY_DEPTH + 1.5, 0.0))  # fmt: skip
    with_turns, without = _plan(m), _plan(m, abreast_turns=0)
    assert with_turns.success and without.success
    assert np.array_equal(with_turns.path.samples, without.path.samples)
    assert with_turns.iterations == without.iterations
