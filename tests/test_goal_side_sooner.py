"""A goal that cannot be driven into straight forward brings the search from the goal in sooner.

:func:`~rrtdrive.planning.hybrid.resolution.approach_blocked` is judged by shapely (the
car's rectangle against the obstacles and the map's edges); the searches by their
counted expansions, with the same paths.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

from rrtdrive.maps import Map, Obstacle, builtin_map
from rrtdrive.planning import PlanningProblem
from rrtdrive.planning.hybrid import resolution
from rrtdrive.planning.hybrid.body import BodyTest
from rrtdrive.planning.hybrid.planner import HybridAStar
from rrtdrive.planning.improved import ImprovedRRTConnect
from rrtdrive.sim.tasks import make_scenario
from rrtdrive.types import Budget, Pose, VehicleParams
from rrtdrive.vehicle import footprint_polygon

CAR = VehicleParams()
CLEARANCE = 0.15
BUDGET = Budget(max_iterations=20_000, max_time_s=600.0)


def _box_map() -> Map:
    """A 20 m square with one 4 x 2 m box in the middle."""
    return Map(
        "box", (0.0, 0.0, 20.0, 20.0), (Obstacle((10.0, 10.0), (4.0, 2.0), 0.3),),
        Pose(2.0, 2.0, 0.0), Pose(14.0, 16.0, 0.0),
    )  # fmt: skip


def _walls(m: Map) -> shapely.Geometry:
    x0, y0, x1, y1 = m.bounds
    outside = shapely.box(x0 - 5, y0 - 5, x1 + 5, y1 + 5).difference(shapely.box(x0, y0, x1, y1))
    return shapely.union_all([outside, *(o.polygon() for o in m.obstacles)])


@settings(max_examples=150, deadline=None)
@given(
    x=st.floats(3.0, 17.0), y=st.floats(3.0, 17.0), yaw=st.floats(-math.pi, math.pi),
)  # fmt: skip
def test_approach_blocked_agrees_with_shapely(x: float, y: float, yaw: float) -> None:
    m = _box_map()
    problem = PlanningProblem.from_map(m)
    body = BodyTest(problem.checker, CLEARANCE)
    walls = _walls(m)
    s = np.arange(1, 11) * 0.1  # the last metre, 0.1 m apart (the goal excluded)
    gaps = [
        footprint_polygon((x - math.cos(yaw) * d, y - math.sin(yaw) * d, yaw), CAR).distance(walls)
        for d in s
    ]
    # Decided only where shapely is clearly on one side (the grid's lower bound and the
    # exact rectangles agree there; within 2 cm of the clearance either answer is fair).
    if min(gaps) < CLEARANCE - 0.02:
        assert resolution.approach_blocked(Pose(x, y, yaw), body, 0.1)
    elif min(gaps) > CLEARANCE + 0.02:
        assert not resolution.approach_blocked(Pose(x, y, yaw), body, 0.1)


def _never_blocked(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(resolution, "approach_blocked", lambda *a, **k: False)


@pytest.mark.parametrize("seed", [2, 8, 9])
def test_parallel_parking_searches_from_the_gap_sooner_for_the_same_path(
    seed: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    task = make_scenario("parallel-parking", seed)
    problem = PlanningProblem.from_map(task.map, reverse=True)
    body = BodyTest(problem.checker, CLEARANCE)
    assert resolution.approach_blocked(problem.goal, body, 0.1)  # the rear car 0.3 m behind
    new = HybridAStar().solve(problem, np.random.default_rng(0), BUDGET)
    _never_blocked(monkeypatch)
    old = HybridAStar().solve(problem, np.random.default_rng(0), BUDGET)
    assert new.success and old.success
    np.testing.assert_allclose(new.path.samples, old.path.samples, atol=1e-9)
    # From the start 100 expansions, not 400, before the goal's side takes its turn.
    assert new.iterations <= old.iterations - 300


def test_a_goal_in_the_open_is_searched_as_before(monkeypatch: pytest.MonkeyPatch) -> None:
    problem = PlanningProblem.from_map(builtin_map("parking_lot"), reverse=True)
    body = BodyTest(problem.checker, CLEARANCE)
    assert not resolution.approach_blocked(problem.goal, body, 0.1)
    new = HybridAStar().solve(problem, np.random.default_rng(0), BUDGET)
    _never_blocked(monkeypatch)
    old = HybridAStar().solve(problem, np.random.default_rng(0), BUDGET)
    assert new.iterations == old.iterations
    np.testing.assert_allclose(new.path.samples, old.path.samples, atol=1e-9)


def test_a_forward_only_kerbside_gap_is_proven_unreachable_sooner(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    problem = PlanningProblem.from_map(builtin_map("kerbside"))
    new = ImprovedRRTConnect().solve(problem, np.random.default_rng(0), BUDGET)
    _never_blocked(monkeypatch)
    old = ImprovedRRTConnect().solve(problem, np.random.default_rng(0), BUDGET)
    assert not new.success and new.status == old.status
    assert "reached in reverse" in new.message
    assert new.iterations < old.iterations
