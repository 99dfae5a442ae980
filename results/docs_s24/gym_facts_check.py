"""Check a few constants docs/gym.md states (session 24)."""
import math, gymnasium as gym, numpy as np, rrtdrive  # noqa: F401
from rrtdrive.envs.config import DriveEnvConfig
from rrtdrive.controllers import SpeedConfig
import rrtdrive.envs.drive_env as de
import rrtdrive.envs.action as act
cfg = DriveEnvConfig.from_options("parking")
print("limits", cfg.limits, "max_steer deg", math.degrees(cfg.max_steer))
print("steer limit deg", math.degrees(cfg.limits.steer_max) if hasattr(cfg.limits, "steer_max") else cfg.limits)
sc = cfg.scenario_for(0)
v = sc.vehicle
print("wheelbase", v.wheelbase, "kappa_max", v.kappa_max, "atan(L kappa_max) deg", math.degrees(math.atan(v.wheelbase * v.kappa_max)))
sp = cfg.speed_for(sc)
print("speed a_min a_max jerk_max jerk_brake_max", sp.a_min, sp.a_max, sp.jerk_max, sp.jerk_brake_max)
print("CUSP_REACH_M", de.CUSP_REACH_M, "RESIDUAL_FADE_M", getattr(act, "RESIDUAL_FADE_M", None))
env = gym.make("rrtdrive/Parking-v0")
print("obs shape", env.observation_space.shape)
lo, hi = env.observation_space.low, env.observation_space.high
print("speed bounds", lo[0], hi[0], "steer bounds deg", math.degrees(hi[1]))
print("time limits", {i: gym.make(i).unwrapped.config.scenario_for(0).max_time_s if hasattr(gym.make(i).unwrapped.config.scenario_for(0), "max_time_s") else None for i in ["rrtdrive/Parking-v0", "rrtdrive/Overtake-v0", "rrtdrive/OvertakeTraffic-v0"]})
