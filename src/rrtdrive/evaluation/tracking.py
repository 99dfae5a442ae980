"""Tracking errors: the logged rear axle against the tracked path's polyline, per gear segment.

:func:`tracking_errors` gives the signed cross-track and heading errors;
:func:`distinct_samples` the path polyline that both they and progress project onto
(:func:`rrtdrive.geometry.project_to_polyline`). A path with gear changes is measured
against the segment being driven (:func:`driven_segments`): a three-point turn drives
back over its own ground, so a projection on the whole polyline could pick the
wrong leg.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rrtdrive.geometry import project_to_polyline, wrap_angle
from rrtdrive.types import InputError, Path

__all__ = [
    "GearRun",
    "UNDRIVEN_RUN_M",
    "distinct_samples",
    "gear_runs",
    "driven_segments",
    "gear_changes",
    "tracking_errors",
    "along_path",
]


def distinct_samples(path: Path) -> np.ndarray:
    """The path's samples with consecutive repeated positions dropped (projection needs them)."""
    s = np.asarray(path.samples, dtype=float)
    keep = np.concatenate([[True], np.hypot(*np.diff(s[:, :2], axis=0).T) > 1e-9])
    return s[keep]


@dataclass(frozen=True, eq=False)
class GearRun:
    """One gear segment of a path as the evaluators measure it.

    Attributes
    ----------
    gear : int
        +1 forward, -1 reverse.
    s0 : float
        Travelled length along the whole path at its start (metres).
    samples : numpy.ndarray
        Its distinct samples ``(M, 5)``, ``M >= 2``.
    """

    gear: int
    s0: float
    samples: np.ndarray


#: A gear segment shorter than this is not driven: the controllers stop within their
#: ``stop_distance`` (``SpeedConfig``, 0.05 m) of a segment's end, so at the cusp before
#: it the car is at its end already. Measured as a run, it kept the car assigned to the
#: run before it (it never moved in the stub's gear): a 3 cm stub of a planned path
#: made the rest of the drive read 6 m of cross-track error.
UNDRIVEN_RUN_M = 0.05


def gear_runs(path: Path) -> list[GearRun]:
    """The gear segments of ``path`` with at least two distinct samples, in order.

    A forward-only path is one run of all its distinct samples. Segments without
    length, or shorter than :data:`UNDRIVEN_RUN_M` (not driven), are dropped and
    neighbours of the same gear then joined; a path of such segments alone keeps them.

    Examples
    --------
    >>> xs = np.linspace(0.0, 5.0, 6)
    >>> fwd = np.column_stack([xs, 0 * xs, 0 * xs, 0 * xs, 1 + 0 * xs])
    >>> back = np.column_stack([xs[::-1], 0 * xs, 0 * xs, 0 * xs, -1 + 0 * xs])
    >>> [(r.gear, r.s0, len(r.samples)) for r in gear_runs(Path(np.vstack([fwd, back]), []))]
    [(1, 0.0, 6), (-1, 5.0, 6)]
    """
    if path.is_forward_only:
        return [GearRun(1, 0.0, distinct_samples(path))]
    runs = _runs(path, UNDRIVEN_RUN_M)
    return runs if runs else _runs(path, 0.0)


def _runs(path: Path, shortest: float) -> list[GearRun]:
    runs: list[GearRun] = []
    s0 = 0.0
    for a, b in path.segments():
        seg = distinct_samples(Path(path.samples[a:b], path.waypoints))
        gear = int(seg[0, 4])
        length = float(np.sum(np.hypot(*np.diff(seg[:, :2], axis=0).T))) if len(seg) > 1 else 0.0
        if len(seg) >= 2 and length >= shortest:
            if runs and runs[-1].gear == gear:
                joined = np.vstack([runs[-1].samples, seg[1:]])
                runs[-1] = GearRun(gear, runs[-1].s0, joined)
            else:
                runs.append(GearRun(gear, s0, seg))
        s0 += length
    return runs


def driven_segments(runs: list[GearRun], speeds: np.ndarray) -> np.ndarray:
    """Index of the run being driven at each logged time, from the signed speeds.

    The car starts on the first run and moves on to the next one when it first
    moves in that run's gear (runs alternate gears); standing still it stays on
    the run it drove last, so a stop at a cusp is measured against the run it ends.

    Examples
    --------
    >>> runs = [GearRun(1, 0.0, np.zeros((2, 5))), GearRun(-1, 5.0, np.zeros((2, 5)))]
    >>> driven_segments(runs, np.array([0.0, 1.0, 0.0, -0.5, 0.0])).tolist()
    [0, 0, 0, 1, 1]
    """
    speeds = np.asarray(speeds, dtype=float)
    out = np.zeros(len(speeds), dtype=np.int64)
    k = 0
    last = len(runs) - 1
    for i, v in enumerate(speeds.tolist()):
        if k < last and v != 0.0 and (v > 0.0) == (runs[k + 1].gear > 0):
            k += 1
        out[i] = k
    return out


def gear_changes(speeds: np.ndarray) -> int:
    """How many times the direction of motion changed (standstill between does not count).

    Examples
    --------
    >>> gear_changes(np.array([0.0, 1.0, 0.0, -1.0, -0.5, 0.0, 0.3]))
    2
    """
    v = np.asarray(speeds, dtype=float)
    sign = np.sign(v[v != 0.0])
    return int(np.count_nonzero(sign[1:] != sign[:-1]))


def _errors_on(s: np.ndarray, p: np.ndarray, chunk: int) -> tuple[np.ndarray, np.ndarray]:
    """Cross-track and heading errors of poses ``p`` against distinct samples ``s``."""
    d = np.diff(s[:, :2], axis=0)
    yaw = np.unwrap(s[:, 2])
    proj = project_to_polyline(s[:, :2], p[:, :2], chunk)
    j, tj = proj.segment, proj.fraction
    off = p[:, :2] - proj.foot
    cross = d[j, 0] * off[:, 1] - d[j, 1] * off[:, 0]
    cte = np.where(cross < 0, -proj.distance, proj.distance)
    path_yaw = yaw[j] + tj * (yaw[j + 1] - yaw[j])
    herr = wrap_angle(p[:, 2] - path_yaw)
    return cte, herr


def _assign(path: Path, runs: list[GearRun], p: np.ndarray, speeds: np.ndarray | None,
            chunk: int) -> np.ndarray:
    if speeds is not None:
        return driven_segments(runs, speeds)
    # No speeds: the nearest run (not progress-aware; a drive over its own ground may
    # pick the wrong leg).
    dist = np.stack([project_to_polyline(r.samples[:, :2], p[:, :2], chunk).distance
                     for r in runs])
    return np.argmin(dist, axis=0)


def tracking_errors(
    path: Path, poses: np.ndarray, chunk: int = 256, speeds: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Signed cross-track and heading errors of rear-axle poses against a path.

    The cross-track error is the distance from the rear axle to the nearest point
    of the path polyline, signed positive when the car is to the left of the
    path's direction of travel; the heading error is the car's yaw minus the
    path's yaw at that point (both where the nose points, in either gear), wrapped
    to [-pi, pi). On a path with gear changes each pose is measured against the
    gear segment being driven (:func:`driven_segments`, from ``speeds``).

    Parameters
    ----------
    path : Path
        At least two samples.
    poses : numpy.ndarray
        ``(N, 3)`` rear-axle poses, or ``(N, 4)`` with the signed speed last
        (then ``speeds`` defaults to that column).
    chunk : int
        Poses per vectorised block.
    speeds : numpy.ndarray, optional
        Signed speeds ``(N,)`` of the poses; a path with gear changes uses them to
        tell which segment is driven (without them: the nearest segment).

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
    poses = np.asarray(poses, dtype=float)
    if speeds is None and poses.ndim == 2 and poses.shape[1] == 4:
        speeds = poses[:, 3]
    p = poses[..., :3].reshape(-1, 3)
    runs = gear_runs(path)
    if not runs or len(runs[0].samples) < 2:
        raise InputError("path: need at least two distinct samples to measure tracking errors")
    if len(runs) == 1:
        return _errors_on(runs[0].samples, p, chunk)
    which = _assign(path, runs, p, speeds, chunk)
    cte = np.zeros(len(p))
    herr = np.zeros(len(p))
    for k, run in enumerate(runs):
        mask = which == k
        if np.any(mask):
            cte[mask], herr[mask] = _errors_on(run.samples, p[mask], chunk)
    return cte, herr


def along_path(path: Path, poses: np.ndarray, speeds: np.ndarray | None = None) -> np.ndarray:
    """Travelled length along ``path`` (metres) of the foot point of each pose.

    Per gear segment, as :func:`tracking_errors`: the segment's start length plus
    the foot point's arc length on it.
    """
    p = np.asarray(poses, dtype=float)[:, :2]
    runs = gear_runs(path)
    if len(runs) == 1:
        return project_to_polyline(runs[0].samples[:, :2], p).s
    which = _assign(path, runs, np.column_stack([p, np.zeros(len(p))]), speeds, 256)
    out = np.zeros(len(p))
    for k, run in enumerate(runs):
        mask = which == k
        if np.any(mask):
            out[mask] = run.s0 + project_to_polyline(run.samples[:, :2], p[mask]).s
    return out
