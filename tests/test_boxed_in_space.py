"""A boxed-in end names the space along its heading, as a user measures a kerbside gap."""

from __future__ import annotations

import pytest
import shapely

from rrtdrive.maps import Map, Obstacle
from rrtdrive.planning.base import PlanningProblem
from rrtdrive.planning.diagnosis import DiagnosisKind, diagnose
from rrtdrive.types import Pose, VehicleParams

CAR = VehicleParams()


def box(o: Obstacle) -> shapely.Polygon:
    (cx, cy), (length, width) = o.center, o.size
    return shapely.box(cx - length / 2, cy - width / 2, cx + length / 2, cy + width / 2)


@pytest.mark.parametrize("gap", [4.52, 5.0, 6.0])
def test_the_space_is_the_gap_between_the_parked_cars(gap):
    x0 = 20.0
    parked = (Obstacle((x0 - gap / 2 - 2.15, 2.0), (4.3, 1.8)),
              Obstacle((x0 + gap / 2 + 2.15, 2.0), (4.3, 1.8)))  # fmt: skip
    # The goal's body centred in the gap (the rear axle 1.255 m behind the body's centre).
    centre_to_axle = CAR.length / 2 - CAR.rear_overhang
    m = Map("gap", (0.0, 0.0, 40.0, 15.0), parked, Pose(5.0, 8.0, 0.0),
            Pose(x0 - centre_to_axle, 2.0, 0.0))  # fmt: skip
    found = diagnose(PlanningProblem.from_map(m))
    assert found is not None and found.kind is DiagnosisKind.BOXED_IN
    between = shapely.distance(box(parked[0]), box(parked[1]))
    assert found.numbers["space_along_m"] == pytest.approx(between, abs=0.01)
    space = found.numbers["space_along_m"]
    assert f"the space is {space:.2f} m, {space / CAR.length:.2f} car lengths" in found.message
