"""A forward-only failure with nothing else to blame says whether reversing finds a path.

The map is a new user's home garage: a 12 m driveway with a 2.7 m bay 7 m to the side
of the start; forward the car cannot turn into it, with ``--reverse`` it backs in.
"""

from __future__ import annotations

import pathlib

import numpy as np
import pytest

from rrtdrive.maps import Map, load_map
from rrtdrive.planning import make_planner
from rrtdrive.planning.base import PlanningProblem, failure
from rrtdrive.planning.diagnosis import Diagnosis, DiagnosisKind
from rrtdrive.planning.hybrid.config import HybridConfig
from rrtdrive.planning.hybrid.probe import PROBE_EXPANSIONS, reverse_probe
from rrtdrive.planning.result import run_query
from rrtdrive.types import Budget, PlanStatus
from rrtdrive.verify import verify_path

# Forward it fails within this budget (and at the default 20 000 as well, only slower).
SMALL = Budget(max_iterations=3000)
HOME_GARAGE = pathlib.Path(__file__).resolve().parents[1] / "docs" / "maps" / "home_garage.json"


def home_garage() -> Map:
    """A 20 x 18.3 m plot: a 12 m driveway, a 2.7 m bay off it between two blocks.

    The map README.md's ``needs_reverse`` example plans (``docs/maps/home_garage.json``).
    """
    return load_map(HOME_GARAGE)


@pytest.mark.parametrize("planner", ["improved-rrt-connect", "hybrid-a-star"])
def test_a_forward_failure_names_the_reversing_path(planner):
    m = home_garage()
    failed = make_planner(planner).solve(
        PlanningProblem.from_map(m), np.random.default_rng(0), SMALL
    )
    assert not failed.success
    found = failed.diagnosis
    assert found is not None and found.kind is DiagnosisKind.NEEDS_REVERSE
    assert "try --reverse" in found.message
    # What it names is what reversing plans: the same length and gear changes, and a
    # path the independent check accepts.
    solved = make_planner("hybrid-a-star").solve(
        PlanningProblem.from_map(m, reverse=True), np.random.default_rng(0), SMALL
    )
    assert solved.success
    check = verify_path(m, solved.path)
    assert check.ok, check
    assert found.numbers["reverse_length_m"] == pytest.approx(solved.path.length, abs=1e-9)
    assert found.numbers["reverse_cusps"] == len(solved.path.cusps) >= 1
    assert f"{solved.path.length:.1f} m" in found.message


def test_the_probe_is_counted_and_runs_apart_from_the_planning_clock(monkeypatch):
    from rrtdrive.planning.hybrid import probe as probe_module

    m = home_garage()
    problem = PlanningProblem.from_map(m)
    first = reverse_probe(problem, HybridConfig(), None, 120.0)
    again = reverse_probe(problem, HybridConfig(), None, 120.0)
    assert first is not None and first == again
    assert 1 <= first.numbers["probe_expansions"] <= PROBE_EXPANSIONS
    # A short --max-time does not cut the counted probe short (its cap has a floor) ...
    assert reverse_probe(problem, HybridConfig(), None, 1e-9) == first
    # ... its own safety cap met: no finding (what it found would depend on the machine).
    monkeypatch.setattr(probe_module, "PROBE_CAP_FLOOR_S", 1e-9)
    assert reverse_probe(problem, HybridConfig(), None, 1e-9) is None


def test_no_probe_with_reverse_allowed():
    problem = PlanningProblem.from_map(home_garage(), reverse=True)
    assert reverse_probe(problem, HybridConfig(), None, 120.0) is None


def test_the_paper_pipeline_without_escalation_does_not_probe():
    m = home_garage()
    planner = make_planner("improved-rrt-connect", escalation=False)
    failed = planner.solve(PlanningProblem.from_map(m), np.random.default_rng(0), SMALL)
    assert not failed.success
    assert failed.diagnosis is None or "Hybrid A* finds one" not in failed.diagnosis.message


@pytest.mark.parametrize(
    ("status", "probed"),
    [
        (PlanStatus.NO_PATH_IN_BUDGET, True),
        (PlanStatus.POSTPROCESS_FAILED, True),
        (PlanStatus.TIMEOUT, False),  # what it would have found depends on the machine
    ],
)
def test_run_query_probes_counted_failures_only(status, probed):
    looked = Diagnosis(DiagnosisKind.NEEDS_REVERSE, "the probe's finding")

    def search(watch):
        return failure("demo", status, watch, "gave up")

    out = run_query(
        "demo", PlanningProblem.from_map(home_garage()), SMALL, search,
        rng=np.random.default_rng(0), probe=lambda: looked,
    )  # fmt: skip
    assert out.status is status
    assert (out.diagnosis is looked) is probed
