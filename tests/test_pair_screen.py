"""The scenes' pair screen never drops a pair highway-env's own collision test acts on."""

from __future__ import annotations

import math

import numpy as np
from highway_env.road.road import Road, RoadNetwork
from highway_env.vehicle.kinematics import Vehicle
from highway_env.vehicle.objects import Obstacle
from hypothesis import given, settings
from hypothesis import strategies as st

from rrtdrive.sim.ego import EgoVehicle
from rrtdrive.sim.pair_screen import object_boxes, pairs_to_handle
from rrtdrive.types import Pose

ROAD = Road(RoadNetwork.straight_road_network(2))  # vehicles look up their lane
DT = 0.05

box = st.tuples(
    st.floats(0.0, 12.0), st.floats(0.0, 12.0), st.floats(-math.pi, math.pi),  # x, y, heading
    st.floats(0.3, 30.0), st.floats(0.3, 5.0),  # length, width
    st.floats(-8.0, 25.0),  # speed (the ego reverses)
)


def _vehicle(x: float, y: float, h: float, length: float, width: float, v: float,
             ego: bool) -> Vehicle:
    if ego:
        car = EgoVehicle(ROAD, Pose(x, y, h), max(v, -10.0))
    else:
        car = Vehicle(ROAD, np.array([x, y]), h, v)
        car.LENGTH, car.WIDTH = length, width
        car.diagonal = math.hypot(length, width)
    return car


def _obstacle(x: float, y: float, h: float, length: float, width: float) -> Obstacle:
    o = Obstacle(ROAD, np.array([x, y]), h)
    o.LENGTH, o.WIDTH = length, width
    o.diagonal = math.hypot(length, width)
    return o


@settings(max_examples=5 * settings.default.max_examples, deadline=None)
@given(st.lists(box, min_size=1, max_size=4), st.lists(box, max_size=4), st.booleans())
def test_every_pair_highway_env_acts_on_is_kept(cars, things, ego_first) -> None:
    vehicles = [_vehicle(*c, ego=ego_first and i == 0) for i, c in enumerate(cars)]
    objects = [_obstacle(*t[:5]) for t in things]
    kept = pairs_to_handle(vehicles, objects, DT, [isinstance(v, EgoVehicle) for v in vehicles])
    order = [(v, o) for i, v in enumerate(vehicles) for o in [*vehicles[i + 1 :], *objects]]
    # Road.step's order, a subsequence of it.
    positions = [order.index(p) for p in kept]
    assert positions == sorted(positions)
    for v, o in order:
        intersecting, will_intersect, _ = v._is_colliding(o, DT)
        if intersecting or will_intersect:
            assert (v, o) in kept


def test_the_screen_drops_pairs_the_circles_keep() -> None:
    # A car beside a long wall, 1 m clear of it: inside the pre-check's circles (the
    # wall's diagonal), apart for the separating-axis test: dropped. Touching: kept.
    car = _vehicle(10.0, 3.0, 0.0, 4.5, 1.8, 5.0, ego=False)
    wall = _obstacle(10.0, 0.0, 0.0, 40.0, 2.2)  # its top edge at y = 1.1; the car's bottom 2.1
    assert not car._is_colliding(wall, DT)[0] and not car._is_colliding(wall, DT)[1]
    assert np.hypot(*(wall.position - car.position)) < (car.diagonal + wall.diagonal) / 2
    assert pairs_to_handle([car], [wall], DT, [False]) == []
    touching = _obstacle(10.0, 1.1, 0.0, 40.0, 2.2)  # top edge at y = 2.2: overlaps
    assert car._is_colliding(touching, DT)[0]
    assert pairs_to_handle([car], [touching], DT, [False]) == [(car, touching)]


@given(st.lists(box, min_size=1, max_size=4), st.lists(box, min_size=1, max_size=6), st.booleans())
def test_kept_object_boxes_give_the_same_pairs(cars, things, ego_first) -> None:
    # The scenes keep their objects' boxes between steps: the same pairs come out.
    vehicles = [_vehicle(*c, ego=ego_first and i == 0) for i, c in enumerate(cars)]
    objects = [_obstacle(*t[:5]) for t in things]
    both_ways = [isinstance(v, EgoVehicle) for v in vehicles]
    fresh = pairs_to_handle(vehicles, objects, DT, both_ways)
    assert pairs_to_handle(vehicles, objects, DT, both_ways, object_boxes(objects)) == fresh


def test_a_scene_road_screens_an_object_added_mid_episode() -> None:
    from rrtdrive.sim.scenes import SceneRoad

    road = SceneRoad(RoadNetwork.straight_road_network(2))
    car = Vehicle(road, np.array([10.0, 0.0]), 0.0, 5.0)
    road.vehicles.append(car)
    road.objects.append(Obstacle(road, np.array([60.0, 0.0])))
    road.step(DT)
    assert not car.crashed
    # An obstacle dropped onto the car after a step (the kept boxes were the old list's).
    road.objects.append(Obstacle(road, car.position.copy()))
    road.step(DT)
    assert car.crashed
