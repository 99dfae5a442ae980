"""Today's stock parking-v0 --reverse 100-seed run against session 16's last one
(results/closed_loop_stock100_reverse_s16_cusps.json); run from /work/main."""
import json, statistics
new = json.load(open("results/docs_s24/closed_loop_stock100_reverse_s24.json"))["reports"]
old = json.load(open("results/closed_loop_stock100_reverse_s16_cusps.json"))["reports"]
o = {(r["seed"], r["controller"]): r for r in old}
for c in ("pure-pursuit", "stanley", "lqr"):
    rs = [r for r in new if r["controller"] == c]
    print(c, "n", len(rs), "success", sum(bool(r["success"]) for r in rs),
          "is_success", sum(bool(r.get("highway_env_success")) for r in rs),
          "nuplan", sum(bool(r["nuplan_comfortable"]) for r in rs),
          "time mean %.2f (s16 %.2f)" % (statistics.mean(r["duration_s"] for r in rs),
                                         statistics.mean(o[(r["seed"], c)]["duration_s"] for r in rs)),
          "goal max %.3f" % max(r["goal_position_err_m"] for r in rs),
          "cte max %.3f" % max(r["cte_max_m"] for r in rs),
          "cusps>0", sum(r["path_cusps"] > 0 for r in rs))
    diff = [(r["seed"], round(o[(r["seed"], c)]["path_length_m"], 4), round(r["path_length_m"], 4),
             o[(r["seed"], c)]["path_cusps"], r["path_cusps"]) for r in rs
            if abs(r["path_length_m"] - o[(r["seed"], c)]["path_length_m"]) > 1e-3
            or r["path_cusps"] != o[(r["seed"], c)]["path_cusps"]]
    print("  plans differing from s16_cusps (>1 mm or cusps): seed, len s16, len now, cusps s16, now:", diff)
