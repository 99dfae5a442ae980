"""Whole files or nothing: write to a temporary file beside the target, then rename.

A target that is a symbolic link is written through it (the file it points to is
replaced, the link stays). One that is not a regular file (``/dev/null``, a named
pipe, ``/dev/stdout``) gets the finished bytes written into it: renaming over it
would put a regular file in its place.
"""

from __future__ import annotations

import os
import shutil
import stat
import tempfile
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

__all__ = [
    "atomic_target",
    "destination",
    "is_stream",
    "publish",
    "temp_beside",
    "write_text_atomic",
]


def _umask() -> int:
    # Linux says it in /proc (4.7+). os.umask can only read it by setting it, for the
    # whole process: a file another thread created in between was world-writable.
    try:
        with open("/proc/self/status", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError, IndexError):
        pass
    with _UMASK_LOCK:  # elsewhere: set and put back (two readers at once left it 0)
        mask = os.umask(0)
        os.umask(mask)
    return mask


_UMASK_LOCK = threading.Lock()


def destination(target: str | os.PathLike[str]) -> Path:
    """The file ``target`` names: itself, or the file its symbolic link points to.

    A link to a device or pipe is kept as it is: ``/dev/stdout`` resolves to
    ``/proc/self/fd/1``, whose target, when stdout is a pipe, is no path at all
    (``pipe:[N]``); opening the link itself reaches the pipe.
    """
    if not os.path.islink(target) or is_stream(target):
        return Path(target)
    return Path(os.path.realpath(target))


def is_stream(target: str | os.PathLike[str]) -> bool:
    """Whether ``target`` exists and is neither a regular file nor a folder (a device, a pipe).

    Examples
    --------
    >>> is_stream(os.devnull), is_stream(__file__)
    (True, False)
    """
    try:
        mode = os.stat(target).st_mode
    except OSError:
        return False
    return not (stat.S_ISREG(mode) or stat.S_ISDIR(mode))


def temp_beside(target: str | os.PathLike[str], suffix: str | None = None) -> Path:
    """Create an empty hidden temporary file in ``target``'s folder and return its path.

    Beside the file a link points to; for a device or pipe, in the system's temporary
    folder (``/dev`` takes no files).
    """
    target = destination(target)
    folder = None if is_stream(target) else (target.parent if str(target.parent) else ".")
    suffix = _fitting(target.suffix if suffix is None else suffix, 0, folder)
    try:
        fd, tmp = tempfile.mkstemp(
            prefix=f".{_fitting(target.stem, len(os.fsencode(suffix)), folder)}.",
            suffix=suffix, dir=folder,
        )
    except OSError as exc:
        raise _naming(exc, target) from None
    os.close(fd)
    return Path(tmp)


#: Bytes mkstemp adds to prefix and suffix: the dot before the stem, the dot after it
#: and its 8 random characters.
_TEMP_EXTRA = 10


def _fitting(part: str, taken: int, folder: str | os.PathLike[str] | None) -> str:
    """``part`` of the temporary name (stem or suffix) cut so the whole name fits.

    The temporary file's name is 10 bytes longer than the target's: a target named
    with 250 bytes, which the file system takes, was refused (an audit). ``taken``:
    bytes the rest of the name already uses (the suffix, for the stem).
    """
    try:
        name_max = os.pathconf(folder or tempfile.gettempdir(), "PC_NAME_MAX")
    except (OSError, ValueError):
        name_max = 255
    room = max(name_max - _TEMP_EXTRA - taken, 0)
    encoded = os.fsencode(part)
    if len(encoded) <= room:
        return part
    # Cut whole characters: a UTF-8 sequence cut in half is no name.
    return os.fsdecode(encoded[:room].decode("utf-8", "ignore").encode("utf-8"))


def _naming(exc: OSError, target: str | os.PathLike[str]) -> OSError:
    """``exc`` naming ``target``, not the hidden temporary file it failed on."""
    return OSError(exc.errno, exc.strerror, os.fspath(target))


def publish(tmp: str | os.PathLike[str], target: str | os.PathLike[str]) -> None:
    """Put the finished ``tmp`` in ``target``'s place.

    A regular file (or none yet) is replaced by renaming ``tmp``, which keeps the
    replaced file's permissions (else the usual ones: mkstemp makes 0600); through a
    link, the file it points to is replaced; a device or pipe has the bytes written
    into it.
    """
    target = destination(target)
    try:
        if is_stream(target):
            with open(tmp, "rb") as src, open(target, "wb") as dst:
                shutil.copyfileobj(src, dst)
            os.unlink(tmp)
            return
        try:
            mode = stat.S_IMODE(os.stat(target).st_mode)
        except OSError:
            mode = 0o666 & ~_umask()
        os.chmod(tmp, mode)
        os.replace(tmp, target)
    except OSError as exc:  # the rename's error names the temporary file too
        raise _naming(exc, target) from None


@contextmanager
def atomic_target(target: str | os.PathLike[str], suffix: str | None = None) -> Iterator[Path]:
    """Yield a temporary path to write; on success it replaces ``target``, on error it is removed.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> folder = pathlib.Path(tempfile.mkdtemp())
    >>> with atomic_target(folder / "a.txt") as tmp:
    ...     _ = tmp.write_text("done")
    >>> (folder / "a.txt").read_text()
    'done'
    """
    tmp = temp_beside(target, suffix)
    try:
        yield tmp
        publish(tmp, target)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def write_text_atomic(path: str | os.PathLike[str], text: str) -> None:
    """Write ``text`` (UTF-8) to ``path`` atomically."""
    with atomic_target(path) as tmp:
        tmp.write_text(text, encoding="utf-8")
