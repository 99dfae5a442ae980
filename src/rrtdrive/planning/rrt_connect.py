"""Classic RRT-Connect (Kuffner & LaValle, 2000): the second baseline of the paper (Sec. 4.1).

Two trees grow, one from the start and one from the goal. Each iteration
extends one tree a step towards a random sample; if that adds a node, the other
tree greedily steps towards the new node until it reaches it or is trapped.
Then the trees swap roles.

Edges are tested in the direction the car drives them: start-tree edges from
parent to child, goal-tree edges from child to parent (towards the goal).
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

__all__ = ["RRTConnectPlanner"]

#: Outcomes of one extension.
_TRAPPED, _ADVANCED, _REACHED = 0, 1, 2


class _Side:
    """One tree with the direction its edges are driven in."""

    def __init__(self, tree: GrowingTree, towards_root: bool, edges: EdgeTester) -> None:
        self.tree = tree
        self.towards_root = towards_root
        self.edges = edges

    def extend(self, q: np.ndarray, step: float) -> tuple[int, int]:
        """Step from the nearest node towards ``q``; return (outcome, new node index or -1)."""
        tree = self.tree
        i = tree.nearest(q)
        return self.extend_from(i, q, step)

    def extend_from(self, i: int, q: np.ndarray, step: float) -> tuple[int, int]:
        """Step from node ``i`` towards ``q``; return (outcome, new node index or -1).

        A node ``i`` already at ``q`` is reached: its own index comes back, no node is
        added.
        """
        tree = self.tree
        a = tree.nodes[i].copy()
        if math.dist(a, q) < 1e-9:
            # Node i already is the target (the start tree stepped onto the goal, say):
            # reached, as Kuffner & LaValle's CONNECT has it, with no new node; reporting
            # it trapped missed the meeting and the path drove past the goal and back.
            return _REACHED, i
        new, reached = step_towards(a, q, step)
        if not self.towards_root:
            ok = self.edges.edge(a, new)
        elif i == 0:
            # The car drives new -> root, and the goal tree's root is the goal.
            ok = self.edges.goal_edge(new)
        else:
            ok = self.edges.edge(new, a)
        if not ok:
            return _TRAPPED, -1
        j = tree.add(new, i)
        return (_REACHED if reached else _ADVANCED), j


@register_planner("rrt-connect")
class RRTConnectPlanner:
    """Bidirectional RRT with greedy connection (Kuffner & LaValle, 2000).

    Parameters
    ----------
    step : float
        Extension length in metres, for the extend and each connect step (paper: 5 m).
    goal_bias : float
        Probability of sampling the other tree's root instead of a random point, in
        ``[0, 1)``; 0 (classic RRT-Connect) by default.
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
    >>> result = RRTConnectPlanner().solve(problem, np.random.default_rng(0), Budget())
    >>> result.success, len(result.trees)
    (True, 2)
    """

    name = "rrt-connect"

    def __init__(
        self,
        step: float = 5.0,
        goal_bias: float = 0.0,
        reject_samples: bool = True,
        exact_goal_edge: bool = True,
    ) -> None:
        self.step = check_step(step)
        self.goal_bias = check_probability("planner.goal_bias", goal_bias)
        self.reject_samples = check_flag("planner.reject_samples", reject_samples)
        self.exact_goal_edge = check_flag("planner.exact_goal_edge", exact_goal_edge)

    def __repr__(self) -> str:
        return f"RRTConnectPlanner(step={self.step})"

    def solve(
        self, problem: PlanningProblem, rng: np.random.Generator, budget: Budget
    ) -> PlanResult:
        """Grow a start tree and a goal tree until they meet or the budget ends.

        Parameters
        ----------
        problem : PlanningProblem
            Map, checker, start and goal.
        rng : numpy.random.Generator
            The only source of randomness.
        budget : Budget
            Iteration budget (decides) and safety cap (each connect loop also
            checks it; reaching it ends the query as ``timeout``).

        Returns
        -------
        PlanResult
            Solved with the raw path through both trees, or a failure with both trees.
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
        start_side = _Side(GrowingTree(start), towards_root=False, edges=edges)
        goal_side = _Side(GrowingTree(goal), towards_root=True, edges=edges)
        step = self.step
        samples = SampleSource(problem, self.reject_samples)
        connect_steps = 0
        meeting: tuple[int, int] | None = None  # (start-tree node, goal-tree node)

        # A start within one step of the goal connects at once (the first extend would too).
        if math.dist(start, goal) <= step and edges.goal_edge(start):
            meeting = (0, 0)

        a_side, b_side = start_side, goal_side
        iterations = 0
        while meeting is None and iterations < budget.max_iterations and not watch.expired():
            iterations += 1
            if rng.random() < self.goal_bias:
                q = b_side.tree.nodes[0].copy()
            else:
                q = samples.draw(rng)
            outcome, new = a_side.extend(q, step)
            if outcome != _TRAPPED:
                target = a_side.tree.nodes[new].copy()
                # Greedy connect of the other tree towards the new node.
                i = b_side.tree.nearest(target)
                while True:
                    connect_steps += 1
                    outcome_b, j = b_side.extend_from(i, target, step)
                    if outcome_b != _ADVANCED or watch.expired():
                        break
                    i = j
                if outcome_b == _REACHED:
                    meeting = (new, j) if a_side is start_side else (j, new)
                    break
            a_side, b_side = b_side, a_side

        stats = {
            **edges.stats(),
            "connect_steps": connect_steps,
        }
        trees = (start_side.tree.freeze(), goal_side.tree.freeze())
        if meeting is None:
            return search_result(self.name, problem, None, trees, iterations, watch, budget, stats)
        head = start_side.tree.branch(meeting[0])[::-1]
        tail = goal_side.tree.branch(meeting[1])
        if meeting == (0, 0):
            raw = np.vstack([start, goal])
        else:
            # Both trees hold the meeting point; keep one copy.
            raw = np.vstack([head, tail[1:]])
        return search_result(self.name, problem, raw, trees, iterations, watch, budget, stats)
