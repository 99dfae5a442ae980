"""Hybrid A*'s last-resort stages, on random queries of ``experiments/coverage.py``.

- coarse (``HybridConfig.coarse_after``): a search that spends its share of the
  budget without a path hands the rest to one at 4x the cell, bin and step; forward
  drives that must loop round on ``parking_lot`` need it. Its failure proves nothing.
- tight (``min_clearance``): after a proof for paths keeping 0.15 m, one search
  keeping 0.05 m; a start with room around it but less ahead needs it.
- middle (``HybridConfig.middled``): after a coarse search that ended with budget
  left, one at half its factor, then keeping ``min_clearance`` there.
- wide (``wide_radius_factor``): after every goal connection was rejected (the
  ramps of full-lock words cannot end on the pose), one search turning wider.
- shares (``refine_share``): a finer search that a last resort may follow spends at
  most half the rest, so that the last resort still runs.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from rrtdrive.maps import Map, Obstacle, builtin_map
from rrtdrive.planning import PlanningProblem, make_planner
from rrtdrive.planning.hybrid import HybridConfig
from rrtdrive.pose_sets import random_free_poses
from rrtdrive.sim.tasks import make_scenario
from rrtdrive.types import Budget, InputError, PlanStatus, Pose
from rrtdrive.verify import verify_path


def _random_problem(
    vary: str, index: int, count: int = 30, reverse: bool = False, seed: int = 1
):
    """Random ``vary`` pose ``index`` of ``coverage.py --count count --seed seed``."""
    pose = random_free_poses("parking_lot", count, seed, vary)[index]
    m = dataclasses.replace(builtin_map("parking_lot"), **{vary: pose})
    return m, PlanningProblem.from_map(m, reverse=reverse)


def _loop_start_problem() -> PlanningProblem:
    """Random start 25 of the coverage set: forward only, the car must turn round."""
    return _random_problem("start", 25)[1]


def _solve(problem: PlanningProblem, budget: int, **options: object):
    planner = make_planner("hybrid-a-star", **options)
    return planner.solve(
        problem, np.random.default_rng(0), Budget(max_iterations=budget, max_time_s=300)
    )


def test_coarse_stage_solves_what_the_fine_search_cannot_in_the_budget() -> None:
    problem = _loop_start_problem()
    without = _solve(problem, 2000, coarse_after=0.0)
    assert without.status is PlanStatus.NO_PATH_IN_BUDGET
    res = _solve(problem, 2000)
    assert res.status is PlanStatus.SOLVED, res.message
    assert "at 2 m / 20 deg resolution" in res.message
    assert "spent its share of 500 expansions" in res.message
    assert res.stats["coarse_search"] == 1.0 and res.stats["refinements"] == 0.0
    assert 500 < res.iterations <= 2000
    # Exact start and goal, forward only, and the independent check passes.
    assert np.allclose(res.path.samples[0, :3], problem.start.as_tuple(), atol=1e-9)
    assert np.allclose(res.path.samples[-1, :3], problem.goal.as_tuple(), atol=1e-6)
    assert np.all(res.path.samples[:, 4] == 1)
    m = dataclasses.replace(builtin_map("parking_lot"), start=problem.start)
    assert verify_path(m, res.path, max_sharpness=0.2).ok


def test_a_failed_coarse_search_is_not_a_proof() -> None:
    # kerbside forward only: the fine search is cut at its share (100 of 400), the coarse
    # one cannot reach the gap and runs out of states; the middle one (1 m) and its tight
    # one (0.05 m) run out of ways to arrive at the goal (the gap cannot be driven into
    # straight, so the search from the goal starts after 100 expansions), at their
    # coarser grid. No proof, and the message says why.
    problem = PlanningProblem.from_map(builtin_map("kerbside"))
    cut = _solve(problem, 400)
    assert cut.status is PlanStatus.NO_PATH_IN_BUDGET
    assert "spent its share of 100 expansions, then at 2 m / 20 deg / 4 m steps it ran out of " \
        "states" in cut.message
    assert "then at 1 m / 10 deg / 2 m steps it ran out of ways to arrive at the goal" in (
        cut.message
    )
    assert "keeping only 0.05 m body clearance it ran out of ways to arrive" in cut.message
    assert "a coarser search proves nothing" in cut.message
    assert cut.iterations <= 400
    # With budget enough that the fine search ends within its share, it (and its finer
    # retry) proves that no forward drive arrives: the proof is not lost.
    proof = _solve(problem, 2000)
    assert proof.status is PlanStatus.PROVEN_UNREACHABLE, proof.message
    assert proof.stats["coarse_search"] == 0.0 and proof.stats["refinements"] == 1.0


def test_middle_stage_threads_an_approach_too_tight_for_the_coarse_grid() -> None:
    # Random goal 94 forward: the only way in passes about 0.05 m from a parked car. The
    # first search spends its share, the coarse one (2 m) and the middle one keeping
    # 0.15 m (1 m) run out of ways to arrive; the middle one keeping 0.05 m finds it.
    # The ladder as it runs where the heading lattice does not help (lattice_after=0);
    # with it (the default) the first search finds a way keeping 0.15 m (below).
    m, problem = _random_problem("goal", 94, count=100)
    res = _solve(problem, 20000, lattice_after=0)
    assert res.status is PlanStatus.SOLVED, res.message
    assert "keeping only 0.05 m body clearance at 1 m / 10 deg resolution" in res.message
    assert res.stats["tight_search"] == 1.0
    assert verify_path(m, res.path, max_sharpness=0.2).ok
    assert np.all(res.path.samples[:, 4] == 1)
    # Without the middle stage (coarse_factor 2 has none) the budget ends without a path.
    without = _solve(problem, 20000, coarse_factor=2, lattice_after=0)
    assert without.status is PlanStatus.NO_PATH_IN_BUDGET
    # Guided by the heading lattice after 800 expansions, the first search threads it
    # keeping the query's 0.15 m, in fewer expansions than the ladder took.
    guided = _solve(problem, 20000)
    assert guided.status is PlanStatus.SOLVED, guided.message
    assert guided.message.startswith("solved by Hybrid A*: ")
    assert guided.iterations < res.iterations
    assert verify_path(m, guided.path, max_sharpness=0.2).ok
    assert problem.checker.poses_free(guided.path.samples[:, :3], clearance=0.145).all()


def test_the_wall_clock_cap_on_the_middle_branch_is_a_timeout_named_as_such(monkeypatch) -> None:
    # The cap is the machine's; to hit it at a known point, the middle search (the third)
    # is made to end as the search loop ends when the stopwatch expires.
    from rrtdrive.planning.hybrid import query
    from rrtdrive.planning.hybrid.search import SearchOutcome

    real = query.search_at_resolution
    calls = []

    def capped(problem, allowed, watch, cfg, *rest):
        calls.append(cfg.xy_resolution)
        if len(calls) == 3:
            return None, SearchOutcome("time", 7, 9, 0, 0), ()
        return real(problem, allowed, watch, cfg, *rest)

    monkeypatch.setattr(query, "search_at_resolution", capped)
    _, problem = _random_problem("goal", 94, count=100)
    res = _solve(problem, 20000, lattice_after=0)
    assert calls == [0.5, 2.0, 1.0]
    assert res.status is PlanStatus.TIMEOUT
    assert res.message.startswith(
        "no path found: the wall-clock cap of 300 s was hit before the expansion budget of "
        "20000: at 0.5 m / 5 deg / 1 m steps the search spent its share of 5000 expansions"
    )
    assert "then at 1 m / 10 deg / 2 m steps it was stopped by the wall-clock cap" in res.message


def test_queries_solved_within_the_share_are_unchanged() -> None:
    problem = PlanningProblem.from_map(builtin_map("garage"))
    a, b = _solve(problem, 2000), _solve(problem, 2000, coarse_after=0.0)
    assert a.status is b.status is PlanStatus.SOLVED
    assert a.iterations == b.iterations
    assert np.array_equal(a.path.samples, b.path.samples)
    assert a.stats["coarse_search"] == 0.0


def test_tight_stage_keeps_less_clearance_only_after_a_proof() -> None:
    m, problem = _random_problem("start", 7)
    proof = _solve(problem, 20_000, min_clearance=0.15)
    assert proof.status is PlanStatus.PROVEN_UNREACHABLE
    # Turning at 1.02 / kappa_max, as the search before it (at full lock, the default,
    # the snug search finds a way keeping 0.10 m: the next test).
    res = _solve(problem, 20_000, tight_radius_factor=1.02)
    assert res.status is PlanStatus.SOLVED, res.message
    assert "keeping only 0.05 m body clearance (none keeps 0.15 m)" in res.message
    assert res.stats["tight_search"] == 1.0
    assert res.stats["body_clearance_m"] == pytest.approx(0.05)
    assert verify_path(m, res.path, max_sharpness=0.2).ok
    clear = min(problem.checker.body_clearance(tuple(r[:3])) for r in res.path.samples)
    # The re-check allows 5 mm below the search's clearance (interpolated rows).
    assert 0.045 - 1e-6 <= clear < 0.15


def test_last_resorts_turn_at_full_lock() -> None:
    # Random start 352 of the held-out set, forward: OMPL's Dubins RRT (radius
    # 1 / kappa_max) drives out of it; turning at 1.02 / kappa_max ours cannot.
    m, problem = _random_problem("start", 352, count=400, seed=2)
    kappa_max = problem.vehicle.kappa_max
    wider = _solve(problem, 20_000, tight_radius_factor=1.02)
    assert wider.status is PlanStatus.PROVEN_UNREACHABLE, wider.message
    res = _solve(problem, 20_000)
    assert res.status is PlanStatus.SOLVED, res.message
    assert "keeping only 0.10 m body clearance (none keeps 0.15 m)" in res.message
    assert res.stats["body_clearance_m"] == pytest.approx(0.10)
    # It turns tighter than the usual searches can, and never beyond the car's limit.
    assert kappa_max / 1.02 + 1e-6 < res.path.max_curvature <= kappa_max + 1e-9
    assert verify_path(m, res.path, max_sharpness=0.2).ok
    start = _random_problem("start", 7)[1]
    snug = _solve(start, 20_000)
    assert snug.status is PlanStatus.SOLVED, snug.message
    assert "keeping only 0.10 m body clearance (none keeps 0.15 m)" in snug.message


def test_tight_search_runs_again_at_the_finest_grid() -> None:
    # Random goal 183 of the held-out set, forward: at full lock keeping 0.05 m the
    # first grid's search has every connection rejected, the finest grid's finds one.
    m, problem = _random_problem("goal", 183, count=400, seed=2)
    res = _solve(problem, 20_000)
    assert res.status is PlanStatus.SOLVED, res.message
    assert res.message.startswith(
        "solved by Hybrid A* keeping only 0.05 m body clearance (none keeps 0.15 m) at "
        "0.25 m / 2.5 deg resolution"
    )
    assert (
        "at 0.5 m / 5 deg / 1 m steps keeping only 0.05 m body clearance the search had "
        "every goal connection rejected" in res.message
    )
    assert res.path.max_curvature <= problem.vehicle.kappa_max + 1e-9
    assert verify_path(m, res.path, max_sharpness=0.2).ok


def test_no_expansions_held_back_for_a_search_that_cannot_follow() -> None:
    # Random start 131 of the held-out set, forward: every connection rejected at the
    # first grid, then the wide and fine searches spend their shares. Only a search
    # after rejections (persist) may follow the fine one, so the fine one gets all the
    # rest; it had left 4 267 of the 20 000 unspent (session 21). Since session 39 its
    # rejected connections (a long segment's whole ramp fit) are fitted a stretch at a
    # time and it solves: the accounting is tested with the whole fit alone.
    m, problem = _random_problem("start", 131, count=400, seed=2)
    res = _solve(problem, 20_000, ramp_chunks=False)
    assert res.status is PlanStatus.NO_PATH_IN_BUDGET, res.message
    assert res.iterations == 20_000
    assert "within its share" not in res.message.split(";")[0]
    solved = _solve(problem, 20_000)
    assert solved.success and solved.iterations < 20_000, solved.message
    assert verify_path(m, solved.path, max_sharpness=0.205).ok


def test_wide_stage_turns_wider_after_rejected_connections() -> None:
    m, problem = _random_problem("goal", 39, count=100, reverse=True)
    # The search of session 7 (unit steps, weight 1.5, every shot): its connections are
    # all rejected.
    before = {"long_steps": (), "heuristic_weight": 1.5, "shot_cell": 0.0}
    # (persist=False: without the search that goes on through the rejections, session 18.)
    rejected = _solve(problem, 20_000, wide_radius_factor=1.02, persist=False, **before)
    assert rejected.status is PlanStatus.NO_PATH_IN_BUDGET
    assert "could not be made drivable" in rejected.message
    res = _solve(problem, 20_000, **before)
    assert res.status is PlanStatus.SOLVED, res.message
    assert "turning with radius 6.6 m (1.1 x the car's tightest)" in res.message
    assert res.stats["wide_search"] == 1.0 and len(res.path.cusps) >= 1
    assert verify_path(m, res.path, max_sharpness=0.2).ok
    assert res.path.max_curvature <= problem.vehicle.kappa_max + 1e-9


@pytest.mark.parametrize(
    ("field", "value"),
    [("coarse_after", 1.5), ("coarse_after", -0.1), ("coarse_factor", 1),
     ("min_clearance", -0.01), ("wide_radius_factor", 0.9), ("refine_share", 0.0),
     ("refine_share", 1.5)],
)
def test_bad_coarse_settings_name_the_field(field: str, value: float) -> None:
    with pytest.raises(InputError, match=f"hybrid.{field}"):
        HybridConfig(**{field: value})


def _pinned_start_problem():
    """Random start 34 of ``coverage.py --count 100``: 0.152 m clearance at the pose."""
    return _random_problem("start", 34, count=100)


def test_finer_search_leaves_the_tight_search_its_share() -> None:
    # Forward only, no motion out of the start keeps 0.15 m at 0.5 m / 5 deg (3
    # expansions); the finer search keeping 0.15 m needs ~35 000 expansions, the tight
    # one 3 626: with refine_share the finer one stops at half the rest and the tight
    # one solves it.
    m, problem = _pinned_start_problem()
    assert problem.checker.body_clearance(problem.start.as_tuple()) < 0.16
    res = _solve(problem, 20_000, lattice_after=0)  # the ladder (the lattice: below)
    assert res.status is PlanStatus.SOLVED, res.message
    assert "keeping only 0.05 m body clearance" in res.message
    assert "the search ran out of states after 3 expansions" in res.message
    assert "at 0.25 m / 2.5 deg / 0.5 m steps the search spent its share of 9999" in res.message
    # No proof for 0.15 m at the finer resolution, so none is claimed.
    assert "none keeps" not in res.message
    assert res.stats["tight_search"] == 1.0 and res.stats["refinements"] == 1.0
    # The tight search solved it within the half left to it.
    assert 3 + 9999 < res.iterations <= 20_000
    assert np.all(res.path.samples[:, 4] == 1)
    assert verify_path(m, res.path, max_sharpness=0.2).ok
    # All the rest to the finer search (the ladder before refine_share): no path.
    old = _solve(problem, 20_000, refine_share=1.0, lattice_after=0)
    assert old.status is PlanStatus.NO_PATH_IN_BUDGET
    assert old.stats["tight_search"] == 0.0
    # Guided by the heading lattice, the finer search finds a way keeping what the
    # start has (0.15 m capped at its own), before the tight search is needed.
    guided = _solve(problem, 20_000)
    assert guided.status is PlanStatus.SOLVED, guided.message
    assert "keeping only" not in guided.message and guided.stats["tight_search"] == 0.0
    assert guided.iterations < res.iterations
    assert verify_path(m, guided.path, max_sharpness=0.2).ok


def test_tight_search_cut_short_after_a_shared_finer_one_proves_nothing() -> None:
    _, problem = _pinned_start_problem()
    res = _solve(problem, 6000, lattice_after=0)  # 3 + 2999 + 2998: the tight one needs 3 626
    assert res.status is PlanStatus.NO_PATH_IN_BUDGET, res.message
    assert res.message.startswith(
        "no path found at 0.25 m / 2.5 deg resolution within its share of 2999 expansions"
    )
    assert "keeping only 0.05 m body clearance, at 0.5 m / 5 deg the search spent" in res.message
    assert res.iterations == 6000


def test_default_planner_solves_the_pinned_start_forward() -> None:
    m, problem = _pinned_start_problem()
    res = make_planner("improved-rrt-connect").solve(
        problem, np.random.default_rng(0), Budget(max_time_s=300)
    )
    assert res.status is PlanStatus.SOLVED, res.message
    assert res.stats["stage"] == "hybrid-a-star"
    # Its escalation is the Hybrid A* query: guided by the heading lattice, its finer
    # search keeps the start's own clearance (without, only the tight search at 0.05 m).
    assert "keeping only" not in res.message
    assert res.stats["hybrid_tight_search"] == 0.0
    assert np.all(res.path.samples[:, 4] == 1)
    assert verify_path(m, res.path, max_sharpness=0.2).ok


def test_a_finer_grid_met_during_the_search_is_set_up_not_planning(monkeypatch) -> None:
    """The first finer search on a map builds its grid inside a Stopwatch.setup block."""
    import time as _time

    from rrtdrive.planning.hybrid import resolution

    built = resolution.free_cell_graph
    slept = []

    def slow_graph(problem, res):
        if res < 0.5 and not slept:  # the refined grid, the first time: pretend it is big
            slept.append(res)
            _time.sleep(0.3)
        return built(problem, res)

    monkeypatch.setattr(resolution, "free_cell_graph", slow_graph)
    task = make_scenario("parallel-parking", 5)
    problem = PlanningProblem.from_map(task.map, reverse=True)
    res = make_planner("hybrid-a-star", heuristic_weight=1.5).solve(
        problem, np.random.default_rng(0), Budget(max_time_s=300)
    )
    assert res.success and res.stats["refinements"] == 1.0 and slept
    assert res.setup_time_s >= 0.3


def test_setup_blocks_leave_planning_time_and_go_to_setup_time() -> None:
    import time as _time

    from rrtdrive.planning.base import failure
    from rrtdrive.planning.result import run_query

    def search(watch):
        with watch.setup():
            _time.sleep(0.2)
        status = PlanStatus.TIMEOUT if watch.expired() else PlanStatus.NO_PATH_IN_BUDGET
        return failure("demo", status, watch, "none")

    problem = PlanningProblem.from_map(builtin_map("parking_lot"))
    res = run_query("demo", problem, Budget(max_time_s=0.1), search, rng=np.random.default_rng(0))
    assert res.setup_time_s >= 0.2
    assert res.planning_time_s < 0.2
    assert res.status is PlanStatus.NO_PATH_IN_BUDGET  # the set-up did not hit the 0.1 s cap


def test_searches_after_no_approach_start_from_the_goal() -> None:
    # Random goal 20 of coverage.py --count 100 --seed 1: forward, no way arrives at it.
    # Each search of the ladder proves it from the goal's side in 6-22 expansions; the
    # first one spends its first turn (400 expansions) from the start, and until session
    # 35 so did the four after it (2 056 expansions, about 90 % of them from the start).
    _, problem = _random_problem("goal", 20, count=100)
    result = _solve(problem, 20000)
    assert result.status is PlanStatus.PROVEN_UNREACHABLE, result.message
    assert "ran out of ways to arrive at the goal" in result.message
    turn = HybridConfig().switch_after  # the first search's first turn, from the start
    # Five searches (the last leads the message), the first 400 + 6 expansions, the four
    # others from the goal alone.
    assert result.message.count("ran out of ways to arrive at the goal") == 4, result.message
    assert turn < result.iterations < 2 * turn, result.iterations


def test_the_goal_side_goes_first_only_for_a_goal_in_a_pocket() -> None:
    # A street 15.2 m wide, the goal across it facing back, 30 m clear behind it: a forward
    # U-turn at full lock keeping 0.05 m fits. Since session 35 every search after one whose
    # goal side ran out gave the goal's side the first turn; here it ran out after 405
    # expansions before the start's side, whose shots solve it, had a turn, and the query
    # ended proven_unreachable (an audit refuted it with a verified forward path). The
    # goal's side now goes first only for a goal in a pocket (goal 20 above: it keeps its
    # few expansions).
    m = Map("wide street", (0.0, 0.0, 80.0, 15.2), (), Pose(10.0, 1.2, 0.0),
            Pose(10.0, 14.0, math.pi))
    result = _solve(PlanningProblem.from_map(m), 20000)
    assert result.status is PlanStatus.SOLVED, result.message
    assert len(result.path.cusps) == 0
    assert verify_path(m, result.path, max_sharpness=0.2, clearance=0.05).ok


def test_a_start_whose_forward_search_runs_out_says_it_is_the_start() -> None:
    # A car nosed into a pocket: forward, the search from the start runs out at once; the
    # message said "the search ran out of states", which a new user read as the goal's
    # fault (the tree stage before it had blamed the goal).
    walls = (
        Obstacle((18.0, 10.0), (0.6, 4.0)),
        Obstacle((15.5, 8.3), (5.6, 0.6)),
        Obstacle((15.5, 11.7), (5.6, 0.6)),
    )
    m = Map("pocket", (0.0, 0.0, 40.0, 20.0), walls, Pose(14.0, 10.0, 0.0), Pose(30.0, 10.0, 0.0))
    forward = _solve(PlanningProblem.from_map(m), 20_000)
    assert forward.status is PlanStatus.PROVEN_UNREACHABLE
    assert "the search from the start ran out of states" in forward.message
    assert "try --reverse" in forward.message
    backing_out = _solve(PlanningProblem.from_map(m, reverse=True), 20_000)
    assert backing_out.success and len(backing_out.path.cusps) >= 1
