"""Car following behind a slower car: the ego's IDM law and the gap it is fed.

While the traffic re-planner (:mod:`rrtdrive.sim.traffic_driver`) is in ``follow``
mode, the speed loop's command is capped by Treiber's IDM behind the nearest
same-direction car ahead in the ego's lane (:func:`lead_gap`).

This is our own IDM, not highway-env's ``IDMVehicle.acceleration``: that one works
on body centres along highway-env lanes with its class constants (``DISTANCE_WANTED``,
``TIME_WANTED``, ``COMFORT_ACC_MAX``...) and ``lane_distance_to``, while the ego is a
rear-axle car whose gap is measured from its front bumper; feeding the same
numbers through it would not give bit-identical commands, so the recorded traffic
results would change.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from rrtdrive.types import InputError, VehicleParams, require_finite, require_positive

__all__ = ["IDMConfig", "lead_gap"]


@dataclass(frozen=True)
class IDMConfig:
    """The ego's car-following law behind a slower car (Treiber's IDM).

    ``a_idm = a (1 - (v / v0)^delta - (s* / s)^2)``, ``s* = s0 + v T + v dv / (2 sqrt(a b))``
    with ``s`` the bumper-to-bumper gap and ``dv`` the closing speed; it caps the
    speed loop's command while following.

    Parameters
    ----------
    accel : float
        ``a``, largest acceleration (m/s^2).
    comfort_decel : float
        ``b``, comfortable deceleration (m/s^2, positive).
    time_headway : float
        ``T``, desired time gap (s).
    min_gap : float
        ``s0``, gap at standstill (m).
    delta : float
        Free-road exponent.
    pull_out_gap : float
        Desired gap behind a stopped car (m): room to pull out round it
        (:attr:`~rrtdrive.sim.replanning.ReplanConfig.pull_out_speed`); within
        IDM's 4 m a car leaves a stopped lead only by reversing. ``s*`` is at least
        ``pull_out_gap - pull_out_time * v_lead`` (braking for it as for
        ``s0 + v T``): at the lead's speed it binds below 3.3 m/s only.
        ``0``: plain IDM.
    pull_out_time : float
        Seconds the lead drives on while the ego pulls out: a moving lead leaves
        room of its own.

    Examples
    --------
    >>> round(IDMConfig().accel_for(4.0, 11.0, 10.0, 0.0), 3)  # at the desired gap: about 0
    -0.026
    """

    accel: float = 1.5
    comfort_decel: float = 2.0
    time_headway: float = 1.5
    min_gap: float = 4.0
    delta: float = 4.0
    pull_out_gap: float = 14.0
    pull_out_time: float = 1.5

    def __post_init__(self) -> None:
        for name in ("accel", "comfort_decel", "time_headway", "min_gap", "delta"):
            require_positive(f"idm.{name}", getattr(self, name))
        for name in ("pull_out_gap", "pull_out_time"):
            value = getattr(self, name)
            require_finite(f"idm.{name}", value)
            if value < 0.0:
                raise InputError(f"idm.{name}: must be >= 0, got {value!r}")

    def accel_for(self, v: float, v0: float, gap: float, closing: float) -> float:
        """IDM acceleration at speed ``v`` (desired ``v0``), ``gap`` metres behind, ``closing``."""
        brake = 2.0 * math.sqrt(self.accel * self.comfort_decel)
        s_star = self.min_gap + max(0.0, v * self.time_headway + v * closing / brake)
        # Behind a slow car keep room to pull out (the lead's speed is v - closing),
        # braking for it as for s0 + v T.
        floor = self.pull_out_gap - self.pull_out_time * max(v - closing, 0.0)
        if floor > self.min_gap + v * self.time_headway:
            s_star = max(s_star, floor + max(0.0, v * closing / brake))
        free = (max(v, 0.0) / v0) ** self.delta if v0 > 0 else 1.0
        return self.accel * (1.0 - free - (s_star / max(gap, 0.1)) ** 2)


def lead_gap(
    ego: Any, others: Sequence[Any], vehicle: VehicleParams
) -> tuple[float, float] | None:
    """Bumper gap to, and closing speed on, the nearest same-direction car ahead in the lane.

    Parameters
    ----------
    ego : EgoVehicle
        The ego (rear-axle pose ``rear``, ``speed``).
    others : sequence
        The other highway-env vehicles (``position``, ``heading``, ``speed``,
        ``LENGTH``, ``WIDTH``).
    vehicle : VehicleParams
        The ego's dimensions.

    Returns
    -------
    tuple of float or None
        ``(gap, closing speed)``, or ``None`` when no car is ahead in the lane.
    """
    x, y, yaw = ego.rear
    front = x + vehicle.front_extent * math.cos(yaw)
    ego_y = y + (vehicle.length / 2.0 - vehicle.rear_overhang) * math.sin(yaw)
    best: tuple[float, float] | None = None
    for v in others:
        if math.cos(v.heading - yaw) <= 0.0:
            continue  # oncoming
        if abs(v.position[1] - ego_y) > (vehicle.width + v.WIDTH) / 2.0 + 0.3:
            continue
        gap = v.position[0] - v.LENGTH / 2.0 - front
        if v.position[0] <= x or (best is not None and gap >= best[0]):
            continue
        best = (gap, ego.speed - v.speed * math.cos(v.heading - yaw))
    return best
