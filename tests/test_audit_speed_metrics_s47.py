"""Audit (session 47): the speed profile and the metrics of forward-only episodes.

The speed profile (``rrtdrive.speed_profile``) is checked against an independent
closed form of the fastest admissible profile (the min-plus envelope
``v_i^2 = min_j(cap_j^2 + 2 a (s_i - s_j))`` over ``j <= i`` and
``min_j(cap_j^2 + 2 d (s_j - s_i))`` over ``j >= i``, computed as an O(N^2) numpy
table, not as the product's passes), and its documented bounds are asserted on
random curvature profiles (hypothesis, derandomized). The rate-limited
``actuator_profile`` is checked for its documented extra rules (steering-rate cap,
no launch step, no rise on the final approach, a plateau on every peak from rest).

The metrics of ``evaluate`` are recomputed from the logged arrays alone for
forward-only drives in the real highway-env (``overtake`` with the three
controllers, ``parking`` with Stanley, ``overtake`` at 15 Hz, and a forward path
driven straight into the stopped car), and for logs built by hand as
docs/metrics.md describes them (a stationary car, a one-step drive, the nuPlan
0.3 s boundary): tracking errors against the path polyline with shapely, comfort
and curvature figures from the commands, nuPlan's Savitzky-Golay figures with
scipy, the goal terms, the footprint judge and the vehicle collisions with shapely
rectangles, and ``summarise`` with scipy's Wilson interval.
"""

from __future__ import annotations

import dataclasses
import math
import re
from pathlib import Path as FsPath

import numpy as np
import pytest
import shapely
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.signal import savgol_filter
from scipy.stats import binomtest

from rrtdrive.controllers import SpeedConfig
from rrtdrive.evaluation import Outcome, evaluate, summarise, tracking_errors
from rrtdrive.evaluation.nuplan_comfort import COMFORT_BOUNDS, nuplan_comfort
from rrtdrive.evaluation.report import SIGNED_FIELDS, EpisodeReport, EvalConfig
from rrtdrive.evaluation.summary import MEAN_FIELDS
from rrtdrive.sim.runner import EpisodeConfig, run_episode
from rrtdrive.sim.scenes import SimConfig
from rrtdrive.sim.tasks import make_variant
from rrtdrive.speed_profile import (
    FINAL_APPROACH_M,
    SpeedProfile,
    actuator_profile,
    arrival_times,
    profile_times,
    speed_caps_squared,
)
from rrtdrive.steering_sharpness import steering_rate_speed_cap
from rrtdrive.types import InputError, Path

DOCS = FsPath(__file__).resolve().parents[1] / "docs" / "metrics.md"
SETTINGS = settings(
    max_examples=120, deadline=None, derandomize=True,
    suppress_health_check=[HealthCheck.too_slow],
)
WHEELBASE = 2.51


# ----------------------------------------------------------------- reference profile
def _ref_caps(s, kappa, v_max, a_lat, v_first, extra=None):
    k = np.abs(np.asarray(kappa, dtype=float))
    cap = np.full(len(s), float(v_max))
    nz = k > 0
    with np.errstate(over="ignore"):
        cap[nz] = np.minimum(v_max, np.sqrt(a_lat / k[nz]))
    if extra is not None:
        cap = np.minimum(cap, extra)
    cap[0] = min(cap[0], v_first)
    return cap


def _ref_fastest(s, cap, accel, decel, stop):
    """The greatest v with v <= cap, (v_end = 0 if stop), rises <= accel, falls <= decel."""
    c2 = np.square(np.asarray(cap, dtype=float))
    if stop:
        c2[-1] = 0.0
    s = np.asarray(s, dtype=float)
    gap = s[:, None] - s[None, :]  # s_i - s_j
    fwd = np.where(gap >= 0, c2[None, :] + 2.0 * accel * gap, np.inf).min(axis=1)
    bwd = np.where(gap <= 0, c2[None, :] - 2.0 * decel * gap, np.inf).min(axis=1)
    return np.sqrt(np.minimum(fwd, bwd))


def _assert_bounds(s, v, kappa, v_max, a_lat, accel, decel, rel=1e-9, abs2=1e-12):
    s, v = np.asarray(s), np.asarray(v)
    assert np.all(v >= 0.0)
    assert np.all(v**2 <= v_max**2 * (1 + rel) + abs2)
    assert np.all(v**2 * np.abs(kappa) <= a_lat * (1 + rel) + abs2 * np.abs(kappa) + 1e-12)
    dv2, ds = np.diff(v**2), np.diff(s)
    assert np.all(dv2 <= 2 * accel * ds * (1 + rel) + 2 * abs2)
    assert np.all(-dv2 <= 2 * decel * ds * (1 + rel) + 2 * abs2)


@st.composite
def _paths(draw, min_n=2, max_n=50):
    n = draw(st.integers(min_n, max_n))
    ds = draw(st.lists(st.one_of(st.just(0.0), st.floats(0.01, 1.5)), min_size=n - 1,
                       max_size=n - 1))
    kappa = draw(st.lists(st.one_of(st.just(0.0), st.floats(-0.5, 0.5)), min_size=n,
                          max_size=n))
    s = np.concatenate([[0.0], np.cumsum(ds)])
    return s, np.asarray(kappa, dtype=float)


@st.composite
def _limits(draw):
    v_max = draw(st.floats(0.5, 12.0))
    return SpeedConfig(
        v_max=v_max, a_lat_max=draw(st.floats(0.2, 4.0)), accel=draw(st.floats(0.1, 3.0)),
        decel=draw(st.floats(0.1, 3.0)), v_launch=draw(st.floats(0.0, v_max)),
    )


# ------------------------------------------------------------------ speed profile
@SETTINGS
@given(_paths(), _limits(), st.floats(0.0, 15.0), st.booleans(), st.data())
def test_speed_profile_is_the_fastest_admissible_profile(path, cfg, v_start, capped, data):
    s, kappa = path
    v_cap = None
    if capped:
        v_cap = np.asarray(data.draw(st.lists(st.floats(0.0, 10.0), min_size=len(s),
                                              max_size=len(s))))
    prof = SpeedProfile(s, kappa, cfg, v_start=v_start, v_cap=v_cap)
    v = prof.v
    cap = _ref_caps(s, kappa, cfg.v_max, cfg.a_lat_max, max(v_start, cfg.v_launch), v_cap)
    if v_cap is not None:
        assert np.all(v <= v_cap)
    want = _ref_fastest(s, cap, cfg.accel, cfg.decel, stop=True)
    np.testing.assert_allclose(v, want, rtol=1e-9, atol=1e-9)
    _assert_bounds(s, v, kappa, cfg.v_max, cfg.a_lat_max, cfg.accel, cfg.decel)
    assert v[0] <= max(v_start, cfg.v_launch) * (1 + 1e-12)
    assert v[-1] == 0.0
    # The documented per-interval acceleration, and the curve cap of every sample.
    ds = np.diff(s)
    a_want = np.where(ds > 0, np.diff(v**2) / (2 * np.where(ds > 0, ds, 1.0)), 0.0)
    np.testing.assert_allclose(prof.a[:-1], a_want, rtol=1e-9, atol=1e-9)
    assert prof.a[-1] == 0.0
    assert np.all(prof.a <= cfg.accel * (1 + 1e-9) + 1e-12)
    assert np.all(prof.a >= -cfg.decel * (1 + 1e-9) - 1e-12)
    k = np.abs(kappa)
    with np.errstate(divide="ignore"):
        # (|kappa| is floored at 1e-12 there, a straight's "curve speed" is then finite.)
        curve = np.where(k > 1e-12, np.sqrt(cfg.a_lat_max / np.where(k > 0, k, 1.0)), np.inf)
    finite = np.isfinite(curve)
    np.testing.assert_allclose(prof.v_curve[finite], curve[finite], rtol=1e-12)
    assert np.all(prof.v_curve[~finite] >= 1e5)
    assert prof.length == s[-1]
    np.testing.assert_array_equal(prof.times(), arrival_times(s, v))


@SETTINGS
@given(_paths(), _limits(), st.floats(0.0, 15.0), st.booleans(), st.data())
def test_profile_times_is_the_fastest_profile_without_a_stop(path, cfg, v0, capped, data):
    s, kappa = path
    v_cap = None
    if capped:
        v_cap = np.asarray(data.draw(st.lists(st.floats(0.0, 10.0), min_size=len(s),
                                              max_size=len(s))))
    t, v = profile_times(s, kappa, v0, cfg.v_max, cfg.accel, cfg.decel, cfg.a_lat_max,
                         cfg.v_launch, v_cap=v_cap)
    cap = _ref_caps(s, kappa, cfg.v_max, cfg.a_lat_max, max(v0, cfg.v_launch), v_cap)
    # The closed form works on v^2 offset by 2 a s: its rounding is absolute in v^2,
    # ulps of 2 a s (a 1e-7 m/s cap reads 1.2e-7 m/s 40 m along); compare in v^2.
    tol2 = 1e-13 * (1.0 + 2.0 * max(cfg.accel, cfg.decel) * s[-1] + cfg.v_max**2)
    want = _ref_fastest(s, cap, cfg.accel, cfg.decel, stop=False)
    np.testing.assert_allclose(v**2, want**2, rtol=1e-9, atol=tol2)
    if v_cap is not None:
        assert np.all(v**2 <= v_cap**2 * (1 + 1e-9) + tol2)
    _assert_bounds(s, v, kappa, cfg.v_max, cfg.a_lat_max, cfg.accel, cfg.decel, abs2=tol2)
    # Arrival times: each interval at the mean of its end speeds, at least 0.05 m/s.
    mean = np.maximum(0.5 * (v[1:] + v[:-1]), 0.05)
    np.testing.assert_allclose(t, np.concatenate([[0.0], np.cumsum(np.diff(s) / mean)]),
                               rtol=1e-12, atol=1e-12)
    assert np.all(np.diff(t) >= 0.0)
    # The controller's profile of the same caps differs only by its stop at the end.
    prof = SpeedProfile(s, kappa, cfg, v_start=v0, v_cap=v_cap)
    assert np.all(prof.v**2 <= v**2 * (1 + 1e-9) + tol2)


@SETTINGS
@given(_paths(), _limits(), st.floats(0.0, 10.0), st.sampled_from(
    ["v_max", "a_lat_max", "accel", "decel"]), st.floats(1.0, 3.0))
def test_raising_a_limit_never_lowers_the_profile(path, cfg, v_start, name, factor):
    s, kappa = path
    base = SpeedProfile(s, kappa, cfg, v_start=v_start).v
    kw = {name: getattr(cfg, name) * factor}
    looser = SpeedProfile(s, kappa, dataclasses.replace(cfg, **kw), v_start=v_start).v
    assert np.all(looser >= base - 1e-9)


@SETTINGS
@given(st.integers(2, 80), st.floats(0.05, 1.0), _limits(), st.floats(0.0, 15.0))
def test_straight_profile_rises_then_falls_at_exactly_its_limits(n, step, cfg, v_start):
    s = np.arange(n) * step
    v = SpeedProfile(s, np.zeros(n), cfg, v_start=v_start).v
    top = int(np.argmax(v))
    assert np.all(np.diff(v[: top + 1]) >= -1e-12)  # monotone up to the top ...
    assert np.all(np.diff(v[top:]) <= 1e-12)  # ... and down from it
    v0 = min(cfg.v_max, max(v_start, cfg.v_launch))
    # Free of the stop and of v_max, the rise is v^2 = v0^2 + 2 a s; the fall ends at 0.
    free = (v0**2 + 2 * cfg.accel * s < cfg.v_max**2) & (
        v0**2 + 2 * cfg.accel * s < 2 * cfg.decel * (s[-1] - s))
    np.testing.assert_allclose(v[free] ** 2, (v0**2 + 2 * cfg.accel * s)[free], rtol=1e-9)
    tail = 2 * cfg.decel * (s[-1] - s) < np.minimum(cfg.v_max**2, v0**2 + 2 * cfg.accel * s)
    np.testing.assert_allclose(v[tail] ** 2, (2 * cfg.decel * (s[-1] - s))[tail],
                               rtol=1e-9, atol=1e-12)


@SETTINGS
@given(_paths(min_n=2), _limits(), st.floats(0.0, 6.0), st.data())
def test_at_and_peak_read_the_samples_with_v2_linear_between(path, cfg, v_start, data):
    s, kappa = path
    prof = SpeedProfile(s, kappa, cfg, v_start=v_start)
    v = prof.v
    for i in range(len(s) - 1):
        if s[i] < s[-1] and (i == 0 or s[i] > s[i - 1]):
            assert math.isclose(prof.at(float(s[i]))[0], v[i], rel_tol=1e-12, abs_tol=1e-12)
    assert prof.at(float(s[-1])) == (0.0, 0.0)
    assert prof.at(float(s[-1]) + 1.0) == (0.0, 0.0)
    assert prof.at(-1.0) == (v[0], prof.a[0])
    if s[-1] > 0:
        q = data.draw(st.floats(0.0, float(s[-1]), exclude_min=True, exclude_max=True))
        i = int(np.searchsorted(s, q, side="right")) - 1
        frac = (q - s[i]) / (s[i + 1] - s[i])
        want = math.sqrt(v[i] ** 2 + frac * (v[i + 1] ** 2 - v[i] ** 2))
        got_v, got_a = prof.at(q)
        assert math.isclose(got_v, want, rel_tol=1e-9, abs_tol=1e-12)
        assert got_a == prof.a[i]
        lo = data.draw(st.floats(0.0, q))
        inner = v[(s > lo) & (s < q)]
        top = max(prof.at(lo)[0], prof.at(q)[0], *(inner.tolist() or [0.0]))
        assert prof.peak(lo, q) == pytest.approx(top, rel=1e-12, abs=1e-12)


def test_speed_caps_and_arrival_times_by_hand():
    # a_lat / |kappa| = 4 at kappa 0.5 (below v_max^2 = 9); the first sample capped at 1.
    np.testing.assert_allclose(speed_caps_squared(np.array([0.0, -0.5, 0.0]), 3.0, 2.0, 1.0),
                               [1.0, 4.0, 9.0])
    # 1 m at 1 m/s, then 2 m at the mean of 1 and 3 m/s; a standstill at the 0.05 floor.
    np.testing.assert_allclose(arrival_times(np.array([0.0, 1.0, 3.0]), np.array([1.0, 1, 3])),
                               [0.0, 1.0, 2.0])
    np.testing.assert_allclose(arrival_times(np.array([0.0, 0.1]), np.zeros(2)), [0.0, 2.0])


def test_single_sample_profiles_stand_still():
    cfg = SpeedConfig()
    prof = SpeedProfile(np.zeros(1), np.zeros(1), cfg, v_start=2.0)
    assert prof.v.tolist() == [0.0] and prof.length == 0.0
    assert prof.at(0.0) == (0.0, 0.0) and prof.times().tolist() == [0.0]
    assert actuator_profile(np.zeros(1), np.zeros(1), cfg, 0.0, WHEELBASE, 0.4).v.tolist() == [0.0]
    # No stop in the planner's timing: the one sample is at the start speed.
    t, v = profile_times(np.zeros(1), np.zeros(1), 2.0, 3.0, 1.0, 1.0, 1.5)
    assert t.tolist() == [0.0] and v.tolist() == [2.0]


@pytest.mark.parametrize("fn", ["SpeedProfile", "profile_times", "actuator_profile"])
def test_empty_path_is_one_clear_error(fn):
    e = np.zeros(0)
    with pytest.raises(InputError):
        if fn == "SpeedProfile":
            SpeedProfile(e, e, SpeedConfig())
        elif fn == "profile_times":
            profile_times(e, e, 0.0, 3.0, 1.0, 1.0, 1.5)
        else:
            actuator_profile(e, e, SpeedConfig(), 0.0, WHEELBASE, 0.4)


@pytest.mark.parametrize("where", ["kappa", "s", "v_start", "v_cap"])
def test_nan_inputs_are_one_clear_error(where):
    s, kappa = np.linspace(0.0, 5.0, 6), np.zeros(6)
    v_start, v_cap = 0.0, None
    if where == "kappa":
        kappa[2] = np.nan
    elif where == "s":
        s[2] = np.nan
    elif where == "v_start":
        v_start = math.nan
    else:
        v_cap = np.full(6, 2.0)
        v_cap[3] = np.nan
    with pytest.raises(InputError):
        SpeedProfile(s, kappa, SpeedConfig(), v_start=v_start, v_cap=v_cap)


# ------------------------------------------------------------ the actuator's profile
@st.composite
def _curvature_steps(draw):
    n = draw(st.integers(3, 160))
    step = draw(st.floats(0.02, 0.5))
    s = np.arange(n) * step
    knots = np.sort(np.asarray(draw(st.lists(st.floats(0.0, float(s[-1])), min_size=1,
                                             max_size=5))))
    vals = np.asarray(draw(st.lists(st.one_of(st.just(0.0), st.floats(-1 / 6, 1 / 6)),
                                    min_size=len(knots) + 1, max_size=len(knots) + 1)))
    return s, vals[np.searchsorted(knots, s)]


@SETTINGS
@given(_curvature_steps(), st.one_of(st.just(0.0), st.floats(0.01, 3.0)),
       st.sampled_from([None, math.inf, 0.2, 0.4, 1.0]))
def test_actuator_profile_rules(path, v_start, rate):
    s, kappa = path
    cfg = SpeedConfig()
    prof = actuator_profile(s, kappa, cfg, v_start, WHEELBASE, rate)
    v = prof.v
    _assert_bounds(s, v, kappa, cfg.v_max, cfg.a_lat_max, cfg.accel, cfg.decel)
    assert v[-1] == 0.0
    if rate is None or rate == math.inf:
        # An instant actuator: the plain profile, bit for bit.
        assert np.array_equal(v, SpeedProfile(s, kappa, cfg, v_start).v)
        return
    cap = steering_rate_speed_cap(s, kappa, WHEELBASE, rate, cfg.steer_rate_share)
    assert np.all(v <= cap * (1 + 1e-9) + 1e-12)
    assert v[0] <= v_start + 1e-12  # no launch step
    # Never above the plain profile with the same caps and no launch speed.
    plain = SpeedProfile(s, kappa, dataclasses.replace(cfg, v_launch=0.0), v_start, v_cap=cap)
    assert np.all(v <= plain.v + 1e-9)
    final = s > s[-1] - FINAL_APPROACH_M
    if v_start > 0.0 or s[-1] > 4.5:  # short paths from rest rise to their one peak
        assert np.all(np.diff(v[final]) <= 1e-9)
    if v_start == 0.0:
        # Every peak holds for decel / comfort_jerk seconds (v * lag metres).
        lag, eps, i, n = cfg.decel / cfg.comfort_jerk, 1e-9, 1, len(v)
        while i < n - 1:
            j = i
            while j + 1 < n and abs(v[j + 1] - v[i]) <= eps:
                j += 1
            if v[i - 1] < v[i] - eps and j + 1 < n and v[j + 1] < v[i] - eps:
                assert s[j] - s[i] >= v[i] * lag * (1 - 1e-6) - 1e-9, (i, j, v[i])
            i = j + 1


# ----------------------------------------------------------------- the episodes
def _straight(task, length, n=200, y=None):
    st_ = task.start
    d = np.linspace(0.0, length, n)
    y0 = st_.y if y is None else y
    yaw = 0.0 if y is not None else st_.yaw
    rows = np.column_stack([st_.x + d * np.cos(yaw), y0 + d * np.sin(yaw), np.full(n, yaw),
                            np.zeros(n), np.ones(n)])
    return Path(rows, np.zeros((0, 2)))


@pytest.fixture(scope="module")
def episodes():
    out = {}
    for ctrl in ("pure-pursuit", "stanley", "lqr"):
        out[f"overtake-{ctrl}"] = run_episode("overtake", controller=ctrl, seed=0)
    out["parking-stanley"] = run_episode("parking", controller="stanley", seed=1)
    out["overtake-15hz"] = run_episode(
        "overtake", controller="pure-pursuit", seed=2,
        config=EpisodeConfig(sim=SimConfig(simulation_frequency=15)))
    task = make_variant("overtake", 0)
    out["crash"] = run_episode(task, planner=_straight(task, 60.0, y=44.0), seed=0,
                               config=EpisodeConfig(max_time_s=40.0))
    for name, ep in out.items():
        assert ep.path.is_forward_only, name
        assert ep.log.steps > 0, name
    return out


def _wrap(a):
    return (np.asarray(a, dtype=float) + np.pi) % (2 * np.pi) - np.pi


def _tracking(path, states):
    """Signed cross-track and heading errors by shapely projection on the path polyline."""
    rows = np.asarray(path.samples, dtype=float)
    keep = np.concatenate([[True], np.hypot(*np.diff(rows[:, :2], axis=0).T) > 1e-9])
    rows = rows[keep]
    line = shapely.LineString(rows[:, :2])
    pts = shapely.points(states[:, :2])
    s = shapely.line_locate_point(line, pts)
    dist = shapely.distance(line, pts)
    arc = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(rows[:, :2], axis=0).T))])
    j = np.clip(np.searchsorted(arc, s, side="right") - 1, 0, len(rows) - 2)
    frac = np.clip((s - arc[j]) / (arc[j + 1] - arc[j]), 0.0, 1.0)
    foot = rows[j, :2] + frac[:, None] * (rows[j + 1, :2] - rows[j, :2])
    d = rows[j + 1, :2] - rows[j, :2]
    off = states[:, :2] - foot
    left = d[:, 0] * off[:, 1] - d[:, 1] * off[:, 0]
    cte = np.where(left < 0, -dist, dist)
    yaw = np.unwrap(rows[:, 2])
    herr = _wrap(states[:, 2] - (yaw[j] + frac * (yaw[j + 1] - yaw[j])))
    return cte, herr, s


def _nuplan_ref(t, yaw, v, d):
    """docs/metrics.md "Drivability": nuPlan's six figures, at 0.1 s, scipy's savgol."""
    grid = np.arange(int(round(t[-1] / 0.1, 9)) + 1) * 0.1
    if len(grid) < 4:
        return None
    h = np.interp(grid, t, np.unwrap(yaw))
    sp = np.interp(grid, t, v)
    w = np.gradient(h, 0.1)
    w_dot = np.gradient(w, 0.1)
    ax = np.gradient(sp, 0.1)
    ay = sp * w

    def sg(y, win, order, deriv=0):
        return savgol_filter(y, min(win, len(y)), order, deriv=deriv, delta=0.1)

    lon = sg(ax + d * (w**2 + w_dot), 8, 2)
    mag = sg(np.hypot(ax, ay), 8, 2)
    return {
        "lon_accel_min": lon.min(), "lon_accel_max": lon.max(),
        "lat_accel_abs_max": np.abs(sg(ay, 8, 2)).max(),
        "lon_jerk_abs_max": np.abs(sg(lon, 15, 2, 1)).max(),
        "jerk_abs_max": np.abs(sg(mag, 15, 2, 1)).max(),
        "yaw_rate_abs_max": np.abs(sg(h, 5, 2, 1)).max(),
        "yaw_accel_abs_max": np.abs(sg(h, 5, 3, 2)).max(),
    }


def _body(states, vehicle):
    """Body rectangles of rear-axle poses as shapely polygons."""
    rear = (vehicle.length - vehicle.wheelbase) / 2.0
    lon = np.array([-rear, vehicle.length - rear, vehicle.length - rear, -rear])
    lat = np.array([-1, -1, 1, 1]) * vehicle.width / 2.0
    c, s = np.cos(states[:, 2])[:, None], np.sin(states[:, 2])[:, None]
    x = states[:, 0][:, None] + c * lon - s * lat
    y = states[:, 1][:, None] + s * lon + c * lat
    return shapely.polygons(np.stack([x, y], axis=-1))


def _others(log, k):
    o = log.others[:, k, :]
    length, width = log.other_sizes[k]
    hl, hw = length / 2.0, width / 2.0
    c, s = np.cos(o[:, 2])[:, None], np.sin(o[:, 2])[:, None]
    lon, lat = np.array([-hl, hl, hl, -hl]), np.array([-hw, -hw, hw, hw])
    x = o[:, 0][:, None] + c * lon - s * lat
    y = o[:, 1][:, None] + s * lon + c * lat
    return shapely.polygons(np.stack([x, y], axis=-1))


def _close(got, want, rel=1e-9, abs_=1e-9):
    assert got is not None
    assert math.isclose(float(got), float(want), rel_tol=rel, abs_tol=abs_), (got, want)


EPISODE_KEYS = ["overtake-pure-pursuit", "overtake-stanley", "overtake-lqr", "parking-stanley",
                "overtake-15hz", "crash"]


@pytest.mark.parametrize("key", EPISODE_KEYS)
def test_forward_episode_metrics_recomputed(episodes, key):
    ep = episodes[key]
    r = evaluate(ep)
    log, veh = ep.log, ep.scenario.vehicle
    st_, ctl, dt = log.states, log.controls, log.dt
    n = log.steps
    assert st_.shape == (n + 1, 4) and ctl.shape == (n, 2)
    # Time.
    _close(r.duration_s, log.t[-1])
    np.testing.assert_allclose(log.t, np.arange(n + 1) * dt, atol=1e-9)
    assert r.steps == n
    _close(r.simulation_frequency, 1.0 / dt)
    _close(r.final_speed, st_[-1, 3])
    # Tracking: every logged time k = 0..N, rear axle against the polyline.
    cte, herr, s_foot = _tracking(ep.path, st_)
    _close(r.cte_rms_m, np.sqrt(np.mean(cte**2)), rel=1e-7, abs_=1e-9)
    _close(r.cte_max_m, np.max(np.abs(cte)), rel=1e-7, abs_=1e-9)
    _close(r.heading_err_rms_rad, np.sqrt(np.mean(herr**2)), rel=1e-7, abs_=1e-9)
    _close(r.heading_err_max_rad, np.max(np.abs(herr)), rel=1e-7, abs_=1e-9)
    _close(r.progress_m, s_foot[-1] - s_foot[0], rel=1e-7, abs_=1e-7)
    rows = np.asarray(ep.path.samples)
    _close(r.path_length_m, np.sum(np.hypot(*np.diff(rows[:, :2], axis=0).T)))
    _close(r.path_max_curvature, np.max(np.abs(rows[:, 3])))
    assert r.path_cusps == 0 and r.gear_changes == 0
    # Curvature and comfort from the applied commands.
    kappa = np.tan(ctl[:, 1]) / veh.wheelbase
    _close(r.executed_max_curvature, np.max(np.abs(kappa)))
    _close(r.executed_curvature_violation_share,
           np.mean(np.abs(kappa) > veh.kappa_max * (1 + 1e-9)))
    lat = st_[:-1, 3] ** 2 * kappa  # the speed at the start of each step
    _close(r.max_lateral_accel, np.max(np.abs(lat)))
    _close(r.max_long_accel, np.max(np.abs(ctl[:, 0])))
    if n > 1:
        _close(r.max_jerk, np.max(np.hypot(np.diff(ctl[:, 0]), np.diff(lat)) / dt))
    rate = np.abs(np.diff(np.concatenate([[0.0], ctl[:, 1]]))) / dt
    _close(r.max_steering_rate, np.max(rate))
    _close(r.steering_rate_over_limit_share, np.mean(rate > 0.4 + 1e-9))
    ds = np.hypot(*np.diff(rows[:, :2], axis=0).T)
    dd = np.abs(np.diff(np.arctan(veh.wheelbase * rows[:, 3])))
    _close(r.path_max_sharpness, np.max(dd[ds > 1e-9] / ds[ds > 1e-9]))
    # nuPlan's figures.
    ref = _nuplan_ref(log.t, st_[:, 2], st_[:, 3], veh.length / 2 - (veh.length -
                                                                    veh.wheelbase) / 2)
    for name, want in ref.items():
        _close(getattr(r, f"nuplan_{name}"), want, rel=1e-6, abs_=1e-8)
    b = COMFORT_BOUNDS
    assert r.nuplan_comfortable == bool(
        ref["lon_accel_min"] >= b["min_lon_accel"] and ref["lon_accel_max"] <= b["max_lon_accel"]
        and ref["lat_accel_abs_max"] <= b["max_abs_lat_accel"]
        and ref["lon_jerk_abs_max"] <= b["max_abs_lon_jerk"]
        and ref["jerk_abs_max"] <= b["max_abs_jerk"]
        and ref["yaw_rate_abs_max"] <= b["max_abs_yaw_rate"]
        and ref["yaw_accel_abs_max"] <= b["max_abs_yaw_accel"])
    # Goal terms.
    goal = ep.scenario.goal
    pos = math.hypot(st_[-1, 0] - goal.x, st_[-1, 1] - goal.y)
    head = abs(float(_wrap(st_[-1, 2] - goal.yaw)))
    _close(r.goal_position_err_m, pos)
    _close(r.goal_heading_err_rad, head)
    assert r.stopped == (abs(st_[-1, 3]) <= 0.1)
    if ep.scenario.name == "parking":
        assert r.reached_goal == (pos <= 0.5 and head <= math.radians(10))
    # Collisions with shapely: the map (densified 0.1 m) and the logged vehicles.
    dense = _densify(st_[:, :3], 0.1)
    body = _body(dense, veh)
    m = ep.scenario.map
    obst = [shapely.polygons(_obstacle_corners(o)) for o in m.obstacles]
    x0, y0, x1, y1 = m.bounds
    inside = shapely.box(x0, y0, x1, y1)
    map_hit = bool(np.any([np.any(shapely.intersects(body, o)) for o in obst])) or not bool(
        np.all(shapely.covers(inside, body)))
    hits = []
    dmin = math.inf
    ego = _body(st_, veh)
    for k in range(log.others.shape[1] if log.others.size else 0):
        theirs = _others(log, k)
        inter = shapely.intersects(ego, theirs)
        if inter.any():
            hits.append((int(np.argmax(inter)), k))
        dmin = min(dmin, float(np.min(shapely.distance(ego, theirs))))
    assert r.collision_footprint == (map_hit or bool(hits))
    assert r.collision_highway_env == bool(np.any(log.crashed))
    assert r.collision == (r.collision_footprint or r.collision_highway_env)
    assert r.collisions_vehicles == len(hits)
    if log.others.size:
        _close(r.min_distance_m, dmin, rel=1e-9, abs_=1e-9)
    # Success and outcome.
    success = (r.reached_goal and r.stopped and ep.status == "arrived" and not r.collision
               and (ep.scenario.name != "overtake" or (r.passed_lead and r.back_in_lane)))
    assert r.success == success
    want = (Outcome.SUCCESS if success else Outcome.COLLISION if r.collision else Outcome.FAILED)
    assert r.outcome == want
    assert (r.time_to_goal_s is not None) == success
    if key == "crash":
        assert ep.status == "crashed" and hits and not success
        assert r.outcome == Outcome.COLLISION and r.min_distance_m == 0.0
        # The stopped car was hit by a moving ego: "stopped track", at fault, counted once
        # (it is also a map obstacle).
        assert abs(log.others[hits[0][0], hits[0][1], 3]) <= 0.05
        assert r.collisions_at_fault == 1
    else:
        assert r.success, (key, r.outcome)


def _densify(poses, spacing):
    out = [poses[:1]]
    for a, b in zip(poses[:-1], poses[1:], strict=True):
        pieces = max(1, math.ceil(math.hypot(*(b[:2] - a[:2])) / spacing - 1e-9))
        f = np.arange(1, pieces + 1)[:, None] / pieces
        d = b - a
        d[2] = _wrap(d[2])
        out.append(a + f * d)
    return np.vstack(out)


def _obstacle_corners(o):
    hl, hw = o.size[0] / 2.0, o.size[1] / 2.0
    c, s = math.cos(o.yaw), math.sin(o.yaw)
    lon, lat = np.array([-hl, hl, hl, -hl]), np.array([-hw, -hw, hw, hw])
    return np.stack([o.center[0] + c * lon - s * lat, o.center[1] + s * lon + c * lat], axis=-1)


def test_profile_the_controllers_drove_obeys_its_limits(episodes):
    """The reference speed of a forward path from the car's own start (the default car)."""
    ep = episodes["overtake-pure-pursuit"]
    rows = np.asarray(ep.path.samples)
    s = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(rows[:, :2], axis=0).T))])
    speed = ep.scenario.resolve(EpisodeConfig())[0]  # the scenario's speed settings
    prof = actuator_profile(s, rows[:, 3], speed, 0.0, ep.scenario.vehicle.wheelbase,
                            ep.scenario.vehicle.max_steer_rate)
    _assert_bounds(s, prof.v, rows[:, 3], speed.v_max, speed.a_lat_max, speed.accel, speed.decel)
    # The car's speed never runs far past the profile's top (the PI loop's overshoot).
    assert np.max(ep.log.states[:, 3]) <= 1.1 * np.max(prof.v)


def test_sign_conventions_on_a_westbound_path():
    """Left of the direction of travel is positive; yaw minus path yaw, in [-pi, pi)."""
    xs = np.linspace(10.0, 0.0, 11)
    path = Path(np.column_stack([xs, 0 * xs, np.full(11, np.pi), 0 * xs]), np.zeros((0, 2)))
    poses = np.array([[5.0, -0.3, np.pi + 0.1], [5.0, 0.2, 0.0], [2.5, 0.0, np.pi - 0.2]])
    cte, herr = tracking_errors(path, poses)
    np.testing.assert_allclose(cte, [0.3, -0.2, 0.0], atol=1e-12)
    np.testing.assert_allclose(herr, [0.1, -np.pi, -0.2], atol=1e-12)
    ref_cte, ref_herr, _ = _tracking(path, poses)
    np.testing.assert_allclose(cte, ref_cte, atol=1e-12)
    np.testing.assert_allclose(herr, ref_herr, atol=1e-12)


# --------------------------------------------------------------- logs built by hand
def _replaced(ep, states, controls, status="timeout"):
    n = len(controls)
    log = dataclasses.replace(
        ep.log, t=np.arange(n + 1) * ep.log.dt, states=states, controls=controls,
        crashed=np.zeros(n + 1, dtype=bool),
        others=np.repeat(ep.log.others[:1], n + 1, axis=0), arrived=False)
    return dataclasses.replace(ep, log=log, status=status)


def test_stationary_episode(episodes):
    ep = episodes["overtake-lqr"]
    n = 40
    start = ep.log.states[0].copy()
    # 0.4 m to the left of the start (the path begins at the start pose), turned 0.05 rad.
    yaw = float(ep.path.samples[0, 2])
    start[:4] = start[0] - 0.4 * math.sin(yaw), start[1] + 0.4 * math.cos(yaw), yaw + 0.05, 0
    r = evaluate(_replaced(ep, np.repeat(start[None], n + 1, axis=0), np.zeros((n, 2))))
    cte, herr, _ = _tracking(ep.path, start[None])
    assert cte[0] == pytest.approx(0.4, abs=1e-3) and herr[0] == pytest.approx(0.05, abs=1e-3)
    _close(r.cte_rms_m, abs(cte[0]), rel=1e-7)
    _close(r.cte_max_m, abs(cte[0]), rel=1e-7)
    _close(r.heading_err_rms_rad, abs(herr[0]), rel=1e-7)
    _close(r.heading_err_max_rad, abs(herr[0]), rel=1e-7)
    assert tracking_errors(ep.path, start[None, :3])[0][0] > 0  # left is positive
    assert r.progress_m == 0.0 and r.final_speed == 0.0 and r.gear_changes == 0
    for name in ("max_lateral_accel", "max_long_accel", "max_jerk", "max_steering_rate",
                 "executed_max_curvature", "steering_rate_over_limit_share"):
        assert getattr(r, name) == 0.0, name
    for name in ("nuplan_lon_accel_min", "nuplan_lon_accel_max", "nuplan_lat_accel_abs_max",
                 "nuplan_lon_jerk_abs_max", "nuplan_jerk_abs_max", "nuplan_yaw_rate_abs_max",
                 "nuplan_yaw_accel_abs_max"):
        assert abs(getattr(r, name)) <= 1e-12, name
    assert r.nuplan_comfortable is True
    assert r.stopped and not r.reached_goal and not r.success and r.outcome == Outcome.FAILED
    assert not r.collision and r.collisions_vehicles == 0
    _close(r.duration_s, n * ep.log.dt)


def test_one_step_drive_has_no_jerk_and_no_nuplan_figures(episodes):
    ep = episodes["overtake-lqr"]
    r = evaluate(_replaced(ep, ep.log.states[:2].copy(), ep.log.controls[:1].copy()))
    assert r.steps == 1 and r.max_jerk is None and r.nuplan_comfortable is None
    assert r.nuplan_lon_accel_max is None


@pytest.mark.parametrize("steps, has", [(5, False), (6, True)])
def test_nuplan_figures_start_at_0_3_s(episodes, steps, has):
    """docs: "A drive under 0.3 s (fewer than four samples at 0.1 s) has no figures"."""
    ep = episodes["overtake-lqr"]
    r = evaluate(_replaced(ep, ep.log.states[: steps + 1].copy(),
                           ep.log.controls[:steps].copy()))
    assert (r.nuplan_comfortable is not None) == has


def test_nuplan_comfort_on_a_circle():
    """R = 6 m at 3 m/s: yaw rate v / R, lateral v^2 / R, nuPlan's shifted x: d w^2."""
    t = np.arange(0.0, 10.0, 0.05)
    c = nuplan_comfort(t, 0.5 * t, np.full_like(t, 3.0), 1.255)
    _close(c.yaw_rate_abs_max, 0.5, rel=1e-9)
    _close(c.lat_accel_abs_max, 1.5, rel=1e-9)
    _close(c.lon_accel_max, 1.255 * 0.25, rel=1e-9)
    _close(c.lon_accel_min, 1.255 * 0.25, rel=1e-9)
    assert c.yaw_accel_abs_max < 1e-9 and c.comfortable


@pytest.mark.parametrize("key", ["overtake-lqr", "parking-stanley"])
@pytest.mark.parametrize("column", [0, 3])
def test_nan_in_a_log_is_one_clear_error(episodes, key, column):
    ep = episodes[key]
    states = ep.log.states.copy()
    states[3, column] = np.nan
    with pytest.raises(InputError, match="nan|NaN|finite"):
        evaluate(_replaced(ep, states, ep.log.controls.copy()))


def test_short_paths_end_before_driving():
    task = make_variant("overtake", 0)
    for path in (Path.empty(), Path(_straight(task, 5.0).samples[:1], np.zeros((0, 2)))):
        ep = run_episode(task, planner=path, seed=0)
        r = evaluate(ep)
        assert ep.status == "plan_failed" and r.steps == 0
        assert ep.message == "the path has fewer than two samples"
        for name in ("cte_rms_m", "cte_max_m", "heading_err_rms_rad", "progress_m",
                     "max_jerk", "nuplan_comfortable", "final_speed"):
            assert getattr(r, name) is None, name
        assert not r.success and r.outcome == Outcome.FAILED and r.collision is False


# ----------------------------------------------------------------------- summary
def test_summary_recomputed(episodes):
    task = make_variant("overtake", 0)
    failed = run_episode(task, planner=Path.empty(), seed=0)
    reports = [evaluate(e) for e in episodes.values()] + [evaluate(failed)]
    out = summarise(reports)
    n = len(reports)
    k = sum(r.success for r in reports)
    assert out["episodes"] == n and out["success_rate"] == k / n
    ci = binomtest(k, n).proportion_ci(confidence_level=0.95, method="wilson")
    assert out["success_rate_ci95"] == pytest.approx([ci.low, ci.high], abs=1e-12)
    assert out["plan_failures"] == 1
    assert out["collisions_highway_env"] == sum(r.collision_highway_env for r in reports)
    assert out["collisions_at_fault"] == sum(r.collisions_at_fault for r in reports)
    assert sum(out["outcomes"].values()) == n
    drove = [r for r in reports if r.steps > 0]
    for key in MEAN_FIELDS:
        pool = reports if key == "planning_time_s" else drove
        vals = [float(getattr(r, key)) for r in pool if getattr(r, key) is not None]
        if not vals:
            assert out[f"{key}_mean"] is None
            continue
        assert out[f"{key}_mean"] == pytest.approx(np.mean(vals), rel=1e-12), key
        assert out[f"{key}_max"] == pytest.approx(np.max(vals), rel=1e-12), key
        lo, hi = out[f"{key}_ci95"]
        if key not in SIGNED_FIELDS:  # a bootstrap: within the sample's range
            assert min(vals) - 1e-12 <= lo <= hi <= max(vals) + 1e-12, key
    # The failed plan's 0 s is no drive.
    assert out["duration_s_mean"] == pytest.approx(np.mean([r.duration_s for r in drove]))


# ------------------------------------------------------------------ docs vs code
def test_metrics_doc_agrees_with_the_code():
    doc = DOCS.read_text()
    # nuPlan's bounds as documented in the table.
    for text, key in (("[−4.05, 2.40]", ("min_lon_accel", "max_lon_accel")),
                      ("≤ 4.89 m/s²", ("max_abs_lat_accel",)),
                      ("≤ 4.13 m/s³", ("max_abs_lon_jerk",)),
                      ("≤ 8.37 m/s³", ("max_abs_jerk",)), ("≤ 0.95 rad/s", ("max_abs_yaw_rate",)),
                      ("≤ 1.93 rad/s²", ("max_abs_yaw_accel",))):
        assert text in doc, text
        nums = [float(x) for x in re.findall(r"\d+\.\d+", text)]
        assert sorted(abs(COMFORT_BOUNDS[k]) for k in key) == sorted(nums)
    cfg = EvalConfig()
    assert "**0.5 m**" in doc and cfg.goal_tol_m == 0.5
    assert "**10°**" in doc and math.isclose(cfg.goal_tol_rad, math.radians(10))
    assert "≤ 0.1 m/s" in doc and cfg.stop_speed == 0.1
    assert "0.4 rad/s at the front" in doc and cfg.steer_rate_limit == 0.4
    assert "at most 0.1 m" in doc and cfg.footprint_spacing == 0.1
    # The signed fields the doc lists are the code's.
    listed = re.search(r"Student's t\s+for the fields that can be negative \(([^)]*)\)", doc)
    assert listed is not None
    assert set(re.findall(r"`(\w+)`", listed.group(1))) == set(SIGNED_FIELDS)
    # Every report field is named in the doc.
    fields = [f.name for f in dataclasses.fields(EpisodeReport)]
    assert [f for f in fields if not re.search(rf"\b{f}\b", doc)] == []


def test_speed_profile_docs_agree_with_the_defaults():
    doc = DOCS.read_text()
    loop = (DOCS.parent / "closed_loop.md").read_text()
    cfg = SpeedConfig()
    assert "sqrt(1.5 m/s² / |κ(s)|)), ±1 m/s² ramps" in loop
    assert cfg.a_lat_max == 1.5 and cfg.accel == 1.0 and cfg.decel == 1.0
    assert "(share 0.7" in doc and cfg.steer_rate_share == 0.7
    assert "`comfort_jerk` (2 m/s³)" in doc and cfg.comfort_jerk == 2.0
    assert "does not rise again on the final 2 m" in doc and FINAL_APPROACH_M == 2.0
    veh = make_variant("overtake", 0).vehicle
    assert "≈ 22.7°" in doc
    assert round(math.degrees(math.atan(veh.wheelbase * veh.kappa_max)), 1) == 22.7


def test_a_nan_arc_length_read_from_a_profile_is_one_clear_error():
    prof = SpeedProfile(np.linspace(0.0, 5.0, 6), np.zeros(6), SpeedConfig())
    with pytest.raises(InputError, match="^s: "):
        prof.at(float("nan"))
