"""The space-time checker: the static checker's answers and "nobody is there then"."""

from __future__ import annotations

import math
import time
from collections.abc import Sequence

import numpy as np
import shapely

from rrtdrive.collision import CheckerConfig, CollisionChecker
from rrtdrive.maps import Obstacle
from rrtdrive.planning.spacetime.conflicts import traffic_conflicts
from rrtdrive.planning.spacetime.prediction import Prediction
from rrtdrive.planning.spacetime.safety import SafetyConfig
from rrtdrive.planning.spacetime.timing import ArrivalTiming, yaw_curvature
from rrtdrive.speed_profile import profile_times, steering_rate_speed_cap
from rrtdrive.types import InputError, VehicleParams, require_finite, require_positive
from rrtdrive.vehicle import cover_discs

__all__ = ["SpaceTimeChecker"]


class SpaceTimeChecker:
    """A static checker plus predicted vehicles: every answer also asks "and nobody is there then".

    It implements :class:`rrtdrive.checking.Checker` explicitly. The pose and
    motion tests (``edge_free``, ``pose_free``, ``poses_free``,
    ``poses_free_fast``, ``path_free``) are the static checker's answers *and* the
    traffic test at the arrival times, so they are never more permissive than the
    static ones. The map and grid data (bounds, obstacles, the clearance field,
    connectivity labels, sampler and passage cells, the obstacle union, set-up
    time) and ``body_clearance`` are the static checker's: they describe the road,
    which is what samplers and the post-processor's geometry need.

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
    steering : tuple of float, optional
        ``(max_steer_rate, share)`` of a car with a rate-limited steering actuator:
        whole paths are then timed as the controllers drive them, their speed also
        capped by :func:`~rrtdrive.speed_profile.steering_rate_speed_cap` (the car's
        wheelbase, ``share`` of the rate); ``None``: an instant actuator.
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
        steering: tuple[float, float] | None = None,
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
        if steering is not None:
            rate, share = (float(v) for v in steering)
            if not rate > 0.0:
                raise InputError(f"spacetime.steering rate: must be > 0, got {rate!r}")
            if not 0.0 < share <= 1.0:
                raise InputError(f"spacetime.steering share: must lie in (0, 1], got {share!r}")
            steering = None if math.isinf(rate) else (rate, share)
        self.steering = steering
        self.expired = False
        self.dynamic_checks = 0
        # The ego's covering discs, once per checker (the conflict test's hot path).
        offsets, radius = cover_discs(static.vehicle, 3)
        self._discs = (np.asarray(offsets, dtype=float), float(radius))

    def _late(self) -> bool:
        """True (and remembered) once the deadline has passed."""
        if self.deadline is not None and not self.expired:
            self.expired = time.perf_counter() >= self.deadline
        return self.expired


    # ------------------------------------------------------------------ dynamic core

    def conflicts(
        self,
        poses: np.ndarray,
        t_lo: np.ndarray,
        t_hi: np.ndarray,
        spacing: float = 0.0,
    ) -> np.ndarray:
        """:func:`traffic_conflicts` of ``poses`` with this checker's prediction and safety.

        Parameters
        ----------
        poses : numpy.ndarray
            ``(N, 3)`` rear-axle poses.
        t_lo, t_hi : numpy.ndarray
            ``(N,)`` earliest and latest arrival times (seconds after the prediction).
        spacing : float
            Distance to the neighbouring tested poses in metres (the discs grow by half).

        Returns
        -------
        numpy.ndarray
            Boolean ``(N,)``: True where a pose may meet a predicted vehicle.
        """
        self.dynamic_checks += 1
        return traffic_conflicts(
            poses, t_lo, t_hi, self.prediction, self.safety, self.static.vehicle, spacing,
            discs=self._discs,
        )

    def clear_of_traffic(self, poses: np.ndarray, spacing: float = 0.0) -> np.ndarray:
        """True where a pose, reached at its nominal arrival time, is clear of every vehicle.

        Parameters
        ----------
        poses : numpy.ndarray
            ``(N, 3)`` rear-axle poses, timed by :meth:`ArrivalTiming.band`.
        spacing : float
            Distance to the neighbouring tested poses in metres (as :meth:`conflicts`).

        Returns
        -------
        numpy.ndarray
            Boolean ``(N,)``.
        """
        p = np.asarray(poses, dtype=float).reshape(-1, 3)
        lo, hi = self.timing.band(p[:, :2])
        return ~self.conflicts(p, lo, hi, spacing)

    # ------------------------------------------------------------------ map and grid data (static)

    @property
    def vehicle(self) -> VehicleParams:
        """The car (the static checker's)."""
        return self.static.vehicle

    @property
    def bounds(self) -> tuple[float, ...]:
        """``(xmin, ymin, xmax, ymax)`` of the road."""
        return self.static.bounds

    @property
    def obstacles(self) -> tuple[Obstacle, ...]:
        """The static obstacles (traffic is in :attr:`prediction`)."""
        return self.static.obstacles

    @property
    def config(self) -> CheckerConfig:
        """The static checker's grid resolution and margins."""
        return self.static.config

    @property
    def edge_radius(self) -> float:
        """Radius of the static edge test's capsule, metres."""
        return self.static.edge_radius

    @property
    def resolution(self) -> float:
        """Grid cell size in metres."""
        return self.static.resolution

    @property
    def grid_origin(self) -> np.ndarray:
        """World position of the static grid's lower-left corner."""
        return self.static.grid_origin

    @property
    def clearance_grid(self) -> np.ndarray:
        """The static clearance field (traffic not included)."""
        return self.static.clearance_grid

    @property
    def component_labels(self) -> np.ndarray:
        """Static connectivity labels (traffic moves, so it never disconnects for good)."""
        return self.static.component_labels

    @property
    def obstacle_union(self) -> shapely.Geometry:
        """The prepared union of the static obstacles."""
        return self.static.obstacle_union

    @property
    def setup_time_s(self) -> float:
        """The static checker's grid set-up time (nothing here is built ahead)."""
        return self.static.setup_time_s

    def clearance(self, x: float, y: float) -> float:
        """Static clearance lower bound at ``(x, y)`` (see :meth:`CollisionChecker.clearance`).

        Parameters
        ----------
        x, y : float
            Position in metres.

        Returns
        -------
        float
            Metres; negative or ``-inf`` where possibly inside an obstacle or outside.
        """
        return self.static.clearance(x, y)

    def clearances(self, points: np.ndarray) -> np.ndarray:
        """Static clearance lower bounds of ``(N, 2)`` points.

        Parameters
        ----------
        points : numpy.ndarray
            ``(N, 2)`` positions in metres.

        Returns
        -------
        numpy.ndarray
            ``(N,)`` clearances in metres (as :meth:`clearance`).
        """
        return self.static.clearances(points)

    def point_free(self, x: float, y: float) -> bool:
        """The static sampling condition (necessary; traffic passes, so it is ignored here).

        Parameters
        ----------
        x, y : float
            Rear-axle position in metres.

        Returns
        -------
        bool
            True when the car could stand there with some heading.
        """
        return self.static.point_free(x, y)

    def provably_disconnected(self, a: Sequence[float], b: Sequence[float]) -> bool:
        """Static proof of unreachability (traffic cannot make a proof, it moves on).

        Parameters
        ----------
        a, b : sequence of float
            Rear-axle positions ``(x, y, ...)``.

        Returns
        -------
        bool
            True is a proof that no motion joins them; False proves nothing.
        """
        return self.static.provably_disconnected(a, b)

    def too_narrow_between(
        self, a: Sequence[float], b: Sequence[float], keep: float = 0.0
    ) -> bool:
        """The static map's exact proof that every way from ``a`` to ``b`` is too narrow.

        Parameters
        ----------
        a, b : sequence of float
            Rear-axle positions ``(x, y, ...)``.
        keep : float
            Body clearance the car keeps, metres.

        Returns
        -------
        bool
            True is a proof; False proves nothing.
        """
        return self.static.too_narrow_between(a, b, keep)

    def free_cells(self, start: Sequence[float]) -> np.ndarray:
        """The static checker's sampler cells connected to ``start``.

        Parameters
        ----------
        start : sequence of float
            Start position ``(x, y)``.

        Returns
        -------
        numpy.ndarray
            Flat indices into the clearance grid (see :meth:`CollisionChecker.free_cells`).
        """
        return self.static.free_cells(start)

    def passage_cells(self, start: Sequence[float], width: float = 0.6) -> np.ndarray:
        """The static checker's narrow-passage cells reachable from ``start``.

        Parameters
        ----------
        start : sequence of float
            A point of the component to keep (the start position).
        width : float
            How much wider than the edge test a passage may be, in metres.

        Returns
        -------
        numpy.ndarray
            ``(K, 2)`` cell centres (possibly empty).
        """
        return self.static.passage_cells(start, width)

    def body_clearance(self, pose: Sequence[float]) -> float:
        """Exact distance from the body at ``pose`` to the static obstacles or bounds.

        Static only, as the contract says: traffic has no distance without a time.

        Parameters
        ----------
        pose : sequence of float
            Rear-axle pose ``(x, y, yaw)``.

        Returns
        -------
        float
            Metres; 0 when the body touches an obstacle or leaves the bounds.
        """
        return self.static.body_clearance(pose)

    # ------------------------------------------------------------------ pose and motion tests

    def edge_free(self, a: Sequence[float], b: Sequence[float]) -> bool:
        """Static edge test, then the body along the edge against traffic at its arrival times.

        Parameters
        ----------
        a, b : sequence of float
            Rear-axle positions of the edge's ends (the heading is along the edge);
            poses are tested at most ``spacing`` apart.

        Returns
        -------
        bool
            False also once the deadline has passed.
        """
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
        """Exact static body test and the traffic test at the pose's arrival time.

        Parameters
        ----------
        pose : sequence of float
            Rear-axle pose ``(x, y, yaw)``.

        Returns
        -------
        bool
            False also once the deadline has passed.
        """
        if self._late() or not self.static.pose_free(pose):
            return False
        p = np.asarray(pose, dtype=float)[:3]
        return bool(self.clear_of_traffic(p[None, :])[0])

    def poses_free(self, poses: np.ndarray, clearance: float = 0.0) -> np.ndarray:
        """:meth:`CollisionChecker.poses_free` and the traffic test at nominal arrival times.

        Parameters
        ----------
        poses : numpy.ndarray
            ``(N, 3)`` rear-axle poses.
        clearance : float
            Distance the body must keep from static obstacles and bounds, metres.

        Returns
        -------
        numpy.ndarray
            Boolean ``(N,)``; all False once the deadline has passed.
        """
        p = np.asarray(poses, dtype=float).reshape(-1, 3)
        if self._late():
            return np.zeros(len(p), dtype=bool)
        return self.static.poses_free(p, clearance) & self.clear_of_traffic(p)

    def poses_free_fast(self, poses: np.ndarray, clearance: float = 0.0) -> np.ndarray:
        """:meth:`CollisionChecker.poses_free_fast` and the traffic test (conservative).

        Parameters
        ----------
        poses : numpy.ndarray
            ``(N, 3)`` rear-axle poses.
        clearance : float
            Extra distance the body must keep from static obstacles and bounds, metres.

        Returns
        -------
        numpy.ndarray
            Boolean ``(N,)``; True means provably clear; all False once the deadline has passed.
        """
        p = np.asarray(poses, dtype=float).reshape(-1, 3)
        if self._late():
            return np.zeros(len(p), dtype=bool)
        return self.static.poses_free_fast(p, clearance) & self.clear_of_traffic(p)

    def path_times(self, samples: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Arrival times along a path by its speed profile (exact, from its first sample).

        The path starts at the time and speed the nominal timing gives its first
        sample (:meth:`ArrivalTiming.state_at`: the timing's own ``t0`` and ``v0``
        when it starts at the origin). With a rate-limited actuator (``steering``)
        the speed is also capped by the steering rate, as the controllers cap it.

        Parameters
        ----------
        samples : numpy.ndarray
            ``(N, >=3)`` rows ``x, y, yaw`` (a fourth column, when not all zero, is the
            curvature).

        Returns
        -------
        t, v : numpy.ndarray
            Seconds after the prediction, and speeds, at each sample.
        """
        smp = np.asarray(samples, dtype=float)
        s, kappa = yaw_curvature(smp)
        t0, v0 = self.timing.state_at(smp[0, :2])
        v_max, accel, decel, a_lat, v_launch = self.speed
        cap = None
        if self.steering is not None:
            rate, share = self.steering
            cap = steering_rate_speed_cap(s, kappa, self.static.vehicle.wheelbase, rate, share)
        t, v = profile_times(s, kappa, v0, v_max, accel, decel, a_lat, v_launch, cap)
        return t0 + t, v

    def path_free(
        self, samples: np.ndarray, spacing: float = 0.1, clearance: float = 0.0
    ) -> tuple[bool, np.ndarray]:
        """Exact static path test, then the path timed by its speed profile against traffic.

        The path is taken to start at the timing's origin at its time ``t0`` and
        speed ``v0``; every sample is tested at its arrival time, within the
        safety band.

        Parameters
        ----------
        samples : numpy.ndarray
            ``(N, >=3)`` rows ``x, y, yaw, ...``.
        spacing : float
            Largest distance between the poses of the static test, metres.
        clearance : float
            Distance the body must keep from static obstacles and bounds, metres.

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
