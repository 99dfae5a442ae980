"""Guards against mutants that survived the suite: the traffic re-planner, its cut-in rule,
the oncoming gate, the stock-env drive, the scenes and the lane references.

Each test checks what a user sees (the reference the ego tracks, a re-planning record,
a traffic car's motion, a scene's layout) against an independent reference: closed-form
kinematics, shapely geometry, or highway-env's own state and judgement.
"""

from __future__ import annotations

import dataclasses
import math
import re
from collections.abc import Iterator, Sequence
from contextlib import contextmanager

import numpy as np
import pytest
import shapely

from rrtdrive.controllers import make_controller
from rrtdrive.planning.spacetime import Prediction
from rrtdrive.sim.drivelog import DriveRecorder
from rrtdrive.sim.replanning import ReplanConfig, lane_path
from rrtdrive.sim.scenes import SceneEnv, build_env, scenario_rngs
from rrtdrive.sim.tasks import make_scenario, traffic_speed_config
from rrtdrive.sim.tasks.overtake_traffic import OvertakeTrafficTask, traffic_map
from rrtdrive.sim.traffic_driver import TrafficDriver
from rrtdrive.types import Pose
from rrtdrive.vehicle import footprint_corners

SEEDED = ReplanConfig(wall_limit=False)

# --------------------------------------------------------------------------- helpers


def _road(
    start: Pose,
    lead_gap: float = 25.0,
    lead_speed: float = 4.0,
    oncoming: Sequence[tuple[float, float]] = (),
    ego_speed: float = 4.0,
    max_time_s: float = 20.0,
) -> OvertakeTrafficTask:
    """The overtake-traffic road with the ego at ``start``, a lead ``lead_gap`` m ahead
    (bumper to bumper) and the given oncoming cars ``(x, speed)``."""
    base = make_scenario("overtake-traffic", 0)
    v = base.vehicle
    front = start.x + v.length - v.rear_overhang
    lead_x = front + lead_gap + v.length / 2.0
    return dataclasses.replace(
        base, map=traffic_map(v, start), lead=(lead_x, lead_speed),
        oncoming=tuple(oncoming), ego_speed=ego_speed, max_time_s=max_time_s,
    )


@contextmanager
def _scene(
    scen: OvertakeTrafficTask, config: ReplanConfig = SEEDED
) -> Iterator[tuple[SceneEnv, TrafficDriver]]:
    """The env of ``scen`` and a pure-pursuit traffic driver in it (built, not started)."""
    env = build_env(scen)
    try:
        speed = traffic_speed_config(scen)
        ctrl = make_controller("pure-pursuit", vehicle=scen.vehicle, speed=speed)
        yield env, TrafficDriver(env, scen, ctrl, speed, config, scenario_rngs(scen.seed)[1])
    finally:
        env.close()


@contextmanager
def _driving(scen: OvertakeTrafficTask, config: ReplanConfig = SEEDED) -> Iterator[TrafficDriver]:
    """A pure-pursuit traffic driver in the scene of ``scen`` (built, not started)."""
    with _scene(scen, config) as (_, driver):
        yield driver


#: Oncoming cars far down the road (they do not bear on the first plan; tests move them).
FAR_ONCOMING = tuple((1000.0 + 12.0 * k, 8.0) for k in range(20))


@contextmanager
def _overtaking(config: ReplanConfig = SEEDED) -> Iterator[TrafficDriver]:
    """A driver that accepted an overtake of a lead at 2 m/s at its first cycle (t = 0)."""
    scen = _road(Pose(5.0, 44.0, 0.0), lead_gap=12.0, lead_speed=2.0, ego_speed=2.0,
                 oncoming=FAR_ONCOMING)
    with _driving(scen, config) as driver:
        driver.start()
        driver.control(0.0)
        assert driver.records[-1].outcome == "overtake" and driver.mode == "overtake"
        yield driver


def _body(pose: Sequence[float], driver: TrafficDriver) -> shapely.Polygon:
    """The ego's body at a rear-axle pose, as a shapely polygon."""
    return shapely.Polygon(footprint_corners(np.asarray(pose, dtype=float), driver.vehicle))


def _box(x: float, y: float, length: float, width: float) -> shapely.Polygon:
    """An axis-aligned car body centred at ``(x, y)``."""
    return shapely.box(x - length / 2, y - width / 2, x + length / 2, y + width / 2)


# --------------------------------------------------------------------------- sim.traffic_driver


def test_the_follow_reference_stops_at_the_end_of_the_road() -> None:
    """Near the end of the road the lane reference ends on the road, not 200 m past it.

    Reference: the road's own bounds (the map, x in [0, 1500]); the ego starts 100 m
    before the end, where the default 200 m lane extension would overrun it.
    """
    scen = _road(Pose(1400.0, 44.0, 0.0), lead_gap=40.0, max_time_s=5.0)
    xmax = scen.map.bounds[2]
    with _driving(scen) as driver:
        driver.start()
        assert driver.path is not None
        xs = driver.path.samples[:, 0]
        assert xs.max() <= xmax - 1.0 + 1e-9  # one metre short of the end, as documented
        assert xs.max() >= xmax - 1.0 - 0.25  # and all the road there is up to it


@pytest.mark.parametrize("steer", [-0.08, 0.05])
def test_the_first_reference_starts_on_the_curvature_the_wheels_steer(steer: float) -> None:
    """A car whose wheels are turned at the start joins the lane from that curvature.

    Reference: the kinematic bicycle, ``kappa = tan(steer) / wheelbase``; the merge is
    continuous in curvature so the controller need not swing the wheels at once.
    """
    scen = _road(Pose(5.0, 44.0, 0.0))
    with _driving(scen) as driver:
        driver.ego.steer = steer
        driver.start()
        assert driver.path is not None
        kappa0 = math.tan(steer) / scen.vehicle.wheelbase
        assert driver.path.samples[0, 3] == pytest.approx(kappa0, rel=1e-6)


def test_the_overtake_ends_once_the_ego_is_past_the_cut_in_point() -> None:
    """Mode ``follow`` again as soon as the rear axle passes the cut-in point, not later.

    The cut-in point is the cycle's ``goal_x`` on the lane centre line (where the plan
    rejoins the lane); the ego is put 0.5 m before it, then 0.25 m past it.
    """
    with _overtaking() as driver:
        goal_x = driver.records[-1].goal_x
        assert goal_x is not None
        lane_y = driver.lane_y
        driver.ego.set_pose(Pose(goal_x - 0.5, lane_y, 0.0))
        driver.control(0.05)
        assert driver.mode == "overtake"
        driver.ego.set_pose(Pose(goal_x + 0.25, lane_y, 0.0))
        driver.control(0.10)
        assert driver.mode == "follow"
        assert driver.modes[-1] == (0.10, "follow")


def test_a_car_stopped_on_the_last_metres_of_the_plan_makes_it_unsafe() -> None:
    """The safety check covers the plan up to its check end (10 m past the cut-in point).

    The lead car is stopped 8 m past the cut-in point and the ego is 1 m past it:
    shapely confirms the ego's body on the rest of the reference runs into the stopped
    car within those 10 m, so the plan must fail its check.
    """
    with _overtaking() as driver:
        goal_x = driver.records[-1].goal_x
        assert goal_x is not None
        lead = driver.lead
        lead.position = np.array([goal_x + 8.0, driver.lane_y])
        lead.heading, lead.speed = 0.0, 0.0
        driver.ego.set_pose(Pose(goal_x + 1.0, driver.lane_y, 0.0))
        rows = driver.path.samples  # type: ignore[union-attr]
        ahead = rows[(rows[:, 0] >= goal_x + 1.0) & (rows[:, 0] <= goal_x + 10.0)]
        stopped = _box(goal_x + 8.0, driver.lane_y, lead.LENGTH, lead.WIDTH)
        assert any(_body(r[:3], driver).intersects(stopped) for r in ahead)
        assert not driver.current_safe()


@pytest.mark.parametrize(("ego_y", "expected"), [(44.0, "abandoned"), (46.0, "unsafe_kept")])
def test_an_unsafe_plan_is_abandoned_only_with_the_whole_body_in_the_own_lane(
    ego_y: float, expected: str
) -> None:
    """No way on and the plan unsafe: back to following only from inside the ego lane.

    Oncoming cars are moved beside the ego every 12 m (no overtake can pass them). With
    the body inside its lane (shapely: within the lane's strip) the driver abandons the
    plan for following; with the body across the centre line it keeps the plan.
    """
    with _overtaking() as driver:
        x = float(driver.ego.rear[0]) + 2.0
        driver.ego.set_pose(Pose(x, ego_y, 0.0))
        for k, car in enumerate(driver.others[1:]):
            car.position = np.array([x - 30.0 + 12.0 * k, driver.lane_y + driver.lane_width])
        edge = driver.lane_y + driver.lane_width / 2.0
        own_lane = shapely.box(-1e4, edge - 100.0, 1e4, edge)
        inside = own_lane.contains(_body((x, ego_y, 0.0), driver))
        assert inside == (expected == "abandoned")
        record = driver.replan(0.05, "unsafe")
        assert record.outcome == expected
        assert driver.mode == ("follow" if inside else "overtake")


def test_a_rejected_reference_names_the_point_of_conflict_on_it() -> None:
    """The reason given for a rejected reference is ``conflict at (x, y)`` of a row on it.

    A car stands in the lane 20 m ahead; the reported point lies on the lane reference
    (within the message's 0.1 m rounding) and behind the car's rear bumper (shapely:
    the ego's body there does not yet reach the car's).
    """
    scen = _road(Pose(5.0, 44.0, 0.0), lead_gap=60.0, lead_speed=2.0, ego_speed=2.0)
    with _driving(scen) as driver:
        driver.start()
        rear = driver.ego.rear
        path = lane_path(float(rear[0]), float(rear[0]) + 30.0, driver.lane_y)
        x_car = float(rear[0]) + 20.0
        size = (driver.vehicle.length, driver.vehicle.width)
        standing = Prediction.constant_velocity(
            np.array([[x_car, driver.lane_y, 0.0, 0.0]]), [size], 12.0
        )
        ok, _, why = driver._validate(path, len(path.samples) - 1, standing)
        assert not ok
        found = re.fullmatch(r"conflict at \((-?[\d.]+), (-?[\d.]+)\)", why)
        assert found is not None, why
        x, y = float(found[1]), float(found[2])
        assert np.hypot(path.samples[:, 0] - x, path.samples[:, 1] - y).min() <= 0.08
        body = _body((x, y, 0.0), driver)
        assert not body.intersects(_box(x_car, driver.lane_y, *size))


def test_a_taken_oncoming_lane_beside_the_lead_is_no_gap_and_nothing_is_planned() -> None:
    """Oncoming cars nose to tail beside the lead: the cycle says ``no_gap``, the planner idle.

    Reference: the cars' own highway-env positions and speeds. At every time of the
    horizon some car's body (driving on at its speed) overlaps the lead's stretch of
    road in x, so no overtake can be beside the lead then; the driver must say so
    without running the planner (0 iterations, no planning time) and keep following.
    """
    scen = _road(Pose(5.0, 44.0, 0.0), lead_gap=12.0, lead_speed=2.0, ego_speed=2.0,
                 oncoming=FAR_ONCOMING)
    with _driving(scen) as driver:
        driver.start()
        lead = driver.lead
        x0 = float(lead.position[0])
        cars = driver.others[1:]
        for k, car in enumerate(cars):
            car.position = np.array([x0 - 20.0 + 8.0 * k, driver.lane_y + driver.lane_width])
        for t in np.arange(0.0, driver.config.horizon_s + 1e-9, 0.1):
            lead_x = x0 + float(lead.speed) * t
            reach = [(c.LENGTH + lead.LENGTH) / 2 for c in cars]
            xs = [float(c.position[0]) - float(c.speed) * t for c in cars]
            beside = [abs(x - lead_x) < r for x, r in zip(xs, reach, strict=True)]
            assert any(beside), t
        record = driver.replan(0.0, "periodic")
        assert record.outcome == "no_gap"
        assert record.iterations == 0 and record.planning_time_s == 0.0
        assert driver.mode == "follow"


def test_a_safe_plan_is_kept_unless_a_new_one_is_sooner_by_improve_s() -> None:
    """With ``improve_s`` = 100 s no safe plan is ever replaced by a periodic cycle.

    Every cycle after the first overtake plan runs while that plan stays safe (no
    oncoming car near, no unsafe step); none may replace it, as no new plan can reach
    the cut-in point 100 s sooner than the current one.
    """
    scen = _road(Pose(5.0, 44.0, 0.0), lead_gap=12.0, lead_speed=2.0, ego_speed=2.0,
                 oncoming=FAR_ONCOMING)
    with _scene(scen, dataclasses.replace(SEEDED, improve_s=100.0)) as (env, driver):
        driver.start()
        dt = 1.0 / env.unwrapped.config["simulation_frequency"]
        recorder = DriveRecorder(env, dt)
        for k in range(60):
            recorder.step(*driver.control(k * dt))
        assert driver.unsafe_steps == 0
        later = [r for r in driver.records if r.mode == "overtake"]
        assert driver.records[0].outcome == "overtake" and len(later) >= 8
        assert all(r.outcome != "overtake" for r in later)
        assert any(r.outcome == "kept" for r in later)  # safe plans were found, and kept


def test_an_unsafe_plan_gives_way_to_any_safe_new_one() -> None:
    """A plan that became unsafe is replaced by a safe new one, sooner or not.

    The lead car speeds up from 2 to 3 m/s after the first plan: it would now be
    beside the ego at the plan's cut-in. With ``improve_s`` = 100 s no new plan is
    "sooner", yet the unsafe one must go: the cycle accepts the new plan, which passes
    the check.
    """
    with _overtaking(dataclasses.replace(SEEDED, improve_s=100.0)) as driver:
        driver.lead.speed = driver.lead.target_speed = 3.0
        assert not driver.current_safe()
        record = driver.replan(0.05, "periodic")
        assert record.outcome == "overtake" and driver.mode == "overtake"
        assert driver.current_safe()


@pytest.mark.parametrize(("pull_out_speed", "tried"), [(0.0, False), (0.5, True)])
def test_a_pull_out_speed_of_zero_never_pulls_out(pull_out_speed: float, tried: bool) -> None:
    """``pull_out_speed`` 0 means never, even behind a lead standing still.

    The lead stands 12 m ahead; the planner is given a single iteration so that it
    finds nothing, and the cycle tries the pull-out only when the lead is slower than
    ``pull_out_speed`` (0 < 0.5), never when the setting is 0.
    """
    scen = _road(Pose(5.0, 44.0, 0.0), lead_gap=12.0, lead_speed=2.0, ego_speed=0.0)
    config = dataclasses.replace(SEEDED, max_iterations=1, pull_out_speed=pull_out_speed)
    with _driving(scen, config) as driver:
        driver.lead.speed = driver.lead.target_speed = 0.0
        driver.start()
        record = driver.replan(0.0, "periodic")
        pulled = record.message == "pull-out past the slow lead" or "pull-out:" in record.message
        assert pulled == tried, record
        if not tried:
            assert record.outcome == "no_plan" and driver.mode == "follow"


def test_a_pull_out_is_checked_on_past_its_cut_in_point() -> None:
    """The pull-out's check runs on ``check_beyond_m`` (10 m) past where it cuts back in.

    Behind a standing lead the planner (one iteration) finds nothing and the pull-out
    is accepted on an empty road. With a car standing 8 m past that cut-in point
    (shapely: the ego's body on the next 10 m of the path runs into it) the same
    pull-out must be refused.
    """
    config = dataclasses.replace(SEEDED, max_iterations=1)

    def cycle(blocker_x: float | None) -> tuple[str, TrafficDriver]:
        scen = _road(Pose(5.0, 44.0, 0.0), lead_gap=12.0, lead_speed=2.0, ego_speed=0.0,
                     oncoming=[(1000.0, 8.0)])
        with _driving(scen, config) as driver:
            driver.lead.speed = driver.lead.target_speed = 0.0
            if blocker_x is not None:
                car = driver.others[1]
                car.position = np.array([blocker_x, driver.lane_y])
                car.heading, car.speed, car.target_speed = 0.0, 0.0, 0.0
            driver.start()
            return driver.replan(0.0, "periodic").message, driver

    message, driver = cycle(None)
    assert message == "pull-out past the slow lead"
    rows = driver.path.samples  # type: ignore[union-attr]
    out = np.flatnonzero(rows[:, 1] > driver.lane_y + 1e-6)
    x_cut = float(rows[out[-1] + 1, 0])
    blocker = _box(x_cut + 8.0, driver.lane_y, driver.vehicle.length, driver.vehicle.width)
    ahead = rows[(rows[:, 0] >= x_cut) & (rows[:, 0] <= x_cut + 10.0)]
    assert any(_body(r[:3], driver).intersects(blocker) for r in ahead)
    message, driver = cycle(x_cut + 8.0)
    assert "pull-out: conflict at" in message and driver.mode == "follow"
