"""The one speed-profile module: caps, passes, arrival times; both users see the same rules."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from speed_runs import point_mass_run

from rrtdrive.controllers import SpeedConfig, SpeedController
from rrtdrive.controllers import SpeedProfile as ControllersProfile
from rrtdrive.planning.spacetime import profile_times as spacetime_times
from rrtdrive.speed_profile import (
    SHARPNESS_WINDOW_M,
    SpeedProfile,
    actuator_profile,
    arrival_times,
    peak_with_plateau,
    plateau_caps,
    profile_times,
    speed_caps_squared,
    steering_rate_speed_cap,
    steering_sharpness,
)


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


# ----------------------------------------------------------------------------- the car's profile


def _clothoid_dip(length: float = 30.0) -> tuple[np.ndarray, np.ndarray]:
    """A path whose curvature ramps up and down around s = 20 m: a slow stretch near the end."""
    s = np.linspace(0.0, length, int(length / 0.1) + 1)
    kappa = 0.15 * np.clip(1.0 - np.abs(s - 20.0), 0.0, 1.0)
    return s, kappa


def test_the_cars_profile_is_the_plain_one_for_an_instant_actuator():
    s, kappa = _clothoid_dip()
    cfg = SpeedConfig()
    for rate in (None, np.inf):
        prof = actuator_profile(s, kappa, cfg, 0.4, 2.51, rate)
        assert np.array_equal(prof.v, SpeedProfile(s, kappa, cfg, 0.4).v)


def test_the_cars_profile_obeys_the_steering_rate_cap_and_starts_from_rest():
    s, kappa = _clothoid_dip(60.0)
    cfg = SpeedConfig()
    prof = actuator_profile(s, kappa, cfg, 0.0, 2.51, 0.4)
    cap = steering_rate_speed_cap(s, kappa, 2.51, 0.4, cfg.steer_rate_share)
    assert prof.v[0] == 0.0 and np.all(prof.v <= cap + 1e-12)
    assert np.all(prof.v <= SpeedProfile(s, kappa, cfg, 0.0).v + 1e-12)


def test_a_short_speed_up_after_the_last_slow_stretch_is_lowered_not_held_at_the_trough():
    # 10 m after the dip: the plain rules rise and brake at once, which the comfort loop
    # (jerk 2 m/s^3) cannot turn into the stop. The peak is lowered until it holds for
    # (accel + decel) / jerk seconds; it had held the rest at the dip's 0.75 m/s.
    s, kappa = _clothoid_dip(30.0)
    cfg = SpeedConfig()
    prof = actuator_profile(s, kappa, cfg, 0.0, 2.51, 0.4)
    after = s >= 21.0
    dip = float(prof.v[(s > 19.0) & (s < 21.0)].min())
    top = float(prof.v[after].max())
    held = s[after][prof.v[after] >= top - 1e-9]
    lag = (cfg.accel + cfg.decel) / cfg.comfort_jerk
    assert top > 2.0 * dip
    assert held[-1] - held[0] >= top * lag - 1e-9
    # The highest such level: the rate-capped rules' speeds a little above it do not last.
    cap = steering_rate_speed_cap(s, kappa, 2.51, 0.4, cfg.steer_rate_share)
    plain = SpeedProfile(s, kappa, dataclasses.replace(cfg, v_launch=0.0), 0.0, v_cap=cap).v
    above = s[after][plain[after] >= top + 0.02]
    assert above[-1] - above[0] < (top + 0.02) * lag
    times = prof.times()
    assert times[-1] - times[after][0] < 0.7 * (s[-1] - 21.0) / dip  # the old hold's time
    # With a long straight after the dip (a plateau at v_max before the braking) the
    # peak is not lowered.
    s, kappa = _clothoid_dip(80.0)
    prof = actuator_profile(s, kappa, cfg, 0.0, 2.51, 0.4)
    assert prof.v[s >= 21.0].max() == pytest.approx(cfg.v_max)


@settings(max_examples=60, deadline=None)
@given(
    st.floats(0.05, 0.5),  # sample spacing
    st.floats(0.3, 30.0),  # length
    st.floats(0.0, 1.0),  # where, as a share of the length
)
def test_the_reference_between_samples_keeps_the_intervals_acceleration(
    spacing: float, length: float, where: float
):
    # Each interval has one acceleration a_ref = d(v^2/2)/ds, so v_ref^2 is linear in s
    # on it: v_ref linear in s instead made the last interval's v_ref proportional to
    # the distance left (v_ref = 2 d at 0.25 m spacing), an exponential crawl to the stop.
    n = max(2, int(length / spacing) + 1)
    s = np.linspace(0.0, length, n)
    prof = SpeedProfile(s, np.zeros_like(s), SpeedConfig(), 0.0)
    x = where * length * (1 - 1e-9)
    v, a = prof.at(x)
    i = int(np.searchsorted(s, x, side="right") - 1)
    v0, (_, a0) = prof.v[i], prof.at(float(s[i]))
    assert a == a0
    assert v * v - v0 * v0 == pytest.approx(2.0 * a * (x - s[i]), abs=1e-9)


@pytest.mark.parametrize("length", [0.5, 0.7, 1.0, 2.0, 5.0])
def test_a_manoeuvre_segment_peaks_low_enough_for_the_comfort_loop_to_stop(length: float):
    # A multi-point turn's 0.7 m move: the rest-to-rest triangle of a profile (rise, then
    # brake at once) left the jerk-limited loop speeding up when it had to brake; the
    # car reached the cusp at 0.4 m/s and stopped 0.2 m past it.
    cfg = SpeedConfig()
    slow = dataclasses.replace(cfg, accel=cfg.accel_manoeuvre, decel=cfg.accel_manoeuvre)
    s = np.linspace(0.0, length, max(3, int(length / 0.25) + 1))
    prof = actuator_profile(s, np.zeros_like(s), slow, 0.0, 2.51, 0.4, rise_to_peak=True)
    peak = float(prof.v.max())
    assert peak == pytest.approx(
        min(peak_with_plateau(length, slow.accel, slow.accel + slow.decel, slow.comfort_jerk),
            float(SpeedProfile(s, np.zeros_like(s), slow, 0.0).v.max()), slow.v_max),
        rel=1e-6,
    )  # fmt: skip
    # The loop in comfort mode on a point mass: at rest at the end, never past it.
    ctrl = SpeedController(slow, comfort=True)
    ctrl.reset(prof)
    pos, _, _ = point_mass_run(ctrl, 0.0, 0.0)
    assert ctrl.arrived and abs(pos - length) <= slow.stop_distance


@pytest.mark.parametrize("length", [1.0, 3.0, 8.0, 20.0])
def test_plateau_caps_of_a_rest_to_rest_triangle_are_peak_with_plateau(length: float):
    # The same rule in two forms: the closed form for a triangle, the search on samples.
    accel, lag = 0.8, 0.5
    s = np.linspace(0.0, length, 4001)
    v = np.sqrt(2.0 * accel * np.minimum(s, length - s))
    top = float(np.minimum(v, plateau_caps(s, v, lag)).max())
    expected = min(peak_with_plateau(length, accel, lag, 1.0), float(v.max()))
    assert top == pytest.approx(expected, abs=2.0 * accel * length / 4000 / max(expected, 0.1))


@settings(max_examples=80, deadline=None)
@given(
    caps=st.lists(st.floats(0.2, 3.0), min_size=2, max_size=12),
    length=st.floats(2.0, 60.0),
    lag=st.floats(0.1, 1.5),
)
def test_plateau_caps_give_every_peak_its_plateau_within_the_profile_bounds(
    caps: list[float], length: float, lag: float
):
    cfg = SpeedConfig(v_launch=0.0)  # from rest, as actuator_profile (peaks at a moving
    # start are left alone)
    s = np.linspace(0.0, length, int(length / 0.25) + 2)
    cap = np.asarray(caps)[np.minimum((s / length * len(caps)).astype(int), len(caps) - 1)]
    v = SpeedProfile(s, np.zeros_like(s), cfg, v_start=0.0, v_cap=cap).v
    capped = np.minimum(v, plateau_caps(s, v, lag))
    assert np.all(capped <= v)
    # Still within the profile's acceleration and deceleration (min of a feasible
    # profile and a constant).
    dv2 = np.diff(capped**2) / (2.0 * np.diff(s))
    assert dv2.max() <= cfg.accel + 1e-9 and dv2.min() >= -cfg.decel - 1e-9
    # Every peak (a run of samples at one level, lower on both sides) lasts lag seconds.
    i = 1
    while i < len(capped) - 1:
        j = i
        while j + 1 < len(capped) and abs(capped[j + 1] - capped[i]) <= 1e-9:
            j += 1
        lower = capped[i - 1] < capped[i] - 1e-9
        if lower and j + 1 < len(capped) and capped[j + 1] < capped[i] - 1e-9:
            assert s[j] - s[i] >= capped[i] * lag - 1e-6
        i = j + 1


@settings(max_examples=80, deadline=None)
@given(
    gaps=st.lists(st.floats(0.02, 0.6), min_size=2, max_size=30),
    kappas=st.lists(st.floats(-0.2, 0.2), min_size=31, max_size=31),
)
def test_sharpness_is_the_steepest_window_over_each_sample(gaps: list[float], kappas: list[float]):
    # Reference: every window of 0.25 m that comes within 0.25 m of the sample, slid on a
    # fine grid of positions, on the linearly interpolated steering angle. The grid of
    # session 26 read a curvature step between two rows up to 2x too small when offset
    # from the rows.
    s = np.concatenate([[0.0], np.cumsum(gaps)])
    kappa = np.asarray(kappas[: len(s)])
    w, wheelbase = SHARPNESS_WINDOW_M, 2.51
    sharp = steering_sharpness(s, kappa, wheelbase)
    delta = np.arctan(wheelbase * kappa)
    for i, si in enumerate(s):
        starts = np.concatenate([np.linspace(si - 2 * w, si + w, 601),
                                 s[(s >= si - 2 * w) & (s <= si + w)],
                                 s[(s >= si - w) & (s <= si + 2 * w)] - w])  # fmt: skip
        change = np.abs(np.interp(starts + w, s, delta) - np.interp(starts, s, delta)) / w
        assert change.max() == pytest.approx(sharp[i], abs=1e-9)


@pytest.mark.parametrize("extra", [0.05, 0.1, 0.125, 0.2])
def test_the_steering_rate_cap_at_a_step_does_not_depend_on_where_the_path_ends(extra: float):
    # A step from straight to 0.1 1/m between two rows 0.25 m apart; one more row at the
    # end moved session 26's grid off the rows, and the cap at the step rose from
    # 0.285 m/s to up to 0.388 m/s (5 cm more): the wheels asked 36 % over the share.
    s = np.arange(0.0, 15.0 + 1e-9, 0.25)
    kappa = np.where(s > 5.0, 0.1, 0.0)
    longer = np.append(s, s[-1] + extra)
    cap = steering_rate_speed_cap(s, kappa, 2.51, 0.4, 0.7)
    cap_longer = steering_rate_speed_cap(longer, np.append(kappa, 0.1), 2.51, 0.4, 0.7)
    assert np.array_equal(cap[:-3], cap_longer[:-4])
    assert cap.min() == pytest.approx(0.7 * 0.4 * 0.25 / np.arctan(0.251))


def test_a_low_last_peak_does_not_cap_the_higher_stretch_before_it():
    # 2 m/s, a dip to 1.5 m/s, a last peak of 1.62 m/s too short to hold, then the stop:
    # lowering the peak merged its stretch with the 2 m/s one and capped that too
    # (parallel parking seed 3: 26 m of 2 m/s capped at 1.56 m/s).
    s = np.linspace(0.0, 28.5, 286)  # the stop at 28.5 m cuts the last rise at 1.62 m/s
    cap = np.where(s < 25.0, 2.0, np.where(s < 27.0, 1.5, 3.0))
    v = SpeedProfile(s, np.zeros_like(s), SpeedConfig(v_launch=0.0), 0.0, v_cap=cap).v
    last_top = float(v[s > 27.0].max())
    assert 1.6 < last_top < 1.65
    caps = plateau_caps(s, v, 1.0, last_only=True)
    assert np.all(np.isinf(caps[v > last_top + 1e-9]))  # nothing higher is capped
    capped = np.minimum(v, caps)
    assert capped[s > 27.0].max() <= 1.5 + 1e-12  # the peak is lowered to the dip (a shoulder)
    dv2 = np.diff(capped**2) / (2.0 * np.diff(s))
    assert dv2.max() <= 1.0 + 1e-9 and dv2.min() >= -1.0 - 1e-9


@settings(max_examples=60, deadline=None)
@given(
    caps=st.lists(st.floats(0.1, 3.0), min_size=2, max_size=10),
    length=st.floats(3.0, 60.0),
)
def test_every_peak_of_a_profile_from_rest_lasts_the_time_to_swing_into_braking(
    caps: list[float], length: float
):
    cfg = SpeedConfig()
    s = np.linspace(0.0, length, int(length / 0.25) + 2)
    # Curvature steps make steering-rate troughs between stretches of other speed caps.
    level = np.asarray(caps)[np.minimum((s / length * len(caps)).astype(int), len(caps) - 1)]
    _assert_every_peak_lasts(s, np.minimum(cfg.a_lat_max / level**2, 0.2), cfg)


@pytest.mark.parametrize("straight", [3.0, 5.0, 8.0])
def test_a_peak_before_a_curvature_step_lasts_the_time_to_swing_into_braking(straight):
    # Any peak, not only the last: after an earlier peak the loop was still speeding up
    # where the profile braked into a slow stretch (5 m of straight before a curvature
    # step to 1/6 1/m: the car braked at -2.16 m/s^2 and stood still before the step).
    s = np.arange(0.0, straight + 30.0 + 1e-9, 0.25)
    kappa = np.where(s > straight, 1.0 / 6.0, 0.0)
    assert _assert_every_peak_lasts(s, kappa, SpeedConfig()) == 2


def _assert_every_peak_lasts(s: np.ndarray, kappa: np.ndarray, cfg: SpeedConfig) -> int:
    """Every peak of the car's profile from rest (a run of equal speeds, lower on both
    sides) lasts ``decel / comfort_jerk`` seconds; returns how many there are."""
    v = actuator_profile(s, kappa, cfg, 0.0, 2.51, 0.4).v
    peaks, i = 0, 1
    while i < len(v) - 1:
        j = i
        while j + 1 < len(v) and abs(v[j + 1] - v[i]) <= 1e-9:
            j += 1
        if v[i - 1] < v[i] - 1e-9 and j + 1 < len(v) and v[j + 1] < v[i] - 1e-9:
            assert s[j] - s[i] >= v[i] * cfg.decel / cfg.comfort_jerk - 1e-6, (s[i], v[i])
            peaks += 1
        i = j + 1
    return peaks


@settings(max_examples=200)
@given(
    v=st.lists(st.floats(0.0, 15.0) | st.just(float("inf")), min_size=1, max_size=300),
    steps=st.lists(st.floats(0.0, 0.6) | st.just(0.0), min_size=300, max_size=300),
    accel=st.floats(0.05, 4.0),
    decel=st.floats(0.05, 4.0),
)
def test_the_accel_and_decel_passes_are_the_numpy_loop_bit_for_bit(v, steps, accel, decel):
    # Session 31 moved the two passes from numpy scalars to Python floats (5.8x faster);
    # the reference is the loop as it was, element by element on the array.
    from rrtdrive.speed_profile import _accel_decel_passes

    ref, ds = np.array(v), np.array(steps[: len(v) - 1])
    for i in range(1, len(ref)):
        ref[i] = min(ref[i], np.sqrt(ref[i - 1] ** 2 + 2.0 * accel * ds[i - 1]))
    ref[-1] = 0.0
    for i in range(len(ref) - 2, -1, -1):
        ref[i] = min(ref[i], np.sqrt(ref[i + 1] ** 2 + 2.0 * decel * ds[i]))
    got = np.array(_accel_decel_passes(list(v), ds.tolist(), accel, decel))
    assert got.tobytes() == ref.tobytes()
