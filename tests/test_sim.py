"""Scenes, map extraction, the closed-loop runner and the simulate command, in real highway-env."""

from __future__ import annotations

import argparse
import dataclasses
import json
import math

import gymnasium as gym
import highway_env  # noqa: F401 - registers the stock environments
import numpy as np
import pytest
import shapely
from highway_env.road.road import Road
from highway_env.vehicle.kinematics import Vehicle
from highway_env.vehicle.objects import Landmark
from highway_env.vehicle.objects import Obstacle as HwObstacle

from rrtdrive.evaluation import evaluate
from rrtdrive.parking_layout import PARKING_EMPTY_SPOTS, parking_goal_pose
from rrtdrive.planning import PLANNERS, PlanningProblem, make_planner
from rrtdrive.sim import cli_simulate
from rrtdrive.sim.ego import EgoVehicle
from rrtdrive.sim.extract import attach_ego, map_from_env
from rrtdrive.sim.replanning import ReplanConfig
from rrtdrive.sim.runner import EpisodeConfig, drive, run_episode
from rrtdrive.sim.scenes import SceneRoad, SimConfig, build_env
from rrtdrive.sim.tasks import make_scenario
from rrtdrive.types import Budget, InputError, Path

IMPROVED = "improved-rrt-connect"
needs_improved = pytest.mark.skipif(IMPROVED not in PLANNERS, reason="planner not registered")


def lane_change_path(start, lane_y: float, dy: float = 4.0, step: float = 0.1) -> Path:
    """Out to the other lane over 15..40 m, back over 60..85 m (cosine ramps), to x = 92."""
    x = np.arange(start[0], 92.0 + 1e-9, step)

    def ramp(u):
        u = np.clip(u, 0.0, 1.0)
        return (1 - np.cos(math.pi * u)) / 2

    y = lane_y + dy * (ramp((x - 15) / 25) - ramp((x - 60) / 25))
    dy_dx = np.gradient(y, x)
    d2 = np.gradient(dy_dx, x)
    yaw = np.arctan(dy_dx)
    kappa = d2 / (1 + dy_dx**2) ** 1.5
    return Path(np.column_stack([x, y, yaw, kappa]), np.column_stack([x, y])[::50])


def _poly(obj) -> shapely.Polygon:
    return shapely.Polygon(obj.polygon()[:4])


# ----------------------------------------------------------------------------- scenes


def test_parking_scene_is_exactly_the_map():
    scen = make_scenario("parking", 5)
    env = build_env(scen)
    u = env.unwrapped
    objects = [o for o in u.road.objects if isinstance(o, HwObstacle)]
    m = scen.map
    # Every map rectangle is one solid highway-env obstacle with the same polygon; plus 4 walls.
    assert len(objects) == len(m.obstacles) + 4
    for o, ob in zip(m.obstacles, objects[: len(m.obstacles)], strict=True):
        assert ob.solid and ob.collidable
        assert _poly(ob).symmetric_difference(o.polygon()).area < 1e-9
    # The walls close the bounds: their union surrounds the map, touching it.
    walls = shapely.union_all([_poly(w) for w in objects[len(m.obstacles) :]])
    box = shapely.box(*m.bounds)
    assert walls.intersection(box).area < 1e-9
    assert walls.buffer(1e-6).contains(box.exterior)
    ego = u.vehicle
    assert isinstance(ego, EgoVehicle) and ego.pose == scen.start
    assert scen.spot in PARKING_EMPTY_SPOTS and scen.goal == parking_goal_pose(*scen.spot)
    env.close()


def test_scenarios_are_seeded():
    a, b = make_scenario("parking", 11), make_scenario("parking", 11)
    assert a == b
    starts = {make_scenario("parking", s).start for s in range(6)}
    spots = {make_scenario("parking", s).spot for s in range(30)}
    assert len(starts) == 6 and len(spots) >= 5
    base = make_scenario("parking", 0, jitter=(0.0, 0.0, 0.0)).start
    for s in range(10):
        st = make_scenario("parking", s).start
        assert abs(st.x - base.x) <= 1.0 and abs(st.y - base.y) <= 0.5
        assert abs(st.yaw - base.yaw) <= math.radians(5.0)
    with pytest.raises(InputError, match="scenario"):
        make_scenario("roundabout", 0)
    with pytest.raises(InputError, match="spot"):
        make_scenario("parking", 0, spot=(0, 0, 0))
    with pytest.raises(InputError, match="seed"):
        make_scenario("parking", -1)


def test_overtake_scene_matches_the_overtake_map():
    scen = make_scenario("overtake", 0)
    env = build_env(scen)
    u = env.unwrapped
    m = scen.map
    lanes = u.road.network.lanes_list()
    ego_lane = u.road.network.get_lane(("a", "b", 0))
    other = u.road.network.get_lane(("b", "a", 0))
    assert len(lanes) == 2
    assert ego_lane.position(0, 0)[1] == pytest.approx(scen.lane_y)
    assert other.position(0, 0)[1] == pytest.approx(scen.lane_y + 4.0)
    assert ego_lane.heading == pytest.approx(0.0) and abs(other.heading) == pytest.approx(math.pi)
    # The road edges (map obstacles) bound the two lanes exactly.
    low = ego_lane.position(0, -ego_lane.width / 2)[1]
    high = other.position(0, -other.width / 2)[1]
    edges = [o for i, o in enumerate(m.obstacles) if i != scen.lead_index]
    assert sorted(o.corners()[:, 1].max() for o in edges)[0] == pytest.approx(low)
    assert sorted(o.corners()[:, 1].min() for o in edges)[-1] == pytest.approx(high)
    # The stopped car is a highway-env vehicle of the map's rectangle, standing still.
    lead = [v for v in u.road.vehicles if v is not u.vehicle]
    assert len(lead) == 1 and type(lead[0]) is Vehicle and lead[0].speed == 0.0
    assert _poly(lead[0]).symmetric_difference(m.obstacles[scen.lead_index].polygon()).area < 1e-9
    assert u.road.network.get_closest_lane_index(lead[0].position, 0.0) == ("a", "b", 0)
    env.close()


@pytest.mark.parametrize("name", ["parking", "overtake"])
def test_static_objects_get_the_lane_highway_env_would_find(name):
    # The scenes memoise the closest-lane search for static objects; every object
    # must still carry what highway-env's own search returns on its road, in every
    # build (first and cached) and for another seed's scene.
    for seed in (0, 0, 3):
        u = build_env(make_scenario(name, seed)).unwrapped
        net = u.road.network
        placed = [o for o in u.road.objects] + [
            v for v in u.road.vehicles if type(v) is Vehicle and v.speed == 0.0
        ]
        assert placed
        for o in placed:
            assert o.road is u.road
            assert o.lane_index == net.get_closest_lane_index(o.position, o.heading)
            assert o.lane is net.get_lane(o.lane_index)


def _stock_and_screened(monkeypatch, run):
    """``run()`` with the scenes' screened collision step and with highway-env's own."""
    screened = run()
    with monkeypatch.context() as m:
        m.setattr(SceneRoad, "step", Road.step)  # the reference: highway-env's Road.step
        stock = run()
    return screened, stock


def _same_drive(a, b):
    assert a.status == b.status
    for name in ("states", "controls", "crashed", "others"):
        assert np.array_equal(getattr(a.log, name), getattr(b.log, name)), name


@pytest.mark.parametrize(
    "case",
    ["parking", "parking_into_object", "into_stopped_car", "into_moving_lead", "oncoming_traffic"],
)
def test_screened_collision_step_drives_exactly_like_highway_env(monkeypatch, case):
    if case == "parking":
        if IMPROVED not in PLANNERS:
            pytest.skip("planner not registered")
        def run():
            return run_episode("parking", IMPROVED, "pure-pursuit", 4)
    elif case == "parking_into_object":
        scen = make_scenario("parking", 1)
        st = scen.start
        d = np.arange(0.0, 120.0, 0.1)  # through the wall at x = 100
        ahead = np.column_stack([st.x + d * math.cos(st.yaw), st.y + d * math.sin(st.yaw),
                                 np.full_like(d, st.yaw), 0 * d])
        def run():
            return run_episode(scen, Path(ahead, np.zeros((0, 2))), "stanley", 1)
    elif case == "into_stopped_car":
        scen = make_scenario("overtake", 0, jitter=(0.0, 0.0, 0.0))
        x = np.arange(scen.start.x, 92.0, 0.1)
        straight = Path(np.column_stack([x, np.full_like(x, scen.lane_y), 0 * x, 0 * x]),
                        np.zeros((0, 2)))
        def run():
            return run_episode(scen, straight, "lqr", 0)
    else:
        density = "high" if case == "oncoming_traffic" else "low"
        scen = make_scenario("overtake-traffic", 5, density=density)
        cfg = EpisodeConfig(max_time_s=12.0, replan=ReplanConfig(wall_limit=False))
        if case == "into_moving_lead":
            # A lead car standing 6 m ahead: the ego runs into it.
            scen = dataclasses.replace(scen, lead=(scen.start.x + 6.0, 0.0))
        def run():
            return run_episode(scen, IMPROVED, "pure-pursuit", 5, cfg)
    screened, stock = _stock_and_screened(monkeypatch, run)
    _same_drive(screened, stock)
    if case in ("parking_into_object", "into_stopped_car", "into_moving_lead"):
        assert stock.status == "crashed"


# ----------------------------------------------------------------------------- runner


def test_episode_with_a_given_path_is_deterministic_and_successful():
    scen = make_scenario("overtake", 2, jitter=(0.0, 0.0, 0.0))
    path = lane_change_path(scen.start.as_tuple(), scen.lane_y)
    a = run_episode(scen, path, "stanley", 2)
    b = run_episode(scen, path, "stanley", 2)
    assert a.status == "arrived"
    assert np.array_equal(a.log.states, b.log.states)
    assert np.array_equal(a.log.controls, b.log.controls)
    r = evaluate(a)
    assert r.success and not r.collision
    assert r.passed_lead and r.back_in_lane
    assert r.cte_max_m < 0.05
    # The controller ran at the simulation frequency.
    assert a.log.dt == pytest.approx(1 / 20)
    assert r.steps == len(a.log.controls) and r.steps > 300


@needs_improved
@pytest.mark.parametrize("name", ["parking", "overtake"])
def test_episode_jerk_stays_within_the_comfort_limits(name):
    # Jerk-limited braking and the tapered stop: the step-to-step jerk of the applied
    # command (longitudinal and lateral together) stays near the 5 m/s^3 limits.
    ep = run_episode(name, IMPROVED, "pure-pursuit", 2)
    r = evaluate(ep)
    assert r.success and r.goal_position_err_m < 0.1
    assert r.max_jerk < 6.0


def test_frequency_is_configurable_and_validated():
    scen = make_scenario("overtake", 0, jitter=(0.0, 0.0, 0.0))
    path = lane_change_path(scen.start.as_tuple(), scen.lane_y)
    ep = run_episode(scen, path, "lqr", 0, EpisodeConfig(sim=SimConfig(simulation_frequency=15)))
    assert ep.log.dt == pytest.approx(1 / 15) and evaluate(ep).success
    with pytest.raises(InputError, match="simulation_frequency"):
        SimConfig(simulation_frequency=5)


def test_a_path_into_the_stopped_car_crashes_by_both_judges():
    scen = make_scenario("overtake", 0, jitter=(0.0, 0.0, 0.0))
    x = np.arange(scen.start.x, 92.0, 0.1)
    samples = np.column_stack([x, np.full_like(x, scen.lane_y), 0 * x, 0 * x])
    straight = Path(samples, np.zeros((0, 2)))
    ep = run_episode(scen, straight, "pure-pursuit", 0)
    r = evaluate(ep)
    assert ep.status == "crashed"
    assert r.collision_highway_env and r.collision_footprint and not r.success


@needs_improved
@pytest.mark.parametrize("controller", ["pure-pursuit", "stanley", "lqr"])
def test_planned_overtake_succeeds(controller):
    ep = run_episode("overtake", IMPROVED, controller, 1)
    r = evaluate(ep)
    assert r.success, ep.message
    assert not r.collision_highway_env and not r.collision_footprint
    assert r.executed_max_curvature <= r.kappa_max + 1e-12


@needs_improved
@pytest.mark.parametrize("controller", ["pure-pursuit", "stanley", "lqr"])
def test_planned_parking_succeeds(controller):
    seed = next(
        s for s in range(20)
        if make_scenario("parking", s).spot == (0, 0, 3)  # the shortest drive
    )
    ep = run_episode("parking", IMPROVED, controller, seed)
    if ep.status == "plan_failed":
        pytest.skip(f"planner failed on seed {seed}: {ep.message}")
    r = evaluate(ep)
    assert r.success, ep.message
    assert r.goal_position_err_m < 0.2 and r.goal_heading_err_rad < math.radians(3)
    assert r.cte_max_m < 0.3
    assert r.executed_curvature_violation_share == 0.0


# ----------------------------------------------------------------------------- stock envs


def _stock(env_id: str, seed: int):
    env = gym.make(env_id)
    env.reset(seed=seed)
    return env


@pytest.mark.parametrize("env_id", ["parking-v0", "parking-parked-v0"])
def test_map_from_stock_parking_env(env_id):
    env = _stock(env_id, 0)
    u = env.unwrapped
    m = map_from_env(env, lane_lines=False)
    solid = [o for o in u.road.objects if not isinstance(o, Landmark)]
    parked = [v for v in u.road.vehicles if v is not u.vehicle]
    assert len(m.obstacles) == len(solid) + len(parked)
    for ours, theirs in zip(m.obstacles, solid + parked, strict=True):
        assert ours.polygon().symmetric_difference(_poly(theirs)).area < 1e-9
    # Start and goal are rear-axle poses of our car at the ego and its goal landmark.
    goal = u.vehicle.goal
    d = 4.30 / 2 - (4.30 - 2.51) / 2
    assert m.goal.x == pytest.approx(goal.position[0] - d * math.cos(goal.heading))
    assert m.goal.yaw == pytest.approx(goal.heading)
    with_lines = map_from_env(env)
    assert len(with_lines.obstacles) > len(m.obstacles)  # spot lines as thin obstacles
    env.close()


@needs_improved
@pytest.mark.parametrize("env_id", ["parking-v0", "parking-parked-v0"])
def test_plan_and_drive_in_stock_parking_env(env_id):
    solved = None
    for seed in range(16):
        env = _stock(env_id, seed)
        m = map_from_env(env)
        res = make_planner(IMPROVED).solve(
            PlanningProblem.from_map(m), np.random.default_rng(seed), Budget(max_time_s=3.0)
        )
        if res.success:
            solved = (env, m, res)
            break
        env.close()
    if solved is None:
        pytest.skip(f"{IMPROVED} solved none of 16 {env_id} scenes")
    env, m, res = solved
    env.unwrapped.config["simulation_frequency"] = 20
    ego = attach_ego(env)
    assert env.unwrapped.vehicle is ego and ego.pose.x == pytest.approx(m.start.x)
    from rrtdrive.controllers import SpeedConfig, make_controller

    log = drive(env, res.path, make_controller("lqr", speed=SpeedConfig(v_max=3.0)), 90.0)
    assert log.arrived and not log.crashed.any()
    final = log.states[-1]
    assert math.hypot(final[0] - m.goal.x, final[1] - m.goal.y) < 0.5
    env.close()


# ----------------------------------------------------------------------------- CLI


def _cli(argv):
    parser = argparse.ArgumentParser()
    sub = parser.add_subparsers()
    cli_simulate.add_parser(sub)
    return cli_simulate.run(parser.parse_args(["simulate", *argv]))


REQUIRED_KEYS = {
    "success", "collision", "cte_rms_m", "cte_max_m", "heading_err_rms_rad",
    "heading_err_max_rad", "path_max_curvature", "executed_max_curvature",
    "executed_curvature_violation_share", "max_lateral_accel", "max_jerk",
    "max_steering_rate", "goal_position_err_m", "goal_heading_err_rad", "duration_s",
    "steps", "wall_time_s", "planner", "controller", "seed",
}


@needs_improved
def test_cli_simulate_json_and_exit_codes(tmp_path, capsys):
    out = tmp_path / "m.json"
    code = _cli(["overtake", "--controller", "lqr", "--seed", "3", "--json", str(out)])
    data = json.loads(out.read_text())
    assert REQUIRED_KEYS <= set(data)
    assert data["controller"] == "lqr" and data["seed"] == 3 and data["planner"] == IMPROVED
    assert code == (0 if data["success"] else 1) and data["success"]
    assert not list(tmp_path.glob(".*"))  # no temporary file left behind
    capsys.readouterr()
    assert _cli(["overtake", "--seed", "3", "--json", "-"]) == 0
    assert json.loads(capsys.readouterr().out)["success"] is True


@pytest.mark.parametrize(
    ("argv", "field"),
    [
        (["highway"], "scenario"),
        (["parking", "--controller", "mpc"], "--controller"),
        (["parking", "--planner", "astar"], "--planner"),
        (["parking", "--video", "out.gif"], "--video"),
        (["parking", "--video", "/no/such/dir/x.mp4"], "--video"),
    ],
)
def test_cli_bad_input_exits_2(argv, field, capsys):
    assert _cli(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and field in err[0]


def test_cli_failed_episode_exits_1(capsys):
    # A planning budget too small to solve the lot: the episode fails, exit 1.
    assert _cli(["parking", "--planner", "rrt", "--plan-time", "0.001", "--json", "-"]) == 1
    data = json.loads(capsys.readouterr().out)
    assert data["success"] is False and data["status"] == "plan_failed"


@needs_improved
def test_overtake_waits_for_oncoming_traffic():
    scen = make_scenario("overtake", 0, oncoming=1)
    assert len(scen.oncoming) == 1
    assert scen.oncoming == make_scenario("overtake", 0, oncoming=1).oncoming
    ep = run_episode(scen, IMPROVED, "lqr", 0)
    r = evaluate(ep)
    assert r.success, ep.message
    assert not r.collision_highway_env and not r.collision_footprint
    oncoming = ep.log.others[:, 1, :]  # [lead car, oncoming car]
    assert oncoming[0, 0] > oncoming[-1, 0]  # it drove towards -x
    # The ego stayed in its lane until the oncoming car had passed the stopped car.
    lead_x = scen.map.obstacles[scen.lead_index].center[0]
    out = np.flatnonzero(ep.log.states[:, 1] > scen.lane_y + 1.0)
    assert len(out) and oncoming[out[0], 0] < lead_x
    with pytest.raises(InputError, match="oncoming"):
        make_scenario("parking", 0, oncoming=1)
