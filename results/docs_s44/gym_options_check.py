"""Print the options DriveEnv accepts, their defaults as declared in
rrtdrive.envs.config.DriveEnvConfig, and the errors of a few bad values (session 24,
docs/gym.md's options table)."""
import dataclasses
import gymnasium as gym
import rrtdrive  # noqa: F401
from rrtdrive.envs.config import DriveEnvConfig
from rrtdrive.envs.drive_env import DriveEnv
from rrtdrive.sim.replanning import ReplanConfig
from rrtdrive.sim.tasks import SCENARIO_OPTIONS
from rrtdrive.controllers import SpeedConfig
import inspect

print("DriveEnv.__init__:", inspect.signature(DriveEnv.__init__))
print("option_names():", DriveEnvConfig.option_names())
for f in dataclasses.fields(DriveEnvConfig):
    if f.init:
        print(f"  {f.name}: type {f.type}; default {f.default!r}")
cfg = DriveEnvConfig.from_options("parking")
print("resolved defaults for parking:", {k: getattr(cfg, k) for k in
      ("simulation_frequency", "max_time_s", "max_cte", "reward", "scenario_options",
       "replan_options", "controller_options", "speed_options", "budget", "seed_range")})
print("SCENARIO_OPTIONS:", SCENARIO_OPTIONS)
print("ReplanConfig fields:", [f.name for f in dataclasses.fields(ReplanConfig) if f.init])
print("SpeedConfig fields:", [f.name for f in dataclasses.fields(SpeedConfig) if f.init])
t = DriveEnvConfig.from_options("overtake-traffic", replan_options={"wall_limit": False})
print("overtake-traffic replan:", type(t.replan).__name__, "wall_limit", t.replan.wall_limit,
      "rate_hz", t.replan.rate_hz)
print("parking replan:", DriveEnvConfig.from_options("parking").replan)

def err(label, fn):
    try:
        fn()
        print(label, "-> accepted")
    except Exception as exc:  # noqa: BLE001
        print(label, "->", type(exc).__name__ + ":", str(exc)[:200])

err("parking replan_options={'wall_limit': False}",
    lambda: DriveEnvConfig.from_options("parking", replan_options={"wall_limit": False}))
err("overtake-traffic replan_options={'rate': 3}",
    lambda: DriveEnvConfig.from_options("overtake-traffic", replan_options={"rate": 3}))
err("simulation_frequency=10", lambda: DriveEnvConfig.from_options("parking", simulation_frequency=10))
err("n_ref_points=201", lambda: DriveEnvConfig.from_options("parking", n_ref_points=201))
err("n_vehicles=51", lambda: DriveEnvConfig.from_options("parking", n_vehicles=51))
err("action_repeat=1001", lambda: DriveEnvConfig.from_options("parking", action_repeat=1001))
err("reward={'cte': -1}", lambda: DriveEnvConfig.from_options("parking", reward={"cte": -1}))
err("seed_range=(5, 5)", lambda: DriveEnvConfig.from_options("parking", seed_range=(5, 5)))
err("max_cte=None", lambda: DriveEnvConfig.from_options("parking", max_cte=None))
err("map scenario_options={'jitter': (0,0,0)}",
    lambda: DriveEnvConfig.from_options("parking_lot", scenario_options={"jitter": (0, 0, 0)}))
err("controller_options={'speed': 1}",
    lambda: DriveEnvConfig.from_options("parking", controller_options={"speed": 1}))
err("gym.make config='x'", lambda: gym.make("rrtdrive/Parking-v0", config="x"))
err("gym.make render_mode='human'", lambda: gym.make("rrtdrive/Parking-v0", render_mode="human"))
c = DriveEnvConfig.from_options("parking", controller="lqr", residual=True)
e = gym.make("rrtdrive/Parking-v0", config=c, n_ref_points=5)
u = e.unwrapped.config
print("config= with n_ref_points=5:", u.controller, u.residual, u.n_ref_points, u.planner)
c2 = DriveEnvConfig.from_options("parking")
e2 = gym.make("rrtdrive/ParkingReverseIn-v0", config=c2)
print("ParkingReverseIn-v0 with config=: planner", e2.unwrapped.config.planner,
      "scenario_options", e2.unwrapped.config.scenario_options)
e3 = gym.make("rrtdrive/ParkingReverseIn-v0")
print("ParkingReverseIn-v0 without config: planner", e3.unwrapped.config.planner,
      "scenario_options", e3.unwrapped.config.scenario_options)
err("Parking-v0 config for overtake", lambda: gym.make("rrtdrive/Parking-v0",
    config=DriveEnvConfig.from_options("overtake")))
