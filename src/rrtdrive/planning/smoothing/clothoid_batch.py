"""Many clothoid curves sampled at once: :func:`sample_pieces` in a few array operations.

The Dubins fallback samples dozens of candidate curves per query (most of which
collide); one piece at a time that is hundreds of small numpy calls. Here every
piece of every curve is laid out in one set of rows and each formula of
:meth:`Piece.rows <rrtdrive.planning.smoothing.clothoid_curve.Piece.rows>` and
:func:`~rrtdrive.planning.smoothing.clothoid.sample_turn` runs once over all of
them, in the same order of operations on the same operands, so every float is the
same as :func:`sample_pieces` gives (the tests check bit for bit): element-wise
arithmetic, ``sin``, ``cos`` and the Fresnel integrals round alike whatever the
array around an element.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from scipy.special import fresnel

from rrtdrive.planning.smoothing.clothoid import _clothoid_end
from rrtdrive.planning.smoothing.clothoid_curve import Piece

__all__ = ["sample_curves", "CurveBatch"]

#: Per-row parameters of a turn piece, in this order (see :func:`_turn_params`).
_TURN_FIELDS = 17


def _turn_params(p: Piece) -> tuple[float, ...]:
    """The scalars :func:`sample_turn` and :meth:`Piece.rows` compute for a turn piece."""
    t = p.turn
    assert t is not None
    th = abs(t.theta)
    sign = 1.0 if t.theta >= 0.0 else -1.0
    total = t.length
    lc, sig, k = t.clothoid, t.sigma, t.kappa
    # sample_turn's arc-part constants (used only by rows on the arc; harmless otherwise).
    xc, yc = _clothoid_end(lc, sig)
    phi = 0.5 * k * lc
    return (
        th, sign, total, 0.5 * total, lc, sig, k, math.sqrt(math.pi / sig), xc, yc, phi,
        math.sin(phi), math.cos(phi), -math.sin(0.5 * th), math.cos(0.5 * th), t.tangent,
        1.0 if th < 1e-12 else 0.0,
    )  # fmt: skip


def sample_curves(curves: Sequence[Sequence[Piece]], spacing: float) -> list[np.ndarray]:
    """Per curve, the rows of ``sample_pieces(pieces, spacing)``: the same floats.

    Parameters
    ----------
    curves : sequence of sequence of Piece
        Each curve's pieces in driving order (each non-empty).
    spacing : float
        Largest arc length between rows (> 0).

    Returns
    -------
    list of numpy.ndarray
        Rows ``[x, y, yaw, kappa]`` per curve, each piece's ends included once.

    Examples
    --------
    >>> from rrtdrive.planning.smoothing.clothoid_curve import polygon_curve, sample_pieces
    >>> pieces = polygon_curve(np.array([[0.0, 0.0], [20.0, 0.0], [20.0, 20.0]]), 1 / 6, 0.08)
    >>> bool(np.array_equal(sample_curves([pieces], 0.5)[0], sample_pieces(pieces, 0.5)[0]))
    True
    """
    batch = CurveBatch(curves, spacing)
    if not batch.sizes:
        return []
    return np.split(batch.rows(), np.cumsum(batch.sizes[:-1]))


class CurveBatch:
    """The rows of :func:`sample_curves` laid out, each computed only when asked for.

    A row's floats depend only on its arc length and its piece, so any subset of the
    rows is the same floats as those rows of the whole (the tests check bit for
    bit). The Dubins fallback tests every 16th pose of its candidates first and
    most collide there: it asks for those rows, not all.

    Parameters
    ----------
    curves : sequence of sequence of Piece
        Each curve's pieces in driving order (each non-empty).
    spacing : float
        Largest arc length between rows (> 0).

    Attributes
    ----------
    sizes : list of int
        Rows per curve (each piece's ends included once); the rows of curve ``j``
        are ``sum(sizes[:j])`` onwards.
    """

    def __init__(self, curves: Sequence[Sequence[Piece]], spacing: float) -> None:
        flat = [p for pieces in curves for p in pieces]
        self._flat = flat
        if not flat:
            self.sizes = [0] * len(curves)
            self._s = np.empty(0)
            self._piece = np.empty(0, dtype=np.int64)
            return
        lengths = [p.length for p in flat]
        counts = [max(1, math.ceil(length / spacing - 1e-9)) + 1 for length in lengths]
        total = sum(counts)
        cnt = np.array(counts)
        ends = np.cumsum(cnt)
        # np.linspace(0, L, n + 1): i * (L / n), the last exactly L.
        i = np.arange(total, dtype=float) - np.repeat(ends - cnt, cnt)
        step = np.repeat(
            np.array([length / (c - 1) for length, c in zip(lengths, counts, strict=True)]), cnt
        )
        s = i * step
        s[ends - 1] = lengths
        # Each piece after a curve's first starts where the previous ended: drop that row.
        first_row = ends - cnt
        keep = np.ones(total, dtype=bool)
        bounds = np.cumsum([0] + [len(pc) for pc in curves]).tolist()
        for j in range(len(curves)):
            keep[first_row[bounds[j] + 1 : bounds[j + 1]]] = False
        kept = np.flatnonzero(keep)
        self._s = s[kept]
        self._piece = np.repeat(np.arange(len(flat)), cnt)[kept]
        split = np.searchsorted(kept, first_row[bounds[1:-1]]).tolist()
        self.sizes = np.diff([0, *split, len(kept)]).tolist()
        # Per piece, computed when a row of it is first asked for.
        self._base = np.empty((len(flat), 5))
        self._turn = np.zeros((len(flat), _TURN_FIELDS))
        self._is_turn = np.array([p.turn is not None for p in flat], dtype=bool)
        self._known = np.zeros(len(flat), dtype=bool)

    def _prepare(self, pieces: np.ndarray) -> None:
        """Compute the parameters of the pieces not yet known among ``pieces``."""
        new = np.unique(pieces[~self._known[pieces]])
        if not len(new):
            return
        flat = self._flat
        todo = [flat[k] for k in new.tolist()]
        self._base[new] = [(p.x, p.y, p.yaw, math.cos(p.yaw), math.sin(p.yaw)) for p in todo]
        turns = new[self._is_turn[new]]
        if len(turns):
            self._turn[turns] = [_turn_params(flat[k]) for k in turns.tolist()]
        self._known[new] = True

    def rows(self, idx: np.ndarray | None = None) -> np.ndarray:
        """Rows ``[x, y, yaw, kappa]`` at indices ``idx`` (all rows when None), shape ``(N, 4)``."""
        if idx is None:
            s, piece = self._s, self._piece
        else:
            s, piece = self._s[idx], self._piece[idx]
        out = np.empty((len(s), 4))
        if not len(s):
            return out
        self._prepare(piece)
        x0, y0, yaw0, c, sn = self._base[piece].T
        is_turn = self._is_turn[piece]
        line = ~is_turn
        out[line, 0] = x0[line] + s[line] * c[line]
        out[line, 1] = y0[line] + s[line] * sn[line]
        out[line, 2] = yaw0[line]
        out[line, 3] = 0.0
        if is_turn.any():
            rows = self._turn[piece[is_turn]].T
            with np.errstate(divide="ignore", invalid="ignore"):  # turns of no deflection
                local = _sample_turns(s[is_turn], rows)
            ct, st = c[is_turn], sn[is_turn]
            out[is_turn, 0] = x0[is_turn] + ct * local[0] - st * local[1]
            out[is_turn, 1] = y0[is_turn] + st * local[0] + ct * local[1]
            out[is_turn, 2] = yaw0[is_turn] + local[2]
            out[is_turn, 3] = local[3]
        return out


def _sample_turns(s: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """:func:`sample_turn` at ``s`` with per-row turn parameters: ``(4, N)`` local rows."""
    th, sign, total, half_len, lc, sig, k, a, xc, yc, phi, sphi, cphi, d0, d1, tangent, flat = rows
    first = s <= half_len
    q = np.where(first, s, total - s)
    x = np.empty_like(q)
    y = np.empty_like(q)
    yaw = np.empty_like(q)
    kap = np.empty_like(q)
    on_clo = q <= lc
    qc, ac, sc = q[on_clo], a[on_clo], sig[on_clo]
    sf, cf = fresnel(qc / ac)
    x[on_clo], y[on_clo] = ac * cf, ac * sf
    yaw[on_clo] = 0.5 * sc * qc**2
    kap[on_clo] = sc * qc
    arc = ~on_clo
    if arc.any():
        ka = k[arc]
        ang = phi[arc] + ka * (q[arc] - lc[arc])
        x[arc] = xc[arc] + (np.sin(ang) - sphi[arc]) / ka
        y[arc] = yc[arc] - (np.cos(ang) - cphi[arc]) / ka
        yaw[arc] = ang
        kap[arc] = ka
    m = ~first
    if m.any():
        dm0, dm1, tm = d0[m], d1[m], tangent[m]
        rx, ry = x[m] - tm, y[m]
        proj = rx * dm0 + ry * dm1
        x[m] = tm + 2.0 * proj * dm0 - rx
        y[m] = 2.0 * proj * dm1 - ry
        yaw[m] = th[m] - yaw[m]
    sg = sign
    local = np.stack([x, sg * y, sg * yaw, sg * kap])
    line = flat > 0.0
    if line.any():  # a turn of no deflection: sample_turn's straight line
        local[:, line] = 0.0
        local[0, line] = s[line]
    return local
