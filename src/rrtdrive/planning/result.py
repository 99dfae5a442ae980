"""The preamble and epilogue every planner shares: stopwatch, precheck and result building.

A planner's ``solve`` is ``run_query(name, problem, budget, search)``: the
stopwatch starts, :func:`~rrtdrive.planning.base.precheck` answers an invalid
start or goal or a provably unreachable goal, :func:`already_there` a start that is
the goal (a path of 0 m), and only then does ``search`` run. A search ends in
:func:`solved`, :func:`solved_result` (a baseline's raw tree path),
:func:`search_result` (that, or the out-of-budget failure), :func:`timeout_result`
(the safety cap stopped it) or :func:`~rrtdrive.planning.base.failure`.

Counted budgets decide a query's outcome; the wall-clock ``max_time_s`` is a
safety cap whose only outcome is :attr:`PlanStatus.TIMEOUT` (see
:class:`~rrtdrive.types.Budget`), so a seeded query answers the same on any
machine unless it reports ``timeout``.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable

import numpy as np

from rrtdrive.collision.lock import query_lock
from rrtdrive.geometry import wrap_angle
from rrtdrive.planning.base import PlanningProblem, Stopwatch, failure, polyline_path, precheck
from rrtdrive.planning.diagnosis import Diagnosis, diagnose
from rrtdrive.types import Budget, InputError, Path, PlanResult, PlanStatus, Pose, Tree
from rrtdrive.values import counted

__all__ = [
    "check_query",
    "SAME_POSE_TOL",
    "Search",
    "already_there",
    "at_goal",
    "run_query",
    "same_pose",
    "solved",
    "straight_ahead",
    "straight_ahead_result",
    "solved_result",
    "search_result",
    "timeout_result",
    "timeout_message",
    "budget_message",
    "baseline_caveat",
]

#: The body of a planner's query: runs with the started stopwatch once the precheck passed.
Search = Callable[[Stopwatch], PlanResult]


def check_query(problem: object, rng: object, budget: object) -> None:
    """Raise :class:`InputError` naming ``problem``, ``rng`` or ``budget`` when of the wrong type.

    Examples
    --------
    >>> check_query(None, np.random.default_rng(0), Budget())  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    rrtdrive.types.InputError: problem: expected a PlanningProblem (...), got NoneType
    """
    if not isinstance(problem, PlanningProblem):
        raise InputError(
            "problem: expected a PlanningProblem (PlanningProblem.from_map(m)), "
            f"got {type(problem).__name__}"
        )
    if not isinstance(rng, np.random.Generator):
        raise InputError(
            "rng: expected a numpy.random.Generator (np.random.default_rng(seed)), "
            f"got {type(rng).__name__}"
        )
    if not isinstance(budget, Budget):
        raise InputError(f"budget: expected a Budget, got {type(budget).__name__}")


def run_query(
    planner: str,
    problem: PlanningProblem,
    budget: Budget,
    search: Search,
    prepare: Callable[[], object] | None = None,
    *,
    rng: np.random.Generator,
    tree_edges: bool = True,
    probe: Callable[[], Diagnosis | None] | None = None,
    reverses: bool = False,
    exact_goal_edges: bool = False,
    keeps: float = 0.0,
    headings: bool = True,
) -> PlanResult:
    """Set the map up, start the stopwatch, fail early on a hopeless query, else search.

    The per-map set-up (the connectivity labels the precheck reads, the start's
    sampling cells and whatever ``prepare`` builds) runs before the stopwatch
    starts; set-up built on first use during the search runs in the stopwatch's
    :meth:`~rrtdrive.planning.base.Stopwatch.setup` blocks. Both are reported as
    ``setup_time_s`` and never counted in ``planning_time_s`` or against the budget.
    It is cached on the map's checker, so a second query on the same map finds it
    built.

    Parameters
    ----------
    planner : str
        Registered planner name, for the result.
    problem : PlanningProblem
        The query.
    budget : Budget
        Its limits; the stopwatch keeps the safety cap ``max_time_s``.
    search : callable
        ``search(watch) -> PlanResult``, the planner's own work.
    prepare : callable, optional
        The planner's own per-map set-up (cached on the checker).
    rng : numpy.random.Generator
        The planner's ``rng``, checked with ``problem`` and ``budget``
        (:func:`check_query`) before anything reads them.
    tree_edges : bool
        Whether the planner's every search grows swept tree edges, so that a failure
        may be blamed on their keep (:func:`~rrtdrive.planning.diagnosis.diagnose`).
    probe : callable, optional
        The planner's own last look at a counted failure that
        :func:`~rrtdrive.planning.diagnosis.diagnose` found nothing in (the reversing
        planners: :func:`~rrtdrive.planning.hybrid.probe.reverse_probe`); timed with
        the diagnosis.
    reverses : bool
        Whether the planner changes gear where ``problem.reverse`` allows it; one that
        plans forward only is diagnosed as a forward query (its failure says that a
        reversing path may exist).
    exact_goal_edges : bool
        Whether the planner tests an edge into the goal exactly when its swept test
        fails (the tree baselines): the diagnosis then blames no keep at the goal.
    keeps : float
        The least body clearance the planner's paths keep, metres (capped at the
        ends' own): the precheck proves a gap too narrow for the car and that.
    headings : bool
        Whether the planner keeps the start's and goal's headings; the tree baselines
        plan positions only, so a failure of theirs is not blamed on a heading.

    Returns
    -------
    PlanResult
        The precheck's failure, or what ``search`` returns; its ``stats`` get
        ``grid_resolution_m``, the checker's cell size.

    Examples
    --------
    >>> from rrtdrive.maps import builtin_map
    >>> problem = PlanningProblem.from_map(builtin_map("no_path"))
    >>> rng = np.random.default_rng(0)
    >>> run_query("demo", problem, Budget(), lambda watch: None, rng=rng).status.value
    'proven_unreachable'
    """
    check_query(problem, rng, budget)
    # One query at a time per checker: GEOS prepared geometry is not thread-safe.
    with query_lock(problem.checker):
        return _run_query(planner, problem, budget, search, prepare, tree_edges, probe,
                          reverses, exact_goal_edges, keeps, headings)


def _run_query(
    planner: str, problem: PlanningProblem, budget: Budget, search: Search,
    prepare: Callable[[], object] | None, tree_edges: bool,
    probe: Callable[[], Diagnosis | None] | None, reverses: bool, exact_goal_edges: bool,
    keeps: float, headings: bool,
) -> PlanResult:
    """:func:`run_query`'s body, under the checker's lock."""
    t0 = time.perf_counter()
    checker = problem.checker
    checker.component_labels  # noqa: B018 - built here, read by the precheck
    checker.free_cells((problem.start.x, problem.start.y))
    if prepare is not None:
        prepare()
    setup = time.perf_counter() - t0
    watch = Stopwatch(budget)
    result = precheck(problem, planner, watch, keeps)
    if result is None and at_goal(problem):
        result = already_there(planner, problem, watch)
    if result is None:
        result = search(watch)
    if watch.capped and result.status is not PlanStatus.TIMEOUT:
        # The cap was met on the way (an expired() check latched it) though the search
        # answered otherwise: that answer depends on how far this machine got (item 4).
        result = timeout_result(
            result.planner, watch, result.iterations, result.trees, result.stats,
            result.raw_path,
        )  # fmt: skip
    # The grid's cell size, coarser than configured on a very big map.
    stats = {**result.stats, "grid_resolution_m": float(checker.resolution)}
    # Set-up the search met on its way (a map's first finer grid) is set-up too.
    setup += watch.setup_s
    if result.success:
        return dataclasses.replace(result, setup_time_s=setup, stats=stats)
    # A failure says which constraint makes the query hard, measured after the stopwatch.
    t_diagnosis = time.perf_counter()
    def proved(name: str) -> bool:  # a Hybrid A* stat, or the default's escalation's
        return stats.get(name, stats.get(f"hybrid_{name}", 0.0)) > 0.0

    # A planner that plans forward only failed forward, whatever the problem allows.
    asked = problem if reverses else _forward(problem)
    found = diagnose(
        asked, tree_edges=tree_edges, no_approach=proved("no_approach"),
        start_exhausted=proved("start_exhausted"), exact_goal_edges=exact_goal_edges,
        headings=headings,
    )  # fmt: skip
    if found is None and probe is not None and result.status in _PROBED:
        found = probe()
    stats["diagnosis_time_s"] = time.perf_counter() - t_diagnosis
    return dataclasses.replace(result, setup_time_s=setup, diagnosis=found, stats=stats)


def _forward(problem: PlanningProblem) -> PlanningProblem:
    """``problem`` with reversing not allowed (itself when it was not)."""
    return dataclasses.replace(problem, reverse=False) if problem.reverse else problem


#: The failures a planner's probe looks at: counted ones (a timeout's would depend on the
#: machine; an invalid start or goal has its own finding).
_PROBED = frozenset(
    {PlanStatus.NO_PATH_IN_BUDGET, PlanStatus.POSTPROCESS_FAILED, PlanStatus.PROVEN_UNREACHABLE}
)

#: Start and goal closer than this (metres, and radians of heading) are one pose: the
#: plan JSON's 6 decimals cannot tell them apart (a goal 1e-6 rad off the start's
#: heading was planned as a manoeuvre, and forward only it failed).
SAME_POSE_TOL = 1e-6
# A hair above the tolerance: wrap_angle(1e-6) may round to just over 1e-6.
_POSE_TOL = SAME_POSE_TOL * (1.0 + 1e-9)


def same_pose(a: Pose, b: Pose) -> bool:
    """Whether two poses are one (position and heading within :data:`SAME_POSE_TOL`).

    Examples
    --------
    >>> same_pose(Pose(5.0, 6.0, 0.0), Pose(5.0, 6.0, 1e-6))
    True
    >>> same_pose(Pose(5.0, 6.0, 0.0), Pose(5.0, 6.0, 1e-5))
    False
    """
    close = math.hypot(b.x - a.x, b.y - a.y) <= _POSE_TOL
    return close and abs(wrap_angle(b.yaw - a.yaw)) <= _POSE_TOL


def at_goal(problem: PlanningProblem) -> bool:
    """Whether the start is the goal pose (:func:`same_pose`).

    Examples
    --------
    >>> import dataclasses
    >>> from rrtdrive.maps import builtin_map
    >>> m = builtin_map("parking_lot")
    >>> here = dataclasses.replace(m, goal=m.start)
    >>> at_goal(PlanningProblem.from_map(m)), at_goal(PlanningProblem.from_map(here))
    (False, True)
    """
    return same_pose(problem.start, problem.goal)


def already_there(planner: str, problem: PlanningProblem, watch: Stopwatch) -> PlanResult:
    """The answer when the start is the goal: a path of 0 m that stays at the pose.

    Every planner gives it, before any search: a search would look for a way to
    leave and come back (a forward-only one, a loop round the map).
    """
    a, b = problem.start, problem.goal
    rows = np.array([[a.x, a.y, a.yaw, 0.0, 1.0], [b.x, b.y, b.yaw, 0.0, 1.0]])
    return solved(
        planner, watch, Path(rows, rows[:, :2]), rows[:, :2].copy(), (), 0,
        "the start is the goal pose: nothing to drive (a path of 0 m)", {},
    )  # fmt: skip


def straight_ahead(a: Pose, b: Pose) -> bool:
    """Whether ``b`` lies ahead of ``a`` on its heading's line, facing the same way.

    Within :data:`SAME_POSE_TOL` metres aside and radians of heading.

    Examples
    --------
    >>> straight_ahead(Pose(0.0, 0.0, 1.0), Pose(0.54e-5, 0.84e-5, 1.0))
    True
    >>> straight_ahead(Pose(0.0, 0.0, 0.0), Pose(0.1, 1e-3, 0.0))
    False
    """
    c, s = math.cos(a.yaw), math.sin(a.yaw)
    dx, dy = b.x - a.x, b.y - a.y
    aside = abs(dy * c - dx * s)
    turn = abs(wrap_angle(b.yaw - a.yaw))
    return dx * c + dy * s > 0.0 and aside <= _POSE_TOL and turn <= _POSE_TOL


def straight_ahead_result(
    planner: str,
    problem: PlanningProblem,
    watch: Stopwatch,
    clearance: float,
    stats: dict[str, float],
    spacing: float = 0.25,
) -> PlanResult | None:
    """The straight line to a goal :func:`straight_ahead`, when its body keeps ``clearance``.

    For a goal too close for a smoother's heading legs and turns (a goal 1e-5 m
    ahead: the rounding of its position is a turn the car cannot make in that
    length); ``None`` when the goal is not straight ahead or the line is not clear.
    """
    a, b = problem.start, problem.goal
    if not straight_ahead(a, b):
        return None
    length = math.hypot(b.x - a.x, b.y - a.y)
    n = max(1, math.ceil(length / spacing * (1.0 - 1e-9)))
    rows = np.zeros((n + 1, 5))
    rows[:, 0] = np.linspace(a.x, b.x, n + 1)
    rows[:, 1] = np.linspace(a.y, b.y, n + 1)
    rows[:, 2], rows[-1, 2], rows[:, 4] = a.yaw, b.yaw, 1.0
    if not problem.checker.path_free(rows, clearance=clearance)[0]:
        return None
    ends = rows[[0, -1], :2].copy()
    message = f"solved: the goal lies straight ahead (a straight line of {length:.2g} m)"
    path = Path(rows, ends)
    nodes = int(stats.get("nodes", 0))
    return solved(planner, watch, path, ends.copy(), (), 0, message, stats, nodes=nodes)


def solved(
    planner: str,
    watch: Stopwatch,
    path: Path,
    raw_path: np.ndarray,
    trees: tuple[Tree, ...],
    iterations: int,
    message: str,
    stats: dict[str, float],
    *,
    nodes: int | None = None,
    planning_time_s: float | None = None,
) -> PlanResult:
    """A :attr:`PlanStatus.SOLVED` result.

    ``nodes`` defaults to the size of ``trees``; ``planning_time_s`` to the
    stopwatch's elapsed time now.
    """
    return PlanResult(
        status=PlanStatus.SOLVED,
        planner=planner,
        path=path,
        raw_path=raw_path,
        trees=trees,
        nodes=sum(len(t) for t in trees) if nodes is None else nodes,
        iterations=iterations,
        planning_time_s=watch.elapsed() if planning_time_s is None else planning_time_s,
        message=message,
        stats=stats,
    )


def baseline_caveat(path: Path, problem: PlanningProblem) -> str:
    """What a baseline's solved path does not guarantee: its curvature and end headings.

    The baselines return the raw tree path, with corners and whatever headings
    its first and last edges have; the note gives its largest (Menger) curvature as
    a multiple of the car's ``kappa_max``, its largest turn on the spot (a corner,
    where the rows' yaw jumps) and its heading errors at both ends.

    Examples
    --------
    >>> from rrtdrive.maps import builtin_map
    >>> from rrtdrive.planning.base import polyline_path
    >>> problem = PlanningProblem.from_map(builtin_map("overtake"))
    >>> path = polyline_path(np.array([[5.0, 44.0], [50.0, 48.0], [92.0, 44.0]]))
    >>> print(baseline_caveat(path, problem).split(": ")[1])  # doctest: +NORMALIZE_WHITESPACE
    max curvature 0.0 x kappa_max, turns on the spot of up to 11 deg, heading error 5 deg
    at the start, 5 deg at the goal
    """
    samples = path.samples
    ratio = path.max_curvature / problem.vehicle.kappa_max
    if len(samples):
        start_err = abs(math.degrees(wrap_angle(samples[0, 2] - problem.start.yaw)))
        goal_err = abs(math.degrees(wrap_angle(samples[-1, 2] - problem.goal.yaw)))
        # A corner of the polyline is a turn on the spot, where the rows' yaw jumps: the
        # curvature of the kappa column does not show it (0.0 x kappa_max on a polyline).
        turn = float(np.abs(wrap_angle(np.diff(samples[:, 2]))).max(initial=0.0))
    else:
        start_err = goal_err = turn = math.nan
    return (
        f"baselines ignore curvature and headings: max curvature {ratio:.1f} x kappa_max, "
        f"turns on the spot of up to {math.degrees(turn):.0f} deg, heading error "
        f"{start_err:.0f} deg at the start, {goal_err:.0f} deg at the goal"
    )


def solved_result(
    planner: str,
    problem: PlanningProblem,
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
    problem : PlanningProblem
        The query (for the message's :func:`baseline_caveat`).
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
        Its message counts nodes, iterations and the raw length, then says what
        the path does not guarantee (:func:`baseline_caveat`).
    """
    raw = np.array(raw_path, dtype=float).reshape(-1, 2)
    raw.setflags(write=False)
    length = float(np.sum(np.hypot(*np.diff(raw, axis=0).T)))
    stats = {**stats, "raw_length_m": length, "waypoints": len(raw)}
    nodes = sum(len(t) for t in trees)
    path = polyline_path(raw)
    message = (
        f"solved: {nodes} nodes, {iterations} iterations, raw path {length:.1f} m; "
        + baseline_caveat(path, problem)
    )
    return solved(planner, watch, path, raw, trees, iterations, message, stats, nodes=nodes)


def timeout_message(iterations: int, budget: Budget, unit: str = "iterations") -> str:
    """The message of a query stopped by the safety cap: the cap, the count, what to change.

    ``unit`` names the count (e.g. ``"expansions"`` for a search over a lattice).

    Examples
    --------
    >>> msg = timeout_message(1234, Budget(max_time_s=5.0))
    >>> msg.split(": ")[0]
    'stopped by the 5 s safety cap after 1234 iterations'
    >>> msg.split("; ")[1]
    'raise --max-time or lower --max-iterations'
    >>> timeout_message(1, Budget(max_time_s=5.0)).split(":")[0]
    'stopped by the 5 s safety cap after 1 iteration'
    """
    return (
        f"stopped by the {budget.max_time_s:g} s safety cap after {counted(iterations, unit)}: "
        "the result depends on this machine's speed; raise --max-time or lower --max-iterations"
    )


def timeout_result(
    planner: str,
    watch: Stopwatch,
    iterations: int,
    trees: tuple[Tree, ...] = (),
    stats: dict[str, float] | None = None,
    raw_path: np.ndarray | None = None,
    unit: str = "iterations",
) -> PlanResult:
    """The result of a query that the wall-clock safety cap stopped: :attr:`PlanStatus.TIMEOUT`.

    Every planner ends a query whose stopwatch is :attr:`~Stopwatch.capped` here,
    whatever it had found by then (a path found after some work was cut short, or
    the best path so far of an anytime planner, would depend on the machine's
    speed). The message is :func:`timeout_message`.

    Parameters
    ----------
    planner : str
        Registered planner name.
    watch : Stopwatch
        The query's stopwatch (its budget names the cap).
    iterations : int
        Iterations (or expansions) done before the cap.
    trees : tuple of Tree
        Search trees so far, for plotting.
    stats : dict, optional
        Planner statistics so far.
    raw_path : numpy.ndarray, optional
        A tree path the query was working on, if any.
    unit : str
        What ``iterations`` counts, for the message (``"expansions"`` ...).

    Returns
    -------
    PlanResult
        Failed, empty path, status ``timeout``; ``iterations`` is stored as given.

    Examples
    --------
    >>> ticks = iter([0.0, 9.0, 9.0])
    >>> watch = Stopwatch(Budget(max_time_s=5.0), clock=lambda: next(ticks))
    >>> watch.expired()
    True
    >>> res = timeout_result("demo", watch, 7)
    >>> res.status.value, res.success, res.message.split(":")[0]
    ('timeout', False, 'stopped by the 5 s safety cap after 7 iterations')
    """
    return failure(
        planner,
        PlanStatus.TIMEOUT,
        watch,
        timeout_message(iterations, watch.budget, unit),
        trees=trees,
        iterations=iterations,
        raw_path=raw_path,
        stats=stats,
    )


def budget_message(iterations: int, budget: Budget, nodes: int) -> str:
    """The failure message of a search that spent its iteration budget.

    No wall time in it: a seeded run's JSON is the same on any machine (the time is
    ``planning_time_s``). It says what to change, as :func:`timeout_message` does.

    Examples
    --------
    >>> budget_message(1, Budget(max_iterations=1), 2)  # doctest: +NORMALIZE_WHITESPACE
    'no path found within the budget: iteration budget of 1 spent (1 iteration, 2 nodes);
    raise --max-iterations'
    """
    return (
        f"no path found within the budget: iteration budget of {budget.max_iterations} spent "
        f"({counted(iterations, 'iterations')}, {counted(nodes, 'nodes')}); raise --max-iterations"
    )


def search_result(
    planner: str,
    problem: PlanningProblem,
    raw_path: np.ndarray | None,
    trees: tuple[Tree, ...],
    iterations: int,
    watch: Stopwatch,
    budget: Budget,
    stats: dict[str, float],
) -> PlanResult:
    """The end of a baseline search: :func:`solved_result`, out of budget, or the timeout.

    A query whose stopwatch is capped ends in :func:`timeout_result` even with a
    path (an anytime search's best path so far depends on the machine's speed).

    Parameters
    ----------
    planner : str
        Registered planner name.
    problem : PlanningProblem
        The query.
    raw_path : numpy.ndarray or None
        The tree path found, ``None`` when the budget ended first.
    trees : tuple of Tree
        Frozen search trees.
    iterations : int
        Sampling iterations used.
    watch : Stopwatch
        The query's stopwatch.
    budget : Budget
        The query's limits (named in the failure message).
    stats : dict
        Planner statistics.

    Returns
    -------
    PlanResult
    """
    if watch.capped:
        return timeout_result(planner, watch, iterations, trees, stats)
    if raw_path is None:
        return failure(
            planner,
            PlanStatus.NO_PATH_IN_BUDGET,
            watch,
            budget_message(iterations, budget, sum(len(t) for t in trees)),
            trees=trees,
            iterations=iterations,
            stats=stats,
        )
    return solved_result(planner, problem, raw_path, trees, iterations, watch, stats)
