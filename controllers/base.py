"""The shared tracking machinery of every controller: :class:`TrackingController`.

Every controller tracks a :class:`rrtdrive.types.Path` (rear-axle samples
``[x, y, yaw, kappa, gear]``) on the same kinematic bicycle (:class:`VehicleParams`),
one gear segment at a time (:mod:`rrtdrive.controllers.gears`), projecting the car
on it with :class:`~rrtdrive.controllers.projection.PathProjector` (re-exported here,
as are :class:`~rrtdrive.controllers.state.VehicleState` and the
:class:`~rrtdrive.controllers.state.Controller` protocol).
"""

from __future__ import annotations

import dataclasses
import math
import warnings

import numpy as np

from rrtdrive.controllers.gears import (
    CUSP_SPEED,
    GearSegment,
    gear_segments,
    mirror_state_values,
)
from rrtdrive.controllers.projection import PathProjector, Projection
from rrtdrive.controllers.speed import SpeedConfig, SpeedController, SpeedProfile
from rrtdrive.controllers.state import Controller, VehicleState
from rrtdrive.geometry import wrap_angle
from rrtdrive.speed_profile import actuator_profile
from rrtdrive.types import (
    InputError,
    InputWarning,
    Path,
    VehicleParams,
    brief_repr,
    require_finite,
    require_int,
    require_positive,
)

__all__ = [
    "VehicleState",
    "Controller",
    "Projection",
    "PathProjector",
    "TrackingController",
]

#: Fewest samples a gear segment's speed profile is built on: a segment given by its
#: two end rows alone would have no sample between its two stops.
_MIN_PROFILE_SAMPLES = 3
#: Widest gap between the speed profile's samples, metres (the planners' row spacing): a
#: path given by a few rows metres apart had a profile of a few samples, whose peak the
#: jerk-limited loop overshot (2-3 m given as 2 rows: stopped 0.2 m past the goal).
_PROFILE_SPACING = 0.25

def _require_type(name: str, value: object, cls: type) -> None:
    """Raise :class:`InputError` naming ``name`` unless ``value`` is ``None`` or a ``cls``."""
    if value is not None and not isinstance(value, cls):
        raise InputError(
            f"{name}: expected a {cls.__name__}, got {type(value).__name__} {brief_repr(value)}"
        )


def _profile_samples(s: np.ndarray, kappa: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Arc lengths and curvatures a speed profile is built on: the rows', filled in.

    Rows farther apart than :data:`_PROFILE_SPACING` get samples between them, and a
    segment of its two end rows alone (a short stub of a Reeds-Shepp word) gets one
    in the middle: its profile would otherwise stop at both, zero throughout, and the
    car never move. Between two rows the curvature is the first row's. Rows at most
    that far apart (every planner's path) are kept as they are.

    Examples
    --------
    >>> s, k = _profile_samples(np.array([0.0, 1.0]), np.array([0.1, 0.0]))
    >>> s.tolist(), k.tolist()
    ([0.0, 0.25, 0.5, 0.75, 1.0], [0.1, 0.1, 0.1, 0.1, 0.0])
    """
    ds = np.diff(s)
    # 1 % slack: a path resampled to 0.25 m by count has rows 0.25003 m apart (traffic's
    # stitched references), which are as good as 0.25 and kept.
    widest = _PROFILE_SPACING * 1.01
    if len(s) >= _MIN_PROFILE_SAMPLES and (len(ds) == 0 or ds.max() <= widest):
        return s, kappa
    steps = np.maximum(1, np.ceil(ds / widest)).astype(int)
    if steps.sum() < _MIN_PROFILE_SAMPLES - 1:
        steps[np.argmax(ds)] += _MIN_PROFILE_SAMPLES - 1 - steps.sum()
    frac = np.concatenate([np.arange(n) / n for n in steps])
    start = np.repeat(np.arange(len(ds)), steps)
    dense = np.append(s[start] + frac * ds[start], s[-1])
    return dense, np.append(kappa[start], kappa[-1])


class TrackingController:
    """Shared machinery: gear segments, projection, speed profile and PI loop, steering limit.

    Subclasses implement :meth:`steering`. The steering output is clipped to
    ``steer_limit`` (by default the angle of the path curvature limit,
    ``atan(L * kappa_max)``, so the executed curvature never exceeds ``kappa_max``;
    the actuator's own 30° limit is wider).

    **Gears.** A path with cusps is driven one gear segment at a time
    (:func:`rrtdrive.controllers.gears.gear_segments`): each segment's speed profile
    ends in a stop at its cusp; once the car stands still there (``|v| <=``
    :data:`CUSP_SPEED`) the controller switches to the next segment and gear and
    goes on; it has arrived when it stopped at the end of the last one. A reverse
    segment is tracked as the forward problem of the mirrored car (heading + pi,
    curvature, speed and steering negated; see :mod:`rrtdrive.controllers.gears`),
    and the commands are mirrored back. Reverse segments' profiles are capped by
    ``speed.v_max_reverse``, and every segment of a path with gears rises and falls
    at most ``speed.accel_manoeuvre`` (short segments that each end in a stop: with
    the full rates a jerk-limited loop overshot a 3 m segment's stop by 0.4 m). A
    forward-only path is one segment, tracked exactly as
    before gears existed.

    When the car's actuator is rate-limited (``vehicle.max_steer_rate`` finite), the
    controller knows it: the speed profile is also capped by the steering rate
    (``speed.steer_rate_share``), the command is clipped to what the actuator can
    reach in one step from the current angle (``state.steer +- rate * dt``, ``dt``
    the time since the last call; the controllers keep no steering memory, so
    nothing winds up against the limit), at the start of every gear segment the car
    stays at rest until its wheels are within ``speed.start_steer_tol`` of the
    command, the speed loop runs in comfort mode, and :attr:`ff_preview` (the
    distance driven in one step, ``|v| dt``) tells the feed-forward how far ahead to
    read the path's curvature: the actuator turns the wheels linearly over the step
    after a command, so a command reaches its mean one step late. With an instant
    actuator none of this happens.

    Parameters
    ----------
    vehicle : VehicleParams, optional
        The car (wheelbase, limits).
    speed : SpeedConfig, optional
        Longitudinal profile and PI gains.
    steer_limit : float, optional
        Largest steering angle the controller commands, radians.

    Raises
    ------
    InputError
        For an option of the wrong type or value, naming it (``controller.vehicle:
        expected a VehicleParams, got str 'car'``).

    Attributes
    ----------
    cte, heading_error, s, v_ref : float
        Diagnostics of the last call (rear axle; ``cte`` left of the direction of
        travel positive; ``heading_error`` = yaw - path yaw, both nose headings;
        ``s`` the travelled length along the whole path; ``v_ref`` signed).
    gear : int
        Gear of the segment being driven (+1 or -1).
    segment : int
        Index of the gear segment being driven.
    segments : list of GearSegment
        The path's gear segments.
    steer_rate : float or None
        The actuator's rate limit (rad/s) from ``vehicle``; ``None`` when instant.
    ff_preview : float
        Metres ahead of the projection at which feed-forward reads the path (0
        with an instant actuator).
    steer_wanted : float
        The steering angle of the last call before the actuator's reach was applied
        (within ``steer_limit``); the command itself when the actuator is instant.
    steer_window : tuple of float or None
        ``(low, high)``: the angles the actuator can reach in the last call's step
        (the command lies within them, unless the wheels stand beyond ``steer_limit``:
        then it is the limit); ``None`` with an instant actuator. A residual
        added to the command (the gym env's residual mode) is added to
        :attr:`steer_wanted` and clipped to this window, so that the clip does not
        only ever cut the residual that turns the wheels against the controller.
    """

    name = "tracking"

    def __init__(
        self,
        vehicle: VehicleParams | None = None,
        speed: SpeedConfig | None = None,
        steer_limit: float | None = None,
    ) -> None:
        _require_type("controller.vehicle", vehicle, VehicleParams)
        _require_type("controller.speed", speed, SpeedConfig)
        self.vehicle = vehicle or VehicleParams()
        self.speed_config = speed or SpeedConfig()
        limit = self.vehicle.steer_for_kappa_max if steer_limit is None else steer_limit
        require_positive("controller.steer_limit", limit)
        if limit > self.vehicle.max_steer:
            # The lock is taken, but not silently: a tuned limit that never acts is a bug.
            warnings.warn(
                f"controller.steer_limit: {float(limit):g} rad is beyond the car's "
                f"{self.vehicle.max_steer:g} rad lock; the controller commands at most the lock",
                InputWarning, stacklevel=3,
            )
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
        self.steer_wanted = 0.0
        self.steer_window: tuple[float, float] | None = None
        self.segments: list[GearSegment] = []
        self.segment = 0
        self.gear = 1
        self._s0 = 0.0
        self._manoeuvre = False
        self._last_t: float | None = None
        self._launched = False

    @property
    def arrived(self) -> bool:
        """True once the car has stopped at the end of the path (its last gear segment)."""
        return self.speed.arrived and self.segment >= len(self.segments) - 1

    @property
    def at_stop(self) -> bool:
        """True once the car has stopped at the end of the gear segment being driven."""
        return self.speed.arrived

    @property
    def remaining(self) -> float:
        """Metres from the car's projection to the end of the gear segment being driven.

        The distance to the next stop: the next cusp, or the end of the path on its
        last segment (negative past it).
        """
        if self.projector is None:
            return 0.0
        return self.projector.length - (self.s - self._s0)

    def start_segment(self, index: int) -> None:
        """Drive gear segment ``index`` from rest from now on.

        The state is as after :meth:`reset` but for the time of the last call, so that
        the next command keeps to the actuator's reach.

        The controller changes segment by itself at each cusp while it drives; this is
        for a caller that drives the car otherwise (an agent) and tells the controller
        where it is, so that its profile and projection are the segment's.

        Parameters
        ----------
        index : int
            Index into :attr:`segments` (0: the path's first gear segment).

        Raises
        ------
        InputError
            For an index outside the path's segments.
        """
        require_int("segment", index, 0)
        if not 0 <= index < len(self.segments):
            raise InputError(
                f"segment: need 0 <= index < {len(self.segments)}, got {index!r}"
            )
        self._start_segment(index, 0.0, keep_state=False)

    @property
    def next_cusp_s(self) -> float | None:
        """Travelled length along the path of the next cusp ahead, ``None`` on the last segment."""
        if self.segment >= len(self.segments) - 1:
            return None
        seg = self.segments[self.segment]
        return seg.s0 + seg.length

    def reset(self, path: Path, v_start: float = 0.0) -> None:
        """Start tracking ``path`` (its first gear segment) from speed ``v_start``.

        Parameters
        ----------
        path : Path
            The path to track, split into gear segments (:func:`gear_segments`).
        v_start : float
            The car's speed now, m/s (positive forward); the speed profile starts from it
            (at least ``speed.v_launch`` with an instant actuator).

        Raises
        ------
        InputError
            When ``path`` is not a :class:`Path` or all its samples coincide.
        """
        require_finite("v_start", v_start)  # NaN started the profile at v_max silently
        self.segments = self._split(path)
        self._manoeuvre = not path.is_forward_only
        self._last_t = None
        self._start_segment(0, v_start, keep_state=False)

    def retarget(self, path: Path, v_start: float) -> None:
        """Switch to ``path`` while driving, keeping the speed loop's and steering's state.

        For a re-planned path stitched onto the current one at the car's position
        (receding-horizon planning): the projection and the speed profile (from
        ``v_start``) are rebuilt, but the PI integral, the last acceleration
        command (the jerk limit) and any steering memory carry on, so the commands
        do not jump when the reference is continuous. :meth:`reset` starts afresh.

        Parameters
        ----------
        path : Path
            The new path, split into gear segments as by :meth:`reset`.
        v_start : float
            The car's speed now, m/s (positive forward); the new profile starts from it.

        Raises
        ------
        InputError
            When ``path`` is not a :class:`Path` or all its samples coincide.
        """
        require_finite("v_start", v_start)
        self.segments = self._split(path)
        self._manoeuvre = not path.is_forward_only
        self._start_segment(0, v_start, keep_state=True)

    @staticmethod
    def _split(path: Path) -> list[GearSegment]:
        if not isinstance(path, Path):
            raise InputError(
                f"path: expected a rrtdrive.types.Path, got {type(path).__name__} "
                f"{brief_repr(path)}"
            )
        segments = gear_segments(path)
        if not segments:
            raise InputError("path: all samples coincide")
        return segments

    def _start_segment(self, index: int, v_start: float, keep_state: bool) -> None:
        """Track gear segment ``index`` from signed speed ``v_start``."""
        seg = self.segments[index]
        self.segment = index
        self.gear = seg.gear
        self._s0 = seg.s0
        v = v_start if seg.gear > 0 else -v_start
        self.projector = PathProjector(seg.path, arc_end=self._manoeuvre)
        self.profile = self._profile(self.projector, v, seg.gear, self._manoeuvre)
        if keep_state:
            self.speed.retarget(self.profile)
        else:
            self.speed.reset(self.profile)
            self.cte = self.heading_error = self.s = self.v_ref = 0.0
            self.ff_preview = 0.0
            # _last_t carries on over a cusp: the step since the last call is known, and
            # the first command of the new gear is held to the actuator's reach too.
            self._launched = False
            self._reset_steering()
        self._track(seg.path)

    def _track(self, path: Path) -> None:
        """Hook: a gear segment starts (``path``, forward problem); build per-path state."""

    def _profile(
        self, p: PathProjector, v_start: float, gear: int = 1, manoeuvre: bool = False
    ) -> SpeedProfile:
        """The speed profile along ``p``; with a rate-limited actuator, capped by its rate.

        Reverse segments are capped by ``v_max_reverse``; every segment of a path with
        gears (``manoeuvre``) rises and falls at most ``accel_manoeuvre``.
        """
        config = self.speed_config
        if gear < 0 and config.v_max_reverse < config.v_max:
            config = dataclasses.replace(config, v_max=config.v_max_reverse)
        if manoeuvre:
            a = config.accel_manoeuvre
            config = dataclasses.replace(
                config, accel=min(config.accel, a), decel=min(config.decel, a)
            )
        s, kappa = _profile_samples(np.asarray(p.s), np.asarray(p.kappa))
        return actuator_profile(
            s, kappa, config, v_start,
            self.vehicle.wheelbase, self.steer_rate, rise_to_peak=manoeuvre,
        )  # fmt: skip

    def hold_at(self, s: float | None) -> None:
        """Stop at arc length ``s`` (along the whole path) and wait there; ``None``: drive on.

        A stop line for the speed loop (an oncoming-traffic gate); it stays until
        changed, and :meth:`reset` / :meth:`retarget` clear it.

        Parameters
        ----------
        s : float or None
            Arc length of the stop line from the start of the whole path, metres.
        """
        if s is not None:
            require_finite("stop line s", s)
        self.speed.stop_at = None if s is None else s - self._s0

    def cap_accel(self, accel: float | None) -> None:
        """Cap the acceleration command at ``accel`` m/s^2 (``None``: no cap).

        For a car-following law; it stays until changed and :meth:`reset` clears it.

        Parameters
        ----------
        accel : float or None
            Upper bound of the acceleration command, m/s^2 (a negative cap brakes).
        """
        if accel is not None:
            require_finite("accel cap", accel)
        self.speed.accel_cap = accel

    def _reset_steering(self) -> None:
        """Clear steering-controller state (override when there is some)."""

    def control(self, state: VehicleState) -> tuple[float, float]:
        """``(acceleration, steering)`` for ``state``; see :class:`Controller`.

        Parameters
        ----------
        state : VehicleState
            The car now: rear-axle pose, signed speed, current steering, time.

        Returns
        -------
        accel, steer : float
            Acceleration (m/s^2) and steering angle (rad, left positive) of the real
            car; in reverse, the mirrored car's commands negated.

        Raises
        ------
        RuntimeError
            When called before :meth:`reset`.
        """
        if self.projector is None:
            raise RuntimeError(f"{type(self).__name__}.control called before reset")
        if (
            self.speed.arrived
            and self.segment < len(self.segments) - 1
            and abs(state.speed) <= CUSP_SPEED
        ):
            # Stopped at the cusp: change gear and drive the next segment from rest.
            self._start_segment(self.segment + 1, 0.0, keep_state=False)
        self.steer_window = None
        if self.gear > 0:
            accel, steer = self._control_forward(state)
            if accel < 0.0 and state.speed <= 0.0:
                accel = 0.0  # braking at rest holds the car: it never rolls against its gear
            return accel, steer
        yaw, speed, steer = mirror_state_values(state.yaw, state.speed, state.steer)
        accel, steer = self._control_forward(
            VehicleState(state.x, state.y, yaw, speed, steer, state.t)
        )
        if accel < 0.0 and speed <= 0.0:
            accel = 0.0
        self.v_ref = -self.v_ref
        # The mirrored car's angles, back in the real car's terms.
        self.steer_wanted = -self.steer_wanted
        if self.steer_window is not None:
            self.steer_window = (-self.steer_window[1], -self.steer_window[0])
        return -accel, -steer

    def _control_forward(self, state: VehicleState) -> tuple[float, float]:
        """:meth:`control` of the forward problem of the current segment."""
        p = self.projector
        proj = p.project(state.x, state.y)  # type: ignore[union-attr]
        self.s = self._s0 + proj.s
        self.cte = proj.cte
        self.heading_error = wrap_angle(state.yaw - proj.yaw)
        if self.steer_rate is not None:
            return self._control_rate_limited(state, proj, self.steer_rate)
        accel = self.speed.control(proj.s, state.speed, state.t)
        self.v_ref = self.speed.v_ref
        steer = self.steering(state, proj)
        limit = self.steer_limit
        steer = limit if steer > limit else -limit if steer < -limit else steer
        self.steer_wanted = steer
        return accel, steer

    def _control_rate_limited(
        self, state: VehicleState, proj: Projection, rate: float
    ) -> tuple[float, float]:
        """:meth:`control` for a rate-limited actuator (see the class docs)."""
        dt = None if self._last_t is None else state.t - self._last_t
        self._last_t = state.t
        self.ff_preview = abs(state.speed) * dt if dt is not None and dt > 0 else 0.0
        limit = self.steer_limit
        steer = min(max(self.steering(state, proj), -limit), limit)
        want = self.steer_wanted = steer
        if dt is not None and dt > 0:
            reach = rate * dt
            self.steer_window = (state.steer - reach, state.steer + reach)
            steer = min(max(steer, state.steer - reach), state.steer + reach)
            # Wheels standing beyond the limit (a car parked at full lock): the limit
            # wins; the actuator turns them back as fast as it can.
            steer = min(max(steer, -limit), limit)
        if not self._launched:
            # At rest: CUSP_SPEED, not 0.0 (stock envs pass actions as float32, and a car
            # standing at a cusp there reads -2e-8 m/s: the wheels were not turned first).
            at_rest = abs(state.speed) <= CUSP_SPEED
            # Not for a stub the speed loop ends at once: the wheels turned to a 3 cm
            # arc's full lock and back, 2.2 s standing.
            stub = self.speed.ends_at(proj.s)
            if at_rest and not stub and abs(want - state.steer) > self.speed_config.start_steer_tol:
                # Turn the wheels at rest first: the path starts at this angle.
                self.v_ref = 0.0
                return 0.0, steer
            self._launched = True
        accel = self.speed.control(proj.s, state.speed, state.t)
        self.v_ref = self.speed.v_ref
        return accel, steer

    def ff_kappa(self, proj: Projection) -> float:
        """The path curvature for feed-forward: at :attr:`ff_preview` ahead of ``proj``.

        Parameters
        ----------
        proj : Projection
            The rear axle's projection on the gear segment being driven.

        Returns
        -------
        float
            Curvature in 1/m (``proj.kappa`` with an instant actuator).
        """
        if self.ff_preview <= 0.0:
            return proj.kappa
        return self.projector.point_at(proj.s + self.ff_preview)[3]  # type: ignore[union-attr]

    def steering(self, state: VehicleState, proj: Projection) -> float:
        """Steering angle for ``state`` given its rear-axle projection ``proj``.

        Parameters
        ----------
        state : VehicleState
            The car; in reverse, the mirrored car of the forward problem.
        proj : Projection
            Its rear axle's projection on the gear segment being driven.

        Returns
        -------
        float
            Steering angle in rad (left positive), before :meth:`control` clips it to
            ``steer_limit`` and the actuator's reach.
        """
        raise NotImplementedError
