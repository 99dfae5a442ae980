"""The highway-env scenes of rrtdrive's tasks: the environment, the road and its objects.

:func:`build_env` turns a task (:mod:`rrtdrive.sim.tasks`) into a highway-env
environment (:class:`SceneEnv`) whose road objects are exactly the map's
rectangles and whose controlled vehicle is an :class:`~rrtdrive.sim.ego.EgoVehicle`.
Each task builds its own road (``task.build_road``) from the pieces here: the lane
networks (:func:`two_way_network`, :func:`parking_network`, :func:`plain_network`)
and :func:`populate_road`, which puts the moving lead car, the map's obstacles
(solid highway-env obstacles of exactly their size and pose, or stopped vehicles),
the oncoming IDM cars (:class:`OncomingCar`) and the walls on it, in that order.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from highway_env.envs.common.abstract import AbstractEnv
from highway_env.road.lane import LineType, StraightLane
from highway_env.road.road import Road, RoadNetwork
from highway_env.vehicle.behavior import IDMVehicle
from highway_env.vehicle.graphics import VehicleGraphics
from highway_env.vehicle.kinematics import Vehicle
from highway_env.vehicle.objects import Obstacle as HwObstacle

from rrtdrive.maps import Map, Obstacle
from rrtdrive.parking_layout import (
    PARKING_ROW_CENTRES,
    PARKING_SPOT_DEPTH,
    PARKING_SPOT_WIDTH,
    parking_spots,
)
from rrtdrive.sim.ego import EgoVehicle
from rrtdrive.sim.limits import MAX_SIM_FREQUENCY, MIN_SIM_FREQUENCY
from rrtdrive.sim.pair_screen import object_boxes, pairs_to_handle
from rrtdrive.types import InputError, VehicleParams, require_int

__all__ = [
    "SimConfig",
    "SceneEnv",
    "SceneRoad",
    "SceneView",
    "fit_view",
    "OncomingCar",
    "build_env",
    "scenario_rngs",
    "two_way_network",
    "parking_network",
    "plain_network",
    "populate_road",
]


@dataclass(frozen=True)
class SimConfig:
    """How the simulator runs and draws.

    Parameters
    ----------
    simulation_frequency : int
        Steps per second of highway-env's physics; the controller runs at this rate
        (:data:`~rrtdrive.sim.limits.MIN_SIM_FREQUENCY` to
        :data:`~rrtdrive.sim.limits.MAX_SIM_FREQUENCY`: 15 to 1000).
    screen_width, screen_height : int
        Rendered frame size in pixels (0 picks the scenario's default).
    scaling : float
        Pixels per metre (0 picks the scenario's default).
    """

    simulation_frequency: int = 20
    screen_width: int = 0
    screen_height: int = 0
    scaling: float = 0.0

    def __post_init__(self) -> None:
        require_int(
            "sim.simulation_frequency", self.simulation_frequency,
            MIN_SIM_FREQUENCY, MAX_SIM_FREQUENCY,
        )  # fmt: skip
        for name in ("screen_width", "screen_height"):
            require_int(f"sim.{name}", getattr(self, name), 0)
        if not (self.scaling >= 0 and math.isfinite(self.scaling)):
            raise InputError(f"sim.scaling: need a number >= 0, got {self.scaling!r}")

    @property
    def dt(self) -> float:
        """Simulation step in seconds."""
        return 1.0 / self.simulation_frequency


@dataclass(frozen=True)
class SceneView:
    """How a task's live scene is framed by default (a task's ``scene_view()``).

    Attributes
    ----------
    size : tuple of int
        Frame ``(width, height)`` in pixels.
    scaling : float
        Pixels per metre.
    centering : tuple of float
        highway-env's ``centering_position`` (where the ego sits in the frame).
    """

    size: tuple[int, int]
    scaling: float
    centering: tuple[float, float]


#: Largest frame :func:`fit_view` makes, and the smallest (room for the read-out panel).
FIT_MAX_SIZE = (960, 640)
FIT_MIN_SIZE = (320, 240)


def _multiple_of_16(pixels: float) -> int:
    return int(16 * math.ceil(pixels / 16.0 - 1e-9))


def fit_view(
    bounds: tuple[float, float, float, float],
    margin: float = 3.25,
    max_size: tuple[int, int] = FIT_MAX_SIZE,
    max_scaling: float = 30.0,
) -> tuple[tuple[int, int], float, tuple[float, float]]:
    """Frame size, pixels per metre and centre that show the whole of ``bounds``.

    The scene (plus ``margin`` metres on every side) fills the frame as far as
    ``max_size`` allows: a 100 m square lot gets 640 x 640 pixels at 6 px/m, a
    60 x 8 m street a wide 960 x 240 frame, a 30 x 20 m garage 30 px/m. Sides are
    multiples of 16 (H.264 macro blocks) and at least :data:`FIT_MIN_SIZE` (the
    read-out panel), the extra pixels showing more of the ground around the map. A
    video whose panel would hide some of the drive in every corner of this frame adds
    a band above it for the panel (:func:`rrtdrive.sim.render.panel_band`).

    Parameters
    ----------
    bounds : tuple of float
        ``(xmin, ymin, xmax, ymax)`` in metres.
    margin : float
        Metres shown beyond each side of ``bounds``.
    max_size : tuple of int
        Largest ``(width, height)`` in pixels.
    max_scaling : float
        Largest pixels per metre (a tiny map is not blown up without limit).

    Returns
    -------
    size : tuple of int
        ``(width, height)`` in pixels.
    scaling : float
        Pixels per metre (rounded down to 0.1; below 0.1 to two significant digits).
    centre : tuple of float
        The centre of ``bounds``.

    Examples
    --------
    >>> fit_view((0.0, 0.0, 100.0, 100.0))
    ((640, 640), 6.0, (50.0, 50.0))
    >>> fit_view((0.0, 0.0, 60.0, 8.0))[:2]
    ((960, 240), 14.4)
    """
    xmin, ymin, xmax, ymax = (float(b) for b in bounds)
    if not (all(math.isfinite(b) for b in (xmin, ymin, xmax, ymax))
            and xmax > xmin and ymax > ymin):
        raise InputError(f"bounds: need finite xmin < xmax and ymin < ymax, got {bounds!r}")
    w, h = xmax - xmin + 2 * margin, ymax - ymin + 2 * margin
    scaling = min(max_size[0] / w, max_size[1] / h, max_scaling)
    # Down to 0.1 px/m; a map over ~9.6 km wide needs less, which rounded to 0 (a
    # ZeroDivisionError in highway-env's camera): two significant digits there.
    per = 10.0 if scaling >= 0.1 else 10.0 ** (1 - math.floor(math.log10(scaling)))
    scaling = math.floor(scaling * per + 1e-6) / per
    size = (
        max(FIT_MIN_SIZE[0], min(max_size[0], _multiple_of_16(w * scaling))),
        max(FIT_MIN_SIZE[1], min(max_size[1], _multiple_of_16(h * scaling))),
    )
    return size, scaling, ((xmin + xmax) / 2.0, (ymin + ymax) / 2.0)


def scenario_rngs(seed: int) -> tuple[np.random.Generator, np.random.Generator, int]:
    """Independent streams for one episode: scenario draws, planner, simulator seed."""
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise InputError(f"seed: need an integer >= 0, got {seed!r}")
    scen, plan, sim = np.random.SeedSequence(int(seed)).spawn(3)
    return (
        np.random.default_rng(scen),
        np.random.default_rng(plan),
        int(sim.generate_state(1)[0]),
    )


# ----------------------------------------------------------------------------- env


class SceneRoad(Road):
    """highway-env's ``Road`` with the same collision handling, minus calls that do nothing.

    ``Road.step`` calls ``handle_collisions`` for every pair of vehicles and every
    vehicle-object pair: 146 calls a step in the parking scene; in the overtake scene
    the road's walls pass highway-env's spherical pre-check every step, and those calls
    were most of an episode's time. A call whose pair highway-env's own tests (the
    pre-check, then the separating-axis test now and with the step's displacement)
    find apart changes nothing, so :func:`~rrtdrive.sim.pair_screen.pairs_to_handle`
    runs those tests for all pairs at once and only the others are handled, by
    highway-env, in the same order (a pair is dropped only when apart by more than
    1e-7 m).
    """

    def step(self, dt: float) -> None:
        """Step every vehicle, then handle the collisions of the pairs that may touch."""
        vehicles = self.vehicles
        for vehicle in vehicles:
            vehicle.step(dt)
        both_ways = [isinstance(v, EgoVehicle) for v in vehicles]
        # Objects never move (only vehicles step): their boxes are kept while the road
        # holds the same objects (the parking scene's 146 took half of each step).
        key = tuple(map(id, self.objects))
        if key != getattr(self, "_objects_key", None):
            self._objects_key = key
            self._objects_boxes = object_boxes(self.objects) if self.objects else None
        boxes = self._objects_boxes
        for vehicle, other in pairs_to_handle(vehicles, self.objects, dt, both_ways, boxes):
            vehicle.handle_collisions(other, dt)


class SceneEnv(AbstractEnv):
    """A highway-env environment whose scene is built from a task (:mod:`rrtdrive.sim.tasks`).

    Configure with ``{"scenario": Scenario, ...}``. The controlled vehicle is an
    :class:`EgoVehicle` at the scenario's start. Stepping it through ``env.step``
    works (continuous action, normalised acceleration and steering), but the
    closed-loop runner drives the road directly at the simulation frequency.
    """

    @classmethod
    def default_config(cls) -> dict:
        """highway-env configuration defaults for rrtdrive scenes."""
        config = super().default_config()
        vehicle = VehicleParams()
        config.update(
            {
                "observation": {"type": "Kinematics", "vehicles_count": 5},
                "action": {
                    "type": "ContinuousAction",
                    "acceleration_range": [-4.0, 2.0],
                    "steering_range": [-vehicle.max_steer, vehicle.max_steer],
                },
                "simulation_frequency": 20,
                "policy_frequency": 20,
                "duration": 120.0,
                "screen_width": 600,
                "screen_height": 600,
                "centering_position": [0.5, 0.5],
                "scaling": 6.0,
                "scenario": None,
            }
        )
        return config

    def _reset(self) -> None:
        scenario = self.config["scenario"]
        if scenario is None:
            raise InputError(
                "scenario: SceneEnv needs config['scenario'], a task of rrtdrive.sim.tasks "
                "(see build_env)"
            )
        self.road = scenario.build_road(self.np_random, self.config["show_trajectories"])
        ego = EgoVehicle(self.road, scenario.start, scenario.ego_speed, scenario.vehicle)
        ego.color = VehicleGraphics.EGO_COLOR
        self.road.vehicles.insert(0, ego)
        self.controlled_vehicles = [ego]

    def _reward(self, action: object) -> float:
        return 0.0

    def _is_terminated(self) -> bool:
        return bool(self.vehicle.crashed)

    def _is_truncated(self) -> bool:
        return bool(self.time >= self.config["duration"])


class OncomingCar(IDMVehicle):
    """highway-env's IDM car that keeps its lane and reacts to vehicles only.

    Stock IDM also brakes for static road objects next to its lane (it would stop
    for the road-edge walls of the overtake road, whose centres lie within its
    lane's margin); this one follows the nearest *vehicle* ahead in its lane -
    including the ego when it overtakes - and ignores the walls.
    """

    def act(self, action: dict | str | None = None) -> None:
        """IDM longitudinal control behind the nearest vehicle ahead in the lane."""
        if self.crashed:
            return
        self.follow_road()
        steering = float(
            np.clip(
                self.steering_control(self.target_lane_index),
                -self.MAX_STEERING_ANGLE, self.MAX_STEERING_ANGLE,
            )
        )
        lane = self.lane
        s = lane.local_coordinates(self.position)[0]
        front, best = None, math.inf
        straight = isinstance(lane, StraightLane)
        if straight:
            # A cheap scalar screen first (with a little slack, so it never drops a
            # vehicle the exact test below would keep): long roads carry many cars.
            sx, sy = float(lane.start[0]), float(lane.start[1])
            ux, uy = float(lane.direction[0]), float(lane.direction[1])
            reach = lane.width / 2.0 + 1.0 + 1e-6
        for v in self.road.vehicles:
            if v is self:
                continue
            if straight:
                dx, dy = float(v.position[0]) - sx, float(v.position[1]) - sy
                along = dx * ux + dy * uy
                if abs(dy * ux - dx * uy) > reach or along < s - 1e-6 or along > best + 1e-6:
                    continue
            sv, lat = lane.local_coordinates(v.position)
            if lane.on_lane(v.position, sv, lat, margin=1) and s <= sv < best:
                front, best = v, sv
        accel = float(np.clip(self.acceleration(self, front, None), -self.ACC_MAX, self.ACC_MAX))
        Vehicle.act(self, {"steering": steering, "acceleration": accel})

    def step(self, dt: float) -> None:
        """highway-env's step, but a car braking to a stop stays stopped.

        highway-env lets a vehicle's speed fall to ``MIN_SPEED`` (-40 m/s): an IDM car
        close behind the car it follows kept braking into reverse (the overtake's lead
        at 1 m/s, cut in on by the ego, drove backwards at up to 0.92 m/s).
        """
        super().step(dt)
        if self.speed < 0.0:
            self.speed = 0.0


#: Closest lane of a static object, by (network signature, position, heading). highway-env
#: searches every lane for every object it places (parking: 146 objects x 144 spot lanes,
#: 50 ms a build); the scenes reuse a handful of networks and positions, so each pair is
#: looked up once per process with highway-env's own search, and the result is the same.
_LANE_CACHE: dict[tuple[object, ...], tuple[str, str, int]] = {}
_LANE_CACHE_MAX = 100_000


def _network_key(net: RoadNetwork) -> tuple[object, ...]:
    """A hashable description of every lane of ``net`` (what the closest-lane search reads)."""
    key: list[object] = []
    for a, ends in net.graph.items():
        for b, lanes in ends.items():
            for i, lane in enumerate(lanes):
                key.append((a, b, i, type(lane).__name__, tuple(lane.start), tuple(lane.end),
                            lane.width))
    return tuple(key)


def _attach(obj: HwObstacle | Vehicle, road: Road, net_key: tuple[object, ...]) -> None:
    """Put an object built with ``road=None`` on ``road``, with the lane highway-env would find."""
    key = (net_key, float(obj.position[0]), float(obj.position[1]), float(obj.heading))
    lane_index = _LANE_CACHE.get(key)
    if lane_index is None:
        lane_index = road.network.get_closest_lane_index(obj.position, obj.heading)
        if len(_LANE_CACHE) >= _LANE_CACHE_MAX:
            _LANE_CACHE.clear()
        _LANE_CACHE[key] = lane_index
    obj.road = road
    obj.lane_index = lane_index
    obj.lane = road.network.get_lane(lane_index)


def _rect_object(road: Road, o: Obstacle, net_key: tuple[object, ...]) -> HwObstacle:
    """A solid highway-env obstacle of exactly ``o``'s rectangle (length >= width for drawing)."""
    length, width, yaw = o.size[0], o.size[1], o.yaw
    if width > length:  # highway-env draws on a length x length canvas
        length, width, yaw = width, length, yaw + math.pi / 2
    obj = HwObstacle(None, list(o.center), heading=yaw)
    _attach(obj, road, net_key)
    obj.LENGTH, obj.WIDTH = length, width
    obj.diagonal = math.hypot(length, width)
    return obj


def _rect_vehicle(road: Road, o: Obstacle, net_key: tuple[object, ...]) -> Vehicle:
    """A stopped highway-env vehicle of exactly ``o``'s rectangle."""
    v = Vehicle(None, list(o.center), heading=o.yaw, speed=0.0)
    _attach(v, road, net_key)
    v.LENGTH, v.WIDTH = o.size
    v.diagonal = math.hypot(*o.size)
    return v


def two_way_network(
    bounds: tuple[float, float, float, float], lane_y: float, lane_width: float
) -> RoadNetwork:
    """The overtake roads: the ego lane at ``lane_y`` along +x and the oncoming lane beside it."""
    net = RoadNetwork()
    y0 = float(lane_y)
    w = lane_width
    x0, x1 = bounds[0], bounds[2]
    c, s = LineType.CONTINUOUS_LINE, LineType.STRIPED
    net.add_lane("a", "b", StraightLane([x0, y0], [x1, y0], w, (c, s), speed_limit=20))
    # The oncoming lane runs on beyond the map so oncoming cars have a lane to arrive on.
    far = 20.0 * (x1 - x0)
    net.add_lane(
        "b", "a", StraightLane([x1 + far, y0 + w], [x0 - far, y0 + w], w, (c, LineType.NONE))
    )
    return net


def parking_network() -> RoadNetwork:
    """The parking lot: one lane per spot, drawn with solid lines like highway-env's parking-v0."""
    net = RoadNetwork()
    lt = (LineType.CONTINUOUS, LineType.CONTINUOUS)
    for r, side, i, x, _y in parking_spots():
        yc = PARKING_ROW_CENTRES[r]
        outer = yc - PARKING_SPOT_DEPTH if side == 0 else yc + PARKING_SPOT_DEPTH
        net.add_lane(
            f"r{r}s{side}", f"{i}",
            StraightLane([x, outer], [x, yc], PARKING_SPOT_WIDTH, lt, speed_limit=5),
        )
    return net


def plain_network(bounds: tuple[float, float, float, float]) -> RoadNetwork:
    """One undrawn lane along the bottom of ``bounds`` (any map: highway-env needs a lane)."""
    net = RoadNetwork()
    xmin, ymin, xmax, ymax = bounds
    net.add_lane("a", "b", StraightLane([xmin, ymin], [xmax, ymin], line_types=(0, 0)))
    return net


def populate_road(
    net: RoadNetwork,
    m: Map,
    np_random: np.random.Generator,
    history: bool,
    *,
    lead: tuple[float, float] | None = None,
    lead_model: str = "idm",
    vehicle_obstacles: tuple[int, ...] = (),
    oncoming: tuple[tuple[float, float], ...] = (),
    walls: bool = False,
) -> SceneRoad:
    """A :class:`SceneRoad` on ``net`` with the lead car, ``m``'s obstacles, oncoming cars, walls.

    Parameters
    ----------
    net : RoadNetwork
        The lanes; the lead car drives on ``("a", "b", 0)``, oncoming cars on
        ``("b", "a", 0)``.
    m : Map
        Its obstacles become solid highway-env obstacles (or stopped vehicles, see
        ``vehicle_obstacles``); its bounds the walls. The moving cars are the paper's
        car's size (a stock car), whatever ``m``'s car.
    np_random : numpy.random.Generator
        The road's generator.
    history : bool
        Record vehicle histories (highway-env's ``show_trajectories``).
    lead : tuple of (float, float), optional
        ``(x, speed)`` of a moving lead car's body centre in the ego lane; it is the
        first vehicle after the ego in every log.
    lead_model : str
        ``"idm"`` (:class:`OncomingCar`, keeps its lane) or ``"constant"`` (a plain
        highway-env vehicle).
    vehicle_obstacles : tuple of int
        Indices of map obstacles that become stopped highway-env vehicles.
    oncoming : tuple of (float, float)
        ``(x, speed)`` of each oncoming IDM car's body centre.
    walls : bool
        Close ``m``'s bounds with 1 m walls.
    """
    # The moving cars are stock cars whatever the ego, as overtake's stopped car (a tiny
    # ego shrank the whole traffic to its size; an audit).
    vehicle = VehicleParams()
    road = SceneRoad(network=net, np_random=np_random, record_history=history)
    if lead is not None:
        # The moving lead car first (the first vehicle after the ego in every log).
        x, speed = lead
        lane_index = ("a", "b", 0)
        lane = net.get_lane(lane_index)
        pos = lane.position(lane.local_coordinates([x, 0.0])[0], 0.0)
        if lead_model == "idm":
            car: Vehicle = OncomingCar(
                road, pos, lane.heading_at(0.0), speed, target_lane_index=lane_index,
                target_speed=speed, enable_lane_change=False,
            )
        else:
            car = Vehicle(road, pos, lane.heading_at(0.0), speed)
        car.LENGTH, car.WIDTH = vehicle.length, vehicle.width
        car.diagonal = math.hypot(car.LENGTH, car.WIDTH)
        road.vehicles.append(car)
    vehicle_ids = set(vehicle_obstacles)
    net_key = _network_key(net)
    for i, o in enumerate(m.obstacles):
        if i in vehicle_ids:
            road.vehicles.append(_rect_vehicle(road, o, net_key))
        else:
            road.objects.append(_rect_object(road, o, net_key))
    for x, speed in oncoming:
        lane_index = ("b", "a", 0)
        lane = net.get_lane(lane_index)
        other = OncomingCar(
            road, lane.position(lane.local_coordinates([x, 0.0])[0], 0.0), lane.heading_at(0.0),
            speed, target_lane_index=lane_index, target_speed=speed, enable_lane_change=False,
        )
        other.LENGTH, other.WIDTH = vehicle.length, vehicle.width
        other.diagonal = math.hypot(other.LENGTH, other.WIDTH)
        road.vehicles.append(other)
    if walls:
        xmin, ymin, xmax, ymax = m.bounds
        t = 1.0
        for wall in (
            Obstacle(((xmin + xmax) / 2, ymin - t / 2), (xmax - xmin + 2 * t, t)),
            Obstacle(((xmin + xmax) / 2, ymax + t / 2), (xmax - xmin + 2 * t, t)),
            Obstacle((xmin - t / 2, (ymin + ymax) / 2), (ymax - ymin, t), math.pi / 2),
            Obstacle((xmax + t / 2, (ymin + ymax) / 2), (ymax - ymin, t), math.pi / 2),
        ):
            road.objects.append(_rect_object(road, wall, net_key))
    return road


def build_env(scenario: Any, sim: SimConfig | None = None, render: bool = False) -> SceneEnv:
    """The highway-env environment of ``scenario``, reset with the scenario's simulator seed.

    Parameters
    ----------
    scenario : Task
        What to build (a task of :mod:`rrtdrive.sim.tasks`: it builds its road and
        says how the scene is framed, :meth:`~rrtdrive.sim.tasks.Task.scene_view`).
    sim : SimConfig, optional
        Frequency and frame size.
    render : bool
        Create it with ``render_mode="rgb_array"`` (only when recording: drawing is costly).

    Returns
    -------
    SceneEnv
        Reset and ready; ``env.unwrapped.vehicle`` is the :class:`EgoVehicle`.
    """
    sim = sim or SimConfig()
    view = scenario.scene_view()
    config = {
        "scenario": scenario,
        "simulation_frequency": sim.simulation_frequency,
        "policy_frequency": sim.simulation_frequency,
        "duration": scenario.max_time_s,
        "screen_width": sim.screen_width or view.size[0],
        "screen_height": sim.screen_height or view.size[1],
        "scaling": sim.scaling or view.scaling,
        "centering_position": list(view.centering),
        # Full lock of a normalised action is the scenario's car's own (not the stock 30 deg).
        "action": {
            **SceneEnv.default_config()["action"],
            "steering_range": [-scenario.vehicle.max_steer, scenario.vehicle.max_steer],
        },
    }
    env = SceneEnv(config=config, render_mode="rgb_array" if render else None)
    _, _, sim_seed = scenario_rngs(scenario.seed)
    env.reset(seed=sim_seed)
    return env
