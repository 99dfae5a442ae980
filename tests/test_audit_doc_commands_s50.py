"""Audit (session 50): the commands README.md and docs/*.md show run and say what the docs say.

Every command here is read out of the page that shows it, together with the output the page
claims for it (a ``# ...`` comment after the command, a quoted message, a number in the
sentence), and run from a temporary folder holding a copy of ``docs/maps``. Times are not
compared; every other number is. Besides: every CLI flag a page puts in a command exists in
that command's ``--help`` (the experiment scripts' too), the README's synopsis lists exactly
the flags of each subcommand, and every relative link of the pages resolves to a file and,
for a ``#anchor`` into a page, to one of its headings.

The commands that run longer than about a minute (the experiments' 20-100 seed runs, the
5000 m ``wall.json`` map), and the OMPL / Ray / CommonRoad ones, are not run here.
"""

from __future__ import annotations

import json
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
README = ROOT / "README.md"
EXPERIMENTS = ROOT / "experiments"

pytestmark = pytest.mark.skipif(
    not (DOCS.is_dir() and README.is_file() and EXPERIMENTS.is_dir()),
    reason="needs the repository's README.md, docs/ and experiments/",
)

PAGES = [README, *sorted(DOCS.glob("*.md"))]
PAGE_IDS = [p.relative_to(ROOT).as_posix() for p in PAGES]
SUBCOMMANDS = ("plan", "simulate", "verify", "maps", "bench")

_SCRIPT = Path(sys.executable).with_name("rrtdrive")
RRTDRIVE = [str(_SCRIPT)] if _SCRIPT.exists() else [sys.executable, "-m", "rrtdrive"]

FLAG = re.compile(r"(?<![\w-])(--(?:\[no-\])?[a-z][a-z0-9-]*[a-z0-9])")
# Flags of other programs the pages quote (ray start, pytest-xdist).
EXTERNAL_FLAGS = {"--head", "--port", "--num-cpus", "--address"}


def _text(path: Path) -> str:
    return path.read_text(encoding="utf-8")


def _no_fences(text: str) -> str:
    """The page with its fenced blocks blanked (line numbers kept)."""
    return re.sub(r"```.*?```", lambda m: "\n" * m.group(0).count("\n"), text, flags=re.S)


def _squash(text: str) -> str:
    return re.sub(r"\s+", " ", text).strip()


# --------------------------------------------------------------------------------------
# the commands the pages show


def _fenced_commands(text: str) -> list[tuple[str, str]]:
    """(command, comment) for each command line of the ``bash``/``sh``/plain blocks."""
    out = []
    for m in re.finditer(r"```(\w*)\n(.*?)```", text, re.S):
        if m.group(1) not in ("bash", "sh", ""):
            continue
        for line in m.group(2).replace("\\\n", " ").splitlines():
            line = line.strip()
            if line.startswith(("rrtdrive ", "python experiments/")):
                command, _, comment = line.partition("  #")
                out.append((_squash(command), comment.strip()))
    return out


def _inline_commands(text: str) -> list[str]:
    spans = re.findall(r"`([^`]+)`", _no_fences(text).replace("\n", " "))
    return [
        _squash(s)
        for s in spans
        if re.match(r"(rrtdrive (plan|simulate|verify|maps|bench)\b|python experiments/)", s)
    ]


def _segments(command: str) -> list[tuple[str, str]]:
    """(key, segment): each ``rrtdrive X`` / ``python experiments/Y.py`` of a command line."""
    out = []
    for part in re.split(r"&&|(?<!\|)\|(?!\|)", command):
        part = part.strip()
        m = re.match(r"rrtdrive (\w+)|python experiments/(\w+)\.py", part)
        if m and (m.group(1) in SUBCOMMANDS or m.group(2)):
            out.append((m.group(1) or f"experiments/{m.group(2)}.py", part))
    return out


def _page_commands(page: Path) -> list[tuple[str, str]]:
    text = _text(page)
    commands = [c for c, _ in _fenced_commands(text)] + _inline_commands(text)
    return [seg for c in commands for seg in _segments(c)]


_HELP_DUMP = """
import contextlib, io, json, runpy, sys
from rrtdrive.cli import main
out = {}
for name in ["", "plan", "simulate", "verify", "maps", "bench"]:
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        try:
            main([name, "--help"] if name else ["--help"])
        except SystemExit:
            pass
    out[name or "rrtdrive"] = buf.getvalue()
for path in sys.argv[1:]:
    buf, argv, syspath = io.StringIO(), sys.argv, list(sys.path)
    sys.argv = [path, "--help"]
    sys.path.insert(0, "experiments")
    try:
        with contextlib.redirect_stdout(buf), contextlib.redirect_stderr(io.StringIO()):
            runpy.run_path(path, run_name="__main__")
    except SystemExit:
        pass
    finally:
        sys.argv, sys.path[:] = argv, syspath
    out[path] = buf.getvalue()
print(json.dumps(out))
"""


@pytest.fixture(scope="session")
def helps() -> dict[str, str]:
    """``--help`` of rrtdrive, its subcommands and every experiment script.

    One interpreter for all: their imports are shared, so this is quick.
    """
    scripts = sorted(p.relative_to(ROOT).as_posix() for p in EXPERIMENTS.glob("*.py"))
    r = subprocess.run([sys.executable, "-c", _HELP_DUMP, *scripts], capture_output=True,
                       text=True, timeout=300, cwd=ROOT)
    assert r.returncode == 0, r.stderr[-2000:]
    out = json.loads(r.stdout.strip().splitlines()[-1])
    for name in ("rrtdrive", *SUBCOMMANDS):
        assert out[name].startswith("usage: rrtdrive"), (name, out[name][:200])
    return out


def _has_flag(help_text: str, flag: str) -> bool:
    names = [flag] if not flag.startswith("--[no-]") else ["--" + flag[7:], "--no-" + flag[7:]]
    return all(re.search(re.escape(n) + r"(?![\w-])", help_text) for n in names)


@pytest.mark.parametrize("page", PAGES, ids=PAGE_IDS)
def test_every_flag_of_a_shown_command_is_in_its_help(page, helps):
    missing = []
    for key, segment in _page_commands(page):
        assert key in helps, f"{page.name}: no such command or script: {segment[:100]}"
        assert "usage:" in helps[key], f"{key} has no --help: {helps[key][:200]}"
        for flag in FLAG.findall(segment):
            if not _has_flag(helps[key], flag):
                missing.append(f"{key} {flag}  ({segment[:100]})")
    assert not missing, f"{page.name}: flags not in the command's --help:\n" + "\n".join(missing)


@pytest.mark.parametrize("page", PAGES, ids=PAGE_IDS)
def test_every_flag_a_page_mentions_exists_somewhere(page, helps):
    """A bare ``--flag`` in prose belongs to some command: one of ours, or ray's / pytest's."""
    every = "\n".join(helps.values())
    missing = sorted(
        {
            flag
            for span in re.findall(r"`([^`]+)`", _text(page))
            for flag in FLAG.findall(span)
            if flag not in EXTERNAL_FLAGS and not _has_flag(every, flag)
        }
    )
    assert not missing, f"{page.name}: flags no command has: {missing}"


def test_readme_sections_flags_belong_to_their_subcommand(helps):
    """Under ``### `rrtdrive X``` a bare ``--flag`` is X's, or a command named near it has it."""
    text = _no_fences(_text(README))
    parts = re.split(r"^### `rrtdrive (\w+)`", text, flags=re.M)
    assert len(parts) >= 7, "README lost its subcommand sections"
    wrong = []
    for sub, body in zip(parts[1::2], parts[2::2], strict=True):
        body = body.split("\n## ")[0]
        for m in re.finditer(r"`([^`]+)`", body):
            span = m.group(1)
            named = re.match(r"(?:rrtdrive )?(plan|simulate|verify|maps|bench)\b", span)
            owner = named.group(1) if named else sub
            if span.startswith(("python", "pip")):
                continue
            for flag in FLAG.findall(span):
                if _has_flag(helps[owner], flag):
                    continue
                # "`rrtdrive verify` requires it ... unless given `--clearance`"
                before = body[max(0, m.start() - 200) : m.start()]
                near = re.findall(r"`rrtdrive (plan|simulate|verify|maps|bench)`", before)
                if not any(_has_flag(helps[n], flag) for n in near):
                    wrong.append(f"{sub}: {flag} ({span[:60]})")
    assert not wrong, wrong


def _synopsis() -> dict[str, set[str]]:
    block = re.search(r"```text\n(rrtdrive plan .*?)```", _text(README), re.S).group(1)
    out: dict[str, set[str]] = {}
    current = None
    for line in block.splitlines():
        m = re.match(r"rrtdrive (\w+)", line)
        if m:
            current = m.group(1)
        for flag in FLAG.findall(line):
            names = [flag] if "[no-]" not in flag else ["--" + flag[7:], "--no-" + flag[7:]]
            out.setdefault(current, set()).update(names)
    return out


@pytest.mark.parametrize("sub", SUBCOMMANDS)
def test_readme_synopsis_lists_exactly_the_help_flags(sub, helps):
    synopsis = _synopsis()[sub]
    # the option lines of --help; the names on one line are aliases (--workers N, --jobs N)
    options = [
        set(FLAG.findall(re.split(r"\s{2,}", line.strip())[0]))
        for line in helps[sub].splitlines()
        if re.match(r"  -", line)
    ]
    options = [names for names in options if names and names != {"--help"}]
    unlisted = [sorted(names) for names in options if not names & synopsis]
    unknown = sorted(synopsis - set().union(*options))
    assert not unlisted and not unknown, (
        f"`rrtdrive {sub} --help` options the README's synopsis omits: {unlisted}; "
        f"synopsis flags `--help` lacks: {unknown}"
    )


# --------------------------------------------------------------------------------------
# links


def _slug(heading: str) -> str:
    heading = re.sub(r"[^\w\- ]", "", heading.strip().lower())
    return heading.replace(" ", "-")


def _anchors(page: Path) -> set[str]:
    out, seen = set(), {}
    for m in re.finditer(r"^#{1,6}\s+(.*)$", _no_fences(_text(page)), re.M):
        s = _slug(m.group(1))
        out.add(s if s not in seen else f"{s}-{seen[s]}")
        seen[s] = seen.get(s, 0) + 1
    out.update(re.findall(r"<a (?:name|id)=\"([^\"]+)\"", _text(page)))
    return out


@pytest.mark.parametrize("page", PAGES, ids=PAGE_IDS)
def test_relative_links_resolve(page):
    text = _no_fences(_text(page))
    links = re.findall(r"\]\(([^)\s]+)\)", text)
    broken = []
    for target in links:
        if re.match(r"[a-z]+:", target):
            continue
        path, _, anchor = target.partition("#")
        file = (page.parent / path).resolve() if path else page
        if not file.exists():
            broken.append(target)
        elif anchor and file.suffix == ".md" and anchor not in _anchors(file):
            broken.append(target)
    assert not broken, f"{page.name}: broken relative links {broken}"
    if page == README:
        assert len(links) >= 10  # the parser still finds the README's links


def test_anchor_rule_knows_a_real_anchor():
    """The slug rule above is GitHub's: the README's own link to a planning.md anchor."""
    assert "budgets-and-determinism" in _anchors(DOCS / "planning.md")
    assert "budgets-and-determinism-x" not in _anchors(DOCS / "planning.md")


# --------------------------------------------------------------------------------------
# running the shown commands


@pytest.fixture(scope="module")
def work(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("doc_commands")
    shutil.copytree(DOCS / "maps", folder / "docs" / "maps")
    return folder


def _run(command: str, cwd: Path, timeout: float = 180) -> subprocess.CompletedProcess:
    argv = shlex.split(command)
    assert argv[0] == "rrtdrive", command
    return subprocess.run([*RRTDRIVE, *argv[1:]], cwd=cwd, capture_output=True, text=True,
                          timeout=timeout)


def _fenced(page: Path, startswith: str) -> list[tuple[str, str]]:
    """The fenced block's commands, from the one that starts with ``startswith`` on."""
    commands = _fenced_commands(_text(page))
    i = next(i for i, (c, _) in enumerate(commands) if c.startswith(startswith))
    return commands[i:]


@pytest.fixture(scope="module")
def plan_parking_lot(work) -> dict:
    """The README's ``rrtdrive plan parking_lot --json -``, run once."""
    command = re.search(r"`(rrtdrive plan parking_lot --json -)`", _text(README)).group(1)
    r = _run(command, work)
    assert r.returncode == 0, r.stderr
    return json.loads(r.stdout)


def test_readme_plan_json_is_the_shown_object(plan_parking_lot):
    shown = re.search(r"```json\n(\{\"success\".*?)```", _text(README), re.S).group(1)
    # "long lists cut to `...`": keep the rows the page shows, drop the ellipses
    shown = re.sub(r",\s*\.\.\.(?=\s*[,\]])", "", shown)
    doc = json.loads(shown)
    got = plan_parking_lot
    assert list(got) == list(doc), "the keys (and their order) differ from the README's"
    times = {"planning_time_s", "setup_time_s", "diagnosis_time_s"}
    for key, value in doc.items():
        if key in ("path", "waypoints"):
            n_head = len(value) - (1 if key == "path" else 0)
            assert got[key][:n_head] == value[:n_head], key
            if key == "path":
                assert got[key][-1] == value[-1]
        elif key in times:
            assert (got[key] is None) == (value is None), key
        else:
            assert got[key] == value, key


def test_readme_plan_then_verify(work):
    (plan, _), (verify, comment) = _fenced(README, "rrtdrive plan parking_lot --reverse")[:2]
    assert verify.startswith("rrtdrive verify")
    r = _run(plan, work)
    assert r.returncode == 0, r.stderr
    written = re.search(r"--json (\S+)", plan).group(1)
    assert (work / written).is_file()
    r = _run(verify, work)
    assert r.returncode == 0, r.stdout + r.stderr
    expected = comment.removesuffix("...").strip()
    assert r.stdout.splitlines()[0] == expected


def test_readme_maps_import_prints_the_shown_line(work):
    command, = (c for c, _ in _fenced_commands(_text(README)) if "maps --import" in c)
    block = re.search(re.escape(command) + r"\n# (.*)\n", _text(README)).group(1)
    r = _run(command, work)
    assert r.returncode == 0, r.stderr
    assert (r.stdout + r.stderr).strip() == block.strip()
    out = re.search(r"--out (\S+)", command).group(1)
    m = json.loads((work / out).read_text())
    n_rect = int(re.search(r"as (\d+) rectangles", block).group(1))
    assert len(m["obstacles"]) == n_rect


def test_readme_maps_into_head_ends_quietly(work):
    assert "`rrtdrive maps | head -1`" in _text(README)
    r = subprocess.run(f"{shlex.join(RRTDRIVE)} maps | head -1; echo \"rc=${{PIPESTATUS[0]}}\"",
                       shell=True, executable="/bin/bash", cwd=work, capture_output=True,
                       text=True, timeout=120)
    first, rc = r.stdout.splitlines()
    assert rc in ("rc=0", "rc=141")
    assert first.split()[0] == "overtake"
    assert r.stderr == ""


def _quoted_after(text: str, command: str) -> str:
    """The first ``"..."`` quote after ``command``'s code span (squashed)."""
    flat = _squash(text)
    start = flat.index(command)
    return re.search(r"\"([^\"]+)\"", flat[start:]).group(1)


DIAGNOSES = [
    ("rrtdrive plan parking_lot --goal 66.5,22,1.5708", "needs_reverse"),
    ("rrtdrive plan dead_end", "u_turn"),
]


@pytest.mark.parametrize("command, kind", DIAGNOSES, ids=["needs_reverse", "u_turn"])
def test_readme_diagnosis_examples(work, command, kind):
    text = _text(README)
    assert f"`{command}`" in text
    quote = _quoted_after(text, f"`{command}`")
    r = _run(command + " --json -", work)
    assert r.returncode == 1, r.stderr
    doc = json.loads(r.stdout)
    assert doc["diagnosis"]["kind"] == kind
    why = next(line for line in r.stderr.splitlines() if line.strip().startswith("why:"))
    for piece in re.split(r"\s*…\s*", quote):
        assert piece.strip(" ;:") in why, (piece, why)


def test_readme_reverse_detour_example(work):
    text = _squash(_text(README))
    m = re.search(r"\(`(rrtdrive plan parking_lot --goal=[^`]+ --reverse)`\) is ([\d.]+) m "
                  r"with one gear change by default and the ([\d.]+) m forward loop with the "
                  r"option", text)
    command, default_m, option_m = m.groups()
    option = re.search(r"`(--planner-option reverse_detour_tree=false)`", text).group(1)
    r = _run(command, work)
    assert r.returncode == 0, r.stderr
    assert f"length {default_m} m, 1 gear change," in r.stderr + r.stdout
    r = _run(f"{command} {option}", work)
    assert r.returncode == 0, r.stderr
    out = r.stderr + r.stdout
    assert f"length {option_m} m," in out and "gear change" not in out


def test_readme_simulate_map_drives_another_path_than_plan(work, plan_parking_lot):
    m = re.search(r"\(`simulate parking_lot` drives a ([\d.]+) m path, `plan parking_lot` "
                  r"makes a ([\d.]+) m one\)", _squash(_text(README)))
    simulated, planned = m.groups()
    r = _run("rrtdrive simulate parking_lot --json -", work)
    assert r.returncode == 0, r.stderr
    assert f"{json.loads(r.stdout)['path_length_m']:.2f}" == simulated
    assert f"{plan_parking_lot['length_m']:.2f}" == planned


def test_readme_plan_then_simulate_the_given_path(work):
    commands = [c for c, _ in _fenced(README, "rrtdrive simulate parking --reverse-in")]
    chained = next(c for c in commands if "&&" in c)
    plan, simulate = (part.strip() for part in chained.split("&&"))
    r = _run(plan, work)
    assert r.returncode == 0, r.stderr
    plan_file = re.search(r"--json (\S+)", plan).group(1)
    assert (work / plan_file).is_file()
    r = _run(simulate + " --json -", work)
    assert r.returncode == 0, r.stderr
    doc = json.loads(r.stdout)
    # README: "the JSON says `"planner": "given"` and `path_file`"
    assert doc["planner"] == "given" and doc["path_file"].endswith(plan_file)
    assert doc["success"] is True


def test_planning_md_huge_map_error_line(work):
    text = _text(DOCS / "planning.md")
    flat = _squash(text)
    bounds = json.loads(re.search(r"a map file with bounds `(\[[^`]+\])`", flat).group(1))
    command = re.search(r"`(rrtdrive plan huge\.json)`", flat).group(1)
    shown = re.search(r"`(rrtdrive plan: error: bounds:[^`]+)`", flat).group(1)
    (work / "huge.json").write_text(json.dumps(
        {"name": "huge", "bounds": bounds, "obstacles": [], "start": [5, 5, 0],
         "goal": [50, 5, 0]}))
    r = _run(command, work)
    assert r.returncode == 2
    assert r.stdout == ""
    assert r.stderr.strip() == shown


def test_bench_md_baseline_curvature_and_its_verify(work):
    flat = _squash(_text(DOCS / "bench.md"))
    m = re.search(r"\(`(rrtdrive plan [^`]+ --json (\S+))` says max curvature ([\d.]+) 1/m; "
                  r"`(rrtdrive verify \S+)` measures its corners: ([\d.]+) 1/m\)", flat)
    plan, plan_file, said, verify, measured = m.groups()
    r = _run(plan, work)
    assert r.returncode == 0, r.stderr
    assert f"max curvature {said} 1/m" in r.stderr + r.stdout
    assert (work / plan_file).is_file()
    r = _run(verify, work)
    assert r.returncode == 1
    curvature = next(line for line in r.stdout.splitlines() if " curvature " in line)
    assert curvature.split()[0] == "FAIL" and f"{measured} 1/m" in curvature


def test_bench_md_ablation_grid_writes_the_listed_files(work):
    """bench.md's ablation command (1 seed instead of 20) writes every file its table lists."""
    text = _text(DOCS / "bench.md")
    command = next(c for c, _ in _fenced_commands(text) if "reverse_detour_tree=false" in c)
    command = re.sub(r"--seeds \d+", "--seeds 1", command)
    command = re.sub(r"--out \S+", "--out bench_detour", command)
    table = text[text.index("## What is written into `OUT`"):]
    table = table[: table.index("\n\n", table.index("|---"))]
    listed = {name for row in table.splitlines()[2:]
              for name in re.findall(r"`([\w.]+\.\w+)`", row.split("|")[1])}
    assert {"runs.jsonl", "summary.md", "curvature_hist.png"} <= listed
    r = _run(command, work)
    assert r.returncode == 0, r.stderr
    written = {p.name for p in (work / "bench_detour").iterdir()}
    assert listed <= written, f"listed in bench.md but not written: {sorted(listed - written)}"
    rows = [json.loads(line) for line in (work / "bench_detour" / "runs.jsonl").open()]
    planners = re.search(r"--planners (\S+)", command).group(1).split(",")
    assert sorted(r["planner"] for r in rows) == sorted(planners)
