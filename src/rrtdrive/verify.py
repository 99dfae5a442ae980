"""An independent check of a planned path's guarantees, for tests and experiments.

It shares no code with the planner or the checker (only the angle wrap and the
densifier of :mod:`rrtdrive.geometry`): the body is a shapely polygon built in
:mod:`rrtdrive.verify_bodies`, the measures are :mod:`rrtdrive.verify_measures`'s:
curvature is the discrete three-point
(Menger) curvature of the samples and the turn of the rows' yaw per chord (a car
cannot turn faster than its curvature allows, whatever its positions do),
sharpness the change of the steering angle ``atan(L kappa)`` between those
estimates per metre, and the direction of travel comes from the sample chords.
None of them reads the rows' ``kappa`` column.

A path with gears is checked per gear segment, never across a cusp: a cusp is
where the car stops and changes gear, so the chord across it means nothing and
the segments on either side are two separate drives. Each segment's direction
of travel is its chords' direction, the nose yaw in gear +1 and the nose yaw
plus pi in gear -1; the body is drawn along the nose yaw in both gears.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, TypeGuard

import numpy as np
import shapely

from rrtdrive import verify_bodies
from rrtdrive.geometry import densify, wrap_angle
from rrtdrive.maps import Map
from rrtdrive.types import (
    InputError,
    Path,
    brief_repr,
    is_finite_number,
    require_positive,
)
from rrtdrive.verify_measures import (
    YAW_ROUND,
    kappa_column_error,
    segment_curvature,
    segment_sharpness,
    travel_directions,
    turn_curvature,
)

__all__ = ["CHECKS", "PathCheck", "verify_path", "path_from_json"]

_CUSP_TOL_M = 1e-6  # a cusp repeats the position (to the JSON's 6 decimals)
#: Default tolerances of :func:`verify_path` (see its parameters).
HEADING_TOL_DEG = 3.0
CURVATURE_TOL = 0.001
SHARPNESS_TOL = 0.005
TRAVEL_TOL_DEG = 1.0
KAPPA_TOL = 0.01
#: The pass / fail fields of :class:`PathCheck`; ``ok`` is all of them.
CHECKS = (
    "collision_free", "curvature_ok", "sharpness_ok", "headings_ok", "endpoints_ok",
    "spacing_ok", "travel_ok", "cusps_ok", "clearance_ok", "kappa_ok",
)


@dataclass(frozen=True)
class PathCheck:
    """Outcome of :func:`verify_path`; ``ok`` is True when every guarantee holds.

    Attributes
    ----------
    ok : bool
        Every check below passed.
    collision_free : bool
        Every dense body pose lies inside the bounds and clear of the obstacles.
    curvature_ok : bool
        The discrete curvature of every gear segment is at most κ_max (plus slack):
        that of its positions and the turn of its yaw between rows per chord.
    headings_ok : bool
        The direction of travel at the start and at the goal matches their yaw
        (gear-corrected: a path may leave the start or reach the goal in reverse);
        a path that never moves (the start is the goal) has every row's yaw there.
    endpoints_ok : bool
        The first and last rows are the start's and the goal's poses (position and
        yaw).
    spacing_ok : bool
        Consecutive samples are at most the allowed spacing apart.
    max_discrete_curvature : float
        Largest discrete curvature over the segments, 1/m (inf where the yaw turns
        while the car does not move).
    start_heading_err_deg, goal_heading_err_deg : float
        Direction of travel (gear-corrected) against the start and goal yaw.
    max_spacing_m : float
        Largest gap between consecutive samples.
    cusps_ok : bool
        Every gear change repeats the position and the yaw of the row before it.
    cusps : int
        Number of gear changes.
    travel_ok : bool
        Along every segment the direction of travel matches the rows' yaw
        (``travel_heading_err_deg`` within ``travel_tol_deg``).
    travel_heading_err_deg : float
        Largest angle between a chord's direction of travel and the rows' yaw
        (plus pi in reverse), over all segments.
    max_discrete_sharpness : float
        Largest change of the steering angle per metre, rad/m, from the discrete
        curvature of each gear segment (a jump of curvature shows as a large value).
    sharpness_ok : bool
        ``max_discrete_sharpness`` is within the ``max_sharpness`` asked for (plus
        slack); True when none was asked for.
    first_collision : tuple of float or None
        Where the body check first fails along the path: the rear-axle pose
        ``(x, y, yaw)`` of the first tested pose (or the first row off the map, when no
        body before it collides); ``None`` when ``collision_free``.
    collides_with : str
        What the body there overlaps: ``"obstacle K"`` (its index in the map),
        ``"the bounds"``; empty when ``collision_free``.
    endpoint_err_m, endpoint_yaw_err_deg : float
        How far the first and last rows are from the start and goal: the larger
        distance, and the larger yaw difference (``endpoints_ok`` needs both within
        the rows' 6 decimals).
    cusp_gap_m, cusp_yaw_err_deg : float
        The largest jump of position and of yaw at a gear change (a cusp repeats both).
    first_bad_cusp_row : int or None
        The row of the first gear change that moves or turns the car; ``None`` when
        ``cusps_ok``.
    min_clearance_m : float
        The least distance between the body, at the tested poses (``pose_spacing``
        apart along the rows), and any obstacle or the edge of the bounds; 0 where
        they touch or overlap, inf on an empty map.
    clearance_ok : bool
        The body touches nothing and ``min_clearance_m`` is at least the ``clearance``
        asked for.
    kappa_ok : bool
        Every row's ``kappa`` column (``tan delta / L``, in both gears) lies within
        ``kappa_tol`` of the steering curvature the yaw turns at on the steps on
        either side of the row (:func:`~rrtdrive.verify_measures.kappa_column_error`;
        a gear segment's first and last rows, stops, only within ``kappa_tol`` of
        ±κ_max): the curvature a controller feeds forward is the path's, of the right
        sign in reverse.
    kappa_column_err : float
        The largest excess, 1/m, of a row's ``kappa`` over that bracket (an end row's:
        over κ_max).
    worst_kappa_row : int or None
        The row of that excess; ``None`` when ``kappa_ok``.
    """

    ok: bool
    collision_free: bool
    curvature_ok: bool
    headings_ok: bool
    endpoints_ok: bool
    spacing_ok: bool
    max_discrete_curvature: float
    start_heading_err_deg: float
    goal_heading_err_deg: float
    max_spacing_m: float
    cusps_ok: bool = True
    cusps: int = 0
    travel_ok: bool = True
    travel_heading_err_deg: float = 0.0
    max_discrete_sharpness: float = 0.0
    sharpness_ok: bool = True
    first_collision: tuple[float, float, float] | None = None
    collides_with: str = ""
    endpoint_err_m: float = 0.0
    endpoint_yaw_err_deg: float = 0.0
    cusp_gap_m: float = 0.0
    cusp_yaw_err_deg: float = 0.0
    first_bad_cusp_row: int | None = None
    min_clearance_m: float = math.inf
    clearance_ok: bool = True
    kappa_ok: bool = True
    kappa_column_err: float = 0.0
    worst_kappa_row: int | None = None

    @property
    def failed(self) -> tuple[str, ...]:
        """The names of the checks (:data:`CHECKS`) that failed; empty when ``ok``."""
        return tuple(name for name in CHECKS if not getattr(self, name))


#: The finest pose spacing a check may ask for, metres (finer would only take longer).
MIN_POSE_SPACING = 1e-3


def _check_settings(
    pose_spacing: float,
    max_sample_spacing: float,
    heading_tol_deg: float,
    curvature_tol: float,
    max_sharpness: float | None,
    sharpness_tol: float,
    travel_tol_deg: float,
    kappa_tol: float,
) -> None:
    """Raise :class:`InputError` naming a setting of :func:`verify_path` that is not usable.

    A spacing of 0 or less would test no pose between the rows (the body check passed
    through an obstacle), so it is refused rather than taken.
    """
    for name, value in (("pose_spacing", pose_spacing), ("max_sample_spacing", max_sample_spacing)):
        require_positive(name, value)
    if pose_spacing < MIN_POSE_SPACING:
        raise InputError(
            f"pose_spacing: must be at least {MIN_POSE_SPACING:g} m, got {pose_spacing!r}"
        )
    for name, value in (
        ("heading_tol_deg", heading_tol_deg), ("curvature_tol", curvature_tol),
        ("sharpness_tol", sharpness_tol), ("travel_tol_deg", travel_tol_deg),
        ("kappa_tol", kappa_tol),
    ):  # fmt: skip
        # A tolerance may be infinite (that check then passes whatever it measures).
        if isinstance(value, bool) or not isinstance(value, (int, float, np.number)):
            raise InputError(f"{name}: expected a number, got {brief_repr(value)}")
        if not value >= 0:
            raise InputError(f"{name}: must be >= 0, got {value!r}")
    if max_sharpness is not None:
        require_positive("max_sharpness", max_sharpness)


# Rows far off the map (x = 1e308) overflow the geometry to inf and nan: the checks
# fail on them as they should, without a screen of numpy warnings.
@np.errstate(all="ignore")
def verify_path(
    m: Map,
    path: Path,
    pose_spacing: float = 0.1,
    max_sample_spacing: float = 0.25,
    heading_tol_deg: float = HEADING_TOL_DEG,
    curvature_tol: float = CURVATURE_TOL,
    max_sharpness: float | None = None,
    sharpness_tol: float = SHARPNESS_TOL,
    clearance: float = 0.0,
    travel_tol_deg: float = TRAVEL_TOL_DEG,
    kappa_tol: float = KAPPA_TOL,
) -> PathCheck:
    """Check a path against the map with code independent of the planner.

    Parameters
    ----------
    m : Map
        The map (obstacles, bounds, start, goal, car).
    path : Path
        The planned path, forward-only or with gear changes.
    pose_spacing : float
        Poses are tested at most this far apart (interpolated between samples).
    max_sample_spacing : float
        Largest allowed gap between consecutive samples.
    heading_tol_deg : float
        Allowed angle between the direction of travel and the yaw at the start and
        the goal against their poses (SPEC: 3 degrees).
    curvature_tol : float
        Slack on κ_max, 1/m, for the discrete curvature of 0.25 m samples (an arc at
        κ_max measures within 2e-5 of it; 0.01 until session 46 passed a turn 6 % too
        tight).
    max_sharpness : float or None
        Bound on the steering angle's change per metre, rad/m (0.2 for the default
        planners: ``max_steer_rate`` / 2 m/s); ``None`` checks none (the paper's
        degree-2 B-spline jumps in curvature by design). ``max_discrete_sharpness``
        is measured either way.
    sharpness_tol : float
        Slack on ``max_sharpness``, rad/m (the estimate of an exact clothoid is
        within 0.003 rad/m of its sharpness at 0.25 m samples).
    clearance : float
        Least distance, metres, the body must keep from the obstacles and the edge of
        the bounds at the tested poses (``clearance_ok``; 0: no contact, which
        ``collision_free`` also asks). ``min_clearance_m`` is measured either way.
    travel_tol_deg : float
        Allowed angle along the path between a chord's direction of travel and the
        rows' yaw at its middle (``travel_ok``): a chord of 0.25 m across an instant
        flip from full lock left to right (a Dubins or Reeds-Shepp path) measures up
        to 0.6 degrees; a car whose nose points 2 degrees off its motion for 20 m
        slides 0.7 m sideways (passed at 3 degrees until session 46).
    kappa_tol : float
        Slack, 1/m, on the rows' ``kappa`` against the yaw's turn (``kappa_ok``).

    Returns
    -------
    PathCheck

    Examples
    --------
    >>> from rrtdrive.types import Pose
    >>> xs = np.arange(0.0, 5.01, 0.25)
    >>> fwd = np.column_stack([10 + xs, 0 * xs + 10, 0 * xs, 0 * xs, 1 + 0 * xs])
    >>> back = fwd[::-1].copy()
    >>> back[:, 4] = -1.0
    >>> m = Map("open", (0.0, 0.0, 30.0, 30.0), (), Pose(10, 10, 0), Pose(10, 10, 0))
    >>> check = verify_path(m, Path(np.vstack([fwd, back]), np.zeros((0, 2))))
    >>> check.ok, check.cusps
    (True, 1)
    """
    if not isinstance(m, Map):
        raise InputError(f"m: expected a Map (rrtdrive.maps), got {type(m).__name__}")
    if not isinstance(path, Path):
        raise InputError(
            f"path: expected a Path (rrtdrive.types; Path(rows, waypoints) from an array), "
            f"got {type(path).__name__}"
        )
    _check_settings(pose_spacing, max_sample_spacing, heading_tol_deg, curvature_tol,
                    max_sharpness, sharpness_tol, travel_tol_deg, kappa_tol)  # fmt: skip
    if not is_finite_number(clearance) or clearance < 0:  # a bool is no number there
        raise InputError(f"clearance: expected a finite number >= 0, got {brief_repr(clearance)}")
    # The map's poses; a map built with check_query=False may have them in collision
    # (rrtdrive verify): the body check then fails there.
    start, goal = m.start, m.goal
    v = m.vehicle
    s = path.samples
    if len(s) < 2:
        return PathCheck(
            False, False, False, False, False, False, math.inf, 180.0, 180.0, math.inf,
            cusps_ok=False, cusps=0, travel_ok=False, travel_heading_err_deg=180.0,
            endpoint_err_m=math.inf, endpoint_yaw_err_deg=180.0, min_clearance_m=0.0,
            clearance_ok=False, kappa_ok=False,
        )
    xy = s[:, :2]
    gaps = np.hypot(*np.diff(xy, axis=0).T)
    cusps = path.cusps
    cusp_gaps = np.hypot(*(xy[cusps] - xy[cusps - 1]).T)
    cusp_turns = np.abs(wrap_angle(s[cusps, 2] - s[cusps - 1, 2]))
    bad_cusps = (cusp_gaps > _CUSP_TOL_M) | (cusp_turns > math.radians(1e-3))
    cusps_ok = not bool(bad_cusps.any())
    region = shapely.box(*m.bounds)
    xmin, ymin, xmax, ymax = m.bounds
    # A row off the map already fails the body check; densifying a jump of 1e6 m to
    # 0.1 m poses would take minutes and gigabytes first.
    row_on_map = (xy[:, 0] >= xmin) & (xy[:, 0] <= xmax) & (xy[:, 1] >= ymin) & (xy[:, 1] <= ymax)
    # Bodies are drawn up to the first row off the map, so that a collision before it is
    # still the first one reported (an obstacle hit at 25 m was named "the bounds" at 60).
    drawn = len(s) if row_on_map.all() else int(np.argmin(row_on_map))
    bodies: list[np.ndarray] = []
    poses: list[np.ndarray] = []
    max_k = 0.0
    max_sharp = 0.0
    kappa_err, kappa_row = 0.0, -1
    travel_err = 0.0
    first_dir = last_dir = math.nan
    for a, b in path.segments():
        seg = s[a:b]
        gear = seg[0, 4]
        # The body along the nose yaw (interpolated between the rows) in either gear.
        if a < drawn:
            dense = densify(s[a:min(b, drawn), :3], pose_spacing, angle_column=2).points
            bodies.append(verify_bodies.body_polygons(dense, v.length, v.width, v.rear_overhang))
            poses.append(dense)
        if len(seg) < 2:
            continue
        max_k = max(max_k, segment_curvature(seg[:, :2]), turn_curvature(seg))
        # The end rows too, within the car's reach (kappa_column_error's docs).
        err, row = kappa_column_error(seg, v.kappa_max)
        if err > kappa_err:
            kappa_err, kappa_row = err, a + row
        max_sharp = max(max_sharp, segment_sharpness(seg[:, :2], v.wheelbase))
        direction, moving = travel_directions(seg)
        if not len(moving):
            continue
        nose = direction if gear > 0 else direction + math.pi
        # A chord runs parallel to the tangent at its midpoint: compare with the mean yaw.
        mid_yaw = seg[moving, 2] + 0.5 * wrap_angle(seg[moving + 1, 2] - seg[moving, 2])
        travel_err = max(travel_err, float(np.max(np.abs(wrap_angle(nose - mid_yaw)))))
        # The first and last chords less half their step's turn: the tangent at the
        # ends (a micro car starting at full lock turned 4 deg over its first 0.25 m
        # chord, failing the 3 deg check on a right path; an audit). The turn per step
        # is bounded by the curvature check.
        if math.isnan(first_dir):
            first_dir = float(nose[0] - (mid_yaw[0] - seg[moving[0], 2]))
        last_dir = float(nose[-1] + (seg[moving[-1] + 1, 2] - mid_yaw[-1]))
    # The bodies and the obstacles once, for the body check and the least clearance.
    shapes = np.concatenate(bodies) if bodies else np.empty(0, dtype=object)
    polygons = [shapely.Polygon(o.corners()) for o in m.obstacles]
    first_collision, collides_with = verify_bodies.first_collision(
        s, region, shapes, polygons, poses, row_on_map
    )
    collision_free = first_collision is None
    # Chords of the first and last moving steps, turned to the tangent at their ends.
    if math.isnan(first_dir):
        # A path that never moves (the start is the goal): the car keeps its heading, so
        # every row's yaw must be the start's and the goal's.
        yaws = s[:, 2]
        err_s = float(np.max(np.abs(wrap_angle(yaws - start.yaw))))
        err_g = float(np.max(np.abs(wrap_angle(yaws - goal.yaw))))
    else:
        err_s = abs(wrap_angle(first_dir - start.yaw))
        err_g = abs(wrap_angle(last_dir - goal.yaw))
    end_err = max(math.hypot(xy[0, 0] - start.x, xy[0, 1] - start.y),
                  math.hypot(xy[-1, 0] - goal.x, xy[-1, 1] - goal.y))  # fmt: skip
    end_yaw_err = max(abs(wrap_angle(s[0, 2] - start.yaw)), abs(wrap_angle(s[-1, 2] - goal.yaw)))
    # Each coordinate to 1e-6 m, as the JSON's 6 decimals keep them.
    endpoints_ok = bool(
        np.allclose(xy[0], (start.x, start.y), rtol=0.0, atol=1e-6)
        and np.allclose(xy[-1], (goal.x, goal.y), rtol=0.0, atol=1e-6)
        and end_yaw_err <= YAW_ROUND
    )
    least = 0.0
    if collision_free:
        least = verify_bodies.least_clearance(
            m, shapes, polygons, verify_bodies.body_corners(shapes)
        ) if len(shapes) else math.inf
    # Contact is no clearance, whatever was asked (a path 0.7 m out of the bounds read "ok
    # clearance ... 0.0000 m (min 0)"; a student's find).
    clearance_ok = collision_free and least >= clearance - 1e-9
    curvature_ok = max_k <= v.kappa_max + curvature_tol
    tol = math.radians(heading_tol_deg)
    headings_ok = max(err_s, err_g) <= tol
    travel_ok = travel_err <= math.radians(travel_tol_deg)
    spacing_ok = float(gaps.max()) <= max_sample_spacing + 1e-6
    sharpness_ok = max_sharpness is None or max_sharp <= max_sharpness + sharpness_tol
    kappa_ok = kappa_err <= kappa_tol
    return PathCheck(
        ok=all((collision_free, curvature_ok, sharpness_ok, headings_ok, endpoints_ok,
                spacing_ok, travel_ok, cusps_ok, clearance_ok, kappa_ok)),
        collision_free=collision_free,
        curvature_ok=curvature_ok,
        headings_ok=headings_ok,
        endpoints_ok=endpoints_ok,
        spacing_ok=spacing_ok,
        max_discrete_curvature=max_k,
        start_heading_err_deg=math.degrees(err_s),
        goal_heading_err_deg=math.degrees(err_g),
        max_spacing_m=float(gaps.max()),
        cusps_ok=cusps_ok,
        cusps=len(cusps),
        travel_ok=travel_ok,
        travel_heading_err_deg=math.degrees(travel_err),
        max_discrete_sharpness=max_sharp,
        sharpness_ok=sharpness_ok,
        first_collision=first_collision,
        collides_with=collides_with,
        endpoint_err_m=end_err,
        endpoint_yaw_err_deg=math.degrees(end_yaw_err),
        cusp_gap_m=float(cusp_gaps.max()) if len(cusps) else 0.0,
        cusp_yaw_err_deg=math.degrees(float(cusp_turns.max())) if len(cusps) else 0.0,
        first_bad_cusp_row=int(cusps[np.argmax(bad_cusps)]) if not cusps_ok else None,
        min_clearance_m=least,
        clearance_ok=clearance_ok,
        kappa_ok=kappa_ok,
        kappa_column_err=kappa_err,
        worst_kappa_row=None if kappa_ok else kappa_row,
    )


def path_from_json(data: Mapping[str, object] | Sequence[Sequence[float]]) -> Path:
    """The :class:`Path` of a ``rrtdrive plan`` JSON object, or of its list of rows.

    Rows with 4 numbers (``[x, y, yaw, kappa]``, JSON written before gears) are
    forward rows; rows with 5 carry their gear; rows with 3 (``[x, y, yaw]``, another
    planner's poses) get their gears, cusps and ``kappa`` from the motion
    (:func:`rrtdrive.pose_rows.path_from_poses`).

    Parameters
    ----------
    data : dict or list
        The parsed plan JSON (its ``"path"`` and ``"waypoints"``) or the rows alone.

    Returns
    -------
    Path

    Raises
    ------
    InputError
        Naming ``path`` (and the row) when the rows are not all 3, all 4 or all 5 finite
        numbers or a gear is not the number +1 or -1, and ``waypoints`` when those
        are not pairs of finite numbers.

    Examples
    --------
    >>> path_from_json({"path": [[0, 0, 0, 0], [0.25, 0, 0, 0]], "waypoints": []}).gears.tolist()
    [1, 1]
    >>> path_from_json([[0, 0, 0, 0, -1], [-0.25, 0, 0, 0, -1]]).is_forward_only
    False
    >>> path_from_json([[0, 0, 0, 0, 1], [0.25, float("nan"), 0, 0, 1]])
    Traceback (most recent call last):
    ...
    rrtdrive.types.InputError: path: row 1 y must be a finite number, got nan
    """
    if isinstance(data, Mapping):
        rows, waypoints = data.get("path"), data.get("waypoints") or []
    else:
        rows, waypoints = data, []
    if not isinstance(rows, Sequence) or isinstance(rows, str):
        raise InputError(f"path: expected a list of rows, got {type(rows).__name__}")
    for i, row in enumerate(rows):
        if not _is_list(row):
            raise InputError(
                f"path: row {i} must be a list [x, y, yaw, kappa, gear], got {brief_repr(row)}"
            )
    widths = {len(r) for r in rows}
    if widths - {3, 4, 5} or len(widths) > 1:
        # Name the first row that is odd: of a bad width, else of a width other than row 0's.
        width = len(rows[0]) if len(rows[0]) in (3, 4, 5) else None
        i = next(k for k, r in enumerate(rows) if len(r) != width)
        raise InputError(
            f"path: rows must all be [x, y, yaw], [x, y, yaw, kappa] or "
            f"[x, y, yaw, kappa, gear], "
            f"got row lengths {sorted(widths)}: row {i} has {len(rows[i])} "
            + ("number" if len(rows[i]) == 1 else "numbers")
        )
    # Checked here, row by row: NaN or inf would reach shapely as a broken polygon,
    # and numpy would read "1" or true as a gear.
    for i, row in enumerate(rows):
        for name, value in zip(_COLUMNS, row[:4], strict=False):
            if not is_finite_number(value):
                raise InputError(
                    f"path: row {i} {name} must be a finite number, got {brief_repr(value)}"
                )
        if len(row) == 5 and not (is_finite_number(row[4]) and row[4] in (1, -1)):
            raise InputError(
                f"path.gear: must be +1 (forward) or -1 (reverse), got {brief_repr(row[4])} "
                f"in row {i}"
            )
    width = widths.pop() if rows else 5
    samples = np.array(rows, dtype=float).reshape(len(rows), width)
    if not _is_list(waypoints) or not all(
        _is_list(w) and len(w) == 2 and all(is_finite_number(v) for v in w) for w in waypoints
    ):
        raise InputError(
            f"waypoints: expected a list of [x, y] finite numbers, got {brief_repr(waypoints)}"
        )
    points = np.array(waypoints, dtype=float).reshape(-1, 2)
    if width == 3:
        from rrtdrive.pose_rows import path_from_poses

        return Path(path_from_poses(samples).samples, points)
    return Path(samples, points)


_COLUMNS = ("x", "y", "yaw", "kappa")


def _is_list(value: object) -> TypeGuard[Sequence[Any] | np.ndarray]:
    """A JSON array (a list or tuple, not a string) or a numpy array."""
    return isinstance(value, (Sequence, np.ndarray)) and not isinstance(value, (str, bytes))
