"""How an improved RRT-Connect query ends once its tree paths failed.

The Dubins fallback over the failed tree paths (beyond the paper), the failed
escalation's result when the fallback after it fails too, and the honest failure:
the safety cap, post-processing failed, or no path within the budget. Each takes
the query's working state (:class:`~rrtdrive.planning.improved.planner._Query`).
"""

from __future__ import annotations

import dataclasses
import time
from typing import Any

import numpy as np

from rrtdrive.planning.base import failure
from rrtdrive.planning.improved.config import NAME, StageBudgets
from rrtdrive.planning.improved.fallback import dubins_fallback
from rrtdrive.planning.result import solved, timeout_result
from rrtdrive.types import PlanResult, PlanStatus
from rrtdrive.values import counted

__all__ = ["fallback_result", "fallback_failed", "failure_result"]


def fallback_result(
    q: Any, escalated: PlanResult | None = None, *, direct: bool = True, joints: bool = True
) -> PlanResult | None:
    """Beyond the paper: the Dubins fallback over the failed tree paths, newest first.

    Parameters
    ----------
    q : _Query
        The query's working state (records which fallback was tried).
    escalated : PlanResult, optional
        The failed Hybrid A* escalation it runs after (with reverse,
        :meth:`ImprovedConfig.escalates_first`), whose counts and stats it keeps.
    direct, joints : bool
        Try the direct Dubins path; the tails and leads.

    Returns
    -------
    PlanResult or None
        Solved by the fallback, or ``None`` when it found no clear path.
    """
    stats, watch = q.stats, q.watch
    q.fallback_tried = "all" if joints else "direct"
    t0 = time.perf_counter()
    found = dubins_fallback(
        q.checker, q.start, q.goal,
        q.cfg.dubins_radius_factor / q.problem.vehicle.kappa_max,
        q.smoothing.clearance, q.failed_raws[::-1], q.smoothing, watch.expired,
        max_candidates=q.limits.candidates if joints else 0, direct=direct,
    )  # fmt: skip
    stats["dubins_time_s"] = stats.get("dubins_time_s", 0.0) + time.perf_counter() - t0
    if found is None:
        return None
    path, word = found
    stats["dubins_fallback"] = 1.0
    stats["max_curvature"] = float(np.abs(path.samples[:, 3]).max())
    if q.last_message:
        # make_drivable's messages open with "post-processing failed: "; the query did not.
        reason = q.last_message.removeprefix("post-processing failed: ")
        note = f"no tree path could be made drivable ({reason})"
    elif q.stuck_root:
        note = q.stuck_words()
    else:
        note = "the trees did not meet within the budget"
    raw = q.last_raw if q.last_raw is not None else np.vstack([q.s_xy, q.g_xy])
    iterations = q.iterations
    if escalated is not None:
        stats = {**escalated.stats, **stats}
        iterations = escalated.iterations
        expansions = int(stats.get("hybrid_expansions", 0.0))
        gear = "with reverse" if q.problem.reverse else "forward only"
        note += f"; Hybrid A* ({gear}) found none ({counted(expansions, 'expansions')})"
    message = f"solved by the Dubins fallback ({word}; {path.length:.1f} m); {note}"
    return solved(
        NAME, watch, path, raw, q.trees, iterations, message, stats,
        nodes=int(stats["nodes"]),
    )  # fmt: skip

def fallback_failed(q: Any, escalated: PlanResult) -> PlanResult:
    """The failed escalation's result, saying that the Dubins fallback after it failed too.

    Parameters
    ----------
    q : _Query
        The query's working state.
    escalated : PlanResult
        The failed escalation.

    Returns
    -------
    PlanResult
    """
    if q.watch.capped:
        return failure_result(q)
    stats = {**escalated.stats, "dubins_time_s": q.stats["dubins_time_s"]}
    return dataclasses.replace(
        escalated,
        message=f"{escalated.message}; no clear Dubins tail or lead either",
        stats=stats,
        planning_time_s=q.watch.elapsed(),
    )

def failure_result(q: Any) -> PlanResult:
    """The honest failure: the safety cap, post-processing failed, or no path in the budget.

    Parameters
    ----------
    q : _Query
        The query's working state.

    Returns
    -------
    PlanResult
    """
    stats, watch, iterations = q.stats, q.watch, q.iterations
    if watch.capped:
        return timeout_result(NAME, watch, iterations, q.trees, stats, q.last_raw)
    if stats["postprocess_attempts"] > 0 and q.last_message:
        tail = {
            "all": "; no clear Dubins path, tail or lead either)",
            "direct": "; no clear Dubins path)",
        }.get(q.fallback_tried, ")")
        return failure(
            NAME,
            PlanStatus.POSTPROCESS_FAILED,
            watch,
            f"{q.last_message} (after {int(stats['postprocess_attempts'])} tree path(s)"
            + tail,
            trees=q.trees,
            iterations=iterations,
            raw_path=q.last_raw,
            stats=stats,
        )
    if q.stuck_root:
        lead = (
            f"no path: {q.stuck_words()} ({counted(iterations, 'iterations')})"
        )
    else:
        lead = (
            f"no path within the iteration budget ({counted(iterations, 'iterations')}"
            f"{_share_note(q.limits, watch.budget.max_iterations)})"
        )
    return failure(
        NAME,
        PlanStatus.NO_PATH_IN_BUDGET,
        watch,
        lead,
        trees=q.trees,
        iterations=iterations,
        stats=stats,
    )




def _share_note(limits: StageBudgets, max_iterations: int) -> str:
    """``", the RRT-Connect stages' share ..."`` for a failure message, when they had one."""
    if limits.iterations >= max_iterations:
        return ""
    return f", the RRT-Connect stages' share of {max_iterations}"
