"""Maps: bounds, oriented rectangular obstacles, a start and a goal pose.

The JSON format (SPEC §2)::

    {"name": "parking_lot", "bounds": [0, 0, 100, 100],
     "obstacles": [{"center": [50.0, 20.0], "size": [4.3, 1.8], "yaw": 0.0}],
     "start": [5.0, 5.0, 0.0], "goal": [90.0, 80.0, 1.5708]}

and optionally the car, ``"vehicle": {"length": 5.0, "wheelbase": 3.0, ...}``
(:mod:`rrtdrive.vehicle_json`; a field left out is the paper's car's). Loading
validates every field and names the offending one in an :class:`~rrtdrive.types.InputError`.
"""

from __future__ import annotations

import dataclasses
import functools
import json
import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path as FsPath

import numpy as np
import shapely

from rrtdrive.atomic import write_text_atomic
from rrtdrive.json_input import json_kind, parse_json, read_json_file
from rrtdrive.map_checks import (
    MAX_COORDINATE,
    MAX_YAW,
    check_endpoint,
    check_name,
    warn_if_degrees,
    warn_obstacle_yaws,
    warn_outside,
)
from rrtdrive.obstacles import Obstacle
from rrtdrive.parking_layout import parking_goal_pose, parking_lot_obstacles
from rrtdrive.types import (
    InputError,
    Pose,
    VehicleParams,
    brief_repr,
    require_finite,
)
from rrtdrive.values import did_you_mean
from rrtdrive.vehicle_json import vehicle_from_json, vehicle_to_json

__all__ = [
    "Obstacle",
    "Map",
    "BUILTIN_MAPS",
    "TIGHT_MAP_NAMES",
    "builtin_map",
    "load_map",
    "parse_json",
    "save_map",
    "map_text",
    "resolve_map",
    "names_map_file",
    "check_endpoint",
    "warn_if_degrees",
    "MAX_COORDINATE",
    "MAX_YAW",
]


@dataclass(frozen=True)
class Map:
    """A planning map: the region, its obstacles and one start/goal query.

    Construction validates the start and goal against ``vehicle``: each must lie within the bounds
    and the car's body there must be clear of every obstacle and inside the bounds.

    Parameters
    ----------
    name : str
        Map name.
    bounds : tuple of float
        ``(xmin, ymin, xmax, ymax)``; outside counts as an obstacle.
    obstacles : tuple of Obstacle
        Oriented rectangles.
    start, goal : Pose
        Rear-axle poses.
    vehicle : VehicleParams
        The car: the start and goal footprints are validated for it, and planners,
        controllers and evaluators take it from the map. A map file keeps it when it
        is not the paper's car.
    check_query : bool
        Validate the start and goal (default). ``False`` for a map that only carries
        the poses a given path is judged against (``rrtdrive verify``: a path from a
        pose in collision fails its body check there, it is not bad input). Copies
        (:meth:`with_query`, ``dataclasses.replace``) validate again.
    """

    name: str
    bounds: tuple[float, float, float, float]
    obstacles: tuple[Obstacle, ...]
    start: Pose
    goal: Pose
    vehicle: VehicleParams = dataclasses.field(default_factory=VehicleParams)
    check_query: dataclasses.InitVar[bool] = True

    def __post_init__(self, check_query: bool = True) -> None:
        check_name(self.name)
        b = self.bounds
        if isinstance(b, np.ndarray) and b.ndim == 1:
            b = tuple(b.tolist())  # four numbers from numpy, as Obstacle and Pose take them
        if not isinstance(b, (list, tuple)) or len(b) != 4:
            raise InputError(
                f"bounds: expected [xmin, ymin, xmax, ymax], got {brief_repr(b)}"
            )
        require_finite("bounds", *b)
        b = (float(b[0]), float(b[1]), float(b[2]), float(b[3]))
        # (A map itself that large is refused by the checker's grid limit, which says
        # what to do about its size.)
        if max(abs(v) for v in b) > MAX_COORDINATE >= max(b[2] - b[0], b[3] - b[1]):
            raise InputError(
                f"bounds: {list(b)} reaches beyond {MAX_COORDINATE:g} m from the origin, "
                "where a double keeps less than the micrometre paths are checked to; move "
                "the map's origin near the map"
            )
        if b[2] <= b[0] or b[3] <= b[1]:
            raise InputError(f"bounds: need xmin < xmax and ymin < ymax, got {list(b)}")
        object.__setattr__(self, "bounds", b)
        if isinstance(self.obstacles, (str, bytes)) or not isinstance(
            self.obstacles, (list, tuple)
        ):
            raise InputError(
                f"obstacles: expected a list of Obstacle, got {type(self.obstacles).__name__}"
            )
        object.__setattr__(self, "obstacles", tuple(self.obstacles))
        for i, o in enumerate(self.obstacles):
            if not isinstance(o, Obstacle):
                raise InputError(
                    f"obstacles[{i}]: expected an Obstacle((x, y), (length, width), yaw), "
                    f"got {brief_repr(o)}"
                )
        if not isinstance(self.vehicle, VehicleParams):
            raise InputError(
                f"vehicle: expected a VehicleParams, got {type(self.vehicle).__name__}"
            )
        for label, pose in (("start", self.start), ("goal", self.goal)):
            if not isinstance(pose, Pose):
                raise InputError(f"{label}: expected a Pose, got {pose!r}")
            if check_query:
                check_endpoint(self, pose, label, self.vehicle)
            else:
                warn_if_degrees(label, pose.yaw)

    def __repr__(self) -> str:
        # Printed in full, the obstacles ran to ~10 k characters (parking_lot's 100).
        car = "" if self.vehicle == VehicleParams() else f", vehicle={self.vehicle}"
        return (f"Map({self.name!r}, bounds={self.bounds}, {len(self.obstacles)} obstacles, "
                f"start={self.start}, goal={self.goal}{car})")  # fmt: skip

    @property
    def width(self) -> float:
        """Extent along x in metres."""
        return self.bounds[2] - self.bounds[0]

    @property
    def height(self) -> float:
        """Extent along y in metres."""
        return self.bounds[3] - self.bounds[1]

    def with_query(self, start: Pose | None = None, goal: Pose | None = None) -> Map:
        """A copy with another start and/or goal (validated).

        Parameters
        ----------
        start, goal : Pose, optional
            The new poses; None keeps the map's own.

        Returns
        -------
        Map
        """
        return dataclasses.replace(
            self,
            start=start if start is not None else self.start,
            goal=goal if goal is not None else self.goal,
        )

    def obstacle_union(self) -> shapely.Geometry:
        """All obstacles as one shapely geometry (empty if none)."""
        return shapely.union_all([o.polygon() for o in self.obstacles])

    def to_json(self) -> dict[str, object]:
        """JSON-ready dict in the map file format (``vehicle`` when not the paper's car)."""
        doc: dict[str, object] = {
            "name": self.name,
            "bounds": list(self.bounds),
            "obstacles": [o.to_json() for o in self.obstacles],
            "start": list(self.start.as_tuple()),
            "goal": list(self.goal.as_tuple()),
        }
        if self.vehicle != VehicleParams():  # the files of the paper's car stay as they were
            doc["vehicle"] = vehicle_to_json(self.vehicle)
        return doc


# ----------------------------------------------------------------------------- JSON

_MAP_KEYS = {"name", "bounds", "obstacles", "start", "goal", "vehicle"}
_OBSTACLE_KEYS = {"center", "size", "yaw"}
_RECTANGLES = "obstacles are rectangles: center [x, y], size [length, width], yaw (radians)"


def map_from_json(
    data: object,
    vehicle: VehicleParams | None = None,
    *,
    start: Pose | None = None,
    goal: Pose | None = None,
    check_query: bool = True,
) -> Map:
    """Build a :class:`Map` from parsed JSON, validating every field.

    Parameters
    ----------
    data : object
        Parsed JSON (a dict in the map file format).
    vehicle : VehicleParams, optional
        The car, instead of the file's ``vehicle`` (default: the file's, else the
        paper's car).
    start, goal : Pose, optional
        Poses that replace the file's (``--start`` / ``--goal``): the file's own must
        still be well-formed, but only the poses used are checked against the map.
    check_query : bool
        Check the start and goal against the map (see :class:`Map`).

    Returns
    -------
    Map
    """
    if not isinstance(data, dict):
        raise InputError(f"map: expected a JSON object, got {json_kind(data)}")
    unknown = set(data) - _MAP_KEYS
    if unknown:
        raise InputError(f"map: unknown key(s) {sorted(unknown)}; allowed {sorted(_MAP_KEYS)}")
    missing = {"bounds", "start", "goal"} - set(data)
    if missing:
        raise InputError(f"map: missing key(s) {sorted(missing)}")
    raw_obstacles = data.get("obstacles", [])
    if not isinstance(raw_obstacles, list):
        raise InputError("obstacles: expected a list")
    obstacles = []
    for i, item in enumerate(raw_obstacles):
        if not isinstance(item, dict):
            got = brief_repr(item)
            raise InputError(f"obstacles[{i}]: expected an object, got {got}; {_RECTANGLES}")
        bad = set(item) - _OBSTACLE_KEYS
        if bad:
            raise InputError(f"obstacles[{i}]: unknown key(s) {sorted(bad)}; {_RECTANGLES}")
        if "center" not in item or "size" not in item:
            raise InputError(f"obstacles[{i}]: needs 'center' and 'size'; {_RECTANGLES}")
        try:
            obstacles.append(Obstacle(item["center"], item["size"], item.get("yaw", 0.0)))
        except InputError as exc:
            # The Obstacle names its own fields "obstacle.center" ...; here the file's
            # path to the field is "obstacles[i].center".
            field = str(exc).removeprefix("obstacle.")
            raise InputError(f"obstacles[{i}].{field}") from None
    name = data.get("name", "map")
    if not isinstance(name, str):
        raise InputError(f"name: expected a non-empty string, got {brief_repr(name)}")
    if data.get("vehicle") is not None:  # checked even when ``vehicle`` replaces it
        own = vehicle_from_json(data["vehicle"])
        vehicle = own if vehicle is None else vehicle
    warn_obstacle_yaws([o.yaw for o in obstacles])
    file_start = Pose.from_seq(data["start"], "start")
    file_goal = Pose.from_seq(data["goal"], "goal")
    m = Map(
        name=name,
        bounds=data["bounds"],
        obstacles=tuple(obstacles),
        start=start if start is not None else file_start,
        goal=goal if goal is not None else file_goal,
        vehicle=vehicle or VehicleParams(),
        check_query=check_query,
    )
    warn_outside(m)
    return m


def load_map(
    path: str | os.PathLike[str],
    vehicle: VehicleParams | None = None,
    *,
    start: Pose | None = None,
    goal: Pose | None = None,
    check_query: bool = True,
) -> Map:
    """Load and validate a map file.

    Parameters
    ----------
    path : str or os.PathLike
        A JSON file in the map format.
    vehicle : VehicleParams, optional
        The car, instead of the file's (as for :func:`map_from_json`).
    start, goal, check_query
        As for :func:`map_from_json`: poses that replace the file's, and whether the
        poses used are checked against the map.

    Returns
    -------
    Map
    """
    data = read_json_file(path, "map")
    if isinstance(data, dict) and "path" in data and "status" in data:
        # A plan where a map is wanted: its 27 keys listed as unknown said nothing useful.
        raise InputError(
            f"map: {os.fspath(path)!r} is a plan (the JSON of rrtdrive plan), not a map; "
            "give the map it was planned on (a built-in name or its map file)"
        )
    return map_from_json(data, vehicle, start=start, goal=goal, check_query=check_query)


def map_text(m: Map) -> str:
    """``m`` in the map file format, as :func:`save_map` writes it.

    Parameters
    ----------
    m : Map
        The map (its name, bounds, obstacles, start and goal; its car when not the
        paper's).

    Returns
    -------
    str
        Indented JSON ending in a newline.
    """
    return json.dumps(m.to_json(), indent=2) + "\n"


def save_map(m: Map, path: str | os.PathLike[str]) -> None:
    """Write ``m`` as JSON atomically (temporary file, then rename).

    Parameters
    ----------
    m : Map
        The map (its name, bounds, obstacles, start and goal; its car when not the
        paper's).
    path : str or os.PathLike
        The file to write; :func:`load_map` reads it back.
    """
    write_text_atomic(path, map_text(m))


# ----------------------------------------------------------------------------- built-ins

#: Width of a highway-env lane, used by the overtake road so the scene matches.
LANE_WIDTH = 4.0


def overtake_map() -> Map:
    """A straight two-lane road along x with its edges as walls and a stopped car in the ego lane.

    The road spans y in [42, 50]: the ego lane is centred on y = 44, the
    oncoming lane on y = 48. The stopped car's body is centred at (50, 44).
    """
    road_low, road_high = 42.0, 42.0 + 2 * LANE_WIDTH
    ego_lane = road_low + LANE_WIDTH / 2
    edge = 1.0
    obstacles = (
        Obstacle((50.0, road_low - edge / 2), (100.0, edge)),
        Obstacle((50.0, road_high + edge / 2), (100.0, edge)),
        Obstacle((50.0, ego_lane), (4.3, 1.8)),
    )
    return Map(
        "overtake",
        (0.0, 0.0, 100.0, 100.0),
        obstacles,
        Pose(5.0, ego_lane, 0.0),
        Pose(92.0, ego_lane, 0.0),
    )


def parking_lot_map() -> Map:
    """Three double rows of parked cars, solid blocks, aisles; the goal far from the entrance.

    The entrance is at the bottom-left (start heading +x); the goal is an empty
    nose-in spot on the upper side of the top row, near the right end
    (:mod:`rrtdrive.parking_layout` lays it out).
    """
    return Map(
        "parking_lot",
        (0.0, 0.0, 100.0, 100.0),
        parking_lot_obstacles(),
        Pose(5.0, 6.0, 0.0),
        parking_goal_pose(2, 1, 19),
    )


def narrow_gap_map() -> Map:
    """A wall across the map with one passage 2.8 m wide (the car is 1.8 m wide)."""
    gap, y_gap, thickness = 2.8, 50.0, 2.0
    low_len = y_gap - gap / 2
    high_len = 100.0 - (y_gap + gap / 2)
    obstacles = (
        Obstacle((50.0, low_len / 2), (thickness, low_len)),
        Obstacle((50.0, 100.0 - high_len / 2), (thickness, high_len)),
    )
    return Map(
        "narrow_gap",
        (0.0, 0.0, 100.0, 100.0),
        obstacles,
        Pose(10.0, 20.0, 0.0),
        Pose(85.0, 80.0, 0.0),
    )


def no_path_map() -> Map:
    """The goal sits inside a closed ring of walls: no path exists."""
    obstacles = (
        Obstacle((77.5, 65.0), (27.0, 2.0)),
        Obstacle((77.5, 90.0), (27.0, 2.0)),
        Obstacle((65.0, 77.5), (2.0, 27.0)),
        Obstacle((90.0, 77.5), (2.0, 27.0)),
    )
    return Map(
        "no_path",
        (0.0, 0.0, 100.0, 100.0),
        obstacles,
        Pose(10.0, 10.0, 0.0),
        Pose(75.0, 77.5, 0.0),
    )


BUILTIN_MAPS: dict[str, Callable[[], Map]] = {
    "overtake": overtake_map,
    "parking_lot": parking_lot_map,
    "narrow_gap": narrow_gap_map,
    "no_path": no_path_map,
}

#: Tight maps shipped as files in ``data/maps/`` (:mod:`rrtdrive.tight_maps` writes them).
TIGHT_MAP_NAMES = ("garage", "turning_bulb", "kerbside", "reverse_bay", "dead_end")
_DATA_MAPS = FsPath(__file__).resolve().parent / "data" / "maps"


def _shipped(name: str) -> Callable[[], Map]:
    def load() -> Map:
        return load_map(_DATA_MAPS / f"{name}.json")

    return load


BUILTIN_MAPS.update({name: _shipped(name) for name in TIGHT_MAP_NAMES})


def builtin_map(name: str) -> Map:
    """Return the built-in map called ``name`` (built once; maps are immutable).

    Parameters
    ----------
    name : str
        One of :data:`BUILTIN_MAPS` (``rrtdrive maps`` lists them).

    Returns
    -------
    Map

    Raises
    ------
    InputError
        For an unknown name, naming ``map`` and the built-ins.

    Examples
    --------
    >>> builtin_map("overtake").start
    Pose(x=5.0, y=44.0, yaw=0.0)
    """
    factory = BUILTIN_MAPS.get(name) if isinstance(name, str) else None
    if factory is None:
        raise InputError(
            f"map: unknown map {name!r}{did_you_mean(name, BUILTIN_MAPS)}; built-ins are "
            f"{', '.join(sorted(BUILTIN_MAPS))} or give a .json file"
        )
    return _built_map(name, factory)


@functools.lru_cache(maxsize=64)
def _built_map(name: str, factory: Callable[[], Map]) -> Map:
    # A Map is immutable: one per name (and factory) serves every caller; building
    # parking_lot's 142 validated obstacles took milliseconds per call.
    return factory()


def names_map_file(spec: str) -> bool:
    """Whether ``spec`` names a map file (``.json``, a path, or a file that exists).

    :func:`resolve_map` reads such a name as a file, so its error is the file's.

    Parameters
    ----------
    spec : str
        What the user gave as the map (a built-in name or a path).

    Returns
    -------
    bool
    """
    return spec.endswith(".json") or os.path.sep in spec or FsPath(spec).exists()


def resolve_map(
    spec: str,
    vehicle: VehicleParams | None = None,
    *,
    start: Pose | None = None,
    goal: Pose | None = None,
    check_query: bool = True,
) -> Map:
    """A built-in map by name, or a map file by path.

    ``start`` and ``goal`` replace the map's own poses, and only the poses used are
    checked against it (unless ``check_query`` is false): a file whose own start is
    bad still serves with a good ``--start``.

    Parameters
    ----------
    spec : str
        A built-in map's name or the path of a map file (``.json``).
    vehicle : VehicleParams, optional
        The car the poses are checked for (default: the map's, or ``VehicleParams()``).
    start, goal : Pose, optional
        Poses replacing the map's own.
    check_query : bool
        Check the start and goal bodies (default); ``False`` for a map that only
        carries the poses a given path is judged against.

    Returns
    -------
    Map

    Raises
    ------
    InputError
        For an unknown name, an unreadable or malformed file, or a bad pose, naming the field.
    """
    if spec == "":  # an unset shell variable; as a path it is the current folder
        raise InputError("map: needs a built-in map name or a map .json file, got an empty one")
    if spec in BUILTIN_MAPS or not names_map_file(spec):
        m = builtin_map(spec)
        if vehicle is None and start is None and goal is None and check_query:
            return m
        return dataclasses.replace(
            m,
            vehicle=m.vehicle if vehicle is None else vehicle,
            start=m.start if start is None else start,
            goal=m.goal if goal is None else goal,
            check_query=check_query,
        )
    return load_map(spec, vehicle, start=start, goal=goal, check_query=check_query)
