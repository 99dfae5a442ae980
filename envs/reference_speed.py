"""The reference speed ``v_ref`` the gym env observes and rewards against.

``v_ref`` is the speed the car is actually asked to drive: the speed profile at
the rear axle's projection, capped by a stop line the speed loop holds (the
oncoming-traffic gate) and, while the traffic driver follows a slower car, by the
speed its car-following law (IDM) settles to at the current gap. Without these
caps a car that rightly follows a 4 m/s lead would be punished for not driving
the 11 m/s of the profile (issue #15).
"""

from __future__ import annotations

import math
from typing import Any

from rrtdrive.controllers import SpeedConfig

__all__ = ["Relaunch", "following_cap", "following_speed", "stop_line_speed"]

#: Bisection steps of :func:`following_speed` (the bracket [0, v0] shrinks 2^-40).
_BISECT_STEPS = 40


def stop_line_speed(v_ref: float, s: float, stop_at: float | None, speed: SpeedConfig) -> float:
    """``v_ref`` capped by the speed loop's stop line at arc length ``stop_at``.

    As :meth:`~rrtdrive.controllers.SpeedController.control`: 0 within
    ``stop_distance`` of the line, else at most ``sqrt(2 decel (stop_at - s))``.

    Examples
    --------
    >>> cfg = SpeedConfig(v_max=5.0, decel=1.0)
    >>> stop_line_speed(5.0, 0.0, None, cfg), stop_line_speed(5.0, 10.0, 12.0, cfg)
    (5.0, 2.0)
    >>> stop_line_speed(5.0, 12.0, 12.0, cfg)
    0.0
    """
    if stop_at is None:
        return v_ref
    d = stop_at - s
    if d <= speed.stop_distance:
        return 0.0
    return min(v_ref, math.sqrt(2.0 * speed.decel * d))


class Relaunch:
    """``v_ref`` after a stop line lets the car go: a rise at ``accel``, not a jump.

    Released at rest 0 m into a 6.5 m/s stretch of the profile, ``v_ref`` jumped to
    6.5 m/s while the speed loop can accelerate at ``comfort_a_max``: the speed term
    cost the plain controller 440 per start (the +50 success bonus nine times over).
    From the release, ``v_ref <= sqrt(v0^2 + 2 accel (s - s0))``, the speed the car
    reaches from its speed ``v0`` there at the loop's largest acceleration.

    Parameters
    ----------
    accel : float
        The speed loop's largest acceleration command, m/s^2.
    """

    def __init__(self, accel: float) -> None:
        self.accel = accel
        self.held = False
        self.start: tuple[float, float] | None = None

    def update(self, stop_at: float | None, s: float, speed: float) -> None:
        """The loop's stop line now (``None``: none) with the car at ``s``, ``speed``."""
        if self.held and stop_at is None:
            self.start = (s, max(speed, 0.0))
        self.held = stop_at is not None

    def cap(self, s: float) -> float:
        """The cap at arc length ``s`` (infinity before any release)."""
        if self.start is None:
            return math.inf
        s0, v0 = self.start
        return math.sqrt(v0 * v0 + 2.0 * self.accel * max(s - s0, 0.0))


def following_speed(idm: object, v0: float, gap: float, v_lead: float) -> float:
    """The speed at which the car-following law asks for no acceleration.

    The ``v`` in ``[0, v0]`` with ``idm.accel_for(v, v0, gap, v - v_lead) = 0``
    (found by bisection): ``v_lead`` at the law's equilibrium gap, more when the
    gap is larger, less when it is smaller; 0 within the standstill gap.

    Parameters
    ----------
    idm : IDMConfig
        The law (:class:`~rrtdrive.sim.replanning.IDMConfig`, its ``accel_for``).
    v0 : float
        Desired (free-road) speed, m/s.
    gap : float
        Bumper-to-bumper gap to the lead car, m.
    v_lead : float
        The lead car's speed along the ego's heading, m/s.

    Examples
    --------
    >>> from rrtdrive.sim.replanning import IDMConfig
    >>> idm = IDMConfig()
    >>> v = following_speed(idm, 11.0, 10.0, 4.0)  # about the desired gap behind 4 m/s
    >>> round(v, 2), round(following_speed(idm, 11.0, 500.0, 4.0), 2)
    (3.97, 10.98)
    """
    accel_for = idm.accel_for  # type: ignore[attr-defined]
    if accel_for(0.0, v0, gap, -v_lead) <= 0.0:
        return 0.0
    lo, hi = 0.0, v0
    for _ in range(_BISECT_STEPS):
        mid = 0.5 * (lo + hi)
        if accel_for(mid, v0, gap, mid - v_lead) > 0.0:
            lo = mid
        else:
            hi = mid
    return lo


def following_cap(driver: Any, ego_speed: float) -> float:
    """The car-following cap of ``v_ref`` while ``driver`` follows a car; else infinity.

    A driver that follows (the traffic driver in its ``follow`` mode, with a car
    ahead in the lane: its :meth:`lead_gap`) is capped at :func:`following_speed`
    for its IDM at the current gap; a driver without car following (a path
    tracker) is not capped.

    Parameters
    ----------
    driver : Driver
        The episode's driver (:class:`~rrtdrive.sim.traffic_driver.TrafficDriver`
        or :class:`~rrtdrive.sim.loop.PathTracker`).
    ego_speed : float
        The ego's speed, m/s.
    """
    if getattr(driver, "mode", None) != "follow":
        return math.inf
    # The driver's own gap measure, the one its IDM cap uses (read-only).
    lead = driver.lead_gap()
    if lead is None:
        return math.inf
    gap, closing = lead
    return following_speed(driver.config.idm, driver.speed.v_max, gap, ego_speed - closing)
