"""The car in a map file and in a plan: read, written, and used by plan, verify, simulate."""

from __future__ import annotations

import dataclasses
import json
import math
import subprocess
import sys

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rrtdrive import InputError, VehicleParams, builtin_map
from rrtdrive.maps import load_map, save_map
from rrtdrive.vehicle_json import VEHICLE_KEYS, vehicle_from_json, vehicle_to_json

TINY = VehicleParams(length=2.5, width=1.2, wheelbase=1.6, min_turning_radius=3.0,
                     max_steer=math.radians(35.0), max_steer_rate=0.8)  # fmt: skip


def _cli(*argv: str, cwd=None) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "rrtdrive", *argv], capture_output=True,
                          text=True, timeout=300, cwd=cwd)  # fmt: skip


def _menger(rows: np.ndarray) -> float:
    """Largest curvature of the circles through three consecutive rows (an own measure)."""
    a, b, c = rows[:-2, :2], rows[1:-1, :2], rows[2:, :2]
    cross = np.abs((b - a)[:, 0] * (c - a)[:, 1] - (b - a)[:, 1] * (c - a)[:, 0])
    sides = (np.linalg.norm(b - a, axis=1) * np.linalg.norm(c - b, axis=1)
             * np.linalg.norm(c - a, axis=1))  # fmt: skip
    ok = sides > 1e-9
    return float((2 * cross[ok] / sides[ok]).max())


@st.composite
def cars(draw) -> VehicleParams:
    length = draw(st.floats(1.0, 20.0))
    wheelbase = draw(st.floats(0.3, 0.95)) * length
    max_steer = draw(st.floats(0.1, 1.3))
    radius = max(wheelbase / math.tan(max_steer), 0.5) * draw(st.floats(1.0, 3.0))
    rate = draw(st.one_of(st.none(), st.floats(0.05, 5.0)))
    return VehicleParams(length=length, width=draw(st.floats(0.5, 4.0)), wheelbase=wheelbase,
                         min_turning_radius=radius, max_steer=max_steer,
                         max_steer_rate=rate)  # fmt: skip


@settings(max_examples=60, deadline=None)
@given(cars())
def test_a_car_survives_json(car):
    doc = json.loads(json.dumps(vehicle_to_json(car), allow_nan=False))
    assert set(doc) == set(VEHICLE_KEYS)
    assert vehicle_from_json(doc) == car


def test_instant_steering_is_null_and_a_left_out_field_is_the_papers():
    assert vehicle_to_json(VehicleParams(max_steer_rate=math.inf))["max_steer_rate"] is None
    assert vehicle_from_json({"max_steer_rate": None}).max_steer_rate is None
    assert vehicle_from_json({}) == VehicleParams()
    assert vehicle_from_json({"length": 5}) == VehicleParams(length=5.0)


@pytest.mark.parametrize(
    ("value", "message"),
    [
        ([4.3, 1.8], "vehicle: expected an object of the car's fields"),
        ({"lenght": 4.3}, "vehicle: unknown key(s) ['lenght']"),
        ({"length": "4.3"}, "vehicle.length: expected a finite number (metres), got '4.3'"),
        ({"width": True}, "vehicle.width: expected a finite number"),
        ({"max_steer": None}, "vehicle.max_steer: expected a finite number (radians)"),
        ({"max_steer_rate": -1}, "vehicle.max_steer_rate: must be > 0"),
        ({"wheelbase": 5.0}, "vehicle.wheelbase: must be shorter than the length"),
        ({"min_turning_radius": 1.0}, "vehicle.min_turning_radius: the steering limit"),
    ],
)
def test_a_bad_car_is_named_by_its_field(value, message):
    with pytest.raises(InputError) as info:
        vehicle_from_json(value)
    assert str(info.value).startswith(message), str(info.value)
    with pytest.raises(InputError, match=r"^plan\.vehicle"):
        vehicle_from_json(value, "plan.vehicle")


def test_a_map_file_keeps_its_car_and_the_papers_car_writes_no_key(tmp_path):
    m = builtin_map("parking_lot")
    save_map(m, tmp_path / "paper.json")
    assert "vehicle" not in json.loads((tmp_path / "paper.json").read_text())
    tiny = dataclasses.replace(m, vehicle=TINY)
    save_map(tiny, tmp_path / "tiny.json")
    assert load_map(tmp_path / "tiny.json") == tiny
    # A car given in Python wins over the file's.
    assert load_map(tmp_path / "tiny.json", VehicleParams()).vehicle == VehicleParams()


def test_the_file_car_decides_whether_its_query_is_valid(tmp_path):
    # The paper's car fits parking_lot's goal bay; a 5.5 x 2.2 m car does not.
    doc = builtin_map("parking_lot").to_json()
    doc["vehicle"] = {"length": 5.5, "width": 2.2, "wheelbase": 3.2}
    (tmp_path / "wide.json").write_text(json.dumps(doc))
    with pytest.raises(InputError, match=r"^goal: the car's body"):
        load_map(tmp_path / "wide.json")


@pytest.fixture(scope="module")
def tiny_runs(tmp_path_factory):
    """plan on a map file holding the tiny car; verify and simulate --path of that plan."""
    d = tmp_path_factory.mktemp("tiny")
    save_map(dataclasses.replace(builtin_map("parking_lot"), vehicle=TINY), d / "tiny.json")
    plan = _cli("plan", "tiny.json", "--json", "p.json", cwd=d)
    assert plan.returncode == 0, plan.stderr
    doc = json.loads((d / "p.json").read_text())
    # The same rows without the car: read as a plan made before the field.
    (d / "nocar.json").write_text(json.dumps({k: v for k, v in doc.items() if k != "vehicle"}))
    return {"dir": d, "doc": doc,
            "verify": _cli("verify", "p.json", "--json", "-", cwd=d),
            "verify_builtin": _cli("verify", "p.json", "parking_lot", "--json", "-", cwd=d),
            "verify_nocar": _cli("verify", "nocar.json", "--json", "-", cwd=d),
            "sim": _cli("simulate", "parking_lot", "--path", "p.json", "--max-time", "3",
                        "--json", "-", cwd=d)}  # fmt: skip


def test_plan_uses_and_records_the_file_car(tiny_runs):
    doc = tiny_runs["doc"]
    assert vehicle_from_json(doc["vehicle"]) == TINY
    rows = np.asarray(doc["path"])
    # Tighter than the paper's car may turn (1/6), within the tiny car's 1/3.
    assert 1 / 6 < _menger(rows) <= TINY.kappa_max + 2e-3


def test_verify_judges_the_path_for_the_plans_car(tiny_runs):
    run = tiny_runs["verify"]
    assert run.returncode == 0, run.stdout + run.stderr
    report = json.loads(run.stdout)
    assert report["ok"] and report["kappa_max"] == pytest.approx(TINY.kappa_max)
    # Against the built-in map (the paper's car there): still the plan's car, no warning.
    run = tiny_runs["verify_builtin"]
    assert run.returncode == 0 and "warning" not in run.stderr.lower(), run.stderr
    # A plan without the field is judged for its map's car: the file's tiny car.
    assert tiny_runs["verify_nocar"].returncode == 0, tiny_runs["verify_nocar"].stdout


def test_verify_warns_when_the_maps_own_car_is_another(tiny_runs):
    d = tiny_runs["dir"]
    other = dataclasses.replace(TINY, width=1.0)
    save_map(dataclasses.replace(builtin_map("parking_lot"), vehicle=other), d / "other.json")
    run = _cli("verify", "p.json", "other.json", cwd=d)
    assert run.returncode == 0, run.stdout + run.stderr
    assert "its car is not the one the plan was made for" in run.stderr


def test_simulate_path_drives_the_plans_car(tiny_runs):
    run = tiny_runs["sim"]
    assert run.returncode in (0, 1), run.stderr
    report = json.loads(run.stdout)
    assert report["kappa_max"] == pytest.approx(TINY.kappa_max)


def test_a_bad_car_in_a_map_file_is_one_line_exit_2(tmp_path):
    doc = builtin_map("overtake").to_json()
    doc["vehicle"] = {"wheelbase": 9.0}
    (tmp_path / "bad.json").write_text(json.dumps(doc))
    run = _cli("plan", "bad.json", cwd=tmp_path)
    assert run.returncode == 2 and "Traceback" not in run.stderr
    assert run.stderr.strip().count("\n") == 0
    assert "vehicle.wheelbase: must be shorter than the length" in run.stderr


def test_maps_import_vehicle_flag_takes_an_object_or_a_file(tmp_path):
    from PIL import Image

    img = np.full((100, 300), 254, np.uint8)
    img[:42], img[58:] = 0, 0  # a 1.6 m corridor: the paper's 1.8 m car does not fit
    Image.fromarray(img).save(tmp_path / "corr.png")
    base = ["maps", "--import", "corr.png", "--resolution", "0.1", "--start", "2,5,0",
            "--goal", "26,5,0"]  # fmt: skip
    run = _cli(*base, "--out", "a.json", cwd=tmp_path)
    assert run.returncode == 2 and "--vehicle gives another" in run.stderr
    run = _cli(*base, "--out", "a.json", "--vehicle", json.dumps(vehicle_to_json(TINY)),
               cwd=tmp_path)  # fmt: skip
    assert run.returncode == 0, run.stderr
    assert load_map(tmp_path / "a.json").vehicle == TINY
    run = _cli(*base, "--out", "b.json", "--vehicle", "a.json", cwd=tmp_path)  # its car
    assert run.returncode == 0 and load_map(tmp_path / "b.json").vehicle == TINY
    run = _cli(*base, "--out", "c.json", "--vehicle", '{"width": 0}', cwd=tmp_path)
    assert run.returncode == 2 and "--vehicle: vehicle.width" in run.stderr
    assert not (tmp_path / "c.json").exists()


def test_an_infinite_steering_rate_is_the_instant_car_and_survives_a_file(tmp_path):
    instant = VehicleParams(max_steer_rate=math.inf)
    assert instant == VehicleParams(max_steer_rate=None) and instant.max_steer_rate is None
    m = dataclasses.replace(builtin_map("overtake"), vehicle=instant)
    save_map(m, tmp_path / "m.json")
    assert load_map(tmp_path / "m.json") == m


def test_verify_names_the_car_it_judged(tiny_runs):
    report = json.loads(tiny_runs["verify"].stdout)
    assert vehicle_from_json(report["vehicle"]) == TINY
    d = tiny_runs["dir"]
    run = _cli("verify", "p.json", cwd=d)
    assert "for a car of 2.5 x 1.2 m, wheelbase 1.6 m, min turning radius 3 m (the plan's)" \
        in run.stdout, run.stdout


@pytest.mark.parametrize(
    ("fields", "message"),
    [({"max_steer_rate": 1e-12}, "vehicle.max_steer_rate: at least 0.01 rad/s"),
     ({"length": 0.1, "wheelbase": 0.05}, "vehicle.length: at least 0.5 m"),
     ({"min_turning_radius": 0.3, "wheelbase": 0.1, "max_steer": 1.2},
      "vehicle.min_turning_radius: at least 0.5 m")],
)  # fmt: skip
def test_cars_too_small_or_too_slow_for_the_sampling_are_refused(fields, message):
    """A 1e-12 rad/s actuator asked for an 8 GiB allocation; a 1 mm car's rows were too
    coarse for its turns and verify passed it through a wall (an audit)."""
    with pytest.raises(InputError, match=f"^{message}"):
        VehicleParams(**fields)
    assert VehicleParams(length=0.5, wheelbase=0.3, min_turning_radius=0.5, max_steer=0.6,
                         max_steer_rate=0.01).length == 0.5  # the least accepted

