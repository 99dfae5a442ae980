"""``summarise(reports)``: aggregates of episode reports over seeds.

Every aggregate is one :func:`rrtdrive.stats.describe` of a metric (the function
the bench summary uses): order statistics, means and 95 % intervals from
``scipy.stats`` (Wilson for the success rate, a bootstrap for the non-negative
metrics, Student's t for the signed ones, :data:`SIGNED_FIELDS`).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from rrtdrive.evaluation.report import OUTCOMES, SIGNED_FIELDS, EpisodeReport
from rrtdrive.stats import Stat, describe
from rrtdrive.types import InputError

__all__ = ["summarise", "MEAN_FIELDS"]

#: The metrics whose mean, max and interval :func:`summarise` gives, over the episodes
#: that drove (``planning_time_s``: over every episode that planned).
MEAN_FIELDS = (
    "cte_rms_m", "cte_max_m", "heading_err_rms_rad", "heading_err_max_rad",
    "path_max_curvature", "path_max_sharpness", "path_length_m",
    "executed_max_curvature", "executed_curvature_violation_share", "max_lateral_accel",
    "max_long_accel", "max_jerk", "max_steering_rate", "steering_rate_over_limit_share",
    "nuplan_lon_accel_min", "nuplan_lon_accel_max", "nuplan_lat_accel_abs_max",
    "nuplan_lon_jerk_abs_max", "nuplan_jerk_abs_max", "nuplan_yaw_rate_abs_max",
    "nuplan_yaw_accel_abs_max", "goal_position_err_m", "goal_heading_err_rad",
    "duration_s", "wall_time_s", "planning_time_s", "progress_m",
    "replans", "replans_over_budget", "unsafe_steps", "replan_time_median_s",
    "replan_time_max_s",
)  # fmt: skip


def summarise(reports: Sequence[EpisodeReport]) -> dict[str, Any]:
    """Aggregate reports: success and collision rates, means and maxima of the errors.

    Parameters
    ----------
    reports : sequence of EpisodeReport
        One per seed (same scenario and controller).

    Returns
    -------
    dict
        ``episodes``, ``success_rate``, ``collisions_highway_env``,
        ``collisions_footprint``, ``outcomes`` (count per :data:`OUTCOMES`),
        ``collisions_at_fault``, ``ttc_below_bound`` (episodes with a TTC at or
        below nuPlan's 0.95 s), ``nuplan_comfortable`` (episodes judged comfortable),
        the minimum and median of ``ttc_min_s`` (over the episodes with a projected
        collision), ``min_distance_m`` and ``completion_time_s``, and for each metric
        of :data:`MEAN_FIELDS` its mean and max over the episodes that drove
        (``steps > 0``; a failed plan's zero duration is no drive). 95 % intervals as
        ``[low, high]`` (``None`` below two values): ``success_rate_ci95``
        (Wilson) and ``<metric>_ci95`` of each mean (bootstrap; Student's t for
        ``progress_m``).

    Examples
    --------
    >>> reports = [evaluate(run_episode("parking", seed=i)) for i in range(5)]  # doctest: +SKIP
    >>> s = summarise(reports)  # doctest: +SKIP
    >>> s["success_rate"], s["success_rate_ci95"]  # doctest: +SKIP
    (1.0, [0.566, 1.0])
    """
    n = len(reports)
    if n == 0:
        raise InputError("reports: need at least one report")
    rate = describe([float(r.success) for r in reports], rate=True)
    out: dict[str, Any] = {
        "episodes": n,
        "success_rate": sum(r.success for r in reports) / n,
        "success_rate_ci95": _ci(rate),
        "collisions_highway_env": sum(r.collision_highway_env for r in reports),
        "collisions_footprint": sum(r.collision_footprint for r in reports),
        "plan_failures": sum(r.status == "plan_failed" for r in reports),
        "outcomes": {o: sum(r.outcome == o for r in reports) for o in OUTCOMES},
        "collisions_at_fault": sum(r.collisions_at_fault for r in reports),
        "ttc_below_bound": sum(r.ttc_within_bound is False for r in reports),
        "nuplan_comfortable": sum(r.nuplan_comfortable is True for r in reports),
    }
    drove = [r for r in reports if r.steps > 0]
    for key in ("ttc_min_s", "min_distance_m", "completion_time_s"):
        st = describe(_present(drove, key))
        out[f"{key}_min"] = st.min if st.n else None
        out[f"{key}_median"] = st.median if st.n else None
    for key in MEAN_FIELDS:
        over = reports if key == "planning_time_s" else drove
        st = describe(_present(over, key), nonnegative=key not in SIGNED_FIELDS)
        out[f"{key}_mean"] = st.mean if st.n else None
        out[f"{key}_max"] = st.max if st.n else None
        out[f"{key}_ci95"] = _ci(st)
    return out


def _present(reports: Sequence[EpisodeReport], key: str) -> list[float]:
    """The values of ``key`` over the reports that have one."""
    return [float(getattr(r, key)) for r in reports if getattr(r, key) is not None]


def _ci(stat: Stat) -> list[float] | None:
    """``[low, high]`` of a 95 % interval, ``None`` when it is undefined (n < 2)."""
    if stat.n == 0 or stat.ci_low != stat.ci_low:  # NaN
        return None
    return [stat.ci_low, stat.ci_high]
