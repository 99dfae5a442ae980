"""Passage cells against their definition, tested one cell at a time in plain Python."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rrtdrive.collision import CollisionChecker
from rrtdrive.maps import Map, Obstacle, builtin_map
from rrtdrive.types import Pose


def _by_definition(checker: CollisionChecker, start: tuple[float, float], width: float) -> list:
    """Every inner cell in the band, of the start's component, on a two-walled ridge."""
    grid = checker.grid
    cl, labels, h = grid.clearance, grid.component_labels, grid.resolution
    nx, ny = cl.shape
    i0 = math.floor((start[0] - grid.origin[0]) / h)
    j0 = math.floor((start[1] - grid.origin[1]) / h)
    label = int(labels[i0, j0]) if 0 <= i0 < nx and 0 <= j0 < ny else 0
    lo, hi = grid.edge_radius, grid.edge_radius + width
    xmin, ymin, xmax, ymax = grid.bounds
    out = []
    for i in range(1, nx - 1):
        for j in range(1, ny - 1):
            c = float(cl[i, j])
            if not lo <= c <= hi or (label and labels[i, j] != label):
                continue
            ridge = False
            for di, dj in ((1, 0), (0, 1), (1, 1), (1, -1)):
                a, b = float(cl[i + di, j + dj]), float(cl[i - di, j - dj])
                if not (c >= a and c >= b and c > min(a, b)):
                    continue
                k = round(c / (math.hypot(di, dj) * h))
                walls = all(
                    cl[min(max(i + s * k * di, 0), nx - 1), min(max(j + s * k * dj, 0), ny - 1)]
                    <= 0.3 * c
                    for s in (1, -1)
                )
                ridge = ridge or walls
            x, y = grid.origin[0] + (i + 0.5) * h, grid.origin[1] + (j + 0.5) * h
            if ridge and xmin < x < xmax and ymin < y < ymax:
                out.append((x, y))
    return out


def _box_map(seed: int) -> Map:
    rng = np.random.default_rng(seed)
    boxes = tuple(
        Obstacle(
            (float(rng.uniform(4, 26)), float(rng.uniform(4, 26))),
            (float(rng.uniform(1, 6)), float(rng.uniform(1, 6))),
            float(rng.uniform(0, math.pi)),
        )
        for _ in range(12)
    )
    start, goal = Pose(-5.0, 15.0, 0.0), Pose(32.5, 15.0, 0.0)
    return Map(f"boxes{seed}", (-8.0, 0.0, 38.0, 30.0), boxes, start, goal)


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("width", [0.6, 1.5])
def test_passage_cells_match_the_definition_on_random_box_maps(seed, width):
    m = _box_map(seed)
    checker = CollisionChecker.for_map(m)
    for start in (m.start.xy, (15.0, 15.0), (-100.0, -100.0)):  # the last: in no component
        cells = checker.passage_cells(start, width)
        expected = np.array(_by_definition(checker, start, width)).reshape(-1, 2)
        # The same cells in the same (row-major) order: the samplers draw by index.
        np.testing.assert_array_equal(cells, expected)


@pytest.mark.parametrize("name", ["narrow_gap", "no_path"])
def test_passage_cells_match_the_definition_on_builtin_maps(name):
    m = builtin_map(name)
    checker = CollisionChecker.for_map(m)
    for start in (m.start.xy, m.goal.xy):  # no_path: two components, one per end
        cells = checker.passage_cells(start, 0.6)
        assert len(cells) > 0
        np.testing.assert_array_equal(cells, np.array(_by_definition(checker, start, 0.6)))
