"""experiments/bench_gym.py measures what it says, on the real environments (a few steps)."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "experiments"))
bench_gym = pytest.importorskip("bench_gym")


def test_a_tiny_run_measures_resets_steps_and_frames(tmp_path):
    assert bench_gym.main(["--steps", "3", "--repeats", "1", "--out", str(tmp_path)]) == 0
    import json

    rows = json.loads((tmp_path / "bench_gym.json").read_text())["rows"]
    assert [r["env_id"] for r in rows] == list(bench_gym.ENV_IDS)
    assert all(r["reset_s"] > 0 and r["steps_per_s"] > 0 and r["steps_per_s_rendered"] > 0
               for r in rows)
    assert rows[0]["frame_shape"] == [640, 640, 3] and rows[1]["frame_shape"] == [320, 960, 3]
    assert "| `rrtdrive/Parking-v0` |" in (tmp_path / "bench_gym.md").read_text()
