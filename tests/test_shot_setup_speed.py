"""Hybrid A*'s shot and set-up shortcuts give what the code they replace gave, bit for bit.

The references are the code as it was at 3f87098: the backward Dubins shots screened
word by word, a Reeds-Shepp sample cut at its cusps by ``np.split``, and the end
poses' field clearance from ``cover_discs`` per call.
"""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from rrtdrive.maps import builtin_map
from rrtdrive.planning.base import PlanningProblem, cached_checker
from rrtdrive.planning.dubins import dubins_paths
from rrtdrive.planning.hybrid import resolution
from rrtdrive.planning.hybrid.body import BodyTest
from rrtdrive.planning.hybrid.shots import Piece, _gear_pieces, walk_hits
from rrtdrive.planning.reeds_shepp import reeds_shepp_paths
from rrtdrive.types import Pose
from rrtdrive.vehicle import cover_discs

RADIUS = 5.9

poses = st.tuples(st.floats(0.0, 100.0), st.floats(0.0, 100.0), st.floats(-math.pi, math.pi)).map(
    lambda p: Pose(*p)
)


def _checker():
    return cached_checker(builtin_map("parking_lot"))


def _reference_backward_shots(target, radius, spacing, body, max_candidates=3):
    """resolution._backward_dubins_shots as it was (3f87098): each word screened alone."""
    coarse = max(spacing, 0.5)

    def shots(pose):
        for cand in dubins_paths(target, pose, radius)[:max_candidates]:
            if walk_hits(target, cand.word, cand.lengths, radius, coarse, body):
                continue
            rows = cand.sample(spacing)[::-1].copy()
            rows[0, :3] = pose.as_tuple()
            rows[-1, :3] = target.as_tuple()
            yield [Piece(-1, rows, True)]

    return shots


def _same_pieces(a: list[Piece], b: list[Piece]) -> bool:
    return len(a) == len(b) and all(
        p.gear == q.gear
        and p.shot == q.shot
        and p.rows.shape == q.rows.shape
        and p.rows.tobytes() == q.rows.tobytes()
        for p, q in zip(a, b, strict=True)
    )


@settings(max_examples=60, deadline=None)
@given(poses, poses, st.sampled_from([0.1, 0.25]))
def test_backward_dubins_shots_screen_the_same_words(target, pose, spacing: float) -> None:
    body = BodyTest(_checker(), 0.15)
    got = list(resolution._backward_dubins_shots(target, RADIUS, spacing, body)(pose))
    want = list(_reference_backward_shots(target, RADIUS, spacing, body)(pose))
    assert len(got) == len(want)
    assert all(_same_pieces(g, w) for g, w in zip(got, want, strict=True))


def _reference_gear_pieces(rows: np.ndarray) -> list[Piece]:
    """shots._gear_pieces as it was (3f87098): np.split at the cusps."""
    gear = rows[:, 4]
    cuts = np.flatnonzero(gear[1:] != gear[:-1]) + 1
    return [Piece(int(part[0, 4]), part[:, :4].copy(), True) for part in np.split(rows, cuts)]


@settings(max_examples=80, deadline=None)
@given(poses, poses, st.sampled_from([0.1, 0.25]))
def test_gear_pieces_are_the_split_parts(a: Pose, b: Pose, spacing: float) -> None:
    for path in reeds_shepp_paths(a, b, RADIUS):
        rows = path.sample(spacing)
        assert _same_pieces(_gear_pieces(rows), _reference_gear_pieces(rows))


def test_gear_pieces_of_one_row_and_alternating_gears() -> None:
    rows = np.arange(30, dtype=float).reshape(6, 5)
    rows[:, 4] = [1, -1, -1, 1, -1, -1]
    assert _same_pieces(_gear_pieces(rows), _reference_gear_pieces(rows))
    one = rows[:1].copy()
    assert _same_pieces(_gear_pieces(one), _reference_gear_pieces(one))


def _reference_field_clearance(checker, pose: Pose) -> float:
    """resolution.field_clearance as it was (3f87098): cover_discs per call."""
    offsets, radius = cover_discs(checker.vehicle, 3)
    c, s = math.cos(pose.yaw), math.sin(pose.yaw)
    return min(checker.clearance(pose.x + c * o, pose.y + s * o) for o in offsets) - radius


@settings(max_examples=200, deadline=None)
@given(poses)
def test_field_clearance_is_the_per_call_discs(pose: Pose) -> None:
    checker = _checker()
    got = resolution.field_clearance(checker, pose)
    want = _reference_field_clearance(checker, pose)
    assert got == want or (math.isnan(got) and math.isnan(want))
    assert np.float64(got).tobytes() == np.float64(want).tobytes()


def test_end_clearance_bound_is_unchanged_on_the_map() -> None:
    problem = PlanningProblem.from_map(builtin_map("parking_lot"))
    have = resolution.EndClearance(problem)
    want = min(
        _reference_field_clearance(problem.checker, problem.start),
        _reference_field_clearance(problem.checker, problem.goal),
    )
    assert have.bound == want
