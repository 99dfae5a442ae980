"""The speed profile v(s) along a path, and the arrival times it gives.

The rules, in one place: ``v(s) <= v_max``, ``v(s) <= sqrt(a_lat_max / |kappa(s)|)``
(the lateral-acceleration cap), the first sample no faster than
``max(v_start, v_launch)``, rising at most ``accel`` and falling at most ``decel``
over arc length (forward and backward passes on ``v^2``), and optionally a stop
at the end. A car with a rate-limited steering actuator adds a per-sample cap
(:func:`steering_rate_speed_cap`): ``v(s) <= share * max_steer_rate / |d delta/ds|(s)``,
so the steering angle the path asks for (``delta = atan(L kappa)``) changes no faster
than the actuator can turn the wheels. Arrival times integrate ``ds / v`` with the
mean speed of each interval.

Two users: the controllers track :class:`SpeedProfile` (which stops at the end of
its path), and space-time planning times whole paths with :func:`profile_times`
(the path goes on past its last sample, so no stop). Both start from the same
caps (:func:`speed_caps_squared`). Their passes are still two arithmetic forms of
the same recurrence: the controller's a loop over ``v``, the planner's a closed
form over ``v^2`` (``v_i^2 = 2 a s_i + cummin_j(cap_j^2 - 2 a s_j)``, fifty to a
hundred times faster on long paths). They agree to rounding (about 1e-14 m/s), not
bit for bit, so one cannot replace the other without changing recorded
behaviour; the choice is left to a deliberate, behaviour-changing change.
"""

from __future__ import annotations

import bisect
import dataclasses
import math
from typing import Protocol

import numpy as np

from rrtdrive.speed_peaks import last_rise_level, peak_with_plateau, plateau_caps
from rrtdrive.steering_sharpness import (
    SHARPNESS_WINDOW_M,
    steering_rate_speed_cap,
    steering_sharpness,
)
from rrtdrive.types import InputError
from rrtdrive.values import brief_repr, is_finite_number

__all__ = [
    "SpeedLimits",
    "speed_caps_squared",
    "SHARPNESS_WINDOW_M",
    "steering_sharpness",
    "steering_rate_speed_cap",
    "SpeedProfile",
    "RateLimitedLimits",
    "actuator_profile",
    "checked_samples",
    "peak_with_plateau",
    "plateau_caps",
    "FINAL_APPROACH_M",
    "profile_times",
    "arrival_times",
]

#: The final approach: within this distance of the path's end the speed loop brings
#: the car to its stop (the taper, or the constant deceleration), and a rate-limited
#: car's profile does not speed up again (:func:`actuator_profile`).
FINAL_APPROACH_M = 2.0


class SpeedLimits(Protocol):
    """The limits a speed profile obeys (``rrtdrive.controllers.SpeedConfig`` has them)."""

    @property
    def v_max(self) -> float:
        """Speed cap in m/s."""
        ...

    @property
    def a_lat_max(self) -> float:
        """Lateral-acceleration cap in m/s^2."""
        ...

    @property
    def accel(self) -> float:
        """Largest acceleration along the path in m/s^2."""
        ...

    @property
    def decel(self) -> float:
        """Largest deceleration along the path in m/s^2 (positive)."""
        ...

    @property
    def v_launch(self) -> float:
        """Speed the profile starts from when the car is at rest, m/s."""
        ...


def speed_caps_squared(
    kappa: np.ndarray, v_max: float, a_lat_max: float, v_first: float
) -> np.ndarray:
    """Squared speed caps: ``min(a_lat_max / |kappa|, v_max^2)``, the first also ``v_first^2``.

    Parameters
    ----------
    kappa : numpy.ndarray
        Path curvature at the samples (1/m, any sign).
    v_max, a_lat_max : float
        Speed cap (m/s) and lateral-acceleration cap (m/s^2).
    v_first : float
        Cap of the first sample (m/s): ``max(v_start, v_launch)``.

    Returns
    -------
    numpy.ndarray
        ``(N,)`` caps on ``v^2`` in m^2/s^2 (a new array).

    Examples
    --------
    >>> speed_caps_squared(np.array([0.0, 0.5, 0.0]), 3.0, 2.0, 1.0).tolist()
    [1.0, 4.0, 9.0]
    """
    k = np.abs(np.asarray(kappa, dtype=float))
    with np.errstate(divide="ignore"):
        cap2 = np.minimum(a_lat_max / np.maximum(k, 1e-12), v_max * v_max)
    cap2[0] = min(cap2[0], v_first**2)
    return cap2


def arrival_times(s: np.ndarray, v: np.ndarray, v_floor: float = 0.05) -> np.ndarray:
    """Arrival time at each sample (0 at the first) driving speeds ``v`` at arc lengths ``s``.

    Each interval is driven at the mean of its end speeds, at least ``v_floor`` m/s
    (so a stop does not take forever).

    Parameters
    ----------
    s, v : numpy.ndarray
        ``(N,)`` arc lengths (metres, increasing) and speeds (m/s) of the samples.
    v_floor : float
        Lowest speed an interval is driven at, m/s.

    Returns
    -------
    numpy.ndarray
        ``(N,)`` arrival times in seconds.

    Examples
    --------
    >>> arrival_times(np.array([0.0, 1.0, 3.0]), np.array([1.0, 1.0, 3.0])).tolist()
    [0.0, 1.0, 2.0]
    """
    s = np.asarray(s, dtype=float)
    v = np.asarray(v, dtype=float)
    mean = np.maximum(0.5 * (v[1:] + v[:-1]), v_floor)
    return np.concatenate([[0.0], np.cumsum(np.diff(s) / mean)])


def checked_samples(
    s: np.ndarray, kappa: np.ndarray, v_start: float, v_cap: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """``s`` and ``kappa`` as float arrays, or one :class:`InputError` naming what is wrong.

    A profile needs one sample at least, finite values and arc lengths that never
    decrease (a cusp's repeated row is a zero-length interval): an empty path raised
    numpy's IndexError, and a NaN speed or arc length gave a profile that started at
    ``v_max`` or jumped past the acceleration limit without a word (an audit).

    Parameters
    ----------
    s, kappa : numpy.ndarray
        Arc length and curvature of the samples.
    v_start : float
        Speed at the first sample, m/s.
    v_cap : numpy.ndarray, optional
        Further per-sample caps, m/s (``inf``: none there).

    Returns
    -------
    s, kappa : numpy.ndarray

    Raises
    ------
    InputError
        Naming the argument that is empty, not finite, decreasing or mis-shaped.

    Examples
    --------
    >>> checked_samples(np.array([0.0, 1.0]), np.array([0.1, 0.0]), 0.0)[0].tolist()
    [0.0, 1.0]
    """
    s = np.asarray(s, dtype=float)
    kappa = np.asarray(kappa, dtype=float)
    if s.ndim != 1 or kappa.shape != s.shape or len(s) == 0:
        raise InputError(
            f"s, kappa: expected two 1-D arrays of the same length, one sample at least; got "
            f"shapes {s.shape} and {kappa.shape}"
        )
    for name, values in (("s", s), ("kappa", kappa)):
        if not np.isfinite(values).all():
            raise InputError(f"{name}: expected finite numbers, got {brief_repr(values)}")
    if (np.diff(s) < 0.0).any():
        raise InputError(f"s: arc lengths must not decrease, got {brief_repr(s)}")
    if not is_finite_number(v_start):  # a car rolling back a hair below 0 is no error
        raise InputError(f"v_start: expected a finite speed in m/s, got {v_start!r}")
    if v_cap is not None:
        cap = np.asarray(v_cap, dtype=float)
        if cap.shape != s.shape or np.isnan(cap).any() or (cap < 0.0).any():  # inf: none
            raise InputError(f"v_cap: expected {len(s)} speeds >= 0 m/s, got {brief_repr(cap)}")
    return s, kappa


def profile_times(
    s: np.ndarray,
    kappa: np.ndarray,
    v0: float,
    v_max: float,
    accel: float,
    decel: float,
    a_lat_max: float,
    v_launch: float = 0.5,
    v_cap: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Speeds and arrival times along a path from the speed-profile rules, without a final stop.

    The same rules as :class:`SpeedProfile` (``v <= v_max``,
    ``v <= sqrt(a_lat_max / |kappa|)``, rising at most ``accel``, falling at most
    ``decel``, starting from ``max(v0, v_launch)``), for a path that goes on past
    its last sample, computed in closed form: the forward pass
    ``v_i^2 = min(cap_i^2, v_{i-1}^2 + 2 a ds)`` is ``2 a s_i + cummin(cap_j^2 - 2 a s_j)``.

    Parameters
    ----------
    s : numpy.ndarray
        Arc length of the samples, increasing from 0.
    kappa : numpy.ndarray
        Curvature at the samples.
    v0, v_max, accel, decel, a_lat_max, v_launch : float
        Start speed and profile limits.
    v_cap : numpy.ndarray, optional
        Further per-sample speed caps in m/s, as for :class:`SpeedProfile` (for
        example :func:`steering_rate_speed_cap`: the path timed as a car with a
        rate-limited steering actuator drives it); ``None``: none.

    Returns
    -------
    t, v : numpy.ndarray
        Arrival time (0 at the first sample) and speed at each sample.

    Examples
    --------
    >>> s = np.linspace(0.0, 8.0, 81)
    >>> t, v = profile_times(s, 0 * s, 0.0, 10.0, 1.0, 1.0, 1.5, v_launch=0.0)
    >>> round(float(t[-1]), 3), round(float(v[-1]), 3)  # 8 m from rest at 1 m/s^2
    (4.0, 4.0)
    """
    s, kappa = checked_samples(s, kappa, v0, v_cap)
    cap2 = speed_caps_squared(kappa, v_max, a_lat_max, max(v0, v_launch))
    if v_cap is not None:
        cap2 = np.minimum(cap2, np.square(np.asarray(v_cap, dtype=float)))
    v2 = 2.0 * accel * s + np.minimum.accumulate(cap2 - 2.0 * accel * s)
    back = (v2 + 2.0 * decel * s)[::-1]
    v2 = np.minimum(v2, np.minimum.accumulate(back)[::-1] - 2.0 * decel * s)
    v = np.sqrt(np.maximum(v2, 0.0))
    return arrival_times(s, v), v


class SpeedProfile:
    """The admissible speed along a path, sampled at its arc lengths, stopping at its end.

    Parameters
    ----------
    s : numpy.ndarray
        Cumulative arc length of the samples (increasing, starting at 0).
    kappa : numpy.ndarray
        Path curvature at the samples.
    config : SpeedLimits
        Limits (for example ``rrtdrive.controllers.SpeedConfig``).
    v_start : float
        Speed at the start of the path.
    v_cap : numpy.ndarray, optional
        Further per-sample speed caps in m/s (for example
        :func:`steering_rate_speed_cap`); ``None``: none.

    Examples
    --------
    >>> from rrtdrive.controllers import SpeedConfig
    >>> s = np.linspace(0.0, 20.0, 81)
    >>> prof = SpeedProfile(s, np.zeros_like(s), SpeedConfig(v_max=3.0), v_start=0.0)
    >>> float(prof.v[-1]), bool(prof.v.max() <= 3.0)
    (0.0, True)
    """

    def __init__(
        self,
        s: np.ndarray,
        kappa: np.ndarray,
        config: SpeedLimits,
        v_start: float = 0.0,
        v_cap: np.ndarray | None = None,
    ) -> None:
        s, kappa = checked_samples(s, kappa, v_start, v_cap)
        kappa = np.abs(kappa)
        with np.errstate(divide="ignore"):
            v_curve = np.sqrt(config.a_lat_max / np.maximum(kappa, 1e-12))
        # The square root of the shared caps is min(v_curve, v_max) bit for bit (sqrt is
        # monotone and correctly rounded, and sqrt(v*v) == v); the first sample's cap is
        # applied on v, as the controllers always had it.
        v = np.sqrt(speed_caps_squared(kappa, config.v_max, config.a_lat_max, math.inf))
        if v_cap is not None:
            v = np.minimum(v, np.asarray(v_cap, dtype=float))
        v[0] = min(v[0], max(v_start, config.v_launch))
        ds = np.diff(s)
        v = np.array(_accel_decel_passes(v.tolist(), ds.tolist(), config.accel, config.decel))
        self.s = s
        self.v = v
        self.v_curve = v_curve
        # Profile acceleration dv/dt = d(v^2/2)/ds on each interval.
        with np.errstate(divide="ignore", invalid="ignore"):
            a = np.where(ds > 0, np.diff(v**2) / (2.0 * np.maximum(ds, 1e-12)), 0.0)
        self.a = np.append(a, 0.0)
        self._s = s.tolist()
        self._v = v.tolist()
        self._a = self.a.tolist()
        self.length = float(s[-1])
        self.config = config

    def at(self, s: float) -> tuple[float, float]:
        """``(v_ref, a_ref)`` at arc length ``s`` (0 speed past the end).

        Parameters
        ----------
        s : float
            Arc length, metres (before 0: the first sample's values).

        Returns
        -------
        v_ref, a_ref : float
            Speed in m/s (``v^2`` linear between samples), the interval's acceleration in m/s^2.
        """
        if s != s:  # NaN: every comparison below is false, and the index ran past the end
            raise InputError("s: expected an arc length in metres, got nan")
        if s >= self.length:
            return 0.0, 0.0
        if s <= 0.0:
            return self._v[0], self._a[0]
        i = bisect.bisect_right(self._s, s) - 1
        frac = (s - self._s[i]) / (self._s[i + 1] - self._s[i])
        # v^2 is linear in s on an interval of constant acceleration (the interval's
        # a_ref): v itself linear made the last interval's v_ref proportional to the
        # distance left, an exponential crawl to the stop (0.5 s time constant at 0.25 m).
        v0, v1 = self._v[i], self._v[i + 1]
        return math.sqrt(v0 * v0 + frac * (v1 * v1 - v0 * v0)), self._a[i]

    def peak(self, s0: float, s1: float) -> float:
        """The highest reference speed on the stretch ``[s0, s1]`` of arc length.

        Parameters
        ----------
        s0, s1 : float
            Ends of the stretch, metres (``s0 <= s1``).

        Returns
        -------
        float
            Speed in m/s: the larger of :meth:`at` at both ends and the samples between.
        """
        top = max(self.at(s0)[0], self.at(s1)[0])
        i = bisect.bisect_right(self._s, s0)
        j = bisect.bisect_left(self._s, s1)
        if i < j:
            top = max(top, max(self._v[i:j]))
        return top

    def times(self) -> np.ndarray:
        """Arrival time at each sample (0 at the first; see :func:`arrival_times`)."""
        return arrival_times(self.s, self.v)


def _accel_decel_passes(
    v: list[float], ds: list[float], accel: float, decel: float
) -> list[float]:
    """Lower ``v`` (in place) to what ``accel`` from the start and ``decel`` into a stop allow.

    The two passes run on Python floats (on numpy scalars they were 5.8x slower, a
    large share of the traffic re-planner's time), the same arithmetic bit for bit.
    """
    two_a, two_d = 2.0 * accel, 2.0 * decel
    sqrt = math.sqrt
    prev = v[0]
    for i in range(1, len(v)):
        reach = sqrt(prev**2 + two_a * ds[i - 1])  # ** as before: pow() is not x * x
        prev = v[i] = reach if reach < v[i] else v[i]  # min(v[i], reach)
    v[-1] = 0.0
    nxt = 0.0
    for i in range(len(v) - 2, -1, -1):
        reach = sqrt(nxt**2 + two_d * ds[i])
        nxt = v[i] = reach if reach < v[i] else v[i]
    return v


class RateLimitedLimits(SpeedLimits, Protocol):
    """:class:`SpeedLimits` plus the share of the steering rate the path may use."""

    @property
    def steer_rate_share(self) -> float:
        """Share of ``max_steer_rate`` the path's own steering may use, in ``(0, 1]``."""
        ...

    @property
    def comfort_jerk(self) -> float:
        """Largest rise and fall of the comfort-mode acceleration command, m/s^3."""
        ...


def actuator_profile(
    s: np.ndarray,
    kappa: np.ndarray,
    config: RateLimitedLimits,
    v_start: float,
    wheelbase: float,
    max_steer_rate: float | None,
    rise_to_peak: bool = False,
) -> SpeedProfile:
    """The speed profile the controllers drive along a path, for the car's steering actuator.

    The one function for everything that times a path as the car will drive it (the
    tracking controllers, the oncoming-traffic gate, the traffic re-planner's checks).
    With an instant actuator (``max_steer_rate`` ``None`` or ``inf``) it is the plain
    :class:`SpeedProfile`. With a rate-limited one it is also capped by the steering
    rate (:func:`steering_rate_speed_cap` with ``config.steer_rate_share``), starts
    from the car's own speed (no launch speed: the comfort-mode loop would answer a
    launch step with an overshoot of its jerk-limited command), and does not speed up
    again within :data:`FINAL_APPROACH_M` of the end. A speed-up after the last slow
    stretch that would be followed at once by the final braking is lowered until it
    ends in a plateau of ``(accel + decel) / comfort_jerk`` seconds
    (:func:`rrtdrive.speed_peaks.last_rise_level`; held at the slow stretch's speed when
    no such plateau fits): without one the comfort-mode loop could not turn the rise
    back into the stop within its jerk bound, and would overshoot the goal. Every peak
    of a profile from rest is then given a plateau of ``decel / comfort_jerk`` seconds
    (:func:`plateau_caps`): the time the command needs to swing from holding the speed
    to braking (a manoeuvre's gear segment has its own, :func:`peak_with_plateau`);
    without one, a peak just before a curvature step of a given path was overrun (a 5 m
    straight before a step to 1/6 1/m: the car braked at -2.2 m/s^2 and stood still
    before the step). A car already moving (the traffic re-planner's stitched plans)
    gets it on its last peak only: re-planning every few steps, it would lower the
    peak ahead at every re-plan (all nine overtake-traffic episodes of a trial took
    0.1-3 s longer). Space-time planning times paths without such caps.

    Parameters
    ----------
    s, kappa : numpy.ndarray
        Arc length (increasing from 0) and curvature of the path's samples.
    config : RateLimitedLimits
        The speed settings (``rrtdrive.controllers.SpeedConfig``).
    v_start : float
        Speed at the start of the path, m/s.
    wheelbase : float
        ``L`` in metres.
    max_steer_rate : float or None
        The actuator's rate limit in rad/s.
    rise_to_peak : bool, optional
        The path is one gear segment of a manoeuvre (it starts at rest and may be
        shorter than the final approach): it may still speed up to its peak, or the
        running minimum from its standstill start would keep it at 0; the peak is
        capped by :func:`peak_with_plateau` for its length. Any path that starts at
        rest within the final approach is treated so.

    Returns
    -------
    SpeedProfile

    Examples
    --------
    >>> from rrtdrive.controllers import SpeedConfig
    >>> s = np.linspace(0.0, 20.0, 81)
    >>> k = np.clip(s - 8.0, 0.0, 1.0) * 0.15  # a clothoid-like rise into a 0.15 1/m arc
    >>> fast = actuator_profile(s, k, SpeedConfig(), 0.0, 2.51, None)
    >>> slow = actuator_profile(s, k, SpeedConfig(), 0.0, 2.51, 0.4)
    >>> float(fast.v[0]), float(slow.v[0]), float(fast.v[34]), round(float(slow.v[34]), 3)
    (0.5, 0.0, 3.0, 0.746)
    """
    s, kappa = checked_samples(s, kappa, v_start)
    if max_steer_rate is None or not math.isfinite(max_steer_rate):
        return SpeedProfile(s, kappa, config, v_start)
    config = dataclasses.replace(config, v_launch=0.0)  # type: ignore[type-var]
    cap = steering_rate_speed_cap(s, kappa, wheelbase, max_steer_rate, config.steer_rate_share)
    first = SpeedProfile(s, kappa, config, v_start, v_cap=cap)
    final = s > s[-1] - FINAL_APPROACH_M
    i0 = int(np.argmax(final)) if np.any(final) else None
    rise = last_rise_level(s, first.v, config.accel + config.decel, config.comfort_jerk)
    if rise is not None and (i0 is None or rise[0] < i0):
        trough, level = rise
        if level > first.v[trough]:
            # The last peak lowered to a plateau the loop can turn into the stop.
            cap[trough:] = np.minimum(cap[trough:], level)
        else:
            i0 = trough  # no such plateau above the trough: the rest at the trough's speed
    if i0 is not None and i0 < len(s) - 1 and first.v[i0] <= 0.0:
        # From rest within the final approach (a path shorter than it): held from rising,
        # the running minimum would be 0 throughout and the car would never move. (The
        # end sample alone, of a path sampled sparsely, is no such start.)
        rise_to_peak = True
    elif i0 is not None and first.v[0] <= 0.0 and bool(np.all(np.diff(first.v[: i0 + 1]) > 0)):
        # From rest and still speeding up where the final approach begins (a path of
        # 2-4 m): that is the start's rise, not a speed-up again; held from there, the
        # car crawled at the speed of its first samples (0.47 m/s on 2 m). Held from the
        # profile's peak instead, as a longer path is.
        i0 = int(np.argmax(first.v))
    if i0 is not None and rise_to_peak:
        i0 = max(i0, int(np.argmax(first.v)))
    if i0 is not None:
        cap[i0:] = np.minimum(cap[i0:], np.minimum.accumulate(first.v[i0:]))
    if rise_to_peak:
        swing = config.accel + config.decel
        accel = min(config.accel, config.decel)
        cap = np.minimum(cap, peak_with_plateau(float(s[-1]), accel, swing, config.comfort_jerk))
        return SpeedProfile(s, kappa, config, v_start, v_cap=cap)
    second = SpeedProfile(s, kappa, config, v_start, v_cap=cap)
    # Every peak from rest (a planned or given path: an earlier peak before a curvature
    # step was overrun, the car braking at -2.2 m/s^2 and standing before the step); the
    # last only for a moving car (the traffic re-planner's stitched plans, whose peak
    # ahead would be lowered at every re-plan).
    flat = plateau_caps(second.s, second.v, config.decel / config.comfort_jerk,
                        last_only=v_start > 0.0)  # fmt: skip
    if np.all(flat >= second.v):
        return second
    return SpeedProfile(s, kappa, config, v_start, v_cap=np.minimum(cap, flat))
