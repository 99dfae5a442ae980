"""Short moves through the real highway-env: paths shorter than the final approach, gear
segments too short to drive, and a car left behind the start of its next segment."""

from __future__ import annotations

import numpy as np
import pytest

import rrtdrive.envs  # noqa: F401  (registers the envs)
from rrtdrive.controllers import SpeedConfig
from rrtdrive.evaluation import evaluate
from rrtdrive.evaluation.tracking import followed_runs, gear_runs
from rrtdrive.maps import Map
from rrtdrive.sim.runner import run_episode
from rrtdrive.sim.tasks import CustomTask
from rrtdrive.speed_profile import FINAL_APPROACH_M, actuator_profile
from rrtdrive.types import Path, Pose

EMPTY = Map("empty", (0.0, 0.0, 30.0, 10.0), (), Pose(10.0, 5.0, 0.0), Pose(5.0, 5.0, 0.0))


def _straight(x0: float, x1: float, gear: int, n: int) -> np.ndarray:
    xs = np.linspace(x0, x1, n)
    return np.column_stack([xs, 5.0 + 0 * xs, 0 * xs, 0 * xs, gear + 0 * xs])


def _drive(rows: np.ndarray, controller: str, reverse: bool = True):
    start = Pose(float(rows[0, 0]), 5.0, 0.0)
    goal = Pose(float(rows[-1, 0]), 5.0, 0.0)
    m = Map("empty", EMPTY.bounds, (), start, goal)
    task = CustomTask.from_map(m, reverse=reverse)
    ep = run_episode(task, Path(rows, np.zeros((0, 2))), controller)
    return ep, evaluate(ep)


@pytest.mark.parametrize("length", [0.3, 1.0, 1.9])
def test_a_profile_from_rest_shorter_than_the_final_approach_rises(length):
    assert length < FINAL_APPROACH_M
    s = np.linspace(0.0, length, 9)
    profile = actuator_profile(s, 0 * s, SpeedConfig(), 0.0, 2.51, 0.4)
    # It was 0 throughout: the running minimum from the standstill start.
    assert profile.v.max() > 0.1 and profile.v[0] == 0.0 and profile.v[-1] == 0.0


@pytest.mark.parametrize("controller", ["pure-pursuit", "stanley", "lqr"])
def test_a_forward_path_of_one_metre_is_driven(controller):
    ep, r = _drive(_straight(10.0, 11.0, 1, 5), controller, reverse=False)
    # It stood still until the time limit (status timeout, goal error 1.0 m).
    assert r.success and r.status == "arrived", (r.status, r.goal_position_err_m)
    assert r.goal_position_err_m < 0.05 and r.duration_s < 10.0


@pytest.mark.parametrize("controller", ["pure-pursuit", "stanley", "lqr"])
def test_a_stub_too_short_to_drive_is_skipped_and_measured_as_skipped(controller):
    # Reverse 6 m, forward 3 cm, reverse 6 m: the stub is within the stop distance.
    rows = np.vstack([_straight(16.0, 10.0, -1, 25), _straight(10.0, 10.03, 1, 2),
                      _straight(10.03, 4.0, -1, 25)])
    ep, r = _drive(rows, controller)
    assert r.success, r.status
    # The rest of the drive was measured against the first segment: 6 m of CTE.
    assert r.cte_max_m < 0.05 and r.heading_err_max_rad < 0.05
    assert r.progress_m == pytest.approx(12.0, abs=0.1)
    assert r.path_cusps == 2 and r.gear_changes == 0
    # The drive is measured on the first run, then the last: the stub is passed over.
    runs = gear_runs(Path(rows, np.zeros((0, 2))))
    which = followed_runs(runs, ep.log.states[:, :3], ep.log.states[:, 3])
    assert which[0] == 0 and which[-1] == 2 and set(which.tolist()) <= {0, 1, 2}


@pytest.mark.parametrize("behind", [0.015, 0.03])
def test_a_car_behind_the_start_of_its_next_segment_drives_on(behind):
    # Two stubs skipped; the third segment starts ``behind`` metres behind the car.
    rows = np.vstack([_straight(10.0, 9.96, -1, 2), _straight(9.96, 10.0 - behind, 1, 2),
                      _straight(10.0 - behind, 5.0, -1, 21)])
    ep, r = _drive(rows, "lqr")
    # It never moved (the comfort cap read the standstill before the segment's start).
    assert r.success and np.abs(ep.log.states[:, 3]).max() > 0.5
    assert r.goal_position_err_m < 0.05


def _arc_left(x: float, y: float, length: float, n: int, k: float = 1 / 6) -> np.ndarray:
    s = np.linspace(0.0, length, n)
    yaw = k * s
    return np.column_stack([x + np.sin(yaw) / k, y + (1 - np.cos(yaw)) / k, yaw, k + 0 * s,
                            1 + 0 * s])


@pytest.mark.parametrize(("stub", "behind"), [(0.052, 0.0), (0.045, 0.01)])
def test_a_stub_near_the_stop_distance_is_measured_as_driven_or_skipped(stub, behind):
    # Reverse 5 m; a forward stub starting ``behind`` past the cusp; reverse 4 m; a left
    # turn forward. A 5.2 cm stub is skipped (the car stops ~3 mm short of the cusp, within
    # the stop distance of the stub's end); a 4.5 cm one 1 cm past the cusp is driven. A
    # cut-off on the stub's length measured one of them against the wrong segment (CTE
    # 5.9 m and 1.2 m where the car kept within centimetres).
    b0 = 15.0 + behind
    rows = np.vstack([_straight(20.0, 15.0, -1, 26), _straight(b0, b0 + stub, 1, 2),
                      _straight(b0 + stub, b0 + stub - 4.0, -1, 21),
                      _arc_left(b0 + stub - 4.0, 5.0, 4.0, 41)])
    m = Map("stub", (0.0, 0.0, 30.0, 15.0), (), Pose(20.0, 5.0, 0.0), Pose(*rows[-1, :3]))
    ep = run_episode(CustomTask.from_map(m, reverse=True), Path(rows, np.zeros((0, 2))), "lqr")
    r = evaluate(ep)
    assert r.success
    assert r.cte_max_m < 0.05 and r.heading_err_max_rad < 0.05
    assert r.progress_m == pytest.approx(r.path_length_m, abs=0.1)


@pytest.mark.parametrize("length", [2.0, 2.5, 3.0])
@pytest.mark.parametrize("controller", ["pure-pursuit", "lqr"])
def test_a_forward_path_given_as_its_two_end_rows_stops_on_the_goal(length, controller):
    # The profile had three samples: the comfort loop overshot its peak and ran 0.2 m past.
    ep, r = _drive(_straight(10.0, 10.0 + length, 1, 2), controller, reverse=False)
    assert r.success and r.goal_position_err_m < 0.01, r.goal_position_err_m
    dense_ep, dense = _drive(_straight(10.0, 10.0 + length, 1, 41), controller, reverse=False)
    # Given as two rows or as 41, the same drive to within a few steps.
    assert abs(r.duration_s - dense.duration_s) < 0.6
    assert ep.log.states[:, 3].max() == pytest.approx(dense_ep.log.states[:, 3].max(), rel=0.15)


@pytest.mark.parametrize("length", [2.0, 2.05, 2.5])
def test_a_profile_from_rest_a_little_longer_than_the_final_approach_does_not_crawl(length):
    # Held from the first sample inside the final approach, the car crawled at the speed
    # of its first samples (0.47 m/s over 2.0 m; 1.99 m rose to 1.03 m/s).
    s = np.linspace(0.0, length, 41)
    profile = actuator_profile(s, 0 * s, SpeedConfig(), 0.0, 2.51, 0.4)
    shorter = actuator_profile(s * 1.99 / length, 0 * s, SpeedConfig(), 0.0, 2.51, 0.4)
    assert profile.v.max() >= shorter.v.max() - 1e-9
    assert profile.v[0] == 0.0 and profile.v[-1] == 0.0
