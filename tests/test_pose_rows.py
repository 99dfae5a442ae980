"""Paths from poses alone (``[x, y, yaw]`` rows of another planner): gears, cusps, kappa.

References: arcs built in closed form with a known curvature and gear (hypothesis), and
our planners' own reversing paths, whose gear and kappa columns come from other code.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rrtdrive.maps import Map, builtin_map
from rrtdrive.planning import PlanningProblem, make_planner
from rrtdrive.pose_rows import path_from_poses
from rrtdrive.types import Budget, InputError, Pose
from rrtdrive.verify import path_from_json, verify_path

KAPPA_MAX = 1 / 6


def _arc_rows(x: float, y: float, yaw: float, kappa: float, gear: int, length: float,
              step: float) -> np.ndarray:
    """Rear-axle poses along an arc of steering curvature ``kappa`` driven in ``gear``.

    Travelling ``s`` metres in reverse turns the nose by ``-kappa s`` (kappa is the
    steering's curvature in both gears); positions in closed form.
    """
    s = np.linspace(0.0, length, max(2, math.ceil(length / step) + 1))
    turn = gear * kappa * s
    heading = yaw if gear > 0 else yaw + math.pi  # direction of travel at s = 0
    if abs(kappa) < 1e-12:
        xs, ys = x + s * math.cos(heading), y + s * math.sin(heading)
    else:
        r = 1.0 / (gear * kappa)
        xs = x + r * (np.sin(heading + turn) - math.sin(heading))
        ys = y - r * (np.cos(heading + turn) - math.cos(heading))
    return np.column_stack([xs, ys, yaw + turn])


pieces = st.lists(
    st.tuples(st.floats(-KAPPA_MAX, KAPPA_MAX), st.sampled_from([1, -1]), st.floats(1.0, 6.0)),
    min_size=1, max_size=5,
)


@settings(max_examples=60, deadline=None)
@given(pieces, st.booleans())
def test_gears_cusps_and_kappa_of_closed_form_arcs(parts, repeat_cusp_rows):
    rows, gears, kappas = [], [], []
    x, y, yaw = 0.0, 0.0, 0.3
    for kappa, gear, length in parts:
        arc = _arc_rows(x, y, yaw, kappa, gear, length, 0.2)
        start = 0 if not rows else (0 if repeat_cusp_rows and gear != gears[-1] else 1)
        rows.extend(arc[start:])
        gears.extend([gear] * (len(arc) - start))
        kappas.extend([kappa] * (len(arc) - start))
        x, y, yaw = arc[-1]
    path = path_from_poses(np.array(rows))
    s = path.samples
    # Gear changes: exactly where the pieces change gear, each row repeated once.
    changes = sum(a[1] != b[1] for a, b in zip(parts, parts[1:], strict=False))
    assert len(path.cusps) == changes
    for c in path.cusps:
        assert np.allclose(s[c, :3], s[c - 1, :3])
    # Each row's gear and kappa are its piece's (a row shared by two pieces: either).
    moving = np.hypot(*np.diff(s[:, :2], axis=0).T) > 1e-9
    for i in np.flatnonzero(moving):
        travel = math.atan2(s[i + 1, 1] - s[i, 1], s[i + 1, 0] - s[i, 0])
        nose = s[i, 2] if s[i, 4] > 0 else s[i, 2] + math.pi
        assert abs(math.remainder(travel - nose, math.tau)) < 0.1  # the gear of the motion
    expected = set(kappas)
    for k in s[:, 3]:
        # Turn over chord is kappa (x/2)/sin(x/2): under 1e-4 relative at these steps.
        assert min(abs(k - e) for e in expected) <= 1e-4 * KAPPA_MAX + 1e-12, (k, expected)


@pytest.mark.parametrize("name", ["kerbside", "reverse_bay"])
def test_a_reversing_plan_without_its_columns_comes_back_with_them(name):
    m = builtin_map(name)
    problem = PlanningProblem.from_map(m, reverse=True)
    res = make_planner("hybrid-a-star").solve(problem, np.random.default_rng(0), Budget())
    assert res.success and res.path.cusps.size >= 1
    full = res.path.samples
    # As another planner writes it: poses only, a cusp's pose once.
    keep = np.ones(len(full), dtype=bool)
    keep[res.path.cusps] = False
    back = path_from_poses(full[keep, :3]).samples
    assert back.shape == full.shape
    assert np.array_equal(back[:, 4], full[:, 4])  # every row's gear, cusps repeated
    assert np.allclose(back[:, :3], full[:, :3])
    # kappa from the yaw's turn over each step, against the planner's steering curvature:
    # within the change of curvature over one step (sharpness <= 0.2 rad/m in steering).
    assert np.max(np.abs(back[:, 3] - full[:, 3])) < 0.03
    check = verify_path(m, path_from_json({"path": full[keep, :3].tolist()}), max_sharpness=0.2)
    assert check.ok, check.failed


@pytest.mark.parametrize("noise", [0.0, 1e-9])
def test_a_cusp_written_twice_comes_out_once_per_gear(noise):
    # Three pieces, each cusp's pose written twice (the second copy off by float
    # noise, as another planner's output may be): the rows are the pieces' own.
    parts = [(0.05, -1, 3.0), (0.125, 1, 3.0), (-0.1, -1, 3.0)]
    rows, gears, kappas = [], [], []
    x, y, yaw = 10.0, 10.0, 0.0
    for kappa, gear, length in parts:
        arc = _arc_rows(x, y, yaw, kappa, gear, length, 0.25)
        if rows:
            arc[0] += (noise * 1e-3, 0.0, noise)  # 1e-12 m, 1e-9 rad
        rows.extend(arc)
        gears.extend([gear] * len(arc))
        kappas.extend([kappa] * len(arc))
        x, y, yaw = arc[-1]
    s = path_from_poses(np.array(rows)).samples
    assert s[:, 4].tolist() == gears
    assert np.allclose(s[:, :2], np.array(rows)[:, :2])
    assert np.allclose(s[:, 3], kappas, rtol=1e-4, atol=1e-9)


def test_poses_without_motion_are_forward_and_bad_shapes_are_named():
    still = path_from_poses([[1.0, 1.0, 0.0], [1.0, 1.0, 0.0]])  # one pose, written twice
    assert still.samples.tolist() == [[1.0, 1.0, 0.0, 0.0, 1.0]]
    turn = path_from_poses([[1.0, 1.0, 0.0], [1.0, 1.0, 0.5]])  # a turn in place stays
    assert turn.samples[:, 4].tolist() == [1.0, 1.0] and turn.samples[:, 3].tolist() == [0, 0]
    # Backing straight up from the start: reverse from the first row.
    back = path_from_poses([[5.0, 0.0, 0.0], [4.9, 0.0, 0.0], [4.8, 0.0, 0.0]])
    assert back.samples[:, 4].tolist() == [-1.0, -1.0, -1.0]
    # A first step without motion (a turn in place) takes the next one's gear and kappa.
    back = path_from_poses([[5.0, 0.0, 0.0], [5.0, 0.0, 0.1], [4.9, 0.0, 0.1]])
    assert back.samples[:, 4].tolist() == [-1.0, -1.0, -1.0]
    assert back.samples[:, 3].tolist() == [0.0, 0.0, 0.0]
    # In the middle: the still step takes the step before it, not the first step's.
    mid = path_from_poses([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.2], [2.0, 0.0, 0.3],
                           [3.0, 0.0, 0.3]]).samples
    assert mid[2, 3] == pytest.approx(0.2) and mid[3, 3] == 0.0
    for bad in ([[0.0, 0.0]], [[0.0, 0.0, float("nan")], [1.0, 0.0, 0.0]], [1.0, 2.0, 3.0]):
        with pytest.raises(InputError, match=r"^path: expected rows \[x, y, yaw\]"):
            path_from_poses(bad)


def test_verify_reads_pose_rows_and_says_their_kappa_was_not_given(tmp_path, capsys):
    import json

    from rrtdrive.cli import main

    m = Map("open", (0.0, 0.0, 40.0, 20.0), (), Pose(5.0, 10.0, 0.0), Pose(15.0, 10.0, 0.0))
    mf = tmp_path / "open.json"
    mf.write_text(json.dumps(m.to_json()))
    xs = np.arange(5.0, 15.0001, 0.2)
    f = tmp_path / "p.json"
    f.write_text(json.dumps({"path": [[x, 10.0, 0.0] for x in xs]}))
    assert main(["verify", str(f), str(mf), "--json", str(tmp_path / "v.json")]) == 0
    out = capsys.readouterr().out
    assert "not given: rows [x, y, yaw], gears and kappa read off the motion" in out
    doc = json.loads((tmp_path / "v.json").read_text())
    assert doc["kappa_given"] is False and doc["rows"] == len(xs) and doc["cusps"] == 0
