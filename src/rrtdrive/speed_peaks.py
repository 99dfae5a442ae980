"""The shapes of a speed profile that a jerk-limited speed loop can follow to a stop.

The comfort-mode speed loop (``rrtdrive.controllers.SpeedController``) bounds every
change of its acceleration command by a jerk; turning from speeding up to braking
then takes ``swing / jerk`` seconds. A profile that rises and at once brakes (a peak
without a plateau) leaves the car still speeding up when it should brake: it runs
past the peak, then past the stop. These functions find such peaks and the caps that
flatten them; :func:`rrtdrive.speed_profile.actuator_profile` applies them.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["last_rise_level", "peak_with_plateau", "plateau_caps"]


def _last_rise(v: list[float]) -> tuple[int, int, int]:
    """``(trough, plateau, brake)``: where the last rise, the plateau and the final braking start.

    Walking back from the end: the braking (``v`` falling to the end) starts at
    ``brake``, the run of equal speeds before it at ``plateau``, and the rise into that
    run (``v`` strictly rising) at ``trough``; ``trough == plateau`` when there is none.
    """
    eps = 1e-9
    brake = len(v) - 1
    while brake > 0 and v[brake - 1] > v[brake] + eps:
        brake -= 1
    plateau = brake
    while plateau > 0 and abs(v[plateau - 1] - v[brake]) <= eps:
        plateau -= 1
    trough = plateau
    while trough > 0 and v[trough - 1] < v[trough] - eps:
        trough -= 1
    return trough, plateau, brake


def last_rise_level(
    s: np.ndarray, v: np.ndarray, swing: float, jerk: float
) -> tuple[int, float] | None:
    """A last speed-up the jerk-limited loop cannot turn into the final stop, and its cap.

    The tail of a profile that stops at its end is a run where ``v`` never rises:
    a plateau, then the braking to the stop. Before it the profile may rise from a
    trough. Turning that rise into the braking swings the command through ``swing``
    m/s^2, which takes ``swing / jerk`` seconds at the comfort jerk; when the plateau
    is shorter than that at its speed, the car overshoots the profile and the stop.
    (A rise from the first sample is the start, not a slow stretch: left alone.)

    The cap is the highest speed ``c`` at which the stretch after the trough where
    ``v >= c`` lasts ``swing / jerk`` seconds (``c swing / jerk`` metres, between
    samples), as :func:`plateau_caps` lowers a peak: the rise then ends in a plateau the
    loop can turn into the stop. It is never below the trough's own speed; when even
    that stretch is too short, the cap is the trough's speed (the rest of the path is
    driven at it). Until session 27 the rest was always held at the trough's speed: a
    10 m arc at the steering-rate cap's 0.18 m/s took 65 s where a lowered peak takes 15 s.

    Returns
    -------
    tuple of (int, float) or None
        ``(trough index, cap in m/s)``; ``None`` when there is no such rise.

    Examples
    --------
    >>> s = np.arange(0.0, 6.01, 0.5)
    >>> v = np.array([0, 1, 2, 1, 0.5, 1, 1.5, 2, 2.2, 1.9, 1.5, 1, 0])  # trough at s = 2 m
    >>> trough, cap = last_rise_level(s, v, 2.0, 2.0)  # needs a plateau of 1 s
    >>> trough, round(cap, 9)  # the peak of 2.2 m/s lowered to 1.5 m/s, held over 2 m
    (4, 1.5)
    """
    # Python floats for the walks (the same numbers, 5x faster than numpy scalars).
    sl, vl = np.asarray(s, dtype=float).tolist(), np.asarray(v, dtype=float).tolist()
    trough, plateau, brake = _last_rise(vl)
    if trough == plateau or trough == 0 or sl[brake] - sl[plateau] >= vl[plateau] * swing / jerk:
        return None
    _, _, level = _plateau_level(sl, vl, plateau, brake, swing / jerk)
    floor = vl[trough]
    return trough, floor if level is None or level < floor else level


def peak_with_plateau(length: float, accel: float, swing: float, jerk: float) -> float:
    """Top speed of a rest-to-rest run of ``length`` metres that the comfort loop can stop.

    The run rises and falls at ``accel`` (m/s^2) and holds its top speed ``v`` for the
    ``swing / jerk`` seconds the jerk-limited command needs to swing from speeding up to
    braking (as :func:`last_rise_level` asks of a last rise):
    ``v^2 / accel + v swing / jerk = length``. A manoeuvre's gear segment is such a run;
    without the plateau, a multi-point turn's 0.7 m moves (a triangle of a profile) left
    the car still speeding up when it had to brake, and it ran 0.2 m past the cusp.

    Parameters
    ----------
    length : float
        Length of the run, metres.
    accel : float
        Rate at which the run's speed rises and falls, m/s^2.
    swing : float
        Range the command swings through from speeding up to braking, m/s^2
        (:func:`~rrtdrive.speed_profile.actuator_profile` passes ``accel + decel``).
    jerk : float
        The loop's jerk bound, m/s^3.

    Returns
    -------
    float
        Top speed ``v`` in m/s.

    Examples
    --------
    >>> round(peak_with_plateau(0.7, 0.5, 1.0, 2.0), 3)
    0.48
    """
    lag = swing / jerk
    return 0.5 * accel * (math.sqrt(lag * lag + 4.0 * length / accel) - lag)


def plateau_caps(s: np.ndarray, v: np.ndarray, lag: float, last_only: bool = False) -> np.ndarray:
    """Caps that give every peak of a profile a plateau of ``lag`` seconds.

    A jerk-limited loop needs ``lag`` seconds to swing its command from speeding up to
    braking; on a peak without a plateau (the profile rises, then at once falls) it is
    still speeding up when the profile brakes, overshoots the peak and must brake
    harder than the profile later (on the stock ``parking-v0`` seed 32 the car reached
    3.24 m/s on a 2.98 m/s peak 5 m before the goal and stopped at -3.5 m/s^2). Each
    local peak is lowered to the highest speed ``c`` at which the stretch around it
    where ``v >= c`` is at least ``c * lag`` metres long (:func:`peak_with_plateau`
    is the same rule for a rest-to-rest triangle). Peaks whose stretch reaches the
    first sample (a car already moving) are left alone.

    Parameters
    ----------
    s, v : numpy.ndarray
        Arc length (increasing) and speed of the profile's samples.
    lag : float
        Seconds the plateau must last, ``swing / jerk``.
    last_only : bool, optional
        Cap the last peak only (the one before a final stop).

    Returns
    -------
    numpy.ndarray
        ``(N,)`` speed caps in m/s (``inf`` where nothing is capped).
        ``min(v, caps)`` keeps ``v``'s acceleration and deceleration bounds.

    Examples
    --------
    >>> s = np.linspace(0.0, 8.0, 33)
    >>> v = np.sqrt(np.minimum(s, 8.0 - s))  # a triangle in v^2: rise, then brake at once
    >>> capped = np.minimum(v, plateau_caps(s, v, 1.0))
    >>> float(v.max()), round(float(capped.max()), 3)  # the peak, lowered to sqrt(3)
    (2.0, 1.732)
    >>> float(np.ptp(s[capped >= capped.max() - 1e-9]))  # its plateau: >= 1.732 m, 1 s
    2.0
    """
    s = np.asarray(s, dtype=float)
    v = np.asarray(v, dtype=float)
    n = len(v)
    caps = np.full(n, np.inf)
    eps = 1e-9
    peaks: list[tuple[int, int]] = []
    sl, w = s.tolist(), v.tolist()  # the same numbers as Python floats: walks 5x faster
    i = 1
    while i < n - 1:
        # A local peak: a run of equal speeds higher than both neighbours.
        j = i
        while j + 1 < n and abs(w[j + 1] - w[i]) <= eps:
            j += 1
        if w[i - 1] < w[i] - eps and j + 1 < n and w[j + 1] < w[i] - eps:
            peaks.append((i, j))
        i = j + 1
    for i, j in peaks[-1:] if last_only else peaks:
        lo, hi, level = _plateau_level(sl, w, i, j, lag)
        if level is not None:
            caps[lo : hi + 1] = np.minimum(caps[lo : hi + 1], level)
    return caps


def _plateau_level(
    sl: list[float], vl: list[float], i: int, j: int, lag: float
) -> tuple[int, int, float | None]:
    """The level of the peak ``vl[i..j]`` (see :func:`plateau_caps`) and the stretch it caps.

    ``sl``, ``vl``: the profile's arc lengths and speeds as Python floats (converted once
    by the caller, not once per peak).

    The stretch never runs on past a sample higher than the peak: lowered that far, the
    peak is a shoulder of the higher part (the level is then the saddle between them,
    and nothing needs a plateau). Before, it ran on over the higher part and capped it
    too: parallel parking seed 3 had 26 m of a 2 m/s stretch capped at 1.56 m/s for a
    1.67 m/s last peak.
    """
    top, n = vl[i], len(vl)
    left, right = i - 1, j + 1
    while left >= 0 and vl[left] <= top + 1e-9:
        left -= 1
    while right < n and vl[right] <= top + 1e-9:
        right += 1
    # The lowest sample between the peak and a higher part on either side (its saddle):
    # the stretch ends there, so that what it caps adjoins the profile's own samples.
    first = left + 1 + int(np.argmin(vl[left + 1 : i])) if left >= 0 else 0
    last = j + 1 + int(np.argmin(vl[j + 1 : right])) if right < n else n - 1
    saddles = ([vl[first]] if left >= 0 else []) + ([vl[last]] if right < n else [])
    saddle = max(saddles, default=0.0)

    def stretch(c: float) -> tuple[int, int]:
        lo, hi = i, j
        while lo > first and vl[lo - 1] >= c:
            lo -= 1
        while hi < last and vl[hi + 1] >= c:
            hi += 1
        return lo, hi

    def width(c: float) -> float:
        # Between the samples at or above c: once capped at c, the samples next to them
        # are below c, so that is the plateau the capped profile has.
        lo, hi = stretch(c)
        return sl[hi] - sl[lo]

    if width(top) >= top * lag:
        return i, j, None
    low, high = 0.0, top
    for _ in range(40):  # bisection to about 1e-12 of the peak: ample for a speed
        mid = 0.5 * (low + high)
        if width(mid) >= mid * lag:
            low = mid
        else:
            high = mid
    low = max(low, saddle)
    lo, hi = stretch(low)
    if lo == 0:
        return lo, hi, None
    return lo, hi, low
