"""A user's audit of ``rrtdrive simulate``'s input and output contract (session 47).

Sources held to: SPEC §4-6, README "Command line" and "rrtdrive simulate", docs/metrics.md
(every JSON field, "The run: identity, options and scenario settings"), ``simulate --help``.
Media (``--video``, ``--plot``) had their own audit and are left out. Episodes are kept short
(``--max-time`` under a second, small maps) so the file runs in well under a minute.
"""

from __future__ import annotations

import csv
import dataclasses
import json
import math
import re
import subprocess
import sys
from pathlib import Path

import pytest

from rrtdrive.cli import main

DOCS = Path(__file__).resolve().parents[1] / "docs"

#: A small open map: the default planner drives it start to goal in about 11 s.
OPEN_MAP = {
    "name": "open",
    "bounds": [0, 0, 40, 20],
    "obstacles": [{"center": [20, 16], "size": [4, 2], "yaw": 0.0}],
    "start": [5, 5, 0],
    "goal": [25, 5, 0],
}
#: The goal walled off: planning is proven impossible before any search.
WALL_MAP = {
    "name": "wall",
    "bounds": [0, 0, 40, 20],
    "obstacles": [{"center": [20, 10], "size": [1, 20], "yaw": 0.0}],
    "start": [5, 10, 0],
    "goal": [35, 10, 0],
}
#: The wall-clock fields docs/metrics.md ("deterministic") says may vary between two runs.
WALL_CLOCK = {
    "total_time_s", "wall_time_s", "planning_time_s", "setup_time_s",
    "replan_time_median_s", "replan_time_max_s", "replans_over_budget",
}
TRAJECTORY_COLUMNS = ["t", "x", "y", "yaw", "speed", "steer", "accel", "gear"]
WHEELBASE = 2.51
STATUSES = {"arrived", "completed", "crashed", "timeout", "plan_failed"}
OUTCOMES = {"success", "collision", "safe_following", "failed"}

# The report's fields (docs/metrics.md) by JSON type: "?" allows null.
STR = ("scenario", "planner", "controller", "status", "message", "outcome", "target")
INT = ("seed", "steps", "collisions_vehicles", "collisions_at_fault", "gear_changes",
       "oncoming")
INT_OR_NULL = ("replans", "replans_over_budget", "unsafe_steps", "path_cusps",
               "max_iterations")
BOOL = ("success", "collision", "collision_highway_env", "collision_footprint",
        "reached_goal", "stopped", "deterministic", "reverse")
BOOL_OR_NULL = ("passed_lead", "back_in_lane", "ttc_within_bound", "nuplan_comfortable")
NUMBER = ("kappa_max", "duration_s", "wall_time_s", "simulation_frequency", "total_time_s")
NUMBER_OR_NULL = (
    "cte_rms_m", "cte_max_m", "heading_err_rms_rad", "heading_err_max_rad",
    "path_max_curvature", "path_length_m", "executed_max_curvature",
    "executed_curvature_violation_share", "max_lateral_accel", "max_long_accel", "max_jerk",
    "max_steering_rate", "goal_position_err_m", "goal_heading_err_rad", "final_speed",
    "time_to_goal_s", "planning_time_s", "completion_time_s", "progress_m", "ttc_min_s",
    "min_distance_m", "replan_time_median_s", "replan_time_max_s", "replan_budget_s",
    "steering_rate_over_limit_share", "path_max_sharpness", "nuplan_lon_accel_min",
    "nuplan_lon_accel_max", "nuplan_lat_accel_abs_max", "nuplan_lon_jerk_abs_max",
    "nuplan_jerk_abs_max", "nuplan_yaw_rate_abs_max", "nuplan_yaw_accel_abs_max",
    "setup_time_s", "plan_max_time_s",
)
#: Fields only some runs have (docs/metrics.md, the table's second column).
CONDITIONAL = {
    "parking": ("spot", "reverse_in"),
    "parallel-parking": ("gap_factor", "gap_m"),
    "u-turn": ("street_width_m", "forward_u_turn_width_m"),
    "overtake-traffic": ("density_per_km", "lead_speed", "lead_model", "replan_rate_hz",
                         "predictor"),
    "stock": ("map", "env_id", "highway_env_success", "highway_env_terminated_s",
              "highway_env_truncated", "highway_env_return"),
    "map": ("map",),
    "path": ("path_file",),
}
SUMMARY = re.compile(
    r"^(?P<scenario>\S+) seed (?P<seed>\d+) (?P<planner>[^/ ]+)/(?P<controller>\S+): "
    r"(?P<verdict>.+); cte rms (?P<cte>n/a|\d+\.\d{3} m); (?P<steps>\d+) steps, "
    r"(?P<duration>\d+\.\d{2}) s simulated$"
)


# --------------------------------------------------------------------------- helpers


def run(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[object, str, str]:
    """``rrtdrive`` in this process: exit code (argparse's too), stdout, stderr."""
    try:
        code: object = main(list(argv))
    except SystemExit as exc:
        code = exc.code
    out, err = capsys.readouterr()
    return code, out, err


def one_error_line(code: object, err: str, needle: str) -> str:
    """Exit 2, no traceback, exactly one stderr line naming ``needle``."""
    assert code == 2, err
    assert "Traceback" not in err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert needle in lines[0], lines[0]
    return lines[0]


def write(tmp: Path, name: str, doc: object) -> str:
    f = tmp / name
    f.write_text(doc if isinstance(doc, str) else json.dumps(doc))
    return str(f)


def read_trajectory(path: Path) -> tuple[list[str], list[list[float]]]:
    with path.open(newline="") as f:
        rows = list(csv.reader(f))
    return rows[0], [[float(v) for v in r] for r in rows[1:]]


def close(a: float, b: float, rel: float = 1e-5, abs_: float = 1e-6) -> bool:
    """The JSON keeps 6 significant digits of a float."""
    return math.isclose(a, b, rel_tol=rel, abs_tol=abs_)


def check_types(data: dict) -> None:
    """Every report field is present with its documented JSON type."""
    def kind(v: object) -> str:
        return type(v).__name__

    for k in STR:
        assert type(data[k]) is str, (k, data[k])
    for k in INT:
        assert type(data[k]) is int and data[k] >= 0, (k, data[k])
    for k in INT_OR_NULL:
        assert data[k] is None or (type(data[k]) is int and data[k] >= 0), (k, data[k])
    for k in BOOL:
        assert type(data[k]) is bool, (k, kind(data[k]))
    for k in BOOL_OR_NULL:
        assert data[k] is None or type(data[k]) is bool, (k, kind(data[k]))
    for k in NUMBER:
        assert type(data[k]) in (int, float) and math.isfinite(data[k]), (k, data[k])
    for k in NUMBER_OR_NULL:
        v = data[k]
        assert v is None or (type(v) in (int, float) and math.isfinite(v)), (k, v)
    assert isinstance(data["planner_options"], dict)
    assert data["diagnosis"] is None or set(data["diagnosis"]) >= {"kind", "message"}
    assert data["plan_status"] is None or type(data["plan_status"]) is str


def check_semantics(data: dict, frequency: float) -> None:
    """The documented units and the relations between fields."""
    assert data["status"] in STATUSES and data["outcome"] in OUTCOMES
    assert data["target"] in ("scenario", "stock", "map")
    assert data["success"] is (data["outcome"] == "success")
    if data["success"]:
        assert data["status"] in ("arrived", "completed")
        assert data["time_to_goal_s"] == data["completion_time_s"] == data["duration_s"]
    else:
        assert data["time_to_goal_s"] is None and data["completion_time_s"] is None
    if data["status"] == "crashed":
        assert data["collision"] is True and data["outcome"] == "collision"
    assert data["collision"] is (data["collision_highway_env"] or data["collision_footprint"])
    # Units: Hz, seconds, 1/m, radians.
    assert data["simulation_frequency"] == frequency
    assert close(data["duration_s"], data["steps"] / frequency)
    assert close(data["kappa_max"], 1 / 6.0)
    for k in ("heading_err_rms_rad", "heading_err_max_rad", "goal_heading_err_rad"):
        assert data[k] is None or 0 <= data[k] <= math.pi + 1e-9, (k, data[k])
    for k in ("executed_curvature_violation_share", "steering_rate_over_limit_share"):
        assert data[k] is None or 0 <= data[k] <= 1, (k, data[k])
    # total_time_s holds planning and the closed loop (docs/metrics.md).
    inner = (data["planning_time_s"] or 0.0) + data["wall_time_s"]
    assert 0 <= inner <= data["total_time_s"] + 1e-6, data
    if data["status"] == "plan_failed":
        assert data["steps"] == 0 and data["cte_rms_m"] is None
        assert data["plan_status"] not in (None, "solved")


def check_message(data: dict, max_time: float | None) -> None:
    """``message`` as docs/metrics.md's table words it for ``status``."""
    status, message = data["status"], data["message"]
    t = f"{data['duration_s']:.2f}"
    if status == "arrived":
        assert message == f"stopped at the end of the path at t = {t} s"
    elif status == "crashed":
        assert message == f"highway-env reported a crash at t = {t} s"
    elif status == "timeout" and max_time is not None:
        limit = f"{max_time:g}"
        assert message in (f"not stopped at the goal within {limit} s",
                           f"no overtake within {limit} s (followed the lead car)"), message
    elif status == "plan_failed":
        assert message.startswith(f"planning failed ({data['plan_status']}): ")


def check_summary(stdout: str, data: dict, code: object) -> None:
    """The printed first line says what the JSON and the exit code say."""
    m = SUMMARY.match(stdout.splitlines()[0])
    assert m, stdout.splitlines()[0]
    assert m["scenario"] == data["scenario"] or data["target"] != "scenario"
    assert int(m["seed"]) == data["seed"]
    assert m["planner"] == data["planner"] and m["controller"] == data["controller"]
    verdict = m["verdict"]
    if data["success"]:
        assert verdict == "success"
    else:
        assert verdict.startswith(f"{data['outcome']} ({data['status']}"), verdict
    assert int(m["steps"]) == data["steps"]
    assert m["duration"] == f"{data['duration_s']:.2f}"
    cte = "n/a" if data["cte_rms_m"] is None else f"{data['cte_rms_m']:.3f} m"
    assert m["cte"] == cte
    ok = data["success"] and data.get("highway_env_success", True)
    assert code == (0 if ok else 1)


def check_trajectory(path: Path, data: dict) -> list[list[float]]:
    """``--trajectory``'s columns and rows (README), and the JSON figures they give."""
    header, rows = read_trajectory(path)
    assert header == TRAJECTORY_COLUMNS
    n = data["steps"]
    if n == 0:
        assert rows == []
        return rows
    assert len(rows) == n + 1
    f = data["simulation_frequency"]
    t, speed, steer, accel, gear = (
        [r[0] for r in rows], [r[4] for r in rows], [r[5] for r in rows],
        [r[6] for r in rows], [r[7] for r in rows],
    )
    assert all(math.isclose(tk, k / f, abs_tol=1e-9) for k, tk in enumerate(t))
    assert t[-1] == pytest.approx(data["duration_s"])
    assert set(gear) <= {1.0, -1.0}
    # A moving car's gear is the sign of its speed.
    assert all(g * v >= 0 for g, v in zip(gear, speed, strict=True))
    # steer in radians (within the 30 deg actuator), accel in m/s^2, speed in m/s.
    assert max(abs(s) for s in steer) <= math.radians(30) + 1e-9
    assert close(speed[-1], data["final_speed"])
    assert close(max(abs(a) for a in accel[:n]), data["max_long_accel"])
    rates = [abs(b - a) * f for a, b in zip([0.0] + steer[: n - 1], steer[:n], strict=True)]
    assert close(max(rates), data["max_steering_rate"], abs_=1e-5)
    kappa = max(abs(math.tan(s)) / WHEELBASE for s in steer[:n])
    assert close(kappa, data["executed_max_curvature"], abs_=1e-6)
    # Each step's acceleration moves the speed of the next row (v' = v + a dt).
    assert all(
        abs(speed[k + 1] - (speed[k] + accel[k] / f)) < 1e-6 for k in range(n)
    )
    return rows


def always_fields() -> list[str]:
    """The fields docs/metrics.md says are 'always' in simulate's JSON."""
    text = (DOCS / "metrics.md").read_text()
    return re.findall(r"^\| `([a-z_0-9]+)` \| always \|", text, flags=re.M)


# --------------------------------------------------------------------------- fixtures


@pytest.fixture(scope="module")
def files(tmp_path_factory: pytest.TempPathFactory) -> dict[str, str]:
    """Maps and plan files (``rrtdrive plan --json``, forward and reversing)."""
    tmp = tmp_path_factory.mktemp("simulate_audit")
    out = {
        "open": write(tmp, "open.json", OPEN_MAP),
        "wall": write(tmp, "wall.json", WALL_MAP),
    }
    out["forward"], out["reverse"] = str(tmp / "forward.json"), str(tmp / "reverse.json")
    assert main(["plan", out["open"], "--max-iterations", "2000", "--json", out["forward"]]) == 0
    assert main(["plan", out["open"], "--reverse", "--start", "25,5,0", "--goal", "12,5,0",
                 "--max-iterations", "2000", "--json", out["reverse"]]) == 0
    return out


# --------------------------------------------------------------------------- every scenario

SCENARIO_RUNS = [
    # (SCENARIO or a files key, flags, frequency, what the JSON says about the flags)
    ("parking", ["--controller", "stanley", "--planner-option", "step=3", "--seed", "1"], 20,
     {"scenario": "parking", "planner_options": {"step": 3}, "reverse_in": False,
      "reverse": False, "max_iterations": 20000}),
    ("parking", ["--reverse-in", "--deterministic", "--controller", "lqr"], 20,
     {"reverse_in": True, "reverse": True, "deterministic": True, "plan_max_time_s": None}),
    ("parking-reverse-in", ["--max-iterations", "15000"], 20,
     {"scenario": "parking", "reverse_in": True, "reverse": True, "max_iterations": 15000}),
    ("overtake", ["--oncoming", "2", "--reverse", "--plan-time", "60", "--frequency", "50"], 50,
     {"oncoming": 2, "reverse": True, "plan_max_time_s": 60.0}),
    ("overtake-traffic", ["--density", "low", "--lead-speed", "3", "--lead-model", "constant",
                          "--replan-rate", "2", "--predictor", "lane-following",
                          "--deterministic", "--controller", "lqr"], 20,
     {"density_per_km": 5.0, "lead_speed": 3.0, "lead_model": "constant",
      "replan_rate_hz": 2.0, "predictor": "lane-following", "replan_budget_s": 0.5,
      "planner": "spacetime-rrt-connect", "planning_time_s": None, "setup_time_s": None,
      "max_iterations": None, "plan_max_time_s": None, "plan_status": None}),
    ("parallel-parking", ["--controller", "stanley", "--frequency", "25", "--seed", "2"], 25,
     {"reverse": True}),
    ("u-turn", ["--controller", "lqr", "--seed", "2"], 20, {"reverse": True}),
    ("parking-v0", ["--reverse", "--deterministic", "--frequency", "15"], 15,
     {"target": "stock", "map": "parking-v0", "env_id": "parking-v0", "reverse": True}),
    ("open", ["--start", "5,8,0", "--goal", "30,8,0", "--resolution", "0.2", "--reverse",
              "--planner", "rrt-connect"], 20,
     {"target": "map", "map": "open", "planner": "rrt-connect", "reverse": True}),
    ("kerbside", ["--reverse", "--planner", "hybrid-a-star"], 20,
     {"target": "map", "scenario": "kerbside", "map": "kerbside"}),
]


@pytest.mark.parametrize(("scenario", "flags", "frequency", "says"), SCENARIO_RUNS,
                         ids=[f"{r[0]}-{i}" for i, r in enumerate(SCENARIO_RUNS)])
def test_each_scenario_takes_its_flags_and_reports_them(
    capsys, tmp_path, files, scenario, flags, frequency, says
):
    target = files.get(scenario, scenario)
    out_json, traj = tmp_path / "run.json", tmp_path / "run.csv"
    max_time = 0.5
    code, stdout, err = run(capsys, "simulate", target, *flags, "--max-time", str(max_time),
                            "--json", str(out_json), "--trajectory", str(traj))
    assert code in (0, 1), err
    assert "Traceback" not in err and "error" not in err, err
    data = json.loads(out_json.read_text())
    check_types(data)
    check_semantics(data, frequency)
    check_message(data, max_time)
    check_summary(stdout, data, code)
    for field in always_fields():
        assert field in data, field
    kind = data["target"] if data["target"] != "scenario" else data["scenario"]
    for field in CONDITIONAL.get(kind, ()):
        assert field in data, (kind, field)
    for field, value in says.items():
        assert data[field] == value, (field, data[field])
    rows = check_trajectory(traj, data)
    if scenario == "overtake-traffic":  # the ego starts at the lead car's speed
        assert rows[0][4] == pytest.approx(data["lead_speed"])
    if scenario == "parallel-parking":  # gap_m = gap_factor x the car's 4.30 m
        assert abs(data["gap_m"] - 4.30 * data["gap_factor"]) <= 1e-3
    if scenario == "u-turn":
        assert data["forward_u_turn_width_m"] > data["street_width_m"] > 0


def test_the_documented_always_fields_are_as_many_as_it_announces():
    words = {"eleven": 11, "twelve": 12, "thirteen": 13, "fourteen": 14}
    text = (DOCS / "metrics.md").read_text()
    announced = re.search(r"the\s+first\s+(\w+)\s+are\s+in\s+every\s+run's\s+JSON", text)
    fields = always_fields()
    assert len(fields) == words[announced.group(1)], fields
    assert {"total_time_s", "target", "plan_status", "deterministic", "max_time_s",
            "resolution_m"} <= set(fields)


# --------------------------------------------------------------------------- maps and plans


@pytest.mark.parametrize(("plan", "gear"), [("forward", 1.0), ("reverse", -1.0)])
def test_a_plan_file_of_rrtdrive_plan_is_driven_first_row_to_last(
    capsys, tmp_path, files, plan, gear
):
    doc = json.loads(Path(files[plan]).read_text())
    out_json, traj = tmp_path / "run.json", tmp_path / "run.csv"
    code, stdout, err = run(capsys, "simulate", files["open"], "--path", files[plan],
                            "--json", str(out_json), "--trajectory", str(traj))
    data = json.loads(out_json.read_text())
    assert code == 0, stdout + err
    check_types(data)
    check_semantics(data, 20.0)
    check_message(data, None)
    check_summary(stdout, data, code)
    assert data["planner"] == "given" and data["path_file"] == files[plan]
    assert data["planning_time_s"] is None and data["plan_status"] is None
    assert data["max_iterations"] is None and data["plan_max_time_s"] is None
    assert data["reverse"] is (gear < 0)
    assert data["path_length_m"] == pytest.approx(doc["length_m"], abs=1e-4)
    rows = check_trajectory(traj, data)
    first, last = doc["path"][0], doc["path"][-1]
    assert rows[0][1:4] == pytest.approx(first[:3], abs=1e-6)
    # Units of the goal errors: metres and radians against the plan's last row.
    x, y, yaw = rows[-1][1:4]
    assert close(data["goal_position_err_m"], math.hypot(x - last[0], y - last[1]))
    wrapped = abs((yaw - last[2] + math.pi) % (2 * math.pi) - math.pi)
    assert close(data["goal_heading_err_rad"], wrapped, abs_=1e-6)
    assert {r[7] for r in rows} == {gear}
    moving = [r[4] for r in rows if abs(r[4]) > 1e-3]
    assert moving and all(v * gear > 0 for v in moving)


def test_a_bare_list_of_poses_is_refused_as_help_says(capsys, tmp_path, files):
    # The help offered "... or [[x, y, yaw], ...]", read as a bare list (an audit); the
    # rows go in {"path": ROWS}, as for rrtdrive verify, and a bare list is one error.
    with pytest.raises(SystemExit):
        main(["simulate", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert '{"path": ROWS} with ROWS [[x, y, yaw, kappa(, gear)], ...] or [[x, y, yaw], ...]' \
        in text
    poses = write(tmp_path, "poses.json", [[5, 5, 0], [15, 5, 0], [25, 5, 0]])
    code, _, err = run(capsys, "simulate", files["open"], "--path", poses, "--max-time", "1")
    one_error_line(code, err, "--path")
    wrapped = write(tmp_path, "wrapped.json", {"path": [[5, 5, 0], [15, 5, 0], [25, 5, 0]]})
    code, _, err = run(capsys, "simulate", files["open"], "--path", wrapped, "--max-time", "1")
    assert code in (0, 1), err


def test_a_failed_plan_is_exit_1_with_whole_json_and_a_header_only_trajectory(
    capsys, tmp_path, files
):
    out_json, traj = tmp_path / "run.json", tmp_path / "run.csv"
    code, stdout, err = run(capsys, "simulate", files["wall"], "--json", str(out_json),
                            "--trajectory", str(traj))
    data = json.loads(out_json.read_text())
    check_types(data)
    check_semantics(data, 20.0)
    check_message(data, None)
    check_summary(stdout, data, code)
    assert code == 1 and data["status"] == "plan_failed" and data["outcome"] == "failed"
    assert data["plan_status"] == "proven_unreachable"
    assert data["diagnosis"] is not None
    assert stdout.splitlines()[1] == f"  why: {data['diagnosis']['message']}"
    header, rows = read_trajectory(traj)
    assert header == TRAJECTORY_COLUMNS and rows == []


def test_a_path_through_a_wall_crashes_exit_1(capsys, tmp_path, files):
    through = write(tmp_path, "through.json", {"path": [[5, 10, 0, 0], [35, 10, 0, 0]]})
    out_json, traj = tmp_path / "run.json", tmp_path / "run.csv"
    code, stdout, err = run(capsys, "simulate", files["wall"], "--path", through,
                            "--json", str(out_json), "--trajectory", str(traj))
    data = json.loads(out_json.read_text())
    check_types(data)
    check_semantics(data, 20.0)
    check_message(data, None)
    check_summary(stdout, data, code)
    assert code == 1 and data["status"] == "crashed" and data["outcome"] == "collision"
    check_trajectory(traj, data)


def test_json_on_stdout_is_the_json_alone_and_the_summary_goes_to_stderr(capsys, files):
    code, stdout, err = run(capsys, "simulate", files["open"], "--path", files["forward"],
                            "--max-time", "1", "--json", "-")
    data = json.loads(stdout)  # nothing else on stdout
    assert code == 1 and data["status"] == "timeout"
    check_summary(err, data, code)


# --------------------------------------------------------------------------- determinism


@pytest.mark.parametrize("argv", [
    ["parking", "--max-time", "2", "--seed", "3"],
    ["overtake-traffic", "--max-time", "1", "--deterministic"],
    ["parking-v0", "--max-time", "1", "--seed", "2"],
    ["open", "--seed", "5", "--max-time", "3"],
])
def test_a_seeded_run_repeats_but_for_the_documented_wall_clock_fields(capsys, files, argv):
    argv = [files.get(a, a) for a in argv]
    runs = []
    for _ in range(2):
        code, stdout, err = run(capsys, "simulate", *argv, "--json", "-")
        runs.append(json.loads(stdout))
    differ = {k for k in runs[0] if runs[0][k] != runs[1][k]}
    assert differ <= WALL_CLOCK, differ
    assert runs[0].keys() == runs[1].keys()


def test_a_seeded_run_repeats_across_processes(tmp_path, files):
    docs = []
    for i in range(2):
        out = tmp_path / f"run{i}.json"
        proc = subprocess.run(
            [sys.executable, "-m", "rrtdrive", "simulate", files["open"], "--seed", "7",
             "--json", str(out)], capture_output=True, text=True, timeout=120,
        )
        assert proc.returncode == 0, proc.stderr
        docs.append(json.loads(out.read_text()))
    differ = {k for k in docs[0] if docs[0][k] != docs[1][k]}
    assert differ <= WALL_CLOCK, differ


# --------------------------------------------------------------------------- exit codes


def test_a_stock_run_exits_1_when_highway_env_says_no(capsys, monkeypatch, tmp_path):
    import rrtdrive.sim.stock as stock

    real = stock.drive_stock_env

    def highway_env_says_no(*args, **kwargs):
        return dataclasses.replace(real(*args, **kwargs), highway_env_success=False)

    monkeypatch.setattr(stock, "drive_stock_env", highway_env_says_no)
    out_json = tmp_path / "run.json"
    code, stdout, err = run(capsys, "simulate", "parking-v0", "--seed", "1", "--frequency",
                            "15", "--json", str(out_json))
    data = json.loads(out_json.read_text())
    assert data["success"] is True and data["highway_env_success"] is False
    assert code == 1  # docs/metrics.md: exit 0 only when both say success
    # The summary says why it exits 1 under a "success" verdict.
    assert "highway-env's own is_success is false" in stdout


def test_an_arrival_after_the_time_limit_is_no_success(capsys, files):
    code, stdout, err = run(capsys, "simulate", files["open"], "--max-time", "10.86",
                            "--json", "-")
    data = json.loads(stdout)
    # Unlimited, this drive arrives at t = 10.90 s.
    assert not (data["success"] and data["duration_s"] > 10.86), data["message"]


def test_a_stock_time_limit_past_the_envs_own_is_honoured_or_refused(capsys, monkeypatch):
    import rrtdrive.sim.stock as stock

    real = stock.make_stock_env

    def one_second_env(*args, **kwargs):  # parking-v0's 100 s, made short to test cheaply
        env = real(*args, **kwargs)
        env.unwrapped.config["duration"] = 1.0
        return env

    monkeypatch.setattr(stock, "make_stock_env", one_second_env)
    code, stdout, err = run(capsys, "simulate", "parking-v0", "--max-time", "2", "--json", "-")
    if code == 2:
        one_error_line(code, err, "--max-time")
        return
    data = json.loads(stdout)
    assert data["duration_s"] == 2.0, (data["duration_s"], data["message"])


# --------------------------------------------------------------------------- bad input

REFUSED = [
    # (flags, flag named): a flag where it does not apply, or flags that conflict
    (["parking", "--start", "1,2,0"], "--start"),
    (["parking-v0", "--goal", "1,2,0"], "--goal"),
    (["overtake", "--resolution", "0.2"], "--resolution"),
    (["overtake", "--reverse-in"], "--reverse-in"),
    (["parking-v0", "--reverse-in"], "--reverse-in"),
    (["parking", "--path", "{forward}"], "--path"),
    (["parking", "--oncoming", "2"], "--oncoming"),
    (["overtake-traffic", "--oncoming", "2"], "--oncoming"),
    (["{open}", "--oncoming", "2"], "--oncoming"),
    (["overtake", "--density", "5"], "--density"),
    (["parking-v0", "--lead-speed", "3"], "--lead-speed"),
    (["{open}", "--lead-model", "idm"], "--lead-model"),
    (["parking", "--replan-rate", "3"], "--replan-rate"),
    (["u-turn", "--predictor", "lane-following"], "--predictor"),
    (["overtake-traffic", "--reverse"], "--reverse"),
    (["overtake-traffic", "--plan-time", "3"], "--plan-time"),
    (["overtake-traffic", "--max-iterations", "30"], "--max-iterations"),
    (["overtake-traffic", "--planner-option", "step=3"], "--planner-option"),
    (["overtake-traffic", "--planner", "rrt"], "--planner"),
    (["parking", "--deterministic", "--plan-time", "3"], "--plan-time"),
    (["parking", "--video-fps", "3"], "--video-fps"),
    (["parking", "--video-stride", "3"], "--video-stride"),
    (["{open}", "--path", "{forward}", "--planner", "rrt"], "--planner"),
    (["{open}", "--path", "{forward}", "--reverse"], "--reverse"),
    (["{open}", "--path", "{forward}", "--deterministic"], "--deterministic"),
    (["{open}", "--path", "{forward}", "--goal", "1,1,0"], "--goal"),
    (["{open}", "--path", "{forward}", "--max-iterations", "5"], "--max-iterations"),
    (["{open}", "--path", "{forward}", "--resolution", "0.2"], "--resolution"),
    # unknown names
    (["parking", "--controller", "mpc"], "--controller"),
    (["parking", "--planner", "astar"], "--planner"),
    (["parking", "--planner-option", "nosuchfield=1"], "--planner-option"),
    (["parkinglot"], "scenario"),
    (["overtake-traffic", "--lead-model", "gipps"], "--lead-model"),
    (["overtake-traffic", "--predictor", "oracle"], "--predictor"),
    # numbers out of range
    (["parking", "--seed", "-1"], "--seed"),
    (["parking", "--frequency", "10"], "--frequency"),
    (["parking", "--frequency", "20.5"], "--frequency"),
    (["parking", "--max-time", "-1"], "--max-time"),
    (["parking", "--max-time", "nan"], "--max-time"),
    (["parking", "--max-time", "0.01"], "--max-time"),
    (["parking", "--max-time", "1e7"], "--max-time"),
    (["overtake-traffic", "--max-time", "1000"], "--max-time"),
    (["parking", "--plan-time", "0"], "--plan-time"),
    (["parking", "--max-iterations", "-5"], "--max-iterations"),
    (["overtake-traffic", "--replan-rate", "-1"], "--replan-rate"),
    (["overtake-traffic", "--replan-rate", "10"], "--replan-rate"),
    (["overtake-traffic", "--density", "-1"], "--density"),
    (["overtake-traffic", "--density", "nan"], "--density"),
    (["overtake-traffic", "--lead-speed", "-3"], "--lead-speed"),
    (["overtake-traffic", "--lead-speed", "9"], "--lead-speed"),
    (["overtake", "--oncoming", "11"], "--oncoming"),
    (["{open}", "--resolution", "-0.1"], "--resolution"),
    (["{open}", "--start", "nan,5,0"], "--start"),
    (["{open}", "--goal", "inf,5,0"], "--goal"),
    (["{open}", "--start", "5,5"], "--start"),
    (["{open}", "--goal", "200,5,0"], "--goal"),
    (["{open}", "--start", "20,16,0"], "--start"),
    # outputs
    (["parking", "--trajectory", "-"], "--trajectory"),
    (["parking", "--trajectory", "{tmp}/t.txt"], "--trajectory"),
    (["{open}", "--json", "{open}"], "--json"),
    (["{open}", "--path", "{forward}", "--json", "{forward}"], "--json"),
    (["parking", "--json", "{tmp}/nofolder/x.json"], "--json"),
    (["parking", "--json", "{tmp}/same.csv", "--trajectory", "{tmp}/same.csv"], "--trajectory"),
]

BAD_FILES = {
    # (file text, field named in the message)
    "nan_pose": ('{"name": "x", "bounds": [0,0,40,20], "obstacles": [], '
                 '"start": [NaN, 5, 0], "goal": [25,5,0]}', "start"),
    "inf_goal": ('{"name": "x", "bounds": [0,0,40,20], "obstacles": [], '
                 '"start": [5, 5, 0], "goal": [25,5,Infinity]}', "goal"),
    "truncated": ('{"name": "x", "bounds": [0,0,40,20], "obstacles": [', "malformed JSON"),
    "empty": ("", "malformed JSON"),
    "array": ("[1, 2, 3]", "map"),
    "in_obstacle": ('{"name": "x", "bounds": [0,0,40,20], "obstacles": [{"center": [5,5], '
                    '"size": [4,2], "yaw": 0}], "start": [5,5,0], "goal": [25,5,0]}', "start"),
    "outside": ('{"name": "x", "bounds": [0,0,40,20], "obstacles": [], '
                '"start": [50,5,0], "goal": [25,5,0]}', "start"),
    "negative_size": ('{"name": "x", "bounds": [0,0,40,20], "obstacles": [{"center": [20,10], '
                      '"size": [-4,2], "yaw": 0}], "start": [5,5,0], "goal": [25,5,0]}',
                      "obstacles[0].size"),
    "unknown_key": ('{"name": "x", "bounds": [0,0,40,20], "obstacles": [], "start": [5,5,0], '
                    '"goal": [25,5,0], "colour": "red"}', "colour"),
    "goal_is_start": ('{"name": "x", "bounds": [0,0,40,20], "obstacles": [], '
                      '"start": [5,5,0], "goal": [5,5,0]}', "goal"),
}

BAD_PLANS = {
    "nan_row": ('{"path": [[5,5,0,0],[NaN,5,0,0],[10,5,0,0]]}', "--path"),
    "one_row": ('{"path": [[5,5,0,0]]}', "--path"),
    "no_rows": ('{"path": []}', "--path"),
    "truncated": ('{"path": [[5,5,0,0],[10,5,0', "--path"),
    "a_map": (json.dumps(OPEN_MAP), "--path"),
    "bad_gear": ('{"path": [[5,5,0,0,2],[10,5,0,0,2]]}', "--path"),
    "leaves_map": ('{"path": [[5,5,0,0],[60,5,0,0]]}', "--path"),
}


def _no_outputs_left(tmp_path: Path, before: str) -> None:
    assert not (tmp_path / "out.csv").exists()
    assert (tmp_path / "out.json").read_text() == before  # an earlier run's, untouched


@pytest.mark.parametrize(("argv", "flag"), REFUSED,
                         ids=[f"{i}-{f}" for i, (_, f) in enumerate(REFUSED)])
def test_a_refused_flag_is_one_line_exit_2_and_writes_nothing(
    capsys, tmp_path, files, argv, flag
):
    argv = [a.format(tmp=tmp_path, **files) for a in argv]
    outputs = []
    if "--json" not in argv:
        outputs += ["--json", str(tmp_path / "out.json")]
    if "--trajectory" not in argv:
        outputs += ["--trajectory", str(tmp_path / "out.csv")]
    (tmp_path / "out.json").write_text("earlier")
    code, stdout, err = run(capsys, "simulate", *argv, *outputs)
    one_error_line(code, err, flag)
    assert stdout == ""
    if "--trajectory" not in argv:
        assert not (tmp_path / "out.csv").exists()
    assert (tmp_path / "out.json").read_text() == "earlier"


@pytest.mark.parametrize("name", sorted(BAD_FILES))
def test_a_bad_map_file_is_one_line_exit_2_and_writes_nothing(capsys, tmp_path, name):
    text, needle = BAD_FILES[name]
    m = write(tmp_path, f"{name}.json", text)
    (tmp_path / "out.json").write_text("earlier")
    code, stdout, err = run(capsys, "simulate", m, "--json", str(tmp_path / "out.json"),
                            "--trajectory", str(tmp_path / "out.csv"))
    one_error_line(code, err, needle)
    _no_outputs_left(tmp_path, "earlier")


def test_a_missing_map_file_is_one_line(capsys, tmp_path):
    (tmp_path / "out.json").write_text("earlier")
    code, _, err = run(capsys, "simulate", str(tmp_path / "absent.json"), "--json",
                       str(tmp_path / "out.json"), "--trajectory", str(tmp_path / "out.csv"))
    one_error_line(code, err, "absent.json")
    _no_outputs_left(tmp_path, "earlier")


@pytest.mark.parametrize("name", sorted(BAD_PLANS) + ["missing"])
def test_a_bad_plan_file_is_one_line_naming_path(capsys, tmp_path, files, name):
    plan = str(tmp_path / "absent.json")
    if name != "missing":
        plan = write(tmp_path, f"{name}.json", BAD_PLANS[name][0])
    (tmp_path / "out.json").write_text("earlier")
    code, _, err = run(capsys, "simulate", files["open"], "--path", plan, "--json",
                       str(tmp_path / "out.json"), "--trajectory", str(tmp_path / "out.csv"))
    one_error_line(code, err, "--path")
    _no_outputs_left(tmp_path, "earlier")


@pytest.mark.parametrize(("argv", "flag"), [
    (["parking", "--planner", "rrt", "--reverse", "--max-time", "0.01"], "--max-time"),
    (["parking", "--planner", "rrt", "--reverse", "--video-fps", "3"], "--video-fps"),
    # Refused inside the drive (past parking-v0's own 100 s): the note came first here too.
    (["parking-v0", "--planner", "rrt", "--reverse", "--max-time", "500"], "--max-time"),
])
def test_bad_input_beside_a_forward_only_note_is_still_one_line(capsys, argv, flag):
    code, _, err = run(capsys, "simulate", *argv)
    one_error_line(code, err, flag)


@pytest.mark.parametrize(("pose", "flag"), [("--goal", "--goal"), ("--start", "--start")])
def test_a_flag_that_makes_the_goal_the_start_is_named(capsys, files, pose, flag):
    value = "5,5,0" if pose == "--goal" else "25,5,0"  # the file's start / goal
    code, _, err = run(capsys, "simulate", files["open"], pose, value)
    one_error_line(code, err, flag)
