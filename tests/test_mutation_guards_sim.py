"""Guards against mutants that survived the suite: speed profile, its peaks, and the sim loop.

Each test checks a rule a user sees (a plateau before braking, a stop at the goal, a
gear, a crash) against an independent reference: a property stated in the docstrings,
closed-form kinematics, or highway-env's own judgement.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from fractions import Fraction
from typing import Any

import gymnasium as gym
import highway_env  # noqa: F401 - registers the stock environments
import numpy as np
import pytest
import shapely
from highway_env.road.lane import LineType, StraightLane
from highway_env.road.road import Road, RoadNetwork
from highway_env.vehicle.kinematics import Vehicle
from highway_env.vehicle.objects import Obstacle as HwObstacle
from hypothesis import given, settings
from hypothesis import strategies as st

from rrtdrive.controllers import SpeedConfig, make_controller
from rrtdrive.sim import limits
from rrtdrive.sim.ego import EgoVehicle
from rrtdrive.sim.episode import EpisodeStatus, driven_gears
from rrtdrive.sim.extract import attach_ego, lane_line_obstacles, map_from_env
from rrtdrive.sim.loop import STOP_AT_PATH_END, EpisodeLoop, PathTracker, StopAtGoal
from rrtdrive.sim.pair_screen import pairs_to_handle
from rrtdrive.sim.prediction import predict
from rrtdrive.sim.pull_out import inside_road, pull_out_candidate, pull_out_path
from rrtdrive.sim.replanning import ReplanConfig, TrafficLog, lane_path, merge_path
from rrtdrive.sim.runner import run_episode
from rrtdrive.sim.scenes import OncomingCar, build_env
from rrtdrive.sim.tasks import make_scenario
from rrtdrive.speed_peaks import last_rise_level, plateau_caps
from rrtdrive.speed_profile import (
    FINAL_APPROACH_M,
    SpeedProfile,
    actuator_profile,
    steering_rate_speed_cap,
)
from rrtdrive.types import Path, Pose, VehicleParams

# --------------------------------------------------------------------------- helpers


def _peaks(s: np.ndarray, v: np.ndarray) -> list[tuple[int, int]]:
    """Runs ``v[i..j]`` of equal speeds with lower samples on both sides."""
    out, i = [], 1
    while i < len(v) - 1:
        j = i
        while j + 1 < len(v) and abs(v[j + 1] - v[i]) <= 1e-9:
            j += 1
        if v[i - 1] < v[i] - 1e-9 and j + 1 < len(v) and v[j + 1] < v[i] - 1e-9:
            out.append((i, j))
        i = j + 1
    return out


def _held_after(s: np.ndarray, v: np.ndarray, start: int, level: float) -> float:
    """Length (m) of the run of samples from ``start`` on whose speed reaches ``level``."""
    idx = np.flatnonzero(v[start:] >= level - 1e-9) + start
    assert len(idx), "no sample reaches the level"
    run = idx[: int(np.argmax(np.diff(idx) > 1)) + 1] if np.any(np.diff(idx) > 1) else idx
    return float(s[run[-1]] - s[run[0]])


# --------------------------------------------------------------------------- speed_profile


@settings(max_examples=60, deadline=None)
@given(a=st.floats(0.0, 30.0), b=st.floats(0.0, 30.0))
def test_peak_is_the_highest_reference_speed_on_the_stretch(a: float, b: float) -> None:
    """``SpeedProfile.peak`` equals the maximum of ``at`` over a dense grid of the stretch."""
    s = np.linspace(0.0, 30.0, 121)
    cap = np.where((s > 8.0) & (s < 12.0), 0.8, 3.0)  # a slow stretch between two fast ones
    prof = SpeedProfile(s, np.zeros_like(s), SpeedConfig(), 0.0, v_cap=cap)
    s0, s1 = min(a, b), max(a, b)
    grid = np.concatenate([np.linspace(s0, s1, 2001), s[(s >= s0) & (s <= s1)]])
    reference = max(prof.at(float(x))[0] for x in grid)
    assert prof.peak(s0, s1) == pytest.approx(reference, abs=1e-12)


def test_a_segment_that_brakes_slower_than_it_speeds_up_keeps_its_plateau() -> None:
    """A gear segment's peak holds ``(accel + decel) / jerk`` s when ``decel < accel``.

    The segment rises at ``accel`` over ``v^2 / (2 accel)`` and brakes at ``decel`` over
    ``v^2 / (2 decel)``; what is left of its length at the top speed ``v`` is the plateau,
    which the jerk-limited loop needs to last ``v * swing / jerk`` metres. (The peak
    computed as if it braked at ``accel`` left 0.19 m of the needed 1.9 m.)
    """
    cfg = SpeedConfig(accel=2.0, decel=0.5)
    s = np.linspace(0.0, 3.0, 61)
    prof = actuator_profile(s, np.zeros_like(s), cfg, 0.0, 2.51, 0.4, rise_to_peak=True)
    top = float(prof.v.max())
    lag = (cfg.accel + cfg.decel) / cfg.comfort_jerk
    held = s[prof.v >= top - 1e-9]
    assert held[-1] - held[0] >= top * lag - 1e-9
    # The profile's own bounds: v^2 rises by at most 2 accel per metre, falls by 2 decel.
    dv2 = np.diff(prof.v**2) / np.diff(s)
    assert dv2.max() <= 2 * cfg.accel + 1e-9 and dv2.min() >= -2 * cfg.decel - 1e-9


@pytest.mark.parametrize("straight", [3.0, 5.0, 8.0])
def test_every_peak_lasts_the_swing_into_braking_when_braking_is_harder(straight: float) -> None:
    """With ``decel > accel`` each peak still lasts ``decel / comfort_jerk`` seconds.

    The swing from holding a speed to braking at ``decel`` takes ``decel / jerk`` s (not
    ``accel / jerk``): a plateau sized for the speeding up was four times too short.
    """
    cfg = SpeedConfig(accel=0.5, decel=2.0)
    s = np.arange(0.0, straight + 30.0 + 1e-9, 0.25)
    kappa = np.where(s > straight, 1.0 / 6.0, 0.0)  # a curvature step: a slow stretch
    v = actuator_profile(s, kappa, cfg, 0.0, 2.51, 0.4).v
    peaks = _peaks(s, v)
    assert len(peaks) == 2
    for i, j in peaks:
        assert s[j] - s[i] >= v[i] * cfg.decel / cfg.comfort_jerk - 1e-6


@pytest.mark.parametrize("where", [1.9, 1.6, 1.2])
def test_a_rate_limited_profile_does_not_speed_up_in_the_final_approach(where: float) -> None:
    """Within ``FINAL_APPROACH_M`` of the end a rate-limited car's reference never rises.

    A short curvature bump ``where`` metres before the end makes the steering-rate cap
    dip there; the plain rules would speed up again after it and brake at once.
    """
    cfg = SpeedConfig()
    s = np.arange(0.0, 12.0 + 1e-9, 0.05)
    kappa = np.where(np.abs(s - (12.0 - where)) < 0.1, 0.15, 0.0)
    cap = steering_rate_speed_cap(s, kappa, 2.51, 0.4, cfg.steer_rate_share)
    plain = SpeedProfile(s, kappa, dataclasses.replace(cfg, v_launch=0.0), 0.0, v_cap=cap).v
    final = s > s[-1] - FINAL_APPROACH_M
    assert np.diff(plain[final]).max() > 0.1  # the plain rules do rise again
    prof = actuator_profile(s, kappa, cfg, 0.0, 2.51, 0.4)
    assert np.diff(prof.v[final]).max() <= 1e-12
    assert np.all(prof.v <= cap + 1e-12)


# --------------------------------------------------------------------------- speed_peaks


def _check_rise_cap(s: np.ndarray, v: np.ndarray, lag: float) -> tuple[int, float]:
    """``last_rise_level``, checked: a plateau of ``lag`` s, never below the trough."""
    found = last_rise_level(s, v, lag, 1.0)
    assert found is not None
    trough, cap = found
    assert cap >= v[trough] - 1e-12  # never below the trough's own speed
    capped = v.copy()
    capped[trough:] = np.minimum(capped[trough:], cap)
    if cap > v[trough] + 1e-9:  # a lowered peak: it holds lag seconds at its level
        assert _held_after(s, capped, trough, cap) >= cap * lag - 1e-9
    return trough, cap


def test_a_last_plateau_shorter_than_its_speed_times_the_lag_is_lowered() -> None:
    """1.5 m at 2.5 m/s lasts 0.6 s, not the 1 s swing: the peak must come down.

    (Compared with ``lag`` in seconds instead of ``v * lag`` in metres, 1.5 m passed.)
    """
    s = np.arange(0.0, 9.0 + 1e-9, 0.25)
    v = np.interp(s, [0.0, 2.0, 3.0, 5.0, 6.5, 9.0], [0.0, 2.0, 1.0, 2.5, 2.5, 0.0])
    trough, cap = _check_rise_cap(s, v, 1.0)
    assert s[trough] == 3.0 and cap < 2.5


def test_a_rise_too_short_for_any_plateau_is_held_at_the_trough_speed() -> None:
    """The cap of a last rise is never below its trough: there the rest is held (docstring).

    Nothing before the rise is higher than its peak, so the search for a level may go on
    below the trough (0.8 m/s); even 0.8 m/s does not last the 5 s asked for.
    """
    s = np.arange(0.0, 6.0 + 1e-9, 0.25)
    v = np.interp(s, [0.0, 2.0, 3.0, 3.5, 4.0, 6.0], [0.0, 1.0, 0.8, 1.4, 1.4, 0.0])
    trough, cap = _check_rise_cap(s, v, 5.0)
    assert s[trough] == 3.0 and cap == pytest.approx(0.8, abs=1e-12)


def test_a_rise_after_a_level_start_is_a_last_rise() -> None:
    """A moving car held level from its first sample, then a short rise and the stop.

    The level stretch is the slow stretch (its last sample the trough), not a start from
    rest: the rise must still end in a plateau the loop can turn into the stop.
    """
    s = np.arange(0.0, 7.0 + 1e-9, 0.25)
    v = np.interp(s, [0.0, 2.0, 3.5, 4.0, 7.0], [1.0, 1.0, 2.2, 2.2, 0.0])
    trough, cap = _check_rise_cap(s, v, 1.0)
    assert s[trough] == 2.0 and 1.0 < cap < 2.2


def test_a_peak_whose_stretch_reaches_the_first_sample_is_left_alone() -> None:
    """A moving car's first peak: lowering it would brake the car at once (docstring)."""
    s = np.arange(0.0, 4.0 + 1e-9, 0.25)
    v = np.interp(s, [0.0, 0.5, 1.5, 4.0], [1.8, 2.0, 1.0, 0.0])
    assert np.all(np.isinf(plateau_caps(s, v, 2.0)))


def test_two_last_peaks_of_the_same_height_share_one_plateau() -> None:
    """Two equal last peaks with a shallow dip between are one stretch, lowered as a whole.

    Only the last peak is capped (a moving car, ``last_only``); the one before it is not
    higher, so it is no shoulder of it: the level is where the merged stretch ``v >= c``
    lasts ``lag`` seconds, and the capped profile's last peak holds that long.
    """
    s = np.arange(0.0, 8.0 + 1e-9, 0.25)
    v = np.interp(s, [0.0, 2.0, 2.5, 3.0, 3.5, 4.0, 8.0], [0.0, 2.0, 2.0, 1.9, 2.0, 2.0, 0.0])
    lag = 2.0
    capped = np.minimum(v, plateau_caps(s, v, lag, last_only=True))
    i, j = _peaks(s, capped)[-1]
    assert s[j] - s[i] >= capped[i] * lag - 1e-9


# --------------------------------------------------------------------------- sim.loop


def _overtake_tracker(length: float) -> tuple[Any, Any, PathTracker]:
    """The overtake scene, and an LQR tracker on a straight lane path of ``length`` m."""
    task = make_scenario("overtake", 0, jitter=(0.0, 0.0, 0.0))
    env = build_env(task)
    x = np.arange(task.start.x, task.start.x + length, 0.1)
    path = Path(np.column_stack([x, np.full_like(x, task.lane_y), 0 * x, 0 * x]), np.zeros((0, 2)))
    ctrl = make_controller("lqr", vehicle=task.vehicle, speed=SpeedConfig(v_max=task.v_max))
    return task, env, PathTracker(env, ctrl, path)


def test_an_arrived_episode_ends_with_the_car_standing_still() -> None:
    """``ARRIVED`` means the controller arrived and the car's speed is exactly 0.

    A car placed 1 cm before its path's end, creeping at 5 mm/s: the controller says it
    arrived at once (within its stop distance, below its stop speed), but its first
    command (no step time yet) only slows the car; the episode ends a step later, at rest.
    """
    task, env, tracker = _overtake_tracker(4.0)
    try:
        end = tracker.path.samples[-1]
        tracker.ego.set_pose(Pose(float(end[0]) - 0.01, float(end[1]), 0.0), speed=0.005)
        loop = EpisodeLoop(env, tracker, STOP_AT_PATH_END, 5.0)
        log = loop.run()
    finally:
        env.close()
    assert loop.status is EpisodeStatus.ARRIVED and log.arrived
    assert loop.ego.speed == 0.0 and log.states[-1, 3] == 0.0
    # Creeping at 5 mm/s and braking, it cannot have gone a centimetre.
    assert abs(log.states[-1, 0] - float(end[0])) < 0.01


def test_a_moving_car_is_tracked_from_its_own_speed() -> None:
    """A car already moving at 3 m/s speeds up from there: it is not braked to launch speed.

    The overtake task caps the speed at 8 m/s; on a 30 m straight from 3 m/s the profile
    rises at 1 m/s^2 from 3 m/s, so over the first second the car never slows down.
    Tracked as from rest, its reference would start at the 0.5 m/s launch speed.
    """
    task, env, tracker = _overtake_tracker(30.0)
    try:
        tracker.ego.set_pose(task.start, speed=3.0)
        loop = EpisodeLoop(env, tracker, STOP_AT_PATH_END, 1.0)
        log = loop.run()
    finally:
        env.close()
    assert task.v_max > 3.0
    assert np.all(np.diff(log.states[:, 3]) >= 0.0) and np.all(log.controls[:, 0] >= 0.0)


@pytest.mark.parametrize("yaw_error", [0.5, -0.5, math.pi])
def test_stop_at_goal_needs_the_heading_and_a_standstill_in_either_gear(yaw_error: float) -> None:
    """A car at rest on the goal position but turned away is not at the goal."""
    task = make_scenario("overtake", 0, jitter=(0.0, 0.0, 0.0))
    rule = StopAtGoal(task.goal, 0.5, 0.2, 0.1)
    env = build_env(task)
    try:
        ego = env.unwrapped.vehicle
        goal = task.goal
        ego.set_pose(Pose(goal.x, goal.y, goal.yaw + yaw_error), speed=0.0)
        assert not rule.reached(ego, None)
        ego.set_pose(Pose(goal.x, goal.y, goal.yaw + 0.15), speed=0.0)  # within 0.2 rad
        assert rule.reached(ego, None)
        # Standing still means |speed| <= 0.1 m/s in either gear: backing through the goal
        # at 0.5 m/s is not a stop there.
        ego.set_pose(goal, speed=-0.5)
        assert not rule.reached(ego, None)
        ego.set_pose(goal, speed=-0.05)
        assert rule.reached(ego, None)
    finally:
        env.close()


def _drive_into_the_stopped_car(stop_on_crash: bool, max_time: float = 12.0) -> Any:
    """The overtake scene's ego on a straight path through the stopped car at x = 50 m."""
    task, env, tracker = _overtake_tracker(60.0)
    try:
        loop = EpisodeLoop(env, tracker, STOP_AT_PATH_END, max_time, stop_on_crash=stop_on_crash)
        log = loop.run()
    finally:
        env.close()
    return loop, log


def test_a_crash_ends_the_episode_only_when_asked_and_brakes_the_car_straight() -> None:
    """``stop_on_crash`` ends at the first crash; without it the crashed car brakes, unsteered.

    After a crash the ego's command is replaced by ``a = -v`` and no steering: over a step
    of ``dt`` the speed falls linearly, ``v1 = v0 (1 - dt)``.
    """
    loop, log = _drive_into_the_stopped_car(True)
    first = int(np.argmax(log.crashed))
    assert loop.status is EpisodeStatus.CRASHED and not log.arrived
    assert log.crashed[-1] and first == len(log.crashed) - 1  # ended at the first crash
    with pytest.raises(RuntimeError, match="already ended"):
        loop.stop(EpisodeStatus.OFF_PATH, "a caller's rule may not override a crash")
    on, log_on = _drive_into_the_stopped_car(False, max_time=first * loop.dt + 1.0)
    assert on.status is EpisodeStatus.CRASHED and not log_on.arrived
    assert log_on.steps == on.max_steps > first + 10  # it went on to the time limit
    assert np.all(log_on.crashed[first:])
    v = log_on.states[first:, 3]
    assert v[0] > 0.5
    assert v[1:] == pytest.approx(v[:-1] * (1.0 - loop.dt), rel=1e-9, abs=1e-12)
    assert np.all(log_on.states[first:, 2] == log_on.states[first, 2])  # heading held


@pytest.mark.parametrize("stop_on_crash", [True, False])
def test_a_crash_at_the_goal_is_a_crash(stop_on_crash: bool) -> None:
    """A car that stands at its path's end but inside the stopped car has crashed, not arrived."""
    task, env, tracker = _overtake_tracker(4.0)
    try:
        # A 0.1 m path whose end lies inside the stopped car's body (centre x = 50 m).
        x = np.array([47.5, 47.6])
        tracker.path = Path(np.column_stack([x, [44.0, 44.0], [0.0, 0.0], [0.0, 0.0]]),
                            np.zeros((0, 2)))  # fmt: skip
        tracker.ego.set_pose(Pose(47.6, 44.0, 0.0), speed=0.0)
        loop = EpisodeLoop(env, tracker, STOP_AT_PATH_END, 0.2, stop_on_crash=stop_on_crash)
        log = loop.run()
    finally:
        env.close()
    assert log.crashed[-1] and loop.status is EpisodeStatus.CRASHED
    if stop_on_crash:  # ended by the crash: the end rule was not asked
        assert not log.arrived


@pytest.mark.parametrize("max_time", [0.51, 0.5, 0.05, 0.049])
def test_the_time_limit_is_the_first_step_that_reaches_it(max_time: float) -> None:
    """A timed-out episode runs the fewest 20 Hz steps whose time reaches ``max_time``.

    Reference in exact arithmetic: the smallest ``n`` with ``n / 20 >= max_time`` (the
    decimal limit read as the fraction it names, so 0.5 s is 10 steps and 0.51 s is 11).
    """
    task, env, tracker = _overtake_tracker(60.0)
    try:
        loop = EpisodeLoop(env, tracker, STOP_AT_PATH_END, max_time)
        log = loop.run()
    finally:
        env.close()
    limit = Fraction(str(max_time))
    n = 1
    while Fraction(n, 20) < limit:
        n += 1
    assert loop.status is EpisodeStatus.TIMEOUT and log.steps == n


# --------------------------------------------------------------------------- sim.ego


def _bare_road() -> Road:
    net = RoadNetwork()
    net.add_lane("a", "b", StraightLane([-200.0, 0.0], [200.0, 0.0]))
    return Road(net, np_random=np.random.RandomState(0))


@pytest.mark.parametrize("command", [math.radians(60.0), -math.radians(60.0), -2.0])
def test_steering_is_clipped_to_full_lock_on_both_sides(command: float) -> None:
    """A command past full lock steers at full lock: the arc has curvature ``tan(30 deg) / L``.

    At speed ``v`` for ``dt`` with the wheels at ``delta`` the rear axle turns by
    ``v dt tan(delta) / L`` (the bicycle's yaw rate times the step).
    """
    road = _bare_road()
    params = VehicleParams(max_steer_rate=None)  # an instant actuator: at lock within the step
    ego = EgoVehicle(road, Pose(0.0, 0.0, 0.0), speed=2.0, vehicle=params)
    road.vehicles.append(ego)
    ego.act({"acceleration": 0.0, "steering": command})
    road.step(0.05)
    lock = math.copysign(params.max_steer, command)
    assert ego.steer == pytest.approx(lock)
    assert ego.rear[2] == pytest.approx(2.0 * 0.05 * math.tan(lock) / params.wheelbase, rel=1e-9)


@pytest.mark.parametrize("v0, accel", [(39.9, 10.0), (-9.9, -10.0)])
def test_speed_is_held_within_the_forward_and_reverse_limits(v0: float, accel: float) -> None:
    """The speed saturates at +40 m/s forward and -10 m/s in reverse (``sim.limits``).

    Over the step the speed rises linearly to the limit and stays there, so the car
    covers the mean of its end speeds, ``0.5 (v0 + v1) dt``.
    """
    road = _bare_road()
    ego = EgoVehicle(road, Pose(0.0, 0.0, 0.0), speed=v0)
    road.vehicles.append(ego)
    dt = 0.05
    ego.act({"acceleration": accel, "steering": 0.0})
    road.step(dt)
    limit = limits.MAX_SPEED if accel > 0 else -limits.MAX_REVERSE_SPEED
    assert ego.speed == limit
    assert ego.rear[0] == pytest.approx(0.5 * (v0 + limit) * dt, rel=1e-12)
    road.step(dt)
    assert ego.speed == limit


def test_backing_fast_past_a_corner_is_flagged_before_the_bodies_overlap() -> None:
    """Reversing at 10 m/s with a parked car's corner 0.3 m behind and 0.1 m across.

    The two bodies meet corner to corner, where their centres are farther apart than
    half the sum of their diagonals less ``|v| dt``: the pre-check must widen its circles
    by ``|v| dt`` in reverse or it misses the contact. Judged with shapely: the crash is
    flagged no later than the first step whose bodies intersect.
    """
    road = _bare_road()
    params = VehicleParams()
    other = Vehicle(road, [0.0, 0.0], heading=0.0, speed=0.0)
    other.LENGTH, other.WIDTH = params.length, params.width
    other.diagonal = math.hypot(params.length, params.width)
    centre = np.array([params.length + 0.3, params.width - 0.1])
    rear = centre[0] - (params.length / 2.0 - params.rear_overhang)
    ego = EgoVehicle(road, Pose(float(rear), float(centre[1]), 0.0), speed=-10.0, vehicle=params)
    road.vehicles.extend([ego, other])
    dt = 0.05
    first_overlap = None
    for k in range(6):
        ego.act({"acceleration": 0.0, "steering": 0.0})
        road.step(dt)
        body = shapely.Polygon(ego.polygon()[:4])
        if first_overlap is None and body.intersection(shapely.Polygon(other.polygon()[:4])).area:
            first_overlap = k
        if ego.crashed:
            break
    assert first_overlap is not None and ego.crashed and k <= first_overlap


def test_a_contact_predicted_within_the_step_is_a_crash_even_if_the_car_then_stops() -> None:
    """highway-env's judge: an intersection predicted within ``dt`` counts as a crash.

    The ego, at 5 m/s, ends a step 0.2 m behind a stopped car: at constant velocity it
    would cover 0.25 m in the next 0.05 s, so highway-env predicts the contact. Braking
    at 200 m/s^2 it then stops after ``v^2 / (2 a) = 0.0625`` m, short of the car
    (shapely: the bodies never meet), yet the crash stands, as for highway-env's own cars.
    """
    road = _bare_road()
    params = VehicleParams(max_steer_rate=None)
    other = Vehicle(road, [0.0, 0.0], heading=0.0, speed=0.0)
    other.LENGTH, other.WIDTH = params.length, params.width
    other.diagonal = math.hypot(params.length, params.width)
    front = -params.length / 2.0 - 0.45  # the ego's front bumper, 0.45 m behind the car
    rear = front - (params.length - params.rear_overhang)
    ego = EgoVehicle(road, Pose(rear, 0.0, 0.0), speed=5.0, vehicle=params)
    road.vehicles.extend([ego, other])
    dt = 0.05
    ego.act({"acceleration": 0.0, "steering": 0.0})
    road.step(dt)
    assert not ego.crashed
    ego.act({"acceleration": -200.0, "steering": 0.0})
    road.step(dt)
    assert ego.speed == 0.0
    gap = -params.length / 2.0 - (ego.rear[0] + params.length - params.rear_overhang)
    assert gap == pytest.approx(0.2 - 0.0625, abs=1e-9)
    assert not shapely.Polygon(ego.polygon()[:4]).intersects(shapely.Polygon(other.polygon()[:4]))
    assert ego.crashed


@pytest.mark.parametrize("steer", [-0.3, 0.3])
def test_the_heading_stays_wrapped_when_turning_across_pi(steer: float) -> None:
    """Turning across the +-pi seam, the rear-axle yaw stays in [-pi, pi] and on the arc.

    Closed form: the yaw after ``k`` steps at speed ``v`` is
    ``yaw0 + k v dt tan(delta) / L``, wrapped.
    """
    road = _bare_road()
    params = VehicleParams(max_steer_rate=None)
    yaw0 = math.copysign(math.pi - 0.005, steer)  # just short of the seam it turns across
    ego = EgoVehicle(road, Pose(0.0, 0.0, yaw0), speed=2.0, vehicle=params)
    road.vehicles.append(ego)
    dt = 0.05
    for k in range(1, 6):
        ego.act({"acceleration": 0.0, "steering": steer})
        road.step(dt)
        yaw = ego.rear[2]
        assert -math.pi <= yaw <= math.pi and ego.heading == yaw
        turned = yaw0 + k * 2.0 * dt * math.tan(steer) / params.wheelbase
        assert math.remainder(yaw - turned, 2.0 * math.pi) == pytest.approx(0.0, abs=1e-9)


# --------------------------------------------------------------------------- sim.episode


def test_the_trajectorys_last_row_keeps_the_wheels_where_the_car_stopped() -> None:
    """The final row keeps the last applied steering angle and has no acceleration.

    The car stops at the end of a 0.05 1/m arc: its wheels stay turned near the arc's
    ``atan(L kappa)``, not straight.
    """
    task = make_scenario("overtake", 0, jitter=(0.0, 0.0, 0.0))
    kappa, n = 0.05, 81
    theta = np.linspace(0.0, 8.0 * kappa, n)  # 8 m of arc from the start pose
    rows = np.column_stack([
        task.start.x + np.sin(theta) / kappa, task.start.y + (1.0 - np.cos(theta)) / kappa,
        theta, np.full(n, kappa),
    ])  # fmt: skip
    episode = run_episode(task, Path(rows, np.zeros((0, 2))), "lqr", 0)
    assert episode.status is EpisodeStatus.ARRIVED
    traj = episode.trajectory()
    wheels = math.atan(task.vehicle.wheelbase * kappa)
    assert traj[-1, 5] == traj[-2, 5] == episode.log.controls[-1, 1]
    assert abs(traj[-1, 5] - wheels) < 0.3 * wheels
    assert traj[-1, 6] == 0.0


@settings(max_examples=80, deadline=None)
@given(st.lists(st.sampled_from([0.0, 1e-6, -1e-6, 5e-4, -5e-4, 0.3, -0.3]), max_size=12))
def test_driven_gears_follow_every_motion_however_slow(speeds: list[float]) -> None:
    """The gear is the sign of any non-zero speed (a 1 um/s creep too); at rest, the last one.

    Reference: a plain loop over the samples, as the docstring words the rule.
    """
    v = np.array(speeds)
    moving = [x for x in speeds if x != 0.0]
    gear = 1.0 if not moving else math.copysign(1.0, moving[0])  # before the first motion
    expected = []
    for x in speeds:
        if x != 0.0:
            gear = math.copysign(1.0, x)
        expected.append(gear)
    assert driven_gears(v).tolist() == expected


# --------------------------------------------------------------------------- sim.extract


def test_the_map_leaves_out_what_highway_env_cannot_crash_into() -> None:
    """A non-collidable road object is no obstacle: highway-env lets the ego drive through it.

    Two equal blocks are added to stock ``parking-v0``; one is made non-collidable. The
    extracted map holds the other only, and highway-env's own judge agrees: the ego placed
    across the non-collidable block does not crash.
    """
    env = gym.make("parking-v0")
    env.reset(seed=0)
    try:
        u = env.unwrapped
        attach_ego(env)
        ghost = HwObstacle(u.road, [-30.0, 0.0])
        ghost.collidable = False
        block = HwObstacle(u.road, [30.0, 0.0])
        u.road.objects.extend([ghost, block])
        before = map_from_env(env, lane_lines=False)
        centres = [tuple(o.center) for o in before.obstacles]
        assert (30.0, 0.0) in centres and (-30.0, 0.0) not in centres
        ego = u.vehicle
        ego.set_pose(Pose(-30.0, 0.0, 0.0), speed=0.0)
        env.step(np.zeros(2, dtype=np.float32))
        assert not ego.crashed
        ego.set_pose(Pose(30.0, 0.0, 0.0), speed=0.0)
        env.step(np.zeros(2, dtype=np.float32))
        assert ego.crashed
    finally:
        env.close()


def test_solid_lane_lines_become_thin_obstacles_on_their_own_side() -> None:
    """Only solid lines are walls, each on its side of the lane.

    highway-env draws ``line_types[side]`` at the lateral offset ``(side - 0.5) * width``
    (``LaneGraphics``); a lane from (0, 0) to (20, 0), 4 m wide, with a solid line on
    side 0 and a striped one on side 1 has one wall: 20 m long, centred at (10, -2).
    """
    net = RoadNetwork()
    lane = StraightLane([0.0, 0.0], [20.0, 0.0], width=4.0,
                        line_types=(LineType.CONTINUOUS_LINE, LineType.STRIPED))  # fmt: skip
    net.add_lane("a", "b", lane)
    road = Road(net, np_random=np.random.RandomState(0))
    walls = lane_line_obstacles(road, thickness=0.1)
    assert len(walls) == 1
    wall = walls[0]
    expected = np.asarray(lane.position(10.0, (0 - 0.5) * 4.0), dtype=float)
    assert np.allclose(wall.center, expected) and np.allclose(expected, [10.0, -2.0])
    assert wall.size == pytest.approx((20.0, 0.1)) and wall.yaw == pytest.approx(0.0)


def test_attach_ego_keeps_the_cars_speed_and_body() -> None:
    """The new ego drives on at the old car's speed, its body centre where the old one's was."""
    env = gym.make("parking-v0")
    env.reset(seed=0)
    try:
        u = env.unwrapped
        old = u.vehicle
        old.speed = 2.5
        centre, heading = np.array(old.position, dtype=float), float(old.heading)
        ego = attach_ego(env)
        assert ego is u.vehicle and ego.speed == 2.5
        assert np.allclose(ego.position, centre)
        assert math.remainder(ego.heading - heading, 2.0 * math.pi) == pytest.approx(0.0, abs=1e-12)
        assert attach_ego(env, speed=1.0) is ego and ego.speed == 2.5  # already attached
    finally:
        env.close()


@pytest.mark.parametrize("pad", [0.5, 3.0])
def test_the_map_bounds_leave_the_pad_round_everything(pad: float) -> None:
    """Every obstacle (shapely), the start and the goal lie ``pad`` m inside the bounds."""
    env = gym.make("parking-v0")
    env.reset(seed=0)
    try:
        m = map_from_env(env, pad=pad)
    finally:
        env.close()
    x0, y0, x1, y1 = m.bounds
    shapes = [o.polygon() for o in m.obstacles]
    shapes += [shapely.Point(p.x, p.y) for p in (m.start, m.goal)]
    lo_x, lo_y, hi_x, hi_y = shapely.GeometryCollection(shapes).bounds
    assert lo_x - x0 >= pad - 1e-9 and lo_y - y0 >= pad - 1e-9
    assert x1 - hi_x >= pad - 1e-9 and y1 - hi_y >= pad - 1e-9


# --------------------------------------------------------------------------- sim.replanning


def test_the_reference_at_a_take_over_time_is_the_new_one() -> None:
    """``reference_at(t)`` at the very time a reference took over returns that reference.

    The loop's clock sums its steps (``0.05 * 6`` summed is 0.30000000000000004): a time
    read off the step count, 0.3, still counts as the take-over time.
    """
    old, new = lane_path(0.0, 10.0, 44.0), lane_path(5.0, 15.0, 44.0)
    t_switch = 0.0
    for _ in range(6):
        t_switch += 0.05
    log = TrafficLog((), ((0.0, old), (t_switch, new)), old, (), 0, None, ReplanConfig())
    assert log.reference_at(0.0) is old and log.reference_at(0.25) is old
    assert log.reference_at(t_switch) is new and log.reference_at(0.3) is new
    assert log.reference_at(99.0) is new


@settings(max_examples=40, deadline=None)
@given(extra=st.floats(0.01, 12.0), length=st.floats(5.0, 20.0))
def test_a_merge_runs_on_along_the_lane_to_x1(extra: float, length: float) -> None:
    """``merge_path`` joins the lane over ``length`` m, then follows it all the way to ``x1``."""
    x1 = 3.0 + length + extra
    rows = merge_path((3.0, 44.5, 0.02), 0.0, length, x1, 44.0).samples
    assert rows[-1, 0] == pytest.approx(x1) and rows[-1, 1] == pytest.approx(44.0)
    assert np.all(np.diff(rows[:, 0]) > 0.0) and np.diff(rows[:, 0]).max() <= 0.25 + 1e-9


# --------------------------------------------------------------------------- sim.pull_out


def _at_speed(v: float) -> Callable[[Path], np.ndarray]:
    """Arrival times along a path at constant speed ``v``: arc length over ``v``."""

    def times_of(path: Path) -> np.ndarray:
        return path.arc_length() / v

    return times_of


@settings(max_examples=25, deadline=None)
@given(v=st.floats(2.0, 8.0), gap=st.floats(0.0, 60.0), head_rows=st.integers(0, 8))
def test_the_pull_out_cuts_in_past_a_stopped_lead(v: float, gap: float, head_rows: int) -> None:
    """The cut-in row lies at or past the admissible point, and the road holds the path.

    The lead stands ``gap`` m ahead; the cut-in point needs the ego 4 m past it. The
    path keeps the given head rows, then the manoeuvre (out and back take a lane change
    of 18 m each), then ``tail`` m of lane, and never runs past the road's end.
    """
    x0 = 10.0 + 0.25 * head_rows
    head = lane_path(10.0, x0, 44.0).samples[:head_rows, :4]
    start = np.array([x0, 44.0, 0.0, 0.0])
    need = x0 + gap + 4.0
    kwargs = dict(lane_y=44.0, out_y=48.0, length=18.0, max_length=110.0, tail=20.0,
                  times_of=_at_speed(v), cut_in_x=lambda t: need)  # fmt: skip
    found = pull_out_candidate(head, start, x_end=1000.0, **kwargs)
    assert found is not None
    path, goal, times = found
    rows = path.samples
    np.testing.assert_array_equal(rows[:head_rows, :4], head)
    np.testing.assert_allclose(rows[head_rows, :4], start)
    assert rows[goal, 1] == pytest.approx(44.0) and rows[goal - 1, 1] > 44.0 + 1e-6
    assert rows[goal, 0] == pytest.approx(max(need, x0 + 36.0))
    assert rows[-1, 0] == pytest.approx(rows[goal, 0] + 20.0)
    np.testing.assert_allclose(times, path.arc_length() / v)
    # The same manoeuvre with the road ending before its tail: no candidate.
    assert pull_out_candidate(head, start, x_end=float(rows[-1, 0]) - 1.0, **kwargs) is None


@pytest.mark.parametrize("v_lead", [0.5, 1.0, 2.0])
def test_the_pull_out_finds_the_nearest_cut_in_point_behind_a_moving_lead(v_lead: float) -> None:
    """Behind a lead at 0.5-2 m/s: the cut-in point found is (about) the nearest that works.

    The ego times the path at 5 m/s; the cut-in point needs it 4 m past a lead that is
    30 m ahead and drives on at ``v_lead``. A brute-force scan (0.1 m steps) finds the
    x_goal values that satisfy ``x_goal >= cut_in_x(t(x_goal))``. The search used to set
    ``x_goal = need`` each round, short again by the lead's share of the extra distance,
    so it settled only in the limit and gave None after 8 rounds (a mutation audit).
    """
    x0, v = 10.0, 5.0
    start = np.array([x0, 44.0, 0.0, 0.0])

    def cut_in_x(t: float) -> float:
        return x0 + 30.0 + v_lead * t + 4.0

    feasible = []
    for x_goal in np.arange(x0 + 36.0, x0 + 110.0, 0.1):
        local = pull_out_path(start, 44.0, 48.0, 18.0, x_goal - 18.0, x_goal + 20.0)
        i = int(np.searchsorted(local.samples[:, 0], x_goal - 1e-9))
        if x_goal >= cut_in_x(float(local.arc_length()[i] / v)):
            feasible.append(float(x_goal))
    assert feasible  # a cut-in point within reach exists
    found = pull_out_candidate(np.zeros((0, 4)), start, lane_y=44.0, out_y=48.0, length=18.0,
                               max_length=110.0, tail=20.0, x_end=1000.0,
                               times_of=_at_speed(v), cut_in_x=cut_in_x)  # fmt: skip
    assert found is not None
    path, goal, times = found
    x_cut = float(path.samples[goal, 0])
    assert x_cut >= cut_in_x(float(times[goal])) - 1e-9  # it works
    assert x_cut <= feasible[0] + 0.2  # and is no farther than the scan's first by much


@pytest.mark.parametrize("dy", [-2.0, 2.0])
def test_a_path_that_leaves_the_road_on_either_side_is_not_inside(dy: float) -> None:
    """``inside_road`` checks every body corner against both edges (road 40-50 m)."""
    params = VehicleParams()
    lane = lane_path(0.0, 10.0, 45.0)
    assert inside_road(lane, params, 40.0, 50.0)
    shifted = Path(lane.samples[:, :4] + np.array([0.0, 5.0 * np.sign(dy) - dy, 0.0, 0.0]),
                   np.zeros((0, 2)))  # fmt: skip
    # Its centre line 1 m inside an edge: the 0.9 m half-width fits, the corners stay in.
    assert inside_road(shifted, params, 40.0, 50.0)
    off = Path(lane.samples[:, :4] + np.array([0.0, 5.0 * np.sign(dy), 0.0, 0.0]),
               np.zeros((0, 2)))  # fmt: skip
    assert not inside_road(off, params, 40.0, 50.0)  # on the edge: half the body outside


# --------------------------------------------------------------------------- sim.pair_screen


@pytest.mark.parametrize("reversing_ego", [False, True])
def test_the_screen_keeps_a_fast_corner_to_corner_approach(reversing_ego: bool) -> None:
    """A car closing on another's corner at 10 m/s: highway-env predicts the contact.

    The centres are farther apart than half the sum of the diagonals, within it plus the
    step's ``|v| dt`` = 0.5 m: the screen's circles must widen by the speed (by ``|v|`` for
    the reversing ego) or the pair is dropped. Reference: highway-env's own ``_is_colliding``.
    """
    road = Road(RoadNetwork.straight_road_network(2))
    params = VehicleParams()
    parked = Vehicle(road, np.array([0.0, 0.0]), 0.0, 0.0)
    parked.LENGTH, parked.WIDTH = params.length, params.width
    parked.diagonal = math.hypot(params.length, params.width)
    centre = (params.length + 0.3, params.width - 0.1)
    if reversing_ego:
        offset = params.length / 2.0 - params.rear_overhang
        mover = EgoVehicle(road, Pose(centre[0] - offset, centre[1], 0.0), -10.0, params)
    else:
        mover = Vehicle(road, np.array(centre), math.pi, 10.0)  # forward, towards -x
        mover.LENGTH, mover.WIDTH = params.length, params.width
        mover.diagonal = math.hypot(params.length, params.width)
    dt = 0.05
    assert math.dist(mover.position, parked.position) > (mover.diagonal + parked.diagonal) / 2
    intersecting, will_intersect, _ = mover._is_colliding(parked, dt)
    assert will_intersect and not intersecting
    kept = pairs_to_handle([mover, parked], [], dt, [reversing_ego, False])
    assert kept == [(mover, parked)]


# --------------------------------------------------------------------------- sim.prediction


def test_a_stopped_car_may_drive_off_at_its_target_speed() -> None:
    """A car standing still below its IDM target speed: it stays, or drives off at the target.

    Lane following has no route speed to scale for a car at rest, so its fast hypothesis
    is constant velocity at the target speed: ``target * t`` along its heading.
    """
    env = build_env(make_scenario("overtake-traffic", 2))
    try:
        car = [v for v in env.unwrapped.road.vehicles if isinstance(v, OncomingCar)][2]
        target = float(car.target_speed)
        assert target > 1.0
        car.speed = 0.0
        both = predict([car], "lane-following", horizon=2.0)
        assert both.alt is not None
        start = np.array(car.position, dtype=float)
        assert np.allclose(both.poses[0, :, :2], start)  # the slow hypothesis stands
        heading = np.array([math.cos(car.heading), math.sin(car.heading)])
        expected = start + 2.0 * target * heading
        assert np.allclose(both.alt[0, -1, :2], expected, atol=1e-6)
    finally:
        env.close()
