"""The reward of :class:`~rrtdrive.envs.drive_env.DriveEnv`: weights and per-step terms.

A step's reward is the sum of named terms (``info["reward_terms"]``); the terms
that depend on the car's state after the step are computed by :func:`state_terms`,
the episode-end terms (``off_path``, ``success``) are set by the environment when
it decides the episode's status.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, fields

from rrtdrive.types import InputError

__all__ = ["TERMS", "RewardWeights", "state_terms"]

#: The reward terms, in the order they are summed (``info["reward_terms"]`` keeps it).
TERMS = ("progress", "cte", "heading", "speed", "collision", "off_path", "success")


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
        Per (m/s)^2 s of squared error against ``v_ref``, the observed reference
        speed (the profile, capped by a stop line and by car following).
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


def state_terms(
    w: RewardWeights,
    *,
    progress_m: float,
    cte: float,
    heading_err: float,
    speed: float,
    v_ref: float,
    span_s: float,
    crashed: bool,
) -> dict[str, float]:
    """The terms of one step, keyed as :data:`TERMS` (``off_path``, ``success`` at 0).

    Parameters
    ----------
    w : RewardWeights
        The weights.
    progress_m : float
        Arc length gained along the path in the step (m).
    cte, heading_err, speed, v_ref : float
        Cross-track error (m), heading error (rad), speed and reference speed
        (m/s) after the step.
    span_s : float
        Duration of the step (s).
    crashed : bool
        highway-env reported a crash in the step.

    Returns
    -------
    dict of str to float

    Examples
    --------
    >>> t = state_terms(RewardWeights(), progress_m=0.5, cte=0.1, heading_err=0.0,
    ...                 speed=2.0, v_ref=2.0, span_s=0.05, crashed=False)
    >>> round(t["progress"], 3), round(t["cte"], 4), t["speed"]
    (0.5, -0.005, -0.0)
    """
    return {
        "progress": w.progress * progress_m,
        "cte": -w.cte * cte * cte * span_s,
        "heading": -w.heading * heading_err * heading_err * span_s,
        "speed": -w.speed * (speed - v_ref) ** 2 * span_s,
        "collision": -w.collision if crashed else 0.0,
        "off_path": 0.0,
        "success": 0.0,
    }
