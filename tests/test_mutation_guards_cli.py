"""Guards found by mutation testing of the command line and the input readers.

Each test fails under a real-looking bug in ``cli*.py``, ``json_input``, ``values``,
``plan_file``, ``pose_rows``, ``occupancy`` or ``map_checks`` that the rest of the suite
let through. References are worked out by hand here: pixel values against ROS
``map_server``'s trinary rule, cell rectangles against shapely boxes, poses and
messages written out in full.
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import imageio.v3 as iio
import numpy as np
import pytest

from rrtdrive.cli import main
from rrtdrive.types import InputError
from rrtdrive.values import brief_repr


def _run(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    """Exit code, stdout, stderr of ``rrtdrive ARGV`` (argparse's errors exit by SystemExit)."""
    try:
        code = main(list(argv))
    except SystemExit as exit_:
        code = exit_.code
    out, err = capsys.readouterr()
    return code, out, err


def _one_line(code: int, err: str, start: str, expected: int = 2) -> None:
    """The CLI's contract for bad input: the exit code, one stderr line, no traceback."""
    assert code == expected, err
    assert "Traceback" not in err and err.count("\n") == 1, err
    assert err.startswith(start), err


# ----------------------------------------------------------------------------- values


@pytest.mark.parametrize("n", [29, 30, 31, 40])
def test_a_value_is_cut_only_past_the_limit_and_then_says_so(n: int) -> None:
    """``limit`` is the longest text shown whole; a longer one ends in an ellipsis."""
    text = repr("x" * n)  # n + 2 characters
    shown = brief_repr("x" * n)
    if len(text) <= 32:
        assert shown == text
    else:
        assert shown == text[:32] + "..."


def test_a_huge_negative_integer_counts_its_digits_not_its_sign() -> None:
    """``-10**400`` has 401 digits, as ``10**400`` has; the message must not say 402."""
    assert brief_repr(-(10**400)) == "-100000000...(401 digits)"
    assert brief_repr(10**400).endswith("(401 digits)")


# ----------------------------------------------------------------------------- json_input


def test_a_number_of_too_many_digits_names_the_map_file(capsys, tmp_path: Path) -> None:
    """Python refuses int literals past 4300 digits: one line naming ``map`` and the file."""
    f = tmp_path / "m.json"
    f.write_text('{"name": "m", "bounds": [0, 0, ' + "9" * 5000 + ", 100]}")
    code, _, err = _run(capsys, "plan", str(f))
    _one_line(code, err, f"rrtdrive plan: error: map: malformed JSON in {f}: a number has too")


def test_a_syntax_error_near_the_start_of_a_long_line_shows_the_text_before_it(
    capsys, tmp_path: Path
) -> None:
    """A map is often one long line: the message quotes the text up to the error, also
    when the error sits in the first 20 characters (no slice from the end of the file)."""
    f = tmp_path / "m.json"
    text = '{"name": nope, "bounds": [0, 0, 100, 100], "obstacles": [], ' + " " * 80 + "}"
    f.write_text(text)
    code, _, err = _run(capsys, "plan", str(f))
    pos = text.index("nope")  # json stops at the n: "Expecting value"
    _one_line(code, err, f"rrtdrive plan: error: map: malformed JSON in {f}: Expecting value "
              f"(line 1, column {pos + 1}, near {text[: pos + 1]!r})")


# ----------------------------------------------------------------------------- occupancy


def _image(tmp_path: Path, pixels: np.ndarray, name: str = "img.png") -> Path:
    f = tmp_path / name
    iio.imwrite(f, pixels)
    return f


def _yaml(tmp_path: Path, pixels: np.ndarray, text: str) -> Path:
    """A ROS map .yaml naming a PGM of ``pixels`` beside it, with ``text`` as its fields."""
    _image(tmp_path, pixels, "m.pgm")
    y = tmp_path / "m.yaml"
    y.write_text("image: m.pgm\n" + text)
    return y


def test_thresholds_may_sit_at_the_ends_of_their_range(tmp_path: Path) -> None:
    """0 and 1 are valid ROS thresholds: p > 1 and p < 0 never hold, so all is unknown."""
    from rrtdrive.occupancy import read_image_map

    f = _image(tmp_path, np.array([[0, 128, 255]], dtype=np.uint8))
    grid = read_image_map(f, 0.1, occupied_thresh=1.0, free_thresh=0.0, unknown_free=True)
    assert grid.occupied.tolist() == [[False, False, False]] and grid.unknown == 3


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"occupied_thresh": 1.5}, "occupied_thresh"),
        ({"free_thresh": -0.1}, "free_thresh"),
        ({"resolution": 1e-7}, "resolution"),
        ({"origin": (2e9, 0.0)}, "origin: x"),
    ],
)
def test_numbers_out_of_range_are_named(tmp_path: Path, kwargs: dict, field: str) -> None:
    """A threshold is a probability in [0, 1]; resolution and origin have bounds too."""
    from rrtdrive.occupancy import read_image_map

    f = _image(tmp_path, np.array([[0, 255]], dtype=np.uint8))
    args = {"resolution": 0.1, **kwargs}
    with pytest.raises(InputError, match=f"^{field}: expected a number from "):
        read_image_map(f, **args)


def test_ros_yaml_fields_negate_thresholds_mode_and_a_two_number_origin(tmp_path: Path) -> None:
    """Each field of the .yaml is read: worked by hand from p = (255 - v) / 255 or v / 255."""
    from rrtdrive.occupancy import read_ros_map

    px = np.array([[0, 50, 255]], dtype=np.uint8)  # p = 1, 0.804, 0 (negated: 0, 0.196, 1)
    y = _yaml(tmp_path, px, "resolution: 0.5\norigin: [1.5, -2.0]\n")
    grid = read_ros_map(y, unknown_free=True)
    assert grid.occupied.tolist() == [[True, True, False]] and grid.origin == (1.5, -2.0)
    y.write_text("image: m.pgm\nresolution: 0.5\norigin: [0, 0, 0]\nnegate: 1\n")
    assert read_ros_map(y, unknown_free=True).occupied.tolist() == [[False, False, True]]
    # occupied_thresh 0.9: p = 0.804 is unknown (free here), not occupied.
    y.write_text("image: m.pgm\nresolution: 0.5\norigin: [0, 0, 0]\noccupied_thresh: 0.9\n")
    assert read_ros_map(y, unknown_free=True).occupied.tolist() == [[True, False, False]]
    # mode scale: the same occupied and free cells as trinary (ROS scales only the rest).
    y.write_text("image: m.pgm\nresolution: 0.5\norigin: [0, 0, 6.283185307179586]\n"
                 "mode: scale\n")  # fmt: skip
    assert read_ros_map(y, unknown_free=True).occupied.tolist() == [[True, True, False]]


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("resolution: 0.5\norigin: [0, 0, 0]\nnegate: 2\n", "negate: expected 0 or 1, got 2"),
        ("origin: [0, 0, 0]\n", "resolution: missing in "),
        ("resolution: 0.5\norigin: [0, 0, 0]\nimage: 5\n", "image: expected the image's"),
    ],
)
def test_bad_ros_yaml_fields_are_named_by_the_reader(tmp_path: Path, text: str,
                                                     message: str) -> None:
    """A malformed .yaml is an InputError naming the field, never a TypeError or KeyError."""
    from rrtdrive.occupancy import read_ros_map

    y = _yaml(tmp_path, np.array([[0, 255]], dtype=np.uint8), text)
    if "image: 5" in text:
        y.write_text(text)
    with pytest.raises(InputError, match="^" + message):
        read_ros_map(y)


def test_imported_bounds_carry_no_binary_noise(tmp_path: Path) -> None:
    """0.1 + 121 x 0.1 is 12.200000000000001 in binary; the map file says 12.2."""
    from rrtdrive.occupancy import ImageMap, map_from_image
    from rrtdrive.types import Pose

    grid = ImageMap(np.zeros((60, 121), dtype=bool), 0.1, (0.1, 0.3))
    m = map_from_image(grid, "m", Pose(3.0, 3.0, 0.0), Pose(6.0, 3.0, 0.0))
    assert m.bounds == (0.1, 0.3, 12.2, 6.3)


# ----------------------------------------------------------------------------- maps --import


def _lot_pixels() -> np.ndarray:
    """200 x 80 pixels (20 x 8 m at 0.1 m): a black 5 x 1 m block at the bottom left
    (x 0..5, y 0..1) and a grey (v = 150, p = 0.41: unknown) 5 x 1 m patch at the top
    right (x 15..20, y 7..8); the rest white."""
    px = np.full((80, 200), 255, dtype=np.uint8)
    px[70:80, 0:50] = 0
    px[0:10, 150:200] = 150
    return px


IMPORT_POSES = ("--start", "3,4,0", "--goal", "12,4,0.5")


@pytest.mark.parametrize("unknown_free", [False, True])
def test_import_reads_grey_as_asked_and_keeps_start_and_goal(capsys, tmp_path: Path,
                                                             unknown_free: bool) -> None:
    """``--unknown-free`` reaches the reader (image and .yaml alike), the summary says how
    grey was read, and the map file has the start and goal given, each where it belongs."""
    import shapely

    from rrtdrive.maps import load_map
    from rrtdrive.types import Pose

    img = _image(tmp_path, _lot_pixels(), "lot.png")
    y = tmp_path / "LOT.YAML"  # a suffix in capitals is still a .yaml
    y.write_text("image: lot.png\nresolution: 0.1\norigin: [0.0, 0.0, 0.0]\n")
    flag = ["--unknown-free"] if unknown_free else []
    for source, extra in ((img, ["--resolution", "0.1"]), (y, [])):
        out = tmp_path / "lot.json"
        code, stdout, err = _run(capsys, "maps", "--import", str(source), *IMPORT_POSES,
                                 "--out", str(out), *extra, *flag)  # fmt: skip
        assert code == 0, err
        occupied, read = (500, "free") if unknown_free else (1000, "occupied")
        assert f"{occupied} occupied cells (500 unknown, read as {read})" in stdout
        m = load_map(out)
        assert m.bounds == (0.0, 0.0, 20.0, 8.0)
        assert m.start == Pose(3.0, 4.0, 0.0) and m.goal == Pose(12.0, 4.0, 0.5)
        union = shapely.union_all([o.polygon() for o in m.obstacles])
        block, grey = shapely.box(0, 0, 5, 1), shapely.box(15, 7, 20, 8)
        expected = block if unknown_free else shapely.union(block, grey)
        assert union.symmetric_difference(expected).area == pytest.approx(0.0, abs=1e-9)


@pytest.mark.parametrize(
    ("source", "extra", "message"),
    [
        ("png", ["--out", "-", "--resolution", "0.1"], "--out: needs a file name, not '-'"),
        ("png", ["--out", "o.json", "--resolution", "0.1", "--origin", "1,2,3"],
         "--origin: expected X,Y in metres, got '1,2,3'"),
        # Python's float reads "1_0" as 10; parse_pose refuses it as a typo, and so here.
        ("png", ["--out", "o.json", "--resolution", "0.1", "--origin", "1_0,2"],
         "--origin: expected X,Y in metres, got '1_0,2'"),
        ("png", ["--out", "o.json", "--resolution", "0.1", "--origin", "0,nan"],
         "--origin: y: expected a number from"),
        ("yaml", ["--out", "o.json", "--origin", "1,2"], "--origin: the .yaml gives it"),
    ],
)
def test_bad_import_flags_are_one_line_naming_the_flag(capsys, tmp_path: Path, monkeypatch,
                                                       source: str, extra: list[str],
                                                       message: str) -> None:
    """Each refused flag is named as typed (``--origin``, not the reader's ``origin``)."""
    monkeypatch.chdir(tmp_path)
    _image(tmp_path, _lot_pixels(), "lot.png")
    (tmp_path / "lot.yaml").write_text("image: lot.png\nresolution: 0.1\norigin: [0, 0, 0]\n")
    code, out, err = _run(capsys, "maps", "--import", f"lot.{source}", *IMPORT_POSES, *extra)
    _one_line(code, err, f"rrtdrive maps: error: {message}")
    assert out == "" and not (tmp_path / "o.json").exists() and not (tmp_path / "-").exists()


# ----------------------------------------------------------------------------- plan files


def test_simulate_names_a_path_file_without_a_path_by_its_flag(capsys, tmp_path: Path) -> None:
    """``simulate MAP --path F`` reads F as ``--path``: its errors say ``--path``, not ``plan``."""
    f = tmp_path / "notaplan.json"
    f.write_text('{"route": []}')
    code, _, err = _run(capsys, "simulate", "parking_lot", "--path", str(f))
    _one_line(code, err, f'rrtdrive simulate: error: --path: {f} has no "path"')


# ----------------------------------------------------------------------------- pose rows


def test_a_turn_in_place_reads_without_numpy_warnings() -> None:
    """A step without motion (a turn in place) must not divide by its zero length: a
    numpy RuntimeWarning would reach the user of ``rrtdrive verify`` as Python noise."""
    import warnings

    from rrtdrive.pose_rows import path_from_poses

    rows = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 0.0, 0.4], [2.0, 0.0, 0.4]]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        s = path_from_poses(rows).samples
    assert s[:, 4].tolist() == [1.0] * 4
    assert np.isfinite(s[:, 3]).all() and s[2, 3] == 0.0  # the still step takes the one before


def test_pose_rows_of_more_than_three_columns_are_refused() -> None:
    """Rows ``[x, y, yaw]`` only: four numbers (``kappa`` too?) are not silently re-read."""
    from rrtdrive.pose_rows import path_from_poses

    with pytest.raises(InputError, match=r"^path: expected rows \[x, y, yaw\] .*\(2, 4\)"):
        path_from_poses([[0.0, 0.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0]])


# ----------------------------------------------------------------------------- map checks


@pytest.mark.parametrize("side", [0, 1, 2, 3])
def test_a_body_touching_any_side_of_the_bounds_is_refused(side: int) -> None:
    """Touching counts on every side (the simulator's walls stand on the bounds); a
    micrometre inside, the same pose is fine."""
    from rrtdrive.maps import Map, check_endpoint
    from rrtdrive.types import Pose, VehicleParams
    from rrtdrive.vehicle import footprint_polygon

    car, pose = VehicleParams(), Pose(20.0, 10.0, 0.0)
    body = footprint_polygon(pose.as_tuple(), car).bounds
    room = [body[0] - 5.0, body[1] - 5.0, body[2] + 5.0, body[3] + 5.0]
    touching = list(room)
    touching[side] = body[side]  # one side of the bounds exactly on the body's edge
    clear = list(room)
    clear[side] = body[side] + (-1e-6 if side < 2 else 1e-6)
    check_endpoint(Map("m", tuple(clear), (), pose, pose, check_query=False), pose, "start", car)
    m = Map("m", tuple(touching), (), pose, pose, check_query=False)
    with pytest.raises(InputError, match=r"^start: the car's body at \(20, 10\) leaves or touches"):
        check_endpoint(m, pose, "start", car)


def test_a_pose_on_two_obstacles_names_the_first() -> None:
    """The message names the first obstacle in the file the body overlaps, and its centre."""
    from rrtdrive.maps import Map, Obstacle, check_endpoint
    from rrtdrive.types import Pose, VehicleParams

    pose = Pose(20.0, 10.0, 0.0)
    # Both overlap the body (x 19.1 .. 23.4): one behind the rear axle, one at the nose.
    obstacles = (Obstacle((30.0, 30.0), (1.0, 1.0)), Obstacle((19.5, 10.0), (1.0, 1.0)),
                 Obstacle((23.0, 10.0), (1.0, 1.0)))  # fmt: skip
    m = Map("m", (0.0, 0.0, 40.0, 40.0), obstacles, Pose(5.0, 30.0, 0.0), Pose(10.0, 30.0, 0.0))
    # By 0.895 m: the body's rear (x 19.105) must pass the block's right side (x 20.0).
    with pytest.raises(InputError, match=r"overlaps obstacle 1 at \[19\.5, 10\.0\] by 0\.895 m "):
        check_endpoint(m, pose, "goal", VehicleParams())


# ----------------------------------------------------------------------------- argument types


def test_an_integer_option_takes_both_ends_of_its_range() -> None:
    """``int_at_least(low, high=...)`` (``simulate --frequency``) takes ``low`` and ``high``."""
    import argparse

    from rrtdrive.cli_args import int_at_least

    parse = int_at_least(5, "Hz", 100)
    assert parse("5") == 5 and parse("100") == 100
    for bad in ("4", "101"):
        with pytest.raises(argparse.ArgumentTypeError,
                           match=r"^expected an integer >= 5 and <= 100 \(Hz\)"):
            parse(bad)


def test_a_negative_pose_starting_with_a_point_is_a_value(capsys) -> None:
    """``--start -.5,6,0`` after a space is the pose, as ``--start=-.5,6,0``: it reaches the
    bounds check (x = -0.5 lies outside parking_lot), not argparse's "expected one argument"."""
    for argv in (["--start", "-.5,6,0"], ["--start=-.5,6,0"]):
        code, _, err = _run(capsys, "plan", "parking_lot", *argv)
        _one_line(code, err, "rrtdrive plan: error: --start: (-0.5, 6) lies outside the bounds")


@pytest.mark.parametrize("value", ["inf", "1e999"])
def test_an_endless_time_cap_is_refused(capsys, value: str) -> None:
    """``--max-time`` is a safety cap: infinity (also written as an overflowing number) is
    no cap, so argparse refuses it by name before any planning."""
    code, _, err = _run(capsys, "plan", "parking_lot", "--max-time", value, "--max-iterations", "1")
    _one_line(code, err, "rrtdrive plan: error: argument --max-time: expected a finite number > 0")


def test_a_clearance_of_zero_is_a_valid_request(capsys, tmp_path: Path) -> None:
    """``verify --clearance 0`` asks only for no overlap: 0 is in ``nonneg_float``'s range."""
    from rrtdrive.cli_args import nonneg_float

    assert nonneg_float("0") == 0.0 and nonneg_float("-0") == 0.0
    f = tmp_path / "plan.json"
    rows = [[5.0 + 0.2 * i, 6.0, 0.0, 0.0, 1] for i in range(6)]
    f.write_text(json.dumps({"map": "parking_lot", "path": rows}))
    code, _, err = _run(capsys, "verify", str(f), "--clearance", "0")
    assert code in (0, 1) and "--clearance" not in err, err


def test_after_a_double_dash_nothing_is_joined() -> None:
    """Past ``--`` every token is positional: ``--start -5,6,0`` there stays two tokens."""
    from rrtdrive.cli_args import join_negative_values

    argv = ["plan", "--start", "-1,2,0", "--", "--start", "-5,6,0"]
    assert join_negative_values(argv, {"--start"}) == [
        "plan", "--start=-1,2,0", "--", "--start", "-5,6,0"]


@pytest.mark.parametrize("name", ["fig.PNG", "fig.Svg", "fig.pdf"])
def test_an_output_suffix_is_matched_in_any_case(tmp_path: Path, name: str) -> None:
    """``--plot FIG.PNG`` is a PNG: the suffix check ignores case."""
    from rrtdrive.cli_args import PLOT_SUFFIXES, validate_output

    validate_output(str(tmp_path / name), "--plot", PLOT_SUFFIXES, allow_stdout=False)
    with pytest.raises(InputError, match=r"^--plot: the file must end in \.pdf or \.png or \.svg"):
        validate_output(str(tmp_path / "fig.gif"), "--plot", PLOT_SUFFIXES, allow_stdout=False)


# ----------------------------------------------------------------------------- warnings


def test_input_warnings_are_one_line_each_once_and_others_go_to_the_previous_handler(
    capsys,
) -> None:
    """A repeated InputWarning is printed once; another kind of warning is handed to the
    handler in place before (Python's own format), not printed as an input slip."""
    import warnings

    from rrtdrive.cli_warnings import warnings_as_lines
    from rrtdrive.types import InputWarning

    handed: list[tuple[str, type[Warning]]] = []
    with warnings.catch_warnings():
        warnings.simplefilter("always", UserWarning)
        warnings.showwarning = lambda message, category, *rest: handed.append(
            (str(message), category))
        with warnings_as_lines("rrtdrive plan"):
            for text in ("goal: yaw 90 is more than a full turn", "goal: yaw 90 is more than a "
                         "full turn", "start: yaw 400 is more than a full turn"):
                warnings.warn(text, InputWarning, stacklevel=1)
            warnings.warn("something else", UserWarning, stacklevel=1)
    assert capsys.readouterr().err.splitlines() == [
        "rrtdrive plan: warning: goal: yaw 90 is more than a full turn",
        "rrtdrive plan: warning: start: yaw 400 is more than a full turn"]
    assert handed == [("something else", UserWarning)]


# ----------------------------------------------------------------------------- plan JSON


def _strict(text: str) -> dict:
    """``text`` parsed as strict JSON: NaN and Infinity are not JSON and fail here."""

    def refuse(name: str) -> None:
        raise AssertionError(f"{name} is not JSON")

    return json.loads(text, parse_constant=refuse)


def test_a_failed_plan_measures_nothing(capsys) -> None:
    """A failed plan has no path: its cusps, length, curvature and stage are null."""
    code, out, _ = _run(capsys, "plan", "no_path", "--planner", "rrt-connect", "--json", "-",
                        "--max-iterations", "50")  # fmt: skip
    doc = _strict(out)
    assert code == 1 and doc["success"] is False
    for key in ("cusps", "length_m", "max_curvature", "stage", "max_sharpness",
                "steer_rate_speed_limit", "body_clearance_m"):
        assert doc[key] is None, key


def test_a_straight_plan_writes_strict_json_with_a_null_speed_limit(capsys, tmp_path: Path,
                                                                   monkeypatch) -> None:
    """A straight path never steers: no steering-rate speed limit (null, not Infinity,
    which strict JSON readers refuse); the map file is named by its absolute path."""
    from rrtdrive.maps import Map, save_map
    from rrtdrive.types import Pose

    save_map(Map("open", (0.0, 0.0, 40.0, 20.0), (), Pose(5.0, 10.0, 0.0),
                 Pose(30.0, 10.0, 0.0)), tmp_path / "open.json")  # fmt: skip
    monkeypatch.chdir(tmp_path)
    code, out, _ = _run(capsys, "plan", "open.json", "--json", "-")
    doc = _strict(out)
    assert code == 0 and doc["cusps"] == 0 and doc["max_curvature"] == 0.0
    assert doc["max_sharpness"] == 0.0 and doc["steer_rate_speed_limit"] is None
    assert doc["map_file"] == str(tmp_path / "open.json")
    assert doc["start"] == [5.0, 10.0, 0.0] and doc["goal"] == [30.0, 10.0, 0.0]


# ----------------------------------------------------------------------------- stdout


@pytest.mark.skipif(not Path("/dev/full").exists(), reason="needs /dev/full")
@pytest.mark.parametrize("argv", [["maps"], ["maps", "--help"]])
def test_a_full_stdout_is_one_line_exit_1_with_buffered_output(argv: list[str]) -> None:
    """As users run it: stdout block-buffered (no PYTHONUNBUFFERED), the text meets the full
    disk only when flushed. The CLI must flush it itself (also before --help's exit) and
    report one line, exit 1, not Python's "Exception ignored" and exit 120 at shutdown."""
    import os
    import subprocess
    import sys

    env = {k: v for k, v in os.environ.items() if k != "PYTHONUNBUFFERED"}
    with open("/dev/full", "w") as full:
        proc = subprocess.run([sys.executable, "-m", "rrtdrive", *argv], stdout=full,
                              stderr=subprocess.PIPE, text=True, check=False, timeout=60,
                              env=env)  # fmt: skip
    assert proc.returncode == 1, proc.stderr
    assert proc.stderr == "rrtdrive: cannot write the output: No space left on device\n"


# ----------------------------------------------------------------------------- subcommands


def test_a_subcommand_that_cannot_load_is_bad_input_in_one_line(capsys, monkeypatch) -> None:
    """A partial install (highway-env missing) leaves ``simulate`` unloadable: one line,
    exit 2, naming the subcommand, never an ImportError traceback."""
    import rrtdrive.cli as cli

    broken = tuple(
        dataclasses.replace(c, builder="rrtdrive.no_such_module:add_parser")
        if c.name == "simulate" else c for c in cli.COMMANDS
    )  # fmt: skip
    monkeypatch.setattr(cli, "COMMANDS", broken)
    code, out, err = _run(capsys, "simulate", "parking_lot")
    _one_line(code, err, "rrtdrive simulate: error: simulate: not available (No module named")
    assert out == ""



def test_paper_smoothing_for_another_planner_is_named_by_its_flag(capsys) -> None:
    """``--paper-smoothing`` belongs to the improved planner: with ``--planner rrt`` the
    error names the flag typed, before any planning."""
    code, out, err = _run(capsys, "plan", "parking_lot", "--planner", "rrt", "--paper-smoothing")
    _one_line(code, err, "rrtdrive plan: error: --paper-smoothing: applies to the improved "
              "planner only, not 'rrt'")
    assert out == ""


def test_an_empty_import_name_is_refused_not_replaced(capsys, tmp_path: Path) -> None:
    """``--name ""`` (an unset shell variable) is bad input, not the file's own name."""
    _image(tmp_path, _lot_pixels(), "lot.png")
    out = tmp_path / "lot.json"
    code, _, err = _run(capsys, "maps", "--import", str(tmp_path / "lot.png"), *IMPORT_POSES,
                        "--resolution", "0.1", "--out", str(out), "--name", "")  # fmt: skip
    _one_line(code, err, "rrtdrive maps: error: --name: expected a non-empty string, got ''")
    assert not out.exists()


@pytest.mark.parametrize(("dev", "same"), [(7, True), (8, False)])
def test_stdout_is_known_by_device_and_inode_together(monkeypatch, dev: int, same: bool) -> None:
    """Two files on two file systems may share an inode number: only the same device and
    inode make ``--json FILE`` the file stdout writes to (else the JSON left the file)."""
    import os
    import stat
    import sys
    from types import SimpleNamespace

    from rrtdrive import cli_args

    mine = SimpleNamespace(st_mode=stat.S_IFREG | 0o644, st_dev=7, st_ino=4242)
    theirs = SimpleNamespace(st_mode=stat.S_IFREG | 0o644, st_dev=dev, st_ino=4242)
    real_fstat, real_stat = os.fstat, os.stat
    monkeypatch.setattr(sys, "stdout", SimpleNamespace(fileno=lambda: -7))
    monkeypatch.setattr(os, "fstat", lambda fd: mine if fd == -7 else real_fstat(fd))
    monkeypatch.setattr(os, "stat", lambda path, *args, **kwargs: theirs if path == "out.json"
                        else real_stat(path, *args, **kwargs))  # fmt: skip
    answer = cli_args.names_stdout("out.json")
    monkeypatch.undo()
    assert answer is same


def test_two_obstacle_yaws_past_a_full_turn_are_one_warning_in_good_english() -> None:
    """One more yaw is "1 more obstacle yaw", not "yaws"."""
    from rrtdrive.maps import map_from_json
    from rrtdrive.types import InputWarning

    data = {"name": "m", "bounds": [0, 0, 40, 20], "start": [5, 10, 0], "goal": [30, 10, 0],
            "obstacles": [{"center": [20, 2], "size": [2, 1], "yaw": 90},
                          {"center": [20, 18], "size": [2, 1], "yaw": 90}]}  # fmt: skip
    with pytest.warns(InputWarning) as caught:
        map_from_json(data)
    assert len(caught) == 1
    assert str(caught[0].message).startswith(
        "obstacles[0].yaw (and 1 more obstacle yaw past a full turn): yaw 90 is more than")
