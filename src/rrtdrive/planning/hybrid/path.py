"""From a Hybrid A* connection to a checked path with gears.

The pieces of a connection are grouped into gear segments (a cusp between two
segments). Each segment is, when ``smooth`` is on, handed to the improved
planner's post-processor (:func:`~rrtdrive.planning.smoothing.make_drivable`)
between its exact end poses, with its own rows (thinned to about a metre) as the
raw path. A reverse segment ``P -> Q`` is the same geometry as the forward drive
``Q -> P`` with the same nose yaw and the same steering curvature: that forward
path is smoothed and its rows reversed. A segment that cannot be smoothed keeps
its exact arcs when ``arc_fallback`` is on. Every segment is then checked again
(exact body with the clearance, ``|kappa| <= kappa_max``), so a path is never
returned unchecked.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from rrtdrive.collision import CollisionChecker
from rrtdrive.geometry import densify, wrap_angle
from rrtdrive.planning.hybrid.ramp_chunks import ramped_in_chunks
from rrtdrive.planning.hybrid.ramps import ramped_segment
from rrtdrive.planning.hybrid.search import Piece
from rrtdrive.planning.smoothing import SmoothingConfig, make_drivable, max_sharpness
from rrtdrive.types import Path, Pose

__all__ = [
    "GearSegment", "gear_segments", "BuiltPath", "path_of", "Ramps", "SegmentMemo", "build_path",
]


@dataclass(frozen=True, eq=False)
class GearSegment:
    """The rows ``[x, y, yaw, kappa]`` of one gear between two stops (or the ends).

    Attributes
    ----------
    gear : int
        +1 forward, -1 reverse.
    rows : numpy.ndarray
        ``(N, 4)`` rows ``x, y, yaw, kappa`` (metres, radians, 1/m).
    """

    gear: int
    rows: np.ndarray


def gear_segments(pieces: Sequence[Piece]) -> list[GearSegment]:
    """Consecutive pieces of one gear joined into segments (junction rows not repeated).

    Parameters
    ----------
    pieces : sequence of Piece
        The path's pieces in driving order.

    Returns
    -------
    list of GearSegment
        One per gear between cusps, in order.
    """
    out: list[GearSegment] = []
    for p in pieces:
        if out and out[-1].gear == p.gear:
            out[-1] = GearSegment(p.gear, np.vstack([out[-1].rows, p.rows[1:]]))
        else:
            out.append(GearSegment(p.gear, np.asarray(p.rows, dtype=float)))
    return out


def path_of(built: BuiltPath) -> Path:
    """The :class:`~rrtdrive.types.Path` of a built path (rows with their gear column)."""
    return Path(built.rows, built.waypoints)


@dataclass(frozen=True, eq=False)
class BuiltPath:
    """A checked path: rows ``[x, y, yaw, kappa, gear]``, its waypoints and how it was made.

    Attributes
    ----------
    rows : numpy.ndarray
        ``(N, 5)``; at a cusp the position row repeats with the new gear.
    waypoints : numpy.ndarray
        ``(M, 2)``: the segments' control points (smoothed) or end and joint positions.
    segments : int
        Gear segments (cusps + 1).
    smoothed : int
        Segments made continuous in curvature (steering ramps or B-splines); the
        others kept their exact arcs.
    smoothing_message : str
        Why the last unsmoothed segment could not be smoothed ('' when all were).
    """

    rows: np.ndarray
    waypoints: np.ndarray
    segments: int
    smoothed: int
    smoothing_message: str
    #: ``(wheelbase, value)`` of :meth:`max_sharpness` when every segment was measured
    #: while the path was built (the ramped segments are), else ``None``.
    measured_sharpness: tuple[float, float] | None = None

    def max_sharpness(self, wheelbase: float) -> float:
        """Largest ``|d delta / ds|`` (rad/m) within the gear segments (``inf``: a jump).

        A cusp is a stop, where the steering may turn at standstill: it does not count
        (:func:`~rrtdrive.planning.smoothing.max_sharpness` skips gear changes).
        Exact arcs jump in curvature where two primitives meet, so their value is
        ``inf`` unless the segment steers constantly. The largest of the segments'
        values measured while building is the same number (the same intervals).

        Parameters
        ----------
        wheelbase : float
            The car's wheelbase in metres (``delta = atan(wheelbase * kappa)``).

        Returns
        -------
        float
            Radians per metre.
        """
        if self.measured_sharpness is not None and self.measured_sharpness[0] == wheelbase:
            return self.measured_sharpness[1]
        return max_sharpness(self.rows, wheelbase)


def _raw_polyline(rows: np.ndarray, spacing: float) -> np.ndarray:
    """The segment's positions thinned to about ``spacing`` apart, both ends kept."""
    xy = rows[:, :2]
    steps = np.hypot(*np.diff(xy, axis=0).T)
    s = np.concatenate([[0.0], np.cumsum(steps)])
    total = s[-1]
    if total <= spacing:
        return xy[[0, -1]].copy()
    marks = np.linspace(0.0, total, max(2, int(math.ceil(total / spacing)) + 1))
    idx = np.unique(np.searchsorted(s, marks).clip(0, len(xy) - 1))
    idx[0], idx[-1] = 0, len(xy) - 1
    return xy[np.unique(idx)]


#: Poses at each end of a segment that :func:`_segment_ok` tests before the others.
END_POSES = 64


def _segment_ok(
    rows: np.ndarray, checker: CollisionChecker, clearance: float, kappa_max: float, spacing: float
) -> bool:
    """``|kappa| <= kappa_max`` and the body free: ``checker.path_free``'s answer.

    The poses ``path_free`` tests, each on its own (the same floats in any batch),
    the ends first: the ramps of a rejected connection mostly cut a corner by a
    tight start or goal (fuzzed maps 1180 and 865: at the first or last 3 % of the
    poses in half of the segments), and the rest need no test then. The start's
    :data:`END_POSES` first of all, densified from their own rows
    (:func:`densify` cuts each row interval on its own: the same points as the
    whole path's first ones): on fuzzed maps 891, 842 and 1180 every rejected
    connection failed there, and the rest of the path is then not densified.
    """
    if len(rows) < 2 or float(np.abs(rows[:, 3]).max()) > kappa_max * (1.0 + 1e-9):
        return False

    def free(part: np.ndarray) -> bool:
        return not len(part) or bool(checker.poses_free(part, clearance).all())

    poses = np.asarray(rows, dtype=float)[:, :3]
    k = END_POSES
    # The first k + 1 rows hold at least k points of the whole path's densified poses.
    head = densify(poses[: k + 1], spacing, angle_column=2)
    cut = head.pieces.max() > 1  # then the whole path is cut too: its poses are points
    if cut and not free(head.points[:k]):
        return False
    dense = densify(poses, spacing, angle_column=2)
    if dense.pieces.max() > 1:  # else dense enough already: the rows themselves
        poses = dense.points
    if cut:  # the first k tested: the last k, then the middle
        rest = poses[k:]
        return all(free(part) for part in ((rest[-k:], rest[:-k]) if len(rest) > k else (rest,)))
    parts = (poses[:k], poses[-k:], poses[k:-k]) if len(poses) > 2 * k else (poses,)
    return all(free(part) for part in parts)


def _resample(rows: np.ndarray, spacing: float, gear: int = 1) -> np.ndarray:
    """Rows at most ``spacing`` apart (linear in position and yaw).

    Each row takes the curvature of the interval of ``rows`` that it starts or lies in:
    of the two rows' kappas the one the yaw's turn between them shows (the interval
    lies on one arc or line); the last row keeps its own. A junction row carries either
    piece's kappa, or a word's end 0 (a word sampled, or reversed in time), and the
    rows added after one took the arc's curvature on the line that followed
    (``rrtdrive verify``'s kappa check, session 35).
    """
    dense = densify(rows[:, :3], spacing, angle_column=2, rel_slack=1e-5)
    if len(rows) < 2:
        return np.column_stack([dense.points, rows[:1, 3]])
    step = rows[1:, :2] - rows[:-1, :2]
    chord = np.maximum(np.hypot(step[:, 0], step[:, 1]), 1e-12)
    turned = gear * 2.0 * np.sin(0.5 * wrap_angle(np.diff(rows[:, 2]))) / chord
    own, next_ = rows[:-1, 3], rows[1:, 3]
    interval = np.where(np.abs(turned - next_) < np.abs(turned - own), next_, own)
    owner = np.searchsorted(dense.vertex_index, np.arange(len(dense.points)), side="right") - 1
    kappa = np.append(interval, rows[-1, 3])[np.clip(owner, 0, len(rows) - 1)]
    return np.column_stack([dense.points, kappa])


def _smoothed(
    seg: GearSegment,
    checker: CollisionChecker,
    smoothing: SmoothingConfig,
    raw_spacing: float,
) -> tuple[np.ndarray, np.ndarray, str]:
    """``(rows, control points, '')`` of the smoothed segment, or empty rows and why not."""
    rows = seg.rows if seg.gear > 0 else seg.rows[::-1]
    start = Pose(*rows[0, :3])
    goal = Pose(*rows[-1, :3])
    raw = _raw_polyline(rows, raw_spacing)
    res = make_drivable(raw, start, goal, checker, smoothing)
    if not res.ok:
        return np.zeros((0, 4)), np.zeros((0, 2)), res.message
    out = np.array(res.samples, dtype=float)
    out[0, :3] = start.as_tuple()
    out[-1, :3] = goal.as_tuple()
    ctrl = np.asarray(res.control_points, dtype=float)
    if seg.gear < 0:
        out, ctrl = out[::-1].copy(), ctrl[::-1].copy()
    return out, ctrl, ""


#: Bytes of keys and rows a memo keeps; later segments are fitted each time. Counted in
#: bytes (was 4 096 segments, "a few MB"): a forward query's segments, a whole connection
#: each, held 109 MB in 4 096, while a search from the goal with reverse shares its
#: goal-side segments among thousands of connections and kept refitting them once 4 096
#: were held (fuzzed map 865 with reverse: 8 506 fits, 7 370 with every segment held).
MEMO_BYTES = 128 * 2**20


class SegmentMemo(dict[tuple[int, bytes], "tuple[np.ndarray, float] | None"]):
    """The checked ramped segments of a search, the first :data:`MEMO_BYTES` of them.

    A gear segment (gear, its rows' bytes) -> its checked ramped rows and
    sharpness, or ``None`` when it fits no guarantee.
    """

    held: int = 0

    def __init__(self) -> None:
        super().__init__()
        #: The stretches of :func:`~.ramp_chunks.ramped_in_chunks` fitted so far (the
        #: connections of one search share their first stretches), in the same bytes.
        self.stretches = StretchMemo(self)

    def keep(self, key: tuple[int, bytes], found: tuple[np.ndarray, float] | None) -> None:
        """Remember ``found`` for ``key`` while the memo holds less than :data:`MEMO_BYTES`."""
        size = len(key[1]) + (found[0].nbytes if found is not None else 0)
        if self.held + size <= MEMO_BYTES:
            self[key] = found
            self.held += size


class StretchMemo(dict[tuple[int, tuple[bool, bool], bytes], "np.ndarray | None"]):
    """Fitted stretches of long segments, counted in their :class:`SegmentMemo`'s bytes."""

    def __init__(self, owner: SegmentMemo) -> None:
        super().__init__()
        self.owner = owner

    def __setitem__(
        self, key: tuple[int, tuple[bool, bool], bytes], found: np.ndarray | None
    ) -> None:
        size = len(key[2]) + (found.nbytes if found is not None else 0)
        if self.owner.held + size <= MEMO_BYTES:
            super().__setitem__(key, found)
            self.owner.held += size


@dataclass(frozen=True)
class Ramps:
    """Continuous curvature for every segment: the sharpness bound and the car.

    ``ramp_share`` of ``sharpness`` goes to the ramps (the rows measure a little
    more than the ramps' own rate); every segment is checked against ``sharpness``.
    ``chunks``: a segment whose whole fit fails is fitted a stretch at a time.

    Attributes
    ----------
    sharpness : float
        Largest ``|d delta / ds|`` a smoothed segment may have, rad/m.
    wheelbase : float
        The car's wheelbase, metres.
    kappa_max : float
        The car's largest curvature, 1/m.
    ramp_share : float
        Share of ``sharpness`` the ramps are built with.
    chunks : bool
        Fit a segment a stretch at a time when its whole fit fails.
    """

    sharpness: float
    wheelbase: float
    kappa_max: float
    ramp_share: float = 0.9
    chunks: bool = True

    @property
    def delta_max(self) -> float:
        """The steering limit ``atan(L kappa_max)``."""
        return math.atan(self.wheelbase * self.kappa_max)


def _ramped(
    seg: GearSegment,
    ramps: Ramps,
    spacing: float,
    ok: Callable[[np.ndarray], bool] | None = None,
    memo: SegmentMemo | None = None,
) -> tuple[np.ndarray, float] | None:
    """The ramped rows of a segment and their sharpness, or ``None`` over the bound.

    With ``ok``: also ``None`` when ``ok(rows)`` is False, tested before the
    sharpness (either one rejects the segment; on tight maps the rejected ramps
    fail the body test, which then spares the sharpness).
    """
    args = (seg.rows, seg.gear, ramps.ramp_share * ramps.sharpness, ramps.wheelbase,
            ramps.delta_max, min(spacing, 0.2))  # fmt: skip
    rows = ramped_segment(*args)
    if rows is None or (ok is not None and not ok(rows)):
        # A long segment's fit spreads its ramps' offsets over the whole (metres off the
        # checked arcs): fitted a stretch at a time instead (only where the whole failed,
        # so every path the whole fit gives stays as it was).
        rows = None
        if ramps.chunks and len(seg.rows) > 2:
            rows = ramped_in_chunks(*args, fits=None if memo is None else memo.stretches)
        if rows is None or (ok is not None and not ok(rows)):
            return None
    sharp = max_sharpness(rows, ramps.wheelbase)
    return None if sharp > ramps.sharpness else (rows, sharp)


def _fitted(
    segs: Sequence[GearSegment],
    ramps: Ramps,
    checker: CollisionChecker,
    clearance: float,
    kappa_max: float,
    check_spacing: float,
    sample_spacing: float,
    memo: SegmentMemo | None,
) -> list[tuple[np.ndarray, float]] | None:
    """Each segment's checked ramped rows and sharpness, or ``None`` when one fails.

    Last segment first: a connection's new part is its end (a search's shot after
    the tree path, a turn's moves), where it fails if it fails; the shared stretch
    before it is most often in the memo.
    """
    out: list[tuple[np.ndarray, float]] = []

    def checked(rows: np.ndarray) -> bool:
        return _segment_ok(rows, checker, clearance, kappa_max, check_spacing)

    for seg in reversed(segs):
        key = (seg.gear, seg.rows.tobytes())
        if memo is not None and key in memo:
            found = memo[key]
        else:
            found = _ramped(seg, ramps, sample_spacing, checked, memo)
            if memo is not None:
                memo.keep(key, found)
        if found is None:
            return None
        out.append(found)
    return out[::-1]


def build_path(
    pieces: Sequence[Piece],
    checker: CollisionChecker,
    smoothing: SmoothingConfig | None,
    arc_fallback: bool,
    clearance: float,
    kappa_max: float,
    check_spacing: float = 0.1,
    sample_spacing: float = 0.25,
    raw_spacing: float = 1.0,
    ramps: Ramps | None = None,
    memo: SegmentMemo | None = None,
) -> BuiltPath | None:
    """The checked path of a connection, or ``None`` when a segment fits no guarantee.

    Parameters
    ----------
    pieces : sequence of Piece
        The connection in driving order (exact arcs, start to goal).
    checker : CollisionChecker
        The map's checker.
    smoothing : SmoothingConfig or None
        The post-processor's settings (its clearance and ``kappa_max`` are the
        query's); ``None``: keep the arcs.
    arc_fallback : bool
        Keep a segment's arcs when it cannot be smoothed.
    clearance : float
        Body clearance every segment keeps (exact test).
    kappa_max : float
        The car's curvature limit.
    check_spacing, sample_spacing, raw_spacing : float
        Spacing of the tested poses, of the returned rows, and of the raw path
        given to the smoothing.
    ramps : Ramps or None
        Steering ramps for every segment (then ``smoothing`` is not used).
    memo : SegmentMemo or None
        The checked ramped segments of earlier calls with the same other
        arguments: connections that share a stretch (a search's tree, a turn's
        moves) fit and check its segments once.

    Returns
    -------
    BuiltPath or None
    """
    segs = gear_segments(pieces)
    fitted: list[tuple[np.ndarray, float]] = []
    if ramps is not None:
        found = _fitted(segs, ramps, checker, clearance, kappa_max, check_spacing,
                        sample_spacing, memo)  # fmt: skip
        if found is None:
            return None
        fitted = found
    out_rows: list[np.ndarray] = []
    waypoints: list[np.ndarray] = []
    smoothed = 0
    message = ""
    sharpness = 0.0
    for i, seg in enumerate(segs):
        rows = np.zeros((0, 4))
        if ramps is not None:
            ramped, sharp = fitted[i]
            sharpness = max(sharpness, sharp)
            smoothed += 1
            waypoints.append(ramped[[0, -1], :2])
            rows = np.column_stack([ramped, np.full(len(ramped), float(seg.gear))])
            rows[:, 2] = wrap_angle(rows[:, 2])
            out_rows.append(rows)
            continue
        if smoothing is not None:
            rows, ctrl, why = _smoothed(seg, checker, smoothing, raw_spacing)
            if len(rows) and _segment_ok(rows, checker, clearance, kappa_max, check_spacing):
                smoothed += 1
                waypoints.append(ctrl)
            else:
                rows = np.zeros((0, 4))
                message = why or "the smoothed segment failed the re-check"
        if not len(rows):
            if not arc_fallback:
                return None
            rows = _resample(seg.rows, sample_spacing, seg.gear)
            if not _segment_ok(rows, checker, clearance, kappa_max, check_spacing):
                return None
            waypoints.append(rows[[0, -1], :2])
        rows = np.column_stack([rows, np.full(len(rows), float(seg.gear))])
        rows[:, 2] = wrap_angle(rows[:, 2])
        out_rows.append(rows)
    all_rows = np.vstack(out_rows)
    measured = (ramps.wheelbase, sharpness) if ramps is not None else None
    return BuiltPath(all_rows, np.vstack(waypoints), len(segs), smoothed, message, measured)

