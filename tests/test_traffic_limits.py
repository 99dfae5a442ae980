"""Limits of the simulator and of overtake-traffic's road that used to run on without a word.

A lead car reaches the end of the 1.5 km road after (road - 10 m - its front) / speed
seconds; past that highway-env sent it round into the oncoming lane, and an episode
allowed to last longer was scored an overtake the car never made, or an at-fault
collision with the end of the road. A frequency of 1e11 Hz stepped for hours.
"""

from __future__ import annotations

import math

import gymnasium as gym
import pytest

import rrtdrive  # noqa: F401 - registers the gym ids
from rrtdrive.cli import main
from rrtdrive.sim.limits import MAX_SIM_FREQUENCY
from rrtdrive.sim.runner import EpisodeConfig, run_episode
from rrtdrive.sim.scenes import SimConfig
from rrtdrive.sim.tasks import make_scenario
from rrtdrive.sim.tasks.overtake_traffic import TRAFFIC_ROAD_LENGTH
from rrtdrive.types import InputError


def test_the_road_time_is_where_the_lead_car_s_front_is_10_m_from_the_end():
    task = make_scenario("overtake-traffic", 0, lead_speed=8.0, lead_model="constant")
    x, speed = task.lead
    front_at_end = x + task.vehicle.length / 2.0 + speed * task.road_time_s
    assert front_at_end == pytest.approx(TRAFFIC_ROAD_LENGTH - 10.0)
    assert task.max_time_s < task.road_time_s  # the default episode fits


@pytest.mark.parametrize("lead_speed", [0.5, 4.0, 8.9])
def test_an_episode_longer_than_the_road_is_refused_before_planning(lead_speed):
    task = make_scenario("overtake-traffic", 3, lead_speed=lead_speed)
    with pytest.raises(InputError, match=r"^episode\.max_time_s: at most \d+ s, got "):
        run_episode(task, "improved-rrt-connect", "pure-pursuit", 3,
                    EpisodeConfig(max_time_s=math.floor(task.road_time_s) + 1.0))  # fmt: skip
    # The gym env draws its own lead car (20-30 m ahead): 40 m more road than any has.
    too_long = task.road_time_s + 40.0 / lead_speed
    env = gym.make("rrtdrive/OvertakeTraffic-v0", scenario_options={"lead_speed": lead_speed},
                   max_time_s=too_long)
    with pytest.raises(InputError, match=r"^max_time_s: at most "):
        env.reset(seed=3)
    env.close()


def test_the_cli_names_max_time_and_the_lead_speed(capsys):
    code = main(["simulate", "overtake-traffic", "--seed", "0", "--lead-speed", "8",
                 "--deterministic", "--max-time", "200"])  # fmt: skip
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1
    assert err.startswith("rrtdrive simulate: error: --max-time: at most 182 s, got 200: the "
                          "lead car at 8 m/s reaches the end")


@pytest.mark.parametrize("flag", ["--plan-time", "--max-iterations"])
def test_plan_budgets_are_refused_where_nothing_is_planned_ahead(capsys, flag):
    assert main(["simulate", "overtake-traffic", flag, "1"]) == 2
    assert f"{flag}: overtake-traffic plans nothing ahead" in capsys.readouterr().err


def test_the_simulation_frequency_has_an_upper_bound(capsys):
    with pytest.raises(InputError, match=r"^sim\.simulation_frequency: "):
        SimConfig(simulation_frequency=MAX_SIM_FREQUENCY + 1)
    assert SimConfig(simulation_frequency=MAX_SIM_FREQUENCY).dt == 1.0 / MAX_SIM_FREQUENCY
    with pytest.raises(SystemExit) as exit_:
        main(["simulate", "overtake-traffic", "--frequency", "100000000000", "--max-time", "0.5"])
    assert exit_.value.code == 2
    assert "--frequency: expected an integer >= 15 and <= 1000 (Hz)" in capsys.readouterr().err
