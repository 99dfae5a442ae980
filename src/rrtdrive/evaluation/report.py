"""The report of one episode and the evaluators' thresholds.

:class:`EpisodeReport` is what :func:`rrtdrive.evaluation.evaluate` returns (every
field is defined in ``docs/metrics.md``); :class:`EvalConfig` holds the thresholds;
:class:`Outcome` sorts an episode into one of four outcomes.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from enum import Enum
from typing import Any

from rrtdrive.types import InputError, require_finite, require_positive

__all__ = [
    "EvalConfig", "EpisodeReport", "Outcome", "OUTCOMES", "SIGNED_FIELDS", "WALL_CLOCK_FIELDS",
]


class Outcome(str, Enum):  # noqa: UP042 (a StrEnum would change str() of a member)
    """How an episode ended, as judged by the evaluators.

    ``SAFE_FOLLOWING`` is an ``overtake-traffic`` episode that ran out of time
    behind the lead car without a collision (counted apart from failures). The
    values are the strings of the report's JSON.
    """

    SUCCESS = "success"
    COLLISION = "collision"
    SAFE_FOLLOWING = "safe_following"
    FAILED = "failed"

    def __str__(self) -> str:
        # As ``enum.StrEnum`` (Python 3.11+): messages print the value.
        return self.value

    def __format__(self, spec: str) -> str:
        return format(self.value, spec)


#: Episode outcomes, as their JSON strings (in :class:`Outcome` order).
OUTCOMES = tuple(o.value for o in Outcome)

#: Numeric report fields that can be negative; every other number of a report is a
#: non-negative quantity (a time, length, count or error magnitude), which the
#: summaries give an interval that cannot go below zero.
SIGNED_FIELDS = frozenset(
    {"progress_m", "final_speed", "nuplan_lon_accel_min", "nuplan_lon_accel_max"}
)


@dataclass(frozen=True)
class EvalConfig:
    """Thresholds of the evaluators.

    Parameters
    ----------
    goal_tol_m : float
        Largest rear-axle distance to the goal pose for success (SPEC: 0.5 m).
    goal_tol_rad : float
        Largest heading error at the goal for success (SPEC: 10°).
    stop_speed : float
        The car counts as stopped below this speed (m/s).
    footprint_spacing : float
        The exact footprint judge checks poses at most this far apart (metres).
    kappa_tol : float
        Relative tolerance of the executed-curvature limit check.
    steer_rate_limit : float
        Steering-rate limit of the executed-steering figures (rad/s at the front
        wheels; CommonRoad's 0.4 by default).
    """

    goal_tol_m: float = 0.5
    goal_tol_rad: float = math.radians(10.0)
    stop_speed: float = 0.1
    footprint_spacing: float = 0.1
    kappa_tol: float = 1e-9
    steer_rate_limit: float = 0.4

    def __post_init__(self) -> None:
        for name in (
            "goal_tol_m", "goal_tol_rad", "stop_speed", "footprint_spacing", "steer_rate_limit"
        ):
            require_positive(f"eval.{name}", getattr(self, name))
        require_finite("eval.kappa_tol", self.kappa_tol)
        if not self.kappa_tol >= 0:
            raise InputError(f"eval.kappa_tol: must be >= 0, got {self.kappa_tol!r}")
        if self.goal_tol_rad > math.pi:  # no heading is further off: degrees, surely
            raise InputError(
                f"eval.goal_tol_rad: must be at most pi (radians), got {self.goal_tol_rad!r}"
            )


#: Report fields measured by the wall clock: they differ from run to run and machine to
#: machine (the rest of a seeded episode's report does not).
WALL_CLOCK_FIELDS = (
    "wall_time_s", "planning_time_s", "replan_time_median_s", "replan_time_max_s",
    "replans_over_budget",
)


@dataclass(frozen=True)
class EpisodeReport:
    """All metrics of one episode (see ``docs/metrics.md`` for each definition).

    ``None`` marks a metric that does not apply (for example tracking errors of an
    episode whose planning failed).

    Attributes
    ----------
    scenario, planner, controller, seed, status, message, ...
        One field per metric, named and defined in ``docs/metrics.md`` (units in
        the names: ``_m``, ``_s``, ``_rad``); the JSON report has the same keys.
    """

    scenario: str
    planner: str
    controller: str
    seed: int
    status: str
    message: str
    success: bool
    collision: bool
    collision_highway_env: bool
    collision_footprint: bool
    reached_goal: bool
    stopped: bool
    passed_lead: bool | None
    back_in_lane: bool | None
    cte_rms_m: float | None
    cte_max_m: float | None
    heading_err_rms_rad: float | None
    heading_err_max_rad: float | None
    path_max_curvature: float | None
    kappa_max: float
    path_length_m: float | None
    executed_max_curvature: float | None
    executed_curvature_violation_share: float | None
    max_lateral_accel: float | None
    max_long_accel: float | None
    max_jerk: float | None
    max_steering_rate: float | None
    goal_position_err_m: float | None
    goal_heading_err_rad: float | None
    final_speed: float | None
    time_to_goal_s: float | None
    duration_s: float
    steps: int
    wall_time_s: float
    planning_time_s: float | None
    simulation_frequency: float
    outcome: Outcome = Outcome.FAILED
    completion_time_s: float | None = None
    progress_m: float | None = None
    ttc_min_s: float | None = None
    ttc_within_bound: bool | None = None
    min_distance_m: float | None = None
    collisions_vehicles: int = 0
    collisions_at_fault: int = 0
    replans: int | None = None
    replan_time_median_s: float | None = None
    replan_time_max_s: float | None = None
    replan_budget_s: float | None = None
    replans_over_budget: int | None = None
    unsafe_steps: int | None = None
    steering_rate_over_limit_share: float | None = None
    path_max_sharpness: float | None = None
    nuplan_comfortable: bool | None = None
    nuplan_lon_accel_min: float | None = None
    nuplan_lon_accel_max: float | None = None
    nuplan_lat_accel_abs_max: float | None = None
    nuplan_lon_jerk_abs_max: float | None = None
    nuplan_jerk_abs_max: float | None = None
    nuplan_yaw_rate_abs_max: float | None = None
    nuplan_yaw_accel_abs_max: float | None = None
    path_cusps: int | None = None
    gear_changes: int = 0  # always applies: 0 when the car never drove

    def __post_init__(self) -> None:
        # Reports read back from JSON carry the outcome as its string.
        try:
            object.__setattr__(self, "outcome", Outcome(self.outcome))
        except ValueError:
            raise InputError(
                f"outcome: must be one of {', '.join(OUTCOMES)}, got {self.outcome!r}"
            ) from None

    def to_json(self) -> dict[str, Any]:
        """A JSON-ready dict (floats rounded to 6 significant digits, NaN as ``None``)."""
        out: dict[str, Any] = {}
        for k, v in asdict(self).items():
            if isinstance(v, float):
                v = None if not math.isfinite(v) else float(f"{v:.6g}")
            elif isinstance(v, Enum):
                v = v.value
            out[k] = v
        return out
