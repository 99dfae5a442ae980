"""``evaluate(episode)``: a table of small metric functions, composed.

As CommonRoad's ``PartialCostFunction`` maps a name to one function, :data:`METRICS`
maps every field of :class:`~rrtdrive.evaluation.report.EpisodeReport` to a
:class:`Metric`: a function ``(episode, context) -> value``. The
:class:`MetricContext` computes what several metrics share (tracking errors,
executed curvature, collision judges, the success terms) once, on first use.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from functools import cached_property
from types import MappingProxyType
from typing import TYPE_CHECKING, Any

import numpy as np

from rrtdrive.evaluation import comfort
from rrtdrive.evaluation.collisions import (
    footprint_collisions,
    logged_vehicle_obstacles,
    map_collision,
    vehicle_collisions,
)
from rrtdrive.evaluation.nuplan_comfort import NuplanComfort, nuplan_comfort
from rrtdrive.evaluation.report import EpisodeReport, EvalConfig
from rrtdrive.evaluation.success import SuccessTerms, success_terms
from rrtdrive.evaluation.tracking import gear_changes, tracking_measures
from rrtdrive.evaluation.traffic_metrics import (
    TTC_LEAST_MIN_S,
    min_vehicle_distance,
    time_to_collision,
)
from rrtdrive.types import InputError

if TYPE_CHECKING:  # pragma: no cover
    from rrtdrive.sim.episode import Episode

__all__ = ["Metric", "MetricContext", "METRICS", "evaluate", "replan_stats"]


class MetricContext:
    """What several metrics of one episode share, each computed once on first use.

    Parameters
    ----------
    episode : Episode
        The episode being scored.
    config : EvalConfig
        Thresholds.
    """

    def __init__(self, episode: Episode, config: EvalConfig) -> None:
        self.episode = episode
        self.config = config

    @property
    def drove(self) -> bool:
        """The car was driven (at least one logged step)."""
        return self.episode.log.steps > 0

    @cached_property
    def measures(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Cross-track and heading errors and the travelled length of every logged pose."""
        states = self.episode.log.states
        return tracking_measures(self.episode.path, states[:, :3], speeds=states[:, 3])

    @cached_property
    def errors(self) -> tuple[np.ndarray, np.ndarray]:
        """Cross-track and heading errors of every logged pose."""
        cte, herr, _ = self.measures
        return cte, herr

    @property
    def progress(self) -> float | None:
        """:func:`~rrtdrive.evaluation.traffic_metrics.progress`, from :attr:`measures`."""
        if len(self.episode.path) < 2:
            return None
        along = self.measures[2]
        return float(along[-1] - along[0])

    @cached_property
    def kappa(self) -> np.ndarray:
        """Executed curvature of every step."""
        return comfort.executed_curvature(self.episode.log, self.episode.scenario.vehicle)

    @cached_property
    def lateral(self) -> np.ndarray:
        """Lateral acceleration of every step."""
        return comfort.lateral_accel(self.episode.log, self.kappa)

    @cached_property
    def crash_highway_env(self) -> bool:
        """highway-env's ``crashed`` flag at any logged time."""
        return bool(np.any(self.episode.log.crashed))

    @cached_property
    def map_hit(self) -> bool:
        """The exact body left the map or touched an obstacle."""
        return map_collision(self.episode, self.config.footprint_spacing)

    @cached_property
    def static_hit(self) -> bool:
        """The body left the map or touched an obstacle that is not a logged vehicle.

        A parked car that is both (:func:`logged_vehicle_obstacles`) counts among the
        vehicle collisions, once.
        """
        if not self.map_hit:
            return False
        skip = logged_vehicle_obstacles(self.episode)
        return not skip or map_collision(self.episode, self.config.footprint_spacing, skip)

    @cached_property
    def crash_footprint(self) -> bool:
        """The footprint judge (map, bounds and other vehicles)."""
        return footprint_collisions(self.episode, self.config.footprint_spacing, self.map_hit)

    @cached_property
    def terms(self) -> SuccessTerms:
        """The success decision."""
        collision = (self.crash_highway_env or self.crash_footprint) if self.drove else False
        return success_terms(self.episode, self.config, collision)

    @cached_property
    def crashes(self) -> list[tuple[int, int, str, bool]]:
        """Collisions with other vehicles (:func:`vehicle_collisions`)."""
        return vehicle_collisions(self.episode)

    @cached_property
    def at_fault(self) -> list[tuple[int, int, str, bool]]:
        """The at-fault collisions with other vehicles."""
        return [c for c in self.crashes if c[3]]

    @cached_property
    def ttc(self) -> np.ndarray | None:
        """Time to collision at every logged time (``None`` without other vehicles)."""
        if not self.episode.log.others.size:
            return None
        return time_to_collision(self.episode, [c[0] for c in self.at_fault])

    @cached_property
    def steering_rates(self) -> np.ndarray:
        """Executed steering rate of every step (:func:`comfort.steering_rate`)."""
        return comfort.steering_rate(self.episode.log)

    @cached_property
    def nuplan(self) -> NuplanComfort | None:
        """NuPlan's comfort figures of the driven trajectory (``None`` under 0.3 s)."""
        ep = self.episode
        v = ep.scenario.vehicle
        return nuplan_comfort(
            ep.log.t, ep.log.states[:, 2], ep.log.states[:, 3], v.length / 2.0 - v.rear_overhang
        )

    @cached_property
    def replan(self) -> dict[str, Any]:
        """Re-planning statistics (:func:`replan_stats`)."""
        return replan_stats(self.episode)


def _nuplan(ctx: MetricContext, name: str) -> Any:
    """One of the nuPlan figures, ``None`` when the drive was too short for them."""
    return None if ctx.nuplan is None else getattr(ctx.nuplan, name)


MetricFn = Callable[["Episode", MetricContext], Any]


@dataclass(frozen=True)
class Metric:
    """One entry of the metric table.

    Attributes
    ----------
    fn : callable
        ``(episode, context) -> value``.
    needs_drive : bool
        Only defined for an episode that drove; else the value is ``empty``.
    empty : Any
        The value when ``needs_drive`` and the car never drove.
    """

    fn: MetricFn
    needs_drive: bool = True
    empty: Any = None


def _always(fn: MetricFn) -> Metric:
    return Metric(fn, needs_drive=False)


def _ttc_min(ep: Episode, ctx: MetricContext) -> float | None:
    if ctx.ttc is None:
        return None
    finite = ctx.ttc[np.isfinite(ctx.ttc)]
    return float(finite.min()) if len(finite) else None


def _ttc_within(ep: Episode, ctx: MetricContext) -> bool | None:
    return None if ctx.ttc is None else bool(np.all(ctx.ttc > TTC_LEAST_MIN_S))


def _when_success(ep: Episode, ctx: MetricContext) -> float | None:
    return float(ep.log.t[-1]) if ctx.terms.success else None


def _replan(key: str) -> Metric:
    return _always(lambda ep, ctx: ctx.replan[key])


#: Field of :class:`EpisodeReport` -> its metric (see ``docs/metrics.md``).
METRICS: Mapping[str, Metric] = MappingProxyType({
    # Identity and run facts.
    "scenario": _always(lambda ep, ctx: ep.scenario.name),
    "planner": _always(lambda ep, ctx: ep.planner),
    "controller": _always(lambda ep, ctx: ep.controller),
    "seed": _always(lambda ep, ctx: ep.seed),
    "status": _always(lambda ep, ctx: ep.status),
    "message": _always(lambda ep, ctx: ep.message),
    "kappa_max": _always(lambda ep, ctx: ep.scenario.vehicle.kappa_max),
    "planning_time_s": _always(
        lambda ep, ctx: ep.plan.planning_time_s if ep.plan is not None else None
    ),
    "simulation_frequency": _always(lambda ep, ctx: 1.0 / ep.log.dt),
    "wall_time_s": _always(lambda ep, ctx: ep.log.wall_time_s),
    "steps": _always(lambda ep, ctx: ep.log.steps),
    "duration_s": _always(lambda ep, ctx: float(ep.log.t[-1]) if len(ep.log.t) else 0.0),
    "path_max_curvature": _always(
        lambda ep, ctx: ep.path.max_curvature if len(ep.path) else None
    ),
    "path_length_m": _always(lambda ep, ctx: ep.path.length if len(ep.path) else None),
    # Success (the terms handle an episode that never drove).
    "success": _always(lambda ep, ctx: ctx.terms.success),
    "outcome": _always(lambda ep, ctx: ctx.terms.outcome),
    "reached_goal": _always(lambda ep, ctx: ctx.terms.reached_goal),
    "stopped": _always(lambda ep, ctx: ctx.terms.stopped),
    "passed_lead": _always(lambda ep, ctx: ctx.terms.passed_lead),
    "back_in_lane": _always(lambda ep, ctx: ctx.terms.back_in_lane),
    "goal_position_err_m": _always(lambda ep, ctx: ctx.terms.goal_position_err_m),
    "goal_heading_err_rad": _always(lambda ep, ctx: ctx.terms.goal_heading_err_rad),
    "time_to_goal_s": Metric(_when_success),
    "completion_time_s": Metric(_when_success),
    # Collisions.
    "collision": Metric(
        lambda ep, ctx: ctx.crash_highway_env or ctx.crash_footprint, empty=False
    ),
    "collision_highway_env": Metric(lambda ep, ctx: ctx.crash_highway_env, empty=False),
    "collision_footprint": Metric(lambda ep, ctx: ctx.crash_footprint, empty=False),
    "collisions_vehicles": Metric(lambda ep, ctx: len(ctx.crashes), empty=0),
    "collisions_at_fault": Metric(
        lambda ep, ctx: len(ctx.at_fault) + int(ctx.static_hit), empty=0
    ),
    # Tracking.
    "cte_rms_m": Metric(lambda ep, ctx: float(np.sqrt(np.mean(ctx.errors[0] ** 2)))),
    "cte_max_m": Metric(lambda ep, ctx: float(np.max(np.abs(ctx.errors[0])))),
    "heading_err_rms_rad": Metric(lambda ep, ctx: float(np.sqrt(np.mean(ctx.errors[1] ** 2)))),
    "heading_err_max_rad": Metric(lambda ep, ctx: float(np.max(np.abs(ctx.errors[1])))),
    # Curvature and comfort.
    "executed_max_curvature": Metric(lambda ep, ctx: float(np.max(np.abs(ctx.kappa)))),
    "executed_curvature_violation_share": Metric(
        lambda ep, ctx: comfort.curvature_violation_share(
            ctx.kappa, ep.scenario.vehicle.kappa_max, ctx.config.kappa_tol
        )
    ),
    "max_lateral_accel": Metric(lambda ep, ctx: float(np.max(np.abs(ctx.lateral)))),
    "max_long_accel": Metric(lambda ep, ctx: float(np.max(np.abs(ep.log.controls[:, 0])))),
    "max_jerk": Metric(lambda ep, ctx: comfort.max_jerk(ep.log, ctx.lateral)),
    "max_steering_rate": Metric(lambda ep, ctx: float(np.max(ctx.steering_rates))),
    "final_speed": Metric(lambda ep, ctx: float(ep.log.states[-1, 3])),
    # Other vehicles and progress.
    "progress_m": Metric(lambda ep, ctx: ctx.progress),
    "ttc_min_s": Metric(_ttc_min),
    "ttc_within_bound": Metric(_ttc_within),
    "min_distance_m": Metric(lambda ep, ctx: min_vehicle_distance(ep)),
    # Re-planning (overtake-traffic).
    "replans": _replan("replans"),
    "replan_time_median_s": _replan("replan_time_median_s"),
    "replan_time_max_s": _replan("replan_time_max_s"),
    "replan_budget_s": _replan("replan_budget_s"),
    "replans_over_budget": _replan("replans_over_budget"),
    "unsafe_steps": _replan("unsafe_steps"),
    # The actuator and nuPlan's ego_is_comfortable (docs/metrics.md, "Drivability").
    "steering_rate_over_limit_share": Metric(
        lambda ep, ctx: float(np.mean(ctx.steering_rates > ctx.config.steer_rate_limit + 1e-9))
    ),
    "path_max_sharpness": _always(
        lambda ep, ctx: comfort.path_sharpness(ep.path, ep.scenario.vehicle.wheelbase)
    ),
    "nuplan_comfortable": Metric(lambda ep, ctx: _nuplan(ctx, "comfortable")),
    "nuplan_lon_accel_min": Metric(lambda ep, ctx: _nuplan(ctx, "lon_accel_min")),
    "nuplan_lon_accel_max": Metric(lambda ep, ctx: _nuplan(ctx, "lon_accel_max")),
    "nuplan_lat_accel_abs_max": Metric(lambda ep, ctx: _nuplan(ctx, "lat_accel_abs_max")),
    "nuplan_lon_jerk_abs_max": Metric(lambda ep, ctx: _nuplan(ctx, "lon_jerk_abs_max")),
    "nuplan_jerk_abs_max": Metric(lambda ep, ctx: _nuplan(ctx, "jerk_abs_max")),
    "nuplan_yaw_rate_abs_max": Metric(lambda ep, ctx: _nuplan(ctx, "yaw_rate_abs_max")),
    "nuplan_yaw_accel_abs_max": Metric(lambda ep, ctx: _nuplan(ctx, "yaw_accel_abs_max")),
    # Gears (docs/metrics.md, "Gear changes").
    "path_cusps": _always(lambda ep, ctx: int(len(ep.path.cusps)) if len(ep.path) else None),
    "gear_changes": Metric(lambda ep, ctx: gear_changes(ep.log.states[:, 3]), empty=0),
})


def evaluate(episode: Episode, config: EvalConfig | None = None) -> EpisodeReport:
    """Score one episode: every metric of :data:`METRICS`.

    Parameters
    ----------
    episode : Episode
        From :func:`rrtdrive.sim.runner.run_episode`.
    config : EvalConfig, optional
        Thresholds.

    Returns
    -------
    EpisodeReport

    Examples
    --------
    >>> report = evaluate(run_episode("parking", seed=0))  # doctest: +SKIP
    >>> report.success, report.cte_rms_m  # doctest: +SKIP
    (True, 0.02)
    """
    from rrtdrive.sim.episode import Episode  # a leaf module: numpy only

    if not isinstance(episode, Episode):
        raise InputError(
            f"episode: expected an Episode (what run_episode returns), got "
            f"{type(episode).__name__}"
        )
    if config is not None and not isinstance(config, EvalConfig):
        raise InputError(f"config: expected an EvalConfig, got {type(config).__name__}")
    ctx = MetricContext(episode, config or EvalConfig())
    values = {
        name: metric.fn(episode, ctx) if ctx.drove or not metric.needs_drive else metric.empty
        for name, metric in METRICS.items()
    }
    return EpisodeReport(**values)


def replan_stats(episode: Episode) -> dict[str, Any]:
    """Re-planning cycle statistics of an ``overtake-traffic`` episode (else ``None``)."""
    traffic = getattr(episode, "traffic", None)
    keys = (
        "replans", "replan_time_median_s", "replan_time_max_s", "replan_budget_s",
        "replans_over_budget", "unsafe_steps",
    )
    if traffic is None:
        return dict.fromkeys(keys)
    times = traffic.cycle_times()
    budget = traffic.config.cycle_budget_s
    return {
        "replans": len(times),
        "replan_time_median_s": float(np.median(times)) if len(times) else None,
        "replan_time_max_s": float(np.max(times)) if len(times) else None,
        "replan_budget_s": budget,
        "replans_over_budget": int(np.sum(times > budget)),
        "unsafe_steps": traffic.unsafe_steps,
    }
