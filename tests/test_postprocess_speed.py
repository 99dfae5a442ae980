"""Post-processing's memos give the old answers bit for bit.

The edge answers and screens one ``make_drivable`` call shares between its two
pruning attempts (each attempt still counts its own ``edge_checks``), against
caches of their own per attempt (the old code, set up here by monkeypatching);
on tree paths of the default planner for random starts of parking_lot that fail
post-processing with reverse, and random goals it solves forward.
"""

from __future__ import annotations

import dataclasses
import sys
from pathlib import Path as FsPath

import numpy as np
import pytest

import rrtdrive.planning.improved.planner as improved_planner
from rrtdrive.maps import builtin_map
from rrtdrive.planning import PlanningProblem
from rrtdrive.planning.base import cached_checker
from rrtdrive.planning.improved import ImprovedRRTConnect
from rrtdrive.planning.smoothing import checks, make_drivable
from rrtdrive.types import Budget

sys.path.insert(0, str(FsPath(__file__).resolve().parents[1] / "experiments"))
from random_goals import draw_goals  # noqa: E402


def _tree_paths() -> list[tuple]:
    """``(raw, start, goal, config)`` of every ``make_drivable`` call of a few queries."""
    calls: list[tuple] = []
    real = improved_planner.make_drivable

    def record(raw, start, goal, checker, cfg):  # noqa: ANN001, ANN202
        calls.append((np.array(raw), start, goal, cfg))
        return real(raw, start, goal, checker, cfg)

    base = builtin_map("parking_lot")
    starts = draw_goals("parking_lot", 100, 1, "start")
    goals = draw_goals("parking_lot", 100, 1, "goal")
    queries = [(dataclasses.replace(base, start=starts[i]), True) for i in (30, 31, 33, 44)]
    queries += [(dataclasses.replace(base, goal=goals[i]), False) for i in (3, 9, 12)]
    planner = ImprovedRRTConnect(escalation=False, dubins_fallback=False)
    improved_planner.make_drivable = record
    try:
        for m, reverse in queries:
            problem = PlanningProblem.from_map(m, reverse=reverse)
            planner.solve(problem, np.random.default_rng(0), Budget(max_time_s=60.0))
    finally:
        improved_planner.make_drivable = real
    return calls


@pytest.fixture(scope="module")
def tree_paths() -> list[tuple]:
    return _tree_paths()


def _same(a, b) -> None:  # noqa: ANN001 - two SmoothingResults
    assert (a.ok, a.message, a.rounds, a.stats) == (b.ok, b.message, b.rounds, b.stats)
    assert a.samples.tobytes() == b.samples.tobytes()
    assert np.asarray(a.key_points).tobytes() == np.asarray(b.key_points).tobytes()
    assert np.asarray(a.control_points).tobytes() == np.asarray(b.control_points).tobytes()
    assert repr(a.max_curvature) == repr(b.max_curvature)
    assert repr(a.max_sharpness) == repr(b.max_sharpness)


def test_shared_edge_answers_give_the_old_results(tree_paths, monkeypatch) -> None:
    checker = cached_checker(builtin_map("parking_lot"))
    assert any(not make_drivable(raw, s, g, checker, cfg).ok for raw, s, g, cfg in tree_paths)
    assert any(make_drivable(raw, s, g, checker, cfg).ok for raw, s, g, cfg in tree_paths)
    new = [make_drivable(raw, s, g, checker, cfg) for raw, s, g, cfg in tree_paths]
    real_init = checks.EdgeCache.__init__

    def own_memos(self, view) -> None:  # noqa: ANN001 - the old code: a cache per attempt
        view.edge_memo, view.screen_memo = {}, {}
        real_init(self, view)

    monkeypatch.setattr(checks.EdgeCache, "__init__", own_memos)
    old = [make_drivable(raw, s, g, checker, cfg) for raw, s, g, cfg in tree_paths]
    for a, b in zip(new, old, strict=True):
        _same(a, b)


def test_edge_caches_of_one_view_share_answers_and_count_their_own() -> None:
    checker = cached_checker(builtin_map("parking_lot"))
    asked: list[tuple] = []

    class Counting:
        def edge_free(self, a, b):  # noqa: ANN001, ANN202
            asked.append((*a, *b))
            return checker.edge_free(a, b)

    view = checks.CheckerView(Counting())
    rng = np.random.default_rng(2)
    edges = [rng.uniform(0.0, 40.0, 4).tolist() for _ in range(30)]
    first, second = checks.EdgeCache(view), checks.EdgeCache(view)
    for e in edges[:20]:
        assert first.edge_free(e[:2], e[2:]) == checker.edge_free(e[:2], e[2:])
    for e in edges[10:]:
        assert second.edge_free(e[:2], e[2:]) == checker.edge_free(e[:2], e[2:])
    assert (first.checks, second.checks) == (20, 20)  # as with caches of their own
    assert len(asked) == 30  # each edge asked of the checker once
