"""OMPL's rows at our body clearance in the side-by-side scripts (``street_turns.py`` and
the three that share its options): the option, the row names, the validity checker."""

from __future__ import annotations

import importlib.util
import json
import sys
from pathlib import Path

import numpy as np
import pytest
import shapely

from rrtdrive.maps import Map, Obstacle
from rrtdrive.types import Pose, VehicleParams
from rrtdrive.vehicle import footprint_polygon

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "experiments"))
import street_turns  # noqa: E402

HAVE_OMPL = importlib.util.find_spec("ompl") is not None


@pytest.mark.parametrize(
    ("text", "want"), [("0,0.15", (0.0, 0.15)), ("0.15", (0.15,)), (" 0 , 0.3 ", (0.0, 0.3))]
)
def test_the_option_parses_its_clearances(text: str, want: tuple[float, ...]) -> None:
    args = kerb_gaps_args(["--ompl-clearances", text])
    assert args.ompl_clearances == want


@pytest.mark.parametrize("text", ["x", "", "-0.1", "2", "0,,nan"])
def test_a_bad_clearance_exits_2_naming_the_option(text: str, capsys) -> None:  # noqa: ANN001
    with pytest.raises(SystemExit) as exc:
        kerb_gaps_args(["--ompl-clearances", text])
    assert exc.value.code == 2
    assert "--ompl-clearances" in capsys.readouterr().err


def test_the_default_runs_ompl_touching_and_at_our_clearance() -> None:
    assert kerb_gaps_args([]).ompl_clearances == (0.0, street_turns.OUR_CLEARANCE)
    assert street_turns.OUR_CLEARANCE == 0.15
    assert street_turns.ompl_label(0.0) == "ompl-rs-rrtconnect"
    assert street_turns.ompl_label(0.15) == "ompl-rs-rrtconnect@0.15m"


def kerb_gaps_args(argv: list[str]):  # noqa: ANN201
    """The shared options as kerb_gaps.py parses and checks them."""
    import argparse

    ap = argparse.ArgumentParser()
    street_turns.add_run_options(ap, "gap", "out")
    args = ap.parse_args(argv)
    street_turns.check_run_options(ap, args)
    return args


def _gap_map() -> Map:
    """A street 8 m wide with a block 4 m deep in its way: touching, OMPL hugs its corners."""
    return Map(
        "block", (0.0, 0.0, 30.0, 8.0), (Obstacle((15.0, 2.0), (4.3, 4.0), 0.0),),
        Pose(2.0, 1.5, 0.0), Pose(25.0, 1.5, 0.0),
    )  # fmt: skip


@pytest.mark.skipif(not HAVE_OMPL, reason="OMPL is not installed (the [ompl] extra)")
def test_ompl_at_our_clearance_keeps_it_at_every_state() -> None:
    # Without a clearance OMPL's simplified paths pass the block's corners within
    # millimetres (0.0-4.3 mm over 4 seeds when this was written); with one, every state
    # it checked keeps 0.15 m.
    m = _gap_map()
    rows = street_turns.planner_rows(m, "gap", 1, 10.0, 5.0, True, ours=(), clearances=(0.0, 0.15))
    assert set(rows) == {"ompl-rs-rrtconnect", "ompl-rs-rrtconnect@0.15m"}
    kept = rows["ompl-rs-rrtconnect@0.15m"][0]
    assert kept["solved"] and kept["clearance_m"] == 0.15
    import coverage as cov

    from rrtdrive.planning import PlanningProblem

    problem = PlanningProblem.from_map(m, reverse=True)
    _, _, _, path = cov.solve_ompl(problem, 0, "ompl-rs-rrtconnect", 5.0, 0.15)
    assert path is not None
    obstacles = shapely.union_all([o.polygon() for o in m.obstacles])
    walls = shapely.box(*m.bounds).exterior
    # Rows 0.1 m apart along OMPL's curves: between its checked states a row may come
    # a little closer (its motion check is at its own resolution): 0.1514 m at least over
    # 4 seeds when this was written.
    least = min(
        min(obstacles.distance(body), walls.distance(body))
        for body in (footprint_polygon(tuple(r[:3]), VehicleParams()) for r in path.samples)
    )
    assert least > 0.14, least
    payload = json.loads(json.dumps(rows))  # the rows are what the scripts write
    assert payload["ompl-rs-rrtconnect@0.15m"][0]["solved"]


def test_the_scalar_pose_test_with_clearance_is_the_batch_ones() -> None:
    m = _gap_map()
    from rrtdrive.planning import PlanningProblem

    checker = PlanningProblem.from_map(m).checker
    rng = np.random.default_rng(3)
    poses = np.column_stack(
        [rng.uniform(0, 30, 400), rng.uniform(0, 5.6, 400), rng.uniform(-np.pi, np.pi, 400)]
    )
    for clearance in (0.0, 0.15, 0.4):
        batch = checker.poses_free(poses, clearance)
        assert [checker.pose_free(p, clearance) for p in poses] == batch.tolist()


@pytest.mark.parametrize(
    ("name", "want"),
    [("ompl-dubins-rrt@0.15m", ("ompl-dubins-rrt", 0.15)),
     ("ompl-rs-rrtconnect", ("ompl-rs-rrtconnect", 0.0)), ("hybrid-a-star", None),
     ("hybrid-a-star@curve=arcs", None)],
)  # fmt: skip
def test_coverage_names_ompl_rows_with_their_clearance(name: str, want) -> None:  # noqa: ANN001
    import coverage as cov

    assert cov.ompl_spec(name) == want
    # The tight-map scripts write the names that coverage.py reads.
    assert cov.ompl_spec(street_turns.ompl_label(0.15)) == (street_turns.OMPL_NAME, 0.15)
    assert cov.ompl_spec(street_turns.ompl_label(0.0)) == (street_turns.OMPL_NAME, 0.0)


@pytest.mark.parametrize(
    "name", ["ompl-dubins-rrt@0.15", "ompl-dubins-rrt@xm", "ompl-rs-rrtconnect@2m"]
)
def test_a_bad_ompl_clearance_is_skipped_naming_it(name: str) -> None:
    import coverage as cov

    why = cov.availability(name)
    assert why is not None and name in why and "clearance in metres" in why


@pytest.mark.skipif(not HAVE_OMPL, reason="OMPL is not installed (the [ompl] extra)")
def test_ompl_keeps_at_most_what_the_start_itself_has() -> None:
    """A start 0.05 m from an obstacle: kept to 0.15 m, OMPL had no valid start at all.

    With ``cap_at_ends`` (coverage.py's rows) the clearance is capped a micron under the
    start's own, as ours is capped, and OMPL plans; every state then keeps the cap.
    """
    import coverage as cov

    from rrtdrive.planning import PlanningProblem

    car = VehicleParams()
    # A 1 m block ahead-left of the front-left corner, its nearest corner 0.05 m away;
    # the goal straight ahead (the car swings a few centimetres right to pass it).
    fx, fy = 2.0 + car.front_extent, 3.0 + car.width / 2.0
    d = 0.05 / np.sqrt(2.0)
    m = Map(
        "close", (0.0, 0.0, 30.0, 12.0),
        (Obstacle((fx + d + 0.5, fy + d + 0.5), (1.0, 1.0), 0.0),),
        Pose(2.0, 3.0, 0.0), Pose(25.0, 3.0, 0.0),
    )  # fmt: skip
    problem = PlanningProblem.from_map(m, reverse=True)
    own = problem.checker.body_clearance(m.start.as_tuple())
    assert 0.04 < own < 0.06
    strict = cov.solve_ompl(problem, 0, "ompl-rs-rrtconnect", 2.0, 0.15)
    assert strict[3] is None and strict[0] < 0.5  # refused at once: no valid start
    capped = cov.solve_ompl(problem, 0, "ompl-rs-rrtconnect", 5.0, 0.15, cap_at_ends=True)
    assert capped[3] is not None
    clear = [problem.checker.body_clearance(tuple(r[:3])) for r in capped[3].samples[::5]]
    assert min(clear) > own - 0.02  # rows between its checked states come a little closer
