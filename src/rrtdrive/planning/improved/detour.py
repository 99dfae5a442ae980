"""A forward detour that a reversing path cuts short (with ``--reverse``).

With reverse allowed, the default's paper stage (one tree path) and its direct
Dubins path answer forward only. An answer longer than
``ImprovedConfig.reverse_detour_ratio`` times the Reeds-Shepp distance (the shortest
path with reversing, obstacles aside) is a detour: the Hybrid A* escalation is asked
for a shorter path before it is returned, and the shorter of the two is the answer.
"""

from __future__ import annotations

import dataclasses

from rrtdrive.planning.reeds_shepp import reeds_shepp_distance
from rrtdrive.types import PlanResult, Pose

__all__ = ["detour_ratio", "detour_words", "shorter_answer"]


def detour_ratio(length: float, start: Pose, goal: Pose, radius: float) -> float:
    """A forward path's length over the Reeds-Shepp distance at ``radius``.

    Examples
    --------
    >>> round(detour_ratio(20.0, Pose(0, 0, 0), Pose(10, 0, 0), 6.3), 6)
    2.0
    """
    shortest = reeds_shepp_distance(start, goal, radius)
    return length / max(shortest, 1e-9)


def detour_words(kind: str, length: float, ratio: float) -> str:
    """What the escalation was asked to shorten, for its message.

    Examples
    --------
    >>> detour_words("tree path", 186.05, 2.46)
    'the RRT-Connect stages found only a forward detour (tree path, 186.1 m, 2.46 times the shortest path with reversing, obstacles aside)'
    """  # noqa: E501
    return (
        f"the RRT-Connect stages found only a forward detour ({kind}, {length:.1f} m, "
        f"{ratio:.2f} times the shortest path with reversing, obstacles aside)"
    )


def shorter_answer(escalated: PlanResult, detour: PlanResult, elapsed: float) -> PlanResult:
    """The escalation's path when it solved shorter than the detour, else the detour.

    The detour keeps its own stage and message, with what the escalation found added.
    """
    if escalated.success and escalated.path.length < detour.path.length:
        return escalated
    found = f"a longer path ({escalated.path.length:.1f} m)" if escalated.success else (
        f"none ({int(escalated.stats.get('hybrid_expansions', 0))} expansions)"
    )
    return dataclasses.replace(
        detour,
        message=f"{detour.message}; Hybrid A* (with reverse) found {found}",
        planning_time_s=elapsed,
        # The escalation's counters, not its stage: the detour's path is returned.
        stats={**{k: v for k, v in escalated.stats.items() if k != "stage"}, **detour.stats},
    )
