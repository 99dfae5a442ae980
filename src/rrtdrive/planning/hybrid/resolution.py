"""The searches of one Hybrid A* query at one resolution (:func:`search_at_resolution`).

The search from the start runs for ``switch_after`` expansions; a query still
open then is searched from the goal back towards the start too, the two taking
turns (:func:`~.schedule.alternate`), and a path found from the goal is driven in the
opposite direction of time (:func:`reversed_in_time`: rows reversed, gears
flipped; with reverse allowed every motion reversed in time is a motion; forward
only, the search from the goal uses reverse arcs alone, so its reversal drives
forward). Many queries are hard at one end only (a tight bay, a start against a
wall): from the other end the hard part is a way out. The search from the goal
that runs out of states proves the goal unreachable at the search's resolution, on its
own lattice (for a goal in a pocket the ladder's next search then gives it the first turn:
``goal_first``). Where every
connection found is rejected (the ramps cut a corner), the searches run again keeping
``ramp_margin`` more clearance. Also here: the per-map set-up
the searches share (:func:`free_cell_graph`, :func:`dubins_table`) and the
query's clearance.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Callable, Iterator, Sequence

import numpy as np

from rrtdrive.collision import CollisionChecker
from rrtdrive.geometry import wrap_angle
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
from rrtdrive.planning.hybrid.lattice import guided, heading_lattice
from rrtdrive.planning.hybrid.leads import Lead, lead_ins
from rrtdrive.planning.hybrid.path import BuiltPath, Ramps, SegmentMemo, build_path
from rrtdrive.planning.hybrid.primitives import PrimitiveSet, primitive_sets
from rrtdrive.planning.hybrid.schedule import Accept, Turn, alternate
from rrtdrive.planning.hybrid.search import (
    HybridSearch,
    Piece,
    SearchOutcome,
    Shots,
    analytic_shots,
    walks_hit,
)
from rrtdrive.planning.hybrid.shortcut import drop_end_stubs, polyline_length, shortcut
from rrtdrive.planning.hybrid.shots import SHOT_CUSP_COST_M
from rrtdrive.planning.hybrid.turn import TurnResult, abreast, multi_point_turn
from rrtdrive.planning.reeds_shepp import reeds_shepp_distance
from rrtdrive.planning.smoothing import SmoothingConfig
from rrtdrive.planning.smoothing.config import sharpness_bound, smoothing_for_car
from rrtdrive.types import Pose, Tree, VehicleParams
from rrtdrive.vehicle import cover_discs

__all__ = [
    "PROOFS",
    "Accept",
    "approach_blocked",
    "dubins_table",
    "EndClearance",
    "field_clearance",
    "free_cell_graph",
    "prims_reverse",
    "query_clearance",
    "reeds_shepp_to",
    "reversed_in_time",
    "search_at_resolution",
    "sharpness_bound_of",
]

#: Search endings that prove the query unreachable for the search's clearance and grid.
PROOFS = ("exhausted", "no_approach")


def sharpness_bound_of(problem: PlanningProblem, smoothing: SmoothingConfig | None) -> float:
    """The query's sharpness bound, rad/m, as the improved planner's.

    ``smoothing.max_sharpness`` (0.2 rad/m without one), or the car's
    ``max_steer_rate / 2 m/s`` when smaller.
    """
    configured = (smoothing or SmoothingConfig()).max_sharpness
    return sharpness_bound(configured, problem.vehicle.max_steer_rate)




def _after(first: Piece, accept: Accept) -> Accept:
    """``accept`` of the pieces with ``first`` driven before them."""
    return lambda pieces: accept([first, *pieces])




def free_cell_graph(problem: PlanningProblem, resolution: float) -> FreeCellGraph:
    """The map's :class:`FreeCellGraph`, built once per map (timed as set-up).

    Parameters
    ----------
    problem : PlanningProblem
        Its checker's grid keeps the graph.
    resolution : float
        Coarse cell size asked for, metres (rounded to a multiple of the checker's).

    Returns
    -------
    FreeCellGraph
    """
    checker = problem.checker
    return checker.grid.derived(
        ("hybrid-free-cells", float(resolution)),
        lambda: FreeCellGraph.build(checker, resolution),
    )


#: Dubins tables kept per process. The default ladder asks for 8 (radius, bins) pairs:
#: with room for 4, a query that climbed it rebuilt 3 of them, 0.1 s each (session 22).
DUBINS_TABLES = 16


@functools.lru_cache(maxsize=DUBINS_TABLES)
def _dubins_table(radius: float, yaw_bins: int) -> DubinsTable:
    table = DubinsTable.build(radius, yaw_bins=yaw_bins)
    table.lengths.setflags(write=False)  # shared by every later query: a write would leak
    return table


#: Most heading bins of a Dubins table (1 degree): a search's bins can be finer, its
#: table need not (61 x 61 x 360 lengths; at 0.01 degree it would take gigabytes).
MAX_TABLE_BINS = 360


def dubins_table(radius: float, config: HybridConfig) -> DubinsTable:
    """The Dubins length table of a turning radius, built once per process."""
    return _dubins_table(float(radius), min(config.yaw_bins, MAX_TABLE_BINS))


#: Body tests kept per map (the last few clearances asked for).
BODY_TESTS = 8
#: A goal facing more than this (degrees) away from the start's heading turns the car
#: round: a turn stuck at the start is then tried further along (``abreast_turns``).
TURN_ROUND_DEG = 100.0
#: With a start boxed in (it has straight lead-ins), or a goal whose straight forward
#: approach is blocked (:func:`approach_blocked`), the search from the goal starts after
#: ``switch_after / BOXED_START_SOONER`` expansions from the start.
BOXED_START_SOONER = 4
#: The straight forward approach into the goal tested by :func:`approach_blocked` (metres).
APPROACH_PROBE = 1.0


def body_test(checker: CollisionChecker, clearance: float) -> BodyTest:
    """The map's :class:`BodyTest` keeping ``clearance``, made once for the last few clearances.

    A body test is immutable and depends on the map and the clearance alone; making
    one costs a query some 25 microseconds (most queries ask for the same clearance).
    """
    tests: dict[float, BodyTest] = checker.grid.derived(("hybrid-body-tests",), dict)
    key = float(clearance)
    test = tests.get(key)
    if test is None:
        test = tests[key] = BodyTest(checker, key)
        while len(tests) > BODY_TESTS:
            del tests[next(iter(tests))]  # the oldest made
    return test


def reeds_shepp_to(goal: Pose, radius: float) -> Callable[[float, float, float], float]:
    """The Reeds-Shepp length from one pose to ``goal`` (the heuristic with reverse)."""

    def length(x: float, y: float, yaw: float) -> float:
        return reeds_shepp_distance(Pose(x, y, yaw), goal, radius)

    return length


class EndClearance:
    """The smaller body clearance of the query's start and goal poses, exact only when needed.

    A clearance wanted of the search is capped at what the start and goal poses
    themselves have (:meth:`cap`). Most have more than any search wants, which the
    clearance field shows without the exact (shapely) distances: the three covering
    discs' centres have ``radius + d`` of room by the field's lower bound, so the
    body keeps ``d`` (:func:`field_clearance`). Only a cap that this bound cannot
    decide computes the exact value, once.
    """

    def __init__(self, problem: PlanningProblem) -> None:
        self._problem = problem
        self.bound = min(
            field_clearance(problem.checker, problem.start),
            field_clearance(problem.checker, problem.goal),
        )
        self._exact: float | None = None

    @property
    def exact(self) -> float:
        """The exact value: the smaller of the two poses' body clearances."""
        if self._exact is None:
            p = self._problem
            ends = (p.start.as_tuple(), p.goal.as_tuple())
            self._exact = min(p.checker.body_clearance(e) for e in ends)
        return self._exact

    def cap(self, wanted: float) -> float:
        """``wanted`` metres, capped at 0.999 of this clearance (0 for ``wanted <= 0``)."""
        if wanted <= 0.0:
            return 0.0
        if wanted <= self.bound * 0.999:  # then also <= exact * 0.999
            return wanted
        return max(0.0, min(wanted, self.exact * 0.999))


def field_clearance(checker: CollisionChecker, pose: Pose) -> float:
    """A lower bound of the body's clearance at ``pose`` from the clearance field.

    The three covering discs (:func:`~rrtdrive.vehicle.cover_discs`) contain the
    body; the field is a lower bound of the distance at their centres.
    """
    offsets, radius = _three_discs(checker.vehicle)
    c, s = math.cos(pose.yaw), math.sin(pose.yaw)
    return min(checker.clearance(pose.x + c * o, pose.y + s * o) for o in offsets) - radius


@functools.lru_cache(maxsize=16)
def _three_discs(vehicle: VehicleParams) -> tuple[tuple[float, ...], float]:
    """``cover_discs(vehicle, 3)``, the offsets as Python floats, made once per car.

    Each query's :class:`EndClearance` reads them twice; a float's products are the
    float64 scalar's.
    """
    offsets, radius = cover_discs(vehicle, 3)
    return tuple(offsets.tolist()), float(radius)


def query_clearance(
    problem: PlanningProblem, wanted: float, have: EndClearance | None = None
) -> float:
    """``wanted``, capped at the exact body clearance the start and goal poses have.

    ``have``: the query's :class:`EndClearance` when the caller has it already.
    """
    return (have if have is not None else EndClearance(problem)).cap(wanted)


def reversed_in_time(pieces: Sequence[Piece]) -> list[Piece]:
    """The same motion driven backwards in time: order and rows reversed, gears flipped.

    Parameters
    ----------
    pieces : sequence of Piece
        A motion's pieces in driving order (left unchanged).

    Returns
    -------
    list of Piece
        New pieces (rows copied; ``shot`` kept).

    Examples
    --------
    >>> rows = np.array([[0.0, 0, 0, 0.1], [1.0, 0, 0, 0.1]])
    >>> out = reversed_in_time([Piece(1, rows)])
    >>> out[0].gear, out[0].rows[:, 0].tolist()
    (-1, [1.0, 0.0])
    """
    return [Piece(-p.gear, p.rows[::-1].copy(), p.shot) for p in reversed(pieces)]


def _backward_dubins_shots(
    target: Pose, radius: float, spacing: float, body: BodyTest, max_candidates: int = 3
) -> Shots:
    """Reverse-only shots from a pose to ``target``: forward Dubins ``target -> pose`` reversed."""
    coarse = max(spacing, 0.5)

    def shots(pose: Pose) -> Iterator[list[Piece]]:
        # All words screened in one look-up (walks_hit: each word's walk_hits), as the
        # forward shots are: most shots screen every word (2.7 of 3 on bench_hybrid's
        # queries), one call costs little more than one word's. Each word is sampled only
        # when the caller asks (Shots).
        cands = dubins_paths(target, pose, radius)[:max_candidates]
        hit = walks_hit(target, [(c.word, c.lengths) for c in cands], radius, coarse, body)
        for cand, dropped in zip(cands, hit, strict=True):
            if dropped:
                continue
            rows = cand.sample(spacing)[::-1].copy()
            rows[0, :3] = pose.as_tuple()
            rows[-1, :3] = target.as_tuple()
            yield [Piece(-1, rows, True)]

    return shots


def _tree(search: HybridSearch) -> Tree:
    xy = np.column_stack([search.x, search.y]) if search.x else np.zeros((0, 2))
    return Tree(xy, np.array(search.parent, dtype=np.int64))


def search_at_resolution(
    problem: PlanningProblem,
    budget: int,
    watch: Stopwatch,
    config: HybridConfig,
    reverse: bool,
    smoothing: SmoothingConfig | None,
    have: EndClearance,
    goal_first: bool = False,
    ends: tuple[Piece | None, Piece | None] = (None, None),
) -> tuple[BuiltPath | None, SearchOutcome, tuple[Tree, ...]]:
    """The searches of :func:`hybrid_query` at one resolution, with ``budget`` expansions.

    ``have``: the start's and goal's own body clearance (:class:`EndClearance`).
    ``goal_first``: the search from the goal takes the first turn (:func:`~.schedule.alternate`).
    ``ends``: pieces driven before and after every path found (a nudged start's arc out
    of the query's start, a nudged goal's arc into its goal: :mod:`.nudge`).
    """
    kappa_max = problem.vehicle.kappa_max
    clearance = query_clearance(problem, config.body_clearance, have)
    radius = config.radius_factor / kappa_max
    # The re-check of the returned rows keeps the query's clearance itself, as the
    # improved planner's does: until session 34 it allowed 5 mm less (for rows off the
    # search's arcs by at most 1.3 mm), and ramped rows kept 0.148 m at a row and
    # 0.139 m between (a helper's fuzz, 4 of 621 paths). The start and goal poses have
    # at least the search's clearance (capped at theirs), never more is asked of them.
    recheck_clearance = clearance
    start, goal = problem.start, problem.goal
    with watch.setup():  # built once per map (per process for the table and primitives)
        grid = free_cell_graph(problem, config.xy_resolution)
        table = None if reverse else dubins_table(radius, config)
        prims, *long_prims = primitive_sets(
            1.0 / radius, config.curvatures, config.step, config.check_spacing,
            0 if reverse else 1, config.long_steps,
        )  # fmt: skip
        # From the goal back to the start: forward only, by reverse arcs alone.
        back_sets = (prims, *long_prims) if reverse else prims_reverse(radius, config)

    ramps = None
    if config.curve == "clothoid":
        bound = sharpness_bound_of(problem, smoothing)
        ramps = Ramps(bound, problem.vehicle.wheelbase, kappa_max, chunks=config.ramp_chunks)
    post = None
    if config.smooth and ramps is None and smoothing is not None:
        # The per-segment post-processor keeps the query's clearance and the car's
        # curvature limit, sharpness bound and wheelbase, as the improved planner's (the
        # car's steering rate was ignored; an audit). Built only where used.
        post = smoothing_for_car(smoothing, problem.vehicle, clearance=clearance)

    memo = SegmentMemo()

    before, after = ([p] if p is not None else [] for p in ends)

    def accept(pieces: list[Piece]) -> BuiltPath | None:
        return build_path(
            [*before, *pieces, *after], problem.checker, post, config.arc_fallback,
            recheck_clearance, kappa_max, config.check_spacing, config.sample_spacing,
            ramps=ramps, memo=memo,
        )  # fmt: skip

    to_goal = HolonomicField.towards(grid, goal)
    if reverse:
        rs = reeds_shepp_to(goal, radius) if config.reeds_shepp_heuristic else None
        heuristic = Heuristic(to_goal, None, goal, rs)
    else:
        assert table is not None
        heuristic = Heuristic(to_goal, table.to(goal), goal, table.scalar_to(goal))
    back_h = Heuristic(HolonomicField.towards(grid, start), None, start)

    def guide() -> tuple[Heuristic, Heuristic] | None:
        # A hard query: the lattice's cost to go (and from the start) guides both ways.
        with watch.setup():
            lattice = heading_lattice(problem.checker, problem.bounds, radius, reverse, config)
        to_goal_cost, from_start_cost = lattice.estimate(goal, True), lattice.estimate(start, False)
        if to_goal_cost is None or from_start_cost is None:
            return None
        return guided(heuristic, to_goal_cost), guided(back_h, from_start_cost)

    gears = (1, -1) if reverse else (1,)
    longest = 2.0 * problem.vehicle.length

    def leads_into(target: Pose, body: BodyTest) -> tuple[Lead, ...]:
        return lead_ins(
            target, body, 1.0 / radius, gears, config.check_spacing, longest, config.lead_ins
        )

    def turn_with(search_clearance: float) -> Turn | None:
        if not reverse or config.turn_moves <= 0 or config.switch_after <= 0:
            return None
        body = body_test(problem.checker, search_clearance)
        shots = analytic_shots(goal, radius, True, config.check_spacing, body)

        def finish(pose: Pose, pieces: list[Piece], allowed: int) -> tuple[BuiltPath | None, int]:
            # Turned round near the goal but not onto it: a short search from there,
            # turning a little wider (the ramps of a word of full-lock arcs need room).
            # Every connection rejected does not end it: the 400 expansions do.
            wide = dataclasses.replace(config.widened(), max_solutions=config.switch_after * 64)
            r_wide = wide.radius_factor / kappa_max
            w_prims, *w_long = primitive_sets(
                1.0 / r_wide, wide.curvatures, wide.step, wide.check_spacing, 0, wide.long_steps
            )
            w_shots = analytic_shots(goal, r_wide, True, wide.check_spacing, body)
            search = HybridSearch(
                body, pose, goal, heuristic, w_prims, w_shots, wide, kappa_max, problem.bounds,
                w_long,
            )  # fmt: skip
            found, outcome = search.run(
                lambda rest: accept([*pieces, *rest]), min(config.switch_after, allowed),
                watch.expired,
            )  # fmt: skip
            return found, outcome.expansions

        def turn(allowed: int) -> TurnResult[BuiltPath]:
            first = multi_point_turn(
                start, goal, body, shots, accept, 1.0 / radius, config.turn_moves,
                config.check_spacing, finish, budget=allowed,
            )  # fmt: skip
            # Turning round, not turning off: leaving a garage bay into the aisle (90 deg)
            # the search finds shorter paths than a turn further along (1.2-8.2 m).
            turning_round = abs(wrap_angle(goal.yaw - start.yaw)) > math.radians(TURN_ROUND_DEG)
            if first.result is not None or not turning_round:
                return first
            # Stuck where it starts: drive on to abreast of the goal (or near it), turn there.
            moves, tried, spent = first.moves, first.shots, first.expansions
            drives = abreast(start, goal, body, config.check_spacing, tries=config.abreast_turns)
            for drive, pose in drives:
                left = allowed - moves - spent - 1  # the drive counts as a move
                if left < 1:
                    break
                again = multi_point_turn(
                    pose, goal, body, shots, _after(drive, accept), 1.0 / radius,
                    config.turn_moves, config.check_spacing, None, budget=left,
                )  # fmt: skip
                moves, tried = moves + again.moves + 1, tried + again.shots  # the drive: a move
                spent += again.expansions
                if again.result is not None:
                    return TurnResult(again.result, moves, tried, spent)
            return TurnResult(None, moves, tried, spent)

        return turn

    def searches_with(
        body: BodyTest, start_leads: tuple[Lead, ...]
    ) -> list[tuple[HybridSearch, Accept]]:
        shots = analytic_shots(
            goal, radius, reverse, config.check_spacing, body, leads=leads_into(goal, body)
        )
        ahead = HybridSearch(
            body, start, goal, heuristic, prims, shots, config, kappa_max, problem.bounds,
            long_prims,
        )  # fmt: skip
        take: Accept = accept
        if config.shortcut_tries > 0:
            take = _shortened(accept, body, radius, reverse, config)
        if reverse and config.stub_tries > 0:
            take = _destubbed(take, accept, body, radius, config)
        out: list[tuple[HybridSearch, Accept]] = [(ahead, take)]
        if config.switch_after > 0:
            back_prims, *back_long = back_sets
            if reverse:
                back_shots = analytic_shots(
                    start, radius, True, config.check_spacing, body, leads=start_leads
                )
            else:
                back_shots = _backward_dubins_shots(start, radius, config.check_spacing, body)
            back = HybridSearch(
                body, goal, start, back_h, back_prims, back_shots, config, kappa_max,
                problem.bounds, back_long,
            )  # fmt: skip
            out.append((back, lambda p: take(reversed_in_time(p))))
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
        body = body_test(problem.checker, search_clearance)
        start_leads = leads_into(start, body) if reverse else ()
        earlier = searches
        searches = searches_with(body, start_leads)
        if margin > 0.0 and search_clearance == clearance:
            # The start or goal keeps less than the margin: capped, both passes keep the
            # same clearance and search alike. The second reads the first's shots.
            for (search, _), (done, _) in zip(searches, earlier, strict=True):
                search.replay(done)
        left = budget - used.expansions
        first_turn = config.switch_after
        if start_leads or approach_blocked(goal, body, config.check_spacing):
            # A start boxed in a bay: the way out is straight, and from the goal's side the
            # lead-in out of the start connects. A goal that cannot be driven into
            # straight forward (a kerbside gap, a bay to reverse into): from the goal's
            # side its hard part is a way out. Search from there sooner.
            first_turn = max(1, config.switch_after // BOXED_START_SOONER)
        path, outcome = alternate(
            searches, left, first_turn, watch, turn_with(search_clearance),
            guide if config.lattice_after > 0 else None, config.lattice_after,
            goal_first=goal_first,
        )  # fmt: skip
        reason = outcome.reason
        if margin > 0.0 and reason in PROOFS:
            # Out of states keeping the margin too proves nothing for the query's own
            # clearance: the rejected connections stand.
            reason = "rejected"
        used = SearchOutcome.total(reason, [used, outcome])
        if path is not None or outcome.reason != "rejected" or left - outcome.expansions <= 0:
            break
    trees = tuple(_tree(s) for s, _ in searches if s.x)
    return path, used, trees


def _shortened(
    accept: Accept, body: BodyTest, radius: float, reverse: bool, config: HybridConfig
) -> Accept:
    """``accept`` followed by :func:`~.shortcut.shortcut` (kept when accepted and shorter)."""

    def take(pieces: list[Piece]) -> BuiltPath | None:
        built = accept(pieces)
        if built is None:
            return None
        shorter = shortcut(
            pieces,
            lambda t: analytic_shots(t, radius, reverse, config.check_spacing, body),
            body,
            config.shortcut_tries,
        )
        if shorter is None:
            return built
        better = accept(shorter)
        if better is None or polyline_length(better.rows) >= polyline_length(built.rows):
            return built
        return better

    return take


def _destubbed(
    take: Accept, accept: Accept, body: BodyTest, radius: float, config: HybridConfig
) -> Accept:
    """``take`` followed by :func:`~.shortcut.drop_end_stubs` (kept when accepted and cheaper)."""

    def cost(built: BuiltPath) -> float:
        return polyline_length(built.rows) + SHOT_CUSP_COST_M * (built.segments - 1)

    def destubbed(pieces: list[Piece]) -> BuiltPath | None:
        built = take(pieces)
        if built is None or built.segments < 2:
            return built
        fewer = drop_end_stubs(
            pieces,
            lambda t: analytic_shots(t, radius, True, config.check_spacing, body),
            body, config.stub_tries, SHOT_CUSP_COST_M,
        )  # fmt: skip
        better = None if fewer is None else accept(fewer)
        return built if better is None or cost(better) >= cost(built) else better

    return destubbed


def prims_reverse(radius: float, config: HybridConfig) -> tuple[PrimitiveSet, ...]:
    """The reverse arcs alone (the search from the goal of a forward-only query), and longer."""
    return primitive_sets(
        1.0 / radius, config.curvatures, config.step, config.check_spacing, -1, config.long_steps
    )


def approach_blocked(goal: Pose, body: BodyTest, spacing: float) -> bool:
    """Whether the straight forward drive into ``goal`` over its last metre collides.

    The poses :data:`APPROACH_PROBE` metres and less behind the goal along its
    heading, ``spacing`` apart, by the body test (the goal itself excluded).
    """
    s = np.arange(1, math.ceil(APPROACH_PROBE / spacing) + 1) * spacing
    c, si = math.cos(goal.yaw), math.sin(goal.yaw)
    poses = np.column_stack([goal.x - c * s, goal.y - si * s, np.full(len(s), goal.yaw)])
    return not body.all_free(poses)
