"""Audit (session 47) of the gymnasium environments as a demanding RL user sees them.

Spaces against what reset/step return, check_env with gear changes, seeding, reset
options, episode ends, the reward recomputed from ``info``, info types, rendering,
close, standard wrappers, a vector env and config validation (docs/gym.md).
"""

from __future__ import annotations

import math
from dataclasses import fields

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from gymnasium.vector import SyncVectorEnv
from gymnasium.wrappers import (
    FlattenObservation,
    NormalizeObservation,
    RecordEpisodeStatistics,
    TimeLimit,
)

import rrtdrive.envs  # noqa: F401  (registers the ids)
from rrtdrive.controllers import VehicleState, make_controller
from rrtdrive.envs import ENV_IDS
from rrtdrive.evaluation import EpisodeReport
from rrtdrive.evaluation.report import WALL_CLOCK_FIELDS
from rrtdrive.maps import builtin_map
from rrtdrive.types import InputError, VehicleParams

GEAR, CUSP = -2, -1
FAST_IDS = [i for i in ENV_IDS if i != "rrtdrive/OvertakeTraffic-v0"]
STEP_KEYS = {
    "episode_seed", "time_s", "cte_m", "heading_err_rad", "speed", "v_ref", "accel",
    "steer", "crashed", "reward_terms",
}
END_KEYS = {"status", "is_success", "metrics"}
TERMS = {"progress", "cte", "heading", "speed", "collision", "off_path", "success"}
ZERO = np.zeros(2, np.float32)


def _check_step(env, obs, reward, terminated, truncated, info):
    """What every step must satisfy, whatever the id or mode."""
    space = env.observation_space
    assert isinstance(obs, np.ndarray) and obs.dtype == np.float32
    assert obs.shape == space.shape
    assert space.contains(obs), obs
    assert type(reward) is float and math.isfinite(reward)
    assert type(terminated) is bool and type(truncated) is bool
    assert not (terminated and truncated)
    expected = STEP_KEYS | (END_KEYS if terminated or truncated else set())
    assert set(info) == expected
    assert type(info["episode_seed"]) is int
    assert type(info["crashed"]) is bool
    for key in ("time_s", "cte_m", "heading_err_rad", "speed", "v_ref", "accel", "steer"):
        assert type(info[key]) is float and math.isfinite(info[key]), key
    assert set(info["reward_terms"]) == TERMS
    assert all(type(v) is float for v in info["reward_terms"].values())
    assert obs[GEAR] in (-1.0, 1.0)


def _controller_agent(env):
    """An agent that sends an LQR controller's command as the action (direct mode)."""
    u = env.unwrapped
    ctrl = make_controller("lqr", speed=u._speed, vehicle=u._scenario.vehicle)
    ctrl.reset(u.path)
    lim = u.config.limits

    def act(info):
        ego = u._ego
        x, y, yaw = ego.rear
        accel, steer = ctrl.control(
            VehicleState(x, y, yaw, ego.speed, ego.steer, info.get("time_s", 0.0))
        )
        a = accel / lim.a_max if accel >= 0 else accel / -lim.a_min
        return np.clip(np.array([a, steer / lim.steer_limit], np.float32), -1.0, 1.0)

    return act


# ------------------------------------------------------------------ ids and spaces


@pytest.mark.parametrize("env_id", list(ENV_IDS))
def test_every_id_makes_an_env_whose_spaces_match_reset_and_step(env_id):
    env = gym.make(env_id)
    assert env.action_space == gym.spaces.Box(-1.0, 1.0, (2,), np.float32)
    k, m = env.unwrapped.config.n_ref_points, env.unwrapped.config.n_vehicles
    assert env.observation_space.shape == (6 + 3 * k + 5 * m + 2,) == (38,)
    assert env.observation_space.dtype == np.float32
    obs, info = env.reset(seed=0)
    assert obs.dtype == np.float32 and env.observation_space.contains(obs)
    assert set(info) == {"episode_seed", "scenario", "path_length_m"}
    assert type(info["episode_seed"]) is int and type(info["path_length_m"]) is float
    env.action_space.seed(0)
    for _ in range(5):
        out = env.step(env.action_space.sample())
        _check_step(env, *out)
        if out[2] or out[3]:
            break
    env.close()


def test_the_module_prefixed_id_imports_rrtdrive_itself():
    env = gym.make("rrtdrive:rrtdrive/UTurn-v0")
    assert env.spec.id == "rrtdrive/UTurn-v0"
    env.close()


@pytest.mark.parametrize(
    "env_id, kwargs",
    [
        ("rrtdrive/UTurn-v0", {}),
        ("rrtdrive/ParallelParking-v0", {}),
        ("rrtdrive/Map-v0", {"scenario_options": {"reverse": True}}),
    ],
)
@pytest.mark.parametrize("residual", [False, True])
def test_check_env_passes_with_reverse(env_id, kwargs, residual):
    env = gym.make(env_id, residual=residual, render_mode="rgb_array", **kwargs)
    check_env(env.unwrapped)
    env.close()


def test_every_step_across_gear_changes_stays_in_the_space_residual():
    env = gym.make("rrtdrive/UTurn-v0", residual=True)
    obs, _ = env.reset(seed=3)
    env.action_space.seed(3)
    rng = np.random.default_rng(3)
    gears = [float(obs[GEAR])]
    flips = 0
    while True:
        action = (0.3 * rng.standard_normal(2)).astype(np.float32).clip(-1, 1)
        out = env.step(action)
        _check_step(env, *out)
        if out[0][GEAR] != gears[-1]:
            flips += 1
        gears.append(float(out[0][GEAR]))
        if out[2] or out[3]:
            break
    info = out[4]
    assert flips >= 1 and set(gears) == {-1.0, 1.0}
    # Residual mode arrives when the controller stops at the end of the path; the
    # evaluators judge success on their own (noise may leave the car off the goal).
    assert info["status"] == "arrived" and out[2]
    assert info["is_success"] is env.unwrapped.report.success
    env.close()


def test_an_agent_alone_drives_a_u_turn_through_its_cusps_to_the_documented_stop():
    env = gym.make("rrtdrive/UTurn-v0", max_time_s=60.0)
    obs, info = env.reset(seed=0)
    act = _controller_agent(env)
    gears = []
    while True:
        out = env.step(act(info))
        _check_step(env, *out)
        obs, _, terminated, truncated, info = out
        gears.append(float(obs[GEAR]))
        if terminated or truncated:
            break
    assert set(gears) == {-1.0, 1.0}
    # docs: direct mode arrives with the rear axle stopped within 0.5 m and 10 deg.
    assert terminated and info["status"] == "arrived" and info["is_success"]
    m = info["metrics"]
    assert abs(info["speed"]) <= 0.1
    assert m["goal_position_err_m"] <= 0.5 and m["goal_heading_err_rad"] <= math.radians(10)
    assert env.unwrapped.report.controller == "agent"
    env.close()


# ------------------------------------------------------------------ seeding


def _rollout(env_id, seed, n=30, **kwargs):
    env = gym.make(env_id, **kwargs)
    obs, info = env.reset(seed=seed)
    env.action_space.seed(123)
    obs_list, rewards, infos = [obs], [], [info]
    for _ in range(n):
        obs, r, terminated, truncated, info = env.step(env.action_space.sample())
        obs_list.append(obs)
        rewards.append(r)
        infos.append(info)
        if terminated or truncated:
            break
    env.close()
    return np.array(obs_list), np.array(rewards), infos


@pytest.mark.parametrize("env_id", ["rrtdrive/Parking-v0", "rrtdrive/UTurn-v0"])
def test_a_seed_fixes_the_rollout_bit_for_bit_and_another_seed_differs(env_id):
    a_obs, a_r, a_info = _rollout(env_id, 7, residual=True)
    b_obs, b_r, b_info = _rollout(env_id, 7, residual=True)
    assert a_obs.tobytes() == b_obs.tobytes() and a_r.tobytes() == b_r.tobytes()
    assert repr(a_info) == repr(b_info)
    c_obs, _, c_info = _rollout(env_id, 8, residual=True)
    assert c_info[0]["episode_seed"] != a_info[0]["episode_seed"]
    assert c_obs.shape != a_obs.shape or not np.array_equal(c_obs, a_obs)


def test_reset_twice_with_the_same_seed_on_one_env_repeats_the_episode():
    env = gym.make("rrtdrive/Parking-v0")
    o1, i1 = env.reset(seed=3)
    env.step(np.array([0.5, 0.2], np.float32))
    o2, i2 = env.reset(seed=3)
    assert np.array_equal(o1, o2) and i1 == i2
    _, i3 = env.reset()  # the generator moves on
    assert i3["episode_seed"] != i1["episode_seed"]
    env.close()


# ------------------------------------------------------------------ reset options


def test_reset_episode_seed_option_runs_that_episode_whatever_the_seed():
    env = gym.make("rrtdrive/UTurn-v0")
    o1, i1 = env.reset(seed=1, options={"episode_seed": 42})
    o2, i2 = env.reset(seed=2, options={"episode_seed": np.int64(42)})
    assert i1["episode_seed"] == i2["episode_seed"] == 42
    assert np.array_equal(o1, o2) and i1 == i2
    env.close()


@pytest.mark.parametrize(
    "options, field",
    [
        ({"bogus": 1}, "options.bogus"),
        ({"episode_seed": 1, "epsiode_seed": 2}, "options.epsiode_seed"),
        ({"episode_seed": -1}, "options.episode_seed"),
        ({"episode_seed": 3.0}, "options.episode_seed"),
        ({"episode_seed": "3"}, "options.episode_seed"),
        ({"episode_seed": True}, "options.episode_seed"),
        ({"episode_seed": 2**63}, "options.episode_seed"),
        ([("episode_seed", 1)], "options"),
    ],
)
def test_bad_reset_options_raise_one_error_naming_the_field(options, field):
    env = gym.make("rrtdrive/Parking-v0", disable_env_checker=True)
    with pytest.raises(InputError) as err:
        env.reset(options=options)
    assert str(err.value).startswith(field + ":")
    env.close()


# ------------------------------------------------------------------ episode ends


def _run(env, policy, seed=0, **reset_kwargs):
    obs, info = env.reset(seed=seed, **reset_kwargs)
    steps = 0
    while True:
        obs, r, terminated, truncated, info = env.step(policy(obs))
        steps += 1
        if terminated or truncated:
            return obs, r, terminated, truncated, info, steps


def test_time_limit_truncates_and_says_timeout():
    env = gym.make("rrtdrive/Parking-v0", max_time_s=0.5)
    obs, r, terminated, truncated, info, steps = _run(env, lambda o: ZERO)
    assert truncated is True and terminated is False
    assert info["status"] == "timeout" and info["is_success"] is False
    assert steps == 10 and info["time_s"] == pytest.approx(0.5)
    assert env.observation_space.contains(obs)
    with pytest.raises(RuntimeError, match="reset"):
        env.step(ZERO)
    env.close()


@pytest.mark.parametrize(
    "env_id, limit",
    [("rrtdrive/UTurn-v0", 120.0), ("rrtdrive/Overtake-v0", 60.0)],
)
def test_default_time_limits_are_the_documented_ones(env_id, limit):
    env = gym.make(env_id, action_repeat=100)
    _, _, terminated, truncated, info, _ = _run(env, lambda o: ZERO)
    assert truncated and not terminated and info["status"] == "timeout"
    assert info["time_s"] == pytest.approx(limit)
    env.close()


def test_map_time_limit_is_60_s_plus_2_s_per_metre_of_diagonal():
    x0, y0, x1, y1 = builtin_map("parking_lot").bounds
    limit = 60.0 + 2.0 * math.hypot(x1 - x0, y1 - y0)
    env = gym.make("rrtdrive/Map-v0", action_repeat=100)
    _, _, _, truncated, info, _ = _run(env, lambda o: ZERO)
    assert truncated and info["status"] == "timeout"
    assert limit <= info["time_s"] < limit + 0.05 + 1e-9  # the first step at or past it
    env.close()


def test_a_crash_terminates_with_the_collision_penalty():
    env = gym.make("rrtdrive/Parking-v0", max_cte=None)
    obs, r, terminated, truncated, info, _ = _run(env, lambda o: np.array([1, 0], np.float32))
    assert terminated is True and truncated is False
    assert info["status"] == "crashed" and info["crashed"] is True
    assert info["reward_terms"]["collision"] == -50.0 and info["reward_terms"]["success"] == 0
    assert info["is_success"] is False and info["metrics"]["collision_highway_env"] is True
    assert r == pytest.approx(sum(info["reward_terms"].values()))
    env.close()


def test_leaving_the_path_terminates_with_the_off_path_penalty():
    env = gym.make("rrtdrive/Parking-v0", max_cte=1.0)
    _, _, terminated, truncated, info, _ = _run(env, lambda o: np.array([0.5, 1], np.float32))
    assert terminated and not truncated and info["status"] == "off_path"
    assert abs(info["cte_m"]) > 1.0
    assert info["reward_terms"]["off_path"] == -50.0 and info["reward_terms"]["collision"] == 0
    assert not info["is_success"]
    env.close()


def test_reaching_the_goal_terminates_with_the_success_bonus():
    env = gym.make("rrtdrive/UTurn-v0", residual=True, reward={"success": 7.5})
    _, _, terminated, truncated, info, _ = _run(env, lambda o: ZERO, seed=4)
    assert terminated and not truncated and info["status"] == "arrived"
    assert info["is_success"] is True and info["reward_terms"]["success"] == 7.5
    env.close()


# ------------------------------------------------------------------ reward


@pytest.mark.parametrize("residual, action_repeat", [(True, 2), (False, 1)])
def test_reward_terms_equal_the_documented_formulas(residual, action_repeat):
    w = {"progress": 3.0, "cte": 100.0, "heading": 7.0, "speed": 2.0}
    env = gym.make(
        "rrtdrive/Parking-v0", residual=residual, action_repeat=action_repeat, reward=w,
        max_time_s=15.0,
    )
    obs, _ = env.reset(seed=2)
    length = env.unwrapped.path.length
    rng = np.random.default_rng(0)
    t_prev, n = 0.0, 0
    while True:
        scale = 0.5 if residual else 1.0
        action = np.array([0.4, 0.0]) + scale * rng.uniform(-0.3, 0.3, 2)
        prev = obs
        obs, reward, terminated, truncated, info = env.step(action.astype(np.float32))
        n += 1
        t = info["time_s"] - t_prev
        t_prev = info["time_s"]
        assert t == pytest.approx(action_repeat * 0.05) or terminated or truncated
        terms = info["reward_terms"]
        exact = {"rel": 1e-9, "abs": 1e-12}
        assert terms["cte"] == pytest.approx(-w["cte"] * info["cte_m"] ** 2 * t, **exact)
        assert terms["heading"] == pytest.approx(
            -w["heading"] * info["heading_err_rad"] ** 2 * t, **exact
        )
        assert terms["speed"] == pytest.approx(
            -w["speed"] * (info["speed"] - info["v_ref"]) ** 2 * t, **exact
        )
        # Progress: metres of arc gained, the projection clipped to the path.
        def along(o):
            return length - min(max(float(o[5]), 0.0), length)

        gained = along(obs) - along(prev)
        assert terms["progress"] == pytest.approx(w["progress"] * gained, abs=1e-3)
        assert reward == pytest.approx(sum(terms.values()), **exact)
        # The observation and the info agree (float32 rounding only).
        assert obs[0] == pytest.approx(info["speed"], abs=1e-5)
        assert obs[2] == pytest.approx(info["cte_m"], abs=1e-5)
        assert obs[3] == pytest.approx(info["heading_err_rad"], abs=1e-5)
        assert obs[4] == pytest.approx(info["v_ref"], abs=1e-5)
        if terminated or truncated:
            break
    assert n > 20
    env.close()


# ------------------------------------------------------------------ info


def _finished_u_turn_info():
    env = gym.make("rrtdrive/UTurn-v0", residual=True)
    *_, info, _ = _run(env, lambda o: ZERO, seed=3)
    report = env.unwrapped.report
    env.close()
    return info, report


def test_end_of_episode_metrics_are_the_report_without_wall_clock_fields():
    info, report = _finished_u_turn_info()
    m = info["metrics"]
    names = {f.name for f in fields(EpisodeReport)}
    assert set(m) == names - set(WALL_CLOCK_FIELDS)
    assert type(info["status"]) is str and info["status"] == m["status"] == "arrived"
    for key in ("steps", "collisions_vehicles", "collisions_at_fault"):
        assert type(m[key]) is int and m[key] == getattr(report, key), key
    assert type(m["success"]) is bool
    # A metric that may not apply is a float (NaN when it does not).
    assert type(m["path_cusps"]) is float and m["path_cusps"] == report.path_cusps >= 1
    assert math.isnan(m["replans"]) and report.replans is None
    assert report.gear_changes == report.path_cusps  # the zero residual drives the cusps


def test_the_gear_changes_count_is_an_int():
    info, report = _finished_u_turn_info()
    assert type(report.gear_changes) is int
    assert type(info["metrics"]["gear_changes"]) is int


# ------------------------------------------------------------------ render and close


@pytest.mark.parametrize(
    "env_id, shape",
    [("rrtdrive/Parking-v0", (640, 640, 3)), ("rrtdrive/Overtake-v0", (320, 960, 3))],
)
def test_render_returns_a_drawn_rgb_frame(env_id, shape):
    env = gym.make(env_id, render_mode="rgb_array", residual=True)
    env.reset(seed=0)
    for _ in range(3):
        env.step(ZERO)
    frame = env.render()
    assert isinstance(frame, np.ndarray) and frame.dtype == np.uint8 and frame.shape == shape
    assert frame.mean() > 20 and len(np.unique(frame.reshape(-1, 3), axis=0)) > 20
    assert env.unwrapped.render() is not frame  # a new frame each call
    env.close()


def test_render_in_reverse_and_without_a_render_mode():
    env = gym.make("rrtdrive/UTurn-v0", render_mode="rgb_array", residual=True)
    obs, _ = env.reset(seed=3)
    while obs[GEAR] > 0:
        obs, *_ = env.step(ZERO)
    frame = env.render()
    assert frame.ndim == 3 and frame.shape[2] == 3 and frame.dtype == np.uint8
    assert frame.max() > 0 and frame.std() > 5
    env.close()
    plain = gym.make("rrtdrive/Parking-v0")
    plain.reset(seed=0)
    assert plain.render() is None
    plain.close()


def test_close_twice_is_safe_and_a_closed_env_can_reset_again():
    env = gym.make("rrtdrive/Parking-v0", render_mode="rgb_array")
    env.reset(seed=0)
    env.render()
    env.close()
    env.close()
    env.unwrapped.close()
    with pytest.raises(RuntimeError, match="reset"):
        env.unwrapped.step(ZERO)
    obs, _ = env.reset(seed=0)
    assert env.observation_space.contains(obs)
    env.close()
    never_reset = gym.make("rrtdrive/Parking-v0")
    never_reset.close()
    never_reset.close()


# ------------------------------------------------------------------ wrappers and vectors


def test_standard_wrappers():
    base = gym.make("rrtdrive/Overtake-v0", residual=True)
    env = NormalizeObservation(
        FlattenObservation(RecordEpisodeStatistics(TimeLimit(base, max_episode_steps=12)))
    )
    obs, _ = env.reset(seed=0)
    assert obs.shape == (38,)
    env.action_space.seed(0)
    total, n = 0.0, 0
    while True:
        obs, r, terminated, truncated, info = env.step(env.action_space.sample())
        total += r
        n += 1
        assert obs.shape == (38,) and np.all(np.isfinite(obs))
        if terminated or truncated:
            break
    assert truncated and not terminated and n == 12
    assert info["episode"]["l"] == 12 and info["episode"]["r"] == pytest.approx(total)
    env.close()


def test_sync_vector_env_with_two_copies_seeds_them_apart():
    def make():
        return gym.make("rrtdrive/Parking-v0", max_time_s=0.5)

    venv = SyncVectorEnv([make, make])
    obs, info = venv.reset(seed=5)
    assert obs.shape == (2, 38) and obs.dtype == np.float32
    assert venv.observation_space.contains(obs)
    seeds = info["episode_seed"]
    assert seeds[0] != seeds[1] and not np.array_equal(obs[0], obs[1])
    obs_again, info_again = venv.reset(seed=5)
    assert np.array_equal(obs, obs_again)
    assert list(info_again["episode_seed"]) == list(seeds)
    ended = False
    for _ in range(12):  # 10 steps end each episode; autoreset follows
        obs, r, terminated, truncated, info = venv.step(np.zeros((2, 2), np.float32))
        assert venv.observation_space.contains(obs) and r.shape == (2,)
        ended |= bool(truncated.all())
    assert ended
    venv.close()
    venv.close()


# ------------------------------------------------------------------ config and actions


@pytest.mark.parametrize(
    "kwargs, field",
    [
        ({"n_ref_points": 0}, "n_ref_points"),
        ({"n_ref_points": 1.5}, "n_ref_points"),
        ({"ref_spacing": float("nan")}, "ref_spacing"),
        ({"n_vehicles": 51}, "n_vehicles"),
        ({"vehicle_range": float("inf")}, "vehicle_range"),
        ({"action_repeat": 0}, "action_repeat"),
        ({"simulation_frequency": 14}, "simulation_frequency"),
        ({"max_time_s": -1.0}, "max_time_s"),
        ({"max_time_s": float("inf")}, "max_time_s"),
        ({"max_cte": 0.0}, "max_cte"),
        ({"residual": "yes"}, "residual"),
        ({"residual_scale": 0.0}, "residual_scale"),
        ({"controller": "pid"}, "controller"),
        ({"planner": "astar"}, "planner"),
        ({"reward": {"progess": 1.0}}, "reward.progess"),
        ({"reward": {"cte": -1.0}}, "reward.cte"),
        ({"scenario_options": {"spot": 999}}, "scenario_options.spot"),
        ({"controller_options": {"vehicle": None}}, "controller_options.vehicle"),
        ({"speed_options": {"v_max": 100.0}}, "speed_options.v_max"),
        ({"planner_options": {"bogus": 1}}, "planner_options.bogus"),
        ({"replan_options": {"rate_hz": 1.0}}, "replan_options"),
        ({"seed_range": (5, 5)}, "seed_range"),
        ({"seed_range": (-1, 3)}, "seed_range"),
        ({"budget": 5}, "budget"),
        ({"residul": True}, "residul"),
        ({"scenario": "overtake"}, "scenario"),
        ({"render_mode": "human2"}, "render_mode"),
        ({"config": {}}, "config"),
    ],
)
@pytest.mark.filterwarnings("ignore:.*not in the possible render_modes")
def test_bad_config_values_are_refused_naming_the_field(kwargs, field):
    with pytest.raises(InputError) as err:
        gym.make("rrtdrive/Parking-v0", **kwargs)
    assert str(err.value).startswith(field + ":"), str(err.value)


def test_the_action_maps_to_the_documented_command_range():
    car = VehicleParams(max_steer_rate=None)  # instant steering: the command shows at once
    env = gym.make("rrtdrive/Parking-v0", scenario_options={"vehicle": car})
    steer_max = math.atan(car.wheelbase * car.kappa_max)
    for action, accel, steer in [
        ([1.0, 0.0], 2.0, 0.0),
        ([-1.0, 0.0], -4.0, 0.0),
        ([-0.5, 0.5], -2.0, 0.5 * steer_max),
        ([0.0, -1.0], 0.0, -steer_max),
    ]:
        env.reset(seed=0)
        obs, *_, info = env.step(np.array(action, np.float32))
        assert info["accel"] == pytest.approx(accel) and info["steer"] == pytest.approx(steer)
        assert obs[1] == pytest.approx(steer, abs=1e-6)
    with pytest.raises(InputError, match="^action"):
        env.step(np.array([np.nan, 0.0], np.float32))
    env.close()


def test_numpy_bools_are_taken_as_numpy_ints_are():
    # A config sweep built from numpy arrays: np.True_ was refused where np.int64 was taken.
    env = gym.make("rrtdrive/Parking-v0", residual=np.True_, n_ref_points=np.int64(3))
    try:
        assert env.unwrapped.config.residual is True
        env.reset(seed=0)
    finally:
        env.close()
    m = builtin_map("reverse_bay")
    env = gym.make("rrtdrive/Map-v0", scenario=m, scenario_options={"reverse": np.True_})
    try:
        env.reset(seed=0)
        assert env.unwrapped.config.scenario_for(0).reverse is True
    finally:
        env.close()


@pytest.mark.parametrize("shape", [(1, 2), (2, 1), (4,)])
def test_an_action_of_another_shape_is_refused(shape):
    env = gym.make("rrtdrive/Parking-v0", disable_env_checker=True)
    try:
        env.reset(seed=0)
        with pytest.raises(InputError, match="^action: expected two finite numbers"):
            env.step(np.zeros(shape, np.float32))
    finally:
        env.close()
