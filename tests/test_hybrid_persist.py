"""Hybrid A* goes on through rejected goal connections before it gives up (``persist``).

A goal 3.8 m from the start in open space, turned 35 degrees: every shot from the
first few nodes is a tight Reeds-Shepp word whose steering ramps fail, and each search
of the ladder (first, wider-turning, finer) stopped after its 16 + 16 rejected
connections, with 99 % of the budget unspent. The ``persist`` search goes on until one
passes. Judged by ``verify_path`` with the sharpness bound and against shapely.
"""

from __future__ import annotations

import numpy as np
import shapely

from rrtdrive.maps import Map, Obstacle
from rrtdrive.planning import PlanningProblem
from rrtdrive.planning.hybrid import HybridAStar
from rrtdrive.types import Budget, PlanStatus, Pose, VehicleParams
from rrtdrive.vehicle import footprint_polygon
from rrtdrive.verify import verify_path

BUDGET = Budget(max_iterations=20_000, max_time_s=1e6)


def _near_goal_map() -> Map:
    """A random map of the planner's fuzzing (seed 2, query 55)."""
    obstacles = (
        Obstacle((4.715381434393857, 7.69183423406434), (5.785621631333534, 2.292011922636508),
                 -0.02412099384617461),
        Obstacle((2.662463996983378, 0.4987194943622633), (4.112778976118882, 1.6834881493346154),
                 2.5712204037963167),
        Obstacle((0.5571281002101531, 4.230661650117109), (7.499124162139369, 2.395247604575833),
                 0.7407328802186695),
        Obstacle((0.726936468361048, 25.428324530784177), (4.361840693528384, 6.635227811807588),
                 1.2410306177990424),
    )  # fmt: skip
    return Map(
        "near_goal", (0.0, 0.0, 20.110980892960097, 36.668811251180365), obstacles,
        Pose(12.366699056663032, 17.71303526751537, 0.44642136318259196),
        Pose(13.875483598528259, 14.236220282071079, 1.0550091693156975),
    )  # fmt: skip


def test_a_near_goal_is_solved_by_going_on_through_rejections() -> None:
    m = _near_goal_map()
    problem = PlanningProblem.from_map(m, reverse=True)
    # (Without widening either: since session 36 the tightest search turning wider after
    # rejected connections solves it too.)
    before = HybridAStar(persist=False, wide_radius_factor=1.02).solve(
        problem, np.random.default_rng(0), BUDGET
    )
    assert before.status is PlanStatus.NO_PATH_IN_BUDGET
    assert "goal connections could not be made drivable" in before.message
    assert before.iterations < 200  # it gave up with the budget almost all left
    res = HybridAStar().solve(problem, np.random.default_rng(0), BUDGET)
    assert res.success, res.message
    assert res.stats["persist_search"] == 1.0
    assert "going on through rejected connections" in res.message
    assert res.iterations <= BUDGET.max_iterations
    assert verify_path(m, res.path, max_sharpness=0.2).ok
    # The whole body stays 0.15 m clear (the re-check's 5 mm aside), by shapely.
    car = VehicleParams()
    walls = shapely.union_all([
        shapely.box(-5, -5, 25.1, 41.7).difference(shapely.box(*m.bounds)),
        *(o.polygon() for o in m.obstacles),
    ])  # fmt: skip
    least = min(footprint_polygon(tuple(r[:3]), car).distance(walls) for r in res.path.samples)
    assert least >= 0.145
    s = res.path.samples
    assert np.allclose(s[0, :3], m.start.as_tuple()) and np.allclose(s[-1, :3], m.goal.as_tuple())


def test_persisting_is_deterministic_and_counted() -> None:
    problem = PlanningProblem.from_map(_near_goal_map(), reverse=True)
    a = HybridAStar().solve(problem, np.random.default_rng(0), BUDGET)
    b = HybridAStar().solve(problem, np.random.default_rng(7), BUDGET)
    assert a.iterations == b.iterations
    np.testing.assert_array_equal(a.path.samples, b.path.samples)
    # A budget too small for the persisting search: it stops, counted, with its reason.
    short = HybridAStar().solve(
        problem, np.random.default_rng(0), Budget(max_iterations=120, max_time_s=1e6)
    )
    assert not short.success and short.iterations <= 120
    assert short.status is PlanStatus.NO_PATH_IN_BUDGET


def test_a_hybrid_proof_names_the_clearance_it_holds_for() -> None:
    from rrtdrive.maps import builtin_map

    res = HybridAStar().solve(
        PlanningProblem.from_map(builtin_map("kerbside")), np.random.default_rng(0), BUDGET
    )
    assert res.status is PlanStatus.PROVEN_UNREACHABLE
    # Forward, the kerbside gap is proven out of reach by every search, down to the
    # tight one keeping 0.05 m: the proof holds for paths keeping that much.
    assert "keeping only 0.05 m body clearance" in res.message
    assert res.message.endswith(
        "(a proof for paths keeping 0.05 m body clearance, on that grid only)"
    )
