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
curvature at the corners), Reeds–Shepp curves with their own headings and the
curvature d(yaw)/ds within each gear segment (a cusp is not a curvature). A
Reeds–Shepp path may reverse; rrtdrive's guarantees are for forward paths, so the
bench's ``verified`` column will say so.

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
from rrtdrive.types import Budget, InputError, Path, PlanResult, PlanStatus

__all__ = ["OmplPlanner", "OMPL_PLANNERS", "SPACES", "ALGORITHMS", "simple_setup"]

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
            st.setYaw(pose.yaw)
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

    def __post_init__(self) -> None:
        if self.space not in SPACES:
            raise InputError(f"space: expected one of {SPACES}, got {self.space!r}")
        if self.algorithm not in ALGORITHMS:
            raise InputError(
                f"algorithm: expected one of {sorted(ALGORITHMS)}, got {self.algorithm!r}"
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
            length = float(solution.length())
            solution.interpolate(max(2, int(math.ceil(length / (0.4 * _SPACING))) + 1))
            path = _curve_path(_states(solution, r2), vertices[:, :2])
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


def _curve_path(states: np.ndarray, waypoints: np.ndarray) -> Path:
    """A :class:`Path` from densely interpolated Reeds–Shepp states; κ = d(yaw)/ds per gear.

    At a cusp the car stops and reverses: the step across it is short in the plane
    but turns the yaw of both sides, so d(yaw)/ds there is no curvature of the
    path. κ is computed within each gear segment (forward or reverse run); the two
    steps at each gear change take the value of their segment's nearest inner step.
    """
    xy = states[:, :2]
    keep = np.concatenate([[True], np.hypot(*np.diff(xy, axis=0).T) > 1e-9])
    states = states[keep]
    kappa = _gear_curvature(states)
    samples = np.column_stack([states[:, :3], kappa])
    return Path(samples, waypoints)


def _gear_curvature(states: np.ndarray) -> np.ndarray:
    """Per-sample κ of ``(N, 3)`` ``x, y, yaw`` states, ignoring the steps at cusps.

    Examples
    --------
    >>> t = np.linspace(0.0, 1.0, 11)
    >>> arc = np.column_stack([np.sin(t) * 5, 5 - np.cos(t) * 5, t])  # κ = 0.2, forward
    >>> bool(np.allclose(_gear_curvature(arc), 0.2, atol=1e-3))
    True
    """
    n = len(states)
    kappa = np.zeros(n)
    if n < 2:
        return kappa
    d = np.diff(states[:, :2], axis=0)
    ds = np.hypot(*d.T)
    dyaw = wrap_angle(np.diff(states[:, 2]))
    mid_yaw = states[:-1, 2] + 0.5 * dyaw
    gear = np.where(d[:, 0] * np.cos(mid_yaw) + d[:, 1] * np.sin(mid_yaw) >= 0.0, 1, -1)
    seg = np.where(ds > 1e-9, dyaw / np.maximum(ds, 1e-12), 0.0)
    change = np.flatnonzero(gear[1:] != gear[:-1])  # a cusp lies in step i or i + 1
    if len(change):
        bad = np.zeros(len(seg), dtype=bool)
        bad[change] = bad[change + 1] = True
        good, idx = np.flatnonzero(~bad), np.flatnonzero(bad)
        if len(good):
            # Each dropped step takes its nearest kept step's value: the last forward
            # step looks back, the first reverse step ahead (its own gear run).
            pos = np.searchsorted(good, idx)
            left = good[np.clip(pos - 1, 0, len(good) - 1)]
            right = good[np.clip(pos, 0, len(good) - 1)]
            seg[idx] = seg[np.where(np.abs(idx - left) <= np.abs(right - idx), left, right)]
        else:
            seg[:] = 0.0
    kappa[:-1] = seg
    kappa[-1] = seg[-1]
    return kappa


def _register() -> None:
    for space in SPACES:
        for algorithm in ALGORITHMS:
            name = f"ompl-{space}-{algorithm}"
            if name not in PLANNERS:
                PLANNERS[name] = functools.partial(OmplPlanner, space, algorithm)


_register()
