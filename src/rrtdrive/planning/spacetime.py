"""Space-time planning: the improved RRT-Connect against the predicted motion of other vehicles.

The paper plans among static obstacles. Here other vehicles move, and a pose is
only in conflict with a vehicle if both are there *at the same time*. The ego's
time at a place comes from its speed profile, so the checks below give every
point of the plane an arrival time and test the ego there against the other
vehicles' predicted poses at that time, with a safety buffer:

* :class:`Prediction` - the other vehicles' predicted body-centre poses on a
  time grid (built in :mod:`rrtdrive.sim.prediction`; plain arrays here, so
  planning never imports the simulator).
* :class:`ArrivalTiming` - the arrival time of a tree node from the nominal
  speed profile (accelerate at ``accel`` from the start speed to ``v_max``)
  over its progress along the road; tree edges and nodes carry these times.
* :func:`profile_times` - the exact arrival times along a sampled path from the
  controller's speed profile (curvature limit, acceleration and deceleration
  limits), used by the exact path test.
* :class:`SpaceTimeChecker` - a collision checker with the static checker's
  interface (``edge_free``, ``pose_free``, ``poses_free``, ``path_free``, and
  everything else delegated), whose answers also require every ego pose to keep
  ``buffer`` from every other vehicle's swept body over the pose's time band.
* :class:`SpaceTimeRRTConnect` - :class:`~rrtdrive.planning.improved.ImprovedRRTConnect`
  run on a :class:`SpaceTimeChecker`: tree growth, direct connection, pruning,
  sharp-angle repair and the B-spline guarantee loop all see moving vehicles.

The conflict test is conservative: the ego body is covered by three discs
(:func:`rrtdrive.vehicle.cover_discs`), grown by half the pose spacing; each
other vehicle by the capsule around its centre line, stretched along its heading
over the time band ``[t - margin(t), t + margin(t)]`` (exact for motion along
the heading, which both predictors produce). A pose conflicts when a disc comes
closer than ``buffer(t)`` to a capsule.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import time
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rrtdrive.collision import CollisionChecker
from rrtdrive.maps import Map
from rrtdrive.planning.base import PlanningProblem, cached_checker
from rrtdrive.planning.improved import ImprovedConfig, ImprovedRRTConnect
from rrtdrive.types import (
    Budget,
    InputError,
    Path,
    PlanResult,
    PlanStatus,
    Pose,
    VehicleParams,
    require_finite,
    require_positive,
)
from rrtdrive.vehicle import cover_discs

__all__ = [
    "Prediction",
    "SafetyConfig",
    "ArrivalTiming",
    "profile_times",
    "traffic_conflicts",
    "SpaceTimeChecker",
    "SpaceTimeProblem",
    "SpaceTimePlan",
    "SpaceTimeRRTConnect",
]


# ----------------------------------------------------------------------------- prediction data


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
        sizes: Sequence[Sequence[float]],
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
        """Only the vehicles where ``keep`` is True (or whose indices are given)."""
        alt = None if self.alt is None else self.alt[keep]
        return Prediction(self.times, self.poses[keep], self.sizes[keep], self.method, alt)

    def shifted(self, dx: float, dy: float = 0.0) -> Prediction:
        """The same prediction with every position moved by ``(dx, dy)`` (a change of frame)."""
        moved = []
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
        """
        return _poses_at(self.poses, self.step, t)

    def centres_at(self, t: np.ndarray) -> np.ndarray:
        """Body-centre positions at times ``t``, shape ``(K, N, 2)``."""
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
    a = poses[:, i, :]
    b = poses[:, i + 1, :]
    out = a + frac * (b - a)
    # Headings: the nearer sample (no interpolation across a wrap).
    out[..., 2] = np.where(frac[..., 0] < 0.5, a[..., 2], b[..., 2])
    return out


# ----------------------------------------------------------------------------- timing


@dataclass(frozen=True)
class SafetyConfig:
    """How far the ego keeps from predicted vehicles, in space and in time.

    A pose the ego reaches at time ``t`` (seconds after the prediction) is
    tested against each vehicle's body swept over ``[t - m(t), t + m(t)]`` with
    ``m(t) = time_margin_s + time_margin_growth * t``, and must keep
    ``b(t) = buffer_m + buffer_growth * t`` from it: both grow with the
    prediction time, as the prediction's uncertainty does.

    Parameters
    ----------
    buffer_m : float
        Distance at ``t = 0`` in metres (between the ego's covering discs and the
        other vehicle's covering capsule, themselves conservative).
    buffer_growth : float
        Growth of the distance per second of prediction (m/s).
    time_margin_s : float
        Half-width of the time band at ``t = 0`` in seconds.
    time_margin_growth : float
        Growth of the half-width per second of prediction (s/s).

    Examples
    --------
    >>> float(SafetyConfig().buffer(10.0)), float(SafetyConfig().margin(10.0))
    (0.9, 1.5)
    """

    buffer_m: float = 0.4
    buffer_growth: float = 0.05
    time_margin_s: float = 0.5
    time_margin_growth: float = 0.1

    def __post_init__(self) -> None:
        for name in ("buffer_m", "buffer_growth", "time_margin_s", "time_margin_growth"):
            value = getattr(self, name)
            require_finite(f"safety.{name}", value)
            if value < 0:
                raise InputError(f"safety.{name}: must be >= 0, got {value!r}")

    def buffer(self, t: float | np.ndarray) -> Any:
        """Distance to keep at prediction time ``t``."""
        return self.buffer_m + self.buffer_growth * np.maximum(t, 0.0)

    def margin(self, t: float | np.ndarray) -> Any:
        """Half-width of the time band at prediction time ``t``."""
        return self.time_margin_s + self.time_margin_growth * np.maximum(t, 0.0)


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
        """Seconds the nominal profile needs to cover ``distance`` metres from the origin."""
        d = np.maximum(np.asarray(distance, dtype=float), 0.0)
        v0 = max(self.v0, 0.0)
        a, vm = self.accel, max(self.v_max, v0)
        d_up = (vm * vm - v0 * v0) / (2.0 * a)
        v = np.sqrt(v0 * v0 + 2.0 * a * np.minimum(d, d_up))
        t_up = (v - v0) / a
        return t_up + np.maximum(d - d_up, 0.0) / vm

    def state_at(self, point: Sequence[float]) -> tuple[float, float]:
        """Earliest arrival time and nominal speed at ``point`` (its progress from the origin)."""
        d = max(float(self.progress(np.asarray(point, dtype=float)[:2])[0]), 0.0)
        v0 = max(self.v0, 0.0)
        v = min(math.sqrt(v0 * v0 + 2.0 * self.accel * d), max(self.v_max, v0))
        return self.t0 + float(self.time_for(np.array([d]))[0]), v

    def progress(self, points: np.ndarray) -> np.ndarray:
        """Progress of ``(N, 2)`` points along the road from the origin (may be negative)."""
        p = np.asarray(points, dtype=float).reshape(-1, 2)
        ux, uy = self.direction
        return (p[:, 0] - self.origin[0]) * ux + (p[:, 1] - self.origin[1]) * uy

    def band(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Earliest and latest arrival times at ``(N, 2)`` points (seconds after the prediction)."""
        s = np.maximum(self.progress(points), 0.0)
        return self.t0 + self.time_for(s), self.t0 + self.time_for(s * self.length_factor)

    def shifted(self, dx: float, dy: float = 0.0) -> ArrivalTiming:
        """The same timing in a frame moved by ``(dx, dy)``."""
        return dataclasses.replace(self, origin=(self.origin[0] + dx, self.origin[1] + dy))


def profile_times(
    s: np.ndarray,
    kappa: np.ndarray,
    v0: float,
    v_max: float,
    accel: float,
    decel: float,
    a_lat_max: float,
    v_launch: float = 0.5,
) -> tuple[np.ndarray, np.ndarray]:
    """Speeds and arrival times along a path from the speed-profile rules, without a final stop.

    The same rules as :class:`rrtdrive.controllers.SpeedProfile` (``v <= v_max``,
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
    s = np.asarray(s, dtype=float)
    k = np.abs(np.asarray(kappa, dtype=float))
    with np.errstate(divide="ignore"):
        cap2 = np.minimum(a_lat_max / np.maximum(k, 1e-12), v_max * v_max)
    cap2[0] = min(cap2[0], max(v0, v_launch) ** 2)
    v2 = 2.0 * accel * s + np.minimum.accumulate(cap2 - 2.0 * accel * s)
    back = (v2 + 2.0 * decel * s)[::-1]
    v2 = np.minimum(v2, np.minimum.accumulate(back)[::-1] - 2.0 * decel * s)
    v = np.sqrt(np.maximum(v2, 0.0))
    mean = np.maximum(0.5 * (v[1:] + v[:-1]), 0.05)
    t = np.concatenate([[0.0], np.cumsum(np.diff(s) / mean)])
    return t, v


# ----------------------------------------------------------------------------- checker


def _yaw_curvature(samples: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Arc length and curvature (heading change per metre) of ``(N, >=3)`` pose samples."""
    xy = samples[:, :2]
    ds = np.hypot(*np.diff(xy, axis=0).T)
    s = np.concatenate([[0.0], np.cumsum(ds)])
    if samples.shape[1] >= 4 and np.any(samples[:, 3] != 0.0):
        return s, samples[:, 3].copy()
    dyaw = (np.diff(samples[:, 2]) + math.pi) % (2.0 * math.pi) - math.pi
    k_seg = np.where(ds > 1e-9, dyaw / np.maximum(ds, 1e-9), 0.0)
    kappa = np.zeros(len(s))
    if len(k_seg):
        kappa[:-1] = np.abs(k_seg)
        kappa[1:] = np.maximum(kappa[1:], np.abs(k_seg))
    return s, kappa


@functools.lru_cache(maxsize=8)
def _discs(vehicle: VehicleParams) -> tuple[np.ndarray, float]:
    offsets, radius = cover_discs(vehicle, 3)
    return np.asarray(offsets, dtype=float), float(radius)


def traffic_conflicts(
    poses: np.ndarray,
    t_lo: np.ndarray,
    t_hi: np.ndarray,
    prediction: Prediction,
    safety: SafetyConfig,
    vehicle: VehicleParams,
    spacing: float = 0.0,
) -> np.ndarray:
    """True where the ego at a rear-axle pose may meet a predicted vehicle in its time band.

    The ego body is covered by three discs (grown by ``spacing / 2``); each other
    vehicle by the capsule around its centre line from its rear bumper at
    ``t_lo - margin(t_lo)`` to its front bumper at ``t_hi + margin(t_hi)``
    (radius half its width), over both hypotheses when the prediction has an
    ``alt``. A pose conflicts when a disc comes within ``buffer(t_hi)`` of a capsule.

    Parameters
    ----------
    poses : numpy.ndarray
        ``(N, 3)`` rear-axle poses.
    t_lo, t_hi : numpy.ndarray
        ``(N,)`` earliest and latest arrival times (seconds after the prediction).
    prediction : Prediction
        The other vehicles.
    safety : SafetyConfig
        Buffer and time margin.
    vehicle : VehicleParams
        The ego car.
    spacing : float
        Distance to the neighbouring tested poses (metres).

    Returns
    -------
    numpy.ndarray
        Boolean ``(N,)``.

    Examples
    --------
    >>> car = Prediction.constant_velocity(np.array([[20.0, 0.0, 0.0, 5.0]]), [(4.3, 1.8)], 5.0)
    >>> poses = np.array([[40.0, 0.0, 0.0], [40.0, 0.0, 0.0]])
    >>> traffic_conflicts(poses, np.array([0.0, 4.0]), np.array([0.0, 4.0]), car,
    ...                   SafetyConfig(), VehicleParams()).tolist()  # it reaches x = 40 at 4 s
    [False, True]
    """
    p = np.asarray(poses, dtype=float).reshape(-1, 3)
    n = len(p)
    pred = prediction
    if n == 0 or len(pred) == 0:
        return np.zeros(n, dtype=bool)
    offsets, radius = _discs(vehicle)
    t_lo = np.asarray(t_lo, dtype=float).reshape(-1)
    t_hi = np.asarray(t_hi, dtype=float).reshape(-1)
    lo = t_lo - safety.margin(t_lo)
    hi = t_hi + safety.margin(t_hi)
    # Disc centres, (N, M) per coordinate.
    c, s = np.cos(p[:, 2]), np.sin(p[:, 2])
    dx = p[:, 0:1] + c[:, None] * offsets[None, :]
    dy = p[:, 1:2] + s[:, None] * offsets[None, :]
    sizes = pred.sizes
    track = pred.poses
    alt = pred.alt
    step = pred.step
    grow = radius + 0.5 * spacing + float(safety.buffer(float(t_hi.max())))
    # Screen: each vehicle's box over the whole time span against the discs' box.
    ends = np.array([max(float(lo.min()), 0.0), float(hi.max())])
    span = _poses_at(track, step, ends)
    if alt is not None:
        span = np.concatenate([span, _poses_at(alt, step, ends)], axis=1)
    reach = grow + 0.5 * (sizes[:, 0] + sizes[:, 1])
    keep = (
        (span[:, :, 0].max(axis=1) + reach >= dx.min())
        & (span[:, :, 0].min(axis=1) - reach <= dx.max())
        & (span[:, :, 1].max(axis=1) + reach >= dy.min())
        & (span[:, :, 1].min(axis=1) - reach <= dy.max())
    )
    if not keep.any():
        return np.zeros(n, dtype=bool)
    if not keep.all():
        track, sizes = track[keep], sizes[keep]
        alt = None if alt is None else alt[keep]
    a_pose = _poses_at(track, step, lo)  # (K, N, 3)
    b_pose = _poses_at(track, step, hi)
    ux, uy = np.cos(b_pose[..., 2]), np.sin(b_pose[..., 2])  # (K, N)
    half_len = (sizes[:, 0] / 2.0)[:, None]
    # Extent along the heading of every predicted centre in the band (both hypotheses).
    ox, oy = a_pose[..., 0], a_pose[..., 1]
    along = [np.zeros_like(ox), (b_pose[..., 0] - ox) * ux + (b_pose[..., 1] - oy) * uy]
    if alt is not None:
        for other in (_poses_at(alt, step, lo), _poses_at(alt, step, hi)):
            along.append((other[..., 0] - ox) * ux + (other[..., 1] - oy) * uy)
    first = np.minimum.reduce(along) - half_len
    last = np.maximum.reduce(along) + half_len
    ax = ox + first * ux
    ay = oy + first * uy
    abx = (last - first) * ux
    aby = (last - first) * uy
    ab2 = np.maximum(abx * abx + aby * aby, 1e-12)[..., None]  # (K, N, 1)
    apx = dx[None, :, :] - ax[..., None]  # (K, N, M)
    apy = dy[None, :, :] - ay[..., None]
    frac = np.clip((apx * abx[..., None] + apy * aby[..., None]) / ab2, 0.0, 1.0)
    ex = apx - frac * abx[..., None]
    ey = apy - frac * aby[..., None]
    limit = (
        radius
        + 0.5 * spacing
        + (sizes[:, 1] / 2.0)[:, None, None]
        + safety.buffer(t_hi)[None, :, None]
    )
    return np.any(ex * ex + ey * ey < limit * limit, axis=(0, 2))


class SpaceTimeChecker:
    """A static checker plus predicted vehicles: every answer also asks "and nobody is there then".

    It offers what the improved planner and the post-processor call on a
    :class:`~rrtdrive.collision.CollisionChecker` (``edge_free``, ``pose_free``,
    ``poses_free``, ``poses_free_fast``, ``path_free``) and delegates every other
    attribute (the clearance field, connectivity labels, bounds, obstacles, the
    car) to the static checker, so a planner that only knows the static interface
    plans in space-time without changes.

    Parameters
    ----------
    static : CollisionChecker
        The road's checker (bounds and static obstacles).
    prediction : Prediction
        The other vehicles, in the same frame as the checker.
    timing : ArrivalTiming
        Arrival times of points (edges, nodes, poses of unknown paths).
    safety : SafetyConfig
        Buffers in space and time.
    speed : tuple of float
        ``(v_max, accel, decel, a_lat_max, v_launch)`` of the speed profile, for
        the exact times along whole paths (:meth:`path_free`).
    spacing : float
        Largest distance between the poses tested along an edge (metres); the
        discs grow by half of it.
    slack_s : float
        Extra half-width of the time band in :meth:`path_free`, so that a path that
        passes here also passes a final check with slightly different timing (the
        controller's own profile, from the car's current speed).
    deadline : float, optional
        A :func:`time.perf_counter` value after which every test answers "not
        free", so that a planner running on this checker (its post-processing is
        bounded by rounds, not time) gives up within a wall-time budget.
    """

    def __init__(
        self,
        static: CollisionChecker,
        prediction: Prediction,
        timing: ArrivalTiming,
        safety: SafetyConfig | None = None,
        speed: tuple[float, float, float, float, float] = (10.0, 1.0, 1.0, 1.5, 0.5),
        spacing: float = 0.5,
        slack_s: float = 0.2,
        deadline: float | None = None,
    ) -> None:
        self.static = static
        self.prediction = prediction
        self.timing = timing
        self.safety = safety or SafetyConfig()
        self.speed = tuple(float(v) for v in speed)
        require_positive("spacetime.spacing", spacing)
        self.spacing = float(spacing)
        require_finite("spacetime.slack_s", slack_s)
        self.slack_s = max(float(slack_s), 0.0)
        self.deadline = deadline
        self.expired = False
        self.dynamic_checks = 0

    def _late(self) -> bool:
        """True (and remembered) once the deadline has passed."""
        if self.deadline is not None and not self.expired:
            self.expired = time.perf_counter() >= self.deadline
        return self.expired

    def __getattr__(self, name: str) -> Any:
        # Only called for attributes not found here: the static checker's.
        if name == "static":
            raise AttributeError(name)
        return getattr(self.static, name)

    # ------------------------------------------------------------------ dynamic core

    def conflicts(
        self,
        poses: np.ndarray,
        t_lo: np.ndarray,
        t_hi: np.ndarray,
        spacing: float = 0.0,
    ) -> np.ndarray:
        """:func:`traffic_conflicts` of ``poses`` with this checker's prediction and safety."""
        self.dynamic_checks += 1
        return traffic_conflicts(
            poses, t_lo, t_hi, self.prediction, self.safety, self.static.vehicle, spacing
        )

    def clear_of_traffic(self, poses: np.ndarray, spacing: float = 0.0) -> np.ndarray:
        """True where a pose, reached at its nominal arrival time, is clear of every vehicle."""
        p = np.asarray(poses, dtype=float).reshape(-1, 3)
        lo, hi = self.timing.band(p[:, :2])
        return ~self.conflicts(p, lo, hi, spacing)

    # ------------------------------------------------------------------ checker interface

    def edge_free(self, a: Sequence[float], b: Sequence[float]) -> bool:
        """Static edge test, then the body along the edge against traffic at its arrival times."""
        if self._late() or not self.static.edge_free(a, b):
            return False
        if len(self.prediction) == 0:
            return True
        ax, ay = float(a[0]), float(a[1])
        dx, dy = float(b[0]) - ax, float(b[1]) - ay
        length = math.hypot(dx, dy)
        yaw = math.atan2(dy, dx) if length > 1e-9 else 0.0
        n = max(2, int(math.ceil(length / self.spacing)) + 1)
        f = np.linspace(0.0, 1.0, n)
        poses = np.column_stack([ax + f * dx, ay + f * dy, np.full(n, yaw)])
        step = length / (n - 1)
        return bool(np.all(self.clear_of_traffic(poses, step)))

    def pose_free(self, pose: Sequence[float]) -> bool:
        """Exact static body test and the traffic test at the pose's arrival time."""
        if self._late() or not self.static.pose_free(pose):
            return False
        p = np.asarray(pose, dtype=float)[:3]
        return bool(self.clear_of_traffic(p[None, :])[0])

    def poses_free(self, poses: np.ndarray, clearance: float = 0.0) -> np.ndarray:
        """:meth:`CollisionChecker.poses_free` and the traffic test at nominal arrival times."""
        p = np.asarray(poses, dtype=float).reshape(-1, 3)
        if self._late():
            return np.zeros(len(p), dtype=bool)
        return self.static.poses_free(p, clearance) & self.clear_of_traffic(p)

    def poses_free_fast(self, poses: np.ndarray, clearance: float = 0.0) -> np.ndarray:
        """:meth:`CollisionChecker.poses_free_fast` and the traffic test (conservative)."""
        p = np.asarray(poses, dtype=float).reshape(-1, 3)
        if self._late():
            return np.zeros(len(p), dtype=bool)
        return self.static.poses_free_fast(p, clearance) & self.clear_of_traffic(p)

    def path_times(self, samples: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Arrival times along a path by its speed profile (exact, from its first sample).

        The path starts at the time and speed the nominal timing gives its first
        sample (:meth:`ArrivalTiming.state_at`: the timing's own ``t0`` and ``v0``
        when it starts at the origin).

        Returns
        -------
        t, v : numpy.ndarray
            Seconds after the prediction, and speeds, at each sample.
        """
        smp = np.asarray(samples, dtype=float)
        s, kappa = _yaw_curvature(smp)
        t0, v0 = self.timing.state_at(smp[0, :2])
        v_max, accel, decel, a_lat, v_launch = self.speed
        t, v = profile_times(s, kappa, v0, v_max, accel, decel, a_lat, v_launch)
        return t0 + t, v

    def path_free(
        self, samples: np.ndarray, spacing: float = 0.1, clearance: float = 0.0
    ) -> tuple[bool, np.ndarray]:
        """Exact static path test, then the path timed by its speed profile against traffic.

        The path is taken to start at the timing's origin at its time ``t0`` and
        speed ``v0``; every sample is tested at its arrival time, within the
        safety band.

        Returns
        -------
        ok : bool
            True when the path is clear of obstacles and of traffic.
        bad : numpy.ndarray
            Indices of segments ``i -> i+1`` with a colliding pose.
        """
        smp = np.asarray(samples, dtype=float)
        if self._late():
            return False, np.arange(max(len(smp) - 1, 0), dtype=np.int64)
        ok, bad = self.static.path_free(samples, spacing=spacing, clearance=clearance)
        if len(self.prediction) == 0 or len(smp) == 0:
            return ok, bad
        t, _ = self.path_times(smp)
        step = float(np.max(np.hypot(*np.diff(smp[:, :2], axis=0).T), initial=0.0))
        hit = self.conflicts(smp[:, :3], t - self.slack_s, t + self.slack_s, step)
        if not hit.any():
            return ok, bad
        idx = np.flatnonzero(hit)
        seg = np.unique(np.concatenate([np.maximum(idx - 1, 0), np.minimum(idx, len(smp) - 2)]))
        return False, np.unique(np.concatenate([bad, seg])).astype(np.int64)


# ----------------------------------------------------------------------------- planner


@dataclass(frozen=True, eq=False)
class SpaceTimeProblem:
    """One space-time query: a static map with its start and goal, the traffic, the timing.

    Attributes
    ----------
    map : Map
        Road bounds and static obstacles, with the start and goal (rear-axle poses).
    prediction : Prediction
        Other vehicles in the map's frame.
    timing : ArrivalTiming
        When the car is where (origin at the start position).
    safety : SafetyConfig
        Buffers.
    speed : tuple of float
        ``(v_max, accel, decel, a_lat_max, v_launch)`` of the controller's profile.
    deadline : float, optional
        :func:`time.perf_counter` value at which the whole query (growth and
        post-processing) gives up (see :class:`SpaceTimeChecker`); ``None``: only
        the budget's limits apply.
    """

    map: Map
    prediction: Prediction
    timing: ArrivalTiming
    safety: SafetyConfig = field(default_factory=SafetyConfig)
    speed: tuple[float, float, float, float, float] = (10.0, 1.0, 1.0, 1.5, 0.5)
    deadline: float | None = None

    @property
    def start(self) -> Pose:
        """Rear-axle start pose."""
        return self.map.start

    @property
    def goal(self) -> Pose:
        """Rear-axle goal pose."""
        return self.map.goal

    @property
    def vehicle(self) -> VehicleParams:
        """The car."""
        return self.map.vehicle


@dataclass(frozen=True, eq=False)
class SpaceTimePlan:
    """A space-time planning result.

    Attributes
    ----------
    result : PlanResult
        The improved planner's result on the space-time checker (its path is in
        the problem's frame).
    times : numpy.ndarray
        Arrival time at each path sample (seconds after the prediction), empty on failure.
    speeds : numpy.ndarray
        Profile speed at each path sample.
    tree_times : tuple of numpy.ndarray
        Nominal arrival time of every node of each tree (earliest of the band).
    dynamic_checks : int
        Calls of the traffic test.
    wall_time_s : float
        Wall time of the whole query.
    deadline_hit : bool
        The problem's deadline passed during the query (the result is then a failure).
    """

    result: PlanResult
    times: np.ndarray
    speeds: np.ndarray
    tree_times: tuple[np.ndarray, ...]
    dynamic_checks: int
    wall_time_s: float
    deadline_hit: bool = False

    @property
    def success(self) -> bool:
        """True when a verified space-time path was found."""
        return self.result.success


#: Components that rely on the static obstacles alone and are off in space-time:
#: the expanded checker is built from the static rectangles (it would lose the
#: traffic) and passage sampling looks for narrow static passages (a road has none).
#: The Dubins fallback is off too: it checks poses without the tree's arrival
#: times, and on a road a lane change never needs to turn round.
STATIC_ONLY = ("obstacle_expansion", "passage_sampling", "dubins_fallback")


class SpaceTimeRRTConnect(ImprovedRRTConnect):
    """The improved RRT-Connect on a :class:`SpaceTimeChecker`: moving vehicles by arrival time.

    Every edge the trees grow, the direct connection, the pruning and repair
    edges of the post-processor and the B-spline's exact check run against the
    predicted vehicles at the car's arrival times (:class:`SpaceTimeChecker`); the
    rest is :class:`~rrtdrive.planning.improved.ImprovedRRTConnect` unchanged.
    Tree nodes carry the nominal arrival time of :class:`ArrivalTiming`; the
    final path carries the exact times of its speed profile.

    Parameters
    ----------
    config : ImprovedConfig, optional
        As for the improved planner; ``obstacle_expansion``,
        ``passage_sampling`` and ``dubins_fallback`` default to off
        (:data:`STATIC_ONLY`).
    disable : iterable of str, optional
        Components to switch off.
    **options
        :class:`~rrtdrive.planning.improved.ImprovedConfig` fields.

    Examples
    --------
    >>> from rrtdrive.maps import Map
    >>> road = Map("road", (0.0, 42.0, 70.0, 50.0), (), Pose(2.0, 44.0, 0.0), Pose(58.0, 44.0, 0.0))
    >>> lead = Prediction.constant_velocity(np.array([[18.0, 44.0, 0.0, 2.0]]), [(4.3, 1.8)], 12.0)
    >>> timing = ArrivalTiming(0.0, 4.0, 10.0, 1.5, (2.0, 44.0))
    >>> plan = SpaceTimeRRTConnect().solve_spacetime(
    ...     SpaceTimeProblem(road, lead, timing, speed=(10.0, 1.5, 1.0, 1.5, 0.5)),
    ...     np.random.default_rng(0), Budget(max_iterations=3000))
    >>> plan.success, bool(plan.result.path.samples[:, 1].max() > 46.0)  # around the slow car
    (True, True)
    """

    name = "spacetime-rrt-connect"

    def __init__(
        self,
        config: ImprovedConfig | None = None,
        *,
        disable: Iterable[str] = (),
        **options: object,
    ) -> None:
        if config is None:
            defaults = {k: False for k in STATIC_ONLY if k not in options}
            config = dataclasses.replace(ImprovedConfig(), **defaults)  # type: ignore[arg-type]
        super().__init__(config, disable=disable, **options)

    def __repr__(self) -> str:
        return f"SpaceTimeRRTConnect({self.config!r})"

    def checker_for(self, problem: SpaceTimeProblem) -> SpaceTimeChecker:
        """The space-time checker of ``problem`` (static part cached per road)."""
        static = cached_checker(problem.map)
        return SpaceTimeChecker(
            static, problem.prediction, problem.timing, problem.safety, problem.speed,
            deadline=problem.deadline,
        )

    def solve_spacetime(
        self, problem: SpaceTimeProblem, rng: np.random.Generator, budget: Budget
    ) -> SpaceTimePlan:
        """Plan from the start to the goal clear of the road and of the predicted traffic.

        Parameters
        ----------
        problem : SpaceTimeProblem
            Road, query, traffic and timing.
        rng : numpy.random.Generator
            The only source of randomness.
        budget : Budget
            Iteration and wall-time limits of the tree growth.

        Returns
        -------
        SpaceTimePlan
            On success the path (in the problem's frame) with its arrival times;
            the times are checked once more against the traffic, so a path whose
            exact times conflict is returned as a failure.
        """
        if not isinstance(problem, SpaceTimeProblem):
            raise InputError(
                f"problem: expected a SpaceTimeProblem, got {type(problem).__name__}"
            )
        t0 = time.perf_counter()
        checker = self.checker_for(problem)
        inner = PlanningProblem(problem.map, checker, problem.start, problem.goal, problem.vehicle)
        res = ImprovedRRTConnect.solve(self, inner, rng, budget)
        tree_times = tuple(checker.timing.band(t.nodes)[0] for t in res.trees)
        times = speeds = np.zeros(0)
        if checker.expired:
            res = dataclasses.replace(
                res,
                status=PlanStatus.NO_PATH_IN_BUDGET,
                path=Path.empty(),
                message=f"deadline passed ({res.message})",
            )
        if res.success:
            times, speeds = checker.path_times(res.path.samples)
            hit = checker.conflicts(res.path.samples[:, :3], times, times, 0.25)
            if hit.any():
                i = int(np.flatnonzero(hit)[0])
                x, y = res.path.samples[i, :2]
                res = dataclasses.replace(
                    res,
                    status=PlanStatus.POSTPROCESS_FAILED,
                    message=f"traffic conflict at ({x:.1f}, {y:.1f}) on the final check",
                )
                times = speeds = np.zeros(0)
        return SpaceTimePlan(
            res, times, speeds, tree_times, checker.dynamic_checks, time.perf_counter() - t0,
            checker.expired,
        )

    def solve(
        self, problem: PlanningProblem, rng: np.random.Generator, budget: Budget
    ) -> PlanResult:
        """The improved planner; a :class:`SpaceTimeProblem` goes to :meth:`solve_spacetime`."""
        if isinstance(problem, SpaceTimeProblem):
            return self.solve_spacetime(problem, rng, budget).result
        return ImprovedRRTConnect.solve(self, problem, rng, budget)
