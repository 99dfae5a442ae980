"""Closed loop at scale: seeds x controllers x scenarios, planned by the improved RRT-Connect.

Usage::

    python experiments/closed_loop.py --seeds 50 --jobs 2 --out results \
        --doc docs/closed_loop.md --figures docs/figures

For every scenario (``parking``, ``overtake`` with the stopped car,
``overtake-oncoming`` with ``--oncoming`` oncoming cars as well), controller (pure
pursuit, Stanley, LQR) and seed 0..seeds-1: plan, drive in highway-env at the
simulation frequency, evaluate (:func:`rrtdrive.evaluation.evaluate`). Writes
``OUT/closed_loop.json`` (every report, the summaries, the resolved settings and
the command) and ``OUT/closed_loop.md``; with ``--doc`` the same table and a few
frames (PNG) of seed 0 for the docs.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import time
from pathlib import Path as FsPath

from rrtdrive.bench.backends import episode_progress, parallel_map
from rrtdrive.evaluation import EpisodeReport, evaluate, summarise
from rrtdrive.maps import write_text_atomic
from rrtdrive.sim.runner import EpisodeConfig, run_episode
from rrtdrive.sim.scenes import SimConfig
from rrtdrive.sim.tasks import DEFAULT_PLANNER, make_scenario
from rrtdrive.sim.tasks import Task as Scenario
from rrtdrive.types import VehicleParams

SCENARIOS = ("parking", "overtake", "overtake-oncoming")
CONTROLLERS = ("pure-pursuit", "stanley", "lqr")


def scenario_for(label: str, seed: int, oncoming: int) -> Scenario:
    """``overtake-oncoming`` is the overtake scenario with ``oncoming`` oncoming cars."""
    if label == "overtake-oncoming":
        return make_scenario("overtake", seed, oncoming=oncoming)
    return make_scenario(label, seed)


def run_one(job: tuple[str, str, str, int, int, int]) -> dict:
    label, planner, controller, seed, hz, oncoming = job
    cfg = EpisodeConfig(sim=SimConfig(simulation_frequency=hz))
    ep = run_episode(scenario_for(label, seed, oncoming), planner, controller, seed, cfg)
    out = evaluate(ep).to_json()
    out["scenario"] = label
    return out


def _fmt(v: float | None, digits: int = 3) -> str:
    return "n/a" if v is None else f"{v:.{digits}f}"


def table(summaries: dict[str, dict]) -> str:
    kmax = VehicleParams().kappa_max
    head = (
        "| scenario | controller | success | collisions (highway-env / footprint) | "
        "CTE RMS mean / max [m] | CTE max [m] | heading RMS mean [rad] | "
        f"max executed κ [1/m] (κ_max {kmax:.3f}) | κ over limit | max a_lat [m/s²] | "
        "max jerk [m/s³] | max steering rate [rad/s] | goal error max [m] | time [s] |\n"
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n"
    )
    rows = []
    for key, s in summaries.items():
        scen, ctrl = key.split("/")
        rows.append(
            f"| {scen} | {ctrl} | {100 * s['success_rate']:.0f} % ({s['episodes']}) | "
            f"{s['collisions_highway_env']} / {s['collisions_footprint']} | "
            f"{_fmt(s['cte_rms_m_mean'])} / {_fmt(s['cte_rms_m_max'])} | "
            f"{_fmt(s['cte_max_m_max'])} | {_fmt(s['heading_err_rms_rad_mean'], 4)} | "
            f"{_fmt(s['executed_max_curvature_max'], 4)} | "
            f"{_fmt(s['executed_curvature_violation_share_max'], 3)} | "
            f"{_fmt(s['max_lateral_accel_max'], 2)} | {_fmt(s['max_jerk_max'], 1)} | "
            f"{_fmt(s['max_steering_rate_max'], 2)} | {_fmt(s['goal_position_err_m_max'])} | "
            f"{_fmt(s['duration_s_mean'], 1)} |"
        )
    return head + "\n".join(rows) + "\n"


def save_frames(figures: FsPath, planner: str, hz: int, oncoming: int) -> list[str]:
    import imageio.v2 as imageio

    from rrtdrive.sim.video import render_frames

    names = []
    cases = (("parking", "pure-pursuit"), ("overtake", "lqr"), ("overtake-oncoming", "stanley"))
    for scenario, controller in cases:
        ep = run_episode(
            scenario_for(scenario, 0, oncoming), planner, controller, 0,
            EpisodeConfig(sim=SimConfig(simulation_frequency=hz)),
        )
        if ep.log.steps == 0:
            continue
        n = len(ep.log.states)
        stride = max(1, (n - 1) // 3) if scenario == "overtake-oncoming" else max(1, (n - 1) // 2)
        for i, frame in enumerate(render_frames(ep, stride=stride)):
            if i > 3:
                break
            name = f"closed_loop_{scenario}_{i}.png"
            imageio.imwrite(figures / name, frame)
            names.append(name)
    return names


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--seeds", type=int, default=50)
    ap.add_argument("--scenarios", default=",".join(SCENARIOS))
    ap.add_argument(
        "--oncoming", type=int, default=2, help="oncoming cars in overtake-oncoming (default 2)"
    )
    ap.add_argument("--controllers", default=",".join(CONTROLLERS))
    ap.add_argument("--planner", default=DEFAULT_PLANNER)
    ap.add_argument("--frequency", type=int, default=20)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--out", default="results")
    ap.add_argument("--doc", default=None, help="also write this markdown page (with frames)")
    ap.add_argument(
        "--figures", default=None, help="with --doc: write seed 0's frames here and show them"
    )
    args = ap.parse_args(argv)
    scenarios = args.scenarios.split(",")
    controllers = args.controllers.split(",")
    jobs = [
        (s, args.planner, c, seed, args.frequency, args.oncoming)
        for s in scenarios for c in controllers for seed in range(args.seeds)
    ]
    t0 = time.perf_counter()
    reports: list[dict] = []

    progress = episode_progress()
    reports = parallel_map(run_one, jobs, args.jobs, progress)
    print(file=sys.stderr)
    summaries: dict[str, dict] = {}
    fields = set(EpisodeReport.__dataclass_fields__)
    for s in scenarios:
        for c in controllers:
            group = [r for r in reports if r["scenario"] == s and r["controller"] == c]
            objs = [EpisodeReport(**{k: v for k, v in r.items() if k in fields}) for r in group]
            summaries[f"{s}/{c}"] = summarise(objs)
    failures = [
        {k: r[k] for k in ("scenario", "controller", "seed", "status", "message")}
        for r in reports if not r["success"]
    ]
    settings = {
        "command": " ".join([sys.executable.rsplit("/", 1)[-1], *sys.argv]),
        "seeds": list(range(args.seeds)),
        "scenarios": scenarios,
        "controllers": controllers,
        "planner": args.planner,
        "simulation_frequency": args.frequency,
        "oncoming": args.oncoming,
        "episode_config": "EpisodeConfig() defaults (speed: SpeedConfig(v_max=scenario.v_max))",
        "python": platform.python_version(),
        "wall_time_s": round(time.perf_counter() - t0, 1),
    }
    out = FsPath(args.out)
    out.mkdir(parents=True, exist_ok=True)
    write_text_atomic(
        out / "closed_loop.json",
        json.dumps({"settings": settings, "summaries": summaries, "failures": failures,
                    "reports": reports}, indent=1, allow_nan=False) + "\n",
    )
    md = (
        f"# Closed loop: {args.seeds} seeds x {len(controllers)} controllers x "
        f"{len(scenarios)} scenarios\n\n"
        f"Planner `{args.planner}`, control and simulation at {args.frequency} Hz in "
        f"highway-env. Command: `{settings['command']}`.\n\n" + table(summaries)
    )
    if failures:
        md += "\nFailed episodes:\n\n" + "".join(
            f"- {f['scenario']} / {f['controller']} / seed {f['seed']}: {f['status']}: "
            f"{f['message']}\n" for f in failures
        )
    write_text_atomic(out / "closed_loop.md", md)
    print(table(summaries))
    if args.doc:
        page = md
        if args.figures:  # frames only into a folder that was named
            figures = FsPath(args.figures)
            figures.mkdir(parents=True, exist_ok=True)
            names = save_frames(figures, args.planner, args.frequency, args.oncoming)
            rel = os.path.relpath(figures, FsPath(args.doc).parent)
            pics = "".join(f"![{n}]({rel}/{n})\n" for n in names)
            page += "\n## Frames (seed 0)\n\n" + pics
        write_text_atomic(FsPath(args.doc), page)
    return 0


if __name__ == "__main__":
    sys.exit(main())
