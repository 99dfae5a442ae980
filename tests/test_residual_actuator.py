"""Residual mode on the rate-limited car: the residual goes on the controller's wish.

Added to a command already clipped to the actuator's reach, every residual against the
controller's turn passed and every one with it was cut, so zero-mean noise slowed the
wheels' corrections and drove the car off the path (max cte 2.6-10 m in parking).
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import rrtdrive.envs  # noqa: F401  (registers the ids)
from rrtdrive.types import VehicleParams


def steer_noise_episode(
    seed: int, env_id: str = "rrtdrive/Parking-v0", **options
) -> tuple[str, float]:
    env = gym.make(env_id, residual=True, residual_scale=0.25, action_repeat=2, **options)
    rng = np.random.default_rng(seed)
    env.reset(seed=seed)
    worst, done, info = 0.0, False, {}
    while not done:
        action = np.array([0.0, np.clip(rng.normal(0.0, 0.37), -1.0, 1.0)], dtype=np.float32)
        _, _, terminated, truncated, info = env.step(action)
        worst = max(worst, abs(info["cte_m"]))
        done = terminated or truncated
    env.close()
    return info["status"], worst


@pytest.mark.parametrize("rate", [0.4, None])
def test_zero_mean_steering_residual_keeps_the_car_on_its_path(rate):
    vehicle = VehicleParams(max_steer_rate=rate)
    status, worst = steer_noise_episode(0, scenario_options={"vehicle": vehicle})
    assert status == "arrived" and worst < 0.4, (status, worst)


@pytest.mark.parametrize("seed", [0, 1])
def test_the_same_across_a_cusp_and_in_reverse(seed):
    # Reversing into the bay (the default car): clipped first, the noise drove the car
    # 4.1 m off its path; the window is mirrored with the car in reverse. The car stays
    # within a metre of it, but this much noise lets it touch a parked car in the tight
    # bay in about half of the seeds (seeds 0-7: 4 of 8 crash with the plans before and
    # after session 16's change of the shots, not the same seeds), so only the
    # tracking is asserted.
    _, worst = steer_noise_episode(seed, "rrtdrive/ParkingReverseIn-v0")  # the default car
    assert worst < 1.5, worst


class _Ctrl:
    at_stop = False
    remaining = 10.0
    steer_wanted = 0.3  # wants far more than the wheels can reach this step
    steer_window = (0.09, 0.11)


@pytest.mark.parametrize(
    "residual, expected",
    [(0.0, 0.11), (-0.15, 0.11), (-0.2, 0.10), (-0.25, 0.09), (0.1, 0.11)],
)
def test_a_residual_is_added_to_the_wish_then_clipped_to_the_reach(residual, expected):
    from rrtdrive.controllers import SpeedConfig
    from rrtdrive.envs.action import CommandLimits, ResidualMixer

    mixer = ResidualMixer(CommandLimits(-4.0, 2.0, 0.4), SpeedConfig(), 0.05)
    # The controller's own command is its wish clipped to the window: 0.11. Clipped
    # first, a residual of -0.15 would have turned the wheels back to 0.09.
    _, steer = mixer.command(_Ctrl(), 0.0, 0.11, 0.0, residual)
    assert steer == pytest.approx(expected)
