"""``bench --config``: a flag's name as a key is pointed at the key, one file only, stdin.

Rough edges an audit found (session 50): ``jobs = 2`` got no hint (difflib finds no key
close to it), a second ``--config`` silently replaced the first, and ``--config -`` looked
for a file named ``-``.
"""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from rrtdrive.bench.config_file import FLAG_KEYS, load_toml
from rrtdrive.bench.grid import CONFIG_KEYS
from rrtdrive.types import InputError


def _bench(cwd, *args, stdin=None):
    return subprocess.run([sys.executable, "-m", "rrtdrive", "bench", *args], cwd=cwd,
                          input=stdin, capture_output=True, text=True, timeout=300)  # fmt: skip


@pytest.mark.parametrize(("written", "key"), [
    ("jobs", "workers"), ("max-time", "max_time_s"), ("max_time", "max_time_s"),
    ("run-timeout", "run_timeout_s"), ("max-iterations", "max_iterations"),
    ("--seeds", "seeds"),
])  # fmt: skip
def test_a_flag_written_as_a_key_is_pointed_at_its_key(tmp_path, written, key):
    f = tmp_path / "b.toml"
    f.write_text(f'"{written}" = 2\n')
    with pytest.raises(InputError) as err:
        load_toml(f)
    flag = "--" + written.lstrip("-").replace("_", "-")
    assert f"unknown key {written!r} (the flag {flag}; its key is {key!r})" in str(err.value)


def test_every_alias_names_a_real_key():
    assert set(FLAG_KEYS.values()) <= set(CONFIG_KEYS)


def test_a_misspelt_key_still_gets_did_you_mean(tmp_path):
    f = tmp_path / "b.toml"
    f.write_text("seedz = 2\n")
    with pytest.raises(InputError, match=r"unknown key 'seedz' \(did you mean 'seeds'\?\)"):
        load_toml(f)


def test_two_config_files_are_refused(tmp_path):
    for name in ("a.toml", "b.toml"):
        (tmp_path / name).write_text('maps = ["parking_lot"]\n')
    p = _bench(tmp_path, "--config", "a.toml", "--config", "b.toml")
    assert p.returncode == 2 and "Traceback" not in p.stderr
    assert "--config: given twice" in p.stderr
    assert not (tmp_path / "bench").exists()


def test_config_dash_reads_the_toml_from_stdin(tmp_path):
    toml = 'maps = ["parking_lot"]\nseeds = 1\nmax_iterations = 200\nplots = false\n'
    p = _bench(tmp_path, "--config", "-", "--out", "o", "--quiet", stdin=toml)
    assert p.returncode == 0, p.stderr
    rows = [json.loads(line) for line in (tmp_path / "o" / "runs.jsonl").read_text().splitlines()]
    assert [(r["map"], r["seed"], r["max_iterations"]) for r in rows] == [("parking_lot", 0, 200)]


def test_a_bad_value_on_stdin_is_named_as_from_stdin(tmp_path):
    p = _bench(tmp_path, "--config", "-", stdin='maps = ["parking_lot"]\nseeds = -1\n')
    assert p.returncode == 2 and "Traceback" not in p.stderr
    assert "(in 'stdin')" in p.stderr and "seeds" in p.stderr


def test_a_folder_as_config_says_why_once(tmp_path):
    with pytest.raises(InputError) as err:
        load_toml(tmp_path)
    assert str(err.value) == f"config: cannot read {str(tmp_path)!r}: Is a directory"
