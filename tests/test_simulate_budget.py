"""``rrtdrive simulate --max-iterations``: the planning budget that decides, as ``plan``'s."""

from __future__ import annotations

import json

import pytest

from rrtdrive.cli import main


def _json(capsys, *argv: str) -> tuple[int, dict]:
    code = main([*argv, "--json", "-"])
    return code, json.loads(capsys.readouterr().out)


@pytest.mark.parametrize("budget", ["60", "400", "20000"])
def test_simulate_plans_with_the_budget_given(capsys, budget):
    """The same map, iteration budget and planner stream: simulate drives that plan.

    The stream is the episode seed's planner stream (scenario_rngs), not `plan --seed`'s
    generator: at the default budget `plan parking_lot` makes a 170.73 m path and
    `simulate parking_lot` a 143.17 m one (this test once compared the two commands and
    passed only because at these budgets both paths happen to agree).
    """
    from rrtdrive import Budget, builtin_map
    from rrtdrive.cli import plan_to_json
    from rrtdrive.planning import PlanningProblem, make_planner
    from rrtdrive.sim.scenes import scenario_rngs

    m = builtin_map("parking_lot")
    result = make_planner("improved-rrt-connect").solve(
        PlanningProblem.from_map(m), scenario_rngs(0)[1], Budget(max_iterations=int(budget))
    )
    plan_code = 0 if result.success else 1
    plan = plan_to_json(result, 0, m.name)
    sim_code, sim = _json(capsys, "simulate", "parking_lot", "--max-iterations", budget)
    assert sim["planner"] == plan["planner"] == "improved-rrt-connect"
    if plan["success"]:
        assert sim_code in (0, 1) and sim["status"] != "plan_failed"
        # simulate reports the length to the millimetre
        assert sim["path_length_m"] == pytest.approx(plan["length_m"], abs=5e-4)
        assert sim["path_cusps"] == plan["cusps"]
    else:
        assert (plan_code, sim_code) == (1, 1) and sim["status"] == "plan_failed"
        assert plan["message"] in sim["message"]


def test_a_budget_too_small_fails_the_plan_by_count(capsys):
    """Five iterations cannot reach the bay: the plan fails on its budget, not its clock."""
    code, data = _json(capsys, "simulate", "parking_lot", "--max-iterations", "5")
    assert code == 1 and data["status"] == "plan_failed"
    assert "iteration budget" in data["message"] and "safety cap" not in data["message"]
    # The JSON names the budget that cut the plan short, beside its wall-clock cap.
    assert (data["max_iterations"], data["plan_max_time_s"]) == (5, 120.0)
    code, data = _json(capsys, "simulate", "parking_lot")
    assert code == 0 and data["success"]
    # The default budget is plan's, the wall-clock cap too: the iterations decide alike.
    code, plan = _json(capsys, "plan", "parking_lot")
    assert (data["max_iterations"], data["plan_max_time_s"]) == (
        plan["max_iterations"], plan["max_time_s"]
    )


def test_the_json_has_no_plan_budget_where_nothing_is_planned_or_the_clock_is_off(
    capsys, tmp_path
):
    """--deterministic has no wall-clock cap; a given path has no plan at all."""
    code, data = _json(capsys, "simulate", "parking_lot", "--deterministic",
                       "--max-iterations", "400")
    assert (data["max_iterations"], data["plan_max_time_s"]) == (400, None)
    plan = tmp_path / "plan.json"
    assert main(["plan", "parking_lot", "--json", str(plan)]) == 0
    capsys.readouterr()
    code, data = _json(capsys, "simulate", "parking_lot", "--path", str(plan))
    assert data["planner"] == "given"
    assert (data["max_iterations"], data["plan_max_time_s"]) == (None, None)


@pytest.mark.parametrize("value", ["0", "-3", "2.5", "many"])
def test_a_bad_budget_is_one_error_naming_the_flag(capsys, value):
    with pytest.raises(SystemExit) as stop:  # argparse's own exit, with our message
        main(["simulate", "parking_lot", "--max-iterations", value])
    assert stop.value.code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--max-iterations" in err and "Traceback" not in err


def test_a_big_map_says_its_set_up_and_the_json_reports_it_apart(capsys, tmp_path):
    """A map of more than 4 M grid cells set up for seconds without a word in simulate
    (plan said it), and its JSON had no setup_time_s (a new user's find)."""
    from rrtdrive.maps import Map, save_map
    from rrtdrive.types import Pose

    big = Map("big", (0.0, 0.0, 210.0, 210.0), (), Pose(20.0, 20.0, 0.0), Pose(32.0, 20.0, 0.0))
    path = tmp_path / "big.json"
    save_map(big, str(path))
    code = main(["simulate", str(path), "--json", "-"])
    out, err = capsys.readouterr()
    data = json.loads(out)
    assert code == 0 and data["success"]
    assert "rrtdrive simulate: setting up a 210 x 210 m map" in err
    assert data["setup_time_s"] > 0.0 and data["planning_time_s"] >= 0.0
    code = main(["simulate", "parking_lot", "--json", "-"])  # under 4 M cells: no line
    out, err = capsys.readouterr()
    assert "setting up" not in err and json.loads(out)["setup_time_s"] >= 0.0
