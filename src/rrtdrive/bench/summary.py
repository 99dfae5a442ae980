"""Bench summary: mean, std and 95 % confidence interval per group, as CSV, markdown and plots.

A group is one cell of the grid: ``(kind, map or scenario, planner, controller)``.
For every numeric or boolean metric of its rows (``None`` values skipped, so the
length of failed plans does not count) the summary gives ``n``, the mean, the
sample standard deviation and a 95 % interval (:func:`rrtdrive.stats.describe`):
the Wilson score interval for rates (booleans), a bootstrap interval for
non-negative quantities, Student's t for the signed ones (:data:`SIGNED_METRICS`).
Error rows (crashed runs) are counted per group and left out of every metric.
"""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Collection, Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path as FsPath
from typing import Any

import numpy as np

from rrtdrive.evaluation.report import SIGNED_FIELDS, EvalConfig
from rrtdrive.stats import Stat, describe, wilson_interval

__all__ = [
    "Stat",
    "GroupSummary",
    "summarise_rows",
    "describe",
    "wilson_interval",
    "to_csv",
    "to_markdown",
    "write_summary",
    "write_plots",
]

#: Row fields that identify a run or carry text; never summarised.
_ID_FIELDS = {
    "config_hash", "seed", "kind", "map", "scenario", "planner", "controller", "status",
    "message", "error", "worker", "finished_at", "map_name", "plan_status", "max_time_s",
    "max_iterations", "attempts", "kappa_max", "simulation_frequency", "reverse",
    "reverse_in", "deterministic",
}

#: Metrics that can be negative (Student's t interval); every other number is a
#: non-negative quantity (time, length, count, error magnitude) and gets a bootstrap
#: interval that cannot go below zero. Plan rows have no signed metric.
SIGNED_METRICS = SIGNED_FIELDS
#: Path geometry summarised over successful runs only: a crashed or timed-out episode's
#: path and its partly driven curvature say nothing of what the planner-controller
#: pair delivers when it works (the summary's note and ``box_length.png`` say so).
SUCCESS_ONLY = frozenset({"length_m", "max_curvature", "path_length_m", "executed_max_curvature"})

#: Metrics shown in the markdown tables (the CSV has every metric).
_MD_COLUMNS = {
    "plan": (
        ("success", "success", 1.0, "{:.0%}"),
        ("verified", "verified", 1.0, "{:.0%}"),
        ("length_m", "length [m]", 1.0, "{:.2f}"),
        ("planning_time_s", "time [ms]", 1e3, "{:.1f}"),
        ("max_curvature", "max κ [1/m]", 1.0, "{:.3f}"),
        ("nodes", "nodes", 1.0, "{:.0f}"),
    ),
    "episode": (
        ("success", "success", 1.0, "{:.0%}"),
        ("collision", "collision", 1.0, "{:.0%}"),
        ("cte_rms_m", "CTE rms [m]", 1.0, "{:.3f}"),
        ("path_length_m", "path [m]", 1.0, "{:.1f}"),
        ("executed_max_curvature", "exec. max κ", 1.0, "{:.3f}"),
        ("max_lateral_accel", "max a_lat", 1.0, "{:.2f}"),
        ("time_to_goal_s", "time to goal [s]", 1.0, "{:.1f}"),
        ("planning_time_s", "plan time [ms]", 1e3, "{:.1f}"),
    ),
}


@dataclass(frozen=True)
class GroupSummary:
    """All metrics of one cell of the grid.

    Attributes
    ----------
    kind : str
        ``"plan"`` or ``"episode"``.
    target : str
        Map spec or scenario name.
    planner : str
        Planner name.
    controller : str or None
        Controller name (``None`` for planning-only runs).
    runs : int
        Rows in the group, error rows included.
    errors : int
        Error rows (crashed runs).
    stats : dict
        Metric name -> :class:`Stat`.
    """

    kind: str
    target: str
    planner: str
    controller: str | None
    runs: int
    errors: int
    stats: Mapping[str, Stat]

    @property
    def label(self) -> str:
        """``target / planner [/ controller]``."""
        parts = [self.target, self.planner] + ([self.controller] if self.controller else [])
        return " / ".join(parts)


def _group_key(row: Mapping[str, Any]) -> tuple[str, str, str, str | None]:
    kind = row.get("kind", "plan")
    target = row.get("map") if kind == "plan" else row.get("scenario")
    return (str(kind), str(target), str(row.get("planner")), row.get("controller"))


def summarise_rows(rows: Iterable[Mapping[str, Any]]) -> list[GroupSummary]:
    """Group rows by grid cell and summarise every metric.

    Parameters
    ----------
    rows : iterable of dict
        Result rows (as stored in ``runs.jsonl``).

    Returns
    -------
    list of GroupSummary
        In the order the groups first appear.
    """
    groups: dict[tuple[str, str, str, str | None], list[Mapping[str, Any]]] = {}
    for row in rows:
        groups.setdefault(_group_key(row), []).append(row)
    out = []
    for (kind, target, planner, controller), members in groups.items():
        errors = sum(r.get("status") == "error" for r in members)
        out.append(
            GroupSummary(kind, target, planner, controller, len(members), errors,
                         metric_stats(members))
        )
    return out


def metric_stats(
    members: Iterable[Mapping[str, Any]], keys: Collection[str] | None = None
) -> dict[str, Any]:
    """The metrics of some rows, described (:func:`~rrtdrive.stats.describe`).

    Error rows are left out, and so is a value that is ``None`` or (for the metrics of
    :data:`SUCCESS_ONLY`) of a failed run: a rate is over the runs that have it (the
    summary's table and ``success.png`` read the same numbers).

    Parameters
    ----------
    members : iterable of mapping
        Result rows.
    keys : collection of str, optional
        Only these metrics (``None``: every one).

    Returns
    -------
    dict
        Metric name to its :class:`~rrtdrive.stats.Stat`.
    """
    metrics: dict[str, list[float]] = {}
    is_rate: dict[str, bool] = {}
    for r in members:
        if r.get("status") == "error":
            continue
        for k, v in r.items():
            if keys is not None and k not in keys:
                continue
            if k in _ID_FIELDS or v is None or (k in SUCCESS_ONLY and not r.get("success")):
                continue
            if isinstance(v, bool):
                metrics.setdefault(k, []).append(float(v))
                is_rate[k] = is_rate.get(k, True)
            elif isinstance(v, (int, float)) and math.isfinite(v):
                metrics.setdefault(k, []).append(float(v))
                is_rate[k] = False
    return {
        k: describe(v, rate=is_rate[k], nonnegative=k not in SIGNED_METRICS)
        for k, v in metrics.items()
    }


def _num(x: float) -> str:
    # Every digit (the shortest round-trip text): the CSV is for recomputing, the
    # markdown for reading (6 significant digits here made the two disagree).
    return "" if not math.isfinite(x) else repr(float(x))


def to_csv(groups: Sequence[GroupSummary]) -> str:
    """Long-format CSV: one line per group and metric.

    A group without metrics (every run an error row) has one line with an empty
    ``metric``, so that its runs and errors are there (it had none: only
    ``summary.md`` showed that the cell ran and crashed).
    """
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    # The order statistics after the interval: a reader of the columns by name, or of
    # the first 13, is unchanged (the median and range were only in the box plots).
    w.writerow(["kind", "map", "scenario", "planner", "controller", "runs", "errors",
                "metric", "n", "mean", "std", "ci95_low", "ci95_high", "median", "min",
                "max"])
    for g in groups:
        cell = [g.kind, g.target if g.kind == "plan" else "",
                g.target if g.kind == "episode" else "", g.planner, g.controller or "",
                g.runs, g.errors]  # fmt: skip
        if not g.stats:
            w.writerow([*cell, "", 0, "", "", "", "", "", "", ""])
        for name in sorted(g.stats):
            s = g.stats[name]
            w.writerow([*cell, name, s.n, _num(s.mean), _num(s.std), _num(s.ci_low),
                        _num(s.ci_high), _num(s.median), _num(s.min), _num(s.max)])  # fmt: skip
    return buf.getvalue()


def _cell(s: Stat | None, scale: float, fmt: str) -> str:
    if s is None or s.n == 0:
        return "–"
    if s.rate:
        return f"{fmt.format(s.mean)} [{fmt.format(s.ci_low)}, {fmt.format(s.ci_high)}]"
    mean = fmt.format(s.mean * scale)
    if s.n < 2:
        return mean
    # The median too: times are skewed (a few slow runs pull the mean up).
    return (
        f"{mean} ± {fmt.format(s.std * scale)} "
        f"[{fmt.format(s.ci_low * scale)}, {fmt.format(s.ci_high * scale)}], "
        f"median {fmt.format(s.median * scale)}"
    )


def to_markdown(groups: Sequence[GroupSummary], title: str = "Bench summary") -> str:
    """Markdown tables (planning-only and closed-loop): mean ± std [95 % CI], median."""
    lines = [f"# {title}", ""]
    lines.append(
        "Cells: mean ± std [95 % CI], median, over the runs with a value (bootstrap "
        "interval for non-negative quantities, Student's t for signed ones); rates with "
        "the Wilson 95 % interval. Lengths and curvatures only of successful runs."
    )
    for kind, heading in (("plan", "Planning only"), ("episode", "Closed loop")):
        gs = [g for g in groups if g.kind == kind]
        if not gs:
            continue
        cols = _MD_COLUMNS[kind]
        first = "map" if kind == "plan" else "scenario"
        lines += ["", f"## {heading}", ""]
        head = [first, "planner"] + (["controller"] if kind == "episode" else [])
        head += ["runs", "errors"] + [c[1] for c in cols]
        lines.append("| " + " | ".join(head) + " |")
        lines.append("|" + "---|" * len(head))
        for g in gs:
            cells = [g.target, g.planner] + ([g.controller or ""] if kind == "episode" else [])
            cells += [str(g.runs), str(g.errors)]
            cells += [_cell(g.stats.get(k), scale, fmt) for k, _, scale, fmt in cols]
            lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def write_summary(
    groups: Sequence[GroupSummary], out: str | FsPath, title: str = "Bench summary"
) -> list[FsPath]:
    """Write ``summary.csv`` and ``summary.md`` into ``out`` atomically; return their paths."""
    from rrtdrive.maps import write_text_atomic

    out = FsPath(out)
    paths = [out / "summary.csv", out / "summary.md"]
    write_text_atomic(paths[0], to_csv(groups))
    write_text_atomic(paths[1], to_markdown(groups, title))
    return paths


def _values(rows: Iterable[Mapping[str, Any]], key: str) -> list[float]:
    return [
        float(r[key]) for r in rows
        if isinstance(r.get(key), (int, float)) and not isinstance(r.get(key), bool)
        and math.isfinite(r[key]) and (key not in SUCCESS_ONLY or r.get("success"))
    ]


#: The figures :func:`write_plots` may write.
PLOT_FILES = ("box_length.png", "box_time.png", "success.png", "curvature_hist.png")


def remove_plots(out: str | FsPath, keep: Iterable[str | FsPath] = ()) -> None:
    """Remove :data:`PLOT_FILES` from ``out`` but those in ``keep`` (just written)."""
    kept = {FsPath(k).name for k in keep}
    for name in PLOT_FILES:
        if name not in kept:
            (FsPath(out) / name).unlink(missing_ok=True)


def _bench_title(rows: Sequence[Mapping[str, Any]]) -> str:
    """What a figure shows, from its rows: how many runs, which seeds, how they ran."""
    seeds = sorted({int(r["seed"]) for r in rows if isinstance(r.get("seed"), int)})
    span = "" if not seeds else (
        f", seed {seeds[0]}" if len(seeds) == 1 else f", seeds {seeds[0]}-{seeds[-1]}"
    )
    how = [w for w, key in (("reverse allowed", "reverse"), ("deterministic", "deterministic"))
           if any(r.get(key) for r in rows)]
    return f"rrtdrive bench: {len(rows)} runs{span}" + "".join(f", {w}" for w in how)


def _curvature_bins(top: float, kappa_max: float | None, count: int = 39) -> np.ndarray:
    """About ``count`` equal bins over ``[0, top]``, one edge on ``kappa_max``.

    A bin never straddles the limit, so a bar right of the dashed line holds only runs
    over it; the edge lies the evaluators' tolerance above ``kappa_max`` (a path exactly
    at the limit is within it, and numpy's bins are closed on the left).
    """
    if kappa_max is None:
        return np.linspace(0.0, top, count + 1)
    edge = kappa_max * (1.0 + EvalConfig().kappa_tol)
    width = edge / max(1, round(count * edge / top))
    return width * np.arange(math.ceil(top / width) + 1)


def write_plots(rows: Sequence[Mapping[str, Any]], out: str | FsPath) -> list[FsPath]:
    """Box plots of length and time, success bars and curvature histograms, as PNGs in ``out``.

    Parameters
    ----------
    rows : sequence of dict
        Result rows of the bench (error rows are skipped).
    out : str or path-like
        Folder.

    Returns
    -------
    list of pathlib.Path
        The files written.
    """
    import matplotlib

    matplotlib.use("Agg")
    # Names are free text: a map called "$x^$" is no formula (mathtext raised on it).
    with matplotlib.rc_context({"text.parse_math": False}):
        return _write_plots(rows, out)


def _write_plots(rows: Sequence[Mapping[str, Any]], out: str | FsPath) -> list[FsPath]:
    from matplotlib.figure import Figure
    from matplotlib.ticker import MaxNLocator

    from rrtdrive.plotting import save_figure

    out = FsPath(out)
    groups: dict[str, list[Mapping[str, Any]]] = {}
    for r in rows:
        if r.get("status") == "error":
            continue
        kind, target, planner, controller = _group_key(r)
        label = " / ".join([target, planner] + ([controller] if controller else []))
        groups.setdefault(label, []).append(r)
    if not groups:
        return []
    title = _bench_title(rows)
    labels = list(groups)
    height = max(3.0, 0.35 * len(labels) + 1.5)
    written: list[FsPath] = []

    def box(
        filename: str, keys: tuple[str, ...], xlabel: str, scale: float = 1.0,
        none: str = "no value",
    ) -> None:
        data, names = [], []
        for lab in labels:
            vals: list[float] = []
            for k in keys:
                vals += _values(groups[lab], k)
            if vals:
                data.append(np.asarray(vals) * scale)
                names.append(lab)
        # A group without a value (no successful run) keeps its row, marked, rather than
        # vanishing from the figure; with no value at all the figure says so (a grid
        # that solved nothing still gets every plot the docs list).
        missing = [lab for lab in labels if lab not in names]
        fig = Figure(figsize=(8, max(3.0, 0.35 * len(labels) + 1.5)), layout="constrained")
        ax = fig.add_subplot()
        if data:
            try:
                ax.boxplot(data, orientation="horizontal", showmeans=True)
            except TypeError:  # matplotlib < 3.10
                ax.boxplot(data, vert=False, showmeans=True)
            lo = min(float(np.min(d)) for d in data)
            hi = max(float(np.max(d)) for d in data)
            if lo > 0 and hi / lo > 100:
                ax.set_xscale("log")
            else:
                # Nearly equal values: matplotlib's offset text ("1e-5+3.39354e1") left the
                # ticks meaningless and overlapped the axis label (an audit).
                ax.ticklabel_format(axis="x", useOffset=False, style="plain")
        else:
            ax.text(0.5, 0.5, f"{none} in any group", transform=ax.transAxes, ha="center")
        rows_shown = names + [f"{lab} ({none})" for lab in missing]
        ax.set_yticks(range(1, len(rows_shown) + 1), rows_shown, fontsize=8)
        ax.set_ylim(len(rows_shown) + 0.5, 0.5)  # top to bottom, the empty rows last
        ax.set_xlabel(xlabel)
        ax.grid(axis="x", alpha=0.3)
        from matplotlib.lines import Line2D

        fig.suptitle(title, fontsize=9)
        ax.legend(
            [Line2D([], [], color="tab:orange"),
             Line2D([], [], marker="^", color="tab:green", linestyle="none")],
            ["median", "mean"], fontsize=8, loc="best",
        )
        save_figure(fig, out / filename)
        written.append(out / filename)

    box("box_length.png", ("length_m", "path_length_m"), "path length [m] (successful runs)",
        none="no success")
    box("box_time.png", ("planning_time_s",), "planning time [ms]", 1e3)

    # Success rates with Wilson intervals; for plans also the share the independent
    # verifier passed (rrt's paths "succeed" but break the curvature limit: the plot
    # showed 100 % where the summary's table said 0 % verified; an audit).
    fig = Figure(figsize=(8, height), layout="constrained")
    ax = fig.add_subplot()
    y = np.arange(len(labels))
    rates_of = [("success", "success", "tab:green")]
    if any("verified" in r for lab in labels for r in groups[lab]):
        rates_of.append(("verified", "verified (no sharpness bound)", "tab:blue"))
    bar = 0.8 / len(rates_of)
    # The table's numbers (a failed plan's null read as "not verified" drew 33 % beside
    # the table's 100 %; an audit).
    keys = [key for key, _, _ in rates_of]
    stats_of = {lab: metric_stats(groups[lab], keys) for lab in labels}
    for i, (key, name, colour) in enumerate(rates_of):
        rates, lo, hi = [], [], []
        for lab in labels:
            s = stats_of[lab].get(key)
            if s is None:  # no run of the group has the value
                rates.append(0.0)
                lo.append(0.0)
                hi.append(0.0)
                continue
            rates.append(s.mean)
            lo.append(max(0.0, s.mean - s.ci_low))
            hi.append(max(0.0, s.ci_high - s.mean))
        offset = (i - (len(rates_of) - 1) / 2) * bar
        ax.barh(y + offset, rates, height=bar, xerr=[lo, hi], capsize=3, color=colour,
                alpha=0.8, label=name)  # fmt: skip
    ax.set_yticks(y, labels, fontsize=8)
    ax.invert_yaxis()
    ax.set_xlim(0, 1.05)
    ax.set_xlabel("share of runs (95 % Wilson interval)")
    if len(rates_of) > 1:
        ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    fig.suptitle(title, fontsize=9)
    save_figure(fig, out / "success.png")
    written.append(out / "success.png")

    # Curvature: histograms of each run's largest path curvature, one panel per planner,
    # over successful runs as the summary's curvature (a failed run's path counted too).
    # Maps of other cars (a map file's vehicle): each run over its own car's limit, the
    # line at 1 (one car's line coloured the others' runs as over it; an audit).
    limits = {r.get("kappa_max") for r in rows if r.get("kappa_max")}
    relative = len(limits) > 1
    by_planner: dict[str, list[float]] = {}
    for r in rows:
        if r.get("status") == "error" or not r.get("success"):
            continue
        kappas = _values([r], "max_curvature") + _values([r], "path_max_curvature")
        if relative:
            kappas = [k / float(r["kappa_max"]) for k in kappas if r.get("kappa_max")]
        by_planner.setdefault(str(r.get("planner")), []).extend(kappas)
    by_planner = {k: v for k, v in by_planner.items() if v}
    kmax = 1.0 if relative else next(iter(limits), None)
    if by_planner:
        n = len(by_planner)
        ncols = min(3, n)
        nrows = math.ceil(n / ncols)
        fig = Figure(figsize=(3.4 * ncols, 2.6 * nrows + 0.6), layout="constrained")
        axes = fig.subplots(nrows, ncols, squeeze=False, sharex=True)
        everything = np.concatenate([np.asarray(v) for v in by_planner.values()])
        top = max(float(everything.max()), float(kmax or 0.0)) * 1.05 or 1.0
        bins = _curvature_bins(top, float(kmax) if kmax else None)
        for ax, (planner, kappas) in zip(axes.flat, by_planner.items(), strict=False):
            _, _, bars = ax.hist(kappas, bins=bins, color="tab:blue", alpha=0.75)
            if kmax:
                ax.axvline(float(kmax), color="k", linestyle="--", linewidth=1)
                for bar, left in zip(bars, bins[:-1], strict=True):
                    if left >= kmax:  # the bins right of the line hold runs over it
                        bar.set_facecolor("tab:red")
            ax.set_title(planner, fontsize=9)
            ax.yaxis.set_major_locator(MaxNLocator(integer=True))  # counts: no 0.5 runs
        for ax in list(axes.flat)[n:]:
            ax.set_visible(False)
        fig.supxlabel(
            # Two lines: one planner's panel is 3.4 inches wide (the label was cut off).
            "largest path curvature of a successful run\nover its car's κ_max (dashed: 1)"
            if relative else
            "largest path curvature of a successful run [1/m]\n(dashed: κ_max)"
        )  # fmt: skip
        fig.supylabel("runs")
        fig.suptitle(title, fontsize=9)
        save_figure(fig, out / "curvature_hist.png")
        written.append(out / "curvature_hist.png")
    return written
