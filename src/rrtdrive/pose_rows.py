"""A :class:`~rrtdrive.types.Path` from poses alone: rows ``[x, y, yaw]`` of another planner.

Many planners give rear-axle poses only. The gear of each step is read off the motion
(along the nose: forward; against it: reverse), a cusp's row is repeated with the new
gear (the :class:`Path` contract), and ``kappa`` is the yaw's turn per metre of the step
(``tan delta / L`` in both gears: the turn's sign flips in reverse). ``rrtdrive verify``
measures curvature from the positions anyway; a tracking controller reads ``kappa``.
"""

from __future__ import annotations

import numpy as np

from rrtdrive.geometry import wrap_angle
from rrtdrive.types import InputError, Path

__all__ = ["path_from_poses"]

#: A row this close to the one before it, in position and yaw, repeats it.
SAME_POSITION_M = 1e-9
SAME_YAW_RAD = 1e-6


def _fill_still(values: np.ndarray, moving: np.ndarray, default: float) -> np.ndarray:
    """``values`` of the steps without motion taken from the moving step before them.

    The steps before the first moving one take its value; with no moving step, ``default``.
    """
    index = np.flatnonzero(moving)
    if len(index) == 0:
        return np.full(len(values), default)
    # Forward fill from the first moving step, then back fill the steps before it.
    source = np.where(moving, np.arange(len(values)), 0)
    np.maximum.accumulate(source, out=source)
    out = values[source]
    out[: index[0]] = values[index[0]]
    return out


def _steps(poses: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each step's gear (+1 or -1: its motion along or against the nose) and ``kappa``.

    The nose of a step is the mean of its two rows' yaws; ``kappa`` is ``gear * turn /
    length``. A step without motion (a repeated row) takes both from the step before it.
    """
    d = np.diff(poses[:, :2], axis=0)
    mid = poses[:-1, 2] + 0.5 * wrap_angle(np.diff(poses[:, 2]))
    along = d[:, 0] * np.cos(mid) + d[:, 1] * np.sin(mid)
    moving = along != 0.0
    gears = _fill_still(np.sign(along), moving, 1.0)
    ds = np.hypot(d[:, 0], d[:, 1])
    kappa = gears * wrap_angle(np.diff(poses[:, 2])) / np.where(moving, ds, 1.0)
    return gears, _fill_still(kappa, moving, 0.0)


def path_from_poses(poses: np.ndarray) -> Path:
    """The path through rear-axle poses ``[x, y, yaw]``, with gears and curvature read off them.

    Parameters
    ----------
    poses : array_like
        Shape ``(N, 3)``: ``x``, ``y`` in metres and ``yaw`` (where the nose points,
        in both gears) in radians, finite.

    Returns
    -------
    Path
        Rows ``[x, y, yaw, kappa, gear]``: the gear of the step leaving a row (the last
        row: of the step reaching it), each cusp row repeated with the new gear, and
        ``kappa`` the step's ``gear * turn / length`` (a step without motion, a repeated
        row: the gear and ``kappa`` of the step before it). A row within 1e-9 m and 1e-6
        rad of the one before it is dropped first (a cusp's pose written twice comes out
        once per gear).

    Raises
    ------
    InputError
        Naming ``path`` when ``poses`` is not an ``(N, 3)`` array of finite numbers.

    Examples
    --------
    >>> fwd = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]]
    >>> back = [[1.0, 0.0, 0.0], [0.0, 0.0, 0.0]]
    >>> p = path_from_poses(fwd + back)
    >>> p.samples[:, 4].tolist(), p.cusps.tolist(), p.length
    ([1.0, 1.0, 1.0, -1.0, -1.0, -1.0], [3], 4.0)
    """
    a = np.asarray(poses, dtype=float)
    if a.ndim != 2 or a.shape[1] != 3 or not np.isfinite(a).all():
        raise InputError(f"path: expected rows [x, y, yaw] of finite numbers, got shape {a.shape}")
    # A row that repeats the one before it (a cusp's pose written twice, maybe with float
    # noise) adds nothing; a turn in place stays, for the verifier to refuse.
    if len(a) > 1:
        same = (np.hypot(*np.diff(a[:, :2], axis=0).T) <= SAME_POSITION_M) & (
            np.abs(wrap_angle(np.diff(a[:, 2]))) <= SAME_YAW_RAD
        )
        a = a[np.concatenate([[True], ~same])]
    if len(a) < 2:
        return Path(np.column_stack([a, np.zeros(len(a)), np.ones(len(a))]), np.zeros((0, 2)))
    gears, kappa = _steps(a)
    rows = []
    for i in range(len(a)):
        leaving = min(i, len(gears) - 1)
        if 0 < i < len(a) - 1 and gears[i - 1] != gears[i]:
            # A cusp: the row ends the old gear's segment and starts the new one's.
            rows.append([*a[i], kappa[i - 1], gears[i - 1]])
        rows.append([*a[i], kappa[leaving], gears[leaving]])
    return Path(np.array(rows), np.zeros((0, 2)))
