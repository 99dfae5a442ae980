import json,glob,math,re
print("Built by a Python one-off (`parking_v0_reverse_failed_seeds_summary.py`, run in this folder) from the `--json` files next to it; each from `rrtdrive simulate parking-v0 --reverse --seed N --deterministic --controller C --json results/docs_s24/parking_v0_reverse_seedN_C.json` (printed summary and exit code in the matching .txt). Seeds and controllers: the 15 failed episodes of closed_loop_stock100_reverse_s8.\n")
print("| seed | controller | exit | success | highway-env is_success | collision (highway-env / footprint) | CTE max [m] | goal error [m] | goal heading [deg] | plan length [m] | cusps / gear changes | time [s] |")
print("|---|---|---|---|---|---|---|---|---|---|---|---|")
def key(f):
    m=re.match(r'parking_v0_reverse_seed(\d+)_(.*)\.json',f); return (int(m[1]),['pure-pursuit','stanley','lqr'].index(m[2]))
for f in sorted(glob.glob('parking_v0_reverse_seed*.json'),key=key):
    d=json.load(open(f)); ex=open(f[:-5]+'.txt').read().strip().splitlines()[-1].split()[-1]
    print(f"| {d['seed']} | {d['controller']} | {ex} | {d['success']} | {d['highway_env_success']} | {d['collision_highway_env']} / {d['collision_footprint']} | {d['cte_max_m']:.3f} | {d['goal_position_err_m']:.3f} | {math.degrees(d['goal_heading_err_rad']):.2f} | {d['path_length_m']:.2f} | {d['path_cusps']} / {d['gear_changes']} | {d['duration_s']:.2f} |")
