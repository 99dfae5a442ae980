"""Code review of session 50 (6fda33d..HEAD): the map file's car, verify's and
simulate's use of the plan's car, the checker cache's build lock, the weakly keyed
fan cache, atomic temp names, bench config files, gym config_of and the CLI's
interrupt handling.

Strict xfails are real bugs found by the review; the other tests pin behaviour the
session added but left untested.
"""

from __future__ import annotations

import dataclasses
import gc
import json
import math
import os
import threading
import warnings
import weakref

import numpy as np
import pytest

from rrtdrive.cli import main
from rrtdrive.maps import Map, Obstacle, load_map, map_from_json, save_map
from rrtdrive.types import InputError, Pose, VehicleParams
from rrtdrive.vehicle_json import vehicle_from_json, vehicle_to_json

TINY = VehicleParams(length=2.5, width=1.2, wheelbase=1.6, min_turning_radius=3.0,
                     max_steer_rate=0.2)  # fmt: skip
BIG = VehicleParams(length=5.0, width=2.0, wheelbase=3.0, min_turning_radius=7.0, max_steer=0.5)


PAPER = VehicleParams()


def _open_map(vehicle: VehicleParams = PAPER, name: str = "open") -> Map:
    """An empty 40 x 12 m map with one box off the straight start-goal line."""
    return Map(name, (0.0, 0.0, 40.0, 12.0), (Obstacle((20.0, 10.5), (2.0, 1.0), 0.0),),
               Pose(5.0, 4.0, 0.0), Pose(30.0, 4.0, 0.0), vehicle)  # fmt: skip


def _straight_plan(vehicle: VehicleParams | None) -> dict:
    """A plan JSON driving the open map's straight line, rows 0.25 m apart."""
    xs = np.arange(5.0, 30.0 + 1e-9, 0.25)
    plan: dict = {"map": "open", "path": [[float(x), 4.0, 0.0, 0.0, 1.0] for x in xs]}
    if vehicle is not None:
        plan["vehicle"] = vehicle_to_json(vehicle)
    return plan


def _write(path, doc) -> str:
    path.write_text(json.dumps(doc), encoding="utf-8")
    return str(path)


# ----------------------------------------------------------------------- vehicle JSON


def test_vehicle_json_round_trip_and_field_defaults():
    assert vehicle_from_json(vehicle_to_json(TINY)) == TINY
    assert vehicle_from_json({}) == VehicleParams()  # every field left out: the paper's car
    assert vehicle_from_json({"max_steer_rate": None}).max_steer_rate is None  # instant
    assert vehicle_to_json(VehicleParams(max_steer_rate=math.inf))["max_steer_rate"] is None
    with pytest.raises(InputError, match=r"^plan\.vehicle\.wheelbase: must be shorter"):
        vehicle_from_json({"wheelbase": 10.0}, "plan.vehicle")
    with pytest.raises(InputError, match=r"^scenario\.vehicle\.length: expected a finite"):
        vehicle_from_json({"length": True}, "scenario.vehicle")


def test_gym_map_fields_keep_an_instant_steering_car_given_as_inf():
    from rrtdrive.envs.config import map_of_fields

    m = dataclasses.replace(_open_map(), vehicle=VehicleParams(max_steer_rate=math.inf))
    back = map_of_fields(dataclasses.asdict(m))
    assert back.vehicle.max_steer_rate in (None, math.inf)


def test_gym_map_fields_keep_a_custom_car():
    from rrtdrive.envs.config import map_of_fields

    m = _open_map(TINY)
    assert map_of_fields(dataclasses.asdict(m)) == m


# ----------------------------------------------------------------------- map files


def test_map_file_keeps_another_car_and_paper_car_files_are_unchanged(tmp_path):
    save_map(_open_map(TINY), tmp_path / "tiny.json")
    save_map(_open_map(), tmp_path / "paper.json")
    assert json.loads((tmp_path / "tiny.json").read_text())["vehicle"] == vehicle_to_json(TINY)
    assert "vehicle" not in json.loads((tmp_path / "paper.json").read_text())
    assert load_map(tmp_path / "tiny.json").vehicle == TINY
    assert load_map(tmp_path / "paper.json").vehicle == VehicleParams()
    # A Python argument wins over the file's car.
    assert load_map(tmp_path / "tiny.json", BIG).vehicle == BIG


def test_map_file_vehicle_errors_are_named():
    doc = _open_map().to_json()
    with pytest.raises(InputError, match=r"^vehicle: unknown key\(s\) \['lenght'\]"):
        map_from_json({**doc, "vehicle": {"lenght": 3.0}})
    with pytest.raises(InputError, match=r"^vehicle\.min_turning_radius"):
        map_from_json({**doc, "vehicle": {"min_turning_radius": 1.0}})


def test_a_malformed_file_car_is_refused_even_when_an_argument_replaces_it():
    doc = {**_open_map().to_json(), "vehicle": "junk"}
    with pytest.raises(InputError, match="vehicle"):
        map_from_json(doc, VehicleParams())


def test_planning_problem_takes_the_maps_car_by_default():
    from rrtdrive.planning import PlanningProblem
    from rrtdrive.planning.checker_cache import cached_checker

    m = _open_map(TINY)
    problem = PlanningProblem(m, cached_checker(m), m.start, m.goal)
    assert problem.vehicle == TINY
    paper = _open_map()
    assert PlanningProblem(paper, cached_checker(paper), paper.start, paper.goal).vehicle == (
        VehicleParams()
    )
    # A car other than the checker's is still refused when given explicitly.
    with pytest.raises(InputError, match="problem.vehicle"):
        PlanningProblem(m, cached_checker(m), m.start, m.goal, VehicleParams())


# ----------------------------------------------------------------------- plan / verify


def test_plan_json_records_the_map_files_car(tmp_path, capsys):
    save_map(_open_map(TINY), tmp_path / "tiny.json")
    save_map(_open_map(), tmp_path / "paper.json")
    for name, car in (("tiny", TINY), ("paper", VehicleParams())):
        out = tmp_path / f"{name}_plan.json"
        assert main(["plan", str(tmp_path / f"{name}.json"), "--json", str(out)]) == 0
        assert json.loads(out.read_text())["vehicle"] == vehicle_to_json(car)
    capsys.readouterr()


def _verify(plan_file: str, map_file: str, out, capsys) -> tuple[int, dict, str]:
    rc = main(["verify", plan_file, map_file, "--json", str(out)])
    err = capsys.readouterr().err
    return rc, json.loads(out.read_text()), err


def test_verify_judges_by_the_plans_car_and_names_the_bound_sharpness_bound(tmp_path, capsys):
    paper_map = str(tmp_path / "paper.json")
    big_map = str(tmp_path / "big.json")
    save_map(_open_map(), paper_map)
    save_map(_open_map(BIG), big_map)
    tiny_plan = _write(tmp_path / "tiny_plan.json", _straight_plan(TINY))
    old_plan = _write(tmp_path / "old_plan.json", _straight_plan(None))

    rc, data, err = _verify(tiny_plan, paper_map, tmp_path / "v1.json", capsys)
    assert rc == 0
    assert data["kappa_max"] == pytest.approx(TINY.kappa_max)
    assert data["sharpness_bound"] == pytest.approx(0.1)  # 0.2 rad/s / 2 m/s
    assert "max_sharpness" not in data
    assert "its car is not the one" not in err

    # Both cars given, and different: the plan's judges, with a warning.
    rc, data, err = _verify(tiny_plan, big_map, tmp_path / "v2.json", capsys)
    assert rc == 0 and data["kappa_max"] == pytest.approx(TINY.kappa_max)
    assert "its car is not the one the plan was made for" in err

    # A plan written before the field: the map's car.
    rc, data, err = _verify(old_plan, big_map, tmp_path / "v3.json", capsys)
    assert rc == 0 and data["kappa_max"] == pytest.approx(BIG.kappa_max)
    assert "its car is not" not in err

    # --no-sharpness: the bound is null under its own name.
    rc = main(["verify", tiny_plan, paper_map, "--no-sharpness", "--json",
               str(tmp_path / "v4.json")])  # fmt: skip
    capsys.readouterr()
    assert rc == 0 and json.loads((tmp_path / "v4.json").read_text())["sharpness_bound"] is None


def test_verify_refuses_a_malformed_plan_car_naming_it(tmp_path, capsys):
    save_map(_open_map(), tmp_path / "paper.json")
    plan = _straight_plan(None)
    plan["vehicle"] = {"length": -1.0}
    rc = main(["verify", _write(tmp_path / "p.json", plan), str(tmp_path / "paper.json")])
    assert rc == 2
    assert "plan.vehicle.length" in capsys.readouterr().err


# ----------------------------------------------------------------------- maps --import


def _gray_png(path, rows: int = 120, cols: int = 400) -> str:
    from PIL import Image

    img = np.full((rows, cols), 255, np.uint8)
    img[:5, :] = img[-5:, :] = 0  # walls top and bottom
    Image.fromarray(img).save(path)
    return str(path)


def test_maps_import_vehicle_is_kept_and_checks_the_query_for_it(tmp_path, capsys):
    png = _gray_png(tmp_path / "floor.png")
    base = ["maps", "--import", png, "--resolution", "0.1", "--goal", "30,6,0"]
    # 0.8 m above the bottom wall (0 - 0.5 m): the paper's car (0.9 m half width) crosses
    # it, the tiny car (0.6 m) does not.
    start = "--start=5,1.3,0"
    tiny = json.dumps(vehicle_to_json(TINY))
    out = tmp_path / "m.json"
    rc = main([*base, start, "--out", str(out)])
    err = capsys.readouterr().err
    assert rc == 2 and "the car is the paper's, 4.3 x 1.8 m: --vehicle gives another" in err
    assert main([*base, start, "--out", str(out), "--vehicle", tiny]) == 0
    capsys.readouterr()
    assert load_map(out).vehicle == TINY
    # A map file with a car gives its car; one without holds the paper's car (save_map
    # writes none for it), which it then gives (it was refused as "holds no vehicle").
    out2 = tmp_path / "m2.json"
    assert main([*base, start, "--out", str(out2), "--vehicle", str(out)]) == 0
    assert load_map(out2).vehicle == TINY
    save_map(_open_map(), tmp_path / "paper.json")
    rc = main([*base, "--start=5,6,0", "--out", str(out2), "--vehicle",
               str(tmp_path / "paper.json")])  # fmt: skip
    assert rc == 0 and load_map(out2).vehicle == VehicleParams()


def test_maps_import_refuses_32_bit_tiff_but_reads_16_bit(tmp_path, capsys):
    from PIL import Image

    img = np.full((120, 400), 255, np.uint16)  # white floor, a black wall
    img[:5, :] = 0
    Image.fromarray(img.astype(np.int32)).save(tmp_path / "i32.tif")  # 0..255 in 32 bits
    Image.fromarray(img * 257).save(tmp_path / "i16.tif")
    args = ["--resolution", "0.1", "--start", "5,6,0", "--goal", "30,6,0"]
    rc = main(["maps", "--import", str(tmp_path / "i32.tif"), *args, "--out",
               str(tmp_path / "a.json")])  # fmt: skip
    assert rc == 2 and "32-bit samples" in capsys.readouterr().err
    rc = main(["maps", "--import", str(tmp_path / "i16.tif"), *args, "--out",
               str(tmp_path / "b.json")])  # fmt: skip
    capsys.readouterr()
    assert rc == 0 and len(load_map(tmp_path / "b.json").obstacles) >= 1


def test_plan_step_is_typed(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["plan", "parking_lot", "--step", "abc"])
    assert exc.value.code == 2
    assert "--step: expected a number > 0, got 'abc'" in capsys.readouterr().err


# ----------------------------------------------------------------------- checker cache


def test_checker_cache_clears_on_the_18th_map_and_builds_each_map_once(monkeypatch):
    from rrtdrive.collision import CollisionChecker
    from rrtdrive.planning import checker_cache

    monkeypatch.setattr(checker_cache, "_CHECKERS", {})
    built: list[object] = []
    real = CollisionChecker.for_map

    def counting(m, config=None):
        built.append(m.name)
        return real(m, config=config)

    monkeypatch.setattr(CollisionChecker, "for_map", staticmethod(counting))
    maps = [dataclasses.replace(_open_map(), bounds=(0.0, 0.0, 40.0 + i, 12.0))
            for i in range(18)]  # fmt: skip
    first = [checker_cache.cached_checker(m) for m in maps[:17]]
    assert len(checker_cache._CHECKERS) == 17
    assert checker_cache.cached_checker(maps[0]) is first[0]  # kept
    checker_cache.cached_checker(maps[17])
    assert len(checker_cache._CHECKERS) == 1  # the 18th cleared them
    assert len(built) == 18
    assert not checker_cache._BUILDING

    # Four threads asking for one new map at once: one build.
    new = dataclasses.replace(_open_map(), bounds=(0.0, 0.0, 99.0, 12.0))
    got: list[object] = []
    barrier = threading.Barrier(4)

    def ask():
        barrier.wait()
        got.append(checker_cache.cached_checker(new))

    threads = [threading.Thread(target=ask) for _ in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert len(built) == 19 and len({id(c) for c in got}) == 1


def test_checker_cache_recovers_from_a_failed_build(monkeypatch):
    from rrtdrive.collision import CollisionChecker
    from rrtdrive.planning import checker_cache

    monkeypatch.setattr(checker_cache, "_CHECKERS", {})
    monkeypatch.setattr(checker_cache, "_BUILDING", {})
    real = CollisionChecker.for_map
    m = dataclasses.replace(_open_map(), bounds=(0.0, 0.0, 77.0, 12.0))

    def failing(m, config=None):
        raise MemoryError("no room")

    monkeypatch.setattr(CollisionChecker, "for_map", staticmethod(failing))
    with pytest.raises(MemoryError):
        checker_cache.cached_checker(m)
    monkeypatch.setattr(CollisionChecker, "for_map", staticmethod(real))
    # The lock left by the failed build is free: the next call builds (no deadlock).
    done: list[object] = []
    t = threading.Thread(target=lambda: done.append(checker_cache.cached_checker(m)))
    t.start()
    t.join(timeout=30)
    assert done and checker_cache.cached_checker(m) is done[0]


# ----------------------------------------------------------------------- fan cache


def test_fan_cache_is_per_checker_bounded_and_weak():
    from rrtdrive.collision import CollisionChecker
    from rrtdrive.planning.improved import boxed

    m = _open_map()
    a, b = CollisionChecker.for_map(m), CollisionChecker.for_map(m)  # equal maps, two objects
    poses = [Pose(5.0, 4.0, 0.0), Pose(30.0, 4.0, 0.0), Pose(10.0, 4.0, 0.0)]
    for p in poses:
        boxed.open_share(a, p)
    boxed.open_share(b, poses[0])
    assert len(boxed._FANS[a]) == boxed._FANS_PER_CHECKER == 2
    assert len(boxed._FANS[b]) == 1  # its own entry, not a's
    assert boxed.open_share(a, poses[2]) == boxed.open_share(b, poses[2])
    gone = weakref.ref(a)
    del a
    gc.collect()  # other tests' dropped checkers may go too: count only these two
    assert gone() is None and b in boxed._FANS


def test_hybrid_tables_are_read_only():
    from rrtdrive.planning.hybrid.primitives import primitive_sets
    from rrtdrive.planning.hybrid.resolution import _dubins_table

    table = _dubins_table(6.0, 36)
    with pytest.raises(ValueError, match="read-only"):
        table.lengths[0] = 1.0
    sets = primitive_sets(1 / 6, 5, 1.0, 0.25, 0, (2.0,))
    with pytest.raises(ValueError, match="read-only"):
        sets[0].kappas[0] = 0.0


# ----------------------------------------------------------------------- atomic names


def _name_max(folder) -> int:
    try:
        return os.pathconf(folder, "PC_NAME_MAX")
    except (OSError, ValueError):
        return 255


@pytest.mark.parametrize("char", ["a", "é", "€", "😀"])
def test_atomic_write_takes_the_longest_name_of_multibyte_characters(tmp_path, char):
    from rrtdrive.maps import write_text_atomic

    room = _name_max(tmp_path) - len(".json")
    name = char * (room // len(char.encode())) + ".json"
    target = tmp_path / name
    write_text_atomic(target, "done")
    assert target.read_text() == "done"
    assert sorted(p.name for p in tmp_path.iterdir()) == [name]  # no temporary left


def test_atomic_write_takes_a_long_name_with_a_long_suffix(tmp_path):
    from rrtdrive.maps import write_text_atomic

    name = "v." + "b" * (_name_max(tmp_path) - 2)
    target = tmp_path / name
    target.write_text("")  # the file system takes the name
    target.unlink()
    write_text_atomic(target, "done")
    assert target.read_text() == "done"


def test_atomic_write_error_names_the_target_not_the_temporary(tmp_path):
    from rrtdrive.maps import write_text_atomic

    target = tmp_path / "missing" / "out.json"
    with pytest.raises(FileNotFoundError) as exc:
        write_text_atomic(target, "x")
    assert exc.value.filename == str(target)


# ----------------------------------------------------------------------- bench config


def test_bench_config_names_the_duplicated_key_after_a_unicode_line_separator(tmp_path):
    from rrtdrive.bench.config_file import load_toml

    f = tmp_path / "b.toml"
    f.write_text('# a\u2028b\nruns = 1\nplanners = ["rrt"]\nruns = 2\n', encoding="utf-8")
    with pytest.raises(InputError, match=r"^runs: given twice"):
        load_toml(f)


def test_bench_config_names_the_duplicated_key(tmp_path):
    from rrtdrive.bench.config_file import load_toml

    f = tmp_path / "b.toml"
    f.write_text('runs = 1\nplanners = ["rrt"]\nruns = 2\n', encoding="utf-8")
    with pytest.raises(InputError, match=r"^runs: given twice in .* \(line 3\)"):
        load_toml(f)


def test_bench_config_expands_home_in_maps_and_out(tmp_path, monkeypatch):
    from rrtdrive.bench.config_file import load_toml

    monkeypatch.setenv("HOME", str(tmp_path))
    f = tmp_path / "b.toml"
    f.write_text('maps = ["~/lot.json", "parking_lot"]\nout = "~/b"\n', encoding="utf-8")
    data = load_toml(f)
    assert data["maps"] == [str(tmp_path / "lot.json"), "parking_lot"]
    assert data["out"] == str(tmp_path / "b")


def test_bench_config_expands_home_in_scenario_map_files(tmp_path, monkeypatch):
    from rrtdrive.bench.config_file import load_toml

    monkeypatch.setenv("HOME", str(tmp_path))
    f = tmp_path / "b.toml"
    f.write_text('scenarios = ["~/lot.json", "parking"]\n', encoding="utf-8")
    assert load_toml(f)["scenarios"] == [str(tmp_path / "lot.json"), "parking"]


# ----------------------------------------------------------------------- gym, signals


def test_config_of_builds_from_fields_and_names_the_field():
    from rrtdrive.frozen import config_of
    from rrtdrive.types import Budget

    b = Budget(max_iterations=50)
    assert config_of(Budget, b, "budget") is b
    assert config_of(Budget, {"max_iterations": 50}, "budget") == b
    with pytest.raises(InputError, match=r"^budget: .*bogus"):
        config_of(Budget, {"bogus": 1}, "budget")
    with pytest.raises(InputError, match=r"^budget: expected a Budget or its fields"):
        config_of(Budget, "x", "budget")


def test_interrupt_behind_finds_the_signal_and_stops_on_cycles():
    from rrtdrive.cli_signals import Terminated, interrupt_behind

    ki = Terminated()
    outer = ImportError("initialization failed")
    outer.__context__ = RuntimeError("middle")
    outer.__context__.__cause__ = ki
    assert interrupt_behind(outer) is ki
    a, b = ImportError("a"), ImportError("b")
    a.__context__, b.__context__ = b, a  # a cycle: no hang, no signal
    assert interrupt_behind(a) is None
    assert interrupt_behind(ImportError("plain")) is None


def test_a_map_file_car_loads_for_any_warning_filter(tmp_path):
    # Loading a car must not warn (no InputWarning from a well-formed vehicle).
    save_map(_open_map(TINY), tmp_path / "t.json")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert load_map(tmp_path / "t.json").vehicle == TINY


def test_verify_with_a_plan_car_warns_about_a_degree_yaw_once(tmp_path, capsys):
    save_map(_open_map(), tmp_path / "paper.json")
    plan = _straight_plan(TINY)
    plan["start"] = [5.0, 4.0, 90.0]
    main(["verify", _write(tmp_path / "p.json", plan), str(tmp_path / "paper.json")])
    err = capsys.readouterr().err
    assert err.count("yaw 90 is more than a full turn") == 1
    assert "plan.start: yaw 90" in err


def test_verify_without_a_plan_car_warns_about_a_degree_yaw_once(tmp_path, capsys):
    save_map(_open_map(), tmp_path / "paper.json")
    plan = _straight_plan(None)
    plan["start"] = [5.0, 4.0, 90.0]
    main(["verify", _write(tmp_path / "p.json", plan), str(tmp_path / "paper.json")])
    err = capsys.readouterr().err
    assert err.count("yaw 90 is more than a full turn") == 1
    assert "plan.start: yaw 90" in err
