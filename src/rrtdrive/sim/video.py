"""Headless MP4 of an episode: the scene, the planned path, the driven trace and a read-out.

The video only reads an :class:`~rrtdrive.sim.runner.Episode`: it rebuilds the
scene with ``render_mode="rgb_array"`` (no display needed; do not set
``SDL_VIDEODRIVER=dummy``, which makes highway-env draw nothing), puts every
vehicle at its logged pose frame by frame, draws with highway-env's own graphics
plus the path and trace, flips the image so that +y points up (highway-env draws
y downwards) and writes the frames through imageio-ffmpeg into a temporary file
that is renamed when complete.
"""

from __future__ import annotations

import math
import os
import tempfile
from pathlib import Path as FsPath
from typing import Any

import numpy as np

from rrtdrive.atomic import publish, temp_beside
from rrtdrive.sim.episode import Episode
from rrtdrive.sim.scenes import SimConfig, build_env
from rrtdrive.types import InputError, Pose, require_int

__all__ = ["render_frames", "write_video", "frame_is_blank"]

PATH_COLOR = (40, 90, 255)
TRACE_COLOR = (255, 60, 40)
GOAL_COLOR = (0, 160, 0)
TEXT_COLOR = (20, 20, 20)
PANEL_COLOR = (255, 255, 255)


class _Camera:
    """A fixed point for highway-env's viewer to centre on (it reads ``.position``)."""

    def __init__(self, x: float, y: float) -> None:
        self.position = np.array([x, y], dtype=float)


def frame_is_blank(frame: np.ndarray, min_std: float = 5.0) -> bool:
    """True when an RGB frame is (nearly) one flat colour."""
    return float(np.asarray(frame, dtype=float).std()) < min_std


def _camera_for(episode: Episode) -> tuple[tuple[int, int], float, _Camera]:
    # The task frames itself (a long road: a window that follows the ego, moved every frame).
    view = episode.scenario.camera()
    return view.size, view.scaling, _Camera(*view.centre)


def render_frames(
    episode: Episode,
    stride: int = 1,
    sim: SimConfig | None = None,
    reuse_background: bool = True,
) -> Any:
    """Yield RGB frames (``H x W x 3`` uint8) of the episode, one every ``stride`` steps.

    Parameters
    ----------
    episode : Episode
        A driven episode (at least one logged state).
    stride : int
        Steps between frames.
    sim : SimConfig, optional
        Frame size and scaling overrides.
    reuse_background : bool
        With a fixed camera (every scene but the long traffic road), draw the road's
        lanes once and copy them into every frame (the parking lot's 144 spot lanes
        are three quarters of a frame's drawing); ``False`` draws them every frame.
        The frames are the same pixels either way.

    Yields
    ------
    numpy.ndarray
        One frame.
    """
    if not os.environ.get("XDG_RUNTIME_DIR"):
        # SDL complains on stderr without it; a private empty folder silences it.
        os.environ["XDG_RUNTIME_DIR"] = tempfile.mkdtemp(prefix="rrtdrive-sdl-")
    import pygame
    from highway_env.road.graphics import RoadGraphics

    from rrtdrive.evaluation import tracking_errors

    log = episode.log
    if len(log.states) == 0:
        raise InputError("video: the episode has no trajectory (planning failed?)")
    require_int("stride", stride)
    size, scaling, camera = _camera_for(episode)
    sim = sim or SimConfig(simulation_frequency=int(round(1.0 / log.dt)))
    sim = SimConfig(
        simulation_frequency=sim.simulation_frequency,
        screen_width=sim.screen_width or size[0],
        screen_height=sim.screen_height or size[1],
        scaling=sim.scaling or scaling,
    )
    env = build_env(episode.scenario, sim, render=True)
    try:
        u = env.unwrapped
        u.config["centering_position"] = [0.5, 0.5]
        env.render()  # creates highway-env's offscreen viewer
        viewer = u.viewer
        viewer.observer_vehicle = camera
        surface = viewer.sim_surface
        road = u.road
        ego = u.vehicle
        others = [v for v in road.vehicles if v is not ego]
        vehicle = episode.scenario.vehicle
        path_xy = episode.path.xy
        traffic = episode.traffic
        follow = episode.scenario.is_traffic
        cte = (
            tracking_errors(episode.path, log.states[:, :3])[0]
            if len(episode.path) >= 2 else np.zeros(len(log.states))
        )
        font = pygame.font.Font(None, 22)
        goal = episode.scenario.goal
        indices = list(range(0, len(log.states), stride))
        if indices[-1] != len(log.states) - 1:
            indices.append(len(log.states) - 1)  # always show the final state
        background = None
        for k in indices:
            x, y, yaw, v = log.states[k]
            steer = float(log.controls[k - 1, 1]) if k > 0 else 0.0
            ego.set_pose(Pose(x, y, yaw), speed=v)
            ego.action = {"acceleration": 0.0, "steering": steer}
            ego.crashed = bool(log.crashed[k])
            if bool(log.crashed[k]):
                ego.color = (255, 100, 100)
            for j, other in enumerate(others):
                if j < log.others.shape[1]:
                    ox, oy, oh, ov = log.others[k, j]
                    other.position = np.array([ox, oy])
                    other.heading, other.speed = float(oh), float(ov)
            if follow:
                camera.position[0] = x + 30.0
            surface.move_display_window_to(viewer.window_position())
            if background is not None:
                surface.blit(background, (0, 0))
            else:
                RoadGraphics.display(road, surface)
                if reuse_background and not follow:
                    background = surface.copy()
            if traffic is not None:
                # The reference tracked at this moment (re-planned in the loop), near the view.
                ref = traffic.reference_at(float(log.t[k])).xy
                path_xy = ref[(ref[:, 0] > x - 60.0) & (ref[:, 0] < x + 120.0)]
            if len(path_xy) >= 2:
                pygame.draw.lines(
                    surface, PATH_COLOR, False, [surface.vec2pix(p) for p in path_xy], 2
                )
            if not follow:
                gx, gy = surface.vec2pix((goal.x, goal.y))
                pygame.draw.circle(surface, GOAL_COLOR, (gx, gy), max(3, surface.pix(0.4)), 2)
            RoadGraphics.display_road_objects(road, surface, offscreen=True)
            RoadGraphics.display_traffic(
                road, surface, simulation_frequency=sim.simulation_frequency, offscreen=True
            )
            if k >= 1:
                first = max(0, k - 600) if follow else 0
                trace = [surface.vec2pix(p) for p in log.states[first : k + 1, :2]]
                if len(trace) >= 2:
                    pygame.draw.lines(surface, TRACE_COLOR, False, trace, 2)
            frame = pygame.transform.flip(surface, False, True)
            kappa = math.tan(steer) / vehicle.wheelbase
            lines = [
                f"t {log.t[k]:5.2f} s   v {v:4.2f} m/s",
                f"kappa {kappa:+.3f} 1/m (max {vehicle.kappa_max:.3f})",
                f"cte {cte[k]:+.3f} m   {episode.controller}",
            ]
            if traffic is not None:
                mode = [m for tm, m in traffic.modes if tm <= log.t[k] + 1e-9]
                lines.append(f"mode {mode[-1] if mode else 'follow'}")
            panel_h = 8 + 20 * len(lines)
            pygame.draw.rect(frame, PANEL_COLOR, (6, 6, 290, panel_h))
            pygame.draw.rect(frame, TEXT_COLOR, (6, 6, 290, panel_h), 1)
            for i, text in enumerate(lines):
                frame.blit(font.render(text, True, TEXT_COLOR), (12, 11 + 20 * i))
            yield np.ascontiguousarray(np.moveaxis(pygame.surfarray.array3d(frame), 0, 1))
    finally:
        env.close()


def write_video(
    episode: Episode,
    target: str | os.PathLike[str],
    fps: float | None = None,
    stride: int = 1,
) -> int:
    """Write the episode as an MP4 (H.264) through imageio-ffmpeg; return the frame count.

    The file appears only when complete: frames go to a temporary file in the
    same folder, renamed at the end (removed on any error).

    Parameters
    ----------
    episode : Episode
        A driven episode.
    target : str or os.PathLike
        Output ``.mp4`` file.
    fps : float, optional
        Frames per second (default: real time, ``simulation_frequency / stride``).
    stride : int
        Steps between frames.

    Returns
    -------
    int
        Number of frames written.
    """
    import imageio.v2 as imageio

    out = FsPath(target)
    if out.suffix.lower() != ".mp4":
        raise InputError(f"--video: the file must end in .mp4, got {str(target)!r}")
    if not out.parent.exists():
        raise InputError(f"--video: folder {str(out.parent)!r} does not exist")
    fps = fps or (1.0 / episode.log.dt) / stride
    if not (math.isfinite(fps) and fps > 0):
        raise InputError(f"fps: must be > 0, got {fps!r}")
    tmp = temp_beside(out)
    count = 0
    try:
        writer = imageio.get_writer(
            tmp, format="FFMPEG", mode="I", fps=fps, codec="libx264", quality=7,
            macro_block_size=16, ffmpeg_log_level="error",
        )
        try:
            for frame in render_frames(episode, stride):
                writer.append_data(frame)
                count += 1
        finally:
            writer.close()
        publish(tmp, out)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    return count
