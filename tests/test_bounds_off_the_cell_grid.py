"""A map whose width is not a whole number of cells: the checker against shapely at the far wall.

Found by mutation testing (session 39): every existing test map is a whole number of
0.1 m cells wide. Cells are aligned with ``xmin``/``ymin`` only; on the ``xmax``/``ymax``
side a cell can straddle the wall with its centre just inside, so it is not occupied,
and the field overestimates the distance to the wall by up to ``(1.5 - sqrt 2) h``
(8.5 mm at 0.1 m). The exact test's disc screens keep no margin, so ``poses_free``
clears bodies that shapely finds outside the bounds or within the clearance asked for.
Fixed: a cell that reaches past xmax / ymax is occupied (grid.rasterise).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely

from rrtdrive.collision import CollisionChecker
from rrtdrive.types import VehicleParams
from rrtdrive.vehicle import cover_discs, footprint_corners

XMAX = 30.05  # 300.5 cells of 0.1 m
BOUNDS = (0.0, 0.0, XMAX, 20.0)


def test_clearance_is_a_lower_bound_at_a_wall_off_the_cell_grid():
    checker = CollisionChecker(BOUNDS, (), VehicleParams())
    x = np.linspace(XMAX - 3.0, XMAX, 30001)
    points = np.column_stack([x, np.full_like(x, 10.0)])
    true = shapely.distance(shapely.box(*BOUNDS).exterior, shapely.points(points))
    assert np.all(checker.clearances(points) <= true + 1e-9)


@pytest.mark.parametrize(("width", "clearance"), [(1.82, 0.0), (1.8, 0.108)])
def test_batch_exact_test_agrees_with_shapely_at_a_wall_off_the_cell_grid(width, clearance):
    # A front corner pointing straight at the wall from the front screening disc's centre,
    # swept across a cell: the disc screen's worst case.
    car = VehicleParams(width=width)
    checker = CollisionChecker(BOUNDS, (), car)
    offsets, radius = cover_discs(car, 3)
    yaw = -math.atan2(car.width / 2, car.front_extent - offsets[-1])
    cx = XMAX - radius - clearance + np.linspace(0.0, 0.012, 1201)
    poses = np.column_stack([cx - math.cos(yaw) * offsets[-1],
                             np.full_like(cx, 10.0) - math.sin(yaw) * offsets[-1],
                             np.full_like(cx, yaw)])  # fmt: skip
    inner = shapely.box(clearance, clearance, XMAX - clearance, 20.0 - clearance)
    want = shapely.contains(inner, shapely.polygons(footprint_corners(poses, car)))
    assert np.array_equal(checker.poses_free(poses, clearance), want)


@pytest.mark.parametrize(
    ("xmax", "ymax", "cell"),
    [(30.05, 20.0, 0.1), (20.0, 17.33, 0.1), (41.3, 23.9, 0.5), (9.97, 9.91, 0.15)],
)
def test_clearance_is_a_lower_bound_near_every_wall(xmax, ymax, cell):
    from rrtdrive.collision import CheckerConfig

    bounds = (0.0, 0.0, xmax, ymax)
    checker = CollisionChecker(bounds, (), VehicleParams(), CheckerConfig(resolution=cell))
    rng = np.random.default_rng(0)
    points = np.column_stack([rng.uniform(0.0, xmax, 20_000), rng.uniform(0.0, ymax, 20_000)])
    true = shapely.distance(shapely.box(*bounds).exterior, shapely.points(points))
    assert np.all(checker.clearances(points) <= true + 1e-9)
