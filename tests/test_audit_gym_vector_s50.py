"""Audit (session 50): the gymnasium environments under vectorisation, wrappers and
serialisation (``envs/``, ``docs/gym.md``, the registered ids), on the real highway-env.

check_env for every id; Sync/Async vector envs (shared memory on and off) against the
single envs run one by one, with autoreset; cloudpickle mid-episode (also into a fresh
process); the common wrappers, RecordVideo into a tmp folder; observations in the space
and info keys as docs/gym.md lists them; close(); reset(options=...); EnvSpec JSON.
Episodes are kept to a few steps with ``max_time_s``.
"""

from __future__ import annotations

import gc
import json
import math
import os
import re
import subprocess
import sys
import warnings
from dataclasses import fields
from pathlib import Path

import cloudpickle
import gymnasium as gym
import numpy as np
import pytest
from gymnasium.envs.registration import EnvSpec
from gymnasium.utils.env_checker import check_env
from gymnasium.vector import AsyncVectorEnv, AutoresetMode, SyncVectorEnv
from gymnasium.wrappers import (
    ClipAction,
    FlattenObservation,
    NormalizeObservation,
    RecordEpisodeStatistics,
    RescaleAction,
    TimeLimit,
)

import rrtdrive.envs  # noqa: F401  (registers the ids)
from rrtdrive import Budget
from rrtdrive.envs import ENV_IDS
from rrtdrive.envs.reward import RewardWeights
from rrtdrive.evaluation import EpisodeReport
from rrtdrive.evaluation.report import WALL_CLOCK_FIELDS
from rrtdrive.planning.spacetime import SafetyConfig
from rrtdrive.sim.follower import IDMConfig
from rrtdrive.types import InputError, VehicleParams

DOC = (Path(__file__).resolve().parents[1] / "docs" / "gym.md").read_text()
PARKING = "rrtdrive/Parking-v0"
TRAFFIC = "rrtdrive/OvertakeTraffic-v0"
ZERO = np.zeros(2, np.float32)
# 0.25 s at 20 Hz: an episode of 5 steps, so that a vector env autoresets within 12.
SHORT = {"max_time_s": 0.25, "residual": True}
N_STEPS = 12
SEEDS = (3, 7)


def _actions(n=N_STEPS, seed=0):
    return np.random.default_rng(seed).uniform(-1, 1, (n, 2, 2)).astype(np.float32)


def _ticked(text):
    return re.findall(r"`([a-z_]+)`", text)


def _documented_info_keys():
    """The info keys docs/gym.md's Info section lists: every step, last step, reset."""
    info = DOC.split("## Info", 1)[1].split("\n## ", 1)[0]
    every = _ticked(info.split("Every step:", 1)[1].split(". On the last step", 1)[0])
    last = _ticked(info.split("On the last step also", 1)[1].split(":", 1)[0])
    reset = _ticked(info.split("`reset` returns", 1)[1].split(".", 1)[0])
    return set(every), set(last), set(reset)


STEP_KEYS, END_KEYS, RESET_KEYS = _documented_info_keys()
METRIC_KEYS = {f.name for f in fields(EpisodeReport)} - set(WALL_CLOCK_FIELDS)


def test_the_documented_info_keys_were_read_from_docs():
    # Guards the parser: the doc's lists, not an empty set, are what the tests compare.
    assert {"episode_seed", "time_s", "reward_terms", "crashed"} <= STEP_KEYS
    assert END_KEYS == {"status", "is_success", "metrics"}
    assert RESET_KEYS == {"episode_seed", "scenario", "path_length_m"}


# --------------------------------------------------------------------------- check_env


@pytest.mark.parametrize("env_id", list(ENV_IDS))
def test_check_env_passes_for_every_registered_id_without_warnings(env_id):
    env = gym.make(env_id, render_mode="rgb_array")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        check_env(env.unwrapped)
    gym_warnings = [str(w.message) for w in caught if "gymnasium" in w.filename]
    assert gym_warnings == []
    env.close()


# --------------------------------------------------------------------------- vector envs


def _make_short(env_id=PARKING, **kw):
    return lambda: gym.make(env_id, **{**SHORT, **kw})


def _run_vector(cls, env_id=PARKING, **vec_kwargs):
    """(obs, rewards, terminated, truncated) per call: the reset, then N_STEPS steps."""
    vec = cls([_make_short(env_id), _make_short(env_id)], **vec_kwargs)
    try:
        obs, info = vec.reset(seed=list(SEEDS))
        assert set(k for k in info if not k.startswith("_")) == RESET_KEYS
        out = [(obs.copy(), np.zeros(2), np.zeros(2, bool), np.zeros(2, bool))]
        for action in _actions():
            obs, rew, term, trunc, _ = vec.step(action)
            for o in obs:
                assert vec.single_observation_space.contains(o)
            out.append((obs.copy(), rew.copy(), term.copy(), trunc.copy()))
    finally:
        vec.close()
    return out


def _run_single_like_next_step_autoreset(env_id, seed, column):
    """One env run with the seeds and actions of sub-env ``column``, reset as NEXT_STEP does."""
    env = _make_short(env_id)()
    obs, _ = env.reset(seed=seed)
    out, done = [(obs, 0.0, False, False)], False
    for action in _actions():
        if done:  # gymnasium's NEXT_STEP autoreset: this step resets, reward 0
            obs, _ = env.reset()
            out.append((obs, 0.0, False, False))
            done = False
            continue
        obs, rew, term, trunc, _ = env.step(action[column])
        out.append((obs, rew, term, trunc))
        done = term or trunc
    env.close()
    return out


_SINGLE_CACHE: dict[str, list] = {}


def _single_reference(env_id):
    if env_id not in _SINGLE_CACHE:
        runs = [_run_single_like_next_step_autoreset(env_id, s, c) for c, s in enumerate(SEEDS)]
        _SINGLE_CACHE[env_id] = [
            (
                np.stack([runs[0][k][0], runs[1][k][0]]),
                np.array([runs[0][k][1], runs[1][k][1]]),
                np.array([runs[0][k][2], runs[1][k][2]]),
                np.array([runs[0][k][3], runs[1][k][3]]),
            )
            for k in range(N_STEPS + 1)
        ]
    return _SINGLE_CACHE[env_id]


VECTORS = {
    "sync": (SyncVectorEnv, {}),
    "async-shared-memory": (AsyncVectorEnv, {"shared_memory": True}),
    "async-no-shared-memory": (AsyncVectorEnv, {"shared_memory": False}),
}


@pytest.mark.parametrize(
    ("kind", "env_id"),
    [
        ("sync", PARKING),
        ("sync", "rrtdrive/UTurn-v0"),
        ("async-shared-memory", PARKING),
        ("async-shared-memory", "rrtdrive/UTurn-v0"),
        ("async-no-shared-memory", PARKING),
    ],
)
def test_a_seeded_vector_run_equals_the_single_envs_run_one_by_one(kind, env_id):
    cls, kwargs = VECTORS[kind]
    got = _run_vector(cls, env_id, **kwargs)
    want = _single_reference(env_id)
    ends = [k for k, (_, _, te, tr) in enumerate(want) if (te | tr).any()]
    assert ends, "no episode ended: autoreset was not exercised"
    assert ends[0] + 1 <= N_STEPS  # the step after an end (the autoreset) was run
    for k, (g, w) in enumerate(zip(got, want, strict=True)):
        for a, b in zip(g, w, strict=True):
            np.testing.assert_array_equal(a, b, err_msg=f"{kind} step {k}")
    # The autoreset step returns the new episode's first observation with reward 0.
    k = ends[0] + 1
    assert np.all(got[k][1][(want[ends[0]][2] | want[ends[0]][3])] == 0.0)


def test_a_seeded_vector_run_is_the_same_twice():
    first = _run_vector(SyncVectorEnv)
    second = _run_vector(SyncVectorEnv)
    for a, b in zip(first, second, strict=True):
        for x, y in zip(a, b, strict=True):
            np.testing.assert_array_equal(x, y)
    # ... and seeds make the two sub-envs differ.
    assert not np.array_equal(first[0][0][0], first[0][0][1])


@pytest.mark.parametrize("cls", [SyncVectorEnv, AsyncVectorEnv])
def test_same_step_autoreset_returns_the_documented_final_info(cls):
    vec = cls(
        [_make_short(max_time_s=0.2), _make_short(max_time_s=0.3)],
        autoreset_mode=AutoresetMode.SAME_STEP,
    )
    vec.reset(seed=0)
    seen = []
    for _ in range(8):
        obs, _, term, trunc, info = vec.step(np.zeros((2, 2), np.float32))
        assert vec.observation_space.contains(obs)
        if (term | trunc).any():
            done = term | trunc
            final = info["final_info"]
            assert END_KEYS | STEP_KEYS <= set(final)
            assert list(final["_status"]) == list(done)
            assert all(s == "timeout" for s in final["status"][done])
            assert {k for k in final["metrics"] if not k.startswith("_")} == METRIC_KEYS
            for i in np.flatnonzero(done):
                assert vec.single_observation_space.contains(info["final_obs"][i])
            seen.extend(np.flatnonzero(done))
    vec.close()
    assert set(seen) == {0, 1}


@pytest.mark.parametrize("cls", [SyncVectorEnv, AsyncVectorEnv])
def test_a_vector_of_different_scenarios_and_maps_steps_through_autoresets(cls):
    # docs/gym.md: "for more variety, give several maps several environments".
    fns = [
        lambda: gym.make("rrtdrive/Map-v0", scenario="parking_lot", max_time_s=0.2),
        lambda: gym.make(
            "rrtdrive/Map-v0",
            scenario="kerbside",
            scenario_options={"reverse": True},
            max_time_s=0.3,
        ),
        lambda: gym.make("rrtdrive/UTurn-v0", max_time_s=0.25),
        lambda: gym.make("rrtdrive/Overtake-v0", max_time_s=0.2),
    ]
    vec = cls(fns)
    _, info = vec.reset(seed=0)
    assert list(info["scenario"]) == ["parking_lot", "kerbside", "u-turn", "overtake"]
    ended = np.zeros(4, bool)
    for _ in range(8):
        obs, rew, term, trunc, info = vec.step(np.zeros((4, 2), np.float32))
        assert vec.observation_space.contains(obs) and np.all(np.isfinite(rew))
        ended |= term | trunc
        if "status" in info:
            assert set(info["status"][info["_status"]]) <= {"timeout"}
    vec.close()
    assert ended.all()


def test_reset_options_reach_every_sub_env_of_a_vector():
    vec = SyncVectorEnv([_make_short(), _make_short()])
    obs, info = vec.reset(seed=[1, 2], options={"episode_seed": 5})
    assert list(info["episode_seed"]) == [5, 5]
    np.testing.assert_array_equal(obs[0], obs[1])
    vec.close()


# --------------------------------------------------------------------------- pickling


def _mid_episode(env_id, render_mode=None, steps=3):
    env = gym.make(env_id, residual=True, render_mode=render_mode)
    env.reset(seed=1)
    for _ in range(steps):
        env.step(np.full(2, 0.3, np.float32))
    return env


@pytest.mark.parametrize("env_id", list(ENV_IDS))
def test_an_env_pickled_mid_episode_carries_on_as_the_original(env_id):
    env = _mid_episode(env_id)
    copy = cloudpickle.loads(cloudpickle.dumps(env))
    action = np.array([0.5, -0.2], np.float32)
    for _ in range(3):
        a, b = env.step(action), copy.step(action)
        np.testing.assert_array_equal(a[0], b[0])
        assert a[1:4] == b[1:4]
        assert a[4]["time_s"] == b[4]["time_s"]
    # The generator came along too: the next drawn episode is the same one.
    assert env.reset()[1]["episode_seed"] == copy.reset()[1]["episode_seed"]
    env.close()
    copy.close()


def test_an_env_pickled_before_reset_and_after_rendering_works():
    fresh = cloudpickle.loads(cloudpickle.dumps(gym.make(PARKING)))
    assert (
        fresh.reset(seed=4)[1]["episode_seed"] == gym.make(PARKING).reset(seed=4)[1]["episode_seed"]
    )
    env = _mid_episode("rrtdrive/Overtake-v0", render_mode="rgb_array")
    env.render()
    copy = cloudpickle.loads(cloudpickle.dumps(env))
    env.step(ZERO)
    copy.step(ZERO)
    np.testing.assert_array_equal(env.render(), copy.render())


def test_an_env_pickled_mid_episode_runs_on_in_a_fresh_process(tmp_path):
    env = _mid_episode("rrtdrive/Overtake-v0")
    blob = tmp_path / "env.pkl"
    blob.write_bytes(cloudpickle.dumps(env))
    out = tmp_path / "obs.npy"
    code = (
        "import cloudpickle, numpy as np\n"
        f"e = cloudpickle.loads(open({str(blob)!r}, 'rb').read())\n"
        "a = np.array([0.5, -0.3], np.float32)\n"
        f"np.save({str(out)!r}, np.stack([e.step(a)[0] for _ in range(4)]))\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True, timeout=120)
    action = np.array([0.5, -0.3], np.float32)
    here = np.stack([env.step(action)[0] for _ in range(4)])
    np.testing.assert_array_equal(np.load(out), here)


# --------------------------------------------------------------------------- wrappers


def test_time_limit_and_episode_statistics_count_the_steps_and_the_return():
    env = RecordEpisodeStatistics(TimeLimit(gym.make(PARKING, residual=True), 4))
    env.reset(seed=0)
    total, n = 0.0, 0
    while n < 10:
        _, rew, term, trunc, info = env.step(np.full(2, 0.3, np.float32))
        total += rew
        n += 1
        if term or trunc:
            break
    assert (n, term, trunc) == (4, False, True)
    assert info["episode"]["l"] == 4
    assert math.isclose(info["episode"]["r"], total, rel_tol=1e-6, abs_tol=1e-12)
    # docs/gym.md: TimeLimit ends the episode without the env knowing (no status).
    assert not (END_KEYS & set(info))
    assert env.unwrapped.report is None


def test_episode_statistics_over_the_envs_own_time_limit():
    env = RecordEpisodeStatistics(gym.make("rrtdrive/Overtake-v0", **SHORT))
    env.reset(seed=0)
    total, n = 0.0, 0
    while True:
        _, rew, term, trunc, info = env.step(np.full(2, 0.3, np.float32))
        total += rew
        n += 1
        if term or trunc:
            break
    assert info["status"] == "timeout" and info["episode"]["l"] == n == 5
    assert math.isclose(info["episode"]["r"], total, rel_tol=1e-6, abs_tol=1e-12)


def test_flatten_and_normalize_observation():
    env = FlattenObservation(NormalizeObservation(gym.make(PARKING, residual=True)))
    plain = gym.make(PARKING, residual=True)
    obs, _ = env.reset(seed=0)
    raw, _ = plain.reset(seed=0)
    assert obs.shape == raw.shape == env.observation_space.shape
    for _ in range(5):
        obs, *_ = env.step(ZERO)
        raw, *_ = plain.step(ZERO)
        assert obs.dtype == np.float32 and np.all(np.isfinite(obs))
        assert env.observation_space.contains(obs)
    # normalising changed the numbers but not what they are computed from
    assert not np.allclose(obs, raw)
    norm = env.env  # NormalizeObservation
    rms = norm.obs_rms
    expected = (raw - rms.mean) / np.sqrt(rms.var + norm.epsilon)
    np.testing.assert_allclose(obs, expected.astype(np.float32), rtol=1e-5, atol=1e-5)


def test_clip_and_rescale_action_reach_the_env_as_the_clipped_rescaled_action():
    low, high = np.full(2, -2.0, np.float32), np.full(2, 2.0, np.float32)
    env = ClipAction(RescaleAction(gym.make(PARKING), low, high))
    plain = gym.make(PARKING)
    env.reset(seed=0)
    plain.reset(seed=0)
    pairs = (([5.0, -0.7], [1.0, -0.35]), ([-2.0, 2.0], [-1.0, 1.0]), ([1.0, 0.0], [0.5, 0.0]))
    for action, direct in pairs:
        a = env.step(np.array(action, np.float32))
        b = plain.step(np.array(direct, np.float32))
        np.testing.assert_allclose(a[0], b[0], rtol=0, atol=1e-6)
        assert math.isclose(a[4]["accel"], b[4]["accel"], abs_tol=1e-6)
        assert math.isclose(a[4]["steer"], b[4]["steer"], abs_tol=1e-6)


def test_record_video_writes_a_drawn_mp4_at_the_env_frame_rate(tmp_path):
    pytest.importorskip("moviepy")  # gymnasium's RecordVideo needs it (docs/gym.md)
    iio = pytest.importorskip("imageio.v3")
    from gymnasium.wrappers import RecordVideo

    folder = tmp_path / "videos"
    base = gym.make("rrtdrive/Overtake-v0", render_mode="rgb_array", action_repeat=2, **SHORT)
    env = RecordVideo(base, str(folder), episode_trigger=lambda i: True, disable_logger=True)
    env.reset(seed=0)
    steps = 0
    while True:
        _, _, term, trunc, _ = env.step(ZERO)
        steps += 1
        if term or trunc:
            break
    env.close()
    videos = sorted(folder.glob("*.mp4"))
    assert len(videos) == 1 and videos[0].stat().st_size > 0
    frames = iio.imread(videos[0])
    assert frames.ndim == 4 and frames.shape[1:] == (320, 960, 3)
    assert len(frames) >= steps  # a frame per step (moviepy may drop the reset one)
    assert all(f.max() > 50 and f.std() > 5 for f in frames)  # drawn, not black
    assert iio.immeta(videos[0])["fps"] == pytest.approx(10.0)  # 20 Hz / action_repeat 2


# ------------------------------------------------------------ spaces and documented info


@pytest.mark.parametrize("env_id", list(ENV_IDS))
def test_observations_stay_in_the_space_and_info_keys_are_the_documented_ones(env_id):
    env = gym.make(env_id, max_time_s=0.3)  # 6 steps, an agent driving alone
    rng = np.random.default_rng(0)
    obs, info = env.reset(seed=0)
    assert env.observation_space.contains(obs)
    assert set(info) == RESET_KEYS
    for _ in range(10):
        obs, rew, term, trunc, info = env.step(rng.uniform(-1, 1, 2).astype(np.float32))
        assert env.observation_space.contains(obs) and math.isfinite(rew)
        if term or trunc:
            break
        assert set(info) == STEP_KEYS
    assert term or trunc
    assert set(info) == STEP_KEYS | END_KEYS
    assert set(info["metrics"]) == METRIC_KEYS
    env.close()


# --------------------------------------------------------------------------- close


def test_close_is_idempotent_and_releases_the_scene():
    env = gym.make(PARKING, render_mode="rgb_array")
    env.close()  # before any reset
    env.reset(seed=0)
    env.render()
    env.step(ZERO)
    env.close()
    env.close()
    u = env.unwrapped
    assert u._sim is None and u._renderer is None and u._loop is None
    with pytest.raises(RuntimeError, match="reset"):
        env.step(ZERO)
    with pytest.raises(RuntimeError, match="reset"):
        env.render()
    assert env.reset(seed=0)[1]["episode_seed"] >= 0  # a closed env can start again
    assert env.render().shape == (640, 640, 3)
    env.close()


def test_make_render_close_cycles_leak_no_file_descriptors():
    def cycle(seed):
        env = gym.make(PARKING, render_mode="rgb_array")
        env.reset(seed=seed)
        env.render()
        env.step(ZERO)
        env.close()

    cycle(0)  # warm: highway-env, pygame and the map's checker load once
    fd = Path("/proc/self/fd")
    if not fd.exists():
        pytest.skip("no /proc")
    gc.collect()
    before = len(os.listdir(fd))
    for seed in range(1, 8):
        cycle(seed)
    gc.collect()
    assert len(os.listdir(fd)) <= before


def test_closing_an_async_vector_env_ends_its_workers_and_twice_is_safe():
    vec = AsyncVectorEnv([_make_short(), _make_short()])
    vec.reset(seed=0)
    vec.step(np.zeros((2, 2), np.float32))
    workers = list(vec.processes)
    vec.close()
    assert not any(p.is_alive() for p in workers)
    vec.close()


# --------------------------------------------------------------------------- reset options


def test_reset_options_behave_as_documented():
    env = gym.make(PARKING, disable_env_checker=True)
    a, info_a = env.reset(seed=1, options={"episode_seed": 9})
    b, info_b = env.reset(seed=2, options={"episode_seed": np.int64(9)})
    assert info_a["episode_seed"] == info_b["episode_seed"] == 9
    np.testing.assert_array_equal(a, b)  # the episode seed fixes the episode, not `seed`
    for options in (None, {}, {"episode_seed": None}):
        assert (
            env.reset(seed=3, options=options)[1]["episode_seed"]
            == env.reset(seed=3)[1]["episode_seed"]
        )
    for options, field in (
        ({"seed": 1}, "options.seed"),
        ({"episode_seed": -1}, "options.episode_seed"),
        ({"episode_seed": 1.5}, "options.episode_seed"),
        ({"episode_seed": True}, "options.episode_seed"),
        ({"episode_seed": 2**63}, "options.episode_seed"),
        ([("episode_seed", 1)], "options"),
    ):
        with pytest.raises(InputError, match=re.escape(field)):
            env.reset(options=options)
    ranged = gym.make(PARKING, seed_range=(10, 13))
    drawn = {ranged.reset(seed=s)[1]["episode_seed"] for s in range(12)}
    assert drawn <= {10, 11, 12} and len(drawn) > 1


# --------------------------------------------------------------------------- EnvSpec JSON


def _round_trip(env):
    return gym.make(EnvSpec.from_json(env.spec.to_json()))


def _same_first_steps(a, b, n=3):
    oa, ia = a.reset(seed=2)
    ob, ib = b.reset(seed=2)
    np.testing.assert_array_equal(oa, ob)
    assert ia == ib
    for _ in range(n):
        ra, rb = a.step(np.full(2, 0.2, np.float32)), b.step(np.full(2, 0.2, np.float32))
        np.testing.assert_array_equal(ra[0], rb[0])
        assert ra[1] == rb[1]


@pytest.mark.parametrize("env_id", list(ENV_IDS))
def test_envspec_json_round_trip_for_every_id(env_id):
    env = gym.make(env_id)
    again = _round_trip(env)
    assert again.spec == env.spec
    assert again.unwrapped.config == env.unwrapped.config
    _same_first_steps(env, again)


@pytest.mark.parametrize("env_id", list(ENV_IDS))
def test_spec_kwargs_saved_as_json_make_the_same_env_through_gym_make(env_id):
    # The rl-zoo pattern: env_kwargs kept in a JSON/YAML file, given back to gym.make.
    env = gym.make(env_id, residual=True)
    kwargs = json.loads(json.dumps(dict(env.spec.kwargs)))
    assert gym.make(env_id, **kwargs).unwrapped.config == env.unwrapped.config


ROUND_TRIP_OPTIONS = [
    (PARKING, {"controller": "lqr", "residual": True, "reward": {"cte": 100.0}, "n_ref_points": 5}),
    (PARKING, {"reward": RewardWeights(cte=100.0), "render_mode": "rgb_array"}),
    (PARKING, {"scenario_options": {"jitter": (0.5, 0.5, 0.05)}, "seed_range": (0, 1000)}),
    (PARKING, {"scenario_options": {"vehicle": VehicleParams(wheelbase=2.7)}}),
    ("rrtdrive/ParkingReverseIn-v0", {"scenario_options": {"jitter": (0.5, 0.5, 0.05)}}),
    ("rrtdrive/Overtake-v0", {"scenario_options": {"oncoming": 2}, "max_episode_steps": 7}),
    ("rrtdrive/OvertakeTraffic-v0", {"replan_options": {"wall_limit": False}, "n_vehicles": 2}),
    ("rrtdrive/Map-v0", {"scenario": "kerbside", "scenario_options": {"reverse": True}}),
    pytest.param(
        PARKING,
        {"budget": Budget(max_iterations=5000)},
        id="budget",
    ),
    pytest.param(
        TRAFFIC,
        {"replan_options": {"wall_limit": False, "safety": SafetyConfig()}},
        id="replan-safety",
    ),
    pytest.param(
        TRAFFIC,
        {"replan_options": {"wall_limit": False, "idm": IDMConfig()}},
        id="replan-idm",
    ),
]


@pytest.mark.parametrize(("env_id", "kwargs"), ROUND_TRIP_OPTIONS)
def test_envspec_json_round_trip_keeps_the_callers_options(env_id, kwargs):
    env = gym.make(env_id, **kwargs)
    again = _round_trip(env)
    assert type(again) is type(env)  # the same wrappers (TimeLimit for max_episode_steps)
    assert again.render_mode == env.render_mode
    names = ("controller", "residual", "n_ref_points", "n_vehicles", "budget", "reward", "replan")
    for name in names:
        assert getattr(again.unwrapped.config, name) == getattr(env.unwrapped.config, name)
    assert again.observation_space == env.observation_space
    _same_first_steps(env, again)
    assert again.unwrapped._scenario.vehicle == env.unwrapped._scenario.vehicle


def test_map_env_takes_a_pathlib_path(tmp_path):
    """save_map takes any path-like; the Map-v0 env refused a pathlib.Path."""
    from rrtdrive.maps import builtin_map, save_map

    save_map(builtin_map("kerbside"), tmp_path / "k.json")
    env = gym.make("rrtdrive/Map-v0", scenario=tmp_path / "k.json",
                   scenario_options={"reverse": True})  # fmt: skip
    try:
        assert env.unwrapped.config.scenario == str(tmp_path / "k.json")
        env.reset(seed=0)
    finally:
        env.close()


def test_a_requested_seed_failure_names_the_envs_option_not_a_cli_flag():
    """The planners say "try --reverse" (the CLI's); the env says its own option."""
    env = gym.make("rrtdrive/Map-v0", scenario="kerbside")
    try:
        with pytest.raises(RuntimeError) as info:
            env.reset(options={"episode_seed": 4})
    finally:
        env.close()
    text = str(info.value)
    assert "--reverse" not in text and "scenario_options={'reverse': True}" in text, text


def test_close_releases_the_highway_env_scene():
    """close() left the scene reachable through the env's other handles (about 0.9 MB)."""
    import gc
    import weakref

    env = gym.make(PARKING)
    env.reset(seed=0)
    for _ in range(3):
        env.step(env.action_space.sample() * 0)
    scene = weakref.ref(env.unwrapped._sim.unwrapped)
    env.close()
    gc.collect()
    assert scene() is None
