"""The parking task: from the lot's entrance into a seeded free spot, nose-in or reversing in."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any, ClassVar, cast

import numpy as np
from highway_env.road.road import Road

from rrtdrive.maps import parking_lot_map
from rrtdrive.parking_layout import PARKING_EMPTY_SPOTS, parking_goal_pose
from rrtdrive.sim.scenes import parking_network, populate_road
from rrtdrive.sim.tasks.base import TaskKind
from rrtdrive.sim.tasks.path_task import PathTask
from rrtdrive.types import InputError, Pose, VehicleParams

__all__ = ["ParkingTask", "parse_spot", "reverse_in_goal"]


def reverse_in_goal(nose_in: Pose, vehicle: VehicleParams) -> Pose:
    """The rear-axle pose of a car in the same place as ``nose_in``, facing out of the bay.

    The body covers the same rectangle; the heading is turned by pi, so the rear
    axle moves forward by twice its distance from the body centre.

    Examples
    --------
    >>> import math
    >>> g = reverse_in_goal(Pose(0.0, 0.0, math.pi / 2), VehicleParams())
    >>> round(g.x, 6), round(g.y, 3), round(g.yaw, 4)
    (0.0, 2.51, -1.5708)
    """
    d = 2.0 * (vehicle.length / 2.0 - vehicle.rear_overhang)
    yaw = math.remainder(nose_in.yaw + math.pi, 2.0 * math.pi)
    return Pose(
        nose_in.x + d * math.cos(nose_in.yaw), nose_in.y + d * math.sin(nose_in.yaw), yaw
    )


def parse_spot(spot: object) -> tuple[int, int, int]:
    """A spot option as ``(row, side, index)``; one of the lot's empty spots.

    Raises
    ------
    InputError
        Naming ``spot`` when it is not three integers or not an empty spot.
    """
    spots = sorted(PARKING_EMPTY_SPOTS)
    try:
        values: tuple[Any, ...] = tuple(cast(Iterable[Any], spot))
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
    starts at the entrance with a seeded jitter and must stop nose-in in the spot,
    or with ``reverse_in`` facing out of it (the spot is entered backwards, as most
    drivers do in perpendicular bays: the path is planned with gear changes).

    Parameters
    ----------
    map, seed, v_max, max_time_s
        See :class:`~rrtdrive.sim.tasks.Task`.
    spot : tuple of int
        The ``(row, side, index)`` of the goal spot.
    reverse_in : bool
        The goal faces out of the spot (``rrtdrive simulate parking --reverse-in``);
        ``reverse`` is then True.
    """

    kind: ClassVar[TaskKind] = TaskKind.PARKING
    #: Options of :func:`~rrtdrive.sim.tasks.make_scenario` besides ``jitter`` and ``vehicle``.
    OPTIONS: ClassVar[tuple[str, ...]] = ("spot", "reverse_in")

    spot: tuple[int, int, int]
    reverse_in: bool = False

    def __post_init__(self) -> None:
        super().__post_init__()
        parse_spot(self.spot)
        if not isinstance(self.reverse_in, (bool, np.bool_)):
            raise InputError(f"reverse_in: expected True or False, got {self.reverse_in!r}")
        if self.reverse_in and not self.reverse:
            raise InputError("reverse_in: a reverse-in bay needs reverse=True (gear changes)")

    def describe(self) -> dict[str, object]:
        """The goal spot and whether it is entered backwards."""
        return {"spot": list(self.spot), "reverse_in": bool(self.reverse_in)}

    @classmethod
    def create(
        cls,
        seed: int,
        rng: np.random.Generator,
        offset: tuple[float, float, float],
        vehicle: VehicleParams,
        spot: object = None,
        reverse_in: object = None,
    ) -> ParkingTask:
        """The task for ``seed``: ``offset`` is the drawn start jitter, ``rng`` draws the spot."""
        if reverse_in is not None and not isinstance(reverse_in, (bool, np.bool_)):
            raise InputError(f"reverse_in: expected True or False, got {reverse_in!r}")
        backwards = bool(reverse_in)
        base = dataclasses.replace(parking_lot_map(), vehicle=vehicle)
        spots = sorted(PARKING_EMPTY_SPOTS)
        if spot is None:
            chosen = spots[int(rng.integers(len(spots)))]
        else:
            chosen = parse_spot(spot)
        dx, dy, dyaw = offset
        start = Pose(base.start.x + dx, base.start.y + dy, base.start.yaw + dyaw)
        goal = parking_goal_pose(*chosen, vehicle=vehicle)
        if backwards:
            goal = reverse_in_goal(goal, vehicle)
        m = base.with_query(start=start, goal=goal)
        return cls(
            map=m, seed=int(seed), spot=chosen, v_max=3.0, max_time_s=120.0,
            reverse=backwards, reverse_in=backwards,
        )

    def build_road(self, np_random: np.random.Generator, history: bool) -> Road:
        """One lane per spot; the lot's obstacles and the walls.

        Parameters
        ----------
        np_random, history
            As :meth:`Task.build_road`.

        Returns
        -------
        Road
        """
        return populate_road(parking_network(), self.map, np_random, history, walls=True)
