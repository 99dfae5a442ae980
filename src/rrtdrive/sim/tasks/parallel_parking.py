"""The parallel-parking task: reverse into a seeded gap between cars parked along the kerb."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np
from highway_env.road.lane import LineType, StraightLane
from highway_env.road.road import Road, RoadNetwork

from rrtdrive.maps import Map, Obstacle
from rrtdrive.sim.scenes import populate_road
from rrtdrive.sim.tasks.base import TaskKind
from rrtdrive.sim.tasks.path_task import PathTask
from rrtdrive.types import InputError, Pose, VehicleParams

__all__ = [
    "ParallelParkingTask",
    "GAP_FACTORS",
    "KERB_STREET_WIDTH",
    "KERB_OFFSET",
    "parallel_parking_map",
]

#: The range of the gap's length, in car lengths (seeded uniformly).
GAP_FACTORS = (1.5, 2.0)
#: Width of the street between the kerb (y = 0) and the far wall, metres.
KERB_STREET_WIDTH = 8.0
#: Distance of the parked cars' (and the goal's) kerb side from the kerb, metres.
KERB_OFFSET = 0.3
#: Length of the street, metres.
STREET_LENGTH = 60.0
#: Room between the goal body's rear and the car behind the gap, metres (the car is
#: reversed in to the back of the gap, as in the ``kerbside`` map).
REAR_ROOM = 0.3
#: Room between two parked cars outside the gap, metres.
PARKED_SPACING = 1.0


def parallel_parking_map(
    gap_factor: float, gap_start: float, vehicle: VehicleParams | None = None
) -> Map:
    """Cars along the kerb (y = 0) with one gap of ``gap_factor`` car lengths; park in it.

    Parameters
    ----------
    gap_factor : float
        The gap between the two cars either side of it, in car lengths.
    gap_start : float
        x of the front bumper of the car behind the gap, metres.
    vehicle : VehicleParams, optional
        The car (it sizes the parked cars too).

    Returns
    -------
    Map
        Start in the lane at the street's west end facing +x; goal in the gap,
        ``REAR_ROOM`` ahead of the car behind it and ``KERB_OFFSET`` from the kerb,
        facing +x.

    Examples
    --------
    >>> m = parallel_parking_map(1.5, 28.0)
    >>> round(m.goal.x, 3), round(m.goal.y, 2)
    (29.195, 1.2)
    """
    car = vehicle or VehicleParams()
    if not (math.isfinite(gap_factor) and gap_factor > 1.0):
        raise InputError(f"gap_factor: need a number > 1 (car lengths), got {gap_factor!r}")
    gap = gap_factor * car.length
    y = KERB_OFFSET + car.width / 2
    size = (car.length, car.width)
    pitch = car.length + PARKED_SPACING
    obstacles = []
    x = gap_start - car.length / 2
    while x - car.length / 2 > 0.5:
        obstacles.append(Obstacle((x, y), size))
        x -= pitch
    x = gap_start + gap + car.length / 2
    while x + car.length / 2 < STREET_LENGTH - 0.5:
        obstacles.append(Obstacle((x, y), size))
        x += pitch
    goal = Pose(gap_start + REAR_ROOM + car.rear_overhang, y, 0.0)
    return Map(
        "parallel_parking",
        (0.0, 0.0, STREET_LENGTH, KERB_STREET_WIDTH),
        tuple(sorted(obstacles, key=lambda o: o.center[0])),
        Pose(3.0, KERB_STREET_WIDTH - 3.0, 0.0),
        goal,
        car,
    )


@dataclass(frozen=True, kw_only=True)
class ParallelParkingTask(PathTask):
    """Parallel-park by the kerb in a seeded gap of 1.5-2.0 car lengths (planned with reversing).

    The street is 8 m wide and 60 m long, closed by walls; the cars parked along
    the kerb are stopped highway-env vehicles of exactly their size. The ego starts
    in the lane at the west end (seeded jitter) and must stop in the gap, 0.3 m
    ahead of the car behind it and 0.3 m from the kerb, facing +x.

    Parameters
    ----------
    map, seed, v_max, max_time_s, reverse
        See :class:`~rrtdrive.sim.tasks.Task` (``reverse`` is True).
    gap_factor : float
        The gap's length in car lengths.
    """

    kind: ClassVar[TaskKind] = TaskKind.PARALLEL_PARKING
    OPTIONS: ClassVar[tuple[str, ...]] = ()

    gap_factor: float

    def __post_init__(self) -> None:
        super().__post_init__()
        if not (math.isfinite(self.gap_factor) and self.gap_factor > 1.0):
            raise InputError(f"gap_factor: need a number > 1, got {self.gap_factor!r}")

    @classmethod
    def create(
        cls,
        seed: int,
        rng: np.random.Generator,
        offset: tuple[float, float, float],
        vehicle: VehicleParams,
    ) -> ParallelParkingTask:
        """The task for ``seed``: ``rng`` draws the gap's length and place, ``offset`` the start."""
        factor = float(rng.uniform(*GAP_FACTORS))
        gap_start = float(rng.uniform(24.0, 32.0))
        base = parallel_parking_map(factor, gap_start, vehicle)
        dx, dy, dyaw = offset
        s = base.start
        m = base.with_query(start=Pose(s.x + dx, s.y + dy, s.yaw + dyaw))
        return cls(map=m, seed=int(seed), gap_factor=factor, v_max=2.0, max_time_s=120.0,
                   reverse=True)

    def describe(self) -> dict[str, Any]:
        """The gap's length in car lengths and metres."""
        return {
            "gap_factor": round(self.gap_factor, 4),
            "gap_m": round(self.gap_factor * self.vehicle.length, 3),
        }

    def build_road(self, np_random: np.random.Generator, history: bool) -> Road:
        """The street as one drawn lane (kerb and far side solid); parked cars; walls.

        Parameters
        ----------
        np_random, history
            As :meth:`Task.build_road`.

        Returns
        -------
        Road
        """
        xmin, ymin, xmax, ymax = self.map.bounds
        net = RoadNetwork()
        solid = (LineType.CONTINUOUS_LINE, LineType.CONTINUOUS_LINE)
        mid = (ymin + ymax) / 2
        net.add_lane("a", "b", StraightLane([xmin, mid], [xmax, mid], ymax - ymin, solid))
        parked = tuple(range(len(self.map.obstacles)))
        return populate_road(
            net, self.map, np_random, history, vehicle_obstacles=parked, walls=True
        )
