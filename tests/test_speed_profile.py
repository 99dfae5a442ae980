"""The one speed-profile module: caps, passes, arrival times; both users see the same rules."""

from __future__ import annotations

import numpy as np
import pytest

from rrtdrive.controllers import SpeedConfig
from rrtdrive.controllers import SpeedProfile as ControllersProfile
from rrtdrive.planning.spacetime import profile_times as spacetime_times
from rrtdrive.speed_profile import SpeedProfile, arrival_times, profile_times, speed_caps_squared


def test_both_users_get_the_one_implementation():
    assert ControllersProfile is SpeedProfile
    assert spacetime_times is profile_times


def test_caps_are_the_square_of_the_controllers_speed_caps_bit_for_bit():
    rng = np.random.default_rng(3)
    kappa = rng.choice([0.0, 1.0], 500) * rng.normal(0.0, 0.3, 500)
    for v_max in (3.0, 10.0, 11.7, 0.9):
        v_curve = np.sqrt(1.7 / np.maximum(np.abs(kappa), 1e-12))
        cap2 = speed_caps_squared(kappa, v_max, 1.7, np.inf)
        assert np.array_equal(np.sqrt(cap2), np.minimum(v_curve, v_max))
    assert speed_caps_squared(np.zeros(3), 5.0, 1.0, 2.0)[0] == 4.0


def test_profile_obeys_the_rules_and_its_times_match_the_closed_form_away_from_the_stop():
    s = np.linspace(0.0, 120.0, 1201)
    kappa = np.where((s > 30) & (s < 45), 1.0 / 20.0, 0.0)
    cfg = SpeedConfig(v_max=9.0, accel=1.2, decel=1.0, a_lat_max=1.5)
    prof = SpeedProfile(s, kappa, cfg, v_start=2.0)
    assert prof.v[-1] == 0.0 and prof.v.max() <= 9.0
    assert np.all(prof.v[(s > 30) & (s < 45)] <= np.sqrt(1.5 * 20.0) + 1e-12)
    dv2 = np.diff(prof.v**2) / np.diff(s)
    assert dv2.max() <= 2 * 1.2 + 1e-9 and dv2.min() >= -2 * 1.0 - 1e-9
    t, v = profile_times(s, kappa, 2.0, cfg.v_max, cfg.accel, cfg.decel, cfg.a_lat_max,
                         cfg.v_launch)
    far = s < 70.0  # beyond reach of the stop at 120 m
    assert v[far] == pytest.approx(prof.v[far], abs=1e-12)
    assert prof.times()[far] == pytest.approx(t[far], abs=1e-9)


def test_arrival_times_use_the_mean_speed_with_a_floor():
    assert arrival_times(np.array([0.0, 2.0]), np.array([1.0, 3.0])).tolist() == [0.0, 1.0]
    assert arrival_times(np.array([0.0, 0.1]), np.array([0.0, 0.0])).tolist() == [0.0, 2.0]
