"""Interaction with other vehicles (nuPlan's definitions) and progress along the path.

:func:`time_to_collision` is nuPlan's ``time_to_collision_within_bound``;
:func:`min_vehicle_distance` the exact smallest body-to-body distance;
:func:`progress` the arc length driven along the tracked path.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np
import shapely

from rrtdrive.evaluation.collisions import (
    between_lanes,
    boxes_intersect,
    ego_centres,
    relative_angles,
    vehicle_collisions,
)
from rrtdrive.evaluation.tracking import along_path
from rrtdrive.geometry import box_corners

if TYPE_CHECKING:  # pragma: no cover
    from rrtdrive.sim.episode import Episode

__all__ = [
    "TTC_HORIZON_S",
    "TTC_STEP_S",
    "TTC_STOPPED_SPEED",
    "TTC_LEAST_MIN_S",
    "time_to_collision",
    "min_vehicle_distance",
    "progress",
]

#: nuPlan's ``time_to_collision_within_bound``: horizon and step of the constant-velocity
#: projection (s), ego speed below which TTC is not computed (m/s), and the bound (s).
TTC_HORIZON_S = 3.0
TTC_STEP_S = 0.1
TTC_STOPPED_SPEED = 5e-3
TTC_LEAST_MIN_S = 0.95


def time_to_collision(
    episode: Episode,
    at_fault_steps: Sequence[int] = (),
    horizon: float = TTC_HORIZON_S,
    step: float = TTC_STEP_S,
) -> np.ndarray:
    """Time to collision at every logged time, as nuPlan defines it (``inf`` when none).

    At each logged time the ego (body centre, its heading and speed) and the other
    vehicles (their headings and speeds) are projected at constant velocity at
    ``step``, ``2 step``, ... below ``horizon`` (``np.arange(step, horizon, step)``,
    as nuPlan's ``time_to_collision_within_bound``); the TTC is the first projected
    time at which the ego's box intersects one of theirs. Only vehicles ahead of the
    ego (within 30° of its heading from the rear axle) count, plus, while the ego
    is in more than one lane or off the road, every vehicle not behind it (more
    than 150° off); vehicles it already collided with are left out. While the ego
    is stopped (speed <= 5e-3 m/s) the TTC is ``inf``; at an at-fault collision it is 0.

    Parameters
    ----------
    episode : Episode
        A driven episode.
    at_fault_steps : sequence of int
        Logged times of at-fault collisions (:func:`vehicle_collisions`).
    horizon, step : float
        nuPlan: 3 s and 0.1 s.

    Returns
    -------
    numpy.ndarray
        ``(N + 1,)`` seconds.
    """
    log = episode.log
    states = log.states
    n = len(states)
    ttc = np.full(n, np.inf)
    others = log.others
    if n == 0 or others.size == 0:
        return ttc
    vehicle = episode.scenario.vehicle
    k = others.shape[1]
    ex, ey = ego_centres(states, vehicle)
    v = states[:, 3]
    angles = relative_angles(states, others)
    between = between_lanes(episode)
    collided_before = np.zeros((n, k), dtype=bool)
    for i, j, _kind, _fault in vehicle_collisions(episode):
        collided_before[i + 1 :, j] = True
    considered = (angles < math.radians(30.0)) | (
        between[:, None] & ~(angles > math.radians(150.0))
    )
    times = np.arange(step, horizon, step)
    sizes = log.other_sizes
    reach = (np.abs(v)[:, None] + np.abs(others[..., 3])) * times[-1] + 0.5 * (
        math.hypot(vehicle.length, vehicle.width) + np.hypot(sizes[:, 0], sizes[:, 1])[None, :]
    )
    dist = np.hypot(others[..., 0] - ex[:, None], others[..., 1] - ey[:, None])
    moving = np.abs(v)[:, None] > TTC_STOPPED_SPEED
    cand = considered & ~collided_before & moving & (dist <= reach)
    ii, jj = np.nonzero(cand)
    if len(ii):
        t = times[None, :]
        h = states[ii, 2][:, None]
        half_l = vehicle.length / 2.0
        e_box = box_corners(
            ex[ii][:, None] + v[ii][:, None] * np.cos(h) * t,
            ey[ii][:, None] + v[ii][:, None] * np.sin(h) * t,
            np.broadcast_to(h, (len(ii), len(times))),
            -half_l, half_l, vehicle.width / 2.0,
        )
        o = others[ii, jj]
        oh = o[:, 2][:, None]
        o_box = box_corners(
            o[:, 0][:, None] + o[:, 3][:, None] * np.cos(oh) * t,
            o[:, 1][:, None] + o[:, 3][:, None] * np.sin(oh) * t,
            np.broadcast_to(oh, (len(ii), len(times))),
            -sizes[jj, 0][:, None] / 2.0, sizes[jj, 0][:, None] / 2.0, sizes[jj, 1][:, None] / 2.0,
        )
        hit = boxes_intersect(e_box, o_box)
        first = np.where(hit.any(axis=1), times[np.argmax(hit, axis=1)], np.inf)
        np.minimum.at(ttc, ii, first)
    ttc[np.asarray(list(at_fault_steps), dtype=np.int64)] = 0.0
    return ttc


def min_vehicle_distance(episode: Episode) -> float | None:
    """Smallest distance between the ego's body and another vehicle's over the episode (m).

    Exact (shapely) on the logged poses; 0 when they overlap; ``None`` without other vehicles.

    Parameters
    ----------
    episode : Episode
        A finished episode.

    Returns
    -------
    float or None
    """
    log = episode.log
    others, states = log.others, log.states
    if others.size == 0 or len(states) == 0:
        return None
    vehicle = episode.scenario.vehicle
    ex, ey = ego_centres(states, vehicle)
    n, k = others.shape[:2]
    sizes = log.other_sizes
    centre = np.hypot(others[..., 0] - ex[:, None], others[..., 1] - ey[:, None])
    half_diag = 0.5 * (
        math.hypot(vehicle.length, vehicle.width) + np.hypot(sizes[:, 0], sizes[:, 1])
    )
    lower = centre - half_diag[None, :]
    # Only pairs that could beat the best upper bound (their centre distance) matter.
    ii, jj = np.nonzero(lower <= centre.min())
    ego = shapely.polygons(
        box_corners(ex[ii], ey[ii], states[ii, 2], -vehicle.length / 2.0, vehicle.length / 2.0,
                    vehicle.width / 2.0)
    )
    oth = shapely.polygons(
        box_corners(others[ii, jj, 0], others[ii, jj, 1], others[ii, jj, 2],
                    -sizes[jj, 0] / 2.0, sizes[jj, 0] / 2.0, sizes[jj, 1] / 2.0)
    )
    return float(np.min(shapely.distance(ego, oth)))


def progress(episode: Episode) -> float | None:
    """Arc length along the tracked path between the first and last logged rear axle (m).

    On a path with gear changes, travelled length over all its segments, each pose
    projected on the segment being driven; within one, on the stretch being driven
    (:func:`~rrtdrive.evaluation.tracking.followed_projection`). ``None`` when the path
    has fewer than two samples.

    Parameters
    ----------
    episode : Episode
        A finished episode.

    Returns
    -------
    float or None
    """
    path = episode.path
    if len(path) < 2:
        return None
    # Every pose, not only the two ends: on a path over its own ground the last one's
    # nearest point may lie on the way out (3.0 m for an 88.3 m path driven to its end,
    # an audit); along_path follows the drive (followed_projection).
    states = episode.log.states
    s_all = along_path(path, states[:, :2], states[:, 3])
    return float(s_all[-1] - s_all[0])
