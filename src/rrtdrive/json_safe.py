"""Values made ready for strict JSON (``allow_nan=False``): one helper for every writer."""

from __future__ import annotations

import enum
import math
from collections.abc import Callable, Mapping
from typing import Any

__all__ = ["json_safe", "options_from_json", "options_json"]

#: How :func:`options_json` spells the non-finite numbers, and :func:`options_from_json`
#: reads them back (the spellings of Python's own JSON and of JavaScript).
NON_FINITE = {"Infinity": math.inf, "-Infinity": -math.inf, "NaN": math.nan}


def _plain(value: Any, non_finite: Callable[[float], Any], enums: bool) -> Any:
    """``value`` as plain JSON, the walk both writers share.

    Mappings, sequences and numpy arrays walked, numpy scalars as Python ones, a
    non-finite float as ``non_finite`` gives it, enums by value when ``enums``.
    """
    if getattr(value, "ndim", 0) and callable(getattr(value, "tolist", None)):
        # A numpy array: item() refuses more than one element, and str() wrote the array
        # as one string ("[ 1. nan]").
        return _plain(value.tolist(), non_finite, enums)
    if isinstance(value, Mapping):
        return {str(k): _plain(v, non_finite, enums) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v, non_finite, enums) for v in value]
    if enums and isinstance(value, enum.Enum):
        return _plain(value.value, non_finite, enums)
    if hasattr(value, "item") and callable(value.item) and not isinstance(value, (str, bytes)):
        try:  # a numpy scalar (np.int64(6), np.float32(0.5)): json cannot write those
            value = value.item()
        except (TypeError, ValueError):
            return str(value)
    if isinstance(value, float) and not math.isfinite(value):
        return non_finite(value)
    return value


def _spelled(value: float) -> str:
    """A non-finite float as :data:`NON_FINITE` spells it."""
    return "NaN" if math.isnan(value) else ("Infinity" if value > 0 else "-Infinity")


def json_safe(value: Any) -> Any:
    """``value`` with non-finite floats as ``None`` and numpy values as Python ones.

    Numpy scalars become Python numbers, numpy arrays (nested) lists.

    Examples
    --------
    >>> json_safe({"a": float("nan"), "b": [1.5, float("inf")]})
    {'a': None, 'b': [1.5, None]}
    >>> import numpy as np
    >>> json_safe(np.array([[1.0, np.nan], [np.inf, 2.0]]))
    [[1.0, None], [None, 2.0]]
    """
    return _plain(value, lambda _: None, enums=False)


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
    return _plain(value, _spelled, enums=True)


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
