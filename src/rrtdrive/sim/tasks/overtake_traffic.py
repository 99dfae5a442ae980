"""The overtake-traffic task: overtake a slow moving car against a seeded oncoming stream.

A long two-way road (the overtake lanes) with a slow *moving* lead car in the ego
lane (highway-env IDM or constant speed) and a seeded stream of oncoming IDM cars
(speeds and gaps drawn per seed, mean gap from the density in cars per km). The
ego overtakes with receding-horizon space-time re-planning
(:class:`~rrtdrive.sim.traffic_driver.TrafficDriver`) and is done once it is back
in its lane ahead of the lead car (:func:`overtake_complete`).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np
from highway_env.road.road import Road

from rrtdrive.controllers import SpeedConfig, TrackingController
from rrtdrive.maps import LANE_WIDTH, Map
from rrtdrive.sim.episode import EpisodeStatus
from rrtdrive.sim.replanning import ReplanConfig, TrafficLog
from rrtdrive.sim.scenes import SceneView, populate_road, scenario_rngs, two_way_network
from rrtdrive.sim.tasks.base import (
    DEFAULT_PLANNER,
    Reference,
    SuccessPart,
    Task,
    TaskKind,
    VideoCamera,
)
from rrtdrive.sim.traffic_driver import TrafficDriver
from rrtdrive.types import Budget, InputError, Path, Pose, VehicleParams, require_positive
from rrtdrive.values import did_you_mean
from rrtdrive.vehicle import footprint_corners

if TYPE_CHECKING:  # pragma: no cover
    from rrtdrive.sim.ego import EgoVehicle
    from rrtdrive.sim.episode import Episode
    from rrtdrive.sim.runner import EpisodeConfig

__all__ = [
    "OvertakeTrafficTask",
    "TRAFFIC_PLANNER",
    "TRAFFIC_DENSITIES",
    "LEAD_MODELS",
    "traffic_map",
    "traffic_speed_config",
    "overtake_complete",
]

#: The planner label of ``overtake-traffic`` episodes (the improved RRT-Connect in space-time).
TRAFFIC_PLANNER = "spacetime-rrt-connect"
#: Named oncoming-traffic densities of ``overtake-traffic`` (cars per km of oncoming lane).
TRAFFIC_DENSITIES: dict[str, float] = {"low": 5.0, "default": 10.0, "high": 20.0}
#: How the lead car of ``overtake-traffic`` drives.
LEAD_MODELS = ("idm", "constant")
#: Road of ``overtake-traffic``: length in metres and the ego's start x.
TRAFFIC_ROAD_LENGTH = 1500.0
TRAFFIC_START_X = 5.0


def overtake_complete(
    ego_rear: Sequence[float],
    lead_centre: Sequence[float],
    lead_length: float,
    lane_y: float,
    lane_width: float,
    vehicle: Any,
    gap: float,
) -> bool:
    """Back in the ego lane (all body corners), aligned within 10°, ``gap`` ahead of the lead.

    The completion test of ``overtake-traffic``: every corner of the ego's body lies
    within the ego lane, its heading is within 10° of the lane's, and its rear
    bumper is at least ``gap`` metres beyond the lead car's front bumper.

    Parameters
    ----------
    ego_rear : sequence of float
        The ego's rear-axle pose ``(x, y, yaw)`` (metres, radians; extra entries ignored).
    lead_centre : sequence of float
        ``(x, y)`` of the lead car's body centre.
    lead_length : float
        The lead car's length in metres.
    lane_y, lane_width : float
        Centre line and width of the ego lane, metres.
    vehicle : VehicleParams
        The ego car (its body).
    gap : float
        Least distance from the lead's front bumper to the ego's rearmost corner, metres.

    Returns
    -------
    bool

    Examples
    --------
    >>> from rrtdrive.types import VehicleParams
    >>> overtake_complete((30.0, 44.0, 0.0), (20.0, 44.0), 4.3, 44.0, 4.0, VehicleParams(), 2.0)
    True
    """
    corners = footprint_corners(np.asarray(ego_rear, dtype=float)[:3], vehicle)
    in_lane = bool(np.all(np.abs(corners[:, 1] - lane_y) <= lane_width / 2.0))
    aligned = abs(math.remainder(float(ego_rear[2]), 2.0 * math.pi)) <= math.radians(10.0)
    ahead = corners[:, 0].min() >= float(lead_centre[0]) + lead_length / 2.0 + gap
    return in_lane and aligned and bool(ahead)


def traffic_map(vehicle: VehicleParams | None = None, start: Pose | None = None) -> Map:
    """The road of ``overtake-traffic`` as a map: two 4 m lanes along x, the edges as bounds.

    The bounds are the road (x in [0, 1500], y in [42, 50]) and act as walls; the
    ego lane is centred on y = 44 (driving +x), the oncoming lane on y = 48. No
    static obstacles: the lead car and the oncoming cars move. The goal is the far
    end of the ego lane (the episode ends earlier, when the overtake is complete).

    Parameters
    ----------
    vehicle : VehicleParams, optional
        The ego car (``None``: the default car).
    start : Pose, optional
        Rear-axle start pose (``None``: x = 5 m on the ego lane's centre, heading +x).

    Returns
    -------
    Map
    """
    vehicle = vehicle or VehicleParams()
    return Map(
        "overtake-traffic",
        (0.0, 42.0, TRAFFIC_ROAD_LENGTH, 42.0 + 2 * LANE_WIDTH),
        (),
        start or Pose(TRAFFIC_START_X, 44.0, 0.0),
        Pose(TRAFFIC_ROAD_LENGTH - 10.0, 44.0, 0.0),
        vehicle,
    )


def traffic_speed_config(scenario: Task) -> SpeedConfig:
    """Speed profile of ``overtake-traffic``: its cap, 1.5 m/s^2 to speed up, 2 m/s^2 lateral.

    Braking is not jerk-limited here and the path-end stop is the constant-deceleration
    one (``jerk_brake_max=None``, ``stop_taper=False``): the re-planner's space-time
    checks time plans by the speed profile itself, and the traffic results
    (docs/traffic.md) were measured with these settings.

    Parameters
    ----------
    scenario : Task
        Gives the cap ``v_max`` (m/s).

    Returns
    -------
    SpeedConfig
    """
    return SpeedConfig(
        v_max=scenario.v_max, accel=1.5, a_lat_max=2.0, jerk_brake_max=None, stop_taper=False
    )


def _density(density: object) -> float:
    """Oncoming cars per km from a number or a name of :data:`TRAFFIC_DENSITIES`."""
    if density is None:
        return TRAFFIC_DENSITIES["default"]
    if isinstance(density, str):
        if density in TRAFFIC_DENSITIES:
            return TRAFFIC_DENSITIES[density]
        try:
            density = float(density)
        except ValueError:
            raise InputError(
                f"density: expected cars per km or one of {', '.join(sorted(TRAFFIC_DENSITIES))}, "
                f"got {density!r}{did_you_mean(density, TRAFFIC_DENSITIES)}"
            ) from None
    require_positive("density", density)  # type: ignore[arg-type]
    if density > 30.0:  # type: ignore[operator]
        raise InputError(f"density: at most 30 cars per km, got {density!r}")
    return float(density)  # type: ignore[arg-type]


@dataclass(frozen=True, kw_only=True)
class OvertakeTrafficTask(Task):
    """Overtake a moving lead car against oncoming traffic, re-planning in the loop.

    Parameters
    ----------
    map, seed, v_max, max_time_s
        See :class:`~rrtdrive.sim.tasks.Task`.
    lane_y : float
        Centre line of the ego lane.
    lane_width : float
        Lane width in metres.
    oncoming : tuple of (float, float)
        ``(x, speed)`` of each oncoming car (body centre, m/s) at the start.
    lead : tuple of (float, float) or None
        ``(x, speed)`` of the moving lead car's body centre in the ego lane (the
        first vehicle of the scene after the ego).
    lead_model : str
        ``"idm"`` (highway-env IDM, keeps its lane, follows the vehicle ahead) or
        ``"constant"`` (a plain highway-env vehicle at constant speed).
    density : float
        Oncoming cars per km (mean gap ``1000 / density`` m).
    ego_speed : float
        Initial speed of the ego in m/s.
    """

    kind: ClassVar[TaskKind] = TaskKind.OVERTAKE_TRAFFIC
    REPLAN_CONFIG: ClassVar[type[ReplanConfig] | None] = ReplanConfig
    OPTIONS: ClassVar[tuple[str, ...]] = ("density", "lead_speed", "lead_model")
    PLANNERS: ClassVar[tuple[str, ...] | None] = (DEFAULT_PLANNER, TRAFFIC_PLANNER)

    # Fields where Task keeps class-level defaults for the kinds without them (mypy
    # reads that as overriding a ClassVar).
    lane_y: float = 44.0  # type: ignore[misc]
    lane_width: float = LANE_WIDTH  # type: ignore[misc]
    oncoming: tuple[tuple[float, float], ...] = ()  # type: ignore[misc]
    lead: tuple[float, float] | None = None  # type: ignore[misc]
    lead_model: str = "idm"
    density: float = TRAFFIC_DENSITIES["default"]
    ego_speed: float = 0.0  # type: ignore[misc]

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.lead_model not in LEAD_MODELS:
            raise InputError(
                f"lead_model: unknown lead model {self.lead_model!r}"
                f"{did_you_mean(self.lead_model, LEAD_MODELS)}; "
                f"choose from {', '.join(LEAD_MODELS)}"
            )
        if not (math.isfinite(self.ego_speed) and self.ego_speed >= 0):
            raise InputError(f"scenario.ego_speed: must be >= 0, got {self.ego_speed!r}")
        if self.lead is None:
            # Without one the episode could only time out, and was scored as following.
            raise InputError(
                "scenario.lead: overtake-traffic needs a lead car to overtake, "
                "given as (x, speed)"
            )

    @classmethod
    def create(
        cls,
        seed: int,
        rng: np.random.Generator,
        offset: tuple[float, float, float],
        vehicle: VehicleParams,
        density: object = None,
        lead_speed: object = None,
        lead_model: object = None,
    ) -> OvertakeTrafficTask:
        """The task for ``seed``: the lead car 20-30 m ahead, the oncoming stream drawn."""
        dens = _density(density)
        v_lead = 4.0 if lead_speed is None else lead_speed
        require_positive("lead_speed", v_lead)  # type: ignore[arg-type]
        v_max = 11.0
        if v_lead >= v_max - 2.0:  # type: ignore[operator]
            raise InputError(
                f"lead_speed: must be below {v_max - 2.0:g} m/s (the ego's cap is {v_max:g}), "
                f"got {v_lead!r}"
            )
        model = "idm" if lead_model is None else lead_model
        if model not in LEAD_MODELS:
            raise InputError(
                f"lead_model: unknown lead model {model!r}{did_you_mean(model, LEAD_MODELS)}; "
                f"choose from {', '.join(LEAD_MODELS)}"
            )
        dx, dy, dyaw = offset
        start = Pose(TRAFFIC_START_X + dx, 44.0 + 0.3 * dy, 0.4 * dyaw)
        m = traffic_map(vehicle, start)
        centre_offset = vehicle.length / 2.0 - vehicle.rear_overhang
        lead_x = start.x + centre_offset + float(rng.uniform(20.0, 30.0))
        mean_gap = 1000.0 / dens
        gap_min = 25.0
        cars = []
        x = start.x + 40.0 + float(rng.uniform(0.0, mean_gap))
        while x < start.x + 1300.0:
            cars.append((x, float(rng.uniform(6.0, 9.0))))
            x += gap_min + float(rng.exponential(max(mean_gap - gap_min, 1.0)))
        return cls(
            map=m, seed=int(seed), lane_y=44.0, v_max=v_max, max_time_s=90.0,
            oncoming=tuple(cars), lead=(lead_x, float(v_lead)),  # type: ignore[arg-type]
            lead_model=str(model), density=dens, ego_speed=float(v_lead),  # type: ignore[arg-type]
        )

    @property
    def road_time_s(self) -> float:
        """How long the lead car stays on the road: until its front is 10 m from the end.

        Past that the scene is over: highway-env sends the lead car round into the
        oncoming lane, and a car still following it runs out of road.
        """
        assert self.lead is not None  # __post_init__ refuses a task without one
        x, speed = self.lead
        if speed <= 0.0:  # a standing lead car (a test's obstacle) never gets there
            return math.inf
        return (TRAFFIC_ROAD_LENGTH - 10.0 - (x + self.vehicle.length / 2.0)) / speed

    def check_time_limit(self, max_time_s: float, name: str) -> None:
        """Refuse a time limit longer than :attr:`road_time_s` (an overtake judged on no road).

        Parameters
        ----------
        max_time_s : float
            The time limit, seconds.
        name : str
            The field that gave it (the message's first word).

        Raises
        ------
        InputError
            When ``max_time_s`` exceeds :attr:`road_time_s`.
        """
        if self.lead is not None and max_time_s > self.road_time_s:
            speed = self.lead[1]
            raise InputError(
                f"{name}: at most {math.floor(self.road_time_s):g} s, got {max_time_s:g}: the "
                f"lead car at {speed:g} m/s reaches the end of overtake-traffic's "
                f"{TRAFFIC_ROAD_LENGTH:g} m road by then (a slower lead car leaves more time)"
            )

    def describe(self) -> dict[str, Any]:
        """Density, lead speed and lead model."""
        return {
            "density_per_km": self.density,
            "lead_speed": self.lead[1] if self.lead else None,
            "lead_model": self.lead_model,
        }

    # ------------------------------------------------------------------ scene

    def build_road(self, np_random: np.random.Generator, history: bool) -> Road:
        """The long two-way road, the moving lead car first, then the oncoming stream.

        Parameters
        ----------
        np_random, history
            As :meth:`Task.build_road`.

        Returns
        -------
        Road
        """
        net = two_way_network(self.map.bounds, self.lane_y, self.lane_width)
        return populate_road(
            net, self.map, np_random, history, lead=self.lead, lead_model=self.lead_model,
            oncoming=self.oncoming,
        )

    def scene_view(self) -> SceneView:
        """A wide window, the ego left of centre."""
        return SceneView((900, 300), 8.0, (0.35, 0.5))

    def camera(self) -> VideoCamera:
        """A long road: a wide window that follows the ego."""
        return VideoCamera((960, 320), 8.0, (0.0, (self.lane_y or 44.0) + 2.0), follow=True)

    # ------------------------------------------------------------------ episode

    @property
    def success_status(self) -> EpisodeStatus:
        """``COMPLETED``."""
        return EpisodeStatus.COMPLETED

    def overtake_complete(
        self, ego_rear: Sequence[float], lead_centre: Sequence[float], lead_length: float,
        gap: float,
    ) -> bool:
        """:func:`overtake_complete` in this task's lane, for this task's car.

        Parameters
        ----------
        ego_rear, lead_centre, lead_length, gap
            As :func:`overtake_complete`.

        Returns
        -------
        bool
        """
        return overtake_complete(
            ego_rear, lead_centre, lead_length, float(self.lane_y), float(self.lane_width),
            self.vehicle, gap,
        )

    def reached(self, ego: EgoVehicle, driver: Any) -> bool:
        """The overtake is complete and the ego never crashed (highway-env's flag stays set).

        Parameters
        ----------
        ego : EgoVehicle
            The ego car after the step.
        driver : TrafficDriver
            The re-planner; its ``lead`` car (``None``: not done) and ``config.complete_gap_m``.

        Returns
        -------
        bool
        """
        lead = driver.lead
        if lead is None or ego.crashed:
            return False
        r = ego.rear
        return self.overtake_complete(
            (r[0], r[1], r[2]), (lead.position[0], lead.position[1]), lead.LENGTH,
            driver.config.complete_gap_m,
        )

    def success_part(self, episode: Episode) -> SuccessPart:
        """The overtake itself: back in the lane, aligned, ahead of the moving lead car.

        It ends on the move and has no goal pose to report; a timeout without a
        collision is safe following.

        Parameters
        ----------
        episode : Episode
            A finished episode of this task (its last logged state and lead car are judged).

        Returns
        -------
        SuccessPart
        """
        log = episode.log
        final = log.states[-1]
        lead, (lead_len, _w) = log.others[-1, 0], log.other_sizes[0]
        body = footprint_corners(final[:3], self.vehicle)
        passed_lead = bool(body[:, 0].min() > lead[0] + lead_len / 2.0)
        back_in_lane = bool(np.all(np.abs(body[:, 1] - self.lane_y) <= self.lane_width / 2.0))
        gap = episode.traffic.config.complete_gap_m if episode.traffic is not None else 0.0
        reached = self.overtake_complete(final[:3], lead[:2], lead_len, gap)
        return SuccessPart(
            passed_lead=passed_lead, back_in_lane=back_in_lane, reached_goal=reached,
            ends_moving=True, goal_errors=False, timeout_is_following=True,
        )

    def default_speed(self) -> SpeedConfig:
        """:func:`traffic_speed_config`."""
        return traffic_speed_config(self)

    def resolve(self, config: EpisodeConfig) -> tuple[SpeedConfig, EpisodeConfig]:
        """The traffic speed settings and the re-planning defaults, recorded in the config.

        Parameters
        ----------
        config : EpisodeConfig
            The episode's settings; ``speed`` and ``replan`` ``None`` take the defaults.

        Returns
        -------
        tuple of (SpeedConfig, EpisodeConfig)
            The speed settings, and ``config`` with both filled in.

        Raises
        ------
        InputError
            When ``config.replan`` is not a :class:`~rrtdrive.sim.replanning.ReplanConfig`.
        """
        replan = config.replan or ReplanConfig()
        if not isinstance(replan, ReplanConfig):
            raise InputError(f"episode.replan: expected a ReplanConfig, got {replan!r}")
        speed = config.speed or self.default_speed()
        return speed, dataclasses.replace(config, speed=speed, replan=replan)

    def reference(
        self, planner: object, seed: int, budget: Budget, options: Mapping[str, Any] | None = None
    ) -> Reference:
        """Nothing planned ahead: the driver re-plans in the loop (only with its own planner).

        Parameters
        ----------
        planner : object
            Must be one of :attr:`PLANNERS` (a name).
        seed, budget
            Unused (the driver plans with the episode seed's planner stream).
        options : mapping of str to Any, optional
            Must be empty.

        Returns
        -------
        Reference
            No plan, no path: :attr:`Reference.plans_while_driving`.

        Raises
        ------
        InputError
            For any planner but the space-time improved RRT-Connect, and for ``options``
            (its re-planner takes ``ReplanConfig.planner_options``).
        """
        if options:
            raise InputError(
                "planner_options: overtake-traffic re-plans with its own planner; give "
                "ReplanConfig(planner_options=...) instead"
            )
        if planner not in (self.PLANNERS or ()):
            raise InputError(
                f"planner: overtake-traffic re-plans with the improved RRT-Connect in space-time "
                f"({DEFAULT_PLANNER!r}); got {planner!r}"
            )
        return Reference(None, TRAFFIC_PLANNER, None)

    def make_driver(
        self,
        env: Any,
        controller: TrackingController,
        reference: Reference,
        speed: SpeedConfig,
        config: EpisodeConfig,
        seed: int,
    ) -> TrafficDriver:
        """The re-planner, its planner drawing from the episode seed's planner stream.

        Parameters
        ----------
        env, controller, reference, speed, config, seed
            As :meth:`Task.make_driver`; ``config.replan`` set by :meth:`resolve`,
            ``reference`` unused.

        Returns
        -------
        TrafficDriver
        """
        _, plan_rng, _ = scenario_rngs(seed)
        replan = config.replan
        assert isinstance(replan, ReplanConfig)  # resolved by :meth:`resolve`
        return TrafficDriver(env, self, controller, speed, replan, plan_rng)

    def outcome(self, driver: Any, reference: Reference, completion_time: float | None
                ) -> tuple[Path, TrafficLog | None]:
        """The reference actually tracked (stitched from the plans) and the re-planner's log.

        Parameters
        ----------
        driver : TrafficDriver
            The re-planner after the drive.
        reference : Reference
            Unused.
        completion_time : float or None
            When the overtake was complete, seconds (``None``: it was not).

        Returns
        -------
        tuple of (Path, TrafficLog)
        """
        traffic = driver.finish(completion_time)
        return traffic.executed, traffic
