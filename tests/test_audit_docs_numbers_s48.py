"""Audit (session 48): the numbers in README.md and docs/ against the files and commands
that made them.

Project rule: no number in a doc that no command produced; every result page with the
command that made it; a benchmark reports what it measured, with the command. These tests
parse the pages and the committed results files and check that they agree, so that a page
that is not re-generated with its results (or a results file replaced under a page) fails.
"""

from __future__ import annotations

import json
import math
import re
import statistics
import subprocess
import sys
from collections import defaultdict
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
RESULTS = ROOT / "results"
EXPERIMENTS = ROOT / "experiments"
README = ROOT / "README.md"

pytestmark = pytest.mark.skipif(
    not (DOCS.is_dir() and RESULTS.is_dir() and README.is_file()),
    reason="needs the repository's docs/, results/ and README.md",
)

PAGES = [README, *sorted(DOCS.glob("*.md"))]


def _read(path: Path) -> str:
    return path.read_text(encoding="utf-8")


def _json(path: Path):
    # Older results files hold NaN (json's default reader takes it).
    return json.loads(path.read_text(encoding="utf-8"))


def _block(text: str, begin: str, end: str) -> str:
    start = text.index(begin) + len(begin)
    return text[start : text.index(end, start)].strip("\n")


def _rounds_to(value: float, shown: str) -> bool:
    """Whether ``shown`` (decimal text) is ``value`` rounded to its decimals (a half either way)."""
    decimals = len(shown.split(".")[1]) if "." in shown else 0
    return abs(value - float(shown)) <= 0.5 * 10**-decimals + 1e-9


# --------------------------------------------------------------------------------------
# (a) commands: every script and flag a page quotes exists


def _script_flags(script: Path, seen: set[str] | None = None) -> set[str]:
    """The flags a script's parser defines: its own and its sibling modules' (shared options)."""
    seen = set() if seen is None else seen
    seen.add(script.stem)
    src = script.read_text(encoding="utf-8")
    flags = set(re.findall(r"[\"'](--[a-z][a-z0-9-]*)[\"']", src))
    for mod in re.findall(r"^\s*(?:from (\w+) import|import (\w+))", src, re.M):
        name = mod[0] or mod[1]
        if name not in seen and (EXPERIMENTS / f"{name}.py").is_file():
            flags |= _script_flags(EXPERIMENTS / f"{name}.py", seen)
    return flags


def _quoted_experiment_commands():
    """(page, line, script, flags) for every ``experiments/X.py --flag ...`` quoted in a page."""
    out = []
    for page in PAGES:
        lines = _read(page).split("\n")
        for i, line in enumerate(lines):
            for m in re.finditer(r"experiments/([a-z_0-9]+\.py)", line):
                # The command runs on while lines end in a backslash or stay inside `...`.
                rest = line[m.end() :]
                j = i
                while (
                    (
                        rest.rstrip().endswith("\\")
                        or rest.count("`") % 2 == 0
                        and line[: m.start()].count("`") % 2 == 1
                        and "`" not in rest
                    )
                    and j + 1 < len(lines)
                    and j < i + 4
                ):
                    j += 1
                    rest = rest.rstrip("\\ ") + " " + lines[j]
                rest = re.split(r"`|\bpython |\brrtdrive |experiments/", rest)[0]
                flags = re.findall(r"(?<![\w-])(--[a-z][a-z0-9-]*)", rest)
                out.append((page.name, i + 1, m.group(1), flags))
    return out


def test_every_quoted_experiment_script_exists_and_takes_its_flags():
    commands = _quoted_experiment_commands()
    assert len(commands) > 100  # the parser finds the pages' commands
    bad = []
    for page, line, script, flags in commands:
        path = EXPERIMENTS / script
        if not path.is_file():
            bad.append(f"{page}:{line}: {script} does not exist")
            continue
        known = _script_flags(path)
        bad += [f"{page}:{line}: {script} has no {f}" for f in flags if f not in known]
    assert not bad, "\n".join(bad)


def _cli_help(sub: str) -> str:
    proc = subprocess.run(
        [sys.executable, "-m", "rrtdrive", sub, "--help"],
        capture_output=True,
        text=True,
        check=True,
        cwd=ROOT,
        timeout=120,
    )
    return proc.stdout


def test_every_quoted_rrtdrive_flag_exists():
    helps = {sub: _cli_help(sub) for sub in ("plan", "simulate", "bench", "verify", "maps")}
    bad, seen = [], 0
    for page in PAGES:
        for i, line in enumerate(_read(page).split("\n")):
            for m in re.finditer(r"rrtdrive (plan|simulate|bench|verify|maps)\b([^`#|;&]*)", line):
                sub, rest = m.groups()
                for flag in re.findall(
                    r"(?<![\w-])(--(?:\[no-\])?[a-z][a-z0-9-]*)", rest.split(" rrtdrive ")[0]
                ):
                    seen += 1
                    flag = flag.replace("[no-]", "")
                    if not re.search(re.escape(flag) + r"(?![a-z0-9-])", helps[sub]):
                        bad.append(f"{page.name}:{i + 1}: rrtdrive {sub} has no {flag}")
    assert seen > 100
    assert not bad, "\n".join(bad)


# --------------------------------------------------------------------------------------
# (b) every results path a page cites exists


def test_every_cited_results_path_exists():
    bad, seen = [], 0
    for page in PAGES:
        for i, line in enumerate(_read(page).split("\n")):
            for m in re.finditer(r"results/[A-Za-z0-9_./-]+", line):
                path = m.group(0).rstrip(".,)")
                before = line[: m.start()]
                if re.search(r"(--out|out =|--out=)\s*[\"']?$", before):
                    continue  # a usage example's output folder
                if re.search(r"TAG|_S\b|seedS|_$", path) or path.endswith("_"):
                    continue  # a template named in the text
                seen += 1
                target = ROOT / path
                if target.exists() or list(target.parent.glob(target.name + "*")):
                    continue
                bad.append(f"{page.name}:{i + 1}: {path}")
    assert seen > 300
    assert not bad, "\n".join(bad)


# --------------------------------------------------------------------------------------
# (c) generated blocks equal the results files they were written with


def _unlink_figures(text: str) -> str:
    return text.replace("](../docs/figures/", "](figures/")


def test_table3_page_is_its_results_file():
    page = _read(DOCS / "table3.md")
    results = _unlink_figures(_read(RESULTS / "table3.md"))
    assert page.strip() == results.strip()
    record = _json(RESULTS / "table3.json")
    assert f"Command: `{record['command']}`" in page


def test_ablation_page_is_its_results_file():
    page = _read(DOCS / "ablation.md")
    assert page.strip() == _read(RESULTS / "ablation.md").strip()
    assert f"Command: `{_json(RESULTS / 'ablation.json')['command']}`" in page


def test_bench_planners_page_is_its_results_file():
    page = _read(DOCS / "bench_planners.md")
    assert page.strip() == _read(RESULTS / "bench_planners_parking_lot.md").strip()
    assert f"Command: `{_json(RESULTS / 'bench_planners_parking_lot.json')['command']}`" in page


def test_cli_startup_block_is_its_results_file():
    page = _read(DOCS / "cli_startup.md")
    block = _block(page, "<!-- bench_cli_startup: begin -->", "<!-- bench_cli_startup: end -->")
    assert block.strip() == _read(RESULTS / "bench_cli_startup.md").strip()


@pytest.mark.parametrize(
    "page, result",
    [
        ("coverage.md", "coverage_parking_lot"),
        ("coverage_tight.md", "coverage_tight"),
    ],
)
def test_coverage_blocks_are_their_results_files(page, result):
    text = _read(DOCS / page)
    block = _block(
        text,
        "<!-- BEGIN generated by experiments/coverage.py -->",
        "<!-- END generated by experiments/coverage.py -->",
    )
    assert block.strip() == _read(RESULTS / f"{result}.md").strip()
    assert f"Command: `{_json(RESULTS / f'{result}.json')['command']}`" in block


def test_video_block_is_its_results_file():
    block = _block(
        _read(DOCS / "video.md"), "<!-- bench_video:begin -->", "<!-- bench_video:end -->"
    )
    results = _read(RESULTS / "docs_s24" / "bench_video.md").split("\n", 1)[1]  # without its title
    assert block.strip() == results.strip()


# --------------------------------------------------------------------------------------
# (c) numbers the pages derive, recomputed from the records


def test_table3_ratios_recomputed_from_the_runs():
    record = _json(RESULTS / "table3.json")
    page = _read(DOCS / "table3.md")
    for name, m in record["maps"].items():
        summary = m["summary"]
        ours = summary["improved-rrt-connect"]["length_m"]["mean"]
        for base in ("rrt", "rrt-connect", "rrt-star"):
            raw = ours / summary[base]["length_m"]["mean"]
            pruned = ours / summary[base]["pruned_length_m"]["mean"]
            assert raw == pytest.approx(m["length_ratios"][base]["raw"], rel=1e-12)
            assert pruned == pytest.approx(m["length_ratios"][base]["pruned"], rel=1e-12)
        section = page.split(f"## `{name}`")[1].split("\n## ")[0]
        line = next(x for x in section.split("\n") if x.startswith("Improved mean length"))
        shown = re.findall(r"(RRT\*?|RRT-Connect) (\d\.\d{3}) / (\d\.\d{3})", line)
        labels = {"RRT": "rrt", "RRT-Connect": "rrt-connect", "RRT*": "rrt-star"}
        assert len(shown) == 3
        for label, raw, pruned in shown:
            ratio = m["length_ratios"][labels[label]]
            assert _rounds_to(ratio["raw"], raw) and _rounds_to(ratio["pruned"], pruned), line
        # median time column: the median of the runs' times
        for planner, runs in m["runs"].items():
            times = [r["time_s"] for r in runs if r["success"]]
            assert statistics.median(times) == pytest.approx(summary[planner]["median_time_s"])


def test_planning_table3_against_the_paper_is_table3():
    """docs/planning.md's "ours" column: the paper's variant (B-spline) over the baselines."""
    record = _json(RESULTS / "table3.json")["maps"]["parking_lot"]
    text = _read(DOCS / "planning.md").split("## Table 3 against the paper")[1].split("\n## ")[0]
    rows = dict(re.findall(r"^\| (improved [^|]+?) \| [^|]+ \| ([^|]+?) \|$", text, re.M))
    ratios = record["length_ratios"]
    assert _rounds_to(ratios["rrt"]["raw"], rows["improved length / RRT length (raw)"])
    assert _rounds_to(
        ratios["rrt-connect"]["raw"], rows["improved length / RRT-Connect length (raw)"]
    )
    assert _rounds_to(ratios["rrt-star"]["raw"], rows["improved length / RRT* length"])
    nodes = (
        record["summary"]["improved-rrt-connect"]["nodes"]["mean"]
        / record["summary"]["rrt-connect"]["nodes"]["mean"]
    )
    assert _rounds_to(nodes, rows["improved nodes / RRT-Connect nodes"])
    raw_rrtc = record["summary"]["rrt-connect"]["length_m"]["mean"]
    assert f"RRT-Connect's raw path is {round(raw_rrtc)} m" in text


def test_planning_ablation_prose_is_the_ablation_record():
    record = _json(RESULTS / "ablation.json")["components"]
    text = _read(DOCS / "planning.md").split("## Ablation")[1].split("\n## ")[0]
    lot, gap = record["parking_lot"], record["narrow_gap"]

    def ms(cfg):
        return f"{cfg['median_time_s'] * 1000:.2f}"

    on, noprune = lot["all on"], lot["no prune"]
    assert f"{noprune['median_time_s'] / on['median_time_s']:.2f} × slower" in text
    assert f"({ms(noprune)} ms against\n{ms(on)} ms)" in text
    assert f"({noprune['mean_length_m']:.2f} m against {on['mean_length_m']:.2f} m)" in text
    for name in ("no obtuse_parent", "no passage_sampling"):
        assert f"{ms(lot[name])} ms / {lot[name]['mean_length_m']:.2f} m" in text, name
    nps, allon = gap["no passage_sampling"], gap["all on"]
    assert f"{nps['mean_nodes']:.1f} nodes instead of {allon['mean_nodes']:.1f}" in text
    assert f"{ms(nps)} ms\ninstead of {ms(allon)} ms" in text


def test_bench_planners_ratios_and_medians_recomputed():
    record = _json(RESULTS / "bench_planners_parking_lot.json")
    ours = record["summary"]["improved-rrt-connect"]
    for planner, s in record["summary"].items():
        runs = record["runs"][planner]
        assert s["median_time_s"] == pytest.approx(statistics.median(r["time_s"] for r in runs))
        assert s["success_rate"] == sum(r["success"] for r in runs) / len(runs)
        assert s["time_ratio_ours_over_this"] == pytest.approx(
            ours["median_time_s"] / s["median_time_s"]
        )
    # docs/planning.md "Speed" quotes this page
    speed = _read(DOCS / "planning.md").split("## Speed")[1]
    simp = record["summary"]["ompl-r2-rrtconnect+simplify"]
    bit = record["summary"]["ompl-dubins-bitstar-first"]
    assert f"its median is\n{ours['median_time_s'] * 1000:.2f} ms" in speed
    assert f"ratio\n  {simp['time_ratio_ours_over_this']:.3f}" in speed
    assert f"ratio {bit['time_ratio_ours_over_this']:.3f}" in speed
    assert f"{bit['length_ratio_ours_over_this']:.3f} × as long" in speed


def test_cli_startup_prose_is_the_two_runs():
    page = _read(DOCS / "cli_startup.md")
    now = _read(RESULTS / "bench_cli_startup.md")
    old = _read(RESULTS / "bench_cli_startup_s28" / "bench_cli_startup.md")

    def row(text):
        line = next(x for x in text.split("\n") if x.startswith("| `rrtdrive bench --help`"))
        cells = [c.strip() for c in line.strip("|").split("|")]
        return cells[1], cells[3]

    (old_med, old_x), (new_med, new_x) = row(old), row(now)
    assert f"median {old_med} → {new_med} s, × `import\nnumpy` {old_x} → {new_x}" in page


# coverage_all.md: the targets tables of each session, recomputed from the run's rows


def _pair(rows, ours, ompl, vary):
    by = defaultdict(dict)
    for r in rows:
        if r["vary"] == vary:
            by[r["planner"]][r["index"]] = r
    a, b = by[ours], by[ompl]
    both = [i for i in a if a[i]["solved"] and b.get(i, {}).get("solved")]
    return {
        "both": len(both),
        "ompl": sum(1 for r in b.values() if r["solved"]),
        "only": sum(1 for i in a if a[i]["solved"] and not b.get(i, {}).get("solved")),
        "time": statistics.median(a[i]["time_s"] for i in both)
        / statistics.median(b[i]["time_s"] for i in both),
        "length": statistics.median(a[i]["length_m"] for i in both)
        / statistics.median(b[i]["length_m"] for i in both),
        "failed_ms": [a[i]["time_s"] * 1000 for i in a if not a[i]["solved"]],
    }


def _target_sections():
    text = _read(DOCS / "coverage_all.md")
    out = []
    for section in re.split(r"\n(?=## )", text):
        m = re.search(r"`(results/coverage_100_s[0-9a-z_]+)`", section[:400])
        if (
            m
            and "| target" in section
            and (ROOT / m.group(1) / "coverage_parking_lot.json").is_file()
        ):
            out.append(pytest.param(section, m.group(1), id=m.group(1).split("/")[1]))
    return out


SECTIONS = _target_sections()


def test_coverage_all_has_target_sections():
    assert len(SECTIONS) >= 10


@pytest.mark.parametrize("section, folder", SECTIONS)
def test_coverage_all_targets_table_is_its_run(section, folder):
    rows = _json(ROOT / folder / "coverage_parking_lot.json")["rows"]
    lines = {
        line.split("|")[1].strip().split(" ")[0]: line
        for line in section.split("\n")
        if line.startswith("| ")
    }
    fg, fs = (_pair(rows, "improved-rrt-connect", "ompl-dubins-rrt", v) for v in ("goal", "start"))
    assert f"{fg['both']} of {fg['ompl']}; {fs['both']} of {fs['ompl']}" in lines["forward"]
    assert f"plus {fg['only']} goals OMPL does not solve" in lines["forward"]
    rev = {
        p: [_pair(rows, p, "ompl-rs-rrtconnect", v) for v in ("goal", "start")]
        for p in ("improved-rrt-connect+reverse", "hybrid-a-star+reverse")
    }
    d, h = rev["improved-rrt-connect+reverse"], rev["hybrid-a-star+reverse"]
    assert (
        f"default {d[0]['time']:.3f}; {d[1]['time']:.3f}, `hybrid-a-star` "
        f"{h[0]['time']:.3f}; {h[1]['time']:.3f}"
    ) in lines["time"]
    shown = re.findall(r"\d\.\d{3}", lines["length"].replace("*", ""))[:4]
    assert shown == [f"{x['length']:.3f}" for x in (d[0], d[1], h[0], h[1])]
    failing = lines["failing"]
    if "planning alone: default forward" in failing:
        nums = re.findall(r"\d+(?:\.\d+)?", failing.split("planning alone: default forward")[1])[:4]
        fails = [
            _pair(rows, p, "ompl-rs-rrtconnect", v)["failed_ms"]
            for p in ("improved-rrt-connect", "hybrid-a-star")
            for v in ("goal", "start")
        ]
        for shown_ms, times in zip(nums, fails, strict=True):
            # the page may round the results table's 0.1 ms figure again
            value = statistics.median(times)
            assert _rounds_to(value, shown_ms) or _rounds_to(round(value, 1), shown_ms), (
                shown_ms,
                value,
            )


def test_coverage_all_session39_failing_median_rounds_once():
    section = next(p.values[0] for p in SECTIONS if p.values[1].endswith("coverage_100_s39"))
    rows = _json(ROOT / "results/coverage_100_s39/coverage_parking_lot.json")["rows"]
    value = statistics.median(
        _pair(rows, "improved-rrt-connect", "ompl-rs-rrtconnect", "goal")["failed_ms"]
    )
    shown = re.search(r"planning alone: default forward (\d+(?:\.\d+)?);", section).group(1)
    assert _rounds_to(value, shown), (shown, value)


def test_coverage_page_counts_its_failures():
    record = _json(RESULTS / "coverage_parking_lot.json")
    failed = sum(
        1 for r in record["rows"] if r["planner"] == "improved-rrt-connect" and not r["solved"]
    )
    text = _read(DOCS / "coverage.md")
    assert f"run afterwards on the {failed}\n  queries `improved-rrt-connect` failed" in text
    parts = re.search(
        r"(\d+) say `needs_reverse`.*?(\d+) say `tight_clearance`.*?(\d+) have no finding",
        text,
        re.S,
    )
    assert parts and sum(map(int, parts.groups())) == failed


def _tight_rows():
    rows = {}
    block = _read(RESULTS / "coverage_tight.md")
    for line in block.split("\n"):
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) >= 11 and cells[2][:1].isdigit() and "/" in cells[2]:
            rows[(cells[0], cells[1])] = cells
    return rows


def test_coverage_tight_facts_quoted_in_coverage_md_that_hold():
    rows = _tight_rows()
    text = _read(DOCS / "coverage.md").split("## Tight maps")[1]
    assert f"wall time {_json(RESULTS / 'coverage_tight.json')['wall_time_s'] / 60:.1f} min" in text
    assert (
        rows[("dead_end", "improved-rrt-connect+reverse")][8] == "4"
    )  # "a multi-point turn, 4 cusps"
    assert rows[("kerbside", "hybrid-a-star")][11] == "proven_unreachable 3"
    assert rows[("kerbside", "hybrid-a-star")][12] == "boxed_in"
    assert rows[("reverse_bay", "hybrid-a-star")][12] == "needs_reverse"
    assert rows[("dead_end", "ompl-rs-rrtconnect")][2] == "3/3"
    assert rows[("dead_end", "ompl-rs-rrtconnect")][5] == "0"  # none collision-free


def test_coverage_md_tight_times_are_the_generated_page():
    rows = _tight_rows()
    text = _read(DOCS / "coverage.md").split("## Tight maps")[1]

    def med(query, planner):
        return float(rows[(query, planner)][6])

    bays = [q for (q, _p) in rows if q.startswith("garage bay")]
    queries = sorted({q for (q, _p) in rows})
    default_solved = [med(q, "improved-rrt-connect+reverse") for q in queries] + [
        med(q, "improved-rrt-connect") for q in bays
    ]
    hybrid_solved = [med(q, "hybrid-a-star+reverse") for q in queries] + [
        med(q, "hybrid-a-star") for q in bays
    ]
    hybrid_bays = [med(q, p) for q in bays for p in ("hybrid-a-star", "hybrid-a-star+reverse")]
    expected = [
        f"median of {min(default_solved):.1f}-{max(default_solved):.1f} ms per query",
        f"(the bulb\nforward {med('turning_bulb', 'improved-rrt-connect'):.1f} ms)",
        f"in {min(hybrid_solved):.1f}-{max(hybrid_solved):.1f} ms",
        f"(the bulb forward {med('turning_bulb', 'hybrid-a-star'):.1f} ms;",
        f"the garage bays {min(hybrid_bays):.1f}-{max(hybrid_bays):.1f} ms",
        f"the reverse bay\n{med('reverse_bay', 'hybrid-a-star+reverse'):.1f} ms",
        "the dead end takes the default "
        f"{med('dead_end', 'improved-rrt-connect+reverse'):.1f} ms and "
        f"`hybrid-a-star` {med('dead_end', 'hybrid-a-star+reverse'):.1f} ms",
        f"solved in a median {med('dead_end', 'ompl-rs-rrtconnect'):.1f} ms",
    ]
    missing = [e for e in expected if e not in text]
    assert not missing, missing


def test_bench_scaling_table_is_its_results_file():
    text = _read(DOCS / "bench.md").split("## Throughput")[1]
    results = _read(RESULTS / "bench_scaling.md")
    for grid in ("closed-loop", "planning"):
        line = next(x for x in results.split("\n") if x.startswith(f"| {grid} |"))
        nums = [c.strip() for c in line.strip("|").split("|")[1:]]
        doc_line = next(x for x in text.split("\n") if x.startswith(f"| {grid}:"))
        assert [c.strip() for c in doc_line.strip("|").split("|")[1:]] == nums
    for folder, ratio in (("bench_scaling_s29", "1.78"), ("bench_scaling_s30", "1.94")):
        assert f"**{ratio}**" in _read(RESULTS / folder / "bench_scaling.md")
        assert f"ratio **{ratio}**" in text


def test_bench_baseline_steer_rate_table_is_its_runs():
    text = _read(DOCS / "bench.md")
    means = {}
    for tag in ("none", "0.4"):
        groups = defaultdict(list)
        for r in _json(RESULTS / "baseline_steer_rate_s30" / f"steer_rate_{tag}.json")["reports"]:
            groups[(r["scenario"], r["controller"])].append(r["duration_s"])
        means[tag] = {k: statistics.mean(v) for k, v in groups.items()}
    for (scenario, controller), instant in means["none"].items():
        line = next(x for x in text.split("\n") if x.startswith(f"| {scenario}, {controller} |"))
        shown = re.findall(r"(\d+\.\d) s", line)
        assert _rounds_to(instant, shown[0]) and _rounds_to(
            means["0.4"][(scenario, controller)], shown[1]
        ), line


def test_closed_loop_session37_is_its_run():
    reports = _json(RESULTS / "closed_loop_stock100_reverse_s37.json")["reports"]
    before = _json(RESULTS / "docs_s24" / "closed_loop_stock100_reverse_s24.json")["reports"]
    text = _read(DOCS / "closed_loop.md").split("## Session 37")[1].split("\n## ")[0]
    order = ("pure-pursuit", "stanley", "lqr")

    def means(reps):
        return " / ".join(
            f"{statistics.mean(r['duration_s'] for r in reps if r['controller'] == c):.2f}"
            for c in order
        )

    assert f"time mean {means(reports)} s" in text
    assert f"{means(before)} before" in text
    goal = " / ".join(
        f"{max(r['goal_position_err_m'] for r in reports if r['controller'] == c):.3f}"
        for c in order
    )
    assert f"goal error max {goal} m" in text
    assert all(r["success"] and r["highway_env_success"] and not r["collision"] for r in reports)
    assert sum(r["nuplan_comfortable"] for r in reports) == 300


def test_gym_training_table_is_its_record():
    record = _json(RESULTS / "train_agent" / "train_agent.json")
    text = _read(DOCS / "gym.md").split("### Results (parking, pure pursuit")[1].split("\n### ")[0]
    fields = {
        "cross-track RMS, mean (m)": ("cte_rms_m", 4),
        "cross-track max, mean (m)": ("cte_max_m", 4),
        "heading RMS, mean (rad)": ("heading_err_rms_rad", 4),
        "goal position error, mean (m)": ("goal_position_err_m", 3),
        "goal heading error, mean (rad)": ("goal_heading_err_rad", 4),
        "duration, mean (s)": ("duration_s", 2),
        "max lateral accel, mean (m/s²)": ("max_lateral_accel", 3),
        "max jerk, mean (m/s³)": ("max_jerk", 2),
        "max steering rate, mean (rad/s)": ("max_steering_rate", 3),
    }
    for label, (key, digits) in fields.items():
        plain = statistics.mean(r[key] for r in record["plain_reports"])
        agent = statistics.mean(r[key] for r in record["agent_reports"])
        assert f"| {label} | {plain:.{digits}f} | {agent:.{digits}f} |" in text, label
    ret = (
        f"| mean return (env reward) | {statistics.mean(record['plain_returns']):.2f} | "
        f"{statistics.mean(record['agent_returns']):.2f} |"
    )
    assert ret in text
    assert (
        f"training {record['train_wall_s']:.0f} s wall time "
        f"({record['train_episodes']} training episodes)" in text.replace("\n", " ")
    )


def test_gym_bench_rates_are_the_two_runs():
    text = _read(DOCS / "gym.md").split("## Vector environments")[1].split("\n## ")[0]
    s24 = _read(RESULTS / "docs_s24" / "bench_gym" / "bench_gym.md")
    rows = re.findall(r"^\| `rrtdrive/(\w+)-v0` \| ([\d.]+) \| (\d+) \| (\d+) \|", s24, re.M)
    (_, r1, s1, f1), (_, r2, s2, f2) = rows
    assert f"{int(s1):,} and {int(s2):,} steps per second, {f1} and {f2} with" in text
    assert f"resets {r1} s and {r2} s" in text


# --------------------------------------------------------------------------------------
# (c) the JSON the CLI writes against the field lists of the docs


def _run(*args, timeout=240):
    proc = subprocess.run(
        [sys.executable, "-m", "rrtdrive", *args],
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=timeout,
        check=False,
    )
    return proc


def test_readme_plan_json_example_is_what_plan_writes():
    proc = _run("plan", "parking_lot", "--json", "-")
    assert proc.returncode == 0, proc.stderr
    doc = json.loads(proc.stdout)
    readme = _read(README)
    example = readme.split("`--json -` prints")[1].split("```json")[1].split("```")[0]
    keys = re.findall(r'"([a-z_0-9]+)":', example)
    nested = set(doc["vehicle"])  # the car's own fields, inside "vehicle"
    assert [k for k in keys if k not in nested] == list(doc)  # the same fields, in order
    assert json.loads(re.search(r'"vehicle": (\{[^}]*\})', example).group(1)) == doc["vehicle"]
    for key in (
        "nodes",
        "iterations",
        "length_m",
        "max_curvature",
        "max_sharpness",
        "steer_rate_speed_limit",
        "body_clearance_m",
        "message",
        "max_iterations",
        "resolution_m",
    ):
        assert f'"{key}": {json.dumps(doc[key])}' in example, key


def test_metrics_md_documents_every_simulate_json_field():
    metrics = _read(DOCS / "metrics.md")
    always = re.findall(r"^\| `([a-z_0-9]+)` \| always \|", metrics, re.M)
    assert re.search(r"the\s+first\s+fourteen\s+are\s+in\s+every\s+run's\s+JSON", metrics)
    assert len(always) == 14
    proc = _run("simulate", "overtake", "--max-time", "3", "--json", "-")
    doc = json.loads(proc.stdout)
    stock = json.loads(_run("simulate", "parking-v0", "--max-time", "1", "--json", "-").stdout)
    undocumented = sorted(
        k for k in set(doc) | set(stock) if not re.search(r"`" + re.escape(k) + r"\b", metrics)
    )
    assert not undocumented
    assert set(always) <= set(doc)
    stock_fields = re.findall(r"^\| `([a-z_0-9]+)` \| a stock env \|", metrics, re.M)
    assert stock_fields and set(stock_fields) <= set(stock)


def test_bench_md_names_every_row_field(tmp_path):
    proc = _run(
        "bench",
        "--maps",
        "overtake",
        "--planners",
        "rrt-connect",
        "--seeds",
        "1",
        "--workers",
        "1",
        "--no-ray",
        "--quiet",
        "--no-plots",
        "--out",
        str(tmp_path / "b"),
    )
    assert proc.returncode == 0, proc.stderr
    row = json.loads((tmp_path / "b" / "runs.jsonl").read_text().splitlines()[0])
    rows_text = _read(DOCS / "bench.md").split("**Rows.**")[1].split("**Groups")[0]
    assert not [k for k in row if f"`{k}`" not in rows_text]
    page = _read(DOCS / "bench.md")
    written = {p.name for p in (tmp_path / "b").iterdir()}
    assert not [f for f in written if f"`{f}`" not in page and f"`OUT/{f}`" not in page]


# --------------------------------------------------------------------------------------
# docs/architecture.md against the files in src/


def _modules():
    mods = [p for p in (ROOT / "src" / "rrtdrive").rglob("*.py")]
    mods += [p for d in ("controllers", "envs") for p in (ROOT / d).glob("*.py")]
    return sorted(p for p in mods if not p.name.startswith("__"))


def test_architecture_names_no_missing_package_folder():
    text = _read(DOCS / "architecture.md")
    for folder in re.findall(r"`((?:planning|sim|collision|evaluation)/[a-z_/]+?)/?`", text):
        path = ROOT / "src" / "rrtdrive" / folder
        assert (
            path.is_dir()
            or path.with_suffix(".py").is_file()
            or path.parent.joinpath(Path(folder).name + ".py").is_file()
        ), folder


def test_architecture_names_every_module():
    text = _read(DOCS / "architecture.md")
    missing = [
        str(p.relative_to(ROOT))
        for p in _modules()
        if not re.search(r"`[^`]*\b" + re.escape(p.stem) + r"\b[^`]*`", text)
    ]
    row = next(line for line in text.split("\n") if "`sim/tasks/` (" in line)
    listed = set(re.findall(r"`([a-z_]+)`", row.split("`sim/tasks/`")[1]))
    files = {
        p.stem
        for p in (ROOT / "src" / "rrtdrive" / "sim" / "tasks").glob("*.py")
        if p.stem != "__init__"
    }
    assert not missing and files <= listed, (missing, sorted(files - listed))


# --------------------------------------------------------------------------------------
# (d) README numbers that a reader must be able to reproduce


def test_readme_seed_stream_example_reproduces():
    # README's example of simulate planning from another stream than plan --seed: a
    # shipped map, and both lengths what the two commands give today.
    from rrtdrive.maps import BUILTIN_MAPS

    text = _read(README)
    sentence = re.search(
        r"`simulate (\w+)` drives a (\d+\.\d\d) m path, `plan (\w+)` makes a\s+(\d+\.\d\d) m one",
        text,
    )
    assert sentence is not None
    name, simulated, planned_on, planned = sentence.groups()
    assert name == planned_on and name in BUILTIN_MAPS
    plan = json.loads(_run("plan", name, "--json", "-").stdout)
    assert f"{plan['length_m']:.2f}" == planned
    # The drive's length is its plan's; a 1 s drive is enough to read it.
    drive = json.loads(_run("simulate", name, "--max-time", "1", "--json", "-").stdout)
    assert f"{drive['path_length_m']:.2f}" == simulated


def test_readme_measured_examples_reproduce():
    # deterministic examples quoted in README.md (counts and lengths, not times)
    text = _read(README)
    home = _run("plan", "docs/maps/home_garage.json")
    assert home.returncode == 1
    why = next(
        line for line in home.stdout.splitlines() + home.stderr.splitlines() if "why:" in line
    )
    found = re.search(
        r"finds one of ([\d.]+) m with (\d+) gear change\(s\) in (\d+) expansions", why
    )
    assert (
        found
        and f"finds one of {found.group(1)} m with {found.group(2)} gear change(s) in "
        f"{found.group(3)} expansions"
        in text.replace("\n", " ")
    )
    goal = "--goal=53.201107188452056,36.30433181948137,2.404196106990101"
    lengths = []
    for extra in ((), ("--planner-option", "reverse_detour_tree=false")):
        proc = _run("plan", "parking_lot", goal, "--reverse", *extra, "--json", "-")
        lengths.append(json.loads(proc.stdout)["length_m"])
    assert (
        f"is {lengths[0]:.2f} m with\none gear change by default and the "
        f"{lengths[1]:.2f} m forward loop" in text
    )


def test_readme_map_import_line_reproduces(tmp_path):
    proc = _run(
        "maps",
        "--import",
        "docs/maps/lot.yaml",
        "--start",
        "2,2,0",
        "--goal",
        "30,15,0",
        "--out",
        str(tmp_path / "lot.json"),
    )
    assert proc.returncode == 0, proc.stderr
    line = (
        (proc.stdout + proc.stderr)
        .strip()
        .splitlines()[-1]
        .replace(str(tmp_path / "lot.json"), "lot.json")
    )
    assert f"# {line}" in _read(README)


def test_no_nan_is_shown_as_a_measured_ratio_without_its_failure():
    # bench_planners' failing OMPL row: ratio columns nan only where success is 0 %
    for line in _read(DOCS / "bench_planners.md").split("\n"):
        if line.startswith("| ompl") or line.startswith("| improved"):
            cells = [c.strip() for c in line.strip("|").split("|")]
            assert (cells[3] in ("nan", "–")) == (cells[1] == "0 %"), line
            if cells[3] not in ("nan", "–"):
                assert math.isfinite(float(cells[3]))


def test_traffic_session27_prose_is_its_reports():
    reports = _json(RESULTS / "traffic_s27" / "traffic_s27.json")["reports"]
    before = {
        (r["density_per_km"], r["seed"]): r
        for r in _json(RESULTS / "traffic_s26" / "traffic_s26.json")["reports"]
    }
    text = _read(DOCS / "traffic.md").split("## Results on today's code (session 27")[1]
    text = " ".join(text.split("\n## ")[0].split())
    groups = defaultdict(list)
    for r in reports:
        groups[r["density_per_km"]].append(r)
    order = [groups[d] for d in sorted(groups)]

    def worst(key, digits):
        return " / ".join(f"{max(r[key] for r in rs):.{digits}f}" for rs in order)

    assert f"filtered longitudinal jerk at most {worst('nuplan_lon_jerk_abs_max', 2)} m/s³" in text
    assert f"executed steering rate at most {worst('max_steering_rate', 3)} rad/s" in text
    assert f"CTE max {worst('cte_max_m', 3)} m" in text
    assert f"lateral acceleration at most {worst('max_lateral_accel', 2)} m/s²" in text
    assert all(r["nuplan_comfortable"] and r["unsafe_steps"] == 0 for r in reports)
    diff = [
        (r["completion_time_s"] or 0)
        - (before[(r["density_per_km"], r["seed"])]["completion_time_s"] or 0)
        for r in reports
    ]
    longer, shorter = [d for d in diff if d > 1e-9], [-d for d in diff if d < -1e-9]
    assert (
        f"{len(longer) + len(shorter)} completion times differ, {len(longer)} longer (by up to "
        f"{max(longer):.2f} s) and {len(shorter)} shorter (by up to {max(shorter):.2f} s)"
    ) in text
    assert all(r["outcome"] == before[(r["density_per_km"], r["seed"])]["outcome"] for r in reports)


def test_closed_loop_default_car_summary_is_its_run():
    reports = _json(RESULTS / "steer_rate" / "steer_rate_default50_merged.json")["reports"]
    text = _read(DOCS / "closed_loop.md").split("**Session 6, main after the session's merges**")[1]
    text = " ".join(text.split("The session-5 run follows")[0].split())
    groups = defaultdict(list)
    for r in reports:
        groups[(r["scenario"], r["controller"])].append(r)
    rms_max = max(r["cte_rms_m"] for r in reports)
    rms_mean = max(statistics.mean(r["cte_rms_m"] for r in rs) for rs in groups.values())
    assert f"CTE RMS ≤ {rms_max:.3f} m (mean ≤ {rms_mean:.3f})" in text
    assert f"CTE max ≤ {max(r['cte_max_m'] for r in reports):.3f} m" in text
    assert f"path sharpness ≤ {max(r['path_max_sharpness'] for r in reports):.3f} rad/m" in text
    assert sum(r["success"] for r in reports) == len(reports) == 300
    assert f"nuPlan comfortable {sum(r['nuplan_comfortable'] for r in reports)}/300" in text
