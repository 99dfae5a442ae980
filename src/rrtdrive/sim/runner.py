"""The closed loop: plan, then drive the task in highway-env at the simulation frequency.

:func:`run_episode` builds a task's scene, gets its reference (plans, or takes a
given plan or path; ``overtake-traffic`` re-plans while driving), drives the ego
with the task's driver through the episode loop (:class:`rrtdrive.sim.loop.EpisodeLoop`)
and returns an :class:`~rrtdrive.sim.episode.Episode`: the plan, the path and the
logged trajectory, nothing else. Metrics come from
:func:`rrtdrive.evaluation.evaluate`; videos replay an episode
(:mod:`rrtdrive.sim.video`). Everything random is drawn from the episode seed,
so an episode is a pure function of its arguments.
"""

from __future__ import annotations

import logging
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from rrtdrive.controllers import SpeedConfig, TrackingController, make_controller
from rrtdrive.frozen import FrozenOptions
from rrtdrive.sim.episode import DriveLog, Episode, EpisodeStatus
from rrtdrive.sim.loop import STOP_AT_PATH_END, EpisodeLoop, PathTracker, require_episode_time
from rrtdrive.sim.scenes import SimConfig, build_env
from rrtdrive.sim.tasks import DEFAULT_PLANNER, Task, make_variant
from rrtdrive.sim.traffic import OncomingGate
from rrtdrive.types import Budget, InputError, Path, PlanResult, brief_repr

if TYPE_CHECKING:  # pragma: no cover
    from rrtdrive.sim.replanning import ReplanConfig

__all__ = ["EpisodeConfig", "run_episode", "drive"]

logger = logging.getLogger(__name__)


@dataclass(frozen=True)
class EpisodeConfig:
    """Everything about an episode besides the scenario, planner, controller and seed.

    Parameters
    ----------
    sim : SimConfig
        Simulation frequency (the control rate) and frame size.
    speed : SpeedConfig, optional
        Speed profile and PI gains; by default the controllers' defaults with the
        scenario's ``v_max``.
    controller_options : Mapping
        Extra keyword arguments for the controller (gains).
    planner_options : Mapping
        Extra keyword arguments for the planner (its config's fields, e.g.
        ``{"reverse_detour_tree": False}``), as ``make_planner(name, **options)``.
    budget : Budget
        Planning budget.
    max_time_s : float, optional
        Time limit of the drive; by default the scenario's.
    stop_on_crash : bool
        End the episode at highway-env's first ``crashed``.
    replan : ReplanConfig, optional
        ``overtake-traffic``: re-planning settings
        (:class:`rrtdrive.sim.replanning.ReplanConfig`; default its defaults).
    """

    sim: SimConfig = field(default_factory=SimConfig)
    speed: SpeedConfig | None = None
    controller_options: Mapping[str, Any] = field(default_factory=dict)
    planner_options: Mapping[str, Any] = field(default_factory=dict)
    budget: Budget = field(default_factory=Budget)
    max_time_s: float | None = None
    stop_on_crash: bool = True
    replan: ReplanConfig | None = None

    def __post_init__(self) -> None:
        kinds: dict[str, tuple[type, bool]] = {
            "sim": (SimConfig, False), "speed": (SpeedConfig, True), "budget": (Budget, False)
        }
        if self.replan is not None:
            # Imported only then: it pulls in the space-time planner.
            from rrtdrive.sim.replanning import ReplanConfig

            kinds["replan"] = (ReplanConfig, True)
        for name, (kind, optional) in kinds.items():
            value = getattr(self, name)
            if not (isinstance(value, kind) or (optional and value is None)):
                raise InputError(
                    f"episode.{name}: expected a {kind.__name__}"
                    f"{' or None' if optional else ''}, got {type(value).__name__}"
                )
        for name, what in (("controller", "(gains)"), ("planner", "(its config's fields)")):
            value = getattr(self, f"{name}_options")
            if not isinstance(value, Mapping) or not all(isinstance(k, str) for k in value):
                raise InputError(
                    f"episode.{name}_options: expected a mapping of the {name}'s keyword "
                    f"arguments {what} by name, got {brief_repr(value)}"
                )
            # Read-only past validation, and hashable as the frozen config around it.
            object.__setattr__(self, f"{name}_options", FrozenOptions(value))
        if self.max_time_s is not None:
            require_episode_time("episode.max_time_s", self.max_time_s)
        if not isinstance(self.stop_on_crash, bool):
            raise InputError(
                f"episode.stop_on_crash: expected true or false, got {self.stop_on_crash!r}"
            )


def drive(
    env: Any,
    path: Path,
    controller: TrackingController,
    max_time_s: float,
    stop_on_crash: bool = True,
    gate: OncomingGate | None = None,
    gate_cars: list[Any] | None = None,
) -> DriveLog:
    """Track ``path`` with ``controller`` in a highway-env environment until done.

    The episode loop (:class:`~rrtdrive.sim.loop.EpisodeLoop`) with a
    :class:`~rrtdrive.sim.loop.PathTracker` and the stop-at-the-path-end rule, for
    any highway-env scene whose ego is an :class:`~rrtdrive.sim.ego.EgoVehicle`
    (a stock ``parking-v0`` after :func:`~rrtdrive.sim.extract.attach_ego` too).
    The controller runs once per simulation step: each step sets the ego's action,
    lets every other vehicle act (``road.act``) and advances the physics
    (``road.step(dt)``), exactly as highway-env's own ``_simulate`` does.

    Parameters
    ----------
    env : gymnasium.Env
        A reset highway-env environment whose controlled vehicle is an :class:`EgoVehicle`.
    path : Path
        Rear-axle path to track.
    controller : TrackingController
        Reset here on ``path``.
    max_time_s : float
        Time limit.
    stop_on_crash : bool
        Stop at highway-env's first ``crashed``.
    gate : OncomingGate, optional
        Holds the car before the oncoming lane until there is a gap.
    gate_cars : list, optional
        The oncoming vehicles the gate watches.

    Returns
    -------
    DriveLog
    """
    tracker = PathTracker(env, controller, path, gate, gate_cars)
    return EpisodeLoop(env, tracker, STOP_AT_PATH_END, max_time_s, stop_on_crash).run()


def run_episode(
    scenario: str | Task,
    planner: str | PlanResult | Path = DEFAULT_PLANNER,
    controller: str = "pure-pursuit",
    seed: int = 0,
    config: EpisodeConfig | None = None,
) -> Episode:
    """Plan and drive one episode; deterministic for a given seed.

    Parameters
    ----------
    scenario : str or Task
        ``"parking"``, ``"overtake"``, ``"overtake-traffic"`` (built for ``seed``) or a
        ready task (:mod:`rrtdrive.sim.tasks`).
    planner : str, PlanResult or Path
        A registered planner name, or a plan/path to track as given
        (``overtake-traffic``: only its space-time planner).
    controller : str
        ``"pure-pursuit"``, ``"stanley"`` or ``"lqr"``.
    seed : int
        Episode seed: start jitter, goal choice, planner and simulator streams.
    config : EpisodeConfig, optional
        Frequency, speed profile, gains, budget, time limit, re-planning.

    Returns
    -------
    Episode

    Examples
    --------
    >>> ep = run_episode("overtake", planner=my_path, controller="lqr", seed=1)  # doctest: +SKIP
    >>> evaluate(ep).success  # doctest: +SKIP
    True
    """
    if config is not None and not isinstance(config, EpisodeConfig):
        raise InputError(f"config: expected an EpisodeConfig, got {type(config).__name__}")
    config = config or EpisodeConfig()
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise InputError(f"seed: need an integer >= 0, got {seed!r}")
    seed = int(seed)
    task = make_variant(scenario, seed) if isinstance(scenario, str) else scenario
    if not isinstance(task, Task):
        raise InputError(f"scenario: expected a name or a task, got {scenario!r}")
    if config.max_time_s is not None:  # before planning: the scene may not last that long
        task.check_time_limit(config.max_time_s, "episode.max_time_s")
    speed, resolved = task.resolve(config)
    ctrl = make_controller(
        controller, vehicle=task.vehicle, speed=speed, **dict(config.controller_options)
    )
    ref = task.reference(planner, seed, config.budget, config.planner_options)
    if ref.failure is not None:
        return Episode(
            task, ref.planner, controller, seed, ref.plan, ref.path or Path.empty(),
            DriveLog.empty(config.sim.dt), EpisodeStatus.PLAN_FAILED, ref.failure, resolved,
        )
    env = build_env(task, config.sim)
    max_time = config.max_time_s or task.max_time_s
    try:
        driver = task.make_driver(env, ctrl, ref, speed, resolved, seed)
        loop = EpisodeLoop(env, driver, task, max_time, config.stop_on_crash)
        log = loop.run()
        path, traffic = task.outcome(driver, ref, loop.t if loop.reached else None)
    finally:
        env.close()
    logger.info(
        "episode %s/%s/%s seed %d: %s", task.name, ref.planner, controller, seed, loop.status
    )
    return Episode(
        task, ref.planner, controller, seed, ref.plan, path, log, loop.status, loop.message,
        resolved, traffic,
    )
