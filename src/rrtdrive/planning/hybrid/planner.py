"""The registered ``hybrid-a-star`` planner and the query runner the escalation shares.

:func:`hybrid_query` runs one search on a started stopwatch and returns a
:class:`HybridAnswer` (the checked path or why there is none);
:class:`HybridAStar` wraps it in the shared preamble
(:func:`~rrtdrive.planning.result.run_query`) and the :class:`PlanResult`.
"""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np

from rrtdrive.planning.base import PlanningProblem, Stopwatch, failure, register_planner
from rrtdrive.planning.hybrid.body import BodyTest
from rrtdrive.planning.hybrid.config import HybridConfig
from rrtdrive.planning.hybrid.heuristic import (
    DubinsTable,
    FreeCellGraph,
    Heuristic,
    HolonomicField,
)
from rrtdrive.planning.hybrid.path import BuiltPath, build_path
from rrtdrive.planning.hybrid.primitives import PrimitiveSet
from rrtdrive.planning.hybrid.search import HybridSearch, SearchOutcome, analytic_shots
from rrtdrive.planning.reeds_shepp import reeds_shepp_distance
from rrtdrive.planning.result import run_query, solved
from rrtdrive.planning.smoothing import SmoothingConfig
from rrtdrive.types import Budget, InputError, Path, PlanResult, PlanStatus, Pose, Tree

__all__ = ["NAME", "HybridAStar", "HybridAnswer", "hybrid_query", "free_cell_graph"]

NAME = "hybrid-a-star"


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


def query_clearance(problem: PlanningProblem, wanted: float) -> float:
    """``wanted``, capped at the exact body clearance the start and goal poses have."""
    if wanted <= 0.0:
        return 0.0
    c = problem.checker
    have = min(
        c.body_clearance(problem.start.as_tuple()), c.body_clearance(problem.goal.as_tuple())
    )
    return max(0.0, min(wanted, have * 0.999))


@dataclass(frozen=True, eq=False)
class HybridAnswer:
    """What one search gave: the checked path (or ``None``), the outcome and a message."""

    path: BuiltPath | None
    outcome: SearchOutcome
    message: str
    tree: Tree


def _failure_message(outcome: SearchOutcome, cfg: HybridConfig, budget: Budget) -> str:
    res = f"{cfg.xy_resolution:g} m / {np.degrees(cfg.yaw_resolution):g} deg"
    counts = f"{outcome.expansions} expansions, {outcome.nodes} nodes"
    if outcome.reason == "exhausted":
        return (
            f"no path at {res} resolution: the search ran out of states ({counts}); "
            "the goal is unreachable for this car at this resolution"
        )
    if outcome.reason == "no_approach":
        return (
            f"no path at {res} resolution: driving forward, the car cannot arrive at the goal "
            f"pose (every way it could have come from, the goal's poses driven backwards, "
            f"was explored and none leads out; {counts}); it can only be reached in reverse "
            "if at all (try --reverse)"
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
    return f"no path found within the expansion budget of {budget.max_iterations} ({counts})"


def hybrid_query(
    problem: PlanningProblem,
    budget: Budget,
    watch: Stopwatch,
    config: HybridConfig,
    reverse: bool,
    smoothing: SmoothingConfig | None,
) -> HybridAnswer:
    """One Hybrid A* search from ``problem.start`` to ``problem.goal``.

    Parameters
    ----------
    problem : PlanningProblem
        The query.
    budget : Budget
        ``max_iterations`` bounds the expansions; ``max_time_s`` is only a cap.
    watch : Stopwatch
        The started stopwatch whose expiry stops the search.
    config : HybridConfig
        The search's settings.
    reverse : bool
        Whether reverse primitives and shots are allowed.
    smoothing : SmoothingConfig or None
        The per-segment post-processor (its ``clearance`` is the one kept); ``None``:
        exact arcs only.

    Returns
    -------
    HybridAnswer
    """
    vehicle = problem.vehicle
    kappa_max = vehicle.kappa_max
    clearance = query_clearance(problem, config.body_clearance)
    if smoothing is not None:
        smoothing = dataclasses.replace(smoothing, clearance=clearance, kappa_max=kappa_max)
    radius = config.radius_factor / kappa_max
    # The returned rows interpolate linearly between arc poses 0.25 m apart (at most
    # 1.3 mm off the arc at kappa_max): the re-check allows 5 mm less than the search kept,
    # so that it does not reject what the search found. The start and goal poses have
    # at least the search's clearance (capped at theirs), never more is asked of them.
    search_clearance = clearance
    recheck_clearance = max(0.0, clearance - 0.005)
    goal = problem.goal
    grid = free_cell_graph(problem, config.xy_resolution)
    field = HolonomicField.towards(grid, goal)
    if reverse:
        rs = reeds_shepp_to(goal, radius) if config.reeds_shepp_heuristic else None
        heuristic = Heuristic(field, None, goal, rs)
    else:
        table = dubins_table(radius, config)
        heuristic = Heuristic(field, table.to(goal), goal, table.scalar_to(goal))
    prims = PrimitiveSet.build(
        1.0 / radius, config.curvatures, config.step, config.check_spacing, reverse
    )
    body = BodyTest(problem.checker, search_clearance)
    shots = analytic_shots(goal, radius, reverse, config.check_spacing, body)
    search = HybridSearch(
        body, problem.start, goal, heuristic, prims, shots, config, kappa_max, problem.bounds
    )

    def accept(pieces: list) -> BuiltPath | None:
        return build_path(
            pieces, problem.checker, smoothing if config.smooth else None, config.arc_fallback,
            recheck_clearance, kappa_max, config.check_spacing, config.sample_spacing,
        )  # fmt: skip

    probe = None
    if not reverse and config.probe_after > 0:

        def unreachable() -> bool:
            return _no_forward_approach(problem, body, field, config, radius, kappa_max, watch)

        probe = (config.probe_after, unreachable)
    path, outcome = search.run(accept, budget.max_iterations, watch.expired, probe)
    tree = Tree(
        np.column_stack([search.x, search.y]) if search.x else np.zeros((0, 2)),
        np.array(search.parent, dtype=np.int64),
    )
    message = "" if path is not None else _failure_message(outcome, config, budget)
    return HybridAnswer(path, outcome, message, tree)


def _no_forward_approach(
    problem: PlanningProblem,
    body: BodyTest,
    field: HolonomicField,
    config: HybridConfig,
    radius: float,
    kappa_max: float,
    watch: Stopwatch,
) -> bool:
    """Whether the poses a forward drive could reach the goal from run out (a proof).

    The goal's predecessors are what the car reaches from the goal in reverse
    (a forward arc driven backwards in time). A search over them from the goal,
    with no goal of its own, that runs out of states within
    ``config.probe_expansions`` proves, at the search's resolution, that no
    forward path arrives: e.g. a goal whose tail is against a wall.
    """
    goal = problem.goal
    prims = PrimitiveSet.build(
        1.0 / radius, config.curvatures, config.step, config.check_spacing, reverse=True
    )
    back = PrimitiveSet(
        prims.kappas[prims.gears < 0], prims.gears[prims.gears < 0],
        prims.local[prims.gears < 0], prims.length,
    )  # fmt: skip
    towards_start = Heuristic(field, None, goal)  # any order serves: only exhaustion counts
    flood = HybridSearch(
        body, goal, problem.start, towards_start, back, lambda pose: [], config, kappa_max,
        problem.bounds,
    )  # fmt: skip
    _, outcome = flood.run(lambda pieces: None, config.probe_expansions, watch.expired)
    return outcome.reason == "exhausted"


def answer_stats(answer: HybridAnswer, wheelbase: float) -> dict[str, float]:
    """The search counters of an answer, for :attr:`PlanResult.stats`."""
    o = answer.outcome
    stats = {
        "expansions": float(o.expansions),
        "hybrid_nodes": float(o.nodes),
        "shots": float(o.shots),
        "connections": float(o.connections),
    }
    if answer.path is not None:
        stats["gear_segments"] = float(answer.path.segments)
        stats["smoothed_segments"] = float(answer.path.smoothed)
        stats["cusps"] = float(answer.path.segments - 1)
        stats["max_sharpness"] = answer.path.max_sharpness(wheelbase)
    return stats


def path_of(built: BuiltPath) -> Path:
    """The :class:`Path` of a built path (rows with their gear column)."""
    return Path(built.rows, built.waypoints)


@register_planner(NAME)
class HybridAStar:
    """Hybrid A* (Dolgov et al. 2008) with analytic expansions to the exact goal pose.

    Parameters
    ----------
    config : HybridConfig, optional
        Full configuration; keyword ``options`` override its fields.
    reverse : bool, optional
        Allow reversing; default ``getattr(problem, "reverse", False)`` per query.
    smoothing : SmoothingConfig, optional
        The per-segment post-processor (default ``SmoothingConfig(max_rounds=24)``,
        the improved planner's).
    **options
        Any :class:`HybridConfig` field.

    Examples
    --------
    >>> from rrtdrive.maps import builtin_map
    >>> res = HybridAStar().solve(PlanningProblem.from_map(builtin_map("overtake")),
    ...                           np.random.default_rng(0), Budget())
    >>> res.success, bool(res.path.max_curvature <= 1 / 6)
    (True, True)
    """

    name = NAME

    def __init__(
        self,
        config: HybridConfig | None = None,
        *,
        reverse: bool | None = None,
        smoothing: SmoothingConfig | None = None,
        **options: object,
    ) -> None:
        base = config if config is not None else HybridConfig()
        if not isinstance(base, HybridConfig):
            raise InputError(f"planner.config: expected a HybridConfig, got {type(base).__name__}")
        self.config = _with_options(base, options) if options else base
        if reverse is not None and not isinstance(reverse, bool):
            raise InputError(f"planner.reverse: expected true or false, got {reverse!r}")
        self.reverse = reverse
        self.smoothing = smoothing if smoothing is not None else SmoothingConfig(max_rounds=24)

    def __repr__(self) -> str:
        return f"HybridAStar({self.config!r}, reverse={self.reverse!r})"

    def solve(
        self, problem: PlanningProblem, rng: np.random.Generator, budget: Budget
    ) -> PlanResult:
        """Plan from ``problem.start`` to ``problem.goal``; never returns ``None``.

        The search is deterministic: ``rng`` is not used, ``budget.max_iterations``
        bounds the expansions and ``budget.max_time_s`` is only a safety cap.
        """
        reverse = self.reverse
        if reverse is None:
            reverse = bool(getattr(problem, "reverse", False))
        cfg = self.config

        def search(watch: Stopwatch) -> PlanResult:
            answer = hybrid_query(problem, budget, watch, cfg, reverse, self.smoothing)
            stats = answer_stats(answer, problem.vehicle.wheelbase)
            return hybrid_result(NAME, answer, watch, stats)

        def prepare() -> None:
            free_cell_graph(problem, cfg.xy_resolution)
            if not reverse:
                dubins_table(cfg.radius_factor / problem.vehicle.kappa_max, cfg)

        return run_query(NAME, problem, budget, search, prepare)


def hybrid_result(
    planner: str, answer: HybridAnswer, watch: Stopwatch, stats: dict[str, float]
) -> PlanResult:
    """The :class:`PlanResult` of an answer: solved, or the failure its outcome names."""
    o = answer.outcome
    if answer.path is None:
        status = PlanStatus.NO_PATH_IN_BUDGET
        if o.reason in ("exhausted", "no_approach"):
            status = PlanStatus.PROVEN_UNREACHABLE
        elif o.reason == "time":
            # The wall-clock cap has its own status where PlanStatus has one (issue 13, item 4).
            status = getattr(PlanStatus, "TIMEOUT", PlanStatus.NO_PATH_IN_BUDGET)
        return failure(
            planner, status, watch, answer.message, trees=(answer.tree,), iterations=o.expansions,
            stats=stats,
        )  # fmt: skip
    built = answer.path
    path = path_of(built)
    cusps = built.segments - 1
    message = (
        f"solved by Hybrid A*: {o.expansions} expansions, {path.length:.1f} m, "
        f"{cusps} cusp(s), {built.smoothed}/{built.segments} segment(s) smoothed" + arcs_note(built)
    )
    raw = built.rows[:, :2]
    return solved(
        planner, watch, path, raw, (answer.tree,), o.expansions, message, stats, nodes=o.nodes
    )


def arcs_note(built: BuiltPath) -> str:
    """What a path with unsmoothed segments does not guarantee (empty when all are smoothed)."""
    if built.smoothed == built.segments:
        return ""
    return (
        "; the unsmoothed segments are exact arcs and lines: |kappa| <= kappa_max and the "
        "body are checked, but the curvature jumps where they meet (no sharpness bound)"
    )


def _with_options(base: HybridConfig, options: Mapping[str, object]) -> HybridConfig:
    fields = {f.name for f in dataclasses.fields(HybridConfig)}
    unknown = sorted(set(options) - fields)
    if unknown:
        raise InputError(
            f"planner.{unknown[0]}: unknown option for hybrid-a-star; allowed {sorted(fields)}"
        )
    return dataclasses.replace(base, **options)  # type: ignore[arg-type]
