"""Audit (session 50): memory and caches, and whether a cache can give a wrong answer.

Complements ``test_audit_long_running_s49.py`` (cache inventory, maxsize of every
``lru_cache``, tracemalloc sawtooth over 40 maps, gym envs). This file covers:

- two maps that differ only in one obstacle, used alternately in one process (and
  from several threads at once while the checker cache overflows): each query gets
  its own map's answer, and a map's answer does not change after the other's query;
- maps with equal obstacles but other start/goal share one checker and still answer
  their own query;
- what stays alive after a query: the map, the planner, the problem and the result
  are collected; the user's own checker (README: "a service cycling through many maps
  keeps its own ``CollisionChecker.for_map(m)``") is not, after an
  improved-rrt-connect query (``improved.boxed._fan_room`` holds it);
- process RSS (``ru_maxrss``) over 200 different small maps against 100 queries on
  one map, in a fresh interpreter;
- ``sim.scenes._LANE_CACHE``: bounded by its cap, and a hit is highway-env's own lane.

Measured (this machine, 40 x 20 m random maps, improved-rrt-connect, tracemalloc):
traced memory is a sawtooth between about 12 and 64 MB as ``planning.checker_cache._CHECKERS``
fills to 17 and clears (about 3.5 MB a map: ``collision/lookup.py`` flat copy of the
field, ``collision/distance.py`` field, ``hybrid/heuristic.py`` distance fields,
scipy labels); RSS +52 MB after 20 maps, +65-110 MB from 40 to 400 maps, +0-6 MB for
100-200 queries on one map. A 100 m map's checker is 17 MB, 27-33 MB after an improved
or hybrid query (README: "tens of MB").
"""

from __future__ import annotations

import gc
import json
import subprocess
import sys
import textwrap
import threading
import weakref
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest

from rrtdrive import Budget, CollisionChecker, Map, Obstacle, Pose
from rrtdrive.planning import PlanningProblem, make_planner
from rrtdrive.planning import checker_cache as cache_module

START, GOAL = Pose(3.0, 10.0, 0.0), Pose(35.0, 10.0, 0.0)
BOUNDS = (0.0, 0.0, 40.0, 20.0)
# 2 m long, 6 m wide across the straight start -> goal line (y = 7..13).
WALL = Obstacle((19.0, 10.0), (2.0, 6.0))
FREE = Map("twin", BOUNDS, (), START, GOAL)
BLOCKED = Map("twin", BOUNDS, (WALL,), START, GOAL)
BUDGET = Budget(max_iterations=3000, max_time_s=20.0)
PLANNERS = ("improved-rrt-connect", "rrt-connect", "rrt", "rrt-star", "hybrid-a-star")


@pytest.fixture
def checker_cache():
    """The process-wide checker cache, restored after the test (other tests rely on it)."""
    saved = dict(cache_module._CHECKERS)
    yield cache_module._CHECKERS
    cache_module._CHECKERS.clear()
    cache_module._CHECKERS.update(saved)


def _filler(i: int) -> Map:
    """A small map of its own (another bounds width): a new key for the checker cache."""
    return Map(f"f{i}", (0.0, 0.0, 20.0 + i, 10.0), (Obstacle((10.0, 5.0), (1.0, 1.0)),),
               Pose(2.0, 2.0, 0.0), Pose(2.0, 8.0, 0.0))  # fmt: skip


def _solve(name: str, m: Map, seed: int = 0, reverse: bool = False):
    problem = PlanningProblem.from_map(m, reverse=reverse)
    return problem, make_planner(name).solve(problem, np.random.default_rng(seed), BUDGET)


def _exactly_free(m: Map, samples: np.ndarray) -> bool:
    """The exact body test of ``m`` by a checker built here (no cache involved)."""
    return CollisionChecker.for_map(m).path_free(samples, spacing=0.1)[0]


def _off_line(samples: np.ndarray) -> float:
    return float(np.abs(samples[:, 1] - START.y).max())


# ------------------------------------------------------------------ cache keys: correctness


@pytest.mark.parametrize("name", PLANNERS)
def test_maps_differing_in_one_obstacle_answer_alternately(name, checker_cache):
    """free, blocked, free, blocked in one process: each query its own map's answer."""
    runs = [(m, *_solve(name, m, seed=5)) for m in (FREE, BLOCKED, FREE, BLOCKED)]
    p_free, p_blocked = runs[0][1], runs[1][1]
    assert p_free.checker is not p_blocked.checker
    assert p_free.checker.obstacles == () and p_blocked.checker.obstacles == (WALL,)
    # The straight drive through the wall's place: free on one map only.
    line = np.array([[x, START.y, 0.0] for x in np.arange(START.x, GOAL.x, 0.5)])
    for m, problem, result in runs:
        assert result.success, (m.obstacles, result.message)
        samples = result.path.samples
        assert _exactly_free(m, samples)
        assert problem.checker.path_free(line)[0] is (m is FREE)
        assert problem.checker.pose_free((19.0, 10.0, 0.0)) is (m is FREE)
        if m is BLOCKED:
            # Around the wall: the body (0.9 m half width) passes beyond y = 10 +- 3.
            assert _off_line(samples) > 3.9
    # A map's second query (after the other map's) is its first one, bit for bit.
    for first, again in ((runs[0], runs[2]), (runs[1], runs[3])):
        assert np.array_equal(first[2].path.samples, again[2].path.samples)


def test_direct_connection_sees_the_obstacle_of_its_own_map(checker_cache):
    """The improved planner's direct start -> goal edge on the free map only."""
    _, free = _solve("improved-rrt-connect", FREE)
    _, blocked = _solve("improved-rrt-connect", BLOCKED)
    _, free_again = _solve("improved-rrt-connect", FREE)
    assert _off_line(free.path.samples) == pytest.approx(0.0, abs=1e-9)
    assert _off_line(free_again.path.samples) == pytest.approx(0.0, abs=1e-9)
    assert _off_line(blocked.path.samples) > 3.9


def test_equal_obstacles_other_query_share_the_checker_not_the_answer(checker_cache):
    """Equal bounds, obstacles and car share one checker; each query ends at its own goal."""
    low_goal = Pose(35.0, 4.0, 0.0)
    other = Map("twin_other_goal", BOUNDS, (WALL,), START, low_goal)
    p1, r1 = _solve("improved-rrt-connect", BLOCKED)
    p2, r2 = _solve("improved-rrt-connect", other)
    p3, r3 = _solve("improved-rrt-connect", BLOCKED)
    assert p1.checker is p2.checker is p3.checker
    for result, goal in ((r1, GOAL), (r2, low_goal), (r3, GOAL)):
        assert result.success
        end = result.path.samples[-1]
        assert np.hypot(end[0] - goal.x, end[1] - goal.y) < 1e-6
    assert np.array_equal(r1.path.samples, r3.path.samples)


def test_threads_planning_alternate_maps_while_the_cache_overflows(checker_cache):
    """4 threads, the twin maps and 20 one-off maps (the cache clears on the way)."""
    fillers = [_filler(i) for i in range(20)]
    jobs = []
    for i in range(40):
        if i % 2:
            jobs.append(("filler", fillers[i // 2]))
        else:
            jobs.append(("free" if i % 4 == 0 else "blocked", FREE if i % 4 == 0 else BLOCKED))
    seen_sizes: list[int] = []
    lock = threading.Lock()

    def work(job):
        kind, m = job
        planner = "improved-rrt-connect" if kind != "filler" else "rrt-connect"
        problem, result = _solve(planner, m, seed=3)
        with problem.checker.lock:
            wall_free = problem.checker.pose_free((19.0, 10.0, 0.0))
        with lock:
            seen_sizes.append(len(cache_module._CHECKERS))
        return kind, result, wall_free

    with ThreadPoolExecutor(max_workers=4) as pool:
        out = list(pool.map(work, jobs))
    assert max(seen_sizes) <= 17
    for kind, result, wall_free in out:
        if kind == "filler":
            continue
        assert result.success, result.message
        if kind == "free":
            assert wall_free and _off_line(result.path.samples) == pytest.approx(0.0, abs=1e-9)
        else:
            assert not wall_free and _off_line(result.path.samples) > 3.9
            assert _exactly_free(BLOCKED, result.path.samples)


# ------------------------------------------------------------------ what stays alive


def _own_checker_query(name: str, reverse: bool):
    """A service's query: its own map and checker; weak references to what it made."""
    m = Map("own", BOUNDS, (WALL,), START, GOAL)
    checker = CollisionChecker.for_map(m)
    problem = PlanningProblem(m, checker, m.start, m.goal, m.vehicle, reverse=reverse)
    planner = make_planner(name)
    result = planner.solve(problem, np.random.default_rng(0), BUDGET)
    assert result.success, result.message
    refs = {
        "map": weakref.ref(m), "problem": weakref.ref(problem),
        "planner": weakref.ref(planner), "result": weakref.ref(result),
        "path": weakref.ref(result.path), "checker": weakref.ref(checker),
    }  # fmt: skip
    return refs


@pytest.mark.parametrize("reverse", [False, True])
@pytest.mark.parametrize("name", PLANNERS)
def test_map_planner_problem_result_are_collected(name, reverse):
    refs = _own_checker_query(name, reverse)
    gc.collect()
    alive = sorted(k for k, r in refs.items() if r() is not None and k != "checker")
    assert alive == []


def test_a_from_map_query_keeps_no_map_alive(checker_cache):
    """The checker cache's key holds bounds, obstacles and car, not the Map itself."""
    m = Map("keyed", BOUNDS, (WALL,), START, GOAL)
    result = _solve("improved-rrt-connect", m)[1]
    assert result.success
    ref = weakref.ref(m)
    del m, result
    gc.collect()
    assert ref() is None


# improved.boxed._fan_room was an lru_cache keyed on the checker: it kept the last checker
# an improved-rrt-connect query used alive (27 MB for parking_lot); now weakly keyed.


@pytest.mark.parametrize(
    "name", PLANNERS
)
def test_a_dropped_own_checker_is_freed(name):
    """README: a service keeps its own checker per map; dropping it must free it."""
    refs = _own_checker_query(name, reverse=False)
    gc.collect()
    assert refs["checker"]() is None


# ------------------------------------------------------------------ process memory


_RSS_SCRIPT = """
import gc, json, resource, sys
import numpy as np
from rrtdrive import Budget, InputError, Map, Obstacle, Pose
from rrtdrive.planning import PlanningProblem, make_planner, base, checker_cache

def rss_mb():  # the peak so far (kB on Linux, bytes on macOS)
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return peak / (1e6 if sys.platform == "darwin" else 1e3)

def random_map(rng, i):
    while True:
        obs = tuple(
            Obstacle((float(rng.uniform(10, 30)), float(rng.uniform(2, 18))),
                     (float(rng.uniform(1, 4)), float(rng.uniform(1, 4))),
                     float(rng.uniform(0, 3.14)))
            for _ in range(int(rng.integers(1, 5)))
        )
        try:
            return Map(f"r{i}", (0.0, 0.0, 40.0, 20.0), obs,
                       Pose(3.0, 10.0, 0.0), Pose(35.0, 10.0, 0.0))
        except InputError:
            continue

rng = np.random.default_rng(1)
maps = [random_map(rng, i) for i in range(201)]
budget = Budget(max_iterations=2000, max_time_s=10.0)
def plan(m, seed):
    p = PlanningProblem.from_map(m)
    return make_planner("improved-rrt-connect").solve(p, np.random.default_rng(seed), budget)

plan(maps[0], 0); gc.collect()
base_mb = rss_mb()
for s in range(100):
    plan(maps[0], s)
gc.collect(); same = rss_mb()
sizes, solved = [], 0
for i, m in enumerate(maps[1:], 1):
    solved += plan(m, i).success
    sizes.append(len(checker_cache._CHECKERS))
    if i == 40:
        gc.collect(); after40 = rss_mb()
gc.collect(); after200 = rss_mb()
print(json.dumps({"base": base_mb, "same": same, "after40": after40,
                  "after200": after200, "max_cached": max(sizes), "solved": solved}))
"""


@pytest.mark.skipif(sys.platform == "win32", reason="resource.getrusage is Unix-only")
def test_rss_many_different_maps_plateaus():
    """200 different maps: peak RSS a plateau after 40; 100 queries on one map: flat.

    Measured (ru_maxrss over a 119 MB base): +0 MB for the same map; +65 MB after 40
    maps, +110 MB after 200 (17 checkers of ~3.5 MB, then allocator fragmentation).
    """
    proc = subprocess.run(
        [sys.executable, "-c", textwrap.dedent(_RSS_SCRIPT)],
        capture_output=True, text=True, timeout=150,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr[-3000:]
    out = json.loads(proc.stdout.strip().splitlines()[-1])
    assert out["solved"] >= 150, out  # the maps were planned on, not refused
    assert out["max_cached"] <= 17, out
    same = out["same"] - out["base"]
    first = out["after40"] - out["base"]
    total = out["after200"] - out["base"]
    assert same < 30.0, out  # MB: one map's queries add no per-query state
    # Five times the maps, at most twice what the first 40 needed (+50 MB for the
    # allocator's fragmentation): a sawtooth, not a ramp (no eviction: ~700 MB).
    assert total < 2.0 * first + 50.0, out


# ------------------------------------------------------------------ the scenes' lane cache


def test_lane_cache_stays_under_its_cap_and_answers_as_highway_env(monkeypatch):
    """parallel-parking places its cars anew per seed: a small cap is reached and kept."""
    from rrtdrive.sim import scenes
    from rrtdrive.sim.tasks import make_variant

    monkeypatch.setattr(scenes, "_LANE_CACHE", {})
    monkeypatch.setattr(scenes, "_LANE_CACHE_MAX", 40)
    sizes = []
    for seed in range(12):
        road = make_variant("parallel-parking", seed).build_road(np.random.default_rng(seed), False)
        sizes.append(len(scenes._LANE_CACHE))
        for obj in [*road.objects, *road.vehicles]:
            want = road.network.get_closest_lane_index(obj.position, obj.heading)
            assert obj.lane_index == want
    assert max(sizes) <= 40 and max(sizes) > 20, sizes  # filled, then cleared


def test_shared_hybrid_tables_are_read_only():
    """The Dubins tables and primitive sets are shared by every later query in the
    process: a stray write would change all later plans, so it raises instead."""
    from rrtdrive.planning.hybrid.config import HybridConfig
    from rrtdrive.planning.hybrid.primitives import primitive_sets
    from rrtdrive.planning.hybrid.resolution import dubins_table

    table = dubins_table(6.0, HybridConfig())
    with pytest.raises(ValueError, match="read-only"):
        table.lengths[0, 0, 0] = 1.0
    for one in primitive_sets(0.16, 5, 2.0, 0.1, 0, (2,)):
        for a in (one.kappas, one.gears, one.local):
            with pytest.raises(ValueError, match="read-only"):
                a.flat[0] = 1.0


def test_threads_asking_for_one_new_map_share_one_checker():
    """cached_checker built one checker per thread when they asked at once (an audit)."""
    import threading

    from rrtdrive.maps import Map
    from rrtdrive.planning.checker_cache import cached_checker

    m = Map("fresh", (0.0, 0.0, 61.3, 40.0), (), Pose(5.0, 20.0, 0.0), Pose(50.0, 20.0, 0.0))
    got: list[object] = []
    go = threading.Barrier(4)

    def ask() -> None:
        go.wait()
        got.append(cached_checker(m))

    threads = [threading.Thread(target=ask) for _ in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert len(got) == 4 and all(c is got[0] for c in got)
