"""DriveEnv's penalty terms scale with the simulated time a step spans, action_repeat included.

Mutation audit, session 35: the reward's span ``steps * dt`` changed to ``dt`` (so
``action_repeat`` was ignored and an agent acting at 1/k the rate paid 1/k of the
documented penalty) survived every test. docs/gym.md (Reward) and ``RewardWeights``
document ``cte = -w e^2 T``, ``heading = -w psi^2 T``, ``speed = -w (v - v_ref)^2 T``,
``T`` the step's duration in seconds. Here each term is recomputed from the step's own
info (``cte_m``, ``heading_err_rad``, ``speed``, ``v_ref``) and ``T`` from the change of
``info["time_s"]``, the simulated clock, for action_repeat 1 and 3.
"""

from __future__ import annotations

import numpy as np
import pytest

from rrtdrive.envs.drive_env import DriveEnv

WEIGHTS = {"cte": 3.0, "heading": 7.0, "speed": 2.0}  # not the defaults: the weights count
ACTION = np.array([1.0, 0.6], np.float32)  # full throttle, steering off the path: errors grow
SIM_SECONDS = 1.5


@pytest.mark.parametrize("repeat", [1, 3])
def test_penalties_are_weight_times_squared_error_times_elapsed_time(repeat: int) -> None:
    env = DriveEnv("overtake", action_repeat=repeat, reward=WEIGHTS)
    try:
        env.reset(options={"episode_seed": 0})
        hz = env.config.simulation_frequency
        t_prev = 0.0  # an episode starts at t = 0
        largest = dict.fromkeys(WEIGHTS, 0.0)
        for _ in range(round(SIM_SECONDS * hz / repeat)):
            _, _, terminated, truncated, info = env.step(ACTION)
            assert not (terminated or truncated), info.get("status")
            span = info["time_s"] - t_prev
            t_prev = info["time_s"]
            # The documented step: action_repeat simulation steps of 1 / hz seconds.
            assert span == pytest.approx(repeat / hz, rel=1e-9)
            want = {
                "cte": -WEIGHTS["cte"] * info["cte_m"] ** 2 * span,
                "heading": -WEIGHTS["heading"] * info["heading_err_rad"] ** 2 * span,
                "speed": -WEIGHTS["speed"] * (info["speed"] - info["v_ref"]) ** 2 * span,
            }
            terms = info["reward_terms"]
            for name, value in want.items():
                assert terms[name] == pytest.approx(value, rel=1e-9, abs=1e-15), name
                largest[name] = max(largest[name], abs(value))
        # The drive left the path and the reference speed: no term was compared at 0 only.
        assert min(largest.values()) > 1e-3, largest
    finally:
        env.close()
