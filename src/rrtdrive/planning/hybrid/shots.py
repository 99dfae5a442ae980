"""Analytic expansions of the Hybrid A* search: the shortest words to the exact goal pose.

From an expanded node the search tries the obstacle-free shortest paths to the
goal (Dubins forward, Reeds-Shepp with reverse) and keeps those whose body is
clear. Most fail by a lot, so each word's poses half a metre apart are screened
first (:func:`walks_hit`, the body test's sure-collision screen), all words of
one shot in one look-up; the survivors are sampled finely for the exact test.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Iterator, Sequence
from dataclasses import dataclass

import numpy as np

from rrtdrive.planning.dubins import DubinsPath, dubins_paths
from rrtdrive.planning.hybrid.body import BodyTest
from rrtdrive.planning.hybrid.leads import Lead
from rrtdrive.planning.reeds_shepp import ReedsSheppPath, reeds_shepp_paths
from rrtdrive.types import Pose

__all__ = ["Piece", "Shots", "analytic_shots", "walk_hits", "walk_poses", "walks_hit"]


@dataclass(frozen=True, eq=False)
class Piece:
    """A stretch of path in one gear: rows ``[x, y, yaw, kappa]``, both end poses included.

    Attributes
    ----------
    gear : int
        +1 forward, -1 reverse.
    rows : numpy.ndarray
        ``(N, 4)`` rows ``x, y, yaw, kappa``; ``kappa`` is the steering curvature (1/m).
    shot : bool
        Part of an analytic word (the shortest path between its ends, nothing to shorten).
    """

    gear: int
    rows: np.ndarray
    shot: bool = False


#: ``shots(pose) -> candidates``: pieces from the pose to the exact goal, shortest first
#: (an iterable, possibly lazy: a search that takes one reads no further).
Shots = Callable[[Pose], Iterable[list[Piece]]]


_TURN = {"L": 1, "S": 0, "R": -1}


def _segment_end(
    x: float, y: float, yaw: float, c0: float, s0: float, turn: int, u: float, radius: float
) -> tuple[float, float, float]:
    """The pose after ``u`` metres of a segment (``turn`` -1, 0, 1) from ``(x, y, yaw)``.

    ``c0, s0``: the cosine and sine of ``yaw``. The arithmetic of :func:`walk_poses`'
    closed form at the segment's last pose.
    """
    if turn == 0:
        return x + u * c0, y + u * s0, yaw
    yaw = yaw + turn * u / radius
    return x + turn * radius * (math.sin(yaw) - s0), y - turn * radius * (math.cos(yaw) - c0), yaw


def walk_poses(
    start: Pose, words: Sequence[tuple[str, Sequence[float]]], radius: float, spacing: float
) -> tuple[np.ndarray, np.ndarray]:
    """Poses at most ``spacing`` apart along several words from one start (start excluded).

    Each segment is cut into ``ceil(|length| / spacing)`` equal steps; its poses
    are closed-form from the segment's start, the end pose of the segment before
    as the same formula gives it, so every pose is computed with the same
    arithmetic as in a walk one pose at a time. ``lengths`` are signed (negative
    in reverse), as in Reeds-Shepp words; Dubins lengths are all positive.

    Returns
    -------
    poses : numpy.ndarray
        ``(M, 3)``: the poses of every word, in order.
    sizes : numpy.ndarray
        ``(W,)``: how many of them belong to each word.
    """
    # Per segment: its start pose (scalar, as the walk), cos and sin of its yaw, the
    # turn, the length and the steps; and where its poses begin.
    segments: list[float] = []  # eight numbers a segment, flat (one quick array)
    counts: list[int] = []
    firsts: list[int] = []
    sizes = [0] * len(words)
    total = 0
    for w, (word, lengths) in enumerate(words):
        x, y, yaw = start.x, start.y, start.yaw
        for letter, seg in zip(word, lengths, strict=True):
            turn = _TURN[letter]
            n = max(1, math.ceil(abs(seg) / spacing))
            c0, s0 = math.cos(yaw), math.sin(yaw)
            segments += (x, y, yaw, c0, s0, turn, seg, n)
            counts.append(n)
            firsts.append(total)
            total += n
            sizes[w] += n
            x, y, yaw = _segment_end(x, y, yaw, c0, s0, turn, seg * n / n, radius)
    if not counts:
        return np.zeros((0, 3)), np.array(sizes, dtype=np.int64)
    # Each pose's segment columns; k = 1..n within its segment (n exact as a float).
    table = np.array(segments, dtype=float).reshape(-1, 8)
    px0, py0, pyaw0, c0, s0, turn, seg, n = table.repeat(counts, axis=0).T
    k = np.arange(1, total + 1) - np.array(firsts).repeat(counts)
    u = seg * k / n
    pyaw = turn * u
    pyaw /= radius
    pyaw += pyaw0
    tr = turn * radius
    straight = turn == 0.0
    # Rows x, y, yaw: the arcs' formula everywhere, then the lines' where they are (the
    # choice np.where made, with the same operations in the same order).
    out = np.empty((3, total))
    np.subtract(np.sin(pyaw), s0, out=out[0])
    out[0] *= tr
    out[0] += px0
    line = u * c0
    line += px0
    np.copyto(out[0], line, where=straight)
    arc = np.cos(pyaw)
    arc -= c0
    arc *= tr
    np.subtract(py0, arc, out=out[1])
    line = u * s0
    line += py0
    np.copyto(out[1], line, where=straight)
    np.copyto(out[2], pyaw)
    np.copyto(out[2], pyaw0, where=straight)
    return out.T, np.array(sizes, dtype=np.int64)


def walk_hits(
    start: Pose, word: str, lengths: Sequence[float], radius: float, spacing: float, body: BodyTest
) -> bool:
    """Whether a pose ``spacing`` apart along a word surely collides (:meth:`BodyTest.hit_at`).

    ``lengths`` are signed (negative in reverse), as in Reeds-Shepp words; Dubins
    lengths are all positive. All poses of the word are screened at once
    (:func:`walk_poses`, :meth:`BodyTest.any_hits`).
    """
    return walks_hit(start, [(word, lengths)], radius, spacing, body)[0]


def walks_hit(
    start: Pose,
    words: Sequence[tuple[str, Sequence[float]]],
    radius: float,
    spacing: float,
    body: BodyTest,
) -> list[bool]:
    """:func:`walk_hits` for several ``(word, lengths)`` from one start, in one screen.

    A word with a segment end far outside the map's bounds is a hit without its
    walk: that end is one of the walk's poses, and every screen point of a body
    whose rear axle is beyond the bounds by more than the car's length (plus a
    metre for the grid's cells) lies outside them, where the field reads occupied.
    With a huge turning radius on a small map every word is kilometres long, and
    walking them took seconds a shot.
    """
    if not words:
        return []
    out = [body.screens and _leaves_map(start, w, lengths, radius, body) for w, lengths in words]
    inside = [wl for wl, left in zip(words, out, strict=True) if not left]
    if not inside:
        return out
    poses, sizes = walk_poses(start, inside, radius, spacing)
    hit = iter(body.any_hits(poses, sizes).tolist())
    return [left or next(hit) for left in out]


def _leaves_map(
    start: Pose, word: str, lengths: Sequence[float], radius: float, body: BodyTest
) -> bool:
    """Whether a segment end of the word lies beyond the bounds by more than the margin.

    The ends as :func:`walk_poses` computes them, to rounding (the margin is metres).
    """
    x0, y0, x1, y1 = body.checker.bounds
    margin = body.checker.vehicle.length + 1.0
    x, y, yaw = start.x, start.y, start.yaw
    for letter, seg in zip(word, lengths, strict=True):
        x, y, yaw = _segment_end(x, y, yaw, math.cos(yaw), math.sin(yaw), _TURN[letter], seg,
                                 radius)  # fmt: skip
        if not (x0 - margin <= x <= x1 + margin and y0 - margin <= y <= y1 + margin):
            return True
    return False


#: Of two Reeds-Shepp words within this many metres of each other, the shots try the one
#: with fewer cusps first: the shortest word to a bay often ends in a 1-2 cm move in the
#: other gear (a cusp the car drives for nothing), 0.05 mm shorter than the word without.
SHOT_CUSP_COST_M = 0.5


def _gear_pieces(rows: np.ndarray) -> list[Piece]:
    """Rows ``[x, y, yaw, kappa, gear]`` cut at the cusps (each piece keeps both end rows)."""
    gear = rows[:, 4]
    # np.split's parts as slices (its Python wrapper cost more than the rest of this).
    cuts = [0, *((gear[1:] != gear[:-1]).nonzero()[0] + 1).tolist(), len(rows)]
    return [
        Piece(int(rows[a, 4]), rows[a:b, :4].copy(), True)
        for a, b in zip(cuts[:-1], cuts[1:], strict=True)
    ]


def analytic_shots(
    goal: Pose,
    radius: float,
    reverse: bool,
    spacing: float,
    body: BodyTest | None = None,
    max_candidates: int = 3,
    leads: Sequence[Lead] = (),
) -> Shots:
    """The analytic expansions to ``goal``: Dubins paths forward, Reeds-Shepp with reverse.

    Only the ``max_candidates`` shortest words are tried; with ``body``, those
    whose poses half a metre apart surely collide are dropped before they are
    sampled finely (each one only when the caller asks for it). A Reeds-Shepp word
    is cut into one piece per gear. ``leads`` (:func:`~.leads.lead_ins`): after the
    words to ``goal``, those to each lead-in's start, followed by its straight drive in.

    Parameters
    ----------
    goal : Pose
        The exact rear-axle goal pose.
    radius : float
        Turning radius of the words, metres.
    reverse : bool
        Reeds-Shepp words (gear changes) instead of Dubins.
    spacing : float
        Distance between the sampled rows, metres.
    body : BodyTest, optional
        Screens out the words that surely collide (``None``: none dropped).
    max_candidates : int
        How many of the shortest words to try.
    leads : sequence of Lead
        Straight lead-ins to try after the words to ``goal``.

    Returns
    -------
    Shots
        ``shots(pose)``: candidate lists of pieces to the goal, shortest first, lazily.
    """
    coarse = max(spacing, 0.5)

    def words(pose: Pose, to: Pose, lead: Lead | None) -> Iterator[list[Piece]]:
        # The longer words loop through the lot: they rarely clear where the short ones fail.
        cands: Sequence[ReedsSheppPath | DubinsPath] = (
            reeds_shepp_paths(pose, to, radius, limit=max_candidates, cusp_cost=SHOT_CUSP_COST_M)
            if reverse
            else dubins_paths(pose, to, radius)
        )[:max_candidates]
        hit = [False] * len(cands)
        if body is not None:
            hit = walks_hit(pose, [(c.word, c.lengths) for c in cands], radius, coarse, body)
        for cand, dropped in zip(cands, hit, strict=True):
            if dropped:
                continue
            rows = cand.sample(spacing)
            if reverse:
                rows[0, :3] = pose.as_tuple()
            elif lead is None:
                yield [Piece(1, rows, True)]
                continue
            else:
                rows = np.column_stack([rows, np.ones(len(rows))])
            yield _gear_pieces(rows if lead is None else _with_lead(rows, lead))

    def shots(pose: Pose) -> Iterator[list[Piece]]:
        yield from words(pose, goal, None)
        for lead in leads:
            yield from words(pose, lead.via, lead)

    return shots


def _with_lead(rows: np.ndarray, lead: Lead) -> np.ndarray:
    """Rows ``[x, y, yaw, kappa, gear]`` of a word to ``lead.via``, then the straight in."""
    straight = np.column_stack([lead.rows, np.full(len(lead.rows), float(lead.gear))])
    straight[:, 2] = rows[-1, 2] + (straight[:, 2] - straight[0, 2])  # the word's unwrapped yaw
    if rows[-1, 4] == lead.gear:
        straight = straight[1:]  # one gear: the junction row once
    return np.vstack([rows, straight])
