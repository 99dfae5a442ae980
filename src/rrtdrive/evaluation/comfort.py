"""Comfort and curvature figures from the logged commands.

Every function reads the applied commands ``(a_k, δ_k)`` of a log (held over
``[t_k, t_k+1)``) and the speeds at the start of each step; definitions in
``docs/metrics.md`` (Curvature, Comfort).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:  # pragma: no cover
    from rrtdrive.sim.episode import DriveLog

__all__ = [
    "executed_curvature",
    "curvature_violation_share",
    "lateral_accel",
    "max_jerk",
    "steering_rate",
]


def executed_curvature(log: DriveLog, vehicle: Any) -> np.ndarray:
    """Curvature ``tan(δ_k) / L`` the car drove during each step, ``(N,)`` (1/m)."""
    return np.tan(log.controls[:, 1]) / vehicle.wheelbase


def curvature_violation_share(kappa: np.ndarray, kappa_max: float, tol: float) -> float:
    """Share of steps with ``|κ_k| > κ_max (1 + tol)``."""
    over = np.abs(kappa) > kappa_max * (1.0 + tol)
    return float(np.mean(over))


def lateral_accel(log: DriveLog, kappa: np.ndarray) -> np.ndarray:
    """Signed lateral acceleration ``v_k² κ_k`` of each step, ``(N,)`` (m/s²)."""
    v_step = log.states[:, 3][:-1]
    return v_step**2 * kappa


def max_jerk(log: DriveLog, lat: np.ndarray) -> float | None:
    """Largest step-to-step jerk magnitude ``|(Δa, Δa_lat)| / dt`` (m/s³); ``None`` for one step."""
    accel = log.controls[:, 0]
    if len(accel) > 1:
        jerk = np.hypot(np.diff(accel), np.diff(lat)) / log.dt
        return float(np.max(jerk))
    return None


def steering_rate(log: DriveLog) -> np.ndarray:
    """``|δ_k − δ_k−1| / dt`` of each step, with ``δ_−1 = 0``, ``(N,)`` (rad/s)."""
    steer = log.controls[:, 1]
    steer_prev = np.concatenate([[0.0], steer[:-1]])
    return np.abs(steer - steer_prev) / log.dt


def path_sharpness(path: Any, wheelbase: float) -> float | None:
    """Largest ``|d delta / ds|`` of a path (rad/m), ``delta = atan(L kappa)``.

    The steering angle the path asks for changes at this rate per metre; a car
    with steering rate ``r`` follows it at up to ``r / sharpness`` m/s. ``None``
    for a path of fewer than two samples.
    """
    samples = np.asarray(path.samples, dtype=float)
    if len(samples) < 2:
        return None
    ds = np.hypot(*np.diff(samples[:, :2], axis=0).T)
    delta = np.arctan(wheelbase * samples[:, 3])
    keep = ds > 1e-9  # a repeated row (a cusp) has no length to change over
    if not np.any(keep):
        return 0.0
    return float(np.max(np.abs(np.diff(delta))[keep] / ds[keep]))
