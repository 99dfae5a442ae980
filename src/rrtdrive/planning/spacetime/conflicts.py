"""The conservative test of ego poses against predicted vehicles in a time band."""

from __future__ import annotations

import numpy as np

from rrtdrive.planning.spacetime.prediction import Prediction, _poses_at
from rrtdrive.planning.spacetime.safety import SafetyConfig
from rrtdrive.types import VehicleParams
from rrtdrive.vehicle import cover_discs

__all__ = ["traffic_conflicts"]


def traffic_conflicts(
    poses: np.ndarray,
    t_lo: np.ndarray,
    t_hi: np.ndarray,
    prediction: Prediction,
    safety: SafetyConfig,
    vehicle: VehicleParams,
    spacing: float = 0.0,
    discs: tuple[np.ndarray, float] | None = None,
) -> np.ndarray:
    """True where the ego at a rear-axle pose may meet a predicted vehicle in its time band.

    The ego body is covered by three discs (grown by ``spacing / 2``); each other
    vehicle by the capsule around its centre line from its rear bumper at
    ``t_lo - margin(t_lo)`` to its front bumper at ``t_hi + margin(t_hi)``
    (radius half its width), over both hypotheses when the prediction has an
    ``alt``. A pose conflicts when a disc comes within ``buffer(t_hi)`` of a capsule.

    Parameters
    ----------
    poses : numpy.ndarray
        ``(N, 3)`` rear-axle poses.
    t_lo, t_hi : numpy.ndarray
        ``(N,)`` earliest and latest arrival times (seconds after the prediction).
    prediction : Prediction
        The other vehicles.
    safety : SafetyConfig
        Buffer and time margin.
    vehicle : VehicleParams
        The ego car.
    spacing : float
        Distance to the neighbouring tested poses (metres).
    discs : tuple, optional
        ``(offsets, radius)`` of the ego's three covering discs
        (:func:`rrtdrive.vehicle.cover_discs` of ``vehicle``), when the caller keeps
        them; computed here otherwise.

    Returns
    -------
    numpy.ndarray
        Boolean ``(N,)``.

    Examples
    --------
    >>> car = Prediction.constant_velocity(np.array([[20.0, 0.0, 0.0, 5.0]]), [(4.3, 1.8)], 5.0)
    >>> poses = np.array([[40.0, 0.0, 0.0], [40.0, 0.0, 0.0]])
    >>> traffic_conflicts(poses, np.array([0.0, 4.0]), np.array([0.0, 4.0]), car,
    ...                   SafetyConfig(), VehicleParams()).tolist()  # it reaches x = 40 at 4 s
    [False, True]
    """
    p = np.asarray(poses, dtype=float).reshape(-1, 3)
    n = len(p)
    pred = prediction
    if n == 0 or len(pred) == 0:
        return np.zeros(n, dtype=bool)
    offsets, radius = cover_discs(vehicle, 3) if discs is None else discs
    t_lo = np.asarray(t_lo, dtype=float).reshape(-1)
    t_hi = np.asarray(t_hi, dtype=float).reshape(-1)
    lo = t_lo - safety.margin(t_lo)
    hi = t_hi + safety.margin(t_hi)
    # Disc centres, (N, M) per coordinate.
    c, s = np.cos(p[:, 2]), np.sin(p[:, 2])
    dx = p[:, 0:1] + c[:, None] * offsets[None, :]
    dy = p[:, 1:2] + s[:, None] * offsets[None, :]
    sizes = pred.sizes
    track = pred.poses
    alt = pred.alt
    step = pred.step
    grow = radius + 0.5 * spacing + float(safety.buffer(float(t_hi.max())))
    # Every interpolated pose at once (one call per hypothesis; _poses_at is elementwise
    # in time): columns 0-1 the screen's span, then the band's start and end per pose.
    times = np.concatenate([[max(float(lo.min()), 0.0), float(hi.max())], lo, hi])
    at = _poses_at(track, step, times)  # (K, 2 + 2N, 3)
    at_alt = None if alt is None else _poses_at(alt, step, times)
    # Screen: each vehicle's box over the whole time span against the discs' box.
    span = at[:, :2] if at_alt is None else np.concatenate([at[:, :2], at_alt[:, :2]], axis=1)
    reach = grow + 0.5 * (sizes[:, 0] + sizes[:, 1])
    keep = (
        (span[:, :, 0].max(axis=1) + reach >= dx.min())
        & (span[:, :, 0].min(axis=1) - reach <= dx.max())
        & (span[:, :, 1].max(axis=1) + reach >= dy.min())
        & (span[:, :, 1].min(axis=1) - reach <= dy.max())
    )
    if not keep.any():
        return np.zeros(n, dtype=bool)
    if not keep.all():
        at, sizes = at[keep], sizes[keep]
        at_alt = None if at_alt is None else at_alt[keep]
    a_pose = at[:, 2 : 2 + n]  # (K, N, 3)
    b_pose = at[:, 2 + n :]
    ux, uy = np.cos(b_pose[..., 2]), np.sin(b_pose[..., 2])  # (K, N)
    half_len = (sizes[:, 0] / 2.0)[:, None]
    # Extent along the heading of every predicted centre in the band (both hypotheses).
    ox, oy = a_pose[..., 0], a_pose[..., 1]
    along = [np.zeros_like(ox), (b_pose[..., 0] - ox) * ux + (b_pose[..., 1] - oy) * uy]
    if at_alt is not None:
        for other in (at_alt[:, 2 : 2 + n], at_alt[:, 2 + n :]):
            along.append((other[..., 0] - ox) * ux + (other[..., 1] - oy) * uy)
    first = np.minimum.reduce(along) - half_len
    last = np.maximum.reduce(along) + half_len
    ax = ox + first * ux
    ay = oy + first * uy
    abx = (last - first) * ux
    aby = (last - first) * uy
    ab2 = np.maximum(abx * abx + aby * aby, 1e-12)[..., None]  # (K, N, 1)
    apx = dx[None, :, :] - ax[..., None]  # (K, N, M)
    apy = dy[None, :, :] - ay[..., None]
    frac = np.clip((apx * abx[..., None] + apy * aby[..., None]) / ab2, 0.0, 1.0)
    ex = apx - frac * abx[..., None]
    ey = apy - frac * aby[..., None]
    limit = (
        radius
        + 0.5 * spacing
        + (sizes[:, 1] / 2.0)[:, None, None]
        + safety.buffer(t_hi)[None, :, None]
    )
    return np.any(ex * ex + ey * ey < limit * limit, axis=(0, 2))
