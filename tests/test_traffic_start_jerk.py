"""The start transient of overtake-traffic: the first reference merges into the lane.

Without the merge (``start_merge_s=0``) the controllers corrected the seeded start
offset (0.12-0.15 m, 1.5 degrees) from the lane centre line within 2-3 m at 4 m/s:
the rate-limited wheels swung from -0.4 to +0.4 rad/s, and nuPlan's body-centre
acceleration (``+ d * w_dot``) read that as a longitudinal jerk over 4.13 m/s^3 at
t = 0 (seeds 42 and 82 with pure pursuit, 82 with LQR). These drive the first 3 s in
highway-env both ways.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from rrtdrive.evaluation import evaluate
from rrtdrive.evaluation.nuplan_comfort import COMFORT_BOUNDS
from rrtdrive.sim.replanning import ReplanConfig, merge_path
from rrtdrive.sim.runner import EpisodeConfig, run_episode
from rrtdrive.sim.tasks import make_scenario
from rrtdrive.types import InputError


def _start(seed: int, controller: str, merge_s: float):
    scen = make_scenario("overtake-traffic", seed)
    config = EpisodeConfig(
        replan=ReplanConfig(wall_limit=False, start_merge_s=merge_s), max_time_s=3.0
    )
    episode = run_episode(scen, controller=controller, seed=seed, config=config)
    return episode, evaluate(episode)


@pytest.mark.parametrize(("seed", "controller"), [(42, "pure-pursuit"), (82, "lqr")])
def test_the_start_merge_keeps_the_start_within_nuplans_jerk_bound(seed, controller) -> None:
    bound = COMFORT_BOUNDS["max_abs_lon_jerk"]
    episode, merged = _start(seed, controller, 4.0)
    _, line = _start(seed, controller, 0.0)
    # The lane line beside the car: the wheels swing at the actuator's limit and the
    # filtered longitudinal jerk breaks nuPlan's bound (the test would catch a regression).
    assert line.max_steering_rate == pytest.approx(0.4, abs=1e-6)
    assert line.nuplan_lon_jerk_abs_max > bound
    # The merge: well within it, the wheels never near their rate limit.
    assert merged.nuplan_lon_jerk_abs_max < bound - 1.0, merged.nuplan_lon_jerk_abs_max
    assert merged.max_steering_rate < 0.5 * 0.4
    assert merged.collisions_at_fault == 0
    # The executed steering rate of every step, from the wheel angle of the trajectory
    # (the car starts with straight wheels).
    traj = episode.trajectory()
    steer = np.concatenate([[0.0], traj[:, 5]])
    rates = np.abs(np.diff(steer)) / episode.log.dt
    assert 0.0 < rates.max() < 0.5 * episode.scenario.vehicle.max_steer_rate


def test_merge_path_starts_at_the_car_and_ends_on_the_lane_smoothly() -> None:
    pose, kappa0, length = (5.3, 44.14, -0.026), 0.004, 16.0
    path = merge_path(pose, kappa0, length, 60.0, 44.0)
    s = path.samples
    assert s[0, :3] == pytest.approx(pose, abs=1e-12)
    assert s[0, 3] == pytest.approx(kappa0, abs=1e-12)
    lane = s[:, 0] >= pose[0] + length - 1e-9
    assert s[lane, 1] == pytest.approx(44.0, abs=1e-12)
    assert np.abs(s[lane, 2:4]).max() < 1e-12
    assert s[-1, 0] == pytest.approx(60.0)
    # Heading and curvature are the geometry's (finite differences along the samples)
    # and continuous: no step anywhere, the lane joined with zero slope and curvature.
    arc = path.arc_length()
    yaw_fd = np.arctan2(np.diff(s[:, 1]), np.diff(s[:, 0]))
    assert yaw_fd == pytest.approx(0.5 * (s[1:, 2] + s[:-1, 2]), abs=1e-5)
    kappa_fd = np.diff(s[:, 2]) / np.diff(arc)
    assert kappa_fd == pytest.approx(0.5 * (s[1:, 3] + s[:-1, 3]), abs=1e-4)
    assert np.abs(np.diff(s[:, 3])).max() < 1e-3
    assert np.abs(s[:, 3]).max() < 0.01


def test_merge_path_bad_input_names_the_field() -> None:
    with pytest.raises(InputError, match="merge.length"):
        merge_path((0.0, 44.0, 0.0), 0.0, 0.0, 50.0, 44.0)
    with pytest.raises(InputError, match="merge.pose"):
        merge_path((0.0, 44.0, math.pi), 0.0, 10.0, 50.0, 44.0)
    with pytest.raises(InputError, match="replan.start_merge_s"):
        ReplanConfig(start_merge_s=-1.0)
