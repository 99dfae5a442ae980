"""The search's body test: a sure-collision screen in front of the checker's exact test.

Most successor arcs and analytic shots that fail, fail by a lot: their body
runs into an obstacle. Proving that is cheaper than proving freedom. A point of
the body's centre line at least ``W/2`` from both bumpers carries the disc of
radius ``W/2`` inside the body; if that point lies in an occupied grid cell, an
obstacle (or the outside) is within ``h + h/sqrt 2`` (< ``W/2``) of it, so the
body collides. Poses that this screen does not reject go to the checker's
:meth:`~rrtdrive.collision.CollisionChecker.poses_free` (disc screens, then the
exact rectangle), so the answer is exactly the checker's.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from rrtdrive.collision import CollisionChecker
from rrtdrive.vehicle import cover_discs

__all__ = ["BodyTest", "disc_reach"]

#: Up to this many unsure poses skip the checker's six-disc screen: its fixed cost
#: (about 18 us) exceeds the exact test's for them (about 2.4 us a pose after 20 us).
_DIRECT_EXACT = 6
#: Up to this many unsure poses in runs_free go to the exact test in one call: its fixed
#: cost exceeds what testing each run's worst pose first saves on so few (with the
#: worst by six-disc room: 82 -> 77 us per call recorded from the 60 reverse queries).
_ONE_CALL = 8


def disc_reach(offsets: Sequence[float], length: float, kappa: float) -> list[float]:
    """:meth:`BodyTest.reach` for discs at ``offsets``: ``length * hypot(1, offset * kappa)``."""
    return [length * math.hypot(1.0, o * kappa) for o in offsets]


class BodyTest:
    """Exact body test with clearance, with a sure-collision screen first.

    Parameters
    ----------
    checker : CollisionChecker
        The map's checker.
    clearance : float
        Distance the body must keep (the checker's exact ``clearance``).

    Examples
    --------
    >>> from rrtdrive.maps import builtin_map
    >>> checker = CollisionChecker.for_map(builtin_map("overtake"))
    >>> test = BodyTest(checker, 0.1)
    >>> test.free(np.array([[5.0, 44.0, 0.0], [-3.0, 44.0, 0.0]])).tolist()
    [True, False]
    """

    def __init__(self, checker: CollisionChecker, clearance: float) -> None:
        self.checker = checker
        self.clearance = float(clearance)
        v = checker.vehicle
        h = checker.resolution
        half = v.width / 2.0
        lo, hi = -v.rear_overhang + half, v.front_extent - half
        reach = h + h / math.sqrt(2.0)
        # The screen is sound only while an occupied cell's obstacle is within the disc.
        sound = reach < half and hi >= lo
        count = max(2, math.ceil((hi - lo) / half) + 1) if sound else 0
        axis = np.linspace(lo, hi, count) if count else np.zeros(0)
        discs, radius = cover_discs(v, 3)
        self._n_axis = len(axis)
        self._axis_list = [float(o) for o in axis]
        self._disc_list = [float(o) for o in discs]
        self.offsets = np.concatenate([axis, discs])
        # clearance() of an occupied cell is -grid_error; of a free cell >= h - grid_error.
        self.occupied_below = -checker.grid_error + 0.5 * h
        # Three covering discs clear by the clearance: the body is (the field is a lower bound).
        self.disc_need = radius + self.clearance
        # The checker's second screen (six discs; the exact test's answer where they clear),
        # looked up with the others in one pass by runs_free.
        six, six_radius = cover_discs(v, 6)
        self.six_need = six_radius + self.clearance
        self._run_offsets = np.concatenate([self.offsets, six])

    @property
    def screens(self) -> bool:
        """Whether the sure-collision screen has points (:meth:`hit_at` can say True)."""
        return self._n_axis > 0

    def screen(self, poses: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(hit, clear, room)`` for poses ``(N, 3)``.

        ``hit``: the body surely collides; ``clear``: it is surely free (else
        unsure); ``room``: the smallest covering-disc clearance beyond what is
        needed (the most negative poses are the likeliest to collide).
        """
        p = np.asarray(poses, dtype=float).reshape(-1, 3)
        val = self.checker.axis_clearances(p.T, self.offsets)
        k = self._n_axis
        # (No NaN in val: a point outside the grid reads -inf.) min < b: some value is.
        if k:
            hit = np.minimum.reduce(val[:k], axis=0) < self.occupied_below
        else:
            hit = np.zeros(len(p), dtype=bool)
        room = np.minimum.reduce(val[k:], axis=0) - self.disc_need
        return hit, room >= 0.0, room

    def _exact(self, poses: np.ndarray) -> np.ndarray:
        """The checker's exact answer for poses the screen left unsure (not ``clear``).

        Their three covering discs do not clear ``disc_need`` (the checker's first
        screen, the same test), so the checker starts at its six-disc screen; a
        few poses go straight to the exact rectangles, which then cost less than
        that screen's look-ups (the answer is the exact test's either way).
        """
        if len(poses) <= _DIRECT_EXACT:
            return self.checker.rectangles_free(poses, clearance=self.clearance)
        return self.checker.poses_free_unscreened(poses, clearance=self.clearance)

    def reach(self, length: float, kappa: float) -> list[float]:
        """How far each covering disc's centre can move while the rear axle drives ``length``.

        A centre ``o`` ahead of the rear axle moves ``sqrt(1 + (o kappa)^2)`` per metre
        of rear-axle travel at steering curvature ``kappa``, in either gear: over
        ``length`` at ``|kappa| <= kappa`` it stays within that many metres.
        """
        return disc_reach(self.disc_offsets, length, kappa)

    @property
    def disc_offsets(self) -> tuple[float, ...]:
        """The covering discs' offsets ahead of the rear axle, metres."""
        return tuple(self._disc_list)

    def free_within(self, x: float, y: float, yaw: float, reach: Sequence[float]) -> bool:
        """True when every pose whose discs lie within ``reach`` of this pose's is free.

        The clearance field is a 1-Lipschitz lower bound of the distance to the nearest
        obstacle: a disc centre with ``disc_need + reach`` of room here has
        ``disc_need`` wherever it moves within ``reach``, so the body keeps the
        clearance there (the checker's exact test says free, its screens no hit).
        False proves nothing. The search makes this decision from :meth:`disc_room`
        with the same comparisons.
        """
        return all(room >= r for room, r in zip(self.disc_room(x, y, yaw), reach, strict=True))

    def disc_room(self, x: float, y: float, yaw: float) -> list[float]:
        """Each covering disc's room beyond ``disc_need`` at a pose (see :meth:`free_within`)."""
        c, s = math.cos(yaw), math.sin(yaw)
        clearance, need = self.checker.clearance, self.disc_need
        return [clearance(x + c * off, y + s * off) - need for off in self._disc_list]

    def hit_at(self, x: float, y: float, yaw: float) -> bool:
        """Scalar :meth:`hits` for one pose (no numpy call: for walks that stop early)."""
        c, s = math.cos(yaw), math.sin(yaw)
        clearance, below = self.checker.clearance, self.occupied_below
        for off in self._axis_list:
            if clearance(x + c * off, y + s * off) < below:
                return True
        return False

    def any_hits(self, poses: np.ndarray, sizes: Sequence[int] | np.ndarray) -> np.ndarray:
        """Boolean ``(W,)``: whether :meth:`hit_at` is True at some pose of each walk.

        ``poses`` ``(M, 3)`` are the walks' poses one walk after the other,
        ``sizes[w]`` of them for walk ``w``. One look-up for all (the same points,
        so the same answer, as :meth:`hit_at` pose by pose).
        """
        counts = [int(m) for m in sizes]
        out = np.zeros(len(counts), dtype=bool)
        if not self._n_axis or not len(poses):
            return out
        p = np.asarray(poses, dtype=float)
        val = self.checker.axis_clearances(p.T, self.offsets[: self._n_axis])
        hit = np.minimum.reduce(val, axis=0) < self.occupied_below
        # Each walk's first pose; reduceat over the nonempty walks alone (it would read
        # an empty walk's next pose).
        walks, starts, first = [], [], 0
        for w, m in enumerate(counts):
            if m > 0:
                walks.append(w)
                starts.append(first)
            first += m
        out[walks] = np.logical_or.reduceat(hit, starts)
        return out

    def hits(self, poses: np.ndarray) -> np.ndarray:
        """Boolean ``(N,)``: True where the body surely collides (False proves nothing)."""
        return self.screen(poses)[0]

    def free(self, poses: np.ndarray) -> np.ndarray:
        """Boolean ``(N,)``: the checker's exact answer with the clearance."""
        p = np.asarray(poses, dtype=float).reshape(-1, 3)
        hit, clear, _ = self.screen(p)
        out = clear & ~hit
        rest = np.flatnonzero(~hit & ~clear)
        if len(rest):
            out[rest] = self._exact(p[rest])
        return out

    def all_free(self, poses: np.ndarray, first: int = 8) -> bool:
        """True when every pose ``(N, 3)`` is free.

        Stops at the screen when one surely hits; else the exact test sees the
        unsure pose with the least room on its own (the rectangle test alone, as
        :meth:`_exact` gives a few poses: the same answer), then the ``first``
        unsure poses with the next least room, then the others. Of the shots on
        fuzzed map 891 that the screen left unsure, 7 662 of 11 953 failed at the
        pose with the least room, for which the six-disc screen cost more than the
        rectangle.
        """
        p = np.asarray(poses, dtype=float).reshape(-1, 3)
        hit, clear, room = self.screen(p)
        # The ufuncs' reductions, not the methods' Python wrappers (the shots' hot path).
        if np.logical_or.reduce(hit):
            return False
        rest = (~clear).nonzero()[0]
        if not len(rest):
            return True
        rest = rest[room[rest].argsort(kind="stable")]
        if not self.checker.rectangles_free(p[rest[:1]], clearance=self.clearance)[0]:
            return False
        rest = rest[1:]
        if not len(rest):
            return True
        if not np.logical_and.reduce(self._exact(p[rest[:first]])):
            return False
        return len(rest) <= first or bool(np.logical_and.reduce(self._exact(p[rest[first:]])))

    def runs_free(self, poses: np.ndarray) -> np.ndarray:
        """Boolean ``(P,)`` for runs of poses ``(P, n, 3)``: True where the whole run is free."""
        P, n = poses.shape[0], poses.shape[1]
        return self.rows_free(poses.reshape(P * n, 3).T, P)

    def rows_free(self, rows: np.ndarray, runs: int) -> np.ndarray:
        """:meth:`runs_free` of ``runs`` runs given as rows ``(3, N)``: x, y, yaw, run after run.

        One look-up for the screen's points and the checker's six discs; a run with a
        sure hit is out, a pose the three or the six discs clear is free (the
        checker's answer). The exact rectangles see the other poses: a few in one
        call, else first the one with the least six-disc room of each run, then the
        others of the runs that passed it (fewer poses where runs fail).
        """
        P = runs
        n = rows.shape[1] // P
        val = self.checker.axis_clearances(rows, self._run_offsets)
        k, k3 = self._n_axis, self._n_axis + 3
        # (No NaN in val.) alive: no axis point of the run below occupied_below.
        if k:
            axis = val[:k].reshape(k, P, n)
            alive = np.minimum.reduce(axis, axis=(0, 2)) >= self.occupied_below
        else:
            alive = np.ones(P, dtype=bool)
        three = np.minimum.reduce(val[k:k3], axis=0)
        six = np.minimum.reduce(val[k3:], axis=0)
        six -= self.six_need
        six = six.reshape(P, n)
        # Neither screen clears the pose (for floats, v - need < 0 exactly when v < need).
        unsure = (three < self.disc_need).reshape(P, n)
        unsure &= six < 0.0
        unsure &= alive[:, None]
        flat = unsure.ravel()
        idx = flat.nonzero()[0]
        if not len(idx):
            return alive
        poses = rows.T
        rectangles_free, clearance = self.checker.rectangles_free, self.clearance
        if len(idx) <= _ONE_CALL:
            alive[idx[~rectangles_free(poses[idx], clearance)] // n] = False
            return alive
        todo = np.logical_or.reduce(unsure, axis=1).nonzero()[0]
        worst = np.where(unsure, six, np.inf)[todo].argmin(axis=1)
        worst += todo * n
        alive[todo[~rectangles_free(poses[worst], clearance)]] = False
        unsure &= alive[:, None]
        flat[worst] = False
        idx = flat.nonzero()[0]
        if len(idx):
            alive[idx[~rectangles_free(poses[idx], clearance)] // n] = False
        return alive
