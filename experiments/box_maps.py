"""Random box maps for the scaling benchmarks and the tests that share their maps.

A module of its own, importing the installed ``rrtdrive`` as it is: the benchmark
scripts put ``src/`` first on ``sys.path`` (to run from a checkout), which a test must
not (an installed package's ``rrtdrive.envs`` is not under ``src/``), so a test that
imported ``box_map`` from a script hid it from the bench workers.
"""

from __future__ import annotations

import math
import random

from rrtdrive.maps import Map, Obstacle
from rrtdrive.types import Pose

__all__ = ["box_map"]


def box_map(side: float, count: int, seed: int = 0, name: str | None = None) -> Map:
    """``count`` boxes of 1-8 m at random places and headings, none near the ends.

    A ``side`` x ``side`` m square; start ``(5, 5)`` and goal ``(side - 5, side - 5)``,
    both heading along +x, no box centre within 15 m of either; named
    ``boxes_{side}_{count}`` unless ``name`` is given.
    """
    rng = random.Random(seed)
    start, goal = Pose(5.0, 5.0, 0.0), Pose(side - 5.0, side - 5.0, 0.0)
    boxes: list[Obstacle] = []
    while len(boxes) < count:
        x, y = rng.uniform(0, side), rng.uniform(0, side)
        if min(math.hypot(x - p.x, y - p.y) for p in (start, goal)) < 15.0:
            continue
        size = (rng.uniform(1, 8), rng.uniform(1, 8))
        boxes.append(Obstacle((x, y), size, rng.uniform(0, math.pi)))
    label = f"boxes_{side:g}_{count}" if name is None else name
    return Map(label, (0.0, 0.0, side, side), tuple(boxes), start, goal)


if __name__ == "__main__":
    import sys

    # Run as a script it did nothing and exited 0: say what it is.
    sys.exit("box_maps.py is a library module of experiments/bench_diagnosis.py, "
             "bench_distance_field.py and bench_ramp_chunks.py: run one of those (--help)")
