"""The improved RRT-Connect: configuration, growth pieces and verified end-to-end results."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
import shapely
from hypothesis import given
from hypothesis import strategies as st

from rrtdrive.collision import CollisionChecker
from rrtdrive.maps import Map, Obstacle, builtin_map
from rrtdrive.planning import make_planner
from rrtdrive.planning.base import PlanningProblem, cached_checker
from rrtdrive.planning.dubins import shortest_dubins
from rrtdrive.planning.improved import (
    COMPONENTS,
    SMOOTHING_COMPONENTS,
    ImprovedConfig,
    ImprovedRRTConnect,
    ObtuseTree,
    default_expansion_lmin,
    envelope_gaps,
    expand_obstacles,
    expanded_checker,
    extend,
    fast_edge_test,
    greedy_connect,
    link,
)
from rrtdrive.planning.improved.config import default_smoothing
from rrtdrive.planning.smoothing import CurveKind, SmoothingConfig, max_sharpness
from rrtdrive.types import Budget, InputError, PlanStatus, Pose, Tree
from rrtdrive.vehicle import footprint_corners
from rrtdrive.verify import verify_path

KAPPA = 1.0 / 6.0
# The iteration budget decides; the safety cap is raised so that a loaded machine (the
# suite runs on both cores) cannot turn a query into a timeout.
BUDGET = Budget(max_time_s=300.0)


# ----------------------------------------------------------------------------- independent check


def menger(points: np.ndarray) -> np.ndarray:
    a, b, c = points[:-2], points[1:-1], points[2:]
    ab, bc, ca = b - a, c - b, a - c
    cross = ab[:, 0] * bc[:, 1] - ab[:, 1] * bc[:, 0]
    return 2.0 * cross / (np.hypot(*ab.T) * np.hypot(*bc.T) * np.hypot(*ca.T))


def densify(s: np.ndarray, spacing: float = 0.1) -> np.ndarray:
    seg = np.hypot(*np.diff(s[:, :2], axis=0).T)
    out = []
    for i, n in enumerate(np.maximum(1, np.ceil(seg / spacing).astype(int))):
        f = np.arange(n)[:, None] / n
        dyaw = (s[i + 1, 2] - s[i, 2] + math.pi) % (2 * math.pi) - math.pi
        out.append(np.hstack([s[i, :2] + f * (s[i + 1, :2] - s[i, :2]), s[i, 2] + f * dyaw]))
    out.append(s[-1:, :3])
    return np.vstack(out)


_UNIONS: dict[int, shapely.Geometry] = {}


def assert_valid_path(result, m: Map) -> None:
    """Check a solved path with shapely and plain geometry, independently of the planner."""
    assert result.status is PlanStatus.SOLVED and result.success
    s = result.path.samples
    start, goal = m.start, m.goal
    assert np.array_equal(s[0, :2], [start.x, start.y])
    assert np.array_equal(s[-1, :2], [goal.x, goal.y])
    gaps = np.hypot(*np.diff(s[:, :2], axis=0).T)
    assert gaps.max() <= 0.25 + 1e-9 and gaps.min() > 0
    for (a, b), yaw in (((s[0], s[1]), start.yaw), ((s[-2], s[-1]), goal.yaw)):
        chord = math.atan2(b[1] - a[1], b[0] - a[0])
        assert abs((chord - yaw + math.pi) % (2 * math.pi) - math.pi) < math.radians(3)
    # Discrete curvature of the xy samples (three-point circles), a small tolerance for
    # the discretisation.
    assert np.abs(menger(s[:, :2])).max() <= KAPPA * 1.01
    assert result.path.max_curvature <= KAPPA + 1e-9
    # Exact body at poses at most 0.1 m apart, against shapely obstacles and the bounds box.
    poses = densify(s)
    bodies = shapely.polygons(footprint_corners(poses, m.vehicle))
    key = id(m.obstacles)
    if key not in _UNIONS:
        _UNIONS[key] = shapely.union_all([shapely.Polygon(o.corners()) for o in m.obstacles])
    assert not shapely.intersects(_UNIONS[key], bodies).any()
    assert shapely.contains(shapely.box(*m.bounds), bodies).all()


def solve(m: Map, seed: int = 0, budget: Budget = BUDGET, **options):
    return ImprovedRRTConnect(**options).solve(
        PlanningProblem.from_map(m), np.random.default_rng(seed), budget
    )


# ----------------------------------------------------------------------------- configuration


def test_components_are_boolean_config_fields_on_by_default():
    fields = {f.name: f for f in dataclasses.fields(ImprovedConfig)}
    smoothing_fields = {f.name for f in dataclasses.fields(SmoothingConfig)}
    assert set(SMOOTHING_COMPONENTS) <= smoothing_fields
    assert set(COMPONENTS) - set(SMOOTHING_COMPONENTS) <= set(fields)
    cfg = ImprovedConfig()
    assert all(cfg.enabled(name) is True for name in COMPONENTS)
    assert all(getattr(cfg.smoothing, name) is True for name in SMOOTHING_COMPONENTS)


def test_the_post_processor_settings_are_one_smoothing_config():
    # No copies of SmoothingConfig's fields: the planner's defaults are one SmoothingConfig.
    fields = {f.name for f in dataclasses.fields(ImprovedConfig)}
    smoothing_fields = {f.name for f in dataclasses.fields(SmoothingConfig)}
    assert fields & smoothing_fields == set()
    assert ImprovedConfig().smoothing == SmoothingConfig(max_rounds=24) == default_smoothing()
    planner = ImprovedRRTConnect(smoothing={"degree": 3, "max_rounds": 8})
    assert planner.config.smoothing == SmoothingConfig(degree=3, max_rounds=8)
    custom = SmoothingConfig(supplement_n=0.4)
    assert ImprovedRRTConnect(smoothing=custom).config.smoothing is custom
    assert ImprovedRRTConnect(ImprovedConfig(smoothing=custom)).config.smoothing is custom


def test_components_can_be_disabled_by_name_or_keyword():
    assert ImprovedRRTConnect(disable=("obtuse_parent",)).config.obtuse_parent is False
    assert ImprovedRRTConnect(disable="prune").config.smoothing.prune is False
    assert ImprovedRRTConnect(adaptive_step=False).config.adaptive_step is False
    planner = make_planner("improved-rrt-connect", disable=["supplement", "sharp_repair"])
    assert planner.config.smoothing.supplement is False
    assert planner.config.smoothing.sharp_repair is False
    assert ImprovedConfig().without(*COMPONENTS) == ImprovedConfig(
        **{name: False for name in COMPONENTS if name not in SMOOTHING_COMPONENTS},
        smoothing=SmoothingConfig(max_rounds=24, **{name: False for name in SMOOTHING_COMPONENTS}),
    )


@pytest.mark.parametrize(
    ("options", "field"),
    [
        ({"step": 0.0}, "planner.step"),
        ({"step": 0.001}, "planner.step"),  # a node a millimetre: millions per iteration
        ({"step": float("nan")}, "planner.step"),
        ({"smoothing": {"prune": "yes"}}, "planner.smoothing.prune"),
        ({"smoothing": {"degree": 4}}, "planner.smoothing.degree"),
        ({"smoothing": {"supplement_n": 1.0}}, "planner.smoothing.supplement_n"),
        ({"smoothing": {"supplement_delta": -1.0}}, "planner.smoothing.supplement_delta"),
        ({"smoothing": {"bogus": 1}}, "planner.smoothing.bogus"),
        ({"smoothing": {"clearance": 0.3}}, "planner.smoothing.clearance"),
        ({"smoothing": 3}, "planner.smoothing"),
        ({"expansion_a": -1.0}, "planner.expansion_a"),
        ({"expansion_lmin": float("inf")}, "planner.expansion_lmin"),
        ({"passage_bias": 1.0}, "planner.passage_bias"),
        ({"smoothing": {"max_rounds": 0}}, "planner.smoothing.max_rounds"),
        ({"max_repair_rounds": 8}, "planner.max_repair_rounds"),
        ({"bogus": 1}, "planner.bogus"),
        ({"disable": ("nope",)}, "planner.disable"),
    ],
)
def test_bad_options_raise_input_error_naming_the_field(options, field):
    with pytest.raises(InputError, match=field.replace(".", r"\.")):
        ImprovedRRTConnect(**options)


def test_make_planner_reports_unknown_options():
    with pytest.raises(InputError, match="planner"):
        make_planner("improved-rrt-connect", colour="red")


# ----------------------------------------------------------------------------- obtuse parent


def reference_parent(nodes, parent_pos, q) -> int:
    """Table 1 with explicit angles: nearest obtuse node, else nearest node.

    A root with a virtual parent (node 0 with a parent position) only qualifies when
    obtuse; -1 when nothing qualifies.
    """
    d = [math.dist(n, q) for n in nodes]
    obtuse = []
    for i, (n, p) in enumerate(zip(nodes, parent_pos, strict=True)):
        if p is None:
            continue
        u, v = np.subtract(p, n), np.subtract(q, n)
        if np.linalg.norm(u) > 0 and np.linalg.norm(v) > 0:
            cos = u @ v / (np.linalg.norm(u) * np.linalg.norm(v))
            if cos < 0:
                obtuse.append(i)
    if obtuse:
        return min(obtuse, key=lambda i: d[i])
    pool = [i for i in range(len(nodes)) if not (i == 0 and parent_pos[0] is not None)]
    return min(pool, key=lambda i: d[i]) if pool else -1


def small_tree() -> ObtuseTree:
    # root (0,0) with virtual parent (-5,0); a=(5,0) <- root; b=(5,5) <- a.
    t = ObtuseTree(np.array([0.0, 0.0]), virtual_parent=np.array([-5.0, 0.0]))
    t.add(np.array([5.0, 0.0]), 0)
    t.add(np.array([5.0, 5.0]), 1)
    return t


def test_table_1_no_obtuse_node_picks_the_nearest():
    t = small_tree()
    # Behind the root and below a: every angle is acute. The root is nearest but, having
    # a virtual parent, grows only along its heading: the nearest other node is chosen.
    q = np.array([-3.0, -0.5])
    assert reference_parent([(0, 0), (5, 0), (5, 5)], [(-5, 0), (0, 0), (5, 0)], q) == 1
    assert t.nearest(q) == 0 and t.choose_parent(q) == 1
    # A root without a virtual parent is never obtuse but can be the nearest.
    bare = ObtuseTree(np.array([0.0, 0.0]))
    bare.add(np.array([5.0, 0.0]), 0)
    bare.add(np.array([5.0, 5.0]), 1)
    assert bare.choose_parent(q) == 0
    # A lone root with a virtual parent behind a sample: nothing to grow from.
    lone = ObtuseTree(np.array([0.0, 0.0]), virtual_parent=np.array([-5.0, 0.0]))
    assert lone.choose_parent(q) == -1 and lone.choose_parent(q, obtuse=False) == 0


def test_table_1_mixed_picks_the_nearest_obtuse_node():
    t = small_tree()
    q = np.array([7.0, -1.0])  # nearest is a (acute: a's parent is the root, q lies ahead),
    # wait: a's angle (root, a, q) is obtuse; b's (a, b, q) acute; the root's obtuse.
    assert t.nearest(q) == 1
    assert t.choose_parent(q) == 1
    q = np.array([4.0, 8.0])  # nearest is b; b's angle (a, b, q) is obtuse -> b
    assert t.choose_parent(q) == 2
    q = np.array([6.0, 3.0])  # nearest is b (acute), a is obtuse but farther -> a
    assert t.nearest(q) == 2
    assert t.choose_parent(q) == 1


def test_table_1_all_obtuse_picks_the_nearest():
    t = ObtuseTree(np.array([0.0, 0.0]), virtual_parent=np.array([-5.0, 0.0]))
    t.add(np.array([5.0, 0.0]), 0)
    q = np.array([20.0, 0.5])  # both angles obtuse
    assert t.choose_parent(q) == t.nearest(q) == 1


def test_obtuse_choice_matches_the_reference_on_random_trees():
    rng = np.random.default_rng(5)
    for _ in range(200):
        root = rng.uniform(0, 50, 2)
        vp = root + rng.normal(0, 5, 2) if rng.random() < 0.7 else None
        t = ObtuseTree(root, capacity=4, virtual_parent=vp)
        for _ in range(rng.integers(0, 30)):
            t.add(rng.uniform(0, 50, 2), int(rng.integers(0, len(t))))
        q = rng.uniform(0, 50, 2)
        parents = [None if vp is None else tuple(vp)] + [
            tuple(t.nodes[t.parents[i]]) for i in range(1, len(t))
        ]
        nodes = [tuple(n) for n in t.nodes[: len(t)]]
        assert t.choose_parent(q) == reference_parent(nodes, parents, q)
        assert t.choose_parent(q, obtuse=False) == t.nearest(q)


def test_virtual_parents_make_the_roots_grow_along_the_headings():
    start = ObtuseTree(np.array([0.0, 0.0]), virtual_parent=np.array([-5.0, 0.0]))
    start.add(np.array([0.0, 6.0]), 0)  # a branch to the side
    # Root obtuse only for samples ahead of the start.
    assert start.choose_parent(np.array([3.0, 3.5])) == 0
    assert start.choose_parent(np.array([-3.0, 3.5])) == 1
    goal = ObtuseTree(np.array([50.0, 0.0]), virtual_parent=np.array([55.0, 0.0]))
    goal.add(np.array([50.0, 6.0]), 0)
    # The goal tree grows from the goal backwards: root obtuse only for samples behind it.
    assert goal.choose_parent(np.array([47.0, 3.5])) == 0
    assert goal.choose_parent(np.array([53.0, 3.5])) == 1


# ----------------------------------------------------------------------------- growth steps


class Recorder:
    def __init__(self, free=lambda a, b: True):
        self.calls = []
        self.free = free

    def __call__(self, a, b):
        self.calls.append((tuple(a), tuple(b)))
        return self.free(a, b)


def test_extend_takes_one_step_and_tests_the_driving_direction():
    t = ObtuseTree(np.array([0.0, 0.0]))
    rec = Recorder()
    i = extend(t, False, 0, np.array([10.0, 0.0]), 5.0, rec)
    assert i == 1 and t.nodes[1].tolist() == [5.0, 0.0]
    assert rec.calls[-1] == ((0.0, 0.0), (5.0, 0.0))
    i = extend(t, True, 1, np.array([7.0, 0.0]), 5.0, rec)  # goal tree: child -> parent
    assert t.nodes[i].tolist() == [7.0, 0.0]
    assert rec.calls[-1] == ((7.0, 0.0), (5.0, 0.0))
    assert extend(t, False, 0, np.array([10.0, 0.0]), 5.0, Recorder(lambda a, b: False)) == -1


def test_greedy_connect_doubles_the_step_after_the_first():
    t = ObtuseTree(np.array([0.0, 0.0]))
    j = greedy_connect(t, False, np.array([40.0, 0.0]), 5.0, Recorder())
    np.testing.assert_allclose(t.nodes[: len(t), 0], [0, 5, 15, 25, 35, 40])
    assert t.nodes[j].tolist() == [40.0, 0.0]
    t = ObtuseTree(np.array([0.0, 0.0]))
    greedy_connect(t, False, np.array([20.0, 0.0]), 5.0, Recorder(), adaptive=False)
    np.testing.assert_allclose(t.nodes[: len(t), 0], [0, 5, 10, 15, 20])


def test_greedy_connect_stops_at_the_first_collision():
    t = ObtuseTree(np.array([0.0, 0.0]))
    wall = Recorder(lambda a, b: max(a[0], b[0]) < 22.0)
    assert greedy_connect(t, False, np.array([40.0, 0.0]), 5.0, wall) == -1
    np.testing.assert_allclose(t.nodes[: len(t), 0], [0, 5, 15])


def test_greedy_connect_on_a_map_with_a_wall():
    m = Map(
        "wall",
        (0.0, 0.0, 100.0, 100.0),
        (Obstacle((50.0, 50.0), (2.0, 40.0)),),
        Pose(10.0, 50.0, 0.0),
        Pose(90.0, 50.0, 0.0),
    )
    checker = CollisionChecker.for_map(m)
    t = ObtuseTree(np.array([10.0, 50.0]))
    assert greedy_connect(t, False, np.array([90.0, 50.0]), 5.0, checker.edge_free) == -1
    xs = t.nodes[: len(t), 0]
    assert xs.tolist() == [10.0, 15.0, 25.0, 35.0]  # 45 would put the front into the wall
    assert all(checker.edge_free(t.nodes[t.parents[i]], t.nodes[i]) for i in range(1, len(t)))


def test_link_joins_straight_in_pieces_no_longer_than_the_step():
    t = ObtuseTree(np.array([0.0, 0.0]))
    t.add(np.array([0.0, 30.0]), 0)
    j = link(t, False, np.array([12.0, 1.0]), 5.0, Recorder())
    chain = t.branch(j)
    assert chain[0].tolist() == [12.0, 1.0] and chain[-1].tolist() == [0.0, 0.0]
    assert np.hypot(*np.diff(chain, axis=0).T).max() <= 5.0 + 1e-12
    assert link(t, False, np.array([90.0, 90.0]), 5.0, Recorder()) == -1  # nothing within 4p


def test_fast_edge_test_agrees_with_the_checker(parking_checker):
    rng = np.random.default_rng(11)
    test = fast_edge_test(parking_checker)
    a = rng.uniform(0, 100, (3000, 2))
    d = rng.uniform(0, 15, 3000)[:, None] * np.column_stack(
        [np.cos(t := rng.uniform(-np.pi, np.pi, 3000)), np.sin(t)]
    )
    b = a + d
    got = [test(p, q) for p, q in zip(a.tolist(), b.tolist(), strict=True)]
    want = [parking_checker.edge_free(p, q) for p, q in zip(a.tolist(), b.tolist(), strict=True)]
    assert got == want
    assert 0.05 < np.mean(want) < 0.95


def test_passage_cells_lie_in_the_narrow_gap_and_not_in_open_space():
    m = builtin_map("narrow_gap")
    cells = cached_checker(m).passage_cells((m.start.x, m.start.y))
    in_gap = (np.abs(cells[:, 0] - 50.0) < 1.0) & (np.abs(cells[:, 1] - 50.0) < 0.3)
    assert in_gap.sum() >= 10
    empty = Map("empty", (0.0, 0.0, 100.0, 100.0), (), Pose(10, 50, 0), Pose(90, 50, 0))
    open_cells = CollisionChecker.for_map(empty).passage_cells((10.0, 50.0))
    assert not ((np.abs(open_cells - 50.0) < 40.0).all(axis=1)).any()


# ----------------------------------------------------------------------------- expansion


def test_envelope_gaps_by_hand():
    a = Obstacle((0.0, 0.0), (6.0, 8.0))  # radius 5
    b = Obstacle((20.0, 0.0), (6.0, 8.0))
    c = Obstacle((20.0, 12.0), (6.0, 8.0))
    np.testing.assert_allclose(envelope_gaps([a, b, c]), [20 - 10, 12 - 10, 12 - 10])
    # With bounds the boundary counts: b is 5 - 5 = 0 from x = 25... choose bounds.
    np.testing.assert_allclose(
        envelope_gaps([a, b], bounds=(-30.0, -30.0, 28.0, 30.0)), [10.0, 28 - 20 - 5]
    )
    assert envelope_gaps([a]).tolist() == [math.inf]


def _pairwise_gaps(obstacles: list[Obstacle]) -> np.ndarray:
    """The envelope gaps from the full distance matrix: the reference, by brute force."""
    c = np.array([o.center for o in obstacles], dtype=float)
    r = np.array([math.hypot(*o.size) / 2.0 for o in obstacles])
    d = np.hypot(c[:, None, 0] - c[None, :, 0], c[:, None, 1] - c[None, :, 1])
    gap = d - r[:, None] - r[None, :]
    np.fill_diagonal(gap, np.inf)
    return gap.min(axis=1)


@given(
    st.lists(
        st.tuples(
            st.integers(0, 12), st.integers(0, 12),  # a coarse lattice: ties and piles
            st.sampled_from((0.2, 1.0, 5.0, 40.0)), st.floats(0.1, 30.0),  # radii far apart
        ),
        min_size=12, max_size=80,
    )
)
def test_envelope_gaps_equal_the_pairwise_matrix(rows):
    # The KD-tree search must find each circle's nearest gap exactly, ties and piled
    # centres included, however much the radii differ.
    obstacles = [Obstacle((2.5 * x, 2.5 * y), (w, h)) for x, y, w, h in rows]
    assert np.array_equal(envelope_gaps(obstacles), _pairwise_gaps(obstacles))


def test_envelope_gaps_of_a_pile_with_one_larger():
    # 300 circles on one spot and a larger one there: each small one's nearest gap is
    # to the large one, beyond its 256 nearest neighbours, so the blockwise comparison
    # with all decides it.
    obstacles = [Obstacle((3.0, 3.0), (1.0, 1.0))] * 300 + [Obstacle((3.0, 3.0), (9.0, 1.0))]
    gaps = envelope_gaps(obstacles)
    assert np.array_equal(gaps, _pairwise_gaps(obstacles))
    assert gaps[0] == pytest.approx(-(math.hypot(1, 1) + math.hypot(9, 1)) / 2)


def test_expansion_grows_only_obstacles_with_room():
    far = [Obstacle((0.0, 0.0), (6.0, 8.0)), Obstacle((20.0, 0.0), (6.0, 8.0))]  # gap 10
    near = [Obstacle((0.0, 0.0), (6.0, 8.0)), Obstacle((12.0, 0.0), (6.0, 8.0))]  # gap 2
    new, grown = expand_obstacles(far, 1.0, 3.4)
    assert grown.tolist() == [True, True]
    assert new[0].size == (7.0, 9.0) and new[0].center == far[0].center
    new, grown = expand_obstacles(near, 1.0, 3.4)
    assert grown.tolist() == [False, False] and new == tuple(near)
    # Exactly L_min: not grown (the rule is L2 > L_min).
    _, grown = expand_obstacles(far, 1.0, 10.0)
    assert grown.tolist() == [False, False]
    # A rectangle close to the boundary keeps its size.
    _, grown = expand_obstacles(far, 1.0, 3.4, bounds=(-7.0, -50.0, 100.0, 50.0))
    assert grown.tolist() == [False, True]


def test_default_lmin_keeps_every_passable_gap_passable():
    a, margin, width = 1.0, 0.1, 1.8
    lmin = default_expansion_lmin(width, margin, a)
    assert lmin == pytest.approx(width + 2 * margin + math.sqrt(2) * a)
    # Two squares rotated 45 degrees, corner to corner, circles just over L_min apart.
    r = math.hypot(4.0, 4.0) / 2
    gap = lmin + 0.01
    obs = [
        Obstacle((0.0, 0.0), (4.0, 4.0), math.pi / 4),
        Obstacle((2 * r + gap, 0.0), (4.0, 4.0), math.pi / 4),
    ]
    new, grown = expand_obstacles(obs, a, lmin)
    assert grown.all()
    after = new[0].polygon().distance(new[1].polygon())
    assert after >= width + 2 * margin


def test_expanded_checker_is_cached_and_absent_when_nothing_grows():
    ovt = cached_checker(builtin_map("overtake"))
    assert expanded_checker(ovt, 1.0, 3.41) == (None, 0)
    m = scattered_map()
    checker = cached_checker(m)
    first = expanded_checker(checker, 1.0, 3.41)
    assert first[1] == len(m.obstacles)
    assert expanded_checker(checker, 1.0, 3.41)[0] is first[0]
    assert first[0].obstacles[0].size == (5.0, 5.0)


def scattered_map() -> Map:
    squares = [(30.0, 30.0), (70.0, 30.0), (30.0, 70.0), (70.0, 70.0), (50.0, 50.0)]
    return Map(
        "scattered",
        (0.0, 0.0, 100.0, 100.0),
        tuple(Obstacle(c, (4.0, 4.0)) for c in squares),
        Pose(10.0, 50.0, 0.0),
        Pose(90.0, 50.0, 0.0),
    )


def test_expanded_obstacles_guide_growth_but_the_path_is_checked_on_the_real_map():
    m = scattered_map()
    for seed in range(3):
        res = solve(m, seed)
        assert res.stats["expanded_obstacles"] == 5 and res.stats["expansion_used"] == 1
        assert res.stats["direct_connection"] == 1 or res.iterations > 0
        assert_valid_path(res, m)


# ----------------------------------------------------------------------------- end to end

MAPS = ("parking_lot", "overtake", "narrow_gap")


@pytest.mark.parametrize("name", MAPS)
def test_every_solved_path_is_drivable_and_clear(name):
    m = builtin_map(name)
    problem = PlanningProblem.from_map(m)
    planner = ImprovedRRTConnect()
    solved = 0
    for seed in range(30):
        res = planner.solve(problem, np.random.default_rng(seed), BUDGET)
        assert res.status in (PlanStatus.SOLVED, PlanStatus.POSTPROCESS_FAILED,
                              PlanStatus.NO_PATH_IN_BUDGET)  # fmt: skip
        if res.success:
            solved += 1
            assert_valid_path(res, m)
        else:
            assert len(res.path) == 0 and res.message
    assert solved >= 27


def test_result_fields(parking_lot):
    res = solve(parking_lot, 0)
    assert res.planner == "improved-rrt-connect"
    start, goal = parking_lot.start, parking_lot.goal
    assert res.raw_path[0].tolist() == [start.x, start.y]
    assert res.raw_path[-1].tolist() == [goal.x, goal.y]
    assert len(res.trees) == 2 and all(isinstance(t, Tree) for t in res.trees)
    assert res.trees[0].nodes[0].tolist() == [start.x, start.y]
    assert res.trees[1].nodes[0].tolist() == [goal.x, goal.y]
    assert res.nodes == sum(len(t) for t in res.trees) == res.stats["nodes"]
    assert res.iterations == res.stats["iterations"] > 0
    for key in ("postprocess_time_s", "growth_time_s", "repair_rounds", "postprocess_attempts",
                "key_points", "control_points", "max_curvature"):  # fmt: skip
        assert key in res.stats
    assert 0 < res.stats["postprocess_time_s"] < res.planning_time_s
    # Waypoints are the control points; the first and last legs lie on the headings.
    w = res.path.waypoints
    assert w[0].tolist() == [start.x, start.y] and w[-1].tolist() == [goal.x, goal.y]
    lead = (w[1] - w[0]) / np.linalg.norm(w[1] - w[0])
    tail = (w[-1] - w[-2]) / np.linalg.norm(w[-1] - w[-2])
    np.testing.assert_allclose(lead, [math.cos(start.yaw), math.sin(start.yaw)], atol=1e-9)
    np.testing.assert_allclose(tail, [math.cos(goal.yaw), math.sin(goal.yaw)], atol=1e-9)


def test_same_seed_same_result():
    m = builtin_map("parking_lot")
    a, b = solve(m, 7), solve(m, 7)
    assert np.array_equal(a.path.samples, b.path.samples)
    assert np.array_equal(a.path.waypoints, b.path.waypoints)
    assert np.array_equal(a.raw_path, b.raw_path)
    assert all(np.array_equal(s.nodes, t.nodes) for s, t in zip(a.trees, b.trees, strict=True))
    assert a.iterations == b.iterations


@pytest.mark.parametrize("component", COMPONENTS)
def test_each_component_can_be_switched_off(component):
    m = builtin_map("parking_lot")
    for seed in range(2):
        res = solve(m, seed, disable=(component,))
        assert_valid_path(res, m)


OPEN = (0.0, 0.0, 60.0, 40.0)


@pytest.mark.parametrize(
    "goal", [(30, 20, math.pi), (30, 20, math.pi / 2), (30, 30, math.pi), (5, 20, math.pi)]
)
def test_dubins_fallback_turns_round_in_open_space(goal):
    # Goals behind or across the start heading: the tree paths' straight legs cannot
    # turn round in the room the corners leave, the Dubins fallback can.
    m = Map("open", OPEN, (), Pose(10, 20, 0), Pose(*goal))
    res = solve(m, 0)
    assert_valid_path(res, m)
    assert res.stats["dubins_fallback"] == 1.0 and "Dubins fallback" in res.message
    # A solved result says what solved it; why no tree path was used is a neutral note.
    assert res.message.startswith("solved by the Dubins fallback (")
    assert "failed" not in res.message
    assert "no tree path could be made drivable (" in res.message or (
        "the trees did not meet" in res.message
    )
    # The default rounds the Dubins word's polygon with clothoid turns: continuous
    # curvature within the sharpness bound, a little longer (a larger radius where
    # the turns need room); the paper's setting keeps the plain Dubins word.
    dubins_length = shortest_dubins(m.start, m.goal, 1.05 / KAPPA).length
    assert max_sharpness(res.path.samples, m.vehicle.wheelbase) <= 0.2 + 1e-6
    assert res.path.samples[0, 3] == 0.0 and res.path.samples[-1, 3] == 0.0
    assert dubins_length <= res.path.length <= 1.45 * dubins_length
    paper = solve(m, 0, smoothing={"curve": CurveKind.BSPLINE})
    assert_valid_path(paper, m)
    assert paper.path.length == pytest.approx(dubins_length, rel=0.01)
    without = solve(m, 0, disable=("dubins_fallback", "escalation"))
    assert without.status is PlanStatus.POSTPROCESS_FAILED


PAPER = {"smoothing": {"curve": CurveKind.BSPLINE}}
#: The fallback's search over tail and lead nodes takes seconds on a loaded machine:
#: iterations decide, not the clock.
NO_CLOCK = Budget(max_time_s=1e6)


def assert_rescued_or_honest(m: Map) -> None:
    """The default (clothoid) fallback: a valid continuous-curvature path, or an honest failure.

    Its clothoid-rounded Dubins ends need about a metre more room at each end
    than the plain arcs, which these tight parking entries do not have.
    """
    res = solve(m, 0, NO_CLOCK)
    if res.success:
        assert_valid_path(res, m)
        assert max_sharpness(res.path.samples, m.vehicle.wheelbase) <= 0.2 + 1e-6
        assert verify_path(m, res.path, max_sharpness=0.2).sharpness_ok
    else:
        assert res.status is PlanStatus.POSTPROCESS_FAILED and "Dubins" in res.message


def test_dubins_tail_rescues_a_goal_facing_into_a_parking_row():
    # A goal across the aisle's direction with no room for the tree path's last
    # corner: the fallback keeps the tree path to a node and ends in a Dubins tail.
    m = dataclasses.replace(builtin_map("parking_lot"), goal=Pose(32.973, 78.843, -1.2366))
    without = solve(m, 0, NO_CLOCK, disable=("dubins_fallback", "escalation"), **PAPER)
    assert without.status is PlanStatus.POSTPROCESS_FAILED
    res = solve(m, 0, NO_CLOCK, **PAPER)
    assert_valid_path(res, m)
    assert "Dubins fallback (tree path to" in res.message
    assert "failed" not in res.message
    assert verify_path(m, res.path).ok
    assert_rescued_or_honest(m)


def test_dubins_lead_rescues_a_start_facing_across_the_aisle():
    # The mirror image: a Dubins path from the start to a tree node, then the tree path.
    start = Pose(20.34552406761496, 26.23133404418495, 1.573087632505973)
    m = dataclasses.replace(builtin_map("parking_lot"), start=start)
    without = solve(m, 0, NO_CLOCK, disable=("dubins_fallback", "escalation"), **PAPER)
    assert without.status is PlanStatus.POSTPROCESS_FAILED
    res = solve(m, 0, NO_CLOCK, **PAPER)
    assert_valid_path(res, m)
    assert "+ tree path from" in res.message
    assert "failed" not in res.message
    assert verify_path(m, res.path).ok
    assert_rescued_or_honest(m)


def test_dubins_fallback_never_returns_a_colliding_path():
    # A wall across the loops every Dubins word would drive: the fallback must fail
    # honestly rather than return one.
    wall = Obstacle((30.0, 8.0), (50.0, 1.0))
    m = Map("walled", OPEN, (wall,), Pose(10, 20, 0), Pose(30, 20, math.pi))
    res = solve(m, 0, budget=Budget(max_iterations=3000, max_time_s=5.0))
    if res.success:
        assert_valid_path(res, m)
    else:
        assert res.path.samples.shape == (0, 5)
    assert ImprovedRRTConnect(dubins_radius_factor=1.2).config.dubins_radius_factor == 1.2
    with pytest.raises(InputError, match="dubins_radius_factor"):
        ImprovedRRTConnect(dubins_radius_factor=0.9)


def test_all_components_off_still_gives_a_valid_path():
    m = builtin_map("overtake")
    assert_valid_path(solve(m, 0, disable=COMPONENTS), m)


@pytest.mark.parametrize("name", ["overtake", "parking_lot", "narrow_gap"])
def test_degree_3_splines(name):
    m = builtin_map(name)
    for seed in range(2):
        assert_valid_path(solve(m, seed, smoothing={"degree": 3}), m)


def test_direct_connection_skips_growth():
    m = Map("empty", (0.0, 0.0, 100.0, 100.0), (), Pose(10.0, 50.0, 0.0), Pose(90.0, 50.0, 0.0))
    res = solve(m)
    assert_valid_path(res, m)
    assert res.stats["direct_connection"] == 1 and res.iterations == 0
    assert res.raw_path.tolist() == [[10.0, 50.0], [90.0, 50.0]]
    assert res.path.max_curvature == pytest.approx(0.0, abs=1e-9)


def test_direct_edge_with_incompatible_headings_is_not_taken_blindly():
    # The straight edge is free, but the goal faces back towards the start: no direct
    # connection; the trees find the way round.
    m = Map("empty", (0.0, 0.0, 100.0, 100.0), (), Pose(10.0, 30.0, 0.0), Pose(10.0, 70.0, math.pi))
    for seed in range(3):
        res = solve(m, seed)
        assert res.stats["direct_connection"] == 0
        assert_valid_path(res, m)


def test_no_path_is_proven_unreachable():
    res = solve(builtin_map("no_path"))
    assert res.status is PlanStatus.PROVEN_UNREACHABLE and len(res.path) == 0


def test_invalid_start():
    m = builtin_map("overtake")
    problem = dataclasses.replace(PlanningProblem.from_map(m), start=Pose(50.0, 44.0, 0.0))
    res = ImprovedRRTConnect().solve(problem, np.random.default_rng(0), BUDGET)
    assert res.status is PlanStatus.INVALID_START


def test_budgets_end_the_search():
    m = builtin_map("parking_lot")
    res = solve(m, 0, Budget(max_iterations=3))
    assert res.status is PlanStatus.NO_PATH_IN_BUDGET and res.iterations == 3
    assert "iteration" in res.message and len(res.trees) == 2
    res = solve(m, 0, Budget(max_time_s=1e-9))  # the safety cap: its own status
    assert res.status is PlanStatus.TIMEOUT and "safety cap" in res.message


def test_an_undrivable_goal_is_an_honest_postprocess_failure():
    # A wall 0.6 m behind the goal's rear bumper: the goal can be reached as a point but
    # not entered forwards along its heading.
    m = Map(
        "wall",
        (0.0, 0.0, 100.0, 100.0),
        (Obstacle((48.0, 50.0), (1.0, 20.0)),),
        Pose(10.0, 10.0, 0.0),
        Pose(50.0, 50.0, 0.0),
    )
    res = solve(m, 0, Budget(max_iterations=3000), max_postprocess_attempts=2)
    # The Hybrid A* escalation proves it forward only (at its resolution): the status says
    # so since session 44, as hybrid-a-star's own, and the message leads with the proof.
    assert res.status is PlanStatus.PROVEN_UNREACHABLE
    assert len(res.path) == 0 and res.message.startswith("no path: Hybrid A* (forward only)")
    # Without the strict root (the obtuse rule off) the goal tree can reach the goal
    # from the side; the post-processor then refuses the unusable approach (the tree
    # stages alone: the escalation would prove the query as above).
    res = solve(m, 0, Budget(max_iterations=3000), max_postprocess_attempts=2,
                disable=("obtuse_parent", "escalation"))  # fmt: skip
    assert res.status is PlanStatus.POSTPROCESS_FAILED
    assert len(res.path) == 0 and "goal heading leg" in res.message
    assert res.stats["postprocess_attempts"] >= 1 and len(res.raw_path) >= 2


def test_fallback_rows_read_by_interpolation_stay_clear():
    # A fuzzed map: an obstacle runs 1 mm beside the goal body, so the path may keep
    # only that much. The Dubins fallback's exact curve kept it, but its rows, read with
    # linear interpolation as verify_path and the controllers read them, clipped the
    # obstacle by 34 um; that candidate is now skipped for one whose rows stay clear.
    from rrtdrive.maps import map_from_json

    m = map_from_json({
        "name": "hug", "bounds": [0, 0, 120, 40],
        "obstacles": [{"center": [116.855, 5.548834215235355],
                       "size": [2.103842758164915, 0.2956684304707084], "yaw": 0}],
        "start": [65.834, 4.72, 0.6606636003457904], "goal": [116.5949, 4.5, 0],
    })  # fmt: skip  (the goal's nose 0.1 mm inside the bounds: touching them is refused)
    res = make_planner("improved-rrt-connect").solve(
        PlanningProblem.from_map(m), np.random.default_rng(0), Budget(max_iterations=20000)
    )
    assert res.success and "Dubins fallback" in res.message
    assert verify_path(m, res.path, max_sharpness=0.2).ok
