"""LQR on the linearised path-error dynamics (python-control) plus curvature feed-forward."""

from __future__ import annotations

import functools
import math

import numpy as np

from rrtdrive.controllers.base import Projection, TrackingController
from rrtdrive.controllers.speed import SpeedConfig
from rrtdrive.controllers.state import APPROACH_ANGLE, VehicleState, checked_approach_angle
from rrtdrive.types import InputError, VehicleParams, require_finite, require_positive

__all__ = ["LQR", "lateral_error_model", "design_gain"]


def lateral_error_model() -> tuple[np.ndarray, np.ndarray]:
    """The linearised lateral-error dynamics of the rear axle, in arc length.

    States ``x = [e, e_psi]``: the rear axle's signed offset from the path (left
    positive) and ``yaw - path_yaw``. Input ``u = tan(delta) / L - kappa``, the
    curvature the car drives beyond the path's. Linearised about the path
    (``sin e_psi ~ e_psi``, ``kappa e ~ 0``) and written per metre travelled::

        de/ds     = e_psi
        de_psi/ds = u

    Writing the model over distance rather than time makes one gain fit every
    speed: the errors decay over metres, the natural scale for a path.

    Returns
    -------
    A, B : numpy.ndarray
        ``(2, 2)`` and ``(2, 1)``.
    """
    return np.array([[0.0, 1.0], [0.0, 0.0]]), np.array([[0.0], [1.0]])


def design_gain(q_e: float, q_psi: float, r: float) -> np.ndarray:
    """The LQR state-feedback gain ``K`` (``u = -K x``) from :func:`control.lqr`.

    Parameters
    ----------
    q_e, q_psi : float
        State weights on the lateral error (1/m^2) and the heading error (1/rad^2).
    r : float
        Input weight on the curvature correction (m^2).

    Returns
    -------
    numpy.ndarray
        Shape ``(2,)``.

    Examples
    --------
    >>> design_gain(1.0, 1.0, 16.0).round(3).tolist()
    [0.25, 0.75]
    """
    require_positive("lqr.q_e", q_e)
    require_positive("lqr.r", r)
    require_finite("lqr.q_psi", q_psi)  # a string would fail the comparison below unnamed
    if not (q_psi >= 0 and math.isfinite(q_psi)):
        raise InputError(f"lqr.q_psi: must be a finite number >= 0, got {q_psi!r}")
    return np.array(_design_gain(float(q_e), float(q_psi), float(r)))


@functools.lru_cache(maxsize=64)
def _design_gain(q_e: float, q_psi: float, r: float) -> tuple[float, float]:
    # Cached: the gain depends on the weights only, and a LAPACK call per episode
    # would wake OpenBLAS's worker threads, which then spin on the other core.
    # Imported here: python-control imports matplotlib.pyplot (0.7 s on every start of
    # the CLI, a bench worker or a script), and the gain is computed once per weights.
    import control

    A, B = lateral_error_model()
    K, _, _ = control.lqr(A, B, np.diag([q_e, q_psi]), np.array([[r]]))
    k = np.asarray(K, dtype=float).reshape(2)
    # Rounded to 12 significant digits: the Riccati solution's last bits depend on the
    # BLAS/LAPACK build and the CPU (0.5000000000000002, ...03 with scipy 1.10, ...04
    # with OpenBLAS's Haswell kernels), and a seeded episode's trajectory with them.
    return (float(f"{k[0]:.12g}"), float(f"{k[1]:.12g}"))


class LQR(TrackingController):
    """Steering ``tan(delta) = L (kappa_path - K [e, e_psi])``.

    The feed-forward ``kappa_path`` keeps the car on a curve; the LQR term pulls the
    errors to zero. Gains from :func:`design_gain`. In reverse the error model is the
    mirrored car's (:mod:`rrtdrive.controllers.gears`): errors and arc length in the
    direction of travel, the same gains.

    Parameters
    ----------
    vehicle : VehicleParams, optional
        The car.
    speed : SpeedConfig, optional
        Longitudinal profile and PI gains.
    q_e, q_psi, r : float
        LQR weights (see :func:`design_gain`).
    steer_limit : float, optional
        Largest commanded steering angle (default: the curvature limit's).
    bandwidth : float
        Rate-limited actuator only: the largest closed-loop bandwidth in time (rad/s).
        The arc-length design has the natural frequency ``(q_e / r)^(1/4)`` per metre,
        ``v`` times that per second; above ``bandwidth / (q_e / r)^(1/4)`` m/s the
        input weight grows to ``q_e (v / bandwidth)^4`` (gains designed per 0.5 m/s),
        so the corrections ask the wheels to turn no faster at speed than at parking
        speeds (a fixed arc-length gain drove the 0.4 rad/s car into a growing
        oscillation at 11 m/s).
    approach_angle : float
        Far from the path the lateral error counts at most ``approach_angle k_psi /
        k_e`` (0.45 m with the default weights), so the car heads back at most this
        many radians off the path's direction. The linear law's corrections from
        further off ask for full lock and, on a rate-limited car, swing across the
        path in a growing oscillation (1 m off at 3 m/s: 1.06 to 1.64 m, then a
        crash in highway-env).

    Examples
    --------
    >>> from rrtdrive.types import Path
    >>> xs = np.linspace(0.0, 20.0, 81)
    >>> c = LQR()
    >>> c.reset(Path(np.column_stack([xs, 0 * xs, 0 * xs, 0 * xs]), np.zeros((0, 2))))
    >>> c.control(VehicleState(0.0, 0.5, 0.0, 1.0))[1] < 0.0
    True
    """

    name = "lqr"

    def __init__(
        self,
        vehicle: VehicleParams | None = None,
        speed: SpeedConfig | None = None,
        q_e: float = 1.0,
        q_psi: float = 1.0,
        r: float = 4.0,
        steer_limit: float | None = None,
        bandwidth: float = 2.0,
        approach_angle: float = APPROACH_ANGLE,
    ) -> None:
        super().__init__(vehicle, speed, steer_limit)
        require_positive("lqr.bandwidth", bandwidth)
        self.approach_angle = checked_approach_angle("lqr.approach_angle", approach_angle)
        self.gain = design_gain(q_e, q_psi, r)
        self._k_e, self._k_psi = float(self.gain[0]), float(self.gain[1])
        self._weights = (float(q_e), float(q_psi), float(r))
        self.bandwidth = float(bandwidth)

    def _gains(self, speed: float) -> tuple[float, float]:
        """``(k_e, k_psi)`` for ``speed``: fixed, or scheduled for a rate-limited actuator."""
        if self.steer_rate is None:
            return self._k_e, self._k_psi
        q_e, q_psi, r = self._weights
        v = 0.5 * math.ceil(abs(speed) / 0.5)  # design per 0.5 m/s (cached)
        r_eff = max(r, q_e * (v / self.bandwidth) ** 4)
        if r_eff == r:
            return self._k_e, self._k_psi
        k_e, k_psi = _design_gain(q_e, q_psi, r_eff)
        return k_e, k_psi

    def steering(self, state: VehicleState, proj: Projection) -> float:
        """LQR steering angle with curvature feed-forward.

        As :meth:`TrackingController.steering`.

        Parameters
        ----------
        state : VehicleState
            The car; in reverse, the mirrored car of the forward problem.
        proj : Projection
            Its rear axle's projection on the gear segment being driven.

        Returns
        -------
        float
            Steering angle in rad (left positive), before the steering limit.
        """
        k_e, k_psi = self._gains(state.speed)
        reach = self.approach_angle * k_psi / k_e
        u = -(k_e * min(max(proj.cte, -reach), reach) + k_psi * self.heading_error)
        return math.atan(self.vehicle.wheelbase * (self.ff_kappa(proj) + u))
