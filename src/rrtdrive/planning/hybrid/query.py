"""One Hybrid A* query: set-up, the search from the start and, if needed, from the goal.

:func:`hybrid_query` runs on a started stopwatch and returns a
:class:`HybridAnswer`. It searches from the start for ``switch_after``
expansions; a query still open then is searched from the goal back towards the
start for the rest of the budget, and the path found is driven in the opposite
direction of time (rows reversed, gears flipped: with reverse allowed every
motion reversed in time is a motion; forward only, the search from the goal
uses reverse arcs alone, so its reversal drives forward). Many queries are hard
at one end only (a tight bay, a start against a wall): from the other end the
hard part is a way out. The search from the goal that runs out of states
proves the goal unreachable at the search's resolution.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from rrtdrive.planning.base import PlanningProblem, Stopwatch
from rrtdrive.planning.dubins import dubins_paths
from rrtdrive.planning.hybrid.body import BodyTest
from rrtdrive.planning.hybrid.config import HybridConfig
from rrtdrive.planning.hybrid.heuristic import (
    DubinsTable,
    FreeCellGraph,
    Heuristic,
    HolonomicField,
)
from rrtdrive.planning.hybrid.path import BuiltPath, Ramps, build_path
from rrtdrive.planning.hybrid.primitives import PrimitiveSet, primitive_sets
from rrtdrive.planning.hybrid.search import (
    HybridSearch,
    Piece,
    SearchOutcome,
    Shots,
    analytic_shots,
    walk_hits,
)
from rrtdrive.planning.reeds_shepp import reeds_shepp_distance
from rrtdrive.planning.smoothing import STEER_RATE_DESIGN_SPEED, SmoothingConfig
from rrtdrive.types import Budget, Pose, Tree

__all__ = [
    "HybridAnswer",
    "hybrid_query",
    "free_cell_graph",
    "dubins_table",
    "query_clearance",
    "reversed_in_time",
    "sharpness_bound_of",
]


def sharpness_bound_of(problem: PlanningProblem, smoothing: SmoothingConfig | None) -> float:
    """The query's sharpness bound, rad/m, as the improved planner's.

    ``smoothing.max_sharpness`` (0.2 rad/m without one), or the car's
    ``max_steer_rate / 2 m/s`` when smaller.
    """
    bound = smoothing.max_sharpness if smoothing is not None else SmoothingConfig().max_sharpness
    rate = problem.vehicle.max_steer_rate
    if rate is not None and rate < float("inf"):
        bound = min(bound, rate / STEER_RATE_DESIGN_SPEED)
    return bound


#: ``accept(pieces)``: the checked path of a connection, or ``None`` to search on.
Accept = Callable[[list[Piece]], BuiltPath | None]


def free_cell_graph(problem: PlanningProblem, resolution: float) -> FreeCellGraph:
    """The map's :class:`FreeCellGraph`, built once per map (timed as set-up)."""
    checker = problem.checker
    return checker.grid.derived(
        ("hybrid-free-cells", float(resolution)),
        lambda: FreeCellGraph.build(checker, resolution),
    )


@functools.lru_cache(maxsize=4)
def _dubins_table(radius: float, yaw_bins: int) -> DubinsTable:
    return DubinsTable.build(radius, yaw_bins=yaw_bins)


def dubins_table(radius: float, config: HybridConfig) -> DubinsTable:
    """The Dubins length table of a turning radius, built once per process."""
    return _dubins_table(float(radius), config.yaw_bins)


def reeds_shepp_to(goal: Pose, radius: float) -> Callable[[float, float, float], float]:
    """The Reeds-Shepp length from one pose to ``goal`` (the heuristic with reverse)."""

    def length(x: float, y: float, yaw: float) -> float:
        return reeds_shepp_distance(Pose(x, y, yaw), goal, radius)

    return length


def end_clearance(problem: PlanningProblem) -> float:
    """The exact body clearance of the query's start and goal poses, the smaller."""
    c = problem.checker
    return min(
        c.body_clearance(problem.start.as_tuple()), c.body_clearance(problem.goal.as_tuple())
    )


def query_clearance(problem: PlanningProblem, wanted: float, have: float | None = None) -> float:
    """``wanted``, capped at the exact body clearance the start and goal poses have.

    ``have``: that clearance (:func:`end_clearance`) when the caller has it already.
    """
    if wanted <= 0.0:
        return 0.0
    if have is None:
        have = end_clearance(problem)
    return max(0.0, min(wanted, have * 0.999))


@dataclass(frozen=True, eq=False)
class HybridAnswer:
    """What one query gave: the checked path (or ``None``), the outcome and a message.

    ``trees`` are the search trees of the last resolution tried, the one from the
    start first (the one from the goal second, when the query turned to it);
    ``refinements`` counts the finer searches run after the first, ``stage`` names
    the last search (``"first"``, ``"fine"`` (:attr:`HybridConfig.refinements`),
    ``"coarse"`` (:attr:`HybridConfig.coarse_after`), ``"tight"`` (``min_clearance``)
    or ``"wide"`` (``wide_radius_factor``)), ``clearance`` is the body clearance the
    last search kept (less than ``body_clearance`` after
    :attr:`HybridConfig.min_clearance`'s search), and ``note`` says, for a solved
    query, at which resolution and why (empty when the first search solved it).
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
    counts = f"{outcome.expansions} expansions, {outcome.nodes} nodes"
    if outcome.reason == "exhausted":
        return (
            f"no path at {res} resolution: the search ran out of states ({counts}); "
            "the goal is unreachable for this car at this resolution"
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
            f"no path found at {res} resolution within its share of {allowed} expansions "
            f"({counts})"
        )
    return f"no path found within the expansion budget of {budget.max_iterations} ({counts})"


def reversed_in_time(pieces: Sequence[Piece]) -> list[Piece]:
    """The same motion driven backwards in time: order and rows reversed, gears flipped.

    Examples
    --------
    >>> rows = np.array([[0.0, 0, 0, 0.1], [1.0, 0, 0, 0.1]])
    >>> out = reversed_in_time([Piece(1, rows)])
    >>> out[0].gear, out[0].rows[:, 0].tolist()
    (-1, [1.0, 0.0])
    """
    return [Piece(-p.gear, p.rows[::-1].copy()) for p in reversed(pieces)]


def _backward_dubins_shots(
    target: Pose, radius: float, spacing: float, body: BodyTest, max_candidates: int = 3
) -> Shots:
    """Reverse-only shots from a pose to ``target``: forward Dubins ``target -> pose`` reversed."""
    coarse = max(spacing, 0.5)

    def shots(pose: Pose) -> list[list[Piece]]:
        out = []
        for cand in dubins_paths(target, pose, radius)[:max_candidates]:
            if walk_hits(target, cand.word, cand.lengths, radius, coarse, body):
                continue
            rows = cand.sample(spacing)[::-1].copy()
            rows[0, :3] = pose.as_tuple()
            rows[-1, :3] = target.as_tuple()
            out.append([Piece(-1, rows)])
        return out

    return shots


def _tree(search: HybridSearch) -> Tree:
    xy = np.column_stack([search.x, search.y]) if search.x else np.zeros((0, 2))
    return Tree(xy, np.array(search.parent, dtype=np.int64))


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


def _ladder(config: HybridConfig) -> tuple[_Stage, ...]:
    """The searches that may follow the first one, in order (:func:`hybrid_query`).

    Examples
    --------
    >>> [(s.name, s.config.xy_resolution, s.share) for s in _ladder(HybridConfig())]
    [('coarse', 2.0, 1.0), ('fine', 0.25, 0.5), ('tight', 0.5, 1.0), ('wide', 0.5, 1.0)]
    """
    stages = []
    if config.coarsens:
        # The first search spent its share, not out of states: the rest goes to a coarser one.
        stages.append(_Stage("coarse", config.coarsened(), ("expansions",), ("expansions",)))
    fine = config
    for _ in range(config.refinements):
        fine = fine.refined()
        stages.append(_Stage("fine", fine, _REFINE_ON, _REFINE_ON, config.refine_share))
    # The last resorts, at the first resolution, after the finer searches: a proof for
    # paths keeping body_clearance (a tighter path may exist), or every connection
    # rejected (the ramps of full-lock words need steering room: turn a little wider);
    # also after a finer search that spent its share without either.
    if config.min_clearance < config.body_clearance:
        stages.append(_Stage("tight", config.tightened(), _PROOFS, (*_PROOFS, "expansions")))
    if config.wide_radius_factor > config.radius_factor:
        stages.append(_Stage("wide", config.widened(), ("rejected",), ("rejected", "expansions")))
    return tuple(stages)


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
    else finer ones (:meth:`HybridConfig.refined`, ``config.refinements`` of them)
    after a search that ran out of states or had every goal connection rejected,
    each with ``refine_share`` of the rest when a last resort may follow, then the
    last resort: the tight search (``min_clearance``) after a proof, or the wide one
    (``wide_radius_factor``) after rejected connections. All counted, so
    deterministic.

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
        (:func:`sharpness_bound_of`); with ``curve="arcs"`` and ``smooth`` it is the
        per-segment post-processor; ``None``: the default bound, or exact arcs.

    Returns
    -------
    HybridAnswer
    """
    left = budget.max_iterations
    have = end_clearance(problem)
    # Each search tried: its settings, how it ended, and its share of the expansions
    # left when it was given one (None: all of them).
    tried: list[tuple[HybridConfig, SearchOutcome, int | None]] = []
    found: tuple[BuiltPath | None, SearchOutcome, tuple[Tree, ...]]

    def run(cfg: HybridConfig, share: float) -> None:
        nonlocal left, found
        allowed = math.ceil(left * share) if share < 1.0 else left
        found = _query_at(problem, allowed, watch, cfg, reverse, smoothing, have)
        tried.append((cfg, found[1], allowed if allowed < left else None))
        left -= found[1].expansions

    run(config, config.coarse_after if config.coarsens else 1.0)
    first, stage, cfg = tried[0][1].reason, "first", config
    ladder = [s for s in _ladder(config) if first in s.after_first]
    for i, st in enumerate(ladder):
        ended = found[1].reason
        if found[0] is not None or left <= 0 or watch.expired() or ended not in st.after_last:
            continue
        later = i + 1 < len(ladder)
        cfg, stage = st.config, st.name
        run(cfg, st.share if later else 1.0)
    path, outcome, trees = found
    reason = outcome.reason
    usual = query_clearance(problem, config.body_clearance, have)
    kept = clearance = query_clearance(problem, cfg.body_clearance, have)
    before = tried[-2][1].reason if len(tried) > 1 else ""
    if stage == "coarse" and path is None and reason in _REFINE_ON:
        # What the coarse search cannot do proves nothing: the finer one was cut short.
        reason = "expansions"
    if (
        stage == "tight"
        and path is None
        and reason != "time"
        and (reason not in _PROOFS or before not in _PROOFS)
    ):
        # Cut short keeping less clearance, a proof for the usual clearance stands; a
        # finer search cut short by its share proved nothing.
        reason = before if before in _PROOFS else "expansions"
        clearance = usual
    if stage == "wide" and path is None and reason != "time":
        # Wider turns prove nothing about the car's own: the rejections stand.
        reason = "rejected"
    total = SearchOutcome.total(reason, [o for _, o, _ in tried])
    earlier = tried[:-1]
    answer = functools.partial(
        HybridAnswer, outcome=total, trees=trees,
        refinements=sum(c.xy_resolution < config.xy_resolution for c, _, _ in tried),
        stage=stage, clearance=clearance,
    )  # fmt: skip
    # How the last-resort search differed from the others, for its messages.
    how = {
        "tight": f"keeping only {kept:.2f} m body clearance",
        "wide": f"turning with radius {cfg.radius_factor:g} / kappa_max",
    }.get(stage, "")
    if path is not None:
        note = f" {how}" if how else ""
        if stage == "tight" and before in _PROOFS:
            note += f" (none keeps {usual:.2f} m)"
        if earlier:
            note += f" at {_resolution(cfg)} resolution ({_earlier_note(earlier)})"
        return answer(path=path, message="", note=note)
    if stage == "coarse":
        first_cfg, first_outcome, _ = tried[0]
        message = (
            f"no path found within the expansion budget of {budget.max_iterations}: at "
            f"{_resolution(first_cfg)} / {first_cfg.step:g} m steps the search "
            f"{_why(first_outcome, 'its share of ')}, then at {_resolution(cfg)} / "
            f"{cfg.step:g} m steps it {_why(outcome, '')} (a coarse search proves nothing; "
            "a larger budget may find a path)"
        )
        return answer(path=None, message=message)
    lead, earlier = tried[-1], tried[:-1]
    if how:
        # Lead with the finest resolution's ending at the usual clearance and radius.
        lead, earlier = tried[-2], tried[:-2]
    lead_cfg, lead_outcome, allowed = lead
    message = _failure_message(lead_outcome, lead_cfg, budget, reverse, allowed)
    if earlier:
        message += f"; {_earlier_note(earlier)}"
    if how:
        too = " too" if stage == "tight" and outcome.reason in _PROOFS and before in _PROOFS else ""
        message += f"; {how}, at {_resolution(cfg)} the search {_why(outcome, '')}{too}"
    return answer(path=None, message=message)


#: Search endings that a finer search is tried after (budget left, no path).
_REFINE_ON = ("exhausted", "no_approach", "rejected")

#: Search endings that prove the query unreachable for the search's clearance and grid.
_PROOFS = ("exhausted", "no_approach")


def _resolution(cfg: HybridConfig) -> str:
    return f"{cfg.xy_resolution:g} m / {np.degrees(cfg.yaw_resolution):g} deg"


def _earlier_note(earlier: Sequence[tuple[HybridConfig, SearchOutcome, int | None]]) -> str:
    """What the searches before the last one ended with, for a message."""
    parts = [
        f"at {_resolution(c)} / {c.step:g} m steps the search {_why(o, 'its share of ')}"
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
        return f"spent {share}{outcome.expansions} expansions"
    ending = _ENDINGS.get(outcome.reason, outcome.reason)
    return f"{ending} after {outcome.expansions} expansions"


#: How a search that did not spend its budget ended, in words.
_ENDINGS = {
    "exhausted": "ran out of states",
    "no_approach": "ran out of ways to arrive at the goal",
    "rejected": "had every goal connection rejected",
    "time": "was stopped by the wall-clock cap",
}


def _query_at(
    problem: PlanningProblem,
    budget: int,
    watch: Stopwatch,
    config: HybridConfig,
    reverse: bool,
    smoothing: SmoothingConfig | None,
    have: float,
) -> tuple[BuiltPath | None, SearchOutcome, tuple[Tree, ...]]:
    """The searches of :func:`hybrid_query` at one resolution, with ``budget`` expansions.

    ``have``: the start's and goal's own body clearance (:func:`end_clearance`).
    """
    kappa_max = problem.vehicle.kappa_max
    clearance = query_clearance(problem, config.body_clearance, have)
    if smoothing is not None:
        smoothing = dataclasses.replace(smoothing, clearance=clearance, kappa_max=kappa_max)
    radius = config.radius_factor / kappa_max
    # The returned rows interpolate linearly between arc poses 0.25 m apart (at most
    # 1.3 mm off the arc at kappa_max): the re-check allows 5 mm less than the search kept,
    # so that it does not reject what the search found. The start and goal poses have
    # at least the search's clearance (capped at theirs), never more is asked of them.
    recheck_clearance = max(0.0, clearance - 0.005)
    start, goal = problem.start, problem.goal
    grid = free_cell_graph(problem, config.xy_resolution)
    prims, *long_prims = primitive_sets(
        1.0 / radius, config.curvatures, config.step, config.check_spacing, 0 if reverse else 1,
        config.long_steps,
    )  # fmt: skip

    ramps = None
    if config.curve == "clothoid":
        bound = sharpness_bound_of(problem, smoothing)
        ramps = Ramps(bound, problem.vehicle.wheelbase, kappa_max)
    post = smoothing if config.smooth and ramps is None else None

    def accept(pieces: list[Piece]) -> BuiltPath | None:
        return build_path(
            pieces, problem.checker, post, config.arc_fallback, recheck_clearance, kappa_max,
            config.check_spacing, config.sample_spacing, ramps=ramps,
        )  # fmt: skip

    to_goal = HolonomicField.towards(grid, goal)
    if reverse:
        rs = reeds_shepp_to(goal, radius) if config.reeds_shepp_heuristic else None
        heuristic = Heuristic(to_goal, None, goal, rs)
    else:
        table = dubins_table(radius, config)
        heuristic = Heuristic(to_goal, table.to(goal), goal, table.scalar_to(goal))
    back_h = Heuristic(HolonomicField.towards(grid, start), None, start)

    def searches_with(search_clearance: float) -> list[tuple[HybridSearch, Accept]]:
        body = BodyTest(problem.checker, search_clearance)
        shots = analytic_shots(goal, radius, reverse, config.check_spacing, body)
        ahead = HybridSearch(
            body, start, goal, heuristic, prims, shots, config, kappa_max, problem.bounds,
            long_prims,
        )  # fmt: skip
        out: list[tuple[HybridSearch, Accept]] = [(ahead, accept)]
        if config.switch_after > 0:
            # From the goal back to the start: forward only, by reverse arcs alone.
            back_prims, *back_long = (
                (prims, *long_prims) if reverse else prims_reverse(radius, config)
            )
            if reverse:
                back_shots = analytic_shots(start, radius, True, config.check_spacing, body)
            else:
                back_shots = _backward_dubins_shots(start, radius, config.check_spacing, body)
            back = HybridSearch(
                body, goal, start, back_h, back_prims, back_shots, config, kappa_max,
                problem.bounds, back_long,
            )  # fmt: skip
            out.append((back, lambda p: accept(reversed_in_time(p))))
            if config.meet_count > 0:

                def connect(a: Pose, b: Pose) -> list[list[Piece]]:
                    words = analytic_shots(b, radius, reverse, config.check_spacing, body)(a)
                    return [
                        w for w in words if body.all_free(np.vstack([p.rows[:, :3] for p in w]))
                    ]

                for here, there in ((ahead, back), (back, ahead)):
                    here.meet = _Meeting(
                        here, there, ahead, connect, radius, config.meet_distance,
                        config.meet_count,
                    )  # fmt: skip
        return out

    # The ramps cut corners by centimetres: where every connection the search finds
    # is rejected for it (max_solutions of them), search again, with the rest of the
    # budget, keeping ``ramp_margin`` more clearance (the re-check is unchanged).
    margins = (0.0, config.ramp_margin) if ramps is not None and config.ramp_margin > 0 else (0.0,)
    used = SearchOutcome("expansions", 0, 0, 0, 0)
    searches: list[tuple[HybridSearch, Accept]] = []
    for margin in margins:
        search_clearance = clearance if margin == 0.0 else query_clearance(
            problem, config.body_clearance + margin, have
        )
        searches = searches_with(search_clearance)
        left = budget - used.expansions
        path, outcome = _alternate(searches, left, config.switch_after, watch)
        reason = outcome.reason
        if margin > 0.0 and reason in _PROOFS:
            # Out of states keeping the margin too proves nothing for the query's own
            # clearance: the rejected connections stand.
            reason = "rejected"
        used = SearchOutcome.total(reason, [used, outcome])
        if path is not None or outcome.reason != "rejected" or left - outcome.expansions <= 0:
            break
    trees = tuple(_tree(s) for s, _ in searches if s.x)
    return path, used, trees


class _Meeting:
    """Connections from one search's nodes to the nodes of the other (meet in the middle).

    The search from the start (``ahead``) and the one from the goal (``back``, whose
    tree reversed in time drives to the goal) take turns; while one runs, the other's
    tree stands still. At its analytic-shot times, a node of the running search tries
    the shortest clear words (Reeds-Shepp with reverse, Dubins forward) to the
    ``count`` nodes of the other tree within ``distance`` whose pose is closest
    (distance plus the turning radius times the heading change); a clear one joins
    both trees: the start's chain, the word, the goal's chain reversed in time.
    """

    def __init__(
        self,
        here: HybridSearch,
        there: HybridSearch,
        ahead: HybridSearch,
        connect: Callable[[Pose, Pose], list[list[Piece]]],
        radius: float,
        distance: float,
        count: int,
    ) -> None:
        self.here, self.there, self.ahead = here, there, ahead
        self.connect, self.radius, self.distance, self.count = connect, radius, distance, count
        self._tree: cKDTree | None = None
        self._size = -1

    def refresh(self) -> None:
        """Index the other tree's nodes (it stands still while this search runs)."""
        there = self.there
        if len(there.x) != self._size:
            self._size = len(there.x)
            self._tree = cKDTree(np.column_stack([there.x, there.y])) if there.x else None

    def __call__(self, i: int) -> list[list[Piece]]:
        if self._tree is None:
            return []
        here, there = self.here, self.there
        x, y, yaw = here.x[i], here.y[i], here.yaw[i]
        near = self._tree.query_ball_point((x, y), self.distance)
        if not near:
            return []
        # The likeliest shortest words first: near in position and heading.
        scored = sorted(
            (math.hypot(there.x[j] - x, there.y[j] - y)
             + self.radius * abs(math.remainder(there.yaw[j] - yaw, 2.0 * math.pi)), j)
            for j in near
        )  # fmt: skip
        out: list[list[Piece]] = []
        for _, j in scored[: self.count]:
            a, b = (i, j) if here is self.ahead else (j, i)
            start_side, goal_side = (here, there) if here is self.ahead else (there, here)
            pa = Pose(start_side.x[a], start_side.y[a], start_side.yaw[a])
            pb = Pose(goal_side.x[b], goal_side.y[b], goal_side.yaw[b])
            for word in self.connect(pa, pb):
                whole = start_side.chain(a) + word + reversed_in_time(goal_side.chain(b))
                out.append(whole if here is self.ahead else reversed_in_time(whole))
        return out


def _alternate(
    searches: list[tuple[HybridSearch, Accept]],
    budget: int,
    first: int,
    watch: Stopwatch,
) -> tuple[BuiltPath | None, SearchOutcome]:
    """Run the searches in turns of ``first``, ``first``, ``2 first``, ``2 first``, ... expansions.

    The turns are counted in expansions, never in time, so the schedule is the
    same on any machine. Either search running out of states ends the query: from
    the start it proves the goal unreachable, from the goal that no approach exists.
    """
    outcomes = [SearchOutcome("expansions", 0, 0, 0, 0) for _ in searches]
    turn, used, k = max(1, first), 0, 0
    while True:
        search, accept = searches[k]
        if len(searches) == 1:
            turn = budget
        step = min(turn, budget - used)
        before = outcomes[k].expansions
        meeting = search.meet
        if isinstance(meeting, _Meeting):
            meeting.refresh()
        path, outcomes[k] = search.run(accept, before + step, watch.expired)
        used += outcomes[k].expansions - before
        if path is not None or outcomes[k].reason != "expansions" or used >= budget:
            break
        if k == len(searches) - 1:
            turn *= 2
        k = (k + 1) % len(searches)
    if len(searches) == 1:
        return path, outcomes[0]
    reason = outcomes[k].reason
    if reason == "exhausted" and k == 1:
        reason = "no_approach"  # exhausted from the goal's side
    return path, SearchOutcome.total(reason, outcomes)


def prims_reverse(radius: float, config: HybridConfig) -> tuple[PrimitiveSet, ...]:
    """The reverse arcs alone (the search from the goal of a forward-only query), and longer."""
    return primitive_sets(
        1.0 / radius, config.curvatures, config.step, config.check_spacing, -1, config.long_steps
    )
