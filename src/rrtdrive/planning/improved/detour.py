"""A forward detour that a reversing path cuts short (with ``--reverse``).

With reverse allowed, the default's paper stage (one tree path) and its direct
Dubins path answer forward only. An answer longer than
``ImprovedConfig.reverse_detour_ratio`` times the Reeds-Shepp distance (the shortest
path with reversing, obstacles aside) and, for a tree path, the distance around the
obstacles (the Hybrid A* search's own estimate, :func:`around_obstacles`) is a detour:
the escalation is asked for a path before it is returned, and the one that costs less
as the search weighs a path (:func:`search_cost`) is the answer. A tree path that is
long only because the map's obstacles make every path long is no detour: asking the
search costs time and finds nothing much shorter.
"""

from __future__ import annotations

import contextlib
import dataclasses
import math

import numpy as np

from rrtdrive.planning.base import PlanningProblem, Stopwatch
from rrtdrive.planning.hybrid.config import HybridConfig
from rrtdrive.planning.hybrid.heuristic import HolonomicField
from rrtdrive.planning.hybrid.resolution import free_cell_graph
from rrtdrive.planning.reeds_shepp import reeds_shepp_distance
from rrtdrive.types import Path, PlanResult, Pose
from rrtdrive.values import counted

__all__ = [
    "DETOURS",
    "around_obstacles",
    "detour_ratio",
    "detour_words",
    "measured_detour",
    "search_cost",
    "shorter_answer",
]


#: The forward answers the rule looks at: kind -> (its ``stats`` key, whether the distance
#: around the obstacles counts too). The tree path: yes (session 37; the Reeds-Shepp
#: distance alone sent 13 of 100 random starts to the escalation, 5 for nothing). The
#: direct Dubins path: no, as in session 33 (random start 74's 98.0 m path is 1.65 times
#: the Reeds-Shepp distance, under 1.5 times the distance around, and the escalation's
#: forward path is 84.4 m).
DETOURS: dict[str, tuple[str, bool]] = {
    "tree path": ("tree_detour_ratio", True),
    "direct Dubins path": ("dubins_detour_ratio", False),
}


def detour_ratio(length: float, start: Pose, goal: Pose, radius: float) -> float:
    """A forward path's length over the Reeds-Shepp distance at ``radius``.

    Examples
    --------
    >>> round(detour_ratio(20.0, Pose(0, 0, 0), Pose(10, 0, 0), 6.3), 6)
    2.0
    """
    shortest = reeds_shepp_distance(start, goal, radius)
    return length / max(shortest, 1e-9)


def around_obstacles(
    problem: PlanningProblem, watch: Stopwatch | None = None, config: HybridConfig | None = None
) -> float:
    """The distance from the start's rear axle to the goal's around the map's obstacles.

    The Hybrid A* escalation's own estimate (:class:`~rrtdrive.planning.hybrid.HolonomicField`
    on its first search's grid, ``config``'s, default ``HybridConfig()``; the field cached
    for the escalation to reuse): the 8-connected grid distance over the cells the rear
    axle may stand in, less a cell diagonal; ``inf`` when the grid joins no way between
    them. The grid is the map's set-up, built once per map (timed as set-up on
    ``watch``); the one Dijkstra from the goal's cell is the query's.
    """
    with watch.setup() if watch is not None else contextlib.nullcontext():
        grid = free_cell_graph(problem, (config or HybridConfig()).xy_resolution)
    start = problem.start
    return HolonomicField.towards(grid, problem.goal).value(start.x, start.y)


def measured_detour(
    length: float, problem: PlanningProblem, radius: float, limit: float,
    watch: Stopwatch | None, config: HybridConfig | None = None,
) -> tuple[float, bool]:
    """``(ratio, around)``: how far a forward path of ``length`` is a detour.

    ``ratio``: ``length`` over the Reeds-Shepp distance at ``radius``, or over the
    distance around the obstacles (:func:`around_obstacles`, looked up only when the
    first ratio is above ``limit``) when that is longer (``around`` True). The path is
    a detour when ``ratio > limit``. ``watch`` None: the Reeds-Shepp distance alone
    (the direct Dubins path's rule, :data:`DETOURS`).
    """  # fmt: skip
    ratio = detour_ratio(length, problem.start, problem.goal, radius)
    if ratio > limit and watch is not None:
        # Shorter than the Reeds-Shepp distance (open ground; inf: no way found on
        # the grid, which a found path rules out) the estimate says nothing more.
        distance = around_obstacles(problem, watch, config)
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


def search_cost(path: Path, config: HybridConfig) -> float:
    """A path's cost as the Hybrid A* search weighs it, in metres.

    Forward metres, reverse metres times ``config.reverse_cost`` and
    ``config.gear_change_cost`` a gear change.

    Examples
    --------
    >>> import numpy as np
    >>> ahead = np.column_stack([np.linspace(0, 10, 11), np.zeros((11, 3)), np.ones(11)])
    >>> back = np.column_stack([np.linspace(10, 6, 5), np.zeros((5, 3)), -np.ones(5)])
    >>> rows = np.vstack([ahead, back])
    >>> search_cost(Path(rows, rows[[0, 10, -1], :2]), HybridConfig())  # 10 + 2 x 4 + 5
    23.0
    """
    rows = path.samples
    if len(rows) < 2:
        return 0.0
    steps = np.hypot(*np.diff(rows[:, :2], axis=0).T)
    reverse = float(steps[rows[1:, 4] < 0].sum())
    return path.length + (config.reverse_cost - 1.0) * reverse + (
        config.gear_change_cost * len(path.cusps)
    )


def shorter_answer(
    escalated: PlanResult, detour: PlanResult, elapsed: float, reverse: bool = True,
    config: HybridConfig | None = None,
) -> PlanResult:
    """The escalation's path when it costs less than the detour, else the detour.

    Costs as the escalation's search weighs them (:func:`search_cost`: a reverse metre
    twice a forward one, a gear change 5 m): a path shorter than a forward detour but
    driven mostly in reverse, or stopping to change gear, is no better (random goal 60
    of the issue's set: 108.4 m with 86.3 m in reverse against a 159.9 m forward loop;
    reversing is slow: stock parking-v0 seeds 56 and 84 take 26 and 11 % longer). The
    detour keeps its own stage and message, with what the escalation found added
    (``reverse``: whether it searched with reverse; forward only with
    ``escalation_first="always"``; ``config``: the escalation's, default ``HybridConfig()``).
    """
    config = config or HybridConfig()
    length = escalated.path.length
    if not escalated.success:
        found = f"none ({counted(int(escalated.stats.get('hybrid_expansions', 0)), 'expansions')})"
    else:
        cost, kept_cost = search_cost(escalated.path, config), search_cost(detour.path, config)
        if cost < kept_cost:
            return escalated
        found = (
            f"a longer path ({length:.1f} m)"
            if length >= detour.path.length
            else f"a path {detour.path.length - length:.1f} m shorter that costs more: "
            f"{cost:.1f} m against {kept_cost:.1f} m, a reverse metre weighed as "
            f"{config.reverse_cost:g}, a gear change as {config.gear_change_cost:g} m"
        )
    gear = "with reverse" if reverse else "forward only"
    return dataclasses.replace(
        detour,
        message=f"{detour.message}; Hybrid A* ({gear}) found {found}",
        planning_time_s=elapsed,
        # Every stage's count: the tree's iterations and the escalation's expansions.
        iterations=max(detour.iterations, escalated.iterations),
        # The escalation's counters, not its stage: the detour's path is returned.
        stats={**{k: v for k, v in escalated.stats.items() if k != "stage"}, **detour.stats},
    )
