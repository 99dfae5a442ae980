"""Audit (session 50): a map file carrying its own car, through every command.

Two map files hold a car that is not the paper's: ``tiny.json`` a tiny car (2.5 x 1.2 m,
wheelbase 1.6 m, r_min 3 m, 35 deg lock, 0.8 rad/s) on a U-turn around a wall the
tiny car turns forward, and ``long.json`` a long car (6 x 2.2 m, wheelbase 3.8 m,
r_min 9 m, 0.45 rad lock, 0.3 rad/s); ``tl.json`` is the tiny map holding the long car
(its forward U-turn does not fit, a reverse one does). ``plan`` (forward, --reverse),
``verify`` (with and without MAP), ``simulate`` (a map target with --video, --plot,
--trajectory; --path), ``bench --maps`` / ``--scenarios``, ``maps --export`` /
``--import``, the gym ``rrtdrive/Map-v0``, the Python API and the OMPL comparators
must all use the file's car. Every property is measured here: curvature from the
rows' positions (circumscribed circles), the body as a shapely rectangle written out
from SPEC section 1, the drawn ego's size in pixels.
"""

from __future__ import annotations

import csv
import dataclasses
import json
import math
import subprocess
import sys

import numpy as np
import pytest
import shapely
from car_bodies import body

from rrtdrive import Budget, InputError, VehicleParams, builtin_map, load_map, save_map
from rrtdrive.cli import main as cli_main

TINY = {"length": 2.5, "width": 1.2, "wheelbase": 1.6, "min_turning_radius": 3.0,
        "max_steer": math.radians(35.0), "max_steer_rate": 0.8}  # fmt: skip
LONG = {"length": 6.0, "width": 2.2, "wheelbase": 3.8, "min_turning_radius": 9.0,
        "max_steer": 0.45, "max_steer_rate": 0.3}  # fmt: skip
PAPER = {"length": 4.3, "width": 1.8, "wheelbase": 2.51, "min_turning_radius": 6.0,
         "max_steer": math.radians(30.0), "max_steer_rate": 0.4}  # fmt: skip

#: A 30 x 20 m yard with a wall from the left edge to x = 18; from below it to above it.
U_TURN = {"name": "tinyturn", "bounds": [0, 0, 30, 20],
          "obstacles": [{"center": [9.0, 10.0], "size": [18.0, 1.0], "yaw": 0.0}],
          "start": [4.0, 6.0, 0.0], "goal": [6.0, 14.0, math.pi]}  # fmt: skip
OPEN = {"name": "longcar", "bounds": [0, 0, 80, 60],
        "obstacles": [{"center": [40.0, 30.0], "size": [10.0, 10.0], "yaw": 0.3}],
        "start": [8.0, 10.0, 0.0], "goal": [65.0, 48.0, math.pi / 2]}  # fmt: skip


# ----------------------------------------------------------------------------- helpers


def _cli(*argv: str, cwd) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "rrtdrive", *argv], cwd=cwd,
                          capture_output=True, text=True, timeout=240)  # fmt: skip


_body = body  # tests/car_bodies.py: the independent body


def _world(doc: dict) -> tuple[shapely.Geometry, shapely.Polygon]:
    """The obstacles of a map document (one union) and its bounds as a polygon."""
    rects = []
    for o in doc["obstacles"]:
        (cx, cy), (length, width), yaw = o["center"], o["size"], o["yaw"]
        box = shapely.box(cx - length / 2, cy - width / 2, cx + length / 2, cy + width / 2)
        rects.append(shapely.affinity.rotate(box, yaw, origin=(cx, cy), use_radians=True))
    return shapely.union_all(rects), shapely.box(*doc["bounds"])


def _least_clearance(doc: dict, car: dict, poses) -> float:
    """Least distance of the car's body at ``poses`` to the obstacles and the bounds' edge.

    Negative when a body overlaps an obstacle or leaves the bounds.
    """
    obstacles, inside = _world(doc)
    least = math.inf
    for x, y, yaw in poses:
        body = _body(car, x, y, yaw)
        if body.intersects(obstacles) or not inside.contains(body):
            return -1.0
        least = min(least, body.distance(obstacles), body.exterior.distance(inside.exterior))
    return least


def _menger(xy: np.ndarray) -> float:
    """Largest circumscribed-circle curvature of consecutive distinct points."""
    keep = np.r_[True, np.hypot(*np.diff(xy, axis=0).T) > 1e-6]
    p = xy[keep]
    if len(p) < 3:
        return 0.0
    a, b, c = p[:-2], p[1:-1], p[2:]
    ab, bc, ca = (np.linalg.norm(b - a, axis=1), np.linalg.norm(c - b, axis=1),
                  np.linalg.norm(a - c, axis=1))  # fmt: skip
    cross = np.abs((b - a)[:, 0] * (c - a)[:, 1] - (b - a)[:, 1] * (c - a)[:, 0])
    return float(np.max(2.0 * cross / (ab * bc * ca)))


def _segment_curvature(rows) -> float:
    """The largest curvature within any gear segment (a cusp is no curve)."""
    a = np.asarray(rows, dtype=float)
    cuts = np.flatnonzero(np.diff(a[:, 4]) != 0) + 1
    return max(_menger(seg[:, :2]) for seg in np.split(a, cuts))


def _in_process(capsys, *argv: str) -> tuple[int, str]:
    """Run the CLI in this process: its exit code and its stderr."""
    code = cli_main(list(argv))
    return code, capsys.readouterr().err


def _run(capsys, *argv: str, cwd) -> subprocess.CompletedProcess:
    """The CLI in this process (faster than a new one), paths relative to ``cwd``."""
    with pytest.MonkeyPatch.context() as mp:
        mp.chdir(cwd)
        code = cli_main(list(argv))
    out = capsys.readouterr()
    return subprocess.CompletedProcess(argv, code, out.out, out.err)


# ----------------------------------------------------------------------------- fixtures


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("carmaps")
    docs = {
        "tiny.json": {**U_TURN, "vehicle": TINY},
        "long.json": {**OPEN, "vehicle": LONG},
        "tl.json": {**U_TURN, "name": "tinymap_longcar", "vehicle": LONG},
        "paper.json": {**U_TURN, "name": "tinyturn_paper"},
    }
    for name, doc in docs.items():
        (d / name).write_text(json.dumps(doc))
    return d, docs


@pytest.fixture(scope="module")
def plans(files):
    """plan --json of each map file (forward; tl.json also --reverse)."""
    d, _ = files
    runs = {}
    for key, argv in {
        "tiny": ("tiny.json",), "long": ("long.json",), "paper": ("paper.json",),
        "tl": ("tl.json", "--max-time", "20"), "tl_rev": ("tl.json", "--reverse"),
    }.items():  # fmt: skip
        with pytest.MonkeyPatch.context() as mp:  # in this process: faster than a new one
            mp.chdir(d)
            code = cli_main(["plan", *argv, "--json", f"{key}.plan.json"])
        run = subprocess.CompletedProcess(argv, code, "", "(stderr not kept)")
        runs[key] = (run, json.loads((d / f"{key}.plan.json").read_text()))
    return runs


# ----------------------------------------------------------------------------- plan


@pytest.mark.parametrize(("key", "mapfile", "car"),
                         [("tiny", "tiny.json", TINY), ("long", "long.json", LONG)])
def test_plan_records_and_keeps_the_files_car(files, plans, key, mapfile, car):
    d, docs = files
    run, doc = plans[key]
    assert run.returncode == 0, run.stderr
    assert doc["vehicle"] == pytest.approx(car)
    rows = np.asarray(doc["path"])
    kappa = _segment_curvature(rows)
    assert kappa <= 1.0 / car["min_turning_radius"] + 2e-3
    # The body of that car, not the paper's, clear along the path.
    assert _least_clearance(docs[mapfile], car, rows[:, :3]) > 0.0
    # max_sharpness and its speed limit are for that car's steering rate.
    assert doc["steer_rate_speed_limit"] == pytest.approx(
        car["max_steer_rate"] / doc["max_sharpness"], rel=1e-3)


def test_the_tiny_car_turns_tighter_than_the_paper_car_may(plans):
    _, doc = plans["tiny"]
    # The U-turn is made forward with the tiny car's turns (the paper's car: 1/6 at most).
    assert 1.0 / 6.0 + 0.02 < _segment_curvature(doc["path"]) <= 1.0 / 3.0 + 2e-3


def test_long_car_forward_u_turn_fails_for_its_own_turning_circle_and_reverse_solves(
    files, plans
):
    d, docs = files
    run, doc = plans["tl"]
    assert run.returncode == 1 and not doc["success"]
    numbers = doc["diagnosis"]["numbers"]
    # The long car's swept turning circle: 2 * hypot(r + w/2, front extent), ~22.45 m
    # (the paper car's would be ~15.4 m), plus the clearance kept each side.
    front = LONG["length"] - (LONG["length"] - LONG["wheelbase"]) / 2
    circle = 2 * math.hypot(LONG["min_turning_radius"] + LONG["width"] / 2, front)
    assert circle - 0.01 <= numbers["turning_circle_m"] <= circle + 0.5
    run, doc = plans["tl_rev"]
    assert run.returncode == 0, run.stderr
    assert doc["cusps"] >= 1 and doc["vehicle"] == pytest.approx(LONG)
    rows = np.asarray(doc["path"])
    assert _segment_curvature(rows) <= 1.0 / 9.0 + 2e-3
    assert _least_clearance(docs["tl.json"], LONG, rows[:, :3]) > 0.0


# ----------------------------------------------------------------------------- verify


def test_verify_without_and_with_map_judges_for_the_plans_car(files, plans, capsys):
    d, _ = files
    alone = _run(capsys, "verify", "tiny.plan.json", "--json", "-", cwd=d)
    assert alone.returncode == 0, alone.stdout + alone.stderr
    assert json.loads(alone.stdout)["kappa_max"] == pytest.approx(1 / 3)
    # The paper car's map: the tiny plan is still judged for the tiny car.
    other = _run(capsys, "verify", "tiny.plan.json", "paper.json", "--json", "-", cwd=d)
    assert other.returncode == 0, other.stdout + other.stderr
    assert json.loads(other.stdout)["kappa_max"] == pytest.approx(1 / 3)
    # The paper car's plan on the tiny car's map: the paper car, with a warning.
    back = _run(capsys, "verify", "paper.plan.json", "tiny.json", "--json", "-", cwd=d)
    assert back.returncode == 0, back.stdout + back.stderr
    assert json.loads(back.stdout)["kappa_max"] == pytest.approx(1 / 6)
    assert "its car is not the one the plan was made for" in back.stderr


def test_verify_fails_the_tiny_cars_path_when_the_plan_claims_the_paper_car(
    files, plans, capsys
):
    d, _ = files
    _, doc = plans["tiny"]
    (d / "claims_paper.json").write_text(json.dumps({**doc, "vehicle": PAPER}))
    code = cli_main(["verify", str(d / "claims_paper.json"), str(d / "tiny.json")])
    out = capsys.readouterr().out
    assert code == 1
    assert any(line.split()[:2] == ["FAIL", "curvature"] for line in out.splitlines()), out


# ----------------------------------------------------------------------------- simulate


@pytest.fixture(scope="module")
def sims(files):
    d, _ = files
    tiny = _cli("simulate", "tiny.json", "--json", "tiny.sim.json", "--plot", "tiny.png",
                "--trajectory", "tiny.csv", "--video", "tiny.mp4", "--video-stride", "60",
                cwd=d)  # fmt: skip
    long = _cli("simulate", "tl.json", "--reverse", "--json", "tl.sim.json", "--trajectory",
                "tl.csv", "--video", "tl.mp4", "--video-stride", "120", cwd=d)  # fmt: skip
    return {"tiny": tiny, "tl": long}


@pytest.mark.parametrize(("key", "mapfile", "car"), [("tiny", "tiny.json", TINY),
                                                     ("tl", "tl.json", LONG)])
def test_simulate_map_target_drives_the_files_car(files, sims, key, mapfile, car):
    d, docs = files
    run = sims[key]
    assert run.returncode == 0, run.stdout + run.stderr
    report = json.loads((d / f"{key}.sim.json").read_text())
    assert report["kappa_max"] == pytest.approx(1.0 / car["min_turning_radius"], rel=1e-5)
    assert report["success"] and not report["collision_footprint"]
    with open(d / f"{key}.csv", newline="") as f:
        rows = [{k: float(v) for k, v in r.items()} for r in csv.DictReader(f)]
    poses = [(r["x"], r["y"], r["yaw"]) for r in rows]
    # The driven body of that car stays clear; steering within its lock and rate.
    assert _least_clearance(docs[mapfile], car, poses) > 0.0
    steer = np.array([r["steer"] for r in rows])
    t = np.array([r["t"] for r in rows])
    assert np.max(np.abs(steer)) <= car["max_steer"] + 1e-9
    assert np.max(np.abs(np.diff(steer) / np.diff(t))) <= car["max_steer_rate"] + 1e-6
    assert (d / f"{key}.mp4").stat().st_size > 0


def _ego_box(frame: np.ndarray) -> tuple[int, int]:
    """Width and height in pixels of highway-env's ego colour (50, 200, 0) in a frame."""
    mask = np.all(np.abs(frame.astype(int) - (50, 200, 0)) < 30, axis=-1)
    ys, xs = np.nonzero(mask)
    return int(xs.max() - xs.min() + 1), int(ys.max() - ys.min() + 1)


def test_video_draws_each_files_car_at_its_size(files, sims):
    iio = pytest.importorskip("imageio.v3")
    d, _ = files
    assert sims["tiny"].returncode == 0 and sims["tl"].returncode == 0
    # Same map, same framing: the first frames (the car at (4, 6), yaw 0) differ by the car.
    tw, th = _ego_box(iio.imread(d / "tiny.mp4", index=0))
    lw, lh = _ego_box(iio.imread(d / "tl.mp4", index=0))
    assert lw / tw == pytest.approx(LONG["length"] / TINY["length"], rel=0.12)
    assert lh / th == pytest.approx(LONG["width"] / TINY["width"], rel=0.15)


def test_simulate_plot_draws_the_files_car(files, sims):
    from matplotlib.patches import Polygon as PolygonPatch

    from rrtdrive.planning import make_planner, solve_on_map
    from rrtdrive.plotting import plot_plan
    from rrtdrive.sim.episode_plot import plot_episode
    from rrtdrive.sim.runner import run_episode
    from rrtdrive.sim.tasks import CustomTask

    d, _ = files
    assert (d / "tiny.png").stat().st_size > 0
    m = load_map(d / "tiny.json")
    fig = plot_episode(run_episode(CustomTask.from_map(m)))
    _, result = solve_on_map(lambda: make_planner("improved-rrt-connect"), m,
                             np.random.default_rng(0), Budget())  # fmt: skip
    fig2 = plot_plan(m, result)
    area = TINY["length"] * TINY["width"]
    for f in (fig, fig2):
        polys = [shapely.Polygon(p.get_xy()) for p in f.axes[0].patches
                 if isinstance(p, PolygonPatch)]  # fmt: skip
        cars = [p for p in polys if p.area == pytest.approx(area, rel=1e-6)]
        assert len(cars) >= 2, [round(p.area, 2) for p in polys]
        start = _body(TINY, *U_TURN["start"])
        assert any(p.symmetric_difference(start).area < 1e-6 for p in cars)
        assert not any(p.area == pytest.approx(4.3 * 1.8, rel=1e-3) for p in polys)
    import matplotlib.pyplot as plt

    plt.close("all")


def test_simulate_path_drives_the_plans_car_where_only_it_fits(files, capsys):
    d, _ = files
    # A start 0.6 m below the wall: the tiny body fits (half-width 0.6), the paper's not.
    code, err = _in_process(capsys, "plan", str(d / "tiny.json"), "--start", "4,8.8,0",
                            "--json", str(d / "close.json"))  # fmt: skip
    assert code == 0, err
    code, err = _in_process(capsys, "plan", str(d / "paper.json"), "--start", "4,8.8,0")
    assert code == 2 and "--start" in err
    run = _run(capsys, "simulate", "paper.json", "--path", "close.json", "--json", "-", cwd=d)
    assert run.returncode == 0, run.stderr
    report = json.loads(run.stdout)
    assert report["success"] and report["kappa_max"] == pytest.approx(1 / 3, rel=1e-5)


# ----------------------------------------------------------------------------- bench


@pytest.fixture(scope="module")
def bench_rows(files):
    """bench --maps long.json,mine.json (the tiny car): its rows, long.json's first."""
    d, _ = files
    (d / "mine.json").write_text(json.dumps({**U_TURN, "vehicle": TINY}))
    run = _cli("bench", "--maps", "long.json,mine.json", "--seeds", "1", "--workers", "1",
               "--out", "b", "--no-plots", "--quiet", cwd=d)  # fmt: skip
    assert run.returncode == 0, run.stderr
    return [json.loads(line) for line in (d / "b/runs.jsonl").read_text().splitlines()]


def test_bench_maps_rows_are_for_each_files_car_and_a_changed_car_is_run_again(
    files, bench_rows
):
    d, _ = files
    rows = {r["map"]: r for r in bench_rows}
    for name, car in (("mine.json", TINY), ("long.json", LONG)):
        row = rows[name]
        assert row["success"] and row["verified"]
        assert row["kappa_max"] == pytest.approx(1 / car["min_turning_radius"])
        assert row["max_curvature"] <= row["kappa_max"] + 1e-9
    summary = (d / "b/summary.md").read_text()
    assert "| mine.json |" in summary and "| long.json |" in summary
    # Another car in the same file: not a resumed row of the old car.
    wider = {**TINY, "width": 1.0, "min_turning_radius": 4.0}
    (d / "mine.json").write_text(json.dumps({**U_TURN, "vehicle": wider}))
    again = _cli("bench", "--maps", "mine.json", "--seeds", "1", "--workers", "1",
                 "--out", "b", "--no-plots", "--quiet", cwd=d)  # fmt: skip
    assert again.returncode == 0 and "0 resumed" in again.stderr + again.stdout
    last = json.loads((d / "b/runs.jsonl").read_text().splitlines()[-1])
    assert last["kappa_max"] == pytest.approx(0.25)


def test_bench_curvature_plot_judges_each_run_by_its_own_car(bench_rows, tmp_path, monkeypatch):
    import rrtdrive.plotting
    from rrtdrive.bench.summary import write_plots

    assert all(r["max_curvature"] <= r["kappa_max"] + 1e-9 for r in bench_rows)
    figures = {}
    monkeypatch.setattr(rrtdrive.plotting, "save_figure",
                        lambda fig, path, *a, **k: figures.__setitem__(str(path), fig))  # fmt: skip
    write_plots(bench_rows, tmp_path)
    (fig,) = [f for p, f in figures.items() if p.endswith("curvature_hist.png")]
    from matplotlib.colors import to_rgb

    red = [
        bar for ax in fig.axes for bar in ax.patches
        if bar.get_height() > 0 and to_rgb(bar.get_facecolor()) == to_rgb("tab:red")
    ]  # fmt: skip
    assert not red, "runs within their own car's bound are drawn as over it"


# ----------------------------------------------------------------------------- bad cars


BAD = [
    ({"width": -1}, "vehicle.width"),
    ({"width": "1.2"}, "vehicle.width"),
    ({"length": True}, "vehicle.length"),
    ({"wheelbase": 3.0}, "vehicle.wheelbase"),
    ({"max_steer": 2.0}, "vehicle.max_steer"),
    ({"max_steer_rate": 0}, "vehicle.max_steer_rate"),
    ({"min_turning_radius": 1.0}, "vehicle.min_turning_radius"),
    ({"lenght": 3.0}, "vehicle: unknown key"),
]


@pytest.mark.parametrize(("change", "named"), BAD)
def test_a_bad_car_in_a_map_file_is_one_line_naming_the_key(tmp_path, capsys, change, named):
    (tmp_path / "bad.json").write_text(json.dumps({**U_TURN, "vehicle": {**TINY, **change}}))
    bad = str(tmp_path / "bad.json")
    (tmp_path / "p.json").write_text(json.dumps({"path": [[4, 6, 0], [5, 6, 0]]}))
    for argv in (("plan", bad), ("simulate", bad), ("verify", str(tmp_path / "p.json"), bad),
                 ("bench", "--maps", bad, "--out", str(tmp_path / "b"))):  # fmt: skip
        code, err = _in_process(capsys, *argv)
        assert code == 2, (argv, err)
        assert len(err.strip().splitlines()) == 1 and named in err, (argv, err)


def test_a_bad_car_in_a_plan_is_one_line_naming_plan_vehicle(files, plans, capsys):
    d, _ = files
    _, doc = plans["tiny"]
    (d / "badcar.plan.json").write_text(json.dumps({**doc, "vehicle": {**TINY, "width": 0}}))
    code, err = _in_process(capsys, "verify", str(d / "badcar.plan.json"))
    assert code == 2 and len(err.strip().splitlines()) == 1
    assert "plan.vehicle.width" in err
    code, err = _in_process(capsys, "simulate", str(d / "tiny.json"), "--path",
                            str(d / "badcar.plan.json"))  # fmt: skip
    assert code == 2 and len(err.strip().splitlines()) == 1 and "vehicle.width" in err


def test_a_bad_car_in_a_gym_map_file_names_the_key(tmp_path):
    gym = pytest.importorskip("gymnasium")
    import rrtdrive.envs  # noqa: F401  (registers the ids)

    (tmp_path / "bad.json").write_text(json.dumps({**U_TURN, "vehicle": {**TINY, "width": 0}}))
    with pytest.raises(InputError, match=r"vehicle\.width"):
        gym.make("rrtdrive/Map-v0", scenario=str(tmp_path / "bad.json"))


# ----------------------------------------------------------------------------- maps


def test_export_writes_no_car_and_an_added_car_is_the_one_planned_for(tmp_path, capsys):
    code, err = _in_process(capsys, "maps", "--export", str(tmp_path / "exp"))
    assert code == 0, err
    doc = json.loads((tmp_path / "exp/overtake.json").read_text())
    assert "vehicle" not in doc
    assert load_map(tmp_path / "exp/overtake.json").vehicle == VehicleParams()
    doc["vehicle"] = LONG
    (tmp_path / "mine.json").write_text(json.dumps(doc))
    code, err = _in_process(capsys, "plan", str(tmp_path / "mine.json"), "--json",
                            str(tmp_path / "p.json"))  # fmt: skip
    assert code == 0, err
    plan = json.loads((tmp_path / "p.json").read_text())
    assert plan["vehicle"] == pytest.approx(LONG)
    assert _least_clearance(doc, LONG, np.asarray(plan["path"])[:, :3]) > 0.0


def _corridor_png(path) -> None:
    """30 x 10 m at 0.1 m per pixel: a 1.6 m corridor for x < 15 m, open beyond."""
    iio = pytest.importorskip("imageio.v3")
    img = np.full((100, 300), 255, np.uint8)
    img[: int(round((10 - 5.8) / 0.1)), :150] = 0  # y above 5.8
    img[int(round((10 - 4.2) / 0.1)) :, :150] = 0  # y below 4.2
    iio.imwrite(path, img)


def test_an_imported_map_takes_a_car_added_by_hand(tmp_path, capsys):
    _corridor_png(tmp_path / "corr.png")
    code, err = _in_process(capsys, "maps", "--import", str(tmp_path / "corr.png"),
                            "--resolution", "0.1", "--start", "20,5,0", "--goal", "26,5,0",
                            "--out", str(tmp_path / "corr.json"))  # fmt: skip
    assert code == 0, err
    doc = json.loads((tmp_path / "corr.json").read_text())
    doc["vehicle"] = TINY
    doc["start"] = [2.0, 5.0, 0.0]  # in the corridor: only the tiny car fits there
    (tmp_path / "tiny_corr.json").write_text(json.dumps(doc))
    assert load_map(tmp_path / "tiny_corr.json").vehicle.width == 1.2


def test_import_can_make_a_map_for_another_car(tmp_path, capsys):
    _corridor_png(tmp_path / "corr.png")
    base = ["maps", "--import", str(tmp_path / "corr.png"), "--resolution", "0.1",
            "--start", "2,5,0", "--goal", "26,5,0", "--out", str(tmp_path / "c.json")]  # fmt: skip
    code, err = _in_process(capsys, *base)
    assert code == 2 and "--start" in err  # the paper's 1.8 m car does not fit a 1.6 m corridor
    with pytest.raises(SystemExit):
        cli_main(["maps", "--help"])
    parser_help = capsys.readouterr().out
    flags = [line.split()[0] for line in parser_help.splitlines()
             if line.strip().startswith("--") and ("car" in line or "vehicle" in line)]
    assert flags, "maps --import offers no option naming the car"
    tiny = json.dumps(TINY)
    code, err = _in_process(capsys, *base, "--vehicle", tiny)
    assert code == 0, err
    assert load_map(tmp_path / "c.json").vehicle == VehicleParams(**TINY)


# ----------------------------------------------------------------------------- gym


def test_gym_map_env_from_a_file_and_a_map_is_that_car(files):
    gym = pytest.importorskip("gymnasium")
    import rrtdrive.envs  # noqa: F401

    d, _ = files
    m = load_map(d / "long.json")
    for scenario in (str(d / "long.json"), m):
        env = gym.make("rrtdrive/Map-v0", scenario=scenario)
        env.reset(seed=0)
        u = env.unwrapped
        for _ in range(20):
            env.step(np.array([0.5, 1.0], np.float32))
        ego = u._ego
        assert (ego.LENGTH, ego.WIDTH) == (LONG["length"], LONG["width"])
        # highway-env's collision polygon is that car's body at the ego's rear axle.
        hull = shapely.Polygon(ego.polygon()[:4])
        assert hull.symmetric_difference(_body(LONG, *ego.rear)).area < 1e-6
        # Full action steers to the car's curvature limit; the observation's bound its lock.
        assert abs(ego.steer) <= math.atan(LONG["wheelbase"] / LONG["min_turning_radius"]) + 1e-9
        assert env.observation_space.high[1] == pytest.approx(LONG["max_steer"], rel=1e-6)
        env.close()
    # The spec of a Map scenario survives its JSON round trip with the car.
    env = gym.make("rrtdrive/Map-v0", scenario=m)
    again = gym.make(gym.envs.registration.EnvSpec.from_json(env.spec.to_json()))
    again.reset(seed=0)
    assert again.unwrapped._ego.params == m.vehicle
    env.close()
    again.close()


def test_gym_render_draws_the_files_car_at_its_size(files):
    gym = pytest.importorskip("gymnasium")
    import rrtdrive.envs  # noqa: F401

    d, _ = files
    boxes = {}
    for name in ("tiny.json", "tl.json"):
        env = gym.make("rrtdrive/Map-v0", scenario=str(d / name), render_mode="rgb_array",
                       scenario_options={"reverse": True})  # fmt: skip
        env.reset(seed=0)
        boxes[name] = _ego_box(env.render())
        env.close()
    (tw, th), (lw, lh) = boxes["tiny.json"], boxes["tl.json"]
    assert lw / tw == pytest.approx(LONG["length"] / TINY["length"], rel=0.12)
    assert lh / th == pytest.approx(LONG["width"] / TINY["width"], rel=0.15)


# ----------------------------------------------------------------------------- Python API


def test_load_save_round_trip_and_to_json(files, tmp_path):
    d, _ = files
    m = load_map(d / "tiny.json")
    assert m.vehicle == VehicleParams(**TINY)
    assert m.to_json()["vehicle"] == pytest.approx(TINY)
    save_map(m, tmp_path / "rt.json")
    assert load_map(tmp_path / "rt.json") == m
    paper = dataclasses.replace(m, vehicle=VehicleParams())
    assert "vehicle" not in paper.to_json()


def test_planning_problem_of_a_map_takes_the_maps_car(files):
    from rrtdrive import CollisionChecker
    from rrtdrive.planning import PlanningProblem

    d, _ = files
    m = load_map(d / "tiny.json")
    problem = PlanningProblem(m, CollisionChecker.for_map(m), m.start, m.goal)
    assert problem.vehicle == m.vehicle


def test_ompl_reeds_shepp_plans_for_the_files_car(files):
    pytest.importorskip("ompl")
    import rrtdrive.bench  # noqa: F401  (registers the OMPL comparators)
    from rrtdrive.planning import PlanningProblem, make_planner

    d, docs = files
    for name, car in (("tiny.json", TINY), ("tl.json", LONG)):
        m = load_map(d / name)
        problem = PlanningProblem.from_map(m, reverse=True)
        result = make_planner("ompl-rs-rrtconnect").solve(
            problem, np.random.default_rng(0), Budget(max_time_s=10.0))
        assert result.success, result.message
        rows = result.path.samples
        assert _segment_curvature(rows) <= 1.0 / car["min_turning_radius"] + 2e-3
        assert _least_clearance(docs[name], car, rows[:, :3]) >= 0.0


def test_map_json_with_a_car_is_checked_for_that_car():
    from rrtdrive.maps import map_from_json

    # A start 0.65 m below the wall: the tiny body clears it, the paper's 0.9 m half-width not.
    doc = {**U_TURN, "start": [4.0, 8.85, 0.0]}
    with pytest.raises(InputError, match="^start"):
        map_from_json(doc)
    assert map_from_json({**doc, "vehicle": TINY}).vehicle == VehicleParams(**TINY)
    assert map_from_json(doc, VehicleParams(**TINY)).vehicle.width == 1.2
    with pytest.raises(InputError, match="^start"):
        dataclasses.replace(map_from_json(doc, VehicleParams(**TINY)), vehicle=VehicleParams())


def _sharpness(rows, wheelbase: float, window: int = 4) -> float:
    """Largest change of the steering angle atan(L kappa) per metre, kappa from the yaw's
    turn per step, both averaged over ``window`` samples (about 1 m)."""
    a = np.asarray(rows, dtype=float)
    ds = np.hypot(*np.diff(a[:, :2], axis=0).T)
    moving = ds > 1e-9
    kappa = np.diff(np.unwrap(a[:, 2]))[moving] / ds[moving]
    s = np.cumsum(ds[moving])
    kernel = np.ones(window) / window
    delta = np.convolve(np.arctan(wheelbase * kappa), kernel, mode="valid")
    s = np.convolve(s, kernel, mode="valid")
    return float(np.max(np.abs(delta[window:] - delta[:-window]) / (s[window:] - s[:-window])))


def _arcs_smooth_plan(tmp_path, capsys, car: dict) -> dict:
    doc = builtin_map("parking_lot").to_json()
    if car:
        doc["vehicle"] = car
    (tmp_path / "lot.json").write_text(json.dumps(doc))
    code, err = _in_process(capsys, "plan", str(tmp_path / "lot.json"), "--planner",
                            "hybrid-a-star", "--planner-option", "curve=arcs",
                            "--planner-option", "smooth=true", "--json",
                            str(tmp_path / "p.json"))  # fmt: skip
    assert code == 0, err
    return json.loads((tmp_path / "p.json").read_text())


def test_hybrid_smooth_keeps_the_paper_cars_sharpness_bound(tmp_path, capsys):
    # The control: the paper's car, whose bound is 0.2 rad/m.
    plan = _arcs_smooth_plan(tmp_path, capsys, {})
    assert "1/1 segment(s) smoothed" in plan["message"]
    assert _sharpness(plan["path"], 2.51) <= 0.2 + 0.01


def test_hybrid_smooth_keeps_the_files_cars_sharpness_bound(tmp_path, capsys):
    plan = _arcs_smooth_plan(tmp_path, capsys, {"max_steer_rate": 0.1})
    # A segment said to be smoothed keeps that car's bound, max_steer_rate / 2 m/s (or
    # the path is given as the exact arcs, without the claim).
    if "1/1 segment(s) smoothed" in plan["message"]:
        assert _sharpness(plan["path"], 2.51) <= 0.1 / 2.0 + 0.01


def test_traffic_keeps_its_own_size_whatever_the_ego():
    gym = pytest.importorskip("gymnasium")
    import rrtdrive.envs  # noqa: F401

    env = gym.make("rrtdrive/OvertakeTraffic-v0",
                   scenario_options={"vehicle": VehicleParams(**TINY)})  # fmt: skip
    env.reset(seed=0)
    u = env.unwrapped
    ego = u._ego
    others = [v for v in u._road.vehicles if v is not ego]
    env.close()
    assert others and (ego.LENGTH, ego.WIDTH) == (2.5, 1.2)
    assert all((v.LENGTH, v.WIDTH) == (4.3, 1.8) for v in others), [
        (v.LENGTH, v.WIDTH) for v in others
    ]
