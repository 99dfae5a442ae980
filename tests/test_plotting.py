"""Figures render headless (Agg); reverse segments and cusps are drawn apart."""

from __future__ import annotations

import math

import matplotlib.image as mpimg
import numpy as np
import pytest

from rrtdrive.cli import main
from rrtdrive.maps import Map, builtin_map
from rrtdrive.planning import PlanningProblem, make_planner
from rrtdrive.plotting import plot_curvature, plot_plan, save_figure
from rrtdrive.types import Budget, Path, PlanResult, PlanStatus, Pose, Tree


def _reverse_result() -> tuple[Map, PlanResult]:
    xs = np.linspace(10.0, 15.0, 26)
    fwd = np.column_stack([xs, np.full(26, 10.0), np.zeros(26), np.zeros(26), np.ones(26)])
    k = 0.125
    s = np.linspace(0.0, (math.pi / 2) / k, 64)
    back = np.column_stack([
        15.0 - np.sin(k * s) / k, 10.0 + (1.0 - np.cos(k * s)) / k, -k * s,
        np.full_like(s, k), -np.ones_like(s),
    ])
    path = Path(np.vstack([fwd, back]), np.array([[10.0, 10.0], [15.0, 10.0], [7.0, 18.0]]))
    m = Map("reverse", (0.0, 0.0, 40.0, 40.0), (), Pose(10.0, 10.0, 0.0),
            Pose(7.0, 18.0, -math.pi / 2))
    result = PlanResult(PlanStatus.SOLVED, "hand-made", path, path.waypoints, (), 0, 0, 0.0)
    return m, result


def test_reverse_path_figure_renders(tmp_path):
    m, result = _reverse_result()
    fig = plot_plan(m, result)
    ax = fig.axes[0]
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "path, forward" in labels and "path, reverse (dashed)" in labels
    assert any(t.startswith("cusp") for t in labels)
    styles = {line.get_label(): line.get_linestyle() for line in ax.get_lines()}
    assert styles["path, forward"] == "-" and styles["path, reverse (dashed)"] == "--"
    colours = {line.get_label(): line.get_color() for line in ax.get_lines()}
    assert colours["path, forward"] != colours["path, reverse (dashed)"]
    cusp = next(line for line in ax.get_lines() if line.get_label().startswith("cusp"))
    np.testing.assert_allclose(np.column_stack(cusp.get_data()), [[15.0, 10.0]])
    out = tmp_path / "reverse.png"
    save_figure(fig, out)
    image = mpimg.imread(out)
    assert image.shape[0] > 100 and image[..., :3].std() > 0.01  # not blank

    fig = plot_curvature(result.path, 1 / 6)
    labels = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert "κ(s), reverse (dashed)" in labels and "cusp" in labels
    save_figure(fig, tmp_path / "kappa.png")


def test_forward_path_keeps_one_path_entry(tmp_path):
    m, result = _reverse_result()
    fwd = Path(result.path.samples[:26, :4], result.path.waypoints)
    m = Map("fwd", m.bounds, (), m.start, Pose(15.0, 10.0, 0.0))
    result = PlanResult(PlanStatus.SOLVED, "hand-made", fwd, fwd.waypoints, (), 0, 0, 0.0)
    fig = plot_plan(m, result)
    labels = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert "path" in labels and not any("reverse" in t or "cusp" in t for t in labels)
    save_figure(fig, tmp_path / "fwd.png")


def _axes_box_fraction(fig) -> tuple[float, float]:
    """The map axes' drawn box (after the equal aspect) as shares of the figure's size."""
    fig.canvas.draw()
    box = fig.axes[0].get_window_extent()
    return box.width / fig.bbox.width, box.height / fig.bbox.height


def test_the_figure_follows_the_maps_aspect():
    # A 60 m x 8 m street in a square figure filled a sixth of its height.
    m, result = _reverse_result()
    for bounds in ((0.0, 0.0, 60.0, 8.0), (0.0, 0.0, 40.0, 40.0), (0.0, 0.0, 12.0, 50.0)):
        wide = Map("aspect", bounds, (), Pose(3.0, 2.0, 0.0), Pose(6.0, 4.0, 0.0))
        fig = plot_plan(wide, result)
        w_share, h_share = _axes_box_fraction(fig)
        # The long side of the map takes most of its side of the figure (the legend
        # sits beside the map, the title above it).
        xmin, ymin, xmax, ymax = bounds
        long_share = w_share if xmax - xmin >= ymax - ymin else h_share
        assert long_share > 0.55, (bounds, w_share, h_share)
        assert w_share * h_share > 0.3, (bounds, w_share, h_share)
        # Equal axes: the drawn box keeps the map's proportions (padding included).
        box = fig.axes[0].get_window_extent()
        pad = 0.04 * max(xmax - xmin, ymax - ymin)  # draw_map's margin, both sides
        ratio = (xmax - xmin + pad) / (ymax - ymin + pad)
        assert math.isclose(box.width / box.height, ratio, rel_tol=0.05)


@pytest.mark.parametrize(("planner", "names"), [
    ("rrt-connect", ["tree from the start", "tree from the goal"]), ("rrt", ["tree"]),
])
def test_the_legend_names_the_trees(planner, names):
    m = builtin_map("overtake")
    result = make_planner(planner).solve(
        PlanningProblem.from_map(m), np.random.default_rng(0), Budget()
    )
    labels = [t.get_text() for t in plot_plan(m, result).axes[0].get_legend().get_texts()]
    assert [t for t in labels if t.startswith("tree")] == names


def test_the_plan_plot_title_names_seed_and_reverse(monkeypatch, tmp_path, capsys):
    import rrtdrive.plotting

    figures = []
    monkeypatch.setattr(rrtdrive.plotting, "save_figure", lambda fig, _: figures.append(fig))
    assert main(["plan", "overtake", "--seed", "5", "--reverse", "--plot",
                 str(tmp_path / "p.png")]) == 0
    title = " ".join(figures[0].axes[0].get_title(loc="left").split())  # wrapped lines
    assert title.startswith("overtake: improved-rrt-connect, seed 5, reverse allowed (solved, ")
    # A planner that cannot reverse is not said to have been allowed to (it plans forward).
    assert main(["plan", "narrow_gap", "--planner", "rrt", "--reverse", "--plot",
                 str(tmp_path / "p.png")]) == 0
    assert figures[1].axes[0].get_title(loc="left").startswith("narrow_gap: rrt, seed 0 (solved, ")
    # The default's escalation: the stage that solved it is named.
    assert main(["plan", "kerbside", "--reverse", "--plot", str(tmp_path / "p.png")]) == 0
    title = " ".join(figures[2].axes[0].get_title(loc="left").split())
    assert title.startswith("kerbside: improved-rrt-connect (hybrid-a-star stage), seed 0, ")


def test_a_tall_maps_plot_title_stays_inside_the_figure():
    # A 20 m x 60 m map's figure is 4.1 in wide: the one-line title lost both ends
    # ("roved-rrt-connect, seed 0, reverse allowed (solved, 2 node").
    m, result = _reverse_result()
    tall = Map("a_tall_ramp_with_a_long_name", (0.0, 0.0, 20.0, 60.0), (), Pose(5.0, 5.0, 1.57),
               Pose(15.0, 55.0, 1.57))
    fig = plot_plan(tall, result, seed=12345, reverse=True)
    fig.canvas.draw()
    text = fig.axes[0]._left_title
    box, page = text.get_window_extent(), fig.bbox
    assert page.x0 <= box.x0 and box.x1 <= page.x1 and box.y1 <= page.y1, (box, page)
    assert " ".join(text.get_text().split()).startswith("a_tall_ramp_with_a_long_name: ")


def test_a_solved_plots_title_gives_its_length_and_gear_changes():
    # The title gave the status and the nodes only (a plot audit).
    m, result = _reverse_result()
    title = " ".join(plot_plan(m, result).axes[0].get_title(loc="left").split())
    assert f"(solved, {result.path.length:.1f} m, 1 gear change, 0 nodes)" in title


def test_a_failed_plots_title_says_why_and_the_figure_has_room_for_it(tmp_path):
    # A failure showed its status alone; on a 60 x 8 m map a four-line title would have
    # cut its first line and the axis label off the figure.
    m = builtin_map("kerbside")
    result = make_planner("improved-rrt-connect").solve(
        PlanningProblem.from_map(m), np.random.default_rng(0), Budget()
    )
    assert not result.success and result.diagnosis is not None
    fig = plot_plan(m, result)
    text = fig.axes[0]._left_title
    assert " ".join(text.get_text().split()).endswith(
        " ".join(f"why: {result.diagnosis.message}".split())
    )
    fig.canvas.draw()
    box, page = text.get_window_extent(), fig.bbox
    assert page.y0 <= box.y0 and box.y1 <= page.y1, (box, page)
    label = fig.axes[0].xaxis.label.get_window_extent()
    assert label.y0 >= page.y0, (label, page)


def test_a_hybrid_path_is_drawn_without_chords_or_a_raw_tree_path():
    # Its waypoints (start, cusps, goal) joined by straight chords crossed obstacles, and
    # its "raw tree path" lay under the path (a plot audit).
    m = builtin_map("parking_lot")
    m = Map(m.name, m.bounds, m.obstacles, m.start, Pose(66.5, 22.0, math.pi / 2))
    result = make_planner("hybrid-a-star").solve(
        PlanningProblem.from_map(m, reverse=True), np.random.default_rng(0), Budget()
    )
    assert result.success and len(result.path.cusps) >= 1
    labels = [t.get_text() for t in plot_plan(m, result).axes[0].get_legend().get_texts()]
    assert "waypoints" not in labels and "raw tree path" not in labels
    assert any(t.startswith("path, reverse") for t in labels)


def test_a_tree_of_one_node_is_not_in_the_legend():
    m, result = _reverse_result()
    lone = Tree(np.array([[7.0, 18.0]]), np.array([-1]))
    grown = Tree(np.array([[10.0, 10.0], [12.0, 11.0]]), np.array([-1, 0]))
    result = PlanResult(PlanStatus.SOLVED, "hand-made", result.path, result.raw_path,
                        (grown, lone), 0, 0, 0.0)
    labels = [t.get_text() for t in plot_plan(m, result).axes[0].get_legend().get_texts()]
    assert "tree from the start" in labels and "tree from the goal" not in labels


def test_the_start_arrow_is_drawn_above_the_path():
    m, result = _reverse_result()
    ax = plot_plan(m, result).axes[0]
    path_z = max(z.get_zorder() for z in ax.get_lines() if z.get_label() == "path, forward")
    arrows = [p for p in ax.patches if p.get_label() in ("start", "goal")]
    assert arrows and min(a.get_zorder() for a in arrows) > path_z


@pytest.mark.parametrize("suffix", [".png", ".svg", ".pdf"])
def test_the_same_plot_is_the_same_bytes_in_every_format(tmp_path, suffix):
    """An SVG carried its creation date and random clip-path ids, a PDF its date: two
    saves of one plan differed (an audit). Saved a second apart, so a date would show."""
    import time

    m, result = _reverse_result()
    files = []
    for k in range(2):
        if k:
            time.sleep(1.1)
        out = tmp_path / f"plan{k}{suffix}"
        save_figure(plot_plan(m, result), out)
        files.append(out.read_bytes())
    assert files[0] == files[1] and len(files[0]) > 1000
