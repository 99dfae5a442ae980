"""Every option of the experiment scripts says what it does in ``--help``.

The check that every ``add_argument`` call has a ``help`` keyword is an ast scan of
every script (fast). ``python experiments/X.py --help`` runs as a subprocess for a
few scripts only: each imports heavy libraries (highway-env, shapely, ...), about
2-3 s a script, and all of them would take minutes.
"""

from __future__ import annotations

import ast
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
EXPERIMENTS = ROOT / "experiments"

#: The scripts that build an argparse parser.
SCRIPTS = sorted(
    p.name for p in EXPERIMENTS.glob("*.py") if "add_argument" in p.read_text(encoding="utf-8")
)
#: Scripts whose ``--help`` actually runs, one per parser style in use: RawTextHelpFormatter
#: (closed_loop, traffic), a shared option helper with an f-string help (street_turns),
#: a long default (coverage), a plain parser (bench_reeds_shepp).
RUN_HELP = ("bench_reeds_shepp.py", "closed_loop.py", "coverage.py", "street_turns.py",
            "traffic.py")


def _add_argument_calls(script: str) -> list[ast.Call]:
    tree = ast.parse((EXPERIMENTS / script).read_text(encoding="utf-8"), filename=script)
    return [
        node for node in ast.walk(tree)
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute)
        and node.func.attr == "add_argument"
    ]


def _name(call: ast.Call) -> str:
    flags = [a.value for a in call.args if isinstance(a, ast.Constant)]
    return "/".join(map(str, flags)) or f"line {call.lineno}"


def _suppressed(call: ast.Call) -> bool:
    return any(
        k.arg == "help" and isinstance(k.value, ast.Attribute) and k.value.attr == "SUPPRESS"
        for k in call.keywords
    )


def test_scripts_found():
    assert len(SCRIPTS) >= 40, SCRIPTS
    assert set(RUN_HELP) <= set(SCRIPTS)


@pytest.mark.parametrize("script", SCRIPTS)
def test_every_option_has_help(script):
    calls = _add_argument_calls(script)
    assert calls, script
    bare = [
        f"{_name(c)} (line {c.lineno})" for c in calls
        if not any(k.arg == "help" for k in c.keywords)
    ]
    assert not bare, f"{script}: options without help=: {', '.join(bare)}"


@pytest.mark.parametrize("script", RUN_HELP)
def test_help_runs_and_lists_every_option(script):
    proc = subprocess.run(
        [sys.executable, str(EXPERIMENTS / script), "--help"],
        capture_output=True, text=True, check=False, cwd=ROOT, timeout=60,
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert proc.stdout.startswith("usage:"), proc.stdout[:200]
    for call in _add_argument_calls(script):
        if _suppressed(call):
            continue
        for flag in call.args:
            if isinstance(flag, ast.Constant) and str(flag.value).startswith("--"):
                assert flag.value in proc.stdout, f"{script}: {flag.value} not in --help"


#: Flags that count runs, seeds, repetitions or workers: 0 or a negative count ran
#: nothing and wrote an empty table over real results (steer_rate.py --seeds 0, exit 0).
COUNT_FLAGS = {"--seeds", "--runs", "--repeat", "--repeats", "--jobs", "--count"}


@pytest.mark.parametrize("script", SCRIPTS)
def test_a_count_flag_takes_integers_from_one(script):
    for call in _add_argument_calls(script):
        names = {a.value for a in call.args if isinstance(a, ast.Constant)}
        if not names & COUNT_FLAGS:
            continue
        kind = next((k.value for k in call.keywords if k.arg == "type"), None)
        if kind is None:
            continue  # a list given as text (random_maps_drive.py --seeds S,S,...)
        assert ast.unparse(kind).endswith("positive_int"), (script, sorted(names))


@pytest.mark.parametrize("script", SCRIPTS)
def test_a_plain_int_flag_is_a_seed(script):
    # Every other integer counts something (pairs, timesteps, expansions, cars): a
    # plain int let --timesteps 0 or --pairs -5 through to a traceback or an empty run.
    for call in _add_argument_calls(script):
        kind = next((k.value for k in call.keywords if k.arg == "type"), None)
        if kind is None or ast.unparse(kind) != "int":
            continue
        names = [a.value for a in call.args if isinstance(a, ast.Constant)]
        assert all(n.endswith("seed") for n in names), (script, names)


def test_an_output_folder_that_cannot_be_one_is_refused_before_the_run(tmp_path):
    # It was a traceback after every episode had run (the run lost).
    sys.path.insert(0, str(EXPERIMENTS))
    import argparse

    from results_io import out_folder, run_main

    afile = tmp_path / "afile"
    afile.write_text("")
    for bad, why in ((afile, "is a file"), (afile / "sub", "(a parent) is a file")):
        with pytest.raises(argparse.ArgumentTypeError, match=re.escape(why)):
            out_folder(str(bad))
    assert out_folder(str(tmp_path / "new" / "deeper")) == str(tmp_path / "new" / "deeper")
    proc = subprocess.run(
        [sys.executable, str(EXPERIMENTS / "table3.py"), "--runs", "1", "--out", str(afile)],
        capture_output=True, text=True, timeout=120, check=False,
    )
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    assert "argument --out:" in proc.stderr and "is a file, not a folder" in proc.stderr

    def unwritable() -> int:
        raise PermissionError(13, "Permission denied", str(tmp_path / "x.json"))

    assert run_main(unwritable) == 1  # one line, exit 1: a run failure, not bad input


def test_a_misspelt_planner_is_refused_not_skipped(tmp_path):
    proc = subprocess.run(
        [sys.executable, str(EXPERIMENTS / "coverage.py"), "--planners",
         "improved-rrt-connect,hybrid-a-stra", "--count", "1", "--out", str(tmp_path)],
        capture_output=True, text=True, timeout=120, check=False,
    )
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    assert "--planners: hybrid-a-stra: planner 'hybrid-a-stra' is not registered" in proc.stderr


#: Time caps and the simulation frequency: a wrong value was refused only deep inside,
#: by a config field's name (``budget.max_time_s``, ``sim.simulation_frequency``).
CHECKED_TYPES = {"--max-time": "positive_float", "--ompl-time": "positive_float",
                 "--frequency": "int_at_least(MIN_SIM_FREQUENCY, 'Hz', MAX_SIM_FREQUENCY)"}


@pytest.mark.parametrize("script", SCRIPTS)
def test_time_caps_and_the_frequency_are_checked_by_argparse(script):
    for call in _add_argument_calls(script):
        names = {a.value for a in call.args if isinstance(a, ast.Constant)}
        for flag in names & set(CHECKED_TYPES):
            kind = next((k.value for k in call.keywords if k.arg == "type"), None)
            assert kind is not None and ast.unparse(kind).startswith(CHECKED_TYPES[flag]), (
                script, flag)


@pytest.mark.parametrize("script", SCRIPTS)
def test_an_option_with_a_default_says_it_in_help(script):
    # A researcher reproducing a results page needs the defaults the command ran with.
    for call in _add_argument_calls(script):
        given = {k.arg: k.value for k in call.keywords}
        default = given.get("default")
        if default is None or (isinstance(default, ast.Constant) and default.value in
                               (None, False, True)):
            continue
        text = ast.unparse(given["help"]) if "help" in given else ""
        assert "default" in text or "SUPPRESS" in text, (script, ast.unparse(call.args[0]))
