"""The built-in parking lot's layout: its spots, parked cars, kerbs and blocks.

Shared by the ``parking_lot`` map (:func:`rrtdrive.maps.parking_lot_map`) and the
highway-env scene of the ``parking`` scenario, which parks the same cars.
"""

from __future__ import annotations

import math

from rrtdrive.obstacles import Obstacle
from rrtdrive.types import InputError, Pose, VehicleParams

__all__ = [
    "PARKING_SPOT_WIDTH",
    "PARKING_SPOT_DEPTH",
    "PARKING_ROW_CENTRES",
    "PARKING_ROW_X",
    "PARKING_EMPTY_SPOTS",
    "PARKING_BLOCK_SPOTS",
    "PARKING_SETBACK",
    "parking_spots",
    "parking_goal_pose",
    "parking_lot_obstacles",
]

#: Parking-lot geometry, shared with the highway-env scene builder.
PARKING_SPOT_WIDTH = 3.0
PARKING_SPOT_DEPTH = 5.5
PARKING_ROW_CENTRES = (20.0, 45.0, 70.0)
PARKING_ROW_X = (14.0, 86.0)
#: Empty spots per (row index, side, spot index); side 0 faces -y, side 1 faces +y.
PARKING_EMPTY_SPOTS = frozenset(
    {(0, 0, 3), (0, 1, 17), (1, 0, 9), (1, 1, 4), (1, 1, 20), (2, 0, 14), (2, 1, 19), (2, 1, 6)}
)
#: Spots replaced by solid blocks (islands with lamp posts, trolley bays).
PARKING_BLOCK_SPOTS = frozenset({(0, 0, 11), (0, 0, 12), (1, 1, 11), (1, 1, 12), (2, 0, 2)})


def parking_spots() -> list[tuple[int, int, int, float, float]]:
    """Every spot of the lot as ``(row, side, index, x_centre, y_centre)``."""
    spots = []
    count = int(round((PARKING_ROW_X[1] - PARKING_ROW_X[0]) / PARKING_SPOT_WIDTH))
    for r, yc in enumerate(PARKING_ROW_CENTRES):
        for side in (0, 1):
            y = yc - PARKING_SPOT_DEPTH / 2 if side == 0 else yc + PARKING_SPOT_DEPTH / 2
            for i in range(count):
                x = PARKING_ROW_X[0] + PARKING_SPOT_WIDTH * (i + 0.5)
                spots.append((r, side, i, x, y))
    return spots


#: How far a parked car's body centre sits from its spot's centre towards the aisle.
PARKING_SETBACK = 0.5


def parking_goal_pose(
    row: int, side: int, index: int, vehicle: VehicleParams | None = None
) -> Pose:
    """The rear-axle pose of a car parked nose-in in the given spot.

    The body is centred across the spot and set back :data:`PARKING_SETBACK`
    towards the aisle, so its nose stays 0.9 m clear of the kerb.
    """
    vehicle = vehicle or VehicleParams()
    for r, s, i, x, y in parking_spots():
        if (r, s, i) == (row, side, index):
            # Nose-in: a side-1 spot (upper half of a row) opens upward, so the car faces -y.
            yaw = -math.pi / 2 if s == 1 else math.pi / 2
            back = vehicle.length / 2 - vehicle.rear_overhang + PARKING_SETBACK
            return Pose(x - back * math.cos(yaw), y - back * math.sin(yaw), yaw)
    raise InputError(f"spot: no spot {(row, side, index)}")


def parking_lot_obstacles() -> tuple[Obstacle, ...]:
    """The lot's obstacles: parked cars, blocks, the kerbs between double rows, buildings.

    Returns
    -------
    tuple of Obstacle
        In a fixed order (the built-in map's).
    """
    obstacles: list[Obstacle] = []
    for r, side, i, x, y in parking_spots():
        key = (r, side, i)
        if key in PARKING_BLOCK_SPOTS:
            obstacles.append(Obstacle((x, y), (PARKING_SPOT_WIDTH, PARKING_SPOT_DEPTH)))
        elif key not in PARKING_EMPTY_SPOTS:
            obstacles.append(Obstacle((x, y), (4.3, 1.8), math.pi / 2))
    # A kerb between the two halves of each double row keeps cars from driving through it.
    for yc in PARKING_ROW_CENTRES:
        obstacles.append(
            Obstacle(
                ((PARKING_ROW_X[0] + PARKING_ROW_X[1]) / 2, yc),
                (PARKING_ROW_X[1] - PARKING_ROW_X[0], 0.4),
            )
        )
    # Solid blocks: a kiosk building, a ticket booth by the entrance, a planter on the right.
    obstacles += [
        Obstacle((35.0, 90.0), (24.0, 10.0)),
        Obstacle((6.0, 30.0), (6.0, 6.0)),
        Obstacle((93.0, 57.0), (6.0, 10.0)),
    ]
    return tuple(obstacles)
