"""max_jerk holds the lateral component: a steering step at constant speed is a jerk.

Mutation audit, session 35: ``max_jerk`` with its lateral component dropped (the
longitudinal ``|Δa| / dt`` only) survived every test. docs/metrics.md (Comfort) defines
``max_jerk = max_k |(a_k+1 - a_k, a_lat,k+1 - a_lat,k)| / dt`` with
``a_lat,k = v_k^2 tan(delta_k) / L`` (``v_k`` the speed at the start of step k). Here
hand-built logs at constant speed (no longitudinal jerk at all) step the steering once,
and the report's ``max_jerk`` is checked against that definition worked out by hand.
"""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest

from rrtdrive.evaluation import evaluate
from rrtdrive.sim.episode import DriveLog, Episode
from rrtdrive.sim.runner import EpisodeConfig
from rrtdrive.sim.tasks import Task, make_scenario
from rrtdrive.types import Path, VehicleParams

DT = 0.05
L = VehicleParams().wheelbase


@functools.cache
def _scenario() -> Task:
    return make_scenario("overtake", 0, jitter=(0.0, 0.0, 0.0))


def _episode(speed: float, steer: np.ndarray, accel: np.ndarray) -> Episode:
    """A drive along the overtake lane from ``speed`` with the given commands per step.

    The speeds follow the accelerations (``v_k+1 = v_k + a_k dt``); the positions stay on
    the lane's line (max_jerk reads the commands and the speeds only).
    """
    scen = _scenario()
    n = len(steer)
    v = speed + np.r_[0.0, np.cumsum(accel)] * DT
    x = scen.start.x + np.r_[0.0, np.cumsum(0.5 * (v[:-1] + v[1:]) * DT)]
    states = np.column_stack([x, np.full(n + 1, scen.lane_y), np.zeros(n + 1), v])
    px = np.arange(scen.start.x, x[-1] + 5.0, 0.1)
    rows = np.column_stack([px, np.full_like(px, scen.lane_y), 0 * px, 0 * px])
    path = Path(rows, np.zeros((0, 2)))
    log = DriveLog(
        dt=DT, t=np.arange(n + 1) * DT, states=states,
        controls=np.column_stack([accel, steer]), crashed=np.zeros(n + 1, bool),
        others=np.zeros((n + 1, 0, 4)), other_sizes=np.zeros((0, 2)), arrived=False,
        wall_time_s=0.01,
    )  # fmt: skip
    return Episode(
        scen, "given", "pure-pursuit", scen.seed, None, path, log, "timeout", "", EpisodeConfig()
    )


@pytest.mark.parametrize(
    ("speed", "before", "after"),
    [(4.0, 0.0, 0.2), (8.0, 0.1, -0.05), (2.5, -0.3, 0.3)],
)
def test_a_steering_step_at_constant_speed_is_a_lateral_jerk(
    speed: float, before: float, after: float
) -> None:
    n, at = 20, 8
    steer = np.where(np.arange(n) < at, before, after)
    ep = _episode(speed, steer, np.zeros(n))
    # The only change between consecutive steps is the lateral acceleration's, once.
    want = speed**2 * abs(math.tan(after) - math.tan(before)) / L / DT
    assert want > 1.0  # a jerk a dropped lateral part would read as 0
    assert evaluate(ep).max_jerk == pytest.approx(want, rel=1e-12)


def test_a_steering_step_with_a_throttle_step_adds_as_a_vector() -> None:
    # The throttle steps at the same instant: both components jump there (the speed is
    # still the constant one at the start of that step). After it the speed grows, so
    # a_lat creeps by about 2 v a1 tan(after) / L * dt a step: 0.6 m/s^3, far below.
    n, at, speed, before, after, a1 = 20, 8, 5.0, 0.05, 0.25, 0.6
    steer = np.where(np.arange(n) < at, before, after)
    accel = np.where(np.arange(n) < at, 0.0, a1)
    ep = _episode(speed, steer, accel)
    lateral = speed**2 * (math.tan(after) - math.tan(before)) / L
    want = math.hypot(a1, lateral) / DT  # 41 m/s^3; the longitudinal part alone, 12
    assert evaluate(ep).max_jerk == pytest.approx(want, rel=1e-12)
