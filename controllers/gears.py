"""Gear segments: a path with cusps is driven one gear segment at a time, reverse as a mirror.

A car reversing along a path is, kinematically, a car driving *forward* with its
heading turned by pi: with the rear-axle model ``x' = v cos(yaw)``,
``y' = v sin(yaw)``, ``yaw' = v tan(delta) / L`` and the substitution
``yaw~ = yaw + pi``, ``v~ = -v``, ``delta~ = -delta`` the equations are unchanged
(``v~ cos(yaw~) = v cos(yaw)``, ``v~ tan(delta~) = v tan(delta)``). So a reverse
segment becomes a forward problem for this *mirrored* car: the path's nose yaw turned
by pi (the direction of travel) and its curvature negated (``tan(delta~) / L``),
and the car's pose, speed and steering mirrored the same way. Every forward
controller then tracks reverse unchanged; its acceleration and steering commands
are mirrored back (both negated).

The reference points follow: pure pursuit stays on the rear axle (the point
without side slip, in both cars); Stanley's steered point of the mirrored car lies
``L`` beyond the rear axle in the direction of travel, a point whose velocity turns
with the wheels exactly as a front axle's does (``yaw~ + delta~``), so Stanley's
first-order cross-track law holds in reverse too; LQR's error model is written in
the direction of travel.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rrtdrive.types import Path

__all__ = ["CUSP_SPEED", "GearSegment", "gear_segments", "mirror_path", "mirror_state_values"]

#: The car counts as standing still at a cusp (and changes gear) at this speed or
#: below, m/s: the speed loop's hold stops it exactly within a step.
CUSP_SPEED = 1e-3

#: A gear segment shorter than this (metres) is not driven (a repeated cusp row).
MIN_SEGMENT_M = 1e-6


@dataclass(frozen=True, eq=False)
class GearSegment:
    """One gear segment of a path, as the forward problem a controller tracks.

    Attributes
    ----------
    gear : int
        +1 forward, -1 reverse.
    path : Path
        The segment to track forward: the segment itself in gear +1, its mirror
        (:func:`mirror_path`) in reverse; every row in gear +1.
    s0 : float
        Travelled length along the whole path at the segment's start (metres).
    length : float
        Travelled length of the segment.
    """

    gear: int
    path: Path
    s0: float
    length: float


def mirror_path(path: Path) -> Path:
    """The forward image of a reverse path: yaw turned by pi, curvature negated, gear +1.

    Parameters
    ----------
    path : Path
        The path to mirror (normally one reverse gear segment); its waypoints are kept.

    Returns
    -------
    Path
        The same positions with ``yaw + pi`` (not wrapped), ``-kappa`` and gear +1.

    Examples
    --------
    >>> xs = np.linspace(0.0, 2.0, 3)
    >>> back = Path(np.column_stack([xs[::-1], 0 * xs, 0 * xs, 0.1 + 0 * xs, -1 + 0 * xs]),
    ...             np.zeros((0, 2)))
    >>> mirror_path(back).samples[0].round(4).tolist()
    [2.0, 0.0, 3.1416, -0.1, 1.0]
    """
    s = np.array(path.samples, dtype=float)
    s[:, 2] = s[:, 2] + math.pi
    s[:, 3] = -s[:, 3]
    s[:, 4] = 1.0
    return Path(s, path.waypoints)


def mirror_state_values(
    yaw: float, speed: float, steer: float
) -> tuple[float, float, float]:
    """``(yaw + pi, -speed, -steer)``, the yaw wrapped into ``[-pi, pi)`` (see the module docs).

    Examples
    --------
    >>> [round(v, 4) for v in mirror_state_values(0.5, -1.0, 0.2)]
    [-2.6416, 1.0, -0.2]
    """
    m = yaw + math.pi
    if m >= math.pi:
        m -= 2.0 * math.pi
    return m, -speed, -steer


def gear_segments(path: Path) -> list[GearSegment]:
    """The gear segments of ``path`` in driving order, each as a forward problem.

    A forward-only path gives one segment whose ``path`` is ``path`` itself (so
    forward tracking is exactly what it was before gears existed). Segments with
    no length (a repeated row) are dropped.

    Parameters
    ----------
    path : Path
        The path to split at its cusps.

    Returns
    -------
    list of GearSegment
        In driving order; ``s0`` and ``length`` measured along ``path``.

    Examples
    --------
    >>> xs = np.linspace(0.0, 5.0, 6)
    >>> fwd = np.column_stack([xs, 0 * xs, 0 * xs, 0 * xs, 1 + 0 * xs])
    >>> back = np.column_stack([xs[::-1], 0 * xs, 0 * xs, 0 * xs, -1 + 0 * xs])
    >>> segs = gear_segments(Path(np.vstack([fwd, back]), np.zeros((0, 2))))
    >>> [(g.gear, g.s0, g.length) for g in segs]
    [(1, 0.0, 5.0), (-1, 5.0, 5.0)]
    """
    if path.is_forward_only:
        return [GearSegment(1, path, 0.0, path.length)]
    out: list[GearSegment] = []
    s0 = 0.0
    for a, b in path.segments():
        seg = Path(path.samples[a:b], path.waypoints)
        length = seg.length
        if length > MIN_SEGMENT_M:
            gear = int(seg.samples[0, 4])
            out.append(GearSegment(gear, seg if gear > 0 else mirror_path(seg), s0, length))
        s0 += length
    return out
