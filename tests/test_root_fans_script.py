"""``experiments/root_fans.py``: open shares of the roots against when they grew."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "experiments"))
import root_fans  # noqa: E402


def test_a_boxed_goal_and_an_open_lot_land_in_their_bands(tmp_path) -> None:  # noqa: ANN001
    run = tmp_path / "root_growth.json"
    run.write_text(json.dumps({
        "meta": {"count": 1, "seeds": 1},
        "pairs": [
            {"query": "kerbside:fwd:0", "met": False, "iterations": 10000,
             "start_grew": 2, "goal_grew": None},
            {"query": "parking_lot:fwd:0", "met": True, "iterations": 120,
             "start_grew": 56, "goal_grew": 8},
        ],
    }))  # fmt: skip
    out = tmp_path / "out"
    assert root_fans.main([str(run), "--out", str(out)]) == 0
    payload = json.loads((out / "root_fans.json").read_text())
    bands = {tuple(b["band"]): b for b in payload["summary"]["bands"]}
    assert bands[(0.0, 0.05)]["never_grew_by_map"] == {"kerbside": 1}  # the boxed-in goal
    assert sum(b["grew"] for b in bands.values()) == 3
    assert payload["shares"]["kerbside:fwd:0"][1] == 0.0
    assert "| [0, 0.05) | 0 | - | 1 | kerbside 1 |" in (out / "root_fans.md").read_text()


def test_a_file_that_is_not_a_run_exits_2(tmp_path, capsys) -> None:  # noqa: ANN001
    bad = tmp_path / "x.json"
    bad.write_text("{}")
    with pytest.raises(SystemExit) as exc:
        root_fans.main([str(bad)])
    assert exc.value.code == 2 and "root_growth.json" in capsys.readouterr().err
