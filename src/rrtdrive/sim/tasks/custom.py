"""A custom task: any map with its own start and goal, planned and tracked like parking."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from highway_env.road.road import Road

from rrtdrive.sim.scenes import plain_network, populate_road
from rrtdrive.sim.tasks.base import PathTask, TaskKind

__all__ = ["CustomTask"]


@dataclass(frozen=True, kw_only=True)
class CustomTask(PathTask):
    """Drive from the map's start to its goal: every obstacle is a solid highway-env obstacle.

    Parameters
    ----------
    map, seed, v_max, max_time_s
        See :class:`~rrtdrive.sim.tasks.Task`.
    closed : bool
        Close the map's bounds with walls in the scene.

    Examples
    --------
    >>> from rrtdrive.maps import builtin_map
    >>> CustomTask(map=builtin_map("narrow_gap"), seed=0).name
    'custom'
    """

    kind: ClassVar[TaskKind] = TaskKind.CUSTOM

    closed: bool = True

    def build_road(self, np_random: np.random.Generator, history: bool) -> Road:
        """One undrawn lane; the map's obstacles (and walls when ``closed``)."""
        return populate_road(
            plain_network(self.map.bounds), self.map, np_random, history, walls=self.closed
        )
