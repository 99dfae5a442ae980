"""The markdown pages of experiments/coverage.py: the random-query run and the tight maps.

Split from ``coverage.py`` (which measures) so that each file keeps to one job; the
pages are built from the payloads that script writes as JSON.
"""

from __future__ import annotations

from typing import Any

from results_io import cell

from rrtdrive.planning.smoothing import SmoothingConfig

__all__ = ["SHARPNESS_BOUND", "report", "tight_report"]

#: The default sharpness bound, rad/m: the default planners' guarantee.
SHARPNESS_BOUND = SmoothingConfig().max_sharpness


def _sharp(v: float | str | None) -> str:
    return "-" if v is None else (v if isinstance(v, str) else f"{v:.3f}")


def _count(v: int | None) -> str:
    return "-" if v is None else str(v)


def _kept(payload: dict[str, Any]) -> str:
    """The header's words on OMPL rows that keep a body clearance (``NAME@0.15m``)."""
    kept = [p for p in payload.get("planners", []) if p.startswith("ompl-") and "@" in p]
    if not kept:
        return ""
    names = ", ".join(f"`{p}`" for p in kept)
    return (
        f" (its states may touch obstacles; in {names} every state keeps that body "
        "clearance, capped at the start's and goal's own, as ours)"
    )


def report(payload: dict[str, Any]) -> str:
    """The markdown page of one run."""
    s = payload["summary"]
    lines = [
        f"# Coverage on `{payload['map']}`: random goal and start poses, planners side by side",
        "",
        f"Command: `{payload['command']}`  ",
        " and ".join(f"{payload['count']} random {v} poses"
                     for v in payload.get("sets", ("goal", "start")))
        + f" (seed {payload['seed']}, as `experiments/random_goals.py`); ours: planner seed 0, "
        f"{payload['max_time_s']:g} s budget; OMPL: {payload['ompl_time_s']:g} s, our exact "
        f"body test{_kept(payload)}; {payload['jobs']} worker(s) on {payload['machine']}; "
        f"wall time {payload['wall_time_s'] / 60:.1f} min.",
        "",
        "`verified`: every guarantee by the independent `rrtdrive.verify.verify_path`, "
        f"sharpness <= {SHARPNESS_BOUND:g} rad/m included (from the positions: OMPL's "
        "curves jump in curvature); `any sharpness`: the same without that bound.",
        "",
        "| planner | set | solved | verified | any sharpness | collision-free "
        "| median time solved [ms] "
        "| median length [m] | median time failed [ms] | with the diagnosis [ms] "
        "| max sharpness [rad/m] "
        f"| within {SHARPNESS_BOUND:g} rad/m | other outcomes |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for p, sets in s["per_planner"].items():
        for name, c in sets.items():
            other = ", ".join(f"{k} {v}" for k, v in sorted(c["statuses"].items()) if k != "solved")
            lines.append(
                f"| {p} | {name}s | {c['solved']}/{c['queries']} | {c['verified']} | "
                f"{c.get('verified_any_sharpness', '-')} | {c['collision_free']} | "
                f"{cell(c['median_time_solved_s'], 1e3)} | "
                f"{cell(c['median_length_m'], 1, 2)} | {cell(c['median_time_failed_s'], 1e3)} | "
                f"{cell(c.get('median_answer_time_failed_s'), 1e3)} | "
                f"{_sharp(c.get('max_sharpness'))} | {_count(c.get('within_bound'))} | "
                f"{other or '-'} |"
            )
    lines += [
        "",
        "Pairs (ours against an OMPL planner): the share of OMPL's solved queries that "
        "ours solves, and on the queries both solve the median of the per-query ratios "
        "ours / OMPL and the ratio of the medians (our median over OMPL's).",
        "",
        "| pair / set | OMPL solved | both | ours only | share of OMPL's solved "
        "| median time ratio | median length ratio | time ratio of medians "
        "| length ratio of medians |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for key, c in s["pairs"].items():
        share = c["share_of_ompl_solved"]
        lines.append(
            f"| {key}s | {c['ompl_solved']} | {c['both_solved']} | {c['ours_only']} | "
            f"{cell(share, 100, 1, ' %')} | "
            f"{cell(c['median_time_ratio'], 1, 3)} | {cell(c['median_length_ratio'], 1, 3)} | "
            f"{cell(c.get('time_ratio_of_medians'), 1, 3)} | "
            f"{cell(c.get('length_ratio_of_medians'), 1, 3)} |"
        )
    geared = [(k, c) for k, c in s["pairs"].items() if "mean_cusps_ours" in c]
    if geared and any(c["mean_cusps_ours"] or c["mean_cusps_ompl"] for _, c in geared):
        lines += [
            "",
            "Gear changes (cusps; each is a stop) on the queries both solve: mean and median "
            "per path, and on how many queries ours has fewer, as many or more than OMPL's "
            "simplified path (read off its motion).",
            "",
            "| pair / set | both | mean cusps ours / OMPL | median cusps ours / OMPL "
            "| ours fewer / equal / more |",
            "|---|---|---|---|---|",
        ]
        for key, c in geared:
            fewer, equal, more = c["cusps_fewer_equal_more"]
            lines.append(
                f"| {key}s | {c['both_solved']} | {c['mean_cusps_ours']:.2f} / "
                f"{c['mean_cusps_ompl']:.2f} | {c['median_cusps_ours']:g} / "
                f"{c['median_cusps_ompl']:g} | {fewer} / {equal} / {more} |"
            )
    staged = [(p, name, c) for p, sets in s["per_planner"].items()
              for name, c in sets.items() if "solved_by_stage" in c]  # fmt: skip
    if staged:
        lines += [
            "",
            "The default planner's stages: which stage solved, and on the queries that "
            "reached the escalation the median time its RRT-Connect stages spent first "
            "(`rrt_stages_time_s`) and the escalation's own (`escalation_time_s`).",
            "",
            "| planner | set | solved by RRT-Connect / Dubins fallback / Hybrid A* | escalated "
            "| median RRT stages time, escalated [ms] | median escalation time [ms] |",
            "|---|---|---|---|---|---|",
        ]
        for p, name, c in staged:
            by = c["solved_by_stage"]
            counts = " / ".join(
                str(by.get(k, 0)) for k in ("improved-rrt-connect", "dubins-fallback",
                                            "hybrid-a-star")
            )  # fmt: skip
            lines.append(
                f"| {p} | {name}s | {counts} | {c['escalated']} | "
                f"{cell(c['median_rrt_stages_time_escalated_s'], 1e3)} | "
                f"{cell(c['median_escalation_time_s'], 1e3)} |"
            )
    if payload.get("load"):
        lines += ["", f"Load average (1/5/15 min) at start {payload['load']['start']}, at end "
                  f"{payload['load']['end']} on {payload['machine']}: only ratios within one "
                  "run compare."]  # fmt: skip
    if payload["skipped"]:
        lines += ["", "Skipped (not available in this run):", ""]
        lines += [f"- `{k}`: {v}" for k, v in payload["skipped"].items()]
    return "\n".join(lines) + "\n"


def tight_report(payload: dict[str, Any]) -> str:
    """The markdown page of a ``--tight`` run: per query and planner, solved over seeds."""
    lines = [
        "# The tight maps: which planners solve them", "",
        f"Command: `{payload['command']}`  ",
        f"Seeds {payload['seeds']} per query; ours {payload['max_time_s']:g} s budget, OMPL "
        f"{payload['ompl_time_s']:g} s; `verified`: every check of `verify_path` per gear "
        f"segment, sharpness <= {SHARPNESS_BOUND:g} rad/m included (OMPL's curves with their "
        "gears and cusps); `any sharpness`: the same without that bound; "
        f"{payload['machine']}; wall time {payload['wall_time_s'] / 60:.1f} min.", "",
        "| query | planner | solved | verified | any sharpness | collision-free "
        "| median time solved [ms] | median length [m] | median cusps "
        f"| max sharpness [rad/m] | within {SHARPNESS_BOUND:g} rad/m | outcomes | diagnosis |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for c in payload["summary"]:
        outcomes = ", ".join(f"{k} {v}" for k, v in sorted(c["statuses"].items()))
        cusps = c.get("median_cusps")
        lines.append(
            f"| {c['query']} | {c['planner']} | {c['solved']}/{c['runs']} | {c['verified']} | "
            f"{c.get('verified_any_sharpness', '-')} | {c['collision_free']} | "
            f"{cell(c.get('median_time_solved_s'), 1e3)} | "
            f"{cell(c.get('median_length_m'), 1, 2)} | {'-' if cusps is None else f'{cusps:g}'} | "
            f"{_sharp(c.get('max_sharpness'))} | {_count(c.get('within_bound'))} | {outcomes} | "
            f"{', '.join(c['diagnoses']) or '-'} |"
        )
    if payload["skipped"]:
        lines += ["", "Skipped:", ""] + [f"- `{k}`: {v}" for k, v in payload["skipped"].items()]
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    import sys

    # Run as a script it did nothing and exited 0: say what it is.
    sys.exit("coverage_report.py is a library module of experiments/coverage.py: "
             "run that instead (--help)")
