"""The Hybrid A* heuristic's cell graph is bounded in size (a huge map gets coarser cells).

Its Dijkstra runs once per query and cannot look at the wall-clock cap: on a 5 km map
at 0.71 m (49 million cells) one took 54 s of a query capped at 5 s (a helper's audit,
session 29). The cap is tested here at a small limit on the built-in lot.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from rrtdrive.collision import CollisionChecker
from rrtdrive.maps import builtin_map
from rrtdrive.planning import PlanningProblem, make_planner
from rrtdrive.planning.hybrid import heuristic
from rrtdrive.planning.hybrid.heuristic import FreeCellGraph, HolonomicField
from rrtdrive.types import Budget, PlanStatus
from rrtdrive.verify import verify_path


@pytest.mark.parametrize("limit", [500, 2_000, 20_000])
def test_the_graph_keeps_within_the_cell_limit(monkeypatch, limit: int) -> None:
    m = builtin_map("parking_lot")
    checker = CollisionChecker.for_map(m)
    monkeypatch.setattr(heuristic, "MAX_FREE_CELLS", limit)
    grid = FreeCellGraph.build(checker, 0.5)
    assert grid.index.size <= limit
    # As fine as the limit allows: one step finer would exceed it.
    f = round(grid.resolution / checker.resolution)
    nx, ny = checker.component_labels.shape
    if f > round(0.5 / checker.resolution):
        assert math.ceil(nx / (f - 1)) * math.ceil(ny / (f - 1)) > limit
    # Still no reachable place cut off: the goal's field is finite at the start.
    field = HolonomicField.towards(grid, m.goal)
    assert np.isfinite(field.at(np.array([[m.start.x, m.start.y]]))).all()


def test_below_the_limit_nothing_changes() -> None:
    m = builtin_map("parking_lot")
    grid = FreeCellGraph.build(CollisionChecker.for_map(m), 0.5)
    assert grid.resolution == pytest.approx(0.5)  # 100 m at 0.5 m: 40 000 cells


def test_a_coarser_heuristic_still_plans_a_checked_path(monkeypatch) -> None:
    m = builtin_map("parking_lot")
    monkeypatch.setattr(heuristic, "MAX_FREE_CELLS", 2_000)  # about 2.2 m cells
    problem = PlanningProblem.from_map(m, checker=CollisionChecker.for_map(m), reverse=True)
    res = make_planner("hybrid-a-star").solve(
        problem, np.random.default_rng(0), Budget(max_iterations=20_000, max_time_s=1e6)
    )
    assert res.status is PlanStatus.SOLVED, res.message
    assert verify_path(m, res.path).ok
