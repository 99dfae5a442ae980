"""The tree baselines plan positions only: their failures are not blamed on a heading."""

from __future__ import annotations

import numpy as np
import pytest

from rrtdrive import Budget, builtin_map
from rrtdrive.planning import PlanningProblem, make_planner
from rrtdrive.planning.diagnosis.findings import DiagnosisKind

#: The findings about the start's and goal's headings (room at the ends, the U-turn).
HEADING_KINDS = {DiagnosisKind.NEEDS_REVERSE, DiagnosisKind.BOXED_IN, DiagnosisKind.U_TURN}


@pytest.mark.parametrize("name", ["rrt", "rrt-connect", "rrt-star"])
def test_a_baseline_failing_on_a_bay_entered_in_reverse_is_not_told_to_reverse(name):
    problem = PlanningProblem.from_map(builtin_map("reverse_bay"))
    result = make_planner(name).solve(problem, np.random.default_rng(0),
                                      Budget(max_iterations=300))  # fmt: skip
    assert not result.success
    assert result.diagnosis is None or result.diagnosis.kind not in HEADING_KINDS, (
        result.diagnosis
    )


def test_the_improved_planner_forward_on_that_bay_still_is():
    problem = PlanningProblem.from_map(builtin_map("reverse_bay"))
    result = make_planner("improved-rrt-connect").solve(
        problem, np.random.default_rng(0), Budget(max_iterations=300)
    )
    assert not result.success and result.diagnosis is not None
    assert result.diagnosis.kind is DiagnosisKind.NEEDS_REVERSE
    assert "try --reverse" in result.diagnosis.message
