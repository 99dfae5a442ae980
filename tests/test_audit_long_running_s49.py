"""Audit (session 49): long-running use of the Python API, memory and caches.

A user who embeds rrtdrive in a service or an RL loop plans thousands of queries in
one process. Every process-wide cache must be bounded, memory must stop growing after
warm-up, results must not be kept alive by caches, and a cache hit must give the
answer a cold build would.

Inventory (src/rrtdrive, envs/, controllers/), each bounded:

- ``planning.checker_cache._CHECKERS``: one checker per (bounds, obstacles, vehicle, config),
  cleared whole when it holds more than 16 (so at most 17 maps' checkers).
- per checker, ``collision.grid.GridCache``: ``_free`` (per start component),
  ``_passages`` (component, width), ``_derived`` (keys from config values only:
  expanded checker, hybrid free cells per resolution, lattice per config, body tests
  at most ``BODY_TESTS``, width proofs per keep, diagnosis labels); the hybrid
  ``FreeCellGraph._fields`` keeps ``FIELD_CACHE`` fields, ``HeadingLattice._tables``
  ``_KEPT`` tables.
- ``functools.lru_cache``: every one has a ``maxsize`` (checked below), except three
  on finite domains (``checking._members``: protocols; ``occupancy._yaml_loader``:
  no argument; ``bench.grid.always_reverses``: a bench target name).
- ``sim.scenes._LANE_CACHE`` (cleared at 100 000 entries), ``checking._CLASS_IMPLEMENTS``
  (classes), ``improved.boxed._fan_room`` (last 2 checkers, by identity).

Measurements run in subprocesses (tracemalloc), with small counts so the file stays
fast; the report extrapolates.
"""

from __future__ import annotations

import dataclasses
import gc
import json
import subprocess
import sys
import textwrap
import weakref

import numpy as np
import pytest

from rrtdrive import Budget, CheckerConfig, CollisionChecker, VehicleParams, builtin_map
from rrtdrive.planning import PlanningProblem, make_planner
from rrtdrive.planning.base import cached_checker


def _run(code: str, timeout: float = 120.0, prelude: str = "") -> dict:
    """Run ``prelude`` and ``code`` in a fresh interpreter; it prints one JSON line last."""
    proc = subprocess.run(
        [sys.executable, "-c", prelude + textwrap.dedent(code)],
        capture_output=True, text=True, timeout=timeout,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr[-3000:]
    return json.loads(proc.stdout.strip().splitlines()[-1])


# Random free poses on a map (shared by the subprocess snippets).
_POSES = """
import gc, json, tracemalloc
import numpy as np
from rrtdrive import Budget, Pose, builtin_map
from rrtdrive.planning import PlanningProblem, make_planner

def pose_sampler(checker, bounds, seed):
    rng = np.random.default_rng(seed)
    xmin, ymin, xmax, ymax = bounds
    def pose():
        while True:
            p = (rng.uniform(xmin, xmax), rng.uniform(ymin, ymax), rng.uniform(-np.pi, np.pi))
            if checker.pose_free(p, 0.3):
                return Pose(*p)
    return pose

def mem():
    gc.collect()
    return tracemalloc.get_traced_memory()[0]
"""

MB = 1e6


# ------------------------------------------------------------------ inventory


def test_every_function_cache_has_a_bound():
    """Every lru_cache in rrtdrive (and its envs, controllers) has a maxsize."""
    out = _run(
        """
        import importlib, json, pkgutil, sys, warnings
        warnings.simplefilter("ignore")
        import rrtdrive
        for pkg in ("rrtdrive",):
            p = importlib.import_module(pkg)
            for mi in pkgutil.walk_packages(p.__path__, pkg + "."):
                if mi.name.endswith("__main__") or "ompl" in mi.name:
                    continue
                try:
                    importlib.import_module(mi.name)
                except Exception:
                    pass
        found = {}
        for name, mod in list(sys.modules.items()):
            if not name.startswith("rrtdrive"):
                continue
            for k, v in vars(mod).items():
                if hasattr(v, "cache_info") and getattr(v, "__module__", "") == name:
                    found[name + "." + k] = v.cache_info().maxsize
        print(json.dumps(found))
        """
    )
    # These take no argument or a value from a small fixed set.
    finite = {
        "rrtdrive.checking._members",
        "rrtdrive.occupancy._yaml_loader",
        "rrtdrive.bench.grid.always_reverses",
    }
    assert "rrtdrive.obstacles._obstacle_polygon" in out  # the scan found the caches
    assert "rrtdrive.controllers.lqr._design_gain" in out  # and controllers/
    unbounded = sorted(k for k, v in out.items() if v is None and k not in finite)
    assert unbounded == []


# ------------------------------------------------------------------ one map, many queries


def test_one_map_many_queries_memory_plateaus():
    """Random queries on one map, four planners, both gears: no steady per-query growth.

    Measured (garage, 400 iterations a query): about 19 MB after warm-up, +6 MB over the
    next 150 queries as the bounded hybrid caches fill (resolutions, distance fields,
    Dubins tables), then about 3 KB a query, falling.
    A repeated pool of queries (same poses, seeds) must not grow at all once warm.
    """
    out = _run(
        """
        m = builtin_map("garage")
        checker = PlanningProblem.from_map(m).checker
        pose = pose_sampler(checker, m.bounds, 0)
        modes = [("improved-rrt-connect", False), ("hybrid-a-star", True),
                 ("hybrid-a-star", False), ("rrt-connect", False),
                 ("improved-rrt-connect", True)]
        budget = Budget(max_iterations=300, max_time_s=10.0)  # iterations decide
        pool = [(pose(), pose()) for _ in range(3)]

        def solve(name, rev, s, g, seed):
            p = PlanningProblem(m, checker, s, g, m.vehicle, reverse=rev)
            return make_planner(name).solve(p, np.random.default_rng(seed), budget)

        def one_pass():
            for k, (s, g) in enumerate(pool):
                for j, (name, rev) in enumerate(modes):
                    solve(name, rev, s, g, 10 * k + j)

        tracemalloc.start()
        one_pass()
        a = mem()
        one_pass()
        b = mem()
        # Fresh random queries after warm-up.
        n = 12
        for i in range(n):
            name, rev = modes[i % len(modes)]
            solve(name, rev, pose(), pose(), 100 + i)
        c = mem()
        d = c
        print(json.dumps({"pool": b - a, "queries": len(pool) * len(modes),
                          "random": c - b, "n": n, "total": d}))
        """,
        timeout=150,
        prelude=_POSES,
    )
    # Same queries again, warm: nothing new to keep (4 KB measured; keeping each
    # query's result alive would add about 8 KB a query, 116 KB here).
    assert out["pool"] < 50e3, out
    # Fresh queries: the bounded caches are still filling (about 120 KB a query here,
    # 3 KB after 300 queries), but not by a megabyte a query.
    assert out["random"] / out["n"] < 1 * MB, out
    assert out["total"] < 80 * MB, out


# ------------------------------------------------------------------ many maps


def test_many_maps_checkers_evicted_and_freed():
    """40 distinct small maps: the checker cache stays at most 17 and frees what it drops.

    Measured: about 3 MB a 30 x 20 m map's checker (after an improved query), a
    sawtooth between ~15 and ~55 MB. A 100 x 100 m map (narrow_gap): 17 MB the checker,
    +11 MB the improved planner's set-up, +52 MB a reverse hybrid query (partly
    process-wide tables): 17 such maps in the cache are 0.5-1 GB.
    """
    out = _run(
        """
        import gc, json, tracemalloc
        import numpy as np
        from rrtdrive import Budget, CollisionChecker, InputError, Map, Obstacle, Pose
        from rrtdrive.planning import PlanningProblem, make_planner, base, checker_cache
        from rrtdrive.planning.improved import boxed

        def gen(i):
            rng = np.random.default_rng(1000 + i)
            while True:
                obs = tuple(
                    Obstacle((float(rng.uniform(8, 22)), float(rng.uniform(2, 18))), (2.0, 2.0))
                    for _ in range(3)
                )
                try:
                    return Map(f"m{i}", (0.0, 0.0, 30.0, 20.0), obs,
                               Pose(3.0, 10.0, 0.0), Pose(24.0, 10.0, 0.0))
                except InputError:
                    continue

        def live_checkers():
            gc.collect()
            return sum(type(o) is CollisionChecker for o in gc.get_objects())

        make_planner("improved-rrt-connect")
        tracemalloc.start()
        base_mem = tracemalloc.get_traced_memory()[0]
        sizes, live, mems = [], [], []
        for i in range(40):
            m = gen(i)
            planner = "improved-rrt-connect" if i % 2 else "rrt-connect"
            make_planner(planner).solve(
                PlanningProblem.from_map(m), np.random.default_rng(i),
                Budget(max_iterations=300, max_time_s=2.0),
            )
            sizes.append(len(checker_cache._CHECKERS))
            live.append(live_checkers())
            mems.append(tracemalloc.get_traced_memory()[0] - base_mem)
        checker_cache._CHECKERS.clear()
        boxed._fan_room.cache_clear()
        left = live_checkers()
        after = tracemalloc.get_traced_memory()[0] - base_mem
        print(json.dumps({"sizes": sizes, "live": live, "mems": mems,
                          "left": left, "after": after}))
        """,
        timeout=150,
    )
    assert max(out["sizes"]) <= 17, out["sizes"]
    # Map checkers, their expanded-obstacle checkers and the 2 in _fan_room.
    assert max(out["live"]) <= 2 * 17 + 2, out["live"]
    # The second 20 maps need no more than the first 20 (a sawtooth, not a ramp).
    first, second = max(out["mems"][:20]), max(out["mems"][20:])
    assert second < 1.3 * first + 5 * MB, (first, second)
    # Once the documented caches are cleared, no checker survives.
    assert out["left"] == 0
    assert out["after"] < 0.5 * first, (out["after"], first)


def test_checker_cache_clears_hot_maps_too():
    """The checker cache is cleared whole: a map planned on between one-off maps is rebuilt.

    A service with one hot map and a stream of one-off maps rebuilds the hot map's
    checker (0.16-0.3 s on a 100 m map) every 17 new maps. Recorded as behaviour, not
    as a bug: the README says only that a checker is built "once per process".
    """
    from rrtdrive import Map, Obstacle, Pose
    from rrtdrive.planning import checker_cache

    checker_cache._CHECKERS.clear()  # a known start: other tests of this process filled it
    hot = builtin_map("garage")
    first = cached_checker(hot)
    rebuilt = []
    for i in range(18):
        m = Map(
            f"oneoff{i}",
            (0.0, 0.0, 20.0 + i, 10.0),
            (Obstacle((10.0, 5.0), (1.0, 1.0)),),
            Pose(2.0, 2.0, 0.0),
            Pose(2.0, 8.0, 0.0),
        )
        cached_checker(m, CheckerConfig(resolution=0.5))
        rebuilt.append(cached_checker(hot) is not first)
    # Hot after each one-off map, and still rebuilt once the cache overflows.
    assert any(rebuilt) and not all(rebuilt)


# ------------------------------------------------------------------ gym env, run_episode


@pytest.mark.parametrize("env_id", ["rrtdrive/Parking-v0", "rrtdrive/Overtake-v0"])
def test_gym_env_reset_step_episodes_do_not_grow(env_id):
    """Many reset/step episodes in one env: flat after warm-up.

    Measured: Parking-v0 27.1-27.6 MB over 10 episodes, Overtake-v0 22.13-22.14 MB,
    OvertakeTraffic-v0 15.9-16.5 MB; ParallelParking-v0 (a new map every episode)
    a sawtooth of 2-30 MB as the checker cache fills to 17 and clears.
    """
    out = _run(
        f"""
        import gc, json, tracemalloc
        import numpy as np
        import gymnasium as gym
        import rrtdrive
        env = gym.make({env_id!r})
        zero = np.zeros(env.action_space.shape, dtype=np.float32)

        def episode(ep):
            env.reset(options={{"episode_seed": ep}})
            for _ in range(10):
                *_, term, trunc, _info = env.step(zero)
                if term or trunc:
                    break

        tracemalloc.start()
        for ep in range(3):
            episode(ep)
        gc.collect(); a = tracemalloc.get_traced_memory()[0]
        for ep in range(3, 11):
            episode(ep)
        gc.collect(); b = tracemalloc.get_traced_memory()[0]
        env.close()
        print(json.dumps({{"growth": b - a, "episodes": 8}}))
        """,
        timeout=120,
    )
    assert out["growth"] / out["episodes"] < 100e3, out


def test_run_episode_repeatedly_does_not_grow():
    """run_episode many times in one process: flat after warm-up (21.82-21.83 MB measured)."""
    out = _run(
        """
        import gc, json, tracemalloc
        from rrtdrive.sim.runner import run_episode
        tracemalloc.start()
        for s, ctrl in enumerate(("pure-pursuit", "lqr")):  # lqr imports python-control
            run_episode("overtake", controller=ctrl, seed=s)
        gc.collect(); a = tracemalloc.get_traced_memory()[0]
        for s in range(2, 6):
            run_episode("overtake", controller=("lqr", "stanley")[s % 2], seed=s)
        gc.collect(); b = tracemalloc.get_traced_memory()[0]
        print(json.dumps({"growth": b - a, "episodes": 4}))
        """,
        timeout=120,
    )
    assert out["growth"] / out["episodes"] < 200e3, out


# ------------------------------------------------------------------ results not kept alive


@pytest.mark.parametrize(
    ("planner", "map_name", "reverse"),
    [
        ("rrt-connect", "garage", False),
        ("improved-rrt-connect", "garage", False),
        ("hybrid-a-star", "reverse_bay", True),
    ],
)
def test_plan_result_is_not_kept_alive_by_caches(planner, map_name, reverse):
    problem = PlanningProblem.from_map(builtin_map(map_name), reverse=reverse)
    result = make_planner(planner).solve(
        problem, np.random.default_rng(0), Budget(max_iterations=3000, max_time_s=30.0)
    )
    assert result.status.name == "SOLVED"
    refs = [weakref.ref(result), weakref.ref(result.path)]
    del result
    gc.collect()
    assert [r() for r in refs] == [None, None]


# ------------------------------------------------------------------ cache keys


def test_checker_cache_keys_separate_cars_and_configs():
    """Same bounds and obstacles, another car or checker config: another checker."""
    m = builtin_map("garage")
    wide = dataclasses.replace(m, vehicle=VehicleParams(width=2.0))
    renamed = dataclasses.replace(m, name="garage_copy")
    a = PlanningProblem.from_map(m).checker
    b = PlanningProblem.from_map(wide).checker
    c = PlanningProblem.from_map(m, config=CheckerConfig(margin=0.3)).checker
    assert b is not a and b.vehicle == wide.vehicle and a.vehicle == m.vehicle
    assert b.edge_radius == pytest.approx(1.1) and a.edge_radius == pytest.approx(1.0)
    assert c is not a and c.edge_radius == pytest.approx(1.2)
    # Only the name differs: the same checker, and it is the cold one's equal.
    assert PlanningProblem.from_map(renamed).checker is a
    fresh = CollisionChecker.for_map(m)
    assert np.array_equal(fresh.clearance_grid, a.clearance_grid)
    rng = np.random.default_rng(3)
    poses = np.column_stack([
        rng.uniform(0, 60, 300), rng.uniform(0, 20, 300), rng.uniform(-np.pi, np.pi, 300)
    ])  # fmt: skip
    assert np.array_equal(fresh.poses_free(poses), a.poses_free(poses))
    assert not np.array_equal(a.poses_free(poses), b.poses_free(poses))


@pytest.mark.parametrize(
    ("map_name", "planner", "reverse"),
    [("reverse_bay", "hybrid-a-star", True), ("garage", "improved-rrt-connect", False)],
)
def test_warm_caches_give_the_cold_answer(map_name, planner, reverse):
    """A query on a checker warmed by other queries (both gears) plans what a cold one does."""
    out = _run(
        f"""
        from rrtdrive import CollisionChecker
        m = builtin_map({map_name!r})
        b = Budget(max_iterations=3000, max_time_s=30)
        cold = PlanningProblem(m, CollisionChecker.for_map(m), m.start, m.goal, m.vehicle,
                               reverse={reverse})
        a = make_planner({planner!r}).solve(cold, np.random.default_rng(7), b)
        warm = PlanningProblem.from_map(m, reverse={reverse})
        pose = pose_sampler(warm.checker, m.bounds, 1)
        for i in range(4):
            for pl in ("hybrid-a-star", "improved-rrt-connect"):
                p = PlanningProblem(m, warm.checker, pose(), pose(), m.vehicle, reverse=i % 2 == 0)
                make_planner(pl).solve(p, np.random.default_rng(i), Budget(400, 1.0))
        c = make_planner({planner!r}).solve(warm, np.random.default_rng(7), b)
        print(json.dumps({{"a": a.status.name, "c": c.status.name,
                          "same": bool(np.array_equal(a.path.samples, c.path.samples))}}))
        """,
        timeout=120,
        prelude=_POSES,
    )
    assert out["a"] == "SOLVED" and out == {"a": "SOLVED", "c": "SOLVED", "same": True}


def test_kept_results_do_not_pin_evicted_checkers():
    """A service storing every result (solved or not) keeps no checker alive by it."""
    out = _run(
        """
        import gc, json
        import numpy as np
        from rrtdrive import Budget, CollisionChecker, builtin_map
        from rrtdrive.planning import PlanningProblem, make_planner, base, checker_cache
        from rrtdrive.planning.improved import boxed
        kept = []
        for name in ("garage", "no_path", "dead_end"):
            m = builtin_map(name)
            for planner, rev in (("improved-rrt-connect", False), ("hybrid-a-star", True),
                                 ("rrt-connect", False)):
                p = PlanningProblem.from_map(m, reverse=rev)
                kept.append(make_planner(planner).solve(
                    p, np.random.default_rng(0), Budget(max_iterations=300, max_time_s=5)))
        del p  # the last problem holds its checker, as it should
        checker_cache._CHECKERS.clear()
        boxed._fan_room.cache_clear()
        gc.collect()
        live = sum(isinstance(o, CollisionChecker) for o in gc.get_objects())
        print(json.dumps({"live": live, "statuses": sorted({r.status.name for r in kept})}))
        """,
        timeout=120,
    )
    assert len(out["statuses"]) >= 2, out  # solved and failed results both kept
    assert out["live"] == 0, out


def test_cached_checker_grid_origin_is_read_only():
    m = builtin_map("garage")
    checker = PlanningProblem.from_map(m).checker
    assert checker.grid.clearance.flags.writeable is False  # the field is protected
    assert checker.grid.origin.flags.writeable is False
