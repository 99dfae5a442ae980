"""The u-turn task: turn round in a dead-end street too narrow for a forward U-turn."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np
from highway_env.road.lane import LineType, StraightLane
from highway_env.road.road import Road, RoadNetwork

from rrtdrive.maps import Map
from rrtdrive.sim.scenes import populate_road
from rrtdrive.sim.tasks.base import TaskKind
from rrtdrive.sim.tasks.path_task import PathTask
from rrtdrive.types import InputError, Pose, VehicleParams
from rrtdrive.vehicle import footprint_corners

__all__ = ["UTurnTask", "U_TURN_WIDTHS", "forward_u_turn_width", "u_turn_map"]

#: The range of the street's width, metres (seeded uniformly; all below a forward U-turn's).
U_TURN_WIDTHS = (9.0, 12.0)
#: Length of the dead-end street, metres.
U_TURN_LENGTH = 40.0


def forward_u_turn_width(vehicle: VehicleParams | None = None) -> float:
    """The narrowest street in which ``vehicle`` turns round forward on full lock.

    A half circle of the rear axle at ``min_turning_radius`` ``r`` about a fixed
    centre: the outer front corner sweeps ``sqrt((r + w/2)^2 + f^2)`` beyond the
    centre on the far side (``f`` the front extent from the rear axle), the outer
    rear corner ``sqrt((r + w/2)^2 + o^2)`` on the near side (``o`` the rear
    overhang). The street must hold both: 14.65 m for the paper's car.

    Examples
    --------
    >>> round(forward_u_turn_width(), 2)
    14.65
    """
    v = vehicle or VehicleParams()
    r, half = v.min_turning_radius, v.width / 2
    return math.hypot(r + half, v.front_extent) + math.hypot(r + half, v.rear_overhang)


def u_turn_map(width: float, vehicle: VehicleParams | None = None) -> Map:
    """A dead-end street ``width`` metres wide, closed at x = 0; start facing the end, goal back.

    Examples
    --------
    >>> m = u_turn_map(10.0)
    >>> m.start, m.goal
    (Pose(x=30.0, y=7.5, yaw=3.141592653589793), Pose(x=30.0, y=2.5, yaw=0.0))
    """
    car = vehicle or VehicleParams()
    if not (math.isfinite(width) and width > 2.0 * car.width):
        raise InputError(f"width: need a street wider than two cars, got {width!r}")
    return Map(
        "u_turn",
        (0.0, 0.0, U_TURN_LENGTH, float(width)),
        (),
        Pose(30.0, 0.75 * width, math.pi),
        Pose(30.0, 0.25 * width, 0.0),
        car,
    )


@dataclass(frozen=True, kw_only=True)
class UTurnTask(PathTask):
    """Turn round in a dead-end street narrower than a forward U-turn needs: a three-point turn.

    The street (40 m long, a seeded width of 9-12 m, below the 14.65 m a forward
    U-turn of the paper's car needs) is closed by walls at its end (x = 0), both
    kerbs and its mouth; its two lanes are drawn. The ego starts in the north lane
    facing the dead end (seeded jitter) and must stop in the south lane at the same
    x, facing out (planned with gear changes).

    Parameters
    ----------
    map, seed, v_max, max_time_s, reverse
        See :class:`~rrtdrive.sim.tasks.Task` (``reverse`` is True).
    width : float
        The street's width in metres.
    """

    kind: ClassVar[TaskKind] = TaskKind.U_TURN
    OPTIONS: ClassVar[tuple[str, ...]] = ()

    width: float

    def __post_init__(self) -> None:
        super().__post_init__()
        if not (math.isfinite(self.width) and self.width > 0):
            raise InputError(f"width: need a number > 0, got {self.width!r}")

    @classmethod
    def create(
        cls,
        seed: int,
        rng: np.random.Generator,
        offset: tuple[float, float, float],
        vehicle: VehicleParams,
    ) -> UTurnTask:
        """The task for ``seed``: ``rng`` draws the width, ``offset`` the start jitter."""
        width = float(rng.uniform(*U_TURN_WIDTHS))
        base = u_turn_map(width, vehicle)
        dx, dy, dyaw = offset
        s = base.start
        start = Pose(s.x + dx, s.y + min(dy, 0.0), s.yaw + dyaw)  # never closer to the kerb
        if not _inside(base, start):
            start = s
        m = base.with_query(start=start)
        return cls(map=m, seed=int(seed), width=width, v_max=2.0, max_time_s=120.0,
                   reverse=True)

    def describe(self) -> dict[str, Any]:
        """The street's width and the width a forward U-turn would need."""
        return {
            "street_width_m": round(self.width, 3),
            "forward_u_turn_width_m": round(forward_u_turn_width(self.vehicle), 3),
        }

    def build_road(self, np_random: np.random.Generator, history: bool) -> Road:
        """Two drawn lanes (one each way) between solid kerbs; the walls close the street.

        Parameters
        ----------
        np_random, history
            As :meth:`Task.build_road`.

        Returns
        -------
        Road
        """
        xmin, ymin, xmax, ymax = self.map.bounds
        half = (ymax - ymin) / 2
        net = RoadNetwork()
        c, s = LineType.CONTINUOUS_LINE, LineType.STRIPED
        net.add_lane("a", "b", StraightLane([xmin, ymin + half / 2], [xmax, ymin + half / 2],
                                            half, (c, s)))
        net.add_lane("b", "a", StraightLane([xmax, ymax - half / 2], [xmin, ymax - half / 2],
                                            half, (c, LineType.NONE)))
        return populate_road(net, self.map, np_random, history, walls=True)


def _inside(m: Map, pose: Pose) -> bool:
    corners = footprint_corners((pose.x, pose.y, pose.yaw), m.vehicle)
    xmin, ymin, xmax, ymax = m.bounds
    return bool(
        np.all((corners[:, 0] > xmin) & (corners[:, 0] < xmax)
               & (corners[:, 1] > ymin) & (corners[:, 1] < ymax))
    )
