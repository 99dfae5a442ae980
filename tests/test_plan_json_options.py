"""A plan JSON's planner_options rebuild its planner; the document is strict JSON."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from rrtdrive import Budget, builtin_map
from rrtdrive.cli import main, plan_to_json
from rrtdrive.json_safe import options_from_json, options_json
from rrtdrive.planning import PlanningProblem, make_planner
from rrtdrive.types import InputError


def _strict(text: str) -> dict:
    def refuse(name: str) -> None:
        raise ValueError(f"non-standard JSON constant {name}")

    return json.loads(text, parse_constant=refuse)


@pytest.mark.parametrize(
    "flags",
    [
        ["--paper-smoothing"],
        ["--planner-option", "reverse_detour_ratio=Infinity", "--reverse"],
        ["--step", "4", "--disable", "prune"],
    ],
)
def test_the_planner_options_of_a_plan_json_rebuild_the_same_path(tmp_path, flags):
    out = tmp_path / "plan.json"
    assert main(["plan", "overtake", "--seed", "3", *flags, "--json", str(out)]) == 0
    doc = _strict(out.read_text())
    m = builtin_map("overtake")
    planner = make_planner(doc["planner"], **doc["planner_options"])
    problem = PlanningProblem.from_map(m, reverse=doc["reverse"])
    again = planner.solve(problem, np.random.default_rng(doc["seed"]), Budget())
    assert again.success
    np.testing.assert_array_equal(np.round(again.path.samples, 6), np.array(doc["path"]))


def test_plan_to_json_writes_numpy_scalars_as_plain_numbers():
    m = builtin_map("overtake")
    options = {"max_postprocess_attempts": np.int64(6), "step": np.float32(2.5)}
    result = make_planner("improved-rrt-connect", **options).solve(
        PlanningProblem.from_map(m), np.random.default_rng(0), Budget()
    )
    doc = _strict(json.dumps(plan_to_json(result, np.int64(0), m.name, planner_options=options)))
    assert doc["seed"] == 0 and doc["planner_options"] == {
        "max_postprocess_attempts": 6,
        "step": 2.5,
    }


def test_options_json_and_options_from_json_are_inverse_for_non_finite_numbers():
    options = {"a": math.inf, "b": [-math.inf, 1.5], "c": {"d": "arcs"}}
    text = json.dumps(options_json(options), allow_nan=False)
    back = options_from_json(_strict(text))
    assert back["a"] == math.inf and back["b"] == [-math.inf, 1.5] and back["c"] == {"d": "arcs"}
    assert math.isnan(options_from_json(options_json(math.nan)))


def test_a_curve_named_as_text_is_the_enum_and_a_wrong_name_is_refused():
    planner = make_planner("improved-rrt-connect", smoothing={"curve": "bspline"})
    assert planner.config.smoothing.curve.value == "bspline"
    with pytest.raises(InputError, match=r"smoothing.curve: must be one of .*got 'spline'"):
        make_planner("improved-rrt-connect", smoothing={"curve": "spline"})


def test_a_plan_json_names_the_budget_and_grid_that_decided_it(tmp_path):
    """A plan cut short by ``--max-iterations`` is made again from its JSON alone.

    The JSON kept the seed and planner options but not the budget or the grid, so a
    failed plan at 20 iterations read like the default's (which solves this query).
    """
    out = tmp_path / "plan.json"
    flags = ["--max-iterations", "20", "--max-time", "60", "--resolution", "0.2"]
    assert main(["plan", "parking_lot", "--seed", "3", *flags, "--json", str(out)]) == 1
    doc = _strict(out.read_text())
    assert (doc["max_iterations"], doc["max_time_s"], doc["resolution_m"]) == (20, 60.0, 0.2)
    from rrtdrive.collision import CheckerConfig

    problem = PlanningProblem.from_map(
        builtin_map("parking_lot"), config=CheckerConfig(resolution=doc["resolution_m"])
    )
    planner = make_planner(doc["planner"], **doc["planner_options"])
    budget = Budget(max_iterations=doc["max_iterations"], max_time_s=doc["max_time_s"])
    again = planner.solve(problem, np.random.default_rng(doc["seed"]), budget)
    assert (again.status.value, again.iterations) == (doc["status"], doc["iterations"])
    default = planner.solve(problem, np.random.default_rng(doc["seed"]), Budget())
    assert default.success and not again.success


def test_the_plan_json_defaults_name_the_default_budget_and_grid(tmp_path):
    out = tmp_path / "plan.json"
    assert main(["plan", "overtake", "--json", str(out)]) == 0
    doc = _strict(out.read_text())
    from rrtdrive.collision import CheckerConfig

    assert doc["max_iterations"] == Budget().max_iterations
    assert doc["max_time_s"] == Budget().max_time_s
    assert doc["resolution_m"] == CheckerConfig().resolution


def test_numpy_arrays_are_written_as_lists_with_their_non_finite_numbers_spelled():
    """An array was written as its text ("[ 1. nan]"): a string where a list belongs."""
    from rrtdrive.json_safe import json_safe

    grid = np.array([[1.0, np.nan], [np.inf, -2.5]])
    doc = _strict(json.dumps(json_safe({"rows": grid}), allow_nan=False))
    assert doc == {"rows": [[1.0, None], [None, -2.5]]}
    options = {"weights": np.array([0.5, np.inf]), "ids": np.arange(3)}
    back = options_from_json(_strict(json.dumps(options_json(options), allow_nan=False)))
    np.testing.assert_array_equal(back["weights"], options["weights"])
    assert back["ids"] == [0, 1, 2] and all(type(i) is int for i in back["ids"])
    assert json_safe(np.float32(0.25)) == 0.25 and json_safe(np.array(3.0)) == 3.0


def test_a_tiny_cap_is_written_as_given_so_the_plan_can_be_made_again(tmp_path, capsys):
    from rrtdrive.cli import main

    out = tmp_path / "p.json"
    assert main(["plan", "narrow_gap", "--max-time", "1e-9", "--json", str(out)]) == 1
    doc = json.loads(out.read_text())
    assert doc["status"] == "timeout" and doc["max_time_s"] == 1e-9
    again = tmp_path / "again.json"
    code = main(["plan", "narrow_gap", "--max-time", repr(doc["max_time_s"]), "--json", str(again)])
    assert code == 1 and json.loads(again.read_text())["status"] == "timeout"
