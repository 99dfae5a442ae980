"""Collision judges: the exact body against the map and against the other vehicles.

:func:`map_collision` and :func:`footprint_collisions` are the footprint judge of
``docs/metrics.md``; :func:`vehicle_collisions` classifies collisions with other
vehicles as nuPlan's ``no_ego_at_fault_collisions``. Box tests use shapely.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np
import shapely

from rrtdrive.types import wrap_angle
from rrtdrive.vehicle import footprint_corners

if TYPE_CHECKING:  # pragma: no cover
    from rrtdrive.sim.episode import Episode

__all__ = [
    "COLLISION_STOPPED_SPEED",
    "densify_poses",
    "map_collision",
    "footprint_collisions",
    "box_corners",
    "boxes_intersect",
    "ego_centres",
    "relative_angles",
    "between_lanes",
    "vehicle_collisions",
]

#: nuPlan's speed below which a car counts as stopped in a collision (m/s).
COLLISION_STOPPED_SPEED = 5e-2


def densify_poses(poses: np.ndarray, spacing: float) -> np.ndarray:
    """Linear interpolation of ``(N, 3)`` poses so consecutive ones are at most ``spacing`` apart.

    Examples
    --------
    >>> densify_poses(np.array([[0.0, 0, 0], [1.0, 0, 0]]), 0.25).shape
    (5, 3)
    """
    p = np.asarray(poses, dtype=float).reshape(-1, 3)
    if len(p) < 2:
        return p
    step = np.hypot(*np.diff(p[:, :2], axis=0).T)
    pieces = np.maximum(1, np.ceil(step / spacing - 1e-9).astype(np.int64))
    owner = np.repeat(np.arange(len(step)), pieces)
    first = np.repeat(np.cumsum(pieces) - pieces, pieces)
    frac = (np.arange(len(owner)) - first) / np.repeat(pieces, pieces)
    a, b = p[owner], p[owner + 1]
    dyaw = wrap_angle(b[:, 2] - a[:, 2])
    out = np.column_stack([a[:, :2] + frac[:, None] * (b[:, :2] - a[:, :2]), a[:, 2] + frac * dyaw])
    return np.vstack([out, p[-1:]])


def map_collision(episode: Episode, spacing: float) -> bool:
    """Exact body rectangle of every (densified) logged pose against the map and its bounds."""
    from rrtdrive.planning.base import cached_checker

    states = episode.log.states
    if len(states) == 0:
        return False
    dense = densify_poses(states[:, :3], spacing)
    return not bool(np.all(cached_checker(episode.scenario.map).poses_free(dense)))


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
        c, s_ = np.cos(o[:, 2]), np.sin(o[:, 2])
        hl, hw = length / 2.0, width / 2.0
        local = np.array([[-hl, -hw], [hl, -hw], [hl, hw], [-hl, hw]])
        x = o[:, None, 0] + c[:, None] * local[None, :, 0] - s_[:, None] * local[None, :, 1]
        y = o[:, None, 1] + s_[:, None] * local[None, :, 0] + c[:, None] * local[None, :, 1]
        polys = shapely.polygons(np.stack([x, y], axis=-1))
        if bool(np.any(shapely.intersects(ego_polys, polys))):
            return True
    return False


def box_corners(cx: np.ndarray, cy: np.ndarray, h: np.ndarray, length: np.ndarray,
                 width: np.ndarray) -> np.ndarray:
    """Corners ``(..., 4, 2)`` of centred oriented boxes.

    In nuPlan's ``OrientedBox`` order: front-left, rear-left, rear-right, front-right.
    """
    c, s = np.cos(h), np.sin(h)
    hl, hw = length / 2.0, width / 2.0
    lx = np.stack([hl, -hl, -hl, hl], axis=-1) * np.ones_like(cx)[..., None]
    ly = np.stack([hw, hw, -hw, -hw], axis=-1) * np.ones_like(cx)[..., None]
    x = cx[..., None] + c[..., None] * lx - s[..., None] * ly
    y = cy[..., None] + s[..., None] * lx + c[..., None] * ly
    return np.stack([x, y], axis=-1)


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


def relative_angles(states: np.ndarray, others: np.ndarray) -> np.ndarray:
    """Angle between the ego heading and the rear axle -> agent centre vector, ``(N, K)``.

    nuPlan's ``get_agent_relative_angle``.
    """
    dx = others[..., 0] - states[:, None, 0]
    dy = others[..., 1] - states[:, None, 1]
    norm = np.maximum(np.hypot(dx, dy), 1e-12)
    dot = (np.cos(states[:, 2])[:, None] * dx + np.sin(states[:, 2])[:, None] * dy) / norm
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
    ego_box = box_corners(
        ex, ey, states[:, 2], np.full(n, vehicle.length), np.full(n, vehicle.width)
    )
    sizes = log.other_sizes
    boxes = box_corners(
        others[..., 0], others[..., 1], others[..., 2],
        np.broadcast_to(sizes[:, 0], (n, k)), np.broadcast_to(sizes[:, 1], (n, k)),
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
                shapely.linestrings(ego_box[i, [0, 3]]), shapely.polygons(boxes[i, j])
            )
        ):
            kind, fault = "active_front", True
        else:
            kind, fault = "active_lateral", bool(between[i])
        out.append((i, j, kind, fault))
    return out
