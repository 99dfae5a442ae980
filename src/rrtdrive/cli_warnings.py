"""Input warnings as one ``warning:`` line each on stderr, not Python's warning format.

A map's start yaw of 90 is a valid angle in radians, so it is planned as given;
:class:`~rrtdrive.types.InputWarning` says so (and what to write for degrees).
Python's own format would print the module path and the source line of the
``warnings.warn`` call, which mean nothing to the user of the CLI.
"""

from __future__ import annotations

import sys
import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any, TextIO

from rrtdrive.types import InputWarning

__all__ = ["warnings_as_lines"]


@contextmanager
def warnings_as_lines(prefix: str) -> Iterator[None]:
    r"""Within the block, each distinct :class:`InputWarning` is one line ``PREFIX: warning: ...``.

    Other warnings keep Python's format. The previous handler is back after the block.

    Examples
    --------
    >>> import contextlib, io
    >>> err = io.StringIO()
    >>> with contextlib.redirect_stderr(err), warnings_as_lines("rrtdrive plan"):
    ...     warnings.warn("start: yaw 90 is more than a full turn", InputWarning)
    >>> err.getvalue()
    'rrtdrive plan: warning: start: yaw 90 is more than a full turn\n'
    """
    shown: set[str] = set()
    with warnings.catch_warnings():
        warnings.simplefilter("always", InputWarning)  # de-duplicated below, by text
        previous = warnings.showwarning

        def show(
            message: Warning | str,
            category: type[Warning],
            filename: str,
            lineno: int,
            file: TextIO | None = None,
            line: str | None = None,
        ) -> Any:
            if not issubclass(category, InputWarning):
                return previous(message, category, filename, lineno, file, line)
            text = str(message)
            if text not in shown:
                shown.add(text)
                print(f"{prefix}: warning: {text}", file=sys.stderr)
            return None

        warnings.showwarning = show
        yield
