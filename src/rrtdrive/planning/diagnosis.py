"""Why a query failed, in the user's terms: the constraint that makes it hard or impossible.

:func:`diagnose` looks at a failed :class:`~rrtdrive.planning.base.PlanningProblem`
and measures, from the map's geometry, the first of these that holds:

1. ``body_collides``: the start or goal body overlaps an obstacle or leaves the bounds.
2. ``needs_reverse`` / ``boxed_in``: the room the end poses leave. A forward arrival
   needs room *behind* the goal pose (the car came from there), a forward departure
   room *ahead* of the start. The free run is measured along steady-steering arcs
   (curvatures from -kappa_max to kappa_max) with the exact body test; less than a
   car length on every arc is too little for the smallest manoeuvre. With room the
   other way the pose is reachable in reverse only; with none either way it is boxed in.
3. ``tight_clearance`` (for planners that search by tree edges only): the first tree
   edge along the start's (or into the goal's) heading fails the swept edge test
   although the exact body is free along it: the
   body is closer to an obstacle than that test keeps beside it (the checker's margin,
   its grid error and trace step) or beyond its bumper (the capsule's round end too).
4. ``narrow_passage`` / ``walled_off``: start and goal are joined only through a gap
   narrower than the swept edge test needs, or by none at all; the gap is located on
   the distance field and measured with shapely. ``walled_off`` is looked for before
   2 and 3: nothing at the ends matters when no way joins them.
5. ``u_turn``: start and goal headings differ by more than 120 degrees while the
   street at the start is narrower than a forward U-turn of this car needs
   (:func:`u_turn_width`), and either no place reachable from the start is that wide
   or the car must first drive to one.

Each finding is a frozen :class:`Diagnosis` with its numbers; ``None`` when none applies.
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
import shapely
from scipy import ndimage

from rrtdrive.collision import CollisionChecker
from rrtdrive.maps import Map
from rrtdrive.types import Pose, VehicleParams
from rrtdrive.vehicle import footprint_polygon

if TYPE_CHECKING:
    from rrtdrive.planning.base import PlanningProblem

__all__ = [
    "DiagnosisKind",
    "Diagnosis",
    "diagnose",
    "edge_keep",
    "end_keep",
    "u_turn_width",
    "free_run",
    "street_width",
    "nearest_obstacle",
]

#: Spacing of the poses tested along a free run, metres.
RUN_STEP = 0.05
#: Steady-steering arcs tried for a free run, as fractions of kappa_max.
ARC_FRACTIONS = (-1.0, -0.5, 0.0, 0.5, 1.0)
#: Heading change beyond which start and goal need the car turned round.
U_TURN_ANGLE = math.radians(120.0)


class DiagnosisKind(enum.Enum):
    """What makes a query hard or impossible."""

    BODY_COLLIDES = "body_collides"
    NEEDS_REVERSE = "needs_reverse"
    BOXED_IN = "boxed_in"
    TIGHT_CLEARANCE = "tight_clearance"
    NARROW_PASSAGE = "narrow_passage"
    WALLED_OFF = "walled_off"
    U_TURN = "u_turn"


@dataclass(frozen=True)
class Diagnosis:
    """One finding: its kind, a sentence for the user, and the numbers behind it.

    Attributes
    ----------
    kind : DiagnosisKind
        The constraint.
    message : str
        What it means for the user, with the measured numbers.
    numbers : dict
        The measurements (metres, or an obstacle index; -1 is the map's edge).
    """

    kind: DiagnosisKind
    message: str
    numbers: dict[str, float] = field(default_factory=dict)

    def to_json(self) -> dict[str, object]:
        """``{"kind", "message", "numbers"}`` for the plan JSON."""
        return {
            "kind": self.kind.value,
            "message": self.message,
            "numbers": {k: round(float(v), 4) for k, v in self.numbers.items()},
        }


# ----------------------------------------------------------------------------- measures


def u_turn_width(vehicle: VehicleParams) -> float:
    """Width of the strip a forward U-turn on the tightest circle sweeps.

    The outer front corner runs on radius ``hypot(R + W/2, front_extent)`` and
    reaches that far beyond the turning centre; the outer rear corner swings
    ``hypot(R + W/2, rear_overhang)`` to the other side of it. Their sum is
    ``2 R`` plus the body's swept width, overhangs included.

    Examples
    --------
    >>> round(u_turn_width(VehicleParams()), 2)
    14.65
    """
    r = vehicle.min_turning_radius + vehicle.width / 2.0
    return math.hypot(r, vehicle.front_extent) + math.hypot(r, vehicle.rear_overhang)


def arc_poses(pose: Pose, direction: int, kappa: float, length: float, step: float) -> np.ndarray:
    """Poses ``(N, 3)`` every ``step`` along a steady-steering arc, the start excluded.

    ``direction`` +1 drives forward, -1 backs; ``kappa`` is the steering's curvature.
    """
    s = np.arange(1, int(math.floor(length / step + 1e-9)) + 1) * step
    return _along(pose, direction * s, kappa)


def _along(pose: Pose, s: np.ndarray, kappa: float) -> np.ndarray:
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
        if checker.pose_free(_along(pose, np.array([direction * mid]), kappa)[0]):
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
class _Shapes:
    """The map's shapes the findings measure against, built once per checker."""

    polygons: np.ndarray  # one shapely polygon per obstacle, in map order
    edge: shapely.Geometry  # the bounds' outline
    walls: shapely.Geometry  # obstacle outlines and the bounds' outline
    solid: shapely.Geometry  # obstacle areas and the bounds' outline


def _shapes(checker: CollisionChecker) -> _Shapes:
    def build() -> _Shapes:
        polys = np.array([o.polygon() for o in checker.obstacles], dtype=object)
        edge = shapely.box(*checker.bounds).exterior
        return _Shapes(
            polys,
            edge,
            shapely.union_all([edge, *shapely.get_exterior_ring(polys)]),
            shapely.union_all([edge, *polys]),
        )

    return checker.grid.derived("diagnosis_shapes", build)


def _first_hit(checker: CollisionChecker, body: shapely.Geometry) -> int:
    """Index of the first obstacle ``body`` overlaps, -1 for none (the bounds)."""
    hits = np.flatnonzero(shapely.intersects(_shapes(checker).polygons, body))
    return int(hits[0]) if len(hits) else -1


def nearest_obstacle(
    m: Map, body: shapely.Geometry, checker: CollisionChecker | None = None
) -> tuple[int, float]:
    """The obstacle nearest to ``body`` and its distance; index -1 is the map's edge.

    With ``checker`` (the map's), its cached obstacle polygons are used.
    """
    edge = shapely.box(*m.bounds).exterior.distance(body)
    if not m.obstacles:
        return -1, float(edge)
    if checker is not None:
        polys = _shapes(checker).polygons
    else:
        polys = np.array([o.polygon() for o in m.obstacles], dtype=object)
    d = shapely.distance(polys, body)
    i = int(np.argmin(d))
    return (i, float(d[i])) if d[i] <= edge else (-1, float(edge))


def street_width(
    m: Map,
    point: tuple[float, float],
    yaw: float,
    reach: float = 1e3,
    checker: CollisionChecker | None = None,
) -> float:
    """Free width across heading ``yaw`` at ``point``: to the first obstacle or edge each side.

    Measured exactly with shapely along the normal to the heading (with ``checker``,
    the map's, its cached outlines are used).
    """
    if checker is not None:
        walls = _shapes(checker).walls
    else:
        walls = shapely.union_all(
            [shapely.box(*m.bounds).exterior, *(o.polygon().exterior for o in m.obstacles)]
        )
    p = shapely.Point(point)
    total = 0.0
    for side in (1.0, -1.0):
        nx, ny = -math.sin(yaw) * side, math.cos(yaw) * side
        ray = shapely.LineString([point, (point[0] + nx * reach, point[1] + ny * reach)])
        hit = ray.intersection(walls)
        total += p.distance(hit) if not hit.is_empty else reach
    return float(total)


def _body_centre(pose: Pose, vehicle: VehicleParams) -> tuple[float, float]:
    off = vehicle.front_extent - vehicle.length / 2.0
    return (pose.x + off * math.cos(pose.yaw), pose.y + off * math.sin(pose.yaw))


def _obstacle_name(index: int) -> str:
    return "the map's edge" if index < 0 else f"obstacle {index}"


def _cell(checker: CollisionChecker, p: tuple[float, float]) -> tuple[int, int] | None:
    g = (np.asarray(p, dtype=float) - checker.grid_origin) / checker.resolution
    i, j = int(math.floor(g[0])), int(math.floor(g[1]))
    nx, ny = checker.clearance_grid.shape
    return (i, j) if 0 <= i < nx and 0 <= j < ny else None


def _centres(checker: CollisionChecker, i: Any, j: Any) -> tuple[Any, Any]:
    """World centres of the grid cells ``(i, j)`` (indices or arrays of them)."""
    o, h = checker.grid_origin, checker.resolution
    return o[0] + (i + 0.5) * h, o[1] + (j + 0.5) * h


# ----------------------------------------------------------------------------- findings


def _collides(m: Map, checker: CollisionChecker, pose: Pose, label: str) -> Diagnosis | None:
    if checker.pose_free(pose.as_tuple()):
        return None
    index = _first_hit(checker, footprint_polygon(pose.as_tuple(), m.vehicle))
    what = _obstacle_name(index) if index >= 0 else "the bounds (it leaves the map)"
    return Diagnosis(
        DiagnosisKind.BODY_COLLIDES,
        f"the {label}'s body at ({pose.x:.1f}, {pose.y:.1f}) overlaps {what}",
        {"obstacle": index},
    )


def _room(
    m: Map, checker: CollisionChecker, start: Pose, goal: Pose, reverse: bool
) -> Diagnosis | None:
    v = m.vehicle
    need = v.length
    least = f"less than the car length ({need:.2f} m) the smallest manoeuvre needs"
    # (label, pose, direction of travel of a forward-gear motion there, its phrase)
    ends = (
        ("start", start, 1, "it can only be left in reverse"),
        ("goal", goal, -1, "it can only be reached in reverse"),
    )
    for label, pose, forward, only in ends:
        run_fwd = best_run(checker, pose, forward, v, need)
        if run_fwd >= need:
            continue
        run_rev = best_run(checker, pose, -forward, v, need)
        ahead, behind = (run_fwd, run_rev) if forward > 0 else (run_rev, run_fwd)
        numbers = {"room_ahead_m": ahead, "room_behind_m": behind, "needed_m": need}
        tip = "" if reverse else " (try --reverse)"
        if run_rev < need:
            return Diagnosis(
                DiagnosisKind.BOXED_IN,
                f"the {label} is boxed in: on any steady steering the car has at most "
                f"{behind:.2f} m behind it and {ahead:.2f} m ahead of it, {least}; "
                f"{'leaving' if label == 'start' else 'reaching'} it takes several gear "
                f"changes{tip}",
                numbers,
            )
        if reverse:
            continue  # reversing is allowed and has room: not the constraint
        straight = free_run(checker, pose, forward, 0.0, need)
        probe = arc_poses(pose, forward, 0.0, straight + 2 * RUN_STEP, RUN_STEP)[-1]
        blocker = _first_hit(checker, footprint_polygon(tuple(probe), v))
        numbers.update(straight_gap_m=straight, obstacle=blocker)
        if forward > 0:
            where = f"{straight:.2f} m ahead of its nose"
            room = f"the car drives at most {run_fwd:.2f} m forward from it"
        else:
            where = f"{straight:.2f} m behind its rear"
            room = (
                f"a forward arrival comes from behind the pose, where the car has at most "
                f"{run_fwd:.2f} m"
            )
        return Diagnosis(
            DiagnosisKind.NEEDS_REVERSE,
            f"the {label} has {_obstacle_name(blocker)} {where}: on any steady steering "
            f"{room}, {least}; {only}{tip}",
            numbers,
        )
    return None


def edge_keep(checker: CollisionChecker) -> float:
    """The room beside the body the swept edge test needs: margin, grid error, trace step."""
    return checker.config.margin + checker.grid_error + checker.config.min_trace_step


def end_keep(checker: CollisionChecker) -> float:
    """The room beyond a bumper the swept edge test needs: its round end, grid error, step."""
    r = checker.edge_radius
    inset = math.sqrt(max(r * r - (checker.vehicle.width / 2.0) ** 2, 0.0))
    return r - inset + checker.grid_error + checker.config.min_trace_step


def _tight(m: Map, checker: CollisionChecker, start: Pose, goal: Pose) -> Diagnosis | None:
    side, ends = edge_keep(checker), end_keep(checker)
    leg = 0.5
    ways = (("start", start, 1, "its rear", "leaves"), ("goal", goal, -1, "its nose", "reaches"))
    for label, pose, forward, bumper, verb in ways:
        # The tree's first edge at the pose: a short one along its heading, driven forward.
        u = np.array([math.cos(pose.yaw), math.sin(pose.yaw)])
        far = pose.xy + forward * leg * u
        a, b = (pose.xy, far) if forward > 0 else (far, pose.xy)
        if checker.edge_free(a, b) or free_run(checker, pose, forward, 0.0, leg) < leg:
            continue
        index, gap = nearest_obstacle(m, footprint_polygon(pose.as_tuple(), m.vehicle), checker)
        return Diagnosis(
            DiagnosisKind.TIGHT_CLEARANCE,
            f"the {label}'s body is {gap:.2f} m from {_obstacle_name(index)}; tree edges keep "
            f"{side:.2f} m beside the body and {ends:.2f} m beyond {bumper} (the swept "
            f"test's round ends, the checker's {checker.config.margin:.2f} m margin, "
            f"{checker.grid_error:.2f} m grid error and {checker.config.min_trace_step:.2f} m "
            f"trace step), so no tree edge {verb} it (try --planner hybrid-a-star, or the "
            f"default planner, whose Hybrid A* stage tests the body exactly)",
            {"gap_m": gap, "keep_m": side, "keep_end_m": ends, "obstacle": index},
        )
    return None


def _connected(field_: np.ndarray, t: float, a: tuple[int, int], b: tuple[int, int]) -> bool:
    labels, _ = ndimage.label(field_ >= t, structure=np.ones((3, 3), dtype=bool))
    return bool(labels[a] != 0 and labels[a] == labels[b])


def _passage(m: Map, checker: CollisionChecker, start: Pose, goal: Pose) -> Diagnosis | None:
    grid = checker.clearance_grid
    a, b = _cell(checker, (start.x, start.y)), _cell(checker, (goal.x, goal.y))
    need = checker.edge_radius + checker.config.min_trace_step
    if a is None or b is None:
        return None
    ends = float(min(grid[a], grid[b]))
    if ends >= need:
        # Where the swept edge test can go at all: one labelling per map, on the checker.
        edge_labels = checker.grid.derived(
            ("diagnosis_edge_labels", need),
            lambda: ndimage.label(grid >= need, structure=np.ones((3, 3), dtype=bool))[0],
        )
        if edge_labels[a] != 0 and edge_labels[a] == edge_labels[b]:
            return None
    elif not checker.provably_disconnected((start.x, start.y), (goal.x, goal.y)):
        # An end within 0.12 m of a wall: the measure below would find the end's own
        # clearance; go on only where no motion joins them (a walled-off goal beside a
        # wall was told "try --reverse" before, or nothing at all).
        return None
    lo, hi = 0.0, min(need, ends)  # connected at lo (or nothing is), disconnected at hi
    if not _connected(grid, 1e-9, a, b):
        lo = -1.0
    else:
        for _ in range(10):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if _connected(grid, mid, a, b) else (lo, mid)
    v = m.vehicle
    needed_width = v.width + 2.0 * edge_keep(checker)
    numbers = {"needed_m": needed_width, "car_width_m": v.width}
    if lo < 0.0:
        return Diagnosis(
            DiagnosisKind.WALLED_OFF,
            "the goal is walled off from the start: no gap connects them",
            {**numbers, "width_m": 0.0},
        )
    # The narrowest place: the cells kept at ``lo`` but not at ``hi`` that join the
    # start's side to the goal's; the best-cleared of them is the pass.
    structure = np.ones((3, 3), dtype=bool)
    low, _ = ndimage.label(grid >= lo, structure=structure)
    high, _ = ndimage.label(grid >= hi, structure=structure)
    band = (low == low[a]) & (high == 0)
    parts, count = ndimage.label(band, structure=structure)
    near_a = ndimage.binary_dilation(high == high[a], structure=structure)
    near_b = ndimage.binary_dilation(high == high[b], structure=structure)
    joins = np.intersect1d(np.unique(parts[near_a & band]), np.unique(parts[near_b & band]))
    pick = band if len(joins) == 0 else np.isin(parts, joins[joins > 0])
    best = np.unravel_index(int(np.argmax(np.where(pick, grid, -np.inf))), grid.shape)
    best = (int(best[0]), int(best[1]))
    x, y = (float(v) for v in _centres(checker, *best))
    width = _gap_width(checker, x, y)
    numbers.update(width_m=width, x=x, y=y)
    if width < v.width:
        tail = f"narrower than the car ({v.width:.2f} m)"
    else:
        tail = (
            f"tree edges need at least {needed_width:.2f} m (the car's {v.width:.2f} m and "
            f"{edge_keep(checker):.2f} m each side)"
        )
    return Diagnosis(
        DiagnosisKind.NARROW_PASSAGE,
        f"the passage near ({x:.1f}, {y:.1f}) is {width:.2f} m wide; {tail}",
        numbers,
    )


def _gap_width(checker: CollisionChecker, x: float, y: float) -> float:
    """Width of the gap at the grid cell ``(x, y)`` of its narrowest place.

    Twice the distance to the nearest wall from the cell's centre, which lies up to
    half a cell off the gap's centre line (a 1.85 m gap read 1.75 m); when the two
    nearest walls (obstacles, or the bounds) are that far apart give or take a cell,
    their own distance, the gap's exact width.
    """
    shapes = _shapes(checker)
    p = shapely.Point(x, y)
    around = 2.0 * float(p.distance(shapes.solid))
    parts = [shapes.edge, *shapes.polygons]
    d = shapely.distance(np.array(parts, dtype=object), p)
    if len(parts) < 2:
        return around
    i, j = (int(k) for k in np.argsort(d)[:2])
    between = float(shapely.distance(parts[i], parts[j]))
    return between if abs(between - around) <= 2.0 * checker.resolution else around


def _u_turn(m: Map, checker: CollisionChecker, start: Pose, goal: Pose) -> Diagnosis | None:
    v = m.vehicle
    turn = abs(math.remainder(goal.yaw - start.yaw, 2.0 * math.pi))
    if turn <= U_TURN_ANGLE:
        return None
    need = u_turn_width(v)
    centre = _body_centre(start, v)
    width = street_width(m, centre, start.yaw, checker=checker)
    if width >= need:
        return None
    # The widest free circle the car can reach from the start (distance field).
    labels = checker.component_labels
    a = _cell(checker, (start.x, start.y))
    if a is None or labels[a] == 0:
        return None
    grid = np.where(labels == labels[a], checker.clearance_grid, -np.inf)
    best = np.unravel_index(int(np.argmax(grid)), grid.shape)
    # Exactly (shapely) at the best cells and half a cell about them: the field's value
    # at cell centres read dead_end's 7.5 m street as "no place wider than 7.4 m".
    h = checker.resolution
    top = np.flatnonzero(grid.ravel() >= grid[best] - h)
    top = top[np.argsort(grid.ravel()[top])[::-1][:2000]]
    cx, cy = _centres(checker, *np.unravel_index(top, grid.shape))
    shift = np.array([(0.0, 0.0), (h / 2, 0.0), (-h / 2, 0.0), (0.0, h / 2), (0.0, -h / 2)])
    px = (cx[:, None] + shift[None, :, 0]).ravel()
    py = (cy[:, None] + shift[None, :, 1]).ravel()
    clear = shapely.distance(_shapes(checker).solid, shapely.points(px, py))
    k = int(np.argmax(clear))
    bx, by = float(px[k]), float(py[k])
    widest = max(2.0 * float(clear[k]), 2.0 * (float(grid[best]) + checker.grid_error))
    numbers = {"street_width_m": width, "needed_m": need, "widest_m": widest,
               "x": centre[0], "y": centre[1], "widest_x": bx, "widest_y": by}  # fmt: skip
    head = (
        f"the street at ({centre[0]:.1f}, {centre[1]:.1f}) is {width:.1f} m wide; a forward "
        f"U-turn needs {need:.1f} m"
    )
    if widest < need:
        tail = f"; no place reachable from the start is wider than {widest:.1f} m (try --reverse)"
    else:
        tail = (
            f"; the car must first drive to a wider place (the widest, about {widest:.0f} m "
            f"across, is near ({bx:.0f}, {by:.0f}))"
        )
    return Diagnosis(DiagnosisKind.U_TURN, head + tail, numbers)


def diagnose(problem: PlanningProblem, *, tree_edges: bool = True) -> Diagnosis | None:
    """The constraint that makes ``problem`` hard or impossible, or ``None``.

    Parameters
    ----------
    problem : PlanningProblem
        A query that failed. Reversing counts as allowed when the problem has a
        true ``reverse`` attribute.
    tree_edges : bool
        Whether the planner that failed searches by swept tree edges only. Without
        (Hybrid A*, or the default's escalation to it) their keep is not what stopped
        it, and ``tight_clearance`` is not looked for: it blamed a nose 0.5 m from a
        wall for a bay that only a turn the car cannot make leads into.

    Returns
    -------
    Diagnosis or None
        The first finding of the module's list; ``None`` when none applies or the
        checker is not a :class:`~rrtdrive.collision.CollisionChecker`.

    Examples
    --------
    >>> from rrtdrive.maps import Obstacle
    >>> from rrtdrive.planning.base import PlanningProblem
    >>> wall = Obstacle((14.305, 10.0), (1.0, 20.0))  # 0.4 m ahead of the start's nose
    >>> m = Map("wall", (0.0, 0.0, 40.0, 20.0), (wall,), Pose(10.0, 10.0, 0.0),
    ...         Pose(6.0, 10.0, math.pi))
    >>> print(diagnose(PlanningProblem.from_map(m)).message)  # doctest: +NORMALIZE_WHITESPACE
    the start has obstacle 0 0.40 m ahead of its nose: on any steady steering the car
    drives at most 0.40 m forward from it, less than the car length (4.30 m) the smallest
    manoeuvre needs; it can only be left in reverse (try --reverse)
    """
    checker = problem.checker
    if not isinstance(checker, CollisionChecker):
        return None
    m, start, goal = problem.map, problem.start, problem.goal
    reverse = bool(getattr(problem, "reverse", False))
    for label, pose in (("start", start), ("goal", goal)):
        found = _collides(m, checker, pose, label)
        if found is not None:
            return found
    passage = _passage(m, checker, start, goal)
    if passage is not None and (
        passage.kind is DiagnosisKind.WALLED_OFF or passage.numbers["width_m"] < m.vehicle.width
    ):
        # Before the room at the ends: a goal in a closed box, or behind a gap narrower
        # than the car, was "boxed in ... (try --reverse)", which no gear change mends.
        return passage
    for step in (
        lambda: _room(m, checker, start, goal, reverse),
        lambda: _tight(m, checker, start, goal) if tree_edges else None,
        lambda: passage,
        lambda: None if reverse else _u_turn(m, checker, start, goal),
    ):
        found = step()
        if found is not None:
            return found
    return None
