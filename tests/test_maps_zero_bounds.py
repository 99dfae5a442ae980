"""A map whose bounds have zero width or zero height is bad input naming ``bounds``.

Mutation audit, session 35: ``Map.__post_init__``'s ``b[2] <= b[0]`` loosened to
``b[2] < b[0]`` survived every test: a zero-width region (xmin == xmax) got past the
bounds check, to fail later naming the start instead (or not at all without the query
check). Here both degenerate boxes raise InputError naming ``bounds``, with and without
the query check, and ``rrtdrive plan FILE`` of such a map exits 2 with one stderr line
naming bounds and no traceback (the contract of tests/test_cli_bad_input.py).
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from rrtdrive.cli import main
from rrtdrive.maps import Map
from rrtdrive.types import InputError, Pose

# (xmin, ymin, xmax, ymax): zero width, zero height.
FLAT = [(0.0, 0.0, 0.0, 10.0), (0.0, 0.0, 10.0, 0.0)]


@pytest.mark.parametrize("bounds", FLAT, ids=["zero-width", "zero-height"])
@pytest.mark.parametrize("check_query", [True, False])
def test_a_flat_box_is_refused_naming_bounds(
    bounds: tuple[float, float, float, float], check_query: bool
) -> None:
    pose = Pose(0.0, 0.0, 0.0)  # on the box's edge: only the bounds can be at fault first
    with pytest.raises(InputError, match=r"^bounds: "):
        Map("flat", bounds, (), pose, pose, check_query=check_query)


@pytest.mark.parametrize("bounds", FLAT, ids=["zero-width", "zero-height"])
def test_plan_of_a_flat_map_file_exits_2_naming_bounds(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], bounds: tuple[float, ...]
) -> None:
    doc = {"name": "flat", "bounds": list(bounds), "obstacles": [],
           "start": [0.0, 0.0, 0.0], "goal": [0.0, 5.0, 0.0]}  # fmt: skip
    f = tmp_path / "flat.json"
    f.write_text(json.dumps(doc), encoding="utf-8")
    code = main(["plan", str(f)])
    _, err = capsys.readouterr()
    assert code == 2, err
    assert "Traceback" not in err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    # The field itself ("...: bounds: need xmin < xmax ..."), not a later check that
    # mentions the bounds ("start: the car's body ... touches the bounds").
    assert re.search(r"(^|: )bounds: ", lines[0]), lines[0]
