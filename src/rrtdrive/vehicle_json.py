"""The car in JSON: a map file's and a plan's optional ``vehicle`` object.

``{"length": 4.3, "width": 1.8, "wheelbase": 2.51, "min_turning_radius": 6.0,
"max_steer": 0.5236, "max_steer_rate": 0.4}``: the fields of
:class:`~rrtdrive.types.VehicleParams` (metres, radians, rad/s); a field left out
keeps the paper's car's value, ``max_steer_rate: null`` is instant steering.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping

from rrtdrive.json_input import json_kind
from rrtdrive.types import InputError, VehicleParams
from rrtdrive.values import brief_repr, did_you_mean, is_finite_number

__all__ = ["VEHICLE_KEYS", "vehicle_from_json", "vehicle_to_json"]

#: The keys of a ``vehicle`` object: :class:`VehicleParams`'s fields.
VEHICLE_KEYS: tuple[str, ...] = tuple(f.name for f in dataclasses.fields(VehicleParams))


def vehicle_to_json(vehicle: VehicleParams) -> dict[str, float | None]:
    """``vehicle`` as a JSON object; an unbounded steering rate as ``null``.

    Parameters
    ----------
    vehicle : VehicleParams
        The car.

    Returns
    -------
    dict
        Every field of :class:`VehicleParams`, strict-JSON numbers or ``None``.

    Examples
    --------
    >>> vehicle_to_json(VehicleParams(max_steer_rate=None))["max_steer_rate"] is None
    True
    """
    # VehicleParams keeps instant steering (inf too) as None: null here.
    values = {k: getattr(vehicle, k) for k in VEHICLE_KEYS}
    return {k: None if v is None else float(v) for k, v in values.items()}


def vehicle_from_json(value: object, field: str = "vehicle") -> VehicleParams:
    """The car of a JSON ``vehicle`` object, every field checked.

    Parameters
    ----------
    value : object
        Parsed JSON: an object with some of :data:`VEHICLE_KEYS`.
    field : str
        How errors name the object (``"vehicle"``, ``"plan.vehicle"``).

    Returns
    -------
    VehicleParams

    Raises
    ------
    InputError
        Naming the field: not an object, an unknown key, a value that is not a
        finite number (``max_steer_rate`` may be ``null``), or a car that cannot be
        (:class:`VehicleParams`'s own checks, such as a wheelbase longer than the car).

    Examples
    --------
    >>> vehicle_from_json({"length": 5.0, "wheelbase": 3.0}).wheelbase
    3.0
    >>> vehicle_from_json({"lenght": 5.0})  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    rrtdrive.types.InputError: vehicle: unknown key(s) ['lenght'] (did you mean 'length'?); ...
    """
    if not isinstance(value, Mapping):
        raise InputError(
            f"{field}: expected an object of the car's fields ({', '.join(VEHICLE_KEYS)}), "
            f"got {json_kind(value)}"
        )
    unknown = sorted(str(k) for k in value if k not in VEHICLE_KEYS)
    if unknown:
        raise InputError(
            f"{field}: unknown key(s) {unknown}{did_you_mean(unknown[0], VEHICLE_KEYS)}; "
            f"allowed {', '.join(VEHICLE_KEYS)}"
        )
    for key, number in value.items():
        # Instant steering: null, or inf (gymnasium's spec JSON writes Infinity).
        if key == "max_steer_rate" and (number is None or number == math.inf):
            continue
        if not is_finite_number(number):
            unit = {"max_steer": "radians", "max_steer_rate": "rad/s"}.get(key, "metres")
            raise InputError(
                f"{field}.{key}: expected a finite number ({unit}), got {brief_repr(number)}"
            )
    try:
        return VehicleParams(**{k: (None if v is None else float(v)) for k, v in value.items()})
    except InputError as exc:  # VehicleParams names its fields "vehicle.<key>"
        raise InputError(f"{field}{str(exc).removeprefix('vehicle')}") from None
