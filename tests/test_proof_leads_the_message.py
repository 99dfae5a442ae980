"""A failed default query leads its message with the Hybrid A* proof, when there is one.

The escalation's search that runs out of states has explored every way on from the
start (or in to the goal) at its resolution: a stronger finding than the RRT-Connect
stages' counted failure, which used to come first (a new user's start nosed into parked
cars read "the goal is boxed in along its heading" first and blamed the goal).
"""

from __future__ import annotations

import numpy as np

from rrtdrive.maps import Map, Obstacle
from rrtdrive.planning import PlanningProblem, make_planner
from rrtdrive.types import Budget, PlanStatus, Pose

#: A car nosed into a three-sided pocket 4 m deep, the open side behind it.
POCKET = (
    Obstacle((18.0, 10.0), (0.6, 4.0)),
    Obstacle((15.5, 8.3), (5.6, 0.6)),
    Obstacle((15.5, 11.7), (5.6, 0.6)),
)


def _default(m: Map, iterations: int = 10_000, reverse: bool = False):
    problem = PlanningProblem.from_map(m, reverse=reverse)
    budget = Budget(max_iterations=iterations, max_time_s=300.0)
    return make_planner("improved-rrt-connect").solve(problem, np.random.default_rng(0), budget)


def _pocket_map() -> Map:
    return Map("pocket", (0.0, 0.0, 40.0, 20.0), POCKET, Pose(14.0, 10.0, 0.0),
               Pose(30.0, 10.0, 0.0))  # fmt: skip


def test_a_start_in_a_pocket_leads_with_the_proof_about_the_start() -> None:
    res = _default(_pocket_map())
    assert res.status is PlanStatus.PROVEN_UNREACHABLE  # as the lead says (session 44)
    lead, _, tree_part = res.message.partition("; the RRT-Connect stages before it: ")
    assert lead.startswith("no path: Hybrid A* (forward only) proved none at "), res.message
    assert "the search from the start ran out of states" in lead
    assert "driving forward from this start" in lead and "try --reverse" in lead
    assert "a proof for paths keeping" in lead
    # The tree stages' own finding follows, without a second "no path:".
    assert tree_part.startswith("the start tree cannot leave the start pose"), res.message
    assert res.message.count("no path") == 1


def test_a_search_cut_short_by_its_budget_keeps_the_tree_stages_first() -> None:
    # No proof: the search stopped for want of expansions, so the order stays the
    # chronology (tree stages, then "Hybrid A* ... found none either").
    walls = (Obstacle((20.0, 10.0), (0.6, 12.0)),)
    m = Map("wall", (0.0, 0.0, 40.0, 20.0), walls, Pose(5.0, 10.0, 0.0), Pose(35.0, 10.0, 0.0))
    res = _default(m, iterations=60)
    assert not res.success
    assert res.message.startswith("no path within the iteration budget"), res.message
    assert "proved none" not in res.message
    assert "; Hybrid A* (forward only) found none either: " in res.message


def test_with_reverse_the_pocket_is_left_backwards() -> None:
    res = _default(_pocket_map(), reverse=True)
    assert res.success and len(res.path.cusps) >= 1, res.message
