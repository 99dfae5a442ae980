"""Options of :class:`~rrtdrive.envs.drive_env.DriveEnv`: one frozen, validated dataclass.

The keyword arguments of ``gym.make("rrtdrive/...", ...)`` become a
:class:`DriveEnvConfig` (:meth:`DriveEnvConfig.from_options`); an unknown key or a
bad value raises :class:`~rrtdrive.types.InputError` naming the field. The config
also builds what each episode needs from its options: the scenario of a seed, its
speed-loop settings and the tracking controller.
"""

from __future__ import annotations

import dataclasses
import math
import os
import warnings
from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from typing import Any

import numpy as np

from rrtdrive.cli_args import flags_for, planner_option_flags
from rrtdrive.controllers import CONTROLLERS, SpeedConfig, TrackingController, make_controller
from rrtdrive.envs import is_registered_default, scenario_text
from rrtdrive.envs.action import CommandLimits
from rrtdrive.envs.reward import RewardWeights
from rrtdrive.frozen import FrozenOptions, config_of
from rrtdrive.maps import Map, map_from_json
from rrtdrive.planning import PLANNERS, forward_only_note, make_planner, reverses, unknown_planner
from rrtdrive.sim.limits import MAX_REVERSE_SPEED, MAX_SPEED
from rrtdrive.sim.loop import require_episode_time
from rrtdrive.sim.scenes import SimConfig
from rrtdrive.sim.tasks import (
    DEFAULT_PLANNER,
    REPLANNING_SCENARIOS,
    SCENARIO_OPTIONS,
    SCENARIO_VARIANTS,
    SCENARIOS,
    TASKS,
    CustomTask,
    make_scenario,
    scenario_map,
)
from rrtdrive.sim.tasks import Task as Scenario
from rrtdrive.types import (
    Budget,
    InputError,
    InputWarning,
    brief_repr,
    require_int,
)
from rrtdrive.vehicle_json import vehicle_from_json

__all__ = ["DriveEnvConfig"]


def _require_number(name: str, value: Any, *, positive: bool = True) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise InputError(f"{name}: expected a number, got {value!r}")
    if not math.isfinite(value) or (positive and value <= 0):
        raise InputError(f"{name}: must be a finite number > 0, got {value!r}")
    return float(value)


def _require_mapping(name: str, value: Any) -> dict[str, Any]:
    if value is None:
        return {}
    if not isinstance(value, Mapping):
        raise InputError(f"{name}: expected a mapping, got {value!r}")
    for key in value:
        if not isinstance(key, str):  # they become keyword arguments
            raise InputError(f"{name}: keys must be option names (strings), got {key!r}")
    return dict(value)


def _frozen(name: str, value: Any) -> FrozenOptions:
    """A checked option mapping, read-only and hashable as the frozen config that holds it."""
    return FrozenOptions(_require_mapping(name, value))


def _planner_options(options: object, planner: str, replan: object) -> dict[str, Any]:
    """``planner_options`` checked by building the planner once (errors name the key)."""
    checked = _require_mapping("planner_options", options)
    if checked and replan is not None:
        raise InputError("planner_options: overtake-traffic re-plans with its own planner; "
                         "give replan_options={'planner_options': ...}")
    with flags_for(planner_option_flags(checked, "planner_options", sep=".")):
        make_planner(planner, **checked)
    return checked


def _check_fields(name: str, options: Mapping[str, Any], cls: type) -> None:
    """Raise naming ``name.key`` for a key that is not an init field of dataclass ``cls``."""
    known = [f.name for f in fields(cls) if f.init]
    for key in options:
        if key not in known:
            raise InputError(
                f"{name}.{key}: unknown field of {cls.__name__}; choose from {known}"
            )


@dataclass(frozen=True)
class DriveEnvConfig:
    """The options of a :class:`~rrtdrive.envs.drive_env.DriveEnv` (``gym.make`` kwargs).

    Every field is validated on construction; the mappings are copied.

    Parameters
    ----------
    scenario : str or Map
        Scenario name (``parking``, ``overtake``, ``overtake-traffic``,
        ``parallel-parking``, ``u-turn``), or a map (a built-in name, a ``.json``
        file or a :class:`~rrtdrive.maps.Map` built in Python) driven from its start
        to its goal, as ``rrtdrive simulate MAP``.
    planner : str
        Registered planner that plans each episode's path.
    controller : str
        ``pure-pursuit``, ``stanley`` or ``lqr``: the controller of residual mode.
    residual : bool
        The action is a correction added to the controller's command.
    residual_scale : float
        Residual mode: fraction of the full command range the action spans.
    n_ref_points : int
        Number K of reference points in the observation.
    ref_spacing : float
        Arc length between reference points, metres.
    n_vehicles : int
        Number M of other vehicles in the observation (0: none, the default).
    vehicle_range : float
        Vehicles further than this from the rear axle (m) are not observed.
    action_repeat : int
        Simulation steps per environment step (the controller still runs every
        simulation step; the agent's action is held).
    simulation_frequency : int
        Physics and control rate in Hz (>= 15).
    max_time_s : float, optional
        Time limit of an episode (default: the scenario's, 120 s parking, 60 s overtake).
    max_cte : float, optional
        End the episode when the rear axle is farther than this from the path
        (metres; ``None``: never).
    reward : RewardWeights or mapping, optional
        Reward weights (see :class:`~rrtdrive.envs.reward.RewardWeights`); stored
        as :class:`~rrtdrive.envs.reward.RewardWeights`.
    scenario_options : mapping, optional
        Keyword arguments of :func:`~rrtdrive.sim.scenes.make_scenario` (``jitter``,
        ``spot``, ``oncoming``; ``density``, ``lead_speed``, ``lead_model`` for
        ``overtake-traffic``); for a map, ``reverse`` (gear changes allowed).
    replan_options : mapping, optional
        ``overtake-traffic``: :class:`~rrtdrive.sim.replanning.ReplanConfig` fields.
        The reference path is then re-planned in the loop
        (:class:`~rrtdrive.sim.replanning.TrafficDriver`, the runner's driver): the
        observation follows the current reference, the residual is added to the
        driver's command, progress is counted across reference switches, and the
        episode ends (``"completed"``) when the overtake is complete.
    controller_options : mapping, optional
        Controller gains.
    planner_options : mapping, optional
        Fields of the planner's config (``{"reverse_detour_tree": False}``), as
        ``rrtdrive plan --planner-option``; not for ``overtake-traffic`` (its re-planner
        takes ``replan_options["planner_options"]``).
    speed_options : mapping, optional
        :class:`~rrtdrive.controllers.SpeedConfig` fields (``v_max`` defaults to the
        scenario's).
    budget : Budget, optional
        Planning budget per episode (``None``: ``Budget()``).
    seed_range : tuple of int
        Episode seeds are drawn uniformly from ``[lo, hi)`` with the env's
        ``np_random`` unless ``reset(options={"episode_seed": n})`` names one.

    Attributes
    ----------
    replan : ReplanConfig or None
        ``overtake-traffic``: the re-planning settings from ``replan_options``.
    limits : CommandLimits
        The command range of the action (the speed loop's acceleration limits and
        the controller's steering limit).
    max_steer : float
        The car's steering limit (rad), the bound of the observed steering angle.
    map : Map or None
        The map a map scenario drives (read once), else ``None``.

    Examples
    --------
    >>> cfg = DriveEnvConfig.from_options("overtake", residual=True, reward={"cte": 100.0})
    >>> cfg.residual, cfg.reward.cte, cfg.sim_config.simulation_frequency
    (True, 100.0, 20)
    >>> DriveEnvConfig.from_options("overtake", residul=True)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    rrtdrive.types.InputError: residul: unknown option; choose from ['scenario', ...]
    """

    scenario: str | Map = "parking"
    planner: str = DEFAULT_PLANNER
    controller: str = "pure-pursuit"
    residual: bool = False
    residual_scale: float = 0.25
    n_ref_points: int = 10
    ref_spacing: float = 1.5
    n_vehicles: int = 0
    vehicle_range: float = 100.0
    action_repeat: int = 1
    simulation_frequency: int = 20
    max_time_s: float | None = None
    max_cte: float | None = 10.0
    reward: RewardWeights | Mapping[str, float] | None = None
    scenario_options: Mapping[str, Any] | None = None
    replan_options: Mapping[str, Any] | None = None
    controller_options: Mapping[str, Any] | None = None
    planner_options: Mapping[str, Any] | None = None
    speed_options: Mapping[str, Any] | None = None
    budget: Budget | None = None
    seed_range: tuple[int, int] = (0, 2**31 - 1)
    replan: Any = field(init=False, repr=False, compare=False)
    limits: CommandLimits = field(init=False, repr=False, compare=False)
    max_steer: float = field(init=False, repr=False, compare=False)
    map: Map | None = field(init=False, repr=False, compare=False, default=None)

    def __post_init__(self) -> None:
        def put(name: str, value: Any) -> None:
            object.__setattr__(self, name, value)

        scenario, planner, controller = self.scenario, self.planner, self.controller
        if isinstance(scenario, os.PathLike):  # a map file as save_map takes it
            scenario = os.fspath(scenario)
            put("scenario", scenario)
        if isinstance(scenario, Mapping) and "obstacles" in scenario:
            scenario = map_of_fields(scenario)
            put("scenario", scenario)
        if isinstance(scenario, Map):
            put("map", scenario)  # validated when it was made
        elif not isinstance(scenario, str):
            raise InputError(
                "scenario: expected a scenario or map name, a .json file or a rrtdrive.Map, "
                f"got {brief_repr(scenario)}"
            )
        elif scenario in SCENARIO_VARIANTS:  # parking-reverse-in: its options and the given
            name, (scenario, options) = scenario, SCENARIO_VARIANTS[scenario]
            given = self.scenario_options
            if isinstance(given, Mapping):
                for key, value in options.items():
                    if key in given and given[key] != value:
                        raise InputError(
                            f"scenario_options.{key}: {name} is {scenario} with {key}={value!r}; "
                            f"for {key}={given[key]!r} give the scenario {scenario!r}"
                        )
                given = {**options, **given}
            put("scenario", scenario)
            put("scenario_options", options if given is None else given)
        elif scenario not in SCENARIOS:
            put("map", scenario_map("scenario", scenario, (), SCENARIO_VARIANTS))
        if not isinstance(planner, str) or planner not in PLANNERS:
            raise unknown_planner("planner", planner)
        if not isinstance(controller, str) or controller not in CONTROLLERS:
            raise InputError(
                f"controller: unknown controller {controller!r}; "
                f"choose from {', '.join(sorted(CONTROLLERS))}"
            )
        if not isinstance(self.residual, (bool, np.bool_)):  # numpy's too, as for the ints
            raise InputError(f"residual: expected True or False, got {self.residual!r}")
        put("residual", bool(self.residual))
        put("residual_scale", _require_number("residual_scale", self.residual_scale))
        put("n_ref_points", require_int("n_ref_points", self.n_ref_points, 1, 200))
        put("ref_spacing", _require_number("ref_spacing", self.ref_spacing))
        put("n_vehicles", require_int("n_vehicles", self.n_vehicles, 0, 50))
        put("vehicle_range", _require_number("vehicle_range", self.vehicle_range))
        put("action_repeat", require_int("action_repeat", self.action_repeat, 1, 1000))
        put("simulation_frequency", self.sim_config.simulation_frequency)
        if self.max_time_s is not None:
            put("max_time_s", require_episode_time("max_time_s", self.max_time_s))
        if self.max_cte is not None:
            put("max_cte", _require_number("max_cte", self.max_cte))
        put("reward", RewardWeights.from_any(self.reward))
        put("scenario_options", _frozen("scenario_options", self.scenario_options))
        replan_options = _require_mapping("replan_options", self.replan_options)
        put("replan_options", FrozenOptions(replan_options))
        replan = None
        # None: the task plans once (a map's too).
        replan_config = None if self.map is not None else TASKS[self.scenario].REPLAN_CONFIG
        if replan_config is not None:
            _check_fields("replan_options", replan_options, replan_config)
            try:
                replan = replan_config(**replan_options)
            except TypeError as exc:
                raise InputError(f"replan_options: {exc}") from None
            except InputError as exc:
                # The config names its fields "replan.rate_hz"; here they are keys of
                # replan_options, as an unknown key's error says (an audit).
                text = str(exc)
                if text.startswith("replan."):
                    raise InputError("replan_options." + text[len("replan."):]) from None
                raise
        elif replan_options:
            raise InputError(
                f"replan_options: only the {' or '.join(REPLANNING_SCENARIOS)} scenario re-plans"
            )
        put("replan", replan)
        put("controller_options", _frozen("controller_options", self.controller_options))
        checked = _planner_options(self.planner_options, planner, replan)
        put("planner_options", FrozenOptions(checked))
        put("speed_options", _frozen("speed_options", self.speed_options))
        put("budget", Budget() if self.budget is None else config_of(Budget, self.budget, "budget"))
        seed_range = self.seed_range
        if (
            not isinstance(seed_range, (tuple, list))
            or len(seed_range) != 2
            or any(isinstance(v, bool) or not isinstance(v, (int, np.integer)) for v in seed_range)
            or not 0 <= seed_range[0] < seed_range[1] <= 2**63
        ):
            raise InputError(f"seed_range: need integers 0 <= lo < hi <= 2**63, got {seed_range!r}")
        put("seed_range", (int(seed_range[0]), int(seed_range[1])))

        # Validate the options once, on a scenario and controller of seed 0.
        probe = self.scenario_for(0)
        if probe.reverse and not reverses(self.planner):
            # Its episodes plan forward and crash where the scenario needs a gear change.
            asked = f"the {self.scenario_name} scenario's gear changes take"
            warnings.warn(forward_only_note(self.planner, asked=asked), InputWarning,
                          stacklevel=3)  # fmt: skip
        speed = self.speed_for(probe)
        probe_ctrl = self.controller_for(probe, speed)
        put("limits", CommandLimits(speed.a_min, speed.a_max, probe_ctrl.steer_limit))
        put("max_steer", probe.vehicle.max_steer)

    # ------------------------------------------------------------------ construction

    @classmethod
    def option_names(cls) -> list[str]:
        """The options (``gym.make`` keyword arguments besides ``render_mode``)."""
        return [f.name for f in fields(cls) if f.init]

    @classmethod
    def from_options(cls, scenario: str | Map = "parking", **options: Any) -> DriveEnvConfig:
        """The config of ``gym.make`` keyword arguments.

        Raises
        ------
        InputError
            For an unknown option (naming it) or a bad value (naming the field).
        """
        cls._check_keys(options)
        return cls(scenario=scenario, **options)

    def with_options(self, **options: Any) -> DriveEnvConfig:
        """A copy with some options replaced (validated again)."""
        self._check_keys(options)
        return dataclasses.replace(self, **options) if options else self

    @classmethod
    def _check_keys(cls, options: Mapping[str, Any]) -> None:
        known = cls.option_names()
        for key in options:
            if key not in known:
                raise InputError(f"{key}: unknown option; choose from {known}")

    # ------------------------------------------------------------------ per episode

    @property
    def scenario_name(self) -> str:
        """The scenario's name as episodes report it (a :class:`Map`'s own ``name``)."""
        return self.map.name if isinstance(self.scenario, Map) else self.scenario

    @property
    def sim_config(self) -> SimConfig:
        """The simulation settings (:class:`~rrtdrive.sim.scenes.SimConfig`)."""
        try:
            return SimConfig(simulation_frequency=self.simulation_frequency)
        except InputError as exc:  # named as this config's field, not SimConfig's
            raise InputError(str(exc).removeprefix("sim.")) from None

    def scenario_for(self, seed: int) -> Scenario:
        """The scenario of episode seed ``seed`` with ``scenario_options``."""
        options: dict[str, Any] = self.scenario_options  # type: ignore[assignment]
        car = options.get("vehicle")
        if isinstance(car, Mapping):
            # The car's fields, as EnvSpec.to_json keeps a VehicleParams (its round
            # trip failed; an audit).
            options = {**options, "vehicle": vehicle_from_json(car, "scenario_options.vehicle")}
        if self.map is not None:
            return _map_task(self.map, seed, options)
        for key in options:
            if key not in SCENARIO_OPTIONS:
                raise InputError(
                    f"scenario_options.{key}: unknown option of make_scenario; "
                    f"choose from {', '.join(SCENARIO_OPTIONS)}"
                )
        try:
            return make_scenario(self.scenario, seed, **options)
        except InputError as exc:
            # make_scenario names the argument ("spot: ..."); say where it came from.
            raise InputError(f"scenario_options.{exc}") from None
        except TypeError as exc:
            # A value of the wrong shape failed inside make_scenario: find which one.
            for key, value in options.items():
                try:
                    make_scenario(self.scenario, seed, **{key: value})
                except TypeError as one:
                    raise InputError(
                        f"scenario_options.{key}: bad value {value!r} ({one})"
                    ) from None
                except InputError:
                    pass
            raise InputError(f"scenario_options: {exc}") from None

    def speed_for(self, scenario: Scenario) -> SpeedConfig:
        """The speed loop's settings for ``scenario`` with ``speed_options``.

        The task's default settings (:meth:`~rrtdrive.sim.tasks.Task.default_speed`)
        with the options replacing some of their fields.
        """
        base = dataclasses.asdict(scenario.default_speed())
        _check_fields("speed_options", self.speed_options, SpeedConfig)  # type: ignore[arg-type]
        options = {**base, **self.speed_options}  # type: ignore[dict-item]
        try:
            speed = SpeedConfig(**options)
        except TypeError as exc:
            raise InputError(f"speed_options: {exc}") from None
        except InputError as exc:  # SpeedConfig names its fields "speed.v_max"
            raise InputError(f"speed_options.{str(exc).removeprefix('speed.')}") from None
        # The simulated car clips its speed there: a higher one would be silently not driven.
        for name, top in (("v_max", MAX_SPEED), ("v_max_reverse", MAX_REVERSE_SPEED)):
            if getattr(speed, name) > top:
                raise InputError(
                    f"speed_options.{name}: {getattr(speed, name):g} m/s is above the "
                    f"simulated car's top speed{' in reverse' if 'reverse' in name else ''}, "
                    f"{top:g} m/s"
                )
        return speed

    def controller_for(self, scenario: Scenario, speed: SpeedConfig) -> TrackingController:
        """The tracking controller for ``scenario`` with ``controller_options``."""
        options = self.controller_options or {}  # a dict after __post_init__
        for key in ("vehicle", "speed"):
            # The scenario gives the car and speed_options the speed loop; a duplicate
            # keyword would fail as a TypeError naming neither.
            if key in options:
                raise InputError(
                    f"controller_options.{key}: set by the scenario"
                    f"{' and speed_options' if key == 'speed' else ''}, not a controller gain"
                )
        try:
            return make_controller(
                self.controller, vehicle=scenario.vehicle, speed=speed, **options
            )
        except InputError as exc:
            # make_controller names an option controller.KEY; here it came from
            # controller_options.
            text = str(exc)
            if text.startswith("controller."):
                raise InputError("controller_options." + text[len("controller."):]) from None
            raise


#: The scenario options of a map scenario.
MAP_OPTIONS = ("reverse",)


def _map_task(m: Map, seed: int, options: Mapping[str, Any]) -> Scenario:
    """The task of driving map ``m`` from its start to its goal (``reverse``: gear changes)."""
    for key in options:
        if key not in MAP_OPTIONS:
            where = (" (a map's car is its own: the map file's \"vehicle\", or "
                     "Map(..., vehicle=...))") if key == "vehicle" else ""
            raise InputError(
                f"scenario_options.{key}: not an option of a map; "
                f"choose from {', '.join(MAP_OPTIONS)}{where}"
            )
    reverse = options.get("reverse", False)
    if not isinstance(reverse, (bool, np.bool_)):
        raise InputError(f"scenario_options.reverse: expected True or False, got {reverse!r}")
    return CustomTask.from_map(m, seed, reverse=bool(reverse))


def caller_options(
    scenario: str | Map | None, config: DriveEnvConfig, options: dict[str, Any]
) -> dict[str, Any]:
    """The options that replace fields of a caller's ``config``.

    ``gym.make`` merges an id's registered keyword arguments with the caller's;
    the registered ones (marked, :func:`rrtdrive.envs.is_registered_default`) are
    defaults for building a config, so they give way to the caller's whole config.

    Raises
    ------
    InputError
        When ``scenario`` differs from ``config.scenario`` (except ``Map-v0``'s
        registered map, which gives way to a config driving another map).
    """
    if scenario is not None and scenario != config.scenario:
        registered_map = is_registered_default(scenario) and scenario not in SCENARIOS
        if registered_map and config.map is None:  # Map-v0's default, the user's scenario
            raise InputError(
                f"config.scenario: {scenario_text(config.scenario)} is a scenario, not a map: "
                "Map-v0 takes a config for a map; give scenario= beside it, or use its own id"
            )
        if not (registered_map and config.map is not None):
            raise InputError(
                f"scenario: {scenario_text(scenario)} differs from config.scenario "
                f"{scenario_text(config.scenario)}"
            )
    return {key: value for key, value in options.items() if not is_registered_default(value)}


def map_of_fields(fields: Mapping[str, Any]) -> Map:
    """The :class:`~rrtdrive.maps.Map` of its fields as a dict, as an env's spec saves it.

    gymnasium's ``EnvSpec.to_json`` keeps ``scenario=Map(...)`` as
    ``dataclasses.asdict(map)``: poses as ``{"x", "y", "yaw"}``, the car's fields as
    ``vehicle``. ``gym.make`` of that spec reads it back here (a map built in Python
    did not survive the round trip docs/gym.md promises; an audit).

    Examples
    --------
    >>> from rrtdrive.maps import builtin_map
    >>> m = builtin_map("parking_lot")
    >>> map_of_fields(dataclasses.asdict(m)) == m
    True
    """
    data = dict(fields)
    car = data.pop("vehicle", None)
    for end in ("start", "goal"):
        pose = data.get(end)
        if isinstance(pose, Mapping):
            data[end] = [pose.get("x"), pose.get("y"), pose.get("yaw")]
    if isinstance(data.get("obstacles"), tuple | list):
        data["obstacles"] = [dict(o) if isinstance(o, Mapping) else o for o in data["obstacles"]]
    vehicle = None if car is None else vehicle_from_json(car, "scenario.vehicle")
    return map_from_json(data, vehicle)
