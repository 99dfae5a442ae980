"""``rrtdrive maps``: list the built-in maps, ``--export`` them, ``--import`` an image."""

from __future__ import annotations

import argparse
import pathlib
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

from rrtdrive.cli_args import flags_for, nonneg_int, positive_float, validate_output, writing
from rrtdrive.types import InputError

if TYPE_CHECKING:
    from rrtdrive.maps import Map
    from rrtdrive.types import VehicleParams

__all__ = ["add_parser", "HELP"]

HELP = "list or export the built-in maps, import an occupancy image"


def add_parser(sub: Any) -> argparse.ArgumentParser:
    """Add ``maps`` to an argparse subparsers object and return its parser."""
    maps = sub.add_parser(
        "maps",
        help=HELP,
        description="List the built-in maps; --export writes them as JSON files; --import "
        "makes a map file from an occupancy image (a ROS map_server .yaml and its image, or "
        "a PNG/PGM with --resolution). Exit 0 when done, 1 when an output could not be "
        "written, 2 on bad input; 130 on Ctrl-C, 143 on SIGTERM.",
    )
    maps.add_argument(
        "--export", metavar="DIR",
        help="write each built-in map to DIR/NAME.json (DIR is created if missing)",
    )
    imp = maps.add_argument_group("import an occupancy image (--import)")
    imp.add_argument(
        "--import", dest="import_from", metavar="MAP.yaml|IMAGE",
        help="a ROS map_server map (.yaml naming its image, resolution, origin, thresholds) "
        "or an image (.png, .pgm, ...: dark is occupied); occupied and unknown cells become "
        "rectangles; needs --start, --goal and --out",
    )
    imp.add_argument("--start", metavar="X,Y,YAW", help="the map's rear-axle start pose")
    imp.add_argument("--goal", metavar="X,Y,YAW", help="the map's rear-axle goal pose")
    imp.add_argument("--out", metavar="FILE.json", help="the map file to write")
    imp.add_argument("--name", metavar="NAME",
                     help="the map's name (default: the file name without its suffix)")
    imp.add_argument("--resolution", type=positive_float, metavar="M",
                     help="an image: metres per pixel (a .yaml gives its own)")
    imp.add_argument("--origin", metavar="X,Y",
                     help="an image: its lower left corner in metres (default 0,0)")
    imp.add_argument("--negate", action="store_true",
                     help="an image: light is occupied, dark free (ROS's negate: 1; a .yaml "
                     "gives its own)")
    imp.add_argument("--unknown-free", action="store_true",
                     help="read the cells between ROS's thresholds (grey, unknown) as free; "
                     "by default they are obstacles")
    imp.add_argument("--vehicle", metavar="JSON|FILE.json",
                     help="the map's car, when not the paper's: a vehicle object "
                     "('{\"length\": 2.5, \"width\": 1.2, \"wheelbase\": 1.6, "
                     "\"min_turning_radius\": 3}', fields left out are the paper's car's) "
                     "or a JSON file holding one or a map file with one; the start and goal "
                     "are checked for it and the map file keeps it")
    imp.add_argument("--despeckle", type=nonneg_int, metavar="N",
                     help="drop groups of at most N occupied cells (touching, corners "
                     "included): a scan's noise; a post or kerb stone that small goes too "
                     "(default: keep every cell)")
    maps.set_defaults(func=_cmd_maps)
    return maps


#: The flags that only an import takes.
IMPORT_FLAGS = (("start", "--start"), ("goal", "--goal"), ("out", "--out"), ("name", "--name"),
                ("resolution", "--resolution"), ("origin", "--origin"), ("negate", "--negate"),
                ("unknown_free", "--unknown-free"), ("despeckle", "--despeckle"),
                ("vehicle", "--vehicle"))  # fmt: skip


def _cmd_import(args: argparse.Namespace) -> int:
    """``rrtdrive maps --import``: write the map of an occupancy image; return the exit code."""
    from rrtdrive.cli_args import distinct_outputs, parse_pose
    from rrtdrive.maps import save_map
    from rrtdrive.occupancy import despeckle, map_from_image, read_image_map, read_ros_map

    source = args.import_from
    if args.export is not None:
        raise InputError("--export: writes the built-in maps; --import makes one map, to --out")
    for attr, flag in (("start", "--start"), ("goal", "--goal"), ("out", "--out")):
        if getattr(args, attr) is None:
            raise InputError(f"{flag}: --import needs it (a map file has a start, a goal)")
    validate_output(args.out, "--out", (".json",), allow_stdout=False)
    distinct_outputs({"--import": source}, out=args.out)
    start, goal = parse_pose(args.start, "--start"), parse_pose(args.goal, "--goal")
    car = _vehicle_arg(args.vehicle)  # before the image is read: bad input first
    is_yaml = source.lower().endswith((".yaml", ".yml"))
    if is_yaml:
        for attr, flag in (("resolution", "--resolution"), ("origin", "--origin"),
                           ("negate", "--negate")):  # fmt: skip
            if getattr(args, attr, None) not in (None, False):
                raise InputError(f"{flag}: the .yaml gives it; only an image takes {flag}")
        with flags_for({"map": "--import"}):
            grid = read_ros_map(source, args.unknown_free)
    else:
        if args.resolution is None:
            raise InputError("--resolution: an image needs its metres per pixel (e.g. 0.05)")
        origin = (0.0, 0.0)
        if args.origin is not None:
            parts = args.origin.split(",")
            try:
                origin = (float(parts[0]), float(parts[1]))
                # "_" too, as parse_pose: float reads "1_0" as 10, a typo, not a number.
                if len(parts) != 2 or "_" in args.origin:
                    raise ValueError
            except (ValueError, IndexError):
                raise InputError(f"--origin: expected X,Y in metres, got {args.origin!r}") from None
        with flags_for({"image": "--import", "resolution": "--resolution", "origin": "--origin"}):
            grid = read_image_map(source, args.resolution, origin,
                                  negate=getattr(args, "negate", False),
                                  unknown_free=args.unknown_free)  # fmt: skip
    groups, cells = 0, 0
    if args.despeckle:
        grid, groups, cells = despeckle(grid, args.despeckle)
    name = args.name if args.name is not None else pathlib.Path(source).stem
    try:
        # A name taken from the file is the file's fault, not a --name never given (an
        # image named with a tab was blamed on --name; an audit).
        named = "--name" if args.name is not None else "the image's file name (give --name)"
        with flags_for({"start": "--start", "goal": "--goal", "name": named}):
            m = map_from_image(grid, name, start, goal, car)
    except InputError as exc:
        hint = None if args.unknown_free else _unknown_hint(grid, str(exc), start, goal, car)
        if hint is None and not is_yaml and not getattr(args, "negate", False):
            hint = _dark_floor_hint(grid, str(exc))
        if car is None and "the car's body" in str(exc):  # whose body (an audit)
            hint = (f"{hint}; " if hint else "") + (
                "the car is the paper's, 4.3 x 1.8 m: --vehicle gives another")
        if hint:
            raise InputError(f"{exc} ({hint})") from None
        raise
    with writing("--out", args.out):
        save_map(m, args.out)
    rows, cols = grid.occupied.shape
    xmin, ymin, xmax, ymax = m.bounds
    print(
        f"{source}: {cols} x {rows} cells at {grid.resolution:g} m, {xmax - xmin:g} x "
        f"{ymax - ymin:g} m; {int(grid.occupied.sum())} occupied cells ({grid.unknown} unknown, "
        f"read as {'free' if args.unknown_free else 'occupied'}) as {len(m.obstacles)} "
        f"rectangle{'' if len(m.obstacles) == 1 else 's'}"
        + (f" ({groups} specks of <= {args.despeckle} cells dropped: {cells} cells)"
           if args.despeckle else "")
        + f" -> {args.out}"
        # Thousands of rectangles: a scan's noise, which slows every query's set-up.
        + (" (many: if they are a scan's noise, --despeckle N drops them)"
           if len(m.obstacles) > 5000 and not args.despeckle else "")
    )  # fmt: skip
    return 0



def _vehicle_arg(text: str | None) -> VehicleParams | None:
    """``--vehicle``: a vehicle object, or a JSON file of one or of a map holding one."""
    from rrtdrive.json_input import parse_json, read_json_file
    from rrtdrive.vehicle_json import vehicle_from_json

    if text is None:
        return None
    if not text.strip():
        raise InputError("--vehicle: needs a vehicle object or a JSON file, got an empty one")
    if text.lstrip()[:1] in ("{", "["):
        data = parse_json(text, "--vehicle", "the value given")
    else:
        data = read_json_file(text, "--vehicle")
        if isinstance(data, dict) and "bounds" in data and data.get("vehicle") is None:
            return None  # a map file of the paper's car (save_map writes no vehicle)
    if isinstance(data, dict) and isinstance(data.get("vehicle"), dict):
        data = data["vehicle"]  # a map file's, a plan's, or {"vehicle": {...}}
    try:
        return vehicle_from_json(data, "vehicle")
    except InputError as exc:
        raise InputError(f"--vehicle: {str(exc).removeprefix('vehicle: ')}") from None


def _cmd_maps(args: argparse.Namespace) -> int:
    from rrtdrive.maps import BUILTIN_MAPS, builtin_map

    if getattr(args, "import_from", None) is not None:
        return _cmd_import(args)
    for attr, flag in IMPORT_FLAGS:
        if getattr(args, attr, None) not in (None, False):
            raise InputError(f"{flag}: only with --import (it describes the map imported)")
    maps = {name: builtin_map(name) for name in BUILTIN_MAPS}
    out = None if args.export is None else _export_folder(args.export, list(maps))
    if out is not None:
        _export(out, maps)
    for name, m in maps.items():
        line = (
            f"{name:12s} {len(m.obstacles):4d} obstacles  start {m.start.as_tuple()}  goal "
            + str(tuple(round(v, 3) for v in m.goal.as_tuple()))
        )
        if out is not None:
            line += f"  -> {out / f'{name}.json'}"
        print(line)
    return 0


def _export(out: pathlib.Path, maps: dict[str, Map]) -> None:
    """Write every map to ``out/NAME.json``: all of them, or (a full disk) none.

    Each is written to a temporary file first; only when all are complete are they
    renamed into place, so a write that fails leaves the folder as it was.
    """
    from rrtdrive.atomic import publish, temp_beside
    from rrtdrive.maps import map_text

    temps: dict[pathlib.Path, pathlib.Path] = {}
    try:
        for name, m in maps.items():
            target = out / f"{name}.json"
            with writing("--export", target):
                temps[target] = temp_beside(target)
                temps[target].write_text(map_text(m), "utf-8")
        for target, tmp in temps.items():
            with writing("--export", target):
                publish(tmp, target)
    finally:
        for tmp in temps.values():
            tmp.unlink(missing_ok=True)


def _export_folder(text: str, names: Sequence[str]) -> pathlib.Path:
    """The ``--export`` folder, created, with every ``NAME.json`` in it checked writable.

    Checked before the first file is written, so a bad target leaves no partial export.
    """
    if not text.strip():
        raise InputError("--export: expected a folder, got an empty value")
    if text == "-":  # stdout elsewhere; a folder named "-" surprised (an audit)
        raise InputError("--export: writes one file per map into a folder, not stdout: "
                         "name a folder (rrtdrive maps --export DIR)")
    out = pathlib.Path(text)
    if out.exists() and not out.is_dir():
        raise InputError(f"--export: {out} is a file; give a folder (it is created if missing)")
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InputError(f"--export: cannot create folder {out}: {exc.strerror}") from None
    for name in names:
        validate_output(str(out / f"{name}.json"), "--export")
    return out


def _unknown_hint(
    grid: Any, error: str, start: Any, goal: Any, car: VehicleParams | None = None
) -> str | None:
    """Why a pose the image refuses may lie on unknown cells, or None when it does not."""
    from rrtdrive.occupancy import unknown_cells_under
    from rrtdrive.vehicle import VehicleParams, footprint_polygon

    flag = error.split(":", 1)[0]
    if flag not in ("--start", "--goal"):
        return None
    pose = start if flag == "--start" else goal
    # A transparent background (matplotlib's transparent=True) reads as unknown: the
    # whole image becomes one obstacle and the pose "overlaps" it, unexplained. A pose on
    # a dark cell alone gets no such hint (it said "0% ... unknown"; an audit).
    body = footprint_polygon((pose.x, pose.y, pose.yaw), car or VehicleParams())  # the Map's
    under = unknown_cells_under(grid, body)
    if not under:
        return None
    share = grid.unknown / grid.occupied.size
    return (
        f"{under} cell{'' if under == 1 else 's'} under the car's body and {share:.0%} of the "
        "image read as unknown, between the free and occupied thresholds, and count as "
        "occupied: a grey or transparent background reads so; --unknown-free reads them "
        "as free"
    )


def _dark_floor_hint(grid: Any, error: str) -> str | None:
    """For a pose refused on an image mostly occupied: its floor may be the dark part."""
    if not error.startswith(("--start", "--goal")):
        return None
    share = float(grid.occupied.mean())
    if share <= 0.5:
        return None
    # Dark is occupied (map_server's default): a plot with a black floor and white
    # walls becomes one big obstacle; ROS's negate reads it the other way round.
    return (
        f"{share:.0%} of the image reads as occupied: if its floor is the dark part, "
        "--negate reads light as occupied"
    )
