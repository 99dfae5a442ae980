"""Guards against mutants of the evaluators that survived the suite (``rrtdrive.evaluation``).

Each test builds an episode by hand (a logged drive through the public
``DriveLog``/``Episode`` constructors) and checks one definition of
``docs/metrics.md`` against an independent reference: closed-form kinematics worked
out in the comments, shapely for bodies, distances and overlaps (the body drawn here
from the doc: 0.895 m behind the rear axle to 3.405 m ahead of it, 1.8 m wide),
scipy's own filters and intervals, or a hypothesis property (rigid-motion invariance).
"""

from __future__ import annotations

import dataclasses
import json
import math
from typing import Any

import numpy as np
import pytest
import scipy.stats
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.signal import savgol_filter

from rrtdrive.evaluation import (
    EpisodeReport,
    EvalConfig,
    evaluate,
    failure_reason,
    min_vehicle_distance,
    success_terms,
    summarise,
    time_to_collision,
    tracking_errors,
    vehicle_collisions,
)
from rrtdrive.evaluation.collisions import between_lanes
from rrtdrive.evaluation.comfort import curvature_violation_share, path_sharpness
from rrtdrive.evaluation.metrics import replan_stats
from rrtdrive.evaluation.nuplan_comfort import COMFORT_BOUNDS, nuplan_comfort
from rrtdrive.maps import Map
from rrtdrive.sim.episode import DriveLog, Episode
from rrtdrive.sim.replanning import ReplanConfig, ReplanRecord, TrafficLog
from rrtdrive.sim.runner import EpisodeConfig
from rrtdrive.sim.tasks import make_scenario
from rrtdrive.sim.tasks.custom import CustomTask
from rrtdrive.types import Path, Pose, VehicleParams

V = VehicleParams()
DT = 0.05
#: Rear axle to body centre (m): 4.30 / 2 - 0.895.
D = V.length / 2.0 - V.rear_overhang
CAR = (4.3, 1.8)

# --------------------------------------------------------------------------- helpers


def _overtake(goal: tuple[float, float, float] | None = None) -> Any:
    """The overtake task without jitter: lane y = 44 (4 m wide), road edges at y <= 42 and
    y >= 50, the stopped car centred at (50, 44)."""
    scen = make_scenario("overtake", 0, jitter=(0.0, 0.0, 0.0))
    if goal is not None:
        scen = dataclasses.replace(scen, map=scen.map.with_query(goal=Pose(*goal)))
    return scen


def _open_lot() -> Any:
    """An empty 100 m x 100 m map without lanes, start (5, 50) and goal (90, 50)."""
    m = Map("lot", (0.0, 0.0, 100.0, 100.0), (), Pose(5.0, 50.0, 0.0), Pose(90.0, 50.0, 0.0))
    return CustomTask.from_map(m)


def _line(x0: float, x1: float, y: float) -> Path:
    """A straight path along +x sampled every 0.1 m from ``(x0, y)`` to ``(x1, y)``."""
    n = int(round(abs(x1 - x0) / 0.1)) + 1
    x = np.linspace(x0, x1, n)
    return Path(np.column_stack([x, np.full(n, y), np.zeros(n), np.zeros(n)]), np.zeros((0, 2)))


def _episode(
    scen: Any,
    states: np.ndarray,
    controls: np.ndarray | None = None,
    *,
    path: Path | None = None,
    others: np.ndarray | None = None,
    sizes: Any = None,
    crashed: np.ndarray | None = None,
    status: str = "arrived",
) -> Episode:
    """An episode of logged rear-axle states ``(N+1, 4)`` and controls ``(N, 2)``."""
    states = np.asarray(states, dtype=float)
    n = len(states)
    controls = np.zeros((n - 1, 2)) if controls is None else np.asarray(controls, dtype=float)
    others = np.zeros((n, 0, 4)) if others is None else np.asarray(others, dtype=float)
    sizes = np.zeros((0, 2)) if sizes is None else np.asarray(sizes, dtype=float)
    log = DriveLog(
        dt=DT, t=np.arange(n) * DT, states=states, controls=controls.reshape(-1, 2),
        crashed=np.zeros(n, bool) if crashed is None else np.asarray(crashed, bool),
        others=others, other_sizes=sizes, arrived=status == "arrived", wall_time_s=0.01,
    )
    if path is None:
        path = _line(float(states[0, 0]), max(float(states[-1, 0]), float(states[0, 0]) + 1.0),
                     float(states[0, 1]))
    return Episode(scen, "given", "pure-pursuit", scen.seed, None, path, log, status, "",
                   EpisodeConfig())


def _states(x: np.ndarray, y: Any, yaw: Any = 0.0, v: Any = 1.0) -> np.ndarray:
    """Rear-axle states from columns (scalars broadcast)."""
    x = np.asarray(x, dtype=float)
    return np.column_stack([x, np.broadcast_to(y, x.shape), np.broadcast_to(yaw, x.shape),
                            np.broadcast_to(v, x.shape)]).astype(float)


def _body(x: float, y: float, yaw: float) -> shapely.Polygon:
    """The ego body of a rear-axle pose, from the doc (not from the package)."""
    c, s = math.cos(yaw), math.sin(yaw)
    pts = ((-0.895, -0.9), (3.405, -0.9), (3.405, 0.9), (-0.895, 0.9))
    return shapely.Polygon([(x + u * c - w * s, y + u * s + w * c) for u, w in pts])


def _box(cx: float, cy: float, yaw: float, length: float, width: float) -> shapely.Polygon:
    """A rectangle centred at ``(cx, cy)`` with its length along ``yaw``."""
    c, s = math.cos(yaw), math.sin(yaw)
    hl, hw = length / 2.0, width / 2.0
    pts = [(-hl, -hw), (hl, -hw), (hl, hw), (-hl, hw)]
    return shapely.Polygon([(cx + u * c - w * s, cy + u * s + w * c) for u, w in pts])


def _other(n: int, cx: Any, cy: Any, heading: Any, speed: Any) -> np.ndarray:
    """One other vehicle's logged body-centre states, ``(n, 1, 4)``."""
    out = np.zeros((n, 1, 4))
    for k, col in enumerate((cx, cy, heading, speed)):
        out[:, 0, k] = col
    return out


# --------------------------------------------------------------------------- tracking


def test_error_maxima_and_rms_are_magnitudes_of_each_own_error() -> None:
    """A car 0.3 m right of the lane, nose 0.1 rad right: cte_max 0.3 and heading max 0.1
    (magnitudes, not the signed extremes), heading RMS of the heading errors, not the cte."""
    scen = _overtake(goal=(30.0, 44.0, 0.0))
    x = np.linspace(5.0, 30.0, 101)
    yaw = -0.1 * np.sin(np.linspace(0.0, math.pi, 101))  # right of the lane's heading
    ep = _episode(scen, _states(x, 43.7, yaw), path=_line(5.0, 40.0, 44.0))
    r = evaluate(ep)
    lane = shapely.LineString([(5.0, 44.0), (40.0, 44.0)])
    dist = [lane.distance(shapely.Point(xx, 43.7)) for xx in x]  # all right of the lane
    assert r.cte_max_m == pytest.approx(max(dist), abs=1e-9)
    assert r.cte_rms_m == pytest.approx(math.sqrt(np.mean(np.square(dist))), abs=1e-9)
    assert r.heading_err_max_rad == pytest.approx(0.1, abs=1e-9)
    assert r.heading_err_rms_rad == pytest.approx(math.sqrt(np.mean(yaw**2)), abs=1e-9)


def test_path_yaw_is_interpolated_along_the_segment() -> None:
    """The path's yaw at the foot point is interpolated between its samples (doc, Tracking):
    a two-sample path whose yaw column goes 0 -> 0.4, a pose a quarter along with yaw 0.1."""
    p = Path(np.array([[0.0, 0.0, 0.0, 0.0], [10.0, 0.0, 0.4, 0.0]]), np.zeros((0, 2)))
    cte, herr = tracking_errors(p, np.array([[2.5, 0.2, 0.1], [7.5, -0.1, 0.3]]))
    assert cte == pytest.approx([0.2, -0.1], abs=1e-12)
    assert herr == pytest.approx([0.0, 0.0], abs=1e-12)


def test_heading_error_of_a_westbound_path_is_wrapped_across_pi() -> None:
    """A path heading west whose yaw column crosses +-pi: a car on it, aligned, has 0
    heading error; one 0.04 rad off reads 0.04 (wrapped to [-pi, pi), not 2 pi - 0.04)."""
    th = np.linspace(math.pi - 0.05, math.pi + 0.05, 11)  # a gentle turn through west
    xy = np.column_stack([-10.0 * np.sin(th - math.pi), 10.0 * np.cos(th - math.pi)])
    yaw_col = np.angle(np.exp(1j * th))  # as a planner writes it: wrapped
    p = Path(np.column_stack([xy, yaw_col, np.full(11, 0.1)]), np.zeros((0, 2)))
    mid = 0.5 * (xy[5] + xy[6])
    on = np.array([[mid[0], mid[1], -math.pi + 0.0001]])
    cte, herr = tracking_errors(p, on)
    expected = math.remainder(-math.pi + 0.0001 - 0.5 * (th[5] + th[6]), 2 * math.pi)
    assert herr[0] == pytest.approx(expected, abs=1e-9)
    assert abs(herr[0]) < 0.01
    off = np.array([[xy[0, 0], xy[0, 1], math.pi - 0.05 + 0.04 - 2 * math.pi]])
    assert tracking_errors(p, off)[1][0] == pytest.approx(0.04, abs=1e-9)


def test_a_repeated_row_does_not_spoil_the_errors() -> None:
    """Rows repeated in a forward path (first row, a middle row) have no length: the errors
    are the signed distances to the polyline (shapely), finite, as without the repeats."""
    xs = np.linspace(0.0, 10.0, 11)
    rows = np.column_stack([xs, 0.1 * xs**2 / 10, 0.02 * xs, np.full(11, 0.02)])
    repeated = Path(np.vstack([rows[:1], rows[:6], rows[5:]]), np.zeros((0, 2)))
    poses = np.array([[-1.0, -0.5, 0.0], [5.0, -0.5, 0.1], [7.5, 1.0, 0.15]])
    cte, herr = tracking_errors(repeated, poses)
    line = shapely.LineString(rows[:, :2])
    dist = [line.distance(shapely.Point(p[:2])) for p in poses]
    assert np.all(np.isfinite(cte)) and np.all(np.isfinite(herr))
    assert np.abs(cte) == pytest.approx(dist, abs=1e-12)
    assert np.sign(cte).tolist() == [-1.0, -1.0, 1.0]  # right, right, left of travel
    plain = tracking_errors(Path(rows, np.zeros((0, 2))), poses)
    assert cte == pytest.approx(plain[0], abs=1e-12) and herr == pytest.approx(plain[1], abs=1e-12)


@settings(max_examples=40, deadline=None)
@given(
    st.floats(-math.pi, math.pi), st.floats(-50.0, 50.0), st.floats(-50.0, 50.0),
    st.floats(-0.8, 0.8), st.floats(-0.4, 0.4), st.floats(0.5, 9.5),
)
def test_tracking_errors_do_not_change_under_a_rigid_motion(
    rot: float, tx: float, ty: float, dy: float, dyaw: float, s: float
) -> None:
    """Turning and shifting the path and the car together changes neither error (the
    heading error compared as an angle, so across +-pi too)."""
    th = np.linspace(0.0, 1.0, 41)  # an arc of radius 10 m, 10 m long
    base = np.column_stack([10 * np.sin(th), 10 * (1 - np.cos(th)), th, np.full(41, 0.1)])
    pose = np.array([[10 * math.sin(s / 10) - dy * math.sin(s / 10),
                      10 * (1 - math.cos(s / 10)) + dy * math.cos(s / 10), s / 10 + dyaw]])

    def moved(rows: np.ndarray) -> np.ndarray:
        c, si = math.cos(rot), math.sin(rot)
        out = rows.copy()
        out[:, 0] = c * rows[:, 0] - si * rows[:, 1] + tx
        out[:, 1] = si * rows[:, 0] + c * rows[:, 1] + ty
        out[:, 2] = np.angle(np.exp(1j * (rows[:, 2] + rot)))  # yaws stored wrapped
        return out

    a = tracking_errors(Path(base, np.zeros((0, 2))), pose)
    b = tracking_errors(Path(moved(base), np.zeros((0, 2))), moved(pose))
    assert b[0][0] == pytest.approx(a[0][0], abs=1e-6)
    # A pose level with a row, dy inside the bend, is as near to the segments either side:
    # the tie may go either way after the move. Its feet lie dy sin(0.0125) from the row,
    # where the yaw interpolated over the 0.25 m segments is 0.1 rad/m * that off the row's,
    # so the two answers differ by 2.5e-3 * dy rad (6.25e-4 at dy = 0.25 m; fresh-seed runs
    # found it): far below any wrap or sign slip.
    tie = 2.5e-3 * abs(dy) * 1.01 + 1e-9
    assert abs(math.remainder(b[1][0] - a[1][0], 2 * math.pi)) < tie
    assert -math.pi <= b[1][0] < math.pi
    # And both are what the pose was built with: dy left of the arc, dyaw off its tangent
    # (up to the 0.25 m chords' sagitta, under 1 mm, and their yaw step).
    assert b[0][0] == pytest.approx(dy, abs=2e-3)
    assert b[1][0] == pytest.approx(dyaw, abs=2e-3)


def _shuttle() -> Path:
    """Forward 10 m along +x, then back 10 m on an arc of radius 12 m bending to +y."""
    from gear_paths import integrate_pieces

    return integrate_pieces([(1, 0.0, 10.0), (-1, 1.0 / 12.0, 10.0)])


@pytest.mark.parametrize("v_end", [0.0, -5e-5])
def test_a_car_standing_at_a_cusp_is_measured_against_the_segment_it_ends(v_end: float) -> None:
    """Driven forward to 0.1 m before the cusp, 5 cm left of the path, and standing there
    (below 1e-4 m/s counts as standing, whatever the sign): its error is against the forward
    leg (+0.05, left of +x), although the reverse leg passes 0.4 mm closer (shapely)."""
    path = _shuttle()
    s = path.samples
    fwd = shapely.LineString(s[s[:, 4] > 0][:, :2])
    back = shapely.LineString(s[s[:, 4] < 0][:, :2])
    end = shapely.Point(9.9, 0.05)
    assert 0.0 < fwd.distance(end) - back.distance(end) < 1e-3
    x = np.linspace(1.0, 9.9, 30)
    poses = np.column_stack([x, np.full(30, 0.05), np.zeros(30)])
    speeds = np.append(np.ones(29), v_end)
    cte, herr = tracking_errors(path, poses, speeds=speeds)
    assert cte == pytest.approx(np.full(30, 0.05), abs=1e-12)
    assert herr == pytest.approx(np.zeros(30), abs=1e-12)


def test_a_drive_starts_on_the_first_segment_unless_passing_it_over_pays() -> None:
    """The segments are taken in order and one is passed over at the cost of its length: a
    car standing 0.1 m left of the 10 m forward leg, 1 cm nearer the reverse leg (shapely),
    is measured against the forward leg."""
    path = _shuttle()
    s = path.samples
    pose = shapely.Point(9.5, 0.1)
    fwd = shapely.LineString(s[s[:, 4] > 0][:, :2])
    back = shapely.LineString(s[s[:, 4] < 0][:, :2])
    assert 0.005 < fwd.distance(pose) - back.distance(pose) < 10.0
    cte, _ = tracking_errors(path, np.array([[9.5, 0.1, 0.0]]), speeds=np.array([0.0]))
    assert cte[0] == pytest.approx(0.1, abs=1e-12)


def test_progress_across_a_dropped_stub_counts_every_metre() -> None:
    """A path forward 0 -> 5 m, a one-row reverse stub (no length: dropped, the forward legs
    joined), forward on to 10 m, then reverse back to 6 m: driving it all is 14 m of
    progress, the path's length."""
    x1, x2, x3 = np.linspace(0, 5, 51), np.linspace(5, 10, 51), np.linspace(10, 6, 41)

    def rows(x: np.ndarray, gear: float) -> np.ndarray:
        return np.column_stack([x, 0 * x, 0 * x, 0 * x, gear + 0 * x])

    path = Path(np.vstack([rows(x1, 1), [[5.0, 0.0, 0.0, 0.0, -1.0]], rows(x2, 1),
                           rows(x3, -1)]), np.zeros((0, 2)))
    assert path.length == pytest.approx(14.0)
    x = np.concatenate([np.linspace(0, 10, 41), np.linspace(9.9, 6, 40)])
    v = np.concatenate([np.ones(40), [0.0], -np.ones(40)])
    scen = _open_lot()
    states = _states(x + 30.0, 50.0, 0.0, v)
    moved = Path(path.samples + np.array([30.0, 50.0, 0.0, 0.0, 0.0]), np.zeros((0, 2)))
    r = evaluate(_episode(scen, states, path=moved, status="timeout"))
    assert r.progress_m == pytest.approx(14.0, abs=1e-9)
    assert r.cte_max_m == pytest.approx(0.0, abs=1e-9)


# --------------------------------------------------------------------------- success


@pytest.mark.parametrize("x_end, reached", [(30.5, True), (30.6, False)])
def test_goal_position_tolerance_is_half_a_metre_inclusive(x_end: float, reached: bool) -> None:
    """Final rear axle within 0.5 m of the goal (SPEC): 0.5 m exactly reaches, 0.6 m not."""
    scen = _overtake(goal=(30.0, 44.0, 0.0))
    x = np.linspace(5.0, x_end, 51)
    t = success_terms(_episode(scen, _states(x, 44.0, 0.0, np.linspace(2.0, 0.0, 51))))
    assert t.goal_position_err_m == pytest.approx(x_end - 30.0, abs=1e-12)
    assert t.reached_goal is reached


@pytest.mark.parametrize("deg, reached", [(9.9, True), (12.0, False)])
def test_goal_heading_tolerance_is_ten_degrees(deg: float, reached: bool) -> None:
    """Final yaw within 10 degrees of the goal yaw (SPEC): 9.9 reaches, 12 does not."""
    scen = _overtake(goal=(30.0, 44.0, 0.0))
    x = np.linspace(5.0, 30.0, 51)
    yaw = np.zeros(51)
    yaw[-1] = math.radians(deg)
    t = success_terms(_episode(scen, _states(x, 44.0, yaw, np.linspace(2.0, 0.0, 51))))
    assert t.goal_heading_err_rad == pytest.approx(math.radians(deg), abs=1e-12)
    assert t.reached_goal is reached


@pytest.mark.parametrize("v_end, stopped", [(0.1, True), (-0.1, True), (0.15, False)])
def test_stopped_is_a_final_speed_of_at_most_a_tenth(v_end: float, stopped: bool) -> None:
    """|v_N| <= 0.1 m/s (doc, Success): exactly 0.1 either way is stopped, 0.15 is not;
    final_speed is the signed v_N (a field that can be negative)."""
    scen = _overtake(goal=(30.0, 44.0, 0.0))
    x = np.linspace(5.0, 30.0, 51)
    ep = _episode(scen, _states(x, 44.0, 0.0, np.linspace(2.0, v_end, 51)))
    assert success_terms(ep).stopped is stopped
    r = evaluate(ep)
    assert r.stopped is stopped and r.final_speed == v_end


def _clean_overtake_states() -> np.ndarray:
    """Out into the oncoming lane past the stopped car, back, stopped at the goal (92, 44)."""
    x = np.arange(5.0, 92.0 + 1e-9, 0.2)
    y = np.where((x > 30) & (x < 70), 48.0, 44.0)
    return _states(x, y, 0.0, np.append(np.full(len(x) - 1, 3.0), 0.0))


def test_a_footprint_collision_alone_fails_an_otherwise_clean_run() -> None:
    """No collision is a success term, judged by either judge (doc): a body that scrapes the
    road edge (shapely says so) on an otherwise clean overtake is a collision outcome."""
    scen = _overtake()
    states = _clean_overtake_states()
    assert evaluate(_episode(scen, states)).success  # the clean run
    states[20, 1] = 42.7  # the body's right side down to y = 41.8
    edge = _box(50.0, 41.5, 0.0, 100.0, 1.0)
    assert _body(*states[20, :3]).intersects(edge)
    r = evaluate(_episode(scen, states))
    assert r.collision_footprint and not r.collision_highway_env
    assert not r.success and r.outcome == "collision"


@pytest.mark.parametrize("status", ["timeout", "crashed"])
def test_a_car_at_the_goal_that_did_not_arrive_is_no_success(status: str) -> None:
    """In time is a term of its own (``status == "arrived"``): the clean overtake, stopped
    at the goal, past the car and in lane, with no collision judged, is no success when the
    episode ended otherwise (the time limit, or a crash status no judge confirms)."""
    r = evaluate(_episode(_overtake(), _clean_overtake_states(), status=status))
    assert r.reached_goal and r.stopped and r.passed_lead and r.back_in_lane
    assert not r.collision and not r.success and r.outcome == "failed"
    assert failure_reason(r).startswith(f"{status}: the car did not arrive within")


@pytest.mark.parametrize("y_mid, passed, in_lane", [(48.0, False, True), (48.0, True, False)])
def test_an_overtake_needs_both_past_the_car_and_back_in_lane(y_mid: float, passed: bool,
                                                             in_lane: bool) -> None:
    """Overtake success needs the body past the stopped car *and* back in the ego lane:
    stopping at a goal short of the car (in lane, not past) or past it in the oncoming
    lane (past, not in lane) both fail, each naming its term."""
    x_end = 92.0 if passed else 40.0
    y_end = 44.0 if in_lane else 48.0
    scen = _overtake(goal=(x_end, y_end, 0.0))
    x = np.arange(5.0, x_end + 1e-9, 0.2)
    y = np.where((x > 30) & (x < 70), y_mid, 44.0)
    y[-5:] = y_end
    states = _states(x, y, 0.0, np.append(np.full(len(x) - 1, 3.0), 0.0))
    r = evaluate(_episode(scen, states))
    assert r.reached_goal and r.stopped and not r.collision
    assert (r.passed_lead, r.back_in_lane) == (passed, in_lane)
    assert not r.success


def _traffic_episode(status: str, crashed_at: int | None) -> Episode:
    """An overtake-traffic drive in its lane 10 m ahead of the lead car (4 m/s) and pulling
    away at 6 m/s: the overtake is complete all along (body 2 m or more past the lead)."""
    scen = make_scenario("overtake-traffic", 0, jitter=(0.0, 0.0, 0.0))
    n = 41
    t = np.arange(n) * DT
    states = _states(70.0 + 6.0 * t, scen.lane_y, 0.0, 6.0)
    others = _other(n, 60.0 + 4.0 * t, scen.lane_y, 0.0, 4.0)
    crashed = np.zeros(n, bool)
    if crashed_at is not None:
        crashed[crashed_at:] = True
    return _episode(scen, states, others=others, sizes=[CAR], crashed=crashed, status=status,
                    path=_line(60.0, 100.0, scen.lane_y))


def test_a_traffic_timeout_with_a_collision_is_a_collision_not_safe_following() -> None:
    """Outcome order (doc, Outcome): a collision outranks safe following; a clean timeout
    behind the lead car is safe following."""
    assert success_terms(_traffic_episode("timeout", 10)).outcome == "collision"
    assert success_terms(_traffic_episode("timeout", None)).outcome == "safe_following"


def test_a_completed_overtake_that_crashed_reads_completed_but() -> None:
    """``failure_reason``: a status that sounds like a success (``completed`` as ``arrived``)
    is followed by ", but" and the failed terms."""
    r = evaluate(_traffic_episode("completed", 30))
    assert r.reached_goal and not r.success
    assert failure_reason(r) == "completed, but a collision reported by highway-env"


def _report(**changes: Any) -> EpisodeReport:
    """The report of a clean overtake, with ``changes``."""
    return dataclasses.replace(evaluate(_episode(_overtake(), _clean_overtake_states())),
                               **changes)


def test_failure_reason_speaks_of_speed_magnitude_and_only_the_failed_terms() -> None:
    """A car still reversing at 0.3 m/s: "the final speed 0.30 m/s" (its magnitude); a
    position error of exactly 0.5 m is within tolerance and not named."""
    backing = _report(success=False, stopped=False, final_speed=-0.3, outcome="failed")
    assert failure_reason(backing) == "arrived, but the final speed 0.30 m/s exceeds 0.1 m/s"
    edge = _report(success=False, reached_goal=False, goal_position_err_m=0.5,
                   goal_heading_err_rad=math.radians(12.0), outcome="failed")
    assert failure_reason(edge) == "arrived, but the heading error 12.0 deg exceeds 10 deg"


# --------------------------------------------------------------------------- collisions


def test_the_footprint_judge_checks_poses_at_most_a_tenth_apart(monkeypatch: Any) -> None:
    """The logged poses are densified (position and yaw linearly) to at most 0.1 m apart
    before the exact test (doc, Collisions): every pose handed to the checker is recorded."""
    from rrtdrive.planning.base import cached_checker

    scen = _overtake()
    cls = type(cached_checker(scen.map, scen.checker_config))
    seen: list[np.ndarray] = []
    original = cls.poses_free

    def spy(self: Any, poses: np.ndarray, *args: Any, **kwargs: Any) -> np.ndarray:
        seen.append(np.array(poses, dtype=float))
        return original(self, poses, *args, **kwargs)

    monkeypatch.setattr(cls, "poses_free", spy)
    x = np.arange(10.0, 30.0 + 1e-9, 1.0)  # 1 m per logged step, turning 0.02 rad per step
    states = _states(x, 44.0, 0.02 * np.arange(len(x)), 20.0)
    assert not evaluate(_episode(scen, states)).collision_footprint
    dense = seen[0]
    steps = np.hypot(*np.diff(dense[:, :2], axis=0).T)
    assert steps.max() <= 0.1 + 1e-9
    assert np.abs(np.diff(dense[:, 2])).max() <= 0.002 + 1e-9
    for pose in states[:, :3]:  # the logged poses themselves are among them
        assert np.min(np.abs(dense - pose).sum(axis=1)) < 1e-9


def test_a_body_that_passes_through_a_car_between_two_logged_poses_collides() -> None:
    """Two logged poses 10.5 m apart, both clear of the stopped car, the car between them:
    the bodies swept between the poses (shapely) hit it, so the footprint judge does."""
    scen = _overtake()
    lead = _box(50.0, 44.0, 0.0, *CAR)
    states = _states(np.array([43.0, 53.5]), 44.0, 0.0, 5.0)
    assert not any(_body(*s[:3]).intersects(lead) for s in states)
    assert any(_body(x, 44.0, 0.0).intersects(lead) for x in np.linspace(43.0, 53.5, 106))
    r = evaluate(_episode(scen, states, path=_line(40.0, 60.0, 44.0)))
    assert r.collision_footprint and r.collision


def test_the_footprint_judge_turns_the_short_way_across_pi() -> None:
    """Backing east 1 m while the nose swings from yaw 3.0 through pi to -3.0: the body
    turns 0.28 rad, not 6 rad, and stays clear of the stopped car just behind it (shapely);
    swung the long way (through yaw 0) its nose would reach into the car."""
    scen = _overtake()
    lead = _box(50.0, 44.0, 0.0, *CAR)
    f = np.linspace(0.0, 1.0, 201)
    short = [_body(45.5 + s, 44.0, 3.0 + s * (2 * math.pi - 6.0)) for s in f]
    assert not shapely.union_all(short).intersects(lead)
    assert _body(46.0, 44.0, 0.0).intersects(lead)  # the long way round hits it
    states = np.array([[45.5, 44.0, 3.0, -1.0], [46.5, 44.0, -3.0, -1.0]])
    r = evaluate(_episode(scen, states, path=_line(40.0, 45.0, 44.0)))
    assert not r.collision_footprint


def test_a_parked_car_logged_facing_the_other_way_still_counts_once() -> None:
    """The overtake's stopped car logged with heading pi is the same box as the map's
    obstacle (a box turned by pi): crashing into it is one at-fault collision, not two."""
    scen = _overtake()
    x = np.arange(5.0, 48.0, 0.2)
    states = _states(x, 44.0, 0.0, 4.0)
    others = _other(len(x), 50.0, 44.0, math.pi, 0.0)
    r = evaluate(_episode(scen, states, others=others, sizes=[CAR], status="crashed",
                          path=_line(5.0, 92.0, 44.0)))
    assert r.collisions_vehicles == 1 and r.collisions_at_fault == 1


def test_a_moving_car_overlapping_only_the_nose_is_a_footprint_collision() -> None:
    """Another car's logged pose is its body centre: one whose rear reaches 0.15 m over the
    ego's nose (shapely) collides, though its centre is 2 m beyond the nose."""
    scen = _overtake()
    n = 5
    states = _states(20.0 + 3.0 * DT * np.arange(n), 44.0, 0.0, 3.0)
    cx = states[:, 0] + 3.405 + 2.15 - 0.15
    others = _other(n, cx, 44.0, 0.0, 3.0)
    assert _body(*states[0, :3]).intersects(_box(cx[0], 44.0, 0.0, *CAR))
    r = evaluate(_episode(scen, states, others=others, sizes=[CAR], status="timeout"))
    assert r.collision_footprint


def _collide(states: np.ndarray, others: np.ndarray, scen: Any = None) -> list[tuple]:
    """``vehicle_collisions`` of a drive on the overtake road."""
    ep = _episode(scen or _overtake(), states, others=others, sizes=[CAR], status="crashed",
                  path=_line(0.0, 95.0, 44.0))
    return vehicle_collisions(ep)


def test_a_reversing_ego_is_not_a_stopped_ego() -> None:
    """Backing at 1 m/s into a standing car: the ego was moving (|v| > 0.05 m/s), the other
    stood still, so it is a stopped-track collision, at fault (nuPlan)."""
    n = 5
    states = _states(30.0 - 1.0 * DT * np.arange(n), 44.0, 0.0, -1.0)
    cx = 30.0 - 0.895 - 2.15 + 0.1  # the car's front 0.1 m inside the ego's rear bumper
    assert _body(30.0, 44.0, 0.0).intersects(_box(cx, 44.0, 0.0, *CAR))
    assert _collide(states, _other(n, cx, 44.0, 0.0, 0.0)) == [(0, 0, "stopped_track", True)]


def test_a_car_reversing_into_the_ego_is_moving_not_stopped() -> None:
    """A car ahead backing at 2 m/s into the ego's front bumper moves (|v| > 0.05): an
    active front collision, at fault, not a stopped-track one."""
    n = 5
    t = DT * np.arange(n)
    states = _states(20.0 + 1.0 * t, 44.0, 0.0, 1.0)
    cx = 20.0 + 3.405 + 2.15 - 0.1 - 2.0 * t
    assert _collide(states, _other(n, cx, 44.0, 0.0, -2.0)) == [(0, 0, "active_front", True)]


def test_a_reversing_ego_leads_with_its_rear_bumper() -> None:
    """Backing at 1 m/s into a car creeping forward behind it: the ego's leading bumper is
    its rear one (doc, Interaction), and it touches the car: active front, at fault."""
    n = 5
    t = DT * np.arange(n)
    states = _states(30.0 - 1.0 * t, 44.0, 0.0, -1.0)
    cx = 30.0 - 0.895 - 2.15 + 0.1 + 0.5 * t
    rear = shapely.LineString([(30.0 - 0.895, 43.1), (30.0 - 0.895, 44.9)])
    assert rear.intersects(_box(cx[0], 44.0, 0.0, *CAR))
    assert _collide(states, _other(n, cx, 44.0, 0.0, 0.5)) == [(0, 0, "active_front", True)]


def test_being_rear_ended_is_an_active_rear_collision() -> None:
    """A faster car running into the ego from behind (its centre 180 deg off the ego's
    travel): active rear, not at fault, even while the ego straddles the lanes."""
    n = 5
    t = DT * np.arange(n)
    states = _states(20.0 + 2.0 * t, 46.0, 0.0, 2.0)  # on the centre line: between lanes
    cx = 20.0 - 0.895 - 2.15 + 0.1 + 4.0 * t
    assert _collide(states, _other(n, cx, 46.0, 0.0, 4.0)) == [(0, 0, "active_rear", False)]


@pytest.mark.parametrize("lane_y, fault", [(44.0, False), (46.0, True)])
def test_a_side_swipe_is_lateral_and_at_fault_only_between_lanes(lane_y: float,
                                                                 fault: bool) -> None:
    """A car scraping the ego's right side (not its front bumper, shapely): active lateral,
    at fault only when the ego's body lies in two lanes (doc, Interaction)."""
    n = 5
    t = DT * np.arange(n)
    states = _states(20.0 + 2.0 * t, lane_y, 0.0, 2.0)
    cx, cy = 20.0 + 0.5 + 2.0 * t, lane_y - 0.9 - 0.9 + 0.1  # 0.1 m into the right side
    other = _box(cx[0], cy, 0.0, *CAR)
    bumper = shapely.LineString([(23.405, lane_y - 0.9), (23.405, lane_y + 0.9)])
    assert _body(20.0, lane_y, 0.0).intersects(other) and not bumper.intersects(other)
    got = _collide(states, _other(n, cx, cy, 0.0, 2.0))
    assert got == [(0, 0, "active_lateral", fault)]


def test_a_collision_is_dated_at_the_first_overlap() -> None:
    """The collision's time is the first logged time the bodies overlap (shapely), though
    the ego stays in the car and comes to rest inside it."""
    n = 12
    x = 42.0 + 0.4 * np.arange(n)
    v = np.where(np.arange(n) < 8, 4.0, 0.0)
    states = _states(x, 44.0, 0.0, v)
    lead = _box(50.0, 44.0, 0.0, *CAR)
    first = next(k for k in range(n) if _body(x[k], 44.0, 0.0).intersects(lead))
    assert 0 < first < 8
    got = _collide(states, _other(n, 50.0, 44.0, 0.0, 0.0))
    assert got == [(first, 0, "stopped_track", True)]


@pytest.mark.parametrize("y", [41.0, 43.1, 44.0, 45.0, 46.0, 47.0, 48.0, 49.0, 50.5])
@pytest.mark.parametrize("yaw", [0.0, 0.15, -0.3])
def test_between_lanes_against_the_lane_strips(y: float, yaw: float) -> None:
    """The body (shapely) is between lanes when it crosses the centre line y = 46, or off
    the road when it leaves the strip 42 <= y <= 50 (the ego lane and the oncoming lane)."""
    scen = _overtake()
    x = 20.0
    body = _body(x, y, yaw)
    centre = shapely.LineString([(0.0, 46.0), (100.0, 46.0)])
    road = shapely.box(0.0, 42.0, 100.0, 50.0)
    expected = body.crosses(centre) or not road.covers(body)
    ep = _episode(scen, np.array([[x, y, yaw, 1.0], [x, y, yaw, 1.0]]))
    assert between_lanes(ep).tolist() == [expected, expected]


@settings(max_examples=40, deadline=None)
@given(st.lists(st.tuples(st.floats(-12.0, 12.0), st.floats(-12.0, 12.0),
                          st.floats(-math.pi, math.pi), st.floats(2.0, 12.0),
                          st.floats(1.0, 3.0)), min_size=1, max_size=3),
       st.floats(-math.pi, math.pi), st.floats(30.0, 60.0), st.floats(30.0, 60.0))
def test_min_distance_is_the_brute_force_shapely_minimum(
    cars: list[tuple[float, float, float, float, float]], yaw: float, x: float, y: float
) -> None:
    """``min_vehicle_distance`` is the smallest body-to-body distance over every logged time
    and vehicle: brute force with shapely over the bodies drawn here."""
    scen = _open_lot()
    n = 3
    states = _states(x + 0.5 * np.arange(n), y, yaw, 1.0)
    k = len(cars)
    others = np.zeros((n, k, 4))
    for j, (dx, dy, h, _length, _width) in enumerate(cars):
        others[:, j] = [x + dx, y + dy, h, 0.0]
        others[:, j, 0] -= 0.3 * np.arange(n)
    sizes = [(c[3], c[4]) for c in cars]
    ep = _episode(scen, states, others=others, sizes=sizes, status="timeout")
    expected = min(
        _body(*states[i, :3]).distance(_box(*others[i, j, :3], *sizes[j]))
        for i in range(n) for j in range(k)
    )
    assert min_vehicle_distance(ep) == pytest.approx(expected, abs=1e-9)


def test_min_distance_finds_a_long_truck_alongside_behind_a_nearer_centre() -> None:
    """A car ahead whose centre is nearest (6 m, bumpers 1.7 m apart) and a 12 m truck
    alongside whose centre is farther (7.2 m) but whose side is 0.85 m from the ego's:
    the smallest body distance is the truck's (shapely)."""
    scen = _open_lot()
    states = _states(np.array([40.0, 40.0]), 50.0, 0.0, 0.0)
    cx = 40.0 + D
    others = np.array([[[cx + 6.0, 50.0, 0.0, 0.0], [cx + 6.5, 47.0, 0.0, 0.0]]] * 2)
    sizes = [CAR, (12.0, 2.5)]
    ego = _body(40.0, 50.0, 0.0)
    car, truck = _box(cx + 6.0, 50.0, 0.0, *CAR), _box(cx + 6.5, 47.0, 0.0, 12.0, 2.5)
    assert ego.distance(car) == pytest.approx(1.7) and ego.distance(truck) == pytest.approx(0.85)
    ep = _episode(scen, states, others=others, sizes=sizes, status="timeout")
    assert min_vehicle_distance(ep) == pytest.approx(0.85, abs=1e-9)


# --------------------------------------------------------------------------- time to collision


def _projected_ttc(ego: tuple[float, float, float, float],
                   car: tuple[float, float, float, float]) -> float:
    """Brute force: the first of 0.1, 0.2, ..., 2.9 s at which the ego body (rear-axle pose
    moved along its heading at its signed speed) and the car (moved along its heading)
    intersect (shapely, touching counts); ``inf`` when none."""
    x, y, h, v = ego
    cx, cy, ch, cv = car
    for k in range(1, 30):
        t = k / 10.0
        a = _body(x + v * math.cos(h) * t, y + v * math.sin(h) * t, h)
        b = _box(cx + cv * math.cos(ch) * t, cy + cv * math.sin(ch) * t, ch, *CAR)
        if a.intersects(b):
            return t
    return math.inf


def _ttc(states: np.ndarray, others: np.ndarray, at_fault: tuple[int, ...] = ()) -> np.ndarray:
    """``time_to_collision`` of a drive on the overtake road with these other cars."""
    k = others.shape[1]
    ep = _episode(_overtake(), states, others=others, sizes=[CAR] * k, status="timeout",
                  path=_line(0.0, 95.0, 44.0))
    return time_to_collision(ep, at_fault)


def test_ttc_of_a_head_on_car_closes_at_both_speeds() -> None:
    """A car straight ahead in the ego lane coming the other way (heading pi), bumpers
    12.05 m apart, both at 5 m/s: they touch after 12.05 / 10 = 1.205 s, so the first
    projected time is 1.3 s; 0.25 m later (next logged step) 1.155 s -> 1.2 s."""
    states = np.array([[10.0, 44.0, 0.0, 5.0], [10.25, 44.0, 0.0, 5.0]])
    cx = 13.405 + 12.05 + 2.15
    others = np.array([[[cx, 44.0, math.pi, 5.0]], [[cx - 0.25, 44.0, math.pi, 5.0]]])
    ttc = _ttc(states, others)
    ref = [_projected_ttc(tuple(states[i]), tuple(others[i, 0])) for i in range(2)]
    assert ref == pytest.approx([1.3, 1.2])
    assert ttc == pytest.approx(ref, abs=1e-9)


@pytest.mark.parametrize("gap, expected", [(28.95, 2.9), (29.5, None)])
def test_ttc_horizon_ends_at_2_9_s(gap: float, expected: float | None) -> None:
    """nuPlan projects at ``np.arange(0.1, 3.0, 0.1)``: a standing car whose bumper the ego
    (10 m/s) reaches after 2.895 s has TTC 2.9 s; one it reaches after 2.95 s has none
    within the horizon (``ttc_min_s`` null, within bound)."""
    states = np.array([[10.0, 44.0, 0.0, 10.0], [10.0, 44.0, 0.0, 0.0]])  # then standing
    cx = 13.405 + gap + 2.15
    others = _other(2, cx, 44.0, 0.0, 0.0)
    ep = _episode(_overtake(), states, others=others, sizes=[CAR], status="timeout",
                  path=_line(0.0, 95.0, 44.0))
    ref = _projected_ttc(tuple(states[0]), tuple(others[0, 0]))
    assert (ref if math.isfinite(ref) else None) == expected
    r = evaluate(ep)
    assert r.ttc_min_s == (pytest.approx(expected) if expected is not None else None)
    assert r.ttc_within_bound is True


def test_ttc_counts_a_crossing_car_at_45_deg_only_while_between_lanes() -> None:
    """A car ahead-left crossing the ego's path: projected to hit (shapely), but its centre
    is more than 30 deg off the ego's travel, so no TTC while the ego keeps its lane; while
    the ego straddles the lanes every car not behind it counts."""
    car = (18.0, 52.0, -math.pi / 2, 5.0)
    in_lane = np.array([[10.0, 44.0, 0.0, 5.0]] * 2)
    assert math.degrees(math.atan2(52.0 - 44.0, 18.0 - 10.0)) == pytest.approx(45.0)
    assert _projected_ttc(tuple(in_lane[0]), car) == pytest.approx(1.0)
    assert np.all(np.isinf(_ttc(in_lane, np.array([[car]] * 2))))
    between = np.array([[10.0, 46.0, 0.0, 5.0]] * 2)  # 36.9 deg off, body across y = 46
    ref = _projected_ttc(tuple(between[0]), car)
    assert ref == pytest.approx(0.8)
    assert _ttc(between, np.array([[car]] * 2)) == pytest.approx([ref, ref], abs=1e-9)


def test_ttc_of_a_reversing_ego_looks_the_way_it_moves() -> None:
    """Backing at 2 m/s towards a standing car 0.95 m behind the rear bumper: the car is
    ahead of the direction of travel, the ego is projected backwards, TTC 0.95 / 2 = 0.475
    -> 0.5 s."""
    states = np.array([[20.0, 44.0, 0.0, -2.0]] * 2)
    car = (20.0 - 0.895 - 0.95 - 2.15, 44.0, 0.0, 0.0)
    ref = _projected_ttc(tuple(states[0]), car)
    assert ref == pytest.approx(0.5)
    assert _ttc(states, np.array([[car]] * 2)) == pytest.approx([ref, ref], abs=1e-9)


def test_ttc_is_the_least_over_the_cars() -> None:
    """Two standing cars ahead, bumpers 4.95 m and 14.95 m away, at 10 m/s: TTC 0.5 s
    (the nearer, logged first), not 1.5 s (the farther, logged second)."""
    states = np.array([[10.0, 44.0, 0.0, 10.0]] * 2)
    near = (13.405 + 4.95 + 2.15, 44.0, 0.0, 0.0)
    far = (13.405 + 14.95 + 2.15, 44.0, 0.0, 0.0)
    assert _projected_ttc(tuple(states[0]), near) == pytest.approx(0.5)
    assert _projected_ttc(tuple(states[0]), far) == pytest.approx(1.5)
    assert _ttc(states, np.array([[near, far]] * 2)) == pytest.approx([0.5, 0.5], abs=1e-9)


def test_ttc_is_zero_at_an_at_fault_collision_and_then_leaves_that_car_out() -> None:
    """Driving into a standing car: TTC 0 at the collision (at fault: ``ttc_min_s`` 0, not
    within bound); at the next steps, still inside it and moving, that car is left out."""
    n = 12
    x = 43.0 + 0.2 * np.arange(n)
    states = _states(x, 44.0, 0.0, 4.0)
    others = _other(n, 50.0, 44.0, 0.0, 0.0)
    ep = _episode(_overtake(), states, others=others, sizes=[CAR], status="crashed",
                  path=_line(0.0, 95.0, 44.0))
    crashes = vehicle_collisions(ep)
    lead = _box(50.0, 44.0, 0.0, *CAR)
    first = next(k for k in range(n) if _body(x[k], 44.0, 0.0).intersects(lead))
    assert crashes == [(first, 0, "stopped_track", True)]
    assert _body(x[first + 1], 44.0, 0.0).intersects(lead)  # still overlapping after
    ttc = time_to_collision(ep, [first])
    assert ttc[first] == 0.0 and np.all(np.isinf(ttc[first + 1:]))
    assert np.all(np.isfinite(ttc[:first]))
    r = evaluate(ep)
    assert r.ttc_min_s == 0.0 and r.ttc_within_bound is False and r.collisions_at_fault == 1


# --------------------------------------------------------------------------- progress


def test_progress_is_measured_from_the_projection_of_the_first_pose() -> None:
    """``progress_m``: arc length between the projections of the first and last logged rear
    axle: a drive from 12 m to 30 m along a lane path starting at 5 m is 18 m."""
    scen = _overtake(goal=(30.0, 44.0, 0.0))
    states = _states(np.linspace(12.0, 30.0, 61), 44.3, 0.0, 2.0)
    r = evaluate(_episode(scen, states, path=_line(5.0, 60.0, 44.0)))
    assert r.progress_m == pytest.approx(18.0, abs=1e-9)
    assert r.path_length_m == pytest.approx(55.0, abs=1e-9)


# --------------------------------------------------------------------------- comfort


def _steering_episode(steer: np.ndarray, v: float = 4.0) -> Episode:
    """A drive along the overtake lane at ``v`` with these steering angles (not driven: the
    comfort figures read the logged commands)."""
    n = len(steer) + 1
    scen = _overtake(goal=(30.0, 44.0, 0.0))
    states = _states(np.linspace(5.0, 30.0, n), 44.0, 0.0, v)
    return _episode(scen, states, np.column_stack([np.zeros(n - 1), steer]))


def test_max_lateral_accel_counts_right_turns() -> None:
    """``max_lateral_accel = max v^2 |kappa|``: steering right (negative) at 4 m/s with
    kappa = -0.1 is 1.6 m/s^2 (a left turn of 0.05 beside it is 0.8)."""
    steer = np.full(40, -math.atan(V.wheelbase * 0.1))
    steer[:5] = math.atan(V.wheelbase * 0.05)
    r = evaluate(_steering_episode(steer))
    assert r.max_lateral_accel == pytest.approx(16.0 * 0.1, rel=1e-9)


@pytest.mark.parametrize("rate, share", [(0.4, 0.0), (0.45, 1.0)])
def test_steering_rate_share_counts_steps_over_the_0_4_limit(rate: float, share: float) -> None:
    """Steering turned at exactly the 0.4 rad/s limit from straight wheels is within it
    (rounding is no violation); at 0.45 rad/s every step is over it (doc, Drivability)."""
    steer = rate * DT * np.arange(1, 11)  # delta_-1 = 0: the first step turns at `rate` too
    r = evaluate(_steering_episode(steer))
    assert r.max_steering_rate == pytest.approx(rate, rel=1e-9)
    assert r.steering_rate_over_limit_share == share


def test_path_sharpness_counts_curvature_falling_as_well_as_rising() -> None:
    """Sharpness is ``max |d delta / ds|``: curvature stepping down from 0.2 to 0 over 1 m
    is atan(0.2 L) rad/m, however it rises elsewhere (here by 0.05 over 1 m)."""
    xs = np.array([0.0, 1.0, 2.0, 3.0, 4.0])
    kappa = np.array([0.2, 0.0, 0.0, 0.05, 0.05])
    p = Path(np.column_stack([xs, 0 * xs, 0 * xs, kappa]), np.zeros((0, 2)))
    assert path_sharpness(p, V.wheelbase) == pytest.approx(math.atan(V.wheelbase * 0.2))


def test_path_sharpness_skips_the_repeated_row_of_a_cusp() -> None:
    """A cusp repeats its position row (the gear flips): no length to change over, so it is
    skipped; the sharpness is that of the rows around it (0.1 rad over 0.5 m)."""
    rows = np.array([
        [0.0, 0.0, 0.0, 0.0, 1.0],
        [0.5, 0.0, 0.0, math.tan(0.1) / V.wheelbase, 1.0],
        [0.5, 0.0, 0.0, -math.tan(0.1) / V.wheelbase, -1.0],
        [0.0, 0.0, 0.0, -math.tan(0.1) / V.wheelbase, -1.0],
    ])
    assert path_sharpness(Path(rows, np.zeros((0, 2))), V.wheelbase) == pytest.approx(0.2)


def test_curvature_limit_has_a_relative_tolerance_of_1e_9() -> None:
    """``|kappa| > kappa_max`` with relative tolerance 1e-9: one part in 1e12 over the
    limit is rounding (not counted), one part in 1e6 over is a violation."""
    kmax = V.kappa_max
    kappa = np.array([kmax * (1 + 1e-12), -kmax * (1 + 1e-12), kmax * (1 + 1e-6), 0.0])
    assert curvature_violation_share(kappa, kmax, EvalConfig().kappa_tol) == 0.25
    steer = np.arctan(V.wheelbase * kappa)
    r = evaluate(_steering_episode(steer, v=1.0))
    assert r.executed_curvature_violation_share == 0.25
    assert EvalConfig(kappa_tol=0.0).kappa_tol == 0.0  # an exact limit is allowed


# --------------------------------------------------------------------------- nuPlan comfort


def _nuplan_reference(t: np.ndarray, yaw: np.ndarray, v: np.ndarray, d: float) -> list[float]:
    """The six figures as docs/metrics.md's table defines them, on an exact 0.1 s grid:
    rear-axle acceleration (dv/dt, v yaw') shifted to the body centre by
    d (yaw'^2 + yaw''), then scipy's Savitzky-Golay filters with the table's windows."""
    grid = t[0] + 0.1 * np.arange(int(round((t[-1] - t[0]) / 0.1)) + 1)
    heading = np.interp(grid, t, np.unwrap(yaw))
    speed = np.interp(grid, t, v)
    w = np.gradient(heading, grid)
    ax, ay = np.gradient(speed, grid), speed * w
    centre_x = ax + d * (w**2 + np.gradient(w, grid))
    lon = savgol_filter(centre_x, 8, 2)
    lat = savgol_filter(ay, 8, 2)
    mag = savgol_filter(np.hypot(ax, ay), 8, 2)
    return [
        lon.min(), lon.max(), np.abs(lat).max(),
        np.abs(savgol_filter(lon, 15, 2, deriv=1, delta=0.1)).max(),
        np.abs(savgol_filter(mag, 15, 2, deriv=1, delta=0.1)).max(),
        np.abs(savgol_filter(heading, 5, 2, deriv=1, delta=0.1)).max(),
        np.abs(savgol_filter(heading, 5, 3, deriv=2, delta=0.1)).max(),
    ]


NUPLAN_FIELDS = ("nuplan_lon_accel_min", "nuplan_lon_accel_max", "nuplan_lat_accel_abs_max",
                 "nuplan_lon_jerk_abs_max", "nuplan_jerk_abs_max", "nuplan_yaw_rate_abs_max",
                 "nuplan_yaw_accel_abs_max")


@pytest.mark.parametrize("kind", ["slalom", "braking_turn", "wrapped_circle"])
def test_nuplan_figures_of_a_report_follow_the_documented_recipe(kind: str) -> None:
    """Every nuPlan figure of ``evaluate`` equals the doc's recipe recomputed with scipy on
    the logged drive (d = 1.255 m from the rear axle to the body centre)."""
    t = np.arange(0.0, 8.0 + 1e-9, DT)
    if kind == "slalom":
        v, yaw = 3.0 + np.sin(0.7 * t), 0.3 * np.sin(0.9 * t)
    elif kind == "braking_turn":
        v, yaw = np.maximum(8.0 - 0.9 * t, 0.5), 0.02 * t**2
    else:
        v, yaw = np.full_like(t, 2.5), np.angle(np.exp(1j * (3.0 + 0.4 * t)))
    x = np.cumsum(np.concatenate([[0.0], v[:-1] * np.cos(yaw[:-1]) * DT])) + 10.0
    y = np.cumsum(np.concatenate([[0.0], v[:-1] * np.sin(yaw[:-1]) * DT])) + 50.0
    scen = _open_lot()
    r = evaluate(_episode(scen, np.column_stack([x, y, yaw, v]), status="timeout"))
    ref = _nuplan_reference(t, yaw, v, D)
    got = [getattr(r, f) for f in NUPLAN_FIELDS]
    assert got == pytest.approx(ref, rel=1e-7, abs=1e-9)
    b = COMFORT_BOUNDS
    assert r.nuplan_comfortable == bool(
        ref[0] >= b["min_lon_accel"] and ref[1] <= b["max_lon_accel"]
        and ref[2] <= b["max_abs_lat_accel"] and ref[3] <= b["max_abs_lon_jerk"]
        and ref[4] <= b["max_abs_jerk"] and ref[5] <= b["max_abs_yaw_rate"]
        and ref[6] <= b["max_abs_yaw_accel"]
    )


def test_nuplan_longitudinal_accel_of_a_circle_is_the_centres_centripetal_share() -> None:
    """A steady circle, 3 m/s at yaw rate 0.5 rad/s: the rear axle's dv/dt is 0 and the body
    centre, 1.255 m ahead, accelerates by d w^2 = 1.255 * 0.25 = 0.31375 m/s^2 along the
    body; the lateral figure is v w = 1.5 m/s^2 whichever way it turns."""
    t = np.arange(0.0, 6.0 + 1e-9, DT)
    for sign in (1.0, -1.0):
        yaw = sign * 0.5 * t
        x, y = 50.0 + 6.0 * np.sin(yaw) * sign, 50.0 + sign * 6.0 * (1 - np.cos(yaw))
        r = evaluate(_episode(_open_lot(), _states(x, y, yaw, 3.0), status="timeout"))
        assert r.nuplan_lon_accel_min == pytest.approx(0.31375, abs=1e-9)
        assert r.nuplan_lon_accel_max == pytest.approx(0.31375, abs=1e-9)
        assert r.nuplan_lat_accel_abs_max == pytest.approx(1.5, abs=1e-9)
        assert r.nuplan_yaw_rate_abs_max == pytest.approx(0.5, abs=1e-9)


def test_nuplan_jerk_of_a_constant_jerk_launch_is_that_jerk() -> None:
    """v = j t^2 / 2 on a straight line (j = 1 m/s^3): the acceleration is j t, so both
    jerk figures are j, per second (not per 0.1 s sample); only the series' ends, where
    the one-sided differences (off by j dt / 2) and the edge fits sit, read up to 10 %
    more."""
    t = np.arange(0.0, 5.0 + 1e-9, DT)
    c = nuplan_comfort(t, np.zeros_like(t), 0.5 * t**2, D)
    assert c.lon_jerk_abs_max == pytest.approx(1.0, rel=0.1)
    assert c.jerk_abs_max == pytest.approx(1.0, rel=0.1)
    assert c.lon_accel_max == pytest.approx(5.0, rel=0.03)


def test_nuplan_yaw_acceleration_alone_fails_comfort() -> None:
    """A heading wobble 0.1 sin(5.03 t) at 1 m/s, the body centre on the rear axle (d = 0):
    yaw rate about 0.5 rad/s and lateral about 0.5 m/s^2 (within 0.95 and 4.89, the edge
    fits reading a little more), no longitudinal figure, but yaw acceleration about
    0.1 * 5.03^2 = 2.53 rad/s^2, over the 1.93 bound: not comfortable, for that alone."""
    t = np.arange(0.0, 8.0 + 1e-9, DT)
    om = 2 * math.pi * 0.8
    c = nuplan_comfort(t, 0.1 * np.sin(om * t), np.ones_like(t), 0.0)
    assert c.yaw_rate_abs_max == pytest.approx(0.1 * om, rel=0.3)
    assert c.lat_accel_abs_max == pytest.approx(0.1 * om, rel=0.3)
    assert c.yaw_accel_abs_max == pytest.approx(0.1 * om**2, rel=0.15)
    assert c.yaw_accel_abs_max > COMFORT_BOUNDS["max_abs_yaw_accel"]
    assert not c.comfortable
    assert [s.split(" ")[0:2] for s in c.violations()] == [["yaw", "acceleration"]]


def _braking(peak: float) -> tuple[np.ndarray, np.ndarray]:
    """Straight braking from 10 m/s: the deceleration ramps at 2 m/s^3 to ``peak``, holds,
    and ramps back to 0 (jerk 2 m/s^3 within nuPlan's 4.13)."""
    t = np.arange(0.0, 12.0 + 1e-9, DT)
    ramp = peak / 2.0
    a = -np.minimum.reduce([np.clip(2.0 * (t - 1.0), 0, peak),
                            np.clip(2.0 * (1.0 + 2 * ramp + 2.0 - t), 0, peak)])
    v = 10.0 + np.concatenate([[0.0], np.cumsum(0.5 * (a[1:] + a[:-1]) * DT)])
    return t, v


def test_braking_at_3_m_s2_is_within_nuplans_minus_4_05_bound() -> None:
    """Braking at 3 m/s^2 (between -2.40, the acceleration bound, and -4.05, the braking
    bound) is comfortable; at 4.5 m/s^2 it is not."""
    t, v = _braking(3.0)
    c = nuplan_comfort(t, np.zeros_like(t), v, D)
    assert c.lon_accel_min == pytest.approx(-3.0, abs=0.05) and c.comfortable
    t, v = _braking(4.5)
    assert not nuplan_comfort(t, np.zeros_like(t), v, D).comfortable


def test_nuplan_grid_at_25_hz_keeps_the_last_sample() -> None:
    """At 25 Hz the 0.1 s grid runs from the first to the last logged time: heading
    0.05 t^2 over 6 s has yaw rate 0.1 t, largest at the end, 0.6 rad/s (not 0.59)."""
    t = np.arange(151) * 0.04
    c = nuplan_comfort(t, 0.05 * t**2, np.full_like(t, 2.0), D)
    assert c.yaw_rate_abs_max == pytest.approx(0.6, abs=2e-3)


# --------------------------------------------------------------------------- report and summary


def _t_interval(values: list[float]) -> list[float]:
    """Student's t 95 % interval of the mean (scipy)."""
    x = np.asarray(values, dtype=float)
    lo, hi = scipy.stats.t.interval(0.95, len(x) - 1, loc=x.mean(), scale=scipy.stats.sem(x))
    return [float(lo), float(hi)]


def test_signed_fields_get_students_t_intervals() -> None:
    """``progress_m`` and ``final_speed`` can be negative (doc, Aggregates): their interval
    is Student's t (scipy), which may reach below zero, not a bootstrap kept within the
    data: in ``summarise`` and in the bench summary of result rows."""
    from rrtdrive.bench.summary import summarise_rows

    speeds, progress = [-0.05, -0.02, 0.01, 0.03], [-1.0, 2.0, 6.0, 0.5]
    reports = [_report(final_speed=v, progress_m=p) for v, p in zip(speeds, progress, strict=True)]
    s = summarise(reports)
    assert s["progress_m_ci95"] == pytest.approx(_t_interval(progress), rel=1e-9)
    assert s["progress_m_ci95"][0] < min(progress)
    rows = [{"kind": "episode", "scenario": "overtake", "planner": "p", "controller": "c",
             "status": "arrived", "success": True, "final_speed": v, "progress_m": p}
            for v, p in zip(speeds, progress, strict=True)]
    (group,) = summarise_rows(rows)
    for key, values in (("final_speed", speeds), ("progress_m", progress)):
        st = group.stats[key]
        assert [st.ci_low, st.ci_high] == pytest.approx(_t_interval(values), rel=1e-9)


def test_summary_counts_planning_time_of_failed_plans_and_only_false_verdicts() -> None:
    """``planning_time_s`` is averaged over every episode that planned, a failed plan
    included; ``ttc_below_bound`` counts only false verdicts and ``nuplan_comfortable``
    only true ones (``null`` is neither); ``plan_failures`` counts ``plan_failed`` only."""
    drove = _report(planning_time_s=1.0, ttc_within_bound=None, nuplan_comfortable=None)
    timeout = _report(planning_time_s=2.0, status="timeout", success=False, outcome="failed",
                      ttc_within_bound=False, nuplan_comfortable=True)
    failed = _report(planning_time_s=6.0, status="plan_failed", steps=0, success=False,
                     outcome="failed", ttc_within_bound=None, nuplan_comfortable=None)
    s = summarise([drove, timeout, failed])
    assert s["planning_time_s_mean"] == pytest.approx(3.0)
    assert s["planning_time_s_max"] == 6.0
    assert s["ttc_below_bound"] == 1 and s["nuplan_comfortable"] == 1
    assert s["plan_failures"] == 1


def test_summary_min_and_median_of_ttc_distance_and_completion() -> None:
    """The minimum and median over the episodes that have a value: TTCs 2.5, 0.5, none and
    1.0 s give min 0.5 and median 1.0 (not the mean 1.33)."""
    reports = [_report(ttc_min_s=v, min_distance_m=d)
               for v, d in ((2.5, 4.0), (0.5, 9.0), (None, 3.0), (1.0, 8.0))]
    s = summarise(reports)
    assert s["ttc_min_s_min"] == 0.5 and s["ttc_min_s_median"] == 1.0
    assert s["min_distance_m_min"] == 3.0 and s["min_distance_m_median"] == 6.0


def test_report_json_rounds_to_six_significant_digits_and_drops_non_finite() -> None:
    """``to_json``: floats to 6 significant digits, NaN and infinities as null, so that the
    JSON is strict."""
    r = _report(cte_rms_m=0.0123456789, max_jerk=float("nan"), max_steering_rate=float("inf"),
                path_length_m=87.123456)
    js = r.to_json()
    assert js["cte_rms_m"] == 0.0123457 and js["path_length_m"] == 87.1235
    assert js["max_jerk"] is None and js["max_steering_rate"] is None
    json.dumps(js, allow_nan=False)


def test_replan_statistics_are_median_max_and_cycles_over_budget() -> None:
    """Re-planning figures of an overtake-traffic log: cycle wall times 0.1, 0.2 and 0.9 s
    at 4 Hz (budget 0.25 s) give median 0.2, max 0.9 and one cycle over budget."""
    cfg = ReplanConfig()
    records = tuple(ReplanRecord(t=0.25 * i, trigger="periodic", mode="follow", outcome="kept",
                                 wall_time_s=w, planning_time_s=0.0, iterations=0, nodes=0,
                                 goal_x=None, message="")
                    for i, w in enumerate((0.9, 0.1, 0.2)))
    traffic = TrafficLog(records, (), Path.empty(), (), 3, None, cfg)
    ep = dataclasses.replace(_traffic_episode("completed", None), traffic=traffic)
    assert cfg.cycle_budget_s == 0.25
    assert replan_stats(ep) == {
        "replans": 3, "replan_time_median_s": 0.2, "replan_time_max_s": 0.9,
        "replan_budget_s": 0.25, "replans_over_budget": 1, "unsafe_steps": 3,
    }


def test_nuplan_yaw_acceleration_is_a_cubic_fit_up_to_the_last_sample() -> None:
    """Heading 0.01 t^3 over 4 s: yaw acceleration 0.06 t, largest at the end, 0.24 rad/s^2.
    ``savgol(5, 3)`` fits a cubic, so it is exact up to the last sample (a quadratic fit
    agrees inside the series but reads the ends 0.2 s early, 0.228)."""
    t = np.arange(0.0, 4.0 + 1e-9, DT)
    c = nuplan_comfort(t, 0.01 * t**3, np.full_like(t, 2.0), D)
    assert c.yaw_accel_abs_max == pytest.approx(0.24, rel=1e-6)


def test_a_long_time_limit_reads_in_seconds_not_notation():
    # A 500 m map's limit is about 1474 s: "within 1.23e+03 s" (an audit).
    import dataclasses

    from rrtdrive.evaluation import failure_reason

    r = evaluate(_episode(_overtake(), _clean_overtake_states(), status="timeout"))
    for duration, text in ((1234.5, "1234.5 s"), (30.0, "30 s"), (7.25, "7.25 s")):
        late = dataclasses.replace(r, duration_s=duration)
        assert f"did not arrive within {text}" in failure_reason(late)
