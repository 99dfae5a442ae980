"""The action of the gym env: its mapping to a command, and residual mode.

Residual mode adds the action to a tracking controller's command.

The action ``[a, d]`` in ``[-1, 1]^2`` maps to an acceleration (``a a_max`` above
0, ``a |a_min|`` below) and a steering angle (``d steer_limit``) by
:func:`action_command`. In residual mode :class:`ResidualMixer` adds it to the
controller's command within the speed loop's acceleration and jerk limits and
fades it out over the last :data:`RESIDUAL_FADE_M` of the path, so that a zero
action is the plain controller exactly.

The action is a ``float32`` Box ``[-1, 1]^2``. Acceleration ``a * a_max``
for ``a >= 0`` and ``a * |a_min|`` below (the speed loop's limits, 2 and -4
m/s^2 by default, so 0 means coasting); steering ``d * steer_limit`` with
``steer_limit = atan(L kappa_max)`` (22.7°, the car's curvature limit). With
``residual=True`` the command is the controller's plus the action mapped the
same way and multiplied by ``residual_scale``, clipped to the same limits and,
for the acceleration, to the speed loop's jerk limits around the last applied
command (:meth:`ResidualMixer.accel`);
once the controller holds the car at the end of the path, or brakes past it,
the residual no longer applies (so a zero action is the plain controller, and
no residual can keep the car from coming to rest at the goal).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from rrtdrive.controllers import SpeedConfig
from rrtdrive.types import InputError, brief_repr

__all__ = ["RESIDUAL_FADE_M", "CommandLimits", "ResidualMixer", "action_command"]

#: Residual mode: the residual fades out linearly over this many metres before the goal.
RESIDUAL_FADE_M = 1.0


@dataclass(frozen=True)
class CommandLimits:
    """The command range an action spans.

    Parameters
    ----------
    a_min : float
        Largest deceleration, m/s^2 (< 0): the speed loop's ``a_min``.
    a_max : float
        Largest acceleration, m/s^2 (> 0): the speed loop's ``a_max``.
    steer_limit : float
        Largest steering angle, rad (> 0): ``atan(L kappa_max)``, the controller's.
    """

    a_min: float
    a_max: float
    steer_limit: float

    def __post_init__(self) -> None:
        for name, sign in (("a_min", -1.0), ("a_max", 1.0), ("steer_limit", 1.0)):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and sign * v > 0):
                raise InputError(
                    f"limits.{name}: need a finite number of sign {sign:+g}, got {v!r}"
                )


def action_command(
    action: Any, limits: CommandLimits, scale: float | None = None
) -> tuple[float, float]:
    """The ``(acceleration, steering)`` an action asks for (its residual in residual mode).

    Parameters
    ----------
    action : array_like
        Two finite numbers; each is clipped to ``[-1, 1]``.
    limits : CommandLimits
        The command range.
    scale : float, optional
        Residual mode: the action is first multiplied by this.

    Returns
    -------
    tuple of float

    Raises
    ------
    InputError
        Unless the action is two finite numbers (not strings, booleans or objects).

    Examples
    --------
    >>> lim = CommandLimits(a_min=-4.0, a_max=2.0, steer_limit=0.4)
    >>> action_command([0.5, -1.0], lim), action_command([-0.5, 2.0], lim, scale=0.5)
    ((1.0, -0.4), (-1.0, 0.2))
    """
    try:
        raw = np.asarray(action)
    except ValueError:  # a ragged sequence
        raw = None
    if raw is not None and raw.dtype.kind == "O" and all(
        isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, bool)
        for v in raw.reshape(-1)
    ):
        try:
            raw = raw.astype(np.float64)
        except OverflowError:  # an int past the largest float: not a finite number
            raise InputError(
                f"action: expected two finite numbers, got {brief_repr(action)}"
            ) from None
    # Only numbers: np.asarray(..., float) would also read strings ("0.5") as numbers,
    # and a string, None or an object would fail with a message not naming the action.
    if raw is None or raw.dtype.kind not in "iuf":
        raise InputError(
            f"action: expected two finite numbers, got {type(action).__name__} "
            f"{brief_repr(action)}"
        )
    # Exactly (2,): a batch of one, (1, 2), was read as one action (an audit).
    a = raw.astype(np.float64)
    if a.shape != (2,) or not np.all(np.isfinite(a)):
        raise InputError(f"action: expected two finite numbers, got {brief_repr(action)}")
    a0 = min(max(float(a[0]), -1.0), 1.0)
    a1 = min(max(float(a[1]), -1.0), 1.0)
    if scale is not None:
        a0 *= scale
        a1 *= scale
    d_accel = a0 * limits.a_max if a0 >= 0.0 else a0 * -limits.a_min
    d_steer = a1 * limits.steer_limit
    return d_accel, d_steer


class ResidualMixer:
    """Residual mode: the controller's command plus the residual, as applied.

    One per episode; it remembers the last applied acceleration and the
    controller's last one (both start at the speed loop's 0,
    ``SpeedController.last_a``) for the jerk limits.

    Parameters
    ----------
    limits : CommandLimits
        The command range the sum is clipped to.
    speed : SpeedConfig
        The speed loop's jerk limits (``jerk_max``, ``jerk_brake_max``).
    dt : float
        Simulation step, s.
    """

    def __init__(self, limits: CommandLimits, speed: SpeedConfig, dt: float) -> None:
        self.limits = limits
        self.speed = speed
        self.dt = dt
        self.applied_accel = 0.0
        self.controller_accel = 0.0

    def applied(self, accel: float) -> None:
        """Note the acceleration applied in this simulation step (in any mode)."""
        self.applied_accel = accel

    def command(
        self, ctrl: Any, c_accel: float, c_steer: float, d_accel: float, d_steer: float
    ) -> tuple[float, float]:
        """The command to apply, from the controller's ``(c_accel, c_steer)`` and the residual.

        ``ctrl`` is the tracking controller (its ``at_stop``, ``remaining``,
        ``steer_window`` and ``steer_wanted``).
        """
        remaining = ctrl.remaining
        if ctrl.at_stop or remaining <= 0.0:
            # Holding at the goal (or a cusp) or braking past it: the controller alone,
            # so that a biased residual cannot keep the car creeping forever.
            self.controller_accel = c_accel
            return c_accel, c_steer
        # The residual fades out over the last RESIDUAL_FADE_M before each stop (the
        # goal, a cusp), so that the hand-over to the controller's hold does not jump.
        fade = min(1.0, remaining / RESIDUAL_FADE_M)
        lim = self.limits.steer_limit
        accel = self.accel(c_accel, fade * d_accel, self.dt)
        window = ctrl.steer_window
        if window is None:
            return accel, min(max(c_steer + fade * d_steer, -lim), lim)
        # A rate-limited actuator: the residual goes on the controller's wish, and the
        # sum is clipped to what the wheels can reach this step. Added to the command
        # already clipped to that reach, every residual against the controller's turn
        # would pass and every one with it be cut: zero-mean noise slowed the
        # controller's corrections to a third and drove the car off the path.
        steer = min(max(ctrl.steer_wanted + fade * d_steer, -lim), lim)
        return accel, min(max(steer, window[0]), window[1])

    def accel(self, c_accel: float, d_accel: float, dt: float) -> float:
        """The controller's acceleration plus the residual, within the speed loop's limits.

        Besides the acceleration range, the sum may rise (fall) from the last applied
        command by at most ``jerk_max`` (``jerk_brake_max``) per second, or by as much
        as the controller's own command changed since its last one when that is more
        (its hold at the goal, a following cap): the residual cannot add a jerk the
        speed loop would not, and a zero residual is the controller's command exactly.
        """
        cfg = self.speed
        prev = self.applied_accel
        change = c_accel - self.controller_accel
        self.controller_accel = c_accel
        hi = min(self.limits.a_max, prev + max(change, cfg.jerk_max * dt))
        lo = self.limits.a_min
        if cfg.jerk_brake_max is not None:
            lo = max(lo, prev + min(change, -cfg.jerk_brake_max * dt))
        return min(max(c_accel + d_accel, lo), hi)
