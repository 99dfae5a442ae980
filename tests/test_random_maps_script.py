"""``experiments/random_maps.py``: seeded maps with free ends, and a run's page and payload."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest
import shapely

from rrtdrive.types import VehicleParams
from rrtdrive.vehicle import footprint_polygon

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "experiments"))
import random_maps  # noqa: E402


@pytest.mark.parametrize("seed", range(8))
def test_a_seed_gives_one_map_whose_ends_are_free(seed: int) -> None:
    m = random_maps.random_map(seed)
    assert m == random_maps.random_map(seed)
    obstacles = shapely.union_all([o.polygon() for o in m.obstacles])
    inside = shapely.box(*m.bounds)
    for pose in (m.start, m.goal):
        body = footprint_polygon(pose.as_tuple(), VehicleParams())
        assert inside.contains(body)
        assert not body.intersects(obstacles)


def test_a_small_run_writes_its_page_and_counts(tmp_path) -> None:  # noqa: ANN001
    assert random_maps.main(
        ["--maps", "3", "--planners", "hybrid-a-star", "--out", str(tmp_path)]
    ) == 0
    payload = json.loads((tmp_path / "random_maps.json").read_text())
    ours = [r for r in payload["rows"] if r["planner"] == "hybrid-a-star"]
    assert [r["seed"] for r in ours] == [0, 1, 2]
    s = payload["summary"]["hybrid-a-star"]
    assert s["solved"] == sum(r["solved"] for r in ours)
    assert s["verified"] <= s["solved"]
    page = (tmp_path / "random_maps.md").read_text()
    assert "python experiments/random_maps.py --maps 3" in page
    assert "| hybrid-a-star | " in page
