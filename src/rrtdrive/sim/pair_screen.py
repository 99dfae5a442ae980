"""The pairs of a scene whose collision handling could change anything, found at once.

highway-env's ``Road.step`` calls ``handle_collisions`` for every pair of vehicles and
every vehicle-object pair. A call changes nothing unless highway-env's own test finds
the two rectangles intersecting or about to (its separating-axis test, the second
with the step's relative displacement), after a spherical pre-check. Most pairs pass
the pre-check and still do not touch: the walls of the overtake road lie within every
car's pre-check circle, and those calls took most of an overtake episode's time.

:func:`pairs_to_handle` runs the pre-check and the separating-axis test of every pair
at once in numpy and returns the pairs neither rules out, in ``Road.step``'s order.
A pair is ruled out only when some axis separates the rectangles by more than
:data:`MARGIN`, both now and with the displacement, so the rounding of highway-env's
own arithmetic cannot drop a pair it would act on; the calls left run unchanged.
A road's objects never move (highway-env steps only its vehicles), so a caller that
steps the same objects again passes their boxes, :func:`object_boxes`, computed once.
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import lru_cache
from typing import Any

import numpy as np

__all__ = ["MARGIN", "object_boxes", "pairs_to_handle"]

#: Separation (m) beyond which a pair is ruled out; float error of highway-env's
#: projections at the scenes' coordinates is about 1e-13 m.
MARGIN = 1e-7

# highway-env's RoadObject.polygon() corners, in units of (length / 2, width / 2).
_UNIT = np.array([[-1.0, -1.0], [-1.0, 1.0], [1.0, 1.0], [1.0, -1.0]])


def _boxes(items: Sequence[Any]) -> tuple[np.ndarray, ...]:
    """Corners ``(n, 4, 2)``, centres, diagonals and velocities of the items."""
    pos = np.array([o.position for o in items], dtype=float).reshape(-1, 2)
    heading = np.array([o.heading for o in items], dtype=float)
    half = np.array([(o.LENGTH / 2, o.WIDTH / 2) for o in items], dtype=float).reshape(-1, 2)
    speed = np.array([o.speed for o in items], dtype=float)
    diag = np.array([o.diagonal for o in items], dtype=float)
    c, s = np.cos(heading), np.sin(heading)
    local = _UNIT[None] * half[:, None, :]
    corners = np.stack(
        [c[:, None] * local[..., 0] - s[:, None] * local[..., 1],
         s[:, None] * local[..., 0] + c[:, None] * local[..., 1]], axis=-1,
    ) + pos[:, None, :]  # fmt: skip
    velocity = speed[:, None] * np.column_stack([c, s])
    return corners, pos, diag, velocity, speed


def object_boxes(objects: Sequence[Any]) -> tuple[np.ndarray, ...]:
    """The boxes of static road objects, for :func:`pairs_to_handle` to reuse step after step."""
    return _boxes(objects)


@lru_cache(maxsize=32)
def _pair_order(n: int, total: int) -> tuple[np.ndarray, np.ndarray]:
    """Pair indices in ``Road.step``'s order (``n`` vehicles first among ``total`` items).

    Each vehicle with the vehicles after it, then with the objects.
    """
    vi, vj = np.triu_indices(n, 1)
    oi, oj = np.meshgrid(np.arange(n), np.arange(n, total), indexing="ij")
    first = np.concatenate([vi, oi.ravel()])
    second = np.concatenate([vj, oj.ravel()])
    order = np.lexsort((second, first))
    first, second = first[order], second[order]
    first.flags.writeable = False  # shared between calls
    second.flags.writeable = False
    return first, second


def _interval_distance(
    min_a: np.ndarray, max_a: np.ndarray, min_b: np.ndarray, max_b: np.ndarray
) -> np.ndarray:
    # highway_env.utils.interval_distance, elementwise.
    return np.where(min_a < min_b, min_b - max_a, min_a - max_b)


def _separated(a: np.ndarray, b: np.ndarray, rel: np.ndarray) -> np.ndarray:
    """Whether some axis separates boxes ``a`` and ``b`` by ``MARGIN``, now and swept.

    ``a``, ``b``: corners ``(m, 4, 2)``; ``rel``: ``a``'s displacement minus ``b``'s,
    ``(m, 2)``. The axes are the normals of both boxes' four edges, as highway-env's.
    """
    normals = []
    for box in (a, b):
        edge = np.roll(box, -1, axis=1) - box  # p[k] -> p[k + 1], closing the polygon
        n = np.stack([-edge[..., 1], edge[..., 0]], axis=-1)
        normals.append(n / np.linalg.norm(n, axis=-1, keepdims=True))
    axes = np.concatenate(normals, axis=1)  # (m, 8, 2)
    proj_a = np.einsum("mkd,mcd->mkc", axes, a)
    proj_b = np.einsum("mkd,mcd->mkc", axes, b)
    min_a, max_a = proj_a.min(axis=2), proj_a.max(axis=2)
    min_b, max_b = proj_b.min(axis=2), proj_b.max(axis=2)
    now = _interval_distance(min_a, max_a, min_b, max_b) > MARGIN
    shift = np.einsum("mkd,md->mk", axes, rel)
    swept = _interval_distance(
        min_a + np.minimum(shift, 0.0), max_a + np.maximum(shift, 0.0), min_b, max_b
    ) > MARGIN
    return now.any(axis=1) & swept.any(axis=1)


def pairs_to_handle(
    vehicles: Sequence[Any],
    objects: Sequence[Any],
    dt: float,
    both_ways: Sequence[bool],
    objects_boxes: tuple[np.ndarray, ...] | None = None,
) -> list[tuple[Any, Any]]:
    """The ``(vehicle, other)`` pairs whose ``handle_collisions`` may act, in ``Road.step``'s order.

    Parameters
    ----------
    vehicles, objects : sequence
        The road's vehicles and objects (highway-env road objects).
    dt : float
        The step.
    both_ways : sequence of bool
        Per vehicle: its pre-check widens by ``|speed| * dt`` (a car that reverses,
        :class:`~rrtdrive.sim.ego.EgoVehicle`) rather than highway-env's ``speed * dt``.
    objects_boxes : tuple of numpy.ndarray, optional
        :func:`object_boxes` of ``objects`` when they have not moved since (the same
        pairs come out, sooner); computed here otherwise.
    """
    n = len(vehicles)
    items = [*vehicles, *objects]
    if n == 0 or len(items) < 2:
        return []
    if objects_boxes is None or not objects:
        corners, pos, diag, velocity, speed = _boxes(items)
    else:
        corners, pos, diag, velocity, speed = (
            np.concatenate([mine, theirs])
            for mine, theirs in zip(_boxes(vehicles), objects_boxes, strict=True)
        )
    first, second = _pair_order(n, len(items))
    extra = np.where(np.asarray(both_ways, dtype=bool), np.abs(speed[:n]), speed[:n]) * dt
    reach = (diag[first] + diag[second]) / 2.0 + extra[first]
    near = np.hypot(*(pos[second] - pos[first]).T) <= reach + MARGIN
    keep = near.copy()
    if near.any():
        f, s = first[near], second[near]
        keep[near] = ~_separated(corners[f], corners[s], (velocity[f] - velocity[s]) * dt)
    return [(items[i], items[j]) for i, j in zip(first[keep], second[keep], strict=True)]
