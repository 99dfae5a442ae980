"""experiments/compare_runs.py: matched episodes, before -> after cells, bad input."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path as FsPath

_SPEC = importlib.util.spec_from_file_location(
    "compare_runs", FsPath(__file__).resolve().parents[1] / "experiments" / "compare_runs.py"
)
assert _SPEC is not None and _SPEC.loader is not None
compare_runs = importlib.util.module_from_spec(_SPEC)
_SPEC.loader.exec_module(compare_runs)


def _report(seed: int, time: float, length: float, comfortable: bool) -> dict:
    return {
        "scenario": "parking", "controller": "lqr", "seed": seed, "success": True,
        "collision": False, "nuplan_comfortable": comfortable, "time_to_goal_s": time,
        "goal_position_err_m": 0.01 * seed, "cte_max_m": 0.02, "path_length_m": length,
        "nuplan_lon_accel_min": -1.0 - seed, "nuplan_lon_jerk_abs_max": 2.0,
    }  # fmt: skip


def test_matched_episodes_are_compared_cell_by_cell(tmp_path):
    before = tmp_path / "before.json"
    after = tmp_path / "after.json"
    before.write_text(json.dumps({"reports": [
        _report(0, 10.0, 20.0, True), _report(1, 20.0, 30.0, False), _report(2, 99.0, 1.0, True),
    ]}))  # fmt: skip
    after.write_text(json.dumps({"reports": [
        _report(0, 12.0, 20.0, True), _report(1, 22.0, 30.5, True),
    ]}))  # fmt: skip
    out = tmp_path / "page.md"
    assert compare_runs.main([str(before), str(after), "--out", str(out)]) == 0
    row = next(line for line in out.read_text().splitlines() if line.startswith("| parking"))
    cells = [c.strip() for c in row.strip("|").split("|")]
    # Seed 2 is in one run only: two episodes, one plan differs (30.0 -> 30.5 m).
    assert cells[:4] == ["parking", "lqr", "2", "1"]
    assert cells[4] == "2/2"  # success, the same
    assert cells[6] == "1/2 -> 2/2"  # nuPlan comfortable
    assert cells[8] == "15.00 -> 17.00"  # time mean of the successes
    assert cells[11] == "-2.000"  # lon accel min, the same
    assert "Left out: 1 episode(s) in one run only." in out.read_text()


def test_a_missing_file_is_a_clear_error(tmp_path, capsys):
    assert compare_runs.main([str(tmp_path / "none.json"), str(tmp_path / "x.json")]) == 2
    assert "cannot read the runs" in capsys.readouterr().err


def test_unrelated_runs_another_json_and_a_folder_out_are_refused(tmp_path, capsys):
    a, b, other = tmp_path / "a.json", tmp_path / "b.json", tmp_path / "other.json"
    a.write_text(json.dumps({"reports": [_report(0, 10.0, 20.0, True)]}))
    b.write_text(json.dumps({"reports": [_report(5, 10.0, 20.0, True)]}))
    other.write_text(json.dumps({"rows": []}))
    # No episode in common: an empty table with exit 0 before.
    assert compare_runs.main([str(a), str(b)]) == 2
    assert "share no episode" in capsys.readouterr().err
    assert compare_runs.main([str(a), str(other)]) == 2
    assert "no field 'reports'" in capsys.readouterr().err
    # --out DIR/ wrote a file named DIR.
    assert compare_runs.main([str(a), str(a), "--out", str(tmp_path / "pages") + "/"]) == 2
    assert "is a folder" in capsys.readouterr().err and not (tmp_path / "pages").exists()
