"""A root that provably cannot grow is known before any iteration (``improved/boxed.py``).

The proof is checked against the growth's own edge test: wherever it says a root is
boxed in, every edge the growth could try at that root (any length, any direction
within 90 degrees of the heading) fails :meth:`CollisionChecker.edge_free`.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

from rrtdrive.maps import Map, Obstacle, builtin_map
from rrtdrive.planning.base import PlanningProblem, cached_checker
from rrtdrive.planning.improved import ImprovedConfig, ImprovedRRTConnect
from rrtdrive.planning.improved import planner as improved_planner
from rrtdrive.planning.improved.boxed import open_share, root_boxed_in
from rrtdrive.tight_maps import garage_goal, kerbside_map
from rrtdrive.types import Budget, Pose
from rrtdrive.verify import verify_path

BUDGET = Budget(max_iterations=20_000, max_time_s=600.0)


def _edges_at(pose: Pose, rng: np.random.Generator, count: int) -> np.ndarray:
    """Points ``q`` an edge at the root may reach: within 90 deg of its heading, 0-10 m."""
    theta = pose.yaw + rng.uniform(-math.pi / 2, math.pi / 2, count)
    length = np.concatenate([rng.uniform(1e-6, 0.05, count // 4), rng.uniform(0.05, 10.0, count)])
    theta = np.resize(theta, len(length))
    return np.column_stack([pose.x + length * np.cos(theta), pose.y + length * np.sin(theta)])


def _assert_no_edge_passes(m: Map, pose: Pose, seed: int) -> None:
    checker = cached_checker(m)
    root = (pose.x, pose.y)
    for q in _edges_at(pose, np.random.default_rng(seed), 300):
        # As the start (edges leave it) and as the goal (edges are driven into it,
        # from a point behind it: the same direction of travel).
        assert not checker.edge_free(root, tuple(q)), (pose, q)
        behind = (2 * pose.x - q[0], 2 * pose.y - q[1])
        assert not checker.edge_free(behind, root), (pose, behind)


def _near_poses(m: Map, seed: int, count: int) -> list[Pose]:
    """Poses scattered about the map's start and goal, free ones only."""
    rng = np.random.default_rng(seed)
    checker = cached_checker(m)
    out = []
    for base in (m.start, m.goal):
        for _ in range(count):
            pose = Pose(
                base.x + rng.normal(0.0, 0.3), base.y + rng.normal(0.0, 0.2),
                base.yaw + rng.normal(0.0, 0.05) + (math.pi if rng.random() < 0.3 else 0.0),
            )  # fmt: skip
            if checker.pose_free(pose.as_tuple()):
                out.append(pose)
    return out


@pytest.mark.parametrize("factor", [1.4, 1.6, 2.0, 2.5])
def test_every_pose_called_boxed_in_lets_no_growth_edge_pass(factor: float) -> None:
    m = kerbside_map(factor)
    checker = cached_checker(m)
    boxed = [p for p in _near_poses(m, 7, 40) if root_boxed_in(checker, p)]
    assert len(boxed) >= 5  # the kerbside goal and its neighbours are
    for i, pose in enumerate(boxed):
        _assert_no_edge_passes(m, pose, i)


@settings(max_examples=40, deadline=None)
@given(
    gap=st.floats(0.15, 1.0), side=st.floats(0.05, 0.6), yaw=st.floats(-0.2, 0.2),
    seed=st.integers(0, 1000),
)  # fmt: skip
def test_a_car_nosed_up_to_a_wall_is_proven_only_when_no_edge_passes(
    gap: float, side: float, yaw: float, seed: int
) -> None:
    m, pose = _slot(gap, side, yaw)
    checker = cached_checker(m)
    if checker.pose_free(pose.as_tuple()) and root_boxed_in(checker, pose):
        _assert_no_edge_passes(m, pose, seed)


def _slot(gap: float, side: float, yaw: float) -> tuple[Map, Pose]:
    """A dead-end slot: walls ``side`` beside the body and one ``gap`` ahead of its bumper."""
    width = 1.8 + 2 * side
    obstacles = (
        Obstacle((10.5, width / 2), (1.0, width + 2.0), 0.0),
        Obstacle((5.0, -0.25), (12.0, 0.5), 0.0),
        Obstacle((5.0, width + 0.25), (12.0, 0.5), 0.0),
    )
    m = Map("slot", (-10.0, -5.0, 20.0, width + 5.0), obstacles, Pose(-8.0, width + 3.0, 0.0),
            Pose(-8.0, -3.0, 0.0))  # fmt: skip
    return m, Pose(10.0 - gap - 3.405, width / 2, yaw)


def test_a_tight_slot_is_proven_and_a_roomy_one_is_not() -> None:
    m, pose = _slot(0.2, 0.1, 0.0)
    assert root_boxed_in(cached_checker(m), pose)
    _assert_no_edge_passes(m, pose, 0)
    # Facing out of the slot the same pose has all the room it needs.
    assert not root_boxed_in(cached_checker(m), Pose(pose.x, pose.y, math.pi))
    m, pose = _slot(3.0, 0.6, 0.0)
    assert not root_boxed_in(cached_checker(m), pose)


def test_an_open_pose_is_not_boxed_in() -> None:
    m = builtin_map("parking_lot")
    checker = cached_checker(m)
    assert not root_boxed_in(checker, m.start) and not root_boxed_in(checker, m.goal)
    # A garage bay with room ahead of the bumper: not provable (the growth decides).
    garage = builtin_map("garage")
    assert not root_boxed_in(cached_checker(garage), garage_goal(0, 9, 9.0))


def test_the_kerbside_goal_skips_the_growth_for_the_same_path(monkeypatch) -> None:  # noqa: ANN001
    m = builtin_map("kerbside")
    problem = PlanningProblem.from_map(m, reverse=True)
    res = ImprovedRRTConnect().solve(problem, np.random.default_rng(0), BUDGET)
    assert res.success, res.message
    assert res.stats["root_boxed_in"] == 1.0 and res.stats["stuck_root"] == 1.0
    assert "the goal tree cannot leave the goal pose" in res.message
    assert res.iterations == int(res.stats["hybrid_expansions"])  # no growth iteration
    assert verify_path(m, res.path, max_sharpness=0.2).ok
    # Without the proof the pair waits out root_patience, then the same escalation.
    monkeypatch.setattr(improved_planner, "boxed_end", lambda *a, **k: "")
    waited = ImprovedRRTConnect(narrow_fan=0.0).solve(problem, np.random.default_rng(0), BUDGET)
    assert waited.success and "root_boxed_in" not in waited.stats
    assert waited.iterations == ImprovedConfig().root_patience + res.iterations
    np.testing.assert_allclose(waited.path.samples, res.path.samples, atol=1e-9)


def test_the_papers_pipeline_and_the_ablations_grow_as_before() -> None:
    m = builtin_map("kerbside")
    problem = PlanningProblem.from_map(m)
    paper = ImprovedRRTConnect(escalation=False).solve(
        problem, np.random.default_rng(0), Budget(max_iterations=3000, max_time_s=600.0)
    )
    assert "root_boxed_in" not in paper.stats and paper.iterations == 3000
    no_obtuse = ImprovedRRTConnect(disable=("obtuse_parent",)).solve(
        problem, np.random.default_rng(0), Budget(max_iterations=3000, max_time_s=600.0)
    )
    assert "root_boxed_in" not in no_obtuse.stats



def test_a_narrow_fan_gives_way_sooner_for_the_same_path() -> None:
    # A garage bay: room ahead of the bumper for a few directions only (not provable),
    # so the pair gives way after narrow_patience iterations, not root_patience.
    import dataclasses

    m = dataclasses.replace(builtin_map("garage"), goal=garage_goal(0, 9, 9.0))
    checker = cached_checker(m)
    share = open_share(checker, m.goal)
    assert 0.0 < share < ImprovedConfig().narrow_fan and not root_boxed_in(checker, m.goal)
    problem = PlanningProblem.from_map(m, reverse=True)
    res = ImprovedRRTConnect().solve(problem, np.random.default_rng(0), BUDGET)
    assert res.success and res.stats["narrow_root"] == 1.0
    assert res.stats["goal_open_share"] == share
    assert f"never left the goal pose in {ImprovedConfig().narrow_patience} iterations" in (
        res.message
    )
    full = ImprovedRRTConnect(narrow_fan=0.0).solve(problem, np.random.default_rng(0), BUDGET)
    assert "narrow_root" not in full.stats
    assert full.iterations - res.iterations == (
        ImprovedConfig().root_patience - ImprovedConfig().narrow_patience
    )
    np.testing.assert_allclose(full.path.samples, res.path.samples, atol=1e-9)
    assert verify_path(m, res.path, max_sharpness=0.2).ok


@settings(max_examples=30, deadline=None)
@given(x=st.floats(2.0, 28.0), y=st.floats(2.0, 6.0), yaw=st.floats(-math.pi, math.pi))
def test_the_open_share_is_the_exact_capsule_count(x: float, y: float, yaw: float) -> None:
    # The field's shortcut never changes the share: against shapely alone, direction by
    # direction (the capsule of a zero-length edge, clear of obstacles and bounds).
    m = kerbside_map(1.6)
    checker = cached_checker(m)
    pose = Pose(x, y, yaw)
    back, front, radius = checker.edge_capsule
    count = math.ceil(math.pi * max(front, back) / 0.05)
    angles = yaw + (np.arange(count) + 0.5) * (math.pi / count) - math.pi / 2
    union = shapely.union_all([o.polygon() for o in m.obstacles])
    walls = shapely.box(*m.bounds)
    opened = 0
    for a in angles:
        u = np.array([math.cos(a), math.sin(a)])
        seg = shapely.LineString([np.array([x, y]) - back * u, np.array([x, y]) + front * u])
        inside = walls.buffer(-radius).contains(seg)
        opened += bool(inside and union.distance(seg) >= radius)
    assert open_share(checker, pose) == pytest.approx(opened / count, abs=1.5 / count)
