"""Predicting the other vehicles of a highway-env road over a horizon.

Two predictors, both returning a :class:`rrtdrive.planning.spacetime.Prediction`
(body-centre poses on a uniform time grid):

* ``"constant-velocity"`` - each vehicle drives on along its heading at its speed;
* ``"lane-following"`` - highway-env's own prediction where the vehicle has one:
  :meth:`highway_env.vehicle.controller.ControlledVehicle.predict_trajectory_constant_speed`
  moves it along its lane (or route) at constant speed, on the lane centre with
  the lane's heading. Vehicles without it (plain ``Vehicle``) fall back to
  constant velocity.

With ``speed_bound=True`` (the default) a vehicle that has an IDM target speed
above its current speed gets two hypotheses: its current speed and its target
speed (:attr:`~rrtdrive.planning.spacetime.Prediction.alt`). Such a car was braked
(by the ego in its lane, or by a slower car ahead): it may speed up again, up to
its target (an IDM car never drives faster), or stay slow; the conflict test
sweeps its body over both, so a plan must be safe whether it arrives early or late.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from rrtdrive.planning.spacetime import Prediction
from rrtdrive.types import InputError, require_positive
from rrtdrive.values import did_you_mean

__all__ = ["PREDICTORS", "predict", "vehicle_states"]

PREDICTORS = ("constant-velocity", "lane-following")


def vehicle_states(vehicles: Sequence[Any]) -> tuple[np.ndarray, np.ndarray]:
    """Body-centre ``[x, y, heading, speed]`` and ``[length, width]`` of highway-env vehicles."""
    states = np.array(
        [(v.position[0], v.position[1], v.heading, v.speed) for v in vehicles], dtype=float
    ).reshape(-1, 4)
    sizes = np.array([(v.LENGTH, v.WIDTH) for v in vehicles], dtype=float).reshape(-1, 2)
    return states, sizes


def _bound(vehicle: Any, speed_bound: bool) -> float:
    v = float(vehicle.speed)
    if speed_bound:
        target = getattr(vehicle, "target_speed", None)
        if target is not None and float(target) > v:
            return float(target)
    return v


def predict(
    vehicles: Sequence[Any],
    method: str = "constant-velocity",
    horizon: float = 12.0,
    step: float = 0.1,
    speed_bound: bool = True,
) -> Prediction:
    """Predict ``vehicles`` (highway-env vehicles) over ``horizon`` seconds.

    Parameters
    ----------
    vehicles : sequence
        highway-env vehicles (``position``, ``heading``, ``speed``, ``LENGTH``, ``WIDTH``).
    method : str
        ``"constant-velocity"`` or ``"lane-following"``.
    horizon, step : float
        Horizon and grid step in seconds.
    speed_bound : bool
        A car slower than its IDM target speed is predicted at its current speed
        and, as the second hypothesis (``alt``), at its target speed.

    Returns
    -------
    Prediction

    Examples
    --------
    >>> from highway_env.road.road import Road, RoadNetwork
    >>> from highway_env.vehicle.kinematics import Vehicle
    >>> road = Road(RoadNetwork.straight_road_network(1))
    >>> car = Vehicle(road, [0.0, 0.0], heading=0.0, speed=5.0)
    >>> predict([car], horizon=2.0).centres_at(np.array([2.0]))[0, 0].round(3).tolist()
    [10.0, 0.0]
    """
    if method not in PREDICTORS:
        raise InputError(
            f"predictor: unknown predictor {method!r}{did_you_mean(method, PREDICTORS)}; "
            f"choose from {', '.join(PREDICTORS)}"
        )
    require_positive("prediction.horizon", horizon)
    require_positive("prediction.step", step)
    vehicles = list(vehicles)
    states, sizes = vehicle_states(vehicles)
    bounds = np.array([_bound(v, speed_bound) for v in vehicles], dtype=float).reshape(-1)
    main = _predict(vehicles, states, sizes, method, horizon, step)
    if not np.any(bounds > states[:, 3] + 1e-9):
        return main
    fast_states = states.copy()
    fast_states[:, 3] = bounds
    fast = _predict(vehicles, fast_states, sizes, method, horizon, step)
    return Prediction(main.times, main.poses, sizes, main.method, fast.poses)


def _predict(
    vehicles: list[Any],
    states: np.ndarray,
    sizes: np.ndarray,
    method: str,
    horizon: float,
    step: float,
) -> Prediction:
    """One hypothesis: every vehicle at the speed in ``states``."""
    cv = Prediction.constant_velocity(states, sizes, horizon, step)
    if method == "constant-velocity" or not vehicles:
        return cv
    times = cv.times
    poses = cv.poses.copy()
    for k, v in enumerate(vehicles):
        fn = getattr(v, "predict_trajectory_constant_speed", None)
        lane = getattr(v, "lane", None)
        if fn is None or lane is None or not hasattr(v, "route"):
            continue  # a plain Vehicle: its own prediction is zero steering, i.e. constant velocity
        speed = float(v.speed)
        if speed <= 1e-6:
            if states[k, 3] > 1e-6:
                continue  # from rest: no route speed to scale, keep constant velocity
            scale = 0.0
        else:
            # highway-env predicts at the current speed; scaling time predicts at another.
            scale = states[k, 3] / speed
        positions, headings = fn(times * scale)
        poses[k, :, :2] = np.asarray(positions, dtype=float).reshape(-1, 2)
        poses[k, :, 2] = np.asarray(headings, dtype=float)
    return Prediction(times, poses, sizes, "lane-following")
