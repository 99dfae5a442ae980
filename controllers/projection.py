"""Projection on a sampled path: :class:`PathProjector` and its :class:`Projection`.

``project`` runs once per simulation step, so the projector works in plain Python
on lists with a local search from the previous match (no numpy per step). It
projects one forward gear segment (:mod:`rrtdrive.controllers.gears` splits a path
with gear changes into them).
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass

import numpy as np

from rrtdrive.types import InputError, Path

__all__ = ["Projection", "PathProjector"]


@dataclass(frozen=True)
class Projection:
    """A point projected on the path.

    Attributes
    ----------
    index : int
        Index of the segment start sample.
    s : float
        Arc length of the foot point (may run past either end on the extensions).
    x, y, yaw, kappa : float
        Foot point, path heading and curvature there.
    cte : float
        Signed lateral offset of the point from the path, positive to the left.
    """

    index: int
    s: float
    x: float
    y: float
    yaw: float
    kappa: float
    cte: float


class PathProjector:
    """Projects points on a sampled path; beyond either end the path runs straight on.

    Parameters
    ----------
    path : Path
        At least two samples, all in gear +1.
    arc_end : bool
        Past its end the path goes on along the circle of its last curvature
        (:meth:`point_at`; the controllers use it on the gear segments of a path with
        gear changes), else straight on. The projection always extends straight.

    Examples
    --------
    >>> xs = np.linspace(0.0, 10.0, 41)
    >>> p = Path(np.column_stack([xs, 0 * xs, 0 * xs, 0 * xs]), np.zeros((0, 2)))
    >>> pr = PathProjector(p).project(3.1, 0.5)
    >>> round(pr.s, 6), round(pr.cte, 6)
    (3.1, 0.5)
    """

    def __init__(self, path: Path, arc_end: bool = False) -> None:
        self.arc_end = bool(arc_end)
        samples = np.asarray(path.samples, dtype=float)
        if samples.ndim != 2 or samples.shape[1] != 5 or len(samples) < 2:
            raise InputError(
                f"path: need at least two samples [x, y, yaw, kappa, gear], got {samples.shape}"
            )
        # (Finite: a Path refuses NaN and inf when it is made, and its arrays are read-only.)
        if not path.is_forward_only:
            n = len(path.cusps)
            what = f"has {n} gear change{'s' if n != 1 else ''}" if n else "is driven in reverse"
            raise InputError(
                f"path: {what}; a PathProjector projects one forward gear segment "
                "(rrtdrive.controllers.gear_segments splits a path into them)"
            )
        xy = samples[:, :2]
        seg = np.hypot(*np.diff(xy, axis=0).T)
        keep = np.concatenate([[True], seg > 1e-9])  # drop repeated samples
        samples = samples[keep]
        if len(samples) < 2:
            raise InputError("path: all samples coincide")
        self.samples = samples
        self.x = samples[:, 0].tolist()
        self.y = samples[:, 1].tolist()
        self.yaw = np.unwrap(samples[:, 2]).tolist()
        self.kappa = samples[:, 3].tolist()
        s = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(samples[:, :2], axis=0).T))])
        self.s = s.tolist()
        self.length = float(s[-1])
        self.n = len(self.x)
        # Segment directions (unit) for projection.
        d = np.diff(samples[:, :2], axis=0)
        norm = np.hypot(d[:, 0], d[:, 1])
        self.ux = (d[:, 0] / norm).tolist()
        self.uy = (d[:, 1] / norm).tolist()
        self.seg_len = norm.tolist()
        self.hint = 0

    def reset_hint(self, index: int = 0) -> None:
        """Restart the local search at segment ``index``.

        Parameters
        ----------
        index : int
            Segment from sample ``index`` to ``index + 1``; clipped to the path's segments.
        """
        self.hint = max(0, min(index, self.n - 2))

    def _seg_dist2(self, i: int, px: float, py: float) -> float:
        dx, dy = px - self.x[i], py - self.y[i]
        t = dx * self.ux[i] + dy * self.uy[i]
        if t < 0.0:
            t = 0.0
        elif t > self.seg_len[i]:
            t = self.seg_len[i]
        ex, ey = dx - t * self.ux[i], dy - t * self.uy[i]
        return ex * ex + ey * ey

    def nearest_segment(self, px: float, py: float) -> int:
        """Index of the segment nearest to ``(px, py)``, by local descent from the last match.

        Walks forward while the next segment is at least as near, else backward while
        the previous one is nearer: a few evaluations per control step, and progress
        stays continuous even where the path comes back near itself.

        Parameters
        ----------
        px, py : float
            The point, metres, in the path's frame.

        Returns
        -------
        int
            ``i``, the segment from sample ``i`` to ``i + 1`` (repeated samples dropped);
            the next search starts there.
        """
        i = self.hint
        last = self.n - 2
        d = self._seg_dist2(i, px, py)
        moved = False
        while i < last:
            dn = self._seg_dist2(i + 1, px, py)
            if dn > d:
                break
            i, d, moved = i + 1, dn, True
        if not moved:
            while i > 0:
                dp = self._seg_dist2(i - 1, px, py)
                if dp >= d:
                    break
                i, d = i - 1, dp
        self.hint = i
        return i

    def project(self, px: float, py: float) -> Projection:
        """Foot point of ``(px, py)`` on the path (with straight extensions at the ends).

        Parameters
        ----------
        px, py : float
            The point, metres, in the path's frame.

        Returns
        -------
        Projection
            Foot point, arc length, heading, curvature (0 on the extensions) and signed
            offset ``cte`` (left positive) of the point.
        """
        i = self.nearest_segment(px, py)
        dx, dy = px - self.x[i], py - self.y[i]
        ux, uy = self.ux[i], self.uy[i]
        t = dx * ux + dy * uy
        seg = self.seg_len[i]
        if (i == 0 and t < 0.0) or (i == self.n - 2 and t > seg):
            # On the straight extension before the start or past the end.
            end = 0 if t < 0.0 else self.n - 1
            yaw = self.yaw[end]
            c, s_ = math.cos(yaw), math.sin(yaw)
            ex, ey = px - self.x[end], py - self.y[end]
            along = ex * c + ey * s_
            return Projection(
                i, self.s[end] + along, self.x[end] + along * c, self.y[end] + along * s_,
                yaw, 0.0, ey * c - ex * s_,
            )
        if t < 0.0:
            t = 0.0
        elif t > seg:
            t = seg
        frac = t / seg
        yaw = self.yaw[i] + frac * (self.yaw[i + 1] - self.yaw[i])
        kappa = self.kappa[i] + frac * (self.kappa[i + 1] - self.kappa[i])
        # Signed offset from the segment's line, positive to the left of the path.
        cte = ux * dy - uy * dx
        return Projection(i, self.s[i] + t, self.x[i] + t * ux, self.y[i] + t * uy, yaw, kappa, cte)

    def point_at(self, s: float) -> tuple[float, float, float, float]:
        """``(x, y, yaw, kappa)`` at arc length ``s``, straight on past either end.

        With ``arc_end`` the path goes on past its end on the circle of its last
        curvature instead.

        Parameters
        ----------
        s : float
            Arc length from the first sample, metres (negative before it).

        Returns
        -------
        x, y, yaw, kappa : float
            Position (m), heading (rad, unwrapped) and curvature (1/m), interpolated linearly
            between samples; curvature 0 on a straight extension.
        """
        if s <= 0.0:
            yaw = self.yaw[0]
            return (self.x[0] + s * math.cos(yaw), self.y[0] + s * math.sin(yaw), yaw, 0.0)
        if s >= self.length:
            yaw = self.yaw[-1]
            d = s - self.length
            k = self.kappa[-1]
            if self.arc_end and abs(k) > 1e-9:
                # On the circle of the end's curvature: the car reaches the end with the
                # path's curvature (a gear segment ends at a stop, not at a straight).
                y1 = yaw + k * d
                return (
                    self.x[-1] + (math.sin(y1) - math.sin(yaw)) / k,
                    self.y[-1] - (math.cos(y1) - math.cos(yaw)) / k,
                    y1,
                    k,
                )
            return (self.x[-1] + d * math.cos(yaw), self.y[-1] + d * math.sin(yaw), yaw, 0.0)
        i = bisect.bisect_right(self.s, s) - 1
        i = min(i, self.n - 2)
        frac = (s - self.s[i]) / (self.s[i + 1] - self.s[i])
        return (
            self.x[i] + frac * (self.x[i + 1] - self.x[i]),
            self.y[i] + frac * (self.y[i + 1] - self.y[i]),
            self.yaw[i] + frac * (self.yaw[i + 1] - self.yaw[i]),
            self.kappa[i] + frac * (self.kappa[i + 1] - self.kappa[i]),
        )
