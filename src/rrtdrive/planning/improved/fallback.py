"""The Dubins fallback (beyond the paper): a Dubins path, or a tree path with a Dubins end."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np

from rrtdrive.collision import CollisionChecker
from rrtdrive.planning.dubins import DubinsPath, dubins_paths
from rrtdrive.planning.smoothing import SmoothingConfig, make_drivable
from rrtdrive.types import Path, Pose

__all__ = ["dubins_fallback", "MAX_FALLBACK_CANDIDATES"]

#: Tree nodes tried as tail joints, and again as lead joints, per query: a counted
#: budget (the wall clock only caps it). Measured on parking_lot's 100 random goals
#: and 100 random starts (docs/planning.md, "Budgets and determinism"): every
#: fallback that solves does so by the 45th tail or the 32nd lead; failures tried
#: up to 211 of each, for seconds, in vain.
MAX_FALLBACK_CANDIDATES = 64


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
) -> tuple[Path, str] | None:
    """A drivable path that ends in a Dubins path, when the tree paths alone fail.

    First the shortest Dubins path from ``start`` to ``goal`` that the exact body
    test clears. Then, for each tree path in ``raw_paths`` and each of its nodes
    from the last but one backwards, a *tail*: the node, with the heading of the
    tree edge into it, is joined to ``goal`` by a clear Dubins path, and the tree
    path up to the node is made drivable by :func:`make_drivable` with that pose
    as its goal; the two meet at the node with the same position and heading.
    Last, the mirror image, a *lead*: a clear Dubins path from ``start`` to a node
    (with the heading of the tree edge out of it, nodes in driving order), then the
    tree path from there made drivable.

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
        counted budget that decides; :data:`MAX_FALLBACK_CANDIDATES`).

    Returns
    -------
    (Path, str) or None
        The path (rows ``x, y, yaw, kappa``; waypoints: the control points of the
        tree part, then the Dubins segment junctions) and a description, or
        ``None`` when nothing fits.
    """
    direct = _free_dubins(checker, start, goal, radius, clearance, check_spacing)
    if direct is not None:
        return Path(direct.sample(sample_spacing), direct.joints()), direct.word
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
            tail = _free_dubins(checker, joint, goal, radius, clearance, check_spacing)
            if tail is None:
                continue
            head = make_drivable(raw[: i + 1], start, joint, checker, smoothing)
            if not head.ok:
                continue
            samples = np.vstack([head.samples, tail.sample(sample_spacing)[1:]])
            waypoints = np.vstack([head.control_points, tail.joints()[1:]])
            where = f"({joint.x:.1f}, {joint.y:.1f})"
            return Path(samples, waypoints), f"tree path to {where} + {tail.word}"
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
            lead = _free_dubins(checker, start, joint, radius, clearance, check_spacing)
            if lead is None:
                continue
            rest = make_drivable(raw[i:], joint, goal, checker, smoothing)
            if not rest.ok:
                continue
            samples = np.vstack([lead.sample(sample_spacing)[:-1], rest.samples])
            waypoints = np.vstack([lead.joints()[:-1], rest.control_points])
            where = f"({joint.x:.1f}, {joint.y:.1f})"
            return Path(samples, waypoints), f"{lead.word} + tree path from {where}"
    return None

