"""Audit of ``rrtdrive bench`` (session 45) as a researcher running benchmark grids.

Checks docs/bench.md against behaviour on tiny grids: the TOML ``--config`` file,
resuming, interrupts (SIGINT / SIGTERM), ``--retries`` / ``--retry-errors``, error rows,
exit codes, the summary statistics recomputed independently with ``scipy.stats``,
``summary.md`` against ``summary.csv``, ``--deterministic`` rows and bad input.
"""

from __future__ import annotations

import csv
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
import scipy.stats as st

from rrtdrive.cli import main

# The fields docs/bench.md and docs/metrics.md name as measured by the wall clock (or
# saying where and when a run ran): the rest of a deterministic row depends on its seed.
TIMING = {
    "wall_time_s", "planning_time_s", "setup_time_s", "diagnosis_time_s", "worker",
    "finished_at", "replan_time_median_s", "replan_time_max_s", "replans_over_budget",
    "total_time_s",
}
# As docs/bench.md "Groups and statistics".
SIGNED = {"progress_m", "final_speed", "nuplan_lon_accel_min", "nuplan_lon_accel_max"}
SUCCESS_ONLY = {"length_m", "max_curvature", "path_length_m", "executed_max_curvature"}
ID_FIELDS = {
    "config_hash", "seed", "kind", "map", "scenario", "planner", "controller", "status",
    "message", "error", "worker", "finished_at", "map_name", "plan_status", "max_time_s",
    "max_iterations", "attempts", "kappa_max", "simulation_frequency", "reverse",
    "reverse_in", "deterministic",
}

PLAN_GRID = ["--maps", "overtake,narrow_gap", "--planners", "rrt-connect,rrt",
             "--seeds", "12", "--max-iterations", "400", "--workers", "2", "--no-plots",
             "--quiet"]


def _sigint_deliverable() -> None:
    # In the child before exec: a pytest-xdist worker hands SIGINT down ignored, and a
    # worker that ran a bench may hand it down blocked (a mask survives exec); either way
    # the child never saw the Ctrl-C and ran to the end (exit 0 in CI, session 47).
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})


def _cli(capsys, *argv: str) -> tuple[int, str, str]:
    argv = argv if argv[:1] == ("bench",) else ("bench", *argv)
    try:
        rc = main(list(argv))
    except SystemExit as exc:  # argparse's own errors
        rc = int(exc.code or 0)
    out, err = capsys.readouterr()
    return rc, out, err


def _rows(out: Path) -> list[dict]:
    return [json.loads(line) for line in (out / "runs.jsonl").read_text().splitlines()]


def _csv(out: Path) -> list[dict]:
    with open(out / "summary.csv", newline="") as fh:
        return list(csv.DictReader(fh))


def _f(text: str) -> float:
    return float(text) if text != "" else math.nan


def _same(a: float, b: float, rel: float = 1e-9) -> bool:
    if math.isnan(a) or math.isnan(b):
        return math.isnan(a) and math.isnan(b)
    return math.isclose(a, b, rel_tol=rel, abs_tol=1e-12)


def _group_rows(rows: list[dict], line: dict) -> list[dict]:
    target = line["map"] or line["scenario"]
    return sorted(
        (r for r in rows
         if r["kind"] == line["kind"] and (r["map"] or r["scenario"]) == target
         and r["planner"] == line["planner"] and (r["controller"] or "") == line["controller"]),
        key=lambda r: r["seed"],
    )


def _reference(values: list, metric: str) -> tuple[int, float, float, float, float, bool]:
    """n, mean, std, CI of one metric, computed here from scipy.stats as the docs say."""
    rate = all(isinstance(v, bool) for v in values)
    x = np.asarray(values, dtype=float)
    n = len(x)
    mean = float(x.mean())
    std = float(x.std(ddof=1)) if n > 1 else math.nan
    if rate:
        ci = st.binomtest(int(x.sum()), n).proportion_ci(confidence_level=0.95, method="wilson")
        return n, mean, std, float(ci.low), float(ci.high), False
    if n < 2:
        return n, mean, std, math.nan, math.nan, False
    if metric in SIGNED:
        if std == 0.0:
            return n, mean, std, mean, mean, False
        lo, hi = st.t.interval(0.95, n - 1, loc=mean, scale=std / math.sqrt(n))
        return n, mean, std, float(lo), float(hi), False
    if np.all(x == x[0]):
        return n, mean, std, float(x[0]), float(x[0]), True
    res = st.bootstrap((x,), np.mean, n_resamples=1999, confidence_level=0.95,
                       method="percentile", rng=np.random.default_rng(0))
    return n, mean, std, float(res.confidence_interval.low), float(
        res.confidence_interval.high), True


def _check_summary_against_rows(out: Path) -> int:
    """Recompute every summary.csv line from runs.jsonl; return the lines checked."""
    rows = _rows(out)
    checked = 0
    for line in _csv(out):
        members = _group_rows(rows, line)
        ok = [r for r in members if r["status"] != "error"]
        assert int(line["runs"]) == len(members), line
        assert int(line["errors"]) == len(members) - len(ok), line
        metric = line["metric"]
        if not metric:
            assert not ok and line["n"] == "0", line
            continue
        values = [r[metric] for r in ok if r.get(metric) is not None
                  and not (metric in SUCCESS_ONLY and not r["success"])]
        n, mean, std, lo, hi, boot = _reference(values, metric)
        assert int(line["n"]) == n, (line, n)
        assert _same(_f(line["mean"]), mean), (line, mean)
        assert _same(_f(line["std"]), std), (line, std)
        assert _same(_f(line["ci95_low"]), lo), (line, lo)
        assert _same(_f(line["ci95_high"]), hi), (line, hi)
        if boot and n >= 5:
            # The documented interval, as scipy's bootstrap gives it with many more
            # resamples: what is left is Monte-Carlo error, a small part of the SEM.
            x = np.asarray(values, dtype=float)
            big = st.bootstrap((x,), np.mean, n_resamples=49_999, method="percentile",
                               rng=np.random.default_rng(12345)).confidence_interval
            sem = x.std(ddof=1) / math.sqrt(n)
            assert abs(_f(line["ci95_low"]) - big.low) <= 0.5 * sem + 1e-12, (line, big)
            assert abs(_f(line["ci95_high"]) - big.high) <= 0.5 * sem + 1e-12, (line, big)
            assert x.min() <= _f(line["ci95_low"]) <= _f(line["ci95_high"]) <= x.max()
        checked += 1
    return checked


@pytest.fixture(scope="module")
def plan_bench(tmp_path_factory):
    """A 4-cell x 12-seed planning grid, run once through the CLI."""
    out = tmp_path_factory.mktemp("plan") / "bench"
    rc = main(["bench", *PLAN_GRID, "--out", str(out)])
    assert rc == 0
    return out


def test_summary_csv_is_scipy_recomputed_from_runs_jsonl(plan_bench):
    assert _check_summary_against_rows(plan_bench) > 20


# ------------------------------------------------------------------- summary.md vs summary.csv

MD_PLAN = {  # column -> (metric, scale, format), as rendered by summary.md
    "success": ("success", 1.0, "{:.0%}"),
    "verified": ("verified", 1.0, "{:.0%}"),
    "length [m]": ("length_m", 1.0, "{:.2f}"),
    "time [ms]": ("planning_time_s", 1e3, "{:.1f}"),
    "max κ [1/m]": ("max_curvature", 1.0, "{:.3f}"),
    "nodes": ("nodes", 1.0, "{:.0f}"),
}


def _md_table(text: str) -> list[dict]:
    lines = [ln for ln in text.splitlines() if ln.startswith("|")]
    head = [c.strip() for c in lines[0].strip("|").split("|")]
    return [dict(zip(head, (c.strip() for c in ln.strip("|").split("|")), strict=True))
            for ln in lines[2:]]


MD_EPISODE = {
    "success": ("success", 1.0, "{:.0%}"),
    "collision": ("collision", 1.0, "{:.0%}"),
    "CTE rms [m]": ("cte_rms_m", 1.0, "{:.3f}"),
    "path [m]": ("path_length_m", 1.0, "{:.1f}"),
    "exec. max κ": ("executed_max_curvature", 1.0, "{:.3f}"),
    "max a_lat": ("max_lateral_accel", 1.0, "{:.2f}"),
    "time to goal [s]": ("time_to_goal_s", 1.0, "{:.1f}"),
    "plan time [ms]": ("planning_time_s", 1e3, "{:.1f}"),
}


def _check_md_against_csv(out: Path) -> int:
    """Every summary.md cell from summary.csv's numbers; return the cells checked."""
    lines = _csv(out)
    text = (out / "summary.md").read_text()
    checked = 0
    for heading, kind, first, columns in (("## Planning only", "plan", "map", MD_PLAN),
                                          ("## Closed loop", "episode", "scenario", MD_EPISODE)):
        cells = {(ln[first], ln["planner"], ln["controller"]) for ln in lines
                 if ln["kind"] == kind}
        if not cells:
            assert heading not in text
            continue
        section = text.split(heading, 1)[1].split("\n## ", 1)[0]
        table = _md_table(section)
        assert len(table) == len(cells)
        for row in table:
            stats = {ln["metric"]: ln for ln in lines
                     if ln["kind"] == kind and ln[first] == row[first]
                     and ln["planner"] == row["planner"]
                     and ln["controller"] == row.get("controller", "")}
            any_line = next(iter(stats.values()))
            assert (row["runs"], row["errors"]) == (any_line["runs"], any_line["errors"])
            for column, (metric, scale, fmt) in columns.items():
                s = stats.get(metric)
                checked += 1
                if s is None or s["n"] == "0":
                    assert row[column] == "–", (row, column)
                    continue
                mean, std = _f(s["mean"]), _f(s["std"])
                lo, hi = _f(s["ci95_low"]), _f(s["ci95_high"])
                if metric in ("success", "verified", "collision"):
                    want = f"{fmt.format(mean)} [{fmt.format(lo)}, {fmt.format(hi)}]"
                elif int(s["n"]) < 2:
                    want = fmt.format(mean * scale)
                else:
                    med = _f(s["median"])  # the CSV's median, also in the page (s49)
                    want = (f"{fmt.format(mean * scale)} ± {fmt.format(std * scale)} "
                            f"[{fmt.format(lo * scale)}, {fmt.format(hi * scale)}], "
                            f"median {fmt.format(med * scale)}")
                assert row[column] == want, (row[first], row["planner"], column)
    return checked


def test_summary_md_agrees_with_summary_csv(plan_bench):
    assert _check_md_against_csv(plan_bench) == 4 * len(MD_PLAN)


# ------------------------------------------------------------------------------------ resume


def test_rerun_redoes_nothing_and_rewrites_the_summary_atomically(plan_bench, capsys):
    runs_before = (plan_bench / "runs.jsonl").read_bytes()
    csv_before = (plan_bench / "summary.csv").read_bytes()
    md_before = (plan_bench / "summary.md").read_bytes()
    inodes = {n: (plan_bench / n).stat().st_ino for n in ("summary.csv", "summary.md")}
    rc, out, _ = _cli(capsys, *PLAN_GRID, "--out", str(plan_bench))
    assert rc == 0
    assert "48 runs (48 resumed, 0 run now, 0 errors)" in out
    assert (plan_bench / "runs.jsonl").read_bytes() == runs_before
    # Rewritten (a rename: a new inode), to the same text: the bootstrap is seeded.
    for name in inodes:
        assert (plan_bench / name).stat().st_ino != inodes[name], name
    assert (plan_bench / "summary.csv").read_bytes() == csv_before
    assert (plan_bench / "summary.md").read_bytes() == md_before
    assert sorted(os.listdir(plan_bench)) == sorted(
        [".lock", "runs.jsonl", "bench_config.json", "summary.csv", "summary.md"])


def test_a_partial_last_line_is_cut_and_its_run_redone(tmp_path, capsys):
    grid = ["--maps", "overtake", "--planners", "rrt-connect", "--seeds", "3",
            "--max-iterations", "300", "--workers", "1", "--no-plots", "--quiet",
            "--out", str(tmp_path)]
    assert _cli(capsys, *grid)[0] == 0
    lines = (tmp_path / "runs.jsonl").read_text().splitlines()
    (tmp_path / "runs.jsonl").write_text("\n".join(lines[:2]) + "\n" + lines[2][:40])
    rc, out, err = _cli(capsys, *grid)
    assert rc == 0 and "(2 resumed, 1 run now, 0 errors)" in out
    rows = _rows(tmp_path)
    assert sorted(r["seed"] for r in rows) == [0, 1, 2]


#: Runs in the interrupted grid: enough left after the third line that the signal lands
#: mid-bench on a fast machine too (16 finished before it in CI, 2 s in all).
KILL_SEEDS = 40


def _kill_mid_bench(out: Path, sig: int) -> subprocess.CompletedProcess:
    cmd = [sys.executable, "-m", "rrtdrive", "bench", "--maps", "parking_lot",
           "--planners", "improved-rrt-connect", "--seeds", str(KILL_SEEDS),
           "--max-iterations", "2000",
           "--workers", "2", "--no-plots", "--out", str(out)]
    # SIGINT at its default in the child: a test run started in the background (nohup ...
    # &, as a CI script may) hands its children SIGINT ignored, and Python then keeps it so
    # (the bench ran to the end: exit 0 where 130 was asked for).
    proc = subprocess.Popen(
        cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        preexec_fn=_sigint_deliverable,
    )  # fmt: skip
    runs = out / "runs.jsonl"
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:
        if runs.exists() and runs.read_bytes().count(b"\n") >= 3:
            break
        time.sleep(0.01)
    proc.send_signal(sig)
    stdout, stderr = proc.communicate(timeout=60)
    return subprocess.CompletedProcess(cmd, proc.returncode, stdout, stderr)


@pytest.mark.parametrize(("sig", "code"), [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_an_interrupted_bench_leaves_whole_lines_and_resumes_without_duplicates(
    tmp_path, sig, code
):
    out = tmp_path / "b"
    done = _kill_mid_bench(out, sig)
    assert done.returncode == code, done.stderr
    text = (out / "runs.jsonl").read_text()
    assert text.endswith("\n")
    rows = [json.loads(line) for line in text.splitlines()]
    assert 3 <= len(rows) < KILL_SEEDS
    assert len({(r["config_hash"], r["seed"]) for r in rows}) == len(rows)
    # No summary of a half-done first grid, and no temporary file left behind.
    assert sorted(os.listdir(out)) == [".lock", "bench_config.json", "runs.jsonl"]
    again = subprocess.run(done.args + ["--quiet"], capture_output=True, text=True,
                           timeout=120)
    assert again.returncode == 0, again.stderr
    assert f"({len(rows)} resumed, {KILL_SEEDS - len(rows)} run now, 0 errors)" in again.stdout
    rows2 = _rows(out)
    keys = Counter((r["config_hash"], r["seed"]) for r in rows2)
    assert len(rows2) == KILL_SEEDS and max(keys.values()) == 1
    assert rows2[: len(rows)] == rows  # append-only: the earlier lines are untouched
    assert _check_summary_against_rows(out) > 5
    assert (out / "summary.md").is_file()


# ------------------------------------------------------------ errors, retries, exit codes


def _timeout_grid(out: Path, *extra: str) -> list[str]:
    return ["--maps", "parking_lot", "--planners", "improved-rrt-connect", "--seeds", "1",
            "--max-iterations", "3000", "--workers", "1", "--no-plots", "--quiet",
            "--out", str(out), *extra]


def test_error_rows_retries_exit_codes_and_retry_errors(tmp_path, capsys):
    # --run-timeout far below a run's length: every attempt is killed (a crash).
    rc, out, _ = _cli(capsys, *_timeout_grid(tmp_path, "--run-timeout", "0.001",
                                            "--retries", "1"))
    assert rc == 1 and "1 errors" in out
    (row,) = _rows(tmp_path)
    assert row["status"] == "error" and row["attempts"] == 2  # 1 + --retries
    assert "run timeout" in row["error"]
    assert "wall_time_s" not in row and "worker" not in row
    (line,) = _csv(tmp_path)  # a group of error rows only: one line, empty metric
    assert (line["runs"], line["errors"], line["metric"], line["n"]) == ("1", "1", "", "0")
    # Error rows count as done: nothing is run again, and the grid still has an error.
    rc, out, _ = _cli(capsys, *_timeout_grid(tmp_path))
    assert rc == 1 and "(1 resumed, 0 run now, 1 errors)" in out
    assert len(_rows(tmp_path)) == 1
    # --retry-errors replaces the error row by a new attempt.
    rc, out, _ = _cli(capsys, *_timeout_grid(tmp_path, "--retry-errors"))
    assert rc == 0 and "(0 resumed, 1 run now, 0 errors)" in out
    (row,) = _rows(tmp_path)
    assert row["status"] != "error" and row["error"] is None and row["attempts"] == 1


def test_retries_zero_means_one_attempt(tmp_path, capsys):
    rc, _, _ = _cli(capsys, *_timeout_grid(tmp_path, "--run-timeout", "0.001",
                                          "--retries", "0"))
    assert rc == 1
    (row,) = _rows(tmp_path)
    assert row["status"] == "error" and row["attempts"] == 1


def test_a_failed_plan_is_a_result_not_an_error(tmp_path, capsys):
    rc, out, _ = _cli(capsys, "--maps", "no_path", "--planners", "rrt-connect", "--seeds",
                      "1", "--max-iterations", "200", "--workers", "1", "--no-plots",
                      "--quiet", "--out", str(tmp_path))
    assert rc == 0 and "0 errors" in out
    (row,) = _rows(tmp_path)
    assert row["success"] is False and row["status"] != "error" and row["error"] is None


# ----------------------------------------------------------------------------- deterministic


def test_deterministic_rows_repeat_apart_from_timing_fields(tmp_path, capsys):
    grid = ["--maps", "parking_lot", "--scenarios", "overtake", "--planners",
            "improved-rrt-connect", "--seeds", "2", "--max-iterations", "1500",
            "--workers", "2", "--no-plots", "--quiet", "--deterministic"]
    for name in ("a", "b"):
        assert _cli(capsys, *grid, "--out", str(tmp_path / name))[0] == 0
    a = {(r["config_hash"], r["seed"]): r for r in _rows(tmp_path / "a")}
    b = {(r["config_hash"], r["seed"]): r for r in _rows(tmp_path / "b")}
    assert a.keys() == b.keys() and len(a) == 4
    for key, row in a.items():
        assert row["deterministic"] is True and row["max_time_s"] == 1e6
        strip = {k: v for k, v in row.items() if k not in TIMING}
        assert strip == {k: v for k, v in b[key].items() if k not in TIMING}, key
    # The summaries agree on every metric that is no timing, to the last digit.
    sa = {(ln["kind"], ln["map"], ln["scenario"], ln["metric"]): ln
          for ln in _csv(tmp_path / "a") if ln["metric"] not in TIMING}
    sb = {(ln["kind"], ln["map"], ln["scenario"], ln["metric"]): ln
          for ln in _csv(tmp_path / "b") if ln["metric"] not in TIMING}
    assert sa == sb
    assert "deterministic" in (tmp_path / "a" / "summary.md").read_text().splitlines()[0]
    # Closed-loop statistics too: Student's t for the signed metrics, Wilson for rates.
    assert _check_summary_against_rows(tmp_path / "a") > 40
    metrics = {ln["metric"] for ln in _csv(tmp_path / "a")}
    assert {"progress_m", "collision", "cte_rms_m"} <= metrics
    assert _check_md_against_csv(tmp_path / "a") == len(MD_PLAN) + len(MD_EPISODE)


# -------------------------------------------------------------------------------- TOML file

FULL_TOML = """\
maps = ["overtake"]
scenarios = []
planners = ["rrt-connect"]
controllers = ["pure-pursuit"]
seeds = 2
workers = 1
out = "{out}"
max_time_s = 4.0
max_iterations = 300
run_timeout_s = 60
retries = 2
plots = false
deterministic = false
reverse = false
ray = false
"""


def _resolved(out: Path) -> dict:
    return json.loads((out / "bench_config.json").read_text())["config"]


def test_every_documented_toml_key_is_read(tmp_path, capsys):
    out = tmp_path / "b"
    cfg = tmp_path / "bench.toml"
    cfg.write_text(FULL_TOML.format(out=out))
    rc, _, _ = _cli(capsys, "bench", "--config", str(cfg), "--quiet")
    assert rc == 0
    got = _resolved(out)
    assert {k: got[k] for k in ("maps", "scenarios", "planners", "controllers", "seeds",
                                "workers", "out", "max_time_s", "max_iterations",
                                "run_timeout_s", "retries", "plots", "deterministic",
                                "reverse", "ray")} == {
        "maps": ["overtake"], "scenarios": [], "planners": ["rrt-connect"],
        "controllers": ["pure-pursuit"], "seeds": 2, "workers": 1, "out": str(out),
        "max_time_s": 4.0, "max_iterations": 300, "run_timeout_s": 60.0, "retries": 2,
        "plots": False, "deterministic": False, "reverse": False, "ray": None,
    }
    assert sorted(os.listdir(out)) == [".lock", "bench_config.json", "runs.jsonl",
                                       "summary.csv", "summary.md"]  # plots = false
    rows = _rows(out)
    assert len(rows) == 2 and {r["max_iterations"] for r in rows} == {300}
    assert {r["max_time_s"] for r in rows} == {4.0}


def test_a_bench_table_is_the_same_file(tmp_path, capsys):
    cfg = tmp_path / "bench.toml"
    cfg.write_text("[bench]\n" + FULL_TOML.format(out=tmp_path / "t"))
    assert _cli(capsys, "bench", "--config", str(cfg), "--quiet")[0] == 0
    flat = tmp_path / "flat.toml"
    flat.write_text(FULL_TOML.format(out=tmp_path / "f"))
    assert _cli(capsys, "bench", "--config", str(flat), "--quiet")[0] == 0
    strip = {"out"}
    assert ({k: v for k, v in _resolved(tmp_path / "t").items() if k not in strip}
            == {k: v for k, v in _resolved(tmp_path / "f").items() if k not in strip})


def test_flags_override_the_file_and_more_seeds_run_only_the_new_ones(tmp_path, capsys):
    out = tmp_path / "b"
    cfg = tmp_path / "bench.toml"
    cfg.write_text(FULL_TOML.format(out=tmp_path / "unused").replace(
        "plots = false", "plots = true"))
    rc, _, _ = _cli(capsys, "bench", "--config", str(cfg), "--out", str(out),
                    "--max-iterations", "250", "--maps", "narrow_gap", "--no-plots",
                    "--quiet")
    assert rc == 0 and not (tmp_path / "unused").exists()
    got = _resolved(out)
    assert (got["maps"], got["max_iterations"], got["plots"], got["seeds"]) == (
        ["narrow_gap"], 250, False, 2)
    assert not list(out.glob("*.png"))
    rc, out_text, _ = _cli(capsys, "bench", "--config", str(cfg), "--out", str(out),
                           "--max-iterations", "250", "--maps", "narrow_gap", "--no-plots",
                           "--quiet", "--seeds", "3")
    assert rc == 0 and "3 runs (2 resumed, 1 run now, 0 errors)" in out_text
    assert sorted(r["seed"] for r in _rows(out)) == [0, 1, 2]


BAD_TOML = [
    ('seeds = "3"', "seeds"),
    ("seeds = 3.5", "seeds"),
    ("seeds = 0", "seeds"),
    ("workers = 0", "workers"),
    ('max_time_s = "5"', "max_time_s"),
    ("max_time_s = -1", "max_time_s"),
    ("max_iterations = 0", "max_iterations"),
    ("run_timeout_s = 0", "run_timeout_s"),
    ("retries = -1", "retries"),
    ('plots = "yes"', "plots"),
    ("deterministic = 1", "deterministic"),
    ('reverse = "true"', "reverse"),
    ("ray = 5", "ray"),
    ("maps = 5", "maps"),
    ('maps = ["no_such_map"]', "maps"),
    ('planners = ["no_such_planner"]', "planners"),
    ('controllers = ["no_such_controller"]', "controllers"),
    ('out = ""', "out"),
    ("seed = 3", "seed"),  # an unknown key
    ("deterministic = true\nmax_time_s = 2.0", "max_time_s"),
    ("maps = [", "malformed TOML"),
]


@pytest.mark.parametrize(("line", "field"), BAD_TOML)
def test_bad_toml_is_one_line_naming_the_field_exit_2(tmp_path, capsys, line, field):
    base = {"maps": '["overtake"]', "planners": '["rrt-connect"]', "seeds": "1",
            "out": json.dumps(str(tmp_path / "b"))}
    key = line.split(" ")[0]
    text = "".join(f"{k} = {v}\n" for k, v in base.items() if k != key) + line + "\n"
    cfg = tmp_path / "bench.toml"
    cfg.write_text(text)
    rc, out, err = _cli(capsys, "bench", "--config", str(cfg), "--quiet")
    assert rc == 2 and out == ""
    assert len(err.splitlines()) == 1, err
    assert err.startswith("rrtdrive bench: error: ") and field in err, err
    assert not (tmp_path / "b").exists()


BAD_FLAGS = [
    (["--seeds", "0"], "--seeds"),
    (["--workers", "0"], "--workers"),
    (["--jobs", "0"], "--workers"),
    (["--seeds", "x"], "--seeds"),
    (["--max-time", "0"], "--max-time"),
    (["--max-iterations", "-5"], "--max-iterations"),
    (["--run-timeout", "-1"], "--run-timeout"),
    (["--retries", "-1"], "--retries"),
    (["--planners", "nope"], "--planners"),
    (["--controllers", "nope"], "--controllers"),
    (["--scenarios", "nope"], "--scenarios"),
    (["--planners", "rrt-connect@no_field=1"], "--planners"),
    (["--deterministic", "--max-time", "2"], "--max-time"),
    (["--config", "does_not_exist.toml"], "config"),
]


@pytest.mark.parametrize(("extra", "field"), BAD_FLAGS)
def test_bad_flags_are_one_line_naming_the_field_exit_2(tmp_path, capsys, extra, field):
    rc, out, err = _cli(capsys, "bench", "--maps", "overtake", "--out",
                        str(tmp_path / "b"), "--quiet", *extra)
    assert rc == 2 and out == ""
    assert len(err.splitlines()) == 1, err
    assert field in err, err
    assert not (tmp_path / "b").exists()


def test_an_unknown_map_flag_names_maps(tmp_path, capsys):
    rc, _, err = _cli(capsys, "bench", "--maps", "no_such_map", "--out", str(tmp_path / "b"))
    assert rc == 2 and len(err.splitlines()) == 1 and "--maps" in err


# ---------------------------------------------------------------- plots against the summary


def test_the_success_figure_and_the_summary_give_one_verified_rate(tmp_path, monkeypatch):
    import rrtdrive.plotting
    from rrtdrive.bench.summary import summarise_rows, write_plots

    figures = {}
    monkeypatch.setattr(rrtdrive.plotting, "save_figure",
                        lambda fig, path: figures.setdefault(Path(path).name, fig))
    # Two solved and verified plans and one failed plan (verified: null), as bench writes.
    rows = [
        {"kind": "plan", "map": "parking_lot", "planner": "improved-rrt-connect",
         "controller": None, "seed": s, "config_hash": "h", "success": s < 2,
         "status": "solved" if s < 2 else "iteration_limit", "verified": True if s < 2 else None,
         "length_m": 140.0 + s if s < 2 else None, "planning_time_s": 0.01,
         "max_curvature": 0.15 if s < 2 else None}
        for s in range(3)
    ]
    (group,) = summarise_rows(rows)
    write_plots(rows, tmp_path)
    ax = figures["success.png"].axes[0]
    bars = {c.get_label(): [b.get_width() for b in c.patches] for c in ax.containers
            if c.get_label() in ("success", "verified (no sharpness bound)")}
    assert bars["success"] == pytest.approx([group.stats["success"].mean])
    assert bars["verified (no sharpness bound)"] == pytest.approx(
        [group.stats["verified"].mean])


def test_retry_errors_survives_a_row_with_nan_from_another_tool(tmp_path, capsys):
    from rrtdrive.bench import BenchConfig, expand
    from rrtdrive.bench.worker import error_row

    argv = ["--maps", "overtake", "--planners", "rrt-connect", "--seeds", "1",
            "--max-iterations", "300", "--workers", "1", "--no-plots", "--quiet",
            "--out", str(tmp_path)]
    (spec,) = expand(BenchConfig(maps=("overtake",), planners=("rrt-connect",), seeds=1,
                                 max_iterations=300))
    foreign = ('{"config_hash": "0123456789abcdef", "seed": 0, "kind": "plan", "map": "x", '
               '"planner": "rrt", "status": "solved", "length_m": NaN}')
    (tmp_path / "runs.jsonl").write_text(
        foreign + "\n" + json.dumps(error_row(spec, "worker process died", 2)) + "\n")
    rc, _, err = _cli(capsys, *argv)  # a plain resume reads the file fine
    assert rc == 1 and "Traceback" not in err
    rc, out, err = _cli(capsys, *argv, "--retry-errors")
    assert "Traceback" not in err and rc == 0, err[-300:]
    assert "(0 resumed, 1 run now, 0 errors)" in out
    lines = (tmp_path / "runs.jsonl").read_text().splitlines()
    assert len(lines) == 2 and json.loads(lines[0])["config_hash"] == "0123456789abcdef"
