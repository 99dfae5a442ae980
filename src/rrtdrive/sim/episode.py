"""An episode as plain data: what was asked, what was planned, what happened.

:class:`Episode` and its :class:`DriveLog` are what the evaluators
(:mod:`rrtdrive.evaluation`) and the video (:mod:`rrtdrive.sim.video`) read;
nothing here imports highway-env. :class:`EpisodeStatus` is the one list of
episode outcomes and :func:`end_message` the one place their messages are written.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from rrtdrive.types import InputError, read_only_array

if TYPE_CHECKING:  # pragma: no cover
    from rrtdrive.sim.replanning import TrafficLog
    from rrtdrive.sim.runner import EpisodeConfig
    from rrtdrive.sim.tasks import Task
    from rrtdrive.types import Path, PlanResult

__all__ = [
    "TRAJECTORY_COLUMNS",
    "trajectory_csv",
    "driven_gears",
    "EpisodeStatus",
    "DriveLog",
    "Episode",
    "end_message",
    "plan_failed_message",
    "SHORT_PATH_MESSAGE",
]


class EpisodeStatus(enum.StrEnum):
    """How an episode ended (the values are the JSON strings).

    ``ARRIVED``: stopped at the end of the tracked path; ``COMPLETED``: the
    ``overtake-traffic`` overtake is done; ``CRASHED``: highway-env reported a crash;
    ``TIMEOUT``: neither within the time limit; ``PLAN_FAILED``: nothing to drive;
    ``OFF_PATH``: the gym env's agent left the path by more than its limit.
    """

    ARRIVED = "arrived"
    COMPLETED = "completed"
    CRASHED = "crashed"
    TIMEOUT = "timeout"
    PLAN_FAILED = "plan_failed"
    OFF_PATH = "off_path"


#: The message of an episode that has fewer than two path samples to track.
SHORT_PATH_MESSAGE = "the path has fewer than two samples"


def plan_failed_message(status: str, detail: str) -> str:
    """The message of an episode whose planner failed with ``status`` (and ``detail``)."""
    return f"planning failed ({status}): {detail}"


def end_message(
    status: EpisodeStatus, t_end: float, max_time_s: float, success: EpisodeStatus
) -> str:
    """The message of an episode that ended with ``status`` at ``t_end``.

    Parameters
    ----------
    status : EpisodeStatus
        How it ended (not ``PLAN_FAILED``).
    t_end : float
        Simulation time of the last step, seconds.
    max_time_s : float
        The time limit.
    success : EpisodeStatus
        The task's success status (``ARRIVED`` or ``COMPLETED``): it words the timeout.

    Examples
    --------
    >>> end_message(EpisodeStatus.CRASHED, 3.0, 60.0, EpisodeStatus.ARRIVED)
    'highway-env reported a crash at t = 3.00 s'
    """
    if status is EpisodeStatus.CRASHED:
        return f"highway-env reported a crash at t = {t_end:.2f} s"
    if status is EpisodeStatus.ARRIVED:
        return f"stopped at the end of the path at t = {t_end:.2f} s"
    if status is EpisodeStatus.COMPLETED:
        return f"overtake complete at t = {t_end:.2f} s"
    if success is EpisodeStatus.COMPLETED:
        return f"no overtake within {max_time_s:g} s (followed the lead car)"
    return f"not stopped at the goal within {max_time_s:g} s"


@dataclass(frozen=True, eq=False)
class DriveLog:
    """The logged trajectory of one drive.

    Attributes
    ----------
    dt : float
        Simulation step in seconds.
    t : numpy.ndarray
        Times, shape ``(N + 1,)``, starting at 0.
    states : numpy.ndarray
        Rear-axle ``[x, y, yaw, speed]`` at each time, ``(N + 1, 4)``.
    controls : numpy.ndarray
        Applied ``[acceleration, steering]`` over each step, ``(N, 2)``.
    crashed : numpy.ndarray
        highway-env's ``crashed`` flag of the ego at each time, ``(N + 1,)``.
    others : numpy.ndarray
        Body-centre ``[x, y, heading, speed]`` of every other vehicle, ``(N + 1, K, 4)``.
    other_sizes : numpy.ndarray
        ``[length, width]`` of every other vehicle, ``(K, 2)``.
    arrived : bool
        The task's success rule held at the end (the controller stopped the car at
        the end of the path; ``overtake-traffic``: the overtake was complete).
    wall_time_s : float
        Wall time of the loop (``overtake-traffic``: without the re-planning cycles).
    """

    dt: float
    t: np.ndarray
    states: np.ndarray
    controls: np.ndarray
    crashed: np.ndarray
    others: np.ndarray
    other_sizes: np.ndarray
    arrived: bool
    wall_time_s: float

    def __post_init__(self) -> None:
        # Read-only, as Path's and PlanResult's: evaluate() scores what was driven, and a
        # consumer's edit of a log it was handed must not rewrite it (an audit).
        for name in ("t", "states", "controls", "crashed", "others", "other_sizes"):
            object.__setattr__(self, name, read_only_array(getattr(self, name)))
        # A NaN scored as a collision, or a success with a NaN lateral acceleration, or
        # ended in numpy's "zero-size array" error (an audit): one error names it here.
        for name in ("t", "states", "controls", "others", "other_sizes"):
            values = getattr(self, name)
            if values.dtype.kind == "f" and not np.isfinite(values).all():
                row = int(np.argwhere(~np.isfinite(values))[0][0])
                raise InputError(f"log.{name}: row {row} is not finite ({values[row]!r})")

    @property
    def steps(self) -> int:
        """Number of simulation steps."""
        return len(self.controls)

    @classmethod
    def empty(cls, dt: float) -> DriveLog:
        """A drive that never started."""
        return cls(
            dt, np.zeros(0), np.zeros((0, 4)), np.zeros((0, 2)), np.zeros(0, dtype=bool),
            np.zeros((0, 0, 4)), np.zeros((0, 2)), False, 0.0,
        )


@dataclass(frozen=True, eq=False)
class Episode:
    """One closed-loop episode: what was asked, what was planned, what happened.

    Attributes
    ----------
    scenario : Task
        The task (map with start and goal, seed, success terms); one of the classes
        of :mod:`rrtdrive.sim.tasks`.
    planner, controller : str
        Names.
    seed : int
        Episode seed.
    plan : PlanResult or None
        The planner's result (``None`` when a path was given directly).
    path : Path
        The path that was tracked (empty when planning failed).
    log : DriveLog
        The trajectory.
    status : EpisodeStatus
        ``arrived``, ``crashed``, ``timeout`` or ``plan_failed``; for
        ``overtake-traffic`` ``completed`` (the overtake is done), ``crashed``
        or ``timeout``. Compares equal to its string value.
    message : str
        Human-readable detail.
    config : EpisodeConfig
        The resolved configuration.
    traffic : TrafficLog or None
        ``overtake-traffic``: the re-planner's log (cycles, references, modes); the
        ``path`` is then the reference actually tracked, stitched from the plans.
    """

    scenario: Task
    planner: str
    controller: str
    seed: int
    plan: PlanResult | None
    path: Path
    log: DriveLog
    status: EpisodeStatus
    message: str
    config: EpisodeConfig
    traffic: TrafficLog | None = None

    def trajectory(self) -> np.ndarray:
        """The executed trajectory for an outside judge, one row per simulation step.

        Columns :data:`TRAJECTORY_COLUMNS`: ``t, x, y, yaw, speed, steer, accel, gear``
        - time, rear-axle position and heading, signed speed, the front-wheel angle
        and acceleration applied from that time to the next step, and the gear
        (+1 forward, -1 reverse; see :func:`driven_gears`).
        The last row is the final state: it keeps the last steering angle and has
        zero acceleration. Shape ``(N + 1, 8)`` (empty when nothing was driven).
        """
        log = self.log
        n = len(log.states)
        if n == 0:
            return np.zeros((0, len(TRAJECTORY_COLUMNS)))
        steer = np.zeros(n)
        accel = np.zeros(n)
        if log.steps:
            steer[:-1] = log.controls[:, 1]
            steer[-1] = log.controls[-1, 1]
            accel[:-1] = log.controls[:, 0]
        speed = log.states[:, 3]
        return np.column_stack([log.t, log.states[:, :3], speed, steer, accel, driven_gears(speed)])


def driven_gears(speed: np.ndarray) -> np.ndarray:
    """The gear at each logged time from the signed speeds: +1 forward, -1 reverse.

    Moving, the sign of the speed; standing still, the gear of the last motion
    (before the first motion: the gear of the first; +1 when the car never moves),
    so a stop at a cusp keeps its gear until the car moves off in the new one.

    Examples
    --------
    >>> driven_gears(np.array([0.0, -0.5, 0.0, 0.0, 0.4, 0.0])).tolist()
    [-1.0, -1.0, -1.0, -1.0, 1.0, 1.0]
    """
    v = np.asarray(speed, dtype=float)
    moving = np.flatnonzero(v != 0.0)
    if len(moving) == 0:
        return np.ones(len(v))
    # Index of the last moving sample at or before each time (the first one before it).
    last = np.maximum.accumulate(np.where(v != 0.0, np.arange(len(v)), -1))
    last = np.where(last < 0, moving[0], last)
    return np.where(v[last] < 0.0, -1.0, 1.0)


#: Header of :meth:`Episode.trajectory` and ``rrtdrive simulate --trajectory``.
TRAJECTORY_COLUMNS = ("t", "x", "y", "yaw", "speed", "steer", "accel", "gear")


def trajectory_csv(episode: Episode) -> str:
    """:meth:`Episode.trajectory` as CSV text, header ``t,x,y,yaw,speed,steer,accel,gear``."""
    rows = episode.trajectory()
    lines = [",".join(TRAJECTORY_COLUMNS)]
    lines += [",".join(_exact(v) for v in row[:-1]) + f",{int(row[-1])}" for row in rows]
    return "\n".join(lines) + "\n"


def _exact(value: float) -> str:
    """The shortest text that reads back as the same double (``5`` for 5.0, ``0`` for -0.0).

    Nine significant digits were not enough for an outside judge: a steering rate at
    the actuator's 0.4 rad/s, recomputed from the rounded angles, read 0.400000008.
    """
    text = repr(float(value) + 0.0)  # + 0.0: a steering of -0.0 is written 0, not -0
    return text[:-2] if text.endswith(".0") else text
