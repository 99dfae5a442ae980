"""The planner seam: problem, protocol, growing trees, budgets, and shared helpers."""

from __future__ import annotations

import contextlib
import math
import time
import warnings
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np

from rrtdrive.collision import CheckerConfig, CollisionChecker
from rrtdrive.geometry import densify
from rrtdrive.map_checks import warn_if_degrees
from rrtdrive.maps import MAX_YAW, Map, check_endpoint
from rrtdrive.planning.checker_cache import cached_checker
from rrtdrive.types import (
    Budget,
    InputError,
    InputWarning,
    Path,
    PlanResult,
    PlanStatus,
    Pose,
    Tree,
    VehicleParams,
)
from rrtdrive.vehicle import axle_disc_radius

__all__ = [
    "PlanningProblem",
    "Planner",
    "GrowingTree",
    "Stopwatch",
    "precheck",
    "failure",
    "polyline_path",
    "polyline_curvature",
    "cached_checker",
]


@dataclass(frozen=True, eq=False)
class PlanningProblem:
    """One query: a map, the car, its checker, a start and a goal.

    Build it with :meth:`from_map`; checkers are cached per map so that repeated
    queries on one map pay the distance-field construction once.

    Parameters
    ----------
    map : Map
        Obstacles and bounds.
    checker : CollisionChecker
        The map's collision checker.
    start, goal : Pose
        The query.
    vehicle : VehicleParams, optional
        The car (default: the map's; it was the paper's car, refused with a map of
        another car's checker).
    reverse : bool
        Whether the path may change gear (drive in reverse, ``rrtdrive plan
        --reverse``). A planner that cannot reverse ignores it and returns a
        forward-only path; without it every planner's path is forward-only.
    """

    map: Map
    checker: CollisionChecker
    start: Pose
    goal: Pose
    vehicle: VehicleParams = None  # type: ignore[assignment]  # the map's, set below
    reverse: bool = False

    def __post_init__(self) -> None:
        if self.vehicle is None and isinstance(self.map, Map):
            object.__setattr__(self, "vehicle", self.map.vehicle)
        for name, kind in (
            ("map", Map), ("start", Pose), ("goal", Pose), ("vehicle", VehicleParams),
        ):  # fmt: skip
            value = getattr(self, name)
            if not isinstance(value, kind):
                raise InputError(
                    f"problem.{name}: expected a {kind.__name__}, got {type(value).__name__}"
                )
        # Any checker with the collision checker's tests (the space-time one in traffic).
        if not hasattr(self.checker, "poses_free"):
            raise InputError(
                f"problem.checker: expected a CollisionChecker, got {type(self.checker).__name__}"
            )
        # A checker of another map would plan around obstacles that are not there.
        bounds = getattr(self.checker, "bounds", None)
        obstacles = getattr(self.checker, "obstacles", None)
        if (bounds is not None and tuple(bounds) != tuple(self.map.bounds)) or (
            obstacles is not None and tuple(obstacles) != tuple(self.map.obstacles)
        ):
            raise InputError(
                "problem.checker: it was built for another map (its bounds or obstacles "
                f"differ from map {self.map.name!r}'s); use PlanningProblem.from_map(m)"
            )
        # A checker for another car would clear a wider car through gaps it cannot pass.
        car = getattr(self.checker, "vehicle", None)
        if isinstance(car, VehicleParams) and car != self.vehicle:
            raise InputError(
                "problem.vehicle: the checker was built for another car; give the map "
                "that car (dataclasses.replace(m, vehicle=...)) and use "
                "PlanningProblem.from_map(m)"
            )
        for label, pose, mapped in (
            ("start", self.start, self.map.start),
            ("goal", self.goal, self.map.goal),
        ):
            if pose != mapped:  # the map warned about its own poses already
                warn_if_degrees(f"problem.{label}", pose.yaw)
        if not isinstance(self.reverse, (bool, np.bool_)):
            raise InputError(f"reverse: expected True or False, got {self.reverse!r}")
        object.__setattr__(self, "reverse", bool(self.reverse))

    def __repr__(self) -> str:
        # The map's obstacles and the checker's grid are too long to print.
        return (
            f"PlanningProblem(map={self.map.name!r}, start={self.start}, goal={self.goal}, "
            f"reverse={self.reverse})"
        )

    @classmethod
    def from_map(
        cls,
        m: Map,
        checker: CollisionChecker | None = None,
        config: CheckerConfig | None = None,
        reverse: bool = False,
    ) -> PlanningProblem:
        """The problem of map ``m`` with its own start and goal (gear changes if ``reverse``)."""
        if not isinstance(m, Map):
            raise InputError(f"map: expected a Map (rrtdrive.maps), got {type(m).__name__}")
        if config is not None and not isinstance(config, CheckerConfig):
            raise InputError(f"config: expected a CheckerConfig, got {type(config).__name__}")
        if checker is None:
            checker = cached_checker(m, config)
        return cls(m, checker, m.start, m.goal, m.vehicle, reverse=reverse)

    @property
    def bounds(self) -> tuple[float, float, float, float]:
        """The map's ``(xmin, ymin, xmax, ymax)``."""
        return self.map.bounds


@runtime_checkable
class Planner(Protocol):
    """What every planner offers."""

    @property
    def name(self) -> str:
        """The registered name (a read-only attribute will do)."""
        ...

    def solve(
        self, problem: PlanningProblem, rng: np.random.Generator, budget: Budget
    ) -> PlanResult:
        """Plan from ``problem.start`` to ``problem.goal`` within ``budget``; never return None.

        Parameters
        ----------
        problem : PlanningProblem
            The map's checker, the start and goal poses, the car and whether it may reverse.
        rng : numpy.random.Generator
            The only source of randomness (a seed decides the result).
        budget : Budget
            Iterations or expansions decide; the wall-clock limit is a safety cap.

        Returns
        -------
        PlanResult
            Its status says how it ended; a path only when solved.
        """
        ...


class Stopwatch:
    """The query's wall clock: elapsed time, and the safety cap ``budget.max_time_s``.

    The cap is a safety net, not a budget that decides (see :class:`Budget`): the
    first :meth:`expired` call that finds it passed latches :attr:`capped`, and
    a capped query ends in :func:`rrtdrive.planning.result.timeout_result`
    whatever it found. Only places that stop work on :meth:`expired` can cap a
    query; a query that runs past the cap without asking finishes as its counts say.

    Parameters
    ----------
    budget : Budget
        The query's limits (only ``max_time_s`` is read).
    clock : callable, optional
        Seconds as a float, monotonic (default :func:`time.perf_counter`); tests
        may pass a fake one.

    Examples
    --------
    >>> ticks = iter([0.0, 1.0, 3.0])
    >>> watch = Stopwatch(Budget(max_time_s=2.0), clock=lambda: next(ticks))
    >>> watch.expired(), watch.capped, watch.expired(), watch.capped
    (False, False, True, True)
    """

    def __init__(self, budget: Budget, clock: Callable[[], float] | None = None) -> None:
        self.budget = budget
        self._clock = time.perf_counter if clock is None else clock
        self.t0 = self._clock()
        self._deadline = self.t0 + budget.max_time_s
        self.capped = False
        #: Seconds spent in :meth:`setup` blocks (per-map set-up built on first use).
        self.setup_s = 0.0

    def elapsed(self) -> float:
        """Seconds since start, less the time spent in :meth:`setup` blocks."""
        return self._clock() - self.t0

    @contextlib.contextmanager
    def setup(self) -> Iterator[None]:
        """A block of per-map set-up met during the search (built once, then cached).

        Its time is not planning time: :meth:`elapsed` and the safety cap leave it
        out, and :attr:`setup_s` collects it (the result reports it in
        ``setup_time_s``).

        Examples
        --------
        >>> ticks = iter([0.0, 1.0, 4.0, 5.0])
        >>> watch = Stopwatch(Budget(max_time_s=2.0), clock=lambda: next(ticks))
        >>> with watch.setup():
        ...     pass
        >>> watch.setup_s, watch.elapsed()
        (3.0, 2.0)
        """
        t = self._clock()
        try:
            yield
        finally:
            spent = self._clock() - t
            self.t0 += spent
            self._deadline += spent
            self.setup_s += spent

    def expired(self) -> bool:
        """True once the safety cap is reached (and from then on :attr:`capped` is True)."""
        if not self.capped and self._clock() >= self._deadline:
            self.capped = True
        return self.capped


class GrowingTree:
    """A tree in preallocated numpy arrays with vectorised nearest and near-set queries.

    Parameters
    ----------
    root : array_like
        Root position ``(x, y)``.
    capacity : int
        Initial capacity; the arrays double when full.
    virtual_parent : array_like, optional
        A position that acts as the root's parent for angle tests (never a node).
    """

    def __init__(
        self, root: np.ndarray, capacity: int = 1024, virtual_parent: np.ndarray | None = None
    ) -> None:
        self.nodes = np.empty((capacity, 2))
        self.parents = np.empty(capacity, dtype=np.int64)
        self.cost = np.empty(capacity)
        self.nodes[0] = root
        self.parents[0] = -1
        self.cost[0] = 0.0
        self.size = 1
        self.virtual_parent = None if virtual_parent is None else np.asarray(virtual_parent, float)

    def __len__(self) -> int:
        return self.size

    def add(self, point: np.ndarray, parent: int, cost: float | None = None) -> int:
        """Append ``point`` with ``parent``; return its index.

        Parameters
        ----------
        point : numpy.ndarray
            The node's position ``(x, y)``.
        parent : int
            The parent's index.
        cost : float, optional
            Path length from the root (RRT*'s cost); by default the parent's
            plus the straight distance to it.

        Returns
        -------
        int
        """
        if self.size == len(self.nodes):
            self.nodes = np.concatenate([self.nodes, np.empty_like(self.nodes)])
            self.parents = np.concatenate([self.parents, np.empty_like(self.parents)])
            self.cost = np.concatenate([self.cost, np.empty_like(self.cost)])
        i = self.size
        self.nodes[i] = point
        self.parents[i] = parent
        if cost is None:
            p = self.nodes[parent]
            cost = self.cost[parent] + math.hypot(point[0] - p[0], point[1] - p[1])
        self.cost[i] = cost
        self.size += 1
        return i

    def sq_dists(self, point: np.ndarray) -> np.ndarray:
        """Squared distances from every node to ``point``.

        Parameters
        ----------
        point : numpy.ndarray
            ``(x, y)``.

        Returns
        -------
        numpy.ndarray
            ``(size,)`` in square metres, in node order.
        """
        d = self.nodes[: self.size] - point
        return np.einsum("ij,ij->i", d, d)

    def nearest(self, point: np.ndarray) -> int:
        """Index of the node nearest to ``point`` (the first of equals).

        Parameters
        ----------
        point : numpy.ndarray
            ``(x, y)``.

        Returns
        -------
        int
        """
        return int(np.argmin(self.sq_dists(point)))

    def near(self, point: np.ndarray, radius: float) -> np.ndarray:
        """Indices of the nodes within ``radius`` of ``point``.

        Parameters
        ----------
        point : numpy.ndarray
            ``(x, y)``.
        radius : float
            Metres; a node exactly at ``radius`` counts.

        Returns
        -------
        numpy.ndarray
            Ascending node indices.
        """
        return np.flatnonzero(self.sq_dists(point) <= radius * radius)

    def branch(self, i: int) -> np.ndarray:
        """Positions from node ``i`` back to the root, ``(K, 2)``.

        Parameters
        ----------
        i : int
            The node to start from.

        Returns
        -------
        numpy.ndarray
            ``(K, 2)``: node ``i`` first, the root last.
        """
        out = []
        while i >= 0:
            out.append(self.nodes[i])
            i = int(self.parents[i])
        return np.array(out)

    def freeze(self) -> Tree:
        """An immutable copy for the result."""
        return Tree(self.nodes[: self.size].copy(), self.parents[: self.size].copy())


def step_towards(a: np.ndarray, b: np.ndarray, step: float) -> tuple[np.ndarray, bool]:
    """The point ``step`` from ``a`` towards ``b`` (``b`` when nearer); and whether it is ``b``."""
    d = b - a
    dist = math.hypot(d[0], d[1])
    if dist <= step:
        return b.copy(), True
    return a + d * (step / dist), False


def _endpoint_fault(problem: PlanningProblem, pose: Pose, label: str) -> str:
    """Why ``pose`` cannot be planned from or to, in the words of a map's own check."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", InputWarning)
            check_endpoint(problem.map, pose, label, problem.vehicle)
    except InputError as exc:
        return str(exc)
    return f"{label}: the car's body collides there"  # within the grid's error margin


#: The share of a planner's kept clearance its width proof assumes: its paths are checked
#: exactly at poses a few centimetres apart, and between two the body may pass a corner
#: a few millimetres closer.
PROOF_KEEP_SHARE = 0.8


def precheck(
    problem: PlanningProblem, planner: str, watch: Stopwatch, keeps: float = 0.0
) -> PlanResult | None:
    """Fail early on an invalid start or goal or a provably unreachable goal; else ``None``.

    ``keeps``: the least body clearance the planner's paths keep (the ends' own, when
    theirs is less, is kept instead and nothing more is proven).
    """
    checker = problem.checker
    for label, pose, status in (("start", problem.start, PlanStatus.INVALID_START),
                                ("goal", problem.goal, PlanStatus.INVALID_GOAL)):  # fmt: skip
        if abs(pose.yaw) > MAX_YAW or not checker.pose_free(pose.as_tuple()):
            return failure(planner, status, watch, _endpoint_fault(problem, pose, label))
    if checker.provably_disconnected(problem.start.xy, problem.goal.xy):
        return failure(
            planner,
            PlanStatus.PROVEN_UNREACHABLE,
            watch,
            "goal unreachable: no collision-free motion connects the start and the goal: "
            "they lie in different parts of the map's free space (walled off from each "
            "other, or joined only where the car cannot pass)",
        )
    if _too_narrow(problem, watch, 0.0):
        v = problem.vehicle
        return failure(
            planner,
            PlanStatus.PROVEN_UNREACHABLE,
            watch,
            f"goal unreachable: every way from the start to the goal is too narrow for the "
            f"car ({v.width:g} m wide): the {axle_disc_radius(v):g} m disc about "
            "its rear axle cannot pass (no collision-free motion connects them)",
        )
    return _too_narrow_for_the_keep(problem, planner, watch, keeps)


def _too_narrow(problem: PlanningProblem, watch: Stopwatch, keep: float) -> bool:
    """The checker's exact width proof for a car keeping ``keep``, timed as set-up.

    Its region, built on a map's first query and only when the proof is asked for, is
    per-map set-up, outside the budget (3000 tiny obstacles spent a 0.2 s cap building
    it inside the stopwatch; an audit).
    """
    with watch.setup():
        return problem.checker.too_narrow_between(problem.start.xy, problem.goal.xy, keep)


def _too_narrow_for_the_keep(
    problem: PlanningProblem, planner: str, watch: Stopwatch, keeps: float
) -> PlanResult | None:
    """``PROVEN_UNREACHABLE`` when every way is too narrow for the car and what it keeps.

    A 1.85 m gap, which the 1.8 m car fits but not with the 0.05 m the default keeps at
    least, ran its whole budget and asked for a larger one (an audit).
    """
    checker = problem.checker
    proof = PROOF_KEEP_SHARE * keeps
    if keeps <= 0.0 or not _too_narrow(problem, watch, proof):
        return None
    # Only then the ends' exact clearance (two shapely distances to every obstacle): where
    # it is less, the planner keeps that instead, and nothing more is proven.
    ends = (problem.start.as_tuple(), problem.goal.as_tuple())
    if min(checker.body_clearance(e) for e in ends) * 0.999 < keeps:
        return None
    v = problem.vehicle
    return failure(
        planner,
        PlanStatus.PROVEN_UNREACHABLE,
        watch,
        f"goal unreachable for this planner: every way from the start to the goal is "
        f"narrower than the car ({v.width:g} m wide) with {proof:g} m each side, and its "
        f"paths keep {keeps:g} m of body clearance: the {axle_disc_radius(v) + proof:g} m "
        "disc about the rear axle cannot pass (a path keeping less clearance may exist)",
    )


def failure(
    planner: str,
    status: PlanStatus,
    watch: Stopwatch,
    message: str,
    trees: tuple[Tree, ...] = (),
    iterations: int = 0,
    raw_path: np.ndarray | None = None,
    stats: dict[str, float] | None = None,
) -> PlanResult:
    """A failed :class:`PlanResult` with an empty path."""
    return PlanResult(
        status=status,
        planner=planner,
        path=Path.empty(),
        raw_path=np.zeros((0, 2)) if raw_path is None else raw_path,
        trees=trees,
        nodes=sum(len(t) for t in trees),
        iterations=iterations,
        planning_time_s=watch.elapsed(),
        message=message,
        stats=stats or {},
    )


def polyline_curvature(points: np.ndarray) -> np.ndarray:
    """Menger curvature (1 / radius of the circle through three points) at each vertex.

    The end vertices get 0. Signed: positive for a left (counter-clockwise) turn.

    Examples
    --------
    >>> pts = np.array([[1.0, 0.0], [0.0, 1.0], [-1.0, 0.0]])
    >>> polyline_curvature(pts).round(6)
    array([0., 1., 0.])
    """
    p = np.asarray(points, dtype=float)
    k = np.zeros(len(p))
    if len(p) < 3:
        return k
    a, b, c = p[:-2], p[1:-1], p[2:]
    ab, bc, ca = b - a, c - b, a - c
    cross = ab[:, 0] * bc[:, 1] - ab[:, 1] * bc[:, 0]
    denom = np.linalg.norm(ab, axis=1) * np.linalg.norm(bc, axis=1) * np.linalg.norm(ca, axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        k[1:-1] = np.where(denom > 1e-12, 2.0 * cross / denom, 0.0)
    return k


def polyline_path(points: np.ndarray, spacing: float = 0.25) -> Path:
    """A :class:`Path` along a raw polyline: headings along segments, Menger curvature at vertices.

    Used for the baselines' raw tree paths: they have corners, and the curvature
    column reports them (the circle through each corner and its neighbours).

    Parameters
    ----------
    points : numpy.ndarray
        ``(N, 2)`` vertices.
    spacing : float
        Largest distance between samples along each segment (m).

    Returns
    -------
    Path
        Forward gear throughout.
    """
    p = np.asarray(points, dtype=float)
    if len(p) < 2:
        return Path(np.column_stack([p, np.zeros((len(p), 2))]), p)
    # A hair over the exact ratio so that rounding (e.g. in JSON) never pushes a gap past spacing.
    dense = densify(p, spacing, rel_slack=1e-5)
    xy, vertex_index = dense.points, dense.vertex_index
    seg_yaw = np.arctan2(*np.diff(p, axis=0).T[::-1])
    owner = np.searchsorted(vertex_index, np.arange(len(xy)), side="right") - 1
    yaw = seg_yaw[np.minimum(owner, len(seg_yaw) - 1)]
    kappa = np.zeros(len(xy))
    kappa[vertex_index] = polyline_curvature(p)
    return Path(np.column_stack([xy, yaw, kappa]), p)


PlannerFactory = Callable[..., Planner]
PLANNERS: dict[str, PlannerFactory] = {}


def register_planner(name: str) -> Callable[[PlannerFactory], PlannerFactory]:
    """Class decorator adding a planner factory to :data:`PLANNERS`."""

    def deco(factory: PlannerFactory) -> PlannerFactory:
        PLANNERS[name] = factory
        return factory

    return deco
