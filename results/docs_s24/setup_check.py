"""Constants of closed_loop.md's Setup section, as the code has them (session 24)."""
import dataclasses, math
from rrtdrive.types import VehicleParams
from rrtdrive.sim.tasks import make_scenario
from rrtdrive.controllers import make_controller, SpeedConfig
v = VehicleParams()
print("vehicle", {k: getattr(v, k) for k in ("length", "width", "wheelbase", "max_steer_rate")}, "max_steer deg", math.degrees(v.max_steer), "kappa_max", v.kappa_max)
for name in ("parking", "overtake"):
    t = make_scenario(name, 0)
    print(name, "v_max", t.default_speed().v_max, "max_time", getattr(t, "max_time_s", None))
for c in ("pure-pursuit", "stanley", "lqr"):
    ctrl = make_controller(c)
    print(c, {k: val for k, val in vars(ctrl).items() if isinstance(val, (int, float)) and not isinstance(val, bool)})
sp = SpeedConfig()
print("SpeedConfig", dataclasses.asdict(sp))
