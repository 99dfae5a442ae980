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
:attr:`DriveEnv.report`. The observation, action and reward are documented in
``docs/gym.md`` and on :class:`DriveEnv`.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Mapping
from dataclasses import dataclass, fields
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from rrtdrive.controllers import (
    CONTROLLERS,
    PathProjector,
    SpeedConfig,
    SpeedProfile,
    TrackingController,
    VehicleState,
    make_controller,
)
from rrtdrive.envs.render import SceneRenderer, view_for
from rrtdrive.evaluation import EpisodeReport, EvalConfig, evaluate
from rrtdrive.planning import PLANNERS
from rrtdrive.sim.drivelog import DriveRecorder
from rrtdrive.sim.ego import EgoVehicle
from rrtdrive.sim.episode import Episode
from rrtdrive.sim.runner import EpisodeConfig
from rrtdrive.sim.scenes import SimConfig, build_env, scenario_rngs
from rrtdrive.sim.tasks import (
    DEFAULT_PLANNER,
    SCENARIOS,
    TRAFFIC_PLANNER,
    make_scenario,
    plan_scenario,
    traffic_speed_config,
)
from rrtdrive.sim.tasks import Task as Scenario
from rrtdrive.sim.traffic import OncomingGate, conflict_zone
from rrtdrive.types import (
    Budget,
    InputError,
    Path,
    PlanResult,
    PlanStatus,
    require_int,
    wrap_angle,
)

__all__ = ["DriveEnv", "RewardWeights", "observation_names", "OBS_CLIP"]

#: Distances in the observation are clipped to +-OBS_CLIP metres (the bounds of the Box).
OBS_CLIP = 1000.0
#: Curvatures in the observation are clipped to +-KAPPA_CLIP 1/m.
KAPPA_CLIP = 10.0
#: Episode seeds drawn before giving up when planning keeps failing.
MAX_PLAN_ATTEMPTS = 20

_RESET_OPTIONS = ("episode_seed",)


@dataclass(frozen=True)
class RewardWeights:
    """Weights of the reward terms (all >= 0).

    Per step the reward is the sum of the terms ``progress``, ``cte``, ``heading``,
    ``speed``, ``collision``, ``off_path`` and ``success``
    with

    * ``progress = w_progress * (s_after - s_before)``: metres of arc length gained
      along the path (the rear axle's projection, clipped to the path);
    * ``cte = -w_cte * e^2 * T``, ``heading = -w_heading * psi^2 * T`` and
      ``speed = -w_speed * (v - v_ref)^2 * T``: squared cross-track, heading and
      speed errors after the step, times the step's duration ``T`` in seconds (so
      the sums do not depend on the control rate);
    * ``collision = -w_collision`` on the step highway-env reports a crash;
    * ``off_path = -w_off_path`` on the step the rear axle ends more than
      ``max_cte`` from the path (the episode ends there);
    * ``success = +w_success`` on the last step when the evaluators call the
      episode a success.

    Parameters
    ----------
    progress : float
        Per metre of progress.
    cte : float
        Per m^2 s of squared cross-track error.
    heading : float
        Per rad^2 s of squared heading error.
    speed : float
        Per (m/s)^2 s of squared error against the speed profile.
    collision : float
        Penalty of a crash.
    off_path : float
        Penalty of leaving the path by more than ``max_cte``.
    success : float
        Bonus of a successful episode.

    Notes
    -----
    Per second, progress earns ``w_progress * v`` and the speed term costs
    ``w_speed * (v - v_ref)^2``, so the best constant speed is
    ``v_ref + w_progress / (2 w_speed)``: the default ``w_speed = 5`` keeps that
    within 0.1 m/s of the speed profile (a small ``w_speed`` teaches an agent to
    speed, since discounting rewards early progress).
    """

    progress: float = 1.0
    cte: float = 10.0
    heading: float = 10.0
    speed: float = 5.0
    collision: float = 50.0
    off_path: float = 50.0
    success: float = 50.0

    def __post_init__(self) -> None:
        for f in fields(self):
            v = getattr(self, f.name)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                raise InputError(f"reward.{f.name}: expected a finite number, got {v!r}")
            if v < 0:
                raise InputError(f"reward.{f.name}: must be >= 0, got {v!r}")
            object.__setattr__(self, f.name, float(v))

    @classmethod
    def from_any(cls, value: RewardWeights | Mapping[str, float] | None) -> RewardWeights:
        """Weights from ``None`` (defaults), a mapping of some weights, or weights."""
        if value is None:
            return cls()
        if isinstance(value, cls):
            return value
        if not isinstance(value, Mapping):
            raise InputError(f"reward: expected a mapping of weights, got {value!r}")
        known = [f.name for f in fields(cls)]
        for key in value:
            if key not in known:
                raise InputError(f"reward.{key}: unknown weight; choose from {known}")
        return cls(**dict(value))


#: Residual mode: the residual fades out linearly over this many metres before the goal.
RESIDUAL_FADE_M = 1.0

#: Per observed vehicle: present (1/0), then its body centre and velocity relative to
#: the ego's rear axle, in the ego frame.
VEHICLE_FEATURES = ("present", "dx", "dy", "dvx", "dvy")


def observation_names(n_ref_points: int, n_vehicles: int = 0) -> list[str]:
    """Names of the observation entries, in order.

    Examples
    --------
    >>> observation_names(2)
    ['speed', 'steer', 'cte', 'heading_err', 'v_ref', 'dist_to_goal', 'ref_x_1', 'ref_y_1', \
'ref_x_2', 'ref_y_2', 'ref_kappa_1', 'ref_kappa_2']
    >>> observation_names(1, n_vehicles=1)[-5:]
    ['veh_present_1', 'veh_dx_1', 'veh_dy_1', 'veh_dvx_1', 'veh_dvy_1']
    """
    names = ["speed", "steer", "cte", "heading_err", "v_ref", "dist_to_goal"]
    for i in range(1, n_ref_points + 1):
        names += [f"ref_x_{i}", f"ref_y_{i}"]
    names += [f"ref_kappa_{i}" for i in range(1, n_ref_points + 1)]
    for j in range(1, n_vehicles + 1):
        names += [f"veh_{f}_{j}" for f in VEHICLE_FEATURES]
    return names


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
    return dict(value)


class DriveEnv(gym.Env[np.ndarray, np.ndarray]):
    """Drive a planned, curvature-bounded path in highway-env.

    Registered as ``rrtdrive/Parking-v0``, ``rrtdrive/Overtake-v0`` and
    ``rrtdrive/OvertakeTraffic-v0`` (re-planned in the loop, see ``replan_options``);
    keyword arguments of ``gym.make`` reach this constructor.

    **Observation** (``float32``, shape ``(6 + 3 K + 5 M,)``, SI units, ego frame =
    rear axle, x forward, y left):

    ====================  ==========================================================
    index                 entry
    ====================  ==========================================================
    0                     speed ``v`` (m/s)
    1                     steering angle applied in the last step (rad, left > 0)
    2                     cross-track error of the rear axle (m, left of the path > 0)
    3                     heading error, yaw minus path heading (rad, in [-pi, pi])
    4                     reference speed of the speed profile here (m/s)
    5                     distance to the goal along the path (m, < 0 once past it)
    6 .. 5 + 2K           next K reference points ``x_1, y_1, ..., x_K, y_K`` (m),
                          every ``ref_spacing`` metres of arc ahead of the rear
                          axle's projection (held at the path's end)
    6 + 2K .. 5 + 3K      path curvature at those points (1/m)
    6 + 3K .. 5 + 3K + 5M the M nearest other vehicles within ``vehicle_range``
                          (by distance from the rear axle to their body centre,
                          nearest first), 5 entries each: present (1, or 0 for an
                          empty slot, all zeros), body centre ``dx, dy`` (m) and
                          velocity ``dvx, dvy`` relative to the ego's (m/s)
    ====================  ==========================================================

    Distances are clipped to +-1000 m and curvatures to +-10 1/m (the Box bounds);
    :func:`observation_names` lists the entries.

    **Action** (``float32``, ``[-1, 1]^2``): ``[a, d]``. Acceleration ``a * a_max``
    for ``a >= 0`` and ``a * |a_min|`` below (the speed loop's limits, 2 and -4
    m/s^2 by default, so 0 means coasting); steering ``d * steer_limit`` with
    ``steer_limit = atan(L kappa_max)`` (22.7°, the car's curvature limit). With
    ``residual=True`` the command is the controller's plus the action mapped the
    same way and multiplied by ``residual_scale``, clipped to the same limits and,
    for the acceleration, to the speed loop's jerk limits around the last applied
    command (:meth:`_residual_accel`);
    once the controller holds the car at the end of the path, or brakes past it,
    the residual no longer applies (so a zero action is the plain controller, and
    no residual can keep the car from coming to rest at the goal).

    **Episode end**: terminated on highway-env's first crash (status
    ``"crashed"``), when the rear axle is more than ``max_cte`` from the path
    (``"off_path"``), or on arrival (``"arrived"``): with ``residual=True`` when
    the controller has stopped the car at the end of the path (the runner's rule),
    otherwise when the rear axle is stopped (|v| <= 0.1 m/s) within 0.5 m and 10°
    of the goal; ``overtake-traffic`` instead ends (``"completed"``) when the
    overtake is complete. Truncated at the scenario's time limit (``"timeout"``).

    Parameters
    ----------
    scenario : str
        Scenario name (``parking``, ``overtake``, ``overtake-traffic``).
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
    n_vehicles : int
        Number M of other vehicles in the observation (0: none, the default).
    vehicle_range : float
        Vehicles further than this from the rear axle (m) are not observed.
    ref_spacing : float
        Arc length between reference points, metres.
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
        Reward weights (see :class:`RewardWeights`).
    scenario_options : mapping, optional
        Keyword arguments of :func:`~rrtdrive.sim.scenes.make_scenario` (``jitter``,
        ``spot``, ``oncoming``; ``density``, ``lead_speed``, ``lead_model`` for
        ``overtake-traffic``).
    replan_options : mapping, optional
        ``overtake-traffic``: :class:`~rrtdrive.sim.replanning.ReplanConfig` fields.
        The reference path is then re-planned in the loop
        (:class:`~rrtdrive.sim.replanning.TrafficDriver`, the runner's driver): the
        observation follows the current reference, the residual is added to the
        driver's command, progress is counted across reference switches, and the
        episode ends (``"completed"``) when the overtake is complete.
    controller_options : mapping, optional
        Controller gains.
    speed_options : mapping, optional
        :class:`~rrtdrive.controllers.SpeedConfig` fields (``v_max`` defaults to the
        scenario's).
    budget : Budget, optional
        Planning budget per episode.
    seed_range : tuple of int
        Episode seeds are drawn uniformly from ``[lo, hi)`` with ``self.np_random``
        unless ``reset(options={"episode_seed": n})`` names one.
    render_mode : str, optional
        ``"rgb_array"`` or ``None``.

    Attributes
    ----------
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
        scenario: str = "parking",
        *,
        planner: str = DEFAULT_PLANNER,
        controller: str = "pure-pursuit",
        residual: bool = False,
        residual_scale: float = 0.25,
        n_ref_points: int = 10,
        ref_spacing: float = 1.5,
        n_vehicles: int = 0,
        vehicle_range: float = 100.0,
        action_repeat: int = 1,
        simulation_frequency: int = 20,
        max_time_s: float | None = None,
        max_cte: float | None = 10.0,
        reward: RewardWeights | Mapping[str, float] | None = None,
        scenario_options: Mapping[str, Any] | None = None,
        replan_options: Mapping[str, Any] | None = None,
        controller_options: Mapping[str, Any] | None = None,
        speed_options: Mapping[str, Any] | None = None,
        budget: Budget | None = None,
        seed_range: tuple[int, int] = (0, 2**31 - 1),
        render_mode: str | None = None,
    ) -> None:
        super().__init__()
        if not isinstance(scenario, str) or scenario not in SCENARIOS:
            raise InputError(f"scenario: unknown scenario {scenario!r}; choose from {SCENARIOS}")
        if not isinstance(planner, str) or planner not in PLANNERS:
            raise InputError(
                f"planner: unknown planner {planner!r}; choose from {sorted(PLANNERS)}"
            )
        if not isinstance(controller, str) or controller not in CONTROLLERS:
            raise InputError(
                f"controller: unknown controller {controller!r}; choose from {sorted(CONTROLLERS)}"
            )
        if not isinstance(residual, bool):
            raise InputError(f"residual: expected True or False, got {residual!r}")
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise InputError(
                f"render_mode: {render_mode!r} is not supported; choose from "
                f"{self.metadata['render_modes']} or None"
            )
        self.scenario_name = scenario
        self.planner_name = planner
        self.controller_name = controller
        self.residual = residual
        self.residual_scale = _require_number("residual_scale", residual_scale)
        self.n_ref_points = require_int("n_ref_points", n_ref_points, 1, 200)
        self.ref_spacing = _require_number("ref_spacing", ref_spacing)
        self.n_vehicles = require_int("n_vehicles", n_vehicles, 0, 50)
        self.vehicle_range = _require_number("vehicle_range", vehicle_range)
        self.action_repeat = require_int("action_repeat", action_repeat, 1, 1000)
        self.sim_config = SimConfig(simulation_frequency=simulation_frequency)
        self.max_time_s = None if max_time_s is None else _require_number("max_time_s", max_time_s)
        self.max_cte = None if max_cte is None else _require_number("max_cte", max_cte)
        self.weights = RewardWeights.from_any(reward)
        self.scenario_options = _require_mapping("scenario_options", scenario_options)
        self.replan_options = _require_mapping("replan_options", replan_options)
        self._replan = None
        if scenario == "overtake-traffic":
            from rrtdrive.sim.replanning import ReplanConfig

            try:
                self._replan = ReplanConfig(**self.replan_options)
            except TypeError as exc:
                raise InputError(f"replan_options: {exc}") from None
        elif self.replan_options:
            raise InputError("replan_options: only the overtake-traffic scenario re-plans")
        self.controller_options = _require_mapping("controller_options", controller_options)
        self.speed_options = _require_mapping("speed_options", speed_options)
        if budget is None:
            budget = Budget()
        if not isinstance(budget, Budget):
            raise InputError(f"budget: expected a rrtdrive.Budget, got {budget!r}")
        self.budget = budget
        if (
            not isinstance(seed_range, (tuple, list))
            or len(seed_range) != 2
            or any(isinstance(v, bool) or not isinstance(v, (int, np.integer)) for v in seed_range)
            or not 0 <= seed_range[0] < seed_range[1] <= 2**63
        ):
            raise InputError(f"seed_range: need integers 0 <= lo < hi <= 2**63, got {seed_range!r}")
        self.seed_range = (int(seed_range[0]), int(seed_range[1]))
        self.render_mode = render_mode
        self.eval_config = EvalConfig()

        # Validate the options once, on a scenario and controller of seed 0.
        probe = self._make_scenario(0)
        speed = self._speed_config(probe)
        probe_ctrl = self._make_controller(probe, speed)
        self._a_min = speed.a_min
        self._a_max = speed.a_max
        self._steer_limit = probe_ctrl.steer_limit

        fps = self.sim_config.simulation_frequency / self.action_repeat
        self.metadata = {**type(self).metadata, "render_fps": fps}
        self.action_space = spaces.Box(-1.0, 1.0, shape=(2,), dtype=np.float32)
        k = self.n_ref_points
        big = OBS_CLIP
        max_steer = probe.vehicle.max_steer
        low = np.concatenate(
            [
                [EgoVehicle.MIN_SPEED, -max_steer, -big, -math.pi, 0.0, -big],
                np.full(2 * k, -big),
                np.full(k, -KAPPA_CLIP),
                np.tile([0.0, -big, -big, -big, -big], self.n_vehicles),
            ]
        ).astype(np.float32)
        high = np.concatenate(
            [
                [EgoVehicle.MAX_SPEED, max_steer, big, math.pi, big, big],
                np.full(2 * k, big),
                np.full(k, KAPPA_CLIP),
                np.tile([1.0, big, big, big, big], self.n_vehicles),
            ]
        ).astype(np.float32)
        self.observation_space = spaces.Box(low, high, dtype=np.float32)
        # Clip in float64 to the float32 bounds, so the cast lands inside the Box.
        self._low64 = low.astype(np.float64)
        self._high64 = high.astype(np.float64)

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

    def _make_scenario(self, seed: int) -> Scenario:
        try:
            return make_scenario(self.scenario_name, seed, **self.scenario_options)
        except TypeError as exc:
            raise InputError(f"scenario_options: {exc}") from None

    def _speed_config(self, scenario: Scenario) -> SpeedConfig:
        base = {"v_max": scenario.v_max}
        if scenario.is_traffic:
            base = dataclasses.asdict(traffic_speed_config(scenario))
        options = {**base, **self.speed_options}
        try:
            return SpeedConfig(**options)
        except TypeError as exc:
            raise InputError(f"speed_options: {exc}") from None

    def _make_controller(self, scenario: Scenario, speed: SpeedConfig) -> TrackingController:
        return make_controller(
            self.controller_name, vehicle=scenario.vehicle, speed=speed, **self.controller_options
        )

    def _start_episode(self, seed: int) -> PlanResult:
        """Build, plan and set up the episode of ``seed``; return the plan (maybe failed)."""
        scen = self._make_scenario(seed)
        driver = None
        if scen.is_traffic:
            plan = None
        else:
            plan = plan_scenario(scen, self.planner_name, seed, self.budget)
            if not plan.success or len(plan.path) < 2:
                return plan
        speed = self._speed_config(scen)
        ctrl = self._make_controller(scen, speed)
        if self._sim is not None:
            self._sim.close()
        sim = build_env(scen, self.sim_config)
        u = sim.unwrapped
        ego = u.vehicle
        if scen.is_traffic:
            # Receding-horizon re-planning in the loop, as in the runner.
            from rrtdrive.sim.traffic_driver import TrafficDriver

            _, plan_rng, _ = scenario_rngs(seed)
            driver = TrafficDriver(sim, scen, ctrl, speed, self._replan, plan_rng)
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
        self._max_time = self.max_time_s or scen.max_time_s
        self._n_max = int(math.ceil(self._max_time / self._dt - 1e-9))
        self._projector = PathProjector(path)
        p = self._projector
        if driver is not None:
            self._profile = ctrl.profile
        else:
            self._profile = SpeedProfile(np.asarray(p.s), np.asarray(p.kappa), speed, ego.speed)
        self._rec = DriveRecorder(self._sim, self._dt)
        self._k = 0
        # The last applied and the controller's last acceleration command (both start
        # at the speed loop's 0, SpeedController.last_a).
        self._applied_accel = 0.0
        self._controller_accel = 0.0
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
            lo, hi = self.seed_range
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
            "scenario": self.scenario_name,
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
        a = np.asarray(action, dtype=np.float64).reshape(-1)
        if a.shape != (2,) or not np.all(np.isfinite(a)):
            raise InputError(f"action: expected two finite numbers, got {action!r}")
        a0 = min(max(float(a[0]), -1.0), 1.0)
        a1 = min(max(float(a[1]), -1.0), 1.0)
        if self.residual:
            a0 *= self.residual_scale
            a1 *= self.residual_scale
        d_accel = a0 * self._a_max if a0 >= 0.0 else a0 * -self._a_min
        d_steer = a1 * self._steer_limit

        ego, ctrl, dt = self._ego, self._ctrl, self._dt
        steps = 0
        s_before = self._s
        carried = 0.0  # progress on references that were replaced during this step
        driver = self._driver
        wall0 = time.perf_counter()
        for _ in range(self.action_repeat):
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
                if not self.residual:
                    accel, steer = d_accel, d_steer
                else:
                    accel, steer = self._residual_command(c_accel, c_steer, d_accel, d_steer)
            elif self.residual:
                if self._gate is not None:
                    ctrl.speed.stop_at = self._gate.stop_line(
                        ctrl.s, ego.speed, self._gate_cars or []
                    )
                c_accel, c_steer = ctrl.control(
                    VehicleState(r[0], r[1], r[2], ego.speed, ego.steer, self._t)
                )
                accel, steer = self._residual_command(c_accel, c_steer, d_accel, d_steer)
            else:
                accel, steer = d_accel, d_steer
            self._rec.step(accel, steer)
            self._applied_accel = accel
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
        terms = {
            "progress": w.progress * (carried + s_after - s_before),
            "cte": -w.cte * e * e * span,
            "heading": -w.heading * psi * psi * span,
            "speed": -w.speed * (v - v_ref) ** 2 * span,
            "collision": -w.collision if self._status == "crashed" else 0.0,
            "off_path": 0.0,
            "success": 0.0,
        }
        if not self._status and self.max_cte is not None and abs(e) > self.max_cte:
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
        k = self.n_ref_points
        x, y, yaw, _ = self._rec.states[-1]
        c, s = math.cos(yaw), math.sin(yaw)
        ref = obs[6 : 6 + 2 * k].reshape(k, 2)
        ref_world = np.column_stack(
            [x + c * ref[:, 0] - s * ref[:, 1], y + s * ref[:, 0] + c * ref[:, 1]]
        )
        vehicle = scen.vehicle
        kappa = math.tan(self._ego.steer) / vehicle.wheelbase
        mode = f"{self.controller_name} + residual" if self.residual else "agent"
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
        if self.residual:
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
        ego = self._ego
        x, y, yaw = ego.rear
        p = self._projector
        proj = p.project(x, y)
        self._proj_s = proj.s
        k = self.n_ref_points
        out = np.zeros(6 + 3 * k + 5 * self.n_vehicles)
        out[0] = ego.speed
        out[1] = ego.steer
        out[2] = proj.cte
        out[3] = float(wrap_angle(yaw - proj.yaw))
        out[4] = self._profile.at(proj.s)[0]
        out[5] = p.length - proj.s
        c, s = math.cos(yaw), math.sin(yaw)
        base = max(proj.s, 0.0)
        for i in range(k):
            px, py, _, kappa = p.point_at(min(base + (i + 1) * self.ref_spacing, p.length))
            dx, dy = px - x, py - y
            out[6 + 2 * i] = c * dx + s * dy
            out[7 + 2 * i] = -s * dx + c * dy
            out[6 + 2 * k + i] = kappa
        if self.n_vehicles:
            self._observe_vehicles(out[6 + 3 * k :], x, y, c, s)
        return np.clip(out, self._low64, self._high64)

    def _observe_vehicles(
        self, out: np.ndarray, x: float, y: float, c: float, s: float
    ) -> None:
        """Fill ``out`` (zeros, ``5 M``) with the nearest other vehicles, ego frame."""
        others = self._rec.others
        if not others:
            return
        ego = self._ego
        pos = np.array([v.position for v in others], dtype=float).reshape(-1, 2)
        dist = np.hypot(pos[:, 0] - x, pos[:, 1] - y)
        order = [i for i in np.argsort(dist, kind="stable") if dist[i] <= self.vehicle_range]
        evx, evy = ego.speed * math.cos(ego.heading), ego.speed * math.sin(ego.heading)
        for j, i in enumerate(order[: self.n_vehicles]):
            v = others[i]
            dx, dy = pos[i, 0] - x, pos[i, 1] - y
            dvx = v.speed * math.cos(v.heading) - evx
            dvy = v.speed * math.sin(v.heading) - evy
            out[5 * j : 5 * j + 5] = (
                1.0, c * dx + s * dy, -s * dx + c * dy, c * dvx + s * dvy, -s * dvx + c * dvy
            )

    def _residual_command(
        self, c_accel: float, c_steer: float, d_accel: float, d_steer: float
    ) -> tuple[float, float]:
        """Residual mode: the controller's command plus the residual, as applied."""
        ctrl = self._ctrl
        if ctrl.arrived or ctrl.s >= ctrl.projector.length:
            # Holding at the goal or braking past the end: the controller alone,
            # so that a biased residual cannot keep the car creeping forever.
            self._controller_accel = c_accel
            return c_accel, c_steer
        # The residual fades out over the last RESIDUAL_FADE_M of the path, so that the
        # hand-over to the controller's hold at the goal does not jump the command.
        fade = min(1.0, (ctrl.projector.length - ctrl.s) / RESIDUAL_FADE_M)
        lim = self._steer_limit
        accel = self._residual_accel(c_accel, fade * d_accel, self._dt)
        return accel, min(max(c_steer + fade * d_steer, -lim), lim)

    def _residual_accel(self, c_accel: float, d_accel: float, dt: float) -> float:
        """The controller's acceleration plus the residual, within the speed loop's limits.

        Besides the acceleration range, the sum may rise (fall) from the last applied
        command by at most ``jerk_max`` (``jerk_brake_max``) per second, or by as much
        as the controller's own command changed since its last one when that is more
        (its hold at the goal, a following cap): the residual cannot add a jerk the
        speed loop would not, and a zero residual is the controller's command exactly.
        """
        cfg = self._speed
        prev = self._applied_accel
        change = c_accel - self._controller_accel
        self._controller_accel = c_accel
        hi = min(self._a_max, prev + max(change, cfg.jerk_max * dt))
        lo = self._a_min
        if cfg.jerk_brake_max is not None:
            lo = max(lo, prev + min(change, -cfg.jerk_brake_max * dt))
        return min(max(c_accel + d_accel, lo), hi)

    def _obs32(self) -> np.ndarray:
        return self._obs64.astype(np.float32)  # a fresh array every call

    def _finish(self) -> Episode:
        """The finished episode as the runner would return it."""
        log = self._rec.log(self._status in ("arrived", "completed"), self._wall)
        t_end = float(log.t[-1])
        if self._status == "crashed":
            message = f"highway-env reported a crash at t = {t_end:.2f} s"
        elif self._status == "off_path":
            message = f"left the path by more than {self.max_cte:g} m at t = {t_end:.2f} s"
        elif self._status == "arrived":
            where = "the end of the path" if self.residual else "the goal"
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
            controller_options=dict(self.controller_options),
            budget=self.budget,
            max_time_s=self._max_time,
            replan=self._replan,
        )
        label = f"{self.controller_name}+residual" if self.residual else "agent"
        if self._driver is not None:
            traffic = self._driver.finish(t_end if self._status == "completed" else None)
            return Episode(
                self._scenario, TRAFFIC_PLANNER, label, int(self.episode_seed or 0), None,
                traffic.executed, log, self._status, message, config, traffic,
            )
        return Episode(
            self._scenario, self.planner_name, label, int(self.episode_seed or 0), self._plan,
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
