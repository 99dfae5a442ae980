"""A heading-aware cost-to-go over a coarse lattice of poses: the guide of a hard query.

The search's own estimate (:mod:`.heuristic`) is the larger of the distance round
the obstacles, which ignores the heading, and the Dubins or Reeds-Shepp length,
which ignores the obstacles. Neither sees what turning round costs where the
obstacles leave little room: a goal in an angled bay entered against the row, a
lane-to-lane turn in a narrow street. There the search floods thousands of states
near the goal before one of them turns the car.

:class:`HeadingLattice` sees it. Its states are the cell centres of a coarse grid
with ``headings`` headings each, and, with reverse, the gear the car arrived in;
its moves are the search's own in coarse form: full-lock arcs left and right and
a straight, each turning the heading by one step, forward and (with reverse)
backward. A state or move is in it when the car's body is clear (the exact test,
at the state and at the move's middle). Moves cost what the search charges: the
length, ``reverse_cost`` times it backwards, and ``gear_change_cost`` at a cusp.
One Dijkstra (:func:`scipy.sparse.csgraph.dijkstra`) from the goal's states gives
every state's cost to go.

The lattice is built once per map (set-up, outside the planning time); a query
pays its two Dijkstras. It only guides: a state it cannot reach gets no estimate
from it (the search's own stands), so it never cuts off a pose the search could
reach, and proofs of unreachability stay the search's.
"""

from __future__ import annotations

import dataclasses
import math
from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from scipy import sparse
from scipy.sparse.csgraph import dijkstra

from rrtdrive.collision import CollisionChecker
from rrtdrive.planning.hybrid.body import BodyTest
from rrtdrive.planning.hybrid.config import HybridConfig
from rrtdrive.planning.hybrid.heuristic import Heuristic
from rrtdrive.types import Pose

__all__ = ["Estimate", "HeadingLattice", "guided", "heading_lattice"]

_TWO_PI = 2.0 * math.pi
#: Cost tables kept per lattice (by seed pose): a query's later stages reuse its own.
_KEPT = 4

#: ``estimate(x, y, yaw) -> metres``: a cost to go (or from the start), 0 where unknown.
Estimate = Callable[[float, float, float], float]


@dataclass(frozen=True, eq=False)
class HeadingLattice:
    """States ``(cell, heading[, gear])`` of one map, their moves and costs.

    Attributes
    ----------
    origin : tuple of float
        World position of the grid's lower-left corner.
    cell : float
        Cell size, metres.
    headings : int
        Heading steps per turn.
    shape : tuple of int
        ``(nx, ny)`` cells.
    gears : int
        1 (forward only) or 2 (a state per gear arrived in).
    forward : scipy.sparse.csr_matrix
        Move costs, state to successor.
    backward : scipy.sparse.csr_matrix
        The same moves, successor to state (for costs to go).
    free : numpy.ndarray
        ``(nx * ny * headings,)`` whether the body is clear at each state.
    """

    origin: tuple[float, float]
    cell: float
    headings: int
    shape: tuple[int, int]
    gears: int
    forward: sparse.csr_matrix
    backward: sparse.csr_matrix
    free: np.ndarray
    _tables: OrderedDict = field(default_factory=OrderedDict, repr=False)

    @classmethod
    def build(
        cls,
        checker: CollisionChecker,
        bounds: tuple[float, float, float, float],
        radius: float,
        reverse: bool,
        reverse_cost: float,
        gear_change_cost: float,
        cell: float = 0.5,
        headings: int = 16,
        max_nodes: int = 300_000,
    ) -> HeadingLattice:
        """The lattice of a map: states, body tests and moves.

        ``cell`` grows where the map is big, so that the nodes (states times gears)
        stay within ``max_nodes``.

        Examples
        --------
        >>> from rrtdrive.maps import Map
        >>> empty = Map("open", (0.0, 0.0, 20.0, 10.0), (), Pose(3, 5, 0), Pose(15, 5, 0))
        >>> lat = HeadingLattice.build(
        ...     CollisionChecker.for_map(empty), empty.bounds, 6.0, True, 2.0, 5.0
        ... )
        >>> lat.shape, lat.headings, lat.gears
        ((40, 20), 16, 2)
        """
        x0, y0, x1, y1 = (float(b) for b in bounds)
        gears = 2 if reverse else 1
        area = (x1 - x0) * (y1 - y0)
        cell = max(float(cell), math.sqrt(area * headings * gears / max(1, max_nodes)))
        nx, ny = max(1, math.ceil((x1 - x0) / cell)), max(1, math.ceil((y1 - y0) / cell))
        n_states = nx * ny * headings
        index = np.arange(n_states)
        ii, rest = np.divmod(index, ny * headings)
        jj, kk = np.divmod(rest, headings)
        poses = np.column_stack(
            [x0 + (ii + 0.5) * cell, y0 + (jj + 0.5) * cell, _TWO_PI * kk / headings]
        )
        # The exact test, after a screen that settles the poses surely hitting (most of a
        # lattice's states inside obstacles) and surely clear.
        body = BodyTest(checker, 0.0)
        free = body.free(poses)
        arc = radius * _TWO_PI / headings
        # Moves start from clear states only.
        start = index[free]
        from_poses, from_k = poses[start], kk[start]
        src_parts, dst_parts, cost_parts = [], [], []
        for gear in (1, -1) if reverse else (1,):
            for steer in (-1, 0, 1):
                end, middle = _move(from_poses, gear, steer, radius, arc)
                ei = np.floor((end[:, 0] - x0) / cell).astype(np.int64)
                ej = np.floor((end[:, 1] - y0) / cell).astype(np.int64)
                inside = np.flatnonzero((ei >= 0) & (ei < nx) & (ej >= 0) & (ej < ny))
                turned = (from_k[inside] + gear * steer) % headings
                dst = (ei[inside] * ny + ej[inside]) * headings + turned
                keep = free[dst]
                moved, dst = inside[keep], dst[keep]
                clear = body.free(middle[moved])
                src, dst = start[moved[clear]], dst[clear]
                length = arc * (reverse_cost if gear < 0 else 1.0)
                bit = int(gear < 0)
                for before in range(gears):
                    src_parts.append(src * gears + before)
                    dst_parts.append(dst * gears + (bit if gears == 2 else 0))
                    cusp = gear_change_cost if gears == 2 and before != bit else 0.0
                    cost_parts.append(np.full(len(src), length + cusp))
        n = n_states * gears
        graph = sparse.csr_matrix(
            (np.concatenate(cost_parts), (np.concatenate(src_parts), np.concatenate(dst_parts))),
            shape=(n, n),
        )
        return cls((x0, y0), cell, headings, (nx, ny), gears, graph, graph.T.tocsr(), free)

    def _seeds(self, pose: Pose) -> np.ndarray:
        """The clear states nearest ``pose``: its cell and neighbours, the nearest headings."""
        (x0, y0), cell, k = self.origin, self.cell, self.headings
        nx, ny = self.shape
        ci, cj = math.floor((pose.x - x0) / cell), math.floor((pose.y - y0) / cell)
        step = (pose.yaw % _TWO_PI) / _TWO_PI * k
        bins = {math.floor(step) % k, math.ceil(step) % k}
        found: list[tuple[float, int]] = []
        for i in range(ci - 1, ci + 2):
            for j in range(cj - 1, cj + 2):
                if not (0 <= i < nx and 0 <= j < ny):
                    continue
                d = math.hypot(x0 + (i + 0.5) * cell - pose.x, y0 + (j + 0.5) * cell - pose.y)
                for b in bins:
                    s = (i * ny + j) * k + b
                    if self.free[s]:
                        found.append((d, s))
        if not found:
            return np.zeros(0, dtype=np.int64)
        nearest = min(d for d, _ in found)
        states = [s for d, s in found if d <= nearest + 1e-9]
        return np.array([s * self.gears + g for s in states for g in range(self.gears)])

    def _costs(self, pose: Pose, to: bool) -> list[float] | None:
        """Per state, the cost to drive to ``pose`` (``to``) or from it, 0 where it cannot.

        ``None``: no clear state near ``pose``. Kept for the last few poses asked (a
        query's later stages ask again), as the list the look-up reads.
        """
        key = (pose.x, pose.y, pose.yaw, to)
        if key in self._tables:
            self._tables.move_to_end(key)
            return self._tables[key]
        seeds = self._seeds(pose)
        values = None
        if len(seeds):
            graph = self.backward if to else self.forward
            dist = dijkstra(graph, directed=True, indices=seeds, min_only=True)
            table = dist.reshape(-1, self.gears).min(axis=1)
            values = np.where(np.isfinite(table), table, 0.0).tolist()
        self._tables[key] = values
        if len(self._tables) > _KEPT:
            self._tables.popitem(last=False)
        return values

    def estimate(self, pose: Pose, to: bool) -> Estimate | None:
        """The cost to drive to ``pose`` (``to``) or from it, as a scalar look-up.

        0 off the lattice or where it cannot reach; ``None`` when no clear state is
        near ``pose``.

        Examples
        --------
        >>> from rrtdrive.maps import Map
        >>> empty = Map("open", (0.0, 0.0, 30.0, 10.0), (), Pose(3, 5, 0), Pose(25, 5, 0))
        >>> lat = HeadingLattice.build(
        ...     CollisionChecker.for_map(empty), empty.bounds, 6.0, True, 2.0, 5.0
        ... )
        >>> h = lat.estimate(Pose(25.25, 5.25, 0.0), to=True)

        15 m straight ahead of the goal: six straight moves of ``6 * 2 pi / 16`` m
        (from cell to cell, so a little less); off the map, no estimate:

        >>> round(h(10.25, 5.25, 0.0), 1), h(-5.0, 5.0, 0.0)
        (14.1, 0.0)
        """
        values = self._costs(pose, to)
        if values is None:
            return None
        (x0, y0), cell, k = self.origin, self.cell, self.headings
        nx, ny = self.shape
        scale = k / _TWO_PI
        floor = math.floor

        def estimate(x: float, y: float, yaw: float) -> float:
            i, j = floor((x - x0) / cell), floor((y - y0) / cell)
            if not (0 <= i < nx and 0 <= j < ny):
                return 0.0
            return values[(i * ny + j) * k + round((yaw % _TWO_PI) * scale) % k]

        return estimate


def _move(
    poses: np.ndarray, gear: int, steer: int, radius: float, arc: float
) -> tuple[np.ndarray, np.ndarray]:
    """End and middle poses of one move from each of ``poses`` (``steer``: -1, 0, +1)."""
    x, y, yaw = poses[:, 0], poses[:, 1], poses[:, 2]

    def at(s: float) -> np.ndarray:
        if steer == 0:
            return np.column_stack([x + gear * s * np.cos(yaw), y + gear * s * np.sin(yaw), yaw])
        kappa = steer / radius
        turned = yaw + gear * kappa * s
        return np.column_stack(
            [
                x + (np.sin(turned) - np.sin(yaw)) / kappa,
                y - (np.cos(turned) - np.cos(yaw)) / kappa,
                turned,
            ]
        )

    return at(arc), at(arc / 2.0)


def heading_lattice(
    checker: CollisionChecker,
    bounds: tuple[float, float, float, float],
    radius: float,
    reverse: bool,
    config: HybridConfig,
) -> HeadingLattice:
    """The map's lattice for a turning radius and gears, built once per map (set-up)."""
    key = (
        "hybrid-lattice", float(radius), bool(reverse), config.reverse_cost,
        config.gear_change_cost, config.lattice_cell, config.lattice_headings,
        config.lattice_nodes,
    )  # fmt: skip
    return checker.grid.derived(
        key,
        lambda: HeadingLattice.build(
            checker, bounds, radius, reverse, config.reverse_cost, config.gear_change_cost,
            config.lattice_cell, config.lattice_headings, config.lattice_nodes,
        ),  # fmt: skip
    )


def guided(heuristic: Heuristic, extra: Estimate) -> Heuristic:
    """``heuristic`` with ``extra`` taken into its maximum (its scalar form).

    Examples
    --------
    >>> from rrtdrive.maps import Map
    >>> from rrtdrive.planning.hybrid.heuristic import FreeCellGraph, HolonomicField
    >>> empty = Map("open", (0.0, 0.0, 20.0, 10.0), (), Pose(3, 5, 0), Pose(15, 5, 0))
    >>> grid = FreeCellGraph.build(CollisionChecker.for_map(empty), 1.0)
    >>> plain = Heuristic(HolonomicField.towards(grid, empty.goal), None, empty.goal)
    >>> round(plain.at(10.0, 5.0, 0.0), 1), guided(plain, lambda x, y, yaw: 40.0).at(10.0, 5.0, 0.0)
    (5.0, 40.0)
    """
    own = heuristic.scalar_nonholonomic
    gx, gy = heuristic.goal.x, heuristic.goal.y
    hypot = math.hypot

    if own is None:

        def combined(x: float, y: float, yaw: float) -> float:
            return max(extra(x, y, yaw), hypot(x - gx, y - gy))

    else:

        def combined(x: float, y: float, yaw: float) -> float:
            return max(extra(x, y, yaw), own(x, y, yaw))

    return dataclasses.replace(heuristic, scalar_nonholonomic=combined)
