"""The space-time planner and the traffic re-planner with the rate-limited steering actuator."""

from __future__ import annotations

import math

import numpy as np
import pytest
from traffic_drive import traffic_driver

from rrtdrive.controllers import SpeedConfig
from rrtdrive.maps import Map
from rrtdrive.planning.base import cached_checker
from rrtdrive.planning.spacetime import ArrivalTiming, Prediction, SpaceTimeChecker
from rrtdrive.sim.replanning import ReplanConfig, lane_path
from rrtdrive.speed_profile import actuator_profile, steering_sharpness
from rrtdrive.types import InputError, Path, Pose, VehicleParams


def _lane_change(x0: float = 0.0, length: float = 200.0, sharp: float = 0.15) -> Path:
    """A straight lane with a curvature ramp (a clothoid-like S) of sharpness ``sharp``."""
    base = lane_path(x0, x0 + length, 44.0).samples.copy()
    s = base[:, 0] - x0
    ramp = np.clip((s - 40.0) * sharp / 2.51, 0.0, 0.03) - np.clip(
        (s - 60.0) * sharp / 2.51, 0.0, 0.06) + np.clip((s - 80.0) * sharp / 2.51, 0.0, 0.03)
    base[:, 3] = ramp
    return Path(base, np.zeros((0, 2)))


def _checker(steering: tuple[float, float] | None) -> SpaceTimeChecker:
    road = Map("road", (0.0, 40.0, 220.0, 52.0), (), Pose(2.0, 44.0, 0.0),
               Pose(150.0, 44.0, 0.0), VehicleParams())
    timing = ArrivalTiming(0.0, 8.0, 11.0, 1.5, (0.0, 44.0))
    return SpaceTimeChecker(cached_checker(road), Prediction.empty(12.0), timing,
                            speed=(11.0, 1.5, 1.0, 2.0, 0.0), steering=steering)


def test_space_time_paths_are_timed_with_the_steering_rate_cap() -> None:
    path = _lane_change()
    t_free, v_free = _checker(None).path_times(path.samples)
    t_cap, v_cap = _checker((0.4, 0.7)).path_times(path.samples)
    sharp = steering_sharpness(path.arc_length(), path.samples[:, 3], VehicleParams().wheelbase)
    ramp = sharp > 1e-9
    # On the curvature ramps the speed is capped by 0.7 * 0.4 rad/s / |d delta/ds|.
    assert np.all(v_cap[ramp] <= 0.7 * 0.4 / sharp[ramp] + 1e-9)
    assert v_free[ramp].min() > v_cap[ramp].min() + 1.0
    assert t_cap[-1] > t_free[-1] + 1.0
    # The same times as the controllers' profile (actuator_profile), away from its final stop.
    cfg = SpeedConfig(v_max=11.0, accel=1.5, a_lat_max=2.0)
    prof = actuator_profile(path.arc_length(), path.samples[:, 3], cfg, 8.0,
                            VehicleParams().wheelbase, 0.4)
    far = path.arc_length() < 120.0  # the controllers stop at the end (60 m from 11 m/s)
    assert v_cap[far] == pytest.approx(prof.v[far], abs=1e-6)
    # An instant actuator (inf) is the uncapped timing.
    t_inf, _ = _checker((math.inf, 0.7)).path_times(path.samples)
    assert t_inf == pytest.approx(t_free)


@pytest.mark.parametrize("steering", [(0.0, 0.7), (0.4, 0.0), (0.4, 1.5)])
def test_space_time_steering_bad_input_names_the_field(steering) -> None:
    with pytest.raises(InputError, match="spacetime.steering"):
        _checker(steering)


def test_the_replanner_plans_lane_changes_the_car_drives_at_lane_change_speed() -> None:
    # Seed 8 (default density) accepts its first plan 0.5 s in; drive 1 s in highway-env.
    scen, speed, driver = traffic_driver(8, ReplanConfig(wall_limit=False), 20)
    v_turn = min(speed.v_max, math.sqrt(speed.a_lat_max * ReplanConfig().turning_radius_m))
    bound = speed.steer_rate_share * scen.vehicle.max_steer_rate / v_turn
    assert 0.03 < bound < 0.04
    # The first reference is the start merge into the lane (curved too, not a plan).
    planned = [p for _, p in driver.references[1:] if np.any(p.samples[:, 3] != 0.0)]
    assert planned, "no plan was accepted: the test does not reach a plan"
    assert driver.mode == "overtake"
    for path in planned:
        s, kappa = path.arc_length(), path.samples[:, 3]
        sharp = steering_sharpness(s, kappa, scen.vehicle.wheelbase)
        assert sharp.max() <= bound * 1.05, f"sharpness {sharp.max():.4f} > {bound:.4f}"
        # So the car drives the lane change at the lateral-acceleration speed, not slower.
        prof = actuator_profile(s, kappa, speed, 8.0, scen.vehicle.wheelbase,
                                scen.vehicle.max_steer_rate)
        lane_change = (path.samples[:, 1] > 44.5) & (s < s[-1] - 80.0)
        assert prof.v[lane_change].min() >= 0.9 * v_turn


@pytest.mark.parametrize(
    ("options", "expected"),
    [({}, None), ({"smoothing": {"max_sharpness": 0.05}}, 0.05)],
)
def test_the_replanner_sets_the_road_sharpness_unless_given(options, expected) -> None:
    config = ReplanConfig(wall_limit=False, planner_options=options)
    scen, speed, driver = traffic_driver(0, config, None)
    v_turn = math.sqrt(speed.a_lat_max * config.turning_radius_m)
    road = speed.steer_rate_share * scen.vehicle.max_steer_rate / v_turn
    smoothing = driver.planner.config.smoothing
    assert smoothing.max_sharpness == pytest.approx(road if expected is None else expected)
    assert smoothing.max_rounds == 8  # the driver's own default is kept
    assert driver.window.speed_tuple()[4] == 0.0  # no launch speed for a rate-limited car
