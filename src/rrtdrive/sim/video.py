"""Headless MP4 of an episode: the scene, the planned path, the driven trace and a read-out.

The video only reads an :class:`~rrtdrive.sim.runner.Episode`: it rebuilds the
scene (no display needed; do not set ``SDL_VIDEODRIVER=dummy``, which makes
highway-env draw nothing), puts every vehicle at its logged pose frame by frame
and draws with highway-env's own graphics plus the path and trace through
:class:`~rrtdrive.sim.render.SceneCanvas`, which draws what does not move (lanes,
path, obstacles, parked cars) once per camera. :func:`write_video` encodes while
the next frames are drawn (:class:`~rrtdrive.sim.mp4.Mp4Writer`: a writer thread
feeding imageio-ffmpeg) into a temporary file that is renamed when complete.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Iterable, Iterator
from pathlib import Path as FsPath

import numpy as np

from rrtdrive.sim.episode import Episode
from rrtdrive.sim.mp4 import Mp4Writer
from rrtdrive.sim.render import TRACE_COLOR, SceneCanvas, fewest_hits, panel_band
from rrtdrive.sim.scenes import SimConfig, build_env
from rrtdrive.types import InputError, Pose, require_int

__all__ = [
    "render_frames", "write_video", "write_frames", "frame_is_blank", "frame_indices",
    "hud_gears", "real_time_fps", "open_frames_video", "even_frame",
]

#: ``progress(frames_done, frames_total)``, called after each frame is handed to the encoder.
Progress = Callable[[int, int], None]
#: The read-out panel's width, pixels.
PANEL_WIDTH = 290


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


def hud_gears(speeds: np.ndarray) -> np.ndarray:
    """The gear the read-out shows at each logged state: ``"D"`` or ``"R"``.

    The sign of the speed while moving; at standstill the gear of the next motion
    (the gear is changed at rest, before the car moves off), ``"D"`` when it never
    moves again.

    Examples
    --------
    >>> hud_gears(np.array([0.0, 1.0, 0.0, 0.0, -0.5, 0.0])).tolist()
    ['D', 'D', 'R', 'R', 'R', 'D']
    """
    v = np.asarray(speeds, dtype=float)
    out = np.empty(len(v), dtype=object)
    nxt = "D"
    for k in range(len(v) - 1, -1, -1):
        if v[k] > 0:
            nxt = "D"
        elif v[k] < 0:
            nxt = "R"
        out[k] = nxt
    return out.astype(str)


def real_time_fps(frames: int, states: int, dt: float) -> float:
    """Frames per second that make ``frames`` frames last as long as ``states`` logged states.

    ``simulation_frequency / stride`` when the stride divides the steps; otherwise the
    final state's extra frame (after fewer steps than a stride) no longer stretches the
    video: 2 frames of a 5 s episode at stride 1000 played 100 s.

    Examples
    --------
    >>> real_time_fps(101, 101, 0.05), round(real_time_fps(2, 101, 0.05), 3)
    (20.0, 0.396)
    """
    return (frames / states) / dt  # exactly 1 / dt when every state is a frame


def frame_indices(episode: Episode, stride: int = 1) -> list[int]:
    """Logged steps shown by a video: every ``stride``-th one and always the last.

    Parameters
    ----------
    episode : Episode
        A driven episode (at least one logged state).
    stride : int
        Steps between frames.

    Returns
    -------
    list of int
        Indices into ``episode.log.states``.
    """
    n = len(episode.log.states)
    if n == 0:
        raise InputError("video: the episode has no trajectory (planning failed?)")
    require_int("stride", stride)
    indices = list(range(0, n, stride))
    if indices[-1] != n - 1:
        indices.append(n - 1)  # always show the final state
    return indices


def _panel_lines(episode: Episode) -> int:
    """Lines of the read-out: three, plus the path's gear changes and the traffic mode."""
    cusps = len(episode.path.cusps) if len(episode.path) else 0
    return 3 + bool(cusps) + (episode.traffic is not None)


def _panel_layout(
    episode: Episode,
    size: tuple[int, int],
    scaling: float,
    camera: _Camera,
    follow: bool,
    reuse_static: bool,
) -> tuple[SceneCanvas, str]:
    """The canvas of the video and the corner of its read-out panel.

    A following camera keeps the panel top left. A fixed view puts it in the corner
    that hides least of the path and the drive (:meth:`SceneCanvas.panel_corner`);
    when every corner hides some of them (a tall narrow map: a 320 px wide frame
    has no room for the 290 px panel beside the route), the frame grows by a band
    above the scene (:func:`~rrtdrive.sim.render.panel_band`) that holds the panel
    top left, and ``camera`` moves up by half the band so that the scene is drawn
    where it was, below the band.
    """
    canvas = SceneCanvas(size, scaling, tuple(camera.position), reuse_static=reuse_static)
    if follow:
        return canvas, "top-left"
    lines = _panel_lines(episode)
    path_xy = np.asarray(episode.path.xy, dtype=float).reshape(-1, 2)
    route = np.vstack([path_xy, episode.log.states[:, :2]])
    hits = canvas.panel_hits(route, PANEL_WIDTH, lines)
    corner = fewest_hits(hits)
    if hits[corner] == 0:
        return canvas, corner
    band = panel_band(lines)
    camera.position[1] += band / 2.0 / scaling
    canvas = SceneCanvas(
        (size[0], size[1] + band), scaling, tuple(camera.position), reuse_static=reuse_static
    )
    return canvas, "top-left"


def render_frames(
    episode: Episode,
    stride: int = 1,
    sim: SimConfig | None = None,
    reuse_background: bool = True,
) -> Iterator[np.ndarray]:
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
        With a fixed camera (every scene but the long traffic road), draw what does
        not move (lanes, path, goal, obstacles, parked cars) once and copy it into
        every frame; ``False`` draws everything every frame. The frames are the same
        pixels either way.

    Yields
    ------
    numpy.ndarray
        One frame.
    """
    from rrtdrive.evaluation import tracking_errors

    log = episode.log
    indices = frame_indices(episode, stride)
    size, scaling, camera = _camera_for(episode)
    sim = sim or SimConfig(simulation_frequency=int(round(1.0 / log.dt)))
    sim = SimConfig(
        simulation_frequency=sim.simulation_frequency,
        screen_width=sim.screen_width or size[0],
        screen_height=sim.screen_height or size[1],
        scaling=sim.scaling or scaling,
    )
    env = build_env(episode.scenario, sim)
    try:
        u = env.unwrapped
        follow = episode.scenario.camera().follow
        canvas, corner = _panel_layout(
            episode, (sim.screen_width, sim.screen_height), sim.scaling, camera, follow,
            reuse_background,
        )
        road = u.road
        ego = u.vehicle
        others = [v for v in road.vehicles if v is not ego]
        vehicle = episode.scenario.vehicle
        path_xy = episode.path.xy
        traffic = episode.traffic
        cte = (
            # Per gear segment, as the evaluators measure it (docs/metrics.md).
            tracking_errors(episode.path, log.states[:, :3], speeds=log.states[:, 3])[0]
            if len(episode.path) >= 2 else np.zeros(len(log.states))
        )
        goal = episode.scenario.goal
        path_gears = episode.path.gears if len(episode.path) else None
        gear_of = hud_gears(log.states[:, 3])
        cusps = len(episode.path.cusps) if len(episode.path) else 0
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
            if ego.crashed:
                # What the car hit turns red as it did live: highway-env's own test of
                # the logged pose against each object and car (its flags stay set).
                for thing in [*road.objects, *others]:
                    ego.handle_collisions(thing, 0.0)
            if follow:
                camera.position[0] = x + 30.0
            canvas.centre = camera.position
            if traffic is not None:
                # The reference tracked at this moment (re-planned in the loop), near the view.
                ref = traffic.reference_at(float(log.t[k])).xy
                path_xy = ref[(ref[:, 0] > x - 60.0) & (ref[:, 0] < x + 120.0)]
            canvas.draw(
                road, sim.simulation_frequency, path_xy,
                None if follow else (goal.x, goal.y),
                gears=path_gears if traffic is None else None,
            )
            if k >= 1:
                first = max(0, k - 600) if follow else 0
                canvas.polyline(log.states[first : k + 1, :2], TRACE_COLOR)
            kappa = math.tan(steer) / vehicle.wheelbase
            lines = [
                f"t {log.t[k]:5.2f} s   v {v:+5.2f} m/s   gear {gear_of[k]}",
                f"kappa {kappa:+.3f} 1/m (max {vehicle.kappa_max:.3f})",
                f"cte {cte[k]:+.3f} m   {episode.controller}",
            ]
            if cusps:
                lines.append(f"gear changes: path {cusps}")
            if traffic is not None:
                mode = [m for tm, m in traffic.modes if tm <= log.t[k] + 1e-9]
                lines.append(f"mode {mode[-1] if mode else 'follow'}")
            yield canvas.frame(lines, panel_width=PANEL_WIDTH, corner=corner)
    finally:
        env.close()


def write_video(
    episode: Episode,
    target: str | os.PathLike[str],
    fps: float | None = None,
    stride: int = 1,
    progress: Progress | None = None,
) -> int:
    """Write the episode as an MP4 (H.264) through imageio-ffmpeg; return the frame count.

    Frames are encoded by a writer thread while the next ones are drawn. The file
    appears only when complete: frames go to a temporary file in the same folder,
    renamed at the end (removed on any error).

    Parameters
    ----------
    episode : Episode
        A driven episode.
    target : str or os.PathLike
        Output ``.mp4`` file.
    fps : float, optional
        Frames per second (default: real time, :func:`real_time_fps`: the video lasts
        the episode's simulated time, about ``simulation_frequency / stride``).
    stride : int
        Steps between frames.
    progress : callable, optional
        ``progress(frames_done, frames_total)`` after each frame (nothing is printed
        without one).

    Returns
    -------
    int
        Number of frames written.
    """
    out = FsPath(target)
    if out.suffix.lower() != ".mp4":
        raise InputError(f"--video: the file must end in .mp4, got {str(target)!r}")
    if not out.parent.exists():
        raise InputError(f"--video: folder {str(out.parent)!r} does not exist")
    if out.is_dir():  # before every frame is drawn and encoded, not at the rename
        raise InputError(f"--video: {str(target)!r} is a folder; give a file name")
    total = len(frame_indices(episode, stride))  # checks stride first
    if fps is None:
        fps = real_time_fps(total, len(episode.log.states), episode.log.dt)
    # The writer checks fps before a frame is drawn.
    with Mp4Writer(out, fps, quality=7, macro_block_size=16) as writer:
        for frame in render_frames(episode, stride):
            writer.append(frame)
            if progress is not None:
                progress(writer.frames, total)
    return writer.frames


def open_frames_video(target: str | os.PathLike[str], fps: float) -> Mp4Writer:
    """An :class:`~rrtdrive.sim.mp4.Mp4Writer` for frames drawn elsewhere (see :func:`even_frame`).

    For highway-env's own ``env.render()`` of a stock env: a drive can stream its frames
    into it as they are drawn instead of keeping them all (``rrtdrive simulate
    parking-v0 --video``). The file appears only when the writer is closed.
    """
    out = FsPath(target)
    if out.suffix.lower() != ".mp4":
        raise InputError(f"--video: the file must end in .mp4, got {str(target)!r}")
    if not out.parent.exists():
        raise InputError(f"--video: folder {str(out.parent)!r} does not exist")
    if not (math.isfinite(fps) and fps > 0):
        raise InputError(f"fps: must be > 0, got {fps!r}")
    return Mp4Writer(out, fps, quality=7, macro_block_size=2)


def even_frame(frame: np.ndarray) -> np.ndarray:
    """An RGB frame as contiguous uint8 with even sides (odd ones padded by one edge pixel)."""
    f = np.asarray(frame, dtype=np.uint8)
    pad_h, pad_w = f.shape[0] % 2, f.shape[1] % 2
    if pad_h or pad_w:
        f = np.pad(f, ((0, pad_h), (0, pad_w), (0, 0)), mode="edge")
    return np.ascontiguousarray(f)


def write_frames(
    frames: Iterable[np.ndarray], target: str | os.PathLike[str], fps: float
) -> int:
    """Write ready RGB frames (any even or odd size) as an MP4; return the frame count.

    For frames drawn elsewhere (highway-env's own ``env.render()`` of a stock env);
    odd sides are padded by one edge pixel. The file appears only when complete.
    """
    with open_frames_video(target, fps) as writer:
        for frame in frames:
            writer.append(even_frame(frame))
    return writer.frames
