"""``rrtdrive verify``: the independent check of a plan JSON, from the command line."""

from __future__ import annotations

import json

import numpy as np
import pytest

from rrtdrive.cli import main
from rrtdrive.maps import builtin_map, save_map


def run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


@pytest.fixture(scope="module")
def plans(tmp_path_factory):
    """Plans of parking_lot written by ``rrtdrive plan``: default, paper smoothing, reverse."""
    folder = tmp_path_factory.mktemp("plans")
    out = {}
    for name, extra in {
        "default": [],
        "paper": ["--paper-smoothing"],
        "reverse": ["--reverse", "--goal", "20,30,3.1"],
    }.items():
        target = folder / f"{name}.json"
        assert main(["plan", "parking_lot", "--json", str(target), *extra]) == 0
        out[name] = target
    return out


def test_a_default_plan_passes_every_check(capsys, plans):
    code, out, _ = run(capsys, "verify", str(plans["default"]))
    assert code == 0, out
    assert "OK, every check passed" in out and "FAIL" not in out
    assert "sharpness" in out and "(max 0.2 + 0.005)" in out


def test_a_reversing_plan_is_checked_against_its_own_goal(capsys, plans):
    # The plan JSON carries the --goal it was planned for; the map's own goal differs.
    data = json.loads(plans["reverse"].read_text())
    assert data["goal"] == [20.0, 30.0, 3.1] and data["cusps"] >= 1
    code, out, _ = run(capsys, "verify", str(plans["reverse"]))
    assert code == 0, out
    # Against the map's own goal instead, its end is in the wrong place.
    m = builtin_map("parking_lot")
    goal = ",".join(str(v) for v in m.goal.as_tuple())
    code, out, _ = run(capsys, "verify", str(plans["reverse"]), "--goal", goal)
    assert code == 1 and "FAIL ends exactly at start and goal" in out


def test_paper_smoothing_fails_only_the_sharpness_bound(capsys, plans):
    code, out, _ = run(capsys, "verify", str(plans["paper"]))
    assert code == 1
    assert [line.split()[1] for line in out.splitlines() if "FAIL " in line] == ["sharpness"]
    assert "--no-sharpness" in out
    code, out, _ = run(capsys, "verify", str(plans["paper"]), "--no-sharpness")
    assert code == 0 and "(not checked)" in out
    code, _, _ = run(capsys, "verify", str(plans["paper"]), "--max-sharpness", "5")
    assert code == 0


def test_an_obstacle_on_the_path_fails_the_body_check_alone(capsys, plans, tmp_path):
    import dataclasses

    from rrtdrive.maps import Obstacle

    data = json.loads(plans["default"].read_text())
    x, y = np.array(data["path"])[len(data["path"]) // 2, :2]
    m = builtin_map("parking_lot")
    blocked = dataclasses.replace(m, obstacles=(*m.obstacles, Obstacle((x, y), (1.0, 1.0))))
    f = tmp_path / "blocked.json"
    save_map(blocked, f)
    report = tmp_path / "check.json"
    code, out, _ = run(capsys, "verify", str(plans["default"]), str(f), "--json", str(report))
    assert code == 1 and "FAIL body clear of obstacles" in out
    doc = json.loads(report.read_text())
    # The body check and the clearance the plan declares (a body in contact keeps none).
    assert doc["ok"] is False and doc["failed"] == ["collision_free", "clearance_ok"]
    assert doc["min_clearance_m"] == 0.0 and doc["clearance"] == pytest.approx(0.148)
    assert doc["sharpness_bound"] == 0.2 and doc["kappa_max"] == m.vehicle.kappa_max
    assert "max_sharpness" not in doc  # plan --json's name for the measured value


def test_a_map_file_and_json_on_stdout(capsys, plans, tmp_path):
    f = tmp_path / "lot.json"
    save_map(builtin_map("parking_lot"), f)
    code, out, err = run(capsys, "verify", str(plans["default"]), str(f), "--json", "-")
    assert code == 0
    doc = json.loads(out)  # stdout is the JSON alone; the lines went to stderr
    assert doc["ok"] is True and doc["failed"] == [] and "OK" in err


@pytest.mark.parametrize(
    ("content", "field"),
    [
        ("not json", "plan"),
        ('{"success": true}', "plan"),
        ('{"path": [[0, 0, 0, 0], [0, 0, 0]], "map": "parking_lot"}', "path"),
        ('{"path": [[0, 0, 0, 0, 1], [0.2, 0, 0, 0, 1]], "map": "my_garage"}', "map"),
        ('{"path": [[0, 0, 0, 0, 1], [0.2, 0, 0, 0, 1]], "map": "parking_lot", '
         '"start": [1, 2]}', "plan.start"),
    ],
)
def test_bad_input_is_one_line_naming_the_field(capsys, tmp_path, content, field):
    f = tmp_path / "plan.json"
    f.write_text(content)
    code, out, err = run(capsys, "verify", str(f))
    assert code == 2 and out == ""
    assert err.count("\n") == 1 and f"error: {field}" in err and "Traceback" not in err


def test_rows_of_mixed_widths_name_the_first_odd_row(capsys, tmp_path):
    f = tmp_path / "plan.json"
    f.write_text('{"path": [[0, 0, 0, 0, 1], [0.2, 0, 0, 0, 1], [0.4]], "map": "parking_lot"}')
    code, _, err = run(capsys, "verify", str(f))
    assert code == 2 and err.rstrip().endswith("row 2 has 1 number")


def test_a_one_row_plan_reports_its_row(capsys, tmp_path):
    f = tmp_path / "plan.json"
    f.write_text('{"path": [[5, 6, 0, 0, 1]], "map": "parking_lot"}')
    code, out, _ = run(capsys, "verify", str(f), "--json", "-")
    assert code == 1 and json.loads(out)["rows"] == 1


def test_a_failed_plan_has_nothing_to_verify(capsys, tmp_path):
    f = tmp_path / "failed.json"
    f.write_text(json.dumps({"path": [], "map": "parking_lot", "status": "no_path_in_budget"}))
    code, out, _ = run(capsys, "verify", str(f))
    assert code == 1 and "no path (status no_path_in_budget)" in out


def test_a_collision_is_located_at_its_first_pose_and_obstacle(capsys, tmp_path):
    import dataclasses

    from rrtdrive.maps import Obstacle
    from rrtdrive.vehicle import footprint_polygon
    from rrtdrive.verify import path_from_json, verify_path

    assert main(["plan", "parking_lot", "--json", str(tmp_path / "p.json")]) == 0
    plan = json.loads((tmp_path / "p.json").read_text())
    m = builtin_map("parking_lot")
    x, y = plan["path"][len(plan["path"]) // 2][:2]
    block = Obstacle((x, y), (0.5, 0.5))
    blocked = dataclasses.replace(m, obstacles=m.obstacles + (block,))
    check = verify_path(blocked, path_from_json(plan))
    assert not check.collision_free and check.collides_with == f"obstacle {len(m.obstacles)}"
    # The pose named overlaps that block (the planner's footprint, drawn independently).
    assert footprint_polygon(check.first_collision, m.vehicle).intersects(block.polygon())
    save_map(blocked, tmp_path / "blocked.json")
    capsys.readouterr()
    assert main(["verify", str(tmp_path / "p.json"), str(tmp_path / "blocked.json")]) == 1
    line = capsys.readouterr().out.splitlines()[1]
    assert line.startswith("  FAIL body clear") and line.endswith(f"obstacle {len(m.obstacles)}")
    assert verify_path(m, path_from_json(plan)).first_collision is None


def test_a_row_off_the_map_is_located_at_the_bounds():
    from rrtdrive.types import Path
    from rrtdrive.verify import verify_path

    m = builtin_map("overtake")
    rows = np.array([[m.start.x, m.start.y, 0.0, 0.0], [1e6, m.start.y, 0.0, 0.0]])
    check = verify_path(m, Path(rows, np.zeros((0, 2))))
    assert check.first_collision == (1e6, m.start.y, 0.0) and check.collides_with == "the bounds"


def test_a_plan_on_a_map_file_is_verified_against_that_file(capsys, tmp_path, monkeypatch):
    # The plan records the map file's absolute path, so verify finds it from any folder.
    import dataclasses

    m = builtin_map("parking_lot")
    f = tmp_path / "my_lot.json"
    save_map(dataclasses.replace(m, name="my_lot"), f)
    monkeypatch.chdir(tmp_path)
    plan = tmp_path / "plan.json"
    assert main(["plan", "my_lot.json", "--json", str(plan)]) == 0
    assert json.loads(plan.read_text())["map_file"] == str(f)
    monkeypatch.chdir(tmp_path.parent)
    code, out, _ = run(capsys, "verify", str(plan))
    assert code == 0 and out.startswith("my_lot: ")
    # An obstacle put on the path in the file: verify reads the file as it is now.
    data = json.loads(plan.read_text())
    x, y = np.array(data["path"])[len(data["path"]) // 2, :2]
    from rrtdrive.maps import Obstacle

    on_path = Obstacle((x, y), (1, 1))
    blocked = dataclasses.replace(m, name="my_lot", obstacles=(*m.obstacles, on_path))
    save_map(blocked, f)
    code, out, _ = run(capsys, "verify", str(plan))
    assert code == 1 and "FAIL body clear of obstacles" in out
    # The file gone: one line naming the map and how to give it.
    f.unlink()
    code, out, err = run(capsys, "verify", str(plan))
    assert code == 2 and out == "" and err.count("\n") == 1
    assert "error: map:" in err and str(f) in err and "rrtdrive verify PLAN MAP.json" in err


def test_a_builtin_map_plan_names_no_file(capsys, plans):
    assert json.loads(plans["default"].read_text())["map_file"] is None


def test_a_path_starting_in_collision_fails_the_body_check_there(capsys, tmp_path):
    # The plan's start lies on obstacle 0: the path fails (exit 1), located at its start;
    # it is not bad input (exit 2) as the same start given to `rrtdrive plan` would be.
    m = builtin_map("parking_lot")
    (cx, cy), yaw = m.obstacles[0].center, m.obstacles[0].yaw
    s = np.arange(0.0, 5.01, 0.1)
    rows = np.column_stack(
        [cx + s * np.cos(yaw), cy + s * np.sin(yaw), yaw + 0 * s, 0 * s, 1 + 0 * s]
    )
    f = tmp_path / "plan.json"
    end = rows[-1, :3].tolist()
    f.write_text(json.dumps({"path": rows.tolist(), "map": "parking_lot",
                             "start": rows[0, :3].tolist(), "goal": end}))
    code, out, err = run(capsys, "verify", str(f), "--json", str(tmp_path / "c.json"))
    assert code == 1 and err == ""
    assert "FAIL body clear of obstacles" in out and "obstacle 0" in out
    doc = json.loads((tmp_path / "c.json").read_text())
    # Contact is no clearance either (it read "ok clearance 0.0000 m (min 0)").
    assert doc["failed"] == ["collision_free", "clearance_ok"]
    assert doc["collides_with"] == "obstacle 0"
    assert doc["first_collision"][:2] == pytest.approx([cx, cy])


def test_a_map_file_whose_own_start_went_bad_still_verifies_the_plan(capsys, tmp_path):
    # A bollard put on the start after planning: the path fails there (exit 1); the
    # map's own start is not checked as the map of `rrtdrive plan` would be (exit 2).
    import dataclasses

    from rrtdrive.maps import Obstacle

    m = builtin_map("parking_lot")
    f = tmp_path / "lot.json"
    save_map(m, f)
    plan = tmp_path / "plan.json"
    assert main(["plan", str(f), "--json", str(plan)]) == 0
    bollard = Obstacle((m.start.x, m.start.y), (0.3, 0.3))
    save_map(dataclasses.replace(m, obstacles=(*m.obstacles, bollard), check_query=False), f)
    code, out, err = run(capsys, "verify", str(plan))
    assert code == 1 and err == "", err
    assert f"obstacle {len(m.obstacles)}" in out


def test_a_bad_map_file_is_named_apart_from_the_plan(capsys, plans, tmp_path):
    # "goal: must be finite" alone read as the plan's own goal (a helper's audit).
    data = builtin_map("parking_lot").to_json()
    data["goal"] = [float("nan"), 44.0, 0.0]
    f = tmp_path / "nan.json"
    f.write_text(json.dumps(data))  # json writes NaN
    code, _, err = run(capsys, "verify", str(plans["default"]), str(f))
    assert code == 2 and err.count("\n") == 1 and "Traceback" not in err
    assert f"error: map {f}: goal: must be finite" in err


def test_a_yaw_in_degrees_is_named_by_where_it_came_from(capsys, plans, tmp_path):
    code, _, err = run(capsys, "verify", str(plans["default"]), "--goal", "50,40,90")
    assert code == 1
    assert err.startswith("rrtdrive verify: warning: --goal: yaw 90 is more than a full turn")
    data = json.loads(plans["default"].read_text())
    data["goal"][2] = 400.0
    f = tmp_path / "deg.json"
    f.write_text(json.dumps(data))
    code, _, err = run(capsys, "verify", str(f))
    assert code == 1 and "warning: plan.goal: yaw 400 is more than a full turn" in err


def test_checking_a_plan_against_another_map_says_so(capsys, plans):
    code, out, err = run(capsys, "verify", str(plans["default"]), "overtake")
    assert code == 1 and out.startswith("overtake: ")
    assert err.splitlines() == [
        "rrtdrive verify: warning: MAP: the plan was made on map 'parking_lot'; it is "
        "checked against 'overtake' as asked"
    ]
    code, _, err = run(capsys, "verify", str(plans["default"]), "parking_lot")
    assert code == 0 and err == ""


@pytest.mark.parametrize("bad", [5, [], True])
def test_a_map_file_that_is_not_a_path_is_refused(capsys, plans, tmp_path, bad):
    data = json.loads(plans["default"].read_text())
    data["map_file"] = bad
    f = tmp_path / "bad.json"
    f.write_text(json.dumps(data))
    code, _, err = run(capsys, "verify", str(f))
    assert code == 2 and err.count("\n") == 1
    assert "error: plan.map_file: expected the map file's path or null, got" in err


def test_the_plot_draws_the_body_where_the_path_first_collides(capsys, plans, tmp_path):
    import dataclasses

    import shapely
    from matplotlib.patches import Polygon as PolygonPatch

    from rrtdrive.maps import Obstacle
    from rrtdrive.plotting import plot_check
    from rrtdrive.verify import path_from_json, verify_path

    data = json.loads(plans["default"].read_text())
    x, y = np.array(data["path"])[len(data["path"]) // 2, :2]
    m = builtin_map("parking_lot")
    block = Obstacle((x, y), (1.0, 1.0))
    blocked = dataclasses.replace(m, obstacles=(*m.obstacles, block))
    path = path_from_json(data)
    check = verify_path(blocked, path)
    fig = plot_check(blocked, path, check, "p.json")
    title = fig.axes[0].get_title(loc="left")
    assert title == "parking_lot: p.json: FAILED: collision, clearance (697 rows, 170.7 m)".replace(
        "697", str(len(path))).replace("170.7", f"{path.length:.1f}")
    # The red body (tab:red): the car at the first colliding pose, which overlaps the block.
    bodies = [shapely.Polygon(p.get_xy()) for p in fig.axes[0].patches
              if type(p) is PolygonPatch  # not its subclass FancyArrow, the heading
              and np.allclose(p.get_facecolor()[:3], (0.839, 0.153, 0.157), atol=0.01)]
    assert len(bodies) == 1 and bodies[0].intersects(block.polygon())
    cx, cy, yaw = check.first_collision
    length, rear = m.vehicle.length, m.vehicle.rear_overhang
    centre = (cx + (length / 2 - rear) * np.cos(yaw), cy + (length / 2 - rear) * np.sin(yaw))
    assert np.allclose(bodies[0].centroid.coords[0], centre, atol=1e-6)
    assert bodies[0].area == pytest.approx(length * m.vehicle.width)
    # From the command line: a PNG; a suffix matplotlib does not promise is refused.
    save = tmp_path / "blocked.json"
    save_map(blocked, save)
    png = tmp_path / "check.png"
    code, _, _ = run(capsys, "verify", str(plans["default"]), str(save), "--plot", str(png))
    assert code == 1 and png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    code, _, err = run(capsys, "verify", str(plans["default"]), "--plot", str(tmp_path / "c.txt"))
    assert code == 2 and err.startswith("rrtdrive verify: error: --plot:")
    code, _, err = run(capsys, "verify", str(plans["default"]), "--plot", str(plans["default"]))
    assert code == 2 and "--plot" in err


@pytest.mark.parametrize(
    ("edit", "said"),
    [
        ({"reverse": False}, "it says reverse: false, but its path changes gear"),
        ({"cusps": 0}, "it says cusps: 0, but its path changes gear"),
    ],
)
def test_a_plan_whose_own_claims_disagree_with_its_gears_fails(capsys, plans, tmp_path, edit, said):
    # A file saying "forward only" over a reversing path passed every check (an audit).
    data = json.loads(plans["reverse"].read_text())
    cusps = data["cusps"]
    assert data["reverse"] is True and cusps >= 1
    doctored = tmp_path / "claims.json"
    doctored.write_text(json.dumps({**data, **edit}))
    code, out, _ = run(capsys, "verify", str(doctored))
    assert code == 1 and "FAILED" in out.splitlines()[0]
    assert "FAIL the plan says what its path does" in out
    assert f"{said} {cusps} time(s)" in out
    code, out, _ = run(capsys, "verify", str(doctored), "--json", "-")
    doc = json.loads(out)
    assert code == 1 and doc["claims_ok"] is False and doc["failed"] == ["claims_ok"]
    assert doc["ok"] is False
    # The plan as written claims what it does.
    code, out, _ = run(capsys, "verify", str(plans["reverse"]), "--json", "-")
    assert code == 0 and json.loads(out)["claims_ok"] is True


def test_the_json_report_has_pathchecks_fields_and_the_ones_readme_names(capsys, plans):
    import dataclasses
    from pathlib import Path

    from rrtdrive.verify import PathCheck

    def refuse(constant):
        raise ValueError(constant)

    code, out, err = run(capsys, "verify", str(plans["reverse"]), "--json", "-")
    assert code == 0, err
    doc = json.loads(out, parse_constant=refuse)
    extra = {"map", "rows", "length_m", "vehicle", "kappa_given", "kappa_max", "sharpness_bound",
             "clearance", "claims_ok", "failed"}
    assert set(doc) == {f.name for f in dataclasses.fields(PathCheck)} | extra
    assert doc["ok"] is True and doc["failed"] == [] and doc["cusps"] >= 1
    assert doc["first_collision"] is None and doc["collides_with"] == ""
    readme = Path(__file__).resolve().parents[1] / "README.md"
    if readme.is_file():  # the README's verify section names every field PathCheck lacks
        section = readme.read_text().split("### `rrtdrive verify`")[1].split("\n### ")[0]
        assert all(f"`{key}`" in section for key in extra | {"ok"}), extra
