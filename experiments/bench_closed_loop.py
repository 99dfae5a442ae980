"""Closed-loop cost against raw highway-env stepping of the same number of steps.

Usage::

    python experiments/bench_closed_loop.py --seeds 10 --repeats 3 --out results

For each scenario, controller and seed: plan once, then time

* ``closed``: :func:`rrtdrive.sim.runner.drive` on a fresh scene - controller,
  logging, ``road.act()`` and ``road.step(dt)`` every step;
* ``raw``: the same scene stepped the same number of times with the recorded
  actions replayed open-loop (set the action, ``road.act()``, ``road.step(dt)``) -
  exactly highway-env's own ``_simulate`` inner loop, so the ego follows the same
  trajectory and highway-env does the same collision work;
* ``env.step``: the same replay through ``env.step`` with the policy frequency
  equal to the simulation frequency (observation, reward and info every step),
  for reference, on the first ``--env-step-seeds`` seeds.

Closed and raw are interleaved and each is the minimum over ``--repeats`` runs
(less noise on a shared machine).
The target is ``closed / raw <= 1.15``. Writes ``OUT/bench_closed_loop.json`` and ``.md``.
"""

from __future__ import annotations

import argparse
import platform
import sys
import time
from pathlib import Path as FsPath

import numpy as np

from rrtdrive.cli_args import int_at_least, positive_int
from rrtdrive.controllers import SpeedConfig, make_controller
from rrtdrive.maps import write_text_atomic
from rrtdrive.sim.limits import MAX_SIM_FREQUENCY, MIN_SIM_FREQUENCY
from rrtdrive.sim.runner import drive, run_episode
from rrtdrive.sim.scenes import SimConfig, build_env
from rrtdrive.sim.tasks import DEFAULT_PLANNER

SCENARIOS = ("parking", "overtake")
CONTROLLERS = ("pure-pursuit", "stanley", "lqr")


def time_closed(ep, sim: SimConfig) -> float:
    env = build_env(ep.scenario, sim)
    ctrl = make_controller(
        ep.controller, vehicle=ep.scenario.vehicle, speed=SpeedConfig(v_max=ep.scenario.v_max)
    )
    t = time.perf_counter()
    log = drive(env, ep.path, ctrl, ep.scenario.max_time_s)
    el = time.perf_counter() - t
    env.close()
    assert log.steps == ep.log.steps
    return el


def time_raw(ep, sim: SimConfig) -> float:
    env = build_env(ep.scenario, sim)
    u = env.unwrapped
    road, ego = u.road, u.vehicle
    action = ego.action
    dt = 1.0 / sim.simulation_frequency
    controls = ep.log.controls.tolist()
    t = time.perf_counter()
    for accel, steer in controls:
        action["acceleration"] = accel
        action["steering"] = steer
        road.act()
        road.step(dt)
        u.time += dt
        u.steps += 1
    el = time.perf_counter() - t
    env.close()
    return el


def time_env_step(ep, sim: SimConfig) -> float:
    env = build_env(ep.scenario, sim)
    u = env.unwrapped
    acc_lo, acc_hi = u.action_type.acceleration_range
    st_lo, st_hi = u.action_type.steering_range
    actions = [
        np.array([
            2 * (a - acc_lo) / (acc_hi - acc_lo) - 1, 2 * (d - st_lo) / (st_hi - st_lo) - 1
        ], dtype=np.float32)
        for a, d in ep.log.controls
    ]
    t = time.perf_counter()
    for a in actions:
        env.step(a)
    el = time.perf_counter() - t
    env.close()
    return el


def main(argv: list[str] | None = None) -> int:
    from results_io import json_text, out_folder  # the sibling module (run as a script)

    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--seeds", type=positive_int, default=10,
                    help="seeds 0..N-1 per scenario and controller (default: %(default)s)")
    ap.add_argument("--repeats", type=positive_int, default=3,
                    help="timed runs per episode; the minimum counts (default: %(default)s)")
    ap.add_argument("--frequency", default=20,
                    type=int_at_least(MIN_SIM_FREQUENCY, "Hz", MAX_SIM_FREQUENCY),
                    help="simulation frequency of the timed runs [Hz] (default: %(default)s)")
    ap.add_argument(
        "--env-step-seeds", type=positive_int, default=1,
        help="seeds also timed through env.step (slow: an observation every step)",
    )
    ap.add_argument("--planner", default=DEFAULT_PLANNER,
                    help="registered planner name (default: %(default)s)")
    ap.add_argument("--out", type=out_folder, default="results",
                    help="directory for bench_closed_loop.json and .md (default: %(default)s)")
    args = ap.parse_args(argv)
    sim = SimConfig(simulation_frequency=args.frequency)
    rows = []
    for scenario in SCENARIOS:
        for controller in CONTROLLERS:
            closed = raw = envstep = 0.0
            steps = envstep_steps = 0
            for seed in range(args.seeds):
                ep = run_episode(scenario, args.planner, controller, seed)
                if ep.log.steps == 0:
                    continue
                # Interleaved, so that load from other processes hits both alike.
                cs, rs = [], []
                for _ in range(args.repeats):
                    cs.append(time_closed(ep, sim))
                    rs.append(time_raw(ep, sim))
                closed, raw, steps = closed + min(cs), raw + min(rs), steps + ep.log.steps
                if seed < args.env_step_seeds:
                    envstep += time_env_step(ep, sim)
                    envstep_steps += ep.log.steps
            rows.append({
                "scenario": scenario, "controller": controller, "steps": steps,
                "closed_s": closed, "raw_s": raw, "env_step_s": envstep,
                "ratio_closed_raw": closed / raw if raw else None,
                "env_step_us_per_step": 1e6 * envstep / envstep_steps if envstep_steps else None,
                "closed_us_per_step": 1e6 * closed / steps if steps else None,
                "raw_us_per_step": 1e6 * raw / steps if steps else None,
            })
            print(
                f"{scenario:9s} {controller:13s} steps {steps:6d}  closed {closed:6.2f} s  "
                f"raw {raw:6.2f} s  closed/raw "
                f"{rows[-1]['ratio_closed_raw']:.3f}", file=sys.stderr,
            )
    total_c = sum(r["closed_s"] for r in rows)
    total_r = sum(r["raw_s"] for r in rows)
    settings = {
        "command": " ".join(["python", *sys.argv]),
        "seeds": list(range(args.seeds)), "repeats": args.repeats,
        "simulation_frequency": args.frequency, "planner": args.planner,
        "python": platform.python_version(), "machine": platform.machine(),
    }
    out = FsPath(args.out)
    out.mkdir(parents=True, exist_ok=True)
    write_text_atomic(
        out / "bench_closed_loop.json",
        json_text({"settings": settings, "rows": rows,
                    "ratio_closed_raw_total": total_c / total_r}),
    )
    md = [
        "# Closed loop vs raw highway-env stepping\n",
        f"Command: `{settings['command']}`; minimum of {args.repeats} runs per episode, "
        f"{args.frequency} Hz.\n",
        "| scenario | controller | steps | closed [µs/step] | raw [µs/step] | closed / raw | "
        "env.step [µs/step] |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        md.append(
            f"| {r['scenario']} | {r['controller']} | {r['steps']} | "
            f"{r['closed_us_per_step']:.0f} | {r['raw_us_per_step']:.0f} | "
            f"{r['ratio_closed_raw']:.3f} | {r['env_step_us_per_step']:.0f} |"
        )
    md.append(f"\nOverall closed / raw: **{total_c / total_r:.3f}** (target ≤ 1.15).\n")
    write_text_atomic(out / "bench_closed_loop.md", "\n".join(md))
    print("\n".join(md))
    return 0


if __name__ == "__main__":
    from results_io import run_main

    raise SystemExit(run_main(main))
