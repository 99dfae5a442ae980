"""Every option of the experiment scripts says what it does in ``--help``.

The check that every ``add_argument`` call has a ``help`` keyword is an ast scan of
every script (fast). ``python experiments/X.py --help`` runs as a subprocess for a
few scripts only: each imports heavy libraries (highway-env, shapely, ...), about
2-3 s a script, and all of them would take minutes.
"""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
EXPERIMENTS = ROOT / "experiments"

#: The scripts that build an argparse parser.
SCRIPTS = sorted(
    p.name for p in EXPERIMENTS.glob("*.py") if "add_argument" in p.read_text(encoding="utf-8")
)
#: Scripts whose ``--help`` actually runs, one per parser style in use: RawTextHelpFormatter
#: (closed_loop, traffic), a shared option helper with an f-string help (street_turns),
#: a long default (coverage), a plain parser (bench_reeds_shepp).
RUN_HELP = ("bench_reeds_shepp.py", "closed_loop.py", "coverage.py", "street_turns.py",
            "traffic.py")


def _add_argument_calls(script: str) -> list[ast.Call]:
    tree = ast.parse((EXPERIMENTS / script).read_text(encoding="utf-8"), filename=script)
    return [
        node for node in ast.walk(tree)
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute)
        and node.func.attr == "add_argument"
    ]


def _name(call: ast.Call) -> str:
    flags = [a.value for a in call.args if isinstance(a, ast.Constant)]
    return "/".join(map(str, flags)) or f"line {call.lineno}"


def _suppressed(call: ast.Call) -> bool:
    return any(
        k.arg == "help" and isinstance(k.value, ast.Attribute) and k.value.attr == "SUPPRESS"
        for k in call.keywords
    )


def test_scripts_found():
    assert len(SCRIPTS) >= 40, SCRIPTS
    assert set(RUN_HELP) <= set(SCRIPTS)


@pytest.mark.parametrize("script", SCRIPTS)
def test_every_option_has_help(script):
    calls = _add_argument_calls(script)
    assert calls, script
    bare = [
        f"{_name(c)} (line {c.lineno})" for c in calls
        if not any(k.arg == "help" for k in c.keywords)
    ]
    assert not bare, f"{script}: options without help=: {', '.join(bare)}"


@pytest.mark.parametrize("script", RUN_HELP)
def test_help_runs_and_lists_every_option(script):
    proc = subprocess.run(
        [sys.executable, str(EXPERIMENTS / script), "--help"],
        capture_output=True, text=True, check=False, cwd=ROOT, timeout=60,
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert proc.stdout.startswith("usage:"), proc.stdout[:200]
    for call in _add_argument_calls(script):
        if _suppressed(call):
            continue
        for flag in call.args:
            if isinstance(flag, ast.Constant) and str(flag.value).startswith("--"):
                assert flag.value in proc.stdout, f"{script}: {flag.value} not in --help"
