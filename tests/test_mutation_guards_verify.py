"""Guards found by mutation testing of the independent path verifier.

Each test fails under a real-looking bug of rrtdrive.verify that the other tests let
through. References: shapely bodies built here from first principles, rows built in
closed form (straight drives, circle arcs).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely

from rrtdrive.maps import Map, Obstacle
from rrtdrive.types import Path, Pose, VehicleParams
from rrtdrive.verify import verify_path

V = VehicleParams()


def _body(x: float, y: float, yaw: float) -> shapely.Polygon:
    c, s = math.cos(yaw), math.sin(yaw)
    local = ((-V.rear_overhang, -V.width / 2), (V.front_extent, -V.width / 2),
             (V.front_extent, V.width / 2), (-V.rear_overhang, V.width / 2))
    return shapely.Polygon([(x + c * u - s * v, y + s * u + c * v) for u, v in local])


def _straight(x0=10.0, x1=30.0, y=20.0, step=0.25) -> np.ndarray:
    x = np.arange(x0, x1 + 1e-9, step)
    return np.column_stack([x, np.full_like(x, y), 0 * x, 0 * x, 1 + 0 * x])


def _check(rows: np.ndarray, obstacles=(), bounds=(0.0, 0.0, 60.0, 60.0), **kwargs):
    # check_query=False: the start or goal may be in collision (as ``rrtdrive verify`` takes).
    m = Map("open", bounds, tuple(obstacles), Pose(*rows[0, :3]), Pose(*rows[-1, :3]),
            check_query=False)
    return verify_path(m, Path(rows, np.zeros((0, 2))), **kwargs)


def test_a_body_touching_the_bounds_from_inside_collides():
    # The rear bumper exactly on xmin (0.895 - 0.895 is 0.0): the walls stand there.
    rows = _straight(x0=V.rear_overhang, x1=10.0)
    assert _body(*rows[0, :3]).bounds[0] == 0.0
    check = _check(rows)
    assert not check.collision_free and check.collides_with == "the bounds"
    assert check.first_collision == pytest.approx(tuple(rows[0, :3]))
    assert _check(rows[1:]).collision_free  # a row on, it keeps 25 cm


def test_a_post_wholly_under_the_body_collides():
    # The map's one obstacle, a 20 cm post, under the body at every pose of a 1 m drive
    # (the body contains it: their boundaries never cross): a collision, the post named.
    rows = _straight(10.0, 11.0)
    post = Obstacle((12.0, 20.0), (0.2, 0.2))
    assert all(_body(*r[:3]).contains(post.polygon()) for r in rows)
    check = _check(rows, [post])
    assert not check.collision_free and check.collides_with == "obstacle 0"


def test_the_first_collision_is_the_first_pose_that_hits():
    # Two boxes across the lane; the first tested pose whose body reaches the nearer
    # box (x = 19.5) is reported, not one inside the farther.
    rows = _straight()
    near, far = Obstacle((20.0, 20.0), (1.0, 4.0)), Obstacle((27.0, 20.0), (1.0, 4.0))
    check = _check(rows, [far, near], pose_spacing=0.1)
    x, y, yaw = check.first_collision
    assert check.collides_with == "obstacle 1" and y == 20.0 and yaw == 0.0
    assert 19.5 - V.front_extent <= x < 19.5 - V.front_extent + 0.1 + 1e-9


def test_the_poses_between_rows_are_tested():
    # Rows 0.25 m apart turning 0.4 rad (the other checks may fail: only the body check
    # is asked here): a 2 cm post that only a pose between the rows reaches collides at
    # the default pose spacing (0.1 m: poses at thirds of the step).
    a, b = np.array([10.0, 20.0, 0.0]), np.array([10.25, 20.0, 0.4])
    thirds = [a + t * (b - a) for t in (1 / 3, 2 / 3)]
    between = shapely.union_all([_body(*p) for p in thirds])
    only = between.difference(shapely.union_all([_body(*a), _body(*b)]))
    centre = shapely.get_coordinates(only.buffer(-0.015).representative_point())[0]
    post = Obstacle(tuple(centre), (0.02, 0.02))
    rows = np.array([[*a, 0.0, 1.0], [*b, 0.0, 1.0]])
    assert not _check(rows, [post]).collision_free


def test_the_reverse_drive_is_checked_too():
    # Forward 5 m, then back 5 m along the same line past the start: a box behind the
    # start that only the reverse drive reaches (the cusp is clear of it).
    ahead = _straight(20.0, 25.0)
    back = _straight(20.0 - 5.0, 25.0)[::-1].copy()
    back[:, 4] = -1.0
    rows = np.vstack([ahead, back])
    box = Obstacle((20.0 - V.rear_overhang - 3.0, 20.0), (1.0, 1.0))
    assert not any(_body(*r[:3]).intersects(box.polygon()) for r in ahead)
    check = _check(rows, [box])
    assert check.cusps == 1 and not check.collision_free
    assert check.first_collision[0] < 20.0 - 2.0


@pytest.mark.parametrize("side", ["left", "right", "bottom", "top"])
def test_least_clearance_to_each_edge_of_the_bounds(side):
    # A straight drive (body x in [9.105, 33.405], y in [19.1, 20.9]) with one side of the
    # bounds 0.37 m off the body, the others far: the least clearance is 0.37.
    gap = 0.37
    lo_x, hi_x = 10.0 - V.rear_overhang, 30.0 + V.front_extent
    bounds = {
        "left": (lo_x - gap, 0.0, 60.0, 60.0), "right": (0.0, 0.0, hi_x + gap, 60.0),
        "bottom": (0.0, 20.0 - 0.9 - gap, 60.0, 60.0), "top": (0.0, 0.0, 60.0, 20.9 + gap),
    }[side]
    check = _check(_straight(), bounds=bounds)
    assert check.collision_free and check.min_clearance_m == pytest.approx(gap, abs=1e-9)
    assert not _check(_straight(), bounds=bounds, clearance=gap + 1e-4).clearance_ok


@pytest.mark.parametrize("where", [0, -1])
def test_the_first_and_the_last_gap_count_for_the_spacing(where):
    rows = _straight()
    rows = np.delete(rows, 1 if where == 0 else len(rows) - 2, axis=0)  # one 0.5 m gap
    check = _check(rows)
    assert not check.spacing_ok and check.max_spacing_m == pytest.approx(0.5)


def test_the_travel_is_compared_with_the_yaw_halfway_along_each_step():
    # A left arc of radius 6 m (0.25 m steps turn 2.39 deg) whose rows' yaw runs 3.5 deg
    # ahead of the tangent: each chord (along the tangent halfway) is 3.5 deg off the
    # rows' mean yaw, more than the 3 deg allowed (though only 2.3 deg off a step's first).
    r, off = 6.0, math.radians(3.5)
    t = np.arange(0.0, 1.2, 0.25 / r)
    rows = np.column_stack([30 + r * np.sin(t), 20 + r * (1 - np.cos(t)), t + off,
                            np.full_like(t, 1 / r), np.ones_like(t)])  # fmt: skip
    check = _check(rows)
    assert not check.travel_ok
    assert check.travel_heading_err_deg == pytest.approx(3.5, abs=1e-6)


def test_the_last_row_half_a_millimetre_off_the_goal_fails_the_endpoints():
    # Exact ends: each coordinate within the JSON's 1e-6 m of the start and of the goal.
    rows = _straight()
    m = Map("open", (0.0, 0.0, 60.0, 60.0), (), Pose(*rows[0, :3]),
            Pose(rows[-1, 0] + 5e-4, rows[-1, 1], 0.0))  # fmt: skip
    check = verify_path(m, Path(rows, np.zeros((0, 2))))
    assert not check.endpoints_ok and check.endpoint_err_m == pytest.approx(5e-4)


@pytest.mark.parametrize("column", [0, 1])
def test_a_row_far_off_the_map_fails_at_once_in_x_or_y(column):
    # A row 1e12 m off in x or in y: the body check fails at that row without densifying
    # the jump (0.1 m poses over it would need terabytes).
    rows = _straight()
    rows[20, column] = 1e12
    check = _check(rows)
    assert not check.collision_free and check.collides_with == "the bounds"
    assert check.first_collision[column] == 1e12
