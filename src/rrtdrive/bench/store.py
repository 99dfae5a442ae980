"""The append-only result store: one JSON line per finished run, flushed and fsynced.

Only the bench's main process writes (workers return their rows to it), each
line in one ``write`` on an ``O_APPEND`` descriptor followed by ``fsync``. A
bench killed at any moment leaves at most one partial last line; opening the
store cuts it off, so every line in the file is a complete run. Runs are keyed
by ``(config_hash, seed)``; a re-run skips every key already present.

An advisory lock (``DIR/.lock``, ``fcntl.flock``) keeps two benches from
writing into one folder at once; the kernel drops it when its process dies,
even by ``SIGKILL``.
"""

from __future__ import annotations

import json
import logging
import os
from collections.abc import Iterable, Iterator, Mapping
from pathlib import Path as FsPath
from typing import Any

from rrtdrive.json_safe import json_safe
from rrtdrive.types import InputError

__all__ = ["ResultStore", "RUNS_FILE", "row_key", "json_safe"]

logger = logging.getLogger(__name__)

#: Name of the results file inside the output folder.
RUNS_FILE = "runs.jsonl"


def row_key(row: Mapping[str, Any]) -> tuple[str, int] | None:
    """The ``(config_hash, seed)`` of a row, or ``None`` for a row without them."""
    h, seed = row.get("config_hash"), row.get("seed")
    if isinstance(h, str) and isinstance(seed, int) and not isinstance(seed, bool):
        return (h, seed)
    return None


def _fsync_dir(path: FsPath) -> None:
    try:
        fd = os.open(path, os.O_RDONLY)
    except OSError:  # pragma: no cover - platforms without directory descriptors
        return
    try:
        os.fsync(fd)
    except OSError:  # pragma: no cover
        pass
    finally:
        os.close(fd)


class ResultStore:
    """The JSONL results of a bench folder.

    Parameters
    ----------
    out : str or path-like
        The output folder (created when missing).
    lock : bool
        Take the folder's advisory lock (the writer does; readers need not).

    Examples
    --------
    >>> import tempfile
    >>> with ResultStore(tempfile.mkdtemp()) as store:
    ...     store.append({"config_hash": "abc", "seed": 0, "success": True})
    ...     sorted(store.done_keys())
    [('abc', 0)]
    """

    def __init__(self, out: str | os.PathLike[str], lock: bool = True) -> None:
        self.dir = FsPath(out)
        if self.dir.exists() and not self.dir.is_dir():
            raise InputError(f"out: {str(self.dir)!r} exists and is not a folder")
        try:
            self.dir.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise InputError(f"out: cannot create {str(self.dir)!r}: {exc.strerror}") from None
        self.path = self.dir / RUNS_FILE
        self._lock_fd: int | None = None
        self._fd: int | None = None  # until opened below
        try:
            if lock:
                self._acquire_lock()
            created = not self.path.exists()
            self._repair_tail()
            self._fd = os.open(self.path, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o666)
        except OSError as exc:
            # A read-only folder, or runs.jsonl a folder: one line, not a traceback.
            self.close()
            raise InputError(
                f"out: cannot write into {str(self.dir)!r}: "
                f"{exc.strerror or exc} ({exc.filename or self.path})"
            ) from None
        if created:
            _fsync_dir(self.dir)
        self._keys: set[tuple[str, int]] = set()
        for row in self.rows():
            key = row_key(row)
            if key is not None:
                self._keys.add(key)

    # -- lifecycle ---------------------------------------------------------------------------

    def _acquire_lock(self) -> None:
        try:
            import fcntl
        except ImportError:  # pragma: no cover - Windows: no advisory lock
            return
        fd = os.open(self.dir / ".lock", os.O_RDWR | os.O_CREAT, 0o666)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            os.close(fd)
            raise InputError(
                f"out: another bench is writing into {str(self.dir)!r} (lock held)"
            ) from None
        self._lock_fd = fd

    def close(self) -> None:
        """Close the file and release the lock."""
        if self._fd is not None:
            os.close(self._fd)
            self._fd = None
        if self._lock_fd is not None:
            os.close(self._lock_fd)
            self._lock_fd = None

    def _open_fd(self) -> int:
        """The open file's descriptor; ``ValueError`` once the store is closed."""
        if self._fd is None:
            raise ValueError("the result store is closed")
        return self._fd

    def __enter__(self) -> ResultStore:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # -- reading -----------------------------------------------------------------------------

    def _repair_tail(self) -> None:
        """Cut a partial last line (left by a killed writer) so every line is complete."""
        if not self.path.exists():
            return
        size = self.path.stat().st_size
        if size == 0:
            return
        with open(self.path, "rb+") as fh:
            fh.seek(size - 1)
            if fh.read(1) == b"\n":
                return
            # Walk back to the last newline.
            pos = size
            chunk = 4096
            keep = 0
            while pos > 0:
                start = max(0, pos - chunk)
                fh.seek(start)
                data = fh.read(pos - start)
                i = data.rfind(b"\n")
                if i >= 0:
                    keep = start + i + 1
                    break
                pos = start
            logger.warning(
                "%s: dropping a partial last line (%d bytes) left by an interrupted bench",
                self.path,
                size - keep,
            )
            fh.truncate(keep)
            fh.flush()
            os.fsync(fh.fileno())

    def rows(self) -> Iterator[dict[str, Any]]:
        """Every complete, well-formed row in file order (others are skipped with a warning)."""
        for n, line in self._lines():
            try:
                row = json.loads(line)
            except json.JSONDecodeError:
                logger.warning("%s:%d: skipping a malformed line", self.path, n)
                continue
            if isinstance(row, dict):
                yield row

    def _lines(self) -> Iterator[tuple[int, str]]:
        """Every non-empty complete line of the file with its number, without its newline."""
        if not self.path.exists():
            return
        with open(self.path, encoding="utf-8") as fh:
            for n, line in enumerate(fh, start=1):
                if not line.endswith("\n"):
                    break  # a line still being written
                if line.strip():
                    yield n, line.rstrip("\n")

    def done_keys(self) -> set[tuple[str, int]]:
        """Keys of every run in the file."""
        return set(self._keys)

    # -- writing -----------------------------------------------------------------------------

    def append(self, row: Mapping[str, Any]) -> None:
        """Append one row as a JSON line; flushed and fsynced before returning.

        Parameters
        ----------
        row : mapping
            A result row with its ``config_hash`` and integer ``seed`` (its key).

        Raises
        ------
        ValueError
            When the row has no key or its key is already stored.
        """
        key = row_key(row)
        if key is None:
            raise ValueError("a stored row needs a config_hash and an integer seed")
        if key in self._keys:
            raise ValueError(f"run {key} is already stored")
        data = (json.dumps(json_safe(row), allow_nan=False) + "\n").encode()
        fd = self._open_fd()
        view = memoryview(data)
        while view:
            written = os.write(fd, view)
            view = view[written:]
        os.fsync(fd)
        self._keys.add(key)

    def drop(self, keys: Iterable[tuple[str, int]]) -> int:
        """Remove the rows of ``keys`` (rewrite through a temporary file and a rename).

        Parameters
        ----------
        keys : iterable of (str, int)
            ``(config_hash, seed)`` pairs; keys not stored are ignored.

        Returns
        -------
        int
            Number of rows removed.
        """
        drop = set(keys)
        kept: list[str] = []
        removed = 0
        # Every other line as it is, byte for byte: re-serialised, a row holding NaN (as
        # Python's json writes it) ended --retry-errors in a traceback, and malformed or
        # unfinished lines of other runs were lost (an audit).
        for _, line in self._lines():
            try:
                row = json.loads(line)
            except json.JSONDecodeError:
                row = None
            if isinstance(row, dict) and row_key(row) in drop:
                removed += 1
            else:
                kept.append(line)
        if not removed:
            return 0
        tmp = self.dir / f".{RUNS_FILE}.tmp"
        with open(tmp, "w", encoding="utf-8") as fh:
            fh.write("".join(line + "\n" for line in kept))
            fh.flush()
            os.fsync(fh.fileno())
        os.close(self._open_fd())
        os.replace(tmp, self.path)
        _fsync_dir(self.dir)
        self._fd = os.open(self.path, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o666)
        self._keys -= drop
        return removed
