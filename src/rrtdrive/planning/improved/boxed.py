"""Whether a tree root can ever grow: a proof from the map's exact geometry, before any iteration.

A root with a virtual parent (the start and the goal of the improved planner, with the
obtuse-parent component on) is only ever extended by a straight edge within 90 degrees
of its pose's heading: Eq. 11 picks it only when the angle (virtual parent, root, q) is
obtuse, and the virtual parent lies behind the start and ahead of the goal, whose edges
are driven into it. Every such edge, driven in direction ``u``, is tested by
:meth:`~rrtdrive.collision.CollisionChecker.edge_free` at the root: a capsule of
radius ``r`` about the segment from ``root - back u`` to the far end ``+ front u``
(:attr:`~rrtdrive.collision.CollisionChecker.edge_capsule`). That capsule contains the
capsule of the edge of length zero in the same direction, about the segment
``[root - back u, root + front u]``; and the test passes only where its capsule is
truly clear (it walks the field, a lower bound of the distance). So when, for every
direction of the fan, that short capsule holds an obstacle point, no edge at the root
can ever pass, and the tree stays its root whatever it samples.

:func:`root_boxed_in` proves it on a fan of directions ``tol / front`` apart: a
direction's segment whose exact distance (shapely) to the obstacles or to the outside
of the bounds is below ``r - tol`` puts an obstacle point within ``r`` of the segment
of every direction within half a fan step (the segment's points move at most ``front``
times the angle). The clearance field answers first where it can: a direction whose
segment it finds ``r - tol`` clear is not blocked, and then nothing is proven. A
``False`` proves nothing: the growth then runs, and
:attr:`~.config.ImprovedConfig.root_patience` bounds it.
"""

from __future__ import annotations

import math
import threading
import weakref
from collections import OrderedDict

import numpy as np
import shapely

from rrtdrive.collision import CollisionChecker
from rrtdrive.types import Pose

#: A fan's segment ends, clearance-field minima, half point gap and distances to the edge.
_Fan = tuple[np.ndarray, np.ndarray, float, np.ndarray]

__all__ = ["ROOT_FAN_TOL", "boxed_end", "open_share", "root_boxed_in", "stuck_root_words"]

#: The proof's tolerance, metres: a direction counts as blocked when an obstacle lies
#: this much inside its capsule, which covers the directions half a fan step either side.
ROOT_FAN_TOL = 0.05
#: Spacing of the field's look-ups along each direction's segment, metres.
_POINT_SPACING = 0.1


def root_boxed_in(checker: CollisionChecker, root: Pose, tol: float = ROOT_FAN_TOL) -> bool:
    """True when no tree edge can ever leave (or, for the goal, enter) ``root``.

    Parameters
    ----------
    checker : CollisionChecker
        The map's checker, whose :meth:`~CollisionChecker.edge_free` tests edges at
        the roots.
    root : Pose
        The start (edges leave it) or the goal (edges are driven into it); in both,
        an edge's driving direction lies within 90 degrees of ``root.yaw``.
    tol : float
        How far inside every direction's capsule an obstacle must lie, metres.

    Returns
    -------
    bool
        ``True`` is a proof (up to float rounding); ``False`` proves nothing.

    Examples
    --------
    >>> from rrtdrive.maps import Map, Obstacle
    >>> walls = (Obstacle((10.0, 2.0), (0.4, 4.0), 0.0),)  # 0.3 m ahead of the bumper
    >>> m = Map("nose", (0.0, 0.0, 20.0, 4.0), walls, Pose(6.2, 2.0, 0.0), Pose(2.0, 2.0, 0.0))
    >>> c = CollisionChecker.for_map(m)
    >>> root_boxed_in(c, m.start), root_boxed_in(c, Pose(6.2, 2.0, math.pi))
    (True, False)
    """
    back, front, radius = checker.edge_capsule
    # A zero-length edge is tested as a disc about the root (edge_free); where that disc
    # is clear the proof below would not cover it.
    reach = math.hypot(checker.vehicle.front_extent, checker.vehicle.width / 2.0)
    if checker.clearance(root.x, root.y) - reach - checker.config.margin >= 0.0:
        return False
    ends, field_min, half_gap, edge = _fan_room(checker, root, back, front, tol)
    count = len(ends)
    need = radius - tol
    # The field first: a direction it finds ``need`` clear is not blocked, and then
    # nothing is proven.
    if (field_min >= need + half_gap).any():
        return False
    # Outside the bounds, or nearer their edge than need at an end.
    blocked = edge < need
    union = checker.obstacle_union
    if union.is_empty:
        return bool(blocked.all())
    # Straight along the heading first: where the root is not boxed in, most often that
    # direction is clear, and one distance settles it.
    mid = count // 2
    if not blocked[mid] and shapely.distance(shapely.linestrings(ends[mid]), union) >= need:
        return False
    if not blocked.all():
        open_ = ~blocked
        lines = shapely.linestrings(ends[open_])
        blocked[open_] = shapely.distance(lines, union) < need
    return bool(blocked.all())


#: Each live checker's last two fans: a query asks root_boxed_in, then open_share, of
#: its start and goal (a checker never changes once built; the arrays are read-only).
#: Weakly keyed: an lru_cache keyed on the checker kept a user's dropped checker, and
#: its tens of MB, alive (an audit).
_FANS: weakref.WeakKeyDictionary[CollisionChecker, OrderedDict[tuple, _Fan]] = (
    weakref.WeakKeyDictionary()
)
_FANS_PER_CHECKER = 2
_FANS_LOCK = threading.Lock()


def _fan_room(
    checker: CollisionChecker, root: Pose, back: float, front: float, tol: float
) -> _Fan:
    """:func:`_build_fan_room`, remembered per checker (its last two fans)."""
    key = (root, back, front, tol)
    with _FANS_LOCK:  # a query holds its checker's lock, a direct caller may not
        fans = _FANS.setdefault(checker, OrderedDict())
        fan = fans.get(key)
        if fan is not None:
            fans.move_to_end(key)
            return fan
    fan = _build_fan_room(checker, root, back, front, tol)
    with _FANS_LOCK:
        fans[key] = fan
        while len(fans) > _FANS_PER_CHECKER:
            fans.popitem(last=False)
    return fan


_fan_room.cache_clear = _FANS.clear  # type: ignore[attr-defined]  # as lru_cache's


def _build_fan_room(
    checker: CollisionChecker, root: Pose, back: float, front: float, tol: float
) -> _Fan:
    """The fan's segments and two bounds of their room, for both functions here.

    Returns
    -------
    ends : numpy.ndarray
        ``(count, 2, 2)``: each direction's segment ends, the fan cut ``tol / front``
        fine: the centres of ``count`` equal parts of -90 to 90 degrees about the heading.
    field_min, half_gap : numpy.ndarray, float
        ``(count,)``: the clearance field's least value along each segment, at points
        :data:`_POINT_SPACING` apart (at most); less ``half_gap``, half their spacing
        (the points between), a lower bound of the segment's distance to the obstacles
        and the outside.
    edge : numpy.ndarray
        ``(count,)``: each segment's distance to the bounds' edge, negative outside
        (inside a box that distance along a segment is least at an end).
    """
    count = math.ceil(math.pi * max(front, back) / tol)
    angles = root.yaw + (np.arange(count) + 0.5) * (math.pi / count) - math.pi / 2.0
    c, s = np.cos(angles), np.sin(angles)
    ends = np.stack(
        [np.column_stack([root.x - back * c, root.y - back * s]),
         np.column_stack([root.x + front * c, root.y + front * s])], axis=1,
    )  # fmt: skip
    n = max(2, math.ceil((front + back) / _POINT_SPACING) + 1)
    along = np.linspace(0.0, 1.0, n)
    xs = ends[:, :1, 0] + (ends[:, 1:, 0] - ends[:, :1, 0]) * along
    ys = ends[:, :1, 1] + (ends[:, 1:, 1] - ends[:, :1, 1]) * along
    half_gap = 0.5 * (front + back) / (n - 1)
    field_min = checker.clearances_xy(xs, ys).min(axis=1)
    xmin, ymin, xmax, ymax = checker.bounds
    edge = np.minimum.reduce(
        [ends[..., 0] - xmin, xmax - ends[..., 0], ends[..., 1] - ymin, ymax - ends[..., 1]]
    ).min(axis=1)
    for a in (ends, field_min, edge):
        a.setflags(write=False)
    return ends, field_min, half_gap, edge


def open_share(checker: CollisionChecker, root: Pose, tol: float = ROOT_FAN_TOL) -> float:
    """The share of the root's fan with room for a growth edge: a measure, not a proof.

    A direction is open when the capsule of a zero-length edge in it (see the module)
    is clear of obstacles and the bounds' edge by its radius (shapely's exact
    distance; the clearance field decides first where it is sure). A root whose share
    is small can still grow, through the few directions open, but seldom: the
    improved planner gives it less patience (``ImprovedConfig.narrow_fan``).

    Examples
    --------
    >>> from rrtdrive.maps import builtin_map
    >>> m = builtin_map("kerbside")
    >>> c = CollisionChecker.for_map(m)
    >>> open_share(c, m.goal), round(open_share(c, m.start), 2)  # boxed in; a street
    (0.0, 0.51)
    """
    back, front, radius = checker.edge_capsule
    ends, field_min, half_gap, edge = _fan_room(checker, root, back, front, tol)
    sure = field_min >= radius + half_gap
    is_open = sure.copy()
    rest = ~sure & (edge >= radius)
    union = checker.obstacle_union
    if rest.any():
        far = np.full(int(rest.sum()), np.inf)
        if not union.is_empty:
            far = shapely.distance(shapely.linestrings(ends[rest]), union)
        is_open[rest] = far >= radius
    return float(is_open.mean())


def boxed_end(checker: CollisionChecker, start: Pose, goal: Pose) -> str:
    """``"start"`` or ``"goal"``, the first that is :func:`root_boxed_in`, else ``""``."""
    for end, pose in (("start", start), ("goal", goal)):
        if root_boxed_in(checker, pose):
            return end
    return ""


def stuck_root_words(end: str, proven: bool, patience: int, share: float | None) -> str:
    """Why the ``end`` tree (``"start"`` or ``"goal"``) never grew, in a message's words.

    Parameters
    ----------
    end : str
        The stuck root.
    proven : bool
        Whether :func:`root_boxed_in` proved it before any iteration.
    patience : int
        The iterations it was given otherwise.
    share : float or None
        Its fan's :func:`open_share` when that was narrow, else ``None``.

    Examples
    --------
    >>> stuck_root_words("goal", False, 400, 0.1)[:48]
    'the goal tree never left the goal pose in 400 it'
    """
    if proven:
        return (
            f"the {end} tree cannot leave the {end} pose: every edge it may grow, within "
            f"90 deg of the {end}'s heading, is blocked there (the {end} is boxed in "
            "along its heading, or its body nearer to an obstacle or the map's edge than "
            "the edges keep)"
        )  # the proof is about the edges' keep: a wall 0.05 m beside a goal blocks them all
    narrow = ""
    if share is not None:
        narrow = f"; {100 * share:.0f} % of those directions have room for an edge there"
    return (
        f"the {end} tree never left the {end} pose in {patience} "
        f"iterations (it grows only by edges within 90 deg of the {end}'s heading, and "
        f"none tried was free{narrow}: the {end} is boxed in along its heading, or its "
        "body nearer to an obstacle or the map's edge than the edges keep)"
    )
