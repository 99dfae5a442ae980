"""Maps from any highway-env scene, and our ego car dropped into a stock environment.

:func:`map_from_env` turns a highway-env scene into a :class:`~rrtdrive.maps.Map`:
every solid road object (``Obstacle``; ``Landmark`` is not solid and is skipped),
every vehicle other than the ego, and - optionally - every solid lane line
(``CONTINUOUS`` / ``CONTINUOUS_LINE``) as a thin rectangle. The start is the
ego's pose, the goal its ``goal`` landmark (as in ``parking-v0``) unless given.
:func:`attach_ego` replaces the controlled vehicle by an
:class:`~rrtdrive.sim.ego.EgoVehicle` at the same pose, so the closed loop of
:func:`rrtdrive.sim.runner.drive` runs in stock ``parking-v0`` as well.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from highway_env.road.lane import LineType, StraightLane
from highway_env.vehicle.objects import Landmark

from rrtdrive.maps import Map, Obstacle
from rrtdrive.sim.ego import EgoVehicle, centre_to_rear_axle
from rrtdrive.types import InputError, Pose, VehicleParams, require_positive
from rrtdrive.vehicle import footprint_corners

__all__ = ["map_from_env", "attach_ego", "lane_line_obstacles"]

_SOLID_LINES = (LineType.CONTINUOUS, LineType.CONTINUOUS_LINE)


def lane_line_obstacles(
    road: Any, thickness: float = 0.1, piece: float = 2.0
) -> list[Obstacle]:
    """Thin rectangles along every solid lane line of ``road``'s network (duplicates merged).

    Straight lanes give one rectangle per line; curved lanes are cut into pieces of
    about ``piece`` metres.
    """
    require_positive("thickness", thickness)
    out: dict[tuple[float, ...], Obstacle] = {}
    for lane in road.network.lanes_list():
        for side, kind in enumerate(lane.line_types):
            if kind not in _SOLID_LINES:
                continue
            lat = (-1.0 if side == 0 else 1.0) * lane.width_at(0.0) / 2.0
            if isinstance(lane, StraightLane):
                cuts = [0.0, float(lane.length)]
            else:
                n = max(1, int(math.ceil(lane.length / piece)))
                cuts = list(np.linspace(0.0, float(lane.length), n + 1))
            for s0, s1 in zip(cuts[:-1], cuts[1:], strict=True):
                a = np.asarray(lane.position(s0, lat), dtype=float)
                b = np.asarray(lane.position(s1, lat), dtype=float)
                length = float(np.hypot(*(b - a)))
                if length < 1e-6:
                    continue
                centre = (a + b) / 2.0
                yaw = math.atan2(b[1] - a[1], b[0] - a[0]) % math.pi  # undirected
                key = (round(centre[0], 3), round(centre[1], 3), round(length, 3), round(yaw, 4))
                out.setdefault(key, Obstacle(tuple(centre), (length, thickness), yaw))
    return list(out.values())


def _ego_pose(vehicle_obj: Any, params: VehicleParams) -> Pose:
    if isinstance(vehicle_obj, EgoVehicle):
        return vehicle_obj.pose
    return centre_to_rear_axle(
        float(vehicle_obj.position[0]), float(vehicle_obj.position[1]),
        float(vehicle_obj.heading), params,
    )


def map_from_env(
    env: Any,
    *,
    goal: Pose | None = None,
    vehicle: VehicleParams | None = None,
    lane_lines: bool = True,
    line_thickness: float = 0.1,
    pad: float = 1.0,
    name: str | None = None,
) -> Map:
    """Extract a planning map from a highway-env scene.

    Parameters
    ----------
    env : gymnasium.Env
        A reset highway-env environment (wrapped or not).
    goal : Pose, optional
        Rear-axle goal; by default the ego's ``goal`` landmark (its centre and
        heading, converted to the rear axle).
    vehicle : VehicleParams, optional
        Our car (the ego's pose is converted to its rear axle).
    lane_lines : bool
        Turn solid lane lines into thin obstacles (road edges, parking-spot lines).
    line_thickness : float
        Thickness of those rectangles in metres.
    pad : float
        Margin of the bounds around everything in the scene, in metres.
    name : str, optional
        Map name (default: the environment's spec id or class name).

    Returns
    -------
    Map
        Bounds, obstacles, and the ego's start and goal.

    Raises
    ------
    InputError
        When there is no ego, no goal, or the start or goal collides.

    Examples
    --------
    >>> import gymnasium as gym, highway_env  # doctest: +SKIP
    >>> env = gym.make("parking-v0"); env.reset(seed=0)  # doctest: +SKIP
    >>> m = map_from_env(env)  # doctest: +SKIP
    """
    u = env.unwrapped
    road = getattr(u, "road", None)
    if road is None:
        raise InputError("env: not a reset highway-env environment (no road)")
    params = vehicle or VehicleParams()
    ego = getattr(u, "vehicle", None)
    if ego is None:
        raise InputError("env: the scene has no controlled vehicle")
    obstacles: list[Obstacle] = []
    controlled = {id(v) for v in getattr(u, "controlled_vehicles", [ego])}
    for obj in list(road.objects) + [v for v in road.vehicles if id(v) not in controlled]:
        if isinstance(obj, Landmark) or not getattr(obj, "solid", True):
            continue
        if not getattr(obj, "collidable", True):
            continue
        obstacles.append(
            Obstacle(
                (float(obj.position[0]), float(obj.position[1])),
                (float(obj.LENGTH), float(obj.WIDTH)),
                float(obj.heading),
            )
        )
    if lane_lines:
        obstacles += lane_line_obstacles(road, line_thickness)
    start = _ego_pose(ego, params)
    if goal is None:
        landmark = getattr(ego, "goal", None)
        if landmark is None:
            raise InputError("goal: the scene's ego has no goal landmark; pass goal=")
        goal = centre_to_rear_axle(
            float(landmark.position[0]), float(landmark.position[1]),
            float(landmark.heading), params,
        )
    pts = [o.corners() for o in obstacles]
    for lane in road.network.lanes_list():
        w = lane.width_at(0.0) / 2.0
        pts.append(np.array([lane.position(0.0, -w), lane.position(0.0, w),
                             lane.position(lane.length, -w), lane.position(lane.length, w)]))
    for p in (start, goal):
        # The whole car, not its rear axle: a goal given beyond the scene's edge was
        # refused as "leaves the bounds" by its nose unless pad was raised (an audit).
        pts.append(footprint_corners(np.array(p.as_tuple()), params))
    allp = np.vstack(pts)
    lo = allp.min(axis=0) - pad
    hi = allp.max(axis=0) + pad
    label = name or (getattr(getattr(env, "spec", None), "id", None) or type(u).__name__)
    return Map(
        str(label), (float(lo[0]), float(lo[1]), float(hi[0]), float(hi[1])),
        tuple(obstacles), start, goal, params,
    )


def attach_ego(
    env: Any, vehicle: VehicleParams | None = None, speed: float | None = None
) -> EgoVehicle:
    """Replace the controlled vehicle of a highway-env scene by our :class:`EgoVehicle`.

    The new car keeps the old one's body-centre position and heading (so its rear
    axle is converted with our dimensions), its speed, colour and ``goal``.

    Parameters
    ----------
    env : gymnasium.Env
        A reset highway-env environment.
    vehicle : VehicleParams, optional
        Our car.
    speed : float, optional
        Initial speed (default: the old vehicle's).

    Returns
    -------
    EgoVehicle
        Now ``env.unwrapped.vehicle`` and in ``road.vehicles``.
    """
    u = env.unwrapped
    old = u.vehicle
    if old is None:
        raise InputError("env: the scene has no controlled vehicle")
    if isinstance(old, EgoVehicle):
        return old
    params = vehicle or VehicleParams()
    pose = _ego_pose(old, params)
    ego = EgoVehicle(u.road, pose, float(old.speed if speed is None else speed), params)
    for attr in ("color", "goal"):
        if hasattr(old, attr):
            setattr(ego, attr, getattr(old, attr))
    vehicles = u.road.vehicles
    vehicles[vehicles.index(old)] = ego
    u.controlled_vehicles = [ego if v is old else v for v in u.controlled_vehicles]
    # Keep highway-env's action and observation types pointing at the new car.
    u.define_spaces()
    return ego
