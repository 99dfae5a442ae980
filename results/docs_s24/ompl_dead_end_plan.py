"""Re-plan bench's run (dead_end, ompl-rs-rrtconnect, seed 0, its default budget) the way
rrtdrive.bench.worker._plan_metrics does, print verify_path as bench calls it (no
sharpness bound) and write the path as a plan JSON for `rrtdrive verify`."""
import dataclasses, json, sys
import numpy as np
import rrtdrive.bench.ompl_planners  # noqa: F401  (registers the OMPL rows)
from rrtdrive.bench.grid import BenchConfig, expand
from rrtdrive.bench.worker import _map
from rrtdrive.planning import PlanningProblem, make_planner
from rrtdrive.types import Budget
from rrtdrive.verify import verify_path

spec = expand(BenchConfig(maps=("dead_end",), planners=("ompl-rs-rrtconnect",), seeds=1, reverse=True))[0]
m = _map(spec.target, spec.map_json)
problem = PlanningProblem.from_map(m, reverse=spec.reverse)
budget = Budget(max_iterations=spec.max_iterations, max_time_s=spec.max_time_s)
result = make_planner(spec.planner).solve(problem, np.random.default_rng(spec.seed), budget)
print("spec:", spec.planner, spec.target, "seed", spec.seed, "reverse", spec.reverse,
      "budget", spec.max_iterations, spec.max_time_s)
print("plan:", result.status.value, "length %.4f m" % result.path.length,
      "max_curvature %.6f" % result.path.max_curvature, "cusps", len(result.path.cusps))
check = verify_path(m, result.path)
print("verify_path(m, path) as bench calls it: ok =", check.ok)
print(json.dumps(dataclasses.asdict(check), indent=1))
json.dump({"map": "dead_end", "path": result.path.samples.tolist(),
           "waypoints": np.asarray(result.path.waypoints).tolist()}, open(sys.argv[1], "w"))
