"""``experiments/root_growth.py`` watches every pair of trees of the default planner."""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "experiments"))
import root_growth  # noqa: E402


def test_pairs_on_the_built_in_maps() -> None:
    from rrtdrive.planning.improved import planner as improved_planner

    original = improved_planner.grow_until_meet
    # The two maps the assertions read (all nine took 18 s of the suite).
    pairs = root_growth.run(count=0, seeds=1, maps=("kerbside", "parking_lot"))
    assert improved_planner.grow_until_meet is original  # put back
    by_query = {}
    for p in pairs:
        by_query.setdefault(p["query"], []).append(p)
    # The kerbside goal is boxed in along its heading: its tree never leaves the root,
    # and without root_patience the pair spends the whole share (10 000 of 20 000).
    kerb = by_query["kerbside:fwd:0"]
    assert kerb[0]["goal_grew"] is None and not kerb[0]["met"]
    assert kerb[0]["iterations"] == 10_000
    # The open parking lot meets, each root having grown within the pair's iterations.
    lot = by_query["parking_lot:fwd:0"][-1]
    assert lot["met"]
    for end in ("start_grew", "goal_grew"):
        assert 0 <= lot[end] <= lot["iterations"]
    s = root_growth.summarise(pairs)
    assert s["pairs"] == len(pairs) == s["met"] + s["failed"]
    assert s["failed_root_never_grew_by_map"]["kerbside"] >= 1
    assert s["met_last_root_grew_max"] <= max(p["iterations"] for p in pairs if p["met"])
