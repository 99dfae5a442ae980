"""Run a bench: expand the grid, skip finished runs, execute the rest, store, summarise."""

from __future__ import annotations

import contextlib
import json
import logging
import platform
import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path as FsPath
from typing import Any, TextIO

from rrtdrive.bench.backends import Executor, LocalBackend, default_workers
from rrtdrive.bench.grid import BenchConfig, RunSpec, expand
from rrtdrive.bench.ray_backend import RayBackend
from rrtdrive.bench.store import ResultStore, row_key
from rrtdrive.bench.summary import remove_plots, summarise_rows, write_plots, write_summary
from rrtdrive.bench.worker import error_row, execute_run
from rrtdrive.types import InputWarning

__all__ = ["BenchReport", "Progress", "run_bench", "grid_rows"]

logger = logging.getLogger(__name__)


class Progress:
    """A one-line progress report with rate and ETA on a stream (stderr by default).

    On a terminal the line is redrawn in place; otherwise a line is printed at
    most every ``interval_s`` seconds and at the end.

    Parameters
    ----------
    total : int
        Runs to do in this session.
    stream : file-like, optional
        Where to write (default ``sys.stderr``); ``None`` disables output.
    interval_s : float
        Smallest time between lines when the stream is not a terminal.
    """

    def __init__(self, total: int, stream: TextIO | None = None, interval_s: float = 10.0) -> None:
        self.total = total
        self.done = 0
        self.errors = 0
        self.stream = stream
        self.tty = bool(stream is not None and getattr(stream, "isatty", lambda: False)())
        self.interval_s = interval_s
        self.t0 = time.perf_counter()
        self._last = -1e9

    def line(self) -> str:
        """The current progress line."""
        elapsed = time.perf_counter() - self.t0
        rate = self.done / elapsed if elapsed > 0 else 0.0
        left = self.total - self.done
        eta = _clock(left / rate) if rate > 0 else "?"
        pct = 100.0 * self.done / self.total if self.total else 100.0
        err = f", {self.errors} errors" if self.errors else ""
        return (
            f"bench {self.done}/{self.total} ({pct:.0f}%) {rate:.2f} runs/s "
            f"elapsed {_clock(elapsed)} ETA {eta}{err}"
        )

    def update(self, n: int = 1, error: bool = False) -> None:
        """Count ``n`` finished runs and redraw."""
        self.done += n
        self.errors += int(error)
        if self.stream is None:
            return
        now = time.perf_counter()
        if self.tty:
            self.stream.write("\r" + self.line() + "\x1b[K")
            self.stream.flush()
        elif now - self._last >= self.interval_s or self.done == self.total:
            self.stream.write(self.line() + "\n")
            self.stream.flush()
            self._last = now

    def close(self) -> None:
        """End the line."""
        if self.stream is not None and self.tty:
            self.stream.write("\n")
            self.stream.flush()


def _clock(seconds: float) -> str:
    s = int(round(seconds))
    h, rem = divmod(s, 3600)
    m, s = divmod(rem, 60)
    return f"{h}:{m:02d}:{s:02d}" if h else f"{m}:{s:02d}"


@dataclass(frozen=True)
class BenchReport:
    """What a bench did.

    Attributes
    ----------
    total : int
        Runs in the grid.
    skipped : int
        Runs already stored before this session (resumed).
    executed : int
        Runs finished in this session (rows written).
    errors : int
        Error rows among the grid's rows.
    run_wall_s : float
        Wall time of the execution phase (workers start to last row).
    backend : str
        Where the runs executed.
    files : tuple of str
        Files written (results, config, summary, plots).
    """

    total: int
    skipped: int
    executed: int
    errors: int
    run_wall_s: float
    backend: str
    files: tuple[str, ...]

    @property
    def throughput(self) -> float:
        """Runs per second in this session's execution phase."""
        return self.executed / self.run_wall_s if self.run_wall_s > 0 else float("nan")


def grid_rows(cfg: BenchConfig, store: ResultStore) -> list[dict[str, Any]]:
    """The stored rows of ``cfg``'s grid, one per key (the first stored), in grid order.

    A run is found by its map's content, so a row stored under another name of the
    same map (a copied or renamed file) carries this grid's name here: under its old
    one it made a summary row of its own, and the cell's counts were split.
    """
    specs = expand(cfg)
    wanted = {s.key: i for i, s in enumerate(specs)}
    found: dict[tuple[str, int], dict[str, Any]] = {}
    for row in store.rows():
        key = row_key(row)
        if key in wanted and key not in found:
            spec = specs[wanted[key]]
            field = "map" if spec.kind == "plan" else "scenario"
            found[key] = row if row.get(field) == spec.target else {**row, field: spec.target}
    return [found[k] for k in sorted(found, key=wanted.__getitem__)]


#: Settings of how a grid is run, not of which runs it has: a re-run of the same grid
#: with other workers (or the folder spelt otherwise) is the same grid, and an interrupt
#: must not cost it the summary and figures it already had.
_HOW_RUN = frozenset({"workers", "out", "ray", "plots", "retries", "run_timeout_s"})


def _grid_of(config: object) -> object:
    """``config`` without :data:`_HOW_RUN` (``None`` and non-mappings as they are)."""
    if not isinstance(config, dict):
        return config
    return {k: v for k, v in config.items() if k not in _HOW_RUN}


def _previous_config(out: FsPath) -> object:
    """The ``config`` of the bench last started in ``out`` (``None``: none, or unreadable)."""
    try:
        return json.loads((out / "bench_config.json").read_text(encoding="utf-8"))["config"]
    except (OSError, ValueError, KeyError, TypeError):
        return None


#: Local worker processes per usable core at the most: bench runs are CPU-bound, so more
#: only contend for the cores (stretching each run's wall-clock timeout) and memory.
WORKERS_PER_CORE = 4


def local_workers(requested: int | None, runs: int) -> tuple[int, str | None]:
    """How many local worker processes to start for ``runs`` runs, and why fewer if so.

    Parameters
    ----------
    requested : int or None
        ``--workers`` (None: one per usable core).
    runs : int
        Runs still to do.

    Returns
    -------
    workers : int
        At most ``runs`` (at least 1) and at most :data:`WORKERS_PER_CORE` per core.
    note : str or None
        Said on the progress line when ``requested`` was cut to the per-core cap.
    """
    cores = default_workers()
    workers = min(requested or cores, max(1, runs))
    cap = WORKERS_PER_CORE * cores
    if workers <= cap:
        return workers, None
    return cap, (
        f"--workers {requested} capped at {cap} ({WORKERS_PER_CORE} per core here: more "
        "only contend for the cores and memory)"
    )


def run_bench(
    cfg: BenchConfig,
    *,
    executor: Executor = execute_run,
    progress: TextIO | None = None,
    retry_errors: bool = False,
    command: str | None = None,
    on_row: Callable[[dict[str, Any]], None] | None = None,
) -> BenchReport:
    """Run every missing run of ``cfg``'s grid, then write the summary and plots.

    Rows go to ``cfg.out/runs.jsonl`` as runs finish (flushed and fsynced), so
    an interrupted bench resumes where it stopped: runs whose ``(config_hash,
    seed)`` is stored are not run again.

    Parameters
    ----------
    cfg : BenchConfig
        The bench.
    executor : callable
        Module-level ``RunSpec -> row`` function (tests inject faults through it).
    progress : file-like, optional
        Stream for the progress line (``None``: silent).
    retry_errors : bool
        Drop the grid's stored error rows first, so those runs are tried again.
    command : str, optional
        The command line, recorded in ``bench_config.json``.
    on_row : callable, optional
        Called with each stored row (after it is on disk).

    Returns
    -------
    BenchReport

    Examples
    --------
    >>> import tempfile
    >>> cfg = BenchConfig(maps=("overtake",), planners=("rrt-connect",), seeds=2, workers=1,
    ...                   out=tempfile.mkdtemp(), plots=False)
    >>> run_bench(cfg).total
    2
    """
    from rrtdrive.maps import write_text_atomic

    specs = expand(cfg)
    out = FsPath(cfg.out)
    files: list[str] = []
    # Connect first: an address Ray cannot reach leaves no output folder behind.
    ray_backend = (
        RayBackend(cfg.ray, executor=executor, retries=cfg.retries, max_in_flight=cfg.workers,
                   run_timeout_s=cfg.run_timeout_s)
        if cfg.ray is not None
        else None
    )
    try:
        with ResultStore(out) as store:
            if retry_errors:
                keys = {row_key(r) for r in grid_rows(cfg, store) if r.get("status") == "error"}
                dropped = store.drop(k for k in keys if k is not None)
                if dropped:
                    logger.info("dropped %d error rows to run them again", dropped)
            done = store.done_keys()
            todo: list[RunSpec] = [s for s in specs if s.key not in done]
            skipped = len(specs) - len(todo)
            meta = {
                "command": command,
                "started_at": datetime.now(UTC).isoformat(timespec="seconds"),
                "config": cfg.to_json(),
                "seeds": list(range(cfg.seeds)),
                "runs": len(specs),
                "already_done": skipped,
                "python": platform.python_version(),
                "machine": f"{platform.system()} {platform.machine()}",
            }
            if _grid_of(_previous_config(out)) not in (
                None, _grid_of(json.loads(json.dumps(meta["config"])))
            ):
                # Another grid's summary and figures: gone until this one's are written, or an
                # interrupted bench left them beside the new bench_config.json.
                for name in ("summary.md", "summary.csv"):
                    (out / name).unlink(missing_ok=True)
                remove_plots(out)
            write_text_atomic(out / "bench_config.json", json.dumps(meta, indent=1) + "\n")
            backend: LocalBackend | RayBackend
            capped: str | None = None
            if ray_backend is not None:
                backend = ray_backend
            else:
                workers, capped = local_workers(cfg.workers, len(todo))
                backend = LocalBackend(
                    workers, executor=executor, retries=cfg.retries,
                    run_timeout_s=cfg.run_timeout_s,
                )
            if progress is not None:
                where = f"{len(todo)} to run on {backend.describe()}" if todo else "nothing to run"
                where += f"; {capped}" if capped and todo else ""
                progress.write(
                    f"bench: {len(specs)} runs in the grid, {skipped} already in "
                    f"{store.path}, {where}\n"
                )
                progress.flush()
            bar = Progress(len(todo), progress)
            executed = 0
            t0 = time.perf_counter()
            try:
                # closing(): an interrupt stops the workers at once, not at garbage collection.
                with contextlib.closing(backend.run(todo)) as outcomes:
                    for outcome in outcomes:
                        if outcome.row is not None:
                            row = dict(outcome.row)
                            row["attempts"] = outcome.attempts
                        else:
                            error = outcome.error or "unknown error"
                            row = error_row(outcome.spec, error, outcome.attempts)
                        store.append(row)
                        for text in row.get("warnings", ()):  # the worker's, said here once
                            warnings.warn(text, InputWarning, stacklevel=1)
                        executed += 1
                        bar.update(error=outcome.row is None)
                        if on_row is not None:
                            on_row(row)
                run_wall = time.perf_counter() - t0
            finally:
                bar.close()
            rows = grid_rows(cfg, store)
            files.append(str(store.path))
            # Under the folder's lock: a bench that took the folder over once this one's
            # rows were in found this one's plots written over its own (an audit).
            files += _write_summary_files(cfg, rows, out)
    finally:
        if ray_backend is not None:
            ray_backend.close()
    errors = sum(1 for r in rows if r.get("status") == "error")
    return BenchReport(
        total=len(specs), skipped=skipped, executed=executed, errors=errors,
        run_wall_s=run_wall, backend=backend.describe(), files=tuple(files),
    )


def _write_summary_files(cfg: BenchConfig, rows: list[dict[str, Any]], out: FsPath) -> list[str]:
    """Write ``summary.md``, ``summary.csv`` and the plots of ``rows``; the files named."""
    files = [str(out / "bench_config.json")]
    groups = summarise_rows(rows)
    # How it was run: a forward and a reverse grid's tables looked alike.
    # Without --reverse, the scenarios that reverse anyway are named (u-turn's rows
    # changed gear under a title that did not say so).
    anyway = sorted({str(r["scenario"]) for r in rows if r.get("reverse") and r.get("scenario")})
    how = "".join(
        text for text, on in ((", gear changes allowed", cfg.reverse),
                              (f", gear changes in {', '.join(anyway)}",
                               not cfg.reverse and bool(anyway)),
                              (", deterministic", cfg.deterministic)) if on
    )
    title = f"Bench summary ({len(rows)} runs, seeds 0–{cfg.seeds - 1}{how})"
    files += [str(p) for p in write_summary(groups, out, title)]
    # A figure not written now (no data for it, or --no-plots) would stay beside the new
    # summary: removed after the new ones are written, each over its old file, so an
    # interrupt while plotting leaves the last complete set (it left some removed).
    plots = write_plots(rows, out) if cfg.plots else []
    remove_plots(out, keep=plots)
    files += [str(p) for p in plots]
    return files
