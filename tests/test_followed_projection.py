"""Tracking errors follow the drive along a path that comes back over its own ground."""

from __future__ import annotations

import math

import numpy as np
import shapely
from gear_paths import integrate_pieces
from hypothesis import given, settings
from hypothesis import strategies as st

from rrtdrive.evaluation.tracking import distinct_samples, followed_projection, tracking_errors
from rrtdrive.geometry import project_to_polyline
from rrtdrive.types import Path


def arcs(pieces) -> np.ndarray:
    """Distinct rows ``[x, y, yaw, kappa, gear]`` of forward (length, kappa) pieces."""
    path = integrate_pieces([(1, kappa, length) for length, kappa in pieces])
    return distinct_samples(path)


# East 20 m, out round a bulb (60 deg right, 300 deg left, 60 deg right at 6 m) and
# back west along the same line: the way out and the way back overlap.
R = 6.0
BULB = arcs([(20.0, 0.0), (R * math.pi / 3, -1 / R), (R * 5 * math.pi / 3, 1 / R),
             (R * math.pi / 3, -1 / R), (20.0, 0.0)])  # fmt: skip


def test_a_drive_round_the_bulb_is_measured_on_the_leg_it_drives():
    path = Path(BULB, BULB[:, :2])
    # The car 5 cm left of the path, all the way, aligned with it: moving forward.
    left = np.column_stack([-np.sin(BULB[:, 2]), np.cos(BULB[:, 2])])
    poses = np.column_stack([BULB[:, :2] + 0.05 * left, BULB[:, 2]])
    cte, herr = tracking_errors(path, poses, speeds=np.ones(len(poses)))
    assert np.max(np.abs(herr)) < 1e-3  # the yaw interpolated along 0.1 m chords
    # Against the leg it drives: 5 cm left; shapely's distance to the whole path is no
    # more (the other leg may be nearer, which the nearest-point projection took).
    line = shapely.LineString(BULB[:, :2])
    nearest = shapely.distance(line, shapely.points(poses[:, :2]))
    assert np.allclose(cte, 0.05, atol=1e-3)  # the chords cut the arcs by 0.2 mm
    assert np.all(nearest <= np.abs(cte) + 1e-9)
    s = followed_projection(BULB[:, :2], poses[:, :2]).s
    along = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(BULB[:, :2], axis=0).T))])
    assert np.max(np.abs(s - along)) < 0.01
    # What the nearest point alone gave: the way out measured on the way back.
    assert np.max(np.abs(project_to_polyline(BULB[:, :2], poses[:, :2]).s - along)) > 40.0


@settings(max_examples=60, deadline=None)
@given(
    st.lists(st.tuples(st.floats(1.0, 15.0), st.floats(-0.15, 0.15)), min_size=1, max_size=5),
    st.floats(-0.3, 0.3),
)
def test_without_a_jump_the_answer_is_the_nearest_point(pieces, offset):
    # Turns of at most 90 deg in all never bring the path back over its own ground.
    total = sum(abs(length * kappa) for length, kappa in pieces)
    rows = arcs([(length, kappa if total <= math.pi / 2 else 0.0) for length, kappa in pieces])
    left = np.column_stack([-np.sin(rows[:, 2]), np.cos(rows[:, 2])])
    pts = rows[:, :2] + offset * left
    near = project_to_polyline(rows[:, :2], pts)
    followed = followed_projection(rows[:, :2], pts)
    assert np.array_equal(near.segment, followed.segment)
    assert np.array_equal(near.s, followed.s)
