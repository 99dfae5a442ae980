"""A multi-point turn: full-lock moves forward and in reverse by turns, then a shot.

A car that must turn round where the street is narrower than its U-turn needs a
three-point (or a many-point) turn. Hybrid A* finds one, but slowly: each cusp
costs ``gear_change_cost`` and the heuristic (zero where the goal is the start
turned round) does not see it, so the search floods the street first (a closed
street 6.5 m wide: 24 482 expansions at 0.5 m / 5 deg; ``experiments/street_turns.py``).
:func:`multi_point_turn` turns the car the way people do: wheels at full lock,
forward until the body would come closer than the clearance to an obstacle, then
in reverse with the wheels at the other lock (the heading keeps turning the same
way), and so on, each move stopping where the heading reaches the goal's; after
every move an analytic shot (Reeds-Shepp) to the goal is tried. Every move is one
exact arc, so a gear segment has no steering jump inside it; the connection is
checked like any other (``accept``: ramps, body, curvature, sharpness).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Generic, TypeVar

import numpy as np

from rrtdrive.geometry import wrap_angle
from rrtdrive.planning.hybrid.body import BodyTest
from rrtdrive.planning.hybrid.primitives import arc_poses
from rrtdrive.planning.hybrid.shots import Piece, Shots
from rrtdrive.types import Pose

__all__ = ["TurnResult", "abreast", "multi_point_turn"]

T = TypeVar("T")

#: A move shorter than this (metres) turns the car by almost nothing: the turn is stuck.
MIN_MOVE = 0.25
#: A turned car within this many turning radii of the goal gets the finishing search.
FINISH_RADII = 2.0

#: ``finish(pose, pieces, allowed) -> (result or None, expansions)`` (:func:`multi_point_turn`).
Finish = Callable[[Pose, list[Piece], int], tuple[T | None, int]]


@dataclass(frozen=True, eq=False)
class TurnResult(Generic[T]):
    """What :func:`multi_point_turn` gave: the accepted result (or ``None``) and its counts.

    ``moves``: the full-lock moves driven (in the successful turn, or in all tried);
    ``shots``: the analytic shots tried; ``expansions``: those of the finishing searches.
    """

    result: T | None
    moves: int
    shots: int
    expansions: int = 0


#: Poses of a move tested in the first look (a full turn at 6 m is 377 at 0.1 m).
_MOVE_CHUNK = 512


def _move(
    pose: Pose, kappa: float, gear: int, body: BodyTest, longest: float, spacing: float
) -> np.ndarray:
    """The poses of one full-lock move from ``pose``, up to the first one the body test fails.

    At most ``longest`` metres, poses ``spacing`` apart (the last one exactly at
    ``longest``), ``pose`` itself first.
    """
    count = max(1, math.ceil(longest / spacing))
    s = np.minimum(np.arange(1, count + 1) * spacing, longest)
    poses = arc_poses(pose.x, pose.y, pose.yaw, kappa, gear, s)
    # Tested a chunk at a time up to the first pose that fails (each pose's answer is
    # its own): a huge turning radius makes a move kilometres long that fails early.
    n, chunk = 0, _MOVE_CHUNK
    while n < count:
        free = body.free(poses[n : n + chunk])
        if not free.all():
            n += int(np.argmin(free))
            break
        n, chunk = n + len(free), 2 * chunk
    return np.vstack([[pose.x, pose.y, pose.yaw], poses[:n]])


def multi_point_turn(
    start: Pose,
    goal: Pose,
    body: BodyTest,
    shots: Shots,
    accept: Callable[[list[Piece]], T | None],
    kappa: float,
    max_moves: int,
    spacing: float = 0.1,
    finish: Finish[T] | None = None,
    budget: int | None = None,
) -> TurnResult[T]:
    """Turn the car at ``start`` round to the goal's heading by full-lock moves, then shoot.

    The turn runs the shorter way round first (then the longer one). Its first
    move is forward, or in reverse when forward the body cannot move
    :data:`MIN_MOVE`; the gears then alternate. A move ends where the body test
    fails, or where the heading has turned as far as the goal's. Before the first
    move and after each one, the shots from the pose to the goal are tried, each
    connection given to ``accept``. The turn ends on the first accepted
    connection, after ``max_moves`` moves, when a move is shorter than
    :data:`MIN_MOVE`, or when the heading has reached the goal's and no shot is
    accepted.

    Parameters
    ----------
    start, goal : Pose
        Where the turn starts, and the goal the shots aim at.
    body : BodyTest
        The exact body test with the search's clearance.
    shots : Shots
        The analytic expansions to ``goal`` (:func:`~.shots.analytic_shots`, with reverse).
    accept : callable
        ``accept(pieces)``: the result made from a start-to-goal connection, or ``None``.
    kappa : float
        Curvature of the moves (the search's ``1 / radius``).
    max_moves : int
        Largest number of moves in each direction of turning.
    spacing : float
        Largest gap between the poses tested along a move.
    finish : callable, optional
        ``finish(pose, pieces, allowed) -> (result or None, expansions)``: where the
        heading has reached the goal's and no shot is accepted, a short search from
        the pose (``pieces``: the turn so far; at most ``allowed`` expansions), tried
        when the pose lies within :data:`FINISH_RADII` turning radii of the goal.
    budget : int, optional
        Largest number of moves and finishing expansions in all (``None``: no limit
        but ``max_moves``).

    Returns
    -------
    TurnResult

    Examples
    --------
    >>> from rrtdrive.collision import CollisionChecker
    >>> from rrtdrive.maps import Map
    >>> from rrtdrive.planning.hybrid.shots import analytic_shots
    >>> street = Map("street", (0.0, 0.0, 30.0, 8.0), (), Pose(8.0, 4.0, 0.0),
    ...              Pose(8.0, 4.0, math.pi))
    >>> body = BodyTest(CollisionChecker.for_map(street), 0.15)
    >>> turn = multi_point_turn(street.start, street.goal, body,
    ...                         analytic_shots(street.goal, 6.0, True, 0.1, body),
    ...                         lambda pieces: pieces, 1 / 6.0, max_moves=12)
    >>> turn.result is not None, turn.moves
    (True, 2)
    """
    total_moves = total_shots = total_expansions = 0
    target = float(wrap_angle(goal.yaw - start.yaw))
    way = 1.0 if target >= 0.0 else -1.0
    for turn in (way, -way):
        # Heading still to turn, >= 0, in the turning direction ``turn``.
        left = target * turn if target * turn > 0.0 else target * turn + 2.0 * math.pi
        pose, gear = start, 1
        pieces: list[Piece] = []
        moves = 0
        while True:
            for cand in shots(pose):
                total_shots += 1
                result = accept(pieces + cand)
                if result is not None:
                    return TurnResult(result, moves, total_shots, total_expansions)
            allowed = math.inf if budget is None else budget - total_moves - total_expansions
            if left <= 1e-9 and finish is not None and moves > 0 and allowed > 0 and (
                math.hypot(goal.x - pose.x, goal.y - pose.y) <= FINISH_RADII / kappa
            ):
                result, spent = finish(pose, pieces, int(min(allowed, 2**31)))
                total_expansions += spent
                if result is not None:
                    return TurnResult(result, moves, total_shots, total_expansions)
            if moves >= max_moves or left <= 1e-9 or allowed < 1:
                break
            longest = left / kappa
            rows = _move(pose, turn * gear * kappa, gear, body, longest, spacing)
            if moves == 0 and _turned(rows) < MIN_MOVE * kappa:
                gear = -gear  # nose against something: begin in reverse
                rows = _move(pose, turn * gear * kappa, gear, body, longest, spacing)
            turned = _turned(rows)
            if turned < MIN_MOVE * kappa:
                break
            moves += 1
            total_moves += 1
            kappas = np.full(len(rows), turn * gear * kappa)
            pieces = [*pieces, Piece(gear, np.column_stack([rows, kappas]))]
            left = max(0.0, left - turned)
            pose = Pose(*(float(v) for v in rows[-1]))
            gear = -gear
    return TurnResult(None, total_moves, total_shots, total_expansions)


def _turned(rows: np.ndarray) -> float:
    """How far the heading turned along the rows of one move (their yaw is unwrapped)."""
    return abs(float(rows[-1, 2] - rows[0, 2]))


def abreast(
    start: Pose, goal: Pose, body: BodyTest, spacing: float, step: float = 2.0, tries: int = 4
) -> Iterator[tuple[Piece, Pose]]:
    """Straight drives from ``start`` to abreast of ``goal`` and near it, to turn from there.

    A turn that is stuck where the car starts (a wall behind it, no room at full
    lock) may have room further along: a driver who came the wrong way along a
    one-way row of angled bays drives on to the bay, then turns. The distance along
    the start's heading to the goal's projection on it, rounded to ``step``, comes
    first, then ``step`` either side of it by turns (never less than ``step``), at
    most ``tries`` in all; a drive is given, as its piece (forward, or in reverse
    when the goal lies behind) and its end pose, only when the body is free along it
    (poses ``spacing`` apart).

    Examples
    --------
    >>> from rrtdrive.collision import CollisionChecker
    >>> from rrtdrive.maps import Map
    >>> street = Map("street", (0.0, 0.0, 40.0, 8.0), (), Pose(3.0, 2.0, 0.0),
    ...              Pose(21.0, 6.0, math.pi))
    >>> body = BodyTest(CollisionChecker.for_map(street), 0.15)
    >>> [round(pose.x, 6) for _, pose in abreast(street.start, street.goal, body, 0.1)]
    [21.0, 19.0, 23.0, 17.0]
    """
    c, s = math.cos(start.yaw), math.sin(start.yaw)
    along = (goal.x - start.x) * c + (goal.y - start.y) * s
    gear = 1 if along >= 0.0 else -1
    centre = round(abs(along) / step)
    near = range(max(1, centre - tries), centre + tries + 1)
    for k in sorted(near, key=lambda k: (abs(k - centre), k))[:tries]:
        n = max(1, math.ceil(k * step / spacing))
        rows = arc_poses(start.x, start.y, start.yaw, 0.0, gear, np.linspace(0.0, k * step, n + 1))
        if body.free(rows[1:]).all():
            kappas = np.zeros((len(rows), 1))
            yield Piece(gear, np.hstack([rows, kappas])), Pose(*(float(v) for v in rows[-1]))
