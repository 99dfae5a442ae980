"""Episode wall time with the scenes' screened collision step vs highway-env's own.

Usage::

    python experiments/bench_scene_step.py --seeds 10 --repeats 3 --out results

``SceneRoad.step`` (``rrtdrive.sim.scenes``) skips the ``handle_collisions`` calls
that highway-env's own tests would turn into no-ops (the spherical pre-check and,
since session 30, the separating-axis test: ``rrtdrive.sim.pair_screen``), and the scenes
memoise highway-env's closest-lane search for static objects. This script runs the
same episodes both ways in one process, interleaved:

* ``screened``: as shipped;
* ``stock``: ``SceneRoad.step`` replaced by highway-env's ``Road.step`` and the lane
  cache emptied before every episode (what the scenes cost before).

Each episode is a whole :func:`rrtdrive.sim.runner.run_episode` (scene build, plan,
drive) with a fixed seed; the per-episode time is the minimum over ``--repeats``
runs of each arm. The logs of both arms must be identical (checked, reported).
Writes ``OUT/bench_scene_step.json`` and ``.md``.
"""

from __future__ import annotations

import argparse
import platform
import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path as FsPath

import numpy as np
from highway_env.road.road import Road

from rrtdrive.cli_args import positive_int
from rrtdrive.maps import write_text_atomic
from rrtdrive.sim import scenes
from rrtdrive.sim.episode import Episode
from rrtdrive.sim.replanning import ReplanConfig
from rrtdrive.sim.runner import EpisodeConfig, run_episode
from rrtdrive.sim.scenes import SceneRoad
from rrtdrive.sim.tasks import make_scenario

CASES: dict[str, tuple[str, EpisodeConfig | None, dict]] = {
    "parking": ("parking", None, {}),
    "overtake": ("overtake", None, {}),
    # Two oncoming cars: the road's walls pass highway-env's pre-check every step.
    "overtake-oncoming": ("overtake", None, {"oncoming": 2}),
    # Re-planning without wall-clock limits, so that both arms make the same decisions.
    "overtake-traffic": (
        "overtake-traffic",
        EpisodeConfig(max_time_s=30.0, replan=ReplanConfig(wall_limit=False)), {},
    ),
}


def _timed(fn: Callable[[], Episode]) -> tuple[float, Episode]:
    t0 = time.perf_counter()
    ep = fn()
    return time.perf_counter() - t0, ep


def _stock() -> None:
    SceneRoad.step = Road.step  # type: ignore[method-assign]
    scenes._LANE_CACHE.clear()


def _same(a: Episode, b: Episode) -> bool:
    return a.status == b.status and all(
        np.array_equal(getattr(a.log, k), getattr(b.log, k))
        for k in ("states", "controls", "crashed", "others")
    )


def main(argv: list[str] | None = None) -> int:
    from results_io import json_text, out_folder  # the sibling module (run as a script)

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", type=positive_int, default=10,
                    help="episodes per case, seeds 0..N-1 (default: %(default)s)")
    ap.add_argument("--repeats", type=positive_int, default=3,
                    help="runs per episode and arm; the minimum counts (default: %(default)s)")
    ap.add_argument("--cases", default=",".join(CASES),
                    help="comma-separated cases (default: %(default)s)")
    ap.add_argument("--controller", default="pure-pursuit",
                    help="pure-pursuit, stanley or lqr (default: %(default)s)")
    ap.add_argument("--out", type=out_folder, default="results",
                    help="directory for bench_scene_step.json and .md (default: %(default)s)")
    args = ap.parse_args(argv)
    cases = [c.strip() for c in args.cases.split(",") if c.strip()]
    for c in cases:
        if c not in CASES:
            ap.error(f"--cases: unknown case {c!r}; choose from {sorted(CASES)}")
    screened_step = SceneRoad.step
    rows = []
    for case in cases:
        scenario, cfg, options = CASES[case]
        # Warm-up: the first episode of a scenario builds its planner's checkers (cached).
        run_episode(make_scenario(scenario, args.seeds, **options), controller=args.controller,
                    seed=args.seeds, config=cfg)
        for seed in range(args.seeds):
            def run(scenario: str = scenario, seed: int = seed,
                    cfg: EpisodeConfig | None = cfg, options: dict = options) -> Episode:
                return run_episode(make_scenario(scenario, seed, **options),
                                   controller=args.controller, seed=seed, config=cfg)

            t_scr, t_stock = [], []
            same = True
            ref = None
            for _ in range(args.repeats):
                SceneRoad.step = screened_step  # type: ignore[method-assign]
                t, a = _timed(run)
                t_scr.append(t)
                _stock()
                t, b = _timed(run)
                t_stock.append(t)
                SceneRoad.step = screened_step  # type: ignore[method-assign]
                same = same and _same(a, b) and (ref is None or _same(a, ref))
                ref = a
            rows.append({
                "case": case, "seed": seed, "status": ref.status, "steps": ref.log.steps,
                "screened_s": min(t_scr), "stock_s": min(t_stock),
                "identical_logs": bool(same),
            })
            print(f"{case:17s} seed {seed:2d}: stock {min(t_stock) * 1e3:7.1f} ms, screened "
                  f"{min(t_scr) * 1e3:7.1f} ms, identical {same}", file=sys.stderr)
    summary = {}
    for case in cases:
        rs = [r for r in rows if r["case"] == case]
        summary[case] = {
            "episodes": len(rs),
            "stock_median_s": statistics.median(r["stock_s"] for r in rs),
            "screened_median_s": statistics.median(r["screened_s"] for r in rs),
            "speedup_median": statistics.median(r["stock_s"] / r["screened_s"] for r in rs),
            "identical_logs": all(r["identical_logs"] for r in rs),
        }
    given = sys.argv[1:] if argv is None else argv
    command = "python experiments/bench_scene_step.py " + " ".join(given)
    out = FsPath(args.out)
    out.mkdir(parents=True, exist_ok=True)
    meta = {"command": command, "python": platform.python_version(), "machine": platform.machine()}
    write_text_atomic(out / "bench_scene_step.json",
                      json_text({"meta": meta, "summary": summary, "rows": rows}))
    lines = [
        "# Screened collision step vs highway-env's `Road.step` (whole episodes)", "",
        f"Command: `{command}`  ",
        f"Controller `{args.controller}`, per-episode minimum of {args.repeats} interleaved "
        "runs of each arm; *stock* also empties the lane cache before every episode.", "",
        "| case | episodes | stock median [ms] | screened median [ms] "
        "| speed-up (median of ratios) | logs identical |",
        "|---|---|---|---|---|---|",
    ]
    for case, s in summary.items():
        lines.append(
            f"| {case} | {s['episodes']} | {s['stock_median_s'] * 1e3:.1f} | "
            f"{s['screened_median_s'] * 1e3:.1f} | **{s['speedup_median']:.2f}** | "
            f"{'yes' if s['identical_logs'] else 'NO'} |"
        )
    write_text_atomic(out / "bench_scene_step.md", "\n".join(lines) + "\n")
    print("\n".join(lines))
    return 0 if all(s["identical_logs"] for s in summary.values()) else 1


if __name__ == "__main__":
    from results_io import run_main

    raise SystemExit(run_main(main))
