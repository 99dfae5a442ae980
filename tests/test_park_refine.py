"""Hybrid A* refines its resolution when the coarse search ends without a path (issue 14).

Seeded maps that failed to plan at 0.5 m / 5 deg / 1 m steps in
``results/closed_loop_gears100`` of session 5: parallel-parking seed 5 (a gap of
1.51 car lengths, "proven_unreachable") and parking-reverse-in seed 12 (its 32
goal connections rejected by the ramps). Both must now solve at the finer
resolution, with the same guarantees, checked by code independent of the planner.
"""

from __future__ import annotations

import numpy as np
import pytest

from rrtdrive.planning.base import PlanningProblem
from rrtdrive.planning.hybrid import HybridAStar, HybridConfig, resolution
from rrtdrive.planning.smoothing import max_sharpness
from rrtdrive.sim.tasks import make_scenario
from rrtdrive.types import Budget, InputError, Path, PlanStatus
from rrtdrive.verify import verify_path

BUDGET = Budget(max_time_s=1e6)


def _problem(task) -> PlanningProblem:
    return PlanningProblem.from_map(task.map, reverse=task.reverse)


def _assert_guarantees(task, path: Path, problem: PlanningProblem) -> None:
    """Body, curvature, ends and cusps (verify), clearance, and sharpness per segment."""
    check = verify_path(task.map, path)
    assert check.ok, check
    s = path.samples
    assert np.allclose(s[0, :3], task.map.start.as_tuple(), atol=1e-9)
    assert np.allclose(s[-1, :3], task.map.goal.as_tuple(), atol=1e-9)
    car = task.map.vehicle
    assert path.max_curvature <= car.kappa_max + 1e-9
    checker = problem.checker
    clear = min(checker.body_clearance(tuple(r[:3])) for r in s)
    # The query's clearance: 0.15 m capped at the goal's own, minus the re-check's 5 mm.
    want = min(0.15, checker.body_clearance(task.map.goal.as_tuple()) * 0.999) - 0.005
    assert clear >= want - 1e-6
    bound = min(0.2, car.max_steer_rate / 2.0)
    for a, b in path.segments():
        assert max_sharpness(s[a:b, :4], car.wheelbase) <= bound + 1e-9


def test_refined_config_halves_cell_bin_and_step() -> None:
    cfg = HybridConfig(refinements=2)
    fine = cfg.refined()
    assert (fine.xy_resolution, fine.step, fine.refinements) == (0.25, 0.5, 1)
    assert fine.yaw_resolution == pytest.approx(cfg.yaw_resolution / 2)
    with pytest.raises(InputError, match="hybrid.refinements"):
        HybridConfig(refinements=-1)


def test_tight_parallel_gap_is_solved_at_the_finer_resolution() -> None:
    task = make_scenario("parallel-parking", 5)
    assert task.gap_factor < 1.52  # one of the tightest gaps of the range
    problem = _problem(task)
    # (min_clearance: no search keeping less than the usual clearance after the proof.)
    coarse = HybridAStar(refinements=0, min_clearance=0.15).solve(
        problem, np.random.default_rng(0), BUDGET
    )
    assert coarse.status is PlanStatus.PROVEN_UNREACHABLE
    assert "no path at 0.5 m / 5 deg resolution" in coarse.message
    res = HybridAStar().solve(problem, np.random.default_rng(0), BUDGET)
    assert res.success, res.message
    assert res.stats["refinements"] == 1
    # Honest: solved at the finer resolution, the coarse search's end named, not "proven".
    assert "at 0.25 m / 2.5 deg resolution" in res.message
    assert "ran out of ways to arrive at the goal" in res.message
    assert len(res.path.cusps) >= 1 and res.path.samples[-1, 4] in (1.0, -1.0)
    _assert_guarantees(task, res.path, problem)


def test_reverse_in_bay_with_rejected_connections_is_solved_finer(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    task = make_scenario("parking", 12, reverse_in=True)
    problem = _problem(task)
    # (wide_radius_factor: no wider-turning search after the rejections; the search of
    # session 6 (unit steps, weight 1.5, every shot), whose connections at 0.5 m / 5 deg are all
    # rejected here. Since session 17 a goal that cannot be driven into straight brings the
    # search from the goal in 4x sooner, which solves this bay at the coarse resolution; the
    # session-6 timing is restored so that the finer retry is what is tested.)
    before = {"long_steps": (), "heuristic_weight": 1.5, "shot_cell": 0.0}
    monkeypatch.setattr(resolution, "approach_blocked", lambda *_: False)
    coarse = HybridAStar(refinements=0, wide_radius_factor=1.02, persist=False, **before).solve(
        problem, np.random.default_rng(0), BUDGET
    )
    assert coarse.status is PlanStatus.NO_PATH_IN_BUDGET
    assert "could not be made drivable" in coarse.message
    res = HybridAStar(wide_radius_factor=1.02, **before).solve(
        problem, np.random.default_rng(0), BUDGET
    )
    assert res.success, res.message
    assert res.stats["refinements"] == 1
    assert "had every goal connection rejected" in res.message
    assert res.path.samples[-1, 4] == -1.0  # backed into the bay
    _assert_guarantees(task, res.path, problem)
    # By default the wider-turning search comes before the finer one (session 13).
    wide = HybridAStar(**before).solve(problem, np.random.default_rng(0), BUDGET)
    assert wide.success, wide.message
    assert wide.stats["wide_search"] == 1.0 and wide.stats["refinements"] == 0
    wider = "turning with radius 6.6 m (1.1 x the car's tightest) at 0.5 m / 5 deg resolution"
    assert wider in wide.message
    assert wide.path.samples[-1, 4] == -1.0
    _assert_guarantees(task, wide.path, problem)
    # With the goal-side search brought in sooner (session 17) the first coarse search
    # backs into this bay itself: neither the wider turns nor the finer grid are needed.
    monkeypatch.undo()
    now = HybridAStar(**before).solve(problem, np.random.default_rng(0), BUDGET)
    assert now.success, now.message
    assert now.stats["wide_search"] == 0.0 and now.stats["refinements"] == 0
    assert now.iterations < wide.iterations
    assert now.path.samples[-1, 4] == -1.0
    _assert_guarantees(task, now.path, problem)


def test_refinement_shares_the_counted_budget() -> None:
    task = make_scenario("parallel-parking", 5)
    # The coarse search needs ~404 expansions to end; 420 leaves too few for the fine one
    # (coarse_after=0: the first search may spend the whole budget; abreast_turns=0: the
    # turns tried further along would spend the rest before the refinement).
    res = HybridAStar(coarse_after=0.0, abreast_turns=0).solve(
        _problem(task), np.random.default_rng(0), Budget(max_iterations=420, max_time_s=1e6)
    )
    assert not res.success
    assert res.status is PlanStatus.NO_PATH_IN_BUDGET
    assert res.iterations <= 420
    assert "before that, at 0.5 m / 5 deg / 1 m steps" in res.message
