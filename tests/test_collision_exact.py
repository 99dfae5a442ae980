"""The lean exact rectangle test gives what the code it replaced gave, bit for bit (issue 13).

The reference is the checker's exact test as it was at 44c06ab: corners by
:func:`~rrtdrive.vehicle.footprint_corners`, the bounds compared corner by corner,
then ``shapely.polygons`` and ``shapely.dwithin`` / ``shapely.intersects``.
"""

from __future__ import annotations

import functools

import numpy as np
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

from rrtdrive.collision import CollisionChecker
from rrtdrive.collision.exact import RectangleTest
from rrtdrive.maps import builtin_map
from rrtdrive.planning.base import cached_checker
from rrtdrive.vehicle import footprint_corners


def _reference_exact(checker: CollisionChecker, poses: np.ndarray, clearance: float):
    """CollisionChecker._exact as it was (44c06ab)."""
    corners = footprint_corners(np.asarray(poses, dtype=float).reshape(-1, 3), checker.vehicle)
    xmin, ymin, xmax, ymax = checker.bounds
    if clearance > 0.0:
        xmin, ymin = xmin + clearance, ymin + clearance
        xmax, ymax = xmax - clearance, ymax - clearance
    x, y = corners[..., 0], corners[..., 1]
    inside = ((x >= xmin) & (x <= xmax) & (y >= ymin) & (y <= ymax)).all(axis=1)
    union = checker.obstacle_union
    if union.is_empty:
        return inside
    test = np.flatnonzero(inside)
    if len(test):
        rects = shapely.polygons(corners[test])
        if clearance > 0.0:
            inside[test] = ~shapely.dwithin(union, rects, clearance)
        else:
            inside[test] = ~shapely.intersects(union, rects)
    return inside


@functools.cache
def _empty_checker() -> CollisionChecker:
    # Once: building a checker (its distance field) took most of an example's time.
    m = builtin_map("parking_lot")
    return CollisionChecker(m.bounds, (), m.vehicle)


@functools.cache
def _lot_checker() -> CollisionChecker:
    return cached_checker(builtin_map("parking_lot"))


batch = st.lists(
    st.tuples(st.floats(-4.0, 104.0), st.floats(-4.0, 104.0), st.floats(-7.0, 7.0)),
    min_size=0,
    max_size=12,
)


# Five times the profile's examples: 300 in CI, 3 000 under "stress" (with the
# checkers built once, not per example, an example costs milliseconds).
@settings(max_examples=5 * settings.default.max_examples, deadline=None)
@given(batch, st.sampled_from([0.0, 0.05, 0.15, 3.0]), st.booleans())
def test_exact_test_is_the_reference(poses, clearance: float, empty: bool) -> None:
    """Batches inside, across and beyond the bounds, with and without obstacles."""
    checker = _empty_checker() if empty else _lot_checker()
    p = np.array(poses, dtype=float).reshape(-1, 3)
    got = checker.rectangles_free(p, clearance)
    assert got.dtype == bool and got.shape == (len(p),)
    assert np.array_equal(got, _reference_exact(checker, p, clearance))
    # The corners themselves: the same floats, signs of zeros included.
    want = footprint_corners(p, checker.vehicle)
    assert np.array_equal(checker._corners(p), want)
    assert np.array_equal(np.signbit(checker._corners(p)), np.signbit(want))


def test_exact_test_near_the_parked_cars_is_the_reference() -> None:
    """Many poses close to obstacles (both answers), in batches of every size up to 40."""
    checker = cached_checker(builtin_map("parking_lot"))
    rng = np.random.default_rng(7)
    p = np.column_stack(
        [rng.uniform(0, 100, 4000), rng.uniform(0, 100, 4000), rng.uniform(-4, 4, 4000)]
    )
    seen = set()
    start = 0
    for size in list(range(1, 41)) * 5:
        part = p[start : start + size]
        start += size
        for clearance in (0.0, 0.15):
            got = checker.rectangles_free(part, clearance)
            assert np.array_equal(got, _reference_exact(checker, part, clearance))
            seen.update(got.tolist())
    assert seen == {True, False}


def test_polygons_are_shapelys() -> None:
    """The ring and polygon ufuncs called directly: the geometries shapely.polygons makes."""
    vehicle = builtin_map("parking_lot").vehicle
    test = RectangleTest((0.0, 0.0, 10.0, 10.0), shapely.box(4.0, 4.0, 5.0, 5.0), vehicle)
    rng = np.random.default_rng(3)
    for n in (1, 3, 70, 130):  # beyond the initial hole buffer too
        corners = test.corners(rng.uniform(-20, 20, (n, 3)))
        got, want = test.polygons(corners), shapely.polygons(corners)
        assert len(got) == n
        assert all(shapely.to_wkb(a) == shapely.to_wkb(b) for a, b in zip(got, want, strict=True))
