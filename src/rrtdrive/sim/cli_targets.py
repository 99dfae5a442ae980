"""``rrtdrive simulate``'s targets: what a name is, the task it makes, the planner's hint.

Split from :mod:`rrtdrive.sim.cli_simulate`, which parses the flags and runs the episode.
"""

from __future__ import annotations

import argparse
from typing import Any

from rrtdrive.cli_args import flags_for

__all__ = ["make_task", "target_kind", "with_simulate_hint"]


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
    if name in BUILTIN_MAPS or names_map_file(name):
        return "map"
    from rrtdrive.sim.tasks import SCENARIO_VARIANTS, unknown_scenario

    raise unknown_scenario("scenario", name, stock_envs, SCENARIO_VARIANTS)


def _parse_pose(text: str | None, flag: str) -> Any:
    """``"x,y,yaw"`` as a :class:`~rrtdrive.types.Pose` (``None`` stays ``None``)."""
    from rrtdrive.cli_args import parse_pose

    return None if text is None else parse_pose(text, flag)


def make_task(
    args: argparse.Namespace, target: str, oncoming: int, traffic_opts: dict[str, Any],
    make_scenario: Any,
) -> Any:
    """The task of a built-in scenario or of a map, with ``--reverse`` applied."""
    import dataclasses

    from rrtdrive.sim.tasks import CustomTask

    if target == "map":
        from rrtdrive.cli_args import map_with_poses

        start, goal = _parse_pose(args.start, "--start"), _parse_pose(args.goal, "--goal")
        # The poses given replace the file's before it is checked: a file whose own start
        # is bad still serves with a good --start (a bad --start is named by its flag).
        return CustomTask.from_map(
            map_with_poses(args.scenario, start, goal), args.seed, reverse=args.reverse,
            resolution=args.resolution,
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
