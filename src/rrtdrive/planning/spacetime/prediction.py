"""Predicted motion of other vehicles: body-centre poses on a uniform time grid.

Built in :mod:`rrtdrive.sim.prediction`; plain arrays here, so planning never
imports the simulator.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from rrtdrive.types import InputError, require_positive

__all__ = ["Prediction"]


@dataclass(frozen=True, eq=False)
class Prediction:
    """Predicted body-centre poses of other vehicles on a uniform time grid.

    Attributes
    ----------
    times : numpy.ndarray
        ``(T,)`` seconds from the moment of prediction: ``0, step, 2 step, ...``.
    poses : numpy.ndarray
        ``(K, T, 3)`` body-centre ``x, y, heading`` of each vehicle at each time.
    sizes : numpy.ndarray
        ``(K, 2)`` body ``length, width``.
    method : str
        Name of the predictor that made it.
    alt : numpy.ndarray or None
        ``(K, T, 3)`` a second hypothesis for the same vehicles (for example at
        another speed), or ``None``. The conflict test sweeps each vehicle's body
        over *both* hypotheses: it must be safe whichever comes true.

    Examples
    --------
    >>> p = Prediction.constant_velocity(np.array([[0.0, 0.0, 0.0, 2.0]]), [(4.3, 1.8)], 3.0)
    >>> p.centres_at(np.array([1.5]))[0, 0].tolist()
    [3.0, 0.0]
    """

    times: np.ndarray
    poses: np.ndarray
    sizes: np.ndarray
    method: str = "constant-velocity"
    alt: np.ndarray | None = None

    def __post_init__(self) -> None:
        t = np.asarray(self.times, dtype=float).reshape(-1)
        p = np.asarray(self.poses, dtype=float)
        s = np.asarray(self.sizes, dtype=float).reshape(-1, 2)
        if len(t) < 2 or t[0] != 0.0 or np.any(np.diff(t) <= 0):
            raise InputError("prediction.times: need an increasing grid starting at 0")
        if not np.allclose(np.diff(t), t[1] - t[0], rtol=1e-6, atol=1e-9):
            raise InputError("prediction.times: the grid must be uniform")
        if p.size % (len(t) * 3):
            raise InputError(
                f"prediction.poses: need (vehicles, {len(t)}, 3) poses for the {len(t)} times, "
                f"got shape {p.shape}"
            )
        p = p.reshape(-1, len(t), 3)
        if len(p) != len(s):
            raise InputError(
                f"prediction.sizes: {len(s)} sizes for {len(p)} predicted vehicles"
            )
        if not (np.all(np.isfinite(p)) and np.all(np.isfinite(s)) and np.all(s > 0)):
            raise InputError("prediction: poses must be finite and sizes positive")
        arrays = [("times", t), ("poses", p), ("sizes", s)]
        if self.alt is not None:
            a = np.asarray(self.alt, dtype=float)
            if a.shape != p.shape or not np.all(np.isfinite(a)):
                raise InputError(
                    f"prediction.alt: need finite poses of shape {p.shape}, got {a.shape}"
                )
            arrays.append(("alt", a))
        for name, arr in arrays:
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)

    def __len__(self) -> int:
        return len(self.poses)

    @property
    def step(self) -> float:
        """Spacing of the time grid in seconds."""
        return float(self.times[1] - self.times[0])

    @property
    def horizon(self) -> float:
        """Last predicted time in seconds."""
        return float(self.times[-1])

    @classmethod
    def constant_velocity(
        cls,
        states: np.ndarray,
        sizes: Sequence[Sequence[float]] | np.ndarray,
        horizon: float,
        step: float = 0.1,
    ) -> Prediction:
        """Each vehicle drives on along its heading at its current speed.

        Parameters
        ----------
        states : numpy.ndarray
            ``(K, 4)`` body-centre ``x, y, heading, speed``.
        sizes : sequence
            ``(length, width)`` per vehicle.
        horizon, step : float
            Prediction horizon and time step in seconds.
        """
        require_positive("prediction.horizon", horizon)
        require_positive("prediction.step", step)
        st = np.asarray(states, dtype=float).reshape(-1, 4)
        times = np.arange(0.0, horizon + 0.5 * step, step)
        c, s = np.cos(st[:, 2]), np.sin(st[:, 2])
        x = st[:, None, 0] + (st[:, 3] * c)[:, None] * times[None, :]
        y = st[:, None, 1] + (st[:, 3] * s)[:, None] * times[None, :]
        h = np.repeat(st[:, 2:3], len(times), axis=1)
        return cls(times, np.stack([x, y, h], axis=-1), np.asarray(sizes, float).reshape(-1, 2))

    @classmethod
    def empty(cls, horizon: float = 1.0, step: float = 0.1) -> Prediction:
        """A prediction with no vehicles."""
        times = np.arange(0.0, horizon + 0.5 * step, step)
        return cls(times, np.zeros((0, len(times), 3)), np.zeros((0, 2)))

    def select(self, keep: np.ndarray) -> Prediction:
        """Only the vehicles where ``keep`` is True (or whose indices are given).

        Parameters
        ----------
        keep : numpy.ndarray
            Boolean ``(K,)`` mask, or integer indices of the vehicles to keep.

        Returns
        -------
        Prediction
        """
        alt = None if self.alt is None else self.alt[keep]
        return Prediction(self.times, self.poses[keep], self.sizes[keep], self.method, alt)

    def shifted(self, dx: float, dy: float = 0.0) -> Prediction:
        """The same prediction with every position moved by ``(dx, dy)`` (a change of frame).

        Parameters
        ----------
        dx, dy : float
            Shift in metres (``alt`` moved alike; headings unchanged).

        Returns
        -------
        Prediction
        """
        moved: list[np.ndarray | None] = []
        for arr in (self.poses, self.alt):
            if arr is None:
                moved.append(None)
                continue
            arr = arr.copy()
            arr[..., 0] += dx
            arr[..., 1] += dy
            moved.append(arr)
        return Prediction(self.times, moved[0], self.sizes, self.method, moved[1])

    def poses_at(self, t: np.ndarray) -> np.ndarray:
        """Body-centre poses at times ``t`` (seconds from the prediction), shape ``(K, N, 3)``.

        Linear interpolation on the grid; before 0 the first pose; past the horizon
        the last grid interval is extrapolated (constant velocity).

        Parameters
        ----------
        t : numpy.ndarray
            ``(N,)`` times in seconds (any shape, flattened).

        Returns
        -------
        numpy.ndarray
            ``(K, N, 3)`` body-centre ``x, y, heading`` (the heading of the nearer sample).
        """
        return _poses_at(self.poses, self.step, t)

    def centres_at(self, t: np.ndarray) -> np.ndarray:
        """Body-centre positions at times ``t``, shape ``(K, N, 2)``.

        Parameters
        ----------
        t : numpy.ndarray
            ``(N,)`` times in seconds from the prediction (as :meth:`poses_at`).

        Returns
        -------
        numpy.ndarray
            ``(K, N, 2)`` body-centre ``x, y``.
        """
        return self.poses_at(t)[..., :2]

    def x_range(self) -> np.ndarray:
        """``(K, 2)`` smallest and largest centre x each vehicle reaches over the horizon."""
        x = self.poses[..., 0]
        if self.alt is not None:
            x = np.concatenate([x, self.alt[..., 0]], axis=1)
        return np.stack([x.min(axis=1), x.max(axis=1)], axis=1)


def _poses_at(poses: np.ndarray, step: float, t: np.ndarray) -> np.ndarray:
    """:meth:`Prediction.poses_at` on raw ``(K, T, 3)`` arrays."""
    t = np.asarray(t, dtype=float).reshape(-1)
    k, n_t = poses.shape[:2]
    if k == 0:
        return np.zeros((0, len(t), 3))
    u = np.maximum(t, 0.0) / step
    i = np.minimum(np.floor(u).astype(np.int64), n_t - 2)
    frac = (u - i)[None, :, None]
    a = poses.take(i, axis=1)
    b = poses.take(i + 1, axis=1)
    out = a + frac * (b - a)
    # Headings: the nearer sample (no interpolation across a wrap).
    out[..., 2] = np.where(frac[..., 0] < 0.5, a[..., 2], b[..., 2])
    return out
