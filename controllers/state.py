"""The controller seam: what a controller sees and does: VehicleState, the Controller protocol.

Also the approach-angle setting that LQR and pure pursuit share
(:data:`APPROACH_ANGLE`, :func:`checked_approach_angle`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

from rrtdrive.types import InputError, Path, require_finite

__all__ = ["APPROACH_ANGLE", "Controller", "VehicleState", "checked_approach_angle"]

_STATE_FIELDS = ("x", "y", "yaw", "speed", "steer", "t")

#: Default largest heading (rad) off the path's direction at which LQR and pure
#: pursuit steer a car back from far off. A sweep on the 0.4 rad/s car (offsets
#: 0.5-4 m, heading errors up to 0.6 rad, 3-10 m/s) settled every case at 0.2 and
#: 0.15; at 0.3 pure pursuit took 80 m to settle from a 0.4 rad heading error at 3 m/s,
#: and from 0.4 some cases never settled.
APPROACH_ANGLE = 0.2


def checked_approach_angle(name: str, value: float) -> float:
    """``value`` as a float in ``(0, pi/2)``, or an :class:`InputError` naming ``name``."""
    require_finite(name, value)
    if not 0.0 < value < 0.5 * math.pi:
        raise InputError(f"{name}: must lie in (0, pi/2) radians, got {value!r}")
    return float(value)


@dataclass(frozen=True)
class VehicleState:
    """What a controller sees each step: the rear-axle pose, speed and current steering.

    Parameters
    ----------
    x, y, yaw : float
        Rear-axle pose (metres, radians).
    speed : float
        Longitudinal speed in m/s.
    steer : float
        Front-wheel angle applied in the last step, radians.
    t : float
        Simulation time in seconds.

    Raises
    ------
    InputError
        Unless every field is a finite real number (naming it: ``state.x: ...``).
    """

    x: float
    y: float
    yaw: float
    speed: float = 0.0
    steer: float = 0.0
    t: float = 0.0

    def __post_init__(self) -> None:
        # A NaN pose failed deep in the projection (IndexError) and an infinite one
        # steered NaN silently: refuse them here, where the field is known.
        for name in _STATE_FIELDS:
            require_finite(f"state.{name}", getattr(self, name))


@runtime_checkable
class Controller(Protocol):
    """A path-tracking controller on the kinematic bicycle."""

    name: str

    def reset(self, path: Path) -> None:
        """Start tracking ``path`` (clears all internal state).

        Parameters
        ----------
        path : Path
            The path to track: rear-axle samples ``[x, y, yaw, kappa, gear]``.
        """
        ...

    def control(self, state: VehicleState) -> tuple[float, float]:
        """Return ``(acceleration m/s^2, steering angle rad)`` for ``state``.

        Parameters
        ----------
        state : VehicleState
            The car now: rear-axle pose, signed speed, current steering, time.

        Returns
        -------
        accel, steer : float
            Acceleration command (m/s^2) and front-wheel angle (rad, left positive).
        """
        ...
