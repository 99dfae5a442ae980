"""Audit (session 48): the default planner's escalation and budget contract.

``improved-rrt-connect`` is the first attempt (the paper's pipeline, unchanged when it
succeeds); when it fails it escalates (Dubins fallback, then a kinematic Hybrid A*
search, forward only or with reversing under ``--reverse``); the JSON's ``stage`` and
the message say which stage solved it. Counted budgets decide; the wall-clock cap is
only a safety net whose own status is ``timeout``; per-map set-up is ``setup_time_s``,
never ``planning_time_s``; a seeded plan's JSON is the same on a fast and a slow machine
(timing fields aside).
"""

from __future__ import annotations

import json
import math
import pathlib
import time

import numpy as np
import pytest

import rrtdrive.collision.checker as checker_module
import rrtdrive.planning.checker_cache as checker_cache
import rrtdrive.planning.hybrid.resolution as resolution_module
from rrtdrive.cli import main, plan_to_json
from rrtdrive.collision import CollisionChecker
from rrtdrive.maps import builtin_map, save_map
from rrtdrive.planning import PlanningProblem, make_planner
from rrtdrive.planning.base import Stopwatch
from rrtdrive.planning.improved import ImprovedRRTConnect
from rrtdrive.types import Budget, PlanStatus, Pose

#: The plan JSON's timing fields (docs/planning.md): the only ones a machine may change.
TIMING = {"planning_time_s", "setup_time_s", "diagnosis_time_s"}
HOME_GARAGE = pathlib.Path(__file__).resolve().parents[1] / "docs" / "maps" / "home_garage.json"
#: Every collision test the planners (tree stages, fallback, Hybrid A*) make.
CHECKER_METHODS = (
    "edge_free", "pose_free", "pose_free_fast", "poses_free", "poses_free_fast",
    "poses_free_unscreened", "rectangles_free", "axis_clearances", "body_clearance",
    "clearance", "path_free",
)  # fmt: skip
STAGES = {"improved-rrt-connect", "dubins-fallback", "hybrid-a-star"}


def plan(tmp_path, capsys, *args: str) -> tuple[int, dict, str]:
    """``rrtdrive plan ARGS --json F`` in-process: exit code, the JSON, stderr."""
    out = tmp_path / f"plan{len(list(tmp_path.iterdir()))}.json"
    capsys.readouterr()
    code = main(["plan", *args, "--json", str(out)])
    err = capsys.readouterr().err
    doc = json.loads(out.read_text()) if out.exists() else {}
    return code, doc, err


def counted(doc: dict) -> dict:
    return {k: v for k, v in doc.items() if k not in TIMING}


def slow_down(monkeypatch, delay: float) -> None:
    """A slower machine: every collision test sleeps ``delay`` seconds first."""
    for name in CHECKER_METHODS:
        real = getattr(CollisionChecker, name)

        def slow(self, *a, _real=real, **k):  # noqa: ANN001, ANN002, ANN003, ANN202
            time.sleep(delay)
            return _real(self, *a, **k)

        monkeypatch.setattr(CollisionChecker, name, slow)


# --- every stage is reached, and reported as such ------------------------------------

STAGE_QUERIES = {
    # (args, stage, message start, cusps allowed)
    "tree": (("parking_lot",), "improved-rrt-connect", "solved:", False),
    "dubins": (("garage",), "dubins-fallback", "solved by the Dubins fallback", False),
    "hybrid-forward": (
        ("garage", "--disable", "dubins_fallback"), "hybrid-a-star",
        "solved by the Hybrid A* escalation", False,
    ),
    "hybrid-reverse": (
        ("turning_bulb", "--reverse"), "hybrid-a-star",
        "solved by the Hybrid A* escalation", True,
    ),
    "dubins-reverse": (("garage", "--reverse"), "dubins-fallback",
                       "solved by the Dubins fallback", False),
}  # fmt: skip


@pytest.mark.parametrize("query", tuple(STAGE_QUERIES))
def test_each_stage_is_reached_and_named_in_json_and_message(tmp_path, capsys, query):
    args, stage, opening, cusps = STAGE_QUERIES[query]
    code, doc, _ = plan(tmp_path, capsys, *args, "--max-iterations", "3000")
    assert code == 0 and doc["success"] and doc["status"] == "solved"
    assert doc["planner"] == "improved-rrt-connect"
    assert doc["stage"] == stage
    assert doc["message"].startswith(opening), doc["message"]
    assert 1 <= doc["iterations"] <= 3000
    if stage == "hybrid-a-star":
        gear = "with reverse" if "--reverse" in args else "forward only"
        assert f"({gear}" in doc["message"]
        assert "the RRT-Connect stages failed" in doc["message"]
    assert (doc["cusps"] >= 1) if cusps else doc["cusps"] == 0
    assert doc["planning_time_s"] >= 0.0 and doc["setup_time_s"] >= 0.0
    assert doc["diagnosis_time_s"] is None and doc["diagnosis"] is None


def test_a_failure_has_no_stage_and_a_counted_status(tmp_path, capsys):
    code, doc, _ = plan(tmp_path, capsys, "dead_end", "--max-iterations", "600")
    assert code == 1 and not doc["success"]
    assert doc["stage"] is None and doc["length_m"] is None
    assert doc["status"] in {"no_path_in_budget", "postprocess_failed", "proven_unreachable"}
    # It escalated before it gave up, and says so.
    assert "Hybrid A* (forward only)" in doc["message"]
    assert doc["iterations"] <= 600


# --- the ablation switches keep working --------------------------------------------

@pytest.mark.parametrize(
    ("args", "forbidden"),
    [
        (("garage", "--disable", "escalation"), {"hybrid-a-star"}),
        (("garage", "--disable", "dubins_fallback"), {"dubins-fallback"}),
        (("garage", "--disable", "dubins_fallback", "--disable", "escalation"),
         {"hybrid-a-star", "dubins-fallback"}),
        (("turning_bulb", "--reverse", "--disable", "escalation"), {"hybrid-a-star"}),
        (("turning_bulb", "--reverse", "--disable", "dubins_fallback"), {"dubins-fallback"}),
        (("kerbside", "--reverse", "--disable", "escalation", "--disable", "prune"),
         {"hybrid-a-star"}),
    ],
)  # fmt: skip
def test_a_disabled_stage_never_answers(tmp_path, capsys, args, forbidden):
    code, doc, err = plan(tmp_path, capsys, *args, "--max-iterations", "2000")
    assert (code == 0) == doc["success"]
    assert doc["stage"] not in forbidden
    assert doc["stage"] is None or doc["stage"] in STAGES
    if "hybrid-a-star" in forbidden:
        assert "Hybrid A*" not in doc["message"]
        if doc["success"]:
            assert doc["cusps"] == 0  # it reverses only in the escalation
        if "--reverse" in args:
            assert "plans forward only with --disable escalation" in err
    if "dubins-fallback" in forbidden:
        assert "solved by the Dubins fallback" not in doc["message"]
    disabled = sorted(a for i, a in enumerate(args) if i and args[i - 1] == "--disable")
    assert sorted(doc["planner_options"]["disable"]) == disabled


def test_the_paper_pipeline_keeps_the_whole_budget_and_never_escalates():
    problem = PlanningProblem.from_map(builtin_map("turning_bulb"), reverse=True)
    budget = Budget(max_iterations=300)
    paper = ImprovedRRTConnect(disable=("escalation", "dubins_fallback"))
    out = paper.solve(problem, np.random.default_rng(0), budget)
    assert out.stats["rrt_iterations"] == 300
    assert not any(k.startswith("hybrid_") for k in out.stats)
    assert "Hybrid A*" not in out.message and "Dubins" not in out.message
    assert out.status is not PlanStatus.SOLVED or len(out.path.cusps) == 0
    default = ImprovedRRTConnect().solve(problem, np.random.default_rng(0), budget)
    assert default.stats["rrt_iterations"] == math.ceil(0.5 * 300)
    assert default.iterations <= 300


@pytest.mark.parametrize("map_name", ["parking_lot", "overtake", "narrow_gap"])
@pytest.mark.parametrize("paper_smoothing", [False, True])
def test_the_paper_pipeline_is_unchanged_when_it_succeeds(map_name, paper_smoothing):
    """Table 3's queries: the default answers exactly as the paper's pipeline alone."""
    problem = PlanningProblem.from_map(builtin_map(map_name))
    smoothing = {"smoothing": {"curve": "bspline"}} if paper_smoothing else {}
    for seed in range(3):
        alone = make_planner(
            "improved-rrt-connect", disable=("escalation", "dubins_fallback"), **smoothing
        ).solve(problem, np.random.default_rng(seed), Budget())
        default = make_planner("improved-rrt-connect", **smoothing).solve(
            problem, np.random.default_rng(seed), Budget()
        )
        assert alone.success and default.success
        a = plan_to_json(alone, seed, map_name)
        b = plan_to_json(default, seed, map_name)
        assert counted(a) == counted(b)
        assert b["stage"] == "improved-rrt-connect"


# --- tiny budgets and the safety cap --------------------------------------------------

@pytest.mark.parametrize(
    "args",
    [("parking_lot",), ("turning_bulb",), ("turning_bulb", "--reverse"),
     ("kerbside", "--reverse"), ("garage",), ("dead_end", "--reverse")],
)  # fmt: skip
@pytest.mark.parametrize("n", ["1", "2"])
def test_a_tiny_iteration_budget_is_a_counted_answer_never_a_timeout(tmp_path, capsys, args, n):
    code, doc, _ = plan(tmp_path, capsys, *args, "--max-iterations", n)
    assert doc["status"] != "timeout"
    assert "safety cap" not in doc["message"]
    assert doc["iterations"] <= int(n)
    assert doc["max_iterations"] == int(n)
    assert (code == 0) == doc["success"]
    assert (doc["stage"] is None) == (not doc["success"])


@pytest.mark.parametrize("args", [("parking_lot",), ("turning_bulb", "--reverse"), ("garage",)])
def test_a_tiny_cap_on_a_slow_machine_is_a_timeout_with_its_message(
    tmp_path, capsys, monkeypatch, args
):
    slow_down(monkeypatch, 2e-3)
    code, doc, _ = plan(tmp_path, capsys, *args, "--max-time", "0.001")
    assert code == 1 and doc["status"] == "timeout" and not doc["success"]
    assert doc["stage"] is None and doc["length_m"] is None and doc["path"] == []
    assert doc["message"].startswith("stopped by the 0.001 s safety cap after ")
    assert "raise --max-time or lower --max-iterations" in doc["message"]
    assert doc["max_time_s"] == 0.001


def test_a_huge_cap_changes_nothing(tmp_path, capsys):
    _, small, _ = plan(tmp_path, capsys, "turning_bulb", "--reverse")
    _, huge, _ = plan(tmp_path, capsys, "turning_bulb", "--reverse", "--max-time", "1e12")
    assert huge["max_time_s"] == 1e12
    assert {**counted(small), "max_time_s": None} == {**counted(huge), "max_time_s": None}


def test_the_cap_met_at_any_check_of_the_fallback_is_timeout_or_the_counted_answer(
    monkeypatch,
):
    """Forced at checks of the forward query the Dubins fallback solves (garage)."""
    problem = PlanningProblem.from_map(builtin_map("garage"))
    calls = {"n": None, "seen": 0}
    real = Stopwatch.expired

    def expired(self: Stopwatch) -> bool:
        calls["seen"] += 1
        if calls["n"] is not None and calls["seen"] >= calls["n"]:
            self.capped = True
        return real(self)

    monkeypatch.setattr(Stopwatch, "expired", expired)

    def solve():
        calls["seen"] = 0
        return make_planner("improved-rrt-connect").solve(
            problem, np.random.default_rng(0), Budget()
        )

    base = solve()
    total = calls["seen"]
    assert base.success and total > 10
    for n in sorted({1, 2, 3, total - 1, total, total + 1, *range(5, total, 37)}):
        calls["n"] = n
        got = solve()
        if got.status is PlanStatus.TIMEOUT:
            assert not got.success and "safety cap" in got.message
        else:
            assert (got.status, got.message, got.iterations) == (
                base.status, base.message, base.iterations,
            )  # fmt: skip


# --- the same JSON on a slow machine ---------------------------------------------------

SLOW_QUERIES = [
    ("garage",),
    ("garage", "--reverse", "--seed", "1"),
    ("turning_bulb", "--reverse", "--seed", "4"),
    ("kerbside", "--reverse"),
    ("garage", "--disable", "dubins_fallback", "--seed", "5"),
    ("turning_bulb", "--max-iterations", "500"),
]


@pytest.mark.parametrize("args", SLOW_QUERIES, ids=["-".join(a) for a in SLOW_QUERIES])
def test_a_seeded_plan_json_is_the_same_on_a_slow_machine(tmp_path, capsys, monkeypatch, args):
    code, fast, _ = plan(tmp_path, capsys, *args)
    with monkeypatch.context() as patch:
        slow_down(patch, 1e-4)
        slow_code, slow, _ = plan(tmp_path, capsys, *args)
    assert slow["planning_time_s"] > 0.0
    assert code == slow_code
    assert counted(fast) == counted(slow)


def test_a_failures_diagnosis_is_the_same_on_a_slow_machine(tmp_path, capsys, monkeypatch):
    args = (str(HOME_GARAGE), "--max-iterations", "10", "--max-time", "1")
    _, fast, _ = plan(tmp_path, capsys, *args)
    assert fast["status"] == "no_path_in_budget"
    assert fast["diagnosis"]["kind"] == "needs_reverse"
    with monkeypatch.context() as patch:
        slow_down(patch, 2e-3)
        _, slow, _ = plan(tmp_path, capsys, *args)
    # The planning itself finished within the cap, by its counts ...
    assert slow["status"] == "no_path_in_budget" and slow["planning_time_s"] < 1.0
    # ... so the whole JSON, its diagnosis included, must be the fast machine's.
    assert counted(fast) == counted(slow)


G93 = (53.201107188452056, 36.30433181948137, 2.404196106990101)


def test_a_kept_detour_counts_the_escalations_expansions():
    """docs/planning.md's example: random goal 93 with reverse and gear_change_cost=200."""
    m = builtin_map("parking_lot").with_query(goal=Pose(*G93))
    problem = PlanningProblem.from_map(m, reverse=True)
    kept = make_planner("improved-rrt-connect", hybrid={"gear_change_cost": 200}).solve(
        problem, np.random.default_rng(0), Budget()
    )
    assert kept.success and "costs more" in kept.message
    assert kept.stats.get("stage") is None and len(kept.path.cusps) == 0  # the detour
    spent = kept.stats["hybrid_expansions"]
    assert spent > 0
    # The same query and seed whose escalation's path is taken counts both.
    taken = make_planner("improved-rrt-connect").solve(
        problem, np.random.default_rng(0), Budget()
    )
    assert taken.stats["stage"] == "hybrid-a-star"
    assert taken.iterations == taken.stats["iterations"] + taken.stats["hybrid_expansions"]
    assert kept.iterations == kept.stats["iterations"] + spent


# --- set-up is never planning time ---------------------------------------------------

def test_map_setup_is_setup_time_not_planning_time(tmp_path, capsys, monkeypatch):
    """A slow distance field and a slow Hybrid A* grid: set-up, outside a 0.75 s cap."""
    monkeypatch.setattr(checker_cache, "_CHECKERS", {})  # this map's set-up is built afresh
    real_field = checker_module.distance_field
    real_grid = resolution_module.free_cell_graph

    calls = {"field": 0, "grid": 0}

    def slow_field(*a, **k):  # noqa: ANN002, ANN003, ANN202
        calls["field"] += 1
        time.sleep(0.8)
        return real_field(*a, **k)

    def slow_grid(*a, **k):  # noqa: ANN002, ANN003, ANN202
        calls["grid"] += 1
        time.sleep(0.8)
        return real_grid(*a, **k)

    monkeypatch.setattr(checker_module, "distance_field", slow_field)
    monkeypatch.setattr(resolution_module, "free_cell_graph", slow_grid)
    code, doc, _ = plan(tmp_path, capsys, "turning_bulb", "--reverse", "--max-time", "0.75")
    assert code == 0 and doc["status"] == "solved" and doc["stage"] == "hybrid-a-star"
    assert calls["field"] >= 1 and calls["grid"] >= 1
    assert doc["setup_time_s"] >= 1.6  # the field and the escalation's grid
    assert 0.0 <= doc["planning_time_s"] < 0.75


def test_huge_bounds_are_an_exit_2_naming_bounds(tmp_path, capsys):
    m = builtin_map("overtake")
    big = m.__class__(m.name, (0.0, 0.0, 1e6, 1e6), m.obstacles, m.start, m.goal)
    path = tmp_path / "big.json"
    save_map(big, path)
    capsys.readouterr()
    code = main(["plan", str(path), "--json", str(tmp_path / "out.json")])
    err = capsys.readouterr().err
    assert code == 2
    assert "bounds" in err and "Traceback" not in err
    assert not (tmp_path / "out.json").exists()


# --- the Python API agrees with the CLI ------------------------------------------------

@pytest.mark.parametrize(
    ("map_name", "reverse", "disable", "seed"),
    [("garage", False, (), 0), ("turning_bulb", True, (), 1),
     ("garage", False, ("escalation",), 2), ("kerbside", False, (), 0)],
)  # fmt: skip
def test_the_python_api_agrees_with_the_cli(tmp_path, capsys, map_name, reverse, disable, seed):
    args = [map_name, "--seed", str(seed), *(["--reverse"] if reverse else [])]
    for d in disable:
        args += ["--disable", d]
    _, cli, _ = plan(tmp_path, capsys, *args)
    m = builtin_map(map_name)
    options = {"disable": disable} if disable else {}
    result = make_planner("improved-rrt-connect", **options).solve(
        PlanningProblem.from_map(m, reverse=reverse), np.random.default_rng(seed), Budget()
    )
    api = plan_to_json(
        result, seed, m.name, m.vehicle, reverse=reverse, start=m.start, goal=m.goal,
        planner_options=options, budget=Budget(), resolution=0.1,
    )  # fmt: skip
    assert counted(api) == counted(cli)


def test_a_component_disabled_twice_is_named_once(tmp_path, capsys):
    code, doc, _ = plan(
        tmp_path, capsys, "garage", "--disable", "escalation", "--disable", "prune",
        "--disable", "escalation", "--max-iterations", "200",
    )
    assert code in (0, 1)
    assert doc["planner_options"]["disable"] == ["escalation", "prune"]


def test_a_failed_escalation_counts_the_searchs_nodes_as_a_success_does():
    # dead_end with reverse and 1 000 iterations: the escalation runs and finds none.
    problem = PlanningProblem.from_map(builtin_map("dead_end"), reverse=True)
    res = make_planner("improved-rrt-connect").solve(
        problem, np.random.default_rng(0), Budget(max_iterations=1000)
    )
    assert not res.success and res.stats["hybrid_hybrid_nodes"] > 0
    assert res.nodes == res.stats["nodes"] + res.stats["hybrid_hybrid_nodes"]
