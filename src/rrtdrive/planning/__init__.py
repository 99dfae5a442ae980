"""Planners: RRT, RRT-Connect, RRT* and the improved RRT-Connect, behind one protocol."""

from __future__ import annotations

import dataclasses
import inspect
import time
from collections.abc import Callable
from typing import TYPE_CHECKING

from rrtdrive.json_safe import options_from_json
from rrtdrive.planning.base import (
    PLANNERS,
    GrowingTree,
    Planner,
    PlanningProblem,
    polyline_path,
)
from rrtdrive.types import Budget, InputError, PlanResult
from rrtdrive.values import did_you_mean

if TYPE_CHECKING:
    import numpy as np

    from rrtdrive.collision import CheckerConfig
    from rrtdrive.maps import Map

__all__ = [
    "PLANNERS", "GrowingTree", "Planner", "PlanningProblem", "make_planner", "polyline_path",
    "reverses", "solve_on_map", "unknown_planner",
]


def _load_builtin_planners() -> None:
    # Importing the modules registers their planners.
    import importlib

    for module in ("rrt", "rrt_connect", "rrt_star", "improved", "hybrid"):
        try:
            importlib.import_module(f"rrtdrive.planning.{module}")
        except ModuleNotFoundError as exc:  # a planner module not written yet
            if exc.name != f"rrtdrive.planning.{module}":
                raise


_load_builtin_planners()


def make_planner(name: str, **options: object) -> Planner:
    """Build the registered planner ``name`` with keyword ``options``.

    Non-finite numbers may be spelt as a plan JSON's ``planner_options`` spell them
    (``"Infinity"``, ``"-Infinity"``, ``"NaN"``: :func:`rrtdrive.json_safe.options_json`),
    so ``make_planner(doc["planner"], **doc["planner_options"])`` rebuilds a plan's planner.

    Parameters
    ----------
    name : str
        A registered name (``rrtdrive plan --help`` lists them).
    **options
        The planner's settings by field name (its config's fields).

    Returns
    -------
    Planner

    Raises
    ------
    InputError
        For an unknown name or option.
    """
    try:
        factory = PLANNERS[name]
    except (KeyError, TypeError):  # TypeError: an unhashable name (a list)
        raise unknown_planner("planner", name) from None
    try:
        allowed = inspect.signature(factory).parameters
    except (TypeError, ValueError):  # no signature to read: the factory decides
        allowed = None
    if allowed is not None and not any(p.kind is p.VAR_KEYWORD for p in allowed.values()):
        for key in options:
            if key not in allowed:
                raise InputError(
                    f"planner.{key}: unknown option for {name}{did_you_mean(key, allowed)}; "
                    f"allowed {sorted(allowed)}"
                )
    options = options_from_json(options)
    try:
        return factory(**options)
    except TypeError as exc:
        raise InputError(f"planner: {exc}") from None


def solve_on_map(
    planner: Callable[[], Planner],
    m: Map,
    rng: np.random.Generator,
    budget: Budget,
    *,
    config: CheckerConfig | None = None,
    reverse: bool = False,
) -> tuple[PlanningProblem, PlanResult]:
    """Build the query on map ``m`` and solve it; the map's set-up counts as set-up.

    The distance field :meth:`PlanningProblem.from_map` builds (once per map) is added
    to the result's ``setup_time_s``, never to ``planning_time_s``: as ``rrtdrive plan``
    and ``rrtdrive simulate`` report it.

    Parameters
    ----------
    planner : callable
        Gives the planner, called after the problem is built (so that a map's bad
        bounds are named before a planner's bad option).
    m : Map
        The map, its start and goal.
    rng : numpy.random.Generator
        The planner's randomness.
    budget : Budget
        The query's budget.
    config : CheckerConfig, optional
        The collision grid (``None``: the default).
    reverse : bool
        Whether the path may change gear.

    Returns
    -------
    problem : PlanningProblem
    result : PlanResult
    """
    t0 = time.perf_counter()
    problem = PlanningProblem.from_map(m, config=config, reverse=reverse)
    field_s = time.perf_counter() - t0
    result = planner().solve(problem, rng, budget)
    return problem, dataclasses.replace(result, setup_time_s=result.setup_time_s + field_s)


def unknown_planner(field: str, name: object) -> InputError:
    """The error for a planner name not registered: the closest name, then all of them.

    Parameters
    ----------
    field : str
        The option or flag that gave the name (the message's first word).
    name : object
        What the user gave.

    Returns
    -------
    InputError

    Examples
    --------
    >>> print(unknown_planner("--planner", "hybrid-astar"))  # doctest: +ELLIPSIS
    --planner: unknown planner 'hybrid-astar' (did you mean 'hybrid-a-star'?); choose from ...
    """
    hint = ""
    ompl_known = any(n.startswith("ompl-") for n in PLANNERS)
    if isinstance(name, str) and name.startswith("ompl-") and not ompl_known:
        # The OMPL comparators register when the bench loads (planning knows no bench).
        hint = (
            "; the OMPL comparators (ompl-r2-*, ompl-rs-*) are registered by "
            "'import rrtdrive.bench' (OMPL itself: pip install 'rrtdrive[ompl]')"
        )
    return InputError(
        f"{field}: unknown planner {name!r}{did_you_mean(name, PLANNERS)}; "
        f"choose from {', '.join(sorted(PLANNERS))}{hint}"
    )


def reverses(name: str) -> bool:
    """Whether the registered planner ``name`` plans gear changes when a problem allows them.

    Parameters
    ----------
    name : str
        A planner name (False for one not registered).

    Returns
    -------
    bool

    Examples
    --------
    >>> reverses("hybrid-a-star"), reverses("improved-rrt-connect"), reverses("rrt")
    (True, True, False)
    """
    return bool(getattr(PLANNERS.get(name), "reverses", False))


def forward_only_note(name: str, *, why: str = "", asked: str = "--reverse takes") -> str:
    """The note for ``--reverse`` given to a planner that plans forward only.

    ``why``: a condition of its, e.g. ``" with --disable escalation"``; ``asked``: what
    the user asked for, with its verb.

    Examples
    --------
    >>> forward_only_note("rrt")
    'note: rrt plans forward only; --reverse takes effect with hybrid-a-star, improved-rrt-connect'
    """
    # Not the OMPL comparators: their Reeds-Shepp curves change gear whatever is asked.
    takes = ", ".join(sorted(n for n in PLANNERS if reverses(n) and not n.startswith("ompl-")))
    return f"note: {name} plans forward only{why}; {asked} effect with {takes}"
