"""Audit (session 47): ``rrtdrive plan``'s and the API's failure statuses, messages and JSON.

Every map is written here as a JSON file (SPEC §2's format) in ``tmp_path``; every number a
message or a diagnosis quotes is measured again with shapely from the car's parameters
(``VehicleParams``: length, width, wheelbase, turning radius), with its own body rectangle,
arcs and sweeps, not the package's footprint or measure functions.
"""

from __future__ import annotations

import json
import math
import re
import subprocess
import sys

import numpy as np
import pytest
import shapely
import shapely.ops

from rrtdrive.cli import build_parser, main
from rrtdrive.maps import load_map
from rrtdrive.planning import make_planner
from rrtdrive.planning.base import PlanningProblem, cached_checker
from rrtdrive.planning.diagnosis import DiagnosisKind
from rrtdrive.types import Budget, PlanStatus, Pose, VehicleParams

CAR = VehicleParams()
L, W, WB, R = CAR.length, CAR.width, CAR.wheelbase, CAR.min_turning_radius
REAR = (L - WB) / 2.0  # SPEC §1: symmetric overhangs, 0.895 m
FRONT = L - REAR  # 3.405 m ahead of the rear axle
KMAX = 1.0 / R
TIME_FIELDS = ("planning_time_s", "setup_time_s", "diagnosis_time_s")
#: What a message's 2-decimal metres may differ from the exact value by (rounding and the
#: diagnosis's 1 mm bisection, which reports a lower bound).
TOL_2DP = 0.006
#: The same for numbers printed with 1 decimal.
TOL_1DP = 0.051


# --- independent geometry ---------------------------------------------------------------


def body(x: float, y: float, yaw: float) -> shapely.Polygon:
    """The car's body rectangle at rear-axle pose (x, y, yaw), built from the parameters."""
    c, s = math.cos(yaw), math.sin(yaw)
    local = [(-REAR, -W / 2), (FRONT, -W / 2), (FRONT, W / 2), (-REAR, W / 2)]
    return shapely.Polygon([(x + c * a - s * b, y + s * a + c * b) for a, b in local])


def box(cx: float, cy: float, sx: float, sy: float) -> shapely.Polygon:
    return shapely.box(cx - sx / 2, cy - sy / 2, cx + sx / 2, cy + sy / 2)


def arc_pose(x: float, y: float, yaw: float, s: float, k: float) -> tuple[float, float, float]:
    """The rear axle after a signed arc length ``s`` at steady curvature ``k``."""
    if abs(k) < 1e-12:
        return x + s * math.cos(yaw), y + s * math.sin(yaw), yaw
    yaw2 = yaw + k * s
    return (x + (math.sin(yaw2) - math.sin(yaw)) / k, y - (math.cos(yaw2) - math.cos(yaw)) / k,
            yaw2)  # fmt: skip


def free(pose: tuple[float, float, float], solid: shapely.Geometry, bounds) -> bool:
    b = body(*pose)
    return not b.intersects(solid) and shapely.box(*bounds).contains_properly(b)


def run_length(pose, direction, k, solid, bounds, limit) -> float:
    """How far the body goes on one steady arc before it touches an obstacle (to 1 mm)."""
    step = 0.02
    s = 0.0
    while s + step <= limit:
        if not free(arc_pose(*pose, direction * (s + step), k), solid, bounds):
            lo, hi = s, s + step
            while hi - lo > 1e-3:
                mid = 0.5 * (lo + hi)
                lo, hi = (mid, hi) if free(arc_pose(*pose, direction * mid, k), solid, bounds) \
                    else (lo, mid)  # fmt: skip
            return lo
        s += step
    return limit


def best_steady_run(pose, direction, solid, bounds, limit, arcs: int = 41) -> float:
    """The longest run over ``arcs`` steady steerings from full left to full right lock."""
    return max(run_length(pose, direction, k, solid, bounds, limit)
               for k in np.linspace(-KMAX, KMAX, arcs))  # fmt: skip


def u_turn_sweep_width() -> float:
    """Across-street width a forward full-lock 180 deg turn sweeps (shapely union of bodies)."""
    poses = [arc_pose(0.0, 0.0, 0.0, s, KMAX) for s in np.linspace(0.0, math.pi * R, 721)]
    swept = shapely.union_all([body(*p) for p in poses])
    _, ymin, _, ymax = swept.bounds
    return ymax - ymin


# --- maps and runs ------------------------------------------------------------------------


def write_map(path, bounds, obstacles, start, goal, name="audit") -> str:
    doc = {
        "name": name,
        "bounds": list(bounds),
        "obstacles": [{"center": list(c), "size": list(s), "yaw": 0.0} for c, s in obstacles],
        "start": list(start),
        "goal": list(goal),
    }
    path.write_text(json.dumps(doc))
    return str(path)


def solid_of(obstacles) -> shapely.Geometry:
    return shapely.union_all([box(*c, *s) for c, s in obstacles])


def run_main(argv: list[str]) -> int:
    """``main(argv)``'s exit code; argparse's own errors leave by ``SystemExit``."""
    try:
        return main(argv)
    except SystemExit as exc:
        return int(exc.code)


def plan(capsys, args: list[str]) -> tuple[int, dict | None, str, str]:
    """``rrtdrive plan ARGS --json -`` in-process: exit code, JSON, stdout, stderr."""
    rc = run_main(["plan", *args, "--json", "-"])
    out, err = capsys.readouterr()
    return rc, (json.loads(out) if out.strip() else None), out, err


def numbers_in(text: str) -> list[float]:
    return [float(v) for v in re.findall(r"-?\d+\.\d+|-?\d+", text)]


def without_times(doc: dict) -> dict:
    return {k: v for k, v in doc.items() if k not in TIME_FIELDS}


# The maps (each a small room); built by functions so each test writes its own file.
GOAL_X = 30.0
WALL_GAP = 0.40  # behind the goal's rear bumper


def goal_backs_onto_wall(tmp_path):
    """A goal parked facing out with a wall 0.40 m behind its rear: reachable only in reverse."""
    wall = ((GOAL_X - REAR - WALL_GAP - 0.5, 20.0), (1.0, 20.0))
    obstacles = [wall]
    return write_map(tmp_path / "bay.json", (0, 0, 60, 40), obstacles, (45, 20, math.pi),
                     (GOAL_X, 20, 0.0)), obstacles  # fmt: skip


def street(tmp_path, width: float = 12.0):
    """A straight street ``width`` m wide (walls as obstacles); the goal behind, turned round."""
    lo, hi = 15.0 - width / 2, 15.0 + width / 2
    obstacles = [((40.0, lo / 2), (80.0, lo)), ((40.0, hi + (30 - hi) / 2), (80.0, 30 - hi))]
    return write_map(tmp_path / "street.json", (0, 0, 80, 30), obstacles, (10, 15, 0.0),
                     (40, 15, math.pi)), obstacles  # fmt: skip


def wall_with_gap(tmp_path, gap: float):
    """A wall across a 60 x 40 room with one gap of ``gap`` m centred at (30, 20)."""
    below = 20.0 - gap / 2
    above = 20.0 + gap / 2
    obstacles = [((30.0, below / 2), (1.0, below)), ((30.0, above + (40 - above) / 2),
                                                      (1.0, 40 - above))]  # fmt: skip
    return write_map(tmp_path / f"gap{gap}.json", (0, 0, 60, 40), obstacles, (10, 20, 0.0),
                     (50, 20, 0.0)), obstacles  # fmt: skip


def side_wall(tmp_path, at: str, gap: float):
    """An 8-12 m block ``gap`` m beside the left side of the start's or goal's body."""
    pose = (20.0, 20.0, 0.0) if at == "start" else (40.0, 20.0, 0.0)
    other = (45.0, 10.0, 0.0) if at == "start" else (10.0, 10.0, 0.0)
    block = ((pose[0], pose[1] + W / 2 + gap + 1.0), (12.0 if at == "start" else 8.0, 2.0))
    start, goal = (pose, other) if at == "start" else (other, pose)
    return write_map(tmp_path / f"side_{at}.json", (0, 0, 60, 40), [block], start, goal), [block]


# --- every status is reachable, with a message naming its cause ----------------------------


def test_solved_exits_0_with_a_path_from_start_to_goal(tmp_path, capsys):
    f = write_map(tmp_path / "open.json", (0, 0, 60, 40), [((30, 30), (4, 4))], (5, 10, 0),
                  (50, 10, 0))  # fmt: skip
    rc, doc, _, err = plan(capsys, [f, "--max-iterations", "500"])
    assert rc == 0 and doc["status"] == "solved" and doc["success"] is True
    assert doc["stage"] is not None and doc["diagnosis"] is None
    rows = np.array(doc["path"])
    assert rows[0, :2] == pytest.approx([5, 10], abs=1e-6)
    assert rows[-1, :2] == pytest.approx([50, 10], abs=1e-6)
    assert f"solved, length {doc['length_m']:.2f} m" in err  # the summary, on stderr


def test_goal_backing_onto_a_wall_names_the_wall_and_its_gap_and_suggests_reverse(tmp_path, capsys):
    f, obstacles = goal_backs_onto_wall(tmp_path)
    rc, doc, _, err = plan(capsys, [f, "--max-iterations", "2000"])
    assert rc == 1 and doc["success"] is False
    assert doc["status"] in {"proven_unreachable", "no_path_in_budget", "postprocess_failed"}
    diag = doc["diagnosis"]
    assert diag["kind"] == "needs_reverse"
    assert "--reverse" in diag["message"] and "reached in reverse" in diag["message"]
    # The wall: index and centre as the map gives them.
    (cx, cy), _ = obstacles[0]
    assert f"obstacle 0 at ({cx:.1f}, {cy:.1f})" in diag["message"]
    assert diag["numbers"]["obstacle"] == 0
    # Its gap behind the rear bumper, measured with shapely.
    solid, bounds = solid_of(obstacles), (0, 0, 60, 40)
    gap = body(GOAL_X, 20, 0.0).distance(solid)
    assert gap == pytest.approx(WALL_GAP, abs=1e-9)
    said = float(re.search(r"(\d+\.\d+) m behind its rear", diag["message"]).group(1))
    assert said == pytest.approx(gap, abs=TOL_2DP)
    assert diag["numbers"]["straight_gap_m"] == pytest.approx(gap, abs=2e-3)
    # "at most X m" on any steady steering backwards from the goal: no finer arc does better.
    at_most = float(re.search(r"has at most (\d+\.\d+) m", diag["message"]).group(1))
    mine = best_steady_run((GOAL_X, 20.0, 0.0), -1, solid, bounds, L)
    assert at_most == pytest.approx(mine, abs=TOL_2DP)
    assert f"car length ({L:.2f} m)" in diag["message"]
    # The summary on stderr carries the finding too.
    assert "FAILED (" + doc["status"] + ")" in err and "why: " + diag["message"] in err


def test_goal_backing_onto_a_wall_is_solved_with_reverse_in_reverse_gear(tmp_path, capsys):
    f, obstacles = goal_backs_onto_wall(tmp_path)
    rc, doc, _, _ = plan(capsys, [f, "--max-iterations", "2000", "--reverse"])
    assert rc == 0 and doc["reverse"] is True and doc["cusps"] >= 1
    rows = np.array(doc["path"])
    assert rows[-1, 4] == -1.0  # it backs into the pose
    solid = solid_of(obstacles)
    assert min(body(*r[:3]).distance(solid) for r in rows) > 0.0


def test_u_turn_street_names_its_width_and_the_width_a_u_turn_needs(tmp_path, capsys):
    f, obstacles = street(tmp_path, 12.0)
    rc, doc, _, _ = plan(capsys, [f, "--max-iterations", "2000"])
    assert rc == 1 and doc["status"] == "postprocess_failed"
    diag = doc["diagnosis"]
    assert diag["kind"] == "u_turn"
    msg = diag["message"]
    # The street: wall to wall, shapely.
    width = shapely.distance(box(*obstacles[0][0], *obstacles[0][1]),
                             box(*obstacles[1][0], *obstacles[1][1]))  # fmt: skip
    assert width == pytest.approx(12.0)
    m = re.search(r"the street at \((-?\d+\.\d), (-?\d+\.\d)\) is (\d+\.\d) m wide", msg)
    assert m, msg
    assert float(m.group(3)) == pytest.approx(width, abs=TOL_1DP)
    # Where: the body's centre at the start.
    cx = 10.0 + (FRONT - L / 2)
    assert (float(m.group(1)), float(m.group(2))) == pytest.approx((cx, 15.0), abs=TOL_1DP)
    # What a forward U-turn sweeps, by a shapely sweep of the body on the tightest circle,
    # plus the 0.15 m each side the message says it keeps.
    keep = float(re.search(r"keeping (\d+(?:\.\d+)?) m each side", msg).group(1))
    need = u_turn_sweep_width() + 2 * keep
    said_need = float(re.search(r"needs (\d+\.\d) m", msg).group(1))
    assert said_need == pytest.approx(need, abs=TOL_1DP)
    assert diag["numbers"]["needed_m"] == pytest.approx(need, abs=0.01)
    assert said_need > width
    assert "--reverse" in msg
    # No place in this street is wider than the street.
    widest = float(re.search(r"wider than (\d+\.\d) m", msg).group(1))
    assert widest == pytest.approx(width, abs=TOL_1DP)


def test_a_gap_narrower_than_the_car_is_proven_unreachable_with_its_width(tmp_path, capsys):
    f, obstacles = wall_with_gap(tmp_path, 1.6)
    rc, doc, _, _ = plan(capsys, [f, "--max-iterations", "500"])
    assert rc == 1 and doc["status"] == "proven_unreachable"
    assert "unreachable" in doc["message"]
    diag = doc["diagnosis"]
    assert diag["kind"] == "narrow_passage"
    width = shapely.distance(box(*obstacles[0][0], *obstacles[0][1]),
                             box(*obstacles[1][0], *obstacles[1][1]))  # fmt: skip
    m = re.search(r"near \((-?\d+\.\d), (-?\d+\.\d)\) is (\d+\.\d\d) m wide", diag["message"])
    assert m, diag["message"]
    assert float(m.group(3)) == pytest.approx(width, abs=TOL_2DP)
    assert math.dist((float(m.group(1)), float(m.group(2))), (30.0, 20.0)) < 1.0
    assert f"narrower than the car ({W:.2f} m)" in diag["message"]


def test_a_walled_off_goal_is_proven_unreachable(tmp_path, capsys):
    walls = [((40, 15), (12, 1)), ((40, 25), (12, 1)), ((34, 20), (1, 11)), ((46, 20), (1, 11))]
    f = write_map(tmp_path / "box.json", (0, 0, 60, 40), walls, (10, 10, 0), (39, 20, 0))
    rc, doc, _, _ = plan(capsys, [f, "--max-iterations", "200"])
    assert rc == 1 and doc["status"] == "proven_unreachable"
    assert doc["diagnosis"]["kind"] == "walled_off"
    # True by shapely: the goal's point is in a closed piece of free space.
    free_space = shapely.box(0, 0, 60, 40).difference(solid_of(walls))
    pieces = [p for p in shapely.get_parts(free_space) if p.contains(shapely.Point(39, 20))]
    assert pieces and not pieces[0].contains(shapely.Point(10, 10))


def test_a_boxed_in_start_gives_both_runs_and_the_space_along_its_heading(tmp_path, capsys):
    gap = 0.3
    obstacles = [((20 + FRONT + gap + 0.5, 20), (1, 6)), ((20 - REAR - gap - 0.5, 20), (1, 6))]
    f = write_map(tmp_path / "boxed.json", (0, 0, 60, 40), obstacles, (20, 20, 0), (50, 30, 0))
    rc, doc, _, _ = plan(capsys, [f, "--max-iterations", "500"])
    assert rc == 1
    diag = doc["diagnosis"]
    assert diag["kind"] == "boxed_in" and "--reverse" in diag["message"]
    solid, bounds = solid_of(obstacles), (0, 0, 60, 40)
    m = re.search(r"at most (\d+\.\d\d) m behind it and (\d+\.\d\d) m ahead of it", diag["message"])
    behind = best_steady_run((20.0, 20.0, 0.0), -1, solid, bounds, L)
    ahead = best_steady_run((20.0, 20.0, 0.0), 1, solid, bounds, L)
    assert float(m.group(1)) == pytest.approx(behind, abs=TOL_2DP)
    assert float(m.group(2)) == pytest.approx(ahead, abs=TOL_2DP)
    space = L + 2 * gap
    m2 = re.search(r"the space is (\d+\.\d\d) m, (\d+\.\d\d) car lengths", diag["message"])
    assert float(m2.group(1)) == pytest.approx(space, abs=TOL_2DP)
    assert float(m2.group(2)) == pytest.approx(space / L, abs=TOL_2DP)


@pytest.mark.parametrize("gap", [0.05, 0.15])
def test_tight_start_clearance_names_the_obstacle_and_its_distance(tmp_path, capsys, gap):
    f, obstacles = side_wall(tmp_path, "start", gap)
    rc, doc, _, _ = plan(capsys, [f, "--max-iterations", "300", "--planner", "rrt-connect"])
    assert rc == 1 and doc["status"] == "no_path_in_budget"
    diag = doc["diagnosis"]
    assert diag["kind"] == "tight_clearance"
    (cx, cy), _ = obstacles[0]
    d = body(20.0, 20.0, 0.0).distance(solid_of(obstacles))
    m = re.search(r"the start's body is (\d+\.\d\d) m from obstacle 0 at \((-?\d+\.\d), "
                  r"(-?\d+\.\d)\)", diag["message"])  # fmt: skip
    assert m, diag["message"]
    assert float(m.group(1)) == pytest.approx(d, abs=TOL_2DP)
    assert (float(m.group(2)), float(m.group(3))) == pytest.approx((cx, cy), abs=TOL_1DP)
    assert "--planner hybrid-a-star" in diag["message"]


def test_no_path_in_budget_names_the_budget_and_the_counts_in_the_json(tmp_path, capsys):
    f, _ = wall_with_gap(tmp_path, 4.0)
    rc, doc, _, _ = plan(capsys, [f, "--max-iterations", "3", "--planner", "rrt"])
    assert rc == 1 and doc["status"] == "no_path_in_budget"
    m = re.search(r"iteration budget of (\d+) spent \((\d+) iterations, (\d+) nodes\)",
                  doc["message"])  # fmt: skip
    assert m, doc["message"]
    assert int(m.group(1)) == 3 == doc["max_iterations"]
    assert int(m.group(2)) == doc["iterations"] and int(m.group(3)) == doc["nodes"]


def test_timeout_names_the_cap_and_the_flags_to_change(capsys):
    rc, doc, _, _ = plan(capsys, ["parking_lot", "--max-time", "0.001"])
    assert rc == 1 and doc["status"] == "timeout"
    assert "0.001 s safety cap" in doc["message"] and "--max-time" in doc["message"]
    assert doc["max_time_s"] == 0.001


def _api_problem(tmp_path, start: Pose, goal: Pose) -> PlanningProblem:
    obstacles = [((30.0, 20.0), (4.0, 4.0))]
    f = write_map(tmp_path / "api.json", (0, 0, 60, 40), obstacles, (5, 5, 0), (50, 30, 0))
    m = load_map(f)
    return PlanningProblem(m, cached_checker(m), start, goal, m.vehicle)


@pytest.mark.parametrize("end", ["start", "goal"])
def test_api_invalid_end_in_an_obstacle_names_it_and_the_least_shift(tmp_path, end):
    bad = Pose(30.0, 20.0, 0.0)
    ok = Pose(5.0, 5.0, 0.0) if end == "goal" else Pose(50.0, 30.0, 0.0)
    start, goal = (bad, ok) if end == "start" else (ok, bad)
    problem = _api_problem(tmp_path, start, goal)
    res = make_planner("improved-rrt-connect").solve(problem, np.random.default_rng(0),
                                                     Budget(max_iterations=50))  # fmt: skip
    assert res.status is (PlanStatus.INVALID_START if end == "start" else PlanStatus.INVALID_GOAL)
    assert res.message.startswith(f"{end}: ") and "obstacle 0" in res.message
    # The least shift that clears axis-aligned boxes: the smallest overlap along x or y.
    car, obs = body(30.0, 20.0, 0.0).bounds, box(30, 20, 4, 4).bounds
    shifts = [obs[2] - car[0], car[2] - obs[0], obs[3] - car[1], car[3] - obs[1]]
    said = float(re.search(r"by (\d+(?:\.\d+)?) m", res.message).group(1))
    assert said == pytest.approx(min(shifts), rel=0.01)
    assert res.diagnosis is not None and res.diagnosis.kind is DiagnosisKind.BODY_COLLIDES
    assert res.diagnosis.numbers["obstacle"] == 0
    assert f"the {end}'s body at (30.0, 20.0) overlaps obstacle 0 at (30.0, 20.0)" \
        == res.diagnosis.message  # fmt: skip


def test_api_start_outside_the_bounds_is_invalid_start_naming_the_bounds(tmp_path):
    problem = _api_problem(tmp_path, Pose(70.0, 5.0, 0.0), Pose(50.0, 30.0, 0.0))
    res = make_planner("rrt").solve(problem, np.random.default_rng(0), Budget(max_iterations=5))
    assert res.status is PlanStatus.INVALID_START
    assert "(70, 5) lies outside the bounds [0.0, 0.0, 60.0, 40.0]" in res.message
    assert "bounds" in res.diagnosis.message


# --- bugs ----------------------------------------------------------------------------------


def test_goal_tight_clearance_is_not_blamed_when_the_planner_reaches_that_goal(tmp_path, capsys):
    f, _ = side_wall(tmp_path, "goal", 0.05)
    rc_big, doc_big, _, _ = plan(capsys, [f, "--max-iterations", "300", "--planner", "rrt-connect"])
    assert rc_big == 0 and doc_big["status"] == "solved"  # its edges do reach that goal
    rc, doc, _, _ = plan(capsys, [f, "--max-iterations", "3", "--planner", "rrt-connect"])
    assert rc == 1 and doc["status"] == "no_path_in_budget"
    diag = doc["diagnosis"]
    assert diag is None or diag["kind"] != "tight_clearance", diag["message"]


def test_goal_beside_a_wall_is_not_called_boxed_in_along_its_heading(tmp_path, capsys):
    f, obstacles = side_wall(tmp_path, "goal", 0.05)
    solid, bounds = solid_of(obstacles), (0, 0, 60, 40)
    # The room along the goal's heading, both ways, straight: far more than a car length.
    assert run_length((40.0, 20.0, 0.0), -1, 0.0, solid, bounds, 3 * L) >= 3 * L
    assert run_length((40.0, 20.0, 0.0), 1, 0.0, solid, bounds, 3 * L) >= 3 * L
    rc, doc, _, _ = plan(capsys, [f, "--max-iterations", "300"])
    assert rc == 1
    # Unhedged (the stage's other wording adds "or its body nearer to an obstacle ...").
    assert "the goal is boxed in along its heading)" not in doc["message"]


# --- the CLI's contracts -------------------------------------------------------------------


def test_failure_json_fields_and_the_file_equals_what_is_printed(tmp_path, capsys):
    f, _ = street(tmp_path, 12.0)
    args = [f, "--max-iterations", "2000", "--seed", "3"]
    rc, printed, _, _ = plan(capsys, args)
    out = tmp_path / "plan.json"
    rc2 = main(["plan", *args, "--json", str(out)])
    summary, _ = capsys.readouterr()
    written = json.loads(out.read_text())
    assert rc == rc2 == 1
    for doc in (printed, written):
        assert doc["success"] is False and doc["status"] == "postprocess_failed"
        assert doc["stage"] is None and doc["length_m"] is None and doc["cusps"] is None
        for key in ("setup_time_s", "planning_time_s", "diagnosis_time_s"):
            assert isinstance(doc[key], float) and 0.0 <= doc[key] < 60.0
        assert isinstance(doc["message"], str) and doc["message"]
        assert set(doc["diagnosis"]) == {"kind", "message", "numbers"}
    assert without_times(printed) == without_times(written)
    # With --json FILE the human summary goes to stdout, with the status and the finding.
    assert "FAILED (postprocess_failed)" in summary
    assert "why: " + written["diagnosis"]["message"] in summary


def test_with_json_file_the_summary_is_on_stdout_and_names_status_and_why(tmp_path, capsys):
    f, _ = wall_with_gap(tmp_path, 1.6)
    out = tmp_path / "p.json"
    rc = main(["plan", f, "--json", str(out), "--max-iterations", "100"])
    stdout, stderr = capsys.readouterr()
    assert rc == 1 and stderr == ""
    assert "FAILED (proven_unreachable)" in stdout and "\n  why: the passage near" in stdout
    assert json.loads(out.read_text())["status"] == "proven_unreachable"


@pytest.mark.parametrize("maker", ["street", "bay", "budget"])
def test_seeded_failures_give_the_same_json_twice(tmp_path, capsys, maker):
    if maker == "street":
        f, _ = street(tmp_path, 12.0)
        args = [f, "--max-iterations", "1500", "--seed", "7"]
    elif maker == "bay":
        f, _ = goal_backs_onto_wall(tmp_path)
        args = [f, "--max-iterations", "1500", "--seed", "7"]
    else:
        f, _ = wall_with_gap(tmp_path, 4.0)
        args = [f, "--max-iterations", "40", "--seed", "7", "--planner", "rrt-connect"]
    a = plan(capsys, args)[1]
    b = plan(capsys, args)[1]
    assert without_times(a) == without_times(b)


def test_seeded_success_gives_the_same_json_twice(tmp_path, capsys):
    f, _ = goal_backs_onto_wall(tmp_path)
    args = [f, "--max-iterations", "2000", "--seed", "5", "--reverse"]
    a, b = plan(capsys, args)[1], plan(capsys, args)[1]
    assert a["success"] and without_times(a) == without_times(b)


BAD_INPUT = [
    (["--start", "100,5,0"], "--start"),
    (["--start", "30,30,0"], "--start"),
    (["--goal", "1,2"], "--goal"),
    (["--goal", "0.5,20,0"], "--goal"),
    (["--seed", "-1"], "--seed"),
    (["--max-iterations", "0"], "--max-iterations"),
    (["--max-time", "nan"], "--max-time"),
    (["--resolution", "0"], "--resolution"),
    (["--planner", "rrt-conect"], "--planner"),
    (["--step", "-1"], "--step"),
    (["--disable", "bogus"], "--disable"),
    (["--planner", "rrt", "--disable", "prune"], "--disable"),
    (["--planner-option", "nonsense=1"], "--planner-option"),
    (["--json", "/nonexistent_dir_s47/x.json"], "--json"),
    (["--plot", "x.txt"], "--plot"),
]


@pytest.mark.parametrize(("extra", "field"), BAD_INPUT, ids=[b[1] + str(i) for i, b in
                                                            enumerate(BAD_INPUT)])  # fmt: skip
def test_bad_input_exits_2_with_one_line_naming_the_field(tmp_path, capsys, extra, field):
    f = write_map(tmp_path / "m.json", (0, 0, 60, 40), [((30, 30), (4, 4))], (5, 10, 0),
                  (50, 10, 0))  # fmt: skip
    rc = run_main(["plan", f, *extra])
    out, err = capsys.readouterr()
    assert rc == 2 and out == ""
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert field in lines[0] and "Traceback" not in err


@pytest.mark.parametrize(
    ("text", "field"),
    [
        (
            '{"name": "x", "bounds": [0, 0, 60, 40], "obstacles": [], "start": [5, 5, NaN], '
            '"goal": [50, 30, 0]}',
            "start",
        ),
        (
            '{"name": "x", "bounds": [0, 0, 60, 40], "obstacles": [{"center": [30, 20], '
            '"size": [4, -4], "yaw": 0}], "start": [5, 5, 0], "goal": [50, 30, 0]}',
            "size",
        ),
        (
            '{"name": "x", "bounds": [0, 0, 60, 40], "obstacles": [], "start": [30, 20, 0], '
            '"goal": [70, 30, 0]}',
            "goal",
        ),
        ('{"name": "x", bounds', "JSON"),
    ],
)
def test_bad_map_files_exit_2_with_one_line_naming_the_field(tmp_path, capsys, text, field):
    f = tmp_path / "bad.json"
    f.write_text(text)
    rc = main(["plan", str(f)])
    out, err = capsys.readouterr()
    assert rc == 2 and out == "" and len(err.strip().splitlines()) == 1
    assert field in err and "Traceback" not in err


@pytest.mark.parametrize(
    ("argv", "field"),
    [
        (["plan"], "map"),
        (["plan", "parking_lot", "--bogus"], "--bogus"),
        (["plan", "parking_lot", "--json"], "--json"),
    ],
)
def test_usage_errors_exit_2_with_one_line(capsys, argv, field):
    rc = run_main(argv)
    out, err = capsys.readouterr()
    assert rc == 2 and out == "" and len(err.strip().splitlines()) == 1 and field in err


def test_bad_input_writes_no_json_file(tmp_path, capsys):
    out = tmp_path / "never.json"
    rc = run_main(["plan", "parking_lot", "--start", "500,5,0", "--json", str(out)])
    capsys.readouterr()
    assert rc == 2 and not out.exists()


def test_bad_input_in_a_real_process_has_no_traceback(tmp_path):
    f = write_map(tmp_path / "m.json", (0, 0, 60, 40), [((30, 20), (4, 4))], (5, 10, 0),
                  (50, 10, 0))  # fmt: skip
    proc = subprocess.run(
        [sys.executable, "-m", "rrtdrive", "plan", f, "--goal", "29,20,0"],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert proc.returncode == 2 and proc.stdout == ""
    assert proc.stderr.count("\n") == 1 and "Traceback" not in proc.stderr
    # The least shift that clears the goal's body from the 4 x 4 block, by shapely bounds.
    car, obs = body(29.0, 20.0, 0.0).bounds, box(30, 20, 4, 4).bounds
    least = min(obs[2] - car[0], car[2] - obs[0], obs[3] - car[1], car[3] - obs[1])
    said = float(re.search(r"by (\d+(?:\.\d+)?) m", proc.stderr).group(1))
    assert said == pytest.approx(least, rel=0.01)
    assert proc.stderr.startswith("rrtdrive plan: error: --goal:")


def test_every_plan_flag_has_help_text_shown_by_help(capsys):
    parser = build_parser("plan")
    sub = next(a for a in parser._actions if a.__class__.__name__ == "_SubParsersAction")
    plan_parser = sub.choices["plan"]
    flags = [a for a in plan_parser._actions if a.option_strings and "-h" not in a.option_strings]
    assert len(flags) >= 14
    with pytest.raises(SystemExit) as exc:
        main(["plan", "--help"])
    assert exc.value.code == 0
    text = " ".join(capsys.readouterr().out.split())
    for action in flags:
        assert action.help and len(action.help) > 10, action.option_strings
        assert action.option_strings[0] in text
    assert "Exit 0 when solved, 1 when no path was found" in text


def test_reverse_with_a_planner_that_cannot_reverse_notes_it_and_stays_forward(tmp_path, capsys):
    f = write_map(tmp_path / "open.json", (0, 0, 60, 40), [((30, 30), (4, 4))], (5, 10, 0),
                  (50, 10, 0))  # fmt: skip
    rc, doc, _, err = plan(capsys, [f, "--planner", "rrt-connect", "--reverse",
                                    "--max-iterations", "500"])  # fmt: skip
    assert rc == 0 and doc["reverse"] is True and doc["cusps"] == 0
    assert all(r[4] == 1.0 for r in doc["path"])
    assert "rrt-connect" in err and "forward" in err


def test_reverse_with_escalation_disabled_names_the_flag(tmp_path, capsys):
    f, _ = goal_backs_onto_wall(tmp_path)
    rc, doc, _, err = plan(capsys, [f, "--reverse", "--disable", "escalation",
                                    "--max-iterations", "300"])  # fmt: skip
    assert "--disable escalation" in err and "forward only" in err
    assert doc["reverse"] is True
    assert rc == 1 and doc["status"] != "solved"


def test_reverse_with_a_forward_only_planner_keeps_the_needs_reverse_finding(tmp_path, capsys):
    f, _ = goal_backs_onto_wall(tmp_path)
    base = [f, "--disable", "escalation", "--max-iterations", "300"]
    rc, doc, _, _ = plan(capsys, base)
    assert rc == 1 and doc["diagnosis"]["kind"] == "needs_reverse"
    rc, doc, _, _ = plan(capsys, [*base, "--reverse"])
    assert rc == 1 and doc["status"] != "solved"
    assert doc["diagnosis"] is not None and doc["diagnosis"]["kind"] == "needs_reverse"


def test_readme_example_bay_facing_out_quotes_the_gap_shapely_measures(capsys):
    from rrtdrive.maps import builtin_map

    rc, doc, _, _ = plan(capsys, ["parking_lot", "--goal", "66.5,22,1.5708"])
    assert rc == 1 and doc["diagnosis"]["kind"] == "needs_reverse"
    kerb = builtin_map("parking_lot").obstacles[136]
    gap = body(66.5, 22.0, 1.5708).distance(box(*kerb.center, *kerb.size))
    msg = doc["diagnosis"]["message"]
    cx, cy = kerb.center
    assert f"obstacle 136 at ({cx:.1f}, {cy:.1f}) {gap:.2f} m behind its rear" in msg
    assert "(try --reverse)" in msg


def test_reverse_on_a_boxed_start_drops_the_reverse_tip(tmp_path, capsys):
    gap = 0.3
    obstacles = [((20 + FRONT + gap + 0.5, 20), (1, 6)), ((20 - REAR - gap - 0.5, 20), (1, 6))]
    f = write_map(tmp_path / "boxed.json", (0, 0, 60, 40), obstacles, (20, 20, 0), (50, 30, 0))
    rc, doc, _, _ = plan(capsys, [f, "--max-iterations", "300", "--reverse"])
    assert rc == 1
    msg = doc["diagnosis"]["message"]
    assert doc["diagnosis"]["kind"] == "boxed_in" and "try --reverse" not in msg
    assert "gear changes" in msg


def test_the_reported_numbers_match_the_diagnosis_numbers(tmp_path, capsys):
    """Each 2-decimal figure of a needs_reverse message is one of its numbers, rounded."""
    f, _ = goal_backs_onto_wall(tmp_path)
    _, doc, _, _ = plan(capsys, [f, "--max-iterations", "500"])
    diag = doc["diagnosis"]
    figures = re.findall(r"(\d+\.\d\d) m", diag["message"])
    values = [v for k, v in diag["numbers"].items() if k != "obstacle"]
    for fig in figures:
        assert any(abs(float(fig) - v) <= 0.005 + 1e-9 for v in values) or float(fig) == L
    assert numbers_in(diag["message"])  # it quotes numbers at all


def test_u_turn_tip_followed_with_reverse_solves_with_gear_changes(tmp_path, capsys):
    f, obstacles = street(tmp_path, 12.0)
    rc, doc, _, _ = plan(capsys, [f, "--max-iterations", "2000", "--reverse"])
    assert rc == 0 and doc["status"] == "solved" and doc["cusps"] >= 1
    rows = np.array(doc["path"])
    solid = solid_of(obstacles)
    assert min(body(*r[:3]).distance(solid) for r in rows[::4]) > 0.0
    assert rows[-1, :2] == pytest.approx([40, 15], abs=1e-6)


def test_reverse_bay_goal_names_the_maps_edge_at_the_gap_shapely_measures(capsys):
    from rrtdrive.maps import builtin_map

    m = builtin_map("reverse_bay")
    rc, doc, _, _ = plan(capsys, ["reverse_bay", "--max-iterations", "500"])
    assert rc == 1 and doc["diagnosis"]["kind"] == "needs_reverse"
    assert doc["diagnosis"]["numbers"]["obstacle"] == -1
    g = m.goal
    car = body(g.x, g.y, g.yaw)
    gap = car.distance(shapely.box(*m.bounds).exterior)
    # Nothing nearer than the edge (else an obstacle would be named).
    assert all(gap <= car.distance(o.polygon()) + 1e-9 for o in m.obstacles)
    assert f"the map's edge {gap:.2f} m behind its rear" in doc["diagnosis"]["message"]


def test_kerbside_goal_is_boxed_in_with_the_runs_and_space_shapely_measures(capsys):
    from rrtdrive.maps import builtin_map

    m = builtin_map("kerbside")
    rc, doc, _, _ = plan(capsys, ["kerbside", "--max-iterations", "500"])
    diag = doc["diagnosis"]
    assert rc == 1 and diag["kind"] == "boxed_in" and "(try --reverse)" in diag["message"]
    g = (m.goal.x, m.goal.y, m.goal.yaw)
    solid = shapely.union_all([o.polygon() for o in m.obstacles])
    behind = best_steady_run(g, -1, solid, m.bounds, L)
    ahead = best_steady_run(g, 1, solid, m.bounds, L)
    straight = (run_length(g, 1, 0.0, solid, m.bounds, L)
                + run_length(g, -1, 0.0, solid, m.bounds, L))  # fmt: skip
    found = re.search(r"at most (\d+\.\d\d) m behind it and (\d+\.\d\d) m ahead of it.*"
                      r"the space is (\d+\.\d\d) m", diag["message"])  # fmt: skip
    assert found, diag["message"]
    assert float(found.group(1)) == pytest.approx(behind, abs=TOL_2DP)
    assert float(found.group(2)) == pytest.approx(ahead, abs=TOL_2DP)
    assert float(found.group(3)) == pytest.approx(L + straight, abs=TOL_2DP)


def test_a_gap_the_planner_can_never_pass_does_not_ask_for_a_larger_budget(tmp_path, capsys):
    f, obstacles = wall_with_gap(tmp_path, 1.85)
    rc, doc, _, _ = plan(capsys, [f, "--max-iterations", "500"])
    assert rc == 1
    diag = doc["diagnosis"]
    assert diag["kind"] == "narrow_passage"
    width = shapely.distance(box(*obstacles[0][0], *obstacles[0][1]),
                             box(*obstacles[1][0], *obstacles[1][1]))  # fmt: skip
    least = float(re.search(r"allows \((\d+\.\d\d) m\) each side", diag["message"]).group(1))
    assert W < width < W + 2 * least  # the car fits, the planner's least clearance does not
    assert "larger budget may find a path" not in doc["message"]


def test_u_turn_with_a_plaza_ahead_names_the_widest_place_shapely_finds(tmp_path, capsys):
    obstacles = [((25.0, 5.0), (50.0, 10.0)), ((25.0, 25.0), (50.0, 10.0))]
    f = write_map(tmp_path / "plaza.json", (0, 0, 80, 30), obstacles, (10, 15, 0.0),
                  (30, 15, math.pi))  # fmt: skip
    rc, doc, _, _ = plan(capsys, [f, "--max-iterations", "20"])
    assert rc == 1
    diag = doc["diagnosis"]
    assert diag["kind"] == "u_turn" and "must first drive to a wider place" in diag["message"]
    free_space = shapely.box(0, 0, 80, 30).difference(solid_of(obstacles))
    centre = shapely.ops.polylabel(free_space, tolerance=0.01)
    widest = 2 * free_space.exterior.distance(centre)
    m = re.search(r"about (\d+) m across, is near \((-?\d+), (-?\d+)\)", diag["message"])
    assert m, diag["message"]
    assert float(m.group(1)) == pytest.approx(widest, abs=0.51)
    # Where: any centre of a circle that wide (the plaza's centre line x = 65).
    assert float(m.group(2)) == pytest.approx(centre.x, abs=1.0)
    assert float(m.group(3)) == pytest.approx(centre.y, abs=1.0)
    # The same query with a budget drives forward through the plaza and back.
    rc, doc, _, _ = plan(capsys, [f, "--max-iterations", "300"])
    assert rc == 0 and doc["cusps"] == 0


def test_goal_behind_the_start_facing_the_same_way_says_how_far_behind(tmp_path, capsys):
    f = write_map(tmp_path / "behind.json", (0, 0, 60, 10), [], (15, 5, 0.0), (8, 5.5, 0.0))
    rc, doc, _, _ = plan(capsys, [f, "--max-iterations", "500"])
    assert rc == 1
    msg = doc["diagnosis"]["message"]
    behind = -((8 - 15) * math.cos(0.0) + (5.5 - 5) * math.sin(0.0))
    said = float(re.search(r"the goal is (\d+\.\d) m behind the start", msg).group(1))
    assert said == pytest.approx(behind, abs=TOL_1DP)
    width = float(re.search(r"is (\d+\.\d) m wide", msg).group(1))
    assert width == pytest.approx(10.0, abs=TOL_1DP)  # the bounds are the walls
    assert "(try --reverse)" in msg
