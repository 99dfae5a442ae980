"""The kinematic bicycle about the rear axle (paper Eq. 8) and the car's footprint."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import shapely

from rrtdrive.geometry import box_corners
from rrtdrive.types import VehicleParams

__all__ = [
    "footprint_corners", "footprint_polygon", "bicycle_step", "cover_discs", "axle_disc_radius",
]


def axle_disc_radius(vehicle: VehicleParams) -> float:
    """The radius of the disc about the rear axle that the body holds in every pose.

    ``min(rear_overhang, width / 2)``: a rear axle nearer than this to an obstacle or
    the map's edge has the body there, whatever its heading (the connectivity proofs
    and the sampler's test stand on it).

    Parameters
    ----------
    vehicle : VehicleParams
        The car.

    Returns
    -------
    float
        The radius, metres.

    Examples
    --------
    >>> axle_disc_radius(VehicleParams())
    0.895
    """
    return min(vehicle.rear_overhang, vehicle.width / 2.0)


def footprint_corners(
    poses: np.ndarray | Sequence[float], vehicle: VehicleParams
) -> np.ndarray:
    """Corners of the body rectangle for rear-axle poses.

    Parameters
    ----------
    poses : numpy.ndarray
        Shape ``(N, 3)`` (or ``(3,)``) of ``x, y, yaw``.
    vehicle : VehicleParams
        The car.

    Returns
    -------
    numpy.ndarray
        Shape ``(N, 4, 2)`` (or ``(4, 2)``), counter-clockwise from rear-right.

    Examples
    --------
    >>> c = footprint_corners(np.array([0.0, 0.0, 0.0]), VehicleParams())
    >>> c[:, 0].min().round(3), c[:, 0].max().round(3)
    (np.float64(-0.895), np.float64(3.405))
    """
    p = np.asarray(poses, dtype=float)
    single = p.ndim == 1
    p = p.reshape(-1, 3)
    out = box_corners(
        p[:, 0], p[:, 1], p[:, 2], -vehicle.rear_overhang, vehicle.front_extent, vehicle.width / 2.0
    )
    return out[0] if single else out


def footprint_polygon(pose: tuple[float, float, float], vehicle: VehicleParams) -> shapely.Polygon:
    """The body rectangle at ``pose`` as a shapely polygon.

    Parameters
    ----------
    pose : tuple of float
        Rear-axle ``(x, y, yaw)`` in metres and radians.
    vehicle : VehicleParams
        The car.

    Returns
    -------
    shapely.Polygon
        The four corners of :func:`footprint_corners`, counter-clockwise from rear-right.
    """
    return shapely.Polygon(footprint_corners(np.asarray(pose, dtype=float), vehicle))


def cover_discs(vehicle: VehicleParams, count: int = 3) -> tuple[np.ndarray, float]:
    """Discs that together cover the body rectangle.

    Parameters
    ----------
    vehicle : VehicleParams
        The car.
    count : int
        Number of discs along the centre line.

    Returns
    -------
    offsets : numpy.ndarray
        Longitudinal offsets of the disc centres from the rear axle, shape ``(count,)``.
    radius : float
        Common radius: each disc covers a ``length/count`` by ``width`` slice.
    """
    piece = vehicle.length / count
    offsets = -vehicle.rear_overhang + piece * (np.arange(count) + 0.5)
    radius = math.hypot(piece / 2.0, vehicle.width / 2.0)
    return offsets, radius


def bicycle_step(
    state: tuple[float, float, float], speed: float, steer: float, dt: float, wheelbase: float
) -> tuple[float, float, float]:
    """Integrate the rear-axle bicycle exactly over ``dt`` at constant speed and steering.

    With constant ``v`` and ``delta`` the rear axle moves on a circle of radius
    ``L / tan(delta)``, so the closed-form arc is exact (no Euler drift).

    Parameters
    ----------
    state : tuple of float
        ``(x, y, yaw)`` of the rear axle.
    speed : float
        Longitudinal speed in m/s (negative drives backwards).
    steer : float
        Front-wheel angle in radians.
    dt : float
        Time step in seconds.
    wheelbase : float
        Wheelbase in metres.

    Returns
    -------
    tuple of float
        The new ``(x, y, yaw)``.

    Examples
    --------
    >>> x, y, yaw = bicycle_step((0.0, 0.0, 0.0), 1.0, 0.0, 2.0, 2.51)
    >>> round(x, 6), round(y, 6), round(yaw, 6)
    (2.0, 0.0, 0.0)
    """
    x, y, yaw = state
    kappa = math.tan(steer) / wheelbase
    ds = speed * dt
    dyaw = kappa * ds
    if abs(dyaw) < 1e-9:
        # Straight-line limit of the arc formula (second order in dyaw).
        mid = yaw + 0.5 * dyaw
        return (x + ds * math.cos(mid), y + ds * math.sin(mid), yaw + dyaw)
    new_yaw = yaw + dyaw
    return (
        x + (math.sin(new_yaw) - math.sin(yaw)) / kappa,
        y - (math.cos(new_yaw) - math.cos(yaw)) / kappa,
        new_yaw,
    )
