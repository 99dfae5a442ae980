"""Prediction of other vehicles: constant velocity, highway-env's lane following, speed bound."""

from __future__ import annotations

import math

import numpy as np
import pytest
from highway_env.road.road import Road, RoadNetwork
from highway_env.vehicle.kinematics import Vehicle

from rrtdrive.planning.spacetime import Prediction
from rrtdrive.sim.prediction import PREDICTORS, predict, vehicle_states
from rrtdrive.sim.scenes import OncomingCar, build_env
from rrtdrive.sim.tasks import make_scenario
from rrtdrive.types import InputError


@pytest.fixture(scope="module")
def traffic_env():
    env = build_env(make_scenario("overtake-traffic", 2))
    yield env
    env.close()


def test_constant_velocity_grid_interpolation_and_extrapolation():
    states = np.array([[0.0, 0.0, 0.0, 2.0], [10.0, 4.0, math.pi, 5.0]])
    p = Prediction.constant_velocity(states, [(4.3, 1.8), (5.0, 2.0)], 3.0, 0.1)
    assert len(p) == 2 and p.horizon == pytest.approx(3.0) and p.step == pytest.approx(0.1)
    at = p.poses_at(np.array([0.0, 1.25, 3.0, 4.0]))  # 4 s lies past the horizon
    assert at[0, :, 0] == pytest.approx([0.0, 2.5, 6.0, 8.0])
    assert at[1, :, 0] == pytest.approx([10.0, 3.75, -5.0, -10.0])
    assert np.allclose(at[1, :, 1], 4.0) and np.allclose(at[1, :, 2], math.pi)
    assert p.poses_at(np.array([-1.0]))[0, 0, 0] == pytest.approx(0.0)  # before 0: the start
    moved = p.shifted(-10.0, 1.0)
    assert moved.poses[0, 0, :2].tolist() == [-10.0, 1.0]
    assert len(p.select(np.array([False, True]))) == 1
    assert p.x_range()[1].tolist() == pytest.approx([-5.0, 10.0])


def test_prediction_validation():
    with pytest.raises(InputError, match="times"):
        Prediction(np.array([0.0, 0.1, 0.3]), np.zeros((1, 3, 3)), np.ones((1, 2)))
    with pytest.raises(InputError, match="sizes"):
        Prediction(np.array([0.0, 0.1]), np.zeros((2, 2, 3)), np.ones((1, 2)))
    with pytest.raises(InputError, match="horizon"):
        Prediction.constant_velocity(np.zeros((1, 4)), [(4.3, 1.8)], 0.0)
    assert len(Prediction.empty()) == 0


def test_lane_following_is_highway_envs_prediction(traffic_env):
    u = traffic_env.unwrapped
    cars = [v for v in u.road.vehicles if isinstance(v, OncomingCar)]
    oncoming = cars[1]
    # Off the lane centre and turned a little: lane following returns to the lane's line.
    oncoming.position = oncoming.position + np.array([0.0, 0.6])
    oncoming.heading = math.pi - 0.1
    lf = predict([oncoming], "lane-following", horizon=4.0, speed_bound=False)
    cv = predict([oncoming], "constant-velocity", horizon=4.0, speed_bound=False)
    times = lf.times
    positions, headings = oncoming.predict_trajectory_constant_speed(times)
    assert np.allclose(lf.poses[0, :, :2], np.asarray(positions))
    assert np.allclose(lf.poses[0, :, 2], headings)
    assert np.allclose(lf.poses[0, 1:, 1], 48.0)  # on the oncoming lane's centre
    assert not np.allclose(cv.poses[0, -1, 1], 48.0)  # constant velocity drifts off
    assert set(PREDICTORS) == {"constant-velocity", "lane-following"}


def test_plain_vehicle_falls_back_to_constant_velocity():
    road = Road(RoadNetwork.straight_road_network(1))
    car = Vehicle(road, [0.0, 0.0], heading=0.2, speed=5.0)
    lf = predict([car], "lane-following", horizon=2.0)
    assert lf.centres_at(np.array([2.0]))[0, 0] == pytest.approx(
        [10.0 * math.cos(0.2), 10.0 * math.sin(0.2)]
    )
    states, sizes = vehicle_states([car])
    assert states.shape == (1, 4) and sizes[0].tolist() == [car.LENGTH, car.WIDTH]


def test_speed_bound_adds_the_target_speed_for_a_braked_car(traffic_env):
    u = traffic_env.unwrapped
    car = [v for v in u.road.vehicles if isinstance(v, OncomingCar)][2]
    target = float(car.target_speed)
    assert predict([car]).alt is None  # at its target speed: one hypothesis
    car.speed = target - 3.0  # braked
    for method in PREDICTORS:
        both = predict([car], method, horizon=2.0)
        slow = predict([car], method, horizon=2.0, speed_bound=False)
        assert slow.alt is None and np.allclose(both.poses, slow.poses)
        moved_now = abs(both.poses[0, -1, 0] - both.poses[0, 0, 0])
        moved_fast = abs(both.alt[0, -1, 0] - both.alt[0, 0, 0])
        assert moved_now == pytest.approx(2.0 * (target - 3.0), rel=1e-6)
        assert moved_fast == pytest.approx(2.0 * target, rel=1e-6)
        shifted = both.shifted(5.0)
        assert np.allclose(shifted.alt[..., 0], both.alt[..., 0] + 5.0)
        assert both.select(np.array([True])).alt is not None
        assert both.x_range()[0, 0] == pytest.approx(both.alt[0, :, 0].min())
    car.speed = target


def test_bad_predictor_names():
    with pytest.raises(InputError, match="predictor"):
        predict([], "telepathy")
