"""A tree path whose turns crowd each other fails with the numbers that decided it.

``leg_room`` is what the failure message reports; the property ties it to the test
that failed the curve (``polygon_turns``' conflicts), on random polygons.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rrtdrive.maps import load_map
from rrtdrive.planning import make_planner
from rrtdrive.planning.base import PlanningProblem
from rrtdrive.planning.smoothing import SmoothingConfig
from rrtdrive.planning.smoothing.clothoid import sharpness_levels
from rrtdrive.planning.smoothing.clothoid_curve import leg_room, polygon_turns
from rrtdrive.planning.smoothing.config import CurveKind
from rrtdrive.planning.smoothing.corners import Corner, CornerKind
from rrtdrive.planning.smoothing.curve import CurveFitter
from rrtdrive.types import Budget

LEVELS = sharpness_levels(0.2, 0.02, 2.51, 0.98)
HOME_GARAGE = Path(__file__).resolve().parents[1] / "docs" / "maps" / "home_garage.json"

points = st.tuples(st.floats(-30.0, 30.0), st.floats(-30.0, 30.0))


@settings(max_examples=200, deadline=None)
@given(st.lists(points, min_size=3, max_size=7), st.floats(0.0, 1.0))
def test_leg_room_says_which_legs_polygon_turns_refuses(pts, end_gap):
    kappas = [1.0 / 6.0] * len(pts)
    _, conflicts = polygon_turns(pts, kappas, LEVELS, [False] * len(pts), end_gap)
    short = []
    for leg in range(len(pts) - 1):
        length, need, turn_a, turn_b = leg_room(pts, kappas, LEVELS, end_gap, leg)
        assert length == pytest.approx(math.dist(pts[leg], pts[leg + 1]), abs=1e-9)
        assert abs(turn_a) <= math.pi + 1e-12 and abs(turn_b) <= math.pi + 1e-12
        if not need <= length + 1e-9:
            short.append(leg)
    assert short == conflicts


def test_a_single_turn_needs_its_tangent_and_the_end_gap():
    # A right angle 5 m after the start: the straight kept at the start (0.5 m) and the
    # tightest 90-degree clothoid turn's tangent, more than the radius (6 m) alone.
    pts = [(0.0, 0.0), (5.0, 0.0), (5.0, 20.0)]
    length, need, turn_a, turn_b = leg_room(pts, [0.0, 1 / 6, 0.0], LEVELS, 0.5, 0)
    assert (length, turn_a) == (5.0, 0.0)
    assert math.degrees(turn_b) == 90.0
    assert 6.0 + 0.5 < need < 6.0 + 0.5 + 3.0
    no_gap = leg_room(pts, [0.0, 1 / 6, 0.0], LEVELS, 0.0, 0)[1]
    assert need - no_gap == 0.5


def test_the_failure_message_names_the_turn_and_what_it_needs():
    m = load_map(HOME_GARAGE)
    out = make_planner("improved-rrt-connect", escalation=False).solve(
        PlanningProblem.from_map(m), np.random.default_rng(0), Budget(max_iterations=3000)
    )
    assert not out.success
    found = re.search(
        r"turns (\d+) deg (left|right) at \(([\d.]+), ([\d.]+)\), ([\d.]+) m after the start; "
        r"from the start's heading the car's tightest turn needs ([\d.]+) m",
        out.message,
    )
    assert found, out.message
    deg, side, x, y, length, need = found.groups()
    assert side == "left"  # the bay is to the car's left
    assert float(need) > float(length)
    # The turn lies on the start's heading line (y = 6), the stated length from the start.
    assert float(y) == m.start.y
    assert abs(float(length) - (float(x) - m.start.x)) <= 0.1
    assert 45 <= int(deg) <= 135
    assert "are too close for the car" not in out.message


@settings(max_examples=200, deadline=None)
@given(st.lists(points, min_size=3, max_size=7), st.sampled_from([0.0, 3.0, 6.0]))
def test_the_paper_fillets_leg_room_says_which_legs_control_points_refuses(pts, radius):
    cfg = SmoothingConfig(curve=CurveKind.BSPLINE)
    fitter = CurveFitter(cfg, None, None)  # type: ignore[arg-type]  # the polygon only
    corners = [Corner.at(np.array(p, dtype=float), CornerKind.NODE, i) for i, p in enumerate(pts)]
    corners[0].kind, corners[-1].kind = CornerKind.START, CornerKind.GOAL
    for c in corners[1:-1]:
        c.radius = radius
    conflicts = fitter.control_points(corners)[2]
    short = []
    for leg in range(len(pts) - 1):
        length, need, _, _ = fitter.leg_room(corners, leg)
        if need - length > 1e-9:
            short.append(leg)
    assert short == conflicts


def test_the_paper_fillets_start_leg_keeps_the_end_gap():
    def room(length, end_gap):
        cfg = SmoothingConfig(curve=CurveKind.BSPLINE, end_gap=end_gap)
        fitter = CurveFitter(cfg, None, None)  # type: ignore[arg-type]  # the polygon only
        pts = [(0.0, 0.0), (length, 0.0), (length, 20.0)]
        kinds = [CornerKind.START, CornerKind.NODE, CornerKind.GOAL]
        pairs = enumerate(zip(pts, kinds, strict=True))
        corners = [Corner.at(np.array(p), k, i) for i, (p, k) in pairs]
        corners[1].radius = 6.0
        return fitter.leg_room(corners, 0), fitter.control_points(corners)[2]

    (_, bare, _, turn), _ = room(30.0, 0.0)
    assert math.degrees(turn) == 90.0
    # A start leg a little longer than the fillet's reach, shorter than reach + gap.
    (length, need, _, _), conflicts = room(bare + 0.25, 0.5)
    assert need == bare + 0.5 and need > length
    assert 0 in conflicts


@pytest.mark.parametrize("deg", [150.0, 179.0])
def test_a_hairpin_is_named_as_one_not_by_a_runaway_tangent(deg):
    # A tree path that doubles back: rounding the corner needs R tan(deflection / 2), which
    # the message quoted as "6177.8 m between them" at 179.9 deg (an audit). The words say
    # what it takes instead; below the hairpin the needed length stays.
    from rrtdrive.planning.smoothing.drivable import turns_too_close

    turn = math.radians(deg)
    pts = [(0.0, 0.0), (10.0, 0.0), (10.0 + 20.0 * math.cos(turn), 20.0 * math.sin(turn)),
           (0.0, 30.0)]
    kinds = [CornerKind.START, CornerKind.NODE, CornerKind.NODE, CornerKind.GOAL]
    cs = [Corner.at(np.array(p), k, i) for i, (p, k) in enumerate(zip(pts, kinds, strict=True))]
    room = leg_room(pts, [0.0, 1 / 6, 1 / 6, 0.0], LEVELS, 0.5, 0)
    assert math.degrees(abs(room[3])) == pytest.approx(deg)
    text = turns_too_close(cs, 0, room)
    assert f"a corner of {deg:.0f} deg doubles back" in text and "needs" not in text
    gentle = turns_too_close(cs, 0, (room[0], 7.4, 0.0, math.radians(120.0)))
    assert "needs 7.4 m" in gentle and "doubles back" not in gentle
