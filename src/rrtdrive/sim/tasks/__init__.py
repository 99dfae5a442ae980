"""Tasks: one class per scenario kind, each with only its own fields and rules.

* :class:`ParkingTask` (``parking``) - the ``parking_lot`` map: every parked car
  and block becomes a solid highway-env obstacle of exactly its size and pose,
  walls close the bounds, each spot is drawn as a lane. The ego starts at the
  entrance with a seeded jitter and must stop nose-in in a seeded free spot.
* :class:`OvertakeTask` (``overtake``) - the ``overtake`` map as a highway-env
  two-way road: the ego lane (y = 44, driving +x) and the oncoming lane (y = 48),
  road edges as solid obstacles, a stopped highway-env vehicle at the map's car.
  The ego must pass it, return to its lane and stop at the goal.
* :class:`OvertakeTrafficTask` (``overtake-traffic``) - a long two-way road with a
  slow *moving* lead car and a seeded stream of oncoming IDM cars; the ego
  overtakes with receding-horizon space-time re-planning and is done once it is
  back in its lane ahead of the lead car.
* :class:`ParallelParkingTask` (``parallel-parking``) - a kerbside street with
  parked cars and a seeded gap of 1.5-2.0 car lengths; the ego stops by the kerb
  in the gap (planned with gear changes).
* :class:`UTurnTask` (``u-turn``) - a dead-end street of a seeded width (9-12 m)
  narrower than a forward U-turn needs (14.65 m for the paper's car): the ego
  turns round with a three-point turn (planned with gear changes).
* :class:`CustomTask` (``custom``) - any map, planned and tracked to its goal
  (:meth:`CustomTask.from_map`; ``rrtdrive simulate MAP.json``).

``parking`` takes ``reverse_in=True``: the goal faces out of the spot, entered
backwards (planned with gear changes).

:func:`make_scenario` builds a task by name for a seed. Every task has the same
methods (:class:`Task`): ``build_road`` (its highway-env road), ``scene_view`` and
``camera`` (how the live scene and the video frame it), ``resolve`` /
``reference`` / ``make_driver`` / ``outcome`` (how an episode of it is driven) and
``success_status`` / ``reached`` / ``end_message`` / ``agent_end_rule`` (when it is
done, and how that is worded), ``success_part`` (its terms of the evaluators'
success decision), ``default_speed`` and ``REPLAN_CONFIG`` (its speed profile and
re-planning settings), so nothing else needs to ask which kind a task is.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from typing import Any, cast

from rrtdrive.maps import Map
from rrtdrive.sim.scenes import scenario_rngs
from rrtdrive.sim.tasks.base import (
    DEFAULT_PLANNER,
    Reference,
    SuccessPart,
    Task,
    TaskKind,
    VideoCamera,
    plan_scenario,
)
from rrtdrive.sim.tasks.custom import CustomTask
from rrtdrive.sim.tasks.overtake import OvertakeTask
from rrtdrive.sim.tasks.overtake_traffic import (
    LEAD_MODELS,
    TRAFFIC_DENSITIES,
    TRAFFIC_PLANNER,
    OvertakeTrafficTask,
    overtake_complete,
    traffic_map,
    traffic_speed_config,
)
from rrtdrive.sim.tasks.parallel_parking import ParallelParkingTask
from rrtdrive.sim.tasks.parking import ParkingTask
from rrtdrive.sim.tasks.path_task import PathTask
from rrtdrive.sim.tasks.u_turn import UTurnTask
from rrtdrive.types import InputError, VehicleParams, require_int
from rrtdrive.values import did_you_mean

__all__ = [
    "SCENARIOS",
    "TASKS",
    "Task",
    "TaskKind",
    "PathTask",
    "ParkingTask",
    "OvertakeTask",
    "OvertakeTrafficTask",
    "ParallelParkingTask",
    "UTurnTask",
    "CustomTask",
    "Reference",
    "SuccessPart",
    "VideoCamera",
    "REPLANNING_SCENARIOS",
    "make_scenario",
    "SCENARIO_VARIANTS",
    "make_variant",
    "unknown_scenario",
    "scenario_map",
    "SCENARIO_OPTIONS",
    "plan_scenario",
    "DEFAULT_PLANNER",
    "TRAFFIC_PLANNER",
    "TRAFFIC_DENSITIES",
    "LEAD_MODELS",
    "traffic_map",
    "traffic_speed_config",
    "overtake_complete",
]

#: The tasks :func:`make_scenario` builds by name.
TASKS: dict[str, type[Task]] = {
    TaskKind.PARKING.value: ParkingTask,
    TaskKind.OVERTAKE.value: OvertakeTask,
    TaskKind.OVERTAKE_TRAFFIC.value: OvertakeTrafficTask,
    TaskKind.PARALLEL_PARKING.value: ParallelParkingTask,
    TaskKind.U_TURN.value: UTurnTask,
}
#: Names of the built-in scenarios.
SCENARIOS = tuple(TASKS)
#: Named variants of built-in scenarios, benched like scenarios (``rrtdrive bench
#: --scenarios``; the gym's ``ParkingReverseIn-v0``, ``simulate parking --reverse-in``):
#: name -> (scenario, :func:`make_scenario` options).
SCENARIO_VARIANTS: dict[str, tuple[str, dict[str, Any]]] = {
    "parking-reverse-in": ("parking", {"reverse_in": True}),
}
#: Names of the built-in scenarios that re-plan while driving (their tasks have a
#: ``REPLAN_CONFIG``).
REPLANNING_SCENARIOS = tuple(name for name, cls in TASKS.items() if cls.REPLAN_CONFIG)

#: Why an option of one kind is refused by another (the messages name the option).
_NOT_HERE = {
    "spot": "spot: only the parking scenario has spots",
    "reverse_in": "reverse_in: only the parking scenario has reverse-in bays",
    "oncoming": "oncoming: only the overtake scenario has a count of oncoming cars",
    "density": "density: only the overtake-traffic scenario has it",
    "lead_speed": "lead_speed: only the overtake-traffic scenario has it",
    "lead_model": "lead_model: only the overtake-traffic scenario has it",
}
#: The keyword options of :func:`make_scenario` (every kind's, and ``jitter``, ``vehicle``).
SCENARIO_OPTIONS = ("jitter", "vehicle", *_NOT_HERE)


def _jitter(jitter: object) -> tuple[float, float, float]:
    try:
        values: tuple[Any, ...] = tuple(cast(Iterable[Any], jitter))
        ok = len(values) == 3 and all(
            not isinstance(j, bool) and j >= 0 and math.isfinite(j) for j in values
        )
    except (TypeError, OverflowError):  # not numbers; an int past the largest float
        ok = False
    if not ok:
        raise InputError(
            f"jitter: need three finite numbers >= 0 (x, y in metres, yaw in radians), "
            f"got {jitter!r}"
        )
    return values  # type: ignore[return-value]


def unknown_scenario(
    field: str, name: str, stock_envs: Sequence[str] = (), variants: Sequence[str] = ()
) -> InputError:
    """The one error for a scenario name that is no scenario, stock env or map.

    Worded alike wherever a scenario is named (``rrtdrive simulate``, ``rrtdrive
    bench``, the gym config): what may be given instead, the closest known name first.

    Parameters
    ----------
    field : str
        The field or option that named it (the message's first word).
    name : str
        The name given.
    stock_envs : sequence of str
        The stock highway-env names the caller also drives (none: it drives none).
    variants : sequence of str
        The :data:`SCENARIO_VARIANTS` the caller also takes (none: it takes none).

    Examples
    --------
    >>> print(unknown_scenario("scenario", "parkng"))  # doctest: +ELLIPSIS
    scenario: unknown scenario 'parkng' (did you mean 'parking'?); choose from parking, ...
    """
    from rrtdrive.maps import BUILTIN_MAPS

    maps = sorted(m for m in BUILTIN_MAPS if m not in SCENARIOS)
    hint = did_you_mean(name, [*SCENARIOS, *variants, *stock_envs, *maps])
    stock = f", a stock env ({', '.join(stock_envs)})" if stock_envs else ""
    # "" (an unset $SCENARIO): said as such, not as an unknown name.
    what = "needs a scenario, got an empty name" if name == "" else f"unknown scenario {name!r}"
    return InputError(
        f"{field}: {what}{hint}; choose from "
        f"{', '.join([*SCENARIOS, *variants])}{stock}, "
        f"a map file (.json) or a built-in map ({', '.join(maps)})"
    )


def scenario_map(
    field: str, name: str, stock_envs: Sequence[str] = (), variants: Sequence[str] = ()
) -> Map:
    """The map that a target which is no built-in scenario names, or the one error.

    A name that :func:`~rrtdrive.maps.names_map_file` reads as a file gets the file's
    own error after ``field`` and the name; any other unknown name
    :func:`unknown_scenario`'s.

    Parameters
    ----------
    field, name, stock_envs, variants
        As :func:`unknown_scenario`; ``name`` is a map file or a built-in map's name.

    Returns
    -------
    Map

    Raises
    ------
    InputError
        When ``name`` is no readable map file and no built-in map.
    """
    from rrtdrive.maps import names_map_file, resolve_map

    try:
        return resolve_map(name)
    except InputError as exc:
        if names_map_file(name):
            raise InputError(f"{field}: {name!r}: {exc}") from None
        raise unknown_scenario(field, name, stock_envs, variants) from None


def make_variant(name: str, seed: int = 0) -> Task:
    """The task of a built-in scenario or of a named variant of one, for ``seed``.

    Parameters
    ----------
    name : str
        A name of :data:`SCENARIOS` or :data:`SCENARIO_VARIANTS`.
    seed : int
        As :func:`make_scenario`.

    Returns
    -------
    Task

    Raises
    ------
    InputError
        For any other name (:func:`unknown_scenario`).

    Examples
    --------
    >>> t = make_variant("parking-reverse-in", 3)
    >>> t.kind.value, t.reverse_in, t.reverse
    ('parking', True, True)
    """
    if not isinstance(name, str) or (name not in TASKS and name not in SCENARIO_VARIANTS):
        raise unknown_scenario("scenario", str(name), (), SCENARIO_VARIANTS)
    scenario, options = SCENARIO_VARIANTS.get(name, (name, {}))
    return make_scenario(scenario, seed, **options)


def make_scenario(name: str, seed: int = 0, **options: Any) -> Task:
    """Build the task ``name`` for ``seed``.

    Parameters
    ----------
    name : str
        ``"parking"``, ``"overtake"``, ``"overtake-traffic"``, ``"parallel-parking"``
        or ``"u-turn"``.
    seed : int
        Seeds the start jitter and the kind's variation (parking: the free spot;
        parallel-parking: the gap's length and place; u-turn: the street's width).
    **options
        ``jitter`` (three half-ranges of the uniform start jitter in x, y (metres) and
        yaw (radians), default ``(1.0, 0.5, radians(5))``) and ``vehicle`` (a
        :class:`~rrtdrive.types.VehicleParams`) for every kind, and per kind:

        - parking: ``spot``, force this ``(row, side, index)`` spot (must be empty);
          ``reverse_in``, the goal faces out of the spot (entered backwards);
        - overtake: ``oncoming``, the number of oncoming cars (seeded positions
          90-140 m apart beyond the road's end, speeds 6-9 m/s; the ego waits for a
          gap before pulling out);
        - overtake-traffic: ``density``, oncoming cars per km or a name of
          :data:`TRAFFIC_DENSITIES` (default ``"default"``, 10 per km; gaps are 25 m
          plus an exponential draw, speeds uniform in 6-9 m/s); ``lead_speed``, the
          lead car's speed in m/s (default 4, below the ego's 11 m/s cap; the ego
          starts at this speed, 20-30 m behind it); ``lead_model``, ``"idm"``
          (default) or ``"constant"``.

        An option of another kind may be given as ``None`` (``oncoming`` as 0,
        ``reverse_in`` as False).

    Returns
    -------
    Task

    Raises
    ------
    InputError
        Naming the option, for an unknown name or option, an option of another kind,
        or a value of the wrong shape.

    Examples
    --------
    >>> from rrtdrive.parking_layout import PARKING_EMPTY_SPOTS
    >>> s = make_scenario("parking", 3)
    >>> s.spot in PARKING_EMPTY_SPOTS, s == make_scenario("parking", 3)
    (True, True)
    >>> make_scenario("parking", 0, spot=999)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    rrtdrive.types.InputError: spot: expected tuple (row, side, index) of three integers, ...
    """
    rng, _, _ = scenario_rngs(seed)
    jitter = _jitter(options.pop("jitter", (1.0, 0.5, math.radians(5.0))))
    vehicle = options.pop("vehicle", None)
    if vehicle is not None and not isinstance(vehicle, VehicleParams):
        raise InputError(f"vehicle: expected a VehicleParams, got {type(vehicle).__name__}")
    for key in options:
        if key not in _NOT_HERE:
            known = list(SCENARIO_OPTIONS)
            raise InputError(f"{key}: unknown scenario option; choose from {known}")
    if "oncoming" in options:
        options["oncoming"] = require_int("oncoming", options["oncoming"], 0, 10)
    cls = TASKS.get(name)
    own = cls.OPTIONS if cls is not None else ()
    for key, value in list(options.items()):
        if key in own:
            continue
        if value is not None and not (key in ("oncoming", "reverse_in") and not value):
            raise InputError(_NOT_HERE[key])
        del options[key]
    if cls is None:
        raise InputError(f"scenario: unknown scenario {name!r}; choose from {', '.join(SCENARIOS)}")
    vehicle = vehicle or VehicleParams()
    offset = tuple(float(rng.uniform(-j, j)) if j > 0 else 0.0 for j in jitter)
    return cls.create(seed, rng, offset, vehicle, **options)  # type: ignore[attr-defined]
