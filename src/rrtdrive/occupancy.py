"""Maps from occupancy images: a ROS ``map_server`` map (``.yaml`` + image) or a plain image.

A pixel's occupancy probability is ``(255 - v) / 255`` (``v / 255`` with ``negate``;
a colour pixel's ``v`` is the mean of its channels), as ROS ``map_server`` reads its
``trinary`` images: above ``occupied_thresh`` the cell is occupied, below
``free_thresh`` free, and in between unknown, which counts as occupied here unless
asked otherwise (a planner should not drive where nobody has looked). Occupied cells
become axis-aligned rectangles: each row's runs of occupied cells, merged down the
rows while a run keeps the same columns, so a wall is one rectangle, not a thousand.
The image's first row is its top: row ``r``, column ``c`` is the cell whose lower
left corner is ``origin + (c, rows - 1 - r) * resolution``.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import os
import warnings
from collections.abc import Hashable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from rrtdrive.map_checks import MAX_COORDINATE
from rrtdrive.types import (
    InputError,
    Pose,
    VehicleParams,
    brief_repr,
    is_finite_number,
    require_int,
)
from rrtdrive.values import one_line

if TYPE_CHECKING:
    import shapely

    from rrtdrive.maps import Map
    from rrtdrive.obstacles import Obstacle

__all__ = [
    "ImageMap", "read_image_map", "read_ros_map", "despeckle", "grid_rectangles",
    "image_obstacles", "map_from_image", "unknown_cells_under",
]


@dataclass(frozen=True, eq=False)
class ImageMap:
    """Occupied cells of an image and where they lie.

    Parameters
    ----------
    occupied : numpy.ndarray
        Bool ``(rows, cols)``, the image's first row at the top.
    resolution : float
        Cell side, metres.
    origin : tuple of float
        ``(x, y)`` of the lower left corner of the bottom left cell, metres.
    unknown : int
        Cells between the thresholds (counted in ``occupied`` unless read as free).
    unknown_cells : numpy.ndarray or None
        Bool ``(rows, cols)``: which cells those are, less any :func:`despeckle` dropped
        (``None``: not known).
    """

    occupied: np.ndarray
    resolution: float
    origin: tuple[float, float]
    unknown: int = 0
    unknown_cells: np.ndarray | None = None

    @property
    def bounds(self) -> tuple[float, float, float, float]:
        """The image's extent ``(xmin, ymin, xmax, ymax)`` in metres."""
        rows, cols = self.occupied.shape
        x0, y0 = self.origin
        return (x0, y0, x0 + cols * self.resolution, y0 + rows * self.resolution)


def _number(value: object, field: str, low: float, high: float, part: str = "") -> float:
    if not is_finite_number(value) or not low <= float(value) <= high:  # type: ignore[arg-type]
        # ``part`` names the element of a list field ("origin: y: ..."), after the field
        # so that flags_for still finds the field.
        raise InputError(f"{field}: {part + ': ' if part else ''}expected a number from "
                         f"{low:g} to {high:g}, got {brief_repr(value)}")  # fmt: skip
    return float(value)  # type: ignore[arg-type]


def read_image_map(
    image: str | os.PathLike[str],
    resolution: float,
    origin: tuple[float, float] = (0.0, 0.0),
    negate: bool = False,
    occupied_thresh: float = 0.65,
    free_thresh: float = 0.196,
    unknown_free: bool = False,
    mode: str = "trinary",
) -> ImageMap:
    """Read an occupancy image (PNG, PGM, ...) as ROS ``map_server`` reads a trinary map.

    A pixel's value is the mean of its channels. As map_server's ``image_loader``
    (ROS 1 and nav2) does, that mean takes in an alpha channel too in ``trinary``
    mode, and only the colour channels in ``scale`` mode.

    Parameters
    ----------
    image : str or os.PathLike
        The image file.
    resolution : float
        Metres per pixel (> 0).
    origin : tuple of float
        ``(x, y)`` of the image's lower left corner, metres.
    negate : bool
        White is occupied (ROS ``negate: 1``).
    occupied_thresh, free_thresh : float
        Occupancy probabilities above which a pixel is occupied and below which it is
        free (ROS's defaults, 0.65 and 0.196).
    unknown_free : bool
        Read the pixels in between as free (default: occupied).
    mode : str
        The ROS map's ``mode``, ``"trinary"`` (the default) or ``"scale"``: which
        channels a pixel's mean takes (both read the thresholds alike here).

    Returns
    -------
    ImageMap

    Raises
    ------
    InputError
        Naming the argument: a file that cannot be read as an image, a resolution or
        threshold out of range, ``free_thresh`` not below ``occupied_thresh``, an
        unknown ``mode``.
    """
    import imageio.v3 as iio
    import PIL.Image

    res = _number(resolution, "resolution", 1e-6, 1e3)
    occ = _number(occupied_thresh, "occupied_thresh", 0.0, 1.0)
    free = _number(free_thresh, "free_thresh", 0.0, 1.0)
    if free >= occ:
        raise InputError(f"free_thresh: must be below occupied_thresh ({occ:g}), got {free:g}")
    if mode not in ("trinary", "scale"):
        raise InputError(f"mode: only trinary and scale maps are read, got {brief_repr(mode)}")
    # As far out as a map's own coordinates may lie (a ROS map in UTM coordinates, a
    # northing about 5e6 m, was refused at 1e6; an audit).
    x0 = _number(origin[0], "origin", -MAX_COORDINATE, MAX_COORDINATE, "x")
    y0 = _number(origin[1], "origin", -MAX_COORDINATE, MAX_COORDINATE, "y")
    name = os.fspath(image)
    if not os.path.isfile(name):  # said as a missing .yaml is (an audit)
        why = "a folder, not a file" if os.path.isdir(name) else "No such file or directory"
        raise InputError(f"image: cannot read {name}: {why}")
    try:
        with warnings.catch_warnings():  # imageio's plugin probe warns about its DICOM one
            warnings.simplefilter("ignore", DeprecationWarning)
            warnings.simplefilter("ignore", PIL.Image.DecompressionBombWarning)  # sized below
            as_mode = _read_mode(name)
            # The first frame of a GIF or page of a TIFF (all of them read as one array:
            # a GIF was refused, a two-page TIFF read as two colour channels; an audit).
            raw = np.asarray(iio.imread(name, index=0, plugin="pillow", mode=as_mode))
    except InputError:
        raise
    except (OSError, ValueError, SyntaxError) as exc:  # pillow's and imageio's failures
        # imageio's own text runs to several lines of plugins to install: one line here.
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise InputError(
            f"image: cannot read {name} as an image (PNG, PGM, ...): {first}"
        ) from None
    # White is the type's largest value: 255, or 65535 for a 16-bit image. Pillow reads a
    # 16-bit PGM as int32, its values scaled to 0..65535 whatever its maxval (white read
    # 2**31 - 1 made every cell an obstacle; an audit); an 8-bit one with a maxval under
    # 255 comes scaled to 0..255.
    if raw.dtype == np.int32 and raw.size and 0 <= raw.min() and raw.max() <= 65535:
        scale = 65535.0
    elif np.issubdtype(raw.dtype, np.integer):
        scale = float(np.iinfo(raw.dtype).max)
    else:
        scale = 1.0
    pixels = raw.astype(float)
    see_through = np.zeros(pixels.shape[:2], dtype=bool)
    if pixels.ndim == 3:
        # map_server averages every channel in trinary mode, alpha too ("to preserve
        # existing behavior"); in scale mode it leaves alpha (a 2- or 4-channel image's
        # last) out of the mean, and a pixel not opaque is unknown ("any transparency
        # will be interpreted as unknown"; nav2's map_io: alpha != opaque).
        has_alpha = pixels.shape[2] in (2, 4)
        if mode == "scale" and has_alpha:
            see_through = pixels[..., -1] < scale
            pixels = pixels[..., :-1]
        pixels = pixels.mean(axis=2)
    if pixels.ndim != 2 or pixels.size == 0:
        raise InputError(f"image: expected a 2-D image, got shape {pixels.shape}")
    p = pixels / scale if negate else (scale - pixels) / scale
    occupied = (p > occ) & ~see_through
    unknown = ~occupied & (~(p < free) | see_through)
    return ImageMap(
        occupied | (unknown & (not unknown_free)), res, (x0, y0), int(unknown.sum()), unknown
    )


#: The most pixels an image may have: Pillow's own guard against decompression bombs
#: (a 10000 x 10000 image took 10 s and 2 GB to import; a larger one failed as "an
#: unknown error occurred while initializing plugin `pillow`"; an audit).
MAX_IMAGE_PIXELS = 89_478_485


def _read_mode(name: str) -> str | None:
    """The mode to read ``name``'s first frame in; refuse an image too large to read.

    A palette or grey image with a transparent colour (a PNG's tRNS chunk) is read as
    RGBA, so its transparency counts as in an RGBA picture (imageio read it as RGB,
    and a transparent background became free floor); a CMYK one as RGB (its four inks
    were averaged as R, G, B and alpha: white paper read as black). ``None``: as it is.
    """
    import PIL.Image

    limit, PIL.Image.MAX_IMAGE_PIXELS = PIL.Image.MAX_IMAGE_PIXELS, None  # the size first
    try:
        opened = PIL.Image.open(name)
    finally:
        PIL.Image.MAX_IMAGE_PIXELS = limit
    with opened as im:
        w, h = im.size
        if w * h > MAX_IMAGE_PIXELS:
            raise InputError(
                f"image: {name} has {w} x {h} = {w * h:,} pixels, more than the "
                f"{MAX_IMAGE_PIXELS:,} read; crop it or scale it down (and its resolution up)"
            )
        bits = getattr(im, "tag_v2", {}).get(258, (0,)) if im.format == "TIFF" else (0,)
        if im.mode == "F" or max(bits if isinstance(bits, tuple) else (bits,)) > 16:
            # map_server reads images through SDL_image, whose libtiff refuses samples
            # beyond 16 bits; there is no white to measure 32-bit values against (one
            # holding 0..255 was read against 65535: every cell occupied; an audit).
            kind = "floating-point" if im.mode == "F" else "32-bit"
            raise InputError(
                f"image: {name} has {kind} samples; occupancy images are 8- or 16-bit: "
                "save it as an 8-bit grayscale PNG or PGM"
            )
        if im.mode == "CMYK":
            return "RGB"
        if im.mode in ("P", "L", "RGB") and "transparency" in im.info:
            return "RGBA"
    return None


def _unquoted(value: object) -> object:
    """A quoted number as the number (``"0.05"``, ``"1"``); anything else as it is."""
    if isinstance(value, str):
        try:
            number = float(value)
        except ValueError:
            return value
        return int(number) if number.is_integer() and value.strip().isdigit() else number
    return value


def _yaml_why(exc: Exception) -> str:
    """A YAML error in one line: PyYAML's problem and where, as JSON's and TOML's read.

    PyYAML's own message runs over 3-4 lines, the offending text and a caret among them.
    """
    problem, mark = getattr(exc, "problem", None), getattr(exc, "problem_mark", None)
    if problem and mark is not None:
        return f"{problem} (line {mark.line + 1}, column {mark.column + 1})"
    return one_line(exc)


@functools.cache
def _yaml_loader() -> type:
    """PyYAML's safe loader reading ``5e-2`` and ``1e-12`` as numbers (YAML 1.2, yaml-cpp).

    YAML 1.1 wants a dot in a float, so PyYAML read ``resolution: 5e-2`` as text, which
    ROS's map_server (yaml-cpp) reads as 0.05 (an audit).
    """
    import re

    import yaml

    class Loader(yaml.SafeLoader):
        pass

    number = re.compile(
        r"^[-+]?(?:[0-9][0-9_]*\.[0-9_]*(?:[eE][-+]?[0-9]+)?"
        r"|[0-9][0-9_]*[eE][-+]?[0-9]+|\.[0-9_]+(?:[eE][-+]?[0-9]+)?)$"
    )
    Loader.add_implicit_resolver("tag:yaml.org,2002:float", number, list("-+0123456789."))

    def construct_mapping(loader: Any, node: Any, deep: bool = False) -> Any:
        # PyYAML keeps the last of two equal keys without a word; which resolution did
        # the user mean? (YAML 1.2 says keys are unique.)
        first_line: dict[Any, int] = {}
        for key_node, _ in node.value:
            key = loader.construct_object(key_node, deep=True)
            line = key_node.start_mark.line + 1
            if isinstance(key, Hashable) and key in first_line:
                raise _DuplicateKey(key, first_line[key], line)
            first_line.setdefault(key, line)
        return yaml.SafeLoader.construct_mapping(loader, node, deep=deep)

    Loader.add_constructor(yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG, construct_mapping)
    return Loader


class _DuplicateKey(Exception):
    """A key written twice in one mapping of a map's ``.yaml``."""

    def __init__(self, key: Any, first: int, second: int) -> None:
        super().__init__(key, first, second)
        self.key, self.first, self.second = key, first, second


def read_ros_map(yaml_file: str | os.PathLike[str], unknown_free: bool = False) -> ImageMap:
    """Read a ROS ``map_server`` map: its ``.yaml`` and the image it names.

    Parameters
    ----------
    yaml_file : str or os.PathLike
        The ``.yaml`` (``image``, ``resolution``, ``origin: [x, y, yaw]``, ``negate``,
        ``occupied_thresh``, ``free_thresh``, ``mode``); the image path is relative to
        the file's folder.
    unknown_free : bool
        Read the pixels between the thresholds as free (default: occupied).

    Returns
    -------
    ImageMap

    Raises
    ------
    InputError
        Naming the field: a missing or malformed one, a rotated origin (yaw != 0: our
        maps' bounds are axis-aligned), a ``mode`` other than ``trinary`` or ``scale``.
    """
    try:
        return _read_ros_map(yaml_file, unknown_free)
    except InputError as exc:
        # A field's error names the file it is in ("resolution: ..." did not; an audit).
        name = os.fspath(yaml_file)
        if name in str(exc) or os.path.basename(name) in str(exc):
            raise
        raise InputError(f"{exc} (in {name})") from None


def _read_ros_map(yaml_file: str | os.PathLike[str], unknown_free: bool) -> ImageMap:
    """The body of :func:`read_ros_map`."""
    import yaml

    try:
        with open(yaml_file, encoding="utf-8") as f:
            data = yaml.load(f, Loader=_yaml_loader())  # noqa: S506 - a SafeLoader
    except OSError as exc:
        raise InputError(f"map: cannot read {os.fspath(yaml_file)}: {exc.strerror}") from None
    except (yaml.YAMLError, UnicodeDecodeError) as exc:
        raise InputError(f"map: {os.fspath(yaml_file)} is not YAML: {_yaml_why(exc)}") from None
    except _DuplicateKey as dup:
        where = (
            f"line {dup.first}" if dup.first == dup.second
            else f"lines {dup.first} and {dup.second}"
        )
        raise InputError(
            f"{dup.key}: given twice in {os.fspath(yaml_file)} ({where}); keep one"
        ) from None
    if not isinstance(data, dict):
        raise InputError(f"map: {os.fspath(yaml_file)} is not a ROS map .yaml (a mapping)")
    for key in ("image", "resolution", "origin"):
        if key not in data:
            raise InputError(f"{key}: missing in {os.fspath(yaml_file)} (a ROS map .yaml)")
    # map_server (yaml-cpp's as<double>) reads a quoted number as the number: "0.05".
    for key in ("resolution", "occupied_thresh", "free_thresh", "negate"):
        if key in data:
            data[key] = _unquoted(data[key])
    origin = data["origin"]
    if isinstance(origin, list):
        origin = [_unquoted(v) for v in origin]
    if not isinstance(origin, list) or len(origin) not in (2, 3):
        raise InputError(f"origin: expected [x, y, yaw], got {brief_repr(origin)}")
    if len(origin) == 3:
        yaw = _number(origin[2], "origin", -1e3, 1e3, "yaw")
        # A full turn written to 6 decimals (6.283185) is a yaw of 0 too (an audit).
        if abs(math.remainder(yaw, math.tau)) > 1e-6:
            raise InputError(
                f"origin: the map is rotated (yaw {yaw:g} rad); rrtdrive maps are axis-aligned: "
                "rotate the image so that its yaw is 0"
            )
    mode = data.get("mode", "trinary")
    if mode not in ("trinary", "scale"):
        raise InputError(f"mode: only trinary and scale maps are read, got {brief_repr(mode)}")
    negate = data.get("negate", 0)
    if negate not in (0, 1, True, False):
        raise InputError(f"negate: expected 0 or 1, got {brief_repr(negate)}")
    image = data["image"]
    if not isinstance(image, str) or not image:
        raise InputError(f"image: expected the image's file name, got {brief_repr(image)}")
    path = os.path.join(os.path.dirname(os.fspath(yaml_file)), image)
    return read_image_map(
        path, data["resolution"], (origin[0], origin[1]), bool(negate),
        data.get("occupied_thresh", 0.65), data.get("free_thresh", 0.196), unknown_free, mode,
    )  # fmt: skip


def despeckle(grid: ImageMap, max_cells: int) -> tuple[ImageMap, int, int]:
    """``grid`` without its specks: groups of at most ``max_cells`` occupied cells.

    Cells are grouped with their eight neighbours (``scipy.ndimage.label``), so a
    speck touching a wall, even at a corner, is part of the wall and stays. Only
    for the user who knows the specks are scanner noise: a post or a kerb stone is
    a speck too.

    Parameters
    ----------
    grid : ImageMap
        The image read.
    max_cells : int
        Largest group dropped (``0``: none).

    Returns
    -------
    tuple
        ``(despeckled, groups_dropped, cells_dropped)``.

    Examples
    --------
    >>> occ = np.array([[1, 0, 0, 0], [0, 0, 1, 1], [0, 0, 1, 1]], dtype=bool)
    >>> clean, groups, cells = despeckle(ImageMap(occ, 1.0, (0.0, 0.0)), 1)
    >>> clean.occupied.astype(int).tolist(), groups, cells
    ([[0, 0, 0, 0], [0, 0, 1, 1], [0, 0, 1, 1]], 1, 1)
    """
    from scipy import ndimage

    max_cells = require_int("max_cells", max_cells, 0)
    if max_cells == 0:
        return grid, 0, 0
    labels, count = ndimage.label(grid.occupied, structure=np.ones((3, 3), dtype=bool))
    sizes = np.bincount(labels.ravel(), minlength=count + 1)
    small = sizes <= max_cells
    small[0] = False  # label 0: the free cells
    drop = small[labels]
    unknown = None if grid.unknown_cells is None else grid.unknown_cells & ~drop
    kept = dataclasses.replace(grid, occupied=grid.occupied & ~drop, unknown_cells=unknown)
    return kept, int(small.sum()), int(drop.sum())


def grid_rectangles(occupied: np.ndarray) -> np.ndarray:
    """Disjoint rectangles of cells covering exactly the occupied ones.

    Each row's runs of occupied cells; a run continues the rectangle above it when
    that rectangle spans exactly the same columns.

    Parameters
    ----------
    occupied : numpy.ndarray
        Bool ``(rows, cols)``.

    Returns
    -------
    numpy.ndarray
        Int ``(K, 4)`` rows ``[r0, c0, r1, c1]``: rows ``r0 .. r1 - 1`` and columns
        ``c0 .. c1 - 1``.

    Examples
    --------
    >>> grid_rectangles(np.array([[1, 1, 0], [1, 1, 0], [0, 1, 1]], dtype=bool)).tolist()
    [[0, 0, 2, 2], [2, 1, 3, 3]]
    """
    occ = np.asarray(occupied, dtype=bool)
    done: list[list[int]] = []
    open_: dict[tuple[int, int], list[int]] = {}
    for r, row in enumerate(occ):
        edges = np.flatnonzero(np.diff(np.concatenate([[0], row.astype(np.int8), [0]])))
        runs = {(int(a), int(b)) for a, b in zip(edges[::2], edges[1::2], strict=True)}
        for key in list(open_):
            if key not in runs:
                done.append(open_.pop(key))
        for a, b in sorted(runs):
            if (a, b) in open_:
                open_[(a, b)][2] = r + 1
            else:
                open_[(a, b)] = [r, a, r + 1, b]
    done.extend(open_.values())
    out = np.array(sorted(done), dtype=np.int64).reshape(-1, 4)
    return out


def image_obstacles(grid: ImageMap) -> tuple[Obstacle, ...]:
    """The obstacles of an image's occupied cells: :func:`grid_rectangles` placed in metres.

    Parameters
    ----------
    grid : ImageMap
        The image read.

    Returns
    -------
    tuple of Obstacle
        Axis-aligned rectangles, coordinates rounded to the nanometre.
    """
    from rrtdrive.obstacles import Obstacle

    rows = grid.occupied.shape[0]
    res = grid.resolution
    x0, y0 = grid.origin
    out = []
    for r0, c0, r1, c1 in grid_rectangles(grid.occupied).tolist():
        # Image rows count down from the top; y counts up from the origin.
        ylo, yhi = y0 + (rows - r1) * res, y0 + (rows - r0) * res
        xlo, xhi = x0 + c0 * res, x0 + c1 * res
        # To the nanometre: 3 x 0.05 m is 0.15000000000000002 in binary, noise in the file.
        centre = (round((xlo + xhi) / 2, 9), round((ylo + yhi) / 2, 9))
        out.append(Obstacle(centre, (round(xhi - xlo, 9), round(yhi - ylo, 9))))
    return tuple(out)


def unknown_cells_under(grid: ImageMap, body: shapely.Polygon) -> int:
    """How many of the image's unknown cells a shape overlaps (shares area with).

    Parameters
    ----------
    grid : ImageMap
        The image read, with its ``unknown_cells``.
    body : shapely.Polygon
        A shape in metres, e.g. the car's footprint at a pose.

    Returns
    -------
    int
        The count; 0 when ``grid.unknown_cells`` is ``None``.

    Examples
    --------
    >>> import shapely
    >>> unknown = np.array([[0, 1], [0, 0]], dtype=bool)
    >>> grid = ImageMap(unknown, 1.0, (0.0, 0.0), 1, unknown)
    >>> unknown_cells_under(grid, shapely.box(1.5, 1.5, 3.0, 3.0))
    1
    >>> unknown_cells_under(grid, shapely.box(0.0, 0.0, 0.9, 2.0))
    0
    """
    import shapely

    if grid.unknown_cells is None:
        return 0
    x0, y0 = grid.origin
    res = grid.resolution
    n_rows, n_cols = grid.unknown_cells.shape
    top = y0 + n_rows * res  # the image's first row is at the top
    # Only the cells under the shape's bounding box can overlap it: a transparent
    # background is millions of unknown cells, each a shapely box otherwise.
    xmin, ymin, xmax, ymax = body.bounds
    c0, c1 = max(0, math.floor((xmin - x0) / res)), min(n_cols, math.ceil((xmax - x0) / res))
    r0, r1 = max(0, math.floor((top - ymax) / res)), min(n_rows, math.ceil((top - ymin) / res))
    if c0 >= c1 or r0 >= r1:
        return 0
    rows, cols = np.nonzero(grid.unknown_cells[r0:r1, c0:c1])
    rows, cols = rows + r0, cols + c0
    cells = shapely.box(x0 + cols * res, top - (rows + 1) * res, x0 + (cols + 1) * res,
                        top - rows * res)  # fmt: skip
    # Sharing an edge is no overlap: the map checks call a body touching an obstacle free.
    shared = shapely.area(shapely.intersection(cells, body))
    return int(np.count_nonzero(shared > 1e-12))


def map_from_image(
    grid: ImageMap, name: str, start: Pose, goal: Pose, vehicle: VehicleParams | None = None
) -> Map:
    """The :class:`~rrtdrive.maps.Map` of an image's occupied cells, bounds its extent.

    Parameters
    ----------
    grid : ImageMap
        The image read (:func:`read_image_map`, :func:`read_ros_map`).
    name : str
        The map's name.
    start, goal : Pose
        Rear-axle poses; checked against the obstacles as any map's, for ``vehicle``.
    vehicle : VehicleParams, optional
        The map's car (default: the paper's).

    Returns
    -------
    Map
    """
    from rrtdrive.maps import Map

    bounds = tuple(round(v, 9) for v in grid.bounds)
    return Map(name, bounds, image_obstacles(grid), start, goal,  # type: ignore[arg-type]
               vehicle or VehicleParams())  # fmt: skip
