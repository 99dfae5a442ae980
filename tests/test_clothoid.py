"""Clothoid turns and the continuous-curvature default of the improved planner (issue 12)."""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import solve_ivp
from scipy.interpolate import BSpline
from scipy.spatial import cKDTree

from rrtdrive.cli import main as cli_main
from rrtdrive.maps import BUILTIN_MAPS, TIGHT_MAP_NAMES, builtin_map
from rrtdrive.planning.base import PlanningProblem, cached_checker
from rrtdrive.planning.dubins import dubins_paths
from rrtdrive.planning.improved import ImprovedRRTConnect
from rrtdrive.planning.smoothing import (
    CurveKind,
    SmoothingConfig,
    clothoid_turn,
    fit_bspline,
    interval_sharpness,
    make_drivable,
    max_sharpness,
    parameter_grid,
    sample_turn,
    steer_rate_speed_limit,
)
from rrtdrive.planning.smoothing.clothoid import sharpness_levels, turn_circle
from rrtdrive.planning.smoothing.clothoid_curve import polygon_curve, sample_pieces
from rrtdrive.types import Budget, InputError, Pose, VehicleParams
from rrtdrive.verify import verify_path

KAPPA = 1.0 / 6.0
L = 2.51
BOUND = 0.2
SIGMA = BOUND / L


def integrate_turn(turn, s_end: float) -> np.ndarray:
    """Pose after ``s_end`` along the turn's curvature profile, by numerical integration."""
    total = turn.length

    def kappa(s: float) -> float:
        q = s if s <= 0.5 * total else total - s
        return math.copysign(min(turn.sigma * q, turn.kappa), turn.theta)

    sol = solve_ivp(
        lambda s, z: [math.cos(z[2]), math.sin(z[2]), kappa(s)],
        (0.0, s_end), [0.0, 0.0, 0.0], rtol=1e-10, atol=1e-12, max_step=0.02,
    )  # fmt: skip
    return sol.y[:, -1]


@pytest.mark.parametrize(
    ("theta", "kappa", "sigma"),
    [(math.pi / 2, KAPPA, SIGMA), (-2.8, KAPPA, SIGMA), (0.1, KAPPA, SIGMA),
     (1.2, 0.1, 0.01), (-0.4, KAPPA, 0.2)],
)  # fmt: skip
def test_turn_matches_numerical_integration_of_its_curvature(theta, kappa, sigma):
    turn = clothoid_turn(theta, kappa, sigma)
    for frac in (0.2, 0.5, 0.77, 1.0):
        s = frac * turn.length
        row = sample_turn(turn, np.array([s]))[0]
        assert row[:3] == pytest.approx(integrate_turn(turn, s), abs=1e-6)
    # The end lies on the outgoing leg at the tangent length from the corner (T, 0),
    # heading along it, with the curvature back at 0.
    end = sample_turn(turn, np.array([turn.length]))[0]
    corner = np.array([turn.tangent, 0.0])
    out = corner + turn.tangent * np.array([math.cos(theta), math.sin(theta)])
    assert end[:2] == pytest.approx(out, abs=1e-9)
    assert end[2] == pytest.approx(theta, abs=1e-12) and end[3] == pytest.approx(0.0, abs=1e-12)
    assert sample_turn(turn, np.array([0.0]))[0] == pytest.approx([0, 0, 0, 0], abs=1e-15)
    assert turn.kappa <= kappa + 1e-12


def test_turn_kinds_and_the_inner_circle():
    # Small deflection: clothoid-clothoid with the peak sqrt(theta sigma) below kappa.
    small = clothoid_turn(0.1, KAPPA, SIGMA)
    assert small.arc == 0.0 and small.kappa == pytest.approx(math.sqrt(0.1 * SIGMA))
    big = clothoid_turn(2.0, KAPPA, SIGMA)
    assert big.kappa == KAPPA and big.arc > 0.0 and big.clothoid == pytest.approx(KAPPA / SIGMA)
    r_in, d = turn_circle(KAPPA, SIGMA)
    assert big.tangent == pytest.approx(r_in * math.tan(1.0) + d, abs=1e-12)
    assert clothoid_turn(math.pi, KAPPA, SIGMA).tangent == math.inf
    assert clothoid_turn(0.0, KAPPA, SIGMA).tangent == 0.0


def test_gentler_sharpness_needs_longer_legs():
    levels = sharpness_levels(BOUND, 0.02, L, 0.97)
    assert levels[0] * L == pytest.approx(0.97 * BOUND) and levels[-1] * L == pytest.approx(0.02)
    for theta in (0.05, 0.5, 1.5, 2.9):
        tangents = [clothoid_turn(theta, KAPPA, float(s)).tangent for s in levels]
        assert all(a < b for a, b in zip(tangents, tangents[1:], strict=False))


@settings(max_examples=60, deadline=None)
@given(
    theta=st.floats(-2.9, 2.9).filter(lambda t: abs(t) > 1e-3),
    leg_in=st.floats(0.0, 40.0),
    leg_out=st.floats(0.0, 40.0),
    heading=st.floats(-math.pi, math.pi),
    sigma=st.sampled_from(list(sharpness_levels(BOUND, 0.02, L, 0.97))),
)
def test_random_corners_give_exact_ends_and_bounded_curvature_and_sharpness(
    theta, leg_in, leg_out, heading, sigma
):
    turn = clothoid_turn(theta, KAPPA * 0.97, sigma)
    a_len, b_len = turn.tangent + leg_in, turn.tangent + leg_out
    corner = np.array([3.0, -2.0])
    u = np.array([math.cos(heading), math.sin(heading)])
    v = np.array([math.cos(heading + theta), math.sin(heading + theta)])
    pts = np.array([corner - a_len * u, corner, corner + b_len * v])
    pieces = polygon_curve(pts, KAPPA * 0.97, sigma)
    assert pieces is not None
    rows, _ = sample_pieces(pieces, 0.25)
    assert rows[0, :2] == pytest.approx(pts[0], abs=1e-9)
    assert rows[-1, :2] == pytest.approx(pts[-1], abs=1e-9)
    dyaw = (rows[-1, 2] - (heading + theta) + math.pi) % (2 * math.pi) - math.pi
    assert abs(dyaw) < 1e-9
    assert rows[0, 3] == 0.0 and abs(rows[-1, 3]) < 1e-12
    assert np.abs(rows[:, 3]).max() <= KAPPA + 1e-12
    assert max_sharpness(rows, L) <= BOUND + 1e-6
    gaps = np.hypot(*np.diff(rows[:, :2], axis=0).T)
    assert gaps.max() <= 0.25 + 1e-9
    # Continuous curvature: between rows it changes by at most sigma times the arc.
    assert np.all(np.abs(np.diff(rows[:, 3])) <= sigma * gaps * 1.001 + 1e-12)


def test_sharpness_of_clothoid_rows_is_the_design_value():
    turn = clothoid_turn(1.0, KAPPA, SIGMA)
    rows = sample_turn(turn, np.linspace(0.0, turn.length, 50))
    rate = interval_sharpness(rows, L)
    # Largest where kappa = 0: L sigma, the chord in place of the arc erring high.
    assert rate.max() == pytest.approx(L * SIGMA, rel=1e-4) and rate.max() >= L * SIGMA
    assert steer_rate_speed_limit(0.2, 0.4) == pytest.approx(2.0)
    assert steer_rate_speed_limit(0.0, 0.4) == math.inf
    assert steer_rate_speed_limit(0.2, None) is None


def test_config_fields_are_validated():
    for kwargs, name in (
        ({"curve": "spline"}, "curve"),  # "clothoid" as text is the enum
        ({"max_sharpness": 0.0}, "max_sharpness"),
        ({"min_sharpness": -1.0}, "min_sharpness"),
        ({"min_sharpness": 0.5}, "min_sharpness"),
        ({"wheelbase": 0.0}, "wheelbase"),
    ):
        with pytest.raises(InputError, match=f"smoothing.{name}"):
            SmoothingConfig(**kwargs)
    assert SmoothingConfig().curve is CurveKind.CLOTHOID and SmoothingConfig().max_sharpness == 0.2


def test_make_drivable_default_starts_and_ends_straight_within_the_bound():
    m = builtin_map("parking_lot")
    checker = cached_checker(m)
    res = ImprovedRRTConnect().solve(
        PlanningProblem.from_map(m), np.random.default_rng(3), Budget(max_time_s=1e6)
    )
    raw = res.raw_path
    out = make_drivable(raw, m.start, m.goal, checker, SmoothingConfig(wheelbase=L))
    assert out.ok and out.max_sharpness <= 0.97 * BOUND + 1e-12
    s = out.samples
    assert s[0, 3] == 0.0 and s[-1, 3] == 0.0
    assert max_sharpness(s, L) <= BOUND
    assert out.max_curvature <= 0.97 * KAPPA + 1e-12


# The tight maps (issue 13) need the kinematic search or reverse gear: tests/test_tight_maps.py.
@pytest.mark.parametrize(
    "name", [n for n in BUILTIN_MAPS if n != "no_path" and n not in TIGHT_MAP_NAMES]
)
def test_every_improved_path_on_the_builtin_maps_meets_the_bound(name):
    m = builtin_map(name)
    problem = PlanningProblem.from_map(m)
    for seed in range(10):
        res = ImprovedRRTConnect().solve(
            problem, np.random.default_rng(seed), Budget(max_time_s=1e6)
        )
        assert res.success, (seed, res.message)
        assert verify_path(m, res.path, max_sharpness=0.2).ok
        s = res.path.samples
        assert max_sharpness(s, m.vehicle.wheelbase) <= BOUND, seed
        assert s[0, 3] == 0.0 and s[-1, 3] == 0.0
        assert res.stats["max_sharpness"] <= BOUND


def test_a_slower_actuator_tightens_the_bound():
    m = builtin_map("parking_lot")
    slow = dataclasses.replace(m, vehicle=VehicleParams(max_steer_rate=0.3))
    res = ImprovedRRTConnect().solve(
        PlanningProblem.from_map(slow), np.random.default_rng(0), Budget(max_time_s=1e6)
    )
    assert res.success and max_sharpness(res.path.samples, L) <= 0.15


def test_the_paper_setting_still_gives_the_degree_2_bspline():
    m = builtin_map("parking_lot")
    res = ImprovedRRTConnect(smoothing={"curve": CurveKind.BSPLINE}).solve(
        PlanningProblem.from_map(m), np.random.default_rng(0), Budget(max_time_s=1e6)
    )
    assert res.success and "control points" in res.message
    spl = fit_bspline(res.path.waypoints, 2)
    assert isinstance(spl, BSpline) and spl.k == 2
    dense = spl(parameter_grid(spl, 0.005))
    # Every sample lies on the degree-2 B-spline of the waypoints.
    assert cKDTree(dense).query(res.path.xy)[0].max() < 0.005
    # ... whose curvature jumps: far over the bound of the default.
    assert max_sharpness(res.path.samples, L) > 1.0
    assert not verify_path(m, res.path, max_sharpness=0.2).sharpness_ok


def test_dubins_polygon_corners_and_the_cc_fallback_word():
    start, goal = Pose(0.0, 0.0, 0.3), Pose(20.0, 5.0, 2.5)
    for path in dubins_paths(start, goal, 6.0):
        poly = path.polygon()
        assert poly[0] == pytest.approx([0.0, 0.0]) and poly[-1] == pytest.approx([20.0, 5.0])
        first = math.atan2(*(poly[1] - poly[0])[::-1])
        last = math.atan2(*(poly[-1] - poly[-2])[::-1])
        assert abs(math.remainder(first - start.yaw, 2 * math.pi)) < 1e-9
        assert abs(math.remainder(last - goal.yaw, 2 * math.pi)) < 1e-9


def test_plan_json_reports_sharpness_and_the_paper_flag(tmp_path, capsys):
    out = tmp_path / "plan.json"
    assert cli_main(["plan", "parking_lot", "--json", str(out)]) == 0
    doc = json.loads(out.read_text())
    assert doc["max_sharpness"] <= BOUND
    # The default car's actuator (0.4 rad/s) follows the path at 2 m/s or faster.
    assert doc["steer_rate_speed_limit"] == pytest.approx(0.4 / doc["max_sharpness"], rel=1e-2)
    assert doc["steer_rate_speed_limit"] >= 2.0
    assert {"path", "waypoints", "length_m", "max_curvature"} <= set(doc)
    assert cli_main(["plan", "parking_lot", "--paper-smoothing", "--json", str(out)]) == 0
    paper = json.loads(out.read_text())
    assert paper["max_sharpness"] > 1.0 and "control points" in paper["message"]
    assert cli_main(["plan", "parking_lot", "--planner", "rrt", "--paper-smoothing"]) == 2
    assert "--paper-smoothing" in capsys.readouterr().err
