"""Closed-loop bench rows (their plan's set-up) and the figures an interrupted summary keeps."""

from __future__ import annotations

import math

from rrtdrive.bench.grid import BenchConfig, expand
from rrtdrive.bench.worker import execute_run


def test_an_episode_row_has_the_plans_setup_time_as_simulate_json_does():
    spec = expand(BenchConfig(scenarios=("overtake",), planners=("rrt-connect",),
                              controllers=("pure-pursuit",), seeds=1))[0]  # fmt: skip
    row = execute_run(spec)
    assert row["kind"] == "episode" and row["plan_status"] == "solved"
    setup, planning = row["setup_time_s"], row["planning_time_s"]
    assert isinstance(setup, float) and math.isfinite(setup) and setup >= 0.0
    assert isinstance(planning, float) and planning > 0.0


def test_an_interrupt_while_plotting_leaves_the_last_complete_figures(tmp_path, monkeypatch):
    import pytest

    import rrtdrive.bench.core as core
    from rrtdrive.bench import run_bench

    cfg = BenchConfig(maps=("overtake",), planners=("rrt-connect",), seeds=2, workers=1,
                      out=str(tmp_path))  # fmt: skip
    run_bench(cfg)
    before = {p.name: p.read_bytes() for p in tmp_path.glob("*.png")}
    assert "box_length.png" in before

    def interrupted(rows, out):
        raise KeyboardInterrupt

    monkeypatch.setattr(core, "write_plots", interrupted)
    with pytest.raises(KeyboardInterrupt):
        run_bench(cfg)  # nothing to run: only the summary and the figures are rewritten
    assert {p.name: p.read_bytes() for p in tmp_path.glob("*.png")} == before
