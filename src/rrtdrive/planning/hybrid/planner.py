"""The registered ``hybrid-a-star`` planner: :func:`~.query.hybrid_query` as a :class:`PlanResult`.

:class:`HybridAStar` wraps the query in the shared preamble
(:func:`~rrtdrive.planning.result.run_query`); :func:`hybrid_result`,
:func:`answer_stats` and :func:`arcs_note` are shared with the escalation.
"""

from __future__ import annotations

import functools
from collections.abc import Mapping

import numpy as np

from rrtdrive.planning.base import PlanningProblem, Stopwatch, failure, register_planner
from rrtdrive.planning.diagnosis import Diagnosis
from rrtdrive.planning.hybrid.config import HybridConfig, hybrid_with
from rrtdrive.planning.hybrid.path import BuiltPath, path_of
from rrtdrive.planning.hybrid.probe import reverse_probe
from rrtdrive.planning.hybrid.query import HybridAnswer, hybrid_query
from rrtdrive.planning.hybrid.resolution import PROOFS, dubins_table, free_cell_graph
from rrtdrive.planning.hybrid.search import SearchOutcome
from rrtdrive.planning.result import run_query, solved, timeout_result
from rrtdrive.planning.smoothing import SmoothingConfig, smoothing_with
from rrtdrive.types import Budget, InputError, PlanResult, PlanStatus
from rrtdrive.values import counted

__all__ = [
    "NAME", "HybridAStar", "hybrid_result", "answer_stats", "arcs_note", "path_of", "proof_scope",
]

NAME = "hybrid-a-star"


def answer_stats(answer: HybridAnswer, wheelbase: float) -> dict[str, float]:
    """The search counters of an answer, for :attr:`PlanResult.stats`.

    Parameters
    ----------
    answer : HybridAnswer
        The query's answer.
    wheelbase : float
        The car's wheelbase in metres (for the path's ``max_sharpness``).

    Returns
    -------
    dict of str to float
        Counters and flags (1.0 / 0.0); the path's gear segments, cusps and
        sharpness when there is one.
    """
    o = answer.outcome
    proof = answer.path is None and is_proof(o)
    stats = {
        "expansions": float(o.expansions),
        "hybrid_nodes": float(o.nodes),
        "shots": float(o.shots),
        "connections": float(o.connections),
        "refinements": float(answer.refinements),
        "coarse_search": float(answer.stage == "coarse"),
        "tight_search": float(answer.stage in ("snug", "tight")),  # less clearance kept
        "wide_search": float(answer.stage == "wide"),
        "persist_search": float(answer.stage == "persist"),
        "turn_moves": float(o.turn_moves),
        "body_clearance_m": float(answer.clearance),
        # Which side's search proved the query out of reach, for the diagnosis: from the
        # goal, no way in reaches the start; from the start, no way on reaches the goal.
        "no_approach": float(proof and o.reason == "no_approach"),
        "start_exhausted": float(proof and o.reason == "exhausted"),
    }
    if answer.path is not None:
        stats["gear_segments"] = float(answer.path.segments)
        stats["smoothed_segments"] = float(answer.path.smoothed)
        stats["cusps"] = float(answer.path.segments - 1)
        stats["max_sharpness"] = answer.path.max_sharpness(wheelbase)
    return stats


@register_planner(NAME)
class HybridAStar:
    """Hybrid A* (Dolgov et al. 2008) with analytic expansions to the exact goal pose.

    Parameters
    ----------
    config : HybridConfig, optional
        Full configuration; keyword ``options`` override its fields.
    reverse : bool, optional
        Allow reversing; default ``getattr(problem, "reverse", False)`` per query.
    smoothing : SmoothingConfig or mapping, optional
        The per-segment post-processor (default ``SmoothingConfig(max_rounds=24)``,
        the improved planner's); a mapping changes those fields of the default.
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
    #: It honours ``PlanningProblem.reverse`` (gear changes); the baselines plan forward.
    reverses = True

    def __init__(
        self,
        config: HybridConfig | None = None,
        *,
        reverse: bool | None = None,
        smoothing: SmoothingConfig | Mapping[str, object] | None = None,
        **options: object,
    ) -> None:
        base = config if config is not None else HybridConfig()
        if not isinstance(base, HybridConfig):
            raise InputError(f"planner.config: expected a HybridConfig, got {type(base).__name__}")
        self.config = hybrid_with(base, options, "planner") if options else base
        if reverse is not None and not isinstance(reverse, bool):
            raise InputError(f"planner.reverse: expected true or false, got {reverse!r}")
        self.reverse = reverse
        own = SmoothingConfig(max_rounds=24)
        if isinstance(smoothing, Mapping):  # fields to change (a JSON or CLI option)
            smoothing = smoothing_with(own, smoothing)
        if smoothing is not None and not isinstance(smoothing, SmoothingConfig):
            kind = type(smoothing).__name__
            raise InputError(
                f"planner.smoothing: expected a SmoothingConfig or a mapping of its fields, "
                f"got {kind}"
            )
        self.smoothing = smoothing if smoothing is not None else own

    def __repr__(self) -> str:
        return f"HybridAStar({self.config!r}, reverse={self.reverse!r})"

    def solve(
        self, problem: PlanningProblem, rng: np.random.Generator, budget: Budget
    ) -> PlanResult:
        """Plan from ``problem.start`` to ``problem.goal``; never returns ``None``.

        The search is deterministic: ``rng`` is not used, ``budget.max_iterations``
        bounds the expansions and ``budget.max_time_s`` is only a safety cap.

        Parameters
        ----------
        problem : PlanningProblem
            The map, checker and query; its ``reverse`` allows gear changes unless
            the planner's own ``reverse`` is set.
        rng : numpy.random.Generator
            Unused (the search is deterministic).
        budget : Budget
            Expansions and wall-time cap.

        Returns
        -------
        PlanResult
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
            for c in _first_configs(cfg):
                free_cell_graph(problem, c.xy_resolution)
                if not reverse:
                    dubins_table(c.radius_factor / problem.vehicle.kappa_max, c)

        def probe() -> Diagnosis | None:
            return reverse_probe(problem, cfg, self.smoothing, budget.max_time_s)

        return run_query(
            NAME, problem, budget, search, prepare, rng=rng, tree_edges=False,
            probe=None if reverse else probe, reverses=True, keeps=cfg.least_clearance,
        )


@functools.lru_cache(maxsize=16)  # a validated copy once per config, not per query
def _first_configs(cfg: HybridConfig) -> tuple[HybridConfig, ...]:
    """The searches a query starts with: the first, and the coarse one that may follow it."""
    return (cfg, cfg.coarsened()) if cfg.coarsens else (cfg,)


def hybrid_result(
    planner: str, answer: HybridAnswer, watch: Stopwatch, stats: dict[str, float]
) -> PlanResult:
    """The :class:`PlanResult` of an answer: solved, or the failure its outcome names.

    Parameters
    ----------
    planner : str
        The planner's name in the result.
    answer : HybridAnswer
        The query's answer.
    watch : Stopwatch
        The query's clock (a capped clock gives a timeout result).
    stats : dict of str to float
        The result's statistics (:func:`answer_stats`).

    Returns
    -------
    PlanResult
        Solved, timed out, proven unreachable or no path in budget.
    """
    o = answer.outcome
    if watch.capped:
        # The cap, met anywhere (between the ladder's searches too), decides: the searches
        # it skipped would have run on a faster machine (a ladder cut short after its first
        # grid ended proven_unreachable, an audit).
        return timeout_result(
            planner, watch, o.expansions, answer.trees, stats, unit="expansions"
        )
    if answer.path is None:
        status = PlanStatus.NO_PATH_IN_BUDGET
        if is_proof(o):
            status = PlanStatus.PROVEN_UNREACHABLE
        elif o.reason == "time":
            # The wall-clock cap has its own status where PlanStatus has one (issue 13, item 4).
            status = getattr(PlanStatus, "TIMEOUT", PlanStatus.NO_PATH_IN_BUDGET)
        # A proof holds for the clearance its search kept, on its grid: say so.
        message = answer.message + proof_scope(o, answer.clearance)
        return failure(
            planner, status, watch, message, trees=answer.trees, iterations=o.expansions,
            stats=stats,
        )  # fmt: skip
    built = answer.path
    path = path_of(built)
    cusps = built.segments - 1
    message = (
        f"solved by Hybrid A*{turn_note(o)}{answer.note}: {counted(o.expansions, 'expansions')}, "
        f"{path.length:.1f} m, "
        f"{cusps} cusp(s), {built.smoothed}/{built.segments} segment(s) smoothed" + arcs_note(built)
    )
    raw = built.rows[:, :2]
    return solved(
        planner, watch, path, raw, answer.trees, o.expansions, message, stats, nodes=o.nodes
    )


def is_proof(outcome: SearchOutcome) -> bool:
    """Whether a failed search proved the goal out of reach.

    It ran out of states and never connected to the goal: a connection whose steering
    ramps were rejected is a path of arcs to the goal (a car that stops to steer
    drives it), so no proof then.
    """
    return outcome.reason in PROOFS and not outcome.connections


def proof_scope(outcome: SearchOutcome, clearance: float) -> str:
    """What a search that ran out of states proved: only paths that keep its clearance.

    Examples
    --------
    >>> proof_scope(SearchOutcome("exhausted", 10, 20, 3, 0), 0.15)
    ' (a proof for paths keeping 0.15 m body clearance, on that grid only)'
    >>> proof_scope(SearchOutcome("expansions", 10, 20, 3, 0), 0.15)
    ''
    >>> proof_scope(SearchOutcome("exhausted", 10, 20, 3, 2), 0.15)
    ' (no proof: 2 goal connection(s) were found, none drivable within the steering rate)'
    """
    if outcome.reason not in PROOFS:
        return ""
    if not is_proof(outcome):
        return (f" (no proof: {outcome.connections} goal connection(s) were found, none "
                "drivable within the steering rate)")  # fmt: skip
    return f" (a proof for paths keeping {clearance:.2f} m body clearance, on that grid only)"


def turn_note(outcome: SearchOutcome) -> str:
    """How a solved query's path began, for its message: the multi-point turn's moves, if any.

    Examples
    --------
    >>> turn_note(SearchOutcome("solved", 9, 0, 0, 0, 6))
    ' with a multi-point turn of 6 moves'
    """
    if not outcome.turn_moves:
        return ""
    return f" with a multi-point turn of {outcome.turn_moves} moves"


def arcs_note(built: BuiltPath) -> str:
    """What a path with unsmoothed segments does not guarantee (empty when all are smoothed)."""
    if built.smoothed == built.segments:
        return ""
    return (
        "; the unsmoothed segments are exact arcs and lines: |kappa| <= kappa_max and the "
        "body are checked, but the curvature jumps where they meet (no sharpness bound)"
    )
