"""Path-tracking controllers on the kinematic bicycle: pure pursuit, Stanley and LQR.

All share one protocol (:class:`Controller`: ``reset(path)``,
``control(state) -> (accel, steer)``), one speed profile with a PI loop and one
steering limit. Build one by name with :func:`make_controller`.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from rrtdrive.controllers.base import PathProjector, Projection, TrackingController
from rrtdrive.controllers.gears import GearSegment, gear_segments, mirror_path
from rrtdrive.controllers.lqr import LQR
from rrtdrive.controllers.pure_pursuit import PurePursuit
from rrtdrive.controllers.speed import SpeedConfig, SpeedController, SpeedProfile
from rrtdrive.controllers.stanley import Stanley
from rrtdrive.controllers.state import Controller, VehicleState
from rrtdrive.types import InputError, brief_repr

__all__ = [
    "CONTROLLERS",
    "LQR",
    "Controller",
    "GearSegment",
    "PathProjector",
    "Projection",
    "PurePursuit",
    "SpeedConfig",
    "SpeedController",
    "SpeedProfile",
    "Stanley",
    "TrackingController",
    "VehicleState",
    "gear_segments",
    "make_controller",
    "mirror_path",
]

CONTROLLERS: dict[str, Callable[..., TrackingController]] = {
    "pure-pursuit": PurePursuit,
    "stanley": Stanley,
    "lqr": LQR,
}


def make_controller(name: str, **options: object) -> TrackingController:
    """Build the controller ``name`` (``pure-pursuit``, ``stanley`` or ``lqr``).

    Parameters
    ----------
    name : str
        Registered name.
    **options
        Keyword arguments of the controller class (``vehicle``, ``speed``, gains).

    Raises
    ------
    InputError
        For an unknown name or option, or an option of the wrong type or value
        (naming it, ``controller.vehicle: expected a VehicleParams, got str 'car'``).

    Examples
    --------
    >>> make_controller("stanley").name
    'stanley'
    """
    if not isinstance(name, str):
        raise InputError(
            f"controller: expected a controller name, got {type(name).__name__} "
            f"{brief_repr(name)}; choose from {', '.join(sorted(CONTROLLERS))}"
        )
    try:
        cls = CONTROLLERS[name]
    except KeyError:
        raise InputError(
            f"controller: unknown controller {name!r}; choose from {', '.join(sorted(CONTROLLERS))}"
        ) from None
    known = _option_names(cls)
    for key in options:
        if known is not None and key not in known:
            raise InputError(
                f"controller.{key}: unknown option of {cls.__name__}; "
                f"choose from {', '.join(sorted(known))}"
            )
    try:
        return cls(**options)  # type: ignore[arg-type]
    except TypeError as exc:
        raise InputError(f"controller: {exc}") from None


def _option_names(cls: Callable[..., Any]) -> set[str] | None:
    """The keyword options ``cls`` takes (``None``: any, it has ``**kwargs``)."""
    import inspect

    params = list(inspect.signature(cls).parameters.values())
    if any(p.kind is inspect.Parameter.VAR_KEYWORD for p in params):
        return None
    return {p.name for p in params if p.kind is not inspect.Parameter.VAR_POSITIONAL}
