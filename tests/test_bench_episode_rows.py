"""A closed-loop bench row says its plan's per-map set-up apart from its planning time."""

from __future__ import annotations

import math

from rrtdrive.bench.grid import BenchConfig, expand
from rrtdrive.bench.worker import execute_run


def test_an_episode_row_has_the_plans_setup_time_as_simulate_json_does():
    spec = expand(BenchConfig(scenarios=("overtake",), planners=("rrt-connect",),
                              controllers=("pure-pursuit",), seeds=1))[0]  # fmt: skip
    row = execute_run(spec)
    assert row["kind"] == "episode" and row["plan_status"] == "solved"
    setup, planning = row["setup_time_s"], row["planning_time_s"]
    assert isinstance(setup, float) and math.isfinite(setup) and setup >= 0.0
    assert isinstance(planning, float) and planning > 0.0
