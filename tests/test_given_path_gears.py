"""`simulate --path` warns when rows without a gear column move against their yaw."""

from __future__ import annotations

import json

import pytest

from rrtdrive.cli import main


def gearless(src, dst) -> None:
    data = json.loads(src.read_text())
    data["path"] = [row[:4] for row in data["path"]]
    dst.write_text(json.dumps(data))


@pytest.mark.parametrize(("map_name", "reverse", "warned"),
                         [("kerbside", True, True), ("parking_lot", False, False)])
def test_a_reversing_plan_without_its_gear_column_is_named(
    tmp_path, capsys, map_name, reverse, warned
):
    plan = tmp_path / "plan.json"
    assert main(["plan", map_name, *(["--reverse"] if reverse else []), "--json", str(plan)]) == 0
    cut = tmp_path / "cut.json"
    gearless(plan, cut)
    capsys.readouterr()
    main(["simulate", map_name, "--path", str(cut), "--max-time", "0.5"])
    err = capsys.readouterr().err
    assert ("moves against its yaw" in err) is warned, err
    # The plan with its gear column drives as planned: no such warning.
    main(["simulate", map_name, "--path", str(plan), "--max-time", "0.5"])
    assert "moves against its yaw" not in capsys.readouterr().err
