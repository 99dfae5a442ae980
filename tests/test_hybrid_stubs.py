"""A reversing path does not end (or start) with a few centimetres in the other gear.

A car in a 2.2 x 5 m garage drives out to a goal facing south: the shortest shot from
the start (a Reeds-Shepp word whose first turn is small enough to clear the garage)
ends with a 0.3 m reverse; a forward path out of the garage is as short.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from rrtdrive.maps import Map, Obstacle
from rrtdrive.planning import make_planner
from rrtdrive.planning.base import PlanningProblem
from rrtdrive.planning.hybrid.shortcut import STUB_M
from rrtdrive.types import Budget, Pose
from rrtdrive.verify import verify_path

GARAGE = (
    Obstacle((2.5, 7.85), (5.2, 0.3)),
    Obstacle((2.5, 10.35), (5.2, 0.3)),
    Obstacle((-0.05, 9.1), (0.3, 2.8)),
)


def garage_map(goal: Pose) -> Map:
    return Map("garage_out", (0.0, 0.0, 30.0, 20.0), GARAGE, Pose(1.2, 9.1, 0.0), goal)


def segments(path) -> list[float]:
    """Each gear segment's length, start to goal."""
    rows = path.samples
    cuts = np.flatnonzero(np.diff(rows[:, 4])) + 1
    return [float(np.hypot(*np.diff(s[:, :2], axis=0).T).sum()) for s in np.split(rows, cuts)]


def plan(m: Map, **options):
    planner = make_planner("hybrid-a-star", **options)
    problem = PlanningProblem.from_map(m, reverse=True)
    return planner.solve(problem, np.random.default_rng(0), Budget())


def test_the_end_stub_is_dropped_for_a_path_that_costs_less():
    m = garage_map(Pose(20.0, 4.0, -math.pi / 2))
    kept = plan(m, stub_tries=0)
    assert kept.success
    stubbed = segments(kept.path)
    assert len(stubbed) == 2 and stubbed[-1] <= STUB_M  # the stub this is about
    out = plan(m)
    assert out.success
    check = verify_path(m, out.path, max_sharpness=0.2)
    assert check.ok, check
    parts = segments(out.path)
    assert len(parts) < len(stubbed)
    assert all(p > STUB_M for p in (parts[0], parts[-1])) or len(parts) == 1
    # Cheaper by the shots' measure: its length plus 0.5 m a gear change.
    assert out.path.length + 0.5 * (len(parts) - 1) < kept.path.length + 0.5 * (len(stubbed) - 1)


@pytest.mark.parametrize("goal", [Pose(20.0, 4.0, -math.pi / 2), Pose(15.0, 4.0, math.pi)])
def test_dropping_stubs_never_adds_a_gear_change_or_length_beyond_the_cusp_cost(goal):
    m = garage_map(goal)
    kept, out = plan(m, stub_tries=0), plan(m)
    assert kept.success and out.success
    a, b = segments(kept.path), segments(out.path)
    assert len(b) <= len(a)
    assert out.path.length + 0.5 * (len(b) - 1) <= kept.path.length + 0.5 * (len(a) - 1) + 1e-9
    assert verify_path(m, out.path, max_sharpness=0.2).ok


def test_stub_tries_is_validated():
    from rrtdrive.types import InputError

    with pytest.raises(InputError, match="stub_tries"):
        make_planner("hybrid-a-star", stub_tries=-1)
