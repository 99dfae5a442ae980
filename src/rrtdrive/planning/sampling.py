"""Uniform samples over the free cells reachable from the start, shared by every tree planner."""

from __future__ import annotations

import numpy as np

from rrtdrive.planning.base import PlanningProblem

__all__ = ["SampleSource"]


class SampleSource:
    """Uniform samples over the map, optionally only where they can be useful.

    With ``reject`` (the default in every baseline), samples are uniform over
    the points where the car can stand with some heading
    (:meth:`~rrtdrive.collision.CollisionChecker.point_free`) and that are not
    provably disconnected from the start
    (:meth:`~rrtdrive.collision.CollisionChecker.provably_disconnected`), such
    as the land beside a walled road. Both tests are constant on the checker's
    grid cells, so instead of rejecting draws this picks a uniform random cell
    among the accepted ones and a uniform point inside it: the same distribution
    as rejection sampling, without the wasted draws. Without ``reject``, samples
    are uniform in the bounds.
    Numbers are drawn from ``rng`` in batches, so results depend only on the seed.

    Parameters
    ----------
    problem : PlanningProblem
        The query.
    reject : bool
        Sample only useful points (see above).
    batch : int
        Points drawn from the generator at once.
    """

    def __init__(self, problem: PlanningProblem, reject: bool, batch: int = 256) -> None:
        checker = problem.checker
        self.batch = batch
        self._h = checker.resolution
        self._origin = checker.grid_origin
        self._ny = checker.clearance_grid.shape[1]
        xmin, ymin, xmax, ymax = problem.bounds
        self._low = np.array([xmin, ymin])
        self._span = np.array([xmax - xmin, ymax - ymin])
        self._cells = checker.free_cells(problem.start.as_tuple()[:2]) if reject else None
        if self._cells is not None and len(self._cells) == 0:
            self._cells = None
        self._buffer = np.empty((0, 2))
        self._list: list[list[float]] = []
        self._pos = 0

    def _refill(self, rng: np.random.Generator) -> None:
        if self._cells is None:
            self._buffer = self._low + rng.random((self.batch, 2)) * self._span
        else:
            flat = self._cells[rng.integers(len(self._cells), size=self.batch)]
            ij = np.column_stack([flat // self._ny, flat % self._ny])
            self._buffer = self._origin + (ij + rng.random((self.batch, 2))) * self._h
        self._list = self._buffer.tolist()
        self._pos = 0

    def draw(self, rng: np.random.Generator) -> np.ndarray:
        """One sample point ``(x, y)`` (a fresh array)."""
        if self._pos == len(self._buffer):
            self._refill(rng)
        q = self._buffer[self._pos].copy()
        self._pos += 1
        return q

    def draw_xy(self, rng: np.random.Generator) -> list[float]:
        """:meth:`draw` as a fresh list ``[x, y]`` of floats (cheaper in scalar loops).

        Both draw from one stream: mixing them gives the same points in the same order.
        """
        if self._pos == len(self._buffer):
            self._refill(rng)
        q = self._list[self._pos]
        self._pos += 1
        return q

