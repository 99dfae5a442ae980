"""Pure pursuit about the rear axle with a speed-scheduled look-ahead (Coulter 1992)."""

from __future__ import annotations

import math

from rrtdrive.controllers.base import Projection, TrackingController
from rrtdrive.controllers.speed import SpeedConfig
from rrtdrive.controllers.state import APPROACH_ANGLE, VehicleState, checked_approach_angle
from rrtdrive.types import InputError, VehicleParams, require_finite, require_positive

__all__ = ["PurePursuit"]


class PurePursuit(TrackingController):
    """Steer the rear axle onto the arc through a look-ahead point on the path.

    The look-ahead point lies ``ld = clip(ld_gain * |v|, ld_min, ld_max)`` metres
    of arc length ahead of the rear axle's projection (on the straight extension
    past the end). With ``alpha`` its bearing in the car frame and ``l`` its
    distance, the arc has curvature ``2 sin(alpha) / l`` and the steering angle is
    ``atan(2 L sin(alpha) / l)``. In reverse the same law runs on the mirrored car
    (:mod:`rrtdrive.controllers.gears`), still about the rear axle, with the
    look-ahead point behind the nose along the direction of travel; on the segments of
    a path with gear changes the look-ahead point past a segment's end lies on the
    circle of its last curvature (``PathProjector(arc_end=True)``), so the car
    reaches each cusp with the path's curvature instead of straightening early.

    On a path with gear changes (a manoeuvre at parking speeds, where the
    steering often changes from lock to lock within a few metres) the law is
    compensated for its corner cutting: the curvature it would command for a car
    exactly on the path at the projection (the chord law from the path's own pose)
    is replaced by the path's curvature there, so that the car on the path steers
    along it and pure pursuit's correction acts on the deviation only
    (``kappa = 2 sin(alpha) / l + kappa_path(s) - 2 sin(alpha_0) / l_0``). On a
    straight or a circle the two terms cancel (arc-length look-ahead on a circle
    is exact). Without it, the car cut the S-bend before a cusp and reached it a
    few degrees off, and the reverse segment after it, on 98 % of full lock, had no
    steering left to correct that (``parking-reverse-in`` seed 46 stopped 0.194 m
    beside its goal).

    Parameters
    ----------
    vehicle : VehicleParams, optional
        The car.
    speed : SpeedConfig, optional
        Longitudinal profile and PI gains.
    ld_min, ld_gain, ld_max : float
        Look-ahead schedule: metres, seconds, metres.
    compensate : bool
        Apply the corner-cutting compensation on paths with gear changes (forward-only
        paths are tracked by the plain law either way).
    steer_limit : float, optional
        Largest commanded steering angle (default: the curvature limit's).
    approach_angle : float
        The look-ahead is at least ``|cte| / tan(approach_angle)``, so that far from
        the path the car heads back at most this many radians off the path's
        direction (the point 2 m ahead of a car 1 m off asked for full lock and, on
        a rate-limited car, swung it across the path and into a crash).

    Examples
    --------
    >>> import numpy as np
    >>> from rrtdrive.types import Path
    >>> xs = np.linspace(0.0, 20.0, 81)
    >>> c = PurePursuit()
    >>> c.reset(Path(np.column_stack([xs, 0 * xs, 0 * xs, 0 * xs]), np.zeros((0, 2))))
    >>> accel, steer = c.control(VehicleState(0.0, 0.5, 0.0, 1.0))
    >>> steer < 0.0  # left of the path: steer right
    True
    """

    name = "pure-pursuit"

    def __init__(
        self,
        vehicle: VehicleParams | None = None,
        speed: SpeedConfig | None = None,
        ld_min: float = 2.0,
        ld_gain: float = 0.6,
        ld_max: float = 10.0,
        steer_limit: float | None = None,
        compensate: bool = True,
        approach_angle: float = APPROACH_ANGLE,
    ) -> None:
        super().__init__(vehicle, speed, steer_limit)
        require_positive("pure_pursuit.ld_min", ld_min)
        require_positive("pure_pursuit.ld_max", ld_max)
        require_finite("pure_pursuit.ld_gain", ld_gain)  # before comparing it below
        if ld_gain < 0:
            raise InputError(f"pure_pursuit.ld_gain: must be >= 0, got {ld_gain!r}")
        if ld_max < ld_min:
            raise InputError(
                f"pure_pursuit.ld_max: must be >= ld_min ({ld_min!r}), got {ld_max!r}"
            )
        if not isinstance(compensate, bool):
            raise InputError(f"pure_pursuit.compensate: expected true or false, got {compensate!r}")
        self.ld_min, self.ld_gain, self.ld_max = float(ld_min), float(ld_gain), float(ld_max)
        self.compensate = compensate
        self.approach_angle = checked_approach_angle(
            "pure_pursuit.approach_angle", approach_angle
        )
        self._far = 1.0 / math.tan(self.approach_angle)
        self.lookahead = ld_min

    def steering(self, state: VehicleState, proj: Projection) -> float:
        """Pure-pursuit steering angle (compensated on paths with gear changes).

        As :meth:`TrackingController.steering`.

        Parameters
        ----------
        state : VehicleState
            The car; in reverse, the mirrored car of the forward problem.
        proj : Projection
            Its rear axle's projection on the gear segment being driven.

        Returns
        -------
        float
            Steering angle in rad (left positive), before the steering limit; the
            look-ahead used is kept in :attr:`lookahead` (metres).
        """
        ld = min(max(self.ld_gain * abs(state.speed), self.ld_min), self.ld_max)
        ld = max(ld, abs(proj.cte) * self._far)
        self.lookahead = ld
        tx, ty, _, _ = self.projector.point_at(proj.s + ld)  # type: ignore[union-attr]
        kappa = _chord_curvature(state.x, state.y, state.yaw, tx, ty)
        if self.compensate and self._manoeuvre:
            kappa += self.ff_kappa(proj) - _chord_curvature(proj.x, proj.y, proj.yaw, tx, ty)
        return math.atan(self.vehicle.wheelbase * kappa)


def _chord_curvature(x: float, y: float, yaw: float, tx: float, ty: float) -> float:
    """Curvature ``2 sin(alpha) / l`` of the arc from pose ``(x, y, yaw)`` through ``(tx, ty)``."""
    dx, dy = tx - x, ty - y
    dist = math.hypot(dx, dy)
    if dist < 1e-6:
        return 0.0
    return 2.0 * math.sin(math.atan2(dy, dx) - yaw) / dist
