"""Numbers at the edge of a double in maps and options: one line naming the field, exit 2.

From an audit of user-written maps (session 32): bounds of 1e308 m, an obstacle at
1e308, a 1e308 m grid cell and a 1e307 s time limit ended in tracebacks or numpy
overflow warnings; a 1e7 rad yaw was "taken as 155.1 deg" one line before it was
refused. Nothing here plans for long or drives.
"""

from __future__ import annotations

import json
import warnings

import pytest

from rrtdrive.cli import main
from rrtdrive.collision import CheckerConfig
from rrtdrive.maps import Obstacle, builtin_map
from rrtdrive.sim.runner import EpisodeConfig
from rrtdrive.sim.tasks import make_scenario
from rrtdrive.types import InputError


def _run(capsys, *argv: str) -> tuple[int, str]:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            code = main(list(argv))
        except SystemExit as exc:  # argparse's own refusals
            code = int(exc.code)
    # The CLI prints its own InputWarnings; anything else (numpy's overflow) leaked.
    assert not [str(w.message) for w in caught], [str(w.message) for w in caught]
    return code, capsys.readouterr().err


def _one_line(code: int, err: str, needle: str) -> None:
    assert code == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in err and "RuntimeWarning" not in err, err
    assert needle in lines[0], lines[0]


def _map_file(tmp_path, **patch) -> str:
    data = builtin_map("overtake").to_json() | patch
    f = tmp_path / "m.json"
    f.write_text(json.dumps(data))
    return str(f)


@pytest.mark.parametrize("bounds", [[0, 0, 1e308, 100], [-1e308, 0, 1e308, 100]])
@pytest.mark.parametrize("command", ["plan", "simulate"])
def test_bounds_no_grid_can_count_name_bounds(capsys, tmp_path, bounds, command):
    # OverflowError traceback (plan); "scenario.max_time_s: must be finite" (simulate).
    f = _map_file(tmp_path, bounds=bounds)
    _one_line(*_run(capsys, command, f), "is too big for any grid: use a smaller map")


def test_an_obstacle_far_out_or_turned_too_far(capsys, tmp_path):
    # Far out it changes nothing, as its warning says (no numpy overflow warnings).
    far = _map_file(tmp_path, obstacles=[{"center": [1e308, 1e308], "size": [1, 1]}])
    code, err = _run(capsys, "plan", far)
    assert code == 0 and "RuntimeWarning" not in err
    assert err.strip().splitlines() == [
        "rrtdrive plan: warning: obstacles[0]: centre [1e+308, 1e+308] lies wholly outside "
        f"the bounds {list(builtin_map('overtake').bounds)}, where everything counts as "
        "blocked; it changes nothing (a typo in its coordinates?)"
    ]
    turned = _map_file(tmp_path, obstacles=[{"center": [50, 20], "size": [4, 2], "yaw": 1e300}])
    _one_line(*_run(capsys, "plan", turned), "obstacles[0].yaw: 1e+300 rad is beyond")
    with pytest.raises(InputError, match=r"^obstacle\.yaw: "):
        Obstacle((0.0, 0.0), (1.0, 1.0), 1e7)
    assert Obstacle((0.0, 1e9), (1.0, 1e9)).size[1] == 1e9  # a wall may reach in
    with pytest.raises(InputError, match=r"^obstacle\.size: 2e\+300 m is longer than"):
        Obstacle((0.0, 1e300), (1.0, 2e300))  # not from beyond a billion metres


def test_a_yaw_beyond_the_limit_is_one_error_not_a_warning_first(capsys, tmp_path):
    # "warning: --start: yaw 1e+07 ... taken as 155.1 deg", then "error: --start: ...".
    _one_line(*_run(capsys, "plan", "overtake", "--start", "5,44,1e7"), "--start: yaw 10000000 rad")
    f = _map_file(tmp_path, start=[5.0, 44.0, 1e7])
    _one_line(*_run(capsys, "plan", f), "start: yaw 10000000 rad is beyond")
    # A yaw in degrees below the limit still warns, and plans.
    code, err = _run(capsys, "plan", "overtake", "--goal", "92,44,12.566370614359172")  # 4 pi
    assert code == 0 and "--goal: yaw 12.5664 is more than a full turn" in err


def test_a_grid_cell_coarser_than_100_m_is_refused(capsys):
    _one_line(*_run(capsys, "plan", "overtake", "--resolution", "1e308"),
              "--resolution: at most 100 m")
    _one_line(*_run(capsys, "simulate", "overtake", "--resolution", "101"),
              "--resolution: at most 100 m")
    with pytest.raises(InputError, match=r"^checker\.resolution: at most 100 m"):
        CheckerConfig(resolution=1e3)
    assert CheckerConfig(resolution=100.0).resolution == 100.0


def test_an_episode_time_limit_beyond_a_million_seconds_is_refused(capsys):
    _one_line(*_run(capsys, "simulate", "overtake", "--max-time", "1e307"), "--max-time: at most")
    with pytest.raises(InputError, match=r"^episode\.max_time_s: at most 1e\+06 s"):
        EpisodeConfig(max_time_s=2e6)
    scen = make_scenario("overtake", 0)
    with pytest.raises(InputError, match=r"^scenario\.max_time_s: at most"):
        type(scen)(**{**scen.__dict__, "max_time_s": 1e300})
    from rrtdrive.envs.config import DriveEnvConfig

    with pytest.raises(InputError, match=r"^max_time_s: at most"):
        DriveEnvConfig(scenario="overtake", max_time_s=1e9)


def test_a_map_file_that_became_a_folder_is_named_so(capsys, tmp_path):
    folder = tmp_path / "lot.json"
    folder.mkdir()
    plan = tmp_path / "plan.json"
    rows = [[5.0 + 0.2 * i, 6.0, 0.0, 0.0, 1] for i in range(6)]
    plan.write_text(json.dumps({"map": "lot", "map_file": str(folder), "path": rows}))
    _one_line(*_run(capsys, "verify", str(plan)), "which is now a folder")


def test_json_values_are_named_in_json_words(capsys, tmp_path):
    f = tmp_path / "null.json"
    f.write_text("null")
    _one_line(*_run(capsys, "plan", str(f)), "map: expected a JSON object, got null")
    f.write_text("[1, 2]")
    _one_line(*_run(capsys, "plan", str(f)), "map: expected a JSON object, got an array")
