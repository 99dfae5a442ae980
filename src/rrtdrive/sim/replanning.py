"""Receding-horizon re-planning in traffic: its settings, its records and the lane reference.

:class:`ReplanConfig` holds the settings of the traffic re-planner
(:class:`rrtdrive.sim.traffic_driver.TrafficDriver`, which documents how it
works); :class:`ReplanRecord` is one re-planning cycle and :class:`TrafficLog`
what the re-planner did during an episode (:attr:`rrtdrive.sim.episode.Episode.traffic`).
The ego's car-following law is :class:`rrtdrive.sim.follower.IDMConfig`.
"""

from __future__ import annotations

import bisect
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rrtdrive.frozen import config_of
from rrtdrive.planning.spacetime import SafetyConfig, SpaceTimeRRTConnect
from rrtdrive.sim.follower import IDMConfig
from rrtdrive.sim.prediction import PREDICTORS
from rrtdrive.types import InputError, Path, require_finite, require_int, require_positive
from rrtdrive.values import did_you_mean

__all__ = ["ReplanConfig", "ReplanRecord", "TrafficLog", "lane_path", "merge_path", "SPACING"]

#: Sample spacing of lane paths and stitched references (metres).
SPACING = 0.25


@dataclass(frozen=True)
class ReplanConfig:
    """Settings of receding-horizon re-planning in traffic.

    Parameters
    ----------
    rate_hz : float
        Re-planning rate, 2-5 Hz.
    budget_s : float, optional
        Wall-time budget of one re-planning cycle (prediction, planning, checks);
        default one period, ``1 / rate_hz``. The tree growth stops at the budget;
        the stitch point lies where the ego will be when it has elapsed.
    max_iterations : int
        Tree-growth iterations per plan (the deterministic budget; the wall-time
        budget only binds on a slow machine).
    wall_limit : bool
        Hold each cycle to its wall-time budget: the tree growth stops at its share
        and every check fails at 90 % of the budget (the plan is then dropped, as
        one that came too late). Off, an episode depends on its seed only, however
        slow the machine (tests); on, no cycle overruns (experiments).
    postprocess_reserve : float
        Share of the cycle budget kept for the post-processing when ``wall_limit``.
    predictor : str
        ``"constant-velocity"`` or ``"lane-following"`` (:mod:`rrtdrive.sim.prediction`).
    speed_bound : bool
        Predict braked IDM cars at their target speed.
    horizon_s : float
        Prediction horizon; a plan must reach its check end within it.
    prediction_step : float
        Time step of the prediction grid.
    safety : SafetyConfig
        Space and time buffers of the space-time check.
    cut_in_gap_m : float
        At the cut-in point the ego's rear bumper is at least this far ahead of the
        lead car's predicted front bumper ...
    cut_in_headway_s : float
        ... plus this many seconds at the lead car's speed.
    goal_slack_m : float
        The plan's goal lies this far beyond the nearest admissible cut-in point
        (room for the lane change back).
    turning_radius_m : float
        Smallest turning radius of planned paths (a comfort bound; at least the
        car's own 6 m): with the speed profile's lateral-acceleration cap it sets
        the speed through the lane changes (30 m and 2 m/s^2: 7.7 m/s).
    complete_gap_m : float
        The overtake is complete when the ego is back in its lane, aligned with it
        (within 10 degrees) and its rear bumper this far ahead of the lead's front.
    check_beyond_m : float
        A plan is checked this far past its cut-in point.
    max_plan_length_m : float
        Farthest cut-in point considered ahead of the stitch point.
    improve_s : float
        A new plan replaces a safe current one only if it reaches its cut-in point
        this much sooner.
    lane_extension_m : float
        Length of lane appended after a plan (and of the follow reference).
    start_merge_s : float
        The first reference joins the lane from the ego's start pose and steering
        (:func:`merge_path`) over the distance driven in this many seconds at the
        start speed (at least ``start_merge_min_m``), instead of starting on the
        lane centre line beside a jittered car: with the line the controllers
        corrected a 0.15 m, 1.5 degree start offset within 2-3 m, swinging the
        rate-limited wheels from -0.4 to +0.4 rad/s, which nuPlan's body-centre
        acceleration reads as a longitudinal jerk over its 4.13 m/s^3 bound
        (docs/traffic.md). ``0``: the lane centre line from the start.
    start_merge_min_m : float
        Shortest start merge (metres).
    check_every : int
        The current plan's safety check runs every this many control steps.
    pull_out_speed : float
        Behind a lead slower than this (m/s), a cycle whose planner finds no overtake
        tries the plain manoeuvre (:mod:`rrtdrive.sim.pull_out`): quintic lane changes
        out and back of ``pull_out_length_m`` each, checked like a plan. ``0``: never.
    pull_out_length_m : float
        Length of each of its lane changes (18 m across a 4 m lane: curvature up to
        0.07 1/m, steered at 0.4 rad/s up to about 5 m/s).
    idm : IDMConfig
        Car following while in ``follow`` mode.
    planner_options : mapping
        Options of :class:`~rrtdrive.planning.spacetime.SpaceTimeRRTConnect`.
    """

    rate_hz: float = 4.0
    budget_s: float | None = None
    max_iterations: int = 1000
    wall_limit: bool = True
    postprocess_reserve: float = 0.4
    predictor: str = "constant-velocity"
    speed_bound: bool = True
    horizon_s: float = 12.0
    prediction_step: float = 0.1
    safety: SafetyConfig = field(default_factory=SafetyConfig)
    cut_in_gap_m: float = 4.0
    cut_in_headway_s: float = 1.0
    goal_slack_m: float = 8.0
    turning_radius_m: float = 30.0
    complete_gap_m: float = 2.0
    check_beyond_m: float = 10.0
    max_plan_length_m: float = 110.0
    improve_s: float = 0.5
    lane_extension_m: float = 200.0
    start_merge_s: float = 4.0
    start_merge_min_m: float = 10.0
    check_every: int = 1
    pull_out_speed: float = 3.0
    pull_out_length_m: float = 18.0
    idm: IDMConfig = field(default_factory=IDMConfig)
    planner_options: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        require_finite("replan.rate_hz", self.rate_hz)
        if not 2.0 <= self.rate_hz <= 5.0:
            raise InputError(f"replan.rate_hz: must lie in [2, 5] Hz, got {self.rate_hz!r}")
        if self.budget_s is not None:
            require_positive("replan.budget_s", self.budget_s)
        require_int("replan.max_iterations", self.max_iterations)
        if not isinstance(self.wall_limit, bool):
            raise InputError(f"replan.wall_limit: expected true or false, got {self.wall_limit!r}")
        require_finite("replan.postprocess_reserve", self.postprocess_reserve)
        if not 0.0 <= self.postprocess_reserve < 1.0:
            raise InputError(
                f"replan.postprocess_reserve: must lie in [0, 1), got {self.postprocess_reserve!r}"
            )
        if self.predictor not in PREDICTORS:
            raise InputError(
                f"replan.predictor: unknown predictor {self.predictor!r}"
                f"{did_you_mean(self.predictor, PREDICTORS)}; "
                f"choose from {', '.join(PREDICTORS)}"
            )
        for name in (
            "horizon_s", "prediction_step", "complete_gap_m", "max_plan_length_m",
            "lane_extension_m", "turning_radius_m", "start_merge_min_m", "pull_out_length_m",
        ):
            require_positive(f"replan.{name}", getattr(self, name))
        for name in (
            "cut_in_gap_m", "cut_in_headway_s", "check_beyond_m", "improve_s", "goal_slack_m",
            "start_merge_s", "pull_out_speed",
        ):
            value = getattr(self, name)
            require_finite(f"replan.{name}", value)
            if value < 0:
                raise InputError(f"replan.{name}: must be >= 0, got {value!r}")
        if self.horizon_s < 2.0:
            raise InputError(f"replan.horizon_s: must be >= 2 s, got {self.horizon_s!r}")
        require_int("replan.check_every", self.check_every)
        # A mapping of the fields too: a gym spec saved as JSON keeps them so.
        object.__setattr__(self, "safety", config_of(SafetyConfig, self.safety, "replan.safety"))
        object.__setattr__(self, "idm", config_of(IDMConfig, self.idm, "replan.idm"))
        # Unknown planner options raise here, not in the middle of an episode.
        SpaceTimeRRTConnect(**dict(self.planner_options))

    @property
    def period_s(self) -> float:
        """Time between periodic re-plans."""
        return 1.0 / self.rate_hz

    @property
    def cycle_budget_s(self) -> float:
        """Wall-time budget of one cycle."""
        return self.budget_s if self.budget_s is not None else self.period_s


@dataclass(frozen=True)
class ReplanRecord:
    """One re-planning cycle.

    Attributes
    ----------
    t : float
        Simulation time of the cycle.
    trigger : str
        ``"periodic"`` or ``"unsafe"`` (the current plan failed its check).
    mode : str
        Mode before the cycle (``"follow"`` or ``"overtake"``).
    outcome : str
        ``"overtake"`` (a new plan was accepted), ``"kept"`` (a safe plan was found
        but the current one kept), ``"no_goal"`` (no cut-in point within reach),
        ``"no_gap"`` (the oncoming lane is taken where the ego would have to be
        beside the lead car: no plan can exist, the planner did not run),
        ``"no_plan"`` (the planner found no safe path), ``"late"`` (the cycle's
        wall-time budget ran out before a plan was verified), ``"rejected"`` (its stitched
        reference failed the final check), ``"abandoned"`` (an unsafe plan was
        dropped for following), ``"unsafe_kept"`` (no alternative to an unsafe plan).
    wall_time_s : float
        Wall time of the whole cycle (prediction, goal, planning, checks).
    planning_time_s : float
        The planner's own wall time (0 when it did not run).
    iterations, nodes : int
        Tree-growth iterations and nodes.
    goal_x : float or None
        Cut-in point (rear axle x) aimed at.
    message : str
        The planner's message.
    deadline_hit : bool
        The planner ran into the cycle's deadline (outcome ``"late"``).
    """

    t: float
    trigger: str
    mode: str
    outcome: str
    wall_time_s: float
    planning_time_s: float
    iterations: int
    nodes: int
    goal_x: float | None
    message: str
    deadline_hit: bool = False


@dataclass(frozen=True, eq=False)
class TrafficLog:
    """What the re-planner did during an episode.

    Attributes
    ----------
    records : tuple of ReplanRecord
        Every re-planning cycle.
    references : tuple of (float, Path)
        Each reference the controller tracked and the time it took over.
    executed : Path
        The reference actually tracked: each reference up to where the next took
        over (continuous by the stitching).
    modes : tuple of (float, str)
        Mode changes (time, new mode).
    unsafe_steps : int
        Control steps at which the current plan failed its safety check.
    completion_time_s : float or None
        When the overtake was complete.
    config : ReplanConfig
        The settings.
    """

    records: tuple[ReplanRecord, ...]
    references: tuple[tuple[float, Path], ...]
    executed: Path
    modes: tuple[tuple[float, str], ...]
    unsafe_steps: int
    completion_time_s: float | None
    config: ReplanConfig

    def cycle_times(self) -> np.ndarray:
        """Wall time of every re-planning cycle, seconds."""
        return np.array([r.wall_time_s for r in self.records], dtype=float)

    def reference_at(self, t: float) -> Path:
        """The reference tracked at simulation time ``t``."""
        times = [tt for tt, _ in self.references]
        i = max(0, bisect.bisect_right(times, t + 1e-9) - 1)
        return self.references[i][1]


def lane_path(x0: float, x1: float, lane_y: float, spacing: float = SPACING) -> Path:
    """The centre line of a lane along +x from ``x0`` to ``x1`` (rear-axle samples).

    Examples
    --------
    >>> p = lane_path(0.0, 10.0, 44.0)
    >>> len(p), p.samples[-1].tolist()
    (41, [10.0, 44.0, 0.0, 0.0, 1.0])
    """
    n = max(2, int(math.ceil((x1 - x0) / spacing - 1e-9)) + 1)
    xs = np.linspace(x0, x1, n)
    samples = np.column_stack([xs, np.full(n, lane_y), np.zeros(n), np.zeros(n)])
    return Path(samples, np.zeros((0, 2)))


def merge_path(
    pose: tuple[float, float, float],
    kappa0: float,
    length: float,
    x1: float,
    lane_y: float,
    spacing: float = SPACING,
) -> Path:
    """A reference from a car beside a lane into its centre line, then along it to ``x1``.

    Over ``length`` metres of x the lateral offset follows the quintic ``y(x)`` that
    starts at the car (rear axle ``pose``: position, heading, and curvature
    ``kappa0``, the one its wheels steer now) and ends on the centre line with zero
    slope and curvature; the lane line follows. Position, heading and curvature are
    continuous along the whole path, so a car on it steers from its present angle at
    a rate set by the merge's length and its speed. The car heads along +x within
    +-90 degrees (a merge, not a turn).

    Examples
    --------
    >>> p = merge_path((0.0, 44.12, 0.026), 0.0, 16.0, 50.0, 44.0)
    >>> round(float(p.samples[0, 1]), 3), round(float(p.samples[0, 2]), 3), float(p.samples[-1, 1])
    (44.12, 0.026, 44.0)
    >>> bool(abs(p.samples[:, 3]).max() < 0.01)
    True
    """
    x0, y0, yaw0 = (float(v) for v in pose)
    require_positive("merge.length", length)
    if not -math.pi / 2 < yaw0 < math.pi / 2:
        raise InputError(f"merge.pose: heading must lie within +-90 degrees of +x, got {yaw0!r}")
    slope0 = math.tan(yaw0)
    curv0 = float(kappa0) * (1.0 + slope0 * slope0) ** 1.5  # y'' for curvature kappa0
    end = x0 + length
    n = max(2, int(math.ceil(length / spacing - 1e-9)) + 1)
    u = np.linspace(0.0, 1.0, n)
    # Quintic in u = (x - x0) / length with y, y', y'' given at both ends (0 at the end).
    a0, a1, a2 = y0 - lane_y, slope0 * length, 0.5 * curv0 * length * length
    a3 = -10.0 * a0 - 6.0 * a1 - 3.0 * a2
    a4 = 15.0 * a0 + 8.0 * a1 + 3.0 * a2
    a5 = -6.0 * a0 - 3.0 * a1 - a2
    y = lane_y + a0 + u * (a1 + u * (a2 + u * (a3 + u * (a4 + u * a5))))
    dy = (a1 + u * (2 * a2 + u * (3 * a3 + u * (4 * a4 + u * 5 * a5)))) / length
    ddy = (2 * a2 + u * (6 * a3 + u * (12 * a4 + u * 20 * a5))) / (length * length)
    kappa = ddy / (1.0 + dy * dy) ** 1.5
    merge = np.column_stack([x0 + u * length, y, np.arctan(dy), kappa])
    if x1 > end:
        lane = lane_path(end, x1, lane_y, spacing).samples[1:, :4]
        merge = np.concatenate([merge, lane])
    return Path(merge, np.zeros((0, 2)))
