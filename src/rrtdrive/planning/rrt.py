"""Plain RRT (LaValle 1998) with goal bias: the first baseline of the paper (Sec. 4.1).

The helpers the three baselines share live beside it: option validation in
:mod:`~rrtdrive.planning.options`, the edge tester in :mod:`~rrtdrive.planning.edges`,
the sample source in :mod:`~rrtdrive.planning.sampling` and the result building in
:mod:`~rrtdrive.planning.result`.
"""

from __future__ import annotations

import math

import numpy as np

from rrtdrive.planning.base import (
    GrowingTree,
    PlanningProblem,
    Stopwatch,
    register_planner,
    step_towards,
)
from rrtdrive.planning.edges import EdgeTester
from rrtdrive.planning.options import check_flag, check_probability, check_step
from rrtdrive.planning.result import run_query, search_result
from rrtdrive.planning.sampling import SampleSource
from rrtdrive.types import Budget, PlanResult

__all__ = ["RRTPlanner"]


@register_planner("rrt")
class RRTPlanner:
    """Rapidly-exploring random tree with goal bias (LaValle, 1998).

    Each iteration samples a point (the goal with probability ``goal_bias``),
    steps ``step`` metres from the nearest node towards it and adds the new node
    when the edge is free. The search ends when a node within one step of the
    goal has a free edge to the goal.

    Parameters
    ----------
    step : float
        Extension length in metres (paper: 5 m).
    goal_bias : float
        Probability of sampling the goal, in ``[0, 1)`` (paper: 0.05).
    reject_samples : bool
        Sample only where the car can stand and that is not provably cut off from
        the start (see :class:`~rrtdrive.planning.sampling.SampleSource`).
    exact_goal_edge : bool
        Confirm an edge into the goal by the exact body test when the fast test fails
        (see :class:`~rrtdrive.planning.edges.EdgeTester`).

    Examples
    --------
    >>> from rrtdrive.maps import builtin_map
    >>> from rrtdrive.planning.base import PlanningProblem
    >>> problem = PlanningProblem.from_map(builtin_map("overtake"))
    >>> result = RRTPlanner().solve(problem, np.random.default_rng(0), Budget())
    >>> result.success, result.raw_path[0].tolist(), result.raw_path[-1].tolist()
    (True, [5.0, 44.0], [92.0, 44.0])
    """

    name = "rrt"

    def __init__(
        self,
        step: float = 5.0,
        goal_bias: float = 0.05,
        reject_samples: bool = True,
        exact_goal_edge: bool = True,
    ) -> None:
        self.step = check_step(step)
        self.goal_bias = check_probability("planner.goal_bias", goal_bias)
        self.reject_samples = check_flag("planner.reject_samples", reject_samples)
        self.exact_goal_edge = check_flag("planner.exact_goal_edge", exact_goal_edge)

    def __repr__(self) -> str:
        return f"RRTPlanner(step={self.step}, goal_bias={self.goal_bias})"

    def solve(
        self, problem: PlanningProblem, rng: np.random.Generator, budget: Budget
    ) -> PlanResult:
        """Grow one tree from the start until it connects to the goal or the budget ends.

        Parameters
        ----------
        problem : PlanningProblem
            Map, checker, start and goal.
        rng : numpy.random.Generator
            The only source of randomness.
        budget : Budget
            Iteration budget (decides) and safety cap (reaching it: ``timeout``).

        Returns
        -------
        PlanResult
            Solved with the raw tree path, or a failure with the tree.
        """
        return run_query(
            self.name, problem, budget, lambda watch: self._search(problem, rng, budget, watch),
            rng=rng, exact_goal_edges=self.exact_goal_edge, headings=False,
        )

    def _search(
        self, problem: PlanningProblem, rng: np.random.Generator, budget: Budget, watch: Stopwatch
    ) -> PlanResult:
        checker = problem.checker
        start, goal = problem.start.xy, problem.goal.xy
        edges = EdgeTester(checker, goal, self.exact_goal_edge)
        tree = GrowingTree(start)
        step = self.step
        samples = SampleSource(problem, self.reject_samples)
        goal_index = -1
        if math.dist(start, goal) <= step and edges.goal_edge(start):
            goal_index = tree.add(goal, 0)
        iterations = 0
        while goal_index < 0 and iterations < budget.max_iterations and not watch.expired():
            iterations += 1
            goal_sample = rng.random() < self.goal_bias
            if goal_sample:
                q = goal
            else:
                q = samples.draw(rng)
            i = tree.nearest(q)
            a = tree.nodes[i].copy()
            new, reached = step_towards(a, q, step)
            if math.dist(a, new) < 1e-9:
                continue
            if goal_sample and reached:
                if edges.goal_edge(a):
                    goal_index = tree.add(goal, i)
                continue
            if not edges.edge(a, new):
                continue
            j = tree.add(new, i)
            if math.dist(new, goal) <= step and edges.goal_edge(new):
                goal_index = tree.add(goal, j)
        stats = {**edges.stats()}
        raw = tree.branch(goal_index)[::-1] if goal_index >= 0 else None
        trees = (tree.freeze(),)
        return search_result(self.name, problem, raw, trees, iterations, watch, budget, stats)
