"""Two closed-loop runs of the same episodes side by side: before -> after.

Usage::

    python experiments/compare_runs.py BEFORE.json AFTER.json [--out OUT/STEM.md]

Each file is what ``experiments/closed_loop.py`` or ``experiments/steer_rate.py``
writes (a ``reports`` list of episode reports). Episodes are matched by scenario,
controller and seed; only episodes in both runs count. Per scenario x controller the
table gives the episodes matched, success, collisions (either judge), nuPlan
comfortable, highway-env ``is_success`` (stock envs), the time to the goal (mean of the
successes), the goal error max, CTE max, nuPlan's longitudinal acceleration min and
longitudinal jerk max, and how many of the planned paths differ (path length by more
than 1 mm: then the planner, not the controller, made the difference). Prints the page
(and with ``--out`` writes it, through a temporary file).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

sys.path.insert(0, os.path.dirname(__file__))
from results_io import command  # noqa: E402  (the sibling script)

from rrtdrive.atomic import write_text_atomic  # noqa: E402

Report = dict[str, Any]


def _load(path: str) -> dict[tuple[str, str, int], Report]:
    with open(path, encoding="utf-8") as f:
        data = json.load(f)
    reports = data["reports"] if isinstance(data, dict) else data
    return {(r["scenario"], r["controller"], int(r["seed"])): r for r in reports}


def _values(reports: list[Report], key: str) -> list[float]:
    return [
        float(r[key]) for r in reports
        if isinstance(r.get(key), (int, float)) and not isinstance(r.get(key), bool)
        and math.isfinite(float(r[key]))
    ]  # fmt: skip


def _count(reports: list[Report], key: str) -> str:
    flags = [r.get(key) for r in reports if r.get(key) is not None]
    return f"{sum(bool(f) for f in flags)}/{len(flags)}" if flags else "-"


def _stat(reports: list[Report], key: str, how: str) -> str:
    values = _values(reports, key)
    if not values:
        return "-"
    if how == "mean":
        return f"{sum(values) / len(values):.2f}"
    return f"{(max(values) if how == 'max' else min(values)):.3f}"


COLUMNS: tuple[tuple[str, str, str], ...] = (
    ("success", "success", "count"),
    ("collision", "collision", "count"),
    ("nuPlan comfortable", "nuplan_comfortable", "count"),
    ("highway-env is_success", "highway_env_success", "count"),
    ("time to goal mean [s]", "time_to_goal_s", "mean"),
    ("goal error max [m]", "goal_position_err_m", "max"),
    ("CTE max [m]", "cte_max_m", "max"),
    ("lon accel min [m/s^2]", "nuplan_lon_accel_min", "min"),
    ("lon jerk max [m/s^3]", "nuplan_lon_jerk_abs_max", "max"),
)


def _cell(reports: list[Report], key: str, how: str) -> str:
    if how == "count":
        return _count(reports, key)
    chosen = [r for r in reports if r.get("success")] if key == "time_to_goal_s" else reports
    return _stat(chosen, key, how)


def compare(before: str, after: str) -> str:
    """The markdown page comparing the runs in files ``before`` and ``after``."""
    old, new = _load(before), _load(after)
    keys = sorted(set(old) & set(new))
    if not keys:  # two unrelated runs gave an empty table and exit 0
        raise ValueError("the two runs share no episode (scenario, controller and seed)")
    groups: dict[tuple[str, str], list[tuple[str, str, int]]] = {}
    for key in keys:
        groups.setdefault(key[:2], []).append(key)
    head = ["scenario", "controller", "episodes", "plans differ"] + [c[0] for c in COLUMNS]
    lines = [
        f"Before: `{before}`; after: `{after}`. Cells: before -> after (one value: the same).",
        "",
        "| " + " | ".join(head) + " |",
        "|" + "---|" * len(head),
    ]
    for (scenario, controller), members in groups.items():
        a = [old[k] for k in members]
        b = [new[k] for k in members]
        differ = sum(
            abs(float(x.get("path_length_m") or 0.0) - float(y.get("path_length_m") or 0.0)) > 1e-3
            for x, y in zip(a, b, strict=True)
        )
        row = [scenario, controller, str(len(members)), str(differ)]
        for _, key, how in COLUMNS:
            x, y = _cell(a, key, how), _cell(b, key, how)
            row.append(x if x == y else f"{x} -> {y}")
        lines.append("| " + " | ".join(row) + " |")
    only = len(set(old) ^ set(new))
    if only:
        lines += ["", f"Left out: {only} episode(s) in one run only."]
    return "\n".join(lines) + "\n"


def main(argv: Sequence[str] | None = None) -> int:
    """Command-line entry: print (and write) the comparison page."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("before", help="the earlier run's JSON")
    ap.add_argument("after", help="the later run's JSON")
    ap.add_argument("--out", default=None, help="also write the page to this file")
    args = ap.parse_args(argv)
    if args.out and (args.out.endswith(("/", os.sep)) or Path(args.out).is_dir()):
        print(f"compare_runs: error: --out: {args.out!r} is a folder; give the page's file "
              "name", file=sys.stderr)
        return 2
    try:
        page = compare(args.before, args.after)
    except KeyError as exc:  # another kind of JSON: say which field is missing
        print(f"compare_runs: cannot read the runs: no field {exc} (give the JSON files that "
              "experiments/closed_loop.py or steer_rate.py write)", file=sys.stderr)
        return 2
    except (OSError, ValueError) as exc:
        print(f"compare_runs: cannot read the runs: {exc}", file=sys.stderr)
        return 2
    line = command("compare_runs.py", argv)
    text = f"# Closed loop, before -> after\n\nCommand: `{line}`\n\n{page}"
    print(text, end="")
    if args.out:
        Path(args.out).parent.mkdir(parents=True, exist_ok=True)
        write_text_atomic(args.out, text)
    return 0


if __name__ == "__main__":
    from results_io import run_main

    raise SystemExit(run_main(main))
