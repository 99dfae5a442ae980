"""Goals a few centimetres from the start.

Straight ahead, the default planner drives the straight line however short it is (a
goal under 0.111 m ahead used to get a 61 m Dubins loop: the direct connection's
heading legs were skipped below 0.05 m). With reverse allowed, a forward Dubins path
much longer than the Reeds-Shepp distance is kept only when the reversing search finds
nothing shorter (``ImprovedConfig.reverse_detour_ratio``); a forward tree path too
(``reverse_detour_tree``, on by default), unless the obstacles make every path that long.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

import rrtdrive.planning.improved.planner as improved_planner
from rrtdrive.maps import Map, builtin_map
from rrtdrive.planning import PlanningProblem
from rrtdrive.planning.hybrid.escalation import stage_of
from rrtdrive.planning.improved import ImprovedConfig, ImprovedRRTConnect
from rrtdrive.planning.improved.detour import around_obstacles, detour_ratio
from rrtdrive.types import Budget, InputError, Path, PlanStatus, Pose
from rrtdrive.verify import verify_path

BUDGET = Budget(max_time_s=600.0)
START = Pose(50.0, 50.0, 0.0)


def _open_map(goal: Pose, start: Pose = START) -> Map:
    return Map("open", (0.0, 0.0, 100.0, 100.0), (), start, goal)


def _solve(m: Map, reverse: bool = False, **options):
    problem = PlanningProblem.from_map(m, reverse=reverse)
    return ImprovedRRTConnect(**options).solve(problem, np.random.default_rng(0), BUDGET)


@settings(max_examples=40, deadline=None)
@given(
    distance=st.floats(2e-6, 0.3),
    heading=st.floats(-math.pi, math.pi),
)
def test_a_goal_straight_ahead_is_the_straight_line(distance: float, heading: float) -> None:
    start = Pose(START.x, START.y, heading)
    goal = Pose(
        start.x + distance * math.cos(heading), start.y + distance * math.sin(heading), heading
    )
    m = _open_map(goal, start)
    res = _solve(m)
    assert res.success, res.message
    assert res.stats["direct_connection"] == 1.0
    segment = shapely.LineString([(start.x, start.y), (goal.x, goal.y)])
    rows = res.path.samples
    assert res.path.length == pytest.approx(segment.length, abs=1e-9)
    assert max(segment.distance(shapely.Point(x, y)) for x, y in rows[:, :2]) < 1e-9
    assert np.allclose(rows[:, 3], 0.0)
    assert verify_path(m, res.path, max_sharpness=0.2).ok


def test_a_goal_a_few_centimetres_off_the_line_still_needs_the_loop_forward() -> None:
    # Forward only a car cannot side-step 1 mm in 0.1 m: the loop is the answer.
    m = _open_map(Pose(50.1, 50.001, 0.0))
    res = _solve(m)
    assert res.success and res.path.length > 40.0, res.message
    assert verify_path(m, res.path, max_sharpness=0.2).ok


@pytest.mark.parametrize(
    "goal", [Pose(50.1, 50.001, 0.0), Pose(50.1, 50.0, 0.01), Pose(50.0, 50.1, math.pi / 2)]
)
def test_with_reverse_a_close_goal_is_not_a_forward_loop(goal: Pose) -> None:
    m = _open_map(goal)
    res = _solve(m, reverse=True)
    assert res.success, res.message
    assert stage_of(res) == "hybrid-a-star"
    assert res.path.length < 12.0 and len(res.path.cusps) >= 1
    assert res.stats["dubins_detour_ratio"] > ImprovedConfig().reverse_detour_ratio
    assert "found only a forward detour (direct Dubins path, " in res.message, res.message
    assert verify_path(m, res.path, max_sharpness=0.2).ok
    # The ratio switched off: the forward loop as before.
    loop = _solve(m, reverse=True, reverse_detour_ratio=math.inf)
    assert stage_of(loop) == "dubins-fallback" and loop.path.length > 40.0


def test_the_detour_is_kept_when_the_reversing_search_finds_nothing(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # The search answers with the failure it escalated from, as when it finds nothing.
    monkeypatch.setattr(improved_planner, "escalate", lambda failed, *args, **kwargs: failed)
    m = _open_map(Pose(50.0, 50.1, math.pi / 2))
    res = _solve(m, reverse=True)
    assert res.status is PlanStatus.SOLVED and stage_of(res) == "dubins-fallback"
    assert "; Hybrid A* (with reverse) found none (0 expansions)" in res.message
    assert verify_path(m, res.path, max_sharpness=0.2).ok


def _escalation_finds_500_m(monkeypatch: pytest.MonkeyPatch) -> None:
    """The escalation solves, but with a 500 m straight (longer than any detour here)."""
    real = improved_planner.escalate

    def longer(failed, *args, **kwargs):
        out = real(failed, *args, **kwargs)
        rows = np.column_stack([np.linspace(0, 500, 2001), np.zeros((2001, 3)), np.ones(2001)])
        return dataclasses.replace(out, path=Path(rows, rows[[0, -1], :2]))

    monkeypatch.setattr(improved_planner, "escalate", longer)


def test_a_detour_kept_over_a_longer_escalation_is_the_fallback_s(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # The escalation solves, but longer than the detour: the detour's path is returned and
    # its stage is the fallback's (the merged counters said "hybrid-a-star"), with the
    # clearance the detour's check kept.
    _escalation_finds_500_m(monkeypatch)
    m = _open_map(Pose(50.0, 50.1, math.pi / 2))
    res = _solve(m, reverse=True)
    assert res.success and "found a longer path (500.0 m)" in res.message, res.message
    assert stage_of(res) == "dubins-fallback" and res.path.length < 100.0
    assert res.stats["body_clearance_m"] == pytest.approx(0.15)


def test_forward_only_a_kept_detour_says_the_search_was_forward_only(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # escalation_first="always" runs the detour rule forward only too: what the search
    # found is said with its own gear (it said "with reverse").
    _escalation_finds_500_m(monkeypatch)
    m = _open_map(Pose(50.0, 50.1, math.pi / 2))
    res = _solve(m, escalation_first="always")
    assert res.success and len(res.path.cusps) == 0
    assert "Hybrid A* (forward only) found a longer path (500.0 m)" in res.message, res.message


@pytest.mark.parametrize("value", [0.5, math.nan, -1.0])
def test_a_bad_detour_ratio_is_named(value: float) -> None:
    with pytest.raises(InputError, match=r"planner\.reverse_detour_ratio"):
        ImprovedConfig(reverse_detour_ratio=value)


def _parking_lot_goal_93() -> Map:
    # Random goal 93 of experiments/random_goals.py (parking_lot, seed 1): the paper stage's
    # tree path loops 186 m round the lot; with one cusp the goal is 76 m away.
    m = builtin_map("parking_lot")
    goal = Pose(53.201107188452056, 36.30433181948137, 2.404196106990101)
    return dataclasses.replace(m, goal=goal)


def test_with_reverse_a_tree_path_detour_gives_way_to_a_shorter_reversing_path() -> None:
    m = _parking_lot_goal_93()
    kept = _solve(m, reverse=True, reverse_detour_tree=False)  # the paper stage's answer
    assert stage_of(kept) == "improved-rrt-connect" and len(kept.path.cusps) == 0
    res = _solve(m, reverse=True)  # the default
    assert res.success and stage_of(res) == "hybrid-a-star", res.message
    assert len(res.path.cusps) >= 1
    assert res.path.length < kept.path.length / ImprovedConfig().reverse_detour_ratio
    assert res.stats["tree_detour_ratio"] > ImprovedConfig().reverse_detour_ratio
    assert f"found only a forward detour (tree path, {kept.path.length:.1f} m, " in res.message
    assert "times the distance around the obstacles to the goal" in res.message
    assert verify_path(m, res.path, max_sharpness=0.2).ok
    # Forward only the tree path is the answer, as before.
    forward = _solve(m)
    assert stage_of(forward) == "improved-rrt-connect"
    assert forward.path.length == pytest.approx(kept.path.length)


def test_a_tree_path_long_only_round_the_obstacles_is_no_detour() -> None:
    # Random start 23 (parking_lot, seed 1): the tree path is 1.67 times the Reeds-Shepp
    # distance, but the lot's rows make any path long: 1.14 times the distance around
    # them. The search is not asked (it found nothing shorter, in 38 ms against 9 ms).
    m = builtin_map("parking_lot")
    start = Pose(69.78935706830814, 12.867321231716943, -0.7776164294215255)
    m = dataclasses.replace(m, start=start)
    res = _solve(m, reverse=True)
    assert res.success and stage_of(res) == "improved-rrt-connect", res.message
    problem = PlanningProblem.from_map(m, reverse=True)
    around = around_obstacles(problem)
    radius = ImprovedConfig().dubins_radius_factor / problem.vehicle.kappa_max
    limit = ImprovedConfig().reverse_detour_ratio
    assert detour_ratio(res.path.length, m.start, m.goal, radius) > limit
    assert res.stats["tree_detour_ratio"] == pytest.approx(res.path.length / around)
    assert res.stats["tree_detour_ratio"] <= limit
    assert "hybrid_expansions" not in res.stats and "Hybrid A*" not in res.message


def test_a_tree_path_detour_is_kept_over_a_longer_escalation(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    _escalation_finds_500_m(monkeypatch)
    m = _parking_lot_goal_93()
    res = _solve(m, reverse=True)
    assert res.success and "found a longer path (500.0 m)" in res.message, res.message
    assert stage_of(res) == "improved-rrt-connect" and len(res.path.cusps) == 0
    assert verify_path(m, res.path, max_sharpness=0.2).ok


def _escalation_finds_shorter_by(
    monkeypatch: pytest.MonkeyPatch, metres: float, reverse: float
) -> list:
    """The escalation solves ``metres`` shorter than goal 93's tree path: a straight ahead,
    a gear change and ``reverse`` metres back."""
    real = improved_planner.escalate
    tree: list[float] = []

    def with_cusp(failed, *args, **kwargs):
        out = real(failed, *args, **kwargs)
        ahead_m = tree[0] - metres - reverse
        x = np.linspace(0.0, ahead_m, 1001)
        ahead = np.column_stack([x, np.zeros((len(x), 3)), np.ones(len(x))])
        xb = np.linspace(ahead_m, ahead_m - reverse, 101)
        back = np.column_stack([xb, np.zeros((len(xb), 3)), -np.ones(len(xb))])
        rows = np.vstack([ahead, back])
        return dataclasses.replace(out, path=Path(rows, rows[[0, len(x), -1], :2]))

    monkeypatch.setattr(improved_planner, "escalate", with_cusp)
    return tree


@pytest.mark.parametrize(
    ("metres", "reverse", "given_way"), [(5.0, 2.0, False), (10.0, 2.0, True), (40.0, 45.0, False)]
)
def test_a_detour_gives_way_only_to_a_path_that_costs_the_search_less(
    monkeypatch: pytest.MonkeyPatch, metres: float, reverse: float, given_way: bool
) -> None:
    # The search's own weights: a reverse metre twice a forward one, a gear change 5 m.
    # 5 m shorter with 2 m in reverse costs 2 m more than the 186 m forward loop; 10 m
    # shorter costs 3 m less; 40 m shorter but 45 m of it in reverse costs 10 m more.
    m = _parking_lot_goal_93()
    tree = _escalation_finds_shorter_by(monkeypatch, metres, reverse)
    kept = _solve(m, reverse=True, reverse_detour_tree=False)
    tree.append(kept.path.length)
    res = _solve(m, reverse=True)
    assert res.success
    if given_way:
        assert len(res.path.cusps) == 1, res.message
        assert res.path.length == pytest.approx(kept.path.length - metres)
    else:
        assert stage_of(res) == "improved-rrt-connect" and len(res.path.cusps) == 0
        assert res.path.length == pytest.approx(kept.path.length)
        more = kept.path.length + reverse + 5.0 - metres
        assert (
            f"a path {metres:.1f} m shorter that costs more: {more:.1f} m against "
            f"{kept.path.length:.1f} m, a reverse metre weighed as 2, a gear change as 5 m"
        ) in res.message, res.message


def test_a_bad_tree_detour_switch_is_named() -> None:
    with pytest.raises(InputError, match=r"planner\.reverse_detour_tree"):
        ImprovedConfig(reverse_detour_tree="yes")  # type: ignore[arg-type]


START_74 = Pose(17.020617447974907, 61.37785589494178, -2.8994299614665837)


def test_a_direct_dubins_detour_is_measured_against_the_reeds_shepp_distance_alone() -> None:
    # Random start 74 (parking_lot, seed 1): the direct Dubins path is 98.0 m, 1.65 times
    # the Reeds-Shepp distance but under 1.5 times the distance around the rows; the
    # escalation's forward path is 84.4 m. The distance around counts for tree paths only.
    m = builtin_map("parking_lot")
    m = dataclasses.replace(m, start=START_74)
    res = _solve(m, reverse=True)
    assert res.success and stage_of(res) == "hybrid-a-star", res.message
    assert res.stats["dubins_detour_ratio"] > ImprovedConfig().reverse_detour_ratio
    assert "direct Dubins path, 98.0 m" in res.message and "obstacles aside" in res.message
    assert res.path.length < 90.0 and len(res.path.cusps) == 0
    assert verify_path(m, res.path, max_sharpness=0.2).ok
