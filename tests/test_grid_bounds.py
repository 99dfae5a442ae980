"""Bounded grid memory and per-map set-up outside the budget.

A map whose grid would exceed ``CheckerConfig.max_grid_cells`` gets a coarser
grid whose error margin grows with the cell, so the fast tests stay
conservative (checked against shapely on random poses and edges); beyond the
coarsest grid the checker chooses by itself, one clear error naming ``bounds``
(exit 2 on the command line). A big map's set-up is reported in
``setup_time_s`` and never eats the planning budget.
"""

from __future__ import annotations

import json
import math
import re

import numpy as np
import pytest
import shapely

from rrtdrive.cli import main
from rrtdrive.collision import CheckerConfig, CollisionChecker
from rrtdrive.collision.grid import grid_resolution, grid_shape
from rrtdrive.maps import Map, Obstacle, builtin_map
from rrtdrive.planning import PlanningProblem, make_planner
from rrtdrive.types import Budget, InputError, InputWarning, PlanStatus, Pose
from rrtdrive.verify import verify_path

#: Small enough that the 100 x 100 m parking lot (1.04 M cells at 0.1 m) is coarsened.
SMALL_LIMIT = CheckerConfig(max_grid_cells=200_000)


def reference_body(x: float, y: float, yaw: float) -> shapely.Polygon:
    """The body rectangle from first principles (rear axle 0.895 m from the back, 4.3 x 1.8 m)."""
    c, s = math.cos(yaw), math.sin(yaw)
    return shapely.Polygon(
        [(x + c * lx - s * ly, y + s * lx + c * ly)
         for lx, ly in ((-0.895, -0.9), (3.405, -0.9), (3.405, 0.9), (-0.895, 0.9))]
    )  # fmt: skip


@pytest.fixture(scope="module")
def coarse():
    m = builtin_map("parking_lot")
    with pytest.warns(InputWarning, match="^bounds: "):
        return m, CollisionChecker.for_map(m, config=SMALL_LIMIT)


def test_grid_resolution_keeps_small_maps_and_coarsens_big_ones():
    assert grid_resolution((0.0, 0.0, 100.0, 100.0), CheckerConfig()) == 0.1
    # 500 x 500 m at 0.1 m (25.2 M cells) fits the default limit as it is.
    assert grid_resolution((0.0, 0.0, 500.0, 500.0), CheckerConfig()) == 0.1
    for size in (710.0, 1000.0, 2500.0):
        h = grid_resolution((0.0, 0.0, size, size), CheckerConfig())
        nx, ny = grid_shape((0.0, 0.0, size, size), h, 1.0)
        assert 0.1 < h <= 0.5 and nx * ny <= CheckerConfig().max_grid_cells
        # The next centimetre finer would not fit: the coarsening is as small as it can be.
        fx, fy = grid_shape((0.0, 0.0, size, size), round(h - 0.01, 10), 1.0)
        assert h - 0.01 <= 0.1 or fx * fy > CheckerConfig().max_grid_cells


def test_a_too_big_map_is_refused_naming_bounds():
    with pytest.raises(InputError) as err:
        grid_resolution((0.0, 0.0, 10_000.0, 10_000.0), CheckerConfig())
    message = str(err.value)
    assert message.startswith("bounds: 10000 x 10000 m needs 10,004,000,400 grid cells at 0.1 m")
    assert "the limit is 50,000,000 cells" in message and "--resolution 1.42" in message
    # An explicit coarse resolution is taken as given.
    assert grid_resolution((0.0, 0.0, 10_000.0, 10_000.0), CheckerConfig(resolution=1.5)) == 1.5


@pytest.mark.parametrize("side", [1e6, 1e7])
def test_a_map_needing_cells_past_the_coarsest_allowed_gets_no_resolution_advice(side):
    # 1e6 m needs 141.57 m cells, which --resolution refuses (at most 100 m): the
    # advice was to give it anyway.
    with pytest.raises(InputError) as err:
        grid_resolution((0.0, 0.0, side, side), CheckerConfig())
    message = str(err.value)
    assert message.endswith("(checker.max_grid_cells): use a smaller map"), message
    assert "--resolution" not in message
    with pytest.raises(InputError, match=r"checker.resolution: at most 100 m"):
        CheckerConfig(resolution=141.57)


@pytest.mark.parametrize(
    ("field", "value"), [("max_grid_cells", 0), ("max_grid_cells", 2.5),
                         ("max_auto_resolution", -1.0), ("max_auto_resolution", math.inf)],
)  # fmt: skip
def test_the_limits_are_validated(field, value):
    with pytest.raises(InputError, match=f"checker.{field}"):
        CheckerConfig(**{field: value})


def test_the_coarse_checker_reports_its_resolution(coarse):
    m, checker = coarse
    assert checker.requested_resolution == 0.1
    assert 0.1 < checker.resolution <= 0.5 and checker.config.resolution == checker.resolution
    nx, ny = checker.clearance_grid.shape
    assert nx * ny <= SMALL_LIMIT.max_grid_cells
    assert checker.grid_error == pytest.approx(checker.resolution * math.sqrt(2.0))
    with pytest.warns(InputWarning, match=f"^bounds: .* using {checker.resolution:g} m cells"):
        CollisionChecker.for_map(m, config=SMALL_LIMIT)
    with pytest.warns(InputWarning, match="^bounds: "):
        problem = PlanningProblem.from_map(m, config=SMALL_LIMIT)
    res = make_planner("rrt-connect").solve(problem, np.random.default_rng(0), Budget())
    assert res.stats["grid_resolution_m"] == checker.resolution


def test_the_coarse_grid_stays_conservative_against_shapely(coarse):
    m, checker = coarse
    union = shapely.union_all([o.polygon() for o in m.obstacles])
    box = shapely.box(*m.bounds)
    rng = np.random.default_rng(5)
    poses = np.column_stack([rng.uniform(0, 100, (3000, 2)), rng.uniform(-math.pi, math.pi, 3000)])
    ref = np.array([box.contains(b) and not union.intersects(b)
                    for b in (reference_body(*p) for p in poses)])  # fmt: skip
    assert 0.2 < ref.mean() < 0.9  # both outcomes occur
    fast = checker.poses_free_fast(poses)
    assert not (fast & ~ref).any()  # the fast screen never frees a colliding pose
    assert fast.sum() >= 0.5 * ref.sum()  # and it is not useless
    assert (checker.poses_free(poses) == ref).all()  # the exact test agrees with shapely
    points = poses[:, :2]
    true = np.array([0.0 if union.contains(shapely.Point(p))
                     else min(union.distance(shapely.Point(p)),
                              box.exterior.distance(shapely.Point(p))) for p in points])
    assert (checker.clearances(points) <= true + 1e-9).all()
    # Edges: the fast test never frees an edge whose swept body collides.
    freed = 0
    for a, yaw in zip(points[:600], poses[:600, 2], strict=True):
        b = a + 5.0 * np.array([math.cos(yaw), math.sin(yaw)])
        if checker.edge_free(a, b):
            freed += 1
            for t in np.linspace(0.0, 1.0, 26):
                body = reference_body(*(a + t * (b - a)), yaw)
                assert box.contains(body) and not union.intersects(body)
    assert freed > 50


def test_a_coarse_grid_plans_a_verified_path(coarse):
    m, checker = coarse  # the fixture's checker: built (and warned about) there
    problem = PlanningProblem.from_map(m, checker=checker)
    res = make_planner("improved-rrt-connect").solve(problem, np.random.default_rng(0), Budget())
    assert res.success, res.message
    assert verify_path(m, res.path).ok


@pytest.mark.parametrize("command", ["plan", "simulate"])
def test_cli_refuses_10_km_bounds_with_exit_2(tmp_path, capsys, command):
    f = tmp_path / "huge.json"
    f.write_text(json.dumps({
        "name": "huge", "bounds": [0, 0, 10_000, 10_000], "obstacles": [],
        "start": [10, 10, 0], "goal": [9_000, 9_000, 0],
    }))  # fmt: skip
    code = main([command, str(f)])
    out, err = capsys.readouterr()
    assert code == 2 and out == ""
    assert err.startswith(f"rrtdrive {command}: error: bounds: 10000 x 10000 m needs ")
    assert "Traceback" not in err and err.count("\n") == 1
    # simulate has no --resolution of its own: the message names the command that has.
    assert "rrtdrive plan or simulate --resolution 1.42" in err
    assert "CheckerConfig(resolution=1.42)" in err


def big_map(n: int = 800, size: float = 500.0, seed: int = 0) -> Map:
    """``n`` seeded boxes of 1-6 m over ``size`` x ``size`` m, clear of the two corners' poses."""
    rng = np.random.default_rng(seed)
    start, goal = Pose(5.0, 5.0, 0.7), Pose(size - 5.0, size - 5.0, 0.7)
    obstacles: list[Obstacle] = []
    while len(obstacles) < n:
        c = rng.uniform(10.0, size - 10.0, 2)
        size_xy = rng.uniform(1.0, 6.0, 2)
        yaw = float(rng.uniform(-3.0, 3.0))
        if min(math.dist(c, start.xy), math.dist(c, goal.xy)) < 15.0:
            continue
        obstacles.append(Obstacle((float(c[0]), float(c[1])), tuple(size_xy.tolist()), yaw))
    return Map("big", (0.0, 0.0, size, size), tuple(obstacles), start, goal)


def test_a_big_maps_set_up_is_reported_apart_and_outside_the_budget():
    # 300 x 300 m with 290 obstacles (the density of the 500 x 500 m with 800):
    # 9 M cells at 0.1 m, seconds of set-up, 3x cheaper for the suite than 500 m.
    m = big_map(290, 300.0)
    problem = PlanningProblem.from_map(m)
    assert problem.checker.resolution == 0.1 and problem.checker.setup_time_s > 0.0
    res = make_planner("improved-rrt-connect").solve(
        problem, np.random.default_rng(0), Budget(max_iterations=20_000)
    )
    assert res.status is PlanStatus.SOLVED, res.message
    assert res.iterations > 0 and res.setup_time_s > 0.0
    # The labels, sampling and passage cells and the expanded obstacles are built
    # before the stopwatch starts: set-up is orders of magnitude more than the search.
    assert res.planning_time_s < res.setup_time_s
    assert verify_path(m, res.path).ok


def test_plan_announces_a_long_set_up_and_reports_it(capsys, monkeypatch):
    # A map whose grid takes seconds to set up got no word until the result. Here the
    # threshold is lowered so that a small map stands in for a big one.
    import rrtdrive.collision.grid as grid

    assert main(["plan", "overtake", "--max-iterations", "200"]) == 0
    out, err = capsys.readouterr()
    assert err == "" and "set-up" not in out
    monkeypatch.setattr(grid, "LARGE_GRID_CELLS", 1000)
    assert main(["plan", "overtake", "--max-iterations", "200"]) == 0
    out, err = capsys.readouterr()
    assert err.startswith("rrtdrive plan: setting up a 100 x 100 m map: ")
    assert "M grid cells at 0.1 m (seconds; not planning time)" in err
    assert out.rstrip().endswith(" s)") and "(set-up " in out


def test_a_failed_plan_after_a_long_set_up_reports_it_too(capsys, monkeypatch):
    # Only a solved plan's summary gave the set-up time (a docs audit, session 34).
    import rrtdrive.collision.grid as grid

    monkeypatch.setattr(grid, "LARGE_GRID_CELLS", 1000)
    assert main(["plan", "no_path", "--max-iterations", "50"]) == 1
    out = capsys.readouterr().out
    assert "FAILED (" in out and ", set-up " in out.split("):")[0], out
    # And the diagnosis's time, which runs after the stopwatch (session 38).
    assert re.search(r"FAILED \(\w+, set-up \d+\.\d s, diagnosis \d+\.\d s\): ", out), out
