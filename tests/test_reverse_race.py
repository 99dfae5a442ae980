"""experiments/reverse_race.py: the race of the default's stages against Hybrid A*, by hand."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "experiments"))
reverse_race = pytest.importorskip("reverse_race")


def _row(planner, index, length, time, stage=None, solved=True):
    return {"planner": planner, "vary": "goal", "index": index, "solved": solved,
            "length_m": length, "time_s": time, "stage": stage}


def test_the_race_keeps_the_shorter_path_and_adds_the_search_time():
    d, h, o = reverse_race.DEFAULT, reverse_race.HYBRID, reverse_race.OMPL
    rows = [
        # Query 0: the RRT-Connect stage solved it, longer than the search's path.
        _row(d, 0, 12.0, 0.1, "improved-rrt-connect"), _row(h, 0, 10.0, 0.2), _row(o, 0, 11.0, 1.0),
        # Query 1: escalated; its answer is the search's own and stands.
        _row(d, 1, 20.0, 0.5, "hybrid-a-star"), _row(h, 1, 20.0, 0.4), _row(o, 1, 19.0, 1.0),
        # Query 2: the direct Dubins path, shorter than the search's: kept.
        _row(d, 2, 30.0, 0.1, "dubins-fallback"), _row(h, 2, 33.0, 0.3), _row(o, 2, 31.0, 1.0),
        # Query 3: OMPL failed, so it is not compared.
        _row(d, 3, 1.0, 9.0, "hybrid-a-star"), _row(h, 3, 1.0, 9.0),
        _row(o, 3, 0.0, 10.0, None, solved=False),
    ]
    run = {"seed": 5, "count": 4, "sets": ["goal"], "rows": rows}
    (only,) = reverse_race.measure(run)
    assert only["both"] == 3 and only["solved_before_escalation"] == 2
    # Medians over queries 0-2: OMPL length 19, time 1.0.
    assert only["length_ratio"]["default"] == pytest.approx(20.0 / 19.0)
    assert only["length_ratio"]["race"] == pytest.approx(20.0 / 19.0)  # 10, 20, 30
    assert only["length_ratio"]["hybrid-a-star"] == pytest.approx(20.0 / 19.0)
    # Race times: 0.1 + 0.2, 0.5, 0.1 + 0.3: median 0.4.
    assert only["time_ratio"]["race"] == pytest.approx(0.4)
    assert only["time_ratio"]["default"] == pytest.approx(0.1)
    page = reverse_race.report({"command": "x", "rows": [only]})
    assert "| seed 5, 4 | goals | 3 | 2 | 1.053 / 1.053 / 1.053 | 0.100 / 0.300 / 0.400 |" in page
