"""How fast the path asks the steering to turn, and the speed cap a rate-limited actuator gives.

:func:`steering_sharpness` measures ``|d delta/ds|`` (rad/m) along a sampled path, with
``delta = atan(L kappa)`` the steering angle its curvature asks for;
:func:`steering_rate_speed_cap` turns it into ``v(s) <= share * max_steer_rate /
|d delta/ds|(s)``, the speed at which the wheels keep up. Used by the speed profile
(:mod:`rrtdrive.speed_profile`, which the controllers track) and the space-time planner.
"""

from __future__ import annotations

import numpy as np

__all__ = ["SHARPNESS_WINDOW_M", "steering_sharpness", "steering_rate_speed_cap"]

#: Arc-length window (metres) over which :func:`steering_sharpness` measures the
#: change of the steering angle: finer than any path feature the car can follow,
#: coarser than the gaps between repeated or nearly repeated samples.
SHARPNESS_WINDOW_M = 0.25


def steering_sharpness(
    s: np.ndarray, kappa: np.ndarray, wheelbase: float, window: float = SHARPNESS_WINDOW_M
) -> np.ndarray:
    """``|d delta / ds|`` at each sample (rad/m), ``delta = atan(L kappa)``, robust to sampling.

    The change of the steering angle (interpolated linearly in arc length) over windows
    of ``window`` metres that start or end at a sample; a sample takes the largest of
    those windows that come within ``window`` of it. Those windows include the steepest
    of any placement (the change over a window is piecewise linear in its position,
    with corners where an end crosses a sample), so a curvature step between two rows
    counts in full; and the samples a window's length before and after a change are
    capped too, so the jerk-limited speed loop has room to slow down for it (capped at
    the step's two rows alone, the car reached the step too fast and ran 0.17 m off a
    path that steps to 1/6 1/m). So a sample gap much shorter than ``window`` (a
    repeated row, a cusp) cannot make the slope blow up, and a jump of the angle counts
    as a change over ``window``. (Until session 27 the windows were a fixed grid from
    the first sample: offset from the rows, it split a step between two of them and
    read it up to 2x too small.)

    Parameters
    ----------
    s : numpy.ndarray
        Arc length of the samples, non-decreasing from 0.
    kappa : numpy.ndarray
        Path curvature at the samples (1/m).
    wheelbase : float
        ``L`` in metres.
    window : float
        Window length in metres (> 0).

    Returns
    -------
    numpy.ndarray
        ``(N,)`` sharpness in rad/m.

    Examples
    --------
    >>> s = np.linspace(0.0, 10.0, 101)
    >>> k = np.clip(s - 4.0, 0.0, 1.0) * 0.1  # curvature ramps 0 -> 0.1 over s in [4, 5]
    >>> sh = steering_sharpness(s, k, 2.5)
    >>> round(float(sh.max()), 3), float(sh[0])
    (0.25, 0.0)
    >>> s = np.append(np.arange(0.0, 10.01, 0.25), 10.1)  # rows 0.25 m apart, and one more
    >>> k = np.where(s > 5.0, 0.1, 0.0)  # a step from 0 to 0.1 1/m between two rows
    >>> round(float(steering_sharpness(s, k, 2.5).max()), 3)  # atan(0.25) / 0.25 m (was 0.689)
    0.98
    """
    s = np.asarray(s, dtype=float)
    delta = np.arctan(wheelbase * np.asarray(kappa, dtype=float))
    n = len(s)
    if n < 2 or float(s[-1] - s[0]) <= 0.0:
        return np.zeros(n)
    ahead = np.abs(np.interp(s + window, s, delta) - delta) / window  # [s_j, s_j + w]
    behind = np.abs(delta - np.interp(s - window, s, delta)) / window  # [s_j - w, s_j]
    # Windows that meet [s_i - w, s_i + w]: ahead of s_j for s_j in [s_i - 2w, s_i + w],
    # behind s_j for s_j in [s_i - w, s_i + 2w].
    out = np.maximum(
        _range_max(ahead, np.searchsorted(s, s - 2.0 * window, side="left"),
                   np.searchsorted(s, s + window, side="right") - 1),
        _range_max(behind, np.searchsorted(s, s - window, side="left"),
                   np.searchsorted(s, s + 2.0 * window, side="right") - 1),
    )  # fmt: skip
    # The change over a window is piecewise linear in its start, so its largest over
    # starts in [s_i - 2w, s_i + w] is at a start where an end meets a sample (above) or
    # at the interval's two ends (here).
    far_back = np.abs(np.interp(s - window, s, delta) - np.interp(s - 2.0 * window, s, delta))
    far_on = np.abs(np.interp(s + 2.0 * window, s, delta) - np.interp(s + window, s, delta))
    return np.maximum(out, np.maximum(far_back, far_on) / window)


def _range_max(values: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """``max(values[lo_i : hi_i + 1])`` for every ``i`` (``lo <= hi``), by a sparse table.

    Examples
    --------
    >>> _range_max(np.array([3.0, 1.0, 4.0, 1.0, 5.0]), np.array([0, 1, 3]), np.array([1, 3, 3]))
    array([3., 4., 1.])
    """
    count = hi - lo + 1
    levels = [values]
    while 2 ** len(levels) <= count.max():
        prev, width = levels[-1], 2 ** (len(levels) - 1)
        level = prev.copy()
        np.maximum(prev[:-width], prev[width:], out=level[:-width])
        levels.append(level)
    table = np.stack(levels)
    power = np.frexp(count)[1] - 1  # floor(log2(count)), exactly
    return np.maximum(table[power, lo], table[power, hi - 2**power + 1])


def steering_rate_speed_cap(
    s: np.ndarray,
    kappa: np.ndarray,
    wheelbase: float,
    max_steer_rate: float,
    share: float = 1.0,
    window: float = SHARPNESS_WINDOW_M,
) -> np.ndarray:
    """Speed cap of a rate-limited steering actuator: ``share * rate / |d delta/ds|`` (m/s).

    At speed ``v`` the path asks the wheels to turn at ``v |d delta/ds|`` rad/s; the
    cap keeps that within ``share`` of ``max_steer_rate`` (the rest is left to the
    controller's corrections). Straight or constant-curvature stretches are not
    capped (``inf``).

    Parameters
    ----------
    s, kappa : numpy.ndarray
        Arc length and curvature of the samples.
    wheelbase : float
        ``L`` in metres.
    max_steer_rate : float
        The actuator's rate limit in rad/s.
    share : float
        Share of the rate the path's own steering may use, in ``(0, 1]``.
    window : float
        See :func:`steering_sharpness`.

    Returns
    -------
    numpy.ndarray
        ``(N,)`` caps in m/s (``inf`` where the steering angle does not change).

    Examples
    --------
    >>> s = np.linspace(0.0, 10.0, 101)
    >>> k = np.clip(s - 4.0, 0.0, 1.0) * 0.1
    >>> cap = steering_rate_speed_cap(s, k, 2.5, 0.4, share=0.5)
    >>> round(float(cap.min()), 3), bool(np.isinf(cap[0]))
    (0.801, True)
    """
    sharp = steering_sharpness(s, kappa, wheelbase, window)
    with np.errstate(divide="ignore"):
        return np.where(sharp > 1e-12, share * max_steer_rate / np.maximum(sharp, 1e-300), np.inf)
