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


def test_stop_ends_the_episode_with_the_callers_status():
    env, task, tracker, loop = _setup(length=200.0)
    try:
        tracker.start()
        assert loop.recorder.states[0][0] == pytest.approx(task.start.x)
        for _ in range(3):
            loop.step(*tracker.command(loop.t))
        assert loop.stop(EpisodeStatus.OFF_PATH, "left the path") is EpisodeStatus.OFF_PATH
        assert loop.done and loop.status is EpisodeStatus.OFF_PATH
        assert loop.message == "left the path"
        assert loop.log(wall_time_s=1.5).wall_time_s == 1.5 and loop.log().steps == 3
        with pytest.raises(RuntimeError, match="over"):
            loop.step(0.0, 0.0)
    finally:
        env.close()


def test_stop_at_goal_rule_and_the_agent_rule_of_the_tasks():
    from rrtdrive.sim.loop import StopAtGoal

    task = make_scenario("overtake", 0, jitter=(0.0, 0.0, 0.0))
    rule = task.agent_end_rule(0.5, 0.2, 0.1)
    assert isinstance(rule, StopAtGoal) and rule.goal == task.goal
    assert rule.end_message(EpisodeStatus.ARRIVED, 2.0, 60.0) == "stopped at the goal at t = 2.00 s"
    assert rule.end_message(EpisodeStatus.TIMEOUT, 2.0, 60.0) == (
        "not stopped at the goal within 60 s"
    )
    traffic = make_scenario("overtake-traffic", 0)
    assert traffic.agent_end_rule(0.5, 0.2, 0.1) is traffic  # no controller in its rule
    env = build_env(task)
    try:
        ego = env.unwrapped.vehicle
        assert not rule.reached(ego, None)  # at the start, far from the goal
        ego.set_pose(task.goal, speed=0.0)
        assert rule.reached(ego, None)
    finally:
        env.close()
