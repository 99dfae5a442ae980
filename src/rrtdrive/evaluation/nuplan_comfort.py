"""nuPlan's ``ego_is_comfortable``, computed from a driven trajectory as nuPlan computes it.

nuPlan (``nuplan/planning/metrics/utils/state_extractors.py`` and the six metrics that
``ego_is_comfortable`` combines) judges comfort from Savitzky-Golay filtered series of
the ego's history, sampled every 0.1 s:

========================  ============================================  ==================
figure                    series                                        bound
========================  ============================================  ==================
longitudinal accel        centre acceleration x, ``savgol(8, 2)``       [-4.05, 2.40] m/s^2
lateral accel             centre acceleration y, ``savgol(8, 2)``       abs <= 4.89 m/s^2
longitudinal jerk         d/dt of the filtered x accel, ``savgol(15, 2)``  abs <= 4.13 m/s^3
jerk magnitude            d/dt of the filtered accel magnitude, same    abs <= 8.37 m/s^3
yaw rate                  d/dt of the unwrapped heading, ``savgol(5, 2)``  abs <= 0.95 rad/s
yaw acceleration          d2/dt2 of the heading, ``savgol(5, 3)``       abs <= 1.93 rad/s^2
========================  ============================================  ==================

The ego state's acceleration is the rear-axle acceleration in the body frame,
``(dv/dt, v * yaw_rate)`` here (what a log's IMU reports; nuPlan's own simulated
kinematic bicycle sets the lateral part to zero, which would hide every lateral
figure), shifted to the body centre by nuPlan's ``get_acceleration_shifted``
(``a + d * (w^2 + w_dot)`` along the body axis, d the rear-axle-to-centre distance);
the magnitude is that of the rear-axle acceleration, as in ``DynamicCarState.acceleration``.
Our log is first taken every ``nuplan_step_s`` (0.1 s) so that the filter windows span
the same time as in nuPlan: every other sample at 20 Hz, and linearly interpolated on
an exact 0.1 s grid where the step does not divide 0.1 s (15 or 25 Hz: taking every
``round(0.1 / dt)``-th sample stepped 0.133 or 0.08 s, 19-27 % off in the jerks). A
series of fewer than :data:`MIN_SAMPLES` samples at 0.1 s (an episode under 0.3 s)
has no figures: ``None``, not zeros.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

__all__ = ["COMFORT_BOUNDS", "NuplanComfort", "nuplan_comfort"]

#: nuPlan's ``ego_is_comfortable`` thresholds.
COMFORT_BOUNDS = {
    "min_lon_accel": -4.05,
    "max_lon_accel": 2.40,
    "max_abs_lat_accel": 4.89,
    "max_abs_lon_jerk": 4.13,
    "max_abs_jerk": 8.37,
    "max_abs_yaw_rate": 0.95,
    "max_abs_yaw_accel": 1.93,
}
#: nuPlan's sampling interval of the ego history (s).
NUPLAN_STEP_S = 0.1
#: Fewest samples at that interval the figures need: the yaw acceleration's cubic fit.
MIN_SAMPLES = 4


@dataclass(frozen=True)
class NuplanComfort:
    """The six comfort figures (extremes of the filtered series) and nuPlan's verdict.

    Attributes
    ----------
    lon_accel_min, lon_accel_max : float
        Extremes of the longitudinal acceleration (m/s^2).
    lat_accel_abs_max : float
        Largest absolute lateral acceleration (m/s^2).
    lon_jerk_abs_max, jerk_abs_max : float
        Largest absolute longitudinal jerk and jerk of the acceleration magnitude (m/s^3).
    yaw_rate_abs_max : float
        Largest absolute yaw rate (rad/s).
    yaw_accel_abs_max : float
        Largest absolute yaw acceleration (rad/s^2).
    comfortable : bool
        Every figure within its bound (``COMFORT_BOUNDS``).
    """

    lon_accel_min: float
    lon_accel_max: float
    lat_accel_abs_max: float
    lon_jerk_abs_max: float
    jerk_abs_max: float
    yaw_rate_abs_max: float
    yaw_accel_abs_max: float
    comfortable: bool

    def violations(self) -> list[str]:
        """Names of the figures outside nuPlan's bounds, with value and bound."""
        b = COMFORT_BOUNDS
        checks = [
            ("longitudinal acceleration", self.lon_accel_min, b["min_lon_accel"], "<"),
            ("longitudinal acceleration", self.lon_accel_max, b["max_lon_accel"], ">"),
            ("lateral acceleration", self.lat_accel_abs_max, b["max_abs_lat_accel"], ">"),
            ("longitudinal jerk", self.lon_jerk_abs_max, b["max_abs_lon_jerk"], ">"),
            ("jerk", self.jerk_abs_max, b["max_abs_jerk"], ">"),
            ("yaw rate", self.yaw_rate_abs_max, b["max_abs_yaw_rate"], ">"),
            ("yaw acceleration", self.yaw_accel_abs_max, b["max_abs_yaw_accel"], ">"),
        ]
        out = []
        for name, value, bound, side in checks:
            if (side == "<" and value < bound) or (side == ">" and value > bound):
                out.append(f"{name} {value:.2f} {side} {bound:g}")
        return out

    def to_json(self) -> dict[str, float | bool]:
        """A JSON-ready dict."""
        items = asdict(self).items()
        return {k: (v if isinstance(v, bool) else round(float(v), 6)) for k, v in items}


def _window(n: int, wanted: int, order: int) -> int | None:
    """The window nuPlan uses, ``min(window_length, len(x))``; ``None`` if too short."""
    w = min(wanted, n)
    return w if w > order else None


def _filtered(
    y: np.ndarray, window: int, order: int, deriv: int = 0, dt: float = 1.0
) -> np.ndarray:
    w = _window(len(y), window, order)
    if w is None:
        return np.zeros_like(y) if deriv else y
    # Imported here: scipy.signal pulls in scipy.stats (0.7 s on every process start).
    from scipy.signal import savgol_filter

    return savgol_filter(y, window_length=w, polyorder=order, deriv=deriv, delta=dt)


def nuplan_comfort(
    t: np.ndarray,
    yaw: np.ndarray,
    speed: np.ndarray,
    rear_to_centre: float,
    nuplan_step_s: float = NUPLAN_STEP_S,
) -> NuplanComfort | None:
    """The comfort figures nuPlan computes, of a trajectory sampled at equal times.

    Parameters
    ----------
    t : numpy.ndarray
        Times (s), equally spaced, shape ``(N,)``.
    yaw : numpy.ndarray
        Headings (rad), ``(N,)``.
    speed : numpy.ndarray
        Signed rear-axle speed (m/s), ``(N,)``.
    rear_to_centre : float
        Distance from the rear axle to the body centre (m).
    nuplan_step_s : float
        nuPlan's history interval; the series is taken at it first (every
        ``nuplan_step_s / dt``-th sample, or interpolated where that is no integer).

    Returns
    -------
    NuplanComfort or None
        ``None`` for fewer than :data:`MIN_SAMPLES` samples at ``nuplan_step_s``.

    Examples
    --------
    >>> t = np.arange(0.0, 10.0, 0.05)
    >>> c = nuplan_comfort(t, 0.5 * t, np.full_like(t, 3.0), 1.255)  # a circle, R = 6 m
    >>> round(c.yaw_rate_abs_max, 3), round(c.lat_accel_abs_max, 3), c.comfortable
    (0.5, 1.5, True)
    """
    t = np.asarray(t, dtype=float)
    if len(t) < 2:
        return None
    dt_log = float(np.mean(np.diff(t)))
    stride = max(1, int(round(nuplan_step_s / dt_log)))
    if abs(stride * dt_log - nuplan_step_s) <= 1e-9 * nuplan_step_s:
        heading = np.unwrap(np.asarray(yaw, dtype=float)[::stride])
        v = np.asarray(speed, dtype=float)[::stride]
        t = t[::stride]
    else:
        grid = t[0] + nuplan_step_s * np.arange(int((t[-1] - t[0]) / nuplan_step_s + 1e-9) + 1)
        heading = np.interp(grid, t, np.unwrap(np.asarray(yaw, dtype=float)))
        v = np.interp(grid, t, np.asarray(speed, dtype=float))
        t = grid
    if len(t) < MIN_SAMPLES:
        return None
    dt = float(np.mean(np.diff(t)))
    # The ego state's own kinematics (unfiltered, as a log's states carry them).
    omega = np.gradient(heading, t)
    omega_dot = np.gradient(omega, t)
    a_rear_x = np.gradient(v, t)
    a_rear_y = v * omega
    a_centre_x = a_rear_x + rear_to_centre * (omega**2 + omega_dot)
    a_mag = np.hypot(a_rear_x, a_rear_y)
    # nuPlan's extractors.
    lon = _filtered(a_centre_x, 8, 2)
    lat = _filtered(a_rear_y, 8, 2)
    mag = _filtered(a_mag, 8, 2)
    lon_jerk = _filtered(lon, 15, 2, deriv=1, dt=dt)
    jerk = _filtered(mag, 15, 2, deriv=1, dt=dt)
    yaw_rate = _filtered(heading, 5, 2, deriv=1, dt=dt)
    yaw_accel = _filtered(heading, 5, 3, deriv=2, dt=dt)
    b = COMFORT_BOUNDS
    figures = (
        float(lon.min()),
        float(lon.max()),
        float(np.abs(lat).max()),
        float(np.abs(lon_jerk).max()),
        float(np.abs(jerk).max()),
        float(np.abs(yaw_rate).max()),
        float(np.abs(yaw_accel).max()),
    )
    ok = (
        figures[0] >= b["min_lon_accel"]
        and figures[1] <= b["max_lon_accel"]
        and figures[2] <= b["max_abs_lat_accel"]
        and figures[3] <= b["max_abs_lon_jerk"]
        and figures[4] <= b["max_abs_jerk"]
        and figures[5] <= b["max_abs_yaw_rate"]
        and figures[6] <= b["max_abs_yaw_accel"]
    )
    return NuplanComfort(*figures, comfortable=bool(ok))
