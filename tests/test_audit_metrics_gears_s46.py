"""Audit (session 46): the episode metrics on drives with gear changes and on parking.

Every number of ``evaluate(episode)`` (and of ``rrtdrive simulate --json``) is
recomputed here from the logged arrays alone, with numpy / shapely / scipy, as
docs/metrics.md defines it: the tracking errors against the gear segment being
driven (an in-order least-cost assignment written afresh), progress, gears, the
comfort and curvature figures, the goal terms, the footprint judge (shapely body
rectangles on a 0.1 m densified trace), the interaction figures against the parked
row of ``parallel-parking``, and nuPlan's Savitzky-Golay comfort figures. The
episodes: ``parallel-parking``, ``u-turn``, ``parking-reverse-in`` and ``parking``
with pure pursuit, Stanley and LQR, seeds 0 and 1, each driven once per module;
plus two crashes (the parallel-parking plan shifted toward the kerb), a timeout in
the middle of the manoeuvre, and the CLI's JSON / trajectory CSV.
"""

from __future__ import annotations

import json
import math
import subprocess
import sys

import numpy as np
import pytest
import shapely
from scipy.signal import savgol_filter

from rrtdrive.evaluation import METRICS, Outcome, evaluate, failure_reason
from rrtdrive.sim.episode import TRAJECTORY_COLUMNS
from rrtdrive.sim.runner import EpisodeConfig, run_episode
from rrtdrive.sim.tasks import make_variant
from rrtdrive.types import Path

SCENARIOS = ("parallel-parking", "u-turn", "parking-reverse-in", "parking")
CONTROLLERS = ("pure-pursuit", "stanley", "lqr")
SEEDS = (0, 1)
KEYS = [(s, c, seed) for s in SCENARIOS for c in CONTROLLERS for seed in SEEDS]
GEAR_SCENARIOS = ("parallel-parking", "u-turn", "parking-reverse-in")


def _close(got, want, rel=1e-9, abs_=1e-12):
    assert got is not None, want
    assert math.isclose(float(got), float(want), rel_tol=rel, abs_tol=abs_), (got, want)


def _wrap(a):
    return (np.asarray(a, dtype=float) + np.pi) % (2.0 * np.pi) - np.pi


# --------------------------------------------------------------------------- recompute
def _runs(samples):
    """Gear segments of the path rows: split where the gear changes (the cusp position
    repeats), repeated positions dropped, length-less segments dropped and same-gear
    neighbours joined; each with the path length before it."""
    s = np.asarray(samples, dtype=float)
    cut = np.flatnonzero(s[1:, 4] != s[:-1, 4]) + 1
    edges = [0, *cut.tolist(), len(s)]
    out, s0 = [], 0.0
    for a, b in zip(edges[:-1], edges[1:], strict=True):
        seg = s[a:b]
        keep = np.concatenate([[True], np.hypot(*np.diff(seg[:, :2], axis=0).T) > 1e-9])
        seg = seg[keep]
        length = float(np.sum(np.hypot(*np.diff(seg[:, :2], axis=0).T)))
        if len(seg) >= 2:
            if out and out[-1][0] == int(seg[0, 4]):
                out[-1] = (out[-1][0], out[-1][1], np.vstack([out[-1][2], seg[1:]]))
            else:
                out.append((int(seg[0, 4]), s0, seg))
        s0 += length
    return out


def _project(seg, pts):
    """Nearest point on the polyline (shapely): distance, arc length, piece, fraction."""
    line = shapely.LineString(seg[:, :2])
    p = shapely.points(pts[:, :2])
    s = shapely.line_locate_point(line, p)
    d = shapely.distance(line, p)
    arc = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(seg[:, :2], axis=0).T))])
    j = np.clip(np.searchsorted(arc, s, side="right") - 1, 0, len(seg) - 2)
    frac = np.clip((s - arc[j]) / (arc[j + 1] - arc[j]), 0.0, 1.0)
    return d, s, j, frac


def _assign(runs, states):
    """The segment being driven: segments in order, never back, moving poses only on a
    segment of their gear (|v| >= 1e-4 m/s), a segment passed over at the cost of its
    length, least total distance (a plain O(n k^2) dynamic programme); a standing pose
    stays on the segment the car drove last (the tie rule of commit 9e904e9)."""
    n, k = len(states), len(runs)
    v = states[:, 3]
    moving = np.abs(v) >= 1e-4
    dist = np.stack([_project(r[2], states)[0] for r in runs], axis=1)
    gears = np.array([r[0] for r in runs])
    dist += np.where(moving[:, None] & (np.sign(v)[:, None] != gears[None, :]), 1e3, 0.0)
    lengths = np.array([np.sum(np.hypot(*np.diff(r[2][:, :2], axis=0).T)) for r in runs])
    idx = np.flatnonzero(moving)
    best = dist[idx[0]] + np.concatenate([[0.0], np.cumsum(lengths)])[:k]
    back = np.zeros((len(idx), k), dtype=int)
    back[0] = np.arange(k)
    for t in range(1, len(idx)):
        nxt = np.empty(k)
        for j in range(k):
            cands = [best[i] + lengths[i + 1 : j].sum() for i in range(j + 1)]
            i = int(np.argmin(cands))
            nxt[j], back[t, j] = cands[i] + dist[idx[t], j], i
        best = nxt
    chosen = np.zeros(len(idx), dtype=int)
    chosen[-1] = int(np.argmin(best))
    for t in range(len(idx) - 1, 0, -1):
        chosen[t - 1] = back[t, chosen[t]]
    out = np.zeros(n, dtype=int)
    out[idx] = chosen
    last = np.maximum.accumulate(np.where(moving, np.arange(n), -1))
    out[~moving] = np.where(last[~moving] >= 0, out[np.maximum(last[~moving], 0)], chosen[0])
    return out


def _tracking(samples, states):
    runs = _runs(samples)
    which = _assign(runs, states) if len(runs) > 1 else np.zeros(len(states), dtype=int)
    cte, herr, along = (np.zeros(len(states)) for _ in range(3))
    for k, (_, s0, seg) in enumerate(runs):
        m = which == k
        if not m.any():
            continue
        p = states[m]
        d, s, j, f = _project(seg, p)
        foot = seg[j, :2] + f[:, None] * (seg[j + 1, :2] - seg[j, :2])
        dirn, off = seg[j + 1, :2] - seg[j, :2], p[:, :2] - foot
        cte[m] = np.where(dirn[:, 0] * off[:, 1] - dirn[:, 1] * off[:, 0] < 0, -d, d)
        yaw = np.unwrap(seg[:, 2])
        herr[m] = _wrap(p[:, 2] - (yaw[j] + f * (yaw[j + 1] - yaw[j])))
        along[m] = s0 + s
    return cte, herr, along, which, runs


def _body(x, y, yaw, veh):
    c, s = math.cos(yaw), math.sin(yaw)
    back, front, hw = -veh.rear_overhang, veh.length - veh.rear_overhang, veh.width / 2.0
    return shapely.Polygon(
        [(x + a * c - b * s, y + a * s + b * c) for a, b in
         ((back, -hw), (front, -hw), (front, hw), (back, hw))]
    )


def _box(cx, cy, yaw, length, width):
    c, s = math.cos(yaw), math.sin(yaw)
    hl, hw = length / 2.0, width / 2.0
    return shapely.Polygon(
        [(cx + a * c - b * s, cy + a * s + b * c) for a, b in
         ((-hl, -hw), (hl, -hw), (hl, hw), (-hl, hw))]
    )


def _densify(states, spacing=0.1):
    out = [states[0, :3]]
    for a, b in zip(states[:-1, :3], states[1:, :3], strict=True):
        n = max(1, math.ceil(math.hypot(b[0] - a[0], b[1] - a[1]) / spacing))
        turn = float(_wrap(b[2] - a[2]))
        for i in range(1, n + 1):
            f = i / n
            out.append([a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1]), a[2] + f * turn])
    return np.array(out)


def _footprint(ep):
    """(hit, clearance): the densified body against obstacles, bounds and moved cars."""
    m, veh = ep.scenario.map, ep.scenario.vehicle
    obstacles = [_box(o.center[0], o.center[1], o.yaw, *o.size) for o in m.obstacles]
    x0, y0, x1, y1 = m.bounds
    inside = shapely.box(x0, y0, x1, y1)
    walls = inside.exterior
    bodies = [_body(*p, veh) for p in _densify(np.asarray(ep.log.states))]
    hit = not all(inside.covers(b) for b in bodies)
    clearance = min(b.distance(walls) for b in bodies)
    if obstacles:
        tree = shapely.STRtree(obstacles)
        for b in bodies:
            hit = hit or bool(len(tree.query(b, predicate="intersects")))
            clearance = min(clearance, b.distance(obstacles[tree.nearest(b)]))
    st, others = np.asarray(ep.log.states), np.asarray(ep.log.others)
    for k, (length, width) in enumerate(np.asarray(ep.log.other_sizes)):
        o = others[:, k]
        if np.ptp(o[:, 0]) or np.ptp(o[:, 1]):  # a car that moved (not in the map)
            for t in range(len(st)):
                hit = hit or _body(*st[t, :3], veh).intersects(_box(*o[t, :3], length, width))
    return hit, clearance


def _nuplan(t, yaw, v, d, step=0.1):
    stride = round(step / (t[1] - t[0]))
    t, h, v = t[::stride], np.unwrap(yaw[::stride]), v[::stride]
    w = np.gradient(h, t)
    ax = np.gradient(v, t)
    ay = v * w
    centre_x = ax + d * (w**2 + np.gradient(w, t))

    def sg(y, window, order, deriv=0):
        return savgol_filter(y, min(window, len(y)), order, deriv=deriv, delta=step)

    lon = sg(centre_x, 8, 2)
    return {
        "nuplan_lon_accel_min": lon.min(),
        "nuplan_lon_accel_max": lon.max(),
        "nuplan_lat_accel_abs_max": np.abs(sg(ay, 8, 2)).max(),
        "nuplan_lon_jerk_abs_max": np.abs(sg(lon, 15, 2, 1)).max(),
        "nuplan_jerk_abs_max": np.abs(sg(sg(np.hypot(ax, ay), 8, 2), 15, 2, 1)).max(),
        "nuplan_yaw_rate_abs_max": np.abs(sg(h, 5, 2, 1)).max(),
        "nuplan_yaw_accel_abs_max": np.abs(sg(h, 5, 3, 2)).max(),
    }


def _recompute(ep):
    log, veh = ep.log, ep.scenario.vehicle
    st = np.asarray(log.states)
    acc, steer = np.asarray(log.controls)[:, 0], np.asarray(log.controls)[:, 1]
    samples = np.asarray(ep.path.samples)
    cte, herr, along, which, runs = _tracking(samples, st)
    kappa = np.tan(steer) / veh.wheelbase
    lat = st[:-1, 3] ** 2 * kappa
    rate = np.abs(np.diff(np.concatenate([[0.0], steer]))) / log.dt
    signs = np.sign(st[:, 3][st[:, 3] != 0.0])
    ds = np.hypot(*np.diff(samples[:, :2], axis=0).T)
    dd = np.abs(np.diff(np.arctan(veh.wheelbase * samples[:, 3])))
    g = ep.scenario.goal
    out = {
        "cte_rms_m": np.sqrt(np.mean(cte**2)),
        "cte_max_m": np.abs(cte).max(),
        "heading_err_rms_rad": np.sqrt(np.mean(herr**2)),
        "heading_err_max_rad": np.abs(herr).max(),
        "progress_m": along[-1] - along[0],
        "path_length_m": ds.sum(),
        "path_max_curvature": np.abs(samples[:, 3]).max(),
        "path_max_sharpness": np.max(dd[ds > 1e-9] / ds[ds > 1e-9]),
        "path_cusps": np.count_nonzero(samples[1:, 4] != samples[:-1, 4]),
        "gear_changes": np.count_nonzero(signs[1:] != signs[:-1]),
        "executed_max_curvature": np.abs(kappa).max(),
        "executed_curvature_violation_share": np.mean(
            np.abs(kappa) > veh.kappa_max * (1.0 + 1e-9)
        ),
        "max_lateral_accel": np.abs(lat).max(),
        "max_long_accel": np.abs(acc).max(),
        "max_jerk": np.max(np.hypot(np.diff(acc), np.diff(lat))) / log.dt,
        "max_steering_rate": rate.max(),
        "steering_rate_over_limit_share": np.mean(rate > 0.4 + 1e-9),
        "goal_position_err_m": math.hypot(st[-1, 0] - g.x, st[-1, 1] - g.y),
        "goal_heading_err_rad": abs(float(_wrap(st[-1, 2] - g.yaw))),
        "final_speed": st[-1, 3],
        "steps": len(acc),
        "duration_s": log.t[-1],
        "simulation_frequency": 1.0 / log.dt,
    }
    out.update(_nuplan(np.asarray(log.t), st[:, 2], st[:, 3],
                       veh.length / 2.0 - veh.rear_overhang))
    return out, {"cte": cte, "which": which, "runs": runs}


def _drive(scenario, controller="pure-pursuit", seed=0, planner=None, config=None):
    kw = {} if planner is None else {"planner": planner}
    ep = run_episode(scenario, controller=controller, seed=seed, config=config, **kw)
    rep = evaluate(ep)
    mine, aux = _recompute(ep)
    return ep, rep, mine, aux


# ---------------------------------------------------------------------------- fixtures
@pytest.fixture(scope="module")
def drives():
    return {key: _drive(*key) for key in KEYS}


@pytest.fixture(scope="module")
def shifted(drives):
    """The parallel-parking seed-0 plan moved 0.3 m and 0.6 m toward the kerb, driven."""
    path = drives[("parallel-parking", "pure-pursuit", 0)][0].path
    out = {}
    for dy in (0.3, 0.6):
        s = np.array(path.samples)
        s[:, 1] -= dy
        out[dy] = _drive(make_variant("parallel-parking", 0), planner=Path(s, np.zeros((0, 2))))
    return out


@pytest.fixture(scope="module")
def cli(tmp_path_factory):
    """``simulate --json --trajectory``: u-turn twice (determinism) and the two spellings
    of the reverse-in parking."""
    d = tmp_path_factory.mktemp("cli")
    runs = {
        "u1": ["u-turn", "--seed", "1", "--controller", "stanley"],
        "u2": ["u-turn", "--seed", "1", "--controller", "stanley"],
        "ri": ["parking", "--reverse-in", "--seed", "0"],
        "ri2": ["parking-reverse-in", "--seed", "0"],
    }
    procs = {
        k: subprocess.Popen(
            [sys.executable, "-m", "rrtdrive", "simulate", *a, "--json", str(d / f"{k}.json"),
             "--trajectory", str(d / f"{k}.csv")],
            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
        )
        for k, a in runs.items()
    }
    out = {}
    for k, p in procs.items():
        _, err = p.communicate(timeout=120)
        assert p.returncode == 0, err
        out[k] = (json.loads((d / f"{k}.json").read_text()), (d / f"{k}.csv").read_text())
    return out


# ------------------------------------------------------------------------------- tests
TRACKING = ("cte_rms_m", "cte_max_m", "heading_err_rms_rad", "heading_err_max_rad",
            "progress_m")


@pytest.mark.parametrize("key", KEYS, ids=["-".join(map(str, k)) for k in KEYS])
def test_every_recomputed_metric_matches_its_definition(drives, key):
    ep, rep, mine, _ = drives[key]
    assert rep.status == "arrived" and rep.success, failure_reason(rep)
    for name, want in mine.items():
        # nuPlan's series go through three filters: a few ulps more.
        _close(getattr(rep, name), want, rel=1e-9 if name in TRACKING else 1e-8, abs_=1e-10)


@pytest.mark.parametrize("key", KEYS, ids=["-".join(map(str, k)) for k in KEYS])
def test_gears_driven_as_planned(drives, key):
    ep, rep, _, aux = drives[key]
    st, samples = np.asarray(ep.log.states), np.asarray(ep.path.samples)
    runs = aux["runs"]
    # The path convention: rows in driving order, yaw where the nose points, so a
    # reverse row's travel direction is opposite its nose.
    for gear, _, seg in runs:
        d = np.diff(seg[:, :2], axis=0)
        along = d[:, 0] * np.cos(seg[:-1, 2]) + d[:, 1] * np.sin(seg[:-1, 2])
        assert np.all(np.sign(along[np.abs(along) > 1e-6]) == gear)
    # The gears driven, in order, are the path's segments' gears, and each moving pose
    # is measured against a segment of its own gear.
    v = st[:, 3]
    moving = np.sign(v[v != 0.0])
    driven = [int(g) for i, g in enumerate(moving) if i == 0 or g != moving[i - 1]]
    assert driven == [g for g, _, _ in runs]
    assert rep.gear_changes == rep.path_cusps == len(runs) - 1
    gears = np.array([g for g, _, _ in runs])[aux["which"]]
    assert np.all(np.sign(v[np.abs(v) >= 1e-4]) == gears[np.abs(v) >= 1e-4])
    assert (rep.path_cusps > 0) == (key[0] in GEAR_SCENARIOS)
    # On arrival the travelled length is the path's whole length, all segments counted.
    assert rep.progress_m == pytest.approx(rep.path_length_m, abs=0.02)
    assert rep.path_length_m == pytest.approx(float(np.sum(
        np.hypot(*np.diff(samples[:, :2], axis=0).T))), rel=1e-12)


@pytest.mark.parametrize("key", KEYS, ids=["-".join(map(str, k)) for k in KEYS])
def test_success_terms_goal_and_time(drives, key):
    ep, rep, mine, _ = drives[key]
    pos, head, v = mine["goal_position_err_m"], mine["goal_heading_err_rad"], mine["final_speed"]
    assert rep.reached_goal == (pos <= 0.5 and head <= math.radians(10.0))
    assert rep.stopped == (abs(v) <= 0.1)
    assert rep.success == (rep.reached_goal and rep.stopped and rep.status == "arrived"
                           and not rep.collision)
    assert rep.outcome == Outcome.SUCCESS and failure_reason(rep) is None
    assert rep.passed_lead is None and rep.back_in_lane is None
    assert rep.time_to_goal_s == rep.completion_time_s == rep.duration_s
    t = np.asarray(ep.log.t)
    assert np.allclose(t, np.arange(len(t)) * ep.log.dt, rtol=0, atol=1e-9)
    assert rep.steps == len(t) - 1 and rep.simulation_frequency == pytest.approx(20.0)
    assert ep.scenario.max_time_s == 120.0
    assert rep.message == f"stopped at the end of the path at t = {rep.duration_s:.2f} s"
    # The executed curvature never passes the path bound (the controllers clip to it).
    assert rep.executed_curvature_violation_share == 0.0
    assert rep.executed_max_curvature <= ep.scenario.vehicle.kappa_max * (1 + 1e-9)
    assert rep.nuplan_comfortable == (
        rep.nuplan_lon_accel_min >= -4.05 and rep.nuplan_lon_accel_max <= 2.40
        and rep.nuplan_lat_accel_abs_max <= 4.89 and rep.nuplan_lon_jerk_abs_max <= 4.13
        and rep.nuplan_jerk_abs_max <= 8.37 and rep.nuplan_yaw_rate_abs_max <= 0.95
        and rep.nuplan_yaw_accel_abs_max <= 1.93
    )


@pytest.mark.parametrize("key", [k for k in KEYS if k[2] == 0],
                         ids=["-".join(map(str, k)) for k in KEYS if k[2] == 0])
def test_footprint_judge_agrees_with_shapely(drives, key):
    ep, rep, _, _ = drives[key]
    hit, clearance = _footprint(ep)
    assert rep.collision_footprint is hit is False
    assert clearance > 0.0
    assert rep.collision_highway_env is bool(np.any(ep.log.crashed)) is False
    assert rep.collision is False and rep.collisions_at_fault == 0


def test_interaction_against_the_parked_row(drives):
    """min_distance_m and ttc_min_s (reversing: the cone the way the car moves)."""
    ep, rep, _, _ = drives[("parallel-parking", "pure-pursuit", 0)]
    st, others = np.asarray(ep.log.states), np.asarray(ep.log.others)
    sizes, veh = np.asarray(ep.log.other_sizes), ep.scenario.vehicle
    assert others.shape[1] == len(sizes) > 0 and np.all(others[:, :, 3] == 0.0)
    ego = [_body(*p[:3], veh) for p in st]
    boxes = [_box(*o[:3], *sizes[k]) for k, o in enumerate(others[0])]
    dist = shapely.distance(np.array(ego)[:, None], np.array(boxes)[None, :])
    assert rep.min_distance_m == pytest.approx(float(dist.min()), rel=1e-9)
    dc = veh.length / 2.0 - veh.rear_overhang
    ttc = []
    for x, y, yaw, v in st:
        if abs(v) <= 5e-3:
            continue
        travel = yaw + (math.pi if v < 0 else 0.0)
        for k, o in enumerate(others[0]):
            if abs(float(_wrap(math.atan2(o[1] - y, o[0] - x) - travel))) > math.radians(30):
                continue
            for h in np.arange(0.1, 3.0, 0.1):
                cx = x + (dc + v * h) * math.cos(yaw)
                cy = y + (dc + v * h) * math.sin(yaw)
                if _box(cx, cy, yaw, veh.length, veh.width).intersects(boxes[k]):
                    ttc.append(h)
                    break
    assert ttc, "the reversing car never projected a collision with the row"
    assert rep.ttc_min_s == pytest.approx(min(ttc), abs=1e-9)
    assert rep.ttc_within_bound == (min(ttc) > 0.95)
    assert rep.collisions_vehicles == 0


@pytest.mark.parametrize("scenario", ["u-turn", "parking", "parking-reverse-in"])
def test_no_other_vehicle_means_null_interaction(drives, scenario):
    ep, rep, _, _ = drives[(scenario, "lqr", 0)]
    assert np.asarray(ep.log.others).size == 0  # parked cars are map obstacles here
    assert rep.ttc_min_s is None and rep.min_distance_m is None
    assert rep.ttc_within_bound is None and rep.collisions_vehicles == 0


def test_documented_parking_seed0_lengths(drives):
    """docs/metrics.md: parking seed 0 reports 83.3384 m of path and 83.3378 m of progress."""
    rep = drives[("parking", "pure-pursuit", 0)][1]
    assert rep.path_length_m == pytest.approx(83.3384, abs=5e-5)
    assert rep.progress_m == pytest.approx(83.3378, abs=5e-5)


def _terms_consistent(rep, mine):
    pos, head = mine["goal_position_err_m"], mine["goal_heading_err_rad"]
    assert rep.reached_goal == (pos <= 0.5 and head <= math.radians(10.0))
    assert rep.stopped == (abs(mine["final_speed"]) <= 0.1)
    reason = failure_reason(rep)
    assert ("the position error" in reason) == (pos > 0.5)
    assert ("the heading error" in reason) == (head > math.radians(10.0))
    assert ("the final speed" in reason) == (abs(mine["final_speed"]) > 0.1)


def test_crash_into_the_parked_row_both_judges(shifted):
    ep, rep, mine, _ = shifted[0.6]
    hit, clearance = _footprint(ep)
    assert hit and clearance == 0.0
    assert rep.status == "crashed" and rep.collision_footprint and rep.collision_highway_env
    assert rep.outcome == Outcome.COLLISION and not rep.success
    assert rep.collisions_vehicles == 1 and rep.collisions_at_fault == 1  # a stopped track
    assert rep.time_to_goal_s is None and rep.completion_time_s is None
    assert failure_reason(rep).startswith(
        "crashed: a collision reported by highway-env and the footprint judge")
    assert rep.gear_changes == 0 and rep.path_cusps == 3  # crashed before the first cusp
    assert rep.min_distance_m == 0.0
    _terms_consistent(rep, mine)
    for name, want in mine.items():
        _close(getattr(rep, name), want, rel=1e-8, abs_=1e-10)


def test_predicted_kerb_contact_is_highway_env_alone(shifted):
    """0.3 m toward the kerb: highway-env flags the contact it predicts for the next
    step (documented), the exact body never touched anything."""
    ep, rep, mine, _ = shifted[0.3]
    hit, clearance = _footprint(ep)
    assert not hit and 0.0 < clearance < 0.01
    assert rep.collision_highway_env and not rep.collision_footprint and rep.collision
    assert rep.outcome == Outcome.COLLISION and rep.collisions_vehicles == 0
    assert failure_reason(rep).startswith("crashed: a collision reported by highway-env;")
    assert rep.min_distance_m > 0.0
    _terms_consistent(rep, mine)
    for name, want in mine.items():
        _close(getattr(rep, name), want, rel=1e-8, abs_=1e-10)


def test_timeout_in_the_middle_of_the_manoeuvre():
    ep, rep, mine, _ = _drive("parallel-parking", "lqr", 0,
                              config=EpisodeConfig(max_time_s=30.0))
    assert rep.status == "timeout" and rep.outcome == Outcome.FAILED and not rep.success
    assert rep.message == "not stopped at the goal within 30 s"
    assert 0 < rep.gear_changes < rep.path_cusps
    assert 0 < rep.progress_m < rep.path_length_m
    assert rep.time_to_goal_s is None and rep.completion_time_s is None
    reason = failure_reason(rep)
    assert reason.startswith("timeout: ") and "did not arrive within 30 s" in reason
    _terms_consistent(rep, mine)
    for name, want in mine.items():
        _close(getattr(rep, name), want, rel=1e-8, abs_=1e-10)


def test_cli_json_is_the_report_and_the_csv_the_log(drives, cli):
    for run, key in (("u1", ("u-turn", "stanley", 1)),
                     ("ri", ("parking-reverse-in", "pure-pursuit", 0))):
        js, csv = cli[run]
        ep, rep, _, _ = drives[key]
        for name in METRICS:
            if name in ("wall_time_s", "planning_time_s"):
                continue
            want, got = getattr(rep, name), js[name]
            if isinstance(want, float):
                assert got == pytest.approx(want, rel=1e-5, abs=1e-12), name
            else:
                assert got == (want.value if hasattr(want, "value") else want), name
        lines = csv.splitlines()
        assert lines[0] == ",".join(TRAJECTORY_COLUMNS) == "t,x,y,yaw,speed,steer,accel,gear"
        rows = np.array([[float(x) for x in ln.split(",")] for ln in lines[1:]])
        assert len(rows) == js["steps"] + 1
        st, ctrl = np.asarray(ep.log.states), np.asarray(ep.log.controls)
        assert np.array_equal(rows[:, 0], ep.log.t) and np.array_equal(rows[:, 1:5], st)
        assert np.array_equal(rows[:-1, 5], ctrl[:, 1]) and rows[-1, 5] == ctrl[-1, 1]
        assert np.array_equal(rows[:-1, 6], ctrl[:, 0]) and rows[-1, 6] == 0.0
        # gear: the sign of the speed moving; standing, the last motion's (first's before).
        v, gear = rows[:, 4], rows[:, 7]
        for i in range(len(v)):
            moved = np.flatnonzero(v[: i + 1] != 0.0)
            ref = v[moved[-1]] if len(moved) else v[np.flatnonzero(v != 0.0)[0]]
            assert gear[i] == np.sign(ref), i
        assert np.count_nonzero(np.diff(gear)) == js["gear_changes"]
        rate = np.abs(np.diff(np.concatenate([[0.0], rows[:-1, 5]]))) * js["simulation_frequency"]
        assert js["max_steering_rate"] == pytest.approx(rate.max(), rel=1e-5)


def test_cli_determinism_and_the_two_spellings_of_reverse_in(cli):
    # The documented wall-clock fields, plus setup_time_s (a wall time the
    # "deterministic" row does not list: a rough edge of docs/metrics.md).
    clocks = {"total_time_s", "wall_time_s", "planning_time_s", "setup_time_s"}
    for a, b in (("u1", "u2"), ("ri", "ri2")):
        ja, jb = cli[a][0], cli[b][0]
        assert set(ja) == set(jb)
        assert {k for k in ja if ja[k] != jb[k]} <= clocks
        assert cli[a][1] == cli[b][1]
    ri = cli["ri"][0]
    assert ri["scenario"] == "parking" and ri["reverse_in"] is True and ri["reverse"] is True
    assert cli["u1"][0]["reverse"] is True and cli["u1"][0]["forward_u_turn_width_m"] == 14.652


@pytest.mark.parametrize("seed", SEEDS)
def test_scenario_settings_describe_the_scene(drives, seed):
    veh = make_variant("parking", seed).vehicle
    centre = veh.length / 2.0 - veh.rear_overhang
    pp = drives[("parallel-parking", "lqr", seed)][0].scenario
    xs = sorted(o.center[0] for o in pp.map.obstacles)
    gaps = np.diff(xs) - veh.length
    assert gaps.max() == pytest.approx(pp.gap_factor * veh.length, abs=1e-9)
    ut = drives[("u-turn", "lqr", seed)][0].scenario
    assert ut.map.bounds[3] - ut.map.bounds[1] < 14.652  # too narrow to turn forward
    for name in ("parking", "parking-reverse-in"):
        task = drives[(name, "lqr", seed)][0].scenario
        row, side, index = task.spot
        g = task.goal
        cx, cy = g.x + centre * math.cos(g.yaw), g.y + centre * math.sin(g.yaw)
        assert cx == pytest.approx(14 + 3 * (index + 0.5), abs=1e-9)
        assert (cy > (20, 45, 70)[row]) == (side == 1)
        # forward in: the nose toward the row's centre line (deep in the spot);
        # reverse-in: facing out of it, toward the aisle
        into = (cy - (20, 45, 70)[row]) * math.sin(g.yaw) < 0
        assert into == (name == "parking")


def test_python_api_is_deterministic(drives):
    ep = run_episode("u-turn", controller="lqr", seed=1)
    old = drives[("u-turn", "lqr", 1)][0]
    assert np.array_equal(ep.log.states, old.log.states)
    assert np.array_equal(ep.log.controls, old.log.controls)
    assert np.array_equal(ep.path.samples, old.path.samples)
