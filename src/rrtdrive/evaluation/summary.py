"""``summarise(reports)``: aggregates of episode reports over seeds."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from rrtdrive.evaluation.report import OUTCOMES, EpisodeReport
from rrtdrive.types import InputError

__all__ = ["summarise"]


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
        below nuPlan's 0.95 s), the minimum and median of ``ttc_min_s``,
        ``min_distance_m`` and ``completion_time_s``, and for each error metric
        its mean (over the episodes that drove) and max.
    """
    n = len(reports)
    if n == 0:
        raise InputError("reports: need at least one report")
    out: dict[str, Any] = {
        "episodes": n,
        "success_rate": sum(r.success for r in reports) / n,
        "collisions_highway_env": sum(r.collision_highway_env for r in reports),
        "collisions_footprint": sum(r.collision_footprint for r in reports),
        "plan_failures": sum(r.status == "plan_failed" for r in reports),
        "outcomes": {o: sum(r.outcome == o for r in reports) for o in OUTCOMES},
        "collisions_at_fault": sum(r.collisions_at_fault for r in reports),
        "ttc_below_bound": sum(r.ttc_within_bound is False for r in reports),
    }
    for key in ("ttc_min_s", "min_distance_m", "completion_time_s"):
        vals = np.array([getattr(r, key) for r in reports if getattr(r, key) is not None], float)
        out[f"{key}_min"] = float(np.min(vals)) if len(vals) else None
        out[f"{key}_median"] = float(np.median(vals)) if len(vals) else None
    for key in (
        "cte_rms_m", "cte_max_m", "heading_err_rms_rad", "heading_err_max_rad",
        "executed_max_curvature", "executed_curvature_violation_share", "max_lateral_accel",
        "max_jerk", "max_steering_rate", "goal_position_err_m", "goal_heading_err_rad",
        "duration_s", "wall_time_s", "path_max_curvature", "progress_m",
        "replan_time_median_s", "replan_time_max_s",
    ):
        vals = np.array([getattr(r, key) for r in reports if getattr(r, key) is not None], float)
        out[f"{key}_mean"] = float(np.mean(vals)) if len(vals) else None
        out[f"{key}_max"] = float(np.max(vals)) if len(vals) else None
    return out
