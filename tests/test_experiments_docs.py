"""Experiment scripts leave the committed docs alone unless --doc / --figures name them."""

from __future__ import annotations

import hashlib
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
EXPERIMENTS = ROOT / "experiments"
DOCS = ROOT / "docs"


def _docs_digest() -> dict[str, tuple[int, str]]:
    return {
        str(p.relative_to(DOCS)): (p.stat().st_mtime_ns, hashlib.sha256(p.read_bytes()).hexdigest())
        for p in sorted(DOCS.rglob("*"))
        if p.is_file()
    }


def test_no_experiment_defaults_to_a_docs_target():
    for script in sorted(EXPERIMENTS.glob("*.py")):
        text = script.read_text()
        assert not re.search(r"default\s*=\s*[\"']docs/", text), script.name


@pytest.mark.skipif(not DOCS.is_dir(), reason="needs the repository's docs/")
def test_table3_into_elsewhere_leaves_docs_untouched(tmp_path):
    before = _docs_digest()
    proc = subprocess.run(
        [sys.executable, str(EXPERIMENTS / "table3.py"), "--runs", "1", "--maps", "overtake",
         "--max-time", "1", "--out", str(tmp_path)],
        capture_output=True, text=True, check=False, cwd=ROOT, timeout=300,
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert (tmp_path / "table3.md").is_file() and (tmp_path / "table3.json").is_file()
    assert _docs_digest() == before
    # What it prints links the figures as written, no placeholder left.
    assert "@@" not in proc.stdout and "@@" not in (tmp_path / "table3.md").read_text()
    links = re.findall(r"\]\(([^)]+\.png)\)", proc.stdout)
    assert links and all((ROOT / link).resolve().is_file() for link in links)


README = ROOT / "README.md"


@pytest.mark.skipif(not README.is_file(), reason="needs the repository's README.md")
def test_readme_lists_every_disable_component():
    from rrtdrive.planning.improved import COMPONENTS

    text = README.read_text()
    for name in COMPONENTS:
        assert f"`{name}`" in text, name


@pytest.mark.skipif(not (ROOT / ".ci" / "run").is_file(), reason="needs .ci/run")
def test_readme_test_command_is_the_ci_one():
    ci = (ROOT / ".ci" / "run").read_text()
    install = re.search(r'pip install --quiet "([^"]+)"', ci).group(1)
    assert "python -m pytest -q -n auto tests" in ci
    assert f'pip install "{install}" && python -m pytest -q -n auto tests' in README.read_text()
