"""Drive every built-in map (forward and --reverse) and a set of scenarios; pickle the episodes."""
import pickle, sys, time, os
from rrtdrive.cli import map_with_poses
from rrtdrive.sim.tasks import CustomTask, make_scenario
from rrtdrive.sim.runner import DEFAULT_PLANNER, run_episode
os.makedirs("eps", exist_ok=True)
jobs = []
for name in ["overtake", "parking_lot", "narrow_gap", "no_path", "garage", "turning_bulb",
             "kerbside", "reverse_bay", "dead_end"]:
    for rev in (False, True):
        jobs.append((f"map_{name}_{'rev' if rev else 'fwd'}",
                     lambda name=name, rev=rev: CustomTask.from_map(map_with_poses(name, None, None), 0, reverse=rev)))
for scen, seed, kw in [("parking", 0, {}), ("parking", 1, {}), ("parking", 0, {"reverse_in": True}),
                       ("overtake", 0, {}), ("overtake", 0, {"oncoming": 2}), ("overtake-traffic", 0, {}),
                       ("parallel-parking", 0, {}), ("parallel-parking", 1, {}), ("u-turn", 0, {}), ("u-turn", 1, {})]:
    tag = "_".join([scen, str(seed)] + [k for k in kw])
    jobs.append((f"scen_{tag}", lambda scen=scen, seed=seed, kw=kw: make_scenario(scen, seed, **kw)))
only = sys.argv[1:]
if only == ["tall"]:  # the tall map of tall_frames.py, kept out of eps/ (its frames change)
    from rrtdrive.maps import load_map
    ep = run_episode(CustomTask.from_map(load_map("tall.json"), 0), DEFAULT_PLANNER, "pure-pursuit", 0)
    with open("tall.pkl", "wb") as f:
        pickle.dump(ep, f)
    sys.exit(print("tall", ep.status, len(ep.log.states)))
for tag, mk in jobs:
    if only and tag not in only:
        continue
    t = time.time()
    try:
        ep = run_episode(mk(), DEFAULT_PLANNER, "pure-pursuit", 0)
    except Exception as e:
        print(tag, "ERROR", type(e).__name__, e); continue
    n = len(ep.log.states)
    with open(f"eps/{tag}.pkl", "wb") as f:
        pickle.dump(ep, f)
    print(tag, ep.status, n, f"{time.time()-t:.1f}s", flush=True)
