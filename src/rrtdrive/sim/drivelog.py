"""One drive in highway-env, step by step: apply the ego's command, step the road, log.

:class:`DriveRecorder` is the single place where a command is applied to the ego
and a simulation step is taken and recorded; the episode loop
(:class:`rrtdrive.sim.loop.EpisodeLoop`, used by every episode kind) and the
gymnasium environment drive through it, so their logs agree to the bit for the
same commands. The log it returns is :class:`rrtdrive.sim.episode.DriveLog`.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from rrtdrive.sim.episode import DriveLog

__all__ = ["DriveRecorder"]


class DriveRecorder:
    """Steps a highway-env scene with the ego's commands and logs every state.

    Each :meth:`step` does what highway-env's own ``_simulate`` does for one
    simulation step (set the ego's action, ``road.act()``, ``road.step(dt)``, advance
    the env's clock) and records the ego's rear-axle state, the applied command,
    highway-env's ``crashed`` flag and every other vehicle's state.

    Parameters
    ----------
    env : gymnasium.Env
        A reset highway-env environment (wrapped or not) whose controlled vehicle
        is the ego.
    dt : float
        Simulation step in seconds (``1 / simulation_frequency``).
    """

    def __init__(self, env: Any, dt: float) -> None:
        u = env.unwrapped
        self._u = u
        self.road = u.road
        self.ego = u.vehicle
        self.dt = dt
        #: Every other vehicle, in the road's order (the order of ``DriveLog.others``).
        self.others = [v for v in self.road.vehicles if v is not self.ego]
        r = self.ego.rear
        #: Rear-axle ``(x, y, yaw, speed)`` after every step, the start first.
        self.states: list[tuple[float, float, float, float]] = [
            (r[0], r[1], r[2], self.ego.speed)
        ]
        self._controls: list[tuple[float, float]] = []
        self._crashed: list[bool] = [bool(self.ego.crashed)]
        self._other_log = [self._other_states()]

    def _other_states(self) -> list[tuple[float, float, float, float]]:
        return [(v.position[0], v.position[1], v.heading, v.speed) for v in self.others]

    def step(self, accel: float, steer: float) -> None:
        """Apply ``accel`` [m/s²] and ``steer`` [rad] for one step and record the result."""
        ego, u = self.ego, self._u
        action = ego.action
        action["acceleration"] = accel
        action["steering"] = steer
        self.road.act()
        self.road.step(self.dt)
        u.time += self.dt
        u.steps += 1
        r = ego.rear
        self.states.append((r[0], r[1], r[2], ego.speed))
        self._controls.append((ego.accel, ego.steer))
        self._crashed.append(bool(ego.crashed))
        if self.others:
            self._other_log.append(self._other_states())

    def log(self, arrived: bool, wall_time_s: float) -> DriveLog:
        """The drive so far as a :class:`DriveLog`."""
        n = len(self.states)
        others = (
            np.asarray(self._other_log, dtype=float) if self.others else np.zeros((n, 0, 4))
        )
        return DriveLog(
            dt=self.dt,
            t=np.arange(n) * self.dt,
            states=np.asarray(self.states, dtype=float),
            controls=np.asarray(self._controls, dtype=float).reshape(-1, 2),
            crashed=np.asarray(self._crashed, dtype=bool),
            others=others,
            other_sizes=np.asarray(
                [(v.LENGTH, v.WIDTH) for v in self.others], dtype=float
            ).reshape(-1, 2),
            arrived=arrived,
            wall_time_s=wall_time_s,
        )
