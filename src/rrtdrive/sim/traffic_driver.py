"""The traffic re-planner: overtaking a moving car against oncoming traffic, re-planning as it goes.

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
cut-in point ahead of the lead car's predicted position, and plans (in a window of
the road, :mod:`rrtdrive.sim.traffic_window`) from a *stitch point*: the pose on
the current reference that the ego reaches once the planning budget has elapsed.
The new reference is the current one up to the stitch point, then the plan, then
the lane; so the controller sees a continuous reference and never waits on the
planner (a plan that took the whole budget would take over exactly where this one
does). A plan is accepted only when the
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

**A slow lead.** Behind a lead slower than ``pull_out_speed`` a cycle whose planner
found nothing tries the plain pull-out (:mod:`rrtdrive.sim.pull_out`), checked the
same way; the IDM law keeps room for it (``IDMConfig.pull_out_gap``).
"""

from __future__ import annotations

import logging
import math
import time
from typing import Any

import numpy as np

from rrtdrive.controllers import SpeedConfig, TrackingController, VehicleState
from rrtdrive.planning.spacetime import ArrivalTiming, Prediction, traffic_conflicts
from rrtdrive.sim.cut_in import CutInRule
from rrtdrive.sim.follower import lead_gap
from rrtdrive.sim.prediction import predict
from rrtdrive.sim.pull_out import inside_road, pull_out_candidate
from rrtdrive.sim.replanning import (
    SPACING,
    ReplanConfig,
    ReplanRecord,
    TrafficLog,
    lane_path,
    merge_path,
)
from rrtdrive.sim.traffic_window import WindowPlanner
from rrtdrive.speed_profile import actuator_profile
from rrtdrive.types import Path, PlanStatus
from rrtdrive.vehicle import footprint_corners

__all__ = ["TrafficDriver"]

logger = logging.getLogger(__name__)


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
        self.lead = self.others[0]  # the scene's first car (the task requires one)
        self.lane_y = float(scenario.lane_y)
        self.lane_width = float(scenario.lane_width)
        self.road_bounds = scenario.map.bounds
        self.controller = controller
        self.speed = speed
        self.config = config
        # The planner, its car and the road windows: built once, before driving.
        self.window = WindowPlanner(
            config, self.vehicle, speed, self._steering(), self.road_bounds, self.lane_y, rng
        )
        self.planner = self.window.planner
        self.cut_in = CutInRule(
            config, self.vehicle, self.lead, self.lane_y, self.lane_width, self._x_end()
        )
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
        #: Wall time of the control steps that ran a re-planning cycle (the loop
        #: reports its own wall time without it).
        self.planning_wall_s = 0.0

    # ------------------------------------------------------------------ helpers

    def _steering(self) -> tuple[float, float] | None:
        """``(max_steer_rate, share)`` of the controller's actuator; ``None``: instant."""
        rate = self.controller.steer_rate
        if rate is None or not math.isfinite(rate):
            return None
        return (float(rate), float(self.controller.speed_config.steer_rate_share))

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
        times = np.concatenate([[0.0], np.cumsum(np.diff(profile.s) / v)])  # type: ignore[union-attr]
        self._proj_s = np.asarray(self.controller.projector.s)  # type: ignore[union-attr]
        # The profile may have samples between the path's rows (rows farther apart than
        # its spacing): the times are read at the rows (the same numbers when none are).
        self._times = np.interp(self._proj_s, profile.s, times)  # type: ignore[union-attr]

    def _projection(self) -> tuple[int, float]:
        """Index of the sample at or behind the ego's projection on the current path, and its s."""
        proj = self.controller.projector.project(self.ego.rear[0], self.ego.rear[1])  # type: ignore[union-attr]
        return proj.index, proj.s

    def lead_gap(self) -> tuple[float, float] | None:
        """Bumper gap to, and closing speed on, the nearest same-direction car ahead in the lane.

        The gap measure of the driver's car-following cap (the gym env's reference
        speed reads it too); ``None`` without such a car.
        """
        return lead_gap(self.ego, self.others, self.vehicle)

    def _lane_reference(self, t: float, merge: bool = False) -> None:
        """Switch to the lane centre line from the ego's position on.

        ``merge``: join the line from the ego's pose and steering first
        (:func:`~rrtdrive.sim.replanning.merge_path`, ``start_merge_s``).
        """
        cut, _ = self._projection() if self._path is not None else (0, 0.0)
        x0 = self.ego.rear[0]
        x1 = min(x0 + self.config.lane_extension_m, self._x_end())
        cfg = self.config
        # A car turned across the road (a custom jitter) starts on the lane line.
        if merge and cfg.start_merge_s > 0.0 and abs(self.ego.rear[2]) < math.pi / 3:
            length = max(cfg.start_merge_min_m, cfg.start_merge_s * abs(self.ego.speed))
            kappa0 = math.tan(self.ego.steer) / self.vehicle.wheelbase
            path = merge_path(tuple(self.ego.rear), kappa0, length, x1, self.lane_y)
        else:
            path = lane_path(x0, x1, self.lane_y)
        self._switch(t, path, cut)
        self._check_end = 0
        self._goal_time = math.inf
        self._goal_s = math.inf

    def _x_end(self) -> float:
        return self.window.x_end

    # ------------------------------------------------------------------ public

    @property
    def path(self) -> Path | None:
        """The reference tracked now, the newest of :attr:`references` (``None`` before start)."""
        return self._path

    def start(self) -> None:
        """Start in ``follow`` mode on the lane centre line."""
        self.controller.reset(
            lane_path(self.ego.rear[0], self.ego.rear[0] + 1.0, self.lane_y), v_start=self.ego.speed
        )
        self._set_mode(0.0, "follow")
        self._lane_reference(0.0, merge=True)
        self._executed.clear()

    def command(self, t: float) -> tuple[float, float]:
        """:meth:`control`, timing the steps that re-plan (the loop's ``Driver`` API)."""
        n_rec = len(self.records)
        c0 = time.perf_counter()
        out = self.control(t)
        if len(self.records) != n_rec:
            self.planning_wall_s += time.perf_counter() - c0
        return out

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
            lead = self.lead_gap()
            if lead is not None:
                cap = cfg.idm.accel_for(ego.speed, self.speed.v_max, lead[0], lead[1])
        self.controller.cap_accel(cap)
        r = ego.rear
        return self.controller.control(VehicleState(r[0], r[1], r[2], ego.speed, ego.steer, t))

    def finish(self, completion_time: float | None) -> TrafficLog:
        """The log of the episode (call once at the end; ``completion_time`` of the overtake)."""
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

    def _times_on(self, path: Path) -> np.ndarray:
        """Seconds from now at each row of a reference starting at the ego."""
        s = path.arc_length()
        ctrl = self.controller
        # The profile the controller will drive on this path (with its steering-rate cap).
        profile = actuator_profile(
            s, path.samples[:, 3], ctrl.speed_config, self.ego.speed, ctrl.vehicle.wheelbase,
            ctrl.steer_rate,
        )
        v = np.maximum(0.5 * (profile.v[1:] + profile.v[:-1]), 0.05)
        return np.concatenate([[0.0], np.cumsum(np.diff(s) / v)])

    def _validate(
        self,
        path: Path,
        check_end: int,
        prediction: Prediction,
        horizon_end: int | None = None,
        band: tuple[float, float] = (0.0, 0.0),
        times: np.ndarray | None = None,
    ) -> tuple[bool, float, str]:
        """Check a candidate reference (starting at the ego) timed by the controller's profile.

        ``horizon_end``: the row that must be reached within the horizon (default
        ``check_end``); ``band``: each row is checked over ``[t - band[0], t + band[1]]``;
        ``times``: :meth:`_times_on` of ``path`` when the caller has them.

        Returns
        -------
        ok : bool
        t_end : float
            Seconds until the ego reaches sample ``check_end``.
        why : str
        """
        times = self._times_on(path) if times is None else times
        if times[check_end if horizon_end is None else horizon_end] > self.config.horizon_s:
            return False, float(times[check_end]), "the plan ends beyond the prediction horizon"
        idx = np.arange(0, check_end + 1)
        hit = traffic_conflicts(
            path.samples[idx, :3], times[idx] - band[0], times[idx] + band[1], prediction,
            self.config.safety, self.vehicle, SPACING,
        )
        if hit.any():
            x, y = path.samples[int(np.flatnonzero(hit)[0]), :2]
            return False, float(times[check_end]), f"conflict at ({x:.1f}, {y:.1f})"
        return True, float(times[check_end]), ""

    # ------------------------------------------------------------------ planning

    def replan(self, t: float, trigger: str) -> ReplanRecord:
        """One re-planning cycle at simulation time ``t``; returns (and logs) its record."""
        wall0 = time.perf_counter()
        cfg = self.config
        mode = self.mode
        pred = self._predict()
        current_ok = True
        if mode == "overtake":
            current_ok = trigger == "periodic" and self.current_safe(pred)
            if trigger == "periodic" and not current_ok:
                # The step's check failed here instead of in control(): it counts alike.
                self.unsafe_steps += 1
        i0, s_now = self._projection()
        ego = self.ego
        samples = self.controller.projector.samples  # type: ignore[union-attr]
        s_path = self._proj_s
        d_stitch = max(ego.speed * cfg.cycle_budget_s + 1.0, 1.5)
        i_stitch = min(int(np.searchsorted(s_path, s_now + d_stitch)), len(s_path) - 2)
        start = samples[i_stitch]
        timing = ArrivalTiming(
            0.0, max(float(ego.speed), 0.0), self.speed.v_max, self.speed.accel,
            (float(ego.rear[0]), float(ego.rear[1])),
        )
        goal_x = self.cut_in.goal_x(timing, float(start[0]), pred, float(start[1]))
        outcome, message = "no_goal", "no cut-in point within reach"
        plan_time, iters, nodes = 0.0, 0, 0
        accepted = late = False
        if goal_x is not None and not self.cut_in.gap_open(timing, float(start[0]), goal_x, pred):
            outcome, message = "no_gap", "the oncoming lane is taken beside the lead car"
        elif goal_x is not None:
            plan, message, cand = self.window.plan(
                samples, i0, i_stitch, goal_x, timing, pred, wall0
            )
            plan_time = plan.wall_time_s if plan is not None else 0.0
            if plan is not None:
                iters, nodes = plan.result.iterations, plan.result.nodes
            if cand is None:
                outcome = "no_plan" if plan is None or not plan.success else "rejected"
                # The 90 % deadline, or the wall-clock cap on the tree's growth (60 % of
                # the cycle): either way the cycle's time ran out (the cap had left no
                # trace: the cycle read as a plain no_plan).
                if plan is not None and (
                    plan.deadline_hit or plan.result.status is PlanStatus.TIMEOUT
                ):
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
                    self._accept(t, i0, (path, check_end, goal_index, t_end))
                    outcome, accepted = "overtake", True
        if (
            not accepted
            and mode == "follow"
            and float(self.lead.speed) < cfg.pull_out_speed
        ):
            # Held to the cycle like the tree's growth (it takes 15-25 ms).
            spent = time.perf_counter() - wall0
            if cfg.wall_limit and spent > cfg.cycle_budget_s * (1.0 - cfg.postprocess_reserve):
                cand, why = None, "no time left in the cycle"
            else:
                cand, why = self._pull_out(i0, i_stitch, pred)
            if cand is None:
                message = f"{message}; pull-out: {why}"
            else:
                self._accept(t, i0, cand)
                outcome, message, accepted = "overtake", "pull-out past the slow lead", True
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

    def _accept(self, t: float, i0: int, cand: tuple[Path, int, int, float]) -> None:
        """Drive a checked candidate ``(path, check_end, goal_index, t_end)`` from now on."""
        path, check_end, goal_index, t_end = cand
        self._switch(t, path, i0)
        self._check_end = check_end
        self._goal_time = t + t_end
        self._goal_s = float(self._proj_s[min(goal_index, len(self._proj_s) - 1)])
        self._set_mode(t, "overtake")

    def _pull_out(
        self, i0: int, i_stitch: int, pred: Prediction
    ) -> tuple[tuple[Path, int, int, float] | None, str]:
        """The plain overtake of a slow lead (:mod:`rrtdrive.sim.pull_out`), checked; or why not."""
        cfg = self.config
        samples = self.controller.projector.samples  # type: ignore[union-attr]
        start = samples[i_stitch]
        if abs(float(start[1]) - self.lane_y) >= self.lane_width / 2.0:
            return None, "not in the lane"
        found = pull_out_candidate(
            samples[i0:i_stitch], start, lane_y=self.lane_y,
            out_y=self.lane_y + self.lane_width, length=cfg.pull_out_length_m,
            max_length=cfg.max_plan_length_m, tail=cfg.lane_extension_m,
            x_end=self._x_end(), times_of=self._times_on,
            cut_in_x=lambda t: self.cut_in.need_at(t, pred),
        )
        if found is None:
            return None, "no cut-in point within reach"
        path, goal_index, times = found
        if float(np.abs(path.samples[:, 3]).max()) > self.vehicle.kappa_max:
            return None, "its lane changes are too sharp for the car"
        _, ymin, _, ymax = self.road_bounds
        if not inside_road(path, self.vehicle, ymin, ymax):
            return None, "it leaves the road"
        s = path.arc_length()
        check_end = min(int(np.searchsorted(s, s[goal_index] + cfg.check_beyond_m)), len(s) - 1)
        # Back in the lane within the horizon, checked on past it (from standstill the
        # manoeuvre takes longer). Loose timing (docs/traffic.md): the ego is past the
        # first row already, and the speed loop ramps up at the comfort jerk.
        _, s_now = self._projection()
        early = float(np.interp(s_now - self._proj_s[i0], s, times))
        speed = self.controller.speed_config
        late = speed.accel / speed.comfort_jerk
        ok, t_end, why = self._validate(
            path, check_end, pred, horizon_end=goal_index, band=(early, late), times=times
        )
        if not ok:
            return None, why
        return (path, check_end, goal_index, t_end), ""
