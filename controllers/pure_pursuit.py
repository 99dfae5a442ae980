"""Pure pursuit about the rear axle with a speed-scheduled look-ahead (Coulter 1992)."""

from __future__ import annotations

import math

from rrtdrive.controllers.base import Projection, TrackingController, VehicleState
from rrtdrive.controllers.speed import SpeedConfig
from rrtdrive.types import InputError, VehicleParams, require_positive

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

    On a path with gear changes (a manoeuvre at parking speeds) the look-ahead's
    floor is ``ld_min_gears`` instead of ``ld_min``: with 2 m the car cut the
    S-bends before a cusp and reached it a few degrees off, and a reverse segment
    on nearly full lock has no steering left to correct that (``parking-reverse-in``
    seed 46 stopped 0.194 m beside its goal; 0.059 m with 1 m).

    Parameters
    ----------
    vehicle : VehicleParams, optional
        The car.
    speed : SpeedConfig, optional
        Longitudinal profile and PI gains.
    ld_min, ld_gain, ld_max : float
        Look-ahead schedule: metres, seconds, metres.
    ld_min_gears : float
        The look-ahead's floor on a path with gear changes, metres (<= ``ld_max``).
    steer_limit : float, optional
        Largest commanded steering angle (default: the curvature limit's).

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
        ld_min_gears: float = 1.0,
    ) -> None:
        super().__init__(vehicle, speed, steer_limit)
        require_positive("pure_pursuit.ld_min", ld_min)
        require_positive("pure_pursuit.ld_max", ld_max)
        if ld_gain < 0 or ld_max < ld_min:
            raise InputError("pure_pursuit: need ld_gain >= 0 and ld_max >= ld_min")
        require_positive("pure_pursuit.ld_min_gears", ld_min_gears)
        if ld_min_gears > ld_max:
            raise InputError("pure_pursuit: need ld_min_gears <= ld_max")
        self.ld_min, self.ld_gain, self.ld_max = float(ld_min), float(ld_gain), float(ld_max)
        self.ld_min_gears = float(ld_min_gears)
        self.lookahead = ld_min

    def steering(self, state: VehicleState, proj: Projection) -> float:
        """Pure-pursuit steering angle."""
        floor = self.ld_min_gears if self._manoeuvre else self.ld_min
        ld = min(max(self.ld_gain * abs(state.speed), floor), self.ld_max)
        self.lookahead = ld
        tx, ty, _, _ = self.projector.point_at(proj.s + ld)  # type: ignore[union-attr]
        dx, dy = tx - state.x, ty - state.y
        dist = math.hypot(dx, dy)
        if dist < 1e-6:
            return 0.0
        alpha = math.atan2(dy, dx) - state.yaw
        return math.atan(2.0 * self.vehicle.wheelbase * math.sin(alpha) / dist)
