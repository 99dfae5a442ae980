"""Results files are strict JSON: a missing number is ``null``, never a bare ``NaN``.

``json.dumps`` writes ``NaN`` and ``Infinity`` by default, which ``jq``, browsers and
strict parsers refuse; ``results/table3.json`` and ``bench_planners_parking_lot.json``
once held them.
"""

from __future__ import annotations

import json
import math
import re
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
EXPERIMENTS = ROOT / "experiments"


def _refuse(constant: str) -> None:
    raise ValueError(f"non-standard JSON constant {constant}")


def _committed_json() -> list[Path]:
    return sorted(p for top in ("results", "docs") for p in (ROOT / top).rglob("*.json"))


@pytest.mark.skipif(not (ROOT / "results").is_dir(), reason="needs the repository's results/")
def test_every_committed_results_file_is_strict_json():
    files = _committed_json()
    assert len(files) > 10
    bad = []
    for path in files:
        try:
            json.loads(path.read_text(), parse_constant=_refuse)
        except ValueError as exc:
            bad.append(f"{path.relative_to(ROOT)}: {exc}")
    assert not bad, bad


def _write_calls(text: str) -> list[str]:
    """The argument text of every ``write_text_atomic(...)`` call (parentheses balanced)."""
    calls = []
    for match in re.finditer(r"write_text_atomic\(", text):
        depth, k = 1, match.end()
        while depth:
            depth += {"(": 1, ")": -1}.get(text[k], 0)
            k += 1
        calls.append(text[match.end():k - 1])
    return calls


@pytest.mark.skipif(not EXPERIMENTS.is_dir(), reason="needs the repository's experiments/")
def test_experiment_scripts_write_results_through_strict_json():
    loose = [
        f"{script.name}: {call.strip()[:80]}"
        for script in sorted(EXPERIMENTS.glob("*.py"))
        for call in _write_calls(script.read_text())
        if "json.dumps(" in call and "allow_nan=False" not in call
    ]
    assert not loose, loose


def test_json_text_writes_missing_numbers_as_null_and_keeps_the_rest():
    sys.path.insert(0, str(EXPERIMENTS))
    try:
        from results_io import json_text
    finally:
        sys.path.remove(str(EXPERIMENTS))
    import numpy as np

    payload = {"mean": math.nan, "ratio": -math.inf, "n": np.int64(3),
               "rows": [{"length_m": float("nan"), "ok": True}, {"length_m": 12.5, "ok": False}],
               "xs": np.array([1.0, np.nan])}
    back = json.loads(json_text(payload), parse_constant=_refuse)
    assert back == {"mean": None, "ratio": None, "n": 3,
                    "rows": [{"length_m": None, "ok": True}, {"length_m": 12.5, "ok": False}],
                    "xs": [1.0, None]}
