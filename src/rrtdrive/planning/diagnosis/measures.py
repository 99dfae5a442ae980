"""The measures the findings are made of, on the map's exact geometry and its checker."""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import shapely

from rrtdrive.collision import CollisionChecker
from rrtdrive.maps import Map, Obstacle
from rrtdrive.types import Pose, VehicleParams

__all__ = [
    "ACROSS",
    "ARC_FRACTIONS",
    "RUN_STEP",
    "MapShapes",
    "along",
    "arc_poses",
    "best_run",
    "body_centre",
    "cell_centres",
    "edge_keep",
    "end_keep",
    "first_hit",
    "free_run",
    "gap_width",
    "grid_cell",
    "joined_in_free_space",
    "map_shapes",
    "nearest_obstacle",
    "obstacle_name",
    "ray_runs",
    "street_width",
    "turning_circle",
    "u_turn_width",
]

#: Spacing of the poses tested along a free run, metres.
RUN_STEP = 0.05
#: Steady-steering arcs tried for a free run, as fractions of kappa_max: the five of
#: before first, then every eighth between (a car backing 12 m at a quarter lock past two
#: posts was told "at most 4.22 m on any steady steering": a helper's audit, session 34).
ARC_FRACTIONS = (-1.0, -0.5, 0.0, 0.5, 1.0, -0.75, -0.25, 0.25, 0.75,
                 -0.875, -0.625, -0.375, -0.125, 0.125, 0.375, 0.625, 0.875)  # fmt: skip


def u_turn_width(vehicle: VehicleParams) -> float:
    """Width of the strip a forward U-turn on the tightest circle sweeps.

    The outer front corner runs on radius ``hypot(R + W/2, front_extent)`` and
    reaches that far beyond the turning centre; the outer rear corner swings
    ``hypot(R + W/2, rear_overhang)`` to the other side of it. Their sum is
    ``2 R`` plus the body's swept width, overhangs included.

    Parameters
    ----------
    vehicle : VehicleParams
        The car (turning radius ``R``, width ``W``, overhangs).

    Returns
    -------
    float
        Metres.

    Examples
    --------
    >>> round(u_turn_width(VehicleParams()), 2)
    14.65
    """
    r = vehicle.min_turning_radius + vehicle.width / 2.0
    return math.hypot(r, vehicle.front_extent) + math.hypot(r, vehicle.rear_overhang)


def turning_circle(vehicle: VehicleParams) -> float:
    """Diameter of the free circle a car turns round in without reversing.

    Within a round place (no street to swing the rear into) the outer front corner's
    circle, ``2 hypot(R + W/2, front_extent)``, must fit.

    Examples
    --------
    >>> round(turning_circle(VehicleParams()), 2)
    15.39
    """
    return 2.0 * math.hypot(vehicle.min_turning_radius + vehicle.width / 2.0, vehicle.front_extent)


def arc_poses(pose: Pose, direction: int, kappa: float, length: float, step: float) -> np.ndarray:
    """Poses ``(N, 3)`` every ``step`` along a steady-steering arc, the start excluded.

    ``direction`` +1 drives forward, -1 backs; ``kappa`` is the steering's curvature.
    """
    s = np.arange(1, int(math.floor(length / step + 1e-9)) + 1) * step
    return along(pose, direction * s, kappa)


def along(pose: Pose, s: np.ndarray, kappa: float) -> np.ndarray:
    """Poses at signed arc lengths ``s`` on the arc of curvature ``kappa`` from ``pose``."""
    s = np.asarray(s, dtype=float)
    yaw = pose.yaw + kappa * s
    if abs(kappa) < 1e-12:
        x = pose.x + s * math.cos(pose.yaw)
        y = pose.y + s * math.sin(pose.yaw)
    else:
        x = pose.x + (np.sin(yaw) - math.sin(pose.yaw)) / kappa
        y = pose.y - (np.cos(yaw) - math.cos(pose.yaw)) / kappa
    return np.column_stack([x, y, yaw])


def free_run(
    checker: CollisionChecker, pose: Pose, direction: int, kappa: float, limit: float
) -> float:
    """How far the car drives from ``pose`` on a steady arc before its body collides.

    Parameters
    ----------
    checker : CollisionChecker
        The map's checker (its exact body test is used).
    pose : Pose
        Rear-axle pose to leave.
    direction : int
        +1 forward, -1 reverse.
    kappa : float
        Curvature of the arc (0: straight).
    limit : float
        Longest run looked at; returned when nothing is hit.

    Returns
    -------
    float
        The run in metres: poses every :data:`RUN_STEP`, the first hit refined by
        bisection to a millimetre (a lower bound of the true run).
    """
    poses = arc_poses(pose, direction, kappa, limit, RUN_STEP)
    if len(poses) == 0:
        return limit
    bad = np.flatnonzero(~checker.poses_free(poses))
    if len(bad) == 0:
        return limit
    lo, hi = float(bad[0]) * RUN_STEP, float(bad[0] + 1) * RUN_STEP
    while hi - lo > 1e-3:
        mid = 0.5 * (lo + hi)
        if checker.pose_free(along(pose, np.array([direction * mid]), kappa)[0]):
            lo = mid
        else:
            hi = mid
    return lo


def best_run(
    checker: CollisionChecker, pose: Pose, direction: int, vehicle: VehicleParams, limit: float
) -> float:
    """The longest :func:`free_run` over the steady arcs of :data:`ARC_FRACTIONS`."""
    best = 0.0
    for f in ARC_FRACTIONS:
        best = max(best, free_run(checker, pose, direction, f * vehicle.kappa_max, limit))
        if best >= limit:
            break
    return best


@dataclass(frozen=True, eq=False)
class MapShapes:
    """The map's shapes the findings measure against, built once per checker.

    The unions are built when first asked for (a finding needs one or none): on a map
    of 50 000 obstacles both took 8.5 s, and the free space cut from a union that held
    the bounds' outline 8.4 s more (0.5 s from the obstacles' union alone).
    """

    polygons: np.ndarray  # one shapely polygon per obstacle, in map order
    edge: shapely.Geometry  # the bounds' outline
    checker: CollisionChecker  # its obstacle union, shared with its exact body test

    @functools.cached_property
    def walls(self) -> shapely.Geometry:
        """Obstacle outlines and the bounds' outline."""
        return shapely.union_all([self.edge, *shapely.get_exterior_ring(self.polygons)])

    @functools.cached_property
    def solid(self) -> shapely.Geometry:
        """Obstacle areas and the bounds' outline."""
        return shapely.union(self.edge, self.checker.grid.obstacle_union)


def map_shapes(checker: CollisionChecker) -> MapShapes:
    """The map's :class:`MapShapes`, built once per checker (cached on its grid)."""
    def build() -> MapShapes:
        polys = np.array([o.polygon() for o in checker.obstacles], dtype=object)
        return MapShapes(polys, shapely.box(*checker.bounds).exterior, checker)

    return checker.grid.derived("diagnosis_shapes", build)


def joined_in_free_space(checker: CollisionChecker, p: Pose, q: Pose) -> bool:
    """Whether the points ``p`` and ``q`` lie in one piece of the map's free space.

    Exact (shapely): a gap of any width joins them, however narrow for the grid.
    """
    free = shapely.box(*checker.bounds).difference(checker.grid.obstacle_union)
    here, there = shapely.Point(p.x, p.y), shapely.Point(q.x, q.y)
    return any(
        piece.intersects(here) and piece.intersects(there)
        for piece in shapely.get_parts(free)
    )


def first_hit(checker: CollisionChecker, body: shapely.Geometry) -> int:
    """Index of the first obstacle ``body`` overlaps, -1 for none (the bounds)."""
    hits = np.flatnonzero(shapely.intersects(map_shapes(checker).polygons, body))
    return int(hits[0]) if len(hits) else -1


def nearest_obstacle(
    m: Map, body: shapely.Geometry, checker: CollisionChecker | None = None
) -> tuple[int, float]:
    """The obstacle nearest to ``body`` and its distance; index -1 is the map's edge.

    With ``checker`` (the map's), its cached obstacle polygons are used.

    Parameters
    ----------
    m : Map
        The map (its obstacles and bounds).
    body : shapely.Geometry
        The shape to measure from (a car's body rectangle).
    checker : CollisionChecker, optional
        The map's checker (``None``: the polygons are made from ``m``).

    Returns
    -------
    index : int
        The obstacle's index in ``m.obstacles``, -1 for the map's edge.
    distance : float
        Metres (0 when they touch or overlap).
    """
    edge = shapely.box(*m.bounds).exterior.distance(body)
    if not m.obstacles:
        return -1, float(edge)
    if checker is not None:
        polys = map_shapes(checker).polygons
    else:
        polys = np.array([o.polygon() for o in m.obstacles], dtype=object)
    d = shapely.distance(polys, body)
    i = int(np.argmin(d))
    return (i, float(d[i])) if d[i] <= edge else (-1, float(edge))


#: Directions about the heading's normal that :func:`street_width` measures across, rad.
ACROSS = np.radians(np.arange(-45.0, 45.5, 1.0))


def street_width(
    m: Map,
    point: tuple[float, float],
    yaw: float,
    reach: float = 1e3,
    checker: CollisionChecker | None = None,
) -> float:
    """Free width of the street at ``point``, across heading ``yaw``: wall to wall.

    Measured exactly with shapely along lines through ``point``, to the first
    obstacle or edge each side, within 45 deg of the normal to the heading; the
    narrowest is the street's width (a car at 0.5 rad to a 10 m street read 11.4 m
    along its own normal). With ``checker``, the map's cached outlines are used.

    Parameters
    ----------
    m : Map
        The map (its obstacles and bounds).
    point : tuple of float
        ``(x, y)`` in metres.
    yaw : float
        The heading, radians.
    reach : float
        Longest ray each side, metres (a side that meets nothing counts this much).
    checker : CollisionChecker, optional
        The map's checker (``None``: the outlines are made from ``m``).

    Returns
    -------
    float
        Metres.
    """
    if checker is not None:
        walls = map_shapes(checker).walls
    else:
        walls = shapely.union_all(
            [shapely.box(*m.bounds).exterior, *(o.polygon().exterior for o in m.obstacles)]
        )
    normal = np.concatenate([yaw + ACROSS + 0.5 * math.pi, yaw + ACROSS - 0.5 * math.pi])
    run = ray_runs(np.asarray(point, dtype=float), normal, walls, reach)
    return float(np.min(run[: len(ACROSS)] + run[len(ACROSS):]))


def ray_runs(
    origin: np.ndarray, angles: np.ndarray, walls: shapely.Geometry, reach: float
) -> np.ndarray:
    """Distance from ``origin`` along each direction in ``angles`` to the first of ``walls``.

    ``reach`` where a ray meets none. Every ray against every wall segment at once
    (numpy): shapely's intersection took 1.2 ms a ray on parking_lot's outlines.
    """
    segments = [
        np.stack([c[:-1], c[1:]], axis=1)
        for c in (shapely.get_coordinates(line) for line in shapely.get_parts(walls))
        if len(c) > 1
    ]
    if not segments:
        return np.full(len(angles), reach)
    seg = np.concatenate(segments)  # (S, 2, 2)
    a, e = seg[:, 0], seg[:, 1] - seg[:, 0]
    d = np.column_stack([np.cos(angles), np.sin(angles)])  # (R, 2)
    w = a - origin  # origin + t d = a + u e
    denom = d[:, None, 0] * e[None, :, 1] - d[:, None, 1] * e[None, :, 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (w[None, :, 0] * e[None, :, 1] - w[None, :, 1] * e[None, :, 0]) / denom
        u = (w[None, :, 0] * d[:, None, 1] - w[None, :, 1] * d[:, None, 0]) / denom
    hit = (denom != 0.0) & (t >= 0.0) & (t <= reach) & (u >= 0.0) & (u <= 1.0)
    return np.where(hit, t, reach).min(axis=1)


def body_centre(pose: Pose, vehicle: VehicleParams) -> tuple[float, float]:
    """The centre of the car's body at rear-axle ``pose``."""
    off = vehicle.front_extent - vehicle.length / 2.0
    return (pose.x + off * math.cos(pose.yaw), pose.y + off * math.sin(pose.yaw))


def obstacle_name(index: int, obstacles: Sequence[Obstacle] = ()) -> str:
    """``"obstacle i at (x, y)"``, or ``"the map's edge"`` for index -1, for messages.

    The centre is given when ``obstacles`` has it: on an imported map of thousands of
    rectangles an index alone told the user nothing (a new user's find).

    Examples
    --------
    >>> obstacle_name(1, (Obstacle((2.0, 3.0), (1.0, 1.0)), Obstacle((10.26, -4.0), (2.0, 1.0))))
    'obstacle 1 at (10.3, -4.0)'
    >>> obstacle_name(-1), obstacle_name(3)
    ("the map's edge", 'obstacle 3')
    """
    if index < 0:
        return "the map's edge"
    if index < len(obstacles):
        cx, cy = obstacles[index].center
        return f"obstacle {index} at ({cx:.1f}, {cy:.1f})"
    return f"obstacle {index}"


def grid_cell(checker: CollisionChecker, p: tuple[float, float]) -> tuple[int, int] | None:
    """The checker's grid cell holding point ``p``, or ``None`` outside the grid."""
    g = (np.asarray(p, dtype=float) - checker.grid_origin) / checker.resolution
    i, j = int(math.floor(g[0])), int(math.floor(g[1]))
    nx, ny = checker.clearance_grid.shape
    return (i, j) if 0 <= i < nx and 0 <= j < ny else None


def cell_centres(checker: CollisionChecker, i: Any, j: Any) -> tuple[Any, Any]:
    """World centres of the grid cells ``(i, j)`` (indices or arrays of them)."""
    o, h = checker.grid_origin, checker.resolution
    return o[0] + (i + 0.5) * h, o[1] + (j + 0.5) * h



def edge_keep(checker: CollisionChecker) -> float:
    """The room beside the body the swept edge test needs: margin, grid error, trace step.

    Parameters
    ----------
    checker : CollisionChecker
        The map's checker (its settings and grid).

    Returns
    -------
    float
        Metres.
    """
    return checker.config.margin + checker.grid_error + checker.config.min_trace_step


def end_keep(checker: CollisionChecker) -> float:
    """The room beyond a bumper the swept edge test needs: its round end, grid error, step.

    Parameters
    ----------
    checker : CollisionChecker
        The map's checker (its edge radius, car, settings and grid).

    Returns
    -------
    float
        Metres.
    """
    r = checker.edge_radius
    inset = math.sqrt(max(r * r - (checker.vehicle.width / 2.0) ** 2, 0.0))
    return r - inset + checker.grid_error + checker.config.min_trace_step


def gap_width(checker: CollisionChecker, x: float, y: float) -> float:
    """Width of the gap at the grid cell ``(x, y)`` of its narrowest place.

    Twice the distance to the nearest wall from the cell's centre, which lies up to
    half a cell off the gap's centre line (a 1.85 m gap read 1.75 m); when the two
    nearest walls (obstacles, or sides of the bounds) are that far apart give or take
    a cell, their own distance, the gap's exact width.
    """
    shapes = map_shapes(checker)
    p = shapely.Point(x, y)
    around = 2.0 * float(p.distance(shapes.solid))
    # Each side of the bounds is a wall of its own: as one outline, a block touching
    # the top edge was 0 m from "the edge" and a gap between it and the bottom side
    # fell back to the cell-centre reading (1.83 m read 1.76 m, narrower than the car).
    xmin, ymin, xmax, ymax = checker.bounds
    corners = [(xmin, ymin), (xmax, ymin), (xmax, ymax), (xmin, ymax), (xmin, ymin)]
    sides = [shapely.LineString(corners[k : k + 2]) for k in range(4)]
    parts = [*sides, *shapes.polygons]
    d = shapely.distance(np.array(parts, dtype=object), p)
    if len(parts) < 2:
        return around
    i, j = (int(k) for k in np.argsort(d)[:2])
    between = float(shapely.distance(parts[i], parts[j]))
    return between if abs(between - around) <= 2.0 * checker.resolution else around

