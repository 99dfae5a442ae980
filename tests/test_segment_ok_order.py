"""The ramped segments' re-check tests the start first: the same answer as all poses at once."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from rrtdrive.geometry import densify
from rrtdrive.planning.hybrid import path as hybrid_path
from rrtdrive.planning.hybrid.primitives import arc_poses


def _reference(rows, checker, clearance, kappa_max, spacing) -> bool:
    """Every densified pose in one call (the rows themselves when no interval is cut)."""
    if len(rows) < 2 or float(np.abs(rows[:, 3]).max()) > kappa_max * (1.0 + 1e-9):
        return False
    poses = np.asarray(rows, dtype=float)[:, :3]
    dense = densify(poses, spacing, angle_column=2)
    if dense.pieces.max() > 1:
        poses = dense.points
    return bool(checker.poses_free(poses, clearance).all())


def _rows(x: float, y: float, yaw: float, turns: list[tuple[float, float]], step: float):
    out = [np.array([[x, y, yaw, 0.0]])]
    for kappa, length in turns:
        count = max(1, int(np.ceil(length / step)))
        arc = arc_poses(*out[-1][-1, :3], kappa, 1, np.linspace(0.0, length, count + 1))[1:]
        out.append(np.column_stack([arc, np.full(len(arc), kappa)]))
    return np.vstack(out)


@settings(max_examples=60, deadline=None)
@given(
    st.floats(2.0, 58.0),
    st.floats(2.0, 38.0),
    st.floats(-3.2, 3.2),
    st.lists(st.tuples(st.floats(-0.18, 0.18), st.floats(0.3, 12.0)), min_size=1, max_size=5),
    st.sampled_from([0.05, 0.1, 0.2, 0.3]),
    st.sampled_from([0.0, 0.2]),
)
def test_start_first_is_the_same_answer(parking_checker, x, y, yaw, turns, step, clearance):
    rows = _rows(x, y, yaw, turns, step)
    for spacing in (0.1, 0.5):
        got = hybrid_path._segment_ok(rows, parking_checker, clearance, 0.2, spacing)
        assert got == _reference(rows, parking_checker, clearance, 0.2, spacing)
