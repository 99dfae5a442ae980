"""The ``rrtdrive maps`` subcommand: list the built-in maps, ``--export`` them as JSON files."""

from __future__ import annotations

import argparse
import pathlib
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

from rrtdrive.cli_args import validate_output, writing
from rrtdrive.types import InputError

if TYPE_CHECKING:
    from rrtdrive.maps import Map

__all__ = ["add_parser", "HELP"]

HELP = "list the built-in maps"


def add_parser(sub: Any) -> argparse.ArgumentParser:
    """Add ``maps`` to an argparse subparsers object and return its parser."""
    maps = sub.add_parser(
        "maps",
        help=HELP,
        description="List the built-in maps; --export writes them as JSON files.",
    )
    maps.add_argument(
        "--export", metavar="DIR",
        help="write each built-in map to DIR/NAME.json (DIR is created if missing)",
    )
    maps.set_defaults(func=_cmd_maps)
    return maps



def _cmd_maps(args: argparse.Namespace) -> int:
    from rrtdrive.maps import BUILTIN_MAPS, builtin_map

    maps = {name: builtin_map(name) for name in BUILTIN_MAPS}
    out = None if args.export is None else _export_folder(args.export, list(maps))
    if out is not None:
        _export(out, maps)
    for name, m in maps.items():
        line = (
            f"{name:12s} {len(m.obstacles):4d} obstacles  start {m.start.as_tuple()}  goal "
            + str(tuple(round(v, 3) for v in m.goal.as_tuple()))
        )
        if out is not None:
            line += f"  -> {out / f'{name}.json'}"
        print(line)
    return 0


def _export(out: pathlib.Path, maps: dict[str, Map]) -> None:
    """Write every map to ``out/NAME.json``: all of them, or (a full disk) none.

    Each is written to a temporary file first; only when all are complete are they
    renamed into place, so a write that fails leaves the folder as it was.
    """
    from rrtdrive.atomic import publish, temp_beside
    from rrtdrive.maps import map_text

    temps: dict[pathlib.Path, pathlib.Path] = {}
    try:
        for name, m in maps.items():
            target = out / f"{name}.json"
            with writing("--export", target):
                temps[target] = temp_beside(target)
                temps[target].write_text(map_text(m), "utf-8")
        for target, tmp in temps.items():
            with writing("--export", target):
                publish(tmp, target)
    finally:
        for tmp in temps.values():
            tmp.unlink(missing_ok=True)


def _export_folder(text: str, names: Sequence[str]) -> pathlib.Path:
    """The ``--export`` folder, created, with every ``NAME.json`` in it checked writable.

    Checked before the first file is written, so a bad target leaves no partial export.
    """
    if not text.strip():
        raise InputError("--export: expected a folder, got an empty value")
    out = pathlib.Path(text)
    if out.exists() and not out.is_dir():
        raise InputError(f"--export: {out} is a file; give a folder (it is created if missing)")
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InputError(f"--export: cannot create folder {out}: {exc.strerror}") from None
    for name in names:
        validate_output(str(out / f"{name}.json"), "--export")
    return out
