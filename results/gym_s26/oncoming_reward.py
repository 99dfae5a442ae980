"""Reward terms of the plain controller (zero residual) on Overtake-v0 with oncoming traffic.
python check_oncoming_reward.py [episode_seed ...]"""
import collections, sys, warnings
import gymnasium as gym, numpy as np
import rrtdrive  # noqa: F401
warnings.simplefilter("ignore")
for s in [int(x) for x in sys.argv[1:]] or [0, 1, 2]:
    for onc in (0, 2):
        env = gym.make("rrtdrive/Overtake-v0", residual=True, scenario_options={"oncoming": onc})
        env.reset(seed=0, options={"episode_seed": s})
        total, terms, n = 0.0, collections.Counter(), 0
        worst = (0.0, None)
        while True:
            o, r, done, cut, info = env.step(np.zeros(2, np.float32))
            n += 1; total += r; terms.update(info["reward_terms"])
            if info["reward_terms"]["speed"] < worst[0]:
                worst = (info["reward_terms"]["speed"], dict(t=round(info["time_s"], 2), v=round(info["speed"], 2), v_ref=round(info["v_ref"], 2)))
            if done or cut: break
        print(f"episode_seed={s} oncoming={onc}: return={total:.2f} steps={n} status={info['status']} success={info['is_success']} "
              f"terms={ {k: round(v, 2) for k, v in terms.items()} } worst speed step={worst}", flush=True)
