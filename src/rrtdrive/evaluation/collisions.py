"""Collision judges: the exact body against the map and against the other vehicles.

:func:`map_collision` and :func:`footprint_collisions` are the footprint judge of
``docs/metrics.md``; :func:`vehicle_collisions` classifies collisions with other
vehicles as nuPlan's ``no_ego_at_fault_collisions``. Box tests use shapely.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
import shapely

from rrtdrive.geometry import box_corners, densify
from rrtdrive.vehicle import footprint_corners

if TYPE_CHECKING:  # pragma: no cover
    from rrtdrive.sim.episode import Episode

__all__ = [
    "COLLISION_STOPPED_SPEED",
    "map_collision",
    "logged_vehicle_obstacles",
    "footprint_collisions",
    "boxes_intersect",
    "ego_centres",
    "relative_angles",
    "travel_yaw",
    "between_lanes",
    "vehicle_collisions",
]

#: nuPlan's speed below which a car counts as stopped in a collision (m/s).
COLLISION_STOPPED_SPEED = 5e-2


def map_collision(episode: Episode, spacing: float, skip: Sequence[int] = ()) -> bool:
    """Exact body rectangle of every (densified) logged pose against the map and its bounds.

    ``skip``: indices of map obstacles left out (those that are logged vehicles).
    """
    from rrtdrive.planning.base import cached_checker

    states = episode.log.states
    if len(states) == 0:
        return False
    m = episode.scenario.map
    if skip:
        left_out = set(skip)
        kept = tuple(o for i, o in enumerate(m.obstacles) if i not in left_out)
        m = dataclasses.replace(m, obstacles=kept)
    # abs_slack: an exact multiple of the spacing gains no extra piece through rounding.
    dense = densify(states[:, :3], spacing, angle_column=2, abs_slack=1e-9).points
    # The exact test's grid screen: the planner's, so a map too big for the default grid
    # (simulate --resolution) is judged too.
    checker = cached_checker(m, episode.scenario.checker_config)
    return not bool(np.all(checker.poses_free(dense)))


def logged_vehicle_obstacles(episode: Episode) -> tuple[int, ...]:
    """Indices of the map obstacles that are also logged other vehicles.

    A parked car of a scene (the overtake's stopped car, parallel parking's row, a
    stock env's parked cars) is both: a map obstacle for the planner and a vehicle in
    the log. Matched by its box at the first logged time (centre, heading and size
    within 1 mm / 1 mrad).
    """
    others = episode.log.others
    if others.size == 0:
        return ()
    first, sizes = others[0], episode.log.other_sizes
    out = []
    for i, o in enumerate(episode.scenario.map.obstacles):
        near = (
            (np.abs(first[:, 0] - o.center[0]) <= 1e-3)
            & (np.abs(first[:, 1] - o.center[1]) <= 1e-3)
            & (np.abs(sizes[:, 0] - o.size[0]) <= 1e-3)
            & (np.abs(sizes[:, 1] - o.size[1]) <= 1e-3)
        )
        # A box turned by pi is the same box.
        turned = np.abs(np.sin(first[:, 2] - o.yaw)) <= 1e-3
        if bool(np.any(near & turned)):
            out.append(i)
    return tuple(out)


def footprint_collisions(episode: Episode, spacing: float, map_hit: bool | None = None) -> bool:
    """Exact body rectangle of every (densified) logged pose against the map and other cars."""
    m = episode.scenario.map
    states = episode.log.states
    if len(states) == 0:
        return False
    if map_hit is None:
        map_hit = map_collision(episode, spacing)
    if map_hit:
        return True
    others = episode.log.others
    if others.size == 0:
        return False
    # Moving vehicles: compare at the logged times (their poses are body centres).
    vehicle = m.vehicle
    ego_polys = shapely.polygons(footprint_corners(states[:, :3], vehicle))
    for k, (length, width) in enumerate(episode.log.other_sizes):
        o = others[:, k, :]
        hl, hw = length / 2.0, width / 2.0
        polys = shapely.polygons(box_corners(o[:, 0], o[:, 1], o[:, 2], -hl, hl, hw))
        if bool(np.any(shapely.intersects(ego_polys, polys))):
            return True
    return False


def boxes_intersect(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Whether convex quadrilaterals ``(..., 4, 2)`` intersect (shapely); touching counts.

    The leading shapes of ``a`` and ``b`` broadcast against each other. Only pairs
    whose circumscribed circles meet go to shapely (the others cannot intersect).
    """
    a, b = np.broadcast_arrays(np.asarray(a, dtype=float), np.asarray(b, dtype=float))
    ca, cb = a.mean(axis=-2), b.mean(axis=-2)
    ra = np.max(np.linalg.norm(a - ca[..., None, :], axis=-1), axis=-1)
    rb = np.max(np.linalg.norm(b - cb[..., None, :], axis=-1), axis=-1)
    near = np.linalg.norm(ca - cb, axis=-1) <= (ra + rb) * (1.0 + 1e-9) + 1e-9
    out = np.zeros(a.shape[:-2], dtype=bool)
    out[near] = shapely.intersects(shapely.polygons(a[near]), shapely.polygons(b[near]))
    return out


def ego_centres(states: np.ndarray, vehicle: Any) -> tuple[np.ndarray, np.ndarray]:
    """Body-centre positions ``(x, y)`` of logged rear-axle states."""
    d = vehicle.length / 2.0 - vehicle.rear_overhang
    return (
        states[:, 0] + d * np.cos(states[:, 2]),
        states[:, 1] + d * np.sin(states[:, 2]),
    )


def travel_yaw(states: np.ndarray) -> np.ndarray:
    """The direction the ego moves in: its nose heading, turned by pi while it reverses."""
    return np.where(states[:, 3] < 0.0, states[:, 2] + math.pi, states[:, 2])


def relative_angles(states: np.ndarray, others: np.ndarray) -> np.ndarray:
    """Angle between the ego's direction of travel and the rear axle -> agent centre, ``(N, K)``.

    nuPlan's ``get_agent_relative_angle`` about the ego's heading, which is its
    direction of travel there (nuPlan's ego never reverses); here a reversing ego
    looks the way it moves (:func:`travel_yaw`), so the cars it backs towards are
    ahead of it and those past its nose behind.
    """
    dx = others[..., 0] - states[:, None, 0]
    dy = others[..., 1] - states[:, None, 1]
    norm = np.maximum(np.hypot(dx, dy), 1e-12)
    yaw = travel_yaw(states)
    dot = (np.cos(yaw)[:, None] * dx + np.sin(yaw)[:, None] * dy) / norm
    return np.arccos(np.clip(dot, -1.0, 1.0))


def between_lanes(episode: Episode) -> np.ndarray:
    """Per logged time: the ego body is in more than one lane or off the road (road scenarios)."""
    scen = episode.scenario
    states = episode.log.states
    if scen.lane_y is None:
        return np.zeros(len(states), dtype=bool)
    corners = footprint_corners(states[:, :3], scen.vehicle)[..., 1]
    w = scen.lane_width
    low, mid, high = scen.lane_y - w / 2.0, scen.lane_y + w / 2.0, scen.lane_y + 1.5 * w
    straddles = (corners.min(axis=1) < mid) & (corners.max(axis=1) > mid)
    off = (corners.min(axis=1) < low) | (corners.max(axis=1) > high)
    return straddles | off


def vehicle_collisions(episode: Episode) -> list[tuple[int, int, str, bool]]:
    """Collisions with other vehicles, classified as nuPlan's ``no_ego_at_fault_collisions``.

    A collision is the first logged time at which the ego's body rectangle
    intersects another vehicle's (each vehicle counts once). Its type: the ego
    stopped (speed <= 0.05 m/s: not at fault); the other vehicle stopped (at
    fault); the other vehicle's centre behind the ego (more than 150° off the ego
    heading seen from the rear axle: a rear collision, not at fault); the ego's
    front bumper touches it (a front collision, at fault); else lateral, at fault
    when the ego is in more than one lane or off the road.

    Parameters
    ----------
    episode : Episode
        A finished episode with its log of the other vehicles.

    Returns
    -------
    list of (int, int, str, bool)
        ``(step, vehicle index, type, at_fault)`` with type ``"stopped_ego"``,
        ``"stopped_track"``, ``"active_rear"``, ``"active_front"`` or ``"active_lateral"``.
    """
    log = episode.log
    others = log.others
    states = log.states
    if others.size == 0 or len(states) == 0:
        return []
    vehicle = episode.scenario.vehicle
    ex, ey = ego_centres(states, vehicle)
    n, k = others.shape[:2]
    half_l = vehicle.length / 2.0
    ego_box = box_corners(ex, ey, states[:, 2], -half_l, half_l, vehicle.width / 2.0)
    sizes = log.other_sizes
    boxes = box_corners(
        others[..., 0], others[..., 1], others[..., 2],
        -sizes[:, 0] / 2.0, sizes[:, 0] / 2.0, sizes[:, 1] / 2.0,
    )
    hit = boxes_intersect(ego_box[:, None], boxes)
    if not hit.any():
        return []
    angles = relative_angles(states, others)
    between = between_lanes(episode)
    out = []
    for j in np.flatnonzero(hit.any(axis=0)).tolist():
        i = int(np.argmax(hit[:, j]))
        if abs(states[i, 3]) <= COLLISION_STOPPED_SPEED:
            kind, fault = "stopped_ego", False
        elif abs(others[i, j, 3]) <= COLLISION_STOPPED_SPEED:
            kind, fault = "stopped_track", True
        elif angles[i, j] > math.radians(150.0):
            kind, fault = "active_rear", False
        elif bool(
            shapely.intersects(
                # The bumper in the direction of travel: the rear one while reversing.
                shapely.linestrings(ego_box[i, [1, 2] if states[i, 3] >= 0.0 else [3, 0]]),
                shapely.polygons(boxes[i, j]),
            )
        ):
            kind, fault = "active_front", True
        else:
            kind, fault = "active_lateral", bool(between[i])
        out.append((i, j, kind, fault))
    return out
