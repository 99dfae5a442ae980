"""The lock a checker's queries hold: its prepared shapely geometry is not thread-safe.

GEOS builds a prepared geometry's indexes lazily and keeps state while it tests
(libgeos/geos#825): two threads testing against one checker's obstacle union at
once crashed the interpreter (SIGSEGV). Planners hold the checker's lock for a whole
query (:func:`rrtdrive.planning.result.run_query`); code that calls a shared
checker's methods from several threads holds it too.
"""

from __future__ import annotations

import threading
from contextlib import AbstractContextManager, nullcontext
from typing import Any

__all__ = ["QueryLock", "query_lock"]


class QueryLock:
    """A re-entrant lock that survives pickling and copying (as a new, unheld lock).

    A checker is pickled whole with its problem (to worker processes); a lock of
    :mod:`threading` cannot be.

    Examples
    --------
    >>> import pickle
    >>> lock = QueryLock()
    >>> with lock, lock:  # re-entrant: a query inside a query in one thread
    ...     copy = pickle.loads(pickle.dumps(lock))
    >>> with copy:
    ...     pass
    """

    def __init__(self) -> None:
        self._lock = threading.RLock()

    def __enter__(self) -> bool:
        return self._lock.__enter__()

    def __exit__(self, *exc: object) -> None:
        self._lock.__exit__(*exc)

    def __getstate__(self) -> dict[str, Any]:
        return {}

    def __setstate__(self, state: dict[str, Any]) -> None:
        self._lock = threading.RLock()

    def __repr__(self) -> str:
        return "QueryLock()"


def query_lock(checker: object) -> AbstractContextManager[object]:
    """The lock a query on ``checker`` holds (a wrapper's: its static checker's).

    A checker without one (a user's own :class:`~rrtdrive.checking.Checker`) gets none.
    """
    lock = getattr(checker, "lock", None)
    if lock is None:
        lock = getattr(getattr(checker, "static", None), "lock", None)
    return lock if lock is not None else nullcontext()
