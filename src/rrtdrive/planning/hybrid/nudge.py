"""Nudged ends: a start or goal turned a fraction of a degree off the way out of its slot.

A goal parked nose-in in a slot a few centimetres wider than the car, turned 0.46 deg
off the slot's axis and 0.11 m off its centre line, keeps 0.058 m; the straight drive
out of it (the arrival driven backwards in time) drifts into the side wall within a
metre, and the search's arcs turn by whole steps of its curvatures (4.8 deg a step at
full lock), so every move out of the goal collides and the search from it runs out of
states after one or two expansions: ``proven_unreachable``, although a forward path
that straightens the car in the slot passes every check (a helper's audit, session 48:
27 of 142 random slots 1.86-2.2 m wide with a verified forward path were "proven"
unreachable). :func:`nudge` finds, for an end whose straight drive out is short, one
gentle arc of a step's length that turns its heading by a fraction of a degree so that
the straight drive out gets longer (0.01-deg steps up to 0.5 deg when none of the
coarse angles does); :func:`~.query.hybrid_query` searches once more from the nudged
ends, after a proof, and drives those arcs at them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rrtdrive.planning.hybrid.body import BodyTest
from rrtdrive.planning.hybrid.primitives import arc_poses
from rrtdrive.planning.hybrid.shots import Piece
from rrtdrive.types import Pose

__all__ = ["FINE_NUDGES_DEG", "NUDGES_DEG", "Nudge", "nudge"]

#: Heading changes a nudge may make, degrees (each way): the search's own arcs turn by
#: whole steps of several degrees, these by less than one.
NUDGES_DEG = (0.25, 0.5, 1.0, 2.0)
#: The fine scan's heading changes when no coarse one qualifies, degrees (each way).
FINE_NUDGES_DEG = tuple(round(0.01 * k, 2) for k in range(1, 51))
#: How far the straight drive out of an end is probed, metres.
PROBE_M = 6.0
#: A nudge must lengthen the straight drive out by at least this much, metres.
GAIN_M = 1.0


@dataclass(frozen=True, eq=False)
class Nudge:
    """An end moved along a gentle arc: the search's end and the arc to drive there.

    ``pose``: where the search starts (a nudged start) or arrives (a nudged goal);
    ``piece``: the arc in driving order, from the start to ``pose`` or from ``pose``
    to the goal, both end poses included.
    """

    pose: Pose
    piece: Piece


def _straight_run(
    body: BodyTest, x: float, y: float, yaw: float, way: int, spacing: float
) -> float:
    """How far the car drives straight from the pose (``way`` +1 nose first) while free."""
    n = math.ceil(PROBE_M / spacing)
    s = np.arange(1, n + 1) * (PROBE_M / n)
    free = body.free(arc_poses(x, y, yaw, 0.0, way, s))
    hit = np.flatnonzero(~free)
    return PROBE_M if len(hit) == 0 else float(s[hit[0]]) - PROBE_M / n


def nudge(
    end: Pose,
    at_goal: bool,
    gears: tuple[int, ...],
    body: BodyTest,
    kappa_max: float,
    length: float,
    spacing: float,
) -> Nudge | None:
    """The gentle arc out of ``end`` after which the straight drive out is longest.

    Parameters
    ----------
    end : Pose
        The query's start or goal.
    at_goal : bool
        True for the goal: the arc is its arrival, found by driving backwards in time.
    gears : tuple of int
        The gears the car may leave the start or arrive at the goal in.
    body : BodyTest
        The body test keeping the search's clearance.
    kappa_max : float
        The car's curvature limit (1/m).
    length : float
        The arc's length, metres (the search's step).
    spacing : float
        Largest distance between tested poses, metres.

    Returns
    -------
    Nudge or None
        None when no gear's straight drive out is shorter than ``PROBE_M`` or no arc
        of :data:`NUDGES_DEG`, nor then of :data:`FINE_NUDGES_DEG`, lengthens it by
        ``GAIN_M``.
    """
    n = max(1, math.ceil(length / spacing))
    s = np.arange(1, n + 1) * (length / n)
    # Per gear, the way the car moves out of the end (the goal's arrival in ``gear``,
    # driven backwards in time, moves the other way) and its straight run there now.
    ways = {gear: -gear if at_goal else gear for gear in gears}
    bases = {gear: _straight_run(body, end.x, end.y, end.yaw, way, spacing)
             for gear, way in ways.items()}  # fmt: skip

    def candidates(degrees: tuple[float, ...]) -> list[tuple[float, int, float, np.ndarray]]:
        """``(run, gear, kappa, arc)`` of every free arc that lengthens the run by GAIN_M."""
        found = []
        for gear, way in ways.items():
            base = bases[gear]
            if base >= PROBE_M:
                continue
            for deg in degrees:
                for turn in (1.0, -1.0):
                    kappa = turn * math.radians(deg) / length
                    if abs(kappa) > kappa_max:
                        continue
                    arc = arc_poses(end.x, end.y, end.yaw, kappa, way, s)
                    if not body.free(arc).all():
                        continue
                    run = _straight_run(body, *(float(v) for v in arc[-1]), way, spacing)
                    if run >= base + GAIN_M:
                        found.append((run, gear, kappa, arc))
        return found

    # The longest run, the first found among equals.
    best = max(candidates(NUDGES_DEG), key=lambda c: c[0], default=None)
    if best is None:
        # The turn that opens the way out may lie in a narrow window between the coarse
        # angles (0.325-0.475 deg in one slot, 0.01-0.02 in another; a helper's audit):
        # scan finely and take the middle of the longest-run window, whose edges leave
        # the search least room.
        fine = candidates(FINE_NUDGES_DEG)
        if fine:
            top = max(c[0] for c in fine)
            window = [c for c in fine if c[0] == top]
            window = sorted((c for c in window if c[1] == window[0][1]), key=lambda c: c[2])
            best = window[len(window) // 2]
    if best is None:
        return None
    _, gear, kappa, arc = best
    rows = np.vstack([[end.x, end.y, end.yaw], arc])
    rows = np.column_stack([rows, np.full(len(rows), kappa)])
    # In driving order: the goal's arrival ends at the goal (the same steering).
    piece = Piece(gear, rows[::-1].copy() if at_goal else rows)
    return Nudge(Pose(*(float(v) for v in arc[-1])), piece)
