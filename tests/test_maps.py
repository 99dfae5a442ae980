from __future__ import annotations

import json
import math
import warnings

import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

from rrtdrive.maps import (
    BUILTIN_MAPS,
    TIGHT_MAP_NAMES,
    Map,
    Obstacle,
    builtin_map,
    load_map,
    map_from_json,
    resolve_map,
    save_map,
)
from rrtdrive.types import InputError, InputWarning, Pose, VehicleParams


@pytest.mark.parametrize("name", sorted(set(BUILTIN_MAPS) - set(TIGHT_MAP_NAMES)))
def test_builtins_are_valid_100m_maps(name):
    m = builtin_map(name)
    assert m.bounds == (0.0, 0.0, 100.0, 100.0)
    assert m.name == name
    assert len(m.obstacles) >= 2


def test_parking_lot_is_complex(parking_lot):
    assert len(parking_lot.obstacles) > 100
    start, goal = parking_lot.start, parking_lot.goal
    assert math.hypot(goal.x - start.x, goal.y - start.y) > 80
    # Parked cars of the paper's size and some larger solid blocks.
    sizes = {o.size for o in parking_lot.obstacles}
    assert (4.3, 1.8) in sizes
    assert any(s[0] * s[1] > 50 for s in sizes)


def test_roundtrip(tmp_path):
    for name in BUILTIN_MAPS:
        m = builtin_map(name)
        save_map(m, tmp_path / f"{name}.json")
        again = load_map(tmp_path / f"{name}.json")
        assert again == m
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(f"{n}.json" for n in BUILTIN_MAPS)


def _base():
    return {
        "name": "t",
        "bounds": [0, 0, 50, 50],
        "obstacles": [{"center": [25.0, 25.0], "size": [4.0, 2.0], "yaw": 0.3}],
        "start": [5.0, 5.0, 0.0],
        "goal": [40.0, 40.0, 1.0],
    }


@pytest.mark.parametrize(
    "patch, field",
    [
        ({"bounds": [0, 0, -5, 50]}, "bounds"),
        ({"bounds": [0, 0, 50]}, "bounds"),
        ({"bounds": "big"}, "bounds"),
        ({"start": [5.0, 5.0]}, "start"),
        ({"start": [5.0, "a", 0.0]}, "start"),
        ({"start": [500.0, 5.0, 0.0]}, "start"),
        ({"goal": [25.0, 25.0, 0.0]}, "goal"),
        ({"goal": [49.5, 40.0, 0.0]}, "goal"),
        ({"start": [5.0, float("nan"), 0.0]}, "start"),
        ({"goal": [40.0, float("inf"), 0.0]}, "goal"),
        ({"obstacles": [{"center": [1, 1], "size": [0, 2]}]}, r"obstacles\[0\]\.size"),
        ({"obstacles": [{"center": [1, 1], "size": [-1, 2]}]}, r"obstacles\[0\]\.size"),
        ({"obstacles": [{"center": [1], "size": [1, 2]}]}, r"obstacles\[0\]\.center"),
        ({"obstacles": [{"center": [1, 1], "size": [1, 2], "colour": 3}]}, "obstacles"),
        ({"obstacles": {"center": [1, 1]}}, "obstacles"),
        ({"extra": 1}, "unknown key"),
        # Far from the origin doubles lose the micrometre paths are checked to (at 1e15 m
        # a solved path failed its own check), and so does a heading of 1e12 rad.
        ({"bounds": [1e15, 1e15, 1e15 + 50, 1e15 + 50]}, "bounds: .* beyond 1e\\+09 m"),
        ({"goal": [40.0, 40.0, 1e12]}, "goal: yaw 1e\\+12 rad is beyond"),
        ({"start": [5.0, 5.0, -2e6]}, "start: yaw"),
    ],
)
def test_bad_map_fields_are_named(patch, field):
    data = _base() | patch
    with pytest.raises(InputError, match=field):
        map_from_json(data)


def test_missing_keys_named():
    data = _base()
    del data["goal"]
    with pytest.raises(InputError, match="goal"):
        map_from_json(data)


def test_a_syntax_error_names_its_column_and_the_text_before_it(tmp_path):
    # A one-line map with a trailing comma was "Expecting value (line 1)" (an audit).
    text = json.dumps(_base(), separators=(",", ":"))
    at = text.index("]", text.index('"obstacles"'))
    bad = tmp_path / "comma.json"
    bad.write_text(text[:at] + "," + text[at:])
    with pytest.raises(InputError) as info:
        load_map(bad)
    message = str(info.value)
    assert f"(line 1, column {at + 2}, near " in message
    assert message.endswith(f"{text[at - 10 : at]},]')"), message


@pytest.mark.parametrize(
    "obstacle", [{"polygon": [[0, 0], [1, 0], [1, 1]]}, {"center": [1, 1]}, [10, 10, 2, 2]]
)
def test_an_obstacle_in_another_shape_is_told_the_rectangle_format(obstacle):
    data = _base()
    data["obstacles"] = [obstacle]
    with pytest.raises(InputError, match=r"^obstacles\[0\]: .*obstacles are rectangles: center"):
        map_from_json(data)


def test_malformed_json_and_nan_literals(tmp_path):
    bad = tmp_path / "bad.json"
    bad.write_text("{not json")
    with pytest.raises(InputError, match="malformed JSON"):
        load_map(bad)
    nan = tmp_path / "nan.json"
    nan.write_text(json.dumps(_base()).replace("5.0, 5.0, 0.0", "5.0, NaN, 0.0"))
    with pytest.raises(InputError, match="start: must be finite"):
        load_map(nan)
    with pytest.raises(InputError, match="cannot read"):
        load_map(tmp_path / "missing.json")


def test_unknown_builtin():
    with pytest.raises(InputError, match="unknown map 'nope'"):
        resolve_map("nope")


def test_start_inside_obstacle_rejected_against_shapely():
    # The check must agree with an independent shapely overlap test of the body.
    m = map_from_json(_base())
    inside = Pose(24.0, 25.0, 0.0)
    with pytest.raises(InputError, match="start: .*overlaps obstacle 0"):
        m.with_query(start=inside)
    body = shapely.box(24.0 - 0.895, 25.0 - 0.9, 24.0 + 3.405, 25.0 + 0.9)
    assert body.intersects(m.obstacles[0].polygon())


def test_obstacle_geometry():
    o = Obstacle((1.0, 2.0), (4.0, 2.0), math.pi / 2)
    poly = o.polygon()
    assert poly.area == pytest.approx(8.0)
    minx, miny, maxx, maxy = poly.bounds
    assert (maxx - minx, maxy - miny) == pytest.approx((2.0, 4.0))
    assert o.grown(1.0).size == (5.0, 3.0)


def test_map_is_hashable_and_equal():
    a, b = builtin_map("overtake"), builtin_map("overtake")
    assert a == b and hash(a) == hash(b)
    assert isinstance(a, Map)


def test_saved_files_get_ordinary_permissions(tmp_path):
    import os

    mask = os.umask(0o022)
    try:
        save_map(builtin_map("overtake"), tmp_path / "o.json")
    finally:
        os.umask(mask)
    assert (tmp_path / "o.json").stat().st_mode & 0o777 == 0o644


def test_a_key_given_twice_is_refused_and_a_byte_order_mark_is_read(tmp_path):
    from rrtdrive.maps import load_map

    dup = tmp_path / "dup.json"
    dup.write_text('{"name": "d", "bounds": [0, 0, 40, 40], "obstacles": [], '
                   '"start": [5, 5, 0], "start": [6, 6, 0], "goal": [30, 30, 1.57]}')
    with pytest.raises(InputError, match=r"^map: .*dup.json gives 'start' twice in one object"):
        load_map(dup)
    bom = tmp_path / "bom.json"
    bom.write_bytes(b"\xef\xbb\xbf" + dup.read_bytes().replace(b'"start": [6, 6, 0], ', b""))
    assert load_map(bom).start.x == 5.0  # Windows editors write the mark: no error


def _file_map(**changes):
    data = {"bounds": [0, 0, 40, 40], "obstacles": [{"center": [20, 20], "size": [4, 2]}],
            "start": [5, 5, 0], "goal": [30, 30, 1.5708]}
    data.update(changes)
    return data


@pytest.mark.parametrize(
    ("changes", "field", "hint"),
    [
        ({"goal": [30, 30, 90]}, "goal", "for 90 deg write 1.5708"),
        ({"start": [5, 5, -180]}, "start", "for -180 deg write -3.1416"),
        ({"obstacles": [{"center": [20, 20], "size": [4, 2], "yaw": 45}]},
         "obstacles[0].yaw", "for 45 deg write 0.7854"),
        ({"obstacles": [{"center": [20, 20], "size": [4, 2]},
                        {"center": [80, 20], "size": [4, 2]}]},
         "obstacles[1]", "wholly outside the bounds"),
    ],
)
def test_likely_mistakes_warn_naming_the_field(changes, field, hint):
    with pytest.warns(InputWarning) as record:
        m = map_from_json(_file_map(**changes))
    texts = [str(w.message) for w in record]
    assert len(texts) == 1 and texts[0].startswith(f"{field}: ") and hint in texts[0]
    assert isinstance(m, Map)  # valid input: planned as given


def test_many_obstacle_yaws_past_a_full_turn_warn_once():
    # A script's polygon in radians past 2 pi printed a warning per obstacle (1 250 lines).
    boxes = [{"center": [5 + 3 * i, 20], "size": [1, 1], "yaw": 7.0 + i} for i in range(9)]
    boxes[0]["yaw"] = 0.5  # within a full turn: not counted
    with pytest.warns(InputWarning) as record:
        map_from_json(_file_map(obstacles=boxes))
    texts = [str(w.message) for w in record]
    assert len(texts) == 1
    assert texts[0].startswith("obstacles[1].yaw (and 7 more obstacle yaws past a full turn): ")
    assert "for 8 deg write 0.1396" in texts[0]


def test_a_yaw_wraps_as_radians_whatever_the_warning_says():
    # The warning's "taken as" angle is the one the planner uses: 90 rad wraps to 116.6 deg.
    with pytest.warns(InputWarning, match=r"taken as 116\.6 deg"):
        m = map_from_json(_file_map(goal=[30, 30, 90]))
    assert math.degrees(math.remainder(m.goal.yaw, 2 * math.pi)) == pytest.approx(116.62, abs=0.01)


@pytest.mark.parametrize("name", sorted(BUILTIN_MAPS))
def test_builtin_maps_and_sane_files_warn_nothing(name, tmp_path):
    f = tmp_path / "m.json"
    save_map(builtin_map(name), f)
    with warnings.catch_warnings():
        warnings.simplefilter("error", InputWarning)
        load_map(f)
        map_from_json(_file_map(goal=[30, 30, 2 * math.pi]))  # a full turn exactly: fine
        map_from_json(_file_map(obstacles=[{"center": [41, 20], "size": [4, 2]}]))  # overhangs


def test_the_cli_prints_each_warning_as_one_line(tmp_path, capsys):
    from rrtdrive.cli import main

    f = tmp_path / "m.json"
    f.write_text(json.dumps(_file_map(goal=[30, 30, 90])))
    code = main(["plan", str(f), "--json", str(tmp_path / "p.json")])
    err = capsys.readouterr().err
    assert code == 0
    assert err.splitlines() == [
        "rrtdrive plan: warning: goal: yaw 90 is more than a full turn; yaws are in radians, "
        "so it is taken as 116.6 deg; for 90 deg write 1.5708"
    ]
    # One given on the command line is named by its flag, as its errors are.
    code = main(["plan", "parking_lot", "--start", "10,9,360", "--goal", "50,40,90",
                 "--max-iterations", "1"])
    err = capsys.readouterr().err.splitlines()
    assert err[0].startswith("rrtdrive plan: warning: --start: yaw 360 is more than a full turn")
    assert err[1].startswith("rrtdrive plan: warning: --goal: yaw 90 is more than a full turn")
    assert code == 2 and err[2].startswith("rrtdrive plan: error: --goal: the car's body at")


def test_a_body_touching_the_bounds_is_refused_as_one_touching_an_obstacle():
    # The rear bumper on x = 0: highway-env's wall stands there, so the car crashed at once.
    back = VehicleParams().rear_overhang
    with pytest.raises(InputError, match=r"^start: .* touches the bounds"):
        map_from_json(_file_map(start=[back, 5, 0]))
    map_from_json(_file_map(start=[back + 1e-4, 5, 0]))  # a gap of 0.1 mm is clear


def test_verify_fails_a_path_touching_the_bounds():
    import numpy as np

    from rrtdrive.types import Path
    from rrtdrive.verify import verify_path

    back = VehicleParams().rear_overhang
    xs = np.arange(0.0, 3.01, 0.1)
    rows = np.column_stack([back + xs, 5 + 0 * xs, 0 * xs, 0 * xs, 1 + 0 * xs])
    m = Map("m", (0.0, 0.0, 40.0, 40.0), (), Pose(back, 5, 0), Pose(back + 3.0, 5, 0),
            check_query=False)
    check = verify_path(m, Path(rows, np.zeros((0, 2))))
    assert not check.collision_free and check.collides_with == "the bounds"
    assert check.first_collision[0] == pytest.approx(back)


def test_a_name_with_half_a_surrogate_pair_is_bad_input(tmp_path, capsys):
    from rrtdrive.cli import main

    f = tmp_path / "m.json"
    f.write_text(json.dumps(_file_map(name="lot\ud800")))  # json writes it as \\ud800
    with pytest.raises(InputError, match=r"^name: .* surrogate"):
        load_map(f)
    assert main(["plan", str(f)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "error: name:" in err and "Traceback" not in err


@pytest.mark.parametrize("name", ["lot\nB", "\x1b[31mred", "tab\there", "nul\x00"])
def test_a_name_with_a_control_character_is_bad_input(name, tmp_path, capsys):
    # Printed raw, a newline split the one-line summary and an escape recoloured the
    # terminal (a helper's audit, session 29).
    from rrtdrive.cli import main

    with pytest.raises(InputError, match=r"^name: .* control character"):
        map_from_json(_file_map(name=name))
    f = tmp_path / "m.json"
    f.write_text(json.dumps(_file_map(name=name)))
    assert main(["plan", str(f)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "error: name:" in err and "\x1b" not in err


@pytest.mark.parametrize("half", [1e100, 1e200, 1e300])
def test_huge_bounds_are_refused_for_their_size_not_the_start(half):
    # shapely's containment test of a 1 m body in bounds of +-1e200 overflowed, and the
    # start was said to leave the bounds.
    data = _file_map(bounds=[-half, -half, half, half], obstacles=[])
    m = map_from_json(data)  # the start and goal are well inside
    with pytest.raises(InputError, match=r"^bounds: .* grid cells"):
        from rrtdrive.planning import PlanningProblem

        PlanningProblem.from_map(m)


@settings(max_examples=200, deadline=None)
@given(
    st.floats(-3.0, 43.0), st.floats(-3.0, 43.0), st.floats(-math.pi, math.pi),
)
def test_the_body_inside_the_bounds_is_shapelys_containment(x, y, yaw):
    # The corner comparison against shapely's contains_properly at ordinary sizes.
    from rrtdrive.map_checks import check_endpoint
    from rrtdrive.vehicle import footprint_polygon

    m = map_from_json(_file_map(obstacles=[]))
    v = VehicleParams()
    body = footprint_polygon((x, y, yaw), v)
    want = shapely.box(*m.bounds).contains_properly(body)
    try:
        check_endpoint(m, Pose(x, y, yaw), "start", v)
        got = True
    except InputError as exc:
        assert str(exc).startswith("start: ")
        got = False
    assert got == want


_RECT = st.tuples(
    st.floats(-5.0, 5.0), st.floats(-5.0, 5.0), st.floats(0.2, 6.0), st.floats(0.2, 6.0),
    st.floats(-math.pi, math.pi),
)


@settings(max_examples=200, deadline=None)
@given(_RECT, _RECT)
def test_overlap_depth_is_the_minimum_translation_of_two_rectangles(ra, rb):
    """The depth a start or goal error gives: against the Minkowski difference (shapely's
    convex hull of every vertex difference), whose boundary is that far from the origin
    when the two overlap."""
    import numpy as np

    from rrtdrive.map_checks import overlap_depth
    from rrtdrive.obstacles import Obstacle

    a, b = (Obstacle((r[0], r[1]), (r[2], r[3]), r[4]).polygon() for r in (ra, rb))
    pa, pb = (np.asarray(p.exterior.coords)[:-1] for p in (a, b))
    diff = shapely.MultiPoint((pa[:, None, :] - pb[None, :, :]).reshape(-1, 2)).convex_hull
    origin = shapely.Point(0.0, 0.0)
    want = diff.exterior.distance(origin) if diff.contains(origin) else 0.0
    assert overlap_depth(pa, pb) == pytest.approx(want, abs=1e-9)


def test_a_start_into_a_wall_is_refused_with_how_far_in():
    """A start 4.5 cm into a wall was refused without saying by how much (a new user's find)."""
    car = VehicleParams()
    wall = Obstacle((2.0, 10.0), (1.0, 6.0))  # x 1.5 .. 2.5
    rear = car.length - car.front_extent  # the body reaches this far behind the rear axle
    start = Pose(2.5 + rear - 0.045, 10.0, 0.0)
    m = Map("w", (0.0, 0.0, 30.0, 20.0), (wall,), Pose(20.0, 5.0, 0.0), Pose(20.0, 10.0, 0.0))
    from rrtdrive.maps import check_endpoint

    with pytest.raises(InputError, match=r"^start: .* overlaps obstacle 0 at \[2\.0, 10\.0\] "
                                         r"by 0\.045 m \(the least shift that clears it\)$"):
        check_endpoint(m, start, "start", car)


def test_a_start_touching_a_wall_is_refused_as_touching_not_by_0_m():
    # The body's rear edge exactly on the wall's face: shapely says they intersect, the
    # separating-axis depth is 0; "overlaps ... by 0 m (the least shift that clears it)"
    # read as if no shift were needed (an audit).
    car = VehicleParams()
    wall = Obstacle((2.0, 10.0), (1.0, 6.0))  # x 1.5 .. 2.5
    start = Pose(2.5 + car.rear_overhang, 10.0, 0.0)
    m = Map("w", (0.0, 0.0, 30.0, 20.0), (wall,), Pose(20.0, 5.0, 0.0), Pose(20.0, 10.0, 0.0))
    from rrtdrive.maps import check_endpoint
    from rrtdrive.vehicle import footprint_polygon

    assert footprint_polygon(start.as_tuple(), car).distance(wall.polygon()) == 0.0
    with pytest.raises(InputError, match=r"^start: .* touches obstacle 0 at \[2\.0, 10\.0\] "
                                         r"\(touching counts as a collision: move it clear\)$"):
        check_endpoint(m, start, "start", car)
