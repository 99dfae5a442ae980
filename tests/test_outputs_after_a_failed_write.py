"""An output that cannot be written does not cost the others: plan, verify and simulate.

``/dev/full`` fails every write with "No space left on device" after the command's own
checks have passed (a full disk). Each command writes every other output, prints its
summary, then names each failure and exits 1. Before, a failed ``plan --json`` lost the
``--plot`` and the summary, and a failed ``verify --plot`` lost the ``--json``.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

pytestmark = pytest.mark.skipif(not os.path.exists("/dev/full"), reason="needs /dev/full")

PNG = b"\x89PNG\r\n\x1a\n"


def _run(cwd, *args):
    return subprocess.run([sys.executable, "-m", "rrtdrive", *args], cwd=cwd,
                          capture_output=True, text=True, timeout=300)  # fmt: skip


@pytest.fixture(scope="module")
def plan_file(tmp_path_factory):
    d = tmp_path_factory.mktemp("plan")
    p = _run(d, "plan", "parking_lot", "--max-iterations", "300", "--json", "p.json")
    assert p.returncode == 0, p.stderr
    return d / "p.json"


def test_plan_writes_its_plot_and_summary_when_its_json_fails(tmp_path):
    p = _run(tmp_path, "plan", "parking_lot", "--max-iterations", "300",
             "--json", "/dev/full", "--plot", "p.png")  # fmt: skip
    assert p.returncode == 1
    assert (tmp_path / "p.png").read_bytes()[:8] == PNG
    assert "parking_lot: improved-rrt-connect seed 0: solved" in p.stdout
    assert p.stderr.strip().splitlines() == [
        "rrtdrive plan: error: --json: cannot write /dev/full: No space left on device"
    ]


def test_a_failed_json_leaves_no_temporary_file_beside_it(tmp_path):
    (tmp_path / "full.json").symlink_to("/dev/full")
    p = _run(tmp_path, "plan", "parking_lot", "--max-iterations", "300",
             "--json", "full.json", "--plot", "p.png")  # fmt: skip
    assert p.returncode == 1 and "solved" in p.stdout and "Traceback" not in p.stderr
    assert "--json: cannot write full.json: No space left on device" in p.stderr
    assert sorted(f.name for f in tmp_path.iterdir()) == ["full.json", "p.png"]


def test_plan_json_on_stdout_still_comes_when_the_plot_fails(tmp_path):
    (tmp_path / "full.png").symlink_to("/dev/full")
    p = _run(tmp_path, "plan", "parking_lot", "--max-iterations", "300",
             "--json", "-", "--plot", "full.png")  # fmt: skip
    assert p.returncode == 1
    assert json.loads(p.stdout)["status"] == "solved"
    assert "--plot: cannot write" in p.stderr and "solved" in p.stderr


def test_verify_writes_its_json_when_its_plot_fails(tmp_path, plan_file):
    (tmp_path / "full.png").symlink_to("/dev/full")
    p = _run(tmp_path, "verify", str(plan_file), "--plot", "full.png", "--json", "v.json")
    assert p.returncode == 1
    assert json.loads((tmp_path / "v.json").read_text())["ok"] is True
    assert "OK, every check passed" in p.stdout
    assert p.stderr.strip().splitlines()[-1].startswith(
        "rrtdrive verify: error: --plot: cannot write "
    )


def test_verify_draws_its_plot_when_its_json_fails(tmp_path, plan_file):
    p = _run(tmp_path, "verify", str(plan_file), "--plot", "v.png", "--json", "/dev/full")
    assert p.returncode == 1
    assert (tmp_path / "v.png").read_bytes()[:8] == PNG
    assert "--json: cannot write /dev/full" in p.stderr


def test_simulate_says_header_only_of_a_trajectory_it_wrote_not_of_one_it_could_not(tmp_path):
    # A drive that never starts (no iterations to plan with): its CSV is the header only.
    (tmp_path / "full.csv").symlink_to("/dev/full")
    common = ["simulate", "parking", "--max-iterations", "1", "--max-time", "2"]
    ok = _run(tmp_path, *common, "--trajectory", "t.csv", "--json", "s.json")
    assert ok.returncode == 1 and "the file has its header only" in ok.stderr
    assert (tmp_path / "t.csv").read_text().count("\n") == 1
    failed = _run(tmp_path, *common, "--trajectory", "full.csv", "--json", "s2.json")
    assert failed.returncode == 1 and "header only" not in failed.stderr
    assert "--trajectory: cannot write full.csv: No space left on device" in failed.stderr
    assert json.loads((tmp_path / "s2.json").read_text())["success"] is False
