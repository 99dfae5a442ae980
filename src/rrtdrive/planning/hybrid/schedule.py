"""The two searches of one Hybrid A* query taking turns (:func:`alternate`).

The search from the start and the one from the goal back towards it run in turns
counted in expansions, so the schedule is the same on any machine; the multi-point
turn and the lattice's guidance come in at fixed points of it.
"""

from __future__ import annotations

from collections.abc import Callable

from rrtdrive.planning.base import Stopwatch
from rrtdrive.planning.hybrid.heuristic import Heuristic
from rrtdrive.planning.hybrid.path import BuiltPath
from rrtdrive.planning.hybrid.search import HybridSearch, Piece, SearchOutcome
from rrtdrive.planning.hybrid.turn import TurnResult

__all__ = ["Accept", "Guide", "Turn", "alternate"]

#: ``accept(pieces)``: the checked path of a connection, or ``None`` to search on.
Accept = Callable[[list[Piece]], BuiltPath | None]
#: The multi-point turn of a search (:func:`~.turn.multi_point_turn`), given the
#: expansions it may spend.
Turn = Callable[[int], TurnResult[BuiltPath]]
#: The estimates that guide the searches (from the start, from the goal) from now on,
#: or ``None`` to leave them as they are.
Guide = Callable[[], "tuple[Heuristic, Heuristic] | None"]


def alternate(
    searches: list[tuple[HybridSearch, Accept]],
    budget: int,
    first: int,
    watch: Stopwatch,
    turn_first: Turn | None = None,
    guide: Guide | None = None,
    guide_after: int = 0,
    goal_first: bool = False,
) -> tuple[BuiltPath | None, SearchOutcome]:
    """Run the searches in turns of ``first``, ``first``, ``2 first``, ``2 first``, ... expansions.

    The turns are counted in expansions, never in time, so the schedule is the
    same on any machine. Either search running out of states ends the query: from
    the start it proves the goal unreachable, from the goal that no approach exists,
    each on its own lattice only (the other side's shots may reach what it cannot: a
    15.2 m street's forward U-turn that a goal-first search "proves" impossible).
    ``turn_first``: the multi-point turn tried once, after the first turn from the
    start (each of its moves counted as an expansion). ``guide``: the searches'
    new estimates, taken at the first turn that starts with ``guide_after`` or more
    expansions spent (:attr:`HybridConfig.lattice_after`). ``goal_first``: the search
    from the goal (the second) takes the first turn.
    """
    outcomes = [SearchOutcome("expansions", 0, 0, 0, 0) for _ in searches]
    k = 1 if goal_first and len(searches) > 1 else 0
    last, turn, used = (k - 1) % len(searches), max(1, first), 0  # turns double after last
    while True:
        search, accept = searches[k]
        if guide is not None and used >= guide_after:
            guided_by = guide()
            guide = None
            for (s, _), h in zip(searches, guided_by or (), strict=False):
                s.reguide(h)
        if len(searches) == 1:
            turn = budget
        step = min(turn, budget - used)
        if guide is not None and len(searches) == 1:
            step = min(step, guide_after - used)  # one search: stop where the guide comes in
        before = outcomes[k].expansions
        path, outcomes[k] = search.run(accept, before + step, watch.expired)
        used += outcomes[k].expansions - before
        if path is not None or outcomes[k].reason != "expansions" or used >= budget:
            break
        if turn_first is not None and k == 0 and not watch.expired():
            tried = turn_first(budget - used)
            turned = tried.result is not None
            outcomes.append(SearchOutcome(
                "solved" if turned else "expansions", tried.moves + tried.expansions, 0,
                tried.shots, 0, tried.moves if turned else 0,
            ))  # fmt: skip
            used += tried.moves + tried.expansions
            turn_first = None
            if turned:
                return tried.result, SearchOutcome.total("solved", outcomes)
            if used >= budget:
                break
        if k == last:
            turn *= 2
        k = (k + 1) % len(searches)
    if len(outcomes) == 1:
        return path, outcomes[0]
    reason = outcomes[k].reason
    if reason == "exhausted" and k == 1:
        reason = "no_approach"  # exhausted from the goal's side
    return path, SearchOutcome.total(reason, outcomes)
