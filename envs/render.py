"""Offscreen frames of a live rrtdrive scene: highway-env's graphics plus the planned path.

:class:`SceneRenderer` owns one pygame surface and draws onto it with
highway-env's own :class:`~highway_env.road.graphics.RoadGraphics` (lanes, road
objects, vehicles), then the planned path, the goal, the driven trace and the
reference points the agent observes; it flips the image so that +y points up
(highway-env draws y downwards) and adds a read-out. No display is needed: do
not set ``SDL_VIDEODRIVER=dummy`` (highway-env then draws nothing).

It does not go through highway-env's ``EnvViewer``, whose ``close`` calls
``pygame.quit()`` and would break every other renderer in the process.
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Sequence
from typing import Any

import numpy as np

__all__ = ["SceneRenderer", "view_for"]

PATH_COLOR = (40, 90, 255)
TRACE_COLOR = (255, 60, 40)
REF_COLOR = (255, 150, 0)
GOAL_COLOR = (0, 160, 0)
TEXT_COLOR = (20, 20, 20)
PANEL_COLOR = (255, 255, 255)


def view_for(
    bounds: tuple[float, float, float, float], lane_y: float | None
) -> tuple[tuple[int, int], float, tuple[float, float]]:
    """Frame size, pixels per metre and camera centre that show a whole map.

    Parameters
    ----------
    bounds : tuple of float
        ``(xmin, ymin, xmax, ymax)`` of the map in metres.
    lane_y : float or None
        Centre of the ego lane of a road scenario (a wide, low frame), else ``None``.

    Returns
    -------
    size : tuple of int
        ``(width, height)`` in pixels (multiples of 16).
    scaling : float
        Pixels per metre.
    centre : tuple of float
        World point at the frame centre.

    Examples
    --------
    >>> view_for((0.0, 0.0, 100.0, 100.0), None)
    ((640, 640), 6.0, (50.0, 50.0))
    """
    xmin, ymin, xmax, ymax = bounds
    if lane_y is not None:
        size = (960, 320)
        return size, size[0] / (xmax - xmin + 6.5), ((xmin + xmax) / 2.0, lane_y + 2.0)
    size = (640, 640)
    scaling = min(size[0] / (xmax - xmin + 6.5), size[1] / (ymax - ymin + 6.5))
    return size, round(scaling, 1), ((xmin + xmax) / 2.0, (ymin + ymax) / 2.0)


class SceneRenderer:
    """Draws frames of a highway-env road with the path, trace and read-out.

    Parameters
    ----------
    size : tuple of int
        ``(width, height)`` of the frame in pixels.
    scaling : float
        Pixels per metre.
    centre : tuple of float
        World point at the centre of the frame (the camera is fixed).
    """

    def __init__(
        self, size: tuple[int, int], scaling: float, centre: tuple[float, float]
    ) -> None:
        if not os.environ.get("XDG_RUNTIME_DIR"):
            # SDL complains on stderr without it; a private empty folder silences it.
            os.environ["XDG_RUNTIME_DIR"] = tempfile.mkdtemp(prefix="rrtdrive-sdl-")
        import pygame
        from highway_env.road.graphics import WorldSurface

        self.size = (int(size[0]), int(size[1]))
        self.scaling = float(scaling)
        self.centre = np.array(centre, dtype=float)
        self._pygame = pygame
        self.surface = WorldSurface(self.size, 0, pygame.Surface(self.size))
        self.surface.scaling = self.scaling
        self.surface.centering_position = [0.5, 0.5]
        self._font: Any = None
        # The lanes drawn for (network, camera centre): copied into the next frames of
        # the same road and view instead of redrawn (144 spot lanes in the parking lot).
        self._background: Any = None
        self._background_key: tuple[Any, tuple[float, float]] | None = None

    def _text_font(self) -> Any:
        pygame = self._pygame
        if not pygame.font.get_init():  # someone called pygame.quit(): start again
            pygame.font.init()
            self._font = None
        if self._font is None:
            self._font = pygame.font.Font(None, 22)
        return self._font

    def frame(
        self,
        road: Any,
        simulation_frequency: float,
        path_xy: np.ndarray,
        goal_xy: tuple[float, float],
        trace_xy: Sequence[Sequence[float]],
        ref_xy: np.ndarray,
        lines: Sequence[str],
    ) -> np.ndarray:
        """One RGB frame, ``(height, width, 3)`` uint8, freshly allocated.

        Parameters
        ----------
        road : highway_env.road.road.Road
            The road with its objects and vehicles at their current poses.
        simulation_frequency : float
            Passed to highway-env's traffic drawing.
        path_xy : numpy.ndarray
            Planned path, ``(N, 2)`` world points.
        goal_xy : tuple of float
            Goal position.
        trace_xy : sequence
            Driven rear-axle positions so far.
        ref_xy : numpy.ndarray
            Reference points the agent observes, ``(K, 2)`` world points.
        lines : sequence of str
            Read-out text, one line each.
        """
        pygame = self._pygame
        from highway_env.road.graphics import RoadGraphics

        surface = self.surface
        surface.move_display_window_to(self.centre)
        key = (road.network, (float(self.centre[0]), float(self.centre[1])))
        cached = self._background_key
        if cached is not None and cached[0] is key[0] and cached[1] == key[1]:
            surface.blit(self._background, (0, 0))
        else:
            RoadGraphics.display(road, surface)
            self._background, self._background_key = surface.copy(), key
        if len(path_xy) >= 2:
            pygame.draw.lines(surface, PATH_COLOR, False, [surface.vec2pix(p) for p in path_xy], 2)
        gx, gy = surface.vec2pix(goal_xy)
        pygame.draw.circle(surface, GOAL_COLOR, (gx, gy), max(3, surface.pix(0.4)), 2)
        RoadGraphics.display_road_objects(road, surface, offscreen=True)
        RoadGraphics.display_traffic(
            road, surface, simulation_frequency=simulation_frequency, offscreen=True
        )
        if len(trace_xy) >= 2:
            pygame.draw.lines(
                surface, TRACE_COLOR, False, [surface.vec2pix(p) for p in trace_xy], 2
            )
        for p in ref_xy:
            pygame.draw.circle(surface, REF_COLOR, surface.vec2pix(p), 2)
        image = pygame.transform.flip(surface, False, True)
        if lines:
            font = self._text_font()
            width = 12 + max(font.size(text)[0] for text in lines)
            panel_h = 8 + 20 * len(lines)
            pygame.draw.rect(image, PANEL_COLOR, (6, 6, width, panel_h))
            pygame.draw.rect(image, TEXT_COLOR, (6, 6, width, panel_h), 1)
            for i, text in enumerate(lines):
                image.blit(font.render(text, True, TEXT_COLOR), (12, 11 + 20 * i))
        return np.ascontiguousarray(np.moveaxis(pygame.surfarray.array3d(image), 0, 1))
