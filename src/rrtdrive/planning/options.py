"""Validation of the planners' keyword options; errors name the option."""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np

from rrtdrive.types import InputError, require_finite, require_int, require_positive
from rrtdrive.values import did_you_mean

__all__ = [
    "MAX_NODES",
    "MAX_RADIUS_FACTOR",
    "MAX_STEP_M",
    "MAX_TREE_STEP_M",
    "MIN_TREE_STEP_M",
    "MIN_SPACING_M",
    "check_probability",
    "check_count",
    "check_flag",
    "check_step",
    "check_known",
]

# Upper (or lower) bounds on options that size arrays or overflow arithmetic: beyond
# them a typo ("1e20") would end in a MemoryError or an OverflowError, not an answer.
#: Longest tree step (m): nothing is sampled along a tree edge, but squares of it are.
MAX_TREE_STEP_M = 1000.0
#: Shortest tree step (m): a greedy extension adds a node per step (--step 0.001 put 2.4
#: million nodes, 540 MB, into one iteration on a 10 km road; an audit).
MIN_TREE_STEP_M = 0.01
#: Longest Hybrid A* primitive step (m): each is sampled every ``check_spacing``.
MAX_STEP_M = 100.0
#: Shortest sampling or checking spacing along a primitive or shot (m).
MIN_SPACING_M = 0.01
#: Largest turning radius, as a multiple of the car's smallest, for a planned turn.
MAX_RADIUS_FACTOR = 100.0
#: Largest tree a planner may preallocate (nodes).
MAX_NODES = 10_000_000

def check_probability(name: str, value: float) -> float:
    """Return ``value`` as a float in ``[0, 1)`` or raise :class:`InputError` naming ``name``.

    Examples
    --------
    >>> check_probability("planner.goal_bias", 0.05)
    0.05
    """
    require_finite(name, value)
    if not 0.0 <= value < 1.0:
        raise InputError(f"{name}: must be in [0, 1), got {value!r}")
    return float(value)


def check_count(name: str, value: int) -> int:
    """Return ``value`` if it is an integer > 0, else raise :class:`InputError` naming ``name``.

    Examples
    --------
    >>> check_count("planner.max_nodes", 450)
    450
    """
    return require_int(name, value)


def check_flag(name: str, value: bool) -> bool:
    """Return ``value`` if it is a bool, else raise :class:`InputError` naming ``name``."""
    if not isinstance(value, (bool, np.bool_)):
        raise InputError(f"{name}: expected true or false, got {value!r}")
    return bool(value)


def check_step(value: float) -> float:
    """Validate ``planner.step`` (metres, :data:`MIN_TREE_STEP_M` to :data:`MAX_TREE_STEP_M`).

    Examples
    --------
    >>> check_step(2)
    2.0
    """
    require_positive("planner.step", value)
    if value > MAX_TREE_STEP_M:
        raise InputError(f"planner.step: must be at most {MAX_TREE_STEP_M:g} m, got {value!r}")
    if value < MIN_TREE_STEP_M:
        raise InputError(f"planner.step: must be at least {MIN_TREE_STEP_M:g} m, got {value!r}")
    return float(value)


def check_known(names: Iterable[str], allowed: Iterable[str], where: str, what: str) -> None:
    """Refuse the first name (sorted) not in ``allowed``, naming it as ``where.name``.

    ``what``: what the names are, for the message (``"field of SmoothingConfig"``).

    Examples
    --------
    >>> check_known(["degree"], ["degree", "prune"], "planner.smooth", "field of X")
    >>> check_known(["degre"], ["degree", "prune"], "smooth", "field of X")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    rrtdrive.types.InputError: smooth.degre: unknown field of X (did you mean 'degree'?); ...
    """
    options = sorted(allowed)
    unknown = sorted(set(names) - set(options))
    if unknown:
        hint = did_you_mean(unknown[0], options)
        raise InputError(f"{where}.{unknown[0]}: unknown {what}{hint}; allowed {options}")
