"""Every access the smoothing code makes to a collision checker, in one place.

The post-processor needs a motion validator (``edge_free`` and ``path_free``); when the
checker implements the whole :class:`~rrtdrive.checking.Checker` contract it also uses
the checker's prepared obstacle union (behind a bulk screen of edges proven to collide)
and its exact batch body test ``poses_free``.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Protocol, cast

import numpy as np
import shapely

from rrtdrive.checking import Checker, PoseValidityChecker, implements

__all__ = ["EdgeChecker", "PathChecker", "CheckerView", "EdgeCache", "edge_screen"]


class EdgeChecker(Protocol):
    """Anything with the fast edge test of :class:`~rrtdrive.collision.CollisionChecker`."""

    def edge_free(self, a: Sequence[float], b: Sequence[float]) -> bool:
        """True when the car driving straight from ``a`` to ``b`` is clear.

        Parameters
        ----------
        a, b : sequence of float
            Rear-axle positions ``(x, y, ...)`` of the edge's ends (heading along it).

        Returns
        -------
        bool
        """
        ...


class PathChecker(EdgeChecker, Protocol):
    """An edge checker that also has the exact sampled-path test."""

    def path_free(
        self, samples: np.ndarray, spacing: float = 0.1, clearance: float = 0.0
    ) -> tuple[bool, np.ndarray]:
        """Exact body test along ``samples``; returns ``(ok, bad segment indices)``.

        Parameters
        ----------
        samples : numpy.ndarray
            ``(N, >=3)`` rows ``x, y, yaw, ...``.
        spacing : float
            Largest distance between tested poses, metres.
        clearance : float
            Distance the body must keep from obstacles and bounds, metres.

        Returns
        -------
        ok : bool
            True when every tested pose is free.
        bad : numpy.ndarray
            Indices of segments ``i -> i+1`` with a colliding pose.
        """
        ...


#: ``blocked_from(a, bs)``: True where the edge ``a -> b`` is proven to collide.
Screen = Callable[[np.ndarray, np.ndarray], np.ndarray]
#: ``poses_free(poses, clearance)``: True where the body at a pose is clear.
PosesFree = Callable[[np.ndarray, float], np.ndarray]


def edge_screen(checker: object) -> Screen | None:
    """The checker's optional ``blocked_from`` screen, or None when it has none."""
    return getattr(checker, "blocked_from", None)


class CheckerView:
    """The smoother's view of a :class:`PathChecker` and its optional extras.

    Parameters
    ----------
    checker : PathChecker
        The original map's checker.
    """

    def __init__(self, checker: PathChecker) -> None:
        self.checker = checker
        self.edge_free = checker.edge_free
        # Edge answers and screens shared by the EdgeCaches of one make_drivable call:
        # its second pruning attempt tests many of the first one's edges again.
        self.edge_memo: dict[tuple[float, float, float, float], bool] = {}
        self.screen_memo: dict[tuple[float, float, bytes], np.ndarray] = {}
        # implements() inspects the checker statically (~0.1 ms a call for a checker
        # with instance attributes): asked once per view, not once per attempt or round.
        self._implements: dict[type, bool] = {}

    def _is(self, protocol: type) -> bool:
        known = self._implements.get(protocol)
        if known is None:
            known = self._implements[protocol] = implements(self.checker, protocol)
        return known

    def obstacle_union(self) -> shapely.Geometry | None:
        """The prepared union of the obstacles (cached on the checker), or None.

        None when the checker does not implement the whole
        :class:`~rrtdrive.checking.Checker` contract (a bare motion validator).
        """
        return cast(Checker, self.checker).obstacle_union if self._is(Checker) else None

    def poses_free(self) -> PosesFree | None:
        """The exact batch body test of a :class:`~rrtdrive.checking.PoseValidityChecker`.

        For the space-time checker this tests traffic at the nominal arrival times,
        not the exact ones of its ``path_free`` (see docs/traffic.md, "What is left":
        preferring ``path_free`` there was measured in session 48 and not kept).
        """
        checker = cast(PoseValidityChecker, self.checker)
        return checker.poses_free if self._is(PoseValidityChecker) else None

    def path_free(
        self, samples: np.ndarray, spacing: float, clearance: float
    ) -> tuple[bool, np.ndarray]:
        """The checker's exact body test along ``samples``."""
        return self.checker.path_free(samples, spacing=spacing, clearance=clearance)


class EdgeCache:
    """Memoised ``edge_free``: the key polygon is rebuilt from the same tree nodes several times.

    With the checker's obstacles known, :meth:`blocked_from` proves collisions in
    bulk: an edge whose centre line meets an obstacle cannot be free, because the
    swept capsule of ``edge_free`` contains its centre line.
    """

    def __init__(self, view: CheckerView) -> None:
        self._edge_free = view.edge_free
        # This cache's own answers (``checks`` counts its distinct edges, as before)
        # and the view's, shared with the other caches of the same call.
        self._known: dict[tuple[float, float, float, float], bool] = {}
        self._shared = view.edge_memo
        self.checks = 0
        self._screens = view.screen_memo
        self._union = view.obstacle_union()
        if self._union is None:
            # No obstacles known: no screen, so :func:`edge_screen` finds none.
            self.blocked_from = None  # type: ignore[assignment]

    def blocked_from(self, a: np.ndarray, bs: np.ndarray) -> np.ndarray:
        """True where the centre line ``a -> b`` crosses an obstacle (so the edge collides)."""
        if len(bs) == 0 or self._union is None or self._union.is_empty:
            return np.zeros(len(bs), dtype=bool)
        key = (float(a[0]), float(a[1]), bs.tobytes())
        hit = self._screens.get(key)
        if hit is None:
            coords = np.empty((len(bs), 2, 2))
            coords[:, 0] = a
            coords[:, 1] = bs
            hit = self._screens[key] = shapely.intersects(self._union, shapely.linestrings(coords))
        return hit

    def edge_free(self, a: Sequence[float], b: Sequence[float]) -> bool:
        """Memoised ``checker.edge_free(a, b)``; ``a`` and ``b`` as plain float pairs."""
        key = (a[0], a[1], b[0], b[1])
        hit = self._known.get(key)
        if hit is None:
            self.checks += 1
            hit = self._shared.get(key)
            if hit is None:
                hit = self._shared[key] = bool(self._edge_free(a, b))
            self._known[key] = hit
        return hit
