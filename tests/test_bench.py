"""Tests of ``rrtdrive bench``: config, run keys, the JSONL store, local runs, crash retry,
SIGKILL resume, the summary and the OMPL rows."""

from __future__ import annotations

import csv
import dataclasses
import io
import json
import math
import os
import signal
import subprocess
import sys
import time
from collections import Counter
from pathlib import Path

import numpy as np
import pytest

from rrtdrive.bench import BenchConfig, ResultStore, expand, run_bench
from rrtdrive.bench.config_file import config_from_mapping, load_toml
from rrtdrive.bench.core import grid_rows
from rrtdrive.bench.summary import describe, summarise_rows, to_csv, to_markdown, wilson_interval
from rrtdrive.bench.worker import execute_run
from rrtdrive.cli import main
from rrtdrive.maps import builtin_map, save_map
from rrtdrive.types import InputError

FAST = ("rrt-connect", "rrt-star")

# ----------------------------------------------------------------------------- fault injection
# Module-level executors: the spawned workers import this module by name to find them.


def crashing_executor(spec):
    """Seed 1 crashes its worker on the first attempt only; seed 2 always; seed 3 raises."""
    marker_dir = Path(os.environ["RRTDRIVE_TEST_MARKERS"])
    if spec.seed == 1:
        marker = marker_dir / f"{spec.config_hash}-{spec.seed}"
        if not marker.exists():
            marker.write_text("crashed once")
            os._exit(3)
    if spec.seed == 2:
        os._exit(4)
    if spec.seed == 3:
        raise RuntimeError("boom")
    return execute_run(spec)


def sleeping_executor(spec):
    """Seed 0 hangs past any run timeout."""
    if spec.seed == 0:
        time.sleep(600)
    return execute_run(spec)


# ----------------------------------------------------------------------------- config


def test_config_validation_names_the_field():
    cases = [
        (dict(maps=("nowhere",)), "maps"),
        (dict(maps=("overtake",), planners=("bogus",)), "planners"),
        (dict(scenarios=("moon",)), "scenarios"),
        (dict(scenarios=("overtake",), controllers=("pid",)), "controllers"),
        (dict(maps=("overtake",), seeds=0), "seeds"),
        (dict(maps=("overtake",), workers=0), "workers"),
        (dict(maps=("overtake",), max_time_s=-1.0), "max_time_s"),
        (dict(maps=("overtake",), seeds=True), "seeds"),
        (dict(), "maps/scenarios"),
    ]
    for kwargs, field in cases:
        with pytest.raises(InputError, match=f"^{field}"):
            BenchConfig(**kwargs)


def test_toml_config(tmp_path):
    good = tmp_path / "b.toml"
    good.write_text(
        'maps = ["overtake", "parking_lot"]\nplanners = ["rrt-connect"]\nseeds = 4\n'
        'workers = 2\nout = "x"\nray = false\n'
    )
    cfg = config_from_mapping(load_toml(good))
    assert cfg.maps == ("overtake", "parking_lot") and cfg.seeds == 4 and cfg.ray is None
    assert cfg.runs == 8 and len(expand(cfg)) == 8
    bad = tmp_path / "bad.toml"
    bad.write_text("maps = [overtake\n")
    with pytest.raises(InputError, match="^config: malformed TOML"):
        load_toml(bad)
    unknown = tmp_path / "unknown.toml"
    unknown.write_text('maps = ["overtake"]\nseedz = 3\n')
    seeds = r"^config: unknown key 'seedz' \(did you mean 'seeds'\?\)"
    with pytest.raises(InputError, match=seeds):
        load_toml(unknown)
    with pytest.raises(InputError, match="^config: no such file"):
        load_toml(tmp_path / "missing.toml")
    table = tmp_path / "table.toml"
    table.write_text('[bench]\nmaps = ["overtake"]\nseeds = 2\n')
    assert load_toml(table) == {"maps": ["overtake"], "seeds": 2}
    beside = tmp_path / "beside.toml"  # read as "unknown key 'bench'"
    beside.write_text('seeds = 2\n[bench]\nmaps = ["overtake"]\n')
    with pytest.raises(InputError, match="^config: 'seeds' in .* is outside the .bench. table"):
        load_toml(beside)
    wrong_type = tmp_path / "wt.toml"
    wrong_type.write_text('maps = ["overtake"]\nseeds = "ten"\n')
    with pytest.raises(InputError, match="^seeds"):
        config_from_mapping(load_toml(wrong_type))


def test_toml_paths_are_read_from_the_working_folder(tmp_path, monkeypatch, capsys):
    # docs/bench.md: a relative `out` or map file in the TOML is read from the folder the
    # command runs in, as the same flags are, not from the TOML file's folder.
    (tmp_path / "cfg").mkdir()
    (tmp_path / "maps").mkdir()
    save_map(builtin_map("narrow_gap"), tmp_path / "maps" / "mine.json")
    toml = tmp_path / "cfg" / "b.toml"
    toml.write_text('maps = ["maps/mine.json"]\nplanners = ["rrt-connect"]\nseeds = 1\n'
                    'workers = 1\nout = "o"\nmax_iterations = 300\nplots = false\n')
    monkeypatch.chdir(tmp_path)
    assert main(["bench", "--config", "cfg/b.toml"]) == 0, capsys.readouterr().err
    rows = [json.loads(line) for line in (tmp_path / "o" / "runs.jsonl").read_text().splitlines()]
    assert len(rows) == 1 and rows[0]["map"].endswith("mine.json")
    assert not (tmp_path / "cfg" / "o").exists()


def test_cli_bad_input_exit_2(tmp_path, capsys):
    (tmp_path / "afile").write_text("")
    # A value given by a flag is named by the flag, as plan and simulate do.
    for argv, field in (
        (["bench", "--maps", "overtake", "--seeds", "0", "--out", str(tmp_path)], "--seeds"),
        (["bench", "--maps", "overtake", "--workers", "0", "--out", str(tmp_path)], "--workers"),
        (["bench", "--maps", "overtake", "--planners", "nope", "--out", str(tmp_path)],
         "--planners"),
        (["bench", "--maps", "atlantis", "--out", str(tmp_path)], "--maps"),
        (["bench", "--scenarios", "moon", "--out", str(tmp_path)], "--scenarios"),
        (["bench", "--scenarios", "overtake", "--controllers", "pid", "--out", str(tmp_path)],
         "--controllers"),
        (["bench", "--maps", "overtake", "--max-time", "-1", "--out", str(tmp_path)],
         "--max-time"),
        (["bench", "--maps", "overtake", "--out", str(tmp_path / "afile")], "--out"),
        (["bench", "--config", str(tmp_path / "none.toml")], "--config"),
    ):
        assert main(argv) == 2
        err = capsys.readouterr().err.strip()
        assert err.startswith(f"rrtdrive bench: error: {field}: ") and "\n" not in err, err
        assert "Traceback" not in err


def test_run_keys_are_stable_and_cover_the_config(tmp_path):
    cfg = BenchConfig(maps=("overtake", "parking_lot"), planners=FAST, seeds=3)
    specs = expand(cfg)
    assert len(specs) == cfg.runs == 12
    assert len({s.key for s in specs}) == 12
    assert [s.seed for s in specs[:4]] == [0, 0, 0, 0]  # seed-major
    again = expand(BenchConfig(maps=("parking_lot", "overtake"), planners=FAST[::-1], seeds=3))
    assert {s.key for s in again} == {s.key for s in specs}
    other_budget = expand(
        BenchConfig(maps=("overtake", "parking_lot"), planners=FAST, seeds=3, max_time_s=2.0)
    )
    assert not {s.key for s in other_budget} & {s.key for s in specs}
    # A map file: its content, not its name, is in the key.
    f = tmp_path / "m.json"
    save_map(builtin_map("overtake"), f)
    (a,) = expand(BenchConfig(maps=(str(f),), planners=("rrt",), seeds=1))
    m = builtin_map("overtake")
    save_map(m.with_query(goal=type(m.goal)(m.goal.x - 5.0, m.goal.y, m.goal.yaw)), f)
    (b,) = expand(BenchConfig(maps=(str(f),), planners=("rrt",), seeds=1))
    assert a.config_hash != b.config_hash


# ----------------------------------------------------------------------------- store


def test_store_append_resume_and_partial_tail(tmp_path):
    with ResultStore(tmp_path) as s:
        s.append({"config_hash": "h", "seed": 0, "x": float("nan")})
        s.append({"config_hash": "h", "seed": 1, "x": 1.5})
        with pytest.raises(ValueError):
            s.append({"config_hash": "h", "seed": 1})
        with pytest.raises(InputError, match="^out: another bench"):
            ResultStore(tmp_path)
    # A writer killed mid-line leaves a partial tail: it is cut on open.
    with open(tmp_path / "runs.jsonl", "a") as fh:
        fh.write('{"config_hash": "h", "seed": 2, "x"')
    with ResultStore(tmp_path) as s:
        assert s.done_keys() == {("h", 0), ("h", 1)}
        s.append({"config_hash": "h", "seed": 2, "x": 2})
        rows = list(s.rows())
        assert [r["seed"] for r in rows] == [0, 1, 2] and rows[0]["x"] is None
        assert s.drop([("h", 1)]) == 1
        assert s.done_keys() == {("h", 0), ("h", 2)}
        s.append({"config_hash": "h", "seed": 1})
    lines = (tmp_path / "runs.jsonl").read_text().splitlines()
    assert len(lines) == 3 and all(json.loads(line) for line in lines)
    with pytest.raises(InputError, match="^out"):
        ResultStore(tmp_path / "runs.jsonl")


# ----------------------------------------------------------------------------- local runs


def test_local_bench_rows_resume_and_summary(tmp_path):
    cfg = BenchConfig(
        maps=("overtake", "no_path"), planners=("rrt-connect", "improved-rrt-connect"),
        seeds=3, workers=2, out=str(tmp_path), max_time_s=2.0,
    )
    report = run_bench(cfg, command="test")
    assert (report.total, report.skipped, report.executed, report.errors) == (12, 0, 12, 0)
    lines = (tmp_path / "runs.jsonl").read_text().splitlines()
    rows = [json.loads(line) for line in lines]
    assert len(rows) == 12
    assert Counter((r["config_hash"], r["seed"]) for r in rows) == Counter(
        s.key for s in expand(cfg)
    )
    for r in rows:
        for k in ("map", "planner", "controller", "seed", "success", "status", "length_m",
                  "max_curvature", "nodes", "iterations", "planning_time_s", "verified"):
            assert k in r
        assert r["controller"] is None and r["scenario"] is None and r["error"] is None
        if r["map"] == "overtake":
            assert r["success"] and r["length_m"] > 80
            assert r["verified"] is (r["planner"] == "improved-rrt-connect")
        else:
            assert not r["success"] and r["status"] == "proven_unreachable"
            assert r["verified"] is None and r["length_m"] is None
    # Re-running does nothing, and the files are there.
    again = run_bench(cfg)
    assert (again.skipped, again.executed) == (12, 0)
    assert len((tmp_path / "runs.jsonl").read_text().splitlines()) == 12
    for name in ("summary.md", "summary.csv", "bench_config.json", "box_length.png",
                 "box_time.png", "success.png", "curvature_hist.png"):
        assert (tmp_path / name).stat().st_size > 0, name
    meta = json.loads((tmp_path / "bench_config.json").read_text())
    assert meta["config"]["seeds"] == 3 and meta["seeds"] == [0, 1, 2]
    md = (tmp_path / "summary.md").read_text()
    assert "| overtake | improved-rrt-connect | 3 | 0 | 100%" in md
    table = list(csv.DictReader(io.StringIO((tmp_path / "summary.csv").read_text())))
    succ = [t for t in table if t["map"] == "no_path" and t["metric"] == "success"]
    assert len(succ) == 2 and all(float(t["mean"]) == 0.0 for t in succ)
    # More seeds later: only the new ones run.
    more = run_bench(BenchConfig(**{**_kw(cfg), "seeds": 4}))
    assert (more.skipped, more.executed) == (12, 4)


def _kw(cfg):
    return {k: getattr(cfg, k) for k in ("maps", "scenarios", "planners", "controllers",
                                         "workers", "out", "max_time_s", "plots")}


def test_crashed_run_is_retried_once_then_recorded(tmp_path, monkeypatch):
    markers = tmp_path / "markers"
    markers.mkdir()
    monkeypatch.setenv("RRTDRIVE_TEST_MARKERS", str(markers))
    cfg = BenchConfig(
        maps=("overtake",), planners=("rrt-connect",), seeds=5, workers=2,
        out=str(tmp_path / "out"), plots=False,
    )
    report = run_bench(cfg, executor=crashing_executor)
    assert (report.executed, report.errors) == (5, 2)
    with ResultStore(cfg.out, lock=False) as store:
        rows = {r["seed"]: r for r in grid_rows(cfg, store)}
    assert sorted(rows) == [0, 1, 2, 3, 4]
    assert rows[0]["success"] and rows[0]["attempts"] == 1
    assert rows[1]["success"] and rows[1]["attempts"] == 2  # crashed once, then succeeded
    assert rows[2]["status"] == "error" and rows[2]["attempts"] == 2
    assert "worker process died (exit code 4)" in rows[2]["error"]
    assert rows[3]["status"] == "error" and rows[3]["error"].startswith("RuntimeError: boom")
    # The summary counts error rows apart.
    (g,) = summarise_rows(rows.values())
    assert (g.runs, g.errors, g.stats["success"].n) == (5, 2, 3)
    # --retry-errors runs them again (still failing: replaced, not duplicated).
    again = run_bench(cfg, executor=crashing_executor, retry_errors=True)
    assert (again.executed, again.errors) == (2, 2)
    lines = (Path(cfg.out) / "runs.jsonl").read_text().splitlines()
    assert sorted(json.loads(x)["seed"] for x in lines) == [0, 1, 2, 3, 4]


def test_map_file_travels_with_the_run(tmp_path):
    f = tmp_path / "mine.json"
    save_map(builtin_map("overtake"), f)
    cfg = BenchConfig(
        maps=(str(f),), planners=("rrt-connect",), seeds=2, workers=1,
        out=str(tmp_path / "out"), plots=False,
    )
    f.unlink()  # workers (maybe on other machines) get the content, not the path
    report = run_bench(cfg)
    assert (report.executed, report.errors) == (2, 0)
    rows = [json.loads(x) for x in (tmp_path / "out" / "runs.jsonl").read_text().splitlines()]
    assert all(r["success"] and r["map"] == str(f) for r in rows)


def test_run_timeout_kills_the_worker(tmp_path):
    cfg = BenchConfig(
        maps=("overtake",), planners=("rrt-connect",), seeds=2, workers=2, retries=0,
        # Seed 1 plans in about 0.01 s: 3 s leave room on a loaded, slow machine (the
        # timeout counts from the run's hand-over, after the worker's start-up).
        run_timeout_s=3.0, out=str(tmp_path), plots=False,
    )
    report = run_bench(cfg, executor=sleeping_executor)
    assert (report.executed, report.errors) == (2, 1)
    with ResultStore(tmp_path, lock=False) as store:
        rows = {r["seed"]: r for r in grid_rows(cfg, store)}
    assert "run timeout" in rows[0]["error"] and rows[1]["success"]


def test_sigkill_mid_bench_then_resume(tmp_path):
    out = tmp_path / "out"
    argv = [
        sys.executable, "-m", "rrtdrive", "bench", "--maps", "parking_lot,overtake",
        "--planners", ",".join(FAST), "--seeds", "10", "--workers", "2", "--out", str(out),
        "--no-plots", "--quiet",
    ]
    cfg = BenchConfig(maps=("parking_lot", "overtake"), planners=FAST, seeds=10)  # 40 runs
    keys = Counter(s.key for s in expand(cfg))
    proc = subprocess.Popen(argv, start_new_session=True, stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)
    results = out / "runs.jsonl"
    deadline = time.monotonic() + 180  # a safety net for a loaded machine, not a speed check
    try:
        while time.monotonic() < deadline:
            if results.exists() and results.read_bytes().count(b"\n") >= 10:
                break
            time.sleep(0.01)
        os.killpg(proc.pid, signal.SIGKILL)  # the bench and its workers
    finally:
        proc.wait(10)
    assert proc.returncode == -signal.SIGKILL
    first = [json.loads(x) for x in results.read_text().splitlines()]
    assert 10 <= len(first) < len(keys), "the kill must land mid-bench"
    # As if killed inside a write: a partial last line.
    with open(results, "a") as fh:
        fh.write('{"config_hash": "' + first[0]["config_hash"])
    done = subprocess.run(argv, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert f"{len(first)} resumed" in done.stdout
    rows = [json.loads(x) for x in results.read_text().splitlines()]
    assert Counter((r["config_hash"], r["seed"]) for r in rows) == keys  # each exactly once
    assert all(r["error"] is None for r in rows)
    # Once more: nothing to run, so no worker ran anything ("on 1 local worker process"
    # was printed whatever --workers said).
    again = subprocess.run(argv, capture_output=True, text=True, timeout=300)
    assert again.returncode == 0, again.stderr
    assert f"({len(keys)} resumed, 0 run now, 0 errors)\n" in again.stdout, again.stdout


@pytest.mark.skipif(
    os.environ.get("RRTDRIVE_SKIP_SIM") == "1", reason="closed loop disabled"
)
def test_tiny_closed_loop_bench(tmp_path):
    cfg = BenchConfig(
        scenarios=("overtake",), planners=("rrt-connect",), controllers=("pure-pursuit",),
        seeds=1, workers=1, out=str(tmp_path), plots=True,
    )
    report = run_bench(cfg)
    assert (report.executed, report.errors) == (1, 0)
    (row,) = [json.loads(x) for x in (tmp_path / "runs.jsonl").read_text().splitlines()]
    assert row["scenario"] == "overtake" and row["map"] is None
    assert row["controller"] == "pure-pursuit" and row["kind"] == "episode"
    for k in ("success", "collision", "cte_rms_m", "time_to_goal_s", "max_lateral_accel",
              "planning_time_s", "verified", "status"):
        assert k in row
    assert "## Closed loop" in (tmp_path / "summary.md").read_text()


# ----------------------------------------------------------------------------- summary


def test_statistics():
    s = describe([1.0, 2.0, 3.0, 4.0])
    assert s.n == 4 and s.mean == 2.5 and s.std == pytest.approx(np.std([1, 2, 3, 4], ddof=1))
    half = 3.182446305284263 * s.std / 2  # t(0.975, 3)
    assert (s.ci_low, s.ci_high) == (pytest.approx(2.5 - half), pytest.approx(2.5 + half))
    lo, hi = wilson_interval(5, 10)
    assert lo == pytest.approx(0.2366, abs=1e-4) and hi == pytest.approx(0.7634, abs=1e-4)
    one = describe([7.0])
    assert one.mean == 7.0 and np.isnan(one.std) and np.isnan(one.ci_low)
    rows = [
        {"kind": "plan", "map": "m", "planner": "p", "controller": None, "seed": i,
         "config_hash": "h", "success": i < 3, "length_m": (10.0 + i) if i < 3 else None,
         "status": "solved" if i < 3 else "no_path_in_budget"}
        for i in range(4)
    ]
    (g,) = summarise_rows(rows)
    assert g.stats["success"].rate and g.stats["success"].mean == 0.75
    assert g.stats["length_m"].n == 3 and g.stats["length_m"].mean == 11.0
    assert "seed" not in g.stats
    assert "| m | p | 4 | 0 | 75%" in to_markdown([g])
    assert to_csv([g]).splitlines()[0].startswith("kind,map,scenario,planner,controller")
    # The CSV keeps every digit: its numbers read back as the summary's own floats.
    thirds = [{**rows[0], "seed": i, "length_m": 10.0 + i / 3.0} for i in range(3)]
    (g3,) = summarise_rows(thirds)
    line = next(r for r in csv.DictReader(io.StringIO(to_csv([g3]))) if r["metric"] == "length_m")
    stat = g3.stats["length_m"]
    assert [float(line[k]) for k in ("mean", "std", "ci95_low", "ci95_high")] == [
        stat.mean, stat.std, stat.ci_low, stat.ci_high
    ]
    # ... and its order statistics, as numpy reads them off the lengths.
    lengths = np.array([10.0 + i / 3.0 for i in range(3)])
    assert [float(line[k]) for k in ("median", "min", "max")] == [
        np.median(lengths), lengths.min(), lengths.max()
    ]
    # A cell whose every run crashed still has its line (it had none in the CSV).
    crashed = [{"kind": "plan", "map": "m", "planner": "p", "controller": None, "seed": i,
                "config_hash": "h", "status": "error", "error": "boom"} for i in range(2)]
    (g_err,) = summarise_rows(crashed)
    assert to_csv([g_err]).splitlines()[1:] == ["plan,m,,p,,2,2,,0,,,,,,,"]
    # Closed loop: a crashed episode has a path and a partly driven curvature; the
    # summary counts path geometry of the successful runs only, as it says.
    episodes = [
        {"kind": "episode", "scenario": "s", "planner": "p", "controller": "c", "seed": i,
         "config_hash": "h", "success": i == 0, "status": "ok", "path_length_m": 80.0 + i,
         "executed_max_curvature": 0.1 * (i + 1), "cte_rms_m": 0.01 * (i + 1)}
        for i in range(3)
    ]
    (e,) = summarise_rows(episodes)
    assert e.stats["path_length_m"].n == 1 and e.stats["path_length_m"].mean == 80.0
    assert e.stats["executed_max_curvature"].n == 1
    assert e.stats["cte_rms_m"].n == 3  # the tracking error of every run


def test_no_plots_removes_an_earlier_grids_figures(tmp_path):
    from rrtdrive.bench.summary import PLOT_FILES

    for name in PLOT_FILES:
        (tmp_path / name).write_bytes(b"an earlier grid's figure")
    run_bench(BenchConfig(maps=("overtake",), planners=("rrt",), seeds=1, out=str(tmp_path),
                          plots=False))
    assert not any((tmp_path / name).exists() for name in PLOT_FILES)
    assert (tmp_path / "summary.md").is_file()


# ----------------------------------------------------------------------------- OMPL


def test_ompl_planners_are_listed_and_validated():
    from rrtdrive.bench.ompl_planners import OMPL_PLANNERS
    from rrtdrive.planning import PLANNERS, make_planner

    assert {"ompl-r2-rrtconnect", "ompl-rs-bitstar", "ompl-r2-informed-rrtstar",
            "ompl-rs-rrtstar"} <= set(OMPL_PLANNERS) <= set(PLANNERS)
    with pytest.raises(InputError, match="^planner"):
        make_planner("ompl-r2-rrtconnect", step=3.0)


def test_ompl_rows_on_the_same_map_and_checker():
    pytest.importorskip("ompl")
    from rrtdrive.planning import PlanningProblem, make_planner
    from rrtdrive.types import Budget
    from rrtdrive.verify import verify_path

    m = builtin_map("overtake")
    problem = PlanningProblem.from_map(m)
    for name in ("ompl-r2-rrtconnect", "ompl-rs-rrtconnect", "ompl-r2-bitstar"):
        planner = make_planner(name)
        a = planner.solve(problem, np.random.default_rng(3), Budget(max_time_s=3.0))
        b = planner.solve(problem, np.random.default_rng(3), Budget(max_time_s=3.0))
        assert a.success and a.planner == name, a.message
        assert np.array_equal(a.path.samples, b.path.samples)  # seeded
        gaps = np.hypot(*np.diff(a.path.xy, axis=0).T)
        assert gaps.max() <= 0.25 + 1e-6
        assert np.allclose(a.path.xy[0], m.start.xy) and np.allclose(a.path.xy[-1], m.goal.xy)
        assert isinstance(verify_path(m, a.path).ok, bool)
    rs = make_planner("ompl-rs-rrtconnect").solve(
        problem, np.random.default_rng(0), Budget(max_time_s=3.0)
    )
    # Reeds–Shepp curves respect the turning radius (up to sampling noise).
    assert rs.path.max_curvature <= m.vehicle.kappa_max * 1.02
    # In the parking lot they reverse: gear rows that the independent check accepts.
    lot = builtin_map("parking_lot")
    for seed in (0, 1):
        rs = make_planner("ompl-rs-rrtconnect").solve(
            PlanningProblem.from_map(lot), np.random.default_rng(seed), Budget(max_time_s=5.0)
        )
        assert rs.success, rs.message
        check = verify_path(lot, rs.path)
        assert check.ok and check.cusps == len(rs.path.cusps) >= 1, check
        assert rs.path.max_curvature <= lot.vehicle.kappa_max * 1.001
    unreachable = PlanningProblem.from_map(builtin_map("no_path"))
    fail = make_planner("ompl-r2-rrtconnect").solve(
        unreachable, np.random.default_rng(0), Budget(max_time_s=0.3)
    )
    assert not fail.success and fail.status.value == "no_path_in_budget"


def test_ompl_solves_a_goal_facing_exactly_pi():
    # OMPL's SO2 bounds are [-pi, pi): a goal yaw of exactly pi (turning_bulb's, a car
    # turning back down its street) made every OMPL planner fail without a word.
    pytest.importorskip("ompl")
    from rrtdrive.bench.ompl_planners import simple_setup
    from rrtdrive.planning import PlanningProblem, make_planner
    from rrtdrive.tight_maps import turning_bulb_map
    from rrtdrive.types import Budget
    from rrtdrive.verify import verify_path

    m = turning_bulb_map()
    assert m.goal.yaw == math.pi
    problem = PlanningProblem.from_map(m, reverse=True)
    for space in ("rs", "dubins"):
        ss, si = simple_setup(problem, space)
        assert si.satisfiesBounds(ss.getGoal().getState()), space
    res = make_planner("ompl-rs-rrtconnect").solve(
        problem, np.random.default_rng(0), Budget(max_time_s=10.0)
    )
    assert res.success, res.message
    assert verify_path(m, res.path).endpoints_ok


# ----------------------------------------------------------------------------- issue 15

UNGUARDED_SCRIPT = """
from rrtdrive.bench import BenchConfig, run_bench

cfg = BenchConfig(maps=("overtake",), planners=("rrt-connect",), seeds=3, workers=2,
                  out={out!r}, plots=False)
report = run_bench(cfg)
print("finished", report.errors)
"""


def test_workers_dying_at_startup_are_an_error_not_error_rows(tmp_path):
    # docs/bench.md's old snippet: no `if __name__ == "__main__":`, so every spawned
    # worker re-runs the script and dies while bootstrapping.
    script = tmp_path / "bench_script.py"
    out = tmp_path / "out"
    script.write_text(UNGUARDED_SCRIPT.format(out=str(out)))
    proc = subprocess.run([sys.executable, str(script)], capture_output=True, text=True,
                          cwd=tmp_path, timeout=300, check=False)
    assert proc.returncode != 0
    assert "finished" not in proc.stdout
    assert "WorkerStartupError" in proc.stderr and "__main__" in proc.stderr
    runs = out / "runs.jsonl"
    assert not runs.exists() or runs.read_text().strip() == ""  # no rows for unstarted runs
    # The guarded script (the corrected doc) then runs every run from scratch.
    body = UNGUARDED_SCRIPT.format(out=str(out)).strip().splitlines()
    guarded = "\n".join(body[:1] + ["", 'if __name__ == "__main__":']
                        + ["    " + line for line in body[1:] if line])
    script.write_text(guarded + "\n")
    proc = subprocess.run([sys.executable, str(script)], capture_output=True, text=True,
                          cwd=tmp_path, timeout=300, check=False)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert "finished 0" in proc.stdout
    assert len(runs.read_text().splitlines()) == 3


def test_deterministic_bench_config():
    cfg = BenchConfig(scenarios=("overtake-traffic",), seeds=1, deterministic=True)
    (spec,) = expand(cfg)
    assert spec.deterministic and spec.max_time_s >= 1e6
    plain = BenchConfig(scenarios=("overtake-traffic",), seeds=1)
    assert expand(plain)[0].config_hash != spec.config_hash  # a different run
    with pytest.raises(InputError, match="max_time_s"):
        BenchConfig(maps=("overtake",), max_time_s=2.0, deterministic=True)
    with pytest.raises(InputError, match="deterministic"):
        BenchConfig(maps=("overtake",), deterministic="yes")


def test_cli_bench_deterministic_rejects_max_time(capsys):
    assert main(["bench", "--maps", "overtake", "--deterministic", "--max-time", "2"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--max-time" in err[0]


def test_bench_help_lists_overtake_traffic(capsys):
    with pytest.raises(SystemExit):
        main(["bench", "--help"])
    assert "overtake-traffic" in capsys.readouterr().out


def _drive(x, y, yaw, v, kappa, ds, n):
    out = []
    for _ in range(n):
        x, y, yaw = x + v * ds * np.cos(yaw), y + v * ds * np.sin(yaw), yaw + v * ds * kappa
        out.append((x, y, yaw))
    return out, (x, y, yaw)


def test_reeds_shepp_gear_rows_split_at_the_cusp():
    from rrtdrive.bench.ompl_planners import gear_rows
    from rrtdrive.types import Path

    # Forward on a left arc (κ = 0.2) to a cusp, then reverse steering right,
    # κ = tan δ / L = -0.2: the yaw keeps turning left (by -κ per metre travelled).
    fwd, cusp = _drive(0.0, 0.0, 0.0, 1.0, 0.2, 0.01, 490)
    rev, _ = _drive(*cusp, -1.0, -0.2, 0.01, 300)
    states = np.array([(0.0, 0.0, 0.0)] + fwd[9::10] + rev[9::10])  # the cusp is a sample
    d = np.diff(states[:, :2], axis=0)
    naive = np.abs(np.diff(states[:, 2]) / np.hypot(*d.T)).max()
    rows = gear_rows(states)
    path = Path(rows, np.zeros((0, 2)))
    assert path.cusps.tolist() == [50] and path.segments() == [(0, 50), (50, 81)]
    np.testing.assert_array_equal(rows[49, :3], rows[50, :3])  # the cusp row repeats
    assert path.gears[:50].tolist() == [1] * 50 and path.gears[50:].tolist() == [-1] * 31
    np.testing.assert_allclose(rows[:50, 3], 0.2, atol=1e-3)
    np.testing.assert_allclose(rows[50:, 3], -0.2, atol=1e-3)
    assert naive < 0.25  # no step across the cusp here; the OMPL sampler inserts it


@pytest.mark.parametrize("goal", [(0.0, 3.0, 0.0), (-4.0, 1.0, 2.5), (2.0, 0.0, math.pi)])
def test_reeds_shepp_cusps_are_found_on_the_curve(goal):
    pytest.importorskip("ompl")
    from ompl import base as ob
    from ompl import geometric as og

    from rrtdrive.bench.ompl_planners import reeds_shepp_path
    from rrtdrive.maps import Map
    from rrtdrive.types import Pose
    from rrtdrive.verify import verify_path

    space = ob.ReedsSheppStateSpace(6.0)
    bounds = ob.RealVectorBounds(2)
    bounds.setLow(-50.0)
    bounds.setHigh(50.0)
    space.setBounds(bounds)
    si = ob.SpaceInformation(space)
    a, b = space.allocState(), space.allocState()
    a.setX(0.0), a.setY(0.0), a.setYaw(0.0)
    b.setX(goal[0]), b.setY(goal[1]), b.setYaw(goal[2])
    solution = og.PathGeometric(si, a, b)
    path = reeds_shepp_path(space, solution, np.zeros((0, 2)))
    m = Map("open", (-50.0, -50.0, 50.0, 50.0), (), Pose(0.0, 0.0, 0.0), Pose(*goal))
    check = verify_path(m, path)
    assert len(path.cusps) >= 1 and check.ok, check
    assert path.length == pytest.approx(space.distance(a, b), rel=1e-4)
    assert np.abs(path.samples[:, 3]).max() <= 1 / 6 + 1e-4
    for a_, b_ in path.segments():  # the bicycle: yaw turns by gear * kappa per metre
        seg = path.samples[a_:b_]
        ds = np.hypot(*np.diff(seg[:, :2], axis=0).T)
        dyaw = np.diff(np.unwrap(seg[:, 2]))
        np.testing.assert_allclose(dyaw, seg[:-1, 4] * seg[:-1, 3] * ds, atol=1e-6)


# ----------------------------------------------------------------------------- maps driven


def test_a_map_file_is_driven_closed_loop_with_reverse(tmp_path):
    # A user's map as a closed-loop scenario: its start to its goal, here only in reverse.
    f = tmp_path / "bay.json"
    save_map(builtin_map("reverse_bay"), f)
    cfg = BenchConfig(
        scenarios=(str(f),), planners=("improved-rrt-connect",), controllers=("lqr",),
        seeds=1, workers=1, out=str(tmp_path / "out"), plots=False, reverse=True,
    )
    f.unlink()  # the map travels with the run, as for planning-only runs
    report = run_bench(cfg)
    assert (report.executed, report.errors) == (1, 0)
    (row,) = [json.loads(x) for x in (tmp_path / "out" / "runs.jsonl").read_text().splitlines()]
    assert row["kind"] == "episode" and row["scenario"] == str(f)
    assert row["success"] and not row["collision"] and row["verified"]
    assert row["gear_changes"] >= 1 and row["path_cusps"] >= 1  # it reversed into the bay
    summary = (tmp_path / "out" / "summary.md").read_text()
    assert "## Closed loop" in summary and str(f) in summary


def test_reverse_and_driven_maps_are_in_the_run_keys(tmp_path):
    fwd = BenchConfig(scenarios=("kerbside", "parking"), maps=("kerbside",), seeds=1)
    rev = BenchConfig(scenarios=("kerbside", "parking"), maps=("kerbside",), seeds=1, reverse=True)
    assert not {s.key for s in expand(fwd)} & {s.key for s in expand(rev)}
    assert all(s.reverse for s in expand(rev)) and not any(s.reverse for s in expand(fwd))
    # A built-in scenario keeps the key it had before maps could be driven.
    (old,) = expand(BenchConfig(scenarios=("parking",), seeds=1))
    assert old.config_hash in {s.config_hash for s in expand(fwd)}
    # A driven map file: its content is in the key, as for a planned one.
    f = tmp_path / "m.json"
    save_map(builtin_map("kerbside"), f)
    (a,) = expand(BenchConfig(scenarios=(str(f),), seeds=1))
    m = builtin_map("kerbside")
    save_map(m.with_query(start=type(m.start)(m.start.x + 1.0, m.start.y, m.start.yaw)), f)
    (b,) = expand(BenchConfig(scenarios=(str(f),), seeds=1))
    assert a.config_hash != b.config_hash and a.map_json is not None
    # Its content, not its name: the same map under another name is the same run.
    g = tmp_path / "renamed.json"
    g.write_text(f.read_text())
    (c,) = expand(BenchConfig(scenarios=(str(g),), seeds=1))
    assert c.config_hash == b.config_hash


def test_an_unknown_scenario_names_scenarios_and_maps(capsys):
    with pytest.raises(InputError, match="scenarios: unknown scenario 'nowhere'.*a map file"):
        BenchConfig(scenarios=("nowhere",), seeds=1)
    with pytest.raises(InputError, match="reverse"):
        BenchConfig(maps=("overtake",), reverse="yes")
    assert main(["bench", "--scenarios", "nowhere.json"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    # A .json name is a map file: the file's own problem is the message.
    assert len(err) == 1 and "scenarios: 'nowhere.json': map:" in err[0]


def test_a_stock_highway_env_scenario_is_benched_and_judged_by_both(tmp_path):
    cfg = BenchConfig(
        scenarios=("parking-v0",), planners=("improved-rrt-connect",), controllers=("lqr",),
        seeds=1, workers=1, out=str(tmp_path), plots=False, reverse=True,
    )
    (spec,) = expand(cfg)
    assert spec.map_json is None and spec.reverse
    report = run_bench(cfg)
    assert (report.executed, report.errors) == (1, 0)
    (row,) = [json.loads(x) for x in (tmp_path / "runs.jsonl").read_text().splitlines()]
    assert row["scenario"] == "parking-v0" and row["kind"] == "episode"
    assert row["highway_env_success"] is True and row["success"] and not row["collision"]


def test_grid_refusals_name_the_field(tmp_path):
    # Reeds-Shepp rows reverse whatever the grid says; OMPL has no iteration budget; one
    # map under two names gave one run key twice ("already stored", a traceback).
    from rrtdrive.bench.grid import BenchConfig
    from rrtdrive.maps import builtin_map, save_map
    from rrtdrive.types import InputError

    with pytest.raises(InputError, match=r"^planners: 'ompl-rs-rrtconnect' plans Reeds-Shepp"):
        BenchConfig(maps=("dead_end",), planners=("ompl-rs-rrtconnect",), out=str(tmp_path))
    with pytest.raises(InputError, match=r"^planners: 'ompl-r2-rrtconnect' has no iteration"):
        BenchConfig(maps=("dead_end",), planners=("ompl-r2-rrtconnect",), deterministic=True,
                    out=str(tmp_path))
    save_map(builtin_map("parking_lot"), tmp_path / "lot.json")
    with pytest.raises(InputError, match=r"^maps: 'parking_lot' and '.*lot.json' are the same"):
        BenchConfig(maps=("parking_lot", str(tmp_path / "lot.json")), planners=("rrt",),
                    out=str(tmp_path / "b"))


def test_an_output_folder_that_cannot_be_written_is_one_line(tmp_path):
    from rrtdrive.bench.store import ResultStore
    from rrtdrive.types import InputError

    (tmp_path / "runs.jsonl").mkdir()  # a folder where the runs file goes
    with pytest.raises(InputError, match=r"^out: cannot write into .*Is a directory"):
        ResultStore(tmp_path)


def test_an_interrupted_bench_of_another_grid_leaves_no_old_summary(tmp_path):
    out = tmp_path / "b"
    run_bench(BenchConfig(maps=("overtake",), planners=("rrt",), seeds=1, out=str(out)))
    assert (out / "summary.md").exists()

    def stop(row):
        raise KeyboardInterrupt

    other = BenchConfig(maps=("narrow_gap",), planners=("rrt",), seeds=1, out=str(out))
    with pytest.raises(KeyboardInterrupt):
        run_bench(other, on_row=stop)
    # The old grid's summary described overtake beside a config naming narrow_gap.
    assert not (out / "summary.md").exists() and not (out / "summary.csv").exists()
    assert "narrow_gap" in (out / "bench_config.json").read_text()
    # Resumed to its end, the grid writes its own.
    run_bench(other)
    assert "narrow_gap" in (out / "summary.md").read_text()


def test_an_interrupted_re_run_of_the_same_grid_keeps_its_summary(tmp_path):
    # Only the workers differ: the same grid, whose summary an interrupt took away.
    out = tmp_path / "b"
    run_bench(BenchConfig(maps=("overtake",), planners=("rrt",), seeds=2, out=str(out),
                          workers=1))  # fmt: skip
    before = (out / "summary.md").read_text()
    rows = (out / "runs.jsonl").read_text().splitlines()
    (out / "runs.jsonl").write_text(rows[0] + "\n")  # one run left to do again

    def stop(row):
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_bench(BenchConfig(maps=("overtake",), planners=("rrt",), seeds=2,
                              out=str(out) + "/", workers=2), on_row=stop)  # fmt: skip
    assert (out / "summary.md").read_text() == before


def test_rows_say_how_they_were_run(tmp_path):
    # A forward and a reverse grid's rows looked alike; the summary keeps them as ids.
    from rrtdrive.bench.summary import summarise_rows

    cfg = BenchConfig(maps=("overtake",), planners=("rrt-connect",), seeds=1, workers=1,
                      out=str(tmp_path / "b"), plots=False, reverse=True)
    run_bench(cfg)
    rows = [json.loads(line) for line in (tmp_path / "b" / "runs.jsonl").read_text().splitlines()]
    assert [(r["reverse"], r["deterministic"]) for r in rows] == [(True, False)]
    stats = summarise_rows(rows)[0].stats
    assert "reverse" not in stats and "deterministic" not in stats


def test_a_renamed_map_file_keeps_its_runs_in_one_summary_row(tmp_path):
    # Resumed by content, the stored rows kept their old name: the summary had a row
    # of 2 runs under lotA.json and one of 1 under lotB.json for one 3-seed cell.
    out = tmp_path / "b"
    first, second = tmp_path / "lotA.json", tmp_path / "lotB.json"
    save_map(builtin_map("overtake"), first)
    run_bench(BenchConfig(maps=(str(first),), planners=("rrt",), seeds=2, out=str(out)))
    first.rename(second)
    run_bench(BenchConfig(maps=(str(second),), planners=("rrt",), seeds=3, out=str(out)))
    table = [line for line in (out / "summary.md").read_text().splitlines() if "rrt" in line]
    assert len(table) == 1 and "lotB.json" in table[0] and "| 3 |" in table[0], table


def test_bench_figures_say_what_they_show(tmp_path, monkeypatch):
    import rrtdrive.plotting
    from rrtdrive.bench.summary import write_plots

    figures = {}
    monkeypatch.setattr(rrtdrive.plotting, "save_figure",
                        lambda fig, path: figures.setdefault(Path(path).name, fig))
    rows = [
        {"kind": "plan", "map": "garage", "planner": "rrt", "controller": None, "seed": s,
         "config_hash": "h", "success": True, "status": "solved", "length_m": 30.0 + s,
         "planning_time_s": 0.01, "max_curvature": 0.1 + 0.1 * s, "reverse": True}
        for s in (0, 1, 2)
    ]
    write_plots(rows, tmp_path)
    assert set(figures) == {"box_length.png", "box_time.png", "success.png",
                            "curvature_hist.png"}
    for fig in figures.values():
        assert fig._suptitle.get_text() == "rrtdrive bench: 3 runs, seeds 0-2, reverse allowed"
    hist = figures["curvature_hist.png"].axes[0]
    assert all(float(t).is_integer() for t in hist.get_yticks())  # counts of runs


def test_the_success_figure_shows_the_verified_share_of_plans(tmp_path, monkeypatch):
    # rrt's plans "succeed" and break the curvature limit: success.png showed 100 % where
    # the summary's table said 0 % verified (a plot audit).
    import rrtdrive.plotting
    from rrtdrive.bench.summary import write_plots

    figures = {}
    monkeypatch.setattr(rrtdrive.plotting, "save_figure",
                        lambda fig, path: figures.setdefault(Path(path).name, fig))
    rows = [
        {"kind": "plan", "map": "parking_lot", "planner": planner, "controller": None,
         "seed": s, "config_hash": "h", "success": True, "status": "solved",
         "verified": planner != "rrt", "length_m": 30.0, "planning_time_s": 0.01,
         "max_curvature": 0.1}
        for planner in ("improved-rrt-connect", "rrt") for s in (0, 1, 2)
    ]
    write_plots(rows, tmp_path)
    ax = figures["success.png"].axes[0]
    bars = {label: [] for label in ("success", "verified (no sharpness bound)")}
    for container in ax.containers:
        if container.get_label() in bars:
            bars[container.get_label()] = [b.get_width() for b in container.patches]
    assert bars == {"success": [1.0, 1.0], "verified (no sharpness bound)": [1.0, 0.0]}, bars


def test_a_grid_that_solved_nothing_still_gets_its_length_box_plot(tmp_path, monkeypatch):
    # docs/bench.md: a group without a successful run keeps its row, marked "(no success)";
    # with no success in any group box_length.png was not written at all.
    import rrtdrive.plotting
    from rrtdrive.bench.summary import write_plots

    figures = {}
    monkeypatch.setattr(rrtdrive.plotting, "save_figure",
                        lambda fig, path: figures.setdefault(Path(path).name, fig))
    rows = [
        {"kind": "plan", "map": "no_path", "planner": p, "controller": None, "seed": 0,
         "config_hash": "h", "success": False, "status": "proven_unreachable",
         "length_m": None, "planning_time_s": 0.01, "max_curvature": None}
        for p in ("rrt", "hybrid-a-star")
    ]
    write_plots(rows, tmp_path)
    ax = figures["box_length.png"].axes[0]
    labels = [t.get_text() for t in ax.get_yticklabels()]
    assert len(labels) == 2 and all(t.endswith("(no success)") for t in labels), labels


def test_nearly_equal_lengths_get_plain_ticks_not_an_offset(tmp_path, monkeypatch):
    # Lengths 33.9354 +- 1e-5 m: the axis read "1e-5+3.39354e1" beside ticks of 0-2.
    import rrtdrive.plotting
    from rrtdrive.bench.summary import write_plots

    figures = {}
    monkeypatch.setattr(rrtdrive.plotting, "save_figure",
                        lambda fig, path: figures.setdefault(Path(path).name, fig))
    rows = [
        {"kind": "plan", "map": "lot", "planner": "hybrid-a-star", "controller": None,
         "seed": i, "config_hash": "h", "success": True, "status": "solved",
         "length_m": 33.9354 + 1e-5 * i, "planning_time_s": 0.01, "max_curvature": 0.1}
        for i in range(3)
    ]
    write_plots(rows, tmp_path)
    fig = figures["box_length.png"]
    fig.canvas.draw()
    ax = fig.axes[0]
    assert ax.xaxis.get_offset_text().get_text() == ""
    shown = [t.get_text().replace("\u2212", "-") for t in ax.get_xticklabels()]
    ticks = [float(t) for t in shown if t]
    assert ticks and all(33.9 < t < 34.0 for t in ticks), ticks


def test_the_curvature_histogram_puts_the_limit_on_a_bin_edge(tmp_path, monkeypatch):
    # A bin straddled kappa_max once a baseline's 0.67 1/m widened the range: drivable
    # runs (0.1638 < 1/6) were drawn across the dashed line, mostly right of it.
    import rrtdrive.plotting
    from rrtdrive.bench.summary import write_plots

    figures = {}
    monkeypatch.setattr(rrtdrive.plotting, "save_figure",
                        lambda fig, path: figures.setdefault(Path(path).name, fig))
    kmax = 1.0 / 6.0
    kappas = {"rrt": [0.67, 0.31, 0.17], "hybrid-a-star": [0.16384, 0.16354, kmax]}
    rows = [
        {"kind": "plan", "map": "parking_lot", "planner": p, "controller": None, "seed": s,
         "config_hash": p, "success": True, "status": "solved", "length_m": 30.0,
         "planning_time_s": 0.01, "max_curvature": k, "kappa_max": kmax}
        for p, ks in kappas.items() for s, k in enumerate(ks)
    ]
    write_plots(rows, tmp_path)
    line = None
    for ax in figures["curvature_hist.png"].axes[:2]:
        (line,) = ax.get_lines()
        assert line.get_xdata()[0] == pytest.approx(kmax)
        counted = [b for b in ax.patches if b.get_height() > 0]
        over = [b for b in counted if b.get_x() >= kmax]  # bars right of the line
        if ax.get_title() == "hybrid-a-star":
            assert counted and not over  # every run, the one exactly at the limit too
        else:
            assert sum(b.get_height() for b in over) == 3  # 0.17 > 1/6 as well
            assert all(b.get_facecolor()[:3] == pytest.approx((0.839, 0.153, 0.157), abs=1e-3)
                       for b in over)  # drawn red
        for b in counted:  # no bar straddles the line
            assert b.get_x() + b.get_width() <= kmax * (1 + 1e-9) + 1e-12 or b.get_x() >= kmax
    assert line is not None


def _default_sigint() -> None:
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})


@pytest.mark.skipif(not Path("/proc/self/task").exists(), reason="reads /proc for the workers")
def test_ctrl_c_while_the_workers_import_is_one_line_not_their_tracebacks(tmp_path):
    # The terminal sends SIGINT to the whole process group. Workers still importing
    # (before they could ignore it) each printed a KeyboardInterrupt traceback: 119 lines.
    proc = subprocess.Popen(
        [sys.executable, "-m", "rrtdrive", "bench", "--maps", "parking_lot", "--planners",
         "rrt-connect", "--seeds", "6", "--workers", "2", "--out", str(tmp_path / "out"),
         "--no-plots", "--quiet"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True,
        # As from a terminal: a test run started in the background (`cmd &` without job
        # control) ignores SIGINT, and the bench would inherit that and never see Ctrl-C.
        preexec_fn=_default_sigint,  # noqa: PLW1509 - a plain signal reset, no threads
    )
    children = Path(f"/proc/{proc.pid}/task/{proc.pid}/children")
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and len(children.read_text().split()) < 2:
        time.sleep(0.05)
    time.sleep(0.3)  # the workers are importing now (they take seconds)
    os.killpg(proc.pid, signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130
    assert "Traceback" not in err and "KeyboardInterrupt" not in err, err[-1500:]
    assert err.strip().splitlines()[-1] == "rrtdrive: interrupted"


@pytest.mark.skipif(not hasattr(signal, "pthread_sigmask"), reason="POSIX signal masks")
def test_a_ctrl_c_while_a_worker_starts_reaches_the_bench(monkeypatch):
    # SIGINT was ignored in the main process while a worker started (so that the worker
    # is born ignoring it): a Ctrl-C in that window was lost and the bench ran on (the
    # test above then saw exit 0 on a loaded machine). Now it is held and delivered.
    import multiprocessing as mp

    from rrtdrive.bench.backends import LocalBackend

    backend = LocalBackend(workers=1)
    process = type(backend._ctx.Process())
    real_start = process.start

    def start_with_ctrl_c(self):  # noqa: ANN001, ANN202
        os.kill(os.getpid(), signal.SIGINT)  # the terminal's Ctrl-C, mid start-up
        real_start(self)

    monkeypatch.setattr(process, "start", start_with_ctrl_c)
    # As from a terminal (a background test run inherits SIGINT ignored).
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        with pytest.raises(KeyboardInterrupt):
            backend._start()
            time.sleep(1.0)  # the old code: nothing arrives
        assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
        assert signal.SIGINT not in signal.pthread_sigmask(signal.SIG_BLOCK, set())
    finally:
        signal.signal(signal.SIGINT, previous)
        for child in mp.active_children():
            if child.name == "rrtdrive-bench-worker":
                child.kill()
                child.join(5)


def test_a_scenario_that_always_reverses_keeps_one_run_key_and_says_it_reversed(tmp_path):
    # u-turn changes gear with or without --reverse: its rows said reverse false without
    # it (simulate says true), and a --reverse grid ran the same episodes again.
    fwd = BenchConfig(scenarios=("u-turn", "parking"), seeds=1)
    rev = BenchConfig(scenarios=("u-turn", "parking"), seeds=1, reverse=True)
    keys = {(s.target, s.key) for s in expand(fwd)}, {(s.target, s.key) for s in expand(rev)}
    assert {t for t, _ in keys[0] & keys[1]} == {"u-turn"}  # parking's keys differ
    cfg = BenchConfig(
        scenarios=("u-turn", "parking"), planners=("improved-rrt-connect",),
        controllers=("lqr",), seeds=1, workers=1, out=str(tmp_path), plots=False,
        deterministic=True,
    )  # fmt: skip
    assert run_bench(cfg).errors == 0
    rows = {r["scenario"]: r for r in map(json.loads, (tmp_path / "runs.jsonl").open())}
    assert rows["u-turn"]["reverse"] is True and rows["u-turn"]["path_cusps"] >= 1
    assert rows["parking"]["reverse"] is False
    assert main(["simulate", "u-turn", "--seed", "0", "--controller", "lqr",
                 "--deterministic", "--json", str(tmp_path / "sim.json")]) == 0  # fmt: skip
    sim = json.loads((tmp_path / "sim.json").read_text())
    assert sim["reverse"] is True and sim["path_length_m"] == rows["u-turn"]["path_length_m"]
    title = (tmp_path / "summary.md").read_text().splitlines()[0]
    assert title.endswith("gear changes in u-turn, deterministic)"), title
    # The --reverse grid finds u-turn's run stored and runs parking's again.
    report = run_bench(dataclasses.replace(cfg, reverse=True))
    assert (report.skipped, report.executed) == (1, 1)


def test_parking_reverse_in_is_benched_as_simulate_parking_reverse_in(tmp_path):
    cfg = BenchConfig(
        scenarios=("parking-reverse-in",), planners=("improved-rrt-connect",),
        controllers=("lqr",), seeds=1, workers=1, out=str(tmp_path), plots=False,
        deterministic=True,
    )  # fmt: skip
    assert run_bench(cfg).errors == 0
    (row,) = map(json.loads, (tmp_path / "runs.jsonl").open())
    assert row["scenario"] == "parking-reverse-in" and row["success"]
    assert row["reverse"] is True and row["reverse_in"] is True and row["path_cusps"] >= 1
    for name in (["parking-reverse-in"], ["parking", "--reverse-in"]):
        out = tmp_path / f"{len(name)}.json"
        args = ["simulate", *name, "--seed", "0", "--controller", "lqr", "--deterministic"]
        assert main([*args, "--json", str(out)]) == 0
        sim = json.loads(out.read_text())
        assert sim["reverse_in"] is True and sim["path_length_m"] == row["path_length_m"]
        assert sim["goal_position_err_m"] == row["goal_position_err_m"]
    with pytest.raises(InputError, match="did you mean 'parking-reverse-in'"):
        BenchConfig(scenarios=("parking-revers-in",), seeds=1)


def test_an_error_row_of_a_scenario_that_reverses_anyway_says_reverse(tmp_path):
    from rrtdrive.bench.worker import error_row

    rows = {s.target: error_row(s, "crashed", 1) for s in expand(
        BenchConfig(scenarios=("u-turn", "parking"), seeds=1))}  # fmt: skip
    assert rows["u-turn"]["reverse"] is True and rows["parking"]["reverse"] is False


def test_local_workers_are_capped_per_core_with_a_note(monkeypatch):
    """``--workers 200`` on a 2-core machine starts 8 processes and says why, not 200."""
    import rrtdrive.bench.core as core

    monkeypatch.setattr(core, "default_workers", lambda: 2)
    assert core.local_workers(None, 100) == (2, None)  # one per core by default
    assert core.local_workers(200, 3) == (3, None)  # never more than the runs
    assert core.local_workers(8, 100) == (8, None)  # up to 4 per core as asked
    workers, note = core.local_workers(200, 1000)
    assert workers == 8 and note is not None
    assert note.startswith("--workers 200 capped at 8")


@pytest.mark.parametrize("flag", ["--maps", "--scenarios"])
def test_a_map_too_big_for_any_grid_is_refused_before_any_run(tmp_path, capsys, flag):
    """A 20 km map was a crash in every run (retried, an error row each, exit 1), where a
    start in collision was refused at once: bench has no --resolution, so say it now."""
    from rrtdrive.collision import CheckerConfig
    from rrtdrive.collision.grid import grid_resolution
    from rrtdrive.maps import Map, save_map
    from rrtdrive.types import Pose

    huge = Map("huge", (0.0, 0.0, 20000.0, 20000.0), (), Pose(50.0, 50.0, 0.0),
               Pose(150.0, 150.0, 1.57))
    with pytest.raises(InputError, match="^bounds"):  # the grid's own verdict
        grid_resolution(huge.bounds, CheckerConfig())
    path = tmp_path / "huge.json"
    save_map(huge, str(path))
    out = tmp_path / "out"
    assert main(["bench", flag, str(path), "--seeds", "1", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"rrtdrive bench: error: {flag}: '{path}': bounds: 20000 x 20000 m")
    assert "\n" not in err and not out.exists()
