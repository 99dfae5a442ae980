"""Tree-edge tests of the baselines: the fast swept-disc test, with an exact test for goal edges."""

from __future__ import annotations

import math

import numpy as np

from rrtdrive.collision import CollisionChecker

__all__ = ["EXACT_EDGE_SPACING", "EdgeTester", "exact_edge_free"]

#: Pose spacing of the exact test applied to an edge that ends at the goal.
EXACT_EDGE_SPACING = 0.1


class EdgeTester:
    """Edge tests of a tree against one checker, with counters.

    Every tree edge a->b is tested by the checker's fast conservative swept-disc
    test :meth:`~rrtdrive.collision.CollisionChecker.edge_free`. An edge that
    *ends at the goal* may, when the fast test fails and ``exact_goal_edge`` is
    set, be confirmed by the exact body-rectangle test at poses spaced at most
    0.1 m along it with the heading along the edge (the spec's definition of a
    free path). The fast test's capsule reaches ``W/2 + margin`` beyond the
    bumpers, which cannot certify a goal parked close to a kerb or a wall.

    Parameters
    ----------
    checker : CollisionChecker
        The map's checker.
    goal : numpy.ndarray
        Goal position ``(x, y)``.
    exact_goal_edge : bool
        Allow the exact fallback for edges that end at the goal.

    Examples
    --------
    >>> from rrtdrive.maps import builtin_map
    >>> from rrtdrive.planning.base import PlanningProblem
    >>> p = PlanningProblem.from_map(builtin_map("overtake"))
    >>> edges = EdgeTester(p.checker, p.goal.xy)
    >>> edges.edge(np.array([5.0, 44.0]), np.array([10.0, 44.0])), edges.checks
    (True, 1)
    """

    def __init__(self, checker: CollisionChecker, goal: np.ndarray, exact_goal_edge: bool = True):
        self.checker = checker
        self.goal = np.asarray(goal, dtype=float)
        self.exact_goal_edge = exact_goal_edge
        self.checks = 0
        self.exact_checks = 0

    def edge(self, a: np.ndarray, b: np.ndarray) -> bool:
        """Fast conservative test of the edge a->b driven with heading along it."""
        self.checks += 1
        return self.checker.edge_free(a, b)

    def goal_edge(self, a: np.ndarray) -> bool:
        """Test the edge from ``a`` to the goal: fast test, then (optionally) the exact one."""
        if self.edge(a, self.goal):
            return True
        if not self.exact_goal_edge:
            return False
        self.exact_checks += 1
        return exact_edge_free(self.checker, a, self.goal)

    def stats(self) -> dict[str, float]:
        """Counters for :attr:`PlanResult.stats`."""
        return {"edge_checks": self.checks, "exact_edge_checks": self.exact_checks}


def exact_edge_free(
    checker: CollisionChecker,
    a: np.ndarray,
    b: np.ndarray,
    spacing: float = EXACT_EDGE_SPACING,
    stride: int = 8,
) -> bool:
    """Exact body test at poses at most ``spacing`` apart along a->b, heading along the edge.

    Coarse to fine: every ``stride``-th pose from ``b`` backwards first (a blocked
    edge is nearly always caught there), then the poses in between.

    Parameters
    ----------
    checker : CollisionChecker
        The map's checker.
    a, b : numpy.ndarray
        Edge end points ``(x, y)``.
    spacing : float
        Largest distance between tested poses.
    stride : int
        Spacing, in poses, of the coarse first pass.

    Returns
    -------
    bool
        True when the body rectangle is free at every tested pose (both ends included).
    """
    a = np.asarray(a, dtype=float)
    d = np.asarray(b, dtype=float) - a
    length = math.hypot(d[0], d[1])
    if length < 1e-9:
        return False
    n = max(1, math.ceil(length / spacing))
    t = np.linspace(1.0, 0.0, n + 1)
    yaw = np.full(n + 1, math.atan2(d[1], d[0]))
    poses = np.column_stack([a[0] + t * d[0], a[1] + t * d[1], yaw])
    coarse = np.zeros(n + 1, dtype=bool)
    coarse[::stride] = True
    if not checker.poses_free(poses[coarse]).all():
        return False
    return bool(checker.poses_free(poses[~coarse]).all())
