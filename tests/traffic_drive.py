"""Test helper: a pure-pursuit re-planning driver in the overtake-traffic scene of a seed."""

from __future__ import annotations

from rrtdrive.controllers import SpeedConfig, make_controller
from rrtdrive.sim.drivelog import DriveRecorder
from rrtdrive.sim.replanning import ReplanConfig
from rrtdrive.sim.scenes import build_env, scenario_rngs
from rrtdrive.sim.tasks import Task, make_scenario, traffic_speed_config
from rrtdrive.sim.traffic_driver import TrafficDriver


def traffic_driver(
    seed: int, config: ReplanConfig, steps: int | None
) -> tuple[Task, SpeedConfig, TrafficDriver]:
    """``(scenario, speed, driver)``; with ``steps``, the driver started and driven that
    many simulation steps in highway-env (``None``: only built). The env is closed."""
    scen = make_scenario("overtake-traffic", seed)
    env = build_env(scen)
    try:
        speed = traffic_speed_config(scen)
        ctrl = make_controller("pure-pursuit", vehicle=scen.vehicle, speed=speed)
        driver = TrafficDriver(env, scen, ctrl, speed, config, scenario_rngs(seed)[1])
        if steps is not None:
            driver.start()
            dt = 1.0 / env.unwrapped.config["simulation_frequency"]
            recorder = DriveRecorder(env, dt)
            for k in range(steps):
                recorder.step(*driver.control(k * dt))
    finally:
        env.close()
    return scen, speed, driver
