"""The checker contract: what every planner and post-processing step may ask of a checker.

After OMPL's ``StateValidityChecker`` (is one state valid?) and ``MotionValidator``
(is the motion between two states valid?), written as :class:`typing.Protocol`:

* :class:`PoseValidityChecker` - tests of rear-axle poses ``(x, y, yaw)``;
* :class:`MotionValidator` - tests of straight edges and sampled paths;
* :class:`Checker` - both, plus the map data and grid-derived data that the
  planners, samplers and the post-processor read.

Conventions shared by every method: lengths in metres, angles in radians, poses
are *rear-axle* poses. "Exact" means the answer agrees with shapely on the body
rectangle (:func:`rrtdrive.vehicle.footprint_corners`). "Conservative" means it
errs only in the safe direction: True proves "free", False means "maybe not".

:class:`rrtdrive.collision.CollisionChecker` (static obstacles) and
:class:`rrtdrive.planning.spacetime.SpaceTimeChecker` (plus predicted traffic)
implement :class:`Checker` explicitly. A checker with more knowledge (traffic) may
answer False where the static checker answers True, never the reverse.
"""

from __future__ import annotations

import functools
import inspect
from collections.abc import Sequence
from typing import TYPE_CHECKING, Protocol, runtime_checkable

import numpy as np

if TYPE_CHECKING:
    import shapely

    from rrtdrive.collision.config import CheckerConfig
    from rrtdrive.maps import Obstacle
    from rrtdrive.types import VehicleParams

__all__ = ["PoseValidityChecker", "MotionValidator", "Checker", "implements"]


@runtime_checkable
class PoseValidityChecker(Protocol):
    """Validity of single rear-axle poses (OMPL's ``StateValidityChecker``)."""

    @property
    def vehicle(self) -> VehicleParams:
        """The car whose body is tested."""
        ...

    def pose_free(self, pose: Sequence[float]) -> bool:
        """Exact body test at one pose ``(x, y, yaw)``: True when the body is free.

        Free means: the body rectangle does not touch any obstacle and lies
        inside the map bounds (a checker with traffic also requires it clear of
        the traffic at the pose's arrival time).
        """
        ...

    def poses_free(self, poses: np.ndarray, clearance: float = 0.0) -> np.ndarray:
        """Exact batch body test: boolean ``(N,)`` for ``(N, 3)`` poses.

        ``clearance`` (metres, >= 0) is the distance the body must keep from every
        obstacle and from the bounds; 0 means it may not touch them.
        """
        ...

    def poses_free_fast(self, poses: np.ndarray, clearance: float = 0.0) -> np.ndarray:
        """Conservative batch screen: True proves the body keeps ``clearance`` (metres).

        False means "maybe not": confirm with :meth:`poses_free`. Cheaper than it.
        """
        ...

    def body_clearance(self, pose: Sequence[float]) -> float:
        """Exact distance in metres from the body at ``pose`` to the static obstacles or bounds.

        Zero when the body touches or overlaps an obstacle or leaves the bounds.
        Static only: it never includes traffic.
        """
        ...


@runtime_checkable
class MotionValidator(Protocol):
    """Validity of motions between poses (OMPL's ``MotionValidator``)."""

    def edge_free(self, a: Sequence[float], b: Sequence[float]) -> bool:
        """Conservative test of a straight tree edge from ``a`` to ``b`` (``(x, y)``, metres).

        The car drives the edge with its heading along it; True proves its swept
        footprint free (a degenerate edge is the body at ``a`` with any heading).
        False means "maybe not".
        """
        ...

    def path_free(
        self, samples: np.ndarray, spacing: float = 0.1, clearance: float = 0.0
    ) -> tuple[bool, np.ndarray]:
        """Exact test of a sampled path ``(N, >=3)`` rows ``x, y, yaw, ...``.

        Poses are tested at most ``spacing`` metres apart, each keeping
        ``clearance`` metres (see :meth:`PoseValidityChecker.poses_free`).

        Returns
        -------
        ok : bool
            True when every tested pose is free (False for an empty path).
        bad : numpy.ndarray
            Indices ``i`` of the segments ``i -> i+1`` holding a colliding pose.
        """
        ...


@runtime_checkable
class Checker(PoseValidityChecker, MotionValidator, Protocol):
    """What the planners, samplers and post-processor use: both tests plus map and grid data.

    The grid accessors describe the clearance field of the *static* map: a
    lower bound of the distance to the nearest obstacle or the outside, on
    cells of :attr:`resolution` metres from :attr:`grid_origin`.
    """

    @property
    def bounds(self) -> tuple[float, ...]:
        """``(xmin, ymin, xmax, ymax)`` of the map in metres; the outside counts as occupied."""
        ...

    @property
    def obstacles(self) -> tuple[Obstacle, ...]:
        """The static obstacles (oriented rectangles)."""
        ...

    @property
    def config(self) -> CheckerConfig:
        """Grid resolution and margins of the fast tests."""
        ...

    @property
    def edge_radius(self) -> float:
        """Radius in metres of the capsule swept by :meth:`edge_free` (``W/2 + margin``)."""
        ...

    @property
    def resolution(self) -> float:
        """Grid cell size in metres."""
        ...

    @property
    def grid_origin(self) -> np.ndarray:
        """World position of the grid's lower-left corner (a copy)."""
        ...

    @property
    def clearance_grid(self) -> np.ndarray:
        """``(nx, ny)`` lower bound of the obstacle distance at each cell centre, metres."""
        ...

    @property
    def component_labels(self) -> np.ndarray:
        """``(nx, ny)`` connectivity labels of the cells the rear axle may occupy (0: none)."""
        ...

    @property
    def obstacle_union(self) -> shapely.Geometry:
        """The prepared shapely union of :attr:`obstacles` (empty geometry when none)."""
        ...

    @property
    def setup_time_s(self) -> float:
        """Seconds spent building grid data so far (field at construction, lazy builds after)."""
        ...

    def clearance(self, x: float, y: float) -> float:
        """Lower bound of the distance from ``(x, y)`` to an obstacle or the outside, metres.

        Negative or ``-inf``: possibly inside an obstacle or outside the grid.
        """
        ...

    def clearances(self, points: np.ndarray) -> np.ndarray:
        """Vectorised :meth:`clearance` of ``(N, 2)`` points."""
        ...

    def point_free(self, x: float, y: float) -> bool:
        """Necessary condition (for sampling): the rear axle at ``(x, y)`` fits with some heading.

        False proves no heading fits; True is not a body test.
        """
        ...

    def provably_disconnected(self, a: Sequence[float], b: Sequence[float]) -> bool:
        """True proves no collision-free motion takes the rear axle from ``a`` to ``b``.

        False proves nothing (conservative in the planner's favour: it never
        rejects a solvable query).
        """
        ...

    def too_narrow_between(
        self, a: Sequence[float], b: Sequence[float], keep: float = 0.0
    ) -> bool:
        """True proves every way for the rear axle from ``a`` to ``b`` is too narrow for the car.

        The exact twin of :meth:`provably_disconnected`; False proves nothing. ``keep``:
        for a car that keeps this body clearance, metres.
        """
        ...

    def free_cells(self, start: Sequence[float]) -> np.ndarray:
        """Flat indices (into ``clearance_grid.ravel()``) of cells a sampler may draw from.

        The cells where the rear axle can stand with some heading that are in the
        component of ``start``; empty when the start is in none. Cached.
        """
        ...

    def passage_cells(self, start: Sequence[float], width: float = 0.6) -> np.ndarray:
        """``(K, 2)`` centres of cells on narrow-passage centre lines reachable from ``start``.

        Passages at most ``width`` metres wider than the edge test needs. Cached.
        """
        ...


def implements(obj: object, protocol: type) -> bool:
    """True when ``obj`` defines every member of ``protocol`` (without calling any of them).

    ``isinstance`` on a runtime-checkable Protocol evaluates every property on Python
    3.11 (``hasattr``), which would build lazy grid data as a side effect; this looks
    the members up statically instead.

    Examples
    --------
    >>> from rrtdrive.collision import CollisionChecker
    >>> from rrtdrive.maps import builtin_map
    >>> checker = CollisionChecker.for_map(builtin_map("overtake"))
    >>> implements(checker, Checker), implements(object(), MotionValidator)
    (True, False)
    """
    key = (type(obj), protocol)
    if key in _CLASS_IMPLEMENTS:
        return True
    members = _members(protocol)
    if not all(_has_static(obj, name) for name in members):
        return False
    # Members found on the class itself are found on every instance: remembered per
    # class (post-processing asks this of the same checker class a few times a query).
    mro = type(obj).__mro__
    if all(any(name in vars(k) for k in mro) for name in members):
        _CLASS_IMPLEMENTS.add(key)
    return True


#: ``(class, protocol)`` pairs whose class defines every member of the protocol.
_CLASS_IMPLEMENTS: set[tuple[type, type]] = set()


@functools.cache
def _members(protocol: type) -> frozenset[str]:
    """The public members of ``protocol`` and the protocols it extends."""
    return frozenset(
        name
        for klass in protocol.__mro__
        if klass not in (object, Protocol) and getattr(klass, "_is_protocol", False)
        for name in (*vars(klass), *getattr(klass, "__annotations__", {}))
        if not name.startswith("_")
    )


def _has_static(obj: object, name: str) -> bool:
    try:
        inspect.getattr_static(obj, name)
    except AttributeError:
        return False
    return True
