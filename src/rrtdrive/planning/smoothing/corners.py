"""The key polygon: one :class:`Corner` record per key point, built from the tree path.

The polygon runs start -> start-leg point -> tree corners -> goal-leg point ->
goal. The two leg points lie on the start and goal heading rays, so the curve
leaves and arrives along the given headings. Each corner carries its own repair
state (fillet radius, treatment count) so that inserting or deleting a corner
moves everything about it at once.
"""

from __future__ import annotations

import enum
import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from rrtdrive.planning.smoothing.checks import EdgeCache
from rrtdrive.planning.smoothing.clothoid import turn_tangent
from rrtdrive.planning.smoothing.config import SmoothingConfig
from rrtdrive.planning.smoothing.fillet import fillet_points, outer_reach
from rrtdrive.planning.smoothing.operations import prune, repair_sharp_angles
from rrtdrive.types import Pose

__all__ = [
    "CornerKind",
    "Corner",
    "Ends",
    "KeyPolygon",
    "build_key_polygon",
    "unit",
    "unit_between",
    "polygon_legs",
    "turn_angles",
    "deflection",
    "signed_deflection",
    "kind_of",
    "turn_reach",
]


class CornerKind(enum.Enum):
    """The role of a key point in the polygon."""

    START = "start"
    START_LEG = "start_leg"
    NODE = "node"
    GOAL_LEG = "goal_leg"
    GOAL = "goal"


# A mutable record: the repairs move corners and change their treatment in place.
@dataclass(eq=False)
class Corner:
    """One key point of the polygon and its repair state.

    Attributes
    ----------
    point : numpy.ndarray
        Where the corner is now ``(2,)``.
    origin : numpy.ndarray
        Where moves start from ``(2,)`` (its place when it entered the polygon,
        or after a move that is kept).
    kind : CornerKind
        Start, heading-leg point, tree node or goal.
    raw_index : int
        Index into the augmented path (:attr:`KeyPolygon.aug`) it came from.
    radius : float
        Fillet radius in m; 0 for a plain corner (a clothoid curve gives a plain
        corner the design radius).
    attempt : int
        Treatments used so far (:meth:`~rrtdrive.planning.smoothing.repair.Repairer.advance`).
    tight : bool
        Clothoid curves only: the turn uses the tightest clothoids (least cut
        across the corner) instead of the gentlest that fit its legs.
    """

    point: np.ndarray
    origin: np.ndarray
    kind: CornerKind
    raw_index: int
    radius: float = 0.0
    attempt: int = 0
    tight: bool = False

    @classmethod
    def at(cls, point: np.ndarray, kind: CornerKind, raw_index: int) -> Corner:
        """A fresh, plain corner at a copy of ``point``."""
        p = point.copy()
        return cls(p, p.copy(), kind, raw_index)


@dataclass(frozen=True, eq=False)
class Ends:
    """Start and goal positions and heading directions of one smoothing call."""

    start: Pose
    goal: Pose
    s: np.ndarray
    g: np.ndarray
    hs: np.ndarray
    hg: np.ndarray

    @classmethod
    def of(cls, start: Pose, goal: Pose) -> Ends:
        """The ends of a path from ``start`` to ``goal``."""
        return cls(
            start,
            goal,
            np.array([start.x, start.y]),
            np.array([goal.x, goal.y]),
            np.array([math.cos(start.yaw), math.sin(start.yaw)]),
            np.array([math.cos(goal.yaw), math.sin(goal.yaw)]),
        )


@dataclass(eq=False)
class KeyPolygon:
    """The corners and the bookkeeping of the repairs on them.

    Attributes
    ----------
    corners : list of Corner
        In driving order, start first and goal last.
    aug : numpy.ndarray
        The augmented path: start, start-leg point, interior tree nodes,
        goal-leg point, goal.
    d_s, d_g : float
        Lengths of the start and goal heading legs it was built with (m).
    unpruned : set of (int, int)
        Stretches of ``aug`` (first, last index) already un-pruned once.
    grown : dict
        How often each heading corner's leg was grown to fit its fillet.
    """

    corners: list[Corner]
    aug: np.ndarray
    d_s: float
    d_g: float
    unpruned: set[tuple[int, int]] = field(default_factory=set)
    grown: dict[int, int] = field(default_factory=dict)

    def __len__(self) -> int:
        return len(self.corners)

    def points(self) -> list[np.ndarray]:
        """The corner positions, in order."""
        return [c.point for c in self.corners]

    def heading_turns(self) -> tuple[float, float]:
        """Deflections at the start- and goal-leg corners (radians)."""
        p = self.points()
        return deflection(p[0], p[1], p[2]), deflection(p[-3], p[-2], p[-1])

    def heading_reach(self, radius: float, cfg: SmoothingConfig) -> tuple[float, float]:
        """Reach that turns of ``radius`` at the start- and goal-leg corners need."""
        p = self.points()
        out = []
        for c in (1, len(p) - 2):
            ux, uy, _ = unit_between(p[c - 1], p[c])
            vx, vy, _ = unit_between(p[c], p[c + 1])
            out.append(turn_reach(cfg, p[c], (ux, uy), (vx, vy), radius))
        return out[0], out[1]


def turn_reach(
    cfg: SmoothingConfig,
    point: np.ndarray,
    u_in: tuple[float, float],
    u_out: tuple[float, float],
    radius: float,
    memo: dict[tuple[float, float], float] | None = None,
) -> float:
    """Least distance along each leg from a corner that its turn of ``radius`` needs.

    For a B-spline the fillet's outermost guard point; for clothoids the tangent
    length of the tightest turn (``inf`` for a reversal). 0 for ``radius = 0``
    with a B-spline (a plain control point). ``memo`` keeps the clothoid tangents
    per deflection and radius; it belongs to one ``cfg``.
    """
    if cfg.clothoid:
        theta = math.atan2(
            u_in[0] * u_out[1] - u_in[1] * u_out[0], u_in[0] * u_out[0] + u_in[1] * u_out[1]
        )
        r = radius if radius > 0.0 else cfg.design_radius
        if memo is None:
            return turn_tangent(theta, 1.0 / r, cfg.tightest_sigma)
        key = (theta, r)
        tangent = memo.get(key)
        if tangent is None:
            tangent = memo[key] = turn_tangent(theta, 1.0 / r, cfg.tightest_sigma)
        return tangent
    if radius <= 0.0:
        return 0.0
    f = fillet_points(point, u_in, u_out, radius, cfg.fillet_max_angle)
    return outer_reach(f, cfg.degree) if math.isfinite(f.reach) else math.inf


def unit(dx: float, dy: float) -> tuple[float, float, float]:
    """Unit vector and length of ``(dx, dy)``; all zero for a (near) zero vector."""
    n = math.hypot(dx, dy)
    if n < 1e-12:
        return 0.0, 0.0, 0.0
    return dx / n, dy / n, n


def polygon_legs(
    pts: Sequence[Sequence[float]],
) -> tuple[list[tuple[float, float]], list[float]]:
    """Each leg's unit direction and length (:func:`unit`) of polygon ``pts``.

    Examples
    --------
    >>> polygon_legs([(0, 0), (3, 4), (3, 4)])
    ([(0.6, 0.8), (0.0, 0.0)], [5.0, 0.0])
    """
    dirs: list[tuple[float, float]] = []
    lengths: list[float] = []
    for i in range(len(pts) - 1):
        ux, uy, length = unit(pts[i + 1][0] - pts[i][0], pts[i + 1][1] - pts[i][1])
        dirs.append((ux, uy))
        lengths.append(length)
    return dirs, lengths


def turn_angles(
    dirs: Sequence[tuple[float, float]], lengths: Sequence[float], at: Sequence[int]
) -> list[float]:
    """The signed deflection (:func:`signed_deflection`) at each corner index in ``at``.

    0 at the polygon's ends and where a leg has no length (no direction to turn from).
    """
    n = len(lengths) + 1
    return [
        signed_deflection(dirs[c - 1], dirs[c])
        if 0 < c < n - 1 and lengths[c - 1] > 0.0 and lengths[c] > 0.0
        else 0.0
        for c in at
    ]


def unit_between(a: np.ndarray, b: np.ndarray) -> tuple[float, float, float]:
    """``unit(*(b - a))`` for points ``(2,)``, in Python floats: the same values, faster.

    The repairs call it thousands of times a query; numpy scalars make each of its
    few operations slow, and IEEE arithmetic rounds alike on either type.
    """
    (ax, ay), (bx, by) = a.tolist(), b.tolist()
    return unit(bx - ax, by - ay)


def signed_deflection(u: tuple[float, float], v: tuple[float, float]) -> float:
    """Signed turn in radians from direction ``u`` to ``v`` (positive: left)."""
    return math.atan2(u[0] * v[1] - u[1] * v[0], u[0] * v[0] + u[1] * v[1])


def deflection(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> float:
    """Turn in radians at ``b`` of the polyline ``a -> b -> c``."""
    ux, uy, _ = unit_between(a, b)
    vx, vy, _ = unit_between(b, c)
    return math.atan2(abs(ux * vy - uy * vx), ux * vx + uy * vy)


def build_key_polygon(
    raw: np.ndarray,
    ends: Ends,
    d_s: float,
    d_g: float,
    edges: EdgeCache,
    cfg: SmoothingConfig,
    max_turn: float | None,
) -> KeyPolygon | str:
    """The key polygon with heading legs ``d_s``, ``d_g``, or the reason it cannot be built.

    The tree path gets a point on each heading ray, is pruned (keeping those
    points; with ``max_turn`` avoiding turns above it) and sharp-angle repaired.
    """
    edge = edges.edge_free
    s1 = ends.s + d_s * ends.hs
    g1 = ends.g - d_g * ends.hg
    aug = np.vstack([ends.s, s1, raw[1:-1], g1, ends.g])
    n = len(aug)
    if not edge(ends.s.tolist(), s1.tolist()):
        return f"the start heading leg of {d_s:.2f} m is blocked"
    if not edge(g1.tolist(), ends.g.tolist()):
        return f"the goal heading leg of {d_g:.2f} m is blocked"
    if cfg.prune:
        key = prune(
            aug,
            edges,
            keep=(1, n - 2),
            max_turn=max_turn,
            start_heading=ends.hs,
            end_heading=ends.hg,
        )
        if key is None:
            return "a heading-leg point has no free edge to the tree path"
    else:
        key = np.arange(n)
        if not all(edge(aug[i].tolist(), aug[i + 1].tolist()) for i in range(n - 1)):
            return "a heading-leg point has no free edge to the tree path"
    if cfg.sharp_repair:
        key = repair_sharp_angles(aug, key, edges)
    idx = key.tolist()
    kinds = (
        [CornerKind.START, CornerKind.START_LEG]
        + [CornerKind.NODE] * (len(idx) - 4)
        + [CornerKind.GOAL_LEG, CornerKind.GOAL]
    )
    corners = [Corner.at(aug[k], kind, k) for k, kind in zip(idx, kinds, strict=True)]
    return KeyPolygon(corners, aug, d_s, d_g)


def kind_of(raw_index: int, n_aug: int) -> CornerKind:
    """The kind of an interior corner taken from ``aug[raw_index]``."""
    if raw_index == 1:
        return CornerKind.START_LEG
    if raw_index == n_aug - 2:
        return CornerKind.GOAL_LEG
    return CornerKind.NODE
