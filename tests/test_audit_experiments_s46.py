"""Audit of experiments/ as a student reproducing the results (session 46).

What is checked: every script builds a parser whose options are described in --help;
every ``python experiments/X.py ...`` command quoted in README.md, docs/*.md and the
scripts' docstrings names flags that exist (the result pages' ``Command:`` lines parse
whole); the paper's Table 3 command reproduces docs/table3.md (every column but the
times) and its JSON is consistent with its per-run rows; bad input is refused up front
with exit 2 naming the flag; Ctrl-C leaves the previous outputs whole; a missing OMPL or
commonroad is said clearly; a few cheap scripts run at tiny sizes and write what their
docstring promises, with summaries computed from their rows.

The parsers are read in one subprocess (each script's ``main`` with ``parse_args``
intercepted), so no script's imports land in the test process.
"""

from __future__ import annotations

import ast
import importlib.util
import json
import math
import os
import re
import shlex
import signal
import statistics
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
EXP = ROOT / "experiments"
DOCS = ROOT / "docs"
README = ROOT / "README.md"
LIBRARIES = ("box_maps", "coverage_report", "reach_sweep", "results_io")
SCRIPTS = sorted(p.stem for p in EXP.glob("*.py") if p.stem not in LIBRARIES)

pytestmark = pytest.mark.skipif(not EXP.is_dir(), reason="needs the repository's experiments/")


def _sigint_deliverable() -> None:
    # In the child before exec: a pytest-xdist worker hands SIGINT down ignored, and a
    # worker that ran a bench may hand it down blocked (a mask survives exec); either way
    # the child never saw the Ctrl-C and ran to the end (exit 0 in CI, session 47).
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})


def run(script: str, *args: str, cwd: Path, timeout: float = 120, env: dict | None = None):
    return subprocess.run(
        [sys.executable, str(EXP / f"{script}.py"), *args],
        capture_output=True, text=True, check=False, cwd=cwd, timeout=timeout, env=env,
    )


# --------------------------------------------------------------------------- parsers

_INTROSPECT = textwrap.dedent(
    r"""
    import argparse, contextlib, importlib, io, json, sys
    sys.path.insert(0, sys.argv[1])
    todo = json.loads(sys.stdin.read())

    class Captured(Exception):
        pass

    def fake(self, *a, **k):
        raise Captured(self)

    out = {}
    original = argparse.ArgumentParser.parse_args
    for script in todo["scripts"]:
        argparse.ArgumentParser.parse_args = fake
        parser = None
        try:
            importlib.import_module(script).main()
        except Captured as c:
            parser = c.args[0]
        except BaseException as exc:
            out[script] = {"error": repr(exc)}
            continue
        finally:
            argparse.ArgumentParser.parse_args = original
        if parser is None:
            out[script] = {"error": "main() never parsed its arguments"}
            continue
        options = []
        for a in parser._actions:
            if isinstance(a, argparse._HelpAction):
                continue
            options.append({"flags": list(a.option_strings) or [a.dest],
                            "help": a.help, "suppressed": a.help == argparse.SUPPRESS})
        parses = []
        for args in todo["parse"].get(script, []):
            err = io.StringIO()
            with contextlib.redirect_stderr(err):
                try:
                    parser.parse_args(args)
                    parses.append(None)
                except SystemExit:
                    parses.append(err.getvalue().strip().splitlines()[-1])
        out[script] = {"description": parser.description, "help": parser.format_help(),
                       "flags": sorted(parser._option_string_actions), "options": options,
                       "parses": parses}
    print(json.dumps(out))
    """
)


def _code_spans(text: str) -> list[str]:
    """The fenced blocks (lines kept, ``\\`` continuations joined) and inline code spans."""
    fenced = re.finditer(r"```[a-z]*\n(.*?)```", text, re.S)
    spans = [m.group(1).replace("\\\n", " ") for m in fenced]
    rest = re.sub(r"```[a-z]*\n.*?```", "", text, flags=re.S)
    spans += [m.group(1).replace("\n", " ") for m in re.finditer(r"`([^`]+)`", rest)]
    return spans


_CMD = re.compile(r"python3? experiments/(\w+)\.py(.*?)(?=&&|;|\||python3? experiments/|$)")


def quoted_commands() -> list[tuple[str, str, str]]:
    """``(where, script, arguments)`` of every quoted command in README, docs and docstrings."""
    found = []
    pages = [README, *sorted(DOCS.glob("*.md"))] if DOCS.is_dir() else []
    for page in pages:
        for span in _code_spans(page.read_text(encoding="utf-8")):
            for line in span.splitlines():
                found += [(page.name, m.group(1), m.group(2)) for m in _CMD.finditer(line)]
    for script in EXP.glob("*.py"):
        doc = ast.get_docstring(ast.parse(script.read_text(encoding="utf-8"))) or ""
        for line in doc.replace("\\\n", " ").splitlines():
            found += [(script.name, m.group(1), m.group(2)) for m in _CMD.finditer(line)]
    return found


def _tokens(args: str) -> list[str]:
    args = args.split(" #", 1)[0]  # a shell comment after the command
    try:
        return shlex.split(args)
    except ValueError:  # a quoted value cut off by the end of a code span
        return args.split()


def page_commands() -> list[tuple[str, str, list[str]]]:
    """The commands of ``Command: `...` `` lines: the very command that made a page."""
    out = []
    for page in [README, *sorted(DOCS.glob("*.md"))]:
        for m in re.finditer(r"^Command: `python experiments/(\w+)\.py([^`]*)`", page.read_text(
                encoding="utf-8"), re.M):
            out.append((page.name, m.group(1), _tokens(m.group(2))))
    return out


#: Refused by argparse itself (exit 2, ``argument FLAG: ...``), before any import of work.
#: ``afile`` is a file in the folder the parsers run in.
ARGPARSE_REFUSALS = [
    ("table3", ["--runs", "0"], "--runs"),
    ("table3", ["--runs", "-3"], "--runs"),
    ("table3", ["--max-time", "nan"], "--max-time"),
    ("ablation", ["--runs", "-1"], "--runs"),
    ("ablation", ["--out", "afile/sub"], "--out"),
    ("random_goals", ["--goals", "0"], "--goals"),
    ("random_goals", ["--out", "afile"], "--out"),
    ("coverage", ["--count", "-5"], "--count"),
    ("hybrid_curve", ["--count", "0"], "--count"),
    ("bench_reeds_shepp", ["--pairs", "-1"], "--pairs"),
]


@pytest.fixture(scope="module")
def parsers(tmp_path_factory) -> dict:
    todo = {"scripts": SCRIPTS, "parse": {}}
    for _, script, args in page_commands():
        todo["parse"].setdefault(script, []).append(args)
    for script, args, _ in ARGPARSE_REFUSALS:
        todo["parse"].setdefault(script, []).append(args)
    cwd = tmp_path_factory.mktemp("introspect")
    (cwd / "afile").write_text("a file\n")
    proc = subprocess.run(
        [sys.executable, "-c", _INTROSPECT, str(EXP)], input=json.dumps(todo),
        capture_output=True, text=True, check=False, timeout=120, cwd=cwd,
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert sorted(p.name for p in cwd.iterdir()) == ["afile"]  # parsing wrote nothing
    return json.loads(proc.stdout)


def test_every_script_parses_its_arguments_and_describes_every_option(parsers):
    problems = []
    for script in SCRIPTS:
        info = parsers[script]
        if "error" in info:
            problems.append(f"{script}: {info['error']}")
            continue
        if not (info["description"] or "").strip():
            problems.append(f"{script}: no description")
        for opt in info["options"]:
            if opt["suppressed"]:
                continue
            if not (opt["help"] or "").strip():
                problems.append(f"{script}: {opt['flags']} without help")
            if opt["flags"][0].startswith("-") and opt["flags"][0] not in info["help"]:
                problems.append(f"{script}: {opt['flags'][0]} missing from --help")
    assert not problems, problems


@pytest.mark.parametrize("script", ["table3"])
def test_help_of_the_table3_pipeline_and_a_run_script(script, parsers, tmp_path):
    proc = run(script, "--help", cwd=tmp_path, timeout=60)
    assert proc.returncode == 0 and proc.stderr == "", proc.stderr[-2000:]
    assert proc.stdout.startswith("usage:")
    for flag in parsers[script]["flags"]:
        if flag.startswith("--"):
            assert flag in proc.stdout, flag
    assert list(tmp_path.iterdir()) == []  # --help wrote nothing


@pytest.mark.parametrize("module", LIBRARIES)
def test_a_library_module_run_as_a_script_says_what_to_run(module, tmp_path):
    proc = run(module, cwd=tmp_path, timeout=60)
    assert proc.returncode == 1 and "Traceback" not in proc.stderr
    named = re.findall(r"(\w+)\.py", proc.stderr)
    assert "every experiment script" in proc.stderr or any(
        n != module and (EXP / f"{n}.py").is_file() for n in named), proc.stderr


@pytest.mark.skipif(not DOCS.is_dir(), reason="needs docs/")
def test_every_quoted_command_names_a_script_and_flags_that_exist(parsers):
    commands = quoted_commands()
    assert len(commands) > 100  # README + docs quote many
    bad = []
    for where, script, args in commands:
        if script not in parsers:
            bad.append(f"{where}: experiments/{script}.py does not exist")
            continue
        flags = set(parsers[script]["flags"])
        for tok in _tokens(args):
            flag = tok.strip("[]").split("=")[0]
            if re.fullmatch(r"--[a-z][a-z0-9-]*", flag) and flag not in flags:
                bad.append(f"{where}: {script}.py has no {flag}")
    assert not bad, bad


@pytest.mark.skipif(not DOCS.is_dir(), reason="needs docs/")
def test_the_command_of_every_result_page_parses(parsers):
    pages = page_commands()
    assert {p for p, _, _ in pages} >= {"table3.md", "ablation.md", "bench_planners.md",
                                         "coverage.md", "coverage_tight.md"}
    seen: dict[str, int] = {}
    for page, script, _ in pages:
        i = seen.get(script, 0)
        seen[script] = i + 1
        assert parsers[script]["parses"][i] is None, (page, parsers[script]["parses"][i])


def test_argparse_refuses_bad_counts_caps_and_output_folders_naming_the_flag(parsers):
    # After the page commands, each script's parses are these refusals, in order.
    seen = {script: len([1 for _, s, _ in page_commands() if s == script]) for script in SCRIPTS}
    for script, args, flag in ARGPARSE_REFUSALS:
        error = parsers[script]["parses"][seen[script]]
        seen[script] += 1
        assert error is not None, (script, args)
        assert f"argument {flag}" in error, (script, args, error)


# --------------------------------------------------------------------------- table 3

def _t975(dof: int) -> float:
    from scipy import stats

    return float(stats.t.ppf(0.975, dof))


def _check_describe(cell: dict, values: list[float]) -> None:
    assert cell["n"] == len(values)
    if not values:
        assert cell["mean"] is None
        return
    assert cell["mean"] == pytest.approx(statistics.fmean(values), rel=1e-9, abs=1e-12)
    if len(values) > 1:
        std = statistics.stdev(values)
        assert cell["std"] == pytest.approx(std, rel=1e-9, abs=1e-12)
        half = _t975(len(values) - 1) * std / math.sqrt(len(values))
        assert cell["ci95"] == pytest.approx(half, rel=1e-6, abs=1e-12)


def _check_table3_json(data: dict, runs: int) -> None:
    assert data["seeds"] == list(range(runs))
    for name, per_map in data["maps"].items():
        summary, rows = per_map["summary"], per_map["runs"]
        assert set(summary) == set(rows) and len(rows) == 5, name
        for method, rs in rows.items():
            s = summary[method]
            assert [r["seed"] for r in rs] == list(range(runs))
            ok = [r for r in rs if r["success"]]
            assert s["success_rate"] == pytest.approx(len(ok) / runs)
            assert all(r["status"] == "solved" for r in ok)
            _check_describe(s["nodes"], [r["nodes"] for r in ok])
            _check_describe(s["length_m"], [r["length_m"] for r in ok])
            _check_describe(s["time_s"], [r["time_s"] for r in rs])
            assert s["median_time_s"] == pytest.approx(statistics.median(r["time_s"] for r in rs))
            _check_describe(s["max_curvature"], [r["max_curvature"] for r in ok])
            if method.startswith("improved"):
                assert s["guarantees_ok_rate"] == (
                    pytest.approx(sum(r["guarantees_ok"] for r in ok) / len(ok)) if ok else None)
                sharp = [r["max_sharpness"] for r in ok]
                assert s["largest_sharpness"] == (max(sharp) if sharp else None)
            else:
                _check_describe(s["pruned_length_m"], [r["pruned_length_m"] for r in ok])
                # Pruning shortcuts a path: never longer than the tree path it came from.
                assert all(r["pruned_length_m"] <= r["length_m"] + 1e-9 for r in ok)
        ours = summary["improved-rrt-connect"]["length_m"]["mean"]
        for base, ratio in per_map["length_ratios"].items():
            theirs = summary[base]["length_m"]["mean"]
            if ours is not None and theirs is not None:
                assert ratio["raw"] == pytest.approx(ours / theirs)


def _md_rows(text: str) -> dict[str, list[str]]:
    """Per map section: its table lines with the two time columns dropped."""
    out: dict[str, list[str]] = {}
    section = None
    for line in text.splitlines():
        if line.startswith("## "):
            section = line
            out[section] = []
        elif section and line.startswith("|"):
            cells = line.split("|")
            out[section].append("|".join(cells[:6] + cells[8:]) if len(cells) == 11 else line)
        elif section and line.startswith("Improved"):
            out[section].append(line)
    return out


@pytest.mark.skipif(not (DOCS / "table3.md").is_file(), reason="needs docs/table3.md")
def test_table3_docs_command_reproduces_the_page_and_its_numbers_are_computed(tmp_path):
    # docs/table3.md: "the other columns the same on any machine". Its command, with
    # --doc and --figures pointed away from docs/ (everything else the paper's settings).
    page = (DOCS / "table3.md").read_text(encoding="utf-8")
    cmd = re.search(r"^Command: `python experiments/table3.py ([^`]*)`", page, re.M).group(1)
    args = cmd.split()
    args[args.index("--doc") + 1] = str(tmp_path / "page.md")
    args[args.index("--figures") + 1] = str(tmp_path / "figs")
    args[args.index("--out") + 1] = str(tmp_path / "out")
    proc = run("table3", *args, cwd=tmp_path, timeout=240)
    assert proc.returncode == 0, proc.stderr[-2000:]
    out = tmp_path / "out"
    assert sorted(p.name for p in out.iterdir()) == ["table3.json", "table3.md"]
    data = json.loads((out / "table3.json").read_text())
    runs = int(args[args.index("--runs") + 1])
    _check_table3_json(data, runs)
    # The figures its docstring promises, per map, listed in the JSON and on the page.
    for name, per_map in data["maps"].items():
        assert per_map["figures"] == [f"table3_{name}_{k}.png" for k in
                                      ("planners", "improved", "curvature")]
        for fig in per_map["figures"]:
            assert (tmp_path / "figs" / fig).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    new = (tmp_path / "page.md").read_text(encoding="utf-8")
    assert new == (out / "table3.md").read_text(encoding="utf-8").replace(
        "](../figs/", "](figs/")
    for link in re.findall(r"\]\(([^)]+\.png)\)", new):
        assert (tmp_path / link).is_file(), link
    # Every column but the times is the committed page's.
    assert _md_rows(new) == _md_rows(page)
    # The page's cells are the JSON's numbers.
    labels = {"RRT": "rrt", "RRT-Connect": "rrt-connect", "RRT*": "rrt-star"}
    for name, per_map in data["maps"].items():
        section = new.split(f"## `{name}`", 1)[1]
        for label, method in labels.items():
            row = re.search(rf"^\| {re.escape(label)} \| (\d+) % \| ([\d.]+) ± ", section, re.M)
            s = per_map["summary"][method]
            assert int(row.group(1)) == round(100 * s["success_rate"])
            assert float(row.group(2)) == pytest.approx(s["nodes"]["mean"], abs=0.051)


def test_table3_at_a_tiny_budget_keeps_its_numbers_consistent(tmp_path):
    # A cap so short that some runs fail: rates, spreads and ratios from the solved rows
    # only; no NaN in the JSON; figures only when every planner has an example.
    proc = run("table3", "--runs", "3", "--maps", "parking_lot", "--max-time", "0.01",
               "--out", str(tmp_path / "o"), cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr[-2000:]
    text = (tmp_path / "o" / "table3.json").read_text()
    data = json.loads(text, parse_constant=lambda c: pytest.fail(f"bare {c} in the JSON"))
    _check_table3_json(data, 3)
    summary = data["maps"]["parking_lot"]["summary"]
    md = (tmp_path / "o" / "table3.md").read_text()
    for label, method in (("RRT", "rrt"), ("RRT*", "rrt-star")):
        rate = re.search(rf"^\| {re.escape(label)} \| (\d+) % \|", md, re.M).group(1)
        assert int(rate) == round(100 * summary[method]["success_rate"])
    figs = data["maps"]["parking_lot"]["figures"]
    fig_dir = tmp_path / "o" / "figures"
    on_disk = sorted(p.name for p in fig_dir.iterdir()) if fig_dir.exists() else []
    assert on_disk == sorted(figs)
    planners = {"RRT": "rrt", "RRT-Connect": "rrt-connect", "RRT*": "rrt-star",
                "Improved RRT-Connect (paper's B-spline)": "improved-rrt-connect"}
    unsolved = [label for label, method in planners.items()
                if summary[method]["success_rate"] == 0]
    # A planner that never solved leaves no figures, and the page and stderr say which.
    assert bool(figs) == (not unsolved)
    for label in unsolved:
        assert label in proc.stderr and "No figures:" in md and label in md.split("No figures:")[1]


# --------------------------------------------------------------------------- bad input

@pytest.fixture
def afile(tmp_path) -> Path:
    f = tmp_path / "afile"
    f.write_text("not a folder\n")
    return f


@pytest.mark.parametrize(
    ("script", "args", "flag"),
    [
        ("random_goals", ["--map", "nosuch", "--goals", "1"], "--map"),
        ("hybrid_variants", ["--sets", "nosuch", "--count", "1"], "--sets"),
    ],
)
def test_a_bad_name_is_refused_up_front_naming_the_flag(script, args, flag, tmp_path):
    out = tmp_path / "out"
    proc = run(script, *args, "--out", str(out), cwd=tmp_path, timeout=60)
    assert proc.returncode == 2, proc.stderr[-1000:]
    assert "Traceback" not in proc.stderr and flag in proc.stderr, proc.stderr
    assert not out.exists()  # nothing ran


def test_table3_refuses_an_unknown_map_before_any_planning(tmp_path):
    proc = run("table3", "--runs", "1", "--maps", "overtake,nosuch", "--out", str(tmp_path / "o"),
               cwd=tmp_path, timeout=60)
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    assert "'nosuch'" in proc.stderr and "done" not in proc.stderr
    assert not (tmp_path / "o").exists()


def test_table3_refuses_a_doc_page_it_cannot_write_before_the_run(afile, tmp_path):
    # Was a bug: found after every run, naming a hidden temporary file. A page under a
    # file, or a folder as the page, is refused up front; a missing folder is made, as
    # --out's is.
    for doc in (afile / "page.md", tmp_path):
        proc = run("table3", "--runs", "1", "--maps", "overtake", "--out", str(tmp_path / "o"),
                   "--doc", str(doc), cwd=tmp_path, timeout=120)
        assert proc.returncode == 2 and "--doc" in proc.stderr, proc.stderr[-500:]
        assert "done" not in proc.stderr and not (tmp_path / "o").exists()
    page = tmp_path / "missing" / "page.md"
    proc = run("table3", "--runs", "1", "--maps", "overtake", "--out", str(tmp_path / "o"),
               "--doc", str(page), cwd=tmp_path, timeout=120)
    assert proc.returncode == 0, proc.stderr[-500:]
    assert page.read_text() == (tmp_path / "o" / "table3.md").read_text().replace(
        "](figures/", "](../o/figures/")


def test_table3_refuses_a_figures_folder_that_is_a_file(afile, tmp_path):
    proc = run("table3", "--runs", "1", "--maps", "overtake", "--out", str(tmp_path / "o"),
               "--figures", str(afile), cwd=tmp_path, timeout=120)
    assert proc.returncode == 2 and "--figures" in proc.stderr, proc.stderr[-500:]


def test_traffic_refuses_a_figures_folder_that_is_a_file_before_the_run(afile, tmp_path):
    tmp = tmp_path / "tmp"
    tmp.mkdir()
    env = {**os.environ, "TMPDIR": str(tmp)}
    proc = run("traffic", "--seeds", "1", "--densities", "low", "--jobs", "1",
               "--out", str(tmp_path / "o"), "--figures", str(afile), cwd=tmp_path,
               timeout=180, env=env)
    assert list(tmp.iterdir()) == [], "temporary episode folder left behind"
    assert proc.returncode == 2 and "--figures" in proc.stderr, proc.stderr[-500:]
    assert "episodes" not in proc.stderr  # refused before driving


def test_hybrid_curve_names_its_cap_flag(tmp_path):
    proc = run("hybrid_curve", "--count", "1", "--cap", "-1", "--out", str(tmp_path / "o"),
               cwd=tmp_path, timeout=60)
    assert proc.returncode == 2 and "--cap" in proc.stderr, proc.stderr


def test_traffic_names_its_rate_flag(tmp_path):
    proc = run("traffic", "--seeds", "1", "--rate", "0", "--out", str(tmp_path / "o"),
               cwd=tmp_path, timeout=60)
    assert proc.returncode == 2 and "--rate" in proc.stderr, proc.stderr


# --------------------------------------------------------------------------- Ctrl-C

@pytest.mark.parametrize("trigger", ["overtake: rrt done",
                                     "overtake: improved-rrt-connect (default) done"])
def test_ctrl_c_leaves_the_previous_results_whole(trigger, tmp_path):
    out = tmp_path / "o"
    out.mkdir()
    (out / "table3.json").write_text('{"old": true}\n')
    (out / "table3.md").write_text("old page\n")
    proc = subprocess.Popen(
        [sys.executable, str(EXP / "table3.py"), "--runs", "6", "--maps", "overtake",
         "--out", str(out)],
        stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, cwd=tmp_path,
        preexec_fn=_sigint_deliverable,
    )
    try:
        for line in proc.stderr:
            if trigger in line:
                proc.send_signal(signal.SIGINT)
                break
        rest = proc.stderr.read()
        rc = proc.wait(timeout=60)
    finally:
        proc.kill()
    assert rc in (0, 130), rest
    hidden = [p.name for p in out.rglob(".*")]
    assert hidden == [], hidden  # no temporary file left
    if rc == 130:
        assert "table3.py: interrupted" in rest and "Traceback" not in rest
        assert (out / "table3.json").read_text() == '{"old": true}\n'
        assert (out / "table3.md").read_text() == "old page\n"
    for png in (out / "figures").glob("*.png"):
        assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


# --------------------------------------------------------------------------- optional extras

@pytest.mark.skipif(importlib.util.find_spec("ompl") is not None, reason="OMPL is installed")
def test_bench_planners_says_ompl_is_missing(tmp_path):
    proc = run("bench_planners", "--seeds", "1", "--out", str(tmp_path / "o"), cwd=tmp_path)
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    assert "OMPL is not installed" in proc.stderr and ".[ompl]" in proc.stderr
    assert not (tmp_path / "o").exists()


@pytest.mark.skipif(importlib.util.find_spec("commonroad") is not None,
                    reason="commonroad is installed")
def test_commonroad_judge_says_commonroad_is_missing(tmp_path):
    proc = run("commonroad_judge", "--seeds", "1", "--out", str(tmp_path / "o"), cwd=tmp_path)
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    assert "commonroad" in proc.stderr and "pip install" in proc.stderr
    assert not (tmp_path / "o").exists()


@pytest.mark.skipif(importlib.util.find_spec("ompl") is not None, reason="OMPL is installed")
def test_coverage_runs_the_rest_and_names_the_missing_ompl_row(tmp_path):
    proc = run("coverage", "--map", "parking_lot", "--count", "1", "--jobs", "1", "--planners",
               "improved-rrt-connect,ompl-rs-rrtconnect", "--out", str(tmp_path), cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr[-2000:]
    data = json.loads((tmp_path / "coverage_parking_lot.json").read_text())
    assert "OMPL is not installed" in data["skipped"]["ompl-rs-rrtconnect"]
    assert data["planners"] == ["improved-rrt-connect"]
    md = (tmp_path / "coverage_parking_lot.md").read_text()
    assert "`ompl-rs-rrtconnect`: OMPL is not installed" in md
    # The summary counts the rows.
    rows = data["rows"]
    for vary, s in data["summary"]["per_planner"]["improved-rrt-connect"].items():
        mine = [r for r in rows if r["vary"] == vary]
        assert s["queries"] == len(mine) == 1
        assert s["solved"] == sum(r["solved"] for r in mine)
        assert s["verified"] == sum(bool(r["verified"]) for r in mine)
        assert sum(s["statuses"].values()) == len(mine)


# --------------------------------------------------------------------------- cheap runs

def test_ablation_tiny_run_writes_its_files_with_computed_rates(tmp_path):
    proc = run("ablation", "--runs", "1", "--maps", "overtake", "--out", str(tmp_path),
               cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ablation.json", "ablation.md"]
    data = json.loads((tmp_path / "ablation.json").read_text())
    assert data["seeds"] == [0] and "--runs 1" in data["command"]
    md = (tmp_path / "ablation.md").read_text()
    for config, s in data["components"]["overtake"].items():
        row = re.search(rf"^\| {re.escape(config)} \| (\d+) % \| (\d+) % \| ([\d.]+) \|", md, re.M)
        assert row, config
        assert int(row.group(1)) == round(100 * s["success_rate"])
        assert int(row.group(2)) == round(100 * s["verified_rate"])
        assert float(row.group(3)) == pytest.approx(s["mean_length_m"], abs=0.006)


def test_random_goals_tiny_run_counts_its_rows(tmp_path):
    proc = run("random_goals", "--map", "parking_lot", "--goals", "3", "--out", str(tmp_path),
               cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr[-2000:]
    data = json.loads((tmp_path / "random_goals_parking_lot.json").read_text())
    assert (tmp_path / "random_goals_parking_lot.md").is_file() and len(data["rows"]) == 3
    md = (tmp_path / "random_goals_parking_lot.md").read_text()
    for label, s in data["summary"].items():
        cells = [r[label] for r in data["rows"]]
        assert s["goals"] == 3
        assert s["solved"] == sum(c["status"] == "solved" for c in cells)
        assert s["verified"] == sum(c["verified"] for c in cells)
        assert s["by_fallback"] == sum(c["fallback"] for c in cells)
        assert f"| {label} | {s['solved']}/3 | {s['verified']} |" in md


def test_hybrid_curve_tiny_run_counts_its_rows(tmp_path):
    proc = run("hybrid_curve", "--count", "1", "--out", str(tmp_path), cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["hybrid_curve.json", "hybrid_curve.md"]
    data = json.loads((tmp_path / "hybrid_curve.json").read_text())
    for key, s in data["summary"].items():
        vary, curve = key.split("/")
        rows = [r for r in data["rows"] if r["vary"] == vary and r["curve"] == curve]
        assert s["queries"] == len(rows) == 1
        assert s["solved"] == sum(r["solved"] for r in rows)
        assert s["collision_free"] == sum(bool(r["collision_free"]) for r in rows)


def test_bench_reeds_shepp_tiny_run_writes_its_json(tmp_path):
    proc = run("bench_reeds_shepp", "--pairs", "20", "--repeats", "1", "--out", str(tmp_path),
               cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert [p.name for p in tmp_path.iterdir()] == ["reeds_shepp.json"]  # as its docstring says
    data = json.loads((tmp_path / "reeds_shepp.json").read_text())
    assert data["meta"]["config"]["pairs"] == 20
    for timing in data["timings"].values():
        if "wall_mean_us_per_repeat" in timing:
            assert timing["wall_mean_us_best"] == min(timing["wall_mean_us_per_repeat"])


def test_map_figures_draws_every_built_in_map(tmp_path):
    from rrtdrive.maps import BUILTIN_MAPS

    proc = run("map_figures", "--out", str(tmp_path / "figs"), cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert sorted(p.name for p in (tmp_path / "figs").iterdir()) == sorted(
        f"map_{n}.png" for n in BUILTIN_MAPS)


@pytest.mark.parametrize("script", ["closed_loop", "steer_rate"])
@pytest.mark.parametrize(
    ("flag", "word"),
    [("--scenarios", "unknown scenario"), ("--controllers", "unknown controller"),
     ("--planner", "unknown planner")],
)
def test_closed_loop_scripts_name_their_flags_before_any_episode(tmp_path, script, flag, word):
    # They said "scenario:", "controller:", "planner:" from inside the first worker.
    proc = run(script, flag, "nosuch", "--out", str(tmp_path / "o"), cwd=tmp_path, timeout=60)
    assert proc.returncode == 2, proc.stderr
    assert f"error: {flag}: {word} 'nosuch'" in proc.stderr
    assert "Traceback" not in proc.stderr and not (tmp_path / "o").exists()
