"""Reading a plan JSON file (``rrtdrive plan --json``, or another planner's ``{"path": ...}``).

``rrtdrive verify PLAN`` checks one and ``rrtdrive simulate MAP --path PLAN`` drives
one; both read it here, each naming the file by its own argument (``plan``,
``--path``) in errors.
"""

from __future__ import annotations

import dataclasses
import sys
import warnings
from typing import TYPE_CHECKING, Any, BinaryIO, cast

from rrtdrive.types import InputError, InputWarning, VehicleParams, brief_repr

if TYPE_CHECKING:
    from rrtdrive.maps import Map

__all__ = ["plan_car", "read_plan_json", "with_plan_car"]


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
    from rrtdrive.json_input import parse_json, read_capped, read_json_file
    from rrtdrive.types import PlanStatus

    label = "stdin" if source == "-" else source
    if source == "":
        raise InputError(f"{field}: needs a plan .json file (or - for stdin), got an empty one")
    if source == "-":
        # Bytes, so a file that is not UTF-8 is named as such whatever the locale
        # (a text stream without a buffer, as a caller's StringIO, gives its text).
        stdin = cast(BinaryIO, getattr(sys.stdin, "buffer", sys.stdin))
        try:
            data = parse_json(read_capped(stdin, field, label), field, label)
        except OSError as exc:
            raise InputError(f"{field}: cannot read {label}: {exc.strerror}") from None
    else:
        data = read_json_file(source, field)
    if not isinstance(data, dict) or "path" not in data:
        raise InputError(f"{field}: {label} has no \"path\" (expected the JSON of rrtdrive plan)")
    # Printed in verdict lines: only a status rrtdrive writes (a newline split the line).
    statuses = [s.value for s in PlanStatus]
    if "status" in data and data["status"] not in statuses:
        raise InputError(
            f"{field}.status: must be one of {statuses}, got {brief_repr(data['status'])}"
        )
    return data


def plan_car(data: dict[str, Any], field: str) -> VehicleParams | None:
    """The car a plan was made for, its ``vehicle``; ``None`` for a plan without one.

    Raises
    ------
    InputError
        Naming ``field`` and the key: a malformed car.
    """
    if data.get("vehicle") is None:
        return None
    from rrtdrive.vehicle_json import vehicle_from_json

    return vehicle_from_json(data["vehicle"], field)


def with_plan_car(m: Map, car: VehicleParams | None, who: str) -> Map:
    """``m`` with the plan's ``car`` (``None``: ``m`` as it is), the query unchecked.

    A path is judged and driven for the car it was made for (a small car's tight turns
    are no fault). A map whose own car is another, and not the paper's, gets a warning
    naming ``who`` (``MAP``, ``SCENARIO``); a map of the paper's car, such as a built-in
    one, takes the plan's without a word.
    """
    if car is None or car == m.vehicle:
        return m
    if m.vehicle != VehicleParams():
        warnings.warn(
            f"{who}: its car is not the one the plan was made for; the plan's "
            f"({car.length:g} x {car.width:g} m, wheelbase {car.wheelbase:g} m, min turning "
            f"radius {car.min_turning_radius:g} m) is used", InputWarning, stacklevel=2,
        )  # fmt: skip
    with warnings.catch_warnings():  # the map's own warnings were given as it loaded
        warnings.simplefilter("ignore", InputWarning)
        return dataclasses.replace(m, vehicle=car, check_query=False)

