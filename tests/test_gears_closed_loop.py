"""The closed loop drives forward only (until issue #14): reverse paths are refused clearly."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import rrtdrive.envs  # noqa: F401  (registers the envs)
from rrtdrive.controllers import make_controller
from rrtdrive.planning import PLANNERS, PlanningProblem
from rrtdrive.planning.base import Stopwatch
from rrtdrive.sim.runner import run_episode
from rrtdrive.types import Budget, InputError, Path, PlanResult, PlanStatus, Pose

MESSAGE = r"path: has 1 gear change; driving in reverse is not supported yet \(issue #14\)"


def _shuttle(start: Pose) -> Path:
    """Forward 5 m along the start heading, cusp, back to the start in reverse."""
    d = np.linspace(0.0, 5.0, 21)
    c, s = np.cos(start.yaw), np.sin(start.yaw)
    rows = np.column_stack([start.x + c * d, start.y + s * d, np.full(21, start.yaw),
                            np.zeros(21)])
    fwd = np.column_stack([rows, np.ones(21)])
    back = np.column_stack([rows[::-1], -np.ones(21)])
    return Path(np.vstack([fwd, back]), np.zeros((0, 2)))


class _Shuttler:
    """A planner whose path drives out and back in reverse (what a reversing planner emits)."""

    name = "test-shuttle"

    def solve(self, problem: PlanningProblem, rng: np.random.Generator, budget: Budget
              ) -> PlanResult:
        path = _shuttle(problem.start)
        return PlanResult(PlanStatus.SOLVED, self.name, path, path.xy.copy(), (), 0, 0,
                          Stopwatch(budget).elapsed())


def test_controllers_refuse_a_reverse_path():
    path = _shuttle(Pose(0.0, 0.0, 0.0))
    for name in ("pure-pursuit", "stanley", "lqr"):
        with pytest.raises(InputError, match=MESSAGE):
            make_controller(name).reset(path)
    back_only = Path(path.samples[21:], path.waypoints)
    with pytest.raises(InputError, match="is driven in reverse; driving in reverse is not"):
        make_controller("pure-pursuit").reset(back_only)


def test_runner_refuses_a_reverse_path():
    from rrtdrive.maps import builtin_map

    path = _shuttle(builtin_map("parking_lot").start)
    with pytest.raises(InputError, match=MESSAGE):
        run_episode("parking", planner=path, controller="pure-pursuit", seed=0)


def test_gym_env_refuses_a_reverse_path(monkeypatch):
    monkeypatch.setitem(PLANNERS, "test-shuttle", _Shuttler)
    env = gym.make("rrtdrive/Overtake-v0", planner="test-shuttle")
    with pytest.raises(InputError, match=MESSAGE):
        env.reset(seed=0)
    env.close()
