"""How a value reads in a one-line error message, and whether it is a finite number.

Kept apart from :mod:`rrtdrive.types` (which re-exports both), which validates with them.
"""

from __future__ import annotations

import difflib
import math
from collections.abc import Iterable

import numpy as np

__all__ = ["brief_repr", "counted", "did_you_mean", "is_finite_number", "one_line"]


def brief_repr(value: object, limit: int = 32) -> str:
    """``repr(value)`` cut to about ``limit`` characters, for one-line error messages.

    A huge integer (from a JSON literal of hundreds of digits) shows its first
    digits and its length; numpy scalars show as plain Python numbers.

    Parameters
    ----------
    value : object
        The offending value.
    limit : int
        Longest text shown in full.

    Returns
    -------
    str

    Examples
    --------
    >>> brief_repr(10**400)
    '1000000000...(401 digits)'
    >>> brief_repr(np.float64(0.5)), brief_repr("1")
    ('0.5', "'1'")
    >>> brief_repr([0, 10**5000])
    'a list holding an integer too long to print'
    """
    if isinstance(value, (np.integer, np.floating, np.bool_)):
        value = value.item()
    try:
        text = repr(value)
    except ValueError:  # an int past Python's str-conversion limit (over 4300 digits)
        if isinstance(value, int):
            return f"an integer of about {int(value.bit_length() * math.log10(2)) + 1} digits"
        # Such an int inside a list or tuple: the container cannot be shown either.
        return f"a {type(value).__name__} holding an integer too long to print"
    if len(text) <= limit:
        return text
    if isinstance(value, int):
        return f"{text[:10]}...({len(text.lstrip('-'))} digits)"
    return text[:limit] + "..."


def is_finite_number(value: object) -> bool:
    """Whether ``value`` is a real number (not a bool) that a float holds finitely.

    Examples
    --------
    >>> is_finite_number(1), is_finite_number(10**400), is_finite_number(True)
    (True, False, False)
    """
    if isinstance(value, (bool, np.bool_)) or not isinstance(
        value, (int, float, np.integer, np.floating)
    ):
        return False
    try:
        return math.isfinite(float(value))
    except OverflowError:  # an int too large for a float: as good as infinite
        return False


def did_you_mean(name: object, choices: Iterable[str]) -> str:
    """`` (did you mean 'X'?)`` for the choice closest to a misspelt ``name``, else ``""``.

    Examples
    --------
    >>> did_you_mean("parkng", ["parking", "overtake"]), did_you_mean("zzz", ["parking"])
    (" (did you mean 'parking'?)", '')
    """
    close = difflib.get_close_matches(name, list(choices), n=1) if isinstance(name, str) else []
    return f" (did you mean {close[0]!r}?)" if close else ""


def counted(n: int, noun: str) -> str:
    """``n`` and ``noun``, plural unless ``n`` is 1 (``noun`` is the plural, ending in s).

    Parameters
    ----------
    n : int
        The count.
    noun : str
        The plural noun, e.g. ``"expansions"``.

    Returns
    -------
    str

    Examples
    --------
    >>> counted(1, "expansions"), counted(0, "nodes"), counted(2, "iterations")
    ('1 expansion', '0 nodes', '2 iterations')
    """
    return f"{n} {noun.removesuffix('s') if n == 1 else noun}"


def one_line(text: object) -> str:
    r"""A library's message over several lines as one line: its lines joined by ``; ``.

    Examples
    --------
    >>> one_line("Could not connect.\n  Is Ray running?\n")
    'Could not connect.; Is Ray running?'
    """
    return "; ".join(line.strip() for line in str(text).splitlines() if line.strip())
