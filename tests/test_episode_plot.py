"""``rrtdrive simulate --plot``: the episode figure shows what the drive did.

The series are checked against the trajectory CSV the same run writes (its own code)
and the report's metrics; the map view against the drive's extent.
"""

from __future__ import annotations

import csv
import json
import math

import numpy as np
import pytest

from rrtdrive.cli import main


@pytest.fixture(scope="module")
def drive(tmp_path_factory):
    """A 200 m long map, a given 40 m path with a bend, driven with LQR; plot, CSV, JSON."""
    folder = tmp_path_factory.mktemp("drive")
    m = {"name": "long", "bounds": [0, 0, 200, 20], "obstacles": [],
         "start": [5, 8, 0], "goal": [45, 12, 0]}  # fmt: skip
    (folder / "long.json").write_text(json.dumps(m))
    # A gentle S-bend: y = 8 + 4 sin^2(pi (x - 5) / 80), yaw its slope, kappa 0 (kappa
    # is only the controllers' preview here).
    x = np.arange(5.0, 45.0001, 0.2)
    y = 8.0 + 4.0 * np.sin(math.pi * (x - 5.0) / 80.0) ** 2
    yaw = np.arctan(4.0 * math.pi / 80.0 * np.sin(2 * math.pi * (x - 5.0) / 80.0))
    rows = np.column_stack([x, y, yaw]).round(9)
    (folder / "path.json").write_text(json.dumps({"path": rows.tolist()}))
    out = {k: folder / v for k, v in
           (("png", "ep.png"), ("csv", "t.csv"), ("json", "s.json"))}  # fmt: skip
    code = main(["simulate", str(folder / "long.json"), "--path", str(folder / "path.json"),
                 "--controller", "lqr", "--plot", str(out["png"]), "--trajectory",
                 str(out["csv"]), "--json", str(out["json"])])  # fmt: skip
    return code, out, folder


def test_the_cli_writes_the_figure_and_names_it(drive):
    code, out, _ = drive
    assert code == 0
    assert out["png"].read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert json.loads(out["json"].read_text())["plot"] == str(out["png"])


def test_the_series_are_the_drive_and_the_limits_the_car(drive):
    from rrtdrive.maps import load_map
    from rrtdrive.pose_rows import path_from_poses
    from rrtdrive.sim.episode_plot import plot_episode
    from rrtdrive.sim.runner import run_episode
    from rrtdrive.sim.tasks import CustomTask
    from rrtdrive.types import Pose

    _, out, folder = drive
    rows = np.array(json.loads((folder / "path.json").read_text())["path"])
    path = path_from_poses(rows)
    task = CustomTask.from_map(load_map(folder / "long.json"), 0,
                               start=Pose(*rows[0]), goal=Pose(*rows[-1]))  # fmt: skip
    episode = run_episode(task, path, "lqr", 0)
    fig = plot_episode(episode)
    ax_map, speed, steer, rate, cte = fig.axes
    traj = list(csv.DictReader(out["csv"].open()))
    t = np.array([float(r["t"]) for r in traj])
    # The seeded drive is the CLI's: the same series as its trajectory file.
    assert np.allclose(speed.lines[0].get_ydata(), [float(r["speed"]) for r in traj])
    assert np.allclose(steer.lines[0].get_ydata(),
                       np.degrees([float(r["steer"]) for r in traj]))  # fmt: skip
    expected_rate = np.degrees(np.diff([float(r["steer"]) for r in traj]) / np.diff(t))
    assert np.allclose(rate.lines[0].get_ydata(), expected_rate)
    # The limits drawn are the car's: 30 deg and 0.4 rad/s.
    assert [ln.get_ydata()[0] for ln in steer.lines[1:]] == pytest.approx([30.0, -30.0])
    assert [ln.get_ydata()[0] for ln in rate.lines[1:]] == pytest.approx(
        [math.degrees(0.4), -math.degrees(0.4)])
    # The cross-track error is the report's: its largest magnitude is cte_max_m.
    report = json.loads(out["json"].read_text())
    assert np.max(np.abs(cte.lines[0].get_ydata())) == pytest.approx(
        report["cte_max_m"], rel=1e-4, abs=1e-6)
    # The map view is the drive's, not the 200 m map's: x from 0 to 45 + 10 m.
    assert ax_map.get_xlim() == pytest.approx((0.0, 55.0), abs=0.3)
    [driven] = [ln for ln in ax_map.lines if ln.get_label() == "driven (rear axle)"]
    assert np.allclose(driven.get_xdata(), [float(r["x"]) for r in traj])


def test_plot_outputs_are_checked_before_the_drive(drive, capsys):
    _, out, folder = drive
    args = ["simulate", str(folder / "long.json"), "--path", str(folder / "path.json")]
    assert main([*args, "--plot", str(folder / "ep.txt")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("rrtdrive simulate: error: --plot:") and err.count("\n") == 1
    assert main([*args, "--plot", str(out["png"]), "--json", str(out["png"])]) == 2
    assert "--plot" in capsys.readouterr().err


def test_other_cars_are_drawn_where_the_log_has_them():
    """Traffic: each other car's body at the last step, and a track for each that moved."""
    import shapely
    from shapely import affinity

    from rrtdrive.sim.episode_plot import plot_episode
    from rrtdrive.sim.runner import EpisodeConfig, run_episode

    episode = run_episode("overtake-traffic", seed=0, config=EpisodeConfig(max_time_s=4.0))
    others, sizes = episode.log.others, episode.log.other_sizes
    assert others.shape[1] >= 2  # the lead car and oncoming cars
    ax = plot_episode(episode).axes[0]
    bodies = {p.get_gid(): p for p in ax.patches if (p.get_gid() or "").startswith("other-car")}
    assert len(bodies) == others.shape[1]
    for k, ((x, y, heading, _), (length, width)) in enumerate(zip(others[-1], sizes, strict=True)):
        patch = bodies[f"other-car-{k}"]
        expected = affinity.translate(
            affinity.rotate(shapely.box(-length / 2, -width / 2, length / 2, width / 2),
                            heading, origin=(0, 0), use_radians=True), x, y)  # fmt: skip
        drawn = shapely.Polygon(patch.get_xy())
        assert drawn.symmetric_difference(expected).area < 1e-9
    moved = [k for k in range(others.shape[1]) if np.ptp(others[:, k, :2], axis=0).max() > 0.1]
    assert moved  # the oncoming cars drive
    tracks = {ln.get_gid(): ln for ln in ax.lines if (ln.get_gid() or "").startswith("other-")}
    assert sorted(tracks) == sorted(f"other-track-{k}" for k in moved)
    for k in moved:
        assert np.allclose(tracks[f"other-track-{k}"].get_xydata(), others[:, k, :2])


def test_other_car_bodies_turn_with_their_heading_and_parked_cars_have_no_track():
    """Any heading (not only the road's 0 or pi) and a car that never moves: body, no track."""
    from types import SimpleNamespace

    import matplotlib.pyplot as plt
    import shapely
    from shapely import affinity

    from rrtdrive.sim.episode_plot import _draw_others

    steps = np.linspace(0.0, 1.0, 5)
    mover = np.column_stack([10 + 3 * steps, 5 + 2 * steps, 0.7 + 0 * steps, 1 + 0 * steps])
    parked = np.tile([30.0, 8.0, -2.0, 0.0], (5, 1))
    log = SimpleNamespace(others=np.stack([mover, parked], axis=1),
                          other_sizes=np.array([[5.0, 2.0], [4.0, 1.6]]))  # fmt: skip
    fig, ax = plt.subplots()
    _draw_others(ax, log)
    gids = sorted(a.get_gid() for a in [*ax.lines, *ax.patches] if a.get_gid())
    assert gids == ["other-car-0", "other-car-1", "other-track-0"]
    for k, (x, y, heading, _) in enumerate(log.others[-1]):
        length, width = log.other_sizes[k]
        expected = affinity.translate(
            affinity.rotate(shapely.box(-length / 2, -width / 2, length / 2, width / 2),
                            heading, origin=(0, 0), use_radians=True), x, y)  # fmt: skip
        [patch] = [p for p in ax.patches if p.get_gid() == f"other-car-{k}"]
        assert shapely.Polygon(patch.get_xy()).symmetric_difference(expected).area < 1e-9
    plt.close(fig)
