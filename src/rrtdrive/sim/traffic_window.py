"""The traffic re-planner's planning step: an overtake planned in a window of the road.

:class:`WindowPlanner` owns what every re-planning cycle of
:class:`~rrtdrive.sim.traffic_driver.TrafficDriver` plans with: the space-time
improved RRT-Connect (its smoothing held to the road's lane-change speed for a
rate-limited car), the planning car (turning no tighter than the road's
``turning_radius_m``) and the empty road windows, built once before driving.
:meth:`WindowPlanner.plan` plans from a stitch pose on the current reference to a
cut-in point in a window of the road around the two, shifted so that the window
starts near x = 0, and stitches the result into one reference: the current one up
to the stitch pose, the plan, then the lane.
"""

from __future__ import annotations

import dataclasses
import math
import re
import time
from collections.abc import Mapping
from typing import Any

import numpy as np

from rrtdrive.controllers import SpeedConfig
from rrtdrive.maps import Map
from rrtdrive.planning.base import cached_checker
from rrtdrive.planning.spacetime import (
    ArrivalTiming,
    Prediction,
    SpaceTimeProblem,
    SpaceTimeRRTConnect,
)
from rrtdrive.sim.replanning import ReplanConfig, lane_path
from rrtdrive.types import Budget, InputError, Path, Pose, VehicleParams

__all__ = ["Candidate", "WindowPlanner", "road_frame_message"]

#: A stitched reference ready for the safety check: ``(path, check_end, goal_index)``,
#: the rows to check up to and the row of the cut-in point.
Candidate = tuple[Path, int, int]


class WindowPlanner:
    """Plans an overtake's reference in a window of the road; built once per drive.

    Parameters
    ----------
    config : ReplanConfig
        Re-planning settings (planner options, turning radius, plan lengths, budgets).
    vehicle : VehicleParams
        The ego car.
    speed : SpeedConfig
        The controller's speed-profile settings (plans are timed with them).
    steering : tuple of float, or None
        ``(max_steer_rate, share)`` of the controller's actuator; ``None``: instant.
    road_bounds : tuple of float
        ``(xmin, ymin, xmax, ymax)`` of the road.
    lane_y : float
        The ego lane's centre line.
    rng : numpy.random.Generator
        The planner's only source of randomness.
    """

    def __init__(
        self,
        config: ReplanConfig,
        vehicle: VehicleParams,
        speed: SpeedConfig,
        steering: tuple[float, float] | None,
        road_bounds: tuple[float, float, float, float],
        lane_y: float,
        rng: np.random.Generator,
    ) -> None:
        self.config = config
        self.speed = speed
        self.steering = steering
        self.road_bounds = road_bounds
        self.lane_y = lane_y
        self.rng = rng
        smoothing: dict[str, Any] = {"max_rounds": 8}
        if steering is not None:
            # Plans a rate-limited car can drive at the road's lane-change speed: the
            # speed the lateral-acceleration cap allows on the tightest planned turn.
            v_turn = min(speed.v_max, math.sqrt(speed.a_lat_max * config.turning_radius_m))
            smoothing["max_sharpness"] = steering[0] * steering[1] / v_turn
        options: dict[str, Any] = {"max_postprocess_attempts": 2}
        user = dict(config.planner_options)
        given = user.pop("smoothing", None)
        if isinstance(given, Mapping):
            smoothing.update(given)
        options.update(user)
        options["smoothing"] = smoothing if given is None or isinstance(given, Mapping) else given
        self.planner = SpaceTimeRRTConnect(**options)
        self.plan_vehicle = dataclasses.replace(
            vehicle, min_turning_radius=max(config.turning_radius_m, vehicle.min_turning_radius)
        )
        # The static part of every plan window (the road between its edges) is built
        # once here, like a map loaded before driving, not inside a planning cycle.
        _, ymin, _, ymax = road_bounds
        longest = config.max_plan_length_m + config.check_beyond_m + 45.0
        for length in np.arange(20.0, longest, 20.0):
            window = Map(
                "traffic-window", (0.0, ymin, float(length), ymax), (),
                Pose(5.0, lane_y, 0.0), Pose(float(length) - 5.0, lane_y, 0.0),
                self.plan_vehicle,
            )
            cached_checker(window).component_labels  # noqa: B018 - warm the cache

    @property
    def x_end(self) -> float:
        """The farthest x a reference reaches: 1 m short of the road's end."""
        return self.road_bounds[2] - 1.0

    def speed_tuple(self) -> tuple[float, float, float, float, float]:
        """``(v_max, accel, decel, a_lat_max, v_launch)`` the planner times plans with."""
        c = self.speed
        # A rate-limited car starts from its own speed, no launch speed (actuator_profile).
        v_launch = c.v_launch if self.steering is None else 0.0
        return (c.v_max, c.accel, c.decel, c.a_lat_max, v_launch)

    def plan(
        self,
        samples: np.ndarray,
        i0: int,
        i_stitch: int,
        goal_x: float,
        timing: ArrivalTiming,
        pred: Prediction,
        wall0: float,
    ) -> tuple[Any, str, Candidate | None]:
        """Plan from row ``i_stitch`` of ``samples`` to the cut-in point; the stitched candidate.

        ``samples`` are the current reference's rows and ``i0`` the row at the ego's
        projection: the candidate starts there. ``wall0`` is when the cycle began
        (``time.perf_counter``): with ``config.wall_limit`` the tree's growth gets what
        is left of the cycle less the post-processing reserve.

        Returns
        -------
        plan : SpaceTimePlan or None
            The planner's answer (``None`` when no window could be built).
        message : str
            Its message, or why no window could be built.
        candidate : Candidate or None
            The stitched reference; ``None`` when the plan failed.
        """
        cfg = self.config
        start = samples[i_stitch]
        x_off = float(start[0]) - 5.0
        length = math.ceil((goal_x - x_off + cfg.check_beyond_m + 5.0) / 20.0) * 20.0
        _, ymin, _, ymax = self.road_bounds
        goal = Pose(goal_x - x_off, self.lane_y, 0.0)
        try:
            window = Map(
                "traffic-window", (0.0, ymin, length, ymax), (),
                Pose(float(start[0]) - x_off, float(start[1]), float(start[2])), goal,
                self.plan_vehicle,
            )
        except InputError as exc:
            return None, f"no plan window: {exc}", None
        local = pred.shifted(-x_off)
        if len(local):
            xr = local.x_range()
            near = (xr[:, 1] >= -20.0) & (xr[:, 0] <= length + 20.0)
            local = local.select(near)
        problem = SpaceTimeProblem(
            window, local, timing.shifted(-x_off), cfg.safety, self.speed_tuple(),
            steering=self.steering,
        )
        deadline = None
        left = 1e6
        if cfg.wall_limit:
            # Tree growth may use what is left of the cycle minus a reserve for the
            # post-processing; at the deadline every check fails, so that a long
            # post-processing gives up too, leaving a little time for the final check.
            spent = time.perf_counter() - wall0
            left = max(cfg.cycle_budget_s * (1.0 - cfg.postprocess_reserve) - spent, 1e-3)
            deadline = wall0 + 0.9 * cfg.cycle_budget_s
        problem = dataclasses.replace(problem, deadline=deadline)
        plan = self.planner.solve_spacetime(
            problem, self.rng, Budget(max_iterations=cfg.max_iterations, max_time_s=left)
        )
        if not plan.success:
            return plan, road_frame_message(plan.result.message, x_off), None
        local_path = plan.result.path.samples.copy()
        local_path[:, 0] += x_off
        # Stitch: current reference from the ego to the stitch pose, the plan, then the lane.
        x_goal = float(local_path[-1, 0])
        lane = lane_path(x_goal, min(x_goal + cfg.lane_extension_m, self.x_end), self.lane_y)
        stitched = np.concatenate([samples[i0:i_stitch], local_path, lane.samples[1:]])
        keep = np.concatenate([[True], np.hypot(*np.diff(stitched[:, :2], axis=0).T) > 1e-9])
        stitched = stitched[keep]
        path = Path(stitched, plan.result.path.waypoints + np.array([x_off, 0.0]))
        goal_index = (i_stitch - i0) + len(local_path) - 1
        s = path.arc_length()
        goal_index = min(goal_index, len(s) - 1)
        check_end = int(np.searchsorted(s, s[goal_index] + cfg.check_beyond_m))
        return plan, plan.result.message, (path, min(check_end, len(s) - 1), goal_index)


_POINT = re.compile(r"\((-?\d+(?:\.(\d+))?), (-?\d+(?:\.\d+)?)\)")


def road_frame_message(message: str, x_off: float) -> str:
    """A planner's message with its points ``(x, y)`` moved from the window's frame to the road's.

    The planner plans in a window shifted by ``-x_off`` along the road; its messages
    named a conflict at x = 22 with the car at x = 88 (an audit). Each point keeps its
    number of decimals.

    Examples
    --------
    >>> road_frame_message("traffic conflict at (22.1, 46.3) on the final check", 65.8)
    'traffic conflict at (87.9, 46.3) on the final check'
    """

    def shift(m: re.Match[str]) -> str:
        decimals = len(m.group(2) or "")
        return f"({float(m.group(1)) + x_off:.{decimals}f}, {m.group(3)})"

    return _POINT.sub(shift, message)
