"""The ego car: the rear-axle bicycle of SPEC §1 inside highway-env."""

from __future__ import annotations

import math

import numpy as np
import pytest
from highway_env.road.lane import StraightLane
from highway_env.road.road import Road, RoadNetwork
from highway_env.vehicle.kinematics import Vehicle

from rrtdrive.sim.ego import EgoVehicle, centre_to_rear_axle, rear_axle_to_centre
from rrtdrive.sim.scenes import build_env
from rrtdrive.sim.tasks import make_scenario
from rrtdrive.types import Pose, VehicleParams
from rrtdrive.vehicle import footprint_corners

#: Instant steering: these tests are about the bicycle model, not the actuator.
INSTANT = VehicleParams(max_steer_rate=None)


def _road() -> Road:
    net = RoadNetwork()
    net.add_lane("a", "b", StraightLane([0.0, 0.0], [200.0, 0.0]))
    return Road(net, np_random=np.random.RandomState(0))


def _drive(ego: EgoVehicle, road: Road, steps: int, dt: float) -> np.ndarray:
    out = []
    for _ in range(steps):
        road.act()
        road.step(dt)
        out.append(list(ego.rear))
    return np.array(out)


@pytest.mark.parametrize("steer_deg", [5.0, 15.0, 22.0, 30.0, -18.0])
@pytest.mark.parametrize("hz", [15, 20])
def test_constant_steering_drives_circle_of_radius_L_over_tan_delta(steer_deg, hz):
    road = _road()
    ego = EgoVehicle(road, Pose(0.0, 0.0, 0.0), speed=4.0, vehicle=INSTANT)
    road.vehicles.append(ego)
    delta = math.radians(steer_deg)
    ego.act({"acceleration": 0.0, "steering": delta})
    radius = 2.51 / math.tan(abs(delta))
    steps = int(2.2 * math.pi * radius / 4.0 * hz)  # a bit more than one lap
    rear = _drive(ego, road, steps, 1.0 / hz)
    centre_y = math.copysign(radius, delta)
    r = np.hypot(rear[:, 0], rear[:, 1] - centre_y)
    assert np.all(np.abs(r - radius) <= 0.01 * radius)
    # Exact integration: much better than the 1 % target.
    assert np.max(np.abs(r - radius)) < 1e-6


def test_highway_env_vehicle_is_a_different_model():
    """The stock Vehicle (CoG, wheelbase = length) turns on another radius at the same angle."""
    road = _road()
    stock = Vehicle(road, [0.0, 0.0], 0.0, 4.0)
    road.vehicles.append(stock)
    stock.act({"acceleration": 0.0, "steering": math.radians(20.0)})
    pts = []
    for _ in range(300):
        stock.step(1.0 / 15)
        pts.append(stock.position.copy())
    pts = np.array(pts)
    # Fit a circle: centre on the y axis through the start.
    c = (pts[:, 0] ** 2 + pts[:, 1] ** 2) / (2 * pts[:, 1])
    stock_radius = float(np.median(np.abs(c)))
    ours = 2.51 / math.tan(math.radians(20.0))
    assert abs(stock_radius - ours) / ours > 0.3


def test_true_size_and_reference_point():
    road = _road()
    pose = Pose(3.0, -1.0, 0.7)
    ego = EgoVehicle(road, pose)
    v = VehicleParams()
    assert (ego.LENGTH, ego.WIDTH) == (4.30, 1.80)
    assert ego.diagonal == pytest.approx(math.hypot(4.3, 1.8))
    assert EgoVehicle.LENGTH == 4.30  # highway-env's default class would be 5.0
    # highway-env's polygon (used for its collisions) is our footprint rectangle.
    poly = ego.polygon()[:4]
    ours = footprint_corners(np.array(pose.as_tuple()), v)
    for corner in ours:
        assert np.min(np.hypot(*(poly - corner).T)) < 1e-9
    cx, cy = rear_axle_to_centre(pose, v)
    assert np.allclose(ego.position, [cx, cy])
    back = centre_to_rear_axle(cx, cy, pose.yaw, v)
    assert back.x == pytest.approx(pose.x) and back.y == pytest.approx(pose.y)


def test_steering_is_clipped_to_30_degrees():
    road = _road()
    ego = EgoVehicle(road, Pose(0.0, 0.0, 0.0), speed=2.0, vehicle=INSTANT)
    road.vehicles.append(ego)
    ego.act({"acceleration": 0.0, "steering": math.radians(60.0)})
    road.step(0.05)
    assert ego.steer == pytest.approx(math.radians(30.0))


def test_braking_stops_without_reversing():
    road = _road()
    ego = EgoVehicle(road, Pose(0.0, 0.0, 0.0), speed=1.0)
    road.vehicles.append(ego)
    ego.act({"acceleration": -10.0, "steering": 0.0})
    road.step(0.5)
    assert ego.speed == 0.0
    # Stopped after 0.1 s having covered v^2 / (2 a) = 0.05 m.
    assert ego.rear[0] == pytest.approx(0.05)


def test_speed_ramp_is_exact():
    road = _road()
    ego = EgoVehicle(road, Pose(0.0, 0.0, 0.0), speed=0.0)
    road.vehicles.append(ego)
    ego.act({"acceleration": 1.0, "steering": 0.0})
    _drive(ego, road, 20, 0.05)
    assert ego.speed == pytest.approx(1.0)
    assert ego.rear[0] == pytest.approx(0.5)  # a t^2 / 2


def test_env_step_drives_the_ego_through_continuous_action():
    env = build_env(make_scenario("overtake", 0))
    u = env.unwrapped
    ego = u.vehicle
    assert isinstance(ego, EgoVehicle)
    x0 = ego.rear[0]
    for _ in range(20):
        env.step(np.array([1.0, 0.0], dtype=np.float32))
    assert ego.speed > 0.5 and ego.rear[0] > x0
    env.close()


def test_highway_env_flags_a_crash_into_the_stopped_car():
    scen = make_scenario("overtake", 0, jitter=(0.0, 0.0, 0.0))
    env = build_env(scen)
    u = env.unwrapped
    ego = u.vehicle
    ego.act({"acceleration": 2.0, "steering": 0.0})
    for _ in range(400):
        u.road.act()
        u.road.step(0.05)
        if ego.crashed:
            break
    assert ego.crashed
    lead = scen.map.obstacles[scen.lead_index]
    # It hit the car's rear bumper (within the last step's travel).
    front = ego.rear[0] + VehicleParams().front_extent
    assert lead.corners()[:, 0].min() - 1.0 < front < lead.corners()[:, 0].min() + 0.5
    env.close()
