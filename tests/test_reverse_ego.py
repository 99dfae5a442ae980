"""The ego car in reverse inside highway-env: the rear-axle model, pose, collisions, the log."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely
from highway_env.road.lane import StraightLane
from highway_env.road.road import Road, RoadNetwork
from highway_env.vehicle.objects import Obstacle

from rrtdrive.sim.ego import EgoVehicle
from rrtdrive.sim.episode import driven_gears
from rrtdrive.types import Pose, VehicleParams
from rrtdrive.vehicle import bicycle_step, footprint_corners

RATES = [None, 0.4]


def _road() -> Road:
    net = RoadNetwork()
    net.add_lane("a", "b", StraightLane([-100.0, 0.0], [100.0, 0.0]))
    return Road(net, np_random=np.random.RandomState(0))


def _step(road: Road, dt: float) -> None:
    road.act()
    road.step(dt)


@pytest.mark.parametrize("steer_deg", [10.0, 25.0, -20.0])
def test_reversing_at_constant_steering_drives_the_same_circle_backwards(steer_deg):
    road = _road()
    ego = EgoVehicle(road, Pose(0.0, 0.0, 0.0), speed=-1.5, vehicle=VehicleParams())
    road.vehicles.append(ego)
    delta = math.radians(steer_deg)
    ego.steer = delta  # the wheels already at the angle (also for a rate-limited actuator)
    ego.act({"acceleration": 0.0, "steering": delta})
    radius = 2.51 / math.tan(abs(delta))
    yaws, rear = [], []
    for _ in range(100):
        _step(road, 0.1)
        rear.append(list(ego.rear))
        yaws.append(ego.rear[2])
    rear = np.array(rear)
    # The instantaneous centre lies on the rear axle line on the steered side, in
    # both gears; reversing with left steering turns the nose right (yaw falls).
    r = np.hypot(rear[:, 0], rear[:, 1] - math.copysign(radius, delta))
    assert np.max(np.abs(r - radius)) < 1e-6
    assert np.sign(np.unwrap(yaws)[-1]) == -np.sign(delta)
    # The exact arc: 100 steps of 0.15 m backwards.
    expect = (0.0, 0.0, 0.0)
    for _ in range(100):
        expect = bicycle_step(expect, -1.5, delta, 0.1, 2.51)
    assert np.allclose(rear[-1, :2], expect[:2], atol=1e-9)


@pytest.mark.parametrize("rate", RATES)
def test_reverse_from_rest_and_brake_to_a_stop_without_rolling_forward(rate):
    road = _road()
    ego = EgoVehicle(road, Pose(0.0, 0.0, 0.3), vehicle=VehicleParams(max_steer_rate=rate))
    road.vehicles.append(ego)
    ego.act({"acceleration": -1.0, "steering": 0.0})
    for _ in range(10):
        _step(road, 0.1)
    assert ego.speed == pytest.approx(-1.0)
    # Backwards along the nose heading: 0.5 m behind the start.
    assert ego.rear[0] == pytest.approx(-0.5 * math.cos(0.3))
    assert ego.rear[1] == pytest.approx(-0.5 * math.sin(0.3))
    assert ego.rear[2] == pytest.approx(0.3)
    ego.act({"acceleration": 3.0, "steering": 0.0})
    for _ in range(4):
        _step(road, 0.1)
    # Braking stops at zero within the step (the 4th); it does not turn into driving
    # forward within it (from rest the next command moves the car either way: the
    # controllers never brake at rest).
    assert ego.speed == 0.0
    x_stop = ego.rear[0]
    assert x_stop == pytest.approx(-0.5 * math.cos(0.3) - 1.0 / 6.0 * math.cos(0.3))


@pytest.mark.parametrize("rate", RATES)
def test_pose_and_body_are_right_while_reversing(rate):
    v = VehicleParams(max_steer_rate=rate)
    road = _road()
    ego = EgoVehicle(road, Pose(2.0, 1.0, 2.0), speed=-1.0, vehicle=v)
    road.vehicles.append(ego)
    ego.act({"acceleration": -0.5, "steering": 0.3})
    for _ in range(15):
        _step(road, 0.1)
        x, y, yaw = ego.rear
        d = v.length / 2 - v.rear_overhang
        assert ego.heading == yaw  # the nose, in either gear
        assert np.allclose(ego.position, [x + d * math.cos(yaw), y + d * math.sin(yaw)])
        # highway-env draws and collides this polygon: our exact footprint.
        ours = shapely.Polygon(footprint_corners(np.array([x, y, yaw]), v))
        theirs = shapely.Polygon(ego.polygon()[:4])
        assert ours.symmetric_difference(theirs).area < 1e-9
        assert ego.velocity @ np.array([math.cos(yaw), math.sin(yaw)]) < 0.0


@pytest.mark.parametrize("rate", RATES)
def test_highway_env_flags_backing_into_an_obstacle(rate):
    v = VehicleParams(max_steer_rate=rate)
    road = _road()
    ego = EgoVehicle(road, Pose(0.0, 0.0, 0.0), vehicle=v)
    road.vehicles.append(ego)
    # A block 3 m behind the rear bumper.
    wall = Obstacle(road, [-v.rear_overhang - 3.0 - 0.5, 0.0], heading=0.0)
    wall.LENGTH, wall.WIDTH = 1.0, 4.0
    wall.diagonal = math.hypot(1.0, 4.0)
    road.objects.append(wall)
    ego.act({"acceleration": -1.0, "steering": 0.0})
    dt = 0.1
    first_overlap = None
    for k in range(60):
        _step(road, dt)
        body = shapely.Polygon(footprint_corners(np.array(ego.rear), v))
        if first_overlap is None and body.intersects(shapely.Polygon(wall.polygon()[:4])):
            first_overlap = k
        if ego.crashed:
            break
    assert ego.crashed
    # Flagged no later than the first step whose body touches the block (a contact
    # predicted within the step counts too).
    assert first_overlap is None or k <= first_overlap
    rear_bumper = ego.rear[0] - v.rear_overhang
    face = -v.rear_overhang - 3.0
    assert face - abs(ego.speed) * dt - 0.05 < rear_bumper < face + 0.05
    # After the crash the car brakes straight (highway-env's rule: a = -v), not forward.
    v0, yaw0 = ego.speed, ego.rear[2]
    for _ in range(20):
        _step(road, dt)
    assert v0 < ego.speed <= 0.0 and ego.rear[2] == yaw0


def test_driven_gears_keep_the_gear_at_a_standstill():
    v = np.array([0.0, 0.5, 1.0, 0.2, 0.0, 0.0, -0.3, -1.0, 0.0, 0.4, 0.0])
    g = driven_gears(v)
    assert g.tolist() == [1, 1, 1, 1, 1, 1, -1, -1, -1, 1, 1]
    assert driven_gears(np.array([0.0, 0.0, -1.0])).tolist() == [-1, -1, -1]
    assert driven_gears(np.zeros(3)).tolist() == [1, 1, 1]
