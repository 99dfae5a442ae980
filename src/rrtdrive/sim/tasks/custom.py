"""A custom task: any map with its own start and goal, planned and tracked like parking.

``rrtdrive simulate MAP.json`` drives one (:meth:`CustomTask.from_map`): every
rectangle of the map becomes a solid highway-env obstacle, walls close its
bounds, and the video frames the whole map.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from highway_env.road.road import Road

from rrtdrive.collision import CheckerConfig
from rrtdrive.maps import Map
from rrtdrive.planning.result import same_pose
from rrtdrive.sim.loop import MAX_EPISODE_S
from rrtdrive.sim.scenes import plain_network, populate_road
from rrtdrive.sim.tasks.base import TaskKind
from rrtdrive.sim.tasks.path_task import PathTask
from rrtdrive.types import InputError, Pose, require_positive

__all__ = ["CustomTask"]


@dataclass(frozen=True, kw_only=True)
class CustomTask(PathTask):
    """Drive from the map's start to its goal: every obstacle is a solid highway-env obstacle.

    Parameters
    ----------
    map, seed, v_max, max_time_s, reverse
        See :class:`~rrtdrive.sim.tasks.Task`.
    closed : bool
        Close the map's bounds with walls in the scene.
    resolution : float, optional
        Cell size of the planner's collision grid in metres (``None``: the checker's
        own choice); a map too big for any automatic grid needs one.

    Examples
    --------
    >>> from rrtdrive.maps import builtin_map
    >>> CustomTask(map=builtin_map("narrow_gap"), seed=0).name
    'custom'
    """

    kind: ClassVar[TaskKind] = TaskKind.CUSTOM

    closed: bool = True
    resolution: float | None = None

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.resolution is not None:
            require_positive("scenario.resolution", self.resolution)
        a = self.map.start
        if same_pose(a, self.map.goal):
            # A planner answers 0 m (run_query); an episode would have nothing to drive.
            raise InputError(
                f"goal: the goal is the start pose ({a.x:g}, {a.y:g}, "
                f"{math.degrees(a.yaw):g} deg): there is nothing to drive; give another goal"
            )

    @classmethod
    def from_map(
        cls,
        m: Map,
        seed: int = 0,
        *,
        start: Pose | None = None,
        goal: Pose | None = None,
        reverse: bool = False,
        v_max: float = 3.0,
        max_time_s: float | None = None,
        resolution: float | None = None,
    ) -> CustomTask:
        """The task of driving map ``m`` from its start (or ``start``) to its goal (or ``goal``).

        Parameters
        ----------
        m : Map
            Any map (a file loaded with :func:`rrtdrive.maps.load_map`, a built-in).
        seed : int
            Episode seed (the planner and simulator streams; a map has no jitter).
        start, goal : Pose, optional
            Rear-axle poses replacing the map's (validated against its obstacles).
        reverse : bool
            Plan with gear changes.
        v_max : float
            Speed cap, m/s.
        max_time_s : float, optional
            Time limit; by default 60 s plus 2 s per metre of the map's diagonal
            (a drive across a tight map at walking pace, with gear changes), at most
            :data:`~rrtdrive.sim.loop.MAX_EPISODE_S`.
        resolution : float, optional
            The planner's collision grid cell size, metres (``rrtdrive simulate
            --resolution``).

        Examples
        --------
        >>> from rrtdrive.maps import builtin_map
        >>> t = CustomTask.from_map(builtin_map("garage"), reverse=True)
        >>> t.reverse, round(t.max_time_s, 1)
        (True, 186.5)
        """
        if not isinstance(m, Map):
            raise InputError(f"map: expected a Map, got {type(m).__name__}")
        if start is not None or goal is not None:
            m = m.with_query(start, goal)
        if max_time_s is None:
            xmin, ymin, xmax, ymax = m.bounds
            # Up to the longest limit an episode takes: a map too big for any grid (an inf
            # diagonal) is then refused by the planner naming its bounds.
            diagonal = math.hypot(xmax - xmin, ymax - ymin)
            max_time_s = min(60.0 + 2.0 * diagonal, MAX_EPISODE_S)
        return cls(
            map=m, seed=seed, reverse=reverse, v_max=v_max, max_time_s=max_time_s,
            resolution=resolution,
        )  # fmt: skip

    @property
    def checker_config(self) -> CheckerConfig | None:
        """The collision grid of :attr:`resolution`, when one was given."""
        return None if self.resolution is None else CheckerConfig(resolution=self.resolution)

    def describe(self) -> dict[str, object]:
        """The map's name and whether gear changes were allowed."""
        return {"map": self.map.name, "reverse": bool(self.reverse)}

    def build_road(self, np_random: np.random.Generator, history: bool) -> Road:
        """One undrawn lane; the map's obstacles (and walls when ``closed``).

        Parameters
        ----------
        np_random, history
            As :meth:`Task.build_road`.

        Returns
        -------
        Road
        """
        return populate_road(
            plain_network(self.map.bounds), self.map, np_random, history, walls=self.closed
        )
