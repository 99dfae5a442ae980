"""What every task is: the base class, its kind, its views, and planning its query.

A task is one episode's job as plain data (a frozen dataclass: the map with this
episode's start and goal, the seed, the speed cap and time limit, and the fields
of its kind) plus the methods where the kinds differ: the highway-env road it
builds, how its scene and video are framed, the driver it needs, and when it is
done. One subclass per kind (:mod:`rrtdrive.sim.tasks`); nothing outside the
classes asks which kind a task is.
"""

from __future__ import annotations

import enum
from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from rrtdrive.collision import CheckerConfig
from rrtdrive.controllers import SpeedConfig, TrackingController
from rrtdrive.maps import LANE_WIDTH, Map
from rrtdrive.planning import make_planner, solve_on_map
from rrtdrive.sim.episode import (
    EpisodeStatus,
    end_message,
)
from rrtdrive.sim.loop import (
    Driver,
    EndRule,
    require_episode_time,
)
from rrtdrive.sim.scenes import SceneView, fit_view, scenario_rngs
from rrtdrive.types import (
    Budget,
    InputError,
    Path,
    PlanResult,
    Pose,
    VehicleParams,
    require_positive,
)

if TYPE_CHECKING:  # pragma: no cover
    from highway_env.road.road import Road

    from rrtdrive.sim.ego import EgoVehicle
    from rrtdrive.sim.episode import Episode
    from rrtdrive.sim.replanning import ReplanConfig, TrafficLog
    from rrtdrive.sim.runner import EpisodeConfig

__all__ = [
    "TaskKind",
    "Task",
    "VideoCamera",
    "Reference",
    "SuccessPart",
    "DEFAULT_PLANNER",
    "plan_scenario",
]

#: The planner of a task when none is named.
DEFAULT_PLANNER = "improved-rrt-connect"


class TaskKind(enum.StrEnum):
    """The kinds of task (the value is the scenario name in JSON and on the command line)."""

    PARKING = "parking"
    OVERTAKE = "overtake"
    OVERTAKE_TRAFFIC = "overtake-traffic"
    PARALLEL_PARKING = "parallel-parking"
    U_TURN = "u-turn"
    CUSTOM = "custom"


@dataclass(frozen=True)
class VideoCamera:
    """How the video frames a task (:func:`rrtdrive.sim.video.render_frames`).

    Attributes
    ----------
    size : tuple of int
        Frame ``(width, height)`` in pixels.
    scaling : float
        Pixels per metre.
    centre : tuple of float
        The point the camera looks at (at the start, when it follows the ego).
    follow : bool
        The camera moves with the ego (a long road).
    """

    size: tuple[int, int]
    scaling: float
    centre: tuple[float, float]
    follow: bool = False


@dataclass(frozen=True, eq=False)
class Reference:
    """What a task drives along, before the drive: the plan, or why there is nothing to drive.

    Attributes
    ----------
    plan : PlanResult or None
        The planner's result (``None`` for a given path, or when the task re-plans
        while driving).
    planner : str
        The planner's name (``"given"`` for a given path).
    path : Path or None
        The path to track (``None`` when the task plans while driving).
    failure : str or None
        Why the episode cannot start (the message of a ``plan_failed`` episode).
    """

    plan: PlanResult | None
    planner: str
    path: Path | None
    failure: str | None = None

    @property
    def plans_while_driving(self) -> bool:
        """No path ahead of the drive: the driver plans its reference while driving."""
        return self.path is None and self.failure is None


@dataclass(frozen=True)
class SuccessPart:
    """The kind-specific part of an episode's success decision.

    :func:`rrtdrive.evaluation.success.success_terms` computes the common terms
    (goal pose, stopped, in time, collision) and asks the task
    (:meth:`Task.success_part`) for these.

    Attributes
    ----------
    passed_lead, back_in_lane : bool or None
        The body is past the lead car and back in the ego lane (road kinds only).
    lead_required : bool
        ``passed_lead`` and ``back_in_lane`` are part of success.
    reached_goal : bool or None
        The task's own "goal reached" (``None``: the goal pose within tolerance).
    ends_moving : bool
        The task ends on the move: standing still is not required.
    goal_errors : bool
        The final errors to the goal pose are reported.
    timeout_is_following : bool
        A timeout without a collision is safe following (the ego stayed behind the lead).
    """

    passed_lead: bool | None = None
    back_in_lane: bool | None = None
    lead_required: bool = False
    reached_goal: bool | None = None
    ends_moving: bool = False
    goal_errors: bool = True
    timeout_is_following: bool = False


def plan_scenario(
    scenario: Task, planner: str, seed: int, budget: Budget | None = None,
    options: Mapping[str, Any] | None = None,
) -> PlanResult:
    """Plan the task's query with the registered planner ``planner``.

    The planner's generator is the episode seed's planner stream; gear changes are
    allowed when the task says so (``scenario.reverse``).

    Parameters
    ----------
    scenario : Task
    planner : str
    seed : int
    budget : Budget, optional
        ``None``: the default :class:`Budget`.
    options : mapping of str to Any, optional
        The planner's keyword arguments (its config's fields).

    Returns
    -------
    PlanResult
    """  # fmt: skip
    _, plan_rng, _ = scenario_rngs(seed)
    _, result = solve_on_map(
        lambda: make_planner(planner, **dict(options or {})), scenario.map, plan_rng,
        budget or Budget(), config=scenario.checker_config, reverse=scenario.reverse,
    )  # fmt: skip
    return result


@dataclass(frozen=True, kw_only=True)
class Task:
    """One episode's task, as plain data; subclassed once per kind.

    Parameters
    ----------
    map : Map
        The map with this episode's start and goal (rear-axle poses).
    seed : int
        The seed the start jitter and the goal were drawn from.
    v_max : float
        Speed cap for the episode in m/s.
    max_time_s : float
        Time allowed before the episode counts as failed.
    reverse : bool
        The path may change gear (plan with reversing allowed, as ``rrtdrive plan
        --reverse``).

    Notes
    -----
    The class attributes ``lane_y``, ``lane_width``, ``lead_index``, ``oncoming``,
    ``lead`` and ``ego_speed`` are the defaults of fields that only some kinds have
    (a kind that has one declares it as a field); they are here for readers that
    do not ask the task yet (the collision judge, the scene builder).
    """

    kind: ClassVar[TaskKind]
    lane_y: ClassVar[float | None] = None
    lane_width: ClassVar[float] = LANE_WIDTH
    lead_index: ClassVar[int | None] = None
    oncoming: ClassVar[tuple[tuple[float, float], ...]] = ()
    lead: ClassVar[tuple[float, float] | None] = None
    ego_speed: ClassVar[float] = 0.0
    #: The re-planning settings' type of a kind that re-plans while driving (``None``:
    #: the path is planned once, before the drive).
    REPLAN_CONFIG: ClassVar[type[ReplanConfig] | None] = None
    #: The keyword options of :func:`~rrtdrive.sim.tasks.make_scenario` this kind takes.
    OPTIONS: ClassVar[tuple[str, ...]] = ()
    #: The planner names this kind drives with (``None``: any registered planner).
    PLANNERS: ClassVar[tuple[str, ...] | None] = None

    map: Map
    seed: int
    v_max: float = 3.0
    max_time_s: float = 120.0
    reverse: bool = False

    def __post_init__(self) -> None:
        if not isinstance(self.map, Map):
            raise InputError(f"scenario.map: expected a Map, got {type(self.map).__name__}")
        if isinstance(self.seed, bool) or not isinstance(self.seed, (int, np.integer)):
            raise InputError(f"scenario.seed: need an integer >= 0, got {self.seed!r}")
        if self.seed < 0:
            raise InputError(f"scenario.seed: need an integer >= 0, got {self.seed!r}")
        require_positive("scenario.v_max", self.v_max)
        require_episode_time("scenario.max_time_s", self.max_time_s)
        self.check_time_limit(self.max_time_s, "scenario.max_time_s")
        if not isinstance(self.reverse, (bool, np.bool_)):
            raise InputError(f"scenario.reverse: expected True or False, got {self.reverse!r}")

    # ------------------------------------------------------------------ data

    @property
    def checker_config(self) -> CheckerConfig | None:
        """The collision checker's settings for planning and judging (``None``: the defaults)."""
        return None

    @property
    def name(self) -> str:
        """The kind's name (``"parking"``, ``"overtake"``, ``"overtake-traffic"``, ``"custom"``)."""
        return self.kind.value

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

    def describe(self) -> dict[str, Any]:
        """Kind-specific settings worth reporting next to the metrics (JSON-ready)."""
        return {}

    def check_time_limit(self, max_time_s: float, name: str) -> None:
        """Raise :class:`InputError` naming ``name`` when the task cannot last ``max_time_s``.

        Any limit up to :data:`~rrtdrive.sim.loop.MAX_EPISODE_S` by default; a task
        whose scene runs out sooner (``overtake-traffic``'s road) says so.

        Parameters
        ----------
        max_time_s : float
            The time limit, seconds.
        name : str
            The field that gave it (the message's first word).
        """

    # ------------------------------------------------------------------ scene

    def build_road(self, np_random: np.random.Generator, history: bool) -> Road:
        """The highway-env road of this task (lanes, obstacles, other vehicles).

        Parameters
        ----------
        np_random : numpy.random.Generator
        history : bool
            Record vehicle histories (highway-env's ``show_trajectories``).

        Returns
        -------
        Road
        """
        raise NotImplementedError

    def scene_view(self) -> SceneView:
        """Default frame of the live scene: a window sized by :func:`fit_view` for the map."""
        size, scaling, _ = fit_view(self.map.bounds)
        return SceneView(size, scaling, (0.5, 0.5))

    def camera(self) -> VideoCamera:
        """How the video frames this task: the whole map, fitted to the frame (:func:`fit_view`)."""
        return VideoCamera(*fit_view(self.map.bounds))

    # ------------------------------------------------------------------ episode

    @property
    def success_status(self) -> EpisodeStatus:
        """The status of an episode that ends by :meth:`reached`."""
        raise NotImplementedError

    def reached(self, ego: EgoVehicle, driver: Any) -> bool:
        """True when the task is done (the episode loop asks after every step).

        Parameters
        ----------
        ego : EgoVehicle
        driver : Driver
            The episode's driver (:meth:`make_driver`).

        Returns
        -------
        bool
        """
        raise NotImplementedError

    def end_message(self, status: EpisodeStatus, t_end: float, max_time_s: float) -> str:
        """The message of an episode of this task that ended with ``status`` at ``t_end``.

        Parameters
        ----------
        status : EpisodeStatus
        t_end, max_time_s : float
            Simulation time of the last step and the time limit, seconds.

        Returns
        -------
        str
        """
        return end_message(status, t_end, max_time_s, self.success_status)

    def agent_end_rule(self, tol_m: float, tol_rad: float, stop_speed: float) -> EndRule:
        """When an episode is done that an agent drives without a tracking controller.

        The task itself (its rule does not depend on a controller); a path task
        overrides this. The arguments are the evaluators' goal tolerances.

        Parameters
        ----------
        tol_m, tol_rad, stop_speed : float
            Goal distance (m), heading error (rad), standing-still speed (m/s).

        Returns
        -------
        EndRule
        """
        return self

    def success_part(self, episode: Episode) -> SuccessPart:
        """The kind-specific success terms of a driven ``episode`` of this task (none here).

        Parameters
        ----------
        episode : Episode

        Returns
        -------
        SuccessPart
        """
        return SuccessPart()

    def default_speed(self) -> SpeedConfig:
        """The speed profile settings of this task when none are given: its cap."""
        return SpeedConfig(v_max=self.v_max)

    def resolve(self, config: EpisodeConfig) -> tuple[SpeedConfig, EpisodeConfig]:
        """The speed profile settings of the drive and the configuration the episode records.

        Parameters
        ----------
        config : EpisodeConfig
            The episode's settings as given (``speed`` ``None``: the task's default).

        Returns
        -------
        tuple of (SpeedConfig, EpisodeConfig)
        """
        raise NotImplementedError

    def reference(
        self, planner: object, seed: int, budget: Budget, options: Mapping[str, Any] | None = None
    ) -> Reference:
        """What to drive along: plan with ``planner`` (a name), or take a given plan or path.

        Parameters
        ----------
        planner : str, PlanResult or Path
        seed : int
            The episode seed (its planner stream seeds the planner).
        budget : Budget
        options : mapping of str to Any, optional
            The named planner's keyword arguments (its config's fields).

        Returns
        -------
        Reference
        """
        raise NotImplementedError

    def make_driver(
        self,
        env: Any,
        controller: TrackingController,
        reference: Reference,
        speed: SpeedConfig,
        config: EpisodeConfig,
        seed: int,
    ) -> Driver:
        """The driver of this task in the built scene ``env``.

        Parameters
        ----------
        env : SceneEnv
        controller : TrackingController
        reference : Reference
            From :meth:`reference`.
        speed, config : SpeedConfig, EpisodeConfig
            From :meth:`resolve`.
        seed : int

        Returns
        -------
        Driver
        """
        raise NotImplementedError

    def outcome(self, driver: Any, reference: Reference, completion_time: float | None
                ) -> tuple[Path, TrafficLog | None]:
        """After the drive: the path the episode records as tracked, and the re-planner's log.

        Parameters
        ----------
        driver : Driver
        reference : Reference
        completion_time : float or None
            Simulation time the task was done, seconds (``None``: it was not).

        Returns
        -------
        tuple of (Path, TrafficLog or None)
        """
        raise NotImplementedError
