"""The checker's grid cache: the same data as the planners' own functions, built once and timed."""

from __future__ import annotations

import numpy as np
import pytest
import shapely

from rrtdrive.collision import CollisionChecker
from rrtdrive.maps import builtin_map

MAPS = ("overtake", "parking_lot", "narrow_gap", "no_path")


@pytest.fixture(scope="module", params=MAPS)
def checker_and_map(request):
    m = builtin_map(request.param)
    return CollisionChecker.for_map(m), m


def test_free_cells_are_standable_cells_of_the_start_component(checker_and_map):
    checker, m = checker_and_map
    cells = checker.free_cells(m.start.xy)
    assert checker.free_cells(m.start.xy) is cells  # cached
    labels = checker.component_labels.ravel()
    if len(cells):
        assert len(np.unique(labels[cells])) == 1 and labels[cells][0] > 0
    assert len(checker.free_cells((-50.0, -50.0))) == 0  # outside the map: no component


def test_passage_cells_are_cached_per_width(checker_and_map):
    checker, m = checker_and_map
    for width in (0.6, 0.3):
        cells = checker.passage_cells(m.start.xy, width)
        assert checker.passage_cells(m.start.xy, width) is cells
        assert cells.ndim == 2 and cells.shape[1] == 2


def test_obstacle_union_is_the_prepared_union_of_the_obstacles(checker_and_map):
    checker, _ = checker_and_map
    theirs = shapely.union_all([o.polygon() for o in checker.obstacles])
    assert checker.obstacle_union.equals(theirs) or (
        checker.obstacle_union.is_empty and theirs.is_empty
    )
    assert shapely.is_prepared(checker.obstacle_union)


def test_setup_time_counts_the_field_and_the_lazy_builds():
    m = builtin_map("narrow_gap")
    checker = CollisionChecker.for_map(m)
    t_field = checker.setup_time_s
    assert t_field > 0.0
    checker.passage_cells(m.start.xy)  # builds the labels too
    t_lazy = checker.setup_time_s
    assert t_lazy > t_field
    checker.passage_cells(m.start.xy)  # cached: no more set-up
    assert checker.setup_time_s == t_lazy
