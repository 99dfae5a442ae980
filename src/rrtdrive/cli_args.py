"""Argument types shared by the subcommands: each turns bad text into one clear argparse error."""

from __future__ import annotations

import argparse
import io
import json
import math
import os
import re
import stat
import sys
import warnings
from collections.abc import Callable, Collection, Iterator, Mapping, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING

from rrtdrive.atomic import destination, is_stream, temp_beside
from rrtdrive.types import InputError, InputWarning, Pose

if TYPE_CHECKING:
    from rrtdrive.maps import Map
    from rrtdrive.types import VehicleParams

__all__ = [
    "register_ompl_if_named",
    "OutputError",
    "cell_size",
    "distinct_outputs",
    "flags_for",
    "flags_for_warnings",
    "int_at_least",
    "join_negative_values",
    "map_with_poses",
    "names_stdout",
    "nonneg_float",
    "nonneg_int",
    "parse_pose",
    "positive_float",
    "positive_int",
    "raise_unwritten",
    "validate_output",
    "write_each",
    "write_output",
    "writing",
]

#: Suffixes ``plan --plot`` and ``verify --plot`` can write (matplotlib's Agg formats we
#: promise).
PLOT_SUFFIXES = (".png", ".pdf", ".svg")

# "-5", "-5,6,0", "-.5,1e-3,0", "-inf", "-nan": a value, not an option (argparse only
# knows plain numbers; "-inf" read "expected one argument").
_NEGATIVE_VALUE = re.compile(r"^-((\d|\.\d)[\d.,eE+\-]*|(?i:inf|infinity|nan))$")


def int_at_least(low: int, unit: str = "", high: int | None = None) -> Callable[[str], int]:
    """An argparse type accepting integers ``>= low`` (and ``<= high``; ``unit`` is named)."""
    suffix = f" ({unit})" if unit else ""
    want = f"an integer >= {low}" + ("" if high is None else f" and <= {high}")

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected {want}{suffix}, got {text!r}") from None
        if value < low or (high is not None and value > high):
            raise argparse.ArgumentTypeError(f"expected {want}{suffix}, got {text!r}")
        return value

    return parse


nonneg_int = int_at_least(0)
positive_int = int_at_least(1)


def positive_float(text: str) -> float:
    """An argparse type accepting finite numbers ``> 0``."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number > 0, got {text!r}") from None
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"expected a finite number > 0, got {text!r}")
    return value


def nonneg_float(text: str) -> float:
    """An argparse type accepting finite numbers ``>= 0``."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number >= 0, got {text!r}") from None
    if not (math.isfinite(value) and value >= 0):
        raise argparse.ArgumentTypeError(f"expected a finite number >= 0, got {text!r}")
    return value


def cell_size(text: str) -> float:
    """An argparse type for a collision grid cell: what ``CheckerConfig`` takes, in metres."""
    from rrtdrive.collision.config import CheckerConfig  # only when the flag is given

    value = positive_float(text)
    try:
        CheckerConfig(resolution=value)
    except InputError as exc:  # its own bound and words, without its field name
        raise argparse.ArgumentTypeError(str(exc).removeprefix("checker.resolution: ")) from None
    return value


def join_negative_values(argv: Sequence[str], value_options: Collection[str]) -> list[str]:
    """Glue ``--start -5,6,0`` into ``--start=-5,6,0`` so argparse takes it as the value.

    Only options in ``value_options`` (those that take one value) are joined, and only
    with a following token that reads as numbers.

    Examples
    --------
    >>> join_negative_values(["plan", "m", "--start", "-5,6,0"], {"--start"})
    ['plan', 'm', '--start=-5,6,0']
    >>> join_negative_values(["--start", "-x"], {"--start"})
    ['--start', '-x']
    """
    out: list[str] = []
    i = 0
    while i < len(argv):
        token = argv[i]
        if token == "--":  # everything after is positional: leave it alone
            out.extend(argv[i:])
            break
        nxt = argv[i + 1] if i + 1 < len(argv) else None
        if token in value_options and nxt is not None and _NEGATIVE_VALUE.match(nxt):
            out.append(f"{token}={nxt}")
            i += 2
        else:
            out.append(token)
            i += 1
    return out


class OutputError(Exception):
    """A file the command writes failed after its checks passed (a full disk): exit 1.

    Not bad input (exit 2): the same command succeeds once there is room again.
    ``flag``: the option whose file it was (``--json``), when known.
    """

    def __init__(self, message: str, flag: str = "") -> None:
        super().__init__(message)
        self.flag = flag


@contextmanager
def writing(flag: str, target: str | os.PathLike[str]) -> Iterator[None]:
    """Turn an ``OSError`` of the block into one :class:`OutputError` naming ``flag``."""
    try:
        yield
    except OSError as exc:
        # The first line only: imageio's error carries ffmpeg's command and output after it.
        why = exc.strerror or (str(exc).strip().splitlines() or [type(exc).__name__])[0]
        # The file that failed: a bench's summary.md inside --out, not the folder (an audit).
        where = exc.filename if isinstance(exc.filename, str) and exc.filename else target
        raise OutputError(f"{flag}: cannot write {where}: {why}", flag) from None


def write_each(
    outputs: Sequence[tuple[str, str | None, Callable[[], None]]],
) -> list[OutputError]:
    """Write every output asked for, each whatever became of the others.

    ``outputs``: ``(flag, target, write)``; ``write`` runs when ``target`` is a file,
    inside :func:`writing` (``-``, stdout, is the caller's to print in its place). One
    that cannot be written (a full disk, a folder gone) does not keep the next from
    being written: a failed ``--json`` lost the ``--plot`` and the summary of a plan
    that had run (an audit).

    Returns
    -------
    list of OutputError
        The outputs that could not be written, in order (see :func:`raise_unwritten`).
    """
    unwritten: list[OutputError] = []
    for flag, target, write in outputs:
        if not target or target == "-":
            continue
        try:
            with writing(flag, target):
                write()
        except OutputError as exc:
            unwritten.append(exc)
    return unwritten


def raise_unwritten(command: str, unwritten: Sequence[OutputError]) -> None:
    """After the summary: print every output that failed but the first, then raise that one.

    The command then exits 1 with each failure named (the first by the caller's handler).
    """
    for exc in unwritten[1:]:
        print(f"rrtdrive {command}: error: {exc}", file=sys.stderr)
    if unwritten:
        raise unwritten[0]


def names_stdout(target: str) -> bool:
    """Whether ``target`` is the pipe or file the process's stdout writes to.

    ``--json /dev/stdout | jq`` and ``--json /dev/stdout > out.json`` are ``--json -``
    (replacing the file by a rename lost the summary printed into it before). Only a
    pipe, socket or regular file: ``--json /dev/null > /dev/null`` keeps its summary
    on stdout.

    Examples
    --------
    >>> names_stdout(__file__)
    False
    """
    try:
        here, there = os.fstat(sys.stdout.fileno()), os.stat(target)
    except (OSError, ValueError, AttributeError, io.UnsupportedOperation):
        return False  # no such file, or a stdout with no file (captured by a test)
    mode = here.st_mode
    kind = stat.S_ISFIFO(mode) or stat.S_ISSOCK(mode) or stat.S_ISREG(mode)
    return kind and (here.st_dev, here.st_ino) == (there.st_dev, there.st_ino)


def distinct_outputs(inputs: Mapping[str, str | None] | None = None, **targets: str | None) -> None:
    """Raise :class:`InputError` when two output options name one file, or an input file.

    Keyword names are the flags without dashes (``json=..., plot=...``); unset ones and
    stdout (``"-"``) are skipped. Links are followed, so ``a.json`` and a link to it clash.
    ``inputs`` maps how an input is named (``"MAP"``, ``"PLAN"``) to its argument: an
    output that would overwrite an existing input file is refused before any work.

    Examples
    --------
    >>> import tempfile
    >>> f = tempfile.NamedTemporaryFile(suffix=".json")
    >>> distinct_outputs({"MAP": f.name}, json=f.name)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    rrtdrive.types.InputError: --json: ... is the MAP file it reads; give the output another name
    """
    seen: dict[str, str] = {}
    for label, source in (inputs or {}).items():
        if source and source != "-" and os.path.isfile(source):
            seen[os.path.realpath(source)] = label
    read = set(seen)
    for name, target in targets.items():
        if not target or target == "-":
            continue
        flag = "--" + name.replace("_", "-")
        key = os.path.realpath(target)
        if key in read:
            raise InputError(
                f"{flag}: {target!r} is the {seen[key]} file it reads; give the output "
                "another name"
            )
        if key in seen:
            raise InputError(
                f"{flag}: {target!r} is also the {seen[key]} file; give each output its own name"
            )
        seen[key] = flag


def _flagged(text: str, fields: Mapping[str, str]) -> str | None:
    """``text`` (``"field: ..."``) with its field replaced by its flag; ``None`` if not one."""
    field, sep, rest = text.partition(": ")
    return f"{fields[field]}: {rest}" if sep and field in fields else None


def register_ompl_if_named(planner: str | None, reverse: bool) -> None:
    """Register the OMPL comparators when ``planner`` names one (``ompl-rs-rrtconnect``).

    They live with the bench (``rrtdrive.bench.ompl_planners``), which ``plan`` and
    ``simulate`` do not load otherwise; OMPL itself is needed only when one plans.

    Raises
    ------
    InputError
        Naming ``--planner``: a Reeds-Shepp one without ``reverse``. Its curves change
        gear whatever the problem says: a plan would claim ``"reverse": false`` over
        a path with cusps.
    """
    if not (isinstance(planner, str) and planner.startswith("ompl-")):
        return
    import rrtdrive.bench.ompl_planners  # noqa: F401 - registers them by name

    if planner.startswith("ompl-rs-") and not reverse:
        raise InputError(f"--planner: {planner} changes gear (Reeds-Shepp); give --reverse")


def parse_planner_options(texts: Sequence[str] | None, flag: str) -> dict[str, object]:
    """``FIELD=VALUE`` texts as planner keywords: values read as JSON, else as text.

    A dotted field sets a field of a nested config (``smoothing.max_rounds=8``: the
    keyword ``smoothing={"max_rounds": 8}``), the spelling the planners' errors use.

    Examples
    --------
    >>> parse_planner_options(["reverse_detour_tree=false", "step=4", "curve=arcs"], "-o")
    {'reverse_detour_tree': False, 'step': 4, 'curve': 'arcs'}
    >>> parse_planner_options(["smoothing.max_rounds=8", "smoothing.clothoid=false"], "-o")
    {'smoothing': {'max_rounds': 8, 'clothoid': False}}
    >>> parse_planner_options(["step"], "-o")
    Traceback (most recent call last):
    ...
    rrtdrive.types.InputError: -o: expected FIELD=VALUE (e.g. reverse_detour_tree=false), got 'step'
    """
    out: dict[str, object] = {}
    given: list[tuple[str, ...]] = []
    for text in texts or ():
        key, eq, value = text.partition("=")
        key = key.strip()
        if not eq or not key:
            raise InputError(
                f"{flag}: expected FIELD=VALUE (e.g. reverse_detour_tree=false), got {text!r}"
            )
        path = tuple(part.strip() for part in key.split("."))
        if not all(path):
            raise InputError(
                f"{flag} {key}: an empty field name; nested fields read "
                "smoothing.max_rounds=8"
            )
        for other in given:
            # The same field, or a config given whole and one of its fields besides.
            if path[: len(other)] == other or other[: len(path)] == path:
                twice = key if path == other else f"{'.'.join(other)} and {key}"
                raise InputError(f"{flag} {twice}: given twice")
        given.append(path)
        if path[0] == "reverse":  # the query's, which the JSON reports: not the planner's own
            raise InputError(f"{flag} reverse: give --reverse to allow gear changes")
        try:
            parsed: object = json.loads(value)
        except ValueError:
            parsed = value
        node = out
        for part in path[:-1]:
            node = node.setdefault(part, {})  # type: ignore[assignment]
        node[path[-1]] = parsed
    return out


def planner_option_flags(
    options: Mapping[str, object], flag: str, sep: str = " "
) -> dict[str, str]:
    """The fields the planners' errors name, mapped to ``flag FIELD`` for :func:`flags_for`.

    ``planner.step``, ``hybrid.curve``, ``planner.smoothing.max_rounds``; ``sep`` between
    the flag and the field (``"."``: ``planner_options.step``, an API keyword's field).

    Examples
    --------
    >>> planner_option_flags({"smoothing": {"max_rounds": 8}}, "-o")["planner.smoothing.max_rounds"]
    '-o smoothing.max_rounds'
    """
    out: dict[str, str] = {}
    for key, value in options.items():
        for prefix in ("planner", "hybrid"):
            out[f"{prefix}.{key}"] = f"{flag}{sep}{key}"
            if isinstance(value, Mapping):
                out.update({f"{prefix}.{key}.{sub}": f"{flag}{sep}{key}.{sub}" for sub in value})
    return out


@contextmanager
def flags_for(fields: Mapping[str, str]) -> Iterator[None]:
    """Re-raise an InputError naming one of ``fields`` with its command-line flag instead.

    ``fields`` maps an API keyword (``lead_speed``) to its flag (``--lead-speed``).
    """
    try:
        yield
    except InputError as exc:
        if (text := _flagged(str(exc), fields)) is not None:
            raise InputError(text) from None
        raise


@contextmanager
def flags_for_warnings(fields: Mapping[str, str]) -> Iterator[None]:
    """Re-issue each :class:`InputWarning` naming one of ``fields`` with its flag instead.

    The warnings' twin of :func:`flags_for`: ``goal: yaw 90 is more than a full turn``
    about a ``--goal`` value reads ``--goal: yaw 90 ...``. Other warnings pass unchanged.
    """
    caught: list[warnings.WarningMessage] = []
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            yield
    finally:  # also when the block raises: a warning before an error is still shown
        for w in caught:
            text = str(w.message)
            if issubclass(w.category, InputWarning):
                text = _flagged(text, fields) or text
            warnings.warn_explicit(text, w.category, w.filename, w.lineno)


def validate_output(
    target: str | None, flag: str, suffixes: Collection[str] = (), allow_stdout: bool = True
) -> None:
    """Raise :class:`InputError` naming ``flag`` unless ``target`` can be written.

    Checked before any work is done: the suffix (one of ``suffixes`` when given), an
    existing, writable folder, and that the target is not itself a folder. ``None``
    (the option not given) and ``"-"`` (stdout, when ``allow_stdout``) pass; a device or
    named pipe (``/dev/null``) passes when writable, and is written into, not replaced.
    """
    if target is None:
        return
    if target == "-":
        if allow_stdout:
            return
        raise InputError(f"{flag}: needs a file name, not '-'")
    if not target:
        raise InputError(f"{flag}: needs a file name, got an empty one")
    if target.endswith(("/", os.sep)):
        # Path() drops the slash: 'out.png/' wrote the file out.png.
        raise InputError(f"{flag}: {target!r} ends in a slash (a folder); name a file")
    out = Path(target)
    if suffixes and out.suffix.lower() not in suffixes:
        want = " or ".join(sorted(s for s in suffixes if s))
        if out.name.lower() in suffixes:  # '.mp4' alone: a hidden file without a suffix
            raise InputError(
                f"{flag}: {target!r} is a suffix without a name; name the file, e.g. "
                f"'run{out.name.lower()}'"
            )
        raise InputError(f"{flag}: the file must end in {want}, got {target!r}")
    if is_stream(out):  # /dev/null, a named pipe: written into, not replaced
        if not os.access(out, os.W_OK):
            raise InputError(f"{flag}: cannot write {target!r} (permission denied)")
        return
    out = destination(out)  # through a symbolic link, the file it points to
    parent = out.parent if str(out.parent) else Path(".")
    if not parent.is_dir():
        if parent.exists():
            raise InputError(f"{flag}: {str(parent)!r} is a file, not a folder")
        raise InputError(f"{flag}: folder {str(parent)!r} does not exist")
    if out.is_dir():
        raise InputError(f"{flag}: {target!r} is a folder")
    if out.exists() and not os.access(out, os.W_OK):
        raise InputError(f"{flag}: cannot write {target!r} (permission denied)")
    # The folder's mode bits do not tell (root, read-only mounts): try a file beside it.
    try:
        temp_beside(out).unlink()
    except OSError as exc:
        raise InputError(
            f"{flag}: cannot write into folder {str(parent)!r}: {exc.strerror}"
        ) from None


def parse_pose(text: str, name: str) -> Pose:
    """Parse ``"x,y,yaw"`` (yaw in radians) into a :class:`Pose`, naming ``name`` in errors.

    Parameters
    ----------
    text : str
        The option's value.
    name : str
        The option (``"--start"``), named in errors.

    Returns
    -------
    Pose

    Examples
    --------
    >>> parse_pose("-5,6,0", "--start")
    Pose(x=-5.0, y=6.0, yaw=0.0)
    >>> parse_pose("", "--start")
    Traceback (most recent call last):
    ...
    rrtdrive.types.InputError: --start: expected X,Y,YAW, got an empty value
    """
    if not text.strip():  # "--start=" (e.g. an unset shell variable): never "not given"
        raise InputError(f"{name}: expected X,Y,YAW, got an empty value")
    parts = text.split(",")
    # "_" too: Python's float reads "9_2" as 92, a typo no user means as a number.
    if len(parts) != 3 or "_" in text:
        raise InputError(f"{name}: expected three numbers x,y,yaw, got {text!r}")
    try:
        values = [float(p) for p in parts]
    except ValueError:
        raise InputError(f"{name}: expected three numbers x,y,yaw, got {text!r}") from None
    return Pose.from_seq(values, name)


def map_with_poses(
    spec: str,
    start: Pose | None,
    goal: Pose | None,
    names: Mapping[str, str] | None = None,
    plan_car: VehicleParams | None = None,
) -> Map:
    """The map ``spec`` with ``--start``/``--goal`` (when given) replacing its poses.

    ``plan_car``: the car of the plan the poses come from (``simulate --path``), which
    replaces the map's (:func:`~rrtdrive.plan_file.with_plan_car`: a warning naming
    SCENARIO when the map file's own car is another); the poses are checked for it.

    The file is read first, so a malformed start in it is named ``start:`` even when
    ``--start`` replaces it; the poses used are then checked, one given on the command
    line named by its flag (``--goal: (200, 44) lies outside the bounds ...``), or by
    ``names[field]`` where the poses came from elsewhere (``simulate --path``: the path's
    first and last rows).
    """
    from rrtdrive.map_checks import check_endpoint
    from rrtdrive.maps import resolve_map
    from rrtdrive.plan_file import with_plan_car

    names = names or {"start": "--start", "goal": "--goal"}
    flags = {k: names[k] for k, v in (("start", start), ("goal", goal)) if v is not None}
    with flags_for_warnings(flags):  # a given yaw that looks like degrees: named by its flag
        m = resolve_map(spec, start=start, goal=goal, check_query=False)
    m = with_plan_car(m, plan_car, "SCENARIO")
    with flags_for(flags):
        for label, pose in (("start", m.start), ("goal", m.goal)):
            check_endpoint(m, pose, label, m.vehicle, warn_degrees=False)
    return m


def write_output(target: str, text: str) -> None:
    """Write a command's ``--json`` text to ``target``: stdout for ``-``, else a file, atomically.

    A file is written to a temporary file beside it, then renamed into place (a failed
    write leaves none behind and raises :class:`OutputError` naming ``--json``).
    """
    if target == "-":
        sys.stdout.write(text)
        sys.stdout.flush()
    else:
        from rrtdrive.maps import write_text_atomic

        with writing("--json", target):
            write_text_atomic(target, text)
