"""Mutation guards for the planner seam and the three baselines (RRT, RRT-Connect, RRT*).

Each test pins a behaviour the baselines promise against an independent reference:
straight-line closed forms in an empty map, brute force over the final tree, the
circle through three points, shapely bodies, or the same algorithm without its
optimisations fed the same random stream.
"""

from __future__ import annotations

import dataclasses
import json
import math
import time
import warnings

import numpy as np
import pytest
from shapely.geometry import LineString, Polygon, box

from rrtdrive.cli import plan_to_json
from rrtdrive.maps import Map, Obstacle, builtin_map
from rrtdrive.planning import make_planner
from rrtdrive.planning.base import PlanningProblem, Stopwatch, failure, polyline_path
from rrtdrive.planning.edges import EdgeTester, exact_edge_free
from rrtdrive.planning.options import MAX_NODES, MAX_TREE_STEP_M, check_known
from rrtdrive.planning.result import (
    run_query,
    search_result,
    solved,
    solved_result,
    straight_ahead,
    straight_ahead_result,
)
from rrtdrive.planning.rrt_star import RRTStarPlanner
from rrtdrive.planning.sampling import SampleSource
from rrtdrive.types import (
    Budget,
    InputError,
    InputWarning,
    Path,
    PlanResult,
    PlanStatus,
    Pose,
    Tree,
    VehicleParams,
)

BUDGET = Budget(max_iterations=4000, max_time_s=120.0)
#: An empty 200 m x 100 m field: every edge between points far from its border is free.
OPEN = Map("open", (0.0, 0.0, 200.0, 100.0), (), Pose(60.0, 50.0, 0.0), Pose(100.0, 50.0, 0.0))
#: Two blocks across the way, so that trees bend and RRT* has something to rewire.
BLOCKS = Map(
    "blocks",
    (0.0, 0.0, 80.0, 40.0),
    (Obstacle((30.0, 14.0), (4.0, 28.0)), Obstacle((50.0, 26.0), (4.0, 28.0))),
    Pose(8.0, 30.0, 0.0),
    Pose(72.0, 10.0, 0.0),
)


def _run(name: str, m: Map, seed: int, budget: Budget = BUDGET, **options: object) -> PlanResult:
    problem = PlanningProblem.from_map(m)
    return make_planner(name, **options).solve(problem, np.random.default_rng(seed), budget)


def _on_segment(points: np.ndarray, a: np.ndarray, b: np.ndarray, tol: float = 1e-9) -> bool:
    """Whether every point lies on the segment a-b (distance to its line, and between ends)."""
    d = b - a
    u = d / np.hypot(*d)
    rel = points - a
    aside = np.abs(rel[:, 0] * u[1] - rel[:, 1] * u[0])
    along = rel @ u
    return bool(np.all(aside < tol) and np.all(along > -tol) and np.all(along < np.hypot(*d) + tol))


def _tree_edges(tree: Tree) -> tuple[np.ndarray, np.ndarray]:
    """(parent positions, child positions) of every non-root node."""
    child = np.flatnonzero(tree.parents >= 0)
    return tree.nodes[tree.parents[child]], tree.nodes[child]


def _path_costs(tree: Tree) -> np.ndarray:
    """Each node's path length from the root along the parent pointers (brute force)."""
    cost = np.full(len(tree), np.nan)
    cost[0] = 0.0

    def walk(k: int) -> float:
        if np.isnan(cost[k]):
            p = int(tree.parents[k])
            cost[k] = walk(p) + math.dist(tree.nodes[k], tree.nodes[p])
        return float(cost[k])

    for k in range(len(tree)):
        walk(k)
    return cost


# ----------------------------------------------------------------------------- RRT


def test_rrt_with_a_strong_goal_bias_runs_straight_at_the_goal_in_steps():
    """Goal samples steer the tree: in an empty field the path is the straight line in 5 m steps."""
    res = _run("rrt", OPEN, 0, goal_bias=0.999)
    assert res.success, res.message
    start, goal = OPEN.start.xy, OPEN.goal.xy
    raw = res.raw_path
    assert _on_segment(raw, start, goal)
    # 40 m in steps of 5 m: the start, 7 intermediate nodes 5 m apart, then the goal.
    np.testing.assert_allclose(np.hypot(*np.diff(raw, axis=0).T), 5.0, atol=1e-9)
    assert len(raw) == 9


@pytest.mark.parametrize("seed", range(3))
def test_rrt_edges_never_exceed_one_step(seed: int):
    """Every RRT edge, the goal edge included, is at most ``step`` long (the extension rule)."""
    res = _run("rrt", BLOCKS, seed, step=3.0)
    assert res.success, res.message
    parents, children = _tree_edges(res.trees[0])
    assert np.hypot(*(children - parents).T).max() <= 3.0 + 1e-9


def test_rrt_start_exactly_one_step_from_the_goal_connects_at_once():
    """A goal exactly ``step`` metres ahead is within one step: the path is the single edge."""
    m = OPEN.with_query(goal=Pose(65.0, 50.0, 0.0))
    for name in ("rrt", "rrt-connect"):
        res = _run(name, m, 0)
        assert res.success and res.iterations == 0, (name, res.message)
        np.testing.assert_array_equal(res.raw_path, [[60.0, 50.0], [65.0, 50.0]])


@pytest.mark.parametrize("name", ["rrt", "rrt-connect"])
def test_a_goal_within_one_step_but_behind_a_wall_is_not_joined_directly(name: str):
    """The direct start-goal edge is tested: a wall between them forces a detour."""
    wall = Obstacle((30.0, 20.0), (0.6, 12.0))
    m = Map("wall", (0.0, 0.0, 60.0, 40.0), (wall,), Pose(24.0, 20.0, 0.0), Pose(35.0, 20.0, 0.0))
    res = _run(name, m, 0, step=12.0)
    assert res.success, res.message
    assert len(res.raw_path) > 2
    assert not LineString(res.raw_path).intersects(box(29.7, 14.0, 30.3, 26.0))


# ----------------------------------------------------------------------------- RRT-Connect


def test_rrt_connect_meets_in_one_iteration_in_an_empty_field():
    """Extend once, then the goal tree connects greedily in whole steps to the new node."""
    res = _run("rrt-connect", OPEN, 3)
    assert res.success and res.iterations == 1, res.message
    start_tree, goal_tree = res.trees
    assert len(start_tree) == 2  # the root and the one extension
    new = start_tree.nodes[1]
    assert math.isclose(math.dist(new, OPEN.start.xy), 5.0)
    gap = math.dist(new, OPEN.goal.xy)
    steps = math.ceil(gap / 5.0)
    assert len(goal_tree) == 1 + steps and res.stats["connect_steps"] == steps
    # The connect walks the straight line from the goal to the new node.
    assert _on_segment(goal_tree.nodes, OPEN.goal.xy, new)
    np.testing.assert_array_equal(res.raw_path[:2], [OPEN.start.xy, new])
    assert _on_segment(res.raw_path[1:], new, OPEN.goal.xy)


def test_rrt_connect_goal_bias_samples_the_other_trees_root():
    """With a goal bias the start tree steps straight at the goal tree's root."""
    res = _run("rrt-connect", OPEN, 0, goal_bias=0.999)
    assert res.success and res.iterations == 1, res.message
    assert _on_segment(res.raw_path, OPEN.start.xy, OPEN.goal.xy)
    np.testing.assert_allclose(np.hypot(*np.diff(res.raw_path, axis=0).T), 5.0, atol=1e-9)


def test_rrt_connect_connect_loop_checks_the_safety_cap(monkeypatch: pytest.MonkeyPatch):
    """A cap met during a greedy connect ends the query as ``timeout``, not as solved."""
    calls = {"n": 0}
    original = Stopwatch.expired

    def expired(self: Stopwatch) -> bool:
        calls["n"] += 1
        if calls["n"] == 3:  # the while check, then the connect loop's first two checks
            self.capped = True
        return original(self)

    monkeypatch.setattr(Stopwatch, "expired", expired)
    res = _run("rrt-connect", OPEN, 3)
    assert res.status is PlanStatus.TIMEOUT
    assert res.iterations == 1 and res.stats["connect_steps"] == 2


# ----------------------------------------------------------------------------- RRT*


def _star(seed: int, rewire_radius: float, **options: object) -> PlanResult:
    return _run(
        "rrt-star", BLOCKS, seed, max_nodes=160, goal_radius=12.0, rewire_radius=rewire_radius,
        **options,
    )  # fmt: skip


@pytest.mark.parametrize("seed", [0, 1])
def test_rrt_star_costs_no_more_than_the_plain_tree_through_the_same_samples(seed: int):
    """Choose-parent and rewiring move no node and only lower costs.

    With a rewiring radius too small to hold any neighbour, RRT* is plain RRT: the same
    samples give the same node positions. With the radius, every node's path length
    (recomputed from the parent pointers) is at most its plain one, some strictly less,
    and the path to the goal is no longer.
    """
    plain = _star(seed, 1e-6)
    star = _star(seed, 8.0)
    assert plain.success and star.success
    tp, ts = plain.trees[0], star.trees[0]
    np.testing.assert_array_equal(tp.nodes[:-1], ts.nodes[:-1])  # the goal is attached last
    cp, cs = _path_costs(tp), _path_costs(ts)
    assert np.all(cs[:-1] <= cp[:-1] + 1e-9)
    assert np.sum(cs[:-1]) < np.sum(cp[:-1]) - 1.0
    assert cs[-1] <= cp[-1] + 1e-9
    assert math.isclose(star.stats["path_cost_m"], cs[-1], rel_tol=1e-9)
    assert star.stats["rewires"] > 0 and plain.stats["rewires"] == 0


@pytest.mark.parametrize("seed", [0, 1])
def test_rrt_star_edges_are_free_and_within_the_radii(seed: int):
    """Every edge is free in its driving direction and no longer than the rewiring radius.

    The goal edge may be longer (up to ``goal_radius``) and may need the exact test.
    """
    star = _star(seed, 5.0, step=2.0)
    checker = PlanningProblem.from_map(BLOCKS).checker
    parents, children = _tree_edges(star.trees[0])
    lengths = np.hypot(*(children - parents).T)
    goal = BLOCKS.goal.xy
    for a, b, length in zip(parents, children, lengths, strict=True):
        if np.array_equal(b, goal):
            assert length <= 12.0 + 1e-9
            assert checker.edge_free(a, b) or exact_edge_free(checker, a, b)
        else:
            assert length <= 5.0 + 1e-9
            assert checker.edge_free(a, b)


@pytest.mark.parametrize(
    ("seed", "goal_radius"), [(0, 12.0), (1, 12.0), (2, 4.0), (3, 30.0), (4, None), (5, None)]
)
def test_rrt_star_attaches_the_goal_by_the_cheapest_free_link(seed: int, goal_radius: float | None):
    """Brute force over the final tree: the goal's parent is the cheapest free link.

    It minimises cost-to-come plus distance among the nodes within ``goal_radius`` (by
    default the rewiring radius) whose edge to the goal is free.
    """
    options = {} if goal_radius is None else {"goal_radius": goal_radius}
    star = _run("rrt-star", BLOCKS, seed, max_nodes=160, rewire_radius=8.0, **options)
    goal_radius = 8.0 if goal_radius is None else goal_radius
    assert star.success, star.message
    tree = star.trees[0]
    checker = PlanningProblem.from_map(BLOCKS).checker
    goal = BLOCKS.goal.xy
    cost = _path_costs(tree)
    best = math.inf
    for k in range(len(tree) - 1):
        d = math.dist(tree.nodes[k], goal)
        if d <= goal_radius and (
            checker.edge_free(tree.nodes[k], goal) or exact_edge_free(checker, tree.nodes[k], goal)
        ):
            best = min(best, cost[k] + d)
    assert math.isclose(cost[-1], best, rel_tol=1e-9)
    assert math.dist(tree.nodes[tree.parents[-1]], goal) <= goal_radius + 1e-9


def test_rrt_star_goal_bias_grows_along_the_line_to_the_goal():
    """With a strong goal bias in an empty field the path is the straight line in 2 m steps."""
    m = OPEN.with_query(goal=Pose(80.0, 50.0, 0.0))
    res = _run("rrt-star", m, 0, goal_bias=0.999, max_nodes=12, goal_radius=2.0)
    assert res.success, res.message
    assert _on_segment(res.raw_path, m.start.xy, m.goal.xy)
    np.testing.assert_allclose(np.hypot(*np.diff(res.raw_path, axis=0).T), 2.0, atol=1e-9)


# ----------------------------------------------------------------------------- seams


def test_polyline_path_headings_and_corner_curvature():
    """Rows take their segment's heading; a corner's kappa is 1 / the circumradius there."""
    pts = np.array([[0.0, 0.0], [4.0, 0.0], [4.0, 3.0], [1.0, 7.0]])
    path = polyline_path(pts)
    rows, vertex = path.samples, []
    for p in pts:
        vertex.append(int(np.flatnonzero(np.all(np.isclose(rows[:, :2], p), axis=1))[0]))
    headings = [math.atan2(*(b - a)[::-1]) for a, b in zip(pts[:-1], pts[1:], strict=True)]
    for seg, (i, j) in enumerate(zip(vertex[:-1], vertex[1:], strict=True)):
        np.testing.assert_allclose(rows[i:j, 2], headings[seg])
    np.testing.assert_allclose(rows[-1, 2], headings[-1])

    def circum(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> float:
        sides = [math.dist(a, b), math.dist(b, c), math.dist(c, a)]
        area = Polygon([a, b, c]).area
        return 4.0 * area / math.prod(sides)

    assert math.isclose(rows[vertex[1], 3], circum(*pts[:3]))  # a left turn: positive
    assert math.isclose(rows[vertex[2], 3], circum(*pts[1:]))
    others = np.setdiff1d(np.arange(len(rows)), vertex[1:3])
    assert np.all(rows[others, 3] == 0.0)
    assert np.all(rows[:, 4] == 1.0)


def test_polyline_path_gaps_stay_within_spacing_after_json_rounding():
    """Rows rounded to the plan JSON's 6 decimals are still at most 0.25 m apart.

    Segments a whole number of spacings long are the edge case: exact division leaves
    no room for the rounding.
    """
    rng = np.random.default_rng(0)
    for _ in range(40):
        a = np.round(rng.uniform(-50.0, 50.0, 2), 6)
        angle = rng.uniform(-math.pi, math.pi)
        b = a + 0.25 * int(rng.integers(1, 40)) * np.array([math.cos(angle), math.sin(angle)])
        rows = np.round(polyline_path(np.array([a, b])).samples, 6)
        assert np.hypot(*np.diff(rows[:, :2], axis=0).T).max() <= 0.25
    one = polyline_path(np.array([[1.0, 2.0]]))
    np.testing.assert_array_equal(one.samples, [[1.0, 2.0, 0.0, 0.0, 1.0]])


def test_stopwatch_cap_is_reached_at_the_deadline_and_set_up_moves_it():
    """The cap counts as reached at exactly ``max_time_s``; set-up time does not count."""
    ticks = iter([0.0, 2.0])
    watch = Stopwatch(Budget(max_time_s=2.0), clock=lambda: next(ticks))
    assert watch.expired() and watch.capped
    ticks = iter([0.0, 1.0, 4.0, 4.5, 4.5, 5.0, 5.0])
    watch = Stopwatch(Budget(max_time_s=2.0), clock=lambda: next(ticks))
    with watch.setup():  # 3 s of set-up between 1.0 and 4.0
        pass
    assert not watch.expired()  # 1.5 s of planning so far
    assert watch.elapsed() == 1.5
    assert watch.expired() and watch.setup_s == 3.0


# ----------------------------------------------------------------------------- textbook references
#
# The papers' algorithms without the planners' optimisations (no lazy edge tests, no
# child lists, costs recomputed from the parent pointers), fed the same random stream:
# each iteration draws ``rng.random()`` for the goal bias, then a sample from a
# SampleSource of its own. They must build the very same trees.


def _steer(a: np.ndarray, q: np.ndarray, step: float) -> tuple[np.ndarray, bool]:
    d = math.dist(a, q)
    if d <= step:
        return np.array(q, dtype=float), True
    return a + (q - a) * (step / d), False


def _nearest(nodes: list[np.ndarray], q: np.ndarray) -> int:
    return min(range(len(nodes)), key=lambda k: (math.dist(nodes[k], q), k))


def _reference_rrt(
    problem: PlanningProblem, seed: int, step: float, goal_bias: float, reject: bool, budget: int
) -> tuple[np.ndarray, np.ndarray]:
    """LaValle's RRT with goal bias; returns (nodes, parents)."""
    checker, start, goal = problem.checker, problem.start.xy, problem.goal.xy
    rng, samples = np.random.default_rng(seed), SampleSource(problem, reject)

    def goal_free(a: np.ndarray) -> bool:
        return checker.edge_free(a, goal) or exact_edge_free(checker, a, goal)

    nodes, parents = [start], [-1]
    if math.dist(start, goal) <= step and goal_free(start):
        return np.array([start, goal]), np.array([-1, 0])
    for _ in range(budget):
        goal_sample = rng.random() < goal_bias
        q = goal if goal_sample else samples.draw(rng)
        i = _nearest(nodes, q)
        new, reached = _steer(nodes[i], q, step)
        if math.dist(nodes[i], new) < 1e-9:
            continue
        if goal_sample and reached:
            if goal_free(nodes[i]):
                nodes.append(goal)
                parents.append(i)
                break
            continue
        if not checker.edge_free(nodes[i], new):
            continue
        nodes.append(new)
        parents.append(i)
        if math.dist(new, goal) <= step and goal_free(new):
            nodes.append(goal)
            parents.append(len(nodes) - 2)
            break
    return np.array(nodes), np.array(parents)


def _reference_rrt_star(
    problem: PlanningProblem, seed: int, step: float, radius: float, goal_radius: float,
    max_nodes: int, goal_bias: float,
) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """Karaman & Frazzoli's RRT* grown to ``max_nodes`` (goal last); returns (nodes, parents)."""
    checker, start, goal = problem.checker, problem.start.xy, problem.goal.xy
    rng, samples = np.random.default_rng(seed), SampleSource(problem, True)
    nodes, parents = [start], [-1]

    def cost(k: int) -> float:
        return 0.0 if parents[k] < 0 else cost(parents[k]) + math.dist(nodes[k], nodes[parents[k]])

    while True:
        if len(nodes) >= max_nodes - 1:
            links = [
                (cost(k) + math.dist(p, goal), k) for k, p in enumerate(nodes)
                if math.dist(p, goal) <= goal_radius
                and (checker.edge_free(p, goal) or exact_edge_free(checker, p, goal))
            ]  # fmt: skip
            if links:
                nodes.append(goal)
                parents.append(min(links)[1])
                return np.array(nodes), np.array(parents)
        goal_sample = rng.random() < goal_bias
        q = goal if goal_sample else samples.draw(rng)
        i = _nearest(nodes, q)
        new, reached = _steer(nodes[i], q, step)
        if math.dist(nodes[i], new) < 1e-9 or (goal_sample and reached):
            continue
        if not checker.edge_free(nodes[i], new):
            continue
        near = [k for k, p in enumerate(nodes) if math.dist(p, new) <= radius]
        parent, best = i, cost(i) + math.dist(nodes[i], new)
        for k in near:  # the cheapest free connection
            c = cost(k) + math.dist(nodes[k], new)
            if c < best - 1e-9 and checker.edge_free(nodes[k], new):
                parent, best = k, c
        nodes.append(new)
        parents.append(parent)
        j = len(nodes) - 1
        for k in near:  # rewire the neighbours that get cheaper through the new node
            c = best + math.dist(new, nodes[k])
            if c < cost(k) - 1e-9 and checker.edge_free(new, nodes[k]):
                parents[k] = j


def _reference_rrt_connect(
    problem: PlanningProblem, seed: int, step: float, goal_bias: float, budget: int
) -> tuple[tuple[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]:
    """Kuffner & LaValle's RRT-Connect; returns the start and goal trees as (nodes, parents)."""
    checker, start, goal = problem.checker, problem.start.xy, problem.goal.xy
    rng, samples = np.random.default_rng(seed), SampleSource(problem, True)
    trees = {"start": ([start], [-1]), "goal": ([goal], [-1])}

    def extend(side: str, i: int, q: np.ndarray) -> tuple[str, int]:
        nodes, parents = trees[side]
        new, reached = _steer(nodes[i], q, step)
        if math.dist(nodes[i], new) < 1e-9:
            return "trapped", -1
        if side == "start":
            ok = checker.edge_free(nodes[i], new)
        elif i == 0:
            ok = checker.edge_free(new, goal) or exact_edge_free(checker, new, goal)
        else:
            ok = checker.edge_free(new, nodes[i])  # driven towards the goal
        if not ok:
            return "trapped", -1
        nodes.append(new)
        parents.append(i)
        return ("reached" if reached else "advanced"), len(nodes) - 1

    a, b = "start", "goal"
    for _ in range(budget):
        q = trees[b][0][0] if rng.random() < goal_bias else samples.draw(rng)
        outcome, new = extend(a, _nearest(trees[a][0], q), q)
        if outcome != "trapped":
            target = trees[a][0][new]
            i = _nearest(trees[b][0], target)
            while (got := extend(b, i, target))[0] == "advanced":
                i = got[1]
            if got[0] == "reached":
                break
        a, b = b, a
    return tuple((np.array(n), np.array(p)) for n, p in (trees["start"], trees["goal"]))


def _assert_same_tree(tree: Tree, nodes: np.ndarray, parents: np.ndarray) -> None:
    np.testing.assert_allclose(tree.nodes, nodes, rtol=0, atol=1e-9)
    np.testing.assert_array_equal(tree.parents, parents)


@pytest.mark.parametrize(
    ("seed", "reject", "bias"), [(0, True, 0.05), (1, False, 0.05), (2, True, 0.3)]
)
def test_rrt_builds_the_textbook_tree(seed: int, reject: bool, bias: float):
    """RRT's tree is LaValle's RRT on the same samples (bounds-uniform without rejection)."""
    problem = PlanningProblem.from_map(BLOCKS)
    res = _run("rrt", BLOCKS, seed, step=4.0, goal_bias=bias, reject_samples=reject)
    nodes, parents = _reference_rrt(problem, seed, 4.0, bias, reject, BUDGET.max_iterations)
    _assert_same_tree(res.trees[0], nodes, parents)
    assert res.success


@pytest.mark.parametrize(("seed", "bias"), [(0, 0.0), (1, 0.0), (2, 0.2)])
def test_rrt_connect_builds_the_textbook_trees(seed: int, bias: float):
    """RRT-Connect's trees are Kuffner & LaValle's on the same samples.

    The trees alternate; after each extension the other one connects greedily.
    """
    problem = PlanningProblem.from_map(BLOCKS)
    res = _run("rrt-connect", BLOCKS, seed, step=4.0, goal_bias=bias)
    ref = _reference_rrt_connect(problem, seed, 4.0, bias, BUDGET.max_iterations)
    assert res.success
    for tree, (nodes, parents) in zip(res.trees, ref, strict=True):
        _assert_same_tree(tree, nodes, parents)


@pytest.mark.parametrize(
    ("seed", "radius", "goal_radius"), [(0, 8.0, 12.0), (1, 15.0, 15.0), (2, 6.0, 3.0)]
)
def test_rrt_star_builds_the_textbook_tree(seed: int, radius: float, goal_radius: float):
    """RRT*'s lazy choose-parent and rewiring give the tree of the plain algorithm."""
    problem = PlanningProblem.from_map(BLOCKS)
    res = _run(
        "rrt-star", BLOCKS, seed, max_nodes=120, rewire_radius=radius, goal_radius=goal_radius
    )
    nodes, parents = _reference_rrt_star(problem, seed, 2.0, radius, goal_radius, 120, 0.05)
    assert res.success
    _assert_same_tree(res.trees[0], nodes, parents)


# ----------------------------------------------------------------------------- the query seam


def test_precheck_names_the_end_that_cannot_be_planned():
    """A start yaw past MAX_YAW is an invalid start; a goal inside a car is an invalid goal."""
    m = builtin_map("overtake")
    checker = PlanningProblem.from_map(m).checker
    assert checker.pose_free((5.0, 44.0, 1e7))  # the body test alone would let it pass
    rng = np.random.default_rng(0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", InputWarning)  # the degrees warning of a huge yaw
        wild = PlanningProblem(m, checker, Pose(5.0, 44.0, 1e7), m.goal)
    res = make_planner("rrt").solve(wild, rng, BUDGET)
    assert res.status is PlanStatus.INVALID_START and "yaw" in res.message
    inside = Pose(49.0, 44.0, 0.0)
    car = m.obstacles[2]
    body = box(
        inside.x - VehicleParams().rear_overhang, inside.y - 0.9,
        inside.x + VehicleParams().front_extent, inside.y + 0.9,
    )  # fmt: skip
    parked = box(car.center[0] - car.size[0] / 2, car.center[1] - car.size[1] / 2,
                 car.center[0] + car.size[0] / 2, car.center[1] + car.size[1] / 2)  # fmt: skip
    assert body.intersects(parked)
    for name in ("rrt", "rrt-connect", "rrt-star"):
        res = make_planner(name).solve(PlanningProblem(m, checker, m.start, inside), rng, BUDGET)
        assert res.status is PlanStatus.INVALID_GOAL and res.message.startswith("goal:"), name
        assert res.iterations == 0 and len(res.path) == 0


def test_run_query_turns_an_answer_found_past_the_cap_into_a_timeout():
    """A search that met the safety cap but answered ``solved`` ends as ``timeout``.

    The timeout keeps the search's work: its raw path, iterations and statistics.
    """
    problem = PlanningProblem.from_map(builtin_map("overtake"))
    raw = np.array([[5.0, 44.0], [50.0, 47.0], [92.0, 44.0]])
    seen: list[Stopwatch] = []

    def search(watch: Stopwatch) -> PlanResult:
        seen.append(watch)
        while not watch.expired():  # a cap of 1 ns: met at once
            pass
        return solved_result("demo", problem, raw, (), 17, watch, {"x": 1.0})

    cap = Budget(max_iterations=10, max_time_s=1e-9)
    res = run_query("demo", problem, cap, search, rng=np.random.default_rng(0))
    assert seen and res.status is PlanStatus.TIMEOUT and not res.success
    assert res.iterations == 17 and len(res.path) == 0
    np.testing.assert_array_equal(res.raw_path, raw)
    assert res.message.startswith("stopped by the 1e-09 s safety cap after 17 iterations")
    # A capped watch ends a baseline search in a timeout even when it holds a path.
    ticks = iter([0.0, 5.0])
    watch = Stopwatch(Budget(max_time_s=1.0), clock=lambda: next(ticks, 5.0))
    assert watch.expired()
    res = search_result("demo", problem, raw, (), 3, watch, cap, {})
    assert res.status is PlanStatus.TIMEOUT and res.iterations == 3


def test_stopwatch_sums_every_set_up_block():
    """Two set-up blocks: both are set-up time, neither is planning time."""
    ticks = iter([0.0, 1.0, 2.0, 3.0, 5.0, 6.0])
    watch = Stopwatch(Budget(max_time_s=10.0), clock=lambda: next(ticks))
    with watch.setup():  # 1.0 -> 2.0
        pass
    with watch.setup():  # 3.0 -> 5.0
        pass
    assert watch.setup_s == 3.0
    assert watch.elapsed() == 3.0  # 6 s of wall time less 3 s of set-up


def test_problem_refuses_a_checker_of_other_bounds_and_a_non_bool_reverse():
    """Same obstacles, other bounds: the checker would plan past this map's edge."""
    m = OPEN
    wider = Map("wider", (0.0, 0.0, 300.0, 100.0), (), m.start, m.goal)
    with pytest.raises(InputError, match=r"^problem\.checker: it was built for another map"):
        PlanningProblem(m, PlanningProblem.from_map(wider).checker, m.start, m.goal)
    checker = PlanningProblem.from_map(m).checker
    with pytest.raises(InputError, match=r"^reverse: expected True or False, got 1"):
        PlanningProblem(m, checker, m.start, m.goal, reverse=1)
    flag = PlanningProblem(m, checker, m.start, m.goal, reverse=np.bool_(True)).reverse
    assert flag is True  # a plain bool: json.dumps takes it
    # Checkers are cached per map: later problems on either map reuse the first ones'.
    other = PlanningProblem.from_map(wider).checker
    assert PlanningProblem.from_map(m).checker is checker
    assert PlanningProblem.from_map(wider).checker is other


def test_failure_reports_its_planning_time_and_nodes():
    """A failed result's time is the stopwatch's, its nodes those of its trees."""
    ticks = iter([1.0, 3.5])
    watch = Stopwatch(Budget(max_time_s=10.0), clock=lambda: next(ticks))
    tree = Tree(np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]]), np.array([-1, 0, 1]))
    res = failure(
        "demo", PlanStatus.NO_PATH_IN_BUDGET, watch, "m", trees=(tree, tree), iterations=4
    )
    assert res.planning_time_s == 2.5 and res.nodes == 6 and res.iterations == 4


@pytest.mark.parametrize("name", ["rrt", "rrt-connect", "rrt-star"])
def test_a_start_that_is_the_goal_is_a_path_of_zero_metres(name: str):
    """Start == goal: solved before any search, two rows at the pose, no tree."""
    m = OPEN.with_query(goal=OPEN.start)
    res = _run(name, m, 0)
    assert res.success and res.iterations == 0 and res.nodes == 0 and res.trees == ()
    assert res.path.length == 0.0
    np.testing.assert_array_equal(res.path.samples, [[60.0, 50.0, 0.0, 0.0, 1.0]] * 2)


def test_set_up_met_during_the_search_is_reported_apart_from_planning_time(
    monkeypatch: pytest.MonkeyPatch,
):
    """A search's set-up block counts in ``setup_time_s``, not in ``planning_time_s``."""
    problem = PlanningProblem.from_map(OPEN)
    now = [100.0]
    monkeypatch.setattr(time, "perf_counter", lambda: now[0])

    def search(watch: Stopwatch) -> PlanResult:
        with watch.setup():
            now[0] += 3.0  # a map's first finer grid, say
        now[0] += 1.0  # the search proper
        return solved_result("demo", problem, np.array([OPEN.start.xy, OPEN.goal.xy]), (), 1,
                             watch, {})  # fmt: skip

    res = run_query("demo", problem, BUDGET, search, rng=np.random.default_rng(0))
    assert res.success
    assert res.setup_time_s == 3.0 and res.planning_time_s == 1.0


# ----------------------------------------------------------------------------- the JSON of a plan


def test_plan_json_reports_times_gears_and_counts_as_given():
    """``plan_to_json``: each field from its own source (no time folded into another)."""
    rows = np.array([
        [0.0, 0.0, 0.0, 0.0, 1.0], [1.0, 0.0, 0.0, 0.0, 1.0], [2.0, 0.0, 0.0, 0.0, 1.0],
        [2.0, 0.0, 0.0, 0.0, -1.0], [1.2345674, 0.0, 0.0, 0.0, -1.0],
    ])  # fmt: skip
    waypoints = np.array([[0.0, 0.0], [2.0, 0.0], [1.2345674, 0.0]])
    solved = PlanResult(
        status=PlanStatus.SOLVED, planner="rrt", path=Path(rows, waypoints), raw_path=waypoints,
        trees=(), nodes=31, iterations=12, planning_time_s=0.25, message="ok",
        stats={"diagnosis_time_s": 0.5}, setup_time_s=1.5,
    )  # fmt: skip
    doc = json.loads(json.dumps(plan_to_json(solved, 7, "m", reverse=True)))
    assert (doc["status"], doc["success"], doc["reverse"]) == ("solved", True, True)
    times = (doc["planning_time_s"], doc["setup_time_s"], doc["diagnosis_time_s"])
    assert times == (0.25, 1.5, 0.5)
    assert (doc["nodes"], doc["iterations"], doc["seed"]) == (31, 12, 7)
    assert [r[4] for r in doc["path"]] == [1.0, 1.0, 1.0, -1.0, -1.0]  # the gear column
    assert doc["cusps"] == 1
    assert doc["waypoints"][-1] == [1.234567, 0.0]  # 6 decimals
    assert math.isclose(doc["length_m"], 2.0 + (2.0 - 1.2345674), abs_tol=1e-6)
    failed = dataclasses.replace(solved, status=PlanStatus.TIMEOUT, path=Path.empty())
    doc = plan_to_json(failed, 7, "m")
    assert (doc["status"], doc["success"], doc["length_m"], doc["cusps"]) == (
        "timeout", False, None, None,
    )  # fmt: skip


# ----------------------------------------------------------------------------- sampling


def test_rejection_samples_cover_exactly_the_cells_where_the_car_can_stand():
    """Every grid cell where the car can stand (and reachable) is drawn, and no other.

    The accepted cells by brute force: the cell centres that ``point_free`` accepts and
    that are not provably cut off from the start. Points fill their cells, not just centres.
    """
    m = Map("strip", (0.0, 0.0, 16.0, 2.2), (), Pose(3.0, 1.1, 0.0), Pose(9.0, 1.1, 0.0))
    problem = PlanningProblem.from_map(m)
    checker = problem.checker
    h, origin = checker.resolution, np.asarray(checker.grid_origin)
    nx, ny = checker.clearance_grid.shape
    start = (3.0, 1.1)
    accepted = {
        (i, j)
        for i in range(nx)
        for j in range(ny)
        if checker.point_free(*(origin + (np.array([i, j]) + 0.5) * h))
        and not checker.provably_disconnected(start, tuple(origin + (np.array([i, j]) + 0.5) * h))
    }
    assert 50 < len(accepted) < 1000
    source, rng = SampleSource(problem, reject=True), np.random.default_rng(1)
    pts = np.array([source.draw(rng) for _ in range(40 * len(accepted))])
    cells = np.floor((pts - origin) / h).astype(int)
    assert set(map(tuple, cells)) == accepted
    frac = (pts - origin) / h - cells
    assert frac.min() < 0.02 and frac.max() > 0.98


def test_without_reject_or_without_accepted_cells_samples_fill_the_bounds():
    """No accepted cell (a start inside a wall): samples are uniform in the bounds, no error."""
    wall = Obstacle((30.0, 20.0), (10.0, 10.0))
    m = Map("o", (0.0, 0.0, 60.0, 40.0), (wall,), Pose(10.0, 10.0, 0.0), Pose(50.0, 10.0, 0.0))
    base = PlanningProblem.from_map(m)
    boxed = PlanningProblem(m, base.checker, Pose(30.0, 20.0, 0.0), m.goal)
    for problem, reject in ((boxed, True), (base, False)):
        rng = np.random.default_rng(2)
        source = SampleSource(problem, reject)
        pts = np.array([source.draw(rng) for _ in range(2000)])
        assert pts.min(axis=0).tolist() == pytest.approx([0.0, 0.0], abs=0.2)
        assert pts.max(axis=0).tolist() == pytest.approx([60.0, 40.0], abs=0.2)
        inside = (np.abs(pts[:, 0] - 30.0) < 5.0) & (np.abs(pts[:, 1] - 20.0) < 5.0)
        assert 0.02 < inside.mean() < 0.06  # the wall's 100 m2 of 2400 m2: about 4 %


# ----------------------------------------------------------------------------- edges and options


class _RecordingChecker:
    """A checker whose body test records the poses and refuses those near ``blocked``."""

    def __init__(self, blocked: tuple[float, float] | None = None) -> None:
        self.poses: list[np.ndarray] = []
        self.blocked = blocked

    def poses_free(self, poses: np.ndarray) -> np.ndarray:
        self.poses.append(np.array(poses))
        if self.blocked is None:
            return np.ones(len(poses), dtype=bool)
        return np.hypot(poses[:, 0] - self.blocked[0], poses[:, 1] - self.blocked[1]) > 0.051


@pytest.mark.parametrize("length", [0.05, 1.0, 2.37])
def test_exact_edge_test_checks_poses_a_tenth_of_a_metre_apart_heading_along(length: float):
    """Both ends, gaps of at most 0.1 m, the edge's heading; any blocked pose fails the edge."""
    angle = 2.2
    a = np.array([3.0, -1.0])
    b = a + length * np.array([math.cos(angle), math.sin(angle)])
    rec = _RecordingChecker()
    assert exact_edge_free(rec, a, b)
    poses = np.concatenate(rec.poses)
    along = (poses[:, :2] - a) @ np.array([math.cos(angle), math.sin(angle)])
    order = np.sort(along)
    assert order[0] == pytest.approx(0.0, abs=1e-12) and order[-1] == pytest.approx(length)
    assert np.diff(order).max() <= 0.1 + 1e-12
    np.testing.assert_allclose(poses[:, 2], angle)
    rng = np.random.default_rng(3)
    for t in (0.0, 1.0, *rng.uniform(0.0, 1.0, 6)):  # the ends, and points between poses
        spot = a + t * (b - a)
        assert not exact_edge_free(_RecordingChecker((spot[0], spot[1])), a, b), t
    assert not exact_edge_free(rec, a, a)  # no heading: a zero-length edge is not certified


def test_goal_edge_asks_the_exact_test_only_when_the_fast_one_fails():
    """A clear goal edge costs one fast test and no exact one."""
    problem = PlanningProblem.from_map(OPEN)
    edges = EdgeTester(problem.checker, OPEN.goal.xy)
    assert edges.goal_edge(np.array([90.0, 50.0]))
    assert edges.stats() == {"edge_checks": 1, "exact_edge_checks": 0}


def test_option_bounds_and_types():
    """Options: bounds inclusive where documented, refusals name the field, plain types kept."""
    assert make_planner("rrt", step=MAX_TREE_STEP_M).step == MAX_TREE_STEP_M
    with pytest.raises(InputError, match=r"^planner\.step: must be at most 1000 m"):
        make_planner("rrt", step=MAX_TREE_STEP_M + 0.5)
    with pytest.raises(InputError, match=r"^planner\.reject_samples: expected true or false"):
        make_planner("rrt-star", reject_samples=1)
    planner = make_planner("rrt-connect", goal_bias=0, exact_goal_edge=np.bool_(False))
    assert type(planner.goal_bias) is float and planner.exact_goal_edge is False
    assert RRTStarPlanner(max_nodes=MAX_NODES).max_nodes == MAX_NODES
    with pytest.raises(InputError, match=r"^planner\.max_nodes: must be at most"):
        RRTStarPlanner(max_nodes=MAX_NODES + 1)
    # The first unknown name in sorted order (26 unknown names: not the first by chance).
    names = [chr(c) * 2 for c in range(ord("z"), ord("a") - 1, -1)]
    with pytest.raises(InputError, match=r"^planner\.smooth\.aa: unknown field"):
        check_known([*names, "degree"], ["degree"], "planner.smooth", "field of X")


# ----------------------------------------------------------------------------- close goals


def test_straight_ahead_means_ahead_on_the_heading_line_facing_the_same_way():
    """Closed forms: behind is not ahead; 5e-6 m aside is beyond the 1e-6 tolerance."""
    a = Pose(2.0, 3.0, 0.7)
    along = np.array([math.cos(0.7), math.sin(0.7)])
    ahead = Pose(*(a.xy + 2.0 * along), 0.7)
    assert straight_ahead(a, ahead)
    assert not straight_ahead(a, Pose(*(a.xy - 2.0 * along), 0.7))
    side = a.xy + 2.0 * along + 5e-6 * np.array([-along[1], along[0]])
    assert not straight_ahead(a, Pose(side[0], side[1], 0.7))


def test_straight_ahead_result_keeps_its_clearance_and_spacing():
    """The straight line: rows <= 0.25 m apart, the goal's own heading last, its clearance kept.

    A box 0.3 m beside the car's side: the line keeps 0.1 m, not 0.5 m.
    """
    side = 50.0 + VehicleParams().width / 2 + 0.3
    m = Map(
        "beside", (0.0, 0.0, 200.0, 100.0), (Obstacle((68.0, side + 1.0), (10.0, 2.0)),),
        Pose(60.0, 50.0, 0.0), Pose(63.3, 50.0, 5e-7),
    )  # fmt: skip
    problem = PlanningProblem.from_map(m)
    watch = Stopwatch(BUDGET)
    res = straight_ahead_result("demo", problem, watch, 0.1, {"nodes": 4.0})
    assert res is not None and res.success and res.nodes == 4
    rows = res.path.samples
    assert np.hypot(*np.diff(rows[:, :2], axis=0).T).max() <= 0.25
    assert rows[0, 2] == 0.0 and rows[-1, 2] == 5e-7
    assert straight_ahead_result("demo", problem, watch, 0.5, {}) is None


def test_solved_keeps_the_counts_and_time_it_is_given():
    """``solved(nodes=..., planning_time_s=...)`` reports those, not the trees' or the clock's."""
    ticks = iter([0.0, 9.0])
    watch = Stopwatch(BUDGET, clock=lambda: next(ticks))
    path = polyline_path(np.array([[0.0, 0.0], [3.0, 4.0]]))
    res = solved("demo", watch, path, path.waypoints, (), 2, "m", {}, nodes=11, planning_time_s=0.5)
    assert (res.nodes, res.planning_time_s, res.iterations) == (11, 0.5, 2)
    res = solved_result("demo", PlanningProblem.from_map(OPEN), path.waypoints, (), 2, watch, {})
    assert res.stats["waypoints"] == 2 and res.stats["raw_length_m"] == 5.0


def test_an_end_the_checker_refuses_but_the_map_accepts_is_still_named(
    monkeypatch: pytest.MonkeyPatch,
):
    """Within the grid's error margin the checker may refuse a pose the map's own check takes.

    The failure then names the end and says its body collides, not an empty reason.
    """
    problem = PlanningProblem.from_map(OPEN)
    monkeypatch.setattr(problem.checker, "pose_free", lambda pose, *args, **kwargs: False)
    res = make_planner("rrt").solve(problem, np.random.default_rng(0), BUDGET)
    assert res.status is PlanStatus.INVALID_START
    assert res.message == "start: the car's body collides there"


# ----------------------------------------------------------------------------- a real bug


def _connect_with_goal_bias() -> tuple[PlanResult, PlanningProblem]:
    problem = PlanningProblem.from_map(builtin_map("overtake"))
    planner = make_planner("rrt-connect", goal_bias=0.3)
    return planner.solve(problem, np.random.default_rng(4), Budget(max_iterations=3000)), problem


def test_rrt_connect_stops_when_the_start_tree_reaches_the_goal():
    """A start tree that reaches the goal joins the trees: the raw path ends at its first visit."""
    res, problem = _connect_with_goal_bias()
    assert res.success
    at_goal = np.flatnonzero(np.all(res.raw_path == problem.goal.xy, axis=1))
    assert at_goal.tolist() == [len(res.raw_path) - 1]
