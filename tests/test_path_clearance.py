"""The improved planner keeps its body clearance, measured with shapely."""

from __future__ import annotations

import numpy as np
import pytest
import shapely

from rrtdrive.maps import Map, Obstacle, builtin_map
from rrtdrive.planning import PlanningProblem, make_planner
from rrtdrive.types import Budget, InputError, Pose
from rrtdrive.vehicle import footprint_corners


def min_clearance(m: Map, samples: np.ndarray) -> float:
    union = shapely.union_all([shapely.Polygon(o.corners()) for o in m.obstacles])
    rects = shapely.polygons(footprint_corners(samples[:, :3], m.vehicle))
    return float(shapely.distance(union, rects).min())


@pytest.mark.parametrize("name", ["parking_lot", "narrow_gap"])
def test_paths_keep_the_body_clearance(name):
    m = builtin_map(name)
    problem = PlanningProblem.from_map(m)
    planner = make_planner("improved-rrt-connect", body_clearance=0.15)
    for seed in range(4):
        res = planner.solve(problem, np.random.default_rng(seed), Budget())
        assert res.success
        assert min_clearance(m, res.path.samples) >= 0.15 - 1e-6


def test_clearance_capped_by_a_goal_close_to_a_wall():
    # The goal body runs 0.35 m beside a wall: the path may come that close, no closer.
    wall = Obstacle((60.0, 14.1 - 0.35 - 0.5), (30.0, 1.0))
    m = Map("wall", (0.0, 0.0, 80.0, 30.0), (wall,), Pose(10.0, 15.0, 0.0), Pose(60.0, 15.0, 0.0))
    res = make_planner("improved-rrt-connect", body_clearance=0.5).solve(
        PlanningProblem.from_map(m), np.random.default_rng(0), Budget()
    )
    assert res.success
    assert min_clearance(m, res.path.samples) == pytest.approx(0.35, abs=0.01)


def test_negative_clearance_rejected():
    with pytest.raises(InputError, match="planner.body_clearance"):
        make_planner("improved-rrt-connect", body_clearance=-0.1)
