"""The default planner's stage order when reversing is allowed.

With ``reverse`` one tree path (``ImprovedConfig.reverse_postprocess_attempts``),
the direct Dubins path (cheap, forward, no cusp), then the Hybrid A* escalation
(Reeds-Shepp shots), and the Dubins fallback's tails and leads only when it fails
(``ImprovedConfig.escalation_first``). Forward only, the order is unchanged: up to
six tree paths, the whole fallback, then the escalation. A query that the first
tree path or the direct Dubins path solves is solved as before either way.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import rrtdrive.planning.improved.planner as improved_planner
from rrtdrive.maps import builtin_map
from rrtdrive.planning import PlanningProblem
from rrtdrive.planning.hybrid.escalation import stage_of
from rrtdrive.planning.improved import ImprovedConfig, ImprovedRRTConnect
from rrtdrive.pose_sets import random_free_poses
from rrtdrive.types import Budget, InputError, PlanStatus
from rrtdrive.verify import verify_path

BUDGET = Budget(max_time_s=600.0)
#: The order and tree paths before session 8.
OLD = {"escalation_first": "never", "reverse_postprocess_attempts": 6}


def _goal_problem(index: int, reverse: bool = True):
    """Random goal ``index`` of ``experiments/coverage.py --count 30`` on ``parking_lot``."""
    pose = random_free_poses("parking_lot", 30, 1, "goal")[index]
    m = dataclasses.replace(builtin_map("parking_lot"), goal=pose)
    return m, PlanningProblem.from_map(m, reverse=reverse)


def _solve(problem: PlanningProblem, **options):
    planner = ImprovedRRTConnect(**options)
    return planner.solve(problem, np.random.default_rng(0), BUDGET)


def test_with_reverse_the_escalation_runs_before_the_dubins_fallback() -> None:
    m, problem = _goal_problem(16)
    res = _solve(problem)
    assert res.success, res.message
    assert stage_of(res) == "hybrid-a-star"
    # Only the direct Dubins path was tried before, no tail or lead.
    assert "(after 1 tree path(s); no clear Dubins path)" in res.message
    assert verify_path(m, res.path, max_sharpness=0.2).ok
    old = _solve(problem, **OLD)
    assert stage_of(old) == "dubins-fallback"
    assert res.path.length < old.path.length  # 91.9 m against 122.9 m


def test_forward_only_the_fallback_still_comes_first() -> None:
    _, problem = _goal_problem(16, reverse=False)
    res, old = _solve(problem), _solve(problem, **OLD)
    assert res.success and stage_of(res) == stage_of(old) == "dubins-fallback"
    assert res.message == old.message and res.iterations == old.iterations
    assert np.array_equal(res.path.samples, old.path.samples)
    assert ImprovedConfig().stage_budgets(20_000).attempts == 6


def test_with_reverse_one_tree_path_then_the_escalation() -> None:
    m, problem = _goal_problem(8)
    old = _solve(problem, **OLD)
    assert stage_of(old) == "improved-rrt-connect" and old.stats["postprocess_attempts"] > 1
    res = _solve(problem)
    assert res.success and stage_of(res) == "hybrid-a-star"
    assert res.stats["postprocess_attempts"] == 1
    assert res.stats["rrt_iterations"] == ImprovedConfig().stage_budgets(20_000).iterations
    assert verify_path(m, res.path, max_sharpness=0.2).ok


def test_a_first_tree_path_that_solves_is_unchanged() -> None:
    _, problem = _goal_problem(10)
    res, old = _solve(problem), _solve(problem, **OLD)
    assert stage_of(res) == stage_of(old) == "improved-rrt-connect"
    assert res.message == old.message and res.iterations == old.iterations
    assert np.array_equal(res.path.samples, old.path.samples)


def test_a_direct_dubins_path_still_comes_before_the_escalation() -> None:
    # Forward and without a cusp: kept where it fits (16 of the 17 stock parking-v0
    # seeds the fallback solved, whose closed loop it keeps).
    _, problem = _goal_problem(7)
    res, old = _solve(problem), _solve(problem, **OLD)
    assert stage_of(res) == stage_of(old) == "dubins-fallback"
    assert "tree path" not in res.message.split(";")[0]  # the direct path, no tail
    assert np.array_equal(res.path.samples, old.path.samples)
    assert "hybrid_expansions" not in res.stats


def _escalation_with(monkeypatch: pytest.MonkeyPatch, expansions: int) -> None:
    """The escalation cut to ``expansions``: it fails where the full one would solve."""
    real = improved_planner.escalate

    def cut(failed, problem, budget, watch, smoothing, **kwargs):
        return real(failed, problem, dataclasses.replace(budget, max_iterations=expansions),
                    watch, smoothing, **kwargs)  # fmt: skip

    monkeypatch.setattr(improved_planner, "escalate", cut)


def test_the_fallback_answers_after_a_failed_escalation(monkeypatch: pytest.MonkeyPatch) -> None:
    _escalation_with(monkeypatch, 1)
    m, problem = _goal_problem(16)
    res = _solve(problem)
    assert res.success and stage_of(res) == "dubins-fallback", res.message
    assert "; Hybrid A* (with reverse) found none (1 expansion)" in res.message
    assert res.iterations == res.stats["iterations"] + 1
    assert res.stats["hybrid_expansions"] == 1.0 and res.stats["dubins_time_s"] > 0
    assert verify_path(m, res.path, max_sharpness=0.2).ok


def test_a_failure_names_the_escalation_and_then_the_fallback(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    _escalation_with(monkeypatch, 1)
    _, problem = _goal_problem(29)
    res = _solve(problem)
    assert res.status is PlanStatus.POSTPROCESS_FAILED
    assert res.message.startswith("post-processing failed: ")
    assert (
        "(after 1 tree path(s); no clear Dubins path); Hybrid A* (with reverse) found none "
        "either" in res.message
    )
    assert res.message.endswith("; no clear Dubins tail or lead either")
    assert "dubins_time_s" in res.stats


@pytest.mark.parametrize(
    ("field", "value"),
    [("escalation_first", "sometimes"), ("escalation_first", True),
     ("reverse_postprocess_attempts", 0), ("reverse_postprocess_attempts", 1.5)],
)
def test_bad_order_settings_are_named(field: str, value: object) -> None:
    with pytest.raises(InputError, match=rf"planner\.{field}"):
        ImprovedConfig(**{field: value})
