"""``experiments/random_maps_drive.py``: random maps driven closed loop through highway-env."""

from __future__ import annotations

import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "experiments"))
import random_maps_drive  # noqa: E402


def test_two_maps_are_driven_and_counted(tmp_path) -> None:  # noqa: ANN001
    out = tmp_path / "out"
    assert random_maps_drive.main(
        ["--maps", "2", "--controllers", "lqr,stanley", "--out", str(out)]
    ) == 0
    payload = json.loads((out / "random_maps_drive.json").read_text())
    rows = payload["rows"]
    assert [(r["map"], r["controller"]) for r in rows] == [
        (0, "lqr"), (0, "stanley"), (1, "lqr"), (1, "stanley")
    ]
    for c, s in payload["summary"].items():
        mine = [r for r in rows if r["controller"] == c]
        assert s["episodes"] == 2 and s["success"] == sum(r["success"] for r in mine)
    # Both maps need a gear change; every one planned is driven.
    assert all(r["success"] and r["cusps"] >= 1 and r["gear_changes"] == r["cusps"] for r in rows)
    assert "| lqr | 2/2 |" in (out / "random_maps_drive.md").read_text()


def test_bad_options_exit_2(capsys) -> None:  # noqa: ANN001
    import pytest

    for argv in (["--controllers", "mpc"], ["--maps", "0"], ["--planner", "nope"],
                 ["--seeds", "3,x"], ["--seeds", "-1"]):
        with pytest.raises(SystemExit) as exc:
            random_maps_drive.main(argv)
        assert exc.value.code == 2
    assert "--controllers" in capsys.readouterr().err


def test_the_commonroad_judges_random_maps_are_the_driven_ones() -> None:
    # experiments/commonroad_judge.py --random-maps drives the same maps, on the car it is given.
    import commonroad_judge
    from random_maps import random_map

    from rrtdrive.types import VehicleParams

    car = VehicleParams(max_steer_rate=0.4)
    task = commonroad_judge._task(commonroad_judge.RANDOM_MAPS, 3, car)
    m = random_map(3)
    assert task.reverse and task.map.obstacles == m.obstacles
    assert (task.map.start, task.map.goal) == (m.start, m.goal)
    assert task.vehicle.max_steer_rate == 0.4
