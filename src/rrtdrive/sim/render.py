"""Offscreen frames of a highway-env road: what does not move is drawn once per camera.

:class:`SceneCanvas` owns one pygame surface and draws onto it with highway-env's
own graphics (:class:`~highway_env.road.graphics.RoadGraphics`,
:class:`~highway_env.vehicle.graphics.VehicleGraphics`) in highway-env's order:
lanes, then the planned path and the goal, road objects, vehicles; the caller
adds the driven trace and dots on top, and :meth:`SceneCanvas.frame` flips the
image so that +y points up (highway-env draws y downwards) and adds a read-out.
It serves both the episode replay (:mod:`rrtdrive.sim.video`) and the gym
environment's ``render`` (:mod:`rrtdrive.envs.render`).

The static layer. Everything drawn before the moving vehicles - lanes, path, goal,
road objects and parked cars - is drawn once into a copy that later frames blit,
as long as the camera, the path, the goal and every static item's drawn state
(pose, size, colour, crash flags) are unchanged; any change redraws it, so a
crash that moves or recolours an obstacle shows. Per frame only the moving
vehicles are drawn, and a parked car that comes after a moving vehicle in the
road's order and may overlap it is drawn again, so that the pixels equal
highway-env's full redraw (its rotated sprites are either opaque or fully
transparent, so the last opaque sprite wins either way).

No display is needed: do not set ``SDL_VIDEODRIVER=dummy`` (highway-env then
draws nothing). It does not go through highway-env's ``EnvViewer``, whose
``close`` calls ``pygame.quit()`` and would break every other canvas in the process.
"""

from __future__ import annotations

import contextlib
import math
import os
import sys
import tempfile
from collections.abc import Iterator, Sequence
from typing import Any

import numpy as np

__all__ = [
    "PATH_COLOR", "REVERSE_COLOR", "CUSP_COLOR", "TRACE_COLOR", "REF_COLOR", "GOAL_COLOR",
    "TEXT_COLOR", "PANEL_COLOR", "PANEL_CORNERS", "SceneCanvas", "fewest_hits", "is_parked",
    "panel_band", "prepare_sdl", "sdl_that_draws",
]

PATH_COLOR = (40, 90, 255)
#: Reverse gear segments of the planned path, dashed (the static plots' cyan, dashed).
REVERSE_COLOR = (23, 190, 207)
#: Cusps (gear changes): yellow dots ringed in black, as the static plots' markers.
CUSP_COLOR = (255, 215, 0)
#: Length of a dash and of the gap after it on a reverse segment, metres.
DASH_M = 1.0
TRACE_COLOR = (255, 60, 40)
REF_COLOR = (255, 150, 0)
GOAL_COLOR = (0, 160, 0)
TEXT_COLOR = (20, 20, 20)
PANEL_COLOR = (255, 255, 255)

#: highway-env draws a vehicle as a square sprite of side ``LENGTH + 2 * tire`` (metres).
_TIRE_LENGTH = 1.0


def prepare_sdl() -> None:
    """Give SDL a runtime folder when there is none (it complains on stderr without one)."""
    if not os.environ.get("XDG_RUNTIME_DIR"):
        os.environ["XDG_RUNTIME_DIR"] = tempfile.mkdtemp(prefix="rrtdrive-sdl-")


@contextlib.contextmanager
def sdl_that_draws() -> Iterator[None]:
    """Lift ``SDL_VIDEODRIVER=dummy`` for the block: highway-env's own viewer draws then.

    highway-env's ``EnvViewer`` turns itself off (``enabled`` false) when it is created
    under the dummy driver, the usual headless-pygame advice, so every ``env.render()``
    of a stock env came back black (an audit); an ``rgb_array`` frame needs no display
    without it either. The variable is put back after the block.
    """
    driver = os.environ.get("SDL_VIDEODRIVER")
    if driver != "dummy":
        yield
        return
    del os.environ["SDL_VIDEODRIVER"]
    try:
        yield
    finally:
        os.environ["SDL_VIDEODRIVER"] = driver


def is_parked(vehicle: Any) -> bool:
    """True for a plain highway-env ``Vehicle`` at rest: a parked car, drawn in the static layer.

    The ego (an :class:`~rrtdrive.sim.ego.EgoVehicle`) and IDM cars are never parked;
    a lead car that stops becomes parked until it moves again, which only costs a
    redraw of the static layer.
    """
    from highway_env.vehicle.kinematics import Vehicle

    return type(vehicle) is Vehicle and float(vehicle.speed) == 0.0


def _to_pixels(surface: Any, xy: Any) -> list[list[int]]:
    """World points to surface pixels, the same integers as ``WorldSurface.vec2pix``.

    ``vec2pix`` is ``int((x - origin) * scaling)`` per coordinate; the same float64
    operations, truncated towards zero, vectorised (long traces cost ~3 us a point).
    """
    pts = np.asarray(xy, dtype=float).reshape(-1, 2)
    origin = np.asarray(surface.origin, dtype=float)
    return ((pts - origin) * surface.scaling).astype(np.int64).tolist()


def _object_state(o: Any) -> tuple[Any, ...]:
    return (
        id(o), type(o), float(o.position[0]), float(o.position[1]), float(o.heading),
        o.LENGTH, o.WIDTH, bool(getattr(o, "crashed", False)), bool(getattr(o, "hit", False)),
    )


def _vehicle_state(v: Any) -> tuple[Any, ...]:
    action = v.action if isinstance(v.action, dict) else {}
    return (
        id(v), type(v), float(v.position[0]), float(v.position[1]), float(v.heading),
        v.LENGTH, v.WIDTH, getattr(v, "color", None), bool(v.crashed),
        action.get("steering"),
    )


class SceneCanvas:
    """One offscreen frame of a road, with a static layer reused across frames.

    Parameters
    ----------
    size : tuple of int
        ``(width, height)`` of the frame in pixels.
    scaling : float
        Pixels per metre.
    centre : tuple of float
        World point at the centre of the frame; the attribute ``centre`` may be
        moved between frames (a following camera), which redraws the static layer.
    reuse_static : bool
        Reuse the static layer between frames (default); ``False`` draws everything
        every frame, as highway-env does (the reference the fast path is tested against).

    Examples
    --------
    >>> canvas = SceneCanvas((640, 640), 6.0, (25.0, 25.0))  # doctest: +SKIP
    >>> canvas.draw(road, 20, path_xy, (goal.x, goal.y))  # doctest: +SKIP
    >>> canvas.polyline(trace_xy, TRACE_COLOR)  # doctest: +SKIP
    >>> rgb = canvas.frame(["t 0.00 s"])  # doctest: +SKIP
    """

    def __init__(
        self,
        size: tuple[int, int],
        scaling: float,
        centre: tuple[float, float],
        reuse_static: bool = True,
    ) -> None:
        prepare_sdl()
        import pygame
        from highway_env.road.graphics import WorldSurface

        self.size = (int(size[0]), int(size[1]))
        self.scaling = float(scaling)
        self.centre = np.array(centre, dtype=float)
        self.reuse_static = bool(reuse_static)
        self._pygame = pygame
        self.surface = WorldSurface(self.size, 0, pygame.Surface(self.size))
        self.surface.scaling = self.scaling
        self.surface.centering_position = [0.5, 0.5]
        self._font: Any = None
        self._static: Any = None
        self._static_key: tuple[Any, ...] | None = None
        #: Frames whose static layer was drawn afresh / copied (for tests and benchmarks).
        self.static_draws = 0
        self.static_reuses = 0

    def _text_font(self) -> Any:
        pygame = self._pygame
        if not pygame.font.get_init():  # never started, or someone called pygame.quit()
            pygame.font.init()
            self._font = None
        if self._font is None:
            self._font = pygame.font.Font(None, 22)
        return self._font

    def draw(
        self,
        road: Any,
        simulation_frequency: float,
        path_xy: np.ndarray,
        goal_xy: tuple[float, float] | None,
        moving: Sequence[Any] | None = None,
        gears: np.ndarray | None = None,
    ) -> None:
        """Draw the road, path, goal, objects and vehicles at their current poses.

        Parameters
        ----------
        road : highway_env.road.road.Road
            The road with its objects and vehicles at their current poses.
        simulation_frequency : float
            Passed to highway-env's traffic drawing.
        path_xy : numpy.ndarray
            Planned path, ``(N, 2)`` world points (drawn when ``N >= 2``).
        goal_xy : tuple of float or None
            Goal position (a green circle), or ``None`` for none.
        moving : sequence, optional
            Vehicles drawn every frame; the others are static. Default: every vehicle
            that is not :func:`is_parked`. The choice only affects speed: a static
            vehicle that changes redraws the static layer.
        """
        from highway_env.road.graphics import RoadGraphics

        surface = self.surface
        surface.move_display_window_to(self.centre)
        gear = None if gears is None else np.asarray(gears, dtype=float).reshape(-1)
        if gear is not None and (len(gear) != len(path_xy) or np.all(gear > 0)):
            gear = None
        if not self.reuse_static:
            self._underlay(road, path_xy, goal_xy, gear)
            RoadGraphics.display_road_objects(road, surface, offscreen=True)
            RoadGraphics.display_traffic(
                road, surface, simulation_frequency=simulation_frequency, offscreen=True
            )
            return
        if road.record_history:
            # Vehicle histories are drawn under every vehicle: nothing of the traffic is static.
            moving = list(road.vehicles)
        elif moving is None:
            moving = [v for v in road.vehicles if not is_parked(v)]
        moving_ids = {id(v) for v in moving}
        path = np.asarray(path_xy, dtype=float)
        key = (
            self.size, self.scaling, float(surface.origin[0]), float(surface.origin[1]),
            id(road.network), path.shape, path.tobytes(),
            None if gear is None else gear.tobytes(),
            None if goal_xy is None else (float(goal_xy[0]), float(goal_xy[1])),
            tuple(_object_state(o) for o in road.objects),
            tuple(_vehicle_state(v) for v in road.vehicles if id(v) not in moving_ids),
        )
        if self._static is not None and key == self._static_key:
            surface.blit(self._static, (0, 0))
            self.static_reuses += 1
        else:
            self._underlay(road, path, goal_xy, gear)
            RoadGraphics.display_road_objects(road, surface, offscreen=True)
            self._vehicles(road, lambda v: id(v) not in moving_ids)
            self._static, self._static_key = surface.copy(), key
            self.static_draws += 1
        if road.record_history:
            RoadGraphics.display_traffic(
                road, surface, simulation_frequency=simulation_frequency, offscreen=True
            )
        else:
            self._moving_vehicles(road, moving_ids)

    def _underlay(
        self, road: Any, path_xy: np.ndarray, goal_xy: tuple[float, float] | None,
        gears: np.ndarray | None = None,
    ) -> None:
        """Ground, lanes, path and goal: what highway-env's objects and vehicles cover."""
        pygame = self._pygame
        from highway_env.road.graphics import RoadGraphics

        surface = self.surface
        RoadGraphics.display(road, surface)
        if len(path_xy) >= 2 and gears is None:
            pygame.draw.lines(surface, PATH_COLOR, False, _to_pixels(surface, path_xy), 2)
        elif len(path_xy) >= 2:
            self._gear_path(np.asarray(path_xy, dtype=float), gears)
        if goal_xy is not None:
            gx, gy = surface.vec2pix(goal_xy)
            pygame.draw.circle(surface, GOAL_COLOR, (gx, gy), max(3, surface.pix(0.4)), 2)

    def _gear_path(self, xy: np.ndarray, gears: np.ndarray) -> None:
        """Forward segments solid, reverse ones dashed in another colour, cusps as dots."""
        pygame, surface = self._pygame, self.surface
        change = np.flatnonzero(np.diff(gears) != 0) + 1
        bounds = [0, *change.tolist(), len(xy)]
        for a, b in zip(bounds[:-1], bounds[1:], strict=True):
            seg = xy[max(0, a - 1) if a else a : b]
            if len(seg) < 2:
                continue
            if gears[a] > 0:
                pygame.draw.lines(surface, PATH_COLOR, False, _to_pixels(surface, seg), 2)
                continue
            s = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(seg, axis=0).T))])
            dash = np.floor(s / DASH_M).astype(int) % 2 == 0
            for start in np.flatnonzero(dash & np.concatenate([[True], ~dash[:-1]])):
                stop = start
                while stop + 1 < len(seg) and dash[stop + 1]:
                    stop += 1
                piece = seg[start : stop + 2]  # one point past the dash's end
                if len(piece) >= 2:
                    pygame.draw.lines(surface, REVERSE_COLOR, False, _to_pixels(surface, piece), 3)
        radius = max(4, surface.pix(0.35))
        for c in change:
            px = surface.vec2pix(xy[c])
            pygame.draw.circle(surface, CUSP_COLOR, px, radius)
            pygame.draw.circle(surface, TEXT_COLOR, px, radius, 1)

    def _vehicles(self, road: Any, keep: Any) -> None:
        from highway_env.vehicle.graphics import VehicleGraphics

        for v in road.vehicles:
            if keep(v):
                VehicleGraphics.display(v, self.surface, offscreen=True)

    def _sprite_box(self, v: Any) -> tuple[float, float, float]:
        """Centre pixel and a half-width that bounds the vehicle's rotated sprite."""
        x, y = self.surface.pos2pix(v.position[0], v.position[1])
        side = self.surface.pix(v.LENGTH + 2 * _TIRE_LENGTH)
        return float(x), float(y), 0.71 * side + 3.0  # sqrt(2)/2 of the square, plus rounding

    def _moving_vehicles(self, road: Any, moving_ids: set[int]) -> None:
        """Moving vehicles in road order; a static one after them is redrawn where they may meet."""
        from highway_env.vehicle.graphics import VehicleGraphics

        drawn: list[tuple[float, float, float]] = []
        for v in road.vehicles:
            if id(v) in moving_ids:
                VehicleGraphics.display(v, self.surface, offscreen=True)
                drawn.append(self._sprite_box(v))
            elif drawn:
                bx, by, br = self._sprite_box(v)
                if any(abs(bx - x) <= br + r and abs(by - y) <= br + r for x, y, r in drawn):
                    VehicleGraphics.display(v, self.surface, offscreen=True)
                    drawn.append((bx, by, br))

    def polyline(self, xy: Any, color: tuple[int, int, int], width: int = 2) -> None:
        """Draw a world polyline (two points or more) on top of the scene."""
        if len(xy) >= 2:
            self._pygame.draw.lines(self.surface, color, False, _to_pixels(self.surface, xy), width)

    def dots(self, xy: Any, color: tuple[int, int, int], radius: int = 2) -> None:
        """Draw a filled dot at each world point."""
        for p in xy:
            self._pygame.draw.circle(self.surface, color, self.surface.vec2pix(p), radius)

    def panel_hits(
        self, points: np.ndarray, width: int, lines: int, reach_m: float = 3.5
    ) -> dict[str, int]:
        """How many of ``points`` the read-out panel covers in each frame corner.

        Parameters
        ----------
        points : numpy.ndarray
            World ``(x, y)`` rear-axle positions (the path, the driven trace), seen
            from the canvas's ``centre``.
        width : int
            Panel width in pixels.
        lines : int
            Lines of text in the panel.
        reach_m : float
            A point counts when the panel comes within ``reach_m`` metres of it (the
            car's body around its axle).

        Returns
        -------
        dict of str to int
            The count per corner of :data:`PANEL_CORNERS`, in that order.
        """
        xy = np.asarray(points, dtype=float).reshape(-1, 2)
        w, h = self.size
        # World to image pixels of the flipped frame (+y up), as the surface maps them.
        px = w / 2.0 + (xy[:, 0] - self.centre[0]) * self.scaling
        py = h / 2.0 - (xy[:, 1] - self.centre[1]) * self.scaling
        r = reach_m * self.scaling
        height = _panel_height(lines)
        hits = {}
        for corner in PANEL_CORNERS:
            left, top = _panel_origin(corner, self.size, width, height)
            inside = (px >= left - r) & (px <= left + width + r) & (py >= top - r)
            inside &= py <= top + height + r
            hits[corner] = int(inside.sum())
        return hits

    def panel_corner(
        self, points: np.ndarray, width: int, lines: int, reach_m: float = 3.5
    ) -> str:
        """The frame corner whose read-out panel covers the fewest of ``points``.

        ``points`` are world ``(x, y)`` rear-axle positions (the path, the driven
        trace) seen from the canvas's ``centre``; a point counts when the panel comes
        within ``reach_m`` of it (the car's body around its axle, :meth:`panel_hits`).
        The panel is ``width`` pixels wide for ``lines`` lines. Ties go to the top
        left, then top right, bottom left, bottom right. On a narrow map (a kerbside
        street, 960 x 240) the top-left panel hid the start. When every corner covers
        some points (a tall narrow map), the video puts the panel in a band above the
        scene instead (:func:`panel_band`).
        """
        return fewest_hits(self.panel_hits(points, width, lines, reach_m))

    def frame(
        self, lines: Sequence[str], panel_width: int | None = None, corner: str = "top-left"
    ) -> np.ndarray:
        """The picture as RGB, ``(height, width, 3)`` uint8, freshly allocated, +y up.

        Parameters
        ----------
        lines : sequence of str
            Read-out text, one line each, in a white panel (none when empty).
        panel_width : int, optional
            Panel width in pixels (default: fitted to the text).
        corner : str
            Where the panel goes: one of :data:`PANEL_CORNERS` (see :meth:`panel_corner`).
        """
        pygame = self._pygame
        image = pygame.transform.flip(self.surface, False, True)
        if lines:
            font = self._text_font()
            width = panel_width or 12 + max(font.size(text)[0] for text in lines)
            panel_h = _panel_height(len(lines))
            left, top = _panel_origin(corner, self.size, width, panel_h)
            pygame.draw.rect(image, PANEL_COLOR, (left, top, width, panel_h))
            pygame.draw.rect(image, TEXT_COLOR, (left, top, width, panel_h), 1)
            for i, text in enumerate(lines):
                image.blit(font.render(text, True, TEXT_COLOR), (left + 6, top + 5 + 20 * i))
        return _rgb_array(image)


#: The read-out panel's places, in the order ties are broken.
PANEL_CORNERS = ("top-left", "top-right", "bottom-left", "bottom-right")


def _panel_height(lines: int) -> int:
    return 8 + 20 * lines


def fewest_hits(hits: dict[str, int]) -> str:
    """The corner of :meth:`SceneCanvas.panel_hits` covering fewest points, the first of equals.

    Examples
    --------
    >>> fewest_hits({"top-left": 3, "top-right": 0, "bottom-left": 0, "bottom-right": 1})
    'top-right'
    """
    return min(PANEL_CORNERS, key=hits.__getitem__)


def panel_band(lines: int) -> int:
    """Height in pixels of a band above the scene that holds a read-out panel of ``lines`` lines.

    The panel with 6 pixels clear above and below, rounded up to a multiple of 16 (H.264
    macro blocks, as :func:`~rrtdrive.sim.scenes.fit_view` sizes frames). The video adds
    it when the panel would cover some of the drive in every corner of the frame.

    Examples
    --------
    >>> panel_band(3), panel_band(4), panel_band(5)
    (80, 112, 128)
    """
    return int(16 * math.ceil((_panel_height(lines) + 12) / 16.0))


def _panel_origin(corner: str, size: tuple[int, int], width: int, height: int) -> tuple[int, int]:
    """The panel's top-left pixel in a frame of ``size``: 6 pixels in from its corner."""
    if corner not in PANEL_CORNERS:
        raise ValueError(f"corner: one of {PANEL_CORNERS}, got {corner!r}")
    left = 6 if corner.endswith("left") else size[0] - 6 - width
    top = 6 if corner.startswith("top") else size[1] - 6 - height
    return left, top


def _rgb_array(image: Any) -> np.ndarray:
    """A 32-bit surface's pixels as a fresh ``(height, width, 3)`` RGB array.

    Three channel copies out of the surface's own buffer: surfarray's ``array3d`` is
    column-major (its transpose copy cost more than drawing a frame) and
    ``pygame.image.tobytes`` converts pixel by pixel, about twice as slow as this.
    """
    import pygame

    w, h = image.get_size()
    if image.get_bytesize() != 4:
        data = bytearray(pygame.image.tobytes(image, "RGB"))
        return np.frombuffer(data, dtype=np.uint8).reshape(h, w, 3)
    shifts = image.get_shifts()[:3]
    byte = [s // 8 if sys.byteorder == "little" else 3 - s // 8 for s in shifts]
    out = np.empty((h, w, 3), dtype=np.uint8)
    # A view of the locked pixels, dropped before returning (the surface unlocks).
    px = np.frombuffer(image.get_buffer(), dtype=np.uint8).reshape(h, image.get_pitch())
    px = px[:, : 4 * w].reshape(h, w, 4)
    for c in range(3):
        out[..., c] = px[..., byte[c]]
    del px
    return out
