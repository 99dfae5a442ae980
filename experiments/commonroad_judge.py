"""Executed episodes judged by CommonRoad's KS model (needs ``pip install ".[commonroad]"``).

    python experiments/commonroad_judge.py --seeds 10 --jobs 2 --out results

Runs scenarios x controllers x seeds closed-loop, then asks
:func:`rrtdrive.commonroad_judge.judge_trajectory` whether the applied inputs are
feasible for CommonRoad's kinematic single-track model with our car and a 0.4 rad/s
steering-velocity limit; reports feasible episodes, the first infeasible step, the
largest executed steering rate, the drift between the two bicycle models, and our own
figures (success, collisions, nuPlan comfort) beside. ``--ego-steer-rate R`` drives the
ego with a rate-limited actuator (``VehicleParams.max_steer_rate``). Writes
``OUT/commonroad_judge[_TAG].{json,md}``.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from rrtdrive.atomic import write_text_atomic
from rrtdrive.bench.backends import episode_progress, parallel_map
from rrtdrive.commonroad_judge import COMMONROAD_STEER_RATE, commonroad_available, judge_trajectory
from rrtdrive.evaluation import evaluate
from rrtdrive.sim.runner import run_episode
from rrtdrive.sim.tasks import make_scenario
from rrtdrive.types import VehicleParams


def run_one(job: tuple[str, str, int, float | None, float]) -> dict:
    scenario, controller, seed, ego_rate, judge_rate = job
    task = make_scenario(scenario, seed, vehicle=VehicleParams(max_steer_rate=ego_rate))
    ep = run_episode(task, controller=controller, seed=seed)
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
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--scenarios", default="parking,overtake")
    ap.add_argument("--controllers", default="pure-pursuit,stanley,lqr")
    ap.add_argument("--ego-steer-rate", type=float, default=None,
                    help="rate limit of the simulated ego's steering (default: instant)")
    ap.add_argument("--judge-steer-rate", type=float, default=COMMONROAD_STEER_RATE)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--out", default="results")
    ap.add_argument("--tag", default="")
    args = ap.parse_args(argv)
    if not commonroad_available():
        print('commonroad_judge: needs the extra: pip install ".[commonroad]"', file=sys.stderr)
        return 2
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
        "| scenario | controller | CommonRoad feasible | max steering rate [rad/s] "
        "| max drift [m] | success | collisions | nuPlan comfortable |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for s in args.scenarios.split(","):
        for c in args.controllers.split(","):
            g = [r for r in rows if r["scenario"] == s and r["controller"] == c]
            judged = [r for r in g if "commonroad_feasible" in r]
            feas = sum(bool(r["commonroad_feasible"]) for r in judged)
            rate = max((r["commonroad_max_steer_rate"] for r in judged), default=float("nan"))
            drift = max((r["commonroad_max_position_drift_m"] for r in judged), default=0.0)
            lines.append(
                f"| {s} | {c} | {feas}/{len(judged)} | {rate:.2f} | {drift:.3f} | "
                f"{sum(r['success'] for r in g)}/{len(g)} | {sum(r['collision'] for r in g)} | "
                f"{sum(bool(r['nuplan_comfortable']) for r in g)}/{len(g)} |"
            )
    total = sum(bool(r.get("commonroad_feasible")) for r in rows)
    lines += ["", f"Feasible in all: **{total}/{len(rows)}**.", ""]
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    tag = f"_{args.tag}" if args.tag else ""
    write_text_atomic(out / f"commonroad_judge{tag}.md", "\n".join(lines))
    write_text_atomic(
        out / f"commonroad_judge{tag}.json",
        json.dumps({"command": " ".join(sys.argv), "rows": rows}, indent=1) + "\n",
    )
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())
