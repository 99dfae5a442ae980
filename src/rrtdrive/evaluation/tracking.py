"""Tracking errors: the logged rear axle against the tracked path's polyline.

:func:`tracking_errors` gives the signed cross-track and heading errors;
:func:`distinct_samples` the path polyline that both they and progress project onto
(:func:`rrtdrive.geometry.project_to_polyline`).
"""

from __future__ import annotations

import numpy as np

from rrtdrive.geometry import project_to_polyline, wrap_angle
from rrtdrive.types import InputError, Path

__all__ = ["distinct_samples", "tracking_errors"]


def distinct_samples(path: Path) -> np.ndarray:
    """The path's samples with consecutive repeated positions dropped (projection needs them)."""
    s = np.asarray(path.samples, dtype=float)
    keep = np.concatenate([[True], np.hypot(*np.diff(s[:, :2], axis=0).T) > 1e-9])
    return s[keep]


def tracking_errors(
    path: Path, poses: np.ndarray, chunk: int = 256
) -> tuple[np.ndarray, np.ndarray]:
    """Signed cross-track and heading errors of rear-axle poses against a path.

    The cross-track error is the distance from the rear axle to the nearest point
    of the path polyline, signed positive when the car is to the left of the
    path; the heading error is the car's yaw minus the path's heading at that
    point, wrapped to [-pi, pi).

    Parameters
    ----------
    path : Path
        At least two samples.
    poses : numpy.ndarray
        ``(N, 3)`` rear-axle poses.
    chunk : int
        Poses per vectorised block.

    Returns
    -------
    cte, heading_err : numpy.ndarray
        Shape ``(N,)`` each.

    Examples
    --------
    >>> xs = np.linspace(0.0, 10.0, 11)
    >>> p = Path(np.column_stack([xs, 0 * xs, 0 * xs, 0 * xs]), np.zeros((0, 2)))
    >>> cte, he = tracking_errors(p, np.array([[2.5, -0.3, 0.1]]))
    >>> round(float(cte[0]), 6), round(float(he[0]), 6)
    (-0.3, 0.1)
    """
    s = distinct_samples(path)
    if len(s) < 2:
        raise InputError("path: need at least two distinct samples to measure tracking errors")
    d = np.diff(s[:, :2], axis=0)
    yaw = np.unwrap(s[:, 2])
    p = np.asarray(poses, dtype=float).reshape(-1, 3)
    proj = project_to_polyline(s[:, :2], p[:, :2], chunk)
    j, tj = proj.segment, proj.fraction
    off = p[:, :2] - proj.foot
    cross = d[j, 0] * off[:, 1] - d[j, 1] * off[:, 0]
    cte = np.where(cross < 0, -proj.distance, proj.distance)
    path_yaw = yaw[j] + tj * (yaw[j + 1] - yaw[j])
    herr = wrap_angle(p[:, 2] - path_yaw)
    return cte, herr
