"""Checks of a map's name, start and goal, and warnings about likely slips in a map.

:func:`check_endpoint` refuses a pose the car cannot stand at (outside or touching
the bounds, on an obstacle, a yaw beyond :data:`MAX_YAW`); :func:`warn_if_degrees`
and :func:`warn_outside` warn (:class:`~rrtdrive.types.InputWarning`) about input
that is valid but probably not what was meant.
"""

from __future__ import annotations

import math
import unicodedata
import warnings
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np
import shapely

from rrtdrive.types import (
    InputError,
    InputWarning,
    Pose,
    VehicleParams,
    brief_repr,
    require_finite,
    require_positive,
)
from rrtdrive.vehicle import footprint_polygon

if TYPE_CHECKING:  # pragma: no cover
    from rrtdrive.maps import Map

__all__ = [
    "MAX_COORDINATE",
    "MAX_YAW",
    "check_endpoint",
    "check_name",
    "check_obstacle_numbers",
    "warn_if_degrees",
    "warn_obstacle_yaws",
    "warn_outside",
]


#: The largest coordinate a map may use, metres: doubles there are spaced 1.2e-7 m apart,
#: well inside the 1e-6 m that path ends are checked to (at 1e15 m a solved path failed
#: its own check: curvature, spacing and headings all rounded away).
MAX_COORDINATE = 1e9
#: The largest start or goal heading, radians (spaced 1e-10 rad apart there; 1e12 rad
#: could not be planned).
MAX_YAW = 1e6


def _past_a_full_turn(yaw: float) -> bool:
    # Beyond MAX_YAW the pose is refused where it is checked: no "taken as" first.
    return 2.0 * math.pi + 1e-9 < abs(yaw) <= MAX_YAW


def warn_if_degrees(label: str, yaw: float) -> None:
    """Warn (:class:`InputWarning`) when ``yaw`` is more than a full turn: likely degrees.

    Such a yaw is a valid angle (it wraps), so it is planned as given; the warning
    says what it is taken as and what to write for degrees.

    Parameters
    ----------
    label : str
        What the yaw belongs to, as the warning names it (``"problem.start"``).
    yaw : float
        The angle as given, radians; warned about when ``2 pi < |yaw| <=``
        :data:`MAX_YAW` (a larger one is refused where the pose is checked).
    """
    if _past_a_full_turn(yaw):
        wrapped = math.degrees(math.remainder(yaw, 2.0 * math.pi))
        if round(wrapped, 1) == 0.0:
            wrapped = 0.0  # -4 pi read "taken as -0.0 deg"
        warnings.warn(
            f"{label}: yaw {yaw:g} is more than a full turn; yaws are in radians, so it is "
            f"taken as {wrapped:.1f} deg; for {yaw:g} deg write {math.radians(yaw):.4f}",
            InputWarning,
            stacklevel=3,
        )


def warn_obstacle_yaws(yaws: Sequence[float]) -> None:
    """:func:`warn_if_degrees` for a map file's obstacles: one warning, not one each.

    The first such yaw is named and the others counted: a script's polygon of 5 000
    segments in radians past 2 pi printed 1 250 warning lines.
    """
    beyond = [i for i, yaw in enumerate(yaws) if _past_a_full_turn(yaw)]
    if beyond:
        more = len(beyond) - 1
        also = f" (and {more} more obstacle yaw{'s' if more > 1 else ''} past a full turn)"
        warn_if_degrees(f"obstacles[{beyond[0]}].yaw" + (also if more else ""), yaws[beyond[0]])


def check_obstacle_numbers(size: tuple[float, float], yaw: float) -> None:
    """Raise :class:`InputError` naming ``obstacle.size`` or ``obstacle.yaw``.

    For numbers a map cannot use: sizes not > 0 or beyond :data:`MAX_COORDINATE` (a
    corner at 5e16 m moves by metres: a wall of 1e17 m refused a start 2 m clear of it),
    a yaw not finite or beyond :data:`MAX_YAW` (as a pose's). A centre may lie far out:
    a long wall reaches in.
    """
    for side in size:
        require_positive("obstacle.size", side)
        if side > MAX_COORDINATE:
            raise InputError(
                f"obstacle.size: {side:g} m is longer than {MAX_COORDINATE:g} m; a wall "
                "need only reach across the bounds"
            )
    require_finite("obstacle.yaw", yaw)
    if abs(yaw) > MAX_YAW:
        raise InputError(
            f"obstacle.yaw: {yaw:g} rad is beyond {MAX_YAW:g} rad either way; give it in "
            "[-pi, pi]"
        )


def check_name(name: object) -> None:
    """Refuse a map name that is empty, not text, or cannot be printed on one line.

    Raises
    ------
    InputError
        Naming ``name``.

    Examples
    --------
    >>> check_name("lot")
    >>> check_name("")
    Traceback (most recent call last):
    ...
    rrtdrive.types.InputError: name: expected a non-empty string, got ''
    """
    if not isinstance(name, str) or not name:
        raise InputError(f"name: expected a non-empty string, got {brief_repr(name)}")
    try:
        name.encode("utf-8")
    except UnicodeEncodeError:
        # JSON's "\ud800" (half of a surrogate pair) is no character: no file or
        # terminal takes it, and printing the name ended in a traceback.
        raise InputError(
            f"name: {name!r} holds half of a UTF-16 surrogate pair, which is no "
            "character; write the character itself"
        ) from None
    control = next((c for c in name if unicodedata.category(c) == "Cc"), None)
    if control is not None:
        # Printed raw, a newline split the one-line summary and an escape recoloured
        # the terminal.
        raise InputError(
            f"name: {name!r} holds the control character {control!r}; names are "
            "printed on one line: use printable characters"
        )


def check_endpoint(
    m: Map, pose: Pose, label: str, vehicle: VehicleParams, warn_degrees: bool = True
) -> None:
    """Raise :class:`InputError` unless the car at ``pose`` lies in bounds and clear of obstacles.

    Parameters
    ----------
    m : Map
        The map (only bounds and obstacles are read).
    pose : Pose
        Rear-axle pose to check.
    label : str
        Field name for the message (``"start"`` or ``"goal"``).
    vehicle : VehicleParams
        The car.
    warn_degrees : bool
        Warn about a yaw that looks like degrees (off where the map already did).
    """
    xmin, ymin, xmax, ymax = m.bounds
    if abs(pose.yaw) > MAX_YAW:
        raise InputError(
            f"{label}: yaw {pose.yaw:.10g} rad is beyond {MAX_YAW:g} rad either way, where an "
            "angle keeps less than the precision headings are checked to; give it in [-pi, pi]"
        )
    if warn_degrees:
        warn_if_degrees(label, pose.yaw)
    if not (xmin <= pose.x <= xmax and ymin <= pose.y <= ymax):
        raise InputError(
            f"{label}: ({pose.x:.10g}, {pose.y:.10g}) lies outside the bounds {list(m.bounds)}"
        )
    body = footprint_polygon(pose.as_tuple(), vehicle)
    # The corners strictly inside, compared as numbers: exact at any size (shapely's
    # containment test of a 1 m body in bounds of +-1e200 overflowed and said "leaves").
    corners = np.asarray(body.exterior.coords)
    inside = (xmin < corners[:, 0]) & (corners[:, 0] < xmax)
    if not np.all(inside & (ymin < corners[:, 1]) & (corners[:, 1] < ymax)):
        # Touching counts, as for an obstacle: the simulator's walls stand on the bounds.
        raise InputError(
            f"{label}: the car's body at ({pose.x:.10g}, {pose.y:.10g}) leaves or touches the "
            "bounds"
        )
    polygons = np.array([o.polygon() for o in m.obstacles], dtype=object)
    hits = np.flatnonzero(shapely.intersects(polygons, body))
    if len(hits):
        i = int(hits[0])
        depth = overlap_depth(corners[:-1], np.asarray(polygons[i].exterior.coords)[:-1])
        # Touching counts as a collision; "overlaps by 0 m (the least shift ...)" read as
        # if no shift were needed.
        how = (
            f"overlaps obstacle {i} at {list(m.obstacles[i].center)} by {depth:.3g} m (the "
            "least shift that clears it)" if depth > 0.0
            else f"touches obstacle {i} at {list(m.obstacles[i].center)} (touching counts "
            "as a collision: move it clear)"
        )
        raise InputError(f"{label}: the car's body at ({pose.x:.10g}, {pose.y:.10g}) {how}")


def overlap_depth(a: np.ndarray, b: np.ndarray) -> float:
    """How far convex polygon ``a`` must move, at least, to stop overlapping convex ``b``.

    The separating-axis theorem: over every edge normal of both polygons, the least
    shift that parts the two projections is the length of the minimum translation (0
    when they are apart). A start 4.5 cm into a wall was refused without saying by how much.

    Parameters
    ----------
    a, b : numpy.ndarray
        ``(n, 2)`` vertices of each polygon, in order, not repeated at the end.

    Returns
    -------
    float
        Metres.

    Examples
    --------
    >>> square = np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [0.0, 2.0]])
    >>> round(overlap_depth(square, square + [1.7, 0.5]), 12)
    0.3
    >>> overlap_depth(square, square + [3.0, 0.0])
    0.0
    """
    least = np.inf
    for poly in (a, b):
        edges = np.roll(poly, -1, axis=0) - poly
        lengths = np.hypot(edges[:, 0], edges[:, 1])
        # A sliver's edge can be 0 long (its corners coincide): it has no normal.
        edges, lengths = edges[lengths > 0], lengths[lengths > 0]
        normals = np.column_stack([-edges[:, 1], edges[:, 0]]) / lengths[:, None]
        pa, pb = a @ normals.T, b @ normals.T
        # The shift along each normal that parts the projections, either way (not their
        # common length: one inside the other needs more than that).
        shift = np.minimum(pa.max(axis=0) - pb.min(axis=0), pb.max(axis=0) - pa.min(axis=0))
        least = min(least, float(shift.min()))
    return max(least, 0.0)


def warn_outside(m: Map) -> None:
    """Warn about obstacles lying wholly outside the bounds: they block nothing there."""
    xmin, ymin, xmax, ymax = m.bounds
    for i, o in enumerate(m.obstacles):
        ox0, oy0, ox1, oy1 = o.polygon().bounds
        if ox1 <= xmin or ox0 >= xmax or oy1 <= ymin or oy0 >= ymax:
            warnings.warn(
                f"obstacles[{i}]: centre {list(o.center)} lies wholly outside the bounds "
                f"{list(m.bounds)}, where everything counts as blocked; it changes nothing "
                "(a typo in its coordinates?)",
                InputWarning,
                stacklevel=3,
            )
