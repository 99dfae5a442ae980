"""A search run again alike reads the earlier one's shots (:meth:`HybridSearch.replay`).

The ramp margin's second pass, where the start's or goal's own clearance caps both
passes alike, repeats the first: it must end as the first did (nodes, counts, tree)
without giving ``accept`` a connection again, and shoot for itself where it differs.
"""

from __future__ import annotations

import dataclasses

from rrtdrive.maps import builtin_map
from rrtdrive.planning.base import PlanningProblem
from rrtdrive.planning.hybrid.body import BodyTest
from rrtdrive.planning.hybrid.config import HybridConfig
from rrtdrive.planning.hybrid.heuristic import Heuristic, HolonomicField
from rrtdrive.planning.hybrid.primitives import PrimitiveSet
from rrtdrive.planning.hybrid.resolution import free_cell_graph
from rrtdrive.planning.hybrid.search import HybridSearch, analytic_shots
from rrtdrive.types import Pose

RADIUS = 5.9


def _search(start: Pose | None = None) -> HybridSearch:
    m = builtin_map("parking_lot")
    problem = PlanningProblem.from_map(m, reverse=True)
    cfg = dataclasses.replace(HybridConfig(), max_solutions=10**6)
    grid = free_cell_graph(problem, cfg.xy_resolution)
    h = Heuristic(HolonomicField.towards(grid, m.goal), None, m.goal)
    prims = PrimitiveSet.build(1 / RADIUS, cfg.curvatures, cfg.step, cfg.check_spacing, True)
    body = BodyTest(problem.checker, 0.15)
    shots = analytic_shots(m.goal, RADIUS, True, cfg.check_spacing, body)
    return HybridSearch(
        body, start or m.start, m.goal, h, prims, shots, cfg, 1 / RADIUS, m.bounds
    )


def _tree(s: HybridSearch) -> tuple:
    return s.x, s.y, s.yaw, s.g, s.gear, s.parent, s.step


def _rejecting(tried: list[int]):
    return lambda pieces: tried.append(len(pieces)) and None


def test_a_repeat_ends_as_the_earlier_search_without_trying_its_connections() -> None:
    first, tried = _search(), []
    _, done = first.run(_rejecting(tried), 800, lambda: False)
    assert done.connections == len(tried) > 0
    for turns in ((800,), (40, 120, 500, 800), (300, 600)):  # resumed as _alternate does
        again, retried = _search(), []
        again.replay(first)
        for upto in turns:
            _, outcome = again.run(_rejecting(retried), upto, lambda: False)
        fresh, tried_fresh = _search(), []
        _, want = fresh.run(_rejecting(tried_fresh), turns[-1], lambda: False)
        assert outcome == want
        assert _tree(again) == _tree(fresh)
        assert not retried  # every shot read from the earlier search


def test_a_search_that_differs_from_the_earlier_one_shoots_itself() -> None:
    first = _search()
    first.run(_rejecting([]), 800, lambda: False)
    m = builtin_map("parking_lot")
    elsewhere = Pose(m.start.x + 0.3, m.start.y, m.start.yaw)
    other, tried = _search(elsewhere), []
    other.replay(first)
    _, outcome = other.run(_rejecting(tried), 800, lambda: False)
    fresh, tried_fresh = _search(elsewhere), []
    _, want = fresh.run(_rejecting(tried_fresh), 800, lambda: False)
    assert outcome == want and _tree(other) == _tree(fresh)
    assert tried == tried_fresh and tried
