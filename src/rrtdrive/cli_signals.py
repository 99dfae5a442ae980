"""SIGTERM ends the CLI as Ctrl-C does: outputs half-written are removed, exit 143.

``timeout``, systemd and CI runners stop a process with SIGTERM, whose default
action kills Python at once: no ``finally`` runs, so the hidden temporary file of
an output being written (:mod:`rrtdrive.atomic`) stayed behind. Raised as an
exception instead, it unwinds like Ctrl-C's :class:`KeyboardInterrupt`.
"""

from __future__ import annotations

import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from types import FrameType

__all__ = ["EXIT_TERMINATED", "Terminated", "sigterm_raises"]

#: 128 + SIGTERM, as a shell reports a process ended by it.
EXIT_TERMINATED = 143


class Terminated(KeyboardInterrupt):
    """SIGTERM arrived: a :class:`KeyboardInterrupt`, so every clean-up for Ctrl-C runs."""


def _raise_terminated(signum: int, frame: FrameType | None) -> None:
    raise Terminated


@contextmanager
def sigterm_raises() -> Iterator[None]:
    """Within the block, SIGTERM raises :class:`Terminated`; the old handler after it.

    Outside the main thread (where Python cannot set handlers) the block runs as is.

    Examples
    --------
    >>> import os
    >>> try:
    ...     with sigterm_raises():
    ...         os.kill(os.getpid(), signal.SIGTERM)
    ... except Terminated:
    ...     print("cleaned up")
    cleaned up
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGTERM, _raise_terminated)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)
