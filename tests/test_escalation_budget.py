"""The default planner's counted budget share: its RRT-Connect stages give way to the escalation.

With ``escalation`` on, the RRT-Connect stages of ``improved-rrt-connect`` get
``rrt_share`` of each counted budget (growth iterations, tree paths, Dubins
fallback joints) and the Hybrid A* escalation the iterations they left
(:meth:`ImprovedConfig.stage_budgets`). Counts decide, so the stage that solves
is the same for a seed on any machine.
"""

from __future__ import annotations

import dataclasses
import json
import math
import re
import time

import numpy as np
import pytest

from rrtdrive.cli import plan_to_json
from rrtdrive.collision import CollisionChecker
from rrtdrive.maps import Map, Obstacle, builtin_map
from rrtdrive.planning.base import PlanningProblem, Stopwatch, failure
from rrtdrive.planning.hybrid.escalation import escalate, stage_of
from rrtdrive.planning.improved import ImprovedConfig, ImprovedRRTConnect
from rrtdrive.planning.improved.fallback import MAX_FALLBACK_CANDIDATES
from rrtdrive.types import Budget, InputError, PlanStatus, Pose
from rrtdrive.verify import verify_path

#: Counts decide; the wall clock is only a generous cap.
BUDGET = Budget(max_iterations=2000, max_time_s=600.0)
_SECONDS = re.compile(r"\b\d+\.\d+ s\b")


def bay_map() -> Map:
    """A 14 m aisle with one dead-end bay 2.8 m wide and 6 m deep above it.

    The goal lies deep in the bay facing out of it: forward, no tree path arrives
    along its heading (the RRT-Connect stages fail); with reverse the car backs in.
    """
    return Map(
        "bay", (0.0, 0.0, 30.0, 20.0),
        (Obstacle((6.8, 17.0), (13.6, 6.0)), Obstacle((23.2, 17.0), (13.6, 6.0))),
        Pose(4.0, 5.0, 0.0), Pose(15.0, 18.6, -math.pi / 2),
    )  # fmt: skip


def solve(problem: PlanningProblem, seed: int = 0, budget: Budget = BUDGET, **options):
    return ImprovedRRTConnect(**options).solve(problem, np.random.default_rng(seed), budget)


def test_stage_budgets_are_the_share_of_each_count() -> None:
    cfg = ImprovedConfig()
    got = cfg.stage_budgets(2000)
    assert got.iterations == math.ceil(cfg.rrt_share * 2000) < 2000
    assert got.attempts == cfg.max_postprocess_attempts
    assert got.candidates == cfg.escalation_fallback_joints < MAX_FALLBACK_CANDIDATES
    # The paper's pipeline alone (no escalation) keeps every budget in full.
    full = cfg.without("escalation").stage_budgets(2000)
    assert (full.iterations, full.attempts, full.candidates) == (
        2000, cfg.max_postprocess_attempts, MAX_FALLBACK_CANDIDATES,
    )  # fmt: skip
    assert ImprovedConfig(rrt_share=1e-9).stage_budgets(7).iterations == 1


@pytest.mark.parametrize("share", [0.0, -0.1, 1.5, float("nan"), "half"])
def test_a_bad_share_is_named(share: object) -> None:
    with pytest.raises(InputError, match=r"planner\.rrt_share"):
        ImprovedConfig(rrt_share=share)


@pytest.mark.parametrize("joints", [-1, 2.5, True])
def test_bad_fallback_joints_are_named(joints: object) -> None:
    with pytest.raises(InputError, match=r"planner\.escalation_fallback_joints"):
        ImprovedConfig(escalation_fallback_joints=joints)


def test_a_query_the_rrt_stages_cannot_solve_is_escalated_within_the_share(monkeypatch) -> None:  # noqa: ANN001
    # The bay's goal is proven boxed in before any iteration (test_root_boxed_in.py); the
    # shares are about growth that runs, so here the proof says nothing.
    from rrtdrive.planning.improved import planner as improved_planner

    monkeypatch.setattr(improved_planner, "boxed_end", lambda *a, **k: "")
    m = bay_map()
    problem = PlanningProblem.from_map(m, reverse=True)
    res = solve(problem, narrow_fan=0.0)  # the whole patience too (its fan is narrow)
    assert res.success, res.message
    assert stage_of(res) == res.stats["stage"] == "hybrid-a-star"
    assert "solved by the Hybrid A* escalation" in res.message and "(with reverse" in res.message
    limits = ImprovedConfig().stage_budgets(BUDGET.max_iterations)
    # The RRT-Connect stages kept to their share; the escalation had the rest.
    assert res.stats["rrt_iterations"] == limits.iterations
    assert res.stats["iterations"] <= limits.iterations
    assert res.stats["postprocess_attempts"] <= limits.attempts
    assert res.iterations == res.stats["iterations"] + res.stats["hybrid_expansions"]
    assert res.iterations <= BUDGET.max_iterations
    assert res.stats["rrt_stages_time_s"] > 0 and res.stats["escalation_time_s"] > 0
    assert not res.path.is_forward_only and verify_path(m, res.path).collision_free
    # With every budget in full the same stages spend more before the escalation starts.
    full = solve(problem, rrt_share=1.0, narrow_fan=0.0)
    assert full.stats["iterations"] > res.stats["iterations"]


def test_without_the_escalation_the_stages_keep_the_whole_budget() -> None:
    problem = PlanningProblem.from_map(bay_map(), reverse=True)
    res = solve(problem, disable=("escalation",))
    assert not res.success and "stage" not in res.stats
    assert res.status in (PlanStatus.NO_PATH_IN_BUDGET, PlanStatus.POSTPROCESS_FAILED)
    assert res.stats["rrt_iterations"] == BUDGET.max_iterations
    assert "share" not in res.message and "Hybrid" not in res.message


class SlowChecker(CollisionChecker):
    """The same checker on a slower machine: every exact batch sleeps first."""

    def poses_free(self, poses: np.ndarray, clearance: float = 0.0) -> np.ndarray:
        time.sleep(2e-4)
        return super().poses_free(poses, clearance)


def _json(res, problem: PlanningProblem) -> str:
    out = plan_to_json(res, 0, problem.map.name, reverse=problem.reverse)
    timing = ("planning_time_s", "setup_time_s", "diagnosis_time_s")
    out = {k: v for k, v in out.items() if k not in timing}
    out["message"] = _SECONDS.sub("<t> s", out["message"])
    return json.dumps(out, sort_keys=True)


def test_the_stage_choice_is_deterministic_also_on_a_slower_machine() -> None:
    m = bay_map()
    problem = PlanningProblem.from_map(m, reverse=True)
    a, b = solve(problem), solve(problem)
    slow = dataclasses.replace(problem, checker=SlowChecker.for_map(m))
    c = solve(slow)
    assert a.success and stage_of(a) == stage_of(b) == stage_of(c) == "hybrid-a-star"
    assert _json(a, problem) == _json(b, problem) == _json(c, slow)
    assert '"stage": "hybrid-a-star"' in _json(a, problem)


def test_the_safety_cap_inside_the_escalation_is_a_timeout() -> None:
    # A clock that passes the cap after a fixed number of readings: deterministic. The
    # dead end needs a turn of several hundred expansions (the bay's straight lead-in
    # answers in a few since session 14).
    problem = PlanningProblem.from_map(builtin_map("dead_end"), reverse=True)
    budget = Budget(max_iterations=2000, max_time_s=1.0)
    readings = iter(range(10**6))
    watch = Stopwatch(budget, clock=lambda: 0.0 if next(readings) < 40 else 2.0)
    failed = failure(
        "improved-rrt-connect", PlanStatus.POSTPROCESS_FAILED, watch, "the turns are too close"
    )
    res = escalate(failed, problem, budget, watch)
    assert res.status is PlanStatus.TIMEOUT and watch.capped
    assert res.message.startswith("stopped by the 1 s safety cap after ")
    assert "in the Hybrid A* escalation, with reverse" in res.message
    assert "the RRT-Connect stages had failed: the turns are too close" in res.message
    assert res.iterations == res.stats["hybrid_expansions"] > 0
