"""Guards found by mutation testing of the Hybrid A* modules (each fails under a real-looking bug).

References are independent of the code under test where possible: shapely bodies and
obstacles, brute-force walks along a straight, closed-form facts (a straight line is the
shortest path between collinear poses) and the contracts in the modules' docstrings.
"""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest
import shapely
from test_mutation_guards_collision import (
    BOUNDS,
    V,
    _checker,
    _union,
)
from test_mutation_guards_collision import _poses_near_obstacles as _near_obstacles

from rrtdrive.collision import CollisionChecker
from rrtdrive.geometry import wrap_angle
from rrtdrive.maps import Map, Obstacle
from rrtdrive.planning.base import PlanningProblem
from rrtdrive.planning.hybrid.body import BodyTest
from rrtdrive.planning.hybrid.config import HybridConfig
from rrtdrive.planning.hybrid.heuristic import Heuristic, HolonomicField
from rrtdrive.planning.hybrid.primitives import PrimitiveSet
from rrtdrive.planning.hybrid.resolution import free_cell_graph
from rrtdrive.planning.hybrid.search import HybridSearch, Piece, analytic_shots
from rrtdrive.types import Pose

RADIUS = 5.9
#: An empty 40 x 20 m lot: every analytic shot between two poses in its middle is clear.
OPEN = Map("open", (0.0, 0.0, 40.0, 20.0), (), Pose(8.0, 10.0, 0.0), Pose(30.0, 10.0, 0.0))


def _walled_start() -> Map:
    """A 30 x 20 m lot split by a wall at x = 15: the start's half, the goal's half."""
    wall = Obstacle((15.0, 10.0), (1.0, 20.0))
    return Map(
        "split", (0.0, 0.0, 30.0, 20.0), (wall,), Pose(6.0, 10.0, 0.0), Pose(24.0, 10.0, 0.0)
    )


@functools.cache
def _open_checker() -> CollisionChecker:
    return CollisionChecker.for_map(OPEN)


def _search(m: Map, start: Pose, cfg: HybridConfig | None = None) -> HybridSearch:
    """A search over ``m`` from ``start`` to its goal, with reverse, at 0.15 m clearance."""
    cfg = cfg or HybridConfig()
    problem = PlanningProblem.from_map(m, reverse=True)
    grid = free_cell_graph(problem, cfg.xy_resolution)
    h = Heuristic(HolonomicField.towards(grid, m.goal), None, m.goal)
    prims = PrimitiveSet.build(1 / RADIUS, cfg.curvatures, cfg.step, cfg.check_spacing, True)
    body = BodyTest(problem.checker, 0.15)
    shots = analytic_shots(m.goal, RADIUS, True, cfg.check_spacing, body)
    return HybridSearch(body, start, m.goal, h, prims, shots, cfg, 1 / RADIUS, m.bounds)


def test_a_replay_from_another_start_shoots_from_its_own_root() -> None:
    """The earlier search's shot outcomes count only for nodes equal to its own: not a new root.

    In the empty lot the root's shot connects. The earlier search (from elsewhere)
    rejected its root's connections; a search from the map's start that replays it
    must still try its own root's shot, and so take that connection at once.
    """
    earlier = _search(OPEN, Pose(8.0, 12.0, 0.3))
    _, done = earlier.run(lambda pieces: None, 1, lambda: False)
    assert done.connections > 0
    search = _search(OPEN, OPEN.start)
    search.replay(earlier)
    found, out = search.run(lambda pieces: pieces, 50, lambda: False)
    assert out.reason == "solved" and out.expansions == 1
    assert found is not None
    assert np.allclose(found[0].rows[0, :3], OPEN.start.as_tuple())
    assert np.allclose(found[-1].rows[-1, :3], OPEN.goal.as_tuple())


#: A start whose only connections cut a corner the ramps cannot keep clear (test_hybrid_ramps).
TIGHT_CORNER_START = Pose(59.2941018104284, 26.00974477372232, 2.135538579126397)


def test_the_margin_pass_replays_only_a_search_of_its_own_clearance(
    parking_lot: Map, parking_checker: object, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A search repeats an earlier one's rejected shots only when both keep one clearance.

    With more clearance the shots' body tests differ (fewer connections), so the
    earlier counts are not this search's: the margin pass here keeps 0.15 m + the
    margin, and must search on its own.
    """
    from rrtdrive.planning.hybrid import HybridAStar
    from rrtdrive.types import Budget

    pairs: list[tuple[float, float]] = []
    replay = HybridSearch.replay

    def recorded(self: HybridSearch, earlier: HybridSearch) -> None:
        pairs.append((self.body.clearance, earlier.body.clearance))
        replay(self, earlier)

    monkeypatch.setattr(HybridSearch, "replay", recorded)
    problem = PlanningProblem.from_map(parking_lot.with_query(start=TIGHT_CORNER_START))
    planner = HybridAStar(long_steps=(), max_solutions=2, refinements=0, lattice_after=0)
    res = planner.solve(problem, np.random.default_rng(0), Budget(max_iterations=20000))
    assert res.success and res.stats["connections"] > 2  # the margin pass ran
    assert all(a == b for a, b in pairs)


def test_a_root_the_goal_cannot_be_reached_from_is_out_of_states_at_once() -> None:
    """A search whose start lies where the goal cannot be reached (h = inf) is exhausted.

    ``HybridSearch.run`` computed the root's shot interval as ``int(hval /
    shot_distance)`` and raised OverflowError for h = inf. The planners' preamble proves
    such a query unreachable (different free components) before any search, so no plan
    was affected; a direct caller of the search got a crash, not ``"exhausted"``.
    """
    m = _walled_start()
    search = _search(m, m.start)
    assert search.heuristic.at(m.start.x, m.start.y, m.start.yaw) == math.inf
    found, out = search.run(lambda pieces: pieces, 100, lambda: False)
    assert found is None and out.reason == "exhausted"


# --- The body test against shapely ---------------------------------------------------

# The collision guards' map (a box and a turned box), its checker and shapely union.
_box_checker = _checker


def _keeps(pose: np.ndarray, clearance: float) -> bool:
    """Shapely: the body inside the shrunk bounds, farther than ``clearance`` from all."""
    x, y, yaw = (float(v) for v in pose[:3])
    c, s = math.cos(yaw), math.sin(yaw)
    local = ((-V.rear_overhang, -V.width / 2), (V.front_extent, -V.width / 2),
             (V.front_extent, V.width / 2), (-V.rear_overhang, V.width / 2))  # fmt: skip
    body = shapely.Polygon([(x + c * u - s * v, y + s * u + c * v) for u, v in local])
    xmin, ymin, xmax, ymax = BOUNDS
    inner = shapely.box(xmin + clearance, ymin + clearance, xmax - clearance, ymax - clearance)
    return inner.contains(body) and _union().distance(body) > clearance


@pytest.mark.parametrize("clearance", [0.0, 0.15, 0.4])
def test_the_body_tests_are_shapelys_answer(clearance: float) -> None:
    """free, all_free (runs of poses) and runs_free answer as shapely does, pose by pose."""
    body = BodyTest(_box_checker(), clearance)
    poses = _near_obstacles(600, 3)
    want = np.array([_keeps(p, clearance) for p in poses])
    assert 0.1 < want.mean() < 0.9
    assert np.array_equal(body.free(poses), want)
    # Runs of 20 poses: all_free and runs_free say whether every pose of a run keeps it.
    runs, wruns = poses.reshape(30, 20, 3), want.reshape(30, 20).all(axis=1)
    assert [body.all_free(r) for r in runs] == wruns.tolist()
    assert body.runs_free(runs).tolist() == wruns.tolist()
    # Runs of free poses the screens leave unsure, with one bad pose among them that is
    # not the likeliest to fail (the most disc room): every pose must be looked at.
    _, clear, room = body.screen(poses)
    unsure_free = np.flatnonzero(~clear & want)
    unsure_free = unsure_free[np.argsort(room[unsure_free])][:12]
    bad = np.flatnonzero(~clear & ~want & ~body.hits(poses))
    assert len(unsure_free) == 12 and len(bad) >= 5
    for b in bad[np.argsort(-room[bad])][:5]:
        assert room[b] > room[unsure_free[0]]
        for run in (poses[[*unsure_free, b]], poses[[unsure_free[0], b]]):
            assert not body.all_free(run) and not body.runs_free(run[None])[0]
    # A pose the sure-collision screen calls a hit does collide.
    assert not (body.hits(poses) & want).any()


@pytest.mark.parametrize("clearance", [0.0, 0.3])
def test_free_within_promises_every_arc_it_covers(clearance: float) -> None:
    """free_within(pose, reach(L, k)): every arc of length L and |kappa| <= k from it keeps clear.

    The search takes such arcs without a body test; shapely checks their poses here.
    """
    body = BodyTest(_box_checker(), clearance)
    kappa, length = 1 / RADIUS, 2.0
    reach = body.reach(length, kappa)
    prims = PrimitiveSet.build(kappa, 5, length, 0.1, reverse=True)
    rng = np.random.default_rng(5)
    poses = _near_obstacles(400, 8) + rng.normal(0.0, 1.0, (400, 3)) * [1.0, 1.0, 0.0]
    taken = 0
    for x, y, yaw in poses:
        if body.free_within(x, y, yaw, reach):
            taken += 1
            arcs = prims.poses_from(x, y, yaw).reshape(-1, 3)
            assert all(_keeps(p, clearance) for p in arcs[::3])
    assert taken >= 20


@pytest.mark.parametrize("over", [1.0, 1.02])
def test_a_path_steering_past_the_curvature_limit_is_never_built(over: float) -> None:
    """An arc at ``over`` times the car's curvature limit is refused; at the limit it is built."""
    from rrtdrive.planning.hybrid.path import build_path
    from rrtdrive.planning.hybrid.primitives import arc_poses

    kappa_max = 1 / RADIUS
    s = np.linspace(0.0, 4.0, 41)
    poses = arc_poses(8.0, 10.0, 0.0, over * kappa_max, 1, s)
    piece = Piece(1, np.column_stack([poses, np.full(len(s), over * kappa_max)]))
    built = build_path([piece], _open_checker(), None, True, 0.1, kappa_max)
    if over > 1.0:
        assert built is None
    else:
        assert built is not None and np.abs(built.rows[:, 3]).max() <= kappa_max
        assert np.allclose(built.rows[[0, -1], :3], poses[[0, -1]])


# --- Lead-ins, shortcuts and the segment re-check -------------------------------------


def _walls(m: Map) -> shapely.Geometry:
    x0, y0, x1, y1 = m.bounds
    outside = shapely.box(x0 - 5, y0 - 5, x1 + 5, y1 + 5).difference(shapely.box(x0, y0, x1, y1))
    return shapely.union_all([outside, *(o.polygon() for o in m.obstacles)])


def _arc_hits(
    walls: shapely.Geometry, pose: Pose, turn: float, gear: int, clearance: float
) -> bool:
    """Shapely: the full-lock arc of ARC_PROBE metres from ``pose`` comes within ``clearance``."""
    from rrtdrive.planning.hybrid.leads import ARC_PROBE
    from rrtdrive.planning.hybrid.primitives import arc_poses

    s = np.arange(1, round(ARC_PROBE / 0.05) + 1) * 0.05
    poses = arc_poses(pose.x, pose.y, pose.yaw, turn * V.kappa_max, gear, s)
    return any(shapely.Polygon(_corners(p)).distance(walls) < clearance - 1e-6 for p in poses)


def _corners(p: np.ndarray) -> list[tuple[float, float]]:
    x, y, yaw = (float(v) for v in p[:3])
    c, s = math.cos(yaw), math.sin(yaw)
    local = ((-V.rear_overhang, -V.width / 2), (V.front_extent, -V.width / 2),
             (V.front_extent, V.width / 2), (-V.rear_overhang, V.width / 2))  # fmt: skip
    return [(x + c * u - s * v, y + s * u + c * v) for u, v in local]


def test_the_first_lead_in_starts_at_the_nearest_point_the_car_can_turn_from() -> None:
    """The first via is the nearest LEAD_STEP point out of the bay whose arcs do not both hit.

    Brute force with shapely: every step nearer the bay is boxed in (both full-lock
    arcs out of it hit), so no shorter straight lead-in exists.
    """
    from rrtdrive.planning.hybrid.leads import LEAD_STEP, VIA_SPACING, lead_ins
    from rrtdrive.tight_maps import garage_goal, garage_map

    m = garage_map(9.0)
    goal = garage_goal(1, 11, 9.0, tail_in=False)
    walls, clearance = _walls(m), 0.15
    body = BodyTest(CollisionChecker.for_map(m), clearance)
    leads = lead_ins(goal, body, V.kappa_max, (1,), 0.1, 2 * V.length)
    assert len(leads) >= 2
    out = -1.0  # the car leaves the bay backwards in time: reverse for a nose-in lead
    c, s = math.cos(goal.yaw), math.sin(goal.yaw)
    dist = [math.hypot(lead.via.x - goal.x, lead.via.y - goal.y) for lead in leads]
    assert dist[1] - dist[0] == pytest.approx(VIA_SPACING)
    steps = round(dist[0] / LEAD_STEP)
    assert steps * LEAD_STEP == pytest.approx(dist[0])
    for k in range(1, steps + 1):
        d = out * k * LEAD_STEP
        pose = Pose(goal.x + c * d, goal.y + s * d, goal.yaw)
        boxed = all(_arc_hits(walls, pose, turn, -1, clearance) for turn in (1.0, -1.0))
        assert boxed == (k < steps), k


def test_a_straight_connection_has_no_shortcut() -> None:
    """A straight drive is the shortest path between its ends: no word is min_gain shorter.

    The anchors' words (Dubins forward) between poses along one straight line are that
    same straight, no shorter, so the connection comes back unchanged (``None``).
    """
    from rrtdrive.planning.hybrid.primitives import arc_poses
    from rrtdrive.planning.hybrid.shortcut import shortcut

    body = BodyTest(_open_checker(), 0.15)
    rows = arc_poses(6.0, 10.0, 0.0, 0.0, 1, np.linspace(0.0, 24.0, 97))
    pieces = [Piece(1, np.column_stack([rows[a : a + 25], np.zeros(25)])) for a in (0, 24, 48, 72)]

    def shots_to(target: Pose):  # noqa: ANN202 - the Shots type
        return analytic_shots(target, RADIUS, False, 0.1, body)

    assert shortcut(pieces, shots_to, body, tries=40) is None


def test_the_recheck_tests_the_middle_of_a_long_dense_segment() -> None:
    """A segment's poses between its first and last END_POSES are tested too.

    Rows 0.25 m apart and a check spacing of 0.5 m: the rows themselves are the poses
    tested. A post in the middle of a 45 m straight (shapely: the bodies there hit it)
    makes the connection fail the re-check (in a 60 m lot; without the post it passes).
    """
    from rrtdrive.planning.hybrid.path import END_POSES, build_path
    from rrtdrive.planning.hybrid.primitives import arc_poses

    post = Obstacle((28.0, 10.0), (0.3, 0.3))
    lot = (0.0, 0.0, 60.0, 20.0)
    m = Map("post", lot, (post,), OPEN.start, OPEN.goal)
    rows = arc_poses(5.0, 10.0, 0.0, 0.0, 1, np.linspace(0.0, 45.0, 181))
    assert len(rows) > 2 * END_POSES
    hit = [not shapely.Polygon(_corners(p)).disjoint(post.polygon()) for p in rows]
    assert any(hit) and not any(hit[:END_POSES] + hit[-END_POSES:])
    piece = Piece(1, np.column_stack([rows, np.zeros(len(rows))]))
    checker = CollisionChecker.for_map(m)
    built = build_path([piece], checker, None, True, 0.1, 1 / RADIUS, 0.5, 0.25)
    assert built is None
    empty = CollisionChecker.for_map(Map("empty", lot, (), OPEN.start, OPEN.goal))
    clear = build_path([piece], empty, None, True, 0.1, 1 / RADIUS, 0.5, 0.25)
    assert clear is not None


def test_the_recheck_tests_the_pose_between_the_first_rows() -> None:
    """Every pose ``check_spacing`` apart near the start is tested, the 64th one too.

    Rows 0.19 m apart (two tested poses each) up to row 31, then 0.15 m on with the yaw
    turned 0.3 rad: the pose halfway between rows 31 and 32 (the 64th pose tested) is
    the only one whose body reaches a 4 cm post (shapely), so the segment must fail.
    """
    from rrtdrive.planning.hybrid.path import build_path

    yaw = 0.3
    before = [[20.0 - 0.19 * (31 - i), 10.0, 0.0] for i in range(32)]
    after = [
        [20.0 - 0.19 * k * math.cos(yaw), 10.15 - 0.19 * k * math.sin(yaw), yaw] for k in range(60)
    ]
    rows = np.array(before + after)
    post = Obstacle((23.45, 9.732), (0.04, 0.04))
    halfway = 0.5 * (rows[31] + rows[32])
    assert not shapely.Polygon(_corners(halfway)).disjoint(post.polygon())
    assert all(shapely.Polygon(_corners(p)).distance(post.polygon()) > 0.01 for p in rows)
    lot = (0.0, 0.0, 60.0, 20.0)
    piece = Piece(1, np.column_stack([rows, np.zeros(len(rows))]))
    hit = CollisionChecker.for_map(Map("post", lot, (post,), OPEN.start, OPEN.goal))
    assert build_path([piece], hit, None, True, 0.0, 1 / RADIUS, 0.1, 0.25) is None
    empty = CollisionChecker.for_map(Map("empty", lot, (), OPEN.start, OPEN.goal))
    assert build_path([piece], empty, None, True, 0.0, 1 / RADIUS, 0.1, 0.25) is not None


# --- Shots and the heuristic's look-ups ------------------------------------------------


def test_a_shot_starts_exactly_at_the_pose_it_is_shot_from() -> None:
    """Every Reeds-Shepp shot's first row is the node's pose, unwrapped yaw included."""
    shots = analytic_shots(OPEN.goal, RADIUS, True, 0.1)
    for yaw in (0.3, 2.0 * math.pi + 0.3, -7.5, 3.0):
        pose = Pose(12.0, 8.0, yaw)
        cands = list(shots(pose))
        assert cands
        for pieces in cands:
            assert tuple(pieces[0].rows[0, :3]) == pose.as_tuple()
            assert np.allclose(pieces[-1].rows[-1, :3], OPEN.goal.as_tuple(), atol=1e-9)


@pytest.mark.parametrize("turned", [0.0, 2.0 * math.pi, -2.0 * math.pi])
def test_a_shot_with_a_lead_in_is_one_continuous_drive(turned: float) -> None:
    """Shots through a lead-in: pieces meet at their cusps, no row repeats, rows 0.1 m apart.

    ``turned``: the pose's yaw unwrapped by a whole turn (the search's yaws are
    unwrapped); yaws are compared wrapped, as every consumer of the rows does.
    """
    from rrtdrive.planning.hybrid.leads import lead_ins
    from rrtdrive.tight_maps import garage_map

    m = garage_map()
    body = BodyTest(CollisionChecker.for_map(m), 0.15)
    leads = lead_ins(m.goal, body, V.kappa_max, (1, -1), 0.1, 2 * V.length)
    assert leads
    pose = Pose(m.goal.x - 12.0, 12.0, turned)
    shots = analytic_shots(m.goal, 1 / V.kappa_max, True, 0.1, body, leads=leads)(pose)
    via_lead = 0
    for pieces in shots:
        if not np.allclose(pieces[-1].rows[-1, :3], m.goal.as_tuple()):
            continue
        rows = [p.rows for p in pieces]
        for a, b in zip(rows, rows[1:], strict=False):
            assert np.allclose(a[-1, :2], b[0, :2])  # the cusp: one pose, both gears
            assert abs(wrap_angle(a[-1, 2] - b[0, 2])) < 1e-9
        for r in rows:
            step = np.hypot(*np.diff(r[:, :2], axis=0).T)
            assert step.min() > 1e-6 and step.max() <= 0.1 + 1e-9
            assert np.abs(wrap_angle(np.diff(r[:, 2]))).max() < 0.1
        via_lead += any(np.allclose(r[0, :3], lead.via.as_tuple()) for r in rows for lead in leads)
    assert via_lead >= 1


def test_the_scalar_estimate_is_the_estimate_everywhere_on_and_off_the_grid() -> None:
    """Heuristic.scalar() gives at()'s values, also beyond each edge of the coarse grid (inf)."""
    m = _walled_start()
    problem = PlanningProblem.from_map(m, reverse=True)
    grid = free_cell_graph(problem, 0.5)
    h = Heuristic(HolonomicField.towards(grid, m.goal), None, m.goal)
    at = h.scalar()
    x0, y0 = grid.origin
    nx, ny = grid.index.shape
    top, right = y0 + ny * grid.resolution, x0 + nx * grid.resolution
    rng = np.random.default_rng(2)
    xs = np.concatenate([rng.uniform(x0 - 2, right + 2, 300), [5.0, 20.0, right - 0.1, 5.0]])
    ys = np.concatenate([rng.uniform(y0 - 2, top + 2, 300), [top + 0.1] * 3 + [y0 - 0.1]])
    for x, y in zip(xs, ys, strict=True):
        assert at(x, y, 0.0) == h.at(x, y, 0.0)
    assert at(20.0, top + 0.1, 0.0) == math.inf
