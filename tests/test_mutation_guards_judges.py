"""Mutation guards for the outside judges: the OMPL comparators and the CommonRoad judge.

``rrtdrive.bench.ompl_planners`` (extra ``[ompl]``): the Dubins and Reeds–Shepp spaces
are checked against the closed-form lengths of a half turn on the car's minimum
turning radius and of a straight reverse; the validity checker against shapely bodies
(a valid state is a free body); the motion check against the documented 0.25 m by
counting checks on a straight motion; the time budget, range, algorithm and cost
threshold against what OMPL itself reports; the returned rows against their own
geometry (gaps, the gear of each row from the direction of travel, the curvature
per gear segment <= kappa_max, the ends equal to the query's poses) and, for
:func:`gear_rows`, against arcs of known curvature driven forward and back.

``rrtdrive.commonroad_judge`` (extra ``[commonroad]``): trajectories whose
feasibility is known in closed form: a constant-speed straight line at any heading,
steering ramps clearly above or below the 0.4 rad/s limit in either direction,
circles of the kinematic bicycle (scipy's ``solve_ivp`` of the single-track model
with the steering ramped as CommonRoad integrates it), logs shifted off the inputs'
trajectory by known amounts against the documented tolerances, and the speed limits
of the BMW 320i set read from ``vehiclemodels`` itself.

Found by mutation testing of both modules (each test names the slips it catches).
Each half skips cleanly where its extra is not installed.
"""

from __future__ import annotations

import importlib
import math
import sys
from collections.abc import Callable
from pathlib import Path as FsPath
from typing import Any

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import solve_ivp

from rrtdrive.geometry import wrap_angle
from rrtdrive.maps import Map, Obstacle, builtin_map
from rrtdrive.types import Budget, InputError, Path, Pose, VehicleParams
from rrtdrive.vehicle import footprint_polygon
from rrtdrive.verify import verify_path


def _importable(name: str) -> bool:
    try:
        importlib.import_module(name)
    except ImportError:
        return False
    return True


# Module-level skips as pytest.importorskip would give, but per test: gear_rows needs
# neither extra and runs everywhere.
HAVE_OMPL = _importable("ompl.base")
HAVE_CR = _importable("commonroad_dc.feasibility.feasibility_checker")
needs_ompl = pytest.mark.skipif(not HAVE_OMPL, reason="OMPL is not installed (the [ompl] extra)")
needs_cr = pytest.mark.skipif(
    not HAVE_CR, reason="CommonRoad is not installed (the [commonroad] extra)"
)

CAR = VehicleParams()
NO_WAYPOINTS = np.zeros((0, 2))


# ----------------------------------------------------------------------------- OMPL helpers


def _problem(m: Map, reverse: bool = False) -> Any:
    from rrtdrive.planning import PlanningProblem

    return PlanningProblem.from_map(m, reverse=reverse)


def _wall_map() -> Map:
    """A 62 m x 30 m lot (no two bounds alike) with a wall across it (x 29.9-30.1, y 5-25)."""
    wall = Obstacle((30.0, 15.0), (0.2, 20.0), 0.0)
    bounds = (-2.0, 1.0, 60.0, 31.0)
    return Map("wall", bounds, (wall,), Pose(8.0, 15.0, 0.0), Pose(50.0, 15.0, 0.0))


def _state(space: Any, x: float, y: float, yaw: float) -> Any:
    s = space.allocState()
    s.setX(x)
    s.setY(y)
    s.setYaw(yaw)
    return s


def _body_free(m: Map, pose: tuple[float, float, float]) -> bool:
    """Shapely: the body at ``pose`` is inside the bounds and touches no obstacle."""
    body = footprint_polygon(pose, m.vehicle)
    inside = shapely.box(*m.bounds).contains(body)
    return inside and not any(body.intersects(o.polygon()) for o in m.obstacles)


def _row_gears(samples: np.ndarray) -> np.ndarray:
    """The gear of each step from its chord against the rows' yaw (skipping repeats)."""
    d = np.diff(samples[:, :2], axis=0)
    yaw = samples[:-1, 2]
    return np.sign(d[:, 0] * np.cos(yaw) + d[:, 1] * np.sin(yaw))


def _segment_curvatures(path: Path) -> list[np.ndarray]:
    """|d yaw / ds| per step within each gear segment (never across a cusp)."""
    out = []
    for a, b in path.segments():
        run = path.samples[a:b]
        ds = np.hypot(*np.diff(run[:, :2], axis=0).T)
        out.append(np.abs(wrap_angle(np.diff(run[:, 2]))) / ds)
    return out


def _assert_drivable_rows(m: Map, path: Path, start: Pose, goal: Pose) -> None:
    """Rows 0.25 m apart, gears from the travel, kappa <= kappa_max per segment, ends."""
    s = path.samples
    assert np.allclose(s[0, :3], [start.x, start.y, wrap_angle(start.yaw)], atol=1e-6)
    assert np.allclose(s[-1, :2], [goal.x, goal.y], atol=1e-6)
    assert abs(wrap_angle(s[-1, 2] - goal.yaw)) < 1e-6
    gaps = np.hypot(*np.diff(s[:, :2], axis=0).T)
    assert gaps.max() <= 0.25 + 1e-9
    moving = gaps > 1e-9
    # Every moving step runs along its row's gear (within the turn of one step).
    assert np.array_equal(_row_gears(s)[moving], s[:-1, 4][moving])
    for c in path.cusps:  # a cusp row repeats exactly
        assert np.array_equal(s[c - 1, :3], s[c, :3])
    for k in _segment_curvatures(path):
        assert k.max() <= m.vehicle.kappa_max * 1.02
    assert verify_path(m, path).ok


class _Spy:
    """Wraps OMPL's ``SimpleSetup`` to record what the planner hands to OMPL."""

    def __init__(self, inner: Any, log: dict[str, Any]) -> None:
        self._inner, self._log = inner, log

    def __getattr__(self, name: str) -> Any:
        return getattr(self._inner, name)

    def setPlanner(self, planner: Any) -> None:  # noqa: N802 (OMPL's name)
        self._log["planner"] = planner
        self._inner.setPlanner(planner)

    def setOptimizationObjective(self, objective: Any) -> None:  # noqa: N802
        self._log["objective"] = objective
        self._inner.setOptimizationObjective(objective)

    def solve(self, seconds: float) -> Any:
        self._log["solve_s"] = seconds
        return self._inner.solve(seconds)


def _spy_ompl(monkeypatch: pytest.MonkeyPatch) -> dict[str, Any]:
    import rrtdrive.bench.ompl_planners as op

    ob, og, ou = op._ompl()
    log: dict[str, Any] = {}

    class _Geometric:
        def __getattr__(self, name: str) -> Any:
            return getattr(og, name)

        @staticmethod
        def SimpleSetup(space: Any) -> _Spy:  # noqa: N802 (OMPL's name)
            return _Spy(og.SimpleSetup(space), log)

    monkeypatch.setattr(op, "_ompl", lambda: (ob, _Geometric(), ou))
    return log


# ----------------------------------------------------------------------------- OMPL spaces


@needs_ompl
@pytest.mark.parametrize("kind", ["rs", "dubins"])
def test_the_curved_spaces_turn_on_the_cars_radius_and_only_rs_reverses(kind: str) -> None:
    """A half turn costs pi r (r = 1 / kappa_max) in both spaces; 5 m straight back costs
    5 m in Reeds–Shepp and a loop (> 2 pi r) in Dubins.

    Catches: the Dubins space built as Reeds–Shepp (the forward-only comparator
    reverses) or the other way round, either space on half the radius or on the
    wheelbase."""
    from rrtdrive.bench.ompl_planners import simple_setup

    m = builtin_map("parking_lot")
    _, si = simple_setup(_problem(m), kind)
    space = si.getStateSpace()
    r = 1.0 / m.vehicle.kappa_max
    a = _state(space, 40.0, 40.0, 0.0)
    half_turn = _state(space, 40.0, 40.0 + 2 * r, wrap_angle(math.pi))
    assert space.distance(a, half_turn) == pytest.approx(math.pi * r, rel=1e-6)
    back = space.distance(a, _state(space, 35.0, 40.0, 0.0))
    if kind == "rs":
        assert back == pytest.approx(5.0, rel=1e-6)
    else:
        assert back > 2 * math.pi * r


@needs_ompl
@pytest.mark.parametrize("kind", ["r2", "rs", "dubins"])
def test_the_state_bounds_are_the_maps(kind: str) -> None:
    """States just inside each edge of a map with four different bounds satisfy OMPL's
    bounds; just outside, not.

    Catches: x and y bounds mixed up (low or high), bounds never set."""
    from rrtdrive.bench.ompl_planners import simple_setup

    m = _wall_map()
    _, si = simple_setup(_problem(m), kind)
    space = si.getStateSpace()
    xmin, ymin, xmax, ymax = m.bounds
    for x, y, inside in (
        (xmin + 0.01, 15.0, True), (xmin - 0.01, 15.0, False),
        (xmax - 0.01, 15.0, True), (xmax + 0.01, 15.0, False),
        (40.0, ymin + 0.01, True), (40.0, ymin - 0.01, False),
        (40.0, ymax - 0.01, True), (40.0, ymax + 0.01, False),
    ):  # fmt: skip
        s = space.allocState()
        if kind == "r2":
            s[0], s[1] = x, y
        else:
            s.setX(x)
            s.setY(y)
            s.setYaw(0.3)
        assert si.satisfiesBounds(s) is inside, (x, y)


@needs_ompl
@pytest.mark.parametrize("kind", ["rs", "dubins"])
def test_a_valid_curved_state_is_a_free_body(kind: str) -> None:
    """On 600 random poses of the parking lot, every state OMPL's checker accepts has a
    body shapely finds free, and at least 85 % of the free bodies are accepted.

    Catches: the checker called with yaw 0, with x and y swapped, or accepting all."""
    from rrtdrive.bench.ompl_planners import simple_setup

    m = builtin_map("parking_lot")
    _, si = simple_setup(_problem(m), kind)
    space = si.getStateSpace()
    rng = np.random.default_rng(7)
    poses = np.column_stack([rng.uniform(0, 100, 600), rng.uniform(0, 100, 600),
                             rng.uniform(-math.pi, math.pi, 600)])  # fmt: skip
    valid = np.array([si.isValid(_state(space, *p)) for p in poses])
    free = np.array([_body_free(m, tuple(p)) for p in poses])
    assert not np.any(valid & ~free)
    assert valid[free].mean() >= 0.85 and free.sum() > 100


@needs_ompl
def test_a_valid_r2_point_keeps_the_capsule_radius() -> None:
    """In R², an accepted point is at least W/2 + margin from every obstacle (shapely),
    and points 0.5 m beyond that are accepted.

    Catches: the point test against 0 or half the radius, x and y swapped."""
    from rrtdrive.bench.ompl_planners import simple_setup

    m = builtin_map("parking_lot")
    problem = _problem(m)
    _, si = simple_setup(problem, "r2")
    space = si.getStateSpace()
    radius = m.vehicle.width / 2 + problem.checker.config.margin
    union = shapely.union_all([o.polygon() for o in m.obstacles])
    walls = shapely.box(*m.bounds).exterior
    rng = np.random.default_rng(3)
    far = 0
    for x, y in rng.uniform(0, 100, (600, 2)):
        s = space.allocState()
        s[0], s[1] = x, y
        gap = min(union.distance(shapely.Point(x, y)), walls.distance(shapely.Point(x, y)))
        if si.isValid(s):
            assert union.distance(shapely.Point(x, y)) >= radius - 1e-9
        if gap >= radius + 0.5:
            far += 1
            assert si.isValid(s), (x, y)
    assert far > 100


@needs_ompl
@pytest.mark.parametrize("kind", ["r2", "rs", "dubins"])
def test_motions_are_checked_every_quarter_metre(kind: str) -> None:
    """A free 10 m straight motion is checked at 40 states (every 0.25 m, the end
    included); a straight motion through a 0.2 m wall is rejected.

    Catches: the motion resolution set in metres instead of a fraction of the space's
    extent, or ten times coarser."""
    from rrtdrive.bench.ompl_planners import simple_setup

    m = _wall_map()
    ss, si = simple_setup(_problem(m), kind)
    space = si.getStateSpace()

    def at(x: float) -> Any:
        if kind == "r2":
            s = space.allocState()
            s[0], s[1] = x, 15.0
            return s
        return _state(space, x, 15.0, 0.0)

    ss.setup()
    assert not si.checkMotion(at(8.0), at(50.0))
    assert si.checkMotion(at(8.0), at(18.0))
    calls: list[int] = []
    ss2, si2 = simple_setup(_problem(m), kind)
    ss2.setStateValidityChecker(lambda s: calls.append(1) is None)
    ss2.setup()
    assert si2.checkMotion(at(8.0), at(18.0))
    assert 38 <= len(calls) <= 42


@needs_ompl
@pytest.mark.parametrize("kind", ["r2", "rs", "dubins"])
def test_start_and_goal_states_are_the_querys(kind: str) -> None:
    """OMPL's start and goal states are the query's (x, y), and yaw wrapped into [-pi, pi).

    Catches: the goal set to the start, start and goal swapped, x and y swapped."""
    from rrtdrive.bench.ompl_planners import simple_setup

    m = builtin_map("parking_lot")  # start (5, 6, 0), goal (72.5, 74.505, -pi/2)
    ss, si = simple_setup(_problem(m), kind)
    space = si.getStateSpace()

    def state(pose: Pose) -> Any:
        if kind == "r2":
            s = space.allocState()
            s[0], s[1] = pose.x, pose.y
            return s
        return _state(space, pose.x, pose.y, wrap_angle(pose.yaw))

    # (getStartState's state crashes nanobind at exit: ask OMPL about our own states.)
    pdef, goal = ss.getProblemDefinition(), ss.getGoal()
    assert pdef.hasStartState(state(m.start), 0) and goal.isSatisfied(state(m.goal))
    assert not pdef.hasStartState(state(m.goal), 0) and not goal.isSatisfied(state(m.start))
    moved = Pose(m.goal.x, m.goal.y + 0.01, m.goal.yaw)
    assert not goal.isSatisfied(state(moved))
    if kind != "r2":
        turned = Pose(m.start.x, m.start.y, 0.01)
        assert not pdef.hasStartState(state(turned), 0)


@needs_ompl
def test_bad_space_algorithm_and_range_are_refused() -> None:
    """Unknown spaces and algorithms, and a range of 0, infinity or NaN raise InputError
    naming the field; every space x algorithm is registered under ompl-<space>-<alg>.

    Catches: the space, algorithm or range validation skipped, the name's parts
    swapped, a space left unregistered, simple_setup building R² for an unknown space."""
    from rrtdrive.bench.ompl_planners import OmplPlanner, simple_setup
    from rrtdrive.planning import PLANNERS, make_planner

    with pytest.raises(InputError, match="^space"):
        OmplPlanner("se2", "rrtconnect")
    with pytest.raises(InputError, match="^algorithm"):
        OmplPlanner("rs", "prm")
    for bad in (0.0, math.inf, math.nan):
        with pytest.raises(InputError, match="^range_m"):
            OmplPlanner("rs", "rrtconnect", range_m=bad)
    with pytest.raises(InputError, match="^space"):
        simple_setup(_problem(builtin_map("parking_lot")), "se2")
    for space in ("r2", "rs"):
        for alg in ("rrtconnect", "rrtstar", "bitstar", "informed-rrtstar"):
            name = f"ompl-{space}-{alg}"
            assert name in PLANNERS and make_planner(name).name == name


# ----------------------------------------------------------------------------- OMPL solving


@needs_ompl
@pytest.mark.parametrize(
    ("alg", "ompl_name", "range_m", "want_range"),
    [("rrtconnect", "RRTConnect", None, 5.0), ("informed-rrtstar", "InformedRRTstar", None, None),
     ("rrtstar", "RRTstar", 7.5, 7.5)],
)  # fmt: skip
def test_ompl_gets_the_asked_budget_algorithm_range_and_first_solution_stop(
    monkeypatch: pytest.MonkeyPatch, alg: str, ompl_name: str, range_m: float | None,
    want_range: float | None,
) -> None:
    """What OMPL reports of its planner and objective: the class asked for, the range
    (5 m by default for RRT-Connect, the user's when given), a cost threshold of
    infinity (stop at the first solution) and the solve time the budget asked.

    Catches: the budget doubled or fixed, the user's range ignored or doubled, the
    default range changed, the threshold or the objective dropped, an algorithm
    mapped to the wrong OMPL class."""
    from rrtdrive.bench.ompl_planners import OmplPlanner

    log = _spy_ompl(monkeypatch)
    planner = OmplPlanner("r2", alg, range_m=range_m)
    res = planner.solve(_problem(builtin_map("overtake")), np.random.default_rng(0),
                        Budget(max_time_s=2.5))  # fmt: skip
    assert res.success, res.message
    assert log["solve_s"] == 2.5
    assert log["planner"].getName() == ompl_name
    if want_range is not None:
        assert log["planner"].getRange() == pytest.approx(want_range)
    assert math.isinf(log["objective"].getCostThreshold().value())
    assert log["planner"].getProblemDefinition().getOptimizationObjective() is not None


@needs_ompl
def test_the_reeds_shepp_comparator_drives_its_rows() -> None:
    """RRT-Connect in Reeds–Shepp space on the parking lot: rows from the query's start
    to its goal, the gear of each row the direction of travel, curvature per gear
    segment within kappa_max, a cusp repeated exactly; two rng seeds give two paths,
    the same seed the same path.

    Catches: OMPL's seed not taken from the rng or not set, the states' x and y swapped, the
    curves returned as a polyline, gears or cusps mislabelled."""
    import rrtdrive.bench.ompl_planners  # noqa: F401  (registers the OMPL rows)
    from rrtdrive.planning import make_planner

    m = builtin_map("parking_lot")
    planner = make_planner("ompl-rs-rrtconnect")
    a = planner.solve(_problem(m), np.random.default_rng(0), Budget(max_time_s=5.0))
    b = planner.solve(_problem(m), np.random.default_rng(1), Budget(max_time_s=5.0))
    assert a.success and b.success
    assert len(a.path.cusps) >= 1
    _assert_drivable_rows(m, a.path, m.start, m.goal)
    assert not np.array_equal(a.raw_path, b.raw_path)
    again = planner.solve(_problem(m), np.random.default_rng(0), Budget(max_time_s=5.0))
    assert np.array_equal(again.path.samples, a.path.samples)
    # The raw path is OMPL's (few) solution states, each one of the rows.
    assert len(a.raw_path) < len(a.path) / 4
    for p in a.raw_path:
        assert np.hypot(*(a.path.xy - p).T).min() < 1e-6


@needs_ompl
def test_the_dubins_comparator_never_reverses() -> None:
    """The coverage script's Dubins RRT (simple_setup's ``dubins`` space, plain RRT) on a
    lot with a wall in the way: all rows forward, ends at the query's poses, curvature
    within kappa_max, and a path shapely finds collision-free.

    Catches: the Dubins space built as Reeds–Shepp or on a smaller radius."""
    sys.path.insert(0, str(FsPath(__file__).resolve().parents[1] / "experiments"))
    import coverage as cov

    m = _wall_map()
    _, _, length, path = cov.solve_ompl(_problem(m), 0, "ompl-dubins-rrt", 5.0)
    assert path is not None and length is not None
    assert path.is_forward_only
    _assert_drivable_rows(m, path, m.start, m.goal)


@needs_ompl
def test_r2_rows_simplified_and_failures_counted() -> None:
    """R² RRT-Connect: simplification shortens the raw polyline (simplify=False keeps
    OMPL's zig-zag), the rows lie on the raw polyline; an unreachable goal is
    ``no_path_in_budget`` with the tree's nodes counted.

    Catches: simplification inverted, the raw path replaced by the dense rows, x and y of
    OMPL's R² states swapped, the nodes of a search dropped, a failure given the wrong
    status, the message naming the wrong space."""
    from rrtdrive.bench.ompl_planners import OmplPlanner

    m = builtin_map("overtake")
    problem = _problem(m)
    runs = [
        OmplPlanner("r2", "rrtconnect", simplify=s).solve(
            problem, np.random.default_rng(4), Budget(max_time_s=3.0)
        )
        for s in (True, False)
    ]
    simple, raw = runs
    assert simple.success and raw.success
    assert simple.path.length < raw.path.length - 1e-6
    assert np.allclose(simple.path.xy[[0, -1]], [m.start.xy, m.goal.xy], atol=1e-9)
    assert simple.nodes > 1 and "RRTConnect in r2" in simple.message
    assert "simplify_time_s" in simple.stats and "simplify_time_s" not in raw.stats
    line = shapely.LineString(simple.raw_path)
    assert max(line.distance(shapely.Point(p)) for p in simple.path.xy) < 1e-6
    assert len(simple.raw_path) < len(simple.path) / 4
    fail = OmplPlanner("r2", "rrtconnect").solve(
        _problem(builtin_map("no_path")), np.random.default_rng(0), Budget(max_time_s=0.3)
    )
    assert fail.status.value == "no_path_in_budget" and fail.nodes > 1


@needs_ompl
def test_a_blocked_start_or_goal_is_named() -> None:
    """A start or goal pose inside an obstacle is ``invalid_start`` / ``invalid_goal``,
    found before the search (the docstring's promise), with no OMPL tree; one 5 cm from
    the wall (free by shapely, not by the covering discs OMPL checks) gets the same
    statuses before the search too, saying why (OMPL searched such a goal to the end of
    its budget).

    Catches: the statuses swapped, either end check skipped (left to OMPL), OMPL's
    "Invalid start" mapped to invalid_goal."""
    import rrtdrive.bench.ompl_planners  # noqa: F401  (registers the OMPL rows)
    from rrtdrive.planning import PlanningProblem, make_planner

    m = _wall_map()
    base = _problem(m)
    inside = Pose(30.0, 15.0, 0.0)
    close = Pose(29.9 - 0.05 - m.vehicle.front_extent, 15.0, 0.0)
    assert _body_free(m, close.as_tuple())
    for start, goal, want in ((inside, m.goal, "invalid_start"), (m.start, inside, "invalid_goal"),
                              (close, m.goal, "invalid_start"), (m.start, close, "invalid_goal")):
        q = PlanningProblem(m, base.checker, start, goal, m.vehicle)
        res = make_planner("ompl-rs-rrtconnect").solve(
            q, np.random.default_rng(0), Budget(max_time_s=0.2)
        )
        assert res.status.value == want
        # Ended before the search, by our own tests (not by OMPL's start check).
        assert res.message.startswith(want.split("_")[1]) and res.nodes == 0
        if inside not in (start, goal):
            assert "covering discs" in res.message


@needs_ompl
@pytest.mark.parametrize(
    ("goal", "cusps"), [((35.0, 40.0, 0.0), 0), ((40.0, 42.0, 0.0), 2), ((46.0, 34.0, 2.0), None)]
)
def test_reeds_shepp_rows_of_one_curve(goal: tuple[float, float, float], cusps: int | None) -> None:
    """The rows of one OMPL Reeds–Shepp curve: at most 0.1 m apart (the docstring's
    sampling), ends at the curve's poses, length equal to OMPL's distance (1 mm: a
    cusp not found exactly cuts its corner), straight back in reverse, a sideways
    shift with its two cusps.

    Catches: coarser sampling, cusps not inserted or found only to a centimetre, the
    bisection turned round, pieces joined wrongly."""
    from ompl import geometric as og

    from rrtdrive.bench.ompl_planners import reeds_shepp_path, simple_setup

    ss, si = simple_setup(_problem(builtin_map("parking_lot")), "rs")
    space = si.getStateSpace()
    a, b = _state(space, 40.0, 40.0, 0.0), _state(space, *goal)
    mid = space.allocState()
    space.interpolate(a, b, 0.5, mid)
    curve = og.PathGeometric(si)
    for s in (a, mid, b):
        curve.append(s)
    path = reeds_shepp_path(space, curve, np.array([[40.0, 40.0], goal[:2]]))
    s = path.samples
    assert np.hypot(*np.diff(s[:, :2], axis=0).T).max() <= 0.1 + 1e-9
    assert np.allclose(s[0, :3], [40.0, 40.0, 0.0]) and np.allclose(s[-1, :3], goal)
    # Chords 0.1 m long on 6 m arcs lose about 1e-6 m each: a cusp cut loses up to 0.1 m.
    assert path.length == pytest.approx(space.distance(a, b), abs=5e-4)
    if cusps is not None:
        assert len(path.cusps) == cusps
    if goal == (35.0, 40.0, 0.0):
        assert np.all(path.gears == -1)
    start = Pose(40.0, 40.0, 0.0)
    free = Map("free", (0.0, 0.0, 100.0, 100.0), (), start, Pose(*goal))
    _assert_drivable_rows(free, path, start, Pose(*goal))


@needs_ompl
def test_reeds_shepp_rows_keep_short_pieces_and_the_waypoints() -> None:
    """A solution whose last piece is 0.2 m long ends its rows at its last state; a
    one-state solution has no rows but keeps the waypoints it was given.

    Catches: short pieces skipped (the rows stop short of the goal), the waypoints of
    an empty path dropped."""
    from ompl import geometric as og

    from rrtdrive.bench.ompl_planners import reeds_shepp_path, simple_setup

    _, si = simple_setup(_problem(builtin_map("parking_lot")), "rs")
    space = si.getStateSpace()
    curve = og.PathGeometric(si)
    for x in (40.0, 45.0, 45.2):
        curve.append(_state(space, x, 40.0, 0.0))
    rows = reeds_shepp_path(space, curve, NO_WAYPOINTS).samples
    assert np.allclose(rows[-1, :3], [45.2, 40.0, 0.0]) and np.all(rows[:, 4] == 1)
    one = og.PathGeometric(si)
    one.append(_state(space, 40.0, 40.0, 0.0))
    kept = reeds_shepp_path(space, one, np.array([[40.0, 40.0]]))
    assert len(kept) == 0 and kept.waypoints.tolist() == [[40.0, 40.0]]


# ----------------------------------------------------------------------------- gear_rows


def _arc(x0: float, y0: float, yaw0: float, kappa: float, length: float, n: int) -> np.ndarray:
    """``(n + 1, 3)`` nose-yaw states along a circle arc (closed form), forward."""
    s = np.linspace(0.0, length, n + 1)
    yaw = yaw0 + kappa * s
    if abs(kappa) < 1e-12:
        x, y = x0 + s * np.cos(yaw0), y0 + s * np.sin(yaw0)
    else:
        x = x0 + (np.sin(yaw) - np.sin(yaw0)) / kappa
        y = y0 - (np.cos(yaw) - np.cos(yaw0)) / kappa
    return np.column_stack([x, y, wrap_angle(yaw)])


@settings(max_examples=40, deadline=None)
@given(
    yaw0=st.floats(-math.pi, math.pi),
    k1=st.floats(-0.3, 0.3),
    k2=st.floats(-0.3, 0.3),
    n=st.integers(3, 30),
)
def test_gear_rows_of_forward_back_forward_arcs(yaw0: float, k1: float, k2: float, n: int) -> None:
    """Forward along an arc of curvature k1, back in reverse steering k2 (so the yaw turns
    by -k2 per metre), forward again: gears +1/-1/+1 per row, each cusp row repeated,
    N + 2 rows, kappa k1 / k2 / k1 on every row of its segment (first and last
    included), yaw crossing +-pi at any start heading.

    Catches: gears inverted or one gear for all segments, the gear column all +1,
    cusps off by one or not repeated, curvature without the gear's sign or without
    the yaw's wrap, a segment's last row given kappa 0, kappa taken from the
    incoming step, mid-step yaw without wrap, repeats dropped too eagerly."""
    from rrtdrive.bench.ompl_planners import gear_rows

    ds = 0.1
    fwd = _arc(0.0, 0.0, yaw0, k1, n * ds, n)
    x, y, yaw = fwd[-1]
    # Reversing with steering curvature k2 the car moves against its heading and its yaw
    # turns by -k2 per metre: a forward arc of curvature -k2 from the heading yaw + pi.
    back_fwd = _arc(x, y, yaw + math.pi, -k2, n * ds, n)
    back = np.column_stack([back_fwd[:, :2], wrap_angle(back_fwd[:, 2] - math.pi)])
    x, y, yaw = back[-1]
    again = _arc(x, y, yaw, k1, n * ds, n)
    states = np.vstack([fwd, back[1:], again[1:]])
    rows = gear_rows(states)
    assert len(rows) == len(states) + 2
    gears = np.r_[np.ones(n + 1), -np.ones(n + 1), np.ones(n + 1)]
    assert np.array_equal(rows[:, 4], gears)
    p = Path(rows, NO_WAYPOINTS)
    assert p.cusps.tolist() == [n + 1, 2 * n + 2]
    for c in p.cusps:
        assert np.array_equal(rows[c - 1, :3], rows[c, :3])
    want = np.r_[np.full(n + 1, k1), np.full(n + 1, k2), np.full(n + 1, k1)]
    # kappa from chords 0.1 m long: within (0.3 * 0.1)^2 / 24 of the arc's, relatively.
    assert np.allclose(rows[:, 3], want, atol=1e-4)
    # A repeated position changes nothing; a single state is one forward row.
    assert np.allclose(gear_rows(np.vstack([states[:5], states[4:]])), gear_rows(states))
    one = gear_rows(states[:1])
    assert one.shape == (1, 5) and one[0, 4] == 1.0 and one[0, 3] == 0.0


def test_gear_rows_keeps_close_distinct_samples() -> None:
    """Samples 0.02 m apart are all kept (only repeats are dropped), kappa exact; on a
    straight then an arc each row takes its outgoing step's kappa (the docstring's rule):
    the junction row already the arc's, the last row its incoming one.

    Catches: repeats dropped with a coarse tolerance, kappa from the incoming step."""
    from rrtdrive.bench.ompl_planners import gear_rows

    states = _arc(1.0, 2.0, 0.4, 0.15, 1.0, 50)
    rows = gear_rows(states)
    assert len(rows) == 51 and np.allclose(rows[:, 3], 0.15, atol=1e-6)
    line = _arc(0.0, 0.0, 0.4, 0.0, 0.5, 5)
    arc = _arc(*line[-1], 0.15, 0.5, 5)
    rows = gear_rows(np.vstack([line, arc[1:]]))
    assert np.allclose(rows[:5, 3], 0.0, atol=1e-9)
    assert np.allclose(rows[5:, 3], 0.15, atol=1e-5)


# ----------------------------------------------------------------------------- CommonRoad

DT = 0.05


def _ks_log(
    rate: Callable[[float], float], v: float, n: int, pose: tuple[float, float, float] = (0, 0, 0),
    wheelbase: float = CAR.wheelbase, dt: float = DT,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The kinematic single-track model at constant speed ``v`` (scipy, tight tolerance):
    the steering angle integrates ``rate(t)`` from 0; returns ``t, states, steer, accel``
    with the steering logged at the end of each step (what the car applied by then)."""

    def f(_t: float, z: np.ndarray) -> list[float]:
        x, y, yaw, delta = z
        return [v * math.cos(yaw), v * math.sin(yaw), v * math.tan(delta) / wheelbase, rate(_t)]

    t = np.arange(n + 1) * dt
    sol = solve_ivp(f, (0.0, t[-1]), [*pose, 0.0], t_eval=t, rtol=1e-10, atol=1e-10,
                    max_step=dt / 4)  # fmt: skip
    z = sol.y.T
    states = np.column_stack([z[:, 0], z[:, 1], wrap_angle(z[:, 2]), np.full(n + 1, v)])
    return t, states, z[1:, 3], np.zeros(n)


def _straight(
    v: float, n: int, x0: float = 3.0, y0: float = -2.0, yaw: float = 0.0, t0: float = 0.0,
    dt: float = DT, accel: float = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """A straight drive in closed form: speed ``v + a t``, distance ``v t + a t^2 / 2``."""
    t = t0 + np.arange(n + 1) * dt
    s = v * (t - t0) + 0.5 * accel * (t - t0) ** 2
    states = np.column_stack([x0 + s * math.cos(yaw), y0 + s * math.sin(yaw),
                              np.full(n + 1, yaw), v + accel * (t - t0)])  # fmt: skip
    return t, states


@needs_cr
@pytest.mark.parametrize(("yaw", "accel"), [(0.0, 0.0), (2.5, 0.0), (-1.2, 1.5), (math.pi, -0.4)])
def test_a_straight_line_at_any_heading_is_feasible(yaw: float, accel: float) -> None:
    """A straight line from 3 m/s along any heading, at constant speed or constant
    acceleration, from t = 7 s, dt 0.1: feasible, no drift, steering rate 0.

    Catches: the initial orientation or position (rear axle for centre, x and y swapped)
    dropped, the body centre behind the axle or sideways, dt read from the first time
    instead of the spacing, the speed, the acceleration or the inputs' time step
    wrong, dt doubled."""
    from rrtdrive.commonroad_judge import judge_trajectory

    t, states = _straight(3.0, 60, yaw=yaw, t0=7.0, dt=0.1, accel=accel)
    v = judge_trajectory(t, states, np.zeros(60), np.full(60, accel))
    assert v.feasible and v.inputs_feasible and v.why == ""
    assert v.max_position_drift_m < 1e-6 and v.max_heading_drift_rad < 1e-9
    assert v.max_steer_rate == 0.0 and v.first_infeasible_step is None


@needs_cr
@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_steering_rates_either_side_of_the_limit(sign: float) -> None:
    """Steering ramped at 0.3 rad/s (left or right) on a KS car: feasible with the default
    0.4 rad/s limit; at 0.5 rad/s: rejected at its first step, and accepted when the
    limit is 0.6; the verdict reports |rate| and the limit applied.

    Catches: the default limit raised, the negative rate bound left at CommonRoad's
    or dropped, the rate's sign or its dt wrong, |rate| not reported, the first
    infeasible step off by one, the limit reported as the default."""
    from rrtdrive.commonroad_judge import COMMONROAD_STEER_RATE, judge_trajectory

    assert COMMONROAD_STEER_RATE == 0.4  # SPEC: all three CommonRoad vehicles
    slow = _ks_log(lambda _t: sign * 0.3, 5.0, 30)
    v = judge_trajectory(*slow)
    assert v.feasible, v.why
    assert v.max_steer_rate == pytest.approx(0.3, rel=1e-3) and v.steer_rate_limit == 0.4
    fast = _ks_log(lambda _t: sign * 0.5, 5.0, 20)  # up to 0.5 rad < max_steer
    v = judge_trajectory(*fast)
    assert not v.feasible and not v.inputs_feasible and v.first_infeasible_step == 0
    assert "rejects an input" in v.why
    assert v.max_steer_rate == pytest.approx(0.5, rel=1e-3)
    v = judge_trajectory(*fast, steer_rate_limit=0.6)
    assert v.feasible and v.steer_rate_limit == 0.6
    jump = _ks_log(lambda _t: sign * 0.3, 5.0, 30)
    steer = jump[2].copy()
    steer[0] = sign * 0.1  # 2 rad/s from straight wheels at the first step
    assert judge_trajectory(jump[0], jump[1], steer, jump[3]).first_infeasible_step == 0


@needs_cr
def test_a_circle_across_pi_on_another_car_is_feasible() -> None:
    """A KS car with a 3.2 m wheelbase steering up to 0.3 rad at 0.3 rad/s and on round
    a circle at 8 m/s, its logged yaw wrapping through +-pi: feasible, drift < 1 cm.

    Catches: the car ignored for the default, the wheelbase (a + b) or the body
    centre offset built from the length, only a set, the heading compared without
    wrapping or without abs, the parameters never assigned."""
    from rrtdrive.commonroad_judge import judge_trajectory

    car = VehicleParams(wheelbase=3.2, length=4.8, min_turning_radius=8.0)
    log = _ks_log(lambda t: 0.3 if t < 1.0 else 0.0, 8.0, 120, pose=(1.0, 2.0, 2.8),
                  wheelbase=3.2)  # fmt: skip
    yaw = log[1][:, 2]
    assert np.any(np.abs(np.diff(yaw)) > math.pi)  # wraps
    v = judge_trajectory(*log, vehicle=car)
    assert v.feasible, v.why
    assert v.max_position_drift_m < 0.01 and v.max_heading_drift_rad < 0.01
    # The same log judged as the default car's (2.51 m) turns faster than logged.
    assert not judge_trajectory(*log).feasible


@needs_cr
def test_drift_tolerances_are_the_documented_ones() -> None:
    """A 10 m straight at 2 m/s whose log shifts sideways over 8 of its last steps: 1 cm is
    within the 2 cm + 1 mm/m tolerance, 5 cm is not (and is reported as 0.05 m); a
    heading off by 0.005 rad passes the 0.01 rad + 0.1 mrad/m tolerance, 0.015 and
    0.03 rad do not; 95 m down a 100 m straight 3 cm and 0.015 rad pass, 20 cm and
    0.03 rad do not.

    Catches: either tolerance (or its per-metre part) loosened, the drift compared with
    any() instead of all(), the largest drift reported from the last step, the
    heading drift averaged, the drift or heading verdict ignored, the heading held to
    the position's tolerance, a first infeasible step reported where CommonRoad
    rejected no input."""
    from rrtdrive.commonroad_judge import judge_trajectory

    n = 100
    t, straight = _straight(2.0, n, x0=0.0, y0=0.0, dt=DT)
    zeros = np.zeros(n)
    for shift, ok in ((0.01, True), (0.05, False)):
        s = straight.copy()
        s[n - 10 : n - 2, 1] += shift
        v = judge_trajectory(t, s, zeros, zeros)
        assert v.feasible is ok and v.inputs_feasible and v.first_infeasible_step is None
        assert v.max_position_drift_m == pytest.approx(shift, abs=1e-6)
        assert ("drifts" in v.why) is not ok
    for turn, ok in ((0.005, True), (0.015, False), (0.03, False)):
        s = straight.copy()
        s[n - 10 : n - 2, 2] -= turn
        v = judge_trajectory(t, s, zeros, zeros)
        assert v.feasible is ok
        assert v.max_heading_drift_rad == pytest.approx(turn, abs=1e-4)
    # 95 m down a 100 m straight the tolerances are 2 cm + 9.5 cm and 0.01 + 0.0095 rad.
    n = 200
    t, straight = _straight(10.0, n, x0=0.0, y0=0.0, dt=DT)
    zeros = np.zeros(n)
    for shift, turn, ok in ((0.03, 0.0, True), (0.2, 0.0, False), (0.0, 0.015, True),
                            (0.0, 0.03, False)):  # fmt: skip
        s = straight.copy()
        s[n - 10 : n - 2, 1] += shift
        s[n - 10 : n - 2, 2] += turn
        assert judge_trajectory(t, s, zeros, zeros).feasible is ok, (shift, turn)
    # A log with a NaN position is bad input (test_a_trajectory_with_a_nan_is_refused).


@needs_cr
def test_angle_and_speed_limits_both_ways() -> None:
    """A steering angle 1 % past max_steer to the right is infeasible, exactly at it is
    not flagged; a speed over the BMW 320i set's v_max or under its v_min (vehiclemodels)
    is infeasible.

    Catches: |angle| checked one-sidedly or with 10 % slack, the limit reached counted
    as over, either speed bound dropped, the speed read from the yaw column."""
    from vehiclemodels.parameters_vehicle2 import parameters_vehicle2

    from rrtdrive.commonroad_judge import judge_trajectory

    n = 40
    t, straight = _straight(2.0, n, yaw=0.0)
    bent = np.zeros(n)
    bent[-1] = -CAR.max_steer * 1.01
    v = judge_trajectory(t, straight, bent, np.zeros(n), steer_rate_limit=100.0)
    assert "steering angle over" in v.why
    bent[-1] = -CAR.max_steer
    v = judge_trajectory(t, straight, bent, np.zeros(n), steer_rate_limit=100.0)
    assert "steering angle over" not in v.why
    v_max = parameters_vehicle2().longitudinal.v_max
    t, fast = _straight(v_max + 1.0, n, yaw=1.0)
    v = judge_trajectory(t, fast, np.zeros(n), np.zeros(n))
    assert not v.feasible and "a speed outside" in v.why
    t, back = _straight(parameters_vehicle2().longitudinal.v_min - 1.0, n, yaw=0.5)
    assert "a speed outside" in judge_trajectory(t, back, np.zeros(n), np.zeros(n)).why
    t, spun = _straight(2.0, n, yaw=-2.0)  # a yaw below v_min must not read as a speed
    assert judge_trajectory(t, spun, np.zeros(n), np.zeros(n)).feasible


@needs_cr
def test_bad_shapes_and_the_json_row() -> None:
    """Mismatched lengths raise InputError; no steps is feasible; the JSON row carries each
    field under its own name; every failed check is named in ``why``.

    Catches: a length check dropped, the empty trajectory called infeasible, JSON
    fields swapped or emptied, only the first reason kept."""
    from rrtdrive.commonroad_judge import judge_trajectory

    t, s = _straight(2.0, 10)
    z = np.zeros(10)
    for args in ((t[:-1], s[:-1], z, z), (t, s, z, z[:-1]), (t[:-1], s, z, z)):
        with pytest.raises(InputError, match="^trajectory"):
            judge_trajectory(*args)
    assert judge_trajectory(t[:1], s[:1], z[:0], z[:0]).feasible
    bad = s.copy()
    bad[5:, 1] += 1.0
    steer = z.copy()
    steer[-1] = 1.0
    v = judge_trajectory(t, bad, steer, z, steer_rate_limit=0.3)
    row = v.to_json()
    assert row["commonroad_steer_rate_limit"] == 0.3
    assert row["commonroad_max_steer_rate"] == pytest.approx(v.max_steer_rate, abs=1e-6)
    assert row["commonroad_max_position_drift_m"] == pytest.approx(v.max_position_drift_m, abs=1e-6)
    assert row["commonroad_inputs_feasible"] is v.inputs_feasible
    assert row["commonroad_why"] == v.why and row["commonroad_feasible"] is False
    assert "drifts" in v.why and "steering angle over" in v.why and v.why.count(";") >= 1
    off = judge_trajectory(t, bad, z, z).to_json()  # inputs fine, trajectory not
    assert off["commonroad_inputs_feasible"] is True and off["commonroad_feasible"] is False


def test_commonroad_available_says_whether_the_checker_imports() -> None:
    """``commonroad_available`` agrees with an import of CommonRoad's feasibility checker
    (here, and in CI without the extra).

    Catches: the function answering True when the import fails."""
    from rrtdrive.commonroad_judge import commonroad_available

    assert commonroad_available() is HAVE_CR


@needs_cr
@pytest.mark.parametrize("bad", [-0.4, 0.0, math.nan, math.inf])
def test_a_bad_steer_rate_limit_is_refused(bad: float) -> None:
    """A steering-rate limit that is no positive number is bad input, named by field.

    A negative or NaN limit called every trajectory, even a straight line, infeasible
    ('CommonRoad rejects an input') instead of an error, as EvalConfig gives.
    """
    from rrtdrive.commonroad_judge import judge_trajectory

    t, states = _straight(2.0, 20)
    with pytest.raises(InputError, match="steer_rate_limit"):
        judge_trajectory(t, states, np.zeros(20), np.zeros(20), steer_rate_limit=bad)


@needs_cr
@pytest.mark.parametrize("where", ["t", "states", "steer", "accel"])
def test_a_trajectory_with_a_nan_is_refused(where: str) -> None:
    """A NaN in the log read as 'its heading drifts 0 rad from the log', not bad input."""
    from rrtdrive.commonroad_judge import judge_trajectory

    t, states = _straight(2.0, 20)
    parts = {"t": t, "states": states, "steer": np.zeros(20), "accel": np.zeros(20)}
    parts[where] = parts[where].copy()
    parts[where].flat[3] = math.nan
    with pytest.raises(InputError, match="trajectory: .*finite"):
        judge_trajectory(parts["t"], parts["states"], parts["steer"], parts["accel"])


@needs_cr
def test_times_not_equally_spaced_are_refused_and_equal_ones_pass() -> None:
    """The judge steps at the mean dt: a log with uneven steps was judged on the wrong clock."""
    from rrtdrive.commonroad_judge import judge_trajectory

    t, states = _straight(2.0, 20)
    assert judge_trajectory(t, states, np.zeros(20), np.zeros(20)).feasible
    uneven = t.copy()
    uneven[10:] += 0.5 * DT  # one step half as long again: the mean hides it
    with pytest.raises(InputError, match="equally spaced"):
        judge_trajectory(uneven, states, np.zeros(20), np.zeros(20))


def test_an_ompl_name_before_the_bench_is_loaded_says_how_to_register_it() -> None:
    """make_planner('ompl-rs-rrtconnect') in a fresh process said only 'unknown planner'."""
    code = (
        "from rrtdrive.planning import make_planner\n"
        "try:\n"
        "    make_planner('ompl-rs-rrtconnect')\n"
        "except Exception as exc:\n"
        "    print(type(exc).__name__, exc)\n"
        "import rrtdrive.bench\n"
        "print(type(make_planner('ompl-rs-rrtconnect')).__name__)\n"
    )
    import subprocess
    import sys

    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    first, second = done.stdout.strip().splitlines()
    assert first.startswith("InputError planner: unknown planner 'ompl-rs-rrtconnect'")
    assert "'import rrtdrive.bench'" in first and "rrtdrive[ompl]" in first
    assert second == "OmplPlanner"


@needs_ompl
def test_an_r2_start_free_but_inside_the_edge_capsule_is_refused_before_the_search() -> None:
    """A start whose body is clear of the wall (shapely) but whose rear axle is nearer than
    the R² edge capsule's radius is no valid OMPL state: invalid_start at once, saying so."""
    import rrtdrive.bench.ompl_planners  # noqa: F401  (registers the OMPL rows)
    from rrtdrive.planning import PlanningProblem, make_planner

    m = _wall_map()
    base = _problem(m)
    gap = 0.5 * (m.vehicle.width / 2.0 + base.checker.edge_radius)  # between the two
    start = Pose(29.9 - gap, 15.0, math.pi / 2.0)
    assert _body_free(m, start.as_tuple())
    assert base.checker.clearance(start.x, start.y) < base.checker.edge_radius
    q = PlanningProblem(m, base.checker, start, m.goal, m.vehicle)
    res = make_planner("ompl-r2-rrtconnect").solve(q, np.random.default_rng(0), Budget())
    assert res.status.value == "invalid_start" and res.nodes == 0
    assert "edge capsule" in res.message
