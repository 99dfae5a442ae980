"""Scenarios and the highway-env scenes built from them.

A :class:`Scenario` is plain data: the map (with this episode's start and goal),
the seed and what success means. :func:`build_env` turns it into a highway-env
environment (:class:`SceneEnv`) whose road objects are exactly the map's
rectangles and whose controlled vehicle is an :class:`~rrtdrive.sim.ego.EgoVehicle`.

* ``parking`` - the ``parking_lot`` map: every parked car and block becomes a solid
  highway-env :class:`~highway_env.vehicle.objects.Obstacle` of exactly its size and
  pose, walls close the bounds, each spot is drawn as a lane. The ego starts at the
  entrance with a seeded jitter and must stop nose-in in a seeded free spot.
* ``overtake`` - the ``overtake`` map as a highway-env two-way road: the ego lane
  (y = 44, driving +x) and the oncoming lane (y = 48), road edges as solid
  obstacles, a stopped highway-env vehicle at the map's car. The ego must pass it,
  return to its lane and stop at the goal.
* ``overtake-traffic`` - a long two-way road (same lanes) with a slow *moving* lead
  car in the ego lane (highway-env IDM or constant speed) and a seeded stream of
  oncoming IDM cars (speeds and gaps drawn per seed, mean gap from the density in
  cars per km). The ego overtakes with receding-horizon space-time re-planning
  (:mod:`rrtdrive.sim.replanning`) and is done once it is back in its lane ahead
  of the lead car.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np
from highway_env.envs.common.abstract import AbstractEnv
from highway_env.road.lane import LineType, StraightLane
from highway_env.road.road import Road, RoadNetwork
from highway_env.vehicle.behavior import IDMVehicle
from highway_env.vehicle.graphics import VehicleGraphics
from highway_env.vehicle.kinematics import Vehicle
from highway_env.vehicle.objects import Obstacle as HwObstacle

from rrtdrive.maps import (
    LANE_WIDTH,
    PARKING_EMPTY_SPOTS,
    PARKING_ROW_CENTRES,
    PARKING_SPOT_DEPTH,
    PARKING_SPOT_WIDTH,
    Map,
    Obstacle,
    overtake_map,
    parking_goal_pose,
    parking_lot_map,
    parking_spots,
)
from rrtdrive.sim.ego import EgoVehicle
from rrtdrive.types import InputError, Pose, VehicleParams, require_int, require_positive

__all__ = [
    "SCENARIOS",
    "Scenario",
    "SimConfig",
    "SceneEnv",
    "SceneRoad",
    "OncomingCar",
    "make_scenario",
    "build_env",
    "scenario_rngs",
    "TRAFFIC_DENSITIES",
    "LEAD_MODELS",
    "traffic_map",
]

SCENARIOS = ("parking", "overtake", "overtake-traffic")

#: Named oncoming-traffic densities of ``overtake-traffic`` (cars per km of oncoming lane).
TRAFFIC_DENSITIES: dict[str, float] = {"low": 5.0, "default": 10.0, "high": 20.0}
#: How the lead car of ``overtake-traffic`` drives.
LEAD_MODELS = ("idm", "constant")
#: Road of ``overtake-traffic``: length in metres and the ego's start x.
TRAFFIC_ROAD_LENGTH = 1500.0
TRAFFIC_START_X = 5.0


@dataclass(frozen=True)
class SimConfig:
    """How the simulator runs and draws.

    Parameters
    ----------
    simulation_frequency : int
        Steps per second of highway-env's physics; the controller runs at this rate.
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
        require_int("sim.simulation_frequency", self.simulation_frequency, 15)
        for name in ("screen_width", "screen_height"):
            require_int(f"sim.{name}", getattr(self, name), 0)
        if not (self.scaling >= 0 and math.isfinite(self.scaling)):
            raise InputError(f"sim.scaling: need a number >= 0, got {self.scaling!r}")

    @property
    def dt(self) -> float:
        """Simulation step in seconds."""
        return 1.0 / self.simulation_frequency


@dataclass(frozen=True)
class Scenario:
    """One episode's task, as plain data.

    Attributes
    ----------
    name : str
        ``"parking"``, ``"overtake"`` or ``"custom"``.
    map : Map
        The map with this episode's start and goal (rear-axle poses).
    seed : int
        The seed the start jitter and the goal were drawn from.
    vehicle_obstacles : tuple of int
        Indices of map obstacles that the scene makes highway-env vehicles.
    spot : tuple of int or None
        Parking: the ``(row, side, index)`` of the goal spot.
    lead_index : int or None
        Overtake: index of the stopped car among the map's obstacles.
    lane_y : float or None
        Overtake: centre line of the ego lane.
    lane_width : float
        Overtake: lane width in metres.
    v_max : float
        Speed cap for the episode in m/s.
    max_time_s : float
        Time allowed before the episode counts as failed.
    walls : bool
        Whether the scene closes the bounds with walls.
    oncoming : tuple of (float, float)
        Overtake: ``(x, speed)`` of each oncoming car (body centre, m/s) at the start;
        they drive -x in the oncoming lane as highway-env IDM vehicles.
    lead : tuple of (float, float) or None
        ``overtake-traffic``: ``(x, speed)`` of the moving lead car's body centre in
        the ego lane (the first vehicle of the scene after the ego).
    lead_model : str
        ``overtake-traffic``: ``"idm"`` (highway-env IDM, keeps its lane, follows the
        vehicle ahead) or ``"constant"`` (a plain highway-env vehicle at constant speed).
    density : float or None
        ``overtake-traffic``: oncoming cars per km (mean gap ``1000 / density`` m).
    ego_speed : float
        Initial speed of the ego in m/s.
    """

    name: str
    map: Map
    seed: int
    vehicle_obstacles: tuple[int, ...] = ()
    spot: tuple[int, int, int] | None = None
    lead_index: int | None = None
    lane_y: float | None = None
    lane_width: float = LANE_WIDTH
    v_max: float = 3.0
    max_time_s: float = 120.0
    walls: bool = True
    oncoming: tuple[tuple[float, float], ...] = ()
    lead: tuple[float, float] | None = None
    lead_model: str = "idm"
    density: float | None = None
    ego_speed: float = 0.0

    def __post_init__(self) -> None:
        require_positive("scenario.v_max", self.v_max)
        require_positive("scenario.max_time_s", self.max_time_s)
        if self.lead_model not in LEAD_MODELS:
            raise InputError(
                f"lead_model: unknown lead model {self.lead_model!r}; "
                f"choose from {list(LEAD_MODELS)}"
            )
        if not (math.isfinite(self.ego_speed) and self.ego_speed >= 0):
            raise InputError(f"scenario.ego_speed: must be >= 0, got {self.ego_speed!r}")

    @property
    def is_traffic(self) -> bool:
        """True for the moving-traffic scenario (re-planning instead of one plan)."""
        return self.name == "overtake-traffic"

    @property
    def start(self) -> Pose:
        """Rear-axle start pose."""
        return self.map.start

    @property
    def goal(self) -> Pose:
        """Rear-axle goal pose."""
        return self.map.goal

    @property
    def vehicle(self) -> VehicleParams:
        """The car."""
        return self.map.vehicle


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


def make_scenario(
    name: str,
    seed: int = 0,
    *,
    spot: tuple[int, int, int] | None = None,
    jitter: tuple[float, float, float] = (1.0, 0.5, math.radians(5.0)),
    vehicle: VehicleParams | None = None,
    oncoming: int = 0,
    density: float | str | None = None,
    lead_speed: float | None = None,
    lead_model: str | None = None,
) -> Scenario:
    """Build the scenario ``name`` for ``seed``.

    Parameters
    ----------
    name : str
        ``"parking"``, ``"overtake"`` or ``"overtake-traffic"``.
    seed : int
        Seeds the start jitter and (parking) the choice of the free spot.
    spot : tuple of int, optional
        Parking: force this ``(row, side, index)`` spot (must be empty).
    jitter : tuple of float
        Half-ranges of the uniform start jitter in x, y (metres) and yaw (radians).
    vehicle : VehicleParams, optional
        The car.
    oncoming : int
        Overtake: number of oncoming cars (seeded positions 90-140 m apart beyond
        the road's end, speeds 6-9 m/s). The ego waits for a gap before pulling out.
    density : float or str, optional
        ``overtake-traffic``: oncoming cars per km, or a name of
        :data:`TRAFFIC_DENSITIES` (default ``"default"``, 10 per km). Gaps between
        oncoming cars are 25 m plus an exponential draw (mean gap ``1000 / density``),
        speeds uniform in 6-9 m/s.
    lead_speed : float, optional
        ``overtake-traffic``: speed of the lead car in m/s (default 4, below the
        ego's 11 m/s cap). The ego starts at this speed, 20-30 m behind it.
    lead_model : str, optional
        ``overtake-traffic``: ``"idm"`` (default) or ``"constant"``.

    Returns
    -------
    Scenario

    Examples
    --------
    >>> s = make_scenario("parking", 3)
    >>> s.spot in PARKING_EMPTY_SPOTS, s == make_scenario("parking", 3)
    (True, True)
    """
    rng, _, _ = scenario_rngs(seed)
    if len(jitter) != 3 or any(not (j >= 0 and math.isfinite(j)) for j in jitter):
        raise InputError(f"jitter: need three finite numbers >= 0, got {jitter!r}")
    require_int("oncoming", oncoming, 0, 10)
    if oncoming and name != "overtake":
        raise InputError("oncoming: only the overtake scenario has a count of oncoming cars")
    if name != "overtake-traffic":
        for label, value in (
            ("density", density), ("lead_speed", lead_speed), ("lead_model", lead_model)
        ):
            if value is not None:
                raise InputError(f"{label}: only the overtake-traffic scenario has it")
    vehicle = vehicle or VehicleParams()
    dx, dy, dyaw = (float(rng.uniform(-j, j)) if j > 0 else 0.0 for j in jitter)
    if name == "parking":
        base = dataclasses.replace(parking_lot_map(), vehicle=vehicle)
        spots = sorted(PARKING_EMPTY_SPOTS)
        if spot is None:
            spot = spots[int(rng.integers(len(spots)))]
        elif tuple(spot) not in PARKING_EMPTY_SPOTS:
            raise InputError(f"spot: {spot!r} is not an empty spot; choose from {spots}")
        spot = tuple(int(v) for v in spot)  # type: ignore[assignment]
        start = Pose(base.start.x + dx, base.start.y + dy, base.start.yaw + dyaw)
        goal = parking_goal_pose(*spot, vehicle=vehicle)  # type: ignore[misc]
        m = base.with_query(start=start, goal=goal)
        return Scenario(
            "parking", m, int(seed), spot=spot, v_max=3.0, max_time_s=120.0, walls=True
        )
    if name == "overtake":
        if spot is not None:
            raise InputError("spot: only the parking scenario has spots")
        base = dataclasses.replace(overtake_map(), vehicle=vehicle)
        start = Pose(base.start.x + dx, base.start.y + 0.3 * dy, base.start.yaw + dyaw)
        m = base.with_query(start=start)
        lead = _car_like(m.obstacles, vehicle)
        cars = []
        x = m.bounds[2]
        for _ in range(oncoming):
            x += float(rng.uniform(90.0, 140.0))
            cars.append((x, float(rng.uniform(6.0, 9.0))))
        return Scenario(
            "overtake", m, int(seed), vehicle_obstacles=tuple(lead), lead_index=lead[0],
            lane_y=base.start.y, v_max=8.0, max_time_s=60.0 + 15.0 * oncoming, walls=False,
            oncoming=tuple(cars),
        )
    if name == "overtake-traffic":
        if spot is not None:
            raise InputError("spot: only the parking scenario has spots")
        dens = _density(density)
        v_lead = 4.0 if lead_speed is None else lead_speed
        require_positive("lead_speed", v_lead)
        v_max = 11.0
        if v_lead >= v_max - 2.0:
            raise InputError(
                f"lead_speed: must be below {v_max - 2.0:g} m/s (the ego's cap is {v_max:g}), "
                f"got {v_lead!r}"
            )
        model = "idm" if lead_model is None else lead_model
        if model not in LEAD_MODELS:
            raise InputError(
                f"lead_model: unknown lead model {model!r}; choose from {list(LEAD_MODELS)}"
            )
        start = Pose(TRAFFIC_START_X + dx, 44.0 + 0.3 * dy, 0.4 * dyaw)
        m = traffic_map(vehicle, start)
        centre_offset = vehicle.length / 2.0 - vehicle.rear_overhang
        lead_x = start.x + centre_offset + float(rng.uniform(20.0, 30.0))
        mean_gap = 1000.0 / dens
        gap_min = 25.0
        cars = []
        x = start.x + 40.0 + float(rng.uniform(0.0, mean_gap))
        while x < start.x + 1300.0:
            cars.append((x, float(rng.uniform(6.0, 9.0))))
            x += gap_min + float(rng.exponential(max(mean_gap - gap_min, 1.0)))
        return Scenario(
            "overtake-traffic", m, int(seed), lane_y=44.0, v_max=v_max, max_time_s=90.0,
            walls=False, oncoming=tuple(cars), lead=(lead_x, float(v_lead)), lead_model=model,
            density=dens, ego_speed=float(v_lead),
        )
    raise InputError(f"scenario: unknown scenario {name!r}; choose from {list(SCENARIOS)}")


def _density(density: float | str | None) -> float:
    """Oncoming cars per km from a number or a name of :data:`TRAFFIC_DENSITIES`."""
    if density is None:
        return TRAFFIC_DENSITIES["default"]
    if isinstance(density, str):
        if density in TRAFFIC_DENSITIES:
            return TRAFFIC_DENSITIES[density]
        try:
            density = float(density)
        except ValueError:
            raise InputError(
                f"density: expected cars per km or one of {sorted(TRAFFIC_DENSITIES)}, "
                f"got {density!r}"
            ) from None
    require_positive("density", density)
    if density > 30.0:
        raise InputError(f"density: at most 30 cars per km, got {density!r}")
    return float(density)


def traffic_map(vehicle: VehicleParams | None = None, start: Pose | None = None) -> Map:
    """The road of ``overtake-traffic`` as a map: two 4 m lanes along x, the edges as bounds.

    The bounds are the road (x in [0, 1500], y in [42, 50]) and act as walls; the
    ego lane is centred on y = 44 (driving +x), the oncoming lane on y = 48. No
    static obstacles: the lead car and the oncoming cars move. The goal is the far
    end of the ego lane (the episode ends earlier, when the overtake is complete).
    """
    vehicle = vehicle or VehicleParams()
    return Map(
        "overtake-traffic",
        (0.0, 42.0, TRAFFIC_ROAD_LENGTH, 42.0 + 2 * LANE_WIDTH),
        (),
        start or Pose(TRAFFIC_START_X, 44.0, 0.0),
        Pose(TRAFFIC_ROAD_LENGTH - 10.0, 44.0, 0.0),
        vehicle,
    )


def _car_like(obstacles: tuple[Obstacle, ...], vehicle: VehicleParams) -> list[int]:
    out = [
        i for i, o in enumerate(obstacles)
        if abs(o.size[0] - vehicle.length) < 1e-6 and abs(o.size[1] - vehicle.width) < 1e-6
    ]
    if not out:
        raise InputError("scenario: the overtake map has no car-sized obstacle")
    return out


# ----------------------------------------------------------------------------- env


#: Up to this many collision pairs a step, ``SceneRoad`` uses ``Road.step`` as it is.
_FEW_PAIRS = 16


def _centres_and_diagonals(items: list) -> tuple[np.ndarray, np.ndarray]:
    if not items:
        return np.zeros((0, 2)), np.zeros(0)
    return (
        np.array([o.position for o in items], dtype=float).reshape(-1, 2),
        np.array([o.diagonal for o in items], dtype=float),
    )


class SceneRoad(Road):
    """highway-env's ``Road`` with the same collision handling, minus calls that do nothing.

    ``Road.step`` calls ``handle_collisions`` for every pair of vehicles and every
    vehicle-object pair: 146 calls a step in the parking scene, 90 % of an episode's
    time. A call whose pair fails highway-env's own spherical pre-check (centres
    further apart than the half diagonals plus ``speed * dt``) changes nothing, so
    those pairs are screened out here with one vectorised distance test (kept with a
    1e-9 m margin so that no pair highway-env would examine is dropped); the others
    are handled by highway-env in the same order.
    """

    def step(self, dt: float) -> None:
        """Step every vehicle, then handle the collisions of the pairs that may touch."""
        vehicles, objects = self.vehicles, self.objects
        n = len(vehicles)
        if n * (n - 1) // 2 + n * len(objects) <= _FEW_PAIRS:
            super().step(dt)  # a few pairs: the screen would cost more than it saves
            return
        for vehicle in vehicles:
            vehicle.step(dt)
        v_pos, v_diag = _centres_and_diagonals(vehicles)
        o_pos, o_diag = _centres_and_diagonals(objects)
        for i, vehicle in enumerate(vehicles):
            own = vehicle.diagonal / 2 + vehicle.speed * dt + 1e-9
            if i + 1 < n:
                d = np.hypot(*(v_pos[i + 1 :] - v_pos[i]).T)
                for k in np.flatnonzero(d <= own + v_diag[i + 1 :] / 2):
                    vehicle.handle_collisions(vehicles[i + 1 + k], dt)
            if objects:
                d = np.hypot(*(o_pos - v_pos[i]).T)
                for k in np.flatnonzero(d <= own + o_diag / 2):
                    vehicle.handle_collisions(objects[k], dt)


class SceneEnv(AbstractEnv):
    """A highway-env environment whose scene is built from a :class:`Scenario`.

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
            scenario = make_scenario("parking", 0)
            self.config["scenario"] = scenario
        self.road = _build_road(scenario, self.np_random, self.config["show_trajectories"])
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


def _build_road(scenario: Scenario, np_random: np.random.Generator, history: bool) -> Road:
    net = RoadNetwork()
    m = scenario.map
    if scenario.name in ("overtake", "overtake-traffic"):
        y0 = float(scenario.lane_y)  # type: ignore[arg-type]
        w = scenario.lane_width
        x0, x1 = m.bounds[0], m.bounds[2]
        c, s = LineType.CONTINUOUS_LINE, LineType.STRIPED
        net.add_lane("a", "b", StraightLane([x0, y0], [x1, y0], w, (c, s), speed_limit=20))
        # The oncoming lane runs on beyond the map so oncoming cars have a lane to arrive on.
        far = 20.0 * (x1 - x0)
        net.add_lane(
            "b", "a", StraightLane([x1 + far, y0 + w], [x0 - far, y0 + w], w, (c, LineType.NONE))
        )
    elif scenario.name == "parking":
        # One lane per spot, drawn with solid lines like highway-env's parking-v0.
        lt = (LineType.CONTINUOUS, LineType.CONTINUOUS)
        for r, side, i, x, _y in parking_spots():
            yc = PARKING_ROW_CENTRES[r]
            outer = yc - PARKING_SPOT_DEPTH if side == 0 else yc + PARKING_SPOT_DEPTH
            net.add_lane(
                f"r{r}s{side}", f"{i}",
                StraightLane([x, outer], [x, yc], PARKING_SPOT_WIDTH, lt, speed_limit=5),
            )
    else:
        xmin, ymin, xmax, ymax = m.bounds
        net.add_lane("a", "b", StraightLane([xmin, ymin], [xmax, ymin], line_types=(0, 0)))
    road = SceneRoad(network=net, np_random=np_random, record_history=history)
    if scenario.lead is not None:
        # The moving lead car first (the first vehicle after the ego in every log).
        x, speed = scenario.lead
        lane_index = ("a", "b", 0)
        lane = net.get_lane(lane_index)
        pos = lane.position(lane.local_coordinates([x, 0.0])[0], 0.0)
        if scenario.lead_model == "idm":
            lead: Vehicle = OncomingCar(
                road, pos, lane.heading_at(0.0), speed, target_lane_index=lane_index,
                target_speed=speed, enable_lane_change=False,
            )
        else:
            lead = Vehicle(road, pos, lane.heading_at(0.0), speed)
        lead.LENGTH, lead.WIDTH = scenario.vehicle.length, scenario.vehicle.width
        lead.diagonal = math.hypot(lead.LENGTH, lead.WIDTH)
        road.vehicles.append(lead)
    vehicle_ids = set(scenario.vehicle_obstacles)
    net_key = _network_key(net)
    for i, o in enumerate(m.obstacles):
        if i in vehicle_ids:
            road.vehicles.append(_rect_vehicle(road, o, net_key))
        else:
            road.objects.append(_rect_object(road, o, net_key))
    for x, speed in scenario.oncoming:
        lane_index = ("b", "a", 0)
        lane = net.get_lane(lane_index)
        car = OncomingCar(
            road, lane.position(lane.local_coordinates([x, 0.0])[0], 0.0), lane.heading_at(0.0),
            speed, target_lane_index=lane_index, target_speed=speed, enable_lane_change=False,
        )
        car.LENGTH, car.WIDTH = scenario.vehicle.length, scenario.vehicle.width
        car.diagonal = math.hypot(car.LENGTH, car.WIDTH)
        road.vehicles.append(car)
    if scenario.walls:
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


def build_env(
    scenario: Scenario, sim: SimConfig | None = None, render: bool = False
) -> SceneEnv:
    """The highway-env environment of ``scenario``, reset with the scenario's simulator seed.

    Parameters
    ----------
    scenario : Scenario
        What to build.
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
    if scenario.name in ("overtake", "overtake-traffic"):
        size, scaling, centering = (900, 300), 8.0, [0.35, 0.5]
    else:
        size, scaling, centering = (640, 640), 6.0, [0.5, 0.5]
    config = {
        "scenario": scenario,
        "simulation_frequency": sim.simulation_frequency,
        "policy_frequency": sim.simulation_frequency,
        "duration": scenario.max_time_s,
        "screen_width": sim.screen_width or size[0],
        "screen_height": sim.screen_height or size[1],
        "scaling": sim.scaling or scaling,
        "centering_position": centering,
    }
    env = SceneEnv(config=config, render_mode="rgb_array" if render else None)
    _, _, sim_seed = scenario_rngs(scenario.seed)
    env.reset(seed=sim_seed)
    return env
