"""Our ego, planner and controller in highway-env's own environments, through ``env.step``.

:func:`drive_stock_env` makes a stock environment (``parking-v0``,
``parking-parked-v0``), resets it with the seed, puts our
:class:`~rrtdrive.sim.ego.EgoVehicle` in place of its car
(:func:`~rrtdrive.sim.extract.attach_ego`), extracts the planning map from its
scene (:func:`~rrtdrive.sim.extract.map_from_env`: the walls, parked cars and
the spot lines as thin obstacles; the goal from the ego's goal landmark), plans,
and tracks the path with our controller, one ``env.step`` per simulation step:
the command is normalised into highway-env's ``ContinuousAction`` range, and
highway-env's own ``_simulate``, reward, termination and rendering run.

highway-env's parking success (a weighted distance to the goal below its
threshold) holds while the car still rolls towards the goal, so its first
``terminated`` is recorded (``highway_env_terminated_s``) and the drive goes on
until our controller has stopped the car at the end of the path (or a crash, or
highway-env's time limit, its ``duration``). ``highway_env_success`` is its
``is_success`` after the last step, our metrics come from
:func:`rrtdrive.evaluation.evaluate` of :attr:`StockEpisode.episode`.
"""

from __future__ import annotations

import bisect
import logging
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from highway_env.utils import lmap

from rrtdrive.controllers import make_controller
from rrtdrive.sim.episode import DriveLog, Episode, EpisodeStatus, end_message
from rrtdrive.sim.extract import attach_ego, map_from_env
from rrtdrive.sim.loop import STOP_AT_PATH_END, PathTracker, in_time, step_limit
from rrtdrive.sim.render import prepare_sdl, sdl_that_draws
from rrtdrive.sim.runner import EpisodeConfig
from rrtdrive.sim.tasks import DEFAULT_PLANNER, CustomTask
from rrtdrive.types import InputError, Path, PlanResult, VehicleParams

__all__ = ["STOCK_ENVS", "StockEpisode", "drive_stock_env", "make_stock_env"]

logger = logging.getLogger(__name__)

#: The stock highway-env ids :func:`drive_stock_env` drives (its installed version has both).
STOCK_ENVS = ("parking-v0", "parking-parked-v0")


@dataclass(frozen=True, eq=False)
class StockEpisode:
    """One drive of our ego in a stock highway-env environment.

    Attributes
    ----------
    env_id : str
        The gymnasium id.
    episode : Episode
        Our record of it (the task is a :class:`~rrtdrive.sim.tasks.CustomTask` of
        the extracted map): :func:`rrtdrive.evaluation.evaluate` scores it.
    highway_env_success : bool
        highway-env's ``is_success`` after the last step (``False`` when nothing
        was driven).
    highway_env_terminated_s : float or None
        Simulation time of highway-env's first ``terminated`` (success or crash).
    highway_env_truncated : bool
        highway-env ended the episode at its time limit.
    highway_env_return : float
        The sum of highway-env's rewards over the drive.
    frames : list of numpy.ndarray
        highway-env's own rendered frames (when asked for, and not handed to an
        ``on_frame``).
    render_time_s : float
        Wall time spent rendering those frames (and in ``on_frame``): not part of the drive's
        ``wall_time_s``, and ``rrtdrive simulate`` leaves it out of ``total_time_s``.
    """

    env_id: str
    episode: Episode
    highway_env_success: bool
    highway_env_terminated_s: float | None
    highway_env_truncated: bool
    highway_env_return: float
    frames: list[np.ndarray]
    render_time_s: float = 0.0

    def to_json(self) -> dict[str, Any]:
        """The highway-env side of the drive as JSON-ready fields."""
        return {
            "env_id": self.env_id,
            "highway_env_success": bool(self.highway_env_success),
            "highway_env_terminated_s": self.highway_env_terminated_s,
            "highway_env_truncated": bool(self.highway_env_truncated),
            "highway_env_return": round(float(self.highway_env_return), 6),
        }


def make_stock_env(
    env_id: str, frequency: int, render: bool = False, vehicle: VehicleParams | None = None
) -> Any:
    """The stock env ``env_id`` stepping at ``frequency`` Hz, one simulation step per ``step``.

    The action's steering range is our car's steering limit (so a normalised
    command maps onto the same angle our ego clips to); everything else is
    highway-env's configuration of that env.

    Raises
    ------
    InputError
        For an id that is not in :data:`STOCK_ENVS`.
    """
    import gymnasium as gym
    import highway_env  # noqa: F401  (registers its envs)

    if env_id not in STOCK_ENVS:
        raise InputError(f"env: unknown stock env {env_id!r}; choose from {', '.join(STOCK_ENVS)}")
    params = vehicle or VehicleParams()
    config = {
        "simulation_frequency": int(frequency),
        "policy_frequency": int(frequency),
        "action": {
            "type": "ContinuousAction",
            "acceleration_range": [-5.0, 5.0],
            "steering_range": [-params.max_steer, params.max_steer],
        },
    }
    # Configured after making: parking-parked-v0's class takes no constructor arguments.
    env = gym.make(env_id)
    env.unwrapped.configure(config)
    env.unwrapped.render_mode = "rgb_array" if render else None
    if render:
        prepare_sdl()  # without a runtime folder SDL prints an "error:" line on stderr
    return env


def _normalise(value: float, low: float, high: float) -> float:
    """The inverse of highway-env's ``lmap(action, [-1, 1], [low, high])``."""
    return float(np.clip(2.0 * (value - low) / (high - low) - 1.0, -1.0, 1.0))


def _decoded(action: np.float32, low: float, high: float) -> float:
    """The steering highway-env decodes from a float32 action (float32 arithmetic)."""
    return float(lmap(action, [-1, 1], [low, high]))


def _float32_key(value: np.float32) -> int:
    """An integer that orders float32 numbers as they compare (both zeros are 0)."""
    bits = int(np.float32(value).view(np.uint32))
    return bits if bits < 0x80000000 else -(bits & 0x7FFFFFFF)


def _float32_at(key: int, negative_zero: bool) -> np.float32:
    """The float32 of :func:`_float32_key` ``key`` (zero signed as ``np.nextafter`` leaves it)."""
    if key == 0:
        return np.float32(-0.0 if negative_zero else 0.0)
    bits = key if key > 0 else (-key) | 0x80000000
    return np.array(bits, dtype=np.uint32).view(np.float32)[()]


def _steering_action(steer: float, low: float, high: float) -> np.float32:
    """The float32 action whose steering, decoded as highway-env does, is no larger than ``steer``.

    Rounded to float32 (the action space's type) and decoded in float32 arithmetic,
    full lock came back 1e-7 over the command: 0.39621043 rad against the controller's
    clip 0.39621040, and the evaluators counted the curvature limit broken on 19 % of a
    stock episode's steps. The answer is the first float32 from the rounded action
    toward the centre of the range whose steering is not larger (or the centre). The
    decoding is monotone in the action, so it is found by bisection over the float32s
    between them: stepping one float32 at a time took 189 485 steps (0.75 s) for a
    command of 1e-6 rad in highway-env's +-45 deg range, where float32s are dense and
    the decoding's rounding is not.
    """
    action = np.float32(_normalise(steer, low, high))
    # The centre of the range decodes to the smallest steering there is.
    centre = np.float32(_normalise(0.5 * (low + high), low, high))
    if action == centre:
        return action
    bound = abs(steer)
    start, stop = _float32_key(action), _float32_key(centre)
    toward = -1 if start > stop else 1  # the decoding falls (rises) on the way to the centre
    negative_zero = start < 0

    def crossed(j: int) -> bool:
        # Monotone in j: the decoding has come down to +bound (up to -bound).
        value = _decoded(_float32_at(start + toward * j, negative_zero), low, high)
        return value <= bound if toward < 0 else value >= -bound

    # The answer is the first crossed step (False, ..., False, True, ...), or the centre.
    lo = bisect.bisect_left(range(abs(stop - start)), True, key=crossed)
    if lo < abs(stop - start):
        candidate = _float32_at(start + toward * lo, negative_zero)
        # float(): a float32 compared with a Python float is compared in float32 (NEP 50).
        if abs(_decoded(candidate, low, high)) <= bound:
            return candidate
    return _float32_at(stop, negative_zero)  # it jumped past the band: the centre


def drive_stock_env(
    env_id: str = "parking-v0",
    seed: int = 0,
    planner: str | PlanResult | Path = DEFAULT_PLANNER,
    controller: str = "pure-pursuit",
    config: EpisodeConfig | None = None,
    *,
    reverse: bool = False,
    vehicle: VehicleParams | None = None,
    render_stride: int = 0,
    on_frame: Callable[[np.ndarray], None] | None = None,
) -> StockEpisode:
    """Plan and drive one episode of a stock highway-env environment through ``env.step``.

    Parameters
    ----------
    env_id : str
        ``"parking-v0"`` or ``"parking-parked-v0"`` (:data:`STOCK_ENVS`).
    seed : int
        ``env.reset(seed=seed)`` (highway-env's own draw of the start heading and
        the goal spot) and our planner's stream.
    planner : str, PlanResult or Path
        A registered planner name, or a plan or path to track.
    controller : str
        ``"pure-pursuit"``, ``"stanley"`` or ``"lqr"``.
    config : EpisodeConfig, optional
        Frequency (default 20 Hz; highway-env's policy frequency is set to it),
        speed profile, gains, planning budget; ``max_time_s`` defaults to the
        env's ``duration`` and may not exceed it (:class:`InputError`).
    reverse : bool
        Plan with gear changes.
    vehicle : VehicleParams, optional
        Our car.
    render_stride : int
        Keep highway-env's own ``env.render()`` frame every this many steps (0: none).
    on_frame : callable, optional
        Given each of those frames as it is drawn, instead of keeping it in
        :attr:`StockEpisode.frames` (a video writer: a 34 s parking drive's frames
        are 370 MB).

    Returns
    -------
    StockEpisode

    Examples
    --------
    >>> from rrtdrive.evaluation import evaluate
    >>> run = drive_stock_env("parking-v0", seed=3)  # doctest: +SKIP
    >>> run.highway_env_success, evaluate(run.episode).success  # doctest: +SKIP
    (True, True)
    """
    from rrtdrive.sim.scenes import scenario_rngs

    scenario_rngs(seed)  # validates the seed
    if config is not None and not isinstance(config, EpisodeConfig):
        raise InputError(f"config: expected an EpisodeConfig, got {type(config).__name__}")
    config = config or EpisodeConfig()
    if vehicle is not None and not isinstance(vehicle, VehicleParams):
        raise InputError(f"vehicle: expected a VehicleParams, got {type(vehicle).__name__}")
    params = vehicle or VehicleParams()
    freq = config.sim.simulation_frequency
    env = make_stock_env(env_id, freq, render=render_stride > 0, vehicle=params)
    try:
        env.reset(seed=int(seed))
        u = env.unwrapped
        attach_ego(env, params)
        duration = float(u.config["duration"])
        max_time = config.max_time_s or duration
        if max_time > duration + 1e-9:
            # The env's own limit would end the drive first, under a message quoting the
            # longer one (an audit); the stock env keeps highway-env's episode.
            raise InputError(
                f"max_time_s: {env_id} ends its episodes at {duration:g} s (highway-env's "
                f"duration); ask for at most that, got {max_time:g} s"
            )
        m = map_from_env(env, vehicle=params, name=env_id)
        task = CustomTask(map=m, seed=int(seed), reverse=reverse, max_time_s=max_time,
                          closed=False)
        speed, resolved = task.resolve(config)
        ctrl = make_controller(
            controller, vehicle=params, speed=speed, **dict(config.controller_options)
        )
        ref = task.reference(planner, int(seed), config.budget, config.planner_options)
        dt = 1.0 / freq
        if ref.failure is not None:
            episode = Episode(
                task, ref.planner, controller, int(seed), ref.plan, ref.path or Path.empty(),
                DriveLog.empty(dt), EpisodeStatus.PLAN_FAILED, ref.failure, resolved,
            )
            return StockEpisode(env_id, episode, False, None, False, 0.0, [])
        assert ref.path is not None
        return _drive(env, env_id, task, ref, ctrl, controller, resolved, max_time,
                      render_stride, on_frame)
    finally:
        env.close()


def _drive(
    env: Any, env_id: str, task: CustomTask, ref: Any, ctrl: Any, controller: str,
    resolved: EpisodeConfig, max_time: float, render_stride: int,
    on_frame: Callable[[np.ndarray], None] | None,
) -> StockEpisode:
    """Track the reference through ``env.step`` until stopped at the end, crashed or out of time."""
    u = env.unwrapped
    ego = u.vehicle
    dt = 1.0 / u.config["simulation_frequency"]
    acc_lo, acc_hi = u.action_type.acceleration_range
    st_lo, st_hi = u.action_type.steering_range
    tracker = PathTracker(env, ctrl, ref.path)
    others = [v for v in u.road.vehicles if v is not ego]
    states = [(*ego.rear, ego.speed)]
    controls: list[tuple[float, float]] = []
    crashed = [bool(ego.crashed)]
    other_log = [[(v.position[0], v.position[1], v.heading, v.speed) for v in others]]
    frames: list[np.ndarray] = []
    keep = frames.append if on_frame is None else on_frame

    def grab() -> float:
        """Draw one frame and keep or hand it on; the seconds it took (not the closed loop's)."""
        t_render = time.perf_counter()
        with sdl_that_draws():
            frame = env.render()
        keep(frame)
        return time.perf_counter() - t_render

    render_s = grab() if render_stride > 0 else 0.0
    loop_render_s = 0.0
    terminated_at: float | None = None
    truncated = reached = False
    success, total = False, 0.0
    t, steps = 0.0, 0
    max_steps = step_limit(max_time, dt)
    wall0 = time.perf_counter()
    tracker.start()
    while steps < max_steps:
        accel, steer = tracker.command(t)
        action = np.array(
            [_normalise(accel, acc_lo, acc_hi), _steering_action(steer, st_lo, st_hi)],
            dtype=np.float32,
        )
        _, reward, term, trunc, info = env.step(action)
        steps += 1
        t = steps * dt
        total += float(reward)
        success = bool(info.get("is_success", False))
        states.append((*ego.rear, ego.speed))
        controls.append((ego.accel, ego.steer))
        crashed.append(bool(ego.crashed))
        other_log.append([(v.position[0], v.position[1], v.heading, v.speed) for v in others])
        if render_stride > 0 and steps % render_stride == 0:
            loop_render_s += grab()
        if term and terminated_at is None:
            terminated_at = round(t, 9)
        if ego.crashed:
            break
        if in_time(steps, dt, max_time) and STOP_AT_PATH_END.reached(ego, tracker):
            reached = True
            break
        if trunc:
            truncated = True
            break
    wall = time.perf_counter() - wall0 - loop_render_s
    render_s += loop_render_s + (grab() if render_stride > 0 and steps % render_stride else 0.0)
    n = len(states)
    log = DriveLog(
        dt=dt, t=np.arange(n) * dt, states=np.asarray(states, dtype=float),
        controls=np.asarray(controls, dtype=float).reshape(-1, 2),
        crashed=np.asarray(crashed, dtype=bool),
        others=np.asarray(other_log, dtype=float).reshape(n, len(others), 4),
        other_sizes=np.asarray([(v.LENGTH, v.WIDTH) for v in others],
                               dtype=float).reshape(-1, 2),
        arrived=reached, wall_time_s=wall,
    )
    status = (
        EpisodeStatus.CRASHED if ego.crashed
        else EpisodeStatus.ARRIVED if reached else EpisodeStatus.TIMEOUT
    )
    message = end_message(status, steps * dt, max_time, EpisodeStatus.ARRIVED)
    episode = Episode(task, ref.planner, controller, task.seed, ref.plan, ref.path, log, status,
                      message, resolved)
    logger.info("stock %s seed %d: %s, highway-env success %s", env_id, task.seed, status,
                success)
    return StockEpisode(
        env_id, episode, success, terminated_at, truncated, total, frames, render_s
    )
