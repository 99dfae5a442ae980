"""A query whose start is its goal: every planner answers a path of 0 m, nothing searches.

Before, the forward-only planners drove a 190 m loop round the parking lot (1.2 s) to
come back to the pose, and the default with reverse a 38 m word with a gear change.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rrtdrive.cli import main
from rrtdrive.maps import builtin_map, save_map
from rrtdrive.planning import PLANNERS, PlanningProblem, make_planner
from rrtdrive.types import Budget, Path, Pose
from rrtdrive.verify import verify_path

HERE = Pose(10.0, 10.0, 0.3)
OURS = sorted(name for name in PLANNERS if not name.startswith("ompl-"))


def _here_map(pose: Pose = HERE):
    return dataclasses.replace(builtin_map("parking_lot"), start=pose, goal=pose)


@pytest.mark.parametrize("reverse", [False, True])
@pytest.mark.parametrize("name", OURS)
def test_every_planner_answers_zero_metres_without_searching(name: str, reverse: bool) -> None:
    m = _here_map()
    res = make_planner(name).solve(
        PlanningProblem.from_map(m, reverse=reverse), np.random.default_rng(0), Budget()
    )
    assert res.success and res.iterations == 0 and res.nodes == 0
    assert res.path.length == 0.0 and res.path.is_forward_only
    assert "the start is the goal" in res.message
    # The independent check passes it, sharpness bound and all.
    assert verify_path(m, res.path, max_sharpness=0.2).ok


@pytest.mark.parametrize("reverse", [False, True])
@pytest.mark.parametrize("off", [(0.0, 0.0, 1e-6), (0.0, 1e-6, -1e-6), (-7e-7, 7e-7, 0.0)])
def test_a_goal_the_plan_json_cannot_tell_from_the_start_is_the_start(off, reverse, tmp_path):
    # Within 1e-6 (the JSON's 6 decimals) the goal is the start: 0 m, also forward only,
    # where a goal 1e-6 rad off the start's heading used to fail as a manoeuvre with
    # the map's edge behind it; and the independent check of the JSON passes it.
    m = dataclasses.replace(builtin_map("parking_lot"),
                            goal=Pose(5.0 + off[0], 6.0 + off[1], off[2]))  # the lot's start
    f = tmp_path / "plan.json"
    goal = f"{5 + off[0]!r},{6 + off[1]!r},{off[2]!r}"
    argv = ["plan", "parking_lot", "--goal", goal, "--json", str(f)]
    assert main(argv + (["--reverse"] if reverse else [])) == 0
    save_map(m, tmp_path / "m.json")
    assert main(["verify", str(f), str(tmp_path / "m.json")]) == 0
    res = make_planner("hybrid-a-star").solve(
        PlanningProblem.from_map(m, reverse=reverse), np.random.default_rng(0), Budget()
    )
    assert res.success and "the start is the goal" in res.message
    assert res.path.length <= 1.5e-6 and res.iterations == 0  # the ends, a micrometre apart


def test_a_goal_one_centimetre_away_is_still_planned() -> None:
    m = dataclasses.replace(_here_map(), start=Pose(HERE.x + 0.01 * math.cos(HERE.yaw),
                                                    HERE.y + 0.01 * math.sin(HERE.yaw), HERE.yaw))
    res = make_planner("improved-rrt-connect").solve(
        PlanningProblem.from_map(m, reverse=True), np.random.default_rng(0), Budget()
    )
    assert res.success and "the start is the goal" not in res.message
    assert res.path.length == pytest.approx(0.01, abs=1e-6) and len(res.path.cusps) == 0
    assert verify_path(m, res.path, max_sharpness=0.2).ok


@settings(max_examples=30, deadline=None)
@given(yaw=st.floats(-3.0, 3.0), turn=st.floats(0.06, math.pi))
def test_verify_refuses_a_car_that_turns_without_moving(yaw: float, turn: float) -> None:
    """A path that stays put keeps its heading: start and goal yaw must be every row's (3 deg)."""
    here = Pose(10.0, 10.0, yaw)
    still = np.array([[10.0, 10.0, yaw, 0.0, 1.0], [10.0, 10.0, yaw, 0.0, 1.0]])
    assert verify_path(_here_map(here), Path(still, np.zeros((0, 2)))).ok
    turned = still.copy()
    turned[1, 2] = yaw + turn
    goal_turned = dataclasses.replace(_here_map(here), goal=Pose(10.0, 10.0, yaw + turn))
    check = verify_path(goal_turned, Path(turned, np.zeros((0, 2))))
    assert not check.ok and not check.headings_ok
    # A pivot in place and back: the ends agree, the rows between do not.
    pivot = np.vstack([still[:1], turned[1:], still[1:]])
    assert not verify_path(_here_map(here), Path(pivot, np.zeros((0, 2)))).headings_ok


def test_simulate_refuses_a_map_whose_goal_is_its_start(capsys, tmp_path) -> None:
    f = tmp_path / "here.json"
    save_map(_here_map(), f)
    assert main(["simulate", str(f)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "goal: the goal is the start pose (10, 10," in err[0], err
    assert main(["simulate", "parking_lot", "--goal", "5,6,0"]) == 2  # the lot's start
    assert "give another goal" in capsys.readouterr().err


def test_bench_refuses_such_a_map_up_front(capsys, tmp_path) -> None:
    """One exit-2 line naming the field, not an error row per seed (each retried)."""
    from rrtdrive.bench import BenchConfig
    from rrtdrive.types import InputError

    f = tmp_path / "here.json"
    save_map(_here_map(), f)
    with pytest.raises(InputError, match=r"scenarios: .*here\.json'?: goal: the goal is the start"):
        BenchConfig(scenarios=(str(f),), seeds=2)
    assert main(["bench", "--scenarios", str(f), "--out", str(tmp_path / "out")]) == 2
    assert not (tmp_path / "out" / "runs.jsonl").exists()
    # Planning it is fine: the plan is 0 m.
    assert BenchConfig(maps=(str(f),), seeds=1).maps == (str(f),)
