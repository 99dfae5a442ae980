"""Headless MP4 of any agent's episodes: the RecordMP4 wrapper and record_episode."""

from __future__ import annotations

import gymnasium as gym
import imageio.v2 as imageio
import numpy as np
import pytest

import rrtdrive  # noqa: F401  (registers the ids)
from rrtdrive.envs.video import RecordMP4, record_episode
from rrtdrive.sim.video import frame_is_blank
from rrtdrive.types import InputError


def read_frames(path):
    reader = imageio.get_reader(path)
    try:
        return [f for f in reader], reader.get_meta_data()
    finally:
        reader.close()


def test_records_an_agent_episode_as_mp4(tmp_path):
    env = RecordMP4(
        gym.make(
            "rrtdrive/Overtake-v0", render_mode="rgb_array", residual=True, action_repeat=4,
            max_time_s=6.0,
        ),
        tmp_path,
    )
    assert env.fps == 5.0  # 20 Hz simulation, 4 steps per action
    rng = np.random.default_rng(0)
    total, info = record_episode(
        env, lambda obs: rng.uniform(-0.2, 0.2, 2).astype(np.float32), seed=0
    )
    env.close()
    video = tmp_path / "episode-0000.mp4"
    assert info["video"] == str(video)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["episode-0000.mp4"]  # no temporaries
    frames, meta = read_frames(video)
    steps = int(round(info["time_s"] * 20)) // 4
    assert len(frames) == steps + 1  # the reset frame plus one per step
    assert meta["fps"] == 5.0
    assert frames[0].shape == (320, 960, 3)
    assert not frame_is_blank(frames[len(frames) // 2])
    assert video.stat().st_mode & 0o044  # readable by others, as any new file (umask)
    assert np.abs(frames[0].astype(int) - frames[-1].astype(int)).sum() > 0  # the car moved


def test_trigger_unfinished_episode_and_stock_env(tmp_path):
    # Any gymnasium env with rgb_array rendering, not only rrtdrive's.
    env = RecordMP4(
        gym.make("CartPole-v1", render_mode="rgb_array"), tmp_path, name_prefix="cart",
        episode_trigger=lambda i: i % 2 == 1,
    )
    env.action_space.seed(0)
    for i in range(3):
        env.reset(seed=i)
        for _ in range(5):
            _, _, terminated, truncated, _ = env.step(env.action_space.sample())
            if terminated or truncated:
                break
    env.close()  # episode 2 is not recorded; episode 1 was written at the next reset
    assert [p.name for p in env.written] == ["cart-0001.mp4"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cart-0001.mp4"]
    frames, _ = read_frames(tmp_path / "cart-0001.mp4")
    assert len(frames) == 6 and frames[0].shape[:2] == (400, 600)


def test_bad_inputs(tmp_path):
    with pytest.raises(InputError, match="render_mode"):
        RecordMP4(gym.make("rrtdrive/Overtake-v0"), tmp_path)
    base = gym.make("rrtdrive/Overtake-v0", render_mode="rgb_array")
    with pytest.raises(InputError, match="fps"):
        RecordMP4(base, tmp_path, fps=0)
    with pytest.raises(InputError, match="name_prefix"):
        RecordMP4(base, tmp_path, name_prefix="")
    with pytest.raises(InputError, match="env"):
        record_episode(base, lambda obs: np.zeros(2))
    with pytest.raises(InputError, match="max_steps"):
        record_episode(RecordMP4(base, tmp_path), lambda obs: np.zeros(2), max_steps=0)
    base.close()


def test_max_steps_writes_a_partial_video(tmp_path):
    env = RecordMP4(gym.make("rrtdrive/Parking-v0", render_mode="rgb_array"), tmp_path)
    _, info = record_episode(env, lambda obs: np.zeros(2, np.float32), seed=0, max_steps=3)
    env.close()
    frames, _ = read_frames(info["video"])
    assert len(frames) == 4 and frames[0].shape == (640, 640, 3)
