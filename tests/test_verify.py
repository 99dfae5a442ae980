"""The independent verifier must catch each kind of broken path."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.special import fresnel

from rrtdrive.maps import Map, Obstacle
from rrtdrive.types import InputError, Path, Pose, VehicleParams
from rrtdrive.verify import path_from_json, verify_path


def _arc_map() -> tuple[Map, Path]:
    # A quarter circle of radius 10 m (kappa 0.1 < 1/6) from (10, 10) heading +x.
    r = 10.0
    t = np.linspace(0.0, math.pi / 2, int(r * math.pi / 2 / 0.2) + 1)
    x = 10.0 + r * np.sin(t)
    y = 20.0 - r * np.cos(t)
    samples = np.column_stack([x, y, t, np.full_like(t, 1 / r)])
    m = Map("arc", (0.0, 0.0, 40.0, 40.0), (), Pose(10.0, 10.0, 0.0), Pose(20.0, 20.0, math.pi / 2))
    return m, Path(samples, samples[:, :2])


def test_good_arc_passes():
    m, p = _arc_map()
    check = verify_path(m, p)
    assert check.ok, check
    assert abs(check.max_discrete_curvature - 0.1) < 0.005


def test_obstacle_on_the_arc_is_caught():
    m, p = _arc_map()
    blocked = Map("arc", m.bounds, (Obstacle((17.07, 12.93), (1.0, 1.0)),), m.start, m.goal)
    check = verify_path(blocked, p)
    assert not check.collision_free and not check.ok


def test_tight_turn_is_caught():
    r = 4.0  # kappa 0.25 > 1/6
    t = np.linspace(0.0, math.pi / 2, 40)
    samples = np.column_stack([10 + r * np.sin(t), 20 - r * np.cos(t), t, np.full_like(t, 1 / r)])
    start, goal = Pose(10.0, 16.0, 0.0), Pose(14.0, 20.0, math.pi / 2)
    m = Map("tight", (0.0, 0.0, 40.0, 40.0), (), start, goal)
    check = verify_path(m, Path(samples, samples[:, :2]))
    assert not check.curvature_ok


def test_wrong_goal_heading_and_sparse_samples_are_caught():
    m, p = _arc_map()
    turned = Map("arc", m.bounds, (), m.start, Pose(20.0, 20.0, math.pi / 2 + 0.2))
    assert not verify_path(turned, p).headings_ok
    sparse = Path(p.samples[::3], p.waypoints)
    assert not verify_path(m, sparse).spacing_ok


# ----------------------------------------------------------------------------- gears

KAPPA = 0.125  # the reverse arc's steering curvature, below 1/6


def _reverse_map(obstacles=()) -> tuple[Map, Path]:
    """Forward 5 m from (10, 10, 0), cusp, reverse a quarter circle steering left to (7, 18)."""
    xs = np.linspace(10.0, 15.0, 26)
    fwd = np.column_stack([xs, np.full(26, 10.0), np.zeros(26), np.zeros(26), np.ones(26)])
    s = np.linspace(0.0, (math.pi / 2) / KAPPA, 64)  # about 0.2 m apart
    # Reversing, the yaw turns by -kappa per metre; the car travels along yaw + pi.
    yaw = -KAPPA * s
    x = 15.0 - np.sin(KAPPA * s) / KAPPA
    y = 10.0 + (1.0 - np.cos(KAPPA * s)) / KAPPA
    back = np.column_stack([x, y, yaw, np.full_like(s, KAPPA), -np.ones_like(s)])
    goal = Pose(float(x[-1]), float(y[-1]), float(yaw[-1]))
    m = Map("reverse", (0.0, 0.0, 40.0, 40.0), tuple(obstacles), Pose(10.0, 10.0, 0.0), goal)
    return m, Path(np.vstack([fwd, back]), np.zeros((0, 2)))


def _shapely_hit(m: Map, p: Path) -> bool:
    """Ground truth at the rows: nose-yaw bodies built here against the obstacles."""
    v = m.vehicle
    obstacles = [shapely.Polygon(o.corners()) for o in m.obstacles]
    for x, y, yaw in p.samples[:, :3]:
        c, s = math.cos(yaw), math.sin(yaw)
        local = [(-v.rear_overhang, -v.width / 2), (v.front_extent, -v.width / 2),
                 (v.front_extent, v.width / 2), (-v.rear_overhang, v.width / 2)]
        body = shapely.Polygon([(x + c * a - s * b, y + s * a + c * b) for a, b in local])
        if any(body.intersects(o) for o in obstacles):
            return True
    return False


def test_reverse_path_passes_per_segment():
    m, p = _reverse_map()
    assert p.cusps.tolist() == [26] and p.segments() == [(0, 26), (26, 90)]
    np.testing.assert_allclose(m.goal.as_tuple(), (7.0, 18.0, -math.pi / 2), atol=1e-9)
    check = verify_path(m, p)
    assert check.ok, check
    assert check.cusps == 1 and check.cusps_ok and check.travel_ok
    # Curvature within the segments only: across the cusp the corner would be sharp.
    assert abs(check.max_discrete_curvature - KAPPA) < 0.005
    assert check.travel_heading_err_deg < 0.5


def test_reverse_body_is_drawn_along_the_nose():
    # Behind the goal in its direction of travel: a body along the direction of travel
    # would reach it (its front 3.4 m up), the real body (nose down) keeps 1.1 m.
    m, p = _reverse_map([Obstacle((7.0, 20.5), (1.0, 1.0))])
    assert not _shapely_hit(m, p)
    assert verify_path(m, p).collision_free
    # Beside the front at the cusp: both must see it.
    m, p = _reverse_map([Obstacle((17.5, 10.8), (1.0, 0.6))])
    assert _shapely_hit(m, p)
    check = verify_path(m, p)
    assert not check.collision_free and not check.ok


def test_reverse_yaw_along_the_travel_is_caught():
    m, p = _reverse_map()
    s = p.samples.copy()
    s[26:, 2] += math.pi  # yaw of the direction of travel instead of the nose
    check = verify_path(m, Path(s, p.waypoints))
    assert not check.travel_ok and not check.ok
    assert check.travel_heading_err_deg > 170.0


def test_reverse_segment_labelled_forward_is_caught():
    m, p = _reverse_map()
    s = p.samples.copy()
    s[:, 4] = 1.0  # no cusp: the arc "driven forward" runs against its yaw
    check = verify_path(m, Path(s, p.waypoints))
    assert check.cusps == 0 and not check.travel_ok and not check.ok


def test_jumping_cusp_is_caught():
    m, p = _reverse_map()
    s = p.samples.copy()
    s[26:, 1] += 0.1  # the reverse leg starts 0.1 m off the cusp: within the spacing
    jumped = Map("reverse", m.bounds, (), m.start, Pose(m.goal.x, m.goal.y + 0.1, m.goal.yaw))
    check = verify_path(jumped, Path(s, p.waypoints))
    assert check.spacing_ok and check.endpoints_ok and check.travel_ok
    assert not check.cusps_ok and not check.ok
    s = p.samples.copy()
    s[26, 2] += 0.3  # the car turned on the spot at the cusp
    assert not verify_path(m, Path(s, p.waypoints)).cusps_ok


def test_reverse_goal_pose_is_exact():
    m, p = _reverse_map()
    turned = Map("reverse", m.bounds, (), m.start, Pose(m.goal.x, m.goal.y, m.goal.yaw + 0.2))
    check = verify_path(turned, p)
    assert not check.headings_ok and check.goal_heading_err_deg > 10.0
    moved = Map("reverse", m.bounds, (), m.start, Pose(m.goal.x + 0.05, m.goal.y, m.goal.yaw))
    assert not verify_path(moved, p).endpoints_ok


def test_path_from_json_reads_four_or_five_columns():
    m, p = _reverse_map()
    data = json.loads(json.dumps({"path": np.round(p.samples, 9).tolist(), "waypoints": []}))
    back = path_from_json(data)
    np.testing.assert_allclose(back.samples, p.samples, atol=1e-9)
    assert verify_path(m, back).ok
    _, arc = _arc_map()
    old = path_from_json({"path": arc.samples[:, :4].tolist(), "waypoints": [[0, 0], [1, 1]]})
    assert old.is_forward_only and old.samples.shape == (len(arc), 5) and len(old.waypoints) == 2
    assert path_from_json([]).samples.shape == (0, 5)
    with pytest.raises(InputError, match="path"):
        path_from_json([[0, 0, 0, 0], [0, 0, 0, 0, 1]])
    with pytest.raises(InputError, match="path.gear"):
        path_from_json([[0, 0, 0, 0, 0], [0.2, 0, 0, 0, 0]])


def _drive_segments(segments, start=(50.0, 50.0, 0.3), spacing=0.2) -> np.ndarray:
    """Exact rows of arcs ``(gear, kappa, length)``: the yaw turns by gear * kappa per metre."""
    x, y, yaw = start
    rows = []
    for gear, kappa, length in segments:
        s = np.linspace(0.0, length, max(2, math.ceil(length / spacing) + 1))
        travel = yaw if gear > 0 else yaw + math.pi
        w = gear * kappa
        # The chord of the arc, 2 sin(w s / 2) / w = s sinc(w s / 2 pi): exact for any w
        # (the difference of sines loses all digits as w -> 0).
        chord = s * np.sinc(w * s / (2 * math.pi))
        xs = x + chord * np.cos(travel + w * s / 2)
        ys = y + chord * np.sin(travel + w * s / 2)
        yaws = yaw + w * s
        rows.append(np.column_stack([xs, ys, yaws, np.full_like(s, kappa), np.full_like(s, gear)]))
        x, y, yaw = float(xs[-1]), float(ys[-1]), float(yaws[-1])
    return np.vstack(rows)


@settings(max_examples=40, deadline=None)
@given(st.lists(st.tuples(st.sampled_from([1, -1]), st.floats(-1 / 6, 1 / 6),
                          st.floats(1.0, 8.0)), min_size=1, max_size=4))
def test_exact_gear_arcs_pass_and_flipped_gears_fail(segments):
    rows = _drive_segments(segments)
    gears = [g for g, _, _ in segments]
    cusps = sum(a != b for a, b in zip(gears[:-1], gears[1:], strict=True))
    end = rows[-1]
    m = Map("open", (0.0, 0.0, 100.0, 100.0), (), Pose(50.0, 50.0, 0.3),
            Pose(float(end[0]), float(end[1]), float(end[2])))
    path = Path(rows, np.zeros((0, 2)))
    check = verify_path(m, path)
    assert check.ok and check.cusps == cusps, check
    assert check.max_discrete_curvature <= max(abs(k) for _, k, _ in segments) + 1e-3
    # The same geometry with the gears the other way round runs against its yaw.
    flipped = rows.copy()
    flipped[:, 4] *= -1
    assert not verify_path(m, Path(flipped, np.zeros((0, 2)))).travel_ok


def _clothoid_rows(rate: float, wheelbase: float, length: float, spacing: float) -> np.ndarray:
    """A straight 3 m lead, then a clothoid kappa = c s with steering rate ``rate`` at s = 0.

    Built with scipy's Fresnel integrals, not the planner's clothoids:
    ``d delta / ds = L c / (1 + (L kappa)^2)``, largest (``L c``) where kappa = 0.
    """
    c = rate / wheelbase
    s = np.linspace(0.0, length, max(3, math.ceil(length / spacing) + 1))
    scale = math.sqrt(math.pi / c)
    fs, fc = fresnel(s / scale)
    lead = np.linspace(-3.0, 0.0, 13)[:-1]
    x = np.concatenate([lead, scale * fc]) + 20.0
    y = np.concatenate([0.0 * lead, scale * fs]) + 20.0
    kappa = np.concatenate([0.0 * lead, c * s])
    yaw = np.concatenate([0.0 * lead, c * s * s / 2])
    return np.column_stack([x, y, yaw, kappa, np.ones_like(x)])


@settings(max_examples=30, deadline=None)
@given(st.floats(0.05, 0.6), st.floats(3.0, 12.0), st.floats(0.05, 0.25))
def test_sharpness_of_an_exact_clothoid_is_measured(rate, length, spacing):
    wheelbase = VehicleParams().wheelbase  # the map's car
    rows = _clothoid_rows(rate, wheelbase, length, spacing)
    # The rows' yaw runs on past a full turn; the goal's is the same heading in (-pi, pi].
    end = rows[-1]
    m = Map("open", (0.0, 0.0, 100.0, 100.0), (), Pose(17.0, 20.0, 0.0),
            Pose(end[0], end[1], math.remainder(end[2], 2.0 * math.pi)))
    path = Path(np.round(rows, 6), np.zeros((0, 2)))  # as the JSON carries it
    kappa_end = rate / wheelbase * length
    # The largest rate is at kappa = 0; the estimate sits between the rate at the
    # clothoid's far end and (a little under) that at its start.
    check = verify_path(m, path, max_sharpness=rate, curvature_tol=math.inf)
    low = rate / (1 + (wheelbase * kappa_end) ** 2)
    assert low - 1e-3 <= check.max_discrete_sharpness <= rate + 0.003, check
    assert check.sharpness_ok
    assert not verify_path(m, path, max_sharpness=0.8 * rate - 0.005,
                           curvature_tol=math.inf).sharpness_ok


def test_curvature_jump_fails_the_sharpness_bound_only_when_asked():
    # A line straight into a 10 m arc: the steering wheel would jump by atan(0.27).
    line = np.column_stack([np.arange(10.0, 20.0, 0.25), np.full(40, 10.0)])
    t = np.arange(0.0, 1.5, 0.025)
    arc = np.column_stack([20.0 + 10.0 * np.sin(t), 20.0 - 10.0 * np.cos(t)])
    xy = np.vstack([line, arc])
    yaw = np.concatenate([np.zeros(40), t])
    rows = np.column_stack([xy, yaw, np.concatenate([np.zeros(40), np.full(len(t), 0.1)])])
    m = Map("jump", (0.0, 0.0, 60.0, 60.0), (), Pose(10.0, 10.0, 0.0), Pose(*rows[-1, :3]))
    path = Path(rows, np.zeros((0, 2)))
    assert verify_path(m, path).ok
    check = verify_path(m, path, max_sharpness=0.2)
    assert not check.sharpness_ok and not check.ok
    assert check.max_discrete_sharpness > 0.4
    assert check.collision_free and check.curvature_ok and check.headings_ok


def test_exact_ends_are_exact_far_from_the_origin():
    # np.allclose's default rtol (1e-5) let a path 9.9 cm off its start and goal pass
    # as "exact" at 10 km from the origin.
    start, goal = Pose(10000.0, 10000.0, 0.0), Pose(10040.0, 10000.0, 0.0)
    m = Map("far", (9990.0, 9990.0, 10060.0, 10010.0), (), start, goal)
    xs = np.linspace(start.x, goal.x, 161)
    rows = np.column_stack([xs, np.full_like(xs, start.y), 0 * xs, 0 * xs, 1 + 0 * xs])
    assert verify_path(m, Path(rows, rows[[0, -1], :2])).endpoints_ok
    off = rows.copy()
    off[:, :2] += 0.07
    assert not verify_path(m, Path(off, off[[0, -1], :2])).endpoints_ok


@settings(max_examples=60, deadline=None)
@given(
    st.lists(
        st.tuples(st.floats(-50.0, 50.0), st.floats(-50.0, 50.0), st.floats(-7.0, 7.0)),
        min_size=1, max_size=20,
    )
)
def test_body_rectangles_are_the_rotated_box(poses: list[tuple[float, float, float]]) -> None:
    # The verifier's vectorised bodies against shapely's own rotate-and-translate of the
    # car's box (rear axle at the origin, nose along +x).
    from shapely import affinity

    from rrtdrive.verify_bodies import body_polygons

    v = VehicleParams()
    p = np.array(poses, dtype=float)
    got = body_polygons(p, v.length, v.width, v.rear_overhang)
    box = shapely.box(-v.rear_overhang, -v.width / 2, v.length - v.rear_overhang, v.width / 2)
    for body, (x, y, yaw) in zip(got, poses, strict=True):
        want = affinity.translate(affinity.rotate(box, yaw, origin=(0, 0), use_radians=True), x, y)
        assert body.is_valid and body.area == pytest.approx(v.length * v.width)
        assert shapely.hausdorff_distance(body, want) < 1e-9
