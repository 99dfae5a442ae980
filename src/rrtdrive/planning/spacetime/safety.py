"""How far the ego keeps from predicted vehicles, in space and in time."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from rrtdrive.types import InputError, require_finite

__all__ = ["SafetyConfig"]


@dataclass(frozen=True)
class SafetyConfig:
    """How far the ego keeps from predicted vehicles, in space and in time.

    A pose the ego reaches at time ``t`` (seconds after the prediction) is
    tested against each vehicle's body swept over ``[t - m(t), t + m(t)]`` with
    ``m(t) = time_margin_s + time_margin_growth * t``, and must keep
    ``b(t) = buffer_m + buffer_growth * t`` from it: both grow with the
    prediction time, as the prediction's uncertainty does.

    Parameters
    ----------
    buffer_m : float
        Distance at ``t = 0`` in metres (between the ego's covering discs and the
        other vehicle's covering capsule, themselves conservative).
    buffer_growth : float
        Growth of the distance per second of prediction (m/s).
    time_margin_s : float
        Half-width of the time band at ``t = 0`` in seconds.
    time_margin_growth : float
        Growth of the half-width per second of prediction (s/s).

    Examples
    --------
    >>> float(SafetyConfig().buffer(10.0)), float(SafetyConfig().margin(10.0))
    (0.9, 1.5)
    """

    buffer_m: float = 0.4
    buffer_growth: float = 0.05
    time_margin_s: float = 0.5
    time_margin_growth: float = 0.1

    def __post_init__(self) -> None:
        for name in ("buffer_m", "buffer_growth", "time_margin_s", "time_margin_growth"):
            value = getattr(self, name)
            require_finite(f"safety.{name}", value)
            if value < 0:
                raise InputError(f"safety.{name}: must be >= 0, got {value!r}")

    def buffer(self, t: float | np.ndarray) -> Any:
        """Distance to keep at prediction time ``t``.

        Parameters
        ----------
        t : float or numpy.ndarray
            Seconds after the prediction (negative counts as 0).

        Returns
        -------
        float or numpy.ndarray
            ``buffer_m + buffer_growth * t`` in metres, shaped like ``t``.
        """
        return self.buffer_m + self.buffer_growth * np.maximum(t, 0.0)

    def margin(self, t: float | np.ndarray) -> Any:
        """Half-width of the time band at prediction time ``t``.

        Parameters
        ----------
        t : float or numpy.ndarray
            Seconds after the prediction (negative counts as 0).

        Returns
        -------
        float or numpy.ndarray
            ``time_margin_s + time_margin_growth * t`` in seconds, shaped like ``t``.
        """
        return self.time_margin_s + self.time_margin_growth * np.maximum(t, 0.0)
