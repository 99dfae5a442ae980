"""Overtaking a car at walking pace by the plain manoeuvre: out, past it, and back.

Behind a lead at 0-3 m/s the space-time planner's lane changes (at the re-planner's
30 m turning radius) do not fit between the ego and the lead, and its tree's straight
edges cannot be bent round in so little road: the ego followed such a lead for the
whole episode with the oncoming lane empty (docs/traffic.md, "Known limits" of
session 27). When a cycle's planner finds no overtake and the lead is slower than
:attr:`~rrtdrive.sim.replanning.ReplanConfig.pull_out_speed`, the traffic driver
tries this one path instead: from the stitch pose a quintic lane change
(:func:`~rrtdrive.sim.replanning.merge_path`) into the oncoming lane, straight on
past the lead, a quintic back into the ego's lane ending at the nearest cut-in point
(the same rule as the planner's goal, at the time this path gets there), then the
lane. The driver checks it as it checks a plan (the speed profile's timing against
every predicted car, the lead among them) and keeps it inside the road.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from rrtdrive.sim.replanning import merge_path
from rrtdrive.types import Path, VehicleParams
from rrtdrive.vehicle import footprint_corners

__all__ = ["inside_road", "pull_out_candidate", "pull_out_path"]

#: Rounds of moving the cut-in point forward to where the lead will be by then.
_GOAL_ROUNDS = 8
#: How far past the secant's estimate of the settled cut-in point a round aims (m).
_SETTLE_MARGIN_M = 0.05


def pull_out_path(
    start: np.ndarray, lane_y: float, out_y: float, length: float, x_back: float, x_end: float
) -> Path:
    """Out to the lane at ``out_y``, along it to ``x_back``, back to ``lane_y``, on to ``x_end``.

    Parameters
    ----------
    start : numpy.ndarray
        The first row ``x, y, yaw, kappa`` (rear axle; heading within 90 degrees of +x).
    lane_y, out_y : float
        Centre lines of the ego's lane and of the lane it passes in.
    length : float
        Length along x of each lane change (a quintic in x with position, slope and
        curvature continuous at both ends).
    x_back : float
        Where the lane change back starts (at least ``start[0] + length``).
    x_end : float
        Where the path ends (at least ``x_back + length``).

    Examples
    --------
    >>> p = pull_out_path(np.array([0.0, 44.0, 0.0, 0.0]), 44.0, 48.0, 14.0, 20.0, 40.0)
    >>> float(p.samples[:, 1].max()), float(p.samples[-1, 1]), round(float(p.samples[-1, 0]), 6)
    (48.0, 44.0, 40.0)
    """
    out = merge_path(tuple(start[:3]), float(start[3]), length, x_back, out_y)
    back = merge_path((x_back, out_y, 0.0), 0.0, length, x_end, lane_y)
    rows = np.concatenate([out.samples[:, :4], back.samples[1:, :4]])
    return Path(rows, np.zeros((0, 2)))


def pull_out_candidate(
    head: np.ndarray,
    start: np.ndarray,
    *,
    lane_y: float,
    out_y: float,
    length: float,
    max_length: float,
    tail: float,
    x_end: float,
    times_of: Callable[[Path], np.ndarray],
    cut_in_x: Callable[[float], float],
) -> tuple[Path, int, np.ndarray] | None:
    """The pull-out reference from the ego on, the index of its cut-in row, its times.

    The cut-in point starts two lane changes ahead of ``start`` and moves forward
    until it lies at or beyond ``cut_in_x(t)``, ``t`` being when the ego gets there
    on this very path (``times_of``: seconds from now at each row).

    Parameters
    ----------
    head : numpy.ndarray
        Rows of the current reference from the ego to (not including) ``start``.
    start : numpy.ndarray
        The stitch row ``x, y, yaw, kappa``.
    lane_y, out_y, length
        As in :func:`pull_out_path`.
    max_length : float
        Farthest cut-in point ahead of ``start`` (x).
    tail : float
        Lane kept after the cut-in point (x).
    x_end : float
        The road's last usable x.
    times_of : callable
        Arrival time (s from now) at every row of a candidate reference.
    cut_in_x : callable
        Nearest admissible cut-in x for an arrival at time ``t``.

    Returns
    -------
    tuple or None
        ``(path, goal_index, times)`` (``times_of(path)``); ``None`` when no cut-in
        point within ``max_length`` (or before the road's end) is far enough ahead of
        the lead.
    """
    x0 = float(start[0])
    x_goal = x0 + 2.0 * length
    last: tuple[float, float] | None = None  # the previous round's cut-in x and need
    for _ in range(_GOAL_ROUNDS):
        if x_goal > x0 + max_length or x_goal + tail > x_end:
            return None
        local = pull_out_path(start, lane_y, out_y, length, x_goal - length, x_goal + tail)
        path = Path(np.concatenate([head[:, :4], local.samples[:, :4]]), np.zeros((0, 2)))
        goal_index = len(head) + int(np.searchsorted(local.samples[:, 0], x_goal - 1e-9))
        times = times_of(path)
        need = cut_in_x(float(times[goal_index]))
        if x_goal >= need - 1e-9:
            return path, goal_index, times
        step = need
        if last is not None and x_goal > last[0]:
            # A moving lead moves the need on as the cut-in point moves: stepping to the
            # need closed the shortfall only by the lead's share of the ego's speed each
            # round, never within 8 (behind a lead at 0.5-2 m/s no pull-out was found,
            # a mutation audit). Aim past where the secant through the last two rounds
            # meets the need.
            slope = (need - last[1]) / (x_goal - last[0])
            if 0.0 <= slope < 1.0:
                step = max(need, (need - slope * x_goal) / (1.0 - slope)) + _SETTLE_MARGIN_M
        last = (x_goal, need)
        x_goal = step
    return None


def inside_road(path: Path, vehicle: VehicleParams, y_min: float, y_max: float) -> bool:
    """True when the body stays between the road edges at every row."""
    corners = footprint_corners(path.samples[:, :3], vehicle)
    return bool(corners[..., 1].min() >= y_min and corners[..., 1].max() <= y_max)
