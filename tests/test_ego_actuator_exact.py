"""The ego's rate-limited steering: exact slew both ways, and the ramped step's pose.

Mutation audit, session 35: two changes to ``EgoVehicle.step`` survived every test:
a one-sided rate limit (the angle could drop at once: only slews from 0 up were
tested) and a step that drives the whole step at the final angle instead of turning
the wheels during it. Here (a) a slew from +0.3 to -0.3 rad and back moves by exactly
``max_steer_rate * dt`` a step, in both gears, and (b) one step whose steering ramps
from 0 is checked against scipy's ``solve_ivp`` of the rear-axle kinematic bicycle
``x' = v cos(yaw), y' = v sin(yaw), yaw' = v tan(delta(t)) / L`` with ``delta``
linear in time over the step (the class docstring: "turning linearly within the
step", as CommonRoad's KS model).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from highway_env.road.lane import StraightLane
from highway_env.road.road import Road, RoadNetwork
from scipy.integrate import solve_ivp

from rrtdrive.sim.ego import EgoVehicle
from rrtdrive.types import Pose, VehicleParams


def _ego(car: VehicleParams, pose: Pose, speed: float) -> EgoVehicle:
    net = RoadNetwork()
    net.add_lane("a", "b", StraightLane([-200.0, 0.0], [200.0, 0.0]))
    road = Road(net, np_random=np.random.RandomState(0))
    ego = EgoVehicle(road, pose, speed=speed, vehicle=car)
    road.vehicles.append(ego)
    return ego


def _slew(ego: EgoVehicle, command: float, steps: int, dt: float) -> np.ndarray:
    """The applied steering angle after each of ``steps`` steps holding ``command``."""
    out = []
    for _ in range(steps):
        ego.act({"acceleration": 0.0, "steering": command})
        ego.step(dt)
        out.append(ego.steer)
    return np.array(out)


@pytest.mark.parametrize("speed", [3.0, -1.5], ids=["forward", "reverse"])
def test_the_steering_slews_at_exactly_the_rate_in_both_directions(speed: float) -> None:
    rate, dt, big = 0.4, 0.05, 0.3
    step = rate * dt  # 0.02 rad a step
    n = round(2 * big / step)  # 30 steps from +0.3 to -0.3
    ego = _ego(VehicleParams(max_steer_rate=rate), Pose(0.0, 0.0, 0.0), speed)
    up = _slew(ego, big, round(big / step) + 3, dt)  # from straight wheels to +0.3
    assert up[-1] == pytest.approx(big, abs=1e-12)
    for sign in (-1.0, 1.0):  # down to -0.3, then back up to +0.3
        series = _slew(ego, sign * big, n + 5, dt)
        moves = np.diff(np.r_[-sign * big, series])
        assert moves[:n] == pytest.approx(np.full(n, sign * step), abs=1e-12)
        # Reached after n steps, then held.
        assert series[n - 1:] == pytest.approx(np.full(6, sign * big), abs=1e-12)


@pytest.mark.parametrize(
    ("rate", "dt", "speed", "command"),
    [
        (0.4, 0.05, 3.0, 0.3),  # the default actuator: 0.02 rad over 0.15 m
        (0.4, 0.05, -2.0, -0.3),  # reversing, steering right
        (4.0, 0.1, 8.0, 0.5),  # a fast actuator: 0.4 rad over 0.8 m
    ],
)
def test_a_ramped_step_follows_the_bicycle_ode(
    rate: float, dt: float, speed: float, command: float
) -> None:
    car = VehicleParams(max_steer_rate=rate)
    start = (1.0, 2.0, 0.3)
    ego = _ego(car, Pose(*start), speed)
    ego.act({"acceleration": 0.0, "steering": command})
    ego.step(dt)
    delta1 = math.copysign(rate * dt, command)  # the command is beyond one step's reach
    assert ego.steer == pytest.approx(delta1, abs=1e-15)
    length = car.wheelbase

    def rhs(t: float, s: np.ndarray) -> list[float]:
        delta = delta1 * t / dt  # from straight wheels, linear in time (constant speed)
        return [
            speed * math.cos(s[2]), speed * math.sin(s[2]), speed * math.tan(delta) / length
        ]

    sol = solve_ivp(rhs, (0.0, dt), start, method="DOP853", rtol=1e-12, atol=1e-13)
    want = sol.y[:, -1]
    # The ego integrates exact arcs over RAMP_SUBSTEPS sub-steps at the ramp's midpoint
    # angles: on each sub-step of length h an arc of the mean curvature is off the
    # linearly turning path by kappa' h^3 / 12, so the step is off by at most
    # |dkappa| ds^2 / (12 n^2) (2.3e-7 m for the default actuator); twice that is the
    # tolerance. Driving the whole step at delta1 is off by 6e-4 m there.
    n = EgoVehicle.RAMP_SUBSTEPS
    ds = abs(speed) * dt
    bound = abs(math.tan(delta1)) / length * ds * ds / (12 * n * n)
    got = np.array(ego.rear)
    assert np.abs(got - want).max() <= 2.0 * bound + 1e-12, (got - want, bound)
