"""Today's gear-scenario 100-seed run against the latest earlier runs: parking-reverse-in
against results/closed_loop_reverse_in100_s18.json (session 18), parallel-parking and
u-turn against results/closed_loop_gears100_s16.json (session 16). Run from /work/main."""
import json, statistics
new = json.load(open("results/docs_s24/closed_loop_gears100_s24.json"))["reports"]
ref = {"parking-reverse-in": "results/closed_loop_reverse_in100_s18.json",
       "parallel-parking": "results/closed_loop_gears100_s16.json",
       "u-turn": "results/closed_loop_gears100_s16.json"}
for sc, f in ref.items():
    old = {(r["scenario"], r["seed"], r["controller"]): r for r in json.load(open(f))["reports"]}
    for c in ("pure-pursuit", "stanley", "lqr"):
        rs = [r for r in new if r["scenario"] == sc and r["controller"] == c]
        os_ = [old[(sc, r["seed"], c)] for r in rs]
        diff = sum(abs(r["path_length_m"] - o["path_length_m"]) > 1e-3 or r["path_cusps"] != o["path_cusps"] for r, o in zip(rs, os_))
        print(f"{sc} {c}: n {len(rs)}, success {sum(r['success'] for r in rs)} (was {sum(o['success'] for o in os_)}), "
              f"nuplan {sum(bool(r['nuplan_comfortable']) for r in rs)}, plans differing {diff}, "
              f"time mean {statistics.mean(r['duration_s'] for r in rs):.2f} (was {statistics.mean(o['duration_s'] for o in os_):.2f}), "
              f"goal max {max(r['goal_position_err_m'] for r in rs):.4f} (was {max(o['goal_position_err_m'] for o in os_):.4f}), "
              f"CTE max {max(r['cte_max_m'] for r in rs):.4f} (was {max(o['cte_max_m'] for o in os_):.4f}), "
              f"path length mean {statistics.mean(r['path_length_m'] for r in rs):.2f} (was {statistics.mean(o['path_length_m'] for o in os_):.2f}) [{f}]")
