"""Stanley steering about the front axle (Hoffmann et al. 2007), on our rear-axle paths."""

from __future__ import annotations

import math

import numpy as np

from rrtdrive.controllers.base import PathProjector, Projection, TrackingController
from rrtdrive.controllers.speed import SpeedConfig
from rrtdrive.controllers.state import VehicleState
from rrtdrive.geometry import wrap_angle
from rrtdrive.types import Path, VehicleParams, require_positive

__all__ = ["Stanley", "front_axle_path"]


def front_axle_path(path: Path, wheelbase: float) -> Path:
    """The trace of the front axle while the rear axle follows ``path`` exactly.

    The front axle sits ``L`` ahead along the heading; its direction of travel is
    the front wheel's, ``yaw + atan(L kappa)``, which is the column stored as yaw.

    Examples
    --------
    >>> xs = np.linspace(0.0, 5.0, 6)
    >>> p = Path(np.column_stack([xs, 0 * xs, 0 * xs, 0 * xs]), np.zeros((0, 2)))
    >>> front_axle_path(p, 2.5).samples[0, :2].tolist()
    [2.5, 0.0]
    """
    s = np.asarray(path.samples, dtype=float)
    c, sn = np.cos(s[:, 2]), np.sin(s[:, 2])
    wheel = s[:, 2] + np.arctan(wheelbase * s[:, 3])
    out = np.column_stack(
        [s[:, 0] + wheelbase * c, s[:, 1] + wheelbase * sn, wheel, s[:, 3], s[:, 4]]
    )
    return Path(out, path.waypoints)


class Stanley(TrackingController):
    """Front-axle heading plus cross-track law.

    With ``e`` the front axle's signed offset from the front-axle trace of the path
    (positive to the left) and ``psi`` the angle from the car's heading to the
    trace's direction there (positive when the path points to the left of the car),
    the steering angle is ``psi + atan2(-k e, k_soft + v)``: a car left of the path
    or pointing left of it steers right (negative). On a circle the trace's
    direction is ``yaw + atan(L kappa)``, so the curvature feed-forward is built in
    and the rear axle stays on the path at steady state. In reverse the law runs on
    the mirrored car (:mod:`rrtdrive.controllers.gears`): its steered point lies ``L``
    beyond the rear axle in the direction of travel (behind the real car), whose
    velocity turns with the wheels as a front axle's does, so the law keeps its
    first-order cross-track dynamics.

    Parameters
    ----------
    vehicle : VehicleParams, optional
        The car.
    speed : SpeedConfig, optional
        Longitudinal profile and PI gains.
    k : float
        Cross-track gain in 1/s.
    k_soft : float
        Softening speed in m/s (keeps the gain finite at rest).
    steer_limit : float, optional
        Largest commanded steering angle (default: the curvature limit's).

    Examples
    --------
    >>> xs = np.linspace(0.0, 20.0, 81)
    >>> c = Stanley()
    >>> c.reset(Path(np.column_stack([xs, 0 * xs, 0 * xs, 0 * xs]), np.zeros((0, 2))))
    >>> c.control(VehicleState(0.0, 0.5, 0.0, 1.0))[1] < 0.0
    True
    """

    name = "stanley"

    def __init__(
        self,
        vehicle: VehicleParams | None = None,
        speed: SpeedConfig | None = None,
        k: float = 1.5,
        k_soft: float = 0.5,
        steer_limit: float | None = None,
    ) -> None:
        super().__init__(vehicle, speed, steer_limit)
        require_positive("stanley.k", k)
        require_positive("stanley.k_soft", k_soft)
        self.k, self.k_soft = float(k), float(k_soft)
        self.front: PathProjector | None = None
        self.front_cte = 0.0

    def _track(self, path: Path) -> None:
        """A gear segment starts: the front-axle trace of its (forward) path steers.

        Rebuilt for every segment and on :meth:`retarget` too: without it the steering
        would keep following the trace of the first path (issue #15: Stanley crashed in
        every re-planned overtake).
        """
        self.front = PathProjector(front_axle_path(path, self.vehicle.wheelbase))

    def steering(self, state: VehicleState, proj: Projection) -> float:
        """Stanley steering angle.

        As :meth:`TrackingController.steering`.

        Parameters
        ----------
        state : VehicleState
            The car; in reverse, the mirrored car of the forward problem.
        proj : Projection
            Its rear axle's projection; the front axle's search on the trace starts
            at its segment.

        Returns
        -------
        float
            Steering angle in rad (left positive), before the steering limit.
        """
        L = self.vehicle.wheelbase
        fx, fy = state.x + L * math.cos(state.yaw), state.y + L * math.sin(state.yaw)
        self.front.reset_hint(proj.index)  # type: ignore[union-attr]
        fp = self.front.project(fx, fy)  # type: ignore[union-attr]
        self.front_cte = fp.cte
        heading = fp.yaw
        if self.ff_preview > 0.0:
            # The wheel's part of the trace's direction, read one step ahead (actuator lag).
            ahead = self.front.point_at(fp.s + self.ff_preview)[3]  # type: ignore[union-attr]
            heading += math.atan(L * ahead) - math.atan(L * fp.kappa)
        psi = wrap_angle(heading - state.yaw)
        return psi + math.atan2(-self.k * fp.cte, self.k_soft + abs(state.speed))
