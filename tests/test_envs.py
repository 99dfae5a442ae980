"""The gymnasium environments: registration, check_env, vector envs, determinism, residual mode."""

from __future__ import annotations

import copy
import dataclasses
import json
import math
import pickle
import re
import subprocess
import sys
import warnings

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import rrtdrive
from rrtdrive.controllers import VehicleState, make_controller
from rrtdrive.envs import (
    ENV_IDS,
    ENV_KWARGS,
    MAP_ID,
    REGISTERED_SCENARIO,
    REGISTERED_SCENARIO_OPTIONS,
)
from rrtdrive.envs.config import DriveEnvConfig
from rrtdrive.envs.drive_env import DriveEnv
from rrtdrive.envs.observation import observation_names
from rrtdrive.envs.reward import RewardWeights
from rrtdrive.evaluation import evaluate
from rrtdrive.sim.runner import run_episode
from rrtdrive.sim.tasks import SCENARIOS
from rrtdrive.sim.video import frame_is_blank
from rrtdrive.types import InputError

# Wall-clock fields and the controller label differ by construction.
NOT_COMPARED = {"wall_time_s", "planning_time_s", "controller"}


def run_to_end(env, policy, **reset_kwargs):
    obs, info = env.reset(**reset_kwargs)
    total, steps = 0.0, 0
    while True:
        obs, reward, terminated, truncated, info = env.step(policy(obs))
        total += reward
        steps += 1
        if terminated or truncated:
            return obs, total, steps, info


def zero(_obs):
    return np.zeros(2, dtype=np.float32)


def test_import_registers_ids_without_highway_env_or_pygame():
    code = (
        "import sys, gymnasium as gym, rrtdrive\n"
        "ids = [k for k in gym.registry if k.startswith('rrtdrive/')]\n"
        "assert sorted(ids) == sorted(rrtdrive.ENV_IDS), ids\n"
        "bad = [m for m in sys.modules if m.split('.')[0] in ('highway_env', 'pygame')]\n"
        "assert not bad, bad\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True)


def test_every_scenario_has_an_env_id():
    # Adding a scenario to sim.tasks.SCENARIOS needs one line in envs/__init__.py: ENV_IDS.
    # Map-v0 drives a map (the parking lot unless ``scenario`` names another).
    assert sorted(set(ENV_IDS.values()) - {"parking_lot"}) == sorted(SCENARIOS)
    assert ENV_IDS["rrtdrive/Map-v0"] == "parking_lot"
    for env_id, scenario in ENV_IDS.items():
        spec = gym.spec(env_id)
        assert spec.entry_point == "rrtdrive.envs.drive_env:DriveEnv"
        # Registered scenario_options go under their own keyword (merged, not replaced).
        extra = {
            REGISTERED_SCENARIO_OPTIONS if k == "scenario_options" else k: v
            for k, v in ENV_KWARGS.get(env_id, {}).items()
        }
        if env_id != MAP_ID:  # its scenario once more, to refuse a caller's other one
            extra[REGISTERED_SCENARIO] = scenario
        assert spec.kwargs == {"scenario": scenario, **extra}


@pytest.mark.parametrize("env_id", sorted(ENV_IDS))
@pytest.mark.parametrize("residual", [False, True])
def test_check_env(env_id, residual):
    env = gym.make(env_id, render_mode="rgb_array", residual=residual)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        check_env(env.unwrapped)
    env.close()
    assert not [str(w.message) for w in caught if "gymnasium" in w.filename.replace("\\", "/")]


def test_spaces_and_observation_layout():
    env = gym.make("rrtdrive/Overtake-v0", n_ref_points=4, ref_spacing=2.0)
    assert env.action_space == gym.spaces.Box(-1.0, 1.0, (2,), np.float32)
    assert env.observation_space.shape == (6 + 3 * 4 + 2,)
    assert env.observation_space.dtype == np.float32
    assert len(observation_names(4)) == 20
    obs, info = env.reset(seed=0)
    assert obs.dtype == np.float32 and obs in env.observation_space
    u = env.unwrapped
    scen = u._scenario
    # At the start: at rest, on the path, the goal a path length away, points ahead.
    assert obs[0] == 0.0 and abs(obs[2]) < 1e-3 and abs(obs[3]) < 1e-3
    assert obs[5] == pytest.approx(u.path.length, rel=1e-4)
    assert info["path_length_m"] == pytest.approx(u.path.length)
    ref = obs[6:14].reshape(4, 2)
    assert np.allclose(ref[:, 0], [2.0, 4.0, 6.0, 8.0], atol=0.05)  # straight ahead first
    assert np.all(np.abs(obs[14:18]) <= scen.vehicle.kappa_max + 1e-6)
    # A forward path: gear +1, the next stop is the goal.
    assert obs[18] == 1.0 and obs[19] == obs[5]
    env.close()


def _vehicles_from_log(log, k, m, rng):
    """The vehicle part of the observation after step k, from the episode's log alone."""
    x, y, yaw, v = log.states[k]
    c, s = np.cos(yaw), np.sin(yaw)
    out = np.zeros((m, 5))
    others = log.others[k]
    d = np.hypot(others[:, 0] - x, others[:, 1] - y)
    order = [i for i in np.argsort(d, kind="stable") if d[i] <= rng][:m]
    for j, i in enumerate(order):
        ox, oy, oh, ov = others[i]
        dvx, dvy = ov * np.cos(oh) - v * np.cos(yaw), ov * np.sin(oh) - v * np.sin(yaw)
        dx, dy = ox - x, oy - y
        out[j] = (1.0, c * dx + s * dy, -s * dx + c * dy, c * dvx + s * dvy, -s * dvx + c * dvy)
    return out.reshape(-1)


def test_observation_of_other_vehicles():
    m, k = 3, 2
    env = gym.make("rrtdrive/OvertakeTraffic-v0", n_ref_points=k, n_vehicles=m,
                   vehicle_range=60.0, residual=True, max_time_s=4.0)
    assert env.observation_space.shape == (6 + 3 * k + 5 * m + 2,)
    names = observation_names(k, m)
    assert len(names) == 6 + 3 * k + 5 * m + 2 and names[6 + 3 * k] == "veh_present_1"
    obs, _ = env.reset(seed=3)
    seen = [obs]
    done = False
    while not done:
        obs, _, terminated, truncated, _ = env.step(np.zeros(2, np.float32))
        assert obs in env.observation_space
        seen.append(obs)
        done = terminated or truncated
    log = env.unwrapped.episode.log
    assert log.others.shape[1] >= m  # the lead car and oncoming cars exist
    for step, o in enumerate(seen):
        expect = _vehicles_from_log(log, step, m, 60.0).astype(np.float32)
        assert np.allclose(o[6 + 3 * k : 6 + 3 * k + 5 * m], expect, atol=1e-4), step
    first = seen[0][6 + 3 * k : 6 + 3 * k + 5 * m].reshape(m, 5)
    assert first[0, 0] == 1.0 and first[0, 1] > 0  # the lead car ahead, nearest
    env.close()
    # No other vehicles (parking: parked cars are obstacles): every slot empty.
    park = gym.make("rrtdrive/Parking-v0", n_vehicles=2)
    obs, _ = park.reset(seed=0)
    assert obs.shape == (6 + 30 + 10 + 2,) and not obs[36:46].any()
    park.close()
    with pytest.raises(InputError, match="n_vehicles"):
        gym.make("rrtdrive/Overtake-v0", n_vehicles=-1)
    with pytest.raises(InputError, match="vehicle_range"):
        gym.make("rrtdrive/Overtake-v0", n_vehicles=1, vehicle_range=0.0)


def test_a_map_whose_start_is_already_at_the_goal_is_refused_for_an_agent(tmp_path):
    # The goal 0.3 m ahead: an agent's episode ended on its first step, whose infos
    # (NaN for metrics that do not apply) failed check_env's determinism check.
    f = tmp_path / "tiny.json"
    f.write_text(json.dumps({"name": "tiny", "bounds": [0, 0, 5, 2], "obstacles": [],
                             "start": [1.0, 1.0, 0.0], "goal": [1.3, 1.0, 0.0]}))
    env = gym.make("rrtdrive/Map-v0", scenario=str(f))
    with pytest.raises(InputError, match=r"^goal: the start is already at the goal"):
        env.reset(seed=1)
    env.close()
    # A controller drives the 0.3 m path (residual mode): the episode runs.
    env = gym.make("rrtdrive/Map-v0", scenario=str(f), residual=True)
    check_env(env.unwrapped, skip_render_check=True)
    env.close()


def test_check_env_with_vehicles():
    env = gym.make("rrtdrive/OvertakeTraffic-v0", n_vehicles=4, residual=True)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        check_env(env.unwrapped)
    env.close()
    assert not [str(w.message) for w in caught if "gymnasium" in w.filename.replace("\\", "/")]


@pytest.mark.parametrize("mode", ["sync", "async"])
def test_make_vec(mode):
    envs = gym.make_vec(
        "rrtdrive/Overtake-v0", num_envs=2, vectorization_mode=mode, residual=True, max_time_s=0.3
    )
    try:
        obs, info = envs.reset(seed=3)
        assert obs.shape == (2, envs.single_observation_space.shape[0])
        assert obs.dtype == np.float32
        assert info["episode_seed"][0] != info["episode_seed"][1]
        ended = False
        for _ in range(8):  # 0.3 s = 6 steps at 20 Hz, then the autoreset step
            obs, reward, terminated, truncated, info = envs.step(np.zeros((2, 2), np.float32))
            assert obs.shape[0] == 2 and reward.shape == (2,)
            if truncated.any():
                ended = True
                assert list(info["status"][truncated]) == ["timeout"] * int(truncated.sum())
                assert np.all(np.isfinite(info["metrics"]["cte_rms_m"][truncated]))
                assert not info["is_success"][truncated].any()
        assert ended
    finally:
        envs.close()


@pytest.mark.parametrize("short_first", [False, True])
def test_a_vector_env_batches_a_metric_that_does_not_apply_as_nan(short_first):
    # Two sub-envs end in the same vector step: one after a single simulation step
    # (nuPlan's comfort needs 0.3 s: it does not apply), one after ten. gymnasium types a
    # batch by its first sub-env's value: a None after a True was batched as False, and
    # a None after a count raised TypeError. Now the same floats in either order.
    from gymnasium.vector import SyncVectorEnv

    makers = [lambda: gym.make("rrtdrive/Parking-v0", max_time_s=0.5, action_repeat=10),
              lambda: gym.make("rrtdrive/Parking-v0", max_time_s=0.05)]
    if short_first:
        makers.reverse()
    envs = SyncVectorEnv(makers)
    try:
        envs.reset(seed=0)
        _, _, terminated, truncated, info = envs.step(np.zeros((2, 2), np.float32))
        assert (terminated | truncated).all()
        short = 0 if short_first else 1
        # A count that always applies stays a count (0 gear changes on either sub-env).
        gears = info["metrics"]["gear_changes"]
        assert gears.dtype.kind == "i" and gears.tolist() == [0, 0], gears
        for name in ("nuplan_comfortable", "path_cusps", "ttc_within_bound"):
            batch = info["metrics"][name]
            assert batch.dtype == np.float64, (name, batch)
            report = envs.envs[short].unwrapped.report
            want = getattr(report, name)
            got = batch[short]
            assert (math.isnan(got) if want is None else got == float(want)), (name, got, want)
        assert math.isnan(info["metrics"]["nuplan_comfortable"][short])
        assert info["metrics"]["nuplan_comfortable"][1 - short] in (0.0, 1.0)
    finally:
        envs.close()


def test_a_closed_env_says_so_when_stepped():
    env = gym.make("rrtdrive/Parking-v0", max_time_s=0.5, disable_env_checker=True)
    env.reset(seed=0)
    env.close()
    with pytest.raises(RuntimeError, match=r"call reset\(\) first \(none since made or closed\)"):
        env.unwrapped.step(np.zeros(2, np.float32))
    env.reset(seed=0)  # and a reset starts again
    env.step(np.zeros(2, np.float32))
    env.close()


def test_deterministic_for_a_seed():
    def rollout(seed):
        env = gym.make("rrtdrive/Parking-v0")
        env.action_space.seed(seed)
        out = [env.reset(seed=seed)]
        for _ in range(40):
            obs, r, te, tr, info = env.step(env.action_space.sample())
            out.append((obs, r, te, tr, info))
            if te or tr:
                break
        env.close()
        return out

    a, b = rollout(7), rollout(7)
    assert len(a) == len(b)
    for x, y in zip(a, b, strict=True):
        assert gym.utils.env_checker.data_equivalence(x, y, exact=True)
    c = rollout(8)
    assert c[0][1]["episode_seed"] != a[0][1]["episode_seed"]


def test_observations_are_fresh_arrays():
    env = gym.make("rrtdrive/Overtake-v0")
    obs0, _ = env.reset(seed=0)
    obs1 = env.step(zero(None))[0]
    obs2 = env.step(zero(None))[0]
    assert not np.shares_memory(obs0, obs1) and not np.shares_memory(obs1, obs2)
    env.close()


@pytest.mark.parametrize(
    "scenario,controller",
    [("overtake", "pure-pursuit"), ("overtake", "stanley"), ("overtake", "lqr"),
     ("parking", "lqr")],
)
def test_zero_residual_reproduces_plain_controller(scenario, controller):
    env = DriveEnv(scenario, controller=controller, residual=True)
    _, total, steps, info = run_to_end(env, zero, options={"episode_seed": 5})
    plain = evaluate(run_episode(scenario, controller=controller, seed=5))
    mine = dataclasses.asdict(env.report)
    ref = dataclasses.asdict(plain)
    assert {k: v for k, v in mine.items() if k not in NOT_COMPARED} == {
        k: v for k, v in ref.items() if k not in NOT_COMPARED
    }
    assert plain.success and info["is_success"] and info["status"] == "arrived"
    assert steps == plain.steps
    # The trajectories are the same arrays, bit for bit.
    ep = run_episode(scenario, controller=controller, seed=5)
    assert np.array_equal(env.episode.log.states, ep.log.states)
    assert np.array_equal(env.episode.log.controls, ep.log.controls)
    # info["metrics"] is the report, NaN where a metric does not apply, without the
    # wall-clock fields (env.report has them).
    from rrtdrive.evaluation.report import WALL_CLOCK_FIELDS

    assert not set(WALL_CLOCK_FIELDS) & set(info["metrics"])
    for k, v in mine.items():
        if k in WALL_CLOCK_FIELDS:
            continue
        got = info["metrics"][k]
        assert (got == v) or (v is None and (got is None or math.isnan(got)))
    env.close()


def test_zero_residual_reproduces_plain_controller_with_oncoming_traffic():
    # The gate that holds the car for a gap in the oncoming lane works as in the runner.
    from rrtdrive.sim.tasks import make_scenario

    env = DriveEnv("overtake", controller="lqr", residual=True, scenario_options={"oncoming": 2})
    _, _, steps, info = run_to_end(env, zero, options={"episode_seed": 3})
    ep = run_episode(make_scenario("overtake", 3, oncoming=2), controller="lqr", seed=3)
    assert env.episode.log.others.shape[1] == ep.log.others.shape[1] == 3
    assert np.array_equal(env.episode.log.states, ep.log.states)
    assert np.array_equal(env.episode.log.others, ep.log.others)
    assert info["status"] == ep.status == "arrived"
    assert env._driver.gate.waiting_steps > 0  # the car did wait for a gap
    env.close()


def test_reward_terms_add_up_and_success_bonus():
    weights = RewardWeights(progress=2.0, success=7.0)
    env = DriveEnv("overtake", residual=True, reward={"progress": 2.0, "success": 7.0})
    assert env.weights == weights
    obs, info = env.reset(options={"episode_seed": 1})
    total_progress = 0.0
    while True:
        obs, reward, terminated, truncated, info = env.step(zero(obs))
        terms = info["reward_terms"]
        assert set(terms) == {
            "progress", "cte", "heading", "speed", "collision", "off_path", "success"
        }
        assert reward == pytest.approx(sum(terms.values()))
        assert terms["cte"] <= 0 and terms["heading"] <= 0 and terms["speed"] <= 0
        total_progress += terms["progress"]
        if terminated or truncated:
            break
    assert terms["success"] == 7.0 and terms["collision"] == 0.0
    # Progress sums to the path length, less the few centimetres short of the goal.
    assert total_progress == pytest.approx(2.0 * env.path.length, abs=2.0 * 0.1)
    env.close()


def test_direct_mode_drives_to_the_goal_with_controller_commands():
    env = DriveEnv("overtake")
    obs, info = env.reset(options={"episode_seed": 2})
    assert info["episode_seed"] == 2
    ctrl = make_controller("lqr", speed=env._speed)
    ctrl.reset(env.path)
    lim = env.config.limits
    while True:
        ego = env._ego
        x, y, yaw = ego.rear
        t = info.get("time_s", 0.0)
        accel, steer = ctrl.control(VehicleState(x, y, yaw, ego.speed, ego.steer, t))
        action = np.array(
            [accel / lim.a_max if accel >= 0 else accel / -lim.a_min, steer / lim.steer_limit],
            dtype=np.float32,
        )
        obs, reward, terminated, truncated, info = env.step(action)
        if terminated or truncated:
            break
    assert info["status"] == "arrived" and info["is_success"]
    assert env.report.controller == "agent"
    with pytest.raises(RuntimeError, match="reset"):
        env.step(np.zeros(2))
    env.close()


def test_leaving_the_path_ends_the_episode():
    env = DriveEnv("overtake", max_cte=2.0)
    _, total, steps, info = run_to_end(
        env, lambda obs: np.array([1.0, 1.0], np.float32), options={"episode_seed": 0}
    )
    assert info["status"] in ("off_path", "crashed")
    assert info["reward_terms"]["off_path"] == -50.0 or info["reward_terms"]["collision"] == -50.0
    assert not info["is_success"]
    env.close()


def test_render_draws_the_scene_and_the_path(tmp_path):
    env = gym.make("rrtdrive/Parking-v0", render_mode="rgb_array", residual=True)
    env.reset(seed=4)
    for _ in range(60):
        env.step(zero(None))
    frame = env.render()
    assert frame.shape == (640, 640, 3) and frame.dtype == np.uint8
    assert not frame_is_blank(frame)
    px = frame.reshape(-1, 3).astype(int)
    assert np.any((px[:, 2] > 200) & (px[:, 0] < 80) & (px[:, 1] < 120))  # path (40, 90, 255)
    assert np.any((px[:, 0] > 200) & (px[:, 1] < 90) & (px[:, 2] < 90))  # trace (255, 60, 40)
    again = env.render()  # the lanes come from the renderer's cached background now
    assert again is not frame and np.array_equal(again, frame)
    env.step(zero(None))
    moved = env.render()
    assert not np.array_equal(moved, frame)
    env.reset(seed=5)  # a new road: its lanes are drawn again, not the old copy
    assert not frame_is_blank(env.render())
    env.close()
    plain = gym.make("rrtdrive/Overtake-v0")
    plain.reset(seed=0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert plain.render() is None
    plain.close()


@pytest.mark.parametrize(
    "kwargs,field",
    [
        ({"scenario": "nowhere"}, "scenario"),
        ({"planner": "astar"}, "planner"),
        ({"controller": "mpc"}, "controller"),
        ({"residual": 1}, "residual"),
        ({"residual_scale": 0.0}, "residual_scale"),
        ({"n_ref_points": 0}, "n_ref_points"),
        ({"ref_spacing": float("nan")}, "ref_spacing"),
        ({"action_repeat": 1.5}, "action_repeat"),
        ({"simulation_frequency": 5}, "^simulation_frequency: "),  # not SimConfig's name
        ({"simulation_frequency": 1001}, "^simulation_frequency: "),
        ({"max_time_s": -1.0}, "max_time_s"),
        ({"max_cte": 0}, "max_cte"),
        ({"reward": {"progess": 1.0}}, "reward.progess"),
        ({"reward": {"cte": -1.0}}, "reward.cte"),
        ({"scenario_options": {"colour": 1}}, "scenario_options"),
        ({"scenario_options": {"oncoming": 2}, "scenario": "parking"}, "oncoming"),
        ({"speed_options": {"v_max": 0.0}}, "^speed_options.v_max: "),  # not SpeedConfig's
        ({"speed_options": {"vmax": 1.0}}, "speed_options"),
        ({"speed_options": {"vmax": 1.0}}, "speed_options.vmax: unknown field"),
        ({"scenario_options": {"colour": 1}}, "scenario_options.colour: unknown option"),
        ({"scenario_options": {"spot": 999}, "scenario": "parking"},
         "scenario_options.spot: expected tuple"),
        ({"scenario_options": {"spot": (9, 9, 9)}, "scenario": "parking"},
         "scenario_options.spot"),
        ({"replan_options": {"rate": 1}, "scenario": "overtake-traffic"},
         "replan_options.rate: unknown field"),
        ({"residul": True}, "residul: unknown option"),
        ({"controller_options": {"gain": 1.0}}, "controller"),
        ({"seed_range": (5, 5)}, "seed_range"),
        ({"render_mode": "human"}, "render_mode"),
    ],
)
def test_bad_options_name_the_field(kwargs, field):
    kwargs = {"scenario": "overtake", **kwargs}
    with pytest.raises(InputError, match=field.replace(".", r"\.")):
        DriveEnv(**kwargs)


def test_bad_reset_options_and_actions():
    env = DriveEnv("overtake")
    with pytest.raises(InputError, match=r"options\.seed"):
        env.reset(options={"seed": 1})
    with pytest.raises(InputError, match=r"options\.episode_seed"):
        env.reset(options={"episode_seed": -1})
    # Past int64 a vector env could not batch its info (OverflowError, and a hung close).
    with pytest.raises(InputError, match=r"options\.episode_seed"):
        env.reset(options={"episode_seed": 2**63})
    env.reset(seed=0)
    with pytest.raises(InputError, match="action"):
        env.step(np.array([0.0, np.nan]))
    with pytest.raises(InputError, match="action"):
        env.step(np.zeros(3))
    env.close()
    env.close()  # closing twice is fine


def test_package_exports_the_ids():
    assert rrtdrive.ENV_IDS is ENV_IDS
    assert "rrtdrive/Parking-v0" in gym.registry and "rrtdrive/Overtake-v0" in gym.registry


def test_short_ppo_run_completes():
    sb3 = pytest.importorskip("stable_baselines3")
    env = gym.make("rrtdrive/Overtake-v0", residual=True, max_time_s=3.0)
    model = sb3.PPO("MlpPolicy", env, n_steps=64, batch_size=32, n_epochs=1, seed=0, device="cpu")
    model.learn(total_timesteps=128)
    obs, _ = env.reset(seed=1)
    action, _ = model.predict(obs, deterministic=True)
    assert action.shape == (2,) and env.action_space.contains(action.astype(np.float32))
    env.close()


def test_residual_cannot_add_jerk():
    # A bang-bang residual on the acceleration: the summed command still rises and
    # falls by at most the speed loop's 5 m/s^3 (the residual is clipped to the rate
    # limits around the last applied command).
    env = gym.make("rrtdrive/Parking-v0", residual=True, residual_scale=1.0, max_time_s=8.0)
    env.reset(seed=3)
    done, k = False, 0
    while not done:
        action = np.array([1.0 if k % 2 else -1.0, 0.0], np.float32)
        _, _, terminated, truncated, _ = env.step(action)
        done, k = terminated or truncated, k + 1
    log = env.unwrapped.episode.log
    accel = log.controls[:, 0]
    jerk = np.abs(np.diff(accel)) / log.dt
    assert jerk.max() <= 5.0 + 1e-6
    # The residual did move the command: from rest the controller alone speeds up.
    assert accel[0] == pytest.approx(-0.25) and np.any(accel < -0.2)
    env.close()


def test_unknown_option_names_the_key():
    with pytest.raises(InputError, match="residul: unknown option"):
        gym.make("rrtdrive/Overtake-v0", residul=True)
    with pytest.raises(InputError, match="residul"):
        DriveEnvConfig.from_options("overtake", residul=True)


def test_config_is_frozen_validated_and_reaches_the_env():
    cfg = DriveEnvConfig.from_options("overtake", residual=True, reward={"cte": 100.0})
    assert cfg.reward == RewardWeights(cte=100.0) and cfg.budget is not None
    with pytest.raises(dataclasses.FrozenInstanceError):
        cfg.residual = False  # type: ignore[misc]
    env = gym.make("rrtdrive/Overtake-v0", config=cfg, n_ref_points=3)
    u = env.unwrapped
    assert u.config == cfg.with_options(n_ref_points=3) and u.weights.cte == 100.0
    assert env.observation_space.shape == (6 + 3 * 3 + 2,)
    env.close()
    with pytest.raises(InputError, match="scenario"):
        DriveEnv("parking", config=cfg)
    with pytest.raises(InputError, match="n_ref_points"):
        cfg.with_options(n_ref_points=0)
    assert DriveEnv(config=cfg).config.scenario == "overtake"


def test_action_mapping_and_zero_residual_mixer():
    from rrtdrive.controllers import SpeedConfig
    from rrtdrive.envs.action import CommandLimits, ResidualMixer, action_command

    lim = CommandLimits(a_min=-4.0, a_max=2.0, steer_limit=0.4)
    assert action_command([1.0, -1.0], lim) == (2.0, -0.4)
    assert action_command([-1.0, 5.0], lim) == (-4.0, 0.4)  # clipped to [-1, 1] first
    assert action_command([0.5, 0.5], lim, scale=0.5) == (0.5, 0.1)
    with pytest.raises(InputError, match="action"):
        action_command([0.0], lim)

    class Ctrl:  # the attributes the mixer reads (an instant actuator: no reach window)
        at_stop, remaining, steer_window = False, 10.0, None

    mixer = ResidualMixer(lim, SpeedConfig(), 0.05)
    for c in (0.0, 0.2, 0.25, -1.0, 1.9):
        got = mixer.command(Ctrl, c, 0.1, 0.0, 0.0)
        assert got == (c, 0.1)  # a zero residual is the controller's command exactly
        mixer.applied(got[0])
    mixer.applied(0.0)
    a, _ = mixer.command(Ctrl, 0.0, 0.0, 2.0, 0.0)
    assert a == pytest.approx(SpeedConfig().jerk_max * 0.05)  # the jerk limit binds


def test_observation_layout_bounds_and_names():
    from rrtdrive.envs.observation import KAPPA_CLIP, OBS_CLIP, ObservationLayout

    lay = ObservationLayout(3, 1.0, 2, 50.0, 0.5)
    assert lay.size == len(lay.names()) == 6 + 9 + 10 + 2 == lay.low.shape[0]
    assert lay.low[-2] == -1.0 and lay.high[-2] == 1.0  # the gear
    assert lay.names() == observation_names(3, 2)
    assert lay.low.dtype == lay.high.dtype == np.float32
    assert lay.high[1] == np.float32(0.5) and lay.high[2] == OBS_CLIP
    assert lay.high[6 + 6] == KAPPA_CLIP and lay.high[6 + 9] == 1.0
    with pytest.raises(InputError, match="n_vehicles"):
        ObservationLayout(3, 1.0, -1, 50.0, 0.5)


def test_following_and_stop_line_speeds():
    from rrtdrive.controllers import SpeedConfig
    from rrtdrive.envs.reference_speed import following_speed, stop_line_speed
    from rrtdrive.sim.replanning import IDMConfig

    idm = IDMConfig()
    # At the IDM's equilibrium gap behind a 4 m/s lead, its speed is the lead's.
    s_eq = (idm.min_gap + 4.0 * idm.time_headway) / math.sqrt(1.0 - (4.0 / 11.0) ** idm.delta)
    assert following_speed(idm, 11.0, s_eq, 4.0) == pytest.approx(4.0, abs=1e-6)
    assert following_speed(idm, 11.0, 2 * s_eq, 4.0) > 4.0
    assert following_speed(idm, 11.0, s_eq / 2, 4.0) < 4.0
    assert following_speed(idm, 11.0, idm.min_gap, 4.0) == 0.0
    cfg = SpeedConfig(v_max=5.0)
    assert stop_line_speed(3.0, 0.0, None, cfg) == 3.0
    assert stop_line_speed(3.0, 9.0, 10.0, cfg) == pytest.approx(min(3.0, math.sqrt(2 * cfg.decel)))
    assert stop_line_speed(3.0, 10.0, 10.0, cfg) == 0.0


def test_traffic_reward_does_not_punish_following():
    # Issue #15 bug 2: v_ref ignored the car-following cap, so a successful zero-residual
    # episode that rightly followed the 4 m/s lead returned -1311 (speed term -1471).
    env = DriveEnv("overtake-traffic", residual=True, replan_options={"wall_limit": False})
    env.reset(options={"episode_seed": 0})
    total, speed_term, following = 0.0, 0.0, []
    while True:
        mode = env._driver.mode
        _, reward, terminated, truncated, info = env.step(zero(None))
        total += reward
        speed_term += info["reward_terms"]["speed"]
        if mode == "follow" and env._driver.mode == "follow" and info["time_s"] > 8.0:
            following.append((info["speed"], info["v_ref"]))
        if terminated or truncated:
            break
    assert info["status"] == "completed" and info["is_success"]
    assert speed_term > -25.0
    assert total > 50.0
    # Behind the lead, v_ref is about its 4 m/s, not the profile's 11 m/s.
    assert following and all(abs(v - v_ref) < 0.5 for v, v_ref in following)
    env.close()



def test_waiting_for_a_gap_in_oncoming_traffic_is_not_punished():
    # The plain controller (zero residual) waits at the gate for a gap, then goes. v_ref
    # jumped from 0 to the profile's 6.5 m/s at the release: the speed term cost about
    # 440 per start (returns -226 / -311 for seeds 0 / 2, +132 without oncoming cars).
    # In direct mode the gate was never consulted, so v_ref ignored its stop line: the
    # same drive replayed as actions returned -7630 (seed 0).
    env = DriveEnv("overtake", residual=True, scenario_options={"oncoming": 2})
    env.reset(options={"episode_seed": 0})
    lim = env.config.limits
    total, speed_term, actions = 0.0, 0.0, []
    while True:
        _, reward, terminated, truncated, info = env.step(zero(None))
        total += reward
        speed_term += info["reward_terms"]["speed"]
        a, d = float(env._ego.accel), float(env._ego.steer)
        actions.append([a / lim.a_max if a >= 0 else a / -lim.a_min, d / lim.steer_limit])
        if terminated or truncated:
            break
    assert info["is_success"] and env._driver.gate.waiting_steps > 0
    assert speed_term > -20.0 and total > 100.0
    direct = DriveEnv("overtake", residual=False, scenario_options={"oncoming": 2})
    direct.reset(options={"episode_seed": 0})
    replay = 0.0
    for a in actions:
        _, reward, terminated, truncated, info = direct.step(np.asarray(a, dtype=np.float32))
        replay += reward
        if terminated or truncated:
            break
    assert info["is_success"] and replay == pytest.approx(total, abs=1.0)
    env.close()
    direct.close()


def test_an_env_copied_after_rendering_renders_on_its_own():
    env = DriveEnv("parking", render_mode="rgb_array")
    env.reset(options={"episode_seed": 0})
    env.render()
    twin = copy.deepcopy(env)  # pygame's surfaces and module do not copy
    assert len(pickle.dumps(env)) > 0
    frame = twin.render()
    assert frame.shape[2] == 3 and frame.std() > 10
    _, r1, *_ = env.step(zero(None))
    _, r2, *_ = twin.step(zero(None))
    assert r1 == r2
    env.close()
    twin.close()


def test_a_map_is_driven_start_to_goal_with_reverse(tmp_path):
    # A user's map file as the scenario: planned with reverse, driven into the kerbside
    # gap by the plain controller (zero residual), judged as any episode.
    from rrtdrive.maps import builtin_map, save_map

    f = tmp_path / "kerb.json"
    save_map(builtin_map("kerbside"), f)
    env = gym.make(
        "rrtdrive/Map-v0", scenario=str(f), scenario_options={"reverse": True},
        controller="lqr", residual=True,
    )  # fmt: skip
    obs, total, steps, info = run_to_end(env, zero, seed=0)
    u = env.unwrapped
    assert info["status"] == "arrived" and info["is_success"] and not info["crashed"]
    assert len(u.path.cusps) >= 1 and u.report.collision is False
    m = builtin_map("kerbside")
    assert np.hypot(*(u.episode.log.states[-1, :2] - [m.goal.x, m.goal.y])) < 0.1
    env.close()
    # The same map built in Python (a Map, not a file) drives the same episode.
    from rrtdrive.maps import Map

    mine = Map("my_kerb", m.bounds, m.obstacles, m.start, m.goal)
    env = gym.make(
        "rrtdrive/Map-v0", scenario=mine, scenario_options={"reverse": True},
        controller="lqr", residual=True,
    )  # fmt: skip
    obs_2, total_2, steps_2, info_2 = run_to_end(env, zero, seed=0)
    assert np.array_equal(env.unwrapped.episode.log.states, u.episode.log.states)
    assert (total_2, steps_2, info_2["status"]) == (total, steps, "arrived")
    assert np.array_equal(obs_2, obs)
    assert env.unwrapped.config.scenario_name == "my_kerb"
    env.close()


@pytest.mark.parametrize(
    ("options", "field"),
    [({"scenario": "nowhere"}, "scenario: unknown scenario 'nowhere'"),
     ({"scenario": "kerbside", "scenario_options": {"spot": 3}}, "scenario_options.spot"),
     ({"scenario": "kerbside", "scenario_options": {"reverse": "yes"}},
      "scenario_options.reverse")],
)  # fmt: skip
def test_bad_map_scenarios_name_the_field(options, field):
    with pytest.raises(InputError, match=re.escape(field)):
        DriveEnvConfig.from_options(**options)
