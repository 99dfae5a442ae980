"""The forward-reachability sweep behind ``experiments/forward_reach.py``: :func:`sweep`.

Kept apart from the script so that tests can load it without the script's sibling
imports (``coverage`` is also a well-known package's name).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rrtdrive.collision import CollisionChecker

#: Sub-steps per step at which poses are integrated and body-tested.
SUBSTEPS = 4
#: Steering bins per ``delta_max`` when drives are merged.
STEER_BINS = 20


@dataclass(frozen=True)
class Reach:
    """One sweep's outcome.

    Parameters
    ----------
    sharpness, cell : float
        The steering-rate bound (rad/m) and the merge cell (m) of the sweep.
    driven_m : float
        Distance of the furthest drive that stayed clear.
    survived : bool
        A drive reached the sweep's distance (``poses`` is one).
    peak_states : int
        Most drives alive at one step, after merging (before any cap).
    capped : bool
        Some layer was cut down to ``max_states`` drives.
    poses : numpy.ndarray
        ``(n, 4)`` rows ``[x, y, yaw, kappa]`` of one furthest drive, every sub-step.
    """

    sharpness: float
    cell: float
    driven_m: float
    survived: bool
    peak_states: int
    capped: bool
    poses: np.ndarray


def sweep(
    checker: CollisionChecker,
    start: tuple[float, float, float],
    *,
    wheelbase: float,
    kappa_max: float,
    sharpness: float,
    clearance: float = 0.0,
    step: float = 0.2,
    cell: float = 0.05,
    heading_bin: float = math.radians(0.5),
    distance: float = 30.0,
    max_states: int = 300_000,
    turned_wheels: bool = False,
) -> Reach:
    """Sweep every forward drive from ``start`` at steering rate ``<= sharpness``.

    Parameters
    ----------
    checker : CollisionChecker
        The map's checker; poses are tested with ``poses_free(..., clearance)``.
    start : tuple of float
        ``(x, y, yaw)``; the drive starts with the wheels straight, or with
        ``turned_wheels`` at any of the ``2 STEER_BINS + 1`` steering angles from lock to
        lock (a car at rest turns its wheels before it sets off, as the controllers do).
    wheelbase, kappa_max : float
        The car: ``kappa = tan(delta) / wheelbase``, ``|kappa| <= kappa_max``.
    sharpness : float
        Largest change of the steering angle per metre, rad/m.
    clearance, step, cell, heading_bin, distance, max_states
        As in the module docstring.
    turned_wheels : bool
        See ``start``.

    Returns
    -------
    Reach
    """
    delta_max = math.atan(wheelbase * kappa_max)
    turn = sharpness * step
    if turned_wheels:
        de = np.linspace(-delta_max, delta_max, 2 * STEER_BINS + 1)
    else:
        de = np.zeros(1)
    x, y, th = (np.full(len(de), v, dtype=float) for v in start)
    kappa0 = np.tan(de) / wheelbase  # each root's curvature, set at rest
    layers: list[tuple[np.ndarray, ...]] = []
    peak, capped = 1, False
    n_steps = int(math.ceil(distance / step))
    h = step / SUBSTEPS
    for _ in range(n_steps):
        n = len(x)
        x, y, th, d0 = (np.repeat(a, 3) for a in (x, y, th, de))
        d1 = np.clip(d0 + np.tile([-turn, 0.0, turn], n), -delta_max, delta_max)
        parent = np.repeat(np.arange(n), 3)
        free = np.ones(len(x), dtype=bool)
        subs = []
        for j in range(SUBSTEPS):
            frac = (j + 0.5) / SUBSTEPS  # steering mid-sub-step: the ramp is linear in s
            kappa = np.tan(d0 + (d1 - d0) * frac) / wheelbase
            mid = th + 0.5 * h * kappa
            x, y, th = x + h * np.cos(mid), y + h * np.sin(mid), th + h * kappa
            kappa_end = np.tan(d0 + (d1 - d0) * (j + 1) / SUBSTEPS) / wheelbase
            subs.append(np.stack([x, y, th, kappa_end], 1))
            free &= checker.poses_free(subs[-1][:, :3], clearance=clearance)
        keep = np.flatnonzero(free)
        key = np.stack([
            np.floor(x[keep] / cell), np.floor(y[keep] / cell),
            np.floor(np.mod(th[keep], 2 * np.pi) / heading_bin),
            np.round(d1[keep] / delta_max * STEER_BINS),
        ], 1).astype(np.int64)  # fmt: skip
        _, first = np.unique(key, axis=0, return_index=True)
        keep = keep[np.sort(first)]
        peak = max(peak, len(keep))
        if len(keep) > max_states:
            capped = True
            keep = keep[np.linspace(0, len(keep) - 1, max_states).astype(int)]
        if len(keep) == 0:
            break
        sub_rows = np.stack(subs, 1)[keep]  # (k, SUBSTEPS, 4)
        layers.append((parent[keep], sub_rows))
        x, y, th, de = x[keep], y[keep], th[keep], d1[keep]
    return Reach(
        sharpness=sharpness, cell=cell, driven_m=len(layers) * step,
        survived=len(layers) == n_steps, peak_states=peak, capped=capped,
        poses=_trace(start, layers, kappa0),
    )  # fmt: skip


def _trace(
    start: tuple[float, float, float], layers: list[tuple[np.ndarray, ...]], kappa0: np.ndarray
) -> np.ndarray:
    """The rows of drive 0 of the last layer, back to the start (``kappa0``: each root's)."""
    rows, i = [], 0
    for parent, sub_rows in reversed(layers):
        rows.append(sub_rows[i])
        i = int(parent[i])
    rows.append(np.array([[*start, float(kappa0[i])]]))
    return np.concatenate(rows[::-1])


if __name__ == "__main__":
    import sys

    # Run as a script it did nothing and exited 0: say where the script is.
    sys.exit("reach_sweep.py is the library of experiments/forward_reach.py: run that script "
             "(python experiments/forward_reach.py --help)")
