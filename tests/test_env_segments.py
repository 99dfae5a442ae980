"""An agent driving alone keeps every gear segment of its path, a 1 m one too.

Replaying the controller's own commands in direct mode on ``ParallelParking-v0``
(episode seed 1: segments of 29.1, 6.0, 1.0 and 2.0 m) skipped the 1 m forward
segment: just after entering it the car still rolled back at 8 cm/s, in the next
segment's gear, and the switch rule counted that as having turned. The observation
then asked for reverse through the metre the car drove forward.
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np

import rrtdrive  # noqa: F401 - registers the gym ids
from rrtdrive.envs.segments import CUSP_REACH_M, starts_next_segment


def test_the_controllers_drive_replayed_alone_keeps_the_1_m_segment():
    kw = {"seed": 0, "options": {"episode_seed": 1}}
    ref = gym.make("rrtdrive/ParallelParking-v0", residual=True)
    alone = gym.make("rrtdrive/ParallelParking-v0")
    ref.reset(**kw)
    obs, _ = alone.reset(**kw)
    segments = alone.unwrapped._ctrl.segments
    assert [round(s.length, 1) for s in segments] == [29.1, 6.0, 1.0, 2.0]
    limits = ref.unwrapped.config.limits
    steps_in, gears_seen = [0] * len(segments), [set() for _ in segments]
    for _ in range(3000):
        _, _, done, cut, info = ref.step(np.zeros(2, np.float32))
        a, d = info["accel"], info["steer"]
        action = np.array([a / limits.a_max if a >= 0 else a / abs(limits.a_min),
                           d / limits.steer_limit], np.float32)  # fmt: skip
        obs, _, done2, cut2, _ = alone.step(action)
        k = alone.unwrapped._segment
        steps_in[k] += 1
        gears_seen[k].add(float(obs[-2]))
        if done or cut or done2 or cut2 or k == len(segments) - 1:
            break
    # The 1 m forward segment is driven (about 4 s at 20 Hz), observed in its own gear.
    assert steps_in[2] >= 20, steps_in
    assert gears_seen[2] == {1.0}
    ref.close()
    alone.close()


def test_moving_in_the_next_gear_counts_within_half_a_short_segment():
    for length in (0.4, 1.0, 1.6, 50.0):
        reach = min(CUSP_REACH_M, length / 2.0)
        assert starts_next_segment(-0.2, -1, reach - 1e-9, length, 0.5, 0.1)
        assert not starts_next_segment(-0.2, -1, reach + 1e-3, length, 0.5, 0.1)
        assert not starts_next_segment(0.2, -1, 0.0, length, 0.5, 0.1)  # its own gear
