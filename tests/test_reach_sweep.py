"""experiments/reach_sweep.py: the forward-reachability sweep behind forward_reach.py.

A surviving drive is judged by the independent check (shapely bodies, discrete
curvature and sharpness); a dead end kills every drive before its wall; the sweep is
deterministic.
"""

from __future__ import annotations

import functools
import importlib.util
import math
import sys
from pathlib import Path as FsPath

import numpy as np
import pytest

from rrtdrive.collision import CollisionChecker
from rrtdrive.maps import Map, Obstacle
from rrtdrive.types import Path, Pose
from rrtdrive.verify import verify_path

_SPEC = importlib.util.spec_from_file_location(
    "reach_sweep", FsPath(__file__).resolve().parents[1] / "experiments" / "reach_sweep.py"
)
reach_sweep = importlib.util.module_from_spec(_SPEC)
sys.modules[_SPEC.name] = reach_sweep  # its dataclass looks its module up while being made
_SPEC.loader.exec_module(reach_sweep)


def _sweep(m: Map, **kw):
    car = m.vehicle
    return reach_sweep.sweep(
        CollisionChecker.for_map(m), m.start.as_tuple(), wheelbase=car.wheelbase,
        kappa_max=car.kappa_max, **kw,
    )  # fmt: skip


def _corner_map() -> Map:
    """A 6 m wide street heading east into a 10 m wide one heading north."""
    walls = (
        Obstacle((15.0, 16.0), (30.0, 10.0)),  # north of the street, west of the turn
        Obstacle((20.0, 2.5), (40.0, 5.0)),  # south wall, beneath the street and the turn
    )
    start, goal = Pose(20.0, 8.0, 0.0), Pose(35.0, 30.0, math.pi / 2)
    return Map("corner", (0.0, 0.0, 40.0, 35.0), walls, start, goal)


#: Coarse merging keeps these sweeps to a few seconds.
COARSE = {"cell": 0.3, "heading_bin": math.radians(3.0), "max_states": 20_000}


@functools.cache
def _corner_sweep(sharpness: float, distance: float):
    return _sweep(_corner_map(), sharpness=sharpness, distance=distance, **COARSE)


@pytest.mark.parametrize("sharpness", [0.2, 0.5])
def test_a_surviving_drive_passes_the_independent_check(sharpness):
    m = _corner_map()
    reach = _corner_sweep(sharpness, 25.0)
    assert reach.survived and reach.driven_m == pytest.approx(25.0)
    end = reach.poses[-1]
    assert end[1] > 11.0  # it turned into the northern street: straight on dies at 16.6 m
    check = verify_path(
        m.with_query(goal=Pose(*end[:3])), Path(reach.poses, np.zeros((0, 2))),
        max_sharpness=sharpness, sharpness_tol=0.01,
    )  # fmt: skip
    assert check.ok, check.failed


def test_a_dead_end_kills_every_drive_before_its_wall():
    # A 4 m wide alley closed 11 m ahead: the car (6 m radius) can neither turn nor pass.
    walls = (Obstacle((10.0, 7.0), (20.0, 2.0)), Obstacle((10.0, 13.0), (20.0, 2.0)),
             Obstacle((14.5, 10.0), (1.0, 4.0)))  # fmt: skip
    m = Map("alley", (0.0, 0.0, 30.0, 20.0), walls, Pose(3.0, 10.0, 0.0), Pose(25.0, 10.0, 0.0))
    reach = _sweep(m, sharpness=5.0, distance=20.0)
    assert not reach.survived
    front = m.vehicle.length - m.vehicle.rear_overhang  # rear axle to the front bumper
    assert reach.driven_m <= 14.0 - front - 3.0 + 0.2  # one step past the last clear pose


def test_the_sweep_is_deterministic():
    m = _corner_map()
    a = _sweep(m, sharpness=0.3, distance=8.0, **COARSE)
    b = _sweep(m, sharpness=0.3, distance=8.0, **COARSE)
    assert a.peak_states == b.peak_states and np.array_equal(a.poses, b.poses)


def test_steering_never_moves_faster_than_the_bound():
    m = _corner_map()
    reach = _corner_sweep(0.2, 25.0)
    delta = np.arctan(m.vehicle.wheelbase * reach.poses[:, 3])
    s = np.r_[0.0, np.cumsum(np.hypot(*np.diff(reach.poses[:, :2], axis=0).T))]
    rate = np.abs(np.diff(delta)) / np.diff(s)
    assert rate.max() <= 0.2 * (1 + 1e-6)
    assert np.abs(reach.poses[:, 3]).max() <= m.vehicle.kappa_max * (1 + 1e-9)
    assert math.isclose(s[-1], 25.0, rel_tol=1e-3)


def test_wheels_turned_at_rest_reach_a_turn_that_straight_wheels_miss():
    # 1 m before the corner the wheels cannot come round at 0.2 rad/m from straight; a
    # car at rest turns them first (the controllers do), and then it makes the turn.
    base = _corner_map()
    m = Map("corner_near", base.bounds, base.obstacles, Pose(29.0, 8.0, 0.0), base.goal)
    straight = _sweep(m, sharpness=0.2, distance=20.0, **COARSE)
    turned = _sweep(m, sharpness=0.2, distance=20.0, turned_wheels=True, **COARSE)
    assert not straight.survived and straight.driven_m < 10.0
    assert turned.survived and turned.poses[-1, 1] > 11.0
    # The drive starts at its wheels' angle (set at rest), then keeps the rate bound.
    assert turned.poses[0, 3] != 0.0  # the wheels were turned at rest
    delta = np.arctan(m.vehicle.wheelbase * turned.poses[:, 3])
    s = np.r_[0.0, np.cumsum(np.hypot(*np.diff(turned.poses[:, :2], axis=0).T))]
    assert (np.abs(np.diff(delta)) / np.diff(s)).max() <= 0.2 * (1 + 1e-6)
    check = verify_path(
        m.with_query(goal=Pose(*turned.poses[-1, :3])), Path(turned.poses, np.zeros((0, 2))),
        max_sharpness=0.2, sharpness_tol=0.01,
    )  # fmt: skip
    assert check.ok, check.failed
