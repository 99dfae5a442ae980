"""Overtaking a moving car against oncoming traffic: scenario, space-time planning, re-planning,
metrics and the command line, in real highway-env."""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest
from highway_env.vehicle.kinematics import Vehicle

from rrtdrive.cli import main as cli_main
from rrtdrive.controllers import SpeedConfig, SpeedProfile, make_controller
from rrtdrive.evaluation import (
    evaluate,
    min_vehicle_distance,
    summarise,
    time_to_collision,
    vehicle_collisions,
)
from rrtdrive.maps import Map
from rrtdrive.planning.base import cached_checker
from rrtdrive.planning.spacetime import (
    ArrivalTiming,
    Prediction,
    SafetyConfig,
    SpaceTimeChecker,
    SpaceTimeProblem,
    SpaceTimeRRTConnect,
    profile_times,
    traffic_conflicts,
)
from rrtdrive.sim.episode import DriveLog, Episode
from rrtdrive.sim.follower import IDMConfig
from rrtdrive.sim.replanning import ReplanConfig, lane_path
from rrtdrive.sim.runner import EpisodeConfig, run_episode
from rrtdrive.sim.scenes import OncomingCar, build_env, scenario_rngs
from rrtdrive.sim.tasks import TRAFFIC_DENSITIES, make_scenario, traffic_speed_config
from rrtdrive.sim.traffic import OncomingGate, conflict_zone
from rrtdrive.sim.traffic_driver import TrafficDriver
from rrtdrive.types import Budget, InputError, Path, Pose, VehicleParams

V = VehicleParams()
#: Tests ignore the wall clock: an episode then depends on its seed only.
SEEDED = EpisodeConfig(replan=ReplanConfig(wall_limit=False))


@pytest.fixture(scope="module")
def overtaken():
    """A low-density episode that completes its overtake (seed 4, about 9 s)."""
    ep = run_episode(make_scenario("overtake-traffic", 4, density="low"), seed=4, config=SEEDED)
    return ep, evaluate(ep)


# ----------------------------------------------------------------------------- scenario


def test_scenario_is_seeded_and_configurable():
    a = make_scenario("overtake-traffic", 7)
    assert a == make_scenario("overtake-traffic", 7)
    assert a != make_scenario("overtake-traffic", 8)
    assert a.density == TRAFFIC_DENSITIES["default"] and a.lead_model == "idm"
    lead_x, lead_v = a.lead
    assert lead_v == 4.0 and a.ego_speed == lead_v
    assert 20.0 <= lead_x - (a.start.x + V.length / 2 - V.rear_overhang) <= 30.0
    xs = np.array([x for x, _ in a.oncoming])
    speeds = np.array([v for _, v in a.oncoming])
    assert np.all(np.diff(xs) >= 25.0) and np.all((speeds >= 6.0) & (speeds <= 9.0))
    # Density: more cars per km, smaller gaps (averaged over seeds).
    def mean_gap(d):
        return np.mean([np.diff([x for x, _ in make_scenario("overtake-traffic", s,
                                                              density=d).oncoming]).mean()
                        for s in range(10)])
    assert mean_gap("low") > mean_gap("default") > mean_gap("high")
    assert mean_gap(20.0) == pytest.approx(50.0, rel=0.25)
    c = make_scenario("overtake-traffic", 7, lead_speed=6.0, lead_model="constant", density=3)
    assert c.lead[1] == 6.0 and c.lead_model == "constant" and c.density == 3.0


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"density": -1.0}, "density"),
        ({"density": "rush hour"}, "density"),
        ({"density": 50.0}, "density"),
        ({"lead_speed": 10.0}, "lead_speed"),
        ({"lead_speed": 0.0}, "lead_speed"),
        ({"lead_model": "bus"}, "lead_model"),
        ({"spot": (0, 0, 3)}, "spot"),
        ({"oncoming": 2}, "oncoming"),
    ],
)
def test_scenario_bad_input_names_the_field(kwargs, field):
    with pytest.raises(InputError, match=field):
        make_scenario("overtake-traffic", 0, **kwargs)


def test_a_traffic_task_without_a_lead_is_refused():
    # It could only time out, and was scored as safe following (session 27's audit).
    task = make_scenario("overtake-traffic", 0)
    with pytest.raises(InputError, match="scenario.lead"):
        dataclasses.replace(task, lead=None)


def test_traffic_options_belong_to_the_traffic_scenario():
    with pytest.raises(InputError, match="density"):
        make_scenario("overtake", 0, density=5.0)
    with pytest.raises(InputError, match="lead_model"):
        make_scenario("parking", 0, lead_model="idm")


@pytest.mark.parametrize("model", ["idm", "constant"])
def test_scene_has_the_lead_first_then_the_oncoming_stream(model):
    scen = make_scenario("overtake-traffic", 1, lead_model=model)
    env = build_env(scen)
    try:
        u = env.unwrapped
        ego, lead, *oncoming = u.road.vehicles
        assert ego is u.vehicle and ego.speed == scen.ego_speed
        assert type(lead) is (OncomingCar if model == "idm" else Vehicle)
        assert lead.position[0] == pytest.approx(scen.lead[0]) and lead.heading == 0.0
        assert (lead.LENGTH, lead.WIDTH) == (V.length, V.width)
        assert len(oncoming) == len(scen.oncoming)
        assert all(abs(v.heading) == pytest.approx(math.pi) for v in oncoming)
        assert all(v.position[1] == pytest.approx(scen.lane_y + 4.0) for v in oncoming)
        for _ in range(20):  # 1 s: the constant-speed lead keeps its speed exactly
            u.road.act()
            u.road.step(0.05)
        assert lead.speed == pytest.approx(scen.lead[1], abs=1e-6 if model == "constant" else 0.5)
    finally:
        env.close()


# ----------------------------------------------------------------------------- space-time


def test_conflicts_are_in_space_and_time():
    safety = SafetyConfig(0.3, 0.0, 0.2, 0.0)
    # A car driving +x at 5 m/s from x = 0: its centre is at x = 20 at t = 4 s.
    car = Prediction.constant_velocity(np.array([[0.0, 0.0, 0.0, 5.0]]), [(4.3, 1.8)], 8.0)
    at = np.array([[20.0 - 1.255, 0.0, 0.0]] * 3)  # ego body centred on x = 20
    t = np.array([1.0, 4.0, 7.0])
    assert traffic_conflicts(at, t, t, car, safety, V).tolist() == [False, True, False]
    # Beside it, laterally: clear unless the buffer reaches across.
    side = at.copy()
    side[:, 1] = 1.8 / 2 + 1.151 + 0.35  # disc radius 1.151 m, 0.35 m beyond half the width
    assert not traffic_conflicts(side, t, t, car, safety, V).any()
    wide = SafetyConfig(0.4, 0.0, 0.2, 0.0)
    assert traffic_conflicts(side, t, t, car, wide, V).tolist() == [False, True, False]
    # A wider time band catches it earlier (the conflict starts at about 2.6 s).
    two = np.array([2.0])
    assert not traffic_conflicts(at[:1], two, two, car, safety, V)[0]
    late = SafetyConfig(0.3, 0.0, 1.0, 0.0)
    assert traffic_conflicts(at[:1], two, two, car, late, V)[0]


def test_a_second_speed_hypothesis_is_swept_too():
    safety = SafetyConfig(0.3, 0.0, 0.2, 0.0)
    slow = Prediction.constant_velocity(np.array([[0.0, 0.0, 0.0, 3.0]]), [(4.3, 1.8)], 8.0)
    fast = Prediction.constant_velocity(np.array([[0.0, 0.0, 0.0, 6.0]]), [(4.3, 1.8)], 8.0)
    both = Prediction(slow.times, slow.poses, slow.sizes, alt=fast.poses)
    at = np.array([[18.0 - 1.255, 0.0, 0.0]] * 2)  # body centred on x = 18
    t = np.array([3.0, 6.0])  # the fast car is there at 3 s, the slow one at 6 s
    assert traffic_conflicts(at, t, t, slow, safety, V).tolist() == [False, True]
    assert traffic_conflicts(at, t, t, fast, safety, V).tolist() == [True, False]
    assert traffic_conflicts(at, t, t, both, safety, V).tolist() == [True, True]
    with pytest.raises(InputError, match="alt"):
        Prediction(slow.times, slow.poses, slow.sizes, alt=np.zeros((2, 3)))


def test_profile_times_follow_the_controllers_speed_profile():
    path = lane_path(0.0, 200.0, 44.0)
    s = path.arc_length()
    kappa = np.where((s > 60) & (s < 80), 1.0 / 30.0, 0.0)
    cfg = SpeedConfig(v_max=11.0, accel=1.5, a_lat_max=2.0)
    t, v = profile_times(s, kappa, 4.0, cfg.v_max, cfg.accel, cfg.decel, cfg.a_lat_max,
                         cfg.v_launch)
    ref = SpeedProfile(s, kappa, cfg, v_start=4.0)
    far = s < 120.0  # the controller's profile stops at the end of its path; this one does not
    assert v[far] == pytest.approx(ref.v[far], abs=1e-9)
    assert t[0] == 0.0 and np.all(np.diff(t) > 0)
    timing = ArrivalTiming(0.0, 4.0, 11.0, 1.5, (0.0, 44.0), length_factor=1.0)
    lo, hi = timing.band(np.array([[40.0, 44.0]]))
    assert lo[0] == pytest.approx(hi[0]) and lo[0] == pytest.approx(
        t[np.searchsorted(s, 40.0)], abs=0.05
    )
    assert timing.state_at((0.0, 44.0)) == (0.0, 4.0)


def _road(goal_x=62.0, start=(2.0, 44.0, 0.0)):
    return Map("road", (0.0, 42.0, 80.0, 50.0), (), Pose(*start), Pose(goal_x, 44.0, 0.0),
               VehicleParams(min_turning_radius=30.0))


def test_space_time_planner_passes_a_slow_car_and_its_times_are_clear():
    lead = Prediction.constant_velocity(np.array([[25.0, 44.0, 0.0, 2.0]]), [(4.3, 1.8)], 12.0)
    timing = ArrivalTiming(0.0, 4.0, 11.0, 1.5, (2.0, 44.0))
    problem = SpaceTimeProblem(_road(), lead, timing, speed=(11.0, 1.5, 1.0, 2.0, 0.5))
    plan = SpaceTimeRRTConnect().solve_spacetime(problem, np.random.default_rng(1),
                                                 Budget(max_iterations=3000))
    assert plan.success, plan.result.message
    path = plan.result.path
    assert path.samples[:, 1].max() > 46.5  # out into the other lane, around the car
    assert path.max_curvature <= 1.0 / 30.0 + 1e-9  # the planning radius bound
    assert len(plan.times) == len(path) and np.all(np.diff(plan.times) > 0)
    assert not traffic_conflicts(path.samples[:, :3], plan.times, plan.times, lead,
                                 problem.safety, V, 0.25).any()
    assert len(plan.tree_times) == len(plan.result.trees) and plan.dynamic_checks > 0
    # The same road without the car: straight along the lane (direct connection).
    empty = SpaceTimeProblem(_road(), Prediction.empty(12.0), timing)
    straight = SpaceTimeRRTConnect().solve_spacetime(empty, np.random.default_rng(1), Budget())
    assert straight.success and np.allclose(straight.result.path.samples[:, 1], 44.0)


def test_space_time_checker_blocks_only_when_the_car_is_there():
    timing = ArrivalTiming(0.0, 4.0, 11.0, 1.5, (2.0, 44.0))
    static = cached_checker(_road())
    oncoming = Prediction.constant_velocity(
        np.array([[54.0, 48.0, math.pi, 8.0]]), [(4.3, 1.8)], 12.0
    )
    checker = SpaceTimeChecker(static, oncoming, timing)
    # The ego reaches x = 25 at about 3.5-3.7 s; so does the oncoming car (54 - 8 t).
    assert checker.edge_free((20.0, 48.0), (30.0, 48.0)) is False
    assert checker.edge_free((20.0, 44.0), (30.0, 44.0)) is True  # own lane
    assert checker.edge_free((2.0, 48.0), (8.0, 48.0)) is True  # long before it arrives
    assert checker.bounds == static.bounds  # everything else is the static checker's
    late = SpaceTimeChecker(static, oncoming, timing, deadline=0.0)
    assert late.edge_free((20.0, 44.0), (30.0, 44.0)) is False and late.expired
    problem = SpaceTimeProblem(_road(), oncoming, timing, deadline=0.0)
    plan = SpaceTimeRRTConnect().solve_spacetime(problem, np.random.default_rng(0), Budget())
    assert not plan.success and plan.deadline_hit


# ----------------------------------------------------------------------------- re-planning


def test_an_overtake_completes_safely_with_stitched_references(overtaken):
    ep, r = overtaken
    assert ep.status == "completed" and r.success and r.outcome == "success"
    assert not r.collision and r.collisions_at_fault == 0 and r.collisions_vehicles == 0
    assert r.passed_lead and r.back_in_lane
    assert r.completion_time_s == pytest.approx(ep.log.t[-1])
    assert r.min_distance_m > 0.5 and (r.ttc_min_s is None or r.ttc_min_s > 0.95)
    assert r.ttc_within_bound
    tr = ep.traffic
    assert [m for _, m in tr.modes][:2] == ["follow", "overtake"]
    # Periodic cycles at 4 Hz from t = 0, each recorded with its wall time.
    periodic = [rec.t for rec in tr.records if rec.trigger == "periodic"]
    assert np.allclose(np.diff(periodic), 0.25) and periodic[0] == 0.0
    assert r.replans == len(tr.records) and r.replan_budget_s == 0.25
    assert any(rec.outcome == "overtake" for rec in tr.records)
    # Stitching: each new reference continues the one before it up to the stitch point.
    for (_, prev), (t_new, new) in zip(tr.references[:-1], tr.references[1:], strict=True):
        k = int(round(t_new / ep.log.dt))
        ego = ep.log.states[k, :2]
        assert np.hypot(*(new.samples[0, :2] - ego)) < 1.0  # starts at the ego
        d = np.hypot(*(prev.xy[:, None, :] - new.xy[None, :8, :]).transpose(2, 0, 1))
        assert d.min(axis=0).max() < 1e-6  # its first metres are the old reference's
    executed = tr.executed
    assert np.hypot(*np.diff(executed.xy, axis=0).T).max() < 0.3  # continuous reference
    assert r.cte_max_m < 0.3  # tracked closely across the switches
    assert r.executed_max_curvature <= V.kappa_max + 1e-9
    assert r.progress_m == pytest.approx(ep.log.states[-1, 0] - ep.log.states[0, 0], abs=0.5)


def test_deterministic_for_a_seed(overtaken):
    ep, _ = overtaken
    again = run_episode(make_scenario("overtake-traffic", 4, density="low"), seed=4,
                        config=SEEDED)
    assert np.array_equal(ep.log.states, again.log.states)
    assert np.array_equal(ep.log.others, again.log.others)
    assert [r.outcome for r in ep.traffic.records] == [r.outcome for r in again.traffic.records]


def test_no_gap_means_safe_following():
    scen = make_scenario("overtake-traffic", 0, density=30.0)
    cfg = EpisodeConfig(max_time_s=15.0, replan=ReplanConfig(wall_limit=False))
    ep = run_episode(scen, seed=0, config=cfg)
    r = evaluate(ep)
    assert ep.status == "timeout" and r.outcome == "safe_following" and not r.collision
    assert [m for _, m in ep.traffic.modes] == ["follow"]
    assert all(rec.outcome in ("no_gap", "no_plan", "no_goal") for rec in ep.traffic.records)
    # IDM following: the ego settles behind the lead at about s0 + v T = 10 m.
    lead = ep.log.others[-1, 0]
    gap = lead[0] - V.length / 2 - (ep.log.states[-1, 0] + V.front_extent)
    assert 7.0 < gap < 14.0
    assert r.min_distance_m == pytest.approx(4.0 - 1.8, abs=0.05)  # oncoming cars passing by
    s = summarise([r])
    assert s["outcomes"]["safe_following"] == 1 and s["collisions_at_fault"] == 0


def _driver(seed=6, density="low"):
    scen = make_scenario("overtake-traffic", seed, density=density)
    env = build_env(scen)
    speed = traffic_speed_config(scen)
    ctrl = make_controller("pure-pursuit", vehicle=scen.vehicle, speed=speed)
    _, rng, _ = scenario_rngs(seed)
    driver = TrafficDriver(env, scen, ctrl, speed, ReplanConfig(wall_limit=False), rng)
    driver.start()
    return env, driver


def test_an_unsafe_plan_is_replaced_or_dropped_never_driven_unchecked():
    env, driver = _driver()
    try:
        driver.control(0.0)  # the first periodic cycle
        assert driver.records[-1].outcome == "overtake" and driver.mode == "overtake"
        assert driver.current_safe()
        # An oncoming car suddenly placed to meet the ego where the plan is in its lane.
        path = driver.controller.projector.samples
        i = int(np.argmax(path[:, 1]))
        car = driver.others[1]
        car.position = np.array([path[i, 0] + car.speed * driver._times[i], 48.0])
        assert not driver.current_safe()
        driver.control(0.05)  # the per-step check notices and re-plans at once
        last = driver.records[-1]
        assert last.trigger == "unsafe"
        assert last.outcome in ("overtake", "abandoned")
        assert driver.current_safe()  # whatever it drives now passed the check
        if last.outcome == "abandoned":
            assert driver.mode == "follow"
    finally:
        env.close()


def test_idm_caps_the_speed_behind_the_lead():
    idm = IDMConfig()
    assert idm.accel_for(4.0, 11.0, 30.0, 0.0) > 1.0  # far behind: speed up
    assert idm.accel_for(4.0, 11.0, 10.0, 0.0) == pytest.approx(0.0, abs=0.05)  # s0 + v T
    assert idm.accel_for(8.0, 11.0, 8.0, 4.0) < -3.0  # closing fast: brake
    with pytest.raises(InputError, match="idm.min_gap"):
        IDMConfig(min_gap=0.0)


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"rate_hz": 1.0}, "rate_hz"),
        ({"rate_hz": 6.0}, "rate_hz"),
        ({"predictor": "oracle"}, "predictor"),
        ({"horizon_s": 1.0}, "horizon_s"),
        ({"max_iterations": 0}, "max_iterations"),
        ({"budget_s": -0.1}, "budget_s"),
        ({"planner_options": {"steps": 3}}, "steps"),
        ({"postprocess_reserve": 1.0}, "postprocess_reserve"),
    ],
)
def test_replan_config_bad_input_names_the_field(kwargs, field):
    with pytest.raises(InputError, match=field):
        ReplanConfig(**kwargs)


def test_traffic_needs_the_space_time_planner():
    with pytest.raises(InputError, match="planner"):
        run_episode(make_scenario("overtake-traffic", 0), planner="rrt", seed=0)


# ----------------------------------------------------------------------------- metrics


def _road_episode(states, others, sizes, status="timeout"):
    scen = make_scenario("overtake-traffic", 0, jitter=(0.0, 0.0, 0.0))
    states = np.asarray(states, float)
    n = len(states)
    log = DriveLog(0.05, np.arange(n) * 0.05, states, np.zeros((n - 1, 2)), np.zeros(n, bool),
                   np.asarray(others, float), np.asarray(sizes, float), False, 0.0)
    path = lane_path(0.0, 200.0, 44.0)
    return Episode(scen, "given", "pure-pursuit", 0, None, path, log, status, "", EpisodeConfig())


def test_ttc_follows_nuplans_definition():
    # Ego at 5 m/s towards a car stopped 7.3 m (bumper to bumper) ahead: 7.3 / 5 = 1.46 s,
    # found at the first step of the 0.1 s grid where the boxes meet: 1.5 s.
    ego = [[10.0, 44.0, 0.0, 5.0], [10.0, 44.0, 0.0, 5.0]]
    ahead_x = 10.0 + V.front_extent + 7.3 + 4.3 / 2
    others = np.array([[[ahead_x, 44.0, 0.0, 0.0]]] * 2)
    ttc = time_to_collision(_road_episode(ego, others, [[4.3, 1.8]]))
    assert ttc == pytest.approx([1.5, 1.5])
    # Behind the ego (even closing fast) it does not count; nor beyond 3 s; nor when stopped.
    behind = others.copy()
    behind[..., 0] = 10.0 - 8.0
    behind[..., 3] = 20.0
    assert np.all(np.isinf(time_to_collision(_road_episode(ego, behind, [[4.3, 1.8]]))))
    far = others.copy()
    far[..., 0] += 20.0
    assert np.all(np.isinf(time_to_collision(_road_episode(ego, far, [[4.3, 1.8]]))))
    stopped = [[10.0, 44.0, 0.0, 0.0]] * 2
    assert np.all(np.isinf(time_to_collision(_road_episode(stopped, others, [[4.3, 1.8]]))))
    # An at-fault collision sets it to 0.
    assert time_to_collision(_road_episode(ego, others, [[4.3, 1.8]]), [1])[1] == 0.0


def test_a_reversing_ego_looks_the_way_it_moves():
    # Backing at 2 m/s towards a car stopped 2.9 m (bumper to bumper) behind it: 1.5 s.
    # The cone about the nose saw nothing while reversing (parallel parking seed 3: no
    # TTC on any of its 190 reversing steps).
    ego = [[10.0, 44.0, 0.0, -2.0]] * 2
    behind_x = 10.0 - V.rear_overhang - 2.9 - 4.3 / 2
    others = np.array([[[behind_x, 44.0, 0.0, 0.0]]] * 2)
    assert time_to_collision(_road_episode(ego, others, [[4.3, 1.8]])) == pytest.approx([1.5] * 2)
    # The car past its nose is now behind it.
    ahead = others.copy()
    ahead[..., 0] = 10.0 + V.front_extent + 1.0 + 4.3 / 2
    assert np.all(np.isinf(time_to_collision(_road_episode(ego, ahead, [[4.3, 1.8]]))))
    # Backing into a moving car: the ego's leading (rear) bumper, at fault.
    hit = np.array([[[10.0 - V.rear_overhang - 4.3 / 2 + 0.1, 44.0, 0.0, 0.5]]] * 2)
    (c,) = vehicle_collisions(_road_episode(ego, hit, [[4.3, 1.8]]))
    assert c[2] == "active_front" and c[3]


def test_at_fault_collisions_follow_nuplans_classification():
    size = [[4.3, 1.8]]
    # The ego drives into a stopped car: at fault.
    ego = [[10.0, 44.0, 0.0, 5.0]] * 2
    hit = np.array([[[10.0 + 4.0, 44.0, 0.0, 0.0]]] * 2)
    (c,) = vehicle_collisions(_road_episode(ego, hit, size))
    assert c[2] == "stopped_track" and c[3]
    # A moving car runs into the moving ego from behind: not at fault.
    rear = np.array([[[10.0 - 3.0, 44.0, 0.0, 8.0]]] * 2)
    (c,) = vehicle_collisions(_road_episode(ego, rear, size))
    assert c[2] == "active_rear" and not c[3]
    # The ego's front bumper into a moving car: at fault.
    front = np.array([[[10.0 + 1.255 + 4.2, 44.0, 0.0, 2.0]]] * 2)
    (c,) = vehicle_collisions(_road_episode(ego, front, size))
    assert c[2] == "active_front" and c[3]
    # A car pressing into the side of a stopped ego: not at fault.
    still = [[10.0, 44.0, 0.0, 0.0]] * 2
    side = np.array([[[11.0, 45.5, 0.0, 3.0]]] * 2)
    (c,) = vehicle_collisions(_road_episode(still, side, size))
    assert c[2] == "stopped_ego" and not c[3]
    r = evaluate(_road_episode(ego, hit, size))
    assert r.collision and r.collisions_at_fault == 1 and r.outcome == "collision"
    assert r.min_distance_m == 0.0


def test_min_distance_is_exact():
    ego = [[10.0, 44.0, 0.0, 5.0]] * 3
    others = np.zeros((3, 2, 4))
    others[:, 0] = [30.0, 44.0, 0.0, 5.0]
    others[:, 1] = [11.255, 48.0, math.pi, 8.0]  # alongside, lane centres 4 m apart
    d = min_vehicle_distance(_road_episode(ego, others, [[4.3, 1.8], [4.3, 1.8]]))
    assert d == pytest.approx(4.0 - 1.8)


# ----------------------------------------------------------------------------- interfaces


def test_cli_simulate_traffic(tmp_path, capsys):
    out = tmp_path / "m.json"
    # --deterministic: the outcome depends on the seed only, not on the machine's load
    # (the re-planner's wall-time budget would cut cycles on a loaded machine).
    code = cli_main(["simulate", "overtake-traffic", "--seed", "4", "--density", "low",
                     "--deterministic", "--json", str(out)])
    data = json.loads(out.read_text())
    assert code == 0 and data["outcome"] == "success" and data["density_per_km"] == 5.0
    for key in ("ttc_min_s", "min_distance_m", "collisions_at_fault", "progress_m",
                "completion_time_s", "replan_time_median_s", "replan_time_max_s",
                "replan_budget_s"):
        assert key in data
    assert data["replans"] > 0
    assert cli_main(["simulate", "overtake-traffic", "--lead-model", "bus"]) == 2
    assert cli_main(["simulate", "overtake-traffic", "--replan-rate", "9"]) == 2
    assert cli_main(["simulate", "parking", "--density", "low"]) == 2
    err = capsys.readouterr().err
    # Each names the flag the user typed.
    assert "--lead-model: " in err and "--replan-rate: " in err and "--density: " in err
    assert "Traceback" not in err


def test_gym_env_replans_like_the_runner(overtaken):
    from rrtdrive.envs.drive_env import DriveEnv

    env = DriveEnv(
        "overtake-traffic", residual=True, scenario_options={"density": "low"},
        replan_options={"wall_limit": False},
    )
    obs, info = env.reset(options={"episode_seed": 4})
    total = 0.0
    while True:
        obs, reward, terminated, truncated, info = env.step(np.zeros(2, np.float32))
        total += info["reward_terms"]["progress"]
        if terminated or truncated:
            break
    ep, _ = overtaken  # the runner's episode of the same seed and density
    assert np.array_equal(env.episode.log.states, ep.log.states)
    assert info["status"] == ep.status == "completed" and info["is_success"]
    refs = len(env.episode.traffic.references)
    assert refs == len(ep.traffic.references) >= 2
    # Progress is counted across the reference switches (no jump back at a switch).
    assert total == pytest.approx(ep.traffic.executed.length, rel=0.05)
    env.close()


def test_video_follows_the_ego_and_draws_the_current_reference(overtaken):
    from rrtdrive.sim.video import frame_is_blank, render_frames

    ep, _ = overtaken
    frames = list(render_frames(ep, stride=60))
    assert len(frames) >= 3 and all(not frame_is_blank(f) for f in frames)
    for f in frames:
        blue = (f[..., 2] > 200) & (f[..., 0] < 80) & (f[..., 1] < 120)
        green = (f[..., 1] > 150) & (f[..., 0] < 120) & (f[..., 2] < 120)
        assert blue.sum() > 100  # the reference ahead is in view
        assert green.sum() > 50  # so is the ego (highway-env's green)


@pytest.mark.parametrize("controller", ["pure-pursuit", "stanley", "lqr"])
def test_every_controller_overtakes_in_traffic_without_a_collision(controller, overtaken):
    # Re-planning retargets the controller on every accepted plan: each controller
    # must follow the new reference (Stanley crashed in every episode before).
    if controller == "pure-pursuit":  # the default: the module's episode
        ep, r = overtaken
    else:
        scen = make_scenario("overtake-traffic", 4, density="low")
        ep = run_episode(scen, controller=controller, seed=4, config=SEEDED)
        r = evaluate(ep)
    assert not r.collision, ep.message
    assert ep.status == "completed" and r.success, ep.message


def test_the_oncoming_gate_times_the_crossing_as_the_car_drives_it():
    # A lane change out of the ego lane: the body enters the oncoming lane.
    x = np.arange(0.0, 60.0, 0.1)
    u = np.clip((x - 15.0) / 25.0, 0.0, 1.0)
    y = 44.0 + 4.0 * (6 * u**5 - 15 * u**4 + 10 * u**3)
    dy = np.gradient(y, x)
    kappa = np.gradient(dy, x) / (1 + dy**2) ** 1.5
    path = Path(np.column_stack([x, y, np.arctan(dy), kappa]), np.zeros((0, 2)))
    speed = SpeedConfig(v_max=8.0)
    instant = VehicleParams(max_steer_rate=None)
    zone = conflict_zone(path, 44.0, 4.0, instant)
    assert zone is not None
    s = path.arc_length()
    t_instant = OncomingGate(zone, (s, kappa), speed, vehicle=instant).crossing_time
    assert t_instant == OncomingGate(zone, (s, kappa), speed).crossing_time
    # The rate-limited car starts from rest without the launch speed, capped by its
    # steering rate, and its comfort loop ramps the command up: a later exit.
    t_rate = OncomingGate(zone, (s, kappa), speed, vehicle=VehicleParams()).crossing_time
    assert t_rate >= t_instant + speed.accel / speed.comfort_jerk
