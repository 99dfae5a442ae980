"""``rrtdrive simulate``'s media outputs: ``--video`` and ``--plot`` of a driven episode.

Either failing to write is reported (exit 1) only after the JSON, the trajectory and the
summary are out, so that a full disk or a bad video path does not lose the drive's
metrics (it did; an audit).
"""

from __future__ import annotations

import argparse
import os
import sys
from typing import Any

from rrtdrive.cli_args import OutputError, writing

__all__ = ["write_media"]


def write_media(
    args: argparse.Namespace, episode: Any, stock: Any, streamed: int, stride: int,
    plot: str | None, extra: dict[str, Any],
) -> list[OutputError]:
    """Write ``--video`` and ``--plot`` when asked for, recording them in ``extra``.

    Parameters
    ----------
    args : argparse.Namespace
        ``simulate``'s arguments (``video``).
    episode : Episode
        The driven episode.
    stock : object or None
        A stock highway-env drive (its ``frames``), else ``None``.
    streamed : int
        Frames a stock drive already streamed into ``--video``.
    stride : int
        Simulation steps between video frames.
    plot : str or None
        The ``--plot`` file.
    extra : dict
        The JSON's extra fields: ``video``, ``video_frames``, ``plot`` (``None`` for
        an output that could not be written).

    Returns
    -------
    list of OutputError
        The outputs that could not be written, in order (empty when all were).
    """
    unwritten: list[OutputError] = []
    try:
        _write_video(args, episode, stock, streamed, stride, extra)
    except OutputError as exc:
        unwritten.append(exc)
        extra["video"] = None
    if plot:
        from rrtdrive.plotting import save_figure
        from rrtdrive.sim.episode_plot import plot_episode

        try:
            with writing("--plot", plot):
                save_figure(plot_episode(episode), plot)
            extra["plot"] = plot
        except OutputError as exc:
            unwritten.append(exc)
            extra["plot"] = None
    return unwritten


def _write_video(
    args: argparse.Namespace, episode: Any, stock: Any, streamed: int, stride: int,
    extra: dict[str, Any],
) -> None:
    """Write ``--video`` (when asked for) and record it in ``extra``."""
    if args.video and stock is not None:
        if not (stock.frames or streamed):
            extra["video"] = None
            _no_video(args.video, episode.message)
        elif streamed:
            extra["video_frames"], extra["video"] = streamed, args.video
        else:
            from rrtdrive.sim.video import real_time_fps, write_frames

            fps = getattr(args, "video_fps", None) or real_time_fps(
                len(stock.frames), len(episode.log.states), episode.log.dt
            )
            with writing("--video", args.video):
                extra["video_frames"] = write_frames(stock.frames, args.video, fps)
            extra["video"] = args.video
    elif args.video:
        if episode.log.steps == 0:
            extra["video"] = None
            _no_video(args.video, episode.message)
        else:
            from rrtdrive.sim.video import write_video

            def progress(done: int, total: int) -> None:
                # One line on stderr, rewritten in place on a terminal, else every 10 %.
                tty = sys.stderr.isatty()
                if tty or done == total or done % max(1, total // 10) == 0:
                    end = "\n" if done == total or not tty else ""
                    start = "\r" if tty else ""  # no carriage returns in a log file
                    print(f"{start}rrtdrive simulate: video {done}/{total} frames", end=end,
                          file=sys.stderr, flush=True)

            with writing("--video", args.video):
                frames = write_video(episode, args.video, stride=stride, progress=progress,
                                     fps=getattr(args, "video_fps", None))  # fmt: skip
            extra["video"] = args.video
            extra["video_frames"] = frames


def _no_video(target: str, why: str) -> None:
    """Say that no video was written, and that a file already at ``target`` is not this run's."""
    old = ""
    if os.path.exists(target):
        # Left as it was (it is the user's), but not to be taken for this drive (an audit).
        old = f"; {target} is an earlier run's, left as it was"
    print(f"rrtdrive simulate: no video: {why}{old}", file=sys.stderr)
