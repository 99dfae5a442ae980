"""From the key polygon to a checked B-spline: control points, curvature and body checks.

How the guarantee is checked: the curvature of a degree-2 curve exactly, span by
span (:func:`~rrtdrive.planning.smoothing.bspline.quadratic_span_max_curvature`;
a cusp counts as infinite), of a degree-3 curve on a parameter grid eight times
finer than the output; the body with the checker's exact test at curve poses at
most ``check_spacing`` apart; and, as a backstop, the heading may turn by at most
``kappa_max`` times the arc length between poses. Each check names the key
corners whose pieces of curve break it.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from scipy.interpolate import BSpline

from rrtdrive.geometry import wrap_angle
from rrtdrive.planning.smoothing.bspline import (
    curvature,
    fit_bspline,
    parameter_grid,
    quadratic_span_max_curvature,
    spline_curvature,
)
from rrtdrive.planning.smoothing.checks import CheckerView
from rrtdrive.planning.smoothing.config import SmoothingConfig
from rrtdrive.planning.smoothing.corners import Corner, Ends, polygon_legs, turn_angles
from rrtdrive.planning.smoothing.fillet import Fillet, fillet_points, outer_reach
from rrtdrive.planning.smoothing.operations import supplement_fractions

__all__ = ["CurveFitter"]


class CurveFitter:
    """Builds control points from corners and checks the curve, with caches for one call.

    Parameters
    ----------
    cfg : SmoothingConfig
        Tunables.
    view : CheckerView
        The original map's checker.
    ends : Ends
        Start and goal of the path.
    """

    def __init__(self, cfg: SmoothingConfig, view: CheckerView, ends: Ends) -> None:
        self.cfg = cfg
        self.view = view
        self.ends = ends
        # Poses at most check_spacing apart (every `stride`-th is an output sample).
        self.stride = max(1, int(cfg.sample_spacing / cfg.check_spacing + 1e-9))
        self._fillets: dict[tuple[float, ...], tuple[Fillet, list[list[float]]]] = {}
        # Bezier pieces (bytes of their three points) whose body test passed.
        self._free_pieces: set[bytes] = set()

    # ------------------------------------------------------------- control points

    def leg_room(self, corners: Sequence[Corner], leg: int) -> tuple[float, float, float, float]:
        """Leg ``leg``'s length, what its fillets need (:meth:`control_points`' test), angles.

        As :meth:`~.clothoid_curve.ClothoidFitter.leg_room`, for the paper's fillets:
        both corners' reach along the leg plus the straight kept at the start or goal.
        """
        pts = [c.point.tolist() for c in corners]
        n = len(pts)
        dirs, lengths = polygon_legs(pts)
        reach = self._corner_points(pts, dirs, [c.radius for c in corners])[1]
        end_leg = (leg == 0 and reach[1] > 0) or (leg == n - 2 and reach[leg] > 0)
        need = reach[leg] + reach[leg + 1] + (self.cfg.end_gap if end_leg else 0.0)
        turn_a, turn_b = turn_angles(dirs, lengths, (leg, leg + 1))
        return lengths[leg], need, turn_a, turn_b

    def control_points(
        self, corners: Sequence[Corner]
    ) -> tuple[np.ndarray, np.ndarray, list[int]]:
        """Control points, the key corner owning each, and the legs too short for their fillets."""
        cfg = self.cfg
        # Plain floats throughout (the polygon is small; numpy per corner costs more).
        pts = [c.point.tolist() for c in corners]
        n = len(pts)
        dirs, lengths = polygon_legs(pts)
        corner_pts, reach = self._corner_points(pts, dirs, [c.radius for c in corners])
        conflicts: list[int] = []
        fr = supplement_fractions(cfg.supplement_n)
        ctrl: list[list[float]] = [pts[0]]
        own: list[int] = [0]
        for i in range(n - 1):
            if i > 0:
                ctrl += corner_pts[i]
                own += [i] * len(corner_pts[i])
            s0, s1 = reach[i], lengths[i] - reach[i + 1]
            end_leg = (i == 0 and reach[1] > 0) or (i == n - 2 and reach[i] > 0)
            need = cfg.end_gap if end_leg else 0.0
            if s1 - s0 < need - 1e-9:
                conflicts.append(i)
                continue
            if cfg.supplement and s1 - s0 >= cfg.supplement_delta and fr:
                ux, uy = dirs[i]
                px, py = pts[i]
                for f_k in fr:
                    along = s0 + f_k * (s1 - s0)
                    ctrl.append([px + along * ux, py + along * uy])
                    own.append(max(i, 1) if f_k < 0.5 else min(i + 1, n - 2))
        ctrl.append(pts[-1])
        own.append(n - 1)
        ctrl_a = np.array(ctrl)
        own_a = np.array(own, dtype=np.int64)
        keep = np.ones(len(ctrl_a), dtype=bool)
        keep[1:] = np.hypot(*np.diff(ctrl_a, axis=0).T) > 1e-9  # merged guards
        return ctrl_a[keep], own_a[keep], conflicts

    def _corner_points(
        self,
        pts: list[list[float]],
        dirs: list[tuple[float, float]],
        radius: list[float],
    ) -> tuple[list[list[list[float]]], list[float]]:
        """Control points of each corner (fillet with guards, or the corner) and their reach."""
        cfg = self.cfg
        n = len(pts)
        guard_steps = range(cfg.degree - 1)
        corner_pts: list[list[list[float]]] = [[pts[0]]]
        reach = [0.0] * n
        for c in range(1, n - 1):
            cx, cy = pts[c]
            if radius[c] > 0.0:
                key = (cx, cy, *dirs[c - 1], *dirs[c], radius[c])
                hit = self._fillets.get(key)
                if hit is None:
                    f = fillet_points(pts[c], dirs[c - 1], dirs[c], radius[c], cfg.fillet_max_angle)
                    hit = self._fillets[key] = (f, f.vertices.tolist())
                f, verts = hit
                r = outer_reach(f, cfg.degree)
                if r > 0.0 and math.isfinite(r):
                    (uix, uiy), (uox, uoy) = dirs[c - 1], dirs[c]
                    at = [f.reach + 2.0 * f.half * k for k in guard_steps]  # guard distances
                    corner_pts.append(
                        [[cx - d * uix, cy - d * uiy] for d in reversed(at)]
                        + verts
                        + [[cx + d * uox, cy + d * uoy] for d in at]
                    )
                else:
                    corner_pts.append(verts)
                reach[c] = r
            else:
                corner_pts.append([pts[c]])
        corner_pts.append([pts[-1]])
        return corner_pts, reach

    # ------------------------------------------------------------- checking

    def check_curvature(
        self, ctrl: np.ndarray, owner: np.ndarray, n_corners: int
    ) -> tuple[list[int], float, BSpline]:
        """Corners whose pieces exceed ``kappa_max``, the largest ``|kappa|``, and the spline."""
        cfg = self.cfg
        spl = fit_bspline(ctrl, cfg.degree)
        if cfg.degree == 2:
            span_k = quadratic_span_max_curvature(ctrl)
            bad = np.flatnonzero(span_k > cfg.kappa_max)
            return self._owners(owner, bad, n_corners), float(span_k.max(initial=0.0)), spl
        # Degree 3: a dense parameter grid (spacing / 8) between the output samples.
        u = parameter_grid(spl, cfg.sample_spacing / 8.0)
        k = np.abs(spline_curvature(spl, u))
        n_int = len(ctrl) - cfg.degree
        span = np.minimum((u * n_int).astype(np.int64), n_int - 1)
        bad_corners = self._owners(owner, np.unique(span[k > cfg.kappa_max]), n_corners)
        return bad_corners, float(k.max()), spl

    def check_collision(
        self, spl: BSpline, owner: np.ndarray, n_corners: int
    ) -> tuple[list[int], np.ndarray, np.ndarray]:
        """Corners whose pieces collide, the dense rows (at most check_spacing apart), their u."""
        cfg = self.cfg
        ends = self.ends
        step = min(cfg.check_spacing, cfg.sample_spacing / self.stride)
        u = parameter_grid(spl, step)
        d1 = spl(u, nu=1)
        dense = np.column_stack([spl(u), np.arctan2(d1[:, 1], d1[:, 0]), np.zeros(len(u))])
        dense[0, :2] = ends.s
        dense[-1, :2] = ends.g
        dense[0, 2] = wrap_angle(ends.start.yaw)
        dense[-1, 2] = wrap_angle(ends.goal.yaw)
        n_int = len(spl.c) - cfg.degree
        span = np.minimum((u * n_int).astype(np.int64), n_int - 1)
        # Backstop against cusps: between samples at most `step` apart the heading
        # of a curve with |kappa| <= kappa_max turns by at most kappa_max * step.
        turn = np.abs(wrap_angle(np.diff(dense[:, 2])))
        jump = np.flatnonzero(turn > cfg.kappa_max * step * 1.05 + 1e-9)
        if len(jump):
            return self._owners(owner, np.unique(span[jump]), n_corners), dense, u
        free, bad_seg = self._body_check(spl, dense, span)
        if free:
            return [], dense, u
        hit = np.unique(
            np.concatenate([span[bad_seg], span[np.minimum(bad_seg + 1, len(span) - 1)]])
        )
        return self._owners(owner, hit, n_corners), dense, u

    def output_samples(self, spl: BSpline, dense: np.ndarray, u: np.ndarray) -> np.ndarray:
        """Every ``stride``-th dense row and the last, with its curvature filled in."""
        pick = np.arange(0, len(dense), self.stride)
        if pick[-1] != len(dense) - 1:
            pick = np.append(pick, len(dense) - 1)
        samples = dense[pick]
        uu = u[pick]
        samples[:, 3] = curvature(spl(uu, nu=1), spl(uu, nu=2))
        return samples

    def _body_check(
        self, spl: BSpline, dense: np.ndarray, span: np.ndarray
    ) -> tuple[bool, np.ndarray]:
        """The exact body test of the dense poses, skipping pieces already proven free.

        A piece of a clamped uniform quadratic B-spline is the Bezier curve of
        three points derived from its control points alone
        (:func:`~rrtdrive.planning.smoothing.bspline.quadratic_span_max_curvature`),
        so a piece whose three points were checked free in an earlier round of
        this call is the same curve, already checked at poses at most
        ``check_spacing`` apart; its poses are not tested again. Everything else
        is tested exactly as by ``path_free`` (the dense poses are already that
        close, which is checked).
        """
        cfg = self.cfg
        poses_free = self.view.poses_free()
        chord = np.hypot(*np.diff(dense[:, :2], axis=0).T)
        if cfg.degree != 2 or poses_free is None or not chord.max() <= cfg.check_spacing:
            return self.view.path_free(dense, spacing=cfg.check_spacing, clearance=cfg.clearance)
        c = np.asarray(spl.c, dtype=float)
        mid = 0.5 * (c[:-1] + c[1:])
        a, b, e = mid[:-1].copy(), c[1:-1], mid[1:].copy()
        a[0], e[-1] = c[0], c[-1]
        keys = [row.tobytes() for row in np.hstack([a, b, e])]
        known = np.array([k in self._free_pieces for k in keys], dtype=bool)
        todo = np.flatnonzero(~known[span])
        ok = np.ones(len(dense), dtype=bool)
        if len(todo):
            ok[todo] = poses_free(dense[todo, :3], cfg.clearance)
        bad_pose = np.flatnonzero(~ok)
        failed = set(span[bad_pose].tolist())
        for j in np.unique(span[todo]).tolist():
            if j not in failed:
                self._free_pieces.add(keys[j])
        # As path_free: pose i stands for segment i (the last pose for the last one).
        return len(bad_pose) == 0, np.unique(np.minimum(bad_pose, len(dense) - 2))

    def _owners(self, owner: np.ndarray, spans: np.ndarray, n_corners: int) -> list[int]:
        """Key corners whose control points shape the given knot spans."""
        k = self.cfg.degree
        last = n_corners - 2
        out: set[int] = set()
        for j in np.asarray(spans, dtype=np.int64).tolist():
            # Degree 2: span j is the Bezier piece of control point j + 1; degree 3:
            # control points j .. j + 3 act on span j.
            window = owner[j + 1 : j + 2] if k == 2 else owner[j : j + k + 1]
            out.update(min(max(int(c), 1), last) for c in window.tolist())
        return sorted(out)
