"""Where the ego may cut back in ahead of the lead car, and whether the oncoming lane lets it pass.

Used by the traffic re-planner (:class:`~rrtdrive.sim.traffic_driver.TrafficDriver`)
for the space-time planner's goal and for the pull-out manoeuvre's
(:mod:`rrtdrive.sim.pull_out`): one rule for both.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from rrtdrive.planning.spacetime import ArrivalTiming, Prediction, traffic_conflicts
from rrtdrive.sim.replanning import ReplanConfig
from rrtdrive.types import VehicleParams

__all__ = ["CutInRule"]


@dataclass(frozen=True)
class CutInRule:
    """The cut-in rule of one overtake-traffic scene.

    Parameters
    ----------
    config : ReplanConfig
        ``cut_in_gap_m``, ``cut_in_headway_s``, ``goal_slack_m``, the turning radius,
        the plan length and horizon, the safety margins.
    vehicle : VehicleParams
        The ego car.
    lead : object
        The lead car (highway-env vehicle: ``speed``, ``LENGTH``; read when asked,
        as it moves), the prediction's first vehicle.
    lane_y, lane_width : float
        The ego lane's centre line and width (the oncoming lane lies one width to +y).
    x_end : float
        The road's last usable x.
    """

    config: ReplanConfig
    vehicle: VehicleParams
    lead: Any
    lane_y: float
    lane_width: float
    x_end: float

    def need(self, lead_x: np.ndarray) -> np.ndarray:
        """Nearest rear-axle x of a cut-in with the lead's centre at ``lead_x``.

        The ego's rear bumper ``cut_in_gap_m`` plus ``cut_in_headway_s`` at the
        lead's speed ahead of the lead's front bumper.
        """
        cfg = self.config
        return (
            np.asarray(lead_x, dtype=float)
            + self.lead.LENGTH / 2.0
            + cfg.cut_in_gap_m
            + cfg.cut_in_headway_s * float(self.lead.speed)
            + self.vehicle.rear_overhang
        )

    def need_at(self, t: float, prediction: Prediction) -> float:
        """:meth:`need` for an arrival at ``t`` (the lead predicted a time margin later)."""
        t_check = np.array([t + float(self.config.safety.margin(t))])
        return float(self.need(prediction.poses_at(t_check)[0][:, 0])[0])

    def goal_x(
        self, timing: ArrivalTiming, x_start: float, prediction: Prediction, y_start: float
    ) -> float | None:
        """Nearest rear-axle x for the planner's cut-in: far enough ahead of the lead by then.

        At least as far as the lane changes still to drive from the stitch point
        (out and back, or back only from the oncoming lane) at the planner's turning
        radius, plus ``goal_slack_m``: behind a lead at walking pace the point just
        ahead of it left too little road, and no plan could be smoothed.
        """
        cfg = self.config
        xs = x_start + np.arange(12.0, cfg.max_plan_length_m + 1e-9, 1.0)
        pts = np.column_stack([xs, np.full(len(xs), self.lane_y)])
        _, t_hi = timing.band(pts)
        t_check = t_hi + cfg.safety.margin(t_hi)
        ok = xs >= self.need(prediction.poses_at(t_check)[0][:, 0])  # the lead is first
        if not ok.any():
            return None
        x = float(xs[int(np.argmax(ok))]) + cfg.goal_slack_m
        # An S of two arcs of the turning radius across the lane width d: 2 sqrt(R d - d^2/4).
        d, radius = self.lane_width, cfg.turning_radius_m
        s_curve = 2.0 * math.sqrt(max(radius * d - d * d / 4.0, 0.0))
        changes = 2 if abs(y_start - self.lane_y) < d / 2.0 else 1
        x = max(x, x_start + changes * s_curve + cfg.goal_slack_m)
        if x > x_start + cfg.max_plan_length_m or x > self.x_end - 20.0:
            return None
        _, t_goal = timing.band(np.array([[x, self.lane_y]]))
        if float(t_goal[0]) > cfg.horizon_s - 1.0:
            return None
        return x

    def gap_open(
        self, timing: ArrivalTiming, x_start: float, goal_x: float, prediction: Prediction
    ) -> bool:
        """A necessary condition for any overtake: the oncoming lane is free beside the lead.

        Where the lead car blocks the ego lane at the ego's nominal arrival times,
        the ego must be laterally clear of it, i.e. in the oncoming lane; if an
        oncoming car is predicted there and then, no plan can pass the checks.
        """
        if len(prediction) < 2:  # no oncoming car
            return True
        xs = np.arange(x_start, goal_x + 1e-9, 0.5)
        lane = np.column_stack([xs, np.full(len(xs), self.lane_y), np.zeros(len(xs))])
        t_lo, t_hi = timing.band(lane[:, :2])
        safety = self.config.safety
        blocked = traffic_conflicts(
            lane, t_lo, t_hi, prediction.select(np.array([0])), safety, self.vehicle, 0.5
        )
        if not blocked.any():
            return True
        out = lane[blocked].copy()
        out[:, 1] = self.lane_y + 0.7 * self.lane_width
        rest = prediction.select(np.arange(1, len(prediction)))
        hit = traffic_conflicts(
            out, t_lo[blocked], t_hi[blocked], rest, safety, self.vehicle, 0.5
        )
        return not bool(hit.any())
