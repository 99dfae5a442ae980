"""The verifier's turn, end-pose, cusp and clearance measures (session 34 audit findings).

References are analytic: a straight drive beside an axis-aligned box, yaws that turn
while the positions run straight, rows moved by known amounts.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rrtdrive.cli import main
from rrtdrive.geometry import wrap_angle
from rrtdrive.maps import Map, Obstacle, save_map
from rrtdrive.types import Path, Pose
from rrtdrive.verify import verify_path

KAPPA_MAX = 1 / 6


def _straight(x0: float = 10.0, x1: float = 30.0, y: float = 20.0, step: float = 0.25):
    x = np.arange(x0, x1 + 1e-9, step)
    return np.column_stack([x, np.full_like(x, y), np.zeros_like(x), np.zeros_like(x),
                            np.ones_like(x)])  # fmt: skip


def _open_map(rows: np.ndarray, obstacles=(), bounds=(0.0, 0.0, 60.0, 60.0)) -> Map:
    return Map("open", bounds, tuple(obstacles), Pose(*rows[0, :3]), Pose(*rows[-1, :3]))


@settings(max_examples=30, deadline=None)
@given(st.floats(0.3, 4.0), st.floats(0.05, 0.25))
def test_a_yaw_that_turns_faster_than_the_car_can_fails_the_curvature(rate, step):
    # The positions run straight (no Menger curvature at all); the yaw turns `rate` rad/m.
    rows = _straight(step=step)
    rows[:, 2] = wrap_angle(rate * (rows[:, 0] - rows[0, 0]))
    m = Map("open", (0.0, 0.0, 60.0, 60.0), (), Pose(*rows[0, :3]), Pose(*rows[-1, :3]))
    check = verify_path(m, Path(rows, np.zeros((0, 2))), heading_tol_deg=math.inf)
    assert not check.curvature_ok
    # 2 sin(rate step / 2) / step, the curvature of an arc turning that much over the chord.
    # (Less 2e-6 rad of the turn that the JSON's rounding may put there: 2e-6 / step.)
    expected = 2 * math.sin(0.5 * rate * step) / step
    assert check.max_discrete_curvature == pytest.approx(expected, rel=1e-9, abs=2e-6 / step)


def test_turning_on_the_spot_between_gear_changes_fails():
    # The audit's path: 30 deg turns over 0.2 m moves, each its own two-row gear segment.
    rows = [[10.0, 20.0, 0.0, 0.0, 1.0], [11.0, 20.0, 0.0, 0.0, 1.0]]
    x, yaw, gear = 11.0, 0.0, -1.0
    for _ in range(6):
        rows.append([x, 20.0, yaw, 0.0, gear])
        x, yaw = x + 0.2 * gear, yaw + math.radians(30)
        rows.append([x, 20.0, yaw, 0.0, gear])
        gear = -gear
    m = Map("open", (0.0, 0.0, 40.0, 40.0), (), Pose(10.0, 20.0, 0.0), Pose(x, 20.0, yaw))
    check = verify_path(m, Path(np.array(rows), np.zeros((0, 2))))
    assert not check.curvature_ok and check.max_discrete_curvature > 2.5


def test_a_yaw_zigzag_about_the_travel_fails():
    # Every row's yaw +-60 deg off the travel: their mean matches each chord, their turn not.
    rows = _straight()
    rows[:, 2] = np.where(np.arange(len(rows)) % 2 == 0, 1.0, -1.0) * math.radians(60)
    m = _open_map(rows)
    check = verify_path(m, Path(rows, np.zeros((0, 2))))
    assert check.travel_heading_err_deg < 1e-6  # the mean yaw is along every chord
    assert not check.curvature_ok


def test_end_rows_must_have_the_start_and_goal_yaw():
    rows = _straight()
    m = _open_map(rows)
    rows[0, 2] = 0.1
    check = verify_path(m, Path(rows, np.zeros((0, 2))), curvature_tol=math.inf)
    assert not check.endpoints_ok
    assert check.endpoint_yaw_err_deg == pytest.approx(math.degrees(0.1))
    rows[0, 2], rows[-1, 0] = 0.0, rows[-1, 0] + 0.002
    check = verify_path(m, Path(rows, np.zeros((0, 2))), max_sample_spacing=1.0)
    assert not check.endpoints_ok and check.endpoint_err_m == pytest.approx(0.002)


def test_a_cusp_that_moves_names_its_row():
    ahead = _straight(10.0, 15.0)
    back = ahead[::-1].copy()
    back[:, 4] = -1.0
    back[:, 1] += 0.05  # the reverse drive starts 5 cm aside: the car jumped
    rows = np.vstack([ahead, back])
    m = _open_map(rows)
    check = verify_path(m, Path(rows, np.zeros((0, 2))))
    assert not check.cusps_ok and check.first_bad_cusp_row == len(ahead)
    assert check.cusp_gap_m == pytest.approx(0.05)


@settings(max_examples=40, deadline=None)
@given(st.floats(0.01, 2.0), st.floats(0.01, 2.0), st.floats(-3.0, 3.0))
def test_least_clearance_is_the_distance_to_a_box_beside_the_drive(gap, edge_gap, shift):
    # The body spans y in [20 - 0.9, 20 + 0.9]: a box whose lower side is `gap` above it,
    # and the top of the bounds `edge_gap` above the body on the other side, mirrored.
    rows = _straight()
    box = Obstacle((20.0 + shift, 20.9 + gap + 1.0), (4.0, 2.0))
    bounds = (0.0, 20.0 - 0.9 - edge_gap, 60.0, 60.0)
    m = _open_map(rows, [box], bounds)
    check = verify_path(m, Path(rows, np.zeros((0, 2))), clearance=0.0)
    assert check.min_clearance_m == pytest.approx(min(gap, edge_gap), abs=1e-9)
    want = min(gap, edge_gap)
    assert verify_path(m, Path(rows, np.zeros((0, 2))), clearance=want - 1e-4).ok
    tight = verify_path(m, Path(rows, np.zeros((0, 2))), clearance=want + 1e-4)
    assert not tight.ok and tight.failed == ("clearance_ok",)


def test_verify_cli_clearance_and_the_json_of_an_empty_plan(tmp_path, capsys):
    rows = _straight()
    box = Obstacle((20.0, 20.9 + 0.3 + 1.0), (4.0, 2.0))
    m = _open_map(rows, [box])
    save_map(m, tmp_path / "m.json")
    plan = {"path": rows.tolist(), "start": rows[0, :3].tolist(), "goal": rows[-1, :3].tolist()}
    (tmp_path / "p.json").write_text(json.dumps(plan))
    args = ["verify", str(tmp_path / "p.json"), str(tmp_path / "m.json")]
    assert main([*args, "--clearance", "0.25"]) == 0
    assert main([*args, "--clearance", "0.35", "--json", str(tmp_path / "v.json")]) == 1
    out = capsys.readouterr().out
    assert "FAIL clearance to obstacles and bounds" in out and "0.3000 m (min 0.35)" in out
    doc = json.loads((tmp_path / "v.json").read_text())
    assert doc["failed"] == ["clearance_ok"] and doc["min_clearance_m"] == pytest.approx(0.3)
    with pytest.raises(SystemExit) as bad:
        main([*args, "--clearance", "-1"])
    assert bad.value.code == 2 and "--clearance" in capsys.readouterr().err
    # An empty path: the same JSON fields as any plan, every check failed (a CI gate on
    # "failed" passed it before: the document had no such field).
    (tmp_path / "e.json").write_text(json.dumps({"path": [], "status": "no_path_in_budget"}))
    empty = ["verify", str(tmp_path / "e.json"), str(tmp_path / "m.json"), "--json", "-"]
    assert main(empty) == 1
    doc = json.loads(capsys.readouterr().out)
    assert doc["ok"] is False and "collision_free" in doc["failed"] and doc["rows"] == 0


def test_the_plan_declares_its_clearance_and_verify_requires_it(tmp_path, capsys):
    plan = tmp_path / "plan.json"
    assert main(["plan", "parking_lot", "--json", str(plan)]) == 0
    doc = json.loads(plan.read_text())
    assert doc["body_clearance_m"] == pytest.approx(0.15)
    assert main(["verify", str(plan)]) == 0
    out = capsys.readouterr().out
    assert "(min 0.148: the plan's 0.15 less 2 mm)" in out, out
    # A plan claiming more than its path keeps fails on it, by default.
    least = float(out.split("clearance to obstacles and bounds")[1].split()[0])
    doc["body_clearance_m"] = least + 0.01
    plan.write_text(json.dumps(doc))
    assert main(["verify", str(plan)]) == 1
    assert "FAIL clearance to obstacles and bounds" in capsys.readouterr().out
    assert main(["verify", str(plan), "--clearance", "0"]) == 0  # asked for less
    # Baselines keep none: null, and verify asks for no contact only.
    assert main(["plan", "parking_lot", "--planner", "rrt", "--json", str(plan)]) in (0, 1)
    assert json.loads(plan.read_text())["body_clearance_m"] is None


@pytest.mark.parametrize("claim", ["0.3", True, float("nan"), -0.1, [0.15]])
def test_a_malformed_declared_clearance_is_bad_input(claim, tmp_path, capsys):
    # It was ignored (exit 0, "min 0"): a claim of 0.3 m as a string passed unchecked.
    plan = tmp_path / "plan.json"
    assert main(["plan", "overtake", "--json", str(plan)]) == 0
    doc = json.loads(plan.read_text())
    doc["body_clearance_m"] = claim
    plan.write_text(json.dumps(doc))
    capsys.readouterr()
    assert main(["verify", str(plan)]) == 2
    assert "plan.body_clearance_m: expected a number >= 0" in capsys.readouterr().err


def _arc(x0, y0, yaw0, kappa, gear, length, step=0.2):
    """Rows of a steady-steering arc from its closed form, nose yaw, in either gear."""
    s = np.linspace(0.0, length, int(round(length / step)) + 1)
    yaw = yaw0 + gear * kappa * s
    if kappa == 0.0:
        x, y = x0 + gear * s * math.cos(yaw0), y0 + gear * s * math.sin(yaw0)
    else:
        x = x0 + (np.sin(yaw) - math.sin(yaw0)) / kappa
        y = y0 - (np.cos(yaw) - math.cos(yaw0)) / kappa
    return np.column_stack([x, y, yaw, np.full_like(s, kappa), np.full_like(s, float(gear))])


@pytest.mark.parametrize("kappa", [0.16, -0.1])
def test_the_kappa_column_must_be_the_steering_curvature_in_both_gears(kappa):
    # kappa = tan(delta) / L in both gears: a reverse segment whose column has the other
    # sign (the turn's curvature along the travel) or none was "OK, every check passed"
    # (a user audit, session 35): the positions and yaws alone were checked.
    fwd = _arc(20.0, 20.0, 0.3, kappa, 1, 6.0)
    back = _arc(*fwd[-1, :3], kappa, -1, 6.0)
    rows = np.vstack([fwd, back])
    m = _open_map(rows)
    good = verify_path(m, Path(rows, np.zeros((0, 2))))
    assert good.ok and good.kappa_column_err < 1e-6, good.failed
    for wrong in (-kappa, 0.0):
        bad_rows = rows.copy()
        bad_rows[len(fwd):, 3] = wrong  # the reverse segment only
        bad = verify_path(m, Path(bad_rows, np.zeros((0, 2))))
        assert bad.failed == ("kappa_ok",)
        assert bad.kappa_column_err == pytest.approx(abs(kappa - wrong), rel=1e-3)
        assert bad.worst_kappa_row >= len(fwd)


@settings(max_examples=30, deadline=None)
@given(st.floats(-KAPPA_MAX, KAPPA_MAX), st.floats(-0.09, 0.09), st.sampled_from([1, -1]))
def test_a_clothoid_column_passes(k0, rate, gear):
    # Curvature changing linearly along the path (a steering ramp, clipped at the lock:
    # a peak there lies above both its steps' means by half a step of the ramp); the
    # check must not fail true columns (closed form by fine integration).
    n, fine = 31, 200
    s = np.linspace(0.0, 6.0, (n - 1) * fine + 1)
    k = np.clip(k0 + rate * s, -KAPPA_MAX, KAPPA_MAX)
    ds = s[1] - s[0]
    yaw = 0.2 + gear * np.concatenate([[0.0], np.cumsum(0.5 * (k[1:] + k[:-1]) * ds)])
    mid = 0.5 * (yaw[1:] + yaw[:-1])
    x = 20.0 + gear * np.concatenate([[0.0], np.cumsum(np.cos(mid) * ds)])
    y = 20.0 + gear * np.concatenate([[0.0], np.cumsum(np.sin(mid) * ds)])
    rows = np.column_stack([x, y, yaw, k, np.full_like(s, float(gear))])[::fine]
    check = verify_path(_open_map(rows), Path(rows, np.zeros((0, 2))))
    assert check.kappa_ok, (check.kappa_column_err, check.worst_kappa_row)
