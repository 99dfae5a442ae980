"""An outside judge: CommonRoad's kinematic single-track (KS) model checks a driven trajectory.

Optional extra: ``pip install ".[commonroad]"`` (commonroad-drivability-checker with
commonroad-io 2024.3; 2026.1 breaks the checker's imports, see ../shared/FACTS.md).

The judge rebuilds the episode's input sequence - the steering velocity
``(delta_k - delta_(k-1)) / dt`` of the front-wheel angle actually applied, and the applied
acceleration - and hands it to ``commonroad_dc``'s ``input_vector_feasibility`` with the
KS model carrying our car: wheelbase ``a + b = L`` with ``a = b = L / 2`` (so a
CommonRoad position is our body centre, the rear axle plus ``L / 2`` along the heading),
the steering limit ``max_steer`` and the steering-velocity limit ``max_steer_rate``
(CommonRoad's own vehicles: 0.4 rad/s). Longitudinal limits are the BMW 320i set's.
Besides the verdict it reports how far CommonRoad's forward simulation of those inputs
drifts from our logged positions (the two bicycle models should agree closely).
"""

from __future__ import annotations

import copy
import math
import warnings
from dataclasses import dataclass

import numpy as np

from rrtdrive.types import InputError, VehicleParams

__all__ = ["CommonRoadVerdict", "commonroad_available", "judge_trajectory"]

#: CommonRoad's steering-velocity limit of all three vehicle parameter sets (rad/s).
COMMONROAD_STEER_RATE = 0.4


@dataclass(frozen=True)
class CommonRoadVerdict:
    """CommonRoad's verdict on one driven trajectory.

    Attributes
    ----------
    feasible : bool
        Every input within the KS model's bounds (steering angle and velocity,
        acceleration) and the friction circle.
    first_infeasible_step : int or None
        Index of the first input CommonRoad rejects.
    max_steer_rate : float
        Largest absolute steering velocity of the inputs (rad/s).
    steer_rate_limit : float
        The limit the judge applied (rad/s).
    max_position_drift_m : float
        Largest distance between CommonRoad's simulation of the inputs (up to the first
        infeasible one) and our logged body centres (m).
    """

    feasible: bool
    first_infeasible_step: int | None
    max_steer_rate: float
    steer_rate_limit: float
    max_position_drift_m: float

    def to_json(self) -> dict[str, object]:
        """A JSON-ready dict."""
        return {
            "commonroad_feasible": self.feasible,
            "commonroad_first_infeasible_step": self.first_infeasible_step,
            "commonroad_max_steer_rate": round(self.max_steer_rate, 6),
            "commonroad_steer_rate_limit": self.steer_rate_limit,
            "commonroad_max_position_drift_m": round(self.max_position_drift_m, 6),
        }


def commonroad_available() -> bool:
    """True when the ``commonroad`` extra imports."""
    try:
        import commonroad_dc.feasibility.feasibility_checker  # noqa: F401
    except ImportError:
        return False
    return True


def _modules():
    try:
        from commonroad.scenario.state import InitialState, InputState
        from commonroad.scenario.trajectory import Trajectory
        from commonroad_dc.feasibility import feasibility_checker
        from commonroad_dc.feasibility.vehicle_dynamics import VehicleDynamics, VehicleType
    except ImportError as exc:
        raise InputError(
            "commonroad: the CommonRoad judge needs the optional extra: "
            f'pip install ".[commonroad]" ({exc})'
        ) from None
    return InitialState, InputState, Trajectory, feasibility_checker, VehicleDynamics, VehicleType


def _dynamics(vehicle: VehicleParams, steer_rate_limit: float):
    *_, vehicle_dynamics, vehicle_type = _modules()
    dyn = vehicle_dynamics.KS(vehicle_type.BMW_320i)
    params = copy.deepcopy(dyn.parameters)
    params.a = params.b = vehicle.wheelbase / 2.0
    params.l, params.w = vehicle.length, vehicle.width
    params.steering.min, params.steering.max = -vehicle.max_steer, vehicle.max_steer
    params.steering.v_min, params.steering.v_max = -steer_rate_limit, steer_rate_limit
    dyn.parameters = params
    return dyn


def judge_trajectory(
    t: np.ndarray,
    states: np.ndarray,
    steer: np.ndarray,
    accel: np.ndarray,
    vehicle: VehicleParams | None = None,
    steer_rate_limit: float = COMMONROAD_STEER_RATE,
) -> CommonRoadVerdict:
    """Judge a driven trajectory with CommonRoad's KS model.

    Parameters
    ----------
    t : numpy.ndarray
        Times ``(N + 1,)`` (s), equally spaced.
    states : numpy.ndarray
        Rear-axle ``[x, y, yaw, speed]`` at each time, ``(N + 1, 4)``.
    steer : numpy.ndarray
        Front-wheel angle applied over each step, ``(N,)`` (rad).
    accel : numpy.ndarray
        Acceleration applied over each step, ``(N,)`` (m/s^2).
    vehicle : VehicleParams, optional
        The car (default the paper's).
    steer_rate_limit : float
        Steering-velocity limit of the judge (rad/s).

    Notes
    -----
    The car starts with its wheels straight (CommonRoad's initial state has no
    steering angle; ours starts at 0 too), so the first input's steering velocity is
    ``steer[0] / dt``.

    Returns
    -------
    CommonRoadVerdict
    """
    vehicle = vehicle or VehicleParams()
    initial_state_cls, input_state_cls, trajectory_cls, checker, *_ = _modules()
    states = np.asarray(states, dtype=float)
    steer = np.asarray(steer, dtype=float)
    accel = np.asarray(accel, dtype=float)
    if len(states) != len(steer) + 1 or len(accel) != len(steer) or len(t) != len(states):
        raise InputError("trajectory: need N + 1 times and states, N steering and N accelerations")
    if len(steer) == 0:
        return CommonRoadVerdict(True, None, 0.0, steer_rate_limit, 0.0)
    dt = float(np.mean(np.diff(t)))
    rates = np.diff(np.concatenate(([0.0], steer))) / dt
    half = vehicle.wheelbase / 2.0
    centres = states[:, :2] + half * np.column_stack((np.cos(states[:, 2]), np.sin(states[:, 2])))
    dyn = _dynamics(vehicle, steer_rate_limit)
    x0, y0, yaw0, v0 = states[0]
    initial = initial_state_cls(
        position=np.array([centres[0, 0], centres[0, 1]]),
        velocity=float(v0),
        orientation=float(yaw0),
        time_step=0,
        yaw_rate=0.0,
        slip_angle=0.0,
        acceleration=0.0,
    )
    inputs = [
        input_state_cls(steering_angle_speed=float(r), acceleration=float(a), time_step=k)
        for k, (r, a) in enumerate(zip(rates, accel, strict=True))
    ]
    with warnings.catch_warnings():
        # commonroad_dc's state arrays trip numpy 2's __array__(copy=) deprecation per step.
        warnings.simplefilter("ignore", DeprecationWarning)
        feasible, simulated = checker.input_vector_feasibility(
            initial, trajectory_cls(initial_time_step=0, state_list=inputs), dyn, dt
        )
    sim_xy = np.array([s.position for s in simulated.state_list], dtype=float)
    drift = float(np.max(np.hypot(*(sim_xy - centres[: len(sim_xy)]).T))) if len(sim_xy) else 0.0
    first_bad = None if feasible else len(simulated.state_list) - 1
    return CommonRoadVerdict(
        feasible=bool(feasible),
        first_infeasible_step=first_bad,
        max_steer_rate=float(np.max(np.abs(rates))),
        steer_rate_limit=float(steer_rate_limit),
        max_position_drift_m=drift if math.isfinite(drift) else float("inf"),
    )
