"""When the ego is where: nominal arrival times of tree nodes, exact times along a path.

The exact times come from :func:`rrtdrive.speed_profile.profile_times` (re-exported).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from rrtdrive.geometry import wrap_angle
from rrtdrive.speed_profile import profile_times
from rrtdrive.types import InputError, require_finite, require_positive

__all__ = ["ArrivalTiming", "profile_times", "yaw_curvature"]


@dataclass(frozen=True)
class ArrivalTiming:
    """Nominal arrival times from progress along the road (used for tree nodes and edges).

    The car starts at ``origin`` at time ``t0`` with speed ``v0`` and speeds up at
    ``accel`` to ``v_max``. A point's *progress* is its distance from ``origin``
    along ``direction`` (the road direction), and its arrival time is the time
    this profile needs for ``progress`` (earliest) to ``length_factor * progress``
    (latest, allowing for a path longer than its progress and for curves).

    Parameters
    ----------
    t0 : float
        Time at ``origin``, seconds after the prediction.
    v0, v_max, accel : float
        Start speed, speed cap (m/s) and acceleration (m/s^2).
    origin : tuple of float
        Where the timing starts (the plan's start position).
    direction : tuple of float
        Unit vector of the road direction.
    length_factor : float
        Largest ratio of path length to progress (>= 1).

    Examples
    --------
    >>> tm = ArrivalTiming(0.0, 0.0, 10.0, 1.0, (0.0, 0.0), (1.0, 0.0), 1.0)
    >>> round(float(tm.time_for(np.array([2.0]))[0]), 6)  # 2 m from rest at 1 m/s^2
    2.0
    """

    t0: float
    v0: float
    v_max: float
    accel: float
    origin: tuple[float, float]
    direction: tuple[float, float] = (1.0, 0.0)
    length_factor: float = 1.08

    def __post_init__(self) -> None:
        require_finite("timing.t0", self.t0)
        require_finite("timing.v0", self.v0)
        # Times are seconds after the prediction and speeds are forward: a negative
        # t0 gave plans negative arrival times, a negative v0 was read as 0.
        for name, value in (("timing.t0", self.t0), ("timing.v0", self.v0)):
            if value < 0.0:
                raise InputError(f"{name}: must be >= 0, got {value!r}")
        require_positive("timing.v_max", self.v_max)
        require_positive("timing.accel", self.accel)
        require_finite("timing.origin", *self.origin)
        require_finite("timing.direction", *self.direction)
        if self.length_factor < 1.0 or not math.isfinite(self.length_factor):
            raise InputError(f"timing.length_factor: must be >= 1, got {self.length_factor!r}")
        n = math.hypot(*self.direction)
        if n < 1e-9:
            raise InputError("timing.direction: must not be zero")
        object.__setattr__(self, "direction", (self.direction[0] / n, self.direction[1] / n))

    def time_for(self, distance: np.ndarray) -> np.ndarray:
        """Seconds the nominal profile needs to cover ``distance`` metres from the origin.

        Parameters
        ----------
        distance : numpy.ndarray
            Distances in metres (negative counts as 0).

        Returns
        -------
        numpy.ndarray
            Seconds after ``t0`` (not including it), shaped like ``distance``.
        """
        d = np.maximum(np.asarray(distance, dtype=float), 0.0)
        v0 = max(self.v0, 0.0)
        a, vm = self.accel, max(self.v_max, v0)
        d_up = (vm * vm - v0 * v0) / (2.0 * a)
        v = np.sqrt(v0 * v0 + 2.0 * a * np.minimum(d, d_up))
        t_up = (v - v0) / a
        return t_up + np.maximum(d - d_up, 0.0) / vm

    def state_at(self, point: Sequence[float] | np.ndarray) -> tuple[float, float]:
        """Earliest arrival time and nominal speed at ``point`` (its progress from the origin).

        Parameters
        ----------
        point : sequence of float or numpy.ndarray
            ``(x, y, ...)``; only the first two entries are used.

        Returns
        -------
        tuple of (float, float)
            Seconds after the prediction (``t0`` included) and speed in m/s.
        """
        d = max(float(self.progress(np.asarray(point, dtype=float)[:2])[0]), 0.0)
        v0 = max(self.v0, 0.0)
        v = min(math.sqrt(v0 * v0 + 2.0 * self.accel * d), max(self.v_max, v0))
        return self.t0 + float(self.time_for(np.array([d]))[0]), v

    def progress(self, points: np.ndarray) -> np.ndarray:
        """Progress of ``(N, 2)`` points along the road from the origin (may be negative).

        Parameters
        ----------
        points : numpy.ndarray
            ``(N, 2)`` positions in metres.

        Returns
        -------
        numpy.ndarray
            ``(N,)`` signed distances along ``direction``, metres.
        """
        p = np.asarray(points, dtype=float).reshape(-1, 2)
        ux, uy = self.direction
        return (p[:, 0] - self.origin[0]) * ux + (p[:, 1] - self.origin[1]) * uy

    def band(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Earliest and latest arrival times at ``(N, 2)`` points (seconds after the prediction).

        Parameters
        ----------
        points : numpy.ndarray
            ``(N, 2)`` positions; points behind the origin arrive at ``t0``.

        Returns
        -------
        tuple of numpy.ndarray
            ``(N,)`` earliest and ``(N,)`` latest times.
        """
        s = np.maximum(self.progress(points), 0.0)
        return self.t0 + self.time_for(s), self.t0 + self.time_for(s * self.length_factor)

    def shifted(self, dx: float, dy: float = 0.0) -> ArrivalTiming:
        """The same timing in a frame moved by ``(dx, dy)``.

        Parameters
        ----------
        dx, dy : float
            Shift of the origin in metres.

        Returns
        -------
        ArrivalTiming
        """
        return dataclasses.replace(self, origin=(self.origin[0] + dx, self.origin[1] + dy))


def yaw_curvature(samples: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Arc length and curvature (heading change per metre) of ``(N, >=3)`` pose samples.

    A fourth column, when present and not all zero, is taken as the curvature.
    """
    xy = samples[:, :2]
    ds = np.hypot(*np.diff(xy, axis=0).T)
    s = np.concatenate([[0.0], np.cumsum(ds)])
    if samples.shape[1] >= 4 and np.any(samples[:, 3] != 0.0):
        return s, samples[:, 3].copy()
    dyaw = wrap_angle(np.diff(samples[:, 2]))
    k_seg = np.where(ds > 1e-9, dyaw / np.maximum(ds, 1e-9), 0.0)
    kappa = np.zeros(len(s))
    if len(k_seg):
        kappa[:-1] = np.abs(k_seg)
        kappa[1:] = np.maximum(kappa[1:], np.abs(k_seg))
    return s, kappa
