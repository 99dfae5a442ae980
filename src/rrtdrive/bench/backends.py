"""Where runs execute: local worker processes (a Ray cluster: :mod:`.ray_backend`).

Both backends take run specs and yield :class:`Outcome` objects as runs finish,
in completion order; the caller (the single writer) stores them. A run whose
worker crashes (dies, raises, or exceeds the run timeout) is retried
``retries`` times and then reported as failed, so the bench records an error
row instead of stopping.

The local backend manages its own processes (``spawn`` start method, one task
at a time per worker over a pipe) rather than a ``concurrent.futures`` pool:
a dead worker is then attributed to exactly the run it held, and only that run
is retried. Workers exit when the main process goes away (their pipe closes),
so a killed bench leaves no process writing anywhere.

A worker says it is ready before it is given a run. One that dies (or hangs)
before that never held a run: it is replaced without costing any run an
attempt, and when workers keep dying at start-up (typically a script that runs
a bench without ``if __name__ == "__main__":``, which every spawned worker
re-executes) the bench stops with :class:`WorkerStartupError` instead of
writing error rows for runs that never started.
"""

from __future__ import annotations

import logging
import multiprocessing as mp
import os
import re
import signal
import sys
import threading
import time
import traceback
from collections import deque
from collections.abc import Callable, Generator, Iterable
from dataclasses import dataclass
from multiprocessing import resource_tracker
from multiprocessing.connection import Connection, wait
from typing import Any

from rrtdrive.bench.grid import RunSpec
from rrtdrive.bench.worker import execute_run
from rrtdrive.types import InputError, brief_repr

__all__ = [
    "parallel_map",
    "Outcome",
    "Executor",
    "LocalBackend",
    "WorkerStartupError",
    "default_workers",
]

logger = logging.getLogger(__name__)

#: A function from a run spec to its row; must be importable by name (spawn, Ray).
Executor = Callable[[RunSpec], dict[str, Any]]

#: Environment for worker processes: one BLAS/OpenMP thread each, so N workers use N cores.
_WORKER_ENV = {
    "OMP_NUM_THREADS": "1",
    "OPENBLAS_NUM_THREADS": "1",
    "MKL_NUM_THREADS": "1",
    "NUMEXPR_NUM_THREADS": "1",
}


#: A worker's first message: it imported everything and waits for runs.
_READY = "ready"

#: Why spawned workers die before they start, in the error's words.
_MAIN_GUARD_HINT = (
    "a script that starts a bench must do so under `if __name__ == \"__main__\":` "
    "(every worker process re-imports the script; see docs/bench.md)"
)


def run_timed_out(seconds: float) -> str:
    """A run's error past the run timeout, the same on every backend."""
    return f"run exceeded the run timeout of {seconds:g} s"


class WorkerStartupError(RuntimeError):
    """Local worker processes die (or hang) before they can take a run.

    Nothing ran, so no row was written for the runs still to do.
    """


@dataclass(frozen=True)
class Outcome:
    """A finished run: its row, or the error of its last attempt.

    Attributes
    ----------
    spec : RunSpec
        The run.
    row : dict or None
        The executor's row when an attempt succeeded.
    error : str or None
        Why the last attempt failed (when ``row`` is ``None``).
    attempts : int
        Attempts made, including the successful one.
    """

    spec: RunSpec
    row: dict[str, Any] | None
    error: str | None
    attempts: int


def default_workers() -> int:
    """One worker per usable core."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not on Linux
        return max(1, os.cpu_count() or 1)


def _label(item: Any) -> str:
    """A run's description for the log; :func:`parallel_map`'s items need not have one."""
    describe = getattr(item, "describe", None)
    return describe() if callable(describe) else brief_repr(item)


def _call(executor: Executor, spec: RunSpec) -> tuple[str, Any]:
    """Run ``executor(spec)``; never raise: ``("ok", row)`` or ``("error", message)``."""
    try:
        return ("ok", executor(spec))
    except Exception as exc:  # noqa: BLE001 - any failure of a run is data for its row
        tb = traceback.extract_tb(exc.__traceback__)
        where = f" at {tb[-1].filename}:{tb[-1].lineno}" if tb else ""
        return ("error", f"{type(exc).__name__}: {exc}{where}")


def _worker_main(conn: Connection, executor: Executor) -> None:
    """Body of a local worker process: receive specs, send results, until told to stop."""
    # Ctrl-C goes to the whole terminal process group: let the main process handle it.
    # Born with SIGINT blocked (LocalBackend._start): setting SIG_IGN drops one that came
    # while importing, and unblocked it stays ignored.
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    if hasattr(signal, "pthread_sigmask"):
        signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})
    try:
        conn.send(_READY)
    except (BrokenPipeError, OSError):
        os._exit(0)  # the main process is gone already
    while True:
        try:
            msg = conn.recv()
        except (EOFError, OSError):
            break  # the main process is gone
        if msg is None:
            break
        task_id, spec = msg
        result = _call(executor, spec)
        try:
            conn.send((task_id, result))
        except (BrokenPipeError, OSError):
            break
    sys.stdout.flush()
    sys.stderr.flush()
    # Skip interpreter teardown (nanobind's leak report, atexit handlers of the parent's modules).
    os._exit(0)


@dataclass
class _Slot:
    proc: Any
    conn: Connection
    task: tuple[int, RunSpec, int] | None = None  # (task id, spec, attempt number)
    started: float = 0.0  # of its run, or (until ready) of the process
    ready: bool = False  # said so: it may be given runs


class LocalBackend:
    """Runs on local worker processes.

    Parameters
    ----------
    workers : int
        Number of processes.
    executor : callable
        Module-level function ``RunSpec -> dict`` (default :func:`execute_run`).
    retries : int
        Extra attempts of a crashed run.
    run_timeout_s : float
        A run taking longer is killed with its worker and counts as a crashed attempt.
    startup_timeout_s : float
        A worker not ready after this long counts as dead at start-up.

    Raises
    ------
    WorkerStartupError
        From :meth:`run`, when more workers than ``workers`` die at start-up in a
        row (no worker became ready in between).
    """

    name = "local"

    def __init__(
        self,
        workers: int,
        executor: Executor = execute_run,
        retries: int = 1,
        run_timeout_s: float = 600.0,
        startup_timeout_s: float = 120.0,
    ) -> None:
        if workers < 1:
            raise InputError(f"workers: must be >= 1, got {workers}")
        self.workers = workers
        self.executor = executor
        self.retries = retries
        self.run_timeout_s = run_timeout_s
        self.startup_timeout_s = startup_timeout_s
        self._ctx = mp.get_context("spawn")

    def describe(self) -> str:
        """Human-readable backend description."""
        return f"{self.workers} local worker process{'es' if self.workers != 1 else ''}"

    def _start(self) -> _Slot:
        parent, child = self._ctx.Pipe(duplex=True)
        saved = {k: os.environ.get(k) for k in _WORKER_ENV}
        os.environ.update(_WORKER_ENV)
        # The worker is born with Ctrl-C blocked (a thread's signal mask survives fork and
        # exec; _worker_main then ignores and unblocks it): the terminal sends SIGINT to
        # the whole process group, and a worker still importing printed a traceback. The
        # main process handles Ctrl-C; its workers end when their pipe closes. Ignoring it
        # in the main process while the worker started instead discarded a Ctrl-C in that
        # window (a disposition is the whole process's) and the bench ran on.
        mask = hasattr(signal, "pthread_sigmask")
        main_thread = threading.current_thread() is threading.main_thread()
        handler = None
        if mask:
            # Started first: starting it unblocks SIGINT and SIGTERM, whatever was blocked.
            resource_tracker.ensure_running()
            signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
        elif main_thread:  # no signal masks: born ignoring it (stays ignored across exec)
            handler = signal.signal(signal.SIGINT, signal.SIG_IGN)
        try:
            proc = self._ctx.Process(
                target=_worker_main, args=(child, self.executor), daemon=True,
                name="rrtdrive-bench-worker",
            )
            proc.start()
        finally:
            if mask:
                signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})
            elif main_thread:
                signal.signal(signal.SIGINT, handler)
            for k, v in saved.items():
                if v is None:
                    os.environ.pop(k, None)
                else:
                    os.environ[k] = v
        child.close()
        return _Slot(proc, parent, started=time.monotonic())

    @staticmethod
    def _stop(slot: _Slot, kill: bool = False) -> None:
        try:
            if kill:
                slot.proc.kill()
            else:
                slot.conn.send(None)
        except (OSError, ValueError):
            pass
        slot.conn.close()

    def run(self, specs: Iterable[RunSpec]) -> Generator[Outcome, None, None]:
        """Execute ``specs``; yield one :class:`Outcome` per spec as runs finish."""
        queue: deque[tuple[int, RunSpec, int]] = deque(
            (i, s, 1) for i, s in enumerate(specs)
        )
        if not queue:
            return
        slots = [self._start() for _ in range(min(self.workers, len(queue)))]
        try:
            yield from self._loop(queue, slots)
        finally:
            for slot in slots:
                self._stop(slot, kill=slot.task is not None)
            deadline = time.monotonic() + 5.0
            for slot in slots:
                slot.proc.join(max(0.0, deadline - time.monotonic()))
                if slot.proc.is_alive():
                    slot.proc.kill()
                    slot.proc.join(1.0)

    def _loop(
        self, queue: deque[tuple[int, RunSpec, int]], slots: list[_Slot]
    ) -> Generator[Outcome, None, None]:
        busy = 0
        startup_deaths = 0  # in a row, since a worker last became ready
        while queue or busy:
            for slot in slots:
                busy += self._assign(slot, queue)
            waitables: list[Any] = []
            for slot in slots:
                waitables.append(slot.conn)
                waitables.append(slot.proc.sentinel)
            now = time.monotonic()
            timeouts = [
                slot.started + self.run_timeout_s - now for slot in slots if slot.task is not None
            ] + [slot.started + self.startup_timeout_s - now for slot in slots if not slot.ready]
            # An hour at most per wait (the loop re-checks the deadlines): the OS wait
            # overflows on a timeout past ~1e9 s, which a generous --run-timeout can be.
            timeout = min(max(0.0, min(timeouts)), 3600.0) if timeouts else None
            ready = set(wait(waitables, timeout=timeout))
            retired: list[int] = []
            for k, slot in enumerate(slots):
                failure: str | None = None
                if slot.conn in ready:
                    try:
                        msg = slot.conn.recv()
                    except (EOFError, OSError):
                        failure = "worker process died"
                    else:
                        if msg == _READY:
                            slot.ready, startup_deaths = True, 0
                            busy += self._assign(slot, queue)
                            continue
                        task_id, (status, payload) = msg
                        task = slot.task
                        assert task is not None and task[0] == task_id
                        slot.task = None
                        busy -= 1
                        # Hand the worker its next run before the caller stores this one,
                        # so storing (JSON, fsync) never leaves a worker idle.
                        busy += self._assign(slot, queue)
                        if status == "ok":
                            yield Outcome(task[1], payload, None, task[2])
                        else:
                            yield from self._failed(queue, task, payload)
                        continue
                elif slot.proc.sentinel in ready:
                    failure = "worker process died"
                elif slot.task is not None and (
                    time.monotonic() - slot.started > self.run_timeout_s
                ):
                    failure = run_timed_out(self.run_timeout_s)
                elif not slot.ready and time.monotonic() - slot.started > self.startup_timeout_s:
                    failure = f"worker process not ready after {self.startup_timeout_s:g} s"
                if failure is None:
                    continue
                if failure == "worker process died":
                    slot.proc.join(2.0)  # its pipe can close just before it can be reaped
                    if slot.proc.exitcode is not None:
                        failure += f" (exit code {slot.proc.exitcode})"
                if slot.proc.is_alive():
                    slot.proc.kill()
                    slot.proc.join(5.0)
                slot.conn.close()
                task = slot.task
                if not slot.ready:
                    # It never held a run: no attempt is charged, but a pattern is an error.
                    startup_deaths += 1
                    logger.warning("bench worker died at start-up: %s", failure)
                    if startup_deaths > self.workers:
                        raise WorkerStartupError(
                            f"bench: {startup_deaths} worker processes in a row died at "
                            f"start-up before running anything ({failure}); "
                            f"{_MAIN_GUARD_HINT}"
                        )
                if task is None and not queue:
                    retired.append(k)  # an idle worker died and nothing waits: no replacement
                    continue
                slots[k] = self._start()
                if task is not None:
                    busy -= 1
                    logger.warning("%s: %s", _label(task[1]), failure)
                    yield from self._failed(queue, task, failure)
            for k in reversed(retired):
                del slots[k]
            if not slots and (queue or busy):  # pragma: no cover - every worker died idle
                slots.append(self._start())

    @staticmethod
    def _assign(slot: _Slot, queue: deque[tuple[int, RunSpec, int]]) -> int:
        """Send the next queued run to an idle worker; return 1 if one was sent."""
        if slot.task is not None or not slot.ready or not queue:
            return 0
        task = queue.popleft()
        try:
            slot.conn.send((task[0], task[1]))
        except (BrokenPipeError, OSError):
            queue.appendleft(task)
            return 0  # its sentinel reports the death
        slot.task, slot.started = task, time.monotonic()
        return 1

    def _failed(
        self, queue: deque[tuple[int, RunSpec, int]], task: tuple[int, RunSpec, int], error: str
    ) -> Generator[Outcome, None, None]:
        task_id, spec, attempt = task
        if attempt <= self.retries:
            queue.append((task_id, spec, attempt + 1))
            return
        yield Outcome(spec, None, error, attempt)


def episode_progress(every: int = 10) -> Callable[[int, int], None]:
    """A :func:`parallel_map` progress callback: ``done/total episodes, N s`` on stderr.

    Prints every ``every``-th finished item and the last, on one line, timed from
    the moment this is called.
    """
    t0 = time.perf_counter()

    def progress(i: int, total: int) -> None:
        if i % every == 0 or i == total:
            print(f"\r{i}/{total} episodes, {time.perf_counter() - t0:.0f} s",
                  end="", file=sys.stderr, flush=True)

    return progress


def parallel_map(
    fn: Callable[[Any], dict[str, Any]],
    items: Iterable[Any],
    workers: int,
    progress: Callable[[int, int], None] | None = None,
    run_timeout_s: float = 3600.0,
) -> list[dict[str, Any]]:
    """``[fn(item) for item in items]`` on the bench's local worker processes, in order.

    For experiment scripts: the same spawned, single-threaded workers, crash handling
    and start-up checks as ``rrtdrive bench`` (:class:`LocalBackend`), without a
    result store. ``fn`` must be a module-level function and ``items`` picklable.

    Parameters
    ----------
    fn : callable
        ``item -> row``.
    items : iterable
        The work.
    workers : int
        Worker processes.
    progress : callable, optional
        Called with ``(done, total)`` after every finished item.
    run_timeout_s : float
        An item taking longer is killed and retried once, then reported.

    Returns
    -------
    list of dict
        The rows, in the order of ``items``.

    Raises
    ------
    InputError
        When an item's work raised one (bad input: an unknown scenario, ...).
    RuntimeError
        When an item failed on every attempt otherwise (its error in the message).
    """
    work = list(items)
    backend = LocalBackend(max(1, workers), executor=fn, run_timeout_s=run_timeout_s)
    # The backend hands back the very item objects; one object may stand twice in ``items``.
    slots: dict[int, list[int]] = {}
    for i, item in enumerate(work):
        slots.setdefault(id(item), []).append(i)
    rows: list[dict[str, Any] | None] = [None] * len(work)
    for done, outcome in enumerate(backend.run(work), 1):
        if outcome.row is None:
            error = outcome.error or ""
            if error.startswith("InputError: "):
                # Bad input is the caller's: one line naming the field, as anywhere else.
                text = error.removeprefix("InputError: ").splitlines()[0]
                raise InputError(re.sub(r" at \S+:\d+$", "", text))  # not _call's "at file:line"
            raise RuntimeError(f"{outcome.spec!r} failed: {error}")
        rows[slots[id(outcome.spec)].pop(0)] = outcome.row
        if progress is not None:
            progress(done, len(work))
    return [row for row in rows if row is not None]
