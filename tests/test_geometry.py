"""The shared geometry primitives: wrap, box corners, densify, projection."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from rrtdrive.geometry import box_corners, densify, project_to_polyline, wrap_angle
from rrtdrive.maps import Obstacle
from rrtdrive.types import VehicleParams
from rrtdrive.vehicle import footprint_corners

angles = st.floats(-1e4, 1e4, allow_nan=False)


@given(angles)
def test_wrap_range_idempotence_congruence(a):
    w = wrap_angle(a)
    assert -math.pi <= w < math.pi
    assert wrap_angle(w) == pytest.approx(w, abs=1e-12)
    # Congruent: a - w is a whole number of turns.
    turns = (a - w) / (2.0 * math.pi)
    assert turns == pytest.approx(round(turns), abs=1e-9)


@given(arrays(float, st.integers(0, 20), elements=angles))
def test_wrap_arrays_match_scalars(a):
    w = wrap_angle(a)
    assert w.shape == a.shape
    assert all(w[i] == wrap_angle(float(a[i])) for i in range(len(a)))


polylines = arrays(
    float, st.tuples(st.integers(1, 12), st.just(3)),
    elements=st.floats(-50.0, 50.0, allow_nan=False),
)


@settings(max_examples=200, deadline=None)
@given(polylines, st.floats(0.05, 5.0), st.sampled_from([(0.0, 0.0), (1e-5, 0.0), (0.0, 1e-9)]))
def test_densify_spacing_and_vertices(p, spacing, slack):
    d = densify(p, spacing, angle_column=2, rel_slack=slack[0], abs_slack=slack[1])
    pts = d.points
    # Endpoints kept, every input position is a row at vertex_index.
    np.testing.assert_array_equal(pts[0], p[0])
    np.testing.assert_array_equal(pts[-1], p[-1])
    if len(p) >= 2:
        np.testing.assert_allclose(pts[d.vertex_index, :2], p[:, :2], atol=1e-9)
        assert len(d.segment) == len(pts)
        gaps = np.hypot(*np.diff(pts[:, :2], axis=0).T)
        assert gaps.max() <= spacing * (1 + 1e-9) + 1e-9
        # Angles turn the short way: each step is at most half a turn over the segment's pieces.
        dyaw = np.abs(wrap_angle(np.diff(pts[:, 2])))
        assert np.all(dyaw <= math.pi / d.pieces[d.segment[:-1]] + 1e-9)


def test_box_corners_reference_and_order():
    v = VehicleParams()
    pose = np.array([1.0, 2.0, 0.7])
    c = box_corners(*pose, -v.rear_overhang, v.front_extent, v.width / 2.0)
    np.testing.assert_array_equal(c, footprint_corners(pose, v))
    # Counter-clockwise: positive shoelace area equal to length x width.
    x, y = c[:, 0], c[:, 1]
    area = 0.5 * np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y)
    assert area == pytest.approx(v.length * v.width)


def test_box_corners_rotate_first_is_the_obstacle_formula():
    o = Obstacle((3.0, -4.0), (4.3, 1.8), 0.3)
    c, s = math.cos(o.yaw), math.sin(o.yaw)
    local = np.array([[-2.15, -0.9], [2.15, -0.9], [2.15, 0.9], [-2.15, 0.9]])
    expected = local @ np.array([[c, -s], [s, c]]).T + np.asarray(o.center)
    np.testing.assert_array_equal(o.corners(), expected)
    np.testing.assert_allclose(
        box_corners(3.0, -4.0, 0.3, -2.15, 2.15, 0.9), expected, atol=1e-12
    )


@settings(max_examples=100, deadline=None)
@given(
    arrays(float, st.tuples(st.integers(2, 8), st.just(2)),
           elements=st.floats(-20.0, 20.0, allow_nan=False)),
    arrays(float, st.tuples(st.integers(1, 10), st.just(2)),
           elements=st.floats(-30.0, 30.0, allow_nan=False)),
)
def test_projection_is_nearest_and_chunking_is_exact(line, pts):
    keep = np.concatenate([[True], np.hypot(*np.diff(line, axis=0).T) > 1e-6])
    line = line[keep]
    if len(line) < 2:
        return
    pr = project_to_polyline(line, pts)
    np.testing.assert_allclose(np.hypot(*(pts - pr.foot).T), pr.distance, atol=1e-9)
    # Nearest: no densified point of the polyline is closer.
    dense = densify(line, 0.05).points
    brute = np.min(np.hypot(*(pts[:, None, :] - dense[None]).transpose(2, 0, 1)), axis=1)
    assert np.all(pr.distance <= brute + 1e-9)
    arc = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(line, axis=0).T))])
    assert np.all((pr.s >= -1e-12) & (pr.s <= arc[-1] + 1e-9))
    one = project_to_polyline(line, pts, chunk=1)
    np.testing.assert_array_equal(one.s, pr.s)
    np.testing.assert_array_equal(one.segment, pr.segment)
