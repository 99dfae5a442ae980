"""Headless video: real highway-env frames, not blank, written atomically as MP4."""

from __future__ import annotations

import math

import imageio.v2 as imageio
import numpy as np
import pytest

from rrtdrive.sim.runner import run_episode
from rrtdrive.sim.tasks import make_scenario
from rrtdrive.sim.video import frame_is_blank, render_frames, write_video
from rrtdrive.types import InputError, Path


@pytest.fixture(scope="module")
def episode():
    scen = make_scenario("overtake", 0, jitter=(0.0, 0.0, 0.0))
    x = np.arange(scen.start.x, 92.0 + 1e-9, 0.1)

    def ramp(u):
        return (1 - np.cos(math.pi * np.clip(u, 0, 1))) / 2

    y = scen.lane_y + 4.0 * (ramp((x - 15) / 25) - ramp((x - 60) / 25))
    dy = np.gradient(y, x)
    kappa = np.gradient(dy, x) / (1 + dy**2) ** 1.5
    path = Path(np.column_stack([x, y, np.arctan(dy), kappa]), np.zeros((0, 2)))
    return run_episode(scen, path, "lqr", 0)


def test_frames_are_real_and_not_blank(episode, tmp_path):
    frames = list(render_frames(episode, stride=60))
    assert len(frames) == len(range(0, len(episode.log.states), 60)) + 1  # plus the final state
    for f in frames:
        assert f.dtype == np.uint8 and f.shape == (320, 960, 3)
        assert not frame_is_blank(f)
    # The scene changes: the car moved.
    assert np.abs(frames[0].astype(int) - frames[-1].astype(int)).sum() > 0
    # The planned path (blue) and the driven trace (red) are drawn.
    mid = frames[len(frames) // 2].reshape(-1, 3).astype(int)
    assert np.any((mid[:, 2] > 200) & (mid[:, 0] < 80))  # path colour (40, 90, 255)
    assert np.any((mid[:, 0] > 200) & (mid[:, 1] < 90) & (mid[:, 2] < 90))  # trace colour
    imageio.imwrite(tmp_path / "frame.png", frames[len(frames) // 2])
    assert frame_is_blank(np.zeros((10, 10, 3), np.uint8))


@pytest.mark.parametrize("name", ["overtake", "parking"])
def test_reused_background_gives_the_same_pixels(episode, name):
    # With a fixed camera the lanes are drawn once; every frame must equal a frame
    # drawn from scratch (the path, goal, objects, cars and trace still on top).
    if name == "parking":
        scen = make_scenario("parking", 2)
        st = scen.start
        d = np.arange(0.0, 12.0, 0.1)
        ahead = np.column_stack([st.x + d * np.cos(st.yaw), st.y + d * np.sin(st.yaw),
                                 np.full_like(d, st.yaw), 0 * d])
        episode = run_episode(scen, Path(ahead, np.zeros((0, 2))), "pure-pursuit", 2)
    fast = list(render_frames(episode, stride=40))
    slow = list(render_frames(episode, stride=40, reuse_background=False))
    assert len(fast) == len(slow) >= 3
    for a, b in zip(fast, slow, strict=True):
        assert np.array_equal(a, b)
    assert not np.array_equal(fast[0], fast[-1])  # the car moved between frames


def test_write_video_atomically(episode, tmp_path):
    out = tmp_path / "ep.mp4"
    n = write_video(episode, out, stride=20)
    assert out.exists() and out.stat().st_size > 1000
    assert [p.name for p in tmp_path.iterdir()] == ["ep.mp4"]  # no temporary left over
    reader = imageio.get_reader(out)
    frames = [f for f in reader]
    reader.close()
    assert len(frames) == n
    assert not frame_is_blank(frames[len(frames) // 2])


def test_video_rejects_bad_targets(episode, tmp_path):
    with pytest.raises(InputError, match="mp4"):
        write_video(episode, tmp_path / "x.avi")
    with pytest.raises(InputError, match="does not exist"):
        write_video(episode, tmp_path / "missing" / "x.mp4")
    with pytest.raises(InputError, match="stride"):
        list(render_frames(episode, stride=0))
