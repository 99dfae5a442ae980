"""The parking task: from the lot's entrance nose-in into a seeded free spot."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from highway_env.road.road import Road

from rrtdrive.maps import PARKING_EMPTY_SPOTS, parking_goal_pose, parking_lot_map
from rrtdrive.sim.scenes import parking_network, populate_road
from rrtdrive.sim.tasks.base import PathTask, TaskKind
from rrtdrive.types import InputError, Pose, VehicleParams

__all__ = ["ParkingTask", "parse_spot"]


def parse_spot(spot: object) -> tuple[int, int, int]:
    """A spot option as ``(row, side, index)``; one of the lot's empty spots.

    Raises
    ------
    InputError
        Naming ``spot`` when it is not three integers or not an empty spot.
    """
    spots = sorted(PARKING_EMPTY_SPOTS)
    try:
        values = tuple(spot)  # type: ignore[call-overload]
    except TypeError:
        values = ()
    if len(values) != 3 or any(
        isinstance(v, bool) or not isinstance(v, (int, np.integer)) for v in values
    ):
        raise InputError(
            f"spot: expected tuple (row, side, index) of three integers, got {spot!r}; "
            f"choose from {spots}"
        )
    if values not in PARKING_EMPTY_SPOTS:
        raise InputError(f"spot: {spot!r} is not an empty spot; choose from {spots}")
    return tuple(int(v) for v in values)  # type: ignore[return-value]


@dataclass(frozen=True, kw_only=True)
class ParkingTask(PathTask):
    """Park in the ``parking_lot`` map: every parked car and block is a solid obstacle.

    The scene's walls close the bounds and each spot is drawn as a lane. The ego
    starts at the entrance with a seeded jitter and must stop nose-in in the spot.

    Parameters
    ----------
    map, seed, v_max, max_time_s
        See :class:`~rrtdrive.sim.tasks.Task`.
    spot : tuple of int
        The ``(row, side, index)`` of the goal spot.
    """

    kind: ClassVar[TaskKind] = TaskKind.PARKING
    #: Options of :func:`~rrtdrive.sim.tasks.make_scenario` besides ``jitter`` and ``vehicle``.
    OPTIONS: ClassVar[tuple[str, ...]] = ("spot",)

    spot: tuple[int, int, int]

    def __post_init__(self) -> None:
        super().__post_init__()
        parse_spot(self.spot)

    @classmethod
    def create(
        cls,
        seed: int,
        rng: np.random.Generator,
        offset: tuple[float, float, float],
        vehicle: VehicleParams,
        spot: object = None,
    ) -> ParkingTask:
        """The task for ``seed``: ``offset`` is the drawn start jitter, ``rng`` draws the spot."""
        base = dataclasses.replace(parking_lot_map(), vehicle=vehicle)
        spots = sorted(PARKING_EMPTY_SPOTS)
        if spot is None:
            chosen = spots[int(rng.integers(len(spots)))]
        else:
            chosen = parse_spot(spot)
        dx, dy, dyaw = offset
        start = Pose(base.start.x + dx, base.start.y + dy, base.start.yaw + dyaw)
        goal = parking_goal_pose(*chosen, vehicle=vehicle)
        m = base.with_query(start=start, goal=goal)
        return cls(map=m, seed=int(seed), spot=chosen, v_max=3.0, max_time_s=120.0)

    def build_road(self, np_random: np.random.Generator, history: bool) -> Road:
        """One lane per spot; the lot's obstacles and the walls."""
        return populate_road(parking_network(), self.map, np_random, history, walls=True)
