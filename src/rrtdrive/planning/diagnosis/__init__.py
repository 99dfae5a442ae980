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
   Forward only, a goal in a pocket (less than 20 m behind it on every steady steering)
   that Hybrid A*'s search from the goal proved no way into (``no_approach``: every pose
   it can be driven into from, explored, and none leads to the start) is
   ``needs_reverse`` too, with that room measured (:func:`~.checks.no_forward_arrival`;
   looked for after 3 and 4); so is a start whose forward search ran out of states (a
   proof at the search's resolution) with a pocket ahead of it
   (:func:`~.checks.no_forward_departure`). With more room the search's exhaustion is
   no proof off its lattice and is not named.
3. ``tight_clearance`` (for planners that search by tree edges only): no 0.5 m tree
   edge at the start (or the goal), in any direction and either way, passes the swept
   edge test although the exact body is free along its heading: the
   body is closer to an obstacle than that test keeps beside it (the checker's margin,
   its grid error and trace step) or beyond its bumper (the capsule's round end too).
4. ``narrow_passage`` / ``walled_off``: start and goal are joined only through a gap
   narrower than the swept edge test needs, or by none at all; the gap is located on
   the distance field and measured with shapely. ``walled_off`` is looked for before
   2 and 3: nothing at the ends matters when no way joins them.
5. ``u_turn``: start and goal headings differ by more than 120 degrees, or the goal
   lies behind the start facing the same way (forward, the car must head back to get
   there), while the street at the start (its narrowest chord within 45 deg of the
   heading's normal) is narrower than a forward U-turn of this car needs
   (:func:`u_turn_width` plus the planners' 0.15 m each side), and either no place
   reachable from the start is that wide, or the widest is narrower than the circle
   the car turns round in (:func:`~.measures.turning_circle`), or the car must first
   drive to it.

Each finding is a frozen :class:`Diagnosis` with its numbers; ``None`` when none applies.
After these, the reversing planners look once more at a forward-only failure with no
finding (:func:`~rrtdrive.planning.result.run_query`'s ``probe``,
:func:`~rrtdrive.planning.hybrid.probe.reverse_probe`): ``needs_reverse`` when a small
Hybrid A* search with reversing allowed finds a path.
The package: :mod:`.findings` (the records), :mod:`.measures` (runs, widths, the map's
shapes), :mod:`.checks` (one function per finding) and :func:`diagnose` here.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from rrtdrive.collision import CollisionChecker
from rrtdrive.planning.diagnosis.checks import (
    body_collides,
    narrow_passage,
    no_forward_arrival,
    no_forward_departure,
    room_at_ends,
    tight_clearance,
    u_turn,
)
from rrtdrive.planning.diagnosis.findings import Diagnosis, DiagnosisKind
from rrtdrive.planning.diagnosis.measures import (
    edge_keep,
    end_keep,
    free_run,
    nearest_obstacle,
    street_width,
    u_turn_width,
)

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


def diagnose(
    problem: PlanningProblem,
    *,
    tree_edges: bool = True,
    no_approach: bool = False,
    start_exhausted: bool = False,
    exact_goal_edges: bool = False,
    headings: bool = True,
) -> Diagnosis | None:
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
    no_approach : bool
        Whether a Hybrid A* search from the goal proved, forward only, that no way in
        reaches the start (``no_approach``): with a pocket behind the goal (less than
        :data:`~.checks.ARRIVAL_POCKET_M`), that proof is the finding
        (:func:`~.checks.no_forward_arrival`), before the u-turn's.
    start_exhausted : bool
        Likewise from the start: every forward way on explored, none reached the goal;
        with a pocket ahead of the start (less than :data:`~.checks.POCKET_M`), the
        finding (:func:`~.checks.no_forward_departure`).
    exact_goal_edges : bool
        Whether the tree planner tests an edge into the goal exactly when its swept test
        fails (:class:`~rrtdrive.planning.edges.EdgeTester`): then an edge the body
        passes reaches the goal, and its keep does not stop it there.
    headings : bool
        Whether the planner keeps the ends' headings. Without (the tree baselines, which
        plan positions), no finding about them: the room at the ends, the approaches
        and the U-turn are left out (a baseline's failure was said to need reverse).

    Returns
    -------
    Diagnosis or None
        The first finding of the module's list; ``None`` when none applies or the
        checker is not a :class:`~rrtdrive.collision.CollisionChecker`.

    Examples
    --------
    >>> import math
    >>> from rrtdrive.maps import Map, Obstacle
    >>> from rrtdrive.types import Pose
    >>> from rrtdrive.planning.base import PlanningProblem
    >>> wall = Obstacle((14.305, 10.0), (1.0, 20.0))  # 0.4 m ahead of the start's nose
    >>> m = Map("wall", (0.0, 0.0, 40.0, 20.0), (wall,), Pose(10.0, 10.0, 0.0),
    ...         Pose(6.0, 10.0, math.pi))
    >>> print(diagnose(PlanningProblem.from_map(m)).message)  # doctest: +NORMALIZE_WHITESPACE
    the start has obstacle 0 at (14.3, 10.0) 0.40 m ahead of its nose: on any steady
    steering the car drives at most 0.40 m forward from it, less than the car length
    (4.30 m) the smallest manoeuvre needs; it can only be left in reverse (try --reverse)
    """
    checker = problem.checker
    if not isinstance(checker, CollisionChecker):
        return None
    m, start, goal = problem.map, problem.start, problem.goal
    reverse = bool(getattr(problem, "reverse", False))
    for label, pose in (("start", start), ("goal", goal)):
        found = body_collides(m, checker, pose, label)
        if found is not None:
            return found
    passage = narrow_passage(m, checker, start, goal, tree_edges)
    if passage is not None and (
        passage.kind is DiagnosisKind.WALLED_OFF
        or passage.numbers["width_m"] < m.vehicle.width
        or reverse
    ):
        # Before the room at the ends: a goal in a closed box, or behind a gap narrower
        # than the car, was "boxed in ... (try --reverse)", which no gear change mends;
        # with reversing allowed, gear changes leave a boxed end, not a narrow gap.
        return passage
    for step in (
        lambda: room_at_ends(m, checker, start, goal, reverse) if headings else None,
        lambda: (
            tight_clearance(m, checker, start, goal, exact_goal_edges) if tree_edges else None
        ),
        lambda: passage,
        lambda: no_forward_arrival(m, checker, goal) if no_approach and not reverse else None,
        lambda: no_forward_departure(m, checker, start)
        if start_exhausted and not reverse
        else None,
        lambda: None if reverse or not headings else u_turn(m, checker, start, goal),
    ):
        found = step()
        if found is not None:
            return found
    return None
