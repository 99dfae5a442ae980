"""The heading lattice that guides a hard Hybrid A* query (:mod:`rrtdrive.planning.hybrid.lattice`).

Its states against shapely's body test, its moves against the arc geometry, its
costs against what a car can drive, and the search it guides: unchanged where the
search answers before ``lattice_after``, fewer expansions where it turns round.
"""

from __future__ import annotations

import math
import time

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st
from test_hybrid_abreast import _against_row

from rrtdrive.collision import CollisionChecker
from rrtdrive.maps import Map, Obstacle, builtin_map
from rrtdrive.planning import PlanningProblem, make_planner
from rrtdrive.planning.hybrid.config import HybridConfig
from rrtdrive.planning.hybrid.heuristic import FreeCellGraph, Heuristic, HolonomicField
from rrtdrive.planning.hybrid.lattice import HeadingLattice, _move, guided
from rrtdrive.types import Budget, InputError, Pose, VehicleParams
from rrtdrive.verify import verify_path

CAR = VehicleParams()
RADIUS = 1.02 / CAR.kappa_max


def _lattice(m: Map, reverse: bool = True, **kw: float) -> HeadingLattice:
    return HeadingLattice.build(
        CollisionChecker.for_map(m), m.bounds, RADIUS, reverse, 2.0, 5.0, **kw
    )


def _body(x: float, y: float, yaw: float) -> shapely.Polygon:
    """The car's body at a rear-axle pose, by shapely (independent of the checker)."""
    back, front, half = -CAR.rear_overhang, CAR.length - CAR.rear_overhang, CAR.width / 2
    c, s = math.cos(yaw), math.sin(yaw)
    return shapely.Polygon(
        [(x + c * u - s * v, y + s * u + c * v)
         for u, v in ((back, -half), (front, -half), (front, half), (back, half))]
    )  # fmt: skip


WALLED = Map(
    "walled",
    (0.0, 0.0, 30.0, 12.0),
    (Obstacle((15.0, 6.0), (1.0, 12.0), 0.0), Obstacle((8.0, 2.0), (3.0, 1.5), 0.6)),
    Pose(3.0, 6.0, 0.0),
    Pose(26.0, 6.0, 0.0),
)


@settings(max_examples=60, deadline=None)
@given(st.integers(min_value=0, max_value=24 * 60 * 16 - 1))
def test_a_state_is_free_where_shapely_finds_the_body_clear(state: int) -> None:
    lat = _lattice(WALLED)
    nx, ny = lat.shape
    k = lat.headings
    i, rest = divmod(state % (nx * ny * k), ny * k)
    j, h = divmod(rest, k)
    x, y = lat.origin[0] + (i + 0.5) * lat.cell, lat.origin[1] + (j + 0.5) * lat.cell
    body = _body(x, y, 2 * math.pi * h / k)
    x0, y0, x1, y1 = WALLED.bounds
    inside = shapely.box(x0, y0, x1, y1).contains(body)
    hits = any(body.intersects(o.polygon()) for o in WALLED.obstacles)
    assert bool(lat.free[(i * ny + j) * k + h]) == (inside and not hits)


def test_every_move_ends_in_the_cell_and_heading_of_its_state() -> None:
    lat = _lattice(WALLED, reverse=True)
    nx, ny = lat.shape
    k, gears = lat.headings, lat.gears
    coo = lat.forward.tocoo()
    src, dst = coo.row // gears, coo.col // gears
    i, rest = np.divmod(src, ny * k)
    j, h = np.divmod(rest, k)
    poses = np.column_stack(
        [lat.origin[0] + (i + 0.5) * lat.cell, lat.origin[1] + (j + 0.5) * lat.cell,
         2 * math.pi * h / k]
    )  # fmt: skip
    di, drest = np.divmod(dst, ny * k)
    dj, dh = np.divmod(drest, k)
    arc = RADIUS * 2 * math.pi / k
    matched = np.zeros(len(src), dtype=bool)
    for gear in (1, -1):
        for steer in (-1, 0, 1):
            end, _ = _move(poses, gear, steer, RADIUS, arc)
            same = (
                (np.floor((end[:, 0] - lat.origin[0]) / lat.cell) == di)
                & (np.floor((end[:, 1] - lat.origin[1]) / lat.cell) == dj)
                & ((h + gear * steer) % k == dh)
            )
            matched |= same
    assert matched.all()
    assert lat.free[src].all() and lat.free[dst].all()


def test_costs_count_length_reverse_and_cusps() -> None:
    open_map = Map("open", (0.0, 0.0, 60.0, 30.0), (), Pose(5, 15, 0), Pose(50, 15, 0))
    goal = Pose(40.25, 15.25, 0.0)
    arc = RADIUS * 2 * math.pi / 16
    ahead = _lattice(open_map).estimate(goal, True)
    assert ahead is not None
    # Straight behind the goal, facing it: straight moves only, at most one more than
    # the distance needs (cells round the ends).
    for d in (5.0, 10.0, 20.0):
        cost = ahead(goal.x - d, goal.y, 0.0)
        assert d - arc <= cost <= d + arc
    # Straight ahead of the goal, facing it: backwards (reverse_cost 2) beats a loop.
    assert 2 * 10.0 - 2 * arc <= ahead(goal.x + 10.0, goal.y, 0.0) <= 2 * 10.0 + 2 * arc
    # Facing away 20 m behind: a loop round, far longer than the distance.
    assert ahead(goal.x - 20.0, goal.y, math.pi) > 20.0 + math.pi * RADIUS
    # Forward only, ahead of the goal: it cannot back in, so it loops.
    forward = _lattice(open_map, reverse=False).estimate(goal, True)
    assert forward is not None and forward(goal.x + 10.0, goal.y, 0.0) > 2 * math.pi * RADIUS


def test_no_estimate_across_a_wall_the_lattice_cannot_pass() -> None:
    ahead = _lattice(WALLED).estimate(WALLED.goal, True)
    assert ahead is not None
    assert ahead(20.0, 6.0, 0.0) > 0.0  # the goal's side
    assert ahead(3.0, 6.0, 0.0) == 0.0  # the wall's other side: the search's own estimate


def test_a_cell_grows_on_a_big_map_to_keep_the_nodes_bounded() -> None:
    m = builtin_map("parking_lot")
    lat = _lattice(m, max_nodes=50_000)
    nx, ny = lat.shape
    assert nx * ny * lat.headings * lat.gears <= 50_000 * 1.05
    assert lat.cell > 0.5


def test_guided_takes_the_larger_estimate() -> None:
    grid = FreeCellGraph.build(CollisionChecker.for_map(WALLED), 1.0)
    plain = Heuristic(HolonomicField.towards(grid, WALLED.goal), None, WALLED.goal)
    both = guided(plain, lambda x, y, yaw: 7.0 if x > 20 else 0.0)
    assert both.at(22.0, 6.0, 0.0) == max(7.0, plain.at(22.0, 6.0, 0.0))
    assert both.at(18.0, 6.0, 0.0) == pytest.approx(plain.at(18.0, 6.0, 0.0), abs=1.5)


@pytest.mark.parametrize("field", ["lattice_after", "lattice_headings", "lattice_nodes"])
def test_lattice_settings_are_validated(field: str) -> None:
    with pytest.raises(InputError, match=f"hybrid.{field}"):
        HybridConfig(**{field: -1})
    with pytest.raises(InputError, match="hybrid.lattice_cell"):
        HybridConfig(lattice_cell=0.0)


def _plan(m: Map, **cfg: int) -> object:
    problem = PlanningProblem.from_map(m, reverse=True)
    return make_planner("hybrid-a-star", **cfg).solve(
        problem, np.random.default_rng(0), Budget(max_iterations=20_000, max_time_s=1e6)
    )


def test_a_query_answered_before_the_lattice_comes_in_is_unchanged() -> None:
    m = _against_row(aisle=5.0)  # the multi-point turn answers it in 417 expansions
    off, on = _plan(m, lattice_after=0), _plan(m, lattice_after=800)
    assert off.success and on.success and off.iterations == on.iterations < 800
    assert np.array_equal(off.path.samples, on.path.samples)


def test_turning_round_against_an_angled_row_takes_fewer_expansions_with_the_lattice() -> None:
    m = _against_row(aisle=4.0)
    off, on = _plan(m, lattice_after=0), _plan(m, lattice_after=800)
    assert off.success and on.success
    assert on.iterations < off.iterations / 2, (off.iterations, on.iterations)
    report = verify_path(m, on.path, max_sharpness=0.2)
    assert report.ok, report
    again = _plan(m, lattice_after=800)
    assert again.iterations == on.iterations
    assert np.array_equal(again.path.samples, on.path.samples)


class _SlowChecker(CollisionChecker):
    """The same checker on a slower machine: every field look-up sleeps first."""

    def axis_clearances(self, rows: np.ndarray, offsets: np.ndarray) -> np.ndarray:
        time.sleep(5e-5)
        return super().axis_clearances(rows, offsets)


def test_the_guided_answer_is_the_same_on_a_slower_machine() -> None:
    m = _against_row(aisle=4.0)
    fast = PlanningProblem.from_map(m, reverse=True)
    slow = PlanningProblem(m, _SlowChecker.for_map(m), m.start, m.goal, m.vehicle, reverse=True)
    budget = Budget(max_iterations=20_000, max_time_s=1e6)
    a, b = (
        make_planner("hybrid-a-star").solve(p, np.random.default_rng(0), budget)
        for p in (fast, slow)
    )
    assert a.success and a.iterations > 800  # the lattice came in
    assert (a.status, a.iterations, a.message) == (b.status, b.iterations, b.message)
    assert np.array_equal(a.path.samples, b.path.samples)
