"""The steering actuator: VehicleParams.max_steer_rate slews the ego's front-wheel angle."""

from __future__ import annotations

import math

import numpy as np
import pytest
from highway_env.road.lane import StraightLane
from highway_env.road.road import Road, RoadNetwork

from rrtdrive.evaluation import evaluate
from rrtdrive.sim.ego import EgoVehicle
from rrtdrive.sim.runner import run_episode
from rrtdrive.sim.tasks import make_scenario
from rrtdrive.types import InputError, Pose, VehicleParams

DT = 0.05


def _ego(rate):
    net = RoadNetwork()
    net.add_lane("a", "b", StraightLane([0.0, 0.0], [200.0, 0.0]))
    road = Road(net, np_random=np.random.RandomState(0))
    car = VehicleParams(max_steer_rate=rate)
    ego = EgoVehicle(road, Pose(0.0, 0.0, 0.0), speed=3.0, vehicle=car)
    road.vehicles.append(ego)
    return road, ego


def _steer_series(rate, command, steps):
    road, ego = _ego(rate)
    out = []
    for _ in range(steps):
        ego.act({"acceleration": 0.0, "steering": command})
        road.step(DT)
        out.append(ego.steer)
    return np.array(out)


def test_steering_slews_at_the_rate_and_holds_the_command():
    series = _steer_series(0.4, 0.3, 30)
    assert np.allclose(np.diff(np.r_[0.0, series])[:15], 0.4 * DT)  # 0.02 rad a step
    assert series[-1] == pytest.approx(0.3)  # reached after 0.75 s, then held
    assert np.all(np.abs(np.diff(np.r_[0.0, series])) <= 0.4 * DT + 1e-12)


@pytest.mark.parametrize("rate", [None, math.inf])
def test_no_limit_steers_at_once(rate):
    assert _steer_series(rate, 0.3, 3)[0] == pytest.approx(0.3)


@pytest.mark.parametrize("bad", [0.0, -0.4, float("nan"), True, "fast"])
def test_bad_rate_names_the_field(bad):
    with pytest.raises(InputError, match="vehicle.max_steer_rate"):
        VehicleParams(max_steer_rate=bad)


def test_a_rate_limited_parking_episode_stays_within_the_limit():
    task = make_scenario("parking", 0, vehicle=VehicleParams(max_steer_rate=0.4))
    ep = run_episode(task, controller="pure-pursuit", seed=0)
    report = evaluate(ep)
    rates = np.abs(np.diff(np.r_[0.0, ep.log.controls[:, 1]])) / ep.log.dt
    assert rates.max() <= 0.4 + 1e-9
    assert report.steering_rate_over_limit_share == 0.0
    assert report.success and not report.collision
