"""The gear-change scenarios as tasks: seeded variation, geometry, options, views (no driving)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from shapely.geometry import Polygon, box
from shapely.ops import unary_union

from rrtdrive.geometry import box_corners
from rrtdrive.maps import builtin_map
from rrtdrive.parking_layout import parking_goal_pose
from rrtdrive.sim.scenes import build_env, fit_view
from rrtdrive.sim.tasks import (
    SCENARIOS,
    CustomTask,
    ParallelParkingTask,
    ParkingTask,
    UTurnTask,
    make_scenario,
)
from rrtdrive.sim.tasks.parallel_parking import GAP_FACTORS, KERB_OFFSET
from rrtdrive.sim.tasks.u_turn import U_TURN_WIDTHS, forward_u_turn_width
from rrtdrive.types import InputError, Pose, VehicleParams
from rrtdrive.vehicle import footprint_corners

CAR = VehicleParams()


def body(pose: Pose) -> Polygon:
    return Polygon(footprint_corners((pose.x, pose.y, pose.yaw), CAR))


@pytest.mark.parametrize(
    ("name", "cls"), [("parallel-parking", ParallelParkingTask), ("u-turn", UTurnTask)]
)
def test_new_scenarios_are_tasks_planned_with_gear_changes(name, cls):
    assert name in SCENARIOS
    task = make_scenario(name, 4)
    assert type(task) is cls and task.name == name and task.reverse
    assert task == make_scenario(name, 4)  # a pure function of the seed
    assert task.describe()  # its seeded variation is reported


def test_parallel_parking_gap_is_seeded_within_range_and_the_goal_is_by_the_kerb():
    factors = set()
    for seed in range(30):
        task = make_scenario("parallel-parking", seed)
        lo, hi = GAP_FACTORS
        assert lo <= task.gap_factor <= hi
        factors.add(round(task.gap_factor, 6))
        goal = body(task.goal)
        cars = [Polygon(o.corners()) for o in task.map.obstacles]
        assert not any(goal.intersects(c) for c in cars)
        # The gap: the free length between the cars either side of the goal.
        behind = max(c.bounds[2] for c in cars if c.bounds[2] <= goal.bounds[0] + 1e-9)
        ahead = min(c.bounds[0] for c in cars if c.bounds[0] >= goal.bounds[2] - 1e-9)
        assert ahead - behind == pytest.approx(task.gap_factor * CAR.length, abs=1e-9)
        assert goal.bounds[1] == pytest.approx(KERB_OFFSET, abs=1e-9)  # 0.3 m from the kerb
        assert abs(task.goal.yaw) < 1e-12
    assert len(factors) == 30


def test_u_turn_street_is_narrower_than_a_forward_u_turn_needs():
    need = forward_u_turn_width(CAR)
    assert need == pytest.approx(14.65, abs=0.005)
    for seed in range(30):
        task = make_scenario("u-turn", seed)
        lo, hi = U_TURN_WIDTHS
        assert lo <= task.width <= hi < need
        b = task.map.bounds
        assert b[3] - b[1] == pytest.approx(task.width)
        assert abs(math.remainder(task.goal.yaw - task.start.yaw - math.pi, 2 * math.pi)) < 0.1


def test_forward_u_turn_width_is_the_swept_extent_of_a_full_lock_half_circle():
    # The body swept round the turn's centre on full lock: its extent across the street.
    r = CAR.min_turning_radius
    poses = [Pose(r * math.sin(a), r - r * math.cos(a), a) for a in np.linspace(0, math.pi, 721)]
    swept = unary_union([body(p) for p in poses])
    lo, hi = swept.bounds[1], swept.bounds[3]
    assert hi - lo == pytest.approx(forward_u_turn_width(CAR), abs=2e-3)


@given(st.integers(0, 10_000))
def test_reverse_in_goal_covers_the_nose_in_body_facing_out(seed):
    task = make_scenario("parking", seed, reverse_in=True)
    assert isinstance(task, ParkingTask) and task.reverse_in and task.reverse
    nose_in = parking_goal_pose(*task.spot, vehicle=CAR)
    a, b = body(nose_in), body(task.goal)
    assert a.symmetric_difference(b).area < 1e-9
    assert abs(math.remainder(task.goal.yaw - nose_in.yaw - math.pi, 2 * math.pi)) < 1e-12
    assert task.spot == make_scenario("parking", seed).spot  # same spot as nose-in


def test_reverse_in_option_is_refused_by_other_kinds_and_validated():
    with pytest.raises(InputError, match="reverse_in: only the parking scenario"):
        make_scenario("overtake", 0, reverse_in=True)
    assert not make_scenario("u-turn", 0, reverse_in=False).describe().get("reverse_in")
    with pytest.raises(InputError, match="reverse_in: expected True or False"):
        make_scenario("parking", 0, reverse_in="yes")
    task = make_scenario("parking", 0)
    with pytest.raises(InputError, match="reverse_in: a reverse-in bay needs reverse=True"):
        ParkingTask(map=task.map, seed=0, spot=task.spot, reverse_in=True)


def _visible(camera) -> tuple[float, float, float, float]:
    (w, h), s, (cx, cy) = camera.size, camera.scaling, camera.centre
    return cx - w / s / 2, cy - h / s / 2, cx + w / s / 2, cy + h / s / 2


@pytest.mark.parametrize(
    "task",
    [
        make_scenario("parking", 0),
        make_scenario("parallel-parking", 0),
        make_scenario("u-turn", 0),
        *(CustomTask.from_map(builtin_map(n)) for n in
          ("garage", "kerbside", "reverse_bay", "turning_bulb", "narrow_gap")),
    ],
    ids=lambda t: t.map.name,
)
def test_the_camera_fits_the_whole_map(task):
    cam = task.camera()
    vis = box(*_visible(cam))
    assert vis.contains(box(*task.map.bounds))
    # ... and the map fills the frame along one side (no small box mid-frame).
    xmin, ymin, xmax, ymax = task.map.bounds
    fill = max((xmax - xmin) / (vis.bounds[2] - vis.bounds[0]),
               (ymax - ymin) / (vis.bounds[3] - vis.bounds[1]))
    assert fill > 0.8
    assert cam.size[0] % 16 == 0 and cam.size[1] % 16 == 0
    assert task.scene_view().size == cam.size


@given(st.floats(0.5, 400.0), st.floats(0.5, 400.0), st.floats(-1e3, 1e3), st.floats(-1e3, 1e3))
def test_fit_view_contains_any_bounds(w, h, x0, y0):
    bounds = (x0, y0, x0 + w, y0 + h)
    size, scaling, centre = fit_view(bounds)
    half_w, half_h = size[0] / scaling / 2, size[1] / scaling / 2
    assert centre[0] - half_w <= x0 and centre[0] + half_w >= x0 + w
    assert centre[1] - half_h <= y0 and centre[1] + half_h >= y0 + h
    assert size[0] <= 960 and size[1] <= 640


def test_fit_view_refuses_empty_bounds():
    with pytest.raises(InputError, match="bounds"):
        fit_view((0.0, 0.0, 0.0, 5.0))


@pytest.mark.parametrize("name", ["parallel-parking", "u-turn"])
def test_scene_objects_are_the_map_rectangles_and_the_walls(name):
    task = make_scenario(name, 1)
    env = build_env(task)
    try:
        road = env.unwrapped.road
        ego = env.unwrapped.vehicle
        parked = [v for v in road.vehicles if v is not ego]
        items = parked + list(road.objects)
        assert len(items) == len(task.map.obstacles) + 4  # and the four walls
        for o in task.map.obstacles:
            want = Polygon(o.corners())
            got = [
                Polygon(box_corners(i.position[0], i.position[1], i.heading, -i.LENGTH / 2,
                                    i.LENGTH / 2, i.WIDTH / 2))
                for i in items
            ]
            assert min(want.symmetric_difference(g).area for g in got) < 1e-6
        assert not ego.crashed
    finally:
        env.close()


def test_custom_task_from_map_takes_start_goal_and_reverse():
    m = builtin_map("garage")
    t = CustomTask.from_map(m, 3, start=Pose(4.0, 13.0, 0.0), reverse=True)
    assert t.start == Pose(4.0, 13.0, 0.0) and t.goal == m.goal and t.reverse and t.seed == 3
    with pytest.raises(InputError, match="start"):
        CustomTask.from_map(m, start=Pose(-50.0, 0.0, 0.0))
    with pytest.raises(InputError, match="scenario.reverse"):
        CustomTask(map=m, seed=0, reverse="no")
