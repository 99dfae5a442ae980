"""Guards against mutants that survived the suite: the improved planner and its diagnosis.

Each test checks a rule a user sees (which stage answers, the budgets, the detour rule,
the fallback's candidates, a diagnosis's claim) against an independent reference: the
rule as the docstrings state it, a hand-derived value, shapely geometry, brute-force
enumeration or the growth's own edge test.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence

import numpy as np
import pytest
import shapely

import rrtdrive.planning.improved.ending as improved_ending
import rrtdrive.planning.improved.planner as improved_planner
from rrtdrive.maps import Map, Obstacle
from rrtdrive.planning.base import PlanningProblem, cached_checker
from rrtdrive.planning.diagnosis import DiagnosisKind, diagnose, free_run, u_turn_width
from rrtdrive.planning.diagnosis.checks import (
    goal_behind,
    no_forward_arrival,
    tight_clearance,
    u_turn,
)
from rrtdrive.planning.diagnosis.measures import best_run
from rrtdrive.planning.hybrid.escalation import stage_of
from rrtdrive.planning.improved import ImprovedConfig, ImprovedRRTConnect
from rrtdrive.planning.improved import fallback as fallback_module
from rrtdrive.planning.improved.detour import shorter_answer
from rrtdrive.planning.improved.fallback import MAX_FALLBACK_CANDIDATES, dubins_fallback
from rrtdrive.planning.improved.growth import ObtuseTree, grow_until_meet, link, link_candidates
from rrtdrive.planning.reeds_shepp import reeds_shepp_distance
from rrtdrive.planning.smoothing import SmoothingConfig
from rrtdrive.types import Budget, InputError, PlanResult, Pose, VehicleParams
from rrtdrive.vehicle import footprint_polygon
from rrtdrive.verify import verify_path

BUDGET = Budget(max_time_s=600.0)
START = Pose(50.0, 50.0, 0.0)


def _open_map(goal: Pose, start: Pose = START) -> Map:
    """A 100 m square without obstacles."""
    return Map("open", (0.0, 0.0, 100.0, 100.0), (), start, goal)


def _solve(m: Map, reverse: bool = False, budget: Budget = BUDGET, **options: object) -> PlanResult:
    problem = PlanningProblem.from_map(m, reverse=reverse)
    return ImprovedRRTConnect(**options).solve(problem, np.random.default_rng(0), budget)


# --------------------------------------------------------------------------- growth


def test_a_passage_link_never_leaves_the_root_backwards() -> None:
    """The root is a link candidate only where Eq. 11 calls its angle obtuse."""
    tree = ObtuseTree(np.array([0.0, 0.0]), virtual_parent=np.array([-5.0, 0.0]))
    # Behind the root (heading +x): D(root, q) + D(root, vp) = 9.25 + 25 > D(vp, q) = 4.25,
    # so the angle (vp, root, q) is acute and the root may not be joined to q.
    behind = np.array([-3.0, 0.5])
    assert link_candidates(tree, behind, 5.0).tolist() == []
    assert link(tree, False, behind, 5.0, lambda a, b: True) == -1 and len(tree) == 1
    # Ahead: 9.25 + 25 < D(vp, q) = 64.25, obtuse: the root is the candidate.
    ahead = np.array([3.0, 0.5])
    assert link_candidates(tree, ahead, 5.0).tolist() == [0]


class _Uniform:
    """Samples uniform in a 40 m square (the growth's SampleSource interface)."""

    def draw_xy(self, rng: np.random.Generator) -> np.ndarray:
        return rng.uniform(0.0, 40.0, size=2)


def _goal_root_blocked(a: Sequence[float], b: Sequence[float]) -> bool:
    """Every edge at the goal root (35, 20) collides; every other edge is free."""
    return not any(p[0] == 35.0 and p[1] == 20.0 for p in (a, b))


@pytest.mark.parametrize("before", [0, 1000, 4321])
def test_the_root_patience_counts_the_pairs_own_iterations(before: int) -> None:
    """A later pair of trees (after earlier pairs' iterations) gets its whole patience."""
    patience = 50
    ts = ObtuseTree(np.array([5.0, 20.0]), virtual_parent=np.array([0.0, 20.0]))
    tg = ObtuseTree(np.array([35.0, 20.0]), virtual_parent=np.array([40.0, 20.0]))
    found, used = grow_until_meet(
        ts, tg, _Uniform(), np.random.default_rng(0), _goal_root_blocked, step=5.0,
        obtuse=True, adaptive=True, passages=None, passage_bias=0.0, iterations=before,
        max_iterations=before + 3000, expired=lambda: False, root_patience=patience,
    )  # fmt: skip
    assert found is None and len(tg) == 1
    assert used == before + patience


# --------------------------------------------------------------------------- fallback


def _recorded_joints(
    monkeypatch: pytest.MonkeyPatch, raws: list[np.ndarray], max_candidates: int
) -> list[tuple[str, tuple[float, float, float]]]:
    """The joints ``dubins_fallback`` tries, in order, when no Dubins end is ever clear."""
    seen: list[tuple[str, tuple[float, float, float]]] = []
    start, goal = Pose(10.0, 10.0, 0.0), Pose(60.0, 10.0, 0.0)

    def never_clear(checker: object, a: Pose, b: Pose, *args: object) -> None:
        seen.append(("tail", a.as_tuple()) if b == goal else ("lead", b.as_tuple()))

    monkeypatch.setattr(fallback_module, "_free_end", never_clear)
    m = _open_map(goal, start)
    out = dubins_fallback(
        cached_checker(m), start, goal, 6.3, 0.15, raws, SmoothingConfig(),
        max_candidates=max_candidates, direct=False,
    )  # fmt: skip
    assert out is None
    return seen


@pytest.mark.parametrize("max_candidates", [0, 1, 3, 5, 64])
def test_the_fallback_tries_the_documented_joints_within_its_budget(
    monkeypatch: pytest.MonkeyPatch, max_candidates: int
) -> None:
    """Tails: nodes from the last but one backwards, with the heading of the edge into them;
    leads: nodes in driving order with the heading of the edge out; at most
    ``max_candidates`` of each over all tree paths."""
    rng = np.random.default_rng(3)
    raws = [10.0 + np.cumsum(rng.uniform(1.0, 5.0, (n, 2)), axis=0) for n in (4, 5)]
    tails: list[tuple[float, float, float]] = []
    leads: list[tuple[float, float, float]] = []
    for raw in raws:  # brute force: every inner node, as the docstring lists them
        for i in range(len(raw) - 2, 0, -1):
            d = raw[i] - raw[i - 1]
            tails.append((float(raw[i, 0]), float(raw[i, 1]), math.atan2(d[1], d[0])))
        for i in range(1, len(raw) - 1):
            d = raw[i + 1] - raw[i]
            leads.append((float(raw[i, 0]), float(raw[i, 1]), math.atan2(d[1], d[0])))
    want = [("tail", j) for j in tails[:max_candidates]]
    want += [("lead", j) for j in leads[:max_candidates]]
    assert _recorded_joints(monkeypatch, raws, max_candidates) == want


def test_without_the_direct_path_the_fallback_tries_only_tails_and_leads() -> None:
    """``direct=False``: no tree paths to join, so nothing, though open space is clear."""
    goal = Pose(70.0, 50.0, math.pi)
    m = _open_map(goal)
    checker = cached_checker(m)
    smoothing = SmoothingConfig()
    assert dubins_fallback(checker, START, goal, 6.3, 0.15, (), smoothing) is not None
    assert dubins_fallback(checker, START, goal, 6.3, 0.15, (), smoothing, direct=False) is None


def test_the_direct_dubins_path_is_the_shortest_over_every_radius(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """In open space every rounded word is clear: the answer is no longer than the
    shortest word at any single radius of ``CC_RADIUS_STEPS`` (here the smallest radius
    fits no word and the second's is 84 m, the third's 59 m)."""
    goal = Pose(91.4865858249546, 114.42143517142021, -1.2365633569717065)
    m = Map("open", (0.0, 0.0, 200.0, 200.0), (), Pose(100.0, 100.0, 0.0), goal)
    checker = cached_checker(m)
    v = VehicleParams()
    smoothing = SmoothingConfig(kappa_max=v.kappa_max, wheelbase=v.wheelbase)
    radius = 1.05 / v.kappa_max

    def direct() -> float:
        found = dubins_fallback(checker, m.start, goal, radius, 0.15, (), smoothing)
        return math.inf if found is None else found[0].length

    every = direct()
    singles = []
    for step in fallback_module.CC_RADIUS_STEPS:
        with monkeypatch.context() as patch:
            patch.setattr(fallback_module, "CC_RADIUS_STEPS", (step,))
            singles.append(direct())
    assert math.isfinite(every) and every <= min(singles) + 1e-9, (every, singles)


# --------------------------------------------------------------------------- config


def test_the_fallback_joints_never_exceed_the_fallbacks_own_budget() -> None:
    """With the escalation the joints only ever lower ``MAX_FALLBACK_CANDIDATES``."""
    for joints in (0, 7, 64, 65, 1000):
        got = ImprovedConfig(escalation_fallback_joints=joints).stage_budgets(20_000).candidates
        assert got == min(joints, MAX_FALLBACK_CANDIDATES)


def test_a_narrow_patience_of_zero_is_refused() -> None:
    """0 is "never give way" to the growth: as a narrow root's patience it would mean
    more patience for a narrower fan."""
    with pytest.raises(InputError, match=r"planner\.narrow_patience"):
        ImprovedConfig(narrow_patience=0)
    assert ImprovedConfig(narrow_patience=1).narrow_patience == 1


def test_a_detour_ratio_of_one_is_allowed() -> None:
    """The documented bound is ``>= 1``."""
    assert ImprovedConfig(reverse_detour_ratio=1.0).reverse_detour_ratio == 1.0
    with pytest.raises(InputError, match=r"planner\.reverse_detour_ratio: must be >= 1"):
        ImprovedConfig(reverse_detour_ratio=0.999)


# --------------------------------------------------------------------------- planner


def test_a_direct_dubins_path_at_exactly_the_ratio_is_kept() -> None:
    """``reverse_detour_ratio``: kept "when at most this multiple" of the Reeds-Shepp distance."""
    m = _open_map(Pose(50.0, 50.1, math.pi / 2))
    first = _solve(m, reverse=True)
    ratio = first.stats["dubins_detour_ratio"]
    assert ratio > ImprovedConfig().reverse_detour_ratio and stage_of(first) == "hybrid-a-star"
    res = _solve(m, reverse=True, reverse_detour_ratio=ratio)
    assert stage_of(res) == "dubins-fallback" and res.path.is_forward_only, res.message
    assert "Hybrid A*" not in res.message and "hybrid_expansions" not in res.stats


def test_a_narrow_root_never_waits_longer_than_the_root_patience(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A narrow fan gives a root less patience, never more."""
    from rrtdrive.maps import builtin_map
    from rrtdrive.tight_maps import garage_goal

    monkeypatch.setattr(improved_planner, "escalate", lambda failed, *a, **k: failed)
    m = dataclasses.replace(builtin_map("garage"), goal=garage_goal(0, 9, 9.0))
    cfg = ImprovedConfig()
    res = _solve(m, reverse=True, root_patience=100)
    assert res.stats["narrow_root"] == 1.0 and cfg.narrow_patience > 100
    assert "never left the goal pose in 100 iterations" in res.message, res.message
    assert res.stats["iterations"] == 100


def _spy_on(monkeypatch: pytest.MonkeyPatch, name: str, module: object = None) -> list[object]:
    """The calls of the improved planner's ``name`` (still called through) from now on.

    ``module``: where the planner looks ``name`` up (default its ``planner`` module).
    """
    calls: list[object] = []
    module = improved_planner if module is None else module
    real = getattr(module, name)

    def spy(*args: object, **kwargs: object) -> object:
        calls.append((args, kwargs))
        return real(*args, **kwargs)

    monkeypatch.setattr(module, name, spy)
    return calls


def test_without_the_fallback_no_tail_or_lead_runs_after_the_escalation(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """``dubins_fallback`` off: the failed escalation is the answer, nothing of the fallback."""
    calls = _spy_on(monkeypatch, "dubins_fallback", improved_ending)
    monkeypatch.setattr(improved_planner, "escalate", lambda failed, *a, **k: failed)
    res = _solve(_open_map(Pose(50.0, 50.1, math.pi / 2)), reverse=True,
                 disable=("dubins_fallback",))  # fmt: skip
    assert not res.success and calls == []
    assert "Dubins" not in res.message, res.message


def test_without_the_escalation_a_reversing_query_gets_no_hybrid_a_star(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The escalation is the planner's only way to reverse; switched off, it never runs."""
    calls = _spy_on(monkeypatch, "escalate")
    m = _open_map(Pose(50.0, 50.1, math.pi / 2))
    res = _solve(m, reverse=True, disable=("escalation",))
    assert calls == [] and res.success
    assert stage_of(res) != "hybrid-a-star" and res.path.is_forward_only
    assert verify_path(m, res.path, max_sharpness=0.2).ok


def test_the_expansion_guides_the_growth_only_when_both_ends_are_free_in_it() -> None:
    """A start 0.3 m beside a block that grows by 0.5 m a side: the growth keeps the map."""
    block = Obstacle((30.0, 10.0), (10.0, 2.0))
    start, goal = Pose(30.0, 12.2, 0.0), Pose(50.0, 25.0, math.pi)  # body 0.3 m above it
    m = Map("block", (0.0, 0.0, 60.0, 30.0), (block,), start, goal)
    body = footprint_polygon(start.as_tuple(), m.vehicle)
    assert body.distance(block.polygon()) == pytest.approx(0.3)
    assert body.intersects(block.grown(1.0).polygon())  # shapely: not free once grown
    assert not footprint_polygon(goal.as_tuple(), m.vehicle).intersects(block.grown(1.0).polygon())
    res = _solve(m, budget=Budget(max_iterations=30, max_time_s=600.0),
                 disable=("escalation", "dubins_fallback"))  # fmt: skip
    assert res.stats["expanded_obstacles"] == 1.0
    assert res.stats["expansion_used"] == 0.0


# --------------------------------------------------------------------------- detour


def test_a_tie_in_the_searchs_cost_keeps_the_detour() -> None:
    """``shorter_answer``: the escalation's path only when it costs *less*."""
    m = _open_map(Pose(70.0, 50.0, 0.0))
    detour = _solve(m)
    assert detour.success
    same = dataclasses.replace(detour, message="escalated", stats={"stage": "hybrid-a-star"})
    out = shorter_answer(same, detour, 0.0)
    assert out.path is detour.path and out.message.startswith(detour.message)
    assert "found a longer path" in out.message


def test_a_tree_path_under_the_ratio_reports_its_reeds_shepp_ratio() -> None:
    """The distance around the obstacles is looked up only above the limit: under it the
    ratio said is the path's length over the Reeds-Shepp distance."""
    from rrtdrive.maps import builtin_map

    m = builtin_map("overtake")  # the path is 1.0016 times the Reeds-Shepp distance
    res = _solve(m, reverse=True)
    assert res.success and stage_of(res) == "improved-rrt-connect", res.message
    radius = ImprovedConfig().dubins_radius_factor / m.vehicle.kappa_max
    shortest = reeds_shepp_distance(m.start, m.goal, radius)
    assert res.stats["tree_detour_ratio"] == pytest.approx(res.path.length / shortest)
    assert res.stats["tree_detour_ratio"] <= ImprovedConfig().reverse_detour_ratio


# --------------------------------------------------------------------------- diagnosis


def test_a_goal_25_m_clear_behind_is_no_pocket_whatever_the_search_proved() -> None:
    """Only a goal with less than 20 m behind it on every steady steering is named from the
    search's exhaustion (``ARRIVAL_POCKET_M``); with more the proof is no proof off its
    lattice. The goal's rear bumper is 25 m from the street's end (closed form: the bounds
    end at x = 60, the rear overhang is 0.895 m)."""
    v = VehicleParams()
    overhang = v.length - v.front_extent
    goal = Pose(60.0 - overhang - 25.0, 14.0, math.pi)
    m = Map("street", (0.0, 0.0, 60.0, 15.2), (), Pose(10.0, 1.2, 0.0), goal)
    checker = cached_checker(m)
    assert free_run(checker, goal, -1, 0.0, 40.0) == pytest.approx(25.0, abs=2e-3)
    assert no_forward_arrival(m, checker, goal) is None
    found = diagnose(PlanningProblem.from_map(m), no_approach=True)
    assert found is None or found.kind is not DiagnosisKind.NEEDS_REVERSE, found.message


def test_behind_the_start_is_more_than_a_metre_back_and_no_farther_aside() -> None:
    """``goal_behind``'s bounds, by hand: exactly 1 m back is not behind; 7 m back and 7 m
    aside is."""
    start = Pose(15.0, 2.0, 0.0)
    assert goal_behind(start, Pose(14.0, 2.0, 0.0)) is None
    assert goal_behind(start, Pose(13.5, 2.0, 0.0)) == 1.5
    assert goal_behind(start, Pose(8.0, 9.0, 0.0)) == 7.0
    assert goal_behind(start, Pose(8.0, -5.0, 0.0)) == 7.0
    assert goal_behind(start, Pose(8.0, 9.5, 0.0)) is None


def test_tight_clearance_is_not_claimed_where_a_short_edge_leaves() -> None:
    """A wall 3.2 m ahead of the start's nose: a long edge fails, but the growth's first
    edge (any length) need only pass somewhere; a 0.5 m one does, so "none leaves it" is
    false and no ``tight_clearance`` is named."""
    v = VehicleParams()
    start = Pose(10.0, 10.0, 0.0)
    nose = start.x + v.front_extent
    wall = Obstacle((nose + 3.2 + 0.5, 10.0), (1.0, 20.0))
    m = Map("wall", (0.0, 0.0, 40.0, 20.0), (wall,), start, Pose(5.0, 16.0, math.pi))
    checker = cached_checker(m)
    assert footprint_polygon(start.as_tuple(), v).distance(wall.polygon()) == pytest.approx(3.2)
    assert checker.edge_free((start.x, start.y), (start.x + 0.5, start.y))  # the reference
    assert tight_clearance(m, checker, start, m.goal) is None


def test_a_turn_of_100_degrees_to_a_goal_ahead_is_no_u_turn() -> None:
    """``u_turn``: headings more than 120 degrees apart, or a goal behind; neither here."""
    start, goal = Pose(10.0, 5.0, 0.0), Pose(40.0, 5.0, math.radians(100.0))
    m = Map("street", (0.0, 0.0, 60.0, 10.0), (), start, goal)
    checker = cached_checker(m)
    assert goal_behind(start, goal) is None
    assert u_turn(m, checker, start, goal) is None
    # Past 120 degrees the same street is one (a control: the street is too narrow).
    turned = Pose(40.0, 5.0, math.radians(130.0))
    found = u_turn(m, checker, start, turned)
    assert found is not None and found.kind is DiagnosisKind.U_TURN


@pytest.mark.parametrize("height", [13.07, 14.77])
def test_the_widest_place_is_the_boxs_own_width_off_the_grid(height: float) -> None:
    """In a 40 m x ``height`` box the widest free circle is ``height`` across (closed
    form); off the 0.1 m grid the sampled cells read up to 0.03 m less, which said "no
    place wider than 13.0 m" of a 13.07 m box and lost the last-resort line at 14.77 m."""
    h = height
    m = Map("box", (0.0, 0.0, 40.0, h), (), Pose(22.0, h / 2, 0.0), Pose(14.0, h / 2, math.pi))
    found = diagnose(PlanningProblem.from_map(m))
    assert found is not None and found.kind is DiagnosisKind.U_TURN
    assert found.numbers["widest_m"] == pytest.approx(h, abs=2e-3)
    least = u_turn_width(VehicleParams()) + 2 * 0.05
    assert ("one may fit that the search missed" in found.message) is (h >= least)


def test_tight_clearance_says_none_leaves_only_when_no_edge_leaves() -> None:
    """A 0.1 m post 1 m ahead of the nose and 0.6 m left of the centre line, else open.

    It blocks the one edge along the heading, which was all the finding tested (it said
    "so none leaves it"); most directions pass the growth's own edge test.
    """
    start = Pose(10.0, 10.0, 0.0)
    nose = start.x + VehicleParams().front_extent
    post = Obstacle((nose + 1.05, 10.6), (0.1, 0.1))
    m = Map("post", (0.0, 0.0, 60.0, 20.0), (post,), start, Pose(50.0, 10.0, 0.0))
    checker = cached_checker(m)
    leaving = [
        deg
        for deg in range(-85, 90, 5)
        if checker.edge_free(
            (start.x, start.y),
            (
                start.x + 2.0 * math.cos(math.radians(deg)),
                start.y + 2.0 * math.sin(math.radians(deg)),
            ),
        )
    ]
    assert len(leaving) > 20  # the reference: most directions leave (2 m edges)
    found = diagnose(PlanningProblem.from_map(m))
    assert found is None or found.kind is not DiagnosisKind.TIGHT_CLEARANCE, found.message


def test_with_reverse_no_search_proof_says_try_reverse() -> None:
    """``no_approach`` is a forward-only proof: with reverse allowed it is no finding."""
    walls = (Obstacle((32.5, 12.0), (15.0, 1.0)), Obstacle((32.5, 8.0), (15.0, 1.0)))
    m = Map("corridor", (0.0, 0.0, 40.0, 20.0), walls, Pose(5.0, 10.0, 0.0),
            Pose(29.0, 10.0, math.pi))  # fmt: skip
    forward = diagnose(PlanningProblem.from_map(m), no_approach=True)
    assert forward is not None and forward.kind is DiagnosisKind.NEEDS_REVERSE  # a control
    found = diagnose(PlanningProblem.from_map(m, reverse=True), no_approach=True)
    assert found is None or "try --reverse" not in found.message, found.message


def test_the_longest_steady_run_covers_an_eighth_lock() -> None:
    """Posts line both sides of the 1/8-lock arc from the start, 1.6 m off the rear axle's
    path: on that arc the car drives 20 m (shapely: no footprint on it meets a post), on
    the quarter-lock and straight arcs about 6 m; "at most X m on any steady steering"
    must count the eighth."""
    v = VehicleParams()
    start = Pose(10.0, 30.0, 0.0)
    kappa = 0.125 * v.kappa_max
    s = np.arange(0.0, 26.0, 0.5)
    yaw = kappa * s
    cx, cy = np.sin(yaw) / kappa, (1.0 - np.cos(yaw)) / kappa  # the rear axle's arc
    nx, ny = -np.sin(yaw), np.cos(yaw)
    posts = tuple(
        Obstacle((start.x + x + side * 1.6 * a, start.y + y + side * 1.6 * b), (0.2, 0.2))
        for x, y, a, b in zip(cx, cy, nx, ny, strict=True)
        for side in (-1.0, 1.0)
    )
    m = Map("arc", (0.0, 0.0, 100.0, 60.0), posts, start, Pose(90.0, 50.0, 0.0))
    checker = cached_checker(m)
    union = shapely.union_all([o.polygon() for o in posts])
    along_arc = [
        (start.x + math.sin(kappa * d) / kappa, start.y + (1 - math.cos(kappa * d)) / kappa,
         kappa * d)
        for d in np.arange(0.0, 20.01, 0.05)
    ]  # fmt: skip
    assert not any(footprint_polygon(p, v).intersects(union) for p in along_arc)
    assert free_run(checker, start, 1, kappa, 20.0) == 20.0
    assert free_run(checker, start, 1, 0.0, 20.0) < 10.0  # the straight is blocked sooner
    assert best_run(checker, start, 1, v, 20.0) == 20.0


def test_the_samples_fill_their_cells_uniformly() -> None:
    """``SampleSource``: a uniform point inside a uniform accepted cell, so the offsets
    within the cells are uniform on [0, 1)^2 (mean 1/2, both halves used)."""
    from rrtdrive.maps import builtin_map
    from rrtdrive.planning.sampling import SampleSource

    problem = PlanningProblem.from_map(builtin_map("parking_lot"))
    source = SampleSource(problem, reject=True)
    rng = np.random.default_rng(0)
    points = np.array([source.draw(rng) for _ in range(4000)])
    checker = problem.checker
    offsets = ((points - checker.grid_origin) / checker.resolution) % 1.0
    assert np.all(np.abs(offsets.mean(axis=0) - 0.5) < 0.03)
    assert np.all((offsets > 0.5).mean(axis=0) > 0.45)


def test_rrt_connect_joins_a_goal_exactly_one_step_ahead_at_once() -> None:
    """A start within one step (5 m, inclusive) of the goal connects before any iteration."""
    from rrtdrive.planning.rrt_connect import RRTConnectPlanner

    start, goal = Pose(10.0, 10.0, 0.0), Pose(15.0, 10.0, 0.0)
    m = Map("open", (0.0, 0.0, 40.0, 20.0), (), start, goal)
    assert math.dist(start.xy, goal.xy) == 5.0
    res = RRTConnectPlanner(step=5.0).solve(
        PlanningProblem.from_map(m), np.random.default_rng(0), BUDGET
    )
    assert res.success and res.iterations == 0
    np.testing.assert_array_equal(res.raw_path, [[10.0, 10.0], [15.0, 10.0]])
