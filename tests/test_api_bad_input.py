"""The Python API refuses bad input with one InputError naming the field, and never hangs.

Found by a QA pass of the public API (session 21): huge bounds looped for minutes, an
obstacle reaching 1e19 m dropped out of the grid (planners drove through it), a tiny
Hybrid A* heading bin built a table of gigabytes, and several types went unchecked.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from rrtdrive.maps import Map, Obstacle, builtin_map
from rrtdrive.planning import PLANNERS, PlanningProblem, make_planner
from rrtdrive.planning.hybrid.config import HybridConfig
from rrtdrive.planning.hybrid.resolution import MAX_TABLE_BINS, dubins_table
from rrtdrive.types import Budget, InputError, Path, Pose
from rrtdrive.verify import verify_path

START, GOAL = Pose(3.0, 5.0, 0.0), Pose(25.0, 5.0, 0.0)
OURS = ("rrt", "rrt-connect", "rrt-star", "improved-rrt-connect", "hybrid-a-star")


@pytest.mark.parametrize("side", [1e12, 1e13, 1e15, 1e300])
def test_huge_bounds_are_refused_at_once_naming_bounds(side: float) -> None:
    with pytest.raises(InputError, match=r"^bounds: .* use a smaller map"):
        PlanningProblem.from_map(Map("big", (0.0, 0.0, side, side), (), START, GOAL))


@pytest.mark.parametrize("size", [1e18, 1e19, 1e300])
def test_a_wall_longer_than_a_billion_metres_is_refused_naming_its_size(size: float) -> None:
    # A turned one's corners at +-5e16 m rounded by 8 m and moved the wall (session 49).
    with pytest.raises(InputError, match=r"^obstacle\.size: .* is longer than 1e\+09 m"):
        Obstacle((15.0, size / 2), (1.0, size))


@pytest.mark.parametrize("yaw", [0.0, 0.3])
def test_a_wall_reaching_far_beyond_the_map_still_blocks_it(yaw: float) -> None:
    size = 1e9  # the longest a side may be, straight or turned, centred on the map
    wall = Obstacle((15.0, 10.0), (size, 1.0), yaw + math.pi / 2)
    m = Map("wall", (0.0, 0.0, 30.0, 20.0), (wall,), START, GOAL)
    problem = PlanningProblem.from_map(m)
    assert not problem.checker.pose_free((15.0, 5.0, 0.0))
    for name in ("improved-rrt-connect", "hybrid-a-star", "rrt"):
        res = make_planner(name).solve(
            problem, np.random.default_rng(0), Budget(max_iterations=500)
        )
        assert not res.success, (name, res.message)


def test_a_fine_heading_bin_keeps_the_dubins_table_bounded() -> None:
    fine = HybridConfig(yaw_resolution=2e-4)
    assert fine.yaw_bins > MAX_TABLE_BINS
    assert dubins_table(6.12, fine).lengths.shape[2] == MAX_TABLE_BINS


@pytest.mark.parametrize(
    ("setting", "value"),
    [
        ("pose_spacing", 0.0), ("pose_spacing", -1.0), ("pose_spacing", float("nan")),
        ("pose_spacing", 1e-300), ("max_sample_spacing", 0.0), ("heading_tol_deg", -1.0),
        ("curvature_tol", float("nan")), ("sharpness_tol", -0.1), ("max_sharpness", "0.2"),
        ("max_sharpness", 0.0),
    ],
)  # fmt: skip
def test_verify_refuses_settings_that_would_skip_checks(setting: str, value: object) -> None:
    m = Map("dot", (0.0, 0.0, 40.0, 30.0), (Obstacle((20.0, 10.0), (0.5, 0.5)),), START, GOAL)
    path = Path(np.array([[5.0, 10.0, 0.0, 0.0], [35.0, 10.0, 0.0, 0.0]]), np.zeros((0, 2)))
    with pytest.raises(InputError, match=f"^{setting}: "):
        verify_path(m, path, **{setting: value})


@pytest.mark.parametrize(
    ("build", "field"),
    [
        (lambda: Map("x", (0, 0, 30, 20), [((15, 15), (1, 1))], START, GOAL), "obstacles[0]"),
        (lambda: Map("x", (0, 0, 30, 20), None, START, GOAL), "obstacles"),
        (lambda: Map("x", (0, 0, 30, 20), "ab", START, GOAL), "obstacles"),
        (lambda: Map("x", (0, 0, 30, 20), (), START, GOAL, vehicle=None), "vehicle"),
        (lambda: PlanningProblem.from_map(None), "map"),
        (lambda: PlanningProblem.from_map(builtin_map("overtake"), config=5), "config"),
        (lambda: make_planner(["rrt"]), "planner"),
        (lambda: make_planner("improved-rrt-connect", disable=5), "planner.disable"),
        (lambda: make_planner("hybrid-a-star", smoothing="x"), "planner.smoothing"),
    ],
)  # fmt: skip
def test_wrong_types_name_their_field(build, field: str) -> None:
    with pytest.raises(InputError) as err:
        build()
    assert str(err.value).startswith(f"{field}: "), str(err.value)


def test_a_problem_checks_its_fields() -> None:
    m = builtin_map("overtake")
    checker = PlanningProblem.from_map(m).checker
    with pytest.raises(InputError, match=r"^problem.goal: expected a Pose, got tuple"):
        PlanningProblem(m, checker, m.start, (25.0, 5.0, 0.0))
    with pytest.raises(InputError, match=r"^problem.checker: "):
        PlanningProblem(m, None, m.start, m.goal)
    # A checker of another map: its path would pass through this map's obstacles.
    other = PlanningProblem.from_map(builtin_map("parking_lot")).checker
    with pytest.raises(InputError, match=r"^problem.checker: it was built for another map"):
        PlanningProblem(m, other, m.start, m.goal)


def test_verify_names_a_wrong_map_or_path() -> None:
    m = builtin_map("overtake")
    path = make_planner("improved-rrt-connect").solve(
        PlanningProblem.from_map(m), np.random.default_rng(0), Budget()
    ).path
    with pytest.raises(InputError, match=r"^m: expected a Map"):
        verify_path(None, path)
    with pytest.raises(InputError, match=r"^path: expected a Path"):
        verify_path(m, path.samples)
    assert verify_path(m, path).ok


@pytest.mark.parametrize("name", OURS)
def test_every_planner_names_a_wrong_rng_problem_or_budget(name: str) -> None:
    assert name in PLANNERS
    problem = PlanningProblem.from_map(builtin_map("overtake"))
    planner = make_planner(name)
    for args, field in (
        ((problem, 0, Budget()), "rng"),
        ((problem, None, Budget()), "rng"),
        ((builtin_map("overtake"), np.random.default_rng(0), Budget()), "problem"),
        ((problem, np.random.default_rng(0), None), "budget"),
    ):
        with pytest.raises(InputError, match=f"^{field}: "):
            planner.solve(*args)
    assert planner.solve(problem, np.random.default_rng(0), Budget()).success


@pytest.mark.parametrize(
    ("samples", "waypoints", "field"),
    [
        ("abc", np.zeros((0, 2)), "path.samples"),
        ([[1.0, 2.0, "x", 0.0]], [], "path.samples"),
        (np.zeros((3, 4)), np.zeros(3), "path.waypoints"),
    ],
)
def test_a_path_names_what_is_not_numbers(samples, waypoints, field: str) -> None:
    with pytest.raises(InputError, match=f"^{field}: "):
        Path(samples, waypoints)


def test_a_problem_whose_checker_is_for_another_car_is_refused():
    # The checker of the stock car cleared a 3.2 m wide car through narrow_gap's 2.8 m.
    from rrtdrive.planning import PlanningProblem
    from rrtdrive.planning.base import cached_checker
    from rrtdrive.types import VehicleParams

    m = builtin_map("narrow_gap")
    wide = VehicleParams(width=3.2)
    with pytest.raises(InputError, match=r"^problem\.vehicle: the checker was built for"):
        PlanningProblem(m, cached_checker(m), m.start, m.goal, vehicle=wide)



@pytest.mark.parametrize(
    ("start", "words"),
    [
        (Pose(49.0, 44.0, 0.0), "overlaps obstacle 2"),
        (Pose(-5.0, 44.0, 0.0), "lies outside the bounds"),
        (Pose(5.0, 44.0, 1e12), "yaw 1e+12 rad is beyond"),
    ],
)
def test_an_invalid_start_says_why_in_the_maps_words(start, words):
    # The problem's own constructor takes any start; the planner answers invalid_start,
    # and said "collides there" for each of these.
    from rrtdrive.planning.base import cached_checker
    from rrtdrive.types import PlanStatus

    m = builtin_map("overtake")
    problem = PlanningProblem(m, cached_checker(m), start, m.goal)
    for name in ("improved-rrt-connect", "hybrid-a-star", "rrt-connect"):
        r = make_planner(name).solve(problem, np.random.default_rng(0), Budget())
        assert r.status is PlanStatus.INVALID_START and r.message.startswith("start: ")
        assert words in r.message, (name, r.message)


def test_huge_integers_inside_values_are_named_not_crashed_on():
    # An int of 5000 digits inside a list: brief_repr called .bit_length() on the list
    # (AttributeError); a gym action or a jitter of 10**400 overflowed float().
    import gymnasium as gym

    import rrtdrive.envs  # noqa: F401  (registers the envs)
    from rrtdrive.sim.tasks import make_scenario
    from rrtdrive.types import brief_repr

    assert brief_repr([0, 10**5000]) == "a list holding an integer too long to print"
    with pytest.raises(InputError, match=r"^bounds: .*too long to print"):
        Map("m", [0, 0, 10**5000], (), Pose(1, 1, 0), Pose(2, 2, 0))
    with pytest.raises(InputError, match=r"^jitter: "):
        make_scenario("parking", 0, jitter=(10**400, 0.5, 0.1))
    env = gym.make("rrtdrive/Parking-v0")
    env.reset(seed=0)
    for action in ([0.5, 10**400], [None, 10**5000]):
        with pytest.raises(InputError, match=r"^action: expected two finite numbers"):
            env.step(action)
    env.close()


def test_option_mappings_with_keys_that_are_not_names_are_bad_input():
    from rrtdrive.envs.config import DriveEnvConfig

    with pytest.raises(InputError, match=r"^controller_options: keys must be option names"):
        DriveEnvConfig(scenario="parking", controller_options={1: 2})


def test_a_users_car_is_taken_whole():
    # Found by an audit of custom cars: each of these failed for a car other than the stock one.
    import dataclasses

    from rrtdrive.sim.scenes import build_env
    from rrtdrive.sim.tasks import make_scenario
    from rrtdrive.types import PlanStatus, VehicleParams

    # A numpy steering rate, as the other fields take numpy numbers.
    assert VehicleParams(max_steer_rate=np.float32(0.3)).max_steer_rate == pytest.approx(0.3)
    # A turning radius whose arcs would run to gigabytes of samples: refused, named.
    with pytest.raises(InputError, match=r"^vehicle.min_turning_radius: at most"):
        VehicleParams(min_turning_radius=1e6)
    # A car steering at 0.03 rad/s: the bound (0.015 rad/m) fell under the gentlest
    # turns' sharpness and the planner raised about a setting the user never touched.
    slow = dataclasses.replace(builtin_map("overtake"), vehicle=VehicleParams(max_steer_rate=0.03))
    r = make_planner("improved-rrt-connect").solve(
        PlanningProblem.from_map(slow), np.random.default_rng(0),
        Budget(max_iterations=300, max_time_s=20),
    )
    assert isinstance(r.status, PlanStatus)
    # The overtake scenario with a car of another size (its stopped car is a stock one).
    car = VehicleParams(length=4.8, width=1.9)
    task = make_scenario("overtake", 0, vehicle=car)
    assert task.vehicle == car
    # highway-env's normalised full lock is the car's own.
    wide_lock = VehicleParams(max_steer=0.6109, min_turning_radius=3.7)
    env = build_env(make_scenario("parking", 0, vehicle=wide_lock))
    assert env.unwrapped.config["action"]["steering_range"] == [-0.6109, 0.6109]
    env.close()


# Session 31's QA pass of the API as a student would use it.


def test_evaluate_names_a_wrong_argument_instead_of_an_attribute_error() -> None:
    from rrtdrive.evaluation import evaluate

    for wrong in (None, "parking", {"log": None}):
        with pytest.raises(InputError, match=r"^episode: expected an Episode .* got "):
            evaluate(wrong)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("field", "value", "says"),
    [
        ("max_time_s", "5", r"^episode\.max_time_s: expected a number, got '5'"),
        ("controller_options", [1], r"^episode\.controller_options: expected a mapping"),
        ("budget", None, r"^episode\.budget: expected a Budget, got NoneType"),
        ("sim", {"simulation_frequency": 20}, r"^episode\.sim: expected a SimConfig"),
        ("speed", 3.0, r"^episode\.speed: expected a SpeedConfig or None, got float"),
        ("replan", {"rate_hz": 2}, r"^episode\.replan: expected a ReplanConfig or None"),
        ("stop_on_crash", "no", r"^episode\.stop_on_crash: expected true or false"),
    ],
)
def test_an_episode_config_names_a_field_of_the_wrong_kind(field, value, says) -> None:
    from rrtdrive.sim.runner import EpisodeConfig

    with pytest.raises(InputError, match=says):
        EpisodeConfig(**{field: value})


def test_run_episode_and_the_stock_drive_refuse_a_config_that_is_not_an_episode_config() -> None:
    from rrtdrive.sim.runner import run_episode
    from rrtdrive.sim.stock import drive_stock_env

    for run in (run_episode, drive_stock_env):
        with pytest.raises(InputError, match=r"^config: expected an EpisodeConfig, got dict"):
            run("parking" if run is run_episode else "parking-v0",  # type: ignore[operator]
                config={"max_time_s": 2.0})


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_a_path_with_a_non_finite_number_is_refused_naming_row_and_column(bad) -> None:
    rows = np.array([[5.0, 5.0, 0.0, 0.0, 1.0], [6.0, 5.0, 0.0, 0.0, 1.0], [7.0, 5.0, 0, 0, 1]])
    rows[1, 2] = bad
    with pytest.raises(InputError, match=r"^path\.samples: must be finite, got .* in row 1, "
                       r"column 2$"):
        Path(rows, np.zeros((0, 2)))
    with pytest.raises(InputError, match=r"^path\.waypoints: must be finite"):
        Path(rows[[0, 2]], np.array([[0.0, 0.0], [bad, 1.0]]))


def test_a_plan_result_shares_no_writable_data_with_its_planner_or_its_copies() -> None:
    problem = PlanningProblem.from_map(builtin_map("parking_lot"))
    res = make_planner("improved-rrt-connect").solve(
        problem, np.random.default_rng(0), Budget(max_iterations=3000)
    )
    assert res.success, res.message
    for array in (res.path.samples, res.raw_path, *(a for t in res.trees
                                                     for a in (t.nodes, t.parents))):
        assert not array.flags.writeable
        with pytest.raises(ValueError, match="read-only"):
            array[0] = 0
    caller_rows = np.zeros((3, 2))
    import dataclasses

    copy = dataclasses.replace(res, raw_path=caller_rows)
    caller_rows[0, 0] = 9.0  # the caller's own array stays writable and apart
    assert copy.raw_path[0, 0] == 0.0 and caller_rows.flags.writeable
    copy.stats["mine"] = 1.0
    assert "mine" not in res.stats and isinstance(copy.stats, dict)


def test_numpy_numbers_in_bounds_and_budget_become_plain_python_numbers() -> None:
    import json

    m = Map("np", np.array([0.0, 0.0, 30.0, 20.0]), (), START, GOAL)
    assert m.bounds == (0.0, 0.0, 30.0, 20.0) and all(type(v) is float for v in m.bounds)
    b = Budget(max_iterations=np.int64(100), max_time_s=np.float32(2.5))
    assert type(b.max_iterations) is int and type(b.max_time_s) is float
    assert json.dumps([b.max_iterations, b.max_time_s]) == "[100, 2.5]"
    with pytest.raises(InputError, match=r"^bounds: expected \[xmin, ymin, xmax, ymax\]"):
        Map("np", np.zeros((2, 2)), (), START, GOAL)
