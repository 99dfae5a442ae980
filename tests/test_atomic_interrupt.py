"""atomic_target cleans up after Ctrl-C and sys.exit too, not only after errors.

Mutation audit, session 35: ``atomic_target``'s ``except BaseException`` narrowed to
``except Exception`` survived every test, yet it leaves the hidden temporary file
behind when the write is interrupted (KeyboardInterrupt, SystemExit are no Exception).
The contract: the interruption propagates, the folder holds only the original file,
and the original's content is unchanged.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from rrtdrive.atomic import atomic_target

ORIGINAL = "the original content\n"


@pytest.mark.parametrize("interrupt", [KeyboardInterrupt, SystemExit])
def test_an_interrupted_write_leaves_the_original_alone_and_no_temp_file(
    tmp_path: Path, interrupt: type[BaseException]
) -> None:
    target = tmp_path / "plan.json"
    target.write_text(ORIGINAL, encoding="utf-8")
    written: list[Path] = []
    with pytest.raises(interrupt):
        with atomic_target(target) as tmp:
            written.append(tmp)
            tmp.write_text("half a new fi", encoding="utf-8")
            raise interrupt()
    assert written and written[0].parent == tmp_path  # the temp file was beside the target
    assert sorted(p.name for p in tmp_path.iterdir()) == ["plan.json"]
    assert target.read_text(encoding="utf-8") == ORIGINAL


@pytest.mark.parametrize("interrupt", [KeyboardInterrupt, SystemExit])
def test_an_interrupted_first_write_creates_nothing(
    tmp_path: Path, interrupt: type[BaseException]
) -> None:
    # No file there before: after the interruption there is still none, and no temp file.
    target = tmp_path / "new.txt"
    with pytest.raises(interrupt):
        with atomic_target(target) as tmp:
            tmp.write_text("partial", encoding="utf-8")
            raise interrupt()
    assert list(tmp_path.iterdir()) == []
