"""Audit (session 48): drivability of closed-loop episodes on tight maps and scenarios.

Each episode is driven through ``rrtdrive simulate`` (in-process, ``--json`` and
``--trajectory``) and judged here, independently of the evaluators, from the trajectory
file: the steering rate against the 0.4 rad/s actuator, the executed curvature against
kappa_max, every gear change driven through a standstill at a path cusp, the goal
errors within 0.5 m / 10 deg, the body (shapely, densified to 5 cm) clear of every map
obstacle and inside the bounds, and the report's own figures equal to the file's.
User maps: a bay entered in reverse, a three-point turn in a 9 m street, parallel
parking into a gap of 1.5 car lengths.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from shapely.geometry import Polygon, box
from shapely.ops import unary_union

import rrtdrive.sim.runner as runner
from rrtdrive.cli import main
from rrtdrive.maps import load_map
from rrtdrive.types import VehicleParams

CAR = VehicleParams()
TIMING = {
    "total_time_s", "wall_time_s", "planning_time_s", "setup_time_s",
    "replan_time_median_s", "replan_time_max_s", "replans_over_budget",
}


def _user_maps(d):
    """Write the three user maps; returns name -> path."""
    length, width, rear = CAR.length, CAR.width, CAR.rear_overhang
    to_centre = length / 2 - rear
    bay = [
        {"center": [x, 2.5], "size": [length, width], "yaw": math.pi / 2}
        for x in (7.5, 10.0, 12.5, 17.5, 20.0, 22.5)
    ]
    x_behind, gap = 20.0, 1.5 * length
    row = [
        {"center": [x_behind - length / 2 - i * (length + 1), 1.2], "size": [length, width],
         "yaw": 0.0} for i in range(3)
    ] + [
        {"center": [x_behind + gap + length / 2 + i * (length + 1), 1.2],
         "size": [length, width], "yaw": 0.0} for i in range(3)
    ]
    maps = {
        # Backed into a bay between parked cars: the goal faces out of it.
        "rev_bay": {"name": "rev_bay", "bounds": [0, 0, 30, 12], "obstacles": bay,
                    "start": [3, 8.5, 0], "goal": [15, 2.5 - to_centre, math.pi / 2]},
        # A 9 m street (the bounds are its walls): a forward U-turn needs 14.65 m.
        "uturn9": {"name": "uturn9", "bounds": [0, 0, 40, 9], "obstacles": [],
                   "start": [20, 6.75, 0], "goal": [20, 2.25, math.pi]},
        # Parallel parking: a gap of 1.5 car lengths, 0.3 m ahead of the car behind.
        "parallel15": {"name": "parallel15", "bounds": [0, 0, 50, 7.5], "obstacles": row,
                       "start": [3, 5.0, 0], "goal": [x_behind + 0.3 + rear, 1.2, 0.0]},
    }
    out = {}
    for name, data in maps.items():
        path = d / f"{name}.json"
        path.write_text(json.dumps(data))
        out[name] = str(path)
    return out


@pytest.fixture(scope="module")
def user_maps(tmp_path_factory):
    return _user_maps(tmp_path_factory.mktemp("maps"))


@pytest.fixture
def simulate(tmp_path, monkeypatch, capsys):
    """Run ``rrtdrive simulate ARGS`` in-process: (exit code, report, trajectory, episode)."""
    seen = {}
    real = runner.run_episode

    def spy(*a, **k):
        seen["episode"] = real(*a, **k)
        return seen["episode"]

    monkeypatch.setattr(runner, "run_episode", spy)
    count = [0]

    def run(*args):
        count[0] += 1
        js, csv = tmp_path / f"r{count[0]}.json", tmp_path / f"r{count[0]}.csv"
        seen.clear()
        rc = main(["simulate", *args, "--json", str(js), "--trajectory", str(csv)])
        capsys.readouterr()
        report = json.loads(js.read_text())
        rows = np.loadtxt(csv, delimiter=",", skiprows=1, ndmin=2)
        return rc, report, rows, seen.get("episode"), csv.read_text()

    return run


def _body(x, y, yaw):
    c, s = math.cos(yaw), math.sin(yaw)
    corners = [(-CAR.rear_overhang, -CAR.width / 2), (CAR.front_extent, -CAR.width / 2),
               (CAR.front_extent, CAR.width / 2), (-CAR.rear_overhang, CAR.width / 2)]
    return Polygon([(x + c * px - s * py, y + s * px + c * py) for px, py in corners])


def _rect(o):
    (cx, cy), (ln, wd), yaw = o.center, o.size, o.yaw
    c, s = math.cos(yaw), math.sin(yaw)
    corners = [(-ln / 2, -wd / 2), (ln / 2, -wd / 2), (ln / 2, wd / 2), (-ln / 2, wd / 2)]
    return Polygon([(cx + c * px - s * py, cy + s * px + c * py) for px, py in corners])


def _footprint_clear(rows, m):
    """The body at every logged pose, densified to 5 cm, clear of the map and inside it."""
    obstacles = unary_union([_rect(o) for o in m.obstacles]) if m.obstacles else None
    inside = box(*m.bounds)
    for a, b in zip(rows[:-1, 1:4], rows[1:, 1:4], strict=True):
        n = max(1, math.ceil(math.hypot(*(b[:2] - a[:2])) / 0.05))
        dyaw = (b[2] - a[2] + math.pi) % (2 * math.pi) - math.pi
        for f in np.arange(1, n + 1) / n:
            body = _body(a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1]), a[2] + f * dyaw)
            if not inside.contains(body):
                return False
            if obstacles is not None and body.intersection(obstacles).area > 1e-9:
                return False
    return True


def _gear_flips(speed):
    """(number of driven gear changes, how many went without a standstill, stop rows)."""
    sign = np.sign(speed)
    moving = np.flatnonzero(sign != 0)
    flips = [(a, b) for a, b in zip(moving[:-1], moving[1:], strict=True) if sign[a] != sign[b]]
    return len(flips), sum(b == a + 1 for a, b in flips), [a + 1 for a, _ in flips]


def _check_drivable(rc, rep, rows, episode, vehicle=CAR):
    task = episode.scenario
    dt = 1.0 / rep["simulation_frequency"]
    assert rep["status"] == "arrived" and rep["success"] and rc == 0, rep["message"]
    assert not rep["collision_highway_env"] and not rep["collision_footprint"]
    # The trajectory file is the report's episode.
    assert len(rows) == rep["steps"] + 1
    assert rows[-1, 0] == pytest.approx(rep["duration_s"], rel=1e-6)
    assert rows[0, 1:3] == pytest.approx([task.start.x, task.start.y], abs=1e-9)
    dyaw = (rows[0, 3] - task.start.yaw + math.pi) % (2 * math.pi) - math.pi  # yaw may wrap
    assert abs(dyaw) < 1e-9
    assert rows[-1, 4] == pytest.approx(rep["final_speed"], abs=1e-6)
    # Actuator: steering rate (from straight wheels) and executed curvature.
    steer = rows[:-1, 5]
    rate = np.abs(np.diff(np.concatenate([[0.0], steer]))) / dt
    assert rate.max() <= vehicle.max_steer_rate + 1e-9
    assert rate.max() == pytest.approx(rep["max_steering_rate"], rel=1e-5)
    kappa = np.abs(np.tan(steer)) / vehicle.wheelbase
    assert kappa.max() <= vehicle.kappa_max * (1 + 1e-9)
    assert kappa.max() == pytest.approx(rep["executed_max_curvature"], rel=1e-5)
    assert rep["steering_rate_over_limit_share"] == 0.0
    assert rep["executed_curvature_violation_share"] == 0.0
    # Gear changes: each through a standstill, at a cusp of the tracked path.
    flips, unstopped, stops = _gear_flips(rows[:, 4])
    assert unstopped == 0
    assert flips == rep["gear_changes"] == rep["path_cusps"] == len(episode.path.cusps)
    moving = rows[:, 4] != 0
    assert np.all(rows[moving, 7] == np.sign(rows[moving, 4]))
    cusp_xy = episode.path.samples[episode.path.cusps, :2]
    for k in stops:
        assert np.min(np.hypot(*(cusp_xy - rows[k, 1:3]).T)) < 0.05
    # Goal errors from the file: the report's, within the documented tolerances.
    goal = task.goal
    pos = math.hypot(rows[-1, 1] - goal.x, rows[-1, 2] - goal.y)
    head = abs((rows[-1, 3] - goal.yaw + math.pi) % (2 * math.pi) - math.pi)
    assert pos == pytest.approx(rep["goal_position_err_m"], rel=1e-5, abs=1e-7)
    assert head == pytest.approx(rep["goal_heading_err_rad"], rel=1e-5, abs=1e-7)
    assert pos <= 0.5 and head <= math.radians(10) and abs(rows[-1, 4]) <= 0.1
    # Tracking: a tight manoeuvre followed within centimetres.
    assert rep["cte_max_m"] < 0.1 and rep["heading_err_max_rad"] < math.radians(5)
    assert rep["progress_m"] == pytest.approx(rep["path_length_m"], abs=0.05)
    # An outside footprint judge.
    assert _footprint_clear(rows, task.map)


@pytest.mark.parametrize(
    "target, controller, cusps_at_least",
    [("uturn9", "lqr", 1), ("parallel15", "stanley", 1), ("rev_bay", "pure-pursuit", 1)],
)
def test_user_tight_maps_drive_with_gears(simulate, user_maps, target, controller,
                                          cusps_at_least):
    rc, rep, rows, ep, _ = simulate(user_maps[target], "--reverse", "--controller", controller)
    _check_drivable(rc, rep, rows, ep)
    assert rep["gear_changes"] >= cusps_at_least
    assert rep["target"] == "map" and rep["reverse"] is True


@pytest.mark.parametrize(
    "args",
    [
        ("dead_end", "--reverse", "--controller", "stanley"),
        ("kerbside", "--reverse", "--controller", "lqr"),
        ("u-turn", "--controller", "pure-pursuit", "--seed", "1"),
        ("parallel-parking", "--controller", "lqr", "--seed", "2"),
        ("parking", "--reverse-in", "--controller", "lqr", "--seed", "1"),
    ],
)
def test_builtin_tight_drives(simulate, args):
    rc, rep, rows, ep, _ = simulate(*args)
    _check_drivable(rc, rep, rows, ep)
    assert rep["gear_changes"] >= 1


def test_same_seed_twice_identical(simulate):
    rc1, rep1, _, _, csv1 = simulate("u-turn", "--controller", "stanley", "--seed", "5")
    rc2, rep2, _, _, csv2 = simulate("u-turn", "--controller", "stanley", "--seed", "5")
    assert rc1 == rc2 == 0
    strip = [{k: v for k, v in r.items() if k not in TIMING} for r in (rep1, rep2)]
    assert strip[0] == strip[1]
    assert csv1 == csv2


def test_max_time_at_the_arrival(simulate, user_maps):
    """A limit one step short of the arrival times out; the arrival time itself arrives."""
    rc, rep, _, _, _ = simulate(user_maps["uturn9"], "--reverse", "--controller", "lqr")
    assert rc == 0
    t_arrive, dt = rep["duration_s"], 1.0 / rep["simulation_frequency"]
    rc, short, rows, _, _ = simulate(user_maps["uturn9"], "--reverse", "--controller", "lqr",
                                     "--max-time", f"{t_arrive - dt:.6f}")
    assert rc == 1 and short["status"] == "timeout" and not short["success"]
    assert short["outcome"] == "failed" and rows[-1, 0] <= t_arrive - dt + 1e-9
    rc, exact, _, _, _ = simulate(user_maps["uturn9"], "--reverse", "--controller", "lqr",
                                  "--max-time", f"{t_arrive:.6f}")
    assert rc == 0 and exact["status"] == "arrived"


def test_forward_only_nine_metre_street_fails_with_the_u_turn_diagnosis(tmp_path, user_maps,
                                                                         capsys):
    js, csv = tmp_path / "f.json", tmp_path / "f.csv"
    rc = main(["simulate", user_maps["uturn9"], "--max-iterations", "2000", "--json", str(js),
               "--trajectory", str(csv)])
    err = capsys.readouterr().err
    rep = json.loads(js.read_text())
    assert rc == 1 and rep["status"] == "plan_failed" and rep["steps"] == 0
    # The trajectory file has its header only, and stderr says why.
    assert len(csv.read_text().splitlines()) == 1
    assert "--trajectory: nothing was driven (the plan failed)" in err
    assert rep["diagnosis"]["kind"] == "u_turn" and "--reverse" in rep["diagnosis"]["message"]
    assert rep["diagnosis"]["numbers"]["street_width_m"] == pytest.approx(9.0, abs=0.1)


def test_slower_steering_actuator_respected(user_maps):
    """A car whose wheels turn at 0.2 rad/s: the controllers keep to its own limit."""
    import dataclasses

    from rrtdrive.evaluation import evaluate
    from rrtdrive.sim.tasks import CustomTask

    car = VehicleParams(max_steer_rate=0.2)
    m = dataclasses.replace(load_map(user_maps["uturn9"]), vehicle=car)
    ep = runner.run_episode(CustomTask.from_map(m, reverse=True), controller="pure-pursuit")
    rep = evaluate(ep)
    assert rep.success and rep.gear_changes >= 1
    steer = ep.log.controls[:, 1]
    rate = np.abs(np.diff(np.concatenate([[0.0], steer]))) / ep.log.dt
    assert rate.max() <= 0.2 + 1e-9
    assert rate.max() == pytest.approx(0.2, rel=1e-6)  # it does use the actuator fully


def test_commonroad_judge_accepts_a_three_point_turn(user_maps):
    pytest.importorskip("commonroad_dc")
    from rrtdrive.commonroad_judge import judge_trajectory
    from rrtdrive.sim.tasks import CustomTask

    ep = runner.run_episode(
        CustomTask.from_map(load_map(user_maps["uturn9"]), reverse=True), controller="lqr"
    )
    log = ep.log
    verdict = judge_trajectory(log.t, log.states, log.controls[:, 1], log.controls[:, 0])
    assert verdict.feasible and verdict.inputs_feasible, verdict.why
    assert verdict.max_steer_rate <= 0.4 + 1e-9
    assert verdict.max_position_drift_m < 0.01
    assert np.any(log.states[:, 3] < 0)  # it judged reverse driving too
