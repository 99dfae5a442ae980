"""A pair of trees whose start or goal tree never leaves its root gives way (``root_patience``).

A root grows only by edges within 90 degrees of its pose's heading (the virtual
parents), so a pose boxed in along it leaves its tree a single node for the whole
growth share (where that is provable before any iteration the growth does not even
start: ``improved/boxed.py``). With the
escalation on, the growth gives up after ``ImprovedConfig.root_patience`` of the
pair's iterations instead; the paper's pipeline alone (escalation off) keeps every
iteration.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rrtdrive.maps import builtin_map
from rrtdrive.planning.base import PlanningProblem
from rrtdrive.planning.improved import ImprovedConfig, ImprovedRRTConnect
from rrtdrive.planning.improved.growth import ObtuseTree, grow_until_meet
from rrtdrive.types import Budget, InputError
from rrtdrive.verify import verify_path

BUDGET = Budget(max_iterations=20_000, max_time_s=600.0)


class _Uniform:
    """Samples uniform in a 40 m square (the growth's SampleSource interface)."""

    def draw_xy(self, rng: np.random.Generator) -> np.ndarray:
        return rng.uniform(0.0, 40.0, size=2)


def _grow(edge_free, patience: int, seed: int = 0, max_iterations: int = 3000):  # noqa: ANN001
    ts = ObtuseTree(np.array([5.0, 20.0]), virtual_parent=np.array([0.0, 20.0]))
    tg = ObtuseTree(np.array([35.0, 20.0]), virtual_parent=np.array([40.0, 20.0]))
    found, used = grow_until_meet(
        ts, tg, _Uniform(), np.random.default_rng(seed), edge_free, step=5.0, obtuse=True,
        adaptive=True, passages=None, passage_bias=0.0, iterations=0,
        max_iterations=max_iterations, expired=lambda: False, root_patience=patience,
    )  # fmt: skip
    return found, used, ts, tg


def _goal_boxed(a, b) -> bool:  # noqa: ANN001 - (x, y) sequences
    """Every edge at the goal root collides; every other edge is free."""
    return not any(p[0] == 35.0 and p[1] == 20.0 for p in (a, b))


@pytest.mark.parametrize("patience", [1, 50, 777])
def test_a_boxed_root_stops_the_pair_after_the_patience(patience: int) -> None:
    found, used, ts, tg = _grow(_goal_boxed, patience)
    assert found is None
    assert used == patience
    assert len(tg) == 1 and len(ts) > 1  # the start tree grew; the goal's never did


def test_without_patience_a_boxed_root_spends_the_whole_budget() -> None:
    found, used, _, tg = _grow(_goal_boxed, 0, max_iterations=1200)
    assert found is None and used == 1200 and len(tg) == 1


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 10_000), patience=st.integers(1, 60))
def test_patience_only_ever_stops_a_pair_with_a_bare_root(seed: int, patience: int) -> None:
    # A wall across the middle with one 4 m door: the trees take a while to meet.
    def door(a, b) -> bool:  # noqa: ANN001
        (ax, ay), (bx, by) = a, b
        if (ax - 20.0) * (bx - 20.0) > 0.0:
            return True
        t = (20.0 - ax) / (bx - ax)
        return 18.0 <= ay + t * (by - ay) <= 22.0

    found, used, ts, tg = _grow(door, patience, seed)
    old_found, old_used, _, _ = _grow(door, 0, seed)
    if found is None and used < old_used:
        # Stopped early: exactly at the patience, with a root still bare.
        assert used == patience and (len(ts) == 1 or len(tg) == 1)
    else:  # otherwise the very same growth
        assert used == old_used and (found is None) == (old_found is None)
        if found is not None:
            np.testing.assert_array_equal(found, old_found)


def test_a_kerbside_gap_gives_way_after_the_patience_with_the_same_path(monkeypatch) -> None:  # noqa: ANN001
    # The kerbside goal is proven boxed in before any iteration (test_root_boxed_in.py);
    # without that proof the pair waits out the patience.
    from rrtdrive.planning.improved import planner as improved_planner

    monkeypatch.setattr(improved_planner, "boxed_end", lambda *a, **k: "")
    problem = PlanningProblem.from_map(builtin_map("kerbside"), reverse=True)
    cfg = ImprovedConfig()
    # The whole patience: without narrow_fan's (its fan is narrow; test_root_boxed_in.py).
    res = ImprovedRRTConnect(narrow_fan=0.0).solve(problem, np.random.default_rng(0), BUDGET)
    assert res.success, res.message
    assert res.stats["stuck_root"] == 1.0
    assert f"the goal tree never left the goal pose in {cfg.root_patience} iterations" in (
        res.message
    )
    expansions = int(res.stats["hybrid_expansions"])
    assert res.iterations == cfg.root_patience + expansions
    assert verify_path(builtin_map("kerbside"), res.path, max_sharpness=0.2).ok
    # Without the patience the growth spends its whole share for the same escalation.
    old = ImprovedRRTConnect(root_patience=0).solve(problem, np.random.default_rng(0), BUDGET)
    assert old.success and "stuck_root" not in old.stats
    assert old.iterations == cfg.stage_budgets(BUDGET.max_iterations, True).iterations + (
        expansions
    )
    np.testing.assert_allclose(old.path.samples, res.path.samples, atol=1e-9)


def test_the_papers_pipeline_alone_keeps_every_iteration() -> None:
    budgets = ImprovedConfig().without("escalation").stage_budgets(20_000)
    assert budgets.root_patience == 0 and budgets.iterations == 20_000


@pytest.mark.parametrize("bad", [-1, 2.5, True, "4000"])
def test_a_bad_patience_names_the_field(bad: object) -> None:
    with pytest.raises(InputError, match="planner.root_patience"):
        ImprovedConfig(root_patience=bad)  # type: ignore[arg-type]
