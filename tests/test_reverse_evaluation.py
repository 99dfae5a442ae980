"""Evaluators across cusps: errors against the segment being driven, progress, gear counts."""

from __future__ import annotations

import math

import numpy as np
from gear_paths import integrate_pieces
from hypothesis import given, settings
from hypothesis import strategies as st

from rrtdrive.evaluation.tracking import (
    along_path,
    driven_segments,
    gear_changes,
    gear_runs,
    tracking_errors,
)
from rrtdrive.geometry import project_to_polyline, wrap_angle
from rrtdrive.types import Path

L = 2.51


#: Forward 10 m, then back over its own ground on a gentle arc: near the cusp the two
#: legs are centimetres apart with different headings.
SHUTTLE = integrate_pieces([(1, 0.0, 10.0), (-1, 1.0 / 12.0, 10.0)])


def _driven(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """Poses exactly on the path and signed speeds that drive each segment in its gear."""
    rows = path.samples
    speeds = rows[:, 4] * 1.0
    speeds[path.cusps - 1] = 0.0  # standing at each cusp
    return rows[:, :3], speeds


def test_errors_are_measured_against_the_segment_driven():
    poses, speeds = _driven(SHUTTLE)
    cte, herr = tracking_errors(SHUTTLE, poses, speeds=speeds)
    assert np.max(np.abs(cte)) < 1e-9 and np.max(np.abs(herr)) < 1e-9
    # 5 cm towards the first leg while reversing: still 5 cm off the leg driven, though
    # near the cusp the first leg is nearer (and points elsewhere).
    back = SHUTTLE.samples[:, 4] < 0
    off = poses.copy()
    yaw = poses[back, 2]
    off[back, 0] += 0.05 * np.sin(yaw)  # to the right of the nose
    off[back, 1] -= 0.05 * np.cos(yaw)
    cte, herr = tracking_errors(SHUTTLE, off, speeds=speeds)
    assert np.allclose(cte[back], 0.05, atol=1e-4)  # left of the direction of travel
    assert np.max(np.abs(herr)) < 1e-9
    xy = SHUTTLE.samples[:, :2]
    keep = np.concatenate([[True], np.hypot(*np.diff(xy, axis=0).T) > 1e-9])
    whole = SHUTTLE.samples[keep]
    proj = project_to_polyline(whole[:, :2], off[:, :2])
    yaw = np.unwrap(whole[:, 2])
    j, f = proj.segment, proj.fraction
    wrong = np.abs(wrap_angle(off[:, 2] - (yaw[j] + f * (yaw[j + 1] - yaw[j]))))
    assert wrong.max() > 0.05
    # The speeds may also come as the fourth column of the poses.
    cte4, _ = tracking_errors(SHUTTLE, np.column_stack([off, speeds]))
    assert np.array_equal(cte4, cte)


def test_cte_sign_is_left_of_the_direction_of_travel():
    back = integrate_pieces([(-1, 0.0, 10.0)])  # reversing along -x, the nose along +x
    cte, herr = tracking_errors(back, np.array([[-5.0, 0.3, 0.1]]), speeds=np.array([-1.0]))
    # +y is to the right of travel (-x): negative; the heading error is nose minus nose.
    assert math.isclose(cte[0], -0.3, abs_tol=1e-12) and math.isclose(herr[0], 0.1)


def test_progress_counts_every_segment():
    poses, speeds = _driven(SHUTTLE)
    s = along_path(SHUTTLE, poses, speeds)
    assert math.isclose(s[-1] - s[0], SHUTTLE.length, rel_tol=1e-9)
    assert np.all(np.diff(s) >= -1e-9)


def test_gear_runs_and_the_segment_driven():
    runs = gear_runs(SHUTTLE)
    assert [r.gear for r in runs] == [1, -1]
    assert math.isclose(runs[1].s0, 10.0, rel_tol=1e-9)
    v = np.array([0.0, 1.0, 1.0, 0.0, 0.0, -1.0, 0.0, 1.0])
    assert driven_segments(runs, v).tolist() == [0, 0, 0, 0, 0, 1, 1, 1]
    assert gear_changes(v) == 2


@settings(max_examples=30, deadline=None)
@given(st.floats(-0.5, 0.5), st.floats(-0.3, 0.3), st.floats(0.5, 9.5))
def test_forward_paths_measure_as_before(dy, dyaw, x):
    fwd = integrate_pieces([(1, 1.0 / 20.0, 10.0)])
    pose = np.array([[x, dy + x * x / 40.0, dyaw + x / 20.0]])
    a = tracking_errors(fwd, pose)
    b = tracking_errors(fwd, pose, speeds=np.array([1.0]))
    assert np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1])
