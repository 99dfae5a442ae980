"""SIGTERM ends the CLI as Ctrl-C does: outputs half-written are removed, exit 143.

``timeout``, systemd and CI runners stop a process with SIGTERM, whose default
action kills Python at once: no ``finally`` runs, so the hidden temporary file of
an output being written (:mod:`rrtdrive.atomic`) stayed behind. Raised as an
exception instead, it unwinds like Ctrl-C's :class:`KeyboardInterrupt`.
"""

from __future__ import annotations

import os
import signal
import sys
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from types import FrameType

__all__ = [
    "EXIT_TERMINATED",
    "Terminated",
    "interrupt_behind",
    "loading_done",
    "quiet_interrupt_while_loading",
    "sigterm_raises",
    "sigterm_received",
]

#: 128 + SIGTERM, as a shell reports a process ended by it.
EXIT_TERMINATED = 143


class Terminated(KeyboardInterrupt):
    """SIGTERM arrived: a :class:`KeyboardInterrupt`, so every clean-up for Ctrl-C runs."""


#: Set when SIGTERM arrived within :func:`sigterm_raises` (reset on entering it): a
#: library that catches the :class:`Terminated` and raises a plain KeyboardInterrupt
#: (Ray's ``ray.get``) still ends as a termination (an audit: exit 130, not 143).
_received = [False]


def sigterm_received() -> bool:
    """Whether SIGTERM arrived within the current (or last) :func:`sigterm_raises` block."""
    return _received[0]


def _raise_terminated(signum: int, frame: FrameType | None) -> None:
    _received[0] = True
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
    _received[0] = False
    previous = signal.signal(signal.SIGTERM, _raise_terminated)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


#: The console script's names (``rrtdrive``; ``rrtdrive.exe`` on Windows).
_SCRIPT_NAMES = ("rrtdrive", "rrtdrive.exe")


def _interrupted_loading(signum: int, frame: FrameType | None) -> None:
    # Nothing is open or half-written yet: one line and out, as cli.main says it.
    sys.stderr.write("rrtdrive: interrupted\n")
    sys.stderr.flush()
    os._exit(130)


def _terminated_loading(signum: int, frame: FrameType | None) -> None:
    sys.stderr.write("rrtdrive: terminated\n")
    sys.stderr.flush()
    os._exit(EXIT_TERMINATED)


def quiet_interrupt_while_loading(argv0: str) -> None:
    """In the console script, Ctrl-C or SIGTERM before the command runs is one line.

    The package's imports (numpy, gymnasium: seconds on a cold machine) run before
    ``main`` can catch anything: a Ctrl-C there printed a 20-35 line traceback, and a
    SIGTERM before :func:`sigterm_raises` killed the process without its line. Exit
    130 or 143, as later. Only for the ``rrtdrive`` script (``argv0``) and default
    handlers; ``cli.main`` puts SIGINT's back (:func:`loading_done`), and
    :func:`sigterm_raises` takes SIGTERM over for the command.
    """
    if os.path.basename(argv0) not in _SCRIPT_NAMES:
        return
    if threading.current_thread() is not threading.main_thread():
        return
    if signal.getsignal(signal.SIGINT) is signal.default_int_handler:
        signal.signal(signal.SIGINT, _interrupted_loading)
    if signal.getsignal(signal.SIGTERM) == signal.SIG_DFL:
        signal.signal(signal.SIGTERM, _terminated_loading)


def loading_done() -> None:
    """Ctrl-C raises KeyboardInterrupt again, after :func:`quiet_interrupt_while_loading`."""
    if signal.getsignal(signal.SIGINT) is _interrupted_loading:
        signal.signal(signal.SIGINT, signal.default_int_handler)


def interrupt_behind(exc: BaseException) -> KeyboardInterrupt | None:
    """The Ctrl-C or SIGTERM that ``exc`` stands for, if any.

    A signal during a C extension's initialisation surfaces as ``ImportError:
    initialization failed``, caused by the KeyboardInterrupt (matplotlib's ``_image`` on
    a loaded machine: a 40-line traceback and exit 1 instead of 130).

    Examples
    --------
    >>> try:
    ...     try:
    ...         raise KeyboardInterrupt
    ...     except KeyboardInterrupt as ki:
    ...         raise ImportError("initialization failed") from ki
    ... except ImportError as exc:
    ...     type(interrupt_behind(exc)).__name__
    'KeyboardInterrupt'
    """
    seen: set[int] = set()
    link: BaseException | None = exc
    while link is not None and id(link) not in seen:
        if isinstance(link, KeyboardInterrupt):
            return link
        seen.add(id(link))
        link = link.__cause__ or link.__context__
    return None

