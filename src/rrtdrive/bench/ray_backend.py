"""The Ray backend of ``rrtdrive bench``: runs as Ray tasks, on a local Ray or a cluster.

It yields :class:`~rrtdrive.bench.backends.Outcome` objects as the local backend does,
with the same retries and the same run timeout. Two things differ because Ray owns the
processes: a ``HOST:PORT`` address is tried with a plain TCP connection first (Ray
itself retries an unreachable head for minutes), and the run timeout is an alarm in
the task's own process, counted from the moment the run starts there.
"""

from __future__ import annotations

import os
import signal
import socket
import threading
from collections import deque
from collections.abc import Generator, Iterable
from types import FrameType
from typing import Any
from urllib.parse import urlsplit

from rrtdrive.bench.backends import Executor, Outcome, _call, run_timed_out
from rrtdrive.bench.grid import RunSpec
from rrtdrive.bench.worker import execute_run
from rrtdrive.types import InputError
from rrtdrive.values import one_line

__all__ = ["RayBackend", "head_endpoint"]

#: Seconds a TCP connection to a ``--ray HOST:PORT`` may take before the head counts as
#: unreachable.
CONNECT_TIMEOUT_S = 5.0


def head_endpoint(address: str) -> tuple[str, int] | None:
    """The ``(host, port)`` a Ray address names; ``None`` when it names none.

    ``"auto"``, ``""`` and addresses without a port are left to Ray (it answers those
    at once).

    Examples
    --------
    >>> head_endpoint("ray://10.0.0.5:10001"), head_endpoint("127.0.0.1:6379")
    (('10.0.0.5', 10001), ('127.0.0.1', 6379))
    >>> head_endpoint("auto") is None and head_endpoint("bogus://x") is None
    True
    """
    try:
        parts = urlsplit(address if "://" in address else f"//{address}")
        port = parts.port
    except ValueError:  # a port that is not a number: Ray's own message says so
        return None
    if not parts.hostname or port is None:
        return None
    return parts.hostname, port


def check_reachable(
    address: str, timeout_s: float = CONNECT_TIMEOUT_S, source: str = ""
) -> None:
    """Raise :class:`InputError` naming ``--ray`` when ``address``'s head does not answer.

    ``source`` follows the address in the message (where it came from).

    Raises
    ------
    InputError
        The host refuses, is unknown, or does not answer within ``timeout_s``.
    """
    endpoint = head_endpoint(address)
    if endpoint is None:
        return
    try:
        with socket.create_connection(endpoint, timeout=timeout_s):
            pass
    except OSError as exc:
        why = (f"no answer in {timeout_s:g} s" if isinstance(exc, TimeoutError)
               else exc.strerror or str(exc))
        raise InputError(
            f"ray: cannot connect to {address}{source}: {why}; is a Ray head running there "
            "(`ray start --head` starts one)?"
        ) from None


class _RunTimedOut(BaseException):
    """The alarm's signal inside a run.

    A BaseException, so that the run's own ``except Exception`` (and :func:`_call`'s)
    cannot swallow it.
    """


def _ray_call(
    executor: Executor, spec: RunSpec, timeout_s: float | None = None
) -> tuple[str, Any]:
    """The Ray task: the local workers' never-raising wrapper, with the run timeout.

    The alarm needs the process's main thread, where Ray runs a task; elsewhere the
    run goes without one.
    """
    if timeout_s is None or threading.current_thread() is not threading.main_thread():
        return _call(executor, spec)

    def expire(signum: int, frame: FrameType | None) -> None:
        raise _RunTimedOut

    previous = signal.signal(signal.SIGALRM, expire)
    signal.setitimer(signal.ITIMER_REAL, timeout_s)
    try:
        return _call(executor, spec)
    except _RunTimedOut:
        return ("error", run_timed_out(timeout_s))
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


class RayBackend:
    """Runs as Ray tasks, on a local Ray or a cluster.

    Parameters
    ----------
    address : str
        ``""`` for ``ray.init()`` (a new local Ray, or ``RAY_ADDRESS``), else the
        address for ``ray.init(address=...)`` (``"auto"``, ``"ray://head:10001"``).
        When Ray is already initialised in this process, that session is used.
    executor : callable
        Module-level function ``RunSpec -> dict``; it must be importable on the
        cluster's workers (install rrtdrive there).
    retries : int
        Extra attempts of a crashed run (Ray's ``max_retries`` for dead workers,
        and a resubmission for a run that raised).
    max_in_flight : int, optional
        Largest number of submitted, unfinished tasks (default twice the
        cluster's CPUs).
    run_timeout_s : float, optional
        A run still going this many seconds after it started on its Ray worker fails
        (and is resubmitted while ``retries`` last), as on the local backend;
        ``None`` for no limit.
    """

    name = "ray"

    def __init__(
        self,
        address: str = "",
        executor: Executor = execute_run,
        retries: int = 1,
        max_in_flight: int | None = None,
        run_timeout_s: float | None = None,
    ) -> None:
        try:
            import ray
        except ImportError:
            raise InputError(
                "ray: the Ray backend needs Ray; install it with pip install 'rrtdrive[ray]'"
            ) from None
        self._ray = ray
        self._owns_session = False
        if not ray.is_initialized():
            # "" means RAY_ADDRESS when set: an unreachable one hangs as long.
            if address:
                check_reachable(address)
            elif os.environ.get("RAY_ADDRESS"):
                check_reachable(os.environ["RAY_ADDRESS"], source=" (from RAY_ADDRESS)")
            # ray.init installs its own SIGTERM handler (sys.exit(15) and a dump): the
            # CLI's (exit 143, "rrtdrive: terminated", as a local bench) is put back.
            sigterm = signal.getsignal(signal.SIGTERM)
            try:
                if address:
                    ray.init(address=address, log_to_driver=False)
                else:
                    ray.init(log_to_driver=False)
            except (ConnectionError, ValueError, RuntimeError) as exc:
                # Ray's messages run over several lines: the error is one.
                raise InputError(
                    f"ray: cannot connect to {address or 'Ray'}: {one_line(exc)}"
                ) from None
            finally:
                if sigterm is not None and threading.current_thread() is threading.main_thread():
                    signal.signal(signal.SIGTERM, sigterm)
            self._owns_session = True
        self.executor = executor
        self.retries = retries
        self.run_timeout_s = run_timeout_s
        cpus = int(ray.cluster_resources().get("CPU", 1))
        self.max_in_flight = max_in_flight or max(1, 2 * cpus)
        self._cpus = cpus
        self._remote = ray.remote(num_cpus=1, max_retries=retries)(_ray_call)

    def describe(self) -> str:
        """Human-readable backend description."""
        return f"Ray ({self._cpus} CPUs, up to {self.max_in_flight} runs in flight)"

    def close(self) -> None:
        """Shut Ray down if this backend started it."""
        if self._owns_session:
            self._ray.shutdown()
            self._owns_session = False

    def run(self, specs: Iterable[RunSpec]) -> Generator[Outcome, None, None]:
        """Execute ``specs``; yield one :class:`Outcome` per spec as runs finish."""
        ray = self._ray
        queue: deque[tuple[RunSpec, int]] = deque((s, 1) for s in specs)
        in_flight: dict[Any, tuple[RunSpec, int]] = {}
        try:
            while queue or in_flight:
                while queue and len(in_flight) < self.max_in_flight:
                    spec, attempt = queue.popleft()
                    ref = self._remote.remote(self.executor, spec, self.run_timeout_s)
                    in_flight[ref] = (spec, attempt)
                done, _ = ray.wait(list(in_flight), num_returns=1)
                for ref in done:
                    spec, attempt = in_flight.pop(ref)
                    try:
                        status, payload = ray.get(ref)
                    except Exception as exc:  # noqa: BLE001 - worker died after Ray's retries
                        yield Outcome(
                            spec, None, f"{type(exc).__name__}: {exc}".splitlines()[0],
                            attempt + self.retries,
                        )
                        continue
                    if status == "ok":
                        yield Outcome(spec, payload, None, attempt)
                    elif attempt <= self.retries:
                        queue.append((spec, attempt + 1))
                    else:
                        yield Outcome(spec, None, payload, attempt)
        finally:
            for ref in in_flight:
                try:
                    ray.cancel(ref, force=True)
                except Exception:  # noqa: BLE001,S110 - best effort on the way out
                    pass


