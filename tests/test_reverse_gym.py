"""The gym env across cusps: gear and distance to the next cusp observed, residual, check_env."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from test_gears_closed_loop import _Shuttler

import rrtdrive.envs  # noqa: F401  (registers the envs)
from rrtdrive.controllers import VehicleState, make_controller
from rrtdrive.planning import PLANNERS
from rrtdrive.types import VehicleParams

GEAR, CUSP = -2, -1  # the last two observation entries


@pytest.fixture
def shuttle(monkeypatch):
    monkeypatch.setitem(PLANNERS, "test-shuttle", _Shuttler)


@pytest.mark.parametrize("residual", [False, True])
def test_check_env_on_a_path_with_a_cusp(shuttle, residual):
    env = gym.make("rrtdrive/Parking-v0", planner="test-shuttle", residual=residual)
    check_env(env.unwrapped)
    env.close()


@pytest.mark.parametrize("rate", [None, 0.4])
def test_zero_residual_drives_out_and_back(shuttle, rate):
    env = gym.make(
        "rrtdrive/Parking-v0", planner="test-shuttle", residual=True,
        scenario_options={"vehicle": VehicleParams(max_steer_rate=rate)},
    )
    obs, _ = env.reset(seed=0)
    u = env.unwrapped
    assert obs[GEAR] == 1.0 and obs[CUSP] == pytest.approx(5.0, abs=0.01)
    assert obs[5] == pytest.approx(10.0, abs=0.01)  # the goal: out and back
    seen = [obs]
    while True:
        obs, _, terminated, truncated, info = env.step(np.zeros(2, np.float32))
        seen.append(obs)
        if terminated or truncated:
            break
    assert info["status"] == "arrived"
    seen = np.array(seen)
    flip = int(np.argmax(seen[:, GEAR] < 0))
    assert flip > 0 and np.all(seen[flip:, GEAR] == -1.0)
    # At the cusp: stopped within centimetres of it; then reversing, v_ref < 0.
    assert abs(seen[flip - 1, CUSP]) < 0.06 and abs(seen[flip - 1, 0]) < 0.05
    assert np.all(seen[flip:, 0] <= 0.0) and seen[flip:, 4].min() < -0.5
    assert abs(seen[-1, 5]) < 0.06 and abs(seen[-1, 2]) < 0.05
    assert u.report.gear_changes == 1 and u.report.path_cusps == 1
    env.close()


def test_an_agent_alone_moves_on_to_the_next_segment(shuttle):
    env = gym.make("rrtdrive/Parking-v0", planner="test-shuttle", max_time_s=40.0)
    obs, info = env.reset(seed=0)
    u = env.unwrapped
    ctrl = make_controller("lqr", speed=u._speed, vehicle=u._scenario.vehicle)
    ctrl.reset(u.path)
    lim = u.config.limits
    gears = []
    while True:
        ego = u._ego
        x, y, yaw = ego.rear
        accel, steer = ctrl.control(
            VehicleState(x, y, yaw, ego.speed, ego.steer, info.get("time_s", 0.0))
        )
        action = np.array(
            [accel / lim.a_max if accel >= 0 else accel / -lim.a_min, steer / lim.steer_limit],
            dtype=np.float32,
        )
        obs, _, terminated, truncated, info = env.step(action)
        gears.append(obs[GEAR])
        if ctrl.arrived or terminated or truncated:
            break
    # The env followed the drive onto the reverse segment and measures along it.
    assert gears[0] == 1.0 and gears[-1] == -1.0
    assert abs(obs[5]) < 0.1 and abs(obs[2]) < 0.05 and abs(obs[3]) < 0.02
    env.close()


def test_the_reverse_in_id_plans_a_reverse_entry_into_the_bay():
    env = gym.make("rrtdrive/ParkingReverseIn-v0")
    obs, _ = env.reset(seed=0)
    u = env.unwrapped
    gears = np.asarray(u.path.gears)
    nose_in = gym.make("rrtdrive/Parking-v0")
    nose_in.reset(seed=0)
    # The same bay, parked facing out: the goal is turned round, and the car
    # reverses into it (possibly with a short forward shuffle at the end).
    turned = abs(abs(u._scenario.goal.yaw - nose_in.unwrapped._scenario.goal.yaw) - np.pi)
    assert turned < 1e-9
    assert gears[0] == 1 and (gears == -1).any() and (np.diff(gears) != 0).any()
    assert obs[-2] == 1.0  # the first segment is driven forward
    assert u.config.planner == "hybrid-a-star"
    env.close()
    nose_in.close()


@pytest.mark.parametrize("env_id", ["rrtdrive/ParkingReverseIn-v0", "rrtdrive/ParallelParking-v0"])
def test_a_car_rolling_back_at_the_start_stays_on_its_segment(env_id):
    # A light brake at rest rolls the car back a centimetre: far from the cusp, that is
    # no gear change of the path (it used to start the reverse segment 11-50 m away and
    # end the episode off the path at once).
    env = gym.make(env_id)
    obs, _ = env.reset(seed=0)
    cusp = obs[CUSP]
    assert obs[GEAR] == 1.0 and cusp > 1.0
    for _ in range(5):
        obs, _, terminated, _, info = env.step(np.array([-0.05, 0.0], dtype=np.float32))
        assert not terminated, info
    assert env.unwrapped._ego.speed < 0.0  # it did roll back
    assert obs[GEAR] == 1.0 and obs[CUSP] == pytest.approx(cusp, abs=0.05)
    env.close()


def test_a_reversing_scenario_with_a_forward_planner_warns():
    # UTurn-v0 plans with gear changes; a forward-only planner's episodes crashed with no
    # word of why (a user audit, session 35): gym.make warns, naming the planners that do.
    import warnings

    from rrtdrive.types import InputWarning

    with pytest.warns(InputWarning, match="rrt plans forward only; the u-turn scenario's"):
        gym.make("rrtdrive/UTurn-v0", planner="rrt").close()
    with warnings.catch_warnings():
        warnings.simplefilter("error", InputWarning)
        gym.make("rrtdrive/UTurn-v0").close()  # the default reverses
        gym.make("rrtdrive/Parking-v0", planner="rrt").close()  # parking drives forward
