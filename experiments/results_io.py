"""What the newer experiment scripts share: the machine line, number lists, writing results.

``forward_reach.py``, ``street_turns.py`` and the report pages use it; a script writes
its payload as ``OUT/STEM.json`` and its page as ``OUT/STEM.md``, each through a
temporary file; :func:`cell` formats a table's numbers.
"""

from __future__ import annotations

import json
import math
import os
import platform
import sys
from collections.abc import Callable, Sequence
from pathlib import Path as FsPath
from typing import Any

from rrtdrive.atomic import write_text_atomic


def machine() -> str:
    """The machine line of a payload: architecture, CPUs and Python."""
    return f"{platform.machine()} {os.cpu_count()} CPUs, Python {platform.python_version()}"


def command(script: str, argv: Sequence[str] | None) -> str:
    """The command line that reproduces a run of ``experiments/SCRIPT``."""
    args = sys.argv[1:] if argv is None else argv
    return " ".join([f"python experiments/{script}", *args])


def numbers_above(text: str, name: str, floor: float = 0.0) -> list[float]:
    """The comma-separated numbers of option ``name``, each finite and above ``floor``.

    Raises
    ------
    ValueError
        Naming ``name`` and what was given.

    Examples
    --------
    >>> numbers_above("0.2,1", "--sharpness")
    [0.2, 1.0]
    """
    try:
        values = [float(v) for v in text.split(",") if v]
    except ValueError:
        raise ValueError(f"{name}: expected comma-separated numbers, got {text!r}") from None
    if not values or not all(math.isfinite(v) and v > floor for v in values):
        raise ValueError(f"{name}: expected numbers above {floor:g}, got {text!r}")
    return values


def cell(value: float | None, scale: float = 1.0, digits: int = 1, suffix: str = "") -> str:
    """A table cell: ``value * scale`` to ``digits`` decimals then ``suffix``, ``-`` for none.

    Examples
    --------
    >>> cell(0.01234, 1000), cell(None), cell(0.989, 100, 1, " %")
    ('12.3', '-', '98.9 %')
    """
    return "-" if value is None else f"{value * scale:.{digits}f}{suffix}"


def write_results(
    out: str, stem: str, payload: dict[str, Any], report: Callable[[dict[str, Any]], str]
) -> str:
    """Write ``OUT/STEM.json`` and the page ``OUT/STEM.md``; return the page."""
    folder = FsPath(out)
    folder.mkdir(parents=True, exist_ok=True)
    write_text_atomic(folder / f"{stem}.json", json.dumps(payload, indent=1) + "\n")
    text = report(payload)
    write_text_atomic(folder / f"{stem}.md", text)
    return text


def run_main(main: Callable[[], int | None]) -> int:
    """A script's ``main()``, with bad input as one line on stderr and exit 2.

    :class:`~rrtdrive.types.InputError` (an unknown map, scenario or planner) and a
    missing input file end the script with ``SCRIPT: error: ...`` instead of a
    traceback; Ctrl-C with exit 130.
    """
    from rrtdrive.types import InputError

    name = FsPath(sys.argv[0]).name
    try:
        return int(main() or 0)
    except InputError as exc:
        print(f"{name}: error: {exc}", file=sys.stderr)
    except FileNotFoundError as exc:
        print(f"{name}: error: {exc.filename}: no such file", file=sys.stderr)
    except KeyboardInterrupt:
        print(f"{name}: interrupted", file=sys.stderr)
        return 130
    return 2
