"""Reading a JSON file a user gives (a map, a plan): bounded in size, every failure one line."""

from __future__ import annotations

import json
import os
from typing import BinaryIO

from rrtdrive.types import InputError

__all__ = ["MAX_JSON_BYTES", "json_kind", "parse_json", "read_capped", "read_json_file"]


#: The largest JSON file (a map, a plan) read, bytes: a map of 20 000 obstacles is 1.5 MB,
#: and a read of /dev/zero or of a huge stream must end with a message, not a MemoryError.
MAX_JSON_BYTES = 256 * 1024 * 1024
#: Characters of the text before a JSON syntax error that its message shows.
EXCERPT = 20


def read_capped(stream: BinaryIO, field: str, source: str) -> bytes:
    """Read ``stream`` whole; past :data:`MAX_JSON_BYTES`, an InputError naming ``field``."""
    raw = stream.read(MAX_JSON_BYTES + 1)
    if len(raw) > MAX_JSON_BYTES:
        raise InputError(
            f"{field}: {source} is larger than {MAX_JSON_BYTES // 2**20} MB; "
            "is it the JSON file you meant?"
        )
    return raw


class _DuplicateKey(ValueError):
    """A JSON object names one key twice (the last would silently win)."""


def _unique_keys(pairs: list[tuple[str, object]]) -> dict[str, object]:
    out: dict[str, object] = {}
    for key, value in pairs:
        if key in out:
            raise _DuplicateKey(key)
        out[key] = value
    return out


def parse_json(raw: bytes | str, field: str, source: str) -> object:
    """Decode UTF-8 JSON, turning every way it can fail into one :class:`InputError` line.

    NaN and Infinity literals parse to floats, so that validation names the field
    they sit in; so do integers too large for a float. A key given twice in one
    object is refused (``json`` keeps the last, silently); a byte-order mark is
    skipped.

    Parameters
    ----------
    raw : bytes or str
        The file's content (bytes are decoded as UTF-8).
    field : str
        Field named first in the message (``"map"``, ``"plan"``).
    source : str
        The file name (or ``"stdin"``) named in the message.

    Returns
    -------
    object
        The parsed JSON value.

    Examples
    --------
    >>> parse_json(b"[1, NaN]", "map", "m.json")
    [1, nan]
    >>> parse_json('{"start": [0, 0, 0], "start": [1, 1, 0]}', "map", "m.json")
    Traceback (most recent call last):
    ...
    rrtdrive.types.InputError: map: m.json gives 'start' twice in one object; keep one
    >>> parse_json("[1, 2,]", "map", "m.json")  # doctest: +NORMALIZE_WHITESPACE
    Traceback (most recent call last):
    ...
    rrtdrive.types.InputError: map: malformed JSON in m.json: Expecting value
    (line 1, column 7, near '[1, 2,]')
    >>> parse_json("[" * 100_000, "map", "m.json")
    Traceback (most recent call last):
    ...
    rrtdrive.types.InputError: map: malformed JSON in m.json: nested too deeply
    """
    if isinstance(raw, bytes):
        try:
            # utf-8-sig: a byte-order mark (Windows editors write one) is no error.
            raw = raw.decode("utf-8-sig")
        except UnicodeDecodeError as exc:
            raise InputError(
                f"{field}: {source} is not a UTF-8 text file (byte {exc.start}: {exc.reason})"
            ) from None
    raw = raw.removeprefix("\ufeff")
    bad = f"{field}: malformed JSON in {source}"
    try:
        return json.loads(raw, parse_constant=float, object_pairs_hook=_unique_keys)
    except _DuplicateKey as exc:
        raise InputError(
            f"{field}: {source} gives {exc.args[0]!r} twice in one object; keep one"
        ) from None
    except json.JSONDecodeError as exc:
        # The column and the text up to it: a map is often one line, whose number alone
        # says nothing (an audit: "Expecting value (line 1)" for a trailing comma).
        near = " ".join(raw[max(0, exc.pos - EXCERPT) : exc.pos + 1].split())
        at = f", near {near!r}" if near else ""
        raise InputError(
            f"{bad}: {exc.msg} (line {exc.lineno}, column {exc.colno}{at})"
        ) from None
    except RecursionError:
        raise InputError(f"{bad}: nested too deeply") from None
    except ValueError:  # an integer literal past Python's 4300-digit conversion limit
        raise InputError(f"{bad}: a number has too many digits") from None


def read_json_file(path: str | os.PathLike[str], field: str) -> object:
    """The parsed JSON of file ``path``: :func:`read_capped`, then :func:`parse_json`.

    Raises
    ------
    InputError
        Naming ``field``: a file that cannot be read (``field: cannot read PATH:
        why``), is too big, or is not UTF-8 JSON.
    """
    try:
        with open(path, "rb") as f:
            raw = read_capped(f, field, str(path))
    except OSError as exc:
        raise InputError(f"{field}: cannot read {path}: {exc.strerror}") from None
    return parse_json(raw, field, str(path))


def json_kind(value: object) -> str:
    """What ``value`` is in JSON's words (``null``, ``array``, ...), for messages.

    Examples
    --------
    >>> [json_kind(v) for v in (None, [1], "x", {}, True, 2.5)]
    ['null', 'an array', 'a string', 'an object', 'true', 'a number']
    """
    if value is None or isinstance(value, bool):
        return json.dumps(value)
    for kind, name in ((dict, "an object"), (list, "an array"), (str, "a string")):
        if isinstance(value, kind):
            return name
    return "a number" if isinstance(value, (int, float)) else type(value).__name__
