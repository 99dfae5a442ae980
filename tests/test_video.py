"""Headless video: real highway-env frames, not blank, written atomically as MP4."""

from __future__ import annotations

import math

import imageio.v2 as imageio
import numpy as np
import pytest

from rrtdrive.sim.runner import run_episode
from rrtdrive.sim.tasks import make_scenario
from rrtdrive.sim.video import frame_is_blank, render_frames, write_video
from rrtdrive.types import InputError, Path, Pose


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


def _canvas_pair(scen):
    from rrtdrive.envs.render import view_for
    from rrtdrive.sim.render import SceneCanvas
    from rrtdrive.sim.scenes import build_env

    env = build_env(scen)
    view = view_for(scen.map.bounds, scen.lane_y)
    return env, SceneCanvas(*view), SceneCanvas(*view, reuse_static=False)


def test_static_layer_redraws_parked_cars_under_the_ego_and_follows_changes():
    # The ego on top of the stopped car of the overtake scene (a highway-env vehicle drawn
    # after the ego), then an obstacle hit: every frame equals highway-env's full redraw.
    from rrtdrive.sim.render import is_parked

    scen = make_scenario("overtake", 0)
    env, fast, scratch = _canvas_pair(scen)
    try:
        road, ego = env.unwrapped.road, env.unwrapped.vehicle
        parked = [v for v in road.vehicles if is_parked(v)]
        assert parked and all(road.vehicles.index(p) > road.vehicles.index(ego) for p in parked)
        poses = [scen.start] + [Pose(p.position[0] + 1.0, p.position[1], p.heading + 0.4)
                                for p in parked[:3]]
        goal = (scen.goal.x, scen.goal.y)
        path = np.array([[scen.start.x, scen.start.y], [scen.goal.x, scen.goal.y]])
        frames = []
        for i, pose in enumerate(poses + poses[:1]):
            ego.set_pose(pose, speed=0.5)
            if i == len(poses):
                road.objects[0].crashed = True  # a hit obstacle turns red: redraw the layer
            for canvas in (fast, scratch):
                canvas.draw(road, 20, path, goal)
            a = fast.frame(["x"])
            assert np.array_equal(a, scratch.frame(["x"]))
            frames.append(a)
        assert not np.array_equal(frames[0], frames[-1])  # the red obstacle shows
        assert fast.static_draws == 2 and fast.static_reuses == len(poses) - 1
    finally:
        env.close()


def test_write_video_reports_progress(episode, tmp_path):
    seen = []
    n = write_video(episode, tmp_path / "p.mp4", stride=50, progress=lambda *a: seen.append(a))
    assert seen == [(i, n) for i in range(1, n + 1)]


def test_mp4_writer_errors_surface_and_leave_no_file(tmp_path):
    from rrtdrive.sim.mp4 import Mp4Writer

    out = tmp_path / "bad.mp4"
    w = Mp4Writer(out, fps=10)
    w.append(np.zeros((32, 32, 3), np.uint8))
    w.append(np.zeros((48, 32, 3), np.uint8))  # a different size: imageio refuses it
    with pytest.raises(ValueError, match="same size"):
        for _ in range(20):  # the writer thread's error comes back on a later call
            w.append(np.zeros((32, 32, 3), np.uint8))
        w.close()
    w.abort()
    assert list(tmp_path.iterdir()) == []
    with pytest.raises(InputError, match="fps"):
        Mp4Writer(out, fps=0)
    with Mp4Writer(out, fps=10) as ok:
        ok.append(np.full((32, 32, 3), 90, np.uint8))
    assert [p.name for p in tmp_path.iterdir()] == ["bad.mp4"] and ok.frames == 1


def test_the_read_out_panel_goes_where_it_hides_least_of_the_drive():
    from rrtdrive.sim.render import PANEL_CORNERS, SceneCanvas

    canvas = SceneCanvas((960, 240), 14.4, (30.0, 5.0))
    # A drive along the top-left of a narrow street: there the panel hid the start.
    along_top = np.column_stack([np.linspace(0.0, 25.0, 50), np.full(50, 8.0)])
    assert canvas.panel_corner(along_top, 290, 4) == "top-right"
    # Nothing under any corner: the top left, as before.
    middle = np.array([[30.0, 5.0]])
    assert canvas.panel_corner(middle, 290, 4) == "top-left"
    # The drawn panel is where it was asked for (its white fill at that corner).
    frame = canvas.frame(["t 0.00 s"], panel_width=290, corner="bottom-right")
    assert (frame[-10, -20] == 255).all() and not (frame[10, 20] == 255).all()
    with pytest.raises(ValueError, match="corner"):
        canvas.frame(["x"], corner="middle")
    assert PANEL_CORNERS[0] == "top-left"


def test_a_narrow_street_video_keeps_its_start_car_clear(tmp_path):
    ep = run_episode(make_scenario("parallel-parking", 0), "hybrid-a-star", "pure-pursuit", 0)
    first = next(iter(render_frames(ep, stride=10**6)))
    assert first.shape == (240, 960, 3)
    # The panel's white fill is at the top right, away from the car at the left.
    assert (first[10, -20] == 255).all() and not (first[10, 20] == 255).all()


def test_what_the_car_hit_turns_red_in_the_video():
    # Driven straight at the overtake's stopped car: the replay drew the crashed ego red
    # and the car it hit in its usual colour, as if it had hit nothing (highway-env turns
    # both red live; docs/video.md says a hit obstacle turns red).
    from rrtdrive.sim.video import _camera_for

    scen = make_scenario("overtake", 0, jitter=(0.0, 0.0, 0.0))
    x = np.arange(scen.start.x, 92.0 + 1e-9, 0.1)
    zero = np.zeros_like(x)
    path = Path(np.column_stack([x, np.full_like(x, scen.lane_y), zero, zero]), np.zeros((0, 2)))
    ep = run_episode(scen, path, "lqr", 0)
    assert ep.log.crashed[-1]
    last = list(render_frames(ep, stride=10**6))[-1]
    red_columns = np.flatnonzero(np.all(last == (255, 100, 100), axis=-1).any(axis=0))
    scaling = _camera_for(ep)[1]
    # Red along both cars, nose to tail (4.3 m each), not along the ego alone.
    assert red_columns[-1] - red_columns[0] > 1.8 * scen.vehicle.length * scaling


@pytest.mark.parametrize("stride", [1, 7, 60, 1000])
def test_a_video_lasts_the_episodes_simulated_time(episode, tmp_path, stride):
    # The final state's frame came after fewer steps than a stride but played a whole
    # stride: 2 frames of an episode at stride 1000 made a video 20 times too long.
    from rrtdrive.sim.video import real_time_fps

    out = tmp_path / f"s{stride}.mp4"
    frames = write_video(episode, out, stride=stride)
    simulated = len(episode.log.states) * episode.log.dt
    fps = real_time_fps(frames, len(episode.log.states), episode.log.dt)
    assert frames / fps == pytest.approx(simulated)
    # The file's own rate (ffmpeg keeps a low rate to two decimals: 0.0543 fps reads 0.05).
    assert imageio.get_reader(out).get_meta_data()["fps"] == pytest.approx(fps, rel=0.05, abs=0.005)
    if stride == 1:
        assert fps == pytest.approx(1.0 / episode.log.dt)


@pytest.mark.parametrize(("option", "field"), [({"stride": 0}, "stride"),
                                               ({"stride": -1}, "stride"),
                                               ({"fps": 0}, "fps")])
def test_write_video_names_a_bad_stride_or_fps(episode, tmp_path, option, field):
    with pytest.raises(InputError, match=f"^{field}:"):
        write_video(episode, tmp_path / "v.mp4", **option)
    assert not (tmp_path / "v.mp4").exists()


def test_a_map_kilometres_long_is_fitted_not_scaled_to_nothing():
    from rrtdrive.sim.scenes import fit_view

    # 9.6 km: under 0.1 px/m, which rounded to 0 (a ZeroDivisionError in the camera).
    size, scaling, _ = fit_view((0.0, 0.0, 9600.0, 10.0))
    assert 0.09 < scaling < 0.1 and size == (960, 240)
    assert 0 < fit_view((0.0, 0.0, 1e6, 10.0))[1] * (1e6 + 6.5) <= 960


def test_the_read_out_cte_is_the_evaluators_on_a_path_with_cusps(monkeypatch):
    # It projected every pose on the whole path, not on the gear segment being driven:
    # on a u-turn driven with a noisy residual it showed the wrong sign on 148 steps.
    import gymnasium as gym

    import rrtdrive.envs  # noqa: F401  (registers the envs)
    from rrtdrive.evaluation.tracking import tracking_errors
    from rrtdrive.sim.render import SceneCanvas

    env = gym.make("rrtdrive/UTurn-v0", controller="pure-pursuit", residual=True)
    env.reset(seed=0)
    rng = np.random.default_rng(0)
    done = False
    while not done:
        _, _, terminated, truncated, _ = env.step(rng.uniform(-1, 1, 2).astype(np.float32))
        done = terminated or truncated
    ep = env.unwrapped.episode
    env.close()
    lines = []
    frame = SceneCanvas.frame

    def spy(self, text, *args, **kwargs):
        lines.append(list(text))
        return frame(self, text, *args, **kwargs)

    monkeypatch.setattr(SceneCanvas, "frame", spy)
    stride = 4
    for _ in render_frames(ep, stride):
        pass
    shown = np.array([float(next(s for s in ln if s.startswith("cte")).split()[1])
                      for ln in lines])
    states = ep.log.states
    cte = tracking_errors(ep.path, states[:, :3], speeds=states[:, 3])[0]
    want = cte[list(range(0, len(states), stride)) + ([len(states) - 1]
                                                       if (len(states) - 1) % stride else [])]
    assert len(ep.path.cusps) >= 1 and np.abs(want).max() > 0.05
    np.testing.assert_allclose(shown, want, atol=0.0011)


def test_abort_returns_although_the_queue_lock_is_held_and_kills_the_encoder(tmp_path):
    """An interrupt inside append() can leave the frame queue's lock held in the caller's
    thread; abort() put a stop mark on that queue and joined the writer thread, so the
    process hung (a SIGTERM during a video in CI). Now it kills ffmpeg and returns."""
    import threading

    from rrtdrive.sim.mp4 import Mp4Writer, _encoder_process

    out = tmp_path / "cut.mp4"
    w = Mp4Writer(out, fps=10)
    for _ in range(3):
        w.append(np.full((32, 32, 3), 60, np.uint8))
    while w._queue.qsize():  # the writer thread has handed them to ffmpeg
        threading.Event().wait(0.01)
    process = _encoder_process(w._writer)
    assert process is not None and process.poll() is None
    assert w._queue.mutex.acquire(timeout=5)  # as a Terminated raised inside put() leaves it
    try:
        done = threading.Thread(target=w.abort, daemon=True)
        done.start()
        done.join(timeout=30)  # a hang detector, not a speed limit
        assert not done.is_alive(), "abort() blocked on the frame queue"
    finally:
        w._queue.mutex.release()
    assert process.poll() is not None  # ffmpeg killed, not left encoding
    w._thread.join(timeout=30)
    assert not w._thread.is_alive()  # the writer thread ended by itself
    assert list(tmp_path.iterdir()) == []
    w.abort()  # idempotent
    with pytest.raises(RuntimeError, match="aborted"):
        w.close()


@pytest.mark.parametrize(("frequency", "fps"), [(20, 20.0), (60, 60.0), (200, 50.0)])
def test_a_high_frequency_video_keeps_within_60_fps(tmp_path, capsys, frequency, fps):
    """``--frequency 1000 --video`` wrote a 1000 fps MP4, which players (and imageio) read
    as 0 fps (an audit); by default every step up to 60 Hz, above it every n-th."""
    import json

    import imageio_ffmpeg

    from rrtdrive.cli import main

    out, js = tmp_path / "v.mp4", tmp_path / "v.json"
    assert main(["simulate", "parking", "--frequency", str(frequency), "--max-time", "1",
                 "--video", str(out), "--json", str(js)]) in (0, 1)  # fmt: skip
    steps = json.loads(js.read_text())["steps"]
    stride = math.ceil(frequency / 60)
    frames, seconds = imageio_ffmpeg.count_frames_and_secs(str(out))
    assert frames == len(range(0, steps + 1, stride)) + (steps % stride != 0)
    assert imageio.get_reader(out).get_meta_data()["fps"] == pytest.approx(fps, rel=0.02)
    assert seconds == pytest.approx(steps / frequency, abs=1.5 / fps)


def test_video_fps_sets_the_rate_and_needs_video(tmp_path, capsys):
    """Slow motion: the same frames at the rate asked for (there was no way to set it)."""
    import json

    import imageio_ffmpeg

    from rrtdrive.cli import main

    out, js = tmp_path / "slow.mp4", tmp_path / "slow.json"
    assert main(["simulate", "parking", "--max-time", "1", "--video", str(out),
                 "--video-fps", "5", "--json", str(js)]) in (0, 1)  # fmt: skip
    steps = json.loads(js.read_text())["steps"]
    frames, seconds = imageio_ffmpeg.count_frames_and_secs(str(out))
    assert frames == steps + 1  # every step at 20 Hz, as without --video-fps
    assert imageio.get_reader(out).get_meta_data()["fps"] == pytest.approx(5.0)
    assert seconds == pytest.approx(frames / 5.0, abs=0.25)
    capsys.readouterr()
    assert main(["simulate", "parking", "--video-fps", "5"]) == 2
    assert "--video-fps: only with --video" in capsys.readouterr().err
    with pytest.raises(SystemExit) as exc:  # argparse's own refusal of the value
        main(["simulate", "parking", "--video", str(out), "--video-fps", "0"])
    assert exc.value.code == 2
    assert "--video-fps: expected a finite number > 0" in capsys.readouterr().err
