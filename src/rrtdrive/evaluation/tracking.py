"""Tracking errors: the logged rear axle against the tracked path's polyline.

:func:`tracking_errors` gives the signed cross-track and heading errors;
:func:`project_s` the arc length of the nearest path point (for progress).
"""

from __future__ import annotations

import math

import numpy as np

from rrtdrive.types import InputError, Path, wrap_angle

__all__ = ["tracking_errors", "project_s"]


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
    s = np.asarray(path.samples, dtype=float)
    keep = np.concatenate([[True], np.hypot(*np.diff(s[:, :2], axis=0).T) > 1e-9])
    s = s[keep]
    if len(s) < 2:
        raise InputError("path: need at least two distinct samples to measure tracking errors")
    a = s[:-1, :2]
    d = np.diff(s[:, :2], axis=0)
    seg_len2 = np.einsum("ij,ij->i", d, d)
    yaw = np.unwrap(s[:, 2])
    p = np.asarray(poses, dtype=float).reshape(-1, 3)
    cte = np.empty(len(p))
    herr = np.empty(len(p))
    for lo in range(0, len(p), chunk):
        q = p[lo : lo + chunk, :2]
        rel = q[:, None, :] - a[None, :, :]
        t = np.clip(np.einsum("nmj,mj->nm", rel, d) / seg_len2[None, :], 0.0, 1.0)
        foot = a[None, :, :] + t[..., None] * d[None, :, :]
        dist2 = np.sum((q[:, None, :] - foot) ** 2, axis=-1)
        j = np.argmin(dist2, axis=1)
        rows = np.arange(len(q))
        off = q - foot[rows, j]
        cross = d[j, 0] * off[:, 1] - d[j, 1] * off[:, 0]
        dist = np.sqrt(dist2[rows, j])
        cte[lo : lo + len(q)] = np.where(cross < 0, -dist, dist)
        tj = t[rows, j]
        path_yaw = yaw[j] + tj * (yaw[j + 1] - yaw[j])
        herr[lo : lo + len(q)] = wrap_angle(p[lo : lo + len(q), 2] - path_yaw)
    return cte, herr



def project_s(path: Path, points: np.ndarray) -> np.ndarray:
    """Arc length of the nearest point of the path polyline to each point."""
    s = np.asarray(path.samples, dtype=float)
    keep = np.concatenate([[True], np.hypot(*np.diff(s[:, :2], axis=0).T) > 1e-9])
    xy = s[keep, :2]
    arc = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(xy, axis=0).T))])
    a, d = xy[:-1], np.diff(xy, axis=0)
    len2 = np.einsum("ij,ij->i", d, d)
    out = []
    for q in np.asarray(points, dtype=float).reshape(-1, 2):
        t = np.clip(np.einsum("ij,ij->i", q - a, d) / len2, 0.0, 1.0)
        foot = a + t[:, None] * d
        j = int(np.argmin(np.sum((q - foot) ** 2, axis=1)))
        out.append(arc[j] + t[j] * math.sqrt(len2[j]))
    return np.array(out)
