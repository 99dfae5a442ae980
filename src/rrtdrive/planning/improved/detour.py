"""A forward detour that a reversing path cuts short (with ``--reverse``).

With reverse allowed, the default's paper stage (one tree path) and its direct
Dubins path answer forward only. An answer longer than
``ImprovedConfig.reverse_detour_ratio`` times both the Reeds-Shepp distance (the
shortest path with reversing, obstacles aside) and the distance around the obstacles
(the Hybrid A* search's own estimate, :func:`around_obstacles`) is a detour: the
escalation is asked for a shorter path before it is returned, and the shorter of the
two is the answer. A path that is long only because the map's obstacles make every
path long is no detour: asking the search costs time and finds nothing much shorter.
"""

from __future__ import annotations

import contextlib
import dataclasses
import math

from rrtdrive.planning.base import PlanningProblem, Stopwatch
from rrtdrive.planning.hybrid.config import HybridConfig
from rrtdrive.planning.hybrid.heuristic import HolonomicField
from rrtdrive.planning.hybrid.resolution import free_cell_graph
from rrtdrive.planning.reeds_shepp import reeds_shepp_distance
from rrtdrive.types import PlanResult, Pose

__all__ = [
    "around_obstacles",
    "detour_ratio",
    "detour_words",
    "measured_detour",
    "shorter_answer",
]


def detour_ratio(length: float, start: Pose, goal: Pose, radius: float) -> float:
    """A forward path's length over the Reeds-Shepp distance at ``radius``.

    Examples
    --------
    >>> round(detour_ratio(20.0, Pose(0, 0, 0), Pose(10, 0, 0), 6.3), 6)
    2.0
    """
    shortest = reeds_shepp_distance(start, goal, radius)
    return length / max(shortest, 1e-9)


def around_obstacles(problem: PlanningProblem, watch: Stopwatch | None = None) -> float:
    """The distance from the start's rear axle to the goal's around the map's obstacles.

    The Hybrid A* escalation's own estimate (:class:`~rrtdrive.planning.hybrid.HolonomicField`
    on its first search's grid, the field cached for the escalation to reuse): the
    8-connected grid distance over the cells the rear axle may stand in, less a cell
    diagonal; ``inf`` when the grid joins no way between them. The grid is the map's
    set-up, built once per map (timed as set-up on ``watch``); the one Dijkstra from
    the goal's cell is the query's.
    """
    with watch.setup() if watch is not None else contextlib.nullcontext():
        grid = free_cell_graph(problem, HybridConfig().xy_resolution)
    start = problem.start
    return HolonomicField.towards(grid, problem.goal).value(start.x, start.y)


def measured_detour(
    length: float, problem: PlanningProblem, radius: float, limit: float, watch: Stopwatch
) -> tuple[float, bool]:
    """``(ratio, around)``: how far a forward path of ``length`` is a detour.

    ``ratio``: ``length`` over the Reeds-Shepp distance at ``radius``, or over the
    distance around the obstacles (:func:`around_obstacles`, looked up only when the
    first ratio is above ``limit``) when that is longer (``around`` True). The path is
    a detour when ``ratio > limit``.
    """
    ratio = detour_ratio(length, problem.start, problem.goal, radius)
    if ratio > limit:
        # Shorter than the Reeds-Shepp distance (open ground; inf: no way found on
        # the grid, which a found path rules out) the estimate says nothing more.
        distance = around_obstacles(problem, watch)
        if math.isfinite(distance) and length / max(distance, 1e-9) < ratio:
            return length / distance, True
    return ratio, False


def detour_words(kind: str, length: float, ratio: float, around: bool = False) -> str:
    """What the escalation was asked to shorten, for its message.

    ``around``: the ratio is to the distance around the obstacles (which is longer than
    the Reeds-Shepp distance), not to the Reeds-Shepp distance.

    Examples
    --------
    >>> detour_words("tree path", 186.05, 2.46)
    'the RRT-Connect stages found only a forward detour (tree path, 186.1 m, 2.46 times the shortest path with reversing, obstacles aside)'
    >>> detour_words("tree path", 186.05, 2.82, around=True)[-57:]
    '2.82 times the distance around the obstacles to the goal)'
    """  # noqa: E501
    base = (
        "the distance around the obstacles to the goal"
        if around
        else "the shortest path with reversing, obstacles aside"
    )
    return (
        f"the RRT-Connect stages found only a forward detour ({kind}, {length:.1f} m, "
        f"{ratio:.2f} times {base})"
    )


def shorter_answer(
    escalated: PlanResult, detour: PlanResult, elapsed: float, reverse: bool = True
) -> PlanResult:
    """The escalation's path when it solved shorter than the detour, else the detour.

    Shorter counts each gear change as the escalation's own
    ``HybridConfig.gear_change_cost`` metres (5): a path a few metres shorter than a
    forward detour but stopping to change gear is no better (on the issue's random sets,
    seeds 1 and 2, the tree paths given way were 28-110 m longer). The detour keeps its
    own stage and message, with what the escalation found added (``reverse``: whether
    it searched with reverse; forward only with ``escalation_first="always"``).
    """
    per_cusp = HybridConfig().gear_change_cost
    if escalated.success:
        cost = escalated.path.length + per_cusp * len(escalated.path.cusps)
        if cost < detour.path.length + per_cusp * len(detour.path.cusps):
            return escalated
    length = escalated.path.length
    if not escalated.success:
        found = f"none ({int(escalated.stats.get('hybrid_expansions', 0))} expansions)"
    elif length >= detour.path.length:
        found = f"a longer path ({length:.1f} m)"
    else:
        cusps = len(escalated.path.cusps)
        found = (
            f"a path {detour.path.length - length:.1f} m shorter with {cusps} gear change(s), "
            f"each weighed as {per_cusp:g} m"
        )
    gear = "with reverse" if reverse else "forward only"
    return dataclasses.replace(
        detour,
        message=f"{detour.message}; Hybrid A* ({gear}) found {found}",
        planning_time_s=elapsed,
        # The escalation's counters, not its stage: the detour's path is returned.
        stats={**{k: v for k, v in escalated.stats.items() if k != "stage"}, **detour.stats},
    )
