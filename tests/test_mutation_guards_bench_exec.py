"""Guards from a mutation audit of the bench's execution layer.

The local worker processes (retries, run timeouts, start-up deaths, the order of
``parallel_map``), the resume and clean-up of ``run_bench`` and the result
store's repair of a torn file. Every run here uses a cheap executor (no
planning), so the workers cost only their start-up.
"""

from __future__ import annotations

import json
import os
import time
from pathlib import Path as FsPath
from typing import Any

import pytest

from rrtdrive.bench import BenchConfig, ResultStore, expand, run_bench
from rrtdrive.bench.backends import LocalBackend, Outcome, WorkerStartupError, parallel_map
from rrtdrive.bench.core import grid_rows
from rrtdrive.bench.grid import RunSpec
from rrtdrive.bench.summary import PLOT_FILES
from rrtdrive.bench.worker import base_row
from rrtdrive.types import InputError

MARKERS = "RRTDRIVE_TEST_MARKERS"

# ----------------------------------------------------------------------------- executors
# Module-level: the spawned workers import this module by name to find them.


def quick_executor(spec: RunSpec) -> dict[str, Any]:
    """A successful row without planning anything."""
    row = base_row(spec)
    row.update({"success": True, "status": "exact", "error": None})
    return row


def _first_time(name: str) -> bool:
    """True once per marker name (the marker folder is the test's)."""
    try:
        fd = os.open(FsPath(os.environ[MARKERS]) / name, os.O_CREAT | os.O_EXCL | os.O_WRONLY)
    except FileExistsError:
        return False
    os.close(fd)
    return True


def flaky_executor(spec: RunSpec) -> dict[str, Any]:
    """Seed 0 always raises, seed 1 raises once, seed 2 kills its worker once."""
    if spec.seed == 0:
        raise RuntimeError("always")
    if spec.seed == 1 and _first_time(f"{spec.config_hash}-1"):
        raise RuntimeError("flaky")
    if spec.seed == 2 and _first_time(f"{spec.config_hash}-2"):
        os._exit(3)
    return quick_executor(spec)


def slow_executor(spec: RunSpec) -> dict[str, Any]:
    """Every run takes 0.4 s."""
    time.sleep(0.4)
    return quick_executor(spec)


def _claim_start(marker_dir: str) -> int:
    """Number a worker's start 0, 1, ...: the first ticket file it can create."""
    n = 0
    while True:
        try:
            fd = os.open(os.path.join(marker_dir, f"start-{n}"), os.O_CREAT | os.O_EXCL)
        except FileExistsError:
            n += 1
            continue
        os.close(fd)
        return n


def _rebuild_fragile(marker_dir: str, die_at: tuple[int, ...], crash_seed: int) -> Any:
    """Unpickled in a starting worker: the starts numbered in ``die_at`` die right here."""
    if _claim_start(marker_dir) in die_at:
        os._exit(5)
    return FragileExecutor(marker_dir, die_at, crash_seed)


class FragileExecutor:
    """An executor whose workers die at start-up (before "ready") on chosen starts.

    Run ``crash_seed`` also kills its worker on its first attempt.
    """

    def __init__(self, marker_dir: str, die_at: tuple[int, ...], crash_seed: int = -1) -> None:
        self.marker_dir, self.die_at, self.crash_seed = marker_dir, die_at, crash_seed

    def __reduce__(self) -> tuple[Any, tuple[Any, ...]]:
        return (_rebuild_fragile, (self.marker_dir, self.die_at, self.crash_seed))

    def __call__(self, spec: RunSpec) -> dict[str, Any]:
        if spec.seed == self.crash_seed:
            marker = os.path.join(self.marker_dir, f"crashed-{spec.seed}")
            if not os.path.exists(marker):
                FsPath(marker).write_text("once")
                os._exit(3)
        return quick_executor(spec)


def square(item: list[int]) -> dict[str, Any]:
    """``parallel_map``'s work: item 0 raises once, 5 kills its worker once; -1 is bad
    input; -2 hangs."""
    (x,) = item
    if x == 0 and _first_time("square-0"):
        raise RuntimeError("once")
    if x == 5 and _first_time("square-5"):
        os._exit(3)
    if x == -1:
        raise InputError("scenario: unknown 'nowhere'")
    if x == -2:
        time.sleep(20)
    return {"x": x, "sq": x * x}


# ----------------------------------------------------------------------------- helpers


@pytest.fixture
def markers(tmp_path: FsPath, monkeypatch: pytest.MonkeyPatch) -> FsPath:
    """A fresh marker folder, named to the workers through the environment."""
    d = tmp_path / "markers"
    d.mkdir()
    monkeypatch.setenv(MARKERS, str(d))
    return d


def _cfg(out: FsPath, seeds: int, **kw: Any) -> BenchConfig:
    return BenchConfig(maps=("overtake",), planners=("rrt",), seeds=seeds, workers=1,
                       out=str(out), plots=False, **kw)


def _rows_by_seed(cfg: BenchConfig) -> dict[int, dict[str, Any]]:
    with ResultStore(cfg.out, lock=False) as store:
        return {r["seed"]: r for r in grid_rows(cfg, store)}


def _specs(n: int) -> list[RunSpec]:
    return expand(BenchConfig(maps=("overtake",), planners=("rrt",), seeds=n))


# ----------------------------------------------------------------------------- retries


def test_retries_zero_records_the_first_failure_and_a_resume_keeps_it(
    tmp_path: FsPath, markers: FsPath
) -> None:
    """--retries 0: a raise and a worker death are recorded at once (one attempt each);
    a resumed bench (no --retry-errors) treats the error rows as finished runs."""
    cfg = _cfg(tmp_path / "b", 3, retries=0)
    run_bench(cfg, executor=flaky_executor)
    rows = _rows_by_seed(cfg)
    assert [(rows[s]["status"], rows[s]["attempts"]) for s in (0, 1, 2)] == [("error", 1)] * 3
    assert [rows[s]["success"] for s in (0, 1, 2)] == [False] * 3
    assert rows[1]["error"].startswith("RuntimeError: flaky")
    assert "worker process died (exit code 3)" in rows[2]["error"]
    again = run_bench(cfg, executor=quick_executor)
    assert (again.skipped, again.executed, again.errors) == (3, 0, 3)
    lines = (tmp_path / "b" / "runs.jsonl").read_text().splitlines()
    assert sorted(json.loads(x)["seed"] for x in lines) == [0, 1, 2]


def test_a_raising_run_gets_exactly_retries_extra_attempts(markers: FsPath) -> None:
    """retries=2: a run raising once passes on its second attempt; one raising always is
    reported after its third, with its error."""
    backend = LocalBackend(1, executor=flaky_executor, retries=2)
    outcomes = {o.spec.seed: o for o in backend.run(_specs(2))}
    assert (outcomes[1].row is not None, outcomes[1].attempts) == (True, 2)
    assert (outcomes[0].row, outcomes[0].attempts) == (None, 3)
    assert (outcomes[0].error or "").startswith("RuntimeError: always")


def test_the_run_timeout_counts_from_each_runs_hand_over(tmp_path: FsPath) -> None:
    """One worker doing runs of 0.4 s in a row is never cut by a 1.5 s run timeout (the
    clock restarts at each hand-over, not at the worker's start)."""
    backend = LocalBackend(1, executor=slow_executor, retries=0, run_timeout_s=1.5)
    outcomes = list(backend.run(_specs(5)))
    assert [o.error for o in outcomes] == [None] * 5
    assert sorted(o.spec.seed for o in outcomes) == list(range(5))


# ----------------------------------------------------------------------------- start-up deaths


def test_a_start_up_death_between_ready_workers_is_not_a_pattern(tmp_path: FsPath) -> None:
    """With one worker: a start-up death, a worker that ran (and crashed a run), another
    start-up death: not two deaths in a row, so the bench finishes every run, and the
    run's crash costs it one attempt."""
    d = tmp_path / "starts"
    d.mkdir()
    backend = LocalBackend(1, executor=FragileExecutor(str(d), (0, 2), crash_seed=0))
    outcomes = {o.spec.seed: o for o in backend.run(_specs(2))}
    assert sorted(outcomes) == [0, 1]
    assert all(o.row is not None for o in outcomes.values())
    assert (outcomes[0].attempts, outcomes[1].attempts) == (2, 1)


def test_workers_plus_one_start_up_deaths_in_a_row_stop_the_bench(tmp_path: FsPath) -> None:
    """Two workers: the third start-up death in a row raises WorkerStartupError (the
    workers that would start healthy later are never reached)."""
    d = tmp_path / "starts"
    d.mkdir()
    backend = LocalBackend(2, executor=FragileExecutor(str(d), tuple(range(6))))
    outcomes: list[Outcome] = []
    with pytest.raises(WorkerStartupError, match=r"bench: 3 worker processes in a row died"):
        outcomes.extend(backend.run(_specs(2)))
    assert outcomes == []


# ----------------------------------------------------------------------------- parallel_map


def test_parallel_map_returns_rows_in_item_order_with_a_repeated_item(markers: FsPath) -> None:
    """Item 0 fails once, so it finishes last; the rows still come in the items'
    order, one object standing twice gets both its rows, and progress counts 1..N."""
    again = [3]
    items = [[0], again, [2], again]
    calls: list[tuple[int, int]] = []
    rows = parallel_map(square, items, 1, progress=lambda i, n: calls.append((i, n)))
    assert rows == [{"x": x, "sq": x * x} for (x,) in items]
    assert calls == [(1, 4), (2, 4), (3, 4), (4, 4)]


def test_parallel_map_bad_input_is_the_callers_one_line(markers: FsPath) -> None:
    """An item's InputError comes back as an InputError with its own words only."""
    with pytest.raises(InputError, match=r"^scenario: unknown 'nowhere'$"):
        parallel_map(square, [[1], [-1]], 1)


# Both failed with AttributeError before session 41: the log line of a dead or timed-out
# run called task[1].describe(), which parallel_map's items need not have.


def test_parallel_map_retries_an_item_whose_worker_died(markers: FsPath) -> None:
    """An item that kills its worker once is retried (as documented) and its row returned."""
    assert parallel_map(square, [[5], [1]], 1) == [{"x": 5, "sq": 25}, {"x": 1, "sq": 1}]


def test_parallel_map_enforces_its_run_timeout(markers: FsPath) -> None:
    """A hanging item is killed at run_timeout_s (and on its retry), then reported."""
    with pytest.raises(RuntimeError, match="run timeout of 1 s"):
        parallel_map(square, [[-2]], 1, run_timeout_s=1.0)


# ----------------------------------------------------------------------------- run_bench files


def _stop(row: dict[str, Any]) -> None:
    raise KeyboardInterrupt


def test_an_interrupted_re_run_with_other_run_settings_keeps_the_summary(
    tmp_path: FsPath,
) -> None:
    """Retries, run timeout, plots, workers and the folder's spelling are how a grid runs,
    not which runs it has: an interrupted re-run keeps the summary it had."""
    out = tmp_path / "b"
    run_bench(_cfg(out, 2), executor=quick_executor)
    before = (out / "summary.md").read_text()
    rows = (out / "runs.jsonl").read_text().splitlines()
    (out / "runs.jsonl").write_text(rows[0] + "\n")
    other = BenchConfig(maps=("overtake",), planners=("rrt",), seeds=2, workers=2,
                        out=str(out) + "/", plots=True, retries=3, run_timeout_s=77.0)
    with pytest.raises(KeyboardInterrupt):
        run_bench(other, executor=quick_executor, on_row=_stop)
    assert (out / "summary.md").read_text() == before


def test_an_interrupted_bench_of_another_grid_leaves_no_old_figures(tmp_path: FsPath) -> None:
    """The old grid's figures go with its summary when another grid starts in the folder."""
    out = tmp_path / "b"
    run_bench(_cfg(out, 1), executor=quick_executor)
    for name in PLOT_FILES:
        (out / name).write_bytes(b"old figure")
    other = BenchConfig(maps=("narrow_gap",), planners=("rrt",), seeds=1, workers=1,
                        out=str(out), plots=False)
    with pytest.raises(KeyboardInterrupt):
        run_bench(other, executor=quick_executor, on_row=_stop)
    assert [n for n in PLOT_FILES if (out / n).exists()] == []


def test_the_config_file_counts_the_grid_and_the_resumed_runs(tmp_path: FsPath) -> None:
    """bench_config.json: the command, the grid's runs and seeds, and how many were stored."""
    out = tmp_path / "b"
    run_bench(_cfg(out, 2), executor=quick_executor)
    more = _cfg(out, 5)
    report = run_bench(more, executor=quick_executor, command="rrtdrive bench --seeds 5")
    meta = json.loads((out / "bench_config.json").read_text())
    assert meta["command"] == "rrtdrive bench --seeds 5"
    assert meta["runs"] == len(expand(more)) == 5 and meta["seeds"] == list(range(5))
    assert meta["already_done"] == 2 == report.skipped


# ----------------------------------------------------------------------------- the store


def test_a_long_partial_last_line_costs_only_itself(tmp_path: FsPath) -> None:
    """A torn line longer than the read-back chunk is cut, the complete rows before it kept."""
    with ResultStore(tmp_path) as s:
        for seed in range(3):
            s.append({"config_hash": "h", "seed": seed})
    with open(tmp_path / "runs.jsonl", "a") as fh:
        fh.write('{"config_hash": "h", "seed": 3, "note": "' + "x" * 10_000)
    with ResultStore(tmp_path) as s:
        assert s.done_keys() == {("h", 0), ("h", 1), ("h", 2)}
        s.append({"config_hash": "h", "seed": 3})
    lines = (tmp_path / "runs.jsonl").read_text().splitlines()
    assert [json.loads(x)["seed"] for x in lines] == [0, 1, 2, 3]


def test_an_empty_results_file_opens(tmp_path: FsPath) -> None:
    """A runs.jsonl created but never written (killed at once) is an empty store."""
    (tmp_path / "runs.jsonl").touch()
    with ResultStore(tmp_path) as s:
        assert s.done_keys() == set()
        s.append({"config_hash": "h", "seed": 0})
    assert len((tmp_path / "runs.jsonl").read_text().splitlines()) == 1


def test_rows_skip_a_line_still_being_written(tmp_path: FsPath) -> None:
    """A reader meets a last line without its newline (a write in progress): not a row yet,
    even when the bytes so far happen to parse."""
    with ResultStore(tmp_path) as s:
        s.append({"config_hash": "h", "seed": 0})
        with open(tmp_path / "runs.jsonl", "a") as fh:
            fh.write('{"config_hash": "h", "seed": 1}')
        assert [r["seed"] for r in s.rows()] == [0]
