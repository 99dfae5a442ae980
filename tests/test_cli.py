from __future__ import annotations

import json
import shutil
import subprocess
import sys

import numpy as np
import pytest

from rrtdrive.cli import main
from rrtdrive.maps import builtin_map, save_map


def run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_plan_json_success_and_deterministic(capsys):
    argv = ["plan", "parking_lot", "--planner", "rrt-connect", "--seed", "0", "--json", "-"]
    code, out, _ = run(capsys, *argv)
    assert code == 0
    first = json.loads(out)
    assert first["success"] is True
    for key in ("planner", "seed", "path", "waypoints", "length_m", "max_curvature", "nodes",
                "planning_time_s", "setup_time_s", "message", "reverse", "cusps", "start",
                "goal"):
        assert key in first
    assert first["reverse"] is False and first["cusps"] == 0
    path = np.array(first["path"])
    assert path.shape[1] == 5 and np.all(path[:, 4] == 1)
    assert np.hypot(*np.diff(path[:, :2], axis=0).T).max() <= 0.25 + 1e-6
    m = builtin_map("parking_lot")
    np.testing.assert_allclose(path[0, :2], [m.start.x, m.start.y], atol=1e-6)
    np.testing.assert_allclose(path[-1, :2], [m.goal.x, m.goal.y], atol=1e-6)
    code, out, _ = run(capsys, *argv)
    second = json.loads(out)
    for timing in ("planning_time_s", "setup_time_s"):  # wall times
        assert first.pop(timing) >= 0.0 and second.pop(timing) >= 0.0
    assert first == second


def test_plan_json_reports_the_diagnosis_time_apart(capsys):
    # The failure's diagnosis runs after the planning stopwatch; its time was in no
    # output (14 s on a 2 km map: a scaling audit, session 38).
    code, out, _ = run(capsys, "plan", "no_path", "--json", "-")
    failed = json.loads(out)
    assert code == 1 and failed["success"] is False and failed["diagnosis"] is not None
    assert isinstance(failed["diagnosis_time_s"], float) and failed["diagnosis_time_s"] > 0.0
    code, out, _ = run(capsys, "plan", "parking_lot", "--json", "-")
    assert code == 0 and json.loads(out)["diagnosis_time_s"] is None


def test_plan_reverse_flag_is_in_the_json(capsys):
    # rrt-connect cannot reverse: allowed, it still returns a forward-only path.
    code, out, _ = run(capsys, "plan", "parking_lot", "--planner", "rrt-connect", "--reverse",
                       "--json", "-")
    data = json.loads(out)
    assert code == 0 and data["reverse"] is True and data["cusps"] == 0
    assert all(len(row) == 5 and row[4] == 1 for row in data["path"])
    # ... and says so on stderr, naming the planners that do reverse.
    _, _, err = run(capsys, "plan", "parking_lot", "--planner", "rrt-connect", "--reverse")
    assert "note: rrt-connect plans forward only; --reverse takes effect with " in err
    assert "hybrid-a-star" in err and "improved-rrt-connect" in err
    _, _, err = run(capsys, "plan", "parking_lot", "--reverse")
    assert "plans forward only" not in err
    with pytest.raises(SystemExit):
        main(["plan", "--help"])
    assert "--reverse" in capsys.readouterr().out


def test_reverse_without_the_escalation_is_forward_only_and_says_so(capsys):
    # The default reverses only in its Hybrid A* escalation: with --disable escalation,
    # --reverse took no effect and nothing said so, while the failure's diagnosis asked
    # for a gear change (a user audit, session 35).
    argv = ["plan", "kerbside", "--reverse", "--disable", "escalation", "--json", "-"]
    code, out, err = run(capsys, *argv)
    data = json.loads(out)
    assert code == 1 and data["success"] is False and data["reverse"] is True
    assert "note: improved-rrt-connect plans forward only with --disable escalation" in err
    # A failed plan has no path to count gear changes on: null, as length_m (was 0).
    assert data["cusps"] is None and data["length_m"] is None
    code, out, err = run(capsys, "plan", "kerbside", "--reverse", "--json", "-")
    assert code == 0 and json.loads(out)["cusps"] >= 1 and "plans forward only" not in err


def test_plan_no_path_exits_1_with_message(capsys):
    code, out, err = run(capsys, "plan", "no_path", "--planner", "rrt-connect", "--json", "-")
    assert code == 1
    data = json.loads(out)
    assert data["success"] is False and "unreachable" in data["message"]
    assert "unreachable" in err


def _write_map(tmp_path, **patch):
    data = builtin_map("overtake").to_json() | patch
    f = tmp_path / "m.json"
    f.write_text(json.dumps(data))
    return str(f)


def _one_line_error(code, err, needle):
    assert code == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert "Traceback" not in err
    assert needle in lines[0], lines[0]


@pytest.mark.parametrize(
    "argv, needle",
    [
        (["plan", "atlantis"], "unknown map 'atlantis'"),
        (["plan", "overtake", "--planner", "dijkstra"], "unknown planner 'dijkstra'"),
        (["plan", "overtake", "--start", "1,2"], "--start"),
        (["plan", "overtake", "--goal", "a,b,c"], "--goal"),
        (["plan", "overtake", "--goal", "nan,44,0"], "--goal"),
        (["plan", "overtake", "--start", "inf,44,0"], "--start"),
        (["plan", "overtake", "--start", "-5,44,0"], "start"),
        (["plan", "overtake", "--goal", "150,44,0"], "goal"),
        (["plan", "overtake", "--goal", "50,44,0"], "goal"),
        (["plan", "overtake", "--step", "0"], "step"),
        (["plan", "overtake", "--step", "-2"], "step"),
        (["plan", "overtake", "--seed", "-1"], "--seed"),
        (["plan", "overtake", "--seed", "x"], "--seed"),
        (["plan", "overtake", "--max-time", "0"], "--max-time"),
        (["plan", "overtake", "--max-iterations", "nan"], "--max-iterations"),
    ],
)
def test_bad_input_one_line_exit_2(capsys, argv, needle):
    with pytest.raises(SystemExit) as info:
        code = main(argv)
        raise SystemExit(code)
    _, err = capsys.readouterr()
    _one_line_error(info.value.code, err, needle)


@pytest.mark.parametrize(
    "patch, needle",
    [
        ({"start": [50.0, 44.0, 0.0]}, "start"),
        ({"start": [5.0, 44.0]}, "start"),
        ({"bounds": [0, 0, "x", 100]}, "bounds"),
        ({"obstacles": [{"center": [10, 10], "size": [0, 1]}]}, "size"),
        ({"obstacles": [{"center": [10, 10], "size": [1e309, 1]}]}, "size"),
    ],
)
def test_bad_map_file_one_line_exit_2(capsys, tmp_path, patch, needle):
    f = _write_map(tmp_path, **patch)
    code, _, err = run(capsys, "plan", f, "--planner", "rrt-connect")
    _one_line_error(code, err, needle)


def test_malformed_json_file(capsys, tmp_path):
    f = tmp_path / "broken.json"
    f.write_text('{"bounds": [0, 0, 100, 100], "start": [1, 2')
    code, _, err = run(capsys, "plan", str(f))
    _one_line_error(code, err, "malformed JSON")


def test_custom_map_file_and_plot(capsys, tmp_path):
    f = tmp_path / "lot.json"
    save_map(builtin_map("overtake"), f)
    png = tmp_path / "out.png"
    code, out, _ = run(capsys, "plan", str(f), "--planner", "rrt-connect", "--plot", str(png))
    assert code == 0 and "solved" in out
    import matplotlib.image as mpimg

    img = mpimg.imread(png)
    assert img.shape[0] > 300 and img.std() > 0.05  # a real figure, not a blank canvas
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []


def test_u_turn_on_an_open_map_file(capsys, tmp_path):
    # A user's own map: a goal behind the start, facing back. Solved (the Dubins
    # fallback), and --disable dubins_fallback gives the paper pipeline's honest failure.
    f = tmp_path / "field.json"
    f.write_text(json.dumps({
        "name": "field", "bounds": [0, 0, 60, 40], "obstacles": [],
        "start": [10, 20, 0], "goal": [30, 20, 3.14159265],
    }))
    code, out, _ = run(capsys, "plan", str(f), "--json", "-")
    res = json.loads(out)
    assert code == 0 and res["success"] and "Dubins fallback" in res["message"]
    xy = np.array(res["path"])[:, :2]
    assert np.allclose(xy[0], [10, 20]) and np.allclose(xy[-1], [30, 20])
    assert xy[:, 0].max() > 32.0  # it loops beyond the goal to turn round
    assert res["stage"] == "dubins-fallback"
    # Without the fallback the Hybrid A* escalation turns round, under the paper's
    # smoothing and under the default (its segments ramped within the sharpness
    # bound); without both, the paper pipeline's honest failure.
    code, out, _ = run(
        capsys, "plan", str(f), "--disable", "dubins_fallback", "--paper-smoothing",
        "--json", "-",
    )  # fmt: skip
    assert code == 0 and json.loads(out)["stage"] == "hybrid-a-star"
    code, out, _ = run(capsys, "plan", str(f), "--disable", "dubins_fallback", "--json", "-")
    res = json.loads(out)
    assert code == 0 and res["stage"] == "hybrid-a-star" and res["max_sharpness"] <= 0.2
    code, out, _ = run(
        capsys, "plan", str(f), "--disable", "dubins_fallback", "--disable", "escalation",
        "--json", "-",
    )  # fmt: skip
    assert code == 1 and json.loads(out)["status"] == "postprocess_failed"


def test_json_to_file_is_atomic(capsys, tmp_path):
    target = tmp_path / "r.json"
    code, _, _ = run(capsys, "plan", "overtake", "--planner", "rrt", "--json", str(target))
    assert code == 0
    assert json.loads(target.read_text())["planner"] == "rrt"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r.json"]


def test_maps_export(capsys, tmp_path):
    code, out, _ = run(capsys, "maps", "--export", str(tmp_path))
    assert code == 0 and "parking_lot" in out
    from rrtdrive.maps import BUILTIN_MAPS

    assert len(list(tmp_path.glob("*.json"))) == len(BUILTIN_MAPS)


def test_console_script_help_and_exit_codes():
    exe = shutil.which("rrtdrive")
    cmd = [exe] if exe else [sys.executable, "-m", "rrtdrive"]
    for sub in ([], ["plan"], ["maps"]):
        proc = subprocess.run([*cmd, *sub, "--help"], capture_output=True, text=True, check=False)
        assert proc.returncode == 0 and "usage:" in proc.stdout
    proc = subprocess.run([*cmd, "plan", "no_path", "--planner", "rrt"], capture_output=True,
                          text=True, check=False)
    assert proc.returncode == 1
    assert "unreachable" in proc.stdout


# ----------------------------------------------------------------------------- issue 15


def test_map_file_not_utf8_one_line_exit_2(capsys, tmp_path):
    f = tmp_path / "latin1.json"
    f.write_bytes('{"name": "Stra\xdfe"}'.encode("latin-1"))
    code, _, err = run(capsys, "plan", str(f))
    _one_line_error(code, err, "not a UTF-8 text file")


def test_plot_suffix_checked_before_planning(capsys, tmp_path):
    target = tmp_path / "r.json"
    code, _, err = run(capsys, "plan", "overtake", "--json", str(target),
                       "--plot", str(tmp_path / "out.txt"))
    _one_line_error(code, err, "--plot")
    assert not target.exists()  # rejected before planning: nothing written


def test_disable_names_the_improved_planner(capsys):
    code, _, err = run(capsys, "plan", "overtake", "--planner", "rrt", "--disable", "prune")
    _one_line_error(code, err, "--disable")
    assert "improved" in err and "unexpected keyword" not in err


@pytest.mark.parametrize("flag", ["--start", "--goal"])
def test_negative_pose_after_a_space(capsys, flag):
    # "-5,44,0" is the value, not an option: the map's bounds check names the pose.
    code, _, err = run(capsys, "plan", "overtake", flag, "-5,44,0")
    _one_line_error(code, err, flag.lstrip("-"))
    assert "expected one argument" not in err


def test_negative_pose_accepted(capsys, tmp_path):
    f = tmp_path / "field.json"
    f.write_text(json.dumps({
        "name": "field", "bounds": [-50, -20, 50, 20], "obstacles": [],
        "start": [0, 0, 0], "goal": [30, 0, 0],
    }))
    code, out, _ = run(capsys, "plan", str(f), "--planner", "rrt-connect",
                       "--start", "-5,-2,0", "--json", "-")
    data = json.loads(out)
    assert code == 0 and data["success"]
    assert np.allclose(data["path"][0][:2], [-5, -2])


def test_maps_export_creates_the_folder(capsys, tmp_path):
    out = tmp_path / "a" / "b"
    code, _, _ = run(capsys, "maps", "--export", str(out))
    from rrtdrive.maps import BUILTIN_MAPS

    assert code == 0 and len(list(out.glob("*.json"))) == len(BUILTIN_MAPS)


def test_failed_plan_json_has_null_length_and_curvature(capsys):
    code, out, _ = run(capsys, "plan", "no_path", "--planner", "rrt-connect", "--json", "-")
    data = json.loads(out)
    assert code == 1 and data["length_m"] is None and data["max_curvature"] is None


def test_bad_obstacle_field_named_by_its_file_path(capsys, tmp_path):
    f = _write_map(tmp_path, obstacles=[{"center": [10, 10], "size": [0, 1]}])
    code, _, err = run(capsys, "plan", f)
    _one_line_error(code, err, "obstacles[0].size")
    assert "obstacle.size" not in err


def test_command_help_lines_match_their_modules():
    from rrtdrive import verify_cli
    from rrtdrive.bench import cli_bench
    from rrtdrive.cli import COMMANDS
    from rrtdrive.sim import cli_simulate

    helps = {c.name: c.help for c in COMMANDS}
    assert helps["simulate"] == cli_simulate.HELP and helps["bench"] == cli_bench.HELP
    assert helps["verify"] == verify_cli.HELP


def test_plan_help_lists_every_component_disable_takes(capsys):
    # The list is written out in the help (the CLI imports no planner to print it): it
    # must stay the config's own.
    from rrtdrive.planning.improved.config import COMPONENTS

    with pytest.raises(SystemExit):
        main(["plan", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    listed = text.split("improved-rrt-connect only: ")[1].split(" (")[0].split(" --")[0]
    assert [c.strip() for c in listed.replace("- ", "").split(",")] == list(COMPONENTS)


def _modules_after(*argv):
    # A fresh interpreter: which heavy libraries did the command import?
    code = (
        "import sys\n"
        "from rrtdrive.cli import main\n"
        "try:\n"
        f"    main({list(argv)!r})\n"
        "except SystemExit:\n"
        "    pass\n"
        "heavy = ('highway_env', 'control', 'matplotlib', 'pygame', 'scipy.signal',\n"
        "         'scipy.stats', 'ray')\n"
        "print(sorted(m for m in heavy if m in sys.modules))\n"
        "print('rrtdrive.planning' in sys.modules, 'rrtdrive.collision' in sys.modules)\n"
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          check=True)
    heavy, light = proc.stdout.strip().splitlines()[-2:]
    return heavy, light


@pytest.mark.parametrize("argv", [["--version"], ["--help"], ["maps"], ["verify", "--help"]])
def test_startup_imports_no_planner_or_simulator(argv):
    heavy, planning = _modules_after(*argv)
    assert heavy == "[]"
    assert planning == "False False"  # not even the planners or the collision checker


def test_plan_imports_no_simulator_controller_or_plotting(tmp_path):
    heavy, planning = _modules_after("plan", "overtake", "--planner", "rrt", "--json",
                                     str(tmp_path / "r.json"))
    assert heavy == "[]" and planning.startswith("True")


def test_verify_imports_no_simulator_controller_or_plotting(tmp_path):
    plan = tmp_path / "r.json"
    assert main(["plan", "overtake", "--planner", "rrt", "--json", str(plan)]) in (0, 1)
    heavy, _ = _modules_after("verify", str(plan))
    assert heavy == "[]"


def test_bench_imports_no_statistics_controller_or_simulator_before_it_runs():
    # A bench worker process imports what `bench` does: scipy.stats (summaries),
    # scipy.signal (nuPlan's comfort filter) and python-control (the LQR gain, which
    # imports matplotlib.pyplot) load on first use (2.4 -> 1.6 s, docs/cli_startup.md).
    heavy, planning = _modules_after("bench", "--help")
    assert heavy == "[]" and planning.startswith("True")


def test_simulate_video_stride_zero_rejected(capsys):
    with pytest.raises(SystemExit) as info:
        main(["simulate", "parking", "--video", "x.mp4", "--video-stride", "0"])
    _one_line_error(info.value.code, capsys.readouterr().err, "--video-stride")


def test_simulate_unwritable_video_folder_fails_before_the_episode(capsys, tmp_path,
                                                                  monkeypatch):
    import time

    import rrtdrive.cli_args as cli_args

    def refuse(target, suffix=None):
        raise PermissionError(13, "Permission denied")

    # Root ignores mode bits, so a read-only folder is played by the probe file failing.
    monkeypatch.setattr(cli_args, "temp_beside", refuse)
    t0 = time.perf_counter()
    code, _, err = run(capsys, "simulate", "parking", "--video", str(tmp_path / "v.mp4"))
    _one_line_error(code, err, "--video")
    assert "Permission denied" in err and time.perf_counter() - t0 < 10.0


def test_simulate_deterministic_conflicts_with_plan_time(capsys):
    code, _, err = run(capsys, "simulate", "parking", "--deterministic", "--plan-time", "2")
    _one_line_error(code, err, "--plan-time")


def test_simulate_deterministic_prints_a_metrics_block(capsys):
    code, out, _ = run(capsys, "simulate", "overtake", "--seed", "3", "--deterministic")
    assert code == 0
    lines = out.splitlines()
    assert "success" in lines[0]
    for word in ("tracking", "path", "comfort", "time"):
        assert any(line.strip().startswith(word) for line in lines[1:]), out


def test_simulate_help_imports_no_simulator():
    heavy, planning = _modules_after("simulate", "--help")
    assert heavy == "[]" and planning == "False False"


def test_a_good_start_replaces_a_bad_one_in_the_map_file(capsys, tmp_path):
    # The file's own start lies outside the bounds; --start replaces it before the check.
    data = builtin_map("overtake").to_json()
    data["start"] = [-5.0, 44.0, 0.0]
    f = tmp_path / "m.json"
    f.write_text(json.dumps(data))
    code, _, err = run(capsys, "plan", str(f), "--planner", "rrt")
    assert code == 2 and "error: start: (-5, 44) lies outside the bounds" in err
    code, _, err = run(capsys, "plan", str(f), "--planner", "rrt", "--start", "5,44,0")
    assert code == 0, err
    data["start"] = [5.0, 44.0, "east"]  # still read: a malformed pose is named
    f.write_text(json.dumps(data))
    code, _, err = run(capsys, "plan", str(f), "--start", "5,44,0")
    assert code == 2 and "error: start" in err


@pytest.mark.parametrize(
    ("argv", "flag"),
    [
        (["--step", "1e9"], "--step"),  # past the planner's 1000 m (0 is argparse's)
        (["--planner", "rrtstar"], "--planner"),
        (["--disable", "foo"], "--disable"),
        (["--goal", "200,44,0"], "--goal"),
        (["--start", "50,44,0"], "--start"),  # on obstacle 2
    ],
)
def test_plan_errors_name_the_flag_typed(capsys, argv, flag):
    # They named the API's fields (planner.step, planner, goal: ...) before session 29.
    code, _, err = run(capsys, "plan", "overtake", *argv)
    _one_line_error(code, err, flag)
    assert f"error: {flag}: " in err


@pytest.mark.parametrize("value", ["9_2,44,0", "92,4_4,0", "92,44,1_0"])
def test_a_pose_with_an_underscore_is_bad_input(capsys, value):
    # Python's float reads "9_2" as 92: a typo went through as a number (a helper's audit).
    code, _, err = run(capsys, "plan", "overtake", "--goal", value)
    _one_line_error(code, err, "--goal: expected three numbers x,y,yaw")


def test_simulate_names_a_bad_goal_on_a_map_by_its_flag(capsys):
    # The same check as plan's (cli.map_with_poses): simulate said "goal:" here.
    code, _, err = run(capsys, "simulate", "kerbside", "--goal", "200,44,0")
    _one_line_error(code, err, "error: --goal: (200, 44) lies outside the bounds")


GOAL_93 = "--goal=53.201107188452056,36.30433181948137,2.404196106990101"


def test_a_planner_option_reaches_the_planners_config(capsys):
    # Random goal 93: by default a detour's escalation path with a gear change; the
    # option keeps the paper stage's forward loop (it could not be set from the CLI).
    code, out, _ = run(capsys, "plan", "parking_lot", GOAL_93, "--reverse", "--json", "-")
    default = json.loads(out)
    code_kept, out, _ = run(capsys, "plan", "parking_lot", GOAL_93, "--reverse", "--json", "-",
                            "--planner-option", "reverse_detour_tree=false")  # fmt: skip
    kept = json.loads(out)
    assert code == code_kept == 0
    assert default["stage"] == "hybrid-a-star" and default["cusps"] == 1
    assert kept["stage"] == "improved-rrt-connect" and kept["cusps"] == 0
    assert kept["length_m"] > 2 * default["length_m"]
    # The JSON says what the plan was made with: the same command can be given again.
    assert default["planner_options"] == {} and kept["planner_options"] == {
        "reverse_detour_tree": False
    }
    _, out, _ = run(capsys, "plan", "parking_lot", "--step", "4", "--disable", "prune",
                    "--planner-option", "reverse_detour_ratio=Infinity", "--json", "-")  # fmt: skip
    assert json.loads(out)["planner_options"] == {
        "step": 4.0, "disable": ["prune"], "reverse_detour_ratio": "Infinity"
    }
    code, out, _ = run(capsys, "plan", "parking_lot", "--planner", "hybrid-a-star", "--json", "-",
                       "--planner-option", "curve=arcs", "--planner-option", "step=1.5")
    assert code == 0 and json.loads(out)["success"]


@pytest.mark.parametrize(
    ("argv", "needle"),
    [
        (["--planner-option", "reverse_detour_tree=yes"],
         "--planner-option reverse_detour_tree: expected true or false, got 'yes'"),
        (["--planner-option", "nonsense=1"],
         "--planner-option nonsense: unknown option for improved-rrt-connect"),
        (["--planner-option", "step"], "--planner-option: expected FIELD=VALUE"),
        (["--planner-option", "step=3", "--step", "4"],
         "--planner-option step: also given by --step"),
        (["--planner-option", "step=3", "--planner-option", "step=4"],
         "--planner-option step: given twice"),
        (["--planner-option", "step=-1"], "--planner-option step: must be > 0"),
        # The baselines' keywords, Hybrid A*'s and the smoothing's fields: each named by
        # the flag (they read "--planner: RRTPlanner.__init__() got ...", "hybrid.curve").
        (["--planner", "rrt", "--planner-option", "bogus=1"],
         "--planner-option bogus: unknown option for rrt; allowed ['exact_goal_edge'"),
        (["--planner", "hybrid-a-star", "--planner-option", "curve=nope"],
         "--planner-option curve: must be one of"),
        (["--planner-option", 'smoothing={"max_rounds": "x"}'],
         "--planner-option smoothing.max_rounds: must be an integer"),
        # The query's gear setting is --reverse (the JSON reports it), not a planner field.
        (["--planner", "hybrid-a-star", "--planner-option", "reverse=true"],
         "--planner-option reverse: give --reverse"),
        (["--disable", "escalation", "--planner-option", "escalation=true"],
         "--planner-option escalation: also given by --disable"),
    ],
)
def test_a_bad_planner_option_is_one_line_naming_it(capsys, argv, needle):
    code, out, err = run(capsys, "plan", "parking_lot", *argv)
    assert code == 2 and out == "" and len(err.strip().splitlines()) == 1, err
    assert needle in err, err


def test_switching_the_escalation_off_by_option_says_the_plan_is_forward_only(capsys):
    code, _, err = run(capsys, "plan", "parking_lot", "--reverse",
                       "--planner-option", "escalation=false")  # fmt: skip
    assert code == 0
    assert "plans forward only with --planner-option escalation=false" in err, err
