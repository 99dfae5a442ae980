"""The Dubins fallback (beyond the paper): a Dubins path, or a tree path with a Dubins end.

With clothoid smoothing (the default) a Dubins word's line-arc path would bring
back the curvature jumps, so each word becomes its tangent polygon
(:meth:`DubinsPath.polygon`) rounded by the tightest clothoid turns
(:func:`polygon_curve`): continuous curvature, 0 at both ends, and the sharpness
bound; where the turns do not fit the polygon's legs, the word is retried with a
larger radius (:data:`CC_RADIUS_STEPS`). The paper's B-spline keeps the plain
Dubins words.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np

from rrtdrive.collision import CollisionChecker
from rrtdrive.geometry import densify, wrap_angle
from rrtdrive.planning.dubins import DubinsPath, dubins_paths
from rrtdrive.planning.smoothing import SmoothingConfig, make_drivable
from rrtdrive.planning.smoothing.clothoid import turn_circle
from rrtdrive.planning.smoothing.clothoid_batch import CurveBatch, sample_curves
from rrtdrive.planning.smoothing.clothoid_curve import Piece as CurvePiece
from rrtdrive.planning.smoothing.clothoid_curve import polygon_curve
from rrtdrive.types import Path, Pose

__all__ = ["CC_RADIUS_STEPS", "MAX_FALLBACK_CANDIDATES", "dubins_fallback"]

#: Tree nodes tried as tail joints, and again as lead joints, per query: a counted
#: budget (the wall clock only caps it). Measured on parking_lot's 100 random goals
#: and 100 random starts (docs/planning.md, "Budgets and determinism"): every
#: fallback that solves does so by the 45th tail or the 32nd lead; failures tried
#: up to 211 of each, for seconds, in vain.
MAX_FALLBACK_CANDIDATES = 64


#: Radii (multiples of the fallback's radius) a Dubins word is tried with when its
#: polygon is rounded by clothoid turns: the turns need longer legs than the arcs.
#: Dubins arcs longer than this are split into equal sub-arcs for the polygon
#: (a polygon corner turns by less than pi; sub-arcs need a larger radius to fit).
_MAX_ARC = 0.95 * math.pi
CC_RADIUS_STEPS: tuple[float, ...] = (1.0, 1.15, 1.35, 1.6, 2.0, 2.5)
#: Candidates per batch of the coarse test, shortest first (0: all the rest).
_BATCHES = (1, 0)
#: The coarse poses of the candidates are tested in rounds: every 16th pose of each,
#: then every 4th of those still clear, then the rest (see _clear_poses).
_STRIDES = (16, 4, 1)


def _free_end(
    checker: CollisionChecker,
    start: Pose,
    goal: Pose,
    radius: float,
    clearance: float,
    smoothing: SmoothingConfig | None,
    sample_spacing: float,
    check_spacing: float,
) -> tuple[np.ndarray, np.ndarray, str] | None:
    """The shortest clear Dubins word (clothoid-rounded with clothoid smoothing), sampled."""
    if smoothing is None or not smoothing.clothoid:
        cand = _free_dubins(checker, start, goal, radius, clearance, check_spacing)
        if cand is None:
            return None
        return cand.sample(sample_spacing), cand.joints(), cand.word
    sigma = smoothing.tightest_sigma
    # A clothoid turn is the arc of radius r_in lengthened by d at either end
    # (Fraichard & Scheuer's inner circle), so the Dubins word of radius r_in between
    # the poses moved in by d, with the real ends put back, is a polygon whose
    # rounded corners fit when its straight is at least 2 d long. Larger radii give
    # the turns more room (CCC words, arcs split at the polygon's corners).
    kappa = 1.0 / max(radius, smoothing.design_radius)
    r_in, d = turn_circle(kappa, sigma)
    a = Pose(start.x + d * math.cos(start.yaw), start.y + d * math.sin(start.yaw), start.yaw)
    b = Pose(goal.x - d * math.cos(goal.yaw), goal.y - d * math.sin(goal.yaw), goal.yaw)
    found: list[tuple[float, int, list[CurvePiece], np.ndarray, str, float]] = []
    for step in CC_RADIUS_STEPS:
        for cand in dubins_paths(a, b, r_in * step):
            poly = np.vstack([start.xy, cand.polygon(_MAX_ARC)[1:-1], goal.xy])
            pieces = polygon_curve(poly, kappa, sigma)
            if pieces is not None and _pieces_inside(pieces, checker.bounds):
                length = sum(p.length for p in pieces)
                found.append((length, len(found), pieces, poly, cand.word, r_in * step))
    # The shortest rounded word first, whatever its radius.
    order = sorted(found, key=lambda f: f[:2])
    # Most candidates collide somewhere: poses at most 1 m apart first, then all. The
    # coarse poses of several candidates are sampled and tested in one batch (the
    # same floats and answers as one by one; on most queries none is clear): the
    # shortest alone, then the next few, then the rest.
    done = 0
    for size in _BATCHES:
        batch = order[done : done + size] if size else order[done:]
        done += len(batch)
        if not batch:
            break
        coarse = CurveBatch([f[2] for f in batch], 1.0)
        clear = _clear_poses(checker, coarse.sizes, _pinned(coarse, start, goal), clearance)
        for (_, _, pieces, poly, word, r), ok in zip(batch, clear, strict=True):
            if not ok:
                continue
            dense = sample_curves([pieces], check_spacing)[0]
            _pin_ends(dense, start, goal)
            if bool(np.all(checker.poses_free(dense[:, :3], clearance=clearance))):
                out = sample_curves([pieces], sample_spacing)[0]
                _pin_ends(out, start, goal)
                # The rows as they are read (interpolated linearly, as rrtdrive.verify and
                # the controllers do) leave the exact curve by tens of micrometres: beside
                # an obstacle 1 mm from the goal body they clipped it (a fuzzed map).
                read = densify(out[:, :3], check_spacing, angle_column=2).points
                if not bool(np.all(checker.poses_free(read, clearance=0.0))):
                    continue
                return out, poly, f"{word} of radius {r:.1f} m with clothoid turns"
    return None


def _pieces_inside(pieces: Sequence[CurvePiece], bounds: Sequence[float]) -> bool:
    """Whether every piece of a curve starts inside the map's ``bounds``.

    A rear axle outside the bounds puts the body outside them, so a curve failing
    this is not clear: dropping it before sampling changes no answer. With a huge
    turning radius on a small map every word is kilometres long and leaves the
    map, and sampling and testing it took seconds a call.
    """
    x0, y0, x1, y1 = bounds
    tol = 1e-6
    return all(x0 - tol <= p.x <= x1 + tol and y0 - tol <= p.y <= y1 + tol for p in pieces)


#: ``poses_at(pick, within)``: the poses ``(len(pick), 3)`` at the batch's rows ``pick``
#: (``within``: the rows' indices within their paths, for all rows of the batch).
PosesAt = Callable[[np.ndarray, np.ndarray], np.ndarray]


def _clear_poses(
    checker: CollisionChecker, sizes: list[int], poses_at: PosesAt, clearance: float
) -> list[bool]:
    """Per path of ``sizes`` rows, whether the body is clear at all its poses (``poses_free``).

    ``poses_at`` gives the poses of the rows asked for. The same answers as testing
    each path's poses, with less exact work: every ``_STRIDES[0]``-th pose of every
    path first (a colliding stretch usually spans several poses), then more of the
    paths still clear only, until all.
    """
    if not sizes:
        return []
    total = sum(sizes)
    owner = np.repeat(np.arange(len(sizes)), sizes)
    within = np.arange(total) - np.repeat(np.cumsum(sizes) - sizes, sizes)
    clear = np.ones(len(sizes), dtype=bool)
    todo = np.ones(total, dtype=bool)
    for stride in _STRIDES:
        pick = np.flatnonzero(todo & (within % stride == 0) & clear[owner])
        if not len(pick):
            continue
        todo[pick] = False
        ok = checker.poses_free(poses_at(pick, within), clearance=clearance)
        clear[owner[pick[~ok]]] = False
    return clear.tolist()


def _pinned(batch: CurveBatch, start: Pose, goal: Pose) -> PosesAt:
    """The poses of ``batch``'s rows as :func:`_pin_ends` leaves them, computed when asked.

    The same floats as sampling every curve, pinning its ends and taking the rows:
    each row is computed alone, the first of a curve is the start pose, the last
    the goal pose, and the yaw is wrapped element by element.
    """
    last = np.cumsum(batch.sizes) - 1
    s_pose, g_pose = start.as_tuple(), goal.as_tuple()

    def poses_at(pick: np.ndarray, within: np.ndarray) -> np.ndarray:
        rows = batch.rows(pick)
        rows[within[pick] == 0, :3] = s_pose
        rows[np.isin(pick, last), :3] = g_pose
        rows[:, 2] = wrap_angle(rows[:, 2])
        return np.ascontiguousarray(rows[:, :3])

    return poses_at


def _pin_ends(rows: np.ndarray, start: Pose, goal: Pose) -> None:
    """Put the first and last rows exactly on the end poses (they differ by ~1e-12)."""
    rows[0, :3] = start.as_tuple()
    rows[-1, :3] = goal.as_tuple()
    rows[:, 2] = wrap_angle(rows[:, 2])


def _free_dubins(
    checker: CollisionChecker,
    start: Pose,
    goal: Pose,
    radius: float,
    clearance: float,
    check_spacing: float,
) -> DubinsPath | None:
    """The shortest Dubins word from ``start`` to ``goal`` whose body stays clear."""
    for cand in dubins_paths(start, goal, radius):
        dense = cand.sample(check_spacing)
        if bool(np.all(checker.poses_free(dense[:, :3], clearance=clearance))):
            return cand
    return None


def dubins_fallback(
    checker: CollisionChecker,
    start: Pose,
    goal: Pose,
    radius: float,
    clearance: float,
    raw_paths: Sequence[np.ndarray] = (),
    smoothing: SmoothingConfig | None = None,
    expired: Callable[[], bool] | None = None,
    sample_spacing: float = 0.25,
    check_spacing: float = 0.1,
    max_candidates: int = MAX_FALLBACK_CANDIDATES,
    direct: bool = True,
) -> tuple[Path, str] | None:
    """A drivable path that ends in a Dubins path, when the tree paths alone fail.

    First (unless ``direct`` is false) the shortest Dubins path from ``start`` to
    ``goal`` that the exact body test clears (with clothoid ``smoothing``: the
    shortest clear word rounded by clothoid turns, see the module docstring).
    Then, for each tree path in ``raw_paths`` and each of its nodes from the last
    but one backwards, a *tail*: the node, with the heading of the tree edge into it, is joined to
    ``goal`` by such a clear path, and the tree path up to the node is made
    drivable by :func:`make_drivable` with that pose as its goal; the two meet at
    the node with the same position and heading (and ``kappa = 0`` with clothoids).
    Last, the mirror image, a *lead*: a clear path from ``start`` to a node (with
    the heading of the tree edge out of it, nodes in driving order), then the tree
    path from there made drivable.

    Parameters
    ----------
    checker : CollisionChecker
        The map's checker (exact test, with ``clearance``).
    start, goal : Pose
        Rear-axle poses.
    radius : float
        Turning radius of the Dubins arcs in metres.
    clearance : float
        Body clearance to keep (the planner's, capped at the end poses' own).
    raw_paths : sequence of numpy.ndarray
        Tree paths ``(K, 2)`` whose post-processing failed, for tails and leads.
    smoothing : SmoothingConfig, optional
        Post-processing settings for the tree part; no tails or leads without it.
    expired : callable, optional
        The safety cap: stops the search for tails and leads when it returns True
        (the caller then reports a timeout).
    sample_spacing, check_spacing : float
        Spacing of the returned samples and of the poses tested.
    max_candidates : int
        Most tree nodes tried as tail joints, and again as lead joints (the
        counted budget that decides; :data:`MAX_FALLBACK_CANDIDATES`); 0: the
        direct path only.
    direct : bool
        Whether to try the direct Dubins path first (``False``: tails and leads
        only, after a caller has tried it).

    Returns
    -------
    (Path, str) or None
        The path (rows ``x, y, yaw, kappa``; waypoints: the control points of the
        tree part, then the Dubins segment junctions) and a description, or
        ``None`` when nothing fits.
    """
    def free_end(a: Pose, b: Pose) -> tuple[np.ndarray, np.ndarray, str] | None:
        return _free_end(
            checker, a, b, radius, clearance, smoothing, sample_spacing, check_spacing
        )

    whole = free_end(start, goal) if direct else None
    if whole is not None:
        return Path(whole[0], whole[1]), whole[2]
    if smoothing is None:
        return None
    tried = 0
    for raw in raw_paths:
        for i in range(len(raw) - 2, 0, -1):
            if tried >= max_candidates:
                break
            if expired is not None and expired():
                return None
            tried += 1
            yaw = math.atan2(raw[i, 1] - raw[i - 1, 1], raw[i, 0] - raw[i - 1, 0])
            joint = Pose(float(raw[i, 0]), float(raw[i, 1]), yaw)
            tail = free_end(joint, goal)
            if tail is None:
                continue
            head = make_drivable(raw[: i + 1], start, joint, checker, smoothing)
            if not head.ok:
                continue
            samples = np.vstack([head.samples, tail[0][1:]])
            waypoints = np.vstack([head.control_points, tail[1][1:]])
            where = f"({joint.x:.1f}, {joint.y:.1f})"
            return Path(samples, waypoints), f"tree path to {where} + {tail[2]}"
    tried = 0
    for raw in raw_paths:
        for i in range(1, len(raw) - 1):
            if tried >= max_candidates:
                return None
            if expired is not None and expired():
                return None
            tried += 1
            yaw = math.atan2(raw[i + 1, 1] - raw[i, 1], raw[i + 1, 0] - raw[i, 0])
            joint = Pose(float(raw[i, 0]), float(raw[i, 1]), yaw)
            lead = free_end(start, joint)
            if lead is None:
                continue
            rest = make_drivable(raw[i:], joint, goal, checker, smoothing)
            if not rest.ok:
                continue
            samples = np.vstack([lead[0][:-1], rest.samples])
            waypoints = np.vstack([lead[1][:-1], rest.control_points])
            where = f"({joint.x:.1f}, {joint.y:.1f})"
            return Path(samples, waypoints), f"{lead[2]} + tree path from {where}"
    return None

