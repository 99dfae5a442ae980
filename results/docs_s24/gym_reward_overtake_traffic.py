import collections, gymnasium as gym, numpy as np, rrtdrive.envs
env = gym.make('rrtdrive/OvertakeTraffic-v0', residual=True, replan_options={'wall_limit': False})
env.reset(seed=0, options={'episode_seed': 0})
total, terms = 0.0, collections.Counter()
n = 0
while True:
    _, r, done, cut, info = env.step(np.zeros(2, np.float32))
    total += r; terms.update(info['reward_terms']); n += 1
    if done or cut: break
print(round(total, 2), {k: round(v, 2) for k, v in terms.items()}, info['status'])
print("steps", n)
