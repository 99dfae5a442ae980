"""RRT* (Karaman & Frazzoli, 2011): the third baseline of the paper (Sec. 4.1).

Like the paper, it grows a tree of a fixed size (450 nodes by default) with a
2 m step and a 15 m rewiring radius, then returns the cheapest path to the goal.
Cost is Euclidean path length.

Speed comes from doing as few edge tests as possible:

* choose-parent sorts the near nodes by cost-through-them and tests edges lazily,
  stopping at the first free one (and never below the nearest node's cost, whose
  edge is already known to be free);
* rewiring only tests the edges of neighbours whose cost would drop;
* a child list per node lets a rewired node push its cost change to its subtree.
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
from rrtdrive.planning.options import (
    MAX_NODES,
    check_count,
    check_flag,
    check_probability,
    check_step,
)
from rrtdrive.planning.result import run_query, search_result
from rrtdrive.planning.sampling import SampleSource
from rrtdrive.types import Budget, InputError, PlanResult, require_positive

__all__ = ["RRTStarPlanner"]

_EPS = 1e-9


@register_planner("rrt-star")
class RRTStarPlanner:
    """Asymptotically optimal RRT with choose-parent and rewiring, grown to a fixed size.

    The tree grows until it holds ``max_nodes`` nodes (the goal, attached at the
    end, counts as one) *and* some node within ``goal_radius`` of the goal has a
    free edge to it. When ``max_nodes`` is reached before the goal is connected,
    the tree keeps growing until it is (or the budget ends). The goal is then
    attached by choose-parent: the cheapest connection (cost-to-come plus the
    distance) whose edge is free.

    Parameters
    ----------
    step : float
        Extension length in metres (paper: 2 m).
    rewire_radius : float
        Radius in metres of the near set for choose-parent and rewiring (paper: 15 m).
    goal_bias : float
        Probability of sampling the goal, in ``[0, 1)`` (paper: 0.05).
    max_nodes : int
        Tree size to build, goal included (paper: 450).
    goal_radius : float, optional
        Largest distance from a node to the goal for a goal connection. The goal
        is inserted like any RRT* sample, by choose-parent over its near set, so
        the default is ``rewire_radius``; ``step`` gives the strict one-step rule.
    reject_samples : bool
        Sample only where the car can stand and that is not provably cut off from
        the start (see :class:`~rrtdrive.planning.sampling.SampleSource`).
    exact_goal_edge : bool
        Confirm an edge into the goal by the exact body test when the fast test fails.

    Examples
    --------
    >>> from rrtdrive.maps import builtin_map
    >>> from rrtdrive.planning.base import PlanningProblem
    >>> problem = PlanningProblem.from_map(builtin_map("overtake"))
    >>> result = RRTStarPlanner().solve(problem, np.random.default_rng(0), Budget())
    >>> result.success, result.nodes
    (True, 450)
    """

    name = "rrt-star"

    def __init__(
        self,
        step: float = 2.0,
        rewire_radius: float = 15.0,
        goal_bias: float = 0.05,
        max_nodes: int = 450,
        goal_radius: float | None = None,
        reject_samples: bool = True,
        exact_goal_edge: bool = True,
    ) -> None:
        self.step = check_step(step)
        require_positive("planner.rewire_radius", rewire_radius)
        self.rewire_radius = float(rewire_radius)
        self.goal_bias = check_probability("planner.goal_bias", goal_bias)
        self.max_nodes = check_count("planner.max_nodes", max_nodes)
        if self.max_nodes < 2:
            raise InputError(
                f"planner.max_nodes: must be >= 2 (start and goal), got {self.max_nodes}"
            )
        if self.max_nodes > MAX_NODES:  # the tree is preallocated
            raise InputError(
                f"planner.max_nodes: must be at most {MAX_NODES}, got {self.max_nodes}"
            )
        if goal_radius is not None:
            require_positive("planner.goal_radius", goal_radius)
            goal_radius = float(goal_radius)
        self.goal_radius = goal_radius
        self.reject_samples = check_flag("planner.reject_samples", reject_samples)
        self.exact_goal_edge = check_flag("planner.exact_goal_edge", exact_goal_edge)

    def __repr__(self) -> str:
        return (
            f"RRTStarPlanner(step={self.step}, rewire_radius={self.rewire_radius}, "
            f"goal_bias={self.goal_bias}, max_nodes={self.max_nodes})"
        )

    def solve(
        self, problem: PlanningProblem, rng: np.random.Generator, budget: Budget
    ) -> PlanResult:
        """Grow a ``max_nodes`` tree with rewiring and return the cheapest path to the goal.

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
            Solved with the best raw tree path, or a failure with the tree.
        """
        return run_query(
            self.name, problem, budget, lambda watch: self._search(problem, rng, budget, watch),
            rng=rng, exact_goal_edges=self.exact_goal_edge, headings=False,
        )

    def _search(
        self, problem: PlanningProblem, rng: np.random.Generator, budget: Budget, watch: Stopwatch
    ) -> PlanResult:
        start, goal = problem.start.xy, problem.goal.xy
        gx, gy = float(goal[0]), float(goal[1])
        edges = EdgeTester(problem.checker, goal, self.exact_goal_edge)
        samples = SampleSource(problem, self.reject_samples)
        tree = GrowingTree(start, capacity=max(1024, 2 * self.max_nodes))
        children: list[list[int]] = [[]]
        step = self.step
        radius_sq = self.rewire_radius**2
        goal_radius = self.rewire_radius if self.goal_radius is None else self.goal_radius
        target = self.max_nodes - 1  # the goal is attached as the last node
        goal_links: list[int] = []  # nodes with a verified free edge to the goal
        considered = 0  # nodes below this index have been considered for the goal edge
        rewires = 0

        def connect_goal() -> None:
            # The goal's choose-parent over the nodes not yet considered: cheapest first,
            # edges tested lazily until the first free one.
            nonlocal considered
            d_sq = tree.sq_dists(goal)[considered:]
            idx = np.flatnonzero(d_sq <= goal_radius * goal_radius)
            cand = considered + idx
            considered = tree.size
            total = tree.cost[cand] + np.sqrt(d_sq[idx])
            for k in np.argsort(total, kind="stable"):
                if edges.goal_edge(tree.nodes[cand[k]]):
                    goal_links.append(int(cand[k]))
                    return

        iterations = 0
        while True:
            if tree.size >= target:
                connect_goal()
                if goal_links:
                    break
            if iterations >= budget.max_iterations or watch.expired():
                break
            iterations += 1
            goal_sample = rng.random() < self.goal_bias
            q = goal if goal_sample else samples.draw(rng)
            nearest = tree.nearest(q)
            a = tree.nodes[nearest].copy()
            new, reached = step_towards(a, q, step)
            d_new = math.dist(a, new)
            if d_new < _EPS or (goal_sample and reached):
                continue  # the goal itself is attached only at the end
            if not edges.edge(a, new):
                continue

            # Choose the parent: cheapest near node with a free edge, tested lazily.
            sq = tree.sq_dists(new)
            near = np.flatnonzero(sq <= radius_sq)
            dist_near = np.sqrt(sq[near])
            cost_near = tree.cost[near] + dist_near
            parent, parent_cost = nearest, float(tree.cost[nearest]) + d_new
            for k in np.argsort(cost_near, kind="stable"):
                if cost_near[k] >= parent_cost:
                    break
                cand = int(near[k])
                if cand != nearest and edges.edge(tree.nodes[cand], new):
                    parent, parent_cost = cand, float(cost_near[k])
                    break
            j = tree.add(new, parent, parent_cost)
            children.append([])
            children[parent].append(j)

            # Rewire: neighbours whose cost would drop through the new node.
            via_new = parent_cost + dist_near
            for k in np.flatnonzero(via_new < tree.cost[near] - _EPS):
                node = int(near[k])
                new_cost = float(via_new[k])
                old_cost = float(tree.cost[node])  # may have dropped since the filter
                if new_cost >= old_cost - _EPS or not edges.edge(new, tree.nodes[node]):
                    continue
                children[int(tree.parents[node])].remove(node)
                children[j].append(node)
                tree.parents[node] = j
                _shift_subtree(tree.cost, children, node, new_cost - old_cost)
                rewires += 1

        stats = {**edges.stats(), "rewires": rewires}
        if not goal_links:
            trees = (tree.freeze(),)
            return search_result(self.name, problem, None, trees, iterations, watch, budget, stats)
        links = np.array(goal_links)
        total = tree.cost[links] + np.hypot(tree.nodes[links, 0] - gx, tree.nodes[links, 1] - gy)
        best = int(links[np.argmin(total)])
        goal_index = tree.add(goal, best)
        stats["goal_links"] = len(goal_links)
        stats["path_cost_m"] = float(tree.cost[goal_index])
        raw = tree.branch(goal_index)[::-1]
        trees = (tree.freeze(),)
        return search_result(self.name, problem, raw, trees, iterations, watch, budget, stats)


def _shift_subtree(cost: np.ndarray, children: list[list[int]], root: int, delta: float) -> None:
    """Add ``delta`` to the cost of ``root`` and of every node below it."""
    stack = [root]
    while stack:
        n = stack.pop()
        cost[n] += delta
        stack.extend(children[n])
