"""``rrtdrive simulate MAP --path PLAN.json``: drive a given plan's path, nothing planned.

The drive is judged by highway-env (its own vehicle states, its own crash flag) and the
trajectory CSV; the plan's own figures (its length, its cusps, its first and last rows)
are the reference. A path that `rrtdrive verify` (shapely bodies) finds colliding on
another map crashes in highway-env too.
"""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest

from rrtdrive.cli import main


def _run(capsys, *argv: str) -> tuple[int, str, str]:
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


@pytest.fixture(scope="module")
def kerbside_plan(tmp_path_factory) -> str:
    """A reversing plan into the built-in kerbside gap (3 gear changes at seed 0)."""
    f = tmp_path_factory.mktemp("plan") / "kerb.json"
    assert main(["plan", "kerbside", "--reverse", "--json", str(f)]) == 0
    return str(f)


def test_a_given_reversing_path_is_driven_from_its_first_row_to_its_last(
    kerbside_plan, tmp_path, capsys
):
    plan = json.loads(open(kerbside_plan).read())
    traj, out = tmp_path / "t.csv", tmp_path / "s.json"
    code, stdout, err = _run(capsys, "simulate", "kerbside", "--path", kerbside_plan,
                             "--controller", "lqr", "--trajectory", str(traj),
                             "--json", str(out))
    assert code == 0, err
    data = json.loads(out.read_text())
    assert data["planner"] == "given" and data["path_file"] == kerbside_plan
    assert data["reverse"] is True and data["planning_time_s"] is None
    # The driven path is the plan's, not a new one: its length from the plan's rows.
    xy = np.array(plan["path"])[:, :2]
    assert data["path_length_m"] == pytest.approx(np.hypot(*np.diff(xy, axis=0).T).sum(), abs=1e-3)
    assert "given/lqr: success" in stdout
    rows = list(csv.DictReader(traj.open()))
    pose = np.array([[float(r[k]) for k in ("x", "y", "yaw")] for r in rows])
    first, last = np.array(plan["path"][0][:3]), np.array(plan["path"][-1][:3])
    assert np.allclose(pose[0], first, atol=1e-9)  # the car is put on the first row
    assert np.hypot(*(pose[-1, :2] - last[:2])) < 0.05
    # Each of the plan's gear changes is driven: the car's gear flips as often.
    gears = np.array([int(float(r["gear"])) for r in rows])
    assert int(np.count_nonzero(np.diff(gears))) == plan["cusps"] == 3


def test_poses_alone_are_driven_with_the_gears_of_their_motion(kerbside_plan, tmp_path, capsys):
    # Another planner's output: [x, y, yaw] rows, each cusp's pose once.
    plan = json.loads(open(kerbside_plan).read())
    poses = []
    for row in plan["path"]:
        if not poses or poses[-1] != row[:3]:
            poses.append(row[:3])
    f, traj = tmp_path / "poses.json", tmp_path / "t.csv"
    f.write_text(json.dumps({"path": poses}))
    code, _, err = _run(capsys, "simulate", "kerbside", "--path", str(f), "--trajectory",
                        str(traj), "--json", str(tmp_path / "s.json"))
    assert code == 0, err
    data = json.loads((tmp_path / "s.json").read_text())
    assert data["path_cusps"] == plan["cusps"] == 3 and data["reverse"] is True
    gears = [int(float(r["gear"])) for r in csv.DictReader(traj.open())]
    assert sum(a != b for a, b in zip(gears, gears[1:], strict=False)) == 3


def test_a_path_of_another_map_is_driven_as_asked_and_crashes_where_verify_says(
    kerbside_plan, tmp_path, capsys
):
    # The kerbside path on a map with a wall across it: verify's shapely bodies hit it,
    # and highway-env's car crashes into it.
    m = {"name": "walled", "bounds": [0, 0, 40, 10],
         "obstacles": [{"center": [16, 5], "size": [1, 10], "yaw": 0}],
         "start": [3, 5, 0], "goal": [30, 5, 0]}  # fmt: skip
    mf = tmp_path / "walled.json"
    mf.write_text(json.dumps(m))
    code, _, _ = _run(capsys, "verify", kerbside_plan, str(mf), "--json", str(tmp_path / "v"))
    assert code == 1 and not json.loads((tmp_path / "v").read_text())["collision_free"]
    out = tmp_path / "s.json"
    code, _, err = _run(capsys, "simulate", str(mf), "--path", kerbside_plan, "--json", str(out))
    assert code == 1
    assert "warning: --path: the plan was made on map 'kerbside'; it is driven on 'walled'" in err
    data = json.loads(out.read_text())
    assert data["status"] == "crashed" and not data["success"]


@pytest.mark.parametrize(
    ("extra", "needle"),
    [
        (["--planner", "rrt"], "--planner: --path gives the path to drive; nothing is planned"),
        (["--planner-option", "step=3"], "--planner-option: --path gives the path"),
        (["--plan-time", "3"], "--plan-time: --path gives the path"),
        (["--max-iterations", "300"], "--max-iterations: --path gives the path"),
        (["--deterministic"], "--deterministic: --path gives the path"),
        (["--reverse"], "--reverse: --path gives the path"),
        (["--start", "3,5,0"], "--start: --path gives the path to drive; nothing is planned "
                               "(the drive starts at its first row and ends at its last)"),
        (["--goal", "30,1.2,0"], "--goal: --path gives the path"),
        (["--resolution", "0.2"], "--resolution: --path gives the path"),
    ],
)
def test_planning_flags_beside_a_given_path_are_refused(kerbside_plan, capsys, extra, needle):
    code, _, err = _run(capsys, "simulate", "kerbside", "--path", kerbside_plan, *extra)
    lines = err.strip().splitlines()
    assert code == 2 and "Traceback" not in err and len(lines) == 1, err
    assert lines[0].startswith(f"rrtdrive simulate: error: {needle}")


def test_bad_given_paths_are_named_by_the_flag(kerbside_plan, tmp_path, capsys):
    def refused(*argv: str) -> str:
        code, _, err = _run(capsys, "simulate", *argv)
        lines = err.strip().splitlines()
        assert code == 2 and len(lines) == 1 and "Traceback" not in err, err
        return lines[0].removeprefix("rrtdrive simulate: error: ")

    assert refused("parking", "--path", kerbside_plan).startswith(
        "--path: only a map drives a given path; parking sets its own start and goal")
    assert refused("kerbside", "--path", str(tmp_path / "none.json")).startswith(
        "--path: cannot read")
    failed = tmp_path / "failed.json"
    failed.write_text(json.dumps({"path": [], "status": "no_path_in_budget"}))
    assert refused("kerbside", "--path", str(failed)) == (
        f"--path: {failed} has no path to drive (status no_path_in_budget): no rows")
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"path": [[0, 0], [1, 0]]}))
    assert refused("kerbside", "--path", str(bad)).startswith("--path: path: rows must all be")
    # The path's first row off the map: named as the path's, not as a --start.
    off = tmp_path / "off.json"
    off.write_text(json.dumps({"path": [[-5, 5, 0, 0, 1], [-4.8, 5, 0, 0, 1]]}))
    assert refused("kerbside", "--path", str(off)).startswith(
        "--path: the path's first row: (-5, 5) lies outside the bounds")
    # The JSON would overwrite the plan it drives.
    assert refused("kerbside", "--path", kerbside_plan, "--json", kerbside_plan).endswith(
        "is the --path file it reads; give the output another name")
