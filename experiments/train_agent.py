"""Residual PPO on top of a tracking controller, judged against the plain controller.

Usage (needs the optional extra ``rl``: ``pip install ".[rl]"``)::

    python experiments/train_agent.py --scenario parking --controller pure-pursuit \
        --timesteps 60000 --eval-seeds 20 --seed 0 --out results/train_agent

1. Trains Stable-Baselines3 PPO in ``rrtdrive/<Scenario>-v0`` with ``residual=True``:
   the agent's action is added to the controller's command (``residual_scale`` of
   the full range). Training episodes draw their seeds from
   ``[0, TRAIN_SEED_HI)``; observations are normalised (``VecNormalize``).
2. Evaluates the deterministic policy on the held-apart episode seeds
   ``EVAL_SEED_BASE + i`` (never drawn in training) and the plain controller on the
   same seeds (:func:`rrtdrive.sim.runner.run_episode`), with the same evaluators.
3. Writes ``OUT/train_agent.json`` (resolved settings, command, wall times, every
   report, summaries), ``OUT/train_agent.md`` (the table), the model and the
   normalisation statistics; with ``--video`` an MP4 of the agent on the first
   evaluation seed.
"""

from __future__ import annotations

import argparse
import platform
import sys
import time
from pathlib import Path as FsPath
from typing import Any

import gymnasium as gym
import numpy as np

import rrtdrive
from rrtdrive.cli_args import positive_int
from rrtdrive.evaluation import evaluate, summarise
from rrtdrive.maps import write_text_atomic
from rrtdrive.sim.runner import run_episode

TRAIN_SEED_HI = 1_000_000
EVAL_SEED_BASE = 10_000_000
IDS = {"parking": "rrtdrive/Parking-v0", "overtake": "rrtdrive/Overtake-v0"}
# Metrics of the comparison table: (key, label, digits).
ROWS = (
    ("success_rate", "success rate", 2),
    ("collisions_highway_env", "collisions (highway-env)", 0),
    ("collisions_footprint", "collisions (footprint)", 0),
    ("cte_rms_m_mean", "cross-track RMS, mean (m)", 4),
    ("cte_max_m_mean", "cross-track max, mean (m)", 4),
    ("heading_err_rms_rad_mean", "heading RMS, mean (rad)", 4),
    ("goal_position_err_m_mean", "goal position error, mean (m)", 3),
    ("goal_heading_err_rad_mean", "goal heading error, mean (rad)", 4),
    ("duration_s_mean", "duration, mean (s)", 2),
    ("max_lateral_accel_mean", "max lateral accel, mean (m/s^2)", 3),
    ("max_jerk_mean", "max jerk, mean (m/s^3)", 2),
    ("max_steering_rate_mean", "max steering rate, mean (rad/s)", 3),
)


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    from results_io import out_folder  # the sibling module (run as a script)

    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--scenario", choices=sorted(IDS), default="parking",
                   help="task to train and evaluate on (default: %(default)s)")
    p.add_argument(
        "--controller", choices=["pure-pursuit", "stanley", "lqr"], default="pure-pursuit",
        help="tracking controller the residual is added to (default: %(default)s)",
    )
    p.add_argument("--planner", default="improved-rrt-connect",
                   help="registered planner name (default: %(default)s)")
    p.add_argument("--timesteps", type=positive_int, default=60_000,
                   help="PPO environment steps (default: %(default)s)")
    p.add_argument("--envs", type=positive_int, default=2,
                   help="parallel training environments (default: %(default)s)")
    p.add_argument("--eval-seeds", type=positive_int, default=20,
                   help="held-apart evaluation episodes (default: %(default)s)")
    p.add_argument("--seed", type=int, default=0, help="seeds PPO and the training envs")
    p.add_argument("--action-repeat", type=positive_int, default=2,
                   help="simulation steps per action (default: %(default)s)")
    p.add_argument("--residual-scale", type=float, default=0.25,
                   help="fraction of the full command range the residual spans "
                   "(default: %(default)s)")
    p.add_argument("--w-cte", type=float, default=100.0,
                   help="reward weight, 1/(m^2 s) (default: %(default)s)")
    p.add_argument("--w-heading", type=float, default=10.0,
                   help="reward weight, 1/(rad^2 s) (default: %(default)s)")
    p.add_argument("--w-speed", type=float, default=5.0,
                   help="reward weight, s/m^2 (default: %(default)s)")
    p.add_argument("--n-steps", type=positive_int, default=512,
                   help="PPO rollout length per env (default: %(default)s)")
    p.add_argument("--log-std-init", type=float, default=-1.0,
                   help="PPO policy's initial log standard deviation (default: %(default)s)")
    p.add_argument("--gamma", type=float, default=0.99,
                   help="discount factor of PPO and VecNormalize (default: %(default)s)")
    p.add_argument("--out", type=out_folder, default="results/train_agent",
                   help="directory for train_agent.json and .md, ppo_residual.zip and "
                   "vecnormalize.pkl (default: %(default)s)")
    p.add_argument("--video", action="store_true", help="MP4 of the agent on the first eval seed")
    args = p.parse_args(argv)
    for name in ("timesteps", "envs", "eval_seeds", "action_repeat", "n_steps"):
        if getattr(args, name) < 1:
            p.error(f"--{name.replace('_', '-')}: must be >= 1")
    return args


def env_kwargs(args: argparse.Namespace) -> dict[str, Any]:
    return {
        "planner": args.planner,
        "controller": args.controller,
        "residual": True,
        "residual_scale": args.residual_scale,
        "action_repeat": args.action_repeat,
        "reward": {"cte": args.w_cte, "heading": args.w_heading, "speed": args.w_speed},
    }


def fmt(v: Any, digits: int) -> str:
    if v is None:
        return "n/a"
    return f"{v:.{digits}f}" if digits else str(int(v))


def table(agent: dict[str, Any], plain: dict[str, Any], args: argparse.Namespace) -> str:
    lines = [
        f"| metric ({args.eval_seeds} held-apart seeds) | {args.controller} | "
        f"{args.controller} + PPO residual |",
        "|---|---:|---:|",
    ]
    for key, label, digits in ROWS:
        lines.append(f"| {label} | {fmt(plain.get(key), digits)} | {fmt(agent.get(key), digits)} |")
    lines.append(
        f"| mean return (env reward) | {plain['mean_return']:.2f} | {agent['mean_return']:.2f} |"
    )
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    from results_io import json_text  # the sibling module (run as a script)

    args = parse_args(argv)
    try:
        import torch
        from stable_baselines3 import PPO
        from stable_baselines3.common.callbacks import BaseCallback
        from stable_baselines3.common.env_util import make_vec_env
        from stable_baselines3.common.vec_env import DummyVecEnv, VecNormalize
    except ImportError:
        print("train_agent: needs stable-baselines3 (pip install '.[rl]')", file=sys.stderr)
        return 2
    torch.set_num_threads(1)
    out = FsPath(args.out)
    out.mkdir(parents=True, exist_ok=True)
    env_id = IDS[args.scenario]
    kwargs = env_kwargs(args)

    # ---------------------------------------------------------------- training
    train_env = make_vec_env(
        env_id, n_envs=args.envs, seed=args.seed, vec_env_cls=DummyVecEnv,
        env_kwargs={**kwargs, "seed_range": (0, TRAIN_SEED_HI)},
    )
    train_env = VecNormalize(train_env, norm_obs=True, norm_reward=True, gamma=args.gamma)
    model = PPO(
        "MlpPolicy", train_env, seed=args.seed, device="cpu", n_steps=args.n_steps,
        batch_size=256, n_epochs=10, learning_rate=3e-4, gamma=args.gamma, gae_lambda=0.95,
        policy_kwargs={"log_std_init": args.log_std_init, "net_arch": [64, 64]}, verbose=0,
    )
    t0 = time.perf_counter()

    class Progress(BaseCallback):
        """A line on stderr at every tenth of the training (it takes minutes)."""

        def __init__(self) -> None:
            super().__init__()
            self.next_tenth = 1

        def _on_step(self) -> bool:
            done = self.num_timesteps / args.timesteps
            if self.next_tenth <= 10 and done * 10 >= self.next_tenth:
                self.next_tenth = int(done * 10) + 1
                print(f"training: {self.num_timesteps}/{args.timesteps} steps, "
                      f"{time.perf_counter() - t0:.0f} s", file=sys.stderr, flush=True)
            return True

    model.learn(total_timesteps=args.timesteps, callback=Progress())
    train_wall = time.perf_counter() - t0
    monitors = train_env.venv.envs  # make_vec_env wraps each env in a Monitor
    train_episodes = sum(len(m.get_episode_rewards()) for m in monitors)
    model.save(out / "ppo_residual.zip")
    train_env.save(str(out / "vecnormalize.pkl"))
    train_env.training = False
    train_env.norm_reward = False
    print(f"trained {args.timesteps} steps in {train_wall:.1f} s", flush=True)

    # ---------------------------------------------------------------- evaluation
    seeds = [EVAL_SEED_BASE + i for i in range(args.eval_seeds)]
    eval_env = gym.make(env_id, **kwargs)
    agent_reports, plain_reports, agent_returns, plain_returns = [], [], [], []
    t1 = time.perf_counter()
    for s in seeds:
        obs, _ = eval_env.reset(options={"episode_seed": s})
        total = 0.0
        while True:
            action, _ = model.predict(train_env.normalize_obs(obs), deterministic=True)
            obs, reward, terminated, truncated, info = eval_env.step(action)
            total += reward
            if terminated or truncated:
                break
        agent_reports.append(eval_env.unwrapped.report)
        agent_returns.append(total)
        # The plain controller: the runner itself, and the env's return of a zero residual.
        plain_reports.append(
            evaluate(run_episode(args.scenario, args.planner, args.controller, s))
        )
        obs, _ = eval_env.reset(options={"episode_seed": s})
        total = 0.0
        while True:
            obs, reward, terminated, truncated, _ = eval_env.step(np.zeros(2, np.float32))
            total += reward
            if terminated or truncated:
                break
        plain_returns.append(total)
    eval_wall = time.perf_counter() - t1
    eval_env.close()

    agent = {**summarise(agent_reports), "mean_return": float(np.mean(agent_returns))}
    plain = {**summarise(plain_reports), "mean_return": float(np.mean(plain_returns))}
    video = None
    if args.video:
        from rrtdrive.envs.video import RecordMP4, record_episode

        venv = RecordMP4(
            gym.make(env_id, render_mode="rgb_array", **kwargs), out, name_prefix="agent"
        )
        _, info = record_episode(
            venv,
            lambda o: model.predict(train_env.normalize_obs(o), deterministic=True)[0],
            options={"episode_seed": seeds[0]},
        )
        venv.close()
        video = info.get("video")

    result = {
        "command": " ".join(["python", sys.argv[0], *(sys.argv[1:] if argv is None else argv)]),
        "settings": {
            **vars(args), "env_id": env_id, "env_kwargs": kwargs,
            "train_seed_range": [0, TRAIN_SEED_HI], "eval_seeds": seeds,
        },
        "versions": {
            "python": platform.python_version(), "rrtdrive": rrtdrive.__version__,
            "torch": torch.__version__,
            "stable_baselines3": __import__("stable_baselines3").__version__,
            "gymnasium": gym.__version__,
        },
        "train_wall_s": train_wall,
        "train_episodes": train_episodes,
        "eval_wall_s": eval_wall,
        "summary": {"agent": agent, "plain": plain},
        "agent_reports": [r.to_json() for r in agent_reports],
        "plain_reports": [r.to_json() for r in plain_reports],
        "agent_returns": agent_returns,
        "plain_returns": plain_returns,
        "video": video,
    }
    write_text_atomic(out / "train_agent.json", json_text(result))
    md = table(agent, plain, args)
    md += (
        f"\nPPO: {args.timesteps} steps, {args.envs} envs, action repeat {args.action_repeat}, "
        f"{train_episodes} training episodes, training wall time {train_wall:.0f} s; "
        f"evaluation {eval_wall:.0f} s.\n"
    )
    write_text_atomic(out / "train_agent.md", md)
    print(md)
    return 0


if __name__ == "__main__":
    from results_io import run_main

    raise SystemExit(run_main(main))
