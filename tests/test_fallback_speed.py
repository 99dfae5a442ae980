"""The Dubins fallback's fast paths give the old answers bit for bit.

:func:`sample_curves` against :func:`sample_pieces`, the batched body test
against one ``poses_free`` per path, the tight-only turns of
:func:`polygon_turns` against the full options, and ``_free_end`` against the old
one-candidate-at-a-time loop (written out here) on random poses of parking_lot.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from rrtdrive.maps import builtin_map
from rrtdrive.planning.base import cached_checker
from rrtdrive.planning.dubins import dubins_paths
from rrtdrive.planning.improved import fallback
from rrtdrive.planning.smoothing import SmoothingConfig
from rrtdrive.planning.smoothing.clothoid import clothoid_turn, turn_circle
from rrtdrive.planning.smoothing.clothoid_batch import CurveBatch, sample_curves
from rrtdrive.planning.smoothing.clothoid_curve import polygon_curve, polygon_turns, sample_pieces
from rrtdrive.types import Pose

SMOOTHING = SmoothingConfig()


def _random_curves(seed: int, count: int) -> list:
    """Clothoid-rounded random polygons: sharp and gentle corners, both directions."""
    rng = np.random.default_rng(seed)
    out = []
    while len(out) < count:
        n = int(rng.integers(2, 7))
        legs = rng.uniform(3.0, 40.0, n - 1)
        turns = rng.uniform(-0.97 * math.pi, 0.97 * math.pi, n - 1)
        turns[rng.random(n - 1) < 0.3] *= 0.05  # small deflections: clothoid-clothoid turns
        yaw = rng.uniform(-math.pi, math.pi)
        pts = [rng.uniform(-50.0, 50.0, 2)]
        for leg, turn in zip(legs, turns, strict=True):
            pts.append(pts[-1] + leg * np.array([math.cos(yaw), math.sin(yaw)]))
            yaw += turn
        kappa = 1.0 / rng.uniform(4.0, 15.0)
        pieces = polygon_curve(np.array(pts), kappa, rng.uniform(0.02, 0.12))
        if pieces is not None:
            out.append(pieces)
    return out


@pytest.mark.parametrize("spacing", [1.0, 0.25, 0.1, 0.37])
def test_sample_curves_is_sample_pieces_bit_for_bit(spacing):
    curves = _random_curves(7, 120)
    got = sample_curves(curves, spacing)
    assert len(got) == len(curves)
    for pieces, rows in zip(curves, got, strict=True):
        ref, _ = sample_pieces(pieces, spacing)
        assert rows.shape == ref.shape
        assert rows.tobytes() == ref.tobytes()
    assert sample_curves([], 1.0) == []



def _all_free(checker, paths, clearance):
    """``_clear_poses`` on sampled paths held whole (as the fallback did before CurveBatch)."""
    if not paths:
        return []
    poses = np.vstack(paths)[:, :3]
    return fallback._clear_poses(
        checker, [len(p) for p in paths], lambda pick, _: poses[pick], clearance
    )


def test_batched_body_test_is_one_test_per_path():
    m = builtin_map("parking_lot")
    checker = cached_checker(m)
    rng = np.random.default_rng(3)
    xmin, ymin, xmax, ymax = m.bounds
    paths = []
    for _ in range(60):  # straight runs through the lot: some clear, most not
        n = int(rng.integers(1, 70))
        x0, y0 = rng.uniform(xmin, xmax), rng.uniform(ymin, ymax)
        yaw = rng.uniform(-math.pi, math.pi)
        s = np.arange(n) * 0.7
        paths.append(
            np.column_stack([x0 + s * math.cos(yaw), y0 + s * math.sin(yaw), np.full(n, yaw)])
        )
    for clearance in (0.0, 0.3):
        want = [bool(np.all(checker.poses_free(p, clearance=clearance))) for p in paths]
        assert _all_free(checker, paths, clearance) == want
        assert any(want) and not all(want)


def test_tight_corners_take_the_tightest_turn_and_share_the_cache():
    pts = [[0.0, 0.0], [20.0, 0.0], [24.0, 14.0], [40.0, 10.0], [45.0, 30.0]]
    kappas = [1 / 6] * len(pts)
    levels = np.array([0.08, 0.056, 0.04])
    cache: dict = {}
    tight, _ = polygon_turns(pts, kappas, levels, [True] * len(pts), 1.0, cache)
    for c in (1, 2, 3):
        theta = tight[c].theta
        assert tight[c] == clothoid_turn(theta, 1 / 6, 0.08)
    # Gentle corners after tight ones, on the shared cache: as with a fresh one.
    gentle, _ = polygon_turns(pts, kappas, levels, [False] * len(pts), 1.0, cache)
    fresh, _ = polygon_turns(pts, kappas, levels, [False] * len(pts), 1.0, {})
    assert gentle == fresh


def _old_free_end(checker, start, goal, radius, clearance, smoothing, sample_spacing, check):
    """``_free_end`` as it was: each candidate sampled and tested on its own."""
    sigma = smoothing.tightest_sigma
    kappa = 1.0 / max(radius, smoothing.design_radius)
    r_in, d = turn_circle(kappa, sigma)
    a = Pose(start.x + d * math.cos(start.yaw), start.y + d * math.sin(start.yaw), start.yaw)
    b = Pose(goal.x - d * math.cos(goal.yaw), goal.y - d * math.sin(goal.yaw), goal.yaw)
    found = []
    for step in fallback.CC_RADIUS_STEPS:
        for cand in dubins_paths(a, b, r_in * step):
            poly = np.vstack([start.xy, cand.polygon(fallback._MAX_ARC)[1:-1], goal.xy])
            pieces = polygon_curve(poly, kappa, sigma)
            if pieces is not None:
                length = sum(p.length for p in pieces)
                found.append((length, len(found), pieces, poly, cand.word, r_in * step))
    for _, _, pieces, poly, word, r in sorted(found, key=lambda f: f[:2]):
        coarse, _ = sample_pieces(pieces, 1.0)
        fallback._pin_ends(coarse, start, goal)
        if not bool(np.all(checker.poses_free(coarse[:, :3], clearance=clearance))):
            continue
        dense, _ = sample_pieces(pieces, check)
        fallback._pin_ends(dense, start, goal)
        if bool(np.all(checker.poses_free(dense[:, :3], clearance=clearance))):
            rows, _ = sample_pieces(pieces, sample_spacing)
            fallback._pin_ends(rows, start, goal)
            return rows, poly, f"{word} of radius {r:.1f} m with clothoid turns"
    return None


def test_free_end_gives_the_old_answers():
    m = builtin_map("parking_lot")
    checker = cached_checker(m)
    rng = np.random.default_rng(11)
    xmin, ymin, xmax, ymax = m.bounds
    poses = []
    while len(poses) < 40:
        p = (rng.uniform(xmin, xmax), rng.uniform(ymin, ymax), rng.uniform(-math.pi, math.pi))
        if checker.pose_free(p):
            poses.append(Pose(*p))
    solved = 0
    for start, goal in zip(poses[::2], poses[1::2], strict=True):
        for ends in ((start, goal), (m.start, goal), (start, m.goal)):
            args = (checker, *ends, 6.2, 0.2, SMOOTHING, 0.25, 0.1)
            new, old = fallback._free_end(*args), _old_free_end(*args)
            assert (new is None) == (old is None)
            if new is not None:
                solved += 1
                assert new[0].tobytes() == old[0].tobytes()
                assert new[1].tobytes() == old[1].tobytes()
                assert new[2] == old[2]
    assert solved > 0


@pytest.mark.parametrize("spacing", [1.0, 0.37])
def test_curve_batch_rows_on_demand_are_the_rows_of_the_whole(spacing):
    curves = _random_curves(13, 60)
    whole = np.vstack(sample_curves(curves, spacing))
    rng = np.random.default_rng(4)
    for size in (1, 7, 200, len(whole)):
        batch = CurveBatch(curves, spacing)  # fresh: pieces computed when first asked for
        assert sum(batch.sizes) == len(whole)
        for _ in range(3):
            idx = np.sort(rng.choice(len(whole), size=size, replace=False))
            assert batch.rows(idx).tobytes() == whole[idx].tobytes()
    assert CurveBatch([], 1.0).sizes == []


def test_pinned_lazy_body_test_is_the_old_one():
    """``_clear_poses`` on poses computed when asked: as sampling, pinning, then ``_all_free``."""
    m = builtin_map("parking_lot")
    checker = cached_checker(m)
    rng = np.random.default_rng(8)
    xmin, ymin, xmax, ymax = m.bounds
    curves = []
    while len(curves) < 80:  # short polygons in the lot: some clear, most not
        n = int(rng.integers(2, 5))
        p0 = rng.uniform((xmin, ymin), (xmax, ymax))
        pts = p0 + np.cumsum(rng.uniform(-9.0, 9.0, (n, 2)), axis=0)
        pieces = polygon_curve(pts, 1 / 6, 0.08)
        if pieces is not None:
            curves.append(pieces)
    # Free end poses with yaws that wrap.
    start = Pose(m.start.x, m.start.y, m.start.yaw + 2.0 * math.pi)
    goal = Pose(m.goal.x, m.goal.y, m.goal.yaw - 2.0 * math.pi)
    answers = []
    for chunk in (curves[:1], curves[1:], curves[:0]):
        old = sample_curves(chunk, 1.0)
        for rows in old:
            fallback._pin_ends(rows, start, goal)
        want = _all_free(checker, old, 0.2)
        batch = CurveBatch(chunk, 1.0)
        poses_at = fallback._pinned(batch, start, goal)
        asked = [0]

        def same_as_old(pick, within, poses_at=poses_at, old=old, asked=asked):  # noqa: ANN001, ANN202
            got = poses_at(pick, within)
            assert got.tobytes() == np.vstack(old)[pick, :3].tobytes()
            asked[0] += len(pick)
            return got

        assert fallback._clear_poses(checker, batch.sizes, same_as_old, 0.2) == want
        assert asked[0] <= sum(batch.sizes)
        answers += want
    assert any(answers) and not all(answers)
