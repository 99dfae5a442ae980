"""Reading a plan JSON file (``rrtdrive plan --json``, or another planner's ``{"path": ...}``).

``rrtdrive verify PLAN`` checks one and ``rrtdrive simulate MAP --path PLAN`` drives
one; both read it here, each naming the file by its own argument (``plan``,
``--path``) in errors.
"""

from __future__ import annotations

import sys
from typing import Any, BinaryIO, cast

from rrtdrive.types import InputError, brief_repr

__all__ = ["read_plan_json"]


def read_plan_json(source: str, field: str = "plan") -> dict[str, Any]:
    """The parsed plan JSON object of file ``source`` (``"-"``: stdin).

    Parameters
    ----------
    source : str
        A file name, or ``"-"`` for stdin.
    field : str
        What errors name the file by (``"plan"``, ``"--path"``).

    Returns
    -------
    dict
        The object, which has a ``"path"`` key; its ``"status"``, when present, is one
        rrtdrive writes (:class:`~rrtdrive.types.PlanStatus`).

    Raises
    ------
    InputError
        Naming ``field``: an empty name, a file that cannot be read, is too big, is not
        UTF-8 JSON, has no ``"path"``, or has an unknown ``"status"``.
    """
    from rrtdrive.json_input import parse_json, read_capped
    from rrtdrive.types import PlanStatus

    label = "stdin" if source == "-" else source
    if source == "":
        raise InputError(f"{field}: needs a plan .json file (or - for stdin), got an empty one")
    try:
        if source == "-":
            # Bytes, so a file that is not UTF-8 is named as such whatever the locale
            # (a text stream without a buffer, as a caller's StringIO, gives its text).
            stdin = cast(BinaryIO, getattr(sys.stdin, "buffer", sys.stdin))
            raw = read_capped(stdin, field, label)
        else:
            with open(source, "rb") as f:
                raw = read_capped(f, field, label)
    except OSError as exc:
        raise InputError(f"{field}: cannot read {label}: {exc.strerror}") from None
    data = parse_json(raw, field, label)
    if not isinstance(data, dict) or "path" not in data:
        raise InputError(f"{field}: {label} has no \"path\" (expected the JSON of rrtdrive plan)")
    # Printed in verdict lines: only a status rrtdrive writes (a newline split the line).
    statuses = [s.value for s in PlanStatus]
    if "status" in data and data["status"] not in statuses:
        raise InputError(
            f"{field}.status: must be one of {statuses}, got {brief_repr(data['status'])}"
        )
    return data
