"""`rrtdrive simulate --json` names the plan's own status (a capped plan's `timeout` too)."""

from __future__ import annotations

import json

from rrtdrive.cli import main


def simulate(capsys, *args: str) -> tuple[int, dict]:
    code = main(["simulate", *args, "--json", "-"])
    return code, json.loads(capsys.readouterr().out)


def test_a_capped_plan_says_timeout_beside_the_episode_status(capsys):
    code, data = simulate(capsys, "parking", "--plan-time", "0.001")
    assert code == 1
    assert (data["status"], data["plan_status"]) == ("plan_failed", "timeout")
    assert "safety cap" in data["message"]


def test_a_planned_drive_says_solved_and_a_given_path_null(capsys, tmp_path):
    code, data = simulate(capsys, "parking")
    assert code == 0 and data["plan_status"] == "solved"
    plan = tmp_path / "plan.json"
    assert main(["plan", "parking_lot", "--json", str(plan)]) == 0
    capsys.readouterr()
    code, data = simulate(capsys, "parking_lot", "--path", str(plan))
    assert code == 0 and data["plan_status"] is None

