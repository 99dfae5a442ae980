"""Driving across cusps in highway-env: given reverse paths and Hybrid A* plans on tight maps.

Every episode runs through the real simulator (``run_episode`` on a
``CustomTask``, the ego an :class:`~rrtdrive.sim.ego.EgoVehicle`) with an instant
and a 0.4 rad/s steering actuator, and is scored by the evaluators.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from test_reverse_controllers import PATHS

from rrtdrive.evaluation import evaluate
from rrtdrive.maps import Map, builtin_map
from rrtdrive.planning import PlanningProblem, make_planner
from rrtdrive.sim.episode import trajectory_csv
from rrtdrive.sim.runner import run_episode
from rrtdrive.sim.tasks import CustomTask
from rrtdrive.types import Budget, Path, Pose, VehicleParams

NAMES = ["pure-pursuit", "stanley", "lqr"]
RATES = [None, 0.4]
#: Where the given paths start in the open map.
ORIGIN = (30.0, 30.0)


def _open_map(path: Path, vehicle: VehicleParams) -> tuple[Map, Path]:
    s = np.array(path.samples)
    s[:, 0] += ORIGIN[0]
    s[:, 1] += ORIGIN[1]
    moved = Path(s, np.zeros((0, 2)))
    start, goal = Pose(*s[0, :3]), Pose(*s[-1, :3])
    return Map("open", (0.0, 0.0, 60.0, 60.0), (), start, goal, vehicle), moved


def _hybrid(map_name: str, vehicle: VehicleParams):
    m = Map(**{**builtin_map(map_name).__dict__, "vehicle": vehicle})
    plan = make_planner("hybrid-a-star").solve(
        PlanningProblem.from_map(m, reverse=True), np.random.default_rng(0), Budget()
    )
    assert plan.success and len(plan.path.cusps) >= 1
    return m, plan


@pytest.mark.parametrize("rate", RATES)
@pytest.mark.parametrize("path_name", list(PATHS))
@pytest.mark.parametrize("name", NAMES)
def test_given_reverse_paths_in_highway_env(name, path_name, rate):
    vehicle = VehicleParams(max_steer_rate=rate)
    m, path = _open_map(PATHS[path_name], vehicle)
    ep = run_episode(CustomTask(map=m, seed=0), planner=path, controller=name, seed=0)
    r = evaluate(ep)
    assert ep.status == "arrived" and r.success and not r.collision
    assert r.path_cusps == len(path.cusps) and r.gear_changes == len(path.cusps)
    # Bounds measured on these runs (docs/closed_loop.md, "Reversing").
    assert r.cte_max_m <= (0.05 if rate is None else 0.2)
    assert r.goal_position_err_m <= (0.06 if rate is None else 0.2)
    speed = ep.log.states[:, 3]
    assert speed.min() >= -1.1 * 1.5  # the reverse cap, with the PI loop's overshoot
    # The log's gear column: -1 while reversing, the gear kept while standing still.
    traj = ep.trajectory()
    assert np.all(traj[speed < 0.0, 7] == -1) and np.all(traj[speed > 0.0, 7] == 1)
    if path.samples[0, 4] < 0:
        assert traj[0, 7] == -1
    assert trajectory_csv(ep).splitlines()[0].endswith(",gear")


@pytest.mark.parametrize("rate", RATES)
@pytest.mark.parametrize("map_name", ["reverse_bay", "turning_bulb"])
def test_hybrid_a_star_plans_drive_end_to_end(map_name, rate):
    vehicle = VehicleParams(max_steer_rate=rate)
    m, plan = _hybrid(map_name, vehicle)
    task = CustomTask(map=m, seed=0)
    for name in NAMES:
        ep = run_episode(task, planner=plan, controller=name, seed=0)
        r = evaluate(ep)
        assert ep.status == "arrived", (name, ep.message)
        assert r.success and not r.collision_highway_env and not r.collision_footprint, name
        assert r.gear_changes == r.path_cusps == len(plan.path.cusps)
        assert r.goal_position_err_m <= 0.1 and r.goal_heading_err_rad <= math.radians(3.0)
        assert r.cte_max_m <= 0.1, (name, r.cte_max_m)
        # Each cusp is a stop: the car stands still between opposite gears.
        v = ep.log.states[:, 3]
        moving = np.flatnonzero(v != 0.0)
        flips = moving[np.flatnonzero(np.sign(v[moving][1:]) != np.sign(v[moving][:-1]))]
        for i in flips:
            nxt = moving[moving > i][0]
            assert np.all(v[i + 1:nxt] == 0.0) and nxt > i + 1
