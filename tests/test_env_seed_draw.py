"""reset() without an episode seed: a map's one query is not planned 20 times over."""

from __future__ import annotations

import gymnasium as gym
import pytest

import rrtdrive.envs  # noqa: F401  (registers the envs)
from rrtdrive.envs.drive_env import DriveEnv
from rrtdrive.envs.seed_draw import MAX_PLAN_ATTEMPTS, RETRIES_PER_QUERY
from rrtdrive.maps import Map, Obstacle, save_map
from rrtdrive.types import Pose

WALLS = (Obstacle((35.0, 25.0), (1.0, 20.0)), Obstacle((45.0, 25.0), (1.0, 20.0)),
         Obstacle((40.0, 35.0), (11.0, 1.0)), Obstacle((40.0, 15.0), (11.0, 1.0)))


def _counting(monkeypatch) -> list[int]:
    planned: list[int] = []
    original = DriveEnv._start_episode

    def start(self, seed, task=None):
        planned.append(seed)
        return original(self, seed, task)

    monkeypatch.setattr(DriveEnv, "_start_episode", start)
    return planned


def test_a_goal_proven_unreachable_is_planned_once(monkeypatch, tmp_path):
    boxed = Map("boxed", (0.0, 0.0, 50.0, 50.0), WALLS, Pose(5.0, 5.0, 0.0), Pose(38.0, 25.0, 0.0))
    save_map(boxed, tmp_path / "boxed.json")
    planned = _counting(monkeypatch)
    env = gym.make("rrtdrive/Map-v0", scenario=str(tmp_path / "boxed.json"))
    with pytest.raises(RuntimeError) as err:
        env.reset(seed=0)
    assert len(planned) == 1  # was 20: the same proof for every seed
    text = str(err.value)
    assert text.startswith(f"no path for {MAX_PLAN_ATTEMPTS} episode seeds in a row (1 query;")
    assert "why: the goal is walled off from the start" in text
    assert "reverse" not in text  # no gear change opens a wall


def test_a_query_that_keeps_failing_is_planned_a_few_times_and_hints_at_reverse(monkeypatch,
                                                                               tmp_path):
    # A goal facing a wall 0.3 m behind its rear: reachable in reverse only.
    wall = Obstacle((30.0 - 0.9 - 0.3 - 0.5, 10.0), (1.0, 20.0))
    m = Map("bay", (0.0, 0.0, 60.0, 20.0), (wall,), Pose(45.0, 10.0, 3.14159),
            Pose(30.0, 10.0, 0.0))
    save_map(m, tmp_path / "bay.json")
    planned = _counting(monkeypatch)
    env = gym.make("rrtdrive/Map-v0", scenario=str(tmp_path / "bay.json"))
    with pytest.raises(RuntimeError) as err:
        env.reset(seed=0)
    assert 1 <= len(planned) <= RETRIES_PER_QUERY
    assert str(err.value).endswith("scenario_options={'reverse': True} allows it")
    env = gym.make("rrtdrive/Map-v0", scenario=str(tmp_path / "bay.json"),
                   scenario_options={"reverse": True})
    _, info = env.reset(seed=0)
    assert info["path_length_m"] > 0
