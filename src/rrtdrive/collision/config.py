"""Tunables of the collision checker."""

from __future__ import annotations

from dataclasses import dataclass

from rrtdrive.types import InputError, require_finite, require_int, require_positive

__all__ = ["CheckerConfig"]


#: The coarsest collision grid cell taken, metres (the error margin is ~0.7 of a cell).
MAX_RESOLUTION = 100.0


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
    max_grid_cells : int
        Most cells a checker's grid may have (bounds plus ``pad`` on each side). A
        map that needs more at ``resolution`` gets a coarser grid (see
        ``max_auto_resolution``). Measured on a 500 x 500 m map at 0.1 m (25.2 M
        cells, which fits): building the checker peaks at 0.93 GB (37 bytes a
        cell, mostly the distance transform), the improved planner's first query
        (the expanded-obstacle checker too) at 1.6 GB; so the default 50 M cells
        is about 3.2 GB at the peak.
    max_auto_resolution : float
        Coarsest cell size in metres the checker may choose by itself to keep
        within ``max_grid_cells``; a map that needs coarser is refused (an
        :class:`~rrtdrive.types.InputError` naming ``bounds``). A ``resolution``
        set coarser than this is used as given.
    """

    resolution: float = 0.1
    margin: float = 0.1
    pad: float = 1.0
    min_trace_step: float = 0.02
    max_grid_cells: int = 50_000_000
    max_auto_resolution: float = 0.5

    def __post_init__(self) -> None:
        require_positive("checker.resolution", self.resolution)
        if self.resolution > MAX_RESOLUTION:  # 1e308 overflowed the grid's coordinates
            raise InputError(
                f"checker.resolution: at most {MAX_RESOLUTION:g} m (a cell that coarse hides "
                f"streets and cars alike), got {self.resolution:g}"
            )
        require_positive("checker.pad", self.pad)
        require_positive("checker.min_trace_step", self.min_trace_step)
        require_int("checker.max_grid_cells", self.max_grid_cells, minimum=16)
        require_positive("checker.max_auto_resolution", self.max_auto_resolution)
        require_finite("checker.margin", self.margin)
        if not self.margin >= 0:
            raise InputError(f"checker.margin: must be >= 0, got {self.margin}")
