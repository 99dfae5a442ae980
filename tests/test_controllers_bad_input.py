"""Bad input to the controllers: options, names, vehicle states and paths name the field."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from rrtdrive.controllers import CONTROLLERS, SpeedConfig, VehicleState, make_controller
from rrtdrive.types import InputError, InputWarning, Path, VehicleParams

XS = np.arange(0.0, 20.01, 0.25)
STRAIGHT = Path(np.column_stack([XS, 0 * XS, 0 * XS, 0 * XS]), np.zeros((0, 2)))


@pytest.mark.parametrize("name", sorted(CONTROLLERS))
@pytest.mark.parametrize(
    ("option", "value", "message"),
    [
        ("vehicle", "car", r"^controller\.vehicle: expected a VehicleParams, got str 'car'$"),
        ("vehicle", {"wheelbase": 2.5}, r"^controller\.vehicle: expected a VehicleParams"),
        ("speed", 5, r"^controller\.speed: expected a SpeedConfig, got int 5$"),
        ("speed", {"v_max": 5.0}, r"^controller\.speed: expected a SpeedConfig, got dict"),
        ("steer_limit", "0.3", r"^controller\.steer_limit: expected a number, got '0.3'"),
        ("steer_limit", math.nan, r"^controller\.steer_limit: must be finite"),
    ],
)
def test_bad_common_option_names_it(name, option, value, message):
    with pytest.raises(InputError, match=message):
        make_controller(name, **{option: value})


@pytest.mark.parametrize(
    ("name", "option", "value"),
    [
        ("lqr", "q_psi", "1"),
        ("lqr", "q_e", "1"),
        ("lqr", "bandwidth", None),
        ("stanley", "k", "fast"),
        ("stanley", "k_soft", math.inf),
        ("pure-pursuit", "ld_gain", "0.6"),
        ("pure-pursuit", "ld_min", -1.0),
    ],
)
def test_bad_gain_names_it(name, option, value):
    with pytest.raises(InputError, match=rf"^[a-z_]+\.{option}: "):
        make_controller(name, **{option: value})


@pytest.mark.parametrize("name", sorted(CONTROLLERS))
def test_good_options_still_build(name):
    c = make_controller(name, vehicle=VehicleParams(), speed=SpeedConfig(), steer_limit=0.3)
    assert c.name == name and c.steer_limit == 0.3
    assert make_controller(name, vehicle=None, speed=None).vehicle == VehicleParams()


@pytest.mark.parametrize("name", [["lqr"], None, 3, ("lqr",), b"lqr"], ids=repr)
def test_controller_name_of_the_wrong_type(name):
    with pytest.raises(InputError, match=r"^controller: expected a controller name, got "):
        make_controller(name)  # type: ignore[arg-type]


def test_unknown_name_and_option_still_named():
    with pytest.raises(InputError, match=r"^controller: unknown controller 'lqrr'"):
        make_controller("lqrr")
    with pytest.raises(InputError, match=r"^controller\.bogus: unknown option of LQR; choose "):
        make_controller("lqr", bogus=1)


@pytest.mark.parametrize("field", ["x", "y", "yaw", "speed", "steer", "t"])
@pytest.mark.parametrize("value", [math.nan, math.inf, -math.inf, 10**400])
def test_vehicle_state_refuses_non_finite_field(field, value):
    values = dict(x=0.0, y=0.0, yaw=0.0, speed=1.0, steer=0.0, t=0.0)
    values[field] = value
    with pytest.raises(InputError, match=rf"^state\.{field}: must be finite"):
        VehicleState(**values)


@pytest.mark.parametrize("value", ["1.0", None, True, [1.0]], ids=repr)
def test_vehicle_state_refuses_non_numbers(value):
    with pytest.raises(InputError, match=r"^state\.speed: expected a number"):
        VehicleState(0.0, 0.0, 0.0, value)  # type: ignore[arg-type]


def test_vehicle_state_takes_numpy_numbers():
    s = VehicleState(np.float64(1.0), np.float32(0.5), np.int64(0), 2, 0.0, 0.05)
    assert s.x == 1.0 and s.speed == 2


@pytest.mark.parametrize("name", sorted(CONTROLLERS))
def test_control_still_runs_and_bad_path_is_named(name):
    c = make_controller(name)
    with pytest.raises(InputError, match=r"^path: expected a rrtdrive\.types\.Path, got str"):
        c.reset("path")  # type: ignore[arg-type]
    c.reset(STRAIGHT)
    accel, steer = c.control(VehicleState(0.0, 0.2, 0.0, 1.0, 0.0, 0.05))
    assert math.isfinite(accel) and steer < 0.0  # left of the path: steer right


@pytest.mark.parametrize(
    ("fields", "message"),
    [
        # The taper starts within the stop's own deceleration: a share of it, (0, 1].
        ({"taper_start": 1.5}, r"^speed\.taper_start: must lie in \(0, 1\], got 1\.5$"),
        # Both signs matter: a loop that cannot brake (a_min > 0) or cannot speed up.
        ({"a_min": 0.5, "a_max": 2.0}, r"^speed\.a_min/a_max: need a_min < 0 < a_max"),
        ({"a_min": -2.0, "a_max": -0.5}, r"^speed\.a_min/a_max: need a_min < 0 < a_max"),
    ],
)
def test_speed_limits_out_of_their_range_are_named(fields, message):
    """A speed config outside its range is refused by field; the range's ends are valid."""
    with pytest.raises(InputError, match=message):
        SpeedConfig(**fields)
    assert SpeedConfig(taper_start=1.0).taper_start == 1.0


def test_a_look_ahead_whose_longest_is_below_its_shortest_is_refused():
    """Pure pursuit's look-ahead is clipped to [ld_min, ld_max]: an empty range is refused."""
    empty = r"^pure_pursuit\.ld_max: must be >= ld_min \(5\.0\), got 2\.0$"
    with pytest.raises(InputError, match=empty):
        make_controller("pure-pursuit", ld_min=5.0, ld_max=2.0)
    assert make_controller("pure-pursuit", ld_min=2.0, ld_max=2.0) is not None
    # The message named both parameters whichever was wrong (an audit).
    with pytest.raises(InputError, match=r"^pure_pursuit\.ld_gain: must be >= 0, got -0\.1$"):
        make_controller("pure-pursuit", ld_gain=-0.1)


@pytest.mark.parametrize("name", sorted(CONTROLLERS))
@pytest.mark.parametrize(
    ("call", "message"),
    [
        # NaN started the speed profile at v_max; "1" was a bare TypeError (an audit).
        (lambda c: c.reset(STRAIGHT, math.nan), r"^v_start: must be finite"),
        (lambda c: c.reset(STRAIGHT, "1"), r"^v_start: expected a number, got '1'"),
        (lambda c: c.retarget(STRAIGHT, math.inf), r"^v_start: must be finite"),
        (lambda c: c.hold_at(math.nan), r"^stop line s: must be finite"),
        (lambda c: c.cap_accel(math.nan), r"^accel cap: must be finite"),
        (lambda c: c.cap_accel("x"), r"^accel cap: expected a number"),
        (lambda c: c.start_segment(0.5), r"^segment: must be an integer >= 0, got 0.5"),
    ],
)
def test_bad_arguments_to_the_tracking_calls_name_them(name, call, message):
    c = make_controller(name)
    c.reset(STRAIGHT)
    with pytest.raises(InputError, match=message):
        call(c)


@pytest.mark.parametrize("name", sorted(CONTROLLERS))
def test_good_arguments_to_the_tracking_calls_pass(name):
    c = make_controller(name)
    c.reset(STRAIGHT, np.float64(1.5))
    c.hold_at(12.0)
    c.hold_at(None)
    c.cap_accel(-0.5)
    c.cap_accel(None)
    c.start_segment(0)
    assert c.segment == 0


@pytest.mark.parametrize("name", sorted(CONTROLLERS))
def test_a_steer_limit_beyond_the_lock_warns_and_takes_the_lock(name):
    lock = VehicleParams().max_steer
    with pytest.warns(InputWarning, match=r"^controller\.steer_limit: 0\.7 rad is beyond"):
        c = make_controller(name, steer_limit=0.7)
    assert c.steer_limit == lock
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # at or under the lock: no word
        assert make_controller(name, steer_limit=lock).steer_limit == lock
