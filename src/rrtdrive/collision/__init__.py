"""One collision checker per map: a fast conservative swept-disc test and an exact body test.

The fast tests read a clearance field: the Euclidean distance transform
(:func:`scipy.ndimage.distance_transform_edt`'s values, computed by
:func:`~rrtdrive.collision.distance.distance_field`) of a fine occupancy grid. The grid
is built so that its error is bounded and subtracted (see
:attr:`CollisionChecker.grid_error`), which keeps every fast answer conservative:
a colliding edge or pose is never called free. The exact test confirms what the
fast screen cannot clear with shapely polygons, so its answers agree with shapely.

Modules: :mod:`~rrtdrive.collision.config` (:class:`CheckerConfig`),
:mod:`~rrtdrive.collision.grid` (rasterisation and the grid-derived data cached
per checker, :class:`GridCache`), :mod:`~rrtdrive.collision.distance` (the distance
field), :mod:`~rrtdrive.collision.checker`
(:class:`CollisionChecker`). The contract it implements is
:class:`rrtdrive.checking.Checker`.
"""

from __future__ import annotations

from rrtdrive.collision.checker import CollisionChecker
from rrtdrive.collision.config import CheckerConfig
from rrtdrive.collision.grid import GridCache

__all__ = ["CollisionChecker", "CheckerConfig", "GridCache"]
