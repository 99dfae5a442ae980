"""The closed loop: plan, then track the path in highway-env at the simulation frequency.

:func:`run_episode` builds a scenario's scene, plans (or takes a given plan),
drives the ego car with a controller once per simulation step and returns an
:class:`Episode`: the plan, the path and the logged trajectory, nothing else.
Metrics come from :func:`rrtdrive.evaluation.evaluate`; videos replay an episode
(:mod:`rrtdrive.sim.video`). Everything random is drawn from the episode seed,
so an episode is a pure function of its arguments.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from rrtdrive.controllers import SpeedConfig, TrackingController, VehicleState, make_controller
from rrtdrive.sim.drivelog import DriveLog, DriveRecorder
from rrtdrive.sim.ego import EgoVehicle
from rrtdrive.sim.scenes import Scenario, SimConfig, build_env, make_scenario, scenario_rngs
from rrtdrive.sim.traffic import OncomingGate, conflict_zone
from rrtdrive.types import Budget, InputError, Path, PlanResult

if TYPE_CHECKING:  # pragma: no cover
    from rrtdrive.sim.replanning import ReplanConfig, TrafficLog

__all__ = ["EpisodeConfig", "Episode", "DriveLog", "run_episode", "drive", "plan_scenario"]

logger = logging.getLogger(__name__)

DEFAULT_PLANNER = "improved-rrt-connect"
#: The planner label of ``overtake-traffic`` episodes (the improved RRT-Connect in space-time).
TRAFFIC_PLANNER = "spacetime-rrt-connect"


@dataclass(frozen=True)
class EpisodeConfig:
    """Everything about an episode besides the scenario, planner, controller and seed.

    Parameters
    ----------
    sim : SimConfig
        Simulation frequency (the control rate) and frame size.
    speed : SpeedConfig, optional
        Speed profile and PI gains; by default the controllers' defaults with the
        scenario's ``v_max``.
    controller_options : Mapping
        Extra keyword arguments for the controller (gains).
    budget : Budget
        Planning budget.
    max_time_s : float, optional
        Time limit of the drive; by default the scenario's.
    stop_on_crash : bool
        End the episode at highway-env's first ``crashed``.
    replan : ReplanConfig, optional
        ``overtake-traffic``: re-planning settings
        (:class:`rrtdrive.sim.replanning.ReplanConfig`; default its defaults).
    """

    sim: SimConfig = field(default_factory=SimConfig)
    speed: SpeedConfig | None = None
    controller_options: Mapping[str, Any] = field(default_factory=dict)
    budget: Budget = field(default_factory=Budget)
    max_time_s: float | None = None
    stop_on_crash: bool = True
    replan: ReplanConfig | None = None

    def __post_init__(self) -> None:
        if self.max_time_s is not None and not (
            math.isfinite(self.max_time_s) and self.max_time_s > 0
        ):
            raise InputError(f"episode.max_time_s: must be > 0, got {self.max_time_s!r}")


@dataclass(frozen=True, eq=False)
class Episode:
    """One closed-loop episode: what was asked, what was planned, what happened.

    Attributes
    ----------
    scenario : Scenario
        The task (map with start and goal, seed, success terms).
    planner, controller : str
        Names.
    seed : int
        Episode seed.
    plan : PlanResult or None
        The planner's result (``None`` when a path was given directly).
    path : Path
        The path that was tracked (empty when planning failed).
    log : DriveLog
        The trajectory.
    status : str
        ``"arrived"``, ``"crashed"``, ``"timeout"`` or ``"plan_failed"``; for
        ``overtake-traffic`` ``"completed"`` (the overtake is done), ``"crashed"``
        or ``"timeout"``.
    message : str
        Human-readable detail.
    config : EpisodeConfig
        The resolved configuration.
    traffic : TrafficLog or None
        ``overtake-traffic``: the re-planner's log (cycles, references, modes); the
        ``path`` is then the reference actually tracked, stitched from the plans.
    """

    scenario: Scenario
    planner: str
    controller: str
    seed: int
    plan: PlanResult | None
    path: Path
    log: DriveLog
    status: str
    message: str
    config: EpisodeConfig
    traffic: TrafficLog | None = None


def plan_scenario(
    scenario: Scenario, planner: str, seed: int, budget: Budget | None = None
) -> PlanResult:
    """Plan the scenario's query with the registered planner ``planner``.

    The planner's generator is the episode seed's planner stream.
    """
    from rrtdrive.planning import PlanningProblem, make_planner

    _, plan_rng, _ = scenario_rngs(seed)
    return make_planner(planner).solve(
        PlanningProblem.from_map(scenario.map), plan_rng, budget or Budget()
    )


def drive(
    env: Any,
    path: Path,
    controller: TrackingController,
    max_time_s: float,
    stop_on_crash: bool = True,
    gate: OncomingGate | None = None,
    gate_cars: list[Any] | None = None,
) -> DriveLog:
    """Track ``path`` with ``controller`` in a highway-env environment until done.

    The controller runs once per simulation step: each step sets the ego's action,
    lets every other vehicle act (``road.act``) and advances the physics
    (``road.step(dt)``), exactly as highway-env's own ``_simulate`` does.

    Parameters
    ----------
    env : gymnasium.Env
        A reset highway-env environment whose controlled vehicle is an :class:`EgoVehicle`.
    path : Path
        Rear-axle path to track.
    controller : TrackingController
        Reset here on ``path``.
    max_time_s : float
        Time limit.
    stop_on_crash : bool
        Stop at highway-env's first ``crashed``.
    gate : OncomingGate, optional
        Holds the car before the oncoming lane until there is a gap.
    gate_cars : list, optional
        The oncoming vehicles the gate watches.

    Returns
    -------
    DriveLog
    """
    u = env.unwrapped
    ego = u.vehicle
    if not isinstance(ego, EgoVehicle):
        raise InputError("env: the controlled vehicle must be an EgoVehicle (see attach_ego)")
    dt = 1.0 / u.config["simulation_frequency"]
    controller.reset(path, v_start=ego.speed)
    n_max = int(math.ceil(max_time_s / dt - 1e-9))
    rec = DriveRecorder(env, dt)
    arrived = False
    t = 0.0
    wall0 = time.perf_counter()
    for _ in range(n_max):
        r = ego.rear
        if gate is not None:
            controller.speed.stop_at = gate.stop_line(controller.s, ego.speed, gate_cars or [])
        rec.step(*controller.control(VehicleState(r[0], r[1], r[2], ego.speed, ego.steer, t)))
        t += dt
        if ego.crashed and stop_on_crash:
            break
        if controller.arrived and ego.speed == 0.0:
            arrived = True
            break
    return rec.log(arrived, time.perf_counter() - wall0)


def run_episode(
    scenario: str | Scenario,
    planner: str | PlanResult | Path = DEFAULT_PLANNER,
    controller: str = "pure-pursuit",
    seed: int = 0,
    config: EpisodeConfig | None = None,
) -> Episode:
    """Plan and drive one episode; deterministic for a given seed.

    Parameters
    ----------
    scenario : str or Scenario
        ``"parking"``, ``"overtake"`` (built for ``seed``) or a ready :class:`Scenario`.
    planner : str, PlanResult or Path
        A registered planner name, or a plan/path to track as given.
    controller : str
        ``"pure-pursuit"``, ``"stanley"`` or ``"lqr"``.
    seed : int
        Episode seed: start jitter, goal choice, planner and simulator streams.
    config : EpisodeConfig, optional
        Frequency, speed profile, gains, budget, time limit.

    Returns
    -------
    Episode

    Examples
    --------
    >>> ep = run_episode("overtake", planner=my_path, controller="lqr", seed=1)  # doctest: +SKIP
    >>> evaluate(ep).success  # doctest: +SKIP
    True
    """
    config = config or EpisodeConfig()
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise InputError(f"seed: need an integer >= 0, got {seed!r}")
    seed = int(seed)
    scen = make_scenario(scenario, seed) if isinstance(scenario, str) else scenario
    if not isinstance(scen, Scenario):
        raise InputError(f"scenario: expected a name or a Scenario, got {scenario!r}")
    if scen.is_traffic:
        return _run_traffic(scen, planner, controller, seed, config)
    speed = config.speed or SpeedConfig(v_max=scen.v_max)
    ctrl = make_controller(
        controller, vehicle=scen.vehicle, speed=speed, **dict(config.controller_options)
    )
    plan: PlanResult | None
    if isinstance(planner, str):
        plan = plan_scenario(scen, planner, seed, config.budget)
        planner_name = planner
        path = plan.path
    elif isinstance(planner, PlanResult):
        plan, planner_name, path = planner, planner.planner, planner.path
    elif isinstance(planner, Path):
        plan, planner_name, path = None, "given", planner
    else:
        raise InputError(f"planner: expected a name, a PlanResult or a Path, got {planner!r}")
    dt = config.sim.dt
    if plan is not None and not plan.success:
        return Episode(
            scen, planner_name, controller, seed, plan, Path.empty(), DriveLog.empty(dt),
            "plan_failed", f"planning failed ({plan.status.value}): {plan.message}", config,
        )
    if len(path) < 2:
        return Episode(
            scen, planner_name, controller, seed, plan, path, DriveLog.empty(dt),
            "plan_failed", "the path has fewer than two samples", config,
        )
    env = build_env(scen, config.sim)
    gate, cars = None, None
    if scen.oncoming and scen.lane_y is not None:
        zone = conflict_zone(path, scen.lane_y, scen.lane_width, scen.vehicle)
        if zone is not None:
            ego = env.unwrapped.vehicle
            cars = [v for v in env.unwrapped.road.vehicles if v is not ego and v.speed > 0]
            gate = OncomingGate(zone, (path.arc_length(), path.samples[:, 3]), speed)
    try:
        max_time = config.max_time_s or scen.max_time_s
        log = drive(env, path, ctrl, max_time, config.stop_on_crash, gate, cars)
    finally:
        env.close()
    if log.crashed[-1]:
        status, message = "crashed", f"highway-env reported a crash at t = {log.t[-1]:.2f} s"
    elif log.arrived:
        status, message = "arrived", f"stopped at the end of the path at t = {log.t[-1]:.2f} s"
    else:
        status, message = "timeout", f"not stopped at the goal within {max_time:g} s"
    logger.info("episode %s/%s/%s seed %d: %s", scen.name, planner_name, controller, seed, status)
    return Episode(scen, planner_name, controller, seed, plan, path, log, status, message, config)


def traffic_speed_config(scenario: Scenario) -> SpeedConfig:
    """Speed profile of ``overtake-traffic``: its cap, 1.5 m/s^2 to speed up, 2 m/s^2 lateral.

    Braking is not jerk-limited here and the path-end stop is the constant-deceleration
    one (``jerk_brake_max=None``, ``stop_taper=False``): the re-planner's space-time
    checks time plans by the speed profile itself, and the traffic results
    (docs/traffic.md) were measured with these settings.
    """
    return SpeedConfig(
        v_max=scenario.v_max, accel=1.5, a_lat_max=2.0, jerk_brake_max=None, stop_taper=False
    )


def _run_traffic(
    scen: Scenario, planner: object, controller: str, seed: int, config: EpisodeConfig
) -> Episode:
    """An ``overtake-traffic`` episode: receding-horizon space-time re-planning in the loop."""
    from rrtdrive.sim.replanning import ReplanConfig, drive_traffic

    if planner not in (DEFAULT_PLANNER, TRAFFIC_PLANNER):
        raise InputError(
            f"planner: overtake-traffic re-plans with the improved RRT-Connect in space-time "
            f"({DEFAULT_PLANNER!r}); got {planner!r}"
        )
    replan = config.replan or ReplanConfig()
    if not isinstance(replan, ReplanConfig):
        raise InputError(f"episode.replan: expected a ReplanConfig, got {replan!r}")
    speed = config.speed or traffic_speed_config(scen)
    ctrl = make_controller(
        controller, vehicle=scen.vehicle, speed=speed, **dict(config.controller_options)
    )
    _, plan_rng, _ = scenario_rngs(seed)
    env = build_env(scen, config.sim)
    max_time = config.max_time_s or scen.max_time_s
    try:
        log, traffic, status = drive_traffic(
            env, scen, ctrl, speed, replan, plan_rng, max_time, config.stop_on_crash
        )
    finally:
        env.close()
    if status == "crashed":
        message = f"highway-env reported a crash at t = {log.t[-1]:.2f} s"
    elif status == "completed":
        message = f"overtake complete at t = {log.t[-1]:.2f} s"
    else:
        message = f"no overtake within {max_time:g} s (followed the lead car)"
    resolved = dataclasses.replace(config, speed=speed, replan=replan)
    logger.info("episode %s/%s seed %d: %s", scen.name, controller, seed, status)
    return Episode(
        scen, TRAFFIC_PLANNER, controller, seed, None, traffic.executed, log, status, message,
        resolved, traffic,
    )
