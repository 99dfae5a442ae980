"""Hybrid A*'s opt-in shortcuts (``HybridConfig.shortcut_tries``) on random queries.

A connection of the search driven along the heading bins (an aisle at 0 deg, a late
turn) is shortened by analytic words between poses along it; the result is built and
checked like any connection, and kept only when accepted and shorter.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from rrtdrive.maps import builtin_map
from rrtdrive.planning import PlanningProblem, make_planner
from rrtdrive.planning.hybrid import HybridConfig
from rrtdrive.planning.smoothing import max_sharpness
from rrtdrive.pose_sets import random_free_poses
from rrtdrive.types import Budget, InputError, PlanStatus
from rrtdrive.verify import verify_path


def _query(vary: str, index: int):
    pose = random_free_poses("parking_lot", 100, 1, vary)[index]
    m = dataclasses.replace(builtin_map("parking_lot"), **{vary: pose})
    return m, PlanningProblem.from_map(m, reverse=True)


def _solve(problem: PlanningProblem, tries: int):
    return make_planner("hybrid-a-star", shortcut_tries=tries).solve(
        problem, np.random.default_rng(0), Budget(max_iterations=20000, max_time_s=300)
    )


def test_a_shortcut_path_is_shorter_checked_and_keeps_every_guarantee() -> None:
    # Random goal 6: the search drives the aisle at 0 deg and turns late (145.1 m);
    # OMPL's simplified Reeds-Shepp path takes the diagonal (137.2 m).
    m, problem = _query("goal", 6)
    plain, short = _solve(problem, 0), _solve(problem, 40)
    assert plain.status is short.status is PlanStatus.SOLVED
    assert short.path.length < plain.path.length - 1.0
    assert verify_path(m, short.path).ok
    assert max_sharpness(short.path.samples, problem.vehicle.wheelbase) <= 0.2
    rows = short.path.samples
    assert np.allclose(rows[0, :3], problem.start.as_tuple(), atol=1e-9)
    assert np.allclose(rows[-1, :3], problem.goal.as_tuple(), atol=1e-6)
    # Counted, so deterministic: the same rows again.
    again = _solve(problem, 40)
    assert np.array_equal(again.path.samples, short.path.samples)


def test_a_path_that_is_one_analytic_word_is_left_alone() -> None:
    # Random start 87 with reverse: the first shot from the start answers; every stretch
    # of a shortest word is a shortest word, so nothing is tried and nothing changes.
    _, problem = _query("start", 87)
    plain, short = _solve(problem, 0), _solve(problem, 40)
    assert plain.status is PlanStatus.SOLVED and plain.iterations == 1
    assert np.array_equal(plain.path.samples, short.path.samples)


@pytest.mark.parametrize("value", [-1, 1.5, True])
def test_bad_shortcut_tries_name_the_field(value: object) -> None:
    with pytest.raises(InputError, match="hybrid.shortcut_tries"):
        HybridConfig(shortcut_tries=value)  # type: ignore[arg-type]
