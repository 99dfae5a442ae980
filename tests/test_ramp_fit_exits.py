"""Two savings of the ramp fit that must not change an answer.

- A fit whose pose error stops falling gives up early (``ramps._STUCK_AFTER``): the
  answer is the one the full twelve Gauss-Newton iterations give.
- ``build_path`` with a memo fits and checks a gear segment once for all connections
  that share it, and returns the same bytes as without it.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from rrtdrive.maps import Map
from rrtdrive.planning.base import PlanningProblem
from rrtdrive.planning.hybrid import arc_poses, ramps
from rrtdrive.planning.hybrid import path as hybrid_path
from rrtdrive.planning.hybrid.path import Ramps, build_path
from rrtdrive.planning.hybrid.search import Piece
from rrtdrive.types import Pose

L = 2.51
KAPPA_MAX = 1.0 / 6.0
DELTA_MAX = math.atan(L * KAPPA_MAX)
RATE = 0.18


def arc_chain(pieces, gear: int, start=(10.0, 4.0, 0.3)) -> np.ndarray:
    """Rows ``[x, y, yaw, kappa]`` of arcs ``(kappa, length)`` one after another, 0.25 m apart."""
    rows = [np.array([[*start, pieces[0][0]]])]
    pose = start
    for kappa, length in pieces:
        n = max(1, math.ceil(length / 0.25))
        p = arc_poses(*pose, kappa, gear, np.linspace(0.0, length, n + 1))
        rows.append(np.column_stack([p[1:], np.full(n, kappa)]))
        pose = tuple(p[-1])
    return np.vstack(rows)


def fit(rows: np.ndarray, gear: int) -> np.ndarray | None:
    return ramps.ramped_segment(rows[:, :3], gear, RATE, L, DELTA_MAX)


#: Full lock one way, then the other, too short for the ramp between them: the
#: angles are held at the steering limit and the two lengths cannot close the gap
#: (a reverse segment of a Reeds-Shepp shot in a 7 m street).
STUCK = [(-KAPPA_MAX, 2.64), (KAPPA_MAX, 1.77)]

levels = st.sampled_from([-KAPPA_MAX, -KAPPA_MAX / 2, 0.0, KAPPA_MAX / 2, KAPPA_MAX])
chains = st.lists(st.tuples(levels, st.floats(0.5, 8.0)), min_size=2, max_size=5)


def test_a_stuck_fit_gives_up_early_with_the_same_answer(monkeypatch) -> None:
    steps = []
    bounded = ramps._bounded_step
    monkeypatch.setattr(ramps, "_bounded_step", lambda *a: steps.append(1) or bounded(*a))
    rows = arc_chain(STUCK, -1)
    assert fit(rows, -1) is None
    early = len(steps)
    steps.clear()
    monkeypatch.setattr(ramps, "_STUCK_AFTER", 10**6)
    assert fit(rows, -1) is None
    assert len(steps) == ramps._NEWTON_ITERATIONS
    assert early <= ramps._NEWTON_ITERATIONS // 2


@settings(max_examples=60, deadline=None)
@given(chains, st.sampled_from([1, -1]))
@example(STUCK, -1)
@example([(-KAPPA_MAX, 3.0), (KAPPA_MAX, 3.0)], 1)
def test_giving_up_early_changes_no_fit(pieces, gear: int) -> None:
    rows = arc_chain(pieces, gear)
    early = fit(rows, gear)
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(ramps, "_STUCK_AFTER", 10**6)
        full = fit(rows, gear)
    assert (early is None) == (full is None)
    if full is not None:
        assert early.tobytes() == full.tobytes()


def _connections() -> list[list[Piece]]:
    """Three connections sharing a forward lead and a reverse leg, ending differently."""
    lead = arc_chain([(0.0, 4.0), (KAPPA_MAX / 2, 3.0)], 1)
    leg = arc_chain([(-KAPPA_MAX / 2, 3.0)], -1, start=tuple(lead[-1, :3]))
    out = []
    for kappa, length in [(0.0, 3.0), (KAPPA_MAX / 2, 4.0), (-KAPPA_MAX / 3, 2.0)]:
        tail = arc_chain([(kappa, length)], 1, start=tuple(leg[-1, :3]))
        out.append([Piece(1, lead), Piece(-1, leg), Piece(1, tail)])
    return out


def test_a_memo_fits_each_shared_segment_once_and_changes_nothing(monkeypatch) -> None:
    m = Map("open", (0.0, 0.0, 60.0, 30.0), (), Pose(10.0, 4.0, 0.3), Pose(40.0, 20.0, 0.0))
    checker = PlanningProblem.from_map(m).checker
    ramp = Ramps(0.2, L, KAPPA_MAX)
    fits = []
    ramped = hybrid_path._ramped
    monkeypatch.setattr(hybrid_path, "_ramped", lambda *a: fits.append(1) or ramped(*a))

    def build(pieces, memo=None):
        return build_path(pieces, checker, None, False, 0.15, KAPPA_MAX, ramps=ramp, memo=memo)

    plain = [build(c) for c in _connections()]
    assert all(p is not None for p in plain)
    assert len(fits) == 9
    fits.clear()
    memo = hybrid_path.SegmentMemo()
    kept = [build(c, memo) for c in _connections()]
    assert len(fits) == 2 + 3  # the lead and the leg once, each tail once
    assert len(memo) == 5
    for a, b in zip(plain, kept, strict=True):
        assert a.rows.tobytes() == b.rows.tobytes()
        assert a.waypoints.tobytes() == b.waypoints.tobytes()
        assert a.measured_sharpness == b.measured_sharpness
    # A segment that fits no guarantee is remembered as such.
    blocked = [Piece(1, arc_chain([(0.0, 80.0)], 1))]  # drives out of the map
    assert build(blocked, memo) is None
    assert list(memo.values())[-1] is None
    fits.clear()
    assert build(blocked, memo) is None and not fits
