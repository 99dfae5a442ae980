"""The video's read-out never hides the car: a tall narrow map gets a band for the panel.

A map 20 m wide and 60 m tall is fitted to a 320 x 640 frame; the 290 px read-out
panel then covered the drive in every corner (the start car at the bottom, the
goal at the top). The frames are checked through the real rendering: the car's
pixels (highway-env's ego green) are counted in each frame and must not touch the
panel's white rectangle.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from rrtdrive.maps import Map, Obstacle, builtin_map
from rrtdrive.sim.runner import run_episode
from rrtdrive.sim.scenes import fit_view
from rrtdrive.sim.tasks import CustomTask
from rrtdrive.sim.video import render_frames
from rrtdrive.types import Path, Pose

#: highway-env's ego colour (``VehicleGraphics.EGO_COLOR``).
EGO_GREEN = (50, 200, 0)
TALL_BOUNDS = (0.0, 0.0, 20.0, 60.0)


@pytest.fixture(scope="module")
def tall_episode():
    # A straight drive up the middle of the map, from near its bottom to near its top.
    up = math.pi / 2
    tall = Map(
        "tall", TALL_BOUNDS, (Obstacle((16.0, 30.0), (3.0, 6.0)),),
        Pose(10.0, 4.0, up), Pose(10.0, 55.0, up),
    )
    task = CustomTask.from_map(tall, 0)
    y = np.arange(4.0, 55.0 + 1e-9, 0.1)
    path = Path(np.column_stack([np.full_like(y, 10.0), y, np.full_like(y, up), 0 * y]),
                np.zeros((0, 2)))
    return run_episode(task, path, "pure-pursuit", 0)


def _panel_box(frame: np.ndarray) -> tuple[int, int, int, int]:
    """``(top, bottom, left, right)`` of the panel: its white fill plus its 1 px border."""
    ys, xs = np.nonzero(np.all(frame == 255, axis=-1))
    assert len(ys), "no read-out panel in the frame"
    return int(ys.min()) - 1, int(ys.max()) + 1, int(xs.min()) - 1, int(xs.max()) + 1


def _car_pixels(frame: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    return np.nonzero(np.all(frame == EGO_GREEN, axis=-1))


def test_the_tall_map_is_fitted_to_320_by_640():
    # The premise: no corner of the fitted frame leaves room beside the route.
    size, scaling, _ = fit_view(TALL_BOUNDS)
    assert size == (320, 640) and scaling == pytest.approx(9.6)


def test_the_read_out_never_covers_the_car_on_a_tall_narrow_map(tall_episode):
    ep = tall_episode
    assert ep.log.states[0, 1] < 5.0 and ep.log.states[-1, 1] > 54.0  # bottom to top
    frames = list(render_frames(ep, stride=40))  # the first, every 40th and the last
    assert len(frames) >= 10
    counts = []
    for k, frame in enumerate(frames):
        top, bottom, left, right = _panel_box(frame)
        ys, xs = _car_pixels(frame)
        counts.append(len(ys))
        assert len(ys), f"frame {k}: the car is hidden"
        # Not one car pixel at the panel's edge or beyond it (a hidden part would be
        # under the panel, so the visible part would touch its border).
        near = (ys >= top - 1) & (ys <= bottom + 1) & (xs >= left - 1) & (xs <= right + 1)
        assert not near.any(), f"frame {k}: the panel covers part of the car"
    # The whole car shows in every frame: as many green pixels as mid-drive.
    assert min(counts) >= 0.9 * float(np.median(counts)), counts


def test_the_tall_map_frame_grows_by_a_band_that_holds_the_panel(tall_episode):
    first, last = list(render_frames(tall_episode, stride=10**6))
    assert first.shape[1] == 320 and first.shape[0] > 640  # taller than the fitted frame

    from rrtdrive.sim.render import panel_band

    band = panel_band(3)
    assert first.shape == last.shape == (640 + band, 320, 3)
    for frame in (first, last):
        top, bottom, left, right = _panel_box(frame)
        assert (top, left) == (6, 6) and bottom < band and right < 320
        # The band shows nothing of the map or the drive: plain ground under the panel.
        below = frame[bottom + 1 : band]
        assert (below == below[0, 0]).all()


def test_the_band_frames_equal_a_full_redraw(tall_episode):
    fast = list(render_frames(tall_episode, stride=100))
    slow = list(render_frames(tall_episode, stride=100, reuse_background=False))
    assert len(fast) == len(slow)
    for a, b in zip(fast, slow, strict=True):
        np.testing.assert_array_equal(a, b)


def test_every_corner_of_the_tall_frame_covers_the_drive():
    from rrtdrive.sim.render import PANEL_CORNERS, SceneCanvas

    size, scaling, centre = fit_view(TALL_BOUNDS)
    canvas = SceneCanvas(size, scaling, centre)
    drive = np.column_stack([np.full(60, 10.0), np.linspace(4.0, 55.0, 60)])
    hits = canvas.panel_hits(drive, 290, 3)
    assert list(hits) == list(PANEL_CORNERS) and min(hits.values()) > 0
    # panel_corner still picks the fewest, ties in the order of PANEL_CORNERS.
    assert canvas.panel_corner(drive, 290, 3) == min(PANEL_CORNERS, key=hits.__getitem__)


@pytest.mark.parametrize("name", ["garage", "turning_bulb", "parking_lot"])
def test_an_ordinary_map_keeps_its_fitted_frame(name):
    # A corner leaves the drive clear: no band, the frame is the fitted size.
    m = builtin_map(name)
    ep = run_episode(CustomTask.from_map(m, 0), controller="pure-pursuit", seed=0)
    (width, height), _, _ = fit_view(m.bounds)
    frames = list(render_frames(ep, stride=10**6))
    assert len(frames) == 2
    for frame in frames:
        assert frame.shape == (height, width, 3)
        top, bottom, left, right = _panel_box(frame)
        assert top == 6 or bottom == height - 7  # 6 px in from the top or bottom edge
        ys, xs = _car_pixels(frame)
        assert len(ys)
        near = (ys >= top - 1) & (ys <= bottom + 1) & (xs >= left - 1) & (xs <= right + 1)
        assert not near.any()
