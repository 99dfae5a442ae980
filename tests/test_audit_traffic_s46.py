"""Audit (session 46): closed-loop driving with traffic, checked from the outside.

Every reported interaction, tracking and comfort metric of a traffic episode is
recomputed here from the logged arrays alone (numpy + shapely, brute force), the
termination rule is re-derived step by step, forced collisions are built by driving
the gym env into the traffic, and the CLI's bad options, determinism and the gym
env's checker and info keys are exercised. Everything runs through the real
highway-env.
"""

from __future__ import annotations

import dataclasses
import json
import math
import warnings

import gymnasium as gym
import numpy as np
import pytest
import shapely
from gymnasium.utils.env_checker import check_env

import rrtdrive.envs  # noqa: F401  (registers the ids)
from rrtdrive.cli import main
from rrtdrive.evaluation import evaluate
from rrtdrive.evaluation.report import WALL_CLOCK_FIELDS, EpisodeReport
from rrtdrive.sim.replanning import ReplanConfig
from rrtdrive.sim.runner import EpisodeConfig, run_episode
from rrtdrive.sim.tasks import make_scenario
from rrtdrive.vehicle import footprint_corners

SEED_ONLY = ReplanConfig(wall_limit=False)
STEER_LIMIT = math.atan(2.51 / 6.0)  # the direct action's steering unit (docs/gym.md)


# --------------------------------------------------------------------------- helpers
def _box(x: float, y: float, h: float, length: float, width: float) -> shapely.Polygon:
    c, s = math.cos(h), math.sin(h)
    pts = [
        (-length / 2, -width / 2),
        (length / 2, -width / 2),
        (length / 2, width / 2),
        (-length / 2, width / 2),
    ]
    return shapely.Polygon([(x + c * a - s * b, y + s * a + c * b) for a, b in pts])


def _ego_box(state, veh, shift=(0.0, 0.0)) -> shapely.Polygon:
    d = veh.length / 2 - veh.rear_overhang
    x, y, h = float(state[0]), float(state[1]), float(state[2])
    return _box(
        x + d * math.cos(h) + shift[0], y + d * math.sin(h) + shift[1], h, veh.length, veh.width
    )


def _independent_interaction(ep):
    """Brute-force min distance, first contact per car and nuPlan TTC from the log."""
    sc, log = ep.scenario, ep.log
    veh, states, others, sizes = sc.vehicle, log.states, log.others, log.other_sizes
    n, k = others.shape[:2]
    lane_y, w = sc.lane_y, sc.lane_width
    mind, first_hit, ttc = math.inf, {}, math.inf
    times = np.arange(0.1, 3.0, 0.1)
    for i in range(n):
        e = _ego_box(states[i], veh)
        ys = np.asarray(e.exterior.coords)[:, 1]
        between = (
            (ys.min() < lane_y + w / 2 < ys.max())
            or ys.min() < lane_y - w / 2
            or (ys.max() > lane_y + 1.5 * w)
        )
        h, v = float(states[i, 2]), float(states[i, 3])
        for j in range(k):
            o = _box(*others[i, j, :3], *sizes[j])
            mind = min(mind, e.distance(o))
            if e.intersects(o) and j not in first_hit:
                first_hit[j] = i
            if abs(v) <= 5e-3 or (j in first_hit and first_hit[j] < i):
                continue
            dx, dy = others[i, j, 0] - states[i, 0], others[i, j, 1] - states[i, 1]
            cosang = (math.cos(h) * dx + math.sin(h) * dy) / max(math.hypot(dx, dy), 1e-12)
            ang = math.acos(max(-1.0, min(1.0, cosang)))
            if not (ang < math.radians(30) or (between and ang <= math.radians(150))):
                continue
            if math.hypot(dx, dy) > (abs(v) + abs(others[i, j, 3])) * 3.0 + 10.0:
                continue  # cannot meet within 3 s
            oh, ov = float(others[i, j, 2]), float(others[i, j, 3])
            for t in times:
                ee = _ego_box(states[i], veh, (v * math.cos(h) * t, v * math.sin(h) * t))
                oo = _box(
                    others[i, j, 0] + ov * math.cos(oh) * t,
                    others[i, j, 1] + ov * math.sin(oh) * t,
                    oh,
                    *sizes[j],
                )
                if ee.intersects(oo):
                    ttc = min(ttc, float(t))
                    break
    return mind, first_hit, ttc


def _overtake_complete(state, lead, lead_len, veh, lane_y=44.0, lane_w=4.0, gap=2.0):
    c = footprint_corners(np.asarray(state[:3], dtype=float), veh)
    return bool(
        np.all(np.abs(c[:, 1] - lane_y) <= lane_w / 2)
        and abs(math.remainder(float(state[2]), 2 * math.pi)) <= math.radians(10)
        and c[:, 0].min() >= lead[0] + lead_len / 2 + gap
    )


def _drive_direct(env, target, speed):
    """A scripted direct-mode agent: P control on an absolute lane y and a speed."""
    u = env.unwrapped
    infos = []
    while True:
        ego = u._ego
        x, y = ego.position
        ty = target(x, u)
        steer = np.clip(0.08 * (ty - y) - 0.8 * ego.heading, -0.3, 0.3) / STEER_LIMIT
        acc = np.clip((speed - ego.speed) * 0.5, -1.0, 1.0)
        _, reward, term, trunc, info = env.step(np.array([acc, steer], np.float32))
        infos.append((reward, info))
        if term or trunc:
            return term, trunc, infos


# --------------------------------------------------------------------------- fixtures
@pytest.fixture(scope="module")
def traffic_run():
    sc = make_scenario("overtake-traffic", 3, density="high")
    ep = run_episode(sc, controller="pure-pursuit", seed=3, config=EpisodeConfig(replan=SEED_ONLY))
    return ep, evaluate(ep)


@pytest.fixture(scope="module")
def oncoming_run():
    sc = make_scenario("overtake", 3, oncoming=3)
    ep = run_episode(sc, controller="stanley", seed=3)
    return ep, evaluate(ep)


# --------------------------------------------------------------------------- metrics
@pytest.mark.parametrize("which", ["traffic_run", "oncoming_run"])
def test_interaction_metrics_match_an_independent_recompute(which, request):
    ep, rep = request.getfixturevalue(which)
    assert ep.log.others.shape[1] >= 4  # there is traffic to judge
    mind, hits, ttc = _independent_interaction(ep)
    assert rep.min_distance_m == pytest.approx(mind, abs=1e-9)
    assert rep.collisions_vehicles == len(hits) == 0
    assert rep.collision_footprint is False
    assert rep.collision_highway_env is bool(ep.log.crashed.any()) is False
    if math.isinf(ttc):
        assert rep.ttc_min_s is None
    else:
        assert rep.ttc_min_s == pytest.approx(ttc, abs=1e-9)
    assert rep.ttc_within_bound is (ttc > 0.95)


@pytest.mark.parametrize("which", ["traffic_run", "oncoming_run"])
def test_tracking_and_comfort_metrics_match_the_log(which, request):
    ep, rep = request.getfixturevalue(which)
    log, veh = ep.log, ep.scenario.vehicle
    states, (accel, steer) = log.states, log.controls.T
    line = shapely.LineString(np.asarray(ep.path.samples)[:, :2])
    cte = np.array([line.distance(shapely.Point(p)) for p in states[:, :2]])
    assert rep.cte_rms_m == pytest.approx(float(np.sqrt(np.mean(cte**2))), abs=1e-6)
    assert rep.cte_max_m == pytest.approx(float(cte.max()), abs=1e-6)
    assert rep.path_length_m == pytest.approx(line.length, rel=1e-6)
    kappa = np.tan(steer) / veh.wheelbase
    lat = states[:-1, 3] ** 2 * kappa
    assert rep.max_lateral_accel == pytest.approx(float(np.abs(lat).max()), rel=1e-6)
    assert rep.max_long_accel == pytest.approx(float(np.abs(accel).max()), rel=1e-6)
    jerk = np.hypot(np.diff(accel), np.diff(lat)) / log.dt
    assert rep.max_jerk == pytest.approx(float(jerk.max()), rel=1e-6)
    rate = np.abs(np.diff(np.concatenate([[0.0], steer]))) / log.dt
    assert rep.max_steering_rate == pytest.approx(float(rate.max()), rel=1e-6)
    assert rep.executed_max_curvature == pytest.approx(float(np.abs(kappa).max()), rel=1e-6)
    # The logged acceleration is what moved the car (speed linear within a step).
    assert np.allclose(np.diff(states[:, 3]) / log.dt, accel, atol=1e-9)
    assert rep.steps == len(accel) and rep.duration_s == pytest.approx(log.t[-1])
    assert rep.final_speed == pytest.approx(states[-1, 3], rel=1e-6)
    if ep.scenario.name == "overtake-traffic":
        # A straight road driven forward: progress is the projection's arc length.
        s0, s1 = (line.project(shapely.Point(states[i, :2])) for i in (0, -1))
        assert rep.progress_m == pytest.approx(s1 - s0, abs=1e-3)


def test_overtake_ends_at_the_first_logged_step_it_is_complete(traffic_run):
    ep, rep = traffic_run
    log, veh = ep.log, ep.scenario.vehicle
    lead = log.others[:, 0]
    # The first logged vehicle is the lead: in the ego lane, driving +x at ~4 m/s.
    assert abs(lead[0, 1] - 44.0) < 1e-6 and abs(lead[0, 2]) < 1e-6
    assert lead[0, 3] == pytest.approx(4.0, abs=1e-6)
    complete = [
        _overtake_complete(log.states[i], lead[i], log.other_sizes[0, 0], veh)
        for i in range(len(log.t))
    ]
    assert complete[-1] and not any(complete[:-1])
    assert ep.status == "completed" and rep.outcome == "success" and rep.success
    assert rep.completion_time_s == pytest.approx(log.t[-1])
    assert rep.reached_goal and rep.passed_lead and rep.back_in_lane
    # The ego actually used the oncoming lane to pass (body centre beyond the lane line).
    d = veh.length / 2 - veh.rear_overhang
    assert np.max(log.states[:, 1] + d * np.sin(log.states[:, 2])) > 46.0


def test_replan_records_are_consistent_with_the_report(traffic_run):
    ep, rep = traffic_run
    tl = ep.traffic
    times = tl.cycle_times()
    assert rep.replans == len(tl.records) and rep.unsafe_steps == tl.unsafe_steps
    assert rep.replan_time_max_s == pytest.approx(times.max())
    assert rep.replan_time_median_s == pytest.approx(float(np.median(times)))
    assert rep.replans_over_budget == int(np.sum(times > rep.replan_budget_s))
    # Periodic cycles at 4 Hz over the drive.
    periodic = sum(r.trigger == "periodic" for r in tl.records)
    assert abs(periodic - ep.log.t[-1] * 4.0) <= 1.0
    assert tl.completion_time_s == pytest.approx(rep.completion_time_s)
    # The tracked (stitched) path is, at every logged time, the reference then in force.
    line = shapely.LineString(np.asarray(ep.path.samples)[:, :2])
    for t, p in zip(ep.log.t[::10], ep.log.states[::10, :2], strict=True):
        ref = shapely.LineString(np.asarray(tl.reference_at(t).samples)[:, :2])
        assert line.distance(shapely.Point(p)) == pytest.approx(
            ref.distance(shapely.Point(p)), abs=1e-6
        )


def test_replan_conflict_positions_are_in_road_coordinates(traffic_run):
    import re

    ep, _ = traffic_run
    found = 0
    for r in ep.traffic.records:
        m = re.search(r"conflict at \(([-\d.]+), ([-\d.]+)\)", r.message)
        if m is None:
            continue
        found += 1
        ego_x = ep.log.states[int(round(r.t / ep.log.dt)), 0]
        # A conflict on the ego's plan ahead: never far behind the ego on the road.
        assert float(m.group(1)) >= ego_x - 10.0, (r.outcome, r.t, ego_x, r.message)
    assert found


def test_spawned_traffic_follows_docs_and_differs_per_seed(traffic_run):
    ep, _ = traffic_run
    first = ep.log.others[0]
    oncoming = first[1:]
    # Oncoming: lane y = 48 heading -x, speeds U(6, 9), gaps >= 25 m, first >= 40 m ahead.
    assert np.allclose(oncoming[:, 1], 48.0) and np.allclose(np.cos(oncoming[:, 2]), -1.0)
    assert np.all((oncoming[:, 3] >= 6.0) & (oncoming[:, 3] <= 9.0))
    xs = np.sort(oncoming[:, 0])
    assert np.all(np.diff(xs) >= 25.0) and xs[0] - ep.log.states[0, 0] >= 40.0
    assert xs[-1] <= 1300.0
    # high = 20 cars/km: about 25 over the 1.26 km stream.
    assert 15 <= len(xs) <= 40
    scenes = [make_scenario("overtake-traffic", s, density="high") for s in range(6)]
    keys = {(sc.lead, sc.oncoming[:3], sc.start) for sc in scenes}
    assert len(keys) == 6
    again = make_scenario("overtake-traffic", 3, density="high")
    assert again.oncoming == scenes[3].oncoming and again.lead == scenes[3].lead


def test_oncoming_overtake_time_limit_and_arrival(oncoming_run):
    ep, rep = oncoming_run
    assert ep.scenario.max_time_s == pytest.approx(60.0 + 15.0 * 3)
    assert ep.status == "arrived" and rep.success and rep.outcome == "success"
    # The oncoming cars move; the stopped car does not.
    assert np.all(ep.log.others[:, 0, 3] == 0.0)
    assert np.all(ep.log.others[1:, 1:, 0] < ep.log.others[:-1, 1:, 0] + 1e-9)


# --------------------------------------------------------------------------- collisions
def test_rear_ending_the_lead_is_detected_and_at_fault():
    env = gym.make("rrtdrive/OvertakeTraffic-v0", replan_options={"wall_limit": False})
    env.reset(seed=0, options={"episode_seed": 5})
    steps = 0
    while True:
        _, reward, term, trunc, info = env.step(np.array([1.0, 0.0], np.float32))
        steps += 1
        if term or trunc:
            break
    ep = env.unwrapped.episode
    assert term and not trunc and info["status"] == "crashed" and info["crashed"] is True
    assert info["reward_terms"]["collision"] == -50.0 and info["is_success"] is False
    assert np.flatnonzero(ep.log.crashed).tolist() == [len(ep.log.t) - 1]
    mind, hits, ttc = _independent_interaction(ep)
    assert hits == {0: len(ep.log.t) - 1}  # the lead, at the last logged time
    m = info["metrics"]
    assert m["outcome"] == "collision" and m["collision"] and m["collision_footprint"]
    assert m["collisions_vehicles"] == 1 and m["collisions_at_fault"] == 1
    assert m["min_distance_m"] == mind == 0.0 and m["ttc_min_s"] == 0.0
    assert m["ttc_within_bound"] == 0.0
    assert m["duration_s"] == pytest.approx(steps * ep.log.dt)
    # Before contact the independent TTC saw it coming, under nuPlan's bound.
    assert 0.0 < ttc <= 0.95


def test_driving_into_the_oncoming_stream_is_detected():
    env = gym.make(
        "rrtdrive/OvertakeTraffic-v0",
        replan_options={"wall_limit": False},
        scenario_options={"density": 30.0},
    )
    env.reset(seed=0, options={"episode_seed": 4})
    term, trunc, infos = _drive_direct(env, lambda x, u: 48.0, 8.0)
    ep = env.unwrapped.episode
    info = infos[-1][1]
    assert term and info["status"] == "crashed"
    _, hits, _ = _independent_interaction(ep)
    assert len(hits) == 1
    ((j, i),) = hits.items()
    assert j >= 1 and i == len(ep.log.t) - 1  # an oncoming car
    assert ep.log.others[i, j, 1] == pytest.approx(48.0, abs=0.1)
    assert info["metrics"]["collisions_at_fault"] == 1
    assert info["metrics"]["outcome"] == "collision"


def test_overtaking_on_the_shoulder_is_a_footprint_collision_not_a_success():
    env = gym.make(
        "rrtdrive/OvertakeTraffic-v0",
        replan_options={"wall_limit": False},
        scenario_options={"density": 30.0},
    )
    env.reset(seed=0, options={"episode_seed": 2})
    lead = env.unwrapped._road.vehicles[1]

    def target(x, u):
        return 40.5 if x < lead.position[0] + 9.0 else 44.0

    term, _, infos = _drive_direct(env, target, 10.0)
    info = infos[-1][1]
    ep = env.unwrapped.episode
    corners = footprint_corners(np.asarray(ep.log.states[:, :3]), ep.scenario.vehicle)
    assert corners[..., 1].min() < 42.0  # the body left the road (independently)
    assert term and info["status"] == "completed"  # the overtake rule held ...
    m = info["metrics"]
    assert m["reached_goal"] is True and m["collision_highway_env"] is False
    assert m["collision_footprint"] is True and m["collisions_at_fault"] == 1  # ... off-road
    assert m["outcome"] == "collision" and info["is_success"] is False


def test_a_scripted_direct_overtake_completes():
    env = gym.make(
        "rrtdrive/OvertakeTraffic-v0",
        replan_options={"wall_limit": False},
        scenario_options={"density": 0.001},
    )
    env.reset(seed=0, options={"episode_seed": 2})
    lead = env.unwrapped._road.vehicles[1]
    term, trunc, infos = _drive_direct(
        env, lambda x, u: 48.0 if x < lead.position[0] + 9.0 else 44.0, 10.0
    )
    info = infos[-1][1]
    ep = env.unwrapped.episode
    assert term and not trunc and info["status"] == "completed" and info["is_success"] is True
    others = ep.log.others
    assert _overtake_complete(
        ep.log.states[-1], others[-1, 0], ep.log.other_sizes[0, 0], ep.scenario.vehicle
    )
    assert not _overtake_complete(
        ep.log.states[-2], others[-2, 0], ep.log.other_sizes[0, 0], ep.scenario.vehicle
    )
    assert infos[-1][1]["reward_terms"]["success"] == 50.0


# --------------------------------------------------------------------------- CLI
def _cli(args, capsys):
    try:
        code = main(["simulate", *args])
    except SystemExit as exc:  # argparse's own errors
        code = exc.code
    out = capsys.readouterr()
    return code, out.out, out.err


@pytest.mark.parametrize(
    ("args", "field"),
    [
        (["overtake-traffic", "--density", "0"], "--density"),
        (["overtake-traffic", "--density", "31"], "--density"),
        (["overtake-traffic", "--density", "nan"], "--density"),
        (["overtake-traffic", "--density", "heavy"], "--density"),
        (["overtake-traffic", "--lead-speed", "9"], "--lead-speed"),
        (["overtake-traffic", "--lead-speed", "-1"], "--lead-speed"),
        (["overtake-traffic", "--lead-model", "aggressive"], "--lead-model"),
        (["overtake-traffic", "--replan-rate", "6"], "--replan-rate"),
        (["overtake-traffic", "--replan-rate", "1"], "--replan-rate"),
        (["overtake-traffic", "--predictor", "psychic"], "--predictor"),
        (["overtake-traffic", "--max-time", "1000"], "--max-time"),
        (["overtake-traffic", "--plan-time", "5"], "--plan-time"),
        (["overtake-traffic", "--reverse"], "--reverse"),
        (["overtake-traffic", "--oncoming", "2"], "--oncoming"),
        (["overtake", "--oncoming", "11"], "--oncoming"),
        (["overtake", "--density", "5"], "--density"),
        (["parking", "--lead-speed", "2"], "--lead-speed"),
    ],
)
def test_bad_traffic_options_exit_2_naming_the_field(args, field, capsys):
    code, out, err = _cli(args, capsys)
    assert code == 2
    assert out == ""
    assert len(err.strip().splitlines()) == 1 and field in err


def test_max_time_limit_names_the_road_time(capsys):
    code, _, err = _cli(["overtake-traffic", "--lead-speed", "8", "--max-time", "200"], capsys)
    sc = make_scenario("overtake-traffic", 0, lead_speed=8.0)
    assert code == 2 and f"at most {math.floor(sc.road_time_s):d} s" in err


def test_cli_json_is_seed_deterministic_and_seed_dependent(tmp_path, capsys):
    def run(seed, tag):
        js, csv = tmp_path / f"{tag}.json", tmp_path / f"{tag}.csv"
        code, _, _ = _cli(
            [
                "overtake-traffic",
                "--seed",
                str(seed),
                "--density",
                "high",
                "--deterministic",
                "--max-time",
                "6",
                "--json",
                str(js),
                "--trajectory",
                str(csv),
            ],
            capsys,
        )
        return code, json.loads(js.read_text()), csv.read_text()

    (c1, a, ta), (c2, b, tb), (c3, c, tc) = run(11, "a"), run(11, "b"), run(12, "c")
    wall = set(WALL_CLOCK_FIELDS) | {"total_time_s"}
    assert {k for k in a if a[k] != b[k]} <= wall
    assert ta == tb
    assert {k for k in a if a[k] != c[k]} - wall - {"seed"}
    assert ta != tc
    # A 6 s limit without a collision is a timeout, reported as safe following, exit 1.
    assert c1 == c2 == c3 == 1
    assert a["status"] == "timeout" and a["outcome"] == "safe_following"
    assert a["duration_s"] == pytest.approx(6.0) and a["steps"] == 120
    assert a["message"] == "no overtake within 6 s (followed the lead car)"
    assert a["success"] is False and a["completion_time_s"] is None
    # The CLI drove exactly the episode the API drives for the same seed and options.
    sc = make_scenario("overtake-traffic", 11, density="high")
    ep = run_episode(sc, seed=11, config=EpisodeConfig(replan=SEED_ONLY, max_time_s=6.0))
    rows = np.loadtxt(tmp_path / "a.csv", delimiter=",", skiprows=1)
    assert np.array_equal(rows[:, 1:5], ep.log.states)
    assert np.array_equal(rows[:-1, 5:7], ep.log.controls[:, ::-1])
    assert a["min_distance_m"] == pytest.approx(_independent_interaction(ep)[0], rel=1e-5)


def test_cli_json_records_the_predictor(tmp_path, capsys):
    js = tmp_path / "p.json"
    code, _, _ = _cli(
        [
            "overtake-traffic",
            "--seed",
            "1",
            "--deterministic",
            "--max-time",
            "0.5",
            "--predictor",
            "lane-following",
            "--json",
            str(js),
        ],
        capsys,
    )
    assert code == 1
    data = json.loads(js.read_text())
    assert "lane-following" in data.values()


def test_episode_plot_shows_the_car_being_followed():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from rrtdrive.sim.episode_plot import plot_episode

    sc = make_scenario("overtake-traffic", 4, density=30.0)
    ep = run_episode(sc, seed=4, config=EpisodeConfig(replan=SEED_ONLY, max_time_s=20.0))
    assert ep.status == "timeout"  # followed the lead for 20 s
    lead_x, lead_len = ep.log.others[-1, 0, 0], ep.log.other_sizes[0, 0]
    assert 8.0 < lead_x - ep.log.states[-1, 0] < 25.0  # following at a normal gap
    fig = plot_episode(ep)
    try:
        lo, hi = fig.axes[0].get_xlim()
    finally:
        plt.close(fig)
    assert lo <= lead_x + lead_len / 2 and lead_x - lead_len / 2 <= hi


# --------------------------------------------------------------------------- gym
@pytest.mark.parametrize(
    ("env_id", "kwargs"),
    [
        (
            "rrtdrive/OvertakeTraffic-v0",
            {"residual": True, "replan_options": {"wall_limit": False}},
        ),
        (
            "rrtdrive/OvertakeTraffic-v0",
            {"residual": False, "n_vehicles": 2, "replan_options": {"wall_limit": False}},
        ),
        ("rrtdrive/Overtake-v0", {"residual": True, "scenario_options": {"oncoming": 2}}),
        (
            "rrtdrive/Overtake-v0",
            {"residual": False, "n_vehicles": 3, "scenario_options": {"oncoming": 2}},
        ),
    ],
)
def test_traffic_envs_pass_check_env(env_id, kwargs):
    env = gym.make(env_id, **kwargs)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_env(env.unwrapped, skip_render_check=True)


def test_gym_info_keys_and_values_match_docs_and_log():
    env = gym.make(
        "rrtdrive/OvertakeTraffic-v0",
        residual=True,
        n_vehicles=3,
        n_ref_points=2,
        replan_options={"wall_limit": False},
        max_time_s=4.0,
    )
    obs, info0 = env.reset(seed=0, options={"episode_seed": 7})
    assert set(info0) == {"episode_seed", "scenario", "path_length_m"}
    assert info0["episode_seed"] == 7 and info0["scenario"] == "overtake-traffic"
    observations, infos = [obs], []
    while True:
        obs, _, term, trunc, info = env.step(np.zeros(2, np.float32))
        observations.append(obs)
        infos.append(info)
        if term or trunc:
            break
    every = {
        "episode_seed",
        "time_s",
        "cte_m",
        "heading_err_rad",
        "speed",
        "v_ref",
        "accel",
        "steer",
        "crashed",
        "reward_terms",
    }
    assert all(set(i) == every for i in infos[:-1])
    assert set(infos[-1]) == every | {"status", "is_success", "metrics"}
    assert trunc and not term and infos[-1]["status"] == "timeout"
    ep = env.unwrapped.episode
    log = ep.log
    for k, i in enumerate(infos):
        assert i["time_s"] == pytest.approx(log.t[k + 1])
        assert i["accel"] == log.controls[k, 0] and i["steer"] == log.controls[k, 1]
        assert i["speed"] == pytest.approx(log.states[k + 1, 3])
        assert i["crashed"] is bool(log.crashed[k + 1])
    fields = {f.name for f in dataclasses.fields(EpisodeReport)}
    assert set(infos[-1]["metrics"]) == fields - set(WALL_CLOCK_FIELDS)
    assert infos[-1]["metrics"]["outcome"] == "safe_following"
    # The observed vehicles, recomputed from the log in the rear-axle frame.
    names = rrtdrive.envs.observation.observation_names(2, 3)
    j0 = names.index("veh_present_1")
    for k, o in enumerate(observations):
        x, y, h, v = log.states[k]
        c, s = math.cos(h), math.sin(h)
        dx, dy = log.others[k, :, 0] - x, log.others[k, :, 1] - y
        dist = np.hypot(dx, dy)
        order = [j for j in np.argsort(dist, kind="stable") if dist[j] <= 100.0][:3]
        want = np.zeros(15)
        for m, j in enumerate(order):
            vx = log.others[k, j, 3] * math.cos(log.others[k, j, 2]) - v * c
            vy = log.others[k, j, 3] * math.sin(log.others[k, j, 2]) - v * s
            want[5 * m : 5 * m + 5] = [
                1.0,
                c * dx[j] + s * dy[j],
                -s * dx[j] + c * dy[j],
                c * vx + s * vy,
                -s * vx + c * vy,
            ]
        assert np.allclose(o[j0 : j0 + 15], want, atol=1e-4)


def test_gym_zero_residual_reproduces_run_episode():
    env = gym.make(
        "rrtdrive/OvertakeTraffic-v0",
        residual=True,
        replan_options={"wall_limit": False},
        max_time_s=5.0,
    )
    env.reset(seed=0, options={"episode_seed": 9})
    while True:
        *_, term, trunc, _ = env.step(np.zeros(2, np.float32))
        if term or trunc:
            break
    gym_log = env.unwrapped.episode.log
    sc = make_scenario("overtake-traffic", 9)
    ep = run_episode(sc, seed=9, config=EpisodeConfig(replan=SEED_ONLY, max_time_s=5.0))
    assert np.array_equal(gym_log.states, ep.log.states)
    assert np.array_equal(gym_log.others, ep.log.others)
    assert np.array_equal(gym_log.controls, ep.log.controls)
