"""What a user sees in the figures and videos: guards from a mutation audit (session 41).

Each test checks a figure's artists or a video's pixels and frames against a reference
worked out here: the samples a test path was built from, arc lengths summed in the
test, world points mapped to pixels by the documented camera (frame centre, pixels per
metre, +y up), frame counts and rates read back by imageio-ffmpeg, the folder's files.
"""

from __future__ import annotations

import logging
import math
import signal
import time
from collections.abc import Iterator
from pathlib import Path as FsPath
from typing import Any

import gymnasium as gym
import imageio.v2 as imageio
import matplotlib.colors as mcolors
import matplotlib.pyplot as plt
import numpy as np
import pytest
from episode_logs import episode as logged_episode
from episode_logs import overtake
from matplotlib.collections import LineCollection
from matplotlib.patches import FancyArrow, Rectangle
from test_plotting import _reverse_result

from rrtdrive.envs.video import RecordMP4
from rrtdrive.maps import Map, Obstacle
from rrtdrive.plotting import map_figure_size, plot_curvature, plot_plan, save_figure
from rrtdrive.sim.episode import Episode
from rrtdrive.sim.mp4 import Mp4Writer
from rrtdrive.sim.render import (
    CUSP_COLOR,
    GOAL_COLOR,
    PANEL_CORNERS,
    PATH_COLOR,
    REVERSE_COLOR,
    SceneCanvas,
)
from rrtdrive.sim.tasks import make_scenario
from rrtdrive.sim.video import even_frame, render_frames, write_frames
from rrtdrive.types import InputError, Path, PlanResult, PlanStatus, Pose, Tree


def _read(path: FsPath) -> tuple[list[np.ndarray], dict]:
    """imageio-ffmpeg's own reading of an MP4: its RGB frames and its metadata."""
    import imageio_ffmpeg

    frames = imageio_ffmpeg.read_frames(str(path))
    meta = next(frames)
    w, h = meta["size"]
    return [np.frombuffer(b, np.uint8).reshape(h, w, 3) for b in frames], meta


# ----------------------------------------------------------------------------- figures


def _gear_rows(pieces: list[tuple[int, np.ndarray]]) -> np.ndarray:
    """Rows ``x, y, yaw, kappa, gear`` of straight ``(gear, xy)`` pieces (cusp rows repeat)."""
    rows = [np.column_stack([xy, np.zeros(len(xy)), np.zeros(len(xy)), np.full(len(xy), g)])
            for g, xy in pieces]
    return np.vstack(rows)


def _line(ax: Any, label: str) -> Any:
    return next(line for line in ax.get_lines() if line.get_label() == label)


def test_each_gear_segment_is_drawn_through_all_its_samples_above_the_trees() -> None:
    """Forward and reverse legs end at the cusp (no gap), the cusp count is right, and
    the path lies above the trees and the waypoints (it was hidden under a tree's fan)."""
    m, result = _reverse_result()
    samples = result.path.samples
    tree = Tree(np.array([[10.0, 10.0], [14.0, 12.0], [12.0, 16.0]]), np.array([-1, 0, 1]))
    result = PlanResult(PlanStatus.SOLVED, "rrt-connect", result.path, result.raw_path,
                        (tree,), 3, 0, 0.0)
    ax = plot_plan(m, result).axes[0]
    fwd, back = _line(ax, "path, forward"), _line(ax, "path, reverse (dashed)")
    np.testing.assert_allclose(np.column_stack(fwd.get_data()), samples[:26, :2])
    np.testing.assert_allclose(np.column_stack(back.get_data()), samples[26:, :2])
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "cusp (gear change, 1)" in labels
    below = [c.get_zorder() for c in ax.collections if isinstance(c, LineCollection)]
    below += [_line(ax, "waypoints").get_zorder(), _line(ax, "raw tree path").get_zorder()]
    assert below and min(fwd.get_zorder(), back.get_zorder()) > max(below)
    plt.close("all")


def test_the_map_figure_shows_the_bounds_every_obstacle_and_the_headings() -> None:
    """The border is the map's rectangle, each obstacle is drawn at its corners and the
    start and goal arrows point along their headings."""
    obstacles = (Obstacle((20.0, 10.0), (4.0, 2.0)), Obstacle((40.0, 5.0), (3.0, 3.0)))
    m = Map("m", (0.0, 0.0, 60.0, 20.0), obstacles, Pose(5.0, 5.0, 0.0),
            Pose(50.0, 15.0, math.pi / 2))
    empty = PlanResult(PlanStatus.NO_PATH_IN_BUDGET, "rrt", Path(np.zeros((0, 4)),
                       np.zeros((0, 2))), np.zeros((0, 2)), (), 0, 0, 0.0)
    ax = plot_plan(m, empty, title="t").axes[0]
    border = [p for p in ax.patches if isinstance(p, Rectangle)]
    assert [(b.get_x(), b.get_y(), b.get_width(), b.get_height()) for b in border] == [
        (0.0, 0.0, 60.0, 20.0)]
    polygons = [np.asarray(p.get_xy())[:4] for p in ax.patches
                if type(p).__name__ == "Polygon"]
    for o in obstacles:
        assert any(len(p) == 4 and np.allclose(p, o.corners()) for p in polygons), o
    for pose in (m.start, m.goal):
        arrow = next(p for p in ax.patches if isinstance(p, FancyArrow)
                     and p.get_label() == ("start" if pose is m.start else "goal"))
        tip = np.array([pose.x + 3.0 * math.cos(pose.yaw), pose.y + 3.0 * math.sin(pose.yaw)])
        assert np.min(np.hypot(*(arrow.get_xy() - tip).T)) < 1e-6, pose
    plt.close("all")


def test_fallback_and_hybrid_paths_draw_fainter_trees_and_no_tree_path() -> None:
    """A Dubins fallback's path is no tree path (no raw path, no waypoint chords); a
    search's fan is fainter than a grown tree; the raw tree path keeps every point."""
    m, base = _reverse_result()
    tree = Tree(np.array([[10.0, 10.0], [14.0, 12.0]]), np.array([-1, 0]))
    raw = np.array([[10.0, 10.0], [14.0, 12.0], [15.0, 10.0], [7.0, 18.0]])

    def figure(planner: str, stats: dict[str, float]) -> Any:
        r = PlanResult(PlanStatus.SOLVED, planner, base.path, raw, (tree,), 2, 0, 0.0,
                       stats=stats)
        return plot_plan(m, r).axes[0]

    grown = figure("rrt", {})
    np.testing.assert_allclose(np.column_stack(_line(grown, "raw tree path").get_data()), raw)
    fallback = figure("improved-rrt-connect", {"dubins_fallback": 1.0})
    labels = [line.get_label() for line in fallback.get_lines()]
    assert "raw tree path" not in labels and "waypoints" not in labels
    hybrid = figure("hybrid-a-star", {})

    def alpha(ax: Any) -> float:
        return next(c for c in ax.collections if isinstance(c, LineCollection)).get_alpha()

    assert alpha(hybrid) < alpha(grown) and alpha(fallback) < alpha(grown)
    plt.close("all")


@pytest.mark.parametrize("bounds", [(0.0, 0.0, 60.0, 8.0), (0.0, 0.0, 12.0, 50.0),
                                    (0.0, 0.0, 4.0, 60.0), (0.0, 0.0, 30.0, 30.0)])
def test_the_figure_size_follows_the_map_down_to_a_minimum_side(
    bounds: tuple[float, float, float, float],
) -> None:
    """The map's longer side gets 6.5 in, the shorter its share but at least 1.5 in,
    plus the legend's 2.6 in beside and the title's 1 in above (a 4 m x 60 m ramp got a
    figure too thin for its axis labels)."""
    w, h = bounds[2] - bounds[0], bounds[3] - bounds[1]
    long_side, short_side = 6.5, max(1.5, 6.5 * min(w, h) / max(w, h))
    want = (long_side, short_side) if w >= h else (short_side, long_side)
    got = map_figure_size(bounds)
    assert got == pytest.approx((want[0] + 2.6, want[1] + 1.0), abs=0.006)


def test_the_legend_sits_beside_the_map_not_on_it() -> None:
    """The legend is outside the axes, to their right (inside, it hid a goal)."""
    m, result = _reverse_result()
    fig = plot_plan(m, result)
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    legend = fig.axes[0].get_legend().get_window_extent(renderer)
    assert legend.x0 >= fig.axes[0].get_window_extent(renderer).x1
    plt.close(fig)


def test_the_curvature_plot_shows_each_segments_curvature_against_normalised_length() -> None:
    """x is arc length over the whole length (summed here), y the path's curvature; reverse
    dashed in another colour; the cusp line at the cusp; the limits at +-kappa_max; one
    legend entry per gear even when a gear comes back."""
    k = 0.2
    fwd1 = np.column_stack([np.linspace(0.0, 5.0, 51), np.zeros(51)])
    back = np.column_stack([np.full(31, 5.0), np.linspace(0.0, 3.0, 31)])
    fwd2 = np.column_stack([np.linspace(5.0, 9.0, 41), np.full(41, 3.0)])
    rows = _gear_rows([(1, fwd1), (-1, back), (1, fwd2)])
    rows[51:82, 3] = k  # the reverse leg's curvature column
    path = Path(rows, np.zeros((0, 2)))
    ax = plot_curvature(path, 0.25).axes[0]
    total = 5.0 + 3.0 + 4.0
    xs = np.concatenate([ln.get_xdata() for ln in ax.get_lines() if len(ln.get_xdata()) > 2])
    assert xs.min() == pytest.approx(0.0) and xs.max() == pytest.approx(1.0)
    curves = [ln for ln in ax.get_lines() if len(ln.get_xdata()) > 2]
    assert len(curves) == 3
    rev = curves[1]
    np.testing.assert_allclose(rev.get_ydata(), k)
    np.testing.assert_allclose(curves[0].get_ydata(), 0.0)
    np.testing.assert_allclose(rev.get_xdata()[[0, -1]], [5.0 / total, 8.0 / total])
    assert rev.get_linestyle() == "--" and curves[0].get_linestyle() == "-"
    assert mcolors.to_rgba(rev.get_color()) != mcolors.to_rgba(curves[0].get_color())
    vlines = [ln for ln in ax.get_lines() if ln.get_linestyle() == ":"]
    assert sorted(ln.get_xdata()[0] for ln in vlines) == pytest.approx(
        [5.0 / total, 8.0 / total])
    hlines = [ln for ln in ax.get_lines() if ln.get_linestyle() == "--" and ln is not rev]
    assert sorted(ln.get_ydata()[0] for ln in hlines) == pytest.approx([-0.25, 0.25])
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert labels.count("κ(s), forward") == 1 and labels.count("κ(s), reverse (dashed)") == 1
    assert "κ(s)" not in labels  # the bare name is for a forward-only path
    plt.close("all")


@pytest.mark.parametrize(("suffix", "magic"), [(".png", b"\x89PNG"), (".pdf", b"%PDF"),
                                               (".svg", b"<?xml")])
def test_a_saved_figure_has_its_files_format_and_size_and_is_closed(
    tmp_path: FsPath, suffix: str, magic: bytes
) -> None:
    """The file's format follows its suffix, a PNG is figsize x dpi pixels, nothing
    else is left in the folder and the figure is closed (bench grids made hundreds)."""
    fig = plt.figure(figsize=(3.0, 2.0))
    fig.add_subplot(111).plot([0, 1], [0, 1])
    out = tmp_path / f"f{suffix}"
    save_figure(fig, out, dpi=40)
    assert out.read_bytes()[: len(magic)] == magic
    assert [p.name for p in tmp_path.iterdir()] == [out.name]
    assert not plt.fignum_exists(fig.number)
    if suffix == ".png":
        assert imageio.imread(out).shape[:2] == (80, 120)


# ----------------------------------------------------------------------------- frames


@pytest.fixture(scope="module")
def road_canvas() -> Iterator[tuple[Any, tuple, SceneCanvas, SceneCanvas]]:
    """The overtake scene's road, with a canvas of its fixed view (the sky above the
    top wall, y 52-63 m, is empty ground) and a canvas that redraws everything."""
    from rrtdrive.envs.render import view_for
    from rrtdrive.sim.scenes import build_env

    scen = make_scenario("overtake", 0)
    env = build_env(scen)
    view = view_for(scen.map.bounds, scen.lane_y)
    yield env.unwrapped.road, view, SceneCanvas(*view), SceneCanvas(*view, reuse_static=False)
    env.close()


def _pixel(view: tuple, x: float, y: float) -> tuple[int, int]:
    """Row and column of a world point in a frame: centre at the frame's middle, +y up."""
    (w, h), s, (cx, cy) = view
    return int(round(h / 2.0 - (y - cy) * s)), int(round(w / 2.0 + (x - cx) * s))


def _near(frame: np.ndarray, rc: tuple[int, int], colour: tuple, r: int = 1) -> bool:
    """Whether ``colour`` is within ``r`` pixels of ``rc``."""
    patch = frame[rc[0] - r : rc[0] + r + 1, rc[1] - r : rc[1] + r + 1].reshape(-1, 3)
    return bool(np.any(np.all(patch.astype(int) == colour, axis=1)))


def _gear_path() -> tuple[np.ndarray, np.ndarray]:
    """Forward along y = 56 m from x = 20 to 40 m, then reverse on to x = 60 m."""
    fwd = np.column_stack([np.linspace(20.0, 40.0, 201), np.full(201, 56.0)])
    back = np.column_stack([np.linspace(40.0, 60.0, 201), np.full(201, 56.0)])
    rows = _gear_rows([(1, fwd), (-1, back)])
    return rows[:, :2], rows[:, 4]


def test_a_reverse_leg_is_dashed_each_metre_and_the_goal_and_cusp_show(road_canvas: Any) -> None:
    """At world points mapped to pixels here: forward in the path colour, reverse dashes
    of 1 m with 1 m gaps from the cusp, the cusp dot, the goal's ring; +y up."""
    road, view, canvas, _ = road_canvas
    xy, gears = _gear_path()
    goal = (70.0, 58.0)
    canvas.draw(road, 20, xy, goal, gears=gears)
    frame = canvas.frame([])
    assert _near(frame, _pixel(view, 30.0, 56.0), PATH_COLOR)
    assert not _near(frame, _pixel(view, 30.0, 56.0), REVERSE_COLOR)
    assert _near(frame, _pixel(view, 40.0, 56.0), CUSP_COLOR)
    for s in (2.5, 4.5, 10.5):  # inside a dash
        assert _near(frame, _pixel(view, 40.0 + s, 56.0), REVERSE_COLOR), s
    for s in (3.5, 5.5, 11.5):  # inside a gap
        assert not _near(frame, _pixel(view, 40.0 + s, 56.0), REVERSE_COLOR, r=2), s
    gr, gc = _pixel(view, *goal)
    ring = frame[gr - 4 : gr + 5, gc - 4 : gc + 5].reshape(-1, 3).astype(int)
    assert np.any(np.all(ring == GOAL_COLOR, axis=1))


def test_the_static_layer_is_redrawn_when_the_path_its_gears_or_goal_change(
    road_canvas: Any,
) -> None:
    """Every frame equals a full redraw when only the path, its gears or the goal change
    (a stale layer showed the previous path)."""
    road, _, fast, scratch = road_canvas
    xy, gears = _gear_path()
    steps = [(xy, np.ones(len(xy)), (70.0, 58.0)), (xy, gears, (70.0, 58.0)),
             (xy + [0.0, 3.0], gears, (70.0, 58.0)), (xy + [0.0, 3.0], gears, (72.0, 55.0))]
    previous = None
    for path, g, goal in steps:
        frames = []
        for canvas in (fast, scratch):
            canvas.draw(road, 20, path, goal, gears=g)
            frames.append(canvas.frame([]))
        np.testing.assert_array_equal(frames[0], frames[1])
        assert previous is None or not np.array_equal(previous, frames[0])
        previous = frames[0]


def test_path_pixels_are_highway_envs_own_pixel_of_each_point(road_canvas: Any) -> None:
    """The vectorised world-to-pixel map gives vec2pix's integers (truncated, not rounded)."""
    from rrtdrive.sim.render import _to_pixels

    road, _, canvas, _ = road_canvas
    canvas.draw(road, 20, np.zeros((0, 2)), None)
    pts = np.random.default_rng(0).uniform([0.0, 30.0], [100.0, 60.0], (200, 2))
    assert _to_pixels(canvas.surface, pts) == [list(canvas.surface.vec2pix(p)) for p in pts]


@pytest.mark.parametrize("corner", PANEL_CORNERS)
def test_the_panel_counts_the_points_it_covers_where_it_is_drawn(corner: str) -> None:
    """panel_hits counts a point at the drawn panel's middle and within reach_m metres
    of its edge, not farther; the panel is 6 px in from its corner of the frame."""
    view = ((960, 240), 14.4, (30.0, 5.0))
    canvas = SceneCanvas(*view)
    frame = canvas.frame(["a", "b", "c"], panel_width=290, corner=corner)
    ys, xs = np.nonzero(np.all(frame == 255, axis=-1))
    top, bottom, left, right = ys.min() - 1, ys.max() + 1, xs.min() - 1, xs.max() + 1
    (w, h), s, (cx, cy) = view
    assert min(left, w - 1 - right) == 6 and min(top, h - 1 - bottom) == 6

    def world(row: float, col: float) -> tuple[float, float]:
        return cx + (col - w / 2.0) / s, cy - (row - h / 2.0) / s

    mid = world((top + bottom) / 2.0, (left + right) / 2.0)
    inward = -1.0 if corner.endswith("right") else 1.0  # towards the frame's middle
    edge_col = right if inward > 0 else left
    near = world((top + bottom) / 2.0, edge_col + inward * 2.0 * s)  # 2 m off its side
    far = world((top + bottom) / 2.0, edge_col + inward * 5.0 * s)  # 5 m off
    v_edge = bottom if corner.startswith("top") else top
    v_in = 1.0 if corner.startswith("top") else -1.0
    below = world(v_edge + v_in * 6.0 * s, (left + right) / 2.0)  # 6 m past its far edge
    for pts, want in (([mid], 1), ([near], 1), ([far], 0), ([below], 0)):
        assert canvas.panel_hits(np.array(pts), 290, 3)[corner] == want, (pts, want)


# ----------------------------------------------------------------------------- videos


def _spy_lines(monkeypatch: pytest.MonkeyPatch) -> list[list[str]]:
    lines: list[list[str]] = []
    frame = SceneCanvas.frame

    def spy(self: SceneCanvas, text: Any, *args: Any, **kwargs: Any) -> np.ndarray:
        lines.append(list(text))
        return frame(self, text, *args, **kwargs)

    monkeypatch.setattr(SceneCanvas, "frame", spy)
    return lines


def test_the_read_out_gives_the_bicycles_curvature_and_the_paths_gear_changes(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """kappa = tan(steer) / wheelbase of the steer applied before the frame, and the
    path's gear change (one here: the line was left out below two)."""
    scen = overtake()
    n = 5
    states = np.column_stack([np.linspace(10.0, 14.0, n), np.full(n, scen.lane_y),
                              np.zeros(n), np.full(n, 1.0)])
    steer = np.array([0.1, 0.3, 0.5, 0.6])
    controls = np.column_stack([np.zeros(n - 1), steer])
    ep = logged_episode(scen, states, controls)
    y = scen.lane_y
    rows = _gear_rows([(1, np.column_stack([np.linspace(6.0, 20.0, 15), np.full(15, y)])),
                       (-1, np.column_stack([np.linspace(20.0, 12.0, 9), np.full(9, y)]))])
    ep = Episode(**{**ep.__dict__, "path": Path(rows, np.zeros((0, 2)))})
    lines = _spy_lines(monkeypatch)
    for _ in render_frames(ep, stride=1):
        pass
    assert len(lines) == n
    shown = [float(ln[1].split()[1]) for ln in lines]
    want = [0.0] + [math.tan(a) / scen.vehicle.wheelbase for a in steer]
    np.testing.assert_allclose(shown, want, atol=6e-4)
    assert all("gear changes: path 1" in ln for ln in lines)


def test_a_following_camera_looks_30_m_ahead_of_the_car() -> None:
    """On the long traffic road the view centres 30 m ahead of the ego (its green body
    sits left of the middle), so the road ahead shows."""
    scen = make_scenario("overtake-traffic", 4, density="low")
    n = 3
    x = np.array([10.0, 40.0, 70.0])
    states = np.column_stack([x, np.full(n, scen.lane_y), np.zeros(n), np.full(n, 8.0)])
    ep = logged_episode(scen, states, np.zeros((n - 1, 2)))
    view = scen.camera()
    (w, _), s = view.size, view.scaling
    for k, frame in enumerate(render_frames(ep, stride=1)):
        cols = np.nonzero(np.all(frame == (50, 200, 0), axis=-1))[1]
        assert len(cols), k
        body_centre = x[k] + scen.vehicle.wheelbase / 2.0  # rear axle to body middle
        want = w / 2.0 + (body_centre - (x[k] + 30.0)) * s
        assert abs(cols.mean() - want) < 1.5 * s, (k, cols.mean(), want)


def test_a_band_above_a_tall_map_leaves_the_map_where_it_was_drawn() -> None:
    """With the read-out's band above it (a 20 m x 60 m map), the map's view sits below
    the band unchanged: the car is at its fitted pixel plus the band's height."""
    from rrtdrive.sim.episode import DriveLog
    from rrtdrive.sim.render import panel_band
    from rrtdrive.sim.runner import EpisodeConfig
    from rrtdrive.sim.scenes import fit_view
    from rrtdrive.sim.tasks import CustomTask

    up = math.pi / 2
    tall = Map("tall", (0.0, 0.0, 20.0, 60.0), (), Pose(10.0, 4.0, up), Pose(10.0, 55.0, up))
    task = CustomTask.from_map(tall, 0)
    y = np.linspace(4.0, 55.0, 4)
    states = np.column_stack([np.full(4, 10.0), y, np.full(4, up), np.ones(4)])
    log = DriveLog(dt=0.05, t=np.arange(4) * 0.05, states=states, controls=np.zeros((3, 2)),
                   crashed=np.zeros(4, bool), others=np.zeros((4, 0, 4)),
                   other_sizes=np.zeros((0, 2)), arrived=True, wall_time_s=0.0)
    path = Path(np.column_stack([np.full(4, 10.0), y, np.full(4, up), np.zeros(4)]),
                np.zeros((0, 2)))
    ep = Episode(task, "given", "pure-pursuit", 0, None, path, log, "arrived", "",
                 EpisodeConfig())
    (w, h), s, (cx, cy) = fit_view(tall.bounds)
    band = panel_band(3)
    for k, frame in enumerate(render_frames(ep, stride=1)):
        assert frame.shape == (h + band, w, 3)
        rows, cols = np.nonzero(np.all(frame == (50, 200, 0), axis=-1))  # the ego's green
        body = y[k] + task.vehicle.wheelbase / 2.0  # rear axle to body middle
        want = (band + h / 2.0 - (body - cy) * s, w / 2.0 + (10.0 - cx) * s)
        assert len(rows) and abs(rows.mean() - want[0]) < 1.5 * s, (k, rows.mean(), want)
        assert abs(cols.mean() - want[1]) < 1.5 * s


def test_odd_frames_are_padded_by_their_edge_not_rescaled(
    tmp_path: FsPath, caplog: pytest.LogCaptureFixture
) -> None:
    """An odd-sized frame gains one row and column copied from its edge; the MP4 has the
    padded size and ffmpeg rescales nothing (imageio warned and rescaled)."""
    rng = np.random.default_rng(0)
    odd = rng.integers(0, 255, (33, 45, 3), dtype=np.uint8)
    even = even_frame(odd)
    assert even.shape == (34, 46, 3)
    np.testing.assert_array_equal(even[:33, :45], odd)
    np.testing.assert_array_equal(even[33, :45], odd[32])
    np.testing.assert_array_equal(even[:33, 45], odd[:, 44])
    assert even_frame(odd[:32, :44]).shape == (32, 44, 3)
    assert even_frame(odd[:, :44]).shape == (34, 44, 3)  # odd rows alone
    assert even_frame(odd[:32]).shape == (32, 46, 3)  # odd columns alone
    out = tmp_path / "odd.mp4"
    with caplog.at_level(logging.WARNING):
        assert write_frames([odd, odd], out, fps=10) == 2
    assert not [r for r in caplog.records if "macro_block_size" in r.getMessage()]
    frames, _ = _read(out)
    assert len(frames) == 2 and frames[0].shape == (34, 46, 3)


# ----------------------------------------------------------------------------- mp4 files


def test_a_failure_leaves_no_file_behind(tmp_path: FsPath, monkeypatch: pytest.MonkeyPatch) -> None:
    """A frame the encoder refuses at the end, an error in the caller's block and an
    encoder that cannot start each leave the folder empty (no temporary, no video)."""
    out = tmp_path / "v.mp4"
    with pytest.raises(ValueError, match="same size"):
        with Mp4Writer(out, fps=10) as w:
            w.append(np.zeros((32, 32, 3), np.uint8))
            w.append(np.zeros((48, 32, 3), np.uint8))  # refused in the writer thread
    assert list(tmp_path.iterdir()) == []
    with pytest.raises(RuntimeError, match="caller"):
        with Mp4Writer(out, fps=10) as w:
            w.append(np.zeros((32, 32, 3), np.uint8))
            raise RuntimeError("the caller's drawing failed")
    assert list(tmp_path.iterdir()) == []
    import imageio.v2

    def refuse(*args: Any, **kwargs: Any) -> Any:
        raise OSError("no encoder")

    monkeypatch.setattr(imageio.v2, "get_writer", refuse)
    with pytest.raises(OSError, match="no encoder"):
        Mp4Writer(out, fps=10)
    assert list(tmp_path.iterdir()) == []


def test_an_encoder_that_dies_publishes_nothing(tmp_path: FsPath) -> None:
    """ffmpeg killed before the end: close raises and neither the video nor a
    temporary file is left (imageio-ffmpeg does not look at its exit status)."""
    from rrtdrive.sim.mp4 import _encoder_process

    out = tmp_path / "v.mp4"
    w = Mp4Writer(out, fps=10)
    for _ in range(3):
        w.append(np.full((32, 32, 3), 90, np.uint8))
    process = None
    for _ in range(200):  # the writer thread starts ffmpeg with the first frame
        process = _encoder_process(w._writer)
        if process is not None:
            break
        time.sleep(0.01)
    assert process is not None
    process.send_signal(signal.SIGKILL)
    process.wait()
    with pytest.raises(OSError, match="ffmpeg"):
        w.close()
    assert list(tmp_path.iterdir()) == []


def test_a_second_close_after_a_failed_one_does_not_claim_the_video(tmp_path: FsPath) -> None:
    """close() returns the published file; after a failed close there is none to return."""
    w = Mp4Writer(tmp_path / "v.mp4", fps=10)
    w.append(np.zeros((32, 32, 3), np.uint8))
    w.append(np.zeros((48, 32, 3), np.uint8))  # refused by the encoder
    with pytest.raises(ValueError, match="same size"):
        w.close()
    with pytest.raises(RuntimeError, match="was not written"):
        w.close()  # returned tmp_path / "v.mp4", which does not exist
    assert not (tmp_path / "v.mp4").exists()
    good = Mp4Writer(tmp_path / "w.mp4", fps=10)
    good.append(np.zeros((32, 32, 3), np.uint8))
    assert good.close() == good.close() == tmp_path / "w.mp4"  # a published file, twice


# ----------------------------------------------------------------------------- RecordMP4


class FrameEnv(gym.Env):
    """A tiny env whose frames a test chooses; its metadata names no render_fps."""

    metadata = {"render_modes": ["rgb_array"]}

    def __init__(self, frames: Any, steps: int = 3, reuse: bool = False) -> None:
        self.render_mode = "rgb_array"
        self.observation_space = gym.spaces.Discrete(1)
        self.action_space = gym.spaces.Discrete(1)
        self.frames, self.steps, self.reuse = frames, steps, reuse
        self.buffer = np.zeros((16, 16, 3), np.uint8)
        self.k = 0

    def reset(self, *, seed: int | None = None, options: Any = None) -> tuple[int, dict]:
        super().reset(seed=seed)
        self.k = 0
        return 0, {}

    def step(self, action: Any) -> tuple[int, float, bool, bool, dict]:
        self.k += 1
        return 0, 0.0, self.k >= self.steps, False, {}

    def render(self) -> np.ndarray:
        frame = self.frames(self.k)
        if self.reuse:
            self.buffer[...] = frame
            return self.buffer
        return frame


def test_record_mp4_frames_rate_and_unfinished_episode(
    tmp_path: FsPath, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Without render_fps the video runs at 30 fps; float frames above 255 are clipped,
    not wrapped; close writes the unfinished episode (reset plus two steps: three
    frames); a frame handed to the encoder is a copy of a reused render buffer."""
    from rrtdrive.sim import mp4

    env = RecordMP4(FrameEnv(lambda k: np.full((16, 16, 3), 300.0 if k == 1 else 60.0),
                             steps=9), tmp_path / "a")
    assert env.fps == 30.0
    env.reset(seed=0)
    env.step(0)
    env.step(0)
    env.close()
    assert [p.name for p in (tmp_path / "a").iterdir()] == ["episode-0000.mp4"]
    frames, meta = _read(tmp_path / "a" / "episode-0000.mp4")
    assert meta["fps"] == pytest.approx(30.0) and len(frames) == 3
    means = [float(f.mean()) for f in frames]
    assert means[1] > 240.0 and max(means[0], means[2]) < 80.0, means  # 300 wrapped to 44

    handed: list[np.ndarray] = []
    append = mp4.Mp4Writer.append

    def spy(self: Mp4Writer, frame: np.ndarray) -> None:
        handed.append(frame)
        append(self, frame)

    monkeypatch.setattr(mp4.Mp4Writer, "append", spy)
    base = FrameEnv(lambda k: np.full((16, 16, 3), 40 * k, np.uint8), steps=2, reuse=True)
    env = RecordMP4(base, tmp_path / "b")
    env.reset(seed=0)
    env.step(0)
    env.step(0)
    env.close()
    assert len(handed) == 3 and not any(np.shares_memory(f, base.buffer) for f in handed)


@pytest.mark.parametrize("bad_at", ["reset", "step"])
def test_a_bad_frame_stops_the_recording_and_leaves_no_file(tmp_path: FsPath, bad_at: str) -> None:
    """A frame of no RGB shape at reset, or a size change mid-episode, raises and
    removes the unfinished video's temporary file."""
    if bad_at == "reset":
        base = FrameEnv(lambda k: np.zeros((16, 16), np.uint8))
    else:
        base = FrameEnv(lambda k: np.zeros((16 if k < 2 else 20, 16, 3), np.uint8))
    env = RecordMP4(base, tmp_path)
    with pytest.raises(InputError, match="render"):
        env.reset(seed=0)
        env.step(0)
        env.step(0)
    assert list(tmp_path.iterdir()) == []
    env.close()
    assert list(tmp_path.iterdir()) == []
