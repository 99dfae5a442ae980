"""Sharpness of a sampled path: the steering angle's rate per metre, ``|d delta / ds|``.

With ``delta = atan(L kappa)``, ``d delta / ds = L (d kappa / ds) / (1 + L^2 kappa^2)``.
Between two rows whose curvature is linear in arc length (a clothoid, a line or an
arc, as the clothoid curves' rows are: every piece starts and ends on a row) the
largest value is at the smaller ``|kappa|`` (0 when the sign changes), so the
per-interval value below is exact, up to the chord standing in for the arc length
(shorter, so the value errs high). On a degree-2 B-spline the curvature jumps at
the knots, so its true sharpness is unbounded and this gives the jump over the
sample gap.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["interval_sharpness", "max_sharpness", "steer_rate_speed_limit"]


def interval_sharpness(samples: np.ndarray, wheelbase: float) -> np.ndarray:
    """Largest ``|d delta / ds|`` (rad/m) between consecutive rows ``[x, y, yaw, kappa, ...]``.

    Parameters
    ----------
    samples : numpy.ndarray
        ``(N, >=4)`` rows ``x, y, yaw, kappa``; a fifth column, the gear, makes a cusp's
        interval 0.
    wheelbase : float
        The car's wheelbase in metres.

    Returns
    -------
    numpy.ndarray
        ``(N - 1,)`` rad/m (``inf`` for a curvature jump between rows on one spot).

    Examples
    --------
    >>> rows = np.array([[0.0, 0, 0, 0.0], [1.0, 0, 0, 0.1], [2.0, 0, 0, 0.1]])
    >>> interval_sharpness(rows, 2.0).round(6).tolist()
    [0.2, 0.0]
    >>> cusp = np.array([[0.0, 0, 0, 0.1, 1], [0.0, 0, 0, -0.1, -1], [-1.0, 0, 0, -0.1, -1]])
    >>> interval_sharpness(cusp, 2.0).tolist()
    [0.0, 0.0]
    """
    s = np.asarray(samples, dtype=float)
    if len(s) < 2:
        return np.zeros(0)
    d = s[1:, :2] - s[:-1, :2]  # np.diff's arithmetic without its wrapper
    ds = np.hypot(d[:, 0], d[:, 1])
    k0, k1 = s[:-1, 3], s[1:, 3]
    dk = np.abs(k1 - k0)
    kmin = np.where(k0 * k1 > 0.0, np.minimum(np.abs(k0), np.abs(k1)), 0.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        rate = wheelbase * dk / (ds * (1.0 + (wheelbase * kmin) ** 2))
    # Two rows on one spot: a jump of curvature there is infinitely sharp, none is nothing
    # (rows all apart, the common case, keep every rate).
    apart = ds > 0.0
    if not np.logical_and.reduce(apart):
        rate = np.where(apart, rate, np.where(dk > 0.0, np.inf, 0.0))
    if s.shape[1] >= 5:
        # A cusp (the gear changes): the car stands, so it may steer there at no cost
        # per metre; sharpness is a property of each gear segment.
        rate = np.where(s[:-1, 4] != s[1:, 4], 0.0, rate)
    return rate


def max_sharpness(samples: np.ndarray, wheelbase: float) -> float:
    """The path's largest ``|d delta / ds|`` in rad/m (0 for fewer than two rows).

    Parameters
    ----------
    samples, wheelbase
        As :func:`interval_sharpness`.

    Returns
    -------
    float

    Examples
    --------
    >>> max_sharpness(np.array([[0.0, 0, 0, 0.0], [0.5, 0, 0, 0.05]]), 2.0)
    0.2
    """
    rate = interval_sharpness(samples, wheelbase)
    return float(rate.max()) if len(rate) else 0.0


def steer_rate_speed_limit(sharpness: float, max_steer_rate: float | None) -> float | None:
    """Speed (m/s) at which a path of ``sharpness`` needs exactly the actuator's rate.

    ``None`` for instant steering (no rate limit); ``inf`` for a path that never steers.

    Parameters
    ----------
    sharpness : float
        The path's largest ``|d delta / ds|``, rad/m.
    max_steer_rate : float or None
        The actuator's steering rate limit, rad/s (``None`` or ``inf``: instant).

    Returns
    -------
    float or None

    Examples
    --------
    >>> steer_rate_speed_limit(0.2, 0.4), steer_rate_speed_limit(0.2, None)
    (2.0, None)
    """
    if max_steer_rate is None or not math.isfinite(max_steer_rate):
        return None
    return math.inf if sharpness <= 0.0 else max_steer_rate / sharpness
