"""The overtake task: pass a stopped car on a two-way road, optionally against oncoming cars."""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np
from highway_env.road.road import Road

from rrtdrive.controllers import SpeedConfig, TrackingController
from rrtdrive.maps import LANE_WIDTH, Obstacle, overtake_map
from rrtdrive.sim.loop import Driver, PathTracker
from rrtdrive.sim.scenes import SceneView, populate_road, two_way_network
from rrtdrive.sim.tasks.base import Reference, SuccessPart, TaskKind, VideoCamera
from rrtdrive.sim.tasks.path_task import PathTask
from rrtdrive.sim.traffic import OncomingGate, conflict_zone
from rrtdrive.types import InputError, Path, Pose, VehicleParams, require_int
from rrtdrive.vehicle import footprint_corners

if TYPE_CHECKING:  # pragma: no cover
    from rrtdrive.sim.episode import Episode
    from rrtdrive.sim.runner import EpisodeConfig

__all__ = ["OvertakeTask"]


def _car_like(obstacles: tuple[Obstacle, ...], vehicle: VehicleParams) -> list[int]:
    out = [
        i for i, o in enumerate(obstacles)
        if abs(o.size[0] - vehicle.length) < 1e-6 and abs(o.size[1] - vehicle.width) < 1e-6
    ]
    if not out:
        raise InputError("scenario: the overtake map has no car-sized obstacle")
    return out


@dataclass(frozen=True, kw_only=True)
class OvertakeTask(PathTask):
    """Pass the stopped car of the ``overtake`` map, return to the lane and stop at the goal.

    The scene is a highway-env two-way road: the ego lane (y = 44, driving +x) and
    the oncoming lane (y = 48), the road edges as solid obstacles and a stopped
    highway-env vehicle at the map's car. Oncoming IDM cars, if any, drive -x in
    the oncoming lane; the ego waits for a gap before pulling out
    (:meth:`oncoming_gate`).

    Parameters
    ----------
    map, seed, v_max, max_time_s
        See :class:`~rrtdrive.sim.tasks.Task`.
    lead_index : int
        Index of the stopped car among the map's obstacles.
    vehicle_obstacles : tuple of int
        Indices of map obstacles that the scene makes (stopped) highway-env vehicles.
    lane_y : float
        Centre line of the ego lane.
    lane_width : float
        Lane width in metres.
    oncoming : tuple of (float, float)
        ``(x, speed)`` of each oncoming car (body centre, m/s) at the start.
    """

    kind: ClassVar[TaskKind] = TaskKind.OVERTAKE
    OPTIONS: ClassVar[tuple[str, ...]] = ("oncoming",)

    # Fields where Task keeps class-level defaults for the kinds without them (mypy
    # reads that as overriding a ClassVar).
    lead_index: int  # type: ignore[misc]
    vehicle_obstacles: tuple[int, ...]
    lane_y: float  # type: ignore[misc]
    lane_width: float = LANE_WIDTH  # type: ignore[misc]
    oncoming: tuple[tuple[float, float], ...] = ()  # type: ignore[misc]

    def __post_init__(self) -> None:
        super().__post_init__()
        n = len(self.map.obstacles)
        if not all(0 <= i < n for i in (self.lead_index, *self.vehicle_obstacles)):
            raise InputError(
                f"scenario.lead_index: obstacle indices must lie in [0, {n}), got "
                f"{self.lead_index!r} and {self.vehicle_obstacles!r}"
            )

    @classmethod
    def create(
        cls,
        seed: int,
        rng: np.random.Generator,
        offset: tuple[float, float, float],
        vehicle: VehicleParams,
        oncoming: object = 0,
    ) -> OvertakeTask:
        """The task for ``seed``: ``oncoming`` cars 90-140 m apart beyond the road's end."""
        count = require_int("oncoming", oncoming, 0, 10)
        base = dataclasses.replace(overtake_map(), vehicle=vehicle)
        dx, dy, dyaw = offset
        start = Pose(base.start.x + dx, base.start.y + 0.3 * dy, base.start.yaw + dyaw)
        m = base.with_query(start=start)
        # The stopped car is the map's own, a stock car whatever the ego (a user's car
        # of another size found none and the scenario refused it).
        lead = _car_like(m.obstacles, VehicleParams())
        cars = []
        x = m.bounds[2]
        for _ in range(count):
            x += float(rng.uniform(90.0, 140.0))
            cars.append((x, float(rng.uniform(6.0, 9.0))))
        return cls(
            map=m, seed=int(seed), vehicle_obstacles=tuple(lead), lead_index=lead[0],
            lane_y=base.start.y, v_max=8.0, max_time_s=60.0 + 15.0 * count,
            oncoming=tuple(cars),
        )

    def build_road(self, np_random: np.random.Generator, history: bool) -> Road:
        """The two-way road, the stopped car and the road edges, the oncoming cars.

        Parameters
        ----------
        np_random, history
            As :meth:`Task.build_road`.

        Returns
        -------
        Road
        """
        net = two_way_network(self.map.bounds, self.lane_y, self.lane_width)
        return populate_road(
            net, self.map, np_random, history, vehicle_obstacles=self.vehicle_obstacles,
            oncoming=self.oncoming,
        )

    def scene_view(self) -> SceneView:
        """A wide window, the ego left of centre."""
        return SceneView((900, 300), 8.0, (0.35, 0.5))

    def camera(self) -> VideoCamera:
        """The whole road, wide."""
        m = self.map
        lane_y = self.lane_y or (m.bounds[1] + m.bounds[3]) / 2
        return VideoCamera((960, 320), 9.0, ((m.bounds[0] + m.bounds[2]) / 2, lane_y + 2.0))

    def success_part(self, episode: Episode) -> SuccessPart:
        """Past the stopped car (all body corners beyond its front) and back in the ego lane.

        Parameters
        ----------
        episode : Episode
            A finished episode of this task (its final state is judged).

        Returns
        -------
        SuccessPart
            ``passed_lead`` and ``back_in_lane`` set, both required.
        """
        final = episode.log.states[-1]
        lead = self.map.obstacles[self.lead_index]
        body = footprint_corners(final[:3], self.vehicle)
        passed_lead = bool(body[:, 0].min() > lead.corners()[:, 0].max())
        half = self.lane_width / 2.0
        back_in_lane = bool(np.all(np.abs(body[:, 1] - self.lane_y) <= half))
        return SuccessPart(passed_lead=passed_lead, back_in_lane=back_in_lane, lead_required=True)

    def oncoming_gate(
        self, env: Any, path: Path, speed: SpeedConfig
    ) -> tuple[OncomingGate, Sequence[Any]] | None:
        """The gate that holds the ego before the oncoming lane, and the cars it watches.

        ``None`` without oncoming cars or when ``path`` never enters the oncoming lane.

        Parameters
        ----------
        env : SceneEnv
            The built scene; the gate watches its moving vehicles other than the ego.
        path : Path
            The path to be tracked.
        speed : SpeedConfig
            The controller's speed profile settings (they time the crossing).

        Returns
        -------
        tuple of (OncomingGate, sequence of highway-env vehicles) or None
        """
        if not self.oncoming:
            return None
        zone = conflict_zone(path, self.lane_y, self.lane_width, self.vehicle)
        if zone is None:
            return None
        ego = env.unwrapped.vehicle
        cars = [v for v in env.unwrapped.road.vehicles if v is not ego and v.speed > 0]
        gate = OncomingGate(
            zone, (path.arc_length(), path.samples[:, 3]), speed, vehicle=self.vehicle
        )
        return gate, cars

    def make_driver(
        self,
        env: Any,
        controller: TrackingController,
        reference: Reference,
        speed: SpeedConfig,
        config: EpisodeConfig,
        seed: int,
    ) -> Driver:
        """A path tracker held by the oncoming-traffic gate (when there is oncoming traffic).

        Parameters
        ----------
        env, controller, reference, speed, config, seed
            As :meth:`Task.make_driver`; ``config`` and ``seed`` are unused.

        Returns
        -------
        PathTracker
        """
        assert reference.path is not None
        gate = self.oncoming_gate(env, reference.path, speed)
        if gate is None:
            return PathTracker(env, controller, reference.path)
        return PathTracker(env, controller, reference.path, gate[0], gate[1])
