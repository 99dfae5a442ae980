"""Bench planner rows with options (``NAME@FIELD=VALUE:...``): parsed, checked before any
run, one run key per row, and the options reach the planner in plan and episode runs."""

from __future__ import annotations

import json

import numpy as np
import pytest

from rrtdrive.bench import BenchConfig, expand
from rrtdrive.bench.config_file import load_toml
from rrtdrive.bench.planner_specs import PlannerSpec, parse_planner_spec
from rrtdrive.bench.worker import execute_run
from rrtdrive.cli import main
from rrtdrive.maps import builtin_map
from rrtdrive.planning import PlanningProblem, make_planner
from rrtdrive.types import Budget, InputError

STEP4 = "improved-rrt-connect@escalation=false:step=4"


def test_spec_parses_values_as_json_else_text_and_has_one_spelling():
    spec = parse_planner_spec("hybrid-a-star@step=0.5:curve=arcs")
    assert spec == PlannerSpec("hybrid-a-star", {"step": 0.5, "curve": "arcs"})
    assert spec.label == "hybrid-a-star@curve=arcs:step=0.5"
    assert parse_planner_spec(spec.label) == spec
    assert parse_planner_spec("rrt").label == "rrt"
    assert parse_planner_spec("improved-rrt-connect@reverse_detour_tree=false").options == {
        "reverse_detour_tree": False
    }


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ("rrt@step", ": expected FIELD=VALUE"),
        ("rrt@", ": nothing after '@'"),
        ("rrt@step=1:step=2", " step: given twice"),
        ("rrt@reverse=true", " reverse: give --reverse"),
    ],
)
def test_malformed_spec_is_named(text, match):
    with pytest.raises(InputError, match=f"^planners: '{text}'{match}"):
        parse_planner_spec(text)


@pytest.mark.parametrize(
    ("planner", "match"),
    [
        ("improved-rrt-connect@stepp=4", r"planner\.stepp: unknown option"),
        ("improved-rrt-connect@step=-1", r"planner\.step: must be > 0"),
        ("hybrid-a-star@curve=bad", r"hybrid\.curve: must be one of"),
        ("ompl-r2-rrtconnect@step=4", "the OMPL rows take no options"),
        ("nope@step=4", "unknown planner 'nope'"),
    ],
)
def test_bad_option_is_refused_before_any_run(planner, match):
    with pytest.raises(InputError, match=rf"^planners: '{planner}': {match}"):
        BenchConfig(maps=("overtake",), planners=(planner,), seeds=1)


def test_two_spellings_are_one_row_and_options_make_a_new_run_key():
    cfg = BenchConfig(
        maps=("overtake",), seeds=1,
        planners=("improved-rrt-connect", STEP4, "improved-rrt-connect@step=4:escalation=false"),
    )
    assert cfg.planners == ("improved-rrt-connect", STEP4)
    plain, with_options = expand(cfg)
    assert plain.key != with_options.key
    (alone,) = expand(BenchConfig(maps=("overtake",), seeds=1))
    assert alone.key == plain.key  # a row without options keeps its key


def test_an_integral_float_is_the_integer_row():
    # step=2 and step=2.0 were two rows with two run keys (a regression audit).
    cfg = BenchConfig(maps=("overtake",), seeds=1, planners=("rrt@step=2", "rrt@step=2.0"))
    assert cfg.planners == ("rrt@step=2",)
    assert parse_planner_spec("rrt@step=2.5").label == "rrt@step=2.5"


@pytest.mark.parametrize(
    ("planners", "match"),
    [
        (("hybrid-a-star@curve=arcs", "step=0.5"), r"'step=0\.5' is not a planner: .*':'"),
        (('improved-rrt-connect@smoothing={"max_rounds":8}',), "a value cannot hold ':' or ','"),
    ],
)
def test_a_comma_or_colon_in_a_value_is_explained(planners, match):
    with pytest.raises(InputError, match=match):
        BenchConfig(maps=("overtake",), seeds=1, planners=planners)


def test_plan_row_is_the_planner_built_with_its_options():
    cfg = BenchConfig(maps=("parking_lot",), planners=("improved-rrt-connect", STEP4), seeds=1)
    rows = {s.planner: execute_run(s) for s in expand(cfg)}
    problem = PlanningProblem.from_map(builtin_map("parking_lot"))
    for label, options in (("improved-rrt-connect", {}), (STEP4, {"escalation": False, "step": 4})):
        direct = make_planner("improved-rrt-connect", **options).solve(
            problem, np.random.default_rng(0), Budget(max_iterations=20_000, max_time_s=5.0)
        )
        assert rows[label]["success"] and direct.success
        assert rows[label]["length_m"] == pytest.approx(direct.path.length, abs=1e-9)
        assert rows[label]["planner"] == label
    assert rows[STEP4]["length_m"] != pytest.approx(rows["improved-rrt-connect"]["length_m"])


def test_episode_row_drives_the_planner_built_with_its_options():
    from rrtdrive.sim.runner import EpisodeConfig, run_episode
    from rrtdrive.sim.tasks import make_variant

    cfg = BenchConfig(
        scenarios=("parking",), planners=(STEP4,), controllers=("pure-pursuit",), seeds=1
    )
    (spec,) = expand(cfg)
    row = execute_run(spec)
    budget = Budget(max_iterations=20_000, max_time_s=5.0)
    direct = run_episode(
        make_variant("parking", 0), "improved-rrt-connect", "pure-pursuit", 0,
        EpisodeConfig(budget=budget, planner_options={"escalation": False, "step": 4}),
    )
    default = run_episode(
        make_variant("parking", 0), "improved-rrt-connect", "pure-pursuit", 0,
        EpisodeConfig(budget=budget),
    )
    # The report rounds to 6 significant digits.
    assert row["path_length_m"] == pytest.approx(direct.path.length, abs=1e-3)
    assert abs(direct.path.length - default.path.length) > 0.1


def test_overtake_traffic_refuses_options():
    with pytest.raises(InputError, match="overtake-traffic re-plans with its own planner"):
        BenchConfig(scenarios=("overtake-traffic",), planners=("improved-rrt-connect@step=4",))


def test_cli_and_toml_take_options(tmp_path, capsys):
    toml = tmp_path / "bench.toml"
    toml.write_text(f'maps = ["overtake"]\nplanners = ["{STEP4}"]\nseeds = 1\n')
    assert load_toml(toml)["planners"] == [STEP4]
    code = main(["bench", "--config", str(toml), "--planners", "rrt@stepp=2",
                 "--out", str(tmp_path / "b")])
    assert code == 2
    err = capsys.readouterr().err
    assert err.startswith("rrtdrive bench: error: --planners: 'rrt@stepp=2': planner.stepp")
    assert len(err.splitlines()) == 1


def test_reverse_grid_notes_each_forward_only_row(tmp_path, capsys):
    # As plan --reverse: the rows say reverse true (asked for) but these paths cannot
    # change gear; the bench said nothing (a regression audit).
    code = main(["bench", "--maps", "overtake", "--reverse", "--seeds", "1", "--quiet",
                 "--no-plots", "--out", str(tmp_path), "--planners",
                 "rrt,improved-rrt-connect,improved-rrt-connect@escalation=false"])
    assert code == 0
    notes = [ln for ln in capsys.readouterr().err.splitlines() if "note:" in ln]
    assert notes == [
        "rrtdrive bench: note: rrt plans forward only; --reverse takes effect with "
        "hybrid-a-star, improved-rrt-connect",
        "rrtdrive bench: note: improved-rrt-connect plans forward only with escalation=false; "
        "--reverse takes effect with hybrid-a-star, improved-rrt-connect",
    ]


def test_map_only_grid_notes_the_controllers_it_leaves_out(tmp_path, capsys):
    # --maps runs plan only: --controllers lqr was dropped without a word (a user's
    # first bench of a map file); the default controller alone says nothing.
    out = tmp_path / "b"
    args = ["bench", "--maps", "overtake", "--seeds", "1", "--quiet", "--no-plots"]
    assert main([*args, "--controllers", "lqr,stanley", "--out", str(out)]) == 0
    notes = [ln for ln in capsys.readouterr().err.splitlines() if "note:" in ln]
    assert notes == [
        "rrtdrive bench: note: --controllers lqr,stanley applies to --scenarios runs; "
        "--maps runs plan only (to drive a map: --scenarios MAP)"
    ]
    assert [json.loads(ln)["controller"] for ln in (out / "runs.jsonl").open()] == [None]
    assert main([*args, "--out", str(tmp_path / "c")]) == 0
    assert "note:" not in capsys.readouterr().err
