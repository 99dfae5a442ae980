"""Bad input and broken output of every subcommand: one line on stderr, the right exit code.

Huge integer literals, JSON nested too deeply, non-finite path rows, files that are not
UTF-8, unwritable export targets, empty option values, a deterministic bench given a
time limit, and a stdout that is closed or full. Nothing here plans for long or drives.
"""

from __future__ import annotations

import dataclasses
import io
import json
import os
import re
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

from rrtdrive.cli import main
from rrtdrive.maps import builtin_map
from rrtdrive.types import InputError
from rrtdrive.types import Path as RowPath

HUGE = 10**400  # a JSON integer literal of 401 digits: no float holds it
ROOT = Path(__file__).resolve().parent.parent


def run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def one_line(code, err, needle, expected_code=2):
    """The contract: ``expected_code``, one stderr line containing ``needle``, no traceback."""
    assert code == expected_code, err
    assert "Traceback" not in err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert needle in lines[0], lines[0]
    return lines[0]


def write_map(tmp_path, **patch):
    data = builtin_map("overtake").to_json() | patch
    f = tmp_path / "m.json"
    f.write_text(json.dumps(data))
    return str(f)


def plan_rows():
    """A short forward path of parking_lot from its start, rows [x, y, yaw, kappa, gear]."""
    xs = 5.0 + 0.2 * np.arange(6)
    return [[float(x), 6.0, 0.0, 0.0, 1] for x in xs]


def write_plan(tmp_path, rows=None, **extra):
    doc = {"map": "parking_lot", "path": plan_rows() if rows is None else rows, **extra}
    f = tmp_path / "plan.json"
    f.write_text(json.dumps(doc))  # NaN and Infinity as the literals json writes
    return str(f)


# ----------------------------------------------------------------------------- 1: huge ints


@pytest.mark.parametrize(
    ("patch", "field"),
    [
        ({"obstacles": [{"center": [50, 20], "size": [4, HUGE]}]}, "obstacles[0].size"),
        ({"bounds": [0, 0, HUGE, 100]}, "bounds"),
        ({"start": [5, HUGE, 0]}, "start"),
    ],
)
def test_huge_integer_in_a_map_names_the_field(capsys, tmp_path, patch, field):
    f = write_map(tmp_path, **patch)
    line = one_line(*run(capsys, "plan", f)[::2], f"{field}: must be finite")
    assert "401 digits" in line and len(line) < 200  # abbreviated, not 400 digits


def test_huge_integer_map_in_verify_and_bench(capsys, tmp_path):
    f = write_map(tmp_path, obstacles=[{"center": [50, 20], "size": [4, HUGE]}])
    plan = write_plan(tmp_path)
    one_line(*run(capsys, "verify", plan, f)[::2], "obstacles[0].size: must be finite")
    code, _, err = run(capsys, "bench", "--maps", f, "--out", str(tmp_path / "b"))
    one_line(code, err, "obstacles[0].size: must be finite")
    assert not (tmp_path / "b").exists()


def test_huge_integer_in_a_bench_config(capsys, tmp_path):
    toml = tmp_path / "b.toml"
    toml.write_text(f'maps = ["overtake"]\nmax_time_s = {HUGE}\n')
    code, _, err = run(capsys, "bench", "--config", str(toml), "--out", str(tmp_path / "b"))
    one_line(code, err, "max_time_s: must be a finite number")


def test_require_finite_abbreviates_a_huge_integer():
    from rrtdrive.types import require_finite

    expected = r"^x: must be finite, got 1000000000\.\.\.\(401 digits\)$"
    with pytest.raises(InputError, match=expected):
        require_finite("x", HUGE)


# ----------------------------------------------------------------------------- 2: deep JSON


@pytest.fixture
def deep(tmp_path):
    f = tmp_path / "deep.json"
    f.write_text("[" * 100_000 + "]" * 100_000)
    return str(f)


def test_deep_json_map(capsys, deep):
    one_line(*run(capsys, "plan", deep)[::2], "map: malformed JSON in")
    code, _, err = run(capsys, "plan", deep)
    assert "deep.json: nested too deeply" in err


def test_deep_json_plan(capsys, deep):
    one_line(*run(capsys, "verify", deep)[::2], "plan: malformed JSON in")


def test_deep_json_bench_maps(capsys, deep, tmp_path):
    code, _, err = run(capsys, "bench", "--maps", deep, "--out", str(tmp_path / "b"))
    one_line(code, err, "nested too deeply")


def test_deep_toml_bench_config(capsys, tmp_path):
    toml = tmp_path / "deep.toml"
    toml.write_text("maps = " + "[" * 100_000 + "]" * 100_000 + "\n")
    one_line(*run(capsys, "bench", "--config", str(toml))[::2], "config: malformed TOML")


# ----------------------------------------------------------------------------- 3: path rows


@pytest.mark.parametrize("column, name", [(0, "x"), (1, "y"), (2, "yaw"), (3, "kappa")])
@pytest.mark.parametrize("value, shown", [
    (float("nan"), "nan"), (float("inf"), "inf"), (None, "None"), ("1", "'1'"), (True, "True"),
])
def test_verify_non_finite_path_value_names_the_row(capsys, tmp_path, column, name, value,
                                                     shown):
    rows = plan_rows()
    rows[3][column] = value
    line = one_line(*run(capsys, "verify", write_plan(tmp_path, rows))[::2], "path: row 3")
    assert line.endswith(f"path: row 3 {name} must be a finite number, got {shown}")


def test_verify_huge_integer_in_the_path(capsys, tmp_path):
    rows = plan_rows()
    rows[0][0] = HUGE
    line = one_line(*run(capsys, "verify", write_plan(tmp_path, rows))[::2], "path: row 0 x")
    assert "401 digits" in line


@pytest.mark.parametrize("gear, shown", [("1", "'1'"), (True, "True"), (0, "0"),
                                         (float("nan"), "nan"), (0.5, "0.5")])
def test_verify_gear_must_be_the_number_plus_or_minus_one(capsys, tmp_path, gear, shown):
    rows = plan_rows()
    rows[2][4] = gear
    line = one_line(*run(capsys, "verify", write_plan(tmp_path, rows))[::2], "path.gear")
    assert f"got {shown} in row 2" in line


def test_path_gear_message_shows_plain_numbers():
    rows = np.array(plan_rows(), dtype=float)
    rows[1, 4] = 0.0
    with pytest.raises(InputError) as info:
        RowPath(rows, np.zeros((0, 2)))
    assert "got 0.0 in row 1" in str(info.value) and "np." not in str(info.value)


# ----------------------------------------------------------------------------- 4: plan not UTF-8


def test_verify_plan_not_utf8(capsys, tmp_path):
    f = tmp_path / "latin1.json"
    f.write_bytes('{"map": "Stra\xdfe", "path": []}'.encode("latin-1"))
    one_line(*run(capsys, "verify", str(f))[::2], "plan: ")
    code, _, err = run(capsys, "verify", str(f))
    assert "latin1.json is not a UTF-8 text file" in err


def test_verify_stdin_not_utf8(capsys, monkeypatch):
    raw = '{"map": "Stra\xdfe", "path": []}'.encode("latin-1")
    monkeypatch.setattr(sys, "stdin", io.TextIOWrapper(io.BytesIO(raw), encoding="utf-8"))
    one_line(*run(capsys, "verify", "-")[::2], "plan: stdin is not a UTF-8 text file")


# ----------------------------------------------------------------------------- 5: maps --export


def test_export_onto_a_folder_writes_nothing(capsys, tmp_path):
    (tmp_path / "parking_lot.json").mkdir()  # in the way of one of the files
    one_line(*run(capsys, "maps", "--export", str(tmp_path))[::2], "--export")
    assert [p.name for p in tmp_path.iterdir()] == ["parking_lot.json"]  # no partial export


@pytest.mark.skipif(os.name != "posix" or os.geteuid() == 0,
                    reason="needs a user whom the mode bits stop")
def test_export_into_a_read_only_folder(capsys, tmp_path):
    folder = tmp_path / "ro"
    folder.mkdir()
    folder.chmod(0o555)
    try:
        one_line(*run(capsys, "maps", "--export", str(folder))[::2], "--export")
    finally:
        folder.chmod(0o755)
    assert list(folder.iterdir()) == []


def test_export_write_failure_is_one_line_and_leaves_no_temp_file(capsys, tmp_path,
                                                                   monkeypatch):
    import rrtdrive.atomic

    def full_disk(self, *args, **kwargs):
        raise OSError(28, "No space left on device")

    # The write itself fails after the checks passed (the disk filled up meanwhile):
    # not bad input, so exit 1 (README: output that cannot be written).
    monkeypatch.setattr(rrtdrive.atomic.Path, "write_text", full_disk)
    code, _, err = run(capsys, "maps", "--export", str(tmp_path))
    one_line(code, err, "--export: cannot write", expected_code=1)
    assert "No space left on device" in err
    assert list(tmp_path.iterdir()) == []


def test_export_that_fails_midway_leaves_the_folder_as_it_was(capsys, tmp_path, monkeypatch):
    from rrtdrive.maps import BUILTIN_MAPS

    names = list(BUILTIN_MAPS)
    for name in names:
        (tmp_path / f"{name}.json").write_text("old\n")
    real_write = Path.write_text
    written = []

    def fills_up(self, *args, **kwargs):
        if len(written) == 2:  # the third map finds the disk full
            raise OSError(28, "No space left on device")
        written.append(self)
        return real_write(self, *args, **kwargs)

    monkeypatch.setattr(Path, "write_text", fills_up)
    code, _, err = run(capsys, "maps", "--export", str(tmp_path))
    one_line(code, err, f"--export: cannot write {tmp_path / names[2]}.json", expected_code=1)
    # All or nothing: the two maps written before stayed temporary files, now removed.
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(f"{n}.json" for n in names)
    assert all((tmp_path / f"{n}.json").read_text() == "old\n" for n in names)


def test_plan_json_write_failure_exits_1(capsys, tmp_path, monkeypatch):
    import rrtdrive.atomic

    def full_disk(self, *args, **kwargs):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(rrtdrive.atomic.Path, "write_text", full_disk)
    target = tmp_path / "p.json"
    code, _, err = run(capsys, "plan", "overtake", "--planner", "rrt", "--json", str(target))
    one_line(code, err, f"--json: cannot write {target}", expected_code=1)
    assert list(tmp_path.iterdir()) == []


def test_json_through_a_symbolic_link_replaces_the_file_it_points_to(capsys, tmp_path):
    real = tmp_path / "real.json"
    real.write_text("old\n")
    real.chmod(0o640)
    link = tmp_path / "link.json"
    link.symlink_to(real.name)
    code, _, _ = run(capsys, "plan", "overtake", "--planner", "rrt", "--json", str(link))
    assert code == 0
    assert link.is_symlink() and os.readlink(link) == real.name  # the link stays a link
    assert json.loads(real.read_text())["planner"] == "rrt"
    assert real.stat().st_mode & 0o777 == 0o640  # the replaced file's permissions kept
    assert sorted(p.name for p in tmp_path.iterdir()) == ["link.json", "real.json"]


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="needs named pipes")
def test_json_into_a_named_pipe_is_written_into_it(capsys, tmp_path):
    import threading

    fifo = tmp_path / "plan.json"
    os.mkfifo(fifo)
    got = []
    # A daemon: were the pipe renamed over, the reader would wait for ever.
    reader = threading.Thread(target=lambda: got.append(fifo.read_text()), daemon=True)
    reader.start()
    code, _, _ = run(capsys, "plan", "overtake", "--planner", "rrt", "--json", str(fifo))
    reader.join(timeout=60)
    assert code == 0 and got, "nothing came through the pipe"
    assert json.loads(got[0])["planner"] == "rrt"
    assert fifo.is_fifo()  # still a pipe, not a regular file renamed over it
    assert [p.name for p in tmp_path.iterdir()] == ["plan.json"]


def test_two_outputs_to_one_file_are_bad_input(capsys, tmp_path):
    same = tmp_path / "out.png"
    one_line(*run(capsys, "plan", "overtake", "--json", str(same), "--plot", str(same))[::2],
             "--plot: " + repr(str(same)) + " is also the --json file")
    link = tmp_path / "link.mp4"
    link.symlink_to(tmp_path / "out.mp4")  # through a link it is the same file still
    one_line(*run(capsys, "simulate", "parking", "--video", str(tmp_path / "out.mp4"),
                  "--json", str(link))[::2], "is also the --video file")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["link.mp4"]  # nothing run


def test_an_output_that_would_overwrite_an_input_file_is_bad_input(capsys, tmp_path):
    from rrtdrive.maps import save_map

    lot = tmp_path / "lot.json"
    save_map(builtin_map("overtake"), lot)
    before = lot.read_bytes()
    one_line(*run(capsys, "plan", str(lot), "--json", str(lot))[::2],
             f"--json: {str(lot)!r} is the MAP file it reads")
    one_line(*run(capsys, "simulate", str(lot), "--json", str(lot))[::2],
             f"--json: {str(lot)!r} is the SCENARIO file it reads")
    plan = tmp_path / "plan.json"
    assert run(capsys, "plan", str(lot), "--planner", "rrt", "--json", str(plan))[0] == 0
    plan_bytes = plan.read_bytes()
    one_line(*run(capsys, "verify", str(plan), "--json", str(plan))[::2],
             f"--json: {str(plan)!r} is the PLAN file it reads")
    # The map file the plan names (map_file) is read too, so it is not written over either.
    one_line(*run(capsys, "verify", str(plan), "--json", str(lot))[::2],
             f"--json: {str(lot)!r} is the MAP file it reads")
    assert lot.read_bytes() == before and plan.read_bytes() == plan_bytes


def test_an_endless_input_is_refused_not_read_for_ever(capsys, tmp_path, monkeypatch):
    import rrtdrive.json_input
    from rrtdrive.maps import save_map

    f = tmp_path / "m.json"
    save_map(builtin_map("overtake"), f)
    # The cap (256 MB) made small: the same code path as /dev/zero, without reading it.
    monkeypatch.setattr(rrtdrive.json_input, "MAX_JSON_BYTES", f.stat().st_size - 1)
    one_line(*run(capsys, "plan", str(f))[::2], f"map: {f} is larger than")
    one_line(*run(capsys, "verify", str(f))[::2], f"plan: {f} is larger than")
    monkeypatch.setattr(rrtdrive.json_input, "MAX_JSON_BYTES", f.stat().st_size)
    assert run(capsys, "plan", str(f))[0] == 0  # exactly the cap is read


def test_simulate_max_time_shorter_than_a_step_is_bad_input(capsys):
    # It used to drive one 0.05 s step and report both "within 0.1 s" and "within 1e-09 s".
    one_line(*run(capsys, "simulate", "parking", "--max-time", "1e-9")[::2],
             "--max-time: 1e-09 s is shorter than one simulation step (0.05 s at 20 Hz)")


def test_empty_output_name_is_bad_input(capsys):
    one_line(*run(capsys, "plan", "overtake", "--json", "")[::2], "--json: needs a file name")


# ------------------------------------------------------------------- 6: deterministic bench


@pytest.mark.parametrize("max_time", ["5.0", "5", "2.0"])
def test_deterministic_toml_rejects_any_max_time(capsys, tmp_path, max_time):
    toml = tmp_path / "b.toml"
    toml.write_text(f'maps = ["overtake"]\ndeterministic = true\nmax_time_s = {max_time}\n')
    code, _, err = run(capsys, "bench", "--config", str(toml), "--out", str(tmp_path / "b"))
    one_line(code, err, "max_time_s: a deterministic bench has no planning time limit")


@pytest.mark.parametrize("where", ["toml", "flag"])
def test_deterministic_rejects_the_max_time_flag_even_at_its_default(capsys, tmp_path, where):
    toml = tmp_path / "b.toml"
    toml.write_text('maps = ["overtake"]\n' + ("deterministic = true\n" if where == "toml" else ""))
    argv = ["bench", "--config", str(toml), "--max-time", "5", "--out", str(tmp_path / "b")]
    if where == "flag":
        argv.append("--deterministic")
    one_line(*run(capsys, *argv)[::2], "--max-time")


def test_bench_refuses_reverse_for_the_scenario_that_re_plans(capsys, tmp_path):
    # As simulate --reverse does: its re-planner drives forward only.
    out = tmp_path / "b"
    one_line(*run(capsys, "bench", "--scenarios", "overtake-traffic", "--reverse",
                  "--out", str(out))[::2], "reverse: overtake-traffic re-plans while driving")
    assert not out.exists()


def test_bench_refuses_another_planner_for_the_scenario_that_re_plans(capsys, tmp_path):
    # It re-plans with its own space-time planner: every run with another became an error
    # row, tried twice, and the bench exited 1.
    out = tmp_path / "b"
    one_line(*run(capsys, "bench", "--scenarios", "parking,overtake-traffic", "--planners",
                  "improved-rrt-connect,rrt-connect", "--out", str(out))[::2],
             "planners: overtake-traffic re-plans with its own space-time planner")  # fmt: skip
    assert not out.exists()


def test_bench_time_limit_defaults_are_unchanged():
    from rrtdrive.bench import BenchConfig
    from rrtdrive.bench.config_file import config_from_mapping
    from rrtdrive.bench.grid import NO_WALL_LIMIT_S

    assert config_from_mapping({"maps": ["overtake"]}).to_json()["max_time_s"] == 5.0
    det = config_from_mapping({"maps": ["overtake"], "deterministic": True})
    assert det.max_time_s == NO_WALL_LIMIT_S
    assert det.to_json()["max_time_s"] is None  # recorded as no limit: fed back as a config
    assert dataclasses.replace(det, seeds=2).max_time_s == NO_WALL_LIMIT_S  # a copy stays valid
    assert BenchConfig(maps=("overtake",), max_time_s=2.0).max_time_s == 2.0
    with pytest.raises(InputError, match="^max_time_s: a deterministic bench"):
        BenchConfig(maps=("overtake",), max_time_s=5.0, deterministic=True)


# ----------------------------------------------------------------------------- 7: stdout


def _cli(*argv, **kwargs):
    return subprocess.run([sys.executable, "-m", "rrtdrive", *argv], capture_output=True,
                          text=True, check=False, timeout=60, **kwargs)


def test_closed_stdout_ends_quietly():
    proc = subprocess.Popen([sys.executable, "-m", "rrtdrive", "maps"], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE)
    proc.stdout.close()  # the reader leaves before the first line, as `| head -0`
    err = proc.stderr.read().decode()
    proc.stderr.close()
    assert proc.wait(timeout=60) == 141
    assert err == ""


@pytest.mark.skipif(not Path("/dev/full").exists(), reason="needs /dev/full")
@pytest.mark.parametrize("argv", [["maps"], ["maps", "--help"]])
def test_full_stdout_is_one_line_exit_1(argv):
    with open("/dev/full", "w") as full:
        proc = subprocess.run([sys.executable, "-m", "rrtdrive", *argv], stdout=full,
                              stderr=subprocess.PIPE, text=True, check=False, timeout=60)
    one_line(proc.returncode, proc.stderr, "rrtdrive: cannot write the output: No space left",
             expected_code=1)


def test_other_os_errors_are_not_called_output_errors(capsys, monkeypatch):
    import rrtdrive.maps

    def broken(name):
        raise FileNotFoundError(2, "No such file or directory")

    monkeypatch.setattr(rrtdrive.maps, "builtin_map", broken)
    with pytest.raises(FileNotFoundError):  # a bug stays a bug, not "cannot write the output"
        main(["maps"])


# ----------------------------------------------------------------------------- 8: smaller ones


@pytest.mark.parametrize("field", ["start", "goal"])
def test_verify_names_the_plans_own_pose(capsys, tmp_path, field):
    f = write_plan(tmp_path, **{field: [float("nan"), 6, 0]})
    one_line(*run(capsys, "verify", f)[::2], f"plan.{field}: must be finite")


@pytest.mark.parametrize("waypoints", [[[1, 2, 3]], "x", [[1, float("nan")]], [[1, True]]])
def test_verify_names_malformed_waypoints(capsys, tmp_path, waypoints):
    f = write_plan(tmp_path, waypoints=waypoints)
    one_line(*run(capsys, "verify", f)[::2], "error: waypoints: expected")


@pytest.mark.parametrize("command", ["plan", "verify", "simulate"])
@pytest.mark.parametrize("flag", ["--start", "--goal"])
def test_empty_pose_option_is_bad_input(capsys, tmp_path, command, flag):
    target = {"plan": ["overtake"], "verify": [write_plan(tmp_path)], "simulate": ["garage"]}
    code, _, err = run(capsys, command, *target[command], f"{flag}=")
    one_line(code, err, f"{flag}: expected X,Y,YAW, got an empty value")


def test_empty_export_folder_is_bad_input(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    one_line(*run(capsys, "maps", "--export", "")[::2], "--export: expected a folder")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("name", [None, ["x"], 3, ""])
def test_map_name_must_be_a_string(capsys, tmp_path, name):
    one_line(*run(capsys, "plan", write_map(tmp_path, name=name))[::2], "name: expected")


@pytest.mark.parametrize("x", [1e308, 1e6])
def test_verify_far_row_fails_without_warnings(capsys, tmp_path, x):
    rows = plan_rows()
    rows[3][0] = x
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a numpy RuntimeWarning would raise here
        code, out, err = run(capsys, "verify", write_plan(tmp_path, rows))
    assert code == 1 and err == ""
    assert "FAIL body clear of obstacles" in out
    assert not re.search(r"\d{20}", out)  # 1e+308, not 309 digits


# ----------------------------------------------------------------------------- 9: messages, README


def test_simulate_timeout_hint_names_plan_time():
    from rrtdrive.planning.result import timeout_message
    from rrtdrive.sim.cli_targets import with_simulate_hint as _with_simulate_hint
    from rrtdrive.types import Budget

    @dataclasses.dataclass(frozen=True)
    class Plan:
        message: str

    @dataclasses.dataclass(frozen=True)
    class Episode:
        message: str
        plan: Plan | None

    text = "planning failed (timeout): " + timeout_message(0, Budget(max_time_s=1e-9))
    fixed = _with_simulate_hint(Episode(text, Plan(text)))
    for message in (fixed.message, fixed.plan.message):
        assert message.endswith("; raise --plan-time")
        assert "--max-time" not in message and "--max-iterations" not in message
    untouched = Episode("arrived", None)
    assert _with_simulate_hint(untouched) is untouched


@pytest.mark.skipif(not (ROOT / "README.md").is_file(), reason="needs the repository's README")
def test_readme_plan_synopsis_lists_every_option():
    from rrtdrive.cli import _build

    block = re.search(r"```text\n(rrtdrive plan .*?)\nrrtdrive ", (ROOT / "README.md").read_text(),
                      re.S).group(1)
    plan = _build("plan")[1]
    options = {o for a in plan._actions for o in a.option_strings if o.startswith("--")}
    missing = sorted(o for o in options - {"--help"} if f"[{o}" not in block)
    assert missing == []


# ------------------------------------------------ bench seeds bounded; strict verify JSON


@pytest.mark.parametrize("seeds", ["100001", "1000000000"])
def test_a_bench_of_endless_seeds_is_refused(capsys, tmp_path, seeds):
    code, _, err = run(
        capsys, "bench", "--maps", "dead_end", "--seeds", seeds, "--out", str(tmp_path / "b")
    )
    one_line(code, err, "seeds")
    assert not (tmp_path / "b").exists()


def test_verify_json_of_a_far_row_is_strict_json(capsys, tmp_path):
    rows = plan_rows()
    rows[3][0] = 1e308
    code, out, _ = run(capsys, "verify", write_plan(tmp_path, rows), "--json", "-")
    assert code == 1
    doc = json.loads(out.strip().splitlines()[-1], parse_constant=pytest.fail)
    assert doc["ok"] is False and doc["length_m"] is None


def test_an_output_path_ending_in_a_slash_is_bad_input(capsys, tmp_path):
    # pathlib drops the slash: 'out.png/' wrote the file out.png.
    for flag, target in (("--plot", "out.png/"), ("--json", "out.json/")):
        one_line(*run(capsys, "plan", "overtake", flag, str(tmp_path) + "/" + target)[::2],
                 f"{flag}: ")
    assert list(tmp_path.iterdir()) == []


def _file_size_limit(kib: int):
    import resource

    def limit() -> None:  # in the child: writes past it fail with EFBIG (File too large)
        resource.setrlimit(resource.RLIMIT_FSIZE, (kib * 1024, kib * 1024))

    return limit


def test_a_bench_that_runs_out_of_room_says_so_in_one_line(tmp_path):
    # A full disk while storing rows was a traceback (OSError out of the store); the
    # rows stored so far stay for a re-run to resume from.
    import subprocess

    out = tmp_path / "b"
    argv = [sys.executable, "-m", "rrtdrive", "bench", "--maps", "parking_lot",
            "--planners", "rrt-connect", "--seeds", "20", "--workers", "1", "--quiet",
            "--out", str(out)]  # fmt: skip
    done = subprocess.run(argv, capture_output=True, text=True, timeout=300,
                          preexec_fn=_file_size_limit(8))  # fmt: skip
    assert done.returncode == 1, done.stderr
    line = f"rrtdrive bench: error: --out: cannot write {out}: File too large"
    assert done.stderr.strip() == line


def test_a_video_that_runs_out_of_room_says_so_in_one_line(tmp_path):
    # imageio's error carried ffmpeg's command line and its output after the first line.
    # A short drive: ffmpeg, killed at the size limit, no longer breaks the pipe before
    # the end, and imageio-ffmpeg does not look at its exit status: a truncated file was
    # published as the video (exit 0 for the video, no word).
    import subprocess

    out = tmp_path / "v.mp4"
    argv = [sys.executable, "-m", "rrtdrive", "simulate", "parking", "--max-time", "3",
            "--video", str(out)]
    done = subprocess.run(argv, capture_output=True, text=True, timeout=300,
                          preexec_fn=_file_size_limit(1))  # fmt: skip
    assert done.returncode == 1, done.stderr
    lines = [x for x in done.stderr.splitlines() if x and " video " not in x]  # progress
    assert lines == [f"rrtdrive simulate: error: --video: cannot write {out}: File too large"]
    assert not out.exists() and os.listdir(tmp_path) == []


@pytest.mark.parametrize("argv, prefix", [
    (["maps", "foo"], "rrtdrive maps: error: unrecognized arguments: foo"),
    (["plan", "parking_lot", "--out", "x"],
     "rrtdrive plan: error: unrecognized arguments: --out x"),
])
def test_an_unknown_argument_is_named_by_its_subcommand(capsys, argv, prefix):
    with pytest.raises(SystemExit) as exc:
        main(argv)
    err = capsys.readouterr().err
    assert exc.value.code == 2 and err == prefix + " (see --help)\n"


def test_a_video_stride_without_a_video_is_refused(capsys):
    # It was read and silently ignored; other options that do not apply are refused.
    assert main(["simulate", "u-turn", "--video-stride", "5"]) == 2
    err = capsys.readouterr().err
    assert err == "rrtdrive simulate: error: --video-stride: only with --video (it sets the " \
        "video's frames)\n"


@pytest.mark.parametrize("argv, message", [
    (["simulate", "u-turn", "--video", ".mp4"],
     "--video: '.mp4' is a suffix without a name; name the file, e.g. 'run.mp4'"),
    (["plan", "garage", "--plot", ".PNG"],
     "--plot: '.PNG' is a suffix without a name; name the file, e.g. 'run.png'"),
    (["plan", "garage", "--plot", "{file}/x.png"], "--plot: '{file}' is a file, not a folder"),
])
def test_an_odd_output_name_is_named_for_what_it_is(capsys, tmp_path, argv, message):
    # They said "must end in .mp4, got '.mp4'" and "folder ... does not exist".
    file = tmp_path / "afile"
    file.write_text("")
    argv = [a.format(file=file) for a in argv]
    code, _, err = run(capsys, *argv)
    assert code == 2 and err.endswith(f"error: {message.format(file=file)}\n"), err


def test_flags_for_warnings_renames_only_input_warnings_of_its_fields():
    from rrtdrive.cli_args import flags_for_warnings
    from rrtdrive.types import InputWarning

    with warnings.catch_warnings(record=True) as got:
        warnings.simplefilter("always")
        with pytest.raises(InputError), flags_for_warnings({"goal": "--goal"}):
            warnings.warn("goal: yaw 90 is more than a full turn", InputWarning, stacklevel=1)
            warnings.warn("start: yaw 90 is more than a full turn", InputWarning, stacklevel=1)
            warnings.warn("goal: not an input warning", UserWarning, stacklevel=1)
            raise InputError("goal: an error after the warnings")  # they are still shown
    assert [str(w.message) for w in got] == [
        "--goal: yaw 90 is more than a full turn", "start: yaw 90 is more than a full turn",
        "goal: not an input warning",
    ]
