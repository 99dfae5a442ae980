"""Tight maps a user might write (issue 13): a garage, a turning bulb, kerbside parking, a bay.

Each builder returns a :class:`~rrtdrive.maps.Map`; the built-in copies ship as
files in ``rrtdrive/data/maps/`` (written by :func:`write_tight_maps`, loaded by
:mod:`rrtdrive.maps` under the same names), so ``rrtdrive plan garage`` works
like any built-in. The geometry, for the paper's car (4.30 m x 1.80 m, r_min 6 m):

- ``garage``: a 9 m aisle between two rows of 2.6 m bays (5.5 m deep, cars parked
  nose-in 0.5 m from the walls) with :data:`GARAGE_EMPTY_BAYS` free; the goal
  parks nose-in in the first of them, the start is at the aisle's west end.
- ``turning_bulb``: a 10 m street closed at its west end, opening at its east end
  into a turning bulb of radius :data:`BULB_RADIUS` (a 24-gon of walls around a
  circle); start and goal in the street's two lanes with opposite headings.
- ``kerbside``: a street with cars parked along the kerb and one gap of 1.6 car
  lengths; the goal is parallel-parked in the gap (0.3 m from the kerb).
- ``reverse_bay``: a walled bay 3.0 m wide off an aisle, the goal facing out of
  it (its rear 0.5 m from the back wall), so it is entered in reverse.
- ``dead_end``: a street :data:`DEAD_END_WIDTH` wide, walled at both ends, far too
  narrow for a U-turn; the car turns round in it. The goal faces back, where the
  full-lock moves :data:`DEAD_END_TURN` from the start and 2 m on leave the car.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable
from pathlib import Path as FsPath

from rrtdrive.maps import Map, Obstacle, save_map
from rrtdrive.types import Pose, VehicleParams

__all__ = [
    "TIGHT_MAPS",
    "GARAGE_BAY_WIDTH",
    "GARAGE_AISLE_WIDTH",
    "GARAGE_EMPTY_BAYS",
    "BULB_RADIUS",
    "STREET_WIDTH",
    "KERB_GAP_FACTOR",
    "garage_bays",
    "garage_goal",
    "garage_map",
    "turning_bulb_map",
    "kerbside_map",
    "reverse_bay_map",
    "DEAD_END_WIDTH",
    "DEAD_END_TURN",
    "dead_end_map",
    "write_tight_maps",
]

_CAR = VehicleParams()
_PARKED = (_CAR.length, _CAR.width)

# ----------------------------------------------------------------------------- garage

GARAGE_BAY_WIDTH = 2.6
GARAGE_BAY_DEPTH = 5.5
GARAGE_AISLE_WIDTH = 9.0
GARAGE_BAYS = 20
GARAGE_X0 = 4.0
#: Free bays as (side, index); side 0 is the south row (nose-in faces -y).
GARAGE_EMPTY_BAYS = ((0, 5), (0, 9), (0, 13), (1, 11))
#: Distance of a parked nose from the garage wall.
GARAGE_NOSE_GAP = 0.5


def garage_bays(aisle: float = GARAGE_AISLE_WIDTH) -> list[tuple[int, int, float, float]]:
    """Every bay as ``(side, index, x_centre, y_of_its_wall)``, the aisle ``aisle`` m wide."""
    top = GARAGE_BAY_DEPTH * 2 + aisle
    return [
        (side, i, GARAGE_X0 + GARAGE_BAY_WIDTH * (i + 0.5), 0.0 if side == 0 else top)
        for side in (0, 1)
        for i in range(GARAGE_BAYS)
    ]


def garage_goal(
    side: int, index: int, aisle: float = GARAGE_AISLE_WIDTH, tail_in: bool = False
) -> Pose:
    """The rear-axle pose of a car parked nose-in (or ``tail_in``) in bay ``(side, index)``.

    Either way the car's end at the wall is :data:`GARAGE_NOSE_GAP` from it.
    """
    for s, i, x, wall in garage_bays(aisle):
        if (s, i) == (side, index):
            inward = -1.0 if s == 0 else 1.0  # direction from the aisle to the wall
            if tail_in:
                return Pose(x, wall - inward * (GARAGE_NOSE_GAP + _CAR.rear_overhang),
                            -inward * math.pi / 2)  # fmt: skip
            return Pose(x, wall - inward * (GARAGE_NOSE_GAP + _CAR.front_extent),
                        inward * math.pi / 2)  # fmt: skip
    raise ValueError(f"no bay {(side, index)}")


def garage_map(aisle: float = GARAGE_AISLE_WIDTH) -> Map:
    """The garage: two rows of 2.6 m bays off a 9 m aisle (or ``aisle`` m), goal nose-in."""
    obstacles = []
    for side, i, x, wall in garage_bays(aisle):
        if (side, i) in GARAGE_EMPTY_BAYS:
            continue
        inward = -1.0 if side == 0 else 1.0
        y = wall - inward * (GARAGE_NOSE_GAP + _CAR.length / 2)
        obstacles.append(Obstacle((x, y), _PARKED, math.pi / 2))
    top = GARAGE_BAY_DEPTH * 2 + aisle
    width = GARAGE_X0 * 2 + GARAGE_BAY_WIDTH * GARAGE_BAYS
    return Map(
        "garage" if aisle == GARAGE_AISLE_WIDTH else f"garage_{aisle:g}m",
        (0.0, 0.0, width, top),
        tuple(obstacles),
        Pose(3.0, GARAGE_BAY_DEPTH + aisle - 1.5, 0.0),
        garage_goal(*GARAGE_EMPTY_BAYS[1], aisle=aisle),
    )


# ----------------------------------------------------------------------------- turning bulb

STREET_WIDTH = 10.0
BULB_RADIUS = 9.0
BULB_CENTRE = (48.0, 20.0)
_WALL = 1.0


def turning_bulb_map() -> Map:
    """A 10 m dead-end street into a turning bulb; go in and come back the other lane."""
    cx, cy = BULB_CENTRE
    half = STREET_WIDTH / 2
    mouth_x = cx - math.sqrt(BULB_RADIUS**2 - half**2)
    obstacles = [
        Obstacle((mouth_x / 2 + 0.5, cy - half - _WALL / 2), (mouth_x + 1.0, _WALL)),
        Obstacle((mouth_x / 2 + 0.5, cy + half + _WALL / 2), (mouth_x + 1.0, _WALL)),
    ]
    n = 24
    side = 2.0 * (BULB_RADIUS + _WALL) * math.tan(math.pi / n)  # covers the corners
    mouth = math.asin(half / BULB_RADIUS)
    for k in range(n):
        a = 2.0 * math.pi * k / n
        # Leave out the walls across the street's mouth (angles about pi).
        if abs(math.remainder(a - math.pi, 2.0 * math.pi)) < mouth + math.pi / n:
            continue
        r = BULB_RADIUS + _WALL / 2
        obstacles.append(
            Obstacle((cx + r * math.cos(a), cy + r * math.sin(a)), (_WALL, side), a)
        )
    return Map(
        "turning_bulb",
        (0.0, 0.0, 60.0, 40.0),
        tuple(obstacles),
        Pose(5.0, cy - half / 2, 0.0),
        Pose(5.0, cy + half / 2, math.pi),
    )


# ----------------------------------------------------------------------------- kerbside

KERB_GAP_FACTOR = 1.6
KERB_OFFSET = 0.3
KERB_STREET = 8.0
#: Free room behind the parked goal body (the rest of the gap is ahead of it).
KERB_REAR_ROOM = 0.3


def kerbside_map(gap_factor: float = KERB_GAP_FACTOR, kerb_offset: float = KERB_OFFSET) -> Map:
    """Cars along the kerb (y = 0) with one gap of ``gap_factor`` car lengths; park in it.

    The parked cars and the goal keep ``kerb_offset`` metres from the kerb.
    """
    gap = gap_factor * _CAR.length
    pitch = _CAR.length + 1.0
    y = kerb_offset + _CAR.width / 2
    gap_start = 30.0  # front bumper of the car behind the gap
    obstacles = []
    x = gap_start - _CAR.length / 2
    while x - _CAR.length / 2 > 0.5:
        obstacles.append(Obstacle((x, y), _PARKED))
        x -= pitch
    x = gap_start + gap + _CAR.length / 2
    while x + _CAR.length / 2 < 60.0 - 0.5:
        obstacles.append(Obstacle((x, y), _PARKED))
        x += pitch
    goal_x = gap_start + KERB_REAR_ROOM + _CAR.rear_overhang
    return Map(
        "kerbside",
        (0.0, 0.0, 60.0, KERB_STREET),
        tuple(sorted(obstacles, key=lambda o: o.center[0])),
        Pose(3.0, 5.0, 0.0),
        Pose(goal_x, y, 0.0),
    )


# ----------------------------------------------------------------------------- reverse bay

REVERSE_BAY_WIDTH = 3.0
REVERSE_BAY_DEPTH = 6.0
REVERSE_AISLE = 10.0


def reverse_bay_map() -> Map:
    """A walled bay 3 m wide off an aisle; the goal faces out of it, rear to the back wall."""
    bx = 25.0
    half = REVERSE_BAY_WIDTH / 2
    top = REVERSE_BAY_DEPTH + REVERSE_AISLE
    obstacles = (
        # The bay's side walls and the wall blocks either side of it along the aisle.
        Obstacle(((bx - half) / 2, REVERSE_BAY_DEPTH / 2), (bx - half, REVERSE_BAY_DEPTH)),
        Obstacle(
            ((bx + half + 50.0) / 2, REVERSE_BAY_DEPTH / 2),
            (50.0 - bx - half, REVERSE_BAY_DEPTH),
        ),
    )
    return Map(
        "reverse_bay",
        (0.0, 0.0, 50.0, top),
        obstacles,
        Pose(5.0, REVERSE_BAY_DEPTH + 6.0, 0.0),
        Pose(bx, 0.5 + _CAR.rear_overhang, math.pi / 2),
    )


# ----------------------------------------------------------------------------- dead end

DEAD_END_WIDTH = 7.5
DEAD_END_LENGTH = 30.0
#: A hand-made turn round: full-lock moves ``(gear, degrees)``, left lock forward and
#: right lock in reverse (the heading turns left in both), 180 degrees in all; each
#: move as long as the body keeps 0.2 m from the walls, to a tenth of a degree.
DEAD_END_TURN = ((1, 50.8), (-1, 30.2), (1, 24.4), (-1, 25.0), (1, 49.6))


def full_lock_move(pose: Pose, gear: int, degrees: float) -> Pose:
    """Where a full-lock move of ``degrees`` leaves the car: left lock forward, right in reverse."""
    kappa = gear / _CAR.min_turning_radius
    yaw = pose.yaw + math.radians(degrees)  # the heading turns left in both gears
    return Pose(
        pose.x + (math.sin(yaw) - math.sin(pose.yaw)) / kappa,
        pose.y - (math.cos(yaw) - math.cos(pose.yaw)) / kappa,
        yaw,
    )


def dead_end_map() -> Map:
    """A 7.5 m street walled at both ends: turn round in it (a U-turn needs about 14 m)."""
    w, length = DEAD_END_WIDTH, DEAD_END_LENGTH
    obstacles = (
        Obstacle((length / 2, -_WALL / 2), (length + 2 * _WALL, _WALL)),
        Obstacle((length / 2, w + _WALL / 2), (length + 2 * _WALL, _WALL)),
        Obstacle((-_WALL / 2, w / 2), (_WALL, w)),
        Obstacle((length + _WALL / 2, w / 2), (_WALL, w)),
    )
    start = Pose(8.0, w / 4, 0.0)
    pose = start
    for gear, degrees in DEAD_END_TURN:
        pose = full_lock_move(pose, gear, degrees)
    goal = Pose(pose.x - 2.0, pose.y, math.pi)
    return Map("dead_end", (-_WALL, -_WALL, length + _WALL, w + _WALL), obstacles, start, goal)


#: The tight maps by name, as shipped in ``rrtdrive/data/maps/``.
TIGHT_MAPS: dict[str, Callable[[], Map]] = {
    "garage": garage_map,
    "turning_bulb": turning_bulb_map,
    "kerbside": kerbside_map,
    "reverse_bay": reverse_bay_map,
    "dead_end": dead_end_map,
}


def write_tight_maps(folder: str | os.PathLike[str]) -> list[FsPath]:
    """Write every tight map to ``folder/NAME.json``; return the paths.

    Regenerates the shipped files: ``python -c "from rrtdrive.tight_maps import
    write_tight_maps; write_tight_maps('src/rrtdrive/data/maps')"``.
    """
    out = FsPath(folder)
    out.mkdir(parents=True, exist_ok=True)
    paths = []
    for name, build in TIGHT_MAPS.items():
        path = out / f"{name}.json"
        save_map(build(), path)
        paths.append(path)
    return paths
