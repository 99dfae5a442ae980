"""Tunables of the collision checker."""

from __future__ import annotations

import math
from dataclasses import dataclass

from rrtdrive.types import require_positive

__all__ = ["CheckerConfig"]


@dataclass(frozen=True)
class CheckerConfig:
    """Tunables of the checker.

    Parameters
    ----------
    resolution : float
        Grid cell size in metres.
    margin : float
        Extra clearance in metres required by the fast tests beyond the car's size.
    pad : float
        Occupied border in metres outside the bounds (the bounds act as walls).
    min_trace_step : float
        Smallest step of the sphere tracing along an edge; a step this small means
        the swept disc is grazing an obstacle, which is reported as a collision.
    """

    resolution: float = 0.1
    margin: float = 0.1
    pad: float = 1.0
    min_trace_step: float = 0.02

    def __post_init__(self) -> None:
        require_positive("checker.resolution", self.resolution)
        require_positive("checker.pad", self.pad)
        require_positive("checker.min_trace_step", self.min_trace_step)
        if not (self.margin >= 0 and math.isfinite(self.margin)):
            raise ValueError(f"checker.margin: must be >= 0, got {self.margin}")
