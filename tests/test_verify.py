"""The independent verifier must catch each kind of broken path."""

from __future__ import annotations

import math

import numpy as np

from rrtdrive.maps import Map, Obstacle
from rrtdrive.types import Path, Pose
from rrtdrive.verify import verify_path


def _arc_map() -> tuple[Map, Path]:
    # A quarter circle of radius 10 m (kappa 0.1 < 1/6) from (10, 10) heading +x.
    r = 10.0
    t = np.linspace(0.0, math.pi / 2, int(r * math.pi / 2 / 0.2) + 1)
    x = 10.0 + r * np.sin(t)
    y = 20.0 - r * np.cos(t)
    samples = np.column_stack([x, y, t, np.full_like(t, 1 / r)])
    m = Map("arc", (0.0, 0.0, 40.0, 40.0), (), Pose(10.0, 10.0, 0.0), Pose(20.0, 20.0, math.pi / 2))
    return m, Path(samples, samples[:, :2])


def test_good_arc_passes():
    m, p = _arc_map()
    check = verify_path(m, p)
    assert check.ok, check
    assert abs(check.max_discrete_curvature - 0.1) < 0.005


def test_obstacle_on_the_arc_is_caught():
    m, p = _arc_map()
    blocked = Map("arc", m.bounds, (Obstacle((17.07, 12.93), (1.0, 1.0)),), m.start, m.goal)
    check = verify_path(blocked, p)
    assert not check.collision_free and not check.ok


def test_tight_turn_is_caught():
    r = 4.0  # kappa 0.25 > 1/6
    t = np.linspace(0.0, math.pi / 2, 40)
    samples = np.column_stack([10 + r * np.sin(t), 20 - r * np.cos(t), t, np.full_like(t, 1 / r)])
    start, goal = Pose(10.0, 16.0, 0.0), Pose(14.0, 20.0, math.pi / 2)
    m = Map("tight", (0.0, 0.0, 40.0, 40.0), (), start, goal)
    check = verify_path(m, Path(samples, samples[:, :2]))
    assert not check.curvature_ok


def test_wrong_goal_heading_and_sparse_samples_are_caught():
    m, p = _arc_map()
    turned = Map("arc", m.bounds, (), m.start, Pose(20.0, 20.0, math.pi / 2 + 0.2))
    assert not verify_path(turned, p).headings_ok
    sparse = Path(p.samples[::3], p.waypoints)
    assert not verify_path(m, sparse).spacing_ok
