"""Evaluators on hand-made episodes with known answers."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rrtdrive.evaluation import (
    EvalConfig,
    evaluate,
    summarise,
    tracking_errors,
)
from rrtdrive.geometry import densify
from rrtdrive.sim.episode import DriveLog, Episode
from rrtdrive.sim.runner import EpisodeConfig
from rrtdrive.sim.tasks import make_scenario
from rrtdrive.types import InputError, Path, VehicleParams

V = VehicleParams()
DT = 0.05


def _episode(scen, path, states, controls, crashed=None, status="arrived", others=None, sizes=None):
    states = np.asarray(states, float)
    n = len(states)
    log = DriveLog(
        dt=DT,
        t=np.arange(n) * DT,
        states=states,
        controls=np.asarray(controls, float).reshape(-1, 2),
        crashed=np.zeros(n, bool) if crashed is None else np.asarray(crashed, bool),
        others=np.zeros((n, 0, 4)) if others is None else np.asarray(others, float),
        other_sizes=np.zeros((0, 2)) if sizes is None else np.asarray(sizes, float),
        arrived=status == "arrived",
        wall_time_s=0.01,
    )
    return Episode(
        scen, "given", "pure-pursuit", scen.seed, None, path, log, status, "", EpisodeConfig()
    )


def _lane_path(scen, x_end=92.0):
    x = np.arange(scen.start.x, x_end + 1e-9, 0.1)
    y = np.full_like(x, scen.lane_y)
    return Path(np.column_stack([x, y, 0 * x, 0 * x]), np.zeros((0, 2)))


@pytest.fixture(scope="module")
def overtake():
    return make_scenario("overtake", 0, jitter=(0.0, 0.0, 0.0))


def test_tracking_errors_signed_and_heading():
    xs = np.linspace(0.0, 10.0, 101)
    p = Path(np.column_stack([xs, 0 * xs, 0 * xs, 0 * xs]), np.zeros((0, 2)))
    cte, he = tracking_errors(p, np.array([[1.0, 0.2, 0.0], [5.0, -0.3, 0.1], [12.0, 0.0, 0.0]]))
    assert cte == pytest.approx([0.2, -0.3, 2.0])  # past the end: distance to the end point
    assert he == pytest.approx([0.0, 0.1, 0.0])
    th = np.linspace(0, math.pi, 400)
    arc = Path(np.column_stack([10 * np.sin(th), 10 * (1 - np.cos(th)), th, np.full_like(th, 0.1)]),
               np.zeros((0, 2)))
    cte, _ = tracking_errors(arc, np.array([[10.5, 10.0, math.pi / 2]]))  # outside: right
    assert cte[0] == pytest.approx(-0.5, abs=1e-3)


def test_densify():
    poses = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.2]])
    d = densify(poses, 0.1, angle_column=2, abs_slack=1e-9).points
    assert len(d) == 11 and np.max(np.diff(d[:, 0])) <= 0.1 + 1e-12
    assert d[5, 2] == pytest.approx(0.1)


def test_metrics_of_a_known_trajectory(overtake):
    path = _lane_path(overtake, 30.0)
    n = 101
    x = np.linspace(overtake.start.x, 30.0, n)
    offset = 0.1 * np.sin(np.linspace(0, math.pi, n))  # left of the path, 0.1 m at most
    v = np.linspace(2.0, 0.0, n)
    states = np.column_stack([x, overtake.lane_y + offset, np.zeros(n), v])
    steer = np.full(n - 1, math.atan(V.wheelbase * 0.1))
    steer[10] = math.atan(V.wheelbase * 0.2)  # one step over kappa_max
    controls = np.column_stack([np.full(n - 1, -0.4), steer])
    scen = overtake.__class__(**{**overtake.__dict__, "map": overtake.map.with_query(
        goal=overtake.map.goal.__class__(30.0, overtake.lane_y, 0.0))})
    ep = _episode(scen, path, states, controls)
    r = evaluate(ep)
    assert r.cte_max_m == pytest.approx(0.1, abs=1e-4)
    assert r.cte_rms_m == pytest.approx(np.sqrt(np.mean(offset**2)), rel=1e-6)
    assert r.heading_err_max_rad == pytest.approx(0.0)
    assert r.executed_max_curvature == pytest.approx(0.2)
    assert r.executed_curvature_violation_share == pytest.approx(1 / (n - 1))
    assert r.max_lateral_accel == pytest.approx(max(v[:-1] ** 2 * np.tan(steer) / V.wheelbase))
    # Steering rate: the jump to 0.2 and back, over one step.
    jump = (math.atan(V.wheelbase * 0.2) - math.atan(V.wheelbase * 0.1)) / DT
    assert r.max_steering_rate == pytest.approx(max(jump, math.atan(V.wheelbase * 0.1) / DT))
    assert r.goal_position_err_m == pytest.approx(0.0, abs=1e-9)
    assert r.stopped and r.reached_goal and not r.collision
    assert r.passed_lead is False  # it stopped before the lead car at x = 50
    assert not r.success
    assert r.duration_s == pytest.approx((n - 1) * DT) and r.steps == n - 1
    js = r.to_json()
    assert js["seed"] == 0 and isinstance(js["cte_max_m"], float)


def test_both_collision_judges_are_reported_separately(overtake):
    path = _lane_path(overtake)
    # Straight through the stopped car at x = 50.
    x = np.arange(overtake.start.x, 60.0, 0.2)
    states = np.column_stack([x, np.full_like(x, overtake.lane_y), 0 * x, np.full_like(x, 4.0)])
    controls = np.zeros((len(x) - 1, 2))
    r = evaluate(_episode(overtake, path, states, controls, status="timeout"))
    assert r.collision_footprint and not r.collision_highway_env and r.collision
    crashed = np.zeros(len(x), bool)
    crashed[-1] = True
    short = states[:20]
    r2 = evaluate(_episode(overtake, path, short, controls[:19], crashed=crashed[-20:],
                           status="crashed"))
    assert r2.collision_highway_env and not r2.collision_footprint and not r2.success


def test_a_parked_car_that_is_both_obstacle_and_vehicle_counts_once(overtake):
    # The overtake's stopped car is a map obstacle for the planner and logged vehicle 0.
    lead = overtake.map.obstacles[overtake.lead_index]
    path = _lane_path(overtake)
    x = np.arange(overtake.start.x, 48.0, 0.2)
    states = np.column_stack([x, np.full_like(x, overtake.lane_y), 0 * x, np.full_like(x, 4.0)])
    others = np.zeros((len(x), 1, 4))
    others[:, 0, :2] = lead.center
    others[:, 0, 2] = lead.yaw
    args = dict(status="crashed", others=others, sizes=[lead.size])
    r = evaluate(_episode(overtake, path, states, np.zeros((len(x) - 1, 2)), **args))
    assert r.collisions_vehicles == 1 and r.collisions_at_fault == 1  # was 2
    # Into the car and on into the road's edge: two collisions, both at fault.
    y = np.linspace(overtake.lane_y, overtake.lane_y - 3.0, 16)
    edge = np.vstack([states, np.column_stack([x[-1] + 0 * y, y, 0 * y, 0 * y + 1.0])])
    others = np.concatenate([others, others[-16:]])
    args["others"] = others
    r = evaluate(_episode(overtake, path, edge, np.zeros((len(edge) - 1, 2)), **args))
    assert r.collisions_vehicles == 1 and r.collisions_at_fault == 2


def test_footprint_judge_sees_moving_vehicles(overtake):
    path = _lane_path(overtake, 40.0)
    x = np.linspace(overtake.start.x, 20.0, 50)
    states = np.column_stack([x, np.full_like(x, overtake.lane_y), 0 * x, np.full_like(x, 3.0)])
    controls = np.zeros((49, 2))
    # An oncoming car driving straight through the ego's lane position at step 30.
    cx = states[:, 0] + 1.255
    others = np.zeros((50, 1, 4))
    others[:, 0, 0] = cx[30]
    others[:, 0, 1] = overtake.lane_y + 4.0
    others[30, 0, 1] = overtake.lane_y
    r = evaluate(_episode(overtake, path, states, controls, status="timeout", others=others,
                          sizes=[[4.3, 1.8]]))
    assert r.collision_footprint


def test_success_of_a_clean_overtake(overtake):
    path = _lane_path(overtake)
    # A fake but clean trajectory: along the oncoming lane past the car, back, stop at the goal.
    x = np.arange(overtake.start.x, 92.0 + 1e-9, 0.2)
    y = np.where((x > 30) & (x < 70), overtake.lane_y + 4.0, overtake.lane_y)
    states = np.column_stack([x, y, 0 * x, np.append(np.full(len(x) - 1, 3.0), 0.0)])
    r = evaluate(_episode(overtake, path, states, np.zeros((len(x) - 1, 2))))
    assert r.passed_lead and r.back_in_lane and r.success
    assert r.time_to_goal_s == pytest.approx(r.duration_s)
    s = summarise([r, r])
    assert s["success_rate"] == 1.0 and s["collisions_footprint"] == 0
    assert s["cte_max_m_max"] == pytest.approx(4.0)


def test_plan_failure_report(overtake):
    log = DriveLog.empty(DT)
    ep = Episode(overtake, "rrt", "lqr", 0, None, Path.empty(), log, "plan_failed", "x",
                 EpisodeConfig())
    r = evaluate(ep)
    assert not r.success and r.cte_rms_m is None and r.steps == 0
    assert r.to_json()["cte_rms_m"] is None


def test_config_validation():
    with pytest.raises(InputError, match="goal_tol_m"):
        EvalConfig(goal_tol_m=0.0)
    with pytest.raises(InputError, match="reports"):
        summarise([])


# ------------------------------------------------------------------ seams of the package


def test_the_metric_table_fills_every_report_field():
    from dataclasses import fields

    from rrtdrive.evaluation import METRICS, EpisodeReport

    assert set(METRICS) == {f.name for f in fields(EpisodeReport)}


def test_outcome_is_an_enum_with_the_json_strings(overtake):
    import json

    from rrtdrive.evaluation import OUTCOMES, EpisodeReport, Outcome

    assert OUTCOMES == ("success", "collision", "safe_following", "failed")
    log = DriveLog.empty(DT)
    ep = Episode(overtake, "rrt", "lqr", 0, None, Path.empty(), log, "plan_failed", "x",
                 EpisodeConfig())
    r = evaluate(ep)
    assert r.outcome is Outcome.FAILED and r.outcome == "failed" and f"{r.outcome}" == "failed"
    js = r.to_json()
    assert type(js["outcome"]) is str and json.loads(json.dumps(js))["outcome"] == "failed"
    back = EpisodeReport(**js)  # read back from JSON
    assert back.outcome is Outcome.FAILED
    with pytest.raises(InputError, match="outcome"):
        EpisodeReport(**{**js, "outcome": "won"})


def test_boxes_intersect_with_shapely():
    from rrtdrive.evaluation.collisions import boxes_intersect
    from rrtdrive.geometry import box_corners

    z = np.zeros(4)
    a = box_corners(z, z, z, -1.0, 1.0, 1.0)  # centred 2 m x 2 m boxes
    b = box_corners(np.array([1.5, 2.0, 2.5, 2.1]), z, np.array([0.0, 0.0, 0.0, math.pi / 4]),
                    -1.0, 1.0, 1.0)
    # Overlapping, touching (counts), apart, and a rotated box whose corner reaches in.
    assert boxes_intersect(a, b).tolist() == [True, True, False, True]
    assert boxes_intersect(a[:1][:, None], b[None]).shape == (1, 4)



def test_success_terms_of_a_clean_overtake(overtake):
    from rrtdrive.evaluation import success_terms

    path = _lane_path(overtake)
    x = np.arange(overtake.start.x, 92.0 + 1e-9, 0.2)
    y = np.where((x > 30) & (x < 70), overtake.lane_y + 4.0, overtake.lane_y)
    states = np.column_stack([x, y, 0 * x, np.append(np.full(len(x) - 1, 3.0), 0.0)])
    terms = success_terms(_episode(overtake, path, states, np.zeros((len(x) - 1, 2))))
    assert terms.success and terms.lead_required and terms.outcome == "success"
    assert terms.passed_lead and terms.back_in_lane and terms.in_time and not terms.collision


def test_summarise_intervals(overtake):
    from rrtdrive.stats import wilson_interval

    path = _lane_path(overtake)
    x = np.arange(overtake.start.x, 92.0 + 1e-9, 0.2)
    y = np.where((x > 30) & (x < 70), overtake.lane_y + 4.0, overtake.lane_y)
    states = np.column_stack([x, y, 0 * x, np.append(np.full(len(x) - 1, 3.0), 0.0)])
    r = evaluate(_episode(overtake, path, states, np.zeros((len(x) - 1, 2))))
    s = summarise([r, r, r])
    assert s["success_rate_ci95"] == list(wilson_interval(3, 3))
    lo, hi = s["cte_max_m_ci95"]
    assert lo == hi == pytest.approx(4.0)  # identical values: a point interval
    assert s["ttc_min_s_min"] is None and s["replan_time_max_s_ci95"] is None
    assert summarise([r])["cte_rms_m_ci95"] is None
    # A failed plan is no drive: its 0 s duration is not averaged in; it is counted.
    failed = evaluate(Episode(overtake, "rrt", "lqr", 0, None, Path.empty(),
                              DriveLog.empty(DT), "plan_failed", "x", EpisodeConfig()))
    both = summarise([r, failed])
    assert both["duration_s_mean"] == pytest.approx(r.duration_s)
    assert both["plan_failures"] == 1 and both["episodes"] == 2
    assert both["max_long_accel_mean"] == r.max_long_accel
    assert both["nuplan_comfortable"] == int(bool(r.nuplan_comfortable))


def test_success_terms_say_which_term_failed(overtake):
    from dataclasses import replace

    from rrtdrive.evaluation import failure_reason, success_terms

    path = _lane_path(overtake)
    x = np.arange(overtake.start.x, 92.0 + 1e-9, 0.2)
    y = np.where((x > 30) & (x < 70), overtake.lane_y + 4.0, overtake.lane_y)
    states = np.column_stack([x, y, 0 * x, np.append(np.full(len(x) - 1, 3.0), 0.0)])
    ep = _episode(overtake, path, states, np.zeros((len(x) - 1, 2)))
    terms = success_terms(ep)
    assert terms.success and terms.lead_required and terms.outcome == "success"
    r = evaluate(ep)
    assert failure_reason(r) is None
    bad = replace(r, success=False, reached_goal=False, goal_heading_err_rad=math.radians(12.0),
                  outcome="failed")
    assert failure_reason(bad) == "arrived, but the heading error 12.0 deg exceeds 10 deg"
    far = replace(bad, goal_position_err_m=0.62, stopped=False, final_speed=0.3)
    assert failure_reason(far) == (
        "arrived, but the position error 0.62 m exceeds 0.5 m; the heading error 12.0 deg "
        "exceeds 10 deg; the final speed 0.30 m/s exceeds 0.1 m/s"
    )
    crash = replace(r, success=False, collision=True, collision_footprint=True,
                    status="timeout", outcome="collision")
    assert failure_reason(crash) == "timeout: a collision reported by the footprint judge"
    crashed = replace(crash, status="crashed", collision_highway_env=True)
    assert failure_reason(crashed) == (
        "crashed: a collision reported by highway-env and the footprint judge"
    )
    # A final speed a hair over the bound reads as over it ("0.10 m/s exceeds 0.1" did not).
    slow = replace(bad, goal_heading_err_rad=0.0, stopped=False, final_speed=0.1026)
    assert failure_reason(slow) == "arrived, but the final speed 0.103 m/s exceeds 0.1 m/s"

