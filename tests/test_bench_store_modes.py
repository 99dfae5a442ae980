"""A bench's ``runs.jsonl`` and its lock get the umask's mode, as every other output does.

They were created 0644 whatever the umask (``os.open(..., 0o644)``): a group sharing a
results folder under umask 002 could not append to it (an audit, session 50).
"""

from __future__ import annotations

import os

import pytest

from rrtdrive.bench.store import ResultStore


@pytest.mark.parametrize(("mask", "mode"), [(0o002, 0o664), (0o077, 0o600), (0o022, 0o644)])
def test_the_store_files_follow_the_umask(tmp_path, mask, mode):
    old = os.umask(mask)
    try:
        store = ResultStore(tmp_path / "out")
        store.append({"config_hash": "abc", "seed": 0, "success": True})
        store.close()
    finally:
        os.umask(old)
    for name in ("runs.jsonl", ".lock"):
        assert ((tmp_path / "out" / name).stat().st_mode & 0o777) == mode, name
