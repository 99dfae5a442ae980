"""An MP4 (H.264) file encoded while the caller renders, and published only when whole.

:class:`Mp4Writer` hands frames through a bounded queue to a writer thread that
feeds imageio-ffmpeg (which runs ffmpeg as a subprocess): the caller draws the
next frame while ffmpeg encodes the last ones, and the queue bound keeps at most
a few frames in memory. Frames go to a temporary file beside the target that is
renamed on :meth:`Mp4Writer.close` (removed by :meth:`Mp4Writer.abort` or on an
error), so a file that exists is complete.

Examples
--------
>>> import numpy as np, tempfile, pathlib
>>> out = pathlib.Path(tempfile.mkdtemp()) / "grey.mp4"
>>> with Mp4Writer(out, fps=10) as writer:
...     for _ in range(3):
...         writer.append(np.full((64, 64, 3), 128, np.uint8))
>>> out.exists(), writer.frames
(True, 3)
"""

from __future__ import annotations

import errno
import os
import queue
import signal
import subprocess
import threading
from pathlib import Path as FsPath
from types import TracebackType
from typing import Any

import numpy as np

from rrtdrive.atomic import publish, temp_beside
from rrtdrive.types import InputError, is_finite_number

__all__ = ["Mp4Writer", "require_fps"]

_STOP = object()
#: How often (s) an idle writer thread looks whether the writer was aborted.
_POLL_S = 0.2


def _encoder_process(writer: Any) -> subprocess.Popen[bytes] | None:
    """imageio-ffmpeg's ffmpeg process behind ``writer`` (``None`` if it cannot be found).

    imageio-ffmpeg never looks at ffmpeg's exit status: an ffmpeg that died (a full
    disk, a file size limit) left a truncated file that was published as a video.
    Its process is a local of the frame generator, read here before it is closed.
    """
    frame = getattr(getattr(writer, "_write_gen", None), "gi_frame", None)
    process = frame.f_locals.get("p") if frame is not None else None
    return process if isinstance(process, subprocess.Popen) else None


def _check_encoder(process: subprocess.Popen[bytes] | None, path: FsPath, frames: int) -> None:
    """Raise ``OSError`` unless ffmpeg exited cleanly (or, unseen, the file holds ``frames``)."""
    if process is not None:
        code = process.poll()
        if code == 0:
            return
        if code == -signal.SIGXFSZ:
            raise OSError(errno.EFBIG, os.strerror(errno.EFBIG))
        raise OSError(f"the video encoder (ffmpeg) failed with exit code {code}")
    import imageio_ffmpeg

    try:  # no process to ask: count the frames in the file (decodes it)
        found, _ = imageio_ffmpeg.count_frames_and_secs(str(path))
    except (RuntimeError, OSError):
        found = -1
    if found != frames:
        raise OSError(f"the video encoder (ffmpeg) wrote {max(found, 0)} of {frames} frames")


def require_fps(fps: object) -> float:
    """``fps`` as a float, or :class:`InputError` naming ``fps`` unless a finite number > 0.

    numpy numbers too (``np.int64(20)`` was "not a number > 0"; an audit).

    Examples
    --------
    >>> require_fps(25)
    25.0
    """
    if not is_finite_number(fps) or not fps > 0:  # type: ignore[operator]
        raise InputError(f"fps: must be a finite number > 0, got {fps!r}")
    return float(fps)  # type: ignore[arg-type]


class Mp4Writer:
    """Encode RGB frames to an MP4 file in a writer thread.

    Parameters
    ----------
    target : str or os.PathLike
        The ``.mp4`` file to create (its folder must exist).
    fps : float
        Frames per second.
    quality : int
        imageio-ffmpeg quality, 0-10.
    macro_block_size : int
        Frame sides are padded to multiples of this (imageio-ffmpeg; H.264 needs 2).
    queue_size : int
        Frames that may wait for the encoder; :meth:`append` blocks beyond that.

    Attributes
    ----------
    frames : int
        Frames handed to :meth:`append` so far.
    """

    def __init__(
        self,
        target: str | os.PathLike[str],
        fps: float,
        quality: int = 7,
        macro_block_size: int = 16,
        queue_size: int = 8,
    ) -> None:
        import imageio.v2 as imageio

        fps = require_fps(fps)
        if isinstance(queue_size, bool) or not isinstance(queue_size, int) or queue_size < 1:
            raise InputError(f"queue_size: need an integer >= 1, got {queue_size!r}")
        self.target = FsPath(target)
        self.frames = 0
        self._tmp = temp_beside(self.target)
        try:
            self._writer = imageio.get_writer(
                self._tmp, format="FFMPEG", mode="I", fps=fps, codec="libx264",
                quality=quality, macro_block_size=macro_block_size, ffmpeg_log_level="error",
            )
        except BaseException:
            self._tmp.unlink(missing_ok=True)
            raise
        self._queue: queue.Queue[Any] = queue.Queue(maxsize=queue_size)
        self._error: BaseException | None = None
        self._done = False
        self._aborted = False
        self._published = False
        self._thread = threading.Thread(target=self._run, name="rrtdrive-mp4", daemon=True)
        self._thread.start()

    def _run(self) -> None:
        # Keep taking frames after a failure so that a blocked append() wakes up.
        while True:
            try:
                item = self._queue.get(timeout=_POLL_S)
            except queue.Empty:
                if self._aborted:
                    break
                continue
            if item is _STOP:
                return
            if self._error is None and not self._aborted:
                try:
                    self._writer.append_data(item)
                except BaseException as exc:  # re-raised in the caller's thread
                    self._error = exc
        # Aborted: what is left of the encoder is closed here, off the caller's thread.
        self._close_killed()

    def _close_killed(self) -> None:
        """Close imageio's writer after an abort, whose ffmpeg was killed or failed."""
        try:
            self._writer.close()
        except Exception:  # the killed ffmpeg's pipe may be broken
            pass

    def append(self, frame: np.ndarray) -> None:
        """Queue one ``H x W x 3`` uint8 frame; it is encoded later, so do not modify it."""
        if self._done:
            raise RuntimeError("Mp4Writer.append: the writer is closed")
        if self._error is not None:
            raise self._error
        self._queue.put(frame)
        self.frames += 1

    def _stop(self) -> None:
        self._done = True
        self._queue.put(_STOP)
        self._thread.join()

    def close(self) -> FsPath:
        """Encode the queued frames, close ffmpeg and move the file into place; return it.

        Again after it succeeded: the same file. After a failed close or an :meth:`abort`
        there is no file to return: a RuntimeError.
        """
        if self._done:
            if self._published:
                return self.target
            raise RuntimeError(
                f"Mp4Writer.close: {self.target} was not written (an earlier close failed "
                "or the writer was aborted)"
            )
        try:
            self._stop()
            if self._error is not None:
                raise self._error
            process = _encoder_process(self._writer)
            self._writer.close()
            _check_encoder(process, self._tmp, self.frames)
            publish(self._tmp, self.target)
            self._published = True
        except BaseException:
            self._tmp.unlink(missing_ok=True)
            raise
        return self.target

    def abort(self) -> None:
        """Stop without publishing: ffmpeg is killed, the temporary file removed (idempotent).

        Nothing here waits on the writer thread or its queue: an interrupt (Ctrl-C,
        SIGTERM) raised while this thread was inside ``append`` may have left the queue's
        lock held, and joining the thread then hung the process (a SIGTERM during a video,
        once in CI). The thread sees the flag and ends by itself.
        """
        self._done = True
        self._aborted = True
        try:
            process = _encoder_process(self._writer)
            if process is not None and process.poll() is None:
                process.kill()
                process.wait()
            if not self._thread.is_alive():  # after a failed close: nobody else closes it
                self._close_killed()
        finally:
            self._tmp.unlink(missing_ok=True)

    def __enter__(self) -> Mp4Writer:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        if exc_type is None:
            self.close()
        else:
            try:
                self.abort()
            except Exception:  # the original error matters more than a failed clean-up
                pass
