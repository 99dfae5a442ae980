"""Evaluators: every metric of SPEC §4 from an episode's path, trajectory and map.

:func:`evaluate` reads an :class:`~rrtdrive.sim.runner.Episode` (plain data) and
returns an :class:`EpisodeReport`; :func:`summarise` aggregates reports over
seeds. The definitions are in ``docs/metrics.md``. This module does not import
highway-env: the simulator's own collision flag was logged by the runner.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
import shapely

from rrtdrive.types import InputError, Path, require_positive, wrap_angle
from rrtdrive.vehicle import footprint_corners

if TYPE_CHECKING:  # pragma: no cover
    from rrtdrive.sim.episode import Episode

__all__ = [
    "EvalConfig",
    "EpisodeReport",
    "evaluate",
    "summarise",
    "tracking_errors",
    "densify_poses",
    "time_to_collision",
    "vehicle_collisions",
    "min_vehicle_distance",
    "overtake_complete",
    "OUTCOMES",
]

#: nuPlan's ``time_to_collision_within_bound``: horizon and step of the constant-velocity
#: projection (s), ego speed below which TTC is not computed (m/s), and the bound (s).
TTC_HORIZON_S = 3.0
TTC_STEP_S = 0.1
TTC_STOPPED_SPEED = 5e-3
TTC_LEAST_MIN_S = 0.95
#: nuPlan's speed below which a car counts as stopped in a collision (m/s).
COLLISION_STOPPED_SPEED = 5e-2
#: Episode outcomes: ``safe_following`` is an ``overtake-traffic`` episode that ran out of
#: time behind the lead car without a collision (counted apart from failures).
OUTCOMES = ("success", "collision", "safe_following", "failed")


@dataclass(frozen=True)
class EvalConfig:
    """Thresholds of the evaluators.

    Parameters
    ----------
    goal_tol_m : float
        Largest rear-axle distance to the goal pose for success (SPEC: 0.5 m).
    goal_tol_rad : float
        Largest heading error at the goal for success (SPEC: 10°).
    stop_speed : float
        The car counts as stopped below this speed (m/s).
    footprint_spacing : float
        The exact footprint judge checks poses at most this far apart (metres).
    kappa_tol : float
        Relative tolerance of the executed-curvature limit check.
    """

    goal_tol_m: float = 0.5
    goal_tol_rad: float = math.radians(10.0)
    stop_speed: float = 0.1
    footprint_spacing: float = 0.1
    kappa_tol: float = 1e-9

    def __post_init__(self) -> None:
        for name in ("goal_tol_m", "goal_tol_rad", "stop_speed", "footprint_spacing"):
            require_positive(f"eval.{name}", getattr(self, name))
        if not (self.kappa_tol >= 0 and math.isfinite(self.kappa_tol)):
            raise InputError(f"eval.kappa_tol: must be >= 0, got {self.kappa_tol!r}")


@dataclass(frozen=True)
class EpisodeReport:
    """All metrics of one episode (see ``docs/metrics.md`` for each definition).

    ``None`` marks a metric that does not apply (for example tracking errors of an
    episode whose planning failed).
    """

    scenario: str
    planner: str
    controller: str
    seed: int
    status: str
    message: str
    success: bool
    collision: bool
    collision_highway_env: bool
    collision_footprint: bool
    reached_goal: bool
    stopped: bool
    passed_lead: bool | None
    back_in_lane: bool | None
    cte_rms_m: float | None
    cte_max_m: float | None
    heading_err_rms_rad: float | None
    heading_err_max_rad: float | None
    path_max_curvature: float | None
    kappa_max: float
    path_length_m: float | None
    executed_max_curvature: float | None
    executed_curvature_violation_share: float | None
    max_lateral_accel: float | None
    max_long_accel: float | None
    max_jerk: float | None
    max_steering_rate: float | None
    goal_position_err_m: float | None
    goal_heading_err_rad: float | None
    final_speed: float | None
    time_to_goal_s: float | None
    duration_s: float
    steps: int
    wall_time_s: float
    planning_time_s: float | None
    simulation_frequency: float
    outcome: str = "failed"
    completion_time_s: float | None = None
    progress_m: float | None = None
    ttc_min_s: float | None = None
    ttc_within_bound: bool | None = None
    min_distance_m: float | None = None
    collisions_vehicles: int = 0
    collisions_at_fault: int = 0
    replans: int | None = None
    replan_time_median_s: float | None = None
    replan_time_max_s: float | None = None
    replan_budget_s: float | None = None
    replans_over_budget: int | None = None
    unsafe_steps: int | None = None

    def to_json(self) -> dict[str, Any]:
        """A JSON-ready dict (floats rounded to 6 significant digits, NaN as ``None``)."""
        out: dict[str, Any] = {}
        for k, v in asdict(self).items():
            if isinstance(v, float):
                v = None if not math.isfinite(v) else float(f"{v:.6g}")
            out[k] = v
        return out


def densify_poses(poses: np.ndarray, spacing: float) -> np.ndarray:
    """Linear interpolation of ``(N, 3)`` poses so consecutive ones are at most ``spacing`` apart.

    Examples
    --------
    >>> densify_poses(np.array([[0.0, 0, 0], [1.0, 0, 0]]), 0.25).shape
    (5, 3)
    """
    p = np.asarray(poses, dtype=float).reshape(-1, 3)
    if len(p) < 2:
        return p
    step = np.hypot(*np.diff(p[:, :2], axis=0).T)
    pieces = np.maximum(1, np.ceil(step / spacing - 1e-9).astype(np.int64))
    owner = np.repeat(np.arange(len(step)), pieces)
    first = np.repeat(np.cumsum(pieces) - pieces, pieces)
    frac = (np.arange(len(owner)) - first) / np.repeat(pieces, pieces)
    a, b = p[owner], p[owner + 1]
    dyaw = wrap_angle(b[:, 2] - a[:, 2])
    out = np.column_stack([a[:, :2] + frac[:, None] * (b[:, :2] - a[:, :2]), a[:, 2] + frac * dyaw])
    return np.vstack([out, p[-1:]])


def tracking_errors(
    path: Path, poses: np.ndarray, chunk: int = 256
) -> tuple[np.ndarray, np.ndarray]:
    """Signed cross-track and heading errors of rear-axle poses against a path.

    The cross-track error is the distance from the rear axle to the nearest point
    of the path polyline, signed positive when the car is to the left of the
    path; the heading error is the car's yaw minus the path's heading at that
    point, wrapped to [-pi, pi).

    Parameters
    ----------
    path : Path
        At least two samples.
    poses : numpy.ndarray
        ``(N, 3)`` rear-axle poses.
    chunk : int
        Poses per vectorised block.

    Returns
    -------
    cte, heading_err : numpy.ndarray
        Shape ``(N,)`` each.

    Examples
    --------
    >>> xs = np.linspace(0.0, 10.0, 11)
    >>> p = Path(np.column_stack([xs, 0 * xs, 0 * xs, 0 * xs]), np.zeros((0, 2)))
    >>> cte, he = tracking_errors(p, np.array([[2.5, -0.3, 0.1]]))
    >>> round(float(cte[0]), 6), round(float(he[0]), 6)
    (-0.3, 0.1)
    """
    s = np.asarray(path.samples, dtype=float)
    keep = np.concatenate([[True], np.hypot(*np.diff(s[:, :2], axis=0).T) > 1e-9])
    s = s[keep]
    if len(s) < 2:
        raise InputError("path: need at least two distinct samples to measure tracking errors")
    a = s[:-1, :2]
    d = np.diff(s[:, :2], axis=0)
    seg_len2 = np.einsum("ij,ij->i", d, d)
    yaw = np.unwrap(s[:, 2])
    p = np.asarray(poses, dtype=float).reshape(-1, 3)
    cte = np.empty(len(p))
    herr = np.empty(len(p))
    for lo in range(0, len(p), chunk):
        q = p[lo : lo + chunk, :2]
        rel = q[:, None, :] - a[None, :, :]
        t = np.clip(np.einsum("nmj,mj->nm", rel, d) / seg_len2[None, :], 0.0, 1.0)
        foot = a[None, :, :] + t[..., None] * d[None, :, :]
        dist2 = np.sum((q[:, None, :] - foot) ** 2, axis=-1)
        j = np.argmin(dist2, axis=1)
        rows = np.arange(len(q))
        off = q - foot[rows, j]
        cross = d[j, 0] * off[:, 1] - d[j, 1] * off[:, 0]
        dist = np.sqrt(dist2[rows, j])
        cte[lo : lo + len(q)] = np.where(cross < 0, -dist, dist)
        tj = t[rows, j]
        path_yaw = yaw[j] + tj * (yaw[j + 1] - yaw[j])
        herr[lo : lo + len(q)] = wrap_angle(p[lo : lo + len(q), 2] - path_yaw)
    return cte, herr


def _map_collision(episode: Episode, spacing: float) -> bool:
    """Exact body rectangle of every (densified) logged pose against the map and its bounds."""
    from rrtdrive.planning.base import cached_checker

    states = episode.log.states
    if len(states) == 0:
        return False
    dense = densify_poses(states[:, :3], spacing)
    return not bool(np.all(cached_checker(episode.scenario.map).poses_free(dense)))


def _footprint_collisions(episode: Episode, spacing: float, map_hit: bool | None = None) -> bool:
    """Exact body rectangle of every (densified) logged pose against the map and other cars."""
    m = episode.scenario.map
    states = episode.log.states
    if len(states) == 0:
        return False
    if map_hit is None:
        map_hit = _map_collision(episode, spacing)
    if map_hit:
        return True
    others = episode.log.others
    if others.size == 0:
        return False
    # Moving vehicles: compare at the logged times (their poses are body centres).
    vehicle = m.vehicle
    ego_polys = shapely.polygons(footprint_corners(states[:, :3], vehicle))
    for k, (length, width) in enumerate(episode.log.other_sizes):
        o = others[:, k, :]
        c, s_ = np.cos(o[:, 2]), np.sin(o[:, 2])
        hl, hw = length / 2.0, width / 2.0
        local = np.array([[-hl, -hw], [hl, -hw], [hl, hw], [-hl, hw]])
        x = o[:, None, 0] + c[:, None] * local[None, :, 0] - s_[:, None] * local[None, :, 1]
        y = o[:, None, 1] + s_[:, None] * local[None, :, 0] + c[:, None] * local[None, :, 1]
        polys = shapely.polygons(np.stack([x, y], axis=-1))
        if bool(np.any(shapely.intersects(ego_polys, polys))):
            return True
    return False


def overtake_complete(
    ego_rear: Sequence[float],
    lead_centre: Sequence[float],
    lead_length: float,
    lane_y: float,
    lane_width: float,
    vehicle: Any,
    gap: float,
) -> bool:
    """Back in the ego lane (all body corners), aligned within 10°, ``gap`` ahead of the lead.

    The completion test of ``overtake-traffic``: every corner of the ego's body lies
    within the ego lane, its heading is within 10° of the lane's, and its rear
    bumper is at least ``gap`` metres beyond the lead car's front bumper.

    Examples
    --------
    >>> from rrtdrive.types import VehicleParams
    >>> overtake_complete((30.0, 44.0, 0.0), (20.0, 44.0), 4.3, 44.0, 4.0, VehicleParams(), 2.0)
    True
    """
    corners = footprint_corners(np.asarray(ego_rear, dtype=float)[:3], vehicle)
    in_lane = bool(np.all(np.abs(corners[:, 1] - lane_y) <= lane_width / 2.0))
    aligned = abs(math.remainder(float(ego_rear[2]), 2.0 * math.pi)) <= math.radians(10.0)
    ahead = corners[:, 0].min() >= float(lead_centre[0]) + lead_length / 2.0 + gap
    return in_lane and aligned and bool(ahead)


def _box_corners(cx: np.ndarray, cy: np.ndarray, h: np.ndarray, length: np.ndarray,
                 width: np.ndarray) -> np.ndarray:
    """Corners ``(..., 4, 2)`` of centred oriented boxes.

    In nuPlan's ``OrientedBox`` order: front-left, rear-left, rear-right, front-right.
    """
    c, s = np.cos(h), np.sin(h)
    hl, hw = length / 2.0, width / 2.0
    lx = np.stack([hl, -hl, -hl, hl], axis=-1) * np.ones_like(cx)[..., None]
    ly = np.stack([hw, hw, -hw, -hw], axis=-1) * np.ones_like(cx)[..., None]
    x = cx[..., None] + c[..., None] * lx - s[..., None] * ly
    y = cy[..., None] + s[..., None] * lx + c[..., None] * ly
    return np.stack([x, y], axis=-1)


def _boxes_intersect(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Separating-axis test of convex quadrilaterals ``(..., 4, 2)``; touching counts."""
    out = np.ones(a.shape[:-2], dtype=bool)
    for poly in (a, b):
        for i in range(2):
            edge = poly[..., i + 1, :] - poly[..., i, :]
            axis = np.stack([-edge[..., 1], edge[..., 0]], axis=-1)[..., None, :]
            pa = np.sum(a * axis, axis=-1)
            pb = np.sum(b * axis, axis=-1)
            out &= (pa.max(axis=-1) >= pb.min(axis=-1)) & (pb.max(axis=-1) >= pa.min(axis=-1))
    return out


def _ego_centres(states: np.ndarray, vehicle: Any) -> tuple[np.ndarray, np.ndarray]:
    d = vehicle.length / 2.0 - vehicle.rear_overhang
    return (
        states[:, 0] + d * np.cos(states[:, 2]),
        states[:, 1] + d * np.sin(states[:, 2]),
    )


def _relative_angles(states: np.ndarray, others: np.ndarray) -> np.ndarray:
    """Angle between the ego heading and the rear axle -> agent centre vector, ``(N, K)``.

    nuPlan's ``get_agent_relative_angle``.
    """
    dx = others[..., 0] - states[:, None, 0]
    dy = others[..., 1] - states[:, None, 1]
    norm = np.maximum(np.hypot(dx, dy), 1e-12)
    dot = (np.cos(states[:, 2])[:, None] * dx + np.sin(states[:, 2])[:, None] * dy) / norm
    return np.arccos(np.clip(dot, -1.0, 1.0))


def _between_lanes(episode: Episode) -> np.ndarray:
    """Per logged time: the ego body is in more than one lane or off the road (road scenarios)."""
    scen = episode.scenario
    states = episode.log.states
    if scen.lane_y is None:
        return np.zeros(len(states), dtype=bool)
    corners = footprint_corners(states[:, :3], scen.vehicle)[..., 1]
    w = scen.lane_width
    low, mid, high = scen.lane_y - w / 2.0, scen.lane_y + w / 2.0, scen.lane_y + 1.5 * w
    straddles = (corners.min(axis=1) < mid) & (corners.max(axis=1) > mid)
    off = (corners.min(axis=1) < low) | (corners.max(axis=1) > high)
    return straddles | off


def vehicle_collisions(episode: Episode) -> list[tuple[int, int, str, bool]]:
    """Collisions with other vehicles, classified as nuPlan's ``no_ego_at_fault_collisions``.

    A collision is the first logged time at which the ego's body rectangle
    intersects another vehicle's (each vehicle counts once). Its type: the ego
    stopped (speed <= 0.05 m/s: not at fault); the other vehicle stopped (at
    fault); the other vehicle's centre behind the ego (more than 150° off the ego
    heading seen from the rear axle: a rear collision, not at fault); the ego's
    front bumper touches it (a front collision, at fault); else lateral, at fault
    when the ego is in more than one lane or off the road.

    Returns
    -------
    list of (int, int, str, bool)
        ``(step, vehicle index, type, at_fault)`` with type ``"stopped_ego"``,
        ``"stopped_track"``, ``"active_rear"``, ``"active_front"`` or ``"active_lateral"``.
    """
    log = episode.log
    others = log.others
    states = log.states
    if others.size == 0 or len(states) == 0:
        return []
    vehicle = episode.scenario.vehicle
    ex, ey = _ego_centres(states, vehicle)
    n, k = others.shape[:2]
    ego_box = _box_corners(
        ex, ey, states[:, 2], np.full(n, vehicle.length), np.full(n, vehicle.width)
    )
    sizes = log.other_sizes
    boxes = _box_corners(
        others[..., 0], others[..., 1], others[..., 2],
        np.broadcast_to(sizes[:, 0], (n, k)), np.broadcast_to(sizes[:, 1], (n, k)),
    )
    hit = _boxes_intersect(np.broadcast_to(ego_box[:, None], boxes.shape), boxes)
    if not hit.any():
        return []
    angles = _relative_angles(states, others)
    between = _between_lanes(episode)
    out = []
    for j in np.flatnonzero(hit.any(axis=0)).tolist():
        i = int(np.argmax(hit[:, j]))
        if abs(states[i, 3]) <= COLLISION_STOPPED_SPEED:
            kind, fault = "stopped_ego", False
        elif abs(others[i, j, 3]) <= COLLISION_STOPPED_SPEED:
            kind, fault = "stopped_track", True
        elif angles[i, j] > math.radians(150.0):
            kind, fault = "active_rear", False
        elif bool(
            shapely.intersects(
                shapely.linestrings(ego_box[i, [0, 3]]), shapely.polygons(boxes[i, j])
            )
        ):
            kind, fault = "active_front", True
        else:
            kind, fault = "active_lateral", bool(between[i])
        out.append((i, j, kind, fault))
    return out


def time_to_collision(
    episode: Episode,
    at_fault_steps: Sequence[int] = (),
    horizon: float = TTC_HORIZON_S,
    step: float = TTC_STEP_S,
) -> np.ndarray:
    """Time to collision at every logged time, as nuPlan defines it (``inf`` when none).

    At each logged time the ego (body centre, its heading and speed) and the other
    vehicles (their headings and speeds) are projected at constant velocity at
    ``step``, ``2 step``, ... below ``horizon`` (``np.arange(step, horizon, step)``,
    as nuPlan's ``time_to_collision_within_bound``); the TTC is the first projected
    time at which the ego's box intersects one of theirs. Only vehicles ahead of the
    ego (within 30° of its heading from the rear axle) count, plus, while the ego
    is in more than one lane or off the road, every vehicle not behind it (more
    than 150° off); vehicles it already collided with are left out. While the ego
    is stopped (speed <= 5e-3 m/s) the TTC is ``inf``; at an at-fault collision it is 0.

    Parameters
    ----------
    episode : Episode
        A driven episode.
    at_fault_steps : sequence of int
        Logged times of at-fault collisions (:func:`vehicle_collisions`).
    horizon, step : float
        nuPlan: 3 s and 0.1 s.

    Returns
    -------
    numpy.ndarray
        ``(N + 1,)`` seconds.
    """
    log = episode.log
    states = log.states
    n = len(states)
    ttc = np.full(n, np.inf)
    others = log.others
    if n == 0 or others.size == 0:
        return ttc
    vehicle = episode.scenario.vehicle
    k = others.shape[1]
    ex, ey = _ego_centres(states, vehicle)
    v = states[:, 3]
    angles = _relative_angles(states, others)
    between = _between_lanes(episode)
    collided_before = np.zeros((n, k), dtype=bool)
    for i, j, _kind, _fault in vehicle_collisions(episode):
        collided_before[i + 1 :, j] = True
    considered = (angles < math.radians(30.0)) | (
        between[:, None] & ~(angles > math.radians(150.0))
    )
    times = np.arange(step, horizon, step)
    sizes = log.other_sizes
    reach = (np.abs(v)[:, None] + np.abs(others[..., 3])) * times[-1] + 0.5 * (
        math.hypot(vehicle.length, vehicle.width) + np.hypot(sizes[:, 0], sizes[:, 1])[None, :]
    )
    dist = np.hypot(others[..., 0] - ex[:, None], others[..., 1] - ey[:, None])
    moving = np.abs(v)[:, None] > TTC_STOPPED_SPEED
    cand = considered & ~collided_before & moving & (dist <= reach)
    ii, jj = np.nonzero(cand)
    if len(ii):
        t = times[None, :]
        h = states[ii, 2][:, None]
        e_box = _box_corners(
            ex[ii][:, None] + v[ii][:, None] * np.cos(h) * t,
            ey[ii][:, None] + v[ii][:, None] * np.sin(h) * t,
            np.broadcast_to(h, (len(ii), len(times))),
            np.full((len(ii), len(times)), vehicle.length),
            np.full((len(ii), len(times)), vehicle.width),
        )
        o = others[ii, jj]
        oh = o[:, 2][:, None]
        o_box = _box_corners(
            o[:, 0][:, None] + o[:, 3][:, None] * np.cos(oh) * t,
            o[:, 1][:, None] + o[:, 3][:, None] * np.sin(oh) * t,
            np.broadcast_to(oh, (len(ii), len(times))),
            np.broadcast_to(sizes[jj, 0][:, None], (len(ii), len(times))),
            np.broadcast_to(sizes[jj, 1][:, None], (len(ii), len(times))),
        )
        hit = _boxes_intersect(e_box, o_box)
        first = np.where(hit.any(axis=1), times[np.argmax(hit, axis=1)], np.inf)
        np.minimum.at(ttc, ii, first)
    ttc[np.asarray(list(at_fault_steps), dtype=np.int64)] = 0.0
    return ttc


def min_vehicle_distance(episode: Episode) -> float | None:
    """Smallest distance between the ego's body and another vehicle's over the episode (m).

    Exact (shapely) on the logged poses; 0 when they overlap; ``None`` without other vehicles.
    """
    log = episode.log
    others, states = log.others, log.states
    if others.size == 0 or len(states) == 0:
        return None
    vehicle = episode.scenario.vehicle
    ex, ey = _ego_centres(states, vehicle)
    n, k = others.shape[:2]
    sizes = log.other_sizes
    centre = np.hypot(others[..., 0] - ex[:, None], others[..., 1] - ey[:, None])
    half_diag = 0.5 * (
        math.hypot(vehicle.length, vehicle.width) + np.hypot(sizes[:, 0], sizes[:, 1])
    )
    lower = centre - half_diag[None, :]
    # Only pairs that could beat the best upper bound (their centre distance) matter.
    ii, jj = np.nonzero(lower <= centre.min())
    ego = shapely.polygons(
        _box_corners(ex[ii], ey[ii], states[ii, 2], np.full(len(ii), vehicle.length),
                     np.full(len(ii), vehicle.width))
    )
    oth = shapely.polygons(
        _box_corners(others[ii, jj, 0], others[ii, jj, 1], others[ii, jj, 2], sizes[jj, 0],
                     sizes[jj, 1])
    )
    return float(np.min(shapely.distance(ego, oth)))


def _project_s(path: Path, points: np.ndarray) -> np.ndarray:
    """Arc length of the nearest point of the path polyline to each point."""
    s = np.asarray(path.samples, dtype=float)
    keep = np.concatenate([[True], np.hypot(*np.diff(s[:, :2], axis=0).T) > 1e-9])
    xy = s[keep, :2]
    arc = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(xy, axis=0).T))])
    a, d = xy[:-1], np.diff(xy, axis=0)
    len2 = np.einsum("ij,ij->i", d, d)
    out = []
    for q in np.asarray(points, dtype=float).reshape(-1, 2):
        t = np.clip(np.einsum("ij,ij->i", q - a, d) / len2, 0.0, 1.0)
        foot = a + t[:, None] * d
        j = int(np.argmin(np.sum((q - foot) ** 2, axis=1)))
        out.append(arc[j] + t[j] * math.sqrt(len2[j]))
    return np.array(out)


def evaluate(episode: Episode, config: EvalConfig | None = None) -> EpisodeReport:
    """Score one episode.

    Parameters
    ----------
    episode : Episode
        From :func:`rrtdrive.sim.runner.run_episode`.
    config : EvalConfig, optional
        Thresholds.

    Returns
    -------
    EpisodeReport

    Examples
    --------
    >>> report = evaluate(run_episode("parking", seed=0))  # doctest: +SKIP
    >>> report.success, report.cte_rms_m  # doctest: +SKIP
    (True, 0.02)
    """
    cfg = config or EvalConfig()
    scen = episode.scenario
    vehicle = scen.vehicle
    log = episode.log
    path = episode.path
    plan_time = episode.plan.planning_time_s if episode.plan is not None else None
    base: dict[str, Any] = {
        "scenario": scen.name,
        "planner": episode.planner,
        "controller": episode.controller,
        "seed": episode.seed,
        "status": episode.status,
        "message": episode.message,
        "kappa_max": vehicle.kappa_max,
        "planning_time_s": plan_time,
        "simulation_frequency": 1.0 / log.dt,
        "wall_time_s": log.wall_time_s,
        "steps": log.steps,
        "duration_s": float(log.t[-1]) if len(log.t) else 0.0,
        "path_max_curvature": path.max_curvature if len(path) else None,
        "path_length_m": path.length if len(path) else None,
    }
    if log.steps == 0:
        none = dict.fromkeys(
            (
                "passed_lead", "back_in_lane", "cte_rms_m", "cte_max_m", "heading_err_rms_rad",
                "heading_err_max_rad", "executed_max_curvature",
                "executed_curvature_violation_share", "max_lateral_accel", "max_long_accel",
                "max_jerk", "max_steering_rate", "goal_position_err_m", "goal_heading_err_rad",
                "final_speed", "time_to_goal_s",
            )
        )
        return EpisodeReport(
            **base, **none, success=False, collision=False, collision_highway_env=False,
            collision_footprint=False, reached_goal=False, stopped=False,
            **_replan_stats(episode),
        )
    states = log.states
    dt = log.dt
    cte, herr = tracking_errors(path, states[:, :3])
    speed = states[:, 3]
    accel = log.controls[:, 0]
    steer = log.controls[:, 1]
    kappa_exec = np.tan(steer) / vehicle.wheelbase
    v_step = speed[:-1]
    lat = v_step**2 * kappa_exec
    steer_prev = np.concatenate([[0.0], steer[:-1]])
    steer_rate = np.abs(steer - steer_prev) / dt
    if len(accel) > 1:
        jerk = np.hypot(np.diff(accel), np.diff(lat)) / dt
        max_jerk = float(np.max(jerk))
    else:
        max_jerk = 0.0
    final = states[-1]
    goal = scen.goal
    pos_err = math.hypot(final[0] - goal.x, final[1] - goal.y)
    head_err = abs(float(wrap_angle(final[2] - goal.yaw)))
    stopped = abs(final[3]) <= cfg.stop_speed
    reached = pos_err <= cfg.goal_tol_m and head_err <= cfg.goal_tol_rad
    hw_crash = bool(np.any(log.crashed))
    map_hit = _map_collision(episode, cfg.footprint_spacing)
    fp_crash = _footprint_collisions(episode, cfg.footprint_spacing, map_hit)
    passed_lead = back_in_lane = None
    extra_ok = True
    pos_err_out: float | None = pos_err
    head_err_out: float | None = head_err
    in_time = episode.status == "arrived"
    if scen.is_traffic:
        # Success is the overtake itself: back in the lane, aligned, ahead of the moving lead.
        lead, (lead_len, _w) = log.others[-1, 0], log.other_sizes[0]
        body = footprint_corners(final[:3], vehicle)
        passed_lead = bool(body[:, 0].min() > lead[0] + lead_len / 2.0)
        back_in_lane = bool(np.all(np.abs(body[:, 1] - scen.lane_y) <= scen.lane_width / 2.0))
        gap = episode.traffic.config.complete_gap_m if episode.traffic is not None else 0.0
        reached = overtake_complete(
            final[:3], lead[:2], lead_len, scen.lane_y, scen.lane_width, vehicle, gap
        )
        stopped = True  # an overtake ends on the move
        in_time = episode.status == "completed"
        pos_err_out = head_err_out = None
    elif scen.lead_index is not None and scen.lane_y is not None:
        lead = scen.map.obstacles[scen.lead_index]
        body = footprint_corners(final[:3], vehicle)
        passed_lead = bool(body[:, 0].min() > lead.corners()[:, 0].max())
        half = scen.lane_width / 2.0
        back_in_lane = bool(
            np.all(np.abs(body[:, 1] - scen.lane_y) <= half)
        )
        extra_ok = passed_lead and back_in_lane
    success = bool(
        reached and stopped and in_time and not hw_crash and not fp_crash and extra_ok
    )
    over = np.abs(kappa_exec) > vehicle.kappa_max * (1.0 + cfg.kappa_tol)
    crashes = vehicle_collisions(episode)
    at_fault = [c for c in crashes if c[3]]
    ttc_within = ttc_min = min_dist = None
    if log.others.size:
        ttc = time_to_collision(episode, [c[0] for c in at_fault])
        finite = ttc[np.isfinite(ttc)]
        ttc_min = float(finite.min()) if len(finite) else None
        ttc_within = bool(np.all(ttc > TTC_LEAST_MIN_S))
        min_dist = min_vehicle_distance(episode)
    progress = None
    if len(path) >= 2:
        s_ends = _project_s(path, states[[0, -1], :2])
        progress = float(s_ends[1] - s_ends[0])
    collision = hw_crash or fp_crash
    if success:
        outcome = "success"
    elif collision:
        outcome = "collision"
    elif scen.is_traffic and episode.status == "timeout":
        outcome = "safe_following"
    else:
        outcome = "failed"
    return EpisodeReport(
        **base,
        success=success,
        collision=collision,
        collision_highway_env=hw_crash,
        collision_footprint=fp_crash,
        reached_goal=bool(reached),
        stopped=bool(stopped),
        passed_lead=passed_lead,
        back_in_lane=back_in_lane,
        cte_rms_m=float(np.sqrt(np.mean(cte**2))),
        cte_max_m=float(np.max(np.abs(cte))),
        heading_err_rms_rad=float(np.sqrt(np.mean(herr**2))),
        heading_err_max_rad=float(np.max(np.abs(herr))),
        executed_max_curvature=float(np.max(np.abs(kappa_exec))),
        executed_curvature_violation_share=float(np.mean(over)),
        max_lateral_accel=float(np.max(np.abs(lat))),
        max_long_accel=float(np.max(np.abs(accel))),
        max_jerk=max_jerk,
        max_steering_rate=float(np.max(steer_rate)),
        goal_position_err_m=pos_err_out,
        goal_heading_err_rad=head_err_out,
        final_speed=float(final[3]),
        time_to_goal_s=float(log.t[-1]) if success else None,
        outcome=outcome,
        completion_time_s=float(log.t[-1]) if success else None,
        progress_m=progress,
        ttc_min_s=ttc_min,
        ttc_within_bound=ttc_within,
        min_distance_m=min_dist,
        collisions_vehicles=len(crashes),
        collisions_at_fault=len(at_fault) + int(map_hit),
        **_replan_stats(episode),
    )


def _replan_stats(episode: Episode) -> dict[str, Any]:
    """Re-planning cycle statistics of an ``overtake-traffic`` episode (else ``None``)."""
    traffic = getattr(episode, "traffic", None)
    keys = (
        "replans", "replan_time_median_s", "replan_time_max_s", "replan_budget_s",
        "replans_over_budget", "unsafe_steps",
    )
    if traffic is None:
        return dict.fromkeys(keys)
    times = traffic.cycle_times()
    budget = traffic.config.cycle_budget_s
    return {
        "replans": len(times),
        "replan_time_median_s": float(np.median(times)) if len(times) else None,
        "replan_time_max_s": float(np.max(times)) if len(times) else None,
        "replan_budget_s": budget,
        "replans_over_budget": int(np.sum(times > budget)),
        "unsafe_steps": traffic.unsafe_steps,
    }


def summarise(reports: Sequence[EpisodeReport]) -> dict[str, Any]:
    """Aggregate reports: success and collision rates, means and maxima of the errors.

    Parameters
    ----------
    reports : sequence of EpisodeReport
        One per seed (same scenario and controller).

    Returns
    -------
    dict
        ``episodes``, ``success_rate``, ``collisions_highway_env``,
        ``collisions_footprint``, ``outcomes`` (count per :data:`OUTCOMES`),
        ``collisions_at_fault``, ``ttc_below_bound`` (episodes with a TTC at or
        below nuPlan's 0.95 s), the minimum and median of ``ttc_min_s``,
        ``min_distance_m`` and ``completion_time_s``, and for each error metric
        its mean (over the episodes that drove) and max.
    """
    n = len(reports)
    if n == 0:
        raise InputError("reports: need at least one report")
    out: dict[str, Any] = {
        "episodes": n,
        "success_rate": sum(r.success for r in reports) / n,
        "collisions_highway_env": sum(r.collision_highway_env for r in reports),
        "collisions_footprint": sum(r.collision_footprint for r in reports),
        "plan_failures": sum(r.status == "plan_failed" for r in reports),
        "outcomes": {o: sum(r.outcome == o for r in reports) for o in OUTCOMES},
        "collisions_at_fault": sum(r.collisions_at_fault for r in reports),
        "ttc_below_bound": sum(r.ttc_within_bound is False for r in reports),
    }
    for key in ("ttc_min_s", "min_distance_m", "completion_time_s"):
        vals = np.array([getattr(r, key) for r in reports if getattr(r, key) is not None], float)
        out[f"{key}_min"] = float(np.min(vals)) if len(vals) else None
        out[f"{key}_median"] = float(np.median(vals)) if len(vals) else None
    for key in (
        "cte_rms_m", "cte_max_m", "heading_err_rms_rad", "heading_err_max_rad",
        "executed_max_curvature", "executed_curvature_violation_share", "max_lateral_accel",
        "max_jerk", "max_steering_rate", "goal_position_err_m", "goal_heading_err_rad",
        "duration_s", "wall_time_s", "path_max_curvature", "progress_m",
        "replan_time_median_s", "replan_time_max_s",
    ):
        vals = np.array([getattr(r, key) for r in reports if getattr(r, key) is not None], float)
        out[f"{key}_mean"] = float(np.mean(vals)) if len(vals) else None
        out[f"{key}_max"] = float(np.max(vals)) if len(vals) else None
    return out
