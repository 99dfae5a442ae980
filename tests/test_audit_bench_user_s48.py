"""Audit of ``rrtdrive bench`` (session 48) as an AV engineer benches their OWN maps.

Map files written here (and one imported from a ROS ``map_server`` .yaml/.pgm), a TOML
``--config`` (in a ``[bench]`` table), ``--maps`` (planning only) against ``--scenarios
MAP`` (driven start to goal), several planners, controllers, seeds, ``--reverse``,
local workers and ``--ray``, a SIGTERM mid-run and the resume, the rows' fields against
docs/bench.md, the summary recomputed from ``runs.jsonl`` with ``scipy.stats``, and bad
input (one line naming the field, exit 2, no traceback).
"""

from __future__ import annotations

import csv
import json
import math
import os
import re
import signal
import subprocess
import sys
import time
from collections import Counter
from pathlib import Path

import numpy as np
import pytest
import scipy.stats as st

from rrtdrive.cli import main

SMALL = {
    "name": "small", "bounds": [0, 0, 40, 20],
    "obstacles": [{"center": [20.0, 6.0], "size": [4.3, 1.8], "yaw": 0.0}],
    "start": [4.0, 4.0, 0.0], "goal": [34.0, 12.0, 0.0],
}
# A wall across the whole map: no path, proven so.
BLOCKED = {
    "name": "blocked", "bounds": [0, 0, 40, 20],
    "obstacles": [{"center": [20.0, 10.0], "size": [2.0, 20.0], "yaw": 0.0}],
    "start": [4.0, 10.0, 0.0], "goal": [34.0, 10.0, 0.0],
}
# A bay to back into: gear changes.
BAY = {
    "name": "bay", "bounds": [0, 0, 30, 20],
    "obstacles": [{"center": [12.0, 2.0], "size": [2.6, 4.0], "yaw": 0.0},
                  {"center": [18.0, 2.0], "size": [2.6, 4.0], "yaw": 0.0}],
    "start": [3.0, 12.0, 0.0], "goal": [15.0, 2.5, 1.5708],
}

TOML = """\
[bench]
maps = ["small.json", "blocked.json", "ros.json"]
scenarios = ["small.json", "blocked.json"]
planners = ["improved-rrt-connect", "rrt-connect"]
controllers = ["pure-pursuit"]
seeds = 2
workers = 2
out = "out"
max_time_s = 2.0
max_iterations = 3000
"""

# docs/bench.md, "Rows".
COMMON_FIELDS = {
    "config_hash", "seed", "kind", "map", "scenario", "planner", "controller",
    "max_time_s", "max_iterations", "reverse", "deterministic", "status", "success",
    "error", "attempts", "wall_time_s", "worker", "finished_at",
}
PLAN_FIELDS = {
    "map_name", "length_m", "max_curvature", "kappa_max", "nodes", "iterations",
    "planning_time_s", "setup_time_s", "diagnosis_time_s", "message", "verified",
}
# docs/bench.md, "Groups and statistics".
SIGNED = {"progress_m", "final_speed", "nuplan_lon_accel_min", "nuplan_lon_accel_max"}
SUCCESS_ONLY = {"length_m", "max_curvature", "path_length_m", "executed_max_curvature"}
PLOTS = {"box_length.png", "box_time.png", "success.png", "curvature_hist.png"}


def _rrtdrive(cwd: Path, *argv: str, timeout: float = 240) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "rrtdrive", *argv], cwd=cwd, capture_output=True,
        text=True, timeout=timeout,
    )


def _write_maps(d: Path) -> None:
    for name, m in (("small", SMALL), ("blocked", BLOCKED), ("bay", BAY)):
        (d / f"{name}.json").write_text(json.dumps(m))


def _write_ros_map(d: Path) -> None:
    # A map_server map: 20 x 10 m at 0.1 m, a 0.5 m wall, a block and an unknown patch.
    img = np.full((100, 200), 254, np.uint8)
    img[:5, :] = img[-5:, :] = 0
    img[:, :5] = img[:, -5:] = 0
    img[30:70, 90:110] = 0
    img[10:20, 150:160] = 205
    (d / "ros.pgm").write_bytes(b"P5\n200 100\n255\n" + img.tobytes())
    (d / "ros.yaml").write_text(
        "image: ros.pgm\nresolution: 0.1\norigin: [-1.0, -2.0, 0.0]\nnegate: 0\n"
        "occupied_thresh: 0.65\nfree_thresh: 0.196\n"
    )


def _rows(out: Path) -> list[dict]:
    return [json.loads(line) for line in (out / "runs.jsonl").read_text().splitlines()]


@pytest.fixture(scope="module")
def user_bench(tmp_path_factory):
    d = tmp_path_factory.mktemp("user_bench")
    _write_maps(d)
    _write_ros_map(d)
    imp = _rrtdrive(d, "maps", "--import", "ros.yaml", "--start", "1,2,0", "--goal",
                    "15,2,0", "--out", "ros.json")
    assert imp.returncode == 0, imp.stderr
    (d / "bench.toml").write_text(TOML)
    t0 = time.perf_counter()
    r = _rrtdrive(d, "bench", "--config", "bench.toml")
    return d, r, time.perf_counter() - t0


def test_maps_plan_only_and_scenarios_drive_the_same_files(user_bench):
    d, r, _ = user_bench
    assert r.returncode == 0, r.stderr
    rows = _rows(d / "out")
    # 3 maps x 2 planners x 2 seeds planned; 2 maps x 2 planners x 1 controller x 2 seeds driven.
    assert Counter(x["kind"] for x in rows) == {"plan": 12, "episode": 8}
    for x in rows:
        if x["kind"] == "plan":
            assert x["controller"] is None and x["scenario"] is None
            assert x["map"] in {"small.json", "blocked.json", "ros.json"}
        else:
            assert x["controller"] == "pure-pursuit" and x["map"] is None
            assert x["scenario"] in {"small.json", "blocked.json"}
            # Driven start to goal: a solved plan is followed by a closed loop.
            if x["plan_status"] == "solved":
                assert x["status"] in {"arrived", "crashed", "timeout"} and x["steps"] > 0
    small = [x for x in rows if x["scenario"] == "small.json"
             and x["planner"] == "improved-rrt-connect"]
    assert small and all(x["success"] and x["status"] == "arrived" for x in small)
    blocked = [x for x in rows if "blocked.json" in (x["map"], x["scenario"])]
    assert blocked and not any(x["success"] for x in blocked)
    assert all(x["error"] is None for x in rows)
    assert Counter((x["config_hash"], x["seed"]) for x in rows).most_common(1)[0][1] == 1


def test_rows_have_the_fields_docs_bench_md_names(user_bench):
    d, _, _ = user_bench
    for x in _rows(d / "out"):
        assert COMMON_FIELDS <= set(x), COMMON_FIELDS - set(x)
        if x["kind"] == "plan":
            assert PLAN_FIELDS <= set(x), PLAN_FIELDS - set(x)
            assert (x["verified"] is None) == (not x["success"])
            assert (x["length_m"] is None) == (not x["success"])
        else:
            assert {"plan_status", "verified"} <= set(x)
            # A map has no such verdict (docs: null; the key is absent, either reads None).
            assert x.get("highway_env_success") is None
        assert x["reverse"] is False and x["deterministic"] is False
        assert x["max_time_s"] == 2.0 and x["max_iterations"] == 3000
        assert re.fullmatch(r"[^:]+:\d+", x["worker"])


def test_progress_and_the_closing_lines(user_bench):
    d, r, _ = user_bench
    assert "bench: 20 runs in the grid, 0 already in out/runs.jsonl" in r.stderr
    assert re.search(r"bench 20/20 \(100%\) [\d.]+ runs/s elapsed \d+:\d\d ETA 0:00", r.stderr)
    assert r.stdout.startswith("bench: 20 runs (0 resumed, 20 run now, 0 errors)")
    assert "Traceback" not in r.stderr


def _recompute(rows: list[dict], line: dict) -> tuple[int, float, float, float, float]:
    kind, metric = line["kind"], line["metric"]
    target = line["map"] if kind == "plan" else line["scenario"]
    key = "map" if kind == "plan" else "scenario"
    members = sorted(
        (x for x in rows if x["kind"] == kind and x[key] == target
         and x["planner"] == line["planner"] and (x["controller"] or "") == line["controller"]),
        key=lambda x: x["seed"],
    )
    assert len(members) == int(line["runs"])
    assert sum(x["status"] == "error" for x in members) == int(line["errors"])
    raw = [x[metric] for x in members if x["status"] != "error" and x.get(metric) is not None
           and not (metric in SUCCESS_ONLY and not x["success"])]
    rate = all(isinstance(v, bool) for v in raw)
    v = np.array([float(a) for a in raw if math.isfinite(float(a))])
    n = len(v)
    mean = float(v.mean()) if n else math.nan
    std = float(v.std(ddof=1)) if n > 1 else math.nan
    if rate and n:
        ci = st.binomtest(int(v.sum()), n).proportion_ci(method="wilson")
        lo, hi = float(ci.low), float(ci.high)
    elif n < 2:
        lo = hi = math.nan
    elif metric in SIGNED:
        lo, hi = (mean, mean) if std == 0 else st.t.interval(
            0.95, n - 1, loc=mean, scale=std / math.sqrt(n))
    elif np.all(v == v[0]):
        lo = hi = float(v[0])
    else:
        ci = st.bootstrap((v,), np.mean, n_resamples=1999, method="percentile",
                          vectorized=True, rng=np.random.default_rng(0)).confidence_interval
        lo, hi = float(ci.low), float(ci.high)
    return n, mean, std, lo, hi


def test_summary_csv_is_what_the_rows_give(user_bench):
    d, _, _ = user_bench
    rows = _rows(d / "out")
    lines = list(csv.DictReader((d / "out" / "summary.csv").open()))
    assert {ln["metric"] for ln in lines} >= {"success", "length_m", "path_length_m",
                                             "cte_rms_m", "verified", "planning_time_s"}
    for ln in lines:
        n, mean, std, lo, hi = _recompute(rows, ln)
        assert n == int(ln["n"]), ln
        for got, want in ((ln["mean"], mean), (ln["std"], std), (ln["ci95_low"], lo),
                          (ln["ci95_high"], hi)):
            if not math.isfinite(want):
                assert got == "", ln
            else:
                assert math.isclose(float(got), want, rel_tol=1e-9, abs_tol=1e-12), (ln, want)


def test_summary_md_success_column_is_the_csv_rate(user_bench):
    d, _, _ = user_bench
    md = (d / "out" / "summary.md").read_text()
    assert md.startswith("# Bench summary (20 runs, seeds 0–1)")
    rates = {}
    for ln in csv.DictReader((d / "out" / "summary.csv").open()):
        if ln["metric"] == "success":
            target = ln["map"] or ln["scenario"]
            rates[(target, ln["planner"], ln["controller"])] = float(ln["mean"])
    assert len(rates) == 10
    for (target, planner, controller), rate in rates.items():
        cells = [target, planner] + ([controller] if controller else [])
        row = next(line for line in md.splitlines()
                   if line.startswith("| " + " | ".join(cells) + " | "))
        pct = row.split(" | ")[len(cells) + 2]
        assert pct.startswith(f"{round(100 * rate)}% ["), (row, rate)


def test_plots_are_pngs(user_bench):
    d, r, _ = user_bench
    for name in PLOTS:
        assert (d / "out" / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "plots: box_length.png" in r.stdout


def test_the_same_command_again_runs_nothing_and_keeps_every_row(user_bench):
    d, _, _ = user_bench
    before = (d / "out" / "runs.jsonl").read_bytes()
    r = _rrtdrive(d, "bench", "--config", "bench.toml", "--quiet")
    assert r.returncode == 0, r.stderr
    assert r.stdout.startswith("bench: 20 runs (20 resumed, 0 run now, 0 errors)")
    assert (d / "out" / "runs.jsonl").read_bytes() == before
    assert r.stderr == ""


def test_reverse_grid_of_an_own_bay_plans_and_drives_with_gear_changes(tmp_path):
    _write_maps(tmp_path)
    r = _rrtdrive(tmp_path, "bench", "--maps", "bay.json", "--scenarios", "bay.json",
                  "--planners", "hybrid-a-star,rrt", "--seeds", "1", "--reverse",
                  "--max-time", "2", "--max-iterations", "1500", "--workers", "2",
                  "--out", "rv", "--quiet", "--no-plots")
    assert r.returncode == 0, r.stderr
    assert "note: rrt plans forward only" in r.stderr
    rows = _rows(tmp_path / "rv")
    assert len(rows) == 4 and all(x["reverse"] for x in rows)
    drove = next(x for x in rows if x["kind"] == "episode" and x["planner"] == "hybrid-a-star")
    assert drove["success"] and drove["gear_changes"] >= 1
    assert "gear changes allowed" in (tmp_path / "rv" / "summary.md").read_text()
    assert not any(p.name in PLOTS for p in (tmp_path / "rv").iterdir())


def test_sigterm_mid_bench_then_the_same_command_completes_it(tmp_path):
    _write_maps(tmp_path)
    argv = [sys.executable, "-m", "rrtdrive", "bench", "--scenarios", "small.json",
            "--planners", "improved-rrt-connect", "--controllers", "pure-pursuit,lqr,stanley",
            "--seeds", "5", "--workers", "2", "--out", "k", "--max-time", "2",
            "--max-iterations", "3000", "--no-plots"]
    p = subprocess.Popen(argv, cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                         text=True)
    runs = tmp_path / "k" / "runs.jsonl"
    deadline = time.monotonic() + 90
    while time.monotonic() < deadline and p.poll() is None:
        if runs.exists() and runs.read_text().count("\n") >= 1:
            break
        time.sleep(0.1)
    p.send_signal(signal.SIGTERM)
    _, err = p.communicate(timeout=60)
    done = runs.read_text()
    if p.returncode == 0 or done.count("\n") == 15:
        pytest.skip("the bench finished before the signal")
    assert p.returncode == 143, err
    assert err.rstrip().splitlines()[-1] == "rrtdrive: terminated"
    assert "Traceback" not in err
    assert sorted(os.listdir(tmp_path / "k")) == [".lock", "bench_config.json", "runs.jsonl"]
    assert done == "" or done.endswith("\n")
    k = done.count("\n")
    r = subprocess.run(argv + ["--quiet"], cwd=tmp_path, capture_output=True, text=True,
                       timeout=120)
    assert r.returncode == 0, r.stderr
    assert f"bench: 15 runs ({k} resumed, {15 - k} run now, 0 errors)" in r.stdout
    after = runs.read_text()
    assert after.startswith(done)  # the rows before the signal are kept as they were
    keys = Counter((x["config_hash"], x["seed"]) for x in _rows(tmp_path / "k"))
    assert len(keys) == 15 and set(keys.values()) == {1}


def _cli(capsys, *argv: str) -> tuple[int, str]:
    try:
        code = main(["bench", *argv])
    except SystemExit as exc:  # argparse's own errors
        code = exc.code
    return code, capsys.readouterr().err


@pytest.mark.parametrize(
    ("argv", "field"),
    [
        (["--maps", "missing.json"], "--maps"),
        (["--scenarios", "missing.json"], "--scenarios"),
        (["--maps", "trunc.json"], "--maps"),
        (["--scenarios", "nogoal.json"], "--scenarios"),
        (["--scenarios", "startin.json"], "start"),
        (["--maps", "small.json", "--planners", "rrt-foo"], "--planners"),
        (["--scenarios", "small.json", "--controllers", "pid"], "--controllers"),
        (["--maps", "small.json", "--planners", "improved-rrt-connect@foo=1"], "planner.foo"),
        (["--maps", "small.json", "--seeds", "0"], "--seeds"),
        (["--maps", "small.json", "--deterministic", "--max-time", "1"], "--max-time"),
        (["--maps", "small.json", "--ray", "--no-ray"], "--no-ray"),
        (["--maps", "small.json", "--planners", "ompl-rs-rrtconnect"], "--planners"),
        (["--config", "syntax.toml"], "syntax.toml"),
        (["--config", "unknown.toml"], "'seed'"),
        (["--config", "type.toml"], "seeds"),
        (["--config", "nope.toml"], "nope.toml"),
    ],
)
def test_bad_input_is_one_line_naming_the_field_exit_2(tmp_path, monkeypatch, capsys, argv,
                                                         field):
    _write_maps(tmp_path)
    (tmp_path / "trunc.json").write_text(json.dumps(SMALL)[:-1])
    (tmp_path / "nogoal.json").write_text(json.dumps({k: v for k, v in SMALL.items()
                                                      if k != "goal"}))
    (tmp_path / "startin.json").write_text(json.dumps(
        {**SMALL, "obstacles": [{"center": [4.0, 4.0], "size": [3.0, 3.0], "yaw": 0.0}]}))
    (tmp_path / "syntax.toml").write_text('maps = ["small.json"\nseeds = 1\n')
    (tmp_path / "unknown.toml").write_text('maps = ["small.json"]\nseed = 1\n')
    (tmp_path / "type.toml").write_text('maps = ["small.json"]\nseeds = "2"\n')
    monkeypatch.chdir(tmp_path)
    code, err = _cli(capsys, *argv, "--out", "bad", "--quiet")
    assert code == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("rrtdrive bench: error: ") and field in lines[0], err
    assert not (tmp_path / "bad" / "runs.jsonl").exists()


def test_controllers_with_maps_alone_say_maps_plan_only(tmp_path, monkeypatch, capsys):
    _write_maps(tmp_path)
    monkeypatch.chdir(tmp_path)
    code, err = _cli(capsys, "--maps", "small.json", "--controllers", "lqr", "--seeds", "1",
                     "--max-iterations", "1500", "--workers", "1", "--out", "o", "--quiet",
                     "--no-plots")
    assert code == 0
    assert "--maps runs plan only (to drive a map: --scenarios MAP)" in err
    assert [x["kind"] for x in _rows(tmp_path / "o")] == ["plan"]


def test_a_map_slip_warning_is_one_line_not_one_per_worker(tmp_path):
    (tmp_path / "deg.json").write_text(json.dumps({**SMALL, "goal": [34.0, 12.0, 90]}))
    r = _rrtdrive(tmp_path, "bench", "--maps", "deg.json", "--seeds", "1", "--workers", "1",
                  "--max-iterations", "500", "--out", "o", "--quiet", "--no-plots")
    assert r.returncode == 0, r.stderr
    assert "rrtdrive bench: warning: goal: yaw 90 is more than a full turn" in r.stderr
    assert r.stderr.count("more than a full turn") == 1, r.stderr
    assert "InputWarning" not in r.stderr


def test_sigterm_on_a_ray_bench_exits_143_like_a_local_one(tmp_path):
    pytest.importorskip("ray")
    _write_maps(tmp_path)
    argv = [sys.executable, "-m", "rrtdrive", "bench", "--scenarios", "small.json",
            "--controllers", "pure-pursuit,lqr,stanley", "--seeds", "6", "--ray",
            "--workers", "2", "--out", "r", "--max-time", "2", "--max-iterations", "3000",
            "--no-plots"]
    env = {k: v for k, v in os.environ.items() if k != "RAY_ADDRESS"}
    p = subprocess.Popen(argv, cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                         text=True, env=env)
    seen = []
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline:
        line = p.stderr.readline()
        if not line:
            break
        seen.append(line)
        if "to run on Ray" in line:
            break
    assert any("to run on Ray" in s for s in seen), "".join(seen)
    time.sleep(1.0)
    p.send_signal(signal.SIGTERM)
    _, rest = p.communicate(timeout=120)
    err = "".join(seen) + rest
    assert p.returncode == 143, err[-2000:]
    assert "rrtdrive: terminated" in err
    assert "SIGTERM received" not in err
