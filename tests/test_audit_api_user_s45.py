"""Session 45 audit: rrtdrive used as a Python library by an AV engineer.

Small maps built in Python; every registered planner forward and with reverse; the
PlanResult fields; the independent check; closed-loop episodes with each controller
and their metrics against independent computations (shapely, numpy); the gymnasium
environment under gymnasium's own tooling. Bugs found are strict xfails.
"""

from __future__ import annotations

import dataclasses
import math

import gymnasium as gym
import numpy as np
import pytest
import shapely
from gymnasium.envs.registration import EnvSpec
from gymnasium.utils.env_checker import check_env
from gymnasium.wrappers import FlattenObservation, RecordEpisodeStatistics, TimeLimit

import rrtdrive  # noqa: F401  (registers the gymnasium ids)
from rrtdrive import Budget, InputError, Map, Obstacle, Path, PlanStatus, Pose, VehicleParams
from rrtdrive.evaluation import evaluate
from rrtdrive.geometry import wrap_angle
from rrtdrive.planning import PLANNERS, PlanningProblem, make_planner, reverses
from rrtdrive.sim.runner import EpisodeConfig, run_episode
from rrtdrive.sim.tasks.custom import CustomTask
from rrtdrive.verify import verify_path

CAR = VehicleParams()
# Our planners: the OMPL comparators are registered once rrtdrive.bench is imported (by
# another test in the same process, or not) and need OMPL; their own test is at the end.
OURS = sorted(n for n in PLANNERS if not n.startswith("ompl-"))
LOT = Map("my_lot", (0, 0, 40, 20), (Obstacle((20, 10), (4, 6)),), Pose(3, 3, 0), Pose(35, 3, 0))
#: A bend round a long wall: every controller has to steer.
BEND = Map("bend", (0, 0, 40, 30), (Obstacle((20, 8), (4, 16)),), Pose(3, 3, 0),
           Pose(35, 25, math.pi / 2))  # fmt: skip
#: A street 8 m wide, goal facing back the way the car came: needs gear changes.
STREET = Map("street", (0, 0, 30, 8), (), Pose(5, 2.5, 0), Pose(20, 5.5, math.pi))
REVERSING = ("hybrid-a-star", "improved-rrt-connect")


def _solve(name: str, m: Map, reverse: bool, seed: int = 0, iterations: int = 4000):
    problem = PlanningProblem.from_map(m, reverse=reverse)
    return make_planner(name).solve(
        problem, np.random.default_rng(seed), Budget(max_iterations=iterations)
    )


def _body(x: float, y: float, yaw: float) -> shapely.Polygon:
    """The car's body at a rear-axle pose, built here from VehicleParams alone."""
    c, s = math.cos(yaw), math.sin(yaw)
    pts = [(-CAR.rear_overhang, -CAR.width / 2), (CAR.front_extent, -CAR.width / 2),
           (CAR.front_extent, CAR.width / 2), (-CAR.rear_overhang, CAR.width / 2)]  # fmt: skip
    return shapely.Polygon([(x + c * a - s * b, y + s * a + c * b) for a, b in pts])


# ----------------------------------------------------------------------------- planning


@pytest.mark.parametrize("reverse", [False, True])
@pytest.mark.parametrize("name", OURS)
def test_every_planner_returns_a_well_formed_result(name, reverse):
    result = _solve(name, LOT, reverse)
    again = _solve(name, LOT, reverse)
    assert isinstance(result.status, PlanStatus) and result.status is PlanStatus.SOLVED
    assert result.success and isinstance(result.message, str) and result.message
    rows = result.path.samples
    assert rows.ndim == 2 and rows.shape[1] == 5 and len(rows) >= 2
    assert set(np.unique(rows[:, 4])) <= {-1.0, 1.0}
    # from exactly the start position to exactly the goal position, rows <= 0.25 m apart
    assert np.allclose(rows[0, :2], LOT.start.xy, atol=1e-9)
    assert np.allclose(rows[-1, :2], LOT.goal.xy, atol=1e-9)
    assert np.hypot(*np.diff(rows[:, :2], axis=0).T).max() <= 0.25 + 1e-9
    assert result.path.cusps.tolist() == (np.flatnonzero(np.diff(rows[:, 4])) + 1).tolist()
    if not reverses(name):
        assert result.path.is_forward_only
    # a seed decides the result
    assert again.status is result.status
    assert np.array_equal(again.path.samples, result.path.samples)
    # result data are read-only
    with pytest.raises(ValueError):
        result.path.samples[0, 0] = 1.0
    with pytest.raises(dataclasses.FrozenInstanceError):
        result.status = PlanStatus.TIMEOUT  # type: ignore[misc]


@pytest.mark.parametrize("name", REVERSING)
def test_reversing_planners_turn_round_in_a_narrow_street_and_verify(name):
    result = _solve(name, STREET, reverse=True)
    assert result.status is PlanStatus.SOLVED, result.message
    cusps = result.path.cusps
    assert len(cusps) >= 1 and not result.path.is_forward_only
    # a cusp repeats the position and the yaw with the new gear
    rows = result.path.samples
    assert np.allclose(rows[cusps, :3], rows[cusps - 1, :3])
    assert np.all(rows[cusps, 4] == -rows[cusps - 1, 4])
    # Path.length is the distance travelled (a cusp adds nothing)
    assert result.path.length == pytest.approx(np.hypot(*np.diff(rows[:, :2], axis=0).T).sum())
    check = verify_path(STREET, result.path, max_sharpness=0.2)
    assert check.ok, check.failed
    assert check.cusps == len(cusps)


@pytest.mark.parametrize("name", sorted(set(OURS) - set(REVERSING)))
def test_forward_only_planners_ignore_reverse(name):
    result = _solve(name, STREET, reverse=True)
    assert result.path.is_forward_only and len(result.path.cusps) == 0


def test_invalid_start_goal_and_zero_length_queries_get_their_statuses():
    checker = PlanningProblem.from_map(LOT).checker
    for name in OURS:
        planner = make_planner(name)
        rng, budget = np.random.default_rng(0), Budget(max_iterations=200)
        bad_start = planner.solve(PlanningProblem(LOT, checker, Pose(-50, 3, 0), LOT.goal), rng,
                                  budget)  # fmt: skip
        assert bad_start.status is PlanStatus.INVALID_START and "start" in bad_start.message
        bad_goal = planner.solve(PlanningProblem(LOT, checker, LOT.start, Pose(20, 10, 0)), rng,
                                 budget)  # fmt: skip
        assert bad_goal.status is PlanStatus.INVALID_GOAL and "goal" in bad_goal.message
        same = planner.solve(PlanningProblem(LOT, checker, LOT.start, LOT.start), rng, budget)
        assert same.status is PlanStatus.SOLVED and len(same.path) == 2
        assert same.path.length == 0.0


def test_checker_agrees_with_shapely_bodies():
    obstacles = (Obstacle((20, 10), (4, 6), 0.3), Obstacle((8, 15), (3, 1), 1.0),
                 Obstacle((30, 5), (2, 2), -0.7))  # fmt: skip
    m = Map("odd", (0, 0, 40.05, 20.03), obstacles, Pose(3, 3, 0), Pose(35, 15, 0))
    checker = PlanningProblem.from_map(m).checker
    union = shapely.union_all([o.polygon() for o in obstacles])
    inside = shapely.box(*m.bounds)
    rng = np.random.default_rng(1)
    poses = np.column_stack([rng.uniform(-1, 41, 1500), rng.uniform(-1, 21, 1500),
                             rng.uniform(-4, 4, 1500)])  # fmt: skip
    free, clear = [], []
    for x, y, yaw in poses:
        b = _body(x, y, yaw)
        ok = inside.contains(b) and not b.intersects(union) and not b.intersects(inside.exterior)
        free.append(ok)
        clear.append(min(union.distance(b), inside.exterior.distance(b)) if ok else 0.0)
    free, clear = np.array(free), np.array(clear)
    assert 0 < free.sum() < len(free)
    assert np.array_equal(checker.poses_free(poses), free)
    assert np.array_equal(checker.poses_free(poses, clearance=0.3), free & (clear >= 0.3))
    some = poses[:200]
    assert np.allclose([checker.body_clearance(p) for p in some], clear[:200], atol=1e-9)


@pytest.mark.parametrize("gap", [0.05, 0.3, -0.01])
def test_verify_clearance_matches_shapely(gap):
    obstacles = (Obstacle((20, 3 + CAR.width / 2 + gap + 1), (4, 2)),)
    m = Map("g", (0, 0, 40, 20), obstacles, Pose(3, 3, 0), Pose(35, 3, 0), check_query=False)
    xs = np.arange(3, 35.001, 0.25)
    path = Path(np.column_stack([xs, 3 + 0 * xs, 0 * xs, 0 * xs, 1 + 0 * xs]), np.zeros((0, 2)))
    check = verify_path(m, path)
    edge = shapely.box(*m.bounds).exterior
    ref = min(min(obstacles[0].polygon().distance(_body(x, 3, 0)), edge.distance(_body(x, 3, 0)))
              for x in np.arange(3, 35.001, 0.1))  # fmt: skip
    assert check.min_clearance_m == pytest.approx(ref, abs=1e-9)
    assert check.collision_free is (gap > 0)
    if gap < 0:
        assert check.collides_with == "obstacle 0" and check.first_collision is not None


# ----------------------------------------------------------------------------- closed loop


@pytest.mark.parametrize("controller", ["pure-pursuit", "stanley", "lqr"])
def test_closed_loop_metrics_match_independent_computation(controller):
    ep = run_episode(CustomTask.from_map(BEND), controller=controller, seed=0)
    rep = evaluate(ep)
    assert ep.status == "arrived" and rep.success
    st, u, dt = ep.log.states, ep.log.controls, ep.log.dt
    line = shapely.LineString(ep.path.xy)
    cte = np.array([line.distance(shapely.Point(p)) for p in st[:, :2]])
    kappa = np.tan(u[:, 1]) / CAR.wheelbase
    steer_rate = np.abs(np.diff(np.concatenate([[0.0], u[:, 1]]))) / dt
    goal = BEND.goal
    expect = {
        "cte_rms_m": math.sqrt(np.mean(cte**2)),
        "cte_max_m": cte.max(),
        "executed_max_curvature": np.abs(kappa).max(),
        "max_steering_rate": steer_rate.max(),
        "max_lateral_accel": (st[:-1, 3] ** 2 * np.abs(kappa)).max(),
        "max_long_accel": np.abs(u[:, 0]).max(),
        "goal_position_err_m": math.hypot(st[-1, 0] - goal.x, st[-1, 1] - goal.y),
        "goal_heading_err_rad": abs(wrap_angle(st[-1, 2] - goal.yaw)),
        "duration_s": ep.log.t[-1],
        "path_length_m": ep.path.length,
    }
    for key, value in expect.items():
        assert getattr(rep, key) == pytest.approx(value, rel=1e-6, abs=1e-9), key
    assert rep.steps == len(u)
    assert rep.executed_max_curvature <= CAR.kappa_max * (1 + 1e-9)


@pytest.mark.parametrize("controller", ["pure-pursuit", "stanley", "lqr"])
def test_a_planned_reversing_path_is_driven_by_every_controller(controller):
    plan = _solve("hybrid-a-star", STREET, reverse=True)
    task = CustomTask.from_map(STREET, reverse=True)
    by_plan = run_episode(task, planner=plan, controller=controller, seed=0)
    by_path = run_episode(task, planner=plan.path, controller=controller, seed=0)
    for ep in (by_plan, by_path):
        rep = evaluate(ep)
        assert ep.status == "arrived" and rep.success and not rep.collision
        assert rep.path_cusps == len(plan.path.cusps) == rep.gear_changes
    assert np.array_equal(by_plan.log.states, by_path.log.states)
    assert evaluate(by_path).planner == "given"


def test_episode_log_arrays_are_read_only():
    ep = run_episode(CustomTask.from_map(LOT), seed=0)
    with pytest.raises(ValueError):
        ep.log.states[-1, 0] = 0.0


# ----------------------------------------------------------------------------- bad input


@pytest.mark.parametrize(
    ("make", "field"),
    [
        (lambda: Map("a", (0, 0, 10, 10), (), Pose(-5, 5, 0), Pose(5, 5, 0)), "start"),
        (
            lambda: Map(
                "a", (0, 0, 40, 10), (Obstacle((30, 5), (2, 2)),), Pose(5, 5, 0), Pose(30, 5, 0)
            ),
            "goal",
        ),  # fmt: skip
        (lambda: Obstacle((1, 1), (-1, 2)), "obstacle.size"),
        (lambda: Budget(max_iterations=0), "budget.max_iterations"),
        (lambda: make_planner("rrt", bogus=1), "planner.bogus"),
        (lambda: make_planner("improved-rrt-connect", step=-1), "planner.step"),
        (lambda: PlanningProblem.from_map(LOT, reverse="yes"), "reverse"),
        (lambda: make_planner("rrt").solve(PlanningProblem.from_map(LOT), 0, Budget()), "rng"),
        (lambda: verify_path(LOT, Path.empty(), pose_spacing=0), "pose_spacing"),
        (lambda: verify_path(LOT, Path.empty(), clearance=-1), "clearance"),
        (lambda: run_episode(CustomTask.from_map(LOT), controller="pid"), "controller"),
        (lambda: run_episode(CustomTask.from_map(LOT), seed=-1), "seed"),
        (lambda: EpisodeConfig(max_time_s=-1), "episode.max_time_s"),
        (lambda: CustomTask.from_map(LOT, goal=LOT.start), "goal"),
        (lambda: evaluate("x"), "episode"),
    ],
)
def test_bad_input_names_the_field(make, field):
    with pytest.raises(InputError) as err:
        make()
    assert str(err.value).startswith(f"{field}:")


# ----------------------------------------------------------------------------- gymnasium

SMALL = Map("my_lot", (0, 0, 40, 20), (Obstacle((20, 10), (4, 2)),), Pose(3, 3, 0),
            Pose(35, 3, 0))  # fmt: skip


def test_gym_map_env_passes_check_env_and_seeds_reproducibly():
    env = gym.make("rrtdrive/Map-v0", scenario=SMALL)
    check_env(env.unwrapped)
    o1, i1 = env.reset(seed=5)
    o2, i2 = env.reset(seed=5)
    other = gym.make("rrtdrive/Map-v0", scenario=SMALL)
    o3, i3 = other.reset(seed=5)
    assert np.array_equal(o1, o2) and np.array_equal(o1, o3)
    assert i1 == i2 == i3 and i1["scenario"] == "my_lot"
    assert env.observation_space.contains(o1) and o1.dtype == np.float32
    space = env.action_space
    assert space.shape == (2,) and np.all(space.low == -1) and np.all(space.high == 1)
    # the drawn episode seeds follow the seed
    env.reset(seed=11)
    first = [env.reset()[1]["episode_seed"] for _ in range(3)]
    env.reset(seed=11)
    assert [env.reset()[1]["episode_seed"] for _ in range(3)] == first


def test_gym_reset_options_as_documented():
    env = gym.make("rrtdrive/Map-v0", scenario=SMALL, disable_env_checker=True)
    _, info = env.reset(options={"episode_seed": 7})
    assert info["episode_seed"] == 7
    for options, field in (({"bogus": 1}, "options.bogus"),
                           ({"episode_seed": -1}, "options.episode_seed"),
                           ({"episode_seed": 1.0}, "options.episode_seed")):  # fmt: skip
        with pytest.raises(InputError) as err:
            env.reset(options=options)
        assert str(err.value).startswith(f"{field}:")


def test_gym_reset_episode_seed_is_run_episode_for_a_reversing_map():
    env = gym.make("rrtdrive/Map-v0", scenario=STREET, scenario_options={"reverse": True},
                   residual=True, controller="lqr")  # fmt: skip
    env.reset(options={"episode_seed": 4})
    while True:
        obs, _, terminated, truncated, info = env.step(np.zeros(2, np.float32))
        assert env.observation_space.contains(obs)
        if terminated or truncated:
            break
    ep = run_episode(CustomTask.from_map(STREET, reverse=True, seed=4), controller="lqr", seed=4)
    mine = env.unwrapped.episode
    assert info["status"] == "arrived" and info["is_success"] is True
    assert np.array_equal(mine.path.samples, ep.path.samples)
    assert np.array_equal(mine.log.states, ep.log.states)


def test_gym_wrappers_work():
    env = RecordEpisodeStatistics(TimeLimit(FlattenObservation(
        gym.make("rrtdrive/Map-v0", scenario=SMALL, residual=True)), 40))  # fmt: skip
    obs, _ = env.reset(seed=1)
    assert obs.shape == (38,)
    steps = 0
    while True:
        _, _, terminated, truncated, info = env.step(np.zeros(2, np.float32))
        steps += 1
        if terminated or truncated:
            break
    assert steps == 40 and truncated and not terminated
    assert info["episode"]["l"] == 40


def test_gym_spec_json_round_trip_for_a_map_name():
    env = gym.make("rrtdrive/Map-v0", scenario="kerbside", scenario_options={"reverse": True})
    again = gym.make(EnvSpec.from_json(env.spec.to_json()))
    assert np.array_equal(env.reset(seed=0)[0], again.reset(seed=0)[0])


def test_gym_spec_json_round_trip_for_a_map_built_in_python():
    env = gym.make("rrtdrive/Map-v0", scenario=SMALL)
    again = gym.make(EnvSpec.from_json(env.spec.to_json()))
    assert np.array_equal(env.reset(seed=0)[0], again.reset(seed=0)[0])


def test_gym_config_is_frozen_all_the_way_down():
    env = gym.make("rrtdrive/Map-v0", scenario="kerbside", scenario_options={"reverse": True})
    config = env.unwrapped.config
    with pytest.raises(TypeError):
        config.scenario_options["reverse"] = False  # type: ignore[index]
    assert hash(config) == hash(config.with_options())
    assert config.scenario_options == {"reverse": True}
    import copy
    import pickle

    assert pickle.loads(pickle.dumps(config.scenario_options)) == config.scenario_options
    assert copy.deepcopy(config) == config
    episode = EpisodeConfig(controller_options={"lookahead": {"min": 2.0}})
    with pytest.raises(TypeError):
        episode.controller_options["lookahead"]["min"] = 3.0  # type: ignore[index]
    assert hash(episode) == hash(EpisodeConfig(controller_options={"lookahead": {"min": 2.0}}))


def test_ompl_comparators_answer_a_start_that_is_the_goal_as_every_planner_does():
    pytest.importorskip("ompl")
    import rrtdrive.bench  # noqa: F401  (registers the OMPL comparators)

    same = PlanningProblem(LOT, PlanningProblem.from_map(LOT).checker, LOT.start, LOT.start)
    names = [n for n in sorted(PLANNERS) if n.startswith("ompl-")]
    assert names
    for name in names:
        out = make_planner(name).solve(same, np.random.default_rng(0), Budget(max_time_s=1.0))
        assert out.status is PlanStatus.SOLVED, name
        assert len(out.path) == 2 and out.path.length == 0.0, name
        assert np.allclose(out.path.samples[:, :3], [LOT.start.as_tuple()] * 2)


def test_gym_info_time_is_the_step_count_times_dt():
    env = gym.make("rrtdrive/Map-v0", scenario=SMALL)
    env.reset(seed=0)
    dt = 1.0 / env.unwrapped.config.simulation_frequency
    for k in range(1, 31):
        *_, info = env.step(np.zeros(2, dtype=np.float32))
        assert info["time_s"] == k * dt  # no running sum's drift
    env.close()
