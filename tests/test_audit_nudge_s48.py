"""Audit of the nudged ends (session 48, ``rrtdrive.planning.hybrid.nudge``).

Dead-end slots 1.86-2.2 m wide, the goal nose-in and turned off the slot's axis by a
fraction of a degree, the start 10 m above heading down the slot. Each slot used here
has a forward witness built by hand (straight down a line in the slot, a clothoid
twist onto the goal's heading, an S of four clothoids from the start onto that line)
that passes ``verify_path`` with ``max_sharpness=0.2`` and keeps at least what the
planner promises, ``min(0.05 m, 0.999 x the ends' own body clearance)``.

What holds: the nudge solves slots that were false proofs before it, also rotated
30 deg; starts nose-out in such a slot and reverse-in bays solve; the built-in maps'
answers do not change with ``nudge_ends`` off. What does not: some slots are still
"proven" unreachable. In every one the goal's side ran out of states after 1-7
expansions, and a gentle arc out of the goal exists that opens a 6 m straight drive,
but its heading change lies between ``NUDGES_DEG``'s 0.25 and 0.5 deg (or below 0.25).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import fsolve

from rrtdrive.maps import Map, Obstacle, builtin_map
from rrtdrive.planning import PlanningProblem, make_planner
from rrtdrive.planning.hybrid.nudge import PROBE_M, _straight_run, nudge
from rrtdrive.planning.hybrid.primitives import arc_poses
from rrtdrive.planning.hybrid.resolution import body_test
from rrtdrive.types import Budget, Path, PlanStatus, Pose
from rrtdrive.verify import verify_path

FRONT, REAR = 3.405, 0.895  # the default car's rear axle to its bumpers, metres

#: Slots of a helper's random sample (width B, goal's offset gx, turn dyaw, depth gy).
SLOTS = {
    47: (2.0679253806880027, -0.09080493651696045, 0.010117003931709698, 10.098607072313005),
    79: (1.8863197297342436, 0.02259372552189481, -0.0068978874723986325, 8.57430743222165),
    123: (2.1386615689772537, -0.14882469150229466, 0.006344801080092697, 8.681246469439909),
    50: (2.02421484951626, 0.08243461066251774, -0.002687752116666234, 8.779351498252934),
    139: (1.8951852056107796, -0.02318896334893889, 0.0003310234244159639, 7.943269664145423),
    3: (2.0489026797530463, 0.07931014748105349, -0.0054851614912775635, 7.926589702608525),
}
#: The slots still answered proven_unreachable although their witness holds.
FALSE_PROOFS = (79, 123, 50, 139, 3)


def _integrate(kf, total: float, x0: float, y0: float, yaw0: float):
    s = np.linspace(0.0, total, max(2, math.ceil(total / 0.01)) + 1)
    k = np.array([kf(v) for v in s])
    ds = np.diff(s)
    yaw = yaw0 + np.concatenate([[0.0], np.cumsum(0.5 * (k[1:] + k[:-1]) * ds)])
    c, si = np.cos(yaw), np.sin(yaw)
    x = x0 + np.concatenate([[0.0], np.cumsum(0.5 * (c[1:] + c[:-1]) * ds)])
    y = y0 + np.concatenate([[0.0], np.cumsum(0.5 * (si[1:] + si[:-1]) * ds)])
    return x, y, yaw, k


def _rows(x, y, yaw, k, step: float = 0.05) -> np.ndarray:
    s = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(x), np.diff(y)))])
    idx = [0]
    for i in range(1, len(s)):
        if s[i] - s[idx[-1]] >= step - 1e-12:
            idx.append(i)
    if idx[-1] != len(s) - 1:
        idx.append(len(s) - 1)
    return np.column_stack([x[idx], y[idx], yaw[idx], k[idx], np.ones(len(idx))])


def _line(x0: float, y0: float, yaw: float, length: float) -> np.ndarray:
    s = np.linspace(0.0, length, max(1, math.ceil(abs(length) / 0.05)) + 1)
    n = len(s)
    return np.column_stack([x0 + s * math.cos(yaw), y0 + s * math.sin(yaw),
                            np.full(n, yaw), np.zeros(n), np.ones(n)])  # fmt: skip


def _hump(k1: float, k2: float, part: float = 1.0):
    def kf(v: float) -> float:
        seg, t = divmod(v, part)
        kk = k1 if seg < 2 else k2
        return kk * (t / part if seg % 2 == 0 else 1 - t / part)

    return kf


def _slot_map(key: int, bounds=(0.0, 0.0, 30.0, 20.0)) -> Map:
    width, gx, dyaw, gy = SLOTS[key]
    depth, xl, xr = 7.5, 15.0 - width / 2, 15.0 + width / 2
    top = 4.25 + depth
    obs = (Obstacle((xl - 0.3, (4.25 + top) / 2), (0.6, depth), 0.0),
           Obstacle((xr + 0.3, (4.25 + top) / 2), (0.6, depth), 0.0),
           Obstacle((15.0, 3.95), (width + 1.2, 0.6), 0.0))  # fmt: skip
    return Map("slot", bounds, obs, Pose(15.0, 19.0, -math.pi / 2),
               Pose(15.0 + gx, gy, -math.pi / 2 + dyaw))  # fmt: skip


def _nose_in_witness(start: Pose, goal: Pose) -> np.ndarray:
    """Forward: an S onto the goal's line, straight down it, a clothoid twist onto the goal."""
    dth = goal.yaw + math.pi / 2
    x, y, yaw, k = _integrate(lambda v: 2 * dth * v, 1.0, 0.0, 0.0, -math.pi / 2)
    x, y = x + goal.x - x[-1], y + goal.y - y[-1]
    tail = _rows(x, y, yaw, k)
    x_line = float(tail[0, 0])

    def miss(p):
        hx, _, hyaw, _ = _integrate(_hump(*p), 4.0, start.x, start.y, start.yaw)
        return [hx[-1] - x_line, hyaw[-1] + math.pi / 2]

    k1, k2 = fsolve(miss, [0.001, -0.001], xtol=1e-14)
    head = _rows(*_integrate(_hump(k1, k2), 4.0, start.x, start.y, start.yaw))
    straight = _line(x_line, head[-1, 1], -math.pi / 2, head[-1, 1] - tail[0, 1])
    rows = np.vstack([head, straight[1:], tail[1:]])
    rows[0, :3], rows[-1, :3] = start.as_tuple(), goal.as_tuple()
    return rows


def _nose_out_witness(start: Pose, goal: Pose, y_hump: float = 13.0) -> np.ndarray:
    """Forward out of a slot nose-out: untwist, straight up, an S onto the goal's line."""
    dth = start.yaw - math.pi / 2
    tail = _rows(*_integrate(lambda v: -2 * dth * (1.0 - v), 1.0, start.x, start.y, start.yaw))
    tail[-1, 2] = math.pi / 2
    x_line = float(tail[-1, 0])
    straight = _line(x_line, tail[-1, 1], math.pi / 2, y_hump - tail[-1, 1])

    def miss(p):
        hx, _, hyaw, _ = _integrate(_hump(*p), 4.0, x_line, y_hump, math.pi / 2)
        return [hx[-1] - goal.x, hyaw[-1] - math.pi / 2]

    k1, k2 = fsolve(miss, [0.001, -0.001], xtol=1e-14)
    hump = _rows(*_integrate(_hump(k1, k2), 4.0, x_line, y_hump, math.pi / 2))
    last = _line(goal.x, hump[-1, 1], math.pi / 2, goal.y - hump[-1, 1])
    rows = np.vstack([tail, straight[1:], hump[1:], last[1:]])
    rows[0, :3], rows[-1, :3] = start.as_tuple(), goal.as_tuple()
    return rows


def _flip(p: Pose) -> Pose:
    """The same footprint facing the other way."""
    d = FRONT - REAR
    return Pose(p.x + d * math.cos(p.yaw), p.y + d * math.sin(p.yaw), p.yaw + math.pi)


def _keep(m: Map) -> float:
    """What the planner promises to keep: min(0.05, 0.999 x the ends' own clearance)."""
    checker = PlanningProblem.from_map(m).checker
    ends = min(checker.body_clearance(p.as_tuple()) for p in (m.start, m.goal))
    return min(0.05, 0.999 * ends)


def _verify(m: Map, path: Path):
    return verify_path(m, path, max_sharpness=0.2, clearance=_keep(m) * (1 - 1e-9))


def _plan(m: Map, planner: str = "improved-rrt-connect", reverse: bool = False, **opts):
    problem = PlanningProblem.from_map(m, reverse=reverse)
    return make_planner(planner, **opts).solve(
        problem, np.random.default_rng(0), Budget(max_iterations=20000, max_time_s=60.0)
    )


def _as_path(rows: np.ndarray) -> Path:
    return Path(rows, rows[:, :2])


def _rotated(m: Map, rows: np.ndarray, deg: float) -> tuple[Map, np.ndarray]:
    th = math.radians(deg)
    c, s = math.cos(th), math.sin(th)

    def at(x: float, y: float) -> tuple[float, float]:
        dx, dy = x - 15.0, y - 10.0
        return (25.0 + c * dx - s * dy, 20.0 + s * dx + c * dy)

    obs = tuple(Obstacle(at(*o.center), o.size, o.yaw + th) for o in m.obstacles)
    start, goal = (Pose(*at(p.x, p.y), p.yaw + th) for p in (m.start, m.goal))
    out = rows.copy()
    for r in out:
        r[0], r[1] = at(r[0], r[1])
        r[2] += th
    return Map("slot30", (0.0, 0.0, 50.0, 40.0), obs, start, goal), out


# --- the witnesses hold --------------------------------------------------------------


@pytest.mark.parametrize("key", sorted(SLOTS))
def test_slot_witness_keeps_the_promised_clearance_and_sharpness(key):
    m = _slot_map(key)
    rows = _nose_in_witness(m.start, m.goal)
    assert (rows[:, 4] == 1).all()  # forward only: a witness for --reverse too
    check = _verify(m, _as_path(rows))
    assert check.ok, check
    assert check.min_clearance_m >= _keep(m)


# --- what the nudge fixed, and keeps fixed ----------------------------------------------


def test_nudge_solves_a_slot_that_was_a_false_proof():
    m = _slot_map(47)
    res = _plan(m)
    assert res.status is PlanStatus.SOLVED, res.message
    assert "goal's heading turned" in res.message
    assert _verify(m, res.path).ok
    off = _plan(m, hybrid={"nudge_ends": False})
    assert off.status is PlanStatus.PROVEN_UNREACHABLE


@pytest.mark.parametrize("planner", ["improved-rrt-connect", "hybrid-a-star"])
def test_nudge_solves_the_slot_rotated_30_deg(planner):
    m0 = _slot_map(47)
    m, rows = _rotated(m0, _nose_in_witness(m0.start, m0.goal), 30.0)
    assert _verify(m, _as_path(rows)).ok  # the witness turns with the map
    res = _plan(m, planner)
    assert res.status is PlanStatus.SOLVED, res.message
    assert _verify(m, res.path).ok


def _nose_out_map(key: int) -> Map:
    m = _slot_map(key, bounds=(0.0, 0.0, 30.0, 24.0))
    return Map("nose_out", m.bounds, m.obstacles, _flip(m.goal), Pose(15.0, 18.0, math.pi / 2))


@pytest.mark.parametrize("key", [79, 123])
def test_nose_out_start_in_a_turned_slot_is_solved(key):
    m = _nose_out_map(key)
    assert _verify(m, _as_path(_nose_out_witness(m.start, m.goal))).ok
    for planner in ("improved-rrt-connect", "hybrid-a-star"):
        res = _plan(m, planner)
        assert res.status is PlanStatus.SOLVED, (planner, res.message)
        assert _verify(m, res.path).ok


@pytest.mark.parametrize("key", [79, 123])
def test_reverse_in_bay_turned_is_solved_with_reverse(key):
    out = _nose_out_map(key)
    m = Map("reverse_in", out.bounds, out.obstacles, out.goal, out.start)
    rows = _nose_out_witness(out.start, out.goal)[::-1].copy()
    rows[:, 4] = -1.0  # the same motion backwards in time
    assert _verify(m, _as_path(rows)).ok
    for planner in ("improved-rrt-connect", "hybrid-a-star"):
        res = _plan(m, planner, reverse=True)
        assert res.status is PlanStatus.SOLVED, (planner, res.message)
        assert _verify(m, res.path).ok


# --- the built-in maps do not change -----------------------------------------------------

_BUILTIN = [
    (name, planner, rev)
    for name in (
        "overtake",
        "parking_lot",
        "narrow_gap",
        "no_path",
        "garage",
        "turning_bulb",
        "kerbside",
        "reverse_bay",
        "dead_end",
    )
    for planner in ("improved-rrt-connect", "hybrid-a-star")
    for rev in (False, True)
    if not (name == "dead_end" and not rev)
]  # fmt: skip  (dead_end forward: 3 s each)


@pytest.mark.parametrize(("name", "planner", "reverse"), _BUILTIN)
def test_builtin_answer_is_the_same_without_the_nudge(name, planner, reverse):
    m = builtin_map(name)
    off = (
        {"hybrid": {"nudge_ends": False}}
        if planner == "improved-rrt-connect"
        else {"nudge_ends": False}
    )
    a, b = _plan(m, planner, reverse), _plan(m, planner, reverse, **off)
    assert a.status is b.status
    assert a.message == b.message
    if a.path is not None:
        assert np.array_equal(np.asarray(a.path.xy), np.asarray(b.path.xy))


# --- the false proofs that remain ----------------------------------------------------------


@pytest.mark.parametrize(("key", "planner", "reverse"), [
    (79, "improved-rrt-connect", False), (79, "improved-rrt-connect", True),
    (79, "hybrid-a-star", False), (123, "improved-rrt-connect", False),
    (50, "improved-rrt-connect", False), (139, "improved-rrt-connect", False),
    pytest.param(3, "improved-rrt-connect", False, marks=pytest.mark.xfail(
        strict=True, reason="BUG: slot 3's goal is still 'proven' unreachable although a "
        "forward path keeping the promised clearance and sharpness 0.2 exists: the coarse "
        "0.25 deg nudge taken opens 2 m of straight drive (0.28-0.38 deg would open 6 m), "
        "and the nudged search runs out after 5-10 expansions (hybrid/nudge.py)")),
])  # fmt: skip
def test_turned_slot_goal_is_not_proven_unreachable(key, planner, reverse):
    res = _plan(_slot_map(key), planner, reverse)
    assert res.status is not PlanStatus.PROVEN_UNREACHABLE, res.message


def _goal_nudge_setup(key: int):
    m = _slot_map(key)
    problem = PlanningProblem.from_map(m)
    body = body_test(problem.checker, 0.999 * problem.checker.body_clearance(m.goal.as_tuple()))
    return m, problem, body


@pytest.mark.parametrize("key", [79, 123])
def test_a_gentle_arc_out_of_the_goal_opens_the_straight_drive(key):
    m, _, body = _goal_nudge_setup(key)
    g = m.goal
    assert _straight_run(body, g.x, g.y, g.yaw, -1, 0.1) < 1.0  # boxed in as it stands
    s = np.arange(1, 6) * 0.1
    opens = []
    for deg in np.arange(0.025, 0.5, 0.025):
        kappa = math.copysign(math.radians(deg), m.goal.yaw + math.pi / 2) / 0.5
        arc = arc_poses(g.x, g.y, g.yaw, kappa, -1, s)
        if body.free(arc).all() and _straight_run(body, *arc[-1], -1, 0.1) >= PROBE_M:
            opens.append(deg)
    # A window of turns strictly between 0.25 and 0.5 deg opens the full probe.
    assert opens and all(0.25 < d < 0.5 for d in opens), opens


@pytest.mark.parametrize("key", [79, 123])
def test_nudge_finds_the_arc_that_opens_the_goal(key):
    m, problem, body = _goal_nudge_setup(key)
    got = nudge(m.goal, True, (1,), body, problem.vehicle.kappa_max, 0.5, 0.1)
    assert got is not None
