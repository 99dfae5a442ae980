"""Bad input to the gym environments, and a caller's config against an id's defaults.

Fast: the environments are made (no planning) or reset on the overtake road and
stepped at most once.
"""

from __future__ import annotations

import re
import warnings
from collections.abc import Mapping

import gymnasium as gym
import numpy as np
import pytest

import rrtdrive  # noqa: F401  (registers the ids)
from rrtdrive.envs import ENV_IDS, ENV_KWARGS
from rrtdrive.envs.action import CommandLimits, action_command
from rrtdrive.envs.config import DriveEnvConfig
from rrtdrive.frozen import FrozenOptions
from rrtdrive.types import InputError


def _make(env_id: str, **kwargs: object) -> DriveEnvConfig:
    """The config ``gym.make(env_id, **kwargs)`` ends up with (the env closed)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        env = gym.make(env_id, **kwargs)
    try:
        return env.unwrapped.config
    finally:
        env.close()


# ---------------------------------------------------------------- config= vs registration

#: A config per id with registered defaults, whose fields differ from those defaults.
CALLER_CONFIGS = {
    "rrtdrive/ParkingReverseIn-v0": dict(
        scenario="parking",
        planner="hybrid-a-star",
        scenario_options={"reverse_in": True, "spot": (0, 0, 3)},
        controller="lqr",
    ),
    "rrtdrive/ParallelParking-v0": dict(
        scenario="parallel-parking", planner="improved-rrt-connect", controller="stanley"
    ),
    "rrtdrive/UTurn-v0": dict(scenario="u-turn", planner="improved-rrt-connect", residual=True),
}


def test_every_id_with_defaults_is_covered():
    assert sorted(CALLER_CONFIGS) == sorted(ENV_KWARGS)


@pytest.mark.parametrize("env_id", sorted(CALLER_CONFIGS))
def test_caller_config_wins_over_registered_defaults(env_id):
    options = dict(CALLER_CONFIGS[env_id])
    cfg = DriveEnvConfig.from_options(options.pop("scenario"), **options)
    got = _make(env_id, config=cfg)
    assert got == cfg
    assert got.planner == cfg.planner and got.scenario_options == cfg.scenario_options


@pytest.mark.parametrize("env_id", sorted(CALLER_CONFIGS))
def test_caller_keywords_win_over_config_and_defaults(env_id):
    options = dict(CALLER_CONFIGS[env_id])
    cfg = DriveEnvConfig.from_options(options.pop("scenario"), **options)
    # The registered planner named explicitly by the caller is the caller's choice.
    got = _make(env_id, config=cfg, planner="hybrid-a-star", n_ref_points=4)
    assert got == cfg.with_options(planner="hybrid-a-star", n_ref_points=4)


@pytest.mark.parametrize("env_id", sorted(ENV_KWARGS))
def test_registered_defaults_apply_without_config(env_id):
    got = _make(env_id)
    for key, value in ENV_KWARGS[env_id].items():
        assert getattr(got, key) == value
        # Plain values in the config, not the registration's marker types; option
        # mappings read-only (FrozenOptions, as every config's).
        kind = FrozenOptions if isinstance(value, Mapping) else type(value)
        assert type(getattr(got, key)) is kind
    assert _make(env_id, planner="rrt-connect").planner == "rrt-connect"


def test_the_benchs_parking_reverse_in_name_is_a_gym_scenario_too():
    # One name for reverse-in parking wherever a scenario is named (bench took it first):
    # the parking scenario with reverse_in, the caller's options over it (an id keeps its
    # own scenario: rrtdrive/ParkingReverseIn-v0 is this one's).
    from rrtdrive.envs.drive_env import DriveEnv

    got = DriveEnvConfig.from_options(scenario="parking-reverse-in")
    assert (got.scenario, got.scenario_options) == ("parking", {"reverse_in": True})
    got = DriveEnvConfig.from_options(
        scenario="parking-reverse-in", scenario_options={"spot": (0, 0, 3)}
    )
    assert got.scenario_options == {"reverse_in": True, "spot": (0, 0, 3)}
    task = got.scenario_for(0)
    assert task.reverse_in and task.reverse
    # Not a mapping: refused as for any scenario (it was dropped); the variant's own
    # option is not overridden under its name (nose-in parking called reverse-in).
    with pytest.raises(InputError, match=r"^scenario_options: expected a mapping"):
        DriveEnvConfig.from_options(scenario="parking-reverse-in", scenario_options=[1])
    with pytest.raises(InputError, match=r"^scenario_options.reverse_in: parking-reverse-in is"):
        DriveEnvConfig.from_options(
            scenario="parking-reverse-in", scenario_options={"reverse_in": False}
        )
    from rrtdrive.sim.tasks import make_variant

    with pytest.raises(InputError, match="did you mean 'parking-reverse-in'"):
        make_variant("parking-revers-in")
    env = DriveEnv("parking-reverse-in")
    try:
        env.reset(seed=0)
        assert len(env.path.cusps) >= 1  # entered backwards
    finally:
        env.close()


def test_registered_scenario_options_merge_with_the_callers():
    # gym.make alone replaces the registered mapping: a caller's start jitter turned
    # reverse-in parking into nose-in parking (a helper's audit, session 29). Now the
    # caller's keys go over the registered ones, key by key.
    got = _make("rrtdrive/ParkingReverseIn-v0", scenario_options={"spot": (0, 0, 3)})
    assert got.scenario_options == {"reverse_in": True, "spot": (0, 0, 3)}
    got = _make("rrtdrive/ParkingReverseIn-v0", scenario_options={"reverse_in": False})
    assert got.scenario_options == {"reverse_in": False}  # the caller's value wins
    assert _make("rrtdrive/ParkingReverseIn-v0", scenario_options=None).scenario_options == {
        "reverse_in": True
    }
    # The registration's keyword is not an option for callers.
    with pytest.raises(InputError, match=r"^registered_scenario_options: set by an id's"):
        _make("rrtdrive/Parking-v0", registered_scenario_options={"reverse_in": True})
    with pytest.raises(InputError, match=r"^scenario_options: expected a mapping"):
        _make("rrtdrive/ParkingReverseIn-v0", scenario_options=5)


def test_a_scenario_of_another_id_is_refused_but_map_v0_takes_any_map():
    # gym.make replaced the id's scenario silently: Parking-v0 drove the overtake road
    # (a helper's audit, session 29), while a config of another scenario was refused.
    with pytest.raises(InputError, match=r"^scenario: this id drives 'parking', not 'overtake'"):
        _make("rrtdrive/Parking-v0", scenario="overtake")
    assert _make("rrtdrive/Parking-v0", scenario="parking").scenario == "parking"
    assert _make("rrtdrive/Map-v0", scenario="kerbside").map.name == "kerbside"
    with pytest.raises(InputError, match=r"^registered_scenario: set by an id's"):
        _make("rrtdrive/Overtake-v0", registered_scenario="overtake")


def test_reverse_in_id_takes_its_own_scenario_under_its_variant_name():
    # parking-reverse-in, the name simulate and the bench give it, was refused by the
    # very id that drives it (session 38); on Parking-v0 it is still another scenario.
    named = _make("rrtdrive/ParkingReverseIn-v0", scenario="parking-reverse-in")
    plain = _make("rrtdrive/ParkingReverseIn-v0")
    assert (named.scenario, named.scenario_options) == (plain.scenario, plain.scenario_options)
    assert named.scenario_options == {"reverse_in": True}
    with pytest.raises(InputError, match=r"^scenario: this id drives 'parking', not "):
        _make("rrtdrive/Parking-v0", scenario="parking-reverse-in")


def test_map_v0_with_a_scenario_config_names_the_config_not_its_default_map():
    # It said "scenario: 'parking_lot' differs from config.scenario 'parking'": the
    # id's default map, which the caller never gave.
    cfg = DriveEnvConfig.from_options("parking")
    with pytest.raises(InputError, match=r"^config\.scenario: 'parking' is a scenario, not a map"):
        gym.make("rrtdrive/Map-v0", config=cfg)
    assert gym.make("rrtdrive/Map-v0", scenario="parking", config=cfg).unwrapped.config == cfg


@pytest.mark.parametrize("env_id", [i for i in ENV_IDS if not i.endswith("/Map-v0")])
def test_a_spec_saved_as_json_makes_the_same_env(env_id):
    # EnvSpec.to_json drops the registration markers; the restored spec was refused
    # ("registered_scenario: set by an id's registration, not an option").
    from gymnasium.envs.registration import EnvSpec

    made = gym.make(env_id)
    again = gym.make(EnvSpec.from_json(made.spec.to_json()))
    assert again.unwrapped.config == made.unwrapped.config
    first, _ = made.reset(seed=3)
    second, _ = again.reset(seed=3)
    assert np.array_equal(first, second)
    made.close()
    again.close()


def test_a_jittered_reverse_in_episode_still_backs_into_the_bay():
    env = gym.make("rrtdrive/ParkingReverseIn-v0", scenario_options={"jitter": (0.5, 0.5, 0.05)})
    try:
        env.reset(seed=0)
        path = env.unwrapped.path
        assert env.unwrapped.config.scenario_options["reverse_in"]
        assert -1 in path.gears and len(path.cusps) >= 1  # it reverses into the bay
    finally:
        env.close()


def test_config_of_another_scenario_is_refused_but_map_v0_takes_any_map():
    cfg = DriveEnvConfig.from_options("overtake")
    with pytest.raises(InputError, match=r"^scenario: 'parking' differs from config\.scenario"):
        _make("rrtdrive/Parking-v0", config=cfg)
    with pytest.raises(InputError, match=r"^config\.scenario: 'overtake' is a scenario, not"):
        _make("rrtdrive/Map-v0", config=cfg)  # a scenario, not a map
    kerb = DriveEnvConfig.from_options("kerbside", scenario_options={"reverse": True})
    assert _make("rrtdrive/Map-v0", config=kerb) == kerb
    assert ENV_IDS["rrtdrive/Map-v0"] == "parking_lot"


def test_a_map_built_in_python_is_a_map_scenario():
    from rrtdrive.maps import Map, builtin_map

    m = builtin_map("kerbside")
    mine = Map("my_kerb", m.bounds, m.obstacles, m.start, m.goal)
    cfg = _make("rrtdrive/Map-v0", scenario=mine)
    assert cfg.map is mine and cfg.scenario_name == "my_kerb" and cfg.replan is None
    assert cfg.scenario_for(3).map == mine
    # Messages name it, not its repr of every obstacle.
    other_id = r"^scenario: this id drives 'parking', not the map 'my_kerb'; "
    with pytest.raises(InputError, match=other_id):
        _make("rrtdrive/Parking-v0", scenario=mine)
    overtake = DriveEnvConfig.from_options("overtake")
    with pytest.raises(InputError, match=r"^scenario: the map 'my_kerb' differs from config"):
        _make("rrtdrive/Map-v0", scenario=mine, config=overtake)
    kinds = r"^scenario: expected a scenario or map name, a \.json file or a rrtdrive\.Map, got 3"
    with pytest.raises(InputError, match=kinds):
        _make("rrtdrive/Map-v0", scenario=3.5)
    with pytest.raises(InputError, match=r"^replan_options: only the overtake-traffic scenario"):
        _make("rrtdrive/Map-v0", scenario=mine, replan_options={"budget_s": 0.1})


def test_config_of_the_wrong_type_names_config():
    with pytest.raises(InputError, match=r"^config: expected a DriveEnvConfig, got dict"):
        _make("rrtdrive/Parking-v0", config={"planner": "rrt"})


def test_duplicate_controller_options_name_the_key():
    with pytest.raises(InputError, match=r"^controller_options\.speed: "):
        DriveEnvConfig.from_options("overtake", controller_options={"speed": 5})
    with pytest.raises(InputError, match=r"^controller_options\.vehicle: "):
        DriveEnvConfig.from_options("overtake", controller_options={"vehicle": None})


def test_an_unknown_controller_option_names_the_key():
    # As speed_options does: the key inside the mapping, and what the controller takes.
    with pytest.raises(InputError, match=r"^controller_options\.kk: unknown option of PurePursuit"):
        gym.make("rrtdrive/Overtake-v0", controller_options={"kk": 1})


@pytest.mark.parametrize(
    ("options", "message"),
    [({"v_max": 100}, r"^speed_options\.v_max: 100 m/s is above the simulated car's top "
                      r"speed, 40 m/s$"),
     ({"v_max_reverse": 12}, r"^speed_options\.v_max_reverse: 12 m/s is above the simulated "
                             r"car's top speed in reverse, 10 m/s$")],
)
def test_a_speed_the_simulated_car_cannot_reach_is_named(options, message):
    # The car clips its speed at 40 m/s (10 in reverse): v_max 100 was accepted and never
    # driven, beyond the observation's own 40 m/s bound too.
    with pytest.raises(InputError, match=message):
        gym.make("rrtdrive/Overtake-v0", speed_options=options)
    gym.make("rrtdrive/Overtake-v0", speed_options={"v_max": 40}).close()  # the top itself


# ---------------------------------------------------------------- actions

LIMITS = CommandLimits(a_min=-4.0, a_max=2.0, steer_limit=0.4)

def _id(action: object) -> str:
    """A test id that is the same in every process (an ``object()``'s repr has its address)."""
    return re.sub(r" at 0x[0-9a-f]+", "", repr(action))


BAD_ACTIONS = [
    "ab",
    ["0.5", "0.5"],
    np.array(["0.5", "0.5"]),
    "0.5",
    None,
    [None, 0.5],
    object(),
    [object(), 0.5],
    [True, False],
    [[0.5], [0.5, 0.5]],
    np.array([0.5, "x"], dtype=object),
    [0.5, float("nan")],
    [float("inf"), 0.0],
    [0.5, 0.5, 0.5],
    [],
]


@pytest.mark.parametrize("action", BAD_ACTIONS, ids=_id)
def test_action_command_refuses_non_numbers_naming_action(action):
    with pytest.raises(InputError, match=r"^action: expected two finite numbers"):
        action_command(action, LIMITS)


@pytest.mark.parametrize(
    "action",
    [[0.5, -1.0], (0.5, -1.0), np.array([0.5, -1.0], dtype=np.float32), [1, -1],
     np.array([0.5, -1.0], dtype=object)],
    ids=_id,
)
def test_action_command_takes_numbers(action):
    a, d = action_command(action, LIMITS)
    assert (a, d) == pytest.approx((1.0 if action[0] == 0.5 else 2.0, -0.4))


@pytest.fixture(scope="module")
def overtake_env():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        env = gym.make("rrtdrive/Overtake-v0")
    yield env
    env.close()


@pytest.mark.parametrize(
    "action", ["ab", ["0.5", "0.5"], None, object(), [float("nan"), 0.0], [0.0]], ids=_id
)
def test_step_refuses_bad_action_naming_action(overtake_env, action):
    overtake_env.reset(seed=0)
    with pytest.raises(InputError, match=r"^action: "):
        overtake_env.step(action)
    # Refused before any simulation step: the episode goes on.
    obs, *_ = overtake_env.step(np.zeros(2, dtype=np.float32))
    assert overtake_env.observation_space.contains(obs)


def test_planner_options_reach_the_episodes_planner():
    # The gym's planner takes its config's fields, as `rrtdrive plan --planner-option`: the
    # reset's path is the one plan_scenario makes with the same options.
    import numpy as np

    from rrtdrive.envs.drive_env import DriveEnv
    from rrtdrive.sim.tasks.base import plan_scenario

    options = {"curve": "arcs"}
    env = DriveEnv("u-turn", planner="hybrid-a-star", planner_options=options)
    plain = DriveEnv("u-turn", planner="hybrid-a-star")
    try:
        env.reset(seed=0, options={"episode_seed": 3})
        plain.reset(seed=0, options={"episode_seed": 3})
        task = env.config.scenario_for(3)
        want = plan_scenario(task, "hybrid-a-star", 3, env.config.budget, options)
        np.testing.assert_array_equal(env.path.samples, want.path.samples)
        assert not np.array_equal(env.path.samples, plain.path.samples)
    finally:
        env.close()
        plain.close()
    with pytest.raises(InputError, match=r"^planner_options.bogus: unknown option for"):
        DriveEnvConfig.from_options(planner_options={"bogus": 1})
    with pytest.raises(InputError, match=r"^planner_options: overtake-traffic re-plans"):
        DriveEnvConfig.from_options(scenario="overtake-traffic", planner_options={"step": 3})


@pytest.mark.parametrize(
    ("options", "message"),
    [
        # The config's own "replan.rate_hz" named no key the user wrote (an audit).
        ({"rate_hz": -1}, r"^replan_options\.rate_hz: must lie in \[2, 5\] Hz, got -1$"),
        ({"bogus": 1}, r"^replan_options\.bogus: unknown field of ReplanConfig"),
    ],
)
def test_bad_replan_options_name_the_key_as_given(options, message):
    with pytest.raises(InputError, match=message):
        _make("rrtdrive/OvertakeTraffic-v0", replan_options=options)
