"""What one worker does for one run: plan (or plan and drive) and return the metrics row.

Everything here is a module-level function so that spawned processes and Ray
workers can import it. Maps are resolved once per process and their checkers
are cached by :meth:`rrtdrive.planning.PlanningProblem.from_map`, so a worker
pays the distance-field construction once per map.
"""

from __future__ import annotations

import functools
import os
import socket
import time
import warnings
from datetime import UTC, datetime
from typing import TYPE_CHECKING, Any

import numpy as np

from rrtdrive.bench.grid import RunSpec, always_reverses
from rrtdrive.bench.planner_specs import parse_planner_spec

if TYPE_CHECKING:  # pragma: no cover
    from rrtdrive.maps import Map

__all__ = ["execute_run", "base_row", "error_row"]


@functools.lru_cache(maxsize=32)
def _map(spec: str, content: str | None = None) -> Map:
    import json

    from rrtdrive.maps import map_from_json, resolve_map
    from rrtdrive.types import InputWarning

    # The bench's own process loaded this map first and warned once, on one line; a
    # worker process printed each warning again in Python's raw form (an audit).
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", InputWarning)
        if content is not None:
            return map_from_json(json.loads(content))
        return resolve_map(spec)


def base_row(spec: RunSpec) -> dict[str, Any]:
    """The identifying fields every row starts with."""
    row: dict[str, Any] = {
        "config_hash": spec.config_hash,
        "seed": spec.seed,
        "kind": spec.kind,
        "map": spec.target if spec.kind == "plan" else None,
        "scenario": spec.target if spec.kind == "episode" else None,
        "planner": spec.planner,
        "controller": spec.controller,
        "max_time_s": spec.max_time_s,
        "max_iterations": spec.max_iterations,
        # How it was run: rows of a forward and a reverse grid looked alike. A scenario
        # that reverses anyway says so whatever the grid's flag (its error rows too).
        "reverse": spec.reverse or (spec.kind == "episode" and always_reverses(spec.target)),
        "deterministic": spec.deterministic,
    }
    return row


def error_row(spec: RunSpec, message: str, attempts: int) -> dict[str, Any]:
    """The row recorded for a run that crashed on every attempt."""
    row = base_row(spec)
    row.update(
        {
            "status": "error",
            "success": False,
            "error": message,
            "attempts": attempts,
            "finished_at": _now(),
        }
    )
    return row


def _now() -> str:
    return datetime.now(UTC).isoformat(timespec="milliseconds")


def execute_run(spec: RunSpec) -> dict[str, Any]:
    """Run one grid cell with one seed and return its row (identifiers and every metric).

    Planning-only runs record ``success``, ``status``, ``length_m``,
    ``max_curvature``, ``nodes``, ``iterations``, ``planning_time_s``, ``message``
    and ``verified`` (:func:`rrtdrive.verify.verify_path` on successful paths,
    ``None`` otherwise). Scenario runs record every metric of
    :func:`rrtdrive.evaluation.evaluate` plus ``verified`` for the planned path.

    Parameters
    ----------
    spec : RunSpec
        The run.

    Returns
    -------
    dict
        The row, JSON-ready apart from non-finite floats.

    Examples
    --------
    >>> from rrtdrive.bench.grid import BenchConfig, expand
    >>> spec = expand(BenchConfig(maps=("overtake",), planners=("rrt-connect",), seeds=1))[0]
    >>> execute_run(spec)["success"]
    True
    """
    from rrtdrive.types import InputWarning

    t0 = time.perf_counter()
    # The run's warnings about its input (a grid coarsened for memory) travel in the row:
    # the bench's process says each once, on one line, as plan does (a worker printed
    # them in Python's raw form, once per process; an audit).
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", InputWarning)
        if spec.kind == "plan":
            metrics = _plan_metrics(spec)
        elif spec.kind == "episode":
            metrics = _episode_metrics(spec)
        else:
            raise ValueError(f"kind: unknown run kind {spec.kind!r}")
    said: list[str] = []
    for w in caught:
        if not issubclass(w.category, InputWarning):
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
        elif str(w.message) not in said:
            said.append(str(w.message))
    row = base_row(spec)
    row.update(metrics)
    if said:
        row["warnings"] = said
    row.update(
        {
            "error": None,
            "wall_time_s": time.perf_counter() - t0,
            "worker": f"{socket.gethostname()}:{os.getpid()}",
            "finished_at": _now(),
        }
    )
    return row


def _plan_metrics(spec: RunSpec) -> dict[str, Any]:
    import rrtdrive.bench.ompl_planners  # noqa: F401  (registers the OMPL rows)
    from rrtdrive.planning import PlanningProblem, make_planner
    from rrtdrive.types import Budget
    from rrtdrive.verify import verify_path

    m = _map(spec.target, spec.map_json)
    problem = PlanningProblem.from_map(m, reverse=spec.reverse)
    row_planner = parse_planner_spec(spec.planner)
    planner = make_planner(row_planner.name, **row_planner.options)
    budget = Budget(max_iterations=spec.max_iterations, max_time_s=spec.max_time_s)
    result = planner.solve(problem, np.random.default_rng(spec.seed), budget)
    ok = result.success
    return {
        "map_name": m.name,
        "success": ok,
        "status": result.status.value,
        "length_m": result.path.length if ok else None,
        "max_curvature": result.path.max_curvature if ok else None,
        "kappa_max": m.vehicle.kappa_max,
        "nodes": int(result.nodes),
        "iterations": int(result.iterations),
        "planning_time_s": float(result.planning_time_s),
        "setup_time_s": float(result.setup_time_s),
        "diagnosis_time_s": result.stats.get("diagnosis_time_s"),
        "verified": bool(verify_path(m, result.path).ok) if ok else None,
        "message": result.message,
    }


def _replan_config(spec: RunSpec) -> Any:
    # A deterministic bench re-plans without wall-time cuts (in the tasks that re-plan).
    from rrtdrive.sim.tasks import REPLANNING_SCENARIOS

    if not (spec.deterministic and spec.target in REPLANNING_SCENARIOS):
        return None
    from rrtdrive.sim.replanning import ReplanConfig

    return ReplanConfig(wall_limit=False)


def _task(spec: RunSpec) -> Any:
    """The closed-loop task of a run: a built-in scenario, or a map from start to goal."""
    import dataclasses

    from rrtdrive.bench.grid import is_map_scenario
    from rrtdrive.sim.tasks import CustomTask, make_variant

    if is_map_scenario(spec.target):
        return CustomTask.from_map(
            _map(spec.target, spec.map_json), spec.seed, reverse=spec.reverse
        )
    task = make_variant(spec.target, spec.seed)
    if spec.reverse and not task.reverse:  # as rrtdrive simulate --reverse
        task = dataclasses.replace(task, reverse=True)
    return task


def _episode_metrics(spec: RunSpec) -> dict[str, Any]:
    import rrtdrive.bench.ompl_planners  # noqa: F401  (registers the OMPL rows)
    from rrtdrive.evaluation import evaluate
    from rrtdrive.sim.runner import EpisodeConfig, run_episode
    from rrtdrive.sim.stock import STOCK_ENVS, drive_stock_env
    from rrtdrive.types import Budget
    from rrtdrive.verify import verify_path

    row_planner = parse_planner_spec(spec.planner)
    config = EpisodeConfig(
        budget=Budget(max_iterations=spec.max_iterations, max_time_s=spec.max_time_s),
        replan=_replan_config(spec),
        planner_options=row_planner.options,
    )
    assert spec.controller is not None
    stock = None
    if spec.target in STOCK_ENVS:
        stock = drive_stock_env(
            spec.target, spec.seed, row_planner.name, spec.controller, config,
            reverse=spec.reverse,
        )
        episode = stock.episode
    else:
        episode = run_episode(_task(spec), row_planner.name, spec.controller, spec.seed, config)
    report = evaluate(episode).to_json()
    if stock is not None:  # the env's own judgement beside ours
        report["highway_env_success"] = stock.highway_env_success
    for k in ("scenario", "planner", "controller", "seed"):
        report.pop(k, None)
    # (The row's "reverse", whether the path was asked for with gear changes, is
    # base_row's: always_reverses covers u-turn and parallel-parking.)
    if getattr(episode.scenario, "reverse_in", False):  # parking-reverse-in, as simulate
        report["reverse_in"] = True
    plan_ok = episode.plan is not None and episode.plan.success
    report["plan_status"] = episode.plan.status.value if episode.plan is not None else None
    # The plan's per-map set-up, apart from its planning time, as simulate's JSON says it.
    report["setup_time_s"] = episode.plan.setup_time_s if episode.plan is not None else None
    report["verified"] = (
        bool(verify_path(episode.scenario.map, episode.path).ok) if plan_ok else None
    )
    return report
