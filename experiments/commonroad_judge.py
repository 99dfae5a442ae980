"""Executed episodes judged by CommonRoad's KS model (needs ``pip install ".[commonroad]"``).

    python experiments/commonroad_judge.py --seeds 10 --jobs 2 --out results

Runs scenarios x controllers x seeds closed-loop, then asks
:func:`rrtdrive.commonroad_judge.judge_trajectory` whether the driven trajectory is
feasible for CommonRoad's kinematic single-track model with our car and a 0.4 rad/s
steering-velocity limit (its inputs accepted by CommonRoad, and CommonRoad's simulation
of them on the logged trajectory); reports feasible episodes (and how many by the
inputs alone), the largest executed steering rate, the drift between the two bicycle
models, and our own
figures (success, collisions, nuPlan comfort) beside. ``--ego-steer-rate R`` drives the
ego with a rate-limited actuator (``VehicleParams.max_steer_rate``). ``--random-maps N``
drives the maps ``0 .. N-1`` of ``experiments/random_maps.py`` with reverse instead (one
episode each, scenario ``random-maps``, as ``experiments/random_maps_drive.py``). Writes
``OUT/commonroad_judge[_TAG].{json,md}``.
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

from rrtdrive.atomic import write_text_atomic
from rrtdrive.bench.backends import episode_progress, parallel_map
from rrtdrive.cli_args import int_at_least, positive_int
from rrtdrive.commonroad_judge import COMMONROAD_STEER_RATE, commonroad_available, judge_trajectory
from rrtdrive.evaluation import evaluate
from rrtdrive.sim.runner import run_episode
from rrtdrive.sim.tasks import make_scenario
from rrtdrive.types import VehicleParams

#: The scenario name of the random maps' rows (``--random-maps``).
RANDOM_MAPS = "random-maps"


def _task(scenario: str, seed: int, vehicle: VehicleParams):  # noqa: ANN202 - a Task
    """A built-in scenario, or (``random-maps``) random map ``seed`` with reverse, episode 0."""
    if scenario != RANDOM_MAPS:
        return make_scenario(scenario, seed, vehicle=vehicle)
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    from random_maps_drive import driving_task

    return driving_task(seed, vehicle)


def run_one(job: tuple[str, str, int, float | None, float]) -> dict:
    scenario, controller, seed, ego_rate, judge_rate = job
    task = _task(scenario, seed, VehicleParams(max_steer_rate=ego_rate))
    ep = run_episode(task, controller=controller, seed=0 if scenario == RANDOM_MAPS else seed)
    report = evaluate(ep)
    row = {
        "scenario": scenario, "controller": controller, "seed": seed,
        "success": report.success, "collision": report.collision,
        "nuplan_comfortable": report.nuplan_comfortable,
        "cte_max_m": report.cte_max_m, "steps": report.steps,
    }
    if ep.log.steps:
        verdict = judge_trajectory(
            ep.log.t, ep.log.states, ep.log.controls[:, 1], ep.log.controls[:, 0],
            ep.scenario.vehicle, judge_rate,
        )
        row.update(verdict.to_json())
    return row


def main(argv: list[str] | None = None) -> int:
    from results_io import json_text, out_folder  # the sibling module (run as a script)

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=positive_int, default=10,
                    help="seeds 0..N-1 per scenario and controller (default: %(default)s)")
    ap.add_argument("--scenarios", default="parking,overtake",
                    help="comma-separated scenario names (default: %(default)s)")
    ap.add_argument("--controllers", default="pure-pursuit,stanley,lqr",
                    help="comma-separated controllers (default: %(default)s)")
    ap.add_argument("--ego-steer-rate", type=float, default=None,
                    help="rate limit of the simulated ego's steering (default: instant)")
    ap.add_argument("--judge-steer-rate", type=float, default=COMMONROAD_STEER_RATE,
                    help="steering-velocity limit of the judge [rad/s] (default: %(default)s)")
    ap.add_argument(
        "--random-maps", type=int_at_least(0), default=0, metavar="N",
        help="drive random maps 0..N-1 (experiments/random_maps.py) with reverse instead "
        "of --scenarios and --seeds",
    )
    ap.add_argument("--jobs", type=positive_int, default=2,
                    help="worker processes (default: %(default)s)")
    ap.add_argument("--out", type=out_folder, default="results",
                    help="directory for commonroad_judge[_TAG].json and .md (default: %(default)s)")
    ap.add_argument("--tag", default="",
                    help="output name suffix: commonroad_judge_TAG.json and .md (default: none)")
    args = ap.parse_args(argv)
    if not commonroad_available():
        print('commonroad_judge: needs the extra: pip install ".[commonroad]"', file=sys.stderr)
        return 2
    if args.random_maps:
        args.scenarios, args.seeds = RANDOM_MAPS, args.random_maps
    jobs = [
        (s, c, seed, args.ego_steer_rate, args.judge_steer_rate)
        for s in args.scenarios.split(",") for c in args.controllers.split(",")
        for seed in range(args.seeds)
    ]
    progress = episode_progress(every=1)
    rows = parallel_map(run_one, jobs, args.jobs, progress)
    print(file=sys.stderr)
    lines = [
        "## Executed episodes judged by CommonRoad's KS model",
        "",
        f"Command: `python {' '.join(sys.argv)}`; ego steering "
        + ("instant" if args.ego_steer_rate is None else f"limited to {args.ego_steer_rate} rad/s")
        + f", judge's steering-velocity limit {args.judge_steer_rate} rad/s.",
        "",
        "| scenario | controller | CommonRoad feasible (inputs alone) | max steering rate "
        "[rad/s] | max drift [m] / [rad] | success | collisions | nuPlan comfortable |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for s in args.scenarios.split(","):
        for c in args.controllers.split(","):
            g = [r for r in rows if r["scenario"] == s and r["controller"] == c]
            judged = [r for r in g if "commonroad_feasible" in r]
            feas = sum(bool(r["commonroad_feasible"]) for r in judged)
            inputs = sum(bool(r["commonroad_inputs_feasible"]) for r in judged)
            rate = max((r["commonroad_max_steer_rate"] for r in judged), default=float("nan"))
            drift = max((r["commonroad_max_position_drift_m"] for r in judged), default=0.0)
            turn = max((r["commonroad_max_heading_drift_rad"] for r in judged), default=0.0)
            lines.append(
                f"| {s} | {c} | {feas}/{len(judged)} ({inputs}) | {rate:.2f} | "
                f"{drift:.4f} / {turn:.5f} | "
                f"{sum(r['success'] for r in g)}/{len(g)} | {sum(r['collision'] for r in g)} | "
                f"{sum(bool(r['nuplan_comfortable']) for r in g)}/{len(g)} |"
            )
    total = sum(bool(r.get("commonroad_feasible")) for r in rows)
    judged = sum("commonroad_feasible" in r for r in rows)
    undriven = "" if judged == len(rows) else (
        f" ({len(rows) - judged} of the {len(rows)} episodes never drove: their plan failed)"
    )
    lines += ["", f"Feasible in all: **{total}/{judged}** episodes driven{undriven}.", ""]
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    tag = f"_{args.tag}" if args.tag else ""
    write_text_atomic(out / f"commonroad_judge{tag}.md", "\n".join(lines))
    write_text_atomic(
        out / f"commonroad_judge{tag}.json",
        json_text({"command": " ".join(sys.argv), "rows": rows}),
    )
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    from results_io import run_main

    raise SystemExit(run_main(main))
