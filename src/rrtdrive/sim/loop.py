"""The one episode loop: a driver's command each step, highway-env's physics, the task's end rule.

Every episode - a planned path tracked in parking or overtake, the receding-horizon
re-planner of ``overtake-traffic``, and the gymnasium environment
(:class:`rrtdrive.envs.drive_env.DriveEnv`) - runs through :class:`EpisodeLoop`.
One step:

1. the caller passes the command ``(acceleration, steering)`` (usually
   ``driver.command(loop.t)``; the gym env may add a residual to it);
2. :class:`~rrtdrive.sim.drivelog.DriveRecorder` applies it to the ego, lets every
   other vehicle act, steps the road by ``dt`` and logs the result;
3. the loop ends the episode at highway-env's first ``crashed`` (when
   ``stop_on_crash``), when the end rule's :meth:`EndRule.reached` holds, or at the
   time limit; a caller with a rule of its own checked between steps (the gym
   env's off-path limit) ends it with :meth:`EpisodeLoop.stop`.

API (for the gym env)::

    loop = EpisodeLoop(env, driver, task, max_time_s, stop_on_crash=True)
    driver.start()                      # once, before the first command
    while not loop.done:
        accel, steer = driver.command(loop.t)
        loop.step(accel, steer)         # -> EpisodeStatus or None while running
    loop.status, loop.message, loop.log()

or ``loop.run()``, which starts the driver and does exactly that. ``loop.recorder``
is the live record (states and other vehicles so far, for an observation).
``loop.t`` is the
simulation time (the sum of the ``dt`` steps), ``loop.steps`` the step count,
``loop.crashed`` whether the ego crashed at the last step, ``loop.reached``
whether the end rule held. A driver is anything with ``start()`` and
``command(t)`` (:class:`Driver`); :class:`PathTracker` is a tracking controller on a
fixed path (with the optional oncoming-traffic gate), the traffic re-planner
(:class:`rrtdrive.sim.traffic_driver.TrafficDriver`) is another. An end rule
(:class:`EndRule`) is a task of :mod:`rrtdrive.sim.tasks`,
:data:`STOP_AT_PATH_END` for a bare environment, or :class:`StopAtGoal` for an
agent that drives without a tracking controller; the rule also words the end
(:meth:`EndRule.end_message`).
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from typing import Any, Protocol, runtime_checkable

from rrtdrive.controllers import TrackingController, VehicleState
from rrtdrive.geometry import wrap_angle
from rrtdrive.sim.drivelog import DriveRecorder
from rrtdrive.sim.ego import EgoVehicle
from rrtdrive.sim.episode import DriveLog, EpisodeStatus, end_message
from rrtdrive.sim.traffic import OncomingGate
from rrtdrive.types import InputError, Path, Pose, require_finite, require_positive

__all__ = [
    "Driver",
    "EndRule",
    "PathTracker",
    "StopAtPathEnd",
    "STOP_AT_PATH_END",
    "StopAtGoal",
    "EpisodeLoop",
    "MAX_EPISODE_S",
    "require_episode_time",
    "step_limit",
    "in_time",
]

#: The longest time limit an episode takes (s): 2e7 steps at 20 Hz, about 11.6 simulated
#: days. Longer is a typo (1e307 s overflowed the step count into a traceback).
MAX_EPISODE_S = 1e6


def require_episode_time(name: str, value: float) -> float:
    """``value`` as a float; :class:`InputError` naming ``name`` outside ``(0, MAX_EPISODE_S]``."""
    require_positive(name, value)
    if value > MAX_EPISODE_S:
        raise InputError(
            f"{name}: at most {MAX_EPISODE_S:g} s (11.6 simulated days), got {value:g}"
        )
    return float(value)


def step_limit(max_time_s: float, dt: float) -> int:
    """The most steps an episode of ``max_time_s`` runs: the first at or past the limit.

    Parameters
    ----------
    max_time_s, dt : float
        The time limit and the step, seconds.

    Returns
    -------
    int

    Examples
    --------
    >>> step_limit(0.5, 0.05), step_limit(0.51, 0.05)
    (10, 11)
    """
    return int(math.ceil(max_time_s / dt - 1e-9))


def in_time(steps: int, dt: float, max_time_s: float) -> bool:
    """Whether the end rule counts after ``steps`` steps: not past the limit.

    The last step may cross it (:func:`step_limit`); a car arriving at 10.90 s in the
    step that crossed a 10.86 s limit was a success (an audit).

    Parameters
    ----------
    steps : int
        Steps driven.
    dt, max_time_s : float
        The step and the time limit, seconds.

    Returns
    -------
    bool

    Examples
    --------
    >>> in_time(217, 0.05, 10.86), in_time(218, 0.05, 10.86)
    (True, False)
    """
    return steps * dt <= max_time_s + 1e-9


@runtime_checkable
class Driver(Protocol):
    """Produces the ego's command once per simulation step."""

    def start(self) -> None:
        """Get ready to drive (called once, before the first :meth:`command`)."""
        ...

    def command(self, t: float) -> tuple[float, float]:
        """``(acceleration m/s^2, steering rad)`` for the step starting at time ``t``."""
        ...


class EndRule(Protocol):
    """When an episode has succeeded (a task of :mod:`rrtdrive.sim.tasks` is one)."""

    @property
    def success_status(self) -> EpisodeStatus:
        """The status of an episode that ends by :meth:`reached`."""
        ...

    def reached(self, ego: EgoVehicle, driver: Any) -> bool:
        """True when the episode is over because the task is done (checked each step)."""
        ...

    def end_message(self, status: EpisodeStatus, t_end: float, max_time_s: float) -> str:
        """The message of an episode that ended with ``status`` at ``t_end``."""
        ...


class StopAtPathEnd:
    """The end rule of path tracking: the controller has stopped the car at the path's end."""

    @property
    def success_status(self) -> EpisodeStatus:
        """``ARRIVED``."""
        return EpisodeStatus.ARRIVED

    def reached(self, ego: EgoVehicle, driver: Any) -> bool:
        """The driver's controller arrived and the car stands still."""
        return bool(driver.arrived) and ego.speed == 0.0

    def end_message(self, status: EpisodeStatus, t_end: float, max_time_s: float) -> str:
        """:func:`~rrtdrive.sim.episode.end_message` with this rule's success status."""
        return end_message(status, t_end, max_time_s, self.success_status)


class StopAtGoal:
    """The end rule of an agent's drive: the rear axle stands still at the goal pose.

    For a drive without a tracking controller that could say it arrived (the gym
    env's direct mode); the tolerances are the evaluators' success thresholds.

    Parameters
    ----------
    goal : Pose
        Rear-axle goal pose.
    tol_m : float
        Largest distance of the rear axle from the goal, metres.
    tol_rad : float
        Largest heading error, radians.
    stop_speed : float
        Largest speed that counts as standing still, m/s.
    """

    def __init__(self, goal: Pose, tol_m: float, tol_rad: float, stop_speed: float) -> None:
        self.goal = goal
        self.tol_m = float(tol_m)
        self.tol_rad = float(tol_rad)
        self.stop_speed = float(stop_speed)

    @property
    def success_status(self) -> EpisodeStatus:
        """``ARRIVED``."""
        return EpisodeStatus.ARRIVED

    def at_goal(self, x: float, y: float, yaw: float) -> bool:
        """The rear-axle pose ``(x, y, yaw)`` lies within the tolerances of the goal pose."""
        goal = self.goal
        return bool(
            math.hypot(x - goal.x, y - goal.y) <= self.tol_m
            and abs(float(wrap_angle(yaw - goal.yaw))) <= self.tol_rad
        )

    def reached(self, ego: EgoVehicle, driver: Any) -> bool:
        """Stopped within the tolerances of the goal pose."""
        return abs(ego.speed) <= self.stop_speed and self.at_goal(*ego.rear)

    def end_message(self, status: EpisodeStatus, t_end: float, max_time_s: float) -> str:
        """As :func:`~rrtdrive.sim.episode.end_message`, arrival worded as "at the goal"."""
        if status is EpisodeStatus.ARRIVED:
            return f"stopped at the goal at t = {t_end:.2f} s"
        return end_message(status, t_end, max_time_s, self.success_status)


#: The end rule of a plain path-tracking drive (:func:`rrtdrive.sim.runner.drive`).
STOP_AT_PATH_END = StopAtPathEnd()


class PathTracker:
    """A tracking controller on a fixed path, optionally held by the oncoming-traffic gate.

    Parameters
    ----------
    env : gymnasium.Env
        The reset highway-env scene (its controlled vehicle is the ego).
    controller : TrackingController
        Reset on ``path`` by :meth:`start`.
    path : Path
        Rear-axle path to track.
    gate : OncomingGate, optional
        Holds the car before the oncoming lane until there is a gap.
    gate_cars : sequence, optional
        The oncoming vehicles the gate watches.
    """

    def __init__(
        self,
        env: Any,
        controller: TrackingController,
        path: Path,
        gate: OncomingGate | None = None,
        gate_cars: Sequence[Any] | None = None,
    ) -> None:
        self.ego = env.unwrapped.vehicle
        self.controller = controller
        self.path = path
        self.gate = gate
        self.gate_cars = list(gate_cars or [])
        #: Wall time spent planning inside :meth:`command` (none: the path is given).
        self.planning_wall_s = 0.0

    @property
    def arrived(self) -> bool:
        """The controller has stopped the car at the end of the path."""
        return self.controller.arrived

    def start(self) -> None:
        """Reset the controller on the path from the ego's current speed."""
        self.controller.reset(self.path, v_start=self.ego.speed)

    def command(self, t: float) -> tuple[float, float]:
        """The controller's command at time ``t`` (after the gate sets its stop line)."""
        ego, ctrl = self.ego, self.controller
        r = ego.rear
        if self.gate is not None:
            ctrl.hold_at(self.gate.stop_line(ctrl.s, ego.speed, self.gate_cars))
        return ctrl.control(VehicleState(r[0], r[1], r[2], ego.speed, ego.steer, t))


class EpisodeLoop:
    """Steps one episode: apply a command, record, ask the end rule (see the module docs).

    Parameters
    ----------
    env : gymnasium.Env
        A reset highway-env environment whose controlled vehicle is an
        :class:`~rrtdrive.sim.ego.EgoVehicle`.
    driver : Driver
        What :meth:`run` takes commands from; the end rule may read it (the path
        tracker's ``arrived``, the re-planner's lead car).
    rule : EndRule
        The task (or :data:`STOP_AT_PATH_END`).
    max_time_s : float
        Time limit: at most :func:`step_limit` steps, the end rule counting only
        :func:`in_time`.
    stop_on_crash : bool
        End the episode at highway-env's first ``crashed``.
    """

    def __init__(
        self,
        env: Any,
        driver: Driver,
        rule: EndRule,
        max_time_s: float,
        stop_on_crash: bool = True,
    ) -> None:
        u = env.unwrapped
        ego = u.vehicle
        if not isinstance(ego, EgoVehicle):
            raise InputError("env: the controlled vehicle must be an EgoVehicle (see attach_ego)")
        require_finite("max_time_s", max_time_s)
        if max_time_s > MAX_EPISODE_S:
            require_episode_time("max_time_s", max_time_s)
        self.env = env
        self.ego = ego
        self.driver = driver
        self.rule = rule
        self.max_time_s = float(max_time_s)
        self.stop_on_crash = stop_on_crash
        self.dt = 1.0 / u.config["simulation_frequency"]
        self.max_steps = step_limit(max_time_s, self.dt)
        self.t = 0.0
        self.steps = 0
        self.crashed = False
        self.reached = False
        self.done = self.max_steps <= 0
        self._recorder: DriveRecorder | None = None
        self._wall0 = 0.0
        self._stopped: tuple[EpisodeStatus, str] | None = None

    def _begin(self) -> DriveRecorder:
        if self._recorder is None:
            self._recorder = DriveRecorder(self.env, self.dt)
            self._wall0 = time.perf_counter()
        return self._recorder

    def step(self, accel: float, steer: float) -> EpisodeStatus | None:
        """Apply ``(accel, steer)`` for one step; the final status once the episode is over.

        Raises
        ------
        RuntimeError
            When the episode is already over.
        """
        if self.done:
            raise RuntimeError("EpisodeLoop.step: the episode is over")
        self._begin().step(accel, steer)
        self.t += self.dt
        self.steps += 1
        ego = self.ego
        self.crashed = bool(ego.crashed)
        if self.crashed and self.stop_on_crash:
            self.done = True
        elif in_time(self.steps, self.dt, self.max_time_s) and self.rule.reached(
            ego, self.driver
        ):
            self.reached = self.done = True
        elif self.steps >= self.max_steps:
            self.done = True
        return self.status if self.done else None

    def stop(self, status: EpisodeStatus, message: str) -> EpisodeStatus:
        """End the episode now, by a rule the caller checks between steps; ``status``.

        For example the gym env's off-path limit. It may override a timeout of the
        last step, but not a crash or a reached end rule.

        Raises
        ------
        RuntimeError
            When the ego crashed or the end rule held.
        """
        if self.crashed or self.reached:
            raise RuntimeError(f"EpisodeLoop.stop: the episode already ended ({self.status})")
        self._stopped = (status, message)
        self.done = True
        return status

    @property
    def recorder(self) -> DriveRecorder:
        """The live record of the drive (starts it: the wall clock runs from here)."""
        return self._begin()

    def run(self) -> DriveLog:
        """Start the driver and step it until the episode is over; the log."""
        self.driver.start()
        self._begin()
        while not self.done:
            self.step(*self.driver.command(self.t))
        return self.log()

    @property
    def status(self) -> EpisodeStatus:
        """Crashed (at the last step), the rule's success status, a :meth:`stop`, else timeout."""
        if self._stopped is not None:
            return self._stopped[0]
        if self.crashed:
            return EpisodeStatus.CRASHED
        if self.reached:
            return self.rule.success_status
        return EpisodeStatus.TIMEOUT

    @property
    def message(self) -> str:
        """Human-readable detail of :attr:`status`."""
        if self._stopped is not None:
            return self._stopped[1]
        t_end = self.steps * self.dt  # the log's last time (``DriveLog.t[-1]``)
        return self.rule.end_message(self.status, t_end, self.max_time_s)

    def log(self, wall_time_s: float | None = None) -> DriveLog:
        """The drive so far.

        Parameters
        ----------
        wall_time_s : float, optional
            The wall time to record; by default the time since the drive started,
            less the driver's planning time (a caller that waits between steps, the
            gym env, times its own steps).
        """
        rec = self._begin()
        if wall_time_s is None:
            wall_time_s = (
                time.perf_counter() - self._wall0 - getattr(self.driver, "planning_wall_s", 0.0)
            )
        return rec.log(self.reached, wall_time_s)
