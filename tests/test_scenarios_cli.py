"""``rrtdrive simulate`` on the new scenarios, on any map, and its bad input."""

from __future__ import annotations

import json

import pytest

from rrtdrive.cli import main
from rrtdrive.maps import Map, Obstacle, save_map
from rrtdrive.types import Pose


def run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def small_map(tmp_path):
    m = Map("yard", (0.0, 0.0, 40.0, 24.0), (Obstacle((20.0, 12.0), (4.0, 6.0)),),
            Pose(4.0, 5.0, 0.0), Pose(30.0, 18.0, 0.0))
    path = tmp_path / "yard.json"
    save_map(m, path)
    return path


def test_simulate_a_map_file_drives_it_and_fits_the_video(capsys, tmp_path):
    path = small_map(tmp_path)
    video = tmp_path / "yard.mp4"
    code, out, err = run(capsys, "simulate", str(path), "--deterministic", "--json", "-",
                         "--video", str(video), "--video-stride", "50")
    data = json.loads(out)
    assert code == 0, err
    assert data["success"] and data["target"] == "map" and data["map"] == "yard"
    assert data["scenario"] == str(path) and data["reverse"] is False
    import imageio.v3 as iio

    frames = iio.imread(video, index=None)
    assert frames.shape[1:3] == (640, 960)  # 40 x 24 m fitted at 20.6 px/m, not 6 px/m
    # Progress lines, and no carriage returns when stderr is not a terminal (a log file).
    assert f"video {len(frames)}/{len(frames)} frames" in err and "\r" not in err


def test_simulate_a_map_with_start_and_goal_flags(capsys, tmp_path):
    path = small_map(tmp_path)
    code, out, err = run(capsys, "simulate", str(path), "--start", "4,18,0", "--goal", "30,5,0",
                         "--deterministic", "--json", "-")
    assert code == 0, err
    assert json.loads(out)["success"]  # stdout: the JSON alone
    # The summary is not dropped: it goes to stderr, as plan's does.
    assert f"{path} seed 0 improved-rrt-connect/pure-pursuit: success;" in err
    assert "cte rms" in err


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["parkng"], "scenario: unknown scenario 'parkng'"),
        (["parking", "--start", "1,2,0"], "--start: only a map takes a start"),
        (["overtake", "--reverse-in"], "--reverse-in: only the parking scenario"),
        (["overtake-traffic", "--reverse"], "--reverse: overtake-traffic re-plans"),
        (["garage", "--oncoming", "2"], "--oncoming: only the overtake scenario has"),
        (["garage", "--goal", "1,2"], "--goal: expected three numbers"),
        (["garage", "--goal", "-5,2,0"], "goal"),
        (["parking-v0", "--density", "low"], "--density: only the overtake-traffic scenario"),
    ],
)
def test_simulate_bad_input_exits_2_with_one_line(capsys, argv, message):
    code, out, err = run(capsys, "simulate", *argv)
    assert code == 2
    assert err.count("\n") == 1 and message in err, err


def test_simulate_bad_map_file_names_the_field(capsys, tmp_path):
    path = small_map(tmp_path)
    doc = json.loads(path.read_text())
    doc["obstacles"][0]["size"] = [4.0, -1.0]
    path.write_text(json.dumps(doc))
    code, _, err = run(capsys, "simulate", str(path))
    assert code == 2 and err.count("\n") == 1 and "size" in err, err


def test_simulate_reverse_with_a_forward_planner_says_so(capsys):
    code = main(["simulate", "kerbside", "--reverse", "--planner", "rrt"])
    err = capsys.readouterr().err
    # The goal is boxed in: rrt cannot reach it forward; the note says why reversing did not help.
    assert code == 1
    assert "note: rrt plans forward only; --reverse takes effect with hybrid-a-star" in err


def test_a_reversing_scenario_with_a_forward_planner_says_so(capsys):
    # parallel-parking plans with gear changes unasked: a forward-only planner crashed
    # with no word of why (a user audit, session 35); --reverse had the note alone.
    code = main(["simulate", "parallel-parking", "--planner", "rrt", "--max-time", "5"])
    err = capsys.readouterr().err
    assert code == 1
    assert "note: rrt plans forward only; the parallel-parking scenario's gear changes" in err
    main(["simulate", "parking", "--planner", "rrt", "--max-time", "1"])
    assert "plans forward only" not in capsys.readouterr().err  # parking: forward


def test_an_unknown_scenario_reads_alike_in_simulate_bench_and_gym(capsys):
    """One wording, the closest name suggested, in each place a scenario is named."""
    from rrtdrive.bench import BenchConfig
    from rrtdrive.envs.config import DriveEnvConfig
    from rrtdrive.types import InputError

    code, _, err = run(capsys, "simulate", "parkng_lot")
    assert code == 2
    simulate = err.strip().split("error: ", 1)[1]
    with pytest.raises(InputError) as bench:
        BenchConfig(scenarios=("parkng_lot",), seeds=1)
    with pytest.raises(InputError) as gym:
        DriveEnvConfig.from_options(scenario="parkng_lot")
    assert simulate.startswith(
        "scenario: unknown scenario 'parkng_lot' (did you mean 'parking_lot'?)"
    )
    # bench names its own option; the gym drives no stock envs, so lists none.
    assert str(bench.value) == "scenarios" + simulate[len("scenario"):]
    stock = ", a stock env (parking-v0, parking-parked-v0)"
    assert stock in simulate and str(gym.value) == simulate.replace(stock, "")
    # Every built-in map that is not itself a scenario is offered.
    from rrtdrive.maps import BUILTIN_MAPS
    from rrtdrive.sim.tasks import SCENARIOS

    assert all(m in simulate for m in BUILTIN_MAPS if m not in SCENARIOS)
    code, _, err = run(capsys, "simulate", "zzzz")
    assert code == 2 and "did you mean" not in err


def test_simulate_a_map_plans_and_judges_on_the_grid_asked_for(capsys, tmp_path):
    # --resolution reaches the planner's checker and the evaluators' (a map too big for
    # any automatic grid, 5 x 5 km, could not be simulated at all: no such option).
    from rrtdrive.collision import CheckerConfig
    from rrtdrive.maps import load_map
    from rrtdrive.planning.checker_cache import _CHECKERS

    path = small_map(tmp_path)
    m = load_map(path)
    key = (m.bounds, m.obstacles, m.vehicle, CheckerConfig(resolution=0.35))
    _CHECKERS.pop(key, None)
    code, out, err = run(capsys, "simulate", str(path), "--resolution", "0.35",
                         "--deterministic", "--json", "-")
    assert code == 0, err
    assert json.loads(out)["success"]
    assert key in _CHECKERS and _CHECKERS[key].resolution == pytest.approx(0.35)
    code, _, err = run(capsys, "simulate", "parking", "--resolution", "0.35")
    assert code == 2 and "--resolution: only a map takes a grid size" in err


GOAL_93 = "--goal=53.201107188452056,36.30433181948137,2.404196106990101"


def test_simulate_passes_planner_options_to_the_episodes_planner(capsys):
    # Random goal 93 with --reverse: the escalation's path with one gear change; with
    # the escalation switched off the tree path's forward loop is driven instead.
    args = ("simulate", "parking_lot", GOAL_93, "--reverse", "--deterministic",
            "--controller", "lqr", "--json", "-")  # fmt: skip
    code, out, _ = run(capsys, *args)
    default = json.loads(out)
    code_off, out, _ = run(capsys, *args, "--planner-option", "escalation=false")
    forward = json.loads(out)
    assert code == code_off == 0 and default["success"] and forward["success"]
    assert default["path_cusps"] == 1 and forward["path_cusps"] == 0
    assert default["planner_options"] == {} and forward["planner_options"] == {
        "escalation": False
    }
    assert forward["path_length_m"] > 2 * default["path_length_m"]


@pytest.mark.parametrize(
    ("argv", "needle"),
    [
        (["parking", "--planner-option", "stepp=3"],
         "--planner-option stepp: unknown option for improved-rrt-connect"),
        (["parking", "--planner-option", "reverse_detour_tree=maybe"],
         "--planner-option reverse_detour_tree: expected true or false"),
        (["overtake-traffic", "--planner-option", "step=3"],
         "--planner-option: overtake-traffic re-plans with its own planner"),
        (["parking", "--planner-option", "step"], "--planner-option: expected FIELD=VALUE"),
        (["parking", "--planner", "rrt", "--planner-option", "bogus=1"],
         "--planner-option bogus: unknown option for rrt"),
        (["u-turn", "--planner", "hybrid-a-star", "--planner-option", "persist=7"],
         "--planner-option persist:"),
    ],
)
def test_simulate_a_bad_planner_option_is_one_line(capsys, argv, needle):
    code, out, err = run(capsys, "simulate", *argv)
    assert code == 2 and out == "" and len(err.strip().splitlines()) == 1, err
    assert needle in err, err


def test_an_episode_configs_planner_options_must_be_a_mapping():
    from rrtdrive.sim.runner import EpisodeConfig
    from rrtdrive.types import InputError

    with pytest.raises(InputError, match=r"^episode.planner_options: expected a mapping"):
        EpisodeConfig(planner_options=[1])  # type: ignore[arg-type]
    with pytest.raises(InputError, match=r"by name, got \{1: 2\}"):
        EpisodeConfig(planner_options={1: 2})  # type: ignore[dict-item]


@pytest.mark.parametrize(
    ("argv", "line"),
    [
        # "only a built-in scenario takes it" sent a user to parking, which has no lead car.
        (["garage", "--lead-model", "idm"],
         "--lead-model: only the overtake-traffic scenario has it, not garage"),
        (["garage", "--oncoming", "1"],
         "--oncoming: only the overtake scenario has a count of oncoming cars, not garage"),
        # The scenario's own error named its field, "planner:", not the flag.
        (["overtake-traffic", "--planner", "hybrid-a-star"],
         "--planner: overtake-traffic re-plans with the improved RRT-Connect in space-time"),
        # overtake-traffic's road is 1.5 km: not "small".
        (["overtake-traffic", "--resolution", "0.2"],
         "--resolution: only a map takes a grid size; overtake-traffic sets its own"),
    ],
)
def test_scenario_only_flags_name_the_scenario_that_takes_them(capsys, argv, line):
    code, _, err = run(capsys, "simulate", *argv, "--max-time", "0.1")
    assert code == 2 and err.count("\n") == 1
    assert err.startswith(f"rrtdrive simulate: error: {line}"), err
