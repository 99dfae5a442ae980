"""The checker's grid cache: the same data as the planners' own functions, built once and timed."""

from __future__ import annotations

import numpy as np
import pytest
import shapely

from rrtdrive.collision import CollisionChecker
from rrtdrive.maps import builtin_map
from rrtdrive.planning import improved, postprocess, rrt

MAPS = ("overtake", "parking_lot", "narrow_gap", "no_path")


@pytest.fixture(scope="module", params=MAPS)
def checker_and_map(request):
    m = builtin_map(request.param)
    return CollisionChecker.for_map(m), m


def test_free_cells_equal_the_samplers_function(checker_and_map):
    checker, m = checker_and_map
    for start in (m.start.xy, m.goal.xy, (-50.0, -50.0)):
        mine = checker.free_cells(start)
        theirs = rrt.free_cells(checker, start)
        assert mine.dtype == theirs.dtype and np.array_equal(mine, theirs)
        assert checker.free_cells(start) is mine  # cached


def test_passage_cells_equal_the_improved_planners_function(checker_and_map):
    checker, m = checker_and_map
    for width in (0.6, 0.3):
        mine = checker.passage_cells(m.start.xy, width)
        theirs = improved.passage_cells(checker, m.start.xy, width)
        assert np.array_equal(mine, theirs)
        assert checker.passage_cells(m.start.xy, width) is mine


def test_obstacle_union_equals_the_post_processors(checker_and_map):
    checker, _ = checker_and_map
    theirs = postprocess._obstacle_union(checker)
    assert shapely.equals_exact(checker.obstacle_union, theirs, tolerance=0.0) or (
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
