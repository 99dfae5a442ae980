from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from rrtdrive.types import InputError, VehicleParams
from rrtdrive.vehicle import bicycle_step, cover_discs, footprint_corners, footprint_polygon


def test_paper_values():
    v = VehicleParams()
    assert (v.length, v.width, v.wheelbase) == (4.30, 1.80, 2.51)
    assert v.kappa_max == pytest.approx(1 / 6.0)
    assert v.rear_overhang == pytest.approx(0.895)
    assert v.front_extent == pytest.approx(3.405)
    assert v.max_steer == pytest.approx(math.radians(30))
    # The curvature limit is reachable by the steering actuator.
    assert v.steer_for_kappa_max < v.max_steer


@pytest.mark.parametrize(
    "kwargs, field",
    [
        ({"length": 0.0}, "vehicle.length"),
        ({"width": -1.0}, "vehicle.width"),
        ({"wheelbase": float("nan")}, "vehicle.wheelbase"),
        ({"wheelbase": 5.0}, "vehicle.wheelbase"),
        ({"min_turning_radius": 2.0}, "vehicle.min_turning_radius"),
        ({"max_steer": 2.0}, "vehicle.max_steer"),
    ],
)
def test_impossible_vehicle_rejected(kwargs, field):
    with pytest.raises(InputError, match=field):
        VehicleParams(**kwargs)


@given(
    x=st.floats(-50, 50),
    y=st.floats(-50, 50),
    yaw=st.floats(-math.pi, math.pi),
)
def test_footprint_matches_rotated_rectangle(x, y, yaw):
    v = VehicleParams()
    poly = footprint_polygon((x, y, yaw), v)
    assert poly.area == pytest.approx(v.length * v.width, rel=1e-9)
    # Centroid lies (length/2 - rear_overhang) ahead of the rear axle.
    ahead = v.length / 2 - v.rear_overhang
    assert poly.centroid.x == pytest.approx(x + ahead * math.cos(yaw), abs=1e-9)
    assert poly.centroid.y == pytest.approx(y + ahead * math.sin(yaw), abs=1e-9)


def test_footprint_batch_equals_single():
    v = VehicleParams()
    poses = np.array([[1.0, 2.0, 0.3], [-4.0, 0.5, -2.0]])
    batch = footprint_corners(poses, v)
    for p, c in zip(poses, batch, strict=True):
        np.testing.assert_allclose(footprint_corners(p, v), c)


@given(yaw=st.floats(-math.pi, math.pi), along=st.floats(0, 1), across=st.floats(0, 1))
def test_cover_discs_contain_body(yaw, along, across):
    v = VehicleParams()
    offsets, radius = cover_discs(v, 3)
    # A point of the body in local coordinates must be inside some disc.
    lx = -v.rear_overhang + along * v.length
    ly = (across - 0.5) * v.width
    assert min(math.hypot(lx - o, ly) for o in offsets) <= radius + 1e-12


@pytest.mark.parametrize("steer_deg", [5.0, 15.0, 30.0, -20.0])
def test_constant_steering_drives_a_circle(steer_deg):
    L = 2.51
    steer = math.radians(steer_deg)
    radius = L / math.tan(abs(steer))
    state = (0.0, 0.0, 0.0)
    points = []
    for _ in range(400):
        state = bicycle_step(state, 5.0, steer, 1 / 15, L)
        points.append(state[:2])
    pts = np.array(points)
    centre = np.array([0.0, math.copysign(radius, steer)])
    dist = np.hypot(*(pts - centre).T)
    np.testing.assert_allclose(dist, radius, rtol=1e-9)


def test_straight_step():
    x, y, yaw = bicycle_step((1.0, 2.0, math.pi / 2), 2.0, 0.0, 0.5, 2.51)
    assert (x, y, yaw) == pytest.approx((1.0, 3.0, math.pi / 2))
