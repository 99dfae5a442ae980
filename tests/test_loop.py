"""The episode loop: steppable one command at a time, the same as run()."""

from __future__ import annotations

import numpy as np
import pytest

from rrtdrive.controllers import SpeedConfig, make_controller
from rrtdrive.sim.episode import EpisodeStatus
from rrtdrive.sim.loop import STOP_AT_PATH_END, Driver, EpisodeLoop, PathTracker
from rrtdrive.sim.scenes import build_env
from rrtdrive.sim.tasks import make_scenario
from rrtdrive.types import Path


def _straight(task, length):
    x = np.arange(task.start.x, task.start.x + length, 0.1)
    return Path(np.column_stack([x, np.full_like(x, task.lane_y), 0 * x, 0 * x]), np.zeros((0, 2)))


def _setup(length=30.0, max_time=30.0):
    task = make_scenario("overtake", 0, jitter=(0.0, 0.0, 0.0))
    env = build_env(task)
    ctrl = make_controller("lqr", vehicle=task.vehicle, speed=SpeedConfig(v_max=task.v_max))
    tracker = PathTracker(env, ctrl, _straight(task, length))
    return env, task, tracker, EpisodeLoop(env, tracker, task, max_time)


def test_stepping_by_hand_equals_run():
    env, task, tracker, loop = _setup()
    try:
        log = loop.run()
    finally:
        env.close()
    env, task, tracker, by_hand = _setup()
    try:
        assert isinstance(tracker, Driver)
        tracker.start()
        status = None
        while not by_hand.done:
            status = by_hand.step(*tracker.command(by_hand.t))
        log2 = by_hand.log()
        with pytest.raises(RuntimeError, match="over"):
            by_hand.step(0.0, 0.0)
    finally:
        env.close()
    assert status is EpisodeStatus.ARRIVED == loop.status and log.arrived and log2.arrived
    assert np.array_equal(log.states, log2.states) and np.array_equal(log.controls, log2.controls)
    assert by_hand.steps == log2.steps and "end of the path" in by_hand.message


def test_time_limit_and_the_bare_path_rule():
    env, task, tracker, _ = _setup(length=200.0)
    try:
        loop = EpisodeLoop(env, tracker, STOP_AT_PATH_END, 2.0)
        log = loop.run()
    finally:
        env.close()
    assert loop.status is EpisodeStatus.TIMEOUT and not log.arrived
    assert log.steps == loop.max_steps == 40
    assert loop.message == "not stopped at the goal within 2 s"
