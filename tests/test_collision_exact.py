"""The lean exact rectangle test gives what the code it replaced gave, bit for bit (issue 13).

The reference is the checker's exact test as it was at 44c06ab: corners by
:func:`~rrtdrive.vehicle.footprint_corners`, the bounds compared corner by corner,
then ``shapely.polygons`` and ``shapely.dwithin`` / ``shapely.intersects``.
"""

from __future__ import annotations

import functools

import numpy as np
import pytest
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
    # Strict since session 41 (a corner on the bounds touches them); 44c06ab had <=.
    inside = ((x > xmin) & (x < xmax) & (y > ymin) & (y < ymax)).all(axis=1)
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


def test_a_body_touching_the_bounds_collides_as_the_verifier_says() -> None:
    """A corner exactly on the bounds (or on the bounds shrunk by the clearance) is not free.

    As touching an obstacle (``intersects``) and as :func:`rrtdrive.verify.verify_path`
    and the map checks judge it; a tenth of a millimetre inside is free.
    """
    from rrtdrive.maps import Map
    from rrtdrive.types import Path, Pose, VehicleParams
    from rrtdrive.verify import verify_path

    car = VehicleParams()
    back, half = car.rear_overhang, car.width / 2.0
    checker = CollisionChecker((0.0, 0.0, 40.0, 40.0), (), car)
    for wanted in (0.0, 0.15):
        for pose, axis in (([back + wanted, 5.0, 0.0], 0), ([8.0, half + wanted, 0.0], 1)):
            on = np.array([pose])
            # The clearance the nearest corner lands on exactly (0.15 itself rounds).
            clearance = float(footprint_corners(on, car)[0, :, axis].min())
            assert clearance == pytest.approx(wanted, abs=1e-12)
            assert not checker.poses_free(on, clearance).any()
            assert not checker.rectangles_free(on, clearance).any()
            assert not checker.pose_free(pose, clearance)
            off = on.copy()
            off[0, axis] += 1e-4
            assert checker.poses_free(off, clearance).all()
    xs = np.arange(0.0, 3.01, 0.1)
    rows = np.column_stack([back + xs, 5 + 0 * xs, 0 * xs, 0 * xs, 1 + 0 * xs])
    m = Map("m", (0.0, 0.0, 40.0, 40.0), (), Pose(back, 5, 0), Pose(back + 3.0, 5, 0),
            check_query=False)
    assert verify_path(m, Path(rows, np.zeros((0, 2)))).collides_with == "the bounds"
    assert not checker.path_free(rows)[0]
