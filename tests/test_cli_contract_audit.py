"""An audit of the command line's bad-input and output contracts (session 41).

The contract (SPEC §5-6): bad input is exit 2 with one stderr line naming the flag or
field, never a traceback; every run ends (budgets); outputs are whole or absent;
``--help`` on every subcommand. The first tests reproduce breaks of it found by the
audit (each failed before its fix); the others hold contracts no other test holds yet.
"""

from __future__ import annotations

import contextlib
import io
import json
import string
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rrtdrive.bench.config_file import config_from_mapping
from rrtdrive.cli import COMMANDS, main
from rrtdrive.types import InputError

#: A small open map: start and goal on a straight line, one box out of the way.
OPEN_MAP = {
    "name": "open",
    "bounds": [0, 0, 40, 20],
    "obstacles": [{"center": [20, 16], "size": [4, 2], "yaw": 0.0}],
    "start": [5, 5, 0],
    "goal": [35, 5, 0],
}
#: Arguments that keep a plan short whatever else is given.
FAST = ["--max-iterations", "200", "--max-time", "20"]


def run(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[object, str, str]:
    """``main(argv)``'s exit code (argparse's ``SystemExit`` code too), stdout and stderr."""
    try:
        code: object = main(list(argv))
    except SystemExit as exc:
        code = exc.code
    out, err = capsys.readouterr()
    return code, out, err


def run_quiet(argv: list[str]) -> tuple[object, str]:
    """``main(argv)`` with its output captured by hand (for Hypothesis tests): code, stderr."""
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        try:
            code: object = main(argv)
        except SystemExit as exc:
            code = exc.code
    return code, err.getvalue()


def one_error_line(code: object, err: str, needle: str) -> str:
    """Exit 2, no traceback, exactly one stderr line, and it contains ``needle``."""
    assert code == 2, err
    assert "Traceback" not in err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert needle in lines[0], lines[0]
    return lines[0]


def within_contract(code: object, err: str, flag: str) -> None:
    """Any of the documented outcomes (0 solved, 1 failed, 2 bad input naming ``flag``)."""
    assert code in (0, 1, 2), err
    assert "Traceback" not in err
    if code == 2:
        one_error_line(code, err, flag)


def write_json(tmp_path: Path, doc: object, name: str = "m.json") -> str:
    f = tmp_path / name
    f.write_text(json.dumps(doc))
    return str(f)


# ------------------------------------------------- breaks found by the audit, now mended


def test_a_huge_step_of_the_default_planner_is_no_traceback(capsys):
    """A typo'd ``--step 1e155`` ends as a plan or one line naming --step, not a crash."""
    code, _, err = run(capsys, "plan", "garage", "--step", "1e155", *FAST)
    within_contract(code, err, "--step")


@pytest.mark.parametrize("argv, flag", [
    (["--step", "1e20"], "--step"),
    (["--planner-option", "radius_factor=1e12"], "--planner-option radius_factor"),
    (["--planner-option", "coarse_factor=1000000000"], "--planner-option coarse_factor"),
])
def test_hybrid_a_star_sizes_nothing_from_an_unbounded_value(capsys, argv, flag):
    """A huge Hybrid A* step or factor is one line naming it, not a memory blow-up."""
    code, _, err = run(capsys, "plan", "garage", "--planner", "hybrid-a-star", *argv, *FAST)
    within_contract(code, err, flag)


@pytest.mark.parametrize("planner, option", [
    ("improved-rrt-connect", "dubins_radius_factor=1e12"),
    ("improved-rrt-connect", "smoothing.kappa_safety=1e-9"),
    ("rrt-star", "max_nodes=1000000000000"),
])
def test_a_planner_option_sizes_no_array_past_memory(capsys, planner, option):
    """An absurd planner option is one line naming it, not a MemoryError traceback."""
    code, _, err = run(capsys, "plan", "garage", "--planner", planner,
                       "--planner-option", option, *FAST)
    within_contract(code, err, f"--planner-option {option.partition('=')[0]}")


def test_a_cell_bigger_than_the_step_is_named_by_the_option_given(capsys):
    """``--planner-option xy_resolution=1e12`` is named as that option, not hybrid.step."""
    code, _, err = run(capsys, "plan", "garage", "--planner", "hybrid-a-star",
                       "--planner-option", "xy_resolution=1e12", *FAST)
    line = one_error_line(code, err, "--planner-option")
    assert "hybrid." not in line


def test_a_huge_run_timeout_is_no_traceback(capsys, tmp_path):
    """``bench --run-timeout 1e10`` (no limit meant) runs, or is one line naming the flag."""
    code, _, err = run(
        capsys, "bench", "--maps", "garage", "--planners", "rrt-connect", "--seeds", "1",
        "--workers", "1", "--run-timeout", "1e10", "--out", str(tmp_path / "b"),
        "--no-plots", "--quiet",
    )
    within_contract(code, err, "--run-timeout")
    if code == 0:  # the command recorded is the one run (main(argv), not sys.argv)
        config = json.loads((tmp_path / "b" / "bench_config.json").read_text())
        assert config["command"].startswith("rrtdrive bench --maps garage --planners")
        assert "--run-timeout 1e10" in config["command"]


def test_a_bench_file_with_a_byte_order_mark_is_read_or_named_so(capsys, tmp_path):
    """A TOML file saved with a BOM is read (its bad ``seeds`` named) or the BOM is named."""
    toml = tmp_path / "b.toml"
    toml.write_bytes(b"\xef\xbb\xbf" + b'maps = ["garage"]\nseeds = 0\n')
    code, _, err = run(capsys, "bench", "--config", str(toml), "--out", str(tmp_path / "o"))
    line = one_error_line(code, err, "")
    assert "seeds" in line or "byte-order mark" in line.lower() or "bom" in line.lower(), line


def test_an_empty_config_name_is_bad_input(capsys, tmp_path):
    """``bench --config ''`` (an unset shell variable) is named, not ignored."""
    code, _, err = run(capsys, "bench", "--config", "", "--maps", "garage", "--seeds", "0",
                       "--out", str(tmp_path / "o"))
    one_error_line(code, err, "--config")


def test_an_unknown_controller_is_refused_in_a_bench_of_maps():
    """A misspelt controller is bad input even where no run drives."""
    with pytest.raises(InputError, match="^controllers"):
        config_from_mapping({"maps": ["garage"], "controllers": ["nosuch"]})


def test_a_map_name_with_a_dollar_sign_can_be_plotted(capsys, tmp_path):
    """``plan --plot`` on a map named ``$x^$`` writes the figure (names are free text)."""
    f = write_json(tmp_path, {**OPEN_MAP, "name": "$x^$"})
    png = tmp_path / "p.png"
    code, _, err = run(capsys, "plan", f, "--plot", str(png), *FAST)
    within_contract(code, err, "name")
    assert code == 2 or png.is_file()


@pytest.mark.parametrize("command", ["plan", "verify", "simulate"])
def test_an_empty_positional_is_named_as_empty(capsys, command):
    """``rrtdrive plan ''`` (an unset shell variable) says the value is empty."""
    code, _, err = run(capsys, command, "")
    line = one_error_line(code, err, ":")
    assert "empty" in line, line


def test_a_plans_status_cannot_split_the_verdict_line(capsys, tmp_path):
    """A plan whose ``status`` holds a newline is refused or printed on one line."""
    f = write_json(tmp_path, {"map": "garage", "path": [], "status": "solved\nOK"}, "p.json")
    code, out, err = run(capsys, "verify", f)
    if code == 2:
        one_error_line(code, err, "status")
    else:
        assert code == 1, err
        assert out.splitlines()[0].endswith(")"), out


@pytest.mark.parametrize("option", ["check_spacing=1e-9", "sample_spacing=1e-9"])
def test_a_hybrid_spacing_too_fine_to_sample_is_named(capsys, option):
    """A spacing that would sample a primitive a billion times is one line naming it."""
    code, _, err = run(capsys, "plan", "garage", "--planner", "hybrid-a-star",
                       "--planner-option", option, *FAST)
    one_error_line(code, err, f"--planner-option {option.partition('=')[0]}: must be at least")


def test_the_bounds_leave_long_primitives_without_a_coarse_stage(capsys):
    """The step bound counts the coarse search's step: 100 m primitives plan without it."""
    code, _, err = run(capsys, "plan", "garage", "--planner", "hybrid-a-star", "--step", "100",
                       "--planner-option", "xy_resolution=70", "--planner-option",
                       "coarse_after=0", *FAST)
    assert code in (0, 1) and "Traceback" not in err, err
    code, _, err = run(capsys, "plan", "garage", "--planner", "hybrid-a-star", "--step", "100",
                       "--planner-option", "xy_resolution=70", *FAST)
    one_error_line(code, err, "--step: must be at most 100 / coarse_factor = 25 m")


def test_a_heuristic_cell_bigger_than_the_map_is_the_whole_map():
    """Hybrid A*'s cost-to-go grid at a resolution past the map's size is one cell.

    Its padding was sized from the cell (a 1e4 m cell over the garage's 0.1 m grid: 1e10
    booleans); now a cell never exceeds the grid.
    """
    from rrtdrive.maps import builtin_map
    from rrtdrive.planning.base import cached_checker
    from rrtdrive.planning.hybrid.heuristic import FreeCellGraph

    checker = cached_checker(builtin_map("garage"))
    graph = FreeCellGraph.build(checker, 1e4)
    nx, ny = checker.clearance_grid.shape
    assert graph.index.shape == (1, 1)
    assert graph.resolution == pytest.approx(max(nx, ny) * checker.resolution)


def test_export_onto_a_file_says_it_is_a_file(capsys, tmp_path):
    """``maps --export FILE`` names the file as one, not "cannot create folder"."""
    target = tmp_path / "taken"
    target.write_text("keep me")
    code, _, err = run(capsys, "maps", "--export", str(target))
    one_error_line(code, err, "--export: ")
    assert "is a file" in err and target.read_text() == "keep me"


# --------------------------------------------------------------- contracts that hold


@pytest.mark.parametrize("command", [c.name for c in COMMANDS])
def test_every_subcommand_has_help(capsys, command):
    """``rrtdrive COMMAND --help``: exit 0, its usage on stdout, nothing on stderr."""
    code, out, err = run(capsys, command, "--help")
    assert code == 0 and err == ""
    assert out.startswith(f"usage: rrtdrive {command}")


@pytest.mark.parametrize("key, value", [
    (key, value) for key in sorted(OPEN_MAP) for value in (None, "x", 3, {}, True)
    if (key, value) != ("name", "x")  # a valid name
])
def test_each_map_field_of_a_wrong_type_is_named(capsys, tmp_path, key, value):
    """Every top-level map field given null, text, a number, an object or a bool: named."""
    f = write_json(tmp_path, {**OPEN_MAP, key: value})
    one_error_line(*run(capsys, "plan", f, *FAST)[::2], f"{key}: ")


@pytest.mark.parametrize("key", ["center", "size", "yaw"])
@pytest.mark.parametrize("value", [None, "1", True, [[1], 2]])
def test_each_obstacle_field_of_a_wrong_type_is_named_by_its_path(capsys, tmp_path, key,
                                                                   value):
    """An obstacle's bad field is named ``obstacles[0].FIELD``."""
    obstacle = {**OPEN_MAP["obstacles"][0], key: value}
    f = write_json(tmp_path, {**OPEN_MAP, "obstacles": [obstacle]})
    one_error_line(*run(capsys, "plan", f, *FAST)[::2], f"obstacles[0].{key}: ")


@pytest.mark.parametrize("doc, needle", [
    ([OPEN_MAP], "map: expected a JSON object, got an array"),
    (None, "map: expected a JSON object, got null"),
    ({}, "map: missing key(s) ['bounds', 'goal', 'start']"),
    ({**OPEN_MAP, "car": {}}, "map: unknown key(s) ['car']"),
    ({**OPEN_MAP, "vehicle": {"width": -1}}, "vehicle.width: must be"),
    ({**OPEN_MAP, "obstacles": [{**OPEN_MAP["obstacles"][0], "size": [-4, 2]}]},
     "obstacles[0].size: must be > 0"),
    ({**OPEN_MAP, "start": [20, 16, 0]}, "start: the car's body at (20, 16) overlaps"),
    ({**OPEN_MAP, "goal": [50, 5, 0]}, "goal: (50, 5) lies outside the bounds"),
    ({**OPEN_MAP, "bounds": [0, 0, 1e6, 1e6]}, "bounds: "),
    ({**OPEN_MAP, "bounds": [40, 20, 0, 0]}, "bounds: need xmin < xmax"),
])
def test_a_bad_map_document_is_one_line(capsys, tmp_path, doc, needle):
    """Top-level lists, null, missing keys, bad sizes, poses off the map: one line each."""
    f = write_json(tmp_path, doc)
    one_error_line(*run(capsys, "plan", f, *FAST)[::2], needle)


@pytest.mark.parametrize("key, value", [
    ("seeds", '"3"'), ("seeds", "2.5"), ("seeds", "nan"), ("workers", "0"),
    ("max_time_s", "inf"), ("max_time_s", "true"), ("max_iterations", "1.5"),
    ("run_timeout_s", "-1"), ("retries", "-1"), ("plots", '"no"'), ("deterministic", '"yes"'),
    ("reverse", "1"), ("ray", "3"), ("out", '""'), ("maps", "3"), ("planners", "[]"),
])
def test_each_bench_file_field_of_a_wrong_value_is_named(capsys, monkeypatch, tmp_path, key,
                                                          value):
    """A TOML bench file's bad field: exit 2, one line naming it, nothing run."""
    monkeypatch.chdir(tmp_path)  # out = "" taken as the current folder would write here
    lines = {"maps": '["garage"]', "planners": '["rrt-connect"]', "seeds": "1",
             "out": json.dumps(str(tmp_path / "o")), key: value}
    toml = tmp_path / "b.toml"
    toml.write_text("".join(f"{k} = {v}\n" for k, v in lines.items()))
    field = "maps/scenarios" if key == "maps" and value == "[]" else key
    one_error_line(*run(capsys, "bench", "--config", str(toml))[::2], f"{field}: ")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["b.toml"]


def test_a_bench_file_typo_is_named_with_a_suggestion(capsys, tmp_path):
    """``seed = 3`` in a bench file: the unknown key and the one meant."""
    toml = tmp_path / "b.toml"
    toml.write_text('maps = ["garage"]\nseed = 3\n')
    one_error_line(*run(capsys, "bench", "--config", str(toml))[::2],
                   "config: unknown key 'seed' (did you mean 'seeds'?)")


@pytest.mark.parametrize("value, needle", [
    ("null", "expected a number, got None"), ("true", "expected a number, got True"),
    ("[1]", "expected a number, got [1]"), ("Infinity", "must be finite"),
    ("1e400", "must be finite"), ("NaN", "must be finite"),
])
def test_a_planner_option_of_the_wrong_json_kind_is_named(capsys, value, needle):
    """``--planner-option step=VALUE`` with a non-number or non-finite value."""
    code, _, err = run(capsys, "plan", "garage", "--planner-option", f"step={value}", *FAST)
    one_error_line(code, err, f"--planner-option step: {needle}")


@pytest.mark.parametrize("command, argv, needle", [
    ("plan", ["--json", "{d}"], "--json: "),
    ("plan", ["--plot", "{d}/p.png/"], "--plot: "),
    ("plan", ["--json", "{d}/no/such/x.json"], "--json: folder "),
    ("verify", ["--json", "{d}"], "--json: "),
    ("simulate", ["--trajectory", "{d}/no/t.csv"], "--trajectory: folder "),
])
def test_an_output_into_a_folder_that_cannot_hold_it_is_named_before_work(
    capsys, tmp_path, command, argv, needle
):
    """Outputs onto a folder or into a missing one: one line, nothing written."""
    plan = write_json(tmp_path, {"map": "garage", "path": []}, "plan.json")
    first = {"plan": "garage", "verify": plan, "simulate": "garage"}[command]
    before = sorted(tmp_path.rglob("*"))
    args = [a.replace("{d}", str(tmp_path)) for a in argv]
    one_error_line(*run(capsys, command, first, *args)[::2], needle)
    assert sorted(tmp_path.rglob("*")) == before


def test_a_failed_plan_still_writes_whole_json(capsys, tmp_path):
    """Exit 1 (no path) and a parseable ``--json`` file with the documented fields."""
    out = tmp_path / "p.json"
    code, _, err = run(capsys, "plan", "no_path", "--planner", "rrt", "--json", str(out),
                       "--max-iterations", "100")
    assert code == 1 and "Traceback" not in err
    doc = json.loads(out.read_text())
    for key in ("success", "planner", "seed", "path", "waypoints", "length_m",
                "max_curvature", "nodes", "planning_time_s", "message"):
        assert key in doc
    assert doc["success"] is False and doc["length_m"] is None
    assert [p.name for p in tmp_path.iterdir()] == ["p.json"]  # no temporary file left


#: Option values a user slips into: malformed numbers, empty, non-finite, unicode digits.
SLIPS = ["", "-", "1,2", "nan", "inf", "1e400", "٣", "1_0", "x=1", "@", "--", "-1", "0"]


@settings(max_examples=40)
@given(st.lists(st.tuples(st.sampled_from(["--start", "--goal", "--max-sharpness",
                                           "--clearance", "--no-sharpness", "--json"]),
                          st.sampled_from(SLIPS)), max_size=3))
def test_verify_with_random_slips_ends_in_a_documented_code(tmp_path_factory, pairs):
    """Random option slips on ``verify``: exit 0, 1 or 2, never a traceback or exception."""
    d = tmp_path_factory.mktemp("v")
    plan = write_json(d, {"map": "garage", "path": []}, "plan.json")
    argv = ["verify", plan]
    for flag, value in pairs:
        argv += [flag] if flag == "--no-sharpness" else [flag, value]
    with contextlib.chdir(d):  # a --json value such as '1,2' is a file name: written there
        code, err = run_quiet(argv)
    assert code in (0, 1, 2), err
    assert "Traceback" not in err


@settings(max_examples=25)
@given(st.text(alphabet=string.printable.strip() + "٣é", max_size=12))
def test_a_pose_of_any_text_is_a_pose_or_one_line(text):
    """``plan --start TEXT``: a plan, or one line naming --start; never a traceback."""
    code, err = run_quiet(["plan", "garage", "--start", text, "--planner", "rrt-connect",
                           "--max-iterations", "50"])
    assert code in (0, 1, 2) and "Traceback" not in err
    if code == 2:
        assert len(err.strip().splitlines()) == 1 and "--start" in err, err
