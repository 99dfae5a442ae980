"""Failed writes of the CLI's stdout: a quiet exit for ``| head``, one line for a full disk.

Python reports both as a traceback (or as "Exception ignored" at exit, when the
last buffered text is flushed): :func:`run_writing_stdout` turns them into exit
codes instead, and only for stdout, never for another ``OSError`` of the command.
"""

from __future__ import annotations

import io
import os
import sys
from collections.abc import Callable
from typing import Any

__all__ = ["EXIT_BROKEN_PIPE", "EXIT_CANNOT_WRITE", "run_writing_stdout"]

#: The reader of stdout went away (``rrtdrive maps | head -1``): 128 + SIGPIPE, as a shell.
EXIT_BROKEN_PIPE = 141
#: Stdout could not be written otherwise (no space left, I/O error).
EXIT_CANNOT_WRITE = 1


class _StdoutError(Exception):
    """Writing stdout failed: not the command's fault, nor a bug of it."""

    def __init__(self, error: OSError) -> None:
        super().__init__(str(error))
        self.error = error


class _GuardedStdout:
    """A stream whose write errors surface as :class:`_StdoutError` (the rest delegated)."""

    def __init__(self, stream: Any) -> None:
        self._stream = stream

    def write(self, text: str) -> int:
        try:
            return self._stream.write(text)
        except OSError as exc:
            raise _StdoutError(exc) from exc

    def flush(self) -> None:
        try:
            self._stream.flush()
        except OSError as exc:
            raise _StdoutError(exc) from exc

    def __getattr__(self, name: str) -> Any:
        return getattr(self._stream, name)


def run_writing_stdout(command: Callable[[], int]) -> int:
    """Run ``command`` with ``sys.stdout`` guarded; return its exit code or the output's.

    Parameters
    ----------
    command : callable
        Runs the CLI and returns its exit code (``SystemExit`` passes through, after
        its text is flushed).

    Returns
    -------
    int
        ``command``'s code; :data:`EXIT_BROKEN_PIPE` (quietly) when the reader of
        stdout went away; :data:`EXIT_CANNOT_WRITE`, with one line on stderr, when
        stdout could not be written otherwise.
    """
    stdout = sys.stdout
    sys.stdout = guarded = _GuardedStdout(stdout)
    try:
        try:
            code = command()
        except SystemExit:  # --help and argparse errors: their text must be written too
            guarded.flush()
            raise
        guarded.flush()  # here, not at exit, where a failure is a traceback-like message
        return code
    except _StdoutError as exc:
        return _output_failed(exc.error, stdout)
    finally:
        sys.stdout = stdout


def _output_failed(error: OSError, stdout: Any) -> int:
    """Report a failed write of stdout; return the exit code."""
    # The stream still holds the unwritten text and the interpreter flushes it at exit:
    # point the descriptor at devnull so that flush cannot fail once more.
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, stdout.fileno())
        os.close(devnull)
    except (OSError, ValueError, AttributeError, io.UnsupportedOperation):
        pass  # no descriptor (an in-memory stream): nothing is flushed at exit
    if isinstance(error, BrokenPipeError):
        return EXIT_BROKEN_PIPE  # quietly: the reader asked for no more
    print(f"rrtdrive: cannot write the output: {error.strerror or error}", file=sys.stderr)
    return EXIT_CANNOT_WRITE
