"""verify_path's curvature gate at its edge: just over kappa_max fails, just under passes.

Mutation audit, session 35: the gate ``max_k <= kappa_max + curvature_tol`` loosened to
``<= 1.1 * kappa_max + curvature_tol`` survived every test (the only tight-turn test
drives 1.5 kappa_max). Here arcs sampled from the closed-form circle, 0.2 m apart,
curve at 1.05 and 0.97 kappa_max. Both discrete measures of verify read exactly 1/R on
such an arc (three points of a circle have circumradius R; a chord 2 R sin(turn / 2)
turns by ``turn``), so the gate alone decides.

With the default car (kappa_max 1/6) and the default slack 0.01 1/m, 1.05 kappa_max
(0.175) lies inside the slack (0.1767) by design; the edge is tested with the slack set
to 0, and with the default slack on a car of kappa_max 1/3, where 5 % is beyond it.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from rrtdrive.maps import Map
from rrtdrive.types import Path, Pose, VehicleParams
from rrtdrive.verify import verify_path

SPACING = 0.2  # metres of arc between rows


def _arc(radius: float) -> tuple[np.ndarray, Pose, Pose]:
    """Rows ``[x, y, yaw, kappa, gear]`` of a left quarter circle from (30, 20) heading +x."""
    n = math.ceil(radius * (math.pi / 2) / SPACING)
    s = np.linspace(0.0, radius * math.pi / 2, n + 1)  # at most SPACING apart along the arc
    yaw = s / radius
    x = 30.0 + radius * np.sin(yaw)
    y = 20.0 + radius * (1.0 - np.cos(yaw))
    rows = np.column_stack([x, y, yaw, np.full_like(s, 1.0 / radius), np.ones_like(s)])
    return rows, Pose(30.0, 20.0, 0.0), Pose(float(x[-1]), float(y[-1]), float(yaw[-1]))


def _check(car: VehicleParams, factor: float, **kwargs: float) -> tuple[bool, float, tuple]:
    """Verify an arc of curvature ``factor * kappa_max`` on an empty 80 m x 80 m map."""
    rows, start, goal = _arc(1.0 / (factor * car.kappa_max))
    m = Map("edge", (0.0, 0.0, 80.0, 80.0), (), start, goal, vehicle=car)
    check = verify_path(m, Path(rows, rows[:, :2]), **kwargs)
    return check.curvature_ok, check.max_discrete_curvature, check.failed


@pytest.mark.parametrize(
    ("car", "kwargs"),
    [
        (VehicleParams(), {"curvature_tol": 0.0}),
        # kappa_max 1/3: 2.51 / tan(45 deg) = 2.51 m <= 3 m, the steering reaches it.
        (VehicleParams(min_turning_radius=3.0, max_steer=math.radians(45.0)), {}),
    ],
    ids=["default-car-no-slack", "tight-car-default-slack"],
)
def test_an_arc_5_percent_over_kappa_max_fails_and_3_percent_under_passes(
    car: VehicleParams, kwargs: dict[str, float]
) -> None:
    ok, k, failed = _check(car, 1.05, **kwargs)
    # The measure itself is the circle's curvature (independent of the gate).
    assert k == pytest.approx(1.05 * car.kappa_max, rel=1e-6)
    assert not ok and failed == ("curvature_ok",), failed
    ok, k, failed = _check(car, 0.97, **kwargs)
    assert k == pytest.approx(0.97 * car.kappa_max, rel=1e-6)
    assert ok and failed == (), failed
