"""An independent check of a planned path's guarantees, for tests and experiments.

It shares no code with the planner or the checker (only the angle wrap and the
densifier of :mod:`rrtdrive.geometry`): the body is a shapely polygon built
here, curvature is the discrete three-point (Menger) curvature of the samples,
and headings are compared at the ends.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import shapely

from rrtdrive.geometry import densify, wrap_angle
from rrtdrive.maps import Map
from rrtdrive.types import Path

__all__ = ["PathCheck", "verify_path"]


@dataclass(frozen=True)
class PathCheck:
    """Outcome of :func:`verify_path`; ``ok`` is True when every guarantee holds."""

    ok: bool
    collision_free: bool
    curvature_ok: bool
    headings_ok: bool
    endpoints_ok: bool
    spacing_ok: bool
    max_discrete_curvature: float
    start_heading_err_deg: float
    goal_heading_err_deg: float
    max_spacing_m: float


def _menger(xy: np.ndarray) -> np.ndarray:
    a, b, c = xy[:-2], xy[1:-1], xy[2:]
    ab, bc, ca = b - a, c - b, a - c
    cross = np.abs(ab[:, 0] * bc[:, 1] - ab[:, 1] * bc[:, 0])
    denom = np.hypot(*ab.T) * np.hypot(*bc.T) * np.hypot(*ca.T)
    return np.where(denom > 1e-12, 2.0 * cross / np.maximum(denom, 1e-300), 0.0)


def _body(x: float, y: float, yaw: float, length: float, width: float, back: float):
    c, s = math.cos(yaw), math.sin(yaw)
    pts = [
        (x + c * lx - s * ly, y + s * lx + c * ly)
        for lx, ly in ((-back, -width / 2), (length - back, -width / 2),
                       (length - back, width / 2), (-back, width / 2))
    ]
    return shapely.Polygon(pts)


def verify_path(
    m: Map,
    path: Path,
    pose_spacing: float = 0.1,
    max_sample_spacing: float = 0.25,
    heading_tol_deg: float = 3.0,
    curvature_tol: float = 0.01,
) -> PathCheck:
    """Check a path against the map with code independent of the planner.

    Parameters
    ----------
    m : Map
        The map (obstacles, bounds, start, goal, car).
    path : Path
        The planned path.
    pose_spacing : float
        Poses are tested at most this far apart (interpolated between samples).
    max_sample_spacing : float
        Largest allowed gap between consecutive samples.
    heading_tol_deg : float
        Allowed heading error at the start and the goal.
    curvature_tol : float
        Slack on κ_max for the discrete curvature of 0.25 m samples.

    Returns
    -------
    PathCheck
    """
    v = m.vehicle
    s = path.samples
    if len(s) < 2:
        return PathCheck(False, False, False, False, False, False, math.inf, 180.0, 180.0, math.inf)
    xy = s[:, :2]
    gaps = np.hypot(*np.diff(xy, axis=0).T)
    # Dense poses: heading from the samples' own yaw column, interpolated.
    dense = densify(s[:, :3], pose_spacing, angle_column=2).points
    bodies = [_body(x, y, yaw, v.length, v.width, v.rear_overhang) for x, y, yaw in dense]
    region = shapely.box(*m.bounds)
    obstacles = shapely.union_all([shapely.Polygon(o.corners()) for o in m.obstacles])
    collision_free = bool(
        all(region.contains(b) for b in bodies)
        and not np.any(shapely.intersects(obstacles, np.array(bodies, dtype=object)))
    )
    # Discrete curvature over points about 0.5 m apart (less noise than adjacent samples).
    keep = [0]
    acc = 0.0
    for i, g in enumerate(gaps, start=1):
        acc += g
        if acc >= 0.5:
            keep.append(i)
            acc = 0.0
    if keep[-1] != len(xy) - 1:
        keep.append(len(xy) - 1)
    kappa = _menger(xy[keep]) if len(keep) >= 3 else np.zeros(1)
    max_k = float(kappa.max()) if len(kappa) else 0.0
    # Chord of the first and last sample gaps: at most 0.25 m long, so even at
    # kappa_max the chord deviates from the tangent by under 0.7 degrees.
    start_dir = math.atan2(*(xy[1] - xy[0])[::-1])
    goal_dir = math.atan2(*(xy[-1] - xy[-2])[::-1])
    err_s = abs(wrap_angle(start_dir - m.start.yaw))
    err_g = abs(wrap_angle(goal_dir - m.goal.yaw))
    endpoints_ok = bool(
        np.allclose(xy[0], (m.start.x, m.start.y), atol=1e-6)
        and np.allclose(xy[-1], (m.goal.x, m.goal.y), atol=1e-6)
    )
    curvature_ok = max_k <= v.kappa_max + curvature_tol
    headings_ok = math.degrees(max(err_s, err_g)) <= heading_tol_deg
    spacing_ok = float(gaps.max()) <= max_sample_spacing + 1e-6
    return PathCheck(
        ok=collision_free and curvature_ok and headings_ok and endpoints_ok and spacing_ok,
        collision_free=collision_free,
        curvature_ok=curvature_ok,
        headings_ok=headings_ok,
        endpoints_ok=endpoints_ok,
        spacing_ok=spacing_ok,
        max_discrete_curvature=max_k,
        start_heading_err_deg=math.degrees(err_s),
        goal_heading_err_deg=math.degrees(err_g),
        max_spacing_m=float(gaps.max()),
    )
