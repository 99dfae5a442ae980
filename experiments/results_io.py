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
from rrtdrive.json_safe import json_safe


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


def json_text(payload: Any, sort_keys: bool = False) -> str:
    """``payload`` as a results file's strict JSON: a missing number is ``null``, not ``NaN``.

    ``json.dumps`` writes ``NaN`` by default, which strict readers (``jq``, browsers,
    ``json.loads(..., parse_constant=...)``) refuse.

    Examples
    --------
    >>> json_text({"mean": float("nan"), "n": 0})
    '{\\n "mean": null,\\n "n": 0\\n}\\n'
    """
    return json.dumps(json_safe(payload), indent=1, allow_nan=False, sort_keys=sort_keys) + "\n"


def write_results(
    out: str, stem: str, payload: dict[str, Any], report: Callable[[dict[str, Any]], str]
) -> str:
    """Write ``OUT/STEM.json`` and the page ``OUT/STEM.md``; return the page."""
    folder = FsPath(out)
    folder.mkdir(parents=True, exist_ok=True)
    write_text_atomic(folder / f"{stem}.json", json_text(payload))
    text = report(payload)
    write_text_atomic(folder / f"{stem}.md", text)
    return text


def out_folder(text: str) -> str:
    """An argparse type for an output folder: refused before the run when it cannot be one.

    A file there, or a file where a parent folder should be, or a folder this user
    cannot write into; found at the end, it lost a whole run's episodes.

    Examples
    --------
    >>> out_folder("results/new/deeper")
    'results/new/deeper'
    """
    import argparse

    for folder in (FsPath(text), *FsPath(text).parents):
        if folder.exists():
            if not folder.is_dir():
                why = "is" if folder == FsPath(text) else "(a parent) is"
                raise argparse.ArgumentTypeError(f"{str(folder)!r} {why} a file, not a folder")
            if not os.access(folder, os.W_OK | os.X_OK):
                raise argparse.ArgumentTypeError(f"cannot write into {str(folder)!r}")
            break
    return text


def out_file(text: str) -> str:
    """An argparse type for an output file (``--doc``): refused before the run when it cannot be.

    Not a folder, and its folder one that :func:`out_folder` takes (a missing one is
    made when the file is written): found at the end, it lost a whole run and named a
    hidden temporary file (an audit).

    Examples
    --------
    >>> out_file("new/page.md")
    'new/page.md'
    """
    import argparse

    if FsPath(text).is_dir():
        raise argparse.ArgumentTypeError(f"{text!r} is a folder, not a file")
    out_folder(str(FsPath(text).parent))
    return text


def run_main(main: Callable[[], int | None]) -> int:
    """A script's ``main()``, with bad input as one line on stderr and exit 2.

    :class:`~rrtdrive.types.InputError` (an unknown map, scenario or planner) and a
    missing input file end the script with ``SCRIPT: error: ...`` instead of a
    traceback; Ctrl-C with exit 130; an output that cannot be written with one line and
    exit 1.
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
        print(f"\n{name}: interrupted", file=sys.stderr)  # after an unfinished progress line
        return 130
    except OSError as exc:  # an output that cannot be written: a run failure, not bad input
        where = exc.filename or "an output"
        print(f"{name}: error: cannot write {where}: {exc.strerror or exc}", file=sys.stderr)
        return 1
    return 2


def _doc_markers(script: str) -> tuple[str, str]:
    return (f"<!-- BEGIN generated by experiments/{script} -->",
            f"<!-- END generated by experiments/{script} -->")


def check_doc(doc: str | None, script: str) -> None:
    """Refuse, before any work, a ``--doc`` page that its run would wipe.

    A new page is fine, and so is one with the script's generated block (its two
    marker lines, :func:`write_doc` replaces what lies between); an existing page
    without them holds hand-written text that a rewrite would lose.
    """
    from rrtdrive.types import InputError

    if doc is None or not FsPath(doc).exists():
        return
    begin, end = _doc_markers(script)
    text = FsPath(doc).read_text(encoding="utf-8")
    if begin not in text or end not in text:
        raise InputError(
            f"--doc: {doc} exists without the block of {script} ({begin} ... {end}): "
            "rewriting it would wipe its hand-written text; give a new page, or put the two "
            "marker lines around the part to regenerate"
        )


def write_doc(doc: str, text: str, script: str) -> None:
    """Write ``text`` as the generated block of page ``doc`` (the rest of the page kept)."""
    begin, end = _doc_markers(script)
    block = f"{begin}\n{text.rstrip()}\n{end}\n"
    path = FsPath(doc)
    path.parent.mkdir(parents=True, exist_ok=True)  # as --out's folder is made
    if path.exists():
        old = path.read_text(encoding="utf-8")
        if begin in old and end in old:
            head, rest = old.split(begin, 1)
            block = head + block + rest.split(end, 1)[1].lstrip("\n")
    write_text_atomic(path, block)


def write_image_atomic(path: FsPath, frame: Any) -> None:
    """Write image ``frame`` to ``path`` whole or not at all (a temporary file, renamed)."""
    import imageio.v3 as iio

    tmp = path.with_name(f".{path.stem}.tmp{path.suffix}")
    try:
        iio.imwrite(tmp, frame)
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)


if __name__ == "__main__":
    import sys

    # Run as a script it did nothing and exited 0: say what it is.
    sys.exit("results_io.py is a library module of every experiment script: "
             "run one of those (--help)")
