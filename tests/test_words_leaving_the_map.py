"""Words and moves that leave the map are dropped unwalked, with the answers unchanged.

With a huge turning radius on a small map every Dubins or Reeds-Shepp word is
kilometres long; the shots, the Dubins fallback and the multi-point turn's moves
walked them pose by pose (seconds a call; a 1e4 m car on a 60 m field ended by the
wall clock). The shortcuts must give exactly the answers of the full walks: each is
compared here with the code it replaced, on random poses and radii.
"""

from __future__ import annotations

import contextlib
import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from rrtdrive.collision import CollisionChecker
from rrtdrive.maps import Map
from rrtdrive.obstacles import Obstacle
from rrtdrive.planning.dubins import dubins_paths
from rrtdrive.planning.hybrid import turn
from rrtdrive.planning.hybrid.body import BodyTest
from rrtdrive.planning.hybrid.primitives import arc_poses
from rrtdrive.planning.hybrid.shots import walk_poses, walks_hit
from rrtdrive.planning.improved import fallback
from rrtdrive.planning.reeds_shepp import reeds_shepp_paths
from rrtdrive.planning.smoothing import SmoothingConfig
from rrtdrive.types import Pose

# A small yard (40 x 25 m) with a block in it: most words of a large radius leave it.
YARD = Map(
    "yard",
    (0.0, 0.0, 40.0, 25.0),
    (Obstacle((20.0, 12.0), (6.0, 4.0), 0.3),),
    Pose(6.0, 6.0, 0.0),
    Pose(34.0, 19.0, 0.0),
)
CHECKER = CollisionChecker.for_map(YARD)
BODY = BodyTest(CHECKER, 0.1)

poses = st.tuples(st.floats(2.0, 38.0), st.floats(2.0, 23.0), st.floats(-math.pi, math.pi)).map(
    lambda p: Pose(*p)
)
radii = st.sampled_from([3.0, 6.0, 15.0, 60.0, 1e3, 1e4])


@settings(max_examples=150, deadline=None)
@given(poses, poses, radii, st.booleans())
def test_the_words_screen_answers_as_the_full_walks_do(a, b, radius, reverse):
    cands = reeds_shepp_paths(a, b, radius, limit=4) if reverse else dubins_paths(a, b, radius)
    words = [(c.word, c.lengths) for c in cands[:4]]
    if not words:
        return
    poses_, sizes = walk_poses(a, words, radius, 0.5)
    assert walks_hit(a, words, radius, 0.5, BODY) == BODY.any_hits(poses_, sizes).tolist()


def test_a_huge_radius_leaves_the_yard_in_every_word():
    # The case the shortcut is for: nothing is walked, every word is a hit.
    a, b = Pose(10.0, 5.0, 0.0), Pose(30.0, 20.0, math.pi)
    words = [(c.word, c.lengths) for c in reeds_shepp_paths(a, b, 1e4, limit=3)]
    assert words and walks_hit(a, words, 1e4, 0.5, BODY) == [True] * len(words)


def _reference_move(pose, kappa, gear, body, longest, spacing):
    """turn._move as it was (358d3d8): every pose tested in one look."""
    count = max(1, math.ceil(longest / spacing))
    s = np.minimum(np.arange(1, count + 1) * spacing, longest)
    poses_ = arc_poses(pose.x, pose.y, pose.yaw, kappa, gear, s)
    free = body.free(poses_)
    n = len(free) if free.all() else int(np.argmin(free))
    return np.vstack([[pose.x, pose.y, pose.yaw], poses_[:n]])


@settings(max_examples=30, deadline=None)
@given(poses, radii, st.sampled_from([1, -1]), st.sampled_from([1.0, -1.0]),
       st.floats(0.05, 2 * math.pi))  # fmt: skip
def test_a_move_tested_in_chunks_stops_where_the_whole_move_did(pose, radius, gear, side, turned):
    kappa = side / radius
    longest = turned * radius
    got = turn._move(pose, kappa, gear, BODY, longest, 0.1)
    want = _reference_move(pose, kappa, gear, BODY, longest, 0.1)
    assert got.shape == want.shape and got.tobytes() == want.tobytes()


def test_a_long_free_move_is_tested_over_several_chunks():
    # A 60 m circle in open ground: well over one chunk, all of it free.
    open_field = Map("field", (0.0, 0.0, 200.0, 200.0), (), Pose(100, 80, 0), Pose(10, 10, 0))
    body = BodyTest(CollisionChecker.for_map(open_field), 0.1)
    pose = Pose(100.0, 80.0, 0.0)
    got = turn._move(pose, 1 / 15.0, 1, body, 60.0, 0.1)
    want = _reference_move(pose, 1 / 15.0, 1, body, 60.0, 0.1)
    assert len(got) == 601 > turn._MOVE_CHUNK
    assert got.tobytes() == want.tobytes()


def test_a_long_move_stops_at_an_obstacle_beyond_the_first_chunk():
    # The same circle with a block three quarters round (about 70 m, 700 poses, in).
    block = Obstacle((85.0, 95.0), (2.0, 2.0))
    field = Map("field", (0.0, 0.0, 200.0, 200.0), (block,), Pose(100, 80, 0), Pose(10, 10, 0))
    body = BodyTest(CollisionChecker.for_map(field), 0.1)
    pose = Pose(100.0, 80.0, 0.0)
    got = turn._move(pose, 1 / 15.0, 1, body, 94.0, 0.1)
    want = _reference_move(pose, 1 / 15.0, 1, body, 94.0, 0.1)
    assert turn._MOVE_CHUNK < len(got) < 900
    assert got.tobytes() == want.tobytes()


@contextlib.contextmanager
def _without_the_bounds_test():
    kept = fallback._pieces_inside
    fallback._pieces_inside = lambda pieces, bounds: True
    try:
        yield
    finally:
        fallback._pieces_inside = kept


@settings(max_examples=40, deadline=None)
@given(poses, poses, st.sampled_from([6.0, 15.0, 60.0, 1e3]))
def test_the_fallback_finds_what_it_found_without_the_bounds_test(a, b, radius):
    smoothing = SmoothingConfig()
    got = fallback._free_end(CHECKER, a, b, radius, 0.1, smoothing, 0.25, 0.1)
    with _without_the_bounds_test():
        want = fallback._free_end(CHECKER, a, b, radius, 0.1, smoothing, 0.25, 0.1)
    assert (got is None) == (want is None)
    if got is not None:
        assert got[2] == want[2] and got[0].tobytes() == want[0].tobytes()
