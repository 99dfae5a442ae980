"""Guards against mutants that survived the suite, second round: the traffic re-planner's
pull-out and planner plans, the cut-in rule, the oncoming gate, the stock-env drive, the
scenes and the lane references.

Each test checks what a user sees (the reference the ego tracks, a re-planning record,
a traffic car's motion, a scene's layout) against an independent reference: closed-form
kinematics, shapely geometry, or highway-env's own state and judgement.
"""

from __future__ import annotations

import copy
import dataclasses
import math
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
import shapely
from highway_env.utils import lmap
from highway_env.vehicle.behavior import IDMVehicle
from highway_env.vehicle.kinematics import Vehicle
from test_mutation_guards_traffic import (
    FAR_ONCOMING,
    SEEDED,
    _body,
    _box,
    _driving,
    _road,
    _scene,
)

from rrtdrive.controllers import SpeedConfig
from rrtdrive.planning.spacetime import ArrivalTiming, Prediction
from rrtdrive.sim import stock
from rrtdrive.sim.drivelog import DriveRecorder
from rrtdrive.sim.ego import centre_to_rear_axle
from rrtdrive.sim.extract import attach_ego
from rrtdrive.sim.replanning import lane_path, merge_path
from rrtdrive.sim.runner import EpisodeConfig
from rrtdrive.sim.scenes import FIT_MIN_SIZE, OncomingCar, SceneEnv, build_env, fit_view
from rrtdrive.sim.stock import drive_stock_env
from rrtdrive.sim.tasks import make_scenario
from rrtdrive.sim.tasks.overtake_traffic import OvertakeTrafficTask
from rrtdrive.sim.traffic import ConflictZone, OncomingGate, conflict_zone
from rrtdrive.sim.traffic_driver import TrafficDriver
from rrtdrive.types import Budget, InputError, Path, Pose, VehicleParams
from rrtdrive.vehicle import footprint_corners

#: One planner iteration: the planner finds nothing, so the cycle tries the pull-out.
ONE_TRY = dataclasses.replace(SEEDED, max_iterations=1)
PULLED_OUT = "pull-out past the slow lead"
#: The ego's usual start: rear axle 5 m along the ego lane's centre line (y = 44).
START = Pose(5.0, 44.0, 0.0)


def _behind_standing_lead(
    oncoming_x: float, ego: Pose = START, ego_speed: float = 0.0
) -> OvertakeTrafficTask:
    """The road with a lead standing 12 m ahead and one oncoming car at 8 m/s at ``oncoming_x``."""
    return _road(ego, lead_gap=12.0, lead_speed=2.0, ego_speed=ego_speed,
                 oncoming=[(oncoming_x, 8.0)])


def _stand_lead(driver: TrafficDriver) -> None:
    """Stop the lead car where it is."""
    driver.lead.speed = driver.lead.target_speed = 0.0


# --------------------------------------------------------------------------- the pull-out


@pytest.mark.parametrize("oncoming_x", [124.0, 125.0, 130.0])
def test_an_accepted_pull_out_stays_safe_while_the_ego_launches_on_it(oncoming_x: float) -> None:
    """A pull-out from standstill is not accepted only to fail its check a moment later.

    The ego launches late on the profile (the speed loop ramps up at the comfort jerk),
    so an oncoming car that would meet it shortly after the profile's time must refuse
    the pull-out. Reference: the driver's own per-step check while highway-env drives
    the ego for 3 s; an accepted pull-out must pass every step (no unsafe step, never
    abandoned). At least one position (130 m) is accepted, so the check is exercised.
    """
    with _scene(_behind_standing_lead(oncoming_x), ONE_TRY) as (env, driver):
        _stand_lead(driver)
        driver.start()
        dt = 1.0 / env.unwrapped.config["simulation_frequency"]
        recorder = DriveRecorder(env, dt)
        for k in range(60):
            recorder.step(*driver.control(k * dt))
        accepted = driver.records[0].message == PULLED_OUT
        if accepted:
            assert driver.unsafe_steps == 0
            assert all(r.outcome != "abandoned" for r in driver.records)
        if oncoming_x == 130.0:
            assert accepted  # the check above is exercised


@pytest.mark.parametrize("oncoming_x", [25.0, 27.0, 28.5])
def test_a_pull_out_accepted_between_two_rows_passes_the_check_at_once(oncoming_x: float) -> None:
    """The pull-out's check allows for the ego standing past its reference's first row.

    The ego stands 0.24 m along its lane reference (rows every 0.25 m) when the cycle
    runs; an oncoming car passes just before it would get there. Reference: the driver's
    per-step check (which reads the ego's own position) right after acceptance; a pull-out
    it fails must not have been accepted. With the car at 25 m the pull-out is accepted.
    """
    with _driving(_behind_standing_lead(oncoming_x), ONE_TRY) as driver:
        _stand_lead(driver)
        driver.start()
        driver.ego.set_pose(Pose(5.24, 44.0, 0.0))
        record = driver.replan(0.0, "periodic")
        accepted = record.message == PULLED_OUT
        if accepted:
            assert driver.current_safe()
        else:
            assert "pull-out: conflict at" in record.message
        if oncoming_x == 25.0:
            assert accepted  # the check above is exercised


def test_no_pull_out_starts_from_the_oncoming_lane() -> None:
    """A car already in the oncoming lane is told ``not in the lane``; no pull-out is made.

    Reference: highway-env's own lane look-up puts the ego's rear axle (y = 47, the
    ego lane's centre being 44 and its width 4) in the oncoming lane, off its own.
    """
    scen = _behind_standing_lead(1000.0, ego=Pose(5.0, 47.0, 0.0), ego_speed=4.0)
    with _driving(scen, ONE_TRY) as driver:
        _stand_lead(driver)
        driver.start()
        net = driver.ego.road.network
        assert net.get_closest_lane_index(driver.ego.rear[:2]) == ("b", "a", 0)
        assert not net.get_lane(("a", "b", 0)).on_lane(driver.ego.rear[:2])
        record = driver.replan(0.0, "periodic")
        assert record.outcome == "no_plan"
        assert record.message.endswith("pull-out: not in the lane")
        assert driver.mode == "follow"


# --------------------------------------------------------------------------- planner plans


def test_a_planner_plan_is_checked_on_past_its_cut_in_point() -> None:
    """A planner overtake is checked ``check_beyond_m`` (10 m) past its cut-in point.

    On an empty oncoming lane the first cycle accepts an overtake; a car standing 8 m
    past its cut-in point (shapely: the ego's body on the next 10 m of the accepted
    path runs into it) must make the same cycle reject it.
    """

    def cycle(blocker_x: float | None) -> TrafficDriver:
        scen = _road(START, lead_gap=12.0, lead_speed=2.0, ego_speed=2.0,
                     oncoming=FAR_ONCOMING)
        with _driving(scen) as driver:
            driver.start()
            if blocker_x is not None:
                car = driver.others[1]
                car.position = np.array([blocker_x, driver.lane_y])
                car.heading, car.speed, car.target_speed = 0.0, 0.0, 0.0
            driver.control(0.0)
            return driver

    driver = cycle(None)
    record = driver.records[-1]
    assert record.outcome == "overtake" and record.goal_x is not None
    goal_x = record.goal_x
    rows = driver.path.samples  # type: ignore[union-attr]
    blocker = _box(goal_x + 8.0, driver.lane_y, driver.vehicle.length, driver.vehicle.width)
    ahead = rows[(rows[:, 0] >= goal_x) & (rows[:, 0] <= goal_x + 10.0)]
    assert any(_body(r[:3], driver).intersects(blocker) for r in ahead)
    driver = cycle(goal_x + 8.0)
    record = driver.records[-1]
    assert record.outcome == "rejected" and record.message.startswith("conflict at")
    assert driver.mode == "follow"


def test_a_planner_overtake_near_the_end_of_the_road_ends_on_the_road() -> None:
    """The lane after a planner plan's cut-in point ends with the road, not 200 m past it.

    Reference: the map's bounds (x up to 1500); the ego overtakes 150 m before the end.
    """
    scen = _road(Pose(1350.0, 44.0, 0.0), lead_gap=12.0, lead_speed=2.0, ego_speed=2.0,
                 oncoming=[(2350.0, 8.0)], max_time_s=5.0)
    xmax = scen.map.bounds[2]
    with _driving(scen) as driver:
        driver.start()
        driver.control(0.0)
        assert driver.records[-1].outcome == "overtake"
        xs = driver.path.samples[:, 0]  # type: ignore[union-attr]
        assert xs.max() <= xmax - 1.0 + 1e-9
        assert xs.max() >= xmax - 1.0 - 0.25


# --------------------------------------------------------------------------- sim.cut_in


@pytest.mark.parametrize("lead_speed", [0.0, 2.5])
def test_the_cut_in_point_leaves_the_gap_and_headway_behind_the_ego_bumper(
    lead_speed: float,
) -> None:
    """At the cut-in point the ego's rear bumper is ``cut_in_gap_m`` plus the headway
    (``cut_in_headway_s`` at the lead's speed) ahead of the lead's front bumper.

    Reference: the ego's body (shapely, from its footprint at the rear-axle pose) and
    the lead's highway-env position and length.
    """
    with _driving(_road(START, lead_gap=12.0, lead_speed=2.0)) as driver:
        lead = driver.lead
        lead.speed = lead_speed
        lead_x = float(lead.position[0])
        x = float(driver.cut_in.need(np.array([lead_x]))[0])
        rear_bumper = _body((x, driver.lane_y, 0.0), driver).bounds[0]
        front_bumper = lead_x + lead.LENGTH / 2.0
        cfg = driver.config
        gap = cfg.cut_in_gap_m + cfg.cut_in_headway_s * lead_speed
        assert rear_bumper - front_bumper == pytest.approx(gap, abs=1e-9)


@pytest.mark.parametrize("t", [0.0, 4.0, 9.0])
def test_the_cut_in_point_is_ahead_of_where_the_lead_will_be_a_margin_later(t: float) -> None:
    """For an arrival at ``t`` the cut-in point is placed by the lead ``m(t)`` later.

    Reference: the lead at constant speed (closed form), ``x(t + m(t))`` with the
    safety margin ``m(t) = time_margin_s + time_margin_growth * t``.
    """
    with _driving(_road(START, lead_gap=12.0, lead_speed=2.0)) as driver:
        lead = driver.lead
        v, x0 = 2.0, float(lead.position[0])
        lead.speed = v
        pred = Prediction.constant_velocity(
            np.array([[x0, driver.lane_y, 0.0, v]]), [(lead.LENGTH, lead.WIDTH)], 12.0
        )
        safety = driver.config.safety
        later = t + safety.time_margin_s + safety.time_margin_growth * t
        expected = float(driver.cut_in.need(np.array([x0 + v * later]))[0])
        assert driver.cut_in.need_at(t, pred) == pytest.approx(expected, abs=1e-9)


def _s_curve_length(radius: float, offset: float) -> float:
    """Length along x of an S of two opposite arcs of ``radius`` across a lateral ``offset``.

    Each arc turns by ``theta`` with ``radius * (1 - cos(theta)) = offset / 2`` and
    advances ``radius * sin(theta)``.
    """
    theta = math.acos(1.0 - offset / (2.0 * radius))
    return 2.0 * radius * math.sin(theta)


def _standing_far_behind(driver: TrafficDriver, x: float) -> Prediction:
    """A prediction of the lead standing 100 m behind ``x`` (it never limits the cut-in)."""
    lead = driver.lead
    return Prediction.constant_velocity(
        np.array([[x - 100.0, driver.lane_y, 0.0, 0.0]]), [(lead.LENGTH, lead.WIDTH)], 12.0
    )


@pytest.mark.parametrize(("dy", "changes"), [(0.0, 2), (4.0, 1)])
def test_the_cut_in_point_leaves_room_for_the_lane_changes_still_to_drive(
    dy: float, changes: int
) -> None:
    """The cut-in point is at least the lane changes still to drive, plus ``goal_slack_m``.

    From the ego lane two (out and back), from the oncoming lane one, each an S of two
    arcs of the turning radius across the lane width (closed-form arc geometry). The
    lead stands far behind, so only this bound places the point.
    """
    with _driving(_road(START)) as driver:
        cfg = driver.config
        x_start = 6.5
        timing = ArrivalTiming(0.0, 4.0, 8.0, 1.0, (5.0, driver.lane_y))
        pred = _standing_far_behind(driver, x_start)
        x = driver.cut_in.goal_x(timing, x_start, pred, driver.lane_y + dy)
        s_curve = _s_curve_length(cfg.turning_radius_m, driver.lane_width)
        assert x == pytest.approx(x_start + changes * s_curve + cfg.goal_slack_m, abs=1e-9)


@pytest.mark.parametrize(("room", "found"), [(25.0, True), (15.0, False)])
def test_no_cut_in_point_in_the_last_20_m_of_the_road(room: float, found: bool) -> None:
    """A cut-in point less than 20 m before the road's last usable x is no cut-in point.

    Reference: the map's bounds (the last usable x is one metre short of the end);
    the point is placed by the lane-change bound (closed-form arcs) ``room`` m before it.
    """
    with _driving(_road(START)) as driver:
        cfg = driver.config
        x_end = driver.road_bounds[2] - 1.0
        reach = 2 * _s_curve_length(cfg.turning_radius_m, driver.lane_width) + cfg.goal_slack_m
        x_start = x_end - room - reach
        timing = ArrivalTiming(0.0, 8.0, 8.0, 1.0, (x_start - 1.5, driver.lane_y))
        pred = _standing_far_behind(driver, x_start)
        x = driver.cut_in.goal_x(timing, x_start, pred, driver.lane_y)
        assert (x is not None) == found
        if found:
            assert x == pytest.approx(x_end - room, abs=1e-9)


@pytest.mark.parametrize(("speed", "found"), [(5.0, False), (6.0, True)])
def test_no_cut_in_point_reached_later_than_a_second_before_the_horizon(
    speed: float, found: bool
) -> None:
    """A cut-in point the ego reaches (at the latest) after ``horizon_s - 1`` is refused.

    Reference: at constant speed the latest nominal arrival is ``1.08 * distance / v``
    (closed form): 11.0 s at 5 m/s (past 12 - 1 s), 9.2 s at 6 m/s.
    """
    with _driving(_road(START)) as driver:
        cfg = driver.config
        x_start = 6.5
        timing = ArrivalTiming(0.0, speed, speed, 1.0, (x_start, driver.lane_y))
        pred = _standing_far_behind(driver, x_start)
        reach = 2 * _s_curve_length(cfg.turning_radius_m, driver.lane_width) + cfg.goal_slack_m
        t_latest = 1.08 * reach / speed
        assert (t_latest <= cfg.horizon_s - 1.0) == found
        x = driver.cut_in.goal_x(timing, x_start, pred, driver.lane_y)
        assert (x is not None) == found


# --------------------------------------------------------------------------- sim.traffic


def _lane_change_path() -> Path:
    """A quintic lane change from the ego lane (y = 44) to the oncoming one (y = 48)."""
    x = np.arange(0.0, 60.0, 0.1)
    u = np.clip((x - 15.0) / 25.0, 0.0, 1.0)
    y = 44.0 + 4.0 * (6 * u**5 - 15 * u**4 + 10 * u**3)
    dy = np.gradient(y, x)
    kappa = np.gradient(dy, x) / (1 + dy**2) ** 1.5
    return Path(np.column_stack([x, y, np.arctan(dy), kappa]), np.zeros((0, 2)))


def test_the_conflict_zone_is_where_the_body_crosses_the_centre_line() -> None:
    """The zone runs from the first to the last pose whose body reaches over the centre
    line, and spans in x every body on that stretch.

    Reference: shapely bodies at every row against the half-plane above ``y = 46``.
    """
    path, vehicle = _lane_change_path(), VehicleParams()
    zone = conflict_zone(path, 44.0, 4.0, vehicle)
    assert zone is not None
    over = shapely.box(-1e3, 46.0, 1e3, 1e3)
    bodies = [shapely.Polygon(footprint_corners(r[:3], vehicle)) for r in path.samples]
    crossing = [i for i, b in enumerate(bodies) if b.intersection(over).area > 0.0]
    s = path.arc_length()
    assert zone.s_in == pytest.approx(s[crossing[0]], abs=1e-9)
    assert zone.s_out == pytest.approx(s[crossing[-1]], abs=1e-9)
    span = shapely.union_all(bodies[crossing[0] : crossing[-1] + 1]).bounds
    assert (zone.x_lo, zone.x_hi) == pytest.approx((span[0], span[2]), abs=1e-9)


@dataclasses.dataclass
class _Car:
    """An oncoming car as the gate reads it (driving towards -x)."""

    x: float
    speed: float
    LENGTH: float = 5.0  # noqa: N815 (highway-env's attribute name)

    @property
    def position(self) -> np.ndarray:
        """The centre, on the oncoming lane."""
        return np.array([self.x, 48.0])


#: A conflict zone from s = 20 to 60 m covering x in [15, 65] (stop line at s = 19).
ZONE = ConflictZone(20.0, 60.0, 15.0, 65.0)


def _gate(margin_s: float = 2.0) -> OncomingGate:
    """A gate on a straight 100 m profile (instant actuator) at the default speed settings."""
    s = np.arange(0.0, 100.0 + 1e-9, 0.25)
    return OncomingGate(ZONE, (s, np.zeros_like(s)), SpeedConfig(v_max=8.0), margin_s=margin_s)


def test_the_gate_times_the_crossing_to_the_end_of_the_zone() -> None:
    """The crossing lasts at least the drive from the stop line to the zone's end at v_max.

    Reference: closed form, ``(s_out - s_stop) / v_max``.
    """
    gate = _gate()
    assert gate.s_stop == pytest.approx(ZONE.s_in - 1.0)
    assert gate.crossing_time >= (ZONE.s_out - gate.s_stop) / 8.0


def test_the_gate_holds_the_ego_for_a_car_arriving_while_it_crosses() -> None:
    """A car reaching the zone before the ego, starting now from the line, is out of it
    plus the margin, holds the ego at the stop line; one after it does not.

    Reference: the car's arrival at constant speed (closed form) against the ego's
    crossing time plus the 2 s margin (the ego stands at the line: ``t_line = 0``).
    """
    v = 10.0
    for lateness, held in [(-0.3, True), (0.3, False)]:
        gate = _gate()
        t_out = gate.crossing_time + 2.0
        front = ZONE.x_hi + v * (t_out + lateness)
        car = _Car(front + 2.5, v)
        answer = gate.stop_line(gate.s_stop, 0.0, [car])
        assert answer == (gate.s_stop if held else None), lateness


def test_a_released_gap_is_revoked_only_when_half_the_margin_is_gone() -> None:
    """Hysteresis: before release the ego waits for the whole margin; once released, a car
    coming into the margin's second half does not stop it, one in the first half does.

    Reference: the car's arrival at constant speed (closed form), the ego at the line.
    """
    v, margin = 10.0, 2.0

    def car_at(gate: OncomingGate, share: float) -> _Car:
        """A car arriving ``share`` of the margin after the ego would be out of the zone."""
        t = gate.crossing_time + share * margin
        return _Car(ZONE.x_hi + v * t + 2.5, v)

    gate = _gate(margin)
    assert gate.stop_line(gate.s_stop, 0.0, [car_at(gate, 0.75)]) == gate.s_stop  # not yet
    assert gate.stop_line(gate.s_stop, 0.0, []) is None  # released
    assert gate.stop_line(gate.s_stop, 0.0, [car_at(gate, 0.75)]) is None  # kept
    assert gate.stop_line(gate.s_stop, 0.0, [car_at(gate, 0.25)]) == gate.s_stop  # revoked


@pytest.mark.parametrize("x", [20.0, 40.0, 64.0, 17.0])
def test_a_car_standing_in_the_zone_holds_the_ego(x: float) -> None:
    """A car stopped with any part of its body in the zone's x range holds the ego.

    Reference: shapely, the car's body (5 m long, centred at ``x``) meets the zone's
    x range [15, 65]; at 17 m only its rear 0.5 m does.
    """
    car = _Car(x, 0.0)
    body = shapely.box(x - 2.5, 46.0, x + 2.5, 50.0)
    assert body.intersects(shapely.box(ZONE.x_lo, 0.0, ZONE.x_hi, 100.0))
    gate = _gate()
    assert gate.stop_line(gate.s_stop, 0.0, [car]) == gate.s_stop


def test_a_car_past_the_zone_does_not_hold_the_ego() -> None:
    """A car whose whole body is behind the zone (x < 15) is no reason to wait."""
    gate = _gate()
    assert gate.stop_line(gate.s_stop, 0.0, [_Car(12.0, 10.0)]) is None


def test_past_the_stop_line_the_gate_never_stops_the_ego() -> None:
    """One metre past the stop line the ego is committed, even with a car in the zone."""
    gate = _gate()
    assert gate.stop_line(gate.s_stop + 1.0, 2.0, [_Car(40.0, 0.0)]) is None
    assert gate.committed


@pytest.mark.parametrize(("speed", "to_line", "committed"), [
    (0.0, 0.0, False), (0.4, 0.0, False), (4.0, 1.0, True), (4.0, 10.0, False),
])
def test_a_released_ego_commits_only_when_it_can_no_longer_stop_comfortably(
    speed: float, to_line: float, committed: bool
) -> None:
    """Released, the ego commits when its comfortable stop (``v^2 / 2 decel``) reaches past
    the line and it is moving (above 0.5 m/s); standing at the line it can still wait.

    Reference: closed-form stopping distance; a car then standing in the zone holds the
    ego only if it has not committed.
    """
    gate = _gate()
    decel = SpeedConfig(v_max=8.0).decel
    assert (speed**2 / (2 * decel) >= to_line and speed > 0.5) == committed
    assert gate.stop_line(gate.s_stop - to_line, speed, []) is None
    assert gate.committed == committed
    answer = gate.stop_line(gate.s_stop - to_line, speed, [_Car(40.0, 0.0)])
    assert answer == (None if committed else gate.s_stop)


def _lead_and_oncoming(
    driver: TrafficDriver, lead_x: float, cars: Sequence[tuple[float, float, float]]
) -> Prediction:
    """A prediction of the lead standing at ``lead_x`` in the ego lane, then oncoming cars
    ``(x, y, speed)`` driving towards -x (the driver's own car sizes)."""
    size = (driver.vehicle.length, driver.vehicle.width)
    rows = [[lead_x, driver.lane_y, 0.0, 0.0]] + [[x, y, math.pi, v] for x, y, v in cars]
    return Prediction.constant_velocity(np.array(rows), [size] * len(rows), 12.0)


def test_the_gap_is_open_when_the_lead_never_blocks_the_way() -> None:
    """With the lead standing far behind (it blocks no point of the way to the cut-in), the
    oncoming lane need not be free: the gap is open whatever the oncoming cars do.

    Reference: the lead's body 100 m behind the start is nowhere near the way (closed form).
    """
    with _driving(_road(START)) as driver:
        timing = ArrivalTiming(0.0, 8.0, 8.0, 1.0, (5.0, driver.lane_y))
        pred = _lead_and_oncoming(driver, -95.0, [(60.0, 48.0, 8.0)])
        assert driver.cut_in.gap_open(timing, 6.5, 60.0, pred)


@pytest.mark.parametrize(("t_beside", "open_"), [(8.0, False), (13.5, True)])
def test_the_gap_is_closed_by_a_car_beside_the_lead_at_a_late_arrival(
    t_beside: float, open_: bool
) -> None:
    """An oncoming car beside the lead at any time the ego may reach the lead closes the gap,
    the latest nominal arrival included; one there well after it does not.

    Reference: the timing at constant 8 m/s with paths up to twice their progress
    (closed form): the ego reaches the lead's stretch (x about 33-47, the lead standing
    at 40) between ``progress / 8`` and ``2 progress / 8`` s, i.e. 3.5-10.5 s; the car
    drives at 8 m/s and is beside the lead (x = 40) at ``t_beside``.
    """
    with _driving(_road(START)) as driver:
        timing = ArrivalTiming(0.0, 8.0, 8.0, 1.0, (5.0, driver.lane_y), length_factor=2.0)
        t_lo, t_hi = timing.band(np.array([[40.0, driver.lane_y]]))
        assert float(t_lo[0]) == pytest.approx(35.0 / 8.0)
        assert float(t_hi[0]) == pytest.approx(70.0 / 8.0)
        pred = _lead_and_oncoming(driver, 40.0, [(40.0 + 8.0 * t_beside, 48.0, 8.0)])
        assert driver.cut_in.gap_open(timing, 6.5, 70.0, pred) == open_


def test_a_narrow_car_at_the_far_edge_leaves_the_gap_open() -> None:
    """A 1 m wide vehicle at the far edge of the oncoming lane, beside the lead when the ego
    gets there, leaves room to pass the lead: the gap stays open.

    Reference: shapely; the ego's body beside the lead at y = 47 keeps more than the largest
    buffer of the 12 s horizon (0.4 + 0.05 * 12 = 1.0 m) from the lead's body and from the
    vehicle's (at y = 49.5), and stays on the road (y <= 50).
    """
    with _driving(_road(START)) as driver:
        length, width = driver.vehicle.length, driver.vehicle.width
        timing = ArrivalTiming(0.0, 8.0, 8.0, 1.0, (5.0, driver.lane_y))
        rows = np.array([[40.0, driver.lane_y, 0.0, 0.0], [80.0, 49.5, math.pi, 8.0]])
        pred = Prediction.constant_velocity(rows, [(length, width), (length, 1.0)], 12.0)
        ego = _box(40.0, 47.0, length, width)
        assert ego.distance(_box(40.0, driver.lane_y, length, width)) > 1.0
        assert ego.distance(_box(40.0, 49.5, length, 1.0)) > 1.0
        assert ego.bounds[3] <= driver.road_bounds[3]
        assert driver.cut_in.gap_open(timing, 6.5, 70.0, pred)


# --------------------------------------------------------------------------- sim.stock


class _Recorded(gym.Wrapper):
    """A stock env that keeps what highway-env answered at every ``step``."""

    def __init__(self, env: gym.Env, duration: float | None) -> None:
        super().__init__(env)
        self.duration = duration
        self.steps: list[tuple[float, bool, bool, bool]] = []  # reward, term, trunc, success
        self.sizes: list[tuple[float, float]] = []

    def reset(self, **kwargs: Any) -> Any:
        """highway-env's reset (with the shorter duration, if given); notes the other cars."""
        if self.duration is not None:
            self.env.unwrapped.config["duration"] = self.duration
        out = self.env.reset(**kwargs)
        u = self.env.unwrapped
        self.sizes = [(v.LENGTH, v.WIDTH) for v in u.road.vehicles if v is not u.vehicle]
        return out

    def step(self, action: Any) -> Any:
        """highway-env's step, recorded."""
        out = self.env.step(action)
        _, reward, term, trunc, info = out
        self.steps.append((float(reward), bool(term), bool(trunc), bool(info["is_success"])))
        return out


@contextmanager
def _recording(duration: float | None = None) -> Iterator[list[_Recorded]]:
    """Every env :func:`drive_stock_env` makes is recorded (the list gets it)."""
    made: list[_Recorded] = []
    original = stock.make_stock_env

    def make(*args: Any, **kwargs: Any) -> _Recorded:
        made.append(_Recorded(original(*args, **kwargs), duration))
        return made[-1]

    stock.make_stock_env = make
    try:
        yield made
    finally:
        stock.make_stock_env = original


STOCK_CONFIG = EpisodeConfig(budget=Budget(max_time_s=1e6))


@pytest.fixture(scope="module")
def parked() -> tuple[stock.StockEpisode, list[tuple[float, bool, bool, bool]]]:
    """``parking-v0`` seed 2 parked by Hybrid A* and pure pursuit, and highway-env's answers."""
    with _recording() as made:
        run = drive_stock_env("parking-v0", 2, "hybrid-a-star", "pure-pursuit", STOCK_CONFIG)
    return run, made[0].steps


def test_a_stock_drive_reports_highway_envs_first_termination_and_its_whole_return(
    parked: tuple[stock.StockEpisode, list[tuple[float, bool, bool, bool]]],
) -> None:
    """The reported termination time is highway-env's first ``terminated`` (it stays so
    while the ego rolls on to its stop); the return is the sum of every step's reward.

    Reference: highway-env's own answers to each ``step`` of the drive.
    """
    run, steps = parked
    dt = run.episode.log.dt
    terms = [k for k, s in enumerate(steps) if s[1]]
    assert len(terms) >= 2  # terminated on more than one step
    assert run.highway_env_terminated_s == pytest.approx((terms[0] + 1) * dt)
    assert run.highway_env_return == pytest.approx(sum(s[0] for s in steps), abs=1e-9)
    assert run.highway_env_success == steps[-1][3]


def test_highway_envs_success_is_its_answer_after_the_last_step(
    parked: tuple[stock.StockEpisode, list[tuple[float, bool, bool, bool]]],
) -> None:
    """A drive that parks in the goal spot and then backs 7 m out of it is not a success.

    The parked drive's path, then its last 7 m again in reverse. Reference: highway-env's
    ``is_success`` at every step: true on the way (parked), false after the last step.
    """
    samples = parked[0].episode.path.samples
    s = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(samples[:, :2], axis=0).T))])
    back = samples[s >= s[-1] - 7.0][::-1].copy()
    back[:, 4] = -1.0  # the same poses backwards, in reverse gear
    path = Path(np.vstack([samples, back]), np.zeros((0, 2)))
    with _recording() as made:
        run = drive_stock_env("parking-v0", 2, path, "pure-pursuit", STOCK_CONFIG)
    success = [step[3] for step in made[0].steps]
    assert any(success) and not success[-1]
    assert not run.highway_env_success


def test_a_stock_drive_logs_the_other_cars_by_length_and_width() -> None:
    """The drive log's sizes of the other cars are highway-env's ``(LENGTH, WIDTH)``.

    Reference: the parked cars of ``parking-parked-v0`` as highway-env placed them.
    """
    with _recording() as made:
        run = drive_stock_env("parking-parked-v0", 1, "hybrid-a-star", "pure-pursuit",
                              EpisodeConfig(max_time_s=0.2, budget=Budget(max_time_s=1e6)))
    sizes = made[0].sizes
    assert len(sizes) == 10 and any(length != width for length, width in sizes)
    assert run.episode.log.other_sizes.tolist() == [list(s) for s in sizes]


def test_the_stock_env_steers_over_the_cars_own_range() -> None:
    """The stock env's full steering action is our car's steering limit, not highway-env's.

    Reference: highway-env's own decoding (``lmap``) of the action +-1.
    """
    vehicle = VehicleParams(max_steer=0.3, min_turning_radius=9.0)
    env = stock.make_stock_env("parking-v0", 20, vehicle=vehicle)
    try:
        env.reset(seed=0)
        low, high = env.unwrapped.action_type.steering_range
        assert lmap(1.0, [-1, 1], [low, high]) == pytest.approx(0.3)
        assert lmap(-1.0, [-1, 1], [low, high]) == pytest.approx(-0.3)
    finally:
        env.close()


def test_a_stock_drive_ends_when_highway_env_truncates_it() -> None:
    """highway-env's own time limit (here 1 s) ends the drive; a longer one is refused.

    Reference: highway-env's ``truncated`` after 20 steps at 20 Hz; nothing is stepped after
    it. More time than the env's own was cut short under a message quoting it (an audit).
    """
    with _recording(duration=1.0) as made:
        run = drive_stock_env("parking-v0", 2, "hybrid-a-star", "pure-pursuit",
                              EpisodeConfig(budget=Budget(max_time_s=1e6)))
    steps = made[0].steps
    assert [s[2] for s in steps] == [False] * 19 + [True]
    assert run.highway_env_truncated and run.episode.log.t[-1] == pytest.approx(1.0)
    with _recording(duration=1.0), pytest.raises(InputError, match=r"^max_time_s: parking-v0"):
        drive_stock_env("parking-v0", 2, "hybrid-a-star", "pure-pursuit",
                        EpisodeConfig(max_time_s=3.0, budget=Budget(max_time_s=1e6)))


def _start_and_straight(seed: int, length: float) -> Path:
    """A straight path ``length`` m ahead from the ego's start in ``parking-v0``."""
    env = stock.make_stock_env("parking-v0", 20)
    try:
        env.reset(seed=seed)
        x, y, yaw = attach_ego(env).rear
    finally:
        env.close()
    d = np.arange(0.0, length + 1e-9, 0.25)
    return Path(np.column_stack([x + d * math.cos(yaw), y + d * math.sin(yaw),
                                 np.full(len(d), yaw), np.zeros(len(d))]), np.zeros((0, 2)))


def test_a_stock_drive_that_stops_at_its_path_end_has_arrived_wherever_that_is() -> None:
    """The episode has arrived when the ego stops at its path's end, goal spot or not.

    A 3 m straight path from the start: highway-env's success is false at the end (the
    goal spot is 15 m away), our status says the path was driven to its end (the ego
    stands within 0.5 m of it).
    """
    path = _start_and_straight(2, 3.0)
    run = drive_stock_env("parking-v0", 2, path, "pure-pursuit", STOCK_CONFIG)
    final = run.episode.log.states[-1]
    assert np.hypot(*(final[:2] - path.samples[-1, :2])) < 0.5 and final[3] == 0.0
    assert not run.highway_env_success
    assert run.episode.status == "arrived"


def test_a_stock_drive_ends_at_the_first_crash() -> None:
    """Driving into the lot's wall ends the drive at once, crashed.

    Reference: highway-env's crash flag, logged every step: it is set on the last step only.
    """
    run = drive_stock_env("parking-v0", 2, _start_and_straight(2, 30.0), "pure-pursuit",
                          STOCK_CONFIG)
    crashed = run.episode.log.crashed
    assert crashed[-1] and not crashed[:-1].any()
    assert run.episode.status == "crashed"


# --------------------------------------------------------------------------- sim.scenes


@pytest.mark.parametrize("bounds", [(0.0, 0.0, 4.0, 3.0), (-3.0, 1.0, 3.0, 3.0)])
def test_a_tiny_map_is_not_blown_up_past_the_largest_scaling_nor_framed_below_the_panel(
    bounds: tuple[float, float, float, float],
) -> None:
    """A map of a few metres gets at most ``max_scaling`` (30) px/m, in a frame of at least
    :data:`FIT_MIN_SIZE` (320 x 240, room for the read-out panel).

    Reference: the map's size in metres plus the 2 m margins, times 30 px/m (closed form),
    is below 320 x 240 pixels: the frame is the minimum.
    """
    (w, h), scaling, centre = fit_view(bounds, margin=2.0)
    assert scaling == 30.0
    assert (bounds[2] - bounds[0] + 4.0) * 30.0 < 320 and (bounds[3] - bounds[1] + 4.0) * 30 < 240
    assert (w, h) == FIT_MIN_SIZE
    assert centre == ((bounds[0] + bounds[2]) / 2, (bounds[1] + bounds[3]) / 2)


def _oncoming_with(
    env: SceneEnv, front_x: float, front_y: float, speed: float = 8.0
) -> tuple[OncomingCar, Vehicle]:
    """The scene's oncoming IDM car at x = 100 (``speed``, towards -x) and its lead car
    moved to ``(front_x, front_y)``, standing (the car ahead of it, if it looks)."""
    road = env.unwrapped.road
    car = next(v for v in road.vehicles[2:] if isinstance(v, OncomingCar))
    car.position, car.speed = np.array([100.0, 48.0]), speed
    other = road.vehicles[1]
    other.position, other.heading, other.speed = np.array([front_x, front_y]), 0.0, 0.0
    if isinstance(other, OncomingCar):
        other.target_speed = 0.0
    return car, other


def _idm(car: OncomingCar, front: Vehicle | None) -> float:
    """highway-env's own IDM acceleration for ``car`` behind ``front``, within ``ACC_MAX``."""
    a = IDMVehicle.acceleration(car, car, front, None)
    return float(np.clip(a, -car.ACC_MAX, car.ACC_MAX))


@pytest.mark.parametrize("offset", [0.0, 2.5])
def test_an_oncoming_car_brakes_for_a_vehicle_half_in_its_lane(offset: float) -> None:
    """An oncoming IDM car follows a vehicle that highway-env counts in its lane (within its
    half width plus 1 m), not only one on its centre line.

    Reference: highway-env's ``on_lane(margin=1)`` and its IDM acceleration behind that
    vehicle (15 m ahead, standing, ``offset`` m off the lane's centre line).
    """
    with _scene(_road(START, oncoming=FAR_ONCOMING[:2])) as (env, _):
        car, other = _oncoming_with(env, 85.0, 48.0 - offset)
        lane = car.lane
        assert lane.on_lane(other.position, margin=1)
        car.act()
        assert car.action["acceleration"] == pytest.approx(_idm(car, other))
        assert car.action["acceleration"] < _idm(car, None)


def test_an_oncoming_car_brakes_no_harder_than_highway_envs_limit() -> None:
    """Right behind a standing vehicle, IDM asks for more than ``ACC_MAX``: it gets
    ``-ACC_MAX`` (6 m/s^2), highway-env's own limit for its IDM cars."""
    with _scene(_road(START, oncoming=FAR_ONCOMING[:2])) as (env, _):
        car, other = _oncoming_with(env, 94.0, 48.0)
        assert IDMVehicle.acceleration(car, car, other, None) < -car.ACC_MAX
        car.act()
        assert car.action["acceleration"] == pytest.approx(-car.ACC_MAX)


def test_an_oncoming_car_that_brakes_to_a_stop_never_backs_up() -> None:
    """Braking behind a standing vehicle, an oncoming car stops and stays put.

    Reference: its highway-env position, step by step for 3 s: x never grows (it drives
    towards -x), and its speed never falls below 0.
    """
    with _scene(_road(START, oncoming=FAR_ONCOMING[:2])) as (env, _):
        car, _ = _oncoming_with(env, 92.0, 48.0, speed=2.0)
        xs, speeds = [float(car.position[0])], [float(car.speed)]
        dt = 1.0 / env.unwrapped.config["simulation_frequency"]
        for _ in range(60):
            car.act()
            car.step(dt)
            xs.append(float(car.position[0]))
            speeds.append(float(car.speed))
        assert min(speeds) >= 0.0
        assert all(b <= a + 1e-12 for a, b in zip(xs, xs[1:], strict=False))


def _corner_pose(obj: Any, ego: Any, overlap: float) -> Pose:
    """The ego's rear-axle pose with its body ``overlap`` m into ``obj``'s corner each way
    (same heading, the ego diagonally beside it)."""
    c, s = math.cos(obj.heading), math.sin(obj.heading)
    along = (obj.LENGTH + ego.LENGTH) / 2.0 - overlap
    across = (obj.WIDTH + ego.WIDTH) / 2.0 - overlap
    x, y = obj.position + np.array([along * c - across * s, along * s + across * c])
    return centre_to_rear_axle(x, y, obj.heading, ego.params)


def _poly(o: Any) -> shapely.Polygon:
    """A highway-env object's own rectangle."""
    return shapely.Polygon(o.polygon()[:4])


@pytest.mark.parametrize("speed", [0.0, -2.0])
def test_a_car_touching_a_parked_cars_corner_crashes(speed: float) -> None:
    """The ego's body overlapping the corner of a parking-lot obstacle (5 cm each way)
    after a step crashes into it, standing or backing into it at 2 m/s.

    The lot is left with that one obstacle. Reference: shapely, the two bodies
    (highway-env's own polygons) intersect; corner to corner their centres are farther
    apart than half the sum of their lengths, so only a pre-check on each body's full
    diagonal keeps the pair.
    """
    env = build_env(make_scenario("parking", 5))
    try:
        u = env.unwrapped
        obj = u.road.objects[0]
        u.road.objects = [obj]
        ego = u.vehicle
        dt = 1.0 / u.config["simulation_frequency"]
        corner = _corner_pose(obj, ego, 0.05)
        ahead = -speed * dt  # a reversing ego starts this far ahead, to back into the corner
        ego.set_pose(Pose(corner.x + ahead * math.cos(corner.yaw),
                          corner.y + ahead * math.sin(corner.yaw), corner.yaw), speed=speed)
        assert not ego.crashed
        u.road.step(dt)
        assert _poly(ego).intersects(_poly(obj))
        gap = np.linalg.norm(ego.position - obj.position)
        assert gap > (obj.LENGTH + ego.LENGTH) / 2.0
        assert ego.crashed
    finally:
        env.close()


def test_an_obstacle_put_on_the_road_between_steps_is_collided_with() -> None:
    """An obstacle added to a scene's road after it has stepped is solid at the next step.

    Reference: shapely, the new obstacle (a copy of a lot obstacle, moved onto the ego)
    overlaps the ego's body; the ego had stepped clear of everything before.
    """
    env = build_env(make_scenario("parking", 5))
    try:
        u = env.unwrapped
        dt = 1.0 / u.config["simulation_frequency"]
        u.road.step(dt)
        ego = u.vehicle
        assert not ego.crashed
        new = copy.copy(u.road.objects[0])
        new.position = np.array(ego.position, dtype=float)
        assert _poly(ego).intersects(_poly(new))
        u.road.objects = [*u.road.objects, new]
        u.road.step(dt)
        assert ego.crashed
    finally:
        env.close()


def test_the_lead_car_is_a_car_of_the_maps_size_along_its_lane() -> None:
    """The overtake's lead car has the map's car size, its length along the lane.

    Reference: shapely, highway-env's own polygon of the lead against a box of
    ``vehicle.length`` x ``vehicle.width`` centred on it, along x.
    """
    scen = _road(START)
    with _scene(scen) as (env, driver):
        lead = driver.lead
        x, y = (float(v) for v in lead.position)
        box = _box(x, y, scen.vehicle.length, scen.vehicle.width)
        assert _poly(lead).symmetric_difference(box).area < 1e-9


def test_oncoming_cars_beyond_the_map_keep_their_distance() -> None:
    """Oncoming cars still arriving from beyond the map's end (x > 1500) follow each other.

    Reference: highway-env's own IDM acceleration of the second car behind the first
    (standing 20 m ahead of it, both 200 m past the map's end), and highway-env's lane
    look-up, which places both on the oncoming lane.
    """
    with _scene(_road(START, oncoming=FAR_ONCOMING[:2])) as (env, _):
        road = env.unwrapped.road
        first, second = (v for v in road.vehicles[2:4])
        first.position, first.speed, first.target_speed = np.array([1700.0, 48.0]), 0.0, 0.0
        second.position, second.speed = np.array([1720.0, 48.0]), 8.0
        lane = second.lane
        assert lane.on_lane(first.position) and lane.on_lane(second.position)
        second.act()
        assert second.action["acceleration"] == pytest.approx(_idm(second, first))
        assert second.action["acceleration"] < _idm(second, None)


# --------------------------------------------------------------------------- sim.replanning


@pytest.mark.parametrize("yaw", [math.pi / 2, 2.0, -2.5])
def test_a_merge_from_a_car_heading_away_from_the_lane_is_refused(yaw: float) -> None:
    """A merge is for a car heading along +x within 90 degrees; one facing back is bad input.

    Reference: the heading itself (cos(yaw) <= 0 points against the lane's direction).
    """
    assert math.cos(yaw) <= 1e-12
    with pytest.raises(InputError, match="heading must lie within"):
        merge_path((0.0, 45.0, yaw), 0.0, 16.0, 50.0, 44.0)


@pytest.mark.parametrize(("x0", "x1"), [(0.0, 10.0), (3.3, 17.0), (0.0, 0.1)])
def test_a_lane_reference_is_sampled_at_most_spacing_apart(x0: float, x1: float) -> None:
    """The lane line runs from ``x0`` to ``x1`` exactly, no two samples more than
    ``spacing`` (0.25 m) apart, and no more samples than that needs.

    Reference: closed form, ``ceil((x1 - x0) / spacing)`` intervals.
    """
    xs = lane_path(x0, x1, 44.0).samples[:, 0]
    assert xs[0] == x0 and xs[-1] == pytest.approx(x1, abs=1e-12)
    assert np.diff(xs).max() <= 0.25 + 1e-12
    assert len(xs) - 1 == max(1, math.ceil((x1 - x0) / 0.25 - 1e-9))
