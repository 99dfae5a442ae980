"""Audit (session 50): a custom car through every part of rrtdrive.

Two non-default cars (a longer, wider car that steers less and slower, and a tiny car
that turns tightly and steers fast) go through the planner (with the Reeds-Shepp /
Hybrid A* escalation), the collision checker, the controllers, the highway-env ego,
the evaluators, the verifier, the plan JSON, the gym env and the stock-env driver.
Every property is measured here with code of our own (shapely bodies, circumscribed
circle curvature, the bicycle model written out), never read from the product.
"""

from __future__ import annotations

import dataclasses
import json
import math
import subprocess
import sys

import numpy as np
import pytest
import shapely

from rrtdrive import Budget, InputError, Map, Path, VehicleParams, builtin_map
from rrtdrive.planning import make_planner, solve_on_map

#: Longer and wider than the paper's car, wheelbase 3.2 m, 25 deg lock, r_min 8 m,
#: slower steering (0.3 rad/s).
BIG = VehicleParams(
    length=5.5, width=2.2, wheelbase=3.2, min_turning_radius=8.0,
    max_steer=math.radians(25.0), max_steer_rate=0.3,
)
#: A tiny car: 2.5 m x 1.2 m, wheelbase 1.6 m, 35 deg lock, r_min 3 m, steering 0.8 rad/s.
TINY = VehicleParams(
    length=2.5, width=1.2, wheelbase=1.6, min_turning_radius=3.0,
    max_steer=math.radians(35.0), max_steer_rate=0.8,
)
CARS = {"big": BIG, "tiny": TINY}


# ----------------------------------------------------------------------------- helpers


def _wrap(a: np.ndarray | float) -> np.ndarray:
    return (np.asarray(a) + np.pi) % (2 * np.pi) - np.pi


def _body(car: VehicleParams, x: float, y: float, yaw: float) -> shapely.Polygon:
    """The body rectangle for a rear-axle pose, written out from SPEC section 1."""
    back = (car.length - car.wheelbase) / 2.0
    front = car.length - back
    c, s = math.cos(yaw), math.sin(yaw)
    local = [(-back, -car.width / 2), (front, -car.width / 2),
             (front, car.width / 2), (-back, car.width / 2)]  # fmt: skip
    return shapely.Polygon([(x + c * a - s * b, y + s * a + c * b) for a, b in local])


def _segments(rows: np.ndarray) -> list[np.ndarray]:
    """Split path rows into gear segments (a new gear starts a new segment)."""
    cuts = np.flatnonzero(np.diff(rows[:, 4]) != 0) + 1
    return [seg for seg in np.split(rows, cuts) if len(seg)]


def _dense(seg: np.ndarray, spacing: float = 0.1) -> np.ndarray:
    """Poses at most ``spacing`` apart, linearly between rows (yaw the short way)."""
    out = [seg[:1, :3]]
    for a, b in zip(seg[:-1, :3], seg[1:, :3], strict=True):
        n = max(1, math.ceil(math.hypot(*(b[:2] - a[:2])) / spacing))
        f = np.arange(1, n + 1)[:, None] / n
        d = np.array([b[0] - a[0], b[1] - a[1], float(_wrap(b[2] - a[2]))])
        out.append(a + f * d)
    return np.vstack(out)


def _collisions(m: Map, car: VehicleParams, poses: np.ndarray) -> int:
    """Poses whose body touches an obstacle or leaves the bounds (shapely)."""
    obstacles = shapely.union_all([shapely.Polygon(o.corners()) for o in m.obstacles])
    region = shapely.box(*m.bounds)
    return sum(
        1 for x, y, yaw in poses
        if obstacles.intersects(b := _body(car, x, y, yaw)) or not region.contains(b)
    )


def _max_circle_curvature(seg: np.ndarray) -> float:
    """Largest curvature of circles through three consecutive distinct positions."""
    xy = seg[:, :2]
    keep = np.concatenate([[True], np.hypot(*np.diff(xy, axis=0).T) > 1e-9])
    xy = xy[keep]
    if len(xy) < 3:
        return 0.0
    p, q, r = xy[:-2], xy[1:-1], xy[2:]
    a, b, c = (np.hypot(*(q - p).T), np.hypot(*(r - q).T), np.hypot(*(r - p).T))
    cross = (q - p)[:, 0] * (r - p)[:, 1] - (q - p)[:, 1] * (r - p)[:, 0]
    return float(np.max(2.0 * np.abs(cross) / (a * b * c)))


def _max_sharpness(seg: np.ndarray, wheelbase: float) -> float:
    """Largest |d delta / ds| with delta = atan(L kappa), from the kappa column."""
    ds = np.hypot(*np.diff(seg[:, :2], axis=0).T)
    dd = np.abs(np.diff(np.arctan(wheelbase * seg[:, 3])))
    ok = ds > 1e-9
    return float(np.max(dd[ok] / ds[ok])) if ok.any() else 0.0


def _car_map(name: str, car: VehicleParams) -> Map:
    return dataclasses.replace(builtin_map(name), vehicle=car)


def _plan(m: Map, planner: str = "improved-rrt-connect", reverse: bool = False, **budget):
    _, result = solve_on_map(
        lambda: make_planner(planner), m, np.random.default_rng(0), Budget(**budget),
        reverse=reverse,
    )
    return result


def _assert_path_is_for(m: Map, car: VehicleParams, rows: np.ndarray) -> None:
    """The path's curvature, sharpness and footprint are those of ``car`` on ``m``."""
    rate = car.max_steer_rate
    sharp_bound = min(0.2, rate / 2.0) if rate is not None else 0.2
    for seg in _segments(rows):
        assert _max_circle_curvature(seg) <= car.kappa_max + 2e-3
        assert _max_sharpness(seg, car.wheelbase) <= sharp_bound + 5e-3
        assert _collisions(m, car, _dense(seg)) == 0


# ----------------------------------------------------------------------------- validation


@pytest.mark.parametrize(
    ("fields", "named"),
    [
        ({"length": -4.3}, "vehicle.length"),
        ({"length": 0.0}, "vehicle.length"),
        ({"width": float("nan")}, "vehicle.width"),
        ({"wheelbase": float("inf")}, "vehicle.wheelbase"),
        ({"wheelbase": 0}, "vehicle.wheelbase"),
        ({"min_turning_radius": -6.0}, "vehicle.min_turning_radius"),
        ({"min_turning_radius": 1.0}, "vehicle.min_turning_radius"),  # lock cannot reach it
        ({"max_steer": 2.0}, "vehicle.max_steer"),  # beyond pi/2
        ({"max_steer": -0.5}, "vehicle.max_steer"),
        ({"max_steer": float("nan")}, "vehicle.max_steer"),
        ({"max_steer_rate": 0.0}, "vehicle.max_steer_rate"),
        ({"max_steer_rate": -0.4}, "vehicle.max_steer_rate"),
        ({"max_steer_rate": float("nan")}, "vehicle.max_steer_rate"),
        ({"max_steer_rate": "fast"}, "vehicle.max_steer_rate"),
        ({"length": "4.3"}, "vehicle.length"),
        ({"width": True}, "vehicle.width"),
        ({"wheelbase": 4.3}, "vehicle.wheelbase"),  # not shorter than the body
    ],
)
def test_impossible_vehicle_is_one_input_error_naming_the_field(fields, named):
    with pytest.raises(InputError) as info:
        VehicleParams(**fields)
    text = str(info.value)
    assert text.startswith(named + ":"), text
    assert "\n" not in text


def test_the_car_decides_whether_the_map_query_is_valid():
    # The paper's car parks at parking_lot's goal; BIG's body there hits a parked car.
    assert builtin_map("parking_lot").vehicle == VehicleParams()
    with pytest.raises(InputError, match=r"^goal: the car's body"):
        _car_map("parking_lot", BIG)
    assert _car_map("parking_lot", TINY).vehicle == TINY


def test_cli_map_file_with_a_vehicle_plans_for_that_car(tmp_path):
    """A map file's "vehicle" (once refused as an unknown key) is the car plan uses."""
    doc = builtin_map("overtake").to_json()
    doc["vehicle"] = dataclasses.asdict(BIG)
    f = tmp_path / "car.json"
    f.write_text(json.dumps(doc))
    run = subprocess.run(
        [sys.executable, "-m", "rrtdrive", "plan", str(f), "--json", "-"],
        capture_output=True, text=True, timeout=120,
    )
    assert run.returncode == 0, run.stderr
    plan = json.loads(run.stdout)
    assert VehicleParams(**plan["vehicle"]) == BIG
    _assert_path_is_for(builtin_map("overtake"), BIG, np.asarray(plan["path"]))


# ----------------------------------------------------------------------------- collision


@pytest.mark.parametrize("name", ["big", "tiny", "long", "wide"])
def test_checker_agrees_with_an_independent_shapely_body(name):
    car = {
        **CARS,
        "long": VehicleParams(length=9.0, width=2.4, wheelbase=5.5, min_turning_radius=12.0),
        "wide": VehicleParams(length=3.0, width=3.4, wheelbase=2.0, min_turning_radius=6.0),
    }[name]
    from rrtdrive.planning.base import cached_checker

    m = dataclasses.replace(builtin_map("parking_lot"), vehicle=car, check_query=False)
    checker = cached_checker(m)
    rng = np.random.default_rng(7)
    poses = np.column_stack(
        [rng.uniform(0, 100, 800), rng.uniform(0, 100, 800), rng.uniform(-np.pi, np.pi, 800)]
    )
    obstacles = shapely.union_all([shapely.Polygon(o.corners()) for o in m.obstacles])
    region = shapely.box(*m.bounds)
    truth = np.array([
        region.contains(b := _body(car, *p)) and not obstacles.intersects(b) for p in poses
    ])
    assert 0.2 < truth.mean() < 0.8  # both kinds of pose are tested
    np.testing.assert_array_equal(checker.poses_free(poses), truth)
    # The fast screens may refuse a free pose, never clear a colliding one.
    assert not np.any(checker.poses_free_fast(poses) & ~truth)
    assert not any(checker.pose_free_fast(*p) and not t for p, t in zip(poses, truth, strict=True))


# ----------------------------------------------------------------------------- planner


@pytest.mark.parametrize(
    ("map_name", "car_name"),
    [("overtake", "big"), ("overtake", "tiny"), ("narrow_gap", "big"),
     ("narrow_gap", "tiny"), ("parking_lot", "tiny")],
)
def test_forward_plan_is_for_that_car(map_name, car_name):
    car = CARS[car_name]
    m = _car_map(map_name, car)
    result = _plan(m)
    assert result.success, result.message
    _assert_path_is_for(m, car, result.path.samples)


def test_tiny_car_uses_its_tighter_turns():
    # Not just "within some limit": the tiny car's path turns tighter than the paper's
    # car may, so the tiny car's own limit was the one applied.
    m = _car_map("parking_lot", TINY)
    result = _plan(m)
    assert result.success
    assert max(_max_circle_curvature(s) for s in _segments(result.path.samples)) > 1 / 6.0


@pytest.mark.parametrize(
    ("map_name", "car_name"),
    [("reverse_bay", "big"), ("reverse_bay", "tiny"), ("dead_end", "tiny"),
     ("turning_bulb", "big")],
)
def test_reverse_escalation_is_for_that_car(map_name, car_name):
    car = CARS[car_name]
    m = _car_map(map_name, car)
    result = _plan(m, reverse=True)
    assert result.success, result.message
    rows = result.path.samples
    assert np.any(rows[:, 4] < 0)  # a gear change was needed and made
    _assert_path_is_for(m, car, rows)
    hybrid = _plan(m, planner="hybrid-a-star", reverse=True)
    assert hybrid.success, hybrid.message
    _assert_path_is_for(m, car, hybrid.path.samples)


def test_car_wider_than_the_gap_fails_honestly_and_says_why():
    fat = VehicleParams(length=5.0, width=3.0, wheelbase=3.0, min_turning_radius=6.0)
    m = _car_map("narrow_gap", fat)  # the passage is 2.8 m wide
    result = _plan(m, max_iterations=2000)
    assert not result.success
    assert result.diagnosis is not None
    assert "3.00 m" in result.diagnosis.message  # the car's width, not the paper's 1.80


# ----------------------------------------------------------------------------- verify, JSON


def test_verify_path_judges_with_the_maps_car():
    from rrtdrive.verify import verify_path

    m = _car_map("parking_lot", TINY)
    result = _plan(m)
    assert verify_path(m, result.path).ok
    # The same path for the paper's car turns too tightly for it.
    default = verify_path(builtin_map("parking_lot"), result.path)
    assert not default.curvature_ok
    # A path for the paper's car through narrow_gap hits the walls with a 3 m wide car.
    plain = _plan(builtin_map("narrow_gap"))
    fat = VehicleParams(length=5.0, width=3.0, wheelbase=3.0, min_turning_radius=6.0)
    fat_map = dataclasses.replace(builtin_map("narrow_gap"), vehicle=fat, check_query=False)
    check = verify_path(fat_map, plain.path)
    assert not check.collision_free
    assert _collisions(fat_map, fat, _dense(plain.path.samples[:, :3].copy())) > 0


def _tiny_plan_json() -> dict:
    from rrtdrive.cli import plan_to_json

    m = _car_map("parking_lot", TINY)
    result = _plan(m)
    assert result.success
    return plan_to_json(result, 0, m.name, TINY, start=m.start, goal=m.goal)


def test_plan_json_records_its_car():
    doc = _tiny_plan_json()
    record = doc.get("vehicle", doc.get("car"))
    assert isinstance(record, dict)
    assert record["wheelbase"] == pytest.approx(TINY.wheelbase)
    assert record["width"] == pytest.approx(TINY.width)
    assert record["min_turning_radius"] == pytest.approx(TINY.min_turning_radius)


def test_cli_verify_accepts_a_valid_plan_for_a_custom_car(tmp_path):
    doc = _tiny_plan_json()
    # The plan is valid for the tiny car (checked independently).
    _assert_path_is_for(_car_map("parking_lot", TINY), TINY, np.asarray(doc["path"]))
    f = tmp_path / "tiny_plan.json"
    f.write_text(json.dumps(doc))
    run = subprocess.run(
        [sys.executable, "-m", "rrtdrive", "verify", str(f)],
        capture_output=True, text=True, timeout=120,
    )
    assert run.returncode == 0, run.stdout + run.stderr


# ----------------------------------------------------------------------------- controllers


def _arc_path(radius: float, length: float = 40.0) -> Path:
    s = np.arange(0.0, length + 1e-9, 0.25)
    th = s / radius
    rows = np.column_stack([
        radius * np.sin(th), radius * (1 - np.cos(th)), th,
        np.full_like(s, 1 / radius), np.ones_like(s),
    ])
    return Path(rows, rows[[0, -1], :2])


@pytest.mark.parametrize("controller", ["pure-pursuit", "stanley", "lqr"])
@pytest.mark.parametrize("car_name", ["big", "tiny"])
def test_controllers_steer_with_that_cars_wheelbase_and_limit(controller, car_name):
    from rrtdrive.controllers import make_controller
    from rrtdrive.controllers.state import VehicleState

    car = CARS[car_name]
    radius = 1.5 * car.min_turning_radius
    steady = math.atan(car.wheelbase / radius)  # the bicycle's steering on this circle
    ctrl = make_controller(controller, vehicle=car)
    ctrl.reset(_arc_path(radius), 2.0)
    th = 10.0 / radius
    on_path = VehicleState(radius * math.sin(th), radius * (1 - math.cos(th)), th, 2.0, steady, 1.0)
    _, steer = ctrl.control(on_path)
    assert steer == pytest.approx(steady, abs=0.01)
    assert abs(steer - math.atan(2.51 / radius)) > 0.03  # not the paper's wheelbase
    # Far off the path, the command stays within the car's curvature steering limit.
    far = make_controller(controller, vehicle=car)
    far.reset(_arc_path(radius), 2.0)
    lock = math.atan(car.wheelbase / car.min_turning_radius)
    prev = 0.0
    for k in range(30):
        y = radius * (1 - math.cos(th)) - 3.0
        _, prev = far.control(VehicleState(on_path.x, y, th, 2.0, prev, 1.0 + 0.05 * k))
        assert abs(prev) <= lock + 1e-9
        assert abs(prev) <= car.max_steer


# ----------------------------------------------------------------------------- highway-env ego


@pytest.mark.parametrize("car_name", ["big", "tiny"])
def test_highway_env_ego_has_that_cars_body_and_bicycle(car_name):
    from rrtdrive.sim.scenes import build_env
    from rrtdrive.sim.tasks import make_scenario

    car = CARS[car_name]
    instant = dataclasses.replace(car, max_steer_rate=None)
    env = build_env(make_scenario("overtake", 0, vehicle=instant))
    try:
        ego = env.unwrapped.vehicle
        assert ego.params == instant
        assert (ego.LENGTH, ego.WIDTH) == (car.length, car.width)
        x, y, yaw = ego.rear
        expected = _body(car, x, y, yaw)
        drawn = shapely.Polygon(np.asarray(ego.polygon())[:4])
        assert drawn.symmetric_difference(expected).area < 1e-9
        # One step at constant speed and steering: the rear axle turns by v dt tan(d) / L.
        dt = 0.05
        ego.speed = 2.0
        for command, applied in ((0.2, 0.2), (1.4, car.max_steer)):
            yaw0 = ego.rear[2]
            ego.act({"acceleration": 0.0, "steering": command})
            ego.step(dt)
            assert ego.steer == pytest.approx(applied)
            turn = float(_wrap(ego.rear[2] - yaw0))
            assert turn == pytest.approx(2.0 * dt * math.tan(applied) / car.wheelbase, rel=1e-6)
    finally:
        env.close()


@pytest.mark.parametrize("car_name", ["big", "tiny"])
def test_highway_env_ego_slews_at_that_cars_steering_rate(car_name):
    from rrtdrive.sim.scenes import build_env
    from rrtdrive.sim.tasks import make_scenario

    car = CARS[car_name]
    env = build_env(make_scenario("overtake", 0, vehicle=car))
    try:
        ego = env.unwrapped.vehicle
        ego.speed = 2.0
        for k in range(1, 4):
            ego.act({"acceleration": 0.0, "steering": car.max_steer})
            ego.step(0.05)
            assert ego.steer == pytest.approx(min(k * 0.05 * car.max_steer_rate, car.max_steer))
    finally:
        env.close()


# ----------------------------------------------------------------------------- closed loop


def _episode(scenario: str, car: VehicleParams, controller: str = "pure-pursuit"):
    from rrtdrive.sim.runner import run_episode
    from rrtdrive.sim.tasks import make_scenario

    return run_episode(make_scenario(scenario, 0, vehicle=car), controller=controller, seed=0)


@pytest.mark.parametrize(
    ("scenario", "car_name", "controller"),
    [("u-turn", "tiny", "pure-pursuit"), ("u-turn", "big", "lqr"),
     ("parallel-parking", "tiny", "stanley")],
)
def test_closed_loop_honours_that_car(scenario, car_name, controller):
    from rrtdrive.evaluation import evaluate

    car = CARS[car_name]
    ep = _episode(scenario, car, controller)
    report = evaluate(ep)
    assert report.success, ep.message
    assert ep.scenario.vehicle == car
    steer = ep.log.controls[:, 1]
    assert np.all(np.abs(steer) <= car.max_steer + 1e-9)
    rates = np.abs(np.diff(np.concatenate([[0.0], steer]))) / ep.log.dt
    assert rates.max() <= car.max_steer_rate + 1e-6
    # The evaluators use the car's wheelbase and curvature limit.
    assert report.kappa_max == pytest.approx(1.0 / car.min_turning_radius)
    executed = np.abs(np.tan(steer)) / car.wheelbase
    assert report.executed_max_curvature == pytest.approx(executed.max())
    assert report.executed_curvature_violation_share == pytest.approx(
        float(np.mean(executed > car.kappa_max * (1 + 1e-9)))
    )
    # The driven body never touches the map (independent shapely judge), as reported.
    assert _collisions(ep.scenario.map, car, _dense(ep.log.states, 0.1)) == 0
    assert not report.collision
    # The planned path tracked is the car's.
    _assert_path_is_for(ep.scenario.map, car, ep.path.samples)


def test_steering_rate_share_is_against_the_judge_and_a_cars_own_limit_can_be_asked():
    """The share judges against CommonRoad's 0.4 rad/s actuator by default (docs/metrics.md:
    a 0.8 rad/s car is flagged where it turns faster than that); EvalConfig's
    steer_rate_limit set to the car's own rate finds no step over it."""
    from rrtdrive.evaluation import EvalConfig, evaluate

    ep = _episode("u-turn", TINY)
    steer = ep.log.controls[:, 1]
    rates = np.abs(np.diff(np.concatenate([[0.0], steer]))) / ep.log.dt
    assert rates.max() <= TINY.max_steer_rate + 1e-6  # the car kept to its actuator
    assert rates.max() > 0.4 + 1e-6  # and used more than the paper's car may
    judged = evaluate(ep).steering_rate_over_limit_share
    assert judged == pytest.approx(float(np.mean(rates > 0.4 + 1e-9))) and judged > 0
    own = EvalConfig(steer_rate_limit=TINY.max_steer_rate)
    assert evaluate(ep, own).steering_rate_over_limit_share == 0.0


# ----------------------------------------------------------------------------- gym env


def test_gym_env_scenario_options_vehicle_reaches_ego_controller_and_action():
    import gymnasium as gym

    import rrtdrive  # noqa: F401  (registers the ids)

    env = gym.make("rrtdrive/Overtake-v0", scenario_options={"vehicle": BIG})
    try:
        env.reset(seed=0)
        u = env.unwrapped
        assert u._ego.params == BIG
        assert (u._ego.LENGTH, u._ego.WIDTH) == (BIG.length, BIG.width)
        assert u._ctrl.vehicle == BIG
        lock = math.atan(BIG.wheelbase / BIG.min_turning_radius)
        assert u.config.limits.steer_limit == pytest.approx(lock)
        assert env.observation_space.high[1] == pytest.approx(BIG.max_steer, rel=1e-6)
        for _ in range(5):
            env.step(np.array([0.0, 1.0], dtype=np.float32))
        # Full right lock of the action, rate-limited by BIG's 0.3 rad/s actuator.
        assert 0.0 < u._ego.steer <= min(lock, 0.3 * 0.05 * 5 * 4) + 1e-9
    finally:
        env.close()


def test_gym_map_env_takes_the_maps_car():
    import gymnasium as gym
    from gymnasium.envs.registration import EnvSpec

    import rrtdrive  # noqa: F401

    env = gym.make("rrtdrive/Map-v0", scenario=_car_map("narrow_gap", TINY))
    try:
        env.reset(seed=0)
        assert env.unwrapped._ego.params == TINY
        again = gym.make(EnvSpec.from_json(env.spec.to_json()))
        again.reset(seed=0)
        assert again.unwrapped._ego.params == TINY
        again.close()
    finally:
        env.close()


def test_gym_spec_round_trip_keeps_a_scenario_options_vehicle():
    import gymnasium as gym
    from gymnasium.envs.registration import EnvSpec

    import rrtdrive  # noqa: F401

    env = gym.make("rrtdrive/Overtake-v0", scenario_options={"vehicle": TINY})
    env.close()
    again = gym.make(EnvSpec.from_json(env.spec.to_json()))
    try:
        again.reset(seed=0)
        assert again.unwrapped._ego.params == TINY
    finally:
        again.close()


# ----------------------------------------------------------------------------- stock env


def test_stock_driver_rejects_a_vehicle_that_is_not_a_vehicle():
    from rrtdrive.sim.runner import EpisodeConfig
    from rrtdrive.sim.stock import drive_stock_env

    with pytest.raises(InputError, match="vehicle"):
        drive_stock_env(
            "parking-v0", seed=3, vehicle=dataclasses.asdict(BIG),  # type: ignore[arg-type]
            config=EpisodeConfig(max_time_s=1.0),
        )


def test_stock_driver_drives_that_car():
    from rrtdrive.sim.runner import EpisodeConfig
    from rrtdrive.sim.stock import drive_stock_env

    run = drive_stock_env("parking-v0", seed=3, vehicle=TINY, config=EpisodeConfig(max_time_s=3.0))
    ep = run.episode
    assert ep.scenario.vehicle == TINY
    assert np.all(np.abs(ep.log.controls[:, 1]) <= TINY.max_steer + 1e-9)
    _assert_path_is_for(ep.scenario.map, TINY, ep.path.samples)
