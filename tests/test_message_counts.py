"""Planner messages: counts read as English ("1 iteration"); the summary names the stage."""

from __future__ import annotations

import dataclasses
import json
import re

import numpy as np
import pytest

from rrtdrive.maps import builtin_map
from rrtdrive.planning import PlanningProblem, make_planner
from rrtdrive.types import Budget, Pose

#: A count of one followed by a plural noun, or any other count by a singular one.
WRONG = re.compile(r"\b1 (iterations|expansions|nodes)\b|\b(?!1\b)\d+ (iteration|expansion|node)\b")


def _message(planner: str, iterations: int, reverse: bool) -> str:
    m = builtin_map("parking_lot")
    # The goal 0.5 m behind the start: forward, only a loop reaches it.
    problem = dataclasses.replace(
        PlanningProblem.from_map(m, reverse=reverse),
        start=Pose(5.0, 6.0, 0.0), goal=Pose(4.5, 6.0, 0.0),
    )
    result = make_planner(planner).solve(
        problem, np.random.default_rng(0), Budget(max_iterations=iterations)
    )
    return result.message


@pytest.mark.parametrize(
    ("planner", "iterations", "reverse"),
    [
        ("improved-rrt-connect", 1, True),
        ("improved-rrt-connect", 2, False),
        ("hybrid-a-star", 2, False),
        ("rrt-star", 1, False),
    ],
)
def test_counts_agree_with_their_nouns(planner, iterations, reverse):
    message = _message(planner, iterations, reverse)
    assert re.search(r"\b1 (iteration|expansion)\b", message), message
    assert not WRONG.search(message), message


def test_the_pattern_catches_both_mistakes():
    assert WRONG.search("after 1 expansions") and WRONG.search("(3 iteration)")
    assert not WRONG.search("1 expansion, 6 nodes; 12 iterations")


@pytest.mark.parametrize(
    ("args", "stage"),
    [
        (["garage"], "dubins-fallback"),
        (["dead_end", "--reverse"], "hybrid-a-star"),
        (["parking_lot"], None),
    ],
)
def test_the_summary_names_a_later_stage_that_solved_it(args, stage, tmp_path, capsys):
    from rrtdrive.cli import main

    out = tmp_path / "plan.json"
    assert main(["plan", *args, "--json", str(out)]) == 0
    line = capsys.readouterr().out
    doc = json.loads(out.read_text())
    # The summary says what the JSON's "stage" says, when it is not the planner's first.
    assert (doc["stage"] == "improved-rrt-connect") == (stage is None)
    if stage is None:
        assert "stage" not in line
    else:
        assert doc["stage"] == stage and f", by its {stage} stage" in line
