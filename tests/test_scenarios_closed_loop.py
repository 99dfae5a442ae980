"""The gear-change scenarios driven in highway-env: real episodes and their gym envs."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import rrtdrive.envs  # noqa: F401  (registers the envs)
from rrtdrive.evaluation import evaluate
from rrtdrive.sim.runner import EpisodeConfig, run_episode
from rrtdrive.sim.tasks import make_scenario
from rrtdrive.sim.video import hud_gears, render_frames
from rrtdrive.types import Budget

#: Iterations decide, not the machine's speed.
DETERMINISTIC = EpisodeConfig(budget=Budget(max_time_s=1e6))


@pytest.mark.parametrize(
    ("name", "options", "planner", "seed"),
    [
        ("parking", {"reverse_in": True}, "hybrid-a-star", 0),
        ("parallel-parking", {}, "hybrid-a-star", 1),
        ("u-turn", {}, "improved-rrt-connect", 0),
    ],
)
def test_scenario_episode_reverses_and_stops_at_the_goal(name, options, planner, seed):
    task = make_scenario(name, seed, **options)
    episode = run_episode(task, planner, "pure-pursuit", seed, DETERMINISTIC)
    report = evaluate(episode)
    assert report.success, report.outcome
    assert len(episode.path.cusps) >= 1
    speed = episode.log.states[:, 3]
    assert speed.min() < -0.1  # it drove backwards
    assert report.goal_position_err_m <= 0.5
    # Every gear change happens at rest: the speed never jumps across zero in a step.
    assert not np.any(speed[:-1] * speed[1:] < 0)
    gears = hud_gears(speed)
    assert "R" in set(gears) and gears[-1] == "D"


def test_video_of_a_reversing_episode_draws_the_reverse_segments_and_cusps():
    from rrtdrive.sim.render import CUSP_COLOR, REVERSE_COLOR

    task = make_scenario("u-turn", 0)
    episode = run_episode(task, "improved-rrt-connect", "pure-pursuit", 0, DETERMINISTIC)
    frame = next(render_frames(episode, stride=10_000))
    px = frame.reshape(-1, 3).astype(int)

    def has(colour):
        return bool(np.any(np.all(np.abs(px - np.array(colour)) <= 3, axis=1)))

    assert has(REVERSE_COLOR) and has(CUSP_COLOR)
    assert frame.shape[:2] == task.camera().size[::-1]


def test_reverse_in_parking_is_an_option_of_the_parking_env():
    env = gym.make("rrtdrive/Parking-v0", planner="hybrid-a-star",
                   scenario_options={"reverse_in": True}, budget=Budget(max_time_s=1e6))
    env.reset(seed=0)
    task = env.unwrapped._scenario
    assert task.reverse_in and task.reverse and len(env.unwrapped._reference.path.cusps) >= 1
    env.close()
