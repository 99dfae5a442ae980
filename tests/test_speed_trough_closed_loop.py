"""After the last slow stretch of a path, the car speeds up again if it can stop in time.

A curvature step slows the rate-limited car (0.4 rad/s) to the steering-rate cap; the
stretch after it used to be held at that speed whenever its peak was too short for the
comfort loop to turn into the stop: a 5 m arc after the step took 17.9 s at 0.29 m/s.
Now the peak is lowered until it has that plateau. Real highway-env, given paths.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from rrtdrive.maps import builtin_map
from rrtdrive.sim.runner import run_episode
from rrtdrive.sim.tasks import CustomTask
from rrtdrive.types import Path, Pose


def _straight_then_arc(straight: float, arc: float, kappa: float, x0: float, y0: float) -> Path:
    """Rows 0.25 m apart: a straight, then an arc whose curvature steps up at a row."""
    s = np.arange(0.0, straight + arc + 1e-9, 0.25)
    rows = [[x0, y0, 0.0, 0.0, 1.0]]
    x, y, yaw = x0, y0, 0.0
    for a, b in zip(s[:-1], s[1:], strict=True):
        k = 0.0 if a < straight - 1e-9 else kappa
        if k == 0.0:
            x, y = x + (b - a) * math.cos(yaw), y + (b - a) * math.sin(yaw)
        else:
            turned = yaw + k * (b - a)
            x += (math.sin(turned) - math.sin(yaw)) / k
            y -= (math.cos(turned) - math.cos(yaw)) / k
            yaw = turned
        rows.append([x, y, yaw, 0.0 if b < straight + 1e-9 else kappa, 1.0])
    return Path(np.array(rows), np.zeros((0, 2)))


@pytest.mark.parametrize("name", ["pure-pursuit", "stanley", "lqr"])
def test_the_arc_after_a_curvature_step_is_not_crawled(name):
    path = _straight_then_arc(5.0, 5.0, 0.1, 10.0, 20.0)
    end = path.samples[-1]
    task = CustomTask.from_map(
        builtin_map("narrow_gap"), start=Pose(10.0, 20.0, 0.0),
        goal=Pose(float(end[0]), float(end[1]), float(end[2])), max_time_s=60.0,
    )  # fmt: skip
    ep = run_episode(task, planner=path, controller=name, seed=0)
    assert ep.status.value == "arrived", ep.message
    states = ep.log.states
    driven = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(states[:, :2], axis=0).T))])
    on_arc = (driven > 5.3) & (driven < driven[-1] - 0.5)
    # The step's steering-rate cap is 0.7 * 0.4 / (d delta / ds) = 0.29 m/s; the arc
    # after it was driven at that speed (median 0.286 m/s, 24.8 s in all).
    assert np.median(states[on_arc, 3]) > 0.8
    assert ep.log.t[-1] < 15.0
    assert math.hypot(states[-1, 0] - end[0], states[-1, 1] - end[1]) < 0.02


def test_the_car_does_not_stand_still_before_a_curvature_step():
    # The peak before the step had no plateau: the comfort loop was still speeding up
    # where the profile braked, braked at -2.16 m/s^2 and stood still before the step.
    path = _straight_then_arc(5.0, 30.0, 1.0 / 6.0, 10.0, 20.0)
    end = path.samples[-1]
    task = CustomTask.from_map(
        builtin_map("narrow_gap"), start=Pose(10.0, 20.0, 0.0),
        goal=Pose(float(end[0]), float(end[1]), float(end[2])), max_time_s=90.0,
    )  # fmt: skip
    ep = run_episode(task, planner=path, controller="lqr", seed=0)
    assert ep.status.value == "arrived", ep.message
    states, t = ep.log.states, ep.log.t
    driven = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(states[:, :2], axis=0).T))])
    middle = (driven > 1.0) & (driven < driven[-1] - 1.0)
    assert states[middle, 3].min() > 0.03
    assert (np.diff(states[:, 3]) / np.diff(t)).min() > -1.8
