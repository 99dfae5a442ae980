"""Tasks: one class per scenario kind, option validation, views, and the end rules."""

from __future__ import annotations

import dataclasses
import json
import math

import pytest

from rrtdrive.maps import builtin_map
from rrtdrive.parking_layout import PARKING_EMPTY_SPOTS
from rrtdrive.sim.episode import EpisodeStatus, end_message
from rrtdrive.sim.scenes import build_env
from rrtdrive.sim.tasks import (
    SCENARIOS,
    CustomTask,
    OvertakeTask,
    OvertakeTrafficTask,
    ParkingTask,
    Task,
    TaskKind,
    make_scenario,
    overtake_complete,
)
from rrtdrive.types import InputError, VehicleParams


@pytest.mark.parametrize(
    ("name", "cls"),
    [
        ("parking", ParkingTask),
        ("overtake", OvertakeTask),
        ("overtake-traffic", OvertakeTrafficTask),
    ],
)
def test_make_scenario_returns_the_task_class_of_its_kind(name, cls):
    task = make_scenario(name, 2)
    assert type(task) is cls and isinstance(task, Task)
    assert task.name == name == task.kind.value and isinstance(task.name, str)
    assert task == make_scenario(name, 2)  # a pure function of the seed
    assert name in SCENARIOS
    assert task.success_status in (EpisodeStatus.ARRIVED, EpisodeStatus.COMPLETED)


def test_each_kind_has_only_its_own_fields():
    fields = {
        cls: {f.name for f in dataclasses.fields(cls)}
        for cls in (ParkingTask, OvertakeTask, OvertakeTrafficTask, CustomTask)
    }
    assert "spot" in fields[ParkingTask] and "spot" not in fields[OvertakeTask]
    assert "lead_index" in fields[OvertakeTask] and "lead_index" not in fields[ParkingTask]
    assert "density" in fields[OvertakeTrafficTask] and "density" not in fields[OvertakeTask]
    assert "lead" not in fields[ParkingTask] and "oncoming" not in fields[CustomTask]


@pytest.mark.parametrize(
    ("name", "options", "field"),
    [
        ("parking", {"spot": 999}, "spot"),  # issue #15: was "'int' object is not iterable"
        ("parking", {"spot": (0, 0)}, "spot"),
        ("parking", {"spot": "abc"}, "spot"),
        ("parking", {"jitter": 1.0}, "jitter"),
        ("parking", {"jitter": (1.0, -1.0, 0.0)}, "jitter"),
        ("parking", {"vehicle": "car"}, "vehicle"),
        ("parking", {"colour": "red"}, "colour"),
        ("overtake", {"oncoming": "two"}, "oncoming"),
        ("overtake", {"spot": (0, 0, 3)}, "spot"),
        ("parking", {"oncoming": 2}, "oncoming"),
        ("nowhere", {}, "scenario"),
    ],
)
def test_bad_options_raise_one_input_error_naming_the_field(name, options, field):
    with pytest.raises(InputError, match=field):
        make_scenario(name, 0, **options)


def test_options_of_other_kinds_may_be_left_empty():
    # What the CLI passes for every scenario.
    a = make_scenario("parking", 1, oncoming=0, density=None, lead_speed=None, lead_model=None)
    assert a == make_scenario("parking", 1)
    spot = sorted(PARKING_EMPTY_SPOTS)[0]
    assert make_scenario("parking", 1, spot=list(spot)).spot == spot


def test_a_custom_map_builds_a_scene():
    task = CustomTask(map=builtin_map("narrow_gap"), seed=0)
    assert task.name == TaskKind.CUSTOM.value == "custom"
    env = build_env(task)
    try:
        ego = env.unwrapped.vehicle
        assert ego.pose.x == pytest.approx(task.start.x)
        assert len(env.unwrapped.road.objects) == len(task.map.obstacles) + 4  # with walls
    finally:
        env.close()
    with pytest.raises(InputError, match="v_max"):
        CustomTask(map=builtin_map("narrow_gap"), seed=0, v_max=0.0)


def test_views_come_from_the_task():
    park, over, traffic = (make_scenario(n, 0) for n in ("parking", "overtake", "overtake-traffic"))
    assert park.camera().size == (640, 640) and not park.camera().follow
    assert over.camera().scaling == 9.0 and over.scene_view().size == (900, 300)
    assert traffic.camera().follow and traffic.camera().centre == (0.0, 46.0)


def test_describe_reports_the_traffic_settings_only():
    assert make_scenario("overtake", 0).describe() == {}
    d = make_scenario("overtake-traffic", 0, density="low", lead_speed=5.0).describe()
    assert d == {"density_per_km": 5.0, "lead_speed": 5.0, "lead_model": "idm"}
    json.dumps(d)


def test_overtake_complete_as_a_task_rule():
    task = make_scenario("overtake-traffic", 0)
    v = VehicleParams()
    assert overtake_complete((30.0, 44.0, 0.0), (20.0, 44.0), 4.3, 44.0, 4.0, v, 2.0)
    assert task.overtake_complete((30.0, 44.0, 0.0), (20.0, 44.0), 4.3, 2.0)
    assert not task.overtake_complete((30.0, 44.0, math.radians(15.0)), (20.0, 44.0), 4.3, 2.0)
    assert not task.overtake_complete((30.0, 47.0, 0.0), (20.0, 44.0), 4.3, 2.0)


def test_status_values_and_messages_are_the_json_strings():
    assert [s.value for s in EpisodeStatus] == [
        "arrived", "completed", "crashed", "timeout", "plan_failed", "off_path"
    ]
    assert EpisodeStatus.CRASHED == "crashed" and json.dumps(EpisodeStatus.TIMEOUT) == '"timeout"'
    assert end_message(EpisodeStatus.TIMEOUT, 1.0, 90.0, EpisodeStatus.COMPLETED) == (
        "no overtake within 90 s (followed the lead car)"
    )
    assert end_message(EpisodeStatus.TIMEOUT, 1.0, 60.0, EpisodeStatus.ARRIVED) == (
        "not stopped at the goal within 60 s"
    )


def test_the_task_says_its_speed_replanning_and_success_terms():
    from rrtdrive.controllers import SpeedConfig
    from rrtdrive.sim.replanning import ReplanConfig
    from rrtdrive.sim.tasks import REPLANNING_SCENARIOS, TASKS, SuccessPart, traffic_speed_config

    park, over, traffic = (make_scenario(n, 0) for n in ("parking", "overtake", "overtake-traffic"))
    assert park.default_speed() == SpeedConfig(v_max=park.v_max)
    assert traffic.default_speed() == traffic_speed_config(traffic)
    assert TASKS["parking"].REPLAN_CONFIG is None and traffic.REPLAN_CONFIG is ReplanConfig
    assert REPLANNING_SCENARIOS == ("overtake-traffic",)
    assert not hasattr(park, "is_traffic")
    assert SuccessPart() == SuccessPart(None, None, False, None, False, True, False)


def test_no_kind_switches_outside_the_tasks():
    import pathlib

    root = pathlib.Path(__file__).resolve().parents[1]
    # The gym env, the evaluators and the simulation ask the task (bench/ is not covered yet).
    pkg = root / "src" / "rrtdrive"
    files = [*(pkg / "sim").rglob("*.py"), *(pkg / "evaluation").rglob("*.py"),
             *(root / "envs").glob("*.py")]
    needles = ("is_traffic", '== "overtake-traffic"', '== "parking"', "scenario.name ==")
    hits = [
        f"{f.relative_to(root)}: {n}" for f in files if "tasks" not in f.parts
        for n in needles if n in f.read_text()
    ]
    assert not hits
