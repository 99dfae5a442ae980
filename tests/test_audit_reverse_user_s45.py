"""Audit (session 45): reverse gear end to end on maps a user writes, as an AV engineer.

Six small maps of our own (parallel parking into a 1.7 car-length kerbside gap, reversing
into a perpendicular bay, an angled bay, a dead end too narrow for a U-turn, a garage to
back out of, a tight car park whose goal faces a wall), each planned with
``rrtdrive plan MAP --reverse`` by the default planner and by ``hybrid-a-star``, checked by
``rrtdrive verify``, and driven by ``rrtdrive simulate MAP --reverse``; plus the maps made
impossible (gap too short, bay too narrow, street too narrow to turn).

Independent references: the rows' yaw turn per chord computed here (the sign of ``kappa``
against ``gear * dyaw / ds``), the direction of travel against the nose, and shapely for
the car's body against the obstacles and bounds, along the plan and along the executed
trajectory (``--trajectory``).
"""

from __future__ import annotations

import concurrent.futures
import csv
import json
import math
import subprocess
import sys

import numpy as np
import pytest

shapely_geometry = pytest.importorskip("shapely.geometry")
shapely_affinity = pytest.importorskip("shapely.affinity")

CAR_L, CAR_W, WHEELBASE = 4.3, 1.8, 2.51
REAR = (CAR_L - WHEELBASE) / 2  # 0.895 m behind the rear axle
KAPPA_MAX = 1.0 / 6.0
PLANNERS = ("improved-rrt-connect", "hybrid-a-star")
CONTROLLERS = ("pure-pursuit", "stanley", "lqr")
TIMINGS = {"planning_time_s", "setup_time_s", "diagnosis_time_s", "total_time_s", "wall_time_s"}


def _car(cx: float, cy: float, yaw: float = 0.0) -> dict:
    return {"center": [cx, cy], "size": [CAR_L, CAR_W], "yaw": yaw}


def _wall(x0: float, y0: float, x1: float, y1: float) -> dict:
    return {"center": [(x0 + x1) / 2, (y0 + y1) / 2], "size": [x1 - x0, y1 - y0], "yaw": 0.0}


def parallel_map(gap_cars: float) -> dict:
    """Kerbside cars at y = 1.2 and a gap of ``gap_cars`` car lengths; goal centred in it."""
    gap = gap_cars * CAR_L
    a_end = 14.15  # rear bumper end of the car before the gap (centre 12.0)
    b_c = a_end + gap + CAR_L / 2
    gx = a_end + (gap - CAR_L) / 2 + REAR
    return {
        "name": "u_parallel", "bounds": [0, 0, 40, 8],
        "obstacles": [_car(12.0, 1.2), _car(b_c, 1.2), _car(b_c + 5.3, 1.2)],
        "start": [3.0, 5.0, 0.0], "goal": [round(gx, 4), 1.2, 0.0],
    }  # fmt: skip


def perpendicular_map(pitch: float) -> dict:
    """Bays ``pitch`` apart, cars parked nose out (yaw 90 deg); the goal faces the aisle."""
    obs = [_car(20 + k * pitch, 2.65, math.pi / 2) for k in (-2, -1, 1, 2)]
    return {"name": "u_perp_bay", "bounds": [0, 0, 40, 16], "obstacles": obs,
            "start": [4.0, 11.0, 0.0], "goal": [20.0, 1.5, math.pi / 2]}  # fmt: skip


def angled_map() -> dict:
    a = math.radians(60)
    pitch = 2.7 / math.sin(a)
    off = CAR_L / 2 - REAR
    obs = [
        _car(20 + k * pitch + off * math.cos(a), 1.8 + off * math.sin(a), a) for k in (-2, -1, 1, 2)
    ]
    return {"name": "u_angled", "bounds": [0, 0, 40, 16], "obstacles": obs,
            "start": [4.0, 11.0, 0.0], "goal": [20.0, 1.8, a]}  # fmt: skip


def dead_end_map(width: float) -> dict:
    return {"name": "u_dead_end", "bounds": [0, 0, 30, width], "obstacles": [],
            "start": [8.0, 1.8 if width >= 7 else 1.5, 0.0],
            "goal": [8.0, width - (1.8 if width >= 7 else 1.5), math.pi]}  # fmt: skip


def garage_map() -> dict:
    """A 3.2 m wide garage open at the top; the car is parked nose in, 0.3 m off the back."""
    return {"name": "u_garage", "bounds": [0, 0, 30, 14],
            "obstacles": [_wall(9.6, 0, 10.0, 6.2), _wall(13.2, 0, 13.6, 6.2)],
            "start": [11.6, 0.3 + CAR_L - REAR, -math.pi / 2],
            "goal": [24.0, 10.0, 0.0]}  # fmt: skip


def wall_park_map() -> dict:
    """Bays nose-in against a wall (the top bound); the goal's nose is 0.3 m off it."""
    obs = [_car(x, 14 - 0.3 - CAR_L / 2, math.pi / 2) for x in (6.0, 8.7, 14.1, 16.8, 19.5)]
    obs.append(_wall(0, 0, 30, 2.5))
    return {"name": "u_wall_park", "bounds": [0, 0, 30, 14], "obstacles": obs,
            "start": [24.0, 6.0, math.pi],
            "goal": [11.4, 14 - 0.3 - (CAR_L - REAR), math.pi / 2]}  # fmt: skip


MAPS = {
    "u_parallel": parallel_map(1.7),
    "u_perp_bay": perpendicular_map(2.7),
    "u_angled": angled_map(),
    "u_dead_end": dead_end_map(7.0),
    "u_garage": garage_map(),
    "u_wall_park": wall_park_map(),
}
# CLI drives (with --trajectory and --json), one per controller; the API drives all 18.
CLI_CONTROLLER = {"u_parallel": "pure-pursuit", "u_dead_end": "stanley", "u_garage": "lqr"}
# ``rrtdrive verify`` on the command line for these plans; verify_path for the others.
CLI_VERIFY = "hybrid-a-star"


def _cli(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "rrtdrive", *args], capture_output=True, text=True, timeout=240
    )


def _wrap(a: float) -> float:
    return (a + math.pi) % (2 * math.pi) - math.pi


def _body(x: float, y: float, yaw: float):
    c, s = math.cos(yaw), math.sin(yaw)
    pts = [(x + c * lx - s * ly, y + s * lx + c * ly)
           for lx, ly in ((-REAR, -CAR_W / 2), (CAR_L - REAR, -CAR_W / 2),
                          (CAR_L - REAR, CAR_W / 2), (-REAR, CAR_W / 2))]  # fmt: skip
    return shapely_geometry.Polygon(pts)


def _obstacle(o: dict):
    (cx, cy), (ln, wd), yaw = o["center"], o["size"], o["yaw"]
    r = shapely_geometry.box(-ln / 2, -wd / 2, ln / 2, wd / 2)
    r = shapely_affinity.rotate(r, yaw, origin=(0, 0), use_radians=True)
    return shapely_affinity.translate(r, cx, cy)


def body_clearance(mp: dict, poses) -> float:
    """Least distance from the body at ``poses`` to obstacles or the bounds' edge (<0: hit)."""
    obs = [_obstacle(o) for o in mp["obstacles"]]
    inner = shapely_geometry.box(*mp["bounds"])
    least = math.inf
    for x, y, yaw in poses:
        b = _body(x, y, yaw)
        if not inner.contains(b) or any(b.intersects(o) for o in obs):
            return -1.0
        least = min([least, inner.exterior.distance(b)] + [b.distance(o) for o in obs])
    return least


def dense_poses(rows: np.ndarray, step: float = 0.05):
    for i in range(len(rows) - 1):
        a, b = rows[i], rows[i + 1]
        n = max(1, math.ceil(math.hypot(b[0] - a[0], b[1] - a[1]) / step))
        dyaw = _wrap(b[2] - a[2])
        for t in np.linspace(0.0, 1.0, n, endpoint=False):
            yield a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]), a[2] + t * dyaw
    yield tuple(rows[-1][:3])


def row_problems(plan: dict) -> list:
    """Our own reading of the rows [x, y, yaw, kappa, gear]; empty when consistent."""
    p = np.asarray(plan["path"], dtype=float)
    probs: list = []
    if p.ndim != 2 or p.shape[1] != 5:
        return [("shape", p.shape)]
    if not set(p[:, 4]) <= {1.0, -1.0}:
        probs.append(("gear values", set(p[:, 4])))
    changes = [i for i in range(len(p) - 1) if p[i, 4] != p[i + 1, 4]]
    if len(changes) != plan["cusps"]:
        probs.append(("cusps", len(changes), plan["cusps"]))
    for i in changes:  # a cusp repeats the pose with the new gear
        if np.abs(p[i, :2] - p[i + 1, :2]).max() > 1e-9 or abs(_wrap(p[i, 2] - p[i + 1, 2])) > 1e-9:
            probs.append(("cusp pose not repeated", i))
    travelled = 0.0
    for i in range(len(p) - 1):
        if i in changes:
            continue
        d = p[i + 1, :2] - p[i, :2]
        ds = float(np.hypot(*d))
        travelled += ds
        if ds > 0.25 + 1e-6:
            probs.append(("spacing", i, ds))
        if ds < 1e-9:
            continue
        # yaw is where the nose points: a step moves along it in gear +1, against it in -1
        along = (d[0] * math.cos(p[i, 2]) + d[1] * math.sin(p[i, 2])) / ds
        if along * p[i, 4] < math.cos(math.radians(3)):
            probs.append(("travel against gear", i, along, p[i, 4]))
        # kappa = tan(delta)/L in both gears: yaw turns by gear * kappa * ds
        implied = p[i, 4] * _wrap(p[i + 1, 2] - p[i, 2]) / ds
        given = 0.5 * (p[i, 3] + p[i + 1, 3])
        if abs(implied - given) > 0.01:
            probs.append(("kappa vs yaw turn", i, implied, given, p[i, 4]))
    if np.abs(p[:, 3]).max() > KAPPA_MAX + 1e-6:
        probs.append(("kappa above limit", np.abs(p[:, 3]).max()))
    if abs(travelled - plan["length_m"]) > 1e-3:
        probs.append(("length", travelled, plan["length_m"]))
    return probs


def reverse_turn_steps(plan: dict) -> int:
    """Reverse steps whose yaw turns clearly: the kappa-sign check was not vacuous."""
    p = np.asarray(plan["path"], dtype=float)
    n = 0
    for i in range(len(p) - 1):
        ds = math.hypot(*(p[i + 1, :2] - p[i, :2]))
        if p[i, 4] == p[i + 1, 4] == -1.0 and ds > 1e-6:
            implied = -_wrap(p[i + 1, 2] - p[i, 2]) / ds
            if abs(implied) > 0.05:
                assert np.sign(implied) == np.sign(p[i, 3] + p[i + 1, 3]), (i, implied, p[i, 3])
                n += 1
    return n


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """Every CLI command of the audit, two at a time."""
    d = tmp_path_factory.mktemp("reverse_user")
    for name, mp in MAPS.items():
        (d / f"{name}.json").write_text(json.dumps(mp))
    out: dict = {"dir": d}

    def plan(name: str, planner: str):
        f = d / f"{name}.{planner}.json"
        r = _cli(
            "plan", str(d / f"{name}.json"), "--reverse", "--planner", planner, "--json", str(f)
        )
        v = None
        if planner == CLI_VERIFY:
            cp = _cli("verify", str(f), str(d / f"{name}.json"), "--json", "-")
            v = {**json.loads(cp.stdout), "exit_code": cp.returncode}
        return (name, planner), (r, json.loads(f.read_text()), v)

    def drive(name: str):
        c = CLI_CONTROLLER[name]
        f, t = d / f"{name}.sim.json", d / f"{name}.csv"
        r = _cli("simulate", str(d / f"{name}.json"), "--reverse", "--controller", c,
                 "--json", str(f), "--trajectory", str(t))  # fmt: skip
        return ("sim", name), (r, json.loads(f.read_text()), t)

    with concurrent.futures.ThreadPoolExecutor(max_workers=2) as ex:
        jobs = [ex.submit(plan, n, p) for n in MAPS for p in PLANNERS]
        jobs += [ex.submit(drive, n) for n in CLI_CONTROLLER]
        for j in jobs:
            k, v = j.result()
            out[k] = v
    return out


@pytest.fixture(scope="module")
def drives(runs):
    """Every map x controller through the Python API (the code behind ``simulate``)."""
    from rrtdrive.evaluation import evaluate
    from rrtdrive.maps import load_map
    from rrtdrive.sim.runner import run_episode
    from rrtdrive.sim.tasks.custom import CustomTask

    out = {}
    for name in MAPS:
        m = load_map(str(runs["dir"] / f"{name}.json"))
        for c in CONTROLLERS:
            ep = run_episode(CustomTask.from_map(m, 0, reverse=True), controller=c, seed=0)
            out[name, c] = evaluate(ep).to_json()
            out[name, c]["_poses"] = ep.trajectory()[::2, 1:4]
    return out


@pytest.mark.parametrize("planner", PLANNERS)
@pytest.mark.parametrize("name", list(MAPS))
def test_plan_rows_are_consistent_and_keep_the_end_poses(runs, name, planner):
    r, plan, _ = runs[name, planner]
    assert r.returncode == 0, r.stderr
    assert plan["success"] and plan["status"] == "solved" and plan["reverse"] is True
    mp = MAPS[name]
    p = np.asarray(plan["path"], dtype=float)
    for row, pose in ((p[0], mp["start"]), (p[-1], mp["goal"])):
        assert math.hypot(row[0] - pose[0], row[1] - pose[1]) <= 1e-6
        assert abs(_wrap(row[2] - pose[2])) <= 2e-6
    assert row_problems(plan) == []
    assert plan["cusps"] >= 1 and (p[:, 4] == -1.0).any()
    assert reverse_turn_steps(plan) > 0  # reverse arcs were checked for the kappa sign
    assert plan["max_curvature"] == pytest.approx(np.abs(p[:, 3]).max(), abs=1e-6)


def test_each_scene_reverses_where_it_must(runs):
    """Gears at the ends follow from the geometry, whichever planner."""
    for planner in PLANNERS:
        gear = {n: np.asarray(runs[n, planner][1]["path"])[:, 4] for n in MAPS}
        assert gear["u_garage"][0] == -1.0  # nose 0.3 m from the garage's back: back out
        assert gear["u_perp_bay"][-1] == -1.0  # rear 0.6 m from the edge: reverse in
        assert gear["u_angled"][-1] == -1.0
        assert gear["u_wall_park"][-1] == 1.0  # nose 0.3 m from the wall: arrive forward
        assert runs["u_dead_end", planner][1]["cusps"] >= 2  # at least a three-point turn


@pytest.mark.parametrize("planner", PLANNERS)
@pytest.mark.parametrize("name", list(MAPS))
def test_plan_body_clear_by_shapely_and_verify_agrees(runs, name, planner):
    from rrtdrive.maps import load_map
    from rrtdrive.verify import path_from_json, verify_path

    _, plan, report = runs[name, planner]
    if report is None:  # the same checks through the API, with the CLI's default clearance
        m = load_map(str(runs["dir"] / f"{name}.json"))
        res = verify_path(m, path_from_json(plan), clearance=plan["body_clearance_m"] - 0.002)
        report = {"ok": res.ok, "failed": list(res.failed), "cusps": res.cusps,
                  "min_clearance_m": res.min_clearance_m}  # fmt: skip
    assert report["ok"] and report["failed"] == [] and report.get("exit_code", 0) == 0
    assert report["cusps"] == plan["cusps"]
    ours = body_clearance(MAPS[name], dense_poses(np.asarray(plan["path"], dtype=float)))
    assert ours >= plan["body_clearance_m"] - 0.003
    assert ours == pytest.approx(report["min_clearance_m"], abs=0.01)


@pytest.mark.parametrize("name", list(CLI_CONTROLLER))
def test_cli_drive_reaches_goal_without_touching_anything(runs, name):
    r, rep, traj = runs["sim", name]
    assert r.returncode == 0, r.stderr
    assert rep["success"] and rep["outcome"] == "success" and not rep["collision"]
    assert rep["controller"] == CLI_CONTROLLER[name] and rep["reverse"] is True
    rows = list(csv.DictReader(traj.open()))
    assert len(rows) == rep["steps"] + 1
    poses = [(float(t["x"]), float(t["y"]), float(t["yaw"])) for t in rows]
    assert body_clearance(MAPS[name], poses) > 0.0
    gx, gy, gyaw = MAPS[name]["goal"]
    assert math.hypot(poses[-1][0] - gx, poses[-1][1] - gy) == pytest.approx(
        rep["goal_position_err_m"], abs=1e-3
    )
    gears = [float(t["gear"]) for t in rows]
    assert sum(a != b for a, b in zip(gears, gears[1:], strict=False)) == rep["gear_changes"]
    for t in rows:  # moving rows: the gear column is the speed's sign
        if abs(float(t["speed"])) > 1e-3:
            assert math.copysign(1.0, float(t["speed"])) == float(t["gear"])


@pytest.mark.parametrize("controller", CONTROLLERS)
@pytest.mark.parametrize("name", list(MAPS))
def test_every_controller_drives_every_scene(drives, name, controller):
    rep = drives[name, controller]
    assert rep["success"] and not rep["collision"] and not rep["collision_footprint"]
    assert rep["goal_position_err_m"] < 0.1
    assert rep["goal_heading_err_rad"] < math.radians(2)
    assert rep["final_speed"] == pytest.approx(0.0, abs=1e-3)
    assert rep["path_cusps"] >= 1
    assert rep["gear_changes"] == rep["path_cusps"]  # one stop and gear change per cusp
    assert rep["cte_max_m"] < 0.05 and rep["heading_err_max_rad"] < 0.05
    assert (
        rep["cte_rms_m"] <= rep["cte_max_m"]
        and rep["heading_err_rms_rad"] <= rep["heading_err_max_rad"]
    )
    assert rep["executed_max_curvature"] <= KAPPA_MAX * (1 + 1e-5)
    assert rep["progress_m"] == pytest.approx(rep["path_length_m"], abs=0.05)
    assert body_clearance(MAPS[name], rep["_poses"]) > 0.0  # shapely: the drive touched nothing


def test_cli_and_api_drives_agree(runs, drives):
    """``simulate MAP --reverse --json`` is the API's episode, number for number."""
    for name in CLI_CONTROLLER:
        cli = runs["sim", name][1]
        api = drives[name, CLI_CONTROLLER[name]]
        for k in (
            "gear_changes",
            "path_cusps",
            "path_length_m",
            "goal_position_err_m",
            "cte_max_m",
            "steps",
        ):
            assert cli[k] == api[k], (name, k)


def test_seeded_plan_and_drive_repeat_exactly(runs, drives):
    d = runs["dir"]
    f = str(d / "u_dead_end.json")
    a, b = (_cli("plan", f, "--reverse", "--seed", "3", "--json", "-") for _ in range(2))
    ja, jb = json.loads(a.stdout), json.loads(b.stdout)
    assert ja["success"]
    assert {k for k in ja if ja[k] != jb[k]} <= TIMINGS
    from rrtdrive.evaluation import evaluate
    from rrtdrive.maps import load_map
    from rrtdrive.sim.runner import run_episode
    from rrtdrive.sim.tasks.custom import CustomTask

    m = load_map(str(d / "u_parallel.json"))
    reps = [
        evaluate(
            run_episode(CustomTask.from_map(m, 5, reverse=True), controller="stanley", seed=5)
        ).to_json()
        for _ in range(2)
    ]
    assert {k for k in reps[0] if reps[0][k] != reps[1][k]} <= TIMINGS
    assert reps[0]["success"] and reps[0]["gear_changes"] >= 1


def test_video_is_headless_short_and_not_blank(runs):
    iio = pytest.importorskip("imageio.v3")
    d = runs["dir"]
    mp4, js = d / "garage.mp4", d / "garage_video.json"
    r = _cli("simulate", str(d / "u_garage.json"), "--reverse", "--video", str(mp4),
             "--video-stride", "20", "--json", str(js))  # fmt: skip
    assert r.returncode == 0, r.stderr
    rep = json.loads(js.read_text())
    frames = iio.imread(mp4)
    assert abs(len(frames) - (rep["steps"] // 20 + 1)) <= 2
    assert all(f.std() > 5 for f in frames)  # not black / blank
    assert np.abs(frames[0].astype(int) - frames[-1].astype(int)).mean() > 0.1  # the car moved
    assert iio.immeta(mp4)["duration"] == pytest.approx(rep["duration_s"], abs=1.5)


@pytest.mark.parametrize("planner", PLANNERS)
def test_gap_too_short_is_named_in_user_terms(tmp_path, planner):
    gap_cars = 1.05
    f = tmp_path / "short.json"
    f.write_text(json.dumps(parallel_map(gap_cars)))
    r = _cli("plan", str(f), "--reverse", "--planner", planner, "--json", "-")
    assert r.returncode == 1
    out = json.loads(r.stdout)
    assert not out["success"] and out["path"] in (None, [])
    assert out["status"] in ("proven_unreachable", "no_path_in_budget")
    diag = out["diagnosis"]
    room = (gap_cars * CAR_L - CAR_L) / 2  # 0.107 m before and behind the car
    assert diag["kind"] == "boxed_in"
    assert diag["numbers"]["room_ahead_m"] == pytest.approx(room, abs=0.01)
    assert diag["numbers"]["room_behind_m"] == pytest.approx(room, abs=0.01)
    assert f"{room:.2f} m" in diag["message"] and "car length (4.30 m)" in diag["message"]
    assert "why:" in r.stderr


@pytest.mark.parametrize("planner", PLANNERS)
def test_bay_narrower_than_the_car_is_refused_naming_the_goal(tmp_path, planner):
    pitch = 1.75  # neighbours 1.70 m apart, the car 1.80 m wide
    f = tmp_path / "narrow.json"
    f.write_text(json.dumps(perpendicular_map(pitch)))
    r = _cli("plan", str(f), "--reverse", "--planner", planner)
    assert r.returncode == 2
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in r.stderr
    overlap = (CAR_W - (2 * pitch - CAR_W)) / 2
    assert "goal" in lines[0] and "overlaps obstacle" in lines[0]
    assert f"by {overlap:.2f} m" in lines[0]


def test_forward_only_says_why_reverse_is_needed(runs):
    d = runs["dir"]
    r = _cli("plan", str(d / "u_perp_bay.json"), "--json", "-")
    assert r.returncode == 1
    diag = json.loads(r.stdout)["diagnosis"]
    behind = MAPS["u_perp_bay"]["goal"][1] - REAR  # rear bumper to the map's edge
    assert diag["kind"] == "needs_reverse" and "try --reverse" in diag["message"]
    assert f"{behind:.2f} m behind its rear" in diag["message"]


def _tampered(plan: dict, how: str) -> dict:
    p = [list(r) for r in plan["path"]]
    cusp = next(i for i in range(len(p) - 1) if p[i][4] != p[i + 1][4])
    seg = [i for i in range(len(p)) if p[i][4] == -1.0]
    if how == "kappa_sign":
        for i in seg:
            p[i][3] = -p[i][3]
    elif how == "yaw_as_travel":
        for i in seg:
            p[i][2] = _wrap(p[i][2] + math.pi)
    elif how == "no_cusp_row":
        del p[cusp + 1]
    return {**plan, "path": p}


@pytest.mark.parametrize(
    ("how", "check"),
    [("kappa_sign", "kappa_ok"), ("yaw_as_travel", "travel_ok"), ("no_cusp_row", "cusps_ok")],
)
def test_verify_rejects_gear_conventions_broken(runs, how, check):
    from rrtdrive.maps import load_map
    from rrtdrive.verify import path_from_json, verify_path

    plan = runs["u_parallel", "hybrid-a-star"][1]
    bad = _tampered(plan, how)
    # our own reading sees the broken convention as well
    assert row_problems(bad) != []
    res = verify_path(load_map(str(runs["dir"] / "u_parallel.json")), path_from_json(bad))
    assert not res.ok and check in res.failed


@pytest.mark.xfail(
    strict=True,
    reason="OPEN (a decision for planning, session 45): the default planner on a street too "
    "narrow to turn (5 m, --reverse) reports postprocess_failed and leads with the tree "
    "stage's smoothing failure, though its Hybrid A* escalation then ran out of budget "
    "(hybrid-a-star alone: no_path_in_budget); tests/test_proof_leads_the_message.py and "
    "test_escalation_order.py keep that chronology for a failure without a proof",
)
def test_street_too_narrow_to_turn_fails_with_the_searchs_status(tmp_path):
    f = tmp_path / "de5.json"
    f.write_text(json.dumps(dead_end_map(5.0)))
    default = json.loads(_cli("plan", str(f), "--reverse", "--json", "-").stdout)
    hybrid = json.loads(
        _cli("plan", str(f), "--reverse", "--planner", "hybrid-a-star", "--json", "-").stdout
    )
    assert not default["success"] and not hybrid["success"]
    assert default["status"] == hybrid["status"]
    assert not default["message"].startswith("post-processing failed")
