"""The multi-point turn of Hybrid A* (:mod:`rrtdrive.planning.hybrid.turn`).

Closed streets narrower than the car's U-turn, the goal the start turned round:
the paths are judged by :func:`rrtdrive.verify.verify_path` (shapely bodies, the
independent sharpness estimate), not by the planner's own checks.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rrtdrive.collision import CollisionChecker
from rrtdrive.maps import Map, Obstacle
from rrtdrive.planning import PlanningProblem, make_planner
from rrtdrive.planning.hybrid.body import BodyTest
from rrtdrive.planning.hybrid.shots import analytic_shots
from rrtdrive.planning.hybrid.turn import MIN_MOVE, multi_point_turn
from rrtdrive.types import Budget, Pose
from rrtdrive.verify import verify_path


def _street(width: float, x: float = 8.0, yaw: float = 0.0, length: float = 30.0) -> Map:
    """A street closed at both ends; the goal is the start facing the other way."""
    y = width / 2.0
    return Map(f"street_{width:g}", (0.0, 0.0, length, width), (), Pose(x, y, yaw),
               Pose(x, y, yaw + math.pi))  # fmt: skip


def _plan(m: Map, budget: int = 20_000, reverse: bool = True, **options: object):
    problem = PlanningProblem.from_map(m, reverse=reverse)
    return make_planner("hybrid-a-star", **options).solve(
        problem, np.random.default_rng(0), Budget(max_iterations=budget, max_time_s=120.0)
    )


@pytest.mark.parametrize("width", [6.0, 6.5, 7.0, 8.0])
def test_turns_round_in_a_street_narrower_than_its_u_turn(width: float) -> None:
    m = _street(width)
    res = _plan(m)
    assert res.success, res.message
    check = verify_path(m, res.path, max_sharpness=0.2)
    assert check.ok, check
    assert res.stats["turn_moves"] >= 2
    assert "multi-point turn" in res.message
    # Fewer than three moves cannot turn round in a street narrower than 2 R + the car.
    assert len(res.path.cusps) >= 3


def test_three_point_turn_from_lane_to_lane_in_a_narrow_street() -> None:
    # The goal in the other lane beside the start: the turn ends off it, and a short
    # search from the turned car finishes (it failed within 20 000 expansions without).
    w = 6.5
    start, goal = Pose(16.0, w / 4, 0.0), Pose(16.0, 3 * w / 4, math.pi)
    m = Map("lanes", (0.0, 0.0, 30.0, w), (), start, goal)
    res = _plan(m)
    assert res.success, res.message
    assert res.stats["turn_moves"] >= 2
    assert verify_path(m, res.path, max_sharpness=0.2).ok


@pytest.mark.parametrize("budget", [401, 410, 450, 700])
def test_the_turn_and_its_finishing_search_keep_within_the_budget(budget: int) -> None:
    w = 6.5
    start, goal = Pose(16.0, w / 4, 0.0), Pose(16.0, 3 * w / 4, math.pi)
    # The first search may spend the whole budget (no coarse stage), so the turn comes
    # after its first 400 expansions with only the rest left.
    m = Map("lanes", (0.0, 0.0, 30.0, w), (), start, goal)
    res = _plan(m, budget=budget, coarse_after=0.0)
    assert res.iterations <= budget


def test_turns_round_in_a_closed_box() -> None:
    # 12 x 8 m, walls all round; the goal is the start turned round about the body's centre.
    m = Map("box", (0.0, 0.0, 12.0, 8.0), (), Pose(4.7, 4.0, 0.0), Pose(7.3, 4.0, math.pi))
    res = _plan(m)
    assert res.success, res.message
    assert res.stats["turn_moves"] >= 2
    check = verify_path(m, res.path, max_sharpness=0.2)
    assert check.ok, check


def test_the_default_planner_escalates_to_the_turn_and_says_so() -> None:
    m = _street(6.5)
    res = make_planner("improved-rrt-connect").solve(
        PlanningProblem.from_map(m, reverse=True), np.random.default_rng(0),
        Budget(max_iterations=20_000, max_time_s=120.0),
    )  # fmt: skip
    assert res.success, res.message
    assert "Hybrid A* escalation with a multi-point turn" in res.message
    assert res.stats["hybrid_turn_moves"] >= 2
    assert verify_path(m, res.path, max_sharpness=0.2).ok


def test_without_the_turn_the_same_budget_does_not_turn_round() -> None:
    m = _street(6.5)
    with_turn = _plan(m, budget=2_000)
    without = _plan(m, budget=2_000, turn_moves=0)
    assert with_turn.success and not without.success
    assert without.stats["turn_moves"] == 0.0


def test_forward_only_never_turns() -> None:
    res = _plan(_street(7.0), budget=2_000, reverse=False)
    assert not res.success
    assert res.stats["turn_moves"] == 0.0


def test_a_turned_plan_is_the_same_on_every_run() -> None:
    a, b = _plan(_street(6.5)), _plan(_street(6.5))
    assert a.iterations == b.iterations
    assert np.array_equal(a.path.samples, b.path.samples)


@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    width=st.floats(6.0, 9.0),
    x=st.floats(6.0, 24.0),
    yaw=st.floats(-0.4, 0.4),
)
def test_every_turned_path_passes_the_independent_check(width: float, x: float, yaw: float) -> None:
    m = _street(width, x=x, yaw=yaw)
    res = _plan(m, budget=3_000)
    if res.success:
        check = verify_path(m, res.path, max_sharpness=0.2)
        assert check.ok, check


def _turn(m: Map, max_moves: int = 12, clearance: float = 0.15):
    body = BodyTest(CollisionChecker.for_map(m), clearance)
    radius = 1.02 / m.vehicle.kappa_max
    shots = analytic_shots(m.goal, radius, True, 0.1, body)
    return multi_point_turn(m.start, m.goal, body, shots, lambda p: p, 1.0 / radius, max_moves)


def test_each_move_is_one_full_lock_arc_alternating_gears_clear_of_the_walls() -> None:
    m = _street(6.5)
    turn = _turn(m)
    assert turn.result is not None
    moves = turn.result[: turn.moves]
    assert [p.gear for p in moves] == [(-1) ** k for k in range(turn.moves)]
    checker = CollisionChecker.for_map(m)
    turned = np.array([p.rows[-1, 2] - p.rows[0, 2] for p in moves])
    # The heading turns the same way in both gears, each move by a useful amount.
    assert np.all(np.sign(turned) == np.sign(turned[0]))
    assert np.all(np.abs(turned) >= MIN_MOVE * m.vehicle.kappa_max / 1.02 - 1e-12)
    for piece in moves:
        assert np.all(np.abs(piece.rows[:, 3]) == pytest.approx(m.vehicle.kappa_max / 1.02))
        assert checker.poses_free(piece.rows[:, :3], clearance=0.15).all()


def test_a_nose_against_a_wall_begins_in_reverse() -> None:
    # A wall 0.3 m ahead of the front bumper: the first move must back away.
    base = _street(7.0)
    front = 8.0 + base.vehicle.front_extent
    wall = Obstacle((front + 0.8, 3.5), (1.0, 7.0))
    m = Map("nose", base.bounds, (wall,), base.start, base.goal)
    turn = _turn(m)
    assert turn.result is not None
    assert turn.result[0].gear == -1


def test_a_turn_stops_at_its_move_limit() -> None:
    turn = _turn(_street(6.0), max_moves=2)
    assert turn.result is None
    assert turn.moves <= 4  # two moves each way round
