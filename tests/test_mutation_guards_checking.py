"""Guards found by mutation testing of rrtdrive.checking.implements (the contract look-up)."""

from __future__ import annotations

import pytest

from rrtdrive.checking import Checker, MotionValidator, PoseValidityChecker, implements


def _public(*protocols: type) -> set[str]:
    """Public names defined or annotated in the protocols' own class bodies."""
    names: set[str] = set()
    for proto in protocols:
        names |= {n for n in (*vars(proto), *vars(proto).get("__annotations__", {}))
                  if not n.startswith("_")}  # fmt: skip
    return names


ALL = _public(PoseValidityChecker, MotionValidator, Checker)


def _stand_in(names: set[str]) -> object:
    """An instance of a fresh class defining exactly ``names`` (each a plain attribute)."""
    return type("StandIn", (), dict.fromkeys(names, None))()


def test_every_member_of_every_protocol_makes_a_checker():
    assert {"pose_free", "edge_free", "passage_cells", "vehicle"} <= ALL
    assert implements(_stand_in(ALL), Checker)


@pytest.mark.parametrize("missing", ["pose_free", "vehicle", "edge_free", "path_free",
                                     "passage_cells", "clearance"])
def test_a_checker_without_one_member_of_an_extended_protocol_is_none(missing):
    # Checker extends PoseValidityChecker and MotionValidator: their members count too.
    assert not implements(_stand_in(ALL - {missing}), Checker)


def test_one_member_is_not_enough():
    assert not implements(_stand_in({"edge_free"}), MotionValidator)
    assert implements(_stand_in({"edge_free", "path_free"}), MotionValidator)
