"""The default planner's escalation takes its own Hybrid A* settings (``ImprovedConfig.hybrid``).

``--planner-option hybrid.gear_change_cost=200`` reaches the escalation's search and the
weighing of a forward detour against its path; the default (``HybridConfig()``) is the
escalation as it was.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from rrtdrive.maps import Map, Obstacle, builtin_map
from rrtdrive.planning import PlanningProblem, make_planner
from rrtdrive.planning.hybrid import HybridConfig
from rrtdrive.planning.improved import ImprovedConfig
from rrtdrive.types import Budget, InputError, Pose
from rrtdrive.verify import verify_path

#: Random goal 93 of experiments/random_goals.py (README: 75.88 m with one gear change
#: by default, the 186.05 m forward loop with reverse_detour_tree=false).
GOAL_93 = Pose(53.201107188452056, 36.30433181948137, 2.404196106990101)


def _solve(m: Map, reverse: bool, **options: object):
    problem = PlanningProblem.from_map(m, reverse=reverse)
    planner = make_planner("improved-rrt-connect", **options)
    return planner.solve(problem, np.random.default_rng(0), Budget(max_time_s=300.0))


def test_the_default_is_the_escalation_as_it_was_and_fields_change_one_at_a_time():
    assert ImprovedConfig().hybrid == HybridConfig()
    cfg = ImprovedConfig().with_options({"hybrid": {"gear_change_cost": 12.0}})
    assert cfg.hybrid == dataclasses.replace(HybridConfig(), gear_change_cost=12.0)


@pytest.mark.parametrize(
    ("options", "match"),
    [
        ({"hybrid": {"gear_cost": 1}}, r"^planner\.hybrid\.gear_cost: unknown field of Hybrid"),
        ({"hybrid": {"gear_change_cost": -1}}, r"^planner\.hybrid\.gear_change_cost: must be >= 0"),
        ({"hybrid": {"curve": "bad"}}, r"^planner\.hybrid\.curve: must be one of"),
        ({"hybrid": 4}, r"^planner\.hybrid: expected a HybridConfig, got int"),
    ],
)  # fmt: skip
def test_a_bad_escalation_field_is_named(options, match):
    with pytest.raises(InputError, match=match):
        make_planner("improved-rrt-connect", **options)


def test_a_dear_gear_change_keeps_the_forward_loop():
    m = builtin_map("parking_lot").with_query(goal=GOAL_93)
    usual = _solve(m, True)
    assert usual.success and len(usual.path.cusps) == 1, usual.message
    dear = _solve(m, True, hybrid={"gear_change_cost": 200.0})
    assert dear.success and len(dear.path.cusps) == 0, dear.message
    assert dear.path.length > usual.path.length + 50.0
    assert "a gear change as 200 m" in dear.message
    assert verify_path(m, dear.path).ok


def test_the_escalation_searches_on_the_given_grid():
    walls = (Obstacle((18.0, 10.0), (0.6, 4.0)), Obstacle((15.5, 8.3), (5.6, 0.6)),
             Obstacle((15.5, 11.7), (5.6, 0.6)))  # fmt: skip
    m = Map("pocket", (0.0, 0.0, 40.0, 20.0), walls, Pose(14.0, 10.0, 0.0), Pose(30.0, 10.0, 0.0))
    usual = _solve(m, False)
    coarse = _solve(m, False, hybrid={"xy_resolution": 0.5, "refinements": 0})
    assert "proved none at 0.25 m / 2.5 deg" in usual.message, usual.message
    assert "proved none at 0.5 m / 5 deg" in coarse.message, coarse.message
