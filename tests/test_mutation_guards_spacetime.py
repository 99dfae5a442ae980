"""Mutation guards for the space-time planner (rrtdrive.planning.spacetime).

Each test checks a user-visible answer (a conflict seen or not, an arrival time,
a path judged clear of traffic) against an independent reference: closed-form
constant-velocity kinematics and constant-acceleration times, and shapely
distances to the other cars' centre lines swept by brute force over time.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely

from rrtdrive.maps import Map
from rrtdrive.planning.base import cached_checker
from rrtdrive.planning.spacetime import (
    ArrivalTiming,
    Prediction,
    SafetyConfig,
    SpaceTimeChecker,
    SpaceTimeProblem,
    SpaceTimeRRTConnect,
    traffic_conflicts,
)
from rrtdrive.planning.spacetime.timing import yaw_curvature
from rrtdrive.types import Budget, Pose, VehicleParams
from rrtdrive.vehicle import cover_discs, footprint_corners

V = VehicleParams()
SAFETY = SafetyConfig(0.3, 0.1, 0.3, 0.15)

#: Constant-velocity cars: x, y, heading, speed, alternative speed (or None), length, width.
CARS = (
    (0.0, 0.0, 0.0, 5.0, None, 4.3, 1.8),
    (40.0, 3.5, math.pi, 6.0, 2.0, 4.8, 2.0),
    (10.0, -6.0, math.pi / 2, 3.0, None, 5.0, 2.0),
)


def _prediction(cars=CARS, horizon: float = 5.0) -> Prediction:
    """The cars as a prediction (alt sweeps the second speed where one is given)."""
    main = Prediction.constant_velocity(
        np.array([c[:4] for c in cars]), [c[5:] for c in cars], horizon
    )
    if all(c[4] is None for c in cars):
        return main
    alt = Prediction.constant_velocity(
        np.array([[c[0], c[1], c[2], c[3] if c[4] is None else c[4]] for c in cars]),
        [c[5:] for c in cars], horizon,
    )
    return Prediction(main.times, main.poses, main.sizes, alt=alt.poses)


def _centre(car, speed: float, t: float) -> np.ndarray:
    """Closed-form body centre of a constant-velocity car at ``t`` (before 0: the start)."""
    x, y, h = car[:3]
    return np.array([x, y]) + speed * max(t, 0.0) * np.array([math.cos(h), math.sin(h)])


def _swept_line(car, lo: float, hi: float) -> shapely.Geometry:
    """Hull of the car's centre lines (bumper to bumper) at dense times in ``[lo, hi]``
    for either speed (any speed between the two hypotheses is covered too)."""
    u = np.array([math.cos(car[2]), math.sin(car[2])])
    half = car[5] / 2.0
    points = []
    for speed in {car[3], car[3] if car[4] is None else car[4]}:
        for t in np.linspace(lo, hi, 60):
            c = _centre(car, speed, float(t))
            points += [c - half * u, c + half * u]
    return shapely.MultiPoint(points).convex_hull


def _model(pose, t_lo: float, t_hi: float, spacing: float, cars=CARS) -> tuple[float, ...]:
    """Per car: distance of the ego's disc centres to its swept centre line minus the limit.

    Negative means the documented conservative test must report a conflict.
    """
    offsets, radius = cover_discs(V, 3)
    x, y, yaw = pose
    discs = shapely.MultiPoint(
        [(x + o * math.cos(yaw), y + o * math.sin(yaw)) for o in offsets]
    )
    lo = t_lo - SAFETY.margin(t_lo)
    hi = t_hi + SAFETY.margin(t_hi)
    out = []
    for car in cars:
        d = discs.distance(_swept_line(car, lo, hi))
        out.append(d - (radius + 0.5 * spacing + car[6] / 2.0 + float(SAFETY.buffer(t_hi))))
    return tuple(out)


def _random_queries(n: int, seed: int) -> list[tuple[np.ndarray, float, float]]:
    """Ego poses near the cars' paths with arrival bands from 0 to beyond the horizon."""
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(n):
        pose = np.array([rng.uniform(-8.0, 48.0), rng.uniform(-12.0, 9.0), rng.uniform(-3.2, 3.2)])
        t_lo = float(rng.uniform(0.0, 7.0))
        out.append((pose, t_lo, t_lo + float(rng.uniform(0.0, 1.5))))
    return out


def test_conflicts_are_exactly_the_documented_swept_capsule_test() -> None:
    """A pose conflicts iff a covering disc comes within the buffer of a car's swept capsule.

    Guards missed and invented conflicts: time-band ends, margins and buffers at the
    right end of the band, bumper extents, the alternative speed, lateral and
    backward directions, every vehicle, extrapolation past the horizon.
    """
    pred = _prediction()
    spacing = 0.4
    queries = _random_queries(260, 7)
    seen = {True: 0, False: 0}
    singles = []
    for pose, t_lo, t_hi in queries:
        gaps = _model(pose, t_lo, t_hi, spacing)
        got = bool(
            traffic_conflicts(pose[None], [t_lo], [t_hi], pred, SAFETY, V, spacing)[0]
        )
        singles.append(got)
        if min(abs(g) for g in gaps) < 1e-3:
            continue  # on the boundary: either answer is right
        want = min(gaps) < 0.0
        assert got == want, (pose.tolist(), t_lo, t_hi, gaps)
        seen[want] += 1
    assert seen[True] > 30 and seen[False] > 30  # both answers are exercised
    # One batched call answers every pose as the single calls do.
    poses = np.array([q[0] for q in queries])
    batch = traffic_conflicts(
        poses, [q[1] for q in queries], [q[2] for q in queries], pred, SAFETY, V, spacing
    )
    assert batch.tolist() == singles


def test_a_pose_whose_true_body_meets_a_car_in_the_band_is_always_a_conflict() -> None:
    """Soundness against shapely bodies: the ego rectangle within the buffer of a car's
    rectangle at any time of the band must be reported (never a plan through a car)."""
    pred = _prediction()
    hits = 0
    for pose, t_lo, t_hi in _random_queries(200, 11):
        ego = shapely.Polygon(footprint_corners(pose, V))
        lo, hi = t_lo - SAFETY.margin(t_lo), t_hi + SAFETY.margin(t_hi)
        near = False
        for car in CARS:
            h = car[2]
            for speed in {car[3], car[3] if car[4] is None else car[4]}:
                for t in np.linspace(lo, hi, 40):
                    cx, cy = _centre(car, speed, float(t))
                    rear = (cx - car[5] / 2 * math.cos(h), cy - car[5] / 2 * math.sin(h), h)
                    body = footprint_corners(
                        np.array(rear), VehicleParams(length=car[5], width=car[6])
                    )
                    # footprint_corners is about the rear axle; re-centre by the overhang.
                    off = VehicleParams(length=car[5], width=car[6]).rear_overhang
                    body = body + off * np.array([math.cos(h), math.sin(h)])
                    if ego.distance(shapely.Polygon(body)) < float(SAFETY.buffer(t_hi)):
                        near = True
        if near:
            hits += 1
            assert traffic_conflicts(pose[None], [t_lo], [t_hi], pred, SAFETY, V)[0]
    assert hits > 10


def test_a_car_arriving_late_is_seen_in_a_batch_with_early_poses() -> None:
    """The time screen spans the whole batch: poses reached late still see a car that
    only arrives then, whatever earlier poses share the call."""
    car = ((0.0, 0.0, 0.0, 5.0, None, 4.3, 1.8),)
    pred = _prediction(car, horizon=10.0)
    safety = SafetyConfig(0.3, 0.0, 0.2, 0.0)
    pose = np.array([40.0 - 1.255, 0.0, 0.0])  # body centred where the car is at 8 s
    t = np.array([0.0, 1.0, 8.0])
    got = traffic_conflicts(np.repeat(pose[None], 3, axis=0), t, t, pred, safety, V)
    assert got.tolist() == [False, False, True]


# ----------------------------------------------------------------------------- prediction


def test_predicted_poses_follow_constant_velocity_and_the_nearest_heading() -> None:
    """Positions by closed form (start before 0, extrapolated past the horizon, in y as
    in x); the heading of a turning car is the nearer grid sample's."""
    states = np.array([[1.0, 2.0, 0.7, 3.0], [-4.0, 5.0, -2.0, 1.5]])
    p = Prediction.constant_velocity(states, [(4.3, 1.8), (5.0, 2.0)], 2.0, 0.1)
    t = np.array([-0.5, 0.0, 0.33, 1.77, 2.0, 3.4])
    at = p.poses_at(t)
    for k, (x, y, h, v) in enumerate(states):
        tt = np.maximum(t, 0.0)
        assert at[k, :, 0] == pytest.approx(x + v * math.cos(h) * tt)
        assert at[k, :, 1] == pytest.approx(y + v * math.sin(h) * tt)
    times = np.arange(0.0, 1.05, 0.1)
    yaw = 0.3 * np.arange(len(times))
    turning = Prediction(times, np.stack([times, 0 * times, yaw], axis=-1)[None], [(4.3, 1.8)])
    q = np.array([0.12, 0.18, 0.44, 0.46])
    assert turning.poses_at(q)[0, :, 2] == pytest.approx(0.3 * np.round(q / 0.1))


def test_select_shift_and_x_range_keep_the_second_hypothesis() -> None:
    """A selected or shifted prediction keeps its alternative speed; x_range spans both."""
    pred = _prediction()
    assert pred.alt is not None
    sel = pred.select(np.array([False, True, False]))
    assert sel.alt is not None and np.array_equal(sel.alt, pred.alt[1:2])
    moved = pred.shifted(2.0, -3.0)
    assert np.allclose(moved.poses[..., :2] - pred.poses[..., :2], [2.0, -3.0])
    assert np.allclose(moved.alt[..., :2] - pred.alt[..., :2], [2.0, -3.0])
    # The oncoming car: x from 40 - 6 * 5 (fast) to 40; the slow hypothesis stays within.
    assert pred.x_range()[1] == pytest.approx([10.0, 40.0])
    slow_only = Prediction(pred.times, pred.alt, pred.sizes)
    assert slow_only.x_range()[1] == pytest.approx([30.0, 40.0])
    swapped = Prediction(pred.times, pred.alt, pred.sizes, alt=pred.poses)
    assert swapped.x_range()[1] == pytest.approx([10.0, 40.0])  # the fast one as alt


def test_a_band_starting_before_the_prediction_is_not_widened() -> None:
    """Buffer and time margin grow with the prediction time only: a time before the
    prediction (a path's first samples minus the slack) counts as 0, not as |t|."""
    safety = SafetyConfig(0.4, 0.5, 0.3, 0.2)
    t = np.array([-2.0, -0.2, 0.0, 3.0])
    assert safety.buffer(t) == pytest.approx([0.4, 0.4, 0.4, 0.4 + 0.5 * 3.0])
    assert safety.margin(t) == pytest.approx([0.3, 0.3, 0.3, 0.3 + 0.2 * 3.0])


# ----------------------------------------------------------------------------- timing


def _time_for(d: float, v0: float, v_max: float, a: float) -> float:
    """Closed form: accelerate from v0 to v_max (never below v0), then cruise."""
    vm = max(v_max, v0)
    d_up = (vm**2 - v0**2) / (2 * a)
    if d <= d_up:
        return (math.sqrt(v0**2 + 2 * a * d) - v0) / a
    return (vm - v0) / a + (d - d_up) / vm


@pytest.mark.parametrize("v0", [0.0, 3.0, 12.0])
def test_arrival_band_is_the_constant_acceleration_time_over_progress(v0: float) -> None:
    """Earliest arrival over the progress along the road direction, latest over
    length_factor times it; points behind the origin arrive at t0."""
    tm = ArrivalTiming(1.5, v0, 10.0, 1.2, (3.0, -1.0), (3.0, 4.0), 1.2)
    pts = np.array([[3.0, -1.0], [6.0, 3.0], [3.0 + 0.6 * 80, -1.0 + 0.8 * 80], [0.0, -5.0]])
    lo, hi = tm.band(pts)
    for i, d in enumerate([0.0, 5.0, 80.0, 0.0]):
        assert lo[i] == pytest.approx(1.5 + _time_for(d, v0, 10.0, 1.2))
        assert hi[i] == pytest.approx(1.5 + _time_for(1.2 * d, v0, 10.0, 1.2))
    t, v = tm.state_at((3.0 + 0.6 * 80, -1.0 + 0.8 * 80))
    assert t == pytest.approx(lo[2]) and v == pytest.approx(max(10.0, v0))
    moved = tm.shifted(2.0, -1.0)
    assert moved.band(pts + [2.0, -1.0])[0] == pytest.approx(lo)


# ----------------------------------------------------------------------------- checker


def _road() -> Map:
    return Map("road", (0.0, 38.0, 90.0, 50.0), (), Pose(2.0, 44.0, 0.0), Pose(80.0, 44.0, 0.0),
               VehicleParams(min_turning_radius=30.0))


def _parked(x: float, y: float = 44.0) -> Prediction:
    """One car standing still with its centre at (x, y)."""
    return Prediction.constant_velocity(np.array([[x, y, 0.0, 0.0]]), [(4.3, 1.8)], 12.0)


def test_every_pose_test_sees_a_car_standing_there() -> None:
    """edge_free (long edge, car in its middle), pose_free, poses_free and
    poses_free_fast all refuse the ego on a standing car and accept it far away."""
    timing = ArrivalTiming(0.0, 4.0, 11.0, 1.5, (2.0, 44.0))
    ck = SpaceTimeChecker(cached_checker(_road()), _parked(40.0), timing)
    assert ck.edge_free((20.0, 44.0), (60.0, 44.0)) is False
    assert ck.edge_free((20.0, 44.0), (30.0, 44.0)) is True
    on, off = np.array([38.8, 44.0, 0.0]), np.array([20.0, 44.0, 0.0])
    assert ck.pose_free(on) is False and ck.pose_free(off) is True
    both = np.array([on, off])
    assert ck.poses_free(both).tolist() == [False, True]
    assert ck.poses_free_fast(both)[0] == np.False_


def test_path_times_start_at_the_timing_and_path_free_uses_the_slack_band() -> None:
    """A path is timed from the timing's t0; path_free flags exactly the samples the
    documented test with band [t - slack, t + slack] flags, and the segments on both
    sides of them; one car alone is enough to block."""
    timing = ArrivalTiming(2.0, 4.0, 11.0, 1.5, (2.0, 44.0), length_factor=1.0)
    xs = np.linspace(2.0, 60.0, 59)
    path = np.column_stack([xs, np.full_like(xs, 44.0), np.zeros_like(xs)])
    free = SpaceTimeChecker(cached_checker(_road()), Prediction.empty(12.0), timing)
    t, _ = free.path_times(path)
    assert t[0] == pytest.approx(2.0)
    assert t[-1] == pytest.approx(2.0 + _time_for(58.0, 4.0, 10.0, 1.0), abs=0.05)
    # An oncoming car in the ego's lane meets it somewhere; find where with the model.
    car = (80.0, 44.0, math.pi, 6.0, None, 4.3, 1.8)
    slack = 0.6
    pred = _prediction((car,), horizon=12.0)
    ck = SpaceTimeChecker(cached_checker(_road()), pred, timing, SAFETY, slack_s=slack)
    ok, bad = ck.path_free(path)
    step = float(xs[1] - xs[0])
    want = []
    for i, (pose, ti) in enumerate(zip(path, t, strict=True)):
        gap = _model(pose, ti - slack, ti + slack, step, (car,))[0]
        assert abs(gap) > 1e-3
        if gap < 0:
            want.append(i)
    assert want and not ok
    segs = sorted({max(i - 1, 0) for i in want} | {min(i, len(path) - 2) for i in want})
    assert bad.tolist() == segs


def test_tree_times_are_the_earliest_arrival_of_each_node() -> None:
    """The plan's tree times are the earliest of each node's band (not the latest)."""
    timing = ArrivalTiming(0.0, 4.0, 11.0, 1.5, (2.0, 44.0), length_factor=1.3)
    problem = SpaceTimeProblem(_road(), _parked(30.0, 44.0), timing,
                               speed=(11.0, 1.5, 1.0, 2.0, 0.5))
    plan = SpaceTimeRRTConnect().solve_spacetime(problem, np.random.default_rng(3),
                                                 Budget(max_iterations=400))
    for tree, times in zip(plan.result.trees, plan.tree_times, strict=True):
        prog = np.maximum((tree.nodes[:, 0] - 2.0), 0.0)
        want = [_time_for(d, 4.0, 11.0, 1.5) for d in prog]
        assert times == pytest.approx(want)


def test_curvature_of_sampled_poses_reaches_both_ends_of_each_segment() -> None:
    """On a circle of radius R every sample, the last one too, has curvature 1/R (so a
    path is timed through the whole curve at curve speed); a straight then a turn gives
    the joint sample the turn's curvature."""
    r = 25.0
    a = np.linspace(0.0, 1.2, 40)
    arc = np.column_stack([r * np.sin(a), r * (1 - np.cos(a)), a])
    s, kappa = yaw_curvature(arc)
    chord = 2 * r * math.sin((a[1] - a[0]) / 2)
    assert s == pytest.approx(chord * np.arange(len(a)))
    assert kappa == pytest.approx(np.full(len(a), (a[1] - a[0]) / chord))
    joint = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.5]])
    assert yaw_curvature(joint)[1] == pytest.approx([0.0, 0.5, 0.5])


@pytest.mark.parametrize(("extra", "free"), [(-0.003, False), (0.26, True)])
def test_an_edge_passing_a_car_between_its_test_poses_is_judged_by_the_whole_sweep(
    extra: float, free: bool
) -> None:
    """A parked car's bumper just within reach of the ego's discs at a place between
    two tested poses of an edge still blocks it (the discs grow by half the spacing);
    one farther than that growth does not."""
    offsets, radius = cover_discs(V, 3)
    safety = SafetyConfig(0.4, 0.0, 0.5, 0.0)
    limit = radius + 0.9 + 0.4
    # Along the edge (20 -> 30 at y = 44) some disc centre passes x = 24.005 exactly,
    # so the continuous sweep comes within `limit + extra` of the bumper below it.
    bumper_y = 44.0 - (limit + extra)
    car = Prediction.constant_velocity(
        np.array([[24.005, bumper_y - 4.3 / 2, math.pi / 2, 0.0]]), [(4.3, 1.8)], 12.0
    )
    timing = ArrivalTiming(0.0, 4.0, 11.0, 1.5, (2.0, 44.0))
    ck = SpaceTimeChecker(cached_checker(_road()), car, timing, safety)
    assert ck.edge_free((20.0, 44.0), (30.0, 44.0)) is free
