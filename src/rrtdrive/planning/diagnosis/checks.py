"""The findings of :func:`~rrtdrive.planning.diagnosis.diagnose`, one function each."""

from __future__ import annotations

import math

import numpy as np
import shapely
from scipy import ndimage, optimize
from scipy.spatial import cKDTree

from rrtdrive.collision import CollisionChecker
from rrtdrive.maps import Map
from rrtdrive.planning.diagnosis.findings import Diagnosis, DiagnosisKind
from rrtdrive.planning.diagnosis.measures import (
    RUN_STEP,
    arc_poses,
    best_run,
    body_centre,
    cell_centres,
    edge_keep,
    end_keep,
    first_hit,
    free_run,
    gap_width,
    grid_cell,
    joined_in_free_space,
    map_shapes,
    nearest_obstacle,
    obstacle_name,
    street_width,
    turning_circle,
    u_turn_width,
)
from rrtdrive.planning.edges import exact_edge_free
from rrtdrive.types import Pose, VehicleParams
from rrtdrive.vehicle import footprint_polygon

__all__ = [
    "BEHIND_MIN",
    "BODY_CLEARANCE",
    "MIN_CLEARANCE",
    "U_TURN_ANGLE",
    "body_collides",
    "goal_behind",
    "narrow_passage",
    "no_forward_arrival",
    "no_forward_departure",
    "pocket_run",
    "room_at_ends",
    "tight_clearance",
    "u_turn",
]

#: Heading change beyond which start and goal need the car turned round.
U_TURN_ANGLE = math.radians(120.0)
#: The body clearance the planners keep (``ImprovedConfig`` and ``HybridConfig``
#: ``body_clearance``; tests/test_diagnosis.py checks they agree): a turn needs it each side.
BODY_CLEARANCE = 0.15
#: The least body clearance any Hybrid A* stage keeps (``HybridConfig.min_clearance``).
MIN_CLEARANCE = 0.05
#: How far (metres) back along the start's heading a goal counts as behind it.
BEHIND_MIN = 1.0


def body_collides(m: Map, checker: CollisionChecker, pose: Pose, label: str) -> Diagnosis | None:
    """``body_collides``: the ``label`` end's body overlaps an obstacle or leaves the map."""
    if checker.pose_free(pose.as_tuple()):
        return None
    index = first_hit(checker, footprint_polygon(pose.as_tuple(), m.vehicle))
    what = obstacle_name(index, m.obstacles) if index >= 0 else "the bounds (it leaves the map)"
    return Diagnosis(
        DiagnosisKind.BODY_COLLIDES,
        f"the {label}'s body at ({pose.x:.1f}, {pose.y:.1f}) overlaps {what}",
        {"obstacle": index},
    )


def _straight_stop(
    checker: CollisionChecker, pose: Pose, direction: int, vehicle: VehicleParams, limit: float
) -> tuple[float, int | None]:
    """The free straight run from ``pose`` (up to ``limit``) and what ends it.

    The obstacle index (-1: the map's edge) that the body hits just past the run, or
    ``None`` when the run reaches ``limit``.
    """
    straight = free_run(checker, pose, direction, 0.0, limit)
    if straight >= limit:
        return straight, None
    probe = arc_poses(pose, direction, 0.0, straight + 2 * RUN_STEP, RUN_STEP)[-1]
    return straight, first_hit(checker, footprint_polygon(tuple(probe), vehicle))


def room_at_ends(
    m: Map, checker: CollisionChecker, start: Pose, goal: Pose, reverse: bool
) -> Diagnosis | None:
    """``needs_reverse`` / ``boxed_in``: too little room ahead of the start or behind the goal."""
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
        other = goal if label == "start" else start
        along = forward * (
            (other.x - pose.x) * math.cos(pose.yaw) + (other.y - pose.y) * math.sin(pose.yaw)
        )
        if 0.0 < along <= run_fwd:
            # The other end lies in that room (a goal 2.5 m ahead of a start 2.6 m from a
            # wall was told "it can only be left in reverse"; an audit): the room is not
            # what stops the car.
            continue
        run_rev = best_run(checker, pose, -forward, v, need)
        ahead, behind = (run_fwd, run_rev) if forward > 0 else (run_rev, run_fwd)
        numbers = {"room_ahead_m": ahead, "room_behind_m": behind, "needed_m": need}
        tip = "" if reverse else " (try --reverse)"
        if run_rev < need:
            verb = "leaving" if label == "start" else "reaching"
            # With reverse already allowed, "at least one gear change" told the user
            # nothing (a user-map audit): the search had them and found no way.
            takes = (
                f"{verb} it takes short moves with gear changes in that room, and the search "
                "found none that fits"
                if reverse
                else f"{verb} it takes at least one gear change{tip}"
            )
            # The space as a user measures it (a kerbside gap's length): the body's length
            # and the straight runs both ways (the runs above are the best steady steering's).
            space = v.length + free_run(checker, pose, 1, 0.0, need) + free_run(
                checker, pose, -1, 0.0, need
            )
            numbers["space_along_m"] = space
            return Diagnosis(
                DiagnosisKind.BOXED_IN,
                f"the {label} is boxed in: on any steady steering the car has at most "
                f"{behind:.2f} m behind it and {ahead:.2f} m ahead of it, {least} (along "
                f"its heading the space is {space:.2f} m, {space / v.length:.2f} car "
                f"lengths); {takes}",
                numbers,
            )
        if reverse:
            continue  # reversing is allowed and has room: not the constraint
        straight, blocker = _straight_stop(checker, pose, forward, v, need)
        assert blocker is not None  # the straight run is one of the runs, all under need
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
            f"the {label} has {obstacle_name(blocker, checker.obstacles)} {where}: on any "
            f"steady steering {room}, {least}; {only}{tip}",
            numbers,
        )
    return None



#: A start whose longest steady-steering run ahead is shorter than this (metres) sits in a
#: pocket: :func:`no_forward_departure` names it. With more room ahead the proof is about
#: the whole region the car can drive forward in, which the room ahead does not measure.
POCKET_M = 10.0
#: Likewise behind a goal, for :func:`no_forward_arrival`. With more room the search's
#: exhaustion from the goal is about a wide region on its lattice, which is no proof off
#: it: a 15.2 m street's forward U-turn to a goal 30 m clear behind was "only in reverse"
#: (an audit; a hand-made forward path passes verify). Dead-end corridors of 10-13 m are
#: within it (a regression audit: at 10 m their lines were lost).
ARRIVAL_POCKET_M = 20.0


def pocket_run(
    checker: CollisionChecker, pose: Pose, direction: int, vehicle: VehicleParams, limit: float
) -> float | None:
    """The longest steady-steering run from ``pose`` in ``direction`` if under ``limit``.

    ``None`` when a run reaches ``limit``: no pocket. Hybrid A* gives the goal's side the
    first turn only for a goal in such a pocket (``direction`` -1, :data:`ARRIVAL_POCKET_M`).
    """
    run = best_run(checker, pose, direction, vehicle, limit)
    return run if run < limit else None


def _pocket(
    checker: CollisionChecker, pose: Pose, direction: int, vehicle: VehicleParams,
    limit: float, room_key: str, beyond: str,
) -> tuple[float, dict[str, float], str] | None:
    """A pocket's run, its numbers and the words for what stops the straight run in it.

    ``None`` without a pocket (:func:`pocket_run`); ``beyond`` places the blocker
    ("ahead of its nose").
    """  # fmt: skip
    run = pocket_run(checker, pose, direction, vehicle, limit)
    if run is None:
        return None
    straight, blocker = _straight_stop(checker, pose, direction, vehicle, limit)
    numbers = {room_key: run, "straight_gap_m": straight}
    words = ""
    if blocker is not None:
        numbers["obstacle"] = blocker
        words = f" ({obstacle_name(blocker, checker.obstacles)} {straight:.2f} m {beyond})"
    return run, numbers, words


def no_forward_arrival(m: Map, checker: CollisionChecker, goal: Pose) -> Diagnosis | None:
    """``needs_reverse``: a forward arrival that Hybrid A* proved impossible, with the room.

    Called when the search from the goal, driving it backwards on the search's arcs, ran
    out of states without reaching the start (``no_approach``) while the room behind
    the goal is a car length or more (else :func:`room_at_ends` speaks). Only a pocket
    behind the goal (less than :data:`ARRIVAL_POCKET_M` on every steady steering) is
    named, with what stops the straight run back; ``None`` otherwise.
    """
    found = _pocket(
        checker, goal, -1, m.vehicle, ARRIVAL_POCKET_M, "room_behind_m", "behind its rear"
    )
    if found is None:
        return None
    run, numbers, behind = found
    return Diagnosis(
        DiagnosisKind.NEEDS_REVERSE,
        f"a forward arrival at the goal comes from behind it, where the car has at most "
        f"{run:.2f} m on any steady steering{behind}, and the search drove every way in "
        "backwards from the goal without reaching the start (a proof at its resolution): "
        "it can only be reached in reverse (try --reverse)",
        numbers,
    )


def no_forward_departure(m: Map, checker: CollisionChecker, start: Pose) -> Diagnosis | None:
    """``needs_reverse``: a forward drive from the start that Hybrid A* proved leads nowhere.

    Called when the search from the start, forward only, ran out of states without
    reaching the goal (``exhausted``) while the room ahead of the start is a car length
    or more (else :func:`room_at_ends` speaks). Only a pocket (less than
    :data:`POCKET_M` ahead on every steady steering) is named; ``None`` otherwise.
    """
    found = _pocket(checker, start, 1, m.vehicle, POCKET_M, "room_ahead_m", "ahead of its nose")
    if found is None:
        return None
    run, numbers, ahead = found
    return Diagnosis(
        DiagnosisKind.NEEDS_REVERSE,
        f"driving forward, the start leads into a pocket: the car has at most {run:.2f} m "
        f"ahead of it on any steady steering{ahead}, and the search drove every way on "
        "forward from the start without reaching the goal (a proof at its resolution): it "
        "can only be left in reverse (try --reverse)",
        numbers,
    )


def _an_edge_passes(
    checker: CollisionChecker, pose: Pose, leg: float, exact_into: bool = False
) -> bool:
    """Whether some ``leg`` m edge at ``pose``, any direction, either way, passes the edge test.

    The improved planner's root grows within 90 deg of the heading, the baselines' trees
    any way, and a tree from the goal tests its edges leaving it: "none leaves (reaches)
    it" holds only if every one fails. One edge along the heading was tested: a post
    ahead-left of the nose, or a wall 0.5 m ahead of a goal's nose (which edges from
    behind at 45 deg, and rrt-connect's edges out of the goal, pass), read "so none
    reaches it" (a mutation audit). ``exact_into``: an edge into ``pose`` that the body
    passes exactly counts too (the baselines' goal edges: a goal 0.05 m beside a wall
    was reached in 19 iterations, and a 3-iteration failure was blamed on the keep).
    """
    ends = [
        pose.xy + leg * np.array([math.cos(pose.yaw + angle), math.sin(pose.yaw + angle)])
        for angle in np.radians(np.arange(0.0, 360.0, 5.0))
    ]
    if any(checker.edge_free(pose.xy, far) or checker.edge_free(far, pose.xy) for far in ends):
        return True
    return exact_into and any(exact_edge_free(checker, far, pose.xy) for far in ends)


def tight_clearance(
    m: Map, checker: CollisionChecker, start: Pose, goal: Pose, exact_goal_edges: bool = False
) -> Diagnosis | None:
    """``tight_clearance``: no tree edge at an end passes, where the exact body is free.

    ``exact_goal_edges``: the planner tests an edge into the goal exactly as well.
    """
    side, ends = edge_keep(checker), end_keep(checker)
    leg = 0.5
    ways = (("start", start, 1, "its rear", "leaves"), ("goal", goal, -1, "its nose", "reaches"))
    for label, pose, forward, bumper, verb in ways:
        # The body is free along the first edge's heading, yet no edge passes the test.
        exact = exact_goal_edges and label == "goal"
        if free_run(checker, pose, forward, 0.0, leg) < leg or _an_edge_passes(
            checker, pose, leg, exact
        ):
            continue
        index, gap = nearest_obstacle(m, footprint_polygon(pose.as_tuple(), m.vehicle), checker)
        return Diagnosis(
            DiagnosisKind.TIGHT_CLEARANCE,
            f"the {label}'s body is {gap:.2f} m from {obstacle_name(index, m.obstacles)}; "
            f"this planner's straight tree edges keep {side:.2f} m beside the body and "
            f"{ends:.2f} m beyond {bumper}, so none {verb} it (try --planner hybrid-a-star, "
            "or the default planner, whose Hybrid A* stage tests the body exactly)",
            # The keep's parts stay in the numbers: the swept test's round ends, the
            # checker's margin, its grid error and trace step.
            {"gap_m": gap, "keep_m": side, "keep_end_m": ends, "obstacle": index,
             "margin_m": checker.config.margin, "grid_error_m": checker.grid_error,
             "trace_step_m": checker.config.min_trace_step},
        )
    return None


def connected(field_: np.ndarray, t: float, a: tuple[int, int], b: tuple[int, int]) -> bool:
    labels, _ = ndimage.label(field_ >= t, structure=np.ones((3, 3), dtype=bool))
    return bool(labels[a] != 0 and labels[a] == labels[b])


def pass_cell(
    grid: np.ndarray, lo: float, hi: float, a: tuple[int, int], b: tuple[int, int]
) -> tuple[int, int]:
    """The grid cell of the narrowest place joining cells ``a`` and ``b``.

    ``a`` and ``b`` are joined by cells of clearance ``>= lo`` but not ``>= hi``: the
    pass is the cell of the band between (kept at ``lo``, not at ``hi``, on ``a``'s
    side) nearest to both sides at once. On the grid the bottleneck's clearance runs
    round every wall as a contour (a cell 0.85 m from a map corner has the clearance
    of a 1.85 m gap's centre), so the band's best-cleared cell can be anywhere.
    """
    structure = np.ones((3, 3), dtype=bool)
    low, _ = ndimage.label(grid >= lo, structure=structure)
    high, _ = ndimage.label(grid >= hi, structure=structure)
    band = (low == low[a]) & (high == 0)
    if high[a] == 0 or high[b] == 0 or high[a] == high[b]:
        best = np.unravel_index(int(np.argmax(np.where(band, grid, -np.inf))), grid.shape)
        return int(best[0]), int(best[1])
    cells = np.nonzero(band)
    if len(cells[0]) == 0:  # cannot happen (a and b join at lo through the band): be safe
        return int(a[0]), int(a[1])
    total = _distance_to(high == high[a], cells) + _distance_to(high == high[b], cells)
    best = int(np.argmin(total))  # the first in row order, as argmin over the whole grid
    return int(cells[0][best]), int(cells[1][best])


def _distance_to(side: np.ndarray, cells: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
    """Distance in cells from each of ``cells`` (outside ``side``) to ``side``'s nearest cell.

    The values ``ndimage.distance_transform_edt(~side)`` has there, from a KD-tree of the
    side's edge cells: a side's cell nearest to a point outside it has a 4-neighbour
    outside it (the one towards the point is nearer). The two whole-grid transforms
    took 10.6 s and 2 GB on a 2 km map (47.7 M cells).
    """
    edge = np.zeros_like(side)
    edge[:-1] |= side[:-1] & ~side[1:]
    edge[1:] |= side[1:] & ~side[:-1]
    edge[:, :-1] |= side[:, :-1] & ~side[:, 1:]
    edge[:, 1:] |= side[:, 1:] & ~side[:, :-1]
    points = np.argwhere(edge)
    query = np.column_stack(cells)
    _, nearest = cKDTree(points).query(query)
    d = query - points[nearest]
    return np.sqrt((d * d).sum(axis=1).astype(float))


def narrow_passage(
    m: Map, checker: CollisionChecker, start: Pose, goal: Pose, tree_edges: bool = True
) -> Diagnosis | None:
    """``narrow_passage`` / ``walled_off``: the narrowest gap joining start and goal, or none.

    ``tree_edges``: the failed planner searches by swept tree edges only, whose keep
    beside the body the gap must leave; else (Hybrid A*) the body and the least
    clearance any of its stages keeps (:data:`MIN_CLEARANCE`) each side.
    """
    grid = checker.clearance_grid
    a, b = grid_cell(checker, (start.x, start.y)), grid_cell(checker, (goal.x, goal.y))
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
    if not connected(grid, 1e-9, a, b):
        lo = -1.0
    else:
        for _ in range(10):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if connected(grid, mid, a, b) else (lo, mid)
    v = m.vehicle
    keep = edge_keep(checker) if tree_edges else MIN_CLEARANCE
    needed_width = v.width + 2.0 * keep
    # Besides the grid error the checker subtracts, its clearance field may read a gap
    # low by up to one more (rasterisation), as the gap's walls fall on the cells: below
    # needed_width no tree edge crosses; between it and sure_width the alignment decides
    # (a 2.4 m gap no edge crosses was taken as wide enough).
    sure_width = needed_width + (2.0 * checker.grid_error if tree_edges else 0.0)
    numbers = {"needed_m": needed_width, "car_width_m": v.width}
    if lo < 0.0:
        words = "the goal is walled off from the start: no gap connects them"
        if joined_in_free_space(checker, start, goal):
            words = (
                f"the goal is cut off from the start: the only gaps joining them are too "
                f"narrow to show on the planner's {checker.resolution:.2f} m grid, far "
                f"narrower than the car ({v.width:.2f} m)"
            )
        return Diagnosis(
            DiagnosisKind.WALLED_OFF,
            words,
            {**numbers, "width_m": 0.0},
        )
    best = pass_cell(grid, lo, hi, a, b)
    x, y = (float(v) for v in cell_centres(checker, *best))
    width = gap_width(checker, x, y)
    numbers.update(width_m=width, x=x, y=y)
    if width < v.width:
        tail = f"narrower than the car ({v.width:.2f} m)"
    elif width >= sure_width:
        return None  # wide enough for the planner that failed: not what stopped it
    elif tree_edges and width >= needed_width:
        numbers["needed_up_to_m"] = sure_width
        tail = (
            f"this planner's straight tree edges need {needed_width:.2f} to "
            f"{sure_width:.2f} m here, as the gap falls on its {checker.resolution:.2f} m "
            f"grid (the car's {v.width:.2f} m and {keep:.2f} m each side, plus up to "
            f"{checker.grid_error:.2f} m of grid error each side); try --planner hybrid-a-star"
        )
    elif tree_edges:
        tail = (
            f"this planner's straight tree edges need at least {needed_width:.2f} m (the car's "
            f"{v.width:.2f} m and {keep:.2f} m each side; try --planner hybrid-a-star)"
        )
    else:
        tail = (
            f"the car ({v.width:.2f} m) needs at least {needed_width:.2f} m, keeping the least "
            f"clearance the planner allows ({keep:.2f} m) each side"
        )
    return Diagnosis(
        DiagnosisKind.NARROW_PASSAGE,
        f"the passage near ({x:.1f}, {y:.1f}) is {width:.2f} m wide; {tail}",
        numbers,
    )



def goal_behind(start: Pose, goal: Pose) -> float | None:
    """How far (metres) the goal lies behind the start, or ``None`` unless it does.

    Behind: more than :data:`BEHIND_MIN` back along the start's heading, and no farther
    aside than back. Driving forward, the car must then head backwards at some point
    (its displacement along the start's heading is negative), whatever the goal's heading.

    Examples
    --------
    >>> goal_behind(Pose(15.0, 2.0, 0.0), Pose(8.0, 2.5, 0.0))
    7.0
    >>> goal_behind(Pose(15.0, 2.0, 0.0), Pose(8.0, 12.0, 0.0)) is None  # more aside
    True
    """
    dx, dy = goal.x - start.x, goal.y - start.y
    c, s = math.cos(start.yaw), math.sin(start.yaw)
    back, aside = -(dx * c + dy * s), abs(dy * c - dx * s)
    return back if back > BEHIND_MIN and aside <= back else None


def u_turn(m: Map, checker: CollisionChecker, start: Pose, goal: Pose) -> Diagnosis | None:
    """``u_turn``: the car must turn round where the street is narrower than its U-turn."""
    v = m.vehicle
    turn = abs(math.remainder(goal.yaw - start.yaw, 2.0 * math.pi))
    behind = goal_behind(start, goal)
    if turn <= U_TURN_ANGLE and behind is None:
        return None
    # Keeping the planners' clearance each side (a 14.8 m street failed with no word).
    need = u_turn_width(v) + 2.0 * BODY_CLEARANCE
    centre = body_centre(start, v)
    width = street_width(m, centre, start.yaw, checker=checker)
    if width >= need:
        return None
    # The widest free circle the car can reach from the start (distance field).
    labels = checker.component_labels
    a = grid_cell(checker, (start.x, start.y))
    if a is None or labels[a] == 0:
        return None
    grid = np.where(labels == labels[a], checker.clearance_grid, -np.inf)
    best = np.unravel_index(int(np.argmax(grid)), grid.shape)
    # Exactly (shapely) at the best cells and half a cell about them: the field's value
    # at cell centres read dead_end's 7.5 m street as "no place wider than 7.4 m".
    h = checker.resolution
    top = np.flatnonzero(grid.ravel() >= grid[best] - h)
    top = top[np.argsort(grid.ravel()[top])[::-1][:2000]]
    cx, cy = cell_centres(checker, *np.unravel_index(top, grid.shape))
    shift = np.array([(0.0, 0.0), (h / 2, 0.0), (-h / 2, 0.0), (0.0, h / 2), (0.0, -h / 2)])
    px = (cx[:, None] + shift[None, :, 0]).ravel()
    py = (cy[:, None] + shift[None, :, 1]).ravel()
    solid = map_shapes(checker).solid
    clear = shapely.distance(solid, shapely.points(px, py))
    k = int(np.argmax(clear))
    # The best sample is up to half a cell off the place's centre: climb to it (exact,
    # shapely). The field's value plus its grid error, taken before, is an upper bound
    # only: a 14.9 m box read "about 15.0 m across" (an audit, session 34).
    polished = optimize.minimize(
        lambda p: -float(shapely.distance(solid, shapely.Point(p))), (px[k], py[k]),
        method="Nelder-Mead",
        options={"xatol": 1e-4, "fatol": 1e-5, "initial_simplex": [
            (px[k], py[k]), (px[k] + h, py[k]), (px[k], py[k] + h)]},
    )  # fmt: skip
    if -polished.fun > clear[k]:
        bx, by, half = float(polished.x[0]), float(polished.x[1]), float(-polished.fun)
    else:
        bx, by, half = float(px[k]), float(py[k]), float(clear[k])
    widest = 2.0 * half
    # A round place has no street to swing the rear into: the front corner's circle.
    turn_in = turning_circle(v) + 2.0 * BODY_CLEARANCE
    numbers = {"street_width_m": width, "needed_m": need, "widest_m": widest,
               "turning_circle_m": turn_in, "clearance_m": BODY_CLEARANCE,
               "x": centre[0], "y": centre[1], "widest_x": bx, "widest_y": by}  # fmt: skip
    head = (
        f"the street at ({centre[0]:.1f}, {centre[1]:.1f}) is {width:.1f} m wide; a forward "
        f"U-turn keeping {BODY_CLEARANCE:g} m each side needs {need:.1f} m"
    )
    if turn <= U_TURN_ANGLE and behind is not None:
        # Facing the same way: forward, the car must head back somewhere to get there.
        numbers["behind_m"] = behind
        head = (
            f"the goal is {behind:.1f} m behind the start, facing the same way: driving "
            f"forward the car must turn round to reach it (and back); {head}"
        )
    least = u_turn_width(v) + 2.0 * MIN_CLEARANCE
    if widest < need:
        tail = f"; no place reachable from the start is wider than {widest:.1f} m"
        if widest >= least:
            # A 14.9 m street: a forward path keeping 0.105 m passes verify (an audit).
            numbers["needed_least_m"] = least
            tail += (
                f"; keeping only {MIN_CLEARANCE:g} m each side (the default's last resort) "
                f"a U-turn needs {least:.2f} m: one may fit that the search missed"
            )
        tail += " (try --reverse)"
    elif widest < turn_in:
        tail = (
            f"; the widest place reachable from the start, about {widest:.1f} m across near "
            f"({bx:.0f}, {by:.0f}), is narrower than the {turn_in:.1f} m circle the car turns "
            "round in (try --reverse)"
        )
    elif (bx - start.x) * math.cos(start.yaw) + (by - start.y) * math.sin(start.yaw) < 0.0:
        # Behind the car: getting there forward is the turn it cannot make here (a car
        # facing into a dead end was sent to the plaza behind it; an audit, session 34).
        tail = (
            f"; the widest place, about {widest:.0f} m across near ({bx:.0f}, "
            f"{by:.0f}), lies behind the car (try --reverse)"
        )
    else:
        tail = (
            f"; the car must first drive to a wider place (the widest, about {widest:.0f} m "
            f"across, is near ({bx:.0f}, {by:.0f}))"
        )
    return Diagnosis(DiagnosisKind.U_TURN, head + tail, numbers)

