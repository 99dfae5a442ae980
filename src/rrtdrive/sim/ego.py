"""The ego car in highway-env: the rear-axle kinematic bicycle of SPEC §1.

highway-env's own :class:`highway_env.vehicle.kinematics.Vehicle` integrates a
centre-of-gravity bicycle with wheelbase = length (5 m) by explicit Euler. The
:class:`EgoVehicle` here keeps the rear-axle pose as its state and advances it
by the exact closed-form arc of :func:`rrtdrive.vehicle.bicycle_step`, with the
paper's dimensions (4.30 m x 1.80 m, wheelbase 2.51 m) and steering limit (30°).
highway-env sees the body centre (``position``) and the true body size, so it
draws and collides the car at its real size, in both gears: a negative speed
drives the rear axle backwards along the same arcs, the nose heading stays the
pose's yaw, and highway-env's velocity (``speed * direction``) points backwards for
its swept collision test.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from highway_env.road.road import Road
from highway_env.utils import are_polygons_intersecting
from highway_env.vehicle.kinematics import Vehicle

from rrtdrive.geometry import wrap_angle
from rrtdrive.sim import limits
from rrtdrive.types import Pose, VehicleParams
from rrtdrive.vehicle import bicycle_step

__all__ = ["EgoVehicle", "centre_to_rear_axle", "rear_axle_to_centre"]


def rear_axle_to_centre(pose: Pose, vehicle: VehicleParams) -> tuple[float, float]:
    """Body-centre position of a car whose rear axle is at ``pose``.

    Examples
    --------
    >>> rear_axle_to_centre(Pose(0.0, 0.0, 0.0), VehicleParams())
    (1.255, 0.0)
    """
    d = vehicle.length / 2.0 - vehicle.rear_overhang
    return (pose.x + d * math.cos(pose.yaw), pose.y + d * math.sin(pose.yaw))


def centre_to_rear_axle(
    x: float, y: float, heading: float, vehicle: VehicleParams
) -> Pose:
    """Rear-axle pose of a car whose body centre is ``(x, y)`` with ``heading``.

    Examples
    --------
    >>> centre_to_rear_axle(1.255, 0.0, 0.0, VehicleParams())
    Pose(x=0.0, y=0.0, yaw=0.0)
    """
    d = vehicle.length / 2.0 - vehicle.rear_overhang
    return Pose(x - d * math.cos(heading), y - d * math.sin(heading), heading)


def _wrap(yaw: float) -> float:
    """``yaw`` itself when already in [-pi, pi), else wrapped (no rounding of in-range values)."""
    return float(yaw) if -math.pi <= yaw < math.pi else float(wrap_angle(yaw))


class EgoVehicle(Vehicle):
    """A highway-env vehicle that moves by the rear-axle bicycle model.

    The action dictionary is highway-env's: ``{"acceleration": a, "steering": delta}``
    with ``delta`` the front-wheel angle in radians, clipped to ``vehicle.max_steer``.
    With ``vehicle.max_steer_rate`` set, the steering angle is part of the state and
    moves toward the command by at most ``max_steer_rate * dt`` per step (a rate-limited
    actuator; the car starts with straight wheels), turning linearly within the step as
    CommonRoad's kinematic single-track model integrates it.
    Over one step of length ``dt`` the acceleration and the steering angle are held;
    the speed changes linearly (stopping at zero rather than reversing within a
    step) and the rear axle follows the exact circular arc of curvature
    ``tan(delta) / L`` for the distance travelled.

    Parameters
    ----------
    road : highway_env.road.road.Road
        The road the car drives on.
    pose : Pose
        Rear-axle pose.
    speed : float
        Initial speed in m/s.
    vehicle : VehicleParams, optional
        The car (defaults to the paper's).

    Attributes
    ----------
    rear : list of float
        ``[x, y, yaw]`` of the rear axle (the authoritative state).
    steer : float
        The steering angle applied in the last step.
    accel : float
        The acceleration applied in the last step.
    """

    LENGTH = VehicleParams().length
    WIDTH = VehicleParams().width
    MAX_SPEED = limits.MAX_SPEED
    #: highway-env's displacement of a predicted intersection (set by its collision check).
    impact: np.ndarray | None
    MIN_SPEED = -limits.MAX_REVERSE_SPEED

    def __init__(
        self,
        road: Road,
        pose: Pose,
        speed: float = 0.0,
        vehicle: VehicleParams | None = None,
    ) -> None:
        self.params = vehicle or VehicleParams()
        self._lane_dirty = False
        self._offset = self.params.length / 2.0 - self.params.rear_overhang
        self.rear = [pose.x, pose.y, _wrap(pose.yaw)]
        centre = rear_axle_to_centre(pose, self.params)
        super().__init__(road, centre, pose.yaw, speed)
        # Per-instance size: drawn and collided with at the true dimensions.
        self.LENGTH = self.params.length
        self.WIDTH = self.params.width
        self.diagonal = math.hypot(self.LENGTH, self.WIDTH)
        self.heading = self.rear[2]
        self.steer = 0.0
        self.accel = 0.0

    # ------------------------------------------------------------------ lane (lazy)
    # highway-env looks the closest lane up after every step, over every lane of the
    # network; in a parking lot with one lane per spot that costs more than the rest
    # of the step. The ego computes it only when something reads it.

    @property
    def lane_index(self) -> Any:  # noqa: D102 - highway-env attribute
        if self._lane_dirty:
            self._update_lane()
        return self._lane_index

    @lane_index.setter
    def lane_index(self, value: Any) -> None:
        self._lane_index = value

    @property
    def lane(self) -> Any:  # noqa: D102 - highway-env attribute
        if self._lane_dirty:
            self._update_lane()
        return self._lane

    @lane.setter
    def lane(self, value: Any) -> None:
        self._lane = value

    def _update_lane(self) -> None:
        self._lane_dirty = False
        if self.road is not None and self.road.network is not None:
            self._lane_index = self.road.network.get_closest_lane_index(self.position, self.heading)
            self._lane = self.road.network.get_lane(self._lane_index)

    def on_state_update(self) -> None:
        """Mark the lane stale and record history when the road asks for it."""
        self._lane_dirty = True
        if self.road is not None and self.road.record_history:
            self.history.appendleft(self.create_from(self))

    @classmethod
    def create_from(cls, vehicle: Vehicle) -> Vehicle:
        """A plain highway-env vehicle at the same state (used for history trails)."""
        v = Vehicle(vehicle.road, vehicle.position, vehicle.heading, vehicle.speed)
        v.LENGTH, v.WIDTH = vehicle.LENGTH, vehicle.WIDTH
        if hasattr(vehicle, "color"):
            v.color = vehicle.color
        return v

    # ------------------------------------------------------------------ state

    @property
    def pose(self) -> Pose:
        """Rear-axle pose."""
        return Pose(*self.rear)

    def set_pose(self, pose: Pose, speed: float | None = None) -> None:
        """Place the car (rear axle at ``pose``) and optionally set its speed."""
        self.rear = [pose.x, pose.y, _wrap(pose.yaw)]
        if speed is not None:
            self.speed = float(speed)
        self._sync()

    def _sync(self) -> None:
        x, y, yaw = self.rear
        c, s = math.cos(yaw), math.sin(yaw)
        self.position = np.array([x + self._offset * c, y + self._offset * s])
        self.heading = yaw
        self.on_state_update()

    def clip_actions(self) -> None:
        """Clip steering to the actuator limit; after a crash, brake straight to a stop."""
        if self.crashed:
            self.action["steering"] = 0.0
            self.action["acceleration"] = -self.speed
        limit = self.params.max_steer
        self.action["steering"] = min(max(float(self.action["steering"]), -limit), limit)
        self.action["acceleration"] = float(self.action["acceleration"])

    def _is_colliding(self, other: Any, dt: float) -> tuple[bool, bool, np.ndarray]:
        """highway-env's collision test, its circle pre-check also right when reversing.

        highway-env widens the pre-check's circles by ``speed * dt``; with a negative
        speed that would shrink them and miss a contact while backing up, so the
        reversing car widens them by ``|speed| * dt``. The exact test (polygons, with
        the displacement ``velocity * dt``) is highway-env's own in both gears.
        """
        if self.speed >= 0.0:
            return super()._is_colliding(other, dt)
        reach = (self.diagonal + other.diagonal) / 2.0 - self.speed * dt
        if np.linalg.norm(other.position - self.position) > reach:
            return False, False, np.zeros(2)
        return are_polygons_intersecting(
            self.polygon(), other.polygon(), self.velocity * dt, other.velocity * dt
        )

    #: Sub-steps of a step in which the rate-limited steering angle moves.
    RAMP_SUBSTEPS = 8

    def _ramped_step(
        self, pose: tuple[float, float, float], ds: float, steer0: float, steer1: float
    ) -> tuple[float, float, float]:
        n = self.RAMP_SUBSTEPS
        for i in range(n):
            delta = steer0 + (steer1 - steer0) * (i + 0.5) / n
            pose = bicycle_step(pose, ds / n, delta, 1.0, self.params.wheelbase)
        return pose

    def step(self, dt: float) -> None:
        """Advance the rear-axle model exactly by ``dt`` seconds.

        Parameters
        ----------
        dt : float
            Time step in seconds.
        """
        self.clip_actions()
        steer = self.action["steering"]
        rate = self.params.max_steer_rate
        slewing = rate is not None and math.isfinite(rate)
        if rate is not None and slewing:
            reach = rate * dt
            steer = min(max(steer, self.steer - reach), self.steer + reach)
        accel = self.action["acceleration"]
        v0 = self.speed
        v1 = v0 + accel * dt
        if v1 > self.MAX_SPEED:
            v1 = self.MAX_SPEED
        elif v1 < self.MIN_SPEED:
            v1 = self.MIN_SPEED
        if abs(v1) < 1e-9:
            v1 = 0.0
        if v0 * v1 < 0.0 or (v0 != 0.0 and v1 == 0.0):
            # The speed reaches zero within the step: the car stops there.
            ds = 0.5 * v0 * abs(v0 / accel) if accel != 0.0 else 0.0
            v1 = 0.0
        else:
            ds = 0.5 * (v0 + v1) * dt
        if ds != 0.0:
            pose = (self.rear[0], self.rear[1], self.rear[2])
            if not slewing or steer == self.steer:
                x, y, yaw = bicycle_step(pose, ds / dt, steer, dt, self.params.wheelbase)
            else:
                # A slewing actuator turns the wheels during the step (as CommonRoad's KS
                # model integrates it): exact arcs over sub-steps at the ramp's midpoints.
                x, y, yaw = self._ramped_step(pose, ds, self.steer, steer)
            if yaw > math.pi or yaw < -math.pi:
                yaw = wrap_angle(yaw)
            self.rear = [x, y, yaw]
        self.speed = v1
        self.steer = steer
        self.accel = accel
        if self.impact is not None:
            # highway-env's judge: an intersection predicted within dt counts as a crash.
            # The car is not pushed: its pose stays the bicycle model's.
            self.crashed = True
            self.impact = None
        self._sync()
