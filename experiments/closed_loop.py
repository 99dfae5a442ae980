"""Closed loop at scale: seeds x controllers x scenarios, planned by the improved RRT-Connect.

Usage::

    python experiments/closed_loop.py --seeds 50 --jobs 2 --out results \
        --doc DOC.md --figures docs/figures

For every scenario (``parking``, ``overtake`` with the stopped car,
``overtake-oncoming`` with ``--oncoming`` oncoming cars as well), controller (pure
pursuit, Stanley, LQR) and seed 0..seeds-1: plan, drive in highway-env at the
simulation frequency, evaluate (:func:`rrtdrive.evaluation.evaluate`). Writes
``OUT/closed_loop.json`` (every report, the summaries, the resolved settings and
the command) and ``OUT/closed_loop.md``; with ``--doc`` the same table and a few
frames (PNG) of seed 0 for the docs (a new page, or one holding this script's
generated block: docs/closed_loop.md is a hand-written log without one and is refused).

The gear-change scenarios (issue 14) and stock highway-env envs::

    python experiments/closed_loop.py --scenarios parking-reverse-in parallel-parking \
        u-turn --seeds 10 --planner hybrid-a-star --name closed_loop_gears
    python experiments/closed_loop.py --stock parking-v0 --seeds 100 --name closed_loop_stock
    python experiments/closed_loop.py --stock parking-v0 --reverse --seeds 100 \
        --deterministic --name closed_loop_stock_reverse

``parking-reverse-in`` is ``parking`` with ``reverse_in=True``; a gear scenario's
table adds the goal errors, nuPlan comfort, the steering-rate limit and the gear
changes. ``--stock ENV`` drives highway-env's own env through ``env.step``
(:func:`rrtdrive.sim.stock.drive_stock_env`) and adds ``highway_env_success``;
with ``--reverse`` it plans the stock envs with gear changes (as ``rrtdrive simulate
parking-v0 --reverse``) and adds the gear table for them.
``--name`` names the output files (default ``closed_loop``), so these runs do not
overwrite the forward table.
"""

from __future__ import annotations

import argparse
import math
import os
import platform
import statistics
import sys
import time
from pathlib import Path as FsPath

sys.path.insert(0, str(FsPath(__file__).resolve().parent))
from results_io import check_doc, json_text, out_file, out_folder, write_doc, write_image_atomic  # noqa: E402

from rrtdrive.bench.backends import episode_progress, parallel_map  # noqa: E402
from rrtdrive.cli_args import flags_for, int_at_least, positive_int  # noqa: E402
from rrtdrive.evaluation import EpisodeReport, evaluate, summarise  # noqa: E402
from rrtdrive.maps import write_text_atomic  # noqa: E402
from rrtdrive.sim.limits import MAX_SIM_FREQUENCY, MIN_SIM_FREQUENCY  # noqa: E402
from rrtdrive.sim.runner import EpisodeConfig, run_episode  # noqa: E402
from rrtdrive.sim.scenes import SimConfig  # noqa: E402
from rrtdrive.sim.tasks import DEFAULT_PLANNER, make_scenario  # noqa: E402
from rrtdrive.sim.tasks import Task as Scenario  # noqa: E402
from rrtdrive.types import Budget, VehicleParams  # noqa: E402

SCENARIOS = ("parking", "overtake", "overtake-oncoming")
#: The gear-change scenarios (issue 14): their table has the gear columns.
GEAR_SCENARIOS = ("parking-reverse-in", "parallel-parking", "u-turn")
CONTROLLERS = ("pure-pursuit", "stanley", "lqr")


def scenario_for(label: str, seed: int, oncoming: int) -> Scenario:
    """``overtake-oncoming`` is the overtake scenario with ``oncoming`` oncoming cars.

    ``parking-reverse-in`` is the parking scenario with its goal facing out of the spot.
    """
    if label == "overtake-oncoming":
        return make_scenario("overtake", seed, oncoming=oncoming)
    if label == "parking-reverse-in":
        return make_scenario("parking", seed, reverse_in=True)
    return make_scenario(label, seed)


def _check_names(
    scenarios: list[str], stock: list[str], controllers: list[str], planner: str, oncoming: int
) -> None:
    """Every name before any episode, each error naming its flag (not ``scenario:``)."""
    from rrtdrive.controllers import make_controller
    from rrtdrive.planning import make_planner
    from rrtdrive.sim.stock import STOCK_ENVS
    from rrtdrive.types import InputError

    with flags_for({"scenario": "--scenarios", "controller": "--controllers",
                    "planner": "--planner"}):  # fmt: skip
        for s in scenarios:
            scenario_for(s, 0, oncoming)
        for c in controllers:
            make_controller(c)
        make_planner(planner)
    for e in stock:
        if e not in STOCK_ENVS:
            raise InputError(f"--stock: unknown env {e!r}; choose from {sorted(STOCK_ENVS)}")


def _config(hz: int, deterministic: bool) -> EpisodeConfig:
    budget = Budget(max_time_s=1e6) if deterministic else Budget()
    return EpisodeConfig(sim=SimConfig(simulation_frequency=hz), budget=budget)


def run_one(job: tuple) -> dict:
    label, planner, controller, seed, hz, oncoming = job[:6]
    deterministic = bool(job[6]) if len(job) > 6 else False
    reverse = bool(job[7]) if len(job) > 7 else False
    cfg = _config(hz, deterministic) if deterministic else EpisodeConfig(
        sim=SimConfig(simulation_frequency=hz))
    if label.startswith("stock:"):
        from rrtdrive.sim.stock import drive_stock_env

        run = drive_stock_env(
            label[len("stock:"):], seed, planner, controller, cfg, reverse=reverse
        )
        out = evaluate(run.episode).to_json()
        out.update(run.to_json())
        out["max_time_s"] = run.episode.scenario.max_time_s
    else:
        ep = run_episode(scenario_for(label, seed, oncoming), planner, controller, seed, cfg)
        out = evaluate(ep).to_json()
    out["scenario"] = label
    return out


def _deg(v: float | None) -> str:
    return "n/a" if v is None else f"{math.degrees(v):.2f}"


def _vals(group: list[dict], key: str) -> list[float]:
    return [r[key] for r in group if r.get(key) is not None]


def gear_table(reports: list[dict], scenarios: list[str], controllers: list[str]) -> str:
    """The gear scenarios' table: success, collisions, errors, comfort, rate limit, gears."""
    head = (
        "| scenario | controller | success | plan failed | collisions (highway-env / "
        "footprint) | CTE RMS mean / max [m] | goal error max [m] | goal heading max [deg] | "
        "nuPlan comfortable | steering rate over limit (episodes) | gear changes driven "
        "(mean) | time mean [s] |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n"
    )
    rows = []
    for scen in scenarios:
        for ctrl in controllers:
            g = [r for r in reports if r["scenario"] == scen and r["controller"] == ctrl]
            if not g:
                continue
            n = len(g)
            drove = [r for r in g if r["status"] != "plan_failed"]
            cte = _vals(drove, "cte_rms_m")
            pos = _vals(drove, "goal_position_err_m")
            head_err = _vals(drove, "goal_heading_err_rad")
            gears = _vals(drove, "gear_changes")
            dur = _vals(drove, "duration_s")
            comfy = sum(bool(r.get("nuplan_comfortable")) for r in drove)
            over = sum((r.get("steering_rate_over_limit_share") or 0) > 0 for r in drove)
            rows.append(
                f"| {scen} | {ctrl} | {sum(r['success'] for r in g)}/{n} | "
                f"{n - len(drove)} | {sum(r['collision_highway_env'] for r in g)} / "
                f"{sum(r['collision_footprint'] for r in g)} | "
                f"{_fmt(sum(cte) / len(cte) if cte else None)} / {_fmt(max(cte, default=None))}"
                f" | {_fmt(max(pos, default=None))} | {_deg(max(head_err, default=None))} | "
                f"{comfy}/{len(drove)} | {over}/{len(drove)} | "
                f"{_fmt(sum(gears) / len(gears) if gears else None, 2)} | "
                f"{_fmt(sum(dur) / len(dur) if dur else None, 1)} |"
            )
    return head + "\n".join(rows) + "\n"


def stock_table(reports: list[dict], envs: list[str], controllers: list[str]) -> str:
    """Stock envs: highway-env's own verdict beside ours, crashes, stopped within the limit."""
    head = (
        "| env | controller | highway-env is_success | our success | plan failed | "
        "crashed | stopped at the goal within the time limit | highway-env terminated "
        "(median) [s] | time max [s] (limit) | goal error max [m] |\n"
        "|---|---|---|---|---|---|---|---|---|---|\n"
    )
    rows = []
    for env in envs:
        for ctrl in controllers:
            g = [r for r in reports if r["scenario"] == f"stock:{env}" and r["controller"] == ctrl]
            if not g:
                continue
            n = len(g)
            term = sorted(_vals(g, "highway_env_terminated_s"))
            dur = _vals(g, "duration_s")
            pos = _vals(g, "goal_position_err_m")
            stopped = sum(r["status"] == "arrived" and r["success"] for r in g)
            rows.append(
                f"| {env} | {ctrl} | {sum(r['highway_env_success'] for r in g)}/{n} | "
                f"{sum(r['success'] for r in g)}/{n} | "
                f"{sum(r['status'] == 'plan_failed' for r in g)} | "
                f"{sum(r['status'] == 'crashed' for r in g)} | {stopped}/{n} | "
                f"{_fmt(statistics.median(term) if term else None, 2)} | "
                f"{_fmt(max(dur, default=None), 1)} ({g[0].get('max_time_s', 0):g}) | "
                f"{_fmt(max(pos, default=None))} |"
            )
    return head + "\n".join(rows) + "\n"


def _fmt(v: float | None, digits: int = 3) -> str:
    return "n/a" if v is None else f"{v:.{digits}f}"


def table(summaries: dict[str, dict]) -> str:
    kmax = VehicleParams().kappa_max
    head = (
        "| scenario | controller | success | collisions (highway-env / footprint) | "
        "CTE RMS mean / max [m] | CTE max [m] | heading RMS mean [rad] | "
        f"max executed κ [1/m] (κ_max {kmax:.3f}) | κ over limit | max a_lat [m/s²] | "
        "max jerk [m/s³] | max steering rate [rad/s] | goal error max [m] | time [s] |\n"
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n"
    )
    rows = []
    for key, s in summaries.items():
        scen, ctrl = key.split("/")
        rows.append(
            f"| {scen} | {ctrl} | {100 * s['success_rate']:.0f} % ({s['episodes']}) | "
            f"{s['collisions_highway_env']} / {s['collisions_footprint']} | "
            f"{_fmt(s['cte_rms_m_mean'])} / {_fmt(s['cte_rms_m_max'])} | "
            f"{_fmt(s['cte_max_m_max'])} | {_fmt(s['heading_err_rms_rad_mean'], 4)} | "
            f"{_fmt(s['executed_max_curvature_max'], 4)} | "
            f"{_fmt(s['executed_curvature_violation_share_max'], 3)} | "
            f"{_fmt(s['max_lateral_accel_max'], 2)} | {_fmt(s['max_jerk_max'], 1)} | "
            f"{_fmt(s['max_steering_rate_max'], 2)} | {_fmt(s['goal_position_err_m_max'])} | "
            f"{_fmt(s['duration_s_mean'], 1)} |"
        )
    return head + "\n".join(rows) + "\n"


def save_frames(figures: FsPath, planner: str, hz: int, oncoming: int) -> list[str]:

    from rrtdrive.sim.video import render_frames

    names = []
    cases = (("parking", "pure-pursuit"), ("overtake", "lqr"), ("overtake-oncoming", "stanley"))
    for scenario, controller in cases:
        ep = run_episode(
            scenario_for(scenario, 0, oncoming), planner, controller, 0,
            EpisodeConfig(sim=SimConfig(simulation_frequency=hz)),
        )
        if ep.log.steps == 0:
            continue
        n = len(ep.log.states)
        stride = max(1, (n - 1) // 3) if scenario == "overtake-oncoming" else max(1, (n - 1) // 2)
        for i, frame in enumerate(render_frames(ep, stride=stride)):
            if i > 3:
                break
            name = f"closed_loop_{scenario}_{i}.png"
            write_image_atomic(figures / name, frame)
            names.append(name)
    return names


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--seeds", type=positive_int, default=50,
                    help="seeds 0..N-1 per scenario and controller (default: %(default)s)")
    ap.add_argument(
        "--scenarios", nargs="+", default=[",".join(SCENARIOS)],
        help=f"comma- or space-separated (default {','.join(SCENARIOS)}); gear scenarios: "
        f"{', '.join(GEAR_SCENARIOS)}",
    )
    ap.add_argument(
        "--stock", nargs="+", default=[], metavar="ENV",
        help="stock highway-env envs to drive through env.step (parking-v0, "
        "parking-parked-v0); with no --scenarios given, only these (default: %(default)s)",
    )
    ap.add_argument(
        "--reverse", action="store_true",
        help="with --stock: plan the stock envs with gear changes (as 'rrtdrive simulate "
        "parking-v0 --reverse'); the gear scenarios always reverse",
    )
    ap.add_argument(
        "--name", default="closed_loop", help="output file stem in --out (default closed_loop)"
    )
    ap.add_argument(
        "--deterministic", action="store_true",
        help="planning stops on its iteration budget only (no wall-clock cap)",
    )
    ap.add_argument("--oncoming", type=int_at_least(0), default=2,
                    help="oncoming cars in overtake-oncoming (default 2)")
    ap.add_argument("--controllers", default=",".join(CONTROLLERS),
                    help="comma-separated controllers (default: %(default)s)")
    ap.add_argument("--planner", default=DEFAULT_PLANNER,
                    help="registered planner name (default: %(default)s)")
    ap.add_argument("--frequency", default=20,
                    type=int_at_least(MIN_SIM_FREQUENCY, "Hz", MAX_SIM_FREQUENCY),
                    help="control and simulation frequency [Hz] (default: %(default)s)")
    ap.add_argument("--jobs", type=positive_int, default=2,
                    help="worker processes (default: %(default)s)")
    ap.add_argument("--out", default="results", type=out_folder,
                    help="directory for NAME.json and .md, NAME from --name (default: %(default)s)")
    ap.add_argument("--doc", default=None, type=out_file,
                    help="also write this markdown page (with frames)")
    ap.add_argument(
        "--figures", default=None, type=out_folder,
        help="with --doc: write seed 0's frames here and show them",
    )
    args = ap.parse_args(argv)
    check_doc(args.doc, "closed_loop.py")
    if not args.name or args.name in (".", "..") or os.sep in args.name or "/" in args.name:
        ap.error(f"--name: a file stem inside --out, not a path, got {args.name!r}")
    raw = argv if argv is not None else sys.argv[1:]
    scenarios = [x for item in args.scenarios for x in item.split(",") if x]
    if args.stock and "--scenarios" not in raw:
        scenarios = []
    stock = [x for item in args.stock for x in item.split(",") if x]
    if args.reverse and not stock:
        ap.error("--reverse: only stock envs (--stock) take it")
    controllers = args.controllers.split(",")
    _check_names(scenarios, stock, controllers, args.planner, args.oncoming)
    labels = scenarios + [f"stock:{e}" for e in stock]
    jobs = [
        (s, args.planner, c, seed, args.frequency, args.oncoming, args.deterministic,
         args.reverse)
        for s in labels for c in controllers for seed in range(args.seeds)
    ]
    t0 = time.perf_counter()
    reports: list[dict] = []

    progress = episode_progress()
    reports = parallel_map(run_one, jobs, args.jobs, progress)
    print(file=sys.stderr)
    summaries: dict[str, dict] = {}
    fields = set(EpisodeReport.__dataclass_fields__)
    for s in labels:
        for c in controllers:
            group = [r for r in reports if r["scenario"] == s and r["controller"] == c]
            objs = [EpisodeReport(**{k: v for k, v in r.items() if k in fields}) for r in group]
            summaries[f"{s}/{c}"] = summarise(objs)
    failures = [
        {k: r[k] for k in ("scenario", "controller", "seed", "status", "message")}
        for r in reports if not r["success"]
    ]
    settings = {
        "command": " ".join([sys.executable.rsplit("/", 1)[-1], *sys.argv]),
        "seeds": list(range(args.seeds)),
        "scenarios": scenarios,
        "stock": stock,
        "reverse": args.reverse,
        "deterministic": args.deterministic,
        "controllers": controllers,
        "planner": args.planner,
        "simulation_frequency": args.frequency,
        "oncoming": args.oncoming,
        "episode_config": "EpisodeConfig() defaults (speed: SpeedConfig(v_max=scenario.v_max))",
        "python": platform.python_version(),
        "wall_time_s": round(time.perf_counter() - t0, 1),
    }
    out = FsPath(args.out)
    out.mkdir(parents=True, exist_ok=True)
    write_text_atomic(
        out / f"{args.name}.json",
        json_text({"settings": settings, "summaries": summaries, "failures": failures,
                    "reports": reports}),
    )
    forward = [s for s in scenarios if s not in GEAR_SCENARIOS]
    gear = [s for s in scenarios if s in GEAR_SCENARIOS]
    tables = ""
    if forward:
        tables += table({k: v for k, v in summaries.items() if k.split("/")[0] in forward})
    if gear:
        tables += ("\n" if tables else "") + gear_table(reports, gear, controllers)
    if stock:
        tables += ("\n" if tables else "") + stock_table(reports, stock, controllers)
    if stock and args.reverse:
        tables += "\n" + gear_table(reports, [f"stock:{e}" for e in stock], controllers)
    md = (
        f"# Closed loop: {args.seeds} seeds x {len(controllers)} controllers x "
        f"{len(labels)} scenarios\n\n"
        f"Planner `{args.planner}`, control and simulation at {args.frequency} Hz in "
        f"highway-env. Command: `{settings['command']}`.\n\n" + tables
    )
    if failures:
        md += "\nFailed episodes:\n\n" + "".join(
            f"- {f['scenario']} / {f['controller']} / seed {f['seed']}: {f['status']}: "
            f"{f['message']}\n" for f in failures
        )
    write_text_atomic(out / f"{args.name}.md", md)
    print(tables)
    if args.doc:
        page = md
        if args.figures:  # frames only into a folder that was named
            figures = FsPath(args.figures)
            figures.mkdir(parents=True, exist_ok=True)
            names = save_frames(figures, args.planner, args.frequency, args.oncoming)
            rel = os.path.relpath(figures, FsPath(args.doc).parent)
            pics = "".join(f"![{n}]({rel}/{n})\n" for n in names)
            page += "\n## Frames (seed 0)\n\n" + pics
        write_doc(args.doc, page, "closed_loop.py")
    return 0


if __name__ == "__main__":
    from results_io import run_main

    raise SystemExit(run_main(main))
