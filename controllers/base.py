"""The controller seam: vehicle state, the Controller protocol, and a fast path projector.

Every controller tracks a :class:`rrtdrive.types.Path` (rear-axle samples
``[x, y, yaw, kappa]``) on the same kinematic bicycle (:class:`VehicleParams`).
``control`` runs once per simulation step, so the projector works in plain
Python on lists with a local search from the previous match (no numpy per step).
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np

from rrtdrive.controllers.speed import SpeedConfig, SpeedController, SpeedProfile
from rrtdrive.geometry import wrap_angle
from rrtdrive.speed_profile import actuator_profile
from rrtdrive.types import InputError, Path, VehicleParams, require_finite, require_positive

__all__ = [
    "VehicleState",
    "Controller",
    "Projection",
    "PathProjector",
    "TrackingController",
]

@dataclass(frozen=True)
class VehicleState:
    """What a controller sees each step: the rear-axle pose, speed and current steering.

    Parameters
    ----------
    x, y, yaw : float
        Rear-axle pose (metres, radians).
    speed : float
        Longitudinal speed in m/s.
    steer : float
        Front-wheel angle applied in the last step, radians.
    t : float
        Simulation time in seconds.
    """

    x: float
    y: float
    yaw: float
    speed: float = 0.0
    steer: float = 0.0
    t: float = 0.0


@runtime_checkable
class Controller(Protocol):
    """A path-tracking controller on the kinematic bicycle."""

    name: str

    def reset(self, path: Path) -> None:
        """Start tracking ``path`` (clears all internal state)."""
        ...

    def control(self, state: VehicleState) -> tuple[float, float]:
        """Return ``(acceleration m/s^2, steering angle rad)`` for ``state``."""
        ...


@dataclass(frozen=True)
class Projection:
    """A point projected on the path.

    Attributes
    ----------
    index : int
        Index of the segment start sample.
    s : float
        Arc length of the foot point (may run past either end on the extensions).
    x, y, yaw, kappa : float
        Foot point, path heading and curvature there.
    cte : float
        Signed lateral offset of the point from the path, positive to the left.
    """

    index: int
    s: float
    x: float
    y: float
    yaw: float
    kappa: float
    cte: float


class PathProjector:
    """Projects points on a sampled path; beyond either end the path runs straight on.

    Parameters
    ----------
    path : Path
        At least two samples.

    Examples
    --------
    >>> xs = np.linspace(0.0, 10.0, 41)
    >>> p = Path(np.column_stack([xs, 0 * xs, 0 * xs, 0 * xs]), np.zeros((0, 2)))
    >>> pr = PathProjector(p).project(3.1, 0.5)
    >>> round(pr.s, 6), round(pr.cte, 6)
    (3.1, 0.5)
    """

    def __init__(self, path: Path) -> None:
        samples = np.asarray(path.samples, dtype=float)
        if samples.ndim != 2 or samples.shape[1] != 5 or len(samples) < 2:
            raise InputError(
                f"path: need at least two samples [x, y, yaw, kappa, gear], got {samples.shape}"
            )
        require_finite("path", *samples.ravel().tolist())
        if not path.is_forward_only:  # every closed loop (runner, re-planner, gym env) gets here
            n = len(path.cusps)
            what = f"has {n} gear change{'s' if n != 1 else ''}" if n else "is driven in reverse"
            raise InputError(
                f"path: {what}; driving in reverse is not supported yet (issue #14)"
            )
        xy = samples[:, :2]
        seg = np.hypot(*np.diff(xy, axis=0).T)
        keep = np.concatenate([[True], seg > 1e-9])  # drop repeated samples
        samples = samples[keep]
        if len(samples) < 2:
            raise InputError("path: all samples coincide")
        self.samples = samples
        self.x = samples[:, 0].tolist()
        self.y = samples[:, 1].tolist()
        self.yaw = np.unwrap(samples[:, 2]).tolist()
        self.kappa = samples[:, 3].tolist()
        s = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(samples[:, :2], axis=0).T))])
        self.s = s.tolist()
        self.length = float(s[-1])
        self.n = len(self.x)
        # Segment directions (unit) for projection.
        d = np.diff(samples[:, :2], axis=0)
        norm = np.hypot(d[:, 0], d[:, 1])
        self.ux = (d[:, 0] / norm).tolist()
        self.uy = (d[:, 1] / norm).tolist()
        self.seg_len = norm.tolist()
        self.hint = 0

    def reset_hint(self, index: int = 0) -> None:
        """Restart the local search at segment ``index``."""
        self.hint = max(0, min(index, self.n - 2))

    def _seg_dist2(self, i: int, px: float, py: float) -> float:
        dx, dy = px - self.x[i], py - self.y[i]
        t = dx * self.ux[i] + dy * self.uy[i]
        if t < 0.0:
            t = 0.0
        elif t > self.seg_len[i]:
            t = self.seg_len[i]
        ex, ey = dx - t * self.ux[i], dy - t * self.uy[i]
        return ex * ex + ey * ey

    def nearest_segment(self, px: float, py: float) -> int:
        """Index of the segment nearest to ``(px, py)``, by local descent from the last match.

        Walks forward while the next segment is at least as near, else backward while
        the previous one is nearer: a few evaluations per control step, and progress
        stays continuous even where the path comes back near itself.
        """
        i = self.hint
        last = self.n - 2
        d = self._seg_dist2(i, px, py)
        moved = False
        while i < last:
            dn = self._seg_dist2(i + 1, px, py)
            if dn > d:
                break
            i, d, moved = i + 1, dn, True
        if not moved:
            while i > 0:
                dp = self._seg_dist2(i - 1, px, py)
                if dp >= d:
                    break
                i, d = i - 1, dp
        self.hint = i
        return i

    def project(self, px: float, py: float) -> Projection:
        """Foot point of ``(px, py)`` on the path (with straight extensions at the ends)."""
        i = self.nearest_segment(px, py)
        dx, dy = px - self.x[i], py - self.y[i]
        ux, uy = self.ux[i], self.uy[i]
        t = dx * ux + dy * uy
        seg = self.seg_len[i]
        if (i == 0 and t < 0.0) or (i == self.n - 2 and t > seg):
            # On the straight extension before the start or past the end.
            end = 0 if t < 0.0 else self.n - 1
            yaw = self.yaw[end]
            c, s_ = math.cos(yaw), math.sin(yaw)
            ex, ey = px - self.x[end], py - self.y[end]
            along = ex * c + ey * s_
            return Projection(
                i, self.s[end] + along, self.x[end] + along * c, self.y[end] + along * s_,
                yaw, 0.0, ey * c - ex * s_,
            )
        if t < 0.0:
            t = 0.0
        elif t > seg:
            t = seg
        frac = t / seg
        yaw = self.yaw[i] + frac * (self.yaw[i + 1] - self.yaw[i])
        kappa = self.kappa[i] + frac * (self.kappa[i + 1] - self.kappa[i])
        # Signed offset from the segment's line, positive to the left of the path.
        cte = ux * dy - uy * dx
        return Projection(i, self.s[i] + t, self.x[i] + t * ux, self.y[i] + t * uy, yaw, kappa, cte)

    def point_at(self, s: float) -> tuple[float, float, float, float]:
        """``(x, y, yaw, kappa)`` at arc length ``s``, straight on past either end."""
        if s <= 0.0:
            yaw = self.yaw[0]
            return (self.x[0] + s * math.cos(yaw), self.y[0] + s * math.sin(yaw), yaw, 0.0)
        if s >= self.length:
            yaw = self.yaw[-1]
            d = s - self.length
            return (self.x[-1] + d * math.cos(yaw), self.y[-1] + d * math.sin(yaw), yaw, 0.0)
        i = bisect.bisect_right(self.s, s) - 1
        i = min(i, self.n - 2)
        frac = (s - self.s[i]) / (self.s[i + 1] - self.s[i])
        return (
            self.x[i] + frac * (self.x[i + 1] - self.x[i]),
            self.y[i] + frac * (self.y[i + 1] - self.y[i]),
            self.yaw[i] + frac * (self.yaw[i + 1] - self.yaw[i]),
            self.kappa[i] + frac * (self.kappa[i + 1] - self.kappa[i]),
        )


class TrackingController:
    """Shared machinery: projection, speed profile and PI loop, steering limit.

    Subclasses implement :meth:`steering`. The steering output is clipped to
    ``steer_limit`` (by default the angle of the path curvature limit,
    ``atan(L * kappa_max)``, so the executed curvature never exceeds ``kappa_max``;
    the actuator's own 30° limit is wider).

    When the car's actuator is rate-limited (``vehicle.max_steer_rate`` finite), the
    controller knows it: the speed profile is also capped by the steering rate
    (``speed.steer_rate_share``), the command is clipped to what the actuator can
    reach in one step from the current angle (``state.steer +- rate * dt``, ``dt``
    the time since the last call; the controllers keep no steering memory, so
    nothing winds up against the limit), at the start of a path the car stays at
    rest until its wheels are within ``speed.start_steer_tol`` of the command, the
    speed loop runs in comfort mode, and :attr:`ff_preview` (the distance driven in
    one step, ``|v| dt``) tells the feed-forward how far ahead to read the path's
    curvature: the actuator turns the wheels linearly over the step after a command,
    so a command reaches its mean one step late. With an instant actuator none of
    this happens.

    Parameters
    ----------
    vehicle : VehicleParams
        The car (wheelbase, limits).
    speed : SpeedConfig
        Longitudinal profile and PI gains.
    steer_limit : float, optional
        Largest steering angle the controller commands, radians.

    Attributes
    ----------
    cte, heading_error, s, v_ref : float
        Diagnostics of the last call (rear axle, left positive; yaw - path yaw).
    steer_rate : float or None
        The actuator's rate limit (rad/s) from ``vehicle``; ``None`` when instant.
    ff_preview : float
        Metres ahead of the projection at which feed-forward reads the path (0
        with an instant actuator).
    """

    name = "tracking"

    def __init__(
        self,
        vehicle: VehicleParams | None = None,
        speed: SpeedConfig | None = None,
        steer_limit: float | None = None,
    ) -> None:
        self.vehicle = vehicle or VehicleParams()
        self.speed_config = speed or SpeedConfig()
        limit = self.vehicle.steer_for_kappa_max if steer_limit is None else steer_limit
        require_positive("controller.steer_limit", limit)
        self.steer_limit = min(float(limit), self.vehicle.max_steer)
        rate = self.vehicle.max_steer_rate
        self.steer_rate: float | None = (
            float(rate) if rate is not None and math.isfinite(rate) else None
        )
        self.projector: PathProjector | None = None
        self.speed = SpeedController(self.speed_config, comfort=self.steer_rate is not None)
        self.profile: SpeedProfile | None = None
        self.cte = self.heading_error = self.s = self.v_ref = 0.0
        self.ff_preview = 0.0
        self._last_t: float | None = None
        self._launched = False

    @property
    def arrived(self) -> bool:
        """True once the car has stopped at the end of the path."""
        return self.speed.arrived

    def reset(self, path: Path, v_start: float = 0.0) -> None:
        """Start tracking ``path`` from speed ``v_start``."""
        self.projector = PathProjector(path)
        self.profile = self._profile(self.projector, v_start)
        self.speed.reset(self.profile)
        self.cte = self.heading_error = self.s = self.v_ref = 0.0
        self.ff_preview = 0.0
        self._last_t = None
        self._launched = False
        self._reset_steering()

    def retarget(self, path: Path, v_start: float) -> None:
        """Switch to ``path`` while driving, keeping the speed loop's and steering's state.

        For a re-planned path stitched onto the current one at the car's position
        (receding-horizon planning): the projection and the speed profile (from
        ``v_start``) are rebuilt, but the PI integral, the last acceleration
        command (the jerk limit) and any steering memory carry on, so the commands
        do not jump when the reference is continuous. :meth:`reset` starts afresh.
        """
        self.projector = PathProjector(path)
        self.profile = self._profile(self.projector, v_start)
        self.speed.retarget(self.profile)

    def _profile(self, p: PathProjector, v_start: float) -> SpeedProfile:
        """The speed profile along ``p``; with a rate-limited actuator, capped by its rate."""
        return actuator_profile(
            np.asarray(p.s), np.asarray(p.kappa), self.speed_config, v_start,
            self.vehicle.wheelbase, self.steer_rate,
        )

    def hold_at(self, s: float | None) -> None:
        """Stop at arc length ``s`` and wait there, or drive on when ``None``.

        A stop line for the speed loop (an oncoming-traffic gate); it stays until
        changed, and :meth:`reset` / :meth:`retarget` clear it.
        """
        self.speed.stop_at = s

    def cap_accel(self, accel: float | None) -> None:
        """Cap the acceleration command at ``accel`` m/s^2 (``None``: no cap).

        For a car-following law; it stays until changed and :meth:`reset` clears it.
        """
        self.speed.accel_cap = accel

    def _reset_steering(self) -> None:
        """Clear steering-controller state (override when there is some)."""

    def control(self, state: VehicleState) -> tuple[float, float]:
        """``(acceleration, steering)`` for ``state``; see :class:`Controller`."""
        p = self.projector
        if p is None:
            raise RuntimeError(f"{type(self).__name__}.control called before reset")
        proj = p.project(state.x, state.y)
        self.s = proj.s
        self.cte = proj.cte
        self.heading_error = wrap_angle(state.yaw - proj.yaw)
        if self.steer_rate is not None:
            return self._control_rate_limited(state, proj, self.steer_rate)
        accel = self.speed.control(proj.s, state.speed, state.t)
        self.v_ref = self.speed.v_ref
        steer = self.steering(state, proj)
        limit = self.steer_limit
        return accel, (limit if steer > limit else -limit if steer < -limit else steer)

    def _control_rate_limited(
        self, state: VehicleState, proj: Projection, rate: float
    ) -> tuple[float, float]:
        """:meth:`control` for a rate-limited actuator (see the class docs)."""
        dt = None if self._last_t is None else state.t - self._last_t
        self._last_t = state.t
        self.ff_preview = abs(state.speed) * dt if dt is not None and dt > 0 else 0.0
        limit = self.steer_limit
        steer = min(max(self.steering(state, proj), -limit), limit)
        want = steer
        if dt is not None and dt > 0:
            reach = rate * dt
            steer = min(max(steer, state.steer - reach), state.steer + reach)
        if not self._launched:
            if state.speed == 0.0 and abs(want - state.steer) > self.speed_config.start_steer_tol:
                # Turn the wheels at rest first: the path starts at this angle.
                self.v_ref = 0.0
                return 0.0, steer
            self._launched = True
        accel = self.speed.control(proj.s, state.speed, state.t)
        self.v_ref = self.speed.v_ref
        return accel, steer

    def ff_kappa(self, proj: Projection) -> float:
        """The path curvature for feed-forward: at :attr:`ff_preview` ahead of ``proj``."""
        if self.ff_preview <= 0.0:
            return proj.kappa
        return self.projector.point_at(proj.s + self.ff_preview)[3]  # type: ignore[union-attr]

    def steering(self, state: VehicleState, proj: Projection) -> float:
        """Steering angle for ``state`` given its rear-axle projection ``proj``."""
        raise NotImplementedError
