"""Values made ready for strict JSON (``allow_nan=False``): one helper for every writer."""

from __future__ import annotations

import enum
import math
from collections.abc import Mapping
from typing import Any

__all__ = ["json_safe", "options_from_json", "options_json"]

#: How :func:`options_json` spells the non-finite numbers, and :func:`options_from_json`
#: reads them back (the spellings of Python's own JSON and of JavaScript).
NON_FINITE = {"Infinity": math.inf, "-Infinity": -math.inf, "NaN": math.nan}


def json_safe(value: Any) -> Any:
    """``value`` with non-finite floats as ``None`` and numpy scalars as Python ones.

    Examples
    --------
    >>> json_safe({"a": float("nan"), "b": [1.5, float("inf")]})
    {'a': None, 'b': [1.5, None]}
    """
    if isinstance(value, Mapping):
        return {str(k): json_safe(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [json_safe(v) for v in value]
    if hasattr(value, "item") and callable(value.item) and not isinstance(value, (str, bytes)):
        try:
            value = value.item()
        except (TypeError, ValueError):
            return str(value)
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def options_json(value: Any) -> Any:
    """Keyword options as plain JSON that gives them back: non-finite numbers as text.

    Enums by value, tuples as lists, numpy scalars as Python ones, and ``inf`` /
    ``nan`` as ``"Infinity"`` / ``"NaN"`` (a metric's missing value is ``null``, see
    :func:`json_safe`; an option's ``inf`` means something). :func:`options_from_json`
    is the inverse; ``make_planner`` applies it, so a plan JSON's ``planner_options``
    rebuild its planner.

    Examples
    --------
    >>> options_json({"disable": ("prune",), "ratio": float("inf"), "n": 3})
    {'disable': ['prune'], 'ratio': 'Infinity', 'n': 3}
    """
    if isinstance(value, Mapping):
        return {str(k): options_json(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [options_json(v) for v in value]
    if isinstance(value, enum.Enum):
        return options_json(value.value)
    if hasattr(value, "item") and callable(value.item) and not isinstance(value, (str, bytes)):
        try:  # a numpy scalar (np.int64(6), np.float32(0.5)): json cannot write those
            value = value.item()
        except (TypeError, ValueError):
            return str(value)
    if isinstance(value, float) and not math.isfinite(value):
        return "NaN" if math.isnan(value) else ("Infinity" if value > 0 else "-Infinity")
    return value


def options_from_json(value: Any) -> Any:
    """:func:`options_json`'s inverse for numbers: ``"Infinity"``, ``"-Infinity"``, ``"NaN"``.

    Examples
    --------
    >>> options_from_json({"ratio": "Infinity", "smoothing": {"curve": "bspline"}})
    {'ratio': inf, 'smoothing': {'curve': 'bspline'}}
    """
    if isinstance(value, Mapping):
        return {k: options_from_json(v) for k, v in value.items()}
    if isinstance(value, list):
        return [options_from_json(v) for v in value]
    if isinstance(value, str) and value in NON_FINITE:
        return NON_FINITE[value]
    return value
