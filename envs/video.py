"""Headless MP4 of any agent's episodes, through imageio-ffmpeg (no moviepy, no display).

:class:`RecordMP4` wraps any gymnasium environment made with
``render_mode="rgb_array"``; it renders after ``reset`` and after every ``step``
and writes each recorded episode to its own MP4 (H.264) when the episode ends
(or at the next ``reset`` or ``close`` for an unfinished one). A writer thread
encodes while the episode runs (:class:`~rrtdrive.sim.mp4.Mp4Writer`); frames go
to a temporary file in the target folder that is renamed when complete, so a
file that exists is whole. :func:`record_episode` runs one episode of a policy
through it.

Examples
--------
>>> import gymnasium as gym, rrtdrive  # doctest: +SKIP
>>> env = RecordMP4(gym.make("rrtdrive/Parking-v0", render_mode="rgb_array"), "videos")
>>> record_episode(env, lambda obs: env.action_space.sample(), seed=0)  # doctest: +SKIP
"""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path as FsPath
from typing import Any

import gymnasium as gym
import numpy as np

from rrtdrive.sim.mp4 import Mp4Writer, require_fps
from rrtdrive.types import InputError

__all__ = ["RecordMP4", "record_episode"]


def _even_frame(frame: Any) -> np.ndarray:
    """``frame`` as contiguous uint8 RGB, padded by edge pixels to even sides (H.264 needs them)."""
    f = np.asarray(frame)
    if f.ndim != 3 or f.shape[2] != 3:
        raise InputError(f"render: expected an H x W x 3 RGB frame, got shape {f.shape}")
    if f.dtype != np.uint8:
        f = np.clip(f, 0, 255).astype(np.uint8)
    pad_h, pad_w = f.shape[0] % 2, f.shape[1] % 2
    if pad_h or pad_w:
        f = np.pad(f, ((0, pad_h), (0, pad_w), (0, 0)), mode="edge")
    return np.ascontiguousarray(f)


class RecordMP4(gym.Wrapper):
    """Write the episodes of the wrapped environment as MP4 files.

    Parameters
    ----------
    env : gymnasium.Env
        Made with ``render_mode="rgb_array"``.
    folder : str or os.PathLike
        Existing or new folder for the videos.
    name_prefix : str
        Files are ``{name_prefix}-{episode:04d}.mp4`` (episodes counted from 0).
    episode_trigger : callable, optional
        ``episode_index -> bool``: record this episode (default: every one).
    fps : float, optional
        Frames per second (default: the environment's ``metadata["render_fps"]``,
        else 30).
    quality : int
        imageio-ffmpeg quality, 0-10.

    Attributes
    ----------
    written : list of pathlib.Path
        Videos written so far, in order.
    """

    def __init__(
        self,
        env: gym.Env,
        folder: str | os.PathLike[str],
        name_prefix: str = "episode",
        episode_trigger: Callable[[int], bool] | None = None,
        fps: float | None = None,
        quality: int = 7,
    ) -> None:
        super().__init__(env)
        if env.render_mode != "rgb_array":
            raise InputError(
                f"render_mode: RecordMP4 needs an env made with render_mode='rgb_array', "
                f"got {env.render_mode!r}"
            )
        if not isinstance(name_prefix, str) or not name_prefix or os.sep in name_prefix:
            raise InputError(f"name_prefix: need a non-empty file-name prefix, got {name_prefix!r}")
        fps = fps if fps is not None else env.metadata.get("render_fps") or 30
        fps = require_fps(fps)  # at once, not at the first episode's writer
        if isinstance(quality, bool) or not isinstance(quality, int) or not 0 <= quality <= 10:
            raise InputError(f"quality: need an integer in 0..10, got {quality!r}")
        self.folder = FsPath(folder)
        self.folder.mkdir(parents=True, exist_ok=True)
        self.name_prefix = name_prefix
        self.episode_trigger = episode_trigger
        self.fps = float(fps)
        self.quality = quality
        self.written: list[FsPath] = []
        self._episode = -1
        self._writer: Mp4Writer | None = None
        self._target: FsPath | None = None
        self._shape: tuple[int, ...] | None = None

    # ------------------------------------------------------------------ writer

    def _open(self) -> None:
        self._target = self.folder / f"{self.name_prefix}-{self._episode:04d}.mp4"
        self._writer = Mp4Writer(
            self._target, self.fps, quality=self.quality, macro_block_size=2
        )
        self._shape = None

    def _capture(self) -> None:
        if self._writer is None:
            return
        frame = _even_frame(self.env.render())
        if self._shape is None:
            self._shape = frame.shape
        elif frame.shape != self._shape:
            raise InputError(
                f"render: frame size changed within an episode ({self._shape} -> {frame.shape})"
            )
        # Encoded later by the writer thread: a copy, in case the env reuses its buffer.
        self._writer.append(frame.copy())

    def _finish(self) -> FsPath | None:
        """Close the current video and move it into place; return its path."""
        writer, target = self._writer, self._target
        self._writer = self._target = None
        if writer is None or target is None:
            return None
        writer.close()
        self.written.append(target)
        return target

    def _abort(self) -> None:
        writer = self._writer
        self._writer = self._target = None
        if writer is not None:
            writer.abort()

    # ------------------------------------------------------------------ gym API

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[Any, dict[str, Any]]:
        """Reset the environment and start recording the new episode if triggered."""
        self._finish()  # an unfinished episode is still written
        obs, info = self.env.reset(seed=seed, options=options)
        self._episode += 1
        if self.episode_trigger is None or self.episode_trigger(self._episode):
            self._open()
            try:
                self._capture()
            except BaseException:
                self._abort()
                raise
        return obs, info

    def step(self, action: Any) -> tuple[Any, float, bool, bool, dict[str, Any]]:
        """Step the environment, add a frame, and write the video at the episode's end."""
        obs, reward, terminated, truncated, info = self.env.step(action)
        try:
            self._capture()
        except BaseException:
            self._abort()
            raise
        if terminated or truncated:
            path = self._finish()
            if path is not None:
                info = {**info, "video": str(path)}
        return obs, float(reward), terminated, truncated, info

    def close(self) -> None:
        """Write any unfinished video, then close the environment."""
        try:
            self._finish()
        finally:
            super().close()


def record_episode(
    env: RecordMP4,
    policy: Callable[[Any], Any],
    seed: int | None = None,
    options: dict[str, Any] | None = None,
    max_steps: int | None = None,
) -> tuple[float, dict[str, Any]]:
    """Run one episode of ``policy`` in a :class:`RecordMP4` environment.

    Parameters
    ----------
    env : RecordMP4
        The recording environment (this episode must be triggered).
    policy : callable
        ``observation -> action``; for a Stable-Baselines3 model
        ``lambda obs: model.predict(obs, deterministic=True)[0]``.
    seed : int, optional
        Reset seed.
    options : dict, optional
        Reset options.
    max_steps : int, optional
        Stop after this many steps (the video is written all the same).

    Returns
    -------
    total_reward : float
    info : dict
        The last step's info; ``info["video"]`` is the MP4's path.
    """
    if not isinstance(env, RecordMP4):
        raise InputError(f"env: expected a RecordMP4 wrapper, got {type(env).__name__}")
    if max_steps is not None and (
        isinstance(max_steps, bool) or not isinstance(max_steps, int) or max_steps < 1
    ):
        raise InputError(f"max_steps: need an integer >= 1, got {max_steps!r}")
    obs, info = env.reset(seed=seed, options=options)
    total = 0.0
    steps = 0
    while True:
        obs, reward, terminated, truncated, info = env.step(policy(obs))
        total += float(reward)
        steps += 1
        if terminated or truncated:
            break
        if max_steps is not None and steps >= max_steps:
            path = env._finish()
            info = {**info, "video": str(path) if path is not None else None}
            break
    return total, info
