"""OMPL comparators behind rrtdrive's :class:`~rrtdrive.planning.Planner` protocol.

Importing this module registers, for each space and algorithm, a planner named
``ompl-<space>-<algorithm>``:

- spaces: ``r2`` (``RealVectorStateSpace(2)``, the geometric problem without the
  curvature bound) and ``rs`` (``ReedsSheppStateSpace(r_min)``, curvature-bounded,
  forward and reverse);
- algorithms: ``rrtconnect`` (range 5 m, the paper's RRT-Connect step),
  ``rrtstar``, ``bitstar`` and ``informed-rrtstar`` (OMPL's defaults).

OMPL itself is imported only when a planner solves, so the names are always
listed; solving without OMPL installed raises :class:`~rrtdrive.types.InputError`
(``pip install 'rrtdrive[ompl]'``).

Same map, same checker: a state is valid in R² when the checker's clearance at the
rear axle is at least the swept-capsule radius of its edge test (W/2 + margin), and
in Reeds–Shepp space when the body's covering discs are clear
(:meth:`~rrtdrive.collision.CollisionChecker.pose_free_fast`). Motions are checked
at 0.25 m. The optimising planners stop at their first solution (a cost threshold
of infinity), and every solution is simplified with OMPL's ``simplifySolution`` in
the remaining budget. The returned path is sampled at most 0.25 m apart: R²
polylines as the baselines' raw paths (headings along the segments, Menger
curvature at the corners), Reeds–Shepp curves as gear rows
``[x, y, yaw, kappa, gear]`` (:func:`reeds_shepp_path`): the gear from the
direction of travel against the yaw, each cusp found on the curve and its row
repeated, κ = gear · d(yaw)/ds within each gear segment (a cusp is not a
curvature), so :func:`rrtdrive.verify.verify_path` checks them segment by segment.

Before the search, as for rrtdrive's planners, an invalid start or goal body
ends the query; OMPL gets no connectivity proof, so on an unreachable goal it
searches to its time budget.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rrtdrive.geometry import wrap_angle
from rrtdrive.planning.base import (
    PLANNERS,
    PlanningProblem,
    Stopwatch,
    failure,
    polyline_path,
)
from rrtdrive.planning.result import already_there, at_goal
from rrtdrive.types import Budget, InputError, Path, PlanResult, PlanStatus, Pose

__all__ = [
    "OmplPlanner",
    "OMPL_PLANNERS",
    "SPACES",
    "ALGORITHMS",
    "simple_setup",
    "reeds_shepp_path",
    "gear_rows",
]

#: Space short names.
SPACES = ("r2", "rs")

#: Algorithm short name -> OMPL geometric planner class name.
ALGORITHMS = {
    "rrtconnect": "RRTConnect",
    "rrtstar": "RRTstar",
    "bitstar": "BITstar",
    "informed-rrtstar": "InformedRRTstar",
}

#: Default ``setRange`` per algorithm (``None`` keeps OMPL's default).
_DEFAULT_RANGE = {"rrtconnect": 5.0}

#: Registered names.
OMPL_PLANNERS = tuple(f"ompl-{s}-{a}" for s in SPACES for a in ALGORITHMS)

_SPACING = 0.25  # largest gap between returned samples (SPEC §5)


@functools.lru_cache(maxsize=1)
def _ompl() -> tuple[Any, Any, Any]:
    try:
        from ompl import base as ob
        from ompl import geometric as og
        from ompl import util as ou
    except ImportError:
        raise InputError(
            "planner: the OMPL planners need OMPL; install it with pip install 'rrtdrive[ompl]'"
        ) from None
    ou.setLogLevel(ou.LogLevel.LOG_NONE)
    return ob, og, ou


def simple_setup(problem: PlanningProblem, space_kind: str) -> tuple[Any, Any]:
    """OMPL's ``SimpleSetup`` for ``problem`` on rrtdrive's checker, start and goal set.

    Parameters
    ----------
    problem : PlanningProblem
        Map, checker, start and goal.
    space_kind : str
        ``"r2"`` (``RealVectorStateSpace(2)``, valid where the clearance reaches the
        edge test's capsule radius), ``"rs"`` (``ReedsSheppStateSpace``) or
        ``"dubins"`` (``DubinsStateSpace``), both with the car's minimum turning
        radius and valid where the body's covering discs are clear. Motions are
        checked every 0.25 m.

    Returns
    -------
    ss, si
        The ``SimpleSetup`` (no planner yet) and its ``SpaceInformation``.
    """
    ob, og, _ = _ompl()
    checker = problem.checker
    r2 = space_kind == "r2"
    if r2:
        space = ob.RealVectorStateSpace(2)
    elif space_kind == "rs":
        space = ob.ReedsSheppStateSpace(problem.vehicle.min_turning_radius)
    elif space_kind == "dubins":
        space = ob.DubinsStateSpace(problem.vehicle.min_turning_radius)
    else:
        raise InputError(f"space: expected r2, rs or dubins, got {space_kind!r}")
    xmin, ymin, xmax, ymax = problem.bounds
    bounds = ob.RealVectorBounds(2)
    bounds.setLow(0, xmin)
    bounds.setLow(1, ymin)
    bounds.setHigh(0, xmax)
    bounds.setHigh(1, ymax)
    space.setBounds(bounds)
    ss = og.SimpleSetup(space)
    if r2:
        clearance, radius = checker.clearance, checker.edge_radius
        ss.setStateValidityChecker(lambda s: clearance(s[0], s[1]) >= radius)
    else:
        # The covering discs, not the exact test: OMPL checks motions only every 0.25 m,
        # and with the exact test at zero clearance its bodies clip walls between the
        # checks (session 44: dead_end's Reeds-Shepp path 42.35 m, verified false, where
        # the discs give 27.69 m, verified). The price: poses up to about 0.6 m in front
        # of a wall, free by shapely, are refused (invalid_start from OMPL).
        free = checker.pose_free_fast
        ss.setStateValidityChecker(lambda s: free(s.getX(), s.getY(), s.getYaw()))
    si = ss.getSpaceInformation()
    si.setStateValidityCheckingResolution(_SPACING / space.getMaximumExtent())
    start, goal = space.allocState(), space.allocState()
    for st, pose in ((start, problem.start), (goal, problem.goal)):
        if r2:
            st[0], st[1] = pose.x, pose.y
        else:
            st.setX(pose.x)
            st.setY(pose.y)
            # OMPL's SO2 bounds are [-pi, pi): a yaw of exactly pi is out of bounds, and
            # a planner then fails silently (turning_bulb's goal was never solved).
            st.setYaw(wrap_angle(pose.yaw))
    ss.setStartAndGoalStates(start, goal)
    return ss, si


@dataclass(frozen=True)
class OmplPlanner:
    """An OMPL geometric planner on rrtdrive's problem and checker.

    Parameters
    ----------
    space : str
        ``"r2"`` or ``"rs"`` (Reeds–Shepp with the car's minimum turning radius).
    algorithm : str
        A key of :data:`ALGORITHMS`.
    range_m : float, optional
        ``setRange`` of the planner (default: 5 m for RRTConnect, OMPL's otherwise).
    simplify : bool
        Run ``simplifySolution`` on a found path.

    Examples
    --------
    >>> from rrtdrive.planning import make_planner
    >>> make_planner("ompl-r2-rrtconnect").name
    'ompl-r2-rrtconnect'
    """

    space: str
    algorithm: str
    range_m: float | None = None
    simplify: bool = True
    name: str = field(init=False)

    @property
    def reverses(self) -> bool:
        """Whether its paths change gear: Reeds–Shepp's do, whether or not asked to."""
        return self.space == "rs"

    def __post_init__(self) -> None:
        if self.space not in SPACES:
            raise InputError(f"space: expected one of {SPACES}, got {self.space!r}")
        if self.algorithm not in ALGORITHMS:
            raise InputError(
                f"algorithm: expected one of {', '.join(sorted(ALGORITHMS))}, "
                f"got {self.algorithm!r}"
            )
        if self.range_m is not None and not (
            isinstance(self.range_m, (int, float)) and math.isfinite(self.range_m)
            and self.range_m > 0
        ):
            raise InputError(f"range_m: must be a number > 0, got {self.range_m!r}")
        object.__setattr__(self, "name", f"ompl-{self.space}-{self.algorithm}")

    def solve(
        self, problem: PlanningProblem, rng: np.random.Generator, budget: Budget
    ) -> PlanResult:
        """Plan with OMPL within ``budget.max_time_s`` (OMPL has no iteration budget).

        Parameters
        ----------
        problem : PlanningProblem
            Map, checker, start and goal.
        rng : numpy.random.Generator
            Seeds OMPL's global RNG (one draw), so a seed gives the same result.
        budget : Budget
            Only ``max_time_s`` applies.

        Returns
        -------
        PlanResult
        """
        ob, og, ou = _ompl()
        watch = Stopwatch(budget)
        checker = problem.checker
        if not checker.pose_free(problem.start.as_tuple()):
            return failure(
                self.name, PlanStatus.INVALID_START, watch, "start: the car's body collides there"
            )
        if not checker.pose_free(problem.goal.as_tuple()):
            return failure(
                self.name, PlanStatus.INVALID_GOAL, watch, "goal: the car's body collides there"
            )
        r2 = self.space == "r2"
        for pose, status, label in (
            (problem.start, PlanStatus.INVALID_START, "start"),
            (problem.goal, PlanStatus.INVALID_GOAL, "goal"),
        ):
            # Free, yet no valid OMPL state (its conservative test, see simple_setup): said
            # now, where OMPL searched a goal like that to the end of its budget.
            if not _ompl_valid(checker, pose, r2):
                test = "the rear axle's edge capsule" if r2 else "the body's covering discs"
                return failure(
                    self.name, status, watch,
                    f"{label}: free, but too near an obstacle for the OMPL comparator, whose "
                    f"states must clear {test} (a conservative test; move it a little off)",
                )
        if at_goal(problem):
            # As every planner answers it (run_query): two equal rows, 0 m. OMPL's own
            # "solution" of a start that is the goal had no rows (an audit).
            return already_there(self.name, problem, watch)
        ss, si = simple_setup(problem, self.space)
        ou.RNG.setSeed(int(rng.integers(1, 2**31 - 1)))  # before the planner is built
        planner = getattr(og, ALGORITHMS[self.algorithm])(si)
        range_m = self.range_m if self.range_m is not None else _DEFAULT_RANGE.get(self.algorithm)
        if range_m is not None:
            planner.setRange(float(range_m))
        ss.setPlanner(planner)
        objective = ob.PathLengthOptimizationObjective(si)
        objective.setCostThreshold(ob.Cost(float("inf")))  # stop at the first solution
        ss.setOptimizationObjective(objective)
        status = ss.solve(float(budget.max_time_s))
        text = status.asString()
        data = ob.PlannerData(si)
        ss.getPlannerData(data)
        nodes = int(data.numVertices())
        stats: dict[str, float] = {}
        if text != "Exact solution":
            kind = {
                "Invalid start": PlanStatus.INVALID_START,
                "Invalid goal": PlanStatus.INVALID_GOAL,
            }.get(text, PlanStatus.NO_PATH_IN_BUDGET)
            result = failure(self.name, kind, watch, f"OMPL: {text}")
            return _with_nodes(result, nodes)
        if self.simplify:
            remaining = budget.max_time_s - watch.elapsed()
            t0 = time.perf_counter()
            ss.simplifySolution(max(0.01, remaining))
            stats["simplify_time_s"] = time.perf_counter() - t0
        solution = ss.getSolutionPath()
        vertices = _states(solution, r2)
        if r2:
            path = polyline_path(vertices[:, :2], _SPACING)
        else:
            path = reeds_shepp_path(ss.getStateSpace(), solution, vertices[:, :2])
        return PlanResult(
            status=PlanStatus.SOLVED,
            planner=self.name,
            path=path,
            raw_path=vertices[:, :2].copy(),
            trees=(),
            nodes=nodes,
            iterations=0,
            planning_time_s=watch.elapsed(),
            message=f"OMPL {ALGORITHMS[self.algorithm]} in {self.space}: {text}",
            stats=stats,
        )


def _ompl_valid(checker: Any, pose: Pose, r2: bool) -> bool:
    """Whether ``pose`` is a valid state for the OMPL comparators (as in simple_setup)."""
    if r2:
        return bool(checker.clearance(pose.x, pose.y) >= checker.edge_radius)
    return bool(checker.pose_free_fast(pose.x, pose.y, pose.yaw))


def _with_nodes(result: PlanResult, nodes: int) -> PlanResult:
    return dataclasses.replace(result, nodes=nodes)


def _states(path: Any, r2: bool) -> np.ndarray:
    """``(N, 3)`` array of ``x, y, yaw`` (yaw 0 in R²) of an OMPL geometric path."""
    n = path.getStateCount()
    out = np.zeros((n, 3))
    for i in range(n):
        s = path.getState(i)
        if r2:
            out[i, 0], out[i, 1] = s[0], s[1]
        else:
            out[i] = (s.getX(), s.getY(), s.getYaw())
    return out


def reeds_shepp_path(space: Any, solution: Any, waypoints: np.ndarray) -> Path:
    """The gear rows of an OMPL Reeds–Shepp solution, sampled at most 0.1 m apart.

    Each curve between consecutive solution states is sampled by
    ``space.interpolate``, and at each sample the car's motion (a micrometre either
    way along the curve) is along its yaw or against it; where that differs between
    two samples a cusp lies between them, found by bisection on the curve and
    inserted, so the cusp row repeats exactly. A cusp at a solution state is a
    sample already.

    Parameters
    ----------
    space : ompl.base.ReedsSheppStateSpace
        The solution's space.
    solution : ompl.geometric.PathGeometric
        The (simplified) solution, not interpolated.
    waypoints : numpy.ndarray
        ``(M, 2)`` kept as the path's waypoints.

    Returns
    -------
    Path
        Rows ``[x, y, yaw, kappa, gear]`` by :func:`gear_rows`.
    """
    tmp = space.allocState()

    def at(a: Any, b: Any, f: float) -> tuple[float, float, float]:
        space.interpolate(a, b, min(1.0, max(0.0, f)), tmp)
        return (tmp.getX(), tmp.getY(), tmp.getYaw())

    pieces: list[np.ndarray] = []
    for i in range(solution.getStateCount() - 1):
        a, b = solution.getState(i), solution.getState(i + 1)
        length = float(space.distance(a, b))
        if length < 1e-9:
            continue
        fractions = list(np.linspace(0.0, 1.0, max(2, math.ceil(length / _DENSE)) + 1))
        eps = 1e-6 / length  # a micrometre along the curve
        curve = functools.partial(at, a, b)
        gears = [_motion_gear(curve, f, eps) for f in fractions]
        cusps = [
            _bisect_cusp(curve, fractions[k], fractions[k + 1], gears[k], eps)
            for k in range(len(fractions) - 1)
            if gears[k] != gears[k + 1]
        ]
        states = np.array([at(a, b, f) for f in sorted(fractions + cusps)])
        pieces.append(states if not pieces else states[1:])
    if not pieces:
        return Path(np.zeros((0, 5)), waypoints)
    return Path(gear_rows(np.vstack(pieces)), waypoints)


_DENSE = 0.4 * _SPACING  # sample step along a Reeds–Shepp curve


def _step_gears(states: np.ndarray) -> np.ndarray:
    """+1 / -1 per step of ``(N, 3)`` states: the chord along or against the mid-step yaw."""
    d = np.diff(states[:, :2], axis=0)
    mid = states[:-1, 2] + 0.5 * wrap_angle(np.diff(states[:, 2]))
    return np.where(d[:, 0] * np.cos(mid) + d[:, 1] * np.sin(mid) >= 0.0, 1, -1)


def _motion_gear(curve: Any, f: float, eps: float) -> int:
    """+1 when the car moves along its yaw at curve fraction ``f``, -1 against it."""
    lo, hi = max(0.0, f - eps), min(1.0, f + eps)
    x0, y0, _ = curve(lo)
    x1, y1, _ = curve(hi)
    yaw = curve(f)[2]
    return 1 if (x1 - x0) * math.cos(yaw) + (y1 - y0) * math.sin(yaw) >= 0.0 else -1


def _bisect_cusp(curve: Any, lo: float, hi: float, gear_lo: int, eps: float) -> float:
    """The curve fraction in ``(lo, hi)`` where the motion's gear changes from ``gear_lo``."""
    while hi - lo > eps:
        mid = 0.5 * (lo + hi)
        if _motion_gear(curve, mid, 0.25 * eps) == gear_lo:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def gear_rows(states: np.ndarray) -> np.ndarray:
    """Rows ``[x, y, yaw, kappa, gear]`` of dense ``(N, 3)`` nose-yaw states.

    The gear of a step is whether its chord runs along the yaw (+1) or against it
    (-1); where it changes the sample is a cusp and its row repeats with the new
    gear. Curvature is computed within each gear segment, never across a cusp:
    κ = gear · d(yaw)/ds (the steering's curvature, as a reversing car turns its
    yaw by -κ per metre travelled), each sample taking its outgoing step's value
    and a segment's last sample its incoming one. Repeated positions are dropped
    first.

    Examples
    --------
    >>> t = np.linspace(0.0, 1.0, 11)
    >>> arc = np.column_stack([np.sin(t) * 5, 5 - np.cos(t) * 5, t])  # κ = 0.2, forward
    >>> back = arc[::-1][1:]  # and back along it in reverse: κ = 0.2 again
    >>> rows = gear_rows(np.vstack([arc, back]))
    >>> Path(rows, np.zeros((0, 2))).cusps.tolist(), bool(np.allclose(rows[:, 3], 0.2, atol=1e-3))
    ([11], True)
    """
    states = np.asarray(states, dtype=float).reshape(-1, 3)
    if len(states) > 1:
        keep = np.concatenate([[True], np.hypot(*np.diff(states[:, :2], axis=0).T) > 1e-9])
        states = states[keep]
    if len(states) < 2:
        return np.column_stack([states, np.zeros(len(states)), np.ones(len(states))])
    gears = _step_gears(states)
    bounds = [0, *(np.flatnonzero(gears[1:] != gears[:-1]) + 1).tolist(), len(gears)]
    rows = []
    for a, b in zip(bounds[:-1], bounds[1:], strict=True):
        run = states[a : b + 1]
        gear = float(gears[a])
        ds = np.hypot(*np.diff(run[:, :2], axis=0).T)
        k = gear * wrap_angle(np.diff(run[:, 2])) / ds
        kappa = np.append(k, k[-1])
        rows.append(np.column_stack([run, kappa, np.full(len(run), gear)]))
    return np.vstack(rows)


def _register() -> None:
    for space in SPACES:
        for algorithm in ALGORITHMS:
            name = f"ompl-{space}-{algorithm}"
            if name not in PLANNERS:
                factory = functools.partial(OmplPlanner, space, algorithm)
                factory.reverses = space == "rs"  # type: ignore[attr-defined]  # reverses()
                PLANNERS[name] = factory


_register()
