"""The closed loop drives paths with gear changes (issue #14); the gym env: test_reverse_gym.py."""

from __future__ import annotations

import numpy as np
import pytest

import rrtdrive.envs  # noqa: F401  (registers the envs)
from rrtdrive.controllers import PathProjector, make_controller
from rrtdrive.planning import PlanningProblem
from rrtdrive.planning.base import Stopwatch
from rrtdrive.sim.runner import run_episode
from rrtdrive.types import Budget, InputError, Path, PlanResult, PlanStatus, Pose

MESSAGE = r"path: has 1 gear change; a PathProjector projects one forward gear segment"


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


def test_controllers_drive_out_and_back():
    path = _shuttle(Pose(0.0, 0.0, 0.0))
    for name in ("pure-pursuit", "stanley", "lqr"):
        c = make_controller(name)
        c.reset(path)
        assert [s.gear for s in c.segments] == [1, -1]
    with pytest.raises(InputError, match="a PathProjector projects one forward gear segment"):
        PathProjector(path)


def test_runner_drives_a_reverse_path():
    from rrtdrive.evaluation import evaluate
    from rrtdrive.maps import builtin_map

    path = _shuttle(builtin_map("parking_lot").start)
    ep = run_episode("parking", planner=path, controller="pure-pursuit", seed=0)
    assert ep.status == "arrived"
    r = evaluate(ep)
    assert r.path_cusps == 1 and r.gear_changes == 1
    assert np.hypot(*(ep.log.states[-1, :2] - path.samples[-1, :2])) < 0.1
