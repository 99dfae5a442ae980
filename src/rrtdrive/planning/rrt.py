"""Plain RRT (LaValle 1998) with goal bias: the first baseline of the paper (Sec. 4.1).

The module also holds the small helpers the three baselines share: option
validation, the edge tester (fast swept-disc test for every tree edge, with an
exact fallback for edges that end at the goal) and the solved-result builder.
"""

from __future__ import annotations

import math
import weakref

import numpy as np

from rrtdrive.collision import CollisionChecker
from rrtdrive.planning.base import (
    GrowingTree,
    PlanningProblem,
    Stopwatch,
    failure,
    polyline_path,
    precheck,
    register_planner,
    step_towards,
)
from rrtdrive.types import (
    Budget,
    InputError,
    PlanResult,
    PlanStatus,
    Tree,
    require_finite,
    require_int,
    require_positive,
)

__all__ = [
    "RRTPlanner",
    "EdgeTester",
    "SampleSource",
    "free_cells",
    "exact_edge_free",
    "check_probability",
    "check_count",
    "check_flag",
]

#: Pose spacing of the exact test applied to an edge that ends at the goal.
EXACT_EDGE_SPACING = 0.1


# ----------------------------------------------------------------------------- validation


def check_probability(name: str, value: float) -> float:
    """Return ``value`` as a float in ``[0, 1)`` or raise :class:`InputError` naming ``name``.

    Examples
    --------
    >>> check_probability("planner.goal_bias", 0.05)
    0.05
    """
    require_finite(name, value)
    if not 0.0 <= value < 1.0:
        raise InputError(f"{name}: must be in [0, 1), got {value!r}")
    return float(value)


def check_count(name: str, value: int) -> int:
    """Return ``value`` if it is an integer > 0, else raise :class:`InputError` naming ``name``.

    Examples
    --------
    >>> check_count("planner.max_nodes", 450)
    450
    """
    return require_int(name, value)


def check_flag(name: str, value: bool) -> bool:
    """Return ``value`` if it is a bool, else raise :class:`InputError` naming ``name``."""
    if not isinstance(value, (bool, np.bool_)):
        raise InputError(f"{name}: expected true or false, got {value!r}")
    return bool(value)


def check_step(value: float) -> float:
    """Validate the ``planner.step`` option (metres, > 0)."""
    require_positive("planner.step", value)
    return float(value)


# ----------------------------------------------------------------------------- edges


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


_CELLS: weakref.WeakKeyDictionary[CollisionChecker, dict[int, np.ndarray]] = (
    weakref.WeakKeyDictionary()
)


def free_cells(checker: CollisionChecker, start: tuple[float, float]) -> np.ndarray:
    """Flat indices of the grid cells where the rear axle can stand, connected to ``start``.

    A cell qualifies when its clearance admits the car with some heading (the
    test of :meth:`~rrtdrive.collision.CollisionChecker.point_free`) and it lies
    in the start's component of
    :meth:`~rrtdrive.collision.CollisionChecker.reachable_components`. Cached
    per checker and component.

    Parameters
    ----------
    checker : CollisionChecker
        The map's checker.
    start : tuple of float
        Start position ``(x, y)``.

    Returns
    -------
    numpy.ndarray
        Indices into ``checker.clearance_grid.ravel()``; empty if the start is in no component.
    """
    labels = checker.component_labels
    origin, h = checker.grid_origin, checker.resolution
    i = int(math.floor((start[0] - origin[0]) / h))
    j = int(math.floor((start[1] - origin[1]) / h))
    inside = 0 <= i < labels.shape[0] and 0 <= j < labels.shape[1]
    label = int(labels[i, j]) if inside else 0
    per_label = _CELLS.setdefault(checker, {})
    cells = per_label.get(label)
    if cells is None:
        if label == 0:
            cells = np.zeros(0, dtype=np.int64)
        else:
            vehicle = checker.vehicle
            stand = checker.clearance_grid >= min(vehicle.rear_overhang, vehicle.width / 2.0)
            cells = np.flatnonzero(stand & (labels == label))
        per_label[label] = cells
    return cells


class SampleSource:
    """Uniform samples over the map, optionally only where they can be useful.

    With ``reject`` (the default in every baseline), samples are uniform over
    the points where the car can stand with some heading
    (:meth:`~rrtdrive.collision.CollisionChecker.point_free`) and that are not
    provably disconnected from the start
    (:meth:`~rrtdrive.collision.CollisionChecker.provably_disconnected`), such
    as the land beside a walled road. Both tests are constant on the checker's
    grid cells, so instead of rejecting draws this picks a uniform random cell
    among the accepted ones and a uniform point inside it: the same distribution
    as rejection sampling, without the wasted draws. Without ``reject``, samples
    are uniform in the bounds, as :func:`~rrtdrive.planning.base.sample_point`.
    Numbers are drawn from ``rng`` in batches, so results depend only on the seed.

    Parameters
    ----------
    problem : PlanningProblem
        The query.
    reject : bool
        Sample only useful points (see above).
    batch : int
        Points drawn from the generator at once.
    """

    def __init__(self, problem: PlanningProblem, reject: bool, batch: int = 256) -> None:
        checker = problem.checker
        self.batch = batch
        self._h = checker.resolution
        self._origin = checker.grid_origin
        self._ny = checker.clearance_grid.shape[1]
        xmin, ymin, xmax, ymax = problem.bounds
        self._low = np.array([xmin, ymin])
        self._span = np.array([xmax - xmin, ymax - ymin])
        self._cells = free_cells(checker, problem.start.as_tuple()[:2]) if reject else None
        if self._cells is not None and len(self._cells) == 0:
            self._cells = None
        self._buffer = np.empty((0, 2))
        self._list: list[list[float]] = []
        self._pos = 0

    def _refill(self, rng: np.random.Generator) -> None:
        if self._cells is None:
            self._buffer = self._low + rng.random((self.batch, 2)) * self._span
        else:
            flat = self._cells[rng.integers(len(self._cells), size=self.batch)]
            ij = np.column_stack([flat // self._ny, flat % self._ny])
            self._buffer = self._origin + (ij + rng.random((self.batch, 2))) * self._h
        self._list = self._buffer.tolist()
        self._pos = 0

    def draw(self, rng: np.random.Generator) -> np.ndarray:
        """One sample point ``(x, y)`` (a fresh array)."""
        if self._pos == len(self._buffer):
            self._refill(rng)
        q = self._buffer[self._pos].copy()
        self._pos += 1
        return q

    def draw_xy(self, rng: np.random.Generator) -> list[float]:
        """:meth:`draw` as a fresh list ``[x, y]`` of floats (cheaper in scalar loops).

        Both draw from one stream: mixing them gives the same points in the same order.
        """
        if self._pos == len(self._buffer):
            self._refill(rng)
        q = self._list[self._pos]
        self._pos += 1
        return q


# ----------------------------------------------------------------------------- results


def solved_result(
    planner: str,
    raw_path: np.ndarray,
    trees: tuple[Tree, ...],
    iterations: int,
    watch: Stopwatch,
    stats: dict[str, float],
) -> PlanResult:
    """A :attr:`PlanStatus.SOLVED` result for a raw tree path from start to goal.

    Parameters
    ----------
    planner : str
        Registered planner name.
    raw_path : numpy.ndarray
        ``(K, 2)`` tree path; first row the start, last row the goal.
    trees : tuple of Tree
        Frozen search trees.
    iterations : int
        Sampling iterations used.
    watch : Stopwatch
        The query's stopwatch.
    stats : dict
        Planner statistics; the raw path length is added as ``raw_length_m``.

    Returns
    -------
    PlanResult
    """
    raw = np.array(raw_path, dtype=float).reshape(-1, 2)
    raw.setflags(write=False)
    length = float(np.sum(np.hypot(*np.diff(raw, axis=0).T)))
    stats = {**stats, "raw_length_m": length, "waypoints": len(raw)}
    nodes = sum(len(t) for t in trees)
    return PlanResult(
        status=PlanStatus.SOLVED,
        planner=planner,
        path=polyline_path(raw),
        raw_path=raw,
        trees=trees,
        nodes=nodes,
        iterations=iterations,
        planning_time_s=watch.elapsed(),
        message=f"solved: {nodes} nodes, {iterations} iterations, raw path {length:.1f} m",
        stats=stats,
    )


def budget_message(iterations: int, watch: Stopwatch, budget: Budget, nodes: int) -> str:
    """The failure message of a search that ran out of budget."""
    if watch.expired():
        limit = f"time budget of {budget.max_time_s:g} s spent"
    else:
        limit = f"iteration budget of {budget.max_iterations} spent"
    return (
        f"no path found within the budget: {limit} "
        f"({iterations} iterations, {watch.elapsed():.3f} s, {nodes} nodes)"
    )


# ----------------------------------------------------------------------------- RRT


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
        the start (see :class:`~rrtdrive.planning.rrt.SampleSource`).
    exact_goal_edge : bool
        Confirm an edge into the goal by the exact body test when the fast test fails
        (see :class:`EdgeTester`).

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
            Iteration and time limits.

        Returns
        -------
        PlanResult
            Solved with the raw tree path, or a failure with the tree.
        """
        watch = Stopwatch(budget)
        early = precheck(problem, self.name, watch)
        if early is not None:
            return early
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
        if goal_index < 0:
            return failure(
                self.name,
                PlanStatus.NO_PATH_IN_BUDGET,
                watch,
                budget_message(iterations, watch, budget, len(tree)),
                trees=(tree.freeze(),),
                iterations=iterations,
                stats=stats,
            )
        raw = tree.branch(goal_index)[::-1]
        return solved_result(self.name, raw, (tree.freeze(),), iterations, watch, stats)
