"""Tracking errors: the logged rear axle against the tracked path's polyline, per gear segment.

:func:`tracking_errors` gives the signed cross-track and heading errors;
:func:`distinct_samples` the path polyline that both they and progress project onto
(:func:`rrtdrive.geometry.project_to_polyline`). A path with gear changes is measured
against the segment being driven (:func:`driven_segments`): a three-point turn drives
back over its own ground, so a projection on the whole polyline could pick the
wrong leg. Within one segment, a path that drives over its own ground (a forward
loop back along its way in) keeps each pose on the stretch being driven
(:func:`followed_projection`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rrtdrive.geometry import PolylineProjection, project_to_polyline, wrap_angle
from rrtdrive.types import InputError, Path

__all__ = [
    "GearRun",
    "distinct_samples",
    "gear_runs",
    "driven_segments",
    "followed_runs",
    "followed_projection",
    "gear_changes",
    "tracking_errors",
    "tracking_measures",
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


def gear_runs(path: Path) -> list[GearRun]:
    """The gear segments of ``path`` with at least two distinct samples, in order.

    A forward-only path is one run of all its distinct samples. Segments without
    length are dropped and neighbours of the same gear then joined.

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
    runs: list[GearRun] = []
    s0 = 0.0
    for a, b in path.segments():
        seg = distinct_samples(Path(path.samples[a:b], path.waypoints))
        gear = int(seg[0, 4])
        length = float(np.sum(np.hypot(*np.diff(seg[:, :2], axis=0).T))) if len(seg) > 1 else 0.0
        if len(seg) >= 2:
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


#: Slower than this (m/s) the car counts as standing: no gear is read from the sign.
STANDING_SPEED = 1e-4
#: Cost of a pose measured against a run of the other gear than it moves in (metres).
_WRONG_GEAR_COST = 1e3


def followed_runs(runs: list[GearRun], poses: np.ndarray, speeds: np.ndarray,
                  chunk: int = 256) -> np.ndarray:
    """Index of the run being driven at each logged time: the runs in order, as driven.

    The runs are taken in order, never going back, each pose measured against one
    whose gear it moves in (standing, any), and a run may be passed over at the cost
    of its length: of all such assignments, the one with the least sum of distances
    (rear axle to the run's polyline) plus lengths passed over (a Viterbi pass over
    the runs). A stub too short to drive (the controllers stop within their
    ``stop_distance`` of a segment's end and go on) is passed over; one the car does
    drive (after running past a cusp) is not; a long run is never passed over. The
    gear rule of :func:`driven_segments` alone kept the car on the run before a
    skipped stub for the rest of the drive (6 m of cross-track error where it kept
    within 5 mm), and a fixed length cut-off failed both ways (a 5.2 cm stub skipped,
    a 4.5 cm one driven).

    Examples
    --------
    >>> xs = np.linspace(0.0, 5.0, 11)
    >>> row = lambda x, g: np.column_stack([x, 0 * x, 0 * x, 0 * x, g + 0 * x])
    >>> runs = [GearRun(1, 0.0, row(xs, 1)), GearRun(-1, 5.0, row(np.array([5.0, 4.97]), -1)),
    ...         GearRun(1, 5.03, row(np.linspace(4.97, 9.0, 11), 1))]
    >>> # Forward to 4.97 m, standing there (at the 3 cm reverse stub), then forward on.
    >>> p = np.column_stack([[1.0, 4.97, 4.97, 7.0], np.zeros(4), np.zeros(4)])
    >>> followed_runs(runs, p, np.array([1.0, 0.0, 0.5, 1.0])).tolist()
    [0, 1, 2, 2]
    >>> driven_segments(runs, np.array([1.0, 0.0, 0.5, 1.0])).tolist()  # by gear alone
    [0, 0, 0, 0]
    """
    p = np.asarray(poses, dtype=float).reshape(-1, 3)
    v = np.asarray(speeds, dtype=float).reshape(-1)
    n, k = len(p), len(runs)
    if n == 0:
        return np.zeros(0, dtype=np.int64)
    cost = np.stack(
        [project_to_polyline(r.samples[:, :2], p[:, :2], chunk).distance for r in runs], axis=1
    )
    gears = np.array([r.gear for r in runs], dtype=float)
    moving = np.abs(v) >= STANDING_SPEED
    wrong = moving[:, None] & (np.sign(v)[:, None] != gears[None, :])
    cost = cost + np.where(wrong, _WRONG_GEAR_COST, 0.0)
    # Standing, the car stays on the run it drove last (a stop at a cusp is measured
    # against the run it ends): a millimetre per run later outweighs the hundredths of a
    # millimetre by which the next run may pass closer to the standing car.
    cost += np.where(moving, 0.0, 1e-3)[:, None] * np.arange(k)[None, :]
    lengths = np.array(
        [float(np.sum(np.hypot(*np.diff(r.samples[:, :2], axis=0).T))) for r in runs]
    )
    # before[j]: the lengths of the runs before j (passed over when the drive starts at j).
    before = np.concatenate([[0.0], np.cumsum(lengths)])
    back = np.zeros((n, k), dtype=np.int64)
    best = cost[0] + before[:k]
    back[0] = np.arange(k)
    idx = np.arange(k)
    for t in range(1, n):
        # From run i to j > i passes over i+1 .. j-1: best[i] - before[i + 1] + before[j].
        leave = best - before[1 : k + 1]
        # arg[j]: the first run i < j where leave is least (a new minimum is strictly lower).
        lowest = np.minimum.accumulate(leave)
        new_low = np.concatenate([[True], leave[1:] < lowest[:-1]])
        first_low = np.maximum.accumulate(np.where(new_low, idx, 0))
        arg = np.concatenate([[0], first_low[:-1]])
        jump = np.full(k, np.inf)
        jump[1:] = lowest[:-1] + before[1:k]
        take_jump = jump < best
        back[t] = np.where(take_jump, arg, idx)
        best = np.where(take_jump, jump, best) + cost[t]
    out = np.zeros(n, dtype=np.int64)
    out[-1] = int(np.argmin(best))
    for t in range(n - 1, 0, -1):
        out[t - 1] = back[t, out[t]]
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


#: Between two logged poses the foot point may move along the path this much more than
#: the car moved (metres) before it counts as a jump to another stretch of the path.
FOLLOW_SLACK_M = 2.0


def followed_projection(
    vertices: np.ndarray, points: np.ndarray, chunk: int = 256
) -> PolylineProjection:
    """The nearest points of a drive's positions, kept on the stretch being driven.

    Each point's nearest point on the polyline (:func:`~rrtdrive.geometry.project_to_polyline`)
    unless that jumps along it, between two consecutive points, by more than the car
    moved plus :data:`FOLLOW_SLACK_M`: a path that comes back over its own ground
    (east 20 m, a loop, back west along the same line) had the way out measured
    against the way back, 180 degrees of heading error at 0.1 m of cross-track (an
    audit). Then the points are followed in order instead: each one's nearest point
    within that reach of the one before (the first's: its nearest, or within its
    distance of the polyline's start when that is nearer along). Without such a jump
    the answer is the nearest point's.

    Examples
    --------
    >>> # East along y = 0, round a square, and east again along y = 0.2.
    >>> loop = np.array([[0, 0], [10, 0], [10, 10], [0, 10], [0, 0.2], [10, 0.2]], float)
    >>> drive = np.array([[1, 0.15], [5, 0.15], [9, 0.15], [10.1, 5.0]])  # out, then up
    >>> project_to_polyline(loop, drive).segment.tolist()  # the first three: the way back
    [4, 4, 4, 1]
    >>> followed_projection(loop, drive).segment.tolist()
    [0, 0, 0, 1]
    """
    q = np.asarray(points, dtype=float).reshape(-1, 2)
    xy = np.asarray(vertices, dtype=float)[:, :2]
    near = project_to_polyline(xy, q, chunk)
    moved = np.hypot(*np.diff(q, axis=0).T)
    if not np.any(np.abs(np.diff(near.s)) > moved + FOLLOW_SLACK_M):
        return near
    arc = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(xy, axis=0).T))])
    seg, frac = near.segment.copy(), near.fraction.copy()
    foot, dist, s = near.foot.copy(), near.distance.copy(), near.s.copy()
    # The first point: its nearest, unless that lies farther along than the car could
    # be from the start (a drive begins at the path's start: the way back was nearer).
    first = float(np.hypot(*(q[0] - xy[0]))) + FOLLOW_SLACK_M
    here, reach = (float(near.s[0]), 0.0) if near.s[0] <= first else (0.0, first)
    for i in range(len(q)):
        if i:
            reach = moved[i - 1] + FOLLOW_SLACK_M
        lo = max(0, int(np.searchsorted(arc, here - reach, side="right")) - 1)
        hi = min(len(xy) - 1, max(lo + 1, int(np.searchsorted(arc, here + reach, side="left"))))
        one = project_to_polyline(xy[lo : hi + 1], q[i])
        seg[i], frac[i], foot[i] = lo + one.segment[0], one.fraction[0], one.foot[0]
        dist[i], s[i] = one.distance[0], arc[lo] + one.s[0]
        here = float(s[i])
    return PolylineProjection(seg, frac, foot, dist, s)


def _errors_on(
    s: np.ndarray, p: np.ndarray, chunk: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Cross-track and heading errors of poses ``p`` on distinct samples ``s``, and arc length.

    The foot points' arc length along ``s`` too: one projection for all three.
    """
    d = np.diff(s[:, :2], axis=0)
    yaw = np.unwrap(s[:, 2])
    proj = followed_projection(s[:, :2], p[:, :2], chunk)
    j, tj = proj.segment, proj.fraction
    off = p[:, :2] - proj.foot
    cross = d[j, 0] * off[:, 1] - d[j, 1] * off[:, 0]
    cte = np.where(cross < 0, -proj.distance, proj.distance)
    path_yaw = yaw[j] + tj * (yaw[j + 1] - yaw[j])
    herr = wrap_angle(p[:, 2] - path_yaw)
    return cte, herr, proj.s


def _assign(path: Path, runs: list[GearRun], p: np.ndarray, speeds: np.ndarray | None,
            chunk: int) -> np.ndarray:
    if speeds is not None:
        return followed_runs(runs, p, speeds, chunk)
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
    cte, herr, _ = tracking_measures(path, poses, chunk, speeds)
    return cte, herr


def tracking_measures(
    path: Path, poses: np.ndarray, chunk: int = 256, speeds: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`tracking_errors` and :func:`along_path` from one projection of the poses.

    The evaluators score both of every episode: each projects every pose on the path
    (a path over its own ground with :func:`followed_projection`), which this does once.

    Parameters
    ----------
    path : Path
        At least two distinct samples.
    poses : numpy.ndarray
        As :func:`tracking_errors` takes them.
    chunk : int
        Poses per vectorised block.
    speeds : numpy.ndarray, optional
        As :func:`tracking_errors` takes them.

    Returns
    -------
    cte, heading_err, along : numpy.ndarray
        Shape ``(N,)`` each; ``along`` is :func:`along_path`'s travelled length.

    Examples
    --------
    >>> xs = np.linspace(0.0, 10.0, 11)
    >>> p = Path(np.column_stack([xs, 0 * xs, 0 * xs, 0 * xs]), np.zeros((0, 2)))
    >>> cte, he, along = tracking_measures(p, np.array([[2.5, -0.3, 0.1]]))
    >>> round(float(cte[0]), 6), round(float(he[0]), 6), round(float(along[0]), 6)
    (-0.3, 0.1, 2.5)
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
    cte, herr, along = np.zeros(len(p)), np.zeros(len(p)), np.zeros(len(p))
    for k, run in enumerate(runs):
        mask = which == k
        if np.any(mask):
            cte[mask], herr[mask], s = _errors_on(run.samples, p[mask], chunk)
            along[mask] = run.s0 + s
    return cte, herr, along


def along_path(path: Path, poses: np.ndarray, speeds: np.ndarray | None = None) -> np.ndarray:
    """Travelled length along ``path`` (metres) of the foot point of each pose.

    Per gear segment, as :func:`tracking_errors`: the segment's start length plus
    the foot point's arc length on it (:func:`tracking_measures`; only positions are
    read from ``poses``).
    """
    p = np.asarray(poses, dtype=float)[:, :2]
    return tracking_measures(path, np.column_stack([p, np.zeros(len(p))]), speeds=speeds)[2]
