"""Hand-made episodes for evaluator tests: a logged drive along the overtake lane."""

from __future__ import annotations

import numpy as np

from rrtdrive.sim.episode import DriveLog, Episode
from rrtdrive.sim.runner import EpisodeConfig
from rrtdrive.sim.tasks import make_scenario
from rrtdrive.types import Path

DT = 0.05


def overtake(goal=None):
    scen = make_scenario("overtake", 0, jitter=(0.0, 0.0, 0.0))
    if goal is not None:
        g = scen.map.goal.__class__(*goal)
        scen = scen.__class__(**{**scen.__dict__, "map": scen.map.with_query(goal=g)})
    return scen


def lane_path(scen, x_end=30.0):
    x = np.arange(scen.start.x, x_end + 1e-9, 0.1)
    return Path(np.column_stack([x, np.full_like(x, scen.lane_y), 0 * x, 0 * x]),
                np.zeros((0, 2)))


def episode(scen, states, controls, status="arrived"):
    states = np.asarray(states, float)
    n = len(states)
    log = DriveLog(dt=DT, t=np.arange(n) * DT, states=states,
                   controls=np.asarray(controls, float).reshape(-1, 2),
                   crashed=np.zeros(n, bool), others=np.zeros((n, 0, 4)),
                   other_sizes=np.zeros((0, 2)), arrived=status == "arrived", wall_time_s=0.01)
    return Episode(scen, "given", "pure-pursuit", scen.seed, None, lane_path(scen), log, status,
                   "", EpisodeConfig())


def drive_to(scen, x_end, n=101, yaw_end=0.0, v_end=0.0):
    x = np.linspace(scen.start.x, x_end, n)
    v = np.linspace(2.0, v_end, n)
    yaw = np.zeros(n)
    yaw[-1] = yaw_end
    return np.column_stack([x, np.full(n, scen.lane_y), yaw, v])
