"""Audit (session 47) of the space-time planner used for re-planning in traffic.

Every solved plan is checked against an independent reference: shapely polygons of
the ego body (from its rear-axle samples) and of every other car, placed in closed
form from the documented constant-velocity model (``x + v t cos h``), at the plan's
own arrival times, over the documented time band ``[t - m(t), t + m(t)]`` and
between samples at a finer time step. Timing is recomputed from the documented
speed-profile rules (docs/traffic.md, "Whole paths are timed exactly").
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
import shapely

from rrtdrive.maps import Map
from rrtdrive.planning.spacetime import (
    ArrivalTiming,
    Prediction,
    SafetyConfig,
    SpaceTimeProblem,
    SpaceTimeRRTConnect,
)
from rrtdrive.types import Budget, InputError, PlanStatus, Pose, VehicleParams
from rrtdrive.vehicle import footprint_corners

SIZE = (4.3, 1.8)
HORIZON = 14.0
SPEED = (10.0, 1.5, 1.0, 1.5, 0.5)  # v_max, accel, decel, a_lat_max, v_launch

#: Two-lane road 8 m wide: ego lane centre y = 44, oncoming lane centre y = 48.
ROAD = (0.0, 42.0, 70.0, 50.0)

#: Constant-velocity cars (x, y, heading, speed).
LEAD_ONLY = ((18.0, 44.0, 0.0, 2.0),)
LEAD_AND_ONCOMING = ((18.0, 44.0, 0.0, 2.0), (100.0, 48.0, math.pi, 6.0))
#: An oncoming car the overtake must clear in front of (several seeds fail the final check).
LEAD_AND_LATE_ONCOMING = ((18.0, 44.0, 0.0, 2.0), (120.0, 48.0, math.pi, 6.0))
LEAD_AND_FOLLOWER = ((18.0, 44.0, 0.0, 2.0), (-12.0, 44.0, 0.0, 3.0))


def _prediction(cars) -> Prediction:
    return Prediction.constant_velocity(np.array(cars, float), [SIZE] * len(cars), HORIZON)


def _problem(cars, *, vehicle: VehicleParams | None = None, steering=None,
             start=(2.0, 44.0), goal_x: float = 58.0, v0: float = 4.0,
             bounds=ROAD, timing_origin=None) -> SpaceTimeProblem:
    vehicle = vehicle or VehicleParams()
    road = Map("road", bounds, (), Pose(start[0], start[1], 0.0), Pose(goal_x, start[1], 0.0),
               vehicle)
    origin = timing_origin or start
    timing = ArrivalTiming(0.0, v0, SPEED[0], SPEED[1], origin)
    return SpaceTimeProblem(road, _prediction(cars), timing, SafetyConfig(), SPEED,
                            steering=steering)


def _solve(problem, seed=0, planner=None, iters=3000):
    planner = planner or SpaceTimeRRTConnect()
    return planner.solve_spacetime(problem, np.random.default_rng(seed),
                                   Budget(max_iterations=iters))


# ----------------------------------------------------------------- reference geometry

def _car_polygon(car, t: float) -> shapely.Polygon:
    """Body of a constant-velocity car at time ``t`` (closed form, before 0: its start)."""
    x, y, h, v = car
    tt = max(t, 0.0)
    cx, cy = x + v * tt * math.cos(h), y + v * tt * math.sin(h)
    ux, uy = math.cos(h), math.sin(h)
    hl, hw = SIZE[0] / 2, SIZE[1] / 2
    return shapely.Polygon([(cx + a * ux * hl - b * uy * hw, cy + a * uy * hl + b * ux * hw)
                            for a, b in ((-1, -1), (1, -1), (1, 1), (-1, 1))])


def _ego_polygons(poses: np.ndarray, vehicle: VehicleParams) -> np.ndarray:
    return shapely.polygons(footprint_corners(np.asarray(poses)[:, :3], vehicle))


def _worst_gap(poses, times, cars, safety: SafetyConfig, vehicle, band: bool) -> float:
    """Smallest ``distance - b(t)`` of the ego at ``poses``/``times`` to every car.

    With ``band`` each car is also placed over ``[t - m(t), t + m(t)]`` (0.05 s steps).
    """
    egos = _ego_polygons(poses, vehicle)
    worst = math.inf
    for car in cars:
        for ego, t in zip(egos, times, strict=True):
            m = safety.margin(t) if band else 0.0
            offs = np.arange(-m, m + 1e-9, 0.05) if band else np.array([0.0])
            others = [_car_polygon(car, t + o) for o in offs]
            d = float(np.min(shapely.distance(ego, others)))
            worst = min(worst, d - float(safety.buffer(t)))
    return worst


def _between(samples: np.ndarray, times: np.ndarray, sub: int = 6):
    """Poses and times linearly interpolated between consecutive samples."""
    f = np.linspace(0.0, 1.0, sub + 1)[1:-1]
    a, b = samples[:-1, :3], samples[1:, :3]
    dyaw = (b[:, 2] - a[:, 2] + math.pi) % (2 * math.pi) - math.pi
    poses, ts = [], []
    for fr in f:
        p = a + fr * (b - a)
        p[:, 2] = a[:, 2] + fr * dyaw
        poses.append(p)
        ts.append(times[:-1] + fr * (times[1:] - times[:-1]))
    return np.concatenate(poses), np.concatenate(ts)


def _reference_profile(samples, v0):
    """Documented profile: v <= v_max, v <= sqrt(a_lat/|kappa|), +accel / -decel, start
    at max(v0, v_launch); each interval at the mean of its end speeds."""
    v_max, accel, decel, a_lat, v_launch = SPEED
    ds = np.hypot(*np.diff(samples[:, :2], axis=0).T)
    k = np.abs(samples[:, 3])
    cap = np.minimum(v_max, np.sqrt(a_lat / np.maximum(k, 1e-12)))
    v = cap.copy()
    v[0] = min(cap[0], max(v0, v_launch))
    for i in range(1, len(v)):
        v[i] = min(cap[i], math.sqrt(v[i - 1] ** 2 + 2 * accel * ds[i - 1]))
    for i in range(len(v) - 2, -1, -1):
        v[i] = min(v[i], math.sqrt(v[i + 1] ** 2 + 2 * decel * ds[i]))
    t = np.concatenate([[0.0], np.cumsum(ds / np.maximum(0.5 * (v[1:] + v[:-1]), 0.05))])
    return t, v


# ----------------------------------------------------------------- solved plans

SCENARIOS = {
    "lead": dict(cars=LEAD_ONLY),
    "lead+oncoming": dict(cars=LEAD_AND_ONCOMING),
    "lead+follower": dict(cars=LEAD_AND_FOLLOWER),
}


@pytest.fixture(scope="module")
def solved():
    """(name, seed, problem, plan) of the scenarios that solved, several seeds each."""
    out = []
    for name, kw in SCENARIOS.items():
        for seed in (0, 1, 2):
            problem = _problem(**kw)
            plan = _solve(problem, seed)
            if plan.success:
                out.append((name, seed, kw["cars"], problem, plan))
    return out


def test_scenarios_mostly_solve(solved):
    assert len(solved) >= 6, [(n, s) for n, s, *_ in solved]


def test_results_carry_the_space_time_planners_name(solved):
    # Both a success and a failure name the planner that ran (the stage of a success too).
    names = {plan.result.planner for *_, plan in solved}
    blocked = _solve(_problem(((60.0, 44.0, math.pi, 4.0),), bounds=NARROW))
    assert names | {blocked.result.planner} == {SpaceTimeRRTConnect.name}


def test_solved_plans_keep_documented_clearance_at_samples_over_the_band(solved):
    for name, seed, cars, problem, plan in solved:
        s = plan.result.path.samples
        gap = _worst_gap(s, plan.times, cars, problem.safety, problem.vehicle, band=True)
        assert gap >= -1e-6, f"{name} seed {seed}: clearance short by {-gap:.3f} m"


def test_solved_plans_keep_clearance_between_samples(solved):
    for name, seed, cars, problem, plan in solved:
        poses, ts = _between(plan.result.path.samples, plan.times)
        gap = _worst_gap(poses, ts, cars, problem.safety, problem.vehicle, band=False)
        assert gap >= -1e-6, f"{name} seed {seed}: clearance short by {-gap:.3f} m"


def test_solved_plans_stay_on_the_road(solved):
    for name, seed, _cars, problem, plan in solved:
        road = shapely.box(*problem.map.bounds).buffer(1e-6)
        s = plan.result.path.samples
        poses, _ = _between(s, plan.times)
        bodies = _ego_polygons(np.concatenate([s[:, :3], poses]), problem.vehicle)
        assert np.all(shapely.covers(road, bodies)), f"{name} seed {seed} leaves the road"


def test_solved_plans_respect_curvature_and_sharpness(solved):
    for name, seed, _cars, problem, plan in solved:
        s = plan.result.path.samples
        vehicle = problem.vehicle
        assert np.max(np.abs(s[:, 3])) <= vehicle.kappa_max + 1e-9, (name, seed)
        # Steering angle rate per metre <= 0.2 rad/m (default; car rate 0.4 / 2 m/s = 0.2).
        ds = np.hypot(*np.diff(s[:, :2], axis=0).T)
        delta = np.arctan(vehicle.wheelbase * s[:, 3])
        ok = ds > 1e-6
        sharp = np.abs(np.diff(delta))[ok] / ds[ok]
        assert sharp.max() <= 0.2 * 1.02, (name, seed, float(sharp.max()))
        # And the heading column agrees with the curvature column (a consistent path).
        dyaw = (np.diff(s[:, 2]) + math.pi) % (2 * math.pi) - math.pi
        mean_k = 0.5 * (s[1:, 3] + s[:-1, 3])
        assert np.allclose(dyaw[ok], (mean_k * ds)[ok], atol=2e-3), (name, seed)


def test_solved_plans_start_at_the_query_and_end_at_the_goal(solved):
    for name, seed, _cars, problem, plan in solved:
        s = plan.result.path.samples
        st, gl = problem.start, problem.goal
        assert np.allclose(s[0, :3], [st.x, st.y, st.yaw], atol=1e-6), (name, seed)
        assert np.allclose(s[-1, :2], [gl.x, gl.y], atol=1e-3), (name, seed)
        assert plan.times[0] == pytest.approx(problem.timing.t0)
        assert plan.speeds[0] == pytest.approx(problem.timing.v0)
        assert len(plan.times) == len(plan.speeds) == len(s)


def test_solved_plan_timing_agrees_with_documented_profile(solved):
    for name, seed, _cars, problem, plan in solved:
        s = plan.result.path.samples
        t_ref, v_ref = _reference_profile(s, problem.timing.v0)
        assert np.all(np.diff(plan.times) > 0), (name, seed)
        np.testing.assert_allclose(plan.speeds, v_ref, atol=1e-6, err_msg=f"{name} {seed}")
        np.testing.assert_allclose(plan.times, problem.timing.t0 + t_ref, atol=1e-6,
                                   err_msg=f"{name} {seed}")
        assert np.all(plan.speeds <= SPEED[0] + 1e-9)


def test_replanner_like_query_with_offset_timing_and_steering():
    """As the re-planner asks: 30 m turning radius, lane-change sharpness, a rate-limited
    actuator, and a timing origin behind the plan's start (the stitch point)."""
    vehicle = dataclasses.replace(VehicleParams(), min_turning_radius=30.0)
    share = 0.8
    v_turn = min(SPEED[0], math.sqrt(SPEED[3] * 30.0))
    bound = 0.4 * share / v_turn
    planner = SpaceTimeRRTConnect(max_postprocess_attempts=2,
                                  smoothing={"max_rounds": 8, "max_sharpness": bound})
    cars = ((22.0, 44.0, 0.0, 1.0), (160.0, 48.0, math.pi, 5.0))
    problem = _problem(cars, vehicle=vehicle, steering=(0.4, share), start=(5.0, 44.0),
                       goal_x=66.0, timing_origin=(2.5, 44.0), bounds=(0.0, 42.0, 90.0, 50.0))
    plans = [_solve(problem, seed, planner, iters=1000) for seed in (0, 1, 2)]
    good = [p for p in plans if p.success]
    assert good, [p.result.message for p in plans]
    t_start, v_start = problem.timing.state_at((5.0, 44.0))
    for plan in good:
        s = plan.result.path.samples
        assert plan.times[0] == pytest.approx(t_start) and t_start > 0.0
        assert plan.speeds[0] <= v_start + 1e-9
        assert np.max(np.abs(s[:, 3])) <= 1.0 / 30.0 + 1e-9
        ds = np.hypot(*np.diff(s[:, :2], axis=0).T)
        ok = ds > 1e-6
        sharp = np.abs(np.diff(np.arctan(vehicle.wheelbase * s[:, 3])))[ok] / ds[ok]
        assert sharp.max() <= bound * 1.02
        gap = _worst_gap(s, plan.times, cars, problem.safety, vehicle, band=True)
        assert gap >= -1e-6
        poses, ts = _between(s, plan.times)
        assert _worst_gap(poses, ts, cars, problem.safety, vehicle, band=False) >= -1e-6


@pytest.mark.xfail(strict=True, reason="BUG: the clothoid guarantee loop checks poses at the "
                   "NOMINAL ArrivalTiming band (SpaceTimeChecker.poses_free, preferred at "
                   "smoothing/clothoid_curve.py for its per-piece cache) instead of exact "
                   "profile times (path_free); 3 of seeds 0-5 return POSTPROCESS_FAILED 'traffic "
                   "conflict ... on the final check'. Using path_free (session 48) fixed this "
                   "test but, in experiments/traffic.py (100 seeds x 3 densities), cost 3 "
                   "high-density overtakes (78 -> 75; seeds 100-199: 82 -> 81) and one nuPlan "
                   "comfort miss (jerk 4.39): not kept, see docs/traffic.md 'What is left'")
def test_postprocessor_sees_the_exact_times_of_the_final_check():
    problem = _problem(LEAD_AND_LATE_ONCOMING)
    lost = [seed for seed in range(6)
            if "on the final check" in _solve(problem, seed).result.message]
    assert lost == []


def test_failed_final_check_returns_no_path(monkeypatch):
    # The post-processor now checks the exact times with the final check's slack, so
    # a conflict found only on the final check is made here: once the improved planner
    # has returned its path, the checker sees traffic everywhere.
    from rrtdrive.planning.improved import ImprovedRRTConnect
    from rrtdrive.planning.spacetime import planner as spacetime_planner

    made = []
    checker_for = SpaceTimeRRTConnect.checker_for
    solve = ImprovedRRTConnect.solve

    def recording_checker_for(self, problem):
        made.append(checker_for(self, problem))
        return made[-1]

    def solve_then_block(self, problem, rng, budget):
        res = solve(self, problem, rng, budget)
        made[-1].conflicts = lambda poses, *args, **kwargs: np.ones(len(poses), dtype=bool)
        return res

    monkeypatch.setattr(SpaceTimeRRTConnect, "checker_for", recording_checker_for)
    monkeypatch.setattr(spacetime_planner.ImprovedRRTConnect, "solve", solve_then_block)
    plan = _solve(_problem(LEAD_AND_LATE_ONCOMING))
    assert plan.result.status is PlanStatus.POSTPROCESS_FAILED
    assert "on the final check" in plan.result.message
    assert len(plan.times) == 0
    assert len(plan.result.path.samples) == 0


# ----------------------------------------------------------------- blocked at the needed time

#: One-lane road 4 m wide: no way round anything.
NARROW = (0.0, 42.0, 70.0, 46.0)


def _crossing(y_start: float):
    """A car crossing the road at x = 30 northwards at 2 m/s."""
    return ((30.0, y_start, math.pi / 2, 2.0),)


def test_crossing_car_blocks_only_at_the_needed_time():
    # The ego (4 m/s, +1.5 m/s^2) reaches x = 30 at about 4 s: v^2 = 16 + 3 * 28.
    blocked = _problem(_crossing(36.0), bounds=NARROW)  # on the lane (y = 44) at 4 s
    later = _problem(_crossing(14.0), bounds=NARROW)  # on the lane at 15 s
    ok = _solve(later)
    assert ok.success, ok.result.message
    assert _worst_gap(ok.result.path.samples, ok.times, _crossing(14.0), later.safety,
                      later.vehicle, band=True) >= -1e-6
    for seed in (0, 1):
        plan = _solve(blocked, seed)
        assert not plan.success
        assert plan.result.status in (PlanStatus.NO_PATH_IN_BUDGET,
                                      PlanStatus.POSTPROCESS_FAILED)
        assert plan.result.status is not PlanStatus.SOLVED
        assert len(plan.times) == 0 and len(plan.speeds) == 0
        assert len(plan.result.path.samples) == 0
        assert plan.result.message.strip()


def test_head_on_car_in_a_single_lane_fails_with_status_and_message():
    problem = _problem(((60.0, 44.0, math.pi, 4.0),), bounds=NARROW)
    plan = _solve(problem)
    assert not plan.success
    assert plan.result.status is not PlanStatus.SOLVED
    assert isinstance(plan.result.message, str) and plan.result.message
    assert plan.times.size == 0


# ----------------------------------------------------------------- determinism

def test_seeded_queries_are_deterministic():
    problem = _problem(LEAD_AND_ONCOMING)
    a = _solve(problem, 7)
    b = _solve(_problem(LEAD_AND_ONCOMING), 7)
    assert a.success == b.success
    assert a.result.status is b.result.status
    np.testing.assert_array_equal(a.result.path.samples, b.result.path.samples)
    np.testing.assert_array_equal(a.times, b.times)
    np.testing.assert_array_equal(a.speeds, b.speeds)
    assert a.dynamic_checks == b.dynamic_checks
    for ta, tb in zip(a.tree_times, b.tree_times, strict=True):
        np.testing.assert_array_equal(ta, tb)


# ----------------------------------------------------------------- bad inputs

T = np.arange(0.0, 1.05, 0.1)
POSES = np.zeros((1, len(T), 3))


def _raises(field: str, fn) -> None:
    with pytest.raises(InputError) as info:
        fn()
    assert field in str(info.value), str(info.value)


def test_nan_predictions_are_input_errors():
    _raises("prediction", lambda: Prediction(T, np.full_like(POSES, np.nan), [SIZE]))
    _raises("prediction", lambda: Prediction.constant_velocity(
        np.array([[np.nan, 0.0, 0.0, 1.0]]), [SIZE], 5.0))
    _raises("prediction.alt", lambda: Prediction(T, POSES, [SIZE], alt=POSES * np.nan))
    _raises("prediction.horizon", lambda: Prediction.constant_velocity(
        np.array([[0.0, 0.0, 0.0, 1.0]]), [SIZE], float("nan")))


def test_negative_or_empty_prediction_times_are_input_errors():
    _raises("prediction.times", lambda: Prediction(T - 0.1, POSES, [SIZE]))
    _raises("prediction.times", lambda: Prediction(np.zeros(0), np.zeros((0, 0, 3)),
                                                    np.zeros((0, 2))))
    _raises("prediction.horizon", lambda: Prediction.constant_velocity(
        np.array([[0.0, 0.0, 0.0, 1.0]]), [SIZE], -5.0))


def test_prediction_poses_of_wrong_length_are_input_error():
    _raises("prediction.poses", lambda: Prediction(T, np.zeros((1, len(T) - 1, 3)), [SIZE]))


def test_negative_timing_t0_is_input_error():
    _raises("timing.t0", lambda: ArrivalTiming(-1.0, 4.0, 10.0, 1.5, (2.0, 44.0)))


def test_negative_timing_v0_is_input_error():
    _raises("timing.v0", lambda: ArrivalTiming(0.0, -4.0, 10.0, 1.5, (2.0, 44.0)))


@pytest.mark.parametrize("field", ["prediction", "timing"])
def test_missing_problem_parts_are_input_errors(field):
    base = _problem(LEAD_ONLY)
    _raises(field, lambda: _solve(dataclasses.replace(base, **{field: None}), iters=100))


@pytest.mark.parametrize("speed", [
    (float("nan"), 1.5, 1.0, 1.5, 0.5),
    (-10.0, 1.5, 1.0, 1.5, 0.5),
    (10.0, -1.5, 1.0, 1.5, 0.5),
    (10.0, 1.5, 1.0, 1.5),
])
def test_bad_speed_tuple_is_input_error(speed):
    base = _problem(LEAD_ONLY)
    _raises("speed", lambda: _solve(dataclasses.replace(base, speed=speed)))


def test_empty_prediction_set_plans_as_static():
    """A prediction with no cars is documented (Prediction.empty): the plan is the
    static one, with its timing, and keeps the road."""
    road = Map("road", ROAD, (), Pose(2.0, 44.0, 0.0), Pose(58.0, 44.0, 0.0))
    timing = ArrivalTiming(0.0, 4.0, 10.0, 1.5, (2.0, 44.0))
    plan = _solve(SpaceTimeProblem(road, Prediction.empty(HORIZON), timing, speed=SPEED))
    assert plan.success
    t_ref, _ = _reference_profile(plan.result.path.samples, 4.0)
    np.testing.assert_allclose(plan.times, t_ref, atol=1e-6)


def test_problem_that_is_not_spacetime_is_input_error():
    with pytest.raises(InputError, match="problem"):
        SpaceTimeRRTConnect().solve_spacetime("road", np.random.default_rng(0), Budget())
