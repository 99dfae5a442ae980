"""The observation of :class:`~rrtdrive.envs.drive_env.DriveEnv`: layout, bounds, values.

A flat ``float32`` vector of ``6 + 3 K + 5 M + 2`` entries in the ego frame (rear
axle, x forward along the nose, y left): the car's state against the path, K
reference points ahead with their curvatures, the M nearest other vehicles, and
the gear to drive with the distance to the next stop (:func:`observation_names`
lists them; ``docs/gym.md`` describes each). On a path with gear changes every
path entry is measured on the gear segment being driven: "ahead" is in its
direction of travel (behind the nose while reversing), the stop at its end is the
next cusp.
:class:`ObservationLayout` holds the sizes and the Box bounds and computes the
vector from the live scene.

====================  ==========================================================
index                 entry
====================  ==========================================================
0                     speed ``v`` (m/s)
1                     steering angle applied in the last step (rad, left > 0)
2                     cross-track error of the rear axle (m, left of the path's
                      direction of travel > 0)
3                     heading error, yaw minus path yaw, both where the nose
                      points (rad, in [-pi, pi])
4                     reference speed ``v_ref`` (m/s, signed: < 0 in reverse): the
                      speed profile here, capped by a stop line of the speed loop
                      and by the car-following speed behind a slower car
                      (:mod:`rrtdrive.envs.reference_speed`)
5                     distance to the goal along the path (m, < 0 once past it)
6 .. 5 + 2K           next K reference points ``x_1, y_1, ..., x_K, y_K`` (m),
                      every ``ref_spacing`` metres of arc ahead of the rear
                      axle's projection (held at the path's end)
6 + 2K .. 5 + 3K      path curvature at those points (1/m, ``tan(delta) / L`` of
                      the steering the path asks for, in either gear)
6 + 3K .. 5 + 3K + 5M the M nearest other vehicles within ``vehicle_range``
                      (by distance from the rear axle to their body centre,
                      nearest first), 5 entries each: present (1, or 0 for an
                      empty slot, all zeros), body centre ``dx, dy`` (m) and
                      velocity ``dvx, dvy`` relative to the ego's (m/s)
6 + 3K + 5M           gear of the segment being driven (+1 forward, -1 reverse)
7 + 3K + 5M           distance along the path to the end of that segment (m): the
                      next cusp, on the last segment the goal (< 0 past it)
====================  ==========================================================

Distances are clipped to +-1000 m and curvatures to +-10 1/m (the Box bounds);
:func:`observation_names` lists the entries' names.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rrtdrive.controllers import PathProjector
from rrtdrive.geometry import wrap_angle
from rrtdrive.sim.ego import EgoVehicle
from rrtdrive.types import InputError, require_int

__all__ = [
    "KAPPA_CLIP",
    "OBS_CLIP",
    "VEHICLE_FEATURES",
    "GEAR_FEATURES",
    "ObservationLayout",
    "observation_names",
]

#: Distances in the observation are clipped to +-OBS_CLIP metres (the bounds of the Box).
OBS_CLIP = 1000.0
#: Curvatures in the observation are clipped to +-KAPPA_CLIP 1/m.
KAPPA_CLIP = 10.0

#: Per observed vehicle: present (1/0), then its body centre and velocity relative to
#: the ego's rear axle, in the ego frame.
VEHICLE_FEATURES = ("present", "dx", "dy", "dvx", "dvy")

#: The last two entries: the gear of the segment being driven and the distance to its end.
GEAR_FEATURES = ("gear", "dist_to_cusp")


def observation_names(n_ref_points: int, n_vehicles: int = 0) -> list[str]:
    """Names of the observation entries, in order.

    Examples
    --------
    >>> observation_names(2)
    ['speed', 'steer', 'cte', 'heading_err', 'v_ref', 'dist_to_goal', 'ref_x_1', 'ref_y_1', \
'ref_x_2', 'ref_y_2', 'ref_kappa_1', 'ref_kappa_2', 'gear', 'dist_to_cusp']
    >>> observation_names(1, n_vehicles=1)[-7:-2]
    ['veh_present_1', 'veh_dx_1', 'veh_dy_1', 'veh_dvx_1', 'veh_dvy_1']
    """
    names = ["speed", "steer", "cte", "heading_err", "v_ref", "dist_to_goal"]
    for i in range(1, n_ref_points + 1):
        names += [f"ref_x_{i}", f"ref_y_{i}"]
    names += [f"ref_kappa_{i}" for i in range(1, n_ref_points + 1)]
    for j in range(1, n_vehicles + 1):
        names += [f"veh_{f}_{j}" for f in VEHICLE_FEATURES]
    return names + list(GEAR_FEATURES)


@dataclass(frozen=True)
class ObservationLayout:
    """Sizes and bounds of the observation, and the observe function.

    Parameters
    ----------
    n_ref_points : int
        K, reference points ahead.
    ref_spacing : float
        Arc length between reference points (m).
    n_vehicles : int
        M, observed other vehicles.
    vehicle_range : float
        Vehicles farther from the rear axle (m) are not observed.
    max_steer : float
        The car's steering limit (rad): the bounds of the steering entry.

    Attributes
    ----------
    low, high : numpy.ndarray
        The Box bounds (``float32``).

    Examples
    --------
    >>> lay = ObservationLayout(2, 1.5, 1, 50.0, 0.5)
    >>> lay.size, lay.low.dtype, float(lay.high[1])
    (19, dtype('float32'), 0.5)
    """

    n_ref_points: int
    ref_spacing: float
    n_vehicles: int
    vehicle_range: float
    max_steer: float
    low: np.ndarray = field(init=False, repr=False, compare=False)
    high: np.ndarray = field(init=False, repr=False, compare=False)
    _low64: np.ndarray = field(init=False, repr=False, compare=False)
    _high64: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        require_int("n_ref_points", self.n_ref_points, 1, 200)
        require_int("n_vehicles", self.n_vehicles, 0, 50)
        for name in ("ref_spacing", "vehicle_range", "max_steer"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                raise InputError(f"{name}: must be a finite number > 0, got {v!r}")
        k = self.n_ref_points
        big = OBS_CLIP
        max_steer = self.max_steer
        low = np.concatenate(
            [
                [EgoVehicle.MIN_SPEED, -max_steer, -big, -math.pi, EgoVehicle.MIN_SPEED, -big],
                np.full(2 * k, -big),
                np.full(k, -KAPPA_CLIP),
                np.tile([0.0, -big, -big, -big, -big], self.n_vehicles),
                [-1.0, -big],
            ]
        ).astype(np.float32)
        high = np.concatenate(
            [
                [EgoVehicle.MAX_SPEED, max_steer, big, math.pi, big, big],
                np.full(2 * k, big),
                np.full(k, KAPPA_CLIP),
                np.tile([1.0, big, big, big, big], self.n_vehicles),
                [1.0, big],
            ]
        ).astype(np.float32)
        object.__setattr__(self, "low", low)
        object.__setattr__(self, "high", high)
        # Clip in float64 to the float32 bounds, so the cast lands inside the Box.
        object.__setattr__(self, "_low64", low.astype(np.float64))
        object.__setattr__(self, "_high64", high.astype(np.float64))

    @property
    def size(self) -> int:
        """Number of entries, ``6 + 3 K + 5 M + 2``."""
        return 6 + 3 * self.n_ref_points + 5 * self.n_vehicles + len(GEAR_FEATURES)

    def names(self) -> list[str]:
        """Names of the entries (:func:`observation_names`)."""
        return observation_names(self.n_ref_points, self.n_vehicles)

    def observe(
        self,
        ego: Any,
        projector: PathProjector,
        v_ref_at: Callable[[float], float],
        others: Sequence[Any],
        gear: int = 1,
        to_goal: float = 0.0,
    ) -> tuple[np.ndarray, float]:
        """The observation in float64 (clipped to the Box bounds), and the projection's s.

        Parameters
        ----------
        ego : EgoVehicle
            The ego car (``rear``, ``speed``, ``steer``, ``heading``).
        projector : PathProjector
            The gear segment being driven as a forward problem (the segment itself, or
            in reverse its mirror, :func:`rrtdrive.controllers.mirror_path`); projecting
            moves its local search on.
        v_ref_at : callable
            Reference speed (unsigned) at an arc length of the segment.
        others : sequence
            The other highway-env vehicles (``position``, ``speed``, ``heading``).
        gear : int
            Gear of the segment: +1, or -1 when ``projector`` is a reverse segment's mirror.
        to_goal : float
            Length of the path after the segment (m): the distance to the goal is the
            distance to the segment's end plus this.

        Returns
        -------
        observation : numpy.ndarray
        s : float
            Arc length of the rear axle's projection on the segment (not clipped).
        """
        x, y, yaw = ego.rear
        p = projector
        proj = p.project(x, y)
        k = self.n_ref_points
        out = np.zeros(self.size)
        reverse = gear < 0
        out[0] = ego.speed
        out[1] = ego.steer
        out[2] = proj.cte
        # A mirror's yaw is the nose's plus pi: compare like with like.
        out[3] = float(wrap_angle((yaw + math.pi if reverse else yaw) - proj.yaw))
        out[4] = -v_ref_at(proj.s) if reverse else v_ref_at(proj.s)
        out[5] = p.length - proj.s + to_goal if to_goal else p.length - proj.s
        c, s = math.cos(yaw), math.sin(yaw)
        base = max(proj.s, 0.0)
        for i in range(k):
            px, py, _, kappa = p.point_at(min(base + (i + 1) * self.ref_spacing, p.length))
            dx, dy = px - x, py - y
            out[6 + 2 * i] = c * dx + s * dy
            out[7 + 2 * i] = -s * dx + c * dy
            out[6 + 2 * k + i] = -kappa if reverse else kappa
        if self.n_vehicles:
            self._observe_vehicles(
                out[6 + 3 * k : 6 + 3 * k + 5 * self.n_vehicles], ego, others, x, y, c, s
            )
        out[-2] = gear
        out[-1] = p.length - proj.s
        return np.clip(out, self._low64, self._high64), proj.s

    def _observe_vehicles(
        self,
        out: np.ndarray,
        ego: Any,
        others: Sequence[Any],
        x: float,
        y: float,
        c: float,
        s: float,
    ) -> None:
        """Fill ``out`` (zeros, ``5 M``) with the nearest other vehicles, ego frame."""
        if not others:
            return
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
