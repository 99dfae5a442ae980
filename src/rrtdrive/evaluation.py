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
    from rrtdrive.sim.runner import Episode

__all__ = [
    "EvalConfig",
    "EpisodeReport",
    "evaluate",
    "summarise",
    "tracking_errors",
    "densify_poses",
]


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


def _footprint_collisions(episode: Episode, spacing: float) -> bool:
    """Exact body rectangle of every (densified) logged pose against the map and other cars."""
    from rrtdrive.planning.base import cached_checker

    m = episode.scenario.map
    states = episode.log.states
    if len(states) == 0:
        return False
    dense = densify_poses(states[:, :3], spacing)
    checker = cached_checker(m)
    if not bool(np.all(checker.poses_free(dense))):
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
    fp_crash = _footprint_collisions(episode, cfg.footprint_spacing)
    passed_lead = back_in_lane = None
    extra_ok = True
    if scen.lead_index is not None and scen.lane_y is not None:
        lead = scen.map.obstacles[scen.lead_index]
        body = footprint_corners(final[:3], vehicle)
        passed_lead = bool(body[:, 0].min() > lead.corners()[:, 0].max())
        half = scen.lane_width / 2.0
        back_in_lane = bool(
            np.all(np.abs(body[:, 1] - scen.lane_y) <= half)
        )
        extra_ok = passed_lead and back_in_lane
    in_time = episode.status == "arrived"
    success = bool(
        reached and stopped and in_time and not hw_crash and not fp_crash and extra_ok
    )
    over = np.abs(kappa_exec) > vehicle.kappa_max * (1.0 + cfg.kappa_tol)
    return EpisodeReport(
        **base,
        success=success,
        collision=hw_crash or fp_crash,
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
        goal_position_err_m=pos_err,
        goal_heading_err_rad=head_err,
        final_speed=float(final[3]),
        time_to_goal_s=float(log.t[-1]) if success else None,
    )


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
        ``collisions_footprint``, and for each error metric its mean (over the
        episodes that drove) and max.
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
    }
    for key in (
        "cte_rms_m", "cte_max_m", "heading_err_rms_rad", "heading_err_max_rad",
        "executed_max_curvature", "executed_curvature_violation_share", "max_lateral_accel",
        "max_jerk", "max_steering_rate", "goal_position_err_m", "goal_heading_err_rad",
        "duration_s", "wall_time_s", "path_max_curvature",
    ):
        vals = np.array([getattr(r, key) for r in reports if getattr(r, key) is not None], float)
        out[f"{key}_mean"] = float(np.mean(vals)) if len(vals) else None
        out[f"{key}_max"] = float(np.max(vals)) if len(vals) else None
    return out
