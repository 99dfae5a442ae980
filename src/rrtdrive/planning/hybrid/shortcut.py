"""Shortcuts of a Hybrid A* connection: analytic words between poses along it.

A search on cells and heading bins drives along the bins (an aisle at 0 deg, then
a late turn) where a shorter diagonal exists. :func:`shortcut` takes a connection
(pieces of exact arcs, start to goal), puts anchor poses along it, and replaces a
stretch between two anchors by the shortest clear analytic word between them
(Dubins forward, Reeds-Shepp with reverse: the shots' words) when that is shorter.
Greedy from the start, the farthest anchor first, with a counted number of tries:
deterministic. The caller builds and checks the result like any connection and
keeps the original when it is rejected.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from rrtdrive.planning.hybrid.body import BodyTest
from rrtdrive.planning.hybrid.shots import Piece, Shots
from rrtdrive.types import Pose

__all__ = [
    "STUB_M",
    "drop_end_stubs",
    "gear_changes",
    "pieces_length",
    "polyline_length",
    "shortcut",
]


def polyline_length(rows: np.ndarray) -> float:
    """Length of the polyline through the rows' positions (columns x, y), metres."""
    d = np.diff(rows[:, :2], axis=0)
    return float(np.hypot(d[:, 0], d[:, 1]).sum())


def pieces_length(pieces: Sequence[Piece]) -> float:
    """Arc length of the pieces' rows (polyline through the samples), metres."""
    return sum(polyline_length(p.rows) for p in pieces)


def _atoms(pieces: Sequence[Piece], spacing: float) -> list[Piece]:
    """The pieces cut at anchors about ``spacing`` apart (and at every piece's ends)."""
    out: list[Piece] = []
    for p in pieces:
        rows = p.rows
        d = np.diff(rows[:, :2], axis=0)
        s = np.concatenate([[0.0], np.cumsum(np.hypot(d[:, 0], d[:, 1]))])
        cuts = [0]
        for k in range(1, len(rows) - 1):
            if s[k] - s[cuts[-1]] >= spacing:
                cuts.append(k)
        cuts.append(len(rows) - 1)
        out.extend(
            Piece(p.gear, rows[a : b + 1], p.shot) for a, b in zip(cuts, cuts[1:], strict=False)
        )
    return out


def _merge(atoms: Sequence[Piece]) -> list[Piece]:
    """Consecutive atoms of one gear as one piece (the junction row not repeated)."""
    out: list[Piece] = []
    for a in atoms:
        if out and out[-1].gear == a.gear:
            out[-1] = Piece(a.gear, np.vstack([out[-1].rows, a.rows[1:]]), out[-1].shot and a.shot)
        else:
            out.append(a)
    return out


def _pose(rows: np.ndarray, k: int) -> Pose:
    return Pose(float(rows[k, 0]), float(rows[k, 1]), float(rows[k, 2]))


def shortcut(
    pieces: Sequence[Piece],
    shots_to: Callable[[Pose], Shots],
    body: BodyTest,
    tries: int,
    spacing: float = 2.0,
    min_gain: float = 0.25,
) -> list[Piece] | None:
    """A shorter connection through the same start and goal, or ``None`` when none was found.

    Parameters
    ----------
    pieces : sequence of Piece
        The connection, start to goal.
    shots_to : callable
        ``shots_to(target)``: the analytic expansions to ``target``
        (:func:`~rrtdrive.planning.hybrid.shots.analytic_shots`).
    body : BodyTest
        The search's body test (its clearance): a word must be clear to be taken.
    tries : int
        Most (anchor, anchor) pairs tried in all: the counted budget.
    spacing : float
        Distance between anchors along the connection, metres.
    min_gain : float
        A word replaces a stretch only when it is at least this much shorter, metres.

    Returns
    -------
    list of Piece or None
    """
    if tries <= 0 or all(p.shot for p in pieces):
        return None  # one analytic word (the first shot answered): nothing to shorten
    atoms = _atoms(pieces, spacing)
    changed = False
    i = 0
    while i < len(atoms) - 1 and tries > 0:
        if atoms[i].shot:
            i += 1  # inside a word: every stretch of it is already the shortest
            continue
        n = len(atoms)
        # The farthest anchors first: the goal, then three quarters, half, a quarter on.
        ends = sorted({n, i + 3 * (n - i) // 4, i + (n - i) // 2, i + (n - i) // 4}, reverse=True)
        taken = False
        for j in (e for e in ends if e >= i + 2):
            if tries <= 0:
                break
            tries -= 1
            start = _pose(atoms[i].rows, 0)
            target = _pose(atoms[j - 1].rows, -1)
            stretch = pieces_length(atoms[i:j])
            for word in shots_to(target)(start):
                if pieces_length(word) > stretch - min_gain:
                    break  # the words come shortest first
                if body.all_free(np.vstack([w.rows[:, :3] for w in word])):
                    atoms[i:j] = word
                    changed = taken = True
                    break
            if taken:
                i += len(word)  # on from the end of the word just put in
                break
        if not taken:
            i += 1
    return _merge(atoms) if changed else None


#: A gear segment at most this long (metres) at either end of a path is a stub: a move
#: the car makes for a few centimetres (a 0.086 m reverse out of a garage, a 0.3 m one at
#: the goal after a 22 m drive; a new user's find) that :func:`drop_end_stubs` tries to do
#: without.
STUB_M = 1.0


def gear_changes(pieces: Sequence[Piece]) -> int:
    """Cusps of a connection: where one piece's gear differs from the one before it."""
    return sum(a.gear != b.gear for a, b in zip(pieces, pieces[1:], strict=False))


def drop_end_stubs(
    pieces: Sequence[Piece],
    shots_to: Callable[[Pose], Shots],
    body: BodyTest,
    tries: int,
    cusp_cost: float,
    spacing: float = 2.0,
) -> list[Piece] | None:
    """The connection without its stub at the start or the goal, or ``None``.

    A stub (a first or last gear segment of at most :data:`STUB_M`) is replaced, with
    the stretch next to it, by an analytic word from the start to an anchor pose along
    the connection (or from an anchor to the goal), the anchors ``spacing`` apart and
    nearest the stub first. A word is taken when it is clear and the result has fewer
    gear changes and costs less, its length plus ``cusp_cost`` a gear change (the
    shots' order), than the original.

    Parameters
    ----------
    pieces : sequence of Piece
        The connection, start to goal.
    shots_to : callable
        ``shots_to(target)``: the analytic expansions to ``target``.
    body : BodyTest
        The search's body test.
    tries : int
        Most anchors tried at each end: the counted budget.
    cusp_cost : float
        Metres a gear change costs in the comparison.
    spacing : float
        Distance between anchors, metres.

    Returns
    -------
    list of Piece or None
    """
    out = list(pieces)

    def cost(ps: Sequence[Piece]) -> float:
        return pieces_length(ps) + cusp_cost * gear_changes(ps)

    changed = False
    for at_goal in (True, False):
        if len(out) < 2 or tries <= 0:
            break
        stub = out[-1] if at_goal else out[0]
        if pieces_length([stub]) > STUB_M:
            continue
        rest = _atoms(out[:-1] if at_goal else out[1:], spacing)
        best, cusps = cost(out) - 1e-9, gear_changes(out)
        found = None
        order = range(len(rest) - 1, -1, -1) if at_goal else range(1, len(rest) + 1)
        for j in list(order)[:tries]:
            if at_goal:
                anchor, end = _pose(rest[j].rows, 0), _pose(stub.rows, -1)
            else:
                anchor, end = _pose(stub.rows, 0), _pose(rest[j - 1].rows, -1)
            for word in shots_to(end)(anchor):
                new = [*rest[:j], *word] if at_goal else [*word, *rest[j:]]
                if gear_changes(new) >= cusps or cost(new) >= best:
                    continue  # a stub's gear change kept, or dearer than the stub
                if body.all_free(np.vstack([w.rows[:, :3] for w in word])):
                    found = _merge(new)
                    break
            if found is not None:
                break
        if found is not None:
            out, changed = found, True
    return out if changed else None
