"""``plan`` and ``simulate`` take the OMPL comparators by name, as ``bench`` does.

They are registered by the bench module, which ``plan`` and ``simulate`` load when a
``--planner`` names one. A Reeds-Shepp planner changes gear whatever the problem
says, so it needs ``--reverse`` (a plan without it claimed ``"reverse": false`` over
a path with cusps, which ``verify`` fails).
"""

from __future__ import annotations

import importlib.util
import json
import math
import warnings

import numpy as np
import pytest

from rrtdrive.cli import main

HAS_OMPL = importlib.util.find_spec("ompl") is not None


@pytest.mark.parametrize("command", ["plan", "simulate"])
def test_a_reeds_shepp_planner_without_reverse_is_refused_before_planning(capsys, command):
    assert main([command, "parking_lot", "--planner", "ompl-rs-rrtconnect"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"rrtdrive {command}: error: --planner: ompl-rs-rrtconnect changes gear "
                   "(Reeds-Shepp); give --reverse"]  # fmt: skip


def test_an_unknown_ompl_name_lists_the_registered_comparators(capsys):
    assert main(["plan", "parking_lot", "--planner", "ompl-rs-rrtcnnect", "--reverse"]) == 2
    err = capsys.readouterr().err
    assert "did you mean 'ompl-rs-rrtconnect'" in err
    assert "import rrtdrive.bench" not in err  # the CLI registered them already


@pytest.mark.skipif(not HAS_OMPL, reason="needs OMPL (pip install 'rrtdrive[ompl]')")
def test_plan_with_ompl_reeds_shepp_writes_a_reversing_plan_that_verify_accepts(
    tmp_path, capsys
):
    out = tmp_path / "p.json"
    code = main(["plan", "parking_lot", "--planner", "ompl-rs-rrtconnect", "--reverse",
                 "--max-time", "10", "--json", str(out)])  # fmt: skip
    assert code == 0, capsys.readouterr().err
    plan = json.loads(out.read_text())
    assert plan["status"] == "solved" and plan["reverse"] is True
    assert "plans forward only" not in capsys.readouterr().err
    # OMPL's curves jump in curvature: every check but the sharpness passes.
    assert main(["verify", str(out), "--no-sharpness"]) == 0


@pytest.mark.skipif(HAS_OMPL, reason="OMPL is installed")
def test_plan_with_ompl_missing_says_how_to_install_it(capsys):
    code = main(["plan", "parking_lot", "--planner", "ompl-rs-rrtconnect", "--reverse"])
    assert code == 2
    assert "pip install 'rrtdrive[ompl]'" in capsys.readouterr().err


def test_a_path_reads_in_one_short_line():
    from rrtdrive import Budget, builtin_map
    from rrtdrive.planning import PlanningProblem, make_planner
    from rrtdrive.types import Path

    r = make_planner("improved-rrt-connect").solve(
        PlanningProblem.from_map(builtin_map("overtake")), np.random.default_rng(0), Budget()
    )
    text = repr(r.path)
    assert text == (f"Path(rows={len(r.path)}, length={r.path.length:.2f} m, cusps=0, "
                    f"waypoints={len(r.path.waypoints)})")  # fmt: skip
    assert repr(Path.empty()) == "Path(rows=0, length=0.00 m, cusps=0, waypoints=0)"


def test_a_yaw_whole_turns_round_is_taken_as_zero_not_minus_zero_degrees():
    from rrtdrive import Map, Pose
    from rrtdrive.types import InputWarning

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", InputWarning)
        Map("x", (0.0, 0.0, 40.0, 30.0), (), Pose(3.0, 3.0, -4 * math.pi), Pose(35.0, 25.0, 0.0))
    (said,) = [str(w.message) for w in caught]
    assert "taken as 0.0 deg" in said and "-0.0" not in said
