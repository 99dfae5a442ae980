"""Receding-horizon re-planning in traffic: overtaking a moving car against oncoming traffic.

:class:`TrafficDriver` drives the ego of an ``overtake-traffic`` scene once per
simulation step. It is in one of two modes:

* ``follow`` - the reference is the centre line of the ego lane; the speed loop is
  capped by an IDM car-following law behind the lead car (:class:`IDMConfig`).
* ``overtake`` - the reference is a space-time plan: the improved RRT-Connect on
  a :class:`~rrtdrive.planning.spacetime.SpaceTimeChecker`, clear of the road edges
  and of every predicted vehicle at the ego's arrival times, from the ego's lane
  behind the lead car to its lane ahead of it.

**Re-planning.** At a fixed rate (``rate_hz``, 2-5 Hz) and whenever the current
plan fails its safety check (run every control step with fresh predictions),
the driver predicts the other vehicles (:mod:`rrtdrive.sim.prediction`), picks a
cut-in point ahead of the lead car's predicted position, and plans from a
*stitch point*: the pose on the current reference that the ego reaches once the
planning budget has elapsed. The new reference is the current one up to the
stitch point, then the plan, then the lane; so the controller sees a continuous
reference and never waits on the planner (a plan that took the whole budget
would take over exactly where this one does). A plan is accepted only when the
whole stitched reference, timed by the controller's own speed profile from the
ego's current speed, passes the space-time check up to the cut-in point and a
little beyond, within the prediction horizon. In ``overtake`` mode a new plan
replaces the current one only when the current one became unsafe or the new one
finishes at least ``improve_s`` sooner.

**No safe overtake.** When nothing passes, the ego keeps following (or keeps a
plan that is still safe) and tries again at the next cycle: an unchecked plan is
never driven. If a plan becomes unsafe while the body is still in the ego's own
lane, the driver abandons it and returns to following; once the body is in the
oncoming lane it re-plans every step until a safe plan is found.
"""

from __future__ import annotations

import bisect
import dataclasses
import logging
import math
import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rrtdrive.controllers import SpeedConfig, SpeedProfile, TrackingController, VehicleState
from rrtdrive.evaluation import overtake_complete
from rrtdrive.maps import Map
from rrtdrive.planning.base import cached_checker
from rrtdrive.planning.spacetime import (
    ArrivalTiming,
    Prediction,
    SafetyConfig,
    SpaceTimeProblem,
    SpaceTimeRRTConnect,
    traffic_conflicts,
)
from rrtdrive.sim.drivelog import DriveRecorder
from rrtdrive.sim.prediction import PREDICTORS, predict
from rrtdrive.types import (
    Budget,
    InputError,
    Path,
    Pose,
    require_finite,
    require_int,
    require_positive,
)
from rrtdrive.vehicle import footprint_corners

__all__ = [
    "IDMConfig",
    "ReplanConfig",
    "ReplanRecord",
    "TrafficLog",
    "TrafficDriver",
    "lane_path",
    "overtake_complete",
    "drive_traffic",
]

logger = logging.getLogger(__name__)

#: Sample spacing of lane paths and stitched references (metres).
SPACING = 0.25


@dataclass(frozen=True)
class IDMConfig:
    """The ego's car-following law behind a slower car (Treiber's IDM).

    ``a_idm = a (1 - (v / v0)^delta - (s* / s)^2)``, ``s* = s0 + v T + v dv / (2 sqrt(a b))``
    with ``s`` the bumper-to-bumper gap and ``dv`` the closing speed; it caps the
    speed loop's command while following.

    Parameters
    ----------
    accel : float
        ``a``, largest acceleration (m/s^2).
    comfort_decel : float
        ``b``, comfortable deceleration (m/s^2, positive).
    time_headway : float
        ``T``, desired time gap (s).
    min_gap : float
        ``s0``, gap at standstill (m).
    delta : float
        Free-road exponent.

    Examples
    --------
    >>> round(IDMConfig().accel_for(4.0, 11.0, 10.0, 0.0), 3)  # at the desired gap: about 0
    -0.009
    """

    accel: float = 1.5
    comfort_decel: float = 2.0
    time_headway: float = 1.5
    min_gap: float = 4.0
    delta: float = 4.0

    def __post_init__(self) -> None:
        for name in ("accel", "comfort_decel", "time_headway", "min_gap", "delta"):
            require_positive(f"idm.{name}", getattr(self, name))

    def accel_for(self, v: float, v0: float, gap: float, closing: float) -> float:
        """IDM acceleration at speed ``v`` (desired ``v0``), ``gap`` metres behind, ``closing``."""
        brake = 2.0 * math.sqrt(self.accel * self.comfort_decel)
        s_star = self.min_gap + max(0.0, v * self.time_headway + v * closing / brake)
        free = (max(v, 0.0) / v0) ** self.delta if v0 > 0 else 1.0
        return self.accel * (1.0 - free - (s_star / max(gap, 0.1)) ** 2)


@dataclass(frozen=True)
class ReplanConfig:
    """Settings of receding-horizon re-planning in traffic.

    Parameters
    ----------
    rate_hz : float
        Re-planning rate, 2-5 Hz.
    budget_s : float, optional
        Wall-time budget of one re-planning cycle (prediction, planning, checks);
        default one period, ``1 / rate_hz``. The tree growth stops at the budget;
        the stitch point lies where the ego will be when it has elapsed.
    max_iterations : int
        Tree-growth iterations per plan (the deterministic budget; the wall-time
        budget only binds on a slow machine).
    wall_limit : bool
        Hold each cycle to its wall-time budget: the tree growth stops at its share
        and every check fails at 90 % of the budget (the plan is then dropped, as
        one that came too late). Off, an episode depends on its seed only, however
        slow the machine (tests); on, no cycle overruns (experiments).
    postprocess_reserve : float
        Share of the cycle budget kept for the post-processing when ``wall_limit``.
    predictor : str
        ``"constant-velocity"`` or ``"lane-following"`` (:mod:`rrtdrive.sim.prediction`).
    speed_bound : bool
        Predict braked IDM cars at their target speed.
    horizon_s : float
        Prediction horizon; a plan must reach its check end within it.
    prediction_step : float
        Time step of the prediction grid.
    safety : SafetyConfig
        Space and time buffers of the space-time check.
    cut_in_gap_m : float
        At the cut-in point the ego's rear bumper is at least this far ahead of the
        lead car's predicted front bumper ...
    cut_in_headway_s : float
        ... plus this many seconds at the lead car's speed.
    goal_slack_m : float
        The plan's goal lies this far beyond the nearest admissible cut-in point
        (room for the lane change back).
    turning_radius_m : float
        Smallest turning radius of planned paths (a comfort bound; at least the
        car's own 6 m): with the speed profile's lateral-acceleration cap it sets
        the speed through the lane changes (30 m and 2 m/s^2: 7.7 m/s).
    complete_gap_m : float
        The overtake is complete when the ego is back in its lane, aligned with it
        (within 10 degrees) and its rear bumper this far ahead of the lead's front.
    check_beyond_m : float
        A plan is checked this far past its cut-in point.
    max_plan_length_m : float
        Farthest cut-in point considered ahead of the stitch point.
    improve_s : float
        A new plan replaces a safe current one only if it reaches its cut-in point
        this much sooner.
    lane_extension_m : float
        Length of lane appended after a plan (and of the follow reference).
    check_every : int
        The current plan's safety check runs every this many control steps.
    idm : IDMConfig
        Car following while in ``follow`` mode.
    planner_options : mapping
        Options of :class:`~rrtdrive.planning.spacetime.SpaceTimeRRTConnect`.
    """

    rate_hz: float = 4.0
    budget_s: float | None = None
    max_iterations: int = 1000
    wall_limit: bool = True
    postprocess_reserve: float = 0.4
    predictor: str = "constant-velocity"
    speed_bound: bool = True
    horizon_s: float = 12.0
    prediction_step: float = 0.1
    safety: SafetyConfig = field(default_factory=SafetyConfig)
    cut_in_gap_m: float = 4.0
    cut_in_headway_s: float = 1.0
    goal_slack_m: float = 8.0
    turning_radius_m: float = 30.0
    complete_gap_m: float = 2.0
    check_beyond_m: float = 10.0
    max_plan_length_m: float = 110.0
    improve_s: float = 0.5
    lane_extension_m: float = 200.0
    check_every: int = 1
    idm: IDMConfig = field(default_factory=IDMConfig)
    planner_options: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        require_finite("replan.rate_hz", self.rate_hz)
        if not 2.0 <= self.rate_hz <= 5.0:
            raise InputError(f"replan.rate_hz: must lie in [2, 5] Hz, got {self.rate_hz!r}")
        if self.budget_s is not None:
            require_positive("replan.budget_s", self.budget_s)
        require_int("replan.max_iterations", self.max_iterations)
        if not isinstance(self.wall_limit, bool):
            raise InputError(f"replan.wall_limit: expected true or false, got {self.wall_limit!r}")
        require_finite("replan.postprocess_reserve", self.postprocess_reserve)
        if not 0.0 <= self.postprocess_reserve < 1.0:
            raise InputError(
                f"replan.postprocess_reserve: must lie in [0, 1), got {self.postprocess_reserve!r}"
            )
        if self.predictor not in PREDICTORS:
            raise InputError(
                f"replan.predictor: unknown predictor {self.predictor!r}; "
                f"choose from {list(PREDICTORS)}"
            )
        for name in (
            "horizon_s", "prediction_step", "complete_gap_m", "max_plan_length_m",
            "lane_extension_m", "turning_radius_m",
        ):
            require_positive(f"replan.{name}", getattr(self, name))
        for name in (
            "cut_in_gap_m", "cut_in_headway_s", "check_beyond_m", "improve_s", "goal_slack_m"
        ):
            value = getattr(self, name)
            require_finite(f"replan.{name}", value)
            if value < 0:
                raise InputError(f"replan.{name}: must be >= 0, got {value!r}")
        if self.horizon_s < 2.0:
            raise InputError(f"replan.horizon_s: must be >= 2 s, got {self.horizon_s!r}")
        require_int("replan.check_every", self.check_every)
        if not isinstance(self.safety, SafetyConfig):
            raise InputError("replan.safety: expected a SafetyConfig")
        if not isinstance(self.idm, IDMConfig):
            raise InputError("replan.idm: expected an IDMConfig")
        # Unknown planner options raise here, not in the middle of an episode.
        SpaceTimeRRTConnect(**dict(self.planner_options))

    @property
    def period_s(self) -> float:
        """Time between periodic re-plans."""
        return 1.0 / self.rate_hz

    @property
    def cycle_budget_s(self) -> float:
        """Wall-time budget of one cycle."""
        return self.budget_s if self.budget_s is not None else self.period_s


@dataclass(frozen=True)
class ReplanRecord:
    """One re-planning cycle.

    Attributes
    ----------
    t : float
        Simulation time of the cycle.
    trigger : str
        ``"periodic"`` or ``"unsafe"`` (the current plan failed its check).
    mode : str
        Mode before the cycle (``"follow"`` or ``"overtake"``).
    outcome : str
        ``"overtake"`` (a new plan was accepted), ``"kept"`` (a safe plan was found
        but the current one kept), ``"no_goal"`` (no cut-in point within reach),
        ``"no_gap"`` (the oncoming lane is taken where the ego would have to be
        beside the lead car: no plan can exist, the planner did not run),
        ``"no_plan"`` (the planner found no safe path), ``"late"`` (the cycle's
        wall-time budget ran out before a plan was verified), ``"rejected"`` (its stitched
        reference failed the final check), ``"abandoned"`` (an unsafe plan was
        dropped for following), ``"unsafe_kept"`` (no alternative to an unsafe plan).
    wall_time_s : float
        Wall time of the whole cycle (prediction, goal, planning, checks).
    planning_time_s : float
        The planner's own wall time (0 when it did not run).
    iterations, nodes : int
        Tree-growth iterations and nodes.
    goal_x : float or None
        Cut-in point (rear axle x) aimed at.
    message : str
        The planner's message.
    deadline_hit : bool
        The planner ran into the cycle's deadline (outcome ``"late"``).
    """

    t: float
    trigger: str
    mode: str
    outcome: str
    wall_time_s: float
    planning_time_s: float
    iterations: int
    nodes: int
    goal_x: float | None
    message: str
    deadline_hit: bool = False


@dataclass(frozen=True, eq=False)
class TrafficLog:
    """What the re-planner did during an episode.

    Attributes
    ----------
    records : tuple of ReplanRecord
        Every re-planning cycle.
    references : tuple of (float, Path)
        Each reference the controller tracked and the time it took over.
    executed : Path
        The reference actually tracked: each reference up to where the next took
        over (continuous by the stitching).
    modes : tuple of (float, str)
        Mode changes (time, new mode).
    unsafe_steps : int
        Control steps at which the current plan failed its safety check.
    completion_time_s : float or None
        When the overtake was complete.
    config : ReplanConfig
        The settings.
    """

    records: tuple[ReplanRecord, ...]
    references: tuple[tuple[float, Path], ...]
    executed: Path
    modes: tuple[tuple[float, str], ...]
    unsafe_steps: int
    completion_time_s: float | None
    config: ReplanConfig

    def cycle_times(self) -> np.ndarray:
        """Wall time of every re-planning cycle, seconds."""
        return np.array([r.wall_time_s for r in self.records], dtype=float)

    def reference_at(self, t: float) -> Path:
        """The reference tracked at simulation time ``t``."""
        times = [tt for tt, _ in self.references]
        i = max(0, bisect.bisect_right(times, t + 1e-9) - 1)
        return self.references[i][1]


def lane_path(x0: float, x1: float, lane_y: float, spacing: float = SPACING) -> Path:
    """The centre line of a lane along +x from ``x0`` to ``x1`` (rear-axle samples).

    Examples
    --------
    >>> p = lane_path(0.0, 10.0, 44.0)
    >>> len(p), p.samples[-1].tolist()
    (41, [10.0, 44.0, 0.0, 0.0])
    """
    n = max(2, int(math.ceil((x1 - x0) / spacing - 1e-9)) + 1)
    xs = np.linspace(x0, x1, n)
    samples = np.column_stack([xs, np.full(n, lane_y), np.zeros(n), np.zeros(n)])
    return Path(samples, np.zeros((0, 2)))


class TrafficDriver:
    """Drives the ego of an ``overtake-traffic`` scene: follow, plan, overtake, re-plan.

    Parameters
    ----------
    env : gymnasium.Env
        A reset highway-env scene (:func:`rrtdrive.sim.scenes.build_env`).
    scenario : Scenario
        Its scenario (lane, lead car, road bounds).
    controller : TrackingController
        The path tracker (reset here).
    speed : SpeedConfig
        The controller's speed-profile settings (the planner times plans with them).
    config : ReplanConfig
        Re-planning settings.
    rng : numpy.random.Generator
        The planner's only source of randomness.
    """

    def __init__(
        self,
        env: Any,
        scenario: Any,
        controller: TrackingController,
        speed: SpeedConfig,
        config: ReplanConfig,
        rng: np.random.Generator,
    ) -> None:
        u = env.unwrapped
        self.road = u.road
        self.ego = u.vehicle
        self.scenario = scenario
        self.vehicle = scenario.vehicle
        self.others = [v for v in self.road.vehicles if v is not self.ego]
        self.lead = self.others[0] if scenario.lead is not None and self.others else None
        self.lane_y = float(scenario.lane_y)
        self.lane_width = float(scenario.lane_width)
        self.road_bounds = scenario.map.bounds
        self.controller = controller
        self.speed = speed
        self.config = config
        self.rng = rng
        options = {"max_postprocess_attempts": 2, "smoothing": {"max_rounds": 8}}
        options.update(config.planner_options)
        self.planner = SpaceTimeRRTConnect(**options)
        self.plan_vehicle = dataclasses.replace(
            self.vehicle,
            min_turning_radius=max(config.turning_radius_m, self.vehicle.min_turning_radius),
        )
        # The static part of every plan window (the road between its edges) is built
        # once here, like a map loaded before driving, not inside a planning cycle.
        _, ymin, _, ymax = self.road_bounds
        longest = config.max_plan_length_m + config.check_beyond_m + 45.0
        for length in np.arange(20.0, longest, 20.0):
            window = Map(
                "traffic-window", (0.0, ymin, float(length), ymax), (),
                Pose(5.0, self.lane_y, 0.0), Pose(float(length) - 5.0, self.lane_y, 0.0),
                self.plan_vehicle,
            )
            cached_checker(window).component_labels  # noqa: B018 - warm the cache
        self.mode = "follow"
        self.records: list[ReplanRecord] = []
        self.references: list[tuple[float, Path]] = []
        self.modes: list[tuple[float, str]] = []
        self.unsafe_steps = 0
        self._executed: list[np.ndarray] = []
        self._steps = 0
        self._next_replan = 0.0
        self._path: Path | None = None
        self._times: np.ndarray = np.zeros(0)
        self._check_end = 0
        self._goal_time = math.inf
        self._goal_s = math.inf

    # ------------------------------------------------------------------ helpers

    def _speed_tuple(self) -> tuple[float, float, float, float, float]:
        c = self.speed
        return (c.v_max, c.accel, c.decel, c.a_lat_max, c.v_launch)

    def _predict(self) -> Prediction:
        c = self.config
        return predict(self.others, c.predictor, c.horizon_s, c.prediction_step, c.speed_bound)

    def _set_mode(self, t: float, mode: str) -> None:
        if mode != self.mode or not self.modes:
            self.modes.append((t, mode))
        self.mode = mode

    def _switch(self, t: float, path: Path, cut_index: int) -> None:
        """Track ``path`` from now on (it starts at the ego's projection on the current one)."""
        if self._path is not None:
            self._executed.append(self.controller.projector.samples[:cut_index])  # type: ignore[union-attr]
        self._path = path
        self.references.append((t, path))
        self.controller.retarget(path, self.ego.speed)
        profile = self.controller.profile
        v = np.maximum(0.5 * (profile.v[1:] + profile.v[:-1]), 0.05)  # type: ignore[union-attr]
        self._times = np.concatenate([[0.0], np.cumsum(np.diff(profile.s) / v)])  # type: ignore[union-attr]
        self._proj_s = np.asarray(self.controller.projector.s)  # type: ignore[union-attr]

    def _projection(self) -> tuple[int, float]:
        """Index of the sample at or behind the ego's projection on the current path, and its s."""
        proj = self.controller.projector.project(self.ego.rear[0], self.ego.rear[1])  # type: ignore[union-attr]
        return proj.index, proj.s

    def _lead_gap(self) -> tuple[float, float] | None:
        """Bumper gap to, and closing speed on, the nearest same-direction car ahead in the lane."""
        x, y, yaw = self.ego.rear
        front = x + self.vehicle.front_extent * math.cos(yaw)
        ego_y = y + (self.vehicle.length / 2.0 - self.vehicle.rear_overhang) * math.sin(yaw)
        best: tuple[float, float] | None = None
        for v in self.others:
            if math.cos(v.heading - yaw) <= 0.0:
                continue  # oncoming
            if abs(v.position[1] - ego_y) > (self.vehicle.width + v.WIDTH) / 2.0 + 0.3:
                continue
            gap = v.position[0] - v.LENGTH / 2.0 - front
            if v.position[0] <= x or (best is not None and gap >= best[0]):
                continue
            best = (gap, self.ego.speed - v.speed * math.cos(v.heading - yaw))
        return best

    def _lane_reference(self, t: float) -> None:
        """Switch to the lane centre line from the ego's position on."""
        cut, _ = self._projection() if self._path is not None else (0, 0.0)
        x0 = self.ego.rear[0]
        x1 = min(x0 + self.config.lane_extension_m, self._x_end())
        self._switch(t, lane_path(x0, x1, self.lane_y), cut)
        self._check_end = 0
        self._goal_time = math.inf
        self._goal_s = math.inf

    def _x_end(self) -> float:
        return self.road_bounds[2] - 1.0

    # ------------------------------------------------------------------ public

    def start(self) -> None:
        """Start in ``follow`` mode on the lane centre line."""
        self.controller.reset(
            lane_path(self.ego.rear[0], self.ego.rear[0] + 1.0, self.lane_y), v_start=self.ego.speed
        )
        self._set_mode(0.0, "follow")
        self._lane_reference(0.0)
        self._executed.clear()

    def control(self, t: float) -> tuple[float, float]:
        """The ``(acceleration, steering)`` command for this simulation step at time ``t``."""
        cfg = self.config
        if t + 1e-9 >= self._next_replan:
            self._next_replan += cfg.period_s
            while self._next_replan <= t + 1e-9:
                self._next_replan += cfg.period_s
            self.replan(t, "periodic")
        elif self.mode == "overtake" and self._steps % cfg.check_every == 0:
            if not self.current_safe():
                self.unsafe_steps += 1
                self.replan(t, "unsafe")
        self._steps += 1
        if self.mode == "overtake":
            _, s_now = self._projection()
            if s_now >= self._goal_s:
                self._set_mode(t, "follow")  # back in the lane past the cut-in point
        if self.mode == "follow":
            _, s_now = self._projection()
            if self.controller.projector.length - s_now < 0.6 * cfg.lane_extension_m:  # type: ignore[union-attr]
                self._lane_reference(t)
        ego = self.ego
        cap = None
        if self.mode == "follow":
            lead = self._lead_gap()
            if lead is not None:
                cap = cfg.idm.accel_for(ego.speed, self.speed.v_max, lead[0], lead[1])
        self.controller.speed.accel_cap = cap
        r = ego.rear
        return self.controller.control(VehicleState(r[0], r[1], r[2], ego.speed, ego.steer, t))

    def finish(self, completion_time: float | None) -> TrafficLog:
        """The log of the episode (call once at the end)."""
        pieces = list(self._executed)
        if self._path is not None:
            i, _ = self._projection()
            pieces.append(self.controller.projector.samples[: i + 2])  # type: ignore[union-attr]
        samples = np.concatenate(pieces) if pieces else np.zeros((0, 4))
        if len(samples) > 1:
            keep = np.concatenate([[True], np.hypot(*np.diff(samples[:, :2], axis=0).T) > 1e-9])
            samples = samples[keep]
        return TrafficLog(
            tuple(self.records), tuple(self.references), Path(samples, np.zeros((0, 2))),
            tuple(self.modes), self.unsafe_steps, completion_time, self.config,
        )

    # ------------------------------------------------------------------ safety

    def _in_own_lane(self) -> bool:
        corners = footprint_corners(np.asarray(self.ego.rear, dtype=float), self.vehicle)
        return bool(np.all(corners[:, 1] <= self.lane_y + self.lane_width / 2.0))

    def current_safe(self, prediction: Prediction | None = None) -> bool:
        """True when the rest of the current plan (to its check end) is clear of the traffic."""
        if self._check_end <= 0 or self._path is None:
            return True
        i0, s_now = self._projection()
        if i0 >= self._check_end:
            return True
        t_now = float(np.interp(s_now, self._proj_s, self._times))
        samples = self.controller.projector.samples  # type: ignore[union-attr]
        idx = np.arange(i0, self._check_end + 1)
        times = self._times[idx] - t_now
        horizon = self.config.horizon_s
        keep = times <= horizon
        pred = prediction if prediction is not None else self._predict()
        hit = traffic_conflicts(
            samples[idx[keep], :3], times[keep], times[keep], pred, self.config.safety,
            self.vehicle, SPACING,
        )
        return not bool(hit.any())

    def _validate(
        self, path: Path, check_end: int, prediction: Prediction
    ) -> tuple[bool, float, str]:
        """Check a candidate reference (starting at the ego) timed by the controller's profile.

        Returns
        -------
        ok : bool
        t_end : float
            Seconds until the ego reaches sample ``check_end``.
        why : str
        """
        s = path.arc_length()
        profile = SpeedProfile(s, path.samples[:, 3], self.speed, self.ego.speed)
        v = np.maximum(0.5 * (profile.v[1:] + profile.v[:-1]), 0.05)
        times = np.concatenate([[0.0], np.cumsum(np.diff(s) / v)])
        if times[check_end] > self.config.horizon_s:
            return False, float(times[check_end]), "the plan ends beyond the prediction horizon"
        idx = np.arange(0, check_end + 1)
        hit = traffic_conflicts(
            path.samples[idx, :3], times[idx], times[idx], prediction, self.config.safety,
            self.vehicle, SPACING,
        )
        if hit.any():
            x, y = path.samples[int(np.flatnonzero(hit)[0]), :2]
            return False, float(times[check_end]), f"conflict at ({x:.1f}, {y:.1f})"
        return True, float(times[check_end]), ""

    # ------------------------------------------------------------------ planning

    def _cut_in_x(
        self, timing: ArrivalTiming, x_start: float, prediction: Prediction
    ) -> float | None:
        """Nearest rear-axle x for the cut-in: far enough ahead of the lead by then."""
        cfg = self.config
        xs = x_start + np.arange(12.0, cfg.max_plan_length_m + 1e-9, 1.0)
        if self.lead is None or len(prediction) == 0:
            return float(xs[min(len(xs) - 1, 18)])
        pts = np.column_stack([xs, np.full(len(xs), self.lane_y)])
        _, t_hi = timing.band(pts)
        t_check = t_hi + cfg.safety.margin(t_hi)
        lead = prediction.poses_at(t_check)[0]  # the lead is the first vehicle
        v_lead = float(self.lead.speed)
        need = (
            lead[:, 0]
            + self.lead.LENGTH / 2.0
            + cfg.cut_in_gap_m
            + cfg.cut_in_headway_s * v_lead
            + self.vehicle.rear_overhang
        )
        ok = xs >= need
        if not ok.any():
            return None
        x = float(xs[int(np.argmax(ok))]) + cfg.goal_slack_m
        if x > x_start + cfg.max_plan_length_m or x > self._x_end() - 20.0:
            return None
        _, t_goal = timing.band(np.array([[x, self.lane_y]]))
        if float(t_goal[0]) > cfg.horizon_s - 1.0:
            return None
        return x

    def _gap_open(
        self, timing: ArrivalTiming, x_start: float, goal_x: float, prediction: Prediction
    ) -> bool:
        """A necessary condition for any overtake: the oncoming lane is free beside the lead.

        Where the lead car blocks the ego lane at the ego's nominal arrival times,
        the ego must be laterally clear of it, i.e. in the oncoming lane; if an
        oncoming car is predicted there and then, no plan can pass the checks.
        """
        if self.lead is None or len(prediction) < 2:
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

    def replan(self, t: float, trigger: str) -> ReplanRecord:
        """One re-planning cycle at simulation time ``t``; returns (and logs) its record."""
        wall0 = time.perf_counter()
        cfg = self.config
        mode = self.mode
        pred = self._predict()
        current_ok = True
        if mode == "overtake":
            current_ok = trigger == "periodic" and self.current_safe(pred)
        i0, s_now = self._projection()
        ego = self.ego
        samples = self.controller.projector.samples  # type: ignore[union-attr]
        s_path = self._proj_s
        d_stitch = max(ego.speed * cfg.cycle_budget_s + 1.0, 1.5)
        i_stitch = min(int(np.searchsorted(s_path, s_now + d_stitch)), len(s_path) - 2)
        start = samples[i_stitch]
        timing = ArrivalTiming(
            0.0, float(ego.speed), self.speed.v_max, self.speed.accel,
            (float(ego.rear[0]), float(ego.rear[1])),
        )
        goal_x = self._cut_in_x(timing, float(start[0]), pred)
        outcome, message = "no_goal", "no cut-in point within reach"
        plan_time, iters, nodes = 0.0, 0, 0
        accepted = late = False
        if goal_x is not None and not self._gap_open(timing, float(start[0]), goal_x, pred):
            outcome, message = "no_gap", "the oncoming lane is taken beside the lead car"
        elif goal_x is not None:
            plan, message, cand = self._plan(i0, i_stitch, goal_x, timing, pred, wall0)
            plan_time = plan.wall_time_s if plan is not None else 0.0
            if plan is not None:
                iters, nodes = plan.result.iterations, plan.result.nodes
            if cand is None:
                outcome = "no_plan" if plan is None or not plan.success else "rejected"
                if plan is not None and plan.deadline_hit:
                    outcome, late = "late", True
            else:
                path, check_end, goal_index = cand
                ok, t_end, why = self._validate(path, check_end, pred)
                if not ok:
                    outcome, message = "rejected", why
                elif (
                    mode == "overtake"
                    and current_ok
                    and t + t_end > self._goal_time - cfg.improve_s
                ):
                    outcome = "kept"
                else:
                    self._switch(t, path, i0)
                    self._check_end = check_end
                    self._goal_time = t + t_end
                    self._goal_s = float(self._proj_s[min(goal_index, len(self._proj_s) - 1)])
                    self._set_mode(t, "overtake")
                    outcome, accepted = "overtake", True
        if not accepted and mode == "overtake" and not current_ok:
            if self._in_own_lane():
                self._set_mode(t, "follow")
                self._lane_reference(t)
                outcome = "abandoned"
            else:
                outcome = "unsafe_kept"
        record = ReplanRecord(
            t, trigger, mode, outcome, time.perf_counter() - wall0, plan_time, iters, nodes,
            goal_x, message, late,
        )
        self.records.append(record)
        logger.debug("replan t=%.2f %s %s -> %s (%s)", t, trigger, mode, outcome, message)
        return record

    def _plan(
        self,
        i0: int,
        i_stitch: int,
        goal_x: float,
        timing: ArrivalTiming,
        pred: Prediction,
        wall0: float,
    ) -> tuple[Any, str, tuple[Path, int, int] | None]:
        """Plan from the stitch sample ``i_stitch`` to the cut-in point; the stitched candidate.

        ``i0`` is the sample at the ego's projection: the candidate starts there.
        """
        cfg = self.config
        samples = self.controller.projector.samples  # type: ignore[union-attr]
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
            window, local, timing.shifted(-x_off), cfg.safety, self._speed_tuple()
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
            return plan, plan.result.message, None
        local_path = plan.result.path.samples.copy()
        local_path[:, 0] += x_off
        # Stitch: current reference from the ego to the stitch pose, the plan, then the lane.
        x_goal = float(local_path[-1, 0])
        lane = lane_path(
            x_goal, min(x_goal + cfg.lane_extension_m, self._x_end()), self.lane_y
        ).samples
        stitched = np.concatenate([samples[i0:i_stitch], local_path, lane[1:]])
        keep = np.concatenate([[True], np.hypot(*np.diff(stitched[:, :2], axis=0).T) > 1e-9])
        stitched = stitched[keep]
        path = Path(stitched, plan.result.path.waypoints + np.array([x_off, 0.0]))
        goal_index = (i_stitch - i0) + len(local_path) - 1
        s = path.arc_length()
        goal_index = min(goal_index, len(s) - 1)
        check_end = int(np.searchsorted(s, s[goal_index] + cfg.check_beyond_m))
        return plan, plan.result.message, (path, min(check_end, len(s) - 1), goal_index)


def drive_traffic(
    env: Any,
    scenario: Any,
    controller: TrackingController,
    speed: SpeedConfig,
    config: ReplanConfig,
    rng: np.random.Generator,
    max_time_s: float,
    stop_on_crash: bool = True,
) -> tuple[Any, TrafficLog, str]:
    """Drive an ``overtake-traffic`` scene with a :class:`TrafficDriver` until done.

    The loop is :func:`rrtdrive.sim.runner.drive`'s (the command is set, every
    vehicle acts, the physics steps, the state is logged), with the driver in
    place of a fixed path. It ends at the first crash, when the overtake is
    complete (:func:`overtake_complete`), or at the time limit.

    Returns
    -------
    log : DriveLog
    traffic : TrafficLog
    status : str
        ``"completed"``, ``"crashed"`` or ``"timeout"``.
    """
    u = env.unwrapped
    ego = u.vehicle
    dt = 1.0 / u.config["simulation_frequency"]
    driver = TrafficDriver(env, scenario, controller, speed, config, rng)
    driver.start()
    lead = driver.lead
    n_max = int(math.ceil(max_time_s / dt - 1e-9))
    rec = DriveRecorder(env, dt)
    status = "timeout"
    completion: float | None = None
    t = 0.0
    wall0 = time.perf_counter()
    plan_wall = 0.0
    for _ in range(n_max):
        n_rec = len(driver.records)
        c0 = time.perf_counter()
        accel, steer = driver.control(t)
        if len(driver.records) != n_rec:
            plan_wall += time.perf_counter() - c0
        rec.step(accel, steer)
        t += dt
        r = ego.rear
        if ego.crashed:
            status = "crashed"
            if stop_on_crash:
                break
        if lead is not None and overtake_complete(
            (r[0], r[1], r[2]), (lead.position[0], lead.position[1]), lead.LENGTH,
            driver.lane_y, driver.lane_width, driver.vehicle, config.complete_gap_m,
        ) and status != "crashed":
            status = "completed"
            completion = t
            break
    log = rec.log(status == "completed", time.perf_counter() - wall0 - plan_wall)
    return log, driver.finish(completion), status
