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

from collections.abc import Mapping

from gymnasium.envs.registration import register, registry

from rrtdrive.types import InputError, brief_repr

__all__ = [
    "ENV_IDS",
    "ENV_KWARGS",
    "ENTRY_POINT",
    "MAP_ID",
    "REGISTERED_SCENARIO",
    "REGISTERED_SCENARIO_OPTIONS",
    "RegisteredDict",
    "RegisteredStr",
    "apply_registration",
    "is_registered_default",
    "plain_value",
    "register_envs",
    "scenario_text",
]

ENTRY_POINT = "rrtdrive.envs.drive_env:DriveEnv"

#: Registered id -> scenario name of :func:`rrtdrive.sim.scenes.make_scenario` (or, for
#: ``Map-v0``, the map it drives unless ``scenario`` names another).
#: A new scenario is one more line here (``tests/test_envs.py`` checks that every
#: name in ``rrtdrive.sim.tasks.SCENARIOS`` has an id).
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
#: Extra keyword arguments of an id, beyond its scenario: defaults (``gym.make``
#: arguments override them, and a whole ``config=`` replaces them). Parallel parking
#: and the U-turn plan with Hybrid A*, the reversing planner, directly: the default
#: planner would reach the same search only after its RRT-Connect stages fail, at
#: each reset (tens of seconds on a U-turn).
#: Reverse-in parking is the parking scenario with ``reverse_in``, planned the same
#: way. Registered ``scenario_options`` are merged with a caller's, key by key (the
#: caller's win): ``gym.make`` alone would replace the whole mapping, so a caller's
#: start jitter turned reverse-in parking into nose-in parking.
ENV_KWARGS: dict[str, dict[str, object]] = {
    "rrtdrive/ParkingReverseIn-v0": {
        "planner": "hybrid-a-star", "scenario_options": {"reverse_in": True},
    },
    "rrtdrive/ParallelParking-v0": {"planner": "hybrid-a-star"},
    "rrtdrive/UTurn-v0": {"planner": "hybrid-a-star"},
}


class RegisteredStr(str):
    """A string given by an id's registration, not by the caller of ``gym.make``.

    ``gym.make`` merges the registered keyword arguments with the caller's before
    the environment sees them; the marker type (equal to the plain value, and
    surviving gymnasium's deep copy and pickling) tells
    :class:`~rrtdrive.envs.drive_env.DriveEnv` which ones are the id's defaults, so
    that a caller's whole ``config=`` is not overridden by them.
    """

    __slots__ = ()


class RegisteredDict(dict):  # type: ignore[type-arg]
    """A mapping given by an id's registration (see :class:`RegisteredStr`)."""


def _registered(name: str, value: object) -> object:
    """``value`` marked as a registration default (a str or a mapping)."""
    if isinstance(value, str):
        return RegisteredStr(value)
    if isinstance(value, dict):
        return RegisteredDict(value)
    # A new kind of default needs a marker type, or a config= would not win over it.
    raise TypeError(f"ENV_KWARGS: no registration marker for {name}={value!r}")


def is_registered_default(value: object) -> bool:
    """Whether a ``gym.make`` keyword argument came from the id's registration.

    Parameters
    ----------
    value : object
        The argument's value as the environment receives it.

    Returns
    -------
    bool
        True for a :class:`RegisteredStr` or :class:`RegisteredDict`.
    """
    return isinstance(value, (RegisteredStr, RegisteredDict))


def plain_value(value: object) -> object:
    """``value`` without its registration marker (a plain ``str`` or ``dict``).

    Parameters
    ----------
    value : object
        Any value; one that carries no marker is returned as it is.

    Returns
    -------
    object
        A :class:`RegisteredDict` as a new (shallow) ``dict``, a
        :class:`RegisteredStr` as a ``str``, anything else unchanged.
    """
    if isinstance(value, RegisteredStr):
        return str.__str__(value)
    if isinstance(value, RegisteredDict):
        return dict(value)
    return value


def scenario_text(value: object) -> str:
    """A ``scenario`` as messages show it: a name quoted, a ``Map`` by its name.

    Parameters
    ----------
    value : object
        A scenario name (marked or not), a map, or anything a caller passed.

    Returns
    -------
    str
        ``'parking'``, ``the map 'lot'``, or a short repr of anything else.
    """
    value = plain_value(value)
    if isinstance(value, str):
        return repr(value)
    name = getattr(value, "name", None)
    return f"the map {name!r}" if isinstance(name, str) else brief_repr(value)


#: The keywords under which an id registers its ``scenario_options`` and (except
#: ``Map-v0``, which drives whatever map ``scenario`` names) its scenario once more; see
#: :func:`apply_registration`. Neither is an option of the environment.
REGISTERED_SCENARIO_OPTIONS = "registered_scenario_options"
REGISTERED_SCENARIO = "registered_scenario"
#: The id whose ``scenario`` a caller sets (a map name or file).
MAP_ID = "rrtdrive/Map-v0"


def _registration_values(key: str) -> list[object]:
    """What the ids register under ``key`` (:data:`REGISTERED_SCENARIO` or the options)."""
    if key == REGISTERED_SCENARIO:
        return [name for env_id, name in ENV_IDS.items() if env_id != MAP_ID]
    return [kw["scenario_options"] for kw in ENV_KWARGS.values() if "scenario_options" in kw]


def apply_registration(
    scenario: object, options: dict[str, object], merge: bool
) -> dict[str, object]:
    """``options`` with the id's registration keywords taken out and applied.

    The id's registered ``scenario_options`` go under the caller's, key by key, the
    caller's winning, when ``merge`` (no ``config=``); with a ``config=`` they give way
    to it, as every registered default does. A caller's ``scenario_options`` that is
    not a mapping is left for the configuration to refuse by name. A ``scenario`` the
    caller passes must be the id's own (``gym.make`` replaces it silently otherwise).

    Parameters
    ----------
    scenario : object
        The environment's ``scenario`` argument (the id's marked default, a caller's
        name or map, or ``None``).
    options : dict
        The other keyword arguments ``gym.make`` passed; not modified.
    merge : bool
        Merge the registered ``scenario_options`` under the caller's (true when no
        ``config=`` is given); else they are dropped.

    Returns
    -------
    dict
        A copy of ``options`` without the registration keywords, its
        ``scenario_options`` merged when ``merge``.

    Raises
    ------
    InputError
        When the caller passes a registration keyword, or a scenario of another id.
    """
    out = dict(options)
    registered = out.pop(REGISTERED_SCENARIO_OPTIONS, None)
    own = out.pop(REGISTERED_SCENARIO, None)
    # A spec restored from JSON (EnvSpec.to_json / from_json) has lost every marker, the
    # scenario's too: its plain values are still an id's registration.
    restored = scenario is not None and not is_registered_default(scenario)
    for key, value in ((REGISTERED_SCENARIO_OPTIONS, registered), (REGISTERED_SCENARIO, own)):
        if value is not None and not is_registered_default(value) and not (
            restored and value in _registration_values(key)
        ):
            raise InputError(f"{key}: set by an id's registration, not an option")
    if (
        own is not None and scenario is not None and plain_value(scenario) != plain_value(own)
        and not _names_the_id(plain_value(scenario), plain_value(own), registered)
    ):
        raise InputError(
            f"scenario: this id drives {plain_value(own)!r}, not {scenario_text(scenario)}; "
            f"make that scenario's own id, or {MAP_ID} for a map"
        )
    given = out.get("scenario_options")
    if registered is not None and merge and (given is None or isinstance(given, Mapping)):
        out["scenario_options"] = {**plain_value(registered), **plain_value(given or {})}  # type: ignore[dict-item]
    return out


def _names_the_id(scenario: object, own: object, registered: object) -> bool:
    """Whether ``scenario`` is a variant's name for the id's own scenario and options.

    ``parking-reverse-in`` on ``rrtdrive/ParkingReverseIn-v0`` (parking with
    ``reverse_in``): the id's own scenario under the name ``simulate`` and the bench use.
    """
    from rrtdrive.sim.tasks import SCENARIO_VARIANTS

    if not isinstance(scenario, str) or scenario not in SCENARIO_VARIANTS:
        return False
    base, options = SCENARIO_VARIANTS[scenario]
    given = plain_value(registered) if registered is not None else {}
    return base == own and isinstance(given, Mapping) and all(
        given.get(k) == v for k, v in options.items()
    )


def register_envs() -> None:
    """Register every id of :data:`ENV_IDS` with gymnasium (idempotent).

    The registered keyword arguments (the scenario and :data:`ENV_KWARGS`) are
    marked as defaults (:class:`RegisteredStr`, :class:`RegisteredDict`): the
    caller's keyword arguments replace them, and a caller's ``config=`` wins over
    them.
    """
    for env_id, scenario in ENV_IDS.items():
        if env_id not in registry:
            extra = ENV_KWARGS.get(env_id, {})
            kwargs = {
                REGISTERED_SCENARIO_OPTIONS if name == "scenario_options" else name:
                _registered(name, value)
                for name, value in {"scenario": scenario, **extra}.items()
            }  # fmt: skip
            if env_id != MAP_ID:
                kwargs[REGISTERED_SCENARIO] = RegisteredStr(scenario)
            register(id=env_id, entry_point=ENTRY_POINT, kwargs=kwargs)


register_envs()
