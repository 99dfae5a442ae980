"""The gymnasium environment: drive a planned path in highway-env, as an agent.

Each episode builds a task (:func:`rrtdrive.sim.tasks.make_scenario`) for an
*episode seed*, takes its reference (:meth:`~rrtdrive.sim.tasks.Task.reference`:
plans its path, or nothing when it re-plans while driving), builds the
highway-env scene (:func:`rrtdrive.sim.scenes.build_env`) and the task's driver
(:meth:`~rrtdrive.sim.tasks.Task.make_driver`), and steps the one episode loop
of the runner (:class:`rrtdrive.sim.loop.EpisodeLoop`): once per simulation step
it sets the ego's acceleration and steering, lets the other vehicles act and
advances the physics. The agent's action sets those two numbers directly, or -
with ``residual=True`` - is added to the driver's command, so that a zero action
reproduces the plain controller exactly.

At the end of an episode the logged trajectory is scored by
:func:`rrtdrive.evaluation.evaluate`, the same evaluators as ``rrtdrive
simulate``; the report is in ``info["metrics"]`` and on
:attr:`DriveEnv.report`.

The parts live apart: the options in :mod:`rrtdrive.envs.config`
(:class:`~rrtdrive.envs.config.DriveEnvConfig`), the observation in
:mod:`rrtdrive.envs.observation`, the action and residual mode in
:mod:`rrtdrive.envs.action`, the reward in :mod:`rrtdrive.envs.reward`. They are
documented in ``docs/gym.md`` and on :class:`DriveEnv`.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import fields
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from rrtdrive.controllers import PathProjector
from rrtdrive.envs import apply_registration, plain_value
from rrtdrive.envs.action import ResidualMixer, action_command
from rrtdrive.envs.config import DriveEnvConfig, _require_mapping, caller_options
from rrtdrive.envs.observation import OBS_CLIP, ObservationLayout, observation_names
from rrtdrive.envs.reference_speed import Relaunch, following_cap, stop_line_speed
from rrtdrive.envs.render import SceneRenderer, view_for
from rrtdrive.envs.reward import RewardWeights, state_terms
from rrtdrive.envs.seed_draw import failure_text, start_drawn_episode
from rrtdrive.envs.segments import starts_next_segment
from rrtdrive.evaluation import EpisodeReport, EvalConfig, evaluate
from rrtdrive.evaluation.report import WALL_CLOCK_FIELDS
from rrtdrive.maps import Map
from rrtdrive.sim.episode import Episode, EpisodeStatus
from rrtdrive.sim.loop import EndRule, EpisodeLoop
from rrtdrive.sim.runner import EpisodeConfig
from rrtdrive.sim.scenes import build_env
from rrtdrive.sim.tasks import Reference
from rrtdrive.sim.tasks.base import Task
from rrtdrive.types import InputError, Path, brief_repr, require_int

# RewardWeights, observation_names, OBS_CLIP: re-exported (they lived here before the split).
__all__ = ["DriveEnv", "DriveEnvConfig", "RewardWeights", "observation_names", "OBS_CLIP"]


_RESET_OPTIONS = ("episode_seed",)


class DriveEnv(gym.Env[np.ndarray, np.ndarray]):
    """Drive a planned, curvature-bounded path in highway-env.

    Registered as ``rrtdrive/Parking-v0``, ``rrtdrive/Overtake-v0`` and
    ``rrtdrive/OvertakeTraffic-v0`` (re-planned in the loop, see ``replan_options``);
    keyword arguments of ``gym.make`` reach this constructor.

    **Observation** (``float32``, shape ``(6 + 3 K + 5 M + 2,)``, SI units, ego frame =
    rear axle, x forward, y left): the car's state against the path, K reference
    points ahead with their curvatures, the M nearest other vehicles, the gear to
    drive and the distance to the next stop; the entries are listed in
    :mod:`rrtdrive.envs.observation` and by :func:`observation_names`.

    **Gear changes**: a path with cusps is observed and rewarded one gear segment
    at a time. With ``residual=True`` the controller changes segment (it stops at
    each cusp; the residual fades out before every stop); an agent driving alone
    moves on to the next segment once it stands still (|v| <= 0.1 m/s) within
    0.5 m of the cusp, or moves in the next segment's gear within ``CUSP_REACH_M``
    (1 m, at most half the segment) of it or past it (:mod:`rrtdrive.envs.segments`).

    **Action** (``float32``, ``[-1, 1]^2``): ``[a, d]``, an acceleration and a
    steering angle over the car's command range, or with ``residual=True`` a
    correction of the controller's command (a zero action is the plain
    controller); see :mod:`rrtdrive.envs.action`.

    **Episode end**: terminated on highway-env's first crash (status
    ``"crashed"``), when the rear axle is more than ``max_cte`` from the path
    (``"off_path"``), or on arrival (``"arrived"``): with ``residual=True`` when
    the controller has stopped the car at the end of the path (the runner's rule),
    otherwise when the rear axle is stopped (|v| <= 0.1 m/s) within 0.5 m and 10°
    of the goal; ``overtake-traffic`` instead ends (``"completed"``) when the
    overtake is complete. Truncated at the scenario's time limit (``"timeout"``).

    Parameters
    ----------
    scenario : str or Map, optional
        Scenario name (the ids pass it) or ``Map-v0``'s map. Default ``config.scenario``.
    config : DriveEnvConfig, optional
        The options as one value; keyword ``options`` replace some of its fields.
        It wins over the defaults an id registers (``ParkingReverseIn-v0``'s
        planner and ``scenario_options``, ``Map-v0``'s map, ...): only the caller's
        own keyword arguments replace its fields.
    render_mode : str, optional
        ``"rgb_array"`` or ``None``.
    **options
        The fields of :class:`~rrtdrive.envs.config.DriveEnvConfig` (``planner``,
        ``controller``, ``residual``, ``residual_scale``, ``n_ref_points``,
        ``ref_spacing``, ``n_vehicles``, ``vehicle_range``, ``action_repeat``,
        ``simulation_frequency``, ``max_time_s``, ``max_cte``, ``reward``,
        ``scenario_options``, ``replan_options``, ``controller_options``,
        ``speed_options``, ``budget``, ``seed_range``), documented there. An
        unknown option raises :class:`~rrtdrive.types.InputError` naming it.

    Attributes
    ----------
    config : DriveEnvConfig
        The validated options.
    weights : RewardWeights
        The reward weights (``config.reward``).
    episode : Episode or None
        The finished episode (plain data, as :func:`~rrtdrive.sim.runner.run_episode`
        returns), set when an episode ends.
    report : EpisodeReport or None
        Its evaluation.
    episode_seed : int or None
        Seed of the current episode.
    path : Path or None
        The planned path of the current episode.
    """

    metadata: dict[str, Any] = {"render_modes": ["rgb_array"], "render_fps": 20}

    def __init__(
        self,
        scenario: str | Map | None = None,
        *,
        config: DriveEnvConfig | None = None,
        render_mode: str | None = None,
        **options: Any,
    ) -> None:
        super().__init__()
        options = apply_registration(scenario, options, merge=config is None)
        if config is None:
            config = DriveEnvConfig.from_options(
                "parking" if scenario is None else plain_value(scenario),  # type: ignore[arg-type]
                **{key: plain_value(value) for key, value in options.items()},
            )
        elif not isinstance(config, DriveEnvConfig):
            kind = type(config).__name__
            raise InputError(f"config: expected a DriveEnvConfig, got {kind} {brief_repr(config)}")
        else:
            config = config.with_options(**caller_options(scenario, config, options))
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise InputError(
                f"render_mode: {render_mode!r} is not supported; choose from "
                f"{self.metadata['render_modes']} or None"
            )
        self.config = config
        self.weights: RewardWeights = config.reward  # type: ignore[assignment]
        self.sim_config = config.sim_config
        self.render_mode = render_mode
        self.eval_config = EvalConfig()

        fps = self.sim_config.simulation_frequency / config.action_repeat
        self.metadata = {**type(self).metadata, "render_fps": fps}
        self.action_space = spaces.Box(-1.0, 1.0, shape=(2,), dtype=np.float32)
        self._layout = ObservationLayout(
            config.n_ref_points, config.ref_spacing, config.n_vehicles, config.vehicle_range,
            config.max_steer,
        )
        self.observation_space = spaces.Box(self._layout.low, self._layout.high, dtype=np.float32)

        self.episode: Episode | None = None
        self.report: EpisodeReport | None = None
        self._driver: Any = None
        self.episode_seed: int | None = None
        self.path: Path | None = None
        self._sim: Any = None
        self._renderer: SceneRenderer | None = None
        self._renderer_key: tuple[Any, ...] | None = None
        #: The episode loop of the current episode (``None`` before the first reset).
        self._loop: EpisodeLoop | None = None

    # ------------------------------------------------------------------ setup

    def _start_episode(self, seed: int, task: Task | None = None) -> Reference:
        """Build, plan and set up the episode of ``seed``; its reference (maybe failed).

        The episode runs on the one episode loop (:class:`~rrtdrive.sim.loop.EpisodeLoop`)
        with the task's driver, as :func:`~rrtdrive.sim.runner.run_episode` does; the
        end rule is the task's (the runner's) when a controller drives or the task
        re-plans, else the task's rule for an agent (stopped at the goal).
        """
        cfg = self.config
        task = cfg.scenario_for(seed) if task is None else task
        if cfg.max_time_s is not None:  # the task checked its own limit when it was made
            task.check_time_limit(cfg.max_time_s, "max_time_s")
        ref = task.reference(cfg.planner, seed, cfg.budget, cfg.planner_options)
        if ref.failure is not None:
            return ref
        speed = cfg.speed_for(task)
        ctrl = cfg.controller_for(task, speed)
        if self._sim is not None:
            self._sim.close()
        sim = build_env(task, self.sim_config)
        max_time = cfg.max_time_s or task.max_time_s
        episode_config = EpisodeConfig(
            sim=self.sim_config,
            speed=speed,
            controller_options=dict(cfg.controller_options),  # type: ignore[arg-type]
            budget=cfg.budget,  # type: ignore[arg-type]
            max_time_s=max_time,
            replan=cfg.replan,
        )
        driver = task.make_driver(sim, ctrl, ref, speed, episode_config, seed)
        if cfg.residual:
            rule: EndRule = task
        else:
            e = self.eval_config
            rule = task.agent_end_rule(e.goal_tol_m, e.goal_tol_rad, e.stop_speed)
        driver.start()
        loop = EpisodeLoop(sim, driver, rule, max_time, stop_on_crash=True)
        self._sim, self._ego, self._road = sim, sim.unwrapped.vehicle, sim.unwrapped.road
        self._scenario, self._reference, self._speed, self._ctrl = task, ref, speed, ctrl
        self._driver, self._loop, self._episode_config = driver, loop, episode_config
        # A driver that plans while driving, or that the oncoming gate holds (its stop
        # line caps v_ref), runs every step even when its command is not applied.
        gated = getattr(driver, "gate", None) is not None
        self._runs_driver = cfg.residual or ref.plans_while_driving or gated
        self._relaunch = Relaunch(speed.comfort_a_max if ctrl.speed.comfort else speed.a_max)
        self.episode_seed = seed
        self._dt = loop.dt
        self._rec = loop.recorder
        self._mixer = ResidualMixer(cfg.limits, speed, self._dt)
        self._wall = 0.0
        self.episode = None
        self.report = None
        self._use_reference(driver.path)  # type: ignore[union-attr]
        self._obs64 = self._observe64()
        self._s = self._progress_s()
        return ref

    # ------------------------------------------------------------------ gym API

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Start an episode: draw (or take) its seed, plan, build the scene.

        Parameters
        ----------
        seed : int, optional
            Seeds ``self.np_random``, from which the episode seeds are drawn.
        options : dict, optional
            ``{"episode_seed": n}`` runs the episode of seed ``n`` (the same episode
            as ``run_episode(scenario, planner, controller, seed=n)``).

        Returns
        -------
        observation : numpy.ndarray
        info : dict
            ``episode_seed``, ``scenario``, ``path_length_m``.

        Raises
        ------
        InputError
            For an unknown option or a bad episode seed.
        RuntimeError
            When planning fails for the requested episode seed (or for
            ``MAX_PLAN_ATTEMPTS`` drawn seeds in a row, :mod:`~rrtdrive.envs.seed_draw`).
        """
        super().reset(seed=seed)
        self._loop = None  # until an episode is set up
        opts = _require_mapping("options", options)
        for key in opts:
            if key not in _RESET_OPTIONS:
                raise InputError(
                    f"options.{key}: unknown reset option; choose from {', '.join(_RESET_OPTIONS)}"
                )
        requested = opts.get("episode_seed")
        if requested is not None:
            s = require_int("options.episode_seed", requested, 0, 2**63 - 1)
            ref = self._start_episode(s)
            if ref.failure is not None:
                raise RuntimeError(
                    f"options.episode_seed: no path for episode seed {s}: {failure_text(ref)}"
                )
        else:
            start_drawn_episode(self.config, self.np_random, self._start_episode)
        info = {
            "episode_seed": self.episode_seed,
            "scenario": self.config.scenario_name,
            "path_length_m": float(self.path.length),  # type: ignore[union-attr]
        }
        return self._obs32(), info

    def step(
        self, action: np.ndarray
    ) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        """Apply ``action`` for ``action_repeat`` simulation steps.

        Returns
        -------
        observation, reward, terminated, truncated, info
            ``info`` has ``reward_terms`` (each term of the reward), ``cte_m``,
            ``heading_err_rad``, ``speed``, ``v_ref``, ``accel`` and ``steer`` (the
            applied command), ``time_s``, ``crashed`` and ``episode_seed``; at the end
            also ``status``, ``is_success`` and ``metrics`` (:func:`_metrics_dict`).
        """
        loop = self._loop
        if self._sim is None or loop is None or loop.done:
            why = "the episode is over" if loop is not None else "none since made or closed"
            raise RuntimeError(f"DriveEnv.step: call reset() first ({why})")
        cfg = self.config
        residual = cfg.residual
        d_accel, d_steer = action_command(
            action, cfg.limits, cfg.residual_scale if residual else None
        )
        mixer = self._mixer

        ego, ctrl, dt = self._ego, self._ctrl, self._dt
        steps = 0
        s_before = self._s
        carried = 0.0  # progress on references that were replaced during this step
        driver = self._driver
        wall0 = time.perf_counter()
        for _ in range(cfg.action_repeat):
            if loop.done:
                break
            accel, steer = d_accel, d_steer
            if self._runs_driver:
                r = ego.rear
                c_accel, c_steer = driver.command(loop.t)
                if driver.path is not self.path:  # a re-planned reference took over
                    carried += self._clipped_s(r) - s_before
                    self._use_reference(driver.path)
                    s_before = self._clipped_s(r)
                if residual:
                    accel, steer = mixer.command(ctrl, c_accel, c_steer, d_accel, d_steer)
            loop.step(accel, steer)
            mixer.applied(accel)
            steps += 1
            self._follow_segments()
        self._wall += time.perf_counter() - wall0

        self._obs64 = self._observe64()
        s_after = self._progress_s()
        self._s = s_after
        w = self.weights
        span = steps * dt
        e, psi, v, v_ref = (float(self._obs64[i]) for i in (2, 3, 0, 4))
        terms = state_terms(
            w, progress_m=carried + s_after - s_before, cte=e, heading_err=psi, speed=v,
            v_ref=v_ref, span_s=span, crashed=loop.crashed,
        )
        if (
            not (loop.crashed or loop.reached)
            and cfg.max_cte is not None
            and abs(e) > cfg.max_cte
        ):
            loop.stop(
                EpisodeStatus.OFF_PATH,
                f"left the path by more than {cfg.max_cte:g} m at t = {loop.steps * dt:.2f} s",
            )
            terms["off_path"] = -w.off_path
        over = loop.done
        truncated = over and loop.status is EpisodeStatus.TIMEOUT
        terminated = over and not truncated
        info: dict[str, Any] = {
            "episode_seed": self.episode_seed,
            # The drive log's time of this step (steps x dt): the loop's running sum of dt
            # drifts (149.44999999999973 s for 149.45; an audit).
            "time_s": loop.steps * dt,
            "cte_m": e,
            "heading_err_rad": psi,
            "speed": v,
            "v_ref": v_ref,
            "accel": float(ego.accel),
            "steer": float(ego.steer),
            "crashed": bool(ego.crashed),
        }
        if over:
            self.episode = self._finish()
            self.report = evaluate(self.episode, self.eval_config)
            if self.report.success:
                terms["success"] = w.success
            info["status"] = loop.status.value
            info["is_success"] = bool(self.report.success)
            info["metrics"] = _metrics_dict(self.report)
        info["reward_terms"] = terms
        reward = float(sum(terms.values()))
        return self._obs32(), reward, bool(terminated), bool(truncated), info

    def render(self) -> np.ndarray | None:  # type: ignore[override]
        """An RGB frame of the scene with the planned path (``render_mode="rgb_array"``).

        Drawn: highway-env's lanes, obstacles and vehicles at their true sizes, the
        planned path (blue), the goal (green circle), the driven trace (red), the
        reference points of the observation (orange) and a read-out of time, speed,
        executed curvature, cross-track error and mode.
        """
        if self.render_mode != "rgb_array":
            return None
        if self._sim is None or self._loop is None:
            raise RuntimeError("DriveEnv.render: call reset() first")
        scen = self._scenario
        camera = scen.camera()
        key = (scen.map.bounds, scen.lane_y)
        if self._renderer is None or self._renderer_key != key:
            if camera.follow:  # a long road: a window that follows the ego
                self._renderer = SceneRenderer(camera.size, camera.scaling, camera.centre)
            else:
                self._renderer = SceneRenderer(*view_for(scen.map.bounds, scen.lane_y))
            self._renderer_key = key
        if camera.follow:
            self._renderer.centre = np.array([self._ego.rear[0] + 25.0, camera.centre[1]])
        obs = self._obs64
        k = self.config.n_ref_points
        x, y, yaw, _ = self._rec.states[-1]
        c, s = math.cos(yaw), math.sin(yaw)
        ref = obs[6 : 6 + 2 * k].reshape(k, 2)
        ref_world = np.column_stack(
            [x + c * ref[:, 0] - s * ref[:, 1], y + s * ref[:, 0] + c * ref[:, 1]]
        )
        vehicle = scen.vehicle
        kappa = math.tan(self._ego.steer) / vehicle.wheelbase
        cfg = self.config
        mode = f"{cfg.controller} + residual" if cfg.residual else "agent"
        lines = [
            f"t {self._loop.t:5.2f} s   v {obs[0]:4.2f} m/s (ref {obs[4]:4.2f})",
            f"kappa {kappa:+.3f} 1/m (max {vehicle.kappa_max:.3f})",
            f"cte {obs[2]:+.3f} m   {mode}   gear {'R' if obs[-2] < 0 else 'D'}",
        ]
        return self._renderer.frame(
            self._road,
            self.sim_config.simulation_frequency,
            self.path.xy,  # type: ignore[union-attr]
            (scen.goal.x, scen.goal.y),
            [st[:2] for st in self._rec.states],
            ref_world,
            lines,
            gears=self.path.gears,  # type: ignore[union-attr]
        )

    def close(self) -> None:
        """Close the highway-env scene (idempotent)."""
        if self._sim is not None:
            self._sim.close()
            self._sim = None
        self._renderer = None
        self._loop = None
        # The scene's other handles too: a closed env kept its highway-env road alive.
        self._driver = self._ego = self._road = self._rec = None
        super().close()

    # ------------------------------------------------------------------ internals

    def _use_reference(self, path: Path) -> None:
        """A new reference: the start, or a re-planned one took over (``overtake-traffic``)."""
        self.path = path
        self._use_segment(self._ctrl.segment)

    def _use_segment(self, index: int) -> None:
        """Observe and reward along gear segment ``index`` of the path (the controller's)."""
        ctrl = self._ctrl
        seg = ctrl.segments[index]
        self._segment = index
        self._seg_s0 = seg.s0
        last = ctrl.segments[-1]
        self._to_goal = last.s0 + last.length - (seg.s0 + seg.length)
        self._projector = PathProjector(
            seg.path, arc_end=not self.path.is_forward_only  # type: ignore[union-attr]
        )
        self._profile = ctrl.profile  # the driver's controller rebuilt it for this segment
        self._relaunch.start, self._proj_s = None, 0.0  # arc lengths of another segment

    def _follow_segments(self) -> None:
        """Move on to the next gear segment when the car has (see the class docs)."""
        ctrl = self._ctrl
        if self._runs_driver:
            if ctrl.segment != self._segment:
                self._use_segment(ctrl.segment)
            return
        if self._segment >= len(ctrl.segments) - 1:
            return
        proj = self._projector.project(*self._ego.rear[:2])
        if starts_next_segment(
            self._ego.speed, ctrl.segments[self._segment + 1].gear,
            self._projector.length - proj.s, ctrl.segments[self._segment].length,
            self.eval_config.goal_tol_m, self.eval_config.stop_speed,
        ):  # fmt: skip
            ctrl.start_segment(self._segment + 1)
            self._use_segment(self._segment + 1)

    def _clipped_s(self, rear: Any) -> float:
        """Length along the current reference of the rear axle's projection, clipped to it.

        On a path with gear changes: along the whole path, the segment being driven
        clipped to its ends.
        """
        proj = self._projector.project(rear[0], rear[1])
        return self._seg_s0 + min(max(proj.s, 0.0), self._projector.length)

    def _progress_s(self) -> float:
        """Length along the path of the rear axle's projection, clipped to its segment."""
        return self._seg_s0 + min(max(self._proj_s, 0.0), self._projector.length)

    def _observe64(self) -> np.ndarray:
        """The observation in float64 (clipped to the Box bounds); sets ``_proj_s``."""
        obs, self._proj_s = self._layout.observe(
            self._ego, self._projector, self._v_ref_at(), self._rec.others,
            self._ctrl.segments[self._segment].gear, self._to_goal,
        )
        return obs

    def _v_ref_at(self) -> Callable[[float], float]:
        """The reference speed at an arc length: what the car is asked to drive now.

        The profile, capped by the speed loop's stop line (the oncoming gate) and the
        rise after it, and by the speed the traffic driver's IDM settles to at the
        current gap while it follows (:mod:`rrtdrive.envs.reference_speed`).
        """
        profile, speed, stop_at = self._profile, self._speed, self._ctrl.speed.stop_at
        cap = following_cap(self._driver, self._ego.speed)
        (rise := self._relaunch).update(stop_at, self._proj_s, self._ego.speed)

        def v_ref_at(s: float) -> float:
            return min(stop_line_speed(profile.at(s)[0], s, stop_at, speed), cap, rise.cap(s))

        return v_ref_at

    def _obs32(self) -> np.ndarray:
        return self._obs64.astype(np.float32)  # a fresh array every call

    def _finish(self) -> Episode:
        """The finished episode as the runner would return it, from the loop's log."""
        cfg, loop, task, ref = self.config, self._loop, self._scenario, self._reference
        assert loop is not None
        log = loop.log(self._wall)
        path, traffic = task.outcome(
            self._driver, ref, float(log.t[-1]) if loop.reached else None
        )
        label = f"{cfg.controller}+residual" if cfg.residual else "agent"
        return Episode(
            task, ref.planner, label, int(self.episode_seed or 0), ref.plan, path, log,
            loop.status, loop.message, self._episode_config, traffic,
        )


def _metrics_dict(report: EpisodeReport) -> dict[str, Any]:
    """The report as a dict whose value types do not depend on the outcome.

    A metric that may not apply (``X | None``) is a float, ``NaN`` when it does not (a
    yes/no 1.0 / 0.0): gymnasium's vector envs type a batch by its first value, and a
    ``None`` read ``False`` in a bool batch (``TypeError`` in an int one). The
    wall-clock fields (:data:`~rrtdrive.evaluation.report.WALL_CLOCK_FIELDS`) are left
    out, so that a seeded episode's infos are the same on every run (gymnasium's
    ``check_env`` compares them; ``env.unwrapped.report`` has them).
    """
    out: dict[str, Any] = {}
    for f in fields(report):
        if f.name in WALL_CLOCK_FIELDS:
            continue
        v, kind = getattr(report, f.name), str(f.type)
        if kind in ("float | None", "int | None", "bool | None"):
            v = math.nan if v is None else float(v)
        out[f.name] = v
    return out
