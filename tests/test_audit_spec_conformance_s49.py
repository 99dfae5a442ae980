"""SPEC conformance audit (session 49): one small check per concrete SPEC statement.

Each test names the SPEC section it checks and recomputes what SPEC says from the
public API or the ``rrtdrive`` CLI (run in-process through ``rrtdrive.cli.main``), with
small budgets. Statements that other test files already cover thoroughly (bad-input
messages, determinism, timeouts, nuPlan thresholds, check_env, CSV export, ...) are
left to them.
"""

from __future__ import annotations

import contextlib
import dataclasses
import io
import json
import math

import numpy as np
import pytest
import shapely

from rrtdrive import Budget, Map, Obstacle, Pose, VehicleParams, builtin_map
from rrtdrive.cli import main
from rrtdrive.planning import PlanningProblem, make_planner
from rrtdrive.types import PlanStatus

KAPPA_MAX = 1.0 / 6.0


def _run(*argv: str) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = main(list(argv))
        except SystemExit as exc:  # argparse's --help
            code = int(exc.code or 0)
    return code, out.getvalue(), err.getvalue()


def _plan_json(*argv: str) -> tuple[int, dict]:
    code, out, _ = _run("plan", *argv, "--json", "-")
    return code, json.loads(out)


def _wrap(a: np.ndarray | float) -> np.ndarray | float:
    return (np.asarray(a) + np.pi) % (2.0 * np.pi) - np.pi


# ------------------------------------------------------------------ §1 the vehicle


def _spec_body(x: float, y: float, yaw: float) -> shapely.Polygon:
    """SPEC §1 independently: 0.895 m behind the rear axle to 3.405 m ahead, 1.80 m wide."""
    c, s = math.cos(yaw), math.sin(yaw)
    pts = [(-0.895, -0.9), (3.405, -0.9), (3.405, 0.9), (-0.895, 0.9)]
    return shapely.Polygon([(x + c * u - s * v, y + s * u + c * v) for u, v in pts])


def _spec_rect(o: Obstacle) -> shapely.Polygon:
    """SPEC §2 independently: ``size`` = (length along yaw, width), yaw counter-clockwise."""
    (cx, cy), (ln, wd), yaw = o.center, o.size, o.yaw
    c, s = math.cos(yaw), math.sin(yaw)
    pts = [(-ln / 2, -wd / 2), (ln / 2, -wd / 2), (ln / 2, wd / 2), (-ln / 2, wd / 2)]
    return shapely.Polygon([(cx + c * u - s * v, cy + s * u + c * v) for u, v in pts])


def test_s1_vehicle_table_and_derived_limits():
    """§1: 4.30 x 1.80 m, L 2.51 m, overhang 0.895 m, R_min 6 m, 30 deg, 0.4 rad/s."""
    v = VehicleParams()
    assert (v.length, v.width, v.wheelbase) == (4.30, 1.80, 2.51)
    assert v.rear_overhang == pytest.approx(0.895)
    assert v.front_extent == pytest.approx(3.405)
    assert v.kappa_max == pytest.approx(KAPPA_MAX) and round(v.kappa_max, 3) == 0.167
    assert math.degrees(v.max_steer) == pytest.approx(30.0)
    assert v.max_steer_rate == pytest.approx(0.4)
    # kappa = tan(delta) / L: the 30 deg actuator reaches beyond the binding path limit.
    assert math.tan(v.max_steer) / v.wheelbase > v.kappa_max


def test_s1_s2_exact_body_clearance_matches_the_spec_geometry():
    """§1 (pose = rear axle, body -0.895..+3.405 m) and §2 (size along yaw, yaw CCW,
    bounds are an obstacle): the checker's exact clearance equals one computed from SPEC."""
    obstacles = (
        Obstacle((30.0, 20.0), (12.0, 1.0), math.pi / 4),
        Obstacle((12.0, 30.0), (6.0, 2.0), -0.4),
        Obstacle((45.0, 8.0), (3.0, 9.0), 2.0),
    )
    m = Map("spec_geom_s49", (0.0, 0.0, 60.0, 40.0), obstacles, Pose(5, 5, 0), Pose(55, 35, 0))
    checker = PlanningProblem.from_map(m).checker
    rects = [_spec_rect(o) for o in obstacles]
    inside = shapely.box(0.0, 0.0, 60.0, 40.0)
    rng = np.random.default_rng(49)
    compared = 0
    for x, y, yaw in zip(rng.uniform(2, 58, 300), rng.uniform(2, 38, 300),
                         rng.uniform(-np.pi, np.pi, 300), strict=True):
        body = _spec_body(x, y, yaw)
        if not inside.contains(body) or any(body.intersects(r) for r in rects):
            want = 0.0
        else:
            want = min([body.distance(r) for r in rects] + [body.distance(inside.exterior)])
        assert checker.body_clearance((x, y, yaw)) == pytest.approx(want, abs=1e-6), (x, y, yaw)
        compared += want > 0.0
    assert compared > 100  # most poses were free: the distances were compared, not just 0 == 0


# ------------------------------------------------------------------ §2 maps


def test_s2_builtin_maps_are_100m_squares_as_described():
    """§2: overtake (road edges + a stopped car in the ego lane), parking_lot, narrow_gap
    (a passage barely wider than the car), no_path (goal walled in), 100 m x 100 m."""
    v = VehicleParams()
    for name in ("overtake", "parking_lot", "narrow_gap", "no_path"):
        assert builtin_map(name).bounds == (0.0, 0.0, 100.0, 100.0), name
    ov = builtin_map("overtake")
    edges = [o for o in ov.obstacles if o.size[0] >= 99.0]
    cars = [o for o in ov.obstacles if o.size == pytest.approx((v.length, v.width))]
    assert len(edges) == 2 and len(cars) == 1
    low, high = sorted(o.center[1] for o in edges)
    assert low < ov.start.y < high and low < ov.goal.y < high
    car = cars[0]
    assert ov.start.x < car.center[0] < ov.goal.x
    assert abs(car.center[1] - ov.start.y) < v.width / 2  # in the ego lane, in the way

    ng = builtin_map("narrow_gap")
    walls = shapely.union_all([_spec_rect(o) for o in ng.obstacles])
    x = float(np.mean([o.center[0] for o in ng.obstacles]))
    column = shapely.LineString([(x, 0.0), (x, 100.0)]).difference(walls)
    gaps = [g.length for g in getattr(column, "geoms", [column]) if 0 < g.bounds[1] < 99]
    assert len(gaps) == 1 and v.width < gaps[0] < 2 * v.width

    npth = builtin_map("no_path")
    walls = shapely.union_all([_spec_rect(o) for o in npth.obstacles])
    holes = [shapely.Polygon(r) for poly in getattr(walls, "geoms", [walls])
             for r in poly.interiors]
    assert any(h.contains(shapely.Point(npth.goal.x, npth.goal.y)) for h in holes)
    assert not any(h.contains(shapely.Point(npth.start.x, npth.start.y)) for h in holes)


# ------------------------------------------------------------------ §3 planners


def test_s3_baselines_use_the_papers_steps_radius_and_goal_bias():
    """§3 Baselines: RRT and RRT-Connect step 5 m; RRT* step 2 m, rewire 15 m; goal bias 5 %."""
    rrt, con, star = (make_planner(n) for n in ("rrt", "rrt-connect", "rrt-star"))
    assert (rrt.step, rrt.goal_bias) == (5.0, 0.05)
    assert con.step == 5.0
    assert (star.step, star.rewire_radius, star.goal_bias) == (2.0, 15.0, 0.05)


def test_s3_every_planner_returns_the_result_fields_spec_lists():
    """§3: success, path, raw tree path, trees, node count, iterations, planning time."""
    problem = PlanningProblem.from_map(builtin_map("overtake"))
    for name in ("rrt", "rrt-connect", "rrt-star", "improved-rrt-connect"):
        r = make_planner(name).solve(problem, np.random.default_rng(1), Budget(max_iterations=3000))
        assert r.status is PlanStatus.SOLVED, (name, r.message)
        assert r.path.samples.shape[1] == 5 and len(r.path.samples) >= 2
        assert r.raw_path.ndim == 2 and r.raw_path.shape[1] == 2 and len(r.raw_path) >= 2
        assert r.trees and r.nodes == sum(len(t.nodes) for t in r.trees), name
        assert r.iterations >= 1 and r.planning_time_s > 0.0
        assert np.allclose(r.raw_path[0], problem.start.xy) and np.allclose(
            r.raw_path[-1], problem.goal.xy)
    # RRT-Connect family: two trees (start and goal).
    assert len(make_planner("rrt-connect").solve(
        problem, np.random.default_rng(1), Budget(max_iterations=3000)).trees) == 2


def test_s3_failure_is_honest_with_a_message_for_every_planner():
    """§3: a failed result says so (never a silently unsafe path) and carries a message."""
    problem = PlanningProblem.from_map(builtin_map("no_path"))
    for name in ("rrt", "rrt-connect", "rrt-star", "improved-rrt-connect", "hybrid-a-star"):
        r = make_planner(name).solve(problem, np.random.default_rng(0), Budget(max_iterations=300))
        assert r.status is not PlanStatus.SOLVED, name
        assert r.message.strip(), name
        assert len(r.path.samples) == 0, name


def test_s3_direct_connection_is_the_straight_edge_without_growth():
    """§3 item 1: a free straight start->goal edge skips growth."""
    m = Map("direct_s49", (0, 0, 60, 40), (Obstacle((30.0, 35.0), (4.0, 2.0), 0.3),),
            Pose(5, 10, 0), Pose(50, 10, 0))
    problem = PlanningProblem.from_map(m)
    r = make_planner("improved-rrt-connect").solve(problem, np.random.default_rng(0), Budget())
    assert r.status is PlanStatus.SOLVED and r.iterations == 0
    assert r.path.length == pytest.approx(45.0) and r.path.max_curvature == 0.0
    grown = make_planner("improved-rrt-connect", direct_connect=False).solve(
        problem, np.random.default_rng(0), Budget())
    assert grown.iterations > 0


@pytest.mark.parametrize("rate", [0.4, 0.2])
def test_s3_item10_sharpness_bound_follows_the_cars_actuator(rate):
    """§3 item 10: |d delta / ds| <= max_steer_rate / (2 m/s), delta = atan(L kappa), for the
    car the map is planned for (a slower actuator gets a tighter bound)."""
    v = VehicleParams(max_steer_rate=rate)
    m = dataclasses.replace(builtin_map("parking_lot"), vehicle=v)
    r = make_planner("improved-rrt-connect").solve(
        PlanningProblem.from_map(m), np.random.default_rng(0), Budget(max_iterations=4000))
    assert r.status is PlanStatus.SOLVED, r.message
    s = r.path.samples
    delta = np.arctan(v.wheelbase * s[:, 3])
    ds = np.hypot(*np.diff(s[:, :2], axis=0).T)
    moving = ds > 1e-9
    sharp = np.abs(np.diff(delta))[moving] / ds[moving]
    assert sharp.max() <= rate / 2.0 + 0.005
    assert np.abs(s[:, 3]).max() <= v.kappa_max + 1e-9


def test_s3_gears_row_layout_cusps_and_per_segment_guarantees():
    """§3 Gears: rows [x, y, yaw, kappa, gear], gear +-1, yaw = nose in both gears, at a cusp
    the position row repeats with the new gear; each segment keeps |kappa| <= kappa_max."""
    code, d = _plan_json("dead_end", "--reverse")
    assert code == 0 and d["status"] == "solved"
    p = np.array(d["path"])
    assert p.shape[1] == 5 and set(np.unique(p[:, 4])) <= {-1.0, 1.0}
    changes = np.nonzero(np.diff(p[:, 4]))[0]
    assert len(changes) == d["cusps"] >= 1
    for i in changes:  # the pose repeats, only the gear changes
        assert np.allclose(p[i, :3], p[i + 1, :3], atol=1e-6)
    step = np.diff(p[:, :2], axis=0)
    length = np.hypot(*step.T)
    along = (step[:, 0] * np.cos(p[:-1, 2]) + step[:, 1] * np.sin(p[:-1, 2])) * p[:-1, 4]
    moving = length > 1e-9
    assert (along[moving] > 0).all()  # forward rows move along the nose, reverse rows against
    # ... and along it within a few degrees (yaw is where the nose points, not the motion)
    assert (along[moving] / length[moving] > math.cos(math.radians(3))).all()
    assert d["length_m"] == pytest.approx(length.sum(), abs=1e-4)  # distance travelled
    assert d["max_curvature"] == pytest.approx(np.abs(p[:, 3]).max(), abs=1e-6)
    assert d["max_curvature"] <= KAPPA_MAX + 1e-9
    assert np.allclose(p[0, :2], d["start"][:2], atol=1e-6)
    assert np.allclose(p[-1, :2], d["goal"][:2], atol=1e-6)
    assert abs(_wrap(p[0, 2] - d["start"][2])) < math.radians(3)
    assert abs(_wrap(p[-1, 2] - d["goal"][2])) < math.radians(3)


def test_s3_setup_is_built_once_and_outside_the_planning_budget():
    """§3: per-map set-up is built once, outside the planning budget, reported as setup_time_s."""
    from rrtdrive.planning import solve_on_map

    lot = builtin_map("parking_lot")
    m = dataclasses.replace(  # a map of its own: nothing cached for it yet in this process
        lot, name="setup_s49", bounds=(0.0, 0.0, 150.0, 100.0),
        obstacles=(*lot.obstacles, Obstacle((140.0, 50.0), (3.0, 3.0), 0.1)),
        start=Pose(5, 6, 0), goal=Pose(40, 6, 0))
    cap = Budget(max_time_s=0.05)

    def solve():
        return solve_on_map(lambda: make_planner("improved-rrt-connect"), m,
                            np.random.default_rng(0), cap)[1]

    first = solve()
    assert first.status is PlanStatus.SOLVED, first.message
    assert first.setup_time_s > cap.max_time_s  # longer than the cap, yet not charged to it
    assert first.planning_time_s < cap.max_time_s
    again = solve()
    assert again.status is PlanStatus.SOLVED
    assert again.setup_time_s < first.setup_time_s / 10  # built once per map
    assert np.array_equal(again.path.samples, first.path.samples)


# ------------------------------------------------------------------ §4 closed loop


@pytest.fixture(scope="module")
def curve_episode():
    from rrtdrive.sim.runner import run_episode
    from rrtdrive.sim.tasks.custom import CustomTask

    m = Map("curve_s49", (0, 0, 60, 50), (Obstacle((20.0, 40.0), (4.0, 2.0), 0.0),),
            Pose(8, 8, 0), Pose(45, 32, math.pi / 2))
    return run_episode(CustomTask.from_map(m), controller="pure-pursuit", seed=0)


def _project(path: np.ndarray, xy: np.ndarray) -> tuple[float, float]:
    """Distance to the polyline and the yaw interpolated at the nearest point."""
    a, b = path[:-1, :2], path[1:, :2]
    ab = b - a
    t = np.clip(np.einsum("ij,ij->i", xy - a, ab) / np.maximum(np.einsum("ij,ij->i", ab, ab),
                                                              1e-18), 0, 1)
    foot = a + t[:, None] * ab
    d = np.hypot(*(xy - foot).T)
    i = int(d.argmin())
    yaw = path[i, 2] + t[i] * _wrap(path[i + 1, 2] - path[i, 2])
    return float(d[i]), float(yaw)


def test_s4_episode_metrics_match_their_definitions(curve_episode):
    """§4 Evaluators: cross-track and heading error of the rear axle (RMS, max), path
    curvature, executed curvature tan(delta)/L (max, share over kappa_max), max lateral
    acceleration v^2 kappa, steering rate, time to goal."""
    from rrtdrive.evaluation import evaluate

    ep = curve_episode
    j = evaluate(ep).to_json()
    assert j["success"] and j["path_cusps"] == 0
    path, st, ctl, dt = ep.path.samples, ep.log.states, ep.log.controls, ep.log.dt
    assert path.shape[1] == 5 and np.abs(path[:, 3]).max() > 0.1  # the drive turns
    proj = [_project(path, np.asarray(s[:2])) for s in st]
    cte = np.array([d for d, _ in proj])
    head = np.abs(_wrap(st[:, 2] - np.array([y for _, y in proj])))
    assert j["cte_max_m"] == pytest.approx(cte.max(), abs=2e-5)
    assert j["cte_rms_m"] == pytest.approx(math.sqrt(np.mean(cte**2)), rel=0.05, abs=2e-5)
    assert j["heading_err_max_rad"] == pytest.approx(head.max(), abs=2e-3)
    assert j["path_max_curvature"] == pytest.approx(np.abs(path[:, 3]).max(), abs=1e-6)
    kappa = np.tan(ctl[:, 1]) / VehicleParams().wheelbase
    assert j["executed_max_curvature"] == pytest.approx(np.abs(kappa).max(), abs=1e-6)
    assert j["executed_curvature_violation_share"] == pytest.approx(
        np.mean(np.abs(kappa) > KAPPA_MAX + 1e-9), abs=1e-6)
    lat = np.maximum(st[:-1, 3] ** 2, st[1:, 3] ** 2) * np.abs(kappa)
    assert 0 < j["max_lateral_accel"] <= lat.max() + 1e-5
    rate = np.abs(np.diff(np.concatenate([[0.0], ctl[:, 1]]))) / dt
    assert j["max_steering_rate"] == pytest.approx(rate.max(), abs=1e-5)
    assert j["max_steering_rate"] <= VehicleParams().max_steer_rate + 1e-9
    assert np.abs(ctl[:, 1]).max() <= math.radians(30) + 1e-12
    assert j["time_to_goal_s"] == pytest.approx(ep.log.t[-1])
    assert j["goal_position_err_m"] == pytest.approx(
        math.hypot(st[-1, 0] - path[-1, 0], st[-1, 1] - path[-1, 1]), abs=1e-5)


def test_s4_report_has_every_metric_spec_lists(curve_episode):
    """§4 Evaluators: the per-episode figures SPEC names, including nuPlan's six."""
    from rrtdrive.evaluation import evaluate

    j = evaluate(curve_episode).to_json()
    for key in ("success", "collision", "collision_highway_env", "collision_footprint",
                "cte_rms_m", "cte_max_m", "heading_err_rms_rad", "heading_err_max_rad",
                "path_max_curvature", "kappa_max", "executed_max_curvature",
                "executed_curvature_violation_share", "max_lateral_accel", "max_jerk",
                "max_steering_rate", "time_to_goal_s", "nuplan_comfortable",
                "nuplan_lon_accel_min", "nuplan_lon_accel_max", "nuplan_lat_accel_abs_max",
                "nuplan_lon_jerk_abs_max", "nuplan_jerk_abs_max", "nuplan_yaw_rate_abs_max",
                "nuplan_yaw_accel_abs_max"):
        assert j[key] is not None, key
    assert j["kappa_max"] == pytest.approx(KAPPA_MAX, abs=1e-6)
    within = (-4.05 <= j["nuplan_lon_accel_min"] and j["nuplan_lon_accel_max"] <= 2.40
              and j["nuplan_lat_accel_abs_max"] <= 4.89 and j["nuplan_lon_jerk_abs_max"] <= 4.13
              and j["nuplan_jerk_abs_max"] <= 8.37 and j["nuplan_yaw_rate_abs_max"] <= 0.95
              and j["nuplan_yaw_accel_abs_max"] <= 1.93)
    assert j["nuplan_comfortable"] is within


def test_s4_ego_moves_by_the_maps_own_car_model():
    """§4 Ego car: the simulated car is the planner's model, sizes and limits included
    (one VehicleParams for every module): a map made for another car drives that car."""
    from rrtdrive.evaluation import evaluate
    from rrtdrive.sim.runner import run_episode
    from rrtdrive.sim.scenes import build_env
    from rrtdrive.sim.tasks.custom import CustomTask

    car = VehicleParams(length=4.8, width=2.0, wheelbase=2.9, min_turning_radius=7.0,
                        max_steer_rate=0.3)
    m = Map("car_s49", (0, 0, 60, 50), (Obstacle((20.0, 40.0), (4.0, 2.0), 0.0),),
            Pose(8, 8, 0), Pose(45, 32, math.pi / 2), vehicle=car)
    task = CustomTask.from_map(m)
    ego = build_env(task).unwrapped.vehicle
    assert (ego.LENGTH, ego.WIDTH) == (4.8, 2.0)
    ep = run_episode(task, controller="lqr", seed=0)
    j = evaluate(ep).to_json()
    assert j["success"] and j["kappa_max"] == pytest.approx(car.kappa_max, abs=1e-6)
    assert j["path_max_curvature"] <= car.kappa_max + 1e-6
    assert j["executed_max_curvature"] <= car.kappa_max + 1e-6
    assert j["max_steering_rate"] <= car.max_steer_rate + 1e-9
    st, ctl, dt = ep.log.states, ep.log.controls, ep.log.dt
    dyaw = np.diff(np.unwrap(st[:, 2]))
    speed = 0.5 * (st[:-1, 3] + st[1:, 3])

    def misfit(wheelbase: float) -> float:
        return float(np.abs(dyaw - speed * np.tan(ctl[:, 1]) / wheelbase * dt).max())

    assert misfit(car.wheelbase) < 1e-3 and misfit(car.wheelbase) < misfit(2.51) / 5


def _with_final(ep, dx=0.0, dy=0.0, dyaw=0.0, speed=None):
    from rrtdrive.evaluation import evaluate

    s = np.array(ep.log.states)
    s[-1, :3] += (dx, dy, dyaw)
    if speed is not None:
        s[-1, 3] = speed
    return evaluate(dataclasses.replace(ep, log=dataclasses.replace(ep.log, states=s))).to_json()


def test_s4_success_is_half_a_metre_ten_degrees_and_stopped(curve_episode):
    """§4: success = goal pose reached within 0.5 m and 10 deg, stopped, no collision."""
    ep = curve_episode
    assert _with_final(ep)["success"]
    # the goal faces +y: a shift along y is along the heading, along x sideways
    assert _with_final(ep, dy=-0.45)["success"]
    assert not _with_final(ep, dy=-0.55)["success"]
    assert _with_final(ep, dx=0.3, dy=-0.3)["success"]  # 0.42 m
    assert not _with_final(ep, dx=0.4, dy=-0.4)["success"]  # 0.57 m
    assert _with_final(ep, dyaw=math.radians(9.5))["success"]
    assert not _with_final(ep, dyaw=math.radians(10.5))["success"]
    assert not _with_final(ep, dyaw=-math.radians(10.5))["success"]
    moving = _with_final(ep, speed=1.0)
    assert not moving["success"] and not moving["stopped"]


def test_s4_collision_includes_an_exact_footprint_check_against_the_map(curve_episode):
    """§4: collision = highway-env's crashed or the exact body against the map's rectangles."""
    from rrtdrive.evaluation import evaluate

    ep = curve_episode
    s = np.array(ep.log.states)
    # midway, put the rear axle so that the body's nose overlaps the obstacle at (20, 40)
    s[len(s) // 2, :3] = (15.0, 40.0, 0.0)
    j = evaluate(dataclasses.replace(ep, log=dataclasses.replace(ep.log, states=s))).to_json()
    assert j["collision_footprint"] and j["collision"] and not j["success"]
    assert not j["collision_highway_env"]


def _arc_path(kappa: float, gear: int, rows: int = 161) -> tuple[np.ndarray, float]:
    """Rows driven by the rear-axle model itself: constant steering, 0.25 m apart."""
    from rrtdrive.vehicle import bicycle_step

    wheelbase = VehicleParams().wheelbase
    delta = math.atan(wheelbase * kappa)
    pose, out = (10.0, 10.0, 0.3), []
    for _ in range(rows):
        out.append([*pose, kappa, gear])
        pose = bicycle_step(pose, 0.25 * gear, delta, 1.0, wheelbase)
    return np.array(out), delta


@pytest.mark.parametrize("gear", [1, -1])
@pytest.mark.parametrize("kappa", [0.1, -0.1])
def test_s3_s4_kappa_is_the_steerings_curvature_in_both_gears_for_every_controller(kappa, gear):
    """§1/§3 Gears: kappa = tan(delta) / L in both gears; §4: every controller tracks the
    same bicycle model: on an arc the model drove, each holds exactly that steering."""
    from rrtdrive.controllers import make_controller
    from rrtdrive.controllers.state import VehicleState
    from rrtdrive.types import Path

    rows, delta = _arc_path(kappa, gear)
    path = Path(rows, np.zeros((0, 2)))
    for name in ("pure-pursuit", "stanley", "lqr"):
        ctl = make_controller(name)
        ctl.reset(path)
        for i in (40, 80):
            x, y, yaw = rows[i, :3]
            _, steer = ctl.control(VehicleState(x, y, yaw, speed=1.0 * gear, steer=delta, t=5.0))
            assert steer == pytest.approx(delta, abs=1e-3), (name, i)


@pytest.mark.parametrize("gear", [1, -1])
def test_s4_controllers_bring_an_offset_car_onto_the_path_in_both_gears(gear):
    """§4 Gear changes / Controllers: a car 0.3 m off a straight segment, driven by the
    rear-axle model with the 0.4 rad/s actuator, converges and stops at the end, in either
    gear."""
    from rrtdrive.controllers import make_controller
    from rrtdrive.controllers.state import VehicleState
    from rrtdrive.types import Path
    from rrtdrive.vehicle import bicycle_step

    v, dt = VehicleParams(), 0.05
    xs = np.arange(0.0, 30.001, 0.25)[:: gear]
    rows = np.column_stack([xs, 0 * xs, 0 * xs, 0 * xs, gear + 0 * xs])
    for name in ("pure-pursuit", "stanley", "lqr"):
        ctl = make_controller(name)
        ctl.reset(Path(rows, np.zeros((0, 2))))
        x, y, yaw, speed, steer = xs[0], 0.3, 0.0, 0.0, 0.0
        for k in range(int(80 / dt)):
            accel, cmd = ctl.control(VehicleState(x, y, yaw, speed=speed, steer=steer, t=k * dt))
            cmd = min(max(cmd, -v.max_steer), v.max_steer)
            steer = min(max(cmd, steer - v.max_steer_rate * dt), steer + v.max_steer_rate * dt)
            new = speed + accel * dt
            x, y, yaw = bicycle_step((x, y, yaw), 0.5 * (speed + new), steer, dt, v.wheelbase)
            speed = new
            assert speed * gear >= -1e-9, (name, k)  # never against the segment's gear
            if ctl.arrived:
                break
        assert ctl.arrived, name
        assert abs(y) < 0.05 and abs(x - xs[-1]) < 0.3 and abs(_wrap(yaw)) < math.radians(3), name


# ------------------------------------------------------------------ §5 interfaces

SPEC_FLAGS = {
    "plan": ["--start", "--goal", "--planner", "--seed", "--json", "--plot"],
    "simulate": ["--planner", "--controller", "--seed", "--video", "--json", "--trajectory"],
    "bench": ["--seeds", "--planners", "--controllers", "--workers"],
    "verify": ["--json", "--plot"],
    "maps": ["--export"],
}


@pytest.mark.parametrize("command", sorted(SPEC_FLAGS))
def test_s5_every_command_has_help_naming_the_spec_flags(command):
    """§5: one entry point, --help on every command."""
    code, out, err = _run(command, "--help")
    assert code == 0 and not err
    for flag in SPEC_FLAGS[command]:
        assert flag in out, (command, flag)


def test_s5_plan_json_contract():
    """§5: plan --json carries success, planner, seed, path (<= 0.25 m apart), waypoints,
    length_m, max_curvature, nodes, planning_time_s, message; exit 0 on success."""
    code, d = _plan_json("parking_lot", "--seed", "2", "--max-iterations", "4000")
    assert code == 0
    for key, kind in (("success", bool), ("planner", str), ("seed", int), ("path", list),
                      ("waypoints", list), ("length_m", float), ("max_curvature", float),
                      ("nodes", int), ("planning_time_s", float), ("message", str)):
        assert isinstance(d[key], kind), key
    assert d["success"] is True and d["planner"] == "improved-rrt-connect" and d["seed"] == 2
    p = np.array(d["path"])
    gaps = np.hypot(*np.diff(p[:, :2], axis=0).T)
    assert gaps.max() <= 0.25 + 1e-6
    assert d["length_m"] == pytest.approx(gaps.sum(), abs=1e-4)
    assert d["max_curvature"] == pytest.approx(np.abs(p[:, 3]).max(), abs=1e-6)
    w = np.array(d["waypoints"])
    assert w.shape[1] == 2 and np.allclose(w[0], p[0, :2]) and np.allclose(w[-1], p[-1, :2])
    m = builtin_map("parking_lot")
    assert np.allclose(p[0, :3], m.start.as_tuple(), atol=1e-6)
    assert np.allclose(p[-1, :2], m.goal.xy, atol=1e-6)


def test_s5_plan_failure_exits_1_with_success_false():
    """§5: exit code 1 for a planning failure, the JSON still written."""
    code, d = _plan_json("no_path")
    assert code == 1 and d["success"] is False and d["message"]
    assert d["length_m"] is None and d["max_curvature"] is None


def test_s5_simulate_failed_episode_exits_1_with_metrics_json():
    """§5: simulate prints the evaluators' metrics as JSON; exit 1 on an episode failure."""
    code, out, _ = _run("simulate", "no_path", "--json", "-")
    d = json.loads(out)
    assert code == 1 and d["success"] is False and d["collision"] is False
    assert "cte_rms_m" in d and "executed_max_curvature" in d


@pytest.mark.parametrize("argv, field", [
    (["plan", "parking_lot", "--start", "-5,6,0"], "--start"),
    (["plan", "parking_lot", "--goal", "50,20,0"], "--goal"),
    (["plan", "parking_lot", "--disable", "bogus"], "--disable"),
    (["simulate", "parking", "--controller", "mpc"], "--controller"),
])
def test_s5_s6_bad_input_is_exit_2_one_line_naming_the_field(argv, field):
    """§5/§6: exit 2, a one-line message naming the field, no traceback."""
    code, out, err = _run(*argv)
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and field in lines[0] and "Traceback" not in err


def test_s5_gym_ids_are_registered_with_normalised_actions():
    """§5 Gymnasium: registered ids (rrtdrive/Parking-v0, rrtdrive/Overtake-v0); action =
    normalised acceleration and steering."""
    import gymnasium as gym

    import rrtdrive

    for env_id in ("rrtdrive/Parking-v0", "rrtdrive/Overtake-v0"):
        assert env_id in gym.registry and env_id in rrtdrive.ENV_IDS
    env = gym.make("rrtdrive/Overtake-v0")
    try:
        space = env.action_space
        assert space.shape == (2,)
        assert np.all(space.low == -1.0) and np.all(space.high == 1.0)
    finally:
        env.close()


def test_s5_bench_summary_has_mean_std_and_a_95_ci_over_the_runs(tmp_path):
    """§5 bench: many seeds x planners, a summary table with mean, std and 95 % CI."""
    import csv
    import statistics

    out = tmp_path / "bench"
    code, _, err = _run("bench", "--maps", "overtake", "--planners", "rrt-connect", "--seeds",
                        "4", "--workers", "1", "--out", str(out), "--no-plots", "--quiet")
    assert code == 0, err
    runs = [json.loads(line) for line in (out / "runs.jsonl").read_text().splitlines()]
    assert sorted(r["seed"] for r in runs) == [0, 1, 2, 3]
    summary = list(csv.DictReader((out / "summary.csv").open()))
    assert (out / "summary.md").read_text().count("95 % CI") >= 1
    checked = 0
    for row in summary:
        if row["metric"] not in ("length_m", "nodes", "iterations"):
            continue
        values = [float(r[row["metric"]]) for r in runs if r[row["metric"]] is not None]
        assert int(row["n"]) == len(values) == 4
        assert float(row["mean"]) == pytest.approx(statistics.mean(values))
        assert float(row["std"]) == pytest.approx(statistics.stdev(values))
        assert float(row["ci95_low"]) <= float(row["mean"]) <= float(row["ci95_high"])
        checked += 1
    assert checked == 3
