"""Gymnasium environments of rrtdrive (installed as ``rrtdrive.envs``).

Importing this package (``import rrtdrive`` does) registers one gymnasium id per
scenario; nothing else happens. The registration uses entry-point strings, so
highway-env and pygame load only when an environment is made::

    import gymnasium as gym
    import rrtdrive  # registers rrtdrive/Parking-v0, ParkingReverseIn-v0, Overtake-v0,
                     # OvertakeTraffic-v0, ParallelParking-v0, UTurn-v0, Map-v0

    env = gym.make("rrtdrive/Parking-v0", controller="lqr", residual=True)

``gym.make("rrtdrive:rrtdrive/Parking-v0")`` imports rrtdrive by itself. The
environment is :class:`rrtdrive.envs.drive_env.DriveEnv`, its options
:class:`rrtdrive.envs.config.DriveEnvConfig`; the observation, action and reward
are in :mod:`~rrtdrive.envs.observation`, :mod:`~rrtdrive.envs.action` and
:mod:`~rrtdrive.envs.reward`. The MP4 recorder is
:class:`rrtdrive.envs.video.RecordMP4`. See ``docs/gym.md``.
"""

from __future__ import annotations

from gymnasium.envs.registration import register, registry

__all__ = ["ENV_IDS", "ENV_KWARGS", "ENTRY_POINT", "register_envs"]

ENTRY_POINT = "rrtdrive.envs.drive_env:DriveEnv"

#: Registered id -> scenario name of :func:`rrtdrive.sim.scenes.make_scenario` (or, for
#: ``Map-v0``, the map it drives unless ``scenario`` names another).
#: A new scenario is one more line here (``tests/test_envs.py`` checks that every
#: name in ``rrtdrive.sim.scenes.SCENARIOS`` has an id).
ENV_IDS: dict[str, str] = {
    "rrtdrive/Parking-v0": "parking",
    "rrtdrive/ParkingReverseIn-v0": "parking",
    "rrtdrive/Overtake-v0": "overtake",
    "rrtdrive/OvertakeTraffic-v0": "overtake-traffic",
    "rrtdrive/ParallelParking-v0": "parallel-parking",
    "rrtdrive/UTurn-v0": "u-turn",
    # Any map, start to goal: gym.make("rrtdrive/Map-v0", scenario="my_lot.json",
    # scenario_options={"reverse": True}); the built-in parking lot by default.
    "rrtdrive/Map-v0": "parking_lot",
}
#: Extra keyword arguments of an id, beyond its scenario (``gym.make`` arguments
#: override them). Parallel parking and the U-turn plan with Hybrid A*, the
#: reversing planner, directly: the default planner would reach the same search only
#: after its RRT-Connect stages fail, at each reset (tens of seconds on a U-turn).
#: Reverse-in parking is the parking scenario with ``reverse_in``, planned the same
#: way (a ``scenario_options`` given to ``gym.make`` replaces the registered one:
#: keep ``"reverse_in": True`` in it).
ENV_KWARGS: dict[str, dict[str, object]] = {
    "rrtdrive/ParkingReverseIn-v0": {
        "planner": "hybrid-a-star", "scenario_options": {"reverse_in": True},
    },
    "rrtdrive/ParallelParking-v0": {"planner": "hybrid-a-star"},
    "rrtdrive/UTurn-v0": {"planner": "hybrid-a-star"},
}


def register_envs() -> None:
    """Register every id of :data:`ENV_IDS` with gymnasium (idempotent)."""
    for env_id, scenario in ENV_IDS.items():
        if env_id not in registry:
            kwargs = {"scenario": scenario, **ENV_KWARGS.get(env_id, {})}
            register(id=env_id, entry_point=ENTRY_POINT, kwargs=kwargs)


register_envs()
