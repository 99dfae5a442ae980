"""The default planner's escalation (issue 13, item 3): Hybrid A* after a failed query.

``improved-rrt-connect`` runs the paper's pipeline (and its Dubins fallback;
with reverse only its direct Dubins path, the tails and leads after the
escalation: :meth:`~rrtdrive.planning.improved.ImprovedConfig.escalates_first`)
first. When that fails for any reason but an invalid start or goal or a proven
unreachable goal, :func:`escalate` runs the Hybrid A* search (forward only, or
with reverse when ``problem.reverse``) on the same stopwatch: the budget it is
given (the improved planner passes the iterations its RRT-Connect stages left,
:meth:`~rrtdrive.planning.improved.ImprovedConfig.stage_budgets`) bounds its
expansions and the wall clock left is its safety cap. The result's
``iterations`` count both: the failed stages' iterations plus the expansions.
The result keeps the improved planner's name; ``stats["stage"]`` and the
message say which stage solved it (:func:`stage_of`).
"""

from __future__ import annotations

import dataclasses

from rrtdrive.planning.base import PlanningProblem, Stopwatch
from rrtdrive.planning.hybrid.config import HybridConfig
from rrtdrive.planning.hybrid.planner import (
    NAME,
    answer_stats,
    arcs_note,
    is_proof,
    path_of,
    proof_scope,
    turn_note,
)
from rrtdrive.planning.hybrid.query import hybrid_query
from rrtdrive.planning.result import timeout_result
from rrtdrive.planning.smoothing import SmoothingConfig
from rrtdrive.types import Budget, PlanResult, PlanStatus
from rrtdrive.values import counted

__all__ = ["STAGES", "ESCALATES_FROM", "escalate", "stage_of", "with_kept_clearance"]

#: The stages of ``improved-rrt-connect``, in the order they run forward only (with
#: reverse the fallback's tails and leads come after the Hybrid A* escalation).
STAGES: tuple[str, ...] = ("improved-rrt-connect", "dubins-fallback", NAME)

#: Failures the escalation answers; the others are about the query itself.
ESCALATES_FROM = frozenset({PlanStatus.NO_PATH_IN_BUDGET, PlanStatus.POSTPROCESS_FAILED})


def stage_of(result: PlanResult) -> str:
    """Which stage produced ``result``: ``stats["stage"]``, else read from its counters.

    Examples
    --------
    >>> from rrtdrive.planning.base import Stopwatch, failure
    >>> r = failure("improved-rrt-connect", PlanStatus.NO_PATH_IN_BUDGET, Stopwatch(Budget()), "")
    >>> stage_of(r), stage_of(dataclasses.replace(r, stats={"dubins_fallback": 1.0}))
    ('improved-rrt-connect', 'dubins-fallback')
    """
    stage = result.stats.get("stage")
    if isinstance(stage, str):
        return stage
    if result.stats.get("dubins_fallback"):
        return "dubins-fallback"
    return result.planner


def with_kept_clearance(result: PlanResult, own: float) -> PlanResult:
    """``result`` with ``stats["body_clearance_m"]`` when solved (the same object).

    The body clearance the returned path's final check kept: the escalation's
    search's (less in its snug and tight stages) when it solved, else ``own``, the
    improved planner's (the query's, capped at the start's and goal's own).
    """
    if result.success:
        escalated = stage_of(result) == NAME
        kept = result.stats["hybrid_body_clearance_m"] if escalated else own
        result.stats["body_clearance_m"] = float(kept)
    return result


def escalate(
    failed: PlanResult,
    problem: PlanningProblem,
    budget: Budget,
    watch: Stopwatch,
    smoothing: SmoothingConfig | None = None,
    config: HybridConfig | None = None,
    before: str | None = None,
) -> PlanResult:
    """Rescue a failed improved-planner result with the Hybrid A* search.

    Parameters
    ----------
    failed : PlanResult
        The improved planner's failure (returned unchanged unless its status is
        in :data:`ESCALATES_FROM` and the search finds a path).
    problem : PlanningProblem
        The query (``getattr(problem, "reverse", False)`` allows reversing).
    budget : Budget
        The escalation's budget: ``max_iterations`` expansions at most.
    watch : Stopwatch
        The query's running stopwatch (its expiry caps the search).
    smoothing : SmoothingConfig, optional
        Per-segment post-processor; ``None``: the exact arcs.
    config : HybridConfig, optional
        The search's settings.
    before : str, optional
        What the RRT-Connect stages left, for the message (default: "the RRT-Connect
        stages failed: " and ``failed``'s reason); the planner names a forward detour
        it asks the search to shorten.

    The search's segments get continuous curvature within the query's sharpness
    bound (``HybridConfig.curve="clothoid"``, the default: steering ramps, exact end
    poses, re-checked), so the find is returned. Under clothoid ``smoothing`` (the
    default) a path that still breaks ``smoothing.max_sharpness`` (only with
    ``curve="arcs"``: exact arcs jump in curvature) is not returned but reported in
    the failure's message and ``stats["hybrid_found_unsmooth"]``.

    Returns
    -------
    PlanResult
        Solved with ``stats["stage"] == "hybrid-a-star"``; ``TIMEOUT`` when the
        safety cap stopped the search; else ``failed`` with the search's outcome
        added to its message and ``stats``.
    """
    # The cap met here latches it: run_query then answers timeout (whatever the caller
    # made of this failure: with reverse it kept a forward detour; an audit).
    if failed.success or failed.status not in ESCALATES_FROM or watch.expired():
        return failed
    cfg = config or HybridConfig()
    reverse = bool(getattr(problem, "reverse", False))
    answer = hybrid_query(problem, budget, watch, cfg, reverse, smoothing)
    own = answer_stats(answer, problem.vehicle.wheelbase)
    stats = {**failed.stats, **{f"hybrid_{k}": v for k, v in own.items()}}
    gear = "with reverse" if reverse else "forward only"
    # Every stage's counts: the tree's and the search's.
    used = failed.iterations + answer.outcome.expansions
    nodes = failed.nodes + answer.outcome.nodes
    reason = failed.message.removeprefix("post-processing failed: ")
    if answer.path is None and (watch.capped or answer.outcome.reason == "time"):
        # The safety cap stopped the search: a timeout, as anywhere else (what it would
        # have found depends on the machine's speed), not the RRT stages' counted failure.
        out = timeout_result(
            failed.planner, watch, used, (*failed.trees, *answer.trees), stats, failed.raw_path
        )
        return dataclasses.replace(
            out,
            message=(
                f"{out.message} (in the Hybrid A* escalation, {gear}, after "
                f"{counted(answer.outcome.expansions, 'expansions')}; "
                f"{before or 'the RRT-Connect stages had failed: ' + reason})"
            ),
        )
    if answer.path is None:
        scope = proof_scope(answer.outcome, answer.clearance)
        message = f"{failed.message}; Hybrid A* ({gear}) found none either: {answer.message}{scope}"
        status = failed.status
        if is_proof(answer.outcome):
            # The status says what the message leads with, as hybrid-a-star alone says it
            # (the tree stage's postprocess_failed read as a counted failure; a new user's
            # find): scripts and bench tables read the status.
            status = PlanStatus.PROVEN_UNREACHABLE
            # A proof (every way on from the start, or in to the goal, explored) says
            # more than the tree stage's counted failure: it leads. A new user's start
            # nosed into parked cars read the tree stage's "the goal is boxed in along its
            # heading" first and blamed the goal (an audit).
            tree_part = reason.removeprefix("no path: ")
            how = answer.message.removeprefix("no path ")  # "at <resolution>: ..."
            how = how if how != answer.message else f": {how}"
            message = (
                f"no path: Hybrid A* ({gear}) proved none {how}{scope}; "
                f"the RRT-Connect stages before it: {tree_part}"
            )
        return dataclasses.replace(
            failed,
            status=status,
            message=message,
            stats=stats,
            nodes=nodes,
            iterations=used,
            planning_time_s=watch.elapsed(),
        )
    built = answer.path
    path = path_of(built)
    bound = smoothing.max_sharpness if smoothing is not None and smoothing.clothoid else None
    sharp = own["max_sharpness"]
    if bound is not None and sharp > bound + 1e-9:
        # The default promises continuous curvature within the sharpness bound
        # (issue 12); exact arcs (curve="arcs") jump in curvature where they meet, so
        # such a path is reported, not returned (hybrid-a-star itself returns it).
        stats["hybrid_found_unsmooth"] = 1.0
        return dataclasses.replace(
            failed,
            message=(
                f"{failed.message}; Hybrid A* ({gear}) found a path ({path.length:.1f} m, "
                f"{built.segments - 1} cusp(s)) whose curvature jumps where its arcs meet "
                f"(|d delta/ds| up to {_shown(sharp)} rad/m, bound {bound:g}): it needs a car "
                "that stops to steer, so the default does not return it; "
                "--planner hybrid-a-star gives it, --paper-smoothing accepts it"
            ),
            stats=stats,
            nodes=nodes,
            iterations=used,
            planning_time_s=watch.elapsed(),
        )
    stats["stage"] = NAME  # type: ignore[assignment]  # the one string entry
    message = (
        f"solved by the Hybrid A* escalation{turn_note(answer.outcome)}{answer.note} ({gear}; "
        f"{counted(answer.outcome.expansions, 'expansions')}, "
        f"{path.length:.1f} m, {built.segments - 1} cusp(s)); "
        f"{before or 'the RRT-Connect stages failed: ' + reason}" + arcs_note(built)
    )
    return dataclasses.replace(
        failed,
        status=PlanStatus.SOLVED,
        path=path,
        raw_path=built.rows[:, :2],
        trees=(*failed.trees, *answer.trees),
        nodes=nodes,
        iterations=used,
        planning_time_s=watch.elapsed(),
        message=message,
        stats=stats,
    )


def _shown(value: float) -> str:
    """A sharpness for a message: ``inf`` where the curvature jumps on the spot."""
    return "inf" if value == float("inf") else f"{value:.2f}"
