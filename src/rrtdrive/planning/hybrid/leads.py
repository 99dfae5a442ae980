"""Straight lead-ins: shots that end with a straight drive into a pose boxed in at its sides.

A goal in a bay between parked cars (or a start to be left from one) can only be
driven into straight: every full-lock arc through it hits a neighbour. The analytic
shots end with an arc into the goal, so from the aisle they all fail, and the search
must itself thread the car into the bay at its resolution (a bay-to-bay drive
across a garage aisle spent 5 000 expansions at 0.5 m / 5 deg without a
connection; ``experiments/garage_moves.py``). :func:`lead_ins` finds where such a
pose lies: per direction along its heading, the straight drive out of it that is
free, and the first point on it from where full-lock arcs are free too.
:func:`~.shots.analytic_shots` then also aims at that point and appends the straight.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rrtdrive.planning.hybrid.body import BodyTest
from rrtdrive.planning.hybrid.primitives import arc_poses
from rrtdrive.types import Pose

__all__ = ["Lead", "lead_ins"]

#: Length of the full-lock arcs that test whether a pose is boxed in (metres).
ARC_PROBE = 2.0
#: Steps along the straight drive out of a boxed-in pose (metres).
LEAD_STEP = 0.5
#: Lead-ins start this far apart from the first unboxed point on (metres): the
#: steering-rate ramp into the straight needs room there.
VIA_SPACING = 1.0


@dataclass(frozen=True, eq=False)
class Lead:
    """A straight lead-in: aim the shots at ``via``, then drive straight to the target.

    ``gear``: the gear of the straight drive into the target (+1: the car comes in
    nose first); ``rows``: ``[x, y, yaw, kappa]`` from ``via`` to the target, ``spacing``
    apart, both ends included, kappa 0.
    """

    via: Pose
    gear: int
    rows: np.ndarray


def _arcs(poses: np.ndarray, kappa: float, gear: int, spacing: float) -> np.ndarray:
    """Both full-lock arcs driven ARC_PROBE from each pose in ``gear``: ``(P, 2, m, 3)``.

    The poses share one heading (they lie on one straight), so the arcs are those
    from the origin shifted (``x + offset`` is what :func:`arc_poses` adds too).
    """
    s = np.arange(1, math.ceil(ARC_PROBE / spacing) + 1) * spacing
    yaw = float(poses[0, 2])
    base = np.stack([arc_poses(0.0, 0.0, yaw, turn * kappa, gear, s) for turn in (1.0, -1.0)])
    out = np.repeat(base[None], len(poses), axis=0)
    out[..., 0] += poses[:, 0, None, None]
    out[..., 1] += poses[:, 1, None, None]
    return out


def _boxed(body: BodyTest, arcs: np.ndarray) -> np.ndarray:
    """Per pose, whether both of its arcs hit: ``arcs`` is ``(P, 2, m, 3)``."""
    free = body.runs_free(arcs.reshape(-1, *arcs.shape[2:])).reshape(-1, 2)
    return ~free.any(axis=1)


def lead_ins(
    target: Pose,
    body: BodyTest,
    kappa: float,
    gears: tuple[int, ...],
    spacing: float,
    longest: float,
    count: int = 3,
) -> tuple[Lead, ...]:
    """The straight lead-ins into ``target`` for each gear of ``gears`` where it is boxed in.

    For a gear ``g`` (the gear of the final straight into ``target``), the car
    leaving ``target`` backwards in time drives in gear ``-g``. When both full-lock
    arcs that way hit within :data:`ARC_PROBE`, the straight drive that way is
    followed in :data:`LEAD_STEP` steps while it stays free, up to ``longest``
    metres, to the first point whose own arcs do not both hit: the first lead-in
    starts there, the next ones :data:`VIA_SPACING` further out each (``count`` in all
    while the straight stays free). No lead-in where the target is not boxed in that
    way, where the straight hits first, or where no such point comes within ``longest``.

    Parameters
    ----------
    target : Pose
        The pose the shots aim at (the goal, or the start for the search from the goal).
    body : BodyTest
        The exact body test with the search's clearance.
    kappa : float
        The full-lock curvature of the search (``1 / radius``).
    gears : tuple of int
        The gears of the final straight to consider (``(1,)`` forward only).
    spacing : float
        Largest gap between the poses tested and returned.
    longest : float
        Longest straight lead-in, metres.
    count : int
        Largest number of lead-ins per gear (0: none).

    Returns
    -------
    tuple of Lead
    """
    leads: list[Lead] = []
    per_via = round(VIA_SPACING / LEAD_STEP)
    n = max(1, math.ceil(LEAD_STEP / spacing))
    steps = int(longest / LEAD_STEP + 1e-9)
    here = np.array(target.as_tuple())
    for gear in gears if count > 0 else ():
        if not _boxed(body, _arcs(here[None], kappa, -gear, spacing))[0]:
            continue
        # The straight drive out, every pose at once: how many whole steps stay free.
        s = np.arange(1, steps * n + 1) * (LEAD_STEP / n)
        ahead = arc_poses(target.x, target.y, target.yaw, 0.0, -gear, s)
        free = body.free(ahead)
        clear_steps = (int(np.argmin(free)) if not free.all() else len(free)) // n
        if clear_steps == 0:
            continue
        vias = ahead[n - 1 : clear_steps * n : n]  # the end of each free step
        boxed = _boxed(body, _arcs(vias, kappa, -gear, spacing))
        if boxed.all():
            continue  # no point within ``longest`` lets the car turn
        first = int(np.argmin(boxed))
        for k in range(first, clear_steps, per_via)[:count]:
            out = (k + 1) * LEAD_STEP
            via = Pose(*(float(v) for v in vias[k]))
            m = max(1, math.ceil(out / spacing))
            back = arc_poses(
                target.x, target.y, target.yaw, 0.0, -gear, np.linspace(out, 0.0, m + 1)
            )
            rows = np.column_stack([back, np.zeros(len(back))])
            rows[0, :3] = via.as_tuple()
            rows[-1, :3] = target.as_tuple()
            leads.append(Lead(via, gear, rows))
    return tuple(leads)
