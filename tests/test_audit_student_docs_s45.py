"""Session-45 audit: a student follows README.md and docs/ on the command line.

Every check runs the CLI (``sys.executable -m rrtdrive``) or an experiment script as a
subprocess, as a user would, and compares what it prints with what the README and
docs/metrics.md say it prints: the numbers are read out of the docs, not copied here.
Real bugs are ``xfail(strict=True)``: they fail (xpass) once fixed.
"""

from __future__ import annotations

import json
import math
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text(encoding="utf-8")
METRICS = (ROOT / "docs" / "metrics.md").read_text(encoding="utf-8")
EXPERIMENTS = ROOT / "experiments"


def _flat(text: str) -> str:
    """Whitespace runs (line breaks of a wrapped doc or help text) as one space.

    argparse wraps after a word's hyphen ("pure- pursuit"): joined again.
    """
    return re.sub(r"(?<=[a-z])- (?=[a-z])", "-", re.sub(r"\s+", " ", text))


def cli(*args: str, cwd: Path, timeout: float = 120) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "rrtdrive", *args],
        capture_output=True, text=True, cwd=cwd, timeout=timeout, check=False,
    )


def script(name: str, *args: str, cwd: Path, timeout: float = 120) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, str(EXPERIMENTS / name), *args],
        capture_output=True, text=True, cwd=cwd, timeout=timeout, check=False,
    )


def _one_clear_error(proc: subprocess.CompletedProcess, field: str) -> None:
    """Exit 2, one line on stderr naming ``field``, no traceback."""
    assert "Traceback" not in proc.stderr, proc.stderr[-1500:]
    assert proc.returncode == 2, (proc.returncode, proc.stderr[-800:])
    lines = [ln for ln in proc.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1, proc.stderr
    assert field in lines[0], lines[0]


def _one_script_error(proc: subprocess.CompletedProcess, field: str) -> None:
    """An experiment script's bad input: exit 2, no traceback, one error line naming ``field``.

    argparse's usage lines may come before it (the scripts' parsers are plain argparse;
    the rrtdrive CLI prints the error alone).
    """
    assert "Traceback" not in proc.stderr, proc.stderr[-1500:]
    assert proc.returncode == 2, (proc.returncode, proc.stderr[-800:])
    errors = [ln for ln in proc.stderr.splitlines() if ": error:" in ln]
    assert len(errors) == 1, proc.stderr
    assert field in errors[0], errors[0]


@pytest.fixture(scope="module")
def work(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("student")


# ----------------------------------------------------------------- help and defaults

@pytest.mark.parametrize("command", ["plan", "simulate", "bench", "verify", "maps"])
def test_every_subcommand_help_lists_the_readme_flags(command, work):
    """``rrtdrive CMD --help`` exits 0 and names every flag the README's synopsis gives."""
    proc = cli(command, "--help", cwd=work)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.startswith(f"usage: rrtdrive {command}")
    block = re.search(r"## Command line\n\n```text\n(.*?)```", README, re.S).group(1)
    entries = re.split(r"\n(?=rrtdrive )", block)
    own = "\n".join(e for e in entries if e.startswith(f"rrtdrive {command} "))
    flags = set(re.findall(r"--[a-z][a-z-]+", own))
    assert flags, block
    missing = sorted(f for f in flags if f not in proc.stdout)
    assert not missing, f"README names {missing} for {command}, --help does not"


def test_plan_help_defaults_are_the_json_defaults(work):
    """The defaults ``plan --help`` states are those a plan's JSON reports."""
    helptext = _flat(cli("plan", "--help", cwd=work).stdout)
    doc = json.loads(cli("plan", "parking_lot", "--json", "-", cwd=work).stdout)
    iters = re.search(r"--max-iterations N .*?\(default (\d+)\)", helptext)
    cap = re.search(r"--max-time S .*?\(default ([\d.]+)\)", helptext)
    res = re.search(r"--resolution M .*?\(default ([\d.]+)", helptext)
    seed = re.search(r"--seed N .*?\(default (\d+)\)", helptext)
    planner = re.search(r"--planner NAME .*?\(default: ([a-z-]+)\)", helptext)
    assert iters and cap and res and seed and planner, helptext
    assert doc["max_iterations"] == int(iters.group(1))
    assert doc["max_time_s"] == float(cap.group(1))
    assert doc["resolution_m"] == float(res.group(1))
    assert doc["seed"] == int(seed.group(1))
    assert doc["planner"] == planner.group(1)


# ------------------------------------------------------------- README's own examples

def test_readme_plan_json_example_has_the_keys_and_numbers_printed(work):
    """README's ``rrtdrive plan parking_lot --json -`` block: same keys, same numbers."""
    block = next(b for b in re.findall(r"```json\n(.*?)```", README, re.S)
                 if '"planner": "improved-rrt-connect"' in b)
    doc_keys = set(re.findall(r'"([a-z_0-9]+)":', block))
    proc = cli("plan", "parking_lot", "--json", "-", cwd=work)
    assert proc.returncode == 0, proc.stderr
    got = json.loads(proc.stdout)
    assert set(got) | set(got["vehicle"]) == doc_keys  # the car's fields nested in vehicle
    for key in ("length_m", "nodes", "iterations", "max_curvature", "steer_rate_speed_limit"):
        quoted = re.search(rf'"{key}": ([\d.]+)', block)
        assert quoted, key
        assert got[key] == pytest.approx(float(quoted.group(1)), abs=1e-9), key
    assert got["message"] == re.search(r'"message": "([^"]+)"', block).group(1)


def test_readme_needs_reverse_diagnosis_quote_is_what_plan_prints(work):
    text = _flat(README)
    m = re.search(r"`rrtdrive plan parking_lot --goal 66\.5,22,1\.5708`, parked in a bay "
                  r'facing out: "([^"…]+)…', text)
    assert m, "README's needs_reverse example moved"
    proc = cli("plan", "parking_lot", "--goal", "66.5,22,1.5708", "--json", "d.json", cwd=work)
    assert proc.returncode == 1, proc.stderr
    why = next(ln for ln in proc.stdout.splitlines() if ln.strip().startswith("why:"))
    assert m.group(1).strip() in why
    doc = json.loads((work / "d.json").read_text())
    assert doc["diagnosis"]["kind"] == "needs_reverse"
    assert doc["success"] is False and doc["length_m"] is None and doc["cusps"] is None


def test_readme_verify_example_prints_the_line_quoted(work):
    m = re.search(r"rrtdrive plan (parking_lot --reverse --goal 20,30,3\.1) --json plan\.json\n"
                  r"rrtdrive verify plan\.json +# (.*?)(?: \.\.\.)?\n", README)
    assert m, "README's verify example moved"
    made = cli("plan", *m.group(1).split(), "--json", "plan.json", cwd=work)
    assert made.returncode == 0, made.stderr
    proc = cli("verify", "plan.json", cwd=work)
    assert proc.returncode == 0, proc.stdout
    assert proc.stdout.splitlines()[0] == m.group(2)


# ------------------------------------------------------------------------ bad input

BAD_INPUT = [
    (("plan", "nosuchmap"), "map"),
    (("plan", "parking_lot", "--seed", "-1"), "--seed"),
    (("plan", "parking_lot", "--step", "nan"), "--step"),
    (("plan", "parking_lot", "--start", "1,2"), "--start"),
    (("plan", "parking_lot", "--planner-option", "foo=1"), "--planner-option foo"),
    (("plan", "parking_lot", "--json", "nodir/x.json"), "--json"),
    (("simulate", "parkng"), "scenario"),
    (("simulate", "parking", "--video-stride", "5"), "--video-stride"),
    (("simulate", "u-turn", "--reverse-in"), "--reverse-in"),
    (("verify", "nosuch.json"), "plan"),
    (("bench", "--seeds", "0"), "--seeds"),
]


@pytest.mark.parametrize(("args", "field"), BAD_INPUT, ids=[" ".join(a) for a, _ in BAD_INPUT])
def test_bad_cli_input_is_one_line_naming_the_field(args, field, work):
    _one_clear_error(cli(*args, cwd=work), field)


# ---------------------------------------------------------- output files on failure

def test_sigterm_while_writing_the_video_leaves_no_partial_file(tmp_path):
    """README: Ctrl-C or SIGTERM removes the half-written file (exit 143)."""
    proc = subprocess.Popen(
        [sys.executable, "-m", "rrtdrive", "simulate", "parking", "--video", "v.mp4",
         "--json", "j.json", "--trajectory", "t.csv"],
        cwd=tmp_path, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
    )
    seen = b""
    deadline = time.monotonic() + 90
    try:
        while b"video " not in seen and time.monotonic() < deadline:
            chunk = os.read(proc.stderr.fileno(), 4096)
            if not chunk:
                break
            seen += chunk
        assert b"video " in seen, seen[-500:]  # the video is being written now
        proc.send_signal(signal.SIGTERM)
        rc = proc.wait(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
        proc.stderr.close()
    assert rc == 143, seen[-500:]
    left = set(os.listdir(tmp_path))
    assert "v.mp4" not in left
    assert left <= {"j.json", "t.csv"}, left  # no temporary file left behind
    if "j.json" in left:
        json.loads((tmp_path / "j.json").read_text())


# ------------------------------------------------- docs/metrics.md's quoted numbers

@pytest.fixture(scope="module")
def parking_seed0(work) -> dict:
    proc = cli("simulate", "parking", "--json", "p0.json", "--trajectory", "p0.csv", cwd=work)
    assert proc.returncode == 0, proc.stderr[-1000:]
    return json.loads((work / "p0.json").read_text())


def test_metrics_doc_parking_seed0_length_and_progress(parking_seed0):
    m = re.search(r"parking seed 0: ([\d.]+) and ([\d.]+) m", _flat(METRICS))
    assert m
    assert parking_seed0["path_length_m"] == pytest.approx(float(m.group(1)), abs=5e-5)
    assert parking_seed0["progress_m"] == pytest.approx(float(m.group(2)), abs=5e-5)


def test_simulate_help_defaults_are_the_json_defaults(parking_seed0, work):
    helptext = _flat(cli("simulate", "--help", cwd=work).stdout)
    plan_time = re.search(r"--plan-time S .*?\(default ([\d.]+)\)", helptext)
    iters = re.search(r"--max-iterations N .*?\(default (\d+)\)", helptext)
    freq = re.search(r"--frequency HZ .*?\(default (\d+)\)", helptext)
    ctrl = re.search(r"--controller NAME .*?\(default: ([a-z-]+)\)", helptext)
    seed = re.search(r"--seed N .*?\(default (\d+)\)", helptext)
    assert plan_time and iters and freq and ctrl and seed, helptext
    assert parking_seed0["plan_max_time_s"] == float(plan_time.group(1))
    assert parking_seed0["max_iterations"] == int(iters.group(1))
    assert parking_seed0["simulation_frequency"] == float(freq.group(1))
    assert parking_seed0["controller"] == ctrl.group(1)
    assert parking_seed0["seed"] == int(seed.group(1))
    # the trajectory export: steps + 1 rows under the documented header
    rows = (work / "p0.csv").read_text().splitlines()
    assert rows[0] == "t,x,y,yaw,speed,steer,accel,gear"
    assert len(rows) - 1 == parking_seed0["steps"] + 1


def test_metrics_doc_lqr_seed3_jerk_at_20hz(work):
    m = re.search(r"gives `max_jerk` ([\d.]+) m/s³ and `max_long_accel` ([\d.]+) m/s² at F = 20",
                  _flat(METRICS))
    assert m
    proc = cli("simulate", "parking", "--seed", "3", "--controller", "lqr", "--frequency", "20",
               "--json", "-", cwd=work)
    assert proc.returncode == 0, proc.stderr[-800:]
    got = json.loads(proc.stdout)
    assert round(got["max_jerk"], 2) == float(m.group(1))
    assert round(got["max_long_accel"], 2) == float(m.group(2))


def test_metrics_doc_parallel_parking_seed3_ttc(work):
    m = re.search(r"gives `ttc_min_s` ([\d.]+) over (\d+) moving reverse-gear steps",
                  _flat(METRICS))
    assert m
    proc = cli("simulate", "parallel-parking", "--seed", "3", "--json", "pp.json",
               "--trajectory", "pp.csv", cwd=work)
    assert proc.returncode == 0, proc.stderr[-800:]
    got = json.loads((work / "pp.json").read_text())
    assert got["ttc_min_s"] == pytest.approx(float(m.group(1)))
    rows = [ln.split(",") for ln in (work / "pp.csv").read_text().splitlines()[1:]]
    reversing = sum(1 for r in rows[:-1] if float(r[4]) < 0)
    assert reversing == int(m.group(2))


# ---------------------------- tracking metrics on a forward path over its own ground

def _bulb_path(ds: float = 0.2, r: float = 7.0) -> list[list[float]]:
    """A forward 'light-bulb' turn: east 20 m, right 60, left 300, right 60 deg, back west.

    The way back runs along the way out, on the same line, the other way: a forward
    U-turn where a street is wide enough (the path never reverses; |kappa| = 1/7).
    """
    rows: list[list[float]] = []
    x, y, h = 5.0, 20.0, 0.0

    def line(length: float) -> None:
        nonlocal x, y
        n = max(1, round(length / ds))
        for _ in range(n):
            rows.append([x, y, h, 0.0])
            x += length / n * math.cos(h)
            y += length / n * math.sin(h)

    def arc(turn: float) -> None:
        nonlocal x, y, h
        k = math.copysign(1.0 / r, turn)
        n = max(1, round(abs(turn) * r / ds))
        for _ in range(n):
            rows.append([x, y, h, k])
            cx, cy = x - math.sin(h) / k, y + math.cos(h) / k
            h += turn / n
            x, y = cx + math.sin(h) / k, cy - math.cos(h) / k

    line(20.0)
    arc(-math.pi / 3)
    arc(5 * math.pi / 3)
    arc(-math.pi / 3)
    line(17.0)
    rows.append([x, y, h, 0.0])
    return rows


@pytest.fixture(scope="module")
def bulb_drive(work) -> dict:
    rows = _bulb_path()
    (work / "bulb.json").write_text(json.dumps({"path": rows}))
    (work / "open.json").write_text(json.dumps({
        "name": "open", "bounds": [0, 0, 50, 40], "obstacles": [],
        "start": rows[0][:3], "goal": rows[-1][:3],
    }))
    proc = cli("simulate", "open.json", "--path", "bulb.json", "--json", "bulb_run.json",
               cwd=work)
    assert proc.returncode == 0, proc.stdout + proc.stderr[-800:]
    return json.loads((work / "bulb_run.json").read_text())


def test_bulb_drive_is_tracked_closely(bulb_drive):
    assert bulb_drive["success"] is True
    assert bulb_drive["path_cusps"] == 0 and bulb_drive["gear_changes"] == 0
    assert bulb_drive["cte_max_m"] < 0.3
    assert bulb_drive["goal_heading_err_rad"] < 0.05


def test_bulb_drive_heading_error_is_measured_on_the_leg_driven(bulb_drive):
    assert bulb_drive["heading_err_max_rad"] < 0.2, bulb_drive["heading_err_max_rad"]


def test_bulb_drive_progress_is_the_path_length(bulb_drive):
    assert bulb_drive["progress_m"] == pytest.approx(bulb_drive["path_length_m"], abs=0.5)


# ------------------------------------------------------------- experiment scripts

def test_experiment_negative_seed_refused_cleanly_where_it_is_handled(tmp_path):
    proc = script("bench_video.py", "--seed", "-1", "--out", str(tmp_path / "o"), cwd=tmp_path)
    _one_script_error(proc, "seed")


SEED_CRASHES = [
    ("random_goals.py", ("--seed", "-1", "--goals", "1")),
    ("coverage.py", ("--seed", "-1", "--count", "1")),
    ("random_goals_hybrid.py", ("--seed", "-1", "--goals", "1")),
    ("hybrid_variants.py", ("--seed", "-1", "--count", "1")),
    ("bench_sharpness.py", ("--goal-seed", "-1", "--goals", "1", "--seeds", "1")),
    ("bench_reeds_shepp.py", ("--seed", "-1", "--pairs", "1", "--repeats", "1")),
]


@pytest.mark.parametrize(("name", "args"), SEED_CRASHES, ids=[n for n, _ in SEED_CRASHES])
def test_experiment_negative_seed_is_bad_input(name, args, tmp_path):
    proc = script(name, *args, "--out", str(tmp_path / "o"), cwd=tmp_path)
    _one_script_error(proc, "seed")


@pytest.mark.parametrize(("name", "args"), [
    ("map_figures.py", ()),
    ("bench_verify.py", ("--seeds", "1", "--rounds", "1", "--repeat", "1", "--maps",
                         "overtake", "--reverse-maps", "reverse_bay")),
], ids=["map_figures", "bench_verify"])
def test_experiment_out_that_is_a_file_is_refused(name, args, tmp_path):
    (tmp_path / "afile").write_text("x")
    proc = script(name, *args, "--out", str(tmp_path / "afile"), cwd=tmp_path)
    assert "Traceback" not in proc.stderr, proc.stderr[-600:]
    assert proc.returncode in (1, 2)
    assert (tmp_path / "afile").read_text() == "x"


@pytest.mark.parametrize("flag", ["--step", "--clearance"])
def test_forward_reach_refuses_nan(flag, tmp_path):
    proc = script("forward_reach.py", flag, "nan", "--sharpness", "0.2", "--max-states", "100",
                  "--out", str(tmp_path / "o"), cwd=tmp_path)
    _one_script_error(proc, flag)
    assert not (tmp_path / "o").exists()


def test_bench_default_refuses_an_unknown_gear(tmp_path):
    proc = script("bench_default.py", "--gears", "foo", "--count", "1", "--repeat", "1",
                  "--record", str(tmp_path / "rec.pkl"), cwd=tmp_path)
    _one_script_error(proc, "--gears")
