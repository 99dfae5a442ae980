"""The gymnasium environment: drive a planned path in highway-env, as an agent.

Each episode builds a scenario (:func:`rrtdrive.sim.scenes.make_scenario`) for an
*episode seed*, plans its path (:func:`rrtdrive.sim.runner.plan_scenario`), builds
the highway-env scene (:func:`rrtdrive.sim.scenes.build_env`) and then steps it
exactly like the closed-loop runner (:func:`rrtdrive.sim.runner.drive`): once per
simulation step it sets the ego's acceleration and steering, lets the other
vehicles act and advances the physics. The agent's action sets those two numbers
directly, or - with ``residual=True`` - is added to a tracking controller's
command, so that a zero action reproduces the plain controller exactly.

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

from rrtdrive.controllers import PathProjector, SpeedProfile, VehicleState
from rrtdrive.envs.action import ResidualMixer, action_command
from rrtdrive.envs.config import DriveEnvConfig, _require_mapping
from rrtdrive.envs.observation import OBS_CLIP, ObservationLayout, observation_names
from rrtdrive.envs.reference_speed import following_speed, stop_line_speed
from rrtdrive.envs.render import SceneRenderer, view_for
from rrtdrive.envs.reward import RewardWeights, state_terms
from rrtdrive.evaluation import EpisodeReport, EvalConfig, evaluate
from rrtdrive.sim.drivelog import DriveRecorder
from rrtdrive.sim.episode import Episode
from rrtdrive.sim.runner import EpisodeConfig
from rrtdrive.sim.scenes import build_env, scenario_rngs
from rrtdrive.sim.tasks import TRAFFIC_PLANNER, plan_scenario
from rrtdrive.sim.traffic import OncomingGate, conflict_zone
from rrtdrive.types import InputError, Path, PlanResult, PlanStatus, require_int, wrap_angle

# RewardWeights, observation_names and OBS_CLIP are re-exported from their modules,
# where they lived before the split.
__all__ = ["DriveEnv", "DriveEnvConfig", "RewardWeights", "observation_names", "OBS_CLIP"]

#: Episode seeds drawn before giving up when planning keeps failing.
MAX_PLAN_ATTEMPTS = 20

_RESET_OPTIONS = ("episode_seed",)


class DriveEnv(gym.Env[np.ndarray, np.ndarray]):
    """Drive a planned, curvature-bounded path in highway-env.

    Registered as ``rrtdrive/Parking-v0``, ``rrtdrive/Overtake-v0`` and
    ``rrtdrive/OvertakeTraffic-v0`` (re-planned in the loop, see ``replan_options``);
    keyword arguments of ``gym.make`` reach this constructor.

    **Observation** (``float32``, shape ``(6 + 3 K + 5 M,)``, SI units, ego frame =
    rear axle, x forward, y left): the car's state against the path, K reference
    points ahead with their curvatures, the M nearest other vehicles; the entries
    are listed in :mod:`rrtdrive.envs.observation` and by :func:`observation_names`.

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
    scenario : str, optional
        Scenario name (``parking``, ``overtake``, ``overtake-traffic``); the
        registered ids pass it. Default ``config.scenario``, or ``"parking"``.
    config : DriveEnvConfig, optional
        The options as one value; keyword ``options`` replace some of its fields.
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
        scenario: str | None = None,
        *,
        config: DriveEnvConfig | None = None,
        render_mode: str | None = None,
        **options: Any,
    ) -> None:
        super().__init__()
        if config is None:
            config = DriveEnvConfig.from_options("parking" if scenario is None else scenario,
                                                 **options)
        elif not isinstance(config, DriveEnvConfig):
            raise InputError(f"config: expected a DriveEnvConfig, got {config!r}")
        else:
            if scenario is not None and scenario != config.scenario:
                raise InputError(
                    f"scenario: {scenario!r} differs from config.scenario {config.scenario!r}"
                )
            config = config.with_options(**options)
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
        self._over = True

    # ------------------------------------------------------------------ setup

    def _start_episode(self, seed: int) -> PlanResult:
        """Build, plan and set up the episode of ``seed``; return the plan (maybe failed)."""
        cfg = self.config
        scen = cfg.scenario_for(seed)
        driver = None
        if scen.is_traffic:
            plan = None
        else:
            plan = plan_scenario(scen, cfg.planner, seed, cfg.budget)
            if not plan.success or len(plan.path) < 2:
                return plan
        speed = cfg.speed_for(scen)
        ctrl = cfg.controller_for(scen, speed)
        if self._sim is not None:
            self._sim.close()
        sim = build_env(scen, self.sim_config)
        u = sim.unwrapped
        ego = u.vehicle
        if scen.is_traffic:
            # Receding-horizon re-planning in the loop, as in the runner.
            from rrtdrive.sim.traffic_driver import TrafficDriver

            _, plan_rng, _ = scenario_rngs(seed)
            driver = TrafficDriver(sim, scen, ctrl, speed, cfg.replan, plan_rng)
            driver.start()
            first = driver.references[-1][1]
            plan = PlanResult(
                PlanStatus.SOLVED, TRAFFIC_PLANNER, first, first.xy, (), 0, 0, 0.0,
                "lane reference; re-planned in the loop",
            )
        path = plan.path
        gate, cars = None, None
        if scen.oncoming and scen.lane_y is not None and driver is None:
            # As the runner: hold the controller before the oncoming lane until a gap.
            zone = conflict_zone(path, scen.lane_y, scen.lane_width, scen.vehicle)
            if zone is not None:
                cars = [v for v in u.road.vehicles if v is not ego and v.speed > 0]
                gate = OncomingGate(zone, (path.arc_length(), path.samples[:, 3]), speed)
        if driver is None:
            ctrl.reset(path, v_start=ego.speed)
        self._driver = driver
        self._sim, self._ego, self._road = sim, ego, u.road
        self._scenario, self._plan, self._speed, self._ctrl = scen, plan, speed, ctrl
        self._gate, self._gate_cars = gate, cars
        self.path = path
        self.episode_seed = seed
        self._dt = self.sim_config.dt
        self._max_time = cfg.max_time_s or scen.max_time_s
        self._n_max = int(math.ceil(self._max_time / self._dt - 1e-9))
        self._projector = PathProjector(path)
        p = self._projector
        if driver is not None:
            self._profile = ctrl.profile
        else:
            self._profile = SpeedProfile(np.asarray(p.s), np.asarray(p.kappa), speed, ego.speed)
        self._rec = DriveRecorder(self._sim, self._dt)
        self._k = 0
        self._mixer = ResidualMixer(cfg.limits, speed, self._dt)
        self._t = 0.0
        self._wall = 0.0
        self._status = ""
        self._over = False
        self.episode = None
        self.report = None
        self._obs64 = self._observe64()
        self._s = self._progress_s()
        return plan

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
            ``MAX_PLAN_ATTEMPTS`` drawn seeds in a row).
        """
        super().reset(seed=seed)
        self._over = True  # until an episode is set up
        opts = _require_mapping("options", options)
        for key in opts:
            if key not in _RESET_OPTIONS:
                raise InputError(
                    f"options.{key}: unknown reset option; choose from {list(_RESET_OPTIONS)}"
                )
        requested = opts.get("episode_seed")
        if requested is not None:
            s = require_int("options.episode_seed", requested, 0)
            plan = self._start_episode(s)
            if not plan.success or self._over:
                raise RuntimeError(
                    f"options.episode_seed: planning failed for episode seed {s} "
                    f"({plan.status.value}): {plan.message}"
                )
        else:
            lo, hi = self.config.seed_range
            for _ in range(MAX_PLAN_ATTEMPTS):
                s = int(self.np_random.integers(lo, hi))
                plan = self._start_episode(s)
                if plan.success and not self._over:
                    break
            else:
                raise RuntimeError(
                    f"planning failed for {MAX_PLAN_ATTEMPTS} episode seeds in a row "
                    f"(last {s}, {plan.status.value}): {plan.message}"
                )
        info = {
            "episode_seed": self.episode_seed,
            "scenario": self.config.scenario,
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
            applied command), ``time_s``, ``crashed`` and ``episode_seed``; at the
            end also ``status``, ``is_success`` and ``metrics`` (the evaluators'
            report as a dict, ``NaN`` for a metric that does not apply).
        """
        if self._sim is None or self._over:
            raise RuntimeError("DriveEnv.step: call reset() first (the episode is over)")
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
            if self._k >= self._n_max:
                break
            r = ego.rear
            if driver is not None:
                n_refs = len(driver.references)
                c_accel, c_steer = driver.control(self._t)
                if len(driver.references) != n_refs:
                    carried += self._clipped_s(r) - s_before
                    self._use_reference(driver.references[-1][1])
                    s_before = self._clipped_s(r)
                if not residual:
                    accel, steer = d_accel, d_steer
                else:
                    accel, steer = mixer.command(ctrl, c_accel, c_steer, d_accel, d_steer)
            elif residual:
                if self._gate is not None:
                    ctrl.speed.stop_at = self._gate.stop_line(
                        ctrl.s, ego.speed, self._gate_cars or []
                    )
                c_accel, c_steer = ctrl.control(
                    VehicleState(r[0], r[1], r[2], ego.speed, ego.steer, self._t)
                )
                accel, steer = mixer.command(ctrl, c_accel, c_steer, d_accel, d_steer)
            else:
                accel, steer = d_accel, d_steer
            self._rec.step(accel, steer)
            mixer.applied(accel)
            self._t += dt
            self._k += 1
            steps += 1
            if ego.crashed:
                self._status = "crashed"
                break
            if driver is not None:
                if self._overtaken():
                    self._status = "completed"
                    break
            elif self._arrived():
                self._status = "arrived"
                break
        self._wall += time.perf_counter() - wall0

        self._obs64 = self._observe64()
        s_after = self._progress_s()
        self._s = s_after
        w = self.weights
        span = steps * dt
        e, psi, v, v_ref = (float(self._obs64[i]) for i in (2, 3, 0, 4))
        terms = state_terms(
            w, progress_m=carried + s_after - s_before, cte=e, heading_err=psi, speed=v,
            v_ref=v_ref, span_s=span, crashed=self._status == "crashed",
        )
        if not self._status and cfg.max_cte is not None and abs(e) > cfg.max_cte:
            self._status = "off_path"
            terms["off_path"] = -w.off_path
        terminated = self._status in ("crashed", "arrived", "off_path", "completed")
        truncated = not terminated and self._k >= self._n_max
        info: dict[str, Any] = {
            "episode_seed": self.episode_seed,
            "time_s": self._t,
            "cte_m": e,
            "heading_err_rad": psi,
            "speed": v,
            "v_ref": v_ref,
            "accel": float(ego.accel),
            "steer": float(ego.steer),
            "crashed": bool(ego.crashed),
        }
        if terminated or truncated:
            if not terminated:
                self._status = "timeout"
            self._over = True
            self.episode = self._finish()
            self.report = evaluate(self.episode, self.eval_config)
            if self.report.success:
                terms["success"] = w.success
            info["status"] = self._status
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
        if self._sim is None:
            raise RuntimeError("DriveEnv.render: call reset() first")
        scen = self._scenario
        key = (scen.map.bounds, scen.lane_y)
        if self._renderer is None or self._renderer_key != key:
            if scen.is_traffic:  # a long road: a window that follows the ego
                self._renderer = SceneRenderer((960, 320), 8.0, (0.0, 0.0))
            else:
                self._renderer = SceneRenderer(*view_for(scen.map.bounds, scen.lane_y))
            self._renderer_key = key
        if scen.is_traffic:
            self._renderer.centre = np.array([self._ego.rear[0] + 25.0, scen.lane_y + 2.0])
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
            f"t {self._t:5.2f} s   v {obs[0]:4.2f} m/s (ref {obs[4]:4.2f})",
            f"kappa {kappa:+.3f} 1/m (max {vehicle.kappa_max:.3f})",
            f"cte {obs[2]:+.3f} m   {mode}",
        ]
        return self._renderer.frame(
            self._road,
            self.sim_config.simulation_frequency,
            self.path.xy,  # type: ignore[union-attr]
            (scen.goal.x, scen.goal.y),
            [st[:2] for st in self._rec.states],
            ref_world,
            lines,
        )

    def close(self) -> None:
        """Close the highway-env scene (idempotent)."""
        if self._sim is not None:
            self._sim.close()
            self._sim = None
        self._renderer = None
        self._over = True
        super().close()

    # ------------------------------------------------------------------ internals

    def _use_reference(self, path: Path) -> None:
        """A re-planned reference took over (``overtake-traffic``)."""
        self.path = path
        self._projector = PathProjector(path)
        self._profile = self._ctrl.profile  # the driver's controller rebuilt it for this path

    def _clipped_s(self, rear: Any) -> float:
        """Arc length of the rear axle's projection on the current reference, clipped to it."""
        proj = self._projector.project(rear[0], rear[1])
        return min(max(proj.s, 0.0), self._projector.length)

    def _overtaken(self) -> bool:
        from rrtdrive.sim.tasks import overtake_complete

        driver = self._driver
        lead = driver.lead
        if lead is None:
            return False
        x, y, yaw = self._ego.rear
        return overtake_complete(
            (x, y, yaw), (lead.position[0], lead.position[1]), lead.LENGTH, driver.lane_y,
            driver.lane_width, driver.vehicle, driver.config.complete_gap_m,
        )

    def _arrived(self) -> bool:
        ego = self._ego
        if self.config.residual:
            return bool(self._ctrl.arrived and ego.speed == 0.0)
        goal = self._scenario.goal
        x, y, yaw = ego.rear
        cfg = self.eval_config
        return bool(
            abs(ego.speed) <= cfg.stop_speed
            and math.hypot(x - goal.x, y - goal.y) <= cfg.goal_tol_m
            and abs(float(wrap_angle(yaw - goal.yaw))) <= cfg.goal_tol_rad
        )

    def _progress_s(self) -> float:
        """Arc length of the rear axle's projection, clipped to the path."""
        return min(max(self._proj_s, 0.0), self._projector.length)

    def _observe64(self) -> np.ndarray:
        """The observation in float64 (clipped to the Box bounds); sets ``_proj_s``."""
        obs, self._proj_s = self._layout.observe(
            self._ego, self._projector, self._v_ref_at(), self._rec.others
        )
        return obs

    def _v_ref_at(self) -> Callable[[float], float]:
        """The reference speed at an arc length: what the car is asked to drive now.

        The speed profile, capped by the speed loop's stop line (the oncoming gate)
        and, while the traffic driver follows a slower car, by the speed its IDM
        settles to at the current gap (:mod:`rrtdrive.envs.reference_speed`).
        """
        profile, speed = self._profile, self._speed
        stop_at = self._ctrl.speed.stop_at
        cap = math.inf
        driver = self._driver
        if driver is not None and driver.mode == "follow":
            # The driver's own gap measure, the one its IDM cap uses (read-only).
            lead = driver._lead_gap()
            if lead is not None:
                gap, closing = lead
                v_lead = self._ego.speed - closing
                cap = following_speed(driver.config.idm, driver.speed.v_max, gap, v_lead)

        def v_ref_at(s: float) -> float:
            return min(stop_line_speed(profile.at(s)[0], s, stop_at, speed), cap)

        return v_ref_at

    def _obs32(self) -> np.ndarray:
        return self._obs64.astype(np.float32)  # a fresh array every call

    def _finish(self) -> Episode:
        """The finished episode as the runner would return it."""
        cfg = self.config
        log = self._rec.log(self._status in ("arrived", "completed"), self._wall)
        t_end = float(log.t[-1])
        if self._status == "crashed":
            message = f"highway-env reported a crash at t = {t_end:.2f} s"
        elif self._status == "off_path":
            message = f"left the path by more than {cfg.max_cte:g} m at t = {t_end:.2f} s"
        elif self._status == "arrived":
            where = "the end of the path" if cfg.residual else "the goal"
            message = f"stopped at {where} at t = {t_end:.2f} s"
        elif self._status == "completed":
            message = f"overtake complete at t = {t_end:.2f} s"
        elif self._driver is not None:
            message = f"no overtake within {self._max_time:g} s (followed the lead car)"
        else:
            message = f"not stopped at the goal within {self._max_time:g} s"
        config = EpisodeConfig(
            sim=self.sim_config,
            speed=self._speed,
            controller_options=dict(cfg.controller_options),  # type: ignore[arg-type]
            budget=cfg.budget,  # type: ignore[arg-type]
            max_time_s=self._max_time,
            replan=cfg.replan,
        )
        label = f"{cfg.controller}+residual" if cfg.residual else "agent"
        if self._driver is not None:
            traffic = self._driver.finish(t_end if self._status == "completed" else None)
            return Episode(
                self._scenario, TRAFFIC_PLANNER, label, int(self.episode_seed or 0), None,
                traffic.executed, log, self._status, message, config, traffic,
            )
        return Episode(
            self._scenario, cfg.planner, label, int(self.episode_seed or 0), self._plan,
            self.path, log, self._status, message, config,  # type: ignore[arg-type]
        )


def _metrics_dict(report: EpisodeReport) -> dict[str, Any]:
    """The report as a dict whose value types do not depend on the outcome.

    A float metric that does not apply is ``NaN`` rather than ``None``, so that
    gymnasium's vector environments can batch the dicts of several episodes.
    """
    out: dict[str, Any] = {}
    for f in fields(report):
        v = getattr(report, f.name)
        if v is None and "float" in str(f.type):
            v = math.nan
        out[f.name] = v
    return out
