"""A static figure of one closed-loop episode: ``rrtdrive simulate --plot``.

Left, the map with the planned path (reverse dashed, cusps marked), the driven
rear-axle trajectory and the other cars (their tracks, their bodies at the last
step); right, against time, the signed speed, the front-wheel angle and its rate
against the car's limits, and the cross-track error as the evaluators measure it
(against the gear segment being driven). The figure a report needs where the video
cannot go.
"""

from __future__ import annotations

import math
from typing import Any

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.patches import Polygon as PolygonPatch

from rrtdrive.obstacles import Obstacle
from rrtdrive.plotting import (  # sets the Agg backend, read by pyplot's first figure
    draw_gear_path,
    draw_map,
    draw_pose,
    map_figure_size,
    title_and_legend,
)
from rrtdrive.types import Pose

__all__ = ["plot_episode"]

#: Width of the time-series column, inches.
_SERIES_IN = 4.2
#: Room around the drive when the view is cut from a big map, metres.
_VIEW_MARGIN_M = 10.0
#: Other cars this near the ego at the last step are in the view too, metres.
_NEAR_CARS_M = 40.0


def _view(episode: Any) -> tuple[float, float, float, float]:
    """The part of the map to draw: the drive (path, trajectory, start) and a margin.

    The whole map unless the drive covers under half of it along a side (a 1.5 km road
    of which the overtake uses 200 m was a thin line across the figure; its goal, the
    road's far end, is not part of the drive). The other cars within
    :data:`_NEAR_CARS_M` of the ego at the last step are part of it (the lead car a
    following drive ended behind was cut off; an audit).
    """
    m = episode.scenario.map
    xmin, ymin, xmax, ymax = m.bounds
    states = episode.log.states
    points = [episode.path.xy, states[:, :2], np.array([m.start.as_tuple()[:2]])]
    others = episode.log.others
    if others.size and len(states):
        last = others[-1, :, :2]
        points.append(last[np.hypot(*(last - states[-1, :2]).T) <= _NEAR_CARS_M])
    pts = np.vstack([p for p in points if len(p)])
    lo, hi = pts.min(axis=0) - _VIEW_MARGIN_M, pts.max(axis=0) + _VIEW_MARGIN_M
    view = (max(xmin, lo[0]), max(ymin, lo[1]), min(xmax, hi[0]), min(ymax, hi[1]))
    if view[2] - view[0] < 0.5 * (xmax - xmin) or view[3] - view[1] < 0.5 * (ymax - ymin):
        return view
    return m.bounds


def _series(episode: Any) -> dict[str, np.ndarray]:
    """Time, signed speed, steering angle and rate (degrees), cross-track error of a drive."""
    from rrtdrive.evaluation.tracking import tracking_errors

    rows = episode.trajectory()
    if len(rows) == 0:
        return {}
    t, speed, steer = rows[:, 0], rows[:, 4], rows[:, 5]
    # The rate the actuator moved at over each step (steer holds from one step to the next).
    rate = np.diff(steer) / np.diff(t) if len(t) > 1 else np.zeros(0)
    out = {"t": t, "speed": speed, "steer": np.degrees(steer),
           "rate_t": t[1:], "rate": np.degrees(rate)}  # fmt: skip
    if len(episode.path) >= 2:
        out["cte"] = tracking_errors(episode.path, rows[:, 1:4], speeds=speed)[0]
    return out


def _draw_others(ax: Any, log: Any) -> None:
    """Every other car: its centre's track and its body at the drive's last step.

    The last step is the crash's when the drive ended in one, so the figure shows
    what the ego hit; a parked car that is also a map obstacle gets an outline on top.
    """
    others, sizes = log.others, log.other_sizes
    if others.size == 0:
        return
    track_label = "other cars' tracks"
    for k, (length, width) in enumerate(sizes):
        track = others[:, k, :2]
        if np.ptp(track, axis=0).max() > 0.1:  # it moved
            ax.plot(track[:, 0], track[:, 1], color="tab:cyan", lw=0.8, alpha=0.6,
                    label=track_label, zorder=4, gid=f"other-track-{k}")  # fmt: skip
            track_label = None
        x, y, heading = others[-1, k, :3]
        body = Obstacle((float(x), float(y)), (float(length), float(width)), float(heading))
        ax.add_patch(PolygonPatch(body.corners(), closed=True, fc="tab:cyan", alpha=0.5,
                                  ec="tab:cyan", lw=1.0, zorder=6, gid=f"other-car-{k}",
                                  label="other cars (last step)" if k == 0 else None))  # fmt: skip


def plot_episode(episode: Any, title: str | None = None) -> Any:
    """The map, the planned path, the driven trajectory and the drive's time series.

    Parameters
    ----------
    episode : Episode
        A finished episode (:func:`rrtdrive.sim.runner.run_episode`); one that drove
        nothing (a failed plan) shows the map and says so.
    title : str, optional
        Replaces the default title (scenario, seed, planner and controller, status).

    Returns
    -------
    matplotlib.figure.Figure
        A new figure; :func:`rrtdrive.plotting.save_figure` saves and closes it.
    """
    task = episode.scenario
    vehicle = task.vehicle
    view = _view(episode)
    width_in, height_in = map_figure_size(view)
    height_in = max(height_in, 5.5)
    fig = plt.figure(figsize=(width_in + _SERIES_IN, height_in), layout="constrained")
    grid = fig.add_gridspec(4, 2, width_ratios=(width_in, _SERIES_IN))
    ax = fig.add_subplot(grid[:, 0])
    draw_map(ax, task.map)
    if view != task.map.bounds:
        ax.set_xlim(view[0], view[2])
        ax.set_ylim(view[1], view[3])
    if len(episode.path):
        draw_gear_path(ax, episode.path, label="planned path")
    data = _series(episode)
    _draw_others(ax, episode.log)
    states = episode.log.states
    if len(states):
        # Thin: the planned path (reverse legs dashed cyan) shows either side of it.
        ax.plot(states[:, 0], states[:, 1], color="black", lw=0.6, label="driven (rear axle)",
                zorder=5)  # fmt: skip
        end = Pose(*states[-1, :3])
        crashed = episode.status.value == "crashed"
        draw_pose(ax, end, vehicle, "tab:red" if crashed else "tab:gray",
                  label="crash" if crashed else "final pose")  # fmt: skip
    axes = [fig.add_subplot(grid[k, 1]) for k in range(4)]
    for a in axes[1:]:
        a.sharex(axes[0])
    labels = ("speed [m/s]", "steering [deg]", "steering rate [deg/s]", "cross-track [m]")
    for a, label in zip(axes, labels, strict=True):
        a.set_ylabel(label, fontsize=8)
        a.tick_params(labelsize=7)
        a.grid(alpha=0.3)
    axes[-1].set_xlabel("time [s]", fontsize=8)
    if data:
        axes[0].plot(data["t"], data["speed"], color="tab:blue", lw=1.0)
        axes[1].plot(data["t"], data["steer"], color="tab:blue", lw=1.0)
        limit = math.degrees(vehicle.max_steer)
        for sign in (1, -1):
            axes[1].axhline(sign * limit, color="tab:red", ls="--", lw=0.8)
        axes[2].plot(data["rate_t"], data["rate"], color="tab:blue", lw=1.0)
        if vehicle.max_steer_rate is not None:
            rate = math.degrees(vehicle.max_steer_rate)
            for sign in (1, -1):
                axes[2].axhline(sign * rate, color="tab:red", ls="--", lw=0.8)
        if "cte" in data:
            axes[3].plot(data["t"], data["cte"], color="tab:blue", lw=1.0)
    else:
        axes[0].text(0.5, 0.5, "nothing driven", transform=axes[0].transAxes, ha="center")
    status = episode.status.value
    text = title or (f"{task.map.name}: seed {episode.seed}, {episode.planner} / "
                     f"{episode.controller}: {status}")  # fmt: skip
    if title is None and episode.message:
        text += f"\n{episode.message}"
    title_and_legend(fig, ax, text, height_in, parse_math=title is not None)
    return fig
