"""Offscreen frames of a live rrtdrive scene: highway-env's graphics plus the planned path.

:class:`SceneRenderer` draws, through the shared
:class:`~rrtdrive.sim.render.SceneCanvas` (lanes, path, goal, objects and parked
cars drawn once per camera; moving vehicles every frame), the driven trace and
the reference points the agent observes, flipped so that +y points up, with a
read-out. No display is needed: do not set ``SDL_VIDEODRIVER=dummy`` (highway-env
then draws nothing).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from rrtdrive.sim.render import REF_COLOR, TRACE_COLOR, SceneCanvas
from rrtdrive.sim.scenes import fit_view

__all__ = ["SceneRenderer", "view_for"]


def view_for(
    bounds: tuple[float, float, float, float], lane_y: float | None
) -> tuple[tuple[int, int], float, tuple[float, float]]:
    """Frame size, pixels per metre and camera centre that show a whole map.

    Parameters
    ----------
    bounds : tuple of float
        ``(xmin, ymin, xmax, ymax)`` of the map in metres.
    lane_y : float or None
        Centre of the ego lane of a road scenario (a wide, low frame), else ``None``
        (the map fitted to the frame, :func:`rrtdrive.sim.scenes.fit_view`).

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
    return fit_view(bounds)


class SceneRenderer:
    """Draws frames of a highway-env road with the path, trace, reference points and read-out.

    Parameters
    ----------
    size : tuple of int
        ``(width, height)`` of the frame in pixels.
    scaling : float
        Pixels per metre.
    centre : tuple of float
        World point at the centre of the frame; set the attribute ``centre`` to move
        the camera.
    reuse_static : bool
        Reuse the static layer between frames (see :class:`~rrtdrive.sim.render.SceneCanvas`).
    """

    def __init__(
        self,
        size: tuple[int, int],
        scaling: float,
        centre: tuple[float, float],
        reuse_static: bool = True,
    ) -> None:
        self.canvas = SceneCanvas(size, scaling, centre, reuse_static=reuse_static)
        self.size = self.canvas.size
        self.scaling = self.canvas.scaling

    def __getstate__(self) -> dict[str, Any]:
        # The canvas holds pygame's surfaces, font and module, which do not pickle: a
        # copied env (pickle, copy.deepcopy) draws its own on its first frame.
        canvas = self.canvas
        return {"args": (canvas.size, canvas.scaling, tuple(canvas.centre), canvas.reuse_static)}

    def __setstate__(self, state: dict[str, Any]) -> None:
        size, scaling, centre, reuse = state["args"]
        self.__init__(size, scaling, centre, reuse_static=reuse)  # type: ignore[misc]

    @property
    def centre(self) -> np.ndarray:
        """World point at the centre of the frame."""
        return self.canvas.centre

    @centre.setter
    def centre(self, value: Any) -> None:
        self.canvas.centre = np.array(value, dtype=float)

    @property
    def surface(self) -> Any:
        """The world surface drawn on (highway-env's ``WorldSurface``)."""
        return self.canvas.surface

    def frame(
        self,
        road: Any,
        simulation_frequency: float,
        path_xy: np.ndarray,
        goal_xy: tuple[float, float],
        trace_xy: Sequence[Sequence[float]],
        ref_xy: np.ndarray,
        lines: Sequence[str],
        gears: np.ndarray | None = None,
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
        gears : numpy.ndarray, optional
            The path's gear per point (``Path.gears``): reverse segments dashed, cusps
            marked (:meth:`~rrtdrive.sim.render.SceneCanvas.draw`).
        """
        canvas = self.canvas
        canvas.draw(road, simulation_frequency, path_xy, goal_xy, gears=gears)
        canvas.polyline(trace_xy, TRACE_COLOR)
        canvas.dots(ref_xy, REF_COLOR, 2)
        return canvas.frame(lines)
