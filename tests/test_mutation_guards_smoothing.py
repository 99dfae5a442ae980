"""Guards found by mutation testing of the path post-processing (smoothing package).

Each test pins a behaviour of the repairs, the key polygon, the paper's polygon steps,
the edge memo, the config or the batched clothoid rows that a small change of the code
left untested. The references are independent of the code under test: shapely bodies
and line crossings, closed-form directions, three-point curvature and steering-rate
differences of the output rows, a numerically integrated clothoid, and a brute-force
pruning.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import pytest
import shapely
from hypothesis import example, given, settings
from hypothesis import strategies as st
from scipy.integrate import solve_ivp
from test_improved import densify
from test_smoothing import menger, random_free_walk

from rrtdrive.collision import CollisionChecker
from rrtdrive.maps import Map, Obstacle, builtin_map
from rrtdrive.planning.base import cached_checker
from rrtdrive.planning.smoothing import CurveKind, SmoothingConfig, make_drivable, prune
from rrtdrive.planning.smoothing.checks import CheckerView, EdgeCache
from rrtdrive.planning.smoothing.clothoid_batch import CurveBatch, sample_curves
from rrtdrive.planning.smoothing.clothoid_curve import ClothoidFitter, polygon_curve, sample_pieces
from rrtdrive.planning.smoothing.corners import (
    Corner,
    CornerKind,
    Ends,
    KeyPolygon,
    build_key_polygon,
    deflection,
    kind_of,
    turn_reach,
)
from rrtdrive.planning.smoothing.drivable import _advance_all
from rrtdrive.planning.smoothing.repair import Repairer
from rrtdrive.types import InputError, Path, Pose
from rrtdrive.vehicle import footprint_corners
from rrtdrive.verify import verify_path

Point = Sequence[float]


class Open:
    """Every edge is free."""

    def edge_free(self, a: Point, b: Point) -> bool:
        """Free."""
        return True


class Blocked:
    """Directed edges ``a -> b`` listed are blocked (their reverse is not); the rest are free."""

    def __init__(self, *edges: tuple[Point, Point]) -> None:
        self.blocked = {(tuple(map(float, a)), tuple(map(float, b))) for a, b in edges}

    def edge_free(self, a: Point, b: Point) -> bool:
        """Free unless listed."""
        return (tuple(map(float, a[:2])), tuple(map(float, b[:2]))) not in self.blocked


def _edges(checker: object) -> EdgeCache:
    """The smoother's memoised edge test over ``checker``."""
    return EdgeCache(CheckerView(checker))  # type: ignore[arg-type]


# ----------------------------------------------------------------------------- references


def _bodies_between(rows: np.ndarray, car: object, spacing: float = 0.1) -> np.ndarray:
    """Shapely bodies at the rows and at poses interpolated at most ``spacing`` apart."""
    return shapely.polygons(footprint_corners(densify(rows, spacing), car))


def _thinned(xy: np.ndarray, gap: float) -> np.ndarray:
    """The points at least ``gap`` apart, first and last kept (rounding noise grows as 1/gap^2)."""
    keep = [0]
    for i in range(1, len(xy)):
        if math.dist(xy[i], xy[keep[-1]]) >= gap:
            keep.append(i)
    if keep[-1] != len(xy) - 1:
        keep[-1] = len(xy) - 1  # the last point stands in for a kept one too close to it
    return xy[keep]


def _numerical_sharpness(xy: np.ndarray, wheelbase: float, gap: float = 0.2) -> float:
    """Largest ``|d delta / ds|`` from the three-point curvature of points >= ``gap`` apart.

    The circle through points with gaps ``p`` and ``q`` has, to first order, the
    curvature of the curve ``(q - p) / 3`` past its middle point; the rate is taken
    between those places.
    """
    pts = _thinned(xy, gap)
    gaps = np.hypot(*np.diff(pts, axis=0).T)
    where = np.cumsum(gaps)[:-1] + (gaps[1:] - gaps[:-1]) / 3.0
    delta = np.arctan(wheelbase * menger(pts))
    return float(np.max(np.abs(np.diff(delta)) / np.diff(where)))


def assert_drivable(
    rows: np.ndarray, m: Map, cfg: SmoothingConfig, sharpness: float | None
) -> None:
    """SPEC §3 items 9-10 on the output rows, measured independently of the smoother.

    Exact end positions, rows at most ``sample_spacing`` apart, end chords along the
    end headings (3 degrees), three-point curvature at most ``kappa_max``, the steering
    rate per metre of the three-point curvature at most ``sharpness`` (when given),
    and every body (shapely, poses <= 0.1 m apart) ``clearance`` off the obstacles and
    inside the bounds.
    """
    start, goal = m.start, m.goal
    assert rows[0, 0] == start.x and rows[0, 1] == start.y
    assert rows[-1, 0] == goal.x and rows[-1, 1] == goal.y
    step = np.hypot(*np.diff(rows[:, :2], axis=0).T)
    assert step.max() <= cfg.sample_spacing + 1e-9
    for (a, b), yaw in (((0, 1), start.yaw), ((-2, -1), goal.yaw)):
        chord = math.atan2(rows[b, 1] - rows[a, 1], rows[b, 0] - rows[a, 0])
        assert abs(math.remainder(chord - yaw, 2 * math.pi)) < math.radians(3.0)
    k = menger(_thinned(rows[:, :2], 0.05))
    assert np.abs(k).max() <= cfg.kappa_max + 1e-3
    if sharpness is not None:
        assert _numerical_sharpness(rows[:, :2], cfg.wheelbase) <= sharpness + 0.005
    bodies = _bodies_between(rows, m.vehicle)
    union = shapely.union_all([o.polygon() for o in m.obstacles])
    if not union.is_empty:
        assert shapely.distance(union, bodies).min() >= cfg.clearance - 1e-6
    inner = shapely.box(*m.bounds).buffer(-cfg.clearance, join_style="mitre")
    assert shapely.contains(inner, bodies).all()


# ----------------------------------------------------------------------------- end to end

#: Tree paths of the improved planner on parking_lot (seed 0, random goals), rounded to
#: centimetres; each needs repairs (tightening, moves, merges, a drop or un-pruning).
PARKING_TREE_PATHS = {
    "drop": ((94.86494471372438, 31.183145201048546, -0.4817541292647971), [
        [5.0, 6.0], [7.74, 10.18], [12.55, 11.56], [12.7, 16.56], [11.73, 21.46],
        [11.36, 26.45], [16.2, 26.43], [26.2, 26.38], [36.2, 26.33], [46.2, 26.29],
        [56.2, 26.24], [61.2, 26.22], [66.18, 26.62], [70.95, 28.11], [75.7, 29.67],
        [80.28, 27.67], [90.0, 30.01]]),
    "merge": ((86.12834961776684, 87.65370964165805, -0.17649643859940056), [
        [5.0, 6.0], [9.76, 7.53], [13.07, 11.28], [12.07, 16.18], [9.37, 20.39],
        [10.48, 25.27], [14.18, 28.63], [17.54, 32.32], [14.66, 36.41], [12.86, 38.97],
        [8.45, 41.32], [9.86, 51.22], [11.27, 61.12], [12.68, 71.02], [13.38, 75.97],
        [15.3, 80.58], [18.14, 82.98], [21.99, 83.38], [26.13, 80.58], [30.5, 78.15],
        [35.34, 76.9], [40.34, 77.02], [44.02, 80.4], [48.34, 77.88], [53.26, 76.97],
        [58.26, 77.11], [61.66, 80.78], [66.1, 78.48], [70.78, 76.71], [75.78, 76.8],
        [82.68, 84.03]]),
    "moves": ((82.6825329556721, 88.55202667099468, 1.0075425708137438), [
        [5.0, 6.0], [6.4, 10.8], [7.5, 15.68], [10.92, 19.32], [12.57, 24.04],
        [11.27, 28.87], [10.89, 33.86], [9.07, 38.51], [6.96, 43.05], [6.28, 48.0],
        [5.68, 52.96], [9.81, 55.77], [18.09, 61.39], [22.84, 62.95], [27.78, 62.17],
        [32.73, 61.47], [37.73, 61.58], [42.58, 62.79], [47.57, 62.47], [52.55, 62.8],
        [62.53, 63.47], [67.05, 61.32], [71.96, 62.22], [76.94, 62.74], [86.88, 63.77],
        [89.35, 64.03], [94.1, 65.6], [93.81, 70.59], [93.81, 75.59], [90.46, 79.29],
        [86.91, 82.82], [82.27, 80.97], [79.23, 84.94]]),
    "unprune": ((38.7769115655954, 79.16562055903405, 0.6605926729954539), [
        [5.0, 6.0], [9.01, 8.98], [8.94, 13.98], [8.69, 18.98], [10.66, 23.57],
        [14.58, 32.77], [11.44, 36.66], [12.21, 41.6], [12.35, 46.6], [12.86, 51.57],
        [15.87, 55.57], [12.81, 59.52], [13.05, 64.51], [9.55, 68.09], [10.81, 72.92],
        [11.17, 74.29], [15.3, 77.11], [19.37, 80.02], [24.37, 80.11], [28.91, 78.01],
        [33.91, 78.04]]),
}

#: The improved planner's smoothing settings on parking_lot.
PLANNER_SMOOTHING = SmoothingConfig(max_rounds=24, clearance=0.15)


def _parking_query(name: str) -> tuple[Map, np.ndarray]:
    """parking_lot with the named tree path's goal, and the tree path."""
    (gx, gy, gyaw), nodes = PARKING_TREE_PATHS[name]
    base = builtin_map("parking_lot")
    goal = Pose(gx, gy, gyaw)
    m = Map(base.name, base.bounds, base.obstacles, base.start, goal, base.vehicle)
    return m, np.array([*nodes, [gx, gy]])


@pytest.mark.parametrize("name", sorted(PARKING_TREE_PATHS))
def test_repaired_parking_paths_keep_every_guarantee(name: str) -> None:
    """Paths that need every kind of repair still meet SPEC §3 items 9-10, measured anew."""
    m, raw = _parking_query(name)
    checker = cached_checker(m)
    assert all(checker.edge_free(a, b) for a, b in zip(raw[:-1], raw[1:], strict=True))
    res = make_drivable(raw, m.start, m.goal, checker, PLANNER_SMOOTHING)
    assert res.ok, res.message
    assert res.max_curvature <= PLANNER_SMOOTHING.kappa_max
    assert res.max_sharpness <= PLANNER_SMOOTHING.max_sharpness
    assert_drivable(res.samples, m, PLANNER_SMOOTHING, PLANNER_SMOOTHING.max_sharpness)
    report = verify_path(m, Path(res.samples, raw), max_sharpness=PLANNER_SMOOTHING.max_sharpness)
    assert report.ok, report


@pytest.mark.parametrize("name", sorted(PARKING_TREE_PATHS))
def test_repaired_bspline_paths_keep_curvature_and_clearance(name: str) -> None:
    """The paper's B-spline pipeline on the same paths: curvature and exact clearance hold."""
    m, raw = _parking_query(name)
    cfg = SmoothingConfig(curve=CurveKind.BSPLINE, max_rounds=24, clearance=0.15)
    res = make_drivable(raw, m.start, m.goal, cached_checker(m), cfg)
    assert res.ok, res.message
    assert_drivable(res.samples, m, cfg, None)


@pytest.mark.parametrize("name", sorted(PARKING_TREE_PATHS))
def test_radius_steps_below_one_never_break_the_curvature_bound(name: str) -> None:
    """A configured radius step under 1 (allowed: only > 0 is required) is caught by the check.

    Such a step gives a turn tighter than ``kappa_max``; the loop must reject it, not
    return it.
    """
    m, raw = _parking_query(name)
    cfg = SmoothingConfig(max_rounds=24, clearance=0.15, radius_steps=(1.0, 0.5, 0.3))
    res = make_drivable(raw, m.start, m.goal, cached_checker(m), cfg)
    if res.ok:
        assert res.max_curvature <= cfg.kappa_max
        assert_drivable(res.samples, m, cfg, cfg.max_sharpness)
    else:
        assert res.message.startswith("post-processing failed")


# ----------------------------------------------------------------------------- repairs

#: A polygon start -> start leg -> (20, 0) -> (20, 20) -> goal leg -> goal, every
#: tree node a corner: a left turn at (20, 0) and a right turn at (20, 20).
ZIGZAG_ENDS = Ends.of(Pose(0.0, 0.0, 0.0), Pose(40.0, 20.0, 0.0))
ZIGZAG_RAW = np.array([[0.0, 0.0], [20.0, 0.0], [20.0, 20.0], [40.0, 20.0]])
ALL_NODES = SmoothingConfig(prune=False, sharp_repair=False)


def _zigzag(
    checker: object | None = None, cfg: SmoothingConfig = ALL_NODES
) -> tuple[KeyPolygon, Repairer]:
    """The zigzag's key polygon, every tree node a corner, and its repairer."""
    edges = _edges(checker or Open())
    poly = build_key_polygon(ZIGZAG_RAW, ZIGZAG_ENDS, 5.0, 5.0, edges, cfg, None)
    assert not isinstance(poly, str)
    return poly, Repairer(poly, ZIGZAG_ENDS, edges, cfg)


@pytest.mark.parametrize(
    ("direction", "expected"),
    [
        ("back", (20.0, -2.0)),  # back along the outgoing line (+y)
        ("ahead", (22.0, 0.0)),  # on along the incoming line (+x)
        ("behind", (18.0, 0.0)),  # back along the incoming line
        ("out", (20.0 + math.sqrt(2.0), -math.sqrt(2.0))),  # away from the left turn's inside
        ("in", (20.0 - math.sqrt(2.0), math.sqrt(2.0))),
    ],
)
def test_corner_moves_go_the_documented_way(direction: str, expected: tuple[float, float]) -> None:
    """MOVE_DIRECTIONS: each move of a tree corner, from its origin, as the config documents."""
    poly, rep = _zigzag()
    assert rep.move(2, direction, 2.0)
    assert poly.corners[2].point == pytest.approx(expected, abs=1e-12)
    assert rep.moves == 1


def test_heading_corners_move_only_along_their_rays() -> None:
    """The start-leg point moves on ahead along the start heading, the goal-leg point back."""
    poly, rep = _zigzag()
    assert not rep.move(1, "back", 3.0) and not rep.move(4, "ahead", 3.0)
    assert rep.move(1, "ahead", 3.0)
    assert poly.corners[1].point == pytest.approx((8.0, 0.0))  # 5 m leg + 3 m, on the ray
    assert rep.move(4, "back", 3.0)
    assert poly.corners[4].point == pytest.approx((32.0, 20.0))  # 5 m before the goal + 3 m


@pytest.mark.parametrize("blocked", ["in", "out"])
def test_a_corner_is_placed_only_where_both_legs_are_free(blocked: str) -> None:
    """Every change keeps the adjacent edges free: a blocked new leg refuses the move."""
    new = (20.0, -2.0)  # "back" by 2 m
    edge = ((5.0, 0.0), new) if blocked == "in" else (new, (20.0, 20.0))
    poly, rep = _zigzag(Blocked(edge))
    assert not rep.move(2, "back", 2.0)
    assert poly.corners[2].point.tolist() == [20.0, 0.0] and rep.moves == 0


def test_each_treatment_changes_the_corner_in_the_documented_order() -> None:
    """Clothoid corner: tighten, then the wider radius, then the moves in config order."""
    poly, rep = _zigzag()
    cfg, corner = ALL_NODES, poly.corners[2]
    r = cfg.design_radius
    assert rep.advance(2) and corner.tight and corner.radius == r
    assert rep.advance(2) and corner.radius == pytest.approx(r * cfg.radius_steps[1])
    for direction, dist in cfg.corner_moves[:4]:
        assert rep.advance(2)
        want = {"back": (20.0, -dist), "ahead": (20.0 + dist, 0.0),
                "behind": (20.0 - dist, 0.0),
                "out": (20.0 + dist / math.sqrt(2), -dist / math.sqrt(2))}[direction]  # fmt: skip
        assert corner.point == pytest.approx(want) and corner.radius == r


def test_a_bspline_corner_gets_every_radius_step_before_it_moves() -> None:
    """B-spline corner: the design radius, each wider step, then the first configured move."""
    cfg = SmoothingConfig(prune=False, sharp_repair=False, curve=CurveKind.BSPLINE,
                          radius_steps=(1.0, 1.3, 1.6))  # fmt: skip
    poly, rep = _zigzag(cfg=cfg)
    corner = poly.corners[2]
    for step in cfg.radius_steps:
        assert rep.advance(2) and corner.radius == pytest.approx(step * cfg.design_radius)
        assert corner.point.tolist() == [20.0, 0.0]
    assert rep.advance(2) and corner.point == pytest.approx((20.0, -1.5))  # ("back", 1.5)


def test_moving_behind_stops_short_of_the_previous_corner() -> None:
    """A corner moved back along its incoming line stays short of the previous corner (0.9 of
    the leg)."""
    poly, rep = _zigzag()
    assert not rep.move(2, "behind", 14.0)  # the leg from (5, 0) is 15 m: 0.9 of it is 13.5
    assert poly.corners[2].point.tolist() == [20.0, 0.0]
    assert rep.move(2, "behind", 13.0)


def _hairpin_polygon() -> tuple[KeyPolygon, Repairer]:
    """Start leg to (5, 0), a node at (20, 0), then back to (-10, 1): dropping the node
    would leave a 176-degree turn at the start-leg point."""
    ends = Ends.of(Pose(0.0, 0.0, 0.0), Pose(-30.0, 1.0, math.pi))
    raw = np.array([[0.0, 0.0], [20.0, 0.0], [-10.0, 1.0], [-30.0, 1.0]])
    edges = _edges(Open())
    poly = build_key_polygon(raw, ends, 5.0, 5.0, edges, ALL_NODES, None)
    assert not isinstance(poly, str)
    return poly, Repairer(poly, ends, edges, ALL_NODES)


def test_a_drop_that_leaves_a_hairpin_at_the_start_leg_is_refused() -> None:
    """drop(): refused when a neighbour would turn more than drop_hairpin_turn."""
    poly, rep = _hairpin_polygon()
    p = poly.points()
    assert deflection(p[0], p[1], p[3]) > ALL_NODES.drop_hairpin_turn  # the reference
    assert not rep.drop(2) and len(poly) == 6 and rep.drops == 0


def _goal_side_polygon() -> tuple[KeyPolygon, Repairer]:
    """Tree nodes (30, 10) and (25, 22) pruned away between (20, 0) and the goal-leg point."""
    ends = Ends.of(Pose(0.0, 0.0, 0.0), Pose(10.0, 20.0, math.pi))
    aug = np.array([[0, 0], [5, 0], [20, 0], [30, 10], [25, 22], [15, 20], [10, 20]], float)
    n = len(aug)
    kinds = {0: CornerKind.START, n - 1: CornerKind.GOAL}
    corners = [Corner.at(aug[k], kinds.get(k) or kind_of(k, n), k) for k in (0, 1, 2, 5, 6)]
    poly = KeyPolygon(corners, aug, 5.0, 5.0)
    return poly, Repairer(poly, ends, _edges(Open()), SmoothingConfig())


def test_unpruning_next_to_the_goal_keeps_the_goal_leg_point() -> None:
    """Putting tree nodes back never loses the point on the goal's heading ray."""
    poly, rep = _goal_side_polygon()
    assert rep.unprune(3) and rep.unprunes == 1
    assert [c.kind for c in poly.corners[-2:]] == [CornerKind.GOAL_LEG, CornerKind.GOAL]
    assert poly.corners[-2].point.tolist() == [15.0, 20.0]
    # A turn of more than unprune_turn (100 degrees) at (20, 0) is avoided via (25, 22).
    assert [c.point.tolist() for c in poly.corners[2:4]] == [[20.0, 0.0], [25.0, 22.0]]


def test_an_exhausted_corner_is_unpruned_before_it_is_dropped() -> None:
    """advance(): after the last move, the tree nodes are put back before a drop is tried."""
    poly, rep = _goal_side_polygon()
    rep.cfg = SmoothingConfig(corner_moves=(), radius_steps=(1.0,))
    rep.corners[2].tight = True
    rep.corners[2].attempt = 1
    assert rep.advance(2) and rep.unprunes == 1 and rep.drops == 0


def test_a_too_short_leg_drops_a_gentle_corner_rather_than_unpruning_it() -> None:
    """unprune_or_drop(): tree nodes are put back only around a hairpin (a turn above
    unprune_hairpin_turn); the 104-degree corner at (20, 0) is dropped instead."""
    poly, rep = _goal_side_polygon()
    p = poly.points()
    assert deflection(p[1], p[2], p[3]) < SmoothingConfig().unprune_hairpin_turn
    assert rep.unprune_or_drop(2)
    assert (rep.drops, rep.unprunes) == (1, 0)
    assert [c.point.tolist() for c in poly.corners] == [[0, 0], [5, 0], [15, 20], [10, 20]]


def _merge_polygon(checker: object) -> tuple[KeyPolygon, Repairer]:
    """Two close corners (10, 0) and (12, 3) between long legs; the goal far up."""
    ends = Ends.of(Pose(0.0, 0.0, 0.0), Pose(30.0, 40.0, 0.0))
    raw = np.array([[0.0, 0.0], [10.0, 0.0], [12.0, 3.0], [14.0, 35.0], [30.0, 40.0]])
    edges = _edges(checker)
    poly = build_key_polygon(raw, ends, 5.0, 5.0, edges, ALL_NODES, None)
    assert not isinstance(poly, str)
    return poly, Repairer(poly, ends, edges, ALL_NODES)


def test_merging_two_corners_puts_one_at_the_crossing_of_the_outer_legs() -> None:
    """merge(): the new corner is where the outer legs' lines cross (shapely reference)."""
    poly, rep = _merge_polygon(Open())
    p = [c.point.copy() for c in poly.corners]
    # Lines through the outer legs, long enough to meet.
    la = shapely.LineString([p[1] - 100 * (p[2] - p[1]), p[1] + 100 * (p[2] - p[1])])
    lb = shapely.LineString([p[3] - 100 * (p[4] - p[3]), p[3] + 100 * (p[4] - p[3])])
    crossing = la.intersection(lb)
    assert rep.merge(2) and rep.merges == 1 and len(poly) == len(p) - 1
    assert poly.corners[2].point == pytest.approx((crossing.x, crossing.y), abs=1e-9)
    assert poly.corners[2].kind is CornerKind.NODE


def test_merging_into_the_start_leg_keeps_a_start_leg_point_on_the_start_ray() -> None:
    """A merge of the start-leg point keeps its kind (so later moves keep it on the ray)."""
    poly, rep = _merge_polygon(Open())
    assert rep.merge(1)
    corner = poly.corners[1]
    assert corner.kind is CornerKind.START_LEG
    assert corner.point[1] == pytest.approx(0.0, abs=1e-12) and corner.point[0] > 0.0


def test_a_merge_whose_outgoing_leg_is_blocked_is_refused() -> None:
    """merge(): both new legs must be free, the one after the crossing too."""
    poly, rep = _merge_polygon(Open())
    assert rep.merge(2)
    y = tuple(poly.corners[2].point)
    poly, rep = _merge_polygon(Blocked((y, (14.0, 35.0))))
    assert not rep.merge(2) and len(poly) == 7 and rep.merges == 0


def test_a_grown_goal_leg_stays_on_the_goal_ray_and_fits_its_turn() -> None:
    """grow_heading_leg(): the goal-leg point moves back along the goal heading, far enough
    for its turn (and the end gap), and twice at most."""
    ends = Ends.of(Pose(0.0, 0.0, 0.0), Pose(40.0, 30.0, math.pi / 2))
    raw = np.array([[0.0, 0.0], [20.0, 0.0], [20.0, 20.0], [40.0, 30.0]])
    edges = _edges(Open())
    poly = build_key_polygon(raw, ends, 5.0, 5.0, edges, ALL_NODES, None)
    assert not isinstance(poly, str)
    rep = Repairer(poly, ends, edges, ALL_NODES)
    p = poly.points()
    u_in = (p[4] - p[3]) / np.hypot(*(p[4] - p[3]))
    need = turn_reach(ALL_NODES, p[4], tuple(u_in), (0.0, 1.0), ALL_NODES.design_radius)
    assert need + ALL_NODES.end_gap > 5.0  # the 5 m goal leg is too short for its turn
    for _ in range(2):
        assert rep.grow_heading_leg(4)
        x, y = poly.corners[4].point
        assert x == pytest.approx(40.0, abs=1e-12) and 30.0 - y >= need + ALL_NODES.end_gap
        assert poly.corners[4].origin.tolist() == [x, y]
    assert not rep.grow_heading_leg(4)


@pytest.mark.parametrize(("end_gap", "fits"), [(2.0, False), (0.2, True)])
def test_the_goal_leg_fits_its_turn_only_with_the_end_gap(end_gap: float, fits: bool) -> None:
    """A 6.5 m goal leg whose turn needs 6.27 m (integrated clothoid) fits with a 0.2 m end
    gap, not with 2 m: the straight kept before the goal counts on the goal leg too."""
    cfg = SmoothingConfig(prune=False, sharp_repair=False, end_gap=end_gap)
    ends = Ends.of(Pose(0.0, 0.0, 0.0), Pose(40.0, 30.0, math.pi / 2))
    raw = np.array([[0.0, 0.0], [20.0, 0.0], [20.0, 20.0], [40.0, 30.0]])
    edges = _edges(Open())
    poly = build_key_polygon(raw, ends, 6.5, 6.5, edges, cfg, None)
    assert not isinstance(poly, str)
    p = poly.points()
    need = _reference_tangent(deflection(p[3], p[4], p[5]), 1.0 / cfg.design_radius,
                              cfg.tightest_sigma)  # fmt: skip
    assert need < 6.5 < need + 2.0 and need + 0.2 < 6.5
    assert Repairer(poly, ends, edges, cfg)._leg_fits(4) is fits


def test_a_failed_stretch_leaves_the_polygon_as_it_was() -> None:
    """stretch(): a shift that does not make the leg fit is undone."""
    # The 2 m leg between (20, 0) and (20, 2) can never fit two design-radius turns
    # within 0.9 of the neighbouring legs.
    ends = Ends.of(Pose(0.0, 0.0, 0.0), Pose(0.0, 2.0, math.pi))
    raw = np.array([[0.0, 0.0], [20.0, 0.0], [20.0, 2.0], [0.0, 2.0]])
    edges = _edges(Open())
    poly = build_key_polygon(raw, ends, 5.0, 5.0, edges, ALL_NODES, None)
    assert not isinstance(poly, str)
    rep = Repairer(poly, ends, edges, ALL_NODES)
    before = [c.point.copy() for c in poly.corners]
    assert not rep.stretch(2)
    assert all(np.array_equal(a, c.point) for a, c in zip(before, poly.corners, strict=True))


# ----------------------------------------------------------------------------- pruning

LIMIT = math.radians(100.0)


def test_a_turn_of_exactly_max_turn_is_allowed() -> None:
    """prune(max_turn): a jump may turn the path by max_turn itself (not by more)."""
    pts = np.array([[0.0, 0.0], [5.0, 0.0], [10.0, 10.0]])  # 0 -> 2 turns exactly 45 degrees
    assert prune(pts, Open(), max_turn=math.pi / 4, start_heading=(1.0, 0.0)).tolist() == [0, 2]


def test_landing_on_a_kept_node_counts_the_turn_on_to_the_next_kept_node() -> None:
    """prune(max_turn): the jump 0 -> 2 would turn 174 degrees at kept node 2 (on to node 3),
    so node 1 stays."""
    pts = np.array([[0.0, 0.0], [12.0, -4.0], [10.0, 0.0], [0.0, 1.0]])
    got = prune(pts, Open(), keep=(2,), max_turn=LIMIT, start_heading=(1.0, 0.0))
    assert got.tolist() == [0, 1, 2, 3]


def test_the_end_heading_limits_the_last_jump() -> None:
    """prune(max_turn): arriving at the last node against end_heading counts as a turn."""
    pts = np.array([[0.0, 0.0], [10.0, -3.0], [10.0, 0.0]])
    got = prune(pts, Open(), max_turn=LIMIT, start_heading=(1.0, 0.0), end_heading=(-1.0, 0.0))
    assert got.tolist() == [0, 1, 2]


def test_without_a_jump_within_the_limit_the_farthest_free_one_is_taken() -> None:
    """prune(max_turn): every jump turns back (169 and 180 degrees): the farthest is taken."""
    pts = np.array([[0.0, 0.0], [-5.0, 1.0], [-10.0, 0.0]])
    got = prune(pts, Open(), max_turn=math.pi / 4, start_heading=(1.0, 0.0))
    assert got.tolist() == [0, 2]


def test_the_turn_limit_is_measured_from_the_last_jump_not_the_start_heading() -> None:
    """prune(max_turn): after 0 -> 1 (north), 1 -> 3 turns 135 degrees and is refused,
    although it is only 45 degrees off the start heading."""
    pts = np.array([[0.0, 0.0], [0.0, 10.0], [5.0, 12.0], [10.0, 0.0]])
    checker = Blocked(((0.0, 0.0), (10.0, 0.0)), ((0.0, 0.0), (5.0, 12.0)))
    got = prune(pts, checker, max_turn=LIMIT, start_heading=(1.0, 0.0))
    assert got.tolist() == [0, 1, 2, 3]


def _farthest_free_reference(pts: np.ndarray, free: object) -> list[int]:
    """The paper's pruning by brute force: from each kept node, the farthest free later node."""
    out, i = [0], 0
    while i < len(pts) - 1:
        i = max(j for j in range(i + 1, len(pts)) if free(pts[i], pts[j]))  # type: ignore[operator]
        out.append(i)
    return out


@pytest.mark.parametrize("seed", range(6))
def test_the_obstacle_screen_never_changes_the_pruning(seed: int) -> None:
    """prune() with the edge cache's screen (proven collisions skipped) = brute force without it."""
    checker = cached_checker(builtin_map("parking_lot"))
    pts = random_free_walk(checker, np.random.default_rng(seed), 25)
    edges = _edges(checker)
    assert edges.blocked_from is not None  # the screen is on
    assert prune(pts, edges).tolist() == _farthest_free_reference(pts, checker.edge_free)


def test_a_node_behind_an_obstacle_does_not_hide_the_free_one_after_it() -> None:
    """prune() with the screen: node 2's line crosses the box, node 3 is free and is taken."""
    m = Map("box", (0.0, 0.0, 100.0, 100.0), (Obstacle((40.0, 35.0), (2.0, 2.0)),),
            Pose(30.0, 30.0, 0.0), Pose(50.0, 27.0, 0.0))  # fmt: skip
    checker = CollisionChecker.for_map(m)
    pts = np.array([[30.0, 30.0], [35.0, 25.0], [50.0, 40.0], [50.0, 27.0]])
    assert shapely.LineString(pts[[0, 2]]).intersects(m.obstacles[0].polygon())
    assert prune(pts, _edges(checker)).tolist() == _farthest_free_reference(pts, checker.edge_free)


# ----------------------------------------------------------------------------- edge cache

PARKING = builtin_map("parking_lot")
PARKING_UNION = shapely.union_all([o.polygon() for o in PARKING.obstacles])


@settings(max_examples=40, deadline=None)
@given(
    st.tuples(st.floats(0.0, 100.0), st.floats(0.0, 100.0)),
    st.floats(-20.0, 20.0).filter(lambda d: abs(d) > 1e-3),
    st.lists(st.tuples(st.floats(0.0, 100.0), st.floats(0.0, 100.0)), min_size=1, max_size=5),
)
def test_the_screen_is_shapely_line_intersection(
    a: tuple[float, float], dy: float, bs: list[tuple[float, float]]
) -> None:
    """blocked_from(a, bs): True exactly where the centre line a -> b meets an obstacle,
    for every start (one cache asked from two starts with the same x and the same ends)."""
    edges = _edges(cached_checker(PARKING))
    ends = np.array(bs)
    for start in (np.array(a), np.array([a[0], a[1] + dy])):
        want = [PARKING_UNION.intersects(shapely.LineString([start, b])) for b in ends]
        assert edges.blocked_from(start, ends).tolist() == want


def test_the_edge_memo_tells_edges_apart_by_every_coordinate_and_direction() -> None:
    """EdgeCache answers each directed edge as its checker does, asked in any order."""
    a, b, c = (0.0, 0.0), (10.0, 0.0), (0.0, 3.0)
    view = CheckerView(Blocked((a, b), (c, a)))  # type: ignore[arg-type]
    queries = [(a, b), (b, a), (c, b), (a, c), (c, a), (b, c)]
    first = EdgeCache(view)
    second = EdgeCache(view)  # shares the view's answers
    for cache in (first, second):
        assert [cache.edge_free(p, q) for p, q in queries] == [
            False, True, True, True, False, True,
        ]  # fmt: skip


def test_a_bare_path_checker_gets_the_configured_clearance() -> None:
    """A checker with only edge_free and path_free: the body still keeps ``clearance`` (shapely)."""
    real = cached_checker(PARKING)

    class Bare:
        """A motion validator without the batch pose test or the obstacles."""

        edge_free = staticmethod(real.edge_free)
        path_free = staticmethod(real.path_free)

    cfg = SmoothingConfig(max_rounds=24, clearance=0.5)
    for name in sorted(PARKING_TREE_PATHS):
        m, raw = _parking_query(name)
        res = make_drivable(raw, m.start, m.goal, Bare(), cfg)  # type: ignore[arg-type]
        if res.ok:
            assert_drivable(res.samples, m, cfg, cfg.max_sharpness)


# ----------------------------------------------------------------------------- the loop

#: A random free walk on parking_lot whose paper pruning leaves turns too close for the
#: car; the hairpin-avoiding pruning (unprune_turn) makes it drivable.
SECOND_TRY_RAW = np.array([
    [26.1, 61.42], [27.18, 58.06], [25.35, 54.75], [25.87, 58.71], [21.53, 54.34],
    [14.75, 56.62], [10.47, 56.5], [10.01, 48.32], [5.56, 44.28],
])  # fmt: skip
SECOND_TRY = Map(
    PARKING.name, PARKING.bounds, PARKING.obstacles,
    Pose(26.1, 61.42, -1.5279), Pose(5.56, 44.28, -2.9329), PARKING.vehicle,
)  # fmt: skip


def _counting_builds(monkeypatch: pytest.MonkeyPatch) -> list[int]:
    """Count the curve fits (one per fit-check-repair round), independently of ``rounds``."""
    calls: list[int] = []
    real = ClothoidFitter.build

    def build(self: ClothoidFitter, corners: Sequence[Corner]) -> object:
        calls.append(len(corners))
        return real(self, corners)

    monkeypatch.setattr(ClothoidFitter, "build", build)
    return calls


def test_the_hairpin_avoiding_pruning_gets_its_own_attempt(monkeypatch: pytest.MonkeyPatch) -> None:
    """When the paper's pruning cannot be made drivable, the second pruning is tried, and
    ``rounds`` counts the fits of both attempts."""
    checker = cached_checker(SECOND_TRY)
    m, raw = SECOND_TRY, SECOND_TRY_RAW
    # With a turn limit of 180 degrees the second pruning is the paper's: both fail.
    same = make_drivable(raw, m.start, m.goal, checker, SmoothingConfig(unprune_turn=math.pi))
    assert not same.ok and same.message.startswith("post-processing failed")
    builds = _counting_builds(monkeypatch)
    res = make_drivable(raw, m.start, m.goal, checker, SmoothingConfig())
    assert res.ok, res.message
    assert res.rounds == len(builds) > SmoothingConfig().max_rounds // 2
    assert_drivable(res.samples, m, SmoothingConfig(), 0.2)


def test_each_attempt_keeps_to_max_rounds(monkeypatch: pytest.MonkeyPatch) -> None:
    """max_rounds bounds the fits of each attempt; ``rounds`` reports them all."""
    builds = _counting_builds(monkeypatch)
    cfg = SmoothingConfig(max_rounds=3)
    res = make_drivable(SECOND_TRY_RAW, SECOND_TRY.start, SECOND_TRY.goal,
                        cached_checker(SECOND_TRY), cfg)  # fmt: skip
    assert not res.ok and "within 3 repair rounds" in res.message
    assert res.rounds == len(builds) == 2 * cfg.max_rounds


@pytest.mark.parametrize("ahead", [6.0, 8.0])
def test_a_goal_a_few_metres_straight_ahead_is_a_straight_path(ahead: float) -> None:
    """Heading legs shorter than half the distance: a goal straight ahead closer than two
    heading legs is reached along the straight line, kappa 0 everywhere."""
    m = Map("open", (-20.0, -20.0, 40.0, 20.0), (), Pose(0.0, 0.0, 0.0), Pose(ahead, 0.0, 0.0))
    res = make_drivable(np.array([[0.0, 0.0], [ahead, 0.0]]), m.start, m.goal,
                        CollisionChecker.for_map(m))  # fmt: skip
    assert res.ok, res.message
    assert np.abs(res.samples[:, 1]).max() < 1e-9 and np.all(np.diff(res.samples[:, 0]) > 0)
    assert_drivable(res.samples, m, SmoothingConfig(), 0.2)


def test_every_bad_corner_gets_its_own_next_treatment() -> None:
    """The loop's repairs of several bad corners: each of them is treated (here both are
    dropped), never a neighbour whose index shifted after a drop."""
    cfg = SmoothingConfig(prune=False, sharp_repair=False, corner_moves=(), radius_steps=(1.0,))
    poly, rep = _zigzag(cfg=cfg)
    for c in (2, 3):
        rep.corners[c].tight, rep.corners[c].attempt = True, 1  # fillets and moves used up
    assert _advance_all(rep, [2, 3]) is None
    assert rep.drops == 2
    assert [c.point.tolist() for c in poly.corners] == [[0, 0], [5, 0], [35, 20], [40, 20]]
    assert not poly.corners[2].tight  # the goal-leg point was not treated


def test_a_tree_path_of_one_point_is_an_honest_failure() -> None:
    """make_drivable needs a path from the start to the goal: one point is refused."""
    m = builtin_map("overtake")
    res = make_drivable(np.array([[m.start.x, m.start.y]]), m.start, m.goal, cached_checker(m))
    assert not res.ok and len(res.samples) == 0
    assert "at least two points" in res.message


# ----------------------------------------------------------------------------- corners


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.floats(-50, 50), st.floats(-50, 50)), min_size=3, max_size=3))
@example([(0.0, 0.0), (3e-4, 4e-4), (1.0, 4e-4)])  # a leg of half a millimetre
def test_deflection_is_the_unsigned_angle_between_the_legs(pts: list[tuple[float, float]]) -> None:
    """deflection(a, b, c): the angle between b - a and c - b in [0, pi], for left and right
    turns, however short a leg (down to a micrometre)."""
    a, b, c = (np.array(p) for p in pts)
    u, v = b - a, c - b
    if min(np.hypot(*u), np.hypot(*v)) < 1e-6:
        return
    cos = float(u @ v / (np.hypot(*u) * np.hypot(*v)))
    want = math.acos(min(1.0, max(-1.0, cos)))
    assert deflection(a, b, c) == pytest.approx(want, abs=1e-6)
    assert deflection(c, b, a) == pytest.approx(want, abs=1e-6)  # the mirror turns the other way


def _reference_tangent(theta: float, kappa: float, sigma: float) -> float:
    """Tangent length of a symmetric clothoid-arc-clothoid turn, by integrating its curvature.

    Started at (0, 0) heading along x, the turn ends on the outgoing leg: ``y_end = T sin(theta)``.
    """
    lc = kappa / sigma
    total = 2.0 * lc + (theta - kappa * lc) / kappa

    def rhs(s: float, z: np.ndarray) -> list[float]:
        q = min(s, total - s)
        return [math.cos(z[2]), math.sin(z[2]), min(sigma * q, kappa)]

    sol = solve_ivp(rhs, (0.0, total), [0.0, 0.0, 0.0], rtol=1e-10, atol=1e-12, max_step=0.05)
    return float(sol.y[1, -1] / math.sin(theta))


def test_turn_reach_is_the_clothoid_turns_tangent_for_each_radius() -> None:
    """turn_reach(): the tangent length of the tightest turn of the corner's own radius, with
    one memo shared by several radii and both turn directions."""
    cfg = SmoothingConfig()
    memo: dict[tuple[float, float], float] = {}
    for theta in (0.9, 2.0):
        for radius in (cfg.design_radius, 1.6 * cfg.design_radius, 0.0):
            r = radius or cfg.design_radius  # a plain corner gets the design radius
            want = _reference_tangent(theta, 1.0 / r, cfg.tightest_sigma)
            for side in (1.0, -1.0):
                u_out = (math.cos(side * theta), math.sin(side * theta))
                got = turn_reach(cfg, np.zeros(2), (1.0, 0.0), u_out, radius, memo)
                assert got == pytest.approx(want, abs=1e-6)


def test_heading_reach_is_the_turn_at_each_heading_leg_point() -> None:
    """KeyPolygon.heading_reach(): the tangent lengths of the turns at the start-leg and the
    goal-leg points (what the heading legs must be lengthened to)."""
    cfg = SmoothingConfig()
    ends = Ends.of(Pose(0.0, 0.0, 0.0), Pose(40.0, 30.0, math.pi / 2))
    raw = np.array([[0.0, 0.0], [20.0, 10.0], [30.0, 20.0], [40.0, 30.0]])
    poly = build_key_polygon(raw, ends, 5.0, 5.0, _edges(Open()), ALL_NODES, None)
    assert not isinstance(poly, str)
    p = poly.points()
    want = [
        _reference_tangent(deflection(p[c - 1], p[c], p[c + 1]), 1.0 / cfg.design_radius,
                           cfg.tightest_sigma)  # fmt: skip
        for c in (1, len(p) - 2)
    ]
    assert poly.heading_reach(cfg.design_radius, cfg) == pytest.approx(want, abs=1e-6)


def test_the_goal_heading_leg_is_tested_in_driving_order() -> None:
    """The goal leg is driven towards the goal: an edge test blocked that way blocks it."""
    ends = Ends.of(Pose(0.0, 0.0, 0.0), Pose(30.0, 0.0, 0.0))
    raw = np.array([[0.0, 0.0], [30.0, 0.0]])
    blocked = Blocked(((25.0, 0.0), (30.0, 0.0)))  # the reverse, goal -> leg point, is free
    got = build_key_polygon(raw, ends, 5.0, 5.0, _edges(blocked), SmoothingConfig(), None)
    assert isinstance(got, str) and "goal heading leg" in got


# ----------------------------------------------------------------------------- config

OVERTAKE_RAW = np.array([[5.0, 44.0], [30.0, 44.0], [42.0, 48.0], [60.0, 48.0], [92.0, 44.0]])


@pytest.mark.parametrize(
    "changes",
    [
        {"kappa_safety": 1.0},  # "must lie in [0.01, 1]"
        {"min_sharpness": 0.2, "max_sharpness": 0.2},  # "must be <= max_sharpness"
        {"end_gap": 0.0},  # "must be >= 0"
        {"hairpin_turn": math.pi, "drop_hairpin_turn": math.pi},  # "must lie in (0, pi]"
        {"curve": CurveKind.BSPLINE, "fillet_max_angle": math.pi / 2},  # "(0, pi/2]"
    ],
)
def test_the_closed_ends_of_the_documented_ranges_are_accepted_and_smooth(
    changes: dict[str, object],
) -> None:
    """The validated ranges include their documented ends; such a config still smooths a
    path within the curvature bound and the sharpness bound."""
    cfg = SmoothingConfig(**changes)  # type: ignore[arg-type]
    m = builtin_map("overtake")
    res = make_drivable(OVERTAKE_RAW, m.start, m.goal, cached_checker(m), cfg)
    assert res.ok, res.message
    assert_drivable(res.samples, m, cfg, cfg.max_sharpness if cfg.clothoid else None)


@pytest.mark.parametrize("spacing", [0.0, -0.1])
def test_a_check_spacing_that_is_not_positive_is_refused(spacing: float) -> None:
    """check_spacing is the gap of the exact body test: 0 or less names the field."""
    with pytest.raises(InputError, match="smoothing.check_spacing"):
        SmoothingConfig(check_spacing=spacing)


# ----------------------------------------------------------------------------- batched rows


@settings(max_examples=30, deadline=None)
@given(
    st.lists(st.tuples(st.floats(8.0, 30.0), st.floats(-2.9, 2.9)), min_size=1, max_size=4),
    st.floats(-math.pi, math.pi),
    st.sampled_from([0.1, 0.25, 0.37]),
)
def test_batched_rows_are_a_curve_with_their_own_heading_and_curvature(
    legs: list[tuple[float, float]], yaw0: float, spacing: float
) -> None:
    """sample_curves(): each curve starts and ends on its polygon with the legs' headings and
    kappa 0; between rows the chord follows the mean heading and the heading turns by the
    mean curvature times the arc (checked on the rows alone, second order in the gap)."""
    pts, yaw = [np.zeros(2)], yaw0
    for length, turn in legs:
        pts.append(pts[-1] + length * np.array([math.cos(yaw), math.sin(yaw)]))
        yaw += turn
    pts.append(pts[-1] + 30.0 * np.array([math.cos(yaw), math.sin(yaw)]))

    pieces = polygon_curve(np.array(pts), 1.0 / 6.5, 0.07)
    if pieces is None:  # legs too short for the turns
        return
    rows = sample_curves([pieces, pieces[::-1][:1]], spacing)[0]
    assert rows[0, :2] == pytest.approx(pts[0], abs=1e-9)
    assert rows[-1, :2] == pytest.approx(pts[-1], abs=1e-6)
    assert math.remainder(rows[0, 2] - yaw0, 2 * math.pi) == pytest.approx(0.0, abs=1e-12)
    assert math.remainder(rows[-1, 2] - yaw, 2 * math.pi) == pytest.approx(0.0, abs=1e-9)
    assert rows[0, 3] == 0.0 and abs(rows[-1, 3]) < 1e-12
    d = np.diff(rows[:, :2], axis=0)
    h = np.hypot(*d.T)
    assert h.max() <= spacing + 1e-9 and np.abs(rows[:, 3]).max() <= 1.0 / 6.5 + 1e-12
    turn = np.remainder(np.diff(rows[:, 2]) + math.pi, 2 * math.pi) - math.pi
    chord = np.arctan2(d[:, 1], d[:, 0])
    off = np.remainder(chord - rows[:-1, 2] - 0.5 * turn + math.pi, 2 * math.pi) - math.pi
    # Curvature is piecewise linear in arc length (sharpness 0.07 rad/m^2 on a clothoid,
    # constant on an arc), so the trapezoid rule misses at most sharpness * t (h - t) / 2
    # per kink at t in a gap h: sharpness h^2 / 8, and a gap can hold two kinks (a short
    # arc). A fixed 1e-3 failed at h = 0.37 m (0.0021) on examples another test order drew.
    bound = 0.07 * h.max() ** 2 / 4 + 1e-6
    assert np.abs(off).max() < bound
    assert np.abs(turn - 0.5 * (rows[:-1, 3] + rows[1:, 3]) * h).max() < bound
    batch = CurveBatch([pieces], spacing)
    pick = np.arange(0, len(rows), 7)
    assert np.array_equal(batch.rows(pick), rows[pick])


@pytest.mark.parametrize("turn", [5e-7, -3e-8])
def test_a_corner_of_a_microradian_is_sampled_as_the_single_curve_sampler_does(
    turn: float,
) -> None:
    """The batch's contract: the same floats as sample_pieces, also for a nearly straight
    corner (a turn piece of a few micrometres that is still a turn)."""
    pts = np.array([[0.0, 0.0], [20.0 * math.cos(0.3), 20.0 * math.sin(0.3)]])
    pts = np.vstack([pts, pts[1] + 30.0 * np.array([math.cos(0.3 + turn), math.sin(0.3 + turn)])])
    pieces = polygon_curve(pts, 1.0 / 6.5, 0.07)
    assert pieces is not None and any(p.turn is not None for p in pieces)
    for spacing in (0.25, 0.001):
        want, _ = sample_pieces(pieces, spacing)
        assert sample_curves([pieces], spacing)[0].tobytes() == want.tobytes()


# ----------------------------------------------------------------------------- a bug found


@pytest.mark.parametrize(
    ("field", "bad"),
    [("clearance", -2.0), ("clearance", math.nan), ("prune", "no"), ("supplement", 1)],
)
def test_values_no_body_or_switch_can_take_are_refused(field: str, bad: object) -> None:
    """SmoothingConfig names the field of a value no body can keep or no switch can be.

    Found by this audit: with clearance=-2 make_drivable returned ok=True for a parking
    lot turn-in whose bodies overlapped parked cars by up to 4.6 m2 (the exact pose test
    calls a pose 2 m inside a car free), and prune="no" switched pruning on.
    """
    with pytest.raises(InputError, match=f"^smoothing.{field}: "):
        SmoothingConfig(**{field: bad})
