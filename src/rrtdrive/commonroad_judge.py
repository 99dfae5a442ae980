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
CommonRoad's ``input_vector_feasibility`` judges the inputs alone (steering velocity,
acceleration, friction circle); it caps the steering angle and the speed at their limits
without saying so, and after the initial state it never looks at the logged states.
So the judge's verdict ``feasible`` also asks that CommonRoad's forward simulation of
the inputs stays on the logged trajectory (:data:`DRIFT_TOL_M`, :data:`HEADING_TOL_RAD`,
each growing with the distance driven, and :data:`SPEED_TOL_MPS`)
and that every applied angle and logged speed is within the car's and the model's
limits: without that, a trajectory whose states jump 5 m sideways, or turn three
times as fast as the inputs allow, was called feasible (the logged inputs were).
"""

from __future__ import annotations

import copy
import math
import warnings
from dataclasses import dataclass

import numpy as np

from rrtdrive.geometry import wrap_angle
from rrtdrive.types import InputError, VehicleParams, require_positive

__all__ = ["CommonRoadVerdict", "commonroad_available", "judge_trajectory"]

#: CommonRoad's steering-velocity limit of all three vehicle parameter sets (rad/s).
COMMONROAD_STEER_RATE = 0.4
#: Largest distance between CommonRoad's simulation of the inputs and the logged body
#: centres for a feasible trajectory: this, plus :data:`DRIFT_PER_M` of the distance
#: driven so far (m). Our episodes drift at most 0.0014 m (the two models integrate the
#: same ramped steering; session 25's 717 judged episodes); a log that holds the
#: steering over each step instead drifts about 0.4 mm per metre (2.6 cm over 60 m).
DRIFT_TOL_M = 0.02
DRIFT_PER_M = 1e-3
#: The same for the heading (rad, and rad per metre driven).
HEADING_TOL_RAD = 0.01
HEADING_PER_M = 1e-4
#: Largest difference between CommonRoad's simulated speed and the logged one (m/s): a
#: log whose speed column disagrees with its own accelerations (12 m/s logged on a 2 m/s
#: drive) was judged feasible on its positions alone (an audit).
SPEED_TOL_MPS = 0.05


@dataclass(frozen=True)
class CommonRoadVerdict:
    """CommonRoad's verdict on one driven trajectory.

    Attributes
    ----------
    feasible : bool
        The judge's verdict: CommonRoad accepts the inputs, its simulation of them stays
        on the logged trajectory (:data:`DRIFT_TOL_M`, :data:`HEADING_TOL_RAD`,
        :data:`SPEED_TOL_MPS`), and
        every applied steering angle and logged speed is within the limits.
    first_infeasible_step : int or None
        Index of the first input CommonRoad rejects.
    inputs_feasible : bool
        CommonRoad's own verdict on the inputs (steering velocity, acceleration,
        friction circle).
    max_heading_drift_rad : float
        Largest heading difference between CommonRoad's simulation and the log (rad).
    max_speed_drift_mps : float
        Largest speed difference between CommonRoad's simulation and the log (m/s;
        :data:`SPEED_TOL_MPS`).
    why : str
        What makes it infeasible (empty when feasible).
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
    inputs_feasible: bool = True
    max_heading_drift_rad: float = 0.0
    why: str = ""
    max_speed_drift_mps: float = 0.0

    def to_json(self) -> dict[str, object]:
        """A JSON-ready dict."""
        return {
            "commonroad_feasible": self.feasible,
            "commonroad_first_infeasible_step": self.first_infeasible_step,
            "commonroad_max_steer_rate": round(self.max_steer_rate, 6),
            "commonroad_steer_rate_limit": self.steer_rate_limit,
            "commonroad_max_position_drift_m": round(self.max_position_drift_m, 6),
            "commonroad_inputs_feasible": self.inputs_feasible,
            "commonroad_max_heading_drift_rad": round(self.max_heading_drift_rad, 6),
            "commonroad_max_speed_drift_mps": round(self.max_speed_drift_mps, 6),
            "commonroad_why": self.why,
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
        Steering-velocity limit of the judge (rad/s), a finite number > 0.

    Notes
    -----
    The car starts with its wheels straight (CommonRoad's initial state has no
    steering angle; ours starts at 0 too), so the first input's steering velocity is
    ``steer[0] / dt``.

    Returns
    -------
    CommonRoadVerdict

    Raises
    ------
    InputError
        For a ``steer_rate_limit`` that is no finite positive number (a negative or NaN
        one made every trajectory, a straight line too, read as infeasible), arrays of
        the wrong lengths, a number that is not finite, or times not equally spaced.
    """
    require_positive("steer_rate_limit", steer_rate_limit)
    vehicle = vehicle or VehicleParams()
    initial_state_cls, input_state_cls, trajectory_cls, checker, *_ = _modules()
    states = np.asarray(states, dtype=float)
    steer = np.asarray(steer, dtype=float)
    accel = np.asarray(accel, dtype=float)
    if len(states) != len(steer) + 1 or len(accel) != len(steer) or len(t) != len(states):
        raise InputError("trajectory: need N + 1 times and states, N steering and N accelerations")
    t = np.asarray(t, dtype=float)
    if not all(np.isfinite(a).all() for a in (t, states, steer, accel)):
        # A NaN spread into the distance driven and loosened every later tolerance.
        raise InputError("trajectory: times, states, steering and accelerations must be finite")
    if len(steer) == 0:
        return CommonRoadVerdict(True, None, 0.0, steer_rate_limit, 0.0)
    steps = np.diff(t)
    dt = float(np.mean(steps))
    if not dt > 0.0 or np.abs(steps - dt).max() > 1e-6 * dt + 1e-12:
        raise InputError(
            f"trajectory: times must be equally spaced and increasing (steps {steps.min():.6g}"
            f" to {steps.max():.6g} s); CommonRoad's model steps at one dt"
        )
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
    sim = simulated.state_list
    n = len(sim)
    gaps = np.hypot(*np.diff(states[:n, :2], axis=0).T)
    driven = np.concatenate(([0.0], np.cumsum(gaps)))
    off = np.hypot(*(np.array([s.position for s in sim], dtype=float) - centres[:n]).T)
    turn = np.abs(wrap_angle(np.array([s.orientation for s in sim]) - states[:n, 2]))
    drift = float(np.max(off)) if n else 0.0
    heading = float(np.max(turn)) if n else 0.0
    gap = np.abs(np.array([s.velocity for s in sim], dtype=float) - states[:n, 3])
    speed_drift = float(np.max(gap)) if n else 0.0
    drift = drift if math.isfinite(drift) else math.inf
    heading = heading if math.isfinite(heading) else math.inf
    speed_drift = speed_drift if math.isfinite(speed_drift) else math.inf
    # NaN (a diverged simulation) fails the tests below as it should.
    off_path = not bool(np.all(off <= DRIFT_TOL_M + DRIFT_PER_M * driven))
    turned = not bool(np.all(turn <= HEADING_TOL_RAD + HEADING_PER_M * driven))
    lon = dyn.parameters.longitudinal
    speed = states[:, 3]
    why = [
        text
        for bad, text in (
            (not feasible, "CommonRoad rejects an input"),
            (off_path, f"its simulation drifts {drift:.3g} m from the log"),
            (turned, f"its heading drifts {heading:.3g} rad from the log"),
            (
                not speed_drift <= SPEED_TOL_MPS,
                f"its speed drifts {speed_drift:.3g} m/s from the log",
            ),
            (
                bool(np.any(np.abs(steer) > vehicle.max_steer * (1 + 1e-9))),
                f"a steering angle over {vehicle.max_steer:.4g} rad",
            ),
            (
                bool(np.any((speed < lon.v_min) | (speed > lon.v_max))),
                f"a speed outside [{lon.v_min:.3g}, {lon.v_max:.3g}] m/s",
            ),
        )
        if bad
    ]
    return CommonRoadVerdict(
        feasible=not why,
        first_infeasible_step=None if feasible else len(sim) - 1,
        max_steer_rate=float(np.max(np.abs(rates))),
        steer_rate_limit=float(steer_rate_limit),
        max_position_drift_m=drift,
        inputs_feasible=bool(feasible),
        max_heading_drift_rad=heading,
        why="; ".join(why),
        max_speed_drift_mps=speed_drift,
    )
