"""``rrtdrive simulate``'s targets: what a name is, the task it makes, the planner's hint.

Split from :mod:`rrtdrive.sim.cli_simulate`, which parses the flags and runs the episode.
"""

from __future__ import annotations

import argparse
from typing import Any

from rrtdrive.cli_args import flags_for
from rrtdrive.types import InputError

__all__ = ["given_path", "make_task", "target_kind", "with_simulate_hint"]

#: The flags that plan, which a given path (``--path``) leaves nothing to do: (attribute, flag).
PLANNING_FLAGS = (
    ("planner", "--planner"), ("planner_options", "--planner-option"),
    ("plan_time", "--plan-time"), ("max_iterations", "--max-iterations"),
    ("deterministic", "--deterministic"),
    ("reverse", "--reverse"), ("start", "--start"), ("goal", "--goal"),
    ("resolution", "--resolution"),
)


def with_simulate_hint(episode: Any) -> Any:
    """``episode`` with the planner's timeout hint naming simulate's flag, ``--plan-time``.

    The planners word it for ``rrtdrive plan`` ("raise --max-time or lower
    --max-iterations"); simulate's planning cap is ``--plan-time``, and ``--max-time``
    here is the drive's time limit.
    """
    import dataclasses

    from rrtdrive.planning.result import timeout_message
    from rrtdrive.types import Budget

    # The hint as the planners write it: the last clause of their timeout message.
    hint = timeout_message(0, Budget()).rpartition("; ")[2]
    if hint not in episode.message:
        return episode
    plan = episode.plan
    if plan is not None:
        plan = dataclasses.replace(plan, message=plan.message.replace(hint, _PLAN_TIME_HINT))
    return dataclasses.replace(
        episode, message=episode.message.replace(hint, _PLAN_TIME_HINT), plan=plan
    )


_PLAN_TIME_HINT = "raise --plan-time"


def target_kind(name: str, scenarios: tuple[str, ...], stock_envs: tuple[str, ...]) -> str:
    """``"scenario"``, ``"stock"`` or ``"map"``; an unknown plain name is bad input."""
    from rrtdrive.maps import BUILTIN_MAPS, names_map_file

    if name in scenarios:
        return "scenario"
    if name in stock_envs:
        return "stock"
    # "" (an unset $SCENARIO) is no map file either: as a path it named the current
    # folder, and the error was the map's.
    if name and (name in BUILTIN_MAPS or names_map_file(name)):
        return "map"
    from rrtdrive.sim.tasks import SCENARIO_VARIANTS, unknown_scenario

    raise unknown_scenario("scenario", name, stock_envs, SCENARIO_VARIANTS)


def _parse_pose(text: str | None, flag: str) -> Any:
    """``"x,y,yaw"`` as a :class:`~rrtdrive.types.Pose` (``None`` stays ``None``)."""
    from rrtdrive.cli_args import parse_pose

    return None if text is None else parse_pose(text, flag)


def given_path(args: argparse.Namespace, target: str) -> tuple[Any, str | None, Any]:
    """The path of ``--path``'s plan file and the map it names (``None``: none).

    The path is driven on the map as it is (nothing planned).

    Raises
    ------
    InputError
        Naming ``--path``: the target is not a map, the file is unreadable or not a plan,
        its rows are bad, or it has under two rows; naming a planning flag given with it.
    """
    from rrtdrive.plan_file import plan_car, read_plan_json
    from rrtdrive.verify import path_from_json

    source = args.path
    if target != "map":
        raise InputError(
            f"--path: only a map drives a given path; {args.scenario} sets its own start "
            "and goal (give a map: a .json file or a built-in map name)"
        )
    for attr, flag in PLANNING_FLAGS:
        if getattr(args, attr, None) not in (None, False):
            raise InputError(
                f"{flag}: --path gives the path to drive; nothing is planned"
                + (" (the drive starts at its first row and ends at its last)"
                   if attr in ("start", "goal") else "")
            )
    data = read_plan_json(source, "--path")
    try:
        path = path_from_json(data)
    except InputError as exc:
        raise InputError(f"--path: {exc}") from None
    if len(path) < 2:
        status = data.get("status", "unknown")
        raise InputError(
            f"--path: {source} has no path to drive (status {status}): "
            + ("no rows" if len(path) == 0 else "one row; a path needs two")
        )
    _warn_gearless_reverse(data, path)
    made_on = data.get("map")
    car = plan_car(data, "--path: vehicle")  # None for plans before the field: the map's
    return path, made_on if isinstance(made_on, str) and made_on else None, car


def _warn_gearless_reverse(data: Any, path: Any) -> None:
    """Warn when rows without a gear column move against their yaw (a reverse plan cut short).

    Such rows read as forward (README), so the car drives a reversing plan nose first
    and crashes where ``verify`` would flag it at once (an audit: a plan's gear column
    dropped, the car hit the kerb at t = 48.85 s).
    """
    import math

    import numpy as np

    from rrtdrive.geometry import wrap_angle
    from rrtdrive.verify_measures import travel_directions

    rows = data.get("path") if isinstance(data, dict) else data
    if not rows or len(rows[0]) != 4 or not path.is_forward_only:
        return
    # verify's own reading of the rows' motion: a step more than 90 deg off its yaw.
    direction, moving = travel_directions(path.samples)
    off = np.abs(wrap_angle(direction - path.samples[moving, 2]))
    back = moving[off > math.pi / 2]
    if len(back) == 0:
        return
    import warnings

    from rrtdrive.types import InputWarning

    warnings.warn(
        f"--path: rows without a gear column drive forward, but from row {int(back[0])} "
        "the path moves against its yaw (a reversing plan without its gear column?): add "
        "the gear column, [x, y, yaw, kappa, gear] with -1 in reverse, as plan --json "
        "writes it",
        InputWarning, stacklevel=2,
    )


def make_task(
    args: argparse.Namespace, target: str, oncoming: int, traffic_opts: dict[str, Any],
    make_scenario: Any, path: Any = None, made_on: str | None = None, car: Any = None,
) -> Any:
    """The task of a built-in scenario or of a map, with ``--reverse`` applied.

    A given ``path`` (``--path``) sets the map's start and goal to its first and last
    rows, and allows gear changes when it has any; a plan made on another map
    (``made_on``) is driven as asked, with a warning. ``car``: the plan's car, which
    drives it (a map whose own car differs gets a warning).
    """
    import dataclasses

    from rrtdrive.sim.tasks import CustomTask

    if target == "map" and path is not None:
        from rrtdrive.cli_args import map_with_poses
        from rrtdrive.types import Pose

        ends = Pose(*path.samples[0, :3]), Pose(*path.samples[-1, :3])
        # The poses are the path's ends, not flags the user gave.
        rows = {"start": "--path: the path's first row", "goal": "--path: the path's last row"}
        m = map_with_poses(args.scenario, *ends, names=rows, plan_car=car)
        if made_on is not None and m.name != made_on:
            import warnings

            from rrtdrive.types import InputWarning

            warnings.warn(
                f"--path: the plan was made on map {made_on!r}; it is driven on "
                f"{m.name!r} as asked", InputWarning, stacklevel=2,
            )
        with flags_for(rows):  # a path that ends where it starts: nothing to drive
            return CustomTask.from_map(
                m, args.seed, reverse=not path.is_forward_only, resolution=args.resolution
            )
    if target == "map":
        from rrtdrive.cli_args import map_with_poses

        start, goal = _parse_pose(args.start, "--start"), _parse_pose(args.goal, "--goal")
        # The poses given replace the file's before it is checked: a file whose own start
        # is bad still serves with a good --start (a bad --start is named by its flag).
        m = map_with_poses(args.scenario, start, goal)
        # A goal that is the start pose is named by the flag that made it so (it read
        # "goal: ..." for a --start on the file's goal; an audit).
        named = {"start": "--start"} if start is not None else {}
        if goal is not None or start is not None:
            named["goal"] = "--goal" if goal is not None else "--start"
        with flags_for(named):
            return CustomTask.from_map(
                m, args.seed, reverse=args.reverse, resolution=args.resolution
            )
    # make_scenario names its keywords (lead_speed); on the command line they are flags.
    keywords = ("oncoming", "density", "lead_speed", "lead_model", "reverse_in")
    with flags_for({k: "--" + k.replace("_", "-") for k in keywords}):
        task = make_scenario(
            args.scenario, args.seed, oncoming=oncoming,
            reverse_in=True if args.reverse_in else None, **traffic_opts,
        )
    if args.reverse and not task.reverse:
        task = dataclasses.replace(task, reverse=True)
    return task
