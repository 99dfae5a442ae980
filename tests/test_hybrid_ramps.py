"""Hybrid A* with continuous curvature: the steering ramps, and the paths it returns by default."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from rrtdrive.geometry import wrap_angle
from rrtdrive.maps import TIGHT_MAP_NAMES, builtin_map
from rrtdrive.planning.base import PlanningProblem
from rrtdrive.planning.hybrid import HybridAStar, HybridConfig, arc_poses
from rrtdrive.planning.hybrid.escalation import stage_of
from rrtdrive.planning.hybrid.ramps import ramped_segment
from rrtdrive.planning.improved import ImprovedRRTConnect
from rrtdrive.planning.smoothing import max_sharpness
from rrtdrive.types import Budget, Path, Pose
from rrtdrive.verify import verify_path

L = 2.51
KAPPA_MAX = 1.0 / 6.0
KS = KAPPA_MAX / 1.02  # the search's curvature
DELTA_MAX = math.atan(L * KAPPA_MAX)
RATE = 0.18
BUDGET = Budget(max_iterations=20000, max_time_s=600.0)


def arc_chain(pieces: list[tuple[float, float]], gear: int, start=(3.0, -2.0, 0.7)) -> np.ndarray:
    """Rows ``[x, y, yaw]`` of arcs ``(kappa, length)`` driven one after another, 0.25 m apart."""
    rows = [np.array([start])]
    pose = start
    for kappa, length in pieces:
        n = max(1, math.ceil(length / 0.25))
        p = arc_poses(*pose, kappa, gear, np.linspace(0.0, length, n + 1))
        rows.append(p[1:])
        pose = tuple(p[-1])
    return np.vstack(rows)


levels = st.sampled_from([-KS, -KS / 2, 0.0, KS / 2, KS])
chains = st.lists(st.tuples(levels, st.floats(3.0, 8.0)), min_size=1, max_size=5)


@settings(max_examples=40, deadline=None)
@given(chains, st.sampled_from([1, -1]))
# Two cases a CI run found: full lock to full lock (the fit may give up), and a fit
# that lengthened the segment past its row spacing.
@example([(-KS, 3.0), (KS, 3.0)], 1)
@example([(-KS, 3.0), (0.0, 3.0)], 1)
def test_ramps_keep_the_rate_the_limit_and_the_exact_ends(pieces, gear) -> None:
    rows = arc_chain(pieces, gear)
    out = ramped_segment(rows, gear, RATE, L, DELTA_MAX)
    if out is None:
        # Arcs of 3 m or more leave room for every ramp (a full swing needs 4.4 m at
        # 0.18), but a swing from full lock to full lock has no steering left to win
        # back the heading the ramp loses: the fit may not converge there, and the
        # search then rejects the connection (an honest failure, never a bad path).
        kappas = [k for k, _ in pieces]
        swings = [abs(b - a) for a, b in zip(kappas[:-1], kappas[1:], strict=True)]
        assert swings and max(swings) > KS * 1.5
        return
    assert np.allclose(out[0, :3], rows[0], atol=1e-12)
    assert np.allclose(out[-1, :3], rows[-1], atol=1e-9)
    assert float(np.abs(out[:, 3]).max()) <= KAPPA_MAX + 1e-12
    # The rows over-state a ramp's rate by under 2 % (the chord and the smaller |kappa|).
    assert max_sharpness(out, L) <= RATE * 1.02
    assert float(np.hypot(*np.diff(out[:, :2], axis=0).T).max()) <= 0.2 + 1e-9
    # The rows are the integrated motion: the yaw turns by kappa per metre in the gear.
    ds = np.hypot(*np.diff(out[:, :2], axis=0).T)
    dyaw = np.diff(np.unwrap(out[:, 2]))
    mean_k = 0.5 * (out[1:, 3] + out[:-1, 3])
    # (to the trapezoid rule over a row gap: a ramp may start between two rows)
    assert np.allclose(dyaw, gear * mean_k * ds, atol=1e-3)


def test_a_single_arc_is_kept_as_it_is() -> None:
    rows = arc_chain([(KS, 5.0)], 1)
    out = ramped_segment(rows, 1, RATE, L, DELTA_MAX)
    assert out is not None and np.allclose(out[:, 3], KS)
    assert max_sharpness(out, L) == 0.0


def test_hybrid_paths_keep_the_sharpness_bound_by_default() -> None:
    m = builtin_map("parking_lot")
    problem = PlanningProblem.from_map(m)
    res = HybridAStar().solve(problem, np.random.default_rng(0), BUDGET)
    assert res.success and verify_path(m, res.path, max_sharpness=0.2).ok
    assert max_sharpness(res.path.samples, L) <= 0.2
    arcs = HybridAStar(curve="arcs").solve(problem, np.random.default_rng(0), BUDGET)
    assert arcs.success and max_sharpness(arcs.path.samples, L) > 0.2
    # The independent check sees the exact arcs' curvature jumps too.
    assert not verify_path(m, arcs.path, max_sharpness=0.2).sharpness_ok
    assert verify_path(m, arcs.path).ok


def _check_gears(m, path: Path) -> None:
    """Each gear segment verified between its own end poses (reverse ones as driven backwards)."""
    s = path.samples
    for row, pose in ((s[0], m.start), (s[-1], m.goal)):
        assert np.allclose(row[:2], (pose.x, pose.y), atol=1e-9)
        assert abs(wrap_angle(row[2] - pose.yaw)) <= 1e-9
    for a, b in path.segments():
        seg = s[a:b]
        rows = seg if seg[0, 4] > 0 else seg[::-1]
        sub = dataclasses.replace(m, start=Pose(*rows[0, :3]), goal=Pose(*rows[-1, :3]))
        assert verify_path(sub, Path(rows[:, :4], np.zeros((0, 2)))).ok


@pytest.mark.parametrize("name", TIGHT_MAP_NAMES)
def test_the_default_solves_the_tight_maps_in_reverse_within_the_bound(name: str) -> None:
    m = builtin_map(name)
    problem = dataclasses.replace(PlanningProblem.from_map(m), reverse=True)
    res = ImprovedRRTConnect().solve(problem, np.random.default_rng(0), BUDGET)
    assert res.success, res.message
    assert stage_of(res) in ("improved-rrt-connect", "dubins-fallback", "hybrid-a-star")
    assert max_sharpness(res.path.samples, L) <= 0.2
    assert res.path.max_curvature <= KAPPA_MAX + 1e-9
    _check_gears(m, res.path)


def test_config_names_the_curve() -> None:
    from rrtdrive.types import InputError

    with pytest.raises(InputError, match="hybrid.curve"):
        HybridConfig(curve="bspline")


#: Random start 11 of the coverage set (``random_goals.draw_goals("parking_lot", 30, 1,
#: "start")``): forward, every connection the first search finds runs through one tight
#: corner that the ramps cut below the clearance.
TIGHT_CORNER_START = Pose(59.2941018104284, 26.00974477372232, 2.135538579126397)


def test_rejected_ramps_search_again_with_more_clearance() -> None:
    m = builtin_map("parking_lot").with_query(start=TIGHT_CORNER_START)
    problem = PlanningProblem.from_map(m)
    # The unit steps of the search (long_steps=()) find only connections through that corner.
    # (persist=False: no search going on through the rejections either, session 18.)
    without = HybridAStar(
        ramp_margin=0.0, refinements=0, wide_radius_factor=1.02, long_steps=(), persist=False
    ).solve(problem, np.random.default_rng(0), BUDGET)
    assert not without.success and without.stats["connections"] == 16
    assert "could not be made drivable" in without.message
    res = HybridAStar(long_steps=()).solve(problem, np.random.default_rng(0), BUDGET)
    assert res.success and verify_path(m, res.path, max_sharpness=0.2).ok
    assert max_sharpness(res.path.samples, L) <= 0.2


@pytest.mark.parametrize("name", ["parking-reverse-in", "parallel-parking", "u-turn"])
def test_sharpness_measured_while_building_is_the_paths_own(name: str) -> None:
    """BuiltPath keeps the largest segment sharpness it measured: the whole path's value."""
    from rrtdrive.planning.base import Stopwatch
    from rrtdrive.planning.hybrid.query import hybrid_query
    from rrtdrive.planning.smoothing import SmoothingConfig
    from rrtdrive.sim.tasks import make_scenario

    task = make_scenario("parking", 3, reverse_in=True) if name == "parking-reverse-in" else (
        make_scenario(name, 3)
    )
    problem = PlanningProblem.from_map(task.map, reverse=True)
    answer = hybrid_query(
        problem, BUDGET, Stopwatch(BUDGET), HybridConfig(), True, SmoothingConfig(max_rounds=24)
    )
    assert answer.path is not None and answer.path.measured_sharpness is not None
    assert answer.path.max_sharpness(L) == max_sharpness(answer.path.rows, L)
    assert answer.path.measured_sharpness == (L, max_sharpness(answer.path.rows, L))
