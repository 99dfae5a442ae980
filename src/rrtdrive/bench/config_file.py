"""A bench's settings from a TOML file or a mapping of its keys (the command line's flags).

The keys are :data:`~rrtdrive.bench.grid.CONFIG_KEYS`, the names of the
:class:`~rrtdrive.bench.grid.BenchConfig` fields; a ``[bench]`` table is accepted too.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Mapping
from pathlib import Path as FsPath
from typing import Any

from rrtdrive.bench.grid import CONFIG_KEYS, DETERMINISTIC_TIME, BenchConfig
from rrtdrive.types import InputError
from rrtdrive.values import did_you_mean

__all__ = ["FLAG_KEYS", "load_toml", "config_from_mapping"]


def load_toml(path: str | os.PathLike[str]) -> dict[str, Any]:
    """Read a TOML bench file and check its keys.

    Parameters
    ----------
    path : str or path-like
        The file.

    Returns
    -------
    dict
        The keys of :data:`CONFIG_KEYS` that the file sets.

    Raises
    ------
    InputError
        For a missing or malformed file or an unknown key (named in the message).
    """
    import tomllib

    p = FsPath(path)
    text = ""
    try:
        if str(path) == "-":  # `--config -`: the TOML on stdin (a here-document)
            p = FsPath("stdin")
            text = sys.stdin.read().removeprefix("\ufeff")
        else:
            # utf-8-sig: a byte-order mark (Windows editors write one) is no error, as in maps.
            text = p.read_text(encoding="utf-8-sig")
        data = tomllib.loads(text)
    except FileNotFoundError:
        raise InputError(f"config: no such file {str(p)!r}") from None
    except (OSError, UnicodeDecodeError) as exc:
        # The reason alone: str(OSError) repeats the errno and the path.
        why = exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc)
        raise InputError(f"config: cannot read {str(p)!r}: {why}") from None
    except tomllib.TOMLDecodeError as exc:
        raise InputError(_toml_error(exc, text, str(p))) from None
    except RecursionError:
        raise InputError(f"config: malformed TOML in {str(p)!r}: nested too deeply") from None
    except ValueError:  # an integer past Python's 4300-digit conversion limit
        raise InputError(
            f"config: malformed TOML in {str(p)!r}: a number has too many digits"
        ) from None
    if "bench" in data and isinstance(data["bench"], dict):
        if len(data) > 1:
            # Keys beside the table, or other tables: "unknown key 'bench'" named the one
            # key that was right.
            other = sorted(k for k in data if k != "bench")[0]
            raise InputError(
                f"config: {other!r} in {str(p)!r} is outside the [bench] table; put every "
                "key in the table, or drop the table"
            )
        data = data["bench"]  # a [bench] table is accepted too
    unknown = sorted(set(data) - set(CONFIG_KEYS))
    if unknown:
        raise InputError(
            f"config: unknown key {unknown[0]!r}{_key_hint(unknown[0])} in {str(p)!r}; "
            f"allowed keys: {', '.join(CONFIG_KEYS)}"
        )
    if "ray" in data:
        ray = data["ray"]
        if ray is True:
            data["ray"] = ""
        elif ray is False:
            data["ray"] = None
        elif not isinstance(ray, str):
            raise InputError(
                f"ray: expected true, false or an address, got {ray!r} (in {str(p)!r})"
            )
    # A shell expands --out ~/x; a file's "~/x" made a folder named "~" (an audit).
    if isinstance(data.get("out"), str):
        data["out"] = os.path.expanduser(data["out"])
    for key in ("maps", "scenarios"):  # map files may stand in either list
        if isinstance(data.get(key), list):
            data[key] = [os.path.expanduser(m) if isinstance(m, str) else m for m in data[key]]
    return data


#: The flags whose key is not the flag's own name with ``_`` for ``-``.
FLAG_KEYS = {"jobs": "workers", "max_time": "max_time_s", "run_timeout": "run_timeout_s"}


def _key_hint(key: str) -> str:
    """`` (the flag --jobs; its key is 'workers')`` for a flag's name, else did-you-mean.

    A user who knows the command line writes ``jobs = 2`` or ``max-time = 5``; difflib
    finds no key close to ``jobs``.
    """
    name = key.lstrip("-").replace("-", "_")
    real = FLAG_KEYS.get(name, name)
    if real in CONFIG_KEYS and real != key:
        return f" (the flag --{name.replace('_', '-')}; its key is {real!r})"
    return did_you_mean(key, CONFIG_KEYS)


def _toml_error(exc: Exception, text: str, name: str) -> str:
    """Tomllib's error in the file's terms.

    A key given twice is named (tomllib says "Cannot overwrite a value"); a JSON or
    YAML file is told that ``--config`` reads TOML.
    """
    import re

    why = str(exc)
    where = re.search(r"\(at line (\d+), column \d+\)", why)
    if where and why.startswith(("Cannot overwrite a value", "Cannot declare")):
        # "\n" only, as tomllib counts lines (splitlines also splits at U+2028).
        line = text.split("\n")[int(where.group(1)) - 1] if text else ""
        key = line.split("=", 1)[0].strip().strip("[]\"' ")
        if key:
            return f"{key}: given twice in {name!r} (line {where.group(1)}); give it once"
    hint = ""
    if name.lower().endswith((".json", ".yaml", ".yml")) or text.lstrip().startswith("{"):
        hint = "; --config reads TOML (key = value lines), not JSON or YAML"
    return f"config: malformed TOML in {name!r}: {why}{hint}"


def config_from_mapping(values: Mapping[str, Any]) -> BenchConfig:
    """Build a :class:`BenchConfig` from a mapping of :data:`CONFIG_KEYS` (``None`` = default).

    Raises
    ------
    InputError
        For an unknown key or an invalid value.
    """
    unknown = sorted(set(values) - set(CONFIG_KEYS))
    if unknown:
        raise InputError(f"config: unknown key {unknown[0]!r}")
    if values.get("deterministic") is True and values.get("max_time_s") is not None:
        raise InputError(DETERMINISTIC_TIME)  # whatever the value, NO_WALL_LIMIT_S too
    return BenchConfig(**{k: v for k, v in values.items() if v is not None})
