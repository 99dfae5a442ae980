"""Python API guards from the audit of session 39: each of these was accepted silently.

A path's waypoints shared the caller's array, a tree's parents went unchecked, a result's
status could be any text, angles given in degrees passed where radians are meant, and a
wrong type reached a bare comparison (a TypeError naming no field).
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from rrtdrive import CheckerConfig, Map, PlanResult
from rrtdrive.evaluation import EvalConfig
from rrtdrive.planning import PlanningProblem, make_planner
from rrtdrive.types import InputError, InputWarning, Path, PlanStatus, Pose, Tree

ROWS = np.array([[0.0, 0.0, 0.0, 0.0, 1.0], [1.0, 0.0, 0.0, 0.0, 1.0]])


def test_path_waypoints_are_its_own_copy_and_must_be_pairs():
    w = np.zeros((2, 2))
    p = Path(ROWS, w)
    w[0, 0] = 3.0
    assert p.waypoints[0, 0] == 0.0 and not p.waypoints.flags.writeable
    with pytest.raises(InputError, match=r"path.waypoints: expected \[x, y\] pairs, got shape"):
        Path(ROWS, np.arange(6.0).reshape(2, 3))
    assert Path(ROWS, []).waypoints.shape == (0, 2)


@pytest.mark.parametrize("parents", [[-1, 7], [-1, -2], [-1], [-1, 0, 1]])
def test_tree_parents_must_index_its_nodes(parents):
    with pytest.raises(InputError, match=r"tree.parents: expected one index in \[-1, 2\)"):
        Tree([[0.0, 0.0], [1.0, 1.0]], parents)
    assert len(Tree([[0.0, 0.0], [1.0, 1.0]], [-1, 0]).edges()) == 1


def test_plan_result_status_is_a_plan_status():
    result = PlanResult("solved", "x", Path.empty(), None, (), 0, 0, 0.0)
    assert result.status is PlanStatus.SOLVED and result.success
    with pytest.raises(InputError, match=r"result.status: must be one of .*got 'done'"):
        PlanResult("done", "x", Path.empty(), None, (), 0, 0, 0.0)


def test_angles_past_what_radians_can_mean_are_refused():
    with pytest.raises(InputError, match=r"hybrid.shot_bin: must be at most pi"):
        make_planner("hybrid-a-star", shot_bin=20)
    with pytest.raises(InputError, match=r"eval.goal_tol_rad: must be at most pi"):
        EvalConfig(goal_tol_rad=10)
    assert EvalConfig(goal_tol_rad=np.pi).goal_tol_rad == np.pi


def test_a_problem_pose_in_degrees_warns_and_the_maps_own_poses_warn_once():
    m = Map("z", (0.0, 0.0, 50.0, 50.0), (), Pose(5.0, 5.0, 0.0), Pose(40.0, 40.0, 0.0))
    problem = PlanningProblem.from_map(m)
    with pytest.warns(InputWarning, match=r"problem.goal: yaw 90 is more than a full turn"):
        PlanningProblem(m, problem.checker, m.start, Pose(40.0, 40.0, 90.0))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        PlanningProblem(m, problem.checker, m.start, Pose(40.0, 40.0, 1.5))


@pytest.mark.parametrize(
    "build, field",
    [
        (lambda: CheckerConfig(margin="0.1"), "checker.margin"),
        (lambda: CheckerConfig(margin=None), "checker.margin"),
        (lambda: EvalConfig(kappa_tol="x"), "eval.kappa_tol"),
    ],
)
def test_a_wrong_type_is_an_input_error_naming_the_field(build, field):
    with pytest.raises(InputError, match=rf"^{field}: expected a number"):
        build()


def test_maps_for_different_cars_differ_and_results_print_in_one_line():
    import dataclasses

    from rrtdrive import Budget, VehicleParams, builtin_map

    m = builtin_map("parking_lot")
    wide = dataclasses.replace(m, vehicle=VehicleParams(width=2.2))
    assert m != wide and m == builtin_map("parking_lot")
    problem = PlanningProblem.from_map(m)
    result = make_planner("improved-rrt-connect").solve(problem, np.random.default_rng(0), Budget())
    for text in (repr(problem), repr(result)):
        assert "\n" not in text and len(text) < 250, text
    assert repr(result).startswith("PlanResult(solved, planner='improved-rrt-connect'")


def test_a_map_prints_in_one_line_with_its_obstacle_count_and_a_non_default_car():
    import dataclasses

    from rrtdrive import VehicleParams, builtin_map

    m = builtin_map("parking_lot")
    text = repr(m)
    assert "\n" not in text and len(text) < 250, text
    assert text.startswith("Map('parking_lot', bounds=(0.0, 0.0, 100.0, 100.0), ")
    assert f" {len(m.obstacles)} obstacles, " in text and len(m.obstacles) > 100
    assert f"start={m.start}, goal={m.goal})" in text and "vehicle" not in text
    wide = repr(dataclasses.replace(m, vehicle=VehicleParams(width=2.2)))
    assert wide.endswith(f", vehicle={VehicleParams(width=2.2)})")


@pytest.mark.parametrize(
    "argv",
    [
        ["plan", "overtake", "--planner", "hybrid-astar"],
        ["simulate", "parking", "--planner", "hybrid-astar"],
        ["bench", "--maps", "overtake", "--planners", "hybrid-astar", "--out", "unused"],
    ],
)
def test_a_misspelt_planner_gets_the_closest_name(argv, capsys):
    from rrtdrive.cli import main

    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "unknown planner 'hybrid-astar' (did you mean 'hybrid-a-star'?); choose from" in err
    assert err.count("\n") == 1


def test_a_misspelt_planner_in_python_gets_the_closest_name_too():
    import gymnasium as gym

    import rrtdrive.envs  # noqa: F401  (registers the ids)

    with pytest.raises(InputError, match=r"^planner: .*\(did you mean 'rrt-star'\?\)"):
        make_planner("rrtstar")
    with pytest.raises(InputError, match=r"^planner: .*\(did you mean 'rrt-star'\?\)"):
        gym.make("rrtdrive/Parking-v0", planner="rrtstar")
    with pytest.raises(InputError, match=r"unknown planner 'zzz'; choose from hybrid-a-star"):
        make_planner("zzz")
