"""Drawing an episode seed whose query plans, for ``DriveEnv.reset`` without a seed.

A map's episodes are one query whatever the seed (no start jitter, no seeded spot):
planned for 20 seeds in a row, a goal that needs reversing failed after about two
minutes. A query proven impossible is not planned again, nor one that failed
:data:`RETRIES_PER_QUERY` times (the planner's seed differs, the query not).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from rrtdrive.maps import Map
from rrtdrive.planning.diagnosis import DiagnosisKind
from rrtdrive.sim.tasks import Reference
from rrtdrive.sim.tasks.base import Task
from rrtdrive.types import PlanStatus

__all__ = ["MAX_PLAN_ATTEMPTS", "RETRIES_PER_QUERY", "failure_text", "start_drawn_episode"]

#: Episode seeds drawn before giving up when planning keeps failing.
MAX_PLAN_ATTEMPTS = 20
#: Plans of one query (map with its start and goal, gears) before its seeds are passed over.
RETRIES_PER_QUERY = 3


def failure_text(ref: Reference) -> str:
    """The plan's failure message, with its diagnosis (``why: ...``) when it has one.

    The planners' "try --reverse" is the command line's; here it is said as the env's
    option (an audit).
    """
    plan = ref.plan
    text = str(ref.failure)
    if plan is not None and plan.diagnosis is not None:
        text = f"{text}; why: {plan.diagnosis.message}"
    return text.replace("try --reverse", "try scenario_options={'reverse': True}")


def start_drawn_episode(
    config: object,
    rng: np.random.Generator,
    start: Callable[[int, Task], Reference],
) -> int:
    """Draw seeds from ``config.seed_range`` until ``start(seed, task)`` plans; return it.

    Parameters
    ----------
    config : DriveEnvConfig
        Gives ``seed_range`` and ``scenario_for(seed)``.
    rng : numpy.random.Generator
        The env's ``np_random``.
    start : callable
        Plans and sets up the episode of a seed (``DriveEnv._start_episode``).

    Raises
    ------
    RuntimeError
        After :data:`MAX_PLAN_ATTEMPTS` draws without a plan: the last failure, its
        diagnosis, and how to allow gear changes when the scenario plans forward only.
        At once when a plan hits the budget's wall-clock safety cap (``timeout``).
    """
    lo, hi = config.seed_range  # type: ignore[attr-defined]
    failures: dict[tuple[Map, bool], int] = {}
    last: tuple[int, Task, Reference, bool] | None = None
    for _ in range(MAX_PLAN_ATTEMPTS):
        seed = int(rng.integers(lo, hi))
        task = config.scenario_for(seed)  # type: ignore[attr-defined]
        key = (task.map, bool(task.reverse))
        if failures.get(key, 0) >= RETRIES_PER_QUERY:
            continue
        ref = start(seed, task)
        if ref.failure is None:
            return seed
        if ref.plan is not None and ref.plan.status is PlanStatus.TIMEOUT:
            # Not a counted failure: a faster machine would have planned this seed, so
            # drawing on would make which episode plays depend on the machine (an audit).
            budget = config.budget  # type: ignore[attr-defined]
            raise RuntimeError(
                f"planning episode seed {seed} hit the safety cap of {budget.max_time_s:g} s "
                "(budget.max_time_s): the episode drawn would depend on this machine's "
                "speed; give a higher cap, budget=Budget(max_time_s=...), or fewer "
                "iterations, budget=Budget(max_iterations=...)"
            )
        proven = ref.plan is not None and ref.plan.status is PlanStatus.PROVEN_UNREACHABLE
        failures[key] = RETRIES_PER_QUERY if proven else failures.get(key, 0) + 1
        last = (seed, task, ref, proven)
    assert last is not None  # the first draw is always planned
    seed, task, ref, proven = last
    queries = f"{len(failures)} quer{'y' if len(failures) == 1 else 'ies'}"
    # No gear change opens a wall: the goal walled off (proven before any search, or so
    # diagnosed). A forward-only search's proof leaves reversing open, so it keeps the hint.
    plan = ref.plan
    walled = plan is not None and (
        (proven and plan.iterations == 0)
        or (plan.diagnosis is not None and plan.diagnosis.kind is DiagnosisKind.WALLED_OFF)
    )
    hint = "" if task.reverse or walled else (
        "; the path may not change gear: scenario_options={'reverse': True} allows it"
    )
    raise RuntimeError(
        f"no path for {MAX_PLAN_ATTEMPTS} episode seeds in a row ({queries}; last, seed "
        f"{seed}: {failure_text(ref)}){hint}"
    )
