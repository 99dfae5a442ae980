"""Obstacles: oriented rectangles, the one kind of obstacle a map holds (SPEC §2)."""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
import shapely

from rrtdrive.geometry import box_corners
from rrtdrive.map_checks import check_obstacle_numbers
from rrtdrive.types import InputError, brief_repr, require_finite

__all__ = ["Obstacle"]


@dataclass(frozen=True)
class Obstacle:
    """An oriented rectangle: centre, size ``(length along yaw, width)``, yaw.

    Parameters
    ----------
    center : tuple of float
        ``(x, y)`` of the rectangle's centre in metres.
    size : tuple of float
        ``(length, width)`` in metres: the length along ``yaw``, the width across it
        (both > 0).
    yaw : float
        Orientation in radians (default 0: the length along +x).

    Examples
    --------
    >>> round(Obstacle((10.0, 2.5), (4.3, 1.8), 1.5708).polygon().area, 2)
    7.74
    """

    center: tuple[float, float]
    size: tuple[float, float]
    yaw: float = 0.0

    def __post_init__(self) -> None:
        center = _pair(self.center, "obstacle.center")
        size = _pair(self.size, "obstacle.size")
        check_obstacle_numbers(size, self.yaw)
        object.__setattr__(self, "center", center)
        object.__setattr__(self, "size", size)
        object.__setattr__(self, "yaw", float(self.yaw))

    def corners(self) -> np.ndarray:
        """The four corners, shape ``(4, 2)``, counter-clockwise from rear-right."""
        half_l, half_w = self.size[0] / 2.0, self.size[1] / 2.0
        return box_corners(
            self.center[0], self.center[1], self.yaw, -half_l, half_l, half_w, rotate_first=True
        )

    def polygon(self) -> shapely.Polygon:
        """The rectangle as a shapely polygon (built once per distinct rectangle)."""
        return _obstacle_polygon(self)

    def grown(self, amount: float) -> Obstacle:
        """This rectangle with ``amount`` added to its length and to its width.

        Parameters
        ----------
        amount : float
            Metres added to each side length (half of it on each face).

        Returns
        -------
        Obstacle
        """
        return Obstacle(self.center, (self.size[0] + amount, self.size[1] + amount), self.yaw)

    def to_json(self) -> dict[str, object]:
        """JSON-ready dict."""
        return {"center": list(self.center), "size": list(self.size), "yaw": self.yaw}


@functools.lru_cache(maxsize=1 << 16)
def _obstacle_polygon(obstacle: Obstacle) -> shapely.Polygon:
    # Every copy of a map (a new goal, ``dataclasses.replace``) checks its start and
    # goal against each obstacle: building the polygons was most of a copy's cost.
    return shapely.Polygon(obstacle.corners())


def _pair(value: object, name: str) -> tuple[float, float]:
    if not isinstance(value, (list, tuple, np.ndarray)) or len(value) != 2:
        raise InputError(f"{name}: expected two numbers, got {brief_repr(value)}")
    require_finite(name, *value)
    return (float(value[0]), float(value[1]))
