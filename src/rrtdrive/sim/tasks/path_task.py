"""The tasks driven by tracking one planned path to its end: :class:`PathTask`."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from rrtdrive.controllers import SpeedConfig, TrackingController
from rrtdrive.sim.episode import SHORT_PATH_MESSAGE, EpisodeStatus, plan_failed_message
from rrtdrive.sim.loop import STOP_AT_PATH_END, Driver, EndRule, PathTracker, StopAtGoal
from rrtdrive.sim.tasks.base import Reference, Task, plan_scenario
from rrtdrive.types import Budget, InputError, Path, PlanResult

if TYPE_CHECKING:  # pragma: no cover
    from rrtdrive.sim.ego import EgoVehicle
    from rrtdrive.sim.replanning import TrafficLog
    from rrtdrive.sim.runner import EpisodeConfig

__all__ = ["PathTask"]


@dataclass(frozen=True, kw_only=True)
class PathTask(Task):
    """A task driven by tracking one planned path to its end and stopping there.

    Done when the controller has stopped the car at the end of the path.

    Parameters
    ----------
    map, seed, v_max, max_time_s, reverse
        See :class:`Task`.
    """

    @property
    def success_status(self) -> EpisodeStatus:
        """``ARRIVED``."""
        return STOP_AT_PATH_END.success_status

    def reached(self, ego: EgoVehicle, driver: Any) -> bool:
        """The controller arrived at the end of the path and the car stands still.

        Parameters
        ----------
        ego : EgoVehicle
        driver : PathTracker
            The episode's driver (:meth:`make_driver`).

        Returns
        -------
        bool
        """
        return STOP_AT_PATH_END.reached(ego, driver)

    def agent_end_rule(self, tol_m: float, tol_rad: float, stop_speed: float) -> EndRule:
        """Stopped at the goal pose within the tolerances (no controller says it arrived).

        Parameters
        ----------
        tol_m, tol_rad, stop_speed : float
            Goal distance (m), heading error (rad), standing-still speed (m/s).

        Returns
        -------
        StopAtGoal

        Raises
        ------
        InputError
            When the start already meets them: the car stands there, so every episode
            would end on its first step.
        """
        rule = StopAtGoal(self.goal, tol_m, tol_rad, stop_speed)
        a, b = self.start, self.goal
        if rule.at_goal(a.x, a.y, a.yaw):
            gap = math.hypot(b.x - a.x, b.y - a.y)
            turn = abs(math.remainder(b.yaw - a.yaw, 2.0 * math.pi))
            raise InputError(
                f"goal: the start is already at the goal within its tolerance ({gap:.2f} m, "
                f"{math.degrees(turn):.1f} deg; tolerance {tol_m:g} m, "
                f"{math.degrees(tol_rad):g} deg): an agent's episode would end on its first "
                "step; give a goal farther away"
            )
        return rule

    def resolve(self, config: EpisodeConfig) -> tuple[SpeedConfig, EpisodeConfig]:
        """The given speed settings, else the defaults with this task's cap; ``config`` as is.

        Parameters
        ----------
        config : EpisodeConfig

        Returns
        -------
        tuple of (SpeedConfig, EpisodeConfig)
        """
        return config.speed or self.default_speed(), config

    def reference(
        self, planner: object, seed: int, budget: Budget, options: Mapping[str, Any] | None = None
    ) -> Reference:
        """Plan with the registered planner ``planner``, or take a given plan or path.

        Parameters
        ----------
        planner, seed, budget, options
            As :meth:`Task.reference`; ``seed``, ``budget`` and ``options`` plan a name.

        Returns
        -------
        Reference

        Raises
        ------
        InputError
            When ``planner`` is none of a name, a :class:`PlanResult` or a :class:`Path`.
        """
        plan: PlanResult | None
        if isinstance(planner, str):
            plan = plan_scenario(self, planner, seed, budget, options)
            name, path = planner, plan.path
        elif isinstance(planner, PlanResult):
            plan, name, path = planner, planner.planner, planner.path
        elif isinstance(planner, Path):
            plan, name, path = None, "given", planner
        else:
            raise InputError(
                f"planner: expected a name, a PlanResult or a Path, got {planner!r}"
            )
        if plan is not None and not plan.success:
            return Reference(
                plan, name, Path.empty(), plan_failed_message(plan.status.value, plan.message)
            )
        if len(path) < 2:
            return Reference(plan, name, path, SHORT_PATH_MESSAGE)
        return Reference(plan, name, path)

    def make_driver(
        self,
        env: Any,
        controller: TrackingController,
        reference: Reference,
        speed: SpeedConfig,
        config: EpisodeConfig,
        seed: int,
    ) -> Driver:
        """A :class:`~rrtdrive.sim.loop.PathTracker` on the reference path.

        Parameters
        ----------
        env, controller, reference, speed, config, seed
            As :meth:`Task.make_driver`; only ``env``, ``controller`` and the
            reference's path are used.

        Returns
        -------
        PathTracker
        """
        assert reference.path is not None
        return PathTracker(env, controller, reference.path)

    def outcome(self, driver: Any, reference: Reference, completion_time: float | None
                ) -> tuple[Path, TrafficLog | None]:
        """The planned path; no re-planning log.

        Parameters
        ----------
        driver, reference, completion_time
            As :meth:`Task.outcome`; only the reference's path is used.

        Returns
        -------
        tuple of (Path, None)
        """
        assert reference.path is not None
        return reference.path, None

