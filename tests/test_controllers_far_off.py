"""A car far from its path on the rate-limited (0.4 rad/s) car: it rejoins the path.

The linear laws of LQR and pure pursuit ask for full lock from a metre off; with the
wheels turning at 0.4 rad/s the car swung across the path in a growing oscillation and
crashed in highway-env (1 m off at 3 m/s). A car well behind the start of its path stood
for good short of it. Both run here in highway-env and on the bicycle with a slewing
actuator.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from rrtdrive.controllers import SpeedConfig, VehicleState, make_controller
from rrtdrive.controllers.speed import BEHIND_START_M, SpeedController, SpeedProfile
from rrtdrive.maps import builtin_map
from rrtdrive.sim.runner import run_episode
from rrtdrive.sim.tasks import CustomTask
from rrtdrive.types import InputError, Path, Pose, VehicleParams
from rrtdrive.vehicle import bicycle_step

NAMES = ["pure-pursuit", "stanley", "lqr"]
LANE_Y = 46.0


def _straight(x0: float, x1: float, y: float) -> Path:
    xs = np.arange(x0, x1 + 1e-9, 0.25)
    return Path(np.column_stack([xs, y + 0 * xs, 0 * xs, 0 * xs, 1 + 0 * xs]), np.zeros((0, 2)))


@pytest.mark.parametrize("offset", [1.0, 3.0])
@pytest.mark.parametrize("name", NAMES)
def test_a_car_metres_off_its_path_rejoins_it_in_highway_env(name, offset):
    task = CustomTask.from_map(
        builtin_map("overtake"), start=Pose(5.0, LANE_Y - offset, 0.0),
        goal=Pose(90.0, LANE_Y, 0.0), max_time_s=80.0,
    )  # fmt: skip
    ep = run_episode(task, planner=_straight(5.0, 90.0, LANE_Y), controller=name, seed=0)
    assert ep.status.value == "arrived", ep.message
    assert not ep.log.crashed.any()
    x, y = ep.log.states[:, 0], ep.log.states[:, 1]
    # On the path 30 m after the start; LQR and pure pursuit, heading back at their
    # approach angle, never swing over to the far side by more than a few centimetres
    # (Stanley's steeper approach overshoots 0.56 m from 3 m off: its own law).
    assert np.abs(y[x > 35.0] - LANE_Y).max() < 0.05
    if name != "stanley":
        assert (y - LANE_Y).max() < 0.1


def _drive(name: str, offset: float, yaw: float, v_max: float, length: float = 160.0):
    """The controller on the exact bicycle with the default car's slewing wheels."""
    car = VehicleParams()
    ctrl = make_controller(name, vehicle=car, speed=SpeedConfig(v_max=v_max))
    ctrl.reset(_straight(0.0, length, 0.0))
    x, y, h, v, steer, dt = 0.0, offset, yaw, 0.0, 0.0, 0.05
    rows = []
    for k in range(int(3 * length / v_max / dt) + 400):
        accel, cmd = ctrl.control(VehicleState(x, y, h, v, steer, k * dt))
        reach = car.max_steer_rate * dt
        steer = min(max(cmd, steer - reach), steer + reach)
        v1 = max(v + accel * dt, 0.0)
        x, y, h = bicycle_step((x, y, h), 0.5 * (v + v1), steer, dt, car.wheelbase)
        v = v1
        rows.append((x, y))
        if ctrl.arrived and v < 1e-3:
            break
    return np.array(rows)


@pytest.mark.parametrize("v_max", [3.0, 10.0])
@pytest.mark.parametrize(("offset", "yaw"), [(2.0, 0.0), (4.0, 0.0), (1.0, 0.5), (3.0, -0.6)])
@pytest.mark.parametrize("name", ["pure-pursuit", "lqr"])
def test_far_off_the_path_the_car_settles_within_60_m(name, offset, yaw, v_max):
    rows = _drive(name, offset, yaw, v_max)
    late = rows[rows[:, 0] > 60.0]
    assert len(late) and np.abs(late[:, 1]).max() < 0.05


def test_near_the_path_the_approach_angle_changes_nothing():
    """Within ``approach_angle k_psi / k_e`` of the path LQR is the linear law."""
    near = make_controller("lqr")
    linear = make_controller("lqr", approach_angle=1.5)  # reach 3.35 m: never binds here
    for ctrl in (near, linear):
        ctrl.reset(_straight(0.0, 50.0, 0.0))
    for y in (-0.4, -0.1, 0.2, 0.44):
        state = VehicleState(5.0, y, 0.05, 2.0, 0.0, 0.0)
        assert near.steering(state, near.projector.project(5.0, y)) == pytest.approx(
            linear.steering(state, linear.projector.project(5.0, y)), abs=1e-12
        )


@pytest.mark.parametrize("behind", [0.5, 6.0])
def test_a_car_behind_the_start_of_its_path_drives_up_to_it(behind):
    task = CustomTask.from_map(
        builtin_map("overtake"), start=Pose(5.0, 44.0, 0.0), goal=Pose(30.0, 44.0, 0.0),
        max_time_s=40.0,
    )  # fmt: skip
    ep = run_episode(task, planner=_straight(5.0 + behind, 30.0, 44.0), controller="lqr", seed=0)
    assert ep.status.value == "arrived", ep.message
    assert ep.log.states[-1, 0] == pytest.approx(30.0, abs=0.05)


def test_a_car_12_cm_behind_a_5_mm_reverse_stub_drives_on():
    # A given path with a gap: forward to x = 15, then a 5 mm reverse stub that starts
    # 12 cm back (behind the car in its direction of travel), then forward again. The
    # car crept and stood at x = 14.935 until the time limit.
    y = 44.0
    a = np.arange(5.0, 15.0 + 1e-9, 0.25)
    c = np.arange(14.875, 30.0 + 1e-9, 0.25)
    rows = np.vstack([
        np.column_stack([a, y + 0 * a, 0 * a, 0 * a, 1 + 0 * a]),
        [[14.88, y, 0.0, 0.0, -1.0], [14.875, y, 0.0, 0.0, -1.0]],
        np.column_stack([c, y + 0 * c, 0 * c, 0 * c, 1 + 0 * c]),
    ])  # fmt: skip
    task = CustomTask.from_map(
        builtin_map("overtake"), start=Pose(5.0, y, 0.0), goal=Pose(float(c[-1]), y, 0.0),
        max_time_s=60.0,
    )  # fmt: skip
    ep = run_episode(task, planner=Path(rows, np.zeros((0, 2))), controller="lqr", seed=0)
    assert ep.status.value == "arrived", ep.message


def test_behind_the_start_the_reference_is_the_launch_speed_and_not_at_the_start():
    cfg = SpeedConfig()
    s = np.linspace(0.0, 10.0, 41)
    # At rest at the start (as the rate-limited car's profile: the wheels turn first).
    at_rest = np.r_[0.0, np.full(len(s) - 1, np.inf)]
    profile = SpeedProfile(s, np.zeros_like(s), cfg, v_cap=at_rest)
    assert profile.at(-4.0)[0] == 0.0
    loop = SpeedController(cfg, comfort=True)
    loop.reset(profile)
    loop.control(-4.0, 0.0, 0.0)
    assert loop.v_ref == cfg.v_launch
    loop.reset(profile)
    loop.control(-0.9 * BEHIND_START_M, 0.0, 0.0)  # a stop past a cusp: the profile's rest
    assert loop.v_ref == 0.0


@pytest.mark.parametrize(
    ("name", "options", "field"),
    [
        ("stanley", {"k": -1.5}, "stanley.k"),
        ("stanley", {"k": 0.0}, "stanley.k"),
        ("lqr", {"approach_angle": 0.0}, "lqr.approach_angle"),
        ("lqr", {"approach_angle": math.pi / 2}, "lqr.approach_angle"),
        ("pure-pursuit", {"approach_angle": -0.1}, "pure_pursuit.approach_angle"),
        ("pure-pursuit", {"approach_angle": float("nan")}, "pure_pursuit.approach_angle"),
    ],
)
def test_gains_that_would_steer_away_are_refused(name, options, field):
    with pytest.raises(InputError, match=field.replace(".", r"\.")):
        make_controller(name, **options)


def test_a_launch_speed_over_the_speed_caps_is_refused():
    # A car behind its path's start drives up at v_launch: 6 m/s was taken with a 3 m/s cap.
    with pytest.raises(InputError, match=r"speed\.v_launch"):
        SpeedConfig(v_max=3.0, v_launch=6.0)
    SpeedConfig(v_max=3.0, v_launch=1.5)


def test_a_start_stub_too_short_to_drive_does_not_turn_the_wheels_first():
    # A 3 cm reverse arc at full lock, then a forward straight: the stub ends at once
    # (shorter than stop_distance), but the wheels turned to its lock and back first,
    # 2.2 s standing at the start.
    from rrtdrive.planning.hybrid.primitives import arc_poses

    y, k = 44.0, 1 / 6.0
    stub = arc_poses(5.0, y, 0.0, k, -1, np.linspace(0.0, 0.03, 3))
    ex, ey, eyaw = stub[-1]
    d = np.linspace(0.0, 20.0, 81)
    fwd = np.column_stack([ex + d * math.cos(eyaw), ey + d * math.sin(eyaw), eyaw + 0 * d, 0 * d])
    rows = np.vstack([
        np.column_stack([stub, np.full(len(stub), k), -np.ones(len(stub))]),
        np.column_stack([fwd, np.ones(len(fwd))]),
    ])  # fmt: skip
    task = CustomTask.from_map(
        builtin_map("overtake"), start=Pose(5.0, y, 0.0), goal=Pose(*fwd[-1, :3]), max_time_s=60.0
    )
    ep = run_episode(task, planner=Path(rows, np.zeros((0, 2))), controller="lqr", seed=0)
    assert ep.status.value == "arrived"
    first_motion = ep.log.t[np.flatnonzero(np.abs(ep.log.states[:, 3]) > 1e-3)[0]]
    assert first_motion < 0.5  # was 2.2 s
