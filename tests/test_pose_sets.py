"""The seeded random pose sets of the coverage benchmarks (``rrtdrive.pose_sets``)."""

from __future__ import annotations

import math

import pytest
import shapely

from rrtdrive.maps import Map, Obstacle, builtin_map
from rrtdrive.pose_sets import random_free_poses
from rrtdrive.types import InputError, Pose
from rrtdrive.vehicle import footprint_polygon


@pytest.mark.parametrize("field", ["start", "goal"])
def test_every_pose_is_free_and_inside_the_bounds(field: str) -> None:
    """Each drawn body is clear of every obstacle and inside the bounds (shapely)."""
    m = builtin_map("parking_lot")
    poses = random_free_poses(m, 40, seed=3, field=field)
    assert len(poses) == 40
    region = shapely.box(*m.bounds)
    walls = m.obstacle_union()
    for p in poses:
        body = footprint_polygon(p.as_tuple(), m.vehicle)
        assert region.contains(body)
        assert not body.intersects(walls)
        assert -math.pi <= p.yaw <= math.pi


def test_same_seed_same_poses_other_seed_other_poses() -> None:
    """A seed fixes the set; a name and the map object give the same set; seeds differ."""
    by_name = random_free_poses("parking_lot", 12, seed=5)
    assert by_name == random_free_poses(builtin_map("parking_lot"), 12, seed=5)
    assert by_name[:5] == random_free_poses("parking_lot", 5, seed=5)
    assert by_name != random_free_poses("parking_lot", 12, seed=6)


def test_positions_spread_over_the_free_room() -> None:
    """Draws are uniform over the bounds: both halves of the open lot get poses."""
    m = builtin_map("parking_lot")
    xs = [p.x for p in random_free_poses(m, 60, seed=2)]
    mid = (m.bounds[0] + m.bounds[2]) / 2
    assert sum(x < mid for x in xs) >= 15 and sum(x >= mid for x in xs) >= 15


def test_no_room_is_an_error_not_a_hang() -> None:
    """A map whose only free room is a pocket round its start gives up with an error."""
    free = (94.0, 98.5, 106.0, 101.5)  # a 12 x 3 m pocket in a 200 x 200 m map
    walls = (
        Obstacle((100.0, free[1] / 2), (200.0, free[1])),
        Obstacle((100.0, (free[3] + 200.0) / 2), (200.0, 200.0 - free[3])),
        Obstacle((free[0] / 2, 100.0), (free[0], 200.0)),
        Obstacle(((free[2] + 200.0) / 2, 100.0), (200.0 - free[2], 200.0)),
    )
    start, goal = Pose(97.0, 100.0, 0.0), Pose(98.0, 100.0, 0.0)
    pocket = Map("pocket", (0.0, 0.0, 200.0, 200.0), walls, start, goal)
    with pytest.raises(InputError, match=r"^map: .*only [01] of 2 free goal poses on 'pocket'"):
        random_free_poses(pocket, 2, seed=0)


def test_bad_arguments_name_the_field() -> None:
    """An unknown field or a negative count is refused by name; zero poses is an empty set."""
    with pytest.raises(InputError, match="^field:"):
        random_free_poses("parking_lot", 2, seed=0, field="middle")
    with pytest.raises(InputError, match="^count:"):
        random_free_poses("parking_lot", -1, seed=0)
    with pytest.raises(InputError, match="^count:"):
        random_free_poses("parking_lot", 2.5, seed=0)
    assert random_free_poses("parking_lot", 0, seed=0) == []
