"""Stock highway-env envs driven by our ego, planner and controller through ``env.step``."""

from __future__ import annotations

import json

import gymnasium as gym
import highway_env  # noqa: F401  (registers its envs)
import numpy as np
import pytest
from highway_env.utils import lmap
from hypothesis import assume, example, given, settings
from hypothesis import strategies as st

from rrtdrive.cli import main
from rrtdrive.evaluation import evaluate
from rrtdrive.sim.ego import EgoVehicle
from rrtdrive.sim.extract import attach_ego, map_from_env
from rrtdrive.sim.runner import EpisodeConfig
from rrtdrive.sim.stock import (
    STOCK_ENVS,
    _normalise,
    _steering_action,
    drive_stock_env,
    make_stock_env,
)
from rrtdrive.types import Budget, InputError

DETERMINISTIC = EpisodeConfig(budget=Budget(max_time_s=1e6))


def test_the_stock_ids_exist_in_this_highway_env():
    for env_id in STOCK_ENVS:
        assert env_id in gym.registry


def test_stock_episode_stops_at_the_goal_and_highway_env_agrees():
    run = drive_stock_env("parking-v0", 2, "hybrid-a-star", "pure-pursuit", DETERMINISTIC)
    report = evaluate(run.episode)
    assert report.success and run.highway_env_success
    assert run.episode.status == "arrived" and run.episode.log.states[-1, 3] == 0.0
    # highway-env's own termination said success on the way in, before we stopped.
    assert run.highway_env_terminated_s is not None
    assert run.highway_env_terminated_s <= report.duration_s <= run.episode.scenario.max_time_s
    assert not run.highway_env_truncated
    assert run.to_json()["highway_env_success"] is True
    # The float32 action never decodes past the controller's steering clip.
    assert report.executed_curvature_violation_share == 0.0
    again = drive_stock_env("parking-v0", 2, "hybrid-a-star", "pure-pursuit", DETERMINISTIC)
    assert np.array_equal(again.episode.log.states, run.episode.log.states)  # deterministic


@settings(max_examples=300, deadline=None)
@given(st.floats(-0.6, 0.6))
def test_the_steering_action_decodes_to_no_more_than_the_command(steer):
    low, high = -0.5236, 0.5236
    action = _steering_action(steer, low, high)
    decoded = float(lmap(action, [-1, 1], [low, high]))  # highway-env's decoding
    assert abs(decoded) <= abs(steer) or abs(steer) > high
    assert abs(decoded - min(max(steer, low), high)) <= 2e-7


def _one_float32_at_a_time(steer: float, low: float, high: float, cap: int) -> np.float32 | None:
    # The definition: from the rounded action toward the centre, one float32 at a time,
    # until the decoded steering is not larger than the command (None past ``cap`` steps).
    action = np.float32(_normalise(steer, low, high))
    centre = np.float32(_normalise(0.5 * (low + high), low, high))
    for _ in range(cap):
        if abs(float(lmap(action, [-1, 1], [low, high]))) <= abs(steer) or action == centre:
            return action
        action = np.nextafter(action, centre)
    return None


@example(1e-5, -0.5236, 0.5236)  # 46 547 float32s stepped (1e-6 rad: 535 311)
@example(-3e-5, -0.3, 0.5)
@example(0.1, -0.3, 0.5)
@given(
    st.one_of(st.floats(-0.6, 0.6), st.floats(-1e-3, 1e-3)),
    st.floats(-0.8, -0.05),
    st.floats(0.05, 0.8),
)
def test_the_steering_action_is_the_first_float32_that_decodes_no_larger(steer, low, high):
    # Found by bisection; the same float32 (bits, sign of zero included) as stepping.
    stepped = _one_float32_at_a_time(steer, low, high, 100_000 if steer == 1e-5 else 20_000)
    assume(stepped is not None)
    action = _steering_action(steer, low, high)
    assert isinstance(action, np.float32)
    assert action.tobytes() == stepped.tobytes()


def test_stock_env_steps_through_env_step_with_our_ego():
    env = make_stock_env("parking-v0", 20)
    env.reset(seed=0)
    ego = attach_ego(env)
    assert isinstance(env.unwrapped.vehicle, EgoVehicle) and ego is env.unwrapped.vehicle
    t0 = env.unwrapped.time
    rear0 = list(ego.rear)
    _, _, term, trunc, info = env.step(np.array([1.0, 0.0], dtype=np.float32))
    assert env.unwrapped.time == pytest.approx(t0 + 1 / 20)  # one policy step = one sim step
    assert ego.speed == pytest.approx(5.0 / 20)  # the top of highway-env's range, 5 m/s^2
    assert ego.rear != rear0 and "is_success" in info and not (term or trunc)
    env.close()


def test_parked_variant_puts_its_parked_cars_in_the_map():
    env = make_stock_env("parking-parked-v0", 20)
    env.reset(seed=1)
    attach_ego(env)
    m = map_from_env(env)
    cars = [o for o in m.obstacles if abs(o.size[0] - 5.0) < 1e-6 and abs(o.size[1] - 2.0) < 1e-6]
    assert len(cars) == env.unwrapped.config["vehicles_count"] == 10
    env.close()


def test_unknown_stock_env_is_bad_input():
    with pytest.raises(InputError, match="env: unknown stock env"):
        make_stock_env("highway-v0", 20)


def test_simulate_parking_v0_reports_highway_env_success(capsys):
    code = main(["simulate", "parking-v0", "--seed", "2", "--planner", "hybrid-a-star",
                 "--deterministic", "--json", "-"])
    data = json.loads(capsys.readouterr().out)
    assert code == 0
    assert data["highway_env_success"] is True and data["success"] is True
    assert data["scenario"] == "parking-v0" and data["target"] == "stock"


@pytest.mark.parametrize("seed", [38])
def test_parking_v0_with_reverse_drives_its_cusps(seed):
    """parking-v0 --reverse in highway-env: seed 38's wheels turn at the cusp (the car
    stands there at -2.4e-8 m/s, float32 actions; it failed before with a collision off
    the path). Seed 77 was here too, for its 0.12 m reverse stub of two rows; since the
    shots prefer words with fewer cusps (session 16) it plans without the stub, which
    ``tests/test_reverse_controllers.py::test_a_reverse_stub_of_two_rows_is_driven``
    drives."""
    run = drive_stock_env(
        "parking-v0", seed, "improved-rrt-connect", "pure-pursuit", DETERMINISTIC, reverse=True
    )
    report = evaluate(run.episode)
    assert report.gear_changes >= 1
    assert report.success and not report.collision_footprint, run.episode.message
    assert report.goal_position_err_m <= 0.1 and report.cte_max_m <= 0.2


def test_a_stock_video_has_highway_envs_frames_at_real_time(tmp_path, capsys):
    # highway-env's own 600 x 300 render, one frame every --video-stride steps plus the
    # start: 20 steps at 20 Hz with stride 10 are frames at steps 0, 10 and 20.
    video, out = tmp_path / "p.mp4", tmp_path / "p.json"
    code = main(["simulate", "parking-v0", "--seed", "3", "--max-time", "1", "--video",
                 str(video), "--video-stride", "10", "--json", str(out)])
    assert code == 1, capsys.readouterr().err  # 1 s is too short to park: a timeout
    data = json.loads(out.read_text())
    assert data["steps"] == 20 and data["video_frames"] == 3
    import imageio.v3 as iio

    frames = iio.imread(video, index=None)
    assert frames.shape == (3, 300, 600, 3) and frames.std() > 10  # drawn, not blank
    fps = iio.immeta(video)["fps"]
    assert len(frames) / fps == pytest.approx(data["duration_s"] + 0.05, rel=0.02)


def test_a_stride_one_stock_video_streams_every_state_at_the_simulation_frequency(
    tmp_path, capsys
):
    # At stride 1 the frames go to the encoder as they are drawn (not kept: a 34 s drive's
    # frames were 370 MB): one per logged state, at 20 fps, the same frames as kept ones.
    video, out = tmp_path / "p.mp4", tmp_path / "p.json"
    code = main(["simulate", "parking-v0", "--seed", "3", "--max-time", "0.5", "--video",
                 str(video), "--json", str(out)])
    assert code == 1, capsys.readouterr().err  # 0.5 s is too short to park: a timeout
    data = json.loads(out.read_text())
    assert data["steps"] == 10 and data["video_frames"] == 11
    import imageio.v3 as iio

    frames = iio.imread(video, index=None)
    assert frames.shape == (11, 300, 600, 3) and frames.std() > 10
    assert iio.immeta(video)["fps"] == pytest.approx(20.0)
    assert {p.name for p in tmp_path.iterdir()} == {"p.json", "p.mp4"}  # no temporary left
    kept = drive_stock_env("parking-v0", 3, config=EpisodeConfig(max_time_s=0.5),
                           render_stride=1)
    handed: list[np.ndarray] = []
    streamed = drive_stock_env("parking-v0", 3, config=EpisodeConfig(max_time_s=0.5),
                               render_stride=1, on_frame=handed.append)
    assert streamed.frames == [] and len(handed) == len(kept.frames) == 11
    assert all(np.array_equal(a, b) for a, b in zip(handed, kept.frames, strict=True))


def test_a_stock_drive_that_is_not_planned_writes_no_video(tmp_path, capsys):
    video = tmp_path / "p.mp4"
    code = main(["simulate", "parking-v0", "--seed", "3", "--plan-time", "0.0001",
                 "--video", str(video)])
    assert code == 1
    assert "no video: planning failed (timeout)" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []  # neither the video nor its temporary file


@pytest.mark.parametrize("goal", [(40.0, 0.0, 0.0), (-20.0, -26.0, -1.5708)])
def test_a_goal_beyond_the_scene_gets_bounds_round_its_whole_body(goal):
    # The bounds held the goal's rear axle plus pad (1 m): a goal past the scene's edge was
    # refused, its nose leaving the bounds (an audit's find). Now its body, plus pad.
    import shapely

    from rrtdrive.types import Pose
    from rrtdrive.vehicle import footprint_polygon

    env = gym.make("parking-v0")
    env.reset(seed=0)
    try:
        m = map_from_env(env, goal=Pose(*goal))
    finally:
        env.close()
    body = footprint_polygon(goal, m.vehicle)
    inner = shapely.box(*m.bounds).buffer(-1.0 + 1e-9, join_style="mitre")
    assert inner.contains(body)
    # The side the goal pokes out of ends exactly pad beyond its body.
    xmin, ymin, xmax, ymax = m.bounds
    bx0, by0, bx1, by1 = body.bounds
    assert max(xmax - bx1, bx0 - xmin, ymax - by1, by0 - ymin) >= 1.0
    assert min(abs(xmax - bx1 - 1.0), abs(bx0 - xmin - 1.0), abs(ymax - by1 - 1.0),
               abs(by0 - ymin - 1.0)) < 1e-9
