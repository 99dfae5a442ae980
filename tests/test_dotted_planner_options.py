"""A nested config's field as ``FIELD.FIELD=VALUE``: the spelling the planners' errors use.

``--planner-option smoothing.max_rounds=8`` is ``smoothing={"max_rounds": 8}``; a bench
row spells it the same way (its JSON would hold the row's separators ':' and ','), and
``hybrid-a-star`` takes its ``smoothing`` as fields to change, as the improved planner does.
"""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rrtdrive.bench.planner_specs import PlannerSpec, parse_planner_spec
from rrtdrive.cli_args import parse_planner_options
from rrtdrive.maps import builtin_map
from rrtdrive.planning import PlanningProblem, make_planner
from rrtdrive.planning.smoothing import SmoothingConfig
from rrtdrive.types import Budget, InputError

NAMES = st.text("abcdefghij_", min_size=1, max_size=6).filter(lambda s: s != "reverse")
LEAVES = st.one_of(st.integers(-1000, 1000), st.booleans(), st.sampled_from(["arcs", "x_y"]))
NESTED = st.recursive(LEAVES, lambda inner: st.dictionaries(NAMES, inner, min_size=1,
                                                            max_size=3), max_leaves=8)  # fmt: skip
OPTIONS = st.dictionaries(NAMES, NESTED, min_size=1, max_size=4)


def _flatten(options: dict, prefix: str = "") -> list[tuple[str, object]]:
    """The test's own flattening (not the bench's): every leaf with its dotted path."""
    out = []
    for key, value in options.items():
        if isinstance(value, dict):
            out += _flatten(value, f"{prefix}{key}.")
        else:
            out.append((f"{prefix}{key}", value))
    return out


@settings(max_examples=200, deadline=None)
@given(OPTIONS)
def test_dotted_fields_build_the_nested_options(options):
    texts = [f"{k}={json.dumps(v)}" for k, v in _flatten(options)]
    assert parse_planner_options(texts, "-o") == options
    spec = PlannerSpec("hybrid-a-star", options)
    # A row's label spells nested fields dotted, and reads back as the same options.
    assert "{" not in spec.label
    assert parse_planner_spec(spec.label) == spec


@pytest.mark.parametrize(
    ("texts", "match"),
    [
        (["smoothing.max_rounds=8", "smoothing.max_rounds=9"],
         r"^-o smoothing\.max_rounds: given twice"),
        (['smoothing={"clothoid": false}', "smoothing.max_rounds=8"],
         r"^-o smoothing and smoothing\.max_rounds: given twice"),
        (["smoothing.max_rounds=8", "smoothing=4"],
         r"^-o smoothing\.max_rounds and smoothing: given twice"),
        (["smoothing..max_rounds=8"], r"^-o smoothing\.\.max_rounds: an empty field name"),
        ([".step=4"], r"^-o \.step: an empty field name"),
        (["reverse.x=1"], r"^-o reverse: give --reverse"),
    ],
)  # fmt: skip
def test_a_field_given_twice_or_misspelt_is_named(texts, match):
    with pytest.raises(InputError, match=match):
        parse_planner_options(texts, "-o")


def test_hybrid_a_star_takes_smoothing_fields_and_keeps_their_bound():
    planner = make_planner("hybrid-a-star", smoothing={"max_sharpness": 0.1})
    assert planner.smoothing == SmoothingConfig(max_rounds=24, max_sharpness=0.1)
    problem = PlanningProblem.from_map(builtin_map("parking_lot"))
    res = planner.solve(problem, np.random.default_rng(0), Budget(max_time_s=300.0))
    assert res.success, res.message
    assert res.stats["max_sharpness"] <= 0.1 + 1e-9
    with pytest.raises(InputError, match=r"^planner\.smoothing\.bogus: unknown field"):
        make_planner("hybrid-a-star", smoothing={"bogus": 1})


def _plan(*argv: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "rrtdrive", "plan", *argv],
                          capture_output=True, text=True, check=False, timeout=300)  # fmt: skip


def test_the_cli_takes_a_dotted_field_and_its_json_rebuilds_the_planner(tmp_path):
    out = tmp_path / "plan.json"
    proc = _plan("parking_lot", "--planner-option", "smoothing.max_rounds=8", "--json", str(out))
    assert proc.returncode == 0, proc.stderr
    doc = json.loads(out.read_text())
    assert doc["planner_options"] == {"smoothing": {"max_rounds": 8}}
    assert make_planner(doc["planner"], **doc["planner_options"]).config.smoothing.max_rounds == 8
    bad = _plan("parking_lot", "--planner-option", "smoothing.max_rounds=-1")
    assert bad.returncode == 2 and "Traceback" not in bad.stderr
    assert "--planner-option smoothing.max_rounds: must be an integer >= 1" in bad.stderr
