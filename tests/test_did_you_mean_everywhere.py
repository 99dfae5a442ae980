"""A near-miss name or option is answered with the right one, wherever it is typed.

The session 51 bad-input sweep found lists of choices without a suggestion (``--disable
prun``, ``--lead-model idn``, ``--density hgih``, ``--predictor constant-velocty``, a
misspelt option) while other commands suggested (``simulate parkng``).
"""

from __future__ import annotations

import pytest

from rrtdrive.cli import main


def _cli(argv, capsys):
    capsys.readouterr()
    try:
        code = main(argv)
    except SystemExit as exc:  # argparse's own errors
        code = exc.code
    return code, capsys.readouterr().err


@pytest.mark.parametrize(("argv", "right", "field"), [
    (["plan", "parking_lot", "--disable", "prun"], "prune", "--disable"),
    (["simulate", "overtake-traffic", "--lead-model", "idn"], "idm", "--lead-model"),
    (["simulate", "overtake-traffic", "--density", "hgih"], "high", "--density"),
    (["simulate", "overtake-traffic", "--predictor", "constant-velocty"],
     "constant-velocity", "--predictor"),
    (["plan", "parking_lot", "--planner-option", "body_clearence=0.2"], "body_clearance",
     "--planner-option"),
    (["plan", "parking_lot", "--max-iteratons", "5"], "--max-iterations", "unrecognized"),
    (["verify", "p.json", "--no-sharpnss"], "--no-sharpness", "unrecognized"),
    (["simulate", "parking", "--contoller", "lqr"], "--controller", "unrecognized"),
    (["maps", "--exprt", "d"], "--export", "unrecognized"),
])  # fmt: skip
def test_the_right_name_is_suggested(argv, right, field, capsys):
    code, err = _cli(argv, capsys)
    assert code == 2 and "Traceback" not in err
    line = err.strip()
    assert "\n" not in line and field in line
    assert f"(did you mean {right!r}?)" in line, line


def test_a_name_close_to_nothing_gets_no_suggestion(capsys):
    code, err = _cli(["simulate", "overtake-traffic", "--lead-model", "zzzz"], capsys)
    assert code == 2 and "did you mean" not in err
    code, err = _cli(["plan", "parking_lot", "--zzzz-qqq", "1"], capsys)
    assert code == 2 and "did you mean" not in err and "--zzzz-qqq" in err


def test_a_car_field_is_suggested_and_null_is_said_in_jsons_words():
    from rrtdrive.types import InputError
    from rrtdrive.vehicle_json import vehicle_from_json

    with pytest.raises(InputError, match=r"\['lenght'\] \(did you mean 'length'\?\)"):
        vehicle_from_json({"lenght": 3.0})
    with pytest.raises(InputError, match=r"got null$"):
        vehicle_from_json(None)
