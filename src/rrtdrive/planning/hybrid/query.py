"""One Hybrid A* query: the first search and the ladder of searches after it.

:func:`hybrid_query` runs on a started stopwatch and returns a
:class:`HybridAnswer`. Its first search (:func:`~.resolution.search_at_resolution`:
from the start, then also from the goal) may be followed, while there is no path
and budget is left, by the searches of :func:`_ladder`: a coarser one, finer ones,
a wider-turning one and the last resorts (less clearance). Its messages say in the
user's terms how each search ended.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from rrtdrive.geometry import wrap_angle
from rrtdrive.planning.base import PlanningProblem, Stopwatch
from rrtdrive.planning.diagnosis.checks import ARRIVAL_POCKET_M, pocket_run
from rrtdrive.planning.hybrid.config import HybridConfig
from rrtdrive.planning.hybrid.nudge import nudge
from rrtdrive.planning.hybrid.path import BuiltPath
from rrtdrive.planning.hybrid.resolution import (
    PROOFS,
    EndClearance,
    body_test,
    query_clearance,
    search_at_resolution,
)
from rrtdrive.planning.hybrid.search import SearchOutcome
from rrtdrive.planning.hybrid.shots import Piece
from rrtdrive.planning.smoothing import SmoothingConfig
from rrtdrive.planning.smoothing.drivable import slow_steering_note
from rrtdrive.types import Budget, Tree
from rrtdrive.values import counted

__all__ = ["HybridAnswer", "hybrid_query"]


@dataclass(frozen=True, eq=False)
class HybridAnswer:
    """What one query gave: the checked path (or ``None``), the outcome and a message.

    Attributes
    ----------
    path : BuiltPath or None
        The checked path (``None``: none found).
    outcome : SearchOutcome
        How the last search ended.
    message : str
        What happened, in words.
    trees : tuple of Tree
        The search trees of the last resolution tried, the one from the start first
        (the one from the goal second, when the query turned to it).
    note : str
        For a solved query, at which resolution and why (empty when the first search
        solved it).
    refinements : int
        The finer searches run after the first.
    stage : str
        The last search: ``"first"``, ``"fine"`` (:attr:`HybridConfig.refinements`),
        ``"coarse"`` (:attr:`HybridConfig.coarse_after`), ``"snug"`` (half-way from
        ``body_clearance`` to ``min_clearance``, at the finest resolution), ``"tight"``
        (``min_clearance``), ``"wide"`` (``wide_radius_factor``) or ``"persist"``
        (:attr:`HybridConfig.persist`).
    clearance : float
        The body clearance the last search kept, metres (less than ``body_clearance``
        after the snug and tight searches).
    """

    path: BuiltPath | None
    outcome: SearchOutcome
    message: str
    trees: tuple[Tree, ...]
    note: str = ""
    refinements: int = 0
    stage: str = "first"
    clearance: float = 0.0


def _failure_message(
    outcome: SearchOutcome,
    cfg: HybridConfig,
    budget: Budget,
    reverse: bool,
    allowed: int | None = None,
) -> str:
    """How one search ended, as the lead of a failure message.

    ``allowed``: the expansions of a search given a share of those left (``None``: all).
    """
    res = _resolution(cfg)
    counts = f"{counted(outcome.expansions, 'expansions')}, {counted(outcome.nodes, 'nodes')}"
    if outcome.reason == "exhausted":
        # "exhausted" is the search from the start's (the goal side's is "no_approach").
        lead = (
            f"no path at {res} resolution: the search from the start ran out of states "
            f"({counts}); "
        )
        if reverse:
            return lead + "the goal is unreachable for this car at this resolution"
        return lead + (
            "driving forward from this start, the car cannot reach the goal at this "
            "resolution (a path with reversing may exist: try --reverse)"
        )
    if outcome.reason == "no_approach":
        if reverse:
            return (
                f"no path at {res} resolution: every way the car could arrive at the goal was "
                f"explored from the goal and none leads to the start ({counts})"
            )
        return (
            f"no path at {res} resolution: driving forward, the car cannot arrive at the goal "
            f"pose (every way it could have come from, the goal driven backwards, was "
            f"explored and none leads to the start; {counts}); it can only be reached in "
            "reverse if at all (try --reverse)"
        )
    if outcome.reason == "time":
        return (
            f"no path found: the wall-clock cap of {budget.max_time_s:g} s was hit before the "
            f"expansion budget of {budget.max_iterations} ({counts})"
        )
    if outcome.reason == "rejected":
        return (
            f"no path found: {outcome.connections} goal connections could not be made "
            f"drivable ({counts})"
        )
    if allowed is not None:
        return (
            f"no path found at {res} resolution within its share of "
            f"{counted(allowed, 'expansions')} ({counts})"
        )
    return (
        f"no path found at {res} resolution within the expansion budget of "
        f"{budget.max_iterations} ({counts})"
    )


@dataclass(frozen=True)
class _Stage:
    """One search of :func:`hybrid_query`'s ladder after the first, and when it runs.

    It runs when the first search ended with one of ``after_first`` and the search
    just before it with one of ``after_last``, without a path, with expansions left.
    ``share`` is the part of the expansions left that it may spend when a later
    stage of the ladder may still run after it (else it gets them all).
    """

    name: str
    config: HybridConfig
    after_first: tuple[str, ...]
    after_last: tuple[str, ...]
    share: float = 1.0


#: Goal connections the ``"persist"`` search may have rejected. Each costs a ramp fit
#: (about 1.5 ms); the five random maps it solved needed up to 410 (about 0.6 s, map 36
#: of ``experiments/random_maps.py``), and this bounds a query whose every connection fails
#: to seconds, not the minutes its expansion budget alone would allow.
PERSIST_SOLUTIONS = 4096
#: The searches that keep less than the usual body clearance: ``"snug"`` (half-way to
#: ``min_clearance``, at the finest resolution) and ``"tight"`` (``min_clearance``).
_SNUGGER = ("snug", "tight")


@functools.lru_cache(maxsize=16)  # each stage's config validated once, not per query
def _ladder(config: HybridConfig) -> tuple[_Stage, ...]:
    """The searches that may follow the first one, in order (:func:`hybrid_query`).

    Built once per configuration (four validated copies of it: about 90 us, which a
    query that solves with its first search spent for nothing); the stages are frozen.

    Examples
    --------
    >>> ladder = _ladder(HybridConfig())
    >>> [s.name for s in ladder]
    ['coarse', 'middle', 'tight', 'wide', 'fine', 'persist', 'snug', 'tight', 'tight', 'tight']
    >>> [s.config.xy_resolution for s in ladder]
    [2.0, 1.0, 1.0, 0.5, 0.25, 0.25, 0.25, 0.5, 0.25, 0.25]
    >>> [round(s.config.body_clearance, 3) for s in ladder]
    [0.15, 0.15, 0.05, 0.15, 0.15, 0.15, 0.1, 0.05, 0.05, 0.05]
    >>> [s.share for s in ladder]
    [1.0, 0.5, 1.0, 0.5, 0.5, 1.0, 0.5, 0.5, 1.0, 1.0]

    The searches keeping less clearance turn at the car's own full lock, the last one
    (after every connection of the one before was rejected) wider:

    >>> [s.config.radius_factor for s in ladder]
    [1.02, 1.02, 1.0, 1.1, 1.02, 1.02, 1.0, 1.0, 1.0, 1.1]
    """
    stages = []
    if config.coarsens:
        # The first search spent its share, not out of states: the rest goes to a coarser one.
        spent = ("expansions",)
        stages.append(_Stage("coarse", config.coarsened(), spent, spent))
        if config.has_middle:
            # The coarse one ended with budget left (its proof holds at 2 m only): a
            # middle resolution, then keeping min_clearance there (an approach too tight
            # for 0.15 m that a 2 m grid cannot thread and a 0.5 m one finds too late).
            middle = config.middled()
            stages.append(_Stage("middle", middle, spent, _REFINE_ON, config.refine_share))
            if config.min_clearance < config.body_clearance:
                # Last of all, with more goal connections (tightened(): 4 x): an approach
                # 0.05 m from a car has most ramped connections cut the corner (random goal
                # 94 forward: the 17th to 24th passed, 4 301 expansions).
                stages.append(_Stage("tight", middle.tightened(), spent, (*PROOFS, "expansions")))
    if config.wide_radius_factor > config.radius_factor:
        # Every goal connection rejected: turn a little wider first (the ramps of a
        # full-lock word need steering room), at the first resolution; the finer search
        # follows if that fails too. Wider first: a kerbside gap of 2.5 car lengths took
        # 2 714 expansions finer and takes 652 wider; on the random sets, goal 96 with
        # reverse and start 61 forward get 6-14 m shorter paths (session 13).
        stages.append(_Stage("wide", config.widened(), ("rejected",), ("rejected",),
                             config.refine_share))  # fmt: skip
    fine = config
    for k in range(config.refinements):
        fine = fine.refined()
        # The first finer search also after a wide one that spent its share.
        after = (*_REFINE_ON, "expansions") if k == 0 else _REFINE_ON
        stages.append(_Stage("fine", fine, _REFINE_ON, after, config.refine_share))
    if config.persist and config.max_solutions < PERSIST_SOLUTIONS:
        # Every goal connection rejected at each resolution tried, with budget left: the
        # finest search once more, going on through the rejections until the budget
        # ends. A goal close to the start is met first by tight words whose steering
        # ramps fail; one tried from further along passes (a random map's goal 3.8 m
        # from the start: 16 + 16 connections rejected in 25 expansions by the first
        # search, every one by the wide and fine ones; this one solves it, 272 in all).
        # Its shots skip a cell and heading bin whose shots all failed, as the first
        # search's do (the finer one shoots every time): on the five random maps it
        # solved, the same paths in 0.68 of the time.
        persist = dataclasses.replace(
            fine, max_solutions=PERSIST_SOLUTIONS, shot_cell=config.shot_cell
        )
        stages.append(_Stage("persist", persist, ("rejected",), ("rejected",)))
    # The last resorts after the finer searches: a proof for paths keeping
    # body_clearance (a tighter path may exist), also after a finer search that spent
    # its share without one.
    if config.min_clearance < config.body_clearance:
        # The last resorts turn at the car's own full lock (tight_radius_factor), and
        # their steering ramps then have less room: more connections are rejected
        # before one fits (session 22: random goal 73 of seed 2, forward, needed over 16).
        if fine is not config:
            # First half-way, at the finest resolution: a kerbside gap of 1.4 car lengths
            # is proven out of reach at 0.15 m; its way in keeps 0.10 m, with short moves
            # (0.5 m steps) that the 0.5 m / 1 m steps of the last one do not take, and
            # 0.05 m there has every ramped connection cut a corner (session 13).
            between = 0.5 * (config.body_clearance + config.min_clearance)
            snug = dataclasses.replace(fine.tightened(), body_clearance=between)
            stages.append(_Stage("snug", snug, PROOFS, PROOFS, config.refine_share))
        # Also after a snug search whose every connection was rejected: its ramps cut
        # corners that 0.05 m less clearance may leave room for.
        after = (*PROOFS, "rejected", "expansions")
        last = fine is config
        share = 1.0 if last else config.refine_share
        tightest = config.tightened()
        stages.append(_Stage("tight", tightest, PROOFS, after, share))
        if not last:
            # Its proof holds on the first grid only: the finest once more keeping as
            # little (random goal 183 of seed 2 threads a gap keeping 0.058 m there).
            tightest = fine.tightened()
            stages.append(_Stage("tight", tightest, PROOFS, after))
        if config.wide_radius_factor > config.radius_factor:  # widening on, as for "wide"
            # Every connection of the tightest search rejected (the ramps of its full-lock
            # words cut a corner): once more turning wider. A goal in the middle of a
            # kerbside gap of 1.6 car lengths (1.29 m free each way) solves so, in about
            # 4 000 expansions; at 0.3 m from its end it solved before (an audit).
            ends = ("rejected", "expansions", *PROOFS)
            stages.append(_Stage("tight", tightest.widened(), ends, ("rejected",)))
    return tuple(stages)


def _wrapped(problem: PlanningProblem) -> PlanningProblem:
    """``problem`` with its start and goal yaw in ``[-pi, pi]`` (itself when they are).

    A start given as 2 pi was searched from cos and sin an ulp off 0's: nodes on cell
    edges changed bins and the plan changed (an audit). Yaws already in range are kept
    to the bit, as every plan before.
    """
    poses = {
        name: dataclasses.replace(pose, yaw=wrap_angle(pose.yaw))
        for name, pose in (("start", problem.start), ("goal", problem.goal))
        if abs(pose.yaw) > math.pi
    }
    return dataclasses.replace(problem, **poses) if poses else problem


def hybrid_query(
    problem: PlanningProblem,
    budget: Budget,
    watch: Stopwatch,
    config: HybridConfig,
    reverse: bool,
    smoothing: SmoothingConfig | None,
) -> HybridAnswer:
    """One Hybrid A* query from ``problem.start`` to ``problem.goal``.

    The first search may spend ``coarse_after`` of the budget; the searches of
    :func:`_ladder` follow it while there is no path and expansions are left: a
    coarser one (:meth:`HybridConfig.coarsened`) when the first spent its share;
    after every goal connection was rejected, a wider-turning one
    (``wide_radius_factor``) first; finer ones (:meth:`HybridConfig.refined`,
    ``config.refinements`` of them) after a search that ran out of states or had
    every goal connection rejected, each with ``refine_share`` of the rest when a
    later search may follow one that spent its share (else all of it); when those
    had every connection rejected too, the finest once more, going on through the
    rejections (``persist``); then, after a proof, the searches keeping less
    clearance and turning at the car's full lock (``tight_radius_factor``): the snug
    one half-way at the finest resolution, the tight one ``min_clearance`` at the
    first and then at the finest. All counted, so deterministic.

    Parameters
    ----------
    problem : PlanningProblem
        The query.
    budget : Budget
        ``max_iterations`` bounds the expansions of all searches together;
        ``max_time_s`` is only a cap.
    watch : Stopwatch
        The started stopwatch whose expiry stops the search.
    config : HybridConfig
        The search's settings (``switch_after``: when to turn to the goal's side;
        ``refinements``, ``coarse_after``, ``min_clearance``, ``wide_radius_factor``:
        the searches after the first).
    reverse : bool
        Whether reverse primitives and shots are allowed.
    smoothing : SmoothingConfig or None
        Its ``max_sharpness`` is the bound of ``curve="clothoid"``
        (:func:`~.resolution.sharpness_bound_of`); with ``curve="arcs"`` and ``smooth`` it is the
        per-segment post-processor; ``None``: the default bound, or exact arcs.

    Returns
    -------
    HybridAnswer
    """
    problem = _wrapped(problem)
    left = budget.max_iterations
    have = EndClearance(problem)
    # Each search tried: its settings, how it ended, and its share of the expansions
    # left when it was given one (None: all of them).
    tried: list[tuple[HybridConfig, SearchOutcome, int | None]] = []
    found: tuple[BuiltPath | None, SearchOutcome, tuple[Tree, ...]]

    @functools.cache
    def goal_in_pocket() -> bool:
        # Only where the goal sits in a pocket (less than ARRIVAL_POCKET_M behind it on
        # every steady steering) is the goal's side running out likely a proof off its
        # lattice too: a 15.2 m street's goal 30 m clear behind ran out after 405
        # expansions, before the start's side, whose shots solve it, had a turn (an audit).
        return (
            pocket_run(problem.checker, problem.goal, -1, problem.vehicle, ARRIVAL_POCKET_M)
            is not None
        )

    def run(cfg: HybridConfig, share: float) -> None:
        nonlocal left, found
        allowed = math.ceil(left * share) if share < 1.0 else left
        # After a search from the goal ran out of ways to arrive, the next one (another
        # grid or clearance) starts from the goal: where it runs out again it does so in a
        # few expansions, and the search from the start's first turn (400 expansions)
        # would be spent for nothing. The 13 random goals that fail forward on parking_lot
        # spent 2 000-2 500 expansions so over five searches, about 90 % of them from the
        # start (session 35).
        goal_first = bool(tried) and tried[-1][1].reason == "no_approach" and goal_in_pocket()
        found = search_at_resolution(
            problem, allowed, watch, cfg, reverse, smoothing, have, goal_first
        )
        tried.append((cfg, found[1], allowed if allowed < left else None))
        left -= found[1].expansions

    run(config, config.coarse_after if config.coarsens else 1.0)
    first, stage, cfg = tried[0][1].reason, "first", config
    ladder = [s for s in _ladder(config) if first in s.after_first]
    for i, st in enumerate(ladder):
        ended = found[1].reason
        if found[0] is not None or left <= 0 or watch.expired() or ended not in st.after_last:
            continue
        # A share holds back expansions only for a later search that may follow one
        # that spent its share; with none left, this one gets them all (session 22).
        later = any("expansions" in s.after_last for s in ladder[i + 1 :])
        cfg, stage = st.config, st.name
        run(cfg, st.share if later else 1.0)
    # After a first search cut short at its share, nothing the later ones find out is a
    # proof: the first resolution's search did not finish.
    coarse_branch = first == "expansions" and len(tried) > 1
    # After a proof (every search finished), once more from the ends nudged by a
    # fraction of a degree where that opens their straight drive out (:mod:`.nudge`).
    nudged = None  # that search's (path, outcome, trees), when it ran
    nudge_note = ""
    proven = found[0] is None and found[1].reason in PROOFS and not coarse_branch
    if proven and config.nudge_ends and left > 0 and not watch.expired():
        moved = _nudged(problem, cfg, reverse, have)
        if moved is not None:
            query, ends, nudge_note = moved
            goal_first = found[1].reason == "no_approach" and goal_in_pocket()
            nudged = search_at_resolution(
                query, left, watch, cfg, reverse, smoothing, have, goal_first, ends
            )
    nudge_solved = nudged is not None and nudged[0] is not None
    path, outcome, trees = nudged if nudge_solved else found
    reason = outcome.reason
    usual = query_clearance(problem, config.body_clearance, have)
    clearance = query_clearance(problem, cfg.body_clearance, have)

    def how_of(c: HybridConfig) -> str:
        """How a last-resort search differed from the others, for the messages."""
        r = c.radius_factor / problem.vehicle.kappa_max
        wider = f"turning with radius {r:.1f} m ({c.radius_factor:g} x the car's tightest)"
        if c.body_clearance < config.body_clearance:
            keeps = query_clearance(problem, c.body_clearance, have)
            tail = f", {wider}" if c.radius_factor > config.radius_factor else ""
            return f"keeping only {keeps:.2f} m body clearance{tail}"
        if c.radius_factor > config.radius_factor:
            return wider
        if c.max_solutions > config.max_solutions:
            return "going on through rejected connections"
        return ""

    # The searches at the usual clearance and radius come first; the last resorts follow.
    usual_count = max(k + 1 for k, (c, _, _) in enumerate(tried) if not how_of(c) or k == 0)
    base = tried[usual_count - 1][1].reason
    if coarse_branch and path is None and reason in _REFINE_ON:
        reason = "expansions"
    if (
        stage in _SNUGGER
        and not coarse_branch
        and path is None
        and reason != "time"
        and (reason not in PROOFS or base not in PROOFS)
    ):
        # Cut short keeping less clearance, a proof for the usual clearance stands; a
        # finer search cut short by its share proved nothing.
        reason = base if base in PROOFS else "expansions"
        clearance = usual
    if stage == "wide" and path is None and reason != "time":
        # Wider turns prove nothing about the car's own: the rejections stand.
        reason = "rejected"
    if coarse_branch and path is None:
        clearance = usual  # what the failure speaks of: the usual clearance
    outcomes = [o for _, o, _ in tried] + ([] if nudged is None else [nudged[1]])
    total = SearchOutcome.total(reason, outcomes)
    earlier = tried[:-1]
    answer = functools.partial(
        HybridAnswer, outcome=total, trees=trees,
        refinements=sum(c.xy_resolution < config.xy_resolution and not how_of(c)
                        for c, _, _ in tried),
        stage=stage, clearance=clearance,
    )  # fmt: skip
    how = how_of(cfg) if stage in (*_SNUGGER, "wide", "persist") else ""
    if path is not None:
        note = (f" {how}" if how else "") + nudge_note
        if stage in _SNUGGER and base in PROOFS and not coarse_branch:
            note += f" (none keeps {usual:.2f} m)"
        if earlier:
            note += f" at {_resolution(cfg)} resolution ({_earlier_note(earlier, how_of)})"
        return answer(path=path, message="", note=note)
    if coarse_branch:
        steps = [
            f"at {_resolution(c)} / {c.step:g} m steps"
            + (f" {how_of(c)}" if k > 0 and how_of(c) else "")
            + f" {'the search' if k == 0 else 'it'} {_why(o, 'its share of ' if a else '')}"
            for k, (c, o, a) in enumerate(tried)
        ]
        lead_in = (
            f"no path found: the wall-clock cap of {budget.max_time_s:g} s was hit before the "
            f"expansion budget of {budget.max_iterations}"
            if reason == "time"
            else f"no path found within the expansion budget of {budget.max_iterations}"
        )
        unused = budget.max_iterations - total.expansions
        tail = (
            "a larger budget may find a path"
            if reason == "time" or unused <= 0
            # The coarser searches ran out of states early: the rest went unspent, and
            # only the first search's share grows with the budget.
            else f"{unused} expansions went unspent: the first search may spend "
            f"{config.coarse_after:.0%} of the budget, so a larger one lets it search longer"
        )
        message = (
            f"{lead_in}: " + ", then ".join(steps)
            + f" (a coarser search proves nothing; {tail})"
        )
        return answer(path=None, message=message)
    # Lead with the finest resolution's ending at the usual clearance and radius.
    lead_cfg, lead_outcome, allowed = tried[usual_count - 1]
    message = _failure_message(lead_outcome, lead_cfg, budget, reverse, allowed)
    if lead_outcome.reason == "rejected" and smoothing is not None:
        message += slow_steering_note(smoothing)  # when a slow actuator is why
    if usual_count > 1:
        message += f"; {_earlier_note(tried[: usual_count - 1], how_of)}"
    for k in range(usual_count, len(tried)):
        c, o, _ = tried[k]
        snug = c.body_clearance < config.body_clearance
        too = " too" if snug and o.reason in PROOFS and tried[k - 1][1].reason in PROOFS else ""
        message += f"; {how_of(c)}, at {_resolution(c)} the search {_why(o, '')}{too}"
    if nudged is not None:  # it ran and found none
        message += f"; once more{nudge_note}, it {_why(nudged[1], '')}"
    return answer(path=None, message=message)


def _nudged(
    problem: PlanningProblem, cfg: HybridConfig, reverse: bool, have: EndClearance
) -> tuple[PlanningProblem, tuple[Piece | None, Piece | None], str] | None:
    """The query between nudged ends, the arcs to drive at them, and a note; or None."""
    body = body_test(problem.checker, query_clearance(problem, cfg.body_clearance, have))
    gears = (1, -1) if reverse else (1,)
    kappa_max = problem.vehicle.kappa_max
    found = [
        nudge(end, at_goal, gears, body, kappa_max, cfg.step, cfg.check_spacing)
        for end, at_goal in ((problem.start, False), (problem.goal, True))
    ]
    if found == [None, None]:
        return None
    pairs = list(zip(found, (problem.start, problem.goal), ("start", "goal"), strict=True))
    start, goal = (n.pose if n is not None else end for n, end, _ in pairs)
    words = [
        f"the {name}'s heading turned {math.degrees(abs(n.pose.yaw - end.yaw)):.2f} deg"
        for n, end, name in pairs
        if n is not None
    ]
    ends = (found[0].piece if found[0] else None, found[1].piece if found[1] else None)
    query = dataclasses.replace(problem, start=start, goal=goal)
    return query, ends, f", with {' and '.join(words)} over {cfg.step:g} m"


#: Search endings that a finer search is tried after (budget left, no path).
_REFINE_ON = ("exhausted", "no_approach", "rejected")



def _resolution(cfg: HybridConfig) -> str:
    return f"{cfg.xy_resolution:g} m / {np.degrees(cfg.yaw_resolution):g} deg"


def _earlier_note(
    earlier: Sequence[tuple[HybridConfig, SearchOutcome, int | None]],
    how_of: Callable[[HybridConfig], str] = lambda c: "",
) -> str:
    """What the searches before the last one ended with, for a message.

    ``how_of(config)``: how a last-resort search differed ('' for the others).
    """
    parts = [
        f"at {_resolution(c)} / {c.step:g} m steps"
        + (f" {how_of(c)}" if how_of(c) else "")
        + f" the search {_why(o, 'its share of ')}"
        for c, o, _ in earlier
    ]
    return "before that, " + "; ".join(parts)


def _why(outcome: SearchOutcome, share: str) -> str:
    """How a search ended, for a message.

    Examples
    --------
    >>> _why(SearchOutcome("expansions", 10, 0, 0, 0), "its share of ")
    'spent its share of 10 expansions'
    >>> _why(SearchOutcome("exhausted", 7, 0, 0, 0), "")
    'ran out of states after 7 expansions'
    """
    if outcome.reason == "expansions":
        return f"spent {share}{counted(outcome.expansions, 'expansions')}"
    ending = _ENDINGS.get(outcome.reason, outcome.reason)
    return f"{ending} after {counted(outcome.expansions, 'expansions')}"


#: How a search that did not spend its budget ended, in words.
_ENDINGS = {
    "exhausted": "ran out of states",
    "no_approach": "ran out of ways to arrive at the goal",
    "rejected": "had every goal connection rejected",
    "time": "was stopped by the wall-clock cap",
}


