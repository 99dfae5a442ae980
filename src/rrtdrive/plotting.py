"""Matplotlib figures of maps, search trees and paths (headless, Agg backend)."""

from __future__ import annotations

import math
import os
import textwrap
import warnings
from collections.abc import Sequence
from pathlib import Path as FsPath
from typing import Any

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib import patheffects  # noqa: E402
from matplotlib.axes import Axes  # noqa: E402
from matplotlib.collections import LineCollection  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402
from matplotlib.patches import Polygon as PolygonPatch  # noqa: E402
from matplotlib.patches import Rectangle  # noqa: E402

from rrtdrive.atomic import atomic_target  # noqa: E402
from rrtdrive.maps import Map  # noqa: E402
from rrtdrive.types import Path, PlanResult, Pose, Tree, VehicleParams  # noqa: E402
from rrtdrive.vehicle import footprint_corners  # noqa: E402

__all__ = [
    "draw_map",
    "draw_trees",
    "draw_path",
    "draw_gear_path",
    "draw_pose",
    "plot_plan",
    "plot_check",
    "title_and_legend",
    "plot_curvature",
    "map_figure_size",
    "save_figure",
]

TREE_COLOURS = ("tab:blue", "tab:red")


def draw_map(ax: Axes, m: Map, show_query: bool = True) -> None:
    """Draw the bounds, the obstacles and (optionally) the start and goal cars.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        The axes to draw on; its limits (the bounds and a 2 % margin), equal aspect
        and axis labels (metres) are set.
    m : Map
        The map; its car (``m.vehicle``) is drawn at the start and the goal.
    show_query : bool
        Draw the start (green) and goal (purple) cars.
    """
    xmin, ymin, xmax, ymax = m.bounds
    ax.add_patch(Rectangle((xmin, ymin), xmax - xmin, ymax - ymin, fill=False, lw=2.0, ec="black"))
    for o in m.obstacles:
        ax.add_patch(PolygonPatch(o.corners(), closed=True, fc="0.35", ec="0.15", lw=0.5))
    if show_query:
        draw_pose(ax, m.start, m.vehicle, "tab:green", "start")
        draw_pose(ax, m.goal, m.vehicle, "tab:purple", "goal")
    pad = 0.02 * max(xmax - xmin, ymax - ymin)
    ax.set_xlim(xmin - pad, xmax + pad)
    ax.set_ylim(ymin - pad, ymax + pad)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")


def draw_pose(
    ax: Axes, pose: Pose, vehicle: VehicleParams, colour: str, label: str | None = None
) -> None:
    """Draw the car's body at ``pose`` and an arrow along its heading.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        The axes to draw on.
    pose : Pose
        Rear-axle pose (metres, radians).
    vehicle : VehicleParams
        The car whose body is drawn.
    colour : str
        Matplotlib colour of the body and the arrow.
    label : str, optional
        Legend entry of the arrow; ``None``: none.
    """
    corners = footprint_corners(np.array(pose.as_tuple()), vehicle)
    ax.add_patch(PolygonPatch(corners, closed=True, fc=colour, ec=colour, alpha=0.35, lw=1.0))
    # Above the path (zorder 4): a path leaves along the start's heading and hid its arrow.
    ax.arrow(
        pose.x,
        pose.y,
        3.0 * math.cos(pose.yaw),
        3.0 * math.sin(pose.yaw),
        head_width=1.0,
        length_includes_head=True,
        color=colour,
        label=label,
        zorder=6,
    )


def draw_trees(
    ax: Axes, trees: Sequence[Tree], lw: float = 0.5, alpha: float = 0.6, label: bool = True
) -> None:
    """Draw each tree's edges (first tree blue, second red) and nodes.

    With ``label``, the legend names the colours: "tree" for a single tree, else
    "tree from the start" (blue) and "tree from the goal" (red), once each.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        The axes to draw on.
    trees : sequence of Tree
        The search trees, the start's first; a tree of its root alone is skipped.
    lw, alpha : float
        Line width of the edges (points) and opacity of edges and nodes.
    label : bool
        Name the trees in the legend.
    """
    names = ("tree",) if len(trees) == 1 else ("tree from the start", "tree from the goal")
    named: set[str] = set()
    for tree, colour in zip(trees, TREE_COLOURS * 4, strict=False):
        if len(tree) < 2:
            continue  # a root alone has no edge to show (the legend listed it)
        name = names[TREE_COLOURS.index(colour) % len(names)]
        ax.add_collection(LineCollection(
            tree.edges(), colors=colour, lw=lw, alpha=alpha,
            label=name if label and name not in named else None,
        ))  # fmt: skip
        named.add(name)
        ax.plot(tree.nodes[:, 0], tree.nodes[:, 1], ".", ms=2, color=colour, alpha=alpha)


def draw_path(
    ax: Axes,
    xy: np.ndarray,
    colour: str = "tab:orange",
    label: str | None = None,
    lw: float = 2.0,
    marker: str | None = None,
) -> None:
    """Draw a polyline or sampled path ``(N, >=2)``.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        The axes to draw on.
    xy : numpy.ndarray
        ``(N, >=2)`` rows whose first two columns are x, y (metres); empty: nothing.
    colour : str
        Matplotlib colour of the line.
    label : str, optional
        Legend entry; ``None``: none.
    lw : float
        Line width in points.
    marker : str, optional
        Matplotlib marker drawn at each row; ``None``: none.
    """
    xy = np.asarray(xy)
    if len(xy):
        ax.plot(xy[:, 0], xy[:, 1], color=colour, lw=lw, label=label, marker=marker, ms=4)


def draw_gear_path(
    ax: Axes,
    path: Path,
    forward: str = "tab:orange",
    reverse: str = "tab:cyan",
    lw: float = 2.0,
    label: str = "path",
) -> None:
    """Draw a path's gear segments: forward solid, reverse dashed in another colour, cusps as x.

    The legend gets one entry per kind present: ``"<label>"`` (``"<label>, forward"``
    when the path reverses), ``"<label>, reverse (dashed)"`` and ``"cusp (gear change)"``.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        The axes to draw on.
    path : Path
        The path to draw.
    forward, reverse : str
        Matplotlib colours of the forward and the reverse segments.
    lw : float
        Line width in points.
    label : str
        The path's name in the legend.
    """
    reverses = not path.is_forward_only
    seen: set[str] = set()
    for a, b in path.segments():
        xy = path.xy[a:b]
        if path.gears[a] > 0:
            kind, colour, ls = (f"{label}, forward" if reverses else label), forward, "-"
        else:
            kind, colour, ls = f"{label}, reverse (dashed)", reverse, "--"
        # Above the trees and waypoints, with a white edge: short reverse legs inside a
        # tree's fan were hidden under it (a user audit, session 35).
        ax.plot(
            xy[:, 0], xy[:, 1], color=colour, lw=lw, ls=ls,
            label=None if kind in seen else kind, zorder=4,
            path_effects=[patheffects.withStroke(linewidth=lw + 2.0, foreground="white")],
        )
        seen.add(kind)
    cusps = path.cusps
    if len(cusps):
        ax.plot(
            path.xy[cusps, 0], path.xy[cusps, 1], "X", color="black", ms=8, mew=0.5,
            mfc="yellow", ls="none", label=f"cusp (gear change, {len(cusps)})", zorder=5,
        )


#: The map's longer side on the page, inches; its shorter side follows the map's aspect,
#: down to :data:`_MIN_SIDE_IN` (a 60 m x 8 m kerbside in a square figure took a sixth of it).
_MAP_SIDE_IN = 6.5
_MIN_SIDE_IN = 1.5
#: Room beside and above the map: the legend (outside, to the right), title and labels.
_LEGEND_IN = 2.6
_TITLE_IN = 1.0
_TITLE_PT = 12.0


def map_figure_size(bounds: tuple[float, float, float, float]) -> tuple[float, float]:
    """A figure size (inches) whose map axes follow the bounds' aspect, legend beside.

    Parameters
    ----------
    bounds : tuple of float
        The map's ``(xmin, ymin, xmax, ymax)`` in metres.

    Returns
    -------
    width, height : float
        Inches, rounded to 0.01; the map's longer side takes 6.5 of them.

    Examples
    --------
    >>> map_figure_size((0.0, 0.0, 60.0, 60.0))
    (9.1, 7.5)
    >>> map_figure_size((0.0, 0.0, 60.0, 8.0))
    (9.1, 2.5)
    """
    xmin, ymin, xmax, ymax = bounds
    width, height = max(xmax - xmin, 1e-9), max(ymax - ymin, 1e-9)
    if width >= height:
        w_in, h_in = _MAP_SIDE_IN, max(_MIN_SIDE_IN, _MAP_SIDE_IN * height / width)
    else:
        w_in, h_in = max(_MIN_SIDE_IN, _MAP_SIDE_IN * width / height), _MAP_SIDE_IN
    return round(w_in + _LEGEND_IN, 2), round(h_in + _TITLE_IN, 2)


def plot_plan(
    m: Map, result: PlanResult, title: str | None = None, seed: int | None = None,
    reverse: bool = False,
) -> Figure:
    """The map, the trees, the raw tree path, the waypoints and the final path of one result.

    The path is drawn by :func:`draw_gear_path`: reverse segments dashed, cusps marked.
    The raw tree path and the waypoints only where a tree path was grown (not for a
    Hybrid A* or Dubins fallback path). The default title names the map, the planner
    (and its stage that solved it, when another: the default's Hybrid A* escalation),
    ``seed`` (when given), whether ``reverse`` gears were allowed, the status (solved: the
    length and the gear changes) and the nodes, and under it a failure's why line; it is
    left-aligned and wrapped to the figure (a tall map's narrow figure cut a one-line
    title at both ends).

    Parameters
    ----------
    m : Map
        The map planned on.
    result : PlanResult
        The planner's result (its trees, raw path, path, status and diagnosis).
    title : str, optional
        Replaces the default title (read by matplotlib as given, math included).
    seed : int, optional
        Named in the default title.
    reverse : bool
        Say "reverse allowed" in the default title.

    Returns
    -------
    matplotlib.figure.Figure
        A new figure; :func:`save_figure` saves and closes it.
    """
    from rrtdrive.planning.hybrid.escalation import stage_of

    width_in, height_in = map_figure_size(m.bounds)
    fig, ax = plt.subplots(figsize=(width_in, height_in), layout="constrained")
    draw_map(ax, m)
    stage = stage_of(result) if result.success else result.planner
    # A tree path only where one was grown: a Hybrid A* path's "raw path" is the path
    # itself, and the Dubins fallback's joins its ends with a line that crossed a car;
    # its waypoints (start, cusps, goal) joined by chords crossed obstacles (an audit).
    tree_path = "hybrid-a-star" not in (stage, result.planner) and stage != "dubins-fallback"
    # A search's fan of arcs, dense about the ends, is drawn fainter: it hid a
    # multi-point turn's short legs and both cars.
    draw_trees(ax, result.trees, alpha=0.6 if tree_path else 0.25)
    if tree_path:
        draw_path(ax, result.raw_path, "tab:gray", "raw tree path", lw=1.0)
    if len(result.path):
        if tree_path:
            draw_path(ax, result.path.waypoints, "tab:olive", "waypoints", lw=0.8, marker="o")
        draw_gear_path(ax, result.path)

    how = (f", seed {seed}" if seed is not None else "") + (", reverse allowed" if reverse else "")
    who = result.planner if stage == result.planner else f"{result.planner} ({stage} stage)"
    if result.success:
        cusps = len(result.path.cusps)
        gears = f", {cusps} gear change{'s' if cusps != 1 else ''}" if cusps else ""
        status = f"solved, {result.path.length:.1f} m{gears}"
    else:
        status = result.status.value
    text = title or f"{m.name}: {who}{how} ({status}, {result.nodes} nodes)"
    if title is None and not result.success and result.diagnosis is not None:
        text += f"\nwhy: {result.diagnosis.message}"
    title_and_legend(fig, ax, text, height_in, parse_math=title is not None)
    return fig


def title_and_legend(
    fig: Figure, ax: Axes, text: str, height_in: float, parse_math: bool
) -> None:
    """A left-aligned title wrapped to the figure, the figure grown for it, and the legend.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure, whose height grows by a line for each title line past two.
    ax : matplotlib.axes.Axes
        The map's axes: the title goes above it, the legend beside it.
    text : str
        The title; its lines are wrapped to the figure's width.
    height_in : float
        The figure's height before the title, inches.
    parse_math : bool
        Let matplotlib read ``$...$`` as math (a title the caller gave), or not (free
        text such as a map's name).
    """
    # About 0.6 em a character; the room is the figure's width (the legend's too).
    per_line = max(20, int((fig.get_figwidth() - 0.6) * 72 / (0.6 * _TITLE_PT)))
    wrapped = "\n".join(
        textwrap.fill(line, per_line, break_on_hyphens=False, break_long_words=False)
        for line in text.split("\n")
    )
    # Room for each title line past two (a why line of four lines over a 60 x 8 m map cut
    # the title's first line and the axis label off).
    extra = max(0, wrapped.count("\n") - 1) * _TITLE_PT * 1.25 / 72
    fig.set_figheight(height_in + extra)
    # The default title is free text: a map named "$x^$" is no formula (mathtext raised);
    # a title given is matplotlib's to read, as anywhere else.
    ax.set_title(wrapped, loc="left", fontsize=_TITLE_PT, parse_math=parse_math)
    # Beside the axes, outside them: inside, it covered a corner of the map (a goal in
    # the garage's top right bays hid under it).
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, frameon=False)


#: How the title of :func:`plot_check` names a failed check (else its field, less ``_ok``).
_CHECK_NAMES = {"collision_free": "collision", "endpoints_ok": "ends", "kappa_ok": "kappa column",
                "travel_ok": "direction of travel"}


def plot_check(m: Map, path: Path, check: Any, name: str = "") -> Figure:
    """The map, a checked path and where the check failed: ``rrtdrive verify --plot``.

    The path is drawn by :func:`draw_gear_path`; the car's body at the first pose that
    collides (``check.first_collision``) in red, named with what it hits. The title
    names the map and ``name`` (the plan file), the verdict and the failed checks.

    Parameters
    ----------
    m : Map
        The map checked against (its start and goal drawn).
    path : Path
        The path checked.
    check : PathCheck
        :func:`rrtdrive.verify.verify_path`'s result for them.
    name : str
        The plan's name in the title (its file); empty: none.

    Returns
    -------
    matplotlib.figure.Figure
        A new figure; :func:`save_figure` saves and closes it.
    """
    width_in, height_in = map_figure_size(m.bounds)
    fig, ax = plt.subplots(figsize=(width_in, height_in), layout="constrained")
    draw_map(ax, m)
    if len(path):
        draw_gear_path(ax, path)
    if check.first_collision is not None:
        draw_pose(ax, Pose(*check.first_collision), m.vehicle, "tab:red",
                  label=f"first collision: {check.collides_with}")  # fmt: skip
    failed = [_CHECK_NAMES.get(f, f.removesuffix("_ok").replace("_", " ")) for f in check.failed]
    verdict = "OK, every check passed" if check.ok else "FAILED: " + ", ".join(failed)
    what = f"{m.name}: {name}" if name else m.name
    text = f"{what}: {verdict} ({len(path)} rows, {path.length:.1f} m)"
    title_and_legend(fig, ax, text, height_in, parse_math=False)
    return fig


def plot_curvature(path: Path, kappa_max: float, ax: Axes | None = None) -> Figure:
    """Curvature against normalised path length (the paper's Figs. 14 and 16).

    Reverse segments are dashed in another colour, cusps dotted vertical lines.

    Parameters
    ----------
    path : Path
        The path whose curvature column is drawn.
    kappa_max : float
        The curvature limit (1/m), drawn as dashed lines at ``+-kappa_max``.
    ax : matplotlib.axes.Axes, optional
        The axes to draw on; ``None``: a new 7 x 3 inch figure.

    Returns
    -------
    matplotlib.figure.Figure
        The figure of ``ax``, or the new one.
    """
    # Constrained layout: on its own figure the x label was clipped at the bottom.
    fig = ax.figure if ax is not None else plt.figure(figsize=(7, 3), layout="constrained")
    ax = ax or fig.add_subplot(111)
    s = path.arc_length()
    u = s / max(s[-1], 1e-9) if len(s) else s
    reverses = not path.is_forward_only
    for i, (a, b) in enumerate(path.segments()):
        fwd = path.gears[a] > 0
        label = ("κ(s)" if not reverses else "κ(s), forward") if fwd else "κ(s), reverse (dashed)"
        first = all(path.gears[c] != path.gears[a] for c, _ in path.segments()[:i])
        ax.plot(
            u[a:b], path.samples[a:b, 3], color="tab:blue" if fwd else "tab:cyan",
            ls="-" if fwd else "--", label=label if first else None,
        )
    for c in path.cusps:
        ax.axvline(u[c], color="0.5", lw=0.8, ls=":", label="cusp" if c == path.cusps[0] else None)
    for sign in (1, -1):
        ax.axhline(
            sign * kappa_max, color="tab:red", ls="--", lw=1.0, label="±κ_max" if sign > 0 else None
        )
    ax.set_xlabel("normalised path length")
    ax.set_ylabel("curvature [1/m]")
    # Beside the axes: inside, it covered the curve.
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, borderaxespad=0.0)
    return fig


def save_figure(fig: Figure, path: str | os.PathLike[str], dpi: int = 110) -> None:
    """Save ``fig`` atomically (temporary file in the same folder, then rename) and close it.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure; closed afterwards, also when saving fails.
    path : str or os.PathLike
        The file to write; its suffix picks the format (PNG without one).
    dpi : int
        Resolution in dots per inch.
    """
    suffix = FsPath(path).suffix or ".png"
    # The same figure, the same bytes, in every format (PNG already was): no creation
    # date in an SVG or PDF, and an SVG's clip-path ids from a fixed salt (an audit).
    metadata = {".svg": {"Date": None}, ".pdf": {"CreationDate": None}}.get(suffix.lower())
    try:
        with (
            atomic_target(path, suffix) as tmp,
            warnings.catch_warnings(),
            plt.rc_context({"svg.hashsalt": "rrtdrive"}),
        ):
            # A map name in a script the font lacks (an emoji) is drawn as a box; the
            # figure is still right, so no two-line warning on stderr.
            warnings.filterwarnings("ignore", message="Glyph .* missing from", category=UserWarning)
            fig.savefig(tmp, dpi=dpi, metadata=metadata)
    finally:
        plt.close(fig)
