"""Seeded sets of random free poses on a map: the query sets of the coverage benchmarks."""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from rrtdrive.maps import Map, builtin_map
from rrtdrive.planning.base import cached_checker
from rrtdrive.types import InputError, Pose, require_int

#: Draws allowed per pose asked for before giving up (a map with almost no free room).
DRAWS_PER_POSE = 10_000


def random_free_poses(map_: Map | str, count: int, seed: int, field: str = "goal") -> list[Pose]:
    """``count`` seeded poses whose body is free and which the map accepts as ``field``.

    Positions are uniform over the map's bounds and headings uniform over
    ``[-pi, pi)``; a draw is kept when the car's body is clear of every obstacle
    and the map takes it as its ``start`` or ``goal`` (inside the bounds). The
    same seed gives the same poses on any machine.

    Parameters
    ----------
    map_ : Map or str
        The map, or the name of a built-in map.
    count : int
        How many poses to return (>= 0).
    seed : int
        Seed of the random generator (``numpy.random.default_rng``).
    field : str
        ``"goal"`` or ``"start"``: which of the map's poses each draw must be
        acceptable as.

    Returns
    -------
    list of Pose
        The poses, in the order drawn.

    Raises
    ------
    InputError
        If ``field`` is neither ``"start"`` nor ``"goal"``, ``count`` is not
        an integer >= 0, or the map has so little free room that
        ``DRAWS_PER_POSE * count`` draws do not find ``count`` poses.

    Examples
    --------
    >>> poses = random_free_poses("parking_lot", 3, seed=1)
    >>> len(poses), poses == random_free_poses("parking_lot", 3, seed=1)
    (3, True)
    """
    if field not in ("start", "goal"):
        raise InputError(f"field: must be 'start' or 'goal', got {field!r}")
    count = require_int("count", count, 0)
    base = builtin_map(map_) if isinstance(map_, str) else map_
    checker = cached_checker(base)
    rng = np.random.default_rng(seed)
    xmin, ymin, xmax, ymax = base.bounds
    poses: list[Pose] = []
    for _ in range(DRAWS_PER_POSE * count):
        if len(poses) == count:
            break
        x, y = rng.uniform(xmin, xmax), rng.uniform(ymin, ymax)
        pose = Pose(x, y, rng.uniform(-math.pi, math.pi))
        if not checker.pose_free(pose.as_tuple()):  # quick reject; the map checks again
            continue
        try:
            dataclasses.replace(base, **{field: pose})
        except InputError:
            continue
        poses.append(pose)
    if len(poses) < count:
        raise InputError(
            f"map: {DRAWS_PER_POSE * count} random draws found only {len(poses)} of {count} "
            f"free {field} poses on {base.name!r}; the map has almost no room for the car"
        )
    return poses
