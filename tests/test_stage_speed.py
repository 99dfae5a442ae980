"""The default planner's fast paths give the old answers bit for bit.

``choose_parent``'s shortcut (the nearest node when it is obtuse), ``polygon_turns``
building the gentler options only without conflicts, and ``implements``
remembering classes, each against the old code kept here.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from rrtdrive.checking import Checker, MotionValidator, implements
from rrtdrive.planning.improved.growth import ObtuseTree
from rrtdrive.planning.smoothing.clothoid import clothoid_turn, clothoid_turns, sharpness_levels
from rrtdrive.planning.smoothing.clothoid_curve import polygon_turns
from rrtdrive.planning.smoothing.corners import signed_deflection, unit


def _old_choose_parent(tree: ObtuseTree, q: list[float], obtuse: bool) -> int:
    q3 = np.array([q[0], q[1], 1.0])
    r = tree._forms[:, : tree.size] @ q3
    near = r[0]
    if not obtuse:
        return int(near.argmin())
    w = np.where(r[1] > 0.0, near, np.inf)
    i = int(w.argmin())
    if w[i] == np.inf:
        if tree.virtual_parent is not None:
            near[0] = np.inf
        i = int(near.argmin())
        if near[i] == np.inf:
            return -1
    return i


@pytest.mark.parametrize("virtual", [False, True])
def test_choose_parent_matches_old(virtual: bool) -> None:
    rng = np.random.default_rng(3)
    vp = np.array([-3.0, 0.0]) if virtual else None
    tree = ObtuseTree(np.array([0.0, 0.0]), capacity=8, virtual_parent=vp)
    for _ in range(400):
        # Integer grid points: many exact ties between distances.
        q = rng.integers(-12, 13, 2).astype(float).tolist()
        for obtuse in (True, False):
            assert tree.choose_parent(np.array(q), obtuse) == _old_choose_parent(tree, q, obtuse)
        i = tree.choose_parent(np.array(q))
        if i >= 0 and q != tree.nodes[i].tolist():
            tree.add(q, i)


def _old_polygon_turns(pts, kappas, levels, tight, end_gap, radius_steps):  # noqa: ANN001, ANN202
    """The options of every corner built before the conflicts are known (the old order)."""
    n = len(pts)
    dirs, lengths = [], []
    for i in range(n - 1):
        ux, uy, length = unit(pts[i + 1][0] - pts[i][0], pts[i + 1][1] - pts[i][1])
        dirs.append((ux, uy))
        lengths.append(length)
    tmin = [0.0] * n
    opts_of = [None] * n
    for c in range(1, n - 1):
        theta = signed_deflection(dirs[c - 1], dirs[c])
        if abs(theta) < 1e-9 or lengths[c - 1] == 0.0 or lengths[c] == 0.0:
            if lengths[c - 1] == 0.0 or lengths[c] == 0.0:
                tmin[c] = math.inf
            continue
        tt = clothoid_turn(theta, kappas[c], float(levels[0]))
        steps = np.repeat(np.asarray(radius_steps, dtype=float), len(levels))
        rest = clothoid_turns(theta, kappas[c] / steps, np.tile(levels, len(radius_steps)))
        opts = [tt] + sorted((t for t in rest if t.tangent > tt.tangent), key=lambda t: t.tangent)
        opts_of[c] = opts[:1] if tight[c] else opts
        tmin[c] = opts[0].tangent
    return opts_of, tmin


def test_polygon_turns_match_eager_options() -> None:
    rng = np.random.default_rng(5)
    levels = sharpness_levels(0.5, 0.1, 2.7, 0.9)
    cache: dict = {}
    conflicts_seen = turns_seen = 0
    for _ in range(300):
        n = int(rng.integers(3, 8))
        pts = np.cumsum(rng.uniform(-15, 15, (n, 2)), axis=0).tolist()
        kappas = [1.0 / float(rng.choice([5.0, 6.0, 8.0]))] * n
        tight = rng.random(n) < 0.3
        steps = (1.0, 1.5)
        turns, conflicts = polygon_turns(pts, kappas, levels, tight, 2.0, cache, steps)
        fresh = polygon_turns(pts, kappas, levels, tight, 2.0, None, steps)
        assert (turns, conflicts) == fresh
        opts_of, tmin = _old_polygon_turns(pts, kappas, levels, tight, 2.0, steps)
        if conflicts:
            conflicts_seen += 1
            assert turns == [None] * n
        else:
            turns_seen += 1
            for c in range(1, n - 1):
                assert (turns[c] is None) == (opts_of[c] is None)
                if turns[c] is not None:
                    assert turns[c] in opts_of[c]
                    assert turns[c].tangent >= tmin[c]
    assert conflicts_seen and turns_seen


def test_implements_per_class_and_instance() -> None:
    from rrtdrive.collision import CollisionChecker
    from rrtdrive.maps import builtin_map

    checker = CollisionChecker.for_map(builtin_map("overtake"))
    for _ in range(2):  # the second time from the remembered classes
        assert implements(checker, Checker)
        assert not implements(object(), MotionValidator)

    class Partial:
        pass

    p = Partial()
    # Instance attributes: asked per instance, the class never remembered.
    p.edge_free = lambda a, b: True  # type: ignore[attr-defined]
    p.path_free = lambda samples: (True, np.zeros(0))  # type: ignore[attr-defined]
    assert implements(p, MotionValidator)
    assert not implements(Partial(), MotionValidator)
