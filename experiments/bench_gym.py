"""What the gymnasium environments cost: steps per second, with and without frames, and resets.

Usage::

    python experiments/bench_gym.py --steps 400 --repeats 3 --out results/bench_gym

For ``rrtdrive/Parking-v0`` and ``rrtdrive/Overtake-v0`` in residual mode (zero
residual, ``action_repeat`` 1), in one process: the time of ``reset(seed=0)`` (it
plans and builds the scene), then ``--steps`` steps (a new episode at its end) without
rendering and with an ``rgb_array`` frame each step. Each figure is the best of
``--repeats`` runs (the machine is shared; the best is the least disturbed).
Writes ``OUT/bench_gym.json`` and ``.md``.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from collections.abc import Sequence
from typing import Any

import gymnasium as gym
import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
from results_io import command, machine, out_folder, write_results  # noqa: E402  (the sibling script)

import rrtdrive.envs  # noqa: E402,F401  (registers the environments)
from rrtdrive.cli_args import positive_int  # noqa: E402

ENV_IDS = ("rrtdrive/Parking-v0", "rrtdrive/Overtake-v0")


def _steps_per_second(env: gym.Env, steps: int, render: bool) -> float:
    env.reset(seed=0)
    zero = np.zeros(2, dtype=np.float32)
    start = time.perf_counter()
    for _ in range(steps):
        _, _, terminated, truncated, _ = env.step(zero)
        if render:
            env.render()
        if terminated or truncated:
            env.reset()
    return steps / (time.perf_counter() - start)


def measure(env_id: str, steps: int, repeats: int) -> dict[str, Any]:
    """Reset time and steps per second of ``env_id``, best of ``repeats``."""
    plain = gym.make(env_id, residual=True)
    framed = gym.make(env_id, residual=True, render_mode="rgb_array")
    resets, bare, drawn = [], [], []
    for _ in range(repeats):
        start = time.perf_counter()
        plain.reset(seed=0)
        resets.append(time.perf_counter() - start)
        bare.append(_steps_per_second(plain, steps, render=False))
        drawn.append(_steps_per_second(framed, max(1, steps // 10), render=True))
    frame = framed.render()
    plain.close()
    framed.close()
    return {
        "env_id": env_id, "reset_s": min(resets), "steps_per_s": max(bare),
        "steps_per_s_rendered": max(drawn), "frame_shape": list(np.shape(frame)),
    }  # fmt: skip


def report(payload: dict[str, Any]) -> str:
    """The markdown page."""
    lines = [
        "# The gymnasium environments' cost",
        "",
        f"Command: `{payload['command']}`  ",
        f"{payload['machine']}; residual mode, zero residual, `action_repeat` 1; best of "
        f"{payload['repeats']} runs of {payload['steps']} steps (rendered: a tenth as many).",
        "",
        "| environment | reset [s] | steps/s | steps/s with a frame each | frame |",
        "|---|---:|---:|---:|---|",
    ]
    for r in payload["rows"]:
        lines.append(
            f"| `{r['env_id']}` | {r['reset_s']:.3f} | {r['steps_per_s']:.0f} | "
            f"{r['steps_per_s_rendered']:.0f} | {' x '.join(map(str, r['frame_shape']))} |"
        )
    return "\n".join(lines) + "\n"


def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--steps", type=positive_int, default=400, help="steps per run (default 400)")
    ap.add_argument("--repeats", type=positive_int, default=3,
                    help="runs, the best kept (default 3)")
    ap.add_argument("--out", type=out_folder, default=None,
                    help="write bench_gym.json and .md here")
    args = ap.parse_args(argv)
    if args.steps < 1 or args.repeats < 1:
        ap.error("--steps and --repeats must be at least 1")
    rows = [measure(env_id, args.steps, args.repeats) for env_id in ENV_IDS]
    payload = {
        "command": command("bench_gym.py", argv), "machine": machine(),
        "steps": args.steps, "repeats": args.repeats, "rows": rows,
    }  # fmt: skip
    page = write_results(args.out, "bench_gym", payload, report) if args.out else report(payload)
    print(page, end="")
    return 0


if __name__ == "__main__":
    from results_io import run_main

    raise SystemExit(run_main(main))
