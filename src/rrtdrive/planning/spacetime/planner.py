"""The improved RRT-Connect run on a space-time checker, and its problem and result types."""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import cast

import numpy as np

from rrtdrive.collision import CollisionChecker
from rrtdrive.maps import Map
from rrtdrive.planning.base import PlanningProblem, cached_checker
from rrtdrive.planning.improved import ImprovedConfig, ImprovedRRTConnect
from rrtdrive.planning.spacetime.checker import SpaceTimeChecker
from rrtdrive.planning.spacetime.prediction import Prediction
from rrtdrive.planning.spacetime.safety import SafetyConfig
from rrtdrive.planning.spacetime.timing import ArrivalTiming
from rrtdrive.types import (
    Budget,
    InputError,
    Path,
    PlanResult,
    PlanStatus,
    Pose,
    VehicleParams,
)
from rrtdrive.values import is_finite_number

__all__ = ["SpaceTimeProblem", "SpaceTimePlan", "STATIC_ONLY", "SpaceTimeRRTConnect"]


@dataclass(frozen=True, eq=False)
class SpaceTimeProblem:
    """One space-time query: a static map with its start and goal, the traffic, the timing.

    Attributes
    ----------
    map : Map
        Road bounds and static obstacles, with the start and goal (rear-axle poses).
    prediction : Prediction
        Other vehicles in the map's frame.
    timing : ArrivalTiming
        When the car is where (origin at the start position).
    safety : SafetyConfig
        Buffers.
    speed : tuple of float
        ``(v_max, accel, decel, a_lat_max, v_launch)`` of the controller's profile.
    deadline : float, optional
        :func:`time.perf_counter` value at which the whole query (growth and
        post-processing) gives up (see :class:`SpaceTimeChecker`); ``None``: only
        the budget's limits apply.
    steering : tuple of float, optional
        ``(max_steer_rate, share)``: paths are timed as a car with this rate-limited
        steering actuator drives them (see :class:`SpaceTimeChecker`); ``None``:
        instant steering.
    """

    map: Map
    prediction: Prediction
    timing: ArrivalTiming
    safety: SafetyConfig = field(default_factory=SafetyConfig)
    speed: tuple[float, float, float, float, float] = (10.0, 1.0, 1.0, 1.5, 0.5)
    deadline: float | None = None
    steering: tuple[float, float] | None = None

    def __post_init__(self) -> None:
        # Checked here, named: None failed deep in the search, a NaN v_max as an
        # IndexError, a negative one was "solved" with nonsense times (an audit).
        for name, kind in (("map", Map), ("prediction", Prediction), ("timing", ArrivalTiming)):
            if not isinstance(getattr(self, name), kind):
                raise InputError(
                    f"{name}: expected a {kind.__name__}, got {type(getattr(self, name)).__name__}"
                )
        speed = tuple(self.speed) if isinstance(self.speed, (tuple, list)) else ()
        if len(speed) != 5 or not all(is_finite_number(v) for v in speed):
            raise InputError(
                "speed: expected (v_max, accel, decel, a_lat_max, v_launch), five finite "
                f"numbers, got {self.speed!r}"
            )
        if min(speed[:4]) <= 0.0 or speed[4] < 0.0:
            raise InputError(
                f"speed: v_max, accel, decel and a_lat_max must be > 0 and v_launch >= 0, "
                f"got {self.speed!r}"
            )

    @property
    def start(self) -> Pose:
        """Rear-axle start pose."""
        return self.map.start

    @property
    def goal(self) -> Pose:
        """Rear-axle goal pose."""
        return self.map.goal

    @property
    def vehicle(self) -> VehicleParams:
        """The car."""
        return self.map.vehicle


@dataclass(frozen=True, eq=False)
class SpaceTimePlan:
    """A space-time planning result.

    Attributes
    ----------
    result : PlanResult
        The improved planner's result on the space-time checker (its path is in
        the problem's frame).
    times : numpy.ndarray
        Arrival time at each path sample (seconds after the prediction), empty on failure.
    speeds : numpy.ndarray
        Profile speed at each path sample.
    tree_times : tuple of numpy.ndarray
        Nominal arrival time of every node of each tree (earliest of the band).
    dynamic_checks : int
        Calls of the traffic test.
    wall_time_s : float
        Wall time of the whole query.
    deadline_hit : bool
        The problem's deadline passed during the query (the result is then a failure).
    """

    result: PlanResult
    times: np.ndarray
    speeds: np.ndarray
    tree_times: tuple[np.ndarray, ...]
    dynamic_checks: int
    wall_time_s: float
    deadline_hit: bool = False

    @property
    def success(self) -> bool:
        """True when a verified space-time path was found."""
        return self.result.success


#: Components that rely on the static obstacles alone and are off in space-time:
#: the expanded checker is built from the static rectangles (it would lose the
#: traffic) and passage sampling looks for narrow static passages (a road has none).
#: The Dubins fallback and the Hybrid A* escalation are off too: they check poses
#: without the tree's arrival times, and on a road a lane change never needs to turn round.
STATIC_ONLY = ("obstacle_expansion", "passage_sampling", "dubins_fallback", "escalation")


class SpaceTimeRRTConnect(ImprovedRRTConnect):
    """The improved RRT-Connect on a :class:`SpaceTimeChecker`: moving vehicles by arrival time.

    Every edge the trees grow, the direct connection, the pruning and repair
    edges of the post-processor and the B-spline's exact check run against the
    predicted vehicles at the car's arrival times (:class:`SpaceTimeChecker`); the
    rest is :class:`~rrtdrive.planning.improved.ImprovedRRTConnect` unchanged.
    Tree nodes carry the nominal arrival time of :class:`ArrivalTiming`; the
    final path carries the exact times of its speed profile.

    Parameters
    ----------
    config : ImprovedConfig, optional
        As for the improved planner; ``obstacle_expansion``,
        ``passage_sampling`` and ``dubins_fallback`` default to off
        (:data:`STATIC_ONLY`).
    disable : iterable of str, optional
        Components to switch off.
    **options
        :class:`~rrtdrive.planning.improved.ImprovedConfig` fields.

    Examples
    --------
    >>> from rrtdrive.maps import Map
    >>> road = Map("road", (0.0, 42.0, 70.0, 50.0), (), Pose(2.0, 44.0, 0.0), Pose(58.0, 44.0, 0.0))
    >>> lead = Prediction.constant_velocity(np.array([[18.0, 44.0, 0.0, 2.0]]), [(4.3, 1.8)], 12.0)
    >>> timing = ArrivalTiming(0.0, 4.0, 10.0, 1.5, (2.0, 44.0))
    >>> plan = SpaceTimeRRTConnect().solve_spacetime(
    ...     SpaceTimeProblem(road, lead, timing, speed=(10.0, 1.5, 1.0, 1.5, 0.5)),
    ...     np.random.default_rng(0), Budget(max_iterations=3000))
    >>> plan.success, bool(plan.result.path.samples[:, 1].max() > 46.0)  # around the slow car
    (True, True)
    """

    name = "spacetime-rrt-connect"

    def __init__(
        self,
        config: ImprovedConfig | None = None,
        *,
        disable: Iterable[str] = (),
        **options: object,
    ) -> None:
        if config is None:
            defaults = {k: False for k in STATIC_ONLY if k not in options}
            config = dataclasses.replace(ImprovedConfig(), **defaults)  # type: ignore[arg-type]
        super().__init__(config, disable=disable, **options)

    def __repr__(self) -> str:
        return f"SpaceTimeRRTConnect({self.config!r})"

    def checker_for(self, problem: SpaceTimeProblem) -> SpaceTimeChecker:
        """The space-time checker of ``problem`` (static part cached per road).

        Parameters
        ----------
        problem : SpaceTimeProblem
            Road, traffic, timing, safety, speed profile, deadline and steering.

        Returns
        -------
        SpaceTimeChecker
        """
        static = cached_checker(problem.map)
        return SpaceTimeChecker(
            static, problem.prediction, problem.timing, problem.safety, problem.speed,
            deadline=problem.deadline, steering=problem.steering,
        )

    def solve_spacetime(
        self, problem: SpaceTimeProblem, rng: np.random.Generator, budget: Budget
    ) -> SpaceTimePlan:
        """Plan from the start to the goal clear of the road and of the predicted traffic.

        Parameters
        ----------
        problem : SpaceTimeProblem
            Road, query, traffic and timing.
        rng : numpy.random.Generator
            The only source of randomness.
        budget : Budget
            Iteration and wall-time limits of the tree growth.

        Returns
        -------
        SpaceTimePlan
            On success the path (in the problem's frame) with its arrival times;
            the times are checked once more against the traffic, so a path whose
            exact times conflict is returned as a failure.
        """
        if not isinstance(problem, SpaceTimeProblem):
            raise InputError(
                f"problem: expected a SpaceTimeProblem, got {type(problem).__name__}"
            )
        t0 = time.perf_counter()
        checker = self.checker_for(problem)
        # The space-time checker answers the same calls as the map's (duck-typed).
        as_checker = cast(CollisionChecker, checker)
        inner = PlanningProblem(
            problem.map, as_checker, problem.start, problem.goal, problem.vehicle
        )
        # The improved planner's result, named after this planner (the name it is registered by).
        res = ImprovedRRTConnect.solve(self, inner, rng, budget)
        res = dataclasses.replace(res, planner=self.name)
        tree_times = tuple(checker.timing.band(t.nodes)[0] for t in res.trees)
        times = speeds = np.zeros(0)
        if checker.expired:
            res = dataclasses.replace(
                res,
                status=PlanStatus.NO_PATH_IN_BUDGET,
                path=Path.empty(),
                message=f"deadline passed ({res.message})",
            )
        if res.success:
            times, speeds = checker.path_times(res.path.samples)
            hit = checker.conflicts(res.path.samples[:, :3], times, times, 0.25)
            if hit.any():
                i = int(np.flatnonzero(hit)[0])
                x, y = res.path.samples[i, :2]
                res = dataclasses.replace(
                    res,
                    status=PlanStatus.POSTPROCESS_FAILED,
                    path=Path.empty(),  # a failure has no path (its conflict was kept; an audit)
                    message=f"traffic conflict at ({x:.1f}, {y:.1f}) on the final check",
                )
                times = speeds = np.zeros(0)
        return SpaceTimePlan(
            res, times, speeds, tree_times, checker.dynamic_checks, time.perf_counter() - t0,
            checker.expired,
        )

    def solve(
        self, problem: PlanningProblem, rng: np.random.Generator, budget: Budget
    ) -> PlanResult:
        """The improved planner; a :class:`SpaceTimeProblem` goes to :meth:`solve_spacetime`.

        Parameters
        ----------
        problem : PlanningProblem
            A static problem, or a :class:`SpaceTimeProblem`.
        rng : numpy.random.Generator
            The only source of randomness.
        budget : Budget
            Iteration and wall-time limits.

        Returns
        -------
        PlanResult
            The space-time plan's ``result`` for a :class:`SpaceTimeProblem`.
        """
        if isinstance(problem, SpaceTimeProblem):
            return self.solve_spacetime(problem, rng, budget).result
        return ImprovedRRTConnect.solve(self, problem, rng, budget)
