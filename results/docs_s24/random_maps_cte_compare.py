"""Largest CTE max per controller in results/docs_s24/random_maps_drive_s24 against
results/random_maps_drive_s19 (run from /work/main)."""
import json
new = json.load(open("results/docs_s24/random_maps_drive_s24/random_maps_drive.json"))["rows"]
old = {(r["map"], r["controller"]): r for r in json.load(open("results/random_maps_drive_s19/random_maps_drive.json"))["rows"]}
for c in ("pure-pursuit", "stanley", "lqr"):
    rows = sorted((r for r in new if r["controller"] == c and r["cte_max_m"] is not None), key=lambda r: -r["cte_max_m"])
    print(c, "nuplan comfortable", sum(bool(r["nuplan_comfortable"]) for r in new if r["controller"] == c))
    for r in rows[:3]:
        print(f"  map {r['map']}: today {r['cte_max_m']:.4f} m, session 19 {old[(r['map'], c)]['cte_max_m']:.4f} m")
