"""Longitudinal control: a curvature-limited speed profile v(s) and a PI loop that tracks it.

The profile itself is :class:`rrtdrive.speed_profile.SpeedProfile` (shared with
space-time planning), re-exported here.

The profile obeys ``v(s) <= sqrt(a_lat_max / |kappa(s)|)`` and ``v(s) <= v_max``,
rises no faster than ``accel`` and falls no faster than ``decel`` (forward and
backward passes over arc length), and reaches zero at the end of the path. The
loop adds the profile's own acceleration ``v dv/ds`` as a feed-forward to a PI
correction on the speed error (its braking taken at the car's speed, ``speed dv/ds``,
when the car is slower than the profile), and holds the car once it has stopped at the
goal; a car that runs past the end stops within ``PAST_END_M`` when it arrives slower
than about 0.6 m/s (faster, within ``v^2 / (2 |a_min|)``: 0.40 m at 3 m/s).

For a car with a rate-limited steering actuator (``VehicleParams.max_steer_rate``)
the tracking controllers also cap the profile by the steering rate
(:func:`rrtdrive.speed_profile.steering_rate_speed_cap`, ``steer_rate_share``), hold
the car at rest until the wheels have turned to the path's initial angle
(``start_steer_tol``), and run the loop in comfort mode: every change of the
acceleration command is bounded by ``comfort_jerk`` (below nuPlan's |jerk| bound of
4.13 m/s^3), also while a car-following cap binds. A positive command is kept small
enough to ramp down to 0 at that bound before the car passes the highest reference
speed within reach (``a^2 / 2 comfort_jerk <= v_top - speed``), so the car does not
overshoot the top of a rise.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from rrtdrive.speed_profile import FINAL_APPROACH_M, SpeedProfile
from rrtdrive.types import InputError, require_finite, require_positive

__all__ = ["SpeedConfig", "SpeedProfile", "SpeedController", "FINAL_APPROACH_M", "PAST_END_M"]

#: A car that runs past the end of its path (or gear segment) stops within this (metres)
#: when it arrives slower than about 0.6 m/s; faster, the brake's ``a_min`` decides.
PAST_END_M = 0.05
#: The window of that stop never shrinks below this (metres): the brake stays finite.
PAST_END_FLOOR_M = 0.01
#: A car more than this behind the start of its path (or gear segment) drives up to it
#: at ``v_launch`` (metres; twice :data:`PAST_END_M`, so a car that stopped past a cusp
#: is never behind the next segment by this much).
BEHIND_START_M = 2 * PAST_END_M
#: Upper bound of the PI gains ``kp`` (1/s) and ``ki`` (1/s^2).
MAX_SPEED_GAIN = 15.0
#: Upper bound of ``stop_distance`` (metres): the evaluator's default goal tolerance.
MAX_STOP_DISTANCE_M = 0.5
#: Upper bound of ``stop_speed`` and ``taper_stop_speed`` (m/s): the hold cancels such a
#: speed in one step.
MAX_STOP_SPEED = 0.5


@dataclass(frozen=True)
class SpeedConfig:
    """Tunables of the speed profile and its PI loop.

    Parameters
    ----------
    v_max : float
        Speed cap in m/s.
    v_max_reverse : float
        Speed cap of reverse gear segments in m/s (the profile there is capped by
        ``min(v_max, v_max_reverse)``).
    accel_manoeuvre : float
        Largest acceleration and deceleration of the profile (m/s^2) on every gear
        segment of a path with gear changes or reverse driving: short segments that
        each end in a stop, which the loop must hit within centimetres.
    a_lat_max : float
        Lateral-acceleration cap in m/s^2 (sets ``v <= sqrt(a_lat_max / |kappa|)``).
    accel : float
        Largest acceleration of the profile in m/s^2.
    decel : float
        Largest deceleration of the profile in m/s^2 (positive number).
    v_launch : float
        Speed the profile starts from when the car is at rest, so it gets going.
    kp, ki : float
        PI gains on the speed error (1/s and 1/s^2), at most 15 each.
    a_min, a_max : float
        Limits of the commanded acceleration in m/s^2 (``a_min`` < 0 < ``a_max``).
    stop_distance : float
        The car counts as arrived when it is this close to the end (metres, at most
        0.5) ...
    stop_speed : float
        ... and slower than this (m/s, at most 0.5); from then on it is held at rest.
    jerk_max : float
        Largest rate of rise of the acceleration command in m/s^3 (smooth starts).
    jerk_brake_max : float or None
        Largest rate of *fall* of the command in m/s^3 (smooth braking onsets);
        ``None``: falls are not limited. Never applies while
        :attr:`SpeedController.accel_cap` binds (a car-following law must be able to
        brake at once) nor to the stop past the end of the path.
    stop_taper : bool
        The stop at the end of the path brakes with a deceleration that fades
        linearly to zero (the constant-jerk stop through the remaining distance
        ``d``: ``a = -2 v^2 / (3 d)``), starting where that law asks for at least
        ``taper_start`` of ``decel`` within the last 2 m, and holds the car once it
        is slower than ``taper_stop_speed``; so braking does not end with a jump at
        standstill. ``False``: the constant ``-v^2 / (2 d)`` of the last 2 m and the
        hold below ``stop_speed``.
    taper_start : float
        See ``stop_taper``; in ``(0, 1]``.
    taper_stop_speed : float
        See ``stop_taper`` (m/s, at most 0.5).
    steer_rate_share : float
        Rate-limited actuator only: the share of ``max_steer_rate`` the path's own
        steering may use (``v <= share * rate / |d delta/ds|``); the rest is left
        to the controller's corrections. In ``(0, 1]``.
    start_steer_tol : float
        Rate-limited actuator only: at the start of a path the car stays at rest
        until its steering angle is within this of the controller's command (rad).
    comfort_jerk : float
        Rate-limited actuator only (comfort mode): largest rise and fall of the
        acceleration command in m/s^3, in every phase but the last stopping steps.
    comfort_a_max : float
        Rate-limited actuator only (comfort mode): the command's upper limit in m/s^2
        instead of ``a_max`` when that is larger. nuPlan reads the acceleration at the
        body centre through its filters, which adds to the command while the car
        turns and re-accelerates (2 m/s^2 commanded read as up to 3.3 m/s^2 in
        overtake-traffic against its bound of 2.40).
    """

    v_max: float = 3.0
    v_max_reverse: float = 1.5
    accel_manoeuvre: float = 0.5
    a_lat_max: float = 1.5
    accel: float = 1.0
    decel: float = 1.0
    v_launch: float = 0.5
    kp: float = 2.0
    ki: float = 0.3
    a_min: float = -4.0
    a_max: float = 2.0
    stop_distance: float = 0.05
    stop_speed: float = 0.05
    jerk_max: float = 5.0
    jerk_brake_max: float | None = 5.0
    stop_taper: bool = True
    taper_start: float = 0.75
    taper_stop_speed: float = 0.01
    steer_rate_share: float = 0.7
    start_steer_tol: float = 0.005
    comfort_jerk: float = 2.0
    comfort_a_max: float = 1.5

    def __post_init__(self) -> None:
        for name in (
            "v_max", "v_max_reverse", "accel_manoeuvre", "a_lat_max", "accel", "decel",
            "stop_distance", "stop_speed", "jerk_max", "taper_stop_speed", "start_steer_tol",
            "comfort_jerk", "comfort_a_max",
        ):
            require_positive(f"speed.{name}", getattr(self, name))
        for name in ("v_launch", "kp", "ki", "a_min", "a_max"):
            require_finite(f"speed.{name}", getattr(self, name))
        if self.v_launch < 0 or self.kp < 0 or self.ki < 0:
            raise InputError("speed.v_launch, speed.kp, speed.ki: must be >= 0")
        for name in ("kp", "ki"):
            # Larger gains make the command chatter at the slowest simulation frequency
            # (15 Hz): kp 30 switched its sign 49 times on a 20 m straight, the default 3.
            if getattr(self, name) > MAX_SPEED_GAIN:
                raise InputError(
                    f"speed.{name}: must be <= {MAX_SPEED_GAIN:g}, got {getattr(self, name)!r}"
                )
        for name, top in (("stop_distance", MAX_STOP_DISTANCE_M), ("stop_speed", MAX_STOP_SPEED),
                          ("taper_stop_speed", MAX_STOP_SPEED)):  # fmt: skip
            # The arrival window: a car held at rest farther than the evaluator's goal
            # tolerance is not at its goal, and a gear segment no longer than
            # stop_distance is skipped as a stub.
            if getattr(self, name) > top:
                raise InputError(f"speed.{name}: must be <= {top:g}, got {getattr(self, name)!r}")
        if self.v_launch > self.v_max:
            # A car behind its path's start drives up at v_launch: 6 m/s with a 3 m/s cap.
            raise InputError(
                f"speed.v_launch: must be <= v_max ({self.v_max:g} m/s), got {self.v_launch!r}"
            )
        if self.jerk_brake_max is not None:
            require_positive("speed.jerk_brake_max", self.jerk_brake_max)
        if not isinstance(self.stop_taper, bool):
            raise InputError(f"speed.stop_taper: expected true or false, got {self.stop_taper!r}")
        require_finite("speed.taper_start", self.taper_start)
        if not 0.0 < self.taper_start <= 1.0:
            raise InputError(f"speed.taper_start: must lie in (0, 1], got {self.taper_start!r}")
        require_finite("speed.steer_rate_share", self.steer_rate_share)
        if not 0.0 < self.steer_rate_share <= 1.0:
            raise InputError(
                f"speed.steer_rate_share: must lie in (0, 1], got {self.steer_rate_share!r}"
            )
        if not self.a_min < 0 < self.a_max:
            raise InputError(
                f"speed.a_min/a_max: need a_min < 0 < a_max, got {self.a_min}, {self.a_max}"
            )


class SpeedController:
    """PI tracking of a :class:`SpeedProfile` with a stop at the end of the path.

    Setting :attr:`stop_at` (an arc length) adds a stop line: the reference is
    capped by ``sqrt(2 decel (stop_at - s))`` and the car is held there until the
    attribute is cleared. Setting :attr:`accel_cap` (m/s^2) caps the command, for
    example by a car-following law (IDM) behind a slower car; while it binds, the
    integral is frozen (the same anti-windup as the other limits).

    Parameters
    ----------
    config : SpeedConfig
        Gains and limits.
    comfort : bool
        Comfort mode: rises and falls of the command are both bounded by
        ``config.comfort_jerk`` (and rises also by ``jerk_max``), while the
        car-following cap binds too.
    """

    def __init__(self, config: SpeedConfig, comfort: bool = False) -> None:
        self.config = config
        self.comfort = comfort
        self.profile: SpeedProfile | None = None
        self.integral = 0.0
        self.last_t: float | None = None
        self.arrived = False
        self.v_ref = 0.0
        self.stop_at: float | None = None
        self.accel_cap: float | None = None
        self.last_a = 0.0
        self.tapering = False
        self.line_taper = False

    def retarget(self, profile: SpeedProfile) -> None:
        """Track ``profile`` from now on, keeping the loop's state (integral, last command).

        For a path that continues the current one (stitched at the car's position),
        so that the command does not jump; :meth:`reset` starts from scratch.

        Parameters
        ----------
        profile : SpeedProfile
            The new reference; arrival and any stop line (:attr:`stop_at`) are cleared.
        """
        self.profile = profile
        self.arrived = False
        self.stop_at = None
        self.tapering = False
        self.line_taper = False

    def reset(self, profile: SpeedProfile) -> None:
        """Track ``profile`` from scratch.

        Parameters
        ----------
        profile : SpeedProfile
            The reference; the integral, last command, stop line and cap are cleared.
        """
        self.profile = profile
        self.integral = 0.0
        self.last_t = None
        self.arrived = False
        self.v_ref = 0.0
        self.stop_at = None
        self.accel_cap = None
        self.last_a = 0.0
        self.tapering = False
        self.line_taper = False

    def ends_at(self, s: float) -> bool:
        """Whether arc length ``s`` is within ``stop_distance`` of the profile's end.

        A car at rest there has arrived: :meth:`control` holds it, and a gear segment
        no longer than that (a stub) ends as soon as it starts.

        Parameters
        ----------
        s : float
            Arc length along the profile, metres.

        Returns
        -------
        bool
            False before :meth:`reset`.
        """
        profile = self.profile
        return profile is not None and profile.length - s <= self.config.stop_distance

    def control(self, s: float, speed: float, t: float) -> float:
        """Acceleration command for the car at arc length ``s`` with ``speed`` at time ``t``.

        Parameters
        ----------
        s : float
            The car's arc length along the profile, metres (negative behind its start,
            above ``profile.length`` past its end).
        speed : float
            The car's speed in the profile's direction of travel, m/s.
        t : float
            Simulation time, seconds; the step since the last call drives the integral
            and the jerk limits.

        Returns
        -------
        float
            Acceleration command in m/s^2, within ``[a_min, a_max]``.

        Raises
        ------
        RuntimeError
            When called before :meth:`reset`.
        """
        cfg = self.config
        profile = self.profile
        if profile is None:
            raise RuntimeError("SpeedController.control called before reset")
        dt = 0.0 if self.last_t is None else max(0.0, t - self.last_t)
        self.last_t = t
        remaining = profile.length - s
        stop_speed = cfg.taper_stop_speed if cfg.stop_taper else cfg.stop_speed
        if self.arrived or (self.ends_at(s) and abs(speed) <= stop_speed):
            # At the goal: hold the car at rest.
            self.arrived = True
            self.v_ref = 0.0
            return self._hold(speed, dt)
        tau = 0.0
        if self.comfort:
            # Read the profile ahead by half the time the jerk bound needs to swing the
            # command through the profile's acceleration range: the jerk-limited ramp then
            # straddles the profile's corners instead of starting at them (and lagging).
            tau = 0.5 * max(cfg.accel, cfg.decel) / cfg.comfort_jerk
            v_ref, a_ref = profile.at(s + abs(speed) * tau)
        else:
            v_ref, a_ref = profile.at(s)
        # In either gear: the profile does not say which.
        approach = min(cfg.v_launch, cfg.v_max_reverse)
        if s < -BEHIND_START_M and v_ref < approach:
            # Before the start the profile is at rest (a car starting there waits for its
            # wheels): a car behind it crept, the integral wound up against the zero
            # reference and it stopped for good (3.5 m or more short, or 12 cm behind a
            # 5-20 mm segment).
            v_ref, a_ref = approach, 0.0
        if remaining <= 0.0:
            # Past the end: stop within PAST_END_M of it. The window shrinks as the car
            # runs on (a fixed one, asked anew each step, lets the car crawl on: the
            # deceleration v^2 / 2d fades with the speed; 0.19 m and 1.6 s at a cusp).
            self.v_ref = 0.0
            return self._brake(speed, dt, max(PAST_END_M + remaining, PAST_END_FLOOR_M))
        if self.stop_at is None:
            self.line_taper = False
        else:
            # A stop line (for example: wait for oncoming traffic) caps the profile.
            d = self.stop_at - s
            if self.comfort:
                a_line = self._line_stop(d, speed, dt)
                if a_line is not None:
                    return a_line
            if d <= cfg.stop_distance:
                # Within ``stop_distance`` of the line: stop within PAST_END_M; past it,
                # within what is left of that (as past the end of the path).
                self.v_ref = 0.0
                return self._brake(
                    speed, dt, max(d, PAST_END_M + min(d, 0.0), PAST_END_FLOOR_M)
                )
            # Comfort mode reads the cap ahead like the profile (the ramp of the
            # jerk-limited command then starts before the braking, not after it).
            ahead = d - abs(speed) * tau if self.comfort else d
            v_cap = math.sqrt(2.0 * cfg.decel * max(ahead, 0.0))
            if v_cap < v_ref:
                v_ref = v_cap
                a_ref = -speed * speed / (2.0 * max(d, cfg.stop_distance)) if speed > 0 else 0.0
        self.v_ref = v_ref
        if remaining < FINAL_APPROACH_M and speed > 0.0:
            if cfg.stop_taper:
                # The constant-jerk stop through the remaining distance: a state feedback
                # whose solution from any (v, d) is that stop, its deceleration fading
                # to 0 at the end. It starts once it asks for a real deceleration (a car
                # slower than the profile would otherwise creep to the end).
                a_stop = -2.0 * speed * speed / (3.0 * max(remaining, 1e-3))
                if self.tapering or a_stop <= -cfg.taper_start * cfg.decel:
                    self.tapering = True
                    self.v_ref = 0.0
                    self.integral = 0.0
                    fall = cfg.comfort_jerk if self.comfort else cfg.jerk_brake_max
                    return self._limit(a_stop, dt, fall)
            else:
                # Final approach: the constant deceleration that stops exactly at the end.
                a_ref = min(a_ref, -speed * speed / (2.0 * max(remaining, cfg.stop_distance)))
        if a_ref < 0.0 and 0.0 <= speed < v_ref:
            # The profile's braking at the car's own speed: a_ref is v_ref dv/ds, and a
            # car slower than v_ref brakes speed dv/ds. Taken whole, it stopped cars 9 cm
            # short of a cusp, then held them creeping at 1 cm/s for seconds.
            a_ref *= speed / v_ref
        err = v_ref - speed
        trial = self.integral + err * dt
        raw = a_ref + cfg.kp * err + cfg.ki * trial
        if self.comfort and raw > 0.0 and speed >= 0.0:
            # Ramping a command a down to 0 at the jerk bound gains a^2 / 2J of speed:
            # keep that within the highest reference the ramp can reach, or the car
            # overshoots the top of a rise (and brakes harder later).
            ramp = raw / cfg.comfort_jerk
            reach = speed * (ramp + tau) + raw * ramp * ramp / 3.0
            # From the segment's start at the latest: a car standing behind it (past a
            # cusp, or where a stub too short to drive ended) read only the profile's
            # standstill before it, was capped to 0 and never moved again.
            here = max(s, 0.0)
            room = max(profile.peak(here, here + reach) - speed, 0.0)
            raw = min(raw, math.sqrt(2.0 * cfg.comfort_jerk * room))
        cap = self.accel_cap
        capped = cap is not None and raw > cap
        target = cap if cap is not None and capped else raw
        if self.comfort:
            a = self._limit(target, dt, cfg.comfort_jerk)
        else:
            a = self._limit(target, dt, None if capped else cfg.jerk_brake_max)
        if a == raw:
            # Conditional integration (anti-windup): only while the command is not limited.
            limit = cfg.a_max / cfg.ki if cfg.ki > 0 else 0.0
            self.integral = min(max(trial, -limit), limit)
        return a

    def _line_stop(self, d: float, speed: float, dt: float) -> float | None:
        """Comfort mode: the jerk-limited stop at the stop line ``d`` metres ahead, or ``None``.

        The constant-jerk stop through ``d`` (``a = -2 v^2 / (3 d)``, its deceleration
        fading to 0 at the line, as the stop at the end of the path) starts where it
        asks for ``taper_start`` of ``decel``; its onset falls at most ``comfort_jerk``.
        The stop at the line comes first: when that law asks for more than twice
        ``decel`` (the gate revoked a release close to the line) the fall is limited by
        ``jerk_brake_max`` only, and a car still moving at or past the line gets the
        plain brake of :meth:`_brake` (``None`` is returned then, as before the taper
        starts). Once slower than ``taper_stop_speed`` the car is held.
        """
        cfg = self.config
        if speed <= 0.0:
            self.line_taper = False
            return None
        if self.line_taper and speed <= cfg.taper_stop_speed:
            self.v_ref = 0.0
            return self._hold(speed, dt)
        if d <= (0.0 if self.line_taper else cfg.stop_distance):
            return None
        a_stop = -2.0 * speed * speed / (3.0 * d)
        if not (self.line_taper or a_stop <= -cfg.taper_start * cfg.decel):
            return None
        self.line_taper = True
        self.v_ref = 0.0
        self.integral = 0.0
        fall = cfg.comfort_jerk if a_stop >= -2.0 * cfg.decel else cfg.jerk_brake_max
        return self._limit(a_stop, dt, fall)

    def _hold(self, speed: float, dt: float) -> float:
        """Keep a (nearly) stopped car at rest: cancel the residual speed, no more."""
        self.integral = 0.0
        if speed == 0.0:
            a = 0.0
        else:
            a = -speed / dt if dt > 0 else -self.config.kp * speed
        a = min(max(a, self.config.a_min), self.config.a_max)
        self.last_a = a
        return a

    def _brake(self, speed: float, dt: float, distance: float) -> float:
        """Stop within ``distance``: the constant deceleration ``v^2 / 2d``, held once stopped."""
        if abs(speed) <= self.config.stop_speed:
            return self._hold(speed, dt)
        self.integral = 0.0
        a = -speed * abs(speed) / (2.0 * distance)
        a = min(max(a, self.config.a_min), self.config.a_max)
        self.last_a = a
        return a

    def _limit(self, a: float, dt: float, fall_jerk: float | None = None) -> float:
        """Clip to the acceleration limits; rises at most ``jerk_max``, falls ``fall_jerk``."""
        cfg = self.config
        a_max = min(cfg.a_max, cfg.comfort_a_max) if self.comfort else cfg.a_max
        a = min(max(a, cfg.a_min), a_max)
        jerk = min(cfg.jerk_max, cfg.comfort_jerk) if self.comfort else cfg.jerk_max
        rise = self.last_a + jerk * dt
        if a > rise:
            a = rise
        if fall_jerk is not None:
            a = max(a, self.last_a - fall_jerk * dt)
        self.last_a = a
        return a
