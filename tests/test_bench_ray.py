"""The Ray backend of ``rrtdrive bench`` on a local ``ray.init(num_cpus=2)``.

Skipped when Ray is not installed (the default CI installs only ``.[dev]``).
"""

from __future__ import annotations

import json
import os
import sys
from collections import Counter
from pathlib import Path

import pytest

ray = pytest.importorskip("ray")

from rrtdrive.bench import BenchConfig, ResultStore, expand, run_bench  # noqa: E402
from rrtdrive.bench.core import grid_rows  # noqa: E402
from rrtdrive.bench.worker import execute_run  # noqa: E402


def crashing_executor(spec):
    """Seed 1 kills its Ray worker on the first attempt only; seed 2 on every attempt."""
    marker = Path(spec_marker_dir()) / f"{spec.config_hash}-{spec.seed}"
    if spec.seed == 1 and not marker.exists():
        marker.write_text("crashed once")
        os._exit(3)
    if spec.seed == 2:
        os._exit(4)
    return execute_run(spec)


def spec_marker_dir() -> str:
    return os.environ["RRTDRIVE_TEST_MARKERS"]


@pytest.fixture(scope="module")
def ray_session(tmp_path_factory):
    markers = tmp_path_factory.mktemp("markers")
    os.environ["RRTDRIVE_TEST_MARKERS"] = str(markers)  # inherited by the Ray workers
    # Ray's workers cannot import this test module by name: ship its functions by value.
    ray.cloudpickle.register_pickle_by_value(sys.modules[__name__])
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    yield
    ray.shutdown()


def test_ray_backend_runs_and_resumes(ray_session, tmp_path):
    cfg = BenchConfig(
        maps=("overtake", "no_path"), planners=("rrt-connect", "improved-rrt-connect"),
        seeds=3, ray="", out=str(tmp_path), plots=False,
    )
    report = run_bench(cfg)
    assert report.backend.startswith("Ray (2 CPUs")
    assert (report.total, report.executed, report.errors) == (12, 12, 0)
    rows = [json.loads(x) for x in (tmp_path / "runs.jsonl").read_text().splitlines()]
    assert Counter((r["config_hash"], r["seed"]) for r in rows) == Counter(
        s.key for s in expand(cfg)
    )
    assert all(r["success"] == (r["map"] == "overtake") for r in rows)
    assert len({r["worker"] for r in rows}) >= 1
    again = run_bench(cfg)
    assert (again.skipped, again.executed) == (12, 0)
    assert ray.is_initialized()  # a session the bench did not start is left running


def test_ray_crashed_task_is_retried_then_recorded(ray_session, tmp_path):
    cfg = BenchConfig(
        maps=("overtake",), planners=("rrt-connect",), seeds=3, ray="", out=str(tmp_path),
        plots=False,
    )
    report = run_bench(cfg, executor=crashing_executor)
    assert (report.executed, report.errors) == (3, 1)
    with ResultStore(tmp_path, lock=False) as store:
        rows = {r["seed"]: r for r in grid_rows(cfg, store)}
    assert rows[0]["success"] and rows[1]["success"]  # seed 1: Ray retried the dead worker
    assert rows[2]["status"] == "error" and rows[2]["attempts"] == 2


def test_an_address_ray_cannot_reach_is_one_line_and_leaves_no_folder(tmp_path):
    # In a fresh process: this module's Ray session would otherwise be reused.
    import subprocess

    out = tmp_path / "bench"
    proc = subprocess.run(
        [sys.executable, "-m", "rrtdrive", "bench", "--maps", "overtake", "--planners",
         "rrt-connect", "--seeds", "1", "--ray", "bogus://x", "--out", str(out)],
        capture_output=True, text=True, timeout=300, check=False,
    )
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.count("\n") == 1
    assert "error: --ray: cannot connect to bogus://x" in proc.stderr
    assert not out.exists()


def sleepy_executor(spec):
    """Seed 1 outlasts any short run timeout; the others run as usual."""
    if spec.seed == 1:
        import time

        time.sleep(120)
    return execute_run(spec)


def test_ray_run_past_the_run_timeout_fails_with_the_local_message(ray_session, tmp_path):
    cfg = BenchConfig(
        maps=("overtake",), planners=("rrt-connect",), seeds=3, ray="", out=str(tmp_path),
        plots=False, retries=0, run_timeout_s=3.0,
    )
    report = run_bench(cfg, executor=sleepy_executor)
    assert (report.executed, report.errors) == (3, 1)
    with ResultStore(tmp_path, lock=False) as store:
        rows = {r["seed"]: r for r in grid_rows(cfg, store)}
    assert rows[0]["success"] and rows[2]["success"]
    assert rows[1]["status"] == "error"
    assert "run exceeded the run timeout of 3 s" in rows[1]["error"]


def _closed_port() -> int:
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.mark.parametrize("how", ["flag", "env"])
def test_a_ray_head_that_is_not_there_is_one_line_at_once(tmp_path, how):
    # Ray itself retries HOST:PORT for minutes (2 min measured): the CLI tries TCP first.
    import subprocess

    address = f"127.0.0.1:{_closed_port()}"
    out = tmp_path / "bench"
    flag = ["--ray", address] if how == "flag" else ["--ray"]
    env = {**os.environ, "RAY_ADDRESS": address} if how == "env" else None
    proc = subprocess.run(
        [sys.executable, "-m", "rrtdrive", "bench", "--maps", "overtake", "--planners",
         "rrt-connect", "--seeds", "1", *flag, "--out", str(out)],
        capture_output=True, text=True, timeout=90, check=False, env=env,
    )
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.count("\n") == 1
    source = " (from RAY_ADDRESS)" if how == "env" else ""
    assert f"error: --ray: cannot connect to {address}{source}: Connection refused" in proc.stderr
    assert not out.exists()
