"""Oncoming traffic on the overtake road: deciding when the ego may pull out.

The planned path is static (it avoids the stopped car and the road edges); the
oncoming cars move. :class:`OncomingGate` decides, every control step, whether
the ego may enter the stretch of path where its body intrudes into the oncoming
lane (the *conflict zone*). Until it is committed, it holds the ego at a stop
line before the zone unless every oncoming car either has already passed the
zone or reaches it only after the ego, starting from rest at the stop line, has
left it again, with a time margin. Once the ego passes the stop line, or can no
longer stop comfortably before it while released, it is committed (the gate
never stops it in the other lane). A released gap is revoked only when half of
the margin is gone (hysteresis, no stop-and-go at the line).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from rrtdrive.controllers import SpeedConfig
from rrtdrive.speed_profile import actuator_profile
from rrtdrive.types import Path, VehicleParams
from rrtdrive.vehicle import footprint_corners

__all__ = ["ConflictZone", "conflict_zone", "OncomingGate"]


@dataclass(frozen=True)
class ConflictZone:
    """The stretch of a path where the body leaves the ego lane for the oncoming one.

    Attributes
    ----------
    s_in, s_out : float
        Arc lengths where the body first enters and last leaves the oncoming lane.
    x_lo, x_hi : float
        Range of x the body covers meanwhile (the road runs along x).
    """

    s_in: float
    s_out: float
    x_lo: float
    x_hi: float


def conflict_zone(
    path: Path, lane_y: float, lane_width: float, vehicle: VehicleParams
) -> ConflictZone | None:
    """Where the body on ``path`` crosses the centre line ``lane_y + lane_width / 2``.

    Returns ``None`` when it never does.
    """
    samples = path.samples
    if len(samples) < 2:
        return None
    corners = footprint_corners(samples[:, :3], vehicle)
    inside = np.any(corners[:, :, 1] > lane_y + lane_width / 2.0, axis=1)
    if not inside.any():
        return None
    idx = np.flatnonzero(inside)
    s = path.arc_length()
    zone = corners[idx[0] : idx[-1] + 1]
    return ConflictZone(
        float(s[idx[0]]), float(s[idx[-1]]), float(zone[:, :, 0].min()), float(zone[:, :, 0].max())
    )


class OncomingGate:
    """Hold the ego before the conflict zone until the oncoming lane is clear long enough.

    Parameters
    ----------
    zone : ConflictZone
        From :func:`conflict_zone`.
    profile_kappa : tuple of numpy.ndarray
        ``(s, kappa)`` of the path, to time the crossing with the speed profile.
    speed : SpeedConfig
        The speed profile settings the controller uses.
    vehicle : VehicleParams, optional
        The ego car: with a rate-limited steering actuator the crossing is timed by the
        same capped profile the controller drives
        (:func:`~rrtdrive.speed_profile.actuator_profile`),
        plus the comfort-mode loop's slower start (its command rises at ``comfort_jerk``).
        ``None``: an instant actuator.
    stop_gap : float
        Stop line this far (metres of arc) before ``zone.s_in``.
    margin_s : float
        Required time margin in seconds between the ego leaving the zone and the
        first oncoming car reaching it.
    """

    def __init__(
        self,
        zone: ConflictZone,
        profile_kappa: tuple[np.ndarray, np.ndarray],
        speed: SpeedConfig,
        stop_gap: float = 1.0,
        margin_s: float = 2.0,
        vehicle: VehicleParams | None = None,
    ) -> None:
        self.zone = zone
        self.s_stop = max(0.0, zone.s_in - stop_gap)
        self.margin_s = margin_s
        self.committed = False
        self.released = False
        self.decel = speed.decel
        self.waiting_steps = 0
        s, kappa = profile_kappa
        # Time to drive from the stop line (at rest) to the end of the zone.
        mask = (s >= self.s_stop) & (s <= zone.s_out + 1e-9)
        ss, kk = s[mask] - self.s_stop, kappa[mask]
        if len(ss) >= 2:
            # Conservative: this profile starts at rest and also stops at the zone's end.
            rate = None if vehicle is None else vehicle.max_steer_rate
            wheelbase = 1.0 if vehicle is None else vehicle.wheelbase
            v = actuator_profile(ss, kk, speed, 0.0, wheelbase, rate).v
            dt = np.diff(ss) / np.maximum(0.5 * (v[1:] + v[:-1]), 0.1)
            self.crossing_time = float(np.sum(dt))
            if rate is not None and math.isfinite(rate):
                # The comfort-mode loop ramps its command up at comfort_jerk: the car
                # starts later than the profile by about the time of that ramp.
                self.crossing_time += speed.accel / speed.comfort_jerk
        else:
            self.crossing_time = 0.0

    def stop_line(self, s: float, speed: float, cars: Sequence[Any]) -> float | None:
        """The arc length to stop at, or ``None`` to drive on.

        Parameters
        ----------
        s : float
            The ego's progress along the path.
        speed : float
            The ego's speed.
        cars : sequence
            Oncoming highway-env vehicles (``position``, ``speed``, ``LENGTH``).
        """
        if self.committed:
            return None
        if s > self.s_stop + 0.5:
            self.committed = True  # already pulling out: never stop in the other lane
            return None
        to_line = max(0.0, self.s_stop - s)
        t_line = to_line / max(speed, 1.0)
        # Hysteresis: once released, a gap is only revoked when half the margin is gone.
        margin = 0.5 * self.margin_s if self.released else self.margin_s
        t_out = t_line + self.crossing_time + margin
        for car in cars:
            v = max(float(car.speed), 0.0)
            rear = float(car.position[0]) + car.LENGTH / 2.0
            front = float(car.position[0]) - car.LENGTH / 2.0
            if rear < self.zone.x_lo:
                continue  # already past the zone
            if front <= self.zone.x_hi:
                break  # in the zone now
            t_arrive = (front - self.zone.x_hi) / v if v > 1e-6 else math.inf
            if t_arrive <= t_out:
                break
        else:
            self.released = True
            if speed * speed / (2.0 * self.decel) >= to_line and speed > 0.5:
                # Past the point where a comfortable stop before the line is possible.
                self.committed = True
            return None
        self.released = False
        self.waiting_steps += 1
        return self.s_stop
