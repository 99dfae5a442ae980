"""A failure that a slow steering actuator causes says so, with its numbers.

A 0.01 rad/s car's failures read "the car's tightest turns need 57.8 m between them"
without naming the steering rate (session 50's extreme-car audit); the wheels then take
tens of metres to reach full lock at the planning speed.
"""

from __future__ import annotations

import json
import math
import subprocess
import sys

import pytest

from rrtdrive.maps import builtin_map, map_text
from rrtdrive.planning.smoothing import SmoothingConfig
from rrtdrive.planning.smoothing.config import STEER_RATE_DESIGN_SPEED, smoothing_for_car
from rrtdrive.planning.smoothing.drivable import slow_steering_note
from rrtdrive.types import VehicleParams


@pytest.mark.parametrize("rate", [None, 1.0, 0.4, 0.2])
def test_a_quick_enough_actuator_is_not_blamed(rate):
    car = VehicleParams(max_steer_rate=rate)
    assert slow_steering_note(smoothing_for_car(SmoothingConfig(), car)) == ""


@pytest.mark.parametrize("rate", [0.01, 0.03, 0.1])
def test_a_slow_actuator_is_named_with_its_run_to_full_lock(rate):
    car = VehicleParams(max_steer_rate=rate)
    note = slow_steering_note(smoothing_for_car(SmoothingConfig(), car))
    per_metre = rate / STEER_RATE_DESIGN_SPEED  # rad of steering a metre at the design speed
    run = math.atan(car.wheelbase * car.kappa_max) / per_metre
    assert run > car.min_turning_radius
    assert f"{per_metre:g} rad of steering a metre, so {run:.0f} m of road" in note


def test_the_cli_failure_of_a_slow_car_names_its_steering(tmp_path):
    doc = json.loads(map_text(builtin_map("parking_lot")))
    doc["vehicle"] = {"max_steer_rate": 0.01}
    (tmp_path / "slow.json").write_text(json.dumps(doc))
    p = subprocess.run([sys.executable, "-m", "rrtdrive", "plan", "slow.json",
                        "--max-iterations", "600"], cwd=tmp_path, capture_output=True,
                       text=True, timeout=300)  # fmt: skip
    assert p.returncode == 1 and "Traceback" not in p.stderr
    assert "the car's steering rate bounds the turns" in p.stdout, p.stdout
