"""Audit (session 46): the planners' guarantees on random maps a user could write.

A demanding student's view of SPEC.md section 3 and the README's "Planners" and
``rrtdrive verify`` paragraphs. Hypothesis draws maps (bounds 20-80 m, 0-12 axis-aligned
or rotated rectangles, a start and a goal that the car's body fits at, some of them close
to an obstacle) and plans them with ``improved-rrt-connect`` and ``hybrid-a-star``,
forward only and with reverse, on small counted budgets. Every solved path must pass
``rrtdrive.verify.verify_path`` with the bounds ``rrtdrive verify`` uses (the default
planners' sharpness bound, the plan's ``body_clearance_m`` less 2 mm) and this file's own
shapely checks (body at densified poses, exact end poses, gears, |kappa|, cusps); every
failure must have a documented status and a message in the user's terms; a
``proven_unreachable`` answer must not be contradicted by a path another planner finds;
the same seed must give the same result; a translated or mirrored map must be answered
as successfully.
"""

from __future__ import annotations

import dataclasses
import math
import warnings

import numpy as np
import pytest
import shapely
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from shapely.geometry import Polygon, box

from rrtdrive import Budget, InputError, Map, Obstacle, Pose, VehicleParams
from rrtdrive.collision import CollisionChecker
from rrtdrive.planning import PlanningProblem, make_planner
from rrtdrive.planning.smoothing.config import SmoothingConfig, sharpness_bound
from rrtdrive.types import PlanStatus
from rrtdrive.verify import verify_path
from rrtdrive.verify_cli import CLEARANCE_SLACK_M

PLANNERS = ("improved-rrt-connect", "hybrid-a-star")
CAR = VehicleParams()
REAR = (CAR.length - CAR.wheelbase) / 2.0  # 0.895 m behind the rear axle
FRONT = CAR.length - REAR  # 3.405 m ahead of it
#: The bound ``rrtdrive verify`` checks by default (verify_cli.py: sharpness_bound of the
#: default smoothing config and the car's steering rate): 0.2 rad/m.
MAX_SHARPNESS = sharpness_bound(SmoothingConfig().max_sharpness, CAR.max_steer_rate)
SMALL = Budget(max_iterations=600, max_time_s=30.0)
BIG = Budget(max_iterations=4000, max_time_s=60.0)
MIRROR_BIG = Budget(max_iterations=8000, max_time_s=60.0)
DOCUMENTED = {s.value for s in PlanStatus}
#: Words a user-facing failure message should lead with, per status (README "statuses").
STATUS_WORDS = {
    PlanStatus.NO_PATH_IN_BUDGET: ("no path", "budget"),
    PlanStatus.PROVEN_UNREACHABLE: ("no path", "unreachable"),
    PlanStatus.POSTPROCESS_FAILED: ("post-processing failed",),
    PlanStatus.INVALID_START: ("start",),
    PlanStatus.INVALID_GOAL: ("goal",),
    PlanStatus.TIMEOUT: ("safety cap",),
}
#: What a message in the user's terms never shows: Python internals.
INTERNALS = ("Traceback", "array(", "np.", "numpy", "Exception", "None", " nan", "<")

FAST = settings(
    max_examples=15,
    deadline=None,
    derandomize=True,
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much],
)


# --------------------------------------------------------------------------- maps


@st.composite
def user_maps(draw: st.DrawFn) -> Map:
    """A map as a user would write it: a box, rectangles, a valid start and goal."""
    width = draw(st.floats(20.0, 80.0))
    height = draw(st.floats(20.0, 80.0))
    x0 = draw(st.floats(-50.0, 50.0))
    y0 = draw(st.floats(-50.0, 50.0))
    bounds = (x0, y0, x0 + width, y0 + height)
    frac = st.floats(0.0, 1.0)
    obstacles = []
    for _ in range(draw(st.integers(0, 12))):
        cx, cy = x0 + draw(frac) * width, y0 + draw(frac) * height
        size = (draw(st.floats(0.5, 15.0)), draw(st.floats(0.5, 6.0)))
        rotated = draw(st.booleans())
        axis = st.sampled_from([0.0, math.pi / 2])
        yaw = draw(st.floats(-math.pi, math.pi)) if rotated else draw(axis)
        obstacles.append(Obstacle((cx, cy), size, yaw))
    obstacles_t = tuple(obstacles)
    checker_map = None
    poses: list[Pose] = []
    for _ in range(40):
        if len(poses) == 2:
            break
        if obstacles and draw(st.integers(0, 3)) == 0:
            pose = _beside(obstacles[draw(st.integers(0, len(obstacles) - 1))],
                           draw(frac), draw(st.sampled_from([0.02, 0.08, 0.14, 0.3])),
                           draw(st.booleans()), draw(st.booleans()))
        else:
            pose = Pose(x0 + draw(frac) * width, y0 + draw(frac) * height,
                        draw(st.floats(-math.pi, math.pi)))
        if _body_fits(bounds, obstacles_t, pose):
            poses.append(pose)
    if len(poses) < 2:
        # A map whose free space is too small for two poses: the car at its centre
        # without obstacles, so that every draw still yields a map.
        obstacles_t = ()
        poses = [Pose(x0 + 3.0, y0 + height / 2, 0.0), Pose(x0 + width - 6.0, y0 + 3.0, 0.0)]
    checker_map = Map("audit", bounds, obstacles_t, poses[0], poses[1])
    return checker_map


def _beside(o: Obstacle, along: float, gap: float, side: bool, flip: bool) -> Pose:
    """A pose parked beside obstacle ``o``, its body ``gap`` from its long side."""
    c, s = math.cos(o.yaw), math.sin(o.yaw)
    t = (along - 0.5) * o.size[0]
    off = (o.size[1] / 2 + gap + CAR.width / 2) * (1 if side else -1)
    cx, cy = o.center[0] + c * t - s * off, o.center[1] + s * t + c * off
    yaw = o.yaw + (math.pi if flip else 0.0)
    yaw = math.remainder(yaw, math.tau)
    mid = (FRONT - REAR) / 2.0  # the body centre lies this far ahead of the rear axle
    return Pose(cx - mid * math.cos(yaw), cy - mid * math.sin(yaw), yaw)


def body(x: float, y: float, yaw: float) -> Polygon:
    """The car's exact body rectangle at rear-axle pose ``(x, y, yaw)`` (SPEC section 1)."""
    c, s = math.cos(yaw), math.sin(yaw)
    hw = CAR.width / 2
    corners = [(-REAR, -hw), (FRONT, -hw), (FRONT, hw), (-REAR, hw)]
    return Polygon([(x + c * a - s * b, y + s * a + c * b) for a, b in corners])


def _body_fits(bounds: tuple[float, ...], obstacles: tuple[Obstacle, ...], pose: Pose) -> bool:
    b = body(pose.x, pose.y, pose.yaw)
    if not box(*bounds).contains(b):
        return False
    return not any(b.intersects(o.polygon()) for o in obstacles)


def translated(m: Map, dx: float, dy: float) -> Map:
    x0, y0, x1, y1 = m.bounds
    return Map(
        m.name, (x0 + dx, y0 + dy, x1 + dx, y1 + dy),
        tuple(Obstacle((o.center[0] + dx, o.center[1] + dy), o.size, o.yaw) for o in m.obstacles),
        Pose(m.start.x + dx, m.start.y + dy, m.start.yaw),
        Pose(m.goal.x + dx, m.goal.y + dy, m.goal.yaw),
    )


def mirrored(m: Map) -> Map:
    """``m`` mirrored about its horizontal centre line (y -> -y, yaw -> -yaw)."""
    x0, y0, x1, y1 = m.bounds
    s = y0 + y1

    def flip(p: Pose) -> Pose:
        return Pose(p.x, s - p.y, -p.yaw)

    return Map(
        m.name, m.bounds,
        tuple(Obstacle((o.center[0], s - o.center[1]), o.size, -o.yaw) for o in m.obstacles),
        flip(m.start), flip(m.goal),
    )


# --------------------------------------------------------------------------- planning


def plan(m: Map, planner: str, reverse: bool, budget: Budget = SMALL, seed: int = 1,
         fresh_checker: bool = False):
    checker = CollisionChecker.for_map(m) if fresh_checker else None
    problem = dataclasses.replace(PlanningProblem.from_map(m, checker=checker), reverse=reverse)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return make_planner(planner).solve(problem, np.random.default_rng(seed), budget)


def verifier_clearance(result) -> float:
    """What ``rrtdrive verify`` asks by default: ``body_clearance_m`` less 2 mm, else 0."""
    kept = result.stats.get("body_clearance_m")
    if kept is None or kept < CLEARANCE_SLACK_M:
        return 0.0
    return float(kept) - CLEARANCE_SLACK_M


def densified(rows: np.ndarray, step: float = 0.05) -> np.ndarray:
    """Poses at most ``step`` apart between the rows (position and yaw interpolated)."""
    out = [rows[0, :3]]
    for a, b in zip(rows[:-1], rows[1:], strict=True):
        n = max(1, math.ceil(math.hypot(b[0] - a[0], b[1] - a[1]) / step))
        dyaw = math.remainder(b[2] - a[2], math.tau)
        for k in range(1, n + 1):
            t = k / n
            out.append(np.array([a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]),
                                 a[2] + t * dyaw]))
    return np.array(out)


def own_violations(m: Map, rows: np.ndarray, reverse: bool, clearance: float) -> list[str]:
    """This file's own checks of a solved path; an empty list when all hold."""
    bad: list[str] = []
    if len(rows) < 2:
        return [f"a solved path of {len(rows)} rows"]
    area = box(*m.bounds)
    obstacles = shapely.union_all([o.polygon() for o in m.obstacles]) if m.obstacles else None
    for pose in densified(rows):
        b = body(*pose)
        if not area.contains(b) or (obstacles is not None and b.intersects(obstacles)):
            bad.append(f"body collides at {np.round(pose, 3).tolist()}")
            break
        edge = area.exterior.distance(b)
        near = edge if obstacles is None else min(edge, obstacles.distance(b))
        if near < clearance:  # already 2 mm under the claim (verify_cli.py)
            bad.append(f"body {near:.4f} m from an obstacle at {np.round(pose, 3).tolist()}, "
                       f"the plan claims {clearance + CLEARANCE_SLACK_M:.3f} m")
            break
    for name, row, pose in (("start", rows[0], m.start), ("goal", rows[-1], m.goal)):
        if math.hypot(row[0] - pose.x, row[1] - pose.y) > 1e-6:
            bad.append(f"first/last row is not the {name} position")
        if abs(math.remainder(row[2] - pose.yaw, math.tau)) > 2e-6:
            bad.append(f"first/last row is not the {name} yaw")
    gears = rows[:, 4]
    if not set(np.unique(gears).tolist()) <= {1.0, -1.0}:
        bad.append(f"gears {np.unique(gears).tolist()}")
    if not reverse and not np.all(gears == 1.0):
        bad.append("a forward-only plan has reverse rows")
    if np.max(np.abs(rows[:, 3])) > CAR.kappa_max + 1e-9:
        bad.append(f"|kappa| {np.max(np.abs(rows[:, 3])):.6f} > kappa_max {CAR.kappa_max:.6f}")
    for i in np.flatnonzero(gears[1:] != gears[:-1]) + 1:
        moved = math.hypot(*(rows[i, :2] - rows[i - 1, :2]))
        turned = abs(math.remainder(rows[i, 2] - rows[i - 1, 2], math.tau))
        if moved > 1e-9 or turned > 1e-9:
            bad.append(f"the cusp at row {i} does not repeat the pose ({moved} m, {turned} rad)")
    steps = np.hypot(*np.diff(rows[:, :2], axis=0).T)
    if steps.max() > 0.25 + 1e-9:
        bad.append(f"rows {steps.max():.3f} m apart (README: at most 0.25 m)")
    return bad


def check_failure_message(result) -> None:
    assert result.status.value in DOCUMENTED
    assert len(result.path) == 0, "a failed plan returned a path"
    msg = result.message
    assert msg.strip(), f"{result.status.value} with an empty message"
    low = msg.lower()
    words = STATUS_WORDS[result.status]
    assert any(w in low for w in words), f"{result.status.value}: {msg[:200]}"
    for internal in INTERNALS:
        assert internal not in msg, f"{internal!r} in a user's message: {msg[:300]}"


def contradicting_path(m: Map, reverse: bool):
    """A solved result of another planner/budget/seed where a proof says none exists.

    A forward-only proof is contradicted only by a forward path; a proof with reverse
    allowed by any path.
    """
    for planner in PLANNERS:
        for rev in (False, True) if reverse else (False,):
            for seed in (3, 11):
                r = plan(m, planner, rev, BIG, seed=seed)
                if r.success:
                    return r
    return None


# --------------------------------------------------------------------------- tests


@FAST
@given(user_maps())
def test_every_answer_keeps_the_guarantees(m: Map) -> None:
    """Every solved path passes verify_path and the own checks; every failure is honest."""
    for planner in PLANNERS:
        for reverse in (False, True):
            r = plan(m, planner, reverse)
            label = f"{planner} reverse={reverse} on {m!r}"
            if r.success:
                rows = np.asarray(r.path.samples)
                clearance = verifier_clearance(r)
                check = verify_path(m, r.path, max_sharpness=MAX_SHARPNESS, clearance=clearance)
                assert check.ok, f"{label}: verify_path failed {check.failed}"
                assert not own_violations(m, rows, reverse, clearance), (
                    f"{label}: {own_violations(m, rows, reverse, clearance)}")
                assert r.path.is_forward_only or reverse, label
            else:
                check_failure_message(r)
                if r.status is PlanStatus.PROVEN_UNREACHABLE:
                    found = contradicting_path(m, reverse)
                    assert found is None, (
                        f"{label}: proven_unreachable ({r.message[:200]}) but "
                        f"{found.planner} solved it: {found.message[:120]}")


def _walled_goal_map() -> Map:
    """A goal boxed in by four walls: no motion of any kind reaches it."""
    walls = (
        Obstacle((40.0, 30.0), (14.0, 0.6)), Obstacle((40.0, 42.0), (14.0, 0.6)),
        Obstacle((33.0, 36.0), (0.6, 12.6)), Obstacle((47.0, 36.0), (0.6, 12.6)),
    )
    return Map("walled", (0.0, 0.0, 60.0, 50.0), walls, Pose(5.0, 5.0, 0.0),
               Pose(38.0, 36.0, 0.0))


@pytest.mark.parametrize("planner", PLANNERS)
@pytest.mark.parametrize("reverse", [False, True])
def test_a_walled_in_goal_is_proven_unreachable_and_really_is(planner: str, reverse: bool) -> None:
    m = _walled_goal_map()
    r = plan(m, planner, reverse)
    assert r.status is PlanStatus.PROVEN_UNREACHABLE
    check_failure_message(r)
    assert contradicting_path(m, True) is None


@pytest.mark.parametrize("planner", PLANNERS)
def test_a_gap_one_centimetre_narrower_than_the_car_fails_and_a_wide_one_solves(
    planner: str,
) -> None:
    """A wall across the map with one gap: 1.79 m is unpassable, 3.5 m is easy."""

    def gap_map(gap: float) -> Map:
        top = 30.0 - (15.0 + gap / 2)
        return Map("gap", (0.0, 0.0, 60.0, 30.0), (
            Obstacle((30.0, (15.0 - gap / 2) / 2), (1.0, 15.0 - gap / 2)),
            Obstacle((30.0, 30.0 - top / 2), (1.0, top)),
        ), Pose(5.0, 15.0, 0.0), Pose(50.0, 15.0, 0.0))

    narrow = plan(gap_map(CAR.width - 0.01), planner, True)
    assert not narrow.success
    check_failure_message(narrow)
    wide = plan(gap_map(3.5), planner, False)
    assert wide.success, wide.message
    assert verify_path(gap_map(3.5), wide.path, max_sharpness=MAX_SHARPNESS,
                       clearance=verifier_clearance(wide)).ok


@settings(max_examples=6, deadline=None, derandomize=True, database=None,
          suppress_health_check=[HealthCheck.too_slow])
@given(user_maps(), st.sampled_from(PLANNERS), st.booleans(), st.integers(0, 2**31))
def test_same_seed_same_answer(m: Map, planner: str, reverse: bool, seed: int) -> None:
    """Same map, planner, seed and budget: the same rows, status, iterations and message,
    also with a freshly built collision checker (no per-map cache)."""
    a = plan(m, planner, reverse, seed=seed)
    b = plan(m, planner, reverse, seed=seed)
    c = plan(m, planner, reverse, seed=seed, fresh_checker=True)
    for other in (b, c):
        assert other.status is a.status
        assert other.iterations == a.iterations
        assert other.nodes == a.nodes
        assert other.message == a.message
        assert np.array_equal(np.asarray(other.path.samples), np.asarray(a.path.samples))


def assert_equally_successful(m: Map, other: Map, planner: str, reverse: bool) -> None:
    """``other`` (an image of ``m``) is answered as successfully as ``m``.

    At the small budget the two may differ at the edge of the budget (a rough edge: the
    search is not mirror-symmetric); then the one that failed must solve with a larger
    budget. Every path must pass the verifier on its own map.
    """
    a = plan(m, planner, reverse)
    b = plan(other, planner, reverse)
    for result, where in ((a, m), (b, other)):
        if result.success:
            check = verify_path(where, result.path, max_sharpness=MAX_SHARPNESS,
                                clearance=verifier_clearance(result))
            assert check.ok, check.failed
    if a.success != b.success:
        retry = plan(other if a.success else m, planner, reverse, MIRROR_BIG)
        assert retry.success, (
            f"{planner} reverse={reverse}: solved on one map, not on its image even with "
            f"{MIRROR_BIG.max_iterations} iterations: {retry.message[:200]}")


@settings(max_examples=6, deadline=None, derandomize=True, database=None,
          suppress_health_check=[HealthCheck.too_slow])
@given(user_maps(), st.sampled_from(PLANNERS), st.booleans())
def test_a_translated_map_is_answered_alike(m: Map, planner: str, reverse: bool) -> None:
    """Moving the whole map by (+1000, -500) m changes nothing but the coordinates."""
    assert_equally_successful(m, translated(m, 1000.0, -500.0), planner, reverse)


@settings(max_examples=6, deadline=None, derandomize=True, database=None,
          suppress_health_check=[HealthCheck.too_slow])
@given(user_maps(), st.sampled_from(PLANNERS), st.booleans())
def test_a_mirrored_map_is_answered_alike(m: Map, planner: str, reverse: bool) -> None:
    """The mirror image (y -> -y, yaw -> -yaw) of a query is answered as successfully."""
    assert_equally_successful(m, mirrored(m), planner, reverse)


def _asymmetric_map() -> Map:
    return Map("audit", (10.51930287052675, 50.0, 55.64851570515636, 75.58083136350008), (
        Obstacle((17.75584234683263, 75.58083136350008), (7.884439319429871, 5.083201402290165)),
        Obstacle((10.51930287052675, 57.26348547834782), (13.430531976802166, 1.0)),
        Obstacle((30.020462730230847, 50.0), (0.5280859915408489, 4.044935519600438), 0.001),
        Obstacle((48.34775686085324, 58.35579557320128), (11.714980807317959, 1.5),
                 1.6411085806837518),
        Obstacle((44.11686306512643, 52.10658591204674), (8.412905019983025, 1.05)),
        Obstacle((20.1885228189724, 55.449283573017716), (12.396533310133208, 4.983203540288867)),
        Obstacle((10.56443208336138, 65.62621702380531), (10.327136350562133, 0.5)),
    ), Pose(13.659545487046302, 72.119230662355, 0.0),
        Pose(46.41363768089654, 58.06172385417679, -1.5004840729060414))


@pytest.mark.parametrize("planner", PLANNERS)
def test_a_mirror_asymmetry_is_a_matter_of_budget_only(planner: str) -> None:
    """Found by this audit: forward only, this map's mirror image solves in 386
    iterations and the map itself only with 3 874 (600 and 2 000 fail: a rough edge).
    Both must solve with enough budget, with verified paths."""
    m = _asymmetric_map()
    for variant in (m, mirrored(m)):
        r = plan(variant, planner, False, MIRROR_BIG)
        assert r.success, r.message
        assert verify_path(variant, r.path, max_sharpness=MAX_SHARPNESS,
                           clearance=verifier_clearance(r)).ok


def test_start_is_goal_is_solved_with_a_zero_length_path() -> None:
    m = Map("same", (0.0, 0.0, 30.0, 30.0), (), Pose(10.0, 10.0, 0.4), Pose(10.0, 10.0, 0.4))
    for planner in PLANNERS:
        for reverse in (False, True):
            r = plan(m, planner, reverse)
            assert r.success, r.message
            assert r.path.length == 0.0
            assert not own_violations(m, np.asarray(r.path.samples), reverse, 0.0)


def test_a_start_inside_an_obstacle_is_refused_naming_start() -> None:
    """Through the Python API a bad start is refused before planning, naming ``start``."""
    with pytest.raises(InputError, match="start"):
        Map("bad", (0.0, 0.0, 30.0, 30.0), (Obstacle((10.0, 10.0), (4.0, 4.0)),),
            Pose(10.0, 10.0, 0.0), Pose(25.0, 25.0, 0.0))


def test_a_start_a_tenth_of_a_millimetre_from_the_bounds_is_planned_honestly() -> None:
    """Less than the usual 0.15 m at the start: the path keeps what the start has, and
    ``body_clearance_m`` says so (README), which the verifier then requires."""
    m = Map("tight", (0.0, 0.0, 40.0, 20.0), (), Pose(0.8951, 10.0, 0.0), Pose(30.0, 10.0, 0.0))
    for planner in PLANNERS:
        r = plan(m, planner, False, Budget(max_iterations=1000))
        assert r.success, r.message
        assert 0.0 < r.stats["body_clearance_m"] < 0.15
        assert verify_path(m, r.path, max_sharpness=MAX_SHARPNESS,
                           clearance=verifier_clearance(r)).ok
        assert not own_violations(m, np.asarray(r.path.samples), False, verifier_clearance(r))


@pytest.mark.parametrize("planner", PLANNERS)
def test_a_car_pinned_in_a_corner_is_proven_stuck_and_really_is(planner: str) -> None:
    """Its side 0.1 mm above the bottom edge, its rear 5 mm from the left one: any turn
    swings a corner into a wall, and straight ahead ends at the far wall."""
    m = Map("corner", (0.0, 0.0, 40.0, 20.0), (), Pose(0.9, 0.9001, 0.0), Pose(30.0, 10.0, 0.0))
    r = plan(m, planner, False)
    assert r.status is PlanStatus.PROVEN_UNREACHABLE
    check_failure_message(r)
    assert contradicting_path(m, False) is None


@pytest.mark.parametrize("planner", PLANNERS)
def test_a_gap_narrower_than_the_car_is_never_solved_and_diagnosed(planner: str) -> None:
    """A 1.7 m gap (the car is 1.8 m wide): the status is no_path_in_budget, not a proof
    (the connectivity proof only uses the 0.895 m disc about the rear axle: a rough edge),
    but the diagnosis names the gap as narrower than the car."""
    lo, hi = 15.0 - 0.85, 15.0 + 0.85
    m = Map("gap", (0.0, 0.0, 60.0, 30.0), (
        Obstacle((30.0, lo / 2), (1.0, lo)), Obstacle((30.0, (hi + 30.0) / 2), (1.0, 30.0 - hi)),
    ), Pose(5.0, 15.0, 0.0), Pose(50.0, 15.0, 0.0))
    r = plan(m, planner, True)
    assert not r.success
    check_failure_message(r)
    assert r.diagnosis is not None
    assert "narrower than the car" in r.diagnosis.message
