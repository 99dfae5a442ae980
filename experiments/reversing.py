"""Drive across cusps in highway-env: Hybrid A* plans on the tight maps, every controller.

For each built-in tight map (``reverse_bay``, ``turning_bulb``, ``kerbside``,
``garage``, ``dead_end``) the Hybrid A* planner plans with gear changes allowed (seed 0; the
search is deterministic), and each controller drives the plan through highway-env
(``run_episode`` on a ``CustomTask``) with an instant and a 0.4 rad/s steering
actuator. Prints a markdown table of the evaluators' figures and writes it, with
the resolved settings, to ``--out``.

    python experiments/reversing.py --out results/reversing
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import sys
from pathlib import Path

import numpy as np

from rrtdrive.atomic import write_text_atomic
from rrtdrive.controllers import SpeedConfig
from rrtdrive.evaluation import evaluate
from rrtdrive.maps import builtin_map
from rrtdrive.planning import PlanningProblem, make_planner
from rrtdrive.sim.runner import run_episode
from rrtdrive.sim.tasks import CustomTask
from rrtdrive.types import Budget, VehicleParams

MAPS = ("reverse_bay", "turning_bulb", "kerbside", "garage", "dead_end")
CONTROLLERS = ("pure-pursuit", "stanley", "lqr")
RATES = (None, 0.4)
COLUMNS = (
    "map", "steer rate", "controller", "status", "cusps", "gear changes", "collision",
    "goal pos err [m]", "goal hdg err [deg]", "CTE RMS [m]", "CTE max [m]",
    "hdg err max [deg]", "max |v| reverse [m/s]", "steer rate max [rad/s]",
    "nuPlan comfortable", "time [s]",
)


def _row(map_name: str, rate: float | None, controller: str, plan) -> list[str]:
    vehicle = VehicleParams(max_steer_rate=rate)
    m = dataclasses.replace(builtin_map(map_name), vehicle=vehicle)
    ep = run_episode(CustomTask(map=m, seed=0), planner=plan, controller=controller, seed=0)
    r = evaluate(ep)
    v = ep.log.states[:, 3]
    return [
        map_name, "instant" if rate is None else f"{rate:g}", controller, ep.status.value,
        str(r.path_cusps), str(r.gear_changes),
        str(bool(r.collision)),
        f"{r.goal_position_err_m:.3f}", f"{math.degrees(r.goal_heading_err_rad):.2f}",
        f"{r.cte_rms_m:.3f}", f"{r.cte_max_m:.3f}",
        f"{math.degrees(r.heading_err_max_rad):.2f}",
        f"{max(0.0, -float(v.min())):.2f}", f"{r.max_steering_rate:.3f}",
        str(r.nuplan_comfortable), f"{r.duration_s:.1f}",
    ]


def main() -> int:
    from results_io import json_text, out_folder  # the sibling module (run as a script)

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=out_folder, default="results/reversing",
                    help="output folder (default: %(default)s)")
    ap.add_argument("--maps", nargs="+", default=list(MAPS), choices=MAPS,
                    help="tight maps to plan and drive, space-separated (default: all)")
    args = ap.parse_args()
    rows = []
    for map_name in args.maps:
        for rate in RATES:
            m = dataclasses.replace(
                builtin_map(map_name), vehicle=VehicleParams(max_steer_rate=rate)
            )
            plan = make_planner("hybrid-a-star").solve(
                PlanningProblem.from_map(m, reverse=True), np.random.default_rng(0), Budget()
            )
            for controller in CONTROLLERS:
                if not plan.success:
                    rows.append([map_name, str(rate), controller, "plan_failed"]
                                + [""] * (len(COLUMNS) - 4))
                    continue
                rows.append(_row(map_name, rate, controller, plan))
                print(" | ".join(rows[-1]), flush=True)
    table = "| " + " | ".join(COLUMNS) + " |\n|" + "---|" * len(COLUMNS) + "\n"
    table += "".join("| " + " | ".join(r) + " |\n" for r in rows)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    cmd = "python experiments/reversing.py " + " ".join(sys.argv[1:])
    write_text_atomic(out / "reversing.md", f"Command: `{cmd}`\n\n{table}")
    config = {
        "command": cmd,
        "maps": args.maps, "controllers": CONTROLLERS, "steer_rates": RATES,
        "planner": "hybrid-a-star", "reverse": True, "seed": 0,
        "speed": dataclasses.asdict(SpeedConfig()),
    }
    write_text_atomic(out / "config.json", json_text(config))
    print(table)
    return 0


if __name__ == "__main__":
    from results_io import run_main

    raise SystemExit(run_main(main))
