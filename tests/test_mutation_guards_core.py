"""Mutation guards for the core helpers: steering sharpness, obstacles, atomic writes,
strict JSON and maps (``rrtdrive.steering_sharpness``, ``obstacles``, ``atomic``,
``json_safe``, ``maps``).

Each test states a documented law against an independent reference: the steering
sharpness against a brute-force maximum over every window placement and the closed
form ``d atan(L kappa)/ds``; an obstacle against shapely's own rotated box; an atomic
write against the file system (the old file whole, no temporary file left, the modes
and links kept); ``json_safe`` against ``json.loads`` round trips and the standard
library's refusal of NaN (``allow_nan=False``); maps against the documented map format
(README "Maps", SPEC section 2, the built-ins' docstrings) and the error naming the
field, exit 2 on the command line. Found by mutation testing of those modules (each
test names the slips it catches in its docstring).
"""

from __future__ import annotations

import enum
import json
import math
import os
import re
import subprocess
import sys
import tempfile
import types
import warnings
from pathlib import Path

import numpy as np
import pytest
import shapely
import shapely.affinity
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from rrtdrive.atomic import atomic_target, temp_beside, write_text_atomic
from rrtdrive.json_safe import json_safe, options_from_json, options_json
from rrtdrive.maps import (
    Map,
    Obstacle,
    builtin_map,
    load_map,
    map_from_json,
    map_text,
    names_map_file,
    resolve_map,
)
from rrtdrive.steering_sharpness import (
    SHARPNESS_WINDOW_M,
    steering_rate_speed_cap,
    steering_sharpness,
)
from rrtdrive.types import InputError, InputWarning, Pose, VehicleParams

WHEELBASE = 2.5

# --- steering sharpness ----------------------------------------------------------------


def brute_sharpness(
    s: np.ndarray, kappa: np.ndarray, wheelbase: float, window: float
) -> np.ndarray:
    """The documented sharpness by brute force: the steepest window near each sample.

    ``delta = atan(L kappa)`` interpolated linearly in arc length (held at the path's
    ends); for sample ``i`` the largest ``|delta(a + w) - delta(a)| / w`` over window
    starts ``a`` in ``[s_i - 2w, s_i + w]`` (every window within ``w`` of the sample),
    tried on a fine grid and at every start where an end meets a sample.
    """
    delta = np.arctan(wheelbase * kappa)
    if len(s) < 2 or s[-1] <= s[0]:
        return np.zeros(len(s))
    corners = np.concatenate([s, s - window])
    out = np.empty(len(s))
    for i, si in enumerate(s):
        lo, hi = si - 2.0 * window, si + window
        met = corners[(corners >= lo) & (corners <= hi)]
        starts = np.concatenate([np.linspace(lo, hi, 241), met])
        change = np.abs(np.interp(starts + window, s, delta) - np.interp(starts, s, delta))
        out[i] = change.max() / window
    return out


@st.composite
def sampled_paths(draw: st.DrawFn) -> tuple[np.ndarray, np.ndarray]:
    """Rows with increasing arc length (gaps 1 cm to 0.6 m) and curvature up to 0.4 1/m."""
    n = draw(st.integers(2, 40))
    gaps = draw(hnp.arrays(float, n - 1, elements=st.floats(0.01, 0.6)))
    kappa = draw(hnp.arrays(float, n, elements=st.floats(-0.4, 0.4)))
    return np.concatenate([[0.0], np.cumsum(gaps)]), kappa


@settings(max_examples=80, deadline=None)
@given(sampled_paths(), st.sampled_from([SHARPNESS_WINDOW_M, 0.1, 0.7]))
def test_sharpness_is_the_steepest_window_near_each_sample(
    path: tuple[np.ndarray, np.ndarray], window: float
) -> None:
    """Brute force over all window placements equals the fast search at every sample.

    Catches: the angle's ``atan`` dropped, a window divided by twice its length, a
    window reaching ``2w`` ahead or behind the wrong way, a search range one window too
    short or long at either end, ``side='left'`` for ``'right'``, the far windows at the
    interval's two ends dropped or shifted, and the sparse table's level count, power or
    second index off by one (a range maximum missing samples).
    """
    s, kappa = path
    got = steering_sharpness(s, kappa, WHEELBASE, window)
    ref = brute_sharpness(s, kappa, WHEELBASE, window)
    np.testing.assert_allclose(got, ref, rtol=1e-9, atol=1e-12)


def test_sharpness_of_a_curvature_ramp_is_the_closed_form_slope() -> None:
    """On a smooth ramp of curvature, the sharpness brackets ``L kappa' / (1 + (L kappa)^2)``.

    ``d atan(L kappa)/ds`` falls along a rising ramp, so the steepest window within
    ``w`` of a sample lies between the slopes ``2w`` after and ``2w`` before it; zero
    more than ``2w`` from the ramp. Catches the ``atan`` dropped (the slope would not fall)
    and every slip that scales the result.
    """
    s = np.linspace(0.0, 30.0, 3001)
    slope = 0.04  # 1/m per metre over s in [10, 20]: kappa reaches 0.4, L kappa = 1
    kappa = np.clip(s - 10.0, 0.0, 10.0) * slope
    sharp = steering_sharpness(s, kappa, WHEELBASE)
    w = SHARPNESS_WINDOW_M

    def exact(x: np.ndarray) -> np.ndarray:
        k = np.clip(x - 10.0, 0.0, 10.0) * slope
        return WHEELBASE * slope / (1.0 + (WHEELBASE * k) ** 2)

    mid = (s > 10.0 + 2 * w) & (s < 20.0 - 2 * w)
    assert np.all(sharp[mid] <= exact(s[mid] - 2 * w) + 1e-9)
    assert np.all(sharp[mid] >= exact(s[mid] + 2 * w) - 1e-9)
    far = (s < 10.0 - 2 * w - 0.01) | (s > 20.0 + 2 * w + 0.01)
    assert np.all(sharp[far] == 0.0)


def test_a_curvature_step_between_rows_counts_in_full_and_repeated_rows_do_not_blow_up() -> None:
    """A step of curvature counts as ``|atan(L k2) - atan(L k1)| / w`` within ``w`` of it.

    Rows 0.25 m apart with the step between two of them, and a repeated row (a cusp's
    zero gap) elsewhere on a straight: the samples up to a window before and after the
    step read the full jump, a repeated row reads zero. Catches the far windows dropped
    (a step read too small away from it) and a slope over a zero gap.
    """
    s = np.concatenate([np.arange(0.0, 10.01, 0.25), [10.0, 10.2]])
    kappa = np.where(s > 5.0, 0.1, 0.0)
    sharp = steering_sharpness(s, kappa, WHEELBASE)
    jump = math.atan(WHEELBASE * 0.1) / SHARPNESS_WINDOW_M
    near = np.abs(s - 5.125) <= 0.125 + SHARPNESS_WINDOW_M + 1e-9
    np.testing.assert_allclose(sharp[near], jump, rtol=1e-12)
    assert np.all(sharp[s > 6.0] == 0.0)
    assert np.all(np.isfinite(sharp))


@pytest.mark.parametrize("rows", [1, 0])
def test_too_few_rows_have_no_sharpness(rows: int) -> None:
    """One row (or none) asks no steering change: zeros, not ``inf``, nor an error.

    Catches a degenerate path answered with an infinite or undefined sharpness.
    """
    got = steering_sharpness(np.zeros(rows), np.full(rows, 0.2), WHEELBASE)
    assert got.shape == (rows,) and np.all(got == 0.0)


@settings(max_examples=40, deadline=None)
@given(sampled_paths(), st.floats(0.05, 1.0), st.floats(0.1, 1.0))
def test_speed_cap_is_share_of_rate_over_sharpness(
    path: tuple[np.ndarray, np.ndarray], rate: float, share: float
) -> None:
    """``cap = share * rate / sharpness`` where the angle changes, ``inf`` where it does not.

    Checked against the brute-force sharpness with a window of 0.6 m. Catches the share
    dropped, the window not passed on, and ``inf`` replaced by a finite number.
    """
    s, kappa = path
    kappa = np.where(np.arange(len(kappa)) < len(kappa) // 3, 0.0, kappa)  # some straight
    cap = steering_rate_speed_cap(s, kappa, WHEELBASE, rate, share=share, window=0.6)
    ref = brute_sharpness(s, kappa, WHEELBASE, 0.6)
    moving = ref > 1e-12
    np.testing.assert_allclose(cap[moving], share * rate / ref[moving], rtol=1e-9)
    assert np.all(np.isposinf(cap[~moving]))


def test_a_gentle_curvature_change_is_capped_too() -> None:
    """A tiny but real change of the angle (1e-5 1/m over 5 m) gets a finite cap.

    Catches the 'no change' threshold raised (a slow clothoid taken as straight).
    """
    s = np.linspace(0.0, 10.0, 101)
    kappa = np.clip(s - 2.0, 0.0, 5.0) * 2e-6
    cap = steering_rate_speed_cap(s, kappa, WHEELBASE, 0.4)
    ref = brute_sharpness(s, kappa, WHEELBASE, SHARPNESS_WINDOW_M)
    assert ref.max() > 1e-12
    np.testing.assert_allclose(cap.min(), 0.4 / ref.max(), rtol=1e-6)


# --- obstacles ---------------------------------------------------------------------------


def shapely_rectangle(
    center: tuple[float, float], size: tuple[float, float], yaw: float
) -> shapely.Polygon:
    """The rectangle as shapely builds it: an axis box about the origin, rotated, moved."""
    box = shapely.box(-size[0] / 2, -size[1] / 2, size[0] / 2, size[1] / 2)
    turned = shapely.affinity.rotate(box, yaw, origin=(0.0, 0.0), use_radians=True)
    return shapely.affinity.translate(turned, *center)


@settings(max_examples=60, deadline=None)
@given(
    st.tuples(st.floats(-50, 50), st.floats(-50, 50)),
    st.tuples(st.floats(0.1, 20), st.floats(0.1, 20)),
    st.floats(-4.0, 4.0),
    st.floats(0.0, 3.0),
)
def test_obstacle_is_shapelys_rotated_box_and_grows_on_every_side(
    center: tuple[float, float], size: tuple[float, float], yaw: float, amount: float
) -> None:
    """The polygon equals shapely's rotated box; corners counter-clockwise from rear-right.

    Catches: length and width swapped, a full length used as the half length, x and y
    of the centre swapped, the yaw's sign flipped; ``grown`` adding half the amount,
    growing one side only, or dropping the yaw.
    """
    o = Obstacle(center, size, yaw)
    ref = shapely_rectangle(center, size, yaw)
    assert o.polygon().symmetric_difference(ref).area <= 1e-9 * max(1.0, ref.area)
    corners = o.corners()
    c, s = math.cos(yaw), math.sin(yaw)
    half_l, half_w = size[0] / 2, size[1] / 2
    rear_right = (center[0] - c * half_l + s * half_w, center[1] - s * half_l - c * half_w)
    np.testing.assert_allclose(corners[0], rear_right, atol=1e-9)
    assert shapely.LinearRing(corners).is_ccw
    big = shapely_rectangle(center, (size[0] + amount, size[1] + amount), yaw)
    assert o.grown(amount).polygon().symmetric_difference(big).area <= 1e-9 * max(1.0, big.area)


def test_obstacle_json_round_trips_and_takes_numpy_numbers() -> None:
    """``to_json`` gives the same rectangle back and strict JSON can write it.

    Numpy centres, sizes and yaws (as a script builds them) are stored as Python floats.
    Catches: ``to_json`` swapping size or centre, writing yaw 0, numpy numbers kept (json
    cannot write a float32) and numpy arrays refused as a centre.
    """
    o = Obstacle(np.array([3.0, -2.0]), (np.float32(4.5), np.float32(1.5)), np.float32(0.75))
    text = json.dumps(o.to_json(), allow_nan=False)
    again = Obstacle(**json.loads(text))
    assert again == o
    assert again.polygon().symmetric_difference(o.polygon()).area == 0.0
    assert json.loads(text) == {"center": [3.0, -2.0], "size": [4.5, 1.5], "yaw": 0.75}
    assert all(type(v) is float for v in (*o.center, *o.size, o.yaw))
    ints = Obstacle((3, 4), (5, 2)).to_json()
    assert ints == {"center": [3.0, 4.0], "size": [5.0, 2.0], "yaw": 0.0}


@pytest.mark.parametrize(
    "center, size, yaw, field",
    [
        ((1.0, 2.0, 3.0), (1.0, 1.0), 0.0, "obstacle.center"),
        ((1.0, float("nan")), (1.0, 1.0), 0.0, "obstacle.center"),
        ((float("inf"), 1.0), (1.0, 1.0), 0.0, "obstacle.center"),
        ((1.0, 1.0), (0.0, 1.0), 0.0, "obstacle.size"),
        ((1.0, 1.0), (1.0, -2.0), 0.0, "obstacle.size"),
        ((1.0, 1.0), (1.0, 1.0, 1.0), 0.0, "obstacle.size"),
        ((1.0, 1.0), (1.0, 1.0), float("nan"), "obstacle.yaw"),
    ],
)
def test_a_bad_obstacle_names_its_field(
    center: tuple[float, ...], size: tuple[float, ...], yaw: float, field: str
) -> None:
    """Three numbers, NaN or inf in a centre, a size not > 0 and a NaN yaw are refused by name.

    Catches the length check loosened to ``< 2``, the finiteness or positivity checks
    skipped, and the centre and size swapped in the error.
    """
    with pytest.raises(InputError, match=rf"^{field}"):
        Obstacle(center, size, yaw)


# --- atomic writes -----------------------------------------------------------------------


def test_a_write_replaces_the_file_whole_keeps_its_mode_and_leaves_no_temp(tmp_path: Path) -> None:
    """A write leaves exactly the target, with the new text, its old mode, and UTF-8.

    Catches: the replaced file's permissions lost (mkstemp's 0600, or the default
    mode instead of the file's own), a copy instead of a rename (the temporary file
    left behind), and the text written in another encoding.
    """
    target = tmp_path / "plan.json"
    target.write_text("old\n", encoding="utf-8")
    target.chmod(0o640)
    write_text_atomic(target, "ő → ∞\n")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["plan.json"]
    assert target.read_bytes() == "ő → ∞\n".encode()
    assert (target.stat().st_mode & 0o777) == 0o640


def test_a_new_file_gets_the_umask_mode_and_the_umask_is_kept(tmp_path: Path) -> None:
    """A new file is ``0666 & ~umask`` (not mkstemp's 0600) and the umask stays as it was.

    Catches the umask ignored (0666 under a 077 umask), the chmod dropped, and the umask
    left at 0 after reading it.
    """
    old = os.umask(0o027)
    try:
        write_text_atomic(tmp_path / "a.txt", "x")
        assert os.umask(0o027) == 0o027  # still the one set: reading it put it back
        assert ((tmp_path / "a.txt").stat().st_mode & 0o777) == 0o640
    finally:
        os.umask(old)


def test_a_link_is_written_through_and_stays_a_link(tmp_path: Path) -> None:
    """Through a symbolic link the file it points to is replaced; the link stays.

    Catches the link not resolved (renamed over: the link becomes a regular file and
    the file it pointed to keeps its old text).
    """
    real = tmp_path / "real.json"
    real.write_text("old", encoding="utf-8")
    link = tmp_path / "link.json"
    link.symlink_to(real)
    write_text_atomic(link, "new")
    assert link.is_symlink() and os.readlink(link) == str(real)
    assert real.read_text(encoding="utf-8") == "new"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["link.json", "real.json"]


def test_the_temp_file_is_hidden_beside_the_target_with_its_suffix(tmp_path: Path) -> None:
    """``temp_beside`` makes an empty hidden file in the target's folder ending in its suffix.

    Beside the target, also when it does not exist yet (not in the system's temporary
    folder); a video writer picks its format from the suffix. Catches: a missing target
    taken for a stream, the leading dot dropped, the suffix dropped.
    """
    for target, suffix, want in [("run.mp4", None, ".mp4"), ("run.mp4", ".part", ".part")]:
        tmp = temp_beside(tmp_path / target, suffix)
        assert tmp.parent == tmp_path and tmp.name.startswith(".run.") and tmp.suffix == want
        assert tmp.read_bytes() == b""
        tmp.unlink()


def test_writing_to_a_device_goes_through_the_system_temp_folder_and_cleans_up(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """For ``/dev/null`` the temporary file lives in the temp folder and is removed after.

    Catches: the device's own folder used for the temporary file, and the temporary
    file left behind after its bytes were copied into the device.
    """
    scratch = tmp_path / "scratch"
    scratch.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(scratch))
    assert temp_beside(os.devnull).parent == scratch
    for p in scratch.iterdir():
        p.unlink()
    write_text_atomic(os.devnull, "nothing to keep")
    assert list(scratch.iterdir()) == []
    assert Path(os.devnull).exists() and not Path(os.devnull).is_file()


def test_writing_to_dev_stdout_reaches_a_pipe() -> None:
    """``/dev/stdout`` through a pipe: the link is not followed to ``pipe:[N]``.

    Catches the link to a stream resolved like a link to a file (the write fails:
    ``/proc/self/fd/pipe:[N]`` is no path).
    """
    code = (
        "from rrtdrive.atomic import write_text_atomic; "
        "write_text_atomic('/dev/stdout', 'piped')"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stderr
    assert done.stdout == "piped"


@pytest.mark.skipif(not Path("/proc/self/fd").is_dir(), reason="counts /proc/self/fd")
def test_writes_leak_no_file_descriptors(tmp_path: Path) -> None:
    """Many writes leave the process's open file count unchanged.

    Catches mkstemp's descriptor left open (a long bench runs out of descriptors).
    """
    before = len(os.listdir("/proc/self/fd"))
    for i in range(20):
        write_text_atomic(tmp_path / f"{i}.txt", "x")
    assert len(os.listdir("/proc/self/fd")) == before


def test_a_failed_write_leaves_the_old_file_and_no_temp(tmp_path: Path) -> None:
    """An error inside the write keeps the old file whole and removes the temporary one.

    Catches the cleanup of the temporary file dropped.
    """
    target = tmp_path / "m.json"
    target.write_text("kept", encoding="utf-8")
    with pytest.raises(ValueError), atomic_target(target) as tmp:
        tmp.write_text("half", encoding="utf-8")
        raise ValueError("disk full")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m.json"]
    assert target.read_text(encoding="utf-8") == "kept"


# --- strict JSON -------------------------------------------------------------------------

NUMBERS = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(-(10**6), 10**6),
    st.floats(-1e6, 1e6).map(np.float32),
    st.floats(allow_nan=True, allow_infinity=True).map(np.float64),
    st.integers(-(10**6), 10**6).map(np.int64),
    st.booleans().map(np.bool_),
)
#: Text that is no spelling of a non-finite number (``options_from_json`` reads those).
TEXT = st.text(max_size=4).filter(lambda t: t not in ("NaN", "Infinity", "-Infinity"))
VALUES = st.recursive(
    st.one_of(NUMBERS, TEXT, st.none()),
    lambda inner: st.one_of(
        st.lists(inner, max_size=3),
        st.lists(inner, max_size=3).map(tuple),
        st.dictionaries(st.one_of(st.text(max_size=3), st.integers(0, 9)), inner, max_size=3),
        st.dictionaries(st.text(max_size=3), inner, max_size=3).map(types.MappingProxyType),
    ),
    max_leaves=12,
)


def plain(value: object, non_finite: object = None) -> object:
    """``value`` as plain JSON values by a walk of its own (the reference for both writers).

    Any mapping to a dict with text keys, lists and tuples to lists, numpy scalars to
    Python numbers, enums to their values; a NaN or infinite float to ``non_finite``
    (``None`` for ``json_safe``), or kept when ``non_finite`` is ``...``.
    """
    if isinstance(value, (dict, types.MappingProxyType)):
        return {str(k): plain(v, non_finite) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [plain(v, non_finite) for v in value]
    if isinstance(value, enum.Enum):
        return plain(value.value, non_finite)
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value) and non_finite is not ...:
        return non_finite
    return value


@settings(max_examples=150, deadline=None)
@given(VALUES)
def test_json_safe_output_is_strict_json_that_reads_back_the_same(value: object) -> None:
    """``json_safe`` is the plain walk with NaN and inf as ``null``: strict JSON that reads back.

    Nested dicts (any mapping), lists and tuples with NaN, inf, numpy scalars and int
    keys, written with ``allow_nan=False`` and read by ``json.loads`` unchanged. Catches:
    int keys kept (they come back as text), tuples or mappings not walked, inf let
    through (only NaN caught), numpy scalars kept, and non-finite numbers spelled as
    text instead of ``null``.
    """
    out = json_safe(value)
    assert json.loads(json.dumps(out, allow_nan=False)) == out == plain(value)


def test_json_safe_makes_missing_values_null_and_arrays_writable() -> None:
    """NaN and ``-inf`` become ``null``; a numpy array that is no scalar is still writable.

    Catches a multi-element array returned as is (json cannot write it).
    """
    out = json_safe({"a": (np.float64("nan"), -math.inf, np.int64(3)), "b": np.array([1.0, 2.0])})
    assert out["a"] == [None, None, 3] and type(out["a"][2]) is int
    json.dumps(out, allow_nan=False)


class Curve(enum.Enum):
    """An option given as an enum (its value a tuple holding inf, to test the walk)."""

    WIDE = ("wide", math.inf)


def same(a: object, b: object) -> bool:
    """Equal plain JSON values, NaN equal to NaN, a float only to a float."""
    if isinstance(a, dict):
        return isinstance(b, dict) and a.keys() == b.keys() and all(same(a[k], b[k]) for k in a)
    if isinstance(a, list):
        return isinstance(b, list) and len(a) == len(b) and all(map(same, a, b))
    if isinstance(a, float):
        return type(b) is float and (a == b or (math.isnan(a) and math.isnan(b)))
    return a == b


@settings(max_examples=100, deadline=None)
@given(VALUES)
def test_options_json_reads_back_through_options_from_json(value: object) -> None:
    """``options_from_json(json.loads(json.dumps(options_json(v))))`` is ``v`` made plain.

    The reference is the plain walk with non-finite numbers kept: NaN, ``inf`` and
    ``-inf`` come back as themselves, nested in lists and dicts. Catches: ``inf`` and
    ``-inf`` spelled the wrong way round, NaN spelled as infinity, ``"-Infinity"`` read
    as ``+inf`` or not read, and dicts or lists inside not read back.
    """
    text = json.dumps(options_json(value), allow_nan=False)
    assert same(plain(value, ...), options_from_json(json.loads(text)))


def test_options_json_writes_enums_by_value_and_reads_infinity_back() -> None:
    """An enum option is its value (walked, so an ``inf`` inside is spelled); text reads back.

    Catches enums left as they are, an enum's value not walked (``inf`` left for the
    strict writer to refuse), and the spellings swapped.
    """
    out = options_json({"curve": Curve.WIDE, "ratios": (-math.inf, math.inf, math.nan)})
    assert out == {"curve": ["wide", "Infinity"], "ratios": ["-Infinity", "Infinity", "NaN"]}
    back = options_from_json(json.loads(json.dumps(out, allow_nan=False)))
    assert back["curve"] == ["wide", math.inf]
    assert back["ratios"][:2] == [-math.inf, math.inf] and math.isnan(back["ratios"][2])


# --- maps --------------------------------------------------------------------------------


def file_map(**changes: object) -> dict[str, object]:
    """A valid map in the file format (README "Maps"), with ``changes`` applied."""
    data: dict[str, object] = {
        "name": "t",
        "bounds": [0, 0, 50, 40],
        "obstacles": [{"center": [25.0, 20.0], "size": [4.0, 2.0], "yaw": 0.3}],
        "start": [5.0, 5.0, 0.0],
        "goal": [40.0, 30.0, 1.0],
    }
    data.update(changes)
    return data


IN_OBSTACLE = [25.0, 20.0, 0.0]


@pytest.mark.parametrize(
    "changes, field",
    [
        ({"bounds": [0, 0, 50, 40, 60]}, r"^bounds"),
        ({"bounds": [0, 0, float("nan"), 40]}, r"^bounds"),
        ({"bounds": [0, 0, math.inf, 40]}, r"^bounds"),
        ({"obstacles": {}}, r"^obstacles"),
        ({"obstacles": ""}, r"^obstacles"),
        ({"obstacles": [5]}, r"^obstacles\[0\]"),
        ({"obstacles": [{"center": [1.0, 1.0]}]}, r"^obstacles\[0\]"),
        ({"obstacles": [{"size": [1.0, 1.0]}]}, r"^obstacles\[0\]"),
        (
            {"obstacles": [{"center": [1.0, 1.0], "size": [1.0, 1.0], "yaw": "x"}]},
            r"^obstacles\[0\]\.yaw",
        ),
        ({"goal": IN_OBSTACLE}, r"^goal: the car's body"),
    ],
)
def test_a_bad_map_field_is_refused_by_name(changes: dict[str, object], field: str) -> None:
    """Five bounds, non-finite bounds, obstacles that are no list, an obstacle that is no
    object or lacks its size or centre, and a goal in an obstacle are each refused naming
    the field.

    Catches the bounds count loosened, the finiteness check skipped, the obstacles type
    check skipped (an empty dict read as no obstacles), ``or`` for ``and`` in the
    centre/size check, and the goal's error naming the start.
    """
    with pytest.raises(InputError, match=field):
        map_from_json(file_map(**changes))


@pytest.mark.parametrize("data", [5, [1, 2], "map", None])
def test_a_map_that_is_no_object_is_refused(data: object) -> None:
    """A JSON number, list, string or null as the whole map is bad input naming ``map``."""
    with pytest.raises(InputError, match=r"^map: expected a JSON object"):
        map_from_json(data)


def test_optional_fields_take_their_documented_defaults() -> None:
    """No ``obstacles`` is an empty map, no ``yaw`` is 0, no ``name`` is ``map``.

    (README "Maps"; docs/metrics.md: "``map`` when the file has none".) Catches the
    obstacles, the yaw or the name made required, or the name defaulting to empty.
    """
    data = file_map(obstacles=[{"center": [25.0, 20.0], "size": [4.0, 2.0]}])
    del data["name"]
    m = map_from_json(data)
    assert m.name == "map" and m.obstacles[0].yaw == 0.0
    data = file_map()
    del data["obstacles"]
    assert map_from_json(data).obstacles == ()


def test_a_loaded_map_is_plain_hashable_floats_and_its_extent_is_right() -> None:
    """Bounds are a tuple of floats and obstacles a tuple: the map hashes and compares.

    Width and height of bounds not at the origin: ``xmax - xmin`` and ``ymax - ymin``.
    Catches the bounds or obstacles left as the file's lists (unhashable), ints kept,
    and the extent taken from the wrong corner.
    """
    data = file_map(bounds=[-10, 5, 50, 45], start=[0.0, 10.0, 0.0])
    m = map_from_json(data)
    assert m.bounds == (-10.0, 5.0, 50.0, 45.0) and all(type(v) is float for v in m.bounds)
    assert isinstance(m.obstacles, tuple) and hash(m) == hash(map_from_json(data))
    assert (m.width, m.height) == (60.0, 40.0)
    box = np.array([0.0, 0.0, 50.0, 40.0])
    wall = [Obstacle((25.0, 20.0), (4.0, 2.0))]
    direct = Map("d", box, wall, Pose(5, 5, 0), Pose(40, 30, 1))
    assert direct.bounds == (0.0, 0.0, 50.0, 40.0) and isinstance(direct.obstacles, tuple)
    hash(direct)


def test_bounds_reaching_exactly_the_coordinate_limit_are_fine() -> None:
    """Bounds up to ``MAX_COORDINATE`` (1e9 m) are accepted; the refusal is for *beyond*.

    Catches ``>`` turned into ``>=`` at the limit.
    """
    edge = 1e9
    data = file_map(bounds=[edge - 50, 0, edge, 40], obstacles=[])
    m = map_from_json(data, start=Pose(edge - 45, 5.0, 0.0), goal=Pose(edge - 10, 30.0, 1.0))
    assert m.bounds[2] == edge


@pytest.mark.parametrize(
    "kwargs, field",
    [
        ({"obstacles": [(1.0, 2.0)]}, r"^obstacles\[0\]"),
        ({"vehicle": "car"}, r"^vehicle"),
        ({"start": (5.0, 5.0, 0.0)}, r"^start"),
        ({"goal": [40.0, 30.0, 1.0]}, r"^goal"),
    ],
)
def test_a_map_built_in_python_refuses_wrong_types_by_name(
    kwargs: dict[str, object], field: str
) -> None:
    """An obstacle that is a tuple, a vehicle that is text, poses as tuples: InputError by name.

    Catches each type check skipped (the later checks failed with AttributeError).
    """
    fields: dict[str, object] = {
        "name": "p", "bounds": (0.0, 0.0, 50.0, 40.0), "obstacles": (),
        "start": Pose(5.0, 5.0, 0.0), "goal": Pose(40.0, 30.0, 1.0),
    }  # fmt: skip
    fields.update(kwargs)
    with pytest.raises(InputError, match=field):
        Map(**fields)  # type: ignore[arg-type]


def test_unchecked_queries_are_kept_and_still_warn_about_degrees(tmp_path: Path) -> None:
    """``check_query=False`` keeps a start inside an obstacle, through every entry.

    (The verifier judges a given path against such a map.) A goal yaw of 90 still warns
    naming the goal. Catches ``check_query`` ignored by ``Map``, ``map_from_json``,
    ``load_map`` or ``resolve_map`` (for a file or a built-in), and the warning dropped.
    """
    data = file_map(start=IN_OBSTACLE)
    with pytest.warns(InputWarning, match="^goal: yaw 90"):
        m = map_from_json(file_map(start=IN_OBSTACLE, goal=[40.0, 30.0, 90.0]), check_query=False)
    assert m.start == Pose(*IN_OBSTACLE)
    f = tmp_path / "m.json"
    f.write_text(json.dumps(data))
    assert load_map(f, check_query=False).start == Pose(*IN_OBSTACLE)
    assert resolve_map(str(f), check_query=False).start == Pose(*IN_OBSTACLE)
    with pytest.raises(InputError, match="^start"):
        resolve_map(str(f))
    wall = builtin_map("overtake").obstacles[0].center
    inside = Pose(wall[0], wall[1], 0.0)
    assert resolve_map("overtake", start=inside, check_query=False).start == inside


def test_given_poses_and_car_replace_the_files_and_are_checked(tmp_path: Path) -> None:
    """``start``/``goal``/``vehicle`` given replace the map's own, in every entry.

    A file whose own start is in an obstacle serves with a good start; the car given is
    the car checked (a 10 m wide car at the start overlaps the obstacle). Catches the
    given start, goal or car dropped by ``map_from_json``, ``load_map``, ``resolve_map``
    or ``Map.with_query``.
    """
    good_start, good_goal = Pose(6.0, 6.0, 0.0), Pose(30.0, 30.0, 0.5)
    data = file_map(start=IN_OBSTACLE, goal=IN_OBSTACLE)
    m = map_from_json(data, start=good_start, goal=good_goal)
    assert (m.start, m.goal) == (good_start, good_goal)
    f = tmp_path / "m.json"
    f.write_text(json.dumps(data))
    for load in (load_map, resolve_map):
        loaded = load(str(f), start=good_start, goal=good_goal)
        assert (loaded.start, loaded.goal) == (good_start, good_goal)
    wide = VehicleParams(width=10.0)
    near = file_map(start=[23.0, 14.0, 0.0])
    assert map_from_json(near).vehicle == VehicleParams()
    with pytest.raises(InputError, match="^start: the car's body"):
        map_from_json(near, wide)
    lane_start, lane_goal = Pose(8.0, 44.0, 0.0), Pose(90.0, 44.0, 0.0)
    built = resolve_map("overtake", VehicleParams(length=4.0), start=lane_start, goal=lane_goal)
    assert built.vehicle == VehicleParams(length=4.0)
    assert (built.start, built.goal) == (lane_start, lane_goal)
    moved = m.with_query(start=Pose(7.0, 7.0, 0.0))
    assert (moved.start, moved.goal) == (Pose(7.0, 7.0, 0.0), good_goal)
    assert m.with_query(goal=Pose(8.0, 30.0, 0.0)).goal == Pose(8.0, 30.0, 0.0)


def test_map_text_is_indented_json_of_the_map_ending_in_a_newline() -> None:
    """``map_text`` is the file format, indented, one newline at the end; it loads back.

    Catches ``to_json`` writing the start as the goal, the indent dropped and the final
    newline dropped.
    """
    m = map_from_json(file_map())
    text = map_text(m)
    assert text.endswith("}\n") and text.count("\n") > 10
    data = json.loads(text)
    assert data["goal"] == [40.0, 30.0, 1.0] and data["start"] == [5.0, 5.0, 0.0]
    assert map_from_json(data) == m


def test_obstacle_union_is_shapelys_union_of_all_rectangles() -> None:
    """The union covers every obstacle: its area is shapely's union of the rectangles.

    Catches obstacles left out of the union.
    """
    m = builtin_map("narrow_gap")
    ref = shapely.union_all([shapely_rectangle(o.center, o.size, o.yaw) for o in m.obstacles])
    assert m.obstacle_union().symmetric_difference(ref).area < 1e-6


def test_load_map_of_a_folder_is_bad_input(tmp_path: Path) -> None:
    """A folder given as the map file is refused naming ``map``, not a traceback.

    Catches only a missing file being caught (IsADirectoryError escaped).
    """
    with pytest.raises(InputError, match=r"^map: cannot read"):
        load_map(tmp_path)


def test_map_names_resolve_as_documented(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A name ending in ``.json``, holding a path separator or naming an existing file is a
    file (docs/metrics.md ``target``); a built-in's name is the built-in even if a file is
    so named; an empty name says it is empty.

    Catches each of the three file tests dropped (a missing file reported as an unknown
    map, or an existing file taken for a map name), the built-in's priority dropped, and
    the empty name read as the current folder.
    """
    monkeypatch.chdir(tmp_path)
    (tmp_path / "mine").write_text(json.dumps(file_map(name="mine")))
    (tmp_path / "overtake").write_text(json.dumps(file_map(name="impostor")))
    assert names_map_file("absent.json") and names_map_file(f"sub{os.sep}absent")
    for missing in ("absent.json", f"sub{os.sep}absent"):
        with pytest.raises(InputError, match=r"^map: cannot read"):
            resolve_map(missing)
    assert resolve_map("mine").name == "mine"
    assert resolve_map("overtake").name == "overtake"
    with pytest.raises(InputError, match="empty"):
        resolve_map("")


@pytest.mark.parametrize("name", [None, 3, ["overtake"]])
def test_builtin_map_of_no_text_is_bad_input(name: object) -> None:
    """A non-text name (None, a number, a list) is refused naming ``map``, not a TypeError."""
    with pytest.raises(InputError, match=r"^map: unknown map"):
        builtin_map(name)  # type: ignore[arg-type]


def test_a_builtin_map_is_built_once() -> None:
    """``builtin_map`` returns the same immutable map each time (its docstring)."""
    assert builtin_map("parking_lot") is builtin_map("parking_lot")


def test_overtake_road_is_as_documented() -> None:
    """The overtake road spans y in [42, 50] with walls beyond it; a car-sized obstacle
    centred at (50, 44) stands in the ego lane, where start and goal are (y = 44).

    Catches the road widened, the ego lane moved, a wall moved into the road and the
    stopped car moved.
    """
    m = builtin_map("overtake")
    union = m.obstacle_union()
    road = shapely.box(0.0, 42.0, 100.0, 50.0)
    car = shapely_rectangle((50.0, 44.0), (VehicleParams().length, VehicleParams().width), 0.0)
    assert union.intersection(road).symmetric_difference(car).area < 1e-9
    below, above = shapely.box(0.0, 41.0, 100.0, 42.0), shapely.box(0.0, 50.0, 100.0, 51.0)
    assert union.contains(below) and union.contains(above)
    assert m.start.y == m.goal.y == 44.0


def test_narrow_gap_is_one_passage_2_8_m_wide_through_a_wall_across_the_map() -> None:
    """Along the wall's centre line the only free stretch is 2.8 m long.

    Catches the gap widened or closed.
    """
    m = builtin_map("narrow_gap")
    free = shapely.LineString([(50.0, 0.0), (50.0, 100.0)]).difference(m.obstacle_union())
    parts = list(getattr(free, "geoms", [free]))
    assert len(parts) == 1 and parts[0].length == pytest.approx(2.8, abs=1e-9)


def test_no_path_goal_is_walled_in() -> None:
    """The free space around the goal does not reach the start (a closed ring).

    Catches a ring wall shortened (the ring opened).
    """
    m = builtin_map("no_path")
    free = shapely.box(*m.bounds).difference(m.obstacle_union())
    pieces = list(getattr(free, "geoms", [free]))
    home = next(p for p in pieces if p.contains(shapely.Point(m.goal.x, m.goal.y)))
    assert not home.contains(shapely.Point(m.start.x, m.start.y))


@pytest.mark.parametrize(
    "changes, field",
    [
        ({"obstacles": {}}, "obstacles"),
        ({"bounds": [0, 0, 50, 40, 60]}, "bounds"),
        ({"obstacles": [{"center": [1.0, 1.0]}]}, r"obstacles\[0\]"),
    ],
)
def test_the_cli_exits_2_naming_the_bad_field(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], changes: dict[str, object], field: str
) -> None:
    """``rrtdrive plan`` on a map file with a bad field exits 2 with one line naming it."""
    from rrtdrive.cli import main

    f = tmp_path / "m.json"
    f.write_text(json.dumps(file_map(**changes)))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", InputWarning)
        code = main(["plan", str(f)])
    err = capsys.readouterr().err.splitlines()
    assert code == 2
    assert len(err) == 1 and err[0].startswith("rrtdrive plan: error: ")
    assert re.match(field, err[0].removeprefix("rrtdrive plan: error: "))
